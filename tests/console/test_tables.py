"""What the commands print, from the library's records: Table I and the restarts, the validation
table, the progress lines of a log, and errors worded as the command's options."""

import io
import re
import time
import warnings
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
from conftest import CONFIGS, robot_of
from rich.console import Console

from excite_cli.cli import export, validate
from excite_cli.config import OptimizerConfig
from excite_cli.config_file import load_problem
from excite_cli.console import tables
from excite_cli.console.bodies import consistent_bodies
from excite_cli.console.errors import printed_warnings, spellings, word
from excite_cli.console.identification import _unresolved, _why_not_least_squares, validation
from excite_cli.console.progress import LOG_PERIOD, Bars, Stages
from excite_cli.errors import ExciteError, ExciteWarning, OutputExists
from excite_cli.identification.choice.admission import Admission
from excite_cli.identification.fitting.physical import ConsistentFit
from excite_cli.identification.validate import RunError
from excite_cli.search.kkt import Optimality
from excite_cli.search.optimizer import RestartResult
from excite_cli.search.sequence import IterationResult


def test_each_warning_is_printed_once_however_often_a_command_raises_it():
    console = Console(record=True, width=300, file=io.StringIO())
    with printed_warnings(console):
        for message in ("robot: 2 directions dropped", "limits: too fast", "robot: 2 directions dropped"):
            warnings.warn(message, ExciteWarning)
    assert console.export_text().splitlines() == ["warning: robot: 2 directions dropped", "warning: limits: too fast"]


def _text(renderables) -> str:
    console = Console(record=True, width=300, file=io.StringIO())
    for r in renderables:
        console.print(r)
    return console.export_text()


def _iteration() -> IterationResult:
    restart = RestartResult(
        0,
        np.zeros((1, 3)),
        np.log(12.34),
        200,
        "limit",
        1.0,
        np.log(99.0),
        np.zeros((200, 2)),
        Optimality(0.25, 3, 1.0, -0.01),
        "stalled",
        "projected",
    )
    return IterationResult(
        1,
        np.zeros((1, 3)),
        np.zeros(2),
        np.zeros((2, 1)),
        np.zeros((2, 1)),
        np.zeros((2, 1)),
        np.ones((4, 2)),
        12.34,
        12.34,
        -0.011,
        2077.9,
        2077.9,
        0.5,
        0.5,
        restarts=(restart,),
    )


def test_table_one_prints_both_condition_numbers_and_the_restarts_name_the_criterion():
    text = _text(tables.iterations([_iteration()], OptimizerConfig(objective="log_cond", scaling="urdf")))
    row = next(line for line in text.splitlines() if line.strip().startswith("│    1 │"))
    assert "12.3" in row and "2078" in row and "0.5" in row and "stalled" in row
    assert "end cond(CL)" in text and "12.34" in text and "2.5e-01" in text  # exp of the kept log cond
    assert "end log_det(C)" in _text(tables.iterations([_iteration()], OptimizerConfig(objective="log_det")))


def test_validation_table_gives_each_run_its_joints_and_mean():
    errors = [RunError("run.csv", np.array([0.1, 0.2]), np.array([1.0, 2.0]), 150)]
    row = next(line for line in _text([validation("r.h5", ["j1", "j2"], errors)]).splitlines() if "run.csv" in line)
    assert [cell.strip() for cell in row.split("│")[2:6]] == ["150", "1.0", "2.0", "1.5"]


def test_a_log_gets_one_line_per_finished_iteration():
    out = io.StringIO()
    with Bars(Console(file=out, width=200, force_terminal=False)) as bars:
        progress, done = bars.iterations(load_problem(CONFIGS / "smoke.yaml").optimizer)
        progress(1)(0, 5, -3.0)
        done(_iteration())
    assert "iteration 1: cond(C(i)) 12.3, cond(C) 12.3, 0 s, 200 solver iterations, stop: stalled" in out.getvalue()


def test_a_log_gets_a_progress_line_every_log_period_while_an_iteration_runs():
    """Without a terminal: nothing before LOG_PERIOD of work, then one line with the run, the solver
    iterations done of those planned, the objective, the elapsed time and the estimate left."""
    out, now = io.StringIO(), [0.0]
    problem = load_problem(CONFIGS / "smoke.yaml")
    with Bars(Console(file=out, width=200, force_terminal=False), clock=lambda: now[0]) as bars:
        hook = bars.iterations(problem.optimizer)[0](1)
        for t, it in ((10.0, 5), (LOG_PERIOD - 1, 10), (LOG_PERIOD + 1, 20), (LOG_PERIOD + 10, 25)):
            now[0] = t
            hook(0, it, -3.0)
    lines = [line for line in out.getvalue().splitlines() if line.startswith("iteration 1:")]
    planned = problem.optimizer.planned_iterations
    left = (LOG_PERIOD + 1) * (planned - 20) / 20
    objective = problem.optimizer.objective
    expected = (
        f"iteration 1: run 1/1, 20/{planned} solver iterations, {objective} -3, {LOG_PERIOD + 1:.0f} s, "
        f"about {left:.0f} s left"
    )
    assert lines == [expected]


def test_a_log_hears_from_an_iteration_whose_workers_report_nothing_for_a_while():
    """Worker processes report a restart only when it ends: a heartbeat line every period meanwhile
    (here 0.1 s of real time), with the runs reported and the lowest objective, none once it is done."""
    out = io.StringIO()
    problem = load_problem(CONFIGS / "smoke.yaml")
    with Bars(Console(file=out, width=200, force_terminal=False), period=0.1) as bars:
        progress, done = bars.iterations(problem.optimizer)
        hook = progress(1)
        time.sleep(0.35)
        hook(0, 40, -3.0)  # a restart ends
        time.sleep(0.35)
        done(_iteration())
        printed = out.getvalue()
        time.sleep(0.3)
    beats = [line for line in printed.splitlines() if line.startswith("iteration 1: working")]
    opts = problem.optimizer
    runs = opts.screened + opts.restarts if opts.screened else opts.restarts
    assert len(beats) >= 4 and beats[0].startswith(f"iteration 1: working, 0/{runs} runs reported, 0 s")
    assert f"1/{runs} runs reported, lowest {problem.optimizer.objective} reported -3," in beats[-1]
    assert out.getvalue().count("working") == printed.count("working")  # silent once done


def test_a_log_hears_what_a_command_without_bars_is_doing_and_its_heartbeat():
    """identify's stages in a log: a line said after a period has passed is printed with the time;
    lines said sooner are not; while nothing new is said the last line is repeated every period (here
    0.1 s of real time), and nothing once the command is done."""
    out, now = io.StringIO(), [0.0]
    with Stages(Console(file=out, width=200, force_terminal=False), "reading", clock=lambda: now[0]) as stages:
        for t, line in ((1.0, "step 1"), (LOG_PERIOD + 1, "step 2"), (LOG_PERIOD + 2, "step 3")):
            now[0] = t
            stages.say(line)
    assert out.getvalue().splitlines() == [f"step 2, {LOG_PERIOD + 1:.0f} s"]
    out = io.StringIO()
    with Stages(Console(file=out, width=200, force_terminal=False), "reading", period=0.1) as stages:
        time.sleep(0.35)
        stages.say("effect search")
        time.sleep(0.35)
        printed = out.getvalue()
    time.sleep(0.3)
    lines = printed.splitlines()
    assert len(lines) >= 4 and lines[0].startswith("reading, 0 s") and lines[-1].startswith("effect search, ")
    assert out.getvalue() == printed  # silent once done


def test_the_command_line_words_fields_as_its_options():
    spelled = spellings(export)
    assert spelled["fmt"] == spelled["format"] == "--format" and spelled["result"] == "RESULT"
    assert spellings(validate)["report"] == "REPORT"
    assert (
        word(ExciteError("format", "unknown", "xml", "csv or npz"), spelled) == "--format: unknown; expected csv or npz"
    )
    assert word(ExciteError("limits.velocity", "must be > 0", -1.0), spelled) == "limits.velocity: must be > 0"
    assert word(OutputExists("output", "r.h5"), spelled) == "--output: r.h5 exists; use --force to replace it"


def test_the_consistent_bodies_table_gives_the_last_body_with_its_payload_the_payload_and_the_rotors_apart():
    robot = robot_of(load_problem(CONFIGS / "panda.yaml"))
    urdf, last = robot.urdf_parameters(), robot.body_names[-1]
    payload = pin.Inertia(1.25, np.array([0.0, 0.02, 0.1]), 1e-3 * np.eye(3)).toDynamicParameters()
    standard = urdf.copy()
    standard[-10:] += payload
    bodies = len(robot.body_names)
    fit = ConsistentFit(
        standard, np.zeros(0), np.zeros(1), np.ones(bodies), [], "optimal", urdf, np.array([0.3, 0.05]),
        ["panda_joint1", "panda_joint4"], np.zeros(1), payload[None], [last], np.array([False, True]),
    )  # fmt: skip
    text = _text([consistent_bodies(fit, robot)])
    assert "with a link's): panda_joint1 0.3 regrouped, panda_joint4 0.05" in " ".join(text.split())  # wrapped
    assert f"{urdf[-10] + 1.25:.3f} / {urdf[-10]:.3f}" in text  # the last body carries it
    assert f"on the last bodies (in their masses above): {last} 1.250 kg at +0.000 +0.020 +0.100 m" in text
    none = ConsistentFit(urdf, np.zeros(0), np.zeros(1), np.ones(bodies), [], "optimal", urdf, np.zeros(0), [],
                         np.zeros(1), np.zeros((0, 10)), [], np.zeros(0, dtype=bool))  # fmt: skip
    assert "on the last bodies (in their masses above): none" in _text([consistent_bodies(none, robot)])
    fit = ConsistentFit(
        standard, np.zeros(0), np.zeros(1), np.ones(bodies), [], "optimal", urdf, np.zeros(0), [], np.zeros(1),
        1e-5 * payload[None], [last], np.zeros(0, dtype=bool),
    )  # fmt: skip
    assert re.search(rf"\(in their masses above\): {last} 0.000 kg\s*$", _text([consistent_bodies(fit, robot)]))


def test_base_parameters_the_data_cannot_tell_from_zero_are_named():
    """The two directions a rounded URDF adds came out of identify as 0.063 ± 7.98 and −3e-5 ± 4.06
    without a word."""
    from types import SimpleNamespace

    fit = SimpleNamespace(x=np.array([1.2, 0.063, -3e-5, 0.01]), std=np.array([0.01, 7.98, 4.06, 0.05]))
    report = SimpleNamespace(base_names=["m1", "a", "b", "c"], selection=SimpleNamespace(fit=fit))
    assert _unresolved(report) == ["std ≥ 10 × the value (the data cannot tell them from 0): a, b"]
    fit.std[1:3] = [0.001, 1e-6]
    assert _unresolved(report) == []


def test_a_lower_least_squares_not_chosen_is_explained_by_the_rule_of_the_folds():
    choice = SimpleNamespace(lead=-0.4, is_consistent=True, margin=0.5, admission=Admission.PRICED)
    assert "time blocks of one recording" in _why_not_least_squares(choice) and "50 %" in _why_not_least_squares(choice)
    paired = SimpleNamespace(lead=-0.4, is_consistent=True, margin=0.0, admission=Admission.PAIRED)
    assert "paired test" in _why_not_least_squares(paired)
    assert (
        _why_not_least_squares(SimpleNamespace(lead=0.3, is_consistent=True, margin=0.5, admission=Admission.PRICED))
        == ""
    )

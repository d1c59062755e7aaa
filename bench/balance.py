"""Does the standing robot stay on its feet? Each iteration of the shipped G1 problem, optimized for
every seed, played in MuJoCo on a floor (bench/mujoco_stance.py on excite_cli/rehearsal: MuJoCo compiles the
URDF itself; the soles' contact spheres, the free root, MuJoCo's integrator and soft contacts, and
every joint given the damping, armature and dry friction of MuJoCo Menagerie's G1, which the URDF and
excite's model do not have), as `excite export` plays it (home → one period → home, at 2 kHz, speed 1
and faster, time-scaled here where the export's limits would refuse it), the moving joints driven by
the exported feed-forward torque plus a PD on tracking, the joints the problem locks held

- welded (rigid, as excite's model holds them): what excite's zero-moment point predicts;
- by a joint PD (`pdK/D`: K Nm/rad, D Nm·s/rad), a stance with compliance of its own;
- by the PD plus the held joints' feed-forward `excite export` writes (`pdK/D+feedforward`,
  excite_cli/design/held_joints.py);
- by the PD plus an ankle stabilizer regulating the centre of mass (`pdK/D+stabilizer`, gains
  --stabilizer in units of the robot's weight m g: k_p m g N·m/m, k_d m g N·m·s/m).

One line per stance, seed, iteration and speed:
`balance ROBOT stance STANCE seed S iteration I speed X: CoP margin M mm (predicted P mm, RMS gap G mm),
tilt T deg, stands|falls` — MuJoCo's smallest distance of the centre of pressure (from the contact
forces) inside the polygon of its contact points, excite's predicted smallest ZMP margin on the same
samples, the RMS distance between the two points, the largest tilt of a foot, and whether it fell (the
root 5 cm lower, a sole tilted more than 5° or the root more than 20°). Then each stance's push test
(the root pushed with 60 N for 50 ms fore-aft and sideways while standing at home: the natural
frequency and damping ratio of its centre of mass's free swing over 5.9 s) and a summary line per
stance and speed.

    .venv/bin/python bench/balance.py [--config configs/g1_arms.yaml] [--seeds 0 1 2] [--result R.h5]
        [--results-dir DIR] [--workers W] [--stances welded pd1000/40 ...] [--stabilizer 2 1]
        [--joint-losses 0.5 0.01 0.1] [--no-push]

With --result the iterations of that result are played instead of optimizing; --results-dir keeps the
optimized results (and plays those already there). The stabilizer's gains were chosen on the push
test (no free swing left fore-aft or sideways), not on the trajectories. Asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import re
import tempfile
from pathlib import Path

import numpy as np
from mujoco_stance import TIMESTEP, Stance, play_standing, standing_model
from scipy.signal import find_peaks

from excite_cli.config_file import load_problem
from excite_cli.constraints.zmp import GRAVITY, zero_moment_point
from excite_cli.design.held_joints import held_joints
from excite_cli.design.playback import plan_playback
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.rehearsal.soles import mesh_soles
from excite_cli.storage.results import read_alphas
from excite_cli.workflows.optimize import run_optimize

ROOT = Path(__file__).resolve().parent.parent
#: The stances played by default: rigid, the plain PD, the PD with the exported feed-forward (stiff
#: and soft), and the ankle stabilizer on the soft PD.
STANCES = (
    "welded",
    "pd1000/40",
    "pd1000/40+feedforward",
    "pd500/20",
    "pd500/20+feedforward",
    "pd500/20+stabilizer",
)
#: MuJoCo Menagerie's G1 (unitree_g1/g1.xml, class g1): joint damping [Nm·s/rad], armature [kg·m²],
#: frictionloss [Nm].
MENAGERIE_G1_JOINTS = (0.5, 0.01, 0.1)


def results(
    config: Path, seeds: list[int], given: Path | None, folder: Path, workers: int | None = None
) -> dict[int, dict[int, np.ndarray]]:
    """{seed: {iteration: α}}: of ``given``, or of each seed's result in ``folder``, optimized there
    where it is not yet."""
    if given is not None:
        return {load_problem(config).optimizer.seed: dict(read_alphas(given))}
    found = {}
    for seed in seeds:
        problem = load_problem(config)
        problem.optimizer.seed, problem.optimizer.workers = seed, workers or problem.optimizer.workers
        target = folder / f"{config.stem}_seed{seed}.h5"
        if not target.exists():
            run_optimize(problem, target, force=True)
        found[seed] = dict(read_alphas(target))
        print(f"  optimized seed {seed}", flush=True)
    return found


def parse_stance(label: str, stabilizer: tuple[float, float], weight: float) -> Stance:
    """The :class:`Stance` of a label: ``welded``, ``pdK/D``, ``pdK/D+feedforward``, ``pdK/D+stabilizer``."""
    if label == "welded":
        return Stance()
    found = re.fullmatch(r"pd([\d.]+)/([\d.]+)(\+feedforward|\+stabilizer)?", label)
    if not found:
        raise SystemExit(f"--stances: {label!r} is not welded, pdK/D, pdK/D+feedforward or pdK/D+stabilizer")
    added = found.group(3) or ""
    gains = (stabilizer[0] * weight, stabilizer[1] * weight) if added == "+stabilizer" else None
    return Stance(float(found.group(1)), float(found.group(2)), added == "+feedforward", gains)


def push_test(model, home: np.ndarray, tau: np.ndarray, held, stance: Stance):
    """[(frequency [Hz], damping ratio)] fore-aft and sideways of the standing robot's centre of mass
        swinging freely after a push of the root: 60 N for 50 ms after 2 s standing at ``home`` (the arms
    given their static torques ``tau``, the held joints ``held``'s), then 5.9 s.
        The frequency from the mean spacing of the swing's peaks, the damping from their logarithmic
        decrement δ (ζ = δ / √(4π² + δ²)); (nan, nan) where it swings less than once (no free swing)."""
    count = 12_000
    still, found = np.zeros((count, len(home))), []
    for axis in (0, 1):
        push = np.zeros((count, 3))
        push[:100, axis] = 60.0
        given = (held[0], np.repeat(held[1], count, axis=0)) if held else None
        run = play_standing(model, still + home, still, still + tau, given, stance.stabilizer, push)
        swing = run.com[200:, axis] - run.com[-4000:, axis].mean()
        peaks = find_peaks(np.abs(swing))[0]
        peaks = peaks[np.abs(swing[peaks]) > 0.05 * np.abs(swing).max()]
        if len(peaks) < 3:
            found.append((np.nan, np.nan))
            continue
        frequency = 0.5 / (np.diff(peaks).mean() * TIMESTEP)  # |swing| peaks every half period
        decrement = -2 * np.mean(np.diff(np.log(np.abs(swing[peaks[:4]]))))  # per period
        found.append((frequency, decrement / np.sqrt(4 * np.pi**2 + decrement**2)))
    return found


def setup(config: Path):
    """The problem of ``config``, its excitation, its ZMP constraint and its URDF."""
    problem = load_problem(config)
    excitation = build_excitation(problem)
    zmp = next(c for c in excitation.constraints if c.name == "zmp")
    return problem, excitation, zmp, resolve_urdf(problem.robot, problem.folder)[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--config", type=Path, default=ROOT / "configs" / "g1_arms.yaml")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--speeds", type=float, nargs="+", default=[1.0, 1.25])
    parser.add_argument("--stances", nargs="+", default=list(STANCES))
    parser.add_argument("--stabilizer", type=float, nargs=2, default=[2.0, 1.0], help="k_p, k_d [m g, m g·s]")
    parser.add_argument("--joint-losses", type=float, nargs=3, default=list(MENAGERIE_G1_JOINTS))
    parser.add_argument("--result", type=Path, help="play this result's iterations instead of optimizing")
    parser.add_argument("--results-dir", type=Path, help="keep the optimized results here (and reuse them)")
    parser.add_argument("--workers", type=int, help="optimizer processes (default: the config's, else every core)")
    parser.add_argument("--no-push", action="store_true", help="leave out the push test")
    args = parser.parse_args()
    problem, excitation, zmp, urdf = setup(args.config)
    robot = excitation.robot
    hold = held_joints(problem.robot, problem.folder, problem.constraints, robot)
    weight = GRAVITY * sum(inertia.mass for inertia in robot.model.inertias)
    stances = [parse_stance(label, tuple(args.stabilizer), weight) for label in args.stances]
    links, losses = problem.constraints.zmp.support_links, tuple(args.joint_losses)
    soles = mesh_soles(robot, links)
    models = [standing_model(problem, urdf, s, losses, soles) for s in stances]
    print(f"joints: damping {losses[0]:g} Nm·s/rad, armature {losses[1]:g} kg·m², frictionloss {losses[2]:g} Nm")
    with tempfile.TemporaryDirectory() as folder:
        alphas = results(args.config, args.seeds, args.result, args.results_dir or Path(folder), args.workers)
    summary: dict[tuple[str, float], list[tuple[float, float, bool]]] = {}
    for seed, iterations in alphas.items():
        for k, alpha in sorted(iterations.items()):
            playback = plan_playback(excitation, alpha)
            for speed in args.speeds:
                _, q, qd, qdd = playback.sample(1.0 / TIMESTEP, speed=speed)
                tau = np.array([robot.torques(*x) for x in zip(q, qd, qdd)])
                held = hold.torques(q, qd, qdd)
                predicted = zero_moment_point(zmp.wrenches(q, qd, qdd), zmp.polygon.height)
                expected = zmp.polygon.margins(predicted).min()
                for stance, model in zip(stances, models):
                    given = (held.joint_names, held.tau) if stance.feedforward else None
                    run = play_standing(model, q, qd, tau, given, stance.stabilizer)
                    gap = np.sqrt(np.nanmean(np.sum((run.cop - predicted) ** 2, axis=1)))
                    margin = run.margin.min()
                    summary.setdefault((str(stance), speed), []).append((margin, gap, run.fell))
                    print(
                        f"balance {args.config.stem} stance {stance} seed {seed} iteration {k} speed {speed:.2f}: "
                        f"CoP margin {1000 * margin:.1f} mm (predicted {1000 * expected:.1f} mm, RMS gap "
                        f"{1000 * gap:.1f} mm), tilt {run.sole_tilt.max():.2f} deg, {'falls' if run.fell else 'stands'}",
                        flush=True,
                    )
    at_home = hold.torques(robot.home[None], 0 * robot.home[None], 0 * robot.home[None])
    for stance, model in zip(stances, models) if not args.no_push else ():
        given = (at_home.joint_names, at_home.tau) if stance.feedforward else None
        static = robot.torques(robot.home, 0 * robot.home, 0 * robot.home)
        (f_x, z_x), (f_y, z_y) = push_test(model, robot.home, static, given, stance)
        fore_aft, sideways = (
            "no free swing" if np.isnan(f) else f"{f:.2f} Hz, damping ratio {z:.2f}"
            for f, z in ((f_x, z_x), (f_y, z_y))
        )
        print(f"push {stance}: fore-aft {fore_aft}; sideways {sideways}")
    for (stance, speed), rows in summary.items():
        margins, gaps, fell = zip(*rows)
        print(
            f"summary {stance} speed {speed:.2f}: {len(rows) - sum(fell)} of {len(rows)} stand, smallest CoP "
            f"margin {1000 * min(margins):.1f} mm, largest RMS gap {1000 * max(gaps):.1f} mm"
        )


if __name__ == "__main__":
    main()

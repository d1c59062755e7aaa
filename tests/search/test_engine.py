"""Restarts and random draws in parallel: a process pool and a Dask cluster give the serial run's
trajectories and candidates, bit for bit, for the same seed; each restart draws its own start."""

import contextlib
import dataclasses
import os
import re
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import h5py
import numpy as np
import pytest
import yaml
from conftest import TESTS, tcp_server, write_config
from pydantic import ValidationError

import excite_cli.search.engine as engine_module
import excite_cli.search.scheduler as scheduler_module
from excite_cli.config import OptimizerConfig
from excite_cli.config_file import load_problem
from excite_cli.design.excitation import build_design
from excite_cli.design.resolve import build_excitation
from excite_cli.errors import ExciteError
from excite_cli.search.engine import Engine
from excite_cli.search.optimizer import RestartResult, best_restart
from excite_cli.search.random_baseline import draw_pool
from excite_cli.search.restarts import RestartTask
from excite_cli.search.sequence import run_sequence

HERE = TESTS


@pytest.fixture(scope="module")
def excitation():
    """The Panda with capsules (all constraint code runs in the workers), two restarts of 15 SQP iterations."""
    problem = load_problem(HERE / "panda_capsules.yaml")
    problem.optimizer.restarts = 2
    problem.optimizer.max_iterations = 15
    return build_excitation(problem)


@pytest.fixture(scope="module")
def serial(excitation):
    return run_sequence(excitation, 2, seed=5)


def _same(a, b):
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x.alpha, y.alpha)
        assert x.cond_stacked == y.cond_stacked


def test_two_workers_give_the_serial_result(excitation, serial):
    with Engine(excitation, workers=2) as engine:
        parallel = run_sequence(excitation, 2, seed=5, engine=engine)
    _same(serial, parallel)
    assert serial[1].cond_stacked < serial[0].cond_own  # the runs optimized something


def test_dask_local_cluster_gives_the_serial_result(excitation, serial):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        with Engine(excitation, scheduler=cluster.scheduler_address) as engine:
            on_cluster = run_sequence(excitation, 2, seed=5, engine=engine)
            pool_on_cluster = draw_pool(engine, 30, seed=2)
    with Engine(excitation) as engine:
        pool = draw_pool(engine, 30, seed=2)
    np.testing.assert_array_equal(pool.alphas, pool_on_cluster.alphas)
    assert len(pool.alphas) == 30 and pool.regressors.shape[:2] == (30, excitation.cost_basis.time.size * 7)
    _same(serial, on_cluster)


def test_each_restart_draws_its_own_start(excitation):
    prior = np.zeros((0, excitation.base.count))
    starts = [excitation.random_start(RestartTask(1, r, 5, prior).rng()) for r in range(3)]
    assert not np.allclose(starts[0], starts[1]) and not np.allclose(starts[1], starts[2])
    again = excitation.random_start(RestartTask(1, 1, 5, prior).rng())
    np.testing.assert_array_equal(again, starts[1])
    assert not np.allclose(excitation.random_start(RestartTask(2, 1, 5, prior).rng()), starts[1])


def test_best_restart_breaks_ties_by_index():
    results = [RestartResult(i, np.zeros((1, 1)), value, 1, "", 0.0) for i, value in [(2, 1.0), (0, 1.0), (1, 3.0)]]
    assert best_restart(results).index == 0


def test_unreachable_scheduler_is_named(excitation, monkeypatch):
    monkeypatch.setattr(engine_module, "CONNECT_TIMEOUT", 1.0)
    with pytest.raises(ExciteError, match="optimizer.scheduler: cannot reach the Dask scheduler at tcp://127.0.0.1:9"):
        with Engine(excitation, scheduler="tcp://127.0.0.1:9"):
            pass


@pytest.mark.parametrize(
    "first_bytes, expected",
    [
        (b"HTTP/1.1 400 Bad Request\r\n\r\n", "its first bytes are no Dask handshake"),
        (b"", "its first message did not come whole within 0.5 s"),
        (bytes(8), "its first bytes are no Dask handshake"),
        (struct.pack("Q", 16) + b"garbage, garbage", "its first bytes are no Dask handshake"),
        (struct.pack("Q", 64) + b"a part of it", "its first message did not come whole within 0.5 s"),
    ],
    ids=["a-web-server", "a-silent-server", "zero-bytes", "framed-garbage", "a-short-message"],
)
def test_a_server_that_is_no_dask_scheduler_is_refused_before_dask_reads_from_it(first_bytes, expected):
    """Dask's client would allocate what a web server's first bytes say (3 EiB): the handshake is
    checked with a bound first."""
    with tcp_server(first_bytes) as address:
        started = time.monotonic()
        with pytest.raises(ExciteError, match=f"is not a Dask scheduler: {expected}"):
            scheduler_module.check_scheduler(address, timeout=0.5)
        assert time.monotonic() - started < 5


def test_a_server_that_trickles_bytes_is_cut_off_at_the_bound():
    """A message of 100 bytes announced, then one byte every 0.1 s: no single read times out, the bound is
    on the whole message (a trickle of a byte every 5 s was refused only after 37 s)."""
    listener = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def serve() -> None:
        connection, _ = listener.accept()
        with connection, contextlib.suppress(OSError):
            connection.sendall(struct.pack("Q", 100))
            while not stop.wait(0.1):
                connection.sendall(b"\x01")

    threading.Thread(target=serve, daemon=True).start()
    started = time.monotonic()
    try:
        with pytest.raises(ExciteError, match="did not come whole within 1 s"):
            scheduler_module.check_scheduler(f"tcp://127.0.0.1:{listener.getsockname()[1]}", timeout=1.0)
    finally:
        stop.set()
        listener.close()
    assert time.monotonic() - started < 3


def test_a_port_out_of_range_is_refused_naming_the_field():
    with pytest.raises(ValidationError, match="port 96543 is out of range"):
        OptimizerConfig(scheduler="tcp://10.0.0.5:96543")


def test_a_dask_scheduler_passes_the_handshake():
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=0, processes=False, protocol="tcp://", dashboard_address=None) as cluster:
        scheduler_module.check_scheduler(cluster.scheduler_address, timeout=5)


def test_workers_optimize_in_the_main_process_base(excitation):
    # The base is resolved once and shipped in the spec: a base whose columns are in another order than
    # any process would compute (a stand-in for the base another BLAS kernel picked) is the one the
    # workers' criterion uses, so a restart's value is the main process's at the returned α.
    base = excitation.base
    order = np.random.default_rng(0).permutation(base.count)
    shuffled = dataclasses.replace(
        base,
        composition_matrix=base.composition_matrix[:, order],
        regrouping=base.regrouping[order],
        names=[base.names[k] for k in order],
        independent=base.independent[order],
    )
    optimizer = excitation.spec.optimizer.model_copy(update={"scaling": "none"})  # the frame L belongs to the
    other = build_design(dataclasses.replace(excitation.spec, base=shuffled, optimizer=optimizer))  # base's order
    prior = other.criterion().regressor(other.random_start(np.random.default_rng(3)))
    tasks = [RestartTask(1, r, 5, prior, iterations=5) for r in range(2)]
    with Engine(other, workers=2) as engine:
        runs = engine.run(tasks)
    for run in runs:
        assert run.objective == pytest.approx(other.criterion(prior).value(run.alpha), rel=1e-12)
        assert run.objective != pytest.approx(excitation.criterion(prior).value(run.alpha), rel=1e-6)


def _changed_in_memory(excitation):
    """The excitation of ``excitation``'s spec with its scaling frame changed in memory, as
    bench/loop.py weighs the effects: A-optimality then weighs the columns anew."""
    spec = excitation.spec
    emphasis = np.where(np.arange(spec.columns) % 2 == 0, 0.25, 1.0)
    return build_design(dataclasses.replace(spec, scaled_frame=spec.scaled_frame * emphasis))


def test_a_pool_worker_s_excitation_is_the_main_process_s_for_a_spec_changed_in_memory(excitation):
    """Workers build from the main process's spec, not from the config: a frame changed in memory
    gives the serial restarts bit for bit in a pool, and other restarts than the spec as resolved
    (the Dask case: tests/search/test_reproducible.py)."""
    changed = _changed_in_memory(excitation)
    tasks = [RestartTask(1, r, 5, np.zeros((0, changed.columns)), iterations=5) for r in range(2)]
    runs = {}
    for name, design, workers in (("serial", changed, 1), ("pool", changed, 2), ("as resolved", excitation, 1)):
        with Engine(design, workers=workers) as engine:
            runs[name] = engine.run(tasks)
    for ours, theirs, unchanged in zip(runs["serial"], runs["pool"], runs["as resolved"]):
        np.testing.assert_array_equal(ours.alpha, theirs.alpha)
        assert ours.objective == theirs.objective
        assert not np.array_equal(ours.alpha, unchanged.alpha)


@contextmanager
def _dask_cluster(port: int) -> Iterator[tuple[str, subprocess.Popen]]:
    """A real `dask scheduler` on ``port`` and a `dask worker` of two one-thread processes: (address, the
    worker's process), both stopped when the block ends."""
    dask = str(Path(sys.executable).with_name("dask"))
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    address = f"tcp://127.0.0.1:{port}"
    scheduler = subprocess.Popen([dask, "scheduler", "--port", str(port), "--no-dashboard"], **quiet)
    worker = subprocess.Popen(  # a session of its own: the whole worker (nannies, processes) can be killed at once
        [dask, "worker", address, "--nworkers", "2", "--nthreads", "1", "--no-dashboard"],
        start_new_session=True,
        **quiet,
    )
    try:
        yield address, worker
    finally:
        for process in (worker, scheduler):
            if process.poll() is None:
                process.terminate()
                process.wait(20)


@pytest.mark.end_to_end
def test_a_dask_worker_killed_mid_run_gives_the_uninterrupted_result(tmp_path):
    """Real `dask scheduler` and `dask worker` processes; one worker process is killed (SIGKILL) while
    it runs a restart: the scheduler gives the task to a worker again (restarts are pure functions
    of the problem, the base and their seed) and the result is the serial one, bit for bit."""
    psutil = pytest.importorskip("psutil")
    distributed = pytest.importorskip("dask.distributed")
    config = yaml.safe_load((HERE / "panda_capsules.yaml").read_text())
    config["optimizer"] = {"restarts": 4, "max_iterations": 25}
    config["sequence"] = {"iterations": 1}
    path = write_config(tmp_path, config)
    excite = str(Path(sys.executable).with_name("excite"))
    serial = subprocess.run([excite, "optimize", str(path), "-o", str(tmp_path / "serial.h5"), "--workers", "1"])
    assert serial.returncode == 0
    run = None
    with _dask_cluster(8500 + os.getpid() % 300) as (address, _):
        try:
            with distributed.Client(address, timeout=60) as client:
                client.wait_for_workers(2, timeout=120)  # started: a kill now is a death mid-run, not a failed start
                workers = [psutil.Process(pid) for pid in client.run(os.getpid).values()]
            argv = [excite, "optimize", str(path), "-o", str(tmp_path / "dask.h5"), "--scheduler", address]
            run = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            killed = None
            deadline = time.monotonic() + 120
            while killed is None and run.poll() is None and time.monotonic() < deadline:
                for process in workers:
                    if process.cpu_percent(interval=0.2) > 20:  # busy with a restart (an idle worker: ~1 %)
                        process.kill()
                        killed = process.pid
                        break
            assert killed is not None, "no worker was seen running a restart"
            assert run.wait(300) == 0
        finally:
            if run is not None and run.poll() is None:
                run.kill()
    with h5py.File(tmp_path / "serial.h5") as a, h5py.File(tmp_path / "dask.h5") as b:
        np.testing.assert_array_equal(a["iterations/1/alpha"][()], b["iterations/1/alpha"][()])
        assert a["iterations/1"].attrs["cond_stacked"] == b["iterations/1"].attrs["cond_stacked"]


def _busy_optimize(tmp_path: Path, iterations: int, **optimizer) -> Path:
    """The Panda with capsules, restarts long enough to be caught running."""
    config = yaml.safe_load((HERE / "panda_capsules.yaml").read_text())
    config["optimizer"] = {"restarts": 4, "max_iterations": 60, **optimizer}
    config["sequence"] = {"iterations": iterations}
    return write_config(tmp_path, config)


def _kill_when(process: subprocess.Popen, ready, kill, deadline_s: float = 180) -> bool:
    """Call ``kill()`` once ``ready()`` holds while ``process`` runs; whether it was called."""
    deadline = time.monotonic() + deadline_s
    while process.poll() is None and time.monotonic() < deadline:
        if ready():
            kill()
            return True
        time.sleep(0.1)
    return False


@pytest.mark.end_to_end
def test_a_cluster_that_loses_every_worker_stops_with_one_line_and_keeps_the_finished_iterations(tmp_path):
    """Real `dask scheduler` and `dask worker` processes; once iteration 1 is written the whole worker
    (its nanny and processes) is killed: the run stops after optimizer.worker_wait seconds without a
    worker (it would wait for one for ever), says so in one line and keeps the finished iterations.
    A result that had finished on a killed worker is 'lost': waiting for it without a bound hung 3 of
    10 runs."""
    pytest.importorskip("dask.distributed")
    path = _busy_optimize(tmp_path, iterations=4, worker_wait=3.0)
    out = tmp_path / "dask.h5"
    run = None
    with _dask_cluster(8200 + os.getpid() % 300) as (address, worker):
        try:
            argv = [str(Path(sys.executable).with_name("excite")), "optimize", str(path), "-o", str(out)]
            run = subprocess.Popen(
                [*argv, "--scheduler", address], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
            )

            def kill_every_worker() -> None:  # at once: a nanny killed after its process would restart it
                os.killpg(worker.pid, signal.SIGKILL)

            assert _kill_when(run, out.exists, kill_every_worker), "iteration 1 was not written"
            _, stderr = run.communicate(timeout=120)
        finally:
            if run is not None and run.poll() is None:
                run.kill()
    _assert_stopped_keeping_iterations(run, stderr, "had no worker for 3 s", out)


def _assert_stopped_keeping_iterations(run: subprocess.Popen, stderr: str, expected: str, out: Path) -> None:
    """Exit 2, one error line containing ``expected`` and "kept k finished iteration(s)" with k ≥ 1,
    and iterations 1 … k in ``out``."""
    assert run.returncode == 2 and "Traceback" not in stderr, stderr
    (line,) = [line for line in stderr.splitlines() if line.startswith("error:")]
    assert expected in line, line
    kept = int(re.search(r"kept (\d+) finished iteration", line).group(1))
    with h5py.File(out) as f:
        assert kept >= 1 and sorted(f["iterations"], key=int) == [str(k) for k in range(1, kept + 1)]


def test_a_local_worker_process_killed_mid_run_is_one_line(tmp_path):
    """The pool's worker processes killed (as the system's out-of-memory killer would) once iteration
    1 is written: one line naming --workers (optimizer.workers), exit 2, the finished iterations kept."""
    psutil = pytest.importorskip("psutil")
    path = _busy_optimize(tmp_path, iterations=4)
    out = tmp_path / "pool.h5"
    argv = [str(Path(sys.executable).with_name("excite")), "optimize", str(path), "-o", str(out), "--workers", "2"]
    run = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:

        def kill_workers() -> None:
            for process in psutil.Process(run.pid).children():
                process.kill()

        assert _kill_when(run, out.exists, kill_workers), "iteration 1 was not written"
        _, stderr = run.communicate(timeout=120)
    finally:
        if run.poll() is None:
            run.kill()
    _assert_stopped_keeping_iterations(run, stderr, "--workers: a worker process died during the run", out)


def test_a_tls_address_without_dask_s_certificates_is_one_line():
    """Dask's client ends in a bare TypeError ("TLS expects a ssl_context argument") without them."""
    with pytest.raises(
        ExciteError, match="is a TLS address, and Dask's configuration gives its client no certificates"
    ):
        scheduler_module.check_scheduler("tls://127.0.0.1:1", timeout=0.5)

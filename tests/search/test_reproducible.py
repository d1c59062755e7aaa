"""One seed, one result, wherever it runs: bit-identical random starts with 1 and 2 BLAS threads,
and restarts on a real Dask cluster (``dask scheduler`` and ``dask worker`` processes started here)
equal to the same restarts in this process."""

import copy
import dataclasses
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import UR5, write_config
from threadpoolctl import threadpool_limits

from excite_cli.config_file import load_problem
from excite_cli.design.excitation import build_design
from excite_cli.design.resolve import build_excitation
from excite_cli.search.engine import Engine
from excite_cli.search.restarts import RestartTask
from excite_cli.search.sequence import run_sequence


def test_a_seed_gives_bit_identical_starts_with_one_and_two_blas_threads(g1_problem):
    excitation = build_excitation(g1_problem)
    prior = np.zeros((0, excitation.base.count))
    starts = {}
    for threads in (1, 2):
        with threadpool_limits(limits=threads):
            starts[threads] = [
                excitation.random_start(RestartTask(1, r, seed, prior).rng()) for seed in (0, 1) for r in (0, 1)
            ]
    for one, two in zip(starts[1], starts[2]):
        assert one.tobytes() == two.tobytes()
        assert all(c.accepts(one) for c in excitation.constraints)


def _dask(tmp_path: Path) -> tuple[list[subprocess.Popen], str]:
    """A scheduler and two single-threaded workers on this machine; their address."""
    dask = Path(sys.executable).with_name("dask")
    if not dask.exists():
        pytest.skip("the dask command line is not installed beside this Python")
    file = tmp_path / "scheduler.json"
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "cwd": tmp_path}
    processes = [
        subprocess.Popen(
            [
                str(dask),
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                str(file),
            ],
            **quiet,
        )
    ]
    deadline = time.monotonic() + 60
    while not file.exists() and time.monotonic() < deadline:
        time.sleep(0.2)
    processes.append(
        subprocess.Popen(
            [
                str(dask),
                "worker",
                "--scheduler-file",
                str(file),
                "--nthreads",
                "1",
                "--nworkers",
                "2",
                "--no-dashboard",
                "--host",
                "127.0.0.1",
            ],
            **quiet,
        )
    )
    return processes, json.loads(file.read_text())["address"]


@pytest.mark.end_to_end
def test_restarts_on_real_dask_workers_equal_this_process_for_a_spec_changed_in_memory(tmp_path):
    """Dask workers build from the main process's spec: with its scaling frame changed in memory (as
    bench/loop.py weighs the effects) they give this process's sequence bit for bit, which differs
    from the sequence of the spec as resolved."""
    data = copy.deepcopy(UR5)
    data["trajectory"].update(harmonics=3, cost_samples=20, cost_period=0.4, constraint_period=0.05)
    data["optimizer"] = {"max_iterations": 60, "restarts": 3, "seed": 7}
    resolved = build_excitation(load_problem(write_config(tmp_path, data)))
    emphasis = np.where(np.arange(resolved.columns) % 2 == 0, 0.25, 1.0)
    excitation = build_design(dataclasses.replace(resolved.spec, scaled_frame=resolved.scaled_frame * emphasis))
    with Engine(excitation) as serial:
        local = run_sequence(excitation, 2, 7, engine=serial)
    with Engine(resolved) as serial:
        assert local[0].alpha.tobytes() != run_sequence(resolved, 1, 7, engine=serial)[0].alpha.tobytes()
    processes, address = _dask(tmp_path)
    try:
        from dask.distributed import Client

        with Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=60)
        with Engine(excitation, scheduler=address) as cluster:
            remote = run_sequence(excitation, 2, 7, engine=cluster)
    finally:
        for process in processes[::-1]:
            process.terminate()
            process.wait(timeout=30)
    for a, b in zip(local, remote):
        assert a.alpha.tobytes() == b.alpha.tobytes()
        assert [r.alpha.tobytes() for r in a.restarts] == [r.alpha.tobytes() for r in b.restarts]

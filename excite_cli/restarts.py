"""Where the restarts of an iteration run: in this process, in a local process pool, or on a Dask
distributed cluster.

The restarts of one iteration are independent SLSQP runs from different starts. Each is a
:class:`RestartTask`: its random start is drawn from its own seed, ``SeedSequence(seed,
spawn_key=(iteration, restart))``, so the result does not depend on where or in which order the
restarts run; the best is chosen by objective, then index (:func:`best_restart`). Pool and cluster
workers build the :class:`~excite_cli.excitation.Excitation` from the validated problem once and
keep it (one per worker thread); every restart runs with one BLAS thread, since the matrices are
small and parallel workers would otherwise oversubscribe the cores.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import threading
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from typing import Iterator, Optional, Sequence

import numpy as np
from threadpoolctl import threadpool_limits

from excite_cli.config import Problem
from excite_cli.errors import ExciteError
from excite_cli.excitation import Excitation, build_excitation
from excite_cli.optimizer import ProgressHook, RestartResult, optimize_restart


@dataclass(frozen=True)
class RestartTask:
    """One restart of one iteration.

    Attributes:
        iteration: k, 1-based; index: the restart's number, 0-based.
        seed: the run's seed (``optimizer.seed``).
        prior: C₀ (m, b), the rows stacked above the trajectory's regressor (Eq. 41).
        warm_start: (n, 2N+1) accepted α to start from instead of a random start, or None.
    """

    iteration: int
    index: int
    seed: int
    prior: np.ndarray
    warm_start: Optional[np.ndarray] = None

    def rng(self) -> np.random.Generator:
        """The restart's own random generator."""
        return np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(self.iteration, self.index)))


def keep_freed_memory() -> None:
    """Let this process keep freed memory instead of returning it to the OS (glibc ``mallopt``).

    The constraint grid's (instants × pairs) temporaries are megabytes, allocated hundreds of times
    per second; by default glibc hands blocks above 128 kB back to the OS on free and page-faults
    them in again on the next allocation, which cost 40 % of a capsule evaluation on the G1 (28 ms
    → 18 ms with this). Elsewhere than glibc it does nothing.
    """
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.mallopt(M_TRIM_THRESHOLD, 1 << 28)
        libc.mallopt(M_MMAP_THRESHOLD, 1 << 25)
    except (OSError, AttributeError):
        pass


def solve(excitation: Excitation, task: RestartTask, progress: Optional[ProgressHook] = None) -> RestartResult:
    """Run one restart: draw its start (or take the warm start) and optimize from it."""
    start = task.warm_start.copy() if task.warm_start is not None else excitation.random_start(task.rng())
    return optimize_restart(excitation.criterion(task.prior), excitation.constraints, excitation.problem.optimizer,
                            start, excitation.boundary, task.index, progress)


#: glibc mallopt parameters (malloc.h).
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
#: How long to wait for a Dask scheduler to answer.
CONNECT_TIMEOUT = "10s"

_local = threading.local()


def _worker_excitation(problem: Problem) -> Excitation:
    """The excitation of ``problem`` in this worker (thread), built on first use."""
    key = (str(problem.source_path), problem.model_dump_json())
    cache = getattr(_local, "cache", None)
    if cache is None or cache[0] != key:
        _local.cache = cache = (key, build_excitation(problem))
    return cache[1]


def solve_on_worker(problem: Problem, task: RestartTask) -> RestartResult:
    """:func:`solve` in a pool or cluster worker, with the worker's own excitation and, from then
    on, one BLAS thread in the worker's process (a worker is there to run restarts)."""
    threadpool_limits(limits=1)
    keep_freed_memory()
    return solve(_worker_excitation(problem), task)


class Restarts:
    """Runs restart tasks serially (``workers`` 1, with per-iteration progress), in a local process
    pool of ``workers`` processes, or on the Dask scheduler at ``scheduler``.

    Use as a context manager: this process runs with one BLAS thread inside it (and keeps freed
    memory, :func:`keep_freed_memory`), and the pool or client is closed on exit.

    Raises:
        ExciteError: the scheduler cannot be reached.
    """

    def __init__(self, excitation: Excitation, workers: int = 1, scheduler: Optional[str] = None):
        self.excitation, self.workers, self.scheduler = excitation, workers, scheduler
        self._pool: Optional[Executor] = None
        self._client = None
        self._limits: Optional[threadpool_limits] = None

    def __enter__(self) -> "Restarts":
        self._limits = threadpool_limits(limits=1)
        keep_freed_memory()
        if self.scheduler:
            from dask.distributed import Client

            try:
                self._client = Client(self.scheduler, timeout=CONNECT_TIMEOUT)
            except (OSError, TimeoutError) as exc:
                raise ExciteError(f"optimizer.scheduler: cannot reach the Dask scheduler at {self.scheduler}: {exc}") from None
        elif self.workers > 1:
            self._pool = ProcessPoolExecutor(max_workers=self.workers)
        return self

    def __exit__(self, *exc) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
        if self._client is not None:
            self._client.close()
        if self._limits is not None:
            self._limits.restore_original_limits()

    def run(self, tasks: Sequence[RestartTask], progress: Optional[ProgressHook] = None) -> list[RestartResult]:
        """Results of all ``tasks`` (in task order). ``progress`` gets every SLSQP iteration when
        serial, and (restart, its iterations, its objective) as each restart finishes otherwise."""
        if self._pool is None and self._client is None:
            return [solve(self.excitation, task, progress) for task in tasks]
        results = {}
        for result in self._completed(tasks):
            results[result.index] = result
            if progress is not None:
                progress(result.index, result.iterations, result.objective)
        return [results[task.index] for task in tasks]

    def _completed(self, tasks: Sequence[RestartTask]) -> Iterator[RestartResult]:
        problem = self.excitation.problem
        if self._client is not None:
            from dask.distributed import as_completed as dask_completed

            futures = [self._client.submit(solve_on_worker, problem, task, pure=False) for task in tasks]
            for future in dask_completed(futures):
                yield future.result()
            return
        pool_futures: list[Future] = [self._pool.submit(solve_on_worker, problem, task) for task in tasks]
        for future in as_completed(pool_futures):
            yield future.result()


def default_workers() -> int:
    """The cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)

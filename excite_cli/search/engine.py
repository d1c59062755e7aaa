"""Where independent pieces of work run: in this process, in a local process pool, or on a Dask
distributed cluster.

The restarts of an iteration (:class:`~excite_cli.search.restarts.RestartTask`) and the random candidates
of ``compare-random`` (:class:`~excite_cli.search.random_baseline.DrawTask`) are tasks: each has an index
and its own seed, and is called with the problem's :class:`~excite_cli.design.excitation.Excitation`, so
its result does not depend on where or in which order it runs. Pool and cluster workers build the
excitation from the main process's :class:`~excite_cli.design.spec.DesignSpec` once and keep it (one
per worker thread, for as long as the spec is the same): every value the main process resolved or
changed in memory reaches them, and no worker computes a base of its own. Every process that
runs tasks uses one BLAS thread, since the matrices are small and parallel workers would otherwise
oversubscribe the cores, and keeps the memory it frees (:func:`~excite_cli.memory.keep_freed_memory`).
"""

from __future__ import annotations

import hashlib
import os
import pickle
import signal
import threading
import time
import warnings
from concurrent.futures import Executor, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Callable, Iterator, Optional, Protocol, Sequence

from threadpoolctl import threadpool_limits

from excite_cli.design.excitation import Excitation, build_design
from excite_cli.design.spec import DesignSpec
from excite_cli.errors import NO_VALUE, ExciteError, ExciteWarning
from excite_cli.memory import keep_freed_memory
from excite_cli.search.scheduler import CONNECT_TIMEOUT, check_scheduler

#: Seconds a stopped worker process is given to end.
WORKER_STOP = 5.0
#: Seconds between looks at a Dask cluster's workers while its tasks run.
WORKER_LOOK = 1.0


class Task(Protocol):
    """A piece of work: ``task(excitation, progress)`` returns its result; ``progress`` (serial runs
    only) is the caller's hook for what the task reports while it runs."""

    index: int

    def __call__(self, excitation: Excitation, progress: Optional[Callable] = None) -> Any: ...


_local = threading.local()


def _worker_excitation(spec: DesignSpec) -> Excitation:
    """The excitation of ``spec`` in this worker (thread), built on first use and kept while the
    spec's values (its pickle) stay the same."""
    key = hashlib.sha256(pickle.dumps(spec)).digest()
    cache = getattr(_local, "cache", None)
    if cache is None or cache[0] != key:
        with warnings.catch_warnings():  # the main process gave them when it resolved the spec
            warnings.simplefilter("ignore", ExciteWarning)
            _local.cache = cache = (key, build_design(spec, check_home=False))
    return cache[1]


def run_on_worker(spec: DesignSpec, task: Task) -> Any:
    """``task`` in a pool or cluster worker, with the worker's own excitation of the main process's
    ``spec`` and, from then on, one BLAS thread in the worker's process (a worker is there to run tasks)."""
    threadpool_limits(limits=1)
    keep_freed_memory()
    return task(_worker_excitation(spec))


def _quiet_abandoned_gathers(loop, context: dict) -> None:
    """The Dask client's event loop reports what its tasks raise as asyncio does, except the
    ``AllExit`` of a result fetch given up on (:meth:`Engine._dask_completed` waits with a bound):
    it ends when the client closes, and would print a traceback after the run's own one line."""
    from distributed.client import AllExit

    if not isinstance(context.get("exception"), AllExit):
        loop.default_exception_handler(context)


def _worker_signals() -> None:
    """A pool worker leaves stopping to the main process: Ctrl-C (sent to the whole terminal group) is
    ignored, SIGTERM (sent by the main process when it stops) ends it at once, without a traceback."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


class Engine:
    """Runs tasks serially (``workers`` 1), in a local process pool of ``workers`` processes (at most
    as many as the first parallel run has tasks), or on the Dask scheduler at ``scheduler``.

    Use as a context manager: this process runs with one BLAS thread inside it (and keeps freed
    memory), and the pool or client is closed on exit. A Dask worker that dies mid-task is replaced
    by another (the scheduler runs the task again, and a task is a pure function of the spec and its
    seed, so the result is the same bit for bit); a cluster left without any worker for
    ``worker_wait`` seconds stops the run, as does a task that killed the workers it ran on.

    Raises:
        ExciteError: the scheduler cannot be reached.
    """

    def __init__(
        self, excitation: Excitation, workers: int = 1, scheduler: Optional[str] = None, worker_wait: float = 120.0
    ):
        self.excitation, self.workers, self.scheduler, self.worker_wait = excitation, workers, scheduler, worker_wait
        self._pool: Optional[Executor] = None
        self._client = None
        self._limits: Optional[threadpool_limits] = None

    def __enter__(self) -> "Engine":
        self._limits = threadpool_limits(limits=1)
        keep_freed_memory()
        if self.scheduler:
            check_scheduler(self.scheduler)
            from dask.distributed import Client

            try:
                self._client = Client(self.scheduler, timeout=f"{CONNECT_TIMEOUT:g}s")
            except (OSError, TimeoutError, ValueError) as exc:
                raise ExciteError(
                    "optimizer.scheduler", f"cannot reach the Dask scheduler at {self.scheduler}: {exc}"
                ) from None
            self._client.loop.asyncio_loop.set_exception_handler(_quiet_abandoned_gathers)
        return self

    def __exit__(self, kind, *exc) -> None:
        if self._pool is not None:
            # on an error or interruption the running tasks are not waited for: their processes are
            # stopped (the executor has no public call for it before Python 3.14)
            processes = list((self._pool._processes or {}).values()) if kind is not None else []
            manager = self._pool._executor_manager_thread if kind is not None else None
            self._pool.shutdown(wait=kind is None, cancel_futures=True)
            for process in processes:
                process.terminate()
            for process in processes:
                process.join(WORKER_STOP)
            if manager is not None:  # its teardown closes the wake-up pipe Python's exit handler writes to:
                manager.join(WORKER_STOP)  # met mid-close, that printed a traceback after the error line
        if self._client is not None:
            self._client.close()
        if self._limits is not None:
            self._limits.restore_original_limits()

    def run(
        self,
        tasks: Sequence[Task],
        progress: Optional[Callable] = None,
        on_result: Optional[Callable[[Any], None]] = None,
    ) -> list[Any]:
        """Results of all ``tasks``, in task order.

        Args:
            tasks: the tasks (distinct indices).
            progress: passed to each task when it runs in this process.
            on_result: called with each result as it arrives.

        Raises:
            ExciteError: a local worker process died (``optimizer.workers``: killed by the system, out
                of memory?); the Dask cluster had no worker for ``worker_wait`` seconds, or a task
                killed every worker it was given (``optimizer.scheduler``).
        """
        results = {}
        for task, result in self._completed(tasks, progress):
            results[task.index] = result
            if on_result is not None:
                on_result(result)
        return [results[task.index] for task in tasks]

    def _completed(self, tasks: Sequence[Task], progress: Optional[Callable]) -> Iterator[tuple[Task, Any]]:
        if (self._client is None and self.workers == 1) or len(tasks) == 1:  # no gain from other processes
            for task in tasks:
                yield task, task(self.excitation, progress)
            return
        spec = self.excitation.spec
        if self._client is not None:
            futures = {self._client.submit(run_on_worker, spec, task, pure=False): task for task in tasks}
            yield from self._dask_completed(futures)
            return
        if self._pool is None:  # sized by the work: more processes than tasks would only start and wait
            self._pool = ProcessPoolExecutor(max_workers=min(self.workers, len(tasks)), initializer=_worker_signals)
        try:  # a process killed while idle breaks the pool too: submit raises then
            pool_futures = {self._pool.submit(run_on_worker, spec, task): task for task in tasks}
            for future in as_completed(pool_futures):
                yield pool_futures[future], future.result()
        except BrokenProcessPool:
            raise ExciteError(
                "optimizer.workers",
                "a worker process died during the run (killed by the system: out of memory?)",
                NO_VALUE,
                "fewer workers, or a machine with more memory",
            ) from None

    def _dask_completed(self, futures: dict) -> Iterator[tuple[Task, Any]]:
        """``futures``' tasks and results as they finish, the cluster's workers looked at meanwhile."""
        from dask.distributed import KilledWorker, wait

        pending, alone_since = set(futures), None
        while pending:
            try:
                done, pending = wait(pending, timeout=WORKER_LOOK, return_when="FIRST_COMPLETED")
            except TimeoutError:
                done = set()
            arrived = False
            for future in done:
                try:  # bounded: a result held by a worker that died is 'lost' until another computes it
                    result = future.result(timeout=WORKER_LOOK)
                except TimeoutError:
                    pending.add(future)
                    continue
                except KilledWorker:
                    raise ExciteError(
                        "optimizer.scheduler",
                        f"task {futures[future].index} ended every worker that ran it (killed: out of memory?)",
                    ) from None
                arrived = True
                yield futures[future], result
            if arrived or self._client.nthreads():  # the scheduler is asked only when nothing arrived
                alone_since = None
            elif alone_since is None:
                alone_since = time.monotonic()
            elif time.monotonic() - alone_since > self.worker_wait:
                raise ExciteError(
                    "optimizer.scheduler",
                    f"the Dask cluster at {self.scheduler} had no worker for {self.worker_wait:g} s",
                    self.scheduler,
                    "a running worker (or a longer optimizer.worker_wait)",
                )


def default_workers() -> int:
    """The cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)

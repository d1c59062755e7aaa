"""Progress of long commands on the terminal: a bar per iteration with the objective at the current
iterate, the restart, elapsed time and an ETA; where the output is a log rather than a terminal, a line
every ``LOG_PERIOD`` seconds of work (iteration, run, solver iterations, objective, elapsed, estimate),
also while worker processes run restarts and report nothing until one ends (a heartbeat thread: the runs
reported, the lowest objective reported, elapsed), and one per finished iteration (with the optimizer's
stop reason); a bar for random draws."""

from __future__ import annotations

import sys
import threading
import time
from typing import TYPE_CHECKING, Callable

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from excite_cli.criteria import CRITERIA

if TYPE_CHECKING:  # annotations only: the command line's frame imports this module at start-up
    from excite_cli.config import OptimizerConfig
    from excite_cli.search.optimizer import ProgressHook
    from excite_cli.search.sequence import IterationResult

#: [s] between two progress lines in a log (no terminal); a heartbeat checks ten times a period, so
#: two lines are at most 1.1 periods (27.5 s) apart while an iteration runs.
LOG_PERIOD = 25.0
#: Width of printed tables where the output is not a terminal (a log, a pipe): rich's default of 80
#: columns would cut their numbers.
LOG_WIDTH = 200


def wide_console(stderr: bool = False) -> Console:
    """A console on stdout (or stderr) as wide as the terminal, or ``LOG_WIDTH`` where it is not one."""
    stream = sys.stderr if stderr else sys.stdout
    return Console(stderr=stderr, width=None if stream.isatty() else LOG_WIDTH)


def heartbeat(
    seen: dict, say: Callable[[], None], clock: Callable[[], float], period: float, name: str
) -> threading.Event:
    """A daemon thread (``name``) that calls ``say`` when ``period`` [s] of ``clock`` has passed since
    ``seen["last"]`` (a line printed), checking ten times a period, until the returned event is set."""
    stop = threading.Event()

    def beat() -> None:
        while not stop.wait(period / 10):
            now = clock()
            if now - seen["last"] >= period:
                seen["last"] = now
                say()

    threading.Thread(target=beat, name=name, daemon=True).start()
    return stop


class Bars:
    """One live display of bars on ``console`` (a context manager); it appears with the first bar, so
    an error found before any work is the only thing printed."""

    def __init__(self, console: Console, clock: Callable[[], float] = time.monotonic, period: float = LOG_PERIOD):
        self.console, self.clock, self.period = console, clock, period
        self._beats: list[threading.Event] = []
        self.bar = Progress(
            TextColumn("{task.description}"),
            BarColumn(),
            TextColumn("{task.fields[status]}"),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=console,
        )
        self._live = False

    def __enter__(self) -> "Bars":
        return self

    def __exit__(self, *exc) -> None:
        for beat in self._beats:
            beat.set()
        if self._live:
            self.bar.__exit__(*exc)

    def _task(self, description: str, total: int | None, status: str) -> int:
        if not self._live:
            self.bar.__enter__()
            self._live = True
        return self.bar.add_task(description, total=total, status=status)

    def iterations(
        self, opts: OptimizerConfig
    ) -> tuple[Callable[[int], ProgressHook], Callable[[IterationResult], None]]:
        """The hooks of :func:`~excite_cli.runs.run_optimize`: ``progress(k)`` per SLSQP iteration
        (the objective at the current iterate) and ``done(result)`` per finished iteration, for the
        ``optimizer`` section ``opts``."""
        bar = self.bar
        record = CRITERIA[opts.objective]
        label, shown = record.label, record.shown
        tasks: dict[int, int] = {}
        beats: dict[int, threading.Event] = {}  # a log's heartbeat per running iteration

        def progress(k: int) -> ProgressHook:
            tasks[k] = self._task(f"iteration {k}", opts.planned_iterations, "starting")
            steps: dict[int, int] = {}
            start = self.clock()
            runs = opts.screened + opts.restarts if opts.screened else opts.restarts
            seen = {"last": start, "lowest": float("inf"), "runs": runs}

            def heartbeat() -> None:
                elapsed = self.clock() - start
                lowest = f", lowest {label} reported {shown(seen['lowest']):.4g}" if steps else ""
                self.console.print(
                    f"iteration {k}: working, {len(steps)}/{seen['runs']} runs reported{lowest}, {elapsed:.0f} s",
                    highlight=False,
                )

            if not self.console.is_terminal:
                beats[k] = self._heartbeat(seen, heartbeat, k)

            def hook(restart: int, it: int, value: float) -> None:
                steps[restart] = it
                seen["lowest"] = min(seen["lowest"], value)
                runs_now = seen["runs"] = max(runs, restart + 1)  # an earlier optimum's run comes last
                done, status = sum(steps.values()), f"run {restart + 1}/{runs_now} · {label} {shown(value):.4g}"
                bar.update(tasks[k], completed=done, status=status)
                now = self.clock()
                if not self.console.is_terminal and now - seen["last"] >= self.period:
                    seen["last"], elapsed = now, now - start
                    left = elapsed * max(opts.planned_iterations - done, 0) / max(done, 1)
                    self.console.print(
                        f"iteration {k}: run {restart + 1}/{runs_now}, "
                        f"{done}/{opts.planned_iterations} solver iterations, "
                        f"{label} {shown(value):.4g}, {elapsed:.0f} s, about {left:.0f} s left",
                        highlight=False,
                    )

            return hook

        def done(result: IterationResult) -> None:
            beats.pop(result.index, threading.Event()).set()
            bar.update(
                tasks[result.index],
                completed=opts.planned_iterations,
                status=f"cond(C) {result.cond_stacked:.1f} · {result.stop}",
            )
            if not self.console.is_terminal:
                self.console.print(
                    f"iteration {result.index}: cond(C(i)) {result.cond_own:.1f}, cond(C) {result.cond_stacked:.1f}, "
                    f"{result.wall_time_s:.0f} s, {result.sqp_iterations} solver iterations, stop: {result.stop}",
                    highlight=False,
                )

        return progress, done

    def _heartbeat(self, seen: dict, say: Callable[[], None], k: int) -> threading.Event:
        """:func:`heartbeat` of iteration ``k``, stopped when the bars close too."""
        stop = heartbeat(seen, say, self.clock, self.period, f"progress-heartbeat-{k}")
        self._beats.append(stop)
        return stop

    def draws(self, total: int | None) -> Callable[[int, int], None]:
        """The (kept, drawn) hook of ``compare-random``'s random draws."""
        task: list[int] = []

        def hook(kept: int, drawn: int) -> None:
            if not task:
                task.append(self._task("random candidates", total, ""))
            self.bar.update(task[0], completed=kept, status=f"{kept} kept of {drawn} drawn")

        return hook


class Stages:
    """What a command without bars is doing (a context manager; :meth:`say` takes the line): a spinner
    with the line on a terminal; in a log, the line when ``period`` has passed since the last one
    printed, and a heartbeat thread that repeats the last line with the time elapsed while nothing new
    comes, so that lines are at most 1.1 periods apart (as :class:`Bars`' iterations)."""

    def __init__(
        self, console: Console, first: str, clock: Callable[[], float] = time.monotonic, period: float = LOG_PERIOD
    ):
        self.console, self.clock, self.period = console, clock, period
        self.start = clock()
        self.seen = {"last": self.start, "line": first}
        self._status = console.status(first) if console.is_terminal else None
        self._stop: threading.Event | None = None

    def __enter__(self) -> "Stages":
        if self._status is not None:
            self._status.__enter__()
        else:
            self._stop = heartbeat(self.seen, self._print, self.clock, self.period, "progress-heartbeat-stages")
        return self

    def __exit__(self, *exc) -> None:
        if self._stop is not None:
            self._stop.set()
        if self._status is not None:
            self._status.__exit__(*exc)

    def _print(self) -> None:
        self.seen["last"] = self.clock()
        self.console.print(f"{self.seen['line']}, {self.seen['last'] - self.start:.0f} s", highlight=False)

    def say(self, line: str) -> None:
        """Show ``line`` (what is under way, without the time)."""
        self.seen["line"] = line
        if self._status is not None:
            self._status.update(line)
        elif self.clock() - self.seen["last"] >= self.period:
            self._print()

"""Worker processes that stop cleanly: one place for every process pool in tenscell.

:func:`starmap` runs ``fn(*args)`` for each tuple of ``arglists`` in worker
processes and returns the results in order. What it guarantees, and why:

* **Ctrl-C stops within a second, quietly.** Workers ignore SIGINT (the
  terminal sends it to the whole process group; a worker that raised
  KeyboardInterrupt would print a traceback and could leave the pool waiting on
  a half-written pipe). The main process gets the KeyboardInterrupt, cancels
  what has not started, terminates the workers (SIGTERM, then SIGKILL after
  :data:`GRACE_S`) and re-raises.
* **Workers die with the main process.** On Linux each worker asks the kernel
  for SIGKILL when its parent dies (``prctl(PR_SET_PDEATHSIG)``), so
  ``kill -9`` of the main process leaves no worker; elsewhere a watchdog thread
  in the worker exits when its parent process id changes.
* **An error in one task stops the others**: the first exception (in task
  order) is re-raised in the main process after the workers are stopped.

``jobs=1`` runs everything in this process (no pool), with the same results.

:class:`CpuWindow` measures, over a stretch of this process's own work, its CPU
time and how many of its CPUs other processes kept busy meanwhile: what a
decision to start workers needs (the population engine's), where the wall clock
and the load average mislead on a shared machine.
"""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator, Literal, Sequence

__all__ = ["starmap", "Workers", "background", "sigint_deferred", "usable_cpus", "jobs_for", "GRACE_S", "CpuWindow",
           "CpuUse"]

#: seconds terminated workers get to exit before they are killed
GRACE_S = 0.5
_PR_SET_PDEATHSIG = 1
_WATCHDOG_PERIOD_S = 0.5


def usable_cpus() -> int:
    """CPUs this process may run on (its affinity mask where the system has one, else the CPU count)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


@dataclass(frozen=True)
class CpuUse:
    """What a :class:`CpuWindow` measured.

    Attributes
    ----------
    wall_s : float
        Elapsed time (s).
    cpu_s : float
        CPU time of this process, every thread, user + system (s).
    cpus : int
        CPUs this process may run on (:func:`usable_cpus`).
    busy_elsewhere : float
        CPUs (of ``cpus``) that other processes kept busy on average over the window, 0 to ``cpus``.
    source : str
        ``"/proc/stat"`` (measured over the window) or ``"load average"`` (the 1-minute load average less this
        process, where /proc/stat is missing or the window too short to count on it).
    """

    wall_s: float
    cpu_s: float
    cpus: int
    busy_elsewhere: float
    source: str

    @property
    def free(self) -> float:
        """CPUs no other process used: ``cpus - busy_elsewhere`` (this process's own use counts as free)."""
        return max(0.0, self.cpus - self.busy_elsewhere)


#: shortest window (s) over which /proc/stat's busy counts (10 ms ticks per CPU) are trusted; below it the
#: load average is used
MIN_WINDOW_S = 0.1


class CpuWindow:
    """Measure this process's CPU time and the CPUs others kept busy, from construction to :meth:`stop`.

    ``w = CpuWindow(); work(); use = w.stop()``. On Linux the busy time of this
    process's CPUs is read from ``/proc/stat`` at both ends and this process's
    own CPU time subtracted, so ``busy_elsewhere`` is what other processes used
    *during* the window (the 1-minute load average lags by a minute and counts
    processes waiting for disk). Elsewhere, or for a window shorter than
    :data:`MIN_WINDOW_S`, it is the load average less this process.
    """

    def __init__(self) -> None:
        self._cpus = sorted(_affinity())
        #: when the window opened (``time.perf_counter()``, s)
        self.started = time.perf_counter()
        self._cpu = time.process_time()
        self._stat = _cpu_ticks(self._cpus)

    def stop(self) -> CpuUse:
        """What was used from construction until now (the window can be stopped more than once)."""
        wall, cpu = time.perf_counter() - self.started, time.process_time() - self._cpu
        after = _cpu_ticks(self._cpus)
        n = len(self._cpus)
        if self._stat is not None and after is not None and wall >= MIN_WINDOW_S:
            busy, total = after[0] - self._stat[0], after[1] - self._stat[1]
            if total > 0:
                per_cpu = total / n  # elapsed ticks of one CPU
                others = (busy - cpu * _CLK_TCK) / per_cpu
                return CpuUse(wall, cpu, n, float(min(max(others, 0.0), n)), "/proc/stat")
        try:
            load = os.getloadavg()[0]
        except OSError:  # pragma: no cover - no load average: assume a quiet machine
            load = 0.0
        return CpuUse(wall, cpu, n, float(min(max(load - 1.0, 0.0), n)), "load average")


def _affinity() -> set[int]:
    try:
        return set(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return set(range(os.cpu_count() or 1))


try:
    _CLK_TCK = float(os.sysconf("SC_CLK_TCK"))
except (AttributeError, ValueError, OSError):  # pragma: no cover - not POSIX
    _CLK_TCK = 100.0


def _cpu_ticks(cpus: list[int]) -> tuple[int, int] | None:
    """(busy, total) ticks of the given CPUs since boot, from /proc/stat; None where it cannot be read.

    Busy is user + nice + system + irq + softirq + steal (steal: time the hypervisor gave to other machines);
    total adds idle and iowait.
    """
    try:
        with open("/proc/stat") as f:
            lines = f.read().splitlines()
    except OSError:
        return None
    wanted = {f"cpu{i}" for i in cpus}
    busy = total = 0
    seen = 0
    for line in lines:
        name, _, rest = line.partition(" ")
        if name in wanted:
            v = [int(x) for x in rest.split()[:8]]
            v += [0] * (8 - len(v))
            b = v[0] + v[1] + v[2] + v[5] + v[6] + v[7]
            busy, total, seen = busy + b, total + b + v[3] + v[4], seen + 1
    return (busy, total) if seen == len(cpus) else None


def jobs_for(tasks: int, jobs: int | None = None) -> int:
    """``jobs`` if given, else one worker process per usable CPU and at most one per task (the commands' default)."""
    return int(jobs) if jobs is not None else max(1, min(int(tasks), usable_cpus()))


def _die_with_parent(parent_pid: int) -> None:
    """Worker initializer: ignore SIGINT; exit when the parent process dies."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - no prctl: the watchdog below covers it
            pass
    if os.getppid() != parent_pid:  # the parent died before prctl took effect
        os._exit(1)

    def watchdog():
        while True:
            if os.getppid() != parent_pid:
                os._exit(1)
            threading.Event().wait(_WATCHDOG_PERIOD_S)

    threading.Thread(target=watchdog, name="tenscell-parent-watchdog", daemon=True).start()


def _stop_workers(pool) -> None:
    """Cancel pending tasks and end every worker now (SIGTERM, then SIGKILL)."""
    procs = list(getattr(pool, "_processes", {}).values())  # no public handle on the workers
    for p in procs:
        if p.is_alive():
            p.terminate()
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        p.join(GRACE_S)
        if p.is_alive():
            p.kill()
            p.join(GRACE_S)


def starmap(fn: Callable[..., Any], arglists: Iterable[Sequence[Any]], *, jobs: int = 1,
            on_done: Callable[[int, Any], None] | None = None) -> list:
    """``[fn(*args) for args in arglists]``, over ``jobs`` worker processes.

    Parameters
    ----------
    fn : callable
        A module-level function (it is pickled to the workers).
    arglists : iterable of tuples
        One tuple of positional arguments per task.
    jobs : int
        Worker processes (at most one per task); 1 runs in this process.
    on_done : callable(index, result), optional
        Called in the main process as each task finishes (for progress bars),
        in completion order.

    Returns
    -------
    list
        The results in task order.

    Raises
    ------
    KeyboardInterrupt
        After the workers are stopped (within about a second).
    Exception
        The first task's exception, after the workers are stopped.
    """
    tasks = [tuple(a) for a in arglists]
    with Workers(min(int(jobs), max(1, len(tasks)))) as workers:
        return workers.starmap(fn, tasks, on_done=on_done)


class Workers:
    """Worker processes kept for several :meth:`starmap` calls (rounds of an iterative search).

    ``with Workers(jobs) as w: w.starmap(fn, tasks)`` — the same guarantees
    as :func:`starmap`; the pool starts at the first call with ``jobs > 1``
    and ends with the block (stopped at once on an exception or Ctrl-C).
    """

    def __init__(self, jobs: int = 1):
        self.jobs = max(1, int(jobs))
        self._pool = None

    def __enter__(self) -> "Workers":
        return self

    def __exit__(self, exc_type, exc, tb) -> Literal[False]:
        pool, self._pool = self._pool, None
        if pool is not None:
            if exc_type is None:
                pool.shutdown(wait=True)
            else:
                _stop_workers(pool)
        return False

    def _start(self):
        from concurrent.futures import ProcessPoolExecutor

        if self._pool is None:
            self._pool = ProcessPoolExecutor(max_workers=self.jobs, initializer=_die_with_parent,
                                             initargs=(os.getpid(),))
        return self._pool

    def imap(self, fn: Callable[..., Any], arglists: Iterable[Sequence[Any]]) -> Iterator[Any]:
        """``fn(*args)`` for each task, yielded in task order.

        In this process (``jobs`` 1, or one task) each task runs only when its
        result is asked for, so a caller that stops reading stops the work; on
        the workers they all run (:meth:`starmap`) and the unread results are
        dropped.
        """
        tasks = [tuple(a) for a in arglists]
        if self._in_process(tasks):
            return (fn(*a) for a in tasks)
        return iter(self.starmap(fn, tasks))

    def _in_process(self, tasks: list) -> bool:
        return self.jobs == 1 or len(tasks) <= 1

    def starmap(self, fn: Callable[..., Any], arglists: Iterable[Sequence[Any]], *,
                on_done: Callable[[int, Any], None] | None = None) -> list:
        """``[fn(*args) for args in arglists]`` on these workers (in this process when ``jobs`` is 1)."""
        tasks = [tuple(a) for a in arglists]
        if self._in_process(tasks):
            results = []
            for i, a in enumerate(tasks):
                results.append(fn(*a))
                if on_done is not None:
                    on_done(i, results[-1])
            return results

        from concurrent.futures import FIRST_COMPLETED, wait

        pool = self._start()
        try:
            # workers are forked at the first submit; Ctrl-C is held meanwhile (and raised right after), so
            # that no worker can receive one before its initializer has run and none is lost
            with sigint_deferred():
                futures = [pool.submit(fn, *a) for a in tasks]
            index = {f: i for i, f in enumerate(futures)}
            pending = set(futures)
            while pending:
                done, pending = wait(pending, return_when=FIRST_COMPLETED)
                for f in sorted(done, key=lambda f: index[f]):
                    err = f.exception()
                    if err is not None:
                        raise err
                    if on_done is not None:
                        on_done(index[f], f.result())
            return [f.result() for f in futures]
        except BaseException:
            self._pool = None
            _stop_workers(pool)
            raise


@contextlib.contextmanager
def background():
    """One worker process beside this one for the block: ``bg.submit(fn, *args)`` returns a future.

    ``with background() as bg: task = bg.submit(fit, data); ...; result = task.result()``.
    Tasks run one after another in the same worker, so a later task finds
    what an earlier one imported. The same guarantees as :func:`starmap`: the
    worker ignores Ctrl-C and dies with this process; leaving the block by an
    exception or Ctrl-C stops it at once, leaving it normally waits for it.
    For independent work that would otherwise wait for an idle core (a fit's
    homogeneous baseline and its figure).
    """
    pool = _BackgroundPool()
    try:
        yield pool
    except BaseException:
        pool.stop()
        raise
    pool.close()


class _BackgroundPool:
    def __init__(self):
        from concurrent.futures import ProcessPoolExecutor

        self._pool = ProcessPoolExecutor(max_workers=1, initializer=_die_with_parent, initargs=(os.getpid(),))

    def submit(self, fn: Callable[..., Any], *args: Any):
        with sigint_deferred():  # no Ctrl-C while the worker is forked, before it has set up its own handling
            return self._pool.submit(fn, *args)

    def stop(self) -> None:
        _stop_workers(self._pool)

    def close(self) -> None:
        self._pool.shutdown(wait=True)


@contextlib.contextmanager
def sigint_deferred():
    """Hold Ctrl-C (SIGINT) during the block; raise KeyboardInterrupt after it if one came.

    For code that must not be cut in half (forking workers, swapping an output
    set into place). Only in the main thread, where Python handles signals;
    elsewhere the block runs unprotected. A process forked inside the block
    inherits the holding handler: a SIGINT it receives before it installs its
    own is recorded and dropped, never a KeyboardInterrupt traceback.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if caught and previous not in (signal.SIG_IGN, None):
        raise KeyboardInterrupt

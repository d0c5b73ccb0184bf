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
"""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from typing import Any, Callable, Iterable, Iterator, Literal, Sequence

__all__ = ["starmap", "Workers", "background", "sigint_deferred", "usable_cpus", "jobs_for", "GRACE_S"]

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

"""The Dask side of populations and studies: connect to a cluster, stream tasks through it.

One place for what every distributed run needs:

* :func:`cluster` — a client on an existing scheduler (tcp address or scheduler
  file) or on a local cluster of processes started here (loopback only, no
  dashboard, one thread per worker), or no client at all (``workers=0``: the
  tasks run in this process, in order);
* :func:`stream` — submit tasks, a batch per Dask task, through a bounded
  window and yield each result as it completes, so that 10⁵ tasks never sit
  in the cluster at once and the caller can write each result as it arrives;
* :func:`run_tasks` — what the commands use: runs the first tasks here,
  measuring their CPU time and the CPUs other processes keep busy
  (:class:`tenscell._parallel.CpuWindow`), and from those decides
  (:func:`plan`) whether a local cluster, and of how many workers, pays for
  its start-up — each worker charged its own — or every task stays here;
  the rest go to the cluster in batches of about two seconds of CPU each.

A worker that dies while running a task is replaced (by its nanny on a local
cluster) and the scheduler reruns the task elsewhere; after
``distributed.scheduler.allowed-failures`` deaths (default 3) the task is given
up with :class:`distributed.KilledWorker`, which :func:`stream` yields as that
task's outcome instead of stopping the run.
"""
from __future__ import annotations

import contextlib
import itertools
import logging
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

from .._errors import TenscellError
from .._parallel import CpuUse, CpuWindow, usable_cpus

__all__ = ["cluster", "stream", "run_tasks", "plan", "Plan", "batch_size", "batch_sizes", "check_scheduler",
           "TaskLost", "SchedulerLost", "n_threads", "open_work_dir", "WorkDirError"]


class WorkDirError(TenscellError, ValueError):
    """A work directory holds a different or unfinished run (one line naming it)."""


def open_work_dir(path, settings_file: str, settings: dict, resume: bool) -> Path:
    """Prepare the work directory of a resumable run: new or empty, or an unfinished run with the same settings.

    ``settings`` are written to ``path/settings_file``. Raises :class:`WorkDirError`
    when the directory holds an unfinished run and ``resume`` is False, a run
    with other settings, or files of something else.
    """
    import json

    from ..io.outputs import json_ready, write_json

    path = Path(path)
    info = path / settings_file
    if info.is_file():
        if not resume:
            raise WorkDirError(f"{path}: holds an unfinished run; resume it (--resume) or remove the directory")
        old = json.loads(info.read_text())
        new = json_ready(settings)  # as written: compared with what the unfinished run wrote
        notes = ("null_means", "non_finite")  # what the JSON writer adds about nulls, not settings
        diff = sorted(k for k in set(old) | set(new) if k not in notes and old.get(k) != new.get(k))
        if diff:
            raise WorkDirError(f"{path}: the unfinished run used different settings ({', '.join(diff)}); "
                               "resume with the same settings or remove the directory")
    elif path.exists() and any(path.iterdir()):
        raise WorkDirError(f"{path}: exists, is not empty and holds no {settings_file}")
    path.mkdir(parents=True, exist_ok=True)
    write_json(info, settings)
    return path


class TaskLost(TenscellError):
    """A task whose workers kept dying (Dask gave up on it); carries Dask's message."""


class SchedulerLost(TenscellError, ConnectionError):
    """The connection to the Dask scheduler was lost: the run stops; what was written is kept."""


def check_scheduler(address: str, flag: str = "--scheduler") -> str:
    """Validate a scheduler address (``tcp://host:port``, ``host:port``) or an existing scheduler file.

    Only the form is checked here (before any computation); connecting is :func:`cluster`'s job.
    """
    text = str(address).strip()
    if not text:
        raise ValueError(f"{flag}: empty scheduler address")
    if Path(text).is_file():
        return text
    body = text.split("://", 1)[1] if "://" in text else text
    host, _, port = body.rpartition(":")
    if not host or not port.isdigit():
        raise ValueError(f"{flag} {text}: neither an existing scheduler file nor an address like tcp://HOST:PORT")
    return text


@contextlib.contextmanager
def cluster(*, client=None, workers: int | None = None, scheduler: str | None = None,
            timeout: float = 30.0, warm: tuple[str, ...] = ()) -> Iterator[Any]:
    """Yield a Dask client (or None for in-process execution when ``workers == 0``).

    Parameters
    ----------
    client : distributed.Client, optional
        Used as is (not closed here).
    workers : int, optional
        Size of the local cluster started when no client or scheduler is given
        (default: the machine's CPU count); 0 runs every task in this process.
    scheduler : str, optional
        Address or scheduler file of an existing cluster.
    timeout : float
        Seconds to wait for the scheduler (s).
    warm : tuple of str
        Modules every worker imports when it starts (a replacement worker too),
        so that the first task's time is the task's, not the imports'.
    """
    if client is not None:
        yield client
        return
    if scheduler is None and workers == 0:
        yield None
        return
    from .._optional import require

    require("distributed")  # an optional dependency: one line naming the extra
    from distributed import Client

    if scheduler is not None:
        scheduler = check_scheduler(scheduler)
        kw = {"scheduler_file": scheduler} if Path(scheduler).is_file() else {"address": scheduler}
        with Client(timeout=timeout, **kw) as c:
            _warm_workers(c, warm)
            yield c
        return
    n = usable_cpus() if workers is None else int(workers)
    with _local_cluster(n, timeout) as c:
        _warm_workers(c, warm)
        yield c


def _warm_workers(client, modules: tuple[str, ...]) -> None:
    if modules:
        from ._warm import Imports  # a Dask class: imported only with a cluster

        client.register_plugin(Imports(tuple(modules)), name="tenscell-imports")


#: environment of a local cluster's worker processes: one BLAS/OpenMP thread, as every hot path of the main
#: process runs (Dask's default also sets MALLOC_TRIM_THRESHOLD_, which the main process does not have)
WORKER_ENVIRON = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
#: Dask settings of a local cluster (its scheduler and nannies in this process, its workers): what a few
#: long-running batches of tenscell tasks do not need, measured in CPU of an idle 1-worker cluster over 10 s
#: (bench/bench_population.py): this process 0.25 s -> 0.05 s, the worker 0.15 s -> 0.03 s (1.5-2.5 % of a
#: core each -> 0.3-0.5 %).
#:
#: * no statistical profiler: it samples the task thread's stack every 10 ms and takes the GIL to do it; a
#:   cell's fit took 9.5 % longer in a Dask worker than in a plain worker process with it (30 cells);
#: * the event-loop health check every second, not every 20 ms (it warns after 3 s blocked: still seen);
#: * the system monitor (CPU, memory, disk I/O for the dashboard and heartbeats) every 2 s, not 0.5 s;
#: * the memory monitor (pause at 80 %, terminate at 95 % of the memory limit) every second, not every
#:   100 ms (it runs in this process, one psutil call per worker);
#: * no active memory manager: it moves replicas of data between workers every 2 s; tasks here share none.
WORKER_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.scheduler.active-memory-manager.start": False,
}


@contextlib.contextmanager
def _local_cluster(n: int, timeout: float) -> Iterator[Any]:
    """A loopback cluster of ``n`` single-thread worker processes that Ctrl-C leaves quiet and stops at once.

    The terminal sends SIGINT to every process of the foreground group; Dask's
    worker processes would each print a KeyboardInterrupt traceback and their
    nannies a CancelledError. So Dask's event-loop thread is started here with
    SIGINT blocked: it keeps the block, and so does every thread and worker
    process it starts (at start-up and when it replaces a dead worker) —
    workers never see Ctrl-C. This thread alone handles it, at any moment
    including start-up, and then kills the workers (:func:`_kill_workers`):
    their work is dropped anyway. No dashboard; the scheduler's own HTTP
    endpoint takes a free loopback port (never "port 8787 is already in use").
    """
    import dask
    from distributed import Client, LocalCluster
    from distributed.utils import LoopRunner

    with _sigint_blocked():
        loop = LoopRunner()
        loop.start()
    lc = client = None
    quiet = _Quiet()
    try:
        with dask.config.set({"distributed.nanny.pre-spawn-environ": WORKER_ENVIRON, **WORKER_CONFIG}):
            lc = LocalCluster(n_workers=0, threads_per_worker=1, processes=True, host="127.0.0.1", loop=loop.loop,
                              dashboard_address=None, silence_logs=logging.ERROR,
                              scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"})
            client = Client(lc, timeout=timeout)
            lc.scale(n)
            # ready means every worker is up: a run never starts on a half-built cluster, nor does a test wait
            # a fixed time for one (the bound only keeps a broken machine from hanging here)
            client.wait_for_workers(n, timeout=max(timeout, 300.0))
        yield client
    finally:
        # the workers hold nothing once the block is left (results are in, or dropped on Ctrl-C or an error):
        # they are ended at once rather than asked to close (0.7-0.9 s at load 10), and the teardown then
        # logs nothing (the scheduler reports each closed connection, a nanny its worker that died starting)
        quiet.start()
        try:
            if lc is not None:
                _kill_workers(lc)
            if client is not None:
                client.close(timeout=2)
            if lc is not None:
                lc.close(timeout=5)
            loop.stop()
        finally:
            quiet.stop()


class _Quiet:
    """Silence logging (Dask's, Tornado's: their loggers set their own levels) until :meth:`stop`."""

    def __init__(self):
        self._before: int | None = None

    def start(self) -> None:
        self._before = logging.root.manager.disable
        logging.disable(logging.CRITICAL)

    def stop(self) -> None:
        if self._before is not None:
            logging.disable(self._before)
        self._before = None


def _kill_workers(lc) -> None:
    """SIGKILL a local cluster's worker processes, started or still starting (on Ctrl-C or an error)."""
    import signal

    from distributed.core import Status

    # the nannies still starting are not in .workers yet (only in the private ._created)
    for nanny in {*getattr(lc, "workers", {}).values(), *getattr(lc, "_created", ())}:
        if nanny.status == Status.running:
            # a running nanny restarts a worker that dies (and closing would wait for the new one); one that
            # is closing gracefully closes itself instead
            nanny.status = Status.closing_gracefully
        # the multiprocessing.Process under Dask's wrappers has its pid from the moment it is forked
        proc = getattr(getattr(getattr(nanny, "process", None), "process", None), "_process", None)
        pid = getattr(proc, "pid", None)
        if pid:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)


@contextlib.contextmanager
def _sigint_blocked():
    """Block SIGINT in this thread (and threads/processes it starts) for the block; main thread only."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    # multiprocessing starts its resource tracker at first need, blocking and then *unblocking* SIGINT in the
    # thread that starts it (it would undo this block in Dask's event-loop thread): start it now
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)  # a Ctrl-C held meanwhile is raised here


def n_threads(client) -> int:
    """Total worker threads of a client's cluster (1 for in-process execution)."""
    if client is None:
        return 1
    return max(1, sum(client.nthreads().values()))


#: CPU seconds of work a Dask task is given by batching: a task costs about 2.3 ms of CPU in this process and
#: the worker together (200 trivial tasks on a 1-worker cluster: 0.24 s + 0.22 s), 0.1 % of two seconds
TASK_SECONDS = 2.0
#: CPU seconds one local worker takes to be ready: a new interpreter importing distributed and the task's
#: modules (0.74-0.76 s measured on 2 cores; bench/bench_population.py prints this machine's)
WORKER_START_CPU_S = 0.8
#: CPU seconds this process takes to import distributed and start a scheduler (0.23 s + 0.05 s measured),
#: charged when distributed is not imported yet
SCHEDULER_START_CPU_S = 0.3
#: wall seconds a local cluster takes to be ready beyond its CPU (spawning processes, connecting them):
#: 0.2-0.6 s measured
CLUSTER_LATENCY_S = 0.5
#: CPU a cluster adds per second of task work: its scheduler, nannies and heartbeats (0.3-0.5 % of a core per
#: process with :data:`WORKER_CONFIG`), the tasks' transfers and the last batches' imbalance, rounded up
CLUSTER_OVERHEAD = 0.02
#: each worker started must be given at least this many times its start-up CPU in work: a cluster's start-up
#: is then at most a tenth of what it runs
WORK_PER_START = 10.0
#: a cluster is started only when estimated this much faster (wall) than this process: room for the
#: estimate's error, so that the default never makes a run slower
PAY_MARGIN = 0.25
#: seconds of tasks run here, and measured, before deciding (one task at least, however long)
SAMPLE_S = 0.5


@dataclass(frozen=True)
class Plan:
    """Where :func:`run_tasks` runs the rest of the tasks when the caller did not say (:func:`plan`).

    Attributes
    ----------
    workers : int
        Local Dask workers to start; 0: every task here.
    tasks : int
        Tasks left to run.
    task_cpu_s : float
        Measured CPU seconds per task (this process, every thread).
    use : CpuUse
        What was measured while the first tasks ran: CPUs, how many others kept busy.
    here_s : float
        Estimated wall seconds of the rest in this process.
    cluster_s : float or None
        Estimated wall seconds on the cluster considered (None: not even one of 2 workers fits the free CPUs
        or pays for its start-up).
    """

    workers: int
    tasks: int
    task_cpu_s: float
    use: CpuUse
    here_s: float
    cluster_s: float | None

    def describe(self) -> str:
        """One line: what was measured and what was decided, in the user's terms."""
        u = self.use
        head = (f"{self.tasks} more tasks of {self.task_cpu_s:.2g} s CPU each; {u.cpus} CPU(s), "
                f"{u.busy_elsewhere:.1f} busy with other work")
        if self.workers:
            return (f"{head}: a local Dask cluster of {self.workers} workers (about {self.cluster_s:.0f} s against "
                    f"{self.here_s:.0f} s in this process)")
        if self.cluster_s is None:
            if u.cpus < 2:
                why = "one CPU"
            elif int(u.free + 0.5) < 2:
                why = "fewer than 2 CPUs are free"
            else:
                why = (f"each worker would get less than {WORK_PER_START:g}x its start-up (about "
                       f"{WORKER_START_CPU_S:g} s CPU) in work")
        else:
            why = f"about {self.cluster_s:.1f} s on a local Dask cluster against {self.here_s:.1f} s here"
        return f"{head}: they run in this process ({why})"


def _share(use: CpuUse, processes: int) -> float:
    """Fraction of a CPU each of ``processes`` busy processes of ours gets beside the others' measured load."""
    return min(1.0, use.cpus / max(use.busy_elsewhere + processes, 1e-9))


def plan(tasks: int, task_cpu_s: float, use: CpuUse, *, distributed_imported: bool = False) -> Plan:
    """Whether ``tasks`` of ``task_cpu_s`` CPU seconds each finish sooner on a new local cluster, and on how many workers.

    Workers: at most the CPUs free of other work (``use.free``, rounded), and
    each must be given at least :data:`WORK_PER_START` times its own start-up
    CPU (:data:`WORKER_START_CPU_S`) in work. The cluster is chosen when its
    estimated wall time — its start-up (each worker's imports at the share of
    a CPU it gets, the latency, importing distributed here unless
    ``distributed_imported``) plus the work spread over the workers with
    :data:`CLUSTER_OVERHEAD` — is below this process's by :data:`PAY_MARGIN`.
    Wall times are CPU times divided by the share of a CPU a process gets beside
    the others' load, so a loaded machine stretches both sides.
    """
    work = max(0, int(tasks)) * max(float(task_cpu_s), 0.0)
    here = work / _share(use, 1)
    most = min(use.cpus, int(use.free + 0.5), int(work / (WORK_PER_START * WORKER_START_CPU_S)))
    if most < 2:
        return Plan(0, int(tasks), float(task_cpu_s), use, here, None)

    def wall(n: int) -> float:
        s = _share(use, n)
        start = WORKER_START_CPU_S / s + CLUSTER_LATENCY_S
        start += 0.0 if distributed_imported else SCHEDULER_START_CPU_S / _share(use, 1)
        return start + work * (1.0 + CLUSTER_OVERHEAD) / (n * s)

    n = min(range(2, most + 1), key=wall)
    best = wall(n)
    return Plan(n if best * (1.0 + PAY_MARGIN) <= here else 0, int(tasks), float(task_cpu_s), use, here, best)


def batch_size(n_tasks: int, task_s: float, n_threads: int) -> int:
    """Tasks per Dask task: about :data:`TASK_SECONDS` of work, and still at least 4 per worker thread."""
    k = max(1, round(TASK_SECONDS / max(task_s, 1e-6)))
    return int(max(1, min(k, n_tasks // (4 * max(1, n_threads)))))


def run_tasks(fn: Callable, items: Iterable[tuple[object, tuple]], *, client=None, workers: int | None = None,
              scheduler: str | None = None, name: str = "tenscell", warm: tuple[str, ...] = (),
              notify: Callable[[str], None] | None = None, placed: dict | None = None) -> Iterator[tuple[Any, Any]]:
    """Run ``fn(*args)`` for each ``(tag, args)``, on Dask or here; yield ``(tag, result)`` as each completes.

    The first task runs here and its CPU time sets the batch size (Dask tasks of
    about :data:`TASK_SECONDS` of CPU each, so Dask's per-task cost is noise).
    When neither ``client``, ``scheduler`` nor ``workers`` is given, tasks keep
    running here for :data:`SAMPLE_S` while the CPUs other processes use are
    measured, and :func:`plan` decides whether a local cluster pays and of how
    many workers; ``notify`` gets one line saying what was decided and why.
    ``workers=0`` runs everything here. Results do not depend on where a task
    ran. ``placed``, if given, receives ``workers``: the Dask workers used (0:
    this process), and ``plan``: the :class:`Plan` when one was made.
    """
    placed = {} if placed is None else placed
    placed["workers"] = 0
    items = list(items)
    if not items:
        return
    if workers == 0 and client is None and scheduler is None:
        yield from ((tag, fn(*args)) for tag, args in items)
        return
    deciding = client is None and scheduler is None and workers is None
    window, done = CpuWindow(), 0
    cpu: list[float] = []  # CPU seconds of each task run here
    # tasks here until the sample is long enough to judge (deciding) or the first one (sizing the batches)
    while done < len(items) and (not cpu or (deciding and time.perf_counter() - window.started < SAMPLE_S)):
        tag, args = items[done]
        c = time.process_time()
        result = fn(*args)
        cpu.append(time.process_time() - c)
        done += 1
        yield tag, result
    rest = items[done:]
    if not rest:
        if deciding and notify is not None:
            notify(f"all {done} tasks ran in this process in {time.perf_counter() - window.started:.2g} s, "
                   "while it measured them (less than a local Dask cluster takes to start)")
        return
    # the first task pays for first-use costs (imports, caches): the later ones, when there are any, say more
    task_cpu = sum(cpu[1:]) / (len(cpu) - 1) if len(cpu) > 1 else cpu[0]
    if deciding:
        p = plan(len(rest), task_cpu, window.stop(), distributed_imported="distributed" in sys.modules)
        placed["plan"] = p
        if notify is not None:
            notify(p.describe())
        if p.workers == 0:
            yield from ((tag, fn(*args)) for tag, args in rest)
            return
        workers = p.workers
    with cluster(client=client, workers=workers, scheduler=scheduler, warm=warm) as c:
        placed["workers"] = len(c.nthreads())
        yield from stream(c, fn, rest, name=name, batch=batch_size(len(rest), task_cpu, n_threads(c)))


def batch_sizes(n_items: int, batch: int, n_threads: int) -> list[int]:
    """Items per Dask task, in the order of submission: ``batch`` each, shrinking toward the end.

    Guided self-scheduling: no task holds more than ``1/(2·n_threads)`` of the
    items not yet handed out, so the last tasks are small and the workers
    finish together, rather than one idling while another runs a full last
    batch (up to :data:`TASK_SECONDS` of a run).
    """
    sizes, left = [], int(n_items)
    per = 2 * max(1, int(n_threads))
    while left > 0:
        k = max(1, min(int(batch), -(-left // per)))
        sizes.append(k)
        left -= k
    return sizes


def _run_batch(fn: Callable, arglists: list) -> list:
    """One Dask task: ``fn(*args)`` for each of ``arglists``, in order."""
    return [fn(*args) for args in arglists]


def stream(client, fn: Callable, items: Iterable[tuple[object, tuple]], *, window: int | None = None,
           name: str = "tenscell", batch: int = 1) -> Iterator[tuple[Any, Any]]:
    """Run ``fn(*args)`` for each ``(tag, args)`` of ``items``; yield ``(tag, result)`` as each completes.

    Items go to the cluster ``batch`` at a time (one Dask task each; for a
    list, fewer toward the end, :func:`batch_sizes`); at most
    ``window`` tasks are in the cluster at a time (default: 8 per worker
    thread, at least 32), refilled as results arrive. A task given up by Dask
    after repeated worker deaths yields a :class:`TaskLost` as the result of
    each of its items. With ``client=None`` the items run here, in order.

    Closing the generator (or an interrupt) cancels the tasks still in flight.
    """
    if client is None:
        for tag, args in items:
            yield tag, fn(*args)
        return
    from concurrent.futures import CancelledError

    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    window = window or max(32, 8 * n_threads(client))
    sizes = iter(batch_sizes(len(items), batch, n_threads(client))) if isinstance(items, (list, tuple)) else None
    it = iter(items)
    pending: dict = {}
    done = as_completed()

    def submit_next() -> bool:
        group = list(itertools.islice(it, max(1, int(batch) if sizes is None else next(sizes, 1))))
        if not group:
            return False
        fut = client.submit(_run_batch, fn, [args for _, args in group], pure=False,
                            key=f"{name}-{os.urandom(8).hex()}")
        pending[fut.key] = ([tag for tag, _ in group], fut)
        done.add(fut)
        return True

    try:
        for _ in range(window):
            if not submit_next():
                break
        for fut in done:
            tags, _ = pending.pop(fut.key)
            try:
                results = fut.result()
            except KilledWorker as err:
                results = [TaskLost(f"the workers running it died repeatedly ({err})")] * len(tags)
            except CancelledError:
                # only a lost scheduler cancels our futures; the finished results are already written
                raise SchedulerLost("lost the Dask scheduler; the finished results are kept: "
                                    "run the same command with --resume when the cluster is back") from None
            fut.release()
            yield from zip(tags, results)
            submit_next()
    finally:
        if pending and client.status == "running":
            client.cancel([f for _, f in pending.values()])

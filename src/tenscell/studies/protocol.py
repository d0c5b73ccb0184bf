"""The study protocol: a study plans its work as tasks, runs them, and returns one result the writer puts on disk.

As lmfit's ``Model`` → ``ModelResult`` is for a fit, and pyMOR's one interface is for every model, every study
follows the same three steps:

* ``study.plan(options)`` → a :class:`Plan`: the study's options, checked, and its :class:`Task` list — every fit
  and evaluation the run will make. The plan is the one count both the run and the estimate use: the command
  line announces ``plan.estimate_cpu(rates)`` before the work, and :func:`execute` revises it as tasks finish.
* ``study.run(plan)`` → a :class:`StudyResult` (by default :func:`execute` the tasks, then ``study.assemble(plan,
  results)``): the study's tables with **named columns** (:class:`Table`, never positional tuples), its figures
  (:class:`Figure`: a drawing function of :mod:`tenscell.plotting` by name, reached through
  :func:`tenscell._results.plotter`), its Markdown (rendered by :mod:`tenscell.reports` through
  :func:`tenscell._results.reporter`), its checks (:class:`Check`: each goal as measured) and the study's own
  result object for Python users (``result.data``).
* one writer (``tenscell study NAME``) puts every table, figure and page of any study on disk, as a complete set
  or not at all.

A study declares the ``options`` it takes (name → default; :func:`study_options` fills them in and refuses any
other, naming it in flag syntax, ``--draws``): the command line passes the flags the user gave and nothing else.

A task names a module-level function (it may run in a worker process) and its arguments; ``needs`` lists the
keys of earlier tasks whose results are appended to its arguments (a held-out refit warm-started from the main
fit needs the main fit). Tasks of one ``kind`` cost about the same per unit of ``weight``: the estimate is
``Σ weight × rate[kind]`` over the tasks, with each kind's rate measured (before the run from a calibration the
study gives, during it from the tasks already done).

**The calibration.** A plan carries probes (``Plan.calibration``): small tasks of the same work, each of a kind
with its ``weight`` in units of that kind (one Jacobian evaluation of a fit that takes about 300 of them: weight
1/300). :func:`calibrate` runs each (once to load what it imports, once timed) and gives every kind's rate in
CPU seconds per unit; :class:`Machine` turns CPU time into wall time with the share of a CPU each worker can
expect now (measured over the calibration, :class:`tenscell._parallel.CpuWindow`), and
:meth:`Plan.estimate_wall` adds the plan up wave by wave, with the writer's figures.
"""
from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

__all__ = ["Task", "Plan", "Table", "Figure", "Check", "StudyResult", "Study", "execute", "run_study",
           "TaskRecord", "calibrate", "Machine", "study_options", "flag", "FIGURE"]

#: a calibration probe is timed again while its CPU seconds stay below this, up to PROBE_CALLS calls
PROBE_CPU_S = 0.1
PROBE_CALLS = 3
#: the kind of the writer's work: drawing and saving one figure (a unit: a two-panel log-log figure of a few
#: curves, :func:`figure_probe`)
FIGURE = "figure"


@dataclass(frozen=True)
class Task:
    """One unit of a study's work: a fit, a refit, an evaluation.

    Attributes
    ----------
    key : str
        Unique within the plan (e.g. ``"springpot+visc/held-out/fabry2001 ≤ 1 Hz"``).
    kind : str
        What the task is (``"fit"``, ``"refit"``, ``"evaluate"``...): tasks of one kind share a CPU rate.
    fn : callable
        A module-level function (pickled to a worker when the plan runs on several).
    args : tuple
        Its positional arguments; the results of ``needs`` follow them, in that order.
    needs : tuple of str
        Keys of earlier tasks of the plan whose results this task takes.
    weight : float
        Its cost in units of its kind's rate (1: a typical task of the kind).
    """

    key: str
    kind: str
    fn: Callable[..., Any]
    args: tuple = ()
    needs: tuple = ()
    weight: float = 1.0

    def __post_init__(self):
        if not isinstance(self.key, str) or not self.key:
            raise ValueError(f"Task: key must be a non-empty string, got {self.key!r}")
        if not (isinstance(self.weight, (int, float)) and math.isfinite(self.weight) and self.weight > 0):
            raise ValueError(f"Task {self.key!r}: weight must be a finite number > 0, got {self.weight!r}")
        object.__setattr__(self, "args", tuple(self.args))
        object.__setattr__(self, "needs", tuple(self.needs))


@dataclass(frozen=True, eq=False)
class Plan:
    """A study's checked options and every task its run makes, in an order where each task follows its needs.

    Attributes
    ----------
    study : str
        The study's name (``tenscell study NAME``).
    options : dict
        The options the study was planned with (as given to :meth:`Study.plan`, defaults filled in).
    tasks : tuple of Task
    calibration : tuple of Task
        Probes for the estimate (module docstring): each a small piece of the work of its ``kind``, its
        ``weight`` that piece in units of the kind; none needs another task.
    figures : float
        What the writer will draw, in units of :data:`FIGURE` (one typical figure: 1).
    jobs : int
        Worker processes over the tasks of a wave (1: in this process).
    sized_by : tuple of str
        The options that set the plan's size, in flag syntax (``("--draws",)``): named when a run is refused as
        too long.
    """

    study: str
    options: dict
    tasks: tuple
    calibration: tuple = ()
    figures: float = 0.0
    jobs: int = 1
    sized_by: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "tasks", tuple(self.tasks))
        object.__setattr__(self, "calibration", tuple(self.calibration))
        object.__setattr__(self, "sized_by", tuple(self.sized_by))
        if not (isinstance(self.jobs, int) and self.jobs >= 1):
            raise ValueError(f"Plan {self.study!r}: jobs must be an integer >= 1, got {self.jobs!r}")
        if not (math.isfinite(self.figures) and self.figures >= 0):
            raise ValueError(f"Plan {self.study!r}: figures must be a finite number >= 0, got {self.figures!r}")
        for t in self.calibration:
            if not isinstance(t, Task) or t.needs:
                raise ValueError(f"Plan {self.study!r}: a calibration probe is a Task that needs no other task")
        seen: set[str] = set()
        for t in self.tasks:
            if not isinstance(t, Task):
                raise ValueError(f"Plan {self.study!r}: tasks must be Task objects, got {type(t).__name__}")
            if t.key in seen:
                raise ValueError(f"Plan {self.study!r}: task key {t.key!r} appears twice")
            missing = [k for k in t.needs if k not in seen]
            if missing:
                raise ValueError(f"Plan {self.study!r}: task {t.key!r} needs {missing[0]!r}, which is not an "
                                 "earlier task of the plan")
            seen.add(t.key)

    def count(self, kind: str | None = None) -> int:
        """How many tasks (of ``kind``, or all)."""
        return sum(1 for t in self.tasks if kind is None or t.kind == kind)

    def kinds(self) -> dict[str, float]:
        """The total weight of each kind of task."""
        out: dict[str, float] = {}
        for t in self.tasks:
            out[t.kind] = out.get(t.kind, 0.0) + float(t.weight)
        return out

    def estimate_cpu(self, rates: Mapping[str, float]) -> float:
        """CPU seconds of the whole plan at ``rates`` (CPU seconds per unit of weight, by kind). KeyError names a
        kind without a rate."""
        total = 0.0
        for kind, w in self.kinds().items():
            if kind not in rates:
                raise KeyError(f"no CPU rate for tasks of kind {kind!r} (kinds of this plan: "
                               f"{', '.join(self.kinds())})")
            total += w * float(rates[kind])
        return total

    def estimate_wall(self, rates: Mapping[str, float], machine: Machine | None = None) -> float:
        """Wall seconds of the whole plan and its figures at ``rates`` (CPU s per unit, by kind; :data:`FIGURE`
        among them when the plan has figures), on ``machine`` (default: one whole CPU per process).

        Wave by wave: a wave's tasks share ``min(jobs, tasks)`` workers, so it lasts its CPU over them or its
        longest task, whichever is more, at the share of a CPU each of them gets; the figures follow, drawn in
        this process.
        """
        machine = Machine(cpus=float(self.jobs)) if machine is None else machine
        self.estimate_cpu(rates)  # KeyError naming a kind without a rate
        wall = 0.0
        for wave in _waves(self):
            cpu = [t.weight * float(rates[t.kind]) for t in wave]
            n = min(self.jobs, len(wave))
            wall += max(max(cpu), sum(cpu) / n) / machine.share(n)
        if self.figures:
            wall += self.figures * float(rates[FIGURE]) / machine.share(1)
        return wall

    def task(self, key: str) -> Task:
        for t in self.tasks:
            if t.key == key:
                return t
        raise KeyError(f"no task {key!r} in the plan of study {self.study!r}")


@dataclass(frozen=True)
class Table:
    """A table with named columns (units in the names: ``rms_fabry2001_decades``, ``prestress_Pa``).

    Build it from records (:meth:`from_records`): each record names its values, so a column cannot shift.
    """

    name: str
    columns: tuple
    rows: tuple
    description: str = ""

    def __post_init__(self):
        cols = tuple(self.columns)
        if len(set(cols)) != len(cols):
            dup = next(c for c in cols if cols.count(c) > 1)
            raise ValueError(f"table {self.name!r}: column {dup!r} appears twice")
        rows = tuple(tuple(r) for r in self.rows)
        for i, r in enumerate(rows):
            if len(r) != len(cols):
                raise ValueError(f"table {self.name!r}: row {i} has {len(r)} values for {len(cols)} columns")
        object.__setattr__(self, "columns", cols)
        object.__setattr__(self, "rows", rows)

    @classmethod
    def from_records(cls, name: str, records: Sequence[Mapping[str, Any]], columns: Sequence[str] | None = None,
                     description: str = "") -> Table:
        """A table from one mapping per row. ``columns`` (default: the first record's keys, in order) must be
        exactly every record's keys: ValueError names the row and the column missing or extra."""
        records = list(records)
        cols = tuple(columns) if columns is not None else (tuple(records[0]) if records else ())
        want = set(cols)
        rows = []
        for i, rec in enumerate(records):
            keys = set(rec)
            if keys != want:
                extra, missing = sorted(keys - want), sorted(want - keys)
                what = f"has no column {missing[0]!r}" if missing else f"has an unknown column {extra[0]!r}"
                raise ValueError(f"table {name!r}: row {i} {what}")
            rows.append(tuple(rec[c] for c in cols))
        return cls(name=name, columns=cols, rows=tuple(rows), description=description)

    def column(self, name: str) -> tuple:
        """The values of column ``name``."""
        if name not in self.columns:
            raise KeyError(f"table {self.name!r} has no column {name!r}; columns: {', '.join(self.columns)}")
        i = self.columns.index(name)
        return tuple(r[i] for r in self.rows)

    def records(self) -> list[dict]:
        """One dict per row."""
        return [dict(zip(self.columns, r)) for r in self.rows]

    def to_dataframe(self):
        """A pandas DataFrame with the table's columns."""
        import pandas as pd

        return pd.DataFrame(list(self.rows), columns=list(self.columns))


@dataclass(frozen=True)
class Figure:
    """A figure of a study: the drawing function ``plotter`` of :mod:`tenscell.plotting` (by name), called with
    ``args`` and ``kwargs``, saved as ``name`` (``"mechanisms.png"``)."""

    name: str
    plotter: str
    args: tuple = ()
    kwargs: dict = field(default_factory=dict)

    def draw(self):
        """The matplotlib figure (drawn now)."""
        from .._results import plotter

        return plotter(self.plotter)(*self.args, **self.kwargs)


@dataclass(frozen=True)
class Check:
    """One goal as the run measured it.

    Attributes
    ----------
    label : str
        The goal in words (with its target).
    met : bool
    closest : str
        The model or structure that comes closest (or meets it).
    detail : str
        By how much, in words with numbers from the run.
    """

    label: str
    met: bool
    closest: str = ""
    detail: str = ""


@dataclass(frozen=True)
class TaskRecord:
    """What one task cost: its kind, weight, CPU seconds (in the process that ran it) and wall seconds."""

    key: str
    kind: str
    weight: float
    cpu_s: float
    wall_s: float


@dataclass(frozen=True, eq=False)
class StudyResult:
    """What a study's run gives: tables, figures, pages, checks, and the study's own result object.

    Attributes
    ----------
    study : str
    tables : tuple of Table
        Written as ``{name}.csv``.
    figures : tuple of Figure
        Written under their names.
    pages : tuple of (str, str)
        ``(file name, Markdown text)``.
    checks : tuple of Check
    data : object
        The study's own result (e.g. :class:`tenscell.studies.mechanisms.MechanismStudy`).
    summary : str
        What the command line prints when the study ends (a few lines).
    tasks : tuple of TaskRecord
        What each task cost.
    elapsed_s : float
        Wall seconds of the run.
    """

    study: str
    tables: tuple = ()
    figures: tuple = ()
    pages: tuple = ()
    checks: tuple = ()
    data: Any = None
    summary: str = ""
    tasks: tuple = ()
    elapsed_s: float = math.nan

    @property
    def cpu_s(self) -> float:
        """CPU seconds of every task."""
        return float(sum(t.cpu_s for t in self.tasks))

    def table(self, name: str) -> Table:
        for t in self.tables:
            if t.name == name:
                return t
        raise KeyError(f"study {self.study!r} has no table {name!r}; tables: {', '.join(t.name for t in self.tables)}")

    def files(self) -> tuple[str, ...]:
        """The names of every file the writer puts on disk."""
        return (*(f"{t.name}.csv" for t in self.tables), *(f.name for f in self.figures), *(p[0] for p in self.pages))


@runtime_checkable
class Study(Protocol):
    """What every study answers (module docstring). ``name`` is its command-line name; ``options`` the options it
    takes, by name, with their defaults (``{}``: none; ``"data"``: the data sets it fits, read from the files the
    command line names)."""

    name: str
    options: Mapping[str, Any]

    def plan(self, options: Mapping[str, Any]) -> Plan:
        """The checked options and the tasks (ValueError naming a bad option, before any work)."""
        ...

    def assemble(self, plan: Plan, results: Mapping[str, Any]) -> StudyResult:
        """The result from every task's result (by key)."""
        ...


def flag(option: str) -> str:
    """The command-line spelling of option ``option``: ``"from_fit"`` → ``"--from-fit"``."""
    return "--" + option.replace("_", "-")


def study_options(study: Study, options: Mapping[str, Any]) -> dict:
    """``study.options`` (the defaults) updated by ``options``; an option the study does not take is refused
    (ValueError naming it in flag syntax and the study's own options)."""
    own = dict(study.options)
    foreign = [k for k in options if k not in own]
    if foreign:
        takes = ", ".join(flag(k) for k in own) or "none"
        raise ValueError(f"{flag(foreign[0])}: study {study.name} takes no such option (its options: {takes})")
    own.update(options)
    return own


@dataclass(frozen=True)
class Machine:
    """What the machine gives a run now: ``cpus`` CPUs, ``others`` of them kept busy by other processes.

    A process gets its fair share of the CPUs among everything runnable: ``min(1, cpus / (others + n))`` for
    each of ``n`` processes of ours (:meth:`share`). :meth:`measure` reads it over a stretch of this process's own
    work (the calibration).
    """

    cpus: float = 1.0
    others: float = 0.0
    source: str = "assumed idle"

    def share(self, n: int = 1) -> float:
        """The share of one CPU each of ``n`` processes of ours can expect (0 to 1)."""
        return min(1.0, self.cpus / max(self.others + max(int(n), 1), 1e-9))

    @classmethod
    def measure(cls, use) -> Machine:
        """From a :class:`tenscell._parallel.CpuUse` of this process's work: the CPUs the others used meanwhile,
        and, when this process got less than a whole CPU, the demand that fair sharing implies (``cpus /
        share − 1``: the others were waiting too, beyond what the busy count shows). The load average is not
        used: it counts processes that wait for disk or sleep in short bursts, and lags by a minute (at a load
        average of 13 on 2 CPUs this process got 42 % of a CPU, not the 14 % it suggests)."""
        others = float(use.busy_elsewhere)
        got = use.cpu_s / use.wall_s if use.wall_s > 0 else 1.0
        if got < 0.9:
            others = max(others, use.cpus / max(got, 1e-3) - 1.0)
        return cls(cpus=float(use.cpus), others=others, source=use.source)

    def line(self) -> str:
        """``"at 45 % of a CPU per process (others keep 1.4 of 2 CPUs busy)"``."""
        return (f"at {self.share(1):.0%} of a CPU per process (others keep {self.others:.1f} of {self.cpus:g} "
                "CPUs busy)")


def calibrate(plan: Plan, extra: Sequence[Task] = ()) -> tuple[dict[str, float], Machine]:
    """Every kind's rate (CPU s per unit of weight) from ``plan.calibration`` and ``extra`` probes, and the
    machine as measured over them (:class:`Machine`). Each probe runs in this process once to load what it
    imports, then timed: once, or while its CPU time stays below :data:`PROBE_CPU_S`, up to :data:`PROBE_CALLS`
    times (the mean: a single short call on a shared machine can land on a stall).

    A probe that returns a callable has set up its work (a problem built, a model fitted: what the tasks it stands
    for do once, not per unit of weight): the callable is then what is timed, and the probe's weight is its work's.
    """
    from .._parallel import CpuWindow

    cpu: dict[str, float] = {}
    weight: dict[str, float] = {}
    window = CpuWindow()
    for probe in (*plan.calibration, *extra):
        work = probe.fn(*probe.args)
        if not callable(work):  # the probe is its own work (its first call loaded what it imports)
            work = functools.partial(probe.fn, *probe.args)
        calls, seconds = 0, 0.0
        while calls < PROBE_CALLS and (calls == 0 or seconds < PROBE_CPU_S):  # a short probe: its mean of a few
            seconds += _timed(work)[1]
            calls += 1
        cpu[probe.kind] = cpu.get(probe.kind, 0.0) + seconds / calls
        weight[probe.kind] = weight.get(probe.kind, 0.0) + probe.weight
    use = window.stop()
    return {k: max(cpu[k], 1e-6) / weight[k] for k in cpu}, Machine.measure(use)


def figure_probe() -> None:
    """One unit of :data:`FIGURE`: a small log-log figure of one curve, drawn and saved as PNG (in memory) through
    the plotting layer; a study's figure is a few units (its plan says how many)."""
    import numpy as np

    from .._results import plotter

    f = np.logspace(-2, 5, 71)
    plotter("png_bytes")(plotter("calibration_figure")(f, f ** 0.2))


def _timed(fn, *args):
    c0, t0 = time.process_time(), time.monotonic()
    out = fn(*args)
    return out, time.process_time() - c0, time.monotonic() - t0


def _waves(plan: Plan) -> list[list[Task]]:
    """The tasks in waves: each wave's tasks need only tasks of earlier waves."""
    level: dict[str, int] = {}
    waves: list[list[Task]] = []
    for t in plan.tasks:
        lv = 1 + max((level[k] for k in t.needs), default=-1)
        level[t.key] = lv
        while len(waves) <= lv:
            waves.append([])
        waves[lv].append(t)
    return waves


def _duration(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


class _Progress:
    """What :func:`execute` says as tasks finish: what was done, what runs next, and the time left at the rates
    and the share of a CPU measured so far."""

    def __init__(self, plan: Plan, rates: Mapping[str, float], notify):
        self.plan, self.known, self.notify = plan, dict(rates), notify
        self.done_w: dict[str, float] = {}
        self.done_cpu: dict[str, float] = {}
        self.cpu = self.wall = 0.0

    def rate(self, kind: str) -> float | None:
        if self.done_w.get(kind):
            return self.done_cpu[kind] / self.done_w[kind]
        return self.known.get(kind)

    def finished(self, task: Task, cpu: float, wall: float, results: Mapping[str, Any], running: Sequence[Task]):
        self.done_w[task.kind] = self.done_w.get(task.kind, 0.0) + task.weight
        self.done_cpu[task.kind] = self.done_cpu.get(task.kind, 0.0) + cpu
        self.cpu, self.wall = self.cpu + cpu, self.wall + wall
        if self.notify is None:
            return
        total = len(self.plan.tasks)
        line = f"{len(results)}/{total} tasks done: {task.key} ({cpu:.1f} s of CPU)"
        if len(results) < total:
            line += self._left(results, running)
        self.notify(line)

    def _left(self, results, running) -> str:
        left = [t for t in self.plan.tasks if t.key not in results]
        rates = [self.rate(t.kind) for t in left]
        nxt = next((t.key for t in running if t.key not in results), left[0].key)
        if any(r is None for r in rates):
            return f"; now: {nxt}"
        share = min(1.0, self.cpu / self.wall) if self.wall > 0 else 1.0
        cpu = float(sum(t.weight * r for t, r in zip(left, rates)))
        wall = cpu / max(share, 1e-3) / max(1, min(self.plan.jobs, len(left)))
        return f"; now: {nxt}; about {_duration(wall)} left ({cpu:.0f} s of CPU at {share:.0%} of a CPU)"


def execute(plan: Plan, *, jobs: int | None = None, rates: Mapping[str, float] | None = None,
            notify: Callable[[str], None] | None = None) -> tuple[dict[str, Any], tuple[TaskRecord, ...]]:
    """Run every task of ``plan`` (each after its needs), over ``jobs`` worker processes (default ``plan.jobs``).

    ``rates``: CPU seconds per unit of weight by kind, known before the run (a study's calibration); as tasks
    finish, each kind's rate becomes the measured one, and ``notify`` (if given) receives a line after each task:
    the tasks done, the one finished, what runs now, and the time the rest should take at the rates and the share
    of a CPU measured so far.

    Returns ``(results by key, what each task cost)``.
    """
    from .._parallel import Workers

    jobs = plan.jobs if jobs is None else jobs
    progress = _Progress(plan, rates or {}, notify)
    results: dict[str, Any] = {}
    records: list[TaskRecord] = []
    with Workers(max(1, int(jobs))) as workers:
        for wave in _waves(plan):
            args = [(t.fn, *t.args, *(results[k] for k in t.needs)) for t in wave]

            def finished(i, out, wave=wave):
                t = wave[i]
                value, cpu, wall = out
                results[t.key] = value
                records.append(TaskRecord(t.key, t.kind, float(t.weight), cpu, wall))
                progress.finished(t, cpu, wall, results, wave)

            workers.starmap(_timed, args, on_done=finished)
    order = {t.key: i for i, t in enumerate(plan.tasks)}
    return results, tuple(sorted(records, key=lambda r: order[r.key]))


def run_study(study: Study, options: Mapping[str, Any] | Plan, *, jobs: int | None = None,
              rates: Mapping[str, float] | None = None, notify: Callable[[str], None] | None = None) -> StudyResult:
    """Plan (unless a :class:`Plan` is given), execute (over ``jobs`` workers, default the plan's) and assemble a
    study: ``run(plan)`` of the protocol."""
    import dataclasses

    plan = options if isinstance(options, Plan) else study.plan(options)
    t0 = time.monotonic()
    results, records = execute(plan, jobs=jobs, rates=rates, notify=notify)
    out = study.assemble(plan, results)
    return dataclasses.replace(out, tasks=records, elapsed_s=time.monotonic() - t0)

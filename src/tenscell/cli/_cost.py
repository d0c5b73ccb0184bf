"""What a long command will cost: announced before it starts, refused beyond the machine.

One convention for every command that can run for minutes (standard library only, so that the parser's
own cost checks — ``--freq a:b:n``, ``--size`` — can use it at parse time):

* the time comes from a rate: measured at the start of the run (:func:`measure`: one draw, one cycle, one
  cell, timed here) or, for checks made while parsing, calibrated once and written down with its machine;
* the estimate is one line on stderr before the long work (:func:`announce`)::

      tenscell: estimated 2 min (measured 12 ms per draw × 10,000 draws / 2 workers)

* a run beyond :data:`BUDGET_S` of wall time, or needing more memory or disk than the machine has, is
  refused before anything is created (:func:`check`): exit 2, one line naming the flag and the limit.
"""
from __future__ import annotations

import os
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

__all__ = ["Cost", "BUDGET_S", "cpu_share", "measure", "check", "announce", "duration", "size",
           "total_memory", "estimate_plan"]


#: longest run a command starts (s): a day. Beyond it the command is refused with its estimate; split the
#: run (fewer draws, cells, amplitudes) or, where the command takes one, give a --scheduler with more workers
BUDGET_S = 24 * 3600.0


@dataclass(frozen=True)
class Cost:
    """The estimated cost of a run: ``count`` units of work at ``seconds_per_unit``, ``parallel`` at a time.

    Attributes
    ----------
    unit : str
        One unit of work, singular ("draw", "cycle", "cell").
    count : int
        Units the run does.
    seconds_per_unit : float
        Time of one unit on one core (s).
    parallel : int or None
        Units run at once (workers); None when unknown (an external scheduler): the estimate is then core time.
    memory_bytes, disk_bytes : float
        Memory the run holds at its peak, and what it writes (bytes); 0 when negligible.
    basis : str
        How ``seconds_per_unit`` was obtained ("measured" here, or "calibrated" with its machine).
    detail : str
        What else multiplies the units, for the line (e.g. "× 4 starts").
    count_max : int or None
        When the run decides its own length (adaptive cycles): the most units it may do; ``count`` is then
        the fewest, and the line states both.
    """

    unit: str
    count: int
    seconds_per_unit: float
    parallel: int | None = 1
    memory_bytes: float = 0.0
    disk_bytes: float = 0.0
    basis: str = "measured"
    detail: str = ""
    count_max: int | None = None

    @property
    def seconds(self) -> float:
        """Wall time (s); core time when ``parallel`` is None."""
        return self.count * self.seconds_per_unit / (self.parallel or 1)

    def line(self) -> str:
        """``estimated 2 min (measured 12 ms per draw × 10,000 draws / 2 workers)``."""
        upto = f" to {self.count_max:,}" if self.count_max else ""
        per = (f"{self.basis} {duration(self.seconds_per_unit)} per {self.unit} × {self.count:,}{upto} "
               f"{self.unit}{'' if self.count == 1 and not upto else 's'}{(' ' + self.detail) if self.detail else ''}")
        when = duration(self.seconds)
        if self.count_max:
            when += f" to {duration(self.seconds * self.count_max / self.count)}"
        if self.parallel is None:
            return f"estimated {when} of one core's time ({per}; shared by the cluster's workers)"
        workers = f" / {self.parallel} workers" if self.parallel > 1 else ""
        extra = "".join(f", {size(b)} of {what}" for b, what in ((self.memory_bytes, "memory"),
                                                                 (self.disk_bytes, "disk")) if b >= 1 << 20)
        return f"estimated {when}{extra} ({per}{workers})"


def measure(fn: Callable[[], object], *, min_time_s: float = 0.05, max_calls: int = 20) -> float:
    """Seconds per call of ``fn`` (its mean over calls until ``min_time_s`` has passed, at most ``max_calls``)."""
    calls, t0 = 0, time.perf_counter()
    while True:
        fn()
        calls += 1
        elapsed = time.perf_counter() - t0
        if elapsed >= min_time_s or calls >= max_calls:
            return elapsed / calls


def check(cost: Cost, flag: str, *, disk_at=None, budget_s: float = BUDGET_S,
          hint: str = "split it into smaller runs") -> Cost:
    """``cost`` if the machine can afford it; ValueError naming ``flag`` and the limit otherwise.

    Wall time is checked against ``budget_s`` (not with an unknown ``parallel``: a cluster's size is its
    own), memory against the machine's, disk against the free space where ``disk_at`` (a path) would be.
    """
    if cost.parallel is not None and cost.seconds > budget_s:
        raise ValueError(f"{flag}: {cost.line()}; more than the {duration(budget_s)} one run may take: {hint}")
    memory = total_memory()
    if memory and cost.memory_bytes > 0.8 * memory:
        raise ValueError(f"{flag}: {cost.line()}; needs about {size(cost.memory_bytes)} of memory, more than 80% of "
                         f"this machine's {size(memory)}")
    if disk_at is not None and cost.disk_bytes:
        free = _free_bytes(Path(disk_at))
        if free is not None and cost.disk_bytes > free:
            raise ValueError(f"{flag}: {cost.line()}; writes about {size(cost.disk_bytes)}, more than the "
                             f"{size(free)} free where {disk_at} would be")
    return cost


def announce(cost: Cost) -> None:
    """The estimate as a stage line on stderr (``tenscell: estimated ...``) before the long work."""
    from .._progress import stage

    stage(cost.line())


def estimate_plan(plan) -> tuple[dict, float]:
    """A study plan's estimate (:mod:`tenscell.studies.protocol`): its calibration run here (and one figure, when
    the plan has figures), the wall time at the share of a CPU the machine gives now, announced in one line; a
    plan beyond :data:`BUDGET_S` is refused naming the options that size it. Returns ``(rates, wall seconds)``
    (NaN when a kind of task has no calibration: the line says the estimate comes with the first tasks)."""
    import math

    from ..studies.protocol import FIGURE, Task, calibrate, figure_probe

    extra = (Task("one figure", FIGURE, figure_probe),) if plan.figures else ()
    rates, machine = calibrate(plan, extra)
    missing = sorted(k for k in plan.kinds() if k not in rates)
    if missing:
        from .._progress import stage

        stage(f"no estimate before the first task of kind {missing[0]!r} has run ({len(plan.tasks)} tasks)")
        return rates, math.nan
    wall = plan.estimate_wall(rates, machine)
    kinds = "; ".join(f"{_units(w)} × {duration(rates[k])} of CPU per {k}" for k, w in plan.kinds().items())
    figures = f"; {_units(plan.figures)} × {duration(rates[FIGURE])} per {FIGURE} unit" if plan.figures else ""
    workers = f", up to {plan.jobs} workers" if plan.jobs > 1 else ""
    line = (f"estimated {duration(wall)} ({len(plan.tasks)} task(s): {kinds}{figures}; measured here, "
            f"{machine.line()}{workers})")
    if wall > BUDGET_S:
        flags = ", ".join(plan.sized_by) or "the study's options"
        kinds = plan.kinds()
        heaviest = max(kinds, key=lambda k: kinds[k] * rates[k])
        raise ValueError(f"{plan.sized_by[0] if plan.sized_by else 'study ' + plan.study}: estimated {duration(wall)}"
                         f" ({len(plan.tasks)} task(s), the most of it {heaviest}), more than the "
                         f"{duration(BUDGET_S)} one run may take: give smaller {flags}")
    from .._progress import stage

    stage(line)
    return rates, wall


def _units(w: float) -> str:
    return f"{w:,.0f}" if w >= 10 or w == int(w) else f"{w:.2g}"


def duration(seconds: float) -> str:
    """``"12 ms"``, ``"3.4 s"``, ``"2 min"``, ``"5.1 h"``, ``"124 days"``."""
    for limit, scale, unit in ((1e-3, 1e6, "µs"), (1.0, 1e3, "ms"), (120.0, 1.0, "s"), (7200.0, 1 / 60, "min"),
                               (172800.0, 1 / 3600, "h")):
        if seconds < limit:
            return f"{seconds * scale:.2g} {unit}" if seconds * scale < 10 else f"{seconds * scale:.0f} {unit}"
    days = seconds / 86400
    return f"{days:.2g} days" if days < 10 else f"{days:,.0f} days"


def size(n: float) -> str:
    """A size in bytes as ``"37.3 GiB"``."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} TiB"  # pragma: no cover


def total_memory() -> float | None:
    """This machine's physical memory (bytes), None where unknown."""
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return None


def _free_bytes(path: Path) -> float | None:
    probe = path.absolute()
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    try:
        return float(shutil.disk_usage(probe).free)
    except OSError:
        return None


def cpu_share(workers: int) -> float:
    """The share of one CPU each of ``workers`` new processes can expect now: the CPUs over everything runnable
    (the load average plus them), at most 1. On a shared machine a short timed call is served at once while a
    long run waits its turn, so wall time is estimated from CPU time and this share."""
    try:
        load = os.getloadavg()[0]
    except (OSError, AttributeError):  # pragma: no cover - no load average on this platform
        return 1.0
    return min(1.0, (os.cpu_count() or 1) / max(load + workers, 1.0))

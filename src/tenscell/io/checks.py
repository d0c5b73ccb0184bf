"""What a reader refuses although every value is a finite positive number: data that cannot be what they claim.

Every reader (:func:`tenscell.io.read_data` and the readers behind it, :func:`~tenscell.io.data.read_csv`,
:func:`~tenscell.io.creep_data.read_creep_csv`, ``from_dataframe``) passes what it read through
:func:`check_measurement`; the constructors of :class:`~tenscell.io.data.RheologyData` and
:class:`~tenscell.io.creep_data.CreepData` do not (a computed data set may be anything positive). Each check
has a name; ``accept=`` (command line ``--accept NAME``) reads the data anyway, and the data's provenance
records that it did.

``one-frequency``
    Moduli at one frequency only, without a prestress that varies (an amplitude or time sweep): a frequency
    sweep it is not, and a model fitted to it is fitted to one point.
``outliers``
    A value inconsistent with the rest of its column by many decades. Between neighbouring points of a sweep a
    passive material's G' changes at most as f² and G'' as f (|d log G''/d log f| <= 1), its creep compliance
    at most as t; a point whose log10 departs from both neighbours' (from the one neighbour at an end of the
    sweep, and from the sweep's median) by more than that change plus :data:`OUTLIER_DECADES` decades is
    refused, naming its line. No measurement scatters by a factor of 1000 between neighbours; a wrong unit or
    a corrupted field does.
``decreasing``
    A creep compliance that decreases with time: the median of log10 J over the last third of the times below
    that over the first third. A passive material's J(t) does not decrease (a relaxation modulus or a force read
    as a compliance does).
``point-count``
    A TRIOS step or RheoCompass interval whose ``Number of points`` (``Interval and data points``) contradicts the
    rows it holds (a truncated or edited export); checked by those readers, for every step of the file, before the
    file is split into steps.
``truncated``
    A file whose last line, a data row, has no line break and whose last field is written with fewer significant
    digits than every other value of its column (``15`` below ``148.132``, ``157.858``...): a file cut in the middle
    of a number, which still reads as a number. (A row cut short of its fields is refused by every reader, whatever
    ``accept`` says: it is not data.)
``one-time``
    Creep compliance at one time only: a table of repeated readings, not a creep curve.
``repeated-times``
    A time held by several rows with different values of J (at least 3 rows and 5 % of the table): two runs in one
    table, or a time column that lost its digits. A time column rounded to its resolution (pairs of rows at one
    time in a dense table) passes.
``collapse``
    Along the times, the median of log10 J over bins of consecutive times (at most :data:`BINS` bins of equal counts,
    at least 5 points each) falls below what an earlier bin reached by more than :data:`COLLAPSE_DECADES` and more
    than 5 standard errors of the two medians: a creep compliance is non-decreasing, so a collapse (the end of a run
    whose 1 % falls 80-fold, another run appended) is refused, naming the lines. The ``outliers`` check is also made
    on these bins' medians (a run of damaged rows that fills a bin, which no single point's neighbours reveal).
"""
from __future__ import annotations

import os
import re
from typing import Iterable

import numpy as np

from .._errors import option
from .columns import DataError, read_text_file

__all__ = ["CHECKS", "ACCEPT_HINT", "OUTLIER_DECADES", "COLLAPSE_DECADES", "BINS", "accepted_checks", "check_measurement", "refuse",
           "significant_digits"]

#: the names of the checks (``accept=``, command line ``--accept``)
CHECKS = ("one-frequency", "outliers", "decreasing", "point-count", "truncated", "one-time", "repeated-times",
          "collapse")
#: how a refusal's message ends, before the option that reads the data anyway
ACCEPT_HINT = "; if the file is right, read it anyway with "
#: decades a value may depart from its neighbours beyond what a passive material allows between them
OUTLIER_DECADES = 3.0
#: decades a bin's median creep compliance may fall below an earlier bin's (a factor 2), beyond the noise
COLLAPSE_DECADES = 0.3
#: most bins of consecutive times the creep checks form (each of at least _BIN_POINTS points)
BINS = 200
_BIN_POINTS = 5
#: largest |d log10 G / d log10 f| of a passive material: G' (<= 2), G'' (<= 1); creep J (<= 1 in log t)
_SLOPE = {"storage": 2.0, "loss": 1.0, "compliance": 1.0}
#: along a prestress sweep no theorem bounds the slope; the tensegrity models give at most 1: 2 is generous
_PRESTRESS_SLOPE = 2.0


def accepted_checks(accept: str | Iterable[str] | None) -> tuple[str, ...]:
    """``accept`` as a tuple of check names, each one of :data:`CHECKS` (ValueError naming the option otherwise)."""
    if accept is None:
        return ()
    names = (accept,) if isinstance(accept, str) else tuple(accept)
    for name in names:
        if name not in CHECKS:
            raise DataError(f"{option('accept', name)}: not a check tenscell makes; the checks are "
                            f"{', '.join(CHECKS)}")
    return tuple(dict.fromkeys(names))


def refuse(source: str, check: str, problem: str, accept: tuple[str, ...]) -> str:
    """Raise the DataError of a failed check, unless the user accepted it: then return the problem (for the
    data's provenance)."""
    if check in accept:
        return f"{check}: {problem}"
    raise DataError(f"{source}: {problem}{ACCEPT_HINT}{option('accept', check)}")


def _where(data, i: int) -> str:
    return data.locations[i] if data.locations is not None else f"point {i}"


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def check_measurement(data, accept: tuple[str, ...] = (), columns: dict | None = None,
                      what: str | None = None) -> tuple[str, ...]:
    """Refuse ``data`` (RheologyData or CreepData, as read) when a check of the module docstring fails.

    ``columns`` maps a field (``"storage"``, ``"loss"``, ``"compliance"``) to the file's own header, for the
    message; ``accept`` holds the checks to skip; ``what`` names the part of the file read (``"step 1
    'Amplitude sweep'"``). Returns the problems found and accepted (for the provenance).
    """
    columns = columns or {}
    found = [_check_file_end(data, accept)]
    if data.kind == "creep":
        found += [_check_one_time(data, accept, what), _check_repeated_times(data, accept, what),
                  _check_decreasing(data, accept, what),
                  _check_outliers(data, "compliance", data.time_s, None, accept, columns, "t", "s")]
        found += _check_bins(data, accept, columns.get("compliance", "J"), what)
    else:
        found += [_check_one_frequency(data, accept, what)]
        found += [_check_outliers(data, field, data.frequency_hz, data.prestress, accept, columns, "f", "Hz")
                  for field in ("storage", "loss")]
    return tuple(f for f in found if f)


def _check_one_frequency(data, accept, what=None) -> str | None:
    freqs = np.unique(data.frequency_hz)
    if freqs.size > 1 or (data.prestress is not None and np.unique(data.prestress).size > 1):
        return None
    points = "1 point" if data.n == 1 else f"{data.n} points"
    return refuse(data.source, "one-frequency",
           f"{what + ' holds ' if what else ''}{points} at one frequency ({_fmt(freqs[0])} Hz) and no prestress that varies: an amplitude or time "
           "sweep, not a frequency sweep; tenscell fits G', G'' against frequency (or against prestress)", accept)


def _check_decreasing(data, accept, what=None) -> str | None:
    n = data.n
    if n < 3:
        return None
    k = max(1, n // 3)
    order = np.argsort(data.time_s, kind="stable")
    logJ = np.log10(data.compliance[order])
    first, last = float(np.median(logJ[:k])), float(np.median(logJ[-k:]))
    if last >= first:
        return None
    t = data.time_s[order]
    return refuse(data.source, "decreasing",
           f"{what + ': ' if what else ''}the creep compliance decreases with time (median {_fmt(10 ** first)} 1/Pa over t = {_fmt(t[0])}.."
           f"{_fmt(t[k - 1])} s, {_fmt(10 ** last)} 1/Pa over t = {_fmt(t[-k])}..{_fmt(t[-1])} s); a creep "
           "compliance does not decrease (is it a relaxation modulus, or a force?)", accept)


def _check_outliers(data, field, axis, prestress, accept, columns, symbol, unit) -> str | None:
    values = data.compliance if field == "compliance" else {"storage": data.G_storage, "loss": data.G_loss}[field]
    groups = [np.arange(data.n)] if prestress is None else [np.flatnonzero(prestress == p) for p in np.unique(prestress)]
    along = axis
    if prestress is not None and all(np.unique(axis[g]).size == 1 for g in groups):
        # one frequency per prestress (a prestress sweep): the neighbours are along the prestress
        groups, along, symbol, unit = [np.arange(data.n)], prestress, "P", "Pa"
    slope = _SLOPE[field] if along is axis else _PRESTRESS_SLOPE
    worst = None
    for g in groups:
        found = _outlier(np.log10(along[g]), np.log10(values[g]), slope)
        if found is not None and (worst is None or found[3] > worst[4]):
            worst = (g, *found)
    if worst is None:
        return None
    g, k, m, median, _ = worst
    i, j = int(g[k]), int(g[m])
    header = columns.get(field, {"storage": "G'", "loss": "G''", "compliance": "J"}[field])
    v_unit = "1/Pa" if field == "compliance" else "Pa"
    law = ({"storage": "G' changes at most as f²", "loss": "G'' changes at most as f",
            "compliance": "J changes at most as t"}[field] if along is axis else "G' changes at most as P²")
    return refuse(f"{data.source}, {_where(data, i)}", "outliers",
                  f"column {header!r}: {_fmt(values[i])} {v_unit} at {symbol} = {_fmt(along[i])} {unit} is "
                  f"{abs(np.log10(values[i] / values[j])):.3g} decades from its neighbour {_fmt(values[j])} {v_unit} "
                  f"at {symbol} = {_fmt(along[j])} {unit} ({_where(data, j)}) and "
                  f"{abs(np.log10(values[i]) - median):.3g} from the column's median {_fmt(10 ** median)} {v_unit}: "
                  f"more than a passive material allows ({law}) by over {OUTLIER_DECADES:g} decades; a wrong unit or "
                  "a damaged field?", accept)


def _outlier(x: np.ndarray, y: np.ndarray, slope: float):
    """The worst implausible point of one series (log10 axis ``x``, log10 values ``y``): (its index, its nearest
    neighbour's, the median of ``y``, the decades beyond the allowance), or None.

    A point is implausible when it departs from the median by more than ``slope`` × the series' span plus
    OUTLIER_DECADES (no passive material changes that much over the sweep), or from each of its neighbours by
    more than ``slope`` × the step plus OUTLIER_DECADES.
    """
    n = x.size
    if n < 2:
        return None
    order = np.lexsort((y, x))
    xs, ys = x[order], y[order]
    median = float(np.median(ys))
    span = float(xs[-1] - xs[0])
    worst = None
    for k in range(n):
        near = [m for m in (k - 1, k + 1) if 0 <= m < n]
        from_neighbours = min(abs(ys[k] - ys[m]) - slope * abs(xs[k] - xs[m]) for m in near)
        from_median = abs(ys[k] - median) - slope * span if n > 2 else -np.inf
        excess = max(from_neighbours, from_median) - OUTLIER_DECADES
        if excess > 0 and (worst is None or excess > worst[0]):
            m = min(near, key=lambda m: abs(xs[m] - xs[k]))
            worst = (excess, int(order[k]), int(order[m]))
    return None if worst is None else (worst[1], worst[2], median, worst[0])


# ---- the end of a file --------------------------------------------------------------------------------------
def significant_digits(text: str) -> int | None:
    """The significant digits a number is written with (``"148.132"``: 6, ``"15"``: 2, ``"1.50e-3"``: 3, a decimal
    comma alike), None when ``text`` is not a number."""
    mantissa = re.split(r"[eE]", text.strip().lstrip("+-"), maxsplit=1)[0]
    if not re.fullmatch(r"\d*[.,]?\d*", mantissa) or not any(c.isdigit() for c in mantissa):
        return None
    return max(1, len(re.sub(r"[.,]", "", mantissa).lstrip("0")))


def _line_numbers(data) -> list[int]:
    """The file lines the data's points were read from (sorted), for data read from a text file; else []."""
    source = str(data.source)
    if data.locations is None or source.lower().endswith((".xlsx", ".xlsm")) or not os.path.isfile(source):
        return []
    return sorted({int(w.split()[1]) for w in data.locations if re.fullmatch(r"line \d+", w)})


def _check_file_end(data, accept) -> str | None:
    """A file whose last line, a data row, ends without a line break: refused when it is shorter than the rows
    above it (cut mid-line; whatever ``accept`` says) or when its last number has fewer significant digits than that
    column's other values (``truncated``)."""
    rows = _line_numbers(data)
    if len(rows) < 4:
        return None
    text = read_text_file(data.source)
    lines = text.splitlines()
    if not text or text.endswith(("\n", "\r")) or rows[-1] != len(lines):
        return None
    above = [lines[k - 1] for k in rows[-51:-1]]
    sep = next((d for d in ("\t", ";", ",") if all(r.count(d) == above[-1].count(d) > 0 for r in above)), None)
    if sep is None:
        return None
    fields, width = lines[-1].split(sep), above[-1].count(sep) + 1
    where = f"{data.source}, line {len(lines)}"
    column = _header_of(lines, rows[0], width, len(fields) - 1, sep)
    if len(fields) < width or (not fields[-1].strip() and all(r.split(sep)[-1].strip() for r in above)):
        raise DataError(f"{where}: the file ends in the middle of this row (no line break, its last field "
                        f"{'empty' if len(fields) == width else f'{len(fields)} of {width}'}"
                        f"{', cut in column ' + repr(column) if column else ''}): a truncated file")
    cut = significant_digits(fields[-1])
    others = [d for d in (significant_digits(r.split(sep)[-1]) for r in above) if d is not None]
    if cut is None or len(others) < 3 or cut >= min(others):
        return None
    return refuse(where, "truncated", f"{'column ' + repr(column) + ': ' if column else ''}the file ends without a "
                  f"line break after {fields[-1].strip()!r}, written with {cut} significant digit(s) where every "
                  f"other value of its column has at least {min(others)}: a file cut in the middle of a number?",
                  accept)


def _header_of(lines: list[str], first: int, width: int, j: int, sep: str) -> str | None:
    """The name of field ``j`` in the header above the first data row (line ``first``): the nearest line above it
    with as many fields whose field ``j`` is not a number; None if there is none."""
    for k in range(first - 2, max(-1, first - 12), -1):
        f = lines[k].split(sep)
        if len(f) >= width and j < len(f) and f[j].strip() and significant_digits(f[j]) is None:
            return f[j].strip()
    return None


# ---- creep: times and the shape of J(t) ------------------------------------------------------------------------
def _groups(data) -> list[np.ndarray]:
    """The points of each prestress (one group without a prestress column), in time order."""
    order = np.argsort(data.time_s, kind="stable")
    if data.prestress is None:
        return [order]
    return [order[data.prestress[order] == p] for p in np.unique(data.prestress)]


def _span(data, idx: np.ndarray) -> str:
    """Where the points ``idx`` (in time order) are: ``line 12``, ``lines 12 to 40`` (``points`` without lines)."""
    first, last = _where(data, int(idx[0])), _where(data, int(idx[-1]))
    if first == last:
        return first
    word, _, a = first.partition(" ")
    return f"{word}s {a} to {last.partition(' ')[2]}"


def _check_one_time(data, accept, what=None) -> str | None:
    times = np.unique(data.time_s)
    if times.size > 1:
        return None
    points = "1 point" if data.n == 1 else f"{data.n} points"
    return refuse(data.source, "one-time", f"{what + ' holds ' if what else ''}{points} at one time "
                  f"(t = {_fmt(times[0])} s): repeated readings, not a creep curve; tenscell fits J against time",
                  accept)


def _check_repeated_times(data, accept, what=None) -> str | None:
    for g in _groups(data):
        t, counts = np.unique(data.time_s[g], return_counts=True)
        k = int(np.argmax(counts))
        if t.size < 2 or counts[k] < 3 or counts[k] < 0.05 * g.size:
            continue
        at = g[data.time_s[g] == t[k]]
        J = data.compliance[at]
        return refuse(f"{data.source}, {_span(data, at)}", "repeated-times",
                      f"{what + ': ' if what else ''}{counts[k]} of {g.size} rows are at t = {_fmt(t[k])} s (J "
                      f"{_fmt(J.min())}..{_fmt(J.max())} 1/Pa): two runs in one table, or a time column that lost "
                      "its digits?", accept)
    return None


def _bins(data, g: np.ndarray):
    """Bins of consecutive times of one group: (the points of each bin, median log10 t, median log10 J, the
    standard error of that median), or None when the group has too few points for 3 bins."""
    m = min(BINS, g.size // _BIN_POINTS)
    if m < 3:
        return None
    edges = np.linspace(0, g.size, m + 1).round().astype(int)
    parts = [g[a:b] for a, b in zip(edges[:-1], edges[1:])]
    y = [np.log10(data.compliance[p]) for p in parts]
    med = np.array([np.median(v) for v in y])
    se = np.array([1.4826 * np.median(np.abs(v - c)) / np.sqrt(v.size) for v, c in zip(y, med)])
    logt = np.array([np.median(np.log10(data.time_s[p])) for p in parts])
    return parts, logt, med, se


def _check_bins(data, accept, header: str, what=None) -> list[str | None]:
    """``collapse`` and ``outliers`` on the medians of bins of consecutive times (module docstring)."""
    found: list[str | None] = []
    for g in _groups(data):
        binned = _bins(data, g)
        if binned is None:
            continue
        parts, logt, med, se = binned
        hit = _run_outlier(logt, med, _SLOPE["compliance"])  # first: a run of damaged rows also looks like a collapse
        if hit is not None:
            b, local = hit
            found.append(refuse(f"{data.source}, {_span(data, parts[b])}", "outliers",
                                f"column {header!r}: the median {_fmt(10 ** med[b])} 1/Pa of these rows is "
                                f"{abs(med[b] - local):.3g} decades from the median {_fmt(10 ** local)} 1/Pa of the "
                                f"rows around them: more than a passive material allows (J changes at most as t) by "
                                f"over {OUTLIER_DECADES:g} decades; a run of damaged rows?", accept))
        found.append(_collapse(data, parts, med, se, accept, header, what))
    return found


def _run_outlier(x: np.ndarray, y: np.ndarray, slope: float, reach: int = 3):
    """The bin whose median ``y`` departs most from the median of the bins within ``reach`` of it (itself included,
    so that a run of up to ``reach`` damaged bins cannot hide behind its own neighbours) by more than ``slope`` × the
    window's span of ``x`` plus OUTLIER_DECADES: (its index, that local median), or None."""
    worst, found = 0.0, None
    for b in range(y.size):
        w = slice(max(0, b - reach), b + reach + 1)
        local = float(np.median(y[w]))
        excess = abs(y[b] - local) - slope * float(np.ptp(x[w])) - OUTLIER_DECADES
        if excess > worst:
            worst, found = excess, (b, local)
    return found


def _collapse(data, parts, med, se, accept, header: str, what=None) -> str | None:
    top = np.maximum.accumulate(med)
    at_top = np.array([int(np.argmax(med[:b + 1])) for b in range(med.size)])
    allowed = np.maximum(COLLAPSE_DECADES, 5.0 * np.hypot(se, se[at_top]))
    excess = (top - med) - allowed
    b = int(np.argmax(excess))
    if excess[b] <= 0:
        return None
    a = at_top[b]
    ta, tb = data.time_s[parts[a]], data.time_s[parts[b]]
    return refuse(f"{data.source}, {_span(data, parts[b])}", "collapse",
                  f"{what + ': ' if what else ''}column {header!r}: the creep compliance falls "
                  f"{10 ** (top[b] - med[b]):.3g}-fold, from a median {_fmt(10 ** med[a])} 1/Pa over t = "
                  f"{_fmt(ta.min())}..{_fmt(ta.max())} s ({_span(data, parts[a])}) to {_fmt(10 ** med[b])} 1/Pa over "
                  f"t = {_fmt(tb.min())}..{_fmt(tb.max())} s, beyond the data's scatter; a creep compliance does not "
                  "decrease (the end of a run collapsed, another run appended?)", accept)

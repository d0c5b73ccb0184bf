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
    A TRIOS step whose ``Number of points`` contradicts the rows it holds (a truncated or edited export);
    checked by the TRIOS reader.
"""
from __future__ import annotations

from typing import Iterable

import numpy as np

from .._errors import option
from .columns import DataError

__all__ = ["CHECKS", "OUTLIER_DECADES", "accepted_checks", "check_measurement", "refuse"]

#: the names of the checks (``accept=``, command line ``--accept``)
CHECKS = ("one-frequency", "outliers", "decreasing", "point-count")
#: decades a value may depart from its neighbours beyond what a passive material allows between them
OUTLIER_DECADES = 3.0
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
    raise DataError(f"{source}: {problem}; if the file is right, read it anyway with {option('accept', check)}")


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
    if getattr(data, "kind", None) == "creep":
        found = [_check_decreasing(data, accept, what),
                 _check_outliers(data, "compliance", data.time_s, None, accept, columns, "t", "s")]
    else:
        found = [_check_one_frequency(data, accept, what)]
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

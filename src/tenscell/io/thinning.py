"""Dense data made small enough to fit: binning in log frequency (moduli) or log time (creep), with a stated rule.

A fit's cost grows with the number of data points, but a dense sweep (10^4 to
10^6 points from a modern rheometer, a creep curve sampled every 0.1 s) carries
no more information about a model with a dozen parameters than a few hundred
well-placed points. The rule (:func:`bin_log_frequency`, :func:`bin_log_time`):

1. Points are grouped by prestress: each distinct prestress is a group when
   there are at most ``max_points // 4`` of them; otherwise prestress is cut
   into equal bins in log10 P as well.
2. Within each group, log10 f (log10 t for creep) is cut into equal-width
   bins, as many as keep the total at most ``max_points`` (empty bins are
   dropped).
3. A bin becomes one point: frequency (time) and prestress are the geometric
   means of its points; log10 G' and log10 G'' (log10 J) are the means of its
   points' values weighted by their squared fit weights ``w`` (``G ln10 / sd``
   with standard deviations, else 1 per measured point).
4. Its weight in the fit: with standard deviations, ``sqrt(sum w^2)``, stored as
   the SD of the weighted mean (``weighting`` does not matter then). Without
   them, ``weighting="counts"`` (moduli) keeps the bin's count of measured
   points (``counts``; the fit weighs such a point √count,
   :attr:`~tenscell.io.data.RheologyData.weights_storage`), and
   ``weighting="bins"`` (creep) gives every bin the weight of one point.

With ``"counts"`` (or SDs), the fit's least-squares objective on the binned
data equals the objective on the raw data minus the within-bin scatter (a
constant), wherever the model varies little across a bin: binning keeps what
the data say about the model and drops only the noise already averaged out.
A frequency sweep is sampled evenly in log f, so its bins hold similar counts
and the two rules agree. A creep table is sampled evenly in *time* (a rheometer
logs every 0.1 s): the raw objective would weigh each decade of time ten times
the decade before (the last decade of a 0.2–720 s curve holds 90 % of its
points), which is the sampling's doing, not the data's; ``"bins"`` gives each
interval of log t the same say, as a curve sampled evenly in log t would.
Binned data without SDs still state none: the fit's noise criterion and its
standard errors do not mistake a bin's count for a measured noise.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

__all__ = ["bin_log_frequency", "bin_log_time", "bin_datasets", "binning_notes", "binning_rule", "DEFAULT_MAX_POINTS"]

#: points a fit uses at most by default (see :func:`bin_log_frequency`)
DEFAULT_MAX_POINTS = 100


_NOTE = "binned from "


def binning_notes(data) -> tuple[str, ...]:
    """The comment lines :func:`bin_log_frequency` or :func:`bin_log_time` added to ``data`` (rule and counts)."""
    return tuple(c for c in data.comments if c.startswith(_NOTE))


def binning_rule(data) -> str | None:
    """What binning did to ``data`` and how the fit weighs its points, in one sentence for a report; None if unbinned.

    E.g. ``"binned from 7,199 to 93 points in equal log10-t bins per prestress (at most 100; tenscell.io.thinning;
    1 to 83 points a bin): t and J are weighted log means within a bin, and each bin weighs as one point in the
    fit (no SDs stated): every interval of log t has the same say, whatever the sampling rate"``.
    """
    notes = binning_notes(data)
    return notes[-1] if notes else None


def _bin_index(values: np.ndarray, nbins: int) -> np.ndarray:
    """Equal-width bins of log10(values); index 0..nbins-1."""
    lv = np.log10(values)
    lo, hi = float(lv.min()), float(lv.max())
    if nbins <= 1 or hi <= lo:
        return np.zeros(values.size, dtype=np.int64)
    idx = np.floor((lv - lo) / (hi - lo) * nbins).astype(np.int64)
    return np.minimum(idx, nbins - 1)


def _check_max_points(max_points) -> None:
    if isinstance(max_points, bool) or not isinstance(max_points, (int, np.integer)) or max_points < 1:
        raise ValueError(f"max_points must be an integer >= 1, got {max_points!r}")


def _bins(axis: np.ndarray, prestress: np.ndarray | None, max_points: int) -> np.ndarray:
    """Each point's bin (0..nb-1) by rules 1 and 2 of the module docstring."""
    n = axis.size
    if prestress is None:
        group = np.zeros(n, dtype=np.int64)
    else:
        levels, group = np.unique(prestress, return_inverse=True)
        if levels.size > max_points // 4:
            group = _bin_index(prestress, max(1, int(math.isqrt(max_points))))
    groups = np.unique(group)
    per_group = max(1, max_points // groups.size)
    abin = np.empty(n, dtype=np.int64)
    for g in groups:  # axis bins over each group's own range
        sel = group == g
        abin[sel] = _bin_index(axis[sel], per_group)
    _, inverse = np.unique(group * per_group + abin, return_inverse=True)
    inverse = inverse.ravel()
    if inverse.max() + 1 > max_points:  # many prestress bins, each with a point: merge the axis
        _, inverse = np.unique(group, return_inverse=True)
        inverse = inverse.ravel()
    return inverse


def _log_mean(inverse: np.ndarray, nb: int, x: np.ndarray, w: np.ndarray | None = None) -> np.ndarray:
    """Weighted mean in log10 per bin, exact where a bin's values are all equal (a prestress level, one point)."""
    w = np.ones(x.size) if w is None else w
    out = 10.0 ** (np.bincount(inverse, weights=w * np.log10(x), minlength=nb)
                   / np.bincount(inverse, weights=w, minlength=nb))
    lo, hi = np.full(nb, np.inf), np.full(nb, -np.inf)
    np.minimum.at(lo, inverse, x)
    np.maximum.at(hi, inverse, x)
    return np.where(lo == hi, lo, out)


def _counts(data) -> np.ndarray:
    return np.ones(data.n) if data.counts is None else np.asarray(data.counts, dtype=float)


_WEIGHTINGS = ("counts", "bins")


def _rule(data, n_out: int, max_points: int, axis: str, counts: np.ndarray, weighting: str) -> str:
    values = "t and J" if axis == "t" else "f, G' and G''"
    lo, hi = int(round(counts.min())), int(round(counts.max()))
    held = f"{lo} to {hi} points" if lo != hi else f"{lo} points"
    head = (f"{_NOTE}{data.n:,} to {n_out:,} points in equal log10-{axis} bins per prestress (at most {max_points}; "
            f"tenscell.io.thinning; {held} a bin): {values} are weighted log means within a bin")
    if data.has_sd:
        return (f"{head}, and each bin weighs sqrt(sum w²) of its points' weights w = value·ln10/sd (its SD is that of "
                f"the mean), so the objective is that of all {data.n:,} points up to their scatter within bins")
    if weighting == "counts":
        return (f"{head}, and each bin weighs √(its points) in the fit (no SDs stated), so the objective is that of "
                f"all {data.n:,} points up to their scatter within bins")
    return (f"{head}, and each bin weighs as one point in the fit (no SDs stated): every interval of log {axis} has "
            f"the same say, whatever the sampling rate")


def _check_weighting(weighting) -> None:
    if weighting not in _WEIGHTINGS:
        raise ValueError(f"weighting must be one of {', '.join(_WEIGHTINGS)}, got {weighting!r}")


def bin_log_frequency(data, max_points: int = DEFAULT_MAX_POINTS, weighting: str = "counts"):
    """``data`` (RheologyData) with at most ``max_points`` points, by the rule in the module docstring.

    Parameters
    ----------
    data : RheologyData
    max_points : int
        Largest number of points returned (>= 1). Data with at most this many
        points is returned unchanged.
    weighting : {"counts", "bins"}
        Without SDs, a bin weighs √(its points) (the raw objective) or as one point.

    Returns
    -------
    RheologyData
        The binned data (with SDs of the bin means when the data state SDs, else with ``counts`` under
        ``"counts"``), its comments and provenance extended by one line stating the rule, the point counts and
        the weights (:func:`binning_rule`).
    """
    return _bin(data, "frequency_hz", (("G_storage", "G_storage_sd", data.weights_storage ** 2),
                                       ("G_loss", "G_loss_sd", data.weights_loss ** 2)), max_points, weighting, "f")


def bin_log_time(data, max_points: int = DEFAULT_MAX_POINTS, weighting: str = "bins"):
    """``data`` (CreepData) with at most ``max_points`` points, binned in log10 t by the rule in the module docstring.

    ``weighting`` (without SDs): ``"bins"`` (default: each bin weighs as one point, every interval of log t
    alike) or ``"counts"`` (√(its points): the objective of all the raw points). Returns ``data`` itself when it
    has no more points than that; else the binned CreepData (SDs of the bin means when the data state SDs), its
    comments and provenance extended by the rule (:func:`binning_rule`).
    """
    return _bin(data, "time_s", (("compliance", "compliance_sd", data.weights ** 2),), max_points, weighting, "t")


def _bin(data, axis: str, series, max_points: int, weighting: str, symbol: str):
    """``data`` binned along its field ``axis`` by the module's rule; ``series``: (value field, its SD field,
    the values' squared fit weights) of each quantity averaged in a bin."""
    _check_max_points(max_points)
    _check_weighting(weighting)
    if data.n <= max_points:
        return data
    inverse = _bins(getattr(data, axis), data.prestress, max_points)
    nb = int(inverse.max()) + 1
    counts = np.bincount(inverse, weights=_counts(data), minlength=nb)
    fields: dict[str, np.ndarray | None] = {axis: _log_mean(inverse, nb, getattr(data, axis))}
    for value, sd, w2 in series:
        fields[value] = mean = _log_mean(inverse, nb, getattr(data, value), w2)
        fields[sd] = mean * math.log(10.0) / np.sqrt(np.bincount(inverse, weights=w2, minlength=nb)) \
            if data.has_sd else None
    rule = _rule(data, nb, max_points, symbol, counts, weighting)
    return replace(data, **fields, prestress=None if data.prestress is None else _log_mean(inverse, nb, data.prestress),
                   comments=tuple(data.comments) + (rule,), provenance=replace(data.provenance, points=nb).noted(rule),
                   counts=counts if weighting == "counts" or data.has_sd else None, locations=None)


def bin_datasets(datasets, max_points: int = DEFAULT_MAX_POINTS) -> tuple:
    """Each data set with more than ``max_points`` points binned: moduli in log frequency
    (:func:`bin_log_frequency`), creep compliance in log time (:func:`bin_log_time`).

    Smaller data sets are returned as they are, the same objects.
    """
    return tuple(d.binned(max_points) if hasattr(d, "binned") else d for d in datasets)

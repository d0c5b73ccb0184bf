"""Dense data made small enough to fit: log-frequency binning with a stated rule.

A fit's cost grows with the number of data points, but a dense sweep (10^4 to
10^6 points from a modern rheometer) carries no more information about a
model with a dozen parameters than a few hundred well-placed points. The rule
(:func:`bin_log_frequency`):

1. Points are grouped by prestress: each distinct prestress is a group when
   there are at most ``max_points // 4`` of them; otherwise prestress is cut
   into equal bins in log10 P as well.
2. Within each group, log10 f is cut into equal-width bins, as many as keep
   the total at most ``max_points`` (empty bins are dropped).
3. A bin becomes one point: frequency and prestress are the geometric means
   of its points; log10 G' and log10 G'' are the means of its points' values
   weighted by their squared fit weights ``w = G ln10 / sd`` (1 without SDs),
   and the bin's weight is ``sqrt(sum w^2)`` (stored as the equivalent SD).

With that weight, the fit's least-squares objective on the binned data equals
the objective on the raw data minus the within-bin scatter (a constant),
wherever the model varies little across a bin: binning keeps what the data
say about the model and drops only the noise already averaged out.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["bin_log_frequency", "bin_datasets", "binning_notes", "DEFAULT_MAX_POINTS"]

#: points a fit uses at most by default (see :func:`bin_log_frequency`)
DEFAULT_MAX_POINTS = 100


_NOTE = "binned from "


def binning_notes(data) -> tuple[str, ...]:
    """The comment lines :func:`bin_log_frequency` added to ``data`` (the rule and the counts)."""
    return tuple(c for c in data.comments if c.startswith(_NOTE))


def _bin_index(values: np.ndarray, nbins: int) -> np.ndarray:
    """Equal-width bins of log10(values); index 0..nbins-1."""
    lv = np.log10(values)
    lo, hi = float(lv.min()), float(lv.max())
    if nbins <= 1 or hi <= lo:
        return np.zeros(values.size, dtype=np.int64)
    idx = np.floor((lv - lo) / (hi - lo) * nbins).astype(np.int64)
    return np.minimum(idx, nbins - 1)


def bin_log_frequency(data, max_points: int = DEFAULT_MAX_POINTS):
    """``data`` with at most ``max_points`` points, by the rule in the module docstring.

    Parameters
    ----------
    data : RheologyData
    max_points : int
        Largest number of points returned (>= 1). Data with at most this many
        points is returned unchanged.

    Returns
    -------
    RheologyData
        The binned data (with SDs that carry each bin's weight), its comments
        extended by one line stating the rule and the point counts.
    """
    if isinstance(max_points, bool) or not isinstance(max_points, (int, np.integer)) or max_points < 1:
        raise ValueError(f"max_points must be an integer >= 1, got {max_points!r}")
    n = data.n
    if n <= max_points:
        return data
    f = data.frequency_hz
    ws, wl = data.weights_storage, data.weights_loss
    if data.prestress is None:
        group = np.zeros(n, dtype=np.int64)
    else:
        levels, group = np.unique(data.prestress, return_inverse=True)
        if levels.size > max_points // 4:
            group = _bin_index(data.prestress, max(1, int(math.isqrt(max_points))))
    groups = np.unique(group)
    per_group = max(1, max_points // groups.size)
    fbin = np.empty(n, dtype=np.int64)
    for g in groups:  # frequency bins over each group's own range
        sel = group == g
        fbin[sel] = _bin_index(f[sel], per_group)
    key = group * per_group + fbin
    _, inverse = np.unique(key, return_inverse=True)
    inverse = inverse.ravel()
    if inverse.max() + 1 > max_points:  # many prestress bins, each with a point: merge frequencies
        _, inverse = np.unique(group, return_inverse=True)
        inverse = inverse.ravel()

    nb = int(inverse.max()) + 1

    def log_mean(x, w=None):
        """Weighted mean in log10, exact where a bin's values are all equal (a prestress level, one point)."""
        w = np.ones(n) if w is None else w
        out = 10.0 ** (np.bincount(inverse, weights=w * np.log10(x), minlength=nb)
                       / np.bincount(inverse, weights=w, minlength=nb))
        lo, hi = np.full(nb, np.inf), np.full(nb, -np.inf)
        np.minimum.at(lo, inverse, x)
        np.maximum.at(hi, inverse, x)
        return np.where(lo == hi, lo, out)

    s2, l2 = ws**2, wl**2
    freq = log_mean(f)
    Gs = log_mean(data.G_storage, s2)
    Gl = log_mean(data.G_loss, l2)
    w_s = np.sqrt(np.bincount(inverse, weights=s2, minlength=nb))
    w_l = np.sqrt(np.bincount(inverse, weights=l2, minlength=nb))
    prestress = None if data.prestress is None else log_mean(data.prestress)
    rule = (f"{_NOTE}{n} to {freq.size} points by tenscell.io.thinning.bin_log_frequency "
            f"(max_points={max_points}): equal log10-f bins per prestress, weighted log means, weight sqrt(sum w^2)")
    return type(data)(  # a RheologyData (not imported: io.data imports this module for RheologyData.binned)
        frequency_hz=freq, G_storage=Gs, G_loss=Gl, prestress=prestress,
        G_storage_sd=Gs * math.log(10.0) / w_s, G_loss_sd=Gl * math.log(10.0) / w_l,
        source=data.source, comments=tuple(data.comments) + (rule,),
    )


def bin_datasets(datasets, max_points: int = DEFAULT_MAX_POINTS) -> tuple:
    """Each moduli data set with more than ``max_points`` points binned (:func:`bin_log_frequency`).

    Creep data (which have no frequency axis to bin) and smaller data sets
    are returned as they are, the same objects.
    """
    return tuple(d.binned(max_points) if hasattr(d, "binned") else d for d in datasets)

"""What a curve G'(f), G''(f) says about a power law: the local exponent, its flat stretches, the loss tangent.

Pure functions of sampled moduli (no structure, no model), shared by the power-law study
(:mod:`tenscell.studies.powerlaw`), its report and its tests.

* the **local exponent** α(f) = d ln G'/d ln f (:func:`tenscell.response.log_slope`);
* a **flat stretch**: a run of consecutive frequencies over which α stays within ±``tolerance`` of the middle of
  its range there (:func:`flat_stretch`), the longest one, optionally with α inside a band (0.1–0.3) and the loss
  tangent within a relative ``tan_tolerance`` of tan(ᾱπ/2), ᾱ the mean exponent over the stretch (the loss
  tangent of a pure power law G* ∝ (iω)^α);
* the prestress trend: dα/d ln P at each frequency, by least squares over the prestresses (:func:`prestress_trend`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..response import log_slope

__all__ = ["Stretch", "flat_stretch", "local_exponent", "prestress_trend", "ALPHA_BAND", "TOLERANCE",
           "TAN_TOLERANCE", "NO_STRETCH"]

#: the exponents the issue asks for (cells: 0.1–0.3)
ALPHA_BAND = (0.1, 0.3)
#: how far the local exponent may stray from its stretch's middle (±, dimensionless)
TOLERANCE = 0.05
#: how far the loss tangent may stray from tan(ᾱπ/2), relative
TAN_TOLERANCE = 0.2


@dataclass(frozen=True)
class Stretch:
    """A run of frequencies over which the local exponent stays flat.

    Attributes
    ----------
    decades : float
        log10(f_high/f_low) (0 when there is none).
    f_low, f_high : float
        Its ends (Hz; NaN when there is none).
    alpha : float
        The mean local exponent over it (NaN when there is none).
    tan_ratio : float
        The largest |tan δ / tan(ᾱπ/2) − 1| over it (NaN when there is none).
    """

    decades: float
    f_low: float
    f_high: float
    alpha: float
    tan_ratio: float


NO_STRETCH = Stretch(0.0, math.nan, math.nan, math.nan, math.nan)


def local_exponent(f_hz, G_storage) -> np.ndarray:
    """α(f) = d ln G'/d ln f along the last axis (dimensionless)."""
    return log_slope(f_hz, G_storage)


def _tan_error(alpha_mean: float, tan_delta: np.ndarray) -> float:
    ref = math.tan(alpha_mean * math.pi / 2)
    return float(np.max(np.abs(tan_delta / ref - 1.0))) if ref > 0 else math.inf


def flat_stretch(f_hz, alpha, tan_delta=None, *, tolerance: float = TOLERANCE,
                 band: tuple[float, float] | None = None, tan_tolerance: float | None = None) -> Stretch:
    """The longest run of consecutive samples over which α stays within ±``tolerance`` of its middle.

    Parameters
    ----------
    f_hz : array_like, shape (n,)
        Increasing frequencies (Hz).
    alpha : array_like, shape (n,)
        Local exponent at each (dimensionless).
    tan_delta : array_like, shape (n,), optional
        Loss tangent G''/G' at each; needed for ``tan_tolerance`` and for :attr:`Stretch.tan_ratio`.
    tolerance : float
        Half-width allowed for α over the run.
    band : (low, high), optional
        Also require every α of the run inside [low, high].
    tan_tolerance : float, optional
        Also require |tan δ / tan(ᾱπ/2) − 1| ≤ this at every sample of the run (ᾱ its mean α).

    Returns
    -------
    Stretch
        :data:`NO_STRETCH` when no run of two samples qualifies.
    """
    f = np.asarray(f_hz, dtype=float)
    a = np.asarray(alpha, dtype=float)
    t = None if tan_delta is None else np.asarray(tan_delta, dtype=float)
    ok = np.isfinite(a)
    if band is not None:
        ok &= (a >= band[0]) & (a <= band[1])
    best = NO_STRETCH
    n = a.size
    logf = np.log10(f)
    total = np.concatenate([[0.0], np.cumsum(np.where(ok, a, 0.0))])
    for i in range(n - 1):
        if not ok[i] or logf[-1] - logf[i] <= best.decades:
            continue
        hi = lo = a[i]
        for j in range(i + 1, n):
            if not ok[j]:
                break
            hi, lo = max(hi, a[j]), min(lo, a[j])
            if hi - lo > 2 * tolerance:
                break
            dec = float(logf[j] - logf[i])
            if dec <= best.decades:
                continue
            mean = float(total[j + 1] - total[i]) / (j + 1 - i)
            err = math.nan if t is None else _tan_error(mean, t[i:j + 1])
            if tan_tolerance is not None and not err <= tan_tolerance:
                continue
            best = Stretch(dec, float(f[i]), float(f[j]), mean, err)
    return best


def prestress_trend(prestress, alpha) -> np.ndarray:
    """dα/d ln P at each frequency: the least-squares slope of α against ln P (dimensionless).

    Parameters
    ----------
    prestress : array_like, shape (nP,)
        Prestresses (N), at least two.
    alpha : array_like, shape (nP, nf)
        Local exponent at each prestress and frequency.
    """
    x = np.log(np.asarray(prestress, dtype=float))
    a = np.asarray(alpha, dtype=float)
    if x.size < 2:
        raise ValueError("the prestress trend needs at least two prestresses")
    xc = x - x.mean()
    return (xc @ (a - a.mean(axis=0))) / (xc @ xc)

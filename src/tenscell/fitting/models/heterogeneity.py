"""Few-parameter heterogeneity: tendon properties drawn from named distributions, assigned reproducibly.

A distribution here turns fixed probabilities ``u ∈ (0, 1)`` into values of a
tendon property (EA, c, a time constant, an exponent) through its quantile
function, with one or two parameters:

* :class:`LogNormal` ``(median, decades)``: ``ln x = ln median + decades·ln10·Φ⁻¹(u)``
  (``decades`` is the standard deviation of ``log10 x``);
* :class:`LogUniform` ``(centre, decades)``: ``ln x = ln centre + decades·ln10·(u − ½)``
  (``log10 x`` uniform over a width of ``decades``);
* :class:`PowerLaw` ``(scale, exponent)``: the trap-model (Pareto) distribution
  of time constants, ``P(x > y) = (scale/y)^exponent`` for ``y ≥ scale``:
  ``ln x = ln scale − ln(1 − u)/exponent``; an exponent below 1 (a glass)
  spreads the time constants over many decades.

The probabilities are **stratified and fixed** (:func:`assignments`): in each
of K assignments the m tendons of a family take the m quantiles
``(i + v_i)/m`` (one per stratum, ``v_i`` a seeded jitter) in a seeded random
order. Every assignment therefore holds the whole distribution, and the
values are smooth (analytic) functions of the distribution's parameters at
fixed ``u``: the model's moduli, averaged over the K assignments, are smooth
in the parameters, which is what a least-squares fit needs. The spread between
assignments says how much the one cell the average stands for depends on which
tendon got which value.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import scipy.special

from ..._checks import positive_scalar

__all__ = ["Distribution", "LogNormal", "LogUniform", "PowerLaw", "DISTRIBUTIONS", "assignments"]

_LN10 = math.log(10.0)


@dataclass(frozen=True)
class Distribution:
    """A one- or two-parameter distribution of a positive tendon property, by its quantile function.

    Subclasses define :attr:`parameters` (names of the two parameters: the
    scale, in the property's unit, then the shape) and :meth:`log_quantile`.
    """

    scale: float
    shape: float
    parameters: ClassVar[tuple[str, str]] = ("scale", "shape")
    shape_unit: ClassVar[str] = ""

    def __post_init__(self):
        positive_scalar(f"{type(self).__name__} {self.parameters[0]}", self.scale)
        positive_scalar(f"{type(self).__name__} {self.parameters[1]}", self.shape, self.shape_unit)

    def log_quantile(self, u) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(ln x, ∂ln x/∂ln scale, ∂ln x/∂ln shape)`` at probabilities ``u`` (same shape as ``u``)."""
        raise NotImplementedError

    def values(self, u) -> np.ndarray:
        """The property at probabilities ``u`` (in the unit of ``scale``)."""
        return np.exp(self.log_quantile(u)[0])


@dataclass(frozen=True)
class LogNormal(Distribution):
    """Log-normal: median ``scale``, standard deviation of ``log10 x`` = ``shape`` (decades)."""

    parameters: ClassVar[tuple[str, str]] = ("median", "decades")
    shape_unit: ClassVar[str] = "decades"

    def log_quantile(self, u):
        z = scipy.special.ndtri(np.asarray(u, dtype=float)) * _LN10
        lnx = math.log(self.scale) + self.shape * z
        return lnx, np.ones_like(lnx), self.shape * z


@dataclass(frozen=True)
class LogUniform(Distribution):
    """Log-uniform: ``log10 x`` uniform over ``shape`` decades centred (in log) on ``scale``."""

    parameters: ClassVar[tuple[str, str]] = ("centre", "decades")
    shape_unit: ClassVar[str] = "decades"

    def log_quantile(self, u):
        z = (np.asarray(u, dtype=float) - 0.5) * _LN10
        lnx = math.log(self.scale) + self.shape * z
        return lnx, np.ones_like(lnx), self.shape * z


@dataclass(frozen=True)
class PowerLaw(Distribution):
    """Trap model (Pareto): ``P(x > y) = (scale/y)^shape`` for ``y ≥ scale``; ``shape`` is the exponent."""

    parameters: ClassVar[tuple[str, str]] = ("scale", "exponent")

    def log_quantile(self, u):
        t = -np.log1p(-np.asarray(u, dtype=float))  # ≥ 0
        lnx = math.log(self.scale) + t / self.shape
        return lnx, np.ones_like(lnx), -t / self.shape


#: the distributions by name
DISTRIBUTIONS: dict[str, type[Distribution]] = {"lognormal": LogNormal, "loguniform": LogUniform,
                                                "powerlaw": PowerLaw}


def assignments(groups, K: int, seed: int = 0, *, jitter: bool = True) -> np.ndarray:
    """Stratified probabilities for K assignments of a property to tendons, shape (K, m).

    Parameters
    ----------
    groups : array_like of int, shape (m,)
        The family (or any group) of each tendon: each group holds one full
        stratified sample of the distribution in every assignment.
    K : int
        Number of assignments (>= 1).
    seed : int
        Seed of the permutations and jitters (the same seed gives the same
        assignments on every machine: numpy's PCG64).
    jitter : bool
        Place each probability uniformly at random within its stratum
        (``(i + v)/n``); without it, at the stratum's centre ``(i + ½)/n``.

    Returns
    -------
    ndarray, shape (K, m)
        Probabilities in (0, 1).
    """
    groups = np.asarray(groups, dtype=int).ravel()
    if isinstance(K, bool) or not isinstance(K, (int, np.integer)) or K < 1:
        raise ValueError(f"K (assignments) must be an integer >= 1, got {K!r}")
    rng = np.random.default_rng(seed)
    u = np.empty((int(K), groups.size))
    for g in np.unique(groups):
        idx = np.flatnonzero(groups == g)
        n = idx.size
        for k in range(int(K)):
            v = rng.uniform(0.02, 0.98, n) if jitter else np.full(n, 0.5)
            u[k, idx[rng.permutation(n)]] = (np.arange(n) + v) / n
    return u

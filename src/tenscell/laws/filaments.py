"""Filaments with a nonlinear elastic law: :class:`StiffeningFilament` (strain-stiffening intermediate filaments)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .base import Parameter, Tangent, TendonLaw, _refs

__all__ = ["StiffeningFilament"]


def _expm1_over_b(b, x):
    """``(exp(b·x) − 1)/b``, equal to ``x`` at ``b = 0``."""
    safe = np.where(b > 0, b, 1.0)
    return np.where(b > 0, np.expm1(safe * x) / safe, x)


def _log1p_over_b(b, y):
    """``log(1 + b·y)/b``, equal to ``y`` at ``b = 0`` (the inverse of :func:`_expm1_over_b`)."""
    safe = np.where(b > 0, b, 1.0)
    return np.where(b > 0, np.log1p(safe * y) / safe, y)


def _dlog1p_over_b_db(b, y):
    """``∂/∂b [log(1 + b·y)/b] = (y/(1 + b·y) − log(1 + b·y)/b)/b``; its series where ``|b·y|`` is small.

    The series ``Σ_{n≥1} (−1)ⁿ n/(n+1) bⁿ⁻¹ yⁿ⁺¹`` avoids the cancellation
    (−y²/2 at b = 0); 8 terms are exact to round-off for ``|b·y| < 0.02``.
    """
    b, y = np.broadcast_arrays(np.asarray(b, dtype=float), np.asarray(y, dtype=float))
    x = b * y
    small = np.abs(x) < 0.02
    series = np.zeros_like(x)
    for n in range(8, 0, -1):
        series = (-1) ** n * n / (n + 1) * y ** 2 * x ** (n - 1) + series
    safe = np.where(small, 1.0, b)
    direct = (y / (1.0 + safe * y) - np.log1p(safe * y) / safe) / safe
    return np.where(small, series, direct)


@dataclass(frozen=True, eq=False)
class StiffeningFilament(TendonLaw):
    """A strain-stiffening filament: ``T = (EA/b)(exp(b·ε) − 1) + c·l'``, ``ε = l/l0 − 1``.

    Intermediate filaments are "known sources of nonlinear elastic behavior"
    (the paper's discussion). ``EA`` is the small-strain stiffness (N) and
    ``b ≥ 0`` the dimensionless stiffening exponent; ``b = 0`` is the Voigt
    spring ``EA·ε``. The tangent stiffness ``∂T/∂l = (EA/l0)·exp(b·ε) =
    (EA + b·T)/l0`` grows linearly with the tension, the signature of
    strain-stiffening biopolymer networks.

    At a reference with tension ``T`` and length ``l``: ``ε = log(1 +
    b·T/EA)/b``, ``l0 = l/(1 + ε)`` and ``k = (EA + b·T)(1 + ε)/l``, with

    * ``∂k/∂T = (1 + b(1 + ε))/l``,
    * ``∂k/∂EA = (1 + ε − T/EA)/l``,
    * ``∂k/∂b = (T(1 + ε) + (EA + b·T)·∂ε/∂b)/l``, ``∂ε/∂b = (T/(EA + b·T) − ε)/b``.

    Parameters
    ----------
    EA : float or ndarray, shape (m,)
        Small-strain stiffness (N), > 0.
    c : float or ndarray, shape (m,)
        Damping (N·s/m), ≥ 0.
    b : float or ndarray, shape (m,)
        Stiffening exponent (dimensionless), ≥ 0.
    l0 : ndarray, shape (m,), optional
        Rest lengths (m).
    """

    EA: Any
    c: Any
    b: object = 0.0
    l0: Any = None
    parameters: ClassVar = (Parameter("EA", "N"), Parameter("c", "N·s/m", True), Parameter("b", "", True))
    mechanism_group: ClassVar = "mechanisms: stiffening filaments"
    lumped_terms: ClassVar = ("E0", "newtonian")
    rate_linear: ClassVar = True

    def __post_init__(self):
        self._validate()

    def elastic(self, l):
        """``(EA/b)(exp(b·ε) − 1)`` (N)."""
        return self.EA * _expm1_over_b(self.b, np.asarray(l, dtype=float) / self._l0() - 1.0)

    def tension(self, l, ldot):
        """``(EA/b)(exp(b·ε) − 1) + c·l'`` (N)."""
        return self.elastic(l) + self.c * ldot

    def stiffness_at_rest(self, l):
        """``(EA/l0)·exp(b·ε)`` (N/m)."""
        l0 = self._l0()
        return self.EA / l0 * np.exp(self.b * (np.asarray(l, dtype=float) / l0 - 1.0))

    def derivatives(self, l, ldot):
        """``(T, (EA/l0)exp(b·ε), c)`` in (N, N/m, N·s/m)."""
        return self.tension(l, ldot), self.stiffness_at_rest(l), np.broadcast_to(self.c, np.shape(self._l0()))

    def damping_at_rest(self, l):
        """``c`` (N·s/m)."""
        return np.broadcast_to(self.c, np.shape(l)).astype(float)

    def _strain(self, T):
        y = np.asarray(T, dtype=float) / self.EA
        if np.any(1.0 + self.b * y <= 0):
            raise ValueError("tension T is below -EA/b, which the exponential law never reaches")
        eps = _log1p_over_b(self.b, y)
        if np.any(eps <= -1.0):
            raise ValueError("the requested tension needs a strain <= -1 (a non-positive rest length)")
        return eps

    def rest_lengths(self, l, T):
        """``l0 = l/(1 + ε)``, ``ε = log(1 + b·T/EA)/b`` (``T/EA`` at ``b = 0``) (m)."""
        l, T = _refs(l, T)
        return l / (1.0 + self._strain(T))

    def tangent_at_rest(self, l, T):
        """``((EA + b·T)(1 + ε)/l, c)``."""
        l, T = _refs(l, T)
        eps = self._strain(T)
        return (self.EA + self.b * T) * (1.0 + eps) / l, np.broadcast_to(self.c, l.shape).astype(float)

    def tangent(self, l, T) -> Tangent:
        """Exact derivatives (see the class docstring)."""
        l, T = _refs(l, T)
        eps = self._strain(T)
        k = (self.EA + self.b * T) * (1.0 + eps) / l
        deps_db = _dlog1p_over_b_db(self.b, T / self.EA)
        return self._tangent(
            l, T, k, np.broadcast_to(self.c, l.shape), (1.0 + self.b * (1.0 + eps)) / l,
            {"EA": (1.0 + eps - T / self.EA) / l, "b": (T * (1.0 + eps) + (self.EA + self.b * T) * deps_db) / l},
            {"c": 1.0},
        )


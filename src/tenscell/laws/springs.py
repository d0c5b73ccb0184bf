"""The spring-dashpot family: :class:`Voigt` (the paper's Eq. 1), :class:`PowerDashpot`, :class:`LinearSpring`."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .._checks import positive_scalar
from .base import LinearizationError, Parameter, Tangent, TendonLaw, _per, _refs

__all__ = ["Voigt", "PowerDashpot", "LinearSpring", "DEFAULT_VELOCITY_SCALE"]

#: default smoothing velocity ε of :class:`PowerDashpot` (m/s)
DEFAULT_VELOCITY_SCALE = 1e-3


# ---- the linear spring part shared by Voigt and the power-law dashpot --------------------------------
class _SpringEA(TendonLaw):
    """``EA(l/l0 − 1)``: the paper's linear spring, with the rest lengths of Eq. (11)."""

    def elastic(self, l):
        """``EA(l/l0 − 1)`` (N)."""
        return self.EA * (np.asarray(l) / self._l0() - 1.0)

    def stiffness_at_rest(self, l):
        """``EA/l0`` (N/m)."""
        return self.EA / self._l0()

    def rest_lengths(self, l, T):
        """Eq. (11): ``l0 = l·EA/(EA + T)`` (m).

        Raises
        ------
        ValueError
            Where ``T ≤ −EA`` (a compressed member softer than its load would need ``l0 ≤ 0``).
        """
        l, T = _refs(l, T)
        d = self.EA + T
        if not d.min() > 0:
            j = int(np.flatnonzero(np.broadcast_to(d, l.shape) <= 0)[0])
            raise ValueError(
                f"EA must exceed the compression −T = {-np.broadcast_to(T, l.shape)[j]:.6g} N of member {j} "
                f"(got EA = {np.broadcast_to(self.EA, l.shape)[j]:.6g} N): the spring would need a non-positive rest length"
            )
        return l * self.EA / d

    def _spring_tangent(self, l, T):
        """``k = (EA + T)/l`` (N/m): Eq. (11) rest lengths make ``EA/l0`` this."""
        return (self.EA + T) / l


@dataclass(frozen=True, eq=False)
class Voigt(_SpringEA):
    """Voigt tendon (paper Eq. 1): ``T = EA·(l/l0 − 1) + c·l'``.

    Parameters
    ----------
    EA : float or ndarray, shape (m,)
        Axial stiffness (N), > 0.
    c : float or ndarray, shape (m,)
        Damping coefficient (N·s/m), ≥ 0.
    l0 : ndarray, shape (m,), optional
        Rest lengths (m); set by :meth:`at_prestress` (Eq. 11).

    Notes
    -----
    At a reference with tension ``T``: ``k = EA/l0 = (EA + T)/l``,
    ``∂k/∂T = 1/l``, ``∂k/∂EA = 1/l``, ``∂c/∂c = 1``.
    """

    EA: Any
    c: Any
    l0: Any = None
    parameters: ClassVar = (Parameter("EA", "N"), Parameter("c", "N·s/m", True))
    mechanism_group: ClassVar = "mechanisms: Voigt tendons"
    lumped_terms: ClassVar = ("E0", "newtonian")
    rate_linear: ClassVar = True

    def __post_init__(self):
        self._validate()

    def tension(self, l, ldot):
        """``EA(l/l0 − 1) + c·l'`` (N)."""
        return self.elastic(l) + self.c * ldot

    def derivatives(self, l, ldot):
        """``(T, EA/l0, c)`` in (N, N/m, N·s/m)."""
        return self.tension(l, ldot), self.EA / self._l0(), np.broadcast_to(self.c, np.shape(self._l0()))

    def damping_at_rest(self, l):
        """``c`` (N·s/m)."""
        return np.broadcast_to(self.c, np.shape(l)).astype(float)

    def tangent_at_rest(self, l, T):
        """``((EA + T)/l, c)``."""
        return self._reference(l, T)[1:]

    def _reference(self, l, T):
        l, T = _refs(l, T)
        return self.rest_lengths(l, T), self._spring_tangent(l, T), _per(self.c, l.shape)

    def tangent(self, l, T) -> Tangent:
        """Exact: ``∂k/∂T = ∂k/∂EA = 1/l``, ``∂c/∂c = 1``."""
        l, T = _refs(l, T)
        k, c = self.tangent_at_rest(l, T)
        return self._tangent(l, T, k, c, 1.0 / l, {"EA": 1.0 / l}, {"c": 1.0})


@dataclass(frozen=True, eq=False)
class PowerDashpot(_SpringEA):
    """Spring in parallel with a power-law dashpot (the paper's discussion).

    The exact law is ``T = EA(l/l0 − 1) + c·sign(l')·|l'|^β``. Its rate
    derivative at ``l' = 0`` is 0 for β > 1 and infinite for β < 1; either
    way the velocities of the massless equations of motion are not a smooth
    function of the configuration where some ``l' = 0``. The time integration
    therefore uses the smoothed dashpot

    ``φ_ε(l') = c·l'·(l'² + ε²)^((β−1)/2)``,

    which equals the exact law to relative accuracy ``(β−1)/2·(ε/l')²`` for
    ``|l'| ≫ ε``, is odd and strictly increasing, and acts as a linear
    dashpot of coefficient ``c·ε^(β−1)`` for ``|l'| ≪ ε``. Choose the
    velocity scale ε (m/s) well below the tendon rates of interest (the
    default :data:`DEFAULT_VELOCITY_SCALE` = 1e-3 m/s is ~1/30 of the peak
    tendon rates of a 3 N, 1 Hz load on the default cell, where going down to
    3e-4 m/s changes G'' by 0.1 %) and check that a smaller ε leaves the
    result unchanged; smaller ε makes the equations stiffer at velocity
    reversals. β = 1 is the Voigt law exactly, for any ε.

    The linearization (:meth:`damping_at_rest`) refers to the exact law, not
    the smoothing: 0 for β > 1 (so C0 = 0 and G'' = 0, the paper's argument),
    ``c`` for β = 1, and no linearization for β < 1.

    Parameters
    ----------
    EA : float or ndarray, shape (m,)
        Axial stiffness (N).
    c : float or ndarray, shape (m,)
        Dashpot coefficient (N·(s/m)^β).
    l0 : ndarray, shape (m,), optional
        Rest lengths (m).
    beta : float
        Dashpot exponent β > 0 (dimensionless).
    velocity_scale : float
        Smoothing velocity ε > 0 (m/s).
    """

    EA: Any
    c: Any
    l0: Any = None
    beta: float = 2.0
    velocity_scale: float = DEFAULT_VELOCITY_SCALE
    parameters: ClassVar = (Parameter("EA", "N"), Parameter("c", "N·(s/m)^beta", True))
    mechanism_group: ClassVar = "mechanisms: power-law dashpot tendons"
    lumped_terms: ClassVar = ("E0", "newtonian")

    def __post_init__(self):
        self._validate()
        object.__setattr__(self, "beta", positive_scalar("beta (dashpot exponent)", self.beta))
        object.__setattr__(self, "velocity_scale", positive_scalar("velocity_scale", self.velocity_scale, "m/s"))

    @property
    def rate_linear(self) -> bool:  # type: ignore[override]  # per instance here, a class constant elsewhere
        """True only for β = 1 (then the law is exactly Voigt)."""
        return self.beta == 1.0

    def _dashpot(self, ldot):
        ldot = np.asarray(ldot, dtype=float)
        b, eps2 = self.beta, self.velocity_scale ** 2
        s = ldot * ldot + eps2
        g = s ** (0.5 * (b - 1.0))
        f = self.c * ldot * g
        # d/dl' [l' s^((β−1)/2)] = s^((β−1)/2) (1 + (β−1) l'^2/s)
        df = self.c * g * (1.0 + (b - 1.0) * ldot * ldot / s)
        return f, df

    def tension(self, l, ldot):
        """Smoothed ``EA(l/l0 − 1) + c·sign(l')|l'|^β`` (N)."""
        return self.elastic(l) + self._dashpot(ldot)[0]

    def derivatives(self, l, ldot):
        """``(T, dT/dl, dT/dl')`` of the smoothed law, in (N, N/m, N·s/m)."""
        f, df = self._dashpot(ldot)
        return self.elastic(l) + f, self.EA / self._l0(), df

    def _exact_rate_slope(self, shape) -> np.ndarray:
        if self.beta > 1.0:
            return np.zeros(shape)
        if self.beta == 1.0:
            return np.broadcast_to(self.c, shape).astype(float)
        raise LinearizationError(
            f"the dashpot law T = c·sign(l')·|l'|^beta with beta={self.beta:g} < 1 has an infinite slope at "
            "l' = 0, so the equations of motion have no linearization about the prestressed rest state and no "
            "linear moduli G', G'' exist; simulate the finite-amplitude response in the time domain instead "
            "(tenscell.dynamics.oscillatory_response)"
        )

    def damping_at_rest(self, l):
        """Rate derivative of the exact law at ``l' = 0`` (N·s/m): 0 for β > 1, ``c`` for β = 1.

        Raises
        ------
        LinearizationError
            For β < 1, where ``d(c|l'|^β)/dl'`` is infinite at ``l' = 0``.
        """
        return self._exact_rate_slope(np.shape(l))

    def tangent_at_rest(self, l, T):
        """``((EA + T)/l, c_lin)`` with the exact law's rate slope (raises for β < 1)."""
        l, T = _refs(l, T)
        self.rest_lengths(l, T)
        return self._spring_tangent(l, T), self._exact_rate_slope(l.shape)

    def tangent(self, l, T) -> Tangent:
        """Exact: ``∂k/∂T = ∂k/∂EA = 1/l``; ``∂c/∂c`` is 1 for β = 1, else 0."""
        l, T = _refs(l, T)
        k, c = self.tangent_at_rest(l, T)
        return self._tangent(l, T, k, c, 1.0 / l, {"EA": 1.0 / l}, {"c": 1.0 if self.beta == 1.0 else 0.0})


@dataclass(frozen=True, eq=False)
class LinearSpring(TendonLaw):
    """A spring of given stiffness: ``T = k(l − l0) + c·l'``.

    Its tangent stiffness is ``k`` (N/m) whatever the tension (``∂k/∂T = 0``);
    :func:`tenscell.linear.linearize.linearize_tangent` linearizes with it.

    Parameters
    ----------
    k : float or ndarray, shape (m,)
        Stiffness (N/m), > 0.
    c : float or ndarray, shape (m,)
        Damping (N·s/m), ≥ 0.
    l0 : ndarray, shape (m,), optional
        Rest lengths (m).
    """

    k: Any
    c: Any
    l0: Any = None
    parameters: ClassVar = (Parameter("k", "N/m"), Parameter("c", "N·s/m", True))
    mechanism_group: ClassVar = "mechanisms: linear springs"
    lumped_terms: ClassVar = ("E0", "newtonian")
    rate_linear: ClassVar = True

    def __post_init__(self):
        self._validate()

    def tension(self, l, ldot):
        """``k(l − l0) + c·l'`` (N)."""
        return self.k * (np.asarray(l, dtype=float) - self._l0()) + self.c * ldot

    def derivatives(self, l, ldot):
        """``(T, k, c)``."""
        return self.tension(l, ldot), np.broadcast_to(self.k, np.shape(self._l0())), np.broadcast_to(self.c, np.shape(self._l0()))

    def rest_lengths(self, l, T):
        """``l − T/k`` (m); ValueError where that is not positive."""
        l, T = _refs(l, T)
        l0 = l - T / self.k
        if np.any(l0 <= 0):
            raise ValueError("a member's tension exceeds k·l: the spring would need a non-positive rest length")
        return l0

    def tangent_at_rest(self, l, T):
        """``(k, c)``."""
        l, T = _refs(l, T)
        return np.broadcast_to(self.k, l.shape).astype(float), np.broadcast_to(self.c, l.shape).astype(float)

    def tangent(self, l, T) -> Tangent:
        """Exact: ``∂k/∂T = 0``, ``∂k/∂k = 1``, ``∂c/∂c = 1``."""
        l, T = _refs(l, T)
        k, c = self.tangent_at_rest(l, T)
        return self._tangent(l, T, k, c, 0.0, {"k": 1.0}, {"c": 1.0})


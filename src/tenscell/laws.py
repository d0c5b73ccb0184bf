"""Tendon laws: tension as a function of length and lengthening rate.

Every law is a frozen dataclass with per-tendon parameter arrays (shape
``(m,)``, one entry per working tendon) and the same small interface, which
is all that :mod:`tenscell.dynamics` uses:

``tension(l, ldot)``
    tension ``T`` (N) for lengths ``l`` (m) and rates ``ldot = dl/dt`` (m/s);
``derivatives(l, ldot)``
    ``(T, dT/dl, dT/dldot)`` in (N, N/m, N·s/m);
``elastic(l)``
    the rate-independent part ``T(l, 0)`` (N), which stores energy;
``stiffness_at_rest(l)``
    ``dT/dl`` at ``ldot = 0`` (N/m), for the linearization;
``damping_at_rest(l)``
    ``dT/dldot`` at ``ldot = 0`` of the *exact* law (N·s/m), for the
    linearization; raises :class:`LinearizationError` when it does not exist;
``rate_linear``
    ``True`` when ``T`` is affine in ``ldot`` (the equations of motion are then
    linear in the velocities and need no inner Newton iteration).

The laws give the constitutive tension only. That a tendon is a cable (it
goes slack rather than carry compression) is a structural fact handled by
:mod:`tenscell.dynamics`, the same for every law.

Laws
----
:class:`Voigt`
    the paper's Eq. (1), ``T = EA(l/l0 − 1) + c·l'``.
:class:`PowerDashpot`
    the discussion's nonlinear dashpot, ``T = EA(l/l0 − 1) + c·sign(l')|l'|^β``,
    smoothed near ``l' = 0`` (see the class docstring).

Rest lengths ``l0`` come from the prestress through the paper's Eq. (11):
build laws with :func:`voigt_law` or :func:`power_dashpot_law`, which call
:func:`tenscell.model.equilibrium.rest_lengths`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ._checks import finite_scalar, positive_array, positive_scalar
from .model.equilibrium import Cell, rest_lengths

__all__ = [
    "TendonLaw",
    "Voigt",
    "PowerDashpot",
    "LinearizationError",
    "voigt_law",
    "power_dashpot_law",
    "DEFAULT_VELOCITY_SCALE",
]

#: default smoothing velocity ε of :class:`PowerDashpot` (m/s)
DEFAULT_VELOCITY_SCALE = 1e-3


class LinearizationError(ValueError):
    """The tendon law has no linearization at rest (its rate derivative at l' = 0 is infinite)."""


class TendonLaw(Protocol):
    """The interface shared by every tendon law (see the module docstring)."""

    rate_linear: bool

    @property
    def m(self) -> int: ...

    def tension(self, l: np.ndarray, ldot: np.ndarray) -> np.ndarray: ...

    def derivatives(self, l: np.ndarray, ldot: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...

    def elastic(self, l: np.ndarray) -> np.ndarray: ...

    def stiffness_at_rest(self, l: np.ndarray) -> np.ndarray: ...

    def damping_at_rest(self, l: np.ndarray) -> np.ndarray: ...


def _params(m: int | None, **arrays) -> tuple[np.ndarray, ...]:
    """Validate per-tendon arrays (positive, equal length) and return them read-only."""
    shape = None
    out = []
    for name, (value, unit) in arrays.items():
        arr = positive_array(name, value, None, unit)
        if arr.ndim > 1:
            raise ValueError(f"{name} must be a scalar or a 1-D array (one value per tendon), got shape {arr.shape}")
        out.append((name, arr))
        if arr.ndim == 1:
            if shape is not None and arr.shape != shape:
                raise ValueError(f"{name} has {arr.shape[0]} entries but another parameter has {shape[0]}")
            shape = arr.shape
    if m is not None:
        if shape is not None and shape != (m,):
            raise ValueError(f"tendon parameters must have {m} entries (one per working tendon), got {shape[0]}")
        shape = (m,)
    if shape is None:
        raise ValueError("at least one tendon parameter must be an array with one entry per tendon")
    res = []
    for _, arr in out:
        a = np.array(np.broadcast_to(arr, shape), dtype=float)
        a.setflags(write=False)
        res.append(a)
    return tuple(res)


@dataclass(frozen=True, eq=False)
class Voigt:
    """Voigt tendon (paper Eq. 1): ``T = EA·(l/l0 − 1) + c·l'``.

    Parameters
    ----------
    EA : ndarray, shape (m,)
        Axial stiffness (N).
    c : ndarray, shape (m,)
        Damping coefficient (N·s/m).
    l0 : ndarray, shape (m,)
        Rest lengths (m).
    """

    EA: np.ndarray
    c: np.ndarray
    l0: np.ndarray
    rate_linear = True

    def __post_init__(self):
        EA, c, l0 = _params(None, EA=(self.EA, "N"), c=(self.c, "N·s/m"), l0=(self.l0, "m"))
        object.__setattr__(self, "EA", EA)
        object.__setattr__(self, "c", c)
        object.__setattr__(self, "l0", l0)

    @property
    def m(self) -> int:
        """Number of tendons."""
        return self.l0.size

    def elastic(self, l):
        """``EA(l/l0 − 1)`` (N)."""
        return self.EA * (np.asarray(l) / self.l0 - 1.0)

    def tension(self, l, ldot):
        """``EA(l/l0 − 1) + c·l'`` (N)."""
        return self.elastic(l) + self.c * ldot

    def derivatives(self, l, ldot):
        """``(T, dT/dl, dT/dl')`` = ``(T, EA/l0, c)`` in (N, N/m, N·s/m)."""
        return self.tension(l, ldot), self.EA / self.l0, self.c

    def stiffness_at_rest(self, l):
        """``EA/l0`` (N/m)."""
        return self.EA / self.l0

    def damping_at_rest(self, l):
        """``c`` (N·s/m)."""
        return self.c


@dataclass(frozen=True, eq=False)
class PowerDashpot:
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
    EA : ndarray, shape (m,)
        Axial stiffness (N).
    c : ndarray, shape (m,)
        Dashpot coefficient (N·(s/m)^β).
    l0 : ndarray, shape (m,)
        Rest lengths (m).
    beta : float
        Dashpot exponent β > 0 (dimensionless).
    velocity_scale : float
        Smoothing velocity ε > 0 (m/s).
    """

    EA: np.ndarray
    c: np.ndarray
    l0: np.ndarray
    beta: float
    velocity_scale: float = DEFAULT_VELOCITY_SCALE

    def __post_init__(self):
        EA, c, l0 = _params(None, EA=(self.EA, "N"), c=(self.c, "N·(s/m)^beta"), l0=(self.l0, "m"))
        object.__setattr__(self, "EA", EA)
        object.__setattr__(self, "c", c)
        object.__setattr__(self, "l0", l0)
        object.__setattr__(self, "beta", positive_scalar("beta (dashpot exponent)", self.beta))
        object.__setattr__(self, "velocity_scale", positive_scalar("velocity_scale", self.velocity_scale, "m/s"))

    @property
    def rate_linear(self) -> bool:
        """True only for β = 1 (then the law is exactly Voigt)."""
        return self.beta == 1.0

    @property
    def m(self) -> int:
        """Number of tendons."""
        return self.l0.size

    def elastic(self, l):
        """``EA(l/l0 − 1)`` (N)."""
        return self.EA * (np.asarray(l) / self.l0 - 1.0)

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
        return self.elastic(l) + f, self.EA / self.l0, df

    def stiffness_at_rest(self, l):
        """``EA/l0`` (N/m)."""
        return self.EA / self.l0

    def damping_at_rest(self, l):
        """Rate derivative of the exact law at ``l' = 0`` (N·s/m): 0 for β > 1, ``c`` for β = 1.

        Raises
        ------
        LinearizationError
            For β < 1, where ``d(c|l'|^β)/dl'`` is infinite at ``l' = 0``.
        """
        if self.beta > 1.0:
            return np.zeros_like(self.c)
        if self.beta == 1.0:
            return self.c
        raise LinearizationError(
            f"the dashpot law T = c·sign(l')·|l'|^beta with beta={self.beta:g} < 1 has an infinite slope at "
            "l' = 0, so the equations of motion have no linearization about the prestressed rest state and no "
            "linear moduli G', G'' exist; simulate the finite-amplitude response in the time domain instead "
            "(tenscell.dynamics.oscillatory_response)"
        )


def voigt_law(cell: Cell, P: float = 1000.0, EA=1.0, c=1.0) -> Voigt:
    """The Voigt law of a cell at prestress ``P`` (rest lengths from Eq. 11).

    Parameters
    ----------
    cell : Cell
    P : float
        Prestress scale (N): tensions ``P·T0`` at the reference.
    EA : float or array_like, shape (m,)
        Stiffness (N).
    c : float or array_like, shape (m,)
        Damping (N·s/m).
    """
    P = positive_scalar("P (prestress)", P, "N")
    EA, c = _params(cell.m, EA=(EA, "N"), c=(c, "N·s/m"))
    return Voigt(EA=EA, c=c, l0=rest_lengths(cell, P, EA))


def power_dashpot_law(cell: Cell, P: float = 1000.0, EA=1.0, c=1.0, beta: float = 2.0,
                      velocity_scale: float = DEFAULT_VELOCITY_SCALE) -> PowerDashpot:
    """The power-law dashpot of a cell at prestress ``P`` (rest lengths from Eq. 11).

    Parameters
    ----------
    cell : Cell
    P : float
        Prestress scale (N).
    EA : float or array_like, shape (m,)
        Stiffness (N).
    c : float or array_like, shape (m,)
        Dashpot coefficient (N·(s/m)^β).
    beta : float
        Exponent β > 0.
    velocity_scale : float
        Smoothing velocity ε (m/s), see :class:`PowerDashpot`.
    """
    P = positive_scalar("P (prestress)", P, "N")
    finite_scalar("beta (dashpot exponent)", beta)
    EA, c = _params(cell.m, EA=(EA, "N"), c=(c, "N·(s/m)^beta"))
    return PowerDashpot(EA=EA, c=c, l0=rest_lengths(cell, P, EA), beta=beta, velocity_scale=velocity_scale)

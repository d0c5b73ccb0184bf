"""Tendons with dynamics of their own: :class:`Maxwell`, :class:`StandardLinearSolid`, :class:`Springpot`,
:class:`TensionSpringpot`.

The paper's Voigt tendon has one stiffness and one damping at every
frequency. The laws here have an internal state (a dashpot's extension, or a
fractional element's memory), so their tangent about the prestressed rest
state depends on the frequency: the dynamic tangent

``k*_j(ω) = ∂T_j/∂l_j`` (N/m, complex), ω in rad/s,

given exactly by :meth:`~tenscell.laws.TendonLaw.complex_stiffness`, with its
derivatives in the tension and in every parameter
(:meth:`~tenscell.laws.TendonLaw.complex_stiffness_derivatives`). Every law
here splits into the paper's two parts at the reference with tension ``T``
and length ``l``: the prestress part ``T/l`` (the paper's ``P·Kp``) and a
material part built on ``EA/l`` (the paper's ``EA_j·K_j``):

================================  ===================================================  ==================  =================
law                               k*(ω)                                                ω → 0               ω → ∞
================================  ===================================================  ==================  =================
:class:`Maxwell` (EA, c)          ``T/l + (EA/l)·iωτ/(1 + iωτ)``, ``τ = c·l/EA``       ``T/l``             ``(EA + T)/l``
:class:`StandardLinearSolid`      ``(EA + T)/l + (EA_arm/l)·iωτ/(1 + iωτ)``,           ``(EA + T)/l``      ``(EA + EA_arm + T)/l``
(EA, EA_arm, c)                   ``τ = c·l/EA_arm``
:class:`Springpot` (EA, kappa,    ``(EA + T)/l + (kappa/l)·(iω·t1)^α``, ``t1 = 1 s``   ``(EA + T)/l``      grows as ω^α
alpha)
:class:`TensionSpringpot` (EA,    ``(EA + T)/l + (kappa/l)·(iω·t1)^α``                 ``(EA + T)/l``      grows as ω^max(α,α_T)
kappa, alpha, beta, alpha_T)      ``+ (beta·T/l)·(iω·t1)^α_T``
================================  ===================================================  ==================  =================

Scaling (exact, and tested): the strut-length scaling ``(P, EA, c, L) →
(λ²P, λ²EA, λc, λL)`` with ``EA_arm → λ²EA_arm`` and ``kappa → λ²kappa``
scales every ``k*`` by λ at the same ω (``beta`` unchanged); the time scaling ``c → λc`` (and
``kappa → λ^α·kappa``, ``beta → λ^α_T·beta``) at ``f → f/λ`` leaves ``k*`` unchanged.

None of these laws has a constant pair (k, c) nor a tension ``T(l, l')``
without internal state: :meth:`tangent_at_rest`, :meth:`tension` and
:meth:`derivatives` raise :class:`~tenscell.laws.DynamicLawError` naming what
to use instead. Rest lengths are those of the spring ``EA`` (the paper's
Eq. 11), so :meth:`at_prestress` works as for Voigt.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any, ClassVar

import numpy as np

from .base import (DEFAULT_REALIZATION_TOL, DynamicLawError, Parameter, Realization, _refs, angular_frequencies,
                   laplace_variables)
from .springs import _SpringEA

__all__ = ["Maxwell", "StandardLinearSolid", "Springpot", "TensionSpringpot", "SPRINGPOT_TIME", "DEFAULT_REALIZATION_BAND_HZ",
           "springpot_prony"]

#: the reference time t1 of :class:`Springpot` (s): kappa is the springpot's axial modulus at ω = 1/t1 = 1 rad/s
SPRINGPOT_TIME = 1.0
#: default band (Hz) over which an approximate realization is accurate: the paper's 10⁻² to 10³ Hz
DEFAULT_REALIZATION_BAND_HZ = (1e-2, 1e3)
#: (arms per decade, decades of margin beyond the band) tried in turn until the Prony series meets its tolerance
_PRONY_SCHEDULE = ((2, 2), (3, 2), (3, 3), (4, 3), (4, 4), (6, 5), (8, 6))
#: points per decade on which the Prony error is measured (5× the densest fitting grid's arms)
_PRONY_CHECK_PER_DECADE = 50


class _DynamicSpring(_SpringEA):
    """A spring ``EA`` (rest lengths of Eq. 11) with an internal-state element: the dynamic-law protocol."""

    dynamic: ClassVar = True
    rate_linear: ClassVar = False

    def _refuse(self, what: str):
        name = type(self).__name__
        return DynamicLawError(
            f"the {name} tendon law has an internal state, so {what}: use law.complex_stiffness(l, T, omega) "
            f"or tenscell.linear.dynamic.dynamic_moduli(cell, law, P, f) for moduli, and "
            f"tenscell.linear.linearize_law(cell, law, P) (its internal-variable realization) for creep and relaxation"
        )

    def tension(self, l, ldot):
        """Refused: the tension depends on the history, not on ``(l, l')`` alone."""
        raise self._refuse("its tension is not a function T(l, l') (the nonlinear time domain does not carry it)")

    def derivatives(self, l, ldot):
        """Refused (see :meth:`tension`)."""
        raise self._refuse("its tension is not a function T(l, l') (the nonlinear time domain does not carry it)")

    def elastic(self, l):
        """Refused (see :meth:`tension`)."""
        raise self._refuse("its tension is not a function T(l, l') (the nonlinear time domain does not carry it)")

    def tangent_at_rest(self, l, T):
        """Refused: the tangent depends on frequency (see :meth:`complex_stiffness`)."""
        raise self._refuse("its tangent depends on frequency and has no constant (k, c)")

    def tangent(self, l, T):
        """Refused: the tangent depends on frequency (see :meth:`complex_stiffness_derivatives`)."""
        raise self._refuse("its tangent depends on frequency and has no constant (k, c)")

    def _check(self, l, T):
        l, T = _refs(l, T)
        self.rest_lengths(l, T)  # a tension the spring cannot carry fails here, as for Voigt
        return l, T


def _band(band_hz) -> tuple[float, float]:
    lo, hi = DEFAULT_REALIZATION_BAND_HZ if band_hz is None else (float(band_hz[0]), float(band_hz[1]))
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
        raise ValueError(f"band_hz must be two frequencies 0 < low < high (Hz), got {band_hz!r}")
    return lo, hi


def _one_arm_per_tendon(k, c, arm_k, arm_c) -> Realization:
    m = np.size(k)
    return Realization(k=np.asarray(k, dtype=float), c=np.broadcast_to(np.asarray(c, dtype=float), (m,)).copy(),
                       tendon=np.arange(m), arm_k=np.asarray(arm_k, dtype=float),
                       arm_c=np.broadcast_to(np.asarray(arm_c, dtype=float), (m,)).copy())


@lru_cache(maxsize=64)
def springpot_prony(alpha: float, band_hz: tuple[float, float] = DEFAULT_REALIZATION_BAND_HZ,
                    tol: float = DEFAULT_REALIZATION_TOL) -> tuple[float, np.ndarray, np.ndarray, float]:
    """A passive Prony series for ``(iω·t1)^α`` over a band: ``g_d·iω + Σ g_i·iωτ_i/(1 + iωτ_i)``.

    Relaxation times τ_i of the arms log-spaced over the band (ω = 2πf) widened by a
    margin; non-negative weights (so every element is a passive spring,
    dashpot or Maxwell arm) from non-negative least squares on the relative
    error at 4 points per arm; more arms per decade and a wider margin until
    the largest relative error ``|series − (iω·t1)^α|/|(iω·t1)^α|``, measured
    on 50 points per decade across the band, is at most ``tol``. No parallel
    spring: the static limit is exact (0).

    Returns
    -------
    g_d : float
        Dashpot weight (s): the term ``g_d·iω``.
    tau : ndarray, shape (r,)
        The arms' relaxation times (s), read-only (the result is cached).
    g : ndarray, shape (r,)
        Arm weights (dimensionless), ≥ 0, read-only.
    error : float
        The measured largest relative error over the band.

    Raises
    ------
    ValueError
        If no series of the schedule (up to 8 arms per decade) reaches ``tol``.
    """
    # scipy.optimize costs 0.1-0.16 s to import and only this fit (cached per alpha, band, tol) uses it
    import scipy.optimize

    lo, hi = np.log10(2 * np.pi * band_hz[0]), np.log10(2 * np.pi * band_hz[1])
    wc = np.logspace(lo, hi, int(np.ceil((hi - lo) * _PRONY_CHECK_PER_DECADE)) + 1)
    err = np.inf
    for per_decade, margin in _PRONY_SCHEDULE:
        n = int(np.ceil((hi - lo + 2 * margin) * per_decade)) + 1
        tau = np.logspace(-(hi + margin), -(lo - margin), n)
        wf = np.logspace(lo, hi, int(np.ceil((hi - lo) * 4 * per_decade)) + 1)
        B, phi = _prony_basis(wf, tau, wf[-1]), (1j * wf * SPRINGPOT_TIME) ** alpha
        Bn, y = B / np.abs(phi)[:, None], phi / np.abs(phi)
        g, _ = scipy.optimize.nnls(np.vstack([Bn.real, Bn.imag]), np.concatenate([y.real, y.imag]), maxiter=50 * n)
        target = (1j * wc * SPRINGPOT_TIME) ** alpha
        err = float(np.max(np.abs(_prony_basis(wc, tau, wf[-1]) @ g - target) / np.abs(target)))
        if err <= tol:
            keep = g[1:] > 0
            tau_k, g_k = tau[keep], g[1:][keep]
            tau_k.setflags(write=False)
            g_k.setflags(write=False)
            return float(g[0]) / wf[-1], tau_k, g_k, err
    raise ValueError(f"no Prony series of up to 8 arms per decade represents the springpot (alpha={alpha:g}) within "
                     f"tol={tol:g} over {band_hz[0]:g}–{band_hz[1]:g} Hz (best {err:.2g}); ask for a larger tol")


def _prony_basis(w, tau, w_top) -> np.ndarray:
    """Columns: the dashpot ``iω/w_top`` (scaled to order 1 in the band) and the arms ``iωτ/(1 + iωτ)``."""
    z = 1j * np.multiply.outer(w, tau)
    return np.concatenate([(1j * w / w_top)[:, None], z / (1 + z)], axis=1)


def _arm_s(k, c, s):
    """A spring ``k`` in series with a dashpot ``c`` at Laplace variables ``s``: ``k·sc/(k + sc)``, shape (n_s, m)."""
    z = np.multiply.outer(s, c)
    return k * z / (k + z)


def _arm_s_derivatives(k, c, s):
    """``∂/∂k`` and ``∂/∂c`` of :func:`_arm_s`: ``(sc/(k + sc))²`` and ``s(k/(k + sc))²``, shape (n_s, m)."""
    z = np.multiply.outer(s, c)
    d = k + z
    return (z / d) ** 2, s[:, None] * (k / d) ** 2


def _log_s(s) -> np.ndarray:
    """``log(s·t1)`` on the principal branch, shape (n_s, 1); 0 at s = 0, where it multiplies ``(s·t1)^α`` = 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log(np.where(s != 0, s * SPRINGPOT_TIME, 1.0))[:, None]


def _power_s(s, alpha):
    """``(s·t1)^α`` on the principal branch, shape (n_s, m) (``(iω·t1)^α`` at s = iω)."""
    return np.power((s * SPRINGPOT_TIME)[:, None], np.asarray(alpha, dtype=float))


def _arm(k, c, w):
    """A spring ``k`` (N/m) in series with a dashpot ``c`` (N·s/m): ``k·iωc/(k + iωc)`` and its ∂/∂k, ∂/∂c.

    Shapes: ``k``, ``c`` (m,), ``w`` (n_omega,); results (n_omega, m).
    """
    z = 1j * np.multiply.outer(w, c)
    d = k + z
    return k * z / d, (z / d) ** 2, 1j * w[:, None] * (k / d) ** 2


@dataclass(frozen=True, eq=False)
class Maxwell(_DynamicSpring):
    """Filament turnover: the spring ``EA`` in series with a dashpot ``c``; the prestress held by active contraction.

    ``k*(ω) = T/l + (EA/l)·iωτ/(1 + iωτ)``, ``τ = c·l/EA`` (s).

    The material stiffness ``EA/l`` relaxes through the dashpot (filaments
    turn over and re-form unstretched), while the tension ``T = P·T0`` is held
    by the contractile machinery and keeps the paper's prestress term ``T/l``
    (its ``P·Kp``): in slow deformations the tendon's tension scales with its
    length, ``dT/T = dl/l``, as for the paper's Voigt tendon with ``EA → 0``.
    So:

    * ``k*(ω → 0) = T/l``: the static stiffness is the paper's prestress
      stiffness ``K(0) = P·Kp`` and the static compliance is ``D0(P·Kp)⁻¹b``,
      exactly proportional to 1/P (the static modulus is proportional to P
      and independent of EA and c);
    * ``k*(ω → ∞) = (EA + T)/l``: the Voigt spring of the same EA.

    A tension held exactly constant (``k*(0) = 0``) is not this law: the paper
    cell would then have ``K(0) = P·Σ T0_j ∇²l_j``, whose lowest eigenvalue is
    −0.256·P N/m, i.e. no static state at all.

    Parameters
    ----------
    EA : float or ndarray, shape (m,)
        Axial stiffness of the filament spring (N), > 0.
    c : float or ndarray, shape (m,)
        Turnover dashpot (N·s/m), > 0; ``c → ∞`` is the Voigt spring with ``c = 0``.
    l0 : ndarray, shape (m,), optional
        Rest lengths of the spring (m), Eq. 11.
    """

    EA: Any
    c: Any
    l0: Any = None
    parameters: ClassVar = (Parameter("EA", "N"), Parameter("c", "N·s/m"))
    mechanism_group: ClassVar = "mechanisms: filament turnover (Maxwell)"
    lumped_terms: ClassVar = ("maxwell",)

    def __post_init__(self):
        self._validate()

    def complex_stiffness(self, l, T, omega) -> np.ndarray:
        """``T/l + (EA/l)·iωc/(EA/l + iωc)`` (N/m), shape (n_omega, m)."""
        l, T = self._check(l, T)
        w = angular_frequencies(omega)
        return T / l + _arm(self.EA / l, np.broadcast_to(self.c, l.shape), w)[0]

    def laplace_stiffness(self, l, T, s) -> np.ndarray:
        """``T/l + (EA/l)·sc/(EA/l + sc)`` (N/m) at Laplace variables ``s`` (1/s), shape (n_s, m)."""
        l, T = self._check(l, T)
        return T / l + _arm_s(self.EA / l, np.broadcast_to(self.c, l.shape), laplace_variables(s))

    def complex_stiffness_derivatives(self, l, T, omega):
        """``∂k*/∂T = 1/l``; ``∂k*/∂EA = (1/l)·z²/(EA/l + z)²``, ``∂k*/∂c = iω(EA/l)²/(EA/l + z)²``, ``z = iωc``."""
        l, T = self._check(l, T)
        w = angular_frequencies(omega)
        _, dk, dc = _arm(self.EA / l, np.broadcast_to(self.c, l.shape), w)
        dT = np.broadcast_to((1.0 / l).astype(complex), (w.size, l.size)).copy()
        return dT, np.stack([dk / l, dc])

    def laplace_stiffness_derivatives(self, l, T, s):
        """:meth:`complex_stiffness_derivatives` at Laplace variables ``s`` (``z = sc``)."""
        l, T = self._check(l, T)
        z = laplace_variables(s)
        dk, dc = _arm_s_derivatives(self.EA / l, np.broadcast_to(self.c, l.shape), z)
        dT = np.broadcast_to((1.0 / l).astype(complex), (z.size, l.size)).copy()
        return dT, np.stack([dk / l, dc])

    def realization(self, l, T, band_hz=None, tol: float = DEFAULT_REALIZATION_TOL) -> Realization:
        """Exact: the spring ``T/l`` in parallel with one arm ``(EA/l, c)`` per tendon (``band_hz``, ``tol`` unused)."""
        l, T = self._check(l, T)
        return _one_arm_per_tendon(T / l, 0.0, self.EA / l, self.c)


@dataclass(frozen=True, eq=False)
class StandardLinearSolid(_DynamicSpring):
    """Zener tendon: the spring ``EA`` in parallel with a Maxwell arm (spring ``EA_arm``, dashpot ``c``).

    ``k*(ω) = (EA + T)/l + (EA_arm/l)·iωτ/(1 + iωτ)``, ``τ = c·l/EA_arm`` (s).

    The spring ``EA`` carries the prestress (rest lengths of Eq. 11); the arm
    is relaxed at the reference (no static tension, unstretched). Limits:
    ``k*(0) = (EA + T)/l`` (the Voigt spring, c = 0), ``k*(∞) = (EA + EA_arm + T)/l``;
    ``c → ∞`` is the Voigt spring ``EA + EA_arm`` with no damping and
    ``EA_arm → ∞`` at fixed ``c`` is the Voigt tendon ``(EA, c)``.

    Parameters
    ----------
    EA : float or ndarray, shape (m,)
        Stiffness of the parallel spring (N), > 0.
    EA_arm : float or ndarray, shape (m,)
        Stiffness of the arm's spring (N), > 0.
    c : float or ndarray, shape (m,)
        The arm's dashpot (N·s/m), > 0.
    l0 : ndarray, shape (m,), optional
        Rest lengths of the parallel spring (m).
    """

    EA: Any
    EA_arm: Any
    c: Any
    l0: Any = None
    parameters: ClassVar = (Parameter("EA", "N"), Parameter("EA_arm", "N"), Parameter("c", "N·s/m"))
    mechanism_group: ClassVar = "mechanisms: standard linear solid"
    lumped_terms: ClassVar = ("E0", "maxwell")

    def __post_init__(self):
        self._validate()

    def complex_stiffness(self, l, T, omega) -> np.ndarray:
        """``(EA + T)/l + (EA_arm/l)·iωc/(EA_arm/l + iωc)`` (N/m), shape (n_omega, m)."""
        l, T = self._check(l, T)
        w = angular_frequencies(omega)
        return self._spring_tangent(l, T) + _arm(self.EA_arm / l, np.broadcast_to(self.c, l.shape), w)[0]

    def laplace_stiffness(self, l, T, s) -> np.ndarray:
        """``(EA + T)/l + (EA_arm/l)·sc/(EA_arm/l + sc)`` (N/m) at Laplace variables ``s`` (1/s), shape (n_s, m)."""
        l, T = self._check(l, T)
        return self._spring_tangent(l, T) + _arm_s(self.EA_arm / l, np.broadcast_to(self.c, l.shape),
                                                   laplace_variables(s))

    def complex_stiffness_derivatives(self, l, T, omega):
        """``∂k*/∂T = ∂k*/∂EA = 1/l``; the arm's ``∂/∂EA_arm``, ``∂/∂c`` as for :class:`Maxwell`."""
        l, T = self._check(l, T)
        w = angular_frequencies(omega)
        _, dk, dc = _arm(self.EA_arm / l, np.broadcast_to(self.c, l.shape), w)
        inv = np.broadcast_to((1.0 / l).astype(complex), (w.size, l.size)).copy()
        return inv, np.stack([inv, dk / l, dc])

    def laplace_stiffness_derivatives(self, l, T, s):
        """:meth:`complex_stiffness_derivatives` at Laplace variables ``s``."""
        l, T = self._check(l, T)
        z = laplace_variables(s)
        dk, dc = _arm_s_derivatives(self.EA_arm / l, np.broadcast_to(self.c, l.shape), z)
        inv = np.broadcast_to((1.0 / l).astype(complex), (z.size, l.size)).copy()
        return inv, np.stack([inv, dk / l, dc])

    def realization(self, l, T, band_hz=None, tol: float = DEFAULT_REALIZATION_TOL) -> Realization:
        """Exact: the spring ``(EA + T)/l`` in parallel with one arm ``(EA_arm/l, c)`` per tendon."""
        l, T = self._check(l, T)
        return _one_arm_per_tendon(self._spring_tangent(l, T), 0.0, self.EA_arm / l, self.c)


@dataclass(frozen=True, eq=False)
class Springpot(_DynamicSpring):
    """The spring ``EA`` in parallel with a fractional element (springpot) of exponent α.

    ``k*(ω) = (EA + T)/l + (kappa/l)·(iω·t1)^α``, ``t1 = 1 s`` (:data:`SPRINGPOT_TIME`), 0 < α ≤ 1.

    The springpot's stress is the α-th derivative of its strain (Scott Blair);
    its relaxation modulus is a power law ``∝ t^(−α)``, its storage and loss
    parts rise as ω^α with the constant loss tangent ``tan(απ/2)``. ``kappa``
    is its axial modulus (N, like EA) at ω = 1 rad/s, so both scale as force
    and the strut-length scaling ``(EA, kappa, L) → (λ²EA, λ²kappa, λL)`` is
    exact; the time scaling ``f → f/λ`` is ``kappa → λ^α·kappa``. α = 1 is the
    Voigt tendon with ``c = kappa·t1/l``; α → 0 adds the spring ``kappa``.

    Parameters
    ----------
    EA : float or ndarray, shape (m,)
        Axial stiffness of the spring (N), > 0; it carries the prestress (Eq. 11).
    kappa : float or ndarray, shape (m,)
        The springpot's modulus at ω = 1 rad/s (N), ≥ 0.
    alpha : float or ndarray, shape (m,)
        Exponent (dimensionless), 0 < α ≤ 1.
    l0 : ndarray, shape (m,), optional
        Rest lengths of the spring (m).
    """

    EA: Any
    kappa: Any
    alpha: Any = 0.2
    l0: Any = None
    parameters: ClassVar = (Parameter("EA", "N"), Parameter("kappa", "N", True), Parameter("alpha", ""))
    mechanism_group: ClassVar = "mechanisms: fractional tendons"
    lumped_terms: ClassVar = ("E0", "springpot")

    def __post_init__(self):
        self._validate()
        if np.any(np.asarray(self.alpha) > 1.0):
            raise ValueError(f"alpha (springpot exponent) must be in (0, 1] (dimensionless), got {self.alpha!r}")

    @staticmethod
    def _power(w, alpha):
        """``(iω·t1)^α``, shape (n_omega, m), 0 at ω = 0."""
        a = np.asarray(alpha, dtype=float)
        mag = (w * SPRINGPOT_TIME)[:, None] ** a
        return mag * np.exp(0.5j * np.pi * a)

    def complex_stiffness(self, l, T, omega) -> np.ndarray:
        """``(EA + T)/l + (kappa/l)·(iω·t1)^α`` (N/m), shape (n_omega, m)."""
        l, T = self._check(l, T)
        w = angular_frequencies(omega)
        return self._spring_tangent(l, T) + (self.kappa / l) * self._power(w, np.broadcast_to(self.alpha, l.shape))

    def laplace_stiffness(self, l, T, s) -> np.ndarray:
        """``(EA + T)/l + (kappa/l)·(s·t1)^α`` (N/m) at Laplace variables ``s`` (1/s), principal branch, shape (n_s, m)."""
        l, T = self._check(l, T)
        return self._spring_tangent(l, T) + (self.kappa / l) * _power_s(laplace_variables(s),
                                                                        np.broadcast_to(self.alpha, l.shape))

    def complex_stiffness_derivatives(self, l, T, omega):
        """``∂k*/∂T = ∂k*/∂EA = 1/l``, ``∂k*/∂kappa = (iω·t1)^α/l``, ``∂k*/∂α = (kappa/l)(iω·t1)^α·log(iω·t1)``."""
        l, T = self._check(l, T)
        w = angular_frequencies(omega)
        pw = self._power(w, np.broadcast_to(self.alpha, l.shape))
        inv = np.broadcast_to((1.0 / l).astype(complex), (w.size, l.size)).copy()
        # at ω = 0, (iω)^α·log(iω) → 0: pw is 0 there, so the product is 0
        return inv, np.stack([inv, pw / l, (self.kappa / l) * pw * _log_iw(w)])

    def laplace_stiffness_derivatives(self, l, T, s):
        """:meth:`complex_stiffness_derivatives` at Laplace variables ``s`` (principal branch of the power and log)."""
        l, T = self._check(l, T)
        z = laplace_variables(s)
        pw = _power_s(z, np.broadcast_to(self.alpha, l.shape))
        inv = np.broadcast_to((1.0 / l).astype(complex), pw.shape).copy()
        return inv, np.stack([inv, pw / l, (self.kappa / l) * pw * _log_s(z)])

    def realization(self, l, T, band_hz=None, tol: float = DEFAULT_REALIZATION_TOL) -> Realization:
        """The spring ``(EA + T)/l`` with the springpot as a Prony series (:func:`springpot_prony`) per exponent.

        Accurate to ``tol`` (relative, in the springpot's part of k*; so at
        least as accurate in k*) over ``band_hz`` (Hz, default the paper's
        10⁻² to 10³ Hz); exact at ω → 0. Outside the band the series is a
        dashpot above it and relaxes below it.
        """
        l, T = self._check(l, T)
        return _springpot_realization(self._spring_tangent(l, T), [(self.kappa / l, self.alpha)], band_hz, tol)



def _log_iw(w) -> np.ndarray:
    """``log(iω·t1)``, shape (n_omega, 1); 0·log 0 is taken as 0 where it multiplies ``(iω·t1)^α`` (ω = 0)."""
    with np.errstate(divide="ignore"):
        return (np.log(np.where(w > 0, w * SPRINGPOT_TIME, 1.0)) + 0.5j * np.pi)[:, None]


@dataclass(frozen=True, eq=False)
class TensionSpringpot(_DynamicSpring):
    """A passive springpot and an active one whose modulus is proportional to the tendon's tension.

    ``k*(ω) = (EA + T)/l + (kappa/l)·(iω·t1)^α + (beta·T/l)·(iω·t1)^α_T``, ``t1 = 1 s``.

    The passive part (``kappa``, α) is the cross-linked network's own power
    law; the active part is the contractile machinery: the more tension a
    tendon carries, the more force-bearing cross-bridges, so its modulus is
    ``beta·T`` (``beta`` dimensionless: the active axial stiffness at ω = 1
    rad/s per unit of tension over length; about l/δ for a tendon of length l
    whose cross-bridges carry force over a distance δ), with its own exponent
    α_T. When α_T < α the tendon's effective exponent falls as its tension
    rises (as measured in airway smooth muscle cells: Stamenović et al., J Appl
    Physiol 96:1600, 2004). Exact identities: ``beta = 0`` is
    :class:`Springpot` ``(EA, kappa, α)``, and α_T = α is :class:`Springpot`
    ``(EA, kappa + beta·T, α)``.

    Scaling: under the strut-length scaling ``(P, EA, kappa, L) → (λ²P,
    λ²EA, λ²kappa, λL)`` beta is unchanged (``beta·T/l`` scales as λ like
    every k*); under the time scaling ``f → f/λ``, ``kappa → λ^α·kappa`` and
    ``beta → λ^α_T·beta``.

    Parameters
    ----------
    EA : float or ndarray, shape (m,)
        Axial stiffness of the spring (N), > 0; it carries the prestress (Eq. 11).
    kappa : float or ndarray, shape (m,)
        The passive springpot's modulus at ω = 1 rad/s (N), ≥ 0.
    alpha : float or ndarray, shape (m,)
        The passive exponent (dimensionless), 0 < α ≤ 1.
    beta : float or ndarray, shape (m,)
        The active springpot's modulus at ω = 1 rad/s per unit tension (dimensionless), ≥ 0.
    alpha_T : float or ndarray, shape (m,)
        The active exponent (dimensionless), 0 < α_T ≤ 1.
    l0 : ndarray, shape (m,), optional
        Rest lengths of the spring (m).
    """

    EA: Any
    kappa: Any
    alpha: Any
    beta: Any
    alpha_T: Any
    l0: Any = None
    parameters: ClassVar = (Parameter("EA", "N"), Parameter("kappa", "N", True), Parameter("alpha", ""),
                            Parameter("beta", "", True), Parameter("alpha_T", ""))
    mechanism_group: ClassVar = "mechanisms: fractional tendons"
    lumped_terms: ClassVar = ("E0", "springpot", "springpot_P")

    def __post_init__(self):
        self._validate()
        for name in ("alpha", "alpha_T"):
            if np.any(np.asarray(getattr(self, name)) > 1.0):
                raise ValueError(f"{name} (springpot exponent) must be in (0, 1] (dimensionless), "
                                 f"got {getattr(self, name)!r}")

    def _powers(self, l, w):
        return (Springpot._power(w, np.broadcast_to(self.alpha, l.shape)),
                Springpot._power(w, np.broadcast_to(self.alpha_T, l.shape)))

    def complex_stiffness(self, l, T, omega) -> np.ndarray:
        """``(EA + T)/l + (kappa/l)·(iω·t1)^α + (beta·T/l)·(iω·t1)^α_T`` (N/m), shape (n_omega, m)."""
        l, T = self._check(l, T)
        w = angular_frequencies(omega)
        pw, pw_T = self._powers(l, w)
        return self._spring_tangent(l, T) + (self.kappa / l) * pw + (self.beta * T / l) * pw_T

    def laplace_stiffness(self, l, T, s) -> np.ndarray:
        """``(EA + T)/l + (kappa/l)·(s·t1)^α + (beta·T/l)·(s·t1)^α_T`` (N/m) at Laplace variables ``s`` (1/s)."""
        l, T = self._check(l, T)
        z = laplace_variables(s)
        return (self._spring_tangent(l, T) + (self.kappa / l) * _power_s(z, np.broadcast_to(self.alpha, l.shape))
                + (self.beta * T / l) * _power_s(z, np.broadcast_to(self.alpha_T, l.shape)))

    def complex_stiffness_derivatives(self, l, T, omega):
        """``∂k*/∂T = (1 + beta·(iω·t1)^α_T)/l``; by EA, kappa, α, beta, α_T in turn: ``1/l``, ``(iω·t1)^α/l``,
        ``(kappa/l)(iω·t1)^α·log(iω·t1)``, ``(T/l)(iω·t1)^α_T``, ``(beta·T/l)(iω·t1)^α_T·log(iω·t1)``."""
        l, T = self._check(l, T)
        w = angular_frequencies(omega)
        pw, pw_T = self._powers(l, w)
        log_iw = _log_iw(w)
        inv = np.broadcast_to((1.0 / l).astype(complex), pw.shape).copy()
        active = (self.beta * T / l) * pw_T
        dT = inv + (np.broadcast_to(self.beta, l.shape) / l) * pw_T
        return dT, np.stack([inv, pw / l, (self.kappa / l) * pw * log_iw, (T / l) * pw_T, active * log_iw])

    def laplace_stiffness_derivatives(self, l, T, s):
        """:meth:`complex_stiffness_derivatives` at Laplace variables ``s`` (principal branch)."""
        l, T = self._check(l, T)
        z = laplace_variables(s)
        pw, pw_T = (_power_s(z, np.broadcast_to(self.alpha, l.shape)),
                    _power_s(z, np.broadcast_to(self.alpha_T, l.shape)))
        log_s = _log_s(z)
        inv = np.broadcast_to((1.0 / l).astype(complex), pw.shape).copy()
        active = (self.beta * T / l) * pw_T
        dT = inv + (np.broadcast_to(self.beta, l.shape) / l) * pw_T
        return dT, np.stack([inv, pw / l, (self.kappa / l) * pw * log_s, (T / l) * pw_T, active * log_s])

    def realization(self, l, T, band_hz=None, tol: float = DEFAULT_REALIZATION_TOL) -> Realization:
        """The spring ``(EA + T)/l`` with both springpots as Prony series (:func:`springpot_prony`), as for :class:`Springpot`."""
        l, T = self._check(l, T)
        return _springpot_realization(self._spring_tangent(l, T),
                                      [(self.kappa / l, self.alpha), (self.beta * T / l, self.alpha_T)], band_hz, tol)

def _springpot_realization(k, terms, band_hz, tol) -> Realization:
    """The spring ``k`` (N/m, per tendon) in parallel with springpots ``(coef_j/l_j)·(iω·t1)^α_j`` as Prony series.

    ``terms``: (coefficient over length (N/m), exponent) pairs, each a scalar or an (m,) array; every
    (term, exponent) pair gets the arms of :func:`springpot_prony` scaled by its coefficient. The error is the
    series' largest relative error (so at most that in each springpot part of k*).
    """
    m = k.size
    lo_hi = _band(band_hz)
    c = np.zeros(m)
    tendon, arm_k, arm_c = [], [], []
    err = 0.0
    for coef, alpha in terms:
        coef, alpha = np.broadcast_to(coef, (m,)), np.broadcast_to(alpha, (m,))
        for a in np.unique(alpha):
            js = np.flatnonzero(alpha == a)
            g_d, tau, g, e = springpot_prony(float(a), lo_hi, float(tol))
            err = max(err, e)
            c[js] += g_d * coef[js]
            tendon.append(np.repeat(js, tau.size))
            arm_k.append(np.outer(coef[js], g).ravel())
            arm_c.append(np.outer(coef[js], g * tau).ravel())
    keep = np.concatenate(arm_k) > 0  # tendons with a zero coefficient have no arms
    return Realization(k=k, c=c, tendon=np.concatenate(tendon)[keep], arm_k=np.concatenate(arm_k)[keep],
                       arm_c=np.concatenate(arm_c)[keep], error=err, band_hz=lo_hi)

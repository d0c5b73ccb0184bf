"""Creep and stress relaxation of the linear model, and power-law analysis of time curves.

The linear model ``C0·q' + K0·q = b·F`` (``b = −H0``), ``z = D0·q`` has the
transfer function ``J(s) = D0 (K0 + s·C0)⁻¹ b`` (m/N). With the generalized
eigenvectors of ``C0 v = τ K0 v`` (``vᵀK0v = 1``; τ ≥ 0 in s, τ = 0 for
modes the tendons do not damp)

``J(s) = Σ_k ρ_k / (1 + s·τ_k)``,  ``ρ_k = (D0·v_k)(b·v_k)`` (m/N),

so the **creep compliance**, the displacement per newton after a unit force
step at t = 0, is exact and closed-form:

``J(t) = J_inst + Σ_{τ_k>0} ρ_k (1 − e^{−t/τ_k})``,  ``J_inst = Σ_{τ_k=0} ρ_k``

(``τ_k = 1/λ_k`` and ``ρ_k = r_k/λ_k`` in the notation of
:class:`tenscell.linear.RelaxationSpectrum`; ``J_inst = 0`` when C0 is positive
definite, as for the paper cell with intermediate filaments).

The **relaxation function**, the force after a unit displacement step, is
the inverse Laplace transform of ``1/(s·J(s))``. Its poles are the zeros of
``J(s)``, so

``R(t) = η·δ(t) + k_∞ + Σ_i g_i e^{−t/θ_i}`` (N/m),

with ``k_∞ = 1/J(0)`` (the static stiffness), ``η = 1/Σ_k ρ_k/τ_k``
(N·s/m; an impulse, present when C0 is positive definite: a Voigt network
resists an instantaneous step with an infinite force) and θ_i the
relaxation times of the clamped structure. The relaxation modulus is
``G(t) = (0.5/L)·R(t)`` (Pa), the same continuum factor as ``G' + iG''``.

Both are exact for the linear model. Dense models take τ_k, ρ_k from their
one modal decomposition; sparse models from the Ritz spectrum of their one
Lanczos run (:meth:`tenscell.linear.modal.Pencil.retardation`), converged
until J(t) at every time, J(∞) and the initial creep rate change by less than
``1e-10`` relative (the spectrum's ``error_estimate``); a sparse model is never
made dense. :mod:`tenscell.dynamics` computes the nonlinear creep by simulation.

**Laws without a finite realization** (the springpots of :mod:`tenscell.laws.viscoelastic`) are
realized by a Prony series accurate over a band of frequencies only
(:meth:`tenscell.laws.Springpot.realization`), so a spectrum of the realized model is right only at
times ``1/(2π f)`` inside that band. :func:`creep_compliance` and :func:`relaxation_modulus` therefore
invert the exact transfer function for such models at every requested time (``method="auto"``):
``J(t) = L⁻¹[J(s)/s]`` and ``R(t) = L⁻¹[1/(s·J(s))]`` with ``J(s)`` from the law's exact ``k*(s)``
(:func:`tenscell.linear.dynamic.laplace_compliance`), by the fixed Talbot contour (Abate & Valkó,
Int J Numer Meth Eng 60:979, 2004) with :data:`TALBOT_NODES` nodes, whose error for these
transfer functions (analytic off the negative real axis, as for every passive law) is below about
1e-9 relative. The spectrum of a realized model (:func:`creep_spectrum`, :func:`stress_relaxation`)
warns (:class:`RealizationWarning`) when asked for a time outside its band.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ._checks import positive_array, positive_scalar
from ._errors import TenscellError
from .linear.linearize import LinearModel
from .linear.assembly import continuum_factor
from .linear.spectrum import ZERO_TIME
from ._threads import hot_path

__all__ = [
    "CreepSpectrum",
    "creep_spectrum",
    "creep_compliance",
    "StressRelaxation",
    "stress_relaxation",
    "relaxation_modulus",
    "local_exponent",
    "PowerLawFit",
    "fit_power_law",
    "RealizationWarning",
    "TALBOT_NODES",
    "invert_laplace",
    "realized_times",
]

#: nodes of the fixed Talbot contour of the exact inversions (module docstring)
TALBOT_NODES = 32


class RealizationWarning(TenscellError, UserWarning):
    """A time-domain quantity was asked of a realized spectrum at a time outside the band it was realized over.

    A warning (``warnings.warn``), and a :class:`~tenscell.TenscellError` like every class tenscell defines, so that
    ``warnings.simplefilter("error", RealizationWarning)`` turns it into an error one ``except`` catches.
    """


def realized_times(band_hz) -> tuple[float, float]:
    """The times (s) a realization over ``band_hz`` (Hz) represents: ``1/(2π f_high)`` to ``1/(2π f_low)``."""
    lo, hi = float(band_hz[0]), float(band_hz[1])
    return 1.0 / (2 * math.pi * hi), 1.0 / (2 * math.pi * lo)


def _warn_outside(band_hz, t, what: str) -> None:
    if band_hz is None:
        return
    t = np.asarray(t, dtype=float)
    lo, hi = realized_times(band_hz)
    out = t[(t > 0) & ((t < lo) | (t > hi))]
    if out.size:
        warnings.warn(
            f"{what} at {out.size} time(s) ({out.min():.3g}-{out.max():.3g} s) outside the {lo:.3g}-{hi:.3g} s its "
            f"realization represents ({band_hz[0]:g}-{band_hz[1]:g} Hz): use tenscell.timedomain.creep_compliance / "
            "relaxation_modulus (exact inversion at every time), or realize with a band_hz that covers 1/(2π t)",
            RealizationWarning, stacklevel=3)


def invert_laplace(F, t, nodes: int = TALBOT_NODES) -> np.ndarray:
    """``f(t)`` from its Laplace transform ``F(s)`` by the fixed Talbot contour (Abate & Valkó 2004).

    Parameters
    ----------
    F : callable
        ``F(s)`` for a 1-D complex array ``s`` (1/s), returning an array of the same shape; analytic off the
        negative real axis (every singularity on it), as the transfer functions of passive laws are.
    t : array_like
        Times (s), > 0.
    nodes : int
        Contour nodes M (≥ 8); the error falls like 10^(−0.6 M) until double-precision rounding, amplified by
        ``e^(2M/5)``, takes over (M = 32: about 1e-10 relative for smooth transforms).

    Returns
    -------
    ndarray, shape of ``t``
        Real values of f at the times.
    """
    tt = positive_array("t (time)", t, unit="s")
    shape = np.shape(tt)
    tt = np.atleast_1d(tt).ravel()
    M = int(nodes)
    if M < 8:
        raise ValueError(f"nodes must be an integer >= 8, got {nodes!r}")
    r = 2.0 * M / (5.0 * tt)  # (nt,)
    theta = np.arange(1, M) * (math.pi / M)
    cot = 1.0 / np.tan(theta)
    s = r[:, None] * (theta * (cot + 1j))[None, :]  # (nt, M-1) on the contour, r at theta = 0
    sigma = theta + (theta * cot - 1.0) * cot
    vals = np.asarray(F(np.concatenate([r.astype(complex), s.ravel()])), dtype=complex)
    F0, Fs = vals[: tt.size].real, vals[tt.size:].reshape(s.shape)
    total = 0.5 * F0 * np.exp(r * tt) + np.sum((np.exp(tt[:, None] * s) * Fs * (1.0 + 1j * sigma[None, :])).real,
                                               axis=1)
    return (r / M * total).reshape(shape)


def _approximate(lin) -> bool:
    """Whether the model's time domain would come from a band-limited realization (a springpot's Prony series)."""
    R = getattr(lin, "realization", None)
    return R is not None and R.band_hz is not None


def _method(lin, method: str) -> str:
    if method not in ("auto", "spectrum", "inversion"):
        raise ValueError(f"method must be 'auto', 'spectrum' or 'inversion', got {method!r}")
    if method == "auto":
        return "inversion" if _approximate(lin) else "spectrum"
    if method == "inversion" and getattr(lin, "law", None) is None:
        raise ValueError("method='inversion' needs a model built from a tendon law (lin.law is None)")
    return method

_ZERO_TIME = ZERO_TIME  # τ below this fraction of the longest retardation time counts as instantaneous


def _times(t) -> np.ndarray:
    return positive_array("t (time)", t, unit="s", allow_zero=True)


def _plot_times(times: np.ndarray, n: int = 200) -> np.ndarray:
    """Log-spaced times (s) from a hundredth of the shortest to a hundred times the longest mode time."""
    t = times[np.isfinite(times) & (times > 0)]
    lo, hi = (float(t.min()), float(t.max())) if t.size else (1e-1, 1e1)
    return np.logspace(np.log10(lo) - 2, np.log10(hi) + 2, n)


@dataclass(frozen=True, eq=False, repr=False)
class CreepSpectrum:
    """Discrete retardation spectrum of the linear model's creep compliance.

    ``J(t) = instantaneous + Σ_k weights_k (1 − e^{−t/times_k})`` (m/N).

    Attributes
    ----------
    times : ndarray, shape (k,)
        Retardation times τ_k (s), ascending, all > 0 (``1/λ_k`` of the
        relaxation rates ``K0 v = λ C0 v``).
    weights : ndarray, shape (k,)
        Compliance weights ρ_k (m/N); non-negative when probe and load
        coincide (as in the paper cell), zero for modes the load does not
        excite.
    instantaneous : float
        Compliance of the undamped modes, ``J(0+)`` (m/N); 0 when C0 is
        positive definite.
    L : float
        Strut length (m), for the continuum factor: compliance in 1/Pa is
        ``J(t)·2L``.
    error_estimate : float
        Relative accuracy of ``J(t)`` (0 for dense models, whose spectrum is
        exact; for sparse ones the Lanczos run's convergence measure).
    band_hz : tuple of float or None
        For a model realized over a band (a springpot's Prony series), that
        band (Hz): ``J(t)`` is right only for times ``1/(2π f)`` inside it, and
        :meth:`compliance` warns (:class:`RealizationWarning`) outside. None when exact.
    """

    times: np.ndarray
    weights: np.ndarray
    instantaneous: float
    L: float
    error_estimate: float = 0.0
    band_hz: tuple | None = None

    @property
    def static(self) -> float:
        """Long-time (static) compliance ``J(∞) = J_inst + Σ ρ_k`` (m/N)."""
        return float(self.instantaneous + self.weights.sum())

    def significant(self, rtol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
        """``(times, weights)`` of the distinct retardation times the load excites, ``|ρ| > rtol·Σ|ρ|``.

        Modes of one repeated time (a degenerate eigenspace: the paper cell's threefold symmetry gives pairs) are
        merged first, their weights added: how a degenerate eigenspace's weight splits between the eigenvectors
        LAPACK returns is arbitrary (it changes with the CPU's kernels), its sum is not.
        """
        rates, weights = _merge_modes(1.0 / self.times, self.weights)
        keep = np.abs(weights) > rtol * max(np.abs(weights).sum(), 1e-300)
        return 1.0 / rates[keep][::-1], weights[keep][::-1]  # shortest time first

    def compliance(self, t) -> np.ndarray:
        """Creep compliance ``J(t)`` (m/N) at times ``t`` (s, ≥ 0); ``J(0) = J_inst``."""
        t = _times(t)
        _warn_outside(self.band_hz, t, "creep compliance of a realized spectrum")
        x = np.multiply.outer(t, 1.0 / self.times)
        return self.instantaneous + (-np.expm1(-x)) @ self.weights

    def rate(self, t) -> np.ndarray:
        """Creep rate ``dJ/dt`` (m/(N·s)) at times ``t`` (s)."""
        t = _times(t)
        return np.exp(-np.multiply.outer(t, 1.0 / self.times)) @ (self.weights / self.times)

    def exponent(self, t) -> np.ndarray:
        """Local power-law exponent ``d ln J/d ln t = t·J'(t)/J(t)`` (dimensionless), t > 0 (s)."""
        t = positive_array("t (time)", t, unit="s")
        return t * self.rate(t) / self.compliance(t)

    def transfer(self, s) -> np.ndarray:
        """``J(s) = J_inst + Σ ρ_k/(1 + s·τ_k)`` (m/N) at complex Laplace variables ``s`` (1/s)."""
        s = np.asarray(s, dtype=complex)
        return self.instantaneous + (1.0 / (1.0 + np.multiply.outer(s, self.times))) @ self.weights

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from ._results import format_repr, span

        excited = self.significant()[0].size
        return format_repr(
            f"CreepSpectrum: {self.times.size} retardation modes ({excited} excited by the load)",
            f"times τ {span(self.times, 's')}",
            f"J(0+) = {self.instantaneous:.6g} m/N, J(∞) = {self.static:.6g} m/N; L = {self.L:.4g} m",
        )

    def to_dataframe(self):
        """One row per mode: ``retardation_time_s, weight_m_per_N``; ``attrs`` hold J(0+), J(∞) and L."""
        from ._results import dataframe

        return dataframe({"retardation_time_s": self.times, "weight_m_per_N": self.weights},
                         {"instantaneous_m_per_N": self.instantaneous, "static_m_per_N": self.static, "L_m": self.L})

    def plot(self, ax=None, t=None, **kw):
        """Creep compliance J(t) (m/N) on log-log axes; ``t`` (s) defaults to span the retardation times."""
        from ._results import plotter

        loglog_curve = plotter("loglog_curve")

        t = _plot_times(self.times) if t is None else positive_array("t (time)", t, unit="s")
        return loglog_curve(t, self.compliance(t), ax=ax, xlabel="time after the step t (s)",
                            ylabel="creep compliance J(t) (m/N)", **kw)


@hot_path
def creep_spectrum(lin: LinearModel) -> CreepSpectrum:
    """Retardation times and weights of the linear model (works for singular C0 too).

    The symmetric-definite pencil ``C0 v = τ K0 v`` through the model's
    pencil (:meth:`tenscell.linear.modal.Pencil.retardation`): dense models
    from their one modal decomposition, sparse ones from the Ritz spectrum of
    their Lanczos run (the modes the load excites).

    Parameters
    ----------
    lin : LinearModel

    Returns
    -------
    CreepSpectrum
    """
    tau, rho, err = lin.pencil.retardation()
    inst = tau <= _ZERO_TIME * max(tau.max() if tau.size else 0.0, 1e-300)
    order = np.argsort(tau[~inst])
    return CreepSpectrum(
        times=tau[~inst][order], weights=rho[~inst][order], instantaneous=float(rho[inst].sum()), L=lin.L,
        error_estimate=float(err), band_hz=lin.realization.band_hz if _approximate(lin) else None,
    )


def creep_compliance(lin: LinearModel, t, *, continuum: bool = False, method: str = "auto") -> np.ndarray:
    """Creep compliance of the linear model: displacement per unit force step.

    Parameters
    ----------
    lin : LinearModel
    t : float or array_like
        Times after the step (s), ≥ 0.
    continuum : bool
        Return ``J(t)·2L`` in 1/Pa (the continuum factor of ``G = (0.5/L)/J``)
        instead of m/N.
    method : {"auto", "spectrum", "inversion"}
        ``"spectrum"``: from the retardation spectrum (:func:`creep_spectrum`; exact
        unless the law is realized over a band, then right only inside it).
        ``"inversion"``: the exact ``J(s)/s`` of the law inverted at each time
        (:func:`invert_laplace`; ``J(0) = 0`` is taken as the instantaneous compliance's
        limit, which is 0 unless some mode is undamped). ``"auto"`` (default): the
        inversion for a band-limited realization (springpot tendons), the spectrum otherwise.

    Returns
    -------
    ndarray, same shape as ``t``
        ``J(t)`` in m/N (or 1/Pa).
    """
    if _method(lin, method) == "spectrum":
        spec = creep_spectrum(lin)
        J = spec.compliance(t)
    else:
        from .linear.dynamic import laplace_compliance

        tt = _times(t)
        J = np.zeros(np.shape(tt))
        pos = tt > 0
        J[pos] = invert_laplace(lambda s: laplace_compliance(lin, s) / s, tt[pos])
        if np.any(~pos):  # J(0+) = lim s J(s)/s as s → ∞: the undamped modes' compliance
            J[~pos] = creep_spectrum(lin).instantaneous
    return J / continuum_factor(lin.L) if continuum else J


@dataclass(frozen=True, eq=False, repr=False)
class StressRelaxation:
    """Force response to a unit displacement step of the probe (linear model).

    ``R(t) = impulse·δ(t) + equilibrium + Σ_i weights_i e^{−t/times_i}`` (N/m);
    the relaxation modulus is ``G(t) = (0.5/L)·R(t)`` (Pa).

    Attributes
    ----------
    times : ndarray, shape (k,)
        Relaxation times θ_i of the clamped structure (s), ascending.
    weights : ndarray, shape (k,)
        Stiffness weights g_i (N/m).
    equilibrium : float
        Static stiffness ``k_∞ = 1/J(0)`` (N/m).
    impulse : float
        Coefficient η of the impulse at t = 0 (N·s/m): ``1/Σ_k ρ_k/τ_k`` when
        C0 is positive definite, otherwise 0.
    L : float
        Strut length (m).
    error_estimate : float
        Relative accuracy of the retardation spectrum it was computed from
        (0 for dense models; see :class:`CreepSpectrum`).
    band_hz : tuple of float or None
        The band (Hz) of a band-limited realization (see :class:`CreepSpectrum`); None when exact.
    """

    times: np.ndarray
    weights: np.ndarray
    equilibrium: float
    impulse: float
    L: float
    error_estimate: float = 0.0
    band_hz: tuple | None = None

    @property
    def initial(self) -> float:
        """``R(0+) = k_∞ + Σ g_i`` (N/m), the regular part just after the step."""
        return float(self.equilibrium + self.weights.sum())

    def force(self, t) -> np.ndarray:
        """Regular part of ``R(t)`` (N/m) at times ``t`` (s, ≥ 0); the impulse is in :attr:`impulse`."""
        t = _times(t)
        _warn_outside(self.band_hz, t, "relaxation of a realized spectrum")
        return self.equilibrium + np.exp(-np.multiply.outer(t, 1.0 / self.times)) @ self.weights

    def modulus(self, t) -> np.ndarray:
        """Relaxation modulus ``G(t) = (0.5/L)·R(t)`` (Pa), regular part, t ≥ 0 (s)."""
        return continuum_factor(self.L) * self.force(t)

    @property
    def viscosity(self) -> float:
        """``(0.5/L)·η`` (Pa·s): equals ``lim G''/ω`` at high frequency."""
        return continuum_factor(self.L) * self.impulse

    def laplace(self, s) -> np.ndarray:
        """``R(s) = η + k_∞/s + Σ g_i θ_i/(1 + s θ_i)`` (N·s/m) at complex ``s`` (1/s); equals ``1/(s·J(s))``."""
        s = np.asarray(s, dtype=complex)
        return (self.impulse + self.equilibrium / s
                + (1.0 / (1.0 + np.multiply.outer(s, self.times))) @ (self.weights * self.times))

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from ._results import format_repr, span

        return format_repr(
            f"StressRelaxation: {self.times.size} relaxation modes",
            f"times θ {span(self.times, 's')}",
            f"R(0+) = {self.initial:.6g} N/m, R(∞) = {self.equilibrium:.6g} N/m, impulse η = {self.impulse:.6g} "
            f"N·s/m; L = {self.L:.4g} m",
        )

    def to_dataframe(self):
        """One row per mode: ``relaxation_time_s, weight_N_per_m``; ``attrs`` hold k_∞, η and L."""
        from ._results import dataframe

        return dataframe({"relaxation_time_s": self.times, "weight_N_per_m": self.weights},
                         {"equilibrium_N_per_m": self.equilibrium, "impulse_Ns_per_m": self.impulse, "L_m": self.L})

    def plot(self, ax=None, t=None, **kw):
        """Relaxation modulus G(t) (Pa, regular part) on log-log axes; ``t`` (s) defaults to span the mode times."""
        from ._results import plotter

        loglog_curve = plotter("loglog_curve")

        t = _plot_times(self.times) if t is None else positive_array("t (time)", t, unit="s")
        return loglog_curve(t, self.modulus(t), ax=ax, xlabel="time after the step t (s)",
                            ylabel="relaxation modulus G(t) (Pa)", **kw)


def _merge_modes(lam: np.ndarray, r: np.ndarray, rtol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """Drop unexcited modes and merge repeated rates (their residues add)."""
    keep = np.abs(r) > 1e-12 * np.abs(r).sum()
    lam, r = lam[keep], r[keep]
    order = np.argsort(lam)
    lam, r = lam[order], r[order]
    out_l: list[float] = []
    out_r: list[float] = []
    for lk, rk in zip(lam, r):
        if out_l and lk - out_l[-1] <= rtol * lk:
            out_r[-1] += rk
        else:
            out_l.append(lk)
            out_r.append(rk)
    return np.array(out_l), np.array(out_r)


@hot_path
def stress_relaxation(lin: LinearModel) -> StressRelaxation:
    """Relaxation function of the linear model from the zeros of ``J(s)``.

    The zeros are the finite eigenvalues of the bordered pencil
    ``[[sI + Λ, w], [pᵀ, −J_inst]]`` (``p_k w_k = r_k``), polished by Newton
    steps on ``J(s)``; the weights are the residues of ``1/(s·J(s))``.

    Parameters
    ----------
    lin : LinearModel

    Returns
    -------
    StressRelaxation

    Raises
    ------
    ValueError
        If ``J(s)`` has complex zeros (possible only when the probe differs
        from the load), for which a sum of decaying exponentials with real
        weights is not the right form.
    """
    spec = creep_spectrum(lin)
    lam, r = _merge_modes(1.0 / spec.times, spec.weights / spec.times)
    Jinst = spec.instantaneous
    k = lam.size
    J0 = spec.static
    if k == 0:  # purely elastic response
        return StressRelaxation(times=np.zeros(0), weights=np.zeros(0), equilibrium=1.0 / J0, impulse=0.0, L=spec.L,
                                error_estimate=spec.error_estimate, band_hz=spec.band_hz)
    p = np.sign(r) * np.sqrt(np.abs(r))
    w = np.sqrt(np.abs(r))
    M = np.zeros((k + 1, k + 1))
    M[:k, :k] = np.diag(lam)
    M[:k, k] = w
    M[k, :k] = p
    M[k, k] = -Jinst
    B = np.diag(np.r_[np.ones(k), 0.0])
    # (M + s B) x = 0  <=>  M x = s (−B) x
    ev = scipy.linalg.eigvals(M, -B)
    ev = ev[np.isfinite(ev)]
    if ev.size and np.any(np.abs(ev.imag) > 1e-8 * np.abs(ev).max()):
        raise ValueError(
            f"J(s) of {lin.cell.describe()} has complex zeros (the probe is not the load point), "
            "so its relaxation function is not a sum of real decaying exponentials"
        )
    z = np.sort(ev.real)

    def J(s):
        return Jinst + np.sum(r / (s + lam))

    def dJ(s):
        return -np.sum(r / (s + lam) ** 2)

    for i in range(z.size):
        for _ in range(3):
            z[i] -= J(z[i]) / dJ(z[i])
    if np.any(z >= 0):
        raise ValueError(f"J(s) of {lin.cell.describe()} has a zero with non-negative real part: unstable clamped structure")
    g = np.array([1.0 / (zi * dJ(zi)) for zi in z])
    theta = -1.0 / z
    order = np.argsort(theta)
    impulse = 1.0 / r.sum() if Jinst == 0.0 else 0.0
    return StressRelaxation(times=theta[order], weights=g[order], equilibrium=1.0 / J0, impulse=impulse, L=spec.L,
                            error_estimate=spec.error_estimate, band_hz=spec.band_hz)


def relaxation_modulus(lin: LinearModel, t, *, method: str = "auto") -> np.ndarray:
    """Relaxation modulus ``G(t)`` (Pa) of the linear model at times ``t`` (s, > 0 for the inversion).

    The regular part only; the impulse at t = 0 (present when C0 is positive
    definite) has weight :attr:`StressRelaxation.viscosity` (Pa·s).

    ``method`` as for :func:`creep_compliance`: ``"inversion"`` inverts
    ``1/(s·J(s))`` minus the cytoplasm's impulse ``2L·η`` exactly; it needs a
    structure whose own ``1/(s·J(s))`` vanishes as ``s → ∞`` (no tendon acts as
    a dashpot at high frequency: every springpot exponent below 1), and says so otherwise.
    """
    if _method(lin, method) == "spectrum":
        return stress_relaxation(lin).modulus(t)
    from .linear.dynamic import laplace_compliance

    tt = positive_array("t (time)", t, unit="s")
    impulse = 2.0 * lin.L * lin.viscosity  # N·s/m: the cytoplasm's dashpot on the probe
    s_hi = np.array([1e8, 1e10]) / float(np.min(tt))
    tail = np.abs(1.0 / (s_hi * laplace_compliance(lin, s_hi)) - impulse)
    if tail[1] > 0.3 * tail[0]:  # 1/(sJ) of the structure falls by less than s^-0.05: a dashpot-like tendon
        raise ValueError("the structure acts as a dashpot at high frequency (a tendon's k*(s) grows like s), so its "
                         "relaxation has an impulse the inversion does not separate; use method='spectrum' with a "
                         "realization whose band_hz covers 1/(2π t)")
    R = invert_laplace(lambda s: 1.0 / (s * laplace_compliance(lin, s)) - impulse, tt)
    return continuum_factor(lin.L) * R


def local_exponent(t, y) -> np.ndarray:
    """Local power-law exponent ``d ln y/d ln t`` of sampled data (second-order differences).

    Parameters
    ----------
    t : array_like, shape (k,)
        Increasing times (s), > 0.
    y : array_like, shape (..., k)
        Positive values (e.g. J(t) in m/N).
    """
    t = positive_array("t (time)", t, unit="s")
    y = positive_array("y", y)
    if t.ndim != 1 or t.size < 3 or y.shape[-1] != t.size:
        raise ValueError(f"t must be 1-D with at least 3 points matching y's last axis, got {t.shape} and {y.shape}")
    if np.any(np.diff(t) <= 0):
        raise ValueError("t must be strictly increasing")
    return np.gradient(np.log(y), np.log(t), axis=-1)


@dataclass(frozen=True, repr=False)
class PowerLawFit:
    """Least-squares fit ``J(t) = A·t^α`` in log-log coordinates over a window.

    Attributes
    ----------
    A : float
        Prefactor, ``J`` at t = 1 s (units of J, e.g. m/N).
    alpha : float
        Exponent (dimensionless).
    t_min, t_max : float
        Window (s).
    n : int
        Points used.
    rms_log : float
        Root-mean-square of ``ln J − ln(A t^α)`` over the window (dimensionless).
    max_rel : float
        Largest ``|J/(A t^α) − 1|`` over the window.
    """

    A: float
    alpha: float
    t_min: float
    t_max: float
    n: int
    rms_log: float
    max_rel: float

    def __call__(self, t) -> np.ndarray:
        """``A·t^α`` at times ``t`` (s)."""
        return self.A * np.asarray(t, dtype=float) ** self.alpha

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from ._results import format_repr

        return format_repr(
            f"PowerLawFit: J = A·t^α with α = {self.alpha:.4g}, A = {self.A:.4g} (J's unit at t = 1 s)",
            f"window {self.t_min:.4g} – {self.t_max:.4g} s, {self.n} points; rms log error {self.rms_log:.3g}, "
            f"largest relative error {self.max_rel:.3g}",
        )

    def to_dataframe(self):
        """One row: ``A_unit_of_J, alpha, t_min_s, t_max_s, n, rms_log, max_rel``."""
        from ._results import dataframe

        return dataframe({"A_unit_of_J": [self.A], "alpha": [self.alpha], "t_min_s": [self.t_min],
                          "t_max_s": [self.t_max], "n": [self.n], "rms_log": [self.rms_log],
                          "max_rel": [self.max_rel]})

    def plot(self, ax=None, **kw):
        """The fitted ``A·t^α`` over its window on log-log axes (e.g. over a creep curve's axes)."""
        from ._results import plotter

        loglog_curve = plotter("loglog_curve")

        t = np.logspace(np.log10(self.t_min), np.log10(self.t_max), 50)
        kw.setdefault("label", f"A·t^α, α = {self.alpha:.3f}")
        return loglog_curve(t, self(t), ax=ax, xlabel="time t (s)", ylabel="J(t)", **kw)


def fit_power_law(t, J, t_min: float | None = None, t_max: float | None = None) -> PowerLawFit:
    """Fit ``J = A·t^α`` by linear least squares on ``(ln t, ln J)`` over ``[t_min, t_max]``.

    Parameters
    ----------
    t : array_like, shape (k,)
        Times (s), > 0.
    J : array_like, shape (k,)
        Positive values (m/N or 1/Pa).
    t_min, t_max : float, optional
        Window (s); defaults to the whole range.

    Raises
    ------
    ValueError
        For fewer than 2 points in the window, or non-positive data.
    """
    t = positive_array("t (time)", t, unit="s")
    J = positive_array("J", J)
    if t.shape != J.shape or t.ndim != 1:
        raise ValueError(f"t and J must be 1-D of equal length, got {t.shape} and {J.shape}")
    lo = float(t.min()) if t_min is None else positive_scalar("t_min", t_min, "s")
    hi = float(t.max()) if t_max is None else positive_scalar("t_max", t_max, "s")
    if hi <= lo:
        raise ValueError(f"the fit window must have t_min < t_max, got [{lo!r}, {hi!r}] s")
    sel = (t >= lo) & (t <= hi)
    if sel.sum() < 2:
        raise ValueError(f"the fit window [{lo:g}, {hi:g}] s contains {int(sel.sum())} point(s); need at least 2")
    x, y = np.log(t[sel]), np.log(J[sel])
    alpha, lnA = np.polyfit(x, y, 1)
    res = y - (lnA + alpha * x)
    return PowerLawFit(
        A=float(np.exp(lnA)), alpha=float(alpha), t_min=lo, t_max=hi, n=int(sel.sum()),
        rms_log=float(np.sqrt(np.mean(res ** 2))), max_rel=float(np.max(np.abs(np.expm1(res)))),
    )

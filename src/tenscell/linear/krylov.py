"""Large (sparse) linear models from one factorization: a shifted Lanczos run, extended on demand.

For a model with tens of thousands of coordinates neither a factorization per
frequency nor a dense eigensolve is affordable. Instead, with a real shift
``σ ≥ 0``:

* factor ``Kσ = K0 + σ·C0`` once (sparse Cholesky, :mod:`tenscell.linear.sparse`);
* run the symmetric Lanczos iteration on ``Op = Kσ⁻¹·C0`` in the
  ``Kσ``-inner product, from ``x0 = Kσ⁻¹·b`` (b = −H0 = D0 for the usual
  probe = load), with full reorthogonalization. After ``k`` steps
  ``Vᵀ Kσ V = I`` and ``T = Vᵀ C0 V`` (tridiagonal), and

      J(s) = bᵀ (K0 + s C0)⁻¹ b  ≈  β0² e1ᵀ (I + (s − σ) T)⁻¹ e1,

  the Galerkin projection of the model onto the Krylov space: a model of the
  same kind, exact at s = σ and matching 2k moments there. With the Ritz
  pairs ``T = S diag(θ) Sᵀ`` it is the retardation spectrum

      J(s) ≈ Σ_i ρ_i / (1 + s·τ_i),   τ_i = θ_i/(1 − σθ_i),   ρ_i = β0² S_0i²/(1 − σθ_i),

  a Gauss quadrature of the load's spectral measure, which is how creep,
  relaxation, the relaxation spectrum and the slowest modes of a sparse model
  are computed (:mod:`tenscell.linear.pencil`). ``1 − σθ > 0`` for every Ritz
  value exactly when K0 is positive definite on the Krylov space.
* the run is kept (cached on the model's :class:`~tenscell.linear.pencil.Pencil`)
  and extended only when a later request needs more accuracy, so every
  frequency, time and mode uses the same factorization and the same steps.

Compliance accuracy: with ``M(s) = I + (s−σ)Op`` and the residual ``r`` of
the Galerkin solution, the error of J is exactly ``⟨M⁻¹r, r⟩`` (quadratic in
the residual, ``‖r‖ = |s−σ|·β_k·|e_kᵀ y(s)|·β0``); it is estimated with
``‖M⁻¹‖`` taken from the Ritz values.

The shift sits inside the band of relaxation rates that the frequencies probe
(:func:`default_shift`; measured on lattices, 3–7 times fewer steps than
σ = 0). ``Kσ·w`` is recomputed by a sparse product at every step rather than
updated by recurrence: with the recurrence, T lost accuracy once Ritz values
converged and J stalled at a relative error of 5·10⁻¹⁰.

When probe ≠ load, ``dᵀ(..)⁻¹b`` follows from two symmetric runs by
polarization: ``¼[(b+d)ᵀ(..)(b+d) − (b−d)ᵀ(..)(b−d)]``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .._checks import positive_array
from .._threads import hot_path
from .spectrum import ritz_is_zero

if TYPE_CHECKING:  # pragma: no cover
    from .linearize import LinearModel

__all__ = ["KrylovResponse", "LanczosRun", "CreepChange", "converge", "krylov_compliance", "default_shift", "load_modes",
           "DEFAULT_BAND_HZ", "SLOW_PROBE_STEPS", "SLOW_SHIFT_FRACTIONS"]

#: the paper's frequency band (Hz); its default shift serves analyses that have no band of their own
DEFAULT_BAND_HZ = (1e-2, 1e3)
_CHECK_EVERY = 5


@dataclass(frozen=True, eq=False)
class KrylovResponse:
    """Compliance from the shifted Lanczos iteration.

    Attributes
    ----------
    frequency_hz : ndarray, shape (nf,)
        Frequencies (Hz).
    J : ndarray of complex, shape (nf,)
        Compliance ``z/F`` (m/N).
    steps : int
        Lanczos steps (solves with the factor) per symmetric run.
    shift : float
        σ (rad/s).
    error_estimate : float
        Largest estimated relative error of J over the frequencies.
    rates : ndarray
        Relaxation rates of the reduced model (1/s), ascending.
    """

    frequency_hz: np.ndarray
    J: np.ndarray
    steps: int
    shift: float
    error_estimate: float
    rates: np.ndarray
    _factor: Any = field(default=None, repr=False)

    @property
    def fill(self) -> int:
        """Nonzeros of the sparse factor (a diagnostic that costs one more factorization)."""
        return self._factor.fill


def default_shift(f_hz) -> float:
    """The default Lanczos shift σ = 3·sqrt(ω_min·ω_max) (rad/s) for frequencies ``f_hz`` (Hz).

    Measured on 3D lattices of 2·10³ and 3·10⁴ coordinates for f = 10⁻²…10³ Hz:
    σ between 20 and 100 rad/s needs 30–45 steps, σ = 0 needs 135–290.
    """
    w = 2 * math.pi * np.asarray(f_hz, dtype=float)
    return float(3.0 * math.sqrt(w.min() * w.max()))


class LanczosRun:
    """Symmetric Lanczos on ``Kσ⁻¹C0`` in the Kσ-inner product from ``Kσ⁻¹b``, extended on demand.

    Parameters
    ----------
    factor : object with ``solve``
        Factor of ``Kσ = K0 + σC0``.
    Ks, C : sparse matrices, shape (n, n)
        ``Kσ`` and ``C0`` (for products).
    b : ndarray, shape (n,)
        Start (load) vector.
    shift : float
        σ (rad/s).
    max_steps : int
        Most steps the run may take (memory: ``max_steps·n`` floats).
    """

    def __init__(self, factor, Ks, C, b: np.ndarray, shift: float, max_steps: int):
        self.factor, self.Ks, self.C, self.shift = factor, Ks, C, float(shift)
        self.max_steps = int(max_steps)
        n = b.size
        self._alpha: list[float] = []
        self._beta: list[float] = []
        self._V = np.empty((min(self.max_steps, n) + 1, n))
        self.broke_down = False
        x0 = factor.solve(b) if np.any(b) else np.zeros(n)
        self.beta0 = math.sqrt(max(float(x0 @ (Ks @ x0)), 0.0))
        if self.beta0 == 0.0:
            self.broke_down = True
        else:
            self._V[0] = x0 / self.beta0
        self._ritz_at = -1
        self._ritz = (np.zeros(0), np.zeros((0, 0)))

    @property
    def steps(self) -> int:
        """Steps taken (solves with the factor, beyond the first)."""
        return len(self._alpha)

    @property
    def exhausted(self) -> bool:
        """The Krylov space is invariant (exact answer) or the step budget is spent."""
        return self.broke_down or self.steps >= self._V.shape[0] - 1 or self.steps >= self.max_steps

    @property
    def last_beta(self) -> float:
        """β_k, the coupling to the next (not yet taken) Lanczos vector."""
        return self._beta[-1] if self._beta else 0.0

    def extend(self, steps: int) -> None:
        """Take steps until ``steps`` are done, the space is invariant or the budget is spent."""
        V, Ks, C = self._V, self.Ks, self.C
        while self.steps < steps and not self.exhausted:
            j = self.steps
            z = C @ V[j]
            wv = self.factor.solve(z)
            # full reorthogonalization in the Kσ-inner product, twice; Kσ·w is recomputed (not updated
            # by recurrence), which keeps T accurate once Ritz values have converged
            h = V[: j + 1] @ z
            wv -= h @ V[: j + 1]
            Kw = Ks @ wv
            h2 = V[: j + 1] @ Kw
            wv -= h2 @ V[: j + 1]
            Kw = Ks @ wv
            a = float(h[j] + h2[j])
            bj = math.sqrt(max(float(wv @ Kw), 0.0))
            self._alpha.append(a)
            self._beta.append(bj)
            if bj <= 1e-14 * max(abs(a), 1e-300):
                self.broke_down = True
            elif j + 1 < V.shape[0]:
                V[j + 1] = wv / bj

    def ritz(self) -> tuple[np.ndarray, np.ndarray]:
        """Ritz values θ (ascending) and eigenvectors S of the current tridiagonal T."""
        k = self.steps
        if self._ritz_at != k:
            a, b = np.asarray(self._alpha), np.asarray(self._beta[: k - 1])
            self._ritz = np.linalg.eigh(np.diag(a) + np.diag(b, 1) + np.diag(b, -1)) if k else (np.zeros(0), np.zeros((0, 0)))
            self._ritz_at = k
        return self._ritz

    def ritz_vectors(self, columns) -> np.ndarray:
        """Ritz vectors ``V S[:, columns]``, shape (n, len(columns)) (Kσ-orthonormal)."""
        _, S = self.ritz()
        return self._V[: self.steps].T @ S[:, columns]

    def spectrum(self) -> tuple[np.ndarray, np.ndarray]:
        """The reduced model as a retardation spectrum: ``(τ, ρ)`` with ``J(s) ≈ Σ ρ/(1 + sτ)``.

        Raises ``FloatingPointError`` if a Ritz value reaches ``1/σ`` (K0 is not positive definite).
        """
        theta, S = self.ritz()
        mu = self.beta0 ** 2 * S[0] ** 2 if theta.size else np.zeros(0)
        theta = np.clip(theta, 0.0, None)  # Op is positive semidefinite: negative θ are rounding
        gap = 1.0 - self.shift * theta
        if np.any(gap <= 0):
            raise FloatingPointError("a Ritz value reached 1/σ: K0 is not positive definite")
        return theta / gap, mu / gap

    def compliance(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reduced ``J(s)`` (m/N) at complex ``s`` (1/s) and its estimated relative error."""
        theta, S = self.ritz()
        if theta.size == 0:  # nothing computed yet, or a load that excites nothing
            return np.zeros(s.shape, dtype=complex), np.full(s.shape, 0.0 if self.broke_down else np.inf)
        z1 = s - self.shift
        den = 1.0 + np.outer(z1, theta)
        J = self.beta0 ** 2 * ((S[0] ** 2) / den).sum(axis=1)
        if self.broke_down:
            return J, np.zeros(s.shape)
        yk = (S[0] * S[-1] / den).sum(axis=1)
        rho = np.abs(z1 * self.last_beta * yk)  # ‖residual‖/β0 of the shifted system
        # ΔJ = <M⁻¹r, r>: bound it with ‖M⁻¹‖ from the Ritz values
        minv = 1.0 / np.min(np.abs(den), axis=1)
        return J, minv * rho ** 2 * self.beta0 ** 2 / np.maximum(np.abs(J), 1e-300)


def converge(run: LanczosRun, error, tol: float, what: str, max_steps: int | None = None,
             every: int = _CHECK_EVERY) -> float:
    """Extend ``run`` (checking every ``every`` steps) until ``error(run) <= tol``; return the last error.

    Raises ``RuntimeError`` if the run is exhausted (or reaches ``max_steps``) first.
    """
    cap = run.max_steps if max_steps is None else int(max_steps)
    while True:
        err = error(run)
        if err <= tol or run.exhausted or run.steps >= cap:
            break
        run.extend(min(run.steps + every, cap))
    if err > tol and not run.broke_down:
        raise RuntimeError(
            f"the Lanczos iteration did not reach the requested accuracy of the {what} in {run.steps} steps "
            f"(estimated relative error {err:.3g}, wanted {tol:.3g})"
        )
    return err


@hot_path
def krylov_compliance(lin: "LinearModel", f_hz, *, tol: float = 1e-12, shift: float | None = None,
                      max_steps: int | None = None) -> KrylovResponse:
    """Compliance ``J(f)`` (m/N) of a (sparse) linear model by one factorization and a Lanczos run.

    The factorization and the run are cached on ``lin.pencil``: a later call
    (other frequencies, creep, relaxation, modes) continues the same run.

    Parameters
    ----------
    lin : LinearModel
    f_hz : array_like
        Frequencies (Hz), > 0.
    tol : float
        Target relative accuracy of J (dimensionless).
    shift : float, optional
        σ (rad/s); default :func:`default_shift`, or a shift already in use
        on this model within a factor 4 of it.
    max_steps : int, optional
        Cap on Lanczos steps (default ``min(n, 2000)``).

    Returns
    -------
    KrylovResponse

    Raises
    ------
    NotPositiveDefiniteError
        If ``K0 + σC0`` is not positive definite.
    RuntimeError
        If the iteration does not reach ``tol`` within ``max_steps``.
    """
    f = positive_array("frequency", f_hz, unit="Hz")
    shape = f.shape
    w = 2 * math.pi * f.ravel()
    if shift is not None and not (math.isfinite(float(shift)) and float(shift) >= 0):
        raise ValueError(f"shift must be a finite number >= 0 (rad/s), got {shift!r}")
    pencil = lin.pencil
    sigma = pencil.nearby_shift(default_shift(f)) if shift is None else float(shift)
    s = 1j * w
    runs = pencil.lanczos_runs(sigma)
    errs, Js = [], []
    for run in runs:
        # the error estimate is a bound at this step (not a change since an earlier one): checked after every
        # step, as its cost (the small tridiagonal's eigensolve, a product at the frequencies) is a few % of a solve
        converge(run, lambda r: float(r.compliance(s)[1].max()), tol, "compliance", max_steps, every=1)
    for run in runs:
        J_run, e = run.compliance(s)
        Js.append(J_run)
        errs.append(float(e.max()))
    J = Js[0] if len(runs) == 1 else 0.25 * (Js[0] - Js[1])
    tau, _ = runs[0].spectrum()
    with np.errstate(divide="ignore"):
        rates = np.sort(np.where(tau > 0, 1.0 / np.where(tau > 0, tau, 1.0), np.inf))
    return KrylovResponse(frequency_hz=f, J=J.reshape(shape), steps=max(r.steps for r in runs), shift=sigma,
                          error_estimate=max(errs), rates=rates, _factor=pencil.factor(sigma))


#: σ = 0 steps of the load's run that estimate the slowest rate before the shift below it is chosen
SLOW_PROBE_STEPS = 10
#: fractions of that estimate tried, in turn, as the shift λ0 below the slowest rate (the factorization of
#: K0 − λ0·C0 exists exactly when λ0 lies below every rate: a failed one proves the estimate too high)
SLOW_SHIFT_FRACTIONS = (0.9, 0.5, 0.1)


@hot_path
def load_modes(lin: "LinearModel", k: int = 3, tol: float = 1e-6, max_steps: int = 150):
    """The ``k`` slowest relaxation modes that the load excites, for sparse models.

    A Lanczos run from the load on ``(K0 − λ0·C0)⁻¹C0`` with ``λ0`` just below the slowest rate
    (shift-and-invert at σ = −λ0): the slowest rates λ map to ``1/(λ − λ0)``, far above the rest of
    the spectrum, so their Ritz pairs converge in a few dozen solves. ``λ0`` is chosen from the
    model's unshifted run (:data:`SLOW_PROBE_STEPS` steps on the factor of K0 that the
    positive-definiteness check made; its largest Ritz value bounds the slowest excited rate from
    above) as the first of :data:`SLOW_SHIFT_FRACTIONS` of that estimate for which ``K0 − λ0·C0``
    has a Cholesky factor — which proves λ0 below every rate of the model (C0 is positive
    semidefinite). When none has, the unshifted run serves (σ = 0).
    Modes the load does not excite (e.g. the many identical local modes of a lattice's modules
    far from the load) are not found.

    Stops when every relative residual ``‖K0 v − λ C0 v‖/‖K0 v‖`` (Kσ⁻¹-norms; from the Ritz
    residual ``r = C0 v − θ Kσ v`` as ``‖r‖/(θ(1 − σθ))``) is below ``tol`` or after
    ``max_steps``. Each residual bounds, to first order, the relative distance from its rate to a
    rate of the model (the operator is self-adjoint in the Kσ-inner product), so ``tol`` is the
    accuracy of the rates returned. In a lattice the slowest rate is shared by one local mode per
    module, a tight cluster (relative width about 10⁻⁴ on the 10⁴-node block), and the Ritz vectors
    are then combinations of cluster modes: good pictures of the slowest motion, with the residuals
    to say how good.

    Parameters
    ----------
    lin : LinearModel
    k : int
        Number of modes.
    tol : float
        Relative accuracy of the rates (dimensionless).
    max_steps : int
        Most steps of the shifted run.

    Returns
    -------
    rates : ndarray, shape (k,)
        Relaxation rates λ (1/s), ascending.
    vectors : ndarray, shape (n, k)
        The modes in generalized coordinates (Kσ-orthonormal).
    residuals : ndarray, shape (k,)
        Relative Ritz residuals (dimensionless): bounds of the rates' relative errors.

    Raises
    ------
    RuntimeError
        If after ``max_steps`` a residual is still above 10⁻² (no usable mode).
    """
    pencil = lin.pencil
    max_steps = max(min(max_steps, lin.cell.n), k)
    sigma = _slow_shift(pencil, k)
    run = pencil.lanczos_runs(sigma)[0]

    def top_residuals(r: LanczosRun):
        theta, S = r.ritz()
        top = np.argsort(theta)[::-1][:k]
        th = theta[top]
        # ‖C0v − θKσv‖/θ is the residual of K0v − λC0v; divided by ‖K0v‖ ≈ (1 − σθ)‖Kσv‖ it is relative
        return top, r.last_beta * np.abs(S[-1, top]) / np.maximum(th * (1.0 - sigma * th), 1e-300)

    run.extend(k)
    while True:  # a check (an eigensolve of the small tridiagonal) costs far less than a step's solve
        top, resid = top_residuals(run)
        if (top.size == k and np.all(resid < tol)) or run.exhausted or run.steps >= max_steps:
            break
        run.extend(run.steps + 1)
    if top.size < k or np.any(resid > 1e-2):
        raise RuntimeError(
            f"the {k} slowest load-excited modes did not converge in {run.steps} Lanczos steps "
            f"(largest relative residual {resid.max() if resid.size else float('inf'):.2g})"
        )
    theta = run.ritz()[0][top]
    rates = (1.0 - sigma * theta) / theta
    return rates, run.ritz_vectors(top), resid


def _slow_shift(pencil, k: int) -> float:
    """σ = −λ0 with λ0 proven below the model's slowest rate (K0 − λ0·C0 factored), or 0 (see :func:`load_modes`)."""
    from .._errors import NotPositiveDefiniteError

    run = pencil.lanczos_runs(0.0)[0]
    run.extend(max(SLOW_PROBE_STEPS, k))
    theta = run.ritz()[0]
    if theta.size == 0 or not theta.max() > 0:
        return 0.0
    estimate = 1.0 / float(theta.max())  # a Ritz value bounds the largest 1/λ from below: λ_slowest <= this
    for fraction in SLOW_SHIFT_FRACTIONS:
        try:
            pencil.factor(-fraction * estimate)
        except NotPositiveDefiniteError:
            continue
        return -fraction * estimate
    return 0.0


class CreepChange:
    """Relative change of the reduced creep compliance since the previous check (the run's error estimate)."""

    def __init__(self):
        self.prev: tuple[np.ndarray, np.ndarray] | None = None

    def __call__(self, run: LanczosRun) -> float:
        if run.steps == 0:
            return 0.0 if run.broke_down else math.inf
        try:
            tau, rho = run.spectrum()
        except FloatingPointError:
            return 0.0  # reported by Pencil.retardation
        if run.broke_down:
            return 0.0  # the Krylov space is invariant: the reduced model is exact
        prev, self.prev = self.prev, (tau, rho)
        if prev is None:
            return math.inf
        pos = tau[~ritz_is_zero(tau)]
        if pos.size == 0:
            return math.inf
        t = np.logspace(math.log10(pos.min()) - 1, math.log10(pos.max()) + 1, 48)
        now, before = _creep_features(tau, rho, t), _creep_features(*prev, t)
        return float(np.max(np.abs(now - before) / np.maximum(np.abs(now), 1e-300)))


def _creep_features(tau, rho, t):
    """J(t) on the grid, J(∞) and Σ_{τ>0} ρ/τ (the initial creep rate per unit force)."""
    zero = ritz_is_zero(tau)
    tp, rp = tau[~zero], rho[~zero]
    J = rho[zero].sum() + (-np.expm1(-np.multiply.outer(t, 1.0 / tp))) @ rp
    return np.concatenate([J, [rho.sum(), (rp / tp).sum()]])

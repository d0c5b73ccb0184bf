"""Frequency response of large (sparse) linear models from one factorization.

For a model with tens of thousands of coordinates a sparse factorization
per frequency is too slow. Instead, with a real shift ``σ > 0``:

* factor ``Kσ = K0 + σ·C0`` once (symmetric positive definite; nested
  dissection ordering, :mod:`tenscell.linear.sparse`);
* run the symmetric Lanczos iteration on ``Op = Kσ⁻¹·C0`` in the
  ``Kσ``-inner product, from ``x0 = Kσ⁻¹·b`` (b = −H0 = D0 for the usual
  probe = load), with full reorthogonalization. After ``k`` steps
  ``Vᵀ Kσ V = I`` and ``T = Vᵀ C0 V`` (tridiagonal), and

      J(s) = bᵀ (K0 + s C0)⁻¹ b  ≈  β0² e1ᵀ (I + (s − σ) T)⁻¹ e1,   s = iω,

  which is the Galerkin projection of the model onto the Krylov space: a
  model of the same kind (positive relaxation spectrum, rates
  ``λ_i = 1/θ_i − σ`` from the eigenvalues θ_i of T), exact at s = σ and
  matching 2k moments there.
* stop when, at every requested frequency, the estimated relative error of
  J is below ``tol``. With ``M(s) = I + (s−σ)Op`` and the residual ``r`` of
  the Galerkin solution, the error is exactly ``⟨M⁻¹r, r⟩`` (quadratic in
  the residual, ``‖r‖ = |s−σ|·β_k·|e_kᵀ y(s)|·β0``); it is estimated with
  ``‖M⁻¹‖`` taken from the Ritz values.

The shift sits inside the band of relaxation rates that the frequencies
probe (:func:`default_shift`; measured on lattices, 3–7 times fewer steps
than σ = 0). ``Kσ·w`` is recomputed by a sparse product at every step
rather than updated by recurrence: with the recurrence, T lost accuracy
once Ritz values converged and J stalled at a relative error of 5·10⁻¹⁰.

When probe ≠ load, ``dᵀ(..)⁻¹b`` follows from two symmetric runs by
polarization: ``¼[(b+d)ᵀ(..)(b+d) − (b−d)ᵀ(..)(b−d)]``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .._checks import positive_array
from .sparse import NotPositiveDefinite, SymmetricFactor, coordinate_locations, factorize_spd
from .linearize import LinearModel, NotPositiveDefiniteError

__all__ = ["KrylovResponse", "krylov_compliance", "factorize_stiffness", "default_shift", "load_modes"]


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
    fill : int
        Nonzeros of the sparse factor.
    rates : ndarray
        Relaxation rates of the reduced model (1/s), ascending.
    """

    frequency_hz: np.ndarray
    J: np.ndarray
    steps: int
    shift: float
    error_estimate: float
    fill: int
    rates: np.ndarray


def factorize_stiffness(lin: LinearModel, shift: float = 0.0) -> SymmetricFactor:
    """Sparse factor of ``K0 + shift·C0`` (shift in rad/s), proving it positive definite.

    Raises
    ------
    NotPositiveDefiniteError
        If the matrix is not positive definite.
    """
    K = sp.csc_matrix(lin.K0)
    if shift:
        K = (K + shift * sp.csc_matrix(lin.C0)).tocsc()
    try:
        return factorize_spd(K, what="K0" if not shift else f"K0 + {shift:g}·C0", points=coordinate_locations(lin.cell.coords))
    except NotPositiveDefinite as err:
        raise NotPositiveDefiniteError(
            f"K0 is not positive definite for {lin.cell.describe()} at P={lin.P:.6g} "
            f"(a pivot of its LDLᵀ factorization is {err.smallest_pivot:.3g}): the reference is not a stable "
            "equilibrium"
        ) from None


def default_shift(f_hz) -> float:
    """The default Lanczos shift σ = 3·sqrt(ω_min·ω_max) (rad/s) for frequencies ``f_hz`` (Hz).

    Measured on 3D lattices of 2·10³ and 3·10⁴ coordinates for f = 10⁻²…10³ Hz:
    σ between 20 and 100 rad/s needs 30–45 steps, σ = 0 needs 135–290.
    """
    w = 2 * math.pi * np.asarray(f_hz, dtype=float)
    return float(3.0 * math.sqrt(w.min() * w.max()))


def krylov_compliance(lin: LinearModel, f_hz, *, tol: float = 1e-12, shift: float | None = None,
                      max_steps: int | None = None) -> KrylovResponse:
    """Compliance ``J(f)`` (m/N) of a (sparse) linear model by one factorization and a Lanczos run.

    Parameters
    ----------
    lin : LinearModel
    f_hz : array_like
        Frequencies (Hz), > 0.
    tol : float
        Target relative accuracy of J (dimensionless).
    shift : float, optional
        σ (rad/s); default :func:`default_shift`.
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
    sigma = default_shift(f) if shift is None else float(shift)
    if not (math.isfinite(sigma) and sigma >= 0):
        raise ValueError(f"shift must be a finite number >= 0 (rad/s), got {shift!r}")
    n = lin.cell.n
    max_steps = min(n, 2000) if max_steps is None else int(max_steps)
    factor = factorize_stiffness(lin, sigma)
    C = sp.csr_matrix(lin.C0)
    Ks = (sp.csr_matrix(lin.K0) + sigma * C).tocsr()
    b = -np.asarray(lin.H0, dtype=float)
    d = np.asarray(lin.D0, dtype=float)
    s = 1j * w
    if np.allclose(b, d, rtol=0, atol=1e-14 * max(np.abs(b).max(), 1e-300)):
        J, k, res, rates = _lanczos(factor, Ks, C, b, s, sigma, tol, max_steps)
    else:
        Jp, k1, r1, rates = _lanczos(factor, Ks, C, b + d, s, sigma, tol, max_steps)
        Jm, k2, r2, _ = _lanczos(factor, Ks, C, b - d, s, sigma, tol, max_steps)
        J, k, res = 0.25 * (Jp - Jm), max(k1, k2), max(r1, r2)
    return KrylovResponse(frequency_hz=f, J=J.reshape(shape), steps=k, shift=sigma, error_estimate=res,
                          fill=factor.fill, rates=rates)


def _lanczos(factor: SymmetricFactor, Ks, C, b, s, sigma, tol, max_steps):
    """Symmetric Lanczos on Kσ⁻¹C in the Kσ-inner product; returns (J(s), steps, error estimate, rates)."""
    n = b.size
    if not np.any(b):
        return np.zeros(s.shape, dtype=complex), 0, 0.0, np.zeros(0)
    x0 = factor.solve(b)
    beta0 = math.sqrt(max(float(x0 @ (Ks @ x0)), 0.0))
    if beta0 == 0.0:
        return np.zeros(s.shape, dtype=complex), 0, 0.0, np.zeros(0)
    V = np.empty((max_steps + 1, n))
    V[0] = x0 / beta0
    alpha: list[float] = []
    beta: list[float] = []
    z1 = s - sigma
    res = np.inf
    for j in range(max_steps):
        z = C @ V[j]
        wv = factor.solve(z)
        # full reorthogonalization in the Kσ-inner product, twice; Kσ·w is recomputed (not updated
        # by recurrence), which keeps T accurate once Ritz values have converged
        h = V[: j + 1] @ z
        wv -= h @ V[: j + 1]
        Kw = Ks @ wv
        h2 = V[: j + 1] @ Kw
        wv -= h2 @ V[: j + 1]
        Kw = Ks @ wv
        a = float(h[j] + h2[j])
        alpha.append(a)
        bj = math.sqrt(max(float(wv @ Kw), 0.0))
        k = j + 1
        if k % 5 == 0 or k == max_steps or bj <= 1e-14 * abs(a):
            theta, S = np.linalg.eigh(np.diag(alpha) + np.diag(beta, 1) + np.diag(beta, -1))
            den = 1.0 + np.outer(z1, theta)
            J = beta0 ** 2 * ((S[0] ** 2) / den).sum(axis=1)
            yk = (S[0] * S[-1] / den).sum(axis=1)
            rho = np.abs(z1 * bj * yk)  # ‖residual‖/β0 of the shifted system
            # ΔJ = <M⁻¹r, r>: bound it with ‖M⁻¹‖ from the Ritz values
            minv = 1.0 / np.min(np.abs(den), axis=1)
            est = minv * rho ** 2 * beta0 ** 2 / np.abs(J)
            res = float(est.max())
            if res <= tol or bj <= 1e-14 * abs(a):
                with np.errstate(divide="ignore"):
                    rates = np.sort(np.where(theta > 0, 1.0 / np.where(theta > 0, theta, 1.0) - sigma, np.inf))
                return J, k, res, rates
        if k == max_steps:
            break
        beta.append(bj)
        V[j + 1] = wv / bj
    raise RuntimeError(
        f"the Lanczos iteration did not reach the requested accuracy in {max_steps} steps "
        f"(estimated relative error {res:.3g}, wanted {tol:.3g})"
    )


def load_modes(lin: LinearModel, k: int = 3, tol: float = 1e-6, max_steps: int = 150):
    """The ``k`` slowest relaxation modes that the load excites, for sparse models.

    Lanczos on ``K0⁻¹C0`` (K0-inner product) from ``K0⁻¹b``: its Ritz pairs with the largest
    θ = 1/λ converge first, so a few dozen solves with one factor of K0 give the slowest modes in
    the Krylov space of the load. Modes the load does not excite (e.g. the many identical local
    modes of a lattice's modules far from the load) are not found.

    Stops when every Ritz residual ``‖C0 v − θ K0 v‖/θ`` (K0⁻¹-norm) is below ``tol`` or after
    ``max_steps``; in a lattice the slowest rate is shared by one local mode per module, a tight
    cluster whose members keep appearing, and the Ritz vectors returned are then combinations of
    cluster modes: good pictures of the slowest motion, with the residuals to say how good.

    Returns
    -------
    rates : ndarray, shape (k,)
        Relaxation rates λ (1/s), ascending.
    vectors : ndarray, shape (n, k)
        The modes in generalized coordinates (K0-orthonormal).
    residuals : ndarray, shape (k,)
        Relative Ritz residuals (dimensionless).

    Raises
    ------
    RuntimeError
        If after ``max_steps`` a residual is still above 10⁻² (no usable mode).
    """
    factor = factorize_stiffness(lin)
    K = sp.csr_matrix(lin.K0)
    C = sp.csr_matrix(lin.C0)
    b = -np.asarray(lin.H0, dtype=float)
    n = b.size
    max_steps = max(min(max_steps, n), k)
    x0 = factor.solve(b)
    V = np.empty((max_steps + 1, n))
    V[0] = x0 / math.sqrt(float(x0 @ (K @ x0)))
    alpha: list[float] = []
    beta: list[float] = []
    for j in range(max_steps):
        z = C @ V[j]
        wv = factor.solve(z)
        h = V[: j + 1] @ z
        wv -= h @ V[: j + 1]
        h2 = V[: j + 1] @ (K @ wv)
        wv -= h2 @ V[: j + 1]
        alpha.append(float(h[j] + h2[j]))
        bj = math.sqrt(max(float(wv @ (K @ wv)), 0.0))
        m = j + 1
        last = m == max_steps or bj <= 1e-14 * abs(alpha[-1])
        if m >= k and (m % 5 == 0 or last):
            theta, S = np.linalg.eigh(np.diag(alpha) + np.diag(beta, 1) + np.diag(beta, -1))
            top = np.argsort(theta)[::-1][:k]
            resid = bj * np.abs(S[-1, top]) / np.maximum(theta[top], 1e-300)
            if np.all(resid < tol) or last:
                if np.any(resid > 1e-2):
                    raise RuntimeError(
                        f"the {k} slowest load-excited modes did not converge in {max_steps} Lanczos steps "
                        f"(largest relative residual {resid.max():.2g})"
                    )
                return 1.0 / theta[top], V[:m].T @ S[:, top], resid
        if last:
            break
        beta.append(bj)
        V[j + 1] = wv / bj
    raise RuntimeError("load_modes: no steps taken")  # pragma: no cover - the loop always returns

"""The linear-algebra core: the pencil (K0, C0) of a linear model and everything computed from it.

Every later stage (compliance and moduli, creep and relaxation, the relaxation
spectrum, the slowest modes, elasticities) reaches K0 and C0 through the one
:class:`Pencil` cached on its :class:`~tenscell.linear.linearize.LinearModel`
(``lin.pencil``), so each decomposition is computed once per model and shared.

Assembly at the reference (:func:`assemble_stiffness`, :func:`assemble_damping`)
    ``K0 = P·Σ T0_j ∇²l_j + Σ k_j a_j a_jᵀ`` for tangent stiffnesses ``k_j``
    (N/m) of the members, ``C0 = Σ c_j a_j a_jᵀ``. The geometric pieces (the
    Gram product ``A diag(w) Aᵀ`` and the member Hessians) belong to the
    geometry stage, :mod:`tenscell.model.equilibrium`, which needs them at any
    configuration; this module only combines them for a linear model.

Positive definiteness (:attr:`Pencil.cholesky`)
    One Cholesky factorization of K0 — dense LAPACK, or sparse CHOLMOD
    (:mod:`tenscell.linear.sparse`). It exists exactly when K0 is positive
    definite, so it is the check (:func:`tenscell.linearize` with
    ``check=True`` computes it) and it is kept for every later solve.

Dense modal decomposition (:attr:`Pencil.modes`)
    One Cholesky and one symmetric eigensolve of the whitened pencil (by K0's
    factor from the check; by C0's, once for every prestress, for a model of a
    :class:`PrestressFamily` whose C0 is well-conditioned) give
    ``C0 v = τ K0 v`` with ``VᵀK0V = I`` (τ ≥ 0 in s, τ = 0 for a mode the
    tendons do not damp), and

        J(s) = D0 (K0 + s·C0)⁻¹ b = Σ_k ρ_k / (1 + s·τ_k),  ρ_k = (D0·v_k)(b·v_k),  b = −H0,

    which serves the compliance at every frequency, creep and relaxation at
    every time, the relaxation spectrum ``λ = 1/τ`` and the resolvent
    ``(K0 + iωC0)⁻¹`` of the elasticities. Singular C0 needs no special case.
    Grids of prestresses, and loops of :func:`tenscell.linearize` over
    prestresses, use the same identity with C0 whitened once for all P (one
    :class:`PrestressFamily`, kept per cell for the last tendons it served).

Sparse models (:meth:`Pencil.lanczos_runs`)
    Besides the Cholesky of K0 (the check, and static solves), one Cholesky of
    ``K0 + σC0`` and one Lanczos run per shift σ, extended on demand
    (:mod:`tenscell.linear.krylov`), serve every frequency, time and mode. Its
    Ritz pairs are a retardation spectrum of the same form as the dense one
    (:meth:`Pencil.retardation`). Why a second factorization rather than
    Lanczos on K0's: measured on the lattices of ``bench/bench_scale.py``,
    σ = 0 needs 3–4 times the steps (130–155 against 35–40 for 100
    frequencies in 10⁻²…10³ Hz), and each step is a solve costing about a
    tenth of a factorization.

The continuum factor (:func:`continuum_factor`, :func:`modulus`)
    ``G = (0.5/L)/J`` (Pa) with strut length L (m), the paper's equivalent
    continuum; ``J(t)·2L`` is the creep compliance in 1/Pa.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.linalg
import scipy.linalg.lapack
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..model.equilibrium import weighted_gram
from .krylov import DEFAULT_BAND_HZ, LanczosRun, converge, default_shift
from .._errors import NotPositiveDefiniteError
from . import ordering
from .sparse import factorize_spd
from .._threads import hot_path

__all__ = [
    "NotPositiveDefiniteError",
    "positive_definite_factor",
    "complement_basis",
    "continuum_factor",
    "modulus",
    "assemble_stiffness",
    "assemble_damping",
    "Modes",
    "Pencil",
    "RelaxationSpectrum",
    "relaxation_spectrum",
    "modal_compliance",
    "prestress_grid_compliance",
    "PrestressFamily",
    "FAMILY_PIVOT_RATIO",
    "prestress_grid_modes",
    "ZERO_TIME",
]

#: a retardation time below this fraction of the longest counts as zero (an undamped mode)
ZERO_TIME = 1e-12
#: relative accuracy to which a sparse model's retardation spectrum is converged (J(t) at every t, and η)
SPECTRUM_TOL = 1e-10
#: a Lanczos run at another shift is reused when its shift is within this factor of the one asked for
SHIFT_REUSE_FACTOR = 4.0
#: rows of prestresses per block of the grid's modal sum (keeps the block in cache)
_GRID_BLOCK = 8


# ---- the continuum factor ---------------------------------------------------------------------
def continuum_factor(L: float) -> float:
    """The paper's equivalent-continuum factor ``0.5/L`` (1/m) for strut length ``L`` (m): ``G = (0.5/L)/J``."""
    return 0.5 / L


def modulus(J, L: float):
    """Complex modulus ``G' + iG'' = (0.5/L)/J`` (Pa) from a compliance ``J`` (m/N) and strut length ``L`` (m)."""
    return continuum_factor(L) / np.asarray(J) if np.ndim(J) else continuum_factor(L) / J


# ---- assembly at the reference ------------------------------------------------------------------
def assemble_stiffness(cell, P: float, k):
    """``K0 = P·Σ T0_j ∇²l_j + Σ k_j a_j a_jᵀ`` (N/m), dense or sparse like the cell.

    Parameters
    ----------
    cell : Cell
    P : float
        Prestress scale (N): member forces ``P·T0``.
    k : ndarray, shape (m,)
        Tangent stiffness ``dT_j/dl_j`` of each member at the reference (N/m).
        For the Voigt spring with the rest lengths of Eq. 11 it is
        ``(EA_j + P·T0_j)/l_j``.
    """
    return P * cell.prestress_hessian + weighted_gram(cell.A, k)


def assemble_damping(cell, c):
    """``C0 = Σ c_j a_j a_jᵀ`` (N·s/m) for member damping ``c`` (N·s/m, shape (m,))."""
    return weighted_gram(cell.A, c)


# ---- the dense modal decomposition ---------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Modes:
    """``C0 v = τ K0 v`` for a dense pencil: ``J(s) = Σ ρ_k/(1 + s·τ_k)``.

    Attributes
    ----------
    tau : ndarray, shape (n,)
        Retardation times τ_k (s), ascending, ≥ 0 (0 for undamped modes).
    vectors : ndarray, shape (n, n)
        K0-orthonormal eigenvectors as columns (``VᵀK0V = I``).
    weights : ndarray, shape (n,)
        ``ρ_k = (D0·v_k)(b·v_k)`` (m/N), ``b = −H0``.
    """

    tau: np.ndarray
    vectors: np.ndarray
    weights: np.ndarray


def modal_compliance(tau: np.ndarray, rho: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``J(iω) = Σ_k ρ_k/(1 + iωτ_k)`` (m/N) for ``tau``, ``rho`` of shape (..., n) and ω (rad/s) of shape (nf,).

    Real arithmetic: one batched ``(2 × n)(n × nf)`` product gives both parts.
    Returns shape (..., nf).
    """
    tau, rho = np.asarray(tau), np.asarray(rho)
    den = np.multiply.outer(tau * tau, w * w)
    den += 1.0
    np.divide(1.0, den, out=den)  # the same correctly rounded 1/x as np.reciprocal, which numpy does not vectorize (2× slower)
    weights = np.empty(rho.shape[:-1] + (2, rho.shape[-1]))
    weights[..., 0, :] = rho
    np.multiply(rho, tau, out=weights[..., 1, :])
    parts = weights @ den
    return parts[..., 0, :] - 1j * (w * parts[..., 1, :])


def _tri(L: np.ndarray, B: np.ndarray, trans: int = 0) -> np.ndarray:
    """``L⁻¹B`` (``L⁻ᵀB`` with trans=1) for a lower-triangular L: LAPACK trtrs without the wrapper's checks."""
    X, info = _trtrs(L, B, lower=1, trans=trans)
    if info != 0:  # pragma: no cover - L comes from a successful Cholesky
        raise np.linalg.LinAlgError(f"triangular solve failed (info={info})")
    return X


_trtrs = scipy.linalg.lapack.dtrtrs
_syevd = scipy.linalg.lapack.dsyevd


def _whiten(L: np.ndarray, M: np.ndarray) -> np.ndarray:
    """``L⁻¹ M L⁻ᵀ`` (symmetrized) for a lower-triangular L, with M of shape (n, n)."""
    X = _tri(L, M)
    X = _tri(L, X.T)
    return 0.5 * (X + X.T)


def _cholesky_or_none(M: np.ndarray) -> np.ndarray | None:
    """Lower Cholesky factor of M, or None if M is indefinite or singular (a pivot below ZERO_TIME of the largest)."""
    try:
        L = np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        return None
    d = np.diagonal(L) ** 2
    return L if d.min() > ZERO_TIME * d.max() else None


def _ritz_is_zero(tau: np.ndarray) -> np.ndarray:
    return tau <= ZERO_TIME * max(float(tau.max()) if tau.size else 0.0, 1e-300)


# ---- positive definiteness: one criterion ---------------------------------------------------------
def positive_definite_factor(M, *, what: str = "K0", describe: str = "the model", hint: str = "", perm=None):
    """The Cholesky factor of a symmetric matrix, which exists exactly when it is positive definite.

    The one criterion of positive definiteness in tenscell (a stable
    equilibrium is one whose K0 passes it): dense LAPACK Cholesky, or sparse
    CHOLMOD (:mod:`tenscell.linear.sparse`). Grids of prestresses use the
    equivalent test that every relaxation rate of the whitened pencil is
    positive (:func:`prestress_grid_modes`).

    Returns
    -------
    ndarray or SparseCholesky
        Lower-triangular factor (dense) or the sparse factorization.

    Raises
    ------
    NotPositiveDefiniteError
        If ``M`` is not positive definite; the message names ``what`` and
        ``describe`` and gives the smallest eigenvalue (dense) or the failed
        pivot's column (sparse), then ``hint``.

    ``perm`` (sparse only) is the fill-reducing ordering to factor with
    (default CHOLMOD's AMD).
    """
    if sp.issparse(M):
        try:
            return factorize_spd(M, what=what, perm=perm)
        except NotPositiveDefiniteError as err:
            detail = f"a pivot of its sparse Cholesky factorization is <= 0, at column {err.column}"
    else:
        try:
            return np.linalg.cholesky(M)
        except np.linalg.LinAlgError:
            detail = f"smallest eigenvalue {float(np.linalg.eigvalsh(M)[0]):.3g}"
    raise NotPositiveDefiniteError(
        f"{what} is not positive definite for {describe} ({detail}): "
        "the reference is not a stable equilibrium." + (f" {hint}" if hint else "")
    )


def complement_basis(R: np.ndarray, n: int) -> np.ndarray:
    """Orthonormal basis (n, n − r) of the complement of the columns of ``R`` (n, r), e.g. rigid-body motions."""
    return scipy.linalg.null_space(R.T) if R.shape[1] else np.eye(n)


# ---- the pencil -----------------------------------------------------------------------------------
class Pencil:
    """The pencil (K0, C0) of one linear model with its decompositions, each computed once.

    Parameters
    ----------
    K0, C0 : ndarray or scipy.sparse matrix, shape (n, n)
        Stiffness (N/m) and damping (N·s/m).
    load : ndarray, shape (n,)
        ``b = −H0``, generalized force of a unit load.
    probe : ndarray, shape (n,)
        ``D0``, the probe's output row.
    describe : str
        What the model is, for messages (e.g. ``"paper cell (...) at P=1000"``).
    hint : str
        Advice appended to the not-positive-definite message.
    points : ndarray, shape (n, 3), optional
        A location (m) for each coordinate. For a large sparse pencil they give
        the fill-reducing ordering (:mod:`tenscell.linear.ordering`) that every
        factorization of the pencil shares; without them CHOLMOD orders each
        factorization by AMD.
    family : (PrestressFamily, float), optional
        Dense only: the family this pencil belongs to and its prestress P (N).
        Its modes then come from the family's one whitening of C0, shared by
        every P (a loop of :func:`tenscell.linearize` over prestresses), not
        from a factor of this K0.
    """

    def __init__(self, K0, C0, load, probe, *, describe: str = "the model", hint: str = "", points=None,
                 family: tuple[PrestressFamily, float] | None = None):
        self.K0, self.C0 = K0, C0
        self.points = points
        self.family = family
        self.load = np.asarray(load, dtype=float)
        self.probe = np.asarray(probe, dtype=float)
        self.describe, self.hint = describe, hint
        self.sparse = sp.issparse(K0)
        self._factors: dict[float, object] = {}
        self._shifted: dict[float, object] = {}
        self._runs: dict[float, list[LanczosRun]] = {}
        self._retardation: tuple | None = None

    @property
    def n(self) -> int:
        """Number of coordinates."""
        return self.K0.shape[0]

    # -- positive definiteness --------------------------------------------------------------------
    @cached_property
    @hot_path
    def cholesky(self):
        """Cholesky factor of K0: lower-triangular ndarray (dense) or :class:`SparseCholesky`.

        Raises
        ------
        NotPositiveDefiniteError
            If K0 is not positive definite.
        """
        return positive_definite_factor(self.K0, what="K0", describe=self.describe, hint=self.hint,
                                        perm=self.ordering)

    @cached_property
    def ordering(self) -> np.ndarray | None:
        """The fill-reducing permutation shared by the factors of K0 and of every ``K0 + σC0`` (sparse), or None.

        Geometric nested dissection on the union of the patterns of K0 and C0
        when the pencil is sparse, has :data:`~tenscell.linear.ordering.MIN_SIZE`
        coordinates or more and knows their locations; None (CHOLMOD's AMD) otherwise.
        """
        if not self.sparse or self.points is None or self.n < ordering.MIN_SIZE:
            return None
        pattern = abs(sp.csr_matrix(self.K0)) + abs(sp.csr_matrix(self.C0))
        return ordering.nested_dissection(pattern, self.points)

    def check(self) -> None:
        """Raise :class:`NotPositiveDefiniteError` unless K0 is positive definite (factors K0 once).

        A pencil of a :class:`PrestressFamily` is checked by its modes instead
        (every relaxation rate > 0, the grid's criterion): they are what its
        models are made for, and a factor of K0 would be extra work.
        """
        if self.family is not None:
            self.modes  # noqa: B018 - the family's rates are the check
            return
        self.cholesky  # noqa: B018 - computing the factor is the check

    @hot_path
    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``K0⁻¹ rhs`` with the cached factor; rhs of shape (n,) or (n, k)."""
        L = self.cholesky
        if self.sparse:
            return L.solve(rhs)
        return scipy.linalg.cho_solve((L, True), rhs, check_finite=False)

    def static_compliance(self) -> float:
        """``J(0) = D0 K0⁻¹ b`` (m/N)."""
        return float(self.probe @ self.solve(self.load))

    @hot_path
    def solve_at(self, s: complex, rhs: np.ndarray) -> np.ndarray:
        """``(K0 + s·C0)⁻¹ rhs`` at one complex shift ``s`` (1/s; ``s = iω`` for a steady state at ω in rad/s).

        One LU factorization of the shifted matrix (dense LAPACK, sparse SuperLU):
        for a single shift it is cheaper than the modal decomposition.
        """
        Z = self.K0 + s * self.C0
        rhs = np.asarray(rhs)
        if self.sparse:
            return spla.splu(sp.csc_matrix(Z, dtype=complex)).solve(rhs.astype(complex))
        return np.linalg.solve(Z, rhs.astype(complex))

    def restricted(self, Q: np.ndarray, describe: str | None = None) -> Pencil:
        """The pencil on the subspace spanned by the orthonormal columns of ``Q`` (dense): ``(QᵀK0Q, QᵀC0Q)``.

        For free-standing structures, whose K0 is singular along the rigid-body
        motions: their stability and modes are those of the pencil on the
        complement (:func:`complement_basis`).
        """
        K, C = Q.T @ np.asarray(self.K0) @ Q, Q.T @ np.asarray(self.C0) @ Q
        return Pencil(0.5 * (K + K.T), 0.5 * (C + C.T), Q.T @ self.load, Q.T @ self.probe,
                      describe=self.describe if describe is None else describe, hint=self.hint)

    def is_positive_definite(self) -> bool:
        """Whether K0 is positive definite (the criterion of :attr:`cholesky`, whose factor is kept)."""
        try:
            self.check()
        except NotPositiveDefiniteError:
            return False
        return True

    def slow_modes(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The ``k`` largest retardation times μ = 1/λ (s) of ``C0 v = μ K0 v`` with their modes, dense.

        Returns ``(mu, V)``: μ ascending (0 for a mode the tendons do not
        damp), K0-orthonormal vectors as the columns of V, shape (n, k). From
        the one modal decomposition (:attr:`modes`).
        """
        m = self.modes
        k = min(int(k), self.n)
        return m.tau[self.n - k:], m.vectors[:, self.n - k:]

    @cached_property
    def damping_modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Eigenvalues (N·s/m, ascending) and orthonormal eigenvectors of C0 alone (dense).

        A zero eigenvalue is a motion no tendon damps: the undamped mechanism
        of a cell whose tendons leave one (e.g. without intermediate filaments).
        """
        if self.sparse:
            raise ValueError(f"{self.describe} is sparse: the eigendecomposition of its C0 is not formed")
        return np.linalg.eigh(np.asarray(self.C0))

    # -- dense: one eigensolve ---------------------------------------------------------------------
    @cached_property
    @hot_path
    def modes(self) -> Modes:
        """The dense modal decomposition ``C0 v = τ K0 v``: one Cholesky, one symmetric eigensolve.

        The pencil is whitened by K0's factor from the positive-definiteness
        check, so the modes are K0-orthonormal and ``Σ ρ_k = D0ᵀK0⁻¹b`` holds to
        round-off whatever the conditioning of C0: the static compliance
        (creep J(∞), G'(0)) stays exact for fitted cells whose damping spans
        many decades, and undamped modes get τ = 0 without a special case.

        A pencil of a :class:`PrestressFamily` (a model from
        :func:`tenscell.linearize` whose C0 is well-conditioned) takes its modes
        from the family instead: C0 whitened once for every prestress, one
        eigensolve per P — the same modes to round-off, and the same numbers
        as :func:`tenscell.frequency_response`'s grid.
        """
        if self.sparse:
            raise ValueError(
                f"{self.describe} is sparse ({self.n} coordinates): its full modal decomposition is not formed; "
                "use Pencil.retardation() (Lanczos) instead"
            )
        if self.family is not None:
            family, P = self.family
            return family.modes(P, self.describe, self.hint)
        L = self.cholesky  # the positive-definiteness check
        tau, U = np.linalg.eigh(_whiten(L, np.asarray(self.C0)))
        tau = np.clip(tau, 0.0, None)  # C0 is positive semidefinite: negative τ are rounding
        V = _tri(L, U, trans=1)
        return Modes(tau=tau, vectors=V, weights=(self.probe @ V) * (self.load @ V))

    @hot_path
    def resolvent(self, w, rhs: np.ndarray) -> np.ndarray:
        """``x(ω) = (K0 + iωC0)⁻¹ rhs`` for every ω (rad/s), shape (nf, n), from the modal decomposition (dense).

        ``(K0 + iωC0)⁻¹ = V diag(1/(1 + iωτ)) Vᵀ``; the pencil is symmetric, so
        this also gives ``(K0 + iωC0)⁻ᵀ rhs``. For elasticities and other
        derivatives of J (:func:`tenscell.sensitivity.analytic_elasticities`).
        """
        m = self.modes
        V = m.vectors
        g = 1.0 / (1.0 + 1j * np.multiply.outer(np.atleast_1d(np.asarray(w, dtype=float)), m.tau))
        return (g * (np.asarray(rhs, dtype=float) @ V)) @ V.T

    # -- sparse: factors and Lanczos runs per shift ----------------------------------------------------
    def factor(self, shift: float = 0.0):
        """Sparse Cholesky factor of ``K0 + shift·C0`` (shift in rad/s, ≥ 0), computed once per shift."""
        shift = float(shift)
        if shift == 0.0:
            return self.cholesky
        if shift not in self._factors:
            Ks = self.shifted(shift).tocsc()
            try:
                self._factors[shift] = factorize_spd(Ks, what=f"K0 + {shift:g}·C0", perm=self.ordering)
            except NotPositiveDefiniteError as err:
                raise NotPositiveDefiniteError(
                    f"K0 + {shift:g}·C0 is not positive definite for {self.describe} (a pivot of its sparse Cholesky "
                    f"factorization is <= 0, at column {err.column}), so neither is K0: the reference is not a "
                    "stable equilibrium"
                ) from None
        return self._factors[shift]

    def shifted(self, shift: float):
        """``K0 + shift·C0`` (sparse CSR, shift in rad/s), formed once per shift for its factor and its Lanczos run."""
        shift = float(shift)
        if shift not in self._shifted:
            self._shifted[shift] = (sp.csr_matrix(self.K0) + shift * sp.csr_matrix(self.C0)).tocsr() if shift \
                else sp.csr_matrix(self.K0)
        return self._shifted[shift]

    def nearby_shift(self, shift: float) -> float:
        """A shift already in use within :data:`SHIFT_REUSE_FACTOR` of ``shift`` (rad/s), else ``shift``."""
        for s in self._runs:
            if s > 0 and shift > 0 and 1.0 / SHIFT_REUSE_FACTOR <= s / shift <= SHIFT_REUSE_FACTOR:
                return s
        return float(shift)

    def lanczos_runs(self, shift: float) -> list[LanczosRun]:
        """The Lanczos run(s) at ``shift`` (rad/s): one from the load, or two (b ± D0) when probe ≠ load."""
        shift = float(shift)
        if shift not in self._runs:
            F = self.factor(shift)
            C = sp.csr_matrix(self.C0)
            Ks = self.shifted(shift)
            b, d = self.load, self.probe
            starts = [b] if self.probe_is_load else [b + d, b - d]
            cap = min(self.n, 2000)
            self._runs[shift] = [LanczosRun(F, Ks, C, v, shift, cap) for v in starts]
        return self._runs[shift]

    @property
    def probe_is_load(self) -> bool:
        """Whether the probe row equals the load vector (symmetric transfer function)."""
        b, d = self.load, self.probe
        return bool(np.allclose(b, d, rtol=0, atol=1e-14 * max(np.abs(b).max(), 1e-300)))

    # -- the retardation spectrum, dense or sparse ------------------------------------------------------
    def retardation(self, tol: float = SPECTRUM_TOL) -> tuple[np.ndarray, np.ndarray, float]:
        """``(τ, ρ, error)``: ``J(s) = Σ ρ/(1 + sτ)`` for every s, dense or sparse.

        Dense: the modal decomposition (error 0). Sparse: the Ritz spectrum of
        the model's Lanczos run, extended until the creep compliance
        ``J(t) = Σ ρ(1 − e^{−t/τ})`` on a logarithmic grid of times spanning the
        spectrum, the static compliance and ``Σ_{τ>0} ρ/τ`` change by less than
        ``tol`` (relative) over the last steps; ``error`` is that change.
        """
        if not self.sparse:
            m = self.modes
            return m.tau, m.weights, 0.0
        if self._retardation is not None and self._retardation[2] <= tol:
            return self._retardation
        sigma = self.retardation_shift
        runs = self.lanczos_runs(sigma)
        err = 0.0
        for run in runs:
            err = max(err, converge(run, _CreepChange(), tol, "creep spectrum"))
        spectra = [self._run_spectrum(r) for r in runs]
        if len(runs) == 1:
            tau, rho = spectra[0]
        else:  # polarization: J = ¼(J₊ − J₋)
            tau = np.concatenate([spectra[0][0], spectra[1][0]])
            rho = np.concatenate([0.25 * spectra[0][1], -0.25 * spectra[1][1]])
        order = np.argsort(tau)
        self._retardation = (tau[order], rho[order], err)
        return self._retardation

    @cached_property
    def retardation_shift(self) -> float:
        """The shift (rad/s) of the Lanczos run behind the time domain: the paper band's, or a nearby one in use."""
        return self.nearby_shift(default_shift(DEFAULT_BAND_HZ))

    def _run_spectrum(self, run: LanczosRun) -> tuple[np.ndarray, np.ndarray]:
        try:
            return run.spectrum()
        except FloatingPointError:
            raise NotPositiveDefiniteError(
                f"K0 is not positive definite for {self.describe}: the Lanczos run found a mode with a "
                "non-positive stiffness (the reference is not a stable equilibrium)"
            ) from None


class _CreepChange:
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
        pos = tau[~_ritz_is_zero(tau)]
        if pos.size == 0:
            return math.inf
        t = np.logspace(math.log10(pos.min()) - 1, math.log10(pos.max()) + 1, 48)
        now, before = _creep_features(tau, rho, t), _creep_features(*prev, t)
        return float(np.max(np.abs(now - before) / np.maximum(np.abs(now), 1e-300)))


def _creep_features(tau, rho, t):
    """J(t) on the grid, J(∞) and Σ_{τ>0} ρ/τ (the initial creep rate per unit force)."""
    zero = _ritz_is_zero(tau)
    tp, rp = tau[~zero], rho[~zero]
    J = rho[zero].sum() + (-np.expm1(-np.multiply.outer(t, 1.0 / tp))) @ rp
    return np.concatenate([J, [rho.sum(), (rp / tp).sum()]])


# ---- the relaxation spectrum -----------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class RelaxationSpectrum:
    """Modes of the linear model: ``J(ω) = Σ_k r_k / (λ_k + iω)``.

    Attributes
    ----------
    rates : ndarray, shape (k,)
        Relaxation rates λ_k (1/s), ascending; ``K0 v = λ C0 v``. Dense
        models: all n of them; sparse models: the Ritz values of the Lanczos
        run from the load (the modes the load excites, converged so that
        ``J`` agrees with the full model to ``error_estimate``).
    residues : ndarray, shape (k,)
        ``r_k = (D0·v_k)(−H0·v_k)`` (m/(N·s)); non-negative when probe = load.
    modes : ndarray, shape (n, k)
        C0-orthonormal eigenvectors as columns. For sparse models these are
        the Ritz vectors, exact eigenvectors only where a Ritz pair has
        converged: a cluster of (nearly) equal rates, such as a lattice's
        identical local modes, is represented by fewer Ritz pairs carrying its
        total weight (what J needs; see :func:`tenscell.summary.relaxation_modes` for
        converged slowest modes).
    error_estimate : float
        Relative accuracy of the spectrum's ``J`` (0 for the dense, exact decomposition).
    """

    rates: np.ndarray
    residues: np.ndarray
    modes: np.ndarray
    error_estimate: float = 0.0

    @property
    def times(self) -> np.ndarray:
        """Relaxation times τ_k = 1/λ_k (s)."""
        return 1.0 / self.rates

    @property
    def weights(self) -> np.ndarray:
        """Compliance weights ``r_k/λ_k`` (m/N): each mode's share of the static compliance."""
        return self.residues / self.rates

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from .._results import format_repr, span

        return format_repr(
            f"RelaxationSpectrum: {self.rates.size} modes",
            f"rates λ {span(self.rates, '1/s')} (times {span(self.times, 's')})",
            f"static compliance Σ r/λ = {self.weights.sum():.6g} m/N; relative error of J {self.error_estimate:.2g}",
        )

    def to_dataframe(self):
        """One row per mode: ``rate_per_s, time_s, residue_m_per_Ns, weight_m_per_N``."""
        from .._results import dataframe

        return dataframe({"rate_per_s": self.rates, "time_s": self.times, "residue_m_per_Ns": self.residues,
                          "weight_m_per_N": self.weights})

    def plot(self, ax=None, **kw):
        """Each mode's compliance weight r/λ (m/N) against its relaxation time 1/λ (s), as stems."""
        from .._results import plotter

        spectrum_stems = plotter("spectrum_stems")

        return spectrum_stems(self.times, self.weights, ax=ax, xlabel="relaxation time 1/λ (s)",
                              ylabel="compliance weight r/λ (m/N)", **kw)


@hot_path
def relaxation_spectrum(lin) -> RelaxationSpectrum:
    """Solve ``K0 v = λ C0 v`` (rates λ in 1/s, ``vᵀC0v = 1``), dense or sparse.

    Dense models: the full spectrum from the model's one modal decomposition.
    Sparse models: the load-excited part, from the model's Lanczos run
    (:meth:`Pencil.retardation`); it needs probe = load.

    Raises
    ------
    ValueError
        If C0 is singular (e.g. the cell without intermediate filaments, whose
        damping leaves a mechanism undamped), so that some λ is infinite; or
        for a sparse model whose probe is not its load.
    """
    pencil = lin.pencil
    if not pencil.sparse:
        m = pencil.modes
        tau, rho, err = m.tau, m.weights, 0.0
        V = m.vectors
    else:
        if not pencil.probe_is_load:
            raise ValueError(
                f"the relaxation spectrum of the sparse model {lin.cell.describe()} is computed from the load; "
                "its probe is not the load (use creep_spectrum, whose retardation spectrum covers this case)"
            )
        err = pencil.retardation()[2]
        run = pencil.lanczos_runs(pencil.retardation_shift)[0]
        tau, rho = pencil._run_spectrum(run)  # in the order of the Ritz values θ, ascending
        V = run.ritz_vectors(np.arange(tau.size))
    if tau.size == 0 or np.any(_ritz_is_zero(tau)):
        raise ValueError(
            f"the damping matrix C0 of {lin.cell.describe()} is singular (not positive definite), "
            "so the relaxation spectrum K0 v = λ C0 v is not defined; compliance() handles this case"
        )
    rates = 1.0 / tau
    # to C0-normalization: dense vectors are K0-normalized (vᵀC0v = τ), Ritz vectors Kσ-normalized (uᵀC0u = θ)
    V = V / np.sqrt(tau if not pencil.sparse else tau / (1.0 + pencil.retardation_shift * tau))
    order = np.argsort(rates)
    return RelaxationSpectrum(rates=rates[order], residues=(rho / tau)[order], modes=V[:, order],
                              error_estimate=err)


# ---- grids of prestresses ---------------------------------------------------------------------------
def prestress_grid_modes(Kpt: np.ndarray, Kmt: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Relaxation rates and modes of ``P·K̃p + K̃m`` for many prestresses, in the basis where C0 = I.

    Parameters
    ----------
    Kpt : ndarray, shape (n, n) or (nP, n, n)
        ``L⁻¹ Kp L⁻ᵀ`` with ``C0 = L Lᵀ`` (symmetric).
    Kmt : ndarray, shape (n, n) or (nP, n, n)
        The whitened material stiffness (one for every P, or one per P).
    P : ndarray, shape (nP,)
        Prestresses (N).

    Returns
    -------
    lam : ndarray, shape (nP, n)
        Rates λ (1/s), ascending; every λ > 0 exactly when that K0 is positive definite.
    U : ndarray, shape (nP, n, n)
        Orthonormal modes (columns); ``v = L⁻ᵀu`` are C0-orthonormal.
    """
    P = np.asarray(P, dtype=float)
    return np.linalg.eigh(P[:, None, None] * np.asarray(Kpt) + np.asarray(Kmt))


#: C0 is whitened once for a family of prestresses only when the pivots of its Cholesky factor span at most
#: this ratio (``min d/max d`` with ``d = diag(Lc)²``, roughly 1/cond(C0)): whitening by an ill-conditioned C0
#: would cost the static compliance the digits that K0's own factor keeps (:attr:`Pencil.modes`)
FAMILY_PIVOT_RATIO = 1e-4


@dataclass(frozen=True, eq=False)
class PrestressFamily:
    """The dense pencils ``(P·Kp + Km, C0)`` of one cell with one set of tendons, for every prestress P.

    K0 is affine in P and C0 does not depend on it, so C0 is whitened once
    (``C0 = Lc Lcᵀ``) and each prestress costs one symmetric eigensolve of
    ``P·K̃p + K̃m``. The grid (:func:`prestress_grid_compliance`) and a loop of
    :func:`tenscell.linearize` over prestresses (each model's
    :attr:`Pencil.modes`) share it, so both give the same modes.

    Build with :meth:`build`, which returns None when C0 is singular or too
    ill-conditioned to whiten by (:data:`FAMILY_PIVOT_RATIO`).

    Attributes
    ----------
    Kp, Km : ndarray, shape (n, n)
        Prestress stiffness per unit P (N/m per N) and material stiffness (N/m): ``K0 = P·Kp + Km``.
    C0 : ndarray, shape (n, n)
        Damping (N·s/m), read-only: every model of the family shares it.
    Lc : ndarray, shape (n, n)
        Lower Cholesky factor of C0.
    Kpt, Kmt : ndarray, shape (n, n)
        ``Lc⁻¹ Kp Lc⁻ᵀ`` (per unit P) and ``Lc⁻¹ Km Lc⁻ᵀ`` (1/s).
    bt, dt : ndarray, shape (n,)
        ``Lc⁻¹ b`` (load, ``b = −H0``) and ``Lc⁻¹ D0`` (probe).
    """

    Kp: np.ndarray
    Km: np.ndarray
    C0: np.ndarray
    Lc: np.ndarray
    Kpt: np.ndarray
    Kmt: np.ndarray
    bt: np.ndarray
    dt: np.ndarray

    @classmethod
    def build(cls, Kp, K_material, C0, load, probe) -> PrestressFamily | None:
        """The family of ``(P·Kp + K_material, C0)`` (dense, N/m and N·s/m), or None if C0 is not well-conditioned."""
        C0 = np.array(C0, dtype=float)
        Lc = _cholesky_or_none(C0)
        if Lc is None:
            return None
        d = np.diagonal(Lc) ** 2
        if d.min() < FAMILY_PIVOT_RATIO * d.max():
            return None
        C0.flags.writeable = False
        Kp, Km = np.asarray(Kp), np.asarray(K_material)
        return cls(Kp=Kp, Km=Km, C0=C0, Lc=Lc, Kpt=_whiten(Lc, Kp), Kmt=_whiten(Lc, Km),
                   bt=_tri(Lc, np.asarray(load, dtype=float)), dt=_tri(Lc, np.asarray(probe, dtype=float)))

    def stiffness(self, P: float) -> np.ndarray:
        """``K0 = P·Kp + Km`` (N/m) at prestress ``P`` (N)."""
        return P * self.Kp + self.Km

    def rates(self, P: np.ndarray, describe: str = "the model", hint: str = "") -> tuple[np.ndarray, np.ndarray]:
        """Relaxation rates λ (1/s, ascending, all > 0) and orthonormal modes U of every prestress ``P`` (N, shape (nP,)).

        Raises
        ------
        NotPositiveDefiniteError
            If K0 is not positive definite at some P (a rate ≤ 0).
        """
        lam, U = prestress_grid_modes(self.Kpt, self.Kmt, P)
        bad = np.flatnonzero(lam[:, 0] <= 0)
        if bad.size:
            raise _unstable(P[bad[0]], lam[bad[0], 0], describe, hint)
        return lam, U

    def modes(self, P: float, describe: str = "the model", hint: str = "") -> Modes:
        """The modal decomposition of the pencil at prestress ``P`` (N), as :attr:`Pencil.modes` gives it.

        ``τ = 1/λ`` ascending, K0-orthonormal vectors ``Lc⁻ᵀu/√λ``, weights ``(d̃·u)(b̃·u)/λ``.

        Raises
        ------
        NotPositiveDefiniteError
            If K0 is not positive definite at P: the family's check, the same as the grid's.
        """
        # one P: LAPACK's syevd directly (the batched call's overhead is a fifth of a 24×24 eigensolve)
        lam, U, info = _syevd(P * self.Kpt + self.Kmt, lower=1)
        if info != 0:  # pragma: no cover - a symmetric eigensolve of a finite matrix converges
            raise np.linalg.LinAlgError(f"symmetric eigensolve failed (info={info})")
        if not lam[0] > 0:
            raise _unstable(P, lam[0], describe, hint)
        r = 1.0 / lam  # τ, descending: the results are reversed views, ascending in τ
        V = _tri(self.Lc, U, trans=1)
        V *= np.sqrt(r)
        return Modes(tau=r[::-1], vectors=V[:, ::-1], weights=((self.dt @ U) * (self.bt @ U) * r)[::-1])

    @hot_path
    def compliance(self, P: np.ndarray, w: np.ndarray, describe: str = "the model") -> np.ndarray:
        """``J(iω)`` (m/N), shape (nP, nf), at prestresses ``P`` (N) and ω (rad/s): one batched eigensolve,
        the modal sum in blocks of prestresses that stay in cache."""
        lam, U = self.rates(P, describe)
        tau = 1.0 / lam
        rho = (self.dt @ U) * (self.bt @ U) * tau  # residues r = (d̃·u)(b̃·u) in rate form; ρ = r/λ
        J = np.empty((P.size, w.size), dtype=complex)
        for i in range(0, P.size, _GRID_BLOCK):
            J[i: i + _GRID_BLOCK] = modal_compliance(tau[i: i + _GRID_BLOCK], rho[i: i + _GRID_BLOCK], w)
        return J


def _unstable(P: float, rate: float, describe: str, hint: str) -> NotPositiveDefiniteError:
    return NotPositiveDefiniteError(
        f"K0 is not positive definite for {describe} at P={P:.6g} (smallest relaxation rate {rate:.3g} 1/s): "
        "the reference is not a stable equilibrium." + (f" {hint}" if hint else "")
    )


@hot_path
def prestress_grid_compliance(Kp, K_material, C0, load, probe, P: np.ndarray, w: np.ndarray,
                              describe: str = "the model") -> np.ndarray | None:
    """``J(iω)`` (m/N) of the dense pencils ``(P·Kp + K_material, C0)`` for many prestresses at once.

    C0 is the same for every P, so it is whitened once (:class:`PrestressFamily`);
    one batched symmetric eigensolve of ``P·K̃p + K̃m`` gives every P's rates
    λ (their positivity is the positive-definiteness check of each K0), and
    the modal sum runs in blocks of prestresses that stay in cache.

    Returns
    -------
    ndarray of complex, shape (nP, nf), or None
        None when C0 is singular or ill-conditioned (use the per-model path).

    Raises
    ------
    NotPositiveDefiniteError
        If K0 is not positive definite at some P.
    """
    family = PrestressFamily.build(Kp, K_material, C0, load, probe)
    return None if family is None else family.compliance(np.asarray(P, dtype=float), w, describe)

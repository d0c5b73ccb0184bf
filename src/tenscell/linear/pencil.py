"""The pencil (K0, C0) of one linear model, with every decomposition of it computed once.

Every later stage (compliance and moduli, creep and relaxation, the relaxation
spectrum, the slowest modes, elasticities) reaches K0 and C0 through the one
:class:`Pencil` cached on its :class:`~tenscell.linear.linearize.LinearModel`
(``lin.pencil``), so each decomposition is computed once per model and shared.

Positive definiteness (:attr:`Pencil.cholesky`, :meth:`Pencil.check`)
    The one criterion of :mod:`tenscell.linear.definite`: K0's Cholesky
    factor exists. :func:`tenscell.linearize` with ``check=True`` computes it,
    and the factor is kept for static solves (dense and sparse).

Dense pencils (:attr:`Pencil.modes`)
    One symmetric eigensolve of the pencil whitened by K0's factor gives
    ``C0 v = τ K0 v`` with ``VᵀK0V = I`` (:class:`~tenscell.linear.spectrum.Modes`),
    which serves the compliance at every frequency, creep and relaxation at
    every time, the relaxation spectrum and the resolvent ``(K0 + iωC0)⁻¹`` of
    the elasticities. Singular C0 needs no special case. A model of a
    :class:`~tenscell.linear.family.PrestressFamily` takes its modes from the
    family (C0 whitened once for every prestress).

Sparse pencils (:meth:`Pencil.lanczos_runs`)
    Besides the Cholesky factor of K0 (the check, and static solves), one
    Cholesky factor of ``K0 + σC0`` and one Lanczos run per shift σ, extended
    on demand (:mod:`tenscell.linear.krylov`), serve every frequency, time and
    mode; every factor of the pencil shares one fill-reducing ordering chosen
    by size (:func:`tenscell.linear.ordering.fill_reducing`). Why a second
    factorization rather than a Lanczos run on K0's: measured on the lattices
    of ``bench/bench_scale.py``, σ = 0 needs 3–4 times the steps, and each
    step is a solve costing about a tenth of a factorization
    (docs/large-structures.md has the numbers).
"""
from __future__ import annotations

from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .._errors import NotPositiveDefiniteError
from .._threads import hot_path
from . import ordering
from .definite import positive_definite_factor, tri, whiten
from .krylov import DEFAULT_BAND_HZ, CreepChange, LanczosRun, converge, default_shift
from .spectrum import Modes

if TYPE_CHECKING:  # pragma: no cover
    from .family import PrestressFamily

__all__ = ["Pencil", "complement_basis", "SPECTRUM_TOL", "SHIFT_REUSE_FACTOR"]

#: relative accuracy to which a sparse model's retardation spectrum is converged (J(t) at every t, and η)
SPECTRUM_TOL = 1e-10
#: a Lanczos run at another shift is reused when its shift is within this factor of the one asked for
SHIFT_REUSE_FACTOR = 4.0


class _once:
    """A property computed on first access and kept in the instance (``functools.cached_property`` without its
    per-access lock, which Python 3.11 takes: 2 µs on a model whose whole response costs 100 µs)."""

    def __init__(self, fn):
        self.fn, self.name = fn, fn.__name__
        self.__doc__ = fn.__doc__

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, obj, cls=None):
        if obj is None:
            return self
        value = obj.__dict__[self.name] = self.fn(obj)
        return value


def complement_basis(R: np.ndarray, n: int) -> np.ndarray:
    """Orthonormal basis (n, n − r) of the complement of the columns of ``R`` (n, r), e.g. rigid-body motions."""
    return scipy.linalg.null_space(R.T) if R.shape[1] else np.eye(n)


def _same_pattern(A, B) -> bool:
    """Whether two CSR matrices share one sparsity structure (the same ``indptr`` and ``indices`` memory, as the
    matrices assembled on a structure's node blocks do: :class:`tenscell.model.equilibrium.NodeBlocks`)."""
    return A.shape == B.shape and _same_memory(A.indptr, B.indptr) and _same_memory(A.indices, B.indices)


def _same_memory(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two arrays are the same memory seen the same way (scipy hands out views of the arrays it is given)."""
    return (a.shape == b.shape and a.dtype == b.dtype and a.strides == b.strides
            and a.__array_interface__["data"][0] == b.__array_interface__["data"][0])


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
    @_once
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

        Chosen by size (:func:`tenscell.linear.ordering.fill_reducing`) on the union
        of the patterns of K0 and C0 when the pencil is sparse, has
        :data:`~tenscell.linear.ordering.MIN_SIZE` coordinates or more and knows
        their locations; None (CHOLMOD's AMD) otherwise.
        """
        if not self.sparse or self.points is None or self.n < ordering.MIN_SIZE:
            return None
        K, C = sp.csr_matrix(self.K0), sp.csr_matrix(self.C0)
        pattern = K if _same_pattern(K, C) else abs(K) + abs(C)
        return ordering.fill_reducing(pattern, self.points)

    def check(self) -> None:
        """Raise :class:`NotPositiveDefiniteError` unless K0 is positive definite (factors K0 once: the one criterion,
        whose factor is kept for static solves)."""
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
    @_once
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
            # K0 checked already (linearize's check: its Cholesky factor) needs no second factorization
            return family.modes(P, self.describe, self.hint, checked="cholesky" in self.__dict__)
        L = self.cholesky  # the positive-definiteness check
        tau, U = np.linalg.eigh(whiten(L, np.asarray(self.C0)))
        tau = np.clip(tau, 0.0, None)  # C0 is positive semidefinite: negative τ are rounding
        V = tri(L, U, trans=1)
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
        """Sparse Cholesky factor of ``K0 + shift·C0`` (shift in rad/s), computed once per shift.

        A positive shift serves the frequency and time domains; a negative one, ``−λ0``, the slowest modes
        (:func:`tenscell.linear.krylov.load_modes`): its factor exists exactly when λ0 (1/s) lies below every
        relaxation rate, and :class:`NotPositiveDefiniteError` says it does not.
        """
        shift = float(shift)
        if shift == 0.0:
            return self.cholesky
        if shift not in self._factors:
            Ks = self.shifted(shift)  # the factorization reads its lower triangle in any sparse format
            # C0 is positive semidefinite: K0 + σC0 (σ > 0) not positive definite means K0 is not either
            what = f"K0 + {shift:g}·C0 (so neither is K0)" if shift > 0 else \
                f"K0 − {-shift:g}·C0 (some relaxation rate is at most {-shift:g} 1/s)"
            try:
                self._factors[shift] = positive_definite_factor(Ks, what=what, describe=self.describe,
                                                                hint=self.hint, perm=self.ordering)
            except NotPositiveDefiniteError:
                del self._shifted[shift]  # no run will use it
                raise
        return self._factors[shift]

    def shifted(self, shift: float):
        """``K0 + shift·C0`` (sparse CSR, shift in rad/s), formed once per shift for its factor and its Lanczos run."""
        shift = float(shift)
        if shift not in self._shifted:
            K, C = sp.csr_matrix(self.K0), sp.csr_matrix(self.C0)
            if not shift:
                Ks = K
            elif _same_pattern(K, C):  # one pattern (a lattice's node blocks): the sum of the data arrays
                Ks = sp.csr_matrix((K.data + shift * C.data, K.indices, K.indptr), shape=K.shape)
                Ks.has_sorted_indices, Ks.has_canonical_format = K.has_sorted_indices, K.has_canonical_format
            else:
                Ks = (K + shift * C).tocsr()
            self._shifted[shift] = Ks
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
            err = max(err, converge(run, CreepChange(), tol, "creep spectrum"))
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



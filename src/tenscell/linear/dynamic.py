"""The frequency-dependent response kernel: moduli of a cell whose tendons have dynamics of their own.

A tendon law with internal dynamics (:class:`tenscell.laws.Maxwell`,
:class:`~tenscell.laws.StandardLinearSolid`, :class:`~tenscell.laws.Springpot`)
has no constant pair (K0, C0); its dynamic tangent ``k*_j(ω)``
(:meth:`tenscell.laws.TendonLaw.complex_stiffness`) gives, with the same
split as :func:`tenscell.linear.assembly.assemble_stiffness`,

``K(ω) = P·Σ_j T0_j ∇²l_j + Σ_j k*_j(ω) a_j a_jᵀ``  (N/m, complex symmetric),

``J(ω) = −D0 K(ω)⁻¹ H0 = D0 K(ω)⁻¹ b`` (m/N), and
``G' + iG'' = (0.5/L)/J + iωη`` (Pa) with an optional Newtonian cytoplasm of
viscosity η (Pa·s) in parallel with the structure. For a rate-linear law
``k* = k + iωc`` and this is exactly :func:`tenscell.moduli` of
:func:`tenscell.linear.linearize_law` (tested).

For the time domain (creep, relaxation, the retardation spectrum) such a law
is *realized* with internal variables (:func:`tenscell.linear.linearize.realize`): each Maxwell arm
(spring ``g`` in series with a dashpot ``η_a``) of the law's
:class:`~tenscell.laws.Realization` adds its dashpot extension ``d_a`` to the
coordinates, and with ``B = [a_j(a)]`` (n × r), ``G = diag(g)``:

``K = [[P·Σ T0∇²l + A diag(k) Aᵀ + B G Bᵀ, −B G], [−G Bᵀ, G]]``,
``C = [[A diag(c) Aᵀ, 0], [0, diag(η_a)]]``,

load ``[b; 0]`` and probe ``[D0; 0]``: a symmetric pencil whose transfer
function is exactly ``D0 K(ω)⁻¹ b`` with the realization's ``k*``
(eliminate ``d``: ``(g + iωη_a) d_a = g a_jᵀq``). K is positive definite
exactly when the relaxed static stiffness is. Every consumer of a
:class:`~tenscell.linear.linearize.LinearModel` then works unchanged.

One LU factorization and solve per frequency: batched LAPACK for dense cells,
a sparse LU per frequency for sparse ones (no modal decomposition: the
pencil's eigenvectors do not exist for a frequency-dependent K). The
derivative ``∂J/∂θ = −Σ_j ∂k*_j/∂θ (yᵀa_j)(a_jᵀx)`` with ``x = K⁻¹b``,
``y = K⁻ᵀD0 = K⁻¹D0`` (K is complex symmetric) comes from the same solves.

For fits, which evaluate the same cell at many points (frequency, prestress, tendon values) and many parameter
vectors, :func:`dynamic_kernel` prepares a cell's matrices once (on the complement of the rigid-body motions for
a free-standing cell; ``a_j a_jᵀ`` flattened so that every point's ``K`` is one matrix product) and
:func:`batched_compliance` solves every point in one batched LAPACK call, each with its own prestress ``P`` and
tangents ``k*``, giving ``∂J/∂k*_j`` and ``∂J/∂P`` from the same factorization.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .._checks import positive_array, positive_scalar
from ..laws.base import TendonLaw, angular_frequencies
from ..model.equilibrium import Cell
from .assembly import assemble_stiffness, gram_table, modulus, stiffness_rows, stiffness_stack
from .definite import positive_definite_factor
from .rigid import deformation_basis
from .._threads import hot_path

__all__ = ["dynamic_solves", "dynamic_stiffness", "dynamic_compliance", "dynamic_moduli", "dynamic_complex_modulus",
           "check_static_stability", "cytoplasm_damping", "exact_compliance", "laplace_compliance", "DynamicKernel",
           "dynamic_kernel", "batched_compliance"]


def _kstar(cell: Cell, kstar) -> np.ndarray:
    k = np.asarray(kstar)
    k = k[None, :] if k.ndim == 1 else k
    if k.ndim != 2 or k.shape[1] != cell.m:
        raise ValueError(f"kstar must have shape (n_omega, {cell.m}) (one dynamic tangent per tendon), got {np.shape(kstar)}")
    return k


@hot_path
def dynamic_stiffness(cell: Cell, P: float, kstar) -> np.ndarray:
    """``K(ω) = P·Σ T0_j ∇²l_j + Σ k*_j(ω) a_j a_jᵀ`` (N/m), complex, shape (n_omega, n, n); dense cells.

    Parameters
    ----------
    cell : Cell
    P : float
        Prestress scale (N): tensions ``P·T0``.
    kstar : ndarray, shape (n_omega, m) or (m,)
        Dynamic tangent of each tendon (N/m), e.g. ``law.complex_stiffness(cell.lengths, P*cell.T0, ω)``.
    """
    k = _kstar(cell, kstar)
    if cell.sparse:
        raise ValueError(f"{cell.describe()} is sparse: its K(ω) is not formed as a dense stack; "
                         "dynamic_compliance solves it frequency by frequency")
    return stiffness_stack(cell, P, k)


def dynamic_solves(cell: Cell, P: float, k: np.ndarray, both: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """``x = K⁻¹b`` and (if ``both`` and probe ≠ load) ``y = K⁻¹D0``, shape (n_omega, n) each."""
    b, d = np.asarray(cell.load, dtype=float), np.asarray(cell.probe, dtype=float)
    same = bool(np.array_equal(b, d))
    rhs = np.stack([b] if (same or not both) else [b, d], axis=1)  # (n, 1 or 2)
    if not cell.sparse:
        K = dynamic_stiffness(cell, P, k)
        N = deformation_basis(cell)
        if N is not None:  # free-standing: solve on the complement of the rigid-body motions, lift back
            Kr = np.einsum("ia,wij,jb->wab", N, K, N)
            sol = N @ np.linalg.solve(Kr, np.broadcast_to(N.T @ rhs, (k.shape[0], N.shape[1], rhs.shape[1]))
                                      .astype(complex))
        else:
            sol = np.linalg.solve(K, np.broadcast_to(rhs, (k.shape[0],) + rhs.shape).astype(complex))
    else:
        sol = np.empty((k.shape[0],) + rhs.shape, dtype=complex)
        for i in range(k.shape[0]):  # the same assembly as K0, with complex member tangents
            sol[i] = spla.splu(sp.csc_matrix(assemble_stiffness(cell, P, k[i]), dtype=complex)).solve(rhs.astype(complex))
    x = sol[:, :, 0]
    y = x if same else (sol[:, :, 1] if both else None)
    return x, y


@hot_path
def dynamic_compliance(cell: Cell, P: float, kstar, dkstar=None):
    """``J(ω) = D0 K(ω)⁻¹ b`` (m/N), and with ``dkstar`` also its exact derivatives.

    Parameters
    ----------
    cell : Cell
    P : float
        Prestress scale (N).
    kstar : ndarray, shape (n_omega, m)
        Dynamic tangents (N/m).
    dkstar : ndarray, shape (q, n_omega, m), optional
        ``∂k*_j/∂θ_q`` for q quantities θ (e.g. the second output of
        :meth:`~tenscell.laws.TendonLaw.complex_stiffness_derivatives`).

    Returns
    -------
    J : ndarray of complex, shape (n_omega,)
    dJ : ndarray of complex, shape (q, n_omega)
        Only with ``dkstar``: ``∂J/∂θ_q = −Σ_j ∂k*_jq (yᵀa_j)(a_jᵀx)`` (m/N per unit of θ_q).
    """
    P = positive_scalar("P (prestress)", P, "N")
    k = _kstar(cell, kstar)
    x, y = dynamic_solves(cell, P, k, both=dkstar is not None)
    J = x @ np.asarray(cell.probe, dtype=float)
    if dkstar is None:
        return J
    dk = np.asarray(dkstar)
    if dk.ndim != 3 or dk.shape[1:] != k.shape:
        raise ValueError(f"dkstar must have shape (q, {k.shape[0]}, {cell.m}), got {dk.shape}")
    A = cell.A
    assert y is not None  # both=True above
    prod = np.asarray((A.T @ y.T).T * (A.T @ x.T).T)  # (n_omega, m): (yᵀa_j)(a_jᵀx)
    return J, -np.einsum("qwm,wm->qw", dk, prod)


@dataclass(frozen=True, eq=False, repr=False)
class DynamicKernel:
    """A cell's matrices prepared for :func:`batched_compliance` (built by :func:`dynamic_kernel`).

    Dense cells are held on the complement ``N`` of their rigid-body motions (the identity when supports hold
    them): ``A = Nᵀ·cell.A``, ``H = Nᵀ·(Σ T0_j ∇²l_j)·N``, ``gram[j] = (a_j a_jᵀ)`` flattened, ``rhs = Nᵀ[b, D0]``.
    A sparse cell keeps only the cell (its points are solved one sparse LU each). Read-only arrays; nothing in it
    changes after construction, so it may cross process boundaries with the problem that holds it.
    """

    cell: Cell
    A: np.ndarray | None  # (n_r, m)
    H: np.ndarray | None  # (n_r, n_r)
    gram: np.ndarray | None  # (m, n_r·n_r)
    rhs: np.ndarray | None  # (n_r, 1 or 2): load, then the probe when it differs
    same: bool  # the probe is the load point (y = x)

    @property
    def m(self) -> int:
        """Number of tendons (columns of ``k*``)."""
        return self.cell.m


def dynamic_kernel(cell: Cell) -> DynamicKernel:
    """Prepare ``cell`` for :func:`batched_compliance` (one reduction and one table of ``a_j a_jᵀ``, read-only)."""
    b, d = np.asarray(cell.load, dtype=float), np.asarray(cell.probe, dtype=float)
    same = bool(np.array_equal(b, d))
    if cell.sparse:
        return DynamicKernel(cell=cell, A=None, H=None, gram=None, rhs=None, same=same)
    A = np.asarray(cell.A, dtype=float)
    H = np.asarray(cell.prestress_hessian, dtype=float)
    rhs = np.stack([b] if same else [b, d], axis=1)
    N = deformation_basis(cell)
    if N is not None:  # free-standing: the complement of the rigid-body motions, as in dynamic_solves
        A, H, rhs = N.T @ A, N.T @ H @ N, N.T @ rhs
    gram = gram_table(A)
    A, H, gram, rhs = (np.ascontiguousarray(x) for x in (A, H, gram, rhs))
    for x in (A, H, gram, rhs):
        x.setflags(write=False)
    return DynamicKernel(cell=cell, A=A, H=H, gram=gram, rhs=rhs, same=same)


def batched_compliance(kernel: DynamicKernel, P, kstar, gradient: bool = False):
    """``J = D0 K⁻¹ b`` (m/N) at many points at once, each with its own prestress and tangents.

    ``K_r = P_r·Σ_j T0_j ∇²l_j + Σ_j k*_rj a_j a_jᵀ`` for every row r: one matrix product assembles them all and
    one batched LU solves them (a sparse LU per row for a sparse cell). No validation: the caller (a fit's
    problem, which checked its inputs once) passes finite arrays of the right shapes.

    Parameters
    ----------
    kernel : DynamicKernel
        From :func:`dynamic_kernel`.
    P : ndarray, shape (R,)
        Prestress scale of each row (N), > 0.
    kstar : ndarray of complex, shape (R, m)
        Dynamic tangent of each tendon at each row (N/m).
    gradient : bool
        Also return the exact derivatives, from the same factorization.

    Returns
    -------
    J : ndarray of complex, shape (R,)
    dJ_dk : ndarray of complex, shape (R, m)
        Only with ``gradient``: ``∂J_r/∂k*_rj = −(yᵀa_j)(a_jᵀx)`` (m/N per N/m).
    dJ_dP : ndarray of complex, shape (R,)
        Only with ``gradient``: ``∂J_r/∂P_r`` at fixed ``k*`` ``= −yᵀ(Σ T0_j ∇²l_j)x`` (m/N per N).

    Raises
    ------
    numpy.linalg.LinAlgError
        A singular ``K_r``.
    """
    P = np.asarray(P, dtype=float)
    k = np.asarray(kstar)
    if kernel.gram is None:
        return _batched_sparse(kernel, P, k, gradient)
    assert kernel.H is not None
    # rows in chunks of at most 128 KiB of matrices: the C library serves larger blocks from fresh memory maps, whose
    # page faults cost more than the arithmetic (a fit of a mechanism over 8 assignments, 192 rows per evaluation:
    # 355k minor page faults and 1.8 s of CPU with 512 KiB chunks; 7 faults and 1.0 s with 128 KiB)
    step = max(1, _CHUNK_BYTES // (16 * kernel.H.size))
    if k.shape[0] <= step:
        return _dense_rows(kernel, P, k, gradient)
    parts = [_dense_rows(kernel, P[s:s + step], k[s:s + step], gradient) for s in range(0, k.shape[0], step)]
    if not gradient:
        return np.concatenate(parts)
    return tuple(np.concatenate(x) for x in zip(*parts))


#: the memory (bytes) of the stiffness matrices :func:`batched_compliance` forms at once
_CHUNK_BYTES = 2**17


def _dense_rows(kernel: DynamicKernel, P, k, gradient: bool):
    """:func:`batched_compliance` on a dense cell, for one chunk of rows."""
    assert kernel.H is not None and kernel.A is not None and kernel.rhs is not None and kernel.gram is not None
    K = stiffness_rows(kernel.H, kernel.gram, P, k)
    sol = np.linalg.solve(K, np.broadcast_to(kernel.rhs, (k.shape[0],) + kernel.rhs.shape))
    x = sol[:, :, 0]
    y = x if kernel.same else sol[:, :, 1]
    J = x @ kernel.rhs[:, -1]
    if not gradient:
        return J
    ax = x @ kernel.A
    ay = ax if kernel.same else y @ kernel.A
    return J, -(ay * ax), -np.einsum("ri,ri->r", y @ kernel.H, x)


def _batched_sparse(kernel: DynamicKernel, P, k, gradient: bool):
    """:func:`batched_compliance` for a sparse cell: one sparse LU per row (the assembly of K0, complex)."""
    cell = kernel.cell
    b, d = np.asarray(cell.load, dtype=float), np.asarray(cell.probe, dtype=float)
    rhs = np.stack([b] if kernel.same else [b, d], axis=1).astype(complex)
    R = k.shape[0]
    J = np.empty(R, dtype=complex)
    dk = np.empty((R, cell.m), dtype=complex) if gradient else None
    dP = np.empty(R, dtype=complex) if gradient else None
    A, H = cell.A, cell.prestress_hessian
    for r in range(R):
        sol = spla.splu(sp.csc_matrix(assemble_stiffness(cell, float(P[r]), k[r]), dtype=complex)).solve(rhs)
        x = sol[:, 0]
        y = x if kernel.same else sol[:, 1]
        J[r] = x @ d
        if gradient:
            assert dk is not None and dP is not None
            dk[r] = -np.asarray(A.T @ y) * np.asarray(A.T @ x)
            dP[r] = -(y @ (H @ x))
    return (J, dk, dP) if gradient else J


@hot_path
def check_static_stability(cell: Cell, law: TendonLaw, P: float) -> None:
    """Raise ``NotPositiveDefiniteError`` unless the static stiffness ``K(ω → 0)`` is positive definite.

    With passive tendons (``Re k*`` rising, ``Im k* ≥ 0``) a structure whose
    static stiffness is positive definite is stable at every frequency.
    """
    K = dynamic_stiffness_static(cell, law, P)
    N = None if cell.sparse else deformation_basis(cell)
    if N is not None:  # free-standing: stability on the complement of the rigid-body motions
        K = N.T @ K @ N
    positive_definite_factor(K, what="the static stiffness K(ω→0)",
                             describe=f"{cell.describe()} with {type(law).__name__} tendons at P={P:.6g} N")


def dynamic_stiffness_static(cell: Cell, law: TendonLaw, P: float):
    """``K(ω → 0)`` (N/m), real, dense or sparse like the cell."""
    k0 = np.asarray(law.complex_stiffness(cell.lengths, P * cell.T0, [0.0])[0].real)
    return assemble_stiffness(cell, P, k0)


@hot_path
def dynamic_complex_modulus(cell: Cell, law: TendonLaw, P: float, f_hz, *, viscosity: float = 0.0,
                            check: bool = True) -> np.ndarray:
    """``G* = (0.5/L)/J(ω) + iωη`` (Pa), complex, shape of ``f_hz`` raveled to (nf,).

    See :func:`dynamic_moduli`.
    """
    if not isinstance(law, TendonLaw):
        raise ValueError(f"law must be a tenscell.laws.TendonLaw, got {type(law).__name__}")
    if law.m is not None and law.m != cell.m:
        raise ValueError(f"the tendon law has {law.m} tendons but the cell has {cell.m}")
    P = positive_scalar("P (prestress)", P, "N")
    f = np.atleast_1d(positive_array("frequency", f_hz, unit="Hz")).ravel()
    eta = viscosity_value(viscosity)
    if check:
        check_static_stability(cell, law, P)
    w = 2 * np.pi * f
    J = dynamic_compliance(cell, P, law.complex_stiffness(cell.lengths, P * cell.T0, angular_frequencies(w)))
    return modulus(J, cell.strut_length) + 1j * w * eta


def viscosity_value(viscosity) -> float:
    """The cytoplasm viscosity η as a float (Pa·s), ≥ 0; ValueError naming it otherwise."""
    return float(positive_array("viscosity (cytoplasm)", viscosity, (), "Pa·s", allow_zero=True))


@hot_path
def dynamic_moduli(cell: Cell, law: TendonLaw, P: float, f_hz, *, viscosity: float = 0.0,
                   check: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Storage and loss moduli ``G'``, ``G''`` (Pa) of a cell with any tendon law, at frequencies ``f_hz`` (Hz).

    ``G' + iG'' = (0.5/L)/J(ω) + iωη`` with ``J(ω) = D0 K(ω)⁻¹ b`` from the
    law's exact dynamic tangent at tensions ``P·T0`` (no realization, no
    approximation) and a Newtonian cytoplasm of viscosity η in parallel.

    Parameters
    ----------
    cell : Cell
    law : TendonLaw
        Any law (need not be placed: its tangent is taken at tensions ``P·T0``).
    P : float
        Prestress scale (N), > 0.
    f_hz : float or array_like
        Frequencies (Hz), > 0.
    viscosity : float
        Cytoplasm viscosity η (Pa·s), ≥ 0; adds ``iωη`` to G* (G'' only).
    check : bool
        Verify that the static stiffness ``K(ω→0)`` is positive definite (one Cholesky).

    Returns
    -------
    G_storage, G_loss : ndarray, shape (nf,)
        In Pa.

    Raises
    ------
    NotPositiveDefiniteError
        If ``K(ω → 0)`` is not positive definite.
    """
    G = dynamic_complex_modulus(cell, law, P, f_hz, viscosity=viscosity, check=check)
    return G.real, G.imag


# ---- the cytoplasm and internal-variable realizations -----------------------------------------------------
def cytoplasm_damping(cell: Cell, viscosity: float):
    """``2L·η·D0ᵀD0`` (N·s/m), dense or sparse like the cell: a dashpot on the probe giving ``G* += iωη``.

    Exact for ``probe = load`` (Sherman–Morrison: ``1/J' = 1/J + iω·2Lη``);
    refused otherwise, where a dashpot on the probe is not "in parallel" with
    the measured modulus.
    """
    eta = viscosity_value(viscosity)
    b, d = np.asarray(cell.load, dtype=float), np.asarray(cell.probe, dtype=float)
    if not np.allclose(b, d, rtol=0, atol=1e-14 * max(np.abs(b).max(), 1e-300)):
        raise ValueError(f"a cytoplasm viscosity needs the probe to be the load point, which it is not in "
                         f"{cell.describe()}; use dynamic_moduli(..., viscosity=η), which adds iωη to G*")
    cd = 2.0 * cell.strut_length * eta
    if cell.sparse:
        nz = np.flatnonzero(d)
        D = sp.csr_matrix((d[nz], (np.zeros(nz.size, dtype=int), nz)), shape=(1, d.size))
        return (cd * (D.T @ D)).tocsr()
    return cd * np.outer(d, d)


@hot_path
def exact_compliance(lin, f_hz) -> np.ndarray:
    """``J(ω)`` (m/N) of a realized model from its law's exact dynamic tangent (and its cytoplasm), shape of f_hz."""
    f = positive_array("frequency", f_hz, unit="Hz")
    w = 2 * np.pi * np.atleast_1d(f).ravel()
    cell = lin.cell
    J = dynamic_compliance(cell, lin.P, lin.law.complex_stiffness(cell.lengths, lin.P * cell.T0, w))
    if lin.viscosity:
        J = J / (1.0 + 1j * w * (2.0 * cell.strut_length * lin.viscosity) * J)
    return J.reshape(np.shape(f))


@hot_path
def laplace_compliance(lin, s) -> np.ndarray:
    """``J(s) = D0 K(s)⁻¹ b`` (m/N) of a linear model from its law's exact ``k*(s)`` (and its cytoplasm), shape (n_s,).

    ``s`` (1/s): complex Laplace variables off the negative real axis (``J(iω)`` is :func:`exact_compliance`). For
    passive laws ``K(s)`` is invertible there, so an exact inversion of ``J(s)/s`` (creep) or ``1/(s·J(s))``
    (relaxation) may use any contour around that axis (:mod:`tenscell.timedomain`).
    """
    cell = lin.cell
    z = np.atleast_1d(np.asarray(s, dtype=complex)).ravel()
    J = dynamic_compliance(cell, lin.P, lin.law.laplace_stiffness(cell.lengths, lin.P * cell.T0, z))
    if lin.viscosity:
        J = J / (1.0 + z * (2.0 * cell.strut_length * lin.viscosity) * J)
    return J

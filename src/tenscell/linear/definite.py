"""Positive definiteness and the conditioning of C0: one criterion each, written once.

**The positive-definiteness criterion** (:func:`positive_definite_factor`):
a symmetric matrix is positive definite exactly when its Cholesky factor
exists — dense LAPACK (``potrf``), or sparse CHOLMOD
(:mod:`tenscell.linear.sparse`). A stable equilibrium is one whose K0 passes
it. Every question of definiteness in tenscell asks this function (or
:func:`is_positive_definite`, :func:`first_indefinite` for a stack of
matrices): a model's K0 (:attr:`tenscell.linear.pencil.Pencil.cholesky`),
each prestress of a grid or a loop (:class:`tenscell.linear.family.PrestressFamily`),
the static stiffness of a law with internal dynamics, trial references of a
form-finding search. The factor is kept where it serves later solves.

**The conditioning rule for C0** (:func:`damping_factor`): the pencil may be
taken into the basis where C0 is the identity (``C0 = Lc Lcᵀ``; the prestress
family, the fits' whitened basis) when C0 passes the criterion above and the
accuracy that basis costs is within the caller's tolerance. That cost is
about ``ε·span`` relative in the compliance, ``span = max d/min d`` over the
squared pivots ``d = diag(Lc)²`` of C0's Cholesky factor (a cheap lower bound
of its condition number) and ε the double-precision rounding unit: measured
on the paper cell with damping spread over decades, spans of 3.2·10³, 5·10⁴,
10⁶, 2.5·10⁷ and 7.4·10⁸ cost 6·10⁻¹⁴, 4·10⁻¹³, 8·10⁻¹², 2·10⁻¹⁰ and
2·10⁻⁹. The tolerances: :data:`EXACT_RTOL` where an exact route exists (a
model's own K0 factor), :data:`FIT_RTOL` where none does (the fits). A C0 whose
span passes neither is singular for every purpose (a mode no tendon damps,
e.g. the nucleated cell's, whose Cholesky passes on rounding noise with
span 2·10¹⁶).

The dense LAPACK kernels the pencil and the family share (triangular solves,
whitening, one symmetric eigensolve) are here too, called without the
wrappers' checks on the hot paths.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg.lapack
import scipy.sparse as sp

from .._errors import NotPositiveDefiniteError
from .sparse import factorize_spd

__all__ = ["positive_definite_factor", "is_positive_definite", "first_indefinite", "damping_factor", "damping_span",
           "EXACT_RTOL", "FIT_RTOL"]

#: the accuracy (relative, in the compliance) a consumer with an exact alternative gives up by whitening by C0
#: (the prestress family, against each model's own K0 factor): a span up to about 4.5·10³
EXACT_RTOL = 1e-12
#: the same for consumers with no other route (the fits' whitened basis): a span up to about 4.5·10⁹
FIT_RTOL = 1e-6
_EPS = float(np.finfo(float).eps)

_potrf = scipy.linalg.lapack.dpotrf
_trtrs = scipy.linalg.lapack.dtrtrs
_syevd = scipy.linalg.lapack.dsyevd


def _dense_factor(M: np.ndarray) -> np.ndarray | None:
    """Lower Cholesky factor of a dense symmetric M, or None when it does not exist (a pivot ≤ 0)."""
    L, info = _potrf(M, lower=1, clean=1, overwrite_a=0)
    if info != 0:
        return None
    return L


def positive_definite_factor(M, *, what: str = "K0", describe: str = "the model", hint: str = "", perm=None):
    """The Cholesky factor of a symmetric matrix, which exists exactly when it is positive definite.

    The one criterion of positive definiteness in tenscell (a stable
    equilibrium is one whose K0 passes it): dense LAPACK Cholesky, or sparse
    CHOLMOD (:mod:`tenscell.linear.sparse`).

    Parameters
    ----------
    M : ndarray or sparse matrix, shape (n, n)
        Symmetric (only its lower triangle is read).
    what, describe, hint : str
        For the message: the matrix's name, the model it belongs to, advice appended.
    perm : ndarray of int, shape (n,), optional
        Sparse only: the fill-reducing ordering to factor with (default CHOLMOD's AMD).

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
    """
    if sp.issparse(M):
        try:
            return factorize_spd(M, what=what, perm=perm)
        except NotPositiveDefiniteError as err:
            detail = f"a pivot of its sparse Cholesky factorization is <= 0, at column {err.column}"
    else:
        M = np.asarray(M, dtype=float)
        L = _dense_factor(M)
        if L is not None:
            return L
        # the message only: how far from definite (the criterion is the factor's existence)
        detail = f"smallest eigenvalue {float(np.linalg.eigvalsh(M)[0]):.3g}"
    raise NotPositiveDefiniteError(
        f"{what} is not positive definite for {describe} ({detail}): "
        "the reference is not a stable equilibrium." + (f" {hint}" if hint else "")
    )


def is_positive_definite(M) -> bool:
    """Whether the symmetric matrix ``M`` (dense or sparse) passes :func:`positive_definite_factor`."""
    try:
        positive_definite_factor(M)
    except NotPositiveDefiniteError:
        return False
    return True


def first_indefinite(stack: np.ndarray) -> int | None:
    """The index of the first matrix of a stack (k, n, n) that is not positive definite, or None.

    The criterion of :func:`positive_definite_factor`, batched: one stacked Cholesky, and
    one matrix at a time only when it fails somewhere.
    """
    try:
        np.linalg.cholesky(stack)
        return None
    except np.linalg.LinAlgError:
        pass
    for i, M in enumerate(stack):
        if _dense_factor(M) is None:
            return i
    return None  # pragma: no cover - the batched and the single factorizations agree


def damping_span(Lc: np.ndarray) -> float:
    """``max d / min d`` over the squared pivots ``d = diag(Lc)²`` of a Cholesky factor (≥ 1; inf if a pivot is 0)."""
    d = np.diagonal(Lc) ** 2
    return float(d.max() / d.min()) if d.min() > 0 else float("inf")


def damping_factor(C0: np.ndarray, rtol: float = EXACT_RTOL) -> np.ndarray | None:
    """The lower Cholesky factor ``Lc`` of a dense C0 (N·s/m) when the pencil may be whitened by it, else None.

    The one conditioning rule for C0: C0 is positive definite (:func:`positive_definite_factor`)
    and ``ε·span`` (:func:`damping_span`), the relative accuracy whitening by it costs, is at
    most ``rtol`` (:data:`EXACT_RTOL` where an exact route exists, :data:`FIT_RTOL` for the fits).
    """
    Lc = _dense_factor(np.asarray(C0, dtype=float))
    if Lc is None or not _EPS * damping_span(Lc) <= rtol:
        return None
    return Lc


# ---- dense LAPACK kernels shared by the pencil and the prestress family ------------------------------
def tri(L: np.ndarray, B: np.ndarray, trans: int = 0) -> np.ndarray:
    """``L⁻¹B`` (``L⁻ᵀB`` with trans=1) for a lower-triangular L: LAPACK trtrs without the wrapper's checks."""
    X, info = _trtrs(L, B, lower=1, trans=trans)
    if info != 0:  # pragma: no cover - L comes from a successful Cholesky
        raise np.linalg.LinAlgError(f"triangular solve failed (info={info})")
    return X


def whiten(L: np.ndarray, M: np.ndarray) -> np.ndarray:
    """``L⁻¹ M L⁻ᵀ`` (symmetrized) for a lower-triangular L, with M of shape (n, n)."""
    X = tri(L, M)
    X = tri(L, X.T)
    return 0.5 * (X + X.T)


def symmetric_eigen(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and orthonormal eigenvectors of one dense symmetric matrix (LAPACK syevd directly:
    the batched numpy call's overhead is a fifth of a 24×24 eigensolve)."""
    lam, U, info = _syevd(M, lower=1)
    if info != 0:  # pragma: no cover - a symmetric eigensolve of a finite matrix converges
        raise np.linalg.LinAlgError(f"symmetric eigensolve failed (info={info})")
    return lam, U

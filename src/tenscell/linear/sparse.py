"""Sparse Cholesky factorization for large structures (internal): CHOLMOD, through cvxopt.

``P A Pᵀ = L Lᵀ`` by CHOLMOD's supernodal Cholesky, with a given fill-reducing
ordering (the geometric nested dissection of :mod:`tenscell.linear.ordering`
for large structures) or CHOLMOD's own (AMD). A symmetric matrix is positive definite exactly when this
factorization exists, so one factorization both proves positive definiteness
and serves every solve (the Lanczos runs of :mod:`tenscell.linear.krylov`).

Why CHOLMOD: measured on this project's 3D lattices (``bench/bench_scale.py``
before this ordering existed), analysis + factorization + one solve of the
11,520-coordinate stiffness took 0.17–0.27 s against 0.65–0.94 s for SuperLU
with a hand-written nested-dissection ordering and 0.8–1.0 s for
``cholespy`` (all three agree to 1e-14). cvxopt ships CHOLMOD in binary
wheels; it is the ``large`` extra (structures above 1,500 coordinates).
"""
from __future__ import annotations

from contextlib import contextmanager
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .._errors import NotPositiveDefiniteError
from .._optional import require

__all__ = ["NotPositiveDefinite", "SparseCholesky", "factorize_spd"]


#: the sparse factorization's name for the one not-positive-definite error (its ``column`` says where it stopped)
NotPositiveDefinite = NotPositiveDefiniteError


class SparseCholesky:
    """``P A Pᵀ = L Lᵀ`` of a sparse symmetric positive definite matrix (CHOLMOD).

    Use :func:`factorize_spd` to make one. ``solve`` accepts real or complex
    right-hand sides, one vector or an ``(n, k)`` block.
    """

    def __init__(self, factor, n: int, source=None, perm=None):
        self._factor = factor
        self._source = source  # the scipy matrix factored (for the fill diagnostic; not a copy)
        self._perm = perm
        self.n = n

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``A⁻¹ b`` for b of shape (n,) or (n, k), real or complex."""
        from cvxopt import cholmod, matrix

        b = np.asarray(b)
        if np.iscomplexobj(b):
            return self.solve(b.real) + 1j * self.solve(b.imag)
        B = matrix(np.array(b, dtype=float, order="C"))
        cholmod.solve(self._factor, B)
        return np.array(B).reshape(b.shape)

    @cached_property
    def fill(self) -> int:
        """Stored nonzeros of the factor L (a diagnostic: costs one more factorization of a copy)."""
        from cvxopt import cholmod

        # CHOLMOD converts a factor in place to hand it out, so read it from a throwaway one
        M = _to_cvxopt(self._source)
        F = _symbolic(M, self._perm)
        cholmod.numeric(M, F)
        return len(cholmod.getfactor(F))


def _to_cvxopt(A):
    spmatrix = require("cvxopt").spmatrix  # an optional dependency: one line naming the extra

    low = sp.tril(sp.coo_matrix(A)).tocoo()
    n = A.shape[0]
    return spmatrix(low.data.astype(float), low.row.astype(np.int64), low.col.astype(np.int64), (n, n))


@contextmanager
def _given_ordering_only():
    """CHOLMOD told to use the caller's permutation as it is.

    By default CHOLMOD compares a given permutation with AMD and keeps the one
    with less fill, which on some matrices discards the nested dissection. cvxopt
    reads its module-level ``options`` at each call, so the setting is made for
    this call and restored (tenscell factors in one thread per process).
    """
    from cvxopt import cholmod

    before = cholmod.options.get("nmethods")
    cholmod.options["nmethods"] = 1
    try:
        yield
    finally:
        if before is None:
            del cholmod.options["nmethods"]
        else:
            cholmod.options["nmethods"] = before


def _symbolic(M, perm):
    """CHOLMOD's symbolic analysis of M with the permutation ``perm`` (or AMD when None)."""
    cvx = require("cvxopt")
    from cvxopt import cholmod

    if perm is None:
        return cholmod.symbolic(M)
    with _given_ordering_only():
        return cholmod.symbolic(M, p=cvx.matrix(np.asarray(perm, dtype=int), tc="i"))


def factorize_spd(A, what: str = "the matrix", perm: np.ndarray | None = None) -> SparseCholesky:
    """Cholesky-factor a sparse symmetric matrix, proving it positive definite.

    Parameters
    ----------
    A : sparse matrix, shape (n, n)
        Symmetric; only its lower triangle is read.
    what : str
        Name of the matrix in the error message.
    perm : ndarray of int, shape (n,), optional
        Fill-reducing permutation (row ``i`` of the factored matrix is row
        ``perm[i]`` of A), e.g. :func:`tenscell.linear.ordering.nested_dissection`;
        default CHOLMOD's AMD.

    Raises
    ------
    NotPositiveDefinite
        If a pivot is not positive (the matrix is indefinite or singular).
    """
    cholmod = require("cvxopt.cholmod")

    n = A.shape[0]
    M = _to_cvxopt(A)
    F = _symbolic(M, perm)
    try:
        cholmod.numeric(M, F)
    except ArithmeticError as err:
        col = int(err.args[0]) if err.args and isinstance(err.args[0], int) else -1
        raise NotPositiveDefinite(
            f"{what} is not positive definite (its Cholesky factorization meets a pivot <= 0 at column {col} "
            "of the reordered matrix)", col,
        ) from None
    del M  # CHOLMOD keeps its own copy in the factor: the lower triangle need not stay alive
    return SparseCholesky(F, n, A, perm)

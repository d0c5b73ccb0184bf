"""The base of every error tenscell raises on purpose (a leaf module: anything may import it).

``except tenscell.TenscellError`` catches them all; each class keeps the
built-in base that describes its kind (most are also a ``ValueError``: bad
input or a model that does not exist at these parameters), so code written
against those bases keeps working.
"""
from __future__ import annotations

__all__ = ["TenscellError", "NotPositiveDefiniteError"]


class TenscellError(Exception):
    """Base class of every error tenscell raises on purpose."""


class NotPositiveDefiniteError(TenscellError, ValueError):
    """A matrix that must be positive definite is not: for K0, the reference is not a stable equilibrium.

    Attributes
    ----------
    column : int or None
        Column (of the reordered matrix) at which a sparse Cholesky
        factorization stopped; None for dense matrices.
    """

    def __init__(self, message: str, column: int | None = None):
        super().__init__(message)
        self.column = column

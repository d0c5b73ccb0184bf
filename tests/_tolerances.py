"""Tolerances that follow from the conditioning of what a test checks (shared by the test modules).

Results differ in the last bits between CPUs and BLAS kernels (OpenBLAS picks Haswell, Sandybridge,
Prescott... by CPU); a tolerance must cover what rounding can do to the quantity checked, and no more:

* a backward-stable solve (Cholesky, LU) or symmetric eigensolve with an n×n matrix M has a backward
  error of a few n·eps, which the condition number κ(M) amplifies into the answer's relative error;
* a sum over modes weights each retardation time τ_k with a relative error ~ eps·τ_max/τ_k (the eigenvalues
  of the K0-whitened C0 have absolute errors ~ eps·τ_max).

The factor 4 covers the constants of these bounds. The quantities the tests check are quadratic forms
D0 M⁻¹ D0ᵀ or sums of positive modal terms (probe = load), which have no cancellation to amplify them further.
"""
from __future__ import annotations

import numpy as np

#: float64 unit round-off
EPS = float(np.finfo(float).eps)


def solve_rtol(M) -> float:
    """Relative accuracy of a solve or symmetric eigensolve with the n×n matrix M: 4·n·eps·κ(M)."""
    M = np.asarray(M)
    return 4 * M.shape[0] * EPS * float(np.linalg.cond(M))


def modal_rtol(lin) -> float:
    """Relative accuracy of a response of a dense linear model summed over its modes (whitened pencil).

    ``solve_rtol(K0)`` for the whitening, plus 4·n·eps·τ_max/τ_min for the retardation times.
    """
    K0 = np.asarray(lin.K0)
    tau = np.asarray(lin.pencil.modes.tau)
    tau = tau[tau > 0]
    spread = float(tau.max() / tau.min()) if tau.size else 1.0
    return solve_rtol(K0) + 4 * K0.shape[0] * EPS * spread

"""Grids and loops of prestresses: the dense pencils ``(P·Kp + Km, C0)`` of one cell with one set of tendons.

K0 is affine in the prestress P and C0 does not depend on it, so C0 is
whitened once (``C0 = Lc Lcᵀ``, when the conditioning rule of
:mod:`tenscell.linear.definite` allows it) and each prestress costs one
symmetric eigensolve of ``P·K̃p + K̃m``. The grid
(:func:`prestress_grid_compliance`, :func:`tenscell.frequency_response`) and
a loop of :func:`tenscell.linearize` over prestresses (each model's
:attr:`Pencil.modes <tenscell.linear.pencil.Pencil.modes>`) share one
:class:`PrestressFamily`, so both give the same numbers. Each K0 is checked by
the one positive-definiteness criterion (its Cholesky factor exists; batched
for a grid).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .._errors import NotPositiveDefiniteError
from .._threads import hot_path
from .definite import EXACT_RTOL, damping_factor, first_indefinite, is_positive_definite, symmetric_eigen, tri, whiten
from .spectrum import Modes, modal_compliance

__all__ = ["PrestressFamily", "prestress_grid_modes", "prestress_grid_compliance"]

#: rows of prestresses per block of the grid's modal sum (keeps the block in cache)
_GRID_BLOCK = 8


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
        Rates λ (1/s), ascending (all > 0 when that K0 is positive definite).
    U : ndarray, shape (nP, n, n)
        Orthonormal modes (columns); ``v = L⁻ᵀu`` are C0-orthonormal.
    """
    P = np.asarray(P, dtype=float)
    return np.linalg.eigh(P[:, None, None] * np.asarray(Kpt) + np.asarray(Kmt))


@dataclass(frozen=True, eq=False)
class PrestressFamily:
    """The dense pencils ``(P·Kp + Km, C0)`` of one cell with one set of tendons, for every prestress P.

    Build with :meth:`build`, which returns None when C0 may not be whitened by
    (:func:`tenscell.linear.definite.damping_factor` at
    :data:`~tenscell.linear.definite.EXACT_RTOL`: each model's own K0 factor is the exact route).

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
        """The family of ``(P·Kp + K_material, C0)`` (dense, N/m and N·s/m), or None if C0 may not be whitened by."""
        C0 = np.array(C0, dtype=float)
        Lc = damping_factor(C0, EXACT_RTOL)
        if Lc is None:
            return None
        C0.flags.writeable = False
        Kp, Km = np.asarray(Kp), np.asarray(K_material)
        return cls(Kp=Kp, Km=Km, C0=C0, Lc=Lc, Kpt=whiten(Lc, Kp), Kmt=whiten(Lc, Km),
                   bt=tri(Lc, np.asarray(load, dtype=float)), dt=tri(Lc, np.asarray(probe, dtype=float)))

    def stiffness(self, P: float) -> np.ndarray:
        """``K0 = P·Kp + Km`` (N/m) at prestress ``P`` (N)."""
        return P * self.Kp + self.Km

    def rates(self, P: np.ndarray, describe: str = "the model", hint: str = "") -> tuple[np.ndarray, np.ndarray]:
        """Relaxation rates λ (1/s, ascending, all > 0) and orthonormal modes U of every prestress ``P`` (N, shape (nP,)).

        Raises
        ------
        NotPositiveDefiniteError
            If K0 is not positive definite at some P (its Cholesky factor does not exist).
        """
        bad = first_indefinite(P[:, None, None] * self.Kp + self.Km)
        lam, U = prestress_grid_modes(self.Kpt, self.Kmt, P)
        if bad is not None:
            raise _unstable(P[bad], lam[bad, 0], describe, hint)
        return lam, U

    def modes(self, P: float, describe: str = "the model", hint: str = "", *, checked: bool = False) -> Modes:
        """The modal decomposition of the pencil at prestress ``P`` (N), as :attr:`Pencil.modes` gives it.

        ``τ = 1/λ`` ascending, weights ``(d̃·u)(b̃·u)/λ``, K0-orthonormal vectors ``Lc⁻ᵀu/√λ`` (formed on first
        use: a compliance needs only τ and ρ). ``checked``: K0 at P is already known to be positive definite.

        Raises
        ------
        NotPositiveDefiniteError
            If K0 is not positive definite at P (the one criterion, as for the grid).
        """
        lam, U = symmetric_eigen(P * self.Kpt + self.Kmt)
        if not checked and not is_positive_definite(self.stiffness(P)):
            raise _unstable(P, lam[0], describe, hint)
        U = U[:, ::-1]  # ascending in τ = 1/λ
        tau = 1.0 / lam[::-1]
        d, b = self._probe_load @ U
        return Modes(tau=tau, weights=d * b * tau, make_vectors=_ModeVectors(self.Lc, U, tau))

    @cached_property
    def _probe_load(self) -> np.ndarray:
        """``[d̃; b̃]``, shape (2, n): one product gives both projections of every mode."""
        return np.stack([self.dt, self.bt])

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


class _ModeVectors:
    """The K0-orthonormal modes ``Lc⁻ᵀU·diag(√τ)`` of a family member, formed when first asked for."""

    __slots__ = ("Lc", "U", "tau")

    def __init__(self, Lc, U, tau):
        self.Lc, self.U, self.tau = Lc, U, tau

    def __call__(self) -> np.ndarray:
        V = tri(self.Lc, np.asarray(self.U, order="F"), trans=1)
        V *= np.sqrt(self.tau)
        return V


def _unstable(P: float, rate: float, describe: str, hint: str) -> NotPositiveDefiniteError:
    return NotPositiveDefiniteError(
        f"K0 is not positive definite for {describe} at P={P:.6g} (its Cholesky factor does not exist; smallest "
        f"relaxation rate {rate:.3g} 1/s): the reference is not a stable equilibrium." + (f" {hint}" if hint else "")
    )


@hot_path
def prestress_grid_compliance(Kp, K_material, C0, load, probe, P: np.ndarray, w: np.ndarray,
                              describe: str = "the model") -> np.ndarray | None:
    """``J(iω)`` (m/N) of the dense pencils ``(P·Kp + K_material, C0)`` for many prestresses at once.

    C0 is the same for every P, so it is whitened once (:class:`PrestressFamily`);
    one batched symmetric eigensolve of ``P·K̃p + K̃m`` gives every P's rates,
    each K0 is checked by one batched Cholesky, and the modal sum runs in
    blocks of prestresses that stay in cache.

    Returns
    -------
    ndarray of complex, shape (nP, nf), or None
        None when C0 may not be whitened by (use the per-model path).

    Raises
    ------
    NotPositiveDefiniteError
        If K0 is not positive definite at some P.
    """
    family = PrestressFamily.build(Kp, K_material, C0, load, probe)
    return None if family is None else family.compliance(np.asarray(P, dtype=float), w, describe)

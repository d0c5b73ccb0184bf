"""The fitting problem: a cell's linear model against data, a parameter layout, residuals and their analytic Jacobian.

Parameters and units
--------------------
* ``EA`` (N): per tendon (``tendons="per-tendon"``, 33 values for the paper
  cell), per family (actin / intermediate filament) or one for all.
* ``c`` (N·s/m): one value (the paper) or per family (``damping="per-family"``).
* The prestress. Where a data set states the prestress at which it was
  measured (a ``prestress_Pa`` column: a prestress sweep, or a frequency sweep
  at a stated prestress), the model prestress of each point is ``s·P_exp`` and
  the parameter is the scale ``s`` (m², since ``P_exp`` is in Pa): one ``s``
  links every data set. A data set that does not state its prestress gets its
  own fitted prestress, ``P_data[k]`` (Pa, on the same scale ``s``) in a joint
  fit, or the model prestress ``P`` (N) directly when no data set states one
  (``P[k]`` for several such data sets).
* ``L`` (m): strut length. For the linear moduli it is exactly redundant: a
  cell scaled by λ (all lengths ×λ) with ``(P, EA, c) -> (λ²P, λ²EA, λc)`` has
  the same G' and G'', so ``(P, EA, c, L) -> (λ²P, λ²EA, λc, λL)`` is an exact
  gauge. It is fitted as the paper did, starts at the cell's own L and stays
  there unless other parameters are fixed or hit bounds; fix P or c to make it
  identifiable.

Everything is fitted in natural-log space within bounds. Residuals are
``w·(log10 G_model − log10 G_data)`` for G' and G'' of every point of every
data set (``w`` = 1, or ``1/sd(log10 G)`` when the data have standard
deviations). The Jacobian is analytic, from the relaxation spectrum
``K0 v = λ C0 v``: with ``x = Z⁻¹(−H0)``, ``y = Z⁻ᵀ D0ᵀ`` and
``Z = K0 + iωC0``, ``∂J/∂EA_j = −(yᵀa_j)(a_jᵀx)/l_j``,
``∂J/∂c_j = −iω(yᵀa_j)(a_jᵀx)``, ``∂J/∂P = −yᵀKp x``, all frequencies at once
from a few matrix products.

Two options shape the search space:

``min_prestress_share``
    The prestress share of the static stiffness, ``P·yᵀKp x / yᵀK0 x`` at
    ω → 0 (equal to ``∂ln G(0)/∂ln P``), must stay at or above this value at
    every prestress of the data. Enforced as a one-sided penalty residual
    ``ρ·ln(S_min/share)`` (zero when satisfied), with its exact Jacobian; the
    share is scale-free, so it depends on P relative to the stiffnesses only.
``min_prestress_elasticity``
    ``∂ln G'/∂ln P`` at ``elasticity_frequency_hz`` (default 0.1 Hz, where
    cells show about 0.7) must stay at or above this value at every prestress
    of the data; the same kind of penalty, with the exact Jacobian of
    ``Re(G·e)/Re(G)``, ``e = P·yᵀKp x / J`` at that frequency. The static
    share can be large while G' at the data's frequencies does not respond to
    P (the tendons' dashpots stiffen them there), so this is the constraint
    that keeps the measured response prestress-driven.
``max_decades``
    The spread ``log10(max EA / min EA)`` of the fitted stiffnesses is at most
    ``D``: the search works in coordinates ``ln EA_j = m + D·ln10·σ_j`` with
    ``σ_j ∈ [−½, ½]`` and ``m`` within the EA bounds shrunk by ``D/2``. Box
    bounds on (m, σ) are exactly the constraint (any set of stiffnesses within
    the bounds whose spread is ≤ D has such a representation), so the
    trust-region solver enforces it at every iterate, and the Jacobian follows
    by the chain rule. A penalty would only approximate the bound.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from .._checks import positive_scalar
from .._results import format_repr
from ..io.data import DataError, RheologyData
from ..laws import Voigt
from ..linear.modal import modulus, prestress_grid_modes
from ..model.equilibrium import Cell
from .result import FitParameter

__all__ = ["TENDON_MODES", "DAMPING_MODES", "FitProblem", "make_problem", "required_points", "as_datasets"]

#: how tendon stiffnesses are parametrized
TENDON_MODES = ("per-tendon", "per-family", "uniform")
#: how tendon damping is parametrized
DAMPING_MODES = ("uniform", "per-family")

_LN10 = math.log(10.0)
# A residual (in decades) returned where the model is not a stable, passive
# cell (K0 not positive definite, G' or G'' <= 0). Finite, so that the
# trust-region solver simply rejects the step.
_PENALTY = 10.0
# Weight of the prestress-share penalty residual ρ·ln(S_min/share): a shortfall of
# 1 % of the share costs as much as a 0.003-decade misfit of one point... times ρ/0.3
_SHARE_WEIGHT = 30.0


def _whiten(Lc, A, H, load, probe):
    """A, H (symmetric), load, probe in the basis where C0 = Lc Lcᵀ becomes the identity."""
    solve = scipy.linalg.solve_triangular
    B = solve(Lc, A, lower=True, check_finite=False)
    X = solve(Lc, H, lower=True, check_finite=False)
    Ht = solve(Lc, X.T, lower=True, check_finite=False)
    bt = solve(Lc, load, lower=True, check_finite=False)
    Dt = solve(Lc, probe, lower=True, check_finite=False)
    return B, 0.5 * (Ht + Ht.T), bt, Dt


def _tangents(EA, c, lengths, T0, P):
    """The Voigt law's tangents at tensions ``P_g·T0`` for every prestress group (the one place the fit meets the law).

    Returns ``(k, dk, dk_dT·T0, eta, deta)``: tangent stiffness ``k`` (groups, m)
    in N/m with its derivative by ``ln EA_j`` and the prestress derivative
    ``∂k/∂P = (∂k/∂T)·T0`` (groups, m); tangent damping ``η`` (m,) in N·s/m with
    its derivative by ``ln c_j``. From :meth:`tenscell.laws.Voigt.tangent`.
    """
    g, m = P.size, EA.size
    law = Voigt._trusted(EA=np.tile(EA, g), c=np.tile(c, g))
    tg = law.tangent(np.tile(lengths, g), (P[:, None] * T0[None]).ravel())
    i_ea, i_c = tg.row("EA"), tg.row("c")
    shape = (g, m)
    k = tg.k.reshape(shape)
    dk = (tg.dk[i_ea] * law.EA).reshape(shape)
    kP = (tg.dk_dT * np.tile(T0, g)).reshape(shape)
    eta, deta = tg.c[:m], tg.dc[i_c][:m] * c
    return k, dk, kP, eta, deta


@dataclass(frozen=True, eq=False)
class _Spectrum:
    """The relaxation spectrum of the model at one parameter vector, per prestress group."""

    P: np.ndarray  # (groups,) effective prestress (N) on the reference cell
    dk: np.ndarray  # (groups, m) d k_j / d ln EA_j (N/m)
    deta: np.ndarray  # (m,) d η_j / d ln c_j (N·s/m)
    B: np.ndarray  # (n, m) whitened tendon directions
    Kpt: np.ndarray  # (groups, n, n) whitened ∂K0/∂P = Σ T0_j ∇²l_j + Σ (∂k_j/∂P) a_j a_jᵀ
    lam: np.ndarray  # (groups, n) relaxation rates (1/s)
    W: np.ndarray  # (groups, n, n) C0-orthonormal modes (whitened)
    alpha: np.ndarray  # (groups, n) probe projections
    beta: np.ndarray  # (groups, n) load projections


@dataclass(frozen=True, eq=False)
class _Evaluation:
    """Moduli, their log-derivatives and the prestress share at one parameter vector."""

    G: np.ndarray  # (N,) complex moduli (Pa)
    dlogG: np.ndarray | None  # (N, n_params) d ln G / d phi
    share: np.ndarray | None  # (groups,) prestress share of the static stiffness
    dshare: np.ndarray | None  # (groups, n_params) d ln share / d phi
    elasticity: np.ndarray | None = None  # (groups,) ∂ln G'/∂ln P at elasticity_omega
    delasticity: np.ndarray | None = None  # (groups, n_params) its d ln / d phi
    Jc: np.ndarray | None = None  # (Nc,) creep compliance at the creep data's times (1/Pa)
    dlogJc: np.ndarray | None = None  # (Nc, n_params) d ln Jc / d phi


# ---------------------------------------------------------------------------------
# the problem: model, data, parameter layout
# ---------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class FitProblem:
    """The linear model of a cell against one or several data sets, with a parameter layout.

    Built by :func:`make_problem`; holds plain arrays only, so that it can be
    sent to worker processes. The parameter vector ``theta`` holds the natural
    logarithms of the *free* parameters, in the order of :attr:`names`
    restricted to :attr:`free`. Parameters are laid out as stiffness groups,
    damping groups, prestress parameters, then ``L``.

    Attributes
    ----------
    names : tuple of str
        All parameter names.
    units, descriptions, kinds : tuple of str
        ``kinds`` is one of ``"EA"``, ``"c"``, ``"P"``, ``"s"``, ``"P_data"``, ``"L"`` per parameter.
    lower, upper : ndarray
        Log-space bounds of all parameters.
    free : ndarray of bool
    fixed_log : ndarray
        Log values of all parameters (used for the fixed ones).
    sources : tuple of str
        The data sets' sources, in order.
    dataset_index : ndarray of int, shape (N,)
        Data set of each point (the points of all data sets, concatenated).
    group_index : ndarray of int, shape (N,)
        Prestress group of each point.
    group_measured : ndarray, shape (groups,)
        Measured prestress (Pa) of each group, NaN where the data set did not state it.
    group_dataset : ndarray of int, shape (groups,)
    min_prestress_share, min_prestress_elasticity, max_decades : float or None
        The search-space options (module docstring).
    elasticity_omega : float
        Angular frequency (rad/s) of ``min_prestress_elasticity``.
    """

    names: tuple
    units: tuple
    descriptions: tuple
    kinds: tuple
    lower: np.ndarray
    upper: np.ndarray
    free: np.ndarray
    fixed_log: np.ndarray
    tendons: str
    damping: str
    n_ea: int
    n_c: int
    ea_groups: np.ndarray
    c_groups: np.ndarray
    # cell (reference strut length L_ref)
    A: np.ndarray
    lengths: np.ndarray
    T0: np.ndarray
    H: np.ndarray
    load: np.ndarray
    probe: np.ndarray
    L_ref: float
    white_unit: tuple
    # data
    sources: tuple
    omega: np.ndarray
    dataset_index: np.ndarray
    group_index: np.ndarray
    group_log_offset: np.ndarray
    group_map: np.ndarray
    group_measured: np.ndarray
    group_dataset: np.ndarray
    y_obs: np.ndarray
    weights: np.ndarray
    # search
    scale_stiffness: float
    scale_damping: float
    prestress_matters: bool
    min_prestress_share: float | None = None
    max_decades: float | None = None
    min_prestress_elasticity: float | None = None
    elasticity_omega: float = 2 * math.pi * 0.1
    # creep data (times after a stress step): their residuals follow the moduli's in y_obs and weights
    creep_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    creep_dataset: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    creep_group: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))

    def __repr__(self) -> str:
        opts = [f"{k}={v:g}" for k, v in (("min_prestress_share", self.min_prestress_share),
                                         ("min_prestress_elasticity", self.min_prestress_elasticity),
                                         ("max_decades", self.max_decades)) if v is not None]
        return format_repr(
            f"FitProblem: {self.n_datasets} data set(s), {self.n_points} points, {self.n_groups} prestress(es)",
            f"{self.n_free} free of {self.n_params} parameters (stiffness {self.tendons}, damping {self.damping}); "
            f"{self.n_residuals} residuals" + (f"; {', '.join(opts)}" if opts else ""),
        )

    # -- layout -------------------------------------------------------------------
    @property
    def n_params(self) -> int:
        """Number of all parameters (free and fixed)."""
        return len(self.names)

    @property
    def n_free(self) -> int:
        """Number of free parameters (length of ``theta``)."""
        return int(self.free.sum())

    @property
    def n_points(self) -> int:
        """Number of data points, all data sets together."""
        return int(self.omega.size)

    @property
    def n_residuals(self) -> int:
        """Number of data residuals: 2 per moduli point (G' and G''), 1 per creep point."""
        return int(self.y_obs.size)

    @property
    def n_creep(self) -> int:
        """Number of creep points, all creep data sets together (their residuals come last)."""
        return int(self.creep_t.size)

    @property
    def n_datasets(self) -> int:
        """Number of data sets fitted together."""
        return len(self.sources)

    @property
    def n_groups(self) -> int:
        """Number of distinct model prestresses (one eigendecomposition each)."""
        return int(self.group_map.shape[0])

    @property
    def prestress_slice(self) -> slice:
        """Positions of the prestress parameters in :attr:`names`."""
        return slice(self.n_ea + self.n_c, self.n_params - 1)

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Log-space bounds of the free parameters."""
        return self.lower[self.free], self.upper[self.free]

    def full(self, theta) -> np.ndarray:
        """Log values of all parameters from the free ones."""
        phi = self.fixed_log.copy()
        phi[self.free] = theta
        return phi

    def values(self, theta) -> np.ndarray:
        """Parameter values (SI units) of all parameters, in the order of :attr:`names`."""
        return np.exp(self.full(theta))

    def rows(self, dataset: int) -> np.ndarray:
        """Positions of data set ``dataset``'s residuals: its G' rows then its G'' rows, or its creep rows."""
        creep = np.flatnonzero(self.creep_dataset == dataset)
        if creep.size:
            return 2 * self.n_points + creep
        pts = np.flatnonzero(self.dataset_index == dataset)
        return np.concatenate([pts, self.n_points + pts])

    # -- model ----------------------------------------------------------------------
    def _effective(self, phi):
        """Tendon properties and group prestresses on the reference cell (strut length L_ref) equivalent to ``phi``."""
        EA = np.exp(phi[: self.n_ea])[self.ea_groups]
        c = np.exp(phi[self.n_ea: self.n_ea + self.n_c])[self.c_groups]
        P = np.exp(self.group_log_offset + self.group_map @ phi[self.prestress_slice])
        lam = math.exp(phi[-1]) / self.L_ref
        # the cell scaled by lam = L/L_ref has the moduli of the reference cell with these
        # properties (module docstring), so L never needs a new cell
        return EA / lam**2, c / lam, P / lam**2

    def _whitening(self, eta):
        """(B, Ht, bt, Dt): A, the prestress Hessian, load and probe in the basis where C0 = I."""
        if self.n_c == 1:  # C0 = c·A Aᵀ: rescale the precomputed basis
            s = 1.0 / math.sqrt(eta[0])
            B0, Ht0, bt0, Dt0 = self.white_unit
            return B0 * s, Ht0 * (s * s), bt0 * s, Dt0 * s
        try:
            Lc = np.linalg.cholesky((self.A * eta) @ self.A.T)
        except np.linalg.LinAlgError:
            return None
        return _whiten(Lc, self.A, self.H, self.load, self.probe)

    def _spectrum(self, phi) -> _Spectrum | None:
        """Relaxation spectrum per prestress group; None where the model is not a stable cell.

        ``K0 = P·Σ T0_j ∇²l_j + Σ k_j a_j a_jᵀ`` with the law's tangent
        stiffness ``k_j`` at tension ``P·T0_j`` (it depends on P), ``C0 = Σ η_j a_j a_jᵀ``.
        """
        EA, c, P = self._effective(phi)
        k, dk, kP, eta, deta = _tangents(EA, c, self.lengths, self.T0, P)
        wh = self._whitening(eta)
        if wh is None:
            return None
        B, Ht, bt, Dt = wh
        lam, W = prestress_grid_modes(Ht, np.matmul(B[None] * k[:, None, :], B.T[None]), P)
        if not np.all(lam > 0):
            return None
        alpha = np.einsum("gnk,n->gk", W, Dt)  # probe projections, D0·v_k
        beta = np.einsum("gnk,n->gk", W, bt)  # load projections, −H0·v_k
        Kpt = Ht[None] + np.matmul(B[None] * kP[:, None, :], B.T[None])
        return _Spectrum(P=P, dk=dk, deta=deta, B=B, Kpt=Kpt, lam=lam, W=W, alpha=alpha, beta=beta)

    def _evaluate(self, phi, jac: bool, share: bool = False, elasticity: bool = False) -> _Evaluation | None:
        """Moduli (and, if asked, their log-derivatives, the prestress share and elasticity); None if unstable."""
        spec = self._spectrum(phi)
        if spec is None:
            return None
        g = self.group_index
        R = 1.0 / (spec.lam[g] + 1j * self.omega[:, None])  # (N, n)
        aR = spec.alpha[g] * R
        bR = spec.beta[g] * R
        J = np.sum(spec.alpha[g] * bR, axis=1)
        G = modulus(J, self.L_ref)
        dlogG = self._dlogG(spec, J, aR, bR) if jac else None
        sh, dsh = self._share(spec, jac) if share else (None, None)
        el, de = self._storage_elasticity(spec, jac) if elasticity else (None, None)
        Jc, dJc = self._creep(spec, jac) if self.n_creep else (None, None)
        return _Evaluation(G=G, dlogG=dlogG, share=sh, dshare=dsh, elasticity=el, delasticity=de, Jc=Jc,
                           dlogJc=dJc)

    def _creep(self, spec, jac: bool):
        """Creep compliance (1/Pa) at the creep points and, if ``jac``, d ln J / d phi (module :mod:`.creep`)."""
        from .creep import creep_derivatives, creep_from_modes

        Jc = np.empty(self.n_creep)
        dJ = np.zeros((self.n_creep, self.n_params)) if jac else None
        AV, M = self._modal(spec) if jac else (None, None)
        for g in np.unique(self.creep_group):
            sel = np.flatnonzero(self.creep_group == g)
            t = self.creep_t[sel]
            # J in 1/Pa is the cell's compliance (m/N) times 2L (the continuum factor of G = (0.5/L)/J)
            Jc[sel] = 2.0 * self.L_ref * creep_from_modes(spec.lam[g], spec.alpha[g], spec.beta[g], t)
            if jac:
                assert dJ is not None and AV is not None and M is not None  # computed above when jac
                d_EA, d_c, d_Pg = creep_derivatives(spec.lam[g], spec.alpha[g], spec.beta[g], AV[g], M[g], t,
                                                    spec.dk[g], spec.deta, spec.P[g])
                d_P = np.zeros((sel.size, self.n_groups))
                d_P[:, g] = d_Pg
                dJ[sel] = 2.0 * self.L_ref * self._to_params(d_EA, d_c, d_P)
        return Jc, (None if dJ is None else dJ / Jc[:, None])

    def _modal(self, spec):
        """AV = a_jᵀ v_k (groups, m, n) and M = Vᵀ Kp V (groups, n, n)."""
        AV = np.matmul(spec.B.T[None], spec.W)
        M = np.matmul(np.transpose(spec.W, (0, 2, 1)), np.matmul(spec.Kpt, spec.W))
        return AV, M

    def _to_params(self, d_EA, d_c, d_P):
        """Per-tendon and per-group derivatives (rows: points or groups) to derivatives by all parameters.

        ``d_EA`` (r, m), ``d_c`` (r, m): by ln EA_j, ln c_j of each tendon; ``d_P`` (r, groups): by the
        log prestress of each group. L acts through the effective (P/λ², EA/λ², c/λ).
        """
        out = np.zeros((d_EA.shape[0], self.n_params), dtype=np.result_type(d_EA, d_c, d_P))
        out[:, : self.n_ea] = d_EA @ np.eye(self.n_ea)[self.ea_groups]
        out[:, self.n_ea: self.n_ea + self.n_c] = d_c @ np.eye(self.n_c)[self.c_groups]
        out[:, self.prestress_slice] = d_P @ self.group_map
        out[:, -1] = -2.0 * d_P.sum(axis=1) - 2.0 * d_EA.sum(axis=1) - d_c.sum(axis=1)
        return out

    def _dlogG(self, spec, J, aR, bR):
        """d ln G / d phi at the data points, shape (N, n_params)."""
        AV, M = self._modal(spec)
        g = self.group_index
        if spec.lam.shape[0] == 1:  # one prestress: plain matrix products
            ax = bR @ AV[0].T  # a_jᵀ x(ω_i), (N, m)
            ay = aR @ AV[0].T  # a_jᵀ y(ω_i)
            dJ_P = -np.einsum("ik,kl,il->i", aR, M[0], bR) * spec.P[0]  # P ∂J/∂P
        else:
            ax = np.einsum("imk,ik->im", AV[g], bR)
            ay = np.einsum("imk,ik->im", AV[g], aR)
            dJ_P = -np.einsum("ik,ikl,il->i", aR, M[g], bR) * spec.P[g]
        pr = ax * ay
        dJ_EA = -pr * spec.dk[g]  # EA_j ∂J/∂EA_j
        dJ_c = -1j * self.omega[:, None] * pr * spec.deta  # c_j ∂J/∂c_j
        d_P = np.zeros((J.size, self.n_groups), dtype=complex)
        d_P[np.arange(J.size), g] = dJ_P
        return -self._to_params(dJ_EA, dJ_c, d_P) / J[:, None]

    def _activity(self, spec, w: float, jac: bool):
        """The prestress elasticity ``e = ∂ln G/∂ln P = P·yᵀKp x / J`` per group at ω = ``w`` (rad/s), complex.

        With ``x = Z⁻¹(−H0)``, ``y = Z⁻ᵀD0ᵀ``, ``Z = K0 + iωC0`` and
        ``J = D0·x``. Returns ``(e, J, d ln e/d phi, d ln J/d phi)``, the
        derivatives (groups, n_params) from ``∂x = −Z⁻¹(∂Z)x`` and its
        transpose (None without ``jac``). At ``w = 0``, ``e`` is real: the
        prestress share of the static stiffness.
        """
        P = spec.P
        r = 1.0 / (spec.lam + 1j * w)
        xs, ys = spec.beta * r, spec.alpha * r  # x, y in modal coordinates
        J = np.sum(spec.alpha * xs, axis=1)
        AV, M = self._modal(spec)
        Mx, My = np.einsum("gkl,gl->gk", M, xs), np.einsum("gkl,gl->gk", M, ys)
        Q = np.sum(ys * Mx, axis=1)  # yᵀ Kp x
        e = P * Q / J
        if not jac:
            return e, J, None, None
        ax, ay = np.einsum("gmk,gk->gm", AV, xs), np.einsum("gmk,gk->gm", AV, ys)
        au, av = np.einsum("gmk,gk->gm", AV, Mx * r), np.einsum("gmk,gk->gm", AV, My * r)
        # by ln EA_j (∂Z = dk_j a_j a_jᵀ) and ln c_j (∂Z = iω dη_j a_j a_jᵀ): Q and J both move
        both, single = ay * au + av * ax, ay * ax
        sc = 1j * w * spec.deta
        d_EA = -spec.dk * (both / Q[:, None] - single / J[:, None])
        d_c = -sc * (both / Q[:, None] - single / J[:, None])
        # by the group's own ln P (∂Z = P Kp; the Voigt law's ∂k/∂T depends on neither T nor EA)
        R = np.sum(My * Mx * r, axis=1)  # yᵀ Kp Z⁻¹ Kp x
        d_P = np.diag(1.0 - 2.0 * P * R / Q + P * Q / J)
        dlnJ = self._to_params(-spec.dk * single / J[:, None], -sc * single / J[:, None], np.diag(-P * Q / J))
        return e, J, self._to_params(d_EA, d_c, d_P), dlnJ

    def _share(self, spec, jac: bool):
        """Prestress share of the static stiffness per group (real), and d ln share / d phi."""
        e, _, de, _ = self._activity(spec, 0.0, jac)
        return e.real, (None if de is None else de.real)

    def _storage_elasticity(self, spec, jac: bool):
        """``∂ln G'/∂ln P`` per group at :attr:`elasticity_omega`, and its d ln / d phi.

        ``E' = Re(G·e)/Re(G)`` with ``G ∝ 1/J``.
        """
        e, J, de, dJ = self._activity(spec, self.elasticity_omega, jac)
        G = 1.0 / J
        E = (G * e).real / G.real
        if not jac:
            return E, None
        dG = -dJ * G[:, None]  # dG = G·d ln G
        dA = (G * e)[:, None] * (de - dJ)
        dE = (dA.real * G.real[:, None] - (G * e).real[:, None] * dG.real) / (G.real**2)[:, None]
        return E, dE / E[:, None]

    # -- residuals ------------------------------------------------------------------
    def moduli(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """Model G', G'' (Pa) at the data points, shape (N,) each; NaN where the model is unstable."""
        out = self._evaluate(self.full(theta), jac=False)
        if out is None:
            nan = np.full(self.omega.size, np.nan)
            return nan, nan.copy()
        return out.G.real, out.G.imag

    def creep(self, theta) -> np.ndarray:
        """Model creep compliance (1/Pa) at the creep points, shape (n_creep,); NaN where the model is unstable."""
        out = self._evaluate(self.full(theta), jac=False)
        return np.full(self.n_creep, np.nan) if out is None or out.Jc is None else out.Jc

    def residuals(self, theta) -> np.ndarray:
        """Weighted data residuals ``w·(log10 G_model − log10 G_data)``, shape (2N,) (G' block, then G'')."""
        return self._residuals_from(self._evaluate(self.full(theta), jac=False))

    def _residuals_from(self, out) -> np.ndarray:
        if out is None:
            return np.full(self.y_obs.size, _PENALTY)
        G = out.G
        if not (np.all(G.real > 0) and np.all(G.imag > 0)):
            return np.full(self.y_obs.size, _PENALTY)
        parts = [np.log10(G.real), np.log10(G.imag)]
        if self.n_creep:
            if not np.all(out.Jc > 0):
                return np.full(self.y_obs.size, _PENALTY)
            parts.append(np.log10(out.Jc))
        return self.weights * (np.concatenate(parts) - self.y_obs)

    def jacobian(self, theta) -> np.ndarray:
        """Analytic Jacobian of :meth:`residuals` with respect to ``theta``, shape (2N, n_free)."""
        return self._jacobian_from(self._evaluate(self.full(theta), jac=True))

    def _jacobian_from(self, out) -> np.ndarray:
        if out is None or out.dlogG is None:
            return np.zeros((self.y_obs.size, self.n_free))
        G = out.G
        dG = G[:, None] * out.dlogG[:, self.free]
        with np.errstate(divide="ignore", invalid="ignore"):
            blocks = [dG.real / (G.real[:, None] * _LN10), dG.imag / (G.imag[:, None] * _LN10)]
        if self.n_creep:
            blocks.append(out.dlogJc[:, self.free] / _LN10)
        return self.weights[:, None] * np.nan_to_num(np.vstack(blocks))

    def jacobian_fd(self, theta, step: float = 1e-5) -> np.ndarray:
        """Central finite-difference Jacobian of :meth:`residuals` (the slow reference), shape (2N, n_free)."""
        return _central(self.residuals, theta, step)

    def rms(self, theta) -> float:
        """RMS of the unweighted log10 residuals of all data sets (decades)."""
        r = self.residuals(theta)
        return float(np.sqrt(np.mean((r / self.weights) ** 2)))

    def dataset_rms(self, theta) -> np.ndarray:
        """RMS of the unweighted log10 residuals of each data set (decades), shape (n_datasets,)."""
        r = self.residuals(theta) / self.weights
        return np.array([math.sqrt(float(np.mean(r[self.rows(k)] ** 2))) for k in range(self.n_datasets)])

    # -- the prestress share and its penalty ---------------------------------------------
    def prestress_share(self, theta) -> np.ndarray:
        """Prestress share of the static stiffness at each prestress group, shape (groups,); NaN if unstable."""
        out = self._evaluate(self.full(theta), jac=False, share=True)
        if out is None or out.share is None:  # share=True always computes it when the model is stable
            return np.full(self.n_groups, np.nan)
        return out.share

    def prestress_elasticity(self, theta) -> np.ndarray:
        """``∂ln G'/∂ln P`` at :attr:`elasticity_omega` at each prestress group, shape (groups,); NaN if unstable."""
        out = self._evaluate(self.full(theta), jac=False, elasticity=True)
        if out is None or out.elasticity is None:  # elasticity=True always computes it when the model is stable
            return np.full(self.n_groups, np.nan)
        return out.elasticity

    def _constraints(self) -> list:
        """The active activity constraints: [(lower bound, field of _Evaluation, its d ln field)]."""
        out = []
        if self.min_prestress_share is not None:
            out.append((self.min_prestress_share, "share", "dshare"))
        if self.min_prestress_elasticity is not None:
            out.append((self.min_prestress_elasticity, "elasticity", "delasticity"))
        return out

    @property
    def n_penalties(self) -> int:
        """Penalty residuals the search adds to the data residuals (one per group and activity constraint)."""
        return self.n_groups * len(self._constraints())

    def _evaluate_constrained(self, phi, jac: bool):
        return self._evaluate(phi, jac=jac, share=self.min_prestress_share is not None,
                              elasticity=self.min_prestress_elasticity is not None)

    def _penalty_from(self, out, jac: bool):
        """Penalty residuals ``ρ·ln(bound/value)`` where a constrained value falls short (else 0), and their Jacobian."""
        rows, jrows = [], []
        for bound, name, dname in self._constraints():
            r = np.zeros(self.n_groups)
            Jr = np.zeros((self.n_groups, self.n_free)) if jac else None
            if out is None:
                r[:] = _PENALTY
            else:
                v = getattr(out, name)
                short = v < bound
                ok = short & (v > 0)
                r[ok] = _SHARE_WEIGHT * np.log(bound / v[ok])
                r[short & ~(v > 0)] = _SHARE_WEIGHT * 50.0  # no positive value: a flat wall
                if Jr is not None and ok.any():
                    Jr[ok] = -_SHARE_WEIGHT * getattr(out, dname)[ok][:, self.free]
            rows.append(r)
            if Jr is not None:
                jrows.append(Jr)
        if not rows:
            return np.zeros(0), (np.zeros((0, self.n_free)) if jac else None)
        return np.concatenate(rows), (np.vstack(jrows) if jac else None)

    def penalty(self, theta) -> np.ndarray:
        """The penalty residuals the search adds (empty without a constraint), shape (n_penalties,)."""
        if self.n_penalties == 0:
            return np.zeros(0)
        return self._penalty_from(self._evaluate_constrained(self.full(theta), jac=False), jac=False)[0]

    def feasible(self, theta) -> bool:
        """Whether every activity constraint holds at ``theta`` to within 1 % of its bound (True without one).

        The search counts a state as meeting the tolerance only when it is
        also feasible (:func:`tenscell.fitting.fit`).
        """
        return bool(np.all(self.penalty(theta) <= _SHARE_WEIGHT * 0.01))

    def penalty_jacobian(self, theta) -> np.ndarray:
        """Analytic Jacobian of :meth:`penalty`, shape (n_penalties, n_free)."""
        if self.n_penalties == 0:
            return np.zeros((0, self.n_free))
        return self._penalty_from(self._evaluate_constrained(self.full(theta), jac=True), jac=True)[1]

    # -- search coordinates (max_decades) ---------------------------------------------
    @property
    def compact(self) -> bool:
        """True if ``max_decades`` actually constrains the stiffnesses (several EA, D below the EA box)."""
        if self.max_decades is None or self.n_ea < 2:
            return False
        return self.max_decades * _LN10 < float(self.upper[0] - self.lower[0])

    @property
    def _decades(self) -> float:
        """``max_decades`` where it is known to be set (the compact coordinates)."""
        assert self.max_decades is not None, "only used when compact"
        return self.max_decades

    def coordinate_map(self) -> np.ndarray:
        """``T`` with ``theta = T @ u`` (search coordinates ``u``), shape (n_free, n_u).

        Identity unless :attr:`compact`; then ``u = (m, σ_1..σ_nEA, rest)`` and
        ``ln EA_j = m + D·ln10·σ_j``.
        """
        n = self.n_free
        if not self.compact:
            return np.eye(n)
        T = np.zeros((n, n + 1))
        T[: self.n_ea, 0] = 1.0
        T[: self.n_ea, 1: self.n_ea + 1] = np.eye(self.n_ea) * (self._decades * _LN10)
        T[self.n_ea:, self.n_ea + 1:] = np.eye(n - self.n_ea)
        return T

    def coordinate_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Box bounds of the search coordinates ``u``."""
        lo, hi = self.bounds
        if not self.compact:
            return lo, hi
        half = 0.5 * self._decades * _LN10
        s = np.full(self.n_ea, 0.5)
        return (np.concatenate([[lo[0] + half], -s, lo[self.n_ea:]]),
                np.concatenate([[hi[0] - half], s, hi[self.n_ea:]]))

    def to_coordinates(self, theta) -> np.ndarray:
        """Search coordinates of ``theta``; stiffnesses spread wider than ``max_decades`` are compressed about their centre."""
        theta = np.asarray(theta, dtype=float)
        if not self.compact:
            return theta.copy()
        e = theta[: self.n_ea]
        width = self._decades * _LN10
        spread = float(e.max() - e.min())
        centre = 0.5 * float(e.max() + e.min())
        lo, hi = self.coordinate_bounds()
        mid = float(np.clip(centre, lo[0], hi[0]))
        scale = min(1.0, width / spread) if spread > 0 else 1.0
        sigma = np.clip((centre + (e - centre) * scale - mid) / width, -0.5, 0.5)
        return np.concatenate([[mid], sigma, theta[self.n_ea:]])

    # -- records ----------------------------------------------------------------------
    def parameters(self, theta) -> tuple:
        """The parameters as :class:`FitParameter` records."""
        vals = self.values(theta)
        lo, hi = np.exp(self.lower), np.exp(self.upper)
        return tuple(
            FitParameter(name=n, value=float(v), lower=float(a), upper=float(b), unit=u, vary=bool(fr), description=d)
            for n, v, a, b, u, fr, d in zip(self.names, vals, lo, hi, self.units, self.free, self.descriptions)
        )

    def gauge(self) -> np.ndarray:
        """The exact strut-length gauge in log-parameter space, shape (n_params,).

        ``(P, EA, c, L) -> (λ²P, λ²EA, λc, λL)`` leaves G unchanged, i.e. the
        moduli are constant along ``phi + t·gauge()`` for every t: 2 for each
        stiffness and for a model prestress ``P`` or scale ``s``, 1 for each
        damping and for ``L``, 0 for a data set's fitted prestress ``P_data``
        (in Pa: the scale ``s`` carries the λ²). It is a gauge of the fit only
        if every parameter it moves is free.
        """
        power = {"EA": 2.0, "c": 1.0, "P": 2.0, "s": 2.0, "P_data": 0.0, "L": 1.0}
        return np.array([power[k] for k in self.kinds])

    def effective_properties(self, theta):
        """(EA (m,), c (m,), P (groups,)) on the reference cell (N, N·s/m, N) equivalent to ``theta``."""
        return self._effective(self.full(theta))


def _central(fun, theta, step):
    theta = np.asarray(theta, dtype=float)
    cols = []
    for k in range(theta.size):
        e = np.zeros_like(theta)
        e[k] = step
        cols.append((fun(theta + e) - fun(theta - e)) / (2 * step))
    return np.stack(cols, axis=-1)


# ---------------------------------------------------------------------------------
# building a problem
# ---------------------------------------------------------------------------------
def required_points(tendons: str = "per-tendon", damping: str = "uniform", n_families: int = 2) -> int:
    """Minimum number of data points for a fit of one data set.

    Each point gives two residuals. Per-tendon stiffnesses are deliberately
    over-parametrized (as in the paper: 36 parameters against 32 residuals
    for the 16-point frequency data; the trust-region solver handles it, and
    the alternatives show the non-uniqueness), so they count as one stiffness
    here; the other parameters (c, P or s, L) each count. A joint fit needs
    one more point per data set whose prestress is fitted.
    """
    n_ea = {"per-tendon": 1, "per-family": n_families, "uniform": 1}[_choice("tendons", tendons, TENDON_MODES)]
    n_c = n_families if _choice("damping", damping, DAMPING_MODES) == "per-family" else 1
    return n_ea + n_c + 2


def _choice(name, value, allowed):
    if value not in allowed:
        raise ValueError(f"{name} must be one of {', '.join(repr(a) for a in allowed)}, got {value!r}")
    return value


def _tendon_labels(cell: Cell) -> list[str]:
    st = cell.structure
    names = st.node_names if st.node_names else tuple(str(i) for i in range(st.n_nodes))
    return [f"{names[a]}-{names[b]} ({fam})" for (a, b), fam in zip(st.tendons, st.families)]


def _family_groups(cell: Cell) -> tuple[np.ndarray, list[str]]:
    fams = list(dict.fromkeys(cell.structure.families))  # in order of appearance
    groups = np.array([fams.index(f) for f in cell.structure.families])
    return groups, fams


def _is_creep(d) -> bool:
    return getattr(d, "kind", None) == "creep"


def as_datasets(data) -> tuple:
    """One data set or a sequence of them as a tuple of :class:`RheologyData` or
    :class:`~tenscell.io.creep_data.CreepData` (ValueError otherwise)."""
    from ..io.creep_data import CreepData

    kinds = (RheologyData, CreepData)
    items = (data,) if isinstance(data, kinds) else tuple(data) if isinstance(data, (list, tuple)) else None
    if not items or not all(isinstance(d, kinds) for d in items):
        raise ValueError("data must be a tenscell.io.data.RheologyData or CreepData, or a non-empty list of them, "
                         f"got {type(data).__name__}")
    return items


def _stiffness_layout(cell: Cell, tendons: str, damping: str):
    """(ea_groups, ea_names, ea_desc, c_groups, c_names, c_desc) for the parametrization."""
    m = cell.m
    fam_groups, fams = _family_groups(cell)
    labels = _tendon_labels(cell)
    if tendons == "per-tendon":
        ea = (np.arange(m), [f"EA[{j}]" for j in range(m)],
              [f"stiffness of tendon {j}, {lab}" for j, lab in enumerate(labels)])
    elif tendons == "per-family":
        ea = (fam_groups, [f"EA_{f}" for f in fams], [f"stiffness of every {f} tendon" for f in fams])
    else:
        ea = (np.zeros(m, dtype=int), ["EA"], ["stiffness of every tendon"])
    if damping == "per-family":
        cc = (fam_groups, [f"c_{f}" for f in fams], [f"damping of every {f} tendon" for f in fams])
    else:
        cc = (np.zeros(m, dtype=int), ["c"], ["damping of every tendon"])
    return (*ea, *cc)


def _prestress_layout(datasets):
    """Prestress parameters and groups: (names, units, descs, kinds, groups) with groups a list of
    (dataset, measured Pa or NaN, log offset, {parameter position: 1}) and point -> group index."""
    known = [d.prestress is not None for d in datasets]
    joint = len(datasets) > 1
    names, units, descs, kinds = [], [], [], []
    if any(known):
        names.append("s")
        units.append("m²")
        kinds.append("s")
        descs.append("prestress scale: model prestress (N) = s × prestress (Pa) of the data"
                     + (" (one scale links the data sets)" if joint else ""))
    own = {}
    for k, d in enumerate(datasets):
        if known[k]:
            continue
        own[k] = len(names)
        if any(known):
            names.append(f"P_data[{k}]")
            units.append("Pa")
            kinds.append("P_data")
            descs.append(f"prestress (Pa) at which data set {k} ({d.source}) was measured: not stated, so fitted")
        else:
            names.append(f"P[{k}]" if joint else "P")
            units.append("N")
            kinds.append("P")
            descs.append("prestress: tendon tensions are P·T0" + (f" for data set {k} ({d.source})" if joint else ""))
    groups, point_group = [], []
    for k, d in enumerate(datasets):
        if known[k]:
            uniq, inv = np.unique(d.prestress, return_inverse=True)
            base = len(groups)
            groups += [(k, float(p), math.log(p), {0: 1.0}) for p in uniq]
            point_group.append(base + np.asarray(inv).ravel())
        else:
            links = {own[k]: 1.0}
            if any(known):
                links[0] = 1.0
            groups.append((k, math.nan, 0.0, links))
            point_group.append(np.full(d.n, len(groups) - 1))
    return names, units, descs, kinds, groups, point_group


def _default_bounds(datasets, L_ref):
    """Default bounds per parameter kind and the scales used by the initial guess.

    A creep point at time t counts as a modulus 1/J at the angular frequency 1/t.
    """
    Gs = np.concatenate([1.0 / d.compliance if _is_creep(d) else d.G_storage for d in datasets])
    omega = np.concatenate([1.0 / d.time_s if _is_creep(d) else 2 * np.pi * d.frequency_hz for d in datasets])
    S = float(np.median(Gs)) * L_ref**2
    w_m = float(np.exp(np.mean(np.log(omega))))
    known = [d.prestress for d in datasets if d.prestress is not None]
    P_med = float(np.median(np.concatenate(known))) if known else 1.0
    defaults = {
        "EA": (1e-8 * S, 1e6 * S),
        "c": (1e-6 * S / w_m, 1e6 * S / w_m),
        "P": (1e-10 * S, 1e4 * S),
        "s": (1e-10 * S / P_med, 1e4 * S / P_med),
        "P_data": (1e-3 * P_med, 1e3 * P_med),
        "L": (1e-3 * L_ref, 1e3 * L_ref),
    }
    return defaults, S, w_m, P_med


def _apply_bounds(kinds, bounds, defaults):
    bounds = dict(bounds or {})
    for key in bounds:
        if key not in defaults:
            raise ValueError(f"bounds: unknown parameter kind {key!r}; allowed: {', '.join(defaults)}")
        if key not in kinds:
            raise ValueError(f"bounds: {key!r} does not apply to these data (parameters here: "
                             f"{', '.join(dict.fromkeys(kinds))})")
    lower = np.empty(len(kinds))
    upper = np.empty(len(kinds))
    for i, k in enumerate(kinds):
        lo, hi = bounds.get(k, defaults[k])
        lo = positive_scalar(f"bounds[{k!r}] lower", lo)
        hi = positive_scalar(f"bounds[{k!r}] upper", hi)
        if not lo < hi:
            raise ValueError(f"bounds[{k!r}]: the lower bound {lo!r} must be below the upper bound {hi!r}")
        lower[i], upper[i] = math.log(lo), math.log(hi)
    return lower, upper


def _apply_fixed(names, kinds, lower, upper, fixed, damping, L_ref, P_med):
    free = np.ones(len(names), dtype=bool)
    fixed_log = 0.5 * (lower + upper)
    fixed_log[-1] = math.log(L_ref) if lower[-1] < math.log(L_ref) < upper[-1] else fixed_log[-1]
    for i, k in enumerate(kinds):  # a data set's own prestress starts at the others' median
        if k == "P_data" and lower[i] < math.log(P_med) < upper[i]:
            fixed_log[i] = math.log(P_med)
    for key, value in dict(fixed or {}).items():
        if key not in names:  # any parameter may be held fixed (a stiffness group, a damping, a prestress, L)
            raise ValueError(f"fixed: cannot fix {key!r}; parameters here: {', '.join(names)}")
        v = positive_scalar(f"fixed[{key!r}]", value)
        i = names.index(key)
        if not lower[i] <= math.log(v) <= upper[i]:
            raise ValueError(f"fixed[{key!r}] = {v!r} lies outside its bounds [{math.exp(lower[i]):.6g}, "
                             f"{math.exp(upper[i]):.6g}]")
        free[i] = False
        fixed_log[i] = math.log(v)
    return free, fixed_log


def _cell_matrices(cell: Cell):
    """Dense A, the symmetric prestress Hessian Σ T0_j ∇²l_j and the Cholesky factor of A Aᵀ.

    ValueError if C0 would be singular.
    """
    dense = lambda M: M.toarray() if sp.issparse(M) else np.asarray(M, dtype=float)  # noqa: E731
    A, H = dense(cell.A), dense(cell.prestress_hessian)
    AAt = A @ A.T
    ev = np.linalg.eigvalsh(AAt)
    # Cholesky alone can pass a singular matrix on rounding noise; compare with its scale
    if not ev[0] > 1e-10 * ev[-1]:
        raise ValueError(
            f"{cell.describe()}: the damping matrix C0 = Σ c_j a_j a_jᵀ is singular (the tendons leave a mechanism "
            "undamped, e.g. the cell without intermediate filaments), so its relaxation spectrum, which the fit "
            "uses, does not exist; fit a cell with a positive definite C0"
        )
    return A, 0.5 * (H + H.T), np.linalg.cholesky(AAt)


def _check_options(min_prestress_share, max_decades, min_prestress_elasticity, elasticity_frequency_hz):
    if min_prestress_elasticity is not None:
        min_prestress_elasticity = positive_scalar("min_prestress_elasticity", min_prestress_elasticity)
    elasticity_frequency_hz = positive_scalar("elasticity_frequency_hz", elasticity_frequency_hz, "Hz")
    if min_prestress_share is not None:
        min_prestress_share = positive_scalar("min_prestress_share", min_prestress_share)
        if min_prestress_share >= 1.0:
            raise ValueError(f"min_prestress_share must be below 1 (a share of the static stiffness), "
                             f"got {min_prestress_share!r}")
    if max_decades is not None:
        max_decades = positive_scalar("max_decades", max_decades, "decades")
    return min_prestress_share, max_decades, min_prestress_elasticity, elasticity_frequency_hz


def make_problem(
    data,
    cell: Cell | None = None,
    *,
    tendons: str = "per-tendon",
    damping: str = "uniform",
    bounds: dict | None = None,
    fixed: dict | None = None,
    min_prestress_share: float | None = None,
    max_decades: float | None = None,
    min_prestress_elasticity: float | None = None,
    elasticity_frequency_hz: float = 0.1,
) -> FitProblem:
    """Set up the fit of ``cell``'s linear model to one or several data sets.

    Parameters
    ----------
    data : RheologyData or sequence of RheologyData
        Frequency sweeps, prestress sweeps, or frequency sweeps at a stated
        prestress (a ``prestress_Pa`` column; see
        :meth:`RheologyData.with_prestress`). Several data sets are fitted
        jointly by one parameter set (module docstring: the prestress).
    cell : Cell, optional
        The reference (default :func:`tenscell.paper_cell`). Its damping
        matrix must be positive definite for positive c (true for the paper
        cell with intermediate filaments).
    tendons : {"per-tendon", "per-family", "uniform"}
        Stiffness parametrization.
    damping : {"uniform", "per-family"}
        Damping parametrization.
    bounds : dict, optional
        ``{"EA": (lo, hi), "c": (lo, hi), "P": (lo, hi), "s": (lo, hi), "P_data": (lo, hi), "L": (lo, hi)}``
        in N, N·s/m, N, m², Pa, m; each applies to every parameter of that
        kind. Defaults scale with the data: with ``S = median(G')·L²`` (N),
        ``ω_m = 2π·geomean(f)`` and ``P_m`` the median stated prestress (Pa):
        EA in [1e-8, 1e6]·S, c in [1e-6, 1e6]·S/ω_m, P in [1e-10, 1e4]·S,
        s in [1e-10, 1e4]·S/P_m, P_data in [1e-3, 1e3]·P_m, L in
        [1e-3, 1e3]·L_cell.
    fixed : dict, optional
        Parameters to hold fixed, by name (any of :attr:`FitProblem.names`:
        ``"L"``, ``"c"`` or ``"c_actin"``, ``"EA_intermediate_filament"``,
        ``"EA[3]"``, a prestress ``"P"``, ``"s"``, ``"P_data[k]"``...), with
        values in SI units (Pa for ``P_data``). Fixing any of EA, c, P (or
        s) or L removes the strut-length gauge (and makes L identifiable).
    min_prestress_share : float in (0, 1), optional
        Lower bound on the prestress share of the static stiffness at every
        prestress of the data (module docstring).
    max_decades : float, optional
        Upper bound on the spread log10(max EA / min EA) of the stiffnesses.
    min_prestress_elasticity : float, optional
        Lower bound on ``∂ln G'/∂ln P`` at ``elasticity_frequency_hz`` at
        every prestress of the data (adherent cells: about 0.7 at 0.1 Hz).
    elasticity_frequency_hz : float
        Frequency (Hz) of that bound (default 0.1 Hz).

    Returns
    -------
    FitProblem

    Raises
    ------
    ValueError
        Unknown modes, bad bounds, fixed values or options, a cell with
        singular damping, or too few data points (:func:`required_points`).
    """
    from ..model.shapes import paper_cell

    datasets = as_datasets(data)
    _choice("tendons", tendons, TENDON_MODES)
    _choice("damping", damping, DAMPING_MODES)
    min_prestress_share, max_decades, min_prestress_elasticity, elasticity_frequency_hz = _check_options(
        min_prestress_share, max_decades, min_prestress_elasticity, elasticity_frequency_hz)
    cell = paper_cell() if cell is None else cell
    if not isinstance(cell, Cell):
        raise ValueError(f"cell must be a tenscell Cell, got {type(cell).__name__}")
    A, H, chol = _cell_matrices(cell)

    ea_groups, ea_names, ea_desc, c_groups, c_names, c_desc = _stiffness_layout(cell, tendons, damping)
    p_names, p_units, p_desc, p_kinds, groups, point_group = _prestress_layout(datasets)
    n_points = sum(d.n for d in datasets)
    need = required_points(tendons, damping, n_families=len(_family_groups(cell)[1])) + len(p_names) - 1
    if n_points < need:
        src = datasets[0].source if len(datasets) == 1 else f"{len(datasets)} data sets"
        raise DataError(
            f"{src}: {n_points} data point{'s' if n_points != 1 else ''}, fewer than the {need} the fit "
            f"needs (tendons={tendons!r}, damping={damping!r}: at least as many points as stiffness groups "
            f"+ damping groups + prestress parameters + L)"
        )
    names = tuple(ea_names + c_names + p_names + ["L"])
    units = tuple(["N"] * len(ea_names) + ["N·s/m"] * len(c_names) + p_units + ["m"])
    descs = tuple(ea_desc + c_desc + p_desc + ["strut length (redundant with P, EA, c: see docs)"])
    kinds = tuple(["EA"] * len(ea_names) + ["c"] * len(c_names) + p_kinds + ["L"])

    L_ref = float(cell.strut_length)
    defaults, S, w_m, P_med = _default_bounds(datasets, L_ref)
    lower, upper = _apply_bounds(kinds, bounds, defaults)
    free, fixed_log = _apply_fixed(names, kinds, lower, upper, fixed, damping, L_ref, P_med)

    n_p = len(p_names)
    group_map = np.zeros((len(groups), n_p))
    for g, (_, _, _, links) in enumerate(groups):
        for j, v in links.items():
            group_map[g, j] = v
    measured = [d.prestress for d in datasets if d.prestress is not None]
    varies = bool(measured) and np.unique(np.concatenate(measured)).size > 1
    load, probe = np.asarray(cell.load, dtype=float), np.asarray(cell.probe, dtype=float)
    moduli = [k for k, d in enumerate(datasets) if not _is_creep(d)]
    creep = [k for k, d in enumerate(datasets) if _is_creep(d)]
    mod = [datasets[k] for k in moduli]

    def cat(parts, dtype=float):
        return np.concatenate(parts) if parts else np.zeros(0, dtype=dtype)

    y_mod = [np.log10(cat([d.G_storage for d in mod])), np.log10(cat([d.G_loss for d in mod]))]
    w_mod = [cat([d.weights_storage for d in mod]), cat([d.weights_loss for d in mod])]
    return FitProblem(
        names=names, units=units, descriptions=descs, kinds=kinds, lower=lower, upper=upper, free=free,
        fixed_log=fixed_log, tendons=tendons, damping=damping, n_ea=len(ea_names), n_c=len(c_names),
        ea_groups=np.asarray(ea_groups), c_groups=np.asarray(c_groups),
        A=A, lengths=np.asarray(cell.lengths, dtype=float), T0=np.asarray(cell.T0, dtype=float), H=H, load=load,
        probe=probe, L_ref=L_ref, white_unit=_whiten(chol, A, H, load, probe),
        sources=tuple(d.source for d in datasets),
        omega=2 * np.pi * cat([d.frequency_hz for d in mod]),
        dataset_index=cat([np.full(datasets[k].n, k) for k in moduli], int),
        group_index=cat([point_group[k] for k in moduli], int),
        group_log_offset=np.array([g[2] for g in groups]), group_map=group_map,
        group_measured=np.array([g[1] for g in groups]), group_dataset=np.array([g[0] for g in groups]),
        y_obs=np.concatenate(y_mod + [np.log10(datasets[k].compliance) for k in creep]),
        weights=np.concatenate(w_mod + [datasets[k].weights for k in creep]),
        scale_stiffness=S, scale_damping=S / w_m,
        prestress_matters=bool(varies or min_prestress_share is not None or min_prestress_elasticity is not None),
        min_prestress_share=min_prestress_share, max_decades=max_decades,
        min_prestress_elasticity=min_prestress_elasticity, elasticity_omega=2 * math.pi * elasticity_frequency_hz,
        creep_t=cat([datasets[k].time_s for k in creep]),
        creep_dataset=cat([np.full(datasets[k].n, k) for k in creep], int),
        creep_group=cat([point_group[k] for k in creep], int),
    )

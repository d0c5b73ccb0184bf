"""The fitting problem: a cell's linear model against data, a parameter layout, residuals and their analytic Jacobian.

Parameters and units
--------------------
* ``EA`` (N): per tendon (``tendons="per-tendon"``, 33 values for the paper
  cell), per family (actin / intermediate filament) or one for all.
* ``c`` (N·s/m): one value (the paper) or per family (``damping="per-family"``).
* ``P`` (N): prestress scale for a frequency sweep; for a prestress sweep the
  model prestress of each point is ``s·P_exp`` and the parameter is the scale
  ``s`` (m², since ``P_exp`` is in Pa).
* ``L`` (m): strut length. For the linear moduli it is exactly redundant:
  a cell scaled by λ (all lengths ×λ) with ``(P, EA, c) -> (λ²P, λ²EA, λc)``
  has the same G' and G'', so ``(P, EA, c, L) -> (λ²P, λ²EA, λc, λL)`` is
  an exact gauge. It is
  fitted as the paper did, starts at the cell's own L and stays there unless
  other parameters are fixed or hit bounds; fix P or c to make it identifiable.

Everything is fitted in natural-log space within bounds. Residuals are
``w·(log10 G_model − log10 G_data)`` for G' and G'' (``w`` = 1, or
``1/sd(log10 G)`` when the data have standard deviations). The Jacobian is
analytic, from the relaxation spectrum ``K0 v = λ C0 v``: with
``x = Z⁻¹(−H0)``, ``y = Z⁻ᵀ D0ᵀ`` and ``Z = K0 + iωC0``,
``∂J/∂EA_j = −(yᵀa_j)(a_jᵀx)/l_j``, ``∂J/∂c_j = −iω(yᵀa_j)(a_jᵀx)``,
``∂J/∂P = −yᵀKp x``, all frequencies at once from a few matrix products.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from .._checks import positive_scalar
from ..io.data import DataError, RheologyData
from ..model.equilibrium import Cell
from .result import FitParameter

__all__ = ["TENDON_MODES", "DAMPING_MODES", "FitProblem", "make_problem", "required_points"]

TENDON_MODES = ("per-tendon", "per-family", "uniform")
#: how tendon damping is parametrized
DAMPING_MODES = ("uniform", "per-family")

_LN10 = math.log(10.0)
# A residual (in decades) returned where the model is not a stable, passive
# cell (K0 not positive definite, G' or G'' <= 0). Finite, so that the
# trust-region solver simply rejects the step.
_PENALTY = 10.0


def _whiten(Lc, A, Kp, load, probe):
    """A, Kp, load, probe in the basis where C0 = Lc Lcᵀ becomes the identity."""
    solve = scipy.linalg.solve_triangular
    B = solve(Lc, A, lower=True, check_finite=False)
    X = solve(Lc, Kp, lower=True, check_finite=False)
    Kpt = solve(Lc, X.T, lower=True, check_finite=False)
    bt = solve(Lc, load, lower=True, check_finite=False)
    Dt = solve(Lc, probe, lower=True, check_finite=False)
    return B, 0.5 * (Kpt + Kpt.T), bt, Dt


# ---------------------------------------------------------------------------------
# the problem: model, data, parameter layout
# ---------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class FitProblem:
    """The linear model of a cell against one data set, with a parameter layout.

    Built by :func:`make_problem`; holds plain arrays only, so that it can be
    sent to worker processes. The parameter vector ``theta`` holds the natural
    logarithms of the *free* parameters, in the order of :attr:`names`
    restricted to :attr:`free`.

    Attributes
    ----------
    names : tuple of str
        All parameter names: stiffness groups, damping groups, ``P`` or ``s``, ``L``.
    units, descriptions : tuple of str
    lower, upper : ndarray
        Log-space bounds of all parameters.
    free : ndarray of bool
    fixed_log : ndarray
        Log values of all parameters (used for the fixed ones).
    """

    names: tuple
    units: tuple
    descriptions: tuple
    lower: np.ndarray
    upper: np.ndarray
    free: np.ndarray
    fixed_log: np.ndarray
    kind: str
    tendons: str
    damping: str
    n_ea: int
    n_c: int
    ea_groups: np.ndarray
    c_groups: np.ndarray
    # cell (reference strut length L_ref)
    A: np.ndarray
    lengths: np.ndarray
    Kp: np.ndarray
    load: np.ndarray
    probe: np.ndarray
    L_ref: float
    white_unit: tuple
    # data
    omega: np.ndarray
    group_index: np.ndarray
    group_prestress: np.ndarray
    y_obs: np.ndarray
    weights: np.ndarray
    scale_stiffness: float
    scale_damping: float
    scale_prestress: float

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
    def n_residuals(self) -> int:
        """Number of residuals: 2 per data point (G' and G'')."""
        return int(self.y_obs.size)

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

    # -- model ----------------------------------------------------------------------
    def _effective(self, phi):
        """Tendon properties on the reference cell (strut length L_ref) equivalent to ``phi``."""
        EA = np.exp(phi[: self.n_ea])[self.ea_groups]
        c = np.exp(phi[self.n_ea: self.n_ea + self.n_c])[self.c_groups]
        p = math.exp(phi[-2])
        lam = math.exp(phi[-1]) / self.L_ref
        # the cell scaled by lam = L/L_ref has the moduli of the reference cell with these
        # properties (module docstring), so L never needs a new cell
        P = p * self.group_prestress / lam**2 if self.kind == "prestress" else np.array([p / lam**2])
        return EA / lam**2, c / lam, P

    def _whitening(self, c):
        """(B, Kpt, bt, Dt): A, Kp, load, probe in the basis where C0 = I."""
        if self.n_c == 1:  # C0 = c·A Aᵀ: rescale the precomputed basis
            s = 1.0 / math.sqrt(c[0])
            B0, Kpt0, bt0, Dt0 = self.white_unit
            return B0 * s, Kpt0 * (s * s), bt0 * s, Dt0 * s
        try:
            Lc = np.linalg.cholesky((self.A * c) @ self.A.T)
        except np.linalg.LinAlgError:
            return None
        return _whiten(Lc, self.A, self.Kp, self.load, self.probe)


    def _evaluate(self, phi, jac: bool):
        """Complex moduli G (N,) and, if ``jac``, d log G / d phi (N, n_params); None if unstable."""
        EA, c, P = self._effective(phi)
        wh = self._whitening(c)
        if wh is None:
            return None
        B, Kpt, bt, Dt = wh
        Bl = B / np.sqrt(self.lengths)
        KE = (Bl * EA) @ Bl.T
        Kt = P[:, None, None] * Kpt[None] + KE[None]
        lam, W = np.linalg.eigh(Kt)  # rates (1/s) and whitened C0-orthonormal modes
        if not np.all(lam > 0):
            return None
        alpha = np.einsum("gnk,n->gk", W, Dt)  # probe projections, D0·v_k
        beta = np.einsum("gnk,n->gk", W, bt)  # load projections, −H0·v_k
        g = self.group_index
        R = 1.0 / (lam[g] + 1j * self.omega[:, None])  # (N, n)
        aR = alpha[g] * R
        bR = beta[g] * R
        J = np.sum(alpha[g] * bR, axis=1)
        G = (0.5 / self.L_ref) / J
        if not jac:
            return G, None
        AV = np.matmul(B.T[None], W)  # (G, m, n): a_jᵀ v_k
        M = np.matmul(np.transpose(W, (0, 2, 1)), np.matmul(Kpt[None], W))  # Vᵀ Kp V
        if lam.shape[0] == 1:  # one prestress: plain matrix products
            ax = bR @ AV[0].T  # a_jᵀ x(ω_i), (N, m)
            ay = aR @ AV[0].T  # a_jᵀ y(ω_i)
            dJ_P = -np.einsum("ik,kl,il->i", aR, M[0], bR) * P[0]  # P ∂J/∂P
        else:
            ax = np.einsum("imk,ik->im", AV[g], bR)
            ay = np.einsum("imk,ik->im", AV[g], aR)
            dJ_P = -np.einsum("ik,ikl,il->i", aR, M[g], bR) * P[g]
        pr = ax * ay
        dJ_EA = -pr * (EA / self.lengths)  # EA_j ∂J/∂EA_j
        dJ_c = -1j * self.omega[:, None] * pr * c  # c_j ∂J/∂c_j
        dJ = np.empty((J.size, self.n_params), dtype=complex)
        dJ[:, : self.n_ea] = dJ_EA @ np.eye(self.n_ea)[self.ea_groups]
        dJ[:, self.n_ea: self.n_ea + self.n_c] = dJ_c @ np.eye(self.n_c)[self.c_groups]
        dJ[:, -2] = dJ_P
        # L enters only through the effective parameters (P/λ², EA/λ², c/λ)
        dJ[:, -1] = -2.0 * dJ_P - 2.0 * dJ_EA.sum(axis=1) - dJ_c.sum(axis=1)
        return G, -dJ / J[:, None]

    def moduli(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """Model G', G'' (Pa) at the data points, shape (N,) each; NaN where the model is unstable."""
        out = self._evaluate(self.full(theta), jac=False)
        if out is None:
            nan = np.full(self.omega.size, np.nan)
            return nan, nan.copy()
        return out[0].real, out[0].imag

    def residuals(self, theta) -> np.ndarray:
        """Weighted residuals ``w·(log10 G_model − log10 G_data)``, shape (2N,) (G' block, then G'')."""
        out = self._evaluate(self.full(theta), jac=False)
        return self._residuals_from(out)

    def _residuals_from(self, out) -> np.ndarray:
        if out is None:
            return np.full(self.y_obs.size, _PENALTY)
        G = out[0]
        if not (np.all(G.real > 0) and np.all(G.imag > 0)):
            return np.full(self.y_obs.size, _PENALTY)
        model = np.concatenate([np.log10(G.real), np.log10(G.imag)])
        return self.weights * (model - self.y_obs)

    def jacobian(self, theta) -> np.ndarray:
        """Analytic Jacobian of :meth:`residuals` with respect to ``theta``, shape (2N, n_free)."""
        out = self._evaluate(self.full(theta), jac=True)
        return self._jacobian_from(out)

    def _jacobian_from(self, out) -> np.ndarray:
        if out is None or out[1] is None:
            return np.zeros((self.y_obs.size, self.n_free))
        G, dlogG = out
        dG = G[:, None] * dlogG[:, self.free]
        with np.errstate(divide="ignore", invalid="ignore"):
            rows = np.vstack([dG.real / (G.real[:, None] * _LN10), dG.imag / (G.imag[:, None] * _LN10)])
        return self.weights[:, None] * np.nan_to_num(rows)

    def jacobian_fd(self, theta, step: float = 1e-5) -> np.ndarray:
        """Central finite-difference Jacobian of :meth:`residuals` (the slow reference), shape (2N, n_free)."""
        theta = np.asarray(theta, dtype=float)
        out = np.empty((self.y_obs.size, theta.size))
        for k in range(theta.size):
            e = np.zeros_like(theta)
            e[k] = step
            out[:, k] = (self.residuals(theta + e) - self.residuals(theta - e)) / (2 * step)
        return out

    def rms(self, theta) -> float:
        """RMS of the unweighted log10 residuals (decades)."""
        r = self.residuals(theta)
        return float(np.sqrt(np.mean((r / self.weights) ** 2)))

    def parameters(self, theta) -> tuple:
        """The parameters as :class:`FitParameter` records."""
        vals = self.values(theta)
        lo, hi = np.exp(self.lower), np.exp(self.upper)
        return tuple(
            FitParameter(name=n, value=float(v), lower=float(a), upper=float(b), unit=u, vary=bool(fr), description=d)
            for n, v, a, b, u, fr, d in zip(self.names, vals, lo, hi, self.units, self.free, self.descriptions)
        )

    def effective_properties(self, theta):
        """(EA (m,), c (m,), P (groups,)) on the reference cell (N, N·s/m, N) equivalent to ``theta``."""
        return self._effective(self.full(theta))


# ---------------------------------------------------------------------------------
# building a problem
# ---------------------------------------------------------------------------------
def required_points(tendons: str = "per-tendon", damping: str = "uniform", n_families: int = 2) -> int:
    """Minimum number of data points for a fit.

    Each point gives two residuals. Per-tendon stiffnesses are deliberately
    over-parametrized (as in the paper: 36 parameters against 32 residuals
    for the 16-point frequency data; the trust-region solver handles it, and
    the alternatives show the non-uniqueness), so they count as one stiffness
    here; the other parameters (c, P or s, L) each count.
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


def make_problem(
    data: RheologyData,
    cell: Cell | None = None,
    *,
    tendons: str = "per-tendon",
    damping: str = "uniform",
    bounds: dict | None = None,
    fixed: dict | None = None,
) -> FitProblem:
    """Set up the fit of ``cell``'s linear model to ``data``.

    Parameters
    ----------
    data : RheologyData
        A frequency sweep (``kind="frequency"``) or prestress sweep.
    cell : Cell, optional
        The reference (default :func:`tenscell.paper_cell`). Its damping
        matrix must be positive definite for positive c (true for the paper
        cell with intermediate filaments).
    tendons : {"per-tendon", "per-family", "uniform"}
        Stiffness parametrization.
    damping : {"uniform", "per-family"}
        Damping parametrization.
    bounds : dict, optional
        ``{"EA": (lo, hi), "c": (lo, hi), "P": (lo, hi), "s": (lo, hi), "L": (lo, hi)}``
        in N, N·s/m, N, m², m; each applies to every parameter of that kind.
        Defaults scale with the data: with ``S = median(G')·L²`` (N) and
        ``ω_m = 2π·geomean(f)``: EA in [1e-8, 1e6]·S, c in [1e-6, 1e6]·S/ω_m,
        P in [1e-10, 1e4]·S (s likewise, divided by the median prestress),
        L in [1e-3, 1e3]·L_cell.
    fixed : dict, optional
        Scalar parameters to hold fixed: any of ``"c"``, ``"P"`` (frequency
        sweep), ``"s"`` (prestress sweep), ``"L"``, with values in SI units.
        ``c`` is only fixable with uniform damping.

    Returns
    -------
    FitProblem

    Raises
    ------
    ValueError
        Unknown modes, bad bounds or fixed values, a cell with singular
        damping, or too few data points (:func:`required_points`).
    """
    from ..model.shapes import paper_cell

    if not isinstance(data, RheologyData):
        raise ValueError(f"data must be a tenscell.io.data.RheologyData, got {type(data).__name__}")
    _choice("tendons", tendons, TENDON_MODES)
    _choice("damping", damping, DAMPING_MODES)
    cell = paper_cell() if cell is None else cell
    if not isinstance(cell, Cell):
        raise ValueError(f"cell must be a tenscell Cell, got {type(cell).__name__}")
    A = cell.A.toarray() if sp.issparse(cell.A) else np.asarray(cell.A, dtype=float)
    Kp = cell.Kp.toarray() if sp.issparse(cell.Kp) else np.asarray(cell.Kp, dtype=float)
    m = cell.m
    AAt = A @ A.T
    ev = np.linalg.eigvalsh(AAt)
    # Cholesky alone can pass a singular matrix on rounding noise; compare with its scale
    if not ev[0] > 1e-10 * ev[-1]:
        raise ValueError(
            f"{cell.describe()}: the damping matrix C0 = Σ c_j a_j a_jᵀ is singular (the tendons leave a mechanism "
            "undamped, e.g. the cell without intermediate filaments), so its relaxation spectrum, which the fit "
            "uses, does not exist; fit a cell with a positive definite C0"
        )
    chol = np.linalg.cholesky(AAt)

    fam_groups, fams = _family_groups(cell)
    need = required_points(tendons, damping, n_families=len(fams))
    if data.n < need:
        raise DataError(
            f"{data.source}: {data.n} data point{'s' if data.n != 1 else ''}, fewer than the {need} the fit "
            f"needs (tendons={tendons!r}, damping={damping!r}: at least as many points as stiffness groups "
            f"+ damping groups + prestress + L)"
        )

    labels = _tendon_labels(cell)
    if tendons == "per-tendon":
        ea_groups = np.arange(m)
        ea_names = [f"EA[{j}]" for j in range(m)]
        ea_desc = [f"stiffness of tendon {j}, {lab}" for j, lab in enumerate(labels)]
    elif tendons == "per-family":
        ea_groups = fam_groups
        ea_names = [f"EA_{f}" for f in fams]
        ea_desc = [f"stiffness of every {f} tendon" for f in fams]
    else:
        ea_groups = np.zeros(m, dtype=int)
        ea_names = ["EA"]
        ea_desc = ["stiffness of every tendon"]
    if damping == "per-family":
        c_groups = fam_groups
        c_names = [f"c_{f}" for f in fams]
        c_desc = [f"damping of every {f} tendon" for f in fams]
    else:
        c_groups = np.zeros(m, dtype=int)
        c_names = ["c"]
        c_desc = ["damping of every tendon"]

    prestress_sweep = data.kind == "prestress"
    p_name = "s" if prestress_sweep else "P"
    p_unit = "m²" if prestress_sweep else "N"
    p_desc = ("prestress scale: model prestress (N) = s × measured prestress (Pa)" if prestress_sweep
              else "prestress: tendon tensions are P·T0")
    names = tuple(ea_names + c_names + [p_name, "L"])
    units = tuple(["N"] * len(ea_names) + ["N·s/m"] * len(c_names) + [p_unit, "m"])
    descs = tuple(ea_desc + c_desc + [p_desc, "strut length (redundant with P, EA, c: see docs)"])

    # scales for default bounds and the initial guess
    L_ref = float(cell.strut_length)
    f = data.frequency_hz
    omega = 2 * np.pi * f
    S = float(np.median(data.G_storage)) * L_ref**2
    w_m = float(np.exp(np.mean(np.log(omega))))
    P_med = float(np.median(data.prestress)) if prestress_sweep else 1.0
    defaults = {
        "EA": (1e-8 * S, 1e6 * S),
        "c": (1e-6 * S / w_m, 1e6 * S / w_m),
        "P": (1e-10 * S, 1e4 * S),
        "s": (1e-10 * S / P_med, 1e4 * S / P_med),
        "L": (1e-3 * L_ref, 1e3 * L_ref),
    }
    bounds = dict(bounds or {})
    for key in bounds:
        if key not in defaults:
            raise ValueError(f"bounds: unknown parameter kind {key!r}; allowed: {', '.join(defaults)}")
        if key == ("P" if prestress_sweep else "s"):
            raise ValueError(f"bounds: {key!r} does not apply to a {data.kind} sweep (use {p_name!r})")
    kinds = ["EA"] * len(ea_names) + ["c"] * len(c_names) + [p_name, "L"]
    lower = np.empty(len(names))
    upper = np.empty(len(names))
    for i, k in enumerate(kinds):
        lo, hi = bounds.get(k, defaults[k])
        lo = positive_scalar(f"bounds[{k!r}] lower", lo)
        hi = positive_scalar(f"bounds[{k!r}] upper", hi)
        if not lo < hi:
            raise ValueError(f"bounds[{k!r}]: the lower bound {lo!r} must be below the upper bound {hi!r}")
        lower[i], upper[i] = math.log(lo), math.log(hi)

    free = np.ones(len(names), dtype=bool)
    fixed_log = 0.5 * (lower + upper)
    fixed_log[-1] = math.log(L_ref) if lower[-1] < math.log(L_ref) < upper[-1] else fixed_log[-1]
    for key, value in dict(fixed or {}).items():
        allowed = (["c"] if damping == "uniform" else []) + [p_name, "L"]
        if key not in allowed:
            raise ValueError(f"fixed: cannot fix {key!r}; fixable here: {', '.join(allowed)}")
        v = positive_scalar(f"fixed[{key!r}]", value)
        i = names.index(key)
        if not lower[i] <= math.log(v) <= upper[i]:
            raise ValueError(f"fixed[{key!r}] = {v!r} lies outside its bounds [{math.exp(lower[i]):.6g}, "
                             f"{math.exp(upper[i]):.6g}]")
        free[i] = False
        fixed_log[i] = math.log(v)

    if prestress_sweep:
        uniq, group_index = np.unique(data.prestress, return_inverse=True)
    else:
        uniq, group_index = np.array([1.0]), np.zeros(data.n, dtype=int)
    y_obs = np.concatenate([np.log10(data.G_storage), np.log10(data.G_loss)])
    weights = np.concatenate([data.weights_storage, data.weights_loss])
    return FitProblem(
        names=names, units=units, descriptions=descs, lower=lower, upper=upper, free=free, fixed_log=fixed_log,
        kind=data.kind, tendons=tendons, damping=damping, n_ea=len(ea_names), n_c=len(c_names),
        ea_groups=np.asarray(ea_groups), c_groups=np.asarray(c_groups),
        A=A, lengths=np.asarray(cell.lengths, dtype=float), Kp=0.5 * (Kp + Kp.T),
        load=np.asarray(cell.load, dtype=float), probe=np.asarray(cell.probe, dtype=float), L_ref=L_ref,
        white_unit=_whiten(chol, A, 0.5 * (Kp + Kp.T), np.asarray(cell.load, dtype=float),
                           np.asarray(cell.probe, dtype=float)),
        omega=omega, group_index=np.asarray(group_index).ravel(), group_prestress=uniq,
        y_obs=y_obs, weights=weights, scale_stiffness=S, scale_damping=S / w_m,
        scale_prestress=S / P_med,
    )

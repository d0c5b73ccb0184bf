"""Heterogeneous fits of the linear tensegrity model to measured cell rheology.

The paper (Sultan, Stamenović & Ingber 2004, Figs. 4–5) fits tendon
stiffnesses, the damping c, the prestress P and the strut length L so that the
model's G', G'' match measured data; a homogeneous cell cannot do it. This
module does the same for any :class:`tenscell.io.data.RheologyData`.

Parameters and units
--------------------
* ``EA`` (N): per tendon (``tendons="per-tendon"``, 33 values for the paper
  cell), per family (actin / intermediate filament) or one for all.
* ``c`` (N·s/m): one value (the paper) or per family (``damping="per-family"``).
* ``P`` (N): prestress scale for a frequency sweep; for a prestress sweep the
  model prestress of each point is ``s·P_exp`` and the parameter is the scale
  ``s`` (m², since ``P_exp`` is in Pa).
* ``L`` (m): strut length. For the linear moduli it is exactly redundant:
  ``(P, EA, c, L) -> (P/λ², EA/λ², c/λ, λL)`` leaves G unchanged (a cell scaled
  by λ has ``J_λ(ω) = λ·J_1(λω)``). It is fitted as the paper did, starts at
  the cell's own L and stays there unless other parameters are fixed or hit
  bounds; fix P or c to make it identifiable.

Everything is fitted in natural-log space within bounds. Residuals are
``w·(log10 G_model − log10 G_data)`` for G' and G'' (``w`` = 1, or
``1/sd(log10 G)`` when the data have standard deviations). The Jacobian is
analytic, from the relaxation spectrum ``K0 v = λ C0 v``: with
``x = Z⁻¹(−H0)``, ``y = Z⁻ᵀ D0ᵀ`` and ``Z = K0 + iωC0``,
``∂J/∂EA_j = −(yᵀa_j)(a_jᵀx)/l_j``, ``∂J/∂c_j = −iω(yᵀa_j)(a_jᵀx)``,
``∂J/∂P = −yᵀKp x``, all frequencies at once from a few matrix products.

Search strategy: each start draws tendon stiffnesses log-uniformly over 5–10
decades, places the damping (a frequency shift) and the overall scale on the
data by a grid and an exact scaling, runs a trust-region least-squares fit
(:func:`scipy.optimize.least_squares`, ``method="trf"``, which accepts more
parameters than residuals), then improves it by monotonic basin hopping: a few
tendon stiffnesses are redrawn and the fit re-polished, keeping improvements.
Redrawing a few stiffnesses moves one relaxation time to another decade, which
is what a power law over many decades needs; it is worth far more than extra
random starts.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.sparse as sp
from threadpoolctl import threadpool_limits

from ._parallel import starmap
from ._checks import positive_scalar
from .io.data import DataError, RheologyData
from .model.equilibrium import Cell
from .linear.linearize import linearize
from .response import compliance, log_slope

__all__ = [
    "TENDON_MODES",
    "DAMPING_MODES",
    "FitParameter",
    "FitAlternative",
    "FitResult",
    "FitCurve",
    "FitProblem",
    "make_problem",
    "fit",
    "model_curve",
    "frequency_slopes",
    "prestress_slopes",
    "fit_markdown",
    "required_points",
]

#: how tendon stiffnesses are parametrized
TENDON_MODES = ("per-tendon", "per-family", "uniform")
#: how tendon damping is parametrized
DAMPING_MODES = ("uniform", "per-family")

_LN10 = math.log(10.0)
# A residual (in decades) returned where the model is not a stable, passive
# cell (K0 not positive definite, G' or G'' <= 0). Finite, so that the
# trust-region solver simply rejects the step.
_PENALTY = 10.0


# ---------------------------------------------------------------------------------
# public records
# ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class FitParameter:
    """One fitted (or fixed) parameter.

    Attributes
    ----------
    name : str
        ``"EA[j]"``, ``"EA_actin"``, ``"EA"``, ``"c"``, ``"c_actin"``, ``"P"``,
        ``"s"`` or ``"L"``.
    value : float
        In ``unit``.
    lower, upper : float
        Bounds (same unit); the fit works in log space between them.
    unit : str
    vary : bool
        False if the user fixed it.
    description : str
        What the parameter is (for a tendon: its nodes and family).
    """

    name: str
    value: float
    lower: float
    upper: float
    unit: str
    vary: bool = True
    description: str = ""

    @property
    def at_bound(self) -> str | None:
        """``"lower"`` or ``"upper"`` if a varied parameter sits at a bound (within 0.1 % in log), else None."""
        if not self.vary:
            return None
        span = math.log(self.upper / self.lower)
        x = math.log(self.value)
        if x - math.log(self.lower) <= 1e-3 * span:
            return "lower"
        if math.log(self.upper) - x <= 1e-3 * span:
            return "upper"
        return None

    def to_dict(self) -> dict:
        """JSON-ready dict."""
        return {
            "name": self.name, "value": self.value, "unit": self.unit, "lower": self.lower, "upper": self.upper,
            "vary": self.vary, "at_bound": self.at_bound, "description": self.description,
        }


@dataclass(frozen=True)
class FitAlternative:
    """A solution from another start that fits almost as well as the best.

    Attributes
    ----------
    start : int
        Index of the start (0-based).
    rms_log10_error : float
        RMS of the unweighted log10 residuals.
    parameters : tuple of FitParameter
    """

    start: int
    rms_log10_error: float
    parameters: tuple

    def to_dict(self) -> dict:
        """JSON-ready dict."""
        return {"start": self.start, "rms_log10_error": self.rms_log10_error,
                "parameters": {p.name: p.value for p in self.parameters}}


@dataclass(frozen=True, eq=False)
class FitCurve:
    """A model curve to draw beside the data (computed here, drawn by plotting).

    Attributes
    ----------
    x : ndarray, shape (k,)
        Frequency (Hz) for a frequency sweep, prestress (Pa) for a prestress sweep.
    G_storage, G_loss : ndarray, shape (k,)
        Model moduli (Pa).
    label : str
    rms_log10_error : float
    kind : {"frequency", "prestress"}
    """

    x: np.ndarray
    G_storage: np.ndarray
    G_loss: np.ndarray
    label: str
    rms_log10_error: float
    kind: str


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


class _Objective:
    """Residuals and Jacobian sharing one model evaluation per parameter vector."""

    def __init__(self, problem: FitProblem):
        self.problem = problem
        self._key = None
        self._out = None
        self.nfev = 0

    def _eval(self, theta):
        key = theta.tobytes()
        if key != self._key:
            self._out = self.problem._evaluate(self.problem.full(theta), jac=True)
            self._key = key
            self.nfev += 1
        return self._out

    def fun(self, theta):
        return self.problem._residuals_from(self._eval(theta))

    def jac(self, theta):
        return self.problem._jacobian_from(self._eval(theta))


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
    from .model.shapes import paper_cell

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


# ---------------------------------------------------------------------------------
# the search
# ---------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class _Chain:
    start: int
    theta: np.ndarray
    rms: float
    cost: float
    nfev: int
    hops: int
    message: str
    status: int
    history: tuple  # ((seconds since the fit began, rms, theta), ...) at each improvement


def _clip(problem: FitProblem, theta):
    lo, hi = problem.bounds
    pad = 1e-9 * (hi - lo)
    return np.clip(theta, lo + pad, hi - pad)


def _initial_guess(problem: FitProblem, rng: np.random.Generator) -> np.ndarray:
    """A start: stiffnesses log-uniform over 5–10 decades, damping and scale placed on the data."""
    phi = problem.fixed_log.copy()
    n_ea, n_c = problem.n_ea, problem.n_c
    spread = rng.uniform(5.0, 10.0) if problem.tendons == "per-tendon" else rng.uniform(0.0, 3.0)
    u = rng.uniform(-0.5, 0.5, n_ea) * spread * _LN10 if n_ea > 1 else np.zeros(1)
    u = u + math.log(problem.scale_stiffness)
    c_jitter = rng.normal(0.0, 0.3, n_c) if n_c > 1 else np.zeros(1)
    free = problem.free
    ic = slice(n_ea, n_ea + n_c)
    base_p = math.log(problem.scale_prestress / problem.scale_stiffness)
    best = None
    # damping c shifts the spectrum in frequency; the prestress-to-stiffness ratio sets how much P matters
    c_grid = np.linspace(-6.0, 6.0, 25) * _LN10 if free[n_ea] else [None]
    if problem.kind == "prestress":
        # the data vary with prestress, so P must matter: relative to a typical tendon, not the
        # softest (a negligible P is a flat, prestress-blind trap the solver cannot leave)
        p_ref = float(np.median(u))
        p_grid = np.array([-2.0, -1.0, 0.0, 1.0]) * _LN10 if free[-2] else [None]
    else:
        p_ref = float(u.min())
        p_grid = np.array([-6.0, -3.0, 0.0]) * _LN10 if free[-2] else [None]
    for lc in c_grid:
        for lp in p_grid:
            trial = phi.copy()
            trial[:n_ea] = u
            if lc is not None:
                trial[ic] = math.log(problem.scale_damping) + lc + c_jitter
            if lp is not None:
                trial[-2] = p_ref + lp + base_p
            out = problem._evaluate(trial, jac=False)
            r = problem._residuals_from(out) / problem.weights
            if out is None or np.any(np.abs(r) >= _PENALTY):
                continue
            # scaling every free EA, c and P together by k scales G by k (exact): take the best k
            shift = -float(np.mean(r)) * _LN10
            scalable = np.zeros(problem.n_params, dtype=bool)
            scalable[:-1] = free[:-1]
            trial[scalable] += shift
            rms = float(np.sqrt(np.mean((r - np.mean(r)) ** 2)))
            if best is None or rms < best[0]:
                best = (rms, trial)
    if best is None:
        trial = phi.copy()
        trial[:n_ea] = u
        best = (np.inf, trial)
    return _clip(problem, best[1][free])


def _perturb(problem: FitProblem, theta, rng: np.random.Generator) -> np.ndarray:
    """A basin-hopping move: redraw a few stiffnesses (or jitter every parameter of a small model)."""
    phi = problem.full(theta)
    free = problem.free
    ea_free = np.flatnonzero(free[: problem.n_ea])
    y = phi.copy()
    if problem.tendons == "per-tendon" and ea_free.size >= 3:
        pick = rng.choice(ea_free, size=3, replace=False)
        lo, hi = float(phi[ea_free].min()), float(phi[ea_free].max())
        if hi - lo < 4 * _LN10:
            mid = 0.5 * (lo + hi)
            lo, hi = mid - 2 * _LN10, mid + 2 * _LN10
        y[pick] = rng.uniform(lo, hi, size=3)
    else:
        move = free.copy()
        # L is a gauge of (P, EA, c) unless one of c, P is held fixed: moving it only wanders
        move[-1] &= not bool(np.all(free[problem.n_ea: -1]))
        y[move] += rng.normal(0.0, 1.0, int(move.sum())) * _LN10
    return _clip(problem, y[free])


def _least_squares(problem: FitProblem, theta, max_nfev: int):
    obj = _Objective(problem)
    lo, hi = problem.bounds
    res = scipy.optimize.least_squares(
        obj.fun, theta, jac=obj.jac, bounds=(lo, hi), method="trf", x_scale="jac",
        max_nfev=max_nfev, xtol=1e-10, ftol=1e-10, gtol=1e-10,
    )
    return res, obj.nfev


def _run_chain(problem: FitProblem, start: int, seed_seq, hops: int, patience: int, max_nfev: int,
               t_begin: float, target: float) -> _Chain:
    """One start: initial guess, least squares, then monotonic basin hopping."""
    # The matrices are tiny (n ~ 24): BLAS threads only add overhead, and on a
    # shared machine they make each evaluation ~10x slower.
    with threadpool_limits(limits=1, user_api="blas"):
        return _hop(problem, start, seed_seq, hops, patience, max_nfev, t_begin, target)


def _hop(problem: FitProblem, start: int, seed_seq, hops: int, patience: int, max_nfev: int,
         t_begin: float, target: float) -> _Chain:
    rng = np.random.default_rng(seed_seq)
    theta = _initial_guess(problem, rng)
    res, nfev = _least_squares(problem, theta, max_nfev)
    best, rms = res, problem.rms(res.x)
    history = [(time.monotonic() - t_begin, rms, res.x.copy())]
    stale = done = 0
    while done < hops and rms > target and stale < patience:
        done += 1
        trial, n = _least_squares(problem, _perturb(problem, best.x, rng), max_nfev)
        nfev += n
        if trial.cost < best.cost:
            r = problem.rms(trial.x)
            stale = 0 if r < 0.95 * rms else stale + 1
            best, rms = trial, r
            history.append((time.monotonic() - t_begin, rms, best.x.copy()))
        else:
            stale += 1
    return _Chain(start=start, theta=best.x, rms=rms, cost=float(best.cost), nfev=nfev, hops=done,
                  message=str(best.message), status=int(best.status), history=tuple(history))


def _progress(total: int, desc: str):
    import sys

    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="start", file=sys.stderr, disable=None, leave=False)


# ---------------------------------------------------------------------------------
# the result
# ---------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class FitResult:
    """The outcome of :func:`fit`.

    Attributes
    ----------
    parameters : tuple of FitParameter
        Best-fit parameters (named, with bounds and whether a bound is hit).
    residuals : ndarray, shape (2N,)
        Unweighted ``log10 G_model − log10 G_data``: the N G' residuals, then the N G'' ones.
    rms_log10_error : float
        RMS of ``residuals`` (decades).
    tolerance : float
        The RMS the fit had to reach.
    converged : bool
        True if ``rms_log10_error <= tolerance``.
    message : str
        What happened, in words (including the optimizer's last message).
    data : RheologyData
    cell : Cell
        The reference cell (strut length ``L_ref``); the model at the fitted L is its scaled copy.
    problem : FitProblem
    theta : ndarray
        Free log-parameters of the best fit.
    tendons, damping : str
        The parametrization.
    starts : int
    seed : int or None
    elapsed_s : float
        Wall-clock time of the whole fit, all starts (s).
    n_evaluations : int
        Model evaluations over all starts.
    alternatives : tuple of FitAlternative
        Other starts' solutions with RMS within ``max(tolerance, 1.5 × best)``, best first.
    start_rms : tuple of float
        Final RMS of every start, in start order.
    history : tuple of (float, float)
        ``(seconds since the fit began, best RMS so far)`` at each improvement over all starts.
    history_theta : tuple of ndarray
        The free log-parameters at each entry of ``history``.
    """

    parameters: tuple
    residuals: np.ndarray
    rms_log10_error: float
    tolerance: float
    converged: bool
    message: str
    data: RheologyData
    cell: Cell
    problem: FitProblem
    theta: np.ndarray
    tendons: str
    damping: str
    starts: int
    seed: int | None
    elapsed_s: float
    n_evaluations: int
    alternatives: tuple
    start_rms: tuple
    history: tuple
    history_theta: tuple

    # -- accessors ------------------------------------------------------------------
    def value(self, name: str) -> float:
        """The value of parameter ``name`` (SI units)."""
        for p in self.parameters:
            if p.name == name:
                return p.value
        raise ValueError(f"no parameter named {name!r}; parameters: {', '.join(p.name for p in self.parameters)}")

    @property
    def EA(self) -> np.ndarray:
        """Stiffness of every tendon (N), shape (m,)."""
        vals = self.problem.values(self.theta)
        return vals[: self.problem.n_ea][self.problem.ea_groups]

    @property
    def c(self) -> np.ndarray:
        """Damping of every tendon (N·s/m), shape (m,)."""
        vals = self.problem.values(self.theta)
        return vals[self.problem.n_ea: self.problem.n_ea + self.problem.n_c][self.problem.c_groups]

    @property
    def L(self) -> float:
        """Fitted strut length (m)."""
        return float(self.problem.values(self.theta)[-1])

    @property
    def stiffness_spread(self) -> tuple[float, float, float]:
        """(min EA, max EA, decades = log10(max/min)) over the tendons (N, N, -)."""
        EA = self.EA
        return float(EA.min()), float(EA.max()), float(math.log10(EA.max() / EA.min()))

    @property
    def stiffness_spread_interior(self) -> tuple[float, float, float] | None:
        """Like :attr:`stiffness_spread`, over the tendons whose stiffness is not at a bound (None if none is)."""
        inside = np.array([self.parameters[g].at_bound is None for g in self.problem.ea_groups])
        if not inside.any():
            return None
        e = self.EA[inside]
        return float(e.min()), float(e.max()), float(math.log10(e.max() / e.min()))

    @property
    def n_at_bound(self) -> int:
        """How many varied parameters sit at a bound."""
        return sum(p.at_bound is not None for p in self.parameters)

    def prestress_model(self, prestress_pa=None) -> np.ndarray:
        """Model prestress P (N) for measured prestresses (Pa) of a prestress sweep, or the fitted P."""
        vals = self.problem.values(self.theta)
        if self.problem.kind == "prestress":
            if prestress_pa is None:
                raise ValueError("prestress_pa (Pa) is required for a prestress-sweep fit")
            return vals[-2] * np.asarray(prestress_pa, dtype=float)
        return np.array([vals[-2]])

    def moduli(self, f_hz, prestress_pa=None) -> tuple[np.ndarray, np.ndarray]:
        """Fitted model's G', G'' (Pa) at frequencies ``f_hz`` (Hz), computed by the core pipeline.

        For a prestress-sweep fit ``prestress_pa`` (Pa) is required and must
        broadcast with ``f_hz``; the model prestress is ``s·prestress_pa``.
        """
        f = np.atleast_1d(np.asarray(f_hz, dtype=float))
        if self.problem.kind == "prestress":
            Pm = np.atleast_1d(self.prestress_model(prestress_pa))
        else:
            Pm = self.prestress_model()
        f, Pm = np.broadcast_arrays(f, Pm)
        lam = self.L / self.problem.L_ref
        EA, c = self.EA / lam**2, self.c / lam
        Gs = np.empty(f.shape)
        Gl = np.empty(f.shape)
        for P in np.unique(Pm):
            sel = Pm == P
            lin = linearize(self.cell, P=P / lam**2, EA=EA, c=c, check=False)
            G = (0.5 / self.problem.L_ref) / compliance(lin, f[sel])
            Gs[sel], Gl[sel] = G.real, G.imag
        return Gs, Gl

    # -- output ---------------------------------------------------------------------
    def to_dict(self) -> dict:
        """JSON-ready summary: parameters, rms_log10_error, converged, time taken, alternatives..."""
        lo, hi, dec = self.stiffness_spread
        return {
            "data": self.data.source,
            "kind": self.data.kind,
            "n_points": self.data.n,
            "cell": self.cell.describe(),
            "tendons": self.tendons,
            "damping": self.damping,
            "rms_log10_error": self.rms_log10_error,
            "rms_log10_error_storage": float(np.sqrt(np.mean(self.residuals[: self.data.n] ** 2))),
            "rms_log10_error_loss": float(np.sqrt(np.mean(self.residuals[self.data.n:] ** 2))),
            "tolerance": self.tolerance,
            "converged": self.converged,
            "message": self.message,
            "time_s": self.elapsed_s,
            "starts": self.starts,
            "seed": None if self.seed is None else int(self.seed),
            "n_evaluations": self.n_evaluations,
            "n_free_parameters": self.problem.n_free,
            "n_residuals": self.problem.n_residuals,
            "parameters": [p.to_dict() for p in self.parameters],
            "tendon_stiffness_spread": {"min_N": lo, "max_N": hi, "decades": dec},
            "tendon_stiffness_spread_not_at_bounds": (
                None if self.stiffness_spread_interior is None else dict(
                    zip(("min_N", "max_N", "decades"), self.stiffness_spread_interior))),
            "residuals_log10": {"G_storage": self.residuals[: self.data.n].tolist(),
                                "G_loss": self.residuals[self.data.n:].tolist()},
            "start_rms": list(self.start_rms),
            "alternatives": [a.to_dict() for a in self.alternatives],
            "history": [{"time_s": t, "rms_log10_error": r} for t, r in self.history],
        }

    def _interior_text(self) -> str:
        inner = self.stiffness_spread_interior
        full = self.stiffness_spread
        if inner is None or inner == full:
            return ""
        return f"; {inner[0]:.3g} .. {inner[1]:.3g} N ({inner[2]:.1f} decades) without those at bounds"

    def report(self) -> str:
        """A readable plain-text report (in the spirit of lmfit's ``fit_report``)."""
        d = self.data
        lo, hi, dec = self.stiffness_spread
        lines = [
            "[[Fit statistics]]",
            f"    data:               {d.source} ({d.n} points, {d.kind} sweep)",
            f"    model:              {self.cell.describe()}; stiffness {self.tendons}, damping {self.damping}",
            f"    free parameters:    {self.problem.n_free} (residuals: {self.problem.n_residuals})",
            f"    rms log10 error:    {self.rms_log10_error:.5f} (tolerance {self.tolerance:g}): "
            + ("converged" if self.converged else "NOT converged"),
            f"    starts:             {self.starts} (seed {self.seed}), {self.n_evaluations} model evaluations, "
            f"{self.elapsed_s:.1f} s",
            f"    stiffness spread:   {lo:.3g} .. {hi:.3g} N ({dec:.1f} decades)" + self._interior_text(),
            f"    message:            {self.message}",
            "[[Parameters]]",
        ]
        width = max(len(p.name) for p in self.parameters)
        for p in self.parameters:
            flag = "" if p.vary else " (fixed)"
            if p.at_bound:
                flag += f" at {p.at_bound} bound"
            lines.append(f"    {p.name:<{width}} = {p.value:<12.6g} {p.unit:<6} "
                         f"[{p.lower:.3g}, {p.upper:.3g}]{flag}  {p.description}")
        lines.append("[[Residuals log10(model/data)]]")
        x = d.prestress if d.kind == "prestress" else d.frequency_hz
        xname = "P (Pa)" if d.kind == "prestress" else "f (Hz)"
        lines.append(f"    {xname:>10}  {'G_storage':>10}  {'G_loss':>10}")
        for i in range(d.n):
            lines.append(f"    {x[i]:>10.4g}  {self.residuals[i]:>+10.5f}  {self.residuals[d.n + i]:>+10.5f}")
        if self.alternatives:
            lines.append(f"[[Alternatives]] {len(self.alternatives)} other start(s) fit almost as well:")
            for a in self.alternatives:
                lines.append(f"    start {a.start}: rms {a.rms_log10_error:.5f}")
        return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------
# the driver
# ---------------------------------------------------------------------------------
def fit(
    data: RheologyData,
    cell: Cell | None = None,
    *,
    tendons: str = "per-tendon",
    damping: str = "uniform",
    starts: int = 4,
    seed: int | None = 0,
    jobs: int = 1,
    tolerance: float = 0.01,
    hops: int = 30,
    patience: int = 6,
    max_nfev: int = 300,
    polish: float = 0.2,
    bounds: dict | None = None,
    fixed: dict | None = None,
    progress: bool | None = None,
) -> FitResult:
    """Fit the tensegrity model's G', G'' to measured data (multi-start, analytic Jacobian).

    Parameters
    ----------
    data : RheologyData
        Frequency or prestress sweep (see :mod:`tenscell.io.data`).
    cell : Cell, optional
        Reference cell; default :func:`tenscell.paper_cell` (strut length 1 m).
    tendons : {"per-tendon", "per-family", "uniform"}
        Stiffness parametrization ("uniform" is the homogeneous baseline).
    damping : {"uniform", "per-family"}
    starts : int
        Independent starts (each followed by basin hopping). >= 1.
    seed : int or None
        Seed of the numpy Generator; the same seed gives the same result
        whatever ``jobs`` is. None draws fresh entropy.
    jobs : int
        Worker processes over starts (1 = in this process).
    tolerance : float
        RMS of the log10 errors (decades) the fit must reach to count as converged.
    hops : int
        Basin-hopping moves per start, at most.
    patience : int
        Stop a start after this many moves without a 5 % improvement of its RMS.
    max_nfev : int
        Model evaluations per least-squares run.
    polish : float
        A start stops early once its RMS is ``polish × tolerance`` (keeps going
        past the tolerance so that the fit is well inside it, not on its edge).
    bounds, fixed : dict, optional
        See :func:`make_problem`.
    progress : bool or None
        tqdm progress bar on stderr; None = only when stderr is a terminal.

    Returns
    -------
    FitResult

    Raises
    ------
    ValueError
        Bad options, data or cell (see :func:`make_problem`).
    """
    from .model.shapes import paper_cell

    t_begin = time.monotonic()
    cell = paper_cell() if cell is None else cell
    problem = make_problem(data, cell, tendons=tendons, damping=damping, bounds=bounds, fixed=fixed)
    starts = _count("starts", starts, 1)
    jobs = _count("jobs", jobs, 1)
    hops = _count("hops", hops, 0)
    patience = _count("patience", patience, 1)
    max_nfev = _count("max_nfev", max_nfev, 1)
    tolerance = positive_scalar("tolerance", tolerance, "decades")
    polish = positive_scalar("polish", polish)
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise ValueError(f"seed must be a non-negative integer or None, got {seed!r}")
    seq = np.random.SeedSequence(seed)
    children = seq.spawn(starts)
    target = polish * tolerance
    args = [(problem, k, children[k], hops, patience, max_nfev, t_begin, target) for k in range(starts)]

    bar = _progress(starts, f"fit ({tendons})") if progress is not False else None
    try:
        # worker processes that stop cleanly on Ctrl-C and die with this process (tenscell._parallel)
        chains: list[_Chain] = starmap(_run_chain, args, jobs=jobs,
                                       on_done=None if bar is None else (lambda i, ch: bar.update(1)))
    finally:
        if bar is not None:
            bar.close()

    chains.sort(key=lambda ch: ch.start)
    best = min(chains, key=lambda ch: (ch.cost, ch.start))
    theta = best.theta
    r = problem.residuals(theta) / problem.weights
    rms = float(np.sqrt(np.mean(r**2)))
    converged = bool(rms <= tolerance)
    cutoff = max(tolerance, 1.5 * rms)
    alternatives = tuple(
        FitAlternative(start=ch.start, rms_log10_error=ch.rms, parameters=problem.parameters(ch.theta))
        for ch in sorted(chains, key=lambda ch: (ch.rms, ch.start))
        if ch is not best and ch.rms <= cutoff
    )
    # merge the starts' improvement records into one best-so-far trajectory
    events = sorted((t, r_, th) for ch in chains for (t, r_, th) in ch.history)
    history, history_theta, so_far = [], [], math.inf
    for t, r_, th in events:
        if r_ < so_far:
            so_far = r_
            history.append((float(t), float(r_)))
            history_theta.append(th)
    verdict = (f"reached rms {rms:.4g} <= tolerance {tolerance:g}" if converged
               else f"did not reach the tolerance: best rms {rms:.4g} > {tolerance:g}")
    message = (f"{verdict} (best of {starts} start(s), start {best.start} after {best.hops} hop(s); "
               f"optimizer: {best.message})")
    return FitResult(
        parameters=problem.parameters(theta), residuals=r, rms_log10_error=rms, tolerance=tolerance,
        converged=converged, message=message, data=data, cell=cell, problem=problem, theta=theta,
        tendons=tendons, damping=damping, starts=starts, seed=seed, elapsed_s=time.monotonic() - t_begin,
        n_evaluations=sum(ch.nfev for ch in chains), alternatives=alternatives,
        start_rms=tuple(ch.rms for ch in chains), history=tuple(history), history_theta=tuple(history_theta),
    )


def _count(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


# ---------------------------------------------------------------------------------
# analyses of a fit
# ---------------------------------------------------------------------------------
def model_curve(result: FitResult, n: int = 200, label: str | None = None) -> FitCurve:
    """The fitted model on a dense grid spanning the data (for plots).

    Frequency sweep: ``n`` log-spaced frequencies over the data's range (Hz).
    Prestress sweep: ``n`` prestresses over the data's range (Pa) at the
    data's (first) frequency.
    """
    d = result.data
    if d.kind == "prestress":
        x = np.linspace(d.prestress.min(), d.prestress.max(), n)
        Gs, Gl = result.moduli(np.full(n, d.frequency_hz[0]), prestress_pa=x)
    else:
        x = np.logspace(math.log10(d.frequency_hz.min()), math.log10(d.frequency_hz.max()), n)
        Gs, Gl = result.moduli(x)
    if label is None:
        label = {"uniform": "homogeneous", "per-family": "per family", "per-tendon": "heterogeneous"}[result.tendons]
    return FitCurve(x=x, G_storage=Gs, G_loss=Gl, label=label, rms_log10_error=result.rms_log10_error, kind=d.kind)


def frequency_slopes(result: FitResult, f_lo: float = 0.01, f_hi: float = 100.0, n: int = 1000):
    """Local log-log slopes of the fitted G' and G'' on ``n`` log-spaced frequencies in [f_lo, f_hi] Hz.

    Returns
    -------
    f : ndarray (Hz), slope_storage : ndarray, slope_loss : ndarray
    """
    f = np.logspace(math.log10(positive_scalar("f_lo", f_lo, "Hz")), math.log10(positive_scalar("f_hi", f_hi, "Hz")),
                    int(n))
    if result.data.kind == "prestress":
        Gs, Gl = result.moduli(f, prestress_pa=float(np.median(result.data.prestress)))
    else:
        Gs, Gl = result.moduli(f)
    return f, log_slope(f, Gs), log_slope(f, Gl)


def prestress_slopes(result: FitResult, n: int = 100) -> tuple[float, float, float, float]:
    """Straight-line fit of the model's G', G'' against prestress over the data's range.

    Returns
    -------
    (dG'/dP, G'(0) intercept, dG''/dP, G''(0) intercept): slopes dimensionless (Pa/Pa),
    intercepts in Pa, from ``n`` prestresses spanning the data at its first frequency.
    """
    if result.data.kind != "prestress":
        raise ValueError("prestress_slopes needs a prestress-sweep fit")
    curve = model_curve(result, n=n)
    a1, b1 = np.polyfit(curve.x, curve.G_storage, 1)
    a2, b2 = np.polyfit(curve.x, curve.G_loss, 1)
    return float(a1), float(b1), float(a2), float(b2)


def _data_slopes(data: RheologyData):
    a1, b1 = np.polyfit(data.prestress, data.G_storage, 1)
    a2, b2 = np.polyfit(data.prestress, data.G_loss, 1)
    return float(a1), float(b1), float(a2), float(b2)


def fit_markdown(result: FitResult, baseline: FitResult | None = None, title: str | None = None) -> str:
    """A markdown report: verdict, parameters (bounds hit), error table, the homogeneous baseline beside it.

    Parameters
    ----------
    result : FitResult
        The (heterogeneous) fit.
    baseline : FitResult, optional
        The homogeneous fit (``tendons="uniform"``) of the same data.
    """
    d = result.data
    title = title or f"Fit of the tensegrity model to {d.source}"
    lo, hi, dec = result.stiffness_spread
    out = [f"# {title}", ""]
    verdict = "**converged**" if result.converged else "**NOT converged**"
    out += [
        f"- Data: `{d.source}`: {d.n} points, {d.kind} sweep.",
        f"- Model: {result.cell.describe()}; stiffness {result.tendons}, damping {result.damping}; "
        f"{result.problem.n_free} free parameters against {result.problem.n_residuals} residuals.",
        f"- RMS of the log10 errors: **{result.rms_log10_error:.5f}** decades "
        f"(tolerance {result.tolerance:g}): {verdict}.",
        f"- {result.message}",
        f"- Starts: {result.starts} (seed {result.seed}); time {result.elapsed_s:.1f} s; "
        f"{result.n_evaluations} model evaluations.",
        f"- Tendon stiffness spread: {lo:.3g} to {hi:.3g} N ({dec:.1f} decades){result._interior_text()}.",
        "",
    ]
    if baseline is not None:
        out += ["## Heterogeneous fit versus the homogeneous baseline", "",
                "| model | stiffness | free parameters | RMS log10 error | converged |", "|---|---|---|---|---|"]
        for name, r in (("heterogeneous", result), ("homogeneous baseline", baseline)):
            out.append(f"| {name} | {r.tendons} | {r.problem.n_free} | {r.rms_log10_error:.5f} | "
                       f"{'yes' if r.converged else 'no'} |")
        out.append("")
    # shape checks
    out += ["## Shape of the fitted model", ""]
    if d.kind == "frequency":
        f_lo, f_hi = float(d.frequency_hz.min()), float(d.frequency_hz.max())
        _, s1, s2 = frequency_slopes(result, f_lo, f_hi, 1000)
        out.append(f"Local log-log slopes on 1000 frequencies from {f_lo:g} to {f_hi:g} Hz: "
                   f"G' {s1.min():.3f} to {s1.max():.3f}; G'' {s2.min():.3f} to {s2.max():.3f}.")
        if f_lo <= 0.01 and f_hi >= 100:
            _, s1, _ = frequency_slopes(result, 0.01, 100, 1000)
            out.append(f"G' slope from 0.01 to 100 Hz: {s1.min():.3f} to {s1.max():.3f}.")
        if baseline is not None:
            _, b1, _ = frequency_slopes(baseline, f_lo, f_hi, 1000)
            out.append(f"Homogeneous baseline: G' slope {b1.min():.3f} to {b1.max():.3f}.")
    else:
        a1, b1, a2, b2 = prestress_slopes(result)
        da1, db1, da2, db2 = _data_slopes(d)
        out += ["| straight line over the data's prestress range | dG'/dP | G'(0) (Pa) | dG''/dP | G''(0) (Pa) |",
                "|---|---|---|---|---|",
                f"| data | {da1:.4f} | {db1:.2f} | {da2:.4f} | {db2:.2f} |",
                f"| fitted model | {a1:.4f} | {b1:.2f} | {a2:.4f} | {b2:.2f} |"]
        if baseline is not None:
            c1, e1, c2, e2 = prestress_slopes(baseline)
            out.append(f"| homogeneous baseline | {c1:.4f} | {e1:.2f} | {c2:.4f} | {e2:.2f} |")
    out.append("")
    # parameters
    out += ["## Parameters", "", "| parameter | value | unit | lower | upper | note |", "|---|---|---|---|---|---|"]
    for p in result.parameters:
        note = ("fixed" if not p.vary else "") + (f"at {p.at_bound} bound" if p.at_bound else "")
        out.append(f"| {p.name} | {p.value:.6g} | {p.unit} | {p.lower:.3g} | {p.upper:.3g} | {note} |")
    out.append("")
    if result.n_at_bound:
        out += [f"{result.n_at_bound} parameter(s) sit at a bound: a stiffness at its lower bound is a tendon "
                "the fit switched off, one at its upper bound a tendon it made rigid.", ""]
    if baseline is not None:
        out += ["Homogeneous baseline parameters: " + ", ".join(
            f"{p.name} = {p.value:.4g} {p.unit}" + (f" ({p.at_bound} bound)" if p.at_bound else "")
            for p in baseline.parameters), ""]
    # error table
    x = d.prestress if d.kind == "prestress" else d.frequency_hz
    xname = "prestress (Pa)" if d.kind == "prestress" else "frequency (Hz)"
    Gs, Gl = result.problem.moduli(result.theta)
    head = f"| {xname} | G' data (Pa) | G' model (Pa) | log10 error | G'' data (Pa) | G'' model (Pa) | log10 error |"
    sep = "|---|---|---|---|---|---|---|"
    if baseline is not None:
        head += " G' baseline | G'' baseline |"
        sep += "---|---|"
        Bs, Bl = baseline.problem.moduli(baseline.theta)
    out += ["## Errors", "", head, sep]
    for i in range(d.n):
        row = (f"| {x[i]:.4g} | {d.G_storage[i]:.4g} | {Gs[i]:.4g} | {result.residuals[i]:+.4f} | "
               f"{d.G_loss[i]:.4g} | {Gl[i]:.4g} | {result.residuals[d.n + i]:+.4f} |")
        if baseline is not None:
            row += f" {Bs[i]:.4g} | {Bl[i]:.4g} |"
        out.append(row)
    out.append("")
    if result.alternatives:
        out += ["## Other solutions that fit almost as well", "",
                "| start | RMS log10 error | c (N·s/m) | stiffness spread (decades) |", "|---|---|---|---|"]
        for a in result.alternatives:
            vals = {p.name: p.value for p in a.parameters}
            ea = np.array([p.value for p in a.parameters if p.name.startswith("EA")])
            cs = ", ".join(f"{v:.4g}" for k, v in vals.items() if k == "c" or k.startswith("c_"))
            out.append(f"| {a.start} | {a.rms_log10_error:.5f} | {cs} | {math.log10(ea.max() / ea.min()):.1f} |")
        out.append("")
    return "\n".join(out)

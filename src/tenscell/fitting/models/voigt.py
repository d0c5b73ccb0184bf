"""The fitting problem: a cell's linear model against data, a parameter layout, residuals and their analytic Jacobian.

The second of the fit's three layers (lmfit's parameters → problem →
minimizer): :mod:`~tenscell.fitting.parameters` lays the parameters out,
:class:`FitProblem` holds the plain arrays and computes residuals, penalties
and Jacobians from the model of :mod:`~tenscell.fitting.models.voigt_kernel`, and
:func:`tenscell.fitting.fit` (:mod:`~tenscell.fitting.search`) searches.

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
import scipy.sparse as sp

from ..._results import format_repr
from ...linear.whitening import rescaled_basis, unit_damping_basis, whitened_basis
from ...model.equilibrium import Cell
from ..problem import LN10 as _LN10, PENALTY as _PENALTY, Problem, centred_start, central_difference as _central
from .base import Capabilities, FitModel
from .voigt_fitted import MODEL_FORMAT, FittedCell, scaled_cell
from .voigt_results import VoigtResults
from .voigt_kernel import _Evaluation, evaluate
from ..parameters import (DAMPING_MODES, TENDON_MODES, Parameters, as_datasets, check_options, data_arrays,
                          parameter_layout, prestress_varies, required_points)

__all__ = ["TENDON_MODES", "DAMPING_MODES", "VoigtModel", "FitProblem", "FittedCell", "scaled_cell", "MODEL_FORMAT", "make_problem", "required_points", "as_datasets"]

# Weight of the prestress-share penalty residual ρ·ln(S_min/share): a shortfall of
# 1 % of the share costs as much as a 0.003-decade misfit of one point... times ρ/0.3
_SHARE_WEIGHT = 30.0


@dataclass(frozen=True)
class VoigtModel(FitModel):
    """The paper's cell with Voigt tendons (``T = EA·(l/l0 − 1) + c·l'``), stiffness and damping laid out per
    tendon, per family or uniform, with the optional activity constraints (module docstring).

    ``VoigtModel()`` is the paper's heterogeneous fit (``"voigt-per-tendon"``); ``VoigtModel("uniform")`` its
    homogeneous baseline.
    """

    tendons: str = "per-tendon"
    damping: str = "uniform"
    min_prestress_share: float | None = None
    max_decades: float | None = None
    min_prestress_elasticity: float | None = None
    elasticity_frequency_hz: float = 0.1
    name: str = ""
    description: str = ""

    def __post_init__(self):
        if self.tendons not in TENDON_MODES:
            raise ValueError(f"tendons must be one of {', '.join(map(repr, TENDON_MODES))}, got {self.tendons!r}")
        if self.damping not in DAMPING_MODES:
            raise ValueError(f"damping must be one of {', '.join(map(repr, DAMPING_MODES))}, got {self.damping!r}")
        check_options(self.min_prestress_share, self.max_decades, self.min_prestress_elasticity,
                      self.elasticity_frequency_hz)
        if not self.name:
            name = f"voigt-{self.tendons}" + ("-damping-per-family" if self.damping == "per-family" else "")
            object.__setattr__(self, "name", name)
        if not self.description:
            what = {"per-tendon": "a stiffness per tendon", "per-family": "a stiffness per family",
                    "uniform": "one stiffness"}[self.tendons]
            damp = "a damping per family" if self.damping == "per-family" else "one damping"
            object.__setattr__(self, "description", f"Voigt tendons with {what} and {damp} (the paper's model)")

    @property
    def group(self) -> str:
        return "the paper's Voigt cell"

    @property
    def capabilities(self) -> Capabilities:
        """Moduli and creep; the Voigt options; its lumped formula (no law tension terms: no shares to split);
        multimodal in every layout: fits per family stopped at two agreeing starts recovered a synthetic population's
        median P with a relative error of −0.70 (tests/test_population.py; 4 starts, no hops), within 0.15 when
        every start runs."""
        return Capabilities(data_kinds=frozenset({"moduli", "creep"}), voigt_options=True, lumped_terms=True,
                            multimodal=True)

    def baseline(self) -> FitModel | None:
        """The homogeneous cell (none for an unconstrained homogeneous fit: it is its own baseline)."""
        if self.tendons == "uniform" and self.damping == "uniform" and not self.constrained:
            return None
        return VoigtModel("uniform")

    def formula(self) -> FitModel | None:
        """Voigt tendons lumped into one element with a modulus proportional to P (what P·Kp gives without a
        structure): E0 + a·P + iωη."""
        from .formulas import Formula

        return Formula("voigt (lumped)", ("aP", "E0", "newtonian"),
                       "the structure-free formula of the Voigt cell: a·P + E0 + iωη")

    def with_options(self, **options) -> VoigtModel:
        """The Voigt cell with these options changed (the name and description follow the layout)."""
        fields = dict(tendons=self.tendons, damping=self.damping, min_prestress_share=self.min_prestress_share,
                      max_decades=self.max_decades, min_prestress_elasticity=self.min_prestress_elasticity,
                      elasticity_frequency_hz=self.elasticity_frequency_hz)
        unknown = sorted(set(options) - set(fields))
        if unknown:
            raise TypeError(f"VoigtModel has no option {unknown[0]!r} (options: {', '.join(fields)})")
        return VoigtModel(**{**fields, **options}) if options else self

    def min_points(self) -> int:
        """:func:`~tenscell.fitting.parameters.required_points` of this layout (the paper cell's two families)."""
        return required_points(self.tendons, self.damping)

    @property
    def constrained(self) -> bool:
        """Whether an activity constraint or a bound on the stiffness spread shapes the search space."""
        return any(x is not None for x in (self.min_prestress_share, self.max_decades, self.min_prestress_elasticity))

    def problem(self, data, cell=None, *, bounds=None, fixed=None) -> FitProblem:
        return make_problem(data, cell, tendons=self.tendons, damping=self.damping, bounds=bounds, fixed=fixed,
                            min_prestress_share=self.min_prestress_share, max_decades=self.max_decades,
                            min_prestress_elasticity=self.min_prestress_elasticity,
                            elasticity_frequency_hz=self.elasticity_frequency_hz)


@dataclass(frozen=True, eq=False, repr=False)
class FitProblem(VoigtResults, Problem):
    """The linear model of a cell against one or several data sets, with a parameter layout.

    Built by :func:`make_problem`; holds plain arrays only, so that it can be
    sent to worker processes. The parameter vector ``theta`` holds the natural
    logarithms of the *free* parameters, in the order of :attr:`names`
    restricted to :attr:`free`. Parameters are laid out as stiffness groups,
    damping groups, prestress parameters, then ``L``.

    Attributes
    ----------
    params : Parameters
        Every parameter (:class:`~tenscell.fitting.parameters.Parameters`; read as ``names``, ``units``,
        ``descriptions``, ``kinds``, ``lower``, ``upper``, ``free``, ``fixed_log``): ``kinds`` is one of ``"EA"``,
        ``"c"``, ``"P"``, ``"s"``, ``"P_data"``, ``"L"`` per parameter.
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

    params: Parameters
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
    cell: Cell  # the reference cell (strut length L_ref) the arrays above come from
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

    @property
    def spec(self) -> VoigtModel:
        """The :class:`VoigtModel` of this problem (its parametrization and constraints)."""
        return VoigtModel(tendons=self.tendons, damping=self.damping, min_prestress_share=self.min_prestress_share,
                          max_decades=self.max_decades, min_prestress_elasticity=self.min_prestress_elasticity,
                          elasticity_frequency_hz=self.elasticity_omega / (2 * math.pi))

    # -- layout (the rest in fitting.problem.Problem) --------------------------
    @property
    def n_creep(self) -> int:
        """Number of creep points, all creep data sets together (their residuals come last)."""
        return int(self.creep_t.size)

    @property
    def prestress_slice(self) -> slice:
        """Positions of the prestress parameters in :attr:`names`."""
        return slice(self.n_ea + self.n_c, self.n_params - 1)

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
        """(B, Ht, bt, Dt): A, the prestress Hessian, load and probe in the basis where C0 = I; None if C0 is not
        positive definite (:mod:`tenscell.linear.whitening`)."""
        if self.n_c == 1:  # C0 = c·A Aᵀ: rescale the precomputed basis
            return rescaled_basis(self.white_unit, float(eta[0]))
        return whitened_basis(self.A, eta, self.H, self.load, self.probe)

    def _evaluate(self, phi, jac: bool, share: bool = False, elasticity: bool = False) -> _Evaluation | None:
        """Moduli (and, if asked, their log-derivatives, the prestress share and elasticity); None if unstable."""
        return evaluate(self, phi, jac, share, elasticity)

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

    # -- residuals ------------------------------------------------------------------
    def moduli(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """Model G', G'' (Pa) at the data points, shape (N,) each; NaN where the model is unstable."""
        out = self._evaluate(self.full(theta), jac=False)
        if out is None:
            nan = np.full(self.omega.size, np.nan)
            return nan, nan.copy()
        return out.G.real, out.G.imag

    def time_points(self, dataset: int) -> np.ndarray:
        """Positions among the creep points of data set ``dataset``'s."""
        return np.flatnonzero(self.creep_dataset == dataset)

    @property
    def time_group(self) -> np.ndarray:
        """The prestress group of every creep point."""
        return self.creep_group

    def time_model(self, theta) -> np.ndarray:
        """The model's creep compliance (1/Pa) at every creep point (:meth:`creep`)."""
        return self.creep(theta)

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

    # -- the search's starts and moves ----------------------------------------------------------
    def _prestress_start(self, trial, p_ref: float, lp: float) -> None:
        """Place the scalable prestress parameters so that the model prestress is about ``exp(p_ref)·10^lp`` (N)."""
        measured = self.group_measured[np.isfinite(self.group_measured)]
        log_pm = math.log(float(np.median(measured))) if measured.size else 0.0
        for i in range(self.prestress_slice.start, self.n_params - 1):
            if not self.free[i]:
                continue
            if self.kinds[i] == "P":
                trial[i] = p_ref + lp
            elif self.kinds[i] == "s":
                trial[i] = p_ref + lp - log_pm


    def initial_guess(self, rng: np.random.Generator) -> np.ndarray:
        """A start (free log-parameters): stiffnesses log-uniform over 5–10 decades, damping and scale placed on the data."""
        phi = self.fixed_log.copy()
        n_ea, n_c = self.n_ea, self.n_c
        spread = rng.uniform(5.0, 10.0) if self.tendons == "per-tendon" else rng.uniform(0.0, 3.0)
        if self.compact:
            spread = min(spread, self._decades)
        u = rng.uniform(-0.5, 0.5, n_ea) * spread * _LN10 if n_ea > 1 else np.zeros(1)
        u = u + math.log(self.scale_stiffness)
        # families' damping may differ by decades (a joint fit of the bundled data puts them ~4 apart)
        c_jitter = rng.uniform(-2.0, 2.0, n_c) * _LN10 if n_c > 1 else np.zeros(1)
        free = self.free
        ic = slice(n_ea, n_ea + n_c)
        kinds = np.array(self.kinds)
        # scaling every EA, c and absolute prestress together by k scales G by k (exact)
        scalable = free & np.isin(kinds, ("EA", "c", "P", "s"))
        best = None
        # damping c shifts the spectrum in frequency; the prestress-to-stiffness ratio sets how much P matters
        c_grid = np.linspace(-6.0, 6.0, 25) * _LN10 if free[n_ea] else [None]
        p_free = bool(np.any(free & np.isin(kinds, ("P", "s"))))
        if self.prestress_matters:
            # the data vary with prestress (or must respond to it), so P must matter: relative to a typical
            # tendon, not the softest (a negligible P is a flat, prestress-blind trap the solver cannot leave)
            p_ref = float(np.median(u))
            p_grid = np.array([-2.0, -1.0, 0.0, 1.0]) * _LN10 if p_free else [None]
        else:
            p_ref = float(u.min())
            p_grid = np.array([-6.0, -3.0, 0.0]) * _LN10 if p_free else [None]
        for lc in c_grid:
            for lp in p_grid:
                trial = phi.copy()
                trial[:n_ea] = u
                if lc is not None:
                    trial[ic] = math.log(self.scale_damping) + lc + c_jitter
                if lp is not None:
                    self._prestress_start(trial, p_ref, lp)
                rms = centred_start(self, self._evaluate(trial, jac=False), trial, scalable)
                if rms is None:
                    continue
                if best is None or rms < best[0]:
                    best = (rms, trial)
        if best is None:
            trial = phi.copy()
            trial[:n_ea] = u
            best = (np.inf, trial)
        return best[1][free]


    def perturb(self, theta, rng: np.random.Generator) -> np.ndarray:
        """A basin-hopping move (free log-parameters): redraw a few stiffnesses, or jitter every parameter of a small model."""
        phi = self.full(theta)
        free = self.free
        ea_free = np.flatnonzero(free[: self.n_ea])
        y = phi.copy()
        if self.tendons == "per-tendon" and ea_free.size >= 3:
            pick = rng.choice(ea_free, size=3, replace=False)
            lo, hi = float(phi[ea_free].min()), float(phi[ea_free].max())
            if hi - lo < 4 * _LN10:
                mid = 0.5 * (lo + hi)
                lo, hi = mid - 2 * _LN10, mid + 2 * _LN10
            y[pick] = rng.uniform(lo, hi, size=3)
        else:
            move = free.copy()
            # L is a gauge of (P, EA, c) unless one of c, P is held fixed: moving it only wanders
            move[-1] &= not bool(np.all(free[self.n_ea: -1]))
            y[move] += rng.normal(0.0, 1.0, int(move.sum())) * _LN10
        return y[free]



# ---------------------------------------------------------------------------------
# building a problem
# ---------------------------------------------------------------------------------
def _cell_arrays(cell: Cell) -> dict:
    """The cell as :class:`FitProblem` fields: dense A, the symmetric prestress Hessian Σ T0_j ∇²l_j, lengths,
    T0, load, probe, the strut length and the whitened basis of unit damping.

    ValueError if C0 would be singular.
    """
    dense = lambda M: M.toarray() if sp.issparse(M) else np.asarray(M, dtype=float)  # noqa: E731
    A, H = dense(cell.A), dense(cell.prestress_hessian)
    H = 0.5 * (H + H.T)
    load, probe = np.asarray(cell.load, dtype=float), np.asarray(cell.probe, dtype=float)
    white_unit = unit_damping_basis(A, H, load, probe)
    if white_unit is None:
        raise ValueError(
            f"{cell.describe()}: the damping matrix C0 = Σ c_j a_j a_jᵀ is singular (the tendons leave a mechanism "
            "undamped, e.g. the cell without intermediate filaments), so its relaxation spectrum, which the fit "
            "uses, does not exist; fit a cell with a positive definite C0"
        )
    return dict(A=A, lengths=np.asarray(cell.lengths, dtype=float), T0=np.asarray(cell.T0, dtype=float), H=H,
                load=load, probe=probe, L_ref=float(cell.strut_length),
                white_unit=white_unit)


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
    from ...model.shapes import paper_cell

    datasets = as_datasets(data)
    options = check_options(min_prestress_share, max_decades, min_prestress_elasticity, elasticity_frequency_hz)
    cell = paper_cell() if cell is None else cell
    if not isinstance(cell, Cell):
        raise ValueError(f"cell must be a tenscell Cell, got {type(cell).__name__}")
    layout, point_group = parameter_layout(cell, datasets, tendons, damping, bounds, fixed)
    matters = prestress_varies(datasets) or min_prestress_share is not None or min_prestress_elasticity is not None
    return FitProblem(**layout, **_cell_arrays(cell), **data_arrays(datasets, point_group),
                      prestress_matters=bool(matters), cell=cell, **options)

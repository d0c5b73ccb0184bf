"""What a fit returns: FitResult with its parameters, per-data-set errors, curves and slopes."""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from .._checks import positive_scalar
from .._results import CORRELATION_THRESHOLD, dataframe, format_repr, plus_minus
from ..io.data import RheologyData
from ..linear.linearize import linearize
from ..linear.modal import modulus
from ..model.equilibrium import Cell
from ..response import compliance, frequency_response, log_slope

if TYPE_CHECKING:
    from ..io.creep_data import CreepData
    from .prestress import PrestressActivity
    from .models.voigt import FitProblem

__all__ = ["FitParameter", "FitAlternative", "FitCurve", "DatasetFit", "CreepFit", "FitResult", "model_curve",
           "frequency_slopes", "prestress_slopes", "report_quantities", "data_axis", "noise_rms", "inside_noise",
           "accepted", "verdict_text", "noise_note"]

def noise_rms(datasets) -> list[float | None]:
    """Per data set, the RMS of the stated standard deviations of log10 G', G'' (or of log10 J for creep data),
    in decades; None for a data set without them."""
    out: list[float | None] = []
    for d in datasets:
        if getattr(d, "kind", None) == "creep":  # creep data: the sd of log10 J
            out.append(float(np.sqrt(np.mean(1.0 / d.weights**2))) if d.has_sd else None)
            continue
        w = np.concatenate([d.weights_storage, d.weights_loss])
        out.append(None if d.G_storage_sd is None or d.G_loss_sd is None else float(np.sqrt(np.mean(1.0 / w**2))))
    return out


def inside_noise(rms: float, noise: float | None) -> bool:
    """A data set's fit is inside its own noise: its RMS (decades) at most the RMS of its stated sd (None: not stated).

    The one rule by which a fit that misses its tolerance still has nothing left to explain (per-tendon reports and
    mechanism fits alike).
    """
    return noise is not None and rms <= noise


def accepted(rms_per_set, noise, tolerance: float) -> bool:
    """The verdict's rule: every data set's RMS (decades) within ``tolerance`` or inside its own stated noise.

    What ``converged`` means for every fit (per-tendon and mechanism alike): a data set inside its noise has nothing
    left that the data could tell apart, whether or not the optimizer reached a tolerance set below that noise.
    """
    return all(r <= tolerance or inside_noise(r, n) for r, n in zip(rms_per_set, noise))


def verdict_text(converged: bool, tolerance_met: bool) -> str:
    """``"converged"``, ``"inside the data's noise (tolerance not met)"`` or ``"NOT converged"``."""
    if tolerance_met:
        return "converged"
    return "inside the data's noise (tolerance not met)" if converged else "NOT converged"


def noise_note(rms_per_set, noise, tolerance: float) -> str:
    """Words for a fit that misses its tolerance: which data sets lie inside their stated noise, and that the
    tolerance is below that noise ("" when every data set met the tolerance)."""
    missed = [(k, r, n) for k, (r, n) in enumerate(zip(rms_per_set, noise)) if r > tolerance]
    if not missed:
        return ""
    if all(inside_noise(r, n) for _, r, n in missed):
        worst = max(n for _, _, n in missed)
        return (f"every data set that misses the tolerance lies inside its stated noise (RMS of the sd up to "
                f"{worst:.3g} decades): the tolerance {tolerance:g} is below the data's noise, which cannot confirm it")
    above = [f"data set {k}: rms {r:.4g} above its noise {n:.3g}" for k, r, n in missed if n is not None]
    return "; ".join(above)


_MODEL_LABEL = {"uniform": "homogeneous", "per-family": "per family", "per-tendon": "heterogeneous"}


def data_axis(data: RheologyData) -> str:
    """``"prestress"`` for a sweep over prestress at one frequency, else ``"frequency"`` (what a plot puts on x)."""
    if data.prestress is not None and np.unique(data.prestress).size > 1 and np.unique(data.frequency_hz).size == 1:
        return "prestress"
    return "frequency"


# ---------------------------------------------------------------------------------
# records
# ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class FitParameter:
    """One fitted (or fixed) parameter.

    Attributes
    ----------
    name : str
        ``"EA[j]"``, ``"EA_actin"``, ``"EA"``, ``"c"``, ``"c_actin"``, ``"P"``,
        ``"s"``, ``"P_data[k]"`` or ``"L"``.
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


def _error_fields(p: FitParameter, error: tuple[float | None, str]) -> dict:
    """``stderr`` (the parameter's unit, None when not determined), ``stderr_percent`` and ``stderr_note``."""
    rel, note = error
    return {"stderr": None if rel is None else abs(p.value) * rel,
            "stderr_percent": None if rel is None else 100.0 * rel, "stderr_note": note}


#: most correlations report() lists (all are in correlations() and fit.json)
_MAX_CORRELATIONS = 20


#: what a null in FitResult.to_dict() (and fit.json) stands for; written into the document as "null_means"
FIT_NULL_MEANS = (
    "null: no value. start_rms: a start the search never ran (an earlier start met the target first); "
    "time_to_tolerance_s, timing.tolerance_met_s: the tolerance was never met; prestress_Pa / prestress_fitted_Pa: "
    "the data set states no prestress / its prestress is not a fitted parameter; kind: a joint fit; seed, "
    "constraints: not set; parameters[].at_bound: not at a bound; tendon_stiffness_spread_not_at_bounds: every "
    "stiffness is at a bound; derived.*.stderr: not determined (derived.*.note says why). A null anywhere else is a computed number that is not finite: its value is listed "
    "under non_finite")

#: largest prestress × frequency grid that FitResult.moduli evaluates in one batch (else per prestress)
_GRID_POINTS = 200_000

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
        What ``x`` is.
    """

    x: np.ndarray
    G_storage: np.ndarray
    G_loss: np.ndarray
    label: str
    rms_log10_error: float
    kind: str


@dataclass(frozen=True, eq=False, repr=False)
class DatasetFit:
    """How the fitted model meets one of the data sets of a (joint) fit.

    Attributes
    ----------
    index : int
        Position of the data set in the fit.
    data : RheologyData
    axis : {"frequency", "prestress"}
        What varies in the data (see :func:`data_axis`).
    prestress_pa : float or None
        Prestress (Pa) the data set states (one value), or None.
    prestress_fitted_pa : float or None
        Prestress (Pa) fitted for a data set that does not state it in a
        joint fit (``P_data[k]``), else None.
    prestress_model_N : ndarray, shape (n,)
        Model prestress P (N) at each point, at the fitted strut length.
    G_storage_model, G_loss_model : ndarray, shape (n,)
        Model moduli at the data points (Pa).
    residuals : ndarray, shape (2n,)
        Unweighted ``log10 G_model − log10 G_data``: G' block, then G''.
    """

    index: int
    data: RheologyData
    axis: str
    prestress_pa: float | None
    prestress_fitted_pa: float | None
    prestress_model_N: np.ndarray
    G_storage_model: np.ndarray
    G_loss_model: np.ndarray
    residuals: np.ndarray

    @property
    def rms_log10_error(self) -> float:
        """RMS of :attr:`residuals` (decades)."""
        return float(np.sqrt(np.mean(self.residuals**2)))

    @property
    def rms_storage(self) -> float:
        """RMS of the G' residuals (decades)."""
        return float(np.sqrt(np.mean(self.residuals[: self.data.n] ** 2)))

    @property
    def rms_loss(self) -> float:
        """RMS of the G'' residuals (decades)."""
        return float(np.sqrt(np.mean(self.residuals[self.data.n:] ** 2)))

    @property
    def x(self) -> np.ndarray:
        """The data's x values: prestress (Pa) for a prestress sweep, frequency (Hz) otherwise."""
        prestress = self.data.prestress
        return prestress if self.axis == "prestress" and prestress is not None else self.data.frequency_hz

    def __repr__(self) -> str:
        at = (f" at {self.prestress_pa:.4g} Pa (stated)" if self.prestress_pa is not None else
              f" at {self.prestress_fitted_pa:.4g} Pa (fitted)" if self.prestress_fitted_pa is not None else "")
        return format_repr(f"DatasetFit {self.index}: {self.data.source}",
                           f"{self.data.n} points, {self.axis} sweep{at}",
                           f"rms log10 error {self.rms_log10_error:.4g} (G' {self.rms_storage:.4g}, "
                           f"G'' {self.rms_loss:.4g})")

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        return {"index": self.index, "data": self.data.source, "n_points": self.data.n, "axis": self.axis,
                "prestress_Pa": self.prestress_pa, "prestress_fitted_Pa": self.prestress_fitted_pa,
                "rms_log10_error": self.rms_log10_error, "rms_log10_error_storage": self.rms_storage,
                "rms_log10_error_loss": self.rms_loss,
                "residuals_log10": {"G_storage": self.residuals[: self.data.n].tolist(),
                                    "G_loss": self.residuals[self.data.n:].tolist()}}

    def to_dataframe(self):
        """Data, model and log10 errors at each point (columns with units)."""
        d, n = self.data, self.data.n
        cols = {"frequency_Hz": d.frequency_hz}
        if d.prestress is not None:
            cols["prestress_Pa"] = d.prestress
        cols.update({"prestress_model_N": self.prestress_model_N, "G_storage_Pa": d.G_storage,
                     "G_loss_Pa": d.G_loss, "G_storage_model_Pa": self.G_storage_model,
                     "G_loss_model_Pa": self.G_loss_model, "log10_error_storage": self.residuals[:n],
                     "log10_error_loss": self.residuals[n:]})
        return dataframe(cols, {"source": d.source, "rms_log10_error": self.rms_log10_error})


@dataclass(frozen=True, eq=False, repr=False)
class CreepFit:
    """How the fitted model meets one creep data set of a fit (the counterpart of :class:`DatasetFit`).

    Attributes
    ----------
    index : int
    data : CreepData
    axis : str
        ``"time"``.
    prestress_pa, prestress_fitted_pa : float or None
        As in :class:`DatasetFit`.
    prestress_model_N : ndarray, shape (n,)
        Model prestress (N) at each point.
    J_model : ndarray, shape (n,)
        Model creep compliance at the data's times (1/Pa).
    residuals : ndarray, shape (n,)
        Unweighted ``log10 J_model − log10 J_data``.
    """

    index: int
    data: CreepData
    axis: str
    prestress_pa: float | None
    prestress_fitted_pa: float | None
    prestress_model_N: np.ndarray
    J_model: np.ndarray
    residuals: np.ndarray

    rms_storage = None  # no moduli: the report prints n/a
    rms_loss = None

    @property
    def rms_log10_error(self) -> float:
        """RMS of :attr:`residuals` (decades)."""
        return float(np.sqrt(np.mean(self.residuals**2)))

    @property
    def x(self) -> np.ndarray:
        """Times (s)."""
        return self.data.time_s

    def __repr__(self) -> str:
        return format_repr(f"CreepFit {self.index}: {self.data.source}",
                           f"{self.data.n} points, creep; rms log10 error {self.rms_log10_error:.4g}")

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        return {"index": self.index, "data": self.data.source, "n_points": self.data.n, "axis": self.axis,
                "prestress_Pa": self.prestress_pa, "prestress_fitted_Pa": self.prestress_fitted_pa,
                "rms_log10_error": self.rms_log10_error, "residuals_log10": {"creep_compliance": self.residuals.tolist()}}

    def to_dataframe(self):
        """Data, model and log10 error at each time (columns with units)."""
        return dataframe({"time_s": self.data.time_s, "prestress_model_N": self.prestress_model_N,
                          "creep_compliance_per_Pa": self.data.compliance, "creep_compliance_model_per_Pa": self.J_model,
                          "log10_error": self.residuals}, {"source": self.data.source})


# ---------------------------------------------------------------------------------
# the result
# ---------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class FitResult:
    """The outcome of :func:`tenscell.fitting.fit`.

    Attributes
    ----------
    parameters : tuple of FitParameter
        Best-fit parameters (named, with bounds and whether a bound is hit).
    residuals : ndarray, shape (2N,)
        Unweighted ``log10 G_model − log10 G_data`` over the points of all
        data sets in order: the N G' residuals, then the N G'' ones
        (:attr:`fits` splits them per data set).
    rms_log10_error : float
        RMS of ``residuals`` (decades), all data sets together.
    tolerance : float
        The RMS every data set had to reach.
    converged : bool
        True if every data set's RMS is within ``tolerance`` or inside the data set's stated noise
        (:func:`accepted`); :attr:`tolerance_met` says whether the tolerance itself was met.
    message : str
        What happened, in words (including why the search stopped).
    datasets : tuple of RheologyData
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
    stop_reason : str
        Why the search stopped.
    """

    parameters: tuple
    residuals: np.ndarray
    rms_log10_error: float
    tolerance: float
    converged: bool
    message: str
    datasets: tuple
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
    stop_reason: str = ""

    # -- accessors ------------------------------------------------------------------
    @property
    def tolerance_met(self) -> bool:
        """Every data set's RMS is within :attr:`tolerance` (what the optimizer aimed at); :attr:`converged` also
        accepts a data set inside its stated noise."""
        return bool(self.problem.dataset_rms(self.theta).max() <= self.tolerance)

    @property
    def verdict(self) -> str:
        """``"converged"``, ``"inside the data's noise (tolerance not met)"`` or ``"NOT converged"``."""
        return verdict_text(self.converged, self.tolerance_met)

    @cached_property
    def time_to_tolerance_s(self) -> float | None:
        """Seconds from the start of the fit until some start first had every data set within the tolerance.

        Read from :attr:`history` (the best-so-far record over all starts), by
        the search's own rule: within the tolerance and feasible (the activity
        constraints, if any, hold). None if that never happened. The search
        runs on after this moment only to polish (:func:`tenscell.fitting.fit`,
        ``polish``).
        """
        for (t, _), theta in zip(self.history, self.history_theta):
            if float(self.problem.dataset_rms(theta).max()) <= self.tolerance and self.problem.feasible(theta):
                return float(t)
        return None

    @property
    def data(self) -> RheologyData:
        """The data set of a single-data-set fit (a joint fit has :attr:`datasets`)."""
        if len(self.datasets) != 1:
            raise ValueError(f"this is a joint fit of {len(self.datasets)} data sets: use .datasets or .fits")
        return self.datasets[0]

    @property
    def joint(self) -> bool:
        """True for a fit of several data sets at once."""
        return len(self.datasets) > 1

    @property
    def label(self) -> str:
        """``"heterogeneous"``, ``"per family"`` or ``"homogeneous"`` (the stiffness parametrization)."""
        return _MODEL_LABEL[self.tendons]

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

    # -- per data set -------------------------------------------------------------------
    def group_prestress(self) -> np.ndarray:
        """Model prestress P (N) of each prestress group of the problem, at the fitted strut length."""
        pr = self.problem
        return np.exp(pr.group_log_offset + pr.group_map @ pr.full(self.theta)[pr.prestress_slice])

    @cached_property
    def fits(self) -> tuple:
        """One :class:`DatasetFit` per data set, in order."""
        pr = self.problem
        Gs, Gl = pr.moduli(self.theta)
        P_pts = self.group_prestress()[pr.group_index]
        vals = dict(zip(pr.names, pr.values(self.theta)))
        out: list[DatasetFit | CreepFit] = []
        Jc = pr.creep(self.theta) if pr.n_creep else None
        for k, d in enumerate(self.datasets):
            pts = np.flatnonzero(pr.dataset_index == k)
            stated = float(d.prestress[0]) if d.prestress is not None and np.unique(d.prestress).size == 1 else None
            if getattr(d, "kind", None) == "creep":
                assert Jc is not None  # a creep data set makes pr.n_creep > 0
                sel = np.flatnonzero(pr.creep_dataset == k)
                out.append(CreepFit(index=k, data=d, axis="time", prestress_pa=stated,
                                    prestress_fitted_pa=vals.get(f"P_data[{k}]"),
                                    prestress_model_N=self.group_prestress()[pr.creep_group[sel]],
                                    J_model=Jc[sel], residuals=self.residuals[pr.rows(k)]))
                continue
            out.append(DatasetFit(
                index=k, data=d, axis=data_axis(d), prestress_pa=stated,
                prestress_fitted_pa=vals.get(f"P_data[{k}]"), prestress_model_N=P_pts[pts],
                G_storage_model=Gs[pts], G_loss_model=Gl[pts], residuals=self.residuals[pr.rows(k)]))
        return tuple(out)

    def prestress_model(self, prestress_pa=None, dataset: int = 0) -> np.ndarray:
        """Model prestress P (N) for prestresses ``prestress_pa`` (Pa), or the one data set ``dataset`` was fitted at.

        With ``prestress_pa`` the fit must have a prestress scale ``s``
        (some data set stated its prestress): ``P = s·prestress_pa``.
        Without it, the data set must have a single prestress (a frequency
        sweep); its model P is returned as a 1-element array.
        """
        if prestress_pa is not None:
            if "s" not in self.problem.names:
                raise ValueError("no data set of this fit stated its prestress, so prestress (Pa) has no model "
                                 "equivalent; use the fitted P (N)")
            return self.value("s") * np.asarray(prestress_pa, dtype=float)
        P = np.unique(self.fits[dataset].prestress_model_N)
        if P.size != 1:
            raise ValueError(f"data set {dataset} spans several prestresses: give prestress_pa (Pa)")
        return P

    def moduli(self, f_hz, prestress_pa=None, *, dataset: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Fitted model's G', G'' (Pa) at frequencies ``f_hz`` (Hz), computed by the core pipeline.

        ``prestress_pa`` (Pa, broadcast with ``f_hz``) maps to the model by
        the fitted scale ``s``; without it the model prestress is the one of
        data set ``dataset`` (default: the only data set, or the first with a
        single prestress).
        """
        f = np.atleast_1d(np.asarray(f_hz, dtype=float))
        if prestress_pa is not None:
            Pm = np.atleast_1d(self.prestress_model(prestress_pa))
        else:
            Pm = self.prestress_model(dataset=self._single_prestress_dataset() if dataset is None else dataset)
        f, Pm = np.broadcast_arrays(f, Pm)
        Pu, at_P = np.unique(Pm, return_inverse=True)
        fu, at_f = np.unique(f, return_inverse=True)
        if 1 < Pu.size and Pu.size * fu.size <= _GRID_POINTS:
            # many prestresses (a prestress sweep's curve): one batched eigensolve over the grid
            lam = self.L / self.problem.L_ref
            J = frequency_response(self.cell, fu, Pu / lam**2, EA=self.EA / lam**2, c=self.c / lam).J
            G = modulus(J[at_P.ravel(), at_f.ravel()].reshape(f.shape), self.problem.L_ref)
            return G.real, G.imag
        Gs = np.empty(f.shape)
        Gl = np.empty(f.shape)
        for P in Pu:
            sel = Pm == P
            G = modulus(compliance(self._linear(P), f[sel]), self.problem.L_ref)
            Gs[sel], Gl[sel] = G.real, G.imag
        return Gs, Gl

    def _single_prestress_dataset(self) -> int:
        for fit in self.fits:
            if np.unique(fit.prestress_model_N).size == 1:
                return fit.index
        raise ValueError("every data set spans several prestresses: give prestress_pa (Pa)")

    def _linear(self, P: float):
        """The linear model of the reference cell equivalent to the fitted cell at model prestress P (N).

        The fitted cell is the reference scaled by λ = L/L_ref; on the
        reference the equivalent properties are (P/λ², EA/λ², c/λ) and the
        moduli are identical (strut-length gauge).
        """
        lam = self.L / self.problem.L_ref
        return linearize(self.cell, P=float(P) / lam**2, EA=self.EA / lam**2, c=self.c / lam, check=False)

    @cached_property
    def prestress(self) -> PrestressActivity:
        """Is the prestress doing anything? Its elasticities and share of the stiffness (:mod:`~.prestress`)."""
        from .prestress import prestress_activity

        return prestress_activity(self)

    # -- the fitted cell as a model, and what the data determine ---------------------------------
    @property
    def model(self):
        """The fitted cell as a :class:`~tenscell.fitting.fitted.FittedModel` (cell at the fitted L, EA, c, prestress)."""
        from .fitted import FittedModel, scaled_cell

        names = self.problem.names
        if "s" in names:  # some data set stated its prestress: P = s × prestress (Pa)
            stated = [p for f in self.fits for p in (
                np.unique(f.data.prestress) if f.data.prestress is not None else [f.prestress_fitted_pa])
                if p is not None]
            pre = {"s": self.value("s"), "prestress_pa": tuple(float(p) for p in stated)}
        else:
            pre = {"P": float(self.prestress_model(dataset=self._single_prestress_dataset())[0])}
        return FittedModel(cell=scaled_cell(self.cell, self.L), EA=self.EA, c=self.c,
                           source=" + ".join(d.source for d in self.datasets), **pre)

    def _default_prestress_N(self) -> float:
        """Model prestress (N) of the first single-prestress data set, else at the first data set's median."""
        try:
            return float(self.prestress_model(dataset=self._single_prestress_dataset())[0])
        except ValueError:
            return float(np.ravel(self.prestress_model(np.median(self.datasets[0].prestress)))[0])

    @property
    def linear(self):
        """The linear model of the fitted cell (at the fitted strut length) at :meth:`_default_prestress_N`."""
        return self.model.linear(P_N=self._default_prestress_N())

    def identifiability(self, rtol: float = 1e-8):
        """Rank, standard errors, correlations and determined combinations (:mod:`tenscell.fitting.identifiability`)."""
        if rtol == 1e-8:
            return self._identifiability
        from .identifiability import identifiability

        known = all(d.has_sd for d in self.datasets)
        return identifiability(self.problem, self.theta, sigma_known=known, rtol=rtol)

    @cached_property
    def _identifiability(self):
        from .identifiability import identifiability

        known = all(d.has_sd for d in self.datasets)
        return identifiability(self.problem, self.theta, sigma_known=known, rtol=1e-8)

    @property
    def standard_errors(self) -> tuple[tuple[float | None, str], ...]:
        """``(standard error, note)`` of each parameter, in :attr:`parameters` order.

        The standard error is in the parameter's unit (first order in its ln:
        ``value × se(ln value)``, from :meth:`identifiability`); None when the
        parameter is fixed, at a bound, the strut-length gauge, or not
        determined by the data, and the note says which. With the gauge
        removed the error is that of the gauge-invariant combination the note
        names (``"of EA[3]/L²"``): the same relative error, at the fitted L.
        """
        ident = self.identifiability()
        out = []
        for p in self.parameters:
            rel, note = ident.relative_error(p.name)
            out.append((None if rel is None else abs(p.value) * rel, note))
        return tuple(out)

    def model_standard_errors(self) -> np.ndarray:
        """Standard error (decades) of the fitted model's log10 G′, log10 G″ or log10 J at each residual, in the
        order of :attr:`residuals` (``pr.rows(k)`` per data set); NaN when σ is unknown.

        From the identifiability analysis (linearized at the optimum): ``σ·sqrt(h_i)/w_i`` with ``h`` the
        leverage (diagonal of the hat matrix) and ``w`` the residual weights; constraints (parameters at a
        bound, fixed, the L gauge) add no uncertainty.
        """
        ident = self.identifiability()
        n = self.residuals.size
        h = np.asarray(ident.leverage, dtype=float)[:n]
        sigma = np.nan if ident.sigma is None else ident.sigma
        return sigma * np.sqrt(np.clip(h, 0.0, None)) / np.asarray(self.problem.weights, dtype=float)[:n]

    @cached_property
    def derived(self):
        """The numbers the report derives from the parameters (slopes, prestress elasticities and share,
        predicted creep, stiffness spread), each with its standard error: a
        :class:`~tenscell.fitting.derived.DerivedQuantities` (delta method, finite-difference gradients)."""
        from .derived import derived_quantities

        return derived_quantities(self, report_quantities)

    def compute_derived(self, executor=None):
        """:attr:`derived`, computed now with half of its model evaluations in ``executor`` (a worker with
        ``submit``, e.g. the fit command's) and kept; the numbers do not depend on it."""
        if "derived" not in self.__dict__:
            from .derived import derived_quantities

            self.__dict__["derived"] = derived_quantities(self, report_quantities, executor=executor)
        return self.__dict__["derived"]

    def correlations(self, threshold: float = CORRELATION_THRESHOLD) -> list[tuple[str, str, float]]:
        """``(a, b, ρ)`` for pairs of determined parameters with ``|ρ| >= threshold``, strongest first."""
        return self.identifiability().strong_correlations(threshold)

    def predicted_creep(self, t_min: float = 0.1, t_max: float = 10.0, n: int = 41):
        """Creep compliance (1/Pa) of the fitted cell over [t_min, t_max] s and its power-law exponent."""
        from .fitted import predicted_creep

        return predicted_creep(self.linear, t_min, t_max, n)

    # -- conventions ----------------------------------------------------------------------
    def __repr__(self) -> str:
        sets = ", ".join(f"{_short(f.data.source)} {f.rms_log10_error:.3g}" for f in self.fits)
        lo, hi, dec = self.stiffness_spread
        share = self.problem.prestress_share(self.theta)
        return format_repr(
            f"FitResult: {self.label} fit ({self.tendons} stiffness, {self.damping} damping), "
            f"{len(self.datasets)} data set(s), {sum(d.n for d in self.datasets)} points, "
            f"{self.problem.n_free} free parameters",
            f"rms log10 error {self.rms_log10_error:.4g} (tolerance {self.tolerance:g}): "
            f"{self.verdict}; per data set: {sets}",
            f"stiffness spread {dec:.1f} decades; prestress share of the static stiffness "
            f"{np.nanmin(share):.3g} to {np.nanmax(share):.3g}",
            f"{self.starts} start(s), seed {self.seed}, {self.elapsed_s:.1f} s; stopped: {self.stop_reason}",
        )

    def to_dataframe(self):
        """Data, model and log10 errors at every point of every data set (columns with units).

        ``attrs["parameters"]`` holds ``{name: (value, unit)}``.
        """
        import pandas as pd

        frames = []
        for f in self.fits:
            df = f.to_dataframe()
            df.insert(0, "dataset", f.index)
            df.insert(1, "source", f.data.source)
            frames.append(df)
        out = pd.concat(frames, ignore_index=True)
        out.attrs.update({"parameters": {p.name: (p.value, p.unit) for p in self.parameters},
                          "rms_log10_error": self.rms_log10_error})
        return out

    def parameters_dataframe(self):
        """The parameters as a DataFrame: name, value, stderr (both in ``unit``; stderr NaN when not determined),
        stderr_percent, stderr_note, unit, lower, upper, vary, at_bound, description."""
        rows = [{**p.to_dict(), **_error_fields(p, (None if e is None else e / abs(p.value) if p.value else None, n))}
                for p, (e, n) in zip(self.parameters, self.standard_errors)]
        order = ["name", "value", "stderr", "stderr_percent", "stderr_note", "unit", "lower", "upper", "vary",
                 "at_bound", "description"]
        cols = {k: [r[k] for r in rows] for k in order}
        cols["stderr"] = [math.nan if v is None else v for v in cols["stderr"]]
        cols["stderr_percent"] = [math.nan if v is None else v for v in cols["stderr_percent"]]
        return dataframe(cols, {"correlations": self.correlations()})

    def plot(self, ax=None, *, dataset: int | None = None, **kw):
        """Data and fitted model of one data set on ``ax`` (or every data set, one panel each, when ``ax`` is None).

        Returns the axes (an array of axes for several panels).
        """
        from .._results import plotter

        plot_fit = plotter("plot_fit")

        return plot_fit(self, ax=ax, dataset=dataset, **kw)

    # -- output ---------------------------------------------------------------------
    def to_dict(self) -> dict:
        """JSON-ready summary: parameters, per-data-set errors, prestress activity, time taken, alternatives..."""
        lo, hi, dec = self.stiffness_spread
        first = self.fits[0]
        doc = {
            "data": [d.source for d in self.datasets] if self.joint else first.data.source,
            "kind": None if self.joint else first.data.kind,
            "n_points": self.problem.n_points,
            "cell": self.cell.describe(),
            "tendons": self.tendons,
            "damping": self.damping,
            "rms_log10_error": self.rms_log10_error,
            "rms_log10_error_storage": _rms(self.residuals[: self.problem.n_points]),
            "rms_log10_error_loss": _rms(self.residuals[self.problem.n_points: 2 * self.problem.n_points]),
            "datasets": [f.to_dict() for f in self.fits],
            "tolerance": self.tolerance,
            "converged": self.converged,
            "tolerance_met": self.tolerance_met,
            "noise_rms_log10_per_dataset": noise_rms(self.datasets),
            "message": self.message,
            "stop_reason": self.stop_reason,
            "time_s": self.elapsed_s,
            "time_to_tolerance_s": self.time_to_tolerance_s,
            "starts": self.starts,
            "seed": None if self.seed is None else int(self.seed),
            "n_evaluations": self.n_evaluations,
            "n_free_parameters": self.problem.n_free,
            "n_residuals": self.problem.n_residuals,
            "constraints": {"min_prestress_share": self.problem.min_prestress_share,
                            "min_prestress_elasticity": self.problem.min_prestress_elasticity,
                            "elasticity_frequency_Hz": float(self.problem.elasticity_omega / (2 * math.pi)),
                            "max_decades": self.problem.max_decades},
            "parameters": [{**p.to_dict(), "stderr": e, "stderr_percent": None if e is None or not p.value
                            else 100.0 * e / abs(p.value), "stderr_note": n}
                           for p, (e, n) in zip(self.parameters, self.standard_errors)],
            "correlations": {"threshold": CORRELATION_THRESHOLD,
                             "pairs": [{"a": a, "b": b, "rho": r} for a, b, r in self.correlations()]},
            "tendon_stiffness_spread": {"min_N": lo, "max_N": hi, "decades": dec},
            "tendon_stiffness_spread_not_at_bounds": (
                None if self.stiffness_spread_interior is None else dict(
                    zip(("min_N", "max_N", "decades"), self.stiffness_spread_interior))),
            "prestress_activity": self.prestress.to_dict(),
            "derived": self.derived.to_dict(),
            # a start the search never ran (an earlier one met the target first) has no RMS: null, not inf
            "start_rms": [r if math.isfinite(r) else None for r in self.start_rms],
            "alternatives": [a.to_dict() for a in self.alternatives],
            "history": [{"time_s": t, "rms_log10_error": r} for t, r in self.history],
            "identifiability": self.identifiability().to_dict(),
            "predicted_creep": self.predicted_creep().to_dict(),
            "model": self.model.to_dict(),
        }
        if not self.joint:
            doc["residuals_log10"] = first.to_dict()["residuals_log10"]
        doc["null_means"] = FIT_NULL_MEANS
        return doc

    def _interior_text(self) -> str:
        inner = self.stiffness_spread_interior
        full = self.stiffness_spread
        if inner is None or inner == full:
            return ""
        return f"; {inner[0]:.3g} .. {inner[1]:.3g} N ({inner[2]:.1f} decades) without those at bounds"

    def report(self) -> str:
        """A readable plain-text report (in the spirit of lmfit's ``fit_report``)."""
        lines = [
            "[[Fit statistics]]",
            *(f"    data {f.index}:             {f.data.source} ({f.data.n} points, {f.axis} sweep): "
              f"rms {f.rms_log10_error:.5f}" for f in self.fits),
            f"    model:              {self.cell.describe()}; stiffness {self.tendons}, damping {self.damping}",
            f"    free parameters:    {self.problem.n_free} (residuals: {self.problem.n_residuals})",
            f"    rms log10 error:    {self.rms_log10_error:.5f} (tolerance {self.tolerance:g}): "
            + self.verdict,
            f"    starts:             {self.starts} (seed {self.seed}), {self.n_evaluations} model evaluations, "
            f"{self.elapsed_s:.1f} s",
            f"    stiffness spread:   {self.derived.text('stiffness_spread', 0, 'N', 3)} .. "
            f"{self.derived.text('stiffness_spread', 1, 'N', 3)} ({self.derived.text('stiffness_spread', 2, 'decades', 3)})"
            + self._interior_text(),
            f"    message:            {self.message}",
            "[[Parameters]] (value +/- standard error, in the unit shown; see identifiability())",
        ]
        width = max(len(p.name) for p in self.parameters)
        ident = self.identifiability()
        if ident.gauge_removed:
            lines.append("    (L is an exact gauge of the moduli: the errors are those of EA/L², c/L, P/L² at the "
                         "fitted L)")
        for p, (se, note) in zip(self.parameters, self.standard_errors):
            lines.append(f"    {p.name + ':':<{width + 1}} {plus_minus(p.value, se, p.unit, note)}  "
                         f"[{p.lower:.3g}, {p.upper:.3g}]  {p.description}")
        strong = self.correlations()
        lines.append(f"[[Correlations]] (unreported correlations are < {CORRELATION_THRESHOLD:.3f})")
        for a, b, r in strong[:_MAX_CORRELATIONS]:
            lines.append(f"    C({a}, {b}) = {r:+.4f}")
        if len(strong) > _MAX_CORRELATIONS:
            lines.append(f"    ... and {len(strong) - _MAX_CORRELATIONS} more (FitResult.correlations())")
        if not strong:
            lines.append("    none")
        for f in self.fits:
            d = f.data
            lines.append(f"[[Residuals log10(model/data): data {f.index}]]")
            xname = "P (Pa)" if f.axis == "prestress" else "f (Hz)"
            lines.append(f"    {xname:>10}  {'G_storage':>10}  {'G_loss':>10}")
            for i in range(d.n):
                lines.append(f"    {f.x[i]:>10.4g}  {f.residuals[i]:>+10.5f}  {f.residuals[d.n + i]:>+10.5f}")
        if self.alternatives:
            lines.append(f"[[Alternatives]] {len(self.alternatives)} other start(s) fit almost as well:")
            for a in self.alternatives:
                lines.append(f"    start {a.start}: rms {a.rms_log10_error:.5f}")
        return "\n".join(lines) + "\n"


def _rms(r) -> float | None:
    """RMS (decades), None for no residuals (a fit to creep data only has no G', G'')."""
    return float(np.sqrt(np.mean(r**2))) if r.size else None


def _short(source: str) -> str:
    return source.replace("\\", "/").rsplit("/", 1)[-1]


# ---------------------------------------------------------------------------------
# analyses of a fit
# ---------------------------------------------------------------------------------
def model_curve(result: FitResult, n: int = 200, label: str | None = None, dataset: int = 0) -> FitCurve:
    """The fitted model on a dense grid spanning data set ``dataset`` (for plots).

    Frequency sweep: ``n`` log-spaced frequencies over the data's range (Hz)
    at the data set's prestress. Prestress sweep: ``n`` prestresses over the
    data's range (Pa) at the data's frequency.
    """
    fit = result.fits[dataset]
    d = fit.data
    if fit.axis == "prestress":
        x = np.linspace(d.prestress.min(), d.prestress.max(), n)
        Gs, Gl = result.moduli(np.full(n, d.frequency_hz[0]), prestress_pa=x)
    else:
        x = np.logspace(math.log10(d.frequency_hz.min()), math.log10(d.frequency_hz.max()), n)
        Gs, Gl = result.moduli(x, dataset=dataset)
    return FitCurve(x=x, G_storage=Gs, G_loss=Gl, label=result.label if label is None else label,
                    rms_log10_error=fit.rms_log10_error, kind=fit.axis)


def frequency_slopes(result: FitResult, f_lo: float = 0.01, f_hi: float = 100.0, n: int = 1000,
                     dataset: int | None = None):
    """Local log-log slopes of the fitted G' and G'' on ``n`` log-spaced frequencies in [f_lo, f_hi] Hz.

    At the prestress of data set ``dataset`` (default: the first frequency
    sweep, else the median prestress of the first data set).

    Returns
    -------
    f : ndarray (Hz), slope_storage : ndarray, slope_loss : ndarray
    """
    f = np.logspace(math.log10(positive_scalar("f_lo", f_lo, "Hz")), math.log10(positive_scalar("f_hi", f_hi, "Hz")),
                    int(n))
    if dataset is None:
        dataset = next((x.index for x in result.fits if x.axis == "frequency"), None)
    if dataset is None:  # no frequency sweep: a data set at one prestress (creep), if any
        dataset = next((x.index for x in result.fits if np.unique(x.prestress_model_N).size == 1), None)
    if dataset is None or np.unique(result.fits[dataset].prestress_model_N).size > 1:
        d = result.datasets[dataset or 0]
        Gs, Gl = result.moduli(f, prestress_pa=float(np.median(d.prestress)))
    else:
        Gs, Gl = result.moduli(f, dataset=dataset)
    return f, log_slope(f, Gs), log_slope(f, Gl)


def prestress_slopes(result: FitResult, n: int = 100, dataset: int | None = None) -> tuple[float, float, float, float]:
    """Straight-line fit of the model's G', G'' against prestress over a prestress sweep's range.

    Returns
    -------
    (dG'/dP, G'(0) intercept, dG''/dP, G''(0) intercept): slopes dimensionless (Pa/Pa),
    intercepts in Pa, from ``n`` prestresses spanning data set ``dataset``
    (default: the first prestress sweep) at its frequency.
    """
    if dataset is None:
        dataset = next((x.index for x in result.fits if x.axis == "prestress"), None)
    if dataset is None or result.fits[dataset].axis != "prestress":
        raise ValueError("prestress_slopes needs a prestress sweep among the fitted data")
    curve = model_curve(result, n=n, dataset=dataset)
    a1, b1 = np.polyfit(curve.x, curve.G_storage, 1)
    a2, b2 = np.polyfit(curve.x, curve.G_loss, 1)
    return float(a1), float(b1), float(a2), float(b2)


def report_quantities(result: FitResult) -> dict[str, np.ndarray]:
    """Every number the fit report derives from the fitted parameters, as flat arrays.

    Keys: ``frequency_slopes[k]`` (G' slope min, max, G'' slope min, max over 1000 frequencies spanning
    frequency sweep k; dimensionless), ``creep_slopes[k]`` (min, max of d ln J/d ln t at creep data set k's
    times), ``prestress_lines[k]`` (dG'/dP, G'(0) in Pa, dG''/dP, G''(0) in Pa over prestress sweep k),
    ``prestress_share`` and ``prestress_storage`` (min, max over the data points of the share of the static
    stiffness carried by P·Kp and of ∂lnG'/∂lnP), ``reference_prestress_N`` (N), ``reference_storage``,
    ``reference_loss``, ``reference_share`` (per prestress at the reference frequency), ``creep_A`` (1/Pa),
    ``creep_alpha``, ``creep_J`` (1/Pa) and ``creep_exponent`` (at the predicted creep's times),
    ``creep_prestress_N`` (N, the prestress the creep is predicted at),
    ``creep_window_slope`` (min, max of the G' slope over the frequencies 1/(2πt) of the creep window), and
    ``stiffness_spread`` (min EA, max EA in N, decades).
    """
    out: dict[str, np.ndarray] = {}
    for f in result.fits:
        d = f.data
        if f.axis == "frequency":
            _, s1, s2 = frequency_slopes(result, float(d.frequency_hz.min()), float(d.frequency_hz.max()), 1000,
                                         dataset=f.index)
            out[f"frequency_slopes[{f.index}]"] = np.array([s1.min(), s1.max(), s2.min(), s2.max()])
        elif f.axis == "time":
            expo = np.gradient(np.log(f.J_model), np.log(d.time_s)) if d.n > 1 else np.zeros(1)
            out[f"creep_slopes[{f.index}]"] = np.array([expo.min(), expo.max()])
        else:
            out[f"prestress_lines[{f.index}]"] = np.array(prestress_slopes(result, dataset=f.index))
    pa = result.prestress
    summary = pa.to_dict()
    out["prestress_share"] = np.array([summary["share_min"], summary["share_max"]])
    out["prestress_storage"] = np.array([summary["dlnGstorage_dlnP"]["min"], summary["dlnGstorage_dlnP"]["max"]])
    for name in ("prestress_N", "storage", "loss", "share"):
        out[f"reference_{name}"] = np.asarray(getattr(pa, f"reference_{name}"), dtype=float)
    creep = result.predicted_creep()
    out.update(creep_A=np.array([creep.A]), creep_alpha=np.array([creep.alpha]), creep_J=creep.J,
               creep_exponent=creep.exponent, creep_prestress_N=np.array([creep.prestress_N]))
    lo, hi = creep.window
    _, s1, _ = frequency_slopes(result, 1 / (2 * math.pi * hi), 1 / (2 * math.pi * lo), 200)
    out["creep_window_slope"] = np.array([s1.min(), s1.max()])
    out["stiffness_spread"] = np.array(result.stiffness_spread)
    return out

"""The records a fit is reported in: parameters, alternatives, per-data-set errors, curves; noise and verdicts."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._results import dataframe, format_repr
from ..io.data import RheologyData

if TYPE_CHECKING:
    from ..io.creep_data import CreepData

__all__ = ["FitParameter", "FitAlternative", "FitCurve", "DatasetFit", "CreepFit", "data_axis", "noise_rms",
           "inside_noise", "accepted", "verdict_text", "noise_note", "error_fields", "information_criteria",
           "lmfit_criteria", "CRITERIA_CONVENTION", "STATUSES"]


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


#: what a fit's ``status`` says (:attr:`tenscell.fitting.FitResult.status`), and what each means
STATUSES = {
    "tolerance met": "every data set's RMS is within the tolerance, or within its stated noise where that is larger "
                     "(converged)",
    "optimum, tolerance not met": "the search stopped at an optimum it could not improve (its starts agree, the best "
                                  "RMS is on a plateau, or every start spent its patience of moves without a 5 % "
                                  "gain): the model does not fit these data to the tolerance (where lmfit, stopping "
                                  "at an optimum, reports success)",
    "stopped by budget": "the search used its budget (every start ran its hops while still improving) before it met "
                         "the tolerance or found an optimum it could not improve: a longer search (--hops, --starts) "
                         "may fit better",
}


def verdict_text(converged: bool, tolerance_met: bool, status: str = "") -> str:
    """``"converged"``, ``"inside the data's noise (tolerance not met)"``, ``"tolerance not met at an optimum"`` or
    ``"NOT converged: stopped by its budget"`` (``status``: one of :data:`STATUSES`)."""
    if tolerance_met:
        return "converged"
    if converged:
        return "inside the data's noise (tolerance not met)"
    return "NOT converged: stopped by its budget" if status == "stopped by budget" else "tolerance not met at an optimum"


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


def error_fields(p: FitParameter, error: tuple[float | None, str]) -> dict:
    """``stderr`` (the parameter's unit, None when not determined), ``stderr_percent`` and ``stderr_note``."""
    rel, note = error
    return {"stderr": None if rel is None else abs(p.value) * rel,
            "stderr_percent": None if rel is None else 100.0 * rel, "stderr_note": note}



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


#: how tenscell's AIC and BIC count, in words (reports, the HTML view, fit.json's ``information_criteria``)
CRITERIA_CONVENTION = (
    "AIC = −2 ln L + 2k and BIC = −2 ln L + k ln n of Gaussian residuals in log10 G (or log10 J), n residuals, with "
    "the full log-likelihood: with the data's standard deviations, −2 ln L = χ² + Σ ln(2π s²) and k counts the "
    "model's parameters; without them the noise σ is estimated from the residuals, −2 ln L = n ln(2π RSS/n) + n, "
    "and σ is counted as one more parameter (k + 1). lmfit reports n ln(χ²/n) + 2k and n ln(χ²/n) + k ln n (χ² the "
    "sum of squared weighted residuals, σ not counted): without standard deviations tenscell's values are lmfit's "
    "plus n(1 + ln 2π) + 2 (AIC) and n(1 + ln 2π) + ln n (BIC), the same for every model fitted to the same data, so "
    "differences between models agree; with standard deviations the two can rank models differently.")


def lmfit_criteria(weighted_residuals, k: int) -> tuple[float, float]:
    """``(AIC, BIC)`` as lmfit reports them (``MinimizerResult.aic``, ``.bic``): ``n ln(χ²/n) + 2k`` and
    ``n ln(χ²/n) + k ln n``, χ² the sum of the squared weighted residuals, ``k`` the varied parameters (σ is not
    one). Beside tenscell's own (:func:`information_criteria`, :data:`CRITERIA_CONVENTION`)."""
    r = np.asarray(weighted_residuals, dtype=float)
    n = r.size
    chi2 = max(float(r @ r), 1e-250 * n)  # lmfit's floor: a perfect fit gives a finite value
    m2 = n * math.log(chi2 / n)
    return m2 + 2 * int(k), m2 + math.log(n) * int(k)


def information_criteria(weighted_residuals, k: int, *, sigma_known: bool, weights=None) -> tuple[float, float, float]:
    """``(AIC, BIC, −2 ln L)`` of Gaussian residuals in log10 G (the convention: :data:`CRITERIA_CONVENTION`;
    lmfit's: :func:`lmfit_criteria`).

    Parameters
    ----------
    weighted_residuals : array_like, shape (n,)
        ``w_i·(log10 G_model − log10 G_data)``.
    k : int
        Number of model parameters (σ is added here when it is estimated).
    sigma_known : bool
        True when the weights are ``1/s_i`` from the data's standard deviations.
    weights : array_like, shape (n,), optional
        The weights ``w_i = 1/s_i`` (decades⁻¹); required when ``sigma_known``.
    """
    r = np.asarray(weighted_residuals, dtype=float)
    n = r.size
    if sigma_known:
        if weights is None:
            raise ValueError("weights (1/standard deviation, per residual) are required when sigma_known is True")
        s = 1.0 / np.asarray(weights, dtype=float)
        m2logl = float(r @ r + np.sum(np.log(2 * np.pi * s**2)))
        kk = int(k)
    else:
        rss = float(r @ r)
        m2logl = n * math.log(2 * math.pi * rss / n) + n if rss > 0 else -math.inf
        kk = int(k) + 1
    return m2logl + 2 * kk, m2logl + kk * math.log(n), m2logl

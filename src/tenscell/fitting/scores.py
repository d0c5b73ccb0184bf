"""Models against each other: AIC/BIC, held-out error, the structural-damping law as the standard.

Every model fitted to the same data (a :class:`~tenscell.fitting.FitResult` of any model: the tensegrity, its
homogeneous cell, the structural-damping law of Fabry et al. 2001 and the other structure-free formulas of
:mod:`tenscell.fitting.models.formulas`) is scored on the same residuals.

Information criteria, for residuals in log10 G with independent Gaussian errors
------------------------------------------------------------------------------
With ``n`` residuals (G′ and G″ of every point count separately):

* data with standard deviations (every residual divided by its ``s_i``, in
  decades): ``−2 ln L = Σ r_i² + Σ ln(2π s_i²)`` and ``k`` = number of
  model parameters;
* without them, one common σ is estimated by maximum likelihood,
  ``σ̂² = RSS/n``: ``−2 ln L = n ln(2π RSS/n) + n`` and ``k`` = model
  parameters + 1 (σ).

``AIC = −2 ln L + 2k`` and ``BIC = −2 ln L + k ln n``. The model parameters of
a tensegrity fit are its free parameters minus the exact strut-length gauge
(:meth:`FitProblem.gauge`). The likelihood is that of log10 G; every model is
scored on the same residuals, so the differences between models are what
count. A model with at least as many parameters as residuals can fit
anything; its AIC then says little, and the small-sample correction (AICc) is
undefined.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import positive_scalar
from .._results import dataframe, format_repr, reporter
from .._threads import hot_path
from ..io.data import DataError, RheologyData
from .models.formulas import PHI0, structural_damping_moduli
from .records import information_criteria

__all__ = ["PHI0", "structural_damping_moduli", "fit_structural_damping", "information_criteria", "split_holdout",
           "ModelScore", "ModelComparison", "compare_models", "score"]

def fit_structural_damping(data: RheologyData, *, newtonian: bool = True, starts: int = 2, seed: int = 0):
    """Fit the structural-damping law (with or without its Newtonian term) to a frequency sweep: a
    :class:`~tenscell.fitting.FitResult` of the formula ``structural-damping(+newtonian)``
    (:mod:`tenscell.fitting.models.formulas`), through the same search as every model."""
    from .entry import fit

    data = _frequency_sweep(data, "fit_structural_damping")
    name = "structural-damping+newtonian" if newtonian else "structural-damping"
    return fit(data, model=name, starts=starts, seed=seed, max_points=None, progress=False)


def _one_prestress(data: RheologyData) -> bool:
    return data.prestress is None or np.unique(data.prestress).size == 1


def _frequency_sweep(data, what: str) -> RheologyData:
    if not isinstance(data, RheologyData) or not _one_prestress(data):
        raise DataError(f"{what}: needs one frequency sweep (RheologyData at a single prestress), got "
                         f"{getattr(data, 'source', type(data).__name__)}")
    return data


# ---------------------------------------------------------------------------------------
# information criteria and the comparison table
# ---------------------------------------------------------------------------------------
def split_holdout(data: RheologyData, f_min: float, f_max: float) -> tuple[RheologyData, RheologyData]:
    """Split a frequency sweep into (training, held-out) at the frequencies in ``[f_min, f_max]`` (Hz).

    Raises
    ------
    ValueError
        For creep data or a prestress sweep, bad limits, or a window that leaves no point on one side.
    """
    if getattr(data, "kind", None) == "creep":  # CreepData: times, no frequencies to hold out
        raise ValueError(f"holdout: {data.source} is creep compliance J(t); a frequency window needs a frequency "
                         "sweep of G', G''")
    f_min = positive_scalar("holdout f_min", f_min, "Hz")
    f_max = positive_scalar("holdout f_max", f_max, "Hz")
    if not f_min < f_max:
        raise ValueError(f"holdout: FMIN must be below FMAX, got {f_min:g}:{f_max:g} Hz")
    if not _one_prestress(data):
        raise ValueError(f"holdout: {data.source} is a prestress sweep; a frequency window needs a frequency sweep")
    held = (data.frequency_hz >= f_min) & (data.frequency_hz <= f_max)
    if not held.any() or held.all():
        raise ValueError(f"holdout: the window {f_min:g}:{f_max:g} Hz holds {int(held.sum())} of the {data.n} points "
                         f"of {data.source}; it must leave points on both sides")
    return _subset(data, ~held, "training"), _subset(data, held, "held out")


def _subset(data: RheologyData, mask, what: str) -> RheologyData:
    def pick(a):
        return None if a is None else a[mask]

    return RheologyData(frequency_hz=data.frequency_hz[mask], G_storage=data.G_storage[mask],
                        G_loss=data.G_loss[mask], prestress=pick(data.prestress),
                        G_storage_sd=pick(data.G_storage_sd), G_loss_sd=pick(data.G_loss_sd),
                        source=f"{data.source} ({what})", comments=data.comments)


@dataclass(frozen=True)
class ModelScore:
    """One model's row in the comparison.

    Attributes
    ----------
    name : str
    n_params : int
        Model parameters (without σ; exact gauges removed).
    rms_log10_error : float
        RMS of the unweighted log10 residuals on the training data (decades).
    aic, bic : float
    holdout_rms_log10_error : float or None
        RMS of the log10 errors at the held-out points (decades).
    """

    name: str
    n_params: int
    rms_log10_error: float
    aic: float
    bic: float
    holdout_rms_log10_error: float | None = None

    def to_dict(self) -> dict:
        return {"model": self.name, "n_params": self.n_params, "rms_log10_error": self.rms_log10_error,
                "aic": self.aic, "bic": self.bic, "holdout_rms_log10_error": self.holdout_rms_log10_error}


@dataclass(frozen=True, eq=False, repr=False)
class ModelComparison:
    """Models fitted to the same data, with RMS, parameters, AIC, BIC and (optionally) held-out error.

    Attributes
    ----------
    scores : tuple of ModelScore
    n_residuals : int
        Residuals every model was scored on (training data).
    sigma_known : bool
        Whether the data's standard deviations set the likelihood.
    holdout : tuple of (float, float) or None
        The held-out window (Hz).
    n_holdout : int
        Held-out data points.
    convention : str
        How AIC and BIC are computed, in words.
    results : tuple of FitResult
        The fits behind the scores, in the same order (their parameters with standard errors).
    """

    scores: tuple
    n_residuals: int
    sigma_known: bool
    holdout: tuple | None
    n_holdout: int
    convention: str
    results: tuple = ()

    def score(self, name: str) -> ModelScore:
        """The row of model ``name``."""
        for s in self.scores:
            if s.name == name:
                return s
        raise ValueError(f"no model named {name!r}; models: {', '.join(s.name for s in self.scores)}")

    def result(self, name: str):
        """The fit behind the row of model ``name``."""
        for s, r in zip(self.scores, self.results):
            if s.name == name:
                return r
        raise ValueError(f"no model named {name!r}; models: {', '.join(s.name for s in self.scores)}")

    def best(self, criterion: str = "aic") -> str:
        """Name of the model with the lowest ``criterion`` (``"aic"``, ``"bic"``, ``"holdout"``)."""
        key = {"aic": lambda s: s.aic, "bic": lambda s: s.bic,
               "holdout": lambda s: math.inf if s.holdout_rms_log10_error is None else s.holdout_rms_log10_error}
        if criterion not in key:
            raise ValueError(f"criterion must be one of {', '.join(key)}, got {criterion!r}")
        return min(self.scores, key=key[criterion]).name

    def __repr__(self) -> str:
        lines = [f"{s.name}: k={s.n_params}, rms {s.rms_log10_error:.3g}, AIC {s.aic:.1f}, BIC {s.bic:.1f}"
                 + ("" if s.holdout_rms_log10_error is None else f", held out {s.holdout_rms_log10_error:.3g}")
                 for s in self.scores]
        return format_repr(f"ModelComparison of {len(self.scores)} models on {self.n_residuals} residuals", *lines[:5])

    def _repr_html_(self) -> str:
        return reporter("comparison_html")(self)  # one row per model, the preferred ones named (reports/html.py)

    def to_dict(self) -> dict:
        return {"models": [s.to_dict() for s in self.scores], "n_residuals": self.n_residuals,
                "sigma_known": self.sigma_known, "holdout_Hz": None if self.holdout is None else list(self.holdout),
                "n_holdout_points": self.n_holdout, "convention": self.convention,
                "parameters": {s.name: {p.name: p.value for p in r.parameters}
                               for s, r in zip(self.scores, self.results)}}

    def to_dataframe(self):
        return dataframe({
            "model": [s.name for s in self.scores], "n_params": [s.n_params for s in self.scores],
            "rms_log10_error": [s.rms_log10_error for s in self.scores], "AIC": [s.aic for s in self.scores],
            "BIC": [s.bic for s in self.scores],
            "holdout_rms_log10_error": [s.holdout_rms_log10_error for s in self.scores]})


def holdout_rms(result, held: RheologyData | None) -> float | None:
    """RMS (decades) of a fitted model's log10 errors at held-out points of the same prestress (None: none held)."""
    if held is None:
        return None
    try:
        Gs, Gl = result.moduli(held.frequency_hz)
    except ValueError:  # not a stable cell there
        return math.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.concatenate([np.log10(Gs / held.G_storage), np.log10(Gl / held.G_loss)])
    return float(np.sqrt(np.mean(r**2))) if np.all(np.isfinite(r)) else math.inf


CONVENTION = {
    True: "Gaussian errors in log10 G with the data's standard deviations: −2 ln L = Σ r² + Σ ln(2π s²); "
          "k = model parameters",
    False: "Gaussian errors in log10 G with one unknown σ (maximum likelihood, σ² = RSS/n): "
           "−2 ln L = n ln(2π RSS/n) + n; k = model parameters + 1 (σ)",
}


def score(result, *, held_out: RheologyData | None = None, name: str | None = None) -> ModelScore:
    """One fit's row: its model parameters (free, less an exact gauge), RMS, AIC, BIC, held-out RMS."""
    aic, bic = result.information_criteria()
    return ModelScore(name=name or result.problem.comparison_name, n_params=int(result.problem.n_model_parameters),
                      rms_log10_error=float(result.rms_log10_error), aic=aic, bic=bic,
                      holdout_rms_log10_error=holdout_rms(result, held_out))


@hot_path
def compare_models(result, *, homogeneous=None, structural=True, baselines=(), held_out: RheologyData | None = None,
                   holdout: tuple | None = None, name: str | None = None) -> ModelComparison:
    """Score a fit beside its baselines on the same data (every one a :class:`~tenscell.fitting.FitResult`).

    Parameters
    ----------
    result : FitResult
        The fit; its data are the training data.
    homogeneous : FitResult, optional
        The homogeneous tensegrity fitted to the same data.
    structural : FitResult or bool
        The structural-damping law (+ Newtonian) fitted to the same data; True fits it here (one frequency sweep
        only: the law has no prestress), False leaves it out.
    baselines : sequence of FitResult
        More models fitted to the same data (structure-free formulas, other mechanisms).
    held_out : RheologyData, optional
        Points no model was fitted to (see :func:`split_holdout`); their RMS log10 error is reported per model.
    holdout : (float, float), optional
        The held-out window (Hz), for the record.
    name : str, optional
        Row name of ``result`` (default its label).
    """
    datasets = result.datasets
    sigma_known = all(d.has_sd for d in datasets)
    if structural is True:
        one = len(datasets) == 1 and datasets[0].kind != "creep" and _one_prestress(datasets[0])
        structural = fit_structural_damping(datasets[0]) if one else None
    fits = [(name, result)]
    if homogeneous is not None and homogeneous is not result:
        fits.append((None, homogeneous))
    if structural not in (None, False):
        fits.append(("structural damping (power law)", structural))
    fits += [(None, b) for b in baselines]
    rows = tuple(score(r, held_out=held_out, name=n) for n, r in fits)
    convention = CONVENTION[sigma_known] + ("; AIC = −2 ln L + 2k, BIC = −2 ln L + k ln n; tensegrity parameters "
                                            "exclude the exact strut-length gauge; lmfit's n ln(χ²/n) + 2k (σ not "
                                            "counted) differs " + ("by a constant, so ΔAIC and ΔBIC are the same"
                                                                   if not sigma_known else "in form"))
    return ModelComparison(scores=rows, n_residuals=int(result.problem.weights.size), sigma_known=sigma_known,
                           holdout=None if holdout is None else (float(holdout[0]), float(holdout[1])),
                           n_holdout=0 if held_out is None else held_out.n, convention=convention,
                           results=tuple(r for _, r in fits))

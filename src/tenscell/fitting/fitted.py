"""A fitted model is a model like any other: moduli anywhere, its cell and tendon law, fit.json.

Every fit's :attr:`~tenscell.fitting.FitResult.model` is a :class:`FittedModel`:

* :class:`FittedCell` — the paper's cell with Voigt tendons (the per-tendon, per-family or homogeneous fit): the cell
  at the fitted strut length, every tendon's EA and c;
* :class:`FittedMechanism` — a mechanism: its law's values per tendon (one assignment of a distributed property, or
  the average over the fit's K assignments for the moduli), the cytoplasm viscosity;
* :class:`FittedFormula` — a structure-free formula (a baseline): moduli only, no cell.

They share the prestress mapping (the model prestress P in N, or the scale s in m² that turns a measured prestress in
Pa into P), :meth:`FittedModel.moduli`, and, for the two with a cell, :meth:`FittedModel.tendon_law` and
:meth:`FittedModel.linear` — what creep, relaxation, simulation and ``show`` take. ``to_dict`` is the ``"model"``
entry of fit.json, and :func:`load_fit` rebuilds any of them from a fit.json, validating it first (schema version,
model, every field and its range) so that a damaged or foreign file is refused in one line naming the field.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._checks import positive_scalar
from .._results import format_repr
from ..linear.linearize import LinearModel
from .fit_labels import check_cell_parameters, check_document_labels, check_model_labels
from .models.base import FITTED_KINDS, FitFileError, FittedModel, cell_from_dict, cell_to_dict
from .models.formulas import FORMULA_FORMAT, FittedFormula
from .models.mechanism import MECHANISM_FORMAT, FittedMechanism
from .models.voigt import MODEL_FORMAT, FittedCell, scaled_cell

__all__ = ["FittedModel", "FittedCell", "FittedMechanism", "FittedFormula", "scaled_cell", "load_fit",
           "fitted_from_dict", "PredictedCreep", "predicted_creep", "MODEL_FORMAT", "MECHANISM_FORMAT",
           "FORMULA_FORMAT", "FIT_SCHEMA", "FitFileError", "cell_to_dict", "cell_from_dict"]

#: the version of the fit.json document :meth:`tenscell.fitting.FitResult.to_dict` writes (``"schema"``); version 1
#: documents (tenscell 0.2, no ``"schema"`` entry) are still read
FIT_SCHEMA = 2


def fitted_from_dict(obj: dict) -> FittedModel:
    """Any fitted model from the dict its ``to_dict`` wrote (FitFileError naming the field that is wrong)."""
    if not isinstance(obj, dict):
        raise FitFileError(f"model: expected an object, got {type(obj).__name__}")
    kind = FITTED_KINDS.get(obj.get("format"))  # type: ignore[arg-type]
    if kind is None:
        raise FitFileError(f"model.format: {obj.get('format')!r} is not a tenscell fitted model (expected one of "
                           f"{', '.join(FITTED_KINDS)})")
    check_model_labels(obj)
    try:
        fitted = kind.from_dict(obj)
    except FitFileError:
        raise
    except (KeyError, TypeError, ValueError, AttributeError) as err:
        raise FitFileError(f"model: the fitted model cannot be rebuilt: {err}") from None
    check_cell_parameters(obj.get("cell_parameters"), obj.get("structure"))
    return fitted


def load_fit(path) -> FittedModel:
    """The fitted model stored in a ``fit.json`` written by ``tenscell fit`` (any model), validated first.

    Raises
    ------
    FitFileError
        (a ValueError) If the file is not JSON, of an unknown schema version, or its model is missing, of an
        unknown kind, or has a missing or out-of-range field; the message names the file and the field.
    """
    path = Path(path)
    try:
        obj = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        raise FitFileError(f"--from-fit {path}: cannot read the file ({err})") from None
    except json.JSONDecodeError as err:
        raise FitFileError(f"--from-fit {path}: not valid JSON (line {err.lineno}: {err.msg})") from None
    if not isinstance(obj, dict):
        raise FitFileError(f"--from-fit {path}: not a fit.json (a JSON object written by `tenscell fit`)")
    schema = obj.get("schema", 1)
    if schema not in (1, FIT_SCHEMA):
        raise FitFileError(f"--from-fit {path}: schema {schema!r} is not one this tenscell reads (1 or {FIT_SCHEMA}); "
                           "refit with this version")
    if "model" not in obj:
        raise FitFileError(f"--from-fit {path}: no fitted model in the file (a fit.json written by `tenscell fit` "
                           "has a \"model\" entry)")
    try:
        fitted = fitted_from_dict(obj["model"])
        check_document_labels(obj, _model_name(obj["model"]))
    except FitFileError as err:
        raise FitFileError(f"--from-fit {path}: {err}") from None
    return fitted


def _model_name(model: dict) -> str | None:
    """The name of the mechanism or formula a fit.json's model holds (None for a fitted Voigt cell)."""
    for kind in ("mechanism", "formula"):
        if isinstance(model.get(kind), dict):
            return model[kind].get("name")
    return None


# ---------------------------------------------------------------------------------------
# predicted creep of a fitted cell
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class PredictedCreep:
    """Creep compliance of a fitted cell and its power-law exponent over a window.

    Attributes
    ----------
    t : ndarray, shape (k,)
        Times after the stress step (s).
    J : ndarray, shape (k,)
        Creep compliance (1/Pa): the model's J(t)·2L.
    exponent : ndarray, shape (k,)
        Local exponent ``d ln J/d ln t``.
    alpha : float
        Exponent of the straight-line fit of ln J against ln t over the window.
    A : float
        ``J`` at t = 1 s of that fit (1/Pa).
    rms_log : float
        RMS of the fit's ln residuals.
    window : (float, float)
        The window (s).
    prestress_N : float
    """

    t: np.ndarray
    J: np.ndarray
    exponent: np.ndarray
    alpha: float
    A: float
    rms_log: float
    window: tuple
    prestress_N: float

    def __repr__(self) -> str:
        return format_repr("PredictedCreep", f"J(t) ~ {self.A:.4g}·t^{self.alpha:.4f} 1/Pa over "
                                             f"{self.window[0]:g}..{self.window[1]:g} s (rms ln {self.rms_log:.2g})")

    def to_dict(self) -> dict:
        return {"window_s": list(self.window), "alpha": self.alpha, "A_per_Pa": self.A, "rms_log": self.rms_log,
                "local_exponent_range": [float(self.exponent.min()), float(self.exponent.max())],
                "prestress_N": self.prestress_N, "time_s": self.t.tolist(), "creep_compliance_per_Pa": self.J.tolist()}

    def to_dataframe(self):
        from .._results import dataframe

        return dataframe({"time_s": self.t, "creep_compliance_per_Pa": self.J, "local_exponent": self.exponent},
                         {"alpha": self.alpha, "window_s": self.window})


def predicted_creep(lin: LinearModel, t_min: float = 0.1, t_max: float = 10.0, n: int = 41) -> PredictedCreep:
    """Creep compliance of a linear model on ``n`` log-spaced times over [t_min, t_max] s and its exponent."""
    from ..timedomain import creep_spectrum, fit_power_law

    t_min = positive_scalar("t_min", t_min, "s")
    t_max = positive_scalar("t_max", t_max, "s")
    if not t_min < t_max:
        raise ValueError(f"t_min must be below t_max, got {t_min:g}, {t_max:g} s")
    t = np.logspace(math.log10(t_min), math.log10(t_max), int(n))
    spec = creep_spectrum(lin)
    J = spec.compliance(t) * (2.0 * spec.L)
    pl = fit_power_law(t, J)
    return PredictedCreep(t=t, J=J, exponent=spec.exponent(t), alpha=pl.alpha, A=pl.A, rms_log=pl.rms_log,
                          window=(t_min, t_max), prestress_N=float(lin.P))

"""CSV layouts of the tables tenscell writes: (header, rows) from results, in one place.

The moduli layout is the prestress-sweep layout that :func:`tenscell.io.data.read_csv`
reads (``prestress_Pa, frequency_Hz, G_storage_Pa, G_loss_Pa``), so a table
written by ``tenscell moduli`` or ``reproduce`` can be fitted by ``tenscell fit``.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["MODULI_HEADER", "moduli_table", "fit_table", "check_finite_rows"]

#: header of every (P, f, G', G'') table; the same names the data reader accepts
MODULI_HEADER = ["prestress_Pa", "frequency_Hz", "G_storage_Pa", "G_loss_Pa"]


def moduli_table(response):
    """(header, rows) of a :class:`~tenscell.response.FrequencyResponse`, prestress-major."""
    return list(MODULI_HEADER), response.rows()


def fit_table(result, baseline):
    """(header, rows) of fit.csv: data, model (with its standard error, first order: value × ln10 ×
    :meth:`~tenscell.fitting.FitResult.model_standard_errors`) and homogeneous baseline at each point of each
    data set.

    ``prestress_Pa`` is the data's own (stated) prestress, or for a data set
    whose prestress was fitted in a joint fit the fitted value; empty for a
    frequency sweep fitted alone.
    """
    header = ["dataset", "source", "prestress_Pa", "frequency_Hz", "G_storage_Pa", "G_loss_Pa",
              "G_storage_model_Pa", "G_storage_model_stderr_Pa", "G_loss_model_Pa", "G_loss_model_stderr_Pa",
              "log10_error_storage", "log10_error_loss", "G_storage_baseline_Pa", "G_loss_baseline_Pa"]
    # time data sets fill their kind's columns (and leave the others empty), moduli rows the moduli ones; a
    # relaxation's shape (data.relative) gives G(t)/G(t_ref) in the relaxation columns
    kinds = [k for k in _TIME_COLUMNS if any(f.axis == "time" and f.data.kind == k for f in result.fits)]
    if kinds:
        header += ["time_s"] + [c for k in kinds for c in _TIME_COLUMNS[k]]
    width = 1 + 5 * len(kinds) if kinds else 0
    se = result.model_standard_errors() * math.log(10.0)  # relative standard error of each model value
    rows = []
    for f, b in zip(result.fits, baseline.fits):
        d, n = f.data, f.data.n
        if f.axis == "time":
            where = result.problem.point_rows(f.index)  # a shape's reference time is no residual: no error
            r = np.where(where >= 0, se[np.maximum(where, 0)], math.nan)
            before = 5 * kinds.index(d.kind)
            for i in range(n):
                P = float(d.prestress[i]) if d.prestress is not None else (
                    "" if f.prestress_fitted_pa is None else f.prestress_fitted_pa)
                m = f.model_values
                rows.append([f.index, d.source, P] + [""] * 11 + [float(d.time_s[i])] + [""] * before + [
                    float(f.data_values[i]), float(m[i]), _se(m[i], r[i]), float(f.residuals[i]),
                    float(b.model_values[i])] + [""] * (width - 6 - before))
            continue
        r = se[result.problem.rows(f.index)]
        for i in range(n):
            P = float(d.prestress[i]) if d.prestress is not None else (
                "" if f.prestress_fitted_pa is None else f.prestress_fitted_pa)
            rows.append([f.index, d.source, P, float(d.frequency_hz[i]), float(d.G_storage[i]), float(d.G_loss[i]),
                         float(f.G_storage_model[i]), _se(f.G_storage_model[i], r[i]), float(f.G_loss_model[i]),
                         _se(f.G_loss_model[i], r[n + i]), float(f.residuals[i]), float(f.residuals[n + i]),
                         float(b.G_storage_model[i]), float(b.G_loss_model[i])]
                        + [""] * width)
    return header, rows


#: the columns of each kind of time data in fit.csv (after ``time_s``)
_TIME_COLUMNS = {
    "creep": ["creep_compliance_per_Pa", "creep_compliance_model_per_Pa", "creep_compliance_model_stderr_per_Pa",
              "log10_error_creep", "creep_compliance_baseline_per_Pa"],
    "relaxation": ["relaxation_modulus_Pa", "relaxation_modulus_model_Pa", "relaxation_modulus_model_stderr_Pa",
                   "log10_error_relaxation", "relaxation_modulus_baseline_Pa"],
}


def _se(value, relative) -> float | str:
    """A model value's standard error from its relative one; empty when not determined (σ unknown)."""
    return float(abs(value) * relative) if math.isfinite(relative) else ""


def check_finite_rows(rows, what: str, inputs: str = ""):
    """Yield ``rows`` unchanged; ValueError at the first row with an inf or NaN number.

    A non-finite modulus means the inputs left the range where float64 resolves
    the model; the message says which inputs to change.
    """
    for row in rows:
        for v in row:
            if isinstance(v, float) and not math.isfinite(v):
                raise ValueError(f"{what} is not finite ({v!r}) at {tuple(row)[:2]}; "
                                 f"the inputs{(' ' + inputs) if inputs else ''} are beyond what float64 resolves")
        yield row


def finite(array, what: str) -> np.ndarray:
    """``array`` if all finite, else ValueError naming ``what``."""
    arr = np.asarray(array)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{what} is not finite for these inputs; reduce the extreme values")
    return arr

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
    """(header, rows) of fit.csv: data, model and homogeneous baseline at each data point."""
    d = result.data
    Gs, Gl = result.problem.moduli(result.theta)
    Bs, Bl = baseline.problem.moduli(baseline.theta)
    n = d.n
    sweep = d.kind == "prestress"
    header = (["prestress_Pa"] if sweep else []) + [
        "frequency_Hz", "G_storage_Pa", "G_loss_Pa", "G_storage_model_Pa", "G_loss_model_Pa",
        "log10_error_storage", "log10_error_loss", "G_storage_baseline_Pa", "G_loss_baseline_Pa"]
    rows = []
    for i in range(n):
        rows.append(([float(d.prestress[i])] if sweep else []) + [
            float(d.frequency_hz[i]), float(d.G_storage[i]), float(d.G_loss[i]), float(Gs[i]), float(Gl[i]),
            float(result.residuals[i]), float(result.residuals[n + i]), float(Bs[i]), float(Bl[i])])
    return header, rows


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

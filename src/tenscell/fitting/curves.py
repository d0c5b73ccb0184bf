"""A fitted model against its data's axes: dense curves, local log-log slopes, straight lines in prestress.

Every function takes a :class:`~tenscell.fitting.FitResult` of any model (it asks only for
:meth:`~tenscell.fitting.FitResult.moduli`), so every model's report and figure use the same ones.
"""
from __future__ import annotations

import math

import numpy as np

from .._checks import positive_scalar
from ..response import log_slope
from .records import FitCurve

__all__ = ["model_curve", "frequency_slopes", "prestress_slopes", "shape_quantities"]


def model_curve(result, n: int = 200, label: str | None = None, dataset: int = 0) -> FitCurve:
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


def frequency_slopes(result, f_lo: float = 0.01, f_hi: float = 100.0, n: int = 1000,
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


def prestress_slopes(result, n: int = 100, dataset: int | None = None) -> tuple[float, float, float, float]:
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



def shape_quantities(result) -> dict[str, np.ndarray]:
    """The shape of the fitted model on each data set's axis, as flat arrays (the report gives each a ±).

    ``frequency_slopes[k]`` (G' slope min, max, G'' slope min, max over 1000 frequencies spanning frequency sweep k),
    ``creep_slopes[k]`` (min, max of d ln J/d ln t at creep data set k's times), ``prestress_lines[k]`` (dG'/dP,
    G'(0) in Pa, dG''/dP, G''(0) in Pa over prestress sweep k).
    """
    out: dict[str, np.ndarray] = {}
    for f in result.fits:
        d = f.data
        if f.axis == "frequency":
            _, s1, s2 = frequency_slopes(result, float(d.frequency_hz.min()), float(d.frequency_hz.max()), 1000,
                                         dataset=f.index)
            out[f"frequency_slopes[{f.index}]"] = np.array([s1.min(), s1.max(), s2.min(), s2.max()])
        elif f.axis == "time":
            expo = np.gradient(np.log(f.model_values), np.log(d.time_s)) if d.n > 1 else np.zeros(1)
            out[f"creep_slopes[{f.index}]"] = np.array([expo.min(), expo.max()])
        else:
            out[f"prestress_lines[{f.index}]"] = np.array(prestress_slopes(result, dataset=f.index))
    return out

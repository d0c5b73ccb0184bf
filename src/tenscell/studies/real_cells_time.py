"""The measured cells in the time domain: mechanisms fitted to a creep curve and to the shape of a stress relaxation.

Both are fitted by the one stack (:func:`tenscell.fitting.fit`, :mod:`tenscell.fitting.time_series`), as every
data set is:

* **creep** (the HL60 optical-stretcher curve, :func:`~tenscell.studies.real_cells.hl60_creep`): the creep compliance
  J(t) (1/Pa) after a stress step, a :class:`~tenscell.io.creep_data.CreepData`; the model's ``J̄(s) = 1/(s·G*(s))``;
* **the shape of a stress relaxation** (the oocyte, :func:`~tenscell.studies.real_cells.oocyte_relaxation`): the
  force at constant height over its value at the first time bin, a relative
  :class:`~tenscell.io.relaxation_data.RelaxationData`; the model's ``G(t)/G(t_ref)`` from ``Ḡ(s) = G*(s)/s``. The
  probe radius is unknown, so the force has no modulus scale: only the shape is fitted, and one combination of the
  parameters is not determined by it (every stiffness, damping, viscosity and P scaled together leaves the shape
  unchanged; it is not counted).

A mechanism's ``G*(s)`` is its cell's exact Laplace-domain modulus from each tendon law's ``k*(s)``, inverted at each
time by the fixed Talbot contour, with the exact Jacobian (the same contour over ``dG*/dθ``); the search, its starts
and its result are the stack's. The baselines have no structure and go through the same stack: the
structural-damping law (``J = A t^x`` exactly; its relaxation ``(t/t_ref)^−x``), and for creep the structural-damping
law with a Newtonian term.

Each fit is summarized as a :class:`TimeDomainFit`, the row of the study's table (the RMS over every point and over
the late times, the fitted values, the model's curve on a dense grid) with the stack's
:class:`~tenscell.fitting.FitResult` it comes from.
"""
from __future__ import annotations

from typing import Any

import math
import time
from dataclasses import dataclass, field

import numpy as np

__all__ = ["TimeSeries", "TimeDomainFit", "creep_series", "relaxation_series", "power_law_fit",
           "structural_newtonian_fit", "mechanism_time_fit", "FIT_NODES", "LATE_S"]

#: Talbot contour nodes of a fit's inversions (:data:`tenscell.fitting.time_series.FIT_NODES`)
FIT_NODES = 16
#: the times from which an AFM relaxation is a relaxation after a step (its approach ramp lasts about 1 s): the RMS
#: from here on is reported beside the RMS over every point
LATE_S = 1.0
#: the search of a baseline's fit (a formula: a few parameters, one basin), to a tolerance no data meet (it runs
#: until its starts agree: the law's own optimum, exact on data the law made)
BASELINE_SEARCH: dict[str, Any] = {"starts": 2, "hops": 2, "tolerance": 1e-9}
#: basin-hopping moves of a mechanism's time-domain fit per start (each evaluation inverts G*(s) at every time)
MECHANISM_HOPS = 4


@dataclass(frozen=True, eq=False, repr=False)
class TimeSeries:
    """A measured time function to fit.

    Attributes
    ----------
    name : str
        E.g. ``"HL60 creep"``.
    kind : {"creep", "relaxation shape"}
        ``values`` is J(t) in 1/Pa, or a force over its value at ``time_s[0]`` (dimensionless).
    time_s : ndarray
        Times after the step (s), increasing.
    values : ndarray
        Positive values at ``time_s``.
    source : str
    """

    name: str
    kind: str
    time_s: np.ndarray
    values: np.ndarray
    source: str

    def __post_init__(self):
        if self.kind not in ("creep", "relaxation shape"):
            raise ValueError(f"kind must be 'creep' or 'relaxation shape', got {self.kind!r}")
        t, y = np.asarray(self.time_s, float), np.asarray(self.values, float)
        if t.shape != y.shape or t.ndim != 1 or t.size < 3:
            raise ValueError(f"{self.name}: time_s and values must be 1-D of one length >= 3, got {t.shape}, {y.shape}")
        if not (np.all(t > 0) and np.all(y > 0) and np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
            raise ValueError(f"{self.name}: times and values must be positive and finite")
        object.__setattr__(self, "time_s", t)
        object.__setattr__(self, "values", y)

    def __repr__(self) -> str:
        return (f"<TimeSeries {self.name} ({self.kind}): {self.time_s.size} points, {self.time_s[0]:.3g}–"
                f"{self.time_s[-1]:.3g} s>")

    @property
    def data(self):
        """The series as the stack's data: :class:`~tenscell.io.creep_data.CreepData` (creep) or a relative
        :class:`~tenscell.io.relaxation_data.RelaxationData` (a relaxation's shape)."""
        from ..io.creep_data import CreepData
        from ..io.relaxation_data import RelaxationData

        if self.kind == "creep":
            return CreepData(time_s=self.time_s, compliance=self.values, source=self.source)
        return RelaxationData(time_s=self.time_s, modulus=self.values, relative=True, source=self.source)

    def rms(self, model, late: bool = False) -> float:
        """RMS (decades) of log10(model/values), over every point or (``late``) those at t ≥ :data:`LATE_S`."""
        sel = self.time_s >= LATE_S if late else np.ones(self.time_s.size, bool)
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.log10(np.asarray(model, float)[sel] / self.values[sel])
        return float(np.sqrt(np.mean(r**2))) if sel.any() and np.all(np.isfinite(r)) else math.inf


def creep_series(creep, name: str = "HL60 creep") -> TimeSeries:
    """A :class:`TimeSeries` of measured creep (:class:`~tenscell.io.creep_data.CreepData`)."""
    return TimeSeries(name=name, kind="creep", time_s=creep.time_s, values=creep.compliance, source=creep.source)


def relaxation_series(relaxation, name: str = "oocyte relaxation (shape)") -> TimeSeries:
    """A :class:`TimeSeries` of a relaxation's shape (:class:`~tenscell.studies.real_cells.OocyteRelaxation`):
    the median over curves of force over force at the first bin after t = 0; bins where it is not positive are left
    out."""
    t, shape = relaxation.shape()
    keep = shape > 0
    return TimeSeries(name=name, kind="relaxation shape", time_s=t[keep], values=shape[keep],
                      source=relaxation.source)


@dataclass(frozen=True, eq=False, repr=False)
class TimeDomainFit:
    """A model fitted to a :class:`TimeSeries`.

    Attributes
    ----------
    data : str
        The series' name.
    model : str
    structural : bool
        A tensegrity (a mechanism) or a structure-free law.
    n_params : int
        Free parameters of this fit.
    rms : float
        RMS of the log10 errors over every point (decades).
    rms_late : float
        The same over t ≥ :data:`LATE_S`.
    values : dict
        Fitted parameters (SI units; P in N).
    at_bound : tuple of str
        Free parameters at a bound (within 0.1 % in log).
    curve : tuple of ndarray
        ``(t, y)``: the model on a dense grid over the data's times.
    local_exponent : float
        d log y / d log t of the model at the geometric middle of the data's times.
    message : str
        How the fit ended.
    cpu_s : float
        CPU seconds of the fit.
    result : FitResult or None
        The stack's fit this row summarizes.
    """

    data: str
    model: str
    structural: bool
    n_params: int
    rms: float
    rms_late: float
    values: dict
    at_bound: tuple
    curve: tuple = field(default=(), repr=False)
    local_exponent: float = math.nan
    message: str = ""
    cpu_s: float = 0.0
    result: object = field(default=None, repr=False, compare=False)

    def __repr__(self) -> str:
        return f"<TimeDomainFit {self.model} on {self.data}: {self.n_params} free, RMS {self.rms:.3g} decades>"


def _dense(series: TimeSeries, n: int = 80) -> np.ndarray:
    return np.logspace(math.log10(series.time_s[0]), math.log10(series.time_s[-1]), n)


def _local_exponent(t, y) -> float:
    mid = math.sqrt(t[0] * t[-1])
    lt, ly = np.log(t), np.log(np.abs(y))
    return float(np.interp(math.log(mid), lt, np.gradient(ly, lt)))


def _curve(result, series: TimeSeries, t) -> np.ndarray:
    """The fitted model's time function at times ``t`` (s): the same model laid out on the same kind of data at
    those times (the layout, and so the parameters, do not depend on the times), at the fit's parameters."""
    dense = TimeSeries(name=series.name, kind=series.kind, time_s=t, values=np.interp(
        np.log(t), np.log(series.time_s), series.values), source=series.source).data
    return result.spec.problem(dense, result.cell).time_model(result.theta)


def _fit(series: TimeSeries, model, label: str, values, *, starts: int, seed: int, **search) -> TimeDomainFit:
    """``model`` fitted to ``series`` by the stack, as the study's row: ``values(result)`` names what it reports."""
    from ..fitting import fit

    t0 = time.process_time()
    result = fit(series.data, model=model, starts=starts, seed=seed, progress=False, **search)
    y = result.fits[0].model_values
    td = _dense(series)
    yd = _curve(result, series, td)
    at_bound = tuple(p.name for p in result.parameters if p.at_bound is not None)
    return TimeDomainFit(data=series.name, model=label, structural=result.spec.capabilities.structural,
                         n_params=result.problem.n_model_parameters, rms=series.rms(y),
                         rms_late=series.rms(y, late=True), values=values(result), at_bound=at_bound,
                         curve=(td, yd), local_exponent=_local_exponent(td, yd), message=result.message,
                         cpu_s=time.process_time() - t0, result=result)


# ---------------------------------------------------------------------------------------
# the baselines
# ---------------------------------------------------------------------------------------
def power_law_fit(series: TimeSeries, *, seed: int = 0) -> TimeDomainFit:
    """``J = A t^x`` (creep, 2 parameters) or ``(t/t_ref)^−x`` (relaxation shape, 1 parameter): the
    structural-damping law ``G0·Γ(1−x)·s^x``, whose creep is ``t^x/(G0 Γ(1−x) Γ(1+x))`` and whose relaxation is
    ``G0 t^−x``, fitted by the stack."""
    def values(result):
        G0, x = result.value("G0"), result.value("alpha")
        if series.kind == "creep":
            return {"A": 1.0 / (G0 * math.gamma(1 - x) * math.gamma(1 + x)), "x": x}
        return {"x": x}

    label = "power law A·t^x" if series.kind == "creep" else "power law (t/t_ref)^-x"
    return _fit(series, "structural-damping", label, values, seed=seed, **BASELINE_SEARCH)


def structural_newtonian_fit(series: TimeSeries, *, seed: int = 0) -> TimeDomainFit:
    """The structural-damping law with a Newtonian term, ``G* = G0·Γ(1−x)·s^x + η s``, fitted to creep (3
    parameters) by the stack."""
    if series.kind != "creep":
        raise ValueError("structural_newtonian_fit: creep data only (a relaxation shape is the power law's)")
    return _fit(series, "structural-damping+newtonian", "structural damping + Newtonian",
                lambda r: {"G0": r.value("G0"), "x": r.value("alpha"), "eta": r.value("eta")}, seed=seed,
                **BASELINE_SEARCH)


# ---------------------------------------------------------------------------------------
# a mechanism
# ---------------------------------------------------------------------------------------
def mechanism_time_fit(series: TimeSeries, model, *, starts: int = 4, seed: int = 0) -> TimeDomainFit:
    """A mechanism (a name or :class:`~tenscell.fitting.models.mechanism.Mechanism`) fitted to ``series`` in the
    time domain by the stack (module docstring): ``starts`` starts of the mechanism's own rule, seed ``seed``."""
    from ..fitting import get_model

    spec = get_model(model)
    if not spec.capabilities.structure_shares:  # a mechanism: a tendon law on the cell
        raise ValueError(f"mechanism_time_fit: {spec.name!r} is not a mechanism")
    return _fit(series, spec, spec.name, lambda r: dict(r.model.parameter_values(), **_prestress(r)),
                starts=starts, seed=seed, hops=MECHANISM_HOPS)


def _prestress(result) -> dict:
    """The fit's model prestress P (N) (no data set states its prestress)."""
    return {"P": float(result.group_prestress()[0])}

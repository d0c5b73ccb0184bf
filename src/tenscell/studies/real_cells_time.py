"""The measured cells in the time domain: mechanisms fitted to a creep curve and to the shape of a stress relaxation.

The frequency-domain fits of :mod:`tenscell.fitting` take moduli; these two data sets are functions of time:

* **creep** (the HL60 optical-stretcher curve, :func:`~tenscell.studies.real_cells.hl60_creep`): the creep compliance
  J(t) (1/Pa) after a stress step, ``J̄(s) = 1/(s·G*(s))``;
* **the shape of a stress relaxation** (the oocyte, :func:`~tenscell.studies.real_cells.oocyte_relaxation`): the
  force at constant height over its value at the first time bin, compared with ``G(t)/G(t_ref)``,
  ``Ḡ(s) = G*(s)/s − η`` (the cytoplasm's impulse at t = 0 removed). The probe radius is unknown, so the force has no
  modulus scale: only the shape is fitted, and one combination of the parameters is not determined by it (every
  stiffness, damping, viscosity and P scaled together leaves the shape unchanged; it is not counted).

A mechanism's ``G*(s)`` is its cell's exact Laplace-domain modulus: each tendon law's ``k*(s)``
(:meth:`~tenscell.laws.base.TendonLaw.laplace_stiffness`), the cell's compliance
(:func:`~tenscell.linear.dynamic.dynamic_compliance`), the assignments' mean for a distributed property (as the
frequency-domain fits average them), plus ``sη``; the time function is inverted at each time by the fixed Talbot
contour (:func:`~tenscell.timedomain.invert_laplace`). A fit starts where the stack (:func:`tenscell.fitting.fit`)
puts the mechanism on the moduli that the data's own power law implies exactly (``J = A t^x`` ⇔
``G* = (iω)^x / (A Γ(1+x))``; ``G(t) ∝ t^−x`` ⇔ ``G* ∝ Γ(1−x)(iω)^x``), then least squares on the log10 of the time
function moves every free parameter (trust region, forward differences in the log-parameters, within the stack's
bounds).

The baselines have no structure: the power law (``J = A t^x``, 2 parameters; ``(t/t_ref)^−x``, 1 shape parameter —
the structural-damping law's own creep and relaxation), and for creep the structural-damping law with a Newtonian
term (3 parameters, inverted the same way).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

__all__ = ["TimeSeries", "TimeDomainFit", "creep_series", "relaxation_series", "power_law_fit",
           "structural_newtonian_fit", "mechanism_time_fit", "FIT_NODES", "LATE_S"]

#: Talbot contour nodes during a search (relative error about 1e-6, far below the data's scatter); the reported
#: curves and RMS use :data:`tenscell.timedomain.TALBOT_NODES`
FIT_NODES = 16
#: the times from which an AFM relaxation is a relaxation after a step (its approach ramp lasts about 1 s): the RMS
#: from here on is reported beside the RMS over every point
LATE_S = 1.0
#: least-squares iterations of a time-domain fit at most (each costs one evaluation per free parameter more)
MAX_ITERATIONS = 150


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

    def __repr__(self) -> str:
        return f"<TimeDomainFit {self.model} on {self.data}: {self.n_params} free, RMS {self.rms:.3g} decades>"


def _dense(series: TimeSeries, n: int = 80) -> np.ndarray:
    return np.logspace(math.log10(series.time_s[0]), math.log10(series.time_s[-1]), n)


def _local_exponent(t, y) -> float:
    mid = math.sqrt(t[0] * t[-1])
    lt, ly = np.log(t), np.log(np.abs(y))
    return float(np.interp(math.log(mid), lt, np.gradient(ly, lt)))


def _finish(series, model, structural, n, values, at_bound, fn, message, t0) -> TimeDomainFit:
    """The fit's record: RMS at the data, the dense curve, the local exponent (``fn(t)`` the fitted function)."""
    y = fn(series.time_s)
    td = _dense(series)
    yd = fn(td)
    return TimeDomainFit(data=series.name, model=model, structural=structural, n_params=n, rms=series.rms(y),
                         rms_late=series.rms(y, late=True), values=dict(values), at_bound=tuple(at_bound),
                         curve=(td, yd), local_exponent=_local_exponent(td, yd), message=message,
                         cpu_s=time.process_time() - t0)


# ---------------------------------------------------------------------------------------
# the baselines
# ---------------------------------------------------------------------------------------
def power_law_fit(series: TimeSeries) -> TimeDomainFit:
    """``J = A t^x`` (creep, 2 parameters) or ``(t/t_ref)^−x`` (relaxation shape, 1 parameter), linear least squares
    on the logarithms."""
    t0 = time.process_time()
    lt, ly = np.log(series.time_s), np.log(series.values)
    if series.kind == "creep":
        x, lnA = np.polyfit(lt, ly, 1)
        return _finish(series, "power law A·t^x", False, 2, {"A": math.exp(lnA), "x": float(x)}, (),
                       lambda t: math.exp(lnA) * np.asarray(t) ** x, "linear least squares", t0)
    u = lt - lt[0]  # the shape is 1 at t_ref = time_s[0]: the line passes through the origin
    x = -float(np.dot(u, ly) / np.dot(u, u))
    t_ref = float(series.time_s[0])
    return _finish(series, "power law (t/t_ref)^-x", False, 1, {"x": x}, (),
                   lambda t: (np.asarray(t) / t_ref) ** (-x), "linear least squares", t0)


def _least_squares(residuals, x0, lower, upper):
    import scipy.optimize

    x0 = np.clip(x0, lower + 1e-9 * (upper - lower), upper - 1e-9 * (upper - lower))
    return scipy.optimize.least_squares(residuals, x0, bounds=(lower, upper), method="trf", x_scale="jac",
                                        diff_step=1e-6, max_nfev=MAX_ITERATIONS)


def _safe(fn, size: int):
    """``fn`` with a large residual where the model fails or is not positive (the search steps away)."""
    def res(x):
        try:
            y = fn(x)
        except (ValueError, ArithmeticError, np.linalg.LinAlgError):
            return np.full(size, 10.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.log10(y)
        return np.where(np.isfinite(r), r, 10.0)
    return res


def structural_newtonian_fit(series: TimeSeries) -> TimeDomainFit:
    """The structural-damping law with a Newtonian term, ``G* = G0·Γ(1−x)·s^x + η s``, fitted to creep (3
    parameters): ``J̄(s) = 1/(s·G*(s))`` inverted at each time."""
    from ..timedomain import invert_laplace

    if series.kind != "creep":
        raise ValueError("structural_newtonian_fit: creep data only (a relaxation shape is the power law's)")
    t0 = time.process_time()
    pl = power_law_fit(series)
    x0 = min(max(pl.values["x"], 0.02), 0.98)

    def J(p, t, nodes=FIT_NODES):
        G0, x, eta = math.exp(p[0]), p[1], math.exp(p[2])
        return invert_laplace(lambda s: 1.0 / (s * (G0 * math.gamma(1 - x) * s**x + eta * s)), t, nodes=nodes)

    G0 = 1.0 / (pl.values["A"] * math.gamma(1 + x0) * math.gamma(1 - x0))  # the power law's own modulus
    lower = np.array([math.log(G0) - 12, 0.01, math.log(G0) - 30])
    upper = np.array([math.log(G0) + 12, 0.99, math.log(G0) + 12])
    target = np.log10(series.values)
    res = _safe(lambda q: J(q, series.time_s), target.size)
    r = _least_squares(lambda p: res(p) - target, np.array([math.log(G0), x0, math.log(G0) - 3]), lower, upper)
    p = r.x
    values = {"G0": math.exp(p[0]), "x": float(p[1]), "eta": math.exp(p[2])}
    bound = [n for n, v, a, b in zip(values, p, lower, upper) if min(v - a, b - v) < 1e-3 * (b - a)]
    return _finish(series, "structural damping + Newtonian", False, 3, values, bound,
                   lambda t: J(p, t, nodes=32), r.message, t0)


# ---------------------------------------------------------------------------------------
# a mechanism
# ---------------------------------------------------------------------------------------
def _pseudo_moduli(series: TimeSeries, pl: TimeDomainFit, n: int = 8):
    """The moduli the series' own power law implies exactly, at f = 1/(2πt) over its times (a start, not data)."""
    from ..io.data import RheologyData

    t = np.logspace(math.log10(series.time_s[0]), math.log10(series.time_s[-1]), n)
    w = 1.0 / t
    x = min(max(pl.values["x"], 0.02), 0.98)
    if series.kind == "creep":
        G = (1j * w) ** x / (pl.values["A"] * math.gamma(1 + x))
    else:  # a relaxation modulus t^-x of 1 kPa at 1 s: the scale is arbitrary (a shape does not fix it)
        G = 1e3 * math.gamma(1 - x) * (1j * w) ** x
    return RheologyData(frequency_hz=w / (2 * np.pi), G_storage=G.real, G_loss=G.imag,
                        source=f"{series.name}: the moduli of its power law (a start)")


def laplace_modulus(fitted, s, P_N: float) -> np.ndarray:
    """``G*(s)`` (Pa) of a fitted mechanism at complex ``s`` (1/s) and prestress ``P_N`` (N): the assignments' mean
    of the cell's exact modulus from its laws' ``k*(s)``, plus the cytoplasm's ``sη``."""
    from ..linear.assembly import modulus
    from ..linear.dynamic import dynamic_compliance

    cell = fitted.cell
    z = np.atleast_1d(np.asarray(s, dtype=complex)).ravel()
    K = fitted.mechanism.K if fitted.mechanism.heterogeneous else 1
    G = np.zeros(z.size, complex)
    for k in range(K):
        law = fitted.tendon_law(k)
        G += modulus(dynamic_compliance(cell, P_N, law.laplace_stiffness(cell.lengths, P_N * cell.T0, z)),
                     cell.strut_length)
    return G / K + z * fitted.viscosity


def _time_function(series: TimeSeries, fitted, P_N: float, nodes: int):
    """``t -> J(t)`` (1/Pa) or ``t -> G(t)/G(t_ref)`` of a fitted mechanism."""
    from ..timedomain import invert_laplace

    if series.kind == "creep":
        return lambda t: invert_laplace(lambda s: 1.0 / (s * laplace_modulus(fitted, s, P_N)), t, nodes=nodes)
    eta, t_ref = fitted.viscosity, float(series.time_s[0])

    def shape(t):
        tt = np.concatenate([[t_ref], np.atleast_1d(t)])
        g = invert_laplace(lambda s: laplace_modulus(fitted, s, P_N) / s - eta, tt, nodes=nodes)
        return g[1:] / g[0]
    return shape


def _search(residuals, starts_x, lower, upper):
    """The best of the least-squares runs from each of ``starts_x``."""
    best = None
    for x in starts_x:
        r = _least_squares(residuals, np.clip(x, lower, upper), lower, upper)
        if best is None or r.cost < best.cost:
            best = r
    return best


def mechanism_time_fit(series: TimeSeries, model, *, starts: int = 4, seed: int = 0) -> TimeDomainFit:
    """A mechanism (a name or :class:`~tenscell.fitting.models.mechanism.Mechanism`) fitted to ``series`` in the time
    domain (module docstring): the best of ``starts`` least-squares runs, the first from the mechanism fitted (4 starts,
    2 hops, ``seed``) to the moduli of the series' own power law, the others from the stack's own random starts on
    those moduli."""
    from ..fitting import fit, get_model
    from ..fitting.models.mechanism import FittedMechanism, Mechanism

    spec = get_model(model)
    if not isinstance(spec, Mechanism):
        raise ValueError(f"mechanism_time_fit: {spec.name!r} is not a mechanism")
    t0 = time.process_time()
    start = fit(_pseudo_moduli(series, power_law_fit(series)), model=spec, starts=4, hops=2, seed=seed, progress=False)
    pars = [p for p in start.parameters if p.vary]
    lower, upper = np.log([p.lower for p in pars]), np.log([p.upper for p in pars])
    cell = start.model.cell
    rng = np.random.default_rng(seed)
    # the first start where the stack put the mechanism on the power law's moduli, the others drawn by its own rule
    # (log-uniform in the middle of the bounds, scaled onto those moduli): a relaxation that is not a power law may
    # lie in another basin
    xs = [np.log([p.value for p in pars])] + [start.problem.initial_guess(rng) for _ in range(int(starts) - 1)]

    def build(x):
        vals = {p.name: math.exp(v) for p, v in zip(pars, x)}
        P = vals.pop("P")
        return FittedMechanism(mechanism=spec, cell=cell, values=vals, P=P), P

    def y(x, t, nodes=FIT_NODES):
        fitted, P = build(x)
        return _time_function(series, fitted, P, nodes)(t)

    target = np.log10(series.values)
    res = _safe(lambda x: y(x, series.time_s), target.size)
    r = _search(lambda x: res(x) - target, xs, lower, upper)
    fitted, P = build(r.x)
    values = dict(fitted.values, P=P)
    bound = [p.name for p, v, a, b in zip(pars, r.x, lower, upper) if min(v - a, b - v) < 1e-3 * (b - a)]
    # a shape has no modulus scale: every stiffness-like parameter and P scaled together leave it unchanged, so one
    # combination of the free parameters is not determined (not counted)
    n = len(pars) - (1 if series.kind == "relaxation shape" else 0)
    return _finish(series, spec.name, True, n, values, bound,
                   lambda t: _time_function(series, fitted, P, 32)(t), r.message, t0)

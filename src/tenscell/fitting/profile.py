"""Profile-likelihood intervals: what the data say about a parameter the local analysis cannot bound.

The local analysis (:mod:`~tenscell.fitting.identifiability`) linearizes the fit at its optimum. It says nothing
useful about a parameter at a bound, one whose local standard error exceeds a factor e, or one whose local 95 %
interval runs past a bound: the data may bound it on one side only, or not at all. For such a parameter the
*profile likelihood* holds it at a grid of values over its bounds (log-spaced), refits every other parameter at each
(a warm start from the neighbouring grid point through the one search, :func:`tenscell.fitting.search.run_search`,
with a short budget), and records ``−2 ln L`` of each refit. By Wilks' theorem the values at which ``−2 ln L`` has
risen by at most 1 (3.84) above its minimum form a 68 % (95 %) confidence interval; where the profile stays within
the threshold all the way to a bound, the interval is open on that side ("not bounded above within [lo, hi]").

``−2 ln L`` follows :func:`tenscell.fitting.records.information_criteria`: with standard deviations in every data
set it is χ² plus a constant; otherwise σ is estimated from the residuals (``n·ln(RSS/n)`` plus a constant), so a
rise of 3.84 is an RSS ratio of ``exp(3.84/n)``.

Each crossing of a threshold is refined by bisection in ln of the parameter (``refine`` refits per crossing) and then
interpolated linearly, so an interval does not depend on the starting grid beyond the bisection's resolution.

A mechanism's *held* fields (a law parameter laid out ``"fixed"``: the active springpot's ``beta`` of
``springpot-tension+visc``) are profiled the same way, on the same mechanism with that field freed: the profile says
whether the data accept the held value and which values they reject. Along every profile, the other parameters that
compensate for the held one (``ln θ_j`` moving with ``ln θ``: ``beta·s`` constant while beta runs over its accepted
range) are reported as the combination the data determine (:attr:`ParameterProfile.compensations`).

A profile costs one refit per grid point and per refinement step (:attr:`ProfileSet.refits`); by default only the
parameters that need one are profiled, and only for models with at most :data:`MAX_FREE` free parameters.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._results import dataframe, format_repr
from .identifiability import simple_exponent
from .records import information_criteria

__all__ = ["ProfileInterval", "ParameterProfile", "ProfileSet", "profile_intervals", "profile_parameter",
           "needs_profile", "profile_plan", "LEVELS", "DEFAULT_POINTS", "MAX_FREE", "UNDETERMINED_LN",
           "REFIT_EVALUATIONS"]

#: (confidence level, rise of −2 ln L): χ² with one degree of freedom at 68.27 % and 95 %
LEVELS = ((0.6827, 1.0), (0.95, 3.841458820694124))
#: grid points over a parameter's bounds (log-spaced), before the crossings are refined
DEFAULT_POINTS = 9
#: bisection refits per threshold crossing (each halves the bracket in ln of the parameter)
DEFAULT_REFINE = 3
#: models with more free parameters are not profiled unless parameters are named ("auto" skips them: every grid
#: point is a refit of all the others)
MAX_FREE = 12
#: a local standard error of ln(parameter) above this (a factor e) is no determination: the parameter is profiled
UNDETERMINED_LN = 1.0
#: a local 95 % interval (ln value ± this × standard error) that reaches a bound makes a parameter one-sided
LOCAL_95 = 1.959963984540054
#: basin-hopping moves of each refit beyond its warm start (a short budget: the warm start is close)
REFIT_HOPS = 2
#: model evaluations per least-squares run of a refit
REFIT_NFEV = 60
#: model evaluations one refit takes on average (its warm run, and the move its patience of 1 allows): 17.6–25.5 in
#: the profiles of springpot-alpha-family+visc, springpot-tension+visc, springpot+visc and sls-trap+visc fitted to
#: the bundled pair (2 least-squares runs per refit, far below the ``(REFIT_HOPS + 1) × REFIT_NFEV`` allowed); the
#: command line's estimate of a profile's cost
REFIT_EVALUATIONS = 26
#: another parameter compensates along a profile when |d ln θ_j / d ln θ| is at least this over the accepted region
COMPENSATION_SLOPE = 0.5
#: ... and the combination varies over that region by at most this fraction of the parameter's own range (in ln)
COMPENSATION_SPREAD = 0.25


@dataclass(frozen=True)
class ProfileInterval:
    """A profile-likelihood confidence interval of one parameter.

    Attributes
    ----------
    level : float
        Confidence level (0.6827 or 0.95).
    threshold : float
        The rise of −2 ln L that defines it (1 or 3.84).
    lower, upper : float or None
        The interval's ends (the parameter's unit); None where it is open: the profile stays within the threshold
        down (up) to the bound, so the data do not bound the parameter on that side within the bounds.
    bounds : (float, float)
        The bounds scanned.
    disjoint : bool
        Values outside the interval, separated from it by values the data reject, are also within the threshold
        (a second basin): the confidence set is not one interval.
    """

    level: float
    threshold: float
    lower: float | None
    upper: float | None
    bounds: tuple
    disjoint: bool = False

    @property
    def kind(self) -> str:
        """``"two-sided"``, ``"bounded below"`` (open above), ``"bounded above"`` (open below) or ``"unbounded"``."""
        if self.lower is not None and self.upper is not None:
            return "two-sided"
        if self.lower is not None:
            return "bounded below"
        return "bounded above" if self.upper is not None else "unbounded"

    def text(self, unit: str = "", digits: int = 3) -> str:
        """In words: ``"0.12 – 0.31 N at 95 %"``, ``"bounded below by 300 at 95 %; not bounded above within
        [1e-3, 1e5]"``."""
        u = f" {unit}" if unit else ""
        pct = f"{100 * self.level:.0f} %"
        lo, hi = (f"{x:.{digits}g}" for x in self.bounds)
        if self.kind == "two-sided":
            out = f"{self.lower:.{digits}g} – {self.upper:.{digits}g}{u} at {pct}"
        elif self.kind == "bounded below":
            out = f"bounded below by {self.lower:.{digits}g}{u} at {pct}; not bounded above within [{lo}, {hi}]"
        elif self.kind == "bounded above":
            out = f"bounded above by {self.upper:.{digits}g}{u} at {pct}; not bounded below within [{lo}, {hi}]"
        else:
            out = f"not bounded within [{lo}, {hi}]{u} at {pct}"
        return out + ("; other values beyond it also fit as well (a second basin)" if self.disjoint else "")

    def to_dict(self) -> dict:
        """JSON-ready dict (an open end is null)."""
        return {"level": self.level, "threshold_m2lnL": self.threshold, "lower": self.lower, "upper": self.upper,
                "kind": self.kind, "bounds": list(self.bounds), "disjoint": self.disjoint}


@dataclass(frozen=True)
class Compensation:
    """Another parameter that moves with the profiled one: their product of powers stays put.

    ``θ^1 · θ_j^exponent`` varies over the 95 % region by ``spread_ln`` (ln units) while θ itself spans
    ``range_ln``: the data determine the combination, not θ.
    """

    profiled: str
    other: str
    exponent: float
    value: float
    spread_ln: float
    range_ln: float

    @property
    def words(self) -> str:
        """``"beta·s"``, ``"beta·s^0.62"``: the product (exponents rounded to ±½, ±1, ±2 when within 0.05)."""
        e = self.exponent
        if e == 1.0:
            return f"{self.profiled}·{self.other}"
        if e == -1.0:
            return f"{self.profiled}/{self.other}"
        return f"{self.profiled}·{self.other}^{e:.2g}"

    def text(self) -> str:
        """``"beta·s = 1.91 (within ×/÷1.04 while beta spans a factor 750)"``."""
        return (f"{self.words} = {self.value:.3g} (within ×/÷ {math.exp(self.spread_ln / 2):.3g} while "
                f"{self.profiled} spans a factor {math.exp(self.range_ln):.3g})")

    def to_dict(self) -> dict:
        """JSON-ready dict."""
        return {"profiled": self.profiled, "other": self.other, "exponent": self.exponent, "value": self.value,
                "spread_ln": self.spread_ln, "range_ln": self.range_ln, "words": self.words, "text": self.text()}


@dataclass(frozen=True, eq=False, repr=False)
class ParameterProfile:
    """The profile likelihood of one parameter.

    Attributes
    ----------
    name, unit : str
    reason : str
        Why it was profiled ("at its lower bound", "not determined locally (ln-standard error 1.03)", "held at 1000 by
        the mechanism", "asked for").
    value : float
        Its fitted (or held) value.
    held : bool
        A mechanism's held field (freed here only to be profiled; the fit itself holds it).
    bounds : (float, float)
        The range scanned (its bounds).
    values : ndarray, shape (k,)
        The values it was held at (ascending), the fit's own value among them.
    m2lnL : ndarray, shape (k,)
        −2 ln L of the refit at each value (:func:`~tenscell.fitting.records.information_criteria`).
    rms : ndarray, shape (k,)
        RMS of the log10 errors of each refit (decades).
    others : tuple of str
        The parameters refitted at each value.
    other_values : ndarray, shape (k, len(others))
        Their refitted values (SI units).
    reference : float
        The lowest −2 ln L seen: the fit's own, or a profile point's if a refit found a better fit.
    intervals : tuple of ProfileInterval
        One per level of :data:`LEVELS`.
    compensations : tuple of Compensation
    refits : int
        Refits this profile took.
    cpu_s : float
        Their CPU time (s, this process).
    held_others : tuple of str
        Parameters held at their fitted values beside the profiled one (the strut length L under its gauge).
    geometric_share : ndarray, shape (k,)
        A mechanism's share of ΔG′ carried by the geometric prestress stiffness at each refit
        (:func:`~tenscell.fitting.shares.structure_shares`, first frequency); NaN for other models or where undefined.
    """

    name: str
    unit: str
    reason: str
    value: float
    held: bool
    bounds: tuple
    values: np.ndarray
    m2lnL: np.ndarray
    rms: np.ndarray
    others: tuple
    other_values: np.ndarray
    reference: float
    intervals: tuple
    compensations: tuple
    refits: int
    cpu_s: float
    held_others: tuple = ()
    geometric_share: np.ndarray | None = None

    def accepted(self, level: float = 0.95) -> np.ndarray:
        """Mask of the profile points inside the interval at ``level`` (its connected region around the minimum)."""
        iv = self.interval(level)
        lo = -math.inf if iv.lower is None else iv.lower * (1 - 1e-12)
        hi = math.inf if iv.upper is None else iv.upper * (1 + 1e-12)
        return (self.values >= lo) & (self.values <= hi) & (self.delta <= iv.threshold)

    def share_range(self, level: float = 0.95) -> tuple[float, float] | None:
        """(min, max) of :attr:`geometric_share` over the points the data accept at ``level``; None when not known."""
        if self.geometric_share is None:
            return None
        g = self.geometric_share[self.accepted(level)]
        g = g[np.isfinite(g)]
        return (float(g.min()), float(g.max())) if g.size else None

    @property
    def delta(self) -> np.ndarray:
        """Rise of −2 ln L above :attr:`reference` at each of :attr:`values`."""
        return self.m2lnL - self.reference

    @property
    def improved(self) -> float:
        """How much lower −2 ln L a refit found than the fit at its own value (0: none lower)."""
        own = self.m2lnL[int(np.argmin(np.abs(np.log(self.values / self.value))))]
        return float(max(0.0, own - self.reference))

    def interval(self, level: float = 0.95) -> ProfileInterval:
        """The interval at ``level`` (one of :data:`LEVELS`)."""
        for iv in self.intervals:
            if math.isclose(iv.level, level, abs_tol=1e-3):
                return iv
        raise ValueError(f"level must be one of {', '.join(f'{lv:g}' for lv, _ in LEVELS)}, got {level!r}")

    def __repr__(self) -> str:
        return format_repr(f"ParameterProfile of {self.name} ({self.reason})",
                           *(iv.text(self.unit) for iv in self.intervals),
                           f"{self.values.size} values, {self.refits} refits, {self.cpu_s:.2f} s CPU")

    def to_dict(self) -> dict:
        """JSON-ready dict: the intervals, the compensations and every point of the profile."""
        def fin(x):
            return float(x) if math.isfinite(x) else None

        return {"name": self.name, "unit": self.unit, "reason": self.reason, "value": self.value, "held": self.held,
                "bounds": list(self.bounds), "intervals": [iv.to_dict() for iv in self.intervals],
                "compensations": [c.to_dict() for c in self.compensations], "refits": self.refits,
                "cpu_s": self.cpu_s, "held_others": list(self.held_others),
                "reference_m2lnL": fin(self.reference), "improved_m2lnL": self.improved,
                "geometric_share_range_95": self.share_range(0.95),
                "points": [{"value": float(v), "delta_m2lnL": fin(d), "rms_log10_error": fin(r),
                            "others": {n: float(x) for n, x in zip(self.others, row)},
                            "geometric_share": None if self.geometric_share is None else fin(self.geometric_share[k])}
                           for k, (v, d, r, row) in enumerate(zip(self.values, self.delta, self.rms,
                                                                  self.other_values))]}

    def to_dataframe(self):
        """One row per profile point: the value, Δ(−2 ln L), the RMS and the refitted others (columns with units)."""
        cols = {f"{self.name}_held": self.values, "delta_m2lnL": self.delta, "rms_log10_error": self.rms}
        if self.geometric_share is not None:
            cols["geometric_share_of_dGstorage"] = self.geometric_share
        for j, n in enumerate(self.others):
            cols[f"{n}_refitted"] = self.other_values[:, j]
        return dataframe(cols, {"parameter": self.name, "unit": self.unit, "reason": self.reason})

    def plot(self, ax=None):
        """Δ(−2 ln L) against the held value, with the 68 % and 95 % thresholds. Returns the axes."""
        from .._results import plotter

        return plotter("plot_profile")(self, ax=ax)


@dataclass(frozen=True, eq=False, repr=False)
class ProfileSet:
    """The profiles of a fit: the parameters that needed one, or those asked for.

    Attributes
    ----------
    profiles : tuple of ParameterProfile
    needed : tuple of (str, str)
        ``(name, reason)`` of every parameter that needs a profile (profiled or not).
    not_run : str
        Why nothing was profiled ("" when the profiles ran).
    sigma_known : bool
        −2 ln L from the data's standard deviations (else σ estimated from the residuals).
    n_residuals : int
    """

    profiles: tuple
    needed: tuple
    not_run: str
    sigma_known: bool
    n_residuals: int

    @property
    def refits(self) -> int:
        """Refits over all profiles."""
        return sum(p.refits for p in self.profiles)

    @property
    def cpu_s(self) -> float:
        """CPU time of all profiles (s, this process)."""
        return float(sum(p.cpu_s for p in self.profiles))

    def __getitem__(self, name: str) -> ParameterProfile:
        for p in self.profiles:
            if p.name == name:
                return p
        raise KeyError(f"no profile of {name!r}; profiled: {', '.join(p.name for p in self.profiles) or 'none'}")

    def __len__(self) -> int:
        return len(self.profiles)

    def __iter__(self):
        return iter(self.profiles)

    def convention(self) -> str:
        """How −2 ln L was computed, in words."""
        if self.sigma_known:
            return "−2 ln L from the data's standard deviations (χ²)"
        return (f"σ estimated from the residuals (−2 ln L = n·ln(RSS/n) + const, n = {self.n_residuals}: a rise of "
                f"3.84 is an RSS {math.exp(LEVELS[1][1] / max(self.n_residuals, 1)):.3f} times the best)")

    def __repr__(self) -> str:
        if self.not_run:
            return format_repr("ProfileSet: not run", self.not_run)
        return format_repr(f"ProfileSet: {len(self.profiles)} parameter(s), {self.refits} refits, "
                           f"{self.cpu_s:.1f} s CPU",
                           *(f"{p.name}: {p.interval(0.95).text(p.unit)}" for p in self.profiles))

    def to_dict(self) -> dict:
        """JSON-ready dict (fit.json ``profile``)."""
        return {"convention": self.convention(), "sigma_known": self.sigma_known, "not_run": self.not_run or None,
                "needed": [{"name": n, "reason": r} for n, r in self.needed], "refits": self.refits,
                "cpu_s": self.cpu_s, "levels": [{"level": lv, "threshold_m2lnL": t} for lv, t in LEVELS],
                "profiles": [p.to_dict() for p in self.profiles]}

    def to_dataframe(self):
        """One row per parameter and level: the interval's ends (NaN where open) and kind."""
        rows = [(p.name, p.unit, p.reason, p.value, iv.level, iv.lower, iv.upper, iv.kind, p.refits)
                for p in self.profiles for iv in p.intervals]
        keys = ("parameter", "unit", "reason", "value", "level", "lower", "upper", "kind", "refits")
        cols = {k: [r[i] for r in rows] for i, k in enumerate(keys)}
        cols["lower"] = [math.nan if v is None else v for v in cols["lower"]]
        cols["upper"] = [math.nan if v is None else v for v in cols["upper"]]
        return dataframe(cols, {"convention": self.convention()})


# ---- which parameters need a profile ----------------------------------------------------------------------------
def needs_profile(result) -> tuple[tuple[str, str], ...]:
    """``(name, reason)`` of the parameters the local analysis cannot bound, and of a mechanism's held fields.

    A free parameter needs a profile when it sits at a bound, is not determined (in a combination the data do not
    see, or a local ln-standard error above :data:`UNDETERMINED_LN`), or when its local 95 % interval reaches a bound
    (the data may bound it on one side only). The strut length under its exact gauge never does (the data cannot
    see it: :mod:`~tenscell.fitting.identifiability`).
    """
    ident = result.identifiability()
    pr = result.problem
    out = []
    excluded = dict(ident.excluded)
    for i, p in enumerate(result.parameters):
        if not p.vary:
            continue
        if p.name in excluded:
            if excluded[p.name] != "gauge":
                out.append((p.name, f"at its {excluded[p.name]}"))
            continue
        k = ident.names.index(p.name)
        se = float(ident.standard_errors[k])
        if math.isinf(se):
            out.append((p.name, "not determined (in a combination the data do not see)"))
        elif se > UNDETERMINED_LN:
            out.append((p.name, f"not determined locally (standard error of ln {se:.3g}, beyond a factor e)"))
        elif math.isfinite(se):
            x, lo, hi = math.log(p.value), pr.lower[i], pr.upper[i]
            if x - LOCAL_95 * se < lo:
                out.append((p.name, "its local 95 % interval reaches the lower bound"))
            elif x + LOCAL_95 * se > hi:
                out.append((p.name, "its local 95 % interval reaches the upper bound"))
    for name, value in _held_fields(pr):
        out.append((name, f"held at {value:.4g} by the mechanism (not fitted)"))
    return tuple(out)


def _held_fields(problem) -> list[tuple[str, float]]:
    """The model's held fields: (law parameter, held value) (:meth:`~.models.base.FitModel.held_fields`)."""
    return list(problem.spec.held_fields())


def _not_supported(problem) -> str:
    """Why a problem cannot be profiled here ("" when it can)."""
    if problem.spec.capabilities.per_cell:
        return "a population model (its parameters per cell are profiled by the population analysis)"
    if problem.n_penalties:
        return "the fit has one-sided penalties (activity constraints) that −2 ln L does not include"
    T = problem.coordinate_map()
    if T.shape[0] != T.shape[1] or not np.array_equal(T, np.eye(T.shape[0])):
        return "the fit searches in compact coordinates (max_decades)"
    return ""


# ---- one profile --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Setup:
    """The problem a profile refits in (the fit's own, or a mechanism with a held field freed), and where."""

    problem: Any  # a Problem dataclass (dataclasses.replace gives its variants)
    index: int  # the profiled parameter's position in problem.names
    phi: np.ndarray  # the fit's log-parameters in this problem's layout
    hold: np.ndarray  # mask of parameters held beside the profiled one (L under the gauge)
    sigma_known: bool
    value: float  # the fitted (or held) value, SI units


def _m2lnL(problem, theta, sigma_known: bool) -> tuple[float, float]:
    """(−2 ln L, RMS in decades) of ``problem`` at free log-parameters ``theta``."""
    r = problem.residuals(theta)
    m2 = information_criteria(r, 0, sigma_known=sigma_known, weights=problem.weights)[2]
    return float(m2), float(np.sqrt(np.mean((r / problem.weights) ** 2)))


class _Profiler:
    """Refits at held values, warm-started from the nearest refitted neighbour, cached by value."""

    def __init__(self, setup: _Setup, hops: int, max_nfev: int, bar):
        self.s = setup
        self.hops, self.max_nfev, self.bar = hops, max_nfev, bar
        pr = setup.problem
        self.free = pr.free.copy()
        self.free[setup.index] = False
        self.free &= ~setup.hold
        self.points: dict[float, tuple[float, float, np.ndarray]] = {}  # ln value -> (m2lnL, rms, phi)
        self.refits = 0
        x0 = float(setup.phi[setup.index])
        own = pr.holding(free=self.free, fixed_log=setup.phi.copy())
        m2, rms = _m2lnL(own, setup.phi[self.free], setup.sigma_known)
        self.points[x0] = (m2, rms, setup.phi.copy())
        self.x0 = x0

    def at(self, x: float) -> float:
        """−2 ln L with the parameter held at ln value ``x`` (a refit, unless done before)."""
        if x in self.points:
            return self.points[x][0]
        from .search import run_search

        near = min(self.points, key=lambda y: (abs(y - x), abs(y - self.x0)))
        fixed = self.points[near][2].copy()
        fixed[self.s.index] = x
        pr = self.s.problem.holding(free=self.free, fixed_log=fixed)
        lo, hi = pr.bounds
        theta0 = np.clip(fixed[self.free], lo, hi)
        # tolerance far below any data: the search runs its hops (a short budget) instead of stopping at a target
        chains, _ = run_search(pr, starts=1, seed=0, jobs=1, tolerance=1e-12, hops=self.hops, patience=1,
                               max_nfev=self.max_nfev, initial=theta0, progress=False)
        theta = chains[0].theta
        phi = pr.full(theta)
        m2, rms = _m2lnL(pr, theta, self.s.sigma_known)
        self.points[x] = (m2, rms, phi)
        self.refits += 1
        self.bar.update(1)
        return m2

    def arrays(self):
        xs = np.array(sorted(self.points))
        m2 = np.array([self.points[x][0] for x in xs])
        rms = np.array([self.points[x][1] for x in xs])
        phis = np.array([self.points[x][2] for x in xs])
        return xs, m2, rms, phis


def _scan(prof: _Profiler, lo: float, hi: float, points: int, se: float | None) -> None:
    """Refit at ``points`` log-spaced values over [lo, hi] (ln units), outward from the fit's own value, and where
    the local analysis puts the thresholds (``x0 ± √t·se``, when it gives a standard error ``se`` of ln)."""
    # a grid point within rounding of the fit's own value is that value (no refit where the fit is)
    grid = [prof.x0 if abs(x - prof.x0) <= 1e-9 * max(1.0, abs(x)) else float(x) for x in np.linspace(lo, hi, points)]
    if se is not None and math.isfinite(se) and se > 0:
        grid += [x for _, t in LEVELS for x in (prof.x0 - math.sqrt(t) * se, prof.x0 + math.sqrt(t) * se)
                 if lo < x < hi]
    up = sorted(x for x in grid if x > prof.x0)
    down = sorted((x for x in grid if x < prof.x0), reverse=True)
    for x in up + down:  # each warm-started from its refitted neighbour nearer the fit (continuation)
        prof.at(x)


def _refine(prof: _Profiler, refine: int) -> None:
    """Bisect every threshold crossing of the connected region around the minimum ``refine`` times."""
    for _, t in LEVELS:
        for side in (-1, 1):
            for _ in range(refine):
                xs, m2, _, _ = prof.arrays()
                bracket = _bracket(xs, m2 - m2.min(), t, side)
                if bracket is None:
                    break
                prof.at(0.5 * (xs[bracket[0]] + xs[bracket[1]]))


def _bracket(xs, d, t: float, side: int) -> tuple[int, int] | None:
    """(inside, outside) indices of the crossing of ``t`` on ``side`` of the minimum of ``d``; None if open."""
    k = int(np.argmin(d))
    while 0 <= k + side < xs.size and d[k + side] <= t:
        k += side
    out = k + side
    return None if not 0 <= out < xs.size else (k, out)


def _region(xs, d, t: float) -> tuple[int, int]:
    """First and last index of the connected region of ``d <= t`` around the minimum of ``d``."""
    lo, hi = _bracket(xs, d, t, -1), _bracket(xs, d, t, 1)
    return (0 if lo is None else lo[0]), (xs.size - 1 if hi is None else hi[0])


def _interval(xs, d, level: float, t: float, bounds) -> ProfileInterval:
    """The connected region of ``d <= t`` around the minimum, its ends interpolated linearly in ln value."""
    ends: list[float | None] = []
    for side in (-1, 1):
        b = _bracket(xs, d, t, side)
        if b is None:  # within the threshold up to the bound: open on this side
            ends.append(None)
            continue
        # √Δ is linear in ln θ where the profile is quadratic (the large-sample limit): interpolate it, not Δ
        (xa, ra), (xb, rb) = (xs[b[0]], math.sqrt(max(d[b[0]], 0.0))), (xs[b[1]], math.sqrt(d[b[1]]))
        w = (math.sqrt(t) - ra) / (rb - ra) if rb != ra else 0.5
        ends.append(float(math.exp(xa + w * (xb - xa))))
    first, last = _region(xs, d, t)
    outside = np.r_[d[:first], d[last + 1:]]
    return ProfileInterval(level=level, threshold=t, lower=ends[0], upper=ends[1], bounds=bounds,
                           disjoint=bool(np.any(outside <= t)))


def _compensations(name: str, xs, d, phis, own_x: float, others: list[tuple[int, str]]) -> tuple:
    """Parameters whose ln moves with the profiled one's over its 95 % region (module docstring)."""
    first, last = _region(xs, d, LEVELS[-1][1])
    inside = slice(first, last + 1)
    if last - first < 2:
        return ()
    x = xs[inside]
    span = float(x.max() - x.min())
    if span < math.log(10.0) / 2:  # the data bound the parameter to within half a decade: nothing compensates much
        return ()
    own = int(np.argmin(np.abs(xs - own_x)))  # the combination's value at the fit's own value
    out = []
    for j, other in others:
        y = phis[inside, j]
        slope = float(np.polyfit(x, y, 1)[0])
        if abs(slope) < COMPENSATION_SLOPE:
            continue
        # ln θ + exponent·ln θ_j stays put; a simple exponent (±½, ±1, ±2) when it does as well
        for exponent in dict.fromkeys((simple_exponent(-1.0 / slope), -1.0 / slope)):
            comb = x + exponent * y
            spread = float(comb.max() - comb.min())
            if spread <= COMPENSATION_SPREAD * span:
                break
        else:
            continue
        value = math.exp(float(xs[own] + exponent * phis[own, j]))
        out.append(Compensation(profiled=name, other=other, exponent=exponent, value=value, spread_ln=spread,
                                range_ln=span))
    return tuple(sorted(out, key=lambda c: c.spread_ln))


def _setup(result, name: str) -> _Setup:
    """Where the profile of ``name`` refits: the fit's problem, or its mechanism with the held field ``name`` freed."""
    pr = result.problem
    ident = result.identifiability()
    hold = np.zeros(pr.n_params, dtype=bool)
    if ident.gauge_removed:  # the strut length is an exact gauge: held at its fitted value, as the local analysis does
        hold[pr.n_params - 1] = True
    phi = pr.full(result.theta)
    if name in pr.names:
        i = pr.names.index(name)
        if not pr.free[i]:
            raise ValueError(f"parameter {name!r} is fixed in this fit: there is nothing to profile")
        if hold[i]:
            raise ValueError(f"parameter {name!r} is the strut length, an exact gauge of the moduli: the data do not "
                             "see it at all")
        return _Setup(pr, i, phi, hold, result.sigma_known, result.parameters[i].value)
    held = dict(_held_fields(pr))
    if name not in held:
        raise ValueError(f"no parameter named {name!r} (parameters: {', '.join(pr.names)}"
                         + (f"; held fields: {', '.join(held)}" if held else "") + ")")
    return _freed(result, name, held[name], phi)


def _freed(result, name: str, value: float, phi) -> _Setup:
    """The fit's model with the held field ``name`` laid out as one fitted parameter, held at ``value``."""
    pr = result.problem
    base = result.spec.freed(name).problem(list(result.datasets), pr.cell)
    where = {n: k for k, n in enumerate(pr.names)}
    keep = np.array([n in where for n in base.names])
    src = np.array([where.get(n, 0) for n in base.names])
    lower = np.where(keep, pr.lower[src], base.lower)
    upper = np.where(keep, pr.upper[src], base.upper)
    free = np.where(keep, pr.free[src], False)
    new_phi = np.where(keep, phi[src], math.log(value))
    problem = base.holding(lower=lower, upper=upper, free=free, fixed_log=new_phi.copy())
    return _Setup(problem, base.names.index(name), new_phi, np.zeros(base.n_params, dtype=bool), result.sigma_known,
                  value)


def profile_parameter(result, name: str, *, points: int = DEFAULT_POINTS, refine: int = DEFAULT_REFINE,
                      bounds: tuple | None = None, reason: str | None = None, hops: int = REFIT_HOPS,
                      max_nfev: int = REFIT_NFEV, progress: bool | None = None) -> ParameterProfile:
    """The profile likelihood of one parameter of a fit (module docstring).

    Parameters
    ----------
    result : FitResult
    name : str
        A free parameter of the fit, or a held field of its mechanism (``"beta"``).
    points : int
        Values over the bounds (log-spaced, >= 3), besides the fit's own.
    refine : int
        Bisection refits per threshold crossing (>= 0).
    bounds : (float, float), optional
        The range to scan (the parameter's unit); default its bounds in the fit (a held field: its kind's default).
    reason : str, optional
        Why it is profiled (for the report); default the reason :func:`needs_profile` gives, else "asked for".
    hops, max_nfev : int
        Each refit's budget: basin-hopping moves after its warm start, model evaluations per least-squares run.
    progress : bool or None
        A progress bar over the refits (see :mod:`tenscell._progress`).

    Returns
    -------
    ParameterProfile
    """
    from .._progress import progress_bar
    from .search import count

    points, refine = count("points", points, 3), count("refine", refine, 0)
    setup = _setup(result, name)
    if reason is None:
        reason = dict(needs_profile(result)).get(name, "asked for")
    pr = setup.problem
    lo, hi = float(pr.lower[setup.index]), float(pr.upper[setup.index])
    if bounds is not None:
        blo, bhi = (float(b) for b in bounds)
        if not (0 < blo < bhi and math.isfinite(bhi)):
            raise ValueError(f"bounds: need 0 < lower < upper < inf, got {bounds!r}")
        lo, hi = max(lo, math.log(blo)), min(hi, math.log(bhi))
        if not lo < hi:
            raise ValueError(f"bounds {bounds!r} do not overlap the bounds of {name!r} "
                             f"[{math.exp(pr.lower[setup.index]):.4g}, {math.exp(pr.upper[setup.index]):.4g}]")
    t0 = time.process_time()
    with progress_bar(total=points + 4 + 4 * refine, desc=f"profile {name}", unit="refit", progress=progress) as bar:
        prof = _Profiler(setup, count("hops", hops, 0), count("max_nfev", max_nfev, 1), bar)
        _scan(prof, lo, hi, points, _local_error(result, name))
        _refine(prof, refine)
    xs, m2, rms, phis = prof.arrays()
    reference = float(m2.min())
    d = m2 - reference
    span = (math.exp(lo), math.exp(hi))
    others = [(j, n) for j, n in enumerate(pr.names) if prof.free[j]]
    return ParameterProfile(
        name=name, unit=pr.units[setup.index], reason=reason, value=setup.value,
        held=name not in result.problem.names, bounds=span, values=np.exp(xs), m2lnL=m2, rms=rms,
        others=tuple(n for _, n in others), other_values=np.exp(phis[:, [j for j, _ in others]]), reference=reference,
        intervals=tuple(_interval(xs, d, lv, t, span) for lv, t in LEVELS),
        compensations=_compensations(name, xs, d, phis, prof.x0, others), refits=prof.refits,
        cpu_s=time.process_time() - t0, held_others=tuple(n for j, n in enumerate(pr.names) if setup.hold[j]),
        geometric_share=_shares_along(pr, prof.free, phis))


def _local_error(result, name: str) -> float | None:
    """The local standard error of ln ``name`` (None: not analysed, or not determined)."""
    ident = result.identifiability()
    if name not in ident.names:
        return None
    se = float(ident.standard_errors[ident.names.index(name)])
    return se if math.isfinite(se) else None


def _shares_along(problem, free, phis) -> np.ndarray | None:
    """A mechanism's geometric share of ΔG′ (first frequency) at each profile point; None for other models."""
    from .shares import structure_shares

    if not problem.spec.capabilities.structure_shares:
        return None
    out = np.full(len(phis), np.nan)
    for k, phi in enumerate(phis):
        try:
            sh = structure_shares(problem.holding(free=free, fixed_log=phi), phi[free])
        except ValueError:  # not a stable cell over the whole range at this point: no share
            continue
        out[k] = sh.geometric_share_storage
    return out


def profile_plan(result, parameters="auto", *, max_free: int = MAX_FREE) -> tuple[list, str]:
    """What :func:`profile_intervals` will profile: ``([(name, reason), ...], "")``, or ``([], why not)`` (options as
    there). The command line estimates a profile's cost from it before it starts."""
    pr = result.problem
    needed = needs_profile(result) if not pr.spec.capabilities.per_cell else ()
    why = _not_supported(pr)
    if why:
        return [], f"not computed: {why}"
    if result.identifiability().sigma is None:
        return [], "not computed: as many seen parameter combinations as residuals, so −2 ln L cannot be estimated"
    if isinstance(parameters, str):
        if parameters not in ("auto", "needed"):
            raise ValueError(f"parameters must be 'auto', 'needed' or a list of names, got {parameters!r}")
        if parameters == "auto" and pr.n_free > max_free:
            return [], (f"not computed: {pr.n_free} free parameters, more than {max_free} (each profile point refits "
                        "all the others); name the parameters to profile them")
        return list(needed), ""
    reasons = dict(needed)
    return [(n, reasons.get(n, "asked for")) for n in parameters], ""


def profile_intervals(result, parameters="auto", *, points: int = DEFAULT_POINTS, refine: int = DEFAULT_REFINE,
                      max_free: int = MAX_FREE, hops: int = REFIT_HOPS, max_nfev: int = REFIT_NFEV,
                      progress: bool | None = None, notify=None) -> ProfileSet:
    """Profile-likelihood intervals of a fit's parameters (module docstring).

    Parameters
    ----------
    result : FitResult
    parameters : "auto", "needed" or sequence of str
        ``"auto"``: the parameters that need a profile (:func:`needs_profile`), for a model with at most
        ``max_free`` free parameters (else none, and :attr:`ProfileSet.not_run` says why); ``"needed"``: those
        parameters whatever the model's size; or the names to profile (free parameters or held fields).
    points, refine, hops, max_nfev, progress :
        As for :func:`profile_parameter`.
    max_free : int
        The largest model ``"auto"`` profiles.
    notify : callable, optional
        Called with one line per profile as it starts (the command line's stage lines).

    Returns
    -------
    ProfileSet
    """
    pr = result.problem
    needed = needs_profile(result) if not pr.spec.capabilities.per_cell else ()
    empty = dict(needed=needed, sigma_known=result.sigma_known, n_residuals=pr.n_residuals)
    todo, not_run = profile_plan(result, parameters, max_free=max_free)
    if not_run:
        return ProfileSet(profiles=(), not_run=not_run, **empty)
    out = []
    for k, (name, reason) in enumerate(todo, start=1):
        if notify is not None:
            notify(f"profile {k} of {len(todo)}, {name}: {reason}; {points} values and up to {4 * refine} refinements")
        out.append(profile_parameter(result, name, points=points, refine=refine, reason=reason, hops=hops,
                                     max_nfev=max_nfev, progress=progress))
    return ProfileSet(profiles=tuple(out), not_run="" if out else "nothing to profile: every parameter is bounded by "
                      "the local analysis", **empty)

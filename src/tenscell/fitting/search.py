"""The search: multi-start trust-region least squares with monotonic basin hopping, stopped at its target.

Each start draws tendon stiffnesses log-uniformly over 5–10 decades, places
the damping (a frequency shift) and the overall scale on the data by a grid
and an exact scaling, runs a trust-region least-squares fit
(:func:`scipy.optimize.least_squares`, ``method="trf"``, which accepts more
parameters than residuals), then improves it by monotonic basin hopping: a few
tendon stiffnesses are redrawn and the fit re-polished, keeping improvements.
Redrawing a few stiffnesses moves one relaxation time to another decade, which
is what a power law over many decades needs; it is worth far more than extra
random starts.

The starts advance together in rounds (one least-squares run per start per
round, in worker processes when ``jobs > 1``), and the stopping rules are
checked after each start's step in start order, which makes the result depend
on the seed only, never on ``jobs`` or timing. The search stops when

* the best start meets the polish target (``polish × tolerance`` on every
  data set), or
* the tolerance was met earlier (at some start's step) and the polishing
  since that step has used ``polish_effort`` × the model evaluations it took
  to get there, or
* every start has finished (its hops, or ``patience`` moves without a 5 %
  improvement).

A step that meets the polish target or exhausts the polishing budget ends the
search at once: the starts after it in that round are not run (or, in worker
processes, their steps are dropped). So a fit that reaches its tolerance takes
at most about ``1 + polish_effort`` times as long as the rounds that reached it.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.optimize

from .._checks import positive_scalar
from .._parallel import Workers
from .._progress import progress_bar
from ..model.equilibrium import Cell
from .models.voigt import _LN10, FitProblem, as_datasets, centred_start, make_problem
from .result import FitAlternative, FitResult, accepted, noise_note, noise_rms
from .._threads import limited
from ..io.thinning import DEFAULT_MAX_POINTS, bin_datasets

__all__ = ["fit", "run_search"]


class _Objective:
    """Residuals (data, then penalties) and Jacobian in search coordinates, sharing one evaluation per point."""

    def __init__(self, problem: FitProblem):
        self.problem = problem
        self.T = problem.coordinate_map()
        self.constrained = problem.n_penalties > 0
        self._key = None
        self._out = None
        self.nfev = 0

    def _eval(self, u):
        key = u.tobytes()
        if key != self._key:
            self._out = self.problem._evaluate_constrained(self.problem.full(self.T @ u), jac=True)
            self._key = key
            self.nfev += 1
        return self._out

    def fun(self, u):
        out = self._eval(u)
        r = self.problem._residuals_from(out)
        return np.concatenate([r, self.problem._penalty_from(out, jac=False)[0]]) if self.constrained else r

    def jac(self, u):
        out = self._eval(u)
        J = self.problem._jacobian_from(out)
        if self.constrained:
            J = np.vstack([J, self.problem._penalty_from(out, jac=True)[1]])
        return J @ self.T


@dataclass
class _Chain:
    """The state of one start between rounds (sent to and from worker processes)."""

    start: int
    rng: np.random.Generator
    initial: np.ndarray | None = None  # a given first point (warm start) instead of a drawn one
    theta: np.ndarray | None = None
    cost: float = math.inf
    rms: float = math.inf
    score: float = math.inf  # the worst data set's RMS
    feasible: bool = True  # penalties (if any) within 1 % of their bound
    met_theta: np.ndarray | None = None  # the lowest-cost state that met the tolerance on every data set
    met_cost: float = math.inf
    met_score: float = math.inf
    nfev: int = 0
    last_nfev: int = 0  # evaluations of the latest step
    hops: int = 0
    stale: int = 0
    finished: bool = False
    message: str = ""
    status: int = 0
    history: list = field(default_factory=list)  # [(seconds since the fit began, rms, theta)] at improvements


@dataclass(frozen=True)
class _Settings:
    hops: int
    patience: int
    max_nfev: int
    tolerance: float
    target: float
    t_begin: float


def _clip(lo, hi, u):
    pad = 1e-9 * (hi - lo)
    return np.clip(u, lo + pad, hi - pad)


def _prestress_start(problem: FitProblem, trial, p_ref: float, lp: float) -> None:
    """Place the scalable prestress parameters so that the model prestress is about ``exp(p_ref)·10^lp`` (N)."""
    measured = problem.group_measured[np.isfinite(problem.group_measured)]
    log_pm = math.log(float(np.median(measured))) if measured.size else 0.0
    for i in range(problem.prestress_slice.start, problem.n_params - 1):
        if not problem.free[i]:
            continue
        if problem.kinds[i] == "P":
            trial[i] = p_ref + lp
        elif problem.kinds[i] == "s":
            trial[i] = p_ref + lp - log_pm


def _initial_guess(problem: FitProblem, rng: np.random.Generator) -> np.ndarray:
    """A start (free log-parameters): stiffnesses log-uniform over 5–10 decades, damping and scale placed on the data."""
    phi = problem.fixed_log.copy()
    n_ea, n_c = problem.n_ea, problem.n_c
    spread = rng.uniform(5.0, 10.0) if problem.tendons == "per-tendon" else rng.uniform(0.0, 3.0)
    if problem.compact:
        spread = min(spread, problem._decades)
    u = rng.uniform(-0.5, 0.5, n_ea) * spread * _LN10 if n_ea > 1 else np.zeros(1)
    u = u + math.log(problem.scale_stiffness)
    # families' damping may differ by decades (a joint fit of the bundled data puts them ~4 apart)
    c_jitter = rng.uniform(-2.0, 2.0, n_c) * _LN10 if n_c > 1 else np.zeros(1)
    free = problem.free
    ic = slice(n_ea, n_ea + n_c)
    kinds = np.array(problem.kinds)
    # scaling every EA, c and absolute prestress together by k scales G by k (exact)
    scalable = free & np.isin(kinds, ("EA", "c", "P", "s"))
    best = None
    # damping c shifts the spectrum in frequency; the prestress-to-stiffness ratio sets how much P matters
    c_grid = np.linspace(-6.0, 6.0, 25) * _LN10 if free[n_ea] else [None]
    p_free = bool(np.any(free & np.isin(kinds, ("P", "s"))))
    if problem.prestress_matters:
        # the data vary with prestress (or must respond to it), so P must matter: relative to a typical
        # tendon, not the softest (a negligible P is a flat, prestress-blind trap the solver cannot leave)
        p_ref = float(np.median(u))
        p_grid = np.array([-2.0, -1.0, 0.0, 1.0]) * _LN10 if p_free else [None]
    else:
        p_ref = float(u.min())
        p_grid = np.array([-6.0, -3.0, 0.0]) * _LN10 if p_free else [None]
    for lc in c_grid:
        for lp in p_grid:
            trial = phi.copy()
            trial[:n_ea] = u
            if lc is not None:
                trial[ic] = math.log(problem.scale_damping) + lc + c_jitter
            if lp is not None:
                _prestress_start(problem, trial, p_ref, lp)
            rms = centred_start(problem, problem._evaluate(trial, jac=False), trial, scalable)
            if rms is None:
                continue
            if best is None or rms < best[0]:
                best = (rms, trial)
    if best is None:
        trial = phi.copy()
        trial[:n_ea] = u
        best = (np.inf, trial)
    return best[1][free]


def _perturb(problem: FitProblem, theta, rng: np.random.Generator) -> np.ndarray:
    """A basin-hopping move (free log-parameters): redraw a few stiffnesses, or jitter every parameter of a small model."""
    phi = problem.full(theta)
    free = problem.free
    ea_free = np.flatnonzero(free[: problem.n_ea])
    y = phi.copy()
    if problem.tendons == "per-tendon" and ea_free.size >= 3:
        pick = rng.choice(ea_free, size=3, replace=False)
        lo, hi = float(phi[ea_free].min()), float(phi[ea_free].max())
        if hi - lo < 4 * _LN10:
            mid = 0.5 * (lo + hi)
            lo, hi = mid - 2 * _LN10, mid + 2 * _LN10
        y[pick] = rng.uniform(lo, hi, size=3)
    else:
        move = free.copy()
        # L is a gauge of (P, EA, c) unless one of c, P is held fixed: moving it only wanders
        move[-1] &= not bool(np.all(free[problem.n_ea: -1]))
        y[move] += rng.normal(0.0, 1.0, int(move.sum())) * _LN10
    return y[free]


def _least_squares(problem: FitProblem, theta, max_nfev: int):
    """One trust-region run from ``theta`` (free log-parameters), in the search coordinates."""
    obj = _Objective(problem)
    lo, hi = problem.coordinate_bounds()
    u0 = _clip(lo, hi, problem.to_coordinates(theta))
    res = scipy.optimize.least_squares(
        obj.fun, u0, jac=obj.jac, bounds=(lo, hi), method="trf", x_scale="jac",
        max_nfev=max_nfev, xtol=1e-10, ftol=1e-10, gtol=1e-10,
    )
    return obj.T @ res.x, res, obj.nfev


def _assess(problem: FitProblem, theta) -> tuple[float, float, bool]:
    """(rms over all data, worst data set's rms, penalties within 1 % of their bound)."""
    return problem.rms(theta), float(problem.dataset_rms(theta).max()), problem.feasible(theta)


def _step(problem: FitProblem, chain: _Chain, settings: _Settings, max_nfev: int) -> _Chain:
    """Advance one start by one least-squares run: its first (from an initial guess) or one basin-hopping move."""
    # The matrices are tiny (n ~ 24): BLAS threads only add overhead, and on a
    # shared machine they make each evaluation ~10x slower.
    with limited():  # one place for BLAS threads (tenscell._threads), overridable by the user
        first = chain.theta is None
        # a problem with starts and moves of its own (a fitted mechanism) brings them: the hook by which a new
        # fitted model plugs into this search
        if first:
            guess = getattr(problem, "initial_guess", None) or (lambda rng: _initial_guess(problem, rng))
            x0 = guess(chain.rng) if chain.initial is None else chain.initial
        else:
            move = getattr(problem, "perturb", None) or (lambda th, rng: _perturb(problem, th, rng))
            x0 = move(chain.theta, chain.rng)
        theta, res, nfev = _least_squares(problem, x0, max_nfev)
        chain.nfev += nfev
        chain.last_nfev = nfev
        if not first:
            chain.hops += 1
        if first or res.cost < chain.cost:
            rms, score, feasible = _assess(problem, theta)
            if not first:
                chain.stale = 0 if score < 0.95 * chain.score else chain.stale + 1
            chain.theta, chain.cost, chain.rms, chain.score, chain.feasible = theta, float(res.cost), rms, score, feasible
            chain.message, chain.status = str(res.message), int(res.status)
            chain.history.append((time.monotonic() - settings.t_begin, rms, theta.copy()))
            if score <= settings.tolerance and feasible and chain.cost < chain.met_cost:
                chain.met_theta, chain.met_cost, chain.met_score = theta, chain.cost, score
        else:
            chain.stale += 1
    chain.finished = chain.hops >= settings.hops or chain.stale >= settings.patience or chain.met_score <= settings.target
    return chain


def _best(chains) -> _Chain:
    """The start whose state the fit returns: the lowest cost among states that met the tolerance, else the lowest cost."""
    met = [ch for ch in chains if ch.met_theta is not None]
    return min(met, key=lambda ch: (ch.met_cost, ch.start)) if met else min(chains, key=lambda ch: (ch.cost, ch.start))


def _rounds(problem, chains, settings, jobs, polish_effort, bar):
    """Advance the starts round by round until a stopping rule holds (module docstring); returns the stop reason.

    The rules are checked after each start's step, in start order. The step
    at which the best start first meets the tolerance opens the polishing
    budget: ``polish_effort`` × the evaluations spent up to and including
    that step. Every later step (the rest of that round included) draws on
    it; the step that meets the polish target, or exhausts the budget, ends
    the search at once (the later starts of that round are not run, or their
    steps dropped), so the result depends on the seed alone.
    """
    budget = None  # evaluations left for polishing, once the tolerance is met
    # worker processes kept across rounds, stopped cleanly on Ctrl-C (tenscell._parallel)
    with Workers(min(jobs, len(chains))) as workers:
        while True:
            active = [k for k, ch in enumerate(chains) if not ch.finished]
            if not active:
                return "every start finished"
            cap = settings.max_nfev if budget is None else max(1, min(settings.max_nfev, budget // len(active)))
            # in start order; reading stops at a stopping rule (Workers.imap: in this process, later steps
            # never run; on workers, their results are dropped), so the result depends on the seed alone
            steps = workers.imap(_step, [(problem, chains[k], settings, cap) for k in active])
            for k, ch in zip(active, steps):
                chains[k] = ch
                budget, stop = _polish_rule(chains, ch, budget, settings, polish_effort)
                if stop:
                    bar.update(1)
                    return stop
            bar.update(1)
            best = _best(chains)
            bar.set_postfix(rms=f"{min(best.met_score, best.score):.4g}")


def _polish_rule(chains, ch: _Chain, budget, settings: _Settings, polish_effort: float):
    """After start ``ch``'s step: the polishing budget left (None before the tolerance is met) and a stop reason."""
    best = _best(chains)
    if best.met_score <= settings.target:
        return budget, "met the polish target"
    if budget is not None:
        budget -= ch.last_nfev
        return budget, ("polished as long as reaching the tolerance allowed" if budget <= 0 else "")
    if best.met_theta is None:
        return None, ""
    # the tolerance is met at this step: polishing gets a budget of its own, counted from here, to pin down
    # the weakly determined parameters (a population's prestress was recovered 5x worse without any)
    budget = int(polish_effort * sum(c.nfev for c in chains))
    return budget, ("" if budget > 0 else "met the tolerance (no polishing asked)")


def _merged_history(chains):
    """The starts' improvement records merged into one best-so-far trajectory."""
    events = sorted((t, r_, k, th) for k, ch in enumerate(chains) for (t, r_, th) in ch.history)
    history, history_theta, so_far = [], [], math.inf
    for t, r_, _, th in events:
        if r_ < so_far:
            so_far = r_
            history.append((float(t), float(r_)))
            history_theta.append(th)
    return tuple(history), tuple(history_theta)


def _warm_start(problem: FitProblem, initial):
    """Free log-parameters of a warm start (None for none), checked against the problem's layout."""
    if initial is None:
        return None
    theta = getattr(initial, "theta", initial)
    theta = np.array(theta, dtype=float).ravel()
    if theta.shape != (problem.n_free,) or not np.all(np.isfinite(theta)):
        raise ValueError(f"initial: expected {problem.n_free} finite free log-parameters (a FitResult of the same "
                         f"data and parametrization), got {theta.shape[0]} values")
    lo, hi = problem.bounds
    return np.clip(theta, lo, hi)


def _count(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def fit(data, cell: Cell | None = None, *, tendons: str = "per-tendon", damping: str = "uniform", starts: int = 4,
        seed: int | None = 0, jobs: int = 1, tolerance: float = 0.01, hops: int = 30, patience: int = 6,
        max_nfev: int = 100, polish: float = 0.2, polish_effort: float = 0.5, bounds: dict | None = None,
        fixed: dict | None = None, min_prestress_share: float | None = None, max_decades: float | None = None,
        min_prestress_elasticity: float | None = None, elasticity_frequency_hz: float = 0.1, initial=None,
        max_points: int | None = DEFAULT_MAX_POINTS, progress: bool | None = None) -> FitResult:
    """Fit the tensegrity model's G', G'' to measured data (multi-start, analytic Jacobian).

    Parameters
    ----------
    data : RheologyData or sequence of RheologyData
        A frequency or prestress sweep (see :mod:`tenscell.io.data`), or several
        data sets fitted jointly by one parameter set; a frequency sweep that
        states its prestress (``data.with_prestress(P_Pa)``) is linked to the
        others by one prestress scale (see :mod:`tenscell.fitting.models.voigt`).
    cell : Cell, optional
        Reference cell; default :func:`tenscell.paper_cell` (strut length 1 m).
    tendons : {"per-tendon", "per-family", "uniform"}
        Stiffness parametrization ("uniform" is the homogeneous baseline).
    damping : {"uniform", "per-family"}
    starts, hops, patience, max_nfev : int
        Independent starts (>= 1), basin-hopping moves per start at most, moves
        without a 5 % improvement before a start stops, model evaluations per
        least-squares run.
    seed : int or None
        Seed of the numpy Generator; the same seed gives the same result
        whatever ``jobs`` is. None draws fresh entropy.
    jobs : int
        Worker processes over starts (1 = in this process).
    tolerance : float
        RMS of the log10 errors (decades) every data set must reach to converge.
    polish, polish_effort : float
        The search stops as soon as one start's RMS is ``polish × tolerance``
        (on every data set), or once the evaluations since the tolerance was
        first met reach ``polish_effort`` × those it took to meet it (0 stops
        at the tolerance); see the module docstring.
    bounds, fixed, min_prestress_share, max_decades, min_prestress_elasticity, elasticity_frequency_hz :
        See :func:`tenscell.fitting.make_problem`.
    initial : FitResult or array_like, optional
        A warm start: start 0 begins here (a FitResult of the same data and
        parametrization, or its free log-parameters ``theta``), moved inside
        the bounds (with ``max_decades``, stiffnesses compressed to the bound).
    max_points : int or None
        A moduli data set with more points is fitted binned in log frequency
        per prestress (:func:`tenscell.io.thinning.bin_log_frequency`; the rule
        and counts go into the data's comments and the report), as ``tenscell
        fit --max-points`` does. None fits every point; creep data are never binned.
    progress : bool or None
        A progress bar: None when someone watches (a terminal or a notebook),
        True always, False never (see :mod:`tenscell._progress`).

    Returns
    -------
    FitResult

    Raises
    ------
    ValueError
        Bad options, data or cell (see :func:`make_problem`).
    """
    t_begin = time.monotonic()
    datasets, cell = _prepared(data, cell, max_points)
    problem = make_problem(datasets, cell, tendons=tendons, damping=damping, bounds=bounds, fixed=fixed,
                           min_prestress_share=min_prestress_share, max_decades=max_decades,
                           min_prestress_elasticity=min_prestress_elasticity,
                           elasticity_frequency_hz=elasticity_frequency_hz)
    chains, stop = run_search(problem, starts=starts, seed=seed, jobs=jobs, tolerance=tolerance, hops=hops,
                              patience=patience, max_nfev=max_nfev, polish=polish, polish_effort=polish_effort,
                              initial=initial, progress=progress, desc=f"fit ({tendons})", t_begin=t_begin)
    return _result(problem, datasets, cell, chains, stop, float(tolerance), seed, t_begin)


def run_search(problem, *, starts: int = 4, seed: int | None = 0, jobs: int = 1, tolerance: float = 0.01,
               hops: int = 30, patience: int = 6, max_nfev: int = 100, polish: float = 0.2,
               polish_effort: float = 0.5, initial=None, progress: bool | None = None, desc: str = "fit",
               t_begin: float | None = None):
    """The multi-start search on any problem; returns ``(chains, stop reason)`` (options as for :func:`fit`).

    ``problem`` is a :class:`FitProblem`, or any object with its residual and
    Jacobian interface that brings its own ``initial_guess(rng)`` and
    ``perturb(theta, rng)`` (:class:`tenscell.fitting.models.mechanism_problem.MechanismProblem`).
    ``t_begin`` (``time.monotonic()``) is the moment the history's times count from (default: now).
    """
    t_begin = time.monotonic() if t_begin is None else t_begin
    settings = _settings(hops, patience, max_nfev, tolerance, polish, polish_effort, t_begin)
    chains = _chains(problem, _count("starts", starts, 1), seed, initial)
    with progress_bar(total=settings.hops + 1, desc=desc, unit="round", progress=progress) as bar:
        stop = _rounds(problem, chains, settings, _count("jobs", jobs, 1), float(polish_effort), bar)
    return chains, stop


def _prepared(data, cell, max_points):
    """The data sets (binned beyond ``max_points``) and the reference cell (default the paper's)."""
    from ..model.shapes import paper_cell

    datasets = as_datasets(data)
    if max_points is not None:
        datasets = bin_datasets(datasets, _count("max_points", max_points, 4))
    return datasets, (paper_cell() if cell is None else cell)


def _settings(hops, patience, max_nfev, tolerance, polish, polish_effort, t_begin) -> _Settings:
    """The search's stopping rules, checked (one line naming the option on bad input)."""
    tolerance = positive_scalar("tolerance", tolerance, "decades")
    if not (isinstance(polish_effort, (int, float)) and math.isfinite(polish_effort) and polish_effort >= 0):
        raise ValueError(f"polish_effort must be a finite number >= 0, got {polish_effort!r}")
    return _Settings(hops=_count("hops", hops, 0), patience=_count("patience", patience, 1),
                     max_nfev=_count("max_nfev", max_nfev, 1), tolerance=tolerance,
                     target=positive_scalar("polish", polish) * tolerance, t_begin=t_begin)


def _chains(problem: FitProblem, starts: int, seed, initial) -> list[_Chain]:
    """One chain per start, each with its own random stream spawned from ``seed``; start 0 may be warm."""
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise ValueError(f"seed must be a non-negative integer or None, got {seed!r}")
    rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(starts)]
    chains = [_Chain(start=k, rng=rngs[k]) for k in range(starts)]
    chains[0].initial = _warm_start(problem, initial)
    return chains


def _result(problem, datasets, cell, chains, stop, tolerance, seed, t_begin) -> FitResult:
    best = _best(chains)
    theta = best.theta if best.met_theta is None else best.met_theta
    assert theta is not None  # every chain that ran holds a point
    r = problem.residuals(theta) / problem.weights
    rms = float(np.sqrt(np.mean(r**2)))
    per_set = problem.dataset_rms(theta)
    noise = noise_rms(datasets)
    converged = accepted(per_set, noise, tolerance)
    cutoff = max(tolerance, 1.5 * rms)
    alternatives = tuple(
        FitAlternative(start=ch.start, rms_log10_error=ch.rms, parameters=problem.parameters(ch.theta))
        for ch in sorted(chains, key=lambda ch: (ch.rms, ch.start))
        if ch is not best and ch.rms <= cutoff
    )
    history, history_theta = _merged_history(chains)
    which = "" if len(datasets) == 1 else " on every data set"
    verdict = (f"reached rms {per_set.max():.4g} <= tolerance {tolerance:g}{which}" if per_set.max() <= tolerance
               else f"did not reach the tolerance{which}: rms {per_set.max():.4g} > {tolerance:g}")
    note = noise_note(per_set, noise, tolerance)
    verdict += f"; {note}" if note else ""
    message = (f"{verdict} (best of {len(chains)} start(s), start {best.start} after {best.hops} hop(s); "
               f"search stopped: {stop}; optimizer: {best.message})")
    return FitResult(
        parameters=problem.parameters(theta), residuals=r, rms_log10_error=rms, tolerance=tolerance,
        converged=converged, message=message, datasets=datasets, cell=cell, problem=problem, theta=theta,
        tendons=problem.tendons, damping=problem.damping, starts=len(chains), seed=seed,
        elapsed_s=time.monotonic() - t_begin, n_evaluations=sum(ch.nfev for ch in chains),
        alternatives=alternatives, history=history,
        # a start the search stopped before it ran has no RMS (NaN, null in fit.json), not an infinite one
        start_rms=tuple(ch.rms if ch.theta is not None else math.nan for ch in chains),
        history_theta=history_theta, stop_reason=stop,
    )

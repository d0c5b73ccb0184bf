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
from .._threads import limited
from .problem import Problem

__all__ = ["run_search", "best_chain", "merged_history", "count"]


class _Objective:
    """Residuals (data, then penalties) and Jacobian in search coordinates, sharing one evaluation per point."""

    def __init__(self, problem: Problem):
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


def _least_squares(problem: Problem, theta, max_nfev: int):
    """One trust-region run from ``theta`` (free log-parameters), in the search coordinates."""
    obj = _Objective(problem)
    lo, hi = problem.coordinate_bounds()
    u0 = _clip(lo, hi, problem.to_coordinates(theta))
    res = scipy.optimize.least_squares(
        obj.fun, u0, jac=obj.jac, bounds=(lo, hi), method="trf", x_scale="jac",
        max_nfev=max_nfev, xtol=1e-10, ftol=1e-10, gtol=1e-10,
    )
    return obj.T @ res.x, res, obj.nfev


def _assess(problem: Problem, theta) -> tuple[float, float, bool]:
    """(rms over all data, worst data set's rms, penalties within 1 % of their bound)."""
    return problem.rms(theta), float(problem.dataset_rms(theta).max()), problem.feasible(theta)


def _step(problem: Problem, chain: _Chain, settings: _Settings, max_nfev: int) -> _Chain:
    """Advance one start by one least-squares run: its first (from an initial guess) or one basin-hopping move."""
    # The matrices are tiny (n ~ 24): BLAS threads only add overhead, and on a
    # shared machine they make each evaluation ~10x slower.
    with limited():  # one place for BLAS threads (tenscell._threads), overridable by the user
        first = chain.theta is None
        # every problem brings its own starts and moves (fitting.problem.Problem): the hook by which a model plugs
        # into this search
        if first:
            x0 = problem.initial_guess(chain.rng) if chain.initial is None else chain.initial
        else:
            x0 = problem.perturb(chain.theta, chain.rng)
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


def best_chain(chains) -> _Chain:
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
            best = best_chain(chains)
            bar.set_postfix(rms=f"{min(best.met_score, best.score):.4g}")


def _polish_rule(chains, ch: _Chain, budget, settings: _Settings, polish_effort: float):
    """After start ``ch``'s step: the polishing budget left (None before the tolerance is met) and a stop reason."""
    best = best_chain(chains)
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


def merged_history(chains):
    """The starts' improvement records merged into one best-so-far trajectory."""
    events = sorted((t, r_, k, th) for k, ch in enumerate(chains) for (t, r_, th) in ch.history)
    history, history_theta, so_far = [], [], math.inf
    for t, r_, _, th in events:
        if r_ < so_far:
            so_far = r_
            history.append((float(t), float(r_)))
            history_theta.append(th)
    return tuple(history), tuple(history_theta)


def _warm_start(problem: Problem, initial):
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


def count(name: str, value, minimum: int) -> int:
    """``value`` as an int, checked to be an integer >= ``minimum`` (ValueError naming ``name``)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def run_search(problem, *, starts: int = 4, seed: int | None = 0, jobs: int = 1, tolerance: float = 0.01,
               hops: int = 30, patience: int = 6, max_nfev: int = 100, polish: float = 0.2,
               polish_effort: float = 0.5, initial=None, progress: bool | None = None, desc: str = "fit",
               t_begin: float | None = None):
    """The multi-start search on any problem; returns ``(chains, stop reason)`` (options as for :func:`fit`).

    ``problem`` is a :class:`FitProblem`, or any object with its residual and
    Jacobian interface that brings its own ``initial_guess(rng)`` and
    ``perturb(theta, rng)`` (:class:`tenscell.fitting.models.mechanism.MechanismProblem`).
    ``t_begin`` (``time.monotonic()``) is the moment the history's times count from (default: now).
    """
    t_begin = time.monotonic() if t_begin is None else t_begin
    settings = _settings(hops, patience, max_nfev, tolerance, polish, polish_effort, t_begin)
    chains = _chains(problem, count("starts", starts, 1), seed, initial)
    with progress_bar(total=settings.hops + 1, desc=desc, unit="round", progress=progress) as bar:
        stop = _rounds(problem, chains, settings, count("jobs", jobs, 1), float(polish_effort), bar)
    return chains, stop


def _settings(hops, patience, max_nfev, tolerance, polish, polish_effort, t_begin) -> _Settings:
    """The search's stopping rules, checked (one line naming the option on bad input)."""
    tolerance = positive_scalar("tolerance", tolerance, "decades")
    if not (isinstance(polish_effort, (int, float)) and math.isfinite(polish_effort) and polish_effort >= 0):
        raise ValueError(f"polish_effort must be a finite number >= 0, got {polish_effort!r}")
    return _Settings(hops=count("hops", hops, 0), patience=count("patience", patience, 1),
                     max_nfev=count("max_nfev", max_nfev, 1), tolerance=tolerance,
                     target=positive_scalar("polish", polish) * tolerance, t_begin=t_begin)


def _chains(problem: Problem, starts: int, seed, initial) -> list[_Chain]:
    """One chain per start, each with its own random stream spawned from ``seed``; start 0 may be warm."""
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise ValueError(f"seed must be a non-negative integer or None, got {seed!r}")
    rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(starts)]
    chains = [_Chain(start=k, rng=rngs[k]) for k in range(starts)]
    chains[0].initial = _warm_start(problem, initial)
    return chains

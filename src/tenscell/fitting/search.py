"""The search: multi-start trust-region least squares with monotonic basin hopping, stopped at its answer.

Each start draws tendon stiffnesses log-uniformly over 5–10 decades, places
the damping (a frequency shift) and the overall scale on the data by a grid
and an exact scaling, runs a trust-region least-squares fit
(:func:`scipy.optimize.least_squares`, ``method="trf"``, which accepts more
parameters than residuals), then improves it by monotonic basin hopping: a few
tendon stiffnesses are redrawn and the fit re-polished, keeping improvements.
Redrawing a few stiffnesses moves one relaxation time to another decade, which
is what a power law over many decades needs; it is worth far more than extra
random starts. (Every model's problem brings its own starts and moves: these
are the Voigt cell's; :mod:`fitting.problem`.)

The starts advance together in rounds (one least-squares run per start per
round, in worker processes when ``jobs > 1``), and the stopping rules are
checked after each start's step in start order, which makes the result depend
on the seed only, never on ``jobs`` or timing.

**The tolerance.** Each data set must reach an RMS log10 error of
``tolerance`` (decades), or its own stated noise when that is larger (a data set
with standard-deviation columns: the RMS of its sd,
:func:`~tenscell.fitting.records.noise_rms`): a fit inside the data's noise has
nothing left the data could tell apart, which is also what the result calls
converged (:func:`~tenscell.fitting.records.accepted`).

**The stopping rules.** The search stops when

* the best start meets the polish target (``polish`` × its tolerance on every
  data set), or
* the tolerance was met earlier (at some start's step) and the polishing
  since that step has used ``polish_effort`` × the model evaluations it took
  to get there, or, while the tolerance is not met,
* **two starts agree at a well-conditioned optimum** of a model that is not
  multimodal (its ``capabilities.multimodal`` is False): two starts hold the
  best fit (RMS within 0.1 % of the best, every free log-parameter within 0.05
  of it, i.e. 5 %) and the fit's Jacobian there is well conditioned (the
  parameters not at a bound, scaled to unit columns, have a Gram matrix whose
  Cholesky pivots span at most :data:`WELL_CONDITIONED_SPAN`): an isolated
  optimum that two independent starts fell into is the basin the model has;
  basin hopping is kept for the models that declare several. Or
* **the starts agree** (any model): at least two starts hold the best fit and
  their moves since their last 5 % improvement add up to ``patience``: moves
  from the same optimum by different starts are draws of the same
  neighbourhood, so their failures pool (one start alone must fail
  ``patience`` times, as before); or at least two starts hold it and the moves
  of *every* start since its last 5 % improvement add up to
  :data:`EVERY_START` × ``patience`` (16 at the default 12): a start held in a
  worse basin spends moves too, and those found nothing 5 % better either,
  but they are draws of another neighbourhood, so they count at a higher
  total. Replayed on the steps of searches run without stopping
  (4 starts × 15 rounds, on the bundled pair: springpot-alpha-family+visc
  seeds 0–9, springpot+visc, springpot and maxwell 0–5, voigt-compact+visc
  0–3), this second count ends the searches of springpot-alpha-family+visc,
  springpot+visc and maxwell 14, 21 and 17 % sooner (springpot's and
  voigt-compact+visc's 2–3 %) and ends no search at a worse optimum than the
  first count alone; at 12 (not 16) one of them
  (springpot+visc, seed 0) would be at the edge of losing its optimum
  (``bench/stop_rule_replay.py``), or
* **the plateau**: every start has run, and the best RMS has improved by less
  than 1 % over the last ``patience`` × ``starts`` steps (every start, on
  average, spent a patience of moves without improving the best: the
  tolerance is out of this search's reach), or
* every start has finished (its hops, or ``patience`` moves without a 5 %
  improvement).

Hops rarely find a better basin (about 1 in 100 moves from the best fit, in the
mechanisms' fits to the bundled data), so a search that stops early can miss
one that a longer search would have found by luck: replayed on every step of
the search without these two rules (the mechanisms on the bundled data, 72
fits), they spent 0.64 of its evaluations and ended at its optimum in 69 fits
(``docs/fitting.md``). A larger ``patience`` buys more of them; more ``starts``
often do not (they fall into the same dominant basin, and agree sooner). The
default patience is 12: with 6, four starts of ``springpot+visc`` and
``springpot-alpha-family+visc`` on the bundled pair (seed 0) agreed on a basin at
RMS 0.070 / 0.017 and stopped; with 12 they reach 0.026 / 0.034 and
0.0148 / 0.0100, the optima a search without the early stops finds, for about
twice the evaluations of those fits (1,246 against 628).

A basin-hopping move whose trust-region run comes back to the optimum it left
(every free log-parameter within 0.05 of it and the cost within 0.2 %) ends
there: the rest of the run would only polish the same optimum again, and the
move counts as one that found nothing better.

A step that meets the polish target or exhausts the polishing budget ends the
search at once: the starts after it in that round are not run (or, in worker
processes, their steps are dropped). So a fit that reaches its tolerance takes
at most about ``1 + polish_effort`` times as long as the rounds that reached it.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize

from .._checks import positive_scalar
from .._errors import TenscellError
from .._parallel import Workers
from .._progress import progress_bar
from .._threads import limited
from .problem import Problem

__all__ = ["run_search", "best_chain", "merged_history", "count", "local_fit", "stopped_by_budget", "BUDGET",
           "AGREE_RMS", "AGREE_LOG", "EVERY_START", "PLATEAU_GAIN", "WELL_CONDITIONED_SPAN", "well_conditioned",
           "EVALUATIONS_PER_START_HOP"]

#: two starts hold the same optimum when their RMS agree within this fraction and every free log-parameter within
#: :data:`AGREE_LOG` (the stopping rule of the module docstring)
AGREE_RMS = 1e-3
#: largest difference of a free natural-log parameter between two starts that hold the same optimum (5 %)
AGREE_LOG = 0.05
#: the starts agree also when the moves of every start since its last 5 % improvement add up to this × patience (and
#: two starts hold the best fit; the stopping rule of the module docstring)
EVERY_START = 4 / 3
#: model evaluations a fit takes per start and basin-hopping move allowed (--hops + 1 least-squares runs at most): the
#: median over the built-in mechanisms, and the per-tendon fit's (30 hops at least, polished 4x as long), both counted
#: on the bundled data (bench/calibrate_study_cost.py prints them; 2 cores, load about 9); a structure-free formula's
#: (its 20 main fits in `study mechanisms` on the bundled pair: 2.9 s of CPU at about 1 ms per evaluation, load 4-5).
#: `tenscell fit`'s and the studies' estimates multiply them by a measured model evaluation
EVALUATIONS_PER_START_HOP = {"mechanism": 20.0, "voigt-per-tendon": 34.0, "formula": 3.5}
#: the plateau: the best RMS improved by less than this fraction over ``patience × starts`` steps
PLATEAU_GAIN = 0.01
#: an optimum is well conditioned when the Gram matrix of its Jacobian (the free parameters not at a bound, columns
#: scaled to unit norm) has Cholesky pivots within this span (a lower bound of its condition number: about 10⁴ in
#: the Jacobian's), so that two starts that reach it within :data:`AGREE_LOG` hold one isolated point
WELL_CONDITIONED_SPAN = 1e8


class _Returned(TenscellError):
    """A basin-hopping move's run came back to the optimum it left (raised from the objective, caught by the run
    that made the move: it never leaves the search)."""


class _Objective:
    """Residuals (data, then penalties) and Jacobian in search coordinates, sharing one evaluation per point."""

    def __init__(self, problem: Problem, home=None):
        self.problem = problem
        # (free log-parameters, cost) of the optimum a basin-hopping move left: coming back to it ends the run
        self.home = home
        # a block-sparse Jacobian (Problem.sparse_jacobian) stays sparse: its problems search their own log-parameters
        self.T = None if problem.sparse_jacobian else problem.coordinate_map()
        self.constrained = problem.n_penalties > 0
        self._key = None
        self._out = None
        self.nfev = 0

    def theta(self, u):
        """Free log-parameters of search coordinates ``u``."""
        return u if self.T is None else self.T @ u

    def _eval(self, u):
        key = u.tobytes()
        if key != self._key:
            self._out = self.problem._evaluate_constrained(self.problem.full(self.theta(u)), jac=True)
            self._key = key
            self.nfev += 1
        return self._out

    def fun(self, u):
        out = self._eval(u)
        r = self.problem._residuals_from(out)
        r = np.concatenate([r, self.problem._penalty_from(out, jac=False)[0]]) if self.constrained else r
        if self.home is not None:
            self._check_home(u, r)
        return r

    def _check_home(self, u, r) -> None:
        theta, cost = self.home
        if 0.5 * float(r @ r) <= cost * (1 + AGREE_RMS) ** 2 and \
                float(np.max(np.abs(self.theta(u) - theta), initial=0.0)) <= AGREE_LOG:
            raise _Returned

    def jac(self, u):
        out = self._eval(u)
        J = self.problem._jacobian_from(out)
        if self.constrained:
            J = np.vstack([J, self.problem._penalty_from(out, jac=True)[1]])
        return J if self.T is None else J @ self.T


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
    ratio: float = math.inf  # the worst data set's RMS over its tolerance (met: <= 1)
    feasible: bool = True  # penalties (if any) within 1 % of their bound
    met_theta: np.ndarray | None = None  # the lowest-cost state that met the tolerance on every data set
    met_cost: float = math.inf
    met_score: float = math.inf
    met_ratio: float = math.inf
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
    tolerances: np.ndarray  # per data set: max(tolerance, its stated noise) (decades)
    polish: float  # the polish target, as a fraction of each data set's tolerance
    t_begin: float
    plateau_steps: int  # the plateau rule's window: patience × starts steps
    multimodal: bool = True  # keep hopping after two starts agree at a well-conditioned optimum


def _clip(lo, hi, u):
    pad = 1e-9 * (hi - lo)
    return np.clip(u, lo + pad, hi - pad)


class _Back:
    """The result of a move's run that came back to the optimum it left (what :func:`_step` reads of one)."""

    def __init__(self, cost: float):
        self.cost, self.message, self.status = cost, "came back to the optimum it left", 0


def _least_squares(problem: Problem, theta, max_nfev: int, home=None):
    """One trust-region run from ``theta`` (free log-parameters), in the search coordinates; ``home`` (free
    log-parameters, cost) of the optimum a basin-hopping move left, which ends the run if it comes back."""
    obj = _Objective(problem, home)
    lo, hi = problem.coordinate_bounds()
    u0 = _clip(lo, hi, problem.to_coordinates(theta))
    # a sparse Jacobian: each trust-region step solved iteratively (LSMR), in time linear in its nonzeros; solved
    # to 1e-10 (LSMR's default 1e-6 leaves inexact steps that stop short: 3 of 6 starts of a 4-cell mechanism
    # population ended at RMS 0.003 instead of 0, as the exact dense steps did not)
    sparse = {"tr_solver": "lsmr", "tr_options": {"atol": 1e-10, "btol": 1e-10}} if problem.sparse_jacobian else {}
    try:
        res = scipy.optimize.least_squares(
            obj.fun, u0, jac=obj.jac, bounds=(lo, hi), method="trf", x_scale="jac",
            max_nfev=max_nfev, xtol=1e-10, ftol=1e-10, gtol=1e-10, **sparse,
        )
    except _Returned:
        assert home is not None
        return home[0], _Back(home[1]), obj.nfev
    return obj.theta(res.x), res, obj.nfev


def local_fit(problem: Problem, theta, max_nfev: int):
    """One trust-region run of ``problem`` from free log-parameters ``theta``: ``(theta, scipy result, evaluations)``.

    The search's own step, for a problem's moves that fit a part of it (a population's cells with the shared
    parameters held: :mod:`tenscell.fitting.models.population`).
    """
    return _least_squares(problem, theta, max_nfev)


def _assess(problem: Problem, theta, tolerances, fun) -> tuple[float, float, float, bool]:
    """(rms over all data, worst data set's rms, worst data set's rms over its tolerance, penalties within 1 % of
    their bound), from the residuals ``fun`` of the run that ended at ``theta`` (data, then penalties)."""
    r = np.asarray(fun)[: problem.n_residuals] / problem.weights
    per_set = problem.dataset_rms_of(r)
    rms = float(np.sqrt(np.mean(r**2)))
    return rms, float(per_set.max()), float(np.max(per_set / tolerances)), problem.feasible(theta)


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
        theta, res, nfev = _least_squares(problem, x0, max_nfev, None if first else (chain.theta, chain.cost))
        chain.nfev += nfev
        chain.last_nfev = nfev
        if not first:
            chain.hops += 1
        if first or res.cost < chain.cost:
            rms, score, ratio, feasible = _assess(problem, theta, settings.tolerances, res.fun)
            if not first:
                chain.stale = 0 if score < 0.95 * chain.score else chain.stale + 1
            chain.theta, chain.cost, chain.rms, chain.score, chain.feasible = theta, float(res.cost), rms, score, feasible
            chain.ratio = ratio
            chain.message, chain.status = str(res.message), int(res.status)
            chain.history.append((time.monotonic() - settings.t_begin, rms, theta.copy()))
            if ratio <= 1.0 and feasible and chain.cost < chain.met_cost:
                chain.met_theta, chain.met_cost, chain.met_score, chain.met_ratio = theta, chain.cost, score, ratio
        else:
            chain.stale += 1
    chain.finished = (chain.hops >= settings.hops or chain.stale >= settings.patience
                      or chain.met_ratio <= settings.polish)
    return chain


def well_conditioned(problem: Problem, theta) -> bool:
    """Whether ``theta`` is a well-conditioned point of ``problem``: the Gram matrix of its Jacobian over the free
    parameters not at a bound, columns scaled to unit norm, passes the one criterion of positive definiteness
    (:func:`tenscell.linear.definite.positive_definite_factor`) with its pivots within
    :data:`WELL_CONDITIONED_SPAN`."""
    import scipy.sparse as sp

    from .._errors import NotPositiveDefiniteError
    from ..linear.definite import damping_span, positive_definite_factor

    theta = np.asarray(theta, dtype=float)
    lo, hi = problem.bounds
    pad = 1e-6 * (hi - lo)
    inside = np.flatnonzero((theta > lo + pad) & (theta < hi - pad))
    if inside.size == 0:
        return True  # every parameter at a bound: the bounds determine the point
    # the problem's own Jacobian: block-sparse where the problem's is (a population's)
    J: Any = problem._jacobian_from(problem._evaluate_constrained(problem.full(theta), jac=True))
    J = sp.csc_matrix(J)[:, inside] if sp.issparse(J) else np.asarray(J)[:, inside]
    G: Any = J.T @ J
    G = G.toarray() if sp.issparse(G) else np.asarray(G)
    norms = np.sqrt(np.diagonal(G))
    if not np.all(norms > 0):
        return False  # a parameter that moves no residual
    try:
        L = positive_definite_factor(G / np.outer(norms, norms), what="the Gram matrix of the fit's Jacobian")
    except NotPositiveDefiniteError:
        return False
    return damping_span(L) <= WELL_CONDITIONED_SPAN


def _agrees(ch: _Chain, best: _Chain) -> bool:
    """Start ``ch`` holds the optimum of ``best`` (module docstring)."""
    assert ch.theta is not None and best.theta is not None
    return ch.rms <= best.rms * (1 + AGREE_RMS) and float(np.max(np.abs(ch.theta - best.theta), initial=0.0)) <= AGREE_LOG


def _isolated_rule(problem: Problem, chains, settings: _Settings, judged: dict) -> str:
    """For a model that is not multimodal: the stop reason when two starts agree at a well-conditioned optimum,
    else "" (``judged``: the conditioning of each best point judged so far, by its bytes)."""
    if settings.multimodal:
        return ""
    ran = [ch for ch in chains if ch.theta is not None]
    best = min(ran, key=lambda ch: (ch.cost, ch.start))
    agree = [ch for ch in ran if _agrees(ch, best)]
    if len(agree) < 2:
        return ""
    key = best.theta.tobytes()
    if key not in judged:
        with limited():
            judged[key] = well_conditioned(problem, best.theta)
    if not judged[key]:
        return ""
    return (f"{len(agree)} starts agree on a well-conditioned optimum (rms {best.rms:.4g}); the model is not "
            "multimodal, so no basin hopping")


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
    steps dropped), so the result depends on the seed alone. Until the
    tolerance is met, the starts' agreement and the plateau
    (:func:`_answer_rule`) may end it the same way.
    """
    budget = None  # evaluations left for polishing, once the tolerance is met
    best_rms: list[float] = []  # the best RMS after each step, for the plateau rule
    judged: dict = {}  # the conditioning of the best points met so far
    # worker processes kept across rounds, stopped cleanly on Ctrl-C (tenscell._parallel)
    with Workers(min(jobs, len(chains))) as workers:
        while True:
            active = [k for k, ch in enumerate(chains) if not ch.finished]
            if not active:
                return _finished(chains, settings)
            cap = settings.max_nfev if budget is None else max(1, min(settings.max_nfev, budget // len(active)))
            # in start order; reading stops at a stopping rule (Workers.imap: in this process, later steps
            # never run; on workers, their results are dropped), so the result depends on the seed alone
            steps = workers.imap(_step, [(problem, chains[k], settings, cap) for k in active])
            for k, ch in zip(active, steps):
                chains[k] = ch
                budget, stop = _polish_rule(chains, ch, budget, settings, polish_effort)
                if not stop:
                    stop = _isolated_rule(problem, chains, settings, judged)
                if not stop and budget is None:
                    stop = _answer_rule(chains, settings, best_rms)
                if stop:
                    bar.update(1)
                    return stop
            bar.update(1)
            best = best_chain(chains)
            bar.set_postfix(rms=f"{min(best.met_score, best.score):.4g}")


#: the stop reason's mark of a search that ran out of budget (:func:`stopped_by_budget`)
BUDGET = "the budget"


def _finished(chains, settings: _Settings) -> str:
    """The stop reason when every start has finished: by its patience (an optimum it could not improve) or by its
    hops while still improving (the budget, :data:`BUDGET`)."""
    by_hops = sum(ch.hops >= settings.hops and ch.stale < settings.patience and ch.met_ratio > settings.polish
                  for ch in chains)
    if by_hops:
        return f"every start finished, {by_hops} of {len(chains)} by running all their hops ({BUDGET})"
    return "every start finished: each made its patience of moves without a 5 % gain"


def stopped_by_budget(stop_reason: str) -> bool:
    """Whether a search with this stop reason ran out of its budget rather than stopping at an optimum."""
    return BUDGET in stop_reason


def _answer_rule(chains, settings: _Settings, best_rms: list) -> str:
    """While the tolerance is not met: the stop reason when the starts agree or the best RMS is on a plateau
    (module docstring), else "". ``best_rms`` (the best RMS after each earlier step) is extended by this step's."""
    ran = [ch for ch in chains if ch.theta is not None]
    best = min(ran, key=lambda ch: (ch.cost, ch.start))
    best_rms.append(best.rms)
    assert best.theta is not None
    agree = [ch for ch in ran if _agrees(ch, best)]
    moves = sum(ch.stale for ch in agree)
    every = sum(ch.stale for ch in ran)
    if len(agree) >= min(2, len(chains)) and moves >= settings.patience:
        return (f"{len(agree)} starts agree on the best fit (rms {best.rms:.4g}) and {moves} moves from it found "
                f"nothing 5 % better")
    if len(agree) >= min(2, len(chains)) and every >= EVERY_START * settings.patience:
        return (f"{len(agree)} starts agree on the best fit (rms {best.rms:.4g}) and {every} moves of all "
                f"{len(ran)} starts found nothing 5 % better")
    window = settings.plateau_steps
    if len(ran) == len(chains) and len(best_rms) > window and best_rms[-1] >= (1 - PLATEAU_GAIN) * best_rms[-1 - window]:
        return (f"plateau: the best rms ({best.rms:.4g}) improved by less than {PLATEAU_GAIN:.0%} over the last "
                f"{window} steps; the tolerance is out of this search's reach")
    return ""


def _polish_rule(chains, ch: _Chain, budget, settings: _Settings, polish_effort: float):
    """After start ``ch``'s step: the polishing budget left (None before the tolerance is met) and a stop reason."""
    best = best_chain(chains)
    if best.met_ratio <= settings.polish:
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
    theta = np.array(initial, dtype=float).ravel()
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
               hops: int = 30, patience: int = 12, max_nfev: int = 100, polish: float = 0.2,
               polish_effort: float = 0.5, initial=None, progress: bool | None = None, desc: str = "fit",
               t_begin: float | None = None, noise=None, multimodal: bool | None = None):
    """The multi-start search on any problem; returns ``(chains, stop reason)`` (options as for :func:`fit`).

    ``problem`` is a :class:`~tenscell.fitting.problem.Problem`: it brings its own ``initial_guess(rng)`` and
    ``perturb(theta, rng)``. ``noise`` (per data set: the RMS of its stated sd in decades, or None;
    :func:`~tenscell.fitting.records.noise_rms`) raises a data set's tolerance to its noise (module docstring).
    ``t_begin`` (``time.monotonic()``) is the moment the history's times count from (default: now).
    ``multimodal``: whether the search keeps hopping after two starts agree at a well-conditioned optimum (default:
    the model's ``capabilities.multimodal``).
    """
    t_begin = time.monotonic() if t_begin is None else t_begin
    starts = count("starts", starts, 1)
    settings = _settings(hops, patience, max_nfev, tolerance, polish, polish_effort, t_begin,
                         _tolerances(tolerance, noise, problem.n_datasets), starts,
                         problem.spec.capabilities.multimodal if multimodal is None else bool(multimodal))
    chains = _chains(problem, starts, seed, initial)
    with progress_bar(total=settings.hops + 1, desc=desc, unit="round", progress=progress) as bar:
        stop = _rounds(problem, chains, settings, count("jobs", jobs, 1), float(polish_effort), bar)
    return chains, stop


def _tolerances(tolerance, noise, n_datasets: int) -> np.ndarray:
    """Per data set, the RMS (decades) the search asks of it: ``tolerance``, or its stated noise if larger."""
    tolerance = positive_scalar("tolerance", tolerance, "decades")
    noise = [None] * n_datasets if noise is None else list(noise)
    if len(noise) != n_datasets:
        raise ValueError(f"noise: one entry per data set ({n_datasets}), got {len(noise)}")
    return np.array([tolerance if n is None else max(tolerance, float(n)) for n in noise])


def _settings(hops, patience, max_nfev, tolerance, polish, polish_effort, t_begin, tolerances,
              starts: int, multimodal: bool = True) -> _Settings:
    """The search's stopping rules, checked (one line naming the option on bad input)."""
    positive_scalar("tolerance", tolerance, "decades")
    if not (isinstance(polish_effort, (int, float)) and math.isfinite(polish_effort) and polish_effort >= 0):
        raise ValueError(f"polish_effort must be a finite number >= 0, got {polish_effort!r}")
    patience = count("patience", patience, 1)
    return _Settings(hops=count("hops", hops, 0), patience=patience, max_nfev=count("max_nfev", max_nfev, 1),
                     tolerances=tolerances, polish=positive_scalar("polish", polish), t_begin=t_begin,
                     plateau_steps=patience * starts, multimodal=multimodal)


def _chains(problem: Problem, starts: int, seed, initial) -> list[_Chain]:
    """One chain per start, each with its own random stream spawned from ``seed``; start 0 may be warm."""
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise ValueError(f"seed must be a non-negative integer or None, got {seed!r}")
    rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(starts)]
    chains = [_Chain(start=k, rng=rngs[k]) for k in range(starts)]
    chains[0].initial = _warm_start(problem, initial)
    return chains

from .._deprecated import moved_away  # noqa: E402

__getattr__ = moved_away(__name__)  # the public names of 0.2.0 that moved away: a DeprecationWarning names their home

"""The search: multi-start trust-region least squares with monotonic basin hopping.

Each start draws tendon stiffnesses log-uniformly over 5–10 decades, places
the damping (a frequency shift) and the overall scale on the data by a grid
and an exact scaling, runs a trust-region least-squares fit
(:func:`scipy.optimize.least_squares`, ``method="trf"``, which accepts more
parameters than residuals), then improves it by monotonic basin hopping: a few
tendon stiffnesses are redrawn and the fit re-polished, keeping improvements.
Redrawing a few stiffnesses moves one relaxation time to another decade, which
is what a power law over many decades needs; it is worth far more than extra
random starts.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import scipy.optimize
from threadpoolctl import threadpool_limits

from .._checks import positive_scalar
from .._parallel import starmap
from .._progress import progress_bar
from ..io.data import RheologyData
from ..model.equilibrium import Cell
from .problem import _LN10, _PENALTY, FitProblem, make_problem
from .result import FitAlternative, FitResult

__all__ = ["fit"]

class _Objective:
    """Residuals and Jacobian sharing one model evaluation per parameter vector."""

    def __init__(self, problem: FitProblem):
        self.problem = problem
        self._key = None
        self._out = None
        self.nfev = 0

    def _eval(self, theta):
        key = theta.tobytes()
        if key != self._key:
            self._out = self.problem._evaluate(self.problem.full(theta), jac=True)
            self._key = key
            self.nfev += 1
        return self._out

    def fun(self, theta):
        return self.problem._residuals_from(self._eval(theta))

    def jac(self, theta):
        return self.problem._jacobian_from(self._eval(theta))


# ---------------------------------------------------------------------------------
# the search
# ---------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class _Chain:
    start: int
    theta: np.ndarray
    rms: float
    cost: float
    nfev: int
    hops: int
    message: str
    status: int
    history: tuple  # ((seconds since the fit began, rms, theta), ...) at each improvement


def _clip(problem: FitProblem, theta):
    lo, hi = problem.bounds
    pad = 1e-9 * (hi - lo)
    return np.clip(theta, lo + pad, hi - pad)


def _initial_guess(problem: FitProblem, rng: np.random.Generator) -> np.ndarray:
    """A start: stiffnesses log-uniform over 5–10 decades, damping and scale placed on the data."""
    phi = problem.fixed_log.copy()
    n_ea, n_c = problem.n_ea, problem.n_c
    spread = rng.uniform(5.0, 10.0) if problem.tendons == "per-tendon" else rng.uniform(0.0, 3.0)
    u = rng.uniform(-0.5, 0.5, n_ea) * spread * _LN10 if n_ea > 1 else np.zeros(1)
    u = u + math.log(problem.scale_stiffness)
    c_jitter = rng.normal(0.0, 0.3, n_c) if n_c > 1 else np.zeros(1)
    free = problem.free
    ic = slice(n_ea, n_ea + n_c)
    base_p = math.log(problem.scale_prestress / problem.scale_stiffness)
    best = None
    # damping c shifts the spectrum in frequency; the prestress-to-stiffness ratio sets how much P matters
    c_grid = np.linspace(-6.0, 6.0, 25) * _LN10 if free[n_ea] else [None]
    if problem.kind == "prestress":
        # the data vary with prestress, so P must matter: relative to a typical tendon, not the
        # softest (a negligible P is a flat, prestress-blind trap the solver cannot leave)
        p_ref = float(np.median(u))
        p_grid = np.array([-2.0, -1.0, 0.0, 1.0]) * _LN10 if free[-2] else [None]
    else:
        p_ref = float(u.min())
        p_grid = np.array([-6.0, -3.0, 0.0]) * _LN10 if free[-2] else [None]
    for lc in c_grid:
        for lp in p_grid:
            trial = phi.copy()
            trial[:n_ea] = u
            if lc is not None:
                trial[ic] = math.log(problem.scale_damping) + lc + c_jitter
            if lp is not None:
                trial[-2] = p_ref + lp + base_p
            out = problem._evaluate(trial, jac=False)
            r = problem._residuals_from(out) / problem.weights
            if out is None or np.any(np.abs(r) >= _PENALTY):
                continue
            # scaling every free EA, c and P together by k scales G by k (exact): take the best k
            shift = -float(np.mean(r)) * _LN10
            scalable = np.zeros(problem.n_params, dtype=bool)
            scalable[:-1] = free[:-1]
            trial[scalable] += shift
            rms = float(np.sqrt(np.mean((r - np.mean(r)) ** 2)))
            if best is None or rms < best[0]:
                best = (rms, trial)
    if best is None:
        trial = phi.copy()
        trial[:n_ea] = u
        best = (np.inf, trial)
    return _clip(problem, best[1][free])


def _perturb(problem: FitProblem, theta, rng: np.random.Generator) -> np.ndarray:
    """A basin-hopping move: redraw a few stiffnesses (or jitter every parameter of a small model)."""
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
    return _clip(problem, y[free])


def _least_squares(problem: FitProblem, theta, max_nfev: int):
    obj = _Objective(problem)
    lo, hi = problem.bounds
    res = scipy.optimize.least_squares(
        obj.fun, theta, jac=obj.jac, bounds=(lo, hi), method="trf", x_scale="jac",
        max_nfev=max_nfev, xtol=1e-10, ftol=1e-10, gtol=1e-10,
    )
    return res, obj.nfev


def _run_chain(problem: FitProblem, start: int, seed_seq, hops: int, patience: int, max_nfev: int,
               t_begin: float, target: float) -> _Chain:
    """One start: initial guess, least squares, then monotonic basin hopping."""
    # The matrices are tiny (n ~ 24): BLAS threads only add overhead, and on a
    # shared machine they make each evaluation ~10x slower.
    with threadpool_limits(limits=1, user_api="blas"):
        return _hop(problem, start, seed_seq, hops, patience, max_nfev, t_begin, target)


def _hop(problem: FitProblem, start: int, seed_seq, hops: int, patience: int, max_nfev: int,
         t_begin: float, target: float) -> _Chain:
    rng = np.random.default_rng(seed_seq)
    theta = _initial_guess(problem, rng)
    res, nfev = _least_squares(problem, theta, max_nfev)
    best, rms = res, problem.rms(res.x)
    history = [(time.monotonic() - t_begin, rms, res.x.copy())]
    stale = done = 0
    while done < hops and rms > target and stale < patience:
        done += 1
        trial, n = _least_squares(problem, _perturb(problem, best.x, rng), max_nfev)
        nfev += n
        if trial.cost < best.cost:
            r = problem.rms(trial.x)
            stale = 0 if r < 0.95 * rms else stale + 1
            best, rms = trial, r
            history.append((time.monotonic() - t_begin, rms, best.x.copy()))
        else:
            stale += 1
    return _Chain(start=start, theta=best.x, rms=rms, cost=float(best.cost), nfev=nfev, hops=done,
                  message=str(best.message), status=int(best.status), history=tuple(history))


# ---------------------------------------------------------------------------------
# the driver
# ---------------------------------------------------------------------------------
def fit(
    data: RheologyData,
    cell: Cell | None = None,
    *,
    tendons: str = "per-tendon",
    damping: str = "uniform",
    starts: int = 4,
    seed: int | None = 0,
    jobs: int = 1,
    tolerance: float = 0.01,
    hops: int = 30,
    patience: int = 6,
    max_nfev: int = 300,
    polish: float = 0.2,
    bounds: dict | None = None,
    fixed: dict | None = None,
    progress: bool | None = None,
) -> FitResult:
    """Fit the tensegrity model's G', G'' to measured data (multi-start, analytic Jacobian).

    Parameters
    ----------
    data : RheologyData
        Frequency or prestress sweep (see :mod:`tenscell.io.data`).
    cell : Cell, optional
        Reference cell; default :func:`tenscell.paper_cell` (strut length 1 m).
    tendons : {"per-tendon", "per-family", "uniform"}
        Stiffness parametrization ("uniform" is the homogeneous baseline).
    damping : {"uniform", "per-family"}
    starts : int
        Independent starts (each followed by basin hopping). >= 1.
    seed : int or None
        Seed of the numpy Generator; the same seed gives the same result
        whatever ``jobs`` is. None draws fresh entropy.
    jobs : int
        Worker processes over starts (1 = in this process).
    tolerance : float
        RMS of the log10 errors (decades) the fit must reach to count as converged.
    hops : int
        Basin-hopping moves per start, at most.
    patience : int
        Stop a start after this many moves without a 5 % improvement of its RMS.
    max_nfev : int
        Model evaluations per least-squares run.
    polish : float
        A start stops early once its RMS is ``polish × tolerance`` (keeps going
        past the tolerance so that the fit is well inside it, not on its edge).
    bounds, fixed : dict, optional
        See :func:`make_problem`.
    progress : bool or None
        A progress bar: None shows one when someone watches (a terminal or a
        notebook), True always, False never (see :mod:`tenscell._progress`).

    Returns
    -------
    FitResult

    Raises
    ------
    ValueError
        Bad options, data or cell (see :func:`make_problem`).
    """
    from ..model.shapes import paper_cell

    t_begin = time.monotonic()
    cell = paper_cell() if cell is None else cell
    problem = make_problem(data, cell, tendons=tendons, damping=damping, bounds=bounds, fixed=fixed)
    starts = _count("starts", starts, 1)
    jobs = _count("jobs", jobs, 1)
    hops = _count("hops", hops, 0)
    patience = _count("patience", patience, 1)
    max_nfev = _count("max_nfev", max_nfev, 1)
    tolerance = positive_scalar("tolerance", tolerance, "decades")
    polish = positive_scalar("polish", polish)
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise ValueError(f"seed must be a non-negative integer or None, got {seed!r}")
    seq = np.random.SeedSequence(seed)
    children = seq.spawn(starts)
    target = polish * tolerance
    args = [(problem, k, children[k], hops, patience, max_nfev, t_begin, target) for k in range(starts)]

    bar = progress_bar(total=starts, desc=f"fit ({tendons})", unit="start", progress=progress)
    try:
        # worker processes that stop cleanly on Ctrl-C and die with this process (tenscell._parallel)
        chains: list[_Chain] = starmap(_run_chain, args, jobs=jobs, on_done=lambda i, ch: bar.update(1))
    finally:
        bar.close()

    chains.sort(key=lambda ch: ch.start)
    best = min(chains, key=lambda ch: (ch.cost, ch.start))
    theta = best.theta
    r = problem.residuals(theta) / problem.weights
    rms = float(np.sqrt(np.mean(r**2)))
    converged = bool(rms <= tolerance)
    cutoff = max(tolerance, 1.5 * rms)
    alternatives = tuple(
        FitAlternative(start=ch.start, rms_log10_error=ch.rms, parameters=problem.parameters(ch.theta))
        for ch in sorted(chains, key=lambda ch: (ch.rms, ch.start))
        if ch is not best and ch.rms <= cutoff
    )
    # merge the starts' improvement records into one best-so-far trajectory
    events = sorted((t, r_, th) for ch in chains for (t, r_, th) in ch.history)
    history, history_theta, so_far = [], [], math.inf
    for t, r_, th in events:
        if r_ < so_far:
            so_far = r_
            history.append((float(t), float(r_)))
            history_theta.append(th)
    verdict = (f"reached rms {rms:.4g} <= tolerance {tolerance:g}" if converged
               else f"did not reach the tolerance: best rms {rms:.4g} > {tolerance:g}")
    message = (f"{verdict} (best of {starts} start(s), start {best.start} after {best.hops} hop(s); "
               f"optimizer: {best.message})")
    return FitResult(
        parameters=problem.parameters(theta), residuals=r, rms_log10_error=rms, tolerance=tolerance,
        converged=converged, message=message, data=data, cell=cell, problem=problem, theta=theta,
        tendons=tendons, damping=damping, starts=starts, seed=seed, elapsed_s=time.monotonic() - t_begin,
        n_evaluations=sum(ch.nfev for ch in chains), alternatives=alternatives,
        start_rms=tuple(ch.rms for ch in chains), history=tuple(history), history_theta=tuple(history_theta),
    )


def _count(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)

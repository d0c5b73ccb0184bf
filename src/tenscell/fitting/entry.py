"""``tenscell.fitting.fit``: any model, through one search, to one result type."""
from __future__ import annotations

import math
import time

import numpy as np

from .._checks import positive_scalar
from ..io.thinning import DEFAULT_MAX_POINTS, bin_datasets
from .models import get_model
from .models.voigt import VoigtModel
from .parameters import as_datasets
from .records import FitAlternative, accepted, noise_note, noise_rms
from .result import AS_WELL, FitResult
from .search import best_chain, count, merged_history, run_search

__all__ = ["fit", "VOIGT_OPTIONS", "prepare", "build_result"]

#: the options that describe the Voigt cell (VoigtModel's fields): refused with another model
VOIGT_OPTIONS = {"tendons": "per-tendon", "damping": "uniform", "min_prestress_share": None, "max_decades": None,
                 "min_prestress_elasticity": None, "elasticity_frequency_hz": 0.1}


def fit(data, cell=None, *, model=None, tendons: str = "per-tendon", damping: str = "uniform", starts: int = 4,
        seed: int | None = 0, jobs: int = 1, tolerance: float = 0.01, hops: int = 30, patience: int = 12,
        max_nfev: int = 100, polish: float = 0.2, polish_effort: float = 0.5, bounds: dict | None = None,
        fixed: dict | None = None, min_prestress_share: float | None = None, max_decades: float | None = None,
        min_prestress_elasticity: float | None = None, elasticity_frequency_hz: float = 0.1, initial=None,
        max_points: int | None = DEFAULT_MAX_POINTS, progress: bool | None = None) -> FitResult:
    """Fit a model's G', G'' (or creep compliance) to measured data (multi-start, analytic Jacobian).

    Every model goes through the same search and returns the same :class:`FitResult`: the paper's
    per-tendon Voigt cell (the default), any registered model by name (:func:`tenscell.fitting.models.get_model`:
    mechanisms, structure-free formulas) or a :class:`~tenscell.fitting.models.base.FitModel` of your own.

    Parameters
    ----------
    data : RheologyData or sequence of RheologyData
        A frequency or prestress sweep (see :mod:`tenscell.io.data`), or several
        data sets fitted jointly by one parameter set; a frequency sweep that
        states its prestress (``data.with_prestress(P_Pa)``) is linked to the
        others by one prestress scale (see :mod:`tenscell.fitting.models.voigt`).
    cell : Cell, optional
        Reference cell; default :func:`tenscell.paper_cell` (strut length 1 m). A structure-free formula has none.
    model : str or FitModel, optional
        What to fit (default: the Voigt cell laid out by ``tendons``, ``damping`` and the activity constraints).
        ``tendons``, ``damping``, ``min_prestress_share``, ``max_decades``, ``min_prestress_elasticity`` and
        ``elasticity_frequency_hz`` describe the Voigt cell and are refused with another model.
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
        RMS of the log10 errors (decades) every data set must reach to converge; a data set with standard
        deviations is asked for no less than its own noise (the RMS of its sd, :func:`~.records.noise_rms`).
    polish, polish_effort : float
        The search stops as soon as one start's RMS is ``polish × tolerance``
        (on every data set), or once the evaluations since the tolerance was
        first met reach ``polish_effort`` × those it took to meet it (0 stops
        at the tolerance). Before the tolerance is met it stops when the starts
        agree on the best fit or the best RMS is on a plateau
        (:mod:`tenscell.fitting.search`; the result's ``stop_reason`` says which).
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
    voigt = dict(tendons=tendons, damping=damping, min_prestress_share=min_prestress_share, max_decades=max_decades,
                 min_prestress_elasticity=min_prestress_elasticity, elasticity_frequency_hz=elasticity_frequency_hz)
    spec = _spec(model, voigt)
    datasets, cell = prepare(data, cell, max_points, spec)
    problem = spec.problem(datasets, cell, bounds=bounds, fixed=fixed)
    positive_scalar("tolerance", tolerance, "decades")
    chains, stop = run_search(problem, starts=starts, seed=seed, jobs=jobs, tolerance=tolerance, hops=hops,
                              patience=patience, max_nfev=max_nfev, polish=polish, polish_effort=polish_effort,
                              initial=initial, progress=progress, desc=f"fit ({spec.name})", t_begin=t_begin,
                              noise=noise_rms(datasets))
    return build_result(problem, datasets, chains, stop, float(tolerance), seed, t_begin)


def _spec(model, voigt: dict):
    """The FitModel to fit: ``model`` (a name or a FitModel), or the Voigt cell of the Voigt options."""
    if model is None:
        return VoigtModel(**voigt)
    spec = get_model(model)
    given = [k for k, default in VOIGT_OPTIONS.items() if voigt[k] != default]
    if given and not isinstance(spec, VoigtModel):
        raise ValueError(f"{', '.join(given)}: option(s) of the Voigt cell, not of model={spec.name!r}")
    return spec


def prepare(data, cell, max_points, spec=None):
    """The data sets (binned beyond ``max_points``) and the reference cell (default the paper's; None for a
    structure-free formula)."""
    from ..model.shapes import paper_cell

    datasets = as_datasets(data)
    if max_points is not None:
        datasets = bin_datasets(datasets, count("max_points", max_points, 4))
    if spec is not None and not spec.structural:
        if cell is not None:
            raise ValueError(f"cell: model {spec.name!r} is a structure-free formula: it has no cell")
        return datasets, None
    return datasets, (paper_cell() if cell is None else cell)


def build_result(problem, datasets, chains, stop: str, tolerance: float, seed, t_begin: float) -> FitResult:
    """The :class:`FitResult` of a finished search (:func:`tenscell.fitting.search.run_search`'s chains)."""
    best = best_chain(chains)
    theta = best.theta if best.met_theta is None else best.met_theta
    assert theta is not None  # every chain that ran holds a point
    r = problem.residuals(theta) / problem.weights
    rms = float(np.sqrt(np.mean(r**2)))
    per_set = problem.dataset_rms(theta)
    noise = noise_rms(datasets)
    cutoff = max(tolerance, AS_WELL * rms)
    alternatives = tuple(
        FitAlternative(start=ch.start, rms_log10_error=ch.rms, parameters=problem.parameters(ch.theta))
        for ch in sorted(chains, key=lambda ch: (ch.rms, ch.start))
        if ch is not best and ch.theta is not None and ch.rms <= cutoff
    )
    history, history_theta = merged_history(chains)
    which = "" if len(datasets) == 1 else " on every data set"
    verdict = (f"reached rms {per_set.max():.4g} <= tolerance {tolerance:g}{which}" if per_set.max() <= tolerance
               else f"did not reach the tolerance{which}: rms {per_set.max():.4g} > {tolerance:g}")
    note = noise_note(per_set, noise, tolerance)
    verdict += f"; {note}" if note else ""
    message = (f"{verdict} (best of {len(chains)} start(s), start {best.start} after {best.hops} hop(s); "
               f"search stopped: {stop}; optimizer: {best.message})")
    return FitResult(
        parameters=problem.parameters(theta), residuals=r, rms_log10_error=rms, tolerance=tolerance,
        converged=accepted(per_set, noise, tolerance), message=message, datasets=tuple(datasets), problem=problem,
        theta=theta, starts=len(chains), seed=seed, elapsed_s=time.monotonic() - t_begin,
        n_evaluations=sum(ch.nfev for ch in chains), alternatives=alternatives, history=history,
        # a start the search stopped before it ran has no RMS (NaN, null in fit.json), not an infinite one
        start_rms=tuple(ch.rms if ch.theta is not None else math.nan for ch in chains),
        history_theta=history_theta, stop_reason=stop,
    )

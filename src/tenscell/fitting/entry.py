"""``tenscell.fitting.fit``: any model, through one search, to one result type."""
from __future__ import annotations

import math
import time
import warnings

import numpy as np

from .._checks import positive_scalar
from .._deprecated import REMOVED_IN, SINCE
from .._errors import CapabilityError
from ..io.thinning import DEFAULT_MAX_POINTS, bin_datasets
from .models import get_model
from .parameters import as_datasets
from .records import FitAlternative, accepted, noise_note, noise_rms
from .result import AS_WELL, FitResult
from .search import best_chain, count, merged_history, run_search
from .time_series import data_kind

__all__ = ["fit", "VOIGT_OPTIONS", "prepare", "build_result"]

#: the options that describe the Voigt cell (VoigtModel's fields, with their defaults): on :func:`fit` they are
#: deprecated (``fit(data, model=VoigtModel(tendons="per-family"))``) and refused with another model
VOIGT_OPTIONS = {"tendons": "per-tendon", "damping": "uniform", "min_prestress_share": None, "max_decades": None,
                 "min_prestress_elasticity": None, "elasticity_frequency_hz": 0.1}


def fit(data, cell=None, *, model=None, starts: int = 4, seed: int | None = 0, jobs: int = 1, tolerance: float = 0.01,
        hops: int = 30, patience: int = 12, max_nfev: int = 100, polish: float = 0.2, polish_effort: float = 0.5,
        bounds: dict | None = None, fixed: dict | None = None, initial=None,
        max_points: int | None = DEFAULT_MAX_POINTS, progress: bool | None = None, **voigt_options) -> FitResult:
    """Fit a model's G', G'' (or creep compliance, or stress relaxation) to measured data (multi-start, analytic
    Jacobian).

    Every model goes through the same search and returns the same :class:`FitResult`: the paper's
    per-tendon Voigt cell (the default), any registered model by name (:func:`tenscell.fitting.models.get_model`:
    mechanisms, structure-free formulas, populations) or a :class:`~tenscell.fitting.models.base.FitModel` of your
    own. What the model fits is declared by it (``model.capabilities.data_kinds``).

    Parameters
    ----------
    data : RheologyData, CreepData or RelaxationData, or a sequence of them
        A frequency or prestress sweep (see :mod:`tenscell.io.data`), a creep or a stress relaxation curve, or
        several data sets fitted jointly by one parameter set; a data set that states its prestress
        (``data.with_prestress(P_Pa)``) is linked to the others by one prestress scale (see
        :mod:`tenscell.fitting.models.voigt`).
    cell : Cell, optional
        Reference cell; default :func:`tenscell.paper_cell` (strut length 1 m). A structure-free formula has none.
    model : str or FitModel, optional
        What to fit (default: the paper's Voigt cell with a stiffness per tendon,
        :class:`~tenscell.fitting.models.voigt.VoigtModel`). The Voigt cell's options are its own:
        ``model=VoigtModel(tendons="per-family", damping="per-family")``.
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
    bounds, fixed : dict, optional
        ``{parameter name or kind: (lo, hi)}`` and ``{parameter name: value}`` in SI units (see the model's
        problem: :func:`tenscell.fitting.make_problem` for the Voigt cell).
    initial : FitResult or array_like, optional
        A warm start: start 0 begins here (a FitResult of the same data and
        parametrization, or its free log-parameters ``theta``), moved inside
        the bounds (with ``max_decades``, stiffnesses compressed to the bound).
    max_points : int or None
        A moduli data set with more points is fitted binned in log frequency
        per prestress (:func:`tenscell.io.thinning.bin_log_frequency`; the rule
        and counts go into the data's comments and the report), as ``tenscell
        fit --max-points`` does. None fits every point; time series are never binned.
    progress : bool or None
        A progress bar: None when someone watches (a terminal or a notebook),
        True always, False never (see :mod:`tenscell._progress`).
    **voigt_options
        Deprecated: ``tendons``, ``damping``, ``min_prestress_share``, ``max_decades``,
        ``min_prestress_elasticity``, ``elasticity_frequency_hz`` belong to the Voigt cell
        (``model=VoigtModel(...)``); given here they still set it, with a DeprecationWarning, for one release.

    Returns
    -------
    FitResult

    Raises
    ------
    ValueError
        Bad options, data or cell (see the model's problem); data of a kind the model does not fit; a Voigt option
        with another model (:class:`~tenscell.fitting.models.base.CapabilityError`).
    TypeError
        An unknown keyword.
    """

    t_begin = time.monotonic()
    spec = _spec(model, voigt_options)
    datasets, cell = prepare(data, cell, max_points, spec)
    problem = spec.problem(datasets, cell, bounds=bounds, fixed=fixed)
    positive_scalar("tolerance", tolerance, "decades")
    warm = initial.theta if isinstance(initial, FitResult) else initial  # a fit of the same problem, or its theta
    chains, stop = run_search(problem, starts=starts, seed=seed, jobs=jobs, tolerance=tolerance, hops=hops,
                              patience=patience, max_nfev=max_nfev, polish=polish, polish_effort=polish_effort,
                              initial=warm, progress=progress, desc=f"fit ({spec.name})", t_begin=t_begin,
                              noise=noise_rms(datasets))
    return build_result(problem, datasets, chains, stop, float(tolerance), seed, t_begin)


def _spec(model, voigt_options: dict):
    """The FitModel to fit: ``model`` (a name or a FitModel; default the per-tendon Voigt cell), with the deprecated
    Voigt options of :func:`fit` applied."""
    unknown = sorted(set(voigt_options) - set(VOIGT_OPTIONS))
    if unknown:
        raise TypeError(f"fit() got an unexpected keyword argument {unknown[0]!r}")
    spec = get_model("voigt-per-tendon" if model is None else model)
    if not voigt_options:
        return spec
    named = ", ".join(f"{k}=" for k in voigt_options)
    warnings.warn(f"tenscell.fit({named}) is deprecated (since {SINCE}, removed in {REMOVED_IN}): the Voigt cell's "
                  "options are its own, "
                  f"fit(data, model=VoigtModel({named.replace('=', '=...')})) (tenscell.fitting.VoigtModel)",
                  DeprecationWarning, stacklevel=3)
    if not spec.capabilities.voigt_options:  # a default value was never refused with another model
        voigt_options = {k: v for k, v in voigt_options.items() if v != VOIGT_OPTIONS[k]}
    return spec.with_options(**voigt_options)


def prepare(data, cell, max_points, spec=None):
    """The data sets (binned beyond ``max_points``) and the reference cell (default the paper's; None for a
    structure-free formula)."""
    from ..model.shapes import paper_cell

    datasets = as_datasets(data)
    if spec is not None:  # what the model fits, it declares (Capabilities.data_kinds)
        for d in datasets:
            if not spec.capabilities.fits(data_kind(d)):
                raise CapabilityError(f"{d.source}: model {spec.name!r} fits {', '.join(sorted(spec.capabilities.data_kinds))} "
                                      f"data, not {data_kind(d)} (a mechanism or a formula fits every kind)")
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

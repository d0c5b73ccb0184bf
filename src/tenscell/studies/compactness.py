"""Compactness: how narrow can the distribution of tendon stiffnesses be and still fit the data?

The paper fits Fabry's power law with tendon stiffnesses spread over 8–9
decades, calls that unrealistic and conjectures that more compact
distributions could also fit. This study answers it for any data: for each
bound ``D`` on the spread ``log10(max EA / min EA)`` it fits the model with
``max_decades=D`` (an exact constraint; see :mod:`tenscell.fitting.models.voigt`)
and records the best RMS reached. Bounds are scanned from the widest to the
narrowest, each fit warm-started from the previous one (its stiffnesses
compressed to the new bound) besides fresh starts, so the front is what a
search of the given effort finds, not a proven optimum.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._progress import progress_bar
from .._results import dataframe, format_repr

__all__ = ["CompactnessStudy", "compactness_study", "DEFAULT_DECADES"]

#: bounds scanned by default (decades)
DEFAULT_DECADES = tuple(float(d) for d in range(14, 0, -1))


@dataclass(frozen=True, eq=False, repr=False)
class CompactnessStudy:
    """Best fit against the bound on the stiffness spread.

    Attributes
    ----------
    decades : ndarray, shape (k,)
        The bounds D (decades), increasing.
    rms : ndarray, shape (k,)
        Best RMS log10 error found with the spread at most D (decades; the worst data set's for a joint
        fit): the best of the searches at this bound and every narrower one, whose fits are feasible
        here too, so the front never rises with D.
    spread : ndarray, shape (k,)
        Spread of the fitted stiffnesses of that best fit (decades, ≤ D).
    fits : tuple of FitResult
        That best fit at each bound.
    search_rms : ndarray, shape (k,)
        What the search at each bound itself reached.
    tolerance : float
    sources : tuple of str
    """

    decades: np.ndarray
    rms: np.ndarray
    spread: np.ndarray
    fits: tuple
    tolerance: float
    sources: tuple
    search_rms: np.ndarray

    @property
    def knee(self) -> float | None:
        """The narrowest bound (decades) whose fit is within the tolerance, or None."""
        ok = self.rms <= self.tolerance
        return float(self.decades[ok].min()) if ok.any() else None

    @property
    def knee_fit(self):
        """The fit at :attr:`knee` (None if no bound reached the tolerance)."""
        if self.knee is None:
            return None
        return self.fits[int(np.flatnonzero(self.decades == self.knee)[0])]

    def __repr__(self) -> str:
        knee = "no bound reaches the tolerance" if self.knee is None else (
            f"narrowest within tolerance {self.tolerance:g}: {self.knee:g} decades "
            f"(spread {self.spread[self.decades == self.knee][0]:.2f})")
        return format_repr(f"CompactnessStudy: {len(self.decades)} bounds from {self.decades.min():g} to "
                           f"{self.decades.max():g} decades, {len(self.sources)} data set(s)",
                           knee, f"best RMS from {self.rms.min():.3g} to {self.rms.max():.3g}")

    def to_dataframe(self):
        """One row per bound: max_decades, rms_log10_error, spread_decades, converged, search_rms_log10_error."""
        return dataframe({"max_decades": self.decades, "rms_log10_error": self.rms, "spread_decades": self.spread,
                          "converged": self.rms <= self.tolerance, "search_rms_log10_error": self.search_rms},
                         {"tolerance": self.tolerance})

    #: header of :meth:`rows`
    HEADER = ("max_decades", "rms_log10_error", "spread_decades", "within_tolerance", "search_rms_log10_error")

    def rows(self):
        """(max_decades, rms, spread, within tolerance, this bound's own search rms) per bound, for CSV."""
        return [(float(d), float(r), float(s), bool(r <= self.tolerance), float(q))
                for d, r, s, q in zip(self.decades, self.rms, self.spread, self.search_rms)]

    def plot(self, ax=None, **kw):
        """The front: best RMS against the bound (see :func:`tenscell.plotting.fits.compactness_front`)."""
        from .._results import plotter

        compactness_front = plotter("compactness_front")

        return compactness_front(self.decades, self.rms, tolerance=self.tolerance, knee=self.knee, ax=ax, **kw)


def compactness_study(data, decades=DEFAULT_DECADES, *, cell=None, tendons: str = "per-tendon",
                      damping: str = "uniform", starts: int = 4, seed: int | None = 0, jobs: int = 1,
                      tolerance: float = 0.01, hops: int = 20, patience: int = 6,
                      progress: bool | None = None, **fit_options) -> CompactnessStudy:
    """Fit ``data`` with the stiffness spread bounded by each of ``decades``.

    Parameters
    ----------
    data : RheologyData or sequence of RheologyData
        As for :func:`tenscell.fitting.fit` (several: a joint fit at each bound).
    decades : sequence of float
        The bounds D (decades), each > 0; scanned from the widest.
    cell, tendons, damping, starts, seed, jobs, tolerance, hops, patience, fit_options :
        Passed to :func:`tenscell.fitting.fit` for every bound (a lighter
        search than its defaults: 20 hops, patience 6).
    progress : bool or None

    Returns
    -------
    CompactnessStudy
    """
    D = _bounds(decades)
    fits = []
    previous = None
    for d in progress_bar(D, desc="compactness", unit="bound", progress=progress):
        previous = bound_fit(data, d, dict(cell=cell, tendons=tendons, damping=damping, starts=starts, seed=seed,
                                           jobs=jobs, tolerance=tolerance, hops=hops, patience=patience,
                                           **fit_options), previous)
        fits.append(previous)
    return _front(D, fits, tolerance)


def _bounds(decades) -> np.ndarray:
    """The bounds (decades), each once, widest first (ValueError naming ``decades``)."""
    D = np.array(sorted({float(d) for d in decades}, reverse=True))
    if D.size == 0 or not np.all(np.isfinite(D)) or np.any(D <= 0):
        raise ValueError(f"decades must be positive numbers, got {list(decades)!r}")
    return D


def bound_fit(data, max_decades: float, options: dict, previous=None):
    """The fit of ``data`` by the Voigt cell with the stiffness spread bounded by ``max_decades``, warm-started from
    ``previous`` (the fit at the next wider bound, or None); ``options`` for :func:`tenscell.fitting.fit`, with the
    cell's ``tendons`` (default per-tendon) and ``damping`` (default uniform)."""
    from ..fitting import VoigtModel, fit

    options = dict(options)
    tendons, damping = options.pop("tendons", "per-tendon"), options.pop("damping", "uniform")
    return fit(data, model=VoigtModel(tendons, damping, max_decades=float(max_decades)), initial=previous,
               progress=False, **options)


def _front(D: np.ndarray, fits: list, tolerance: float) -> CompactnessStudy:
    """The study from the fit at each bound of ``D`` (in the order of ``D``)."""
    order = np.argsort(D)
    fits = [fits[i] for i in order]
    search = np.array([max(f.rms_log10_error for f in r.fits) for r in fits])
    # a fit within a narrower bound is feasible within a wider one: the front is the running best
    best = [int(np.argmin(search[: k + 1])) for k in range(len(fits))]
    fits = [fits[b] for b in best]
    sources = tuple(d.source for d in fits[0].datasets)
    return CompactnessStudy(decades=D[order], rms=search[best], spread=np.array([_decades(r) for r in fits]),
                            fits=tuple(fits), tolerance=float(tolerance), sources=sources, search_rms=search)


def _decades(result) -> float:
    """The tendon-stiffness spread (decades) of a Voigt fit."""
    spread = result.stiffness_spread
    assert spread is not None  # a Voigt cell has tendons
    return float(spread[2])


# ---- the study protocol (tenscell study compactness DATA...) --------------------------------------------------
#: a fit at one bound per start, in units of one evaluation of the model at a start (residuals and Jacobian,
#: :func:`tenscell.studies._common.evaluation_probe`), as measured on the bundled data with the study's search (20 hops, patience 6)
#: (bench/calibrate_study_units.py)
UNITS_PER_START = 20.0


class _Compactness:
    """``tenscell study compactness DATA...``: one fit per bound, widest first, each warm-started from the one
    before (so they run in a chain; each fit's starts over ``jobs`` workers)."""

    name = "compactness"
    options = {"data": (), "decades": DEFAULT_DECADES, "damping": "uniform", "starts": 4, "seed": 0, "jobs": None,
               "tolerance": 0.01}

    def plan(self, options):
        from .._parallel import jobs_for
        from ..fitting.models.voigt import VoigtModel
        from ._common import PROBE_EVALUATIONS, evaluation_probe
        from .protocol import Plan, Task, study_options

        opts = study_options(self, options)
        if not opts["data"]:
            raise ValueError("study compactness needs data files (e.g. bundled:fabry2001)")
        D = _bounds(opts["decades"])
        fit_options = {"damping": opts["damping"], "starts": opts["starts"], "seed": opts["seed"],
                       "jobs": jobs_for(opts["starts"], opts["jobs"]), "tolerance": opts["tolerance"], "hops": 20,
                       "patience": 6}
        tasks, before = [], ()
        for d in D:
            key = f"fit with the spread at most {d:g} decades"
            tasks.append(Task(key, "evaluation", bound_fit, (tuple(opts["data"]), float(d), fit_options),
                              needs=before, weight=UNITS_PER_START * opts["starts"]))
            before = (key,)
        probe = Task("evaluations of the model", "evaluation", evaluation_probe,
                     (VoigtModel(tendons="per-tendon", damping=opts["damping"]), tuple(opts["data"])),
                     weight=PROBE_EVALUATIONS)
        return Plan(self.name, {**opts, "bounds": D}, tuple(tasks), calibration=(probe,), figures=2.0,
                    sized_by=("--decades", "--starts"))

    def assemble(self, plan, results):
        from .._results import reporter
        from .protocol import Figure, StudyResult, Table

        s = _front(plan.options["bounds"], [results[t.key] for t in plan.tasks], plan.options["tolerance"])
        front = Table.from_records("compactness", [dict(zip(s.HEADER, row)) for row in s.rows()])
        figures = [Figure("compactness_front.png", "compactness_front", (s.decades, s.rms),
                          {"tolerance": s.tolerance, "knee": s.knee,
                           "title": "Best fit against the bound on the stiffness spread"})]
        tables = [front]
        knee = s.knee_fit
        if knee is not None:
            families = knee.cell.structure.families
            figures.append(Figure("compactness_histogram.png", "stiffness_histogram", (knee.model.EA,),
                                  {"families": families, "title": "Stiffnesses at the narrowest bound within "
                                                                  f"tolerance ({s.knee:g} decades)"}))
            tables.append(Table.from_records("compactness_knee_stiffness", [
                {"tendon": j, "family": fam, "EA_N": float(e)} for j, (fam, e) in enumerate(zip(families, knee.model.EA))]))
        return StudyResult(self.name, tables=tuple(tables), figures=tuple(figures),
                           pages=(("compactness.md", reporter("compactness_markdown")(s)),), data=s)


#: the study of ``tenscell study compactness`` (:mod:`tenscell.studies.protocol`)
STUDY = _Compactness()

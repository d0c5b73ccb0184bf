"""What every fit returns: :class:`FitResult`, the one result type of every model.

Whatever the model (:mod:`tenscell.fitting.models`: the per-tendon Voigt cell, a mechanism, a structure-free
formula), a fit returns a :class:`FitResult`: its parameters with standard errors and bounds, the verdict against the
tolerance and the data's own noise, per-data-set errors, the derived numbers with their ± (:attr:`FitResult.derived`),
identifiability, other starts that fit as well, AIC/BIC, a DataFrame, a figure (``plot``), fit.json (``to_dict``) and
the fitted model (:attr:`FitResult.model`) that every consumer takes. What differs between models is asked of the
problem (:class:`tenscell.fitting.problem.Problem`), never of the result's type.

A result is immutable: its cached analyses are recomputed after pickling (:meth:`FitResult.__getstate__` carries
its fields only), so it can be sent to another process while this one is still filling them.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .._results import CORRELATION_THRESHOLD, dataframe, format_repr, reporter
from ..io.data import RheologyData
from .problem import Problem
from .records import (CRITERIA_CONVENTION, STATUSES, CreepFit, DatasetFit, data_axis, error_fields,
                      information_criteria, lmfit_criteria, noise_rms, verdict_text)

__all__ = ["FitResult", "FIT_NULL_MEANS", "report_quantities", "AS_WELL"]

#: what a null in FitResult.to_dict() (and fit.json) stands for; written into the document as "null_means"
FIT_NULL_MEANS = (
    "null: no value. start_rms: a start the search never ran (an earlier start met the target first); "
    "time_to_tolerance_s, timing.tolerance_met_s: the tolerance was never met; prestress_Pa / prestress_fitted_Pa: "
    "the data set states no prestress / its prestress is not a fitted parameter; kind: a joint fit; seed, "
    "constraints: not set; parameters[].at_bound: not at a bound; tendon_stiffness_spread_not_at_bounds: every "
    "stiffness is at a bound; derived.*.stderr: not determined (derived.*.note says why); structure: a model without "
    "a cell; structure.shares: the Voigt cell (its prestress activity is prestress_activity); structure.prestress.s_m2 "
    "and what follows from it: no data set states its prestress; profile: not computed (FitResult.compute_profile, "
    "tenscell fit --profile); profile.*.intervals[].lower/upper: open, the data do not bound the parameter on that "
    "side within its bounds. A null anywhere else is a "
    "computed number that is not finite: its value is listed under non_finite")
#: other starts whose RMS is within this factor of the best (or the tolerance) count as fitting "as well"
AS_WELL = 1.1
#: data sets the repr lists by name (a population's cells beyond them are summarized)
_REPR_SETS = 6


@dataclass(frozen=True, eq=False, repr=False)
class FitResult:
    """The outcome of :func:`tenscell.fitting.fit`, for every model.

    Attributes
    ----------
    parameters : tuple of FitParameter
        Best-fit parameters (named, with units, bounds and whether a bound is hit).
    residuals : ndarray
        Unweighted ``log10 model − log10 data`` over the points of all data sets in order: the N G' residuals, the
        N G'' ones, then creep points.
    rms_log10_error : float
        RMS of ``residuals`` (decades), all data sets together.
    tolerance : float
        The RMS every data set had to reach.
    converged : bool
        True if every data set's RMS is within ``tolerance`` or inside the data set's stated noise
        (:func:`~tenscell.fitting.records.accepted`); :attr:`tolerance_met` says whether the tolerance itself was met.
    message : str
        What happened, in words (including why the search stopped).
    datasets : tuple of RheologyData or CreepData
    problem : Problem
        The model against the data (:attr:`spec` is the model).
    theta : ndarray
        Free log-parameters of the best fit.
    starts : int
    seed : int or None
    elapsed_s : float
        Wall-clock time of the whole fit, all starts (s).
    n_evaluations : int
        Model evaluations over all starts.
    alternatives : tuple of FitAlternative
        Other starts' solutions that fit almost as well, best first.
    start_rms : tuple of float
        Final RMS of every start, in start order (NaN for a start the search never ran).
    history : tuple of (float, float)
        ``(seconds since the fit began, best RMS so far)`` at each improvement over all starts.
    history_theta : tuple of ndarray
        The free log-parameters at each entry of ``history``.
    stop_reason : str
        Why the search stopped.
    """

    parameters: tuple
    residuals: np.ndarray
    rms_log10_error: float
    tolerance: float
    converged: bool
    message: str
    datasets: tuple
    problem: Problem
    theta: np.ndarray
    starts: int
    seed: int | None
    elapsed_s: float
    n_evaluations: int
    alternatives: tuple
    start_rms: tuple
    history: tuple
    history_theta: tuple
    stop_reason: str = ""

    def __getstate__(self):
        # the fields only: the cached analyses (fits, identifiability, derived...) are recomputed where needed, so a
        # result can be pickled to a worker while this process is filling them
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def __setstate__(self, state):
        self.__dict__.update(state)

    # -- the model ----------------------------------------------------------------------
    @property
    def spec(self):
        """The model that was fitted (:class:`~tenscell.fitting.models.base.FitModel`)."""
        return self.problem.spec

    @property
    def cell(self):
        """The reference cell (strut length ``L_ref``), None for a structure-free formula."""
        return self.problem.cell

    @property
    def label(self) -> str:
        """A short name of the model: ``"heterogeneous"``, ``"homogeneous"``, a mechanism's or formula's name."""
        return self.problem.label

    @property
    def tendons(self) -> str:
        """The Voigt cell's stiffness parametrization (per-tendon, per-family, uniform)."""
        return self.spec.tendons

    @property
    def damping(self) -> str:
        """The Voigt cell's damping parametrization (uniform, per-family)."""
        return self.spec.damping

    @property
    def n_free(self) -> int:
        """Free parameters of the fit."""
        return self.problem.n_free

    # -- the verdict ------------------------------------------------------------------------
    @property
    def dataset_rms(self) -> tuple:
        """RMS of the log10 errors of each data set (decades)."""
        return tuple(float(x) for x in self.problem.dataset_rms(self.theta))

    @property
    def noise(self) -> tuple:
        """Per data set, the RMS of its stated standard deviations in log10 (decades), None without sd columns."""
        return tuple(noise_rms(self.datasets))

    @property
    def sigma_known(self) -> bool:
        """Every data set states its noise (sd columns): residuals are in units of it."""
        return all(d.has_sd for d in self.datasets)

    @property
    def tolerance_met(self) -> bool:
        """Every data set's RMS is within :attr:`tolerance` (what the optimizer aimed at); :attr:`converged` also
        accepts a data set inside its stated noise."""
        return bool(max(self.dataset_rms) <= self.tolerance)

    @property
    def status(self) -> str:
        """How the fit ended, one of three (:data:`~tenscell.fitting.records.STATUSES`): ``"tolerance met"``
        (:attr:`converged`), ``"optimum, tolerance not met"`` (the search stopped at an optimum it could not improve:
        the model does not fit the data to the tolerance) or ``"stopped by budget"`` (it ran out of hops before
        either). The command line's exit status is 0 for the first and 1 for the other two."""
        from .search import stopped_by_budget

        if self.converged:
            return "tolerance met"
        return "stopped by budget" if stopped_by_budget(self.stop_reason) else "optimum, tolerance not met"

    @property
    def verdict(self) -> str:
        """``"converged"``, ``"inside the data's noise (tolerance not met)"``, ``"tolerance not met at an optimum"``
        or ``"NOT converged: stopped by its budget"`` (:func:`~tenscell.fitting.records.verdict_text`)."""
        return verdict_text(self.converged, self.tolerance_met, self.status)

    @cached_property
    def time_to_tolerance_s(self) -> float | None:
        """Seconds from the start of the fit until some start first had every data set within the tolerance
        (and the constraints, if any, held); None if that never happened."""
        for (t, _), theta in zip(self.history, self.history_theta):
            if float(self.problem.dataset_rms(theta).max()) <= self.tolerance and self.problem.feasible(theta):
                return float(t)
        return None

    @property
    def data(self) -> RheologyData:
        """The data set of a single-data-set fit (a joint fit has :attr:`datasets`)."""
        if len(self.datasets) != 1:
            raise ValueError(f"this is a joint fit of {len(self.datasets)} data sets: use .datasets or .fits")
        return self.datasets[0]

    @property
    def joint(self) -> bool:
        """True for a fit of several data sets at once."""
        return len(self.datasets) > 1

    def value(self, name: str) -> float:
        """The value of parameter ``name`` (SI units)."""
        for p in self.parameters:
            if p.name == name:
                return p.value
        raise ValueError(f"no parameter named {name!r}; parameters: {', '.join(p.name for p in self.parameters)}")

    @property
    def n_at_bound(self) -> int:
        """How many varied parameters sit at a bound."""
        return sum(p.at_bound is not None for p in self.parameters)

    # -- tendons (models with a cell) -------------------------------------------------------
    @property
    def EA(self) -> np.ndarray:
        """Stiffness of every tendon (N), shape (m,) (the Voigt cell)."""
        return self.model.EA

    @property
    def c(self) -> np.ndarray:
        """Damping of every tendon (N·s/m), shape (m,) (the Voigt cell)."""
        return self.model.c

    @property
    def L(self) -> float:
        """Fitted strut length (m) (the Voigt cell)."""
        return self.model.L

    @property
    def stiffness_spread(self) -> tuple[float, float, float] | None:
        """(min, max, decades = log10(max/min)) of the tendon stiffnesses; None for a structure-free formula."""
        return self.problem.stiffness_spread(self.theta)

    @property
    def stiffness_spread_interior(self) -> tuple[float, float, float] | None:
        """Like :attr:`stiffness_spread`, over the tendons whose stiffness is not at a bound (None if none is)."""
        return self.problem.stiffness_spread_interior(self.theta)

    @property
    def assignment_spread(self) -> tuple[float, float]:
        """Largest sd (decades) of G', G'' between the assignments of a distributed property (0, 0: none)."""
        return self.problem.assignment_spread(self.theta)

    # -- per data set -------------------------------------------------------------------
    def group_prestress(self) -> np.ndarray:
        """Model prestress P (N) of each prestress group of the problem."""
        return self.problem.group_prestress(self.theta)

    @cached_property
    def fits(self) -> tuple:
        """One :class:`DatasetFit` (or :class:`CreepFit`) per data set, in order."""
        pr = self.problem
        Gs, Gl = pr.moduli(self.theta)
        P_groups = self.group_prestress()
        P_pts = P_groups[pr.group_index]
        vals = dict(zip(pr.names, pr.values(self.theta)))
        out: list[DatasetFit | CreepFit] = []
        Jc = pr.creep(self.theta) if pr.n_creep else None
        for k, d in enumerate(self.datasets):
            pts = np.flatnonzero(pr.dataset_index == k)
            stated = float(d.prestress[0]) if d.prestress is not None and np.unique(d.prestress).size == 1 else None
            if d.kind == "creep":
                assert Jc is not None  # a creep data set makes pr.n_creep > 0
                sel = np.flatnonzero(pr.creep_dataset == k)
                out.append(CreepFit(index=k, data=d, axis="time", prestress_pa=stated,
                                    prestress_fitted_pa=vals.get(f"P_data[{k}]"),
                                    prestress_model_N=P_groups[pr.creep_group[sel]],
                                    J_model=Jc[sel], residuals=self.residuals[pr.rows(k)]))
                continue
            out.append(DatasetFit(
                index=k, data=d, axis=data_axis(d), prestress_pa=stated,
                prestress_fitted_pa=vals.get(f"P_data[{k}]"), prestress_model_N=P_pts[pts],
                G_storage_model=Gs[pts], G_loss_model=Gl[pts], residuals=self.residuals[pr.rows(k)]))
        return tuple(out)

    def prestress_model(self, prestress_pa=None, dataset: int = 0) -> np.ndarray:
        """Model prestress P (N) for prestresses ``prestress_pa`` (Pa), or the one data set ``dataset`` was fitted at.

        With ``prestress_pa`` the fit must have a prestress scale ``s`` (some data set stated its prestress):
        ``P = s·prestress_pa``. Without it, the data set must have a single prestress (a frequency sweep); its
        model P is returned as a 1-element array.
        """
        if prestress_pa is not None:
            return self.problem.model_prestress(self.theta, prestress_pa)
        P = np.unique(self.fits[dataset].prestress_model_N)
        if P.size != 1:
            raise ValueError(f"data set {dataset} spans several prestresses: give prestress_pa (Pa)")
        return P

    def single_prestress_dataset(self) -> int:
        """The first data set measured at one prestress (ValueError if every one spans several)."""
        for fit in self.fits:
            if np.unique(fit.prestress_model_N).size == 1:
                return fit.index
        raise ValueError("every data set spans several prestresses: give prestress_pa (Pa)")

    def moduli(self, f_hz, prestress_pa=None, *, dataset: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The fitted model's G', G'' (Pa) at frequencies ``f_hz`` (Hz).

        ``prestress_pa`` (Pa, broadcast with ``f_hz``) maps to the model by the fitted scale ``s``; without it the
        model prestress is the one of data set ``dataset`` (default: the only data set, or the first with a single
        prestress).
        """
        f = np.atleast_1d(np.asarray(f_hz, dtype=float))
        if prestress_pa is not None:
            Pm = np.atleast_1d(self.prestress_model(prestress_pa))
            if dataset is None:
                return self.problem.moduli_at(self.theta, f, Pm)
        else:
            dataset = self.single_prestress_dataset() if dataset is None else dataset
            Pm = self.prestress_model(dataset=dataset)
        return self.problem.dataset_moduli_at(self.theta, f, Pm, dataset)

    def _default_prestress_N(self) -> float:
        """Model prestress (N) of the first single-prestress data set, else at the first data set's median."""
        try:
            return float(self.prestress_model(dataset=self.single_prestress_dataset())[0])
        except ValueError:
            return float(np.ravel(self.prestress_model(np.median(self.datasets[0].prestress)))[0])

    # -- the fitted model and analyses of it -------------------------------------------------
    @property
    def model(self):
        """The fitted model (:mod:`tenscell.fitting.fitted`): what ``moduli``, ``creep``, ``simulate``, ``show``
        and ensembles take."""
        return self.problem.fitted(self.theta, self)

    @property
    def linear(self):
        """The linear model of the fitted cell at :meth:`_default_prestress_N` (models with a cell)."""
        return self.model.linear(P_N=self._default_prestress_N())

    @cached_property
    def prestress(self):
        """Is the prestress doing anything? (the Voigt cell: :mod:`tenscell.fitting.prestress`)."""
        return self.problem.prestress_activity(self)

    def predicted_creep(self, t_min: float = 0.1, t_max: float = 10.0, n: int = 41):
        """Creep compliance (1/Pa) of the fitted cell over [t_min, t_max] s and its power-law exponent."""
        from .fitted import predicted_creep

        return predicted_creep(self.linear, t_min, t_max, n)

    def identifiability(self, rtol: float = 1e-8):
        """Rank, standard errors, correlations and determined combinations (:mod:`tenscell.fitting.identifiability`);
        the default tolerance's analysis is computed once."""
        if rtol == 1e-8:
            return self._identifiability
        return self.problem.identifiability(self.theta, sigma_known=self.sigma_known, rtol=rtol)

    @cached_property
    def _identifiability(self):
        return self.problem.identifiability(self.theta, sigma_known=self.sigma_known, rtol=1e-8)

    @property
    def standard_errors(self) -> tuple[tuple[float | None, str], ...]:
        """``(standard error, note)`` of each parameter, in :attr:`parameters` order.

        The standard error is in the parameter's unit (first order in its ln: ``value × se(ln value)``, from
        :meth:`identifiability`); None when the parameter is fixed, at a bound, the strut-length gauge, or not
        determined by the data, and the note says which. With the gauge removed the error is that of the
        gauge-invariant combination the note names (``"of EA[3]/L²"``).
        """
        ident = self.identifiability()
        out = []
        for p in self.parameters:
            rel, note = ident.relative_error(p.name)
            out.append((None if rel is None else abs(p.value) * rel, note))
        return tuple(out)

    def model_standard_errors(self) -> np.ndarray:
        """Standard error (decades) of the fitted model's log10 G′, log10 G″ or log10 J at each residual, in the
        order of :attr:`residuals`; NaN when σ is unknown (the leverage ``h`` of the linearized fit:
        ``σ·sqrt(h_i)/w_i``)."""
        ident = self.identifiability()
        n = self.residuals.size
        h = np.asarray(ident.leverage, dtype=float)[:n]
        sigma = np.nan if ident.sigma is None else ident.sigma
        return sigma * np.sqrt(np.clip(h, 0.0, None)) / np.asarray(self.problem.weights, dtype=float)[:n]

    @cached_property
    def derived(self):
        """The numbers the report derives from the parameters, each with its standard error
        (:class:`~tenscell.fitting.derived.DerivedQuantities`; delta method, finite-difference gradients)."""
        from .derived import derived_quantities

        return derived_quantities(self, self.problem.report_quantities)

    def compute_derived(self, executor=None):
        """:attr:`derived`, computed now with half of its model evaluations in ``executor`` (a worker with
        ``submit``) and kept; the numbers do not depend on it."""
        if "derived" not in self.__dict__:
            from .derived import derived_quantities

            self.__dict__["derived"] = derived_quantities(self, report_quantities, executor=executor)
        return self.__dict__["derived"]

    @cached_property
    def structure(self):
        """What the structure carries (:func:`tenscell.fitting.shares.structure_summary`): a mechanism's shares of
        dG'/dP and dG''/dP with standard errors, and the fitted prestress against the measured one; None for a
        structure-free formula."""
        from .shares import structure_summary

        return structure_summary(self)

    @property
    def profile(self):
        """The profile-likelihood intervals computed by :meth:`compute_profile` (None until then: each is a series
        of refits)."""
        return self.__dict__.get("_profile")

    def compute_profile(self, parameters="auto", **options):
        """Profile-likelihood intervals of the parameters the local analysis cannot bound, computed now and kept
        (:func:`tenscell.fitting.profile.profile_intervals`; ``parameters`` and ``options`` as there). Returns the
        :class:`~tenscell.fitting.profile.ProfileSet`."""
        from .profile import profile_intervals

        self.__dict__["_profile"] = profile_intervals(self, parameters, **options)
        self.__dict__.pop("structure", None)  # the prestress scale reads the profile of s
        return self.__dict__["_profile"]

    def correlations(self, threshold: float = CORRELATION_THRESHOLD) -> list[tuple[str, str, float]]:
        """``(a, b, ρ)`` for pairs of determined parameters with ``|ρ| >= threshold``, strongest first."""
        return self.identifiability().strong_correlations(threshold)

    def information_criteria(self) -> tuple[float, float]:
        """(AIC, BIC) of the log10 residuals; ``k`` counts the model's parameters (free, less an exact gauge), and the
        noise σ when it is estimated (:data:`~tenscell.fitting.records.CRITERIA_CONVENTION`)."""
        aic, bic, _ = information_criteria(self.problem.residuals(self.theta), self.problem.n_model_parameters,
                                           sigma_known=self.sigma_known, weights=self.problem.weights)
        return aic, bic

    def information_criteria_lmfit(self) -> tuple[float, float]:
        """(AIC, BIC) of the same residuals as lmfit reports them: ``n ln(χ²/n) + 2k``, ``n ln(χ²/n) + k ln n``
        (:func:`~tenscell.fitting.records.lmfit_criteria`; σ not counted)."""
        return lmfit_criteria(self.problem.residuals(self.theta), self.problem.n_model_parameters)

    def alternative_spread(self) -> dict:
        """Per free parameter, the spread ``log10(max/min)`` (decades) over the best fit and the alternatives."""
        out = {}
        for i, p in enumerate(self.parameters):
            if not p.vary:
                continue
            vals = [p.value] + [a.parameters[i].value for a in self.alternatives]
            out[p.name] = float(np.log10(max(vals) / min(vals)))
        return out

    # -- conventions ----------------------------------------------------------------------
    def __repr__(self) -> str:
        sets = ", ".join(f"{_short(f.data.source)} {f.rms_log10_error:.3g}" for f in self.fits[:_REPR_SETS])
        if len(self.fits) > _REPR_SETS:  # a population of cells: the first few, the worst, the count
            worst = max(self.fits, key=lambda f: f.rms_log10_error)
            sets += f", … (worst {_short(worst.data.source)} {worst.rms_log10_error:.3g}; {len(self.fits)} in all)"
        return format_repr(
            f"FitResult: {self.label} ({self.problem.describe()}), {len(self.datasets)} data set(s), "
            f"{sum(d.n for d in self.datasets)} points, {self.problem.n_free} free parameters",
            f"rms log10 error {self.rms_log10_error:.4g} (tolerance {self.tolerance:g}): "
            f"{self.verdict}; per data set: {sets}",
            f"{self.starts} start(s), seed {self.seed}, {self.elapsed_s:.1f} s; stopped: {self.stop_reason}",
        )

    def _repr_html_(self) -> str:
        return reporter("fit_html")(self)  # verdict, quality, provenance, parameters with ± (reports/html.py)

    def to_dataframe(self):
        """Data, model and log10 errors at every point of every data set (columns with units).

        ``attrs["parameters"]`` holds ``{name: (value, unit)}``.
        """
        import pandas as pd

        frames = []
        for f in self.fits:
            df = f.to_dataframe()
            df.insert(0, "dataset", f.index)
            df.insert(1, "source", f.data.source)
            frames.append(df)
        out = pd.concat(frames, ignore_index=True)
        out.attrs.update({"parameters": {p.name: (p.value, p.unit) for p in self.parameters},
                          "rms_log10_error": self.rms_log10_error, "model": self.spec.name})
        return out

    def parameters_dataframe(self):
        """The parameters as a DataFrame: name, value, stderr (both in ``unit``; stderr NaN when not determined),
        stderr_percent, stderr_note, unit, lower, upper, vary, at_bound, description, and the spread over the
        other starts that fit as well (decades)."""
        alt = self.alternative_spread()
        rows = [{**p.to_dict(), **error_fields(p, (None if e is None else e / abs(p.value) if p.value else None, n)),
                 "alternatives_spread_decades": alt.get(p.name, math.nan) if self.alternatives else math.nan}
                for p, (e, n) in zip(self.parameters, self.standard_errors)]
        order = ["name", "value", "stderr", "stderr_percent", "stderr_note", "unit", "lower", "upper", "vary",
                 "at_bound", "description", "alternatives_spread_decades"]
        cols = {k: [r[k] for r in rows] for k in order}
        cols["stderr"] = [math.nan if v is None else v for v in cols["stderr"]]
        cols["stderr_percent"] = [math.nan if v is None else v for v in cols["stderr_percent"]]
        return dataframe(cols, {"correlations": self.correlations()})

    def plot(self, ax=None, *, dataset: int | None = None, **kw):
        """Data and fitted model of one data set on ``ax`` (or every data set, one panel each, when ``ax`` is None).

        Returns the axes (an array of axes for several panels).
        """
        from .._results import plotter

        return plotter("plot_fit")(self, ax=ax, dataset=dataset, **kw)

    # -- output ---------------------------------------------------------------------
    def to_dict(self) -> dict:
        """JSON-ready (fit.json): the model, parameters with errors, per-data-set errors, verdict, search, the
        derived numbers, identifiability, alternatives, the model's own entries and the fitted model."""
        from .fitted import FIT_SCHEMA

        first = self.fits[0]
        n = self.problem.n_points
        aic, bic = self.information_criteria()
        doc = {
            "schema": FIT_SCHEMA,
            "spec": self.spec.to_dict(),
            "model_name": self.spec.name,
            "description": self.problem.describe(),
            "data": [d.source for d in self.datasets] if self.joint else first.data.source,
            "kind": None if self.joint else first.data.kind,
            "provenance": [_provenance(d) for d in self.datasets],
            "n_points": n,
            "cell": None if self.cell is None else self.cell.describe(),
            "rms_log10_error": self.rms_log10_error,
            "rms_log10_error_storage": _rms(self.residuals[:n]),
            "rms_log10_error_loss": _rms(self.residuals[n: 2 * n]),
            "rms_log10_error_per_dataset": list(self.dataset_rms),
            "datasets": [f.to_dict() for f in self.fits],
            "tolerance": self.tolerance,
            "converged": self.converged,
            "tolerance_met": self.tolerance_met,
            "noise_rms_log10_per_dataset": list(self.noise),
            "message": self.message,
            "stop_reason": self.stop_reason,
            "time_s": self.elapsed_s,
            "time_to_tolerance_s": self.time_to_tolerance_s,
            "starts": self.starts,
            "seed": None if self.seed is None else int(self.seed),
            "n_evaluations": self.n_evaluations,
            "n_free_parameters": self.problem.n_free,
            "n_model_parameters": self.problem.n_model_parameters,
            "n_residuals": self.problem.n_residuals,
            "AIC": aic,
            "BIC": bic,
            "information_criteria": _criteria_entry(self),
            "status": self.status,
            "parameters": [{**p.to_dict(), "stderr": e, "stderr_percent": None if e is None or not p.value
                            else 100.0 * e / abs(p.value), "stderr_note": note}
                           for p, (e, note) in zip(self.parameters, self.standard_errors)],
            "correlations": {"threshold": CORRELATION_THRESHOLD,
                             "pairs": [{"a": a, "b": b, "rho": r} for a, b, r in self.correlations()]},
            "derived": self.derived.to_dict(),
            # a start the search never ran (an earlier one met the target first) has no RMS: null, not inf
            "start_rms": [r if math.isfinite(r) else None for r in self.start_rms],
            "alternatives": [a.to_dict() for a in self.alternatives],
            "alternative_spread_decades": self.alternative_spread(),
            "history": [{"time_s": t, "rms_log10_error": r} for t, r in self.history],
            "identifiability": self.identifiability().to_dict(),
            "structure": None if self.structure is None else self.structure.to_dict(),
            "profile": None if self.profile is None else self.profile.to_dict(),
            **self.problem.summary(self),
            "model": self.model.to_dict(),
        }
        if not self.joint:
            doc["residuals_log10"] = first.to_dict()["residuals_log10"]
        doc["null_means"] = FIT_NULL_MEANS
        return doc

    def report(self) -> str:
        """A readable plain-text report (in the spirit of lmfit's ``fit_report``; :func:`tenscell.reports.fit_text`)."""
        from .._results import reporter

        return reporter("fit_text")(self)


def report_quantities(result: FitResult) -> dict:
    """The report's derived numbers of ``result`` (module level: a worker process evaluates a share of them)."""
    return result.problem.report_quantities(result)


def _criteria_entry(result) -> dict:
    """fit.json's ``information_criteria``: tenscell's AIC/BIC, lmfit's beside them, the convention, what the status
    means."""
    aic, bic = result.information_criteria()
    aic_l, bic_l = result.information_criteria_lmfit()
    return {"AIC": aic, "BIC": bic, "k": result.problem.n_model_parameters + (0 if result.sigma_known else 1),
            "n": result.problem.n_residuals, "sigma_counted": not result.sigma_known,
            "lmfit": {"AIC": aic_l, "BIC": bic_l, "k": result.problem.n_model_parameters},
            "convention": CRITERIA_CONVENTION, "status_means": STATUSES[result.status]}


def _provenance(d) -> dict:
    """What was read for data set ``d``: its source and, where the reader recorded it, the step, temperature and
    unit conversions (:attr:`tenscell.io.data.RheologyData.provenance`)."""
    return {"source": d.source, **(dict(d.provenance) if d.provenance is not None else {})}


def _rms(r) -> float | None:
    """RMS (decades), None for no residuals (a fit to creep data only has no G', G'')."""
    return float(np.sqrt(np.mean(r**2))) if r.size else None


def _short(source: str) -> str:
    return source.replace("\\", "/").rsplit("/", 1)[-1]

from .._deprecated import moved_away  # noqa: E402

__getattr__ = moved_away(__name__)  # the public names of 0.2.0 that moved away: a DeprecationWarning names their home

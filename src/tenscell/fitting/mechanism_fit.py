"""Fitting a mechanism, and a fitted mechanism as a model: :func:`fit_mechanism`, :class:`MechanismFit`, :class:`FittedMechanism`.

:func:`fit_mechanism` runs the same multi-start search as the per-tendon fit
(:func:`tenscell.fitting.search.run_search`) on a
:class:`~tenscell.fitting.models.mechanism_problem.MechanismProblem`. The result
reports, beside the local standard errors of
:func:`~tenscell.fitting.identifiability.identifiability`, the spread of the
parameters over the other starts that fit as well (RMS within
``max(tolerance, 1.1 × best)``): where a second basin exists, that spread, not
the local error, is the uncertainty. A fit whose every data set lies within
the data's own noise (its stated standard deviations) counts as converged
whatever ``tolerance`` was.

:class:`FittedMechanism` answers like the paper cell: G', G'' at any frequency
and at any prestress in the data's units (Pa, through the fitted scale ``s``),
and round-trips through ``fit.json`` (:func:`load_any_fit`).
"""
from __future__ import annotations

import dataclasses
import json
import time
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from .._checks import positive_scalar
from .._results import dataframe, format_repr
from ..model.equilibrium import Cell
from .fitted import cell_from_dict, cell_to_dict
from .models.mechanism_problem import MechanismProblem, _layout, _maps, make_mechanism_problem
from .models.mechanism import Field, Mechanism
from .result import FitAlternative, accepted, inside_noise, noise_rms, verdict_text

__all__ = ["MechanismFit", "FittedMechanism", "fit_mechanism", "load_any_fit", "MECHANISM_FORMAT",
           "noise_rms"]

#: the ``format`` tag of a fitted mechanism in fit.json's ``"model"`` entry
MECHANISM_FORMAT = "tenscell-fitted-mechanism"
#: alternatives whose RMS is within this factor of the best (or the tolerance) "fit as well"
AS_WELL = 1.1


@dataclass(frozen=True, eq=False, repr=False)
class FittedMechanism:
    """A fitted mechanism as a model: its law values per tendon, prestress mapping and moduli anywhere.

    Attributes
    ----------
    mechanism : Mechanism
    cell : Cell
        The reference cell the parameters refer to.
    values : dict
        The mechanism's own parameters (fields and viscosity), SI units.
    s : float or None
        Prestress scale (m²): model prestress (N) = s × prestress (Pa).
    P : float or None
        Model prestress (N) when no data set stated a prestress.
    prestress_pa : tuple of float
        The prestresses (Pa) of the data (stated or fitted), for the default.
    source : str
    """

    mechanism: Mechanism
    cell: Cell
    values: dict
    s: float | None = None
    P: float | None = None
    prestress_pa: tuple = ()
    source: str = ""

    def __repr__(self) -> str:
        vals = ", ".join(f"{k} = {v:.4g}" for k, v in self.values.items())
        pre = f"s = {self.s:.4g} m²" if self.s is not None else f"P = {self.P:.4g} N"
        return format_repr(f"FittedMechanism {self.mechanism.name}", vals, pre)

    def prestress(self, prestress_pa: float | None = None) -> float:
        """Model prestress P (N): ``s × prestress_pa`` (default the median prestress of the data), or the fitted P."""
        if self.s is None:
            if prestress_pa is not None:
                raise ValueError("this fit has a fitted prestress P (N): no data set stated its prestress, so a "
                                 "prestress in Pa has no model equivalent")
            assert self.P is not None
            return float(self.P)
        if prestress_pa is None:
            prestress_pa = float(np.median(self.prestress_pa))
        return float(self.s) * positive_scalar("prestress", prestress_pa, "Pa")

    def _problem(self) -> MechanismProblem:
        return bare_problem(self.mechanism, self.cell)

    def moduli(self, f_hz, prestress_pa: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """G', G'' (Pa) at frequencies ``f_hz`` (Hz) and one prestress (Pa; see :meth:`prestress`)."""
        f = np.atleast_1d(np.asarray(f_hz, dtype=float)).ravel()
        if not (f.size and np.all(np.isfinite(f)) and np.all(f > 0)):
            raise ValueError("frequencies must be finite numbers > 0 (Hz)")
        pb = self._problem()
        phi = np.log([self.values[n] for n in pb.names])
        P = np.full(f.size, self.prestress(prestress_pa))
        out = pb.evaluate(phi, 2 * np.pi * f, P, jac=False)
        if out is None:
            raise ValueError(f"the fitted {self.mechanism.name} cell is not stable at this prestress")
        return out.G.real, out.G.imag

    def to_dict(self) -> dict:
        """JSON-ready (the ``"model"`` entry of fit.json); :meth:`from_dict` rebuilds it."""
        return {"format": MECHANISM_FORMAT, "mechanism": mechanism_to_dict(self.mechanism),
                **cell_to_dict(self.cell),
                "values": {k: float(v) for k, v in self.values.items()}, "s_m2": self.s, "P_N": self.P,
                "prestress_Pa": list(self.prestress_pa), "source": self.source}

    @classmethod
    def from_dict(cls, obj: dict) -> "FittedMechanism":
        if not isinstance(obj, dict) or obj.get("format") != MECHANISM_FORMAT:
            raise ValueError(f"not a fitted mechanism (expected format {MECHANISM_FORMAT!r})")
        cell, _ = cell_from_dict(obj)
        return cls(mechanism=mechanism_from_dict(obj["mechanism"]), cell=cell,
                   values={k: float(v) for k, v in obj["values"].items()}, s=obj.get("s_m2"), P=obj.get("P_N"),
                   prestress_pa=tuple(obj.get("prestress_Pa") or ()), source=str(obj.get("source", "")))


def mechanism_to_dict(m: Mechanism) -> dict:
    """A mechanism spec as JSON."""
    return dataclasses.asdict(m)


def mechanism_from_dict(obj: dict) -> Mechanism:
    """The spec written by :func:`mechanism_to_dict`."""
    fields = tuple(Field(**f) for f in obj["fields"])
    return Mechanism(**{**obj, "fields": fields})


def bare_problem(mech: Mechanism, cell: Cell) -> MechanismProblem:
    """A problem without data: the mechanism's own parameters only, for :meth:`MechanismProblem.evaluate`."""
    from .. import laws

    rows, per_field, groups = _layout(mech, cell, getattr(laws, mech.law))
    if mech.viscosity:
        rows.append(("eta_cytoplasm", "Pa·s", "viscosity", "cytoplasm viscosity"))
    n = len(rows)
    field_maps, shape_maps = _maps(per_field, groups, n, mech.K, mech.seed)
    z = np.zeros(0)
    return MechanismProblem(
        mechanism=mech, cell=cell, names=tuple(r[0] for r in rows), units=tuple(r[1] for r in rows),
        descriptions=tuple(r[3] for r in rows), kinds=tuple(r[2] for r in rows), lower=np.full(n, -np.inf),
        upper=np.full(n, np.inf), free=np.ones(n, bool), fixed_log=np.zeros(n),
        n_field=n - int(mech.viscosity), field_maps=field_maps, shape_maps=shape_maps,
        eta_index=n - 1 if mech.viscosity else None, L_ref=float(cell.strut_length),
        lengths=np.asarray(cell.lengths, float), T0=np.asarray(cell.T0, float), sources=(), omega=z,
        dataset_index=z.astype(int), group_index=z.astype(int), group_log_offset=z, group_map=np.zeros((0, 0)),
        group_measured=z, y_obs=z, weights=z, prestress_start=n)


def load_any_fit(path):
    """The model in a fit.json: a :class:`FittedMechanism`, or the per-tendon fit's
    :class:`~tenscell.fitting.fitted.FittedModel`. ValueError naming the file otherwise."""
    from .fitted import load_fit

    path = Path(path)
    try:
        obj = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return load_fit(path)  # its messages name the file and the problem
    model = obj.get("model") if isinstance(obj, dict) else None
    if isinstance(model, dict) and model.get("format") == MECHANISM_FORMAT:
        try:
            return FittedMechanism.from_dict(model)
        except (KeyError, TypeError, ValueError) as err:
            raise ValueError(f"--from-fit {path}: the fitted mechanism cannot be rebuilt: {err}") from None
    return load_fit(path)


def mechanism_report_quantities(fit: "MechanismFit") -> dict[str, np.ndarray]:
    """The numbers a mechanism fit's report derives from its parameters: ``stiffness_spread`` (decades) and
    ``assignment_spread`` (largest sd of G', G'' between assignments, decades)."""
    return {"stiffness_spread": np.array([fit.stiffness_spread]),
            "assignment_spread": np.asarray(fit.assignment_spread, dtype=float)}


@dataclass(frozen=True, eq=False, repr=False)
class MechanismFit:
    """The outcome of :func:`fit_mechanism`.

    Attributes
    ----------
    mechanism : Mechanism
    problem : MechanismProblem
    theta : ndarray
        Free log-parameters of the best fit.
    parameters : tuple of FitParameter
    datasets : tuple of RheologyData
    rms_log10_error : float
        RMS of the log10 errors over all data (decades).
    dataset_rms : tuple of float
        Per data set (decades).
    noise : tuple of (float or None)
        Per data set, the RMS of its stated standard deviations in log10 G (decades), None without sd columns.
    tolerance : float
    converged : bool
        Every data set within ``tolerance`` or within its stated noise (:func:`~tenscell.fitting.result.accepted`);
        :attr:`tolerance_met` says whether the tolerance itself was met.
    message : str
    alternatives : tuple of FitAlternative
        Other starts that fit as well (RMS within ``AS_WELL`` × the best), best first.
    starts, seed, elapsed_s, n_evaluations, stop_reason
    """

    mechanism: Mechanism
    problem: MechanismProblem
    theta: np.ndarray
    parameters: tuple
    datasets: tuple
    rms_log10_error: float
    dataset_rms: tuple
    noise: tuple
    tolerance: float
    converged: bool
    message: str
    alternatives: tuple
    starts: int
    seed: int | None
    elapsed_s: float
    n_evaluations: int
    stop_reason: str = ""

    def __repr__(self) -> str:
        per = ", ".join(f"{r:.3g}" for r in self.dataset_rms)
        return format_repr(f"MechanismFit {self.mechanism.name}: {self.n_free} free parameters",
                           f"rms per data set {per} decades; {self.verdict}",
                           self.message)

    @property
    def n_free(self) -> int:
        """Free parameters of the fit."""
        return self.problem.n_free

    @property
    def tolerance_met(self) -> bool:
        """Every data set's RMS within :attr:`tolerance`; :attr:`converged` also accepts one inside its noise."""
        return all(r <= self.tolerance for r in self.dataset_rms)

    @property
    def verdict(self) -> str:
        """``"converged"``, ``"inside the data's noise (tolerance not met)"`` or ``"NOT converged"``."""
        return verdict_text(self.converged, self.tolerance_met)

    def value(self, name: str) -> float:
        """A parameter's value (SI units)."""
        for p in self.parameters:
            if p.name == name:
                return p.value
        raise ValueError(f"no parameter named {name!r}; parameters: {', '.join(p.name for p in self.parameters)}")

    @property
    def stiffness_spread(self) -> float:
        """log10(max/min) of the per-tendon stiffnesses, over every assignment (decades)."""
        return self.problem.stiffness_spread(self.theta)

    @property
    def assignment_spread(self) -> tuple[float, float]:
        """Largest standard deviation (decades) of G', G'' between the K assignments at the data points."""
        return self.problem.assignment_spread(self.theta)

    @property
    def sigma_known(self) -> bool:
        """Every data set states its noise (sd columns): residuals are in units of it."""
        return all(n is not None for n in self.noise)

    def identifiability(self, rtol: float = 1e-8):
        """Local rank, standard errors and determined combinations (:mod:`.identifiability`); the default
        tolerance's analysis is computed once (the report, fit.json and :attr:`derived` all ask for it)."""
        if rtol == 1e-8:
            return self._identifiability
        from .identifiability import identifiability

        return identifiability(self.problem, self.theta, sigma_known=self.sigma_known, rtol=rtol)

    @cached_property
    def _identifiability(self):
        from .identifiability import identifiability

        return identifiability(self.problem, self.theta, sigma_known=self.sigma_known, rtol=1e-8)

    @cached_property
    def derived(self):
        """The numbers the report derives from the parameters (tendon-stiffness spread, spread of G', G'' between
        assignments), each with its standard error: a :class:`~tenscell.fitting.derived.DerivedQuantities`
        (the per-tendon fit's delta method, :func:`~tenscell.fitting.derived.derived_quantities`)."""
        from .derived import derived_quantities

        return derived_quantities(self, mechanism_report_quantities)

    def information_criteria(self) -> tuple[float, float]:
        """(AIC, BIC) of the log10 residuals, ``k`` = free parameters (:func:`.models.information_criteria`)."""
        from .scores import information_criteria

        aic, bic, _ = information_criteria(self.problem.residuals(self.theta), self.n_free,
                                           sigma_known=self.sigma_known, weights=self.problem.weights)
        return aic, bic

    def alternative_spread(self) -> dict:
        """Per free parameter, the spread ``log10(max/min)`` (decades) over the best fit and the alternatives."""
        out = {}
        for i, p in enumerate(self.parameters):
            if not p.vary:
                continue
            vals = [p.value] + [a.parameters[i].value for a in self.alternatives]
            out[p.name] = float(np.log10(max(vals) / min(vals)))
        return out

    def model(self) -> FittedMechanism:
        """The fitted mechanism as a model (:class:`FittedMechanism`)."""
        vals = {p.name: p.value for p in self.parameters[: self.problem.prestress_start]}
        names = [p.name for p in self.parameters]
        s = self.value("s") if "s" in names else None
        P = None if s is not None else self.value(next(n for n in names if n == "P" or n.startswith("P[")))
        measured = [float(x) for x in self.problem.group_measured if np.isfinite(x)]
        fitted = [self.value(n) for n in names if n.startswith("P_data")]
        return FittedMechanism(mechanism=self.mechanism, cell=self.problem.cell, values=vals, s=s, P=P,
                               prestress_pa=tuple(measured + fitted),
                               source=" + ".join(self.problem.sources))

    def dataset_prestress_pa(self, k: int) -> float | None:
        """The prestress (Pa) of data set ``k`` when it has a single one (stated, or fitted as P_data[k])."""
        d = self.datasets[k]
        if d.prestress is not None:
            u = np.unique(d.prestress)
            return float(u[0]) if u.size == 1 else None
        name = f"P_data[{k}]"
        return self.value(name) if name in [p.name for p in self.parameters] else None

    def moduli(self, f_hz, prestress_pa: float | None = None, *, dataset: int | None = None):
        """G', G'' (Pa) at ``f_hz`` (Hz): at ``prestress_pa`` (Pa), or at data set ``dataset``'s prestress."""
        if prestress_pa is None and dataset is not None:
            prestress_pa = self.dataset_prestress_pa(dataset)
        return self.model().moduli(f_hz, prestress_pa)

    def to_dict(self) -> dict:
        """JSON-ready (fit.json): the parameters, the verdict, the spreads and the model."""
        ident = self.identifiability()
        aic, bic = self.information_criteria()
        return {
            "kind": "mechanism-fit", "mechanism": self.mechanism.name, "description": self.mechanism.description,
            "sources": list(self.problem.sources), "n_free_parameters": self.n_free,
            "n_residuals": self.problem.n_residuals, "rms_log10_error": self.rms_log10_error,
            "rms_log10_error_per_dataset": list(self.dataset_rms), "noise_rms_log10_per_dataset": list(self.noise),
            "tolerance": self.tolerance, "converged": self.converged, "tolerance_met": self.tolerance_met,
            "message": self.message,
            "stiffness_spread_decades": self.stiffness_spread,
            "derived": self.derived.to_dict(),
            "assignment_spread_decades": list(self.assignment_spread), "assignments_K": self.mechanism.K,
            "AIC": aic, "BIC": bic,
            "parameters": [p.to_dict() for p in self.parameters],
            "standard_errors_ln": {n: (float(s) if np.isfinite(s) else None)
                                   for n, s in zip(ident.names, ident.standard_errors)},
            "alternative_spread_decades": self.alternative_spread(),
            "alternatives": [a.to_dict() for a in self.alternatives],
            "starts": self.starts, "seed": self.seed, "elapsed_s": self.elapsed_s,
            "n_evaluations": self.n_evaluations, "stop_reason": self.stop_reason,
            "model": self.model().to_dict(),
        }

    def parameters_dataframe(self):
        """The parameters with standard errors (ln units) and the spread over alternatives (decades)."""
        ident = self.identifiability()
        se = dict(zip(ident.names, ident.standard_errors))
        alt = self.alternative_spread()
        return dataframe({"name": [p.name for p in self.parameters], "value": [p.value for p in self.parameters],
                          "unit": [p.unit for p in self.parameters],
                          "at_bound": [p.at_bound or "" for p in self.parameters],
                          "standard_error_ln": [se.get(p.name, np.nan) for p in self.parameters],
                          "alternatives_spread_decades": [alt.get(p.name, np.nan) for p in self.parameters]})


def fit_mechanism(data, model, cell: Cell | None = None, *, starts: int = 4, seed: int | None = 0, jobs: int = 1,
                  tolerance: float = 0.01, hops: int = 30, patience: int = 6, max_nfev: int = 100,
                  polish: float = 0.2, polish_effort: float = 0.5, bounds: dict | None = None,
                  fixed: dict | None = None, max_points: int | None = 100,
                  progress: bool | None = None) -> MechanismFit:
    """Fit a mechanism (a name of :data:`~tenscell.fitting.models.mechanism.MECHANISMS` or a spec) to data.

    Options as for :func:`tenscell.fitting.fit`; ``bounds`` and ``fixed`` as
    for :func:`~tenscell.fitting.models.mechanism_problem.make_mechanism_problem`.
    """
    from ..io.thinning import bin_datasets
    from ..model.shapes import paper_cell
    from .models.voigt import as_datasets
    from .search import _best, run_search

    t_begin = time.monotonic()
    datasets = as_datasets(data)
    if max_points is not None:
        datasets = bin_datasets(datasets, int(max_points))
    cell = paper_cell() if cell is None else cell
    problem = make_mechanism_problem(datasets, model, cell, bounds=bounds, fixed=fixed)
    chains, stop = run_search(problem, starts=starts, seed=seed, jobs=jobs, tolerance=tolerance, hops=hops,
                              patience=patience, max_nfev=max_nfev, polish=polish, polish_effort=polish_effort,
                              progress=progress, desc=f"fit ({problem.mechanism.name})", t_begin=t_begin)
    best = _best(chains)
    theta = best.theta if best.met_theta is None else best.met_theta
    assert theta is not None  # every chain that ran holds a point
    per_set = tuple(float(x) for x in problem.dataset_rms(theta))
    noise = tuple(noise_rms(datasets))
    rms = problem.rms(theta)
    return MechanismFit(
        mechanism=problem.mechanism, problem=problem, theta=theta, parameters=problem.parameters(theta),
        datasets=datasets, rms_log10_error=rms, dataset_rms=per_set, noise=noise, tolerance=float(tolerance),
        converged=accepted(per_set, noise, tolerance),
        message=_verdict(per_set, noise, tolerance, len(chains), best, stop),
        alternatives=tuple(FitAlternative(start=ch.start, rms_log10_error=ch.rms, parameters=problem.parameters(ch.theta))
                           for ch in sorted(chains, key=lambda c: (c.rms, c.start))
                           if ch is not best and ch.theta is not None and ch.rms <= AS_WELL * rms),
        starts=len(chains), seed=seed, elapsed_s=time.monotonic() - t_begin,
        n_evaluations=sum(ch.nfev for ch in chains), stop_reason=stop)


def _verdict(per_set, noise, tolerance, n_starts, best, stop) -> str:
    """The fit's verdict in words: against the tolerance, and against the data's noise where stated."""
    parts = []
    for k, (r, n) in enumerate(zip(per_set, noise)):
        head = f"data set {k}: rms {r:.4g}"
        if inside_noise(r, n):
            met = f" <= tolerance {tolerance:g}" if r <= tolerance else f" > tolerance {tolerance:g} (not met)"
            parts.append(f"{head}{met}, inside the data's noise ({n:.3g} decades)")
        elif r <= tolerance:
            parts.append(f"{head} <= tolerance {tolerance:g}")
        else:
            parts.append(f"{head} > tolerance {tolerance:g}" + (f" and above the data's noise {n:.3g}" if n else ""))
        if n is not None and tolerance < n:
            parts[-1] += f" (the tolerance {tolerance:g} is below this noise: the data cannot confirm it)"
    return "; ".join(parts) + f" (best of {n_starts} start(s), start {best.start}; search stopped: {stop})"

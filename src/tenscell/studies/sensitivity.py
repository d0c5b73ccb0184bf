"""The sensitivity study: elasticities, the ±10 % table, its summary by group and Monte Carlo at one base point.

The paper's claim "a 10 % change of a parameter changes the moduli by a few percent (at most 8 %)" checked with
the tools of :mod:`tenscell.sensitivity`.
"""
from __future__ import annotations

from typing import Any
from dataclasses import dataclass

import numpy as np

from .._checks import positive_scalar
from .._progress import stage
from .._results import dataframe, format_repr
from .._threads import hot_path
from ..sensitivity import (PAPER_BOUND, SENSITIVITY_FREQUENCIES, Elasticities, base_parameters, elasticities,
                           monte_carlo, perturbation_table, summarize)

__all__ = ["SensitivityStudy", "sensitivity_study", "paper_cell_of_fit", "MONTE_CARLO_SETS"]

#: the Monte Carlo sets of the study: every parameter varied, then the material parameters only
MONTE_CARLO_SETS = ("all", "material")


@dataclass(frozen=True, eq=False, repr=False)
class SensitivityStudy:
    """Elasticities, the ±change table, its group summary and Monte Carlo, for one base point.

    Attributes
    ----------
    elasticities : Elasticities
    table : list of PerturbationRow
    summary : list of GroupSummary
    monte_carlo : tuple of MonteCarloResult
        All parameters, then the material parameters only.
    change : float
        Relative change of the one-at-a-time table (fraction).
    alpha_change : float
        Shift of α in the table (rad).
    bound : float
        The claim checked: a ``change`` in gives at most ``bound`` out (fraction).
    describe : str
        The base cell.
    P, L, alpha, delta : float
        Base prestress (N), strut length (m), reference angles (rad).
    EA, c : ndarray, shape (m,)
        Base tendon stiffness (N) and damping (N·s/m).
    """

    elasticities: Elasticities
    table: list
    summary: list
    monte_carlo: tuple
    change: float
    alpha_change: float
    bound: float
    describe: str
    P: float
    L: float
    alpha: float
    delta: float
    EA: np.ndarray
    c: np.ndarray

    def __repr__(self) -> str:
        holds = [g.group for g in self.summary if g.holds]
        fails = [g.group for g in self.summary if g.holds is False]
        return format_repr(
            f"SensitivityStudy of {self.describe} at P = {self.P:g} N",
            f"±{100 * self.change:g}% one at a time: holds ≤ {100 * self.bound:g}% for {len(holds)} groups, "
            f"fails for {len(fails)}" + (f" ({', '.join(fails)})" if fails else ""),
            f"Monte Carlo: {', '.join(f'{100 * m.fraction_within(self.bound):.1f}% within' for m in self.monte_carlo)}",
        )

    def to_dataframe(self):
        """The group summary: one row per parameter group."""
        s = self.summary
        return dataframe({
            "group": [x.group for x in s], "n": [x.n for x in s],
            "max_abs_elasticity_storage": [x.max_elasticity_storage for x in s],
            "max_abs_elasticity_loss": [x.max_elasticity_loss for x in s],
            "max_change_storage": [x.max_change_storage for x in s], "max_change_loss": [x.max_change_loss for x in s],
            "holds": [x.holds for x in s], "note": [x.note for x in s],
        }, {"change": self.change, "bound": self.bound, "prestress_N": self.P})

    def plot(self, ax=None, **kw):
        """The elasticities of G' against frequency (see :meth:`Elasticities.plot`)."""
        return self.elasticities.plot(ax=ax, **kw)


@hot_path
def sensitivity_study(
    draws: int = 200,
    *,
    seed: int = 0,
    change: float = 0.10,
    alpha_change: float | None = None,
    bound: float = PAPER_BOUND,
    alpha: float = 0.0,
    delta: float | None = None,
    L: float = 1.0,
    P: float = 1000.0,
    EA=1.0,
    c=1.0,
    f_hz=SENSITIVITY_FREQUENCIES,
    progress: bool | None = None,
) -> SensitivityStudy:
    """The paper's "10% in, at most 8% out", checked every way: elasticities, ±change table, Monte Carlo.

    Parameters as in :func:`elasticities`, :func:`perturbation_table` and
    :func:`monte_carlo` (``change`` is also the Monte Carlo spread).
    """
    bound = positive_scalar("bound", bound)
    base = dict(alpha=alpha, delta=delta, L=L, P=P, EA=EA, c=c, f_hz=f_hz)
    stage("sensitivity: elasticities", progress=progress)
    el = elasticities(**base)
    stage(f"sensitivity: ±{100 * change:g}% one at a time", progress=progress)
    table = perturbation_table(change=change, alpha_change=alpha_change, **base)
    mcs = tuple(monte_carlo(draws, spread=change, seed=seed, parameters=which, alpha_spread=alpha_change,
                            progress=progress, **base) for which in MONTE_CARLO_SETS)
    return _sensitivity(el, table, mcs, change=change, alpha_change=alpha_change, bound=bound, **base)


def _sensitivity(el, table, mcs, *, change, alpha_change, bound, alpha, delta, L, P, EA, c, f_hz) -> SensitivityStudy:
    """The study from its parts (the base point's options as given to each part)."""
    cell, EA_, c_ = base_parameters(alpha, delta, L, P, EA, c, True)
    return SensitivityStudy(
        elasticities=el, table=table, summary=summarize(el, table, bound), monte_carlo=mcs, change=float(change),
        alpha_change=float(change if alpha_change is None else alpha_change), bound=bound, describe=cell.describe(),
        P=float(P), L=float(L), alpha=float(alpha), delta=float(cell.parameters["delta"]), EA=EA_, c=c_,
    )


def paper_cell_of_fit(path) -> dict:
    """The base point of the study for the fitted paper cell in fit.json ``path``: ``alpha``, ``delta``, ``L``,
    ``P``, ``EA``, ``c`` (ValueError naming ``--from-fit`` when the fit is not one of the paper's Voigt cell)."""
    from ..fitting.fitted import load_fit

    model: Any = load_fit(path)  # a fitted Voigt cell once its capabilities say so (EA, c, L)
    if not model.capabilities.voigt_options:  # the study varies the Voigt cell's own α, δ, L, EA and c
        raise ValueError(f"--from-fit {path}: the sensitivity study varies the paper cell's α, δ, L, EA and c; this "
                         f"fit is {model.describe()}, not a fit of the Voigt cell (tenscell fit without --model)")
    p = model.cell.parameters
    if not {"alpha", "delta"} <= set(p) or not p.get("intermediate_filaments", False):
        raise ValueError(f"--from-fit {path}: the sensitivity study varies the paper cell's α, δ and L; this fit's "
                         f"cell is {model.cell.describe()}")
    return {"alpha": float(p["alpha"]), "delta": float(p["delta"]), "L": model.L, "P": model.prestress(),
            "EA": model.EA, "c": model.c}


# ---- the study protocol (tenscell study sensitivity) -----------------------------------------------------------
#: the elasticities and the ±10 % table in units of the elasticities alone (:func:`elasticities`), as measured
ONE_AT_A_TIME_UNITS = 2.5
#: draws of the Monte Carlo set of every parameter timed for the estimate (the unit: one draw of the probe, the
#: cell built once for all its draws), and one draw of each set in that unit, as measured
#: (bench/calibrate_study_units.py)
PROBE_DRAWS = 16
DRAW_UNITS = {"all": 0.75, "material": 0.12}


def _one_at_a_time(change, base: dict) -> tuple:
    return elasticities(**base), perturbation_table(change=change, **base)


def _monte_carlo_set(draws: int, seed: int, which: str, change: float, base: dict):
    return monte_carlo(draws, spread=change, seed=seed, parameters=which, progress=False, **base)


class _Sensitivity:
    """``tenscell study sensitivity``: the elasticities and the ±10 % table (one task), each Monte Carlo set (one
    task each, ``draws`` units); ``from_fit``: the base point of a fit of the paper cell (a fit.json)."""

    name = "sensitivity"
    options = {"draws": 200, "seed": 0, "from_fit": None}

    def plan(self, options):
        from .._parallel import usable_cpus
        from ..fitting.search import count
        from .protocol import Plan, Task, study_options

        opts = study_options(self, options)
        draws = count("--draws", opts["draws"], 1)
        base = dict(alpha=0.0, delta=None, L=1.0, P=1000.0, EA=1.0, c=1.0, f_hz=SENSITIVITY_FREQUENCIES)
        if opts["from_fit"] is not None:
            base.update(paper_cell_of_fit(opts["from_fit"]))
        change = 0.10
        tasks = [Task("elasticities and the ±10 % table", "elasticities", _one_at_a_time, (change, base),
                      weight=ONE_AT_A_TIME_UNITS)]
        tasks += [Task(f"Monte Carlo, {which} parameters ({draws} draws)", "draw", _monte_carlo_set,
                       (draws, opts["seed"], which, change, base),
                       weight=float(draws) * DRAW_UNITS[which])
                  for which in MONTE_CARLO_SETS]
        probes = [Task("the elasticities", "elasticities", elasticities, (), weight=1.0),
                  Task(f"{PROBE_DRAWS} Monte Carlo draws", "draw", _monte_carlo_set,
                       (PROBE_DRAWS, opts["seed"], "all", change, base), weight=float(PROBE_DRAWS))]
        return Plan(self.name, {**opts, "base": base, "change": change}, tuple(tasks), calibration=tuple(probes),
                    figures=8.0, jobs=min(usable_cpus(), len(tasks)), sized_by=("--draws",))

    def assemble(self, plan, results):
        from .._results import reporter
        from .protocol import Figure, StudyResult, Table

        el, table = results[plan.tasks[0].key]
        mcs = tuple(results[t.key] for t in plan.tasks[1:])
        s = _sensitivity(el, table, mcs, change=plan.options["change"], alpha_change=None, bound=PAPER_BOUND,
                         **plan.options["base"])
        f = el.frequency_hz
        tables = (
            Table.from_records("elasticities", [
                {"parameter": n, "group": g, "value": float(v), "method": m, "frequency_Hz": float(f[k]),
                 "dlnGstorage_dlnp": float(el.storage[i, k]), "dlnGloss_dlnp": float(el.loss[i, k])}
                for i, (n, g, v, m) in enumerate(zip(el.names, el.groups, el.values, el.methods))
                for k in range(f.size)]),
            Table.from_records("perturbations", [
                {"parameter": r.name, "group": r.group, "dGstorage_minus": r.storage[0], "dGstorage_plus": r.storage[1],
                 "dGloss_minus": r.loss[0], "dGloss_plus": r.loss[1], "note": r.note} for r in table]),
            Table.from_records("sensitivity_table", [
                {"group": x.group, "n": x.n, "max_abs_elasticity_storage": x.max_elasticity_storage,
                 "max_abs_elasticity_loss": x.max_elasticity_loss, "max_change_storage": x.max_change_storage,
                 "max_change_loss": x.max_change_loss, "holds_8pct": x.holds, "note": x.note} for x in s.summary]),
            Table.from_records("monte_carlo", [
                {"set": mc.label, "draw": i, "valid": bool(mc.valid[i]), "max_change_storage": float(mc.change_storage[i]),
                 "max_change_loss": float(mc.change_loss[i]), "reason": mc.reasons[i]}
                for mc in mcs for i in range(mc.factors.shape[0])]),
        )
        return StudyResult(self.name, tables=tables,
                           figures=(Figure("elasticities.png", "elasticities_figure", (el,)),
                                    Figure("monte_carlo.png", "monte_carlo_figure", (list(mcs),))),
                           pages=(("sensitivity.md", reporter("sensitivity_markdown")(s)),), data=s)


#: the study of ``tenscell study sensitivity`` (:mod:`tenscell.studies.protocol`)
STUDY = _Sensitivity()

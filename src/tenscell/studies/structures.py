"""Structures compared at the anchor: each mechanism on each structure, fitted with σ held to the measured prestress.

Which structure, not only which tendon law, explains the bundled pair (Stamenović et al. 2002's prestress sweep and
Fabry et al. 2001's frequency sweep at 1000 Pa)? Every mechanism of :data:`MECHANISMS` is fitted on every structure
of :data:`STRUCTURES` three times over: free, with the model's physical prestress σ
(:mod:`tenscell.model.prestress`) within ×/÷1.5 of the measured one, and with σ equal to it
(:class:`tenscell.fitting.anchor.Anchor`). Converged, as a referee would ask:

* the free fit from several seeds; each anchored fit from the best free fit (a warm start, s moved into the anchor's
  window) and from a fresh seed;
* the 30-strut sphere and the lattice, whose fits cost 10–50 times the paper cell's (:data:`HEAVY`), run the free
  fit from one seed and each anchored fit warm only;
* the table gives each (structure, mechanism, anchor) its best fit and the **band** of the RMS over every fit whose
  cost lies within 10 % of the best (:data:`BAND`): the fits the data cannot tell apart.

How a mechanism meets a structure (:func:`structure_mechanism`): its fields are laid out per family of
``cell.structure.families``, so a structure with other families gets their values too (the nucleus shell's edges
are a third family of tendon-law members; a one-family structure gets one value). Where members carry compression
(the elastic struts of the semiflexible cell and of lattices, family ``"strut"``), a spring shared with the tendons
would give a strut the tendons' EA, below its compression (a non-positive rest length): there the mechanism's EA is
laid out per family, and a compressed family's EA is bounded below by twice its largest compression over the fit's
prestresses (:func:`search_space`); its free fit keeps s in the gauge window (0.01–100 m²) so that the bound is
finite. The table counts every parameter these add.

The study follows the protocol (:mod:`tenscell.studies.protocol`): :meth:`StructuresStudy.plan` is one task per
fit, :meth:`StructuresStudy.assemble` the tables (``structures``: one row per structure, mechanism and anchor;
``structures_ranking``: each structure's best mechanism at each anchor) and the Markdown page
(:func:`tenscell.reports.structures.structures_markdown`), with goal G1 of issue 33 as a :class:`Check`.
"""
from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..fitting.anchor import Anchor, prestress_ratio
from .protocol import Check, Plan, StudyResult, Table, Task

__all__ = ["STRUCTURES", "MECHANISMS", "ANCHORS", "BAND", "G1", "StructuresStudy", "STUDY", "FitRecord",
           "structure_cell", "structure_mechanism", "search_space", "fit_task", "bundled_pair", "structures_study"]


def _paper():
    from ..model.shapes import paper_cell

    return paper_cell()


def _no_ifs():
    from ..model.shapes import paper_cell

    return paper_cell(intermediate_filaments=False)


def _nucleated():
    from ..model.shapes import nucleated_cell

    return nucleated_cell()


def _semiflexible():
    from ..model.shapes import semiflexible_paper_cell

    return semiflexible_paper_cell()


def _sphere12():
    from ..model.lattices import sphere_cell

    return sphere_cell(12)


def _sphere30():
    from ..model.lattices import sphere_cell

    return sphere_cell(30)


def _lattice():
    from ..model.lattices import lattice_cell

    return lattice_cell(2, 1, 1)


#: the structures compared: name -> builder of the cell (strut length 1 m)
STRUCTURES = {
    "6-strut paper cell": _paper,
    "6-strut, no IFs": _no_ifs,
    "6-strut + nucleus": _nucleated,
    "6-strut, elastic struts": _semiflexible,
    "12-strut sphere": _sphere12,
    "30-strut sphere": _sphere30,
    "lattice 2×1×1": _lattice,
}
#: the mechanisms fitted on each (the recommended one first)
MECHANISMS = ("springpot-alpha-family+visc", "springpot+visc", "maxwell+visc", "voigt-compact+visc")
#: the anchors: label -> Anchor (None: free)
ANCHORS = {"free": None, "×/÷1.5": Anchor(1.5), "exact": Anchor.exact()}
#: a fit belongs to the band when its cost is within this factor of the best fit's (of the same structure, mechanism
#: and anchor)
BAND = 1.1
#: the search of every fit (each anchored fit runs twice: warm and fresh; the free fit from each seed)
SEARCH = {"starts": 2, "hops": 6, "patience": 3, "tolerance": 0.01}
#: the free fit's seeds
SEEDS = (0, 1)
#: goal G1 of issue 33: at most this many free parameters, σ within ×/÷ this factor, RMS at most this on each set
G1 = {"max_free": 8, "factor": 1.5, "max_rms": 0.02}
#: the prestress (Pa) at which the bundled frequency sweep is placed (tenscell.cli.fit.BUNDLED_FREQUENCY_PRESTRESS_PA)
BUNDLED_FREQUENCY_PRESTRESS_PA = 1000.0
#: a compressed family's EA is bounded below by this many times its largest compression over the fit's prestresses
STRUT_MARGIN = 2.0


def bundled_pair():
    """The bundled pair: the prestress sweep (stamenovic2002) and the frequency sweep (fabry2001) at 1000 Pa."""
    from ..io.data import bundled

    return [bundled("stamenovic2002"), bundled("fabry2001").with_prestress(BUNDLED_FREQUENCY_PRESTRESS_PA)]


def structure_cell(name: str):
    """The cell of structure ``name`` (a key of :data:`STRUCTURES`)."""
    if name not in STRUCTURES:
        raise ValueError(f"structure must be one of {', '.join(STRUCTURES)}, got {name!r}")
    return STRUCTURES[name]()


def _compressed_families(cell) -> dict[str, float]:
    """{family: largest compression per unit P, −min T0 (N/N)} of the families with members in compression."""
    T0 = np.asarray(cell.T0, dtype=float)
    fams = np.asarray(cell.structure.families)
    out = {}
    for fam in dict.fromkeys(cell.structure.families):
        t = T0[fams == fam]
        if t.min() < 0:
            out[str(fam)] = float(-t.min())
    return out


def structure_mechanism(name: str, cell):
    """The mechanism ``name`` as it meets ``cell``: itself, or where members carry compression, with its spring EA
    laid out per family (module docstring)."""
    from ..fitting.models.catalog import mechanism

    mech = mechanism(name)
    if not _compressed_families(cell):
        return mech
    fields = tuple(dataclasses.replace(f, layout="family") if f.law_parameter == "EA" and f.layout == "shared" else f
                   for f in mech.fields)
    if fields == mech.fields:
        return mech
    return dataclasses.replace(mech, name=f"{mech.name} [EA per family]", fields=fields,
                               description=mech.description + "; EA per family (compression members)")


def search_space(cell, mech, datasets, anchor: Anchor | None) -> dict:
    """``bounds`` and ``fixed`` of one fit: the anchor's, and for compressed families EA ≥ :data:`STRUT_MARGIN` × their
    largest compression at the highest model prestress the fit allows (free fits of such a cell: s in the gauge
    window)."""
    from ..fitting.shares import GAUGE_WINDOW_S

    opts: dict[str, Any] = {"bounds": {}, "fixed": {}}
    if anchor is not None:
        o = anchor.options_for(mech, datasets, cell)
        opts = {"bounds": dict(o["bounds"] or {}), "fixed": dict(o["fixed"] or {})}
    compressed = _compressed_families(cell)
    if compressed:
        if anchor is None:
            opts["bounds"]["s"] = GAUGE_WINDOW_S
        s_hi = opts["fixed"].get("s", opts["bounds"].get("s", (None, None))[1])
        p_hi = max(float(np.max(d.prestress)) for d in datasets if d.prestress is not None)
        for fam, c in compressed.items():
            opts["bounds"][f"EA_{fam}"] = (STRUT_MARGIN * c * s_hi * p_hi, 1e12)
    return {k: (v or None) for k, v in opts.items()}


@dataclass(frozen=True)
class FitRecord:
    """One fit of the study (what the table needs; the fit itself stays in its worker)."""

    structure: str
    mechanism: str
    anchor: str
    start: str  # "seed 0", "warm"...
    names: tuple
    phi: tuple  # every log-parameter (natural logs), for warm starts
    n_free: int  # model parameters (free, less an exact gauge)
    rms: tuple  # per data set (decades)
    rms_total: float
    bic: float
    sigma_ratio: float  # σ/measured (NaN: not defined)
    converged: bool
    at_bound: tuple
    cpu_s: float
    error: str = ""

    @property
    def cost(self) -> float:
        return self.rms_total**2 if math.isfinite(self.rms_total) else math.inf

    @property
    def worst(self) -> float:
        return max(self.rms) if self.rms else math.nan


def _failed(structure, mechanism, anchor, start, err, cpu) -> FitRecord:
    return FitRecord(structure=structure, mechanism=mechanism, anchor=anchor, start=start, names=(), phi=(),
                     n_free=0, rms=(), rms_total=math.nan, bic=math.nan, sigma_ratio=math.nan, converged=False,
                     at_bound=(), cpu_s=cpu, error=str(err).splitlines()[0][:200])


def _warm_theta(problem, warm) -> np.ndarray | None:
    """The free log-parameters of ``problem`` at the best of ``warm`` (its s moved into the bounds or to the fixed
    value; other fixed values kept): None when no warm fit succeeded."""
    ok = [w for w in warm if w.phi and math.isfinite(w.cost)]
    if not ok:
        return None
    best = min(ok, key=lambda w: w.cost)
    by = dict(zip(best.names, best.phi))
    phi = np.array([by.get(n, f) for n, f in zip(problem.names, problem.fixed_log)])
    phi = np.clip(phi, problem.lower, problem.upper)
    return phi[problem.free]


def fit_task(structure: str, mechanism: str, anchor: str, seed: int | None, datasets, search: Mapping,
             *warm: FitRecord) -> FitRecord:
    """One fit of the study (a worker's task): ``mechanism`` on ``structure`` under ``anchor`` (a key of
    :data:`ANCHORS`), from ``seed`` or, with ``warm`` fits given, warm-started at the best of them."""
    from ..fitting import fit

    c0 = time.process_time()
    start = "warm" if warm else f"seed {seed}"
    try:
        cell = structure_cell(structure)
        mech = structure_mechanism(mechanism, cell)
        space = search_space(cell, mech, datasets, ANCHORS[anchor])
        initial = _warm_theta(mech.problem(datasets, cell, **space), warm) if warm else None
        r = fit(datasets, cell, model=mech, seed=0 if seed is None else seed, jobs=1, progress=False,
                initial=initial, **dict(search), **space)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as err:
        return _failed(structure, mechanism, anchor, start, err, time.process_time() - c0)
    ratio = prestress_ratio(r)
    return FitRecord(structure=structure, mechanism=mechanism, anchor=anchor, start=start,
                     names=tuple(r.problem.names), phi=tuple(float(x) for x in r.problem.full(r.theta)),
                     n_free=int(r.problem.n_model_parameters), rms=tuple(float(x) for x in r.dataset_rms),
                     rms_total=float(r.rms_log10_error), bic=float(r.information_criteria()[1]),
                     sigma_ratio=math.nan if ratio is None else float(ratio[0]), converged=bool(r.converged),
                     at_bound=tuple(p.name for p in r.parameters if p.vary and p.at_bound is not None),
                     cpu_s=time.process_time() - c0)


def _key(structure, mechanism, anchor, start) -> str:
    return f"{structure}/{mechanism}/{anchor}/{start}"


#: a structure whose fits weigh this much or more (relative to the paper cell's) runs fewer of them
#: (:func:`_structure_tasks`)
HEAVY = 4.0
#: relative cost of one fit on each structure (the paper cell: 1), for the estimate before the run
_WEIGHT = {"6-strut paper cell": 1.0, "6-strut, no IFs": 0.3, "6-strut + nucleus": 2.0, "6-strut, elastic struts": 1.5,
           "12-strut sphere": 1.5, "30-strut sphere": 12.0, "lattice 2×1×1": 4.0}


def _check_choice(what: str, given, allowed) -> tuple:
    given = tuple(allowed if given is None else given)
    bad = [g for g in given if g not in allowed]
    if bad or not given:
        raise ValueError(f"{what} must be a non-empty selection of {', '.join(allowed)}; got {bad[0] if bad else given!r}")
    return given


def _structure_tasks(st, mechanisms, anchors, seeds, datasets, search) -> list[Task]:
    """The fits of one structure: per mechanism the free fit from each seed, each anchored fit warm (from the free
    fits) and fresh. A heavy structure (:data:`HEAVY`) runs the free fit from the first seed and each anchored fit
    warm only, with one start: its fits cost 10–50 times the paper cell's."""
    w = _WEIGHT.get(st, 1.0)
    heavy = w >= HEAVY and "free" in anchors
    seeds = seeds[:1] if heavy else seeds
    warm_search = {**search, "starts": 1} if heavy else search
    tasks = []
    for mech in mechanisms:
        free = [_key(st, mech, "free", f"seed {s}") for s in seeds]
        if "free" in anchors:
            tasks += [Task(k, "fit", fit_task, (st, mech, "free", s, datasets, search), weight=w)
                      for k, s in zip(free, seeds)]
        for a in anchors:
            if a == "free":
                continue
            if "free" in anchors:
                tasks.append(Task(_key(st, mech, a, "warm"), "fit", fit_task,
                                  (st, mech, a, None, datasets, warm_search), needs=tuple(free),
                                  weight=w / search["starts"] if heavy else w))
            if not heavy:
                tasks.append(Task(_key(st, mech, a, f"seed {seeds[0]}"), "fit", fit_task,
                                  (st, mech, a, seeds[0], datasets, search), weight=w))
    return tasks


def _probe(datasets, search: Mapping) -> Task:
    """The calibration probe of the kind "fit": the paper cell's free fit of the recommended mechanism from one
    start with no basin hop, weighed as that share of one paper-cell fit of the study's search (its starts × its
    hops + 1 least-squares runs)."""
    probe_search = {**search, "starts": 1, "hops": 0}
    return Task("one start of a paper-cell fit", "fit", fit_task,
                ("6-strut paper cell", MECHANISMS[0], "free", 0, datasets, probe_search),
                weight=1.0 / (search["starts"] * (search["hops"] + 1)))


class StructuresStudy:
    """The study (protocol :class:`~tenscell.studies.protocol.Study`): ``name = "structures"``."""

    name = "structures"
    #: the options :meth:`plan` takes (the protocol's ``Study.options``; None: the study's default)
    options: Mapping[str, Any] = {"datasets": None, "structures": None, "mechanisms": None, "anchors": None,
                                  "seeds": None, "search": None}

    def plan(self, options: Mapping[str, Any]) -> Plan:
        """Options: ``datasets`` (default :func:`bundled_pair`), ``structures``, ``mechanisms``, ``anchors``
        (selections of :data:`STRUCTURES`, :data:`MECHANISMS`, :data:`ANCHORS`), ``seeds`` (the free fit's),
        ``search`` (overrides of :data:`SEARCH`)."""
        from ..fitting.parameters import as_datasets

        opts = dict(options or {})
        unknown = set(opts) - {"datasets", "structures", "mechanisms", "anchors", "seeds", "search"}
        if unknown:
            raise ValueError(f"study structures: unknown option {sorted(unknown)[0]!r}")
        datasets = as_datasets(opts.get("datasets") or bundled_pair())
        if not any(d.prestress is not None for d in datasets):
            raise ValueError("study structures: no data set states its prestress (Pa), so σ has nothing to be "
                             "anchored to")
        structures = _check_choice("structures", opts.get("structures"), tuple(STRUCTURES))
        mechanisms = _check_choice("mechanisms", opts.get("mechanisms"), MECHANISMS)
        anchors = _check_choice("anchors", opts.get("anchors"), tuple(ANCHORS))
        seeds = tuple(int(s) for s in (opts.get("seeds") or SEEDS)) or SEEDS
        search = {**SEARCH, **dict(opts.get("search") or {})}
        tasks = []
        for st in structures:
            tasks += _structure_tasks(st, mechanisms, anchors, seeds, datasets, search)
        return Plan(study=self.name, options={"datasets": datasets, "structures": structures,
                                              "mechanisms": mechanisms, "anchors": anchors, "seeds": seeds,
                                              "search": search}, tasks=tuple(tasks),
                    calibration=(_probe(datasets, search),), sized_by=("the study's structures and mechanisms",))

    def assemble(self, plan: Plan, results: Mapping[str, Any]) -> StudyResult:
        records = [results[t.key] for t in plan.tasks]
        rows = _rows(records, plan.options)
        table = Table.from_records("structures", rows, description=(
            "each mechanism on each structure, free and with σ anchored; best fit and the band of fits within "
            f"{100 * (BAND - 1):.0f} % of its cost"))
        ranking = Table.from_records("structures_ranking", _ranking(rows), description=(
            "each structure's best mechanism (≤ 8 free parameters when one fits) at each anchor, ranked by the worse "
            "of its two RMS"))
        check = _g1(rows)
        study = StructuresResult(table=table, ranking=ranking, records=tuple(records), check=check,
                                 sources=tuple(d.source for d in plan.options["datasets"]))
        from .._results import reporter

        page = reporter("structures_markdown")(study)
        return StudyResult(study=self.name, tables=(table, ranking), pages=(("structures.md", page),),
                           checks=(check,), data=study, summary=check.detail)


@dataclass(frozen=True, eq=False)
class StructuresResult:
    """The study's own result: the two tables, every fit's record, the G1 check and the data's sources."""

    table: Table
    ranking: Table
    records: tuple
    check: Check
    sources: tuple

    @property
    def cpu_s(self) -> float:
        """CPU seconds of every fit (each measured in its worker)."""
        return float(sum(r.cpu_s for r in self.records))


def _group(records, options) -> dict:
    groups: dict = {}
    for r in records:
        groups.setdefault((r.structure, r.mechanism, r.anchor), []).append(r)
    return groups


def _row(st, mech, anchor, fits, sources) -> dict:
    ok = [f for f in fits if f.phi and math.isfinite(f.cost)]
    best = min(ok, key=lambda f: f.cost) if ok else None
    band = [f for f in ok if best is not None and f.cost <= BAND * best.cost]
    nan = math.nan
    row = {"structure": st, "mechanism": mech, "anchor": anchor,
           "n_free": best.n_free if best else 0}
    for k, src in enumerate(sources):
        row[f"rms_{_short(src)}_decades"] = best.rms[k] if best else nan
    row.update({
        "worst_rms_decades": best.worst if best else nan,
        "cost": best.cost if best else math.inf,
        "worse_than_tighter": False,
        "band_worst_rms_lo_decades": min(f.worst for f in band) if band else nan,
        "band_worst_rms_hi_decades": max(f.worst for f in band) if band else nan,
        "fits": len(fits), "fits_in_band": len(band),
        "sigma_over_measured": best.sigma_ratio if best else nan,
        "bic": best.bic if best else nan,
        "converged": bool(best.converged) if best else False,
        "at_bound": ", ".join(best.at_bound) if best else "",
        "cpu_s": float(sum(f.cpu_s for f in fits)),
        "errors": "; ".join(sorted({f.error for f in fits if f.error})),
    })
    return row


def _short(source: str) -> str:
    """``stamenovic2002`` from ``bundled:stamenovic2002`` or a file name (column names)."""
    s = str(source).split(":")[-1].rsplit("/", 1)[-1]
    s = s.rsplit(".", 1)[0] if "." in s else s
    return "".join(ch if ch.isalnum() else "_" for ch in s).strip("_") or "data"


#: the anchors from the loosest to the tightest: on a structure without compression members each one's fits are
#: fits of the looser ones too (the same parameters, narrower bounds of s)
_NESTED = ("free", "×/÷1.5", "exact")


def _mark_unconverged(rows: list[dict], nested: bool) -> None:
    """``worse_than_tighter``: a row whose best cost exceeds a tighter anchor's by more than 1 % (a fit of the tighter
    problem is a fit of this one: this row's search did not reach its optimum). Only where the anchors nest."""
    if not nested:
        return
    by = {r["anchor"]: r for r in rows}
    for i, a in enumerate(_NESTED):
        if a in by:
            costs = [by[t]["cost"] for t in _NESTED[i + 1:] if t in by]
            by[a]["worse_than_tighter"] = any(by[a]["cost"] > 1.01 * c for c in costs)


def _rows(records, options) -> list[dict]:
    sources = tuple(d.source for d in options["datasets"])
    groups = _group(records, options)
    out = []
    for st in options["structures"]:
        nested = not _compressed_families(structure_cell(st))
        for mech in options["mechanisms"]:
            mine = [_row(st, mech, a, groups[(st, mech, a)], sources) for a in options["anchors"]
                    if (st, mech, a) in groups]
            _mark_unconverged(mine, nested)
            for r in mine:
                r.pop("cost")
            out += mine
    return out


def _ranking(rows) -> list[dict]:
    out = []
    for a in dict.fromkeys(r["anchor"] for r in rows):
        ranked = []
        for st in dict.fromkeys(r["structure"] for r in rows):
            mine = [r for r in rows if r["structure"] == st and r["anchor"] == a and math.isfinite(r["worst_rms_decades"])]
            if not mine:
                continue
            small = [r for r in mine if r["n_free"] <= G1["max_free"]] or mine
            ranked.append(min(small, key=lambda r: (r["worst_rms_decades"], r["bic"])))
        ranked.sort(key=lambda r: r["worst_rms_decades"])
        for i, r in enumerate(ranked, 1):
            out.append({"anchor": a, "rank": i, "structure": r["structure"], "best_mechanism": r["mechanism"],
                        "n_free": r["n_free"], "worst_rms_decades": r["worst_rms_decades"],
                        "band_worst_rms_lo_decades": r["band_worst_rms_lo_decades"],
                        "band_worst_rms_hi_decades": r["band_worst_rms_hi_decades"],
                        "sigma_over_measured": r["sigma_over_measured"], "bic": r["bic"]})
    return out


def _g1(rows) -> Check:
    """G1: ≤ 8 free parameters, σ within ×/÷1.5 (or exact), RMS ≤ 0.02 on each set — across the band."""
    label = (f"G1: ≤ {G1['max_free']} free parameters, σ within ×/÷{G1['factor']:g} of the measured prestress, RMS ≤ "
             f"{G1['max_rms']:g} on each bundled set")
    cands = [r for r in rows if r["anchor"] != "free" and r["n_free"] <= G1["max_free"]
             and math.isfinite(r["worst_rms_decades"]) and abs(math.log(r["sigma_over_measured"])) <=
             math.log(G1["factor"]) + 1e-9]
    if not cands:
        return Check(label=label, met=False, closest="(none)", detail="no anchored fit with ≤ 8 free parameters ran")
    best = min(cands, key=lambda r: (r["worst_rms_decades"], r["bic"]))
    met = best["worst_rms_decades"] <= G1["max_rms"]
    rms = [v for k, v in best.items() if k.startswith("rms_") and k != "worst_rms_decades"]
    each = " / ".join(f"{v:.4f}" for v in rms)
    band = f"band of the worse RMS {best['band_worst_rms_lo_decades']:.4f}–{best['band_worst_rms_hi_decades']:.4f}"
    edge = "; s at its bound: σ sits at the window's edge" if "s" in best["at_bound"].split(", ") else ""
    others = [f"{r['structure']} / {r['mechanism']} / σ {r['anchor']} ({r['worst_rms_decades']:.4f})" for r in cands
              if r is not best and r["worst_rms_decades"] <= G1["max_rms"]]
    detail = (f"{best['structure']}, {best['mechanism']} ({best['n_free']} free), σ {best['anchor']} "
              f"(σ/measured {best['sigma_over_measured']:.3g}{edge}): RMS {each} ({band} over {best['fits_in_band']} "
              f"fit(s))" + ("" if met else f", {best['worst_rms_decades'] - G1['max_rms']:.4f} over")
              + (f"; also met by {'; '.join(others)}" if others else ""))
    return Check(label=label, met=bool(met), closest=f"{best['structure']} / {best['mechanism']} / {best['anchor']}",
                 detail=detail)


#: the study, for the command line's table of studies
STUDY = StructuresStudy()


def structures_study(datasets=None, *, jobs: int = 1, notify=None, **options) -> StudyResult:
    """Plan, run and assemble the study (the Python entry point; ``tenscell study structures`` on the command line).

    ``options``: see :meth:`StructuresStudy.plan`. Returns the :class:`StudyResult`; its ``data`` is a
    :class:`StructuresResult`.
    """
    from .protocol import run_study

    return run_study(STUDY, {**options, "datasets": datasets}, jobs=jobs, notify=notify)

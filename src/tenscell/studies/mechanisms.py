"""Which mechanism explains the cells: every mechanism fitted to the same data, scored as a referee would.

For each model (the paper's per-tendon Voigt fit, every mechanism of :data:`tenscell.fitting.MECHANISMS`, and the
structure-free baselines every tensegrity has to beat) the study fits the data sets jointly and records the free
parameters, the tendon-stiffness spread, the RMS of the log10 errors per data set, AIC and BIC, how many parameters
the data determine within 10 %, convergence, the ripple and range of the local G' slope, and what the structure
carries (:mod:`tenscell.fitting.shares`: the share of dG′/dP and dG″/dP over the data's prestress range carried by
the geometric prestress stiffness P·Kp). Then it referees every tensegrity that describes the data in sample (worst
RMS ≤ :data:`REFEREE_MAX_RMS`; one that misses them in sample has nothing to defend out of sample), and every refit
runs to the main fit's standard (:func:`tenscell.fitting.validation.refit`: the main fit's search budget, start 0
warm at the main fit, the others fresh):

* **baselines at their strongest** (:func:`baseline_pool`): the structural-damping laws (P entering G′ and G″ alike:
  ``(G0 + g·P)·Γ(1−α)(iω)^α + iωη``), and every refereed mechanism's lumped terms as a parallel network (its own
  formula, :meth:`~tenscell.fitting.models.base.FitModel.formula`) and as a series network
  (:func:`~tenscell.fitting.models.formulas.series_formula`); a tensegrity is judged against the best of those with
  no more free parameters than it has — on the mean and on every split;
* **out of sample** (:mod:`tenscell.fitting.validation`): every model and baseline refitted on every held-out split
  (the prestress sweep without its top third, without every third prestress, trained at P ≤ 1000 Pa; the frequency
  sweep trained at or below 0.3, 1, 3, 10, 30 Hz), each refit's training RMS beside its held-out score (a refit
  above 1.5× the main fit's RMS on the same points did not converge and is in no ranking or verdict), the held-out
  score a band over the fits the training data cannot tell apart; a verdict holds only across the band;
* **anchored** (:func:`anchor_options`): refitted with the model's prestress held to the measured one, σ/measured
  printed;
* **falsification at the anchor** (:mod:`tenscell.studies.falsification`): the anchored model fitted to data cells
  do not show, on the same grids, prestresses and noise (stiffness independent of prestress; an exponent rising with
  prestress; G″ independent of prestress): its RMS there over its anchored RMS on the cell data; below
  :data:`DISCRIMINATES` it does not discriminate;
* **the exponent test**: α, the local G′ slope at :data:`EXPONENT_FREQUENCY_HZ` (0.1 Hz), from the lowest to the
  highest measured prestress (350–1900 Pa on the bundled lines), of the anchored fit to the real lines and of the
  anchored fit to lines with a flat loss tangent (G′ kept): a structure whose exponent still falls there gets the
  fall from itself, not from the training lines.

The study follows the study protocol (:mod:`tenscell.studies.protocol`): :class:`MechanismsStudy` plans every fit as
a task (a refit needs the fit it starts from), and assembles the result (:class:`MechanismStudy`, its tables and
goals). :func:`mechanisms_study` runs it from Python. Every number comes from the run's own fits.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Mapping, cast

import numpy as np

from ..fitting.models.catalog import MECHANISMS, PER_TENDON_VOIGT
from ..fitting.anchor import DEFAULT_FACTOR
from ..fitting.shares import GAUGE_WINDOW_S
from ..population.ensemble import DEFAULT_K

if TYPE_CHECKING:
    from ..fitting.validation import OutOfSampleComparison
    from ..population.ensemble import EnsembleResult

__all__ = ["MechanismRow", "MechanismStudy", "MechanismsStudy", "mechanisms_study", "GOALS", "SLOPE_GRID_PER_DECADE",
           "ANCHOR_S", "Anchored", "Falsified", "ExponentTest", "BaselineVerdict", "DISCRIMINATES", "ISSUE33_GOALS",
           "REFEREE_MAX_RMS", "EXPONENT_FREQUENCY_HZ", "ANCHOR_FACTOR", "fits_per_model", "baseline_pool", "anchor_options",
           "exponent_change", "default_models", "study_tables", "HELDOUT_COLUMNS",
           "BASELINE_COLUMNS", "main_fit", "MainFit", "Skipped", "assemble_study", "STUDY", "evaluations_of"]

#: basin-hopping moves of the per-tendon reference fit (at least; the fit's own default)
PER_TENDON_HOPS = 30
#: local slopes are taken on this many points per decade
SLOPE_GRID_PER_DECADE = 200
#: the frequency band of the slope goal (Hz)
SLOPE_BAND_HZ = (0.01, 1000.0)
#: issue 18's goals: free parameters, stiffness spread (decades), RMS per data set (decades), share determined
#: within 10 %, slope target and its tolerance; and issue 27's CPU time of the study's fits (s)
GOALS = {"max_free": 8, "max_spread": 2.0, "max_rms": 0.02, "min_determined": 0.8, "slope": 0.20,
         "slope_tol": 0.02, "max_cpu_s": 40.0}
#: issue 33's goals the study measures: G1 (free parameters, RMS per data set, σ within a factor of the measured
#: prestress), G2 (RMS on each unlike set at least this many times the anchored cell RMS; the exponent falling by
#: this much on flat-loss-tangent lines), G3 (held-out mean and worst across the band at most this fraction of the
#: best structure-free baseline's)
ISSUE33_GOALS = {"max_free": 8, "max_rms": 0.02, "anchor_factor": 1.5, "unlike_ratio": 3.0, "exponent_fall": 0.02,
                 "baseline_factor": 0.8}
#: the prestress window of the free fit (the paper's convention: strut length L = s^(-1/2) in 0.1–10 m): a gauge
#: window, not an anchor
ANCHOR_S = GAUGE_WINDOW_S
#: the anchored fits hold the model's physical prestress σ within ×/÷ this factor of the measured prestress
ANCHOR_FACTOR = DEFAULT_FACTOR
#: a model whose RMS on an unlike data set is below this many times its RMS on the cell data does not discriminate
DISCRIMINATES = 2.0
#: the referee's refits (held out, anchored, unlike, flat loss tangent) are run for the models whose worst RMS in
#: sample is at most this (decades, 2.5× the goals' 0.02): a model that misses the data in sample is not refereed
REFEREE_MAX_RMS = 0.05
#: free parameters above which the referee's refits are left out (the 37-parameter per-tendon cell)
REFIT_MAX_FREE = 12
#: the frequency (Hz) of the exponent test: α is the local G' slope d log G'/d log f there
EXPONENT_FREQUENCY_HZ = 0.1


# ---------------------------------------------------------------------------------------
# records
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Anchored:
    """The fit with the model's prestress held to the measured one (:func:`anchor_options`)."""

    rms: tuple  # per data set, decades
    bic: float
    s: float  # prestress scale (m²)
    at_bound: tuple  # free parameters at a bound
    geometric_share: tuple  # (dG'/dP, dG''/dP) carried by P·Kp over the data's prestress range; NaN if undefined
    converged: bool
    sigma_ratio: float = math.nan  # the model's prestress σ over the measured one (NaN: not defined for this model)
    exponent_change: float = math.nan  # α at the highest measured prestress minus α at the lowest (EXPONENT_...)
    cpu_s: float = math.nan  # CPU seconds of the anchored fit

    @property
    def L(self) -> float:
        """The strut length of the paper's convention (model prestress = measured prestress): s^(−1/2)."""
        return self.s ** -0.5


@dataclass(frozen=True)
class Falsified:
    """The anchored model fitted to data cells do not show (:mod:`tenscell.studies.falsification`)."""

    kind: str
    rms: tuple  # per data set, decades
    ratio: float  # worst RMS on the unlike set over the worst anchored RMS on the cell data
    cpu_s: float = math.nan


@dataclass(frozen=True)
class ExponentTest:
    """The exponent test: α (the local G' slope at :data:`EXPONENT_FREQUENCY_HZ`) from the lowest to the highest
    measured prestress, fitted anchored to the real lines and to lines with a flat loss tangent."""

    prestress_pa: tuple  # (lowest, highest) measured prestress (Pa)
    real: float  # Δα of the anchored fit to the real lines
    flat: float  # Δα of the anchored fit to the flat-loss-tangent lines
    flat_rms: tuple  # RMS per data set of the flat-loss-tangent fit (decades)
    cpu_s: float = math.nan

    @property
    def span_kpa(self) -> float:
        return (self.prestress_pa[1] - self.prestress_pa[0]) / 1000.0

    @property
    def slope_real(self) -> float:
        """dα/dP over the range on the real lines (1/kPa)."""
        return self.real / self.span_kpa

    @property
    def slope_flat(self) -> float:
        """dα/dP over the range on the flat-loss-tangent lines (1/kPa)."""
        return self.flat / self.span_kpa


@dataclass(frozen=True)
class BaselineVerdict:
    """A tensegrity against the strongest structure-free baselines with no more free parameters.

    ``better`` is True when its held-out RMS beats the best of them on the mean and on every split across the band
    (its highest against their lowest), False when it does not, None when it was not refereed.
    """

    baselines: tuple  # the names considered (converged, no more free parameters)
    best: str  # the baseline with the lowest mean held-out RMS (its band's low end)
    best_mean: tuple  # its mean band
    best_worst: tuple  # its worst band
    better: bool | None
    detail: str


@dataclass(frozen=True)
class MechanismRow:
    """One model's line of the study table (every number from this run's fits)."""

    name: str
    description: str
    n_free: int
    stiffness_spread: float  # decades
    rms: tuple  # per data set, decades
    aic: float
    bic: float
    n_determined: int  # free parameters with local standard error ≤ 0.1 (ln)
    n_analysed: int  # free parameters the identifiability analysed (not at a bound)
    at_bound: tuple  # names of free parameters at a bound
    ripple: float  # worst |local slope − chord slope| of G' between data points
    slope_range: tuple  # (min, max) local slope of G' over SLOPE_BAND_HZ
    holdout_rms: float | None  # mean held-out RMS of the best refits (decades), None when not refereed
    alternatives_spread: float  # largest spread (decades) of a free parameter over equally good starts
    assignment_spread: float  # largest sd (decades) of G' between the K assignments (0 if homogeneous)
    converged: bool
    elapsed_s: float
    curves: dict = field(default_factory=dict, compare=False)  # data set -> (x, G', G'') for the figure
    model: object = field(default=None, compare=False)  # the fitted model (tenscell.fitting.fitted)
    heterogeneous: bool = False  # a tendon property drawn from a distribution (the model has an ensemble)
    structural: bool = True  # a tensegrity (a cell), or a structure-free formula (a baseline)
    geometric_share: tuple = (math.nan, math.nan)  # free fit: (dG'/dP, dG''/dP) carried by P·Kp; NaN: not defined
    s: float = math.nan  # free fit's prestress scale (m²); NaN: no data set states its prestress
    formula: tuple | None = None  # its own structure-free formula: (name, free parameters, rms per data set, BIC)
    out_of_sample: OutOfSampleComparison | None = field(default=None, compare=False)  # the model, its own formula
    #  and the baselines it is judged against; None: not refereed
    anchored: Anchored | None = None
    unlike: tuple = ()  # of Falsified
    exponent: ExponentTest | None = None
    baselines: BaselineVerdict | None = None
    exponent_change: float = math.nan  # free fit: Δα over the measured prestress range (EXPONENT_FREQUENCY_HZ)
    sigma_ratio: float = math.nan  # free fit: its physical prestress σ over the measured (NaN: not defined)
    notes: tuple = ()  # what was not run, and why
    cpu_s: float = math.nan  # CPU seconds of every fit of this model (its tasks' process time)
    cpu_main_s: float = math.nan  # CPU seconds of its main fit alone

    @property
    def held_out(self) -> tuple[float, float]:
        """(mean, worst) held-out RMS over the splits of the best refits (decades); NaN when not run."""
        if self.out_of_sample is None:
            return math.nan, math.nan
        row = self.out_of_sample.row(self.out_of_sample.model)
        return row.mean, row.worst

    @property
    def held_out_row(self):
        """The model's :class:`~tenscell.fitting.validation.OutOfSample` (None when not refereed)."""
        return None if self.out_of_sample is None else self.out_of_sample.row(self.name)

    @property
    def discriminates(self) -> bool | None:
        """The model's RMS on every unlike data set is at least :data:`DISCRIMINATES` × its RMS on the cell data
        (None when no unlike data were fitted)."""
        if not self.unlike:
            return None
        return all(u.ratio >= DISCRIMINATES for u in self.unlike)

    @property
    def determined_share(self) -> float:
        """Share of the free parameters determined within 10 % (those at a bound count as not determined)."""
        return self.n_determined / self.n_free if self.n_free else 0.0

    @property
    def worst_rms(self) -> float:
        return max(self.rms)


@dataclass(frozen=True, eq=False)
class MechanismStudy:
    """The study's table, its sources and options, and its wall time."""

    rows: tuple
    sources: tuple
    holdout: tuple | None  # the names of the held-out splits every model was refitted on (None: not run)
    elapsed_s: float
    options: dict
    ensemble: EnsembleResult | None = None  # the best distributed mechanism's (tenscell.population.ensemble)
    baselines: tuple = ()  # the baseline pool's OutOfSample rows (tenscell.fitting.validation)
    baseline_fits: dict = field(default_factory=dict)  # {baseline name: (free parameters, rms per data set, BIC)}
    datasets: tuple = ()  # the data sets fitted
    a_priori: Any = None  # the structures' parameter-free slopes (tenscell.studies.a_priori: a Table), None: not run

    @property
    def cpu_s(self) -> float:
        """CPU seconds of every fit of the study (the ensemble not included)."""
        return float(sum(r.cpu_s for r in self.rows)) + float(self.options.get("baseline_cpu_s", 0.0))

    @property
    def cpu_main_s(self) -> float:
        """CPU seconds of the main fits alone (what the study computed before the referee's columns)."""
        return float(sum(r.cpu_main_s for r in self.rows))

    @property
    def winner(self) -> MechanismRow:
        """The mechanism with the lowest BIC."""
        return min(self.rows, key=lambda r: r.bic)

    def row(self, name: str) -> MechanismRow:
        for r in self.rows:
            if r.name == name:
                return r
        raise ValueError(f"no mechanism {name!r} in this study")

    def goals(self) -> list[tuple[str, str, float, bool]]:
        """Per goal: (goal in words, the mechanism closest to it, its shortfall (0 if met), met by some mechanism)."""
        g = GOALS
        ref = next((r for r in self.rows if r.name == PER_TENDON_VOIGT), None)
        out = []
        cells = [r for r in self.rows if r.structural] or list(self.rows)  # the goals are a tensegrity's

        def closest(label, miss):
            best = min(cells, key=lambda r: (miss(r), r.bic))  # ties (several meet it): the lowest BIC
            out.append((label, best.name, float(miss(best)), miss(best) <= 0))

        compact = [r for r in cells if r.n_free <= g["max_free"]]

        def fit_miss(r):
            return max(r.worst_rms - g["max_rms"], r.stiffness_spread - g["max_spread"], 0.0) + \
                (0.0 if r.n_free <= g["max_free"] else math.inf)

        if compact:
            closest(f"≤ {g['max_free']} free parameters, stiffnesses within {g['max_spread']:g} decades, RMS ≤ "
                    f"{g['max_rms']:g} on every data set (decades over the RMS goal or the spread goal)", fit_miss)
        if ref is not None:
            closest(f"beats the per-tendon fit on BIC (BIC above its {ref.bic:.1f})",
                    lambda r: math.inf if r is ref else max(r.bic - ref.bic, 0.0))
        closest(f"≥ {g['min_determined']:.0%} of parameters determined within 10 % (share short)",
                lambda r: max(g["min_determined"] - r.determined_share, 0.0))
        closest(f"local G' slope within ±{g['slope_tol']:g} of {g['slope']:g} from {SLOPE_BAND_HZ[0]:g} to "
                f"{SLOPE_BAND_HZ[1]:g} Hz (slope units beyond the band)",
                lambda r: max(abs(r.slope_range[0] - g["slope"]), abs(r.slope_range[1] - g["slope"])) - g["slope_tol"]
                if np.all(np.isfinite(r.slope_range)) else math.inf)
        out[-1] = (*out[-1][:2], max(out[-1][2], 0.0), out[-1][2] <= 0)
        out.append((f"the study's fits take ≤ {g['max_cpu_s']:.0f} s of CPU (issue 35; seconds over)", "(all)",
                    max(self.cpu_s - g["max_cpu_s"], 0.0), self.cpu_s <= g["max_cpu_s"]))
        return out

    def goals_issue33(self) -> list[tuple[str, str, str, bool]]:
        """Issue 33's G1–G3 as this study measures them: (goal in words, the model closest to it, by how much in
        words, met). Only tensegrities count (a formula carries no structure)."""
        return [_g1(self), _g2(self), _g3(self)]


def _anchored_rows(study: MechanismStudy) -> list[MechanismRow]:
    g = ISSUE33_GOALS
    return [r for r in study.rows if r.structural and r.anchored is not None and r.n_free <= g["max_free"]]


def _anchor_of(r: MechanismRow) -> Anchored:
    assert r.anchored is not None  # only rows with an anchored fit are asked
    return r.anchored


def _g1_miss(r: MechanismRow) -> float:
    """How far the anchored fit is from G1: RMS over the limit (decades), plus σ outside the factor (log10)."""
    g = ISSUE33_GOALS
    a = r.anchored
    assert a is not None
    over = max(max(a.rms) - g["max_rms"], 0.0)
    ratio = a.sigma_ratio
    off = abs(math.log10(ratio)) - math.log10(g["anchor_factor"]) if math.isfinite(ratio) and ratio > 0 else math.inf
    return over + max(off, 0.0)


def _g1(study: MechanismStudy) -> tuple[str, str, str, bool]:
    g = ISSUE33_GOALS
    label = (f"G1: ≤ {g['max_free']} free parameters, σ within ×/÷{g['anchor_factor']:g} of the measured prestress, "
             f"RMS ≤ {g['max_rms']:g} on every data set")
    rows = _anchored_rows(study)
    if not rows:
        return label, "(none)", "no tensegrity was fitted anchored (no data set states its prestress)", False
    best = min(rows, key=lambda r: (_g1_miss(r), max(_anchor_of(r).rms)))
    a = _anchor_of(best)
    met = _g1_miss(best) == 0
    ratio = "σ/measured not defined" if not math.isfinite(a.sigma_ratio) else f"σ/measured {a.sigma_ratio:.3g}"
    how = "met: " if met else ""
    return label, best.name, f"{how}RMS " + " / ".join(f"{x:.4f}" for x in a.rms) + f", {ratio}", met


def _g2(study: MechanismStudy) -> tuple[str, str, str, bool]:
    g = ISSUE33_GOALS
    label = (f"G2: anchored, RMS on each unlike set ≥ {g['unlike_ratio']:g}× its anchored cell RMS, and on "
             f"flat-loss-tangent lines its exponent still falls by ≥ {g['exponent_fall']:g} over the measured "
             "prestresses (the models meeting G1 first)")
    tested = [r for r in study.rows if r.structural and r.unlike and r.exponent is not None]
    if not tested:
        return label, "(none)", "no tensegrity was fitted to unlike data (none refereed, or no prestress sweep)", False
    g1 = [r for r in tested if r.anchored is not None and r.n_free <= g["max_free"] and _g1_miss(r) == 0]
    pool = g1 or tested

    def miss(r):
        ratio = min(u.ratio for u in r.unlike)
        fall = -r.exponent.flat if math.isfinite(r.exponent.flat) else -math.inf
        return max(math.log(g["unlike_ratio"] / ratio), 0.0) + max(g["exponent_fall"] - fall, 0.0) * 10

    best = min(pool, key=miss)
    met = miss(best) == 0
    e = best.exponent
    how = (", ".join(f"{u.kind} {u.ratio:.2f}×" for u in best.unlike) + f"; Δα on flat-loss-tangent lines "
           f"{e.flat:+.3f} (real lines {e.real:+.3f})")
    return label + ("" if g1 else "; no model meets G1, so the best of all"), best.name, how, met


def _g3(study: MechanismStudy) -> tuple[str, str, str, bool]:
    g = ISSUE33_GOALS
    label = (f"G3: held-out mean and worst over every split, across the band, ≤ {g['baseline_factor']:g}× the best "
             "structure-free baseline's (no more free parameters), refits converged")
    judged = [r for r in study.rows if r.structural and r.baselines is not None and r.held_out_row is not None
              and r.held_out_row.converged and r.baselines.baselines]
    if not judged:
        return label, "(none)", "no tensegrity was refereed out of sample against a baseline", False

    def ratios(r):
        o, b = r.held_out_row, r.baselines
        return o.mean_band[1] / b.best_mean[0], o.worst_band[1] / min(
            _row_of(study, n).worst_band[0] for n in b.baselines)

    best = min(judged, key=lambda r: max(ratios(r)))
    m, w = ratios(best)
    o = best.held_out_row
    met = max(m, w) <= g["baseline_factor"]
    how = (f"mean {o.mean_band[0]:.3f}–{o.mean_band[1]:.3f} ({m:.2f}× the best baseline's {best.baselines.best}), "
           f"worst {o.worst_band[0]:.3f}–{o.worst_band[1]:.3f} ({w:.2f}×)")
    return label, best.name, how, met


def _row_of(study: MechanismStudy, name: str):
    return next(b for b in study.baselines if b.model == name)


# ---------------------------------------------------------------------------------------
# the fits (each a task of the plan: module-level, so that a worker process can run it)
# ---------------------------------------------------------------------------------------
def _frequency_sweep(datasets) -> int | None:
    """Index of the first data set that is a frequency sweep at one prestress (several frequencies)."""
    for k, d in enumerate(datasets):
        if np.unique(d.frequency_hz).size >= 4 and (d.prestress is None or np.unique(d.prestress).size == 1):
            return k
    return None


def _fit(datasets, name: str, opts: dict, **extra):
    from ..fitting import fit

    if name == PER_TENDON_VOIGT:
        # the paper's fit gets the budget `make reproduce` gives it (its default hops, polishing 4× as long as
        # reaching the tolerance took): the reference must be a converged fit, not a truncated search
        # per-family damping: the 37-parameter fit of issue 18 (33 EA, 2 c, s, P_data; L is the exact gauge)
        return fit(datasets, model=_spec(name), progress=False, jobs=1,
                   **dict(opts, hops=max(opts["hops"], PER_TENDON_HOPS), polish_effort=4.0), **extra)
    return fit(datasets, model=name, progress=False, jobs=1, **opts, **extra)


def _shares(result) -> tuple[float, float]:
    """(dG'/dP, dG''/dP) carried by the geometric prestress stiffness over the data's prestress range (a model that
    defines the split); NaN for another model (the Voigt cell's prestress activity is in its own fit report)."""
    from ..fitting.shares import structure_shares

    if not result.spec.capabilities.structure_shares:
        return math.nan, math.nan
    try:
        sh = structure_shares(result.problem, result.theta)
    except ValueError:  # not a stable cell at some prestress of the range
        return math.nan, math.nan
    return sh.geometric_share_storage, sh.geometric_share_loss


def _scale(result) -> float:
    """The fit's prestress scale s (m²), NaN without one."""
    return result.value("s") if "s" in result.problem.names else math.nan


def _measured_range(datasets) -> tuple[float, float] | None:
    """The lowest and highest prestress the data state (Pa), None when they state fewer than two."""
    stated = [np.asarray(d.prestress, float) for d in datasets if getattr(d, "prestress", None) is not None]
    if not stated:
        return None
    P = np.unique(np.concatenate(stated))
    return (float(P[0]), float(P[-1])) if P.size > 1 else None


def exponent_change(result, prestress_pa: tuple[float, float], frequency_hz: float = EXPONENT_FREQUENCY_HZ) -> float:
    """α(P_hi) − α(P_lo): the change of the local G' slope ``d log G'/d log f`` at ``frequency_hz`` between two
    measured prestresses (Pa), read through the fit's prestress scale (NaN where it has none or is no stable cell).
    The slope is a central difference over ±10⁻³ decades."""
    h = 1e-3
    f = frequency_hz * 10.0 ** np.array([-h, h])
    alphas = []
    for P in prestress_pa:
        try:
            Gs, _ = result.moduli(f, prestress_pa=np.full(2, float(P)))
        except (ValueError, ArithmeticError, np.linalg.LinAlgError):
            return math.nan
        with np.errstate(divide="ignore", invalid="ignore"):
            alphas.append(float(np.diff(np.log10(Gs))[0] / (2 * h)))
    return alphas[1] - alphas[0] if all(map(math.isfinite, alphas)) else math.nan


def anchor_options(name, datasets) -> dict:
    """The options of :func:`tenscell.fitting.fit` that hold model ``name``'s physical prestress σ within ×/÷
    :data:`ANCHOR_FACTOR` of the measured prestress (:class:`tenscell.fitting.anchor.Anchor`): the one place the
    study's anchor is defined."""
    from ..fitting.anchor import Anchor

    return Anchor(ANCHOR_FACTOR).options_for(name, datasets)


def _sigma_ratio(result) -> float:
    """The fitted model's physical prestress σ over the measured one (the geometric mean over the data's stated
    prestresses; NaN: not defined for this model)."""
    from ..fitting.anchor import prestress_ratio

    try:
        r = prestress_ratio(result)
    except ValueError:  # a cell whose nodes span no volume has no σ
        return math.nan
    return math.nan if r is None else math.sqrt(r[0] * r[1])


def _model_moduli(result, f, k):
    """G', G'' of a fit (either kind) at frequencies f (Hz) at data set k's prestress."""
    return result.moduli(f, dataset=k)


def _slopes(result, k: int, f_data) -> tuple[float, tuple[float, float], tuple]:
    """(ripple between the data points, slope range over SLOPE_BAND_HZ, (f, G', G'') dense curve)."""
    lo, hi = math.log10(SLOPE_BAND_HZ[0]), math.log10(SLOPE_BAND_HZ[1])
    f = np.logspace(lo, hi, int(round((hi - lo) * SLOPE_GRID_PER_DECADE)) + 1)
    Gs, Gl = _model_moduli(result, f, k)
    x, y = np.log10(f), np.log10(Gs)
    local = np.gradient(y, x)
    fd = np.unique(f_data)
    ripple = 0.0
    ys_d = np.interp(np.log10(fd), x, y)
    for a, b, ya, yb in zip(np.log10(fd[:-1]), np.log10(fd[1:]), ys_d[:-1], ys_d[1:]):
        inside = (x > a) & (x < b)
        if inside.any():
            ripple = max(ripple, float(np.max(np.abs(local[inside] - (yb - ya) / (b - a)))))
    return ripple, (float(local.min()), float(local.max())), (f, Gs, Gl)


def _identifiability_counts(result) -> tuple[int, int, tuple]:
    ident = result.identifiability()
    at_bound = tuple(p.name for p in result.parameters if p.vary and p.at_bound is not None)
    return int(np.sum(ident.determined(0.1))), ident.n_analysed, at_bound


def _scores(result) -> tuple[tuple, float, float, int]:
    """(rms per data set, AIC, BIC, model parameters: free, less an exact gauge) of a fit of any model."""
    aic, bic = result.information_criteria()
    return result.dataset_rms, aic, bic, result.problem.n_model_parameters


def _alternatives_spread(result) -> float:
    """The largest spread (decades) of a free parameter over the best fit and the other starts that fit as well."""
    return max(result.alternative_spread().values(), default=0.0) if result.alternatives else 0.0


def _spread(result) -> float:
    """The tendon-stiffness spread (decades); NaN for a model without tendons."""
    spread = result.stiffness_spread
    return math.nan if spread is None else float(spread[2])


@dataclass(frozen=True, eq=False)
class MainFit:
    """A model's main fit and what the study reads from it (a task's result)."""

    name: str
    result: Any  # FitResult
    fields: dict  # MechanismRow fields computed from the fit
    refereed: bool  # whether the referee's refits run for it
    note: str = ""
    cpu_s: float = math.nan  # CPU seconds of the fit and of reading its columns


def _refereed(result, structural: bool) -> tuple[bool, str]:
    if result.problem.n_free > REFIT_MAX_FREE:
        return False, (f"{result.problem.n_model_parameters} model parameters: the referee's refits are not run "
                       "(`tenscell fit --validate yes` runs the held-out ones)")
    if max(result.dataset_rms) > REFEREE_MAX_RMS:
        return False, (f"worst RMS {max(result.dataset_rms):.3g} > {REFEREE_MAX_RMS:g} in sample: it misses the data "
                       "before any split, so it is not refereed out of sample")
    return True, ""


def main_fit(name, datasets, opts: dict) -> MainFit:
    """Fit one model (a name, or a model of its own) to all the data and read the study's columns from the fit (a
    task)."""
    t0, c0 = time.monotonic(), time.process_time()
    result = _fit(datasets, name, opts)
    spec = result.spec
    name = name if isinstance(name, str) else spec.name
    rms, aic, bic, n_free = _scores(result)
    n_det, n_an, at_bound = _identifiability_counts(result)
    k = _frequency_sweep(datasets)
    ripple, srange, curves = math.nan, (math.nan, math.nan), {}
    if k is not None:
        ripple, srange, curves[k] = _slopes(result, k, datasets[k].frequency_hz)
    span = _measured_range(datasets)
    refereed, note = _refereed(result, spec.structural)
    fields = dict(
        name=name, description=spec.description, n_free=n_free, stiffness_spread=_spread(result), rms=rms, aic=aic,
        bic=bic, n_determined=n_det, n_analysed=n_an, at_bound=at_bound, ripple=ripple, slope_range=srange,
        alternatives_spread=_alternatives_spread(result), assignment_spread=result.assignment_spread[0],
        converged=bool(result.converged), elapsed_s=time.monotonic() - t0, curves=curves, model=result.model,
        heterogeneous=spec.heterogeneous, structural=spec.structural, geometric_share=_shares(result),
        s=_scale(result), exponent_change=math.nan if span is None else exponent_change(result, span),
        sigma_ratio=_sigma_ratio(result) if spec.structural else math.nan)
    return MainFit(name=name, result=result, fields=fields, refereed=refereed, note=note,
                   cpu_s=time.process_time() - c0)


@dataclass(frozen=True)
class Skipped:
    """A referee's task not run, and why."""

    reason: str


def heldout_task(spec, split, opts: dict, main: MainFit):
    """The model refitted on one split to the main fit's standard (:func:`tenscell.fitting.validation.refit_split`)."""
    from ..fitting.validation import refit_split

    if not main.refereed:
        return Skipped(main.note)
    return refit_split(spec, split, main.result, **opts)


def anchored_task(name: str, datasets, opts: dict, main: MainFit):
    """The fit with the prestress anchored (:func:`anchor_options`), warm at the free fit: ``(Anchored, result)``."""
    from ..fitting.validation import refit

    if not main.refereed or not math.isfinite(_scale(main.result)):
        return Skipped(main.note or "no data set states its prestress: nothing to anchor")
    c0 = time.process_time()
    r = refit(name, datasets, main.result, **anchor_options(name, datasets), **opts)
    _, bic = r.information_criteria()
    span = _measured_range(datasets)
    return Anchored(rms=r.dataset_rms, bic=bic, s=_scale(r),
                    at_bound=tuple(p.name for p in r.parameters if p.vary and p.at_bound is not None),
                    geometric_share=_shares(r), converged=bool(r.converged), sigma_ratio=_sigma_ratio(r),
                    exponent_change=math.nan if span is None else exponent_change(r, span),
                    cpu_s=time.process_time() - c0), r


def unlike_task(name: str, kind: str, datasets, opts: dict, anchored):
    """The anchored model fitted to one unlike version of the data, warm at its anchored fit to the cell data."""
    from ..fitting.validation import refit
    from .falsification import unlike_sets

    if isinstance(anchored, Skipped):
        return anchored
    a, result = anchored
    c0 = time.process_time()
    ds = unlike_sets(datasets, (kind,))[kind]
    r = refit(name, ds, result, **anchor_options(name, ds), **opts)
    return Falsified(kind=kind, rms=r.dataset_rms, ratio=max(r.dataset_rms) / max(max(a.rms), 1e-12),
                     cpu_s=time.process_time() - c0)


def flat_task(name: str, datasets, opts: dict, anchored):
    """The exponent test (:class:`ExponentTest`): the anchored model fitted to the lines with a flat loss tangent."""
    from ..fitting.validation import refit
    from .falsification import FLAT_LOSS_TANGENT, unlike_sets

    if isinstance(anchored, Skipped):
        return anchored
    a, result = anchored
    c0 = time.process_time()
    span = _measured_range(datasets)
    assert span is not None  # anchored: some data set states its prestresses
    ds = unlike_sets(datasets, (FLAT_LOSS_TANGENT,))[FLAT_LOSS_TANGENT]
    r = refit(name, ds, result, **anchor_options(name, ds), **opts)
    return ExponentTest(prestress_pa=span, real=a.exponent_change, flat=exponent_change(r, span),
                        flat_rms=r.dataset_rms, cpu_s=time.process_time() - c0)


def a_priori_task(datasets):
    """Each structure's slopes dG′/dσ and dG″/dσ with no fitted parameter, against the data's lines
    (:func:`tenscell.studies.a_priori.a_priori_table`; a task)."""
    from .a_priori import a_priori_table

    return a_priori_table(datasets)


def ensemble_task(datasets, K: int, where: dict, *mains: MainFit):
    """The ensemble of the distributed mechanism with the lowest BIC (None when none was fitted)."""
    from ..population.ensemble import ensemble_at_data

    if not mains:
        return None
    best = min(mains, key=lambda m: m.fields["bic"])
    return ensemble_at_data(best.result.model, datasets, K, **where)


# ---------------------------------------------------------------------------------------
# the baselines at their strongest
# ---------------------------------------------------------------------------------------
def _formula_name(f) -> str:
    """A formula's name from its network: ``formula: aP + E0 + springpot`` or ``formula: (aP + E0) in series
    with (springpot) + newtonian``."""
    if not f.series:
        return "formula: " + " + ".join(f.terms)
    a, b = f.series
    rest = [t for t in f.terms if t not in a and t not in b]
    return f"formula: ({' + '.join(a)}) in series with ({' + '.join(b)})" + "".join(f" + {t}" for t in rest)


def baseline_pool(datasets, models) -> tuple[dict, dict]:
    """The structure-free baselines of a study of ``models``: ``({name: Formula}, {model: its own formula's name})``.

    The standard laws (:func:`tenscell.fitting.validation.standard_baselines`: P entering G′ and G″ alike where the
    data vary the prestress) and, for each tensegrity that can be refereed, its lumped terms as a parallel network
    (its own formula) and as a series network; formulas with the same network are one baseline.
    """
    from ..fitting.models import get_model
    from ..fitting.models.formulas import Formula, series_formula
    from ..fitting.validation import standard_baselines

    pool: dict = {n: get_model(n) for n in standard_baselines(datasets)}
    own: dict = {}
    for name in models:
        if name == PER_TENDON_VOIGT:
            continue
        spec = get_model(name)
        if not (spec.structural and spec.capabilities.lumped_terms):
            continue
        parallel = cast(Formula, spec.formula())  # a model with lumped terms: its formula is a Formula
        for f in (parallel, series_formula(parallel)):
            if f is None:
                continue
            canon = Formula(_formula_name(f), f.terms, f.description, series=f.series)
            pool.setdefault(canon.name, canon)
        own[name] = _formula_name(parallel)
    return pool, own


def _judge(name: str, mine, pool_rows: list, n_free: int) -> BaselineVerdict:
    """``mine`` (an OutOfSample) against the converged baselines with no more free parameters, across the band."""
    rows = [b for b in pool_rows if b.converged and b.n_params <= n_free and b.splits == mine.splits]
    if not rows:
        return BaselineVerdict((), "", (math.nan, math.nan), (math.nan, math.nan), None,
                               f"no converged baseline with ≤ {n_free} free parameters")
    best = min(rows, key=lambda b: (b.mean_band[0], b.worst_band[0]))
    if not mine.converged:
        return BaselineVerdict(tuple(b.model for b in rows), best.model, best.mean_band, best.worst_band, None,
                               f"{name}'s refits did not converge on {', '.join(mine.unconverged)}: no verdict")
    lows = np.array([[s.band[0] for s in b.scores] for b in rows]).min(axis=0)
    mine_hi = np.array([s.band[1] for s in mine.scores])
    losing = [s for s, m, lo in zip(mine.splits, mine_hi, lows) if not m < lo]
    mean_ok = mine.mean_band[1] < best.mean_band[0]
    better = mean_ok and not losing
    if better:
        detail = (f"better than every baseline with ≤ {n_free} free parameters on the mean and on every split, "
                  "across the band")
    else:
        what = ([] if mean_ok else [f"the mean ({mine.mean_band[1]:.3g} against {best.model}'s "
                                    f"{best.mean_band[0]:.3g})"]) + [f"{s}" for s in losing]
        detail = "not better than the best baseline across the band on " + "; ".join(what)
    return BaselineVerdict(tuple(b.model for b in rows), best.model, best.mean_band, best.worst_band, better, detail)


# ---------------------------------------------------------------------------------------
# the plan and its assembly (the study protocol)
# ---------------------------------------------------------------------------------------
def default_models(datasets) -> tuple[str, ...]:
    """The study's models by default: the per-tendon Voigt fit, every built-in mechanism, the baselines."""
    from ..fitting.validation import standard_baselines

    return (PER_TENDON_VOIGT, *MECHANISMS, *standard_baselines(datasets))


def _options(options: Mapping[str, Any]) -> dict:
    """The study's options, checked (ValueError naming the option in flag syntax), with defaults."""
    from ..fitting.parameters import as_datasets

    datasets = options.get("datasets") or options.get("data")
    if not datasets:
        raise ValueError("study mechanisms: needs data (a frequency or prestress sweep, or several)")
    datasets = as_datasets(datasets)
    names = _model_names(options.get("mechanisms"), datasets)
    K = _ensemble_size(options)
    return {"datasets": datasets, "mechanisms": names, "starts": int(options.get("starts") or 4),
            "hops": int(10 if options.get("hops") is None else options["hops"]), "seed": int(options.get("seed") or 0),
            "tolerance": float(options.get("tolerance") or 0.01), "validate": bool(options.get("validate", True)),
            "falsify": bool(options.get("falsify", True)), "ensemble": K or None,
            "workers": options.get("workers"), "scheduler": options.get("scheduler"), "jobs": options.get("jobs"),
            "progress": options.get("progress"), "notify": options.get("notify")}


def _model_names(given, datasets) -> tuple[str, ...]:
    """The models of the study: ``given`` (a sequence of names, or the command line's comma list), or
    :func:`default_models`; an unknown name is refused naming ``--mechanisms``."""
    from ..fitting.models import MODELS
    from ..fitting.models.catalog import mechanism_names
    from ._common import name_list

    if given is None:
        return default_models(datasets)
    names = name_list(given)
    known = ", ".join(mechanism_names())
    if not names:
        raise ValueError(f"--mechanisms {given!r}: no mechanism named; give a comma list of names ({known}), or "
                         "leave the flag out for all of them")
    bad = [n for n in names if n != PER_TENDON_VOIGT and n not in MODELS]
    if bad:
        raise ValueError(f"--mechanisms: unknown mechanism {bad[0]!r}; known: {known}")
    return names


def _ensemble_size(options: Mapping[str, Any]) -> int:
    """K of the ensemble (0: none), checked with where it runs, before any fit: one assignment has no spread,
    ``--workers`` and ``--scheduler`` need an ensemble, and the scheduler must answer."""
    from ..population.ensemble import check_counts

    K = options.get("ensemble", DEFAULT_K)
    K = 0 if K is None else K
    workers, scheduler = options.get("workers"), options.get("scheduler")
    if K == 1:
        raise ValueError("--ensemble: 1 assignment has no spread between assignments; give K >= 2, or 0 for none")
    if not K and (workers is not None or scheduler is not None):
        raise ValueError(f"{'--workers' if workers is not None else '--scheduler'} applies to the study's "
                         "ensemble, and --ensemble 0 has none")
    if K:
        check_counts(K, workers)
    if scheduler is not None:
        from ..population.scheduler import reach_scheduler

        reach_scheduler(scheduler)
    return int(K)


def _search(o: dict) -> dict:
    return {"starts": o["starts"], "hops": o["hops"], "seed": o["seed"], "tolerance": o["tolerance"]}


def evaluations_of(name: str) -> str:
    """The kind of the study's tasks that fit ``name`` (a model's or a formula's name): their weight is the model
    evaluations they are expected to take, their rate the CPU seconds of one (:func:`~tenscell.studies._common.evaluation_probe`)."""
    return f"evaluation of {name}"


#: a referee's refit (held out, anchored, unlike, flat loss tangent) in evaluations, as a share of its main fit's:
#: the mean over the study's default models on the bundled pair, where a refit warm at a refereed model's main fit
#: took 0.4-0.7 of its CPU and the refits of the 9 models of 14 the referee leaves out (they miss the data in sample)
#: none — 164 s of refits against 88 s of main fits × 13 refits (load 4-5; the run revises the rates as tasks finish)
REFIT_SHARE = 0.15


def _evaluations(o: dict, what: str = "mechanism") -> float:
    """Model evaluations one main fit of the study is expected to take: ``EVALUATIONS_PER_START_HOP[what]`` of
    :mod:`tenscell.fitting.search` × starts × (hops + 1) (``what``: "mechanism", "formula" or "voigt-per-tendon",
    which searches at least :data:`PER_TENDON_HOPS` hops); a refit's: :data:`REFIT_SHARE` of that."""
    from ..fitting.search import EVALUATIONS_PER_START_HOP

    hops = max(o["hops"], PER_TENDON_HOPS) if what == "voigt-per-tendon" else o["hops"]
    return EVALUATIONS_PER_START_HOP[what] * o["starts"] * (hops + 1)


def _model_tasks(name: str, o: dict, split_list) -> list:
    from .falsification import UNLIKE_KINDS, varies_with_prestress
    from .protocol import Task

    ds, search = o["datasets"], _search(o)
    per_tendon = name == PER_TENDON_VOIGT
    kind, n = evaluations_of(name), _evaluations(o, "voigt-per-tendon" if per_tendon else "mechanism")
    fit_key = f"fit/{name}"
    tasks = [Task(fit_key, kind, main_fit, (name, ds, search), weight=n)]
    if per_tendon:
        return tasks
    n *= REFIT_SHARE
    if o["validate"]:
        tasks += [Task(f"heldout/{name}/{s.name}", kind, heldout_task, (name, s, search), needs=(fit_key,), weight=n)
                  for s in split_list]
    if any(getattr(d, "prestress", None) is not None for d in ds):
        tasks.append(Task(f"anchored/{name}", kind, anchored_task, (name, ds, search), needs=(fit_key,), weight=n))
        if o["falsify"] and any(varies_with_prestress(d) for d in ds if getattr(d, "prestress", None) is not None):
            tasks += [Task(f"unlike/{name}/{k}", kind, unlike_task, (name, k, ds, search),
                           needs=(f"anchored/{name}",), weight=n) for k in UNLIKE_KINDS]
            tasks.append(Task(f"flat/{name}", kind, flat_task, (name, ds, search), needs=(f"anchored/{name}",),
                              weight=n))
    return tasks


def _baseline_tasks(name: str, spec, o: dict, split_list) -> list:
    from .protocol import Task

    ds, search = o["datasets"], _search(o)
    kind, n = evaluations_of(name), _evaluations(o, "formula")
    fit_key = f"baseline/{name}"
    tasks = [Task(fit_key, kind, main_fit, (spec, ds, search), weight=n)]
    if o["validate"]:
        tasks += [Task(f"baseline-heldout/{name}/{s.name}", kind, heldout_task, (spec, s, search),
                       needs=(fit_key,), weight=n * REFIT_SHARE) for s in split_list]
    return tasks


#: the assignments of the ensemble a probe evaluates
PROBE_ASSIGNMENTS = 32


def _spec(name):
    """The model fitted under ``name`` (a name, the per-tendon cell's, or a model object)."""
    from ..fitting import VoigtModel, get_model

    if not isinstance(name, str):
        return name
    return VoigtModel("per-tendon", "per-family") if name == PER_TENDON_VOIGT else get_model(name)


def _ensemble_probe(name: str, datasets):
    """A calibration probe of the kind "ensemble assignment": a distributed mechanism fitted from one start with no
    hop (its setup), and the work timed returned — its ensemble over :data:`PROBE_ASSIGNMENTS` assignments."""
    from ..population.ensemble import ensemble_at_data

    r = _fit(datasets, name, {"starts": 1, "hops": 0, "seed": 0, "tolerance": 0.01})
    return lambda: ensemble_at_data(r.model, datasets, PROBE_ASSIGNMENTS, progress=False)


def _a_priori_probe(datasets) -> None:
    """The a-priori slopes of the first structure alone: a calibration probe of the kind "a priori" (one
    structure of the table's)."""
    from .a_priori import a_priori_table
    from .structures import STRUCTURES

    a_priori_table(datasets, structures=tuple(STRUCTURES)[:1])


def _calibration(o: dict, tasks) -> tuple:
    """One probe for each kind of the plan's tasks: a model's evaluations, the a-priori table, the ensemble."""
    from ._common import PROBE_EVALUATIONS, evaluation_probe
    from .protocol import Task
    from .structures import STRUCTURES

    probes = []
    for t in tasks:
        if t.key.startswith(("fit/", "baseline/")):
            name = t.key.split("/", 1)[1]
            probes.append(Task(f"probe {name}", evaluations_of(name), evaluation_probe,
                               (_spec(t.args[0]), o["datasets"]), weight=PROBE_EVALUATIONS))
        elif t.key == "a priori":
            probes.append(Task("probe a priori", "a priori", _a_priori_probe, (o["datasets"],),
                               weight=1.0 / len(STRUCTURES)))
        elif t.key == "ensemble":
            best = t.needs[0].split("/", 1)[1]
            probes.append(Task("probe ensemble", "ensemble assignment", _ensemble_probe, (best, o["datasets"]),
                               weight=PROBE_ASSIGNMENTS))
    return tuple(probes)


#: the study's figures in units of :data:`tenscell.studies.protocol.FIGURE` (the mechanisms figure's panels)
_FIGURE_UNITS = 6.0


class MechanismsStudy:
    """``tenscell study mechanisms`` on the study protocol (:mod:`tenscell.studies.protocol`).

    Options: ``data`` or ``datasets`` (required), ``mechanisms`` (names, or a comma list; default
    :func:`default_models`), ``starts``, ``hops``, ``seed``, ``tolerance`` (every fit's search, refits included),
    ``validate`` (held-out refits), ``falsify`` (unlike data and the exponent test), ``ensemble`` (K assignments of
    the best distributed mechanism; 0 or None: none), ``workers``, ``scheduler`` (where the ensemble runs),
    ``jobs`` (worker processes over the tasks; default one per CPU).

    Every fit's task counts the model evaluations it is expected to take; the plan's probes time a few
    evaluations of each model (:func:`evaluations_of`), so the estimate is evaluations × their measured CPU.
    """

    name = "mechanisms"
    #: the options of ``tenscell study mechanisms`` (the protocol's ``Study.options``: name -> default; ``data``:
    #: the data sets read from the files the command line names; ``ensemble``: K assignments, 0 for none)
    options: Mapping[str, Any] = {"data": (), "seed": 0, "starts": 4, "jobs": None, "tolerance": 0.01,
                                  "mechanisms": None, "hops": 10, "ensemble": DEFAULT_K, "workers": None,
                                  "scheduler": None}

    def plan(self, options: Mapping[str, Any]):
        from .._parallel import jobs_for
        from ..fitting.validation import splits
        from .falsification import varies_with_prestress
        from .protocol import Plan, Task

        o = _options(options)
        split_list = splits(o["datasets"]) if o["validate"] else ()
        names = [n for n in o["mechanisms"] if n == PER_TENDON_VOIGT or _structural(n)]
        pool, own = baseline_pool(o["datasets"], names)
        given = [n for n in o["mechanisms"] if n not in names]  # structure-free formulas named as models
        for n in given:
            from ..fitting.models import get_model

            pool.setdefault(n, get_model(n))
        tasks = [t for n in names for t in _model_tasks(n, o, split_list)]
        tasks += [t for n, spec in pool.items() for t in _baseline_tasks(n, spec, o, split_list)]
        heterogeneous = tuple(f"fit/{n}" for n in names if n in MECHANISMS and MECHANISMS[n].heterogeneous)
        if o["ensemble"] and heterogeneous:
            # where its chunks run (the progress and notify callables stay in this process: a task may run in a
            # worker)
            where = {"workers": o["workers"], "scheduler": o["scheduler"], "progress": False}
            tasks.append(Task("ensemble", "ensemble assignment", ensemble_task,
                              (o["datasets"], o["ensemble"], where), needs=heterogeneous, weight=o["ensemble"]))
        if any(getattr(d, "prestress", None) is not None and varies_with_prestress(d) for d in o["datasets"]):
            tasks.insert(0, Task("a priori", "a priori", a_priori_task, (o["datasets"],)))
        o.update(models=tuple(names), given=tuple(given), pool=tuple(pool), own=own,
                 splits=tuple(s.name for s in split_list), jobs=jobs_for(len(tasks), o["jobs"]),
                 started=time.monotonic())  # the study's wall time begins with its plan
        return Plan(self.name, o, tuple(tasks), calibration=_calibration(o, tasks), figures=_FIGURE_UNITS,
                    jobs=o["jobs"], sized_by=("--starts", "--hops", "--mechanisms NAMES"))

    def assemble(self, plan, results: Mapping[str, Any]):
        return self.result(assemble_study(plan, results, elapsed_s=time.monotonic() - plan.options["started"]))

    def result(self, study: MechanismStudy):
        """The :class:`~tenscell.studies.protocol.StudyResult` of an assembled study: its tables, figure, page and
        checks, with the ensemble's table, figure and page when one was evaluated."""
        from .protocol import Figure, StudyResult

        tables = study_tables(study) + ((study.a_priori,) if study.a_priori is not None else ())
        figures: tuple = (Figure("mechanisms.png", "mechanisms_figure", (study, study.datasets)),)
        pages: tuple = (("mechanisms.md", _markdown(study)),)
        summary = _summary(study)
        if study.ensemble is not None:
            more = _ensemble_outputs(study.ensemble)
            tables, figures, pages = tables + more[0], figures + more[1], pages + more[2]
        elif study.options.get("ensemble"):
            summary += "\nno ensemble: none of the mechanisms fitted draws a tendon property from a distribution"
        return StudyResult(study=self.name, tables=tables, data=study, checks=_checks(study), summary=summary,
                           pages=pages, figures=figures)


def _ensemble_outputs(ensemble) -> tuple:
    """``ensemble.csv``, ``ensemble.png`` and ``ensemble.md`` of the best distributed mechanism's ensemble, as the
    protocol's (tables, figures, pages)."""
    from .._results import reporter
    from .protocol import Figure, Table

    df = ensemble.to_dataframe()
    table = Table("ensemble", tuple(df.columns), tuple(tuple(map(float, r)) for r in df.itertuples(index=False)),
                  description="G', G'' over the assignments of the distributed mechanism with the lowest BIC")
    title = f"Ensemble of `{ensemble.mechanism}`, the distributed mechanism with the lowest BIC"
    return ((table,), (Figure("ensemble.png", "ensemble_moduli", (ensemble,)),),
            (("ensemble.md", reporter("ensemble_markdown")(ensemble, title)),))


def _structural(name: str) -> bool:
    from ..fitting.models import get_model

    return get_model(name).structural


def _cpu_of(*records) -> float:
    """CPU seconds the records measured (a skipped task: none)."""
    return float(sum(x for x in (getattr(r, "cpu_s", math.nan) for r in records) if math.isfinite(x)))


def _out_of_sample(name: str, mine_fit: MainFit, results, o: dict):
    from ..fitting.validation import OutOfSample

    scores = [results.get(f"heldout/{name}/{s}") for s in o["splits"]]  # none for a model not refereed
    if not scores or any(s is None or isinstance(s, Skipped) for s in scores):
        return None
    return OutOfSample.from_scores(name, True, mine_fit.fields["n_free"], scores)


def _baseline_rows(results, o: dict) -> tuple[list, dict, float]:
    """The pool's OutOfSample rows (refereed baselines), ``{name: (free, rms, BIC)}``, and their CPU seconds."""
    from ..fitting.validation import OutOfSample

    rows, fits, cpu = [], {}, 0.0
    for name in o["pool"]:
        m = results[f"baseline/{name}"]
        fits[name] = (m.fields["n_free"], m.fields["rms"], m.fields["bic"])
        scores = [results.get(f"baseline-heldout/{name}/{s}") for s in o["splits"]]
        cpu += _cpu_of(m, *scores)
        if scores and not any(s is None or isinstance(s, Skipped) for s in scores):
            rows.append(OutOfSample.from_scores(name, False, m.fields["n_free"], scores))
    return rows, fits, cpu


def _comparison(name: str, mine, own: str | None, pool_rows: list, n_free: int):
    import dataclasses

    from ..fitting.validation import OutOfSampleComparison, out_of_sample_verdict

    theirs = [dataclasses.replace(b, baseline_of=name) for b in pool_rows if b.n_params <= n_free or b.model == own]
    formula = next((b for b in theirs if b.model == own), None)
    ranked = tuple(sorted([mine, *theirs], key=lambda r: (not r.converged, r.mean, r.worst)))
    return OutOfSampleComparison(rows=ranked, model=name, verdict=out_of_sample_verdict(mine, formula),
                                 splits=mine.splits)


def _row(name: str, results, o: dict, pool_rows: list) -> MechanismRow:
    main: MainFit = results[f"fit/{name}"]
    f = dict(main.fields)
    own = o["own"].get(name)
    oos = _out_of_sample(name, main, results, o)
    comparison = verdict = None
    if oos is not None:
        comparison = _comparison(name, oos, own, pool_rows, f["n_free"])
        verdict = _judge(name, oos, pool_rows, f["n_free"])
    anchored = results.get(f"anchored/{name}")
    a = None if anchored is None or isinstance(anchored, Skipped) else anchored[0]
    unlike = tuple(u for k, u in results.items() if k.startswith(f"unlike/{name}/") and isinstance(u, Falsified))
    exponent = results.get(f"flat/{name}")
    exponent = exponent if isinstance(exponent, ExponentTest) else None
    formula = None
    if own is not None and f"baseline/{own}" in results:
        fm = results[f"baseline/{own}"].fields
        formula = (own, fm["n_free"], fm["rms"], fm["bic"])
    held = [results[f"heldout/{name}/{s}"] for s in o["splits"] if f"heldout/{name}/{s}" in results]
    cpu = _cpu_of(main, *held, a, *unlike, exponent)
    return MechanismRow(**f, holdout_rms=None if oos is None else oos.mean, formula=formula,
                        out_of_sample=comparison, anchored=a, unlike=unlike, exponent=exponent, baselines=verdict,
                        notes=(main.note,) if main.note else (), cpu_s=cpu, cpu_main_s=main.cpu_s)


def _formula_row(name: str, results, pool_rows: list) -> MechanismRow:
    from ..fitting.validation import OutOfSampleComparison

    m: MainFit = results[f"baseline/{name}"]
    mine = next((b for b in pool_rows if b.model == name), None)
    comparison = None if mine is None else OutOfSampleComparison(
        rows=(mine,), model=name, verdict=f"{name} is itself a structure-free formula", splits=mine.splits)
    return MechanismRow(**m.fields, holdout_rms=None if mine is None else mine.mean, out_of_sample=comparison,
                        notes=(m.note,) if m.note else (), cpu_s=m.cpu_s, cpu_main_s=m.cpu_s)


def assemble_study(plan, results: Mapping[str, Any], elapsed_s: float = math.nan) -> MechanismStudy:
    """The :class:`MechanismStudy` of a plan's results."""
    o = plan.options
    pool_rows, fits, base_cpu = _baseline_rows(results, o)
    rows = [_row(n, results, o, pool_rows) for n in o["models"]]
    rows += [_formula_row(n, results, pool_rows) for n in o["given"]]  # formulas named as models
    order = list(o["mechanisms"])
    rows.sort(key=lambda r: order.index(r.name))
    given = set(o["given"])
    return MechanismStudy(rows=tuple(rows), sources=tuple(d.source for d in o["datasets"]),
                          holdout=o["splits"] if o["validate"] else None, elapsed_s=elapsed_s,
                          options={**{k: o[k] for k in ("starts", "hops", "seed", "tolerance", "validate", "falsify")},
                                   "jobs": o.get("jobs", 1), "refit": "the main fit's search, warm at the main fit",
                                   "baseline_cpu_s": base_cpu - sum(_cpu_of(results[f"baseline/{n}"]) for n in given
                                                                    if f"baseline/{n}" in results)},
                          ensemble=results.get("ensemble"), baselines=tuple(pool_rows), baseline_fits=fits,
                          datasets=tuple(o["datasets"]), a_priori=results.get("a priori"))


def _rms_text(values) -> str:
    return " ".join(f"{x:.4g}" for x in values)


def _or_blank(x):
    return "" if x is None else x


def _referee_fields(r: MechanismRow) -> dict:
    """The referee's columns of one row (blank where not run)."""
    from .falsification import UNLIKE_KINDS

    o, b, a, e = r.held_out_row, r.baselines, r.anchored, r.exponent
    own = None if r.out_of_sample is None or r.formula is None else r.out_of_sample.get(r.formula[0])
    out = {
        "held_out_rms_mean_decades": "" if o is None else o.mean,
        "held_out_rms_worst_decades": "" if o is None else o.worst,
        "held_out_mean_band_low": "" if o is None else o.mean_band[0],
        "held_out_mean_band_high": "" if o is None else o.mean_band[1],
        "held_out_worst_band_low": "" if o is None else o.worst_band[0],
        "held_out_worst_band_high": "" if o is None else o.worst_band[1],
        "held_out_refits_converged": "" if o is None else o.converged,
        "formula_held_out_mean_band_low": "" if own is None else own.mean_band[0],
        "formula_held_out_mean_band_high": "" if own is None else own.mean_band[1],
        "out_of_sample_verdict": "" if r.out_of_sample is None else r.out_of_sample.verdict,
        "strongest_baseline": "" if b is None else b.best,
        "strongest_baseline_mean_band_low": "" if b is None else b.best_mean[0],
        "strongest_baseline_worst_band_low": "" if b is None else b.best_worst[0],
        "better_than_baselines": "" if b is None or b.better is None else b.better,
        "baselines_verdict": "" if b is None else b.detail,
        "anchored_rms_per_dataset_decades": "" if a is None else _rms_text(a.rms),
        "anchored_BIC": "" if a is None else a.bic,
        "anchored_s_m2": "" if a is None else a.s,
        "anchored_sigma_over_measured": "" if a is None else a.sigma_ratio,
        "anchored_converged": "" if a is None else a.converged,
        "anchored_geometric_share_dGstorage_dP": "" if a is None else a.geometric_share[0],
    }
    for kind in UNLIKE_KINDS:
        out[f"unlike_{kind.replace('-', '_')}_ratio"] = next((u.ratio for u in r.unlike if u.kind == kind), "")
    out["discriminates"] = _or_blank(r.discriminates)
    out.update({
        "exponent_prestress_low_Pa": "" if e is None else e.prestress_pa[0],
        "exponent_prestress_high_Pa": "" if e is None else e.prestress_pa[1],
        "delta_alpha_free": r.exponent_change,
        "delta_alpha_anchored": "" if e is None else e.real,
        "delta_alpha_flat_loss_tangent": "" if e is None else e.flat,
        "dalpha_dP_anchored_per_kPa": "" if e is None else e.slope_real,
        "dalpha_dP_flat_loss_tangent_per_kPa": "" if e is None else e.slope_flat,
        "flat_loss_tangent_rms_per_dataset_decades": "" if e is None else _rms_text(e.flat_rms),
    })
    return out


def _main_fields(r: MechanismRow) -> dict:
    f = r.formula
    return {"model": r.name, "kind": "tensegrity" if r.structural else "structure-free",
            "free_parameters": r.n_free, "stiffness_spread_decades": r.stiffness_spread,
            "rms_per_dataset_decades": _rms_text(r.rms), "AIC": r.aic, "BIC": r.bic,
            "determined_within_10pct": r.n_determined, "at_bound": " ".join(r.at_bound), "converged": r.converged,
            "ripple_Gstorage_slope": r.ripple, "Gstorage_slope_min": r.slope_range[0],
            "Gstorage_slope_max": r.slope_range[1], "alternatives_spread_decades": r.alternatives_spread,
            "prestress_scale_s_m2": r.s, "sigma_over_measured": r.sigma_ratio,
            "geometric_share_dGstorage_dP": r.geometric_share[0],
            "geometric_share_dGloss_dP": r.geometric_share[1],
            "formula": "" if f is None else f[0], "formula_parameters": "" if f is None else f[1],
            "formula_rms_per_dataset_decades": "" if f is None else _rms_text(f[2]),
            "formula_BIC": "" if f is None else f[3]}


def _heldout_records(study: MechanismStudy) -> list[dict]:
    rows = [(r.name, "tensegrity", r.held_out_row) for r in study.rows if r.structural and r.held_out_row is not None]
    rows += [(b.model, "baseline", b) for b in study.baselines]
    return [{"model": name, "role": role, "split": s.split, "train_rms_decades": s.train_rms,
             "full_fit_train_rms_decades": s.reference_train_rms, "converged": s.converged,
             "held_out_rms_decades": s.held_out, "band_low_decades": s.band[0], "band_high_decades": s.band[1],
             "fits_in_band": s.n_band, "cpu_s": s.cpu_s}
            for name, role, o in rows for s in o.scores]


def _baseline_records(study: MechanismStudy) -> list[dict]:
    held = {b.model: b for b in study.baselines}
    out = []
    for name, (k, rms, bic) in study.baseline_fits.items():
        o = held.get(name)
        out.append({"baseline": name, "free_parameters": k, "rms_per_dataset_decades": _rms_text(rms), "BIC": bic,
                    "held_out_mean_band_low": "" if o is None else o.mean_band[0],
                    "held_out_mean_band_high": "" if o is None else o.mean_band[1],
                    "held_out_worst_band_low": "" if o is None else o.worst_band[0],
                    "held_out_worst_band_high": "" if o is None else o.worst_band[1],
                    "held_out_refits_converged": "" if o is None else o.converged})
    return out


def study_tables(study: MechanismStudy) -> tuple:
    """The study's tables with named columns: ``mechanisms`` (one row per model), ``mechanisms_heldout`` (one row
    per refereed model or baseline and split: training RMS beside the full fit's, the held-out band),
    ``mechanisms_baselines`` (the baseline pool)."""
    from .protocol import Table

    main = [{**_main_fields(r), **_referee_fields(r), "cpu_s": r.cpu_s, "cpu_main_fit_s": r.cpu_main_s,
             "notes": "; ".join(r.notes)} for r in study.rows]
    return (Table.from_records("mechanisms", main, description="every model, fitted and refereed"),
            Table.from_records("mechanisms_heldout", _heldout_records(study), columns=HELDOUT_COLUMNS,
                               description="every held-out refit: training RMS beside the full fit's, the band"),
            Table.from_records("mechanisms_baselines", _baseline_records(study), columns=BASELINE_COLUMNS,
                               description="the structure-free baselines at their strongest"))


#: the columns of the held-out table (named even when it has no row)
HELDOUT_COLUMNS = ("model", "role", "split", "train_rms_decades", "full_fit_train_rms_decades", "converged",
                   "held_out_rms_decades", "band_low_decades", "band_high_decades", "fits_in_band", "cpu_s")
#: the columns of the baselines table
BASELINE_COLUMNS = ("baseline", "free_parameters", "rms_per_dataset_decades", "BIC", "held_out_mean_band_low",
                    "held_out_mean_band_high", "held_out_worst_band_low", "held_out_worst_band_high",
                    "held_out_refits_converged")


def _checks(study: MechanismStudy) -> tuple:
    from .protocol import Check

    return tuple(Check(label=g, met=ok, closest=n, detail=how) for g, n, how, ok in study.goals_issue33())


def _summary(study: MechanismStudy) -> str:
    from .._results import reporter

    return reporter("mechanisms_summary")(study)


def _markdown(study: MechanismStudy) -> str:
    from .._results import reporter

    return reporter("mechanisms_markdown")(study)


def fits_per_model(datasets, n_free: int, structural: bool, validate: bool = True, falsify: bool = True) -> int:
    """How many fits the study makes of one tensegrity if it is refereed (the main fit, held out on every split,
    anchored, the unlike data and the flat-loss-tangent lines): for the cost estimate."""
    from ..fitting.validation import splits
    from .falsification import UNLIKE_KINDS, varies_with_prestress

    n = 1
    if n_free > REFIT_MAX_FREE or not structural:
        return n
    if validate:
        n += len(splits(datasets))
    if any(getattr(d, "prestress", None) is not None for d in datasets):
        n += 1
        if falsify and any(getattr(d, "prestress", None) is not None and varies_with_prestress(d) for d in datasets):
            n += len(UNLIKE_KINDS) + 1
    return n


def mechanisms_study(datasets, *, mechanisms=None, starts: int = 4, hops: int = 10, seed: int = 0,
                     tolerance: float = 0.01, validate: bool = True, falsify: bool = True, jobs: int = 1,
                     ensemble: int | None = None, workers: int | None = None, scheduler: str | None = None,
                     progress: bool | None = None, notify=None) -> MechanismStudy:
    """Fit every model to the same data and score them (module docstring): :class:`MechanismsStudy` planned,
    executed over ``jobs`` worker processes and assembled.

    Parameters
    ----------
    datasets : sequence of RheologyData
    mechanisms : sequence of str, optional
        Default: the per-tendon Voigt fit, every built-in mechanism and the structure-free baselines
        (:func:`tenscell.fitting.validation.standard_baselines`). Any name of :data:`tenscell.fitting.MODELS`.
    starts, hops, seed, tolerance :
        Search options of every fit (:func:`tenscell.fitting.fit`), the referee's refits included.
    validate : bool
        Refit each model and the baselines on held-out splits (:mod:`tenscell.fitting.validation`).
    falsify : bool
        Fit each anchored model to data cells do not show and to flat-loss-tangent lines (needs a prestress sweep).
    jobs : int
        Worker processes over the tasks (:mod:`tenscell._parallel`).
    ensemble : int, optional
        Evaluate the distributed mechanism with the lowest BIC over this many assignments at the data's
        prestresses and frequencies (:func:`tenscell.population.mechanism_ensemble`); None or 0 skips it.
    workers, scheduler, notify
        Where the ensemble's chunks run (as for :func:`~tenscell.population.mechanism_ensemble`).
    """
    from .protocol import execute

    t0 = time.monotonic()
    study = MechanismsStudy()
    plan = study.plan({"datasets": datasets, "mechanisms": mechanisms, "starts": starts, "hops": hops, "seed": seed,
                       "tolerance": tolerance, "validate": validate, "falsify": falsify, "ensemble": ensemble,
                       "workers": workers, "scheduler": scheduler, "progress": progress, "notify": notify,
                       "jobs": jobs})
    results, _ = execute(plan, jobs=jobs)
    return assemble_study(plan, results, elapsed_s=time.monotonic() - t0)


#: the study of ``tenscell study mechanisms`` (:data:`tenscell.cli.study.STUDIES`)
STUDY = MechanismsStudy()

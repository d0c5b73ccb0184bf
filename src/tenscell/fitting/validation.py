"""Out of sample: every model refitted without some of its data and scored on what it did not see.

A model is judged out of sample, beside baselines that have no tensegrity in them. :func:`splits` cuts the data
the way a referee would (issue 33):

* every frequency sweep at one prestress is cut at several training cut-offs (:data:`CUTOFFS_HZ`: trained on the
  points at or below 0.3, 1, 3, 10, 30 Hz, scored on the points above), the other data sets kept whole;
* every prestress sweep loses some prestresses (the top third: an extrapolation in P; every third prestress: an
  interpolation; the prestresses above :data:`PRESTRESS_CUTOFFS_PA`, 1000 Pa: trained at or below, scored above),
  the other data sets kept whole.

**Refits that converge.** A held-out refit runs to the full fit's standard (:func:`refit`): the same search budget,
start 0 warm at the full fit (moved inside the refit's bounds), the other starts fresh. Its RMS on its training
data is reported beside its held-out score, with the full fit's RMS on the same training points: a refit whose
training RMS exceeds :data:`UNCONVERGED` (1.5) × the full fit's did not converge (the full fit is a point of the
refit's search space that fits better), and :class:`HeldOutScore.converged` says so; such a refit is left out of
every ranking and verdict.

**The band.** Where the training data cannot tell fits apart, neither can the held-out score be one number: the
held-out RMS is reported as a band over the refit's best fit and every other start whose training cost (its
weighted sum of squares) lies within :data:`BAND_COST` (10 %) of the best's (each start with its own random stream:
the warm one and the fresh ones). A verdict holds only if it holds across the band.

:func:`out_of_sample` refits a model on each split's training data (through the one stack: :func:`fit`) and scores
the RMS of its log10 errors on the held-out points; :func:`compare_out_of_sample` does it for a model and its
baselines, ranks them by the mean over the splits (the worst reported beside it), and says when a tensegrity does
no better than its own structure-free formula across the band: "the structure adds nothing measurable here".
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from .._results import dataframe, format_repr
from ..io.data import RheologyData
from .parameters import as_datasets
from .records import data_axis
from .scores import data_subset

__all__ = ["Split", "splits", "OutOfSample", "out_of_sample", "OutOfSampleComparison", "compare_out_of_sample",
           "CUTOFFS_HZ", "PRESTRESS_CUTOFFS_PA", "NO_BETTER", "UNCONVERGED", "BAND_COST", "held_out_rms",
           "out_of_sample_verdict", "standard_baselines", "HeldOutScore", "refit", "refit_split", "score_split",
           "rms_on", "band_fits", "warm_start"]

#: training cut-offs of a frequency sweep (Hz): trained at or below, scored above
CUTOFFS_HZ = (0.3, 1.0, 3.0, 10.0, 30.0)
#: training cut-offs of a prestress sweep (Pa): trained at or below, scored above
PRESTRESS_CUTOFFS_PA = (1000.0,)
#: a tensegrity whose mean held-out RMS is not at least this fraction below its structure-free formula's does no
#: better than it (a 10 % margin: below that, the difference is within what another start or split would move)
NO_BETTER = 0.9
#: a refit whose training RMS exceeds this many times the full fit's RMS on the same training points did not
#: converge (the full fit lies in the refit's search space and fits those points better)
UNCONVERGED = 1.5
#: the band of held-out scores: the refit's fits whose training cost is within this factor of the best's
BAND_COST = 1.1
#: the fewest points a split leaves for training or scoring in a data set it cuts
_MIN_POINTS = 2


@dataclass(frozen=True, eq=False)
class Split:
    """One way of holding data out.

    Attributes
    ----------
    name : str
        E.g. ``"fabry2001 ≤ 10 Hz"``, ``"stamenovic2002: top third of P held out"``.
    train : tuple of RheologyData
        The training data (every data set, the cut one reduced).
    held : RheologyData
        The held-out points of the cut data set.
    dataset : int
        Which data set was cut.
    """

    name: str
    train: tuple
    held: RheologyData
    dataset: int


def _short(source: str) -> str:
    name = source.replace("\\", "/").rsplit("/", 1)[-1].split(" (")[0]
    return name.rsplit(".", 1)[0] if "." in name else name


def _prestress_masks(P: np.ndarray, cutoffs_pa) -> list[tuple[str, np.ndarray]]:
    levels = np.unique(P)
    top = levels[-max(1, levels.size // 3):]
    masks = [("top third of P held out", ~np.isin(P, top)), ("every third P held out", ~np.isin(P, levels[1::3]))]
    masks += [(f"P ≤ {c:g} Pa → above", P <= c) for c in cutoffs_pa]
    return masks


def splits(data, cutoffs_hz=CUTOFFS_HZ, prestress_cutoffs_pa=PRESTRESS_CUTOFFS_PA) -> tuple[Split, ...]:
    """Every split of :mod:`the module docstring <tenscell.fitting.validation>` the data allow (moduli only: a
    creep data set is kept whole in every training set). A split that leaves fewer than 2 training points, or no
    held-out point, in the data set it cuts is not made."""
    datasets = as_datasets(data)
    out: list[Split] = []
    for k, d in enumerate(datasets):
        if d.kind == "creep":
            continue
        masks: list[tuple[str, np.ndarray]] = []
        if data_axis(d) == "frequency" and np.unique(d.frequency_hz).size >= 2 * _MIN_POINTS:
            masks += [(f"≤ {c:g} Hz", d.frequency_hz <= c) for c in cutoffs_hz]
        elif data_axis(d) == "prestress":
            masks += _prestress_masks(np.asarray(d.prestress), prestress_cutoffs_pa)
        for label, train in masks:
            if train.sum() < _MIN_POINTS or (~train).sum() < 1:
                continue
            cut = data_subset(d, train, "training")
            out.append(Split(name=f"{_short(d.source)}: {label}",
                             train=tuple(cut if j == k else e for j, e in enumerate(datasets)),
                             held=data_subset(d, ~train, "held out"), dataset=k))
    return tuple(out)


def _errors_at(result, d: RheologyData, dataset: int) -> np.ndarray:
    """log10 model/data of a fit at the points of ``d`` (G' then G''), ``d`` standing in for data set ``dataset``
    (its prestresses mapped by the fit's scale where it states several; else that data set's prestress)."""
    if d.prestress is not None and np.unique(d.prestress).size > 1:
        Gs, Gl = result.moduli(d.frequency_hz, prestress_pa=d.prestress)
    else:
        Gs, Gl = result.moduli(d.frequency_hz, dataset=dataset)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.concatenate([np.log10(Gs / d.G_storage), np.log10(Gl / d.G_loss)])


def _rms_of(parts) -> float:
    r = np.concatenate(parts) if parts else np.zeros(0)
    return float(np.sqrt(np.mean(r**2))) if r.size and np.all(np.isfinite(r)) else math.inf


def held_out_rms(result, split: Split) -> float:
    """RMS (decades) of a fit's log10 errors at a split's held-out points (inf where the model is not a stable cell
    there)."""
    try:
        return _rms_of([_errors_at(result, split.held, split.dataset)])
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return math.inf


def rms_on(result, datasets) -> float:
    """RMS (decades) of a fit's log10 errors at the points of ``datasets`` (one per data set of the fit, in its
    order: e.g. a split's training data), unweighted; inf where the model is not a stable cell there."""
    try:
        return _rms_of([_errors_at(result, d, k) for k, d in enumerate(as_datasets(datasets))])
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return math.inf


# ---------------------------------------------------------------------------------------
# refits that converge, and the band
# ---------------------------------------------------------------------------------------
def warm_start(result, problem) -> np.ndarray:
    """The free log-parameters of ``problem`` at the fitted values of ``result``, matched by parameter name (a
    refit whose layout differs, e.g. with a parameter held fixed, starts where the full fit ended); a name the fit
    does not have starts at the middle of its bounds (log)."""
    values = dict(zip(result.problem.names, result.problem.full(result.theta)))
    mid = 0.5 * (problem.lower + problem.upper)
    phi = np.array([values.get(n, m) for n, m in zip(problem.names, mid)], dtype=float)
    return np.clip(phi[problem.free], problem.lower[problem.free], problem.upper[problem.free])


def refit(spec, data, full, *, cell=None, bounds=None, fixed=None, **search):
    """``spec`` refitted on ``data`` to the full fit's standard: the search options of the full fit (``search``),
    start 0 warm at ``full`` (a :class:`~tenscell.fitting.result.FitResult`, matched by parameter name and moved
    inside ``bounds``), the other starts fresh. ``full`` None: every start fresh."""
    from ..io.thinning import DEFAULT_MAX_POINTS
    from .entry import fit, prepare
    from .models import get_model

    model = get_model(spec)
    if full is None:
        return fit(data, cell, model=model, bounds=bounds, fixed=fixed, progress=False, **search)
    datasets, c = prepare(data, cell if cell is not None else full.cell, search.get("max_points", DEFAULT_MAX_POINTS),
                          model)
    problem = model.problem(datasets, c, bounds=bounds, fixed=fixed)
    return fit(data, c, model=model, bounds=bounds, fixed=fixed, initial=warm_start(full, problem), progress=False,
               **search)


def _cost(result, theta) -> float:
    r = result.problem.residuals(theta)
    return float(np.sum(r**2))


def band_fits(result, cost: float = BAND_COST) -> tuple:
    """The fits the training data cannot tell apart: ``result`` and each of its alternatives (other starts) whose
    training cost (weighted sum of squares) is within ``cost`` × the best's, best first, as FitResults."""
    best = _cost(result, result.theta)
    out = [result]
    free = result.problem.free
    for alt in result.alternatives:
        theta = np.log(np.array([p.value for p in alt.parameters], dtype=float))[free]
        if np.all(np.isfinite(theta)) and _cost(result, theta) <= cost * best:
            out.append(dataclasses.replace(result, theta=theta, parameters=alt.parameters, alternatives=()))
    return tuple(out)


@dataclass(frozen=True)
class HeldOutScore:
    """A refit on one split: its held-out RMS, the band, its training RMS beside the full fit's.

    Attributes
    ----------
    split : str
    held_out : float
        Held-out RMS (decades) of the refit's best fit (inf: no stable cell there).
    band : (float, float)
        Lowest and highest held-out RMS over the band (:func:`band_fits`).
    n_band : int
        Fits in the band (1: the best alone).
    train_rms : float
        The refit's RMS on its training points (decades, unweighted).
    reference_train_rms : float
        The full fit's RMS on the same training points (NaN without a full fit).
    """

    split: str
    held_out: float
    band: tuple
    n_band: int
    train_rms: float
    reference_train_rms: float = math.nan
    cpu_s: float = math.nan  # CPU seconds of the refit (NaN: not measured)

    @property
    def converged(self) -> bool:
        """The refit fits its training points within :data:`UNCONVERGED` × the full fit's RMS on them (True when
        there is no full fit to compare with)."""
        ref = self.reference_train_rms
        return not math.isfinite(ref) or self.train_rms <= UNCONVERGED * ref

    def to_dict(self) -> dict:
        return {"split": self.split, "held_out_rms": self.held_out, "band": list(self.band), "n_band": self.n_band,
                "train_rms": self.train_rms, "full_fit_train_rms": self.reference_train_rms,
                "converged": self.converged}


def score_split(result, split: Split, full=None, cost: float = BAND_COST) -> HeldOutScore:
    """The :class:`HeldOutScore` of ``result`` (a refit on ``split``'s training data), against the full fit
    ``full`` on the same training points."""
    band = [held_out_rms(r, split) for r in band_fits(result, cost)]
    return HeldOutScore(split=split.name, held_out=band[0], band=(min(band), max(band)), n_band=len(band),
                        train_rms=rms_on(result, split.train),
                        reference_train_rms=math.nan if full is None else rms_on(full, split.train))


def refit_split(spec, split: Split, full=None, *, cell=None, bounds=None, fixed=None, **search) -> HeldOutScore:
    """``spec`` refitted on ``split``'s training data (:func:`refit`, warm at ``full``) and scored."""
    c0 = time.process_time()
    r = refit(spec, split.train, full, cell=cell, bounds=bounds, fixed=fixed, **search)
    return dataclasses.replace(score_split(r, split, full), cpu_s=time.process_time() - c0)


@dataclass(frozen=True, eq=False, repr=False)
class OutOfSample:
    """A model's held-out errors over the splits.

    Attributes
    ----------
    model : str
    structural : bool
        Whether the model has a cell (a tensegrity) or is a structure-free formula.
    n_params : int
        The model's parameters on the full data (free, less an exact gauge).
    splits : tuple of str
    rms : ndarray
        Held-out RMS (decades) per split of the best refit (inf where the refit gave no stable cell there).
    baseline_of : str or None
        For a baseline: the model it is the baseline of.
    scores : tuple of HeldOutScore
        Per split: the band and the training RMS (empty: only ``rms`` is known; the band is then ``rms`` itself).
    """

    model: str
    structural: bool
    n_params: int
    splits: tuple
    rms: np.ndarray
    baseline_of: str | None = None
    scores: tuple = ()

    @classmethod
    def from_scores(cls, model: str, structural: bool, n_params: int, scores, baseline_of=None) -> OutOfSample:
        scores = tuple(scores)
        return cls(model=model, structural=structural, n_params=n_params, splits=tuple(s.split for s in scores),
                   rms=np.array([s.held_out for s in scores], dtype=float), baseline_of=baseline_of, scores=scores)

    @property
    def mean(self) -> float:
        """Mean held-out RMS over the splits (decades)."""
        return float(np.mean(self.rms)) if self.rms.size else math.nan

    @property
    def worst(self) -> float:
        """Largest held-out RMS over the splits (decades)."""
        return float(np.max(self.rms)) if self.rms.size else math.nan

    def _bands(self) -> np.ndarray:
        if not self.scores:
            return np.column_stack([self.rms, self.rms])
        return np.array([s.band for s in self.scores], dtype=float).reshape(-1, 2)

    @property
    def mean_band(self) -> tuple[float, float]:
        """(lowest, highest) mean held-out RMS over the band: each split at its band's low, then high end."""
        b = self._bands()
        return (float(np.mean(b[:, 0])), float(np.mean(b[:, 1]))) if b.size else (math.nan, math.nan)

    @property
    def worst_band(self) -> tuple[float, float]:
        """(lowest, highest) worst held-out RMS over the splits, across the band."""
        b = self._bands()
        return (float(np.max(b[:, 0])), float(np.max(b[:, 1]))) if b.size else (math.nan, math.nan)

    @property
    def converged(self) -> bool:
        """Every refit converged (:attr:`HeldOutScore.converged`)."""
        return all(s.converged for s in self.scores)

    @property
    def unconverged(self) -> tuple:
        """The splits whose refit did not converge."""
        return tuple(s.split for s in self.scores if not s.converged)

    def __repr__(self) -> str:
        lo, hi = self.mean_band
        return format_repr(f"OutOfSample {self.model}", f"{len(self.splits)} splits: mean held-out RMS "
                           f"{self.mean:.4g} (band {lo:.4g}–{hi:.4g}), worst {self.worst:.4g} decades"
                           + ("" if self.converged else f"; NOT converged on {', '.join(self.unconverged)}"))

    def to_dict(self) -> dict:
        return {"model": self.model, "structural": self.structural, "n_params": self.n_params,
                "held_out_rms_mean": self.mean, "held_out_rms_worst": self.worst,
                "held_out_rms_mean_band": list(self.mean_band), "held_out_rms_worst_band": list(self.worst_band),
                "converged": self.converged, "baseline_of": self.baseline_of,
                "per_split": {s: float(r) for s, r in zip(self.splits, self.rms)},
                "scores": [s.to_dict() for s in self.scores]}


def out_of_sample(spec, data, split_list=None, *, n_params: int | None = None, cell=None, full=None,
                  **search) -> OutOfSample:
    """Refit ``spec`` (a model or its name) on each split's training data and score it on the held-out points.

    ``full``: the model's fit to all of ``data`` (a FitResult): each refit starts warm there and is checked against
    it (:func:`refit`, :class:`HeldOutScore`). ``search``: options of :func:`tenscell.fitting.fit` for every refit
    (the full fit's, for refits to its standard).
    """
    from .models import get_model

    model = get_model(spec)
    split_list = splits(data) if split_list is None else tuple(split_list)
    c = None if not model.structural else cell
    scores = [refit_split(model, s, full, cell=c, **search) for s in split_list]
    return OutOfSample.from_scores(model.name, model.structural, -1 if n_params is None else n_params, scores)


@dataclass(frozen=True, eq=False, repr=False)
class OutOfSampleComparison:
    """A model and its baselines out of sample, ranked by their mean held-out RMS.

    Attributes
    ----------
    rows : tuple of OutOfSample
        Best (lowest mean) first.
    model : str
        The model the baselines are of.
    verdict : str
        In words: whether the tensegrity does better out of sample than its own structure-free formula.
    """

    rows: tuple
    model: str
    verdict: str
    splits: tuple = field(default=())

    def row(self, name: str) -> OutOfSample:
        r = self.get(name)
        if r is None:
            raise ValueError(f"no model named {name!r} here; models: {', '.join(r.model for r in self.rows)}")
        return r

    def get(self, name: str) -> OutOfSample | None:
        """The row of model ``name``, or None where it was not scored out of sample (e.g. a baseline that misses
        the data in sample is not refereed)."""
        return next((r for r in self.rows if r.model == name), None)

    @property
    def structure_adds_nothing(self) -> bool:
        """The tensegrity's mean held-out RMS is not at least 10 % below its own structure-free formula's across
        the band."""
        return self.verdict.startswith("the structure adds nothing")

    def __repr__(self) -> str:
        return format_repr(f"OutOfSampleComparison of {self.model} over {len(self.splits)} splits",
                           *[f"{r.model}: mean {r.mean:.4g}, worst {r.worst:.4g}" for r in self.rows[:6]],
                           self.verdict)

    def to_dict(self) -> dict:
        return {"model": self.model, "splits": list(self.splits), "verdict": self.verdict,
                "models": [r.to_dict() for r in self.rows]}

    def to_dataframe(self):
        return dataframe({"model": [r.model for r in self.rows], "n_params": [r.n_params for r in self.rows],
                          "structural": [r.structural for r in self.rows],
                          "held_out_rms_mean": [r.mean for r in self.rows],
                          "held_out_rms_worst": [r.worst for r in self.rows],
                          "held_out_rms_mean_band_low": [r.mean_band[0] for r in self.rows],
                          "held_out_rms_mean_band_high": [r.mean_band[1] for r in self.rows],
                          "converged": [r.converged for r in self.rows],
                          **{f"held_out_rms[{s}]": [float(r.rms[i]) for r in self.rows]
                             for i, s in enumerate(self.splits)}})


def _fittable(model, data, cell) -> bool:
    """Whether ``model``'s problem can be laid out on ``data`` (enough points for its parameters)."""
    from ..io.data import DataError

    try:
        model.problem(data, None if not model.structural else cell)
    except (DataError, ValueError):
        return False
    return True


def standard_baselines(data) -> tuple[str, ...]:
    """The structural-damping law with and without its Newtonian term — with a modulus linear in P when some data
    set varies the prestress (the plain law has no prestress)."""
    from .parameters import prestress_varies

    if prestress_varies(as_datasets(data)):
        return "structural-damping-prestress", "structural-damping-prestress+newtonian"
    return "structural-damping", "structural-damping+newtonian"


def _band_text(band: tuple) -> str:
    lo, hi = band
    return f"{lo:.3g}" if math.isclose(lo, hi, rel_tol=5e-3) else f"{lo:.3g}–{hi:.3g}"


def out_of_sample_verdict(model: OutOfSample, formula: OutOfSample | None) -> str:
    """Words for a tensegrity against its own structure-free formula, from their mean held-out RMS across the band
    (a verdict holds only if it holds for every fit the training data cannot tell apart; refits that did not
    converge give none)."""
    if formula is None:
        return f"{model.model} has no structure-free formula of its own to be judged against"
    if not math.isfinite(model.mean):
        return f"{model.model} gave no stable cell on some held-out data: it does not predict them"
    for r in (model, formula):
        if not r.converged:
            return (f"no verdict: {r.model}'s refit did not converge on {', '.join(r.unconverged)} (training RMS "
                    f"above {UNCONVERGED:g}× the full fit's on the same points)")
    m, f = model.mean_band, formula.mean_band
    if m[1] < NO_BETTER * f[0]:
        return (f"the structure does better out of sample: {model.model}'s mean held-out RMS {_band_text(m)} is "
                f"{100 * (1 - m[1] / f[0]):.0f} % or more below its structure-free formula's ({_band_text(f)}) "
                "across the band")
    if model.mean < NO_BETTER * formula.mean:
        return (f"the structure adds nothing measurable here across the band: {model.model}'s mean held-out RMS "
                f"{_band_text(m)} against its structure-free formula's {_band_text(f)} (the best fits: "
                f"{model.mean:.3g} against {formula.mean:.3g}, but not across the band)")
    return (f"the structure adds nothing measurable here: {model.model}'s mean held-out RMS {_band_text(m)} is not "
            f"{100 * (1 - NO_BETTER):.0f} % below its structure-free formula's ({_band_text(f)})")


def _rank_key(r: OutOfSample):
    """Converged rows first (a refit that did not converge is in no ranking), then by mean, then worst."""
    return (not r.converged, r.mean, r.worst)


def compare_out_of_sample(spec, data, baselines=(), *, formula=None, n_params: dict | None = None, cell=None,
                          model_options: dict | None = None, full: dict | None = None, notify=None,
                          **search) -> OutOfSampleComparison:
    """``spec`` and each of ``baselines`` (models or names) out of sample on the same splits, ranked (refits that
    did not converge last, in no ranking).

    ``formula`` (a model or name, one of ``baselines`` or not) is the structure-free formula the tensegrity is
    judged against for the verdict (default: the model's own,
    :meth:`~tenscell.fitting.models.base.FitModel.formula`). ``n_params``: {model name: parameters on the full
    data}, for the table. ``model_options``: more options of :func:`~tenscell.fitting.fit` for ``spec``'s refits
    only (its ``bounds``, ``fixed``). ``full``: {model name: its FitResult on all of ``data``}: each model's refits
    start warm there and are checked against it (a model without one is first fitted to all of ``data`` with
    ``search``). ``notify``: called with a line before each model's refits (progress on the command line).
    """
    from .models import get_model

    model = get_model(spec)
    formula = get_model(formula) if formula is not None else model.formula()
    others = [get_model(b) for b in baselines]
    if formula is not None and all(o.name != formula.name for o in others) and not formula.structural:
        others.insert(0, formula)
    # a baseline that cannot describe these data at all (a formula of moduli against creep data) is left out
    others = [o for o in others if _fittable(o, data, cell)]
    if formula is not None and not _fittable(formula, data, cell):
        formula = None
    # a split whose training data some model cannot be fitted to (too few points for its parameters) is left out
    split_list = tuple(s for s in splits(data) if all(_fittable(m, s.train, cell) for m in (model, *others)))
    counts = dict(n_params or {})
    for m in (model, *others):  # the parameters each model has on the full data (free, less an exact gauge)
        if m.name not in counts:
            counts[m.name] = m.problem(data, None if not m.structural else cell).n_model_parameters
    say = notify or (lambda line: None)
    fulls = dict(full or {})
    rows = []
    for m in (model, *others):
        options = {**search, **(model_options or {})} if m is model else search
        say(f"out of sample: {m.name} refitted on {len(split_list)} splits")
        if m.name not in fulls:
            fulls[m.name] = refit(m, data, None, cell=None if not m.structural else cell, **options)
        row = out_of_sample(m, data, split_list, n_params=counts.get(m.name), cell=cell, full=fulls[m.name],
                            **options)
        rows.append(row if m is model else dataclasses.replace(row, baseline_of=model.name))
    judged = next((r for r in rows if formula is not None and r.model == formula.name), None)
    verdict = out_of_sample_verdict(rows[0], judged) if model.structural else \
        f"{model.name} is itself a structure-free formula"
    ranked = tuple(sorted(rows, key=_rank_key))
    return OutOfSampleComparison(rows=ranked, model=model.name, verdict=verdict,
                                 splits=tuple(s.name for s in split_list))

"""Out of sample: every model refitted without some of its data and scored on what it did not see.

A model is judged out of sample, beside baselines that have no tensegrity in them. :func:`splits` cuts the data
the way a referee would:

* every frequency sweep at one prestress is cut at several training cut-offs (:data:`CUTOFFS_HZ`: trained on the
  points at or below 1, 10, 30 Hz, scored on the points above), the other data sets kept whole;
* every prestress sweep loses some prestresses (the top third: an extrapolation in P; every third prestress: an
  interpolation), the other data sets kept whole.

:func:`out_of_sample` refits a model on each split's training data (through the one stack: :func:`fit`) and scores
the RMS of its log10 errors on the held-out points; :func:`compare_out_of_sample` does it for a model and its
baselines, ranks them by the mean over the splits (the worst reported beside it), and says when a tensegrity does
no better than its own structure-free formula: "the structure adds nothing measurable here".
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from .._results import dataframe, format_repr
from ..io.data import RheologyData
from .parameters import as_datasets
from .records import data_axis
from .scores import data_subset

__all__ = ["Split", "splits", "OutOfSample", "out_of_sample", "OutOfSampleComparison", "compare_out_of_sample",
           "CUTOFFS_HZ", "NO_BETTER", "held_out_rms", "out_of_sample_verdict", "standard_baselines"]

#: training cut-offs of a frequency sweep (Hz): trained at or below, scored above
CUTOFFS_HZ = (1.0, 10.0, 30.0)
#: a tensegrity whose mean held-out RMS is not at least this fraction below its structure-free formula's does no
#: better than it (a 10 % margin: below that, the difference is within what another start or split would move)
NO_BETTER = 0.9
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


def splits(data, cutoffs_hz=CUTOFFS_HZ) -> tuple[Split, ...]:
    """Every split of :mod:`the module docstring <tenscell.fitting.validation>` the data allow (moduli only: a
    creep data set is kept whole in every training set)."""
    datasets = as_datasets(data)
    out: list[Split] = []
    for k, d in enumerate(datasets):
        if d.kind == "creep":
            continue
        masks: list[tuple[str, np.ndarray]] = []
        if data_axis(d) == "frequency" and np.unique(d.frequency_hz).size >= 2 * _MIN_POINTS:
            masks += [(f"≤ {c:g} Hz", d.frequency_hz <= c) for c in cutoffs_hz]
        elif data_axis(d) == "prestress":
            P = np.asarray(d.prestress)
            levels = np.unique(P)
            top = levels[-max(1, levels.size // 3):]
            masks.append(("top third of P held out", ~np.isin(P, top)))
            masks.append(("every third P held out", ~np.isin(P, levels[1::3])))
        for label, train in masks:
            if train.sum() < _MIN_POINTS or (~train).sum() < 1:
                continue
            cut = data_subset(d, train, "training")
            out.append(Split(name=f"{_short(d.source)}: {label}",
                             train=tuple(cut if j == k else e for j, e in enumerate(datasets)),
                             held=data_subset(d, ~train, "held out"), dataset=k))
    return tuple(out)


def held_out_rms(result, split: Split) -> float:
    """RMS (decades) of a fit's log10 errors at a split's held-out points (inf where the model is not a stable cell
    there)."""
    held = split.held
    try:
        if held.prestress is not None and np.unique(held.prestress).size > 1:
            Gs, Gl = result.moduli(held.frequency_hz, prestress_pa=held.prestress)
        else:
            Gs, Gl = result.moduli(held.frequency_hz, dataset=split.dataset)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return math.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.concatenate([np.log10(Gs / held.G_storage), np.log10(Gl / held.G_loss)])
    return float(np.sqrt(np.mean(r**2))) if np.all(np.isfinite(r)) else math.inf


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
        Held-out RMS (decades) per split (inf where the refit gave no stable cell there).
    baseline_of : str or None
        For a baseline: the model it is the baseline of.
    """

    model: str
    structural: bool
    n_params: int
    splits: tuple
    rms: np.ndarray
    baseline_of: str | None = None

    @property
    def mean(self) -> float:
        """Mean held-out RMS over the splits (decades)."""
        return float(np.mean(self.rms)) if self.rms.size else math.nan

    @property
    def worst(self) -> float:
        """Largest held-out RMS over the splits (decades)."""
        return float(np.max(self.rms)) if self.rms.size else math.nan

    def __repr__(self) -> str:
        return format_repr(f"OutOfSample {self.model}", f"{len(self.splits)} splits: mean held-out RMS "
                           f"{self.mean:.4g}, worst {self.worst:.4g} decades")

    def to_dict(self) -> dict:
        return {"model": self.model, "structural": self.structural, "n_params": self.n_params,
                "held_out_rms_mean": self.mean, "held_out_rms_worst": self.worst, "baseline_of": self.baseline_of,
                "per_split": {s: float(r) for s, r in zip(self.splits, self.rms)}}


def out_of_sample(spec, data, split_list=None, *, n_params: int | None = None, cell=None, **search) -> OutOfSample:
    """Refit ``spec`` (a model or its name) on each split's training data and score it on the held-out points.

    ``search``: options of :func:`tenscell.fitting.fit` for every refit (e.g. a short budget: ``starts=2``).
    """
    from .entry import fit
    from .models import get_model

    model = get_model(spec)
    split_list = splits(data) if split_list is None else tuple(split_list)
    rms = []
    for s in split_list:
        r = fit(s.train, None if not model.structural else cell, model=model, progress=False, **search)
        rms.append(held_out_rms(r, s))
    return OutOfSample(model=model.name, structural=model.structural, n_params=-1 if n_params is None else n_params,
                       splits=tuple(s.name for s in split_list), rms=np.array(rms, dtype=float))


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
        for r in self.rows:
            if r.model == name:
                return r
        raise ValueError(f"no model named {name!r} here; models: {', '.join(r.model for r in self.rows)}")

    @property
    def structure_adds_nothing(self) -> bool:
        """The tensegrity's mean held-out RMS is not at least 10 % below its own structure-free formula's."""
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


def out_of_sample_verdict(model: OutOfSample, formula: OutOfSample | None) -> str:
    """Words for a tensegrity against its own structure-free formula, from their mean held-out RMS."""
    if formula is None:
        return f"{model.model} has no structure-free formula of its own to be judged against"
    if not math.isfinite(model.mean):
        return f"{model.model} gave no stable cell on some held-out data: it does not predict them"
    if model.mean < NO_BETTER * formula.mean:
        return (f"the structure does better out of sample: {model.model}'s mean held-out RMS {model.mean:.3g} is "
                f"{100 * (1 - model.mean / formula.mean):.0f} % below its structure-free formula's ({formula.mean:.3g})")
    return (f"the structure adds nothing measurable here: {model.model}'s mean held-out RMS {model.mean:.3g} is not "
            f"{100 * (1 - NO_BETTER):.0f} % below its structure-free formula's ({formula.mean:.3g})")


def compare_out_of_sample(spec, data, baselines=(), *, formula=None, n_params: dict | None = None, cell=None,
                          model_options: dict | None = None, notify=None, **search) -> OutOfSampleComparison:
    """``spec`` and each of ``baselines`` (models or names) out of sample on the same splits, ranked.

    ``formula`` (a model or name, one of ``baselines`` or not) is the structure-free formula the tensegrity is
    judged against for the verdict (default: the model's own, :meth:`~tenscell.fitting.models.base.FitModel.formula`). ``n_params``: {model name: parameters on the full data}, for the table.
    ``model_options``: more options of :func:`~tenscell.fitting.fit` for ``spec``'s refits only (its ``bounds``,
    ``fixed``). ``notify``: called with a line before each model's refits (progress on the command line).
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
    say(f"out of sample: {model.name} refitted on {len(split_list)} splits")
    rows = [out_of_sample(model, data, split_list, n_params=counts.get(model.name), cell=cell,
                          **search, **(model_options or {}))]
    for o in others:
        say(f"out of sample: {o.name} refitted on {len(split_list)} splits")
        rows.append(dataclasses.replace(out_of_sample(o, data, split_list, n_params=counts.get(o.name), cell=cell,
                                                      **search), baseline_of=model.name))
    judged = next((r for r in rows if formula is not None and r.model == formula.name), None)
    verdict = out_of_sample_verdict(rows[0], judged) if model.structural else \
        f"{model.name} is itself a structure-free formula"
    ranked = tuple(sorted(rows, key=lambda r: (r.mean, r.worst)))
    return OutOfSampleComparison(rows=ranked, model=model.name, verdict=verdict,
                                 splits=tuple(s.name for s in split_list))

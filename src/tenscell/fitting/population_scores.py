"""A population model scored the way a referee would: against per-cell power laws, out of sample, by its correlations.

:func:`score_population` fits a :class:`~tenscell.fitting.models.population.Population` to every cell of a line and
compares it with **independent per-cell structure-free formulas** (by default the structural-damping power law with
2 parameters per cell, and with a Newtonian term, 3 per cell), each fitted cell by cell through the same search:

* **BIC** on the same residuals (every cell's log10 G′ and G″; :func:`~tenscell.fitting.records.information_criteria`
  with ``k`` the free parameters of all cells together);
* **held-out frequencies**: for each training window ``[lo, hi]`` Hz, every model is fitted to each cell's points in
  the window and scored (RMS of log10 G′, G″, decades) at the cell's points outside it;
* **held-out cells** (k-fold): the population is fitted to the cells of the other folds; each held-out cell's one
  per-cell parameter is then set by **one measured number**, its G′ at the anchor frequency (two per-cell
  parameters: its G′ and G″ there), and the rest of its spectrum (every other residual) is predicted. The per-cell formulas meet the same test: their other parameters
  at the median of the training cells' fits, their scale (``G0``) set by the same measured G′;
* **correlations** across cells (Spearman): a cell's exponent with its stiffness (G′ at the anchor frequency) and
  each stiffness with each covariate (e.g. the aspect ratio from the files' comments), measured against those of
  the population model's fitted cells. The exponent is the one Xie et al. report, a springpot fitted to G′ and G″
  over 1–100 Hz (:func:`springpot_exponent`), computed the same way on data and model.

**The exponent–stiffness relation as a measurement would show it** (:func:`exponent_stiffness`): a population with
one parameter per cell puts every fitted cell on one curve, so its exponent–stiffness Spearman is ±1 by
construction, while a measured cell's exponent and stiffness carry measurement error. Each measured cell's error
is estimated from its own spectrum (:func:`measurement_errors`: the springpot fit's standard error of α, and the
scatter of log10 G′ about it for the stiffness); that scatter is added to the model's fitted cells, cell by cell, in
many seeded draws, and the slope dα/dlog10 k (least squares) and the Spearman correlation are computed after it,
against the measured ones (which carry the same error).

What these numbers do not show is listed in :attr:`PopulationScores.notes` (computed from the run: parameters at a
bound, the per-cell parameter's role in the correlations).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

import numpy as np

from .._progress import progress_bar
from .._results import dataframe, format_repr
from ..io.data import RheologyData
from .models import get_model
from .models.population import Population
from .records import information_criteria
from .scores import data_subset

if TYPE_CHECKING:
    from .models.formulas import Formula
    from .result import FitResult

__all__ = ["PopulationScores", "ScoreRow", "Correlation", "score_population", "population_cells", "springpot_exponent",
           "comment_values", "EXPONENT_BAND_HZ", "DEFAULT_SPLITS", "DEFAULT_BASELINES", "ExponentStiffness",
           "exponent_stiffness", "measurement_errors", "springpot_exponent_error", "RELATION_DRAWS"]

#: frequencies (Hz) over which a cell's exponent is measured (Xie et al.'s springpot fits: 1–100 Hz)
EXPONENT_BAND_HZ = (1.0, 100.0)
#: training windows (Hz) of the held-out-frequency scores (issue 26: 1–30 Hz → 100–200 Hz; 3–100 Hz → 1 and 200 Hz)
DEFAULT_SPLITS = ((0.0, 30.0), (3.0, 100.0))
#: the independent per-cell formulas every population model is scored against
DEFAULT_BASELINES = ("structural-damping", "structural-damping+newtonian")
#: seeded draws of the measurement's scatter added to the model population (:func:`exponent_stiffness`)
RELATION_DRAWS = 1000


def springpot_exponent(f_hz, G_storage, G_loss, band_hz=EXPONENT_BAND_HZ) -> float:
    """Exponent α of the springpot ``G* = A (iω)^α`` fitted to G′ and G″ (least squares in log10) over ``band_hz``.

    ``log G′ = a + α log ω + log cos(πα/2)``, ``log G″ = a + α log ω + log sin(πα/2)``: for each α the scale ``a`` is
    the mean of what remains, so one bounded scalar search over 0 < α < 1 gives the fit. NaN with fewer than two
    frequencies in the band.
    """
    import scipy.optimize

    f = np.asarray(f_hz, dtype=float)
    sel = (f >= band_hz[0] * (1 - 1e-9)) & (f <= band_hz[1] * (1 + 1e-9))
    if np.unique(f[sel]).size < 2:
        return math.nan
    lw = np.log10(2 * np.pi * f[sel])
    y = np.concatenate([np.log10(np.asarray(G_storage, float)[sel]), np.log10(np.asarray(G_loss, float)[sel])])

    def rss(alpha):
        base = alpha * np.concatenate([lw, lw]) + np.concatenate(
            [np.full(lw.size, math.log10(math.cos(math.pi * alpha / 2))),
             np.full(lw.size, math.log10(math.sin(math.pi * alpha / 2)))])
        r = y - base
        return float(np.sum((r - r.mean()) ** 2))

    return float(scipy.optimize.minimize_scalar(rss, bounds=(1e-4, 1 - 1e-4), method="bounded",
                                                options={"xatol": 1e-7}).x)


def _springpot_columns(f_hz, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """d log10 G′/dα and d log10 G″/dα of the springpot ``A (iω)^α`` at frequencies ``f_hz`` (Hz)."""
    lw = np.log10(2 * np.pi * np.asarray(f_hz, dtype=float))
    half = math.pi / 2
    return (lw - half * math.tan(half * alpha) / math.log(10), lw + half / math.tan(half * alpha) / math.log(10))


def springpot_exponent_error(f_hz, G_storage, G_loss, band_hz=EXPONENT_BAND_HZ) -> tuple[float, float, float]:
    """``(α, standard error of α, σ)`` of the springpot fit of :func:`springpot_exponent` (least squares in log10):
    σ is the RMS of its residuals over the 2n − 2 degrees of freedom (decades), the standard error of α the linear
    one, ``σ·√((JᵀJ)⁻¹)_αα`` with the columns ∂/∂log10 A = 1 and ∂/∂α of log10 G′, log10 G″. NaNs with fewer than
    two frequencies in the band (or no degree of freedom left)."""
    alpha = springpot_exponent(f_hz, G_storage, G_loss, band_hz)
    f = np.asarray(f_hz, dtype=float)
    sel = (f >= band_hz[0] * (1 - 1e-9)) & (f <= band_hz[1] * (1 + 1e-9))
    n = int(sel.sum())
    if not math.isfinite(alpha) or 2 * n <= 2:
        return alpha, math.nan, math.nan
    ds, dl = _springpot_columns(f[sel], alpha)
    a_col = np.concatenate([ds, dl])
    y = np.concatenate([np.log10(np.asarray(G_storage, float)[sel]), np.log10(np.asarray(G_loss, float)[sel])])
    base = alpha * np.log10(2 * np.pi * np.concatenate([f[sel], f[sel]])) + np.concatenate(
        [np.full(n, math.log10(math.cos(math.pi * alpha / 2))), np.full(n, math.log10(math.sin(math.pi * alpha / 2)))])
    r = y - base
    r = r - r.mean()  # log10 A at its least-squares value
    sigma = float(np.sqrt(np.sum(r**2) / (2 * n - 2)))
    # (JᵀJ)⁻¹_αα for J = [1, a]: the variance of α about the intercept's own fit
    s_aa = float(np.sum((a_col - a_col.mean()) ** 2))
    return alpha, (sigma / math.sqrt(s_aa) if s_aa > 0 else math.nan), sigma


def measurement_errors(cells, band_hz=EXPONENT_BAND_HZ) -> tuple[np.ndarray, np.ndarray]:
    """Per measured cell: the standard error of its exponent (:func:`springpot_exponent_error`) and of its log10
    stiffness (the scatter σ of its spectrum about that springpot, decades): the measurement's own error, estimated
    from each cell's data."""
    out = np.array([springpot_exponent_error(d.frequency_hz, d.G_storage, d.G_loss, band_hz)[1:] for d in cells],
                   dtype=float).reshape(-1, 2)
    return out[:, 0], out[:, 1]


def _slope(x: np.ndarray, y: np.ndarray) -> float:
    """The least-squares slope of y on x (NaN with fewer than 3 points or no spread in x)."""
    if x.size < 3 or np.ptp(x) == 0:
        return math.nan
    xc = x - x.mean()
    return float(np.sum(xc * (y - y.mean())) / np.sum(xc**2))


@dataclass(frozen=True)
class ExponentStiffness:
    """The exponent–stiffness relation across cells: measured, of the model's fitted cells, and of those cells with
    the measurement's scatter added (:func:`exponent_stiffness`).

    Attributes
    ----------
    n_cells : int
        Cells with a finite exponent, stiffness and errors.
    slope_measured, spearman_measured : float
        dα/dlog10 k (least squares) and the Spearman correlation of the measured cells.
    slope_model, spearman_model : float
        The same of the model's fitted cells (no scatter).
    slope_noisy, spearman_noisy : (float, float, float)
        The model's cells with the measured scatter added: 5th percentile, median, 95th percentile over the draws.
    draws : int
    se_alpha_median, se_log10_k_median : float
        The median measurement errors added (dimensionless; decades).
    """

    n_cells: int
    slope_measured: float
    spearman_measured: float
    slope_model: float
    spearman_model: float
    slope_noisy: tuple
    spearman_noisy: tuple
    draws: int
    se_alpha_median: float
    se_log10_k_median: float

    def slope_within(self, fraction: float) -> bool:
        """The noise-added slope's median within ±``fraction`` of the measured slope."""
        return abs(self.slope_noisy[1] - self.slope_measured) <= fraction * abs(self.slope_measured)

    def spearman_within(self, tol: float) -> bool:
        """The noise-added Spearman's median within ±``tol`` of the measured one."""
        return abs(self.spearman_noisy[1] - self.spearman_measured) <= tol

    def to_dict(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}


def exponent_stiffness(alpha_measured, k_measured, alpha_model, k_model, se_alpha, se_log10_k, *,
                       draws: int = RELATION_DRAWS, seed: int = 0) -> ExponentStiffness:
    """The exponent–stiffness relation (module docstring): per cell the measured and the model's exponent α and
    stiffness k (Pa), and the measurement's standard errors of α and of log10 k; ``draws`` seeded draws of normal
    scatter with those errors, cell by cell, are added to the model's cells."""
    import scipy.stats

    a_m, k_m, a_p, k_p, se_a, se_k = (np.asarray(x, dtype=float) for x in
                                       (alpha_measured, k_measured, alpha_model, k_model, se_alpha, se_log10_k))
    with np.errstate(divide="ignore", invalid="ignore"):
        lk_m, lk_p = np.log10(k_m), np.log10(k_p)
    ok = np.isfinite(a_m) & np.isfinite(lk_m) & np.isfinite(a_p) & np.isfinite(lk_p) & np.isfinite(se_a) \
        & np.isfinite(se_k)
    a_m, lk_m, a_p, lk_p, se_a, se_k = (x[ok] for x in (a_m, lk_m, a_p, lk_p, se_a, se_k))
    rng = np.random.default_rng(seed)
    slopes, rhos = np.full(draws, np.nan), np.full(draws, np.nan)
    if ok.sum() >= 3:
        for i in range(draws):
            a = a_p + rng.normal(0.0, se_a)
            lk = lk_p + rng.normal(0.0, se_k)
            slopes[i] = _slope(lk, a)
            rhos[i] = scipy.stats.spearmanr(lk, a)[0]

    def q(x):
        return tuple(float(v) for v in np.nanpercentile(x, [5, 50, 95])) if np.isfinite(x).any() else \
            (math.nan,) * 3

    return ExponentStiffness(
        n_cells=int(ok.sum()), slope_measured=_slope(lk_m, a_m), spearman_measured=_spearman(a_m, lk_m)[0],
        slope_model=_slope(lk_p, a_p), spearman_model=_spearman(a_p, lk_p)[0], slope_noisy=q(slopes),
        spearman_noisy=q(rhos), draws=int(draws), se_alpha_median=float(np.median(se_a)) if se_a.size else math.nan,
        se_log10_k_median=float(np.median(se_k)) if se_k.size else math.nan)


def comment_values(data: RheologyData) -> dict:
    """The ``key=value`` numbers in a data set's comment lines (e.g. ``aspect_ratio=1.385 area=165.5``)."""
    out = {}
    for line in data.comments:
        for token in line.replace(";", " ").replace(",", " ").split():
            key, eq, value = token.partition("=")
            if not eq or not key.isidentifier():
                continue
            try:
                out[key] = float(value)
            except ValueError:
                continue
    return out


@dataclass(frozen=True)
class ScoreRow:
    """One model's scores over a population.

    Attributes
    ----------
    model : str
    kind : str
        ``"population"`` (fitted jointly) or ``"independent per cell"``.
    n_params : int
        Free parameters over all cells.
    rms_log10_error : float
        RMS of the log10 errors over every cell (decades).
    bic : float
        On the same residuals as every other row.
    heldout_frequencies : tuple of float
        RMS (decades) at each cell's points outside each training window, in the order of the splits.
    heldout_cells : float
        RMS (decades) of the held-out cells' predicted residuals (k-fold; one measured G′ per cell).
    """

    model: str
    kind: str
    n_params: int
    rms_log10_error: float
    bic: float
    heldout_frequencies: tuple
    heldout_cells: float

    def to_dict(self) -> dict:
        return {"model": self.model, "kind": self.kind, "n_params": self.n_params,
                "rms_log10_error": self.rms_log10_error, "BIC": self.bic,
                "heldout_frequencies_rms_log10": list(self.heldout_frequencies),
                "heldout_cells_rms_log10": self.heldout_cells}


@dataclass(frozen=True)
class Correlation:
    """A Spearman rank correlation across cells, measured and implied by the population model.

    Attributes
    ----------
    x, y : str
        What is correlated (``"exponent"``, ``"stiffness"``, a covariate).
    measured : float
        Both from the data.
    model : float
        Both from the population model's fitted cells (a covariate is the measured one).
    model_vs_measured : float
        The model's ``x`` against the measured ``y``.
    n_cells : int
        Cells with both values.
    """

    x: str
    y: str
    measured: float
    model: float
    model_vs_measured: float
    n_cells: int

    def to_dict(self) -> dict:
        return {"x": self.x, "y": self.y, "measured": self.measured, "model": self.model,
                "model_vs_measured": self.model_vs_measured, "n_cells": self.n_cells}


@dataclass(frozen=True, eq=False, repr=False)
class PopulationScores:
    """What :func:`score_population` found (module docstring).

    Attributes
    ----------
    label : str
        What the cells are (e.g. a cell line).
    population : Population
    fit : FitResult
        The population fitted to every cell.
    rows : tuple of ScoreRow
        The population first, then each independent per-cell formula.
    splits : tuple of (float, float)
        The training windows (Hz) of the held-out-frequency scores.
    folds : int
    anchor_hz : float
        The frequency (Hz) whose measured G′ sets a held-out cell's per-cell parameter, and where stiffness is read.
    cells : dict of str to ndarray
        Per cell: ``source``, the measured and model ``exponent`` and ``stiffness_Pa``, each covariate, and the
        population's per-cell parameters (SI units).
    correlations : tuple of Correlation
    notes : tuple of str
        What the numbers do not show.
    relation : ExponentStiffness or None
        The exponent–stiffness relation with the measurement's scatter added to the model's cells.
    """

    label: str
    population: Population
    fit: FitResult
    rows: tuple
    splits: tuple
    folds: int
    anchor_hz: float
    cells: dict
    correlations: tuple
    notes: tuple
    relation: ExponentStiffness | None = None

    @property
    def n_cells(self) -> int:
        return len(self.fit.datasets)

    def row(self, model: str) -> ScoreRow:
        """The row of ``model``."""
        for r in self.rows:
            if r.model == model:
                return r
        raise ValueError(f"no model {model!r}; rows: {', '.join(r.model for r in self.rows)}")

    def correlation(self, x: str, y: str) -> Correlation:
        """The correlation of ``x`` with ``y``."""
        for c in self.correlations:
            if (c.x, c.y) == (x, y):
                return c
        raise ValueError(f"no correlation of {x} with {y}")

    def __repr__(self) -> str:
        lines = [f"{r.model} ({r.kind}): k={r.n_params}, rms {r.rms_log10_error:.3g}, BIC {r.bic:.1f}, held-out "
                 f"frequencies {', '.join(f'{x:.3g}' for x in r.heldout_frequencies)}, held-out cells "
                 f"{r.heldout_cells:.3g}" for r in self.rows]
        lines += [f"Spearman {c.x}–{c.y}: measured {c.measured:+.2f}, model {c.model:+.2f}" for c in self.correlations]
        return format_repr(f"PopulationScores {self.label}: {self.population.name}, {self.n_cells} cells", *lines)

    def to_dataframe(self):
        """The rows as a table (RMS in decades)."""
        cols: dict = {"model": [r.model for r in self.rows], "kind": [r.kind for r in self.rows],
                      "n_params": [r.n_params for r in self.rows],
                      "rms_log10_error": [r.rms_log10_error for r in self.rows], "BIC": [r.bic for r in self.rows]}
        for i, (lo, hi) in enumerate(self.splits):
            cols[f"heldout_rms_log10_train_{lo:g}_{hi:g}Hz"] = [r.heldout_frequencies[i] for r in self.rows]
        cols["heldout_cells_rms_log10"] = [r.heldout_cells for r in self.rows]
        return dataframe(cols, {"label": self.label, "population": self.population.name})

    def cells_dataframe(self):
        """Per cell: source, measured and model exponent and stiffness (Pa), covariates, per-cell parameters."""
        return dataframe(self.cells, {"label": self.label, "anchor_Hz": self.anchor_hz})

    def to_dict(self) -> dict:
        return {"label": self.label, "population": self.population.to_dict(), "n_cells": self.n_cells,
                "rows": [r.to_dict() for r in self.rows], "splits_Hz": [list(s) for s in self.splits],
                "folds": self.folds, "anchor_Hz": self.anchor_hz,
                "correlations": [c.to_dict() for c in self.correlations], "notes": list(self.notes),
                "exponent_stiffness": None if self.relation is None else self.relation.to_dict()}


# ---------------------------------------------------------------------------------------
# the scores
# ---------------------------------------------------------------------------------------
def _window(d: RheologyData, lo: float, hi: float) -> tuple[RheologyData | None, RheologyData | None]:
    inside = (d.frequency_hz >= lo * (1 - 1e-9)) & (d.frequency_hz <= hi * (1 + 1e-9))
    train = data_subset(d, inside, "training") if inside.any() else None
    test = data_subset(d, ~inside, "held out") if (~inside).any() else None
    return train, test


def _rms(parts) -> float:
    r = np.concatenate([np.ravel(p) for p in parts]) if parts else np.zeros(0)
    return float(np.sqrt(np.mean(r**2))) if r.size and np.all(np.isfinite(r)) else math.inf


def _errors(Gs, Gl, d: RheologyData) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.concatenate([np.log10(Gs / d.G_storage), np.log10(Gl / d.G_loss)])
    return np.where(np.isfinite(r), r, np.inf)


def _fit(data, model, settings: dict, cell=None) -> FitResult:
    """One fit through the stack with the scores' search settings (``starts``, ``hops``, ``seed``)."""
    from .entry import fit

    return fit(data, cell, model=model, starts=settings["starts"], hops=settings["hops"], seed=settings["seed"],
               max_points=None, progress=False)


def _independent(cells, model, settings) -> list:
    return [_fit(d, model, settings) for d in cells]


def _anchor_index(d: RheologyData, anchor_hz: float) -> int:
    return int(np.argmin(np.abs(np.log(d.frequency_hz / anchor_hz))))


def _predict_cell(base, values: dict, own: tuple, d: RheologyData, anchor_hz: float, cell=None) -> np.ndarray:
    """The residuals of cell ``d`` (log10 model/data, G′ then G″) predicted by ``base`` with the parameters ``values``
    (by name, SI; those named in ``own`` are the start) and its own parameters ``own`` set by its measured moduli at
    the anchor frequency: G′ for one own parameter, G′ and G″ for two. The anchor's residuals are left out."""
    import scipy.optimize

    pb = base.problem(d, cell)
    phi = pb.fixed_log.copy()
    for name, v in values.items():
        if name in pb.names:
            phi[pb.names.index(name)] = math.log(v)
    j = np.array([pb.names.index(n) for n in own])
    i = _anchor_index(d, anchor_hz)
    anchors = np.array([i, d.n + i][: j.size])

    def miss(x):
        phi[j] = x
        Gs, Gl = pb.moduli(phi[pb.free])
        r = _errors(Gs, Gl, d)[anchors]
        return np.where(np.isfinite(r), r, 10.0)

    lo, hi = pb.lower[j], pb.upper[j]
    x0 = np.clip(phi[j], lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
    phi[j] = scipy.optimize.least_squares(miss, x0, bounds=(lo, hi), xtol=1e-12, ftol=1e-12, gtol=1e-12).x
    Gs, Gl = pb.moduli(phi[pb.free])
    return np.delete(_errors(Gs, Gl, d), anchors)


def _folds(n: int, folds: int, seed: int) -> list[np.ndarray]:
    order = np.random.default_rng(seed).permutation(n)
    return [np.sort(order[k::folds]) for k in range(folds)]




def score_population(cells, population, *, baselines=DEFAULT_BASELINES, splits=DEFAULT_SPLITS, folds: int = 5,
                     anchor_hz: float = 10.0, covariates: dict | None = None, label: str = "", cell=None,
                     starts: int = 2, hops: int = 2, seed: int = 0, progress: bool | None = None) -> PopulationScores:
    """Score a population model against independent per-cell formulas (module docstring).

    Parameters
    ----------
    cells : sequence of RheologyData
        One frequency sweep per cell.
    population : Population
        With one or two per-cell parameters: a held-out cell's are set by its measured G′ (one) or G′ and G″ (two)
        at the anchor frequency.
    baselines : sequence of str or Formula
        Structure-free formulas fitted to each cell on its own; each must have a scale ``G0``.
    splits : sequence of (float, float)
        Training windows (Hz) for the held-out-frequency scores.
    folds : int
        Folds of the held-out-cell scores (2 to the number of cells).
    anchor_hz : float
        The measured G′ nearest this frequency (Hz) sets a held-out cell's own parameter; stiffness is G′ here.
    covariates : dict of str to sequence of float, optional
        Per-cell measured quantities to correlate with stiffness; default every ``key=value`` number the cells'
        comments share (:func:`comment_values`).
    label : str
    cell : Cell, optional
        The reference cell of a structural base model.
    starts, hops, seed : int
        Search settings of every fit (see :func:`tenscell.fitting.fit`).
    progress : bool or None

    Returns
    -------
    PopulationScores
    """
    population = get_model(population)
    if not population.capabilities.per_cell or len(population.per_cell) > 2:
        raise ValueError("score_population: needs a Population with one or two per-cell parameters (a held-out "
                         "cell's are set by its G′, or G′ and G″, at the anchor frequency)")
    cells = tuple(cells)
    if not 2 <= int(folds) <= len(cells):
        raise ValueError(f"folds must lie between 2 and the number of cells ({len(cells)}), got {folds!r}")
    forms = [get_model(b) for b in baselines]
    for b in forms:
        caps = b.capabilities  # a structure-free formula of one cell (not a population of them)
        if caps.structural or caps.per_cell or "G0" not in [r[0] for r in cast("Formula", b).parameter_rows]:
            raise ValueError(f"baselines: {b.name!r} is not a structure-free formula with a scale G0")
    settings = dict(starts=starts, hops=hops, seed=seed)
    steps = 1 + len(forms) + len(splits) * (1 + len(forms)) + folds
    with progress_bar(total=steps, desc=f"score {label or population.name}", unit="fit", progress=progress) as bar:
        def step(x):
            bar.update(1)
            return x

        joint = step(_fit(cells, population, settings, cell))
        independent = [step(_independent(cells, b, settings)) for b in forms]
        held_f = [step(_heldout_frequencies(cells, population, forms, lo, hi, settings, cell, bar))
                  for lo, hi in splits]
        held_c = _heldout_cells(cells, population, forms, independent, joint, folds, anchor_hz, settings, cell, step)
    rows = [_row(population.name, "population", [joint], joint.sigma_known, [h[0] for h in held_f], held_c[0])]
    rows += [_row(b.name, "independent per cell", fits, joint.sigma_known, [h[1 + i] for h in held_f], held_c[1 + i])
             for i, (b, fits) in enumerate(zip(forms, independent))]
    table, correlations = _correlations(cells, joint, anchor_hz, covariates)
    se_alpha, se_k = measurement_errors(cells)
    relation = exponent_stiffness(table["exponent_measured"], table["stiffness_measured_Pa"], table["exponent_model"],
                                  table["stiffness_model_Pa"], se_alpha, se_k, seed=seed)
    return PopulationScores(label=label, population=population, fit=joint, rows=tuple(rows),
                            splits=tuple((float(a), float(b)) for a, b in splits), folds=int(folds),
                            anchor_hz=float(anchor_hz), cells=table, correlations=correlations,
                            notes=_notes(joint, correlations), relation=relation)


def _row(name, kind, fits, sigma_known: bool, held_f, held_c) -> ScoreRow:
    """A model's row from its fits (one joint fit, or one per cell), all scored on the same residuals."""
    weighted = np.concatenate([f.problem.residuals(f.theta) for f in fits])
    weights = np.concatenate([f.problem.weights for f in fits])
    k = sum(int(f.problem.n_model_parameters) for f in fits)
    _, bic, _ = information_criteria(weighted, k, sigma_known=sigma_known, weights=weights)
    plain = np.concatenate([f.residuals for f in fits])
    return ScoreRow(model=name, kind=kind, n_params=k, rms_log10_error=float(np.sqrt(np.mean(plain**2))),
                    bic=float(bic), heldout_frequencies=tuple(held_f), heldout_cells=held_c)


def _heldout_frequencies(cells, population, forms, lo, hi, settings, cell, bar) -> list[float]:
    """RMS at each cell's points outside ``[lo, hi]`` Hz of the population and of each formula, all trained inside."""
    pairs = [(tr, te) for tr, te in (_window(d, lo, hi) for d in cells) if tr is not None and te is not None]
    train, test = [tr for tr, _ in pairs], [te for _, te in pairs]
    joint = _fit(train, population, settings, cell)
    out = [_rms([_errors(*joint.moduli(t.frequency_hz, dataset=i), t) for i, t in enumerate(test)])]
    for b in forms:
        fits = _independent(train, b, settings)
        out.append(_rms([_heldout_errors(f, t) for f, t in zip(fits, test)]))
        bar.update(1)
    return out


def _heldout_errors(result, held: RheologyData) -> np.ndarray:
    Gs, Gl = result.moduli(held.frequency_hz)
    return _errors(Gs, Gl, held)


def _heldout_cells(cells, population, forms, independent, joint, folds, anchor_hz, settings, cell, step):
    """k-fold: RMS of the held-out cells' predicted residuals, for the population and each formula."""
    own = population.per_cell
    errors: list[list[np.ndarray]] = [[] for _ in range(1 + len(forms))]
    for held in _folds(len(cells), int(folds), int(settings["seed"])):
        rest = [d for k, d in enumerate(cells) if k not in set(held.tolist())]
        part = step(_fit(rest, population, settings, cell))
        # the shared values, and the training cells' median own values as the start
        typical = part.problem.typical_phi(part.problem.full(part.theta))
        values = dict(zip(part.problem.cells[0].names, np.exp(typical)))
        training = np.setdiff1d(np.arange(len(cells)), held)
        # a formula for a new cell: every parameter at its median over the training cells' own fits (G0 as the
        # start of the anchor's solve)
        medians = [{p.name: float(np.exp(np.median([math.log(fits[j].value(p.name)) for j in training])))
                    for p in fits[0].parameters} for fits in independent]
        for k in held:
            errors[0].append(_predict_cell(population.base, values, own, cells[k], anchor_hz, cell))
            for i, b in enumerate(forms):
                errors[1 + i].append(_predict_cell(b, medians[i], ("G0",), cells[k], anchor_hz))
    return [_rms(e) for e in errors]


def _stiffness(f_hz, Gs, anchor_hz: float) -> float:
    i = int(np.argmin(np.abs(np.log(np.asarray(f_hz) / anchor_hz))))
    return float(Gs[i]) if abs(math.log(f_hz[i] / anchor_hz)) < 1e-6 else math.nan


def _spearman(x, y) -> tuple[float, int]:
    import scipy.stats

    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 3 or np.ptp(x[ok]) == 0 or np.ptp(y[ok]) == 0:  # no ranks to correlate
        return math.nan, int(ok.sum())
    return float(scipy.stats.spearmanr(x[ok], y[ok])[0]), int(ok.sum())


def population_cells(result, anchor_hz: float = 10.0):
    """Per cell of a population fit: source, points, RMS, the per-cell parameters with their standard errors,
    and the measured and model exponent (:func:`springpot_exponent`) and stiffness (G′ at ``anchor_hz``, Pa; the
    measured one where the cell has a point there, else NaN), as a DataFrame with units in the column names."""
    pb = result.problem
    errors = result.standard_errors
    cols: dict = {"cell": np.arange(pb.n_cells), "source": [d.source for d in result.datasets],
                  "n_points": [d.n for d in result.datasets],
                  "rms_log10_error": [f.rms_log10_error for f in result.fits]}
    for j, name in enumerate(pb.own_names):
        idx = [int(pb.own_index(k)[j]) for k in range(pb.n_cells)]
        unit = _unit_suffix(pb.units[idx[0]])
        cols[f"{name}_{unit}"] = [result.parameters[i].value for i in idx]
        cols[f"{name}_stderr_{unit}"] = [math.nan if errors[i][0] is None else errors[i][0] for i in idx]
        cols[f"{name}_at_bound"] = [result.parameters[i].at_bound or "" for i in idx]
    meas_e, meas_s, model_e, model_s = [], [], [], []
    for k, d in enumerate(result.datasets):
        meas_e.append(springpot_exponent(d.frequency_hz, d.G_storage, d.G_loss))
        meas_s.append(_stiffness(d.frequency_hz, d.G_storage, anchor_hz))
        Gs, Gl = result.moduli(d.frequency_hz, dataset=k)
        model_e.append(springpot_exponent(d.frequency_hz, Gs, Gl))
        model_s.append(float(result.moduli(np.array([anchor_hz]), dataset=k)[0][0]))
    cols.update({"exponent_measured": meas_e, "exponent_model": model_e, "stiffness_measured_Pa": meas_s,
                 "stiffness_model_Pa": model_s})
    return dataframe(cols, {"anchor_Hz": anchor_hz, "exponent": "springpot exponent fitted to G', G'' over "
                                                               f"{EXPONENT_BAND_HZ[0]:g}-{EXPONENT_BAND_HZ[1]:g} Hz"})


def _correlations(cells, joint, anchor_hz: float, covariates) -> tuple[dict, tuple]:
    """The per-cell table and the Spearman correlations, measured and from the population's fitted cells."""
    df = population_cells(joint, anchor_hz)
    table = {c: df[c].to_numpy() for c in df.columns}
    if covariates is None:
        found = [comment_values(d) for d in cells]
        keys = [key for key in found[0] if all(key in v for v in found)]
        covariates = {key: [v[key] for v in found] for key in keys}
    meas_s, model_s = table["stiffness_measured_Pa"], table["stiffness_model_Pa"]
    out = [_correlation("exponent", "stiffness", table["exponent_measured"], meas_s, table["exponent_model"],
                        model_s)]
    for key, values in covariates.items():
        v = np.asarray(values, dtype=float)
        if v.size != len(cells):
            raise ValueError(f"covariates[{key!r}]: {v.size} values for {len(cells)} cells")
        table[key] = v
        out.append(_correlation("stiffness", key, meas_s, v, model_s, v))
    return table, tuple(out)


def _correlation(x, y, mx, my, model_x, model_y) -> Correlation:
    measured, n = _spearman(mx, my)
    return Correlation(x=x, y=y, measured=measured, model=_spearman(model_x, model_y)[0],
                       model_vs_measured=_spearman(model_x, my)[0], n_cells=n)


def _unit_suffix(unit: str) -> str:
    return {"N": "N", "Pa": "Pa", "m²": "m2", "": "", "Pa·s": "Pa_s"}.get(unit, "SI")


def _notes(joint, correlations) -> tuple:
    """What the scores do not show, from this run."""
    pb = joint.problem
    own = ", ".join(pb.own_names)
    notes = [f"Each cell's {own} is fitted to that cell: the model's stiffness of a cell restates its data, so a "
             "correlation of the model's stiffness with a measured covariate is the data's, not a prediction."]
    ec = correlations[0]
    if math.isfinite(ec.model) and abs(ec.model) > 0.99:
        notes.append(f"With one parameter per cell ({own}) every fitted cell lies on one curve: the model's exponent "
                     f"and stiffness are both functions of {own}, so their rank correlation is ±1 "
                     f"({ec.model:+.2f} here); the measured {ec.measured:+.2f} includes cell-to-cell variation and "
                     "noise the model does not have.")
    bound = [p.name for p in joint.parameters[: pb.n_shared] if p.at_bound]
    if bound:
        notes.append(f"Shared parameter(s) at a bound: {', '.join(bound)} (a limit, not an estimate).")
    n_own_bound = sum(any(joint.parameters[i].at_bound for i in pb.own_index(k)) for k in range(pb.n_cells))
    if n_own_bound:
        notes.append(f"{n_own_bound} of {pb.n_cells} cells have {'their' if pb.n_own == 1 else 'one of their'} "
                     f"{own} at a bound.")
    if pb.n_own == 2:
        notes.append(f"With two parameters per cell ({own}) each cell's exponent and stiffness are both fitted to it: "
                     "their correlation across cells restates the data; a held-out cell's two are set by two "
                     "measured numbers (its G′ and G″ at the anchor frequency), not one.")
    ident = joint.identifiability()
    loose = [n for n, se in zip(ident.names, ident.standard_errors) if not (np.isfinite(se) and se <= 0.1)]
    if loose:
        notes.append(f"Shared parameter(s) not determined within ±10 %: {', '.join(loose)}.")
    if not joint.sigma_known:
        notes.append("The data give no standard deviations: BIC uses one σ estimated from each model's own "
                     "residuals (maximum likelihood).")
    return tuple(notes)

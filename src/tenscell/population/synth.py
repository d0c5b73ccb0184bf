"""Synthetic cell populations: data drawn from a known distribution, so that a fit's recovery can be checked.

Two generators:

``model="tensegrity"``
    each cell is the paper cell (strut length 1 m) with one stiffness per
    tendon family (actin, intermediate filament), one damping c and a
    prestress P, each drawn log-normally around a median; its G'(f), G''(f)
    come from the linear model itself (:func:`tenscell.linearize`,
    :func:`tenscell.moduli`). This is exactly the model the population fit
    uses by default, so the generating parameters can be compared one by one.
``model="powerlaw"``
    each cell follows the structural-damping law used for cells (Fabry et al.
    2001), :func:`tenscell.fitting.scores.structural_damping_moduli` with
    Φ0 = 2π·f0, with a log-normal G0 and a normal
    exponent x. The tensegrity fit then cannot return G0 and x; recovery is
    checked on what both share: G' at the reference frequency and the
    log-slope of G' there (``x − 1`` for the law).

Measurement noise is multiplicative and log-normal: each G' and G'' is
multiplied by ``exp(ε)``, ``ε ~ N(0, noise²)``, so ``noise`` is the relative
standard deviation (0.03 = 3 %). Conditions scale the medians (see
:func:`parse_condition`).

Every cell's generating parameters are kept in :attr:`SyntheticPopulation.parameters`
(and written as ``_generating_parameters.csv`` beside the cell files; names
starting with ``_`` are not read as cells by :mod:`tenscell.population.sources`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any
from pathlib import Path

import numpy as np

from .._checks import positive_array, positive_scalar
from .._results import format_repr

__all__ = [
    "MODELS",
    "GENERATING_FILE",
    "TENSEGRITY_MEDIANS",
    "POWERLAW_MEDIANS",
    "Condition",
    "parse_condition",
    "SyntheticCell",
    "SyntheticPopulation",
    "synth_population",
    "reference_frequency",
]

#: generators of :func:`synth_population`
MODELS = ("tensegrity", "powerlaw")
#: file (beside the cell files) holding every cell's generating parameters
GENERATING_FILE = "_generating_parameters.csv"

#: medians of the tensegrity generator (N, N, N·s/m, N) for the 1 m paper cell: G' of order 100 Pa,
#: relaxation times c/EA inside 0.01–100 Hz
TENSEGRITY_MEDIANS = {"EA_actin": 1000.0, "EA_intermediate_filament": 100.0, "c": 100.0, "P": 300.0}
#: medians of the power-law generator: G0 (Pa), x (-), mu (Pa·s), f0 (Hz, Φ0 = 2π f0)
POWERLAW_MEDIANS = {"G0": 1000.0, "x": 1.20, "mu": 0.25, "f0": 1.0}
_TENSEGRITY_UNITS = {"EA_actin": "N", "EA_intermediate_filament": "N", "c": "Ns_per_m", "P": "N"}
_POWERLAW_UNITS = {"G0": "Pa", "x": "", "mu": "Pa_s"}


@dataclass(frozen=True)
class Condition:
    """One experimental condition of a synthetic population.

    Attributes
    ----------
    name : str
        Label written in the ``condition`` column (and the subdirectory name).
    factors : tuple of (str, float)
        ``(parameter, factor)``: the parameter's median is multiplied by the
        factor (for the exponent ``x``: ``x − 1`` is multiplied).
    """

    name: str
    factors: tuple = ()

    def factor(self, name: str) -> float:
        """The factor applied to the median of ``name`` (1 if none)."""
        return dict(self.factors).get(name, 1.0)


def parse_condition(text: str, model: str = "tensegrity") -> Condition:
    """Parse ``NAME`` or ``NAME:PARAM=FACTOR[,PARAM=FACTOR...]`` (e.g. ``histamine:P=2``).

    ``PARAM`` is a parameter of the generator (tensegrity: EA_actin,
    EA_intermediate_filament, c, P; power law: G0, x, mu). For x the factor
    multiplies ``x − 1``.
    """
    _model(model)
    name, _, rest = str(text).partition(":")
    name = name.strip()
    if not name or not all(ch.isalnum() or ch in "-_." for ch in name) or name.startswith((".", "_")):
        raise ValueError(f"condition name {name!r} in {text!r}: use letters, digits, '-', '_' or '.', "
                         "not starting with '.' or '_'")
    allowed = _TENSEGRITY_UNITS if model == "tensegrity" else _POWERLAW_UNITS
    factors = []
    for item in filter(None, (s.strip() for s in rest.split(","))):
        key, eq, val = item.partition("=")
        key = key.strip()
        if not eq or key not in allowed:
            raise ValueError(f"condition {text!r}: {item!r} is not PARAM=FACTOR with PARAM one of {', '.join(allowed)}")
        try:
            factors.append((key, positive_scalar(f"factor of {key} in condition {name!r}", float(val))))
        except ValueError as err:
            raise ValueError(f"condition {text!r}: {err}") from None
    return Condition(name, tuple(factors))


def reference_frequency(f_hz) -> float:
    """The frequency where a population's summary moduli and slopes are read: the geometric mean of ``f_hz`` (Hz)."""
    f = np.asarray(f_hz, dtype=float)
    return float(np.exp(np.mean(np.log(f))))


@dataclass(frozen=True, eq=False)
class SyntheticCell:
    """One synthetic cell: its id, condition and data (:class:`tenscell.io.data.RheologyData`)."""

    cell: str
    condition: str
    data: Any


@dataclass(frozen=True, eq=False, repr=False)
class SyntheticPopulation:
    """Cells drawn from a known distribution, with every cell's generating parameters.

    Attributes
    ----------
    cells : tuple of SyntheticCell
    parameters : pandas.DataFrame
        One row per cell: ``cell``, ``condition``, the generating parameters
        with units in the column names, and the noise-free ``G_storage_ref_Pa``,
        ``G_loss_ref_Pa`` and ``storage_slope`` (∂lnG'/∂lnf) at ``f_ref_Hz``.
    model : str
    medians : dict
        The generator's medians before condition factors.
    spread_decades : float
        Standard deviation of log10 of each log-normal parameter (for x: of x itself).
    noise : float
        Relative measurement noise (see module docstring).
    seed : int
    frequency_hz : ndarray, shape (n,)
    conditions : tuple of Condition
    """

    cells: tuple
    parameters: Any
    model: str
    medians: dict
    spread_decades: float
    noise: float
    seed: int
    frequency_hz: np.ndarray
    conditions: tuple = field(default=())

    def __repr__(self) -> str:
        names = ", ".join(c.name for c in self.conditions) or "none"
        return format_repr(
            f"SyntheticPopulation: {len(self.cells)} cells, model {self.model}",
            f"conditions: {names}",
            f"frequencies: {self.frequency_hz.size} from {self.frequency_hz[0]:.3g} to {self.frequency_hz[-1]:.3g} Hz",
            f"spread {self.spread_decades:g} decades, noise {self.noise:g}, seed {self.seed}",
        )

    def to_dataframe(self):
        """The generating parameters, one row per cell (a copy of :attr:`parameters`)."""
        return self.parameters.copy()

    def write(self, directory) -> list[Path]:
        """Write one CSV per cell (``<condition>/<cell>.csv``, or ``<cell>.csv`` without conditions) and
        :data:`GENERATING_FILE`; returns the cell files' paths.

        The directory must exist; files are written atomically.
        """
        from ..io.data import write_csv
        from ..io.outputs import write_csv_rows

        directory = Path(directory)
        paths = []
        for c in self.cells:
            path = directory / f"{c.cell}.csv"
            path.parent.mkdir(parents=True, exist_ok=True)
            write_csv(c.data, path)
            paths.append(path)
        df = self.parameters
        write_csv_rows(directory / GENERATING_FILE, list(df.columns), df.itertuples(index=False, name=None))
        return paths


def _model(model: str) -> str:
    if model not in MODELS:
        raise ValueError(f"model must be one of {', '.join(MODELS)}, got {model!r}")
    return model


def _tensegrity_cell(rng, medians, spread, cond, cell, fams, f):
    """Draw one tensegrity cell: its parameters and noise-free complex modulus (Pa) at ``f``."""
    from ..linear.linearize import linearize
    from ..linear.assembly import modulus
    from ..response import compliance

    p = {k: medians[k] * cond.factor(k) * 10 ** (spread * rng.standard_normal()) for k in _TENSEGRITY_UNITS}
    EA = np.where(fams == "actin", p["EA_actin"], p["EA_intermediate_filament"])
    lin = linearize(cell, P=p["P"], EA=EA, c=p["c"])
    G = modulus(compliance(lin, f), cell.strut_length)
    return {f"{k}_{_TENSEGRITY_UNITS[k]}": v for k, v in p.items()}, G


def _powerlaw_cell(rng, medians, spread, cond, f):
    G0 = medians["G0"] * cond.factor("G0") * 10 ** (spread * rng.standard_normal())
    # spread of x: the same relative spread as the log-normal parameters have in ln, on x − 1
    x = 1.0 + (medians["x"] - 1.0) * cond.factor("x") * (1 + spread * math.log(10) * rng.standard_normal())
    x = float(np.clip(x, 1.0 + 1e-3, 1.9))
    mu = medians["mu"] * cond.factor("mu")
    from ..fitting.scores import structural_damping_moduli

    G = structural_damping_moduli(2 * math.pi * f, G0, x, mu, 2 * math.pi * medians["f0"])
    return {"G0_Pa": G0, "x": x, "mu_Pa_s": mu, "f0_Hz": medians["f0"]}, G


_H = 1e-3  # log-step of the central difference that gives the generating curve's slope


def _log_slope(G_minus, G_plus) -> float:
    """∂lnG'/∂lnf from the noise-free moduli at f_ref·e^(∓h) (central difference, error O(h²))."""
    return float((math.log(G_plus.real) - math.log(G_minus.real)) / (2 * _H))


def synth_population(
    cells: int = 200,
    *,
    model: str = "tensegrity",
    conditions=None,
    noise: float = 0.02,
    spread_decades: float = 0.2,
    medians: dict | None = None,
    frequency_hz=None,
    seed: int = 0,
):
    """Draw a synthetic population of cells with known generating parameters.

    Parameters
    ----------
    cells : int
        Number of cells, ≥ 1; split evenly over the conditions (the first
        conditions take one more when it does not divide).
    model : {"tensegrity", "powerlaw"}
        Generator (see the module docstring).
    conditions : sequence of str or Condition, optional
        e.g. ``["control", "histamine:P=2"]``; None: one unnamed condition.
    noise : float
        Relative measurement noise of G' and G'' (0.02 = 2 %), ≥ 0.
    spread_decades : float
        Standard deviation of log10 of each log-normal parameter, ≥ 0.
    medians : dict, optional
        Overrides of :data:`TENSEGRITY_MEDIANS` or :data:`POWERLAW_MEDIANS`.
    frequency_hz : array_like, optional
        Frequencies (Hz); default 13 points from 0.01 to 100 Hz.
    seed : int
        Seed; each cell draws from its own stream derived from (seed, cell index).

    Returns
    -------
    SyntheticPopulation
    """
    import pandas as pd

    from ..model.shapes import paper_cell

    _model(model)
    n = _whole("cells", cells, 1)
    seed = _whole("seed", seed, 0)
    noise = 0.0 if noise == 0 else positive_scalar("noise", noise)
    spread = 0.0 if spread_decades == 0 else positive_scalar("spread_decades", spread_decades, "decades")
    base = _medians(model, medians)
    f = np.logspace(-2, 2, 13) if frequency_hz is None else np.sort(
        np.atleast_1d(positive_array("frequency_hz", frequency_hz, unit="Hz")).ravel())
    conds = _conditions(conditions, model)
    ref = reference_frequency(f)
    f_all = np.concatenate([f, ref * np.exp([-_H, 0.0, _H])])
    cell_model = paper_cell() if model == "tensegrity" else None
    fams = None if cell_model is None else np.asarray(cell_model.structure.families)
    groups = conds or (Condition(""),)
    out, rows = [], []
    width = max(4, len(str(n)))
    for i in range(n):
        cond = groups[i % len(groups)]
        rng = np.random.default_rng([seed, i])
        if model == "tensegrity":
            params, G = _tensegrity_cell(rng, base, spread, cond, cell_model, fams, f_all)
        else:
            params, G = _powerlaw_cell(rng, base, spread, cond, f_all)
        cid = f"cell-{i:0{width}d}" if not cond.name else f"{cond.name}/cell-{i:0{width}d}"
        origin = f"synthetic {model} cell {i} (tenscell synth-population, seed {seed})"
        out.append(SyntheticCell(cid, cond.name, _measured(rng, f, G[:-3], noise, cid, origin)))
        rows.append(_generating_row(cid, cond.name, params, ref, G[-3:]))
    return SyntheticPopulation(cells=tuple(out), parameters=pd.DataFrame(rows), model=model, medians=base,
                               spread_decades=spread, noise=noise, seed=seed, frequency_hz=f, conditions=conds)


def _medians(model: str, overrides: dict | None) -> dict:
    """The generator's medians (SI units; see :data:`TENSEGRITY_MEDIANS`) with ``overrides`` applied."""
    base = dict(TENSEGRITY_MEDIANS if model == "tensegrity" else POWERLAW_MEDIANS)
    for k, v in (overrides or {}).items():
        if k not in base:
            raise ValueError(f"medians: unknown parameter {k!r} for model {model!r}; known: {', '.join(base)}")
        base[k] = float(v)
    return base


def _conditions(conditions, model: str) -> tuple:
    """The conditions as :class:`Condition` objects, refusing a name given twice."""
    conds = tuple(c if isinstance(c, Condition) else parse_condition(c, model) for c in (conditions or ()))
    if len({c.name for c in conds}) != len(conds):
        raise ValueError("conditions: names must be distinct")
    return conds


def _measured(rng, f, G, noise: float, cid: str, origin: str):
    """The data of one cell: the moduli ``G`` (Pa) at ``f`` (Hz) with log-normal relative noise ``noise``."""
    from ..io.data import RheologyData

    eps = noise * rng.standard_normal((2, f.size))
    return RheologyData(f, G.real * np.exp(eps[0]), G.imag * np.exp(eps[1]), source=cid,
                        comments=(origin, "generated by a model, not measured"))


def _generating_row(cid: str, condition: str, params: dict, ref: float, G_ref3) -> dict:
    """One row of the generating parameters: the draw and G', G'' (Pa) and the log-slope of G' at ``ref`` (Hz).

    ``G_ref3`` holds the noise-free moduli (Pa) at ref·e^(-h), ref and ref·e^(+h).
    """
    G_minus, G_ref, G_plus = G_ref3
    return {"cell": cid, "condition": condition, **params, "f_ref_Hz": ref,
            "G_storage_ref_Pa": G_ref.real, "G_loss_ref_Pa": G_ref.imag, "storage_slope": _log_slope(G_minus, G_plus)}


def _whole(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be a whole number >= {minimum}, got {value!r}")
    return int(value)

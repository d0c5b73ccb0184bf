"""The population's results: a tidy table (one row per cell), per-condition summaries, recovery checks.

Columns of :attr:`PopulationResult.table` (units in the names):

``cell, condition``
    identity;
``status, error``
    ``ok`` or why the cell has no fit (``data_error``, ``fit_error``,
    ``worker_lost``) and the one-line error message;
``converged, rms_log10_error``
    whether the fit reached its tolerance, and its RMS log10 error (decades);
``parameters_at_bound``
    the varied parameters that ended at a bound, e.g. ``P:lower`` (a fit
    whose prestress sits at its lower bound has an inert prestress);
fitted parameters
    e.g. ``EA_actin_N, EA_intermediate_filament_N, c_Ns_per_m, P_N, L_m``;
``stiffness_spread_decades``
    log10(max EA / min EA) over the tendons;
``prestress_elasticity_storage, prestress_elasticity_loss``
    ∂lnG'/∂lnP and ∂lnG''/∂lnP of the fitted cell at ``f_ref_Hz``;
``f_ref_Hz, G_storage_ref_Pa, G_loss_ref_Pa, storage_slope``
    the fitted moduli at the geometric-mean frequency of the cell's data and
    ∂lnG'/∂lnf there (comparable with any model, e.g. ``x − 1`` of the
    structural-damping law);
``prestress_ref_Pa``
    for prestress sweeps, the (geometric-mean) prestress where the above are read;
``kind, n_points, n_evaluations, seed, time_s, source``
    bookkeeping.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._optional import require
from .._results import format_repr, reporter

__all__ = ["PopulationResult", "condition_summary", "recovery", "FIXED_COLUMNS", "SUMMARY_COLUMNS", "read_table",
           "CURVE_FREQUENCIES"]

#: the common frequency grid (Hz) on which every cell's fitted and measured moduli are kept for the
#: population bands (10 points per decade; each cell fills only its own data range)
CURVE_FREQUENCIES = np.logspace(-4, 4, 81)

_FIRST = ("cell", "condition", "status", "error", "converged", "rms_log10_error", "parameters_at_bound")
_DERIVED = ("stiffness_spread_decades", "prestress_elasticity_storage", "prestress_elasticity_loss",
            "f_ref_Hz", "prestress_ref_Pa", "G_storage_ref_Pa", "G_loss_ref_Pa", "storage_slope")
_LAST = ("kind", "n_points", "n_evaluations", "seed", "time_s", "source")
_TEXT = ("cell", "condition", "status", "error", "parameters_at_bound", "kind", "source", "converged")
#: the table's columns other than the fitted parameters, in order (parameters sit between the two groups)
FIXED_COLUMNS = _FIRST + _DERIVED + _LAST
#: quantities summarised per condition besides the fitted parameters
SUMMARY_COLUMNS = ("rms_log10_error",) + tuple(c for c in _DERIVED if c not in ("f_ref_Hz",))


def _table(records):
    import pandas as pd

    params: dict[str, str] = {}
    for r in records:
        params.update(r.get("columns", {}))
    rows = []
    for r in records:
        row = {k: r.get(k, math.nan) for k in FIXED_COLUMNS}
        row["converged"] = bool(r.get("converged", False))
        row["error"] = r.get("error") or ""
        row["parameters_at_bound"] = r.get("parameters_at_bound") or ""
        for name, col in params.items():
            row[col] = r.get("parameters", {}).get(name, math.nan)
        rows.append(row)
    cols = list(_FIRST) + list(params.values()) + list(_DERIVED) + list(_LAST)
    df = pd.DataFrame(rows, columns=cols)
    for c in cols:
        if c not in _TEXT:
            df[c] = pd.to_numeric(df[c], errors="coerce")
    return df, tuple(params.values())


def _curve_arrays(records):
    n, k = len(records), CURVE_FREQUENCIES.size
    out = {name: np.full((n, k), np.nan) for name in ("model_storage", "model_loss", "data_storage", "data_loss")}
    for i, r in enumerate(records):
        cv = r.get("curve") or {}
        if not cv:
            continue
        s = cv["start"]
        for name, arr in out.items():
            vals = np.asarray(cv[name], dtype=float)
            arr[i, s:s + vals.size] = vals
    return out


@dataclass(frozen=True, eq=False, repr=False)
class PopulationResult:
    """The outcome of :func:`tenscell.population.fit_population`.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per cell, in input order (columns: see the module docstring).
    parameter_columns : tuple of str
        The fitted parameters' columns of ``table``.
    records : tuple of dict
        The per-cell records as written to the work directory (with the curves).
    frequency_hz : ndarray, shape (k,)
        The common grid of the curves (Hz).
    curves : dict of ndarray, shape (n_cells, k)
        ``model_storage, model_loss`` (fitted G', G'', Pa) and ``data_storage,
        data_loss`` (the data interpolated in log-log, Pa); NaN outside each
        cell's data range and for cells without a frequency-sweep fit.
    options : PopulationFitOptions
    seed : int
    elapsed_s : float
        Wall-clock time of the run (s), including cluster start-up.
    n_workers : int
        Dask workers (0: fitted in-process).
    n_resumed : int
        Cells whose records were taken from an earlier, interrupted run.
    """

    table: Any
    parameter_columns: tuple
    records: tuple
    frequency_hz: np.ndarray
    curves: dict
    options: Any
    seed: int
    elapsed_s: float
    n_workers: int
    n_resumed: int

    @classmethod
    def from_records(cls, records, *, options, seed: int, elapsed_s: float = math.nan, n_workers: int = 0,
                     n_resumed: int = 0) -> "PopulationResult":
        """Assemble the table and curves from per-cell records (as written by :func:`fit_cell`)."""
        df, params = _table(records)
        return cls(table=df, parameter_columns=params, records=tuple(records), frequency_hz=CURVE_FREQUENCIES,
                   curves=_curve_arrays(records), options=options, seed=seed, elapsed_s=elapsed_s,
                   n_workers=n_workers, n_resumed=n_resumed)

    # -- conventions ------------------------------------------------------------------------------
    @property
    def n_cells(self) -> int:
        return len(self.records)

    @property
    def ok(self):
        """Mask (ndarray of bool) of the cells that were fitted."""
        return (self.table["status"] == "ok").to_numpy()

    def __repr__(self) -> str:
        t = self.table
        conds = sorted(set(t["condition"])) if len(t) else []
        rms = t.loc[self.ok, "rms_log10_error"]
        return format_repr(
            f"PopulationResult: {self.n_cells} cells, {len(conds)} condition(s)",
            f"fitted {int(self.ok.sum())}, converged {int(t['converged'].sum())}, failed {int((~self.ok).sum())}",
            f"median rms log10 error {np.median(rms):.3g}" if len(rms) else "no fitted cell",
            f"model: tendons {self.options.tendons}, damping {self.options.damping}; seed {self.seed}",
            f"{self.elapsed_s:.1f} s on {self.n_workers or 'no'} Dask worker(s), {self.n_resumed} resumed",
        )

    def _repr_html_(self) -> str:
        return reporter("population_html")(self)  # cells per condition and the medians (reports/html.py)

    def to_dataframe(self):
        """The tidy per-cell table (a copy)."""
        return self.table.copy()

    def summary(self):
        """Per-condition medians and quartiles (see :func:`condition_summary`)."""
        return condition_summary(self.table, self.parameter_columns)

    def plot(self, ax=None, **kw):
        """Distributions of the fitted parameters per condition (see :mod:`tenscell.plotting.population`)."""
        from .._results import plotter

        parameter_distributions = plotter("parameter_distributions")

        return parameter_distributions(self.table, self.parameter_columns, ax=ax, **kw)

    def plot_moduli(self, ax=None, **kw):
        """Population G', G'': median and interquartile band, fitted against data (per condition)."""
        from .._results import plotter

        population_moduli = plotter("population_moduli")

        return population_moduli(self, ax=ax, **kw)

    # -- output -----------------------------------------------------------------------------------
    def write(self, directory, truth=None) -> list:
        """Write the set's files into an existing directory; returns their names.

        ``population.csv`` and ``population.parquet`` (the table), ``summary.csv``
        (per condition), ``cells.jsonl`` (every record, with the curves),
        ``report.md``, ``parameters.png``, ``moduli.png``, ``report.html`` (the
        report with both figures, one self-contained page), and with ``truth``
        (generating parameters of a synthetic population) ``recovery.csv``.
        """
        from pathlib import Path

        from .._results import plotter, reporter
        from ..io.outputs import atomic_path, json_text, write_bytes, write_csv_rows, write_text

        # drawn and rendered by tenscell.plotting and tenscell.reports, later stages (tenscell._results)
        population_markdown = reporter("population_markdown")
        page = reporter("markdown_report_html")
        png_bytes = plotter("png_bytes")

        d = Path(directory)
        _write_frame(d / "population.csv", self.table, write_csv_rows)
        require("pyarrow")  # before any file: the set is written whole or not at all
        with atomic_path(d / "population.parquet") as tmp:
            self.table.to_parquet(tmp, index=False)
        _write_frame(d / "summary.csv", self.summary(), write_csv_rows)
        write_text(d / "cells.jsonl", "".join(json_text(r, indent=None) + "\n"
                                              for r in self.records))
        rec = None
        if truth is not None:
            rec = recovery(self.table, truth)
            _write_frame(d / "recovery.csv", rec, write_csv_rows)
        figures = [("The fitted parameters per condition (parameters.png).", png_bytes(self.plot())),
                   ("G′, G″ of the population: median and interquartile band, fitted against data (moduli.png).",
                    png_bytes(self.plot_moduli()))]
        for (_, png), name in zip(figures, ("parameters.png", "moduli.png")):
            write_bytes(d / name, png)
        report = population_markdown(self, recovery_table=rec)
        write_text(d / "report.md", report)
        write_text(d / "report.html", page(report, figures))
        return sorted(p.name for p in d.iterdir())


def _write_frame(path, df, writer) -> None:
    rows = ([None if isinstance(v, float) and math.isnan(v) else v for v in row]
            for row in df.itertuples(index=False, name=None))
    writer(path, list(df.columns), ([("" if v is None else v) for v in r] for r in rows))


def read_table(path):
    """Read a population table written by :meth:`PopulationResult.write` (``.csv`` or ``.parquet``)."""
    import pandas as pd

    path = str(path)
    if path.endswith((".parquet", ".pq")):
        require("pyarrow")
        return pd.read_parquet(path)
    text = [c for c in _TEXT if c != "converged"]
    df = pd.read_csv(path, keep_default_na=False, na_values=[""], dtype=dict.fromkeys(text, "str"))
    return df.fillna({c: "" for c in text if c in df.columns})


def condition_summary(table, parameter_columns=()):
    """Per condition and quantity: cells fitted, median, first and third quartile.

    Parameters
    ----------
    table : pandas.DataFrame
        A population table.
    parameter_columns : sequence of str
        The fitted parameters' columns (summarised first, then :data:`SUMMARY_COLUMNS`).

    Returns
    -------
    pandas.DataFrame
        Columns ``condition, quantity, n_cells, n_fitted, n_converged, median, q25, q75``.
    """
    import pandas as pd

    rows = []
    quantities = [c for c in (*parameter_columns, *SUMMARY_COLUMNS) if c in table.columns]
    for cond, g in table.groupby("condition", sort=True):
        ok = g[g["status"] == "ok"]
        for q in quantities:
            v = ok[q].to_numpy(dtype=float)
            v = v[np.isfinite(v)]
            if not v.size and len(ok):
                continue  # a quantity this condition's cells do not have (e.g. prestress_ref_Pa of frequency sweeps)
            med, q25, q75 = (np.percentile(v, [50, 25, 75]) if v.size else (math.nan,) * 3)
            rows.append({"condition": cond, "quantity": q, "n_cells": len(g), "n_fitted": len(ok),
                         "n_converged": int(ok["converged"].sum()), "median": med, "q25": q25, "q75": q75})
    return pd.DataFrame(rows, columns=["condition", "quantity", "n_cells", "n_fitted", "n_converged", "median",
                                       "q25", "q75"])


def recovery(table, truth):
    """Compare a fitted population with the distribution that generated it (synthetic populations).

    For every quantity present in both tables (parameters such as ``P_N``,
    and ``G_storage_ref_Pa``, ``G_loss_ref_Pa``, ``storage_slope``) and every
    condition: the generating median, the fitted median (fitted cells only),
    and the error — for positive quantities in decades, ``log10(fitted
    median / generating median)``, with the median over cells of
    ``|log10(fitted / generating)|``; for the slope, differences.

    Parameters
    ----------
    table : pandas.DataFrame
        A population table (``cell`` column).
    truth : pandas.DataFrame or path
        Generating parameters (:attr:`SyntheticPopulation.parameters`, or its CSV).

    Returns
    -------
    pandas.DataFrame
        Columns ``condition, quantity, n, generating_median, fitted_median, median_error, cell_error, error_unit``.
    """
    import pandas as pd

    if not isinstance(truth, pd.DataFrame):
        truth = pd.read_csv(truth, keep_default_na=False, na_values=[""], dtype={"cell": "str", "condition": "str"})
        truth = truth.fillna({"condition": ""})
    truth = truth.copy()
    truth["cell"] = truth["cell"].astype(str)
    fitted = table[table["status"] == "ok"]
    skip = {"cell", "condition", "f_ref_Hz"}
    common = [c for c in truth.columns if c in fitted.columns and c not in skip]
    merged = fitted.merge(truth[["cell", *common]], on="cell", suffixes=("", "_true"))
    rows = []
    for cond, g in merged.groupby("condition", sort=True):
        for q in common:
            a, b = g[q].to_numpy(float), g[f"{q}_true"].to_numpy(float)
            keep = np.isfinite(a) & np.isfinite(b)
            a, b = a[keep], b[keep]
            if not a.size:
                continue
            positive = bool(np.all(a > 0) and np.all(b > 0) and q != "storage_slope")
            if positive:
                med_err = math.log10(np.median(a) / np.median(b))
                cell_err = float(np.median(np.abs(np.log10(a / b))))
            else:
                med_err = float(np.median(a) - np.median(b))
                cell_err = float(np.median(np.abs(a - b)))
            rows.append({"condition": cond, "quantity": q, "n": int(a.size), "generating_median": float(np.median(b)),
                         "fitted_median": float(np.median(a)), "median_error": med_err, "cell_error": cell_err,
                         "error_unit": "decades" if positive else "absolute"})
    return pd.DataFrame(rows, columns=["condition", "quantity", "n", "generating_median", "fitted_median",
                                       "median_error", "cell_error", "error_unit"])

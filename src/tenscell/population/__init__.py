"""Populations of cells and large studies on Dask.

* :mod:`~tenscell.population.synth` — synthetic populations with known generating parameters;
* :mod:`~tenscell.population.sources` — where the cells' data come from (a directory, a glob, a long table);
* :mod:`~tenscell.population.run` — :func:`fit_population`: one fit per cell on a Dask cluster (or in
  this process), written cell by cell, resumable;
* :mod:`~tenscell.population.table` — the tidy per-cell table, per-condition summaries, recovery;
* :mod:`~tenscell.population.studies` — Monte Carlo and parameter sweeps streamed to chunked Parquet;
* :mod:`~tenscell.population.ensemble` — :func:`mechanism_ensemble`: a fitted distributed mechanism over
  thousands of assignments of its tendon values (mean G′, G″ and the spread between assignments).

Dask is imported only when a cluster is used, so ``import tenscell`` stays light.
"""
from __future__ import annotations

import importlib

_EXPORTS = {
    "synth_population": "synth", "SyntheticPopulation": "synth",
    "parse_condition": "synth", "Condition": "synth",
    "CellSource": "sources", "read_sources": "sources",
    "fit_population": "run", "PopulationFitOptions": "run", "fit_cell": "run", "cell_seed": "run",
    "PopulationResult": "table", "recovery": "table", "condition_summary": "table",
    "monte_carlo_study": "studies", "sweep_study": "studies", "read_study": "studies",
    "mechanism_ensemble": "ensemble", "EnsembleResult": "ensemble",
    "check_scheduler": "_engine",
}

__all__ = [  # the keys of _EXPORTS (a literal list, so that tools can read it)
    "CellSource", "Condition", "EnsembleResult", "PopulationFitOptions", "PopulationResult", "SyntheticPopulation",
    "cell_seed", "check_scheduler", "condition_summary", "fit_cell", "fit_population", "mechanism_ensemble", "monte_carlo_study",
    "parse_condition", "read_sources", "read_study", "recovery", "sweep_study", "synth_population",
]


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + __all__)

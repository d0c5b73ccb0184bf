"""Large studies on the population engine: Monte Carlo sensitivity and parameter sweeps, streamed to Parquet.

Both split the study into chunks, run each chunk as one Dask task (or in this
process with ``workers=0``), and write each chunk's rows as one Parquet file
(``parts/part-NNNNN.parquet``, atomically) as soon as it completes, so a
study of 10⁵ draws never holds more than a few chunks in memory. A chunk's
rows depend only on the study's settings and the chunk's index (its random
stream is seeded by ``(seed, chunk)``), so an interrupted study resumes
(``resume=True``) by computing only the missing parts, with the same result.

:func:`monte_carlo_study`
    the Monte Carlo of :func:`tenscell.sensitivity.monte_carlo` (simultaneous
    uniform ±spread perturbations of every EA_j, c_j, P and, with
    ``parameters="all"``, L, δ, α), one row per draw: ``draw``,
    ``change_storage``, ``change_loss``, ``reason`` and (``keep_factors``) the
    factors. The draws follow the same rule as ``monte_carlo`` but from one
    random stream per chunk, so they are not the same draws as
    ``monte_carlo(n, seed=seed)``.
:func:`sweep_study`
    prestress × heterogeneity × frequency: for each prestress P and
    heterogeneity σ (decades), ``realizations`` cells of the paper's shape
    whose tendon stiffnesses are ``EA·10^(σ·z_j)``, ``z_j ~ N(0, 1)``; one row
    per (P, σ, realization, f): ``G_storage_Pa``, ``G_loss_Pa``.

:func:`read_study` reads a study's parts back as one DataFrame (or selected columns).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._checks import positive_array, positive_scalar
from .._optional import require
from .._results import format_repr

__all__ = ["StudyResult", "monte_carlo_study", "sweep_study", "read_study", "PARTS"]

#: subdirectory of a study directory holding its Parquet parts
PARTS = "parts"
_STUDY_FILE = "study.json"


@dataclass(frozen=True, eq=False, repr=False)
class StudyResult:
    """A streamed study on disk.

    Attributes
    ----------
    directory : Path
        Holds ``study.json`` (settings) and ``parts/part-NNNNN.parquet``.
    kind : str
        ``"monte-carlo"`` or ``"sweep"``.
    settings : dict
    n_rows : int
    n_parts : int
    n_resumed : int
        Parts taken from an interrupted run.
    elapsed_s : float
    summary : dict
        Headline numbers (Monte Carlo: fraction of valid draws within the
        bound, percentiles of the changes; sweep: medians per (P, σ) at each f
        are in :meth:`medians`).
    """

    directory: Path
    kind: str
    settings: dict
    n_rows: int
    n_parts: int
    n_resumed: int
    elapsed_s: float
    summary: dict

    def __repr__(self) -> str:
        head = ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in
                         list(self.summary.items())[:4])
        return format_repr(f"StudyResult: {self.kind}, {self.n_rows} rows in {self.n_parts} parts",
                           f"directory {self.directory}", head,
                           f"{self.elapsed_s:.1f} s, {self.n_resumed} part(s) resumed")

    def to_dataframe(self, columns=None):
        """All rows (or only ``columns``) as one DataFrame."""
        return read_study(self.directory, columns)

    def medians(self):
        """Sweep: median and quartiles of G', G'' over realizations per (P, σ, f) (a DataFrame)."""
        df = read_study(self.directory, ["prestress_N", "heterogeneity_decades", "frequency_Hz", "G_storage_Pa",
                                         "G_loss_Pa"])
        g = df.groupby(["prestress_N", "heterogeneity_decades", "frequency_Hz"])
        out = g.median().add_suffix("_median")
        for q in (25, 75):
            out = out.join(g.quantile(q / 100).add_suffix(f"_q{q}"))
        return out.reset_index()


def read_study(directory, columns=None):
    """The rows of a study's Parquet parts as one DataFrame (only ``columns`` if given), in part order."""
    import pandas as pd

    parts = sorted((Path(directory) / PARTS).glob("part-*.parquet"))
    if not parts:
        return pd.DataFrame(columns=columns)
    require("pyarrow")
    return pd.concat([pd.read_parquet(p, columns=columns) for p in parts], ignore_index=True)


def _write_part(path: Path, columns: dict) -> None:
    pa = require("pyarrow")
    import pyarrow.parquet as pq

    from ..io.outputs import atomic_path

    with atomic_path(path) as tmp:
        pq.write_table(pa.table(columns), tmp)


def _open_study(directory: Path, settings: dict, resume: bool) -> set[int]:
    """Check the directory against the settings; the chunk indices already written (resume only)."""
    from ._engine import open_work_dir

    directory = open_work_dir(directory, _STUDY_FILE, settings, resume)
    (directory / PARTS).mkdir(exist_ok=True)
    if not resume:
        return set()
    return {int(p.stem.split("-")[1]) for p in (directory / PARTS).glob("part-*.parquet")}


def _run(directory, settings, chunks, fn, *, resume, client, workers, scheduler, progress, desc, notify=None):
    """Run ``fn(settings, k, lo, hi)`` for every missing chunk; write each part as it completes."""
    from .._progress import progress_bar
    from . import _engine

    directory = Path(directory)
    done = _open_study(directory, settings, resume)
    todo = [(k, lo, hi) for k, (lo, hi) in enumerate(chunks) if k not in done]
    bar = progress_bar(total=len(chunks), desc=desc, unit="chunk", progress=progress)
    bar.update(len(chunks) - len(todo))
    try:
        items = ((k, (settings, k, lo, hi)) for k, lo, hi in todo)
        for k, cols in _engine.run_tasks(fn, items, client=client, workers=workers, scheduler=scheduler,
                                         name=f"tenscell-{desc}", warm=(fn.__module__,), notify=notify):
            if isinstance(cols, _engine.TaskLost):
                raise RuntimeError(f"chunk {k}: {cols}; rerun with --resume")
            _write_part(directory / PARTS / f"part-{k:05d}.parquet", cols)
            bar.update(1)
    finally:
        bar.close()
    return len(chunks) - len(todo)


def _chunks(n: int, size: int) -> list[tuple[int, int]]:
    return [(lo, min(lo + size, n)) for lo in range(0, n, size)]


def _whole(name, v, lo, hi=None):
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo or (hi is not None and v > hi):
        upto = f" and <= {hi:,}" if hi is not None else ""
        raise ValueError(f"{name} must be a whole number >= {lo}{upto}, got {v!r}")
    return int(v)


# ---- Monte Carlo ------------------------------------------------------------------------------
def _mc_chunk(settings: dict, k: int, lo: int, hi: int) -> dict:
    """One chunk of draws (a pure function of the settings and the chunk index)."""
    from threadpoolctl import threadpool_limits

    from ..model.shapes import paper_cell
    from ..sensitivity import monte_carlo_draws, monte_carlo_factors, monte_carlo_names

    s = settings
    names = monte_carlo_names(paper_cell().m, s["parameters"])
    rng = np.random.default_rng([s["seed"], k])
    factors = monte_carlo_factors(rng, hi - lo, len(names), s["spread"], s["alpha_spread"], s["parameters"])
    with threadpool_limits(1):
        cs, cl, reasons = monte_carlo_draws(factors, parameters=s["parameters"], P=s["P"], f_hz=s["frequency_Hz"])
    cols = {"draw": np.arange(lo, hi), "change_storage": cs, "change_loss": cl, "reason": np.asarray(reasons, str)}
    if s["keep_factors"]:
        cols.update({f"factor_{name}": factors[:, j] for j, name in enumerate(names)})
    return cols


def monte_carlo_study(n: int, directory, *, spread: float = 0.10, alpha_spread: float | None = None,
                      parameters: str = "all", P: float = 1000.0, f_hz=None, seed: int = 0, chunk: int = 1000,
                      bound: float = 0.08, keep_factors: bool = True, client=None, workers: int | None = None,
                      scheduler: str | None = None, resume: bool = False, progress: bool | None = None,
                      notify=None) -> StudyResult:
    """The Monte Carlo sensitivity study for any number of draws, streamed to ``directory/parts/``.

    Parameters
    ----------
    n : int
        Number of draws, ≥ 1.
    directory : path
        New or empty directory (or the directory of an interrupted study with ``resume=True``).
    spread, alpha_spread, parameters, P
        As in :func:`tenscell.sensitivity.monte_carlo` (fraction; rad; "all" | "material"; N).
    f_hz : array_like, optional
        Frequencies (Hz); default :data:`tenscell.sensitivity.SENSITIVITY_FREQUENCIES`.
    seed : int
        Chunk k draws from ``numpy.random.default_rng([seed, k])``.
    chunk : int
        Draws per task and per Parquet part.
    bound : float
        The summary's bound on the changes (fraction; the paper's 8 %).
    keep_factors : bool
        Also store every draw's factors (one column per parameter).
    client, workers, scheduler, notify
        Where the chunks run (see :func:`tenscell.population.fit_population`).

    Returns
    -------
    StudyResult
        ``summary``: ``n_valid``, ``fraction_within_bound``, percentiles 50/95/100 of the storage and loss changes.
    """
    from ..sensitivity import SENSITIVITY_FREQUENCIES, monte_carlo_spreads

    t0 = time.perf_counter()
    n = _whole("n", n, 1)
    chunk = _whole("chunk", chunk, 1)
    seed = _whole("seed", seed, 0)
    spread, alpha_spread = monte_carlo_spreads(spread, alpha_spread, parameters)
    f = SENSITIVITY_FREQUENCIES if f_hz is None else f_hz
    f = np.atleast_1d(positive_array("frequency", f, unit="Hz")).ravel()
    bound = positive_scalar("bound", bound)
    settings = {"kind": "monte-carlo", "n": n, "spread": spread, "alpha_spread": alpha_spread,
                "parameters": parameters, "P": positive_scalar("P", P, "N"), "frequency_Hz": f.tolist(),
                "seed": seed, "chunk": chunk, "keep_factors": bool(keep_factors)}
    resumed = _run(directory, settings, _chunks(n, chunk), _mc_chunk, resume=resume, client=client, workers=workers,
                   scheduler=scheduler, progress=progress, desc="monte-carlo", notify=notify)
    df = read_study(directory, ["change_storage", "change_loss"])
    cs, cl = df["change_storage"].to_numpy(), df["change_loss"].to_numpy()
    valid = np.isfinite(cs)
    worst = np.maximum(cs[valid], cl[valid])
    summary = {"n_valid": int(valid.sum()), "bound": bound,
               "fraction_within_bound": float(np.mean(worst <= bound)) if worst.size else math.nan}
    for name, v in (("storage", cs[valid]), ("loss", cl[valid])):
        for q, val in zip((50, 95, 100), np.percentile(v, (50, 95, 100)) if v.size else (math.nan,) * 3):
            summary[f"change_{name}_p{q}"] = float(val)
    return StudyResult(Path(directory), "monte-carlo", settings, len(df), len(_chunks(n, chunk)), resumed,
                       time.perf_counter() - t0, summary)


# ---- sweeps: prestress × heterogeneity × frequency ----------------------------------------------
def _sweep_chunk(settings: dict, k: int, lo: int, hi: int) -> dict:
    """Realizations [lo, hi) of the k-th (P, σ) pair: G', G'' at every frequency."""
    from threadpoolctl import threadpool_limits

    from ..linear.linearize import linearize
    from ..model.shapes import paper_cell
    from ..response import moduli

    s = settings
    n_sigma = len(s["heterogeneity_decades"])
    P, sigma = s["prestress_N"][k // n_sigma], s["heterogeneity_decades"][k % n_sigma]
    f = np.asarray(s["frequency_Hz"])
    cell = paper_cell()
    rows: dict[str, list] = {"prestress_N": [], "heterogeneity_decades": [], "realization": [], "frequency_Hz": [],
            "G_storage_Pa": [], "G_loss_Pa": []}
    with threadpool_limits(1):
        for r in range(s["realizations"]):
            # the same stiffness pattern z for realization r at every (P, σ): the sweep varies P and σ only
            z = np.random.default_rng([s["seed"], r]).standard_normal(cell.m)
            EA = s["EA"] * 10.0 ** (sigma * z)
            Gs, Gl = moduli(linearize(cell, P=P, EA=EA, c=s["c"]), f)
            for name, val in (("prestress_N", np.full(f.size, P)), ("heterogeneity_decades", np.full(f.size, sigma)),
                              ("realization", np.full(f.size, r)), ("frequency_Hz", f), ("G_storage_Pa", Gs),
                              ("G_loss_Pa", Gl)):
                rows[name].append(val)
    return {name: np.concatenate(v) for name, v in rows.items()}


def sweep_study(prestress, heterogeneity, directory, *, f_hz=None, realizations: int = 20, EA: float = 1.0,
                c: float = 1.0, seed: int = 0, client=None, workers: int | None = None, scheduler: str | None = None,
                resume: bool = False, progress: bool | None = None, notify=None) -> StudyResult:
    """G'(f), G''(f) of heterogeneous paper cells over prestress × heterogeneity, streamed to Parquet.

    Parameters
    ----------
    prestress : array_like
        Prestresses P (N), > 0.
    heterogeneity : array_like
        Standard deviations σ of log10 EA_j (decades), ≥ 0.
    directory : path
        New or empty directory (or an interrupted study's, with ``resume=True``).
    f_hz : array_like, optional
        Frequencies (Hz); default 0.01–1000 Hz, 51 points.
    realizations : int
        Cells per (P, σ); realization r has stiffness pattern ``z`` from
        ``default_rng([seed, r])`` at every (P, σ).
    EA, c : float
        Median tendon stiffness (N) and damping (N·s/m).

    Returns
    -------
    StudyResult
        One part per (P, σ); :meth:`StudyResult.medians` gives the bands.
    """
    t0 = time.perf_counter()
    P = np.atleast_1d(positive_array("prestress", prestress, unit="N")).ravel()
    sig = np.atleast_1d(np.asarray(heterogeneity, dtype=float)).ravel()
    if not np.all(np.isfinite(sig)) or np.any(sig < 0):
        raise ValueError(f"heterogeneity must be finite numbers >= 0 (decades), got {sig.tolist()}")
    f = np.logspace(-2, 3, 51) if f_hz is None else np.atleast_1d(positive_array("frequency", f_hz, unit="Hz")).ravel()
    settings = {"kind": "sweep", "prestress_N": P.tolist(), "heterogeneity_decades": sig.tolist(),
                "frequency_Hz": f.tolist(), "realizations": _whole("realizations", realizations, 1),
                "EA": positive_scalar("EA", EA, "N"), "c": positive_scalar("c", c, "N·s/m"),
                "seed": _whole("seed", seed, 0)}
    pairs = [(0, realizations)] * (P.size * sig.size)
    resumed = _run(directory, settings, pairs, _sweep_chunk, resume=resume, client=client, workers=workers,
                   scheduler=scheduler, progress=progress, desc="sweep", notify=notify)
    n_rows = P.size * sig.size * realizations * f.size
    summary = {"prestress_points": int(P.size), "heterogeneity_points": int(sig.size),
               "realizations": int(realizations), "frequencies": int(f.size)}
    return StudyResult(Path(directory), "sweep", settings, n_rows, len(pairs), resumed, time.perf_counter() - t0,
                       summary)

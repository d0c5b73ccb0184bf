"""Fit a population of cells: one :func:`tenscell.fitting.fit` per cell, on Dask, written cell by cell.

Guarantees
----------
Deterministic
    each cell's fit is seeded by :func:`cell_seed` from the run seed and the
    cell's id only, and runs single-threaded, so the table does not depend on
    the number of workers, the order of completion or whether the run was
    resumed (except the ``time_s`` column).
Nothing lost
    a cell whose data are malformed or whose fit raises is recorded with
    ``status`` and ``error`` and the run goes on; a worker that dies
    mid-task is replaced and the task rerun by Dask (a task whose workers die
    repeatedly is recorded as ``worker_lost``).
Resumable
    with a ``work_dir``, each cell's record is written atomically to
    ``work_dir/cells/`` as soon as it completes; ``resume=True`` refits only
    the cells without a record (or whose data changed, or that were
    ``worker_lost``) and gives the same table as an uninterrupted run.

The default per-cell model is deliberately small (:class:`PopulationFitOptions`):
one stiffness per tendon family, one damping, the prestress, the strut length
fixed at the cell's own (it is an exact gauge of the moduli, so fixing it makes
the fitted values comparable between cells), 4 starts of 1 basin-hopping
move, tolerance 0.02 decades (about 5 %): a few tenths of a second per cell,
and parameters a population can be summarised by. Starts matter more than
moves here: with one start about a third of synthetic cells land in the basin
where the prestress sits at its lower bound and EA compensates (RMS nearly as
small); with four, 6 of 200 in the benchmark; more moves per start did not
change that. Such cells are flagged (``parameters_at_bound``). Any other
:func:`~tenscell.fitting.fit` setting can be chosen.
"""
from __future__ import annotations

import hashlib
import json
import math
import re
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from .._checks import positive_scalar
from ._engine import WorkDirError, open_work_dir
from .sources import CellSource, read_sources
from .table import CURVE_FREQUENCIES

__all__ = ["PopulationFitOptions", "cell_seed", "fit_cell", "fit_population", "CURVE_FREQUENCIES", "STATUSES",
           "WorkDirError"]

#: ``status`` of a cell record: fitted, unreadable data, fit raised, workers died
STATUSES = ("ok", "data_error", "fit_error", "worker_lost")
_RUN_FILE = "run.json"
#: what a worker imports before its first fit (so that a fit takes the same time there as here)
_WARM = ("tenscell.population.run", "tenscell.fitting", "tenscell.sensitivity", "scipy.optimize")
_CELLS = "cells"


@dataclass(frozen=True)
class PopulationFitOptions:
    """How each cell is fitted (passed to :func:`tenscell.fitting.fit`).

    Attributes
    ----------
    tendons, damping : str
        Parametrization (see :func:`tenscell.fitting.fit`); default one
        stiffness per family and one damping.
    starts, hops, patience, max_nfev : int
        Search effort per cell.
    tolerance : float
        RMS log10 error (decades) a cell must reach to count as converged.
    polish_effort : float
        Polishing budget after the tolerance is met, as a multiple of the
        evaluations it took (see :func:`tenscell.fitting.fit`). Larger than a
        single fit's default: a cell's fit is small, and its first start often
        meets the tolerance in the basin where the prestress is inert at its
        lower bound (EA compensating, RMS nearly as small), so every start is
        given its run and the best kept (with a budget of 0.5 the fitted
        median prestress of the test population was 8 decades off).
    fix_L : bool
        Hold the strut length at the reference cell's (removes the exact gauge
        ``(P, EA, c, L) → (λ²P, λ²EA, λc, λL)`` so cells are comparable).
    bounds : tuple of (str, (float, float))
        Bounds passed to :func:`~tenscell.fitting.fit` (as a tuple so the options stay hashable).
    """

    tendons: str = "per-family"
    damping: str = "uniform"
    starts: int = 4
    hops: int = 1
    patience: int = 6
    max_nfev: int = 300
    tolerance: float = 0.02
    polish_effort: float = 10.0
    fix_L: bool = True
    bounds: tuple = field(default=())

    def __post_init__(self):
        from ..fitting import DAMPING_MODES, TENDON_MODES

        if self.tendons not in TENDON_MODES:
            raise ValueError(f"tendons must be one of {', '.join(TENDON_MODES)}, got {self.tendons!r}")
        if self.damping not in DAMPING_MODES:
            raise ValueError(f"damping must be one of {', '.join(DAMPING_MODES)}, got {self.damping!r}")
        for name, low in (("starts", 1), ("hops", 0), ("patience", 1), ("max_nfev", 1)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
                raise ValueError(f"{name} must be a whole number >= {low}, got {v!r}")
        positive_scalar("tolerance", self.tolerance, "decades")
        positive_scalar("polish_effort", self.polish_effort)

    def fit_kwargs(self, cell) -> dict:
        """Keyword arguments of :func:`tenscell.fitting.fit` for a reference ``cell``."""
        from ..fitting import VoigtModel

        kw = dict(model=VoigtModel(self.tendons, self.damping), starts=self.starts, hops=self.hops,
                  patience=self.patience, max_nfev=self.max_nfev, tolerance=self.tolerance,
                  polish_effort=self.polish_effort)
        if self.fix_L:
            kw["fixed"] = {"L": float(cell.strut_length)}
        if self.bounds:
            kw["bounds"] = {k: tuple(v) for k, v in self.bounds}
        return kw

    def to_dict(self) -> dict:
        """JSON-ready (recorded in the work directory and the output)."""
        d = asdict(self)
        d["bounds"] = [[k, list(v)] for k, v in self.bounds]
        return d


def cell_seed(run_seed: int, cell: str) -> int:
    """The seed of one cell's fit: from the run seed and a stable hash of the cell id (a 32-bit int).

    ``numpy.random.SeedSequence((run_seed, h))`` with ``h`` the first 8 bytes of
    SHA-256 of the id: independent of the order, the worker and the process
    (Python's ``hash`` of a str is salted per process and would not be).
    """
    h = int.from_bytes(hashlib.sha256(str(cell).encode()).digest()[:8], "little")
    return int(np.random.SeedSequence([int(run_seed), h]).generate_state(1)[0])


def _param_column(name: str, unit: str) -> str:
    suffix = {"N": "N", "N·s/m": "Ns_per_m", "m": "m", "m²": "m2", "": ""}.get(unit, re.sub(r"\W+", "_", unit))
    base = re.sub(r"\W+", "_", name).strip("_")
    return f"{base}_{suffix}" if suffix else base


def _curves(result, data) -> dict:
    """Fitted and measured G', G'' on :data:`CURVE_FREQUENCIES` within the data's range (frequency sweeps)."""
    f = CURVE_FREQUENCIES
    lo, hi = data.frequency_hz.min(), data.frequency_hz.max()
    inside = np.flatnonzero((f >= lo * (1 - 1e-9)) & (f <= hi * (1 + 1e-9)))
    if data.kind != "frequency" or inside.size == 0:
        return {}
    fi = f[inside]
    Gs, Gl = result.moduli(fi)
    order = np.argsort(data.frequency_hz)
    lf = np.log(data.frequency_hz[order])
    ds = np.exp(np.interp(np.log(fi), lf, np.log(data.G_storage[order])))
    dl = np.exp(np.interp(np.log(fi), lf, np.log(data.G_loss[order])))
    return {"start": int(inside[0]), "model_storage": Gs.tolist(), "model_loss": Gl.tolist(),
            "data_storage": ds.tolist(), "data_loss": dl.tolist()}


def _summarize(result, data) -> dict:
    """The table's numbers for one fitted cell: parameters, errors, prestress elasticity, moduli at f_ref."""
    from ..sensitivity import analytic_elasticities
    from .synth import reference_frequency

    f_ref = reference_frequency(data.frequency_hz)
    if data.kind == "prestress":
        P_ref = float(np.exp(np.mean(np.log(data.prestress))))
        P_model = float(result.prestress_model([P_ref])[0])
    else:
        P_ref, P_model = math.nan, float(result.prestress_model()[0])
    el = analytic_elasticities(result.model.linear(P_N=P_model), [f_ref])
    G = el.G[0]
    e_P = el.complex[el.index("P"), 0]
    slope = el.group_sum("c")[0]  # Σ ∂lnG/∂ln c_j = ∂lnG/∂ln f (damping only sets the time scale)
    return {
        "converged": bool(result.converged),
        "rms_log10_error": float(result.rms_log10_error),
        "parameters": {p.name: float(p.value) for p in result.parameters},
        "columns": {p.name: _param_column(p.name, p.unit) for p in result.parameters},
        "parameters_at_bound": " ".join(f"{p.name}:{p.at_bound}" for p in result.parameters if p.at_bound),
        "stiffness_spread_decades": float(result.stiffness_spread[2]),
        "prestress_elasticity_storage": float((G * e_P).real / G.real),
        "prestress_elasticity_loss": float((G * e_P).imag / G.imag),
        "f_ref_Hz": f_ref,
        "prestress_ref_Pa": P_ref,
        "G_storage_ref_Pa": float(G.real),
        "G_loss_ref_Pa": float(G.imag),
        "storage_slope": float((G * slope).real / G.real),
        "n_evaluations": int(result.n_evaluations),
        "message": str(result.message),
        "curve": _curves(result, data),
    }


def fit_cell(source: CellSource, seed: int, options: PopulationFitOptions | None = None, cell=None) -> dict:
    """Fit one cell; never raises for bad data or a failed fit (they are recorded).

    Parameters
    ----------
    source : CellSource
    seed : int
        The fit's seed (see :func:`cell_seed`).
    options : PopulationFitOptions, optional
    cell : Cell, optional
        Reference cell (default :func:`tenscell.paper_cell`).

    Returns
    -------
    dict
        JSON-ready record: ``cell``, ``condition``, ``source``, ``digest``,
        ``seed``, ``status`` (one of :data:`STATUSES`), ``error``, ``kind``,
        ``n_points``, ``time_s`` and, for fitted cells, the fields of the
        table (parameters, RMS, elasticities...) and the curves.
    """
    from threadpoolctl import threadpool_limits

    from ..fitting import fit
    from ..model.shapes import paper_cell

    t0 = time.perf_counter()
    options = options or PopulationFitOptions()
    rec = {"cell": source.cell, "condition": source.condition, "source": source.source, "digest": source.digest,
           "seed": int(seed), "status": "ok", "error": "", "kind": "", "n_points": 0}
    try:
        data = source.load()
    except Exception as err:  # noqa: BLE001 - any unreadable cell is recorded, never fatal
        rec.update(status="data_error", error=_message(err))
    else:
        rec.update(kind=data.kind, n_points=data.n)
        try:
            ref = paper_cell() if cell is None else cell
            # one thread: the same arithmetic, hence the same result, on any worker
            with threadpool_limits(1):
                result = fit(data, ref, seed=int(seed), progress=False, **options.fit_kwargs(ref))
                rec.update(_summarize(result, data))
        except Exception as err:  # noqa: BLE001 - a failed fit is this cell's outcome, not the run's
            rec.update(status="fit_error", error=_message(err))
    rec["time_s"] = time.perf_counter() - t0
    return rec


def _message(err: BaseException) -> str:
    text = str(err).strip().splitlines()
    first = text[0] if text else ""
    return f"{type(err).__name__}: {first}" if first else type(err).__name__


# ---- the work directory: one record per cell, written atomically ----------------------------------
def _record_name(cell: str) -> str:
    safe = re.sub(r"[^A-Za-z0-9._-]+", "_", cell).strip("._")[-60:]
    return f"{safe}-{hashlib.sha256(cell.encode()).hexdigest()[:12]}.json"


class _WorkDir:
    """``run.json`` (the run's settings) and ``cells/<cell>.json`` (one record per finished cell)."""

    def __init__(self, path):
        self.path = Path(path)
        self.cells = self.path / _CELLS

    def open(self, config: dict, resume: bool) -> dict[str, dict]:
        """Check the directory against ``config``; return the finished records (empty unless resuming)."""
        open_work_dir(self.path, _RUN_FILE, config, resume)
        self.cells.mkdir(exist_ok=True)
        return self.records() if resume else {}

    def records(self) -> dict[str, dict]:
        out = {}
        for p in sorted(self.cells.glob("*.json")):
            if p.name.startswith("."):
                continue  # a record being written (atomic_path's temporary file), or left by a killed writer
            try:
                rec = json.loads(p.read_text())
            except (OSError, ValueError):
                continue  # cannot happen with atomic writes; a damaged record is simply refitted
            out[rec["cell"]] = rec
        return out

    def write(self, rec: dict) -> None:
        from ..io.outputs import write_json

        write_json(self.cells / _record_name(rec["cell"]), rec)


def _done(rec: dict | None, src: CellSource) -> bool:
    return rec is not None and rec.get("digest") == src.digest and rec.get("status") != "worker_lost"


def fit_population(
    sources,
    *,
    options: PopulationFitOptions | None = None,
    seed: int = 0,
    client=None,
    workers: int | None = None,
    scheduler: str | None = None,
    work_dir=None,
    resume: bool = False,
    cell=None,
    progress: bool | None = None,
    notify=None,
):
    """Fit every cell of a population, in parallel on Dask, writing each result as it completes.

    Parameters
    ----------
    sources
        Anything :func:`tenscell.population.sources.read_sources` accepts (a
        directory, a glob, a long table, in-memory data, a synthetic
        population) or a sequence of :class:`CellSource`.
    options : PopulationFitOptions, optional
        How each cell is fitted (default: the small per-family model).
    seed : int
        Run seed; each cell's seed is :func:`cell_seed` (seed, cell id).
    client : distributed.Client, optional
        An existing client (not closed here).
    workers : int, optional
        Without ``client`` or ``scheduler``: size of the local cluster started
        for this run; 0 fits in this process, without Dask. Default: one worker
        per CPU when that pays, judged from the first cell's fit time (see
        :func:`tenscell.population._engine.run_tasks`), else in this process.
    scheduler : str, optional
        Address (``tcp://host:port``) or scheduler file of an existing Dask cluster.
    work_dir : path, optional
        Where each cell's record is written as it completes (see the module
        docstring); None keeps them in memory only.
    resume : bool
        Reuse the records already in ``work_dir`` and fit only the rest.
    cell : Cell, optional
        Reference cell of every fit (default :func:`tenscell.paper_cell`).
    progress : bool or None
        Progress bar (see :mod:`tenscell._progress`).
    notify : callable(str), optional
        Receives one line when the cells are fitted here rather than on a new
        local cluster because the work is too small to pay for its start-up
        (only when neither ``client``, ``scheduler`` nor ``workers`` is given).

    Returns
    -------
    PopulationResult

    Raises
    ------
    SourceError, WorkDirError, ValueError
        Before any fit: nothing to read, a work directory holding another run, bad options.
    """
    from .table import PopulationResult

    t0 = time.perf_counter()
    options = options or PopulationFitOptions()
    _check_run_arguments(seed, workers)
    srcs = tuple(sources) if _is_sources(sources) else read_sources(sources)
    store, records = _open_store(srcs, work_dir, resume, seed, options, cell)
    n_reused = len(records)
    placed: dict = {}
    run = dict(client=client, workers=workers, scheduler=scheduler, notify=notify, placed=placed)
    _fit_remaining(srcs, records, store, seed, options, cell, progress, run)
    ordered = tuple(records[s.cell] for s in srcs)
    return PopulationResult.from_records(ordered, options=options, seed=int(seed), elapsed_s=time.perf_counter() - t0,
                                         n_workers=placed.get("workers", 0), n_resumed=n_reused)


def _check_run_arguments(seed, workers) -> None:
    """Raise ValueError for a seed that is not a whole number >= 0 or a bad ``workers``."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative whole number, got {seed!r}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 0):
        raise ValueError(f"workers must be a whole number >= 0, got {workers!r}")


def _open_store(srcs, work_dir, resume: bool, seed, options: PopulationFitOptions, cell):
    """The run's work directory (None without one) and the records it already holds for unchanged cells."""
    config = {"seed": int(seed), "options": options.to_dict(),
              "cell": None if cell is None else cell.describe()}
    store = _WorkDir(work_dir) if work_dir is not None else None
    found = store.open(config, resume) if store is not None else {}
    records = {s.cell: found[s.cell] for s in srcs if _done(found.get(s.cell), s)}
    return store, records


def _fit_remaining(srcs, records: dict, store, seed, options, cell, progress, run: dict) -> None:
    """Fit the cells of ``srcs`` without a record, adding each record to ``records`` (and ``store``) as it completes.

    ``run`` holds :func:`tenscell.population._engine.run_tasks`' ``client``,
    ``workers``, ``scheduler``, ``notify`` and ``placed``.
    """
    from .._progress import progress_bar
    from . import _engine

    todo = [s for s in srcs if s.cell not in records]
    bar = progress_bar(total=len(srcs), desc="fit-population", unit="cell", progress=progress)
    bar.update(len(records))
    try:
        items = ((s, (s, cell_seed(seed, s.cell), options, cell)) for s in todo)
        for src, rec in _engine.run_tasks(fit_cell, items, name="tenscell-fit", warm=_WARM, **run):
            if isinstance(rec, _engine.TaskLost):
                rec = _lost_record(src, seed, rec)
            if store is not None:
                store.write(rec)
            records[src.cell] = rec
            bar.update(1)
    finally:
        bar.close()


def _lost_record(src: CellSource, seed, lost) -> dict:
    """The record of a cell whose workers died repeatedly (status ``worker_lost``)."""
    return {"cell": src.cell, "condition": src.condition, "source": src.source, "digest": src.digest,
            "seed": cell_seed(seed, src.cell), "status": "worker_lost", "error": str(lost),
            "kind": "", "n_points": 0, "time_s": math.nan}


def _is_sources(obj) -> bool:
    return isinstance(obj, (list, tuple)) and bool(obj) and all(isinstance(s, CellSource) for s in obj)

"""Large ensembles of a distributed mechanism on the population engine: its mean moduli and their spread.

A mechanism whose tendon properties are drawn from a distribution
(:mod:`tenscell.fitting.models.heterogeneity`) is fitted through the average of its
moduli over a few stratified assignments (K = 8, :class:`~tenscell.fitting.models.mechanism.Mechanism`):
an estimate of the moduli's expectation over every way of assigning the
drawn values to the tendons. :func:`mechanism_ensemble` evaluates a fitted
mechanism over many more assignments (K = 200–2000, up to :data:`MAX_K`) and
gives, at each prestress and frequency, the ensemble's mean G′, G″ and the
spread between assignments (standard deviation, 5–95 % band): how much one
cell of the mechanism depends on which tendon got which value, and whether
the fit's own K-assignment average is within its sampling error of the
ensemble mean (:meth:`EnsembleResult.reference_z`).

The assignments run on the population engine
(:func:`tenscell.population._engine.run_tasks`, as ``fit-population`` and
``large-study`` do): a task is a chunk of :data:`CHUNK` assignments; the first
is timed here and, without ``workers``, decides whether a local Dask cluster
pays for its start-up (else every chunk runs here); chunks are batched into
Dask tasks of about two seconds. The numbers depend only on the model, the
grid, K and the seed: the assignments are drawn here before any task runs
(:func:`tenscell.fitting.models.heterogeneity.assignments`), chunk boundaries are
fixed, and each chunk is a pure function of its rows — ``workers=0`` and a
cluster give the same numbers.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .._checks import positive_array
from .._results import dataframe, format_repr, plotter, reporter
from .studies import _whole

__all__ = ["EnsembleResult", "mechanism_ensemble", "ensemble_at_data", "DEFAULT_K", "MAX_K", "CHUNK"]

#: assignments of an ensemble unless told (issue 18: "large ensembles", 200–2000)
DEFAULT_K = 1000
#: most assignments one ensemble takes (its members are held in memory: K × prestresses × frequencies values)
MAX_K = 100_000
#: assignments per task: fixed, so that the numbers never depend on where or how the tasks ran
CHUNK = 50
#: most K(ω) matrices one kernel call stacks (24×24 complex for the paper cell: about 9 kB each)
MAX_STACK = 2048
#: the band reported between assignments (percentiles)
BAND = (5.0, 95.0)


@dataclass(frozen=True, eq=False, repr=False)
class EnsembleResult:
    """G′, G″ of every assignment of a distributed mechanism, with their mean and spread (:func:`mechanism_ensemble`).

    Attributes
    ----------
    mechanism : str
        The mechanism's name.
    frequency_hz : ndarray, shape (nf,)
        Frequencies (Hz).
    prestress : ndarray, shape (nP,)
        Prestresses, in :attr:`prestress_unit`.
    prestress_unit : {"Pa", "N"}
        Pa: the data's prestress (mapped through the fitted scale s); N: the model prestress of a fit to data
        that state none.
    members : ndarray of complex, shape (K, nP, nf)
        G* = G′ + iG″ (Pa) of each assignment (cytoplasm viscosity included); NaN for an assignment that is not
        a stable cell.
    reference : ndarray of complex, shape (nP, nf)
        The fitted model's own moduli: the average over its ``reference_K`` assignments (what the fit used).
    reference_K : int
    seed : int
        Seed of the ensemble's assignments.
    workers : int
        Dask workers the chunks ran on (0: this process).
    elapsed_s : float
        Wall time (s).
    """

    mechanism: str
    frequency_hz: np.ndarray
    prestress: np.ndarray
    prestress_unit: str
    members: np.ndarray
    reference: np.ndarray
    reference_K: int
    seed: int
    workers: int
    elapsed_s: float

    @property
    def K(self) -> int:
        """Assignments in the ensemble."""
        return int(self.members.shape[0])

    @property
    def stable(self) -> np.ndarray:
        """Per assignment: its moduli are finite at every point (a stable cell), shape (K,)."""
        return np.all(np.isfinite(self.members), axis=(1, 2))

    @property
    def n_failed(self) -> int:
        """Assignments that are not a stable cell somewhere on the grid (left out of every statistic)."""
        return int(self.K - np.count_nonzero(self.stable))

    def _parts(self) -> tuple[np.ndarray, np.ndarray]:
        G = self.members[self.stable]
        if G.shape[0] < 2:
            raise ValueError(f"ensemble of {self.mechanism}: fewer than 2 of its {self.K} assignments are stable "
                             "cells: no mean or spread")
        return G.real, G.imag

    @property
    def mean(self) -> np.ndarray:
        """Mean G* over the stable assignments (Pa), shape (nP, nf)."""
        s, l = self._parts()
        return s.mean(axis=0) + 1j * l.mean(axis=0)

    @property
    def sd(self) -> np.ndarray:
        """Standard deviation between assignments of G′ (real part) and of G″ (imaginary part) (Pa), (nP, nf)."""
        s, l = self._parts()
        return s.std(axis=0, ddof=1) + 1j * l.std(axis=0, ddof=1)

    @property
    def sem(self) -> np.ndarray:
        """Sampling standard error of :attr:`mean` (Pa): ``sd/√K`` per part, (nP, nf)."""
        return self.sd / math.sqrt(self.K - self.n_failed)

    def band(self, q: tuple[float, float] = BAND) -> tuple[np.ndarray, np.ndarray]:
        """The ``q`` percentiles (default 5 and 95) of G′ (real) and G″ (imaginary) between assignments (Pa)."""
        s, l = self._parts()
        ps, pl = np.percentile(s, q, axis=0), np.percentile(l, q, axis=0)
        return ps[0] + 1j * pl[0], ps[1] + 1j * pl[1]

    def reference_z(self) -> tuple[float, float]:
        """Largest |fit's average − ensemble mean| in sampling standard errors, for G′ and for G″.

        The fit's average is a mean of ``reference_K`` assignments, the ensemble's of K; both estimate the same
        expectation, so their difference has the standard error ``sd·√(1/reference_K + 1/K)``. Values of a few
        units mean the fit's K was enough; much larger ones, that its average stands for other cells than the
        ensemble's.
        """
        n = self.K - self.n_failed
        scale = np.sqrt(1.0 / self.reference_K + 1.0 / n)
        out = []
        for part in (np.real, np.imag):
            se = part(self.sd) * scale
            diff = np.abs(part(self.reference) - part(self.mean))
            tiny = 1e-12 * np.abs(part(self.mean))  # a point where every assignment is the same cell
            out.append(float(np.max(diff / np.maximum(se, tiny))) if diff.size else 0.0)
        return out[0], out[1]

    @property
    def passive(self) -> bool:
        """Every stable assignment has G″ ≥ 0 at every point (a passive cell dissipates)."""
        return bool(np.all(self.members[self.stable].imag >= 0))

    def relative_spread(self) -> tuple[float, float]:
        """Largest sd/mean over the grid, for G′ and for G″ (a fraction)."""
        m, s = self.mean, self.sd
        return float(np.max(s.real / m.real)), float(np.max(s.imag / m.imag))

    def __repr__(self) -> str:
        nP, nf = self.reference.shape
        rs, rl = self.relative_spread()
        zs, zl = self.reference_z()
        where = "this process" if self.workers == 0 else f"{self.workers} Dask worker(s)"
        return format_repr(
            f"EnsembleResult {self.mechanism}: {self.K} assignments × {nP} prestress(es) × {nf} frequencies",
            f"largest spread between assignments (sd/mean): G′ {100 * rs:.3g} %, G″ {100 * rl:.3g} %",
            f"the fit's {self.reference_K}-assignment average: within {zs:.2g} (G′) and {zl:.2g} (G″) sampling "
            "standard errors of the ensemble mean",
            f"{self.n_failed} assignment(s) not a stable cell; seed {self.seed}; {self.elapsed_s:.1f} s in {where}")

    def _repr_html_(self) -> str:
        return reporter("ensemble_html")(self)  # spread between assignments, the fit's average (reports/html.py)

    def to_dataframe(self):
        """One row per (prestress, frequency): mean, sd, standard error, 5–95 % band and the fit's average (Pa)."""
        nP, nf = self.reference.shape
        lo, hi = self.band()
        cols: dict = {f"prestress_{self.prestress_unit}": np.repeat(self.prestress, nf),
                      "frequency_Hz": np.tile(self.frequency_hz, nP)}
        for name, part in (("storage", np.real), ("loss", np.imag)):
            for what, value in (("mean", self.mean), ("sd", self.sd), ("sem", self.sem),
                                (f"p{BAND[0]:02.0f}", lo), (f"p{BAND[1]:02.0f}", hi),
                                ("fit_average", self.reference)):
                cols[f"G_{name}_{what}_Pa"] = part(value).ravel()
        return dataframe(cols, attrs={"mechanism": self.mechanism, "K": self.K, "seed": self.seed,
                                      "reference_K": self.reference_K, "n_failed": self.n_failed})

    def plot(self, ax=None, **kw):
        """Mean G′ (solid) and G″ (dashed) with the 5–95 % band and the fit's average (circles); returns ``ax``."""
        return plotter("ensemble_moduli")(self, ax=ax, **kw)


# ---------------------------------------------------------------------------------------
# the work: one chunk of assignments (a task)
# ---------------------------------------------------------------------------------------
def _members(problem, phi, omega, P: float) -> np.ndarray:
    """G* (K_chunk, n_w) of the problem's assignments at one prestress P (N); NaN rows for unstable cells."""
    out = problem.evaluate(phi, omega, np.full(omega.size, P), jac=False)
    if out is not None:
        return out.G_assign
    k = problem.field_maps[0][1].shape[0]
    rows = np.full((k, omega.size), np.nan, dtype=complex)
    for j in range(k):  # one of them failed the stacked solve: find which, keep the others
        one = problem.assignments_subset(j, j + 1).evaluate(phi, omega, np.full(omega.size, P), jac=False)
        if one is not None:
            rows[j] = one.G_assign[0]
    return rows


def ensemble_chunk(problem, phi, omega, P_N) -> np.ndarray:
    """G* (Pa) of every assignment of ``problem`` at prestresses ``P_N`` (N) and ``omega`` (rad/s): (k, nP, nf).

    A task of :func:`mechanism_ensemble` (a pure function of its arguments; one BLAS thread, as on a worker).
    """
    from threadpoolctl import threadpool_limits

    k = problem.field_maps[0][1].shape[0]
    out = np.empty((k, len(P_N), omega.size), dtype=complex)
    step = max(1, MAX_STACK // k)
    with threadpool_limits(1):
        for i, P in enumerate(P_N):
            for a in range(0, omega.size, step):
                out[:, i, a:a + step] = _members(problem, phi, omega[a:a + step], float(P))
    return out


# ---------------------------------------------------------------------------------------
# the entry point
# ---------------------------------------------------------------------------------------
def _fitted_mechanism(model):
    """The fitted model of ``model`` (itself, or a fit's) when it has a distributed tendon property; ValueError
    (:class:`~tenscell.fitting.models.base.CapabilityError` for a fitted model without one) for anything else."""
    from ..fitting.models.base import CapabilityError, FittedModel
    from ..fitting.result import FitResult

    if isinstance(model, FitResult):  # the one result type of every fit, not a model class
        model = model.model
    if not isinstance(model, FittedModel):  # the fitted-model family, any kind
        raise ValueError(f"an ensemble needs a fitted mechanism (a FittedMechanism, or the FitResult of a "
                         f"mechanism), got {type(model).__name__}: only a mechanism with a distributed tendon "
                         "property has assignments to draw (a per-tendon fit or a formula has none)")
    if not model.capabilities.heterogeneous:
        raise CapabilityError(f"{model.describe()} draws no tendon property from a distribution: every assignment is "
                              "the same cell, so it has no ensemble")
    return model


def check_counts(K, workers=None) -> tuple[int, int | None]:
    """``(K, workers)`` checked: K assignments in 2..MAX_K, workers None or >= 0 (ValueError in one line)."""
    return _whole("K (assignments)", K, 2, MAX_K), None if workers is None else _whole("workers", workers, 0)


def check_ensemble(model, K, workers=None, seed=None):
    """``(fitted model, K, workers, seed)`` checked (ValueError in one line naming the argument), before any work."""
    model = _fitted_mechanism(model)
    K, workers = check_counts(K, workers)
    seed = None if seed is None else _whole("seed", seed, 0)  # None: the model's own
    return model, K, workers, seed


def mechanism_ensemble(model, f_hz, prestress_pa=None, *, K: int = DEFAULT_K, seed: int | None = None,
                       client=None, workers: int | None = None, scheduler: str | None = None,
                       progress: bool | None = None, notify=None) -> EnsembleResult:
    """G′, G″ of a fitted distributed mechanism over K assignments, on the population engine (module docstring).

    Parameters
    ----------
    model : FittedMechanism or MechanismFit
        A mechanism with at least one field drawn from a distribution: a fit's, or any mechanism at values
        of your own, ``FittedMechanism(MECHANISMS["voigt-lognormal-damping"], paper_cell(), values, P=1.0)``
        (values: SI units, by the names of ``bare_problem(mechanism, cell).names``; ``P`` the model
        prestress in N, or ``s`` in m² to take prestresses in Pa).
    f_hz : array_like
        Frequencies (Hz), > 0.
    prestress_pa : float or sequence of float, optional
        Prestresses in the data's units (Pa), as for
        :meth:`~tenscell.fitting.fitted.FittedMechanism.moduli` (default: its default prestress; for a
        fit with its own model prestress P only None is accepted). ``model.prestress_pa`` gives every
        prestress of the data.
    K : int
        Assignments, 2 to :data:`MAX_K`.
    seed : int, optional
        Seed of the assignments (default the mechanism's own). The same seed gives the same numbers wherever
        the chunks run.
    client, workers, scheduler, notify
        Where the chunks run, as for :func:`tenscell.population.fit_population`: ``workers=0`` in this
        process, ``workers=N`` a local Dask cluster of N processes, None decides from the first chunk's time
        (``notify`` gets a line when the work stays here).
    progress : bool, optional
        A progress bar over the chunks.

    Returns
    -------
    EnsembleResult
    """
    from .._progress import progress_bar
    from . import _engine

    t0 = time.perf_counter()
    model, K, workers, seed = check_ensemble(model, K, workers, seed)
    f = np.atleast_1d(positive_array("frequency", f_hz, unit="Hz")).ravel()
    pres = list(np.atleast_1d(np.asarray(prestress_pa, dtype=float))) if prestress_pa is not None else [None]
    P_N = [model.prestress(None if p is None else float(p)) for p in pres]  # every prestress checked first
    reference = np.array([_complex(model.moduli(f, None if p is None else float(p))) for p in pres])
    pb, phi, seed = model.ensemble_problem(K, seed)
    omega = 2 * np.pi * f
    chunks = [(lo, min(lo + CHUNK, K)) for lo in range(0, K, CHUNK)]
    members = np.empty((K, len(P_N), f.size), dtype=complex)
    placed: dict = {}
    items = ((k, (pb.assignments_subset(lo, hi), phi, omega, P_N)) for k, (lo, hi) in enumerate(chunks))
    with progress_bar(total=len(chunks), desc="ensemble", unit="chunk", progress=progress) as bar:
        for k, G in _engine.run_tasks(ensemble_chunk, items, client=client, workers=workers, scheduler=scheduler,
                                      name="tenscell-ensemble", warm=(__name__,), notify=notify, placed=placed):
            if isinstance(G, _engine.TaskLost):
                raise RuntimeError(f"ensemble chunk {k}: {G}")
            lo, hi = chunks[k]
            members[lo:hi] = G
            bar.update(1)
    if model.s is not None:
        shown, unit = np.array([float(np.median(model.prestress_pa)) if p is None else p for p in pres]), "Pa"
    else:
        shown, unit = np.array(P_N), "N"
    return EnsembleResult(mechanism=model.spec.name, frequency_hz=f, prestress=shown, prestress_unit=unit,
                          members=members, reference=reference, reference_K=model.assignments, seed=seed,
                          workers=int(placed.get("workers", 0)), elapsed_s=time.perf_counter() - t0)


def ensemble_at_data(model, datasets, K: int = DEFAULT_K, **where) -> EnsembleResult:
    """:func:`mechanism_ensemble` at the data's frequencies and prestresses: every prestress of the fit's data in
    Pa (stated or fitted), or the fit's own model prestress P when no data set stated one. ``where``: ``seed``,
    ``client``, ``workers``, ``scheduler``, ``progress``, ``notify``."""
    model = _fitted_mechanism(model)
    f = np.unique(np.concatenate([np.asarray(d.frequency_hz, dtype=float) for d in datasets]))
    prestress = sorted(set(model.prestress_pa)) if model.s is not None else None
    return mechanism_ensemble(model, f, prestress, K=K, **where)


def _complex(moduli) -> np.ndarray:
    Gs, Gl = moduli
    return np.asarray(Gs) + 1j * np.asarray(Gl)

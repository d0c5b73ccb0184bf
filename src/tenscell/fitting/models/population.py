"""Populations of cells fitted as one: parameters shared by every cell, and a few of each cell's own.

A :class:`Population` takes any model of the registry with one data set per cell (a mechanism, a structure-free
formula) and names the base model's parameters that differ from cell to cell (``per_cell``, e.g. the prestress
``P`` of a mechanism, or the modulus scale ``G0`` of a formula); every other parameter is a material property shared
by all cells of the line. Against ``n`` cells its problem (:class:`PopulationProblem`) lays out

* the shared parameters once (the base model's names), then
* the per-cell ones once per cell, ``name[k]`` for cell ``k`` (in the order of the data sets),

and concatenates the cells' residuals in the layout of :mod:`tenscell.fitting.problem` (every cell's G′ residuals,
then every cell's G″ residuals). Cell ``k``'s residuals depend on the shared parameters and on its own only, so the
Jacobian is block-sparse: the shared columns are dense, a cell's own columns are nonzero on its rows alone
(:attr:`PopulationProblem.sparsity`). Each evaluation costs one evaluation of the base model per cell, the Jacobian
has ``Σ_k 2 n_k (p_shared + p_cell)`` nonzeros, and the search solves its steps by LSMR on that sparse matrix
(:attr:`tenscell.fitting.problem.Problem.sparse_jacobian`): every step costs time linear in the number of cells.

The search's moves fit the cells with the shared parameters held (one sparse least-squares run whose Jacobian is
block-diagonal): a start places the base model on the population's median cell, then fits each cell's own
parameters; a basin-hopping move jitters the shared parameters and fits the cells again.

What the data determine (:func:`block_identifiability`) is computed with the same block structure: each cell's own
columns are projected out of its rows (the Schur complement of bundle adjustment), which gives the shared
parameters' covariance with every cell's own parameters profiled out, and each cell's own parameters' errors, in
time linear in the number of cells; the full Jacobian's singular value decomposition would need memory quadratic
in the number of residuals.

The fitted model (:class:`FittedPopulation`) answers as its typical cell: the shared parameters with each per-cell
parameter at its median over the cells (of an even number, the geometric mean of the middle two); :meth:`FittedPopulation.cell_model` gives any
cell's own fitted model.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse

from ..._results import format_repr
from ...io.data import DataError, RheologyData
from ..identifiability import Identifiability, combinations, sigma_estimate, errors_from_covariance
from ..parameters import Parameters, as_datasets
from ..problem import LN10, PENALTY, Problem, log_residual_blocks
from .base import FITTED_KINDS, Capabilities, FitFileError, FitModel, FittedModel, field_of, model_from_dict

__all__ = ["Population", "PopulationProblem", "FittedPopulation", "PopulationIdentifiability",
           "make_population_problem", "block_identifiability", "POPULATION_FORMAT", "cell_parameter_name"]

#: the ``format`` tag of a fitted population in fit.json's ``"model"`` entry
POPULATION_FORMAT = "tenscell-fitted-population"
#: evaluations of one fit of the cells' own parameters (the shared ones held) in a start or a move
CELL_FIT_EVALUATIONS = 25
#: cells of the small population a start or a move fits first (PopulationProblem.initial_guess, perturb)
START_CELLS = 8
#: free parameters up to which a population's Jacobian is dense and the search's steps exact
#: (:attr:`PopulationProblem.sparse_jacobian`)
DENSE_FREE = 64


def cell_parameter_name(name: str, k: int) -> str:
    """The name of cell ``k``'s own value of base parameter ``name``: ``"P[3]"``."""
    return f"{name}[{k}]"


@dataclass(frozen=True)
class Population(FitModel):
    """A base model fitted to many cells at once, with shared parameters and parameters of each cell's own.

    Attributes
    ----------
    base : FitModel or str
        The model of one cell (a name of :data:`tenscell.fitting.models.MODELS` or a model): a mechanism or a
        structure-free formula.
    per_cell : tuple of str
        Names of the base model's parameters that each cell has its own value of (one or two, typically: the
        prestress ``P`` of a mechanism, the modulus scale ``G0`` of a formula); every other parameter is shared.
    name, description : str
        Defaults say what the population is.
    """

    base: FitModel
    per_cell: tuple = ("P",)
    name: str = ""
    description: str = ""
    family = "population"

    def __post_init__(self):
        from . import get_model

        base = get_model(self.base)
        if isinstance(base, Population):
            raise ValueError("Population: the base model must be a model of one cell, not a population")
        per = (self.per_cell,) if isinstance(self.per_cell, str) else tuple(self.per_cell)
        if not per or not all(isinstance(n, str) and n for n in per) or len(set(per)) != len(per):
            raise ValueError(f"Population: per_cell must name one or more distinct parameters of {base.name}, "
                             f"got {self.per_cell!r}")
        object.__setattr__(self, "base", base)
        object.__setattr__(self, "per_cell", per)
        if not self.name:
            object.__setattr__(self, "name", f"{base.name} population (per cell: {', '.join(per)})")
        if not self.description:
            object.__setattr__(self, "description", f"{base.name} with {', '.join(per)} of each cell's own and every "
                                                    "other parameter shared by the cells")

    @property
    def structural(self) -> bool:
        return self.base.structural

    @property
    def group(self) -> str:
        return "populations"

    @property
    def capabilities(self) -> Capabilities:
        """The base model's, for many cells at once (per-cell parameters; moduli of each cell; no structure shares of a
        population)."""
        base = self.base.capabilities
        return Capabilities(data_kinds=frozenset({"moduli"}), structural=base.structural,
                            heterogeneous=base.heterogeneous, multimodal=base.multimodal, per_cell=True)

    def problem(self, data, cell=None, *, bounds=None, fixed=None) -> PopulationProblem:
        return make_population_problem(data, self, cell, bounds=bounds, fixed=fixed)

    def to_dict(self) -> dict:
        return {"class": "Population", "base": self.base.to_dict(), "per_cell": list(self.per_cell),
                "name": self.name, "description": self.description}

    @classmethod
    def from_fields(cls, fields: dict) -> Population:
        return cls(**{**fields, "base": model_from_dict(fields["base"]), "per_cell": tuple(fields["per_cell"])})


# ---------------------------------------------------------------------------------------
# the problem
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class PopulationProblem(Problem):
    """A :class:`Population` against its cells (built by :func:`make_population_problem`; module docstring).

    Attributes beyond the :class:`~tenscell.fitting.problem.Problem` layout
    ------------------------------------------------------------------------
    population : Population
    cells : tuple of Problem
        Each cell's base problem (its own data, the base model's layout).
    n_shared : int
        Parameters laid out once (they come first in ``names``); cell ``k``'s own are at
        ``n_shared + k·n_own + j``.
    base_shared, base_own : ndarray of int
        Positions in the base model's names of the shared parameters and of the per-cell ones.
    base_fixed_log : ndarray, shape (n_cells, n_base)
        Each cell's base log-parameters where the population does not set them.
    reference_cell : int
        The cell whose geometric-mean G′ is the median over the cells (the starts place the base model on it).
    sparse_jacobian : bool
        Whether the search takes the Jacobian sparse, its trust-region steps solved by LSMR (more than
        :data:`DENSE_FREE` free parameters), or dense, with scipy's exact steps (a small population: the starts'
        :data:`START_CELLS` cells). LSMR's steps lie in the plane of the gradient and the Gauss–Newton step (scipy's
        ``trf``); on a small, ill-conditioned population they took 135–200 evaluations (stopped by the budget, short
        of the optimum) where the exact steps took 55–62 (8 synthetic cells of ``springpot-tension+visc``, 13
        parameters). On a large one both took the same number (300 cells: 42), and exact steps cost time cubic in
        the cells.
    """

    population: Population
    cells: tuple
    params: Parameters
    n_shared: int
    base_shared: np.ndarray
    base_own: np.ndarray
    base_fixed_log: np.ndarray
    reference_cell: int
    sources: tuple
    omega: np.ndarray
    dataset_index: np.ndarray
    group_index: np.ndarray
    group_log_offset: np.ndarray
    group_map: np.ndarray
    group_measured: np.ndarray
    y_obs: np.ndarray
    weights: np.ndarray
    cell: object = None
    # the Jacobian's pattern, from ``free`` (set in __post_init__)
    _pattern: tuple = field(init=False, repr=False, default=())

    def __post_init__(self):
        object.__setattr__(self, "_pattern", _jacobian_pattern(self))
        # sparse (LSMR steps) beyond DENSE_FREE free parameters, dense (exact steps) below: class docstring
        object.__setattr__(self, "sparse_jacobian", self.n_free > DENSE_FREE)

    def __repr__(self) -> str:
        return (f"PopulationProblem({self.population.name}: {self.n_cells} cells, {self.n_free} free of "
                f"{self.n_params} parameters ({self.n_shared} shared), {self.n_points} points)")

    @property
    def spec(self) -> Population:
        return self.population


    @property
    def n_cells(self) -> int:
        """Number of cells (data sets)."""
        return len(self.cells)

    @property
    def n_own(self) -> int:
        """Parameters of each cell's own."""
        return int(self.base_own.size)

    @property
    def own_names(self) -> tuple:
        """The base model's names of the per-cell parameters."""
        return self.population.per_cell

    @property
    def shared_names(self) -> tuple:
        """Names of the shared parameters."""
        return self.names[: self.n_shared]

    def own_index(self, k: int) -> np.ndarray:
        """Positions in :attr:`names` of cell ``k``'s own parameters."""
        return self.n_shared + k * self.n_own + np.arange(self.n_own)

    @property
    def prestress_slice(self) -> slice:
        raise ValueError("a population's prestresses are each cell's (PopulationProblem.group_prestress)")

    # -- each cell's base parameters --------------------------------------------------------
    def cell_phis(self, phi) -> np.ndarray:
        """Every cell's base log-parameters (n_cells, n_base) from the population's ``phi``."""
        out = self.base_fixed_log.copy()
        out[:, self.base_shared] = phi[: self.n_shared]
        out[:, self.base_own] = np.asarray(phi[self.n_shared:]).reshape(self.n_cells, self.n_own)
        return out

    def cell_theta(self, theta, k: int) -> np.ndarray:
        """Cell ``k``'s free base log-parameters at the population's free log-parameters ``theta``."""
        pb = self.cells[k]
        return self.cell_phis(self.full(theta))[k][pb.free]

    def typical_phi(self, phi) -> np.ndarray:
        """Base log-parameters of the typical cell: the shared values, each per-cell one at its median over cells."""
        out = self.cell_phis(phi)[self.reference_cell].copy()
        own = np.asarray(phi[self.n_shared:]).reshape(self.n_cells, self.n_own)
        out[self.base_own] = np.median(own, axis=0)
        return out

    # -- evaluation -------------------------------------------------------------------------------
    def _evaluate_constrained(self, phi, jac: bool):
        # every cell at once where the base model's kernel can (Problem._evaluate_cells)
        return self.cells[0]._evaluate_cells(self.cells, self.cell_phis(phi), jac)

    def _stacked_moduli(self, out, jac: bool):
        """Every cell's model ``G*`` at its points (P,) and ``dG*/dφ`` over the base model's free parameters (P, q)
        (None without ``jac``), stacked in the population's order of points (:meth:`Problem._moduli_of` of each
        evaluation; NaN, and zero derivatives, for a cell whose evaluation found no stable cell)."""
        pairs = [pb._moduli_of(o) for pb, o in zip(self.cells, out)]
        sizes = [pb.n_points for pb in self.cells]
        G = np.concatenate([np.full(n, np.nan + 0j) if m is None else m[0] for m, n in zip(pairs, sizes)])
        if not jac:
            return G, None
        free = self.cells[0].free
        dG = np.concatenate([np.zeros((n, int(free.sum())), complex) if m is None or m[1] is None else m[1][:, free]
                             for m, n in zip(pairs, sizes)])
        return G, dG

    def _residuals_from(self, out) -> np.ndarray:
        """``w·(log10 model − log10 data)`` of every cell in stacked array calls; a cell without finite positive
        G′, G″ at every point gets the base problems' penalty on its rows, as its own problem gives it."""
        G, _ = self._stacked_moduli(out, jac=False)
        y = np.concatenate([G.real, G.imag])
        fine = np.isfinite(y) & (y > 0)
        cell = np.concatenate([self.dataset_index, self.dataset_index])
        bad = np.bincount(cell, ~fine, minlength=self.n_cells) > 0
        with np.errstate(divide="ignore", invalid="ignore"):
            r = self.weights * (np.log10(y) - self.y_obs)
        r[bad[cell]] = PENALTY
        return r

    def _jacobian_from(self, out):
        """The block-sparse Jacobian (CSR; an array where :attr:`sparse_jacobian` is False): each cell's rows hold its
        shared and own columns only; its values from the stacked moduli in array calls."""
        indices, indptr, kept = self._pattern
        G, dG = self._stacked_moduli(out, jac=True)
        data = self.weights[:, None] * log_residual_blocks(G, dG[:, kept])
        J = scipy.sparse.csr_matrix((data.ravel(), indices, indptr), shape=(self.n_residuals, self.n_free))
        return J if self.sparse_jacobian else J.toarray()

    def jacobian(self, theta) -> np.ndarray:
        """The Jacobian as a dense array (n_residuals, n_free) (the search uses the sparse one)."""
        J = self._jacobian_from(self._evaluate_constrained(self.full(theta), jac=True))
        return J.toarray() if scipy.sparse.issparse(J) else J

    def sparsity(self) -> scipy.sparse.csr_matrix:
        """The Jacobian's nonzero pattern (1 where a residual may depend on a free parameter)."""
        indices, indptr, _ = self._pattern
        return scipy.sparse.csr_matrix((np.ones(indices.size), indices, indptr), shape=(self.n_residuals, self.n_free))

    def moduli(self, theta) -> tuple[np.ndarray, np.ndarray]:
        phis = self.cell_phis(self.full(theta))
        parts = [pb.moduli(p[pb.free]) for pb, p in zip(self.cells, phis)]
        return np.concatenate([a for a, _ in parts]), np.concatenate([b for _, b in parts])

    def moduli_at(self, theta, f_hz, P_N) -> tuple[np.ndarray, np.ndarray]:
        """The typical cell's G′, G″ (Pa) (:meth:`typical_phi`) at ``f_hz`` (Hz) and model prestresses ``P_N`` (N)."""
        pb = self.cells[self.reference_cell]
        return pb.moduli_at(self.typical_phi(self.full(theta))[pb.free], f_hz, P_N)

    def dataset_moduli_at(self, theta, f_hz, P_N, dataset: int) -> tuple[np.ndarray, np.ndarray]:
        pb = self.cells[dataset]
        return pb.moduli_at(self.cell_theta(theta, dataset), f_hz, P_N)

    def group_prestress(self, theta) -> np.ndarray:
        phis = self.cell_phis(self.full(theta))
        return np.concatenate([pb.group_prestress(p[pb.free]) for pb, p in zip(self.cells, phis)])

    def model_prestress(self, theta, prestress_pa) -> np.ndarray:
        """The typical cell's model prestress (N) of measured prestresses (Pa), where the base model maps them."""
        pb = self.cells[self.reference_cell]
        return pb.model_prestress(self.typical_phi(self.full(theta))[pb.free], prestress_pa)

    # -- the search's moves -----------------------------------------------------------------------
    def initial_guess(self, rng: np.random.Generator) -> np.ndarray:
        """A start: the base model's own start on the reference cell, fitted there; then the population of a few cells
        spanning the stiffnesses (:data:`START_CELLS`) fitted from it; then every cell's own parameters fitted with
        the shared ones held. The small population pins the shared parameters down at little cost, so the search
        over all cells starts near its optimum."""
        from ..search import local_fit

        ref = self.cells[self.reference_cell]
        theta_ref, _, _ = local_fit(ref, ref.initial_guess(rng), 4 * CELL_FIT_EVALUATIONS)
        phi_ref = ref.full(theta_ref)
        phi = self.fixed_log.copy()
        phi[: self.n_shared] = phi_ref[self.base_shared]
        phi[self.n_shared:] = np.tile(phi_ref[self.base_own], self.n_cells)
        return self._from_shared(np.clip(phi, self.lower, self.upper))[self.free]

    def _from_shared(self, phi) -> np.ndarray:
        """``phi`` moved to the optimum of the small population (:attr:`start_cells`) from its shared values, then
        every cell's own parameters fitted with those shared values held."""
        from ..search import local_fit

        few = self.start_cells
        if few.size < self.n_cells:
            sub = self.subset(few)
            own = np.concatenate([self.own_index(int(k)) for k in few])
            sub_phi = sub.fit_cells(np.concatenate([phi[: self.n_shared], phi[own]]))
            theta, _, _ = local_fit(sub, sub_phi[sub.free], 8 * CELL_FIT_EVALUATIONS)
            phi = phi.copy()
            phi[: self.n_shared] = sub.full(theta)[: self.n_shared]
        return self.fit_cells(phi)

    @property
    def start_cells(self) -> np.ndarray:
        """The cells of a start's small population: :data:`START_CELLS` at even quantiles of the cells' mean log G′."""
        if self.n_cells <= START_CELLS:
            return np.arange(self.n_cells)
        order = np.argsort([float(np.mean(pb.y_obs[: pb.n_points])) for pb in self.cells], kind="stable")
        return np.sort(order[np.round(np.linspace(0, self.n_cells - 1, START_CELLS)).astype(int)])

    def subset(self, cells) -> PopulationProblem:
        """The same population over the cells ``cells`` (indices), with the same parameters free and held."""
        cells = np.asarray(cells, dtype=int)
        own = np.concatenate([self.own_index(int(k)) for k in cells]) if cells.size else np.zeros(0, int)
        keep = np.concatenate([np.arange(self.n_shared), own])
        rows = [np.flatnonzero(self.dataset_index == k) for k in cells]
        pts = np.concatenate(rows)
        n = self.n_points
        group_offsets = np.cumsum([0] + [self.cells[k].n_groups for k in cells])[:-1]
        return dataclasses.replace(
            self, cells=tuple(self.cells[k] for k in cells), params=self.params.subset(keep),
            base_fixed_log=self.base_fixed_log[cells],
            reference_cell=int(np.argmin(np.abs(cells - self.reference_cell))),
            sources=tuple(self.sources[k] for k in cells), omega=self.omega[pts],
            dataset_index=np.concatenate([np.full(r.size, j) for j, r in enumerate(rows)]),
            group_index=np.concatenate([self.cells[k].group_index + o for k, o in zip(cells, group_offsets)]),
            group_log_offset=np.concatenate([self.cells[k].group_log_offset for k in cells]),
            group_map=np.zeros((sum(self.cells[k].n_groups for k in cells), 0)),
            group_measured=np.concatenate([self.cells[k].group_measured for k in cells]),
            y_obs=np.concatenate([self.y_obs[pts], self.y_obs[n + pts]]),
            weights=np.concatenate([self.weights[pts], self.weights[n + pts]]))

    def perturb(self, theta, rng: np.random.Generator) -> np.ndarray:
        """A basin-hopping move: the shared parameters jittered by about half a decade, the small population's
        optimum from there, then each cell's own parameters fitted (so the search over all cells starts near the
        new basin's optimum)."""
        phi = self.full(theta)
        shared = np.flatnonzero(self.free[: self.n_shared])
        step = np.minimum(0.5 * LN10, 0.25 * (self.upper[shared] - self.lower[shared]))
        phi[shared] = np.clip(phi[shared] + rng.normal(0.0, 1.0, shared.size) * step, self.lower[shared],
                              self.upper[shared])
        return self._from_shared(phi)[self.free]

    def fit_cells(self, phi, max_nfev: int = CELL_FIT_EVALUATIONS) -> np.ndarray:
        """``phi`` with every cell's own parameters fitted and the shared ones held (one sparse least-squares run:
        the Jacobian of the cells' own parameters is block-diagonal)."""
        from ..search import local_fit

        own = np.zeros(self.n_params, dtype=bool)
        own[self.n_shared:] = True
        if not np.any(own & self.free):
            return phi
        held = self.holding(free=self.free & own, fixed_log=np.asarray(phi, dtype=float).copy())
        theta, _, _ = local_fit(held, phi[held.free], max_nfev)
        return held.full(theta)

    # -- what the result reads --------------------------------------------------------------------
    def identifiability(self, theta, *, sigma_known: bool = False, rtol: float = 1e-8):
        return block_identifiability(self, theta, sigma_known=sigma_known, rtol=rtol)

    def fitted(self, theta, result):
        phi = self.full(theta)
        ref = self.cells[self.reference_cell]
        typical = ref.fitted(self.typical_phi(phi)[ref.free], result)
        own = np.exp(np.asarray(phi[self.n_shared:]).reshape(self.n_cells, self.n_own))
        per_cell = {n: tuple(float(v) for v in own[:, j]) for j, n in enumerate(self.own_names)}
        return FittedPopulation(population=self.population, typical=typical, cells=self.sources, per_cell=per_cell,
                                s=typical.s, P=typical.P, prestress_pa=typical.prestress_pa,
                                source=f"{self.n_cells} cells")

    def summary(self, result) -> dict:
        return {"population": {"base": self.population.base.name, "per_cell": list(self.own_names),
                               "shared": list(self.shared_names), "n_cells": self.n_cells,
                               "reference_cell": self.reference_cell}}

    def describe(self) -> str:
        return (f"population of {self.n_cells} cells: {self.cells[0].describe()}; {', '.join(self.own_names)} of "
                "each cell's own, every other parameter shared")


def _jacobian_pattern(pb: PopulationProblem) -> tuple:
    """(column indices, row pointers, the base Jacobian's columns kept) of the sparse Jacobian (CSR).

    Every row (a cell's point, G′ rows then G″ rows) holds the base model's free parameters that the population
    frees: a shared one in its column, an own one in the column of the row's cell (a parameter the population holds
    is dropped). The rows are those of the stacked moduli (:meth:`PopulationProblem._stacked_moduli`).
    """
    if not pb.cells:
        return np.zeros(0, int), np.zeros(pb.n_residuals + 1, int), np.zeros(0, bool)
    base_free = np.flatnonzero(pb.cells[0].free)
    free_col = np.where(pb.free, np.cumsum(pb.free) - 1, -1)
    cell = np.concatenate([pb.dataset_index, pb.dataset_index])  # each row's cell
    own_pos = {int(i): j for j, i in enumerate(pb.base_own)}
    shared_pos = {int(i): j for j, i in enumerate(pb.base_shared)}
    # each base column's position in the population's parameters, per row (a shared one the same in every row)
    index = np.stack([np.full(cell.size, shared_pos[i]) if i in shared_pos else
                      pb.n_shared + cell * pb.n_own + own_pos[i] for i in base_free.tolist()], axis=1)
    cols = free_col[index]
    kept = np.all(cols >= 0, axis=0)
    cols = cols[:, kept]
    return cols.ravel(), np.arange(cell.size + 1) * int(kept.sum()), kept


def _cell_problems(datasets, base: FitModel, cell, bounds, fixed) -> tuple:
    problems = []
    for d in datasets:
        try:
            problems.append(base.problem(d, cell, bounds=bounds, fixed=fixed))
        except DataError as err:
            raise DataError(f"{d.source}: {err}") from None
    first = problems[0]
    for d, pb in zip(datasets, problems):
        if pb.names != first.names or not np.array_equal(pb.free, first.free):
            raise ValueError(f"{d.source}: its {base.name} parameters ({', '.join(pb.names)}) differ from those of "
                             f"{datasets[0].source} ({', '.join(first.names)}): every cell of a population must have "
                             "the same (state a prestress for every cell or for none)")
        if pb.n_penalties or np.any(pb.gauge() != 0) or pb.sparse_jacobian or \
                not np.array_equal(pb.coordinate_map(), np.eye(pb.n_free)):
            raise ValueError(f"model {base.name!r}: a population needs a base model without constraints or a gauge "
                             "(a mechanism or a formula; the Voigt cell's strut length is a gauge)")
    return tuple(problems)


def make_population_problem(data, population: Population, cell=None, *, bounds: dict | None = None,
                            fixed: dict | None = None) -> PopulationProblem:
    """Set up the fit of a :class:`Population` to its cells (one data set per cell).

    Parameters
    ----------
    data : sequence of RheologyData
        One moduli data set per cell (at least two).
    population : Population
    cell : Cell, optional
        The reference cell of a base model with a structure (default the paper cell).
    bounds, fixed : dict, optional
        As for the base model (``{name or kind: (lo, hi)}``, ``{name: value}``, SI units), applied to every cell; a
        per-cell parameter cannot be fixed (leave it out of ``per_cell``).

    Raises
    ------
    ValueError
        Fewer than two cells, creep data, an unknown per-cell name, cells whose parameters differ.
    DataError
        A cell with too few points for the base model (named).
    """
    datasets = as_datasets(data)
    if len(datasets) < 2 or not all(isinstance(d, RheologyData) for d in datasets):
        raise ValueError(f"a population needs two or more cells, each a RheologyData of moduli; got "
                         f"{len(datasets)} data set(s)")
    held = sorted(set(fixed or {}) & set(population.per_cell))
    if held:
        raise ValueError(f"fixed: {', '.join(held)} is a per-cell parameter of {population.name}: leave it out of "
                         "per_cell to hold it")
    base = population.base
    cells = _cell_problems(datasets, base, cell, bounds, fixed)
    first = cells[0]
    unknown = [n for n in population.per_cell if n not in first.names]
    if unknown:
        raise ValueError(f"per_cell: {', '.join(unknown)} is not a parameter of {base.name} here (parameters: "
                         f"{', '.join(first.names)})")
    own = np.array([first.names.index(n) for n in population.per_cell], dtype=int)
    shared = np.array([i for i in range(first.n_params) if i not in set(own.tolist())], dtype=int)
    lows = np.array([pb.lower for pb in cells])
    highs = np.array([pb.upper for pb in cells])
    n_cells = len(cells)
    names = [first.names[i] for i in shared]
    units = [first.units[i] for i in shared]
    kinds = [first.kinds[i] for i in shared]
    descs = [f"{first.descriptions[i]} (shared by the cells)" for i in shared]
    for k, d in enumerate(datasets):
        names += [cell_parameter_name(first.names[i], k) for i in own]
        units += [first.units[i] for i in own]
        kinds += [first.kinds[i] for i in own]
        descs += [f"{first.descriptions[i]}, of cell {k} ({_short(d.source)})" for i in own]
    # shared bounds: the union of the cells' own (each from its data's scale); per-cell ones: the cell's own
    lower = np.concatenate([lows[:, shared].min(axis=0), lows[:, own].ravel()])
    upper = np.concatenate([highs[:, shared].max(axis=0), highs[:, own].ravel()])
    free = np.concatenate([first.free[shared], np.tile(first.free[own], n_cells)])
    fixed_log = np.concatenate([first.fixed_log[shared], np.array([pb.fixed_log[own] for pb in cells]).ravel()])
    offsets = np.cumsum([0] + [pb.n_groups for pb in cells])[:-1]
    log_G = [float(np.mean(pb.y_obs[: pb.n_points])) for pb in cells]
    params = Parameters(names=tuple(names), units=tuple(units), descriptions=tuple(descs), kinds=tuple(kinds),
                        lower=lower, upper=upper, free=free, fixed_log=fixed_log)
    return PopulationProblem(
        population=population, cells=cells, params=params, n_shared=int(shared.size),
        base_shared=shared, base_own=own, base_fixed_log=np.array([pb.fixed_log for pb in cells]),
        reference_cell=int(np.argsort(log_G)[(n_cells - 1) // 2]), sources=tuple(d.source for d in datasets),
        omega=np.concatenate([pb.omega for pb in cells]),
        dataset_index=np.concatenate([np.full(pb.n_points, k) for k, pb in enumerate(cells)]),
        group_index=np.concatenate([pb.group_index + o for pb, o in zip(cells, offsets)]),
        group_log_offset=np.concatenate([pb.group_log_offset for pb in cells]),
        group_map=np.zeros((sum(pb.n_groups for pb in cells), 0)),
        group_measured=np.concatenate([pb.group_measured for pb in cells]),
        y_obs=np.concatenate([np.concatenate([pb.y_obs[: pb.n_points] for pb in cells]),
                              np.concatenate([pb.y_obs[pb.n_points: 2 * pb.n_points] for pb in cells])]),
        weights=np.concatenate([np.concatenate([pb.weights[: pb.n_points] for pb in cells]),
                                np.concatenate([pb.weights[pb.n_points: 2 * pb.n_points] for pb in cells])]),
        cell=first.cell,
    )


def _short(source: str) -> str:
    return source.replace("\\", "/").rsplit("/", 1)[-1]


# ---------------------------------------------------------------------------------------
# what the data determine, cell block by cell block
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class PopulationIdentifiability(Identifiability):
    """:class:`~tenscell.fitting.identifiability.Identifiability` of a population fit (:func:`block_identifiability`).

    The inherited fields describe the **shared** parameters with every cell's own parameters profiled out: their
    singular values, rank, combinations, standard errors and correlations are those of the reduced Jacobian (each
    cell's rows with its own columns projected out), whose normal matrix is the Schur complement of the cells'
    blocks; ``dof`` and ``sigma`` count every seen combination (shared and own); ``leverage`` is the full fit's.
    Each cell's own parameters carry their marginal standard errors in the fields below.

    Attributes
    ----------
    cell_names : tuple of str
        Per-cell parameters analysed (free, not at a bound).
    cell_standard_errors : ndarray
        Their standard errors of ln (inf: not determined; NaN: σ unknown).
    cell_null_share : ndarray
        Share of each one's unit vector in the combinations the data do not see.
    cell_excluded : tuple of (str, str)
        Per-cell parameters at a bound, and which.
    """

    cell_names: tuple = ()
    cell_standard_errors: np.ndarray = field(default_factory=lambda: np.zeros(0))
    cell_null_share: np.ndarray = field(default_factory=lambda: np.zeros(0))
    cell_excluded: tuple = ()

    def relative_error(self, name: str) -> tuple[float | None, str]:
        for n, reason in self.cell_excluded:
            if n == name:
                return None, f"(at its {reason}: not an estimate)"
        if name in self.cell_names:
            se = float(self.cell_standard_errors[self.cell_names.index(name)])
            if math.isnan(se):
                return None, "(σ unknown: as many seen combinations as residuals)"
            if not math.isfinite(se):
                return None, "(not determined: in a combination the data do not see)"
            return se, ""
        return super().relative_error(name)

    def to_dict(self) -> dict:
        def num(x):
            return float(x) if np.isfinite(x) else None

        return {**super().to_dict(),
                "profiled": "the shared parameters with each cell's own profiled out (the Schur complement of the "
                            "cells' blocks); per_cell: each cell's own parameters' marginal errors",
                "per_cell": [{"name": n, "standard_error_ln": num(se), "null_share": float(ns)}
                             for n, se, ns in zip(self.cell_names, self.cell_standard_errors, self.cell_null_share)],
                "per_cell_excluded": [{"name": n, "reason": r} for n, r in self.cell_excluded]}


def block_identifiability(problem: PopulationProblem, theta, *, sigma_known: bool = False,
                          rtol: float = 1e-8) -> PopulationIdentifiability:
    """What the data determine in a population fit, from the Jacobian's cell blocks (module docstring).

    For cell ``k`` with own columns ``A_k = U_k S_k V_kᵀ`` and shared columns ``B_k``, the reduced rows
    ``B̃_k = (I − U_k U_kᵀ) B_k`` stacked over the cells have ``B̃ᵀB̃ = Σ_k B_kᵀB_k − B_kᵀA_k(A_kᵀA_k)⁻¹A_kᵀB_k``, the
    Schur complement whose pseudo-inverse is the shared parameters' covariance (÷σ²). Cell ``k``'s own parameters
    have ``(A_kᵀA_k)⁻¹ + G_k (B̃ᵀB̃)⁺ G_kᵀ`` with ``G_k = (A_kᵀA_k)⁻¹A_kᵀB_k``. A combination is unseen where a
    singular value falls below ``rtol`` times the largest (of the blocks and of the stacked shared columns); a
    parameter is not determined when more than :data:`~tenscell.fitting.identifiability.NULL_SHARE` of its unit
    vector lies in the full Jacobian's null space, spanned by each ``A_k``'s own null vectors and, for every unseen
    shared direction ``u``, by ``(u, −G_1 u, …, −G_n u)``. These are the full-Jacobian numbers of
    :func:`~tenscell.fitting.identifiability.identifiability` (to rounding, where the fit has full rank) in memory
    and time linear in the number of cells.
    """
    theta = np.asarray(theta, dtype=float)
    if not 0 < rtol < 1:
        raise ValueError(f"rtol must lie in (0, 1), got {rtol!r}")
    pars = problem.parameters(theta)
    free_cols = np.cumsum(problem.free) - 1
    analysed = problem.free & np.array([p.at_bound is None for p in pars])
    shared = np.flatnonzero(analysed[: problem.n_shared])
    J = scipy.sparse.csr_matrix(problem._jacobian_from(problem._evaluate_constrained(problem.full(theta), jac=True)))
    r = problem.residuals(theta)
    B_all = J[:, free_cols[shared]].toarray()
    blocks, cell_rows = [], []
    for k in range(problem.n_cells):
        own = problem.own_index(k)
        own = own[analysed[own]]
        rows = np.flatnonzero(problem.dataset_index == k)
        rows = np.concatenate([rows, problem.n_points + rows])
        blocks.append((own, J[rows][:, free_cols[own]].toarray()))
        cell_rows.append(rows)
    return _block_analysis(problem, pars, r, B_all, blocks, cell_rows, shared, analysed,
                           sigma_known=sigma_known, rtol=rtol)


def _block_analysis(problem, pars, r, B_all, blocks, cell_rows, shared, analysed, *,
                    sigma_known: bool, rtol: float) -> PopulationIdentifiability:
    """The linear algebra of :func:`block_identifiability` (SVDs of each cell's block and of the reduced shared
    columns: parameter space, not a structure's matrices)."""
    svds = [np.linalg.svd(A, full_matrices=False) for _, A in blocks]
    s_all = np.linalg.svd(B_all, compute_uv=False) if B_all.size else np.zeros(0)
    top = max([float(s[0]) for _, s, _ in svds if s.size] + [float(s_all[0]) if s_all.size else 0.0])
    cut = rtol * top
    B_red = np.zeros_like(B_all)
    G, own_rank, own_null = [], 0, []
    h = np.zeros(r.size)
    for (own, _), (U, s, Vt), rows in zip(blocks, svds, cell_rows):
        rk = int(np.sum(s > cut)) if top > 0 else 0
        Uk, Bk = U[:, :rk], B_all[rows]
        B_red[rows] = Bk - Uk @ (Uk.T @ Bk)
        G.append((Vt[:rk].T / s[:rk]) @ (Uk.T @ Bk))  # (q, p): own parameters' response to the shared ones
        own_rank += rk
        own_null.append(np.sqrt(np.sum(Vt[rk:] ** 2, axis=0)) if own.size else np.zeros(0))
        h[rows] += np.sum(Uk**2, axis=1)
    Us, ss, Vts = np.linalg.svd(B_red, full_matrices=False) if B_red.size else (
        np.zeros((r.size, 0)), np.zeros(0), np.zeros((0, 0)))
    rank = int(np.sum(ss > cut)) if top > 0 else 0
    h += np.sum(Us[:, :rank] ** 2, axis=1)
    chi2 = float(r @ r)
    dof = r.size - rank - own_rank
    sigma, source = sigma_estimate(sigma_known, chi2, dof)
    V = Vts.T
    names = tuple(problem.names[i] for i in shared)
    # the full null space: (u, −G_k u) for each unseen shared direction u (and each block's own null vectors)
    V0 = V[:, rank:]
    GV0 = [g @ V0 for g in G]
    M = np.eye(V0.shape[1]) + sum((x.T @ x for x in GV0), np.zeros((V0.shape[1],) * 2))
    Minv = np.linalg.inv(M) if M.size else M
    null_share = np.sqrt(np.einsum("ij,jk,ik->i", V0, Minv, V0)) if V0.size else np.zeros(shared.size)
    cov_s = (V[:, :rank] / ss[:rank] ** 2) @ V[:, :rank].T if rank else np.zeros((shared.size, shared.size))
    se, corr = errors_from_covariance(cov_s, null_share, sigma)
    cell_names, cell_se, cell_null = [], [], []
    for (own, _), (_, s, Vt), g, gv0, nn in zip(blocks, svds, G, GV0, own_null):
        if not own.size:
            continue
        rk = g.shape[0]
        cov = (Vt[:rk].T / s[:rk] ** 2) @ Vt[:rk] + g @ cov_s @ g.T
        via_shared = np.einsum("ij,jk,ik->i", gv0, Minv, gv0) if gv0.size else np.zeros(own.size)
        share = np.sqrt(nn**2 + via_shared)
        cell_names += [problem.names[i] for i in own]
        cell_se.append(errors_from_covariance(cov, share, sigma)[0])
        cell_null.append(share)
    bound = list(np.flatnonzero(problem.free & ~analysed))
    excluded = [(pars[i].name, f"{pars[i].at_bound} bound") for i in bound]
    n_shared_excluded = sum(i < problem.n_shared for i in bound)
    return PopulationIdentifiability(
        names=names, labels=names, values=np.array([pars[i].value for i in shared]), singular_values=ss, rank=rank,
        rtol=rtol, gauge_removed=False, excluded=tuple(excluded[:n_shared_excluded]),
        fixed=tuple(problem.names[i] for i in np.flatnonzero(~problem.free)), n_residuals=r.size, sigma=sigma,
        sigma_source=source, dof=dof, chi2=chi2, standard_errors=se, null_share=null_share, correlation=corr,
        combinations=combinations(V, ss, rank, names, sigma), leverage=h, directions=V,
        cell_names=tuple(cell_names), cell_standard_errors=np.concatenate(cell_se) if cell_se else np.zeros(0),
        cell_null_share=np.concatenate(cell_null) if cell_null else np.zeros(0),
        cell_excluded=tuple(excluded[n_shared_excluded:]))


# ---------------------------------------------------------------------------------------
# the fitted population
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class FittedPopulation(FittedModel):
    """A fitted population: the typical cell (what every consumer of a fitted model takes) and each cell's own values.

    Attributes
    ----------
    population : Population
    typical : FittedModel
        The base model's fitted model with the shared parameters and each per-cell one at its median over the cells.
    cells : tuple of str
        Each cell's source, in order.
    per_cell : dict of str to tuple of float
        Each per-cell parameter's value (SI units) in every cell.
    s, P, prestress_pa, source
        Those of the typical cell (see :class:`~tenscell.fitting.models.base.FittedModel`).
    """

    population: Population
    typical: FittedModel
    cells: tuple
    per_cell: dict
    s: float | None = None
    P: float | None = None
    prestress_pa: tuple = ()
    source: str = ""
    FORMAT = POPULATION_FORMAT

    def __post_init__(self):
        self._check_prestress()
        object.__setattr__(self, "cells", tuple(str(c) for c in self.cells))
        values = {str(k): tuple(float(x) for x in v) for k, v in dict(self.per_cell).items()}
        bad = [k for k, v in values.items() if len(v) != len(self.cells)]
        if bad:
            raise ValueError(f"per_cell: {', '.join(bad)} must have one value for each of the {len(self.cells)} cells")
        object.__setattr__(self, "per_cell", values)

    def __repr__(self) -> str:
        med = ", ".join(f"{k} median {np.median(v):.4g}" for k, v in self.per_cell.items())
        return format_repr(f"FittedPopulation {self.population.name}", f"{len(self.cells)} cells; {med}",
                           f"typical cell: {self.typical!r}")

    @property
    def spec(self):
        return self.population

    @property
    def structural(self) -> bool:
        return self.typical.structural

    @property
    def n_cells(self) -> int:
        return len(self.cells)

    @property
    def cell(self):
        """The typical cell's reference cell (None for a structure-free formula)."""
        return self.typical.cell  # every fitted model of one cell has one (None: a formula)

    def describe(self) -> str:
        return f"the typical cell of the fitted population {self.population.name} ({len(self.cells)} cells)"

    def cell_model(self, k: int) -> FittedModel:
        """Cell ``k``'s own fitted model: the typical cell with cell ``k``'s per-cell values."""
        if not 0 <= int(k) < len(self.cells):
            raise ValueError(f"cell must lie in 0..{len(self.cells) - 1}, got {k!r}")
        values = {n: v[int(k)] for n, v in self.per_cell.items() if n not in ("P", "s")}
        pre = {n: v[int(k)] for n, v in self.per_cell.items() if n in ("P", "s")}
        return self.typical.with_values(values, source=self.cells[int(k)], **pre)

    # every consumer of a fitted model gets the typical cell's answers
    def moduli(self, f_hz, prestress_pa: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        return self.typical.moduli(f_hz, prestress_pa)

    @property
    def viscosity(self) -> float:
        return self.typical.viscosity

    def parameter_values(self) -> dict:
        """The typical cell's (each per-cell parameter at its median over the cells)."""
        return self.typical.parameter_values()

    def tendon_law(self, assignment: int = 0):
        return self.typical.tendon_law(assignment)

    def linear(self, prestress_pa: float | None = None, *, P_N: float | None = None, **kw):
        return self.typical.linear(prestress_pa, P_N=P_N, **kw)

    def voigt_tendons(self, P_N: float) -> tuple[np.ndarray, np.ndarray]:
        return self.typical.voigt_tendons(P_N)

    def to_dict(self) -> dict:
        return {"format": POPULATION_FORMAT, "population": self.population.to_dict(),
                "typical": self.typical.to_dict(), "cells": list(self.cells),
                "per_cell": {k: list(v) for k, v in self.per_cell.items()}, **self._prestress_fields()}

    @classmethod
    def from_dict(cls, obj: dict) -> FittedPopulation:
        spec = model_from_dict(field_of(obj, "population", dict))
        if not isinstance(spec, Population):
            raise FitFileError(f"model.population: a {type(spec).__name__}, not a population")
        typ = field_of(obj, "typical", dict)
        kind = FITTED_KINDS.get(typ.get("format"))
        if kind is None or kind is cls:
            raise FitFileError(f"model.typical.format: {typ.get('format')!r} is not a fitted model of one cell")
        typical = kind.from_dict(typ)
        cells = field_of(obj, "cells", list)
        per_cell = field_of(obj, "per_cell", dict)
        for name, vals in per_cell.items():
            if not isinstance(vals, list) or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                     and math.isfinite(v) and v > 0 for v in vals):
                raise FitFileError(f"model.per_cell.{name}: expected a list of finite numbers > 0")
        return cls(population=spec, typical=typical, cells=tuple(cells), per_cell=per_cell, s=typical.s,
                   P=typical.P, prestress_pa=typical.prestress_pa, source=str(obj.get("source", "")))

"""What a structure is: counts, rank, self-stress, mechanisms, prestressability, lowest modes.

:func:`summarize` answers the questions a user asks before trusting a new
structure (the text of ``tenscell show``); :func:`relaxation_modes` gives
the slowest relaxation modes as node displacement fields, ready for
:func:`tenscell.plotting.structure_3d`.

Free-standing structures (fewer than three fixed non-collinear nodes) keep
rigid-body motions; their stiffness is singular along them, so stability and
modes are computed on the complement of the rigid-body motions
(:func:`tenscell.model.formfinding.rigid_body_modes`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .model.coordinates import Coordinates, kinematics, make_coordinates
from .model.equilibrium import Cell, NotPrestressableError, equilibrate, equilibrium_matrix, member_geometry
from .model.formfinding import rigid_body_modes
from .linear.krylov import load_modes
from .linear.linearize import LinearModel, NotPositiveDefiniteError, linearize
from .linear.pencil import complement_basis
from .laws import DynamicLawError
from .model.structure import Structure, cable_mask
from ._threads import hot_path

__all__ = ["StructureSummary", "summarize", "relaxation_modes", "RelaxationModes", "node_displacements"]


@dataclass(frozen=True, repr=False)
class StructureSummary:
    """Counts and verdicts for one structure.

    Attributes
    ----------
    name : str
    n_nodes, n_fixed, n_point_nodes : int
    n_struts, n_anchored : int
        Rigid struts, and those anchored by a ball joint.
    members : tuple of (str, int)
        Number of members per family (tendons, and elastic struts ``"strut"``).
    n_coordinates : int
        Generalized coordinates n.
    rank : int
        Rank of the equilibrium matrix A(q0); -1 if not computed (sparse size).
    self_stress_dim : int
        ``m − rank``; -1 if not computed.
    mechanisms : int
        Infinitesimal mechanisms ``n − rank`` (rigid-body motions included); -1 if not computed.
    rigid_body_dof : int
        Rigid-body motions the supports leave free.
    prestressable : bool
        A self-stress with every tendon in tension exists at the reference.
    stable : bool or None
        K0 positive definite (on the complement of rigid-body motions) at the
        given P and EA; None if not prestressable or not checked.
    min_tension : float
        Smallest normalized tendon tension in T0 (NaN if not prestressable).
    P, EA : float
        The prestress (N) and a representative EA (N) used for ``stable``.
    verdict : str
        One sentence.
    """

    name: str
    n_nodes: int
    n_fixed: int
    n_point_nodes: int
    n_struts: int
    n_anchored: int
    members: tuple
    n_coordinates: int
    rank: int
    self_stress_dim: int
    mechanisms: int
    rigid_body_dof: int
    prestressable: bool
    stable: bool | None
    min_tension: float
    P: float
    verdict: str

    def text(self) -> str:
        """The summary as a few lines of text."""
        fam = ", ".join(f"{k} {v}" for k, v in self.members)
        unk = "not computed (sparse size)"
        lines = [
            f"structure      {self.name}",
            f"nodes          {self.n_nodes} ({self.n_fixed} fixed, {self.n_point_nodes} point nodes)",
            f"rigid struts   {self.n_struts} ({self.n_anchored} anchored by ball joints)",
            f"members        {sum(v for _, v in self.members)} ({fam})",
            f"coordinates    {self.n_coordinates}",
            f"rank of A      {self.rank if self.rank >= 0 else unk}",
            f"self-stresses  {self.self_stress_dim if self.self_stress_dim >= 0 else unk} (dimension of null A)",
            f"mechanisms     {self.mechanisms if self.mechanisms >= 0 else unk} (n - rank A, "
            f"including {self.rigid_body_dof} rigid-body motion(s))",
            f"verdict        {self.verdict}",
        ]
        return "\n".join(lines) + "\n"

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from ._results import format_repr

        fam = ", ".join(f"{v} {k}" for k, v in self.members)
        return format_repr(
            f"StructureSummary {self.name!r}",
            f"{self.n_nodes} nodes ({self.n_fixed} fixed), {self.n_struts} rigid struts, members: {fam}",
            f"{self.n_coordinates} coordinates; self-stresses {self.self_stress_dim if self.self_stress_dim >= 0 else '?'}"
            f", mechanisms {self.mechanisms if self.mechanisms >= 0 else '?'}",
            self.verdict,
        )

    def to_dataframe(self):
        """One row of the counts and verdicts (``P_N`` is the prestress used for ``stable``)."""
        from ._results import dataframe

        row = {k: [getattr(self, k)] for k in ("name", "n_nodes", "n_fixed", "n_point_nodes", "n_struts",
                                               "n_anchored", "n_coordinates", "rank", "self_stress_dim",
                                               "mechanisms", "rigid_body_dof", "prestressable", "stable")}
        return dataframe({**row, "min_T0": [self.min_tension], "P_N": [self.P], "verdict": [self.verdict]})


def _rigid_dof(structure: Structure) -> int:
    """Rigid-body motions v = t + ω × p the fixed nodes and the per-direction supports leave free (0 to 6)."""
    x = structure.nodes
    held = [(i, a) for i in structure.fixed for a in range(3)]
    held += [(i, "xyz".index(a)) for i, axes in structure.supports for a in axes]
    if not held:
        return 6
    nodes = sorted({i for i, _ in held})
    centre = x[nodes].mean(axis=0)
    rows = []
    for i, a in held:  # e_a·(t + ω × p) = 0 for every held direction a of node i
        p = x[i] - centre
        P = np.array([[0, p[2], -p[1]], [-p[2], 0, p[0]], [p[1], -p[0], 0]])
        rows.append(np.hstack([np.eye(3), P])[a])
    scale = max(1.0, float(np.abs(x[nodes] - centre).max()))
    return int(6 - np.linalg.matrix_rank(np.vstack(rows), tol=1e-9 * scale))


def summarize(target, P: float = 1000.0, EA=1.0, c=1.0, parametrization: str = "local"):
    """Summarize a structure or cell; never raises for a non-prestressable structure.

    Parameters
    ----------
    target : Structure or Cell
    P : float
        Prestress (N) for the stability verdict.
    EA, c : float or array_like, shape (m,)
        Member stiffness (N) and damping (N·s/m).
    parametrization : {"local", "angles"}
        Coordinates used when ``target`` is a Structure.

    Returns
    -------
    summary : StructureSummary
    cell : Cell or None
        None when not prestressable.
    lin : LinearModel or None
        The linearized model when prestressable and stable, else None.
    """
    if isinstance(target, Cell):
        cell, structure, reason = target, target.structure, ""
    else:
        structure = target
        try:
            cell, reason = equilibrate(structure, parametrization), ""
        except NotPrestressableError as err:
            cell, reason = None, str(err)
    s = structure
    fams: dict = {}
    for f in s.families:
        fams[f] = fams.get(f, 0) + 1
    rigid = _rigid_dof(s)
    n, rank, dim = _ranks(s, cell, parametrization)
    mech = n - rank if rank >= 0 else -1
    stable, lin, min_t = None, None, float("nan")
    if cell is None:
        verdict = f"NOT prestressable: {reason}"
    else:
        stable, lin, min_t, verdict = _stability(cell, P, EA, c, rigid)
    if s.notes:  # members between fixed nodes left out (model.structure)
        verdict += "; " + "; ".join(s.notes)
    summary = StructureSummary(
        name=s.name, n_nodes=s.n_nodes, n_fixed=len(s.fixed), n_point_nodes=len(s.point_nodes),
        n_struts=len(s.struts), n_anchored=sum(s.is_anchored(k) for k in range(len(s.struts))),
        members=tuple(sorted(fams.items())), n_coordinates=n, rank=rank, self_stress_dim=dim, mechanisms=mech,
        rigid_body_dof=rigid, prestressable=cell is not None, stable=stable, min_tension=min_t, P=float(P),
        verdict=verdict,
    )
    return summary, cell, lin


def _ranks(s: Structure, cell: Cell | None, parametrization: str) -> tuple[int, int, int]:
    """(coordinates, rank of the equilibrium matrix, self-stress dimension); -1 where not computed (sparse)."""
    if cell is not None:
        dim = cell.self_stress_dim
        return cell.n, (cell.m - dim if dim >= 0 else -1), dim
    coords = make_coordinates(s, parametrization)
    A = equilibrium_matrix(member_geometry(coords, coords.q0))
    if sp.issparse(A):
        return coords.n, -1, -1
    rank = int(np.linalg.matrix_rank(A, tol=1e-10 * max(np.abs(A).max(), 1e-300)))
    return coords.n, rank, s.n_tendons - rank


def _stability(cell: Cell, P: float, EA, c, rigid: int):
    """(stable: bool or None, the linear model or None, smallest normalized tension, the verdict's words)."""
    min_t = float(cell.T0[cable_mask(cell.structure.families)].min())
    stable: bool | None
    lin: LinearModel | None
    try:
        lin = linearize(cell, P=P, EA=EA, c=c, check=rigid == 0)
        stable = _stable_free(lin) if rigid else True
        if stable is False:
            lin = None
    except NotPositiveDefiniteError:
        stable, lin = False, None
    where = f"at P={P:g} N"
    if stable:
        verdict = (f"prestressable and stable: every tendon in tension (smallest normalized tension "
                   f"{min_t:.4g}), K0 positive definite {where}")
    elif stable is None:
        verdict = (f"prestressable (smallest normalized tension {min_t:.4g}); stability of this free-standing "
                   "structure not checked at this size")
    else:
        verdict = (f"prestressable (smallest normalized tension {min_t:.4g}) but NOT stable {where}: K0 is not "
                   "positive definite" + (" on the complement of the rigid-body motions" if rigid else ""))
    if rigid:
        verdict += f"; free-standing: {rigid} rigid-body motion(s) excluded"
    return stable, lin, min_t, verdict


def _complement(lin: LinearModel) -> np.ndarray:
    return complement_basis(rigid_body_modes(lin.cell.coords), lin.cell.n)


def _stable_free(lin: LinearModel):
    if sp.issparse(lin.K0):
        return None
    if lin.basis is not None:  # the model's pencil is already on the complement (tenscell.linear.rigid)
        return lin.pencil.is_positive_definite()
    return lin.pencil.restricted(_complement(lin)).is_positive_definite()


def node_displacements(coords: Coordinates, v: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
    """Node displacements ``∂x/∂q · v`` (m per unit of v), shape (n_nodes, 3), for a coordinate vector ``v``."""
    kin = kinematics(coords, coords.q0 if q is None else q)
    vv = np.append(np.asarray(v, dtype=float), 0.0)  # index -1 reads the padding zero
    return np.einsum("nxk,nk->nx", kin.jac, vv[kin.index])


@dataclass(frozen=True, eq=False, repr=False)
class RelaxationModes:
    """The slowest relaxation modes ``K0 v = λ C0 v``.

    Attributes
    ----------
    rates : ndarray, shape (k,)
        Relaxation rates λ (1/s), ascending.
    displacements : ndarray, shape (k, n_nodes, 3)
        Node displacements of each mode, scaled so the largest is 1
        (dimensionless shape).
    vectors : ndarray, shape (n, k)
        The modes in generalized coordinates.
    residuals : ndarray, shape (k,) or None
        Relative Ritz residuals of approximate modes (sparse models): each
        bounds, to first order, the relative distance from its rate to a rate
        of the model; None when exact (dense eigensolver).
    """

    rates: np.ndarray
    displacements: np.ndarray
    vectors: np.ndarray
    residuals: np.ndarray | None = None

    def rates_text(self) -> str:
        """The rates (1/s) with the significant digits their accuracy supports: six when exact (dense); else as
        many as keep the largest residual bound ε below half a unit in the last digit (2 to 6)."""
        if self.residuals is None or self.residuals.size == 0:
            digits = 6
        else:
            eps = max(float(self.residuals.max()), 1e-300)
            digits = int(min(6, max(2, np.floor(-np.log10(2 * eps)))))
        return ", ".join(f"{r:#.{digits}g}".rstrip(".") for r in self.rates)  # trailing zeros are digits too

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from ._results import format_repr, span

        how = "exact (dense)" if self.residuals is None else f"approximate, Ritz residuals {span(self.residuals)}"
        return format_repr(f"RelaxationModes: the {self.rates.size} slowest", f"rates λ {span(self.rates, '1/s')}",
                           f"{self.displacements.shape[1]} nodes; {how}")

    def to_dataframe(self):
        """One row per mode: ``mode, rate_per_s, time_s`` (and ``relative_error`` for approximate modes)."""
        from ._results import dataframe

        with np.errstate(divide="ignore"):
            cols = {"mode": np.arange(1, self.rates.size + 1), "rate_per_s": self.rates, "time_s": 1.0 / self.rates}
        if self.residuals is not None:
            cols["relative_error"] = self.residuals
        return dataframe(cols)

    def plot(self, ax=None, **kw):
        """The rates as bars; draw the mode shapes with :func:`tenscell.plotting.relaxation_modes_3d`."""
        from ._results import plotter

        rates_bar = plotter("rates_bar")

        return rates_bar(self.rates, ax=ax, **kw)


@hot_path
def relaxation_modes(lin: LinearModel, k: int = 3, tol: float = 1e-6) -> RelaxationModes:
    """The ``k`` slowest relaxation modes, also when C0 is singular or the structure is free-standing.

    Solves ``C0 v = μ K0 v`` (K0 positive definite; μ = 1/λ, μ = 0 for an
    undamped mechanism) and keeps the largest μ. Free-standing structures
    are treated on the complement of their rigid-body motions. Dense models
    use the pencil's modal decomposition (:meth:`~tenscell.linear.modal.Pencil.slow_modes`);
    sparse ones (more than 1500 coordinates) return the slowest modes *that the load excites*
    (:func:`tenscell.linear.krylov.load_modes`), each rate within ``tol`` (relative, to first
    order) of a rate of the model; ``residuals`` gives the bound each reached.
    """
    if not (isinstance(k, (int, np.integer)) and k >= 1):
        raise ValueError(f"k (number of modes) must be a whole number >= 1, got {k!r}")
    if lin.realization is not None:
        raise DynamicLawError(f"relaxation_modes: the {type(lin.law).__name__} tendons' internal variables are part of "
                         "every mode, which then has no node displacements alone; use creep_spectrum(lin) for its times")
    n = lin.cell.n
    if sp.issparse(lin.K0):
        # ARPACK does not converge in reasonable time on lattices, whose slowest rate is shared by
        # one local mode per module; the Lanczos run from the load finds the slowest modes it excites
        rates, V, resid = load_modes(lin, min(k, n), tol=tol)
        mu = 1.0 / rates
    elif rigid_body_modes(lin.cell.coords).shape[1] == 0:
        # anchored structures: the model's one modal decomposition (C0 v = τ K0 v, τ = μ ascending)
        mu, V = lin.pencil.slow_modes(k)
        resid = None
    else:  # free-standing: the pencil on the complement of the rigid-body motions
        Q = lin.basis if lin.basis is not None else _complement(lin)
        mu, W = (lin.pencil if lin.basis is not None else lin.pencil.restricted(Q)).slow_modes(k)
        V = Q @ W
        resid = None
    order = np.argsort(mu)[::-1][:k]
    mu, V = mu[order], V[:, order]
    if resid is not None:
        resid = resid[order]
    with np.errstate(divide="ignore"):
        rates = np.where(mu > 0, 1.0 / np.where(mu > 0, mu, 1.0), np.inf)
    disp = np.stack([node_displacements(lin.cell.coords, V[:, i]) for i in range(V.shape[1])])
    scale = np.abs(disp).reshape(disp.shape[0], -1).max(axis=1)
    disp = disp / np.where(scale > 0, scale, 1.0)[:, None, None]
    return RelaxationModes(rates=rates, displacements=disp, vectors=V, residuals=resid)

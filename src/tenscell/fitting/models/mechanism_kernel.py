"""The mechanism's moduli and their exact derivatives at every point at once: law values, one batched solve.

For parameters ``φ`` (natural logs), each field of the :class:`~tenscell.fitting.models.mechanism.Mechanism`
gives the law parameter of every tendon in every assignment k (K × m values,
:mod:`~tenscell.fitting.models.heterogeneity`); the law gives the dynamic tangent ``k*_j(ω)`` at the tensions
``P·T0`` and its exact derivatives (``complex_stiffness_derivatives``); and
:func:`tenscell.linear.dynamic.batched_compliance` gives J at every (point, assignment) in one batched solve, with
``∂J/∂k*_j`` and ``∂J/∂P`` from the same factorization. The chain rule then gives, exactly,

* a mechanism parameter q: ``∂J/∂φ_q = Σ_j ∂J/∂k*_j · Σ_p (∂k*_j/∂x_p)·x_p·∂ln x_p/∂φ_q``;
* the prestress: ``P·dJ/dP = P·∂J/∂P|_k* + Σ_j ∂J/∂k*_j · (∂k*_j/∂T)·P·T0_j`` (the law's tension dependence),
  times ``∂ln P/∂φ``;
* the viscosity adds ``iωη`` to G*: its derivative is itself.

The moduli are ``G* = mean_k (0.5/L)/J_k + iωη``.

**Many cells at once** (a population, :func:`evaluate_cells`): cells whose data points share one plan are
evaluated together, each at its own parameters: one law evaluation per grid with the tendons of every cell side by
side, one batched solve for every cell's points, the chain rule cell by cell in one contraction.

**The plan.** A law is evaluated on a grid of frequencies for a set of tendons. The points of a data set pair a
frequency with a prestress group (a frequency sweep: many frequencies at one prestress; a prestress sweep: one
frequency at many), so the points are split once, when the problem is built, into grids whose prestress groups
share one set of frequencies (:func:`plan_points`): the law is evaluated once per grid, with the tendons of every
group and assignment side by side, and each point takes its row. Nothing is validated, looked up or sorted per
evaluation: the problem checked its data and parameters when it was built.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...linear.assembly import continuum_factor
from ...linear.dynamic import batched_compliance
from .heterogeneity import DISTRIBUTIONS

__all__ = ["MechanismEvaluation", "Grid", "EvaluationPlan", "plan_points", "law_values", "evaluate",
           "evaluate_planned", "evaluate_cells"]


@dataclass(frozen=True, eq=False)
class MechanismEvaluation:
    """Moduli at one parameter vector (points of a problem, or any grid)."""

    G: np.ndarray  # (N,) complex moduli (Pa), averaged over assignments, viscosity included
    G_assign: np.ndarray  # (K, N) complex moduli of each assignment (structure + viscosity)
    dG: np.ndarray | None  # (N, n_params) complex dG/dφ


@dataclass(frozen=True, eq=False)
class Grid:
    """Points whose prestress groups share one set of frequencies: the law is evaluated once for all of them.

    Attributes
    ----------
    omega : ndarray, shape (U,)
        The grid's angular frequencies (rad/s), ascending.
    groups : ndarray of int, shape (G,)
        Its prestress groups, ascending.
    points : ndarray of int, shape (n,)
        The points it serves.
    cell : ndarray of int, shape (n,)
        Each point's place on the grid, ``u·G + g`` (its frequency's index u, its group's index g).
    rows : slice or None
        ``points`` as a slice when they are consecutive and in grid order (a data set's own sweep: its values are
        copied, not gathered).
    """

    omega: np.ndarray
    groups: np.ndarray
    points: np.ndarray
    cell: np.ndarray
    rows: slice | None = None  # the points as a slice, when they are consecutive and in grid order (no gathering)


@dataclass(frozen=True, eq=False)
class EvaluationPlan:
    """The points of a problem split into :class:`Grid` s (:func:`plan_points`)."""

    group_index: np.ndarray  # (N,) each point's prestress group
    grids: tuple

    @property
    def n_points(self) -> int:
        return int(self.group_index.size)


def plan_points(omega, group_index) -> EvaluationPlan:
    """Split points (angular frequency ``omega`` (rad/s), prestress group ``group_index``) into grids.

    Prestress groups with the same set of frequencies form one grid (a frequency sweep at several prestresses is
    one grid; a prestress sweep at one frequency is one grid), so every grid is evaluated only where some point
    needs it, and a data set adds at most one grid per distinct frequency set.
    """
    w = np.asarray(omega).ravel()  # angular frequencies (rad/s), or complex Laplace variables (1/s)
    gi = np.asarray(group_index, dtype=int).ravel()
    by_set: dict[bytes, tuple[np.ndarray, list]] = {}
    for g in np.unique(gi):
        f = np.unique(w[gi == g])
        by_set.setdefault(f.tobytes(), (f, []))[1].append(int(g))
    grids = []
    for f, gs in by_set.values():
        groups = np.array(gs, dtype=int)
        pts = np.flatnonzero(np.isin(gi, groups))
        cell = np.searchsorted(f, w[pts]) * groups.size + np.searchsorted(groups, gi[pts])
        n = pts.size
        ordered = n == f.size * groups.size and np.array_equal(cell, np.arange(n)) and np.array_equal(pts, pts[0] + np.arange(n))
        grids.append(Grid(omega=f, groups=groups, points=pts, cell=cell,
                          rows=slice(int(pts[0]), int(pts[0]) + n) if ordered else None))
    return EvaluationPlan(group_index=gi, grids=tuple(grids))


def law_values(problem, phi) -> tuple[dict, dict]:
    """Per law parameter: values (K, m) and d ln value / d φ (K, m, n_params), at log-parameters ``phi``."""
    vals, dln = {}, {}
    for name, D, const in problem.field_maps:
        lnx = const + D @ phi
        dl = D
        for fname, idx, dist, u in problem.shape_maps:
            if fname == name:  # ln x = ln scale + q(u; shape), with q the distribution's log quantile at scale 1
                q, _, dq = DISTRIBUTIONS[dist](1.0, math.exp(phi[idx])).log_quantile(u)
                lnx = lnx + q
                dl = D.copy()
                dl[..., idx] = dq
        vals[name], dln[name] = np.exp(lnx), dl
    return vals, dln


def evaluate(problem, phi, omega, P, jac: bool, dP=None, *, laplace: bool = False) -> MechanismEvaluation | None:
    """Moduli at angular frequencies ``omega`` (rad/s) and model prestresses ``P`` (N), per point, anywhere; with
    ``laplace`` the complex modulus ``G*(s)`` at complex Laplace variables ``omega`` (1/s) instead.

    ``dP`` (N, n_params): d ln P / d φ of each point (for the Jacobian). None where not a stable cell. The points
    are planned here (:func:`plan_points`, prestress groups from the distinct values of ``P``); a problem's own
    data points use the plan made once (:func:`evaluate_planned`).
    """
    omega = np.asarray(omega, dtype=complex if laplace else float).ravel()
    P_groups, group = np.unique(np.asarray(P, dtype=float).ravel(), return_inverse=True)
    return evaluate_planned(problem, phi, plan_points(omega, group), omega, P_groups, jac, dP, laplace=laplace)


def evaluate_planned(problem, phi, plan: EvaluationPlan, omega, P_groups, jac: bool,
                     dP=None, *, laplace: bool = False) -> MechanismEvaluation | None:
    """Moduli at the points of ``plan`` (angular frequencies ``omega``, rad/s; with ``laplace`` complex Laplace
    variables, 1/s, and ``G*(s)``), prestress ``P_groups[g]`` (N) in group g; ``dP`` (N, n_params) is d ln P / d φ of
    each point (with ``jac``). None where not a stable cell."""
    vals, dln = law_values(problem, phi)
    K, m = next(iter(vals.values())).shape
    N = plan.n_points
    laws = _tangents(problem, plan, vals, P_groups, K, m, jac, laplace)
    kstar = laws[0]
    P = np.repeat(P_groups[plan.group_index], K)  # rows (point, assignment)
    try:
        out = batched_compliance(problem.kernel, P, kstar.reshape(N * K, m), gradient=jac)
    except np.linalg.LinAlgError:
        return None
    J = (out[0] if jac else out).reshape(N, K)
    if not np.all(np.isfinite(J)):
        return None
    G = continuum_factor(problem.L_ref) / J  # (N, K)
    dG = None
    if jac:
        assert dP is not None
        dG = _derivatives(problem, laws, out, J, G, P.reshape(N, K), vals, dln, dP)
    G_assign = G.T
    if problem.eta_index is not None:
        visc = (omega if laplace else 1j * omega) * math.exp(phi[problem.eta_index])
        G_assign = G_assign + visc[None]
        if dG is not None:
            dG[:, problem.eta_index] += visc
    return MechanismEvaluation(G=G_assign.mean(axis=0), G_assign=G_assign, dG=dG)


def _tangents(problem, plan: EvaluationPlan, vals: dict, P_groups, K: int, m: int, jac: bool, laplace: bool = False):
    """``k*`` (N, K, m) at every point, and with ``jac`` ``∂k*/∂T`` (N, K, m) and ``∂k*/∂x_p`` (p, N, K, m); at
    complex Laplace variables with ``laplace`` (the laws' ``laplace_stiffness``).

    One law per grid, its tendons those of every (group, assignment) of the grid side by side.
    """
    N = plan.n_points
    kstar = np.empty((N, K, m), dtype=complex)
    dk_dT = np.empty((N, K, m), dtype=complex) if jac else None
    dk = None
    law_cls = problem.law_class
    for grid in plan.grids:
        shape = (grid.groups.size, K, m)
        T = (P_groups[grid.groups][:, None, None] * problem.T0).repeat(K, axis=1).ravel()
        l = np.broadcast_to(problem.lengths, shape).ravel()
        law = law_cls._trusted(**{n: _tile(v, grid.groups.size) for n, v in vals.items()})
        U = grid.omega.size * grid.groups.size
        rows = grid.rows
        pick = slice(None) if rows is not None else grid.cell
        rows = grid.points if rows is None else rows
        stiffness, derivatives = ((law.laplace_stiffness, law.laplace_stiffness_derivatives) if laplace else
                                  (law.complex_stiffness, law.complex_stiffness_derivatives))
        kstar[rows] = stiffness(l, T, grid.omega).reshape(U, K, m)[pick]
        if jac:
            assert dk_dT is not None
            dT, dx = derivatives(l, T, grid.omega)
            dk_dT[rows] = dT.reshape(U, K, m)[pick]
            if dk is None:
                dk = np.empty((dx.shape[0], N, K, m), dtype=complex)
            dk[:, rows] = dx.reshape(-1, U, K, m)[:, pick]
    return kstar, dk_dT, dk


def _tile(values, copies: int) -> np.ndarray:
    """``values`` (K, m) raveled, ``copies`` times over (a view when once)."""
    return values.ravel() if copies == 1 else np.tile(values.ravel(), copies)


def _derivatives(problem, laws, out, J, G, P, vals: dict, dln: dict, dP) -> np.ndarray:
    """``dG/dφ`` (N, n_params) of the assignments' mean from the kernel's ``∂J/∂k*``, ``∂J/∂P`` (module docstring)."""
    _, dk_dT, dk = laws
    _, dJ_dk, dJ_dP = out
    N, K = J.shape
    dG_dJ = -G / J  # (N, K): G = c/J
    g = dJ_dk.reshape(N, K, -1) * dG_dJ[..., None]  # dG_k/dk*_j
    dG = np.zeros((N, problem.n_params), dtype=complex)
    for p, name in enumerate(problem.law_names):
        chain = vals[name][..., None] * dln[name]  # x_p ∂ln x_p/∂φ, (K, m, n_params)
        if not chain.any():
            continue  # a held field
        dG += np.einsum("nkm,kmq->nq", g * dk[p], chain)
    # P dG/dP along the prestress: at fixed k*, and through the tensions P·T0 in k*
    dG_P = dG_dJ * P * dJ_dP.reshape(N, K) + np.einsum("nkm,nkm,m->nk", g, dk_dT, problem.T0) * P
    dG += dG_P.sum(axis=1)[:, None] * dP
    return dG / K


# ---- many cells at once (a population) ----------------------------------------------------------------------
def evaluate_cells(problems, phis, jac: bool) -> tuple:
    """Each mechanism problem of ``problems`` (cells of one population: the same mechanism, cell and parameter
    layout) at its own log-parameters ``phis[c]``, as ``problem._at_data(phis[c], jac)`` gives it (a
    :class:`MechanismEvaluation`, or None where not a stable cell), the cells whose points share a plan evaluated
    together (module docstring)."""
    phis = np.asarray(phis, dtype=float)
    out: list = [None] * len(problems)
    batches: dict = {}
    for c, pb in enumerate(problems):
        batches.setdefault((pb.omega.tobytes(), pb.group_index.tobytes()), []).append(c)
    for cells in batches.values():
        group = [problems[c] for c in cells]
        try:
            done = _evaluate_batch(group, phis[cells], jac)
        except np.linalg.LinAlgError:  # a singular cell: each cell alone (the others keep their moduli)
            done = [pb._at_data(phi, jac) for pb, phi in zip(group, phis[cells])]
        for c, e in zip(cells, done):
            out[c] = e
    return tuple(out)


def _cell_law_values(problems, phis) -> tuple[dict, dict]:
    """Per law parameter: values (C, K, m) and d ln value / d φ ((K, m, n) shared, or (C, K, m, n) per cell)."""
    first = problems[0]
    if first.shape_maps:  # a distribution's quantiles depend on each cell's shape parameter
        each = [law_values(pb, phi) for pb, phi in zip(problems, phis)]
        return ({n: np.stack([v[n] for v, _ in each]) for n in each[0][0]},
                {n: np.stack([d[n] for _, d in each]) for n in each[0][1]})
    vals, dln = {}, {}
    for name, D, const in first.field_maps:
        vals[name] = np.exp(const + np.einsum("kmq,cq->ckm", D, phis))
        dln[name] = D
    return vals, dln


def _evaluate_batch(problems, phis, jac: bool) -> list:
    """:func:`evaluate_cells` for cells of one plan: C cells, N points each, K assignments, m tendons."""
    first = problems[0]
    plan = first.plan
    C, N = len(problems), plan.n_points
    vals, dln = _cell_law_values(problems, phis)
    K, m = next(iter(vals.values())).shape[1:]
    sl = first.prestress_slice
    offsets = np.array([pb.group_log_offset for pb in problems])  # (C, G): stated prestresses differ by cell
    maps = np.array([pb.group_map for pb in problems])
    P_groups = np.exp(offsets + np.einsum("cgp,cp->cg", maps, phis[:, sl]))
    laws = _cell_tangents(first, plan, vals, P_groups, C, K, m, jac)
    P = np.repeat(P_groups[:, plan.group_index], K, axis=1)  # (C, N·K): rows (cell, point, assignment)
    out = batched_compliance(first.kernel, P.ravel(), laws[0].reshape(C * N * K, m), gradient=jac)
    J = (out[0] if jac else out).reshape(C, N, K)
    G = continuum_factor(first.L_ref) / J
    dG = None
    if jac:
        dP = np.zeros((C, N, first.n_params))
        dP[:, :, sl] = maps[:, plan.group_index]
        dG = _cell_derivatives(first, laws, out, J, G, P.reshape(C, N, K), vals, dln, dP)
    G_assign = np.swapaxes(G, 1, 2)  # (C, K, N)
    if first.eta_index is not None:
        visc = 1j * first.omega[None] * np.exp(phis[:, first.eta_index])[:, None]  # (C, N)
        G_assign = G_assign + visc[:, None]
        if dG is not None:
            dG[:, :, first.eta_index] += visc
    ok = np.all(np.isfinite(J), axis=(1, 2))
    return [MechanismEvaluation(G=G_assign[c].mean(axis=0), G_assign=G_assign[c], dG=None if dG is None else dG[c])
            if ok[c] else None for c in range(C)]


def _cell_tangents(problem, plan: EvaluationPlan, vals: dict, P_groups, C: int, K: int, m: int, jac: bool):
    """:func:`_tangents` for C cells: ``k*`` (C, N, K, m), ``∂k*/∂T`` (C, N, K, m), ``∂k*/∂x_p`` (p, C, N, K, m).

    One law per grid, its tendons those of every (cell, group, assignment) side by side.
    """
    N = plan.n_points
    kstar = np.empty((C, N, K, m), dtype=complex)
    dk_dT = np.empty((C, N, K, m), dtype=complex) if jac else None
    dk = None
    for grid in plan.grids:
        Gg = grid.groups.size
        shape = (C, Gg, K, m)
        T = np.broadcast_to(P_groups[:, grid.groups][:, :, None, None] * problem.T0, shape).ravel()
        l = np.broadcast_to(problem.lengths, shape).ravel()
        law = problem.law_class._trusted(**{n: np.broadcast_to(v[:, None], shape).ravel() for n, v in vals.items()})
        U = grid.omega.size
        rows = grid.points if grid.rows is None else grid.rows
        pick = slice(None) if grid.rows is not None else grid.cell

        dims = (U, C, Gg, K, m)
        kstar[:, rows] = _by_cell(law.complex_stiffness(l, T, grid.omega), dims, pick)
        if jac:
            assert dk_dT is not None
            dT, dx = law.complex_stiffness_derivatives(l, T, grid.omega)
            dk_dT[:, rows] = _by_cell(dT, dims, pick)
            if dk is None:
                dk = np.empty((dx.shape[0], C, N, K, m), dtype=complex)
            dk[:, :, rows] = _by_cell(dx, dims, pick, (dx.shape[0],))
    return kstar, dk_dT, dk


def _by_cell(a, dims, pick, lead=()) -> np.ndarray:
    """A grid's law output (..., U, C·Gg·K·m) as (..., C, U·Gg, K, m) (a point's row: u·Gg + g), its points picked."""
    U, C, Gg, K, m = dims
    a = np.moveaxis(a.reshape(*lead, U, C, Gg, K, m), len(lead) + 1, len(lead))
    return a.reshape(*lead, C, U * Gg, K, m)[..., pick, :, :]


def _cell_derivatives(problem, laws, out, J, G, P, vals: dict, dln: dict, dP) -> np.ndarray:
    """:func:`_derivatives` for C cells: ``dG/dφ`` (C, N, n_params), each cell at its own parameters."""
    _, dk_dT, dk = laws
    _, dJ_dk, dJ_dP = out
    C, N, K = J.shape
    dG_dJ = -G / J
    g = dJ_dk.reshape(C, N, K, -1) * dG_dJ[..., None]
    dG = np.zeros((C, N, problem.n_params), dtype=complex)
    for p, name in enumerate(problem.law_names):
        d = dln[name]
        chain = vals[name][..., None] * (d[None] if d.ndim == 3 else d)  # (C, K, m, n_params)
        if not chain.any():
            continue  # a held field
        dG += np.einsum("cnkm,ckmq->cnq", g * dk[p], chain)
    dG_P = dG_dJ * P * dJ_dP.reshape(C, N, K) + np.einsum("cnkm,cnkm,m->cnk", g, dk_dT, problem.T0) * P
    dG += dG_P.sum(axis=2)[..., None] * dP
    return dG / K

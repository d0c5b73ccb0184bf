"""Form-finding: from a topology and a rough shape to a prestressable configuration.

Method (force densities with rigid struts)
------------------------------------------
Give every cable ``j`` a force density ``w_j > 0`` (N/m). The configurations
that are stationary points of

    E(q) = ½ Σ_cables w_j l_j(q)²  +  ½ Σ_elastic struts k (l_j(q) − s_j)²

over the structure's generalized coordinates ``q`` (rigid struts keep their
length exactly because the coordinates do) satisfy ``A(q)·T = 0`` with
``T_j = w_j l_j > 0`` on every cable: they are prestressable, with the
self-stress ``T`` known by construction (the force-density method). A
*minimum* of ``E`` is moreover stable with spring constants ``w_j``, so the
search minimizes ``E`` by a damped Newton iteration (Levenberg–Marquardt,
exact analytic gradient and Hessian from :mod:`tenscell.model.equilibrium`,
solved with scipy). The strut directions are re-charted at every step
(``"local"`` coordinates around the current shape), so struts may turn by
any angle.

Members of family ``"strut"`` (elastic compression members between point
nodes) are springs of stiffness ``k`` whose rest length ``s_j`` is corrected
after each converged solve until they have their initial length again, so
they too come out at their given length.

When no configuration is found (the iteration does not converge, a cable or
the whole structure collapses to zero size), :class:`FormFindingError` says
which and why.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .coordinates import Coordinates, kinematics, make_coordinates, positions
from .equilibrium import (
    Cell,
    NotPrestressableError,
    equilibrate,
    equilibrium_matrix,
    member_geometry,
    tangent_stiffness,
)
from .structure import STRUT, Structure, member_values

__all__ = [
    "FormFindingError",
    "FormFindingResult",
    "find_form",
    "rigid_body_modes",
    "pin_jointed",
]


class FormFindingError(NotPrestressableError):
    """Form-finding found no prestressable configuration; the message says why."""


@dataclass(frozen=True, eq=False, repr=False)
class FormFindingResult:
    """A configuration found by :func:`find_form`.

    Attributes
    ----------
    structure : Structure
        The input topology at the found node positions (m).
    cell : Cell
        The structure equilibrated with ``T0 = tensions / ‖tensions_cables‖``.
    force_density : ndarray, shape (m,)
        Force densities used, ``w_j`` (N/m); NaN for elastic struts.
    tensions : ndarray, shape (m,)
        Member forces of the found self-stress (N): ``w_j·l_j`` on cables,
        ``k·(l_j − s_j)`` (negative: compression) on elastic struts.
    iterations : int
        Newton steps taken (all rest-length corrections together).
    residual : float
        ``‖A·T‖₂ / (max|A|·‖T‖₂)`` at the end (dimensionless).
    stable : bool or None
        Whether ``E`` has a strict minimum there apart from rigid-body
        motions (its Hessian is positive definite on their complement);
        None when not checked (structures above the sparse threshold).
    rigid_body_dof : int
        Number of rigid-body motions the supports leave free (6 for a
        free-standing structure, 0 for one anchored at three points).
    """

    structure: Structure
    cell: Cell
    force_density: np.ndarray
    tensions: np.ndarray
    iterations: int
    residual: float
    stable: bool | None
    rigid_body_dof: int

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from .._results import format_repr, span

        stable = {True: "a strict energy minimum", False: "NOT a strict energy minimum", None: "stability not checked"}
        return format_repr(
            f"FormFindingResult {self.structure.name!r}",
            f"{self.structure.n_nodes} nodes, {len(self.structure.struts)} rigid struts, "
            f"{self.structure.n_tendons} members; member forces {span(self.tensions, 'N')}",
            f"{self.iterations} Newton steps, residual {self.residual:.3g}; {stable[self.stable]}; "
            f"{self.rigid_body_dof} rigid-body motion(s) free",
        )

    def to_dataframe(self):
        """One row per member: the structure's columns, ``force_density_N_per_m`` and ``tension_N``."""
        return self.structure.to_dataframe("tendons", force_density_N_per_m=self.force_density,
                                           tension_N=self.tensions)

    def plot(self, ax=None, **kw):
        """The found structure in 3D (:func:`tenscell.plotting.structure_3d`)."""
        return self.structure.plot(ax=ax, **kw)


def _force_density(structure: Structure, force_density) -> np.ndarray:
    fams = structure.families
    if isinstance(force_density, dict):
        force_density = {STRUT: np.nan, **force_density}  # struts carry no force density of their own
    w = member_values(structure, force_density, name="force_density", unit="N/m")
    w[[f == STRUT for f in fams]] = np.nan
    cable = np.array([f != STRUT for f in fams], dtype=bool)
    bad = cable & ~(np.isfinite(w) & (w > 0))
    if np.any(bad):
        j = int(np.flatnonzero(bad)[0])
        raise ValueError(f"force_density of tendon {j} ({fams[j]}) must be a finite number > 0 (N/m), got {w[j]!r}")
    return w


def rigid_body_modes(coords: Coordinates, q: np.ndarray | None = None, rtol: float = 1e-9) -> np.ndarray:
    """Infinitesimal rigid-body motions allowed by the supports, in generalized coordinates.

    Parameters
    ----------
    coords : Coordinates
    q : ndarray, shape (n,), optional
        Configuration (default: the reference ``coords.q0``).

    Returns
    -------
    ndarray, shape (n, k)
        Orthonormal columns spanning the ``q̇`` that move every node rigidly
        (translations and rotations keeping the fixed nodes still). ``k`` is 6
        for a free-standing structure and 0 when three non-collinear nodes
        are fixed.
    """
    q = coords.q0 if q is None else np.asarray(q, dtype=float)
    kin = kinematics(coords, q)
    x = kin.x
    s = coords.structure
    nn = s.n_nodes
    # node velocities of the 6 rigid motions, v_i = t + ω × x_i, about the centroid (conditioning)
    xc = x - x.mean(axis=0)
    V: np.ndarray = np.zeros((nn, 3, 6))
    V[:, :, :3] = np.eye(3)
    for k, e in enumerate(np.eye(3)):
        V[:, :, 3 + k] = np.cross(e, xc)
    V = V.reshape(3 * nn, 6)
    fixed = np.zeros(nn, dtype=bool)
    fixed[list(s.fixed)] = True
    # motions that leave the fixed nodes still, and the supported directions of rollers
    Vn = V.reshape(nn, 3, 6)
    held = [Vn[node, "xyz".index(a)] for node, axes in s.supports for a in axes]
    Vf = np.vstack([Vn[fixed].reshape(-1, 6), *(np.array(held).reshape(-1, 6) for _ in [0] if held)])
    if Vf.size:
        Z = scipy.linalg.null_space(Vf, rcond=rtol)
        V = V @ Z
    if V.shape[1] == 0:
        return np.zeros((coords.n, 0))
    # the generalized velocities realizing them, block by block (a strut's or a point's coordinates
    # are moved by at most two nodes): J_b q̇_b = v on those nodes, exact for a rigid motion
    Qd = np.zeros((coords.n, V.shape[1]))
    V3 = V.reshape(nn, 3, -1)
    idx = kin.index
    blocks: dict = {}
    for i in range(nn):
        if idx[i, 0] >= 0:
            blocks.setdefault(int(idx[i, 0]), []).append(i)
    for nodes in blocks.values():
        cols = idx[nodes[0]][idx[nodes[0]] >= 0]
        Jb = np.concatenate([kin.jac[i][:, : cols.size] for i in nodes])
        Vb = np.concatenate([V3[i] for i in nodes])
        Qd[cols] = np.linalg.lstsq(Jb, Vb, rcond=None)[0]
    # keep the independent ones (a structure on one line has only 5 rigid motions)
    U, sv2, _ = np.linalg.svd(Qd, full_matrices=False)
    k = int(np.sum(sv2 > rtol * max(sv2.max(initial=0.0), 1e-300)))
    return U[:, :k]


def pin_jointed(structure: Structure, name: str | None = None) -> Structure:
    """The same structure with every rigid strut replaced by an elastic member of family ``"strut"``.

    All nodes that are not fixed become point nodes (3 coordinates each): the
    node-based formulation. The strut members are appended after the
    tendons, in strut order, so tendon indices (and equal-tension groups)
    are unchanged.
    """
    s = structure
    return dataclasses.replace(
        s,
        struts=(),
        tendons=tuple(s.tendons) + tuple(s.struts),
        families=tuple(s.families) + (STRUT,) * len(s.struts),
        name=name or f"{s.name} (pin-jointed)",
    )


def _energy(l, w, r):
    return float(0.5 * np.sum(w * (l - r) ** 2))


def find_form(
    structure: Structure,
    force_density=1.0,
    *,
    rest_length=0.0,
    strut_stiffness: float | None = None,
    max_iter: int = 300,
    tol: float = 1e-12,
    parametrization: str = "local",
) -> FormFindingResult:
    """Find a prestressable configuration of a topology from a rough initial shape.

    Parameters
    ----------
    structure : Structure
        The topology (struts, tendons, fixed nodes, load, probe) at a rough
        initial shape (m). Rigid struts keep their lengths; fixed nodes stay.
    force_density : float, dict or array_like, shape (m,)
        Cable force densities ``w`` (N/m): one for all, ``{family: w}`` (key
        ``"default"`` for the rest) or one per tendon.
    rest_length : float, dict or array_like, shape (m,)
        Cable rest lengths ``r`` (m), same forms; default 0. Cable tensions
        come out as ``T = w·(l − r)``: with ``r = 0`` this is the
        force-density method (the ratio of force densities between families
        sets the shape); ``r > 0`` makes the cables springs (dynamic
        relaxation), which picks one shape where the force-density method
        admits a continuous family (e.g. the affine shears of the 6-strut
        icosahedron).
    strut_stiffness : float, optional
        Spring constant (N/m) holding members of family ``"strut"`` at their
        initial length; default ``1e3·max(w)``.
    max_iter : int
        Newton steps allowed in all.
    tol : float
        Convergence threshold on the relative equilibrium residual
        ``‖A·T‖/(max|A|·‖T‖)``.
    parametrization : {"local", "angles"}
        Coordinates of the returned cell (see :mod:`tenscell.model.coordinates`).

    Returns
    -------
    FormFindingResult

    Raises
    ------
    FormFindingError
        If no prestressable configuration is found: the iteration does not
        converge, a cable shrinks to zero length or goes slack, or the
        structure collapses.
    ValueError
        For bad force densities, rest lengths or options.
    """
    s = structure
    w, r, cable, target = _member_springs(s, force_density, rest_length, strut_stiffness)
    if not (isinstance(max_iter, (int, np.integer)) and max_iter >= 1):
        raise ValueError(f"max_iter must be a whole number >= 1, got {max_iter!r}")
    if not (tol > 0):
        raise ValueError(f"tol must be > 0, got {tol!r}")
    size0 = _size(s.nodes)
    if size0 <= 0:
        raise FormFindingError(f"{s.name}: all nodes coincide; give a rough initial shape")
    nodes, r, it, resid = _relax(s, w, r, cable, target, max_iter, tol, size0)
    found = dataclasses.replace(s, nodes=nodes)
    coords = make_coordinates(found, "local")
    geom = member_geometry(coords, coords.q0)
    T = w * (geom.lengths - r)
    slack = np.flatnonzero(cable & (T <= 0))
    if slack.size:
        j = int(slack[0])
        raise FormFindingError(
            f"{s.name}: no prestressable configuration found: at the equilibrium reached, tendon {j} "
            f"({s.families[j]}) is shorter than its rest length and would be slack; use smaller rest lengths"
        )
    A = equilibrium_matrix(geom)
    try:
        cell = equilibrate(found, parametrization, T0=T, parameters={"form-found": True})
    except NotPrestressableError as err:  # pragma: no cover - T is a self-stress by construction
        raise FormFindingError(f"{s.name}: the found configuration failed the self-stress check: {err}") from None
    R = rigid_body_modes(coords)
    stable = None
    if not sp.issparse(A):
        H = tangent_stiffness(geom, T, w)
        if R.shape[1]:
            Qc = scipy.linalg.null_space(R.T)
            H = Qc.T @ H @ Qc
        ev = np.linalg.eigvalsh(0.5 * (H + H.T)) if H.size else np.array([1.0])
        stable = bool(ev[0] > 1e-9 * max(abs(ev[-1]), 1e-300))
    return FormFindingResult(
        structure=found, cell=cell, force_density=np.where(cable, w, np.nan), tensions=T, iterations=it,
        residual=resid, stable=stable, rigid_body_dof=R.shape[1],
    )


def _member_springs(s: Structure, force_density, rest_length, strut_stiffness):
    """``(w, r, cable, target)``: every member's force density (N/m) and rest length (m) — the cables' as given,
    the struts' a stiff spring at their initial length —, which members are cables, and every member's initial
    length (m). ValueError for bad values."""
    w = _force_density(s, force_density)
    cable = np.array([f != STRUT for f in s.families], dtype=bool)
    if not np.any(cable):
        raise ValueError("form-finding needs at least one cable (a member whose family is not 'strut')")
    r = _rest_lengths(s, rest_length, cable)
    t_idx = np.asarray(s.tendons, dtype=int).reshape(-1, 2)
    target = np.linalg.norm(s.nodes[t_idx[:, 0]] - s.nodes[t_idx[:, 1]], axis=1)
    if np.any(~cable):
        k = float(strut_stiffness) if strut_stiffness is not None else 1e3 * float(np.max(w[cable]))
        if not (np.isfinite(k) and k > 0):
            raise ValueError(f"strut_stiffness must be a finite number > 0 (N/m), got {strut_stiffness!r}")
        w = np.where(cable, w, k)
        r = np.where(cable, r, target)
    return w, r, cable, target


def _relax(s: Structure, w, r, cable, target, max_iter: int, tol: float, size0: float):
    """Minimize the energy, then move the struts' rest lengths until the elastic struts are back at their lengths:
    ``(nodes, rest lengths, Newton steps, relative residual)``."""
    t_idx = np.asarray(s.tendons, dtype=int).reshape(-1, 2)
    nodes = np.array(s.nodes, dtype=float)
    it, corrections, mu = 0, 0, 1e-3
    while True:
        nodes, it, mu, resid = _minimize(s, nodes, w, r, cable, it, max_iter, tol, mu, size0)
        if np.all(cable):
            return nodes, r, it, resid
        l = np.linalg.norm(nodes[t_idx[:, 0]] - nodes[t_idx[:, 1]], axis=1)
        err = np.max(np.abs(l[~cable] - target[~cable]) / target[~cable])
        if err < 1e-11:
            return nodes, r, it, resid
        corrections += 1
        if corrections > 60:
            raise FormFindingError(
                f"{s.name}: no prestressable configuration found: the elastic struts did not return to their "
                f"lengths (relative error {err:.3g}); try a larger strut_stiffness"
            )
        r = r + np.where(cable, 0.0, target - l)


def _rest_lengths(s: Structure, rest_length, cable) -> np.ndarray:
    m = s.n_tendons
    if isinstance(rest_length, dict):
        r = np.array([rest_length.get(f, rest_length.get("default", 0.0)) if cable[j] else 0.0
                      for j, f in enumerate(s.families)], dtype=float)
    else:
        arr = np.asarray(rest_length, dtype=float)
        if arr.ndim == 0:
            r = np.full(m, float(arr))
        elif arr.shape == (m,):
            r = arr.copy()
        else:
            raise ValueError(f"rest_length must be a number, a {{family: value}} dict or have shape ({m},) (m), "
                             f"got shape {arr.shape}")
    bad = cable & ~(np.isfinite(r) & (r >= 0))
    if np.any(bad):
        j = int(np.flatnonzero(bad)[0])
        raise ValueError(f"rest_length of tendon {j} must be a finite number >= 0 (m), got {r[j]!r}")
    return np.where(cable, r, 0.0)


def _size(x: np.ndarray) -> float:
    return float(np.max(np.linalg.norm(x - x.mean(axis=0), axis=1)))


def _residual(A, T) -> float:
    amax = abs(A).max() if sp.issparse(A) else np.abs(A).max()
    return float(np.linalg.norm(A @ T) / max(amax * np.linalg.norm(T), 1e-300))


def _minimize(s, nodes, w, r, cable, it, max_iter, tol, mu, size0):
    """Damped Newton (Levenberg–Marquardt) on E, re-charting the strut directions every step."""
    collapse = 1e-9 * size0
    while True:
        coords = make_coordinates(dataclasses.replace(s, nodes=nodes), "local")
        q = coords.q0
        geom = member_geometry(coords, q)
        l = geom.lengths
        T = w * (l - r)
        A = equilibrium_matrix(geom)
        g = A @ T
        if np.max(np.abs(T)) <= 1e-9 * np.max(w) * size0:
            raise FormFindingError(
                f"{s.name}: no prestressable configuration found: every cable reached its rest length and the "
                "structure is left without tension (slack); use smaller rest lengths"
            )
        resid = _residual(A, T)
        if resid <= tol:
            return nodes, it, mu, resid
        if it >= max_iter:
            raise _not_converged(s, max_iter, resid, tol)
        dq, gn, mu, it = _lm_accepted(s, coords, geom, w, r, g, resid, mu, it, max_iter, tol)
        nodes = positions(coords, q + dq)
        lc = gn.lengths[cable]
        if np.min(lc) < collapse:
            j = int(np.flatnonzero(cable)[int(np.argmin(lc))])
            raise FormFindingError(
                f"{s.name}: no prestressable configuration found: tendon {j} ({s.families[j]}) shrank to zero "
                "length; with these force densities nothing (struts, supports) holds the cables apart"
            )
        if _size(nodes) < 1e-6 * size0:
            raise FormFindingError(f"{s.name}: no prestressable configuration found: the structure collapsed to a point")


def _lm_accepted(s, coords, geom, w, r, g, resid: float, mu: float, it: int, max_iter: int, tol: float):
    """One accepted Levenberg–Marquardt step from ``geom`` (damping ``mu`` raised until the energy decreases):
    ``(dq, geometry after it, next mu, steps taken)``. FormFindingError when the budget or the damping runs out."""
    H = tangent_stiffness(geom, w * (geom.lengths - r), w)
    E0 = _energy(geom.lengths, w, r)
    D = np.abs(H.diagonal())
    D = np.maximum(D, 1e-12 * max(D.max(), 1e-300))
    while True:
        it += 1
        dq = _lm_step(H, D, g, mu)
        pred = -(g @ dq + 0.5 * dq @ (H @ dq))
        gn = member_geometry(coords, coords.q0 + dq)
        En = _energy(gn.lengths, w, r)
        if pred <= 1e-13 * E0 and resid < 1e-6:
            # the energy change is lost in rounding near the minimum: judge the step by the residual
            ok = _residual(equilibrium_matrix(gn), w * (gn.lengths - r)) < resid
        else:
            rho = (E0 - En) / pred
            ok = rho > 1e-4 and np.isfinite(En)
            if ok:
                mu = mu / 3.0 if rho > 0.75 else (mu * 2.0 if rho < 0.25 else mu)
        if ok:
            return dq, gn, max(mu, 1e-12), it
        mu *= 4.0
        if it >= max_iter:
            raise _not_converged(s, max_iter, resid, tol)
        if mu > 1e12:
            raise FormFindingError(
                f"{s.name}: no prestressable configuration found: the energy stopped decreasing "
                f"(relative equilibrium residual {resid:.3g} after {it} steps)"
            )


def _not_converged(s, max_iter, resid, tol) -> FormFindingError:
    return FormFindingError(
        f"{s.name}: no prestressable configuration found: form-finding did not converge in {max_iter} "
        f"Newton steps (relative equilibrium residual {resid:.3g}, wanted {tol:g}); the topology may admit "
        "no self-stress with these force densities, or the initial shape is too far from one"
    )


def _lm_step(H, D, g, mu):
    if sp.issparse(H):
        M = (H + mu * sp.diags(D)).tocsc()
        try:
            return -spla.splu(M).solve(g)
        except RuntimeError:  # exactly singular: damp harder
            return -spla.splu((H + (mu * 10 + 1e-8) * sp.diags(D)).tocsc()).solve(g)
    M = H + mu * np.diag(D)
    try:
        return -scipy.linalg.solve(M, g, assume_a="sym")
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
        return -np.linalg.lstsq(M, g, rcond=None)[0]

"""Which references of the paper cell are valid, and how other references compare.

:func:`prestress_map` maps the appendix family q0(α, δ) (all tendons in
tension, K0 positive definite); :func:`references_study` compares the
spherical reference with the regular member (its IF-free self-stress), a
cylindrical reference found by form-finding and the cell without IFs.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import finite_scalar, positive_scalar
from .._results import dataframe, format_repr
from ..linear.assembly import voigt_stiffness
from ..linear.definite import is_positive_definite
from ..linear.linearize import NotPositiveDefiniteError, linearize
from ..model.coordinates import make_coordinates
from ..model.equilibrium import NotPrestressableError, equilibrium_matrix, member_geometry
from ..model.shapes import (DEFAULT_DELTA, cylindrical_cell, cylindrical_nodes, if_free_delta, paper_cell,
                            paper_nodes, paper_structure, regular_cell)
from ..model.shapes import TURN  # the node permutation of the cell's +120° turn, which cylindrical_nodes builds on
from ..model.structure import INTERMEDIATE_FILAMENT, Structure
from ..response import frequency_response
from ._common import grid

__all__ = ["ReferenceMap", "prestress_map", "ReferencesStudy", "references_study", "VALID", "NOT_PRESTRESSABLE",
           "NOT_STABLE", "find_cylindrical_reference", "if_free_point", "reference_responses", "join_maps"]


#: status codes of :func:`prestress_map`
VALID, NOT_PRESTRESSABLE, NOT_STABLE = 0, 1, 2


@dataclass(frozen=True, eq=False, repr=False)
class ReferenceMap:
    """Validity of the references q0(α, δ) of the paper cell (with IFs).

    Attributes
    ----------
    alpha, delta : ndarray, shape (na,), (nd,)
        Grid (rad).
    status : ndarray of int, shape (nd, na)
        :data:`VALID`, :data:`NOT_PRESTRESSABLE` (no equal-IF self-stress with
        every tendon in tension) or :data:`NOT_STABLE` (K0 not positive definite).
    min_tension : ndarray, shape (nd, na)
        Smallest normalized tendon tension of the equal-IF state (NaN where none).
    if_tension : ndarray, shape (nd, na)
        The common IF tension (normalized; NaN where none).
    P, EA : float
        Prestress (N) and uniform stiffness (N) of the stability check.
    """

    alpha: np.ndarray
    delta: np.ndarray
    status: np.ndarray
    min_tension: np.ndarray
    if_tension: np.ndarray
    P: float
    EA: float

    @property
    def fraction_valid(self) -> float:
        """Share of the grid that is a valid reference."""
        return float(np.mean(self.status == VALID))

    def delta_band(self, alpha: float = 0.0) -> tuple[float, float]:
        """Smallest and largest valid δ (rad) on the grid column nearest ``alpha`` (NaN if none)."""
        k = int(np.argmin(np.abs(self.alpha - alpha)))
        ok = self.delta[self.status[:, k] == VALID]
        return (float(ok.min()), float(ok.max())) if ok.size else (math.nan, math.nan)

    def __repr__(self) -> str:
        lo, hi = self.delta_band(0.0)
        return format_repr(
            f"ReferenceMap of {self.alpha.size} × {self.delta.size} references q0(α, δ)",
            f"{100 * self.fraction_valid:.1f}% valid (K0 checked at P = {self.P:g} N, EA = {self.EA:g} N)",
            f"at α = 0: valid δ = {math.degrees(lo):.4g}°…{math.degrees(hi):.4g}°",
        )

    def to_dataframe(self):
        """One row per grid point: α, δ (degrees), status, smallest and IF tension (normalized)."""
        A, D = np.meshgrid(self.alpha, self.delta)
        names = np.array(["valid", "not prestressable", "K0 not positive definite"])
        return dataframe({"alpha_deg": np.degrees(A).ravel(), "delta_deg": np.degrees(D).ravel(),
                          "status": names[self.status.ravel()], "min_tension_per_P": self.min_tension.ravel(),
                          "if_tension_per_P": self.if_tension.ravel()}, {"prestress_N": self.P, "EA_N": self.EA})

    def plot(self, ax=None, **kw):
        """The validity map over (α, δ) in degrees; returns the axes."""
        from .._results import plotter

        reference_map_figure = plotter("reference_map_figure")

        return reference_map_figure(self, ax=ax, **kw)


def prestress_map(
    alpha=np.radians(np.arange(-30.0, 60.1, 2.5)),
    delta=np.radians(np.arange(30.0, 70.1, 1.25)),
    *,
    P: float = 1000.0,
    EA: float = 1.0,
) -> ReferenceMap:
    """Map which references q0(α, δ) (with IFs) are valid: T0 > 0 and K0 positive definite.

    Parameters
    ----------
    alpha, delta : array_like
        Grid of the reference angles (rad); δ in (0, π/2).
    P, EA : float
        Prestress (N) and uniform tendon stiffness (N) of the K0 check
        (stability depends on them; T0 does not).
    """
    a = np.atleast_1d(np.asarray(alpha, dtype=float)).ravel()
    d = np.atleast_1d(np.asarray(delta, dtype=float)).ravel()
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(d))):
        raise ValueError("alpha and delta must be finite angles in radians")
    if np.any(d <= 0) or np.any(d >= math.pi / 2):
        raise ValueError("delta values must lie strictly between 0 and pi/2 rad")
    P, EA = positive_scalar("P (prestress)", P, "N"), positive_scalar("EA", EA, "N")
    status = np.zeros((d.size, a.size), dtype=int)
    tmin = np.full((d.size, a.size), np.nan)
    tif = np.full((d.size, a.size), np.nan)
    for i, dd in enumerate(d):
        for k, aa in enumerate(a):
            try:
                cell = paper_cell(alpha=float(aa), delta=float(dd))
            except NotPrestressableError:
                status[i, k] = NOT_PRESTRESSABLE
                continue
            tmin[i, k] = cell.T0.min()
            tif[i, k] = cell.T0[cell.structure.family_indices(INTERMEDIATE_FILAMENT)[0]]
            try:
                linearize(cell, P=P, EA=EA, c=1.0)
            except NotPositiveDefiniteError:
                status[i, k] = NOT_STABLE
    return ReferenceMap(alpha=a, delta=d, status=status, min_tension=tmin, if_tension=tif, P=P, EA=EA)


@dataclass(frozen=True, eq=False, repr=False)
class ReferencesStudy:
    """Several prestressable references compared.

    Attributes
    ----------
    map : ReferenceMap
    if_free_curve : ndarray, shape (k, 2)
        Points (α, δ*(α)) (rad) of the IF-free prestressable curve.
    cells : dict of str -> Cell
        In this order: the spherical default reference (its key names its
        α and δ), ``"regular member, IFs unprestressed"``, ``"cylindrical"``,
        ``"spherical, no IFs (regular member)"``.
    responses : dict of str -> FrequencyResponse
        Moduli of each cell at the study's prestresses and frequencies.
    EA, c : float
        Uniform tendon stiffness (N) and damping (N·s/m) of the responses.
    """

    map: ReferenceMap
    if_free_curve: np.ndarray
    cells: dict
    responses: dict
    EA: float
    c: float

    @property
    def roles(self) -> dict:
        """``{"spherical", "regular", "cylindrical", "no_ifs"}`` -> the key of that cell."""
        return dict(zip(("spherical", "regular", "cylindrical", "no_ifs"), self.cells))

    def __repr__(self) -> str:
        r = next(iter(self.responses.values()))
        return format_repr(
            f"ReferencesStudy: {len(self.cells)} references, {r.prestress.size} prestresses × {r.frequency_hz.size} "
            "frequencies",
            f"EA = {self.EA:g} N, c = {self.c:g} N·s/m",
            f"validity map: {100 * self.map.fraction_valid:.1f}% of {self.map.status.size} references valid",
        )

    def to_dataframe(self):
        """Moduli of every reference: one row per (reference, prestress, frequency)."""
        rows = [(name, *row) for name, r in self.responses.items() for row in r.rows()]
        cols = list(zip(*rows)) if rows else [()] * 5
        return dataframe({"reference": cols[0], "prestress_N": cols[1], "frequency_Hz": cols[2],
                          "G_storage_Pa": cols[3], "G_loss_Pa": cols[4]}, {"EA_N": self.EA, "c_Ns_per_m": self.c})

    def plot(self, ax=None, P: float | None = None, **kw):
        """G' and G'' of every reference against f at prestress ``P`` (default: the middle one), on a pair of axes."""
        from .._results import plotter

        references_figure = plotter("references_figure")

        first = next(iter(self.responses.values()))
        P = float(first.prestress[first.prestress.size // 2]) if P is None else float(P)
        return references_figure(self.responses, P, axes=ax, **kw)


#: the study's grids: prestresses (N) and frequencies (Hz) of the moduli, the validity map's α and δ (rad), the α
#: (rad) of the IF-free curve's points
PRESTRESS = (500.0, 1000.0, 4500.0)
FREQUENCY_HZ = np.logspace(-2, 3, 51)
MAP_ALPHA = np.radians(np.arange(-25.0, 35.1, 2.5))
MAP_DELTA = np.radians(np.arange(30.0, 65.1, 1.25))
CURVE_ALPHA = np.radians([-10.0, -5.0, 0.0, 5.0, 10.0, 15.0, 20.0])


def references_study(
    prestress=PRESTRESS,
    f_hz=FREQUENCY_HZ,
    *,
    EA: float = 1.0,
    c: float = 1.0,
    map_alpha=MAP_ALPHA,
    map_delta=MAP_DELTA,
    curve_alpha=CURVE_ALPHA,
) -> ReferencesStudy:
    """The valid-reference map and the moduli of the spherical, regular, cylindrical and IF-free cells."""
    Ps = grid("prestress", prestress, "N")
    mp = prestress_map(map_alpha, map_delta, P=float(Ps[len(Ps) // 2]), EA=EA)
    curve = [if_free_point(a) for a in np.atleast_1d(curve_alpha)]
    return _references(mp, curve, reference_responses(prestress, f_hz, EA, c), EA, c)


def if_free_point(alpha: float) -> tuple[float, float] | None:
    """``(α, δ*(α))`` (rad) of the IF-free prestressable curve, None where it has no point."""
    try:
        return float(alpha), if_free_delta(float(alpha))
    except NotPrestressableError:
        return None


def reference_responses(prestress=PRESTRESS, f_hz=FREQUENCY_HZ, EA: float = 1.0, c: float = 1.0) -> dict:
    """The spherical, regular, cylindrical and IF-free cells: ``{name: (cell, FrequencyResponse)}``."""
    Ps = grid("prestress", prestress, "N")
    f = grid("frequency", f_hz, "Hz")
    sph = paper_cell()
    cells = {
        f"spherical (α={math.degrees(sph.parameters['alpha']):g}°, δ={math.degrees(sph.parameters['delta']):g}°)": sph,
        "regular member, IFs unprestressed": regular_cell(),
        "cylindrical": cylindrical_cell(),
        "spherical, no IFs (regular member)": paper_cell(intermediate_filaments=False),
    }
    return {k: (v, frequency_response(v, f, Ps, EA=EA, c=c)) for k, v in cells.items()}


def _references(mp: ReferenceMap, curve, responses: dict, EA: float, c: float) -> ReferencesStudy:
    points = [p for p in curve if p is not None]
    return ReferencesStudy(map=mp, if_free_curve=np.array(points).reshape(-1, 2),
                           cells={k: cell for k, (cell, _) in responses.items()},
                           responses={k: r for k, (_, r) in responses.items()}, EA=float(EA), c=float(c))


def join_maps(maps) -> ReferenceMap:
    """One :class:`ReferenceMap` from maps of consecutive δ rows over the same α (and the same P and EA)."""
    maps = list(maps)
    first = maps[0]
    if any(not np.array_equal(m.alpha, first.alpha) or m.P != first.P or m.EA != first.EA for m in maps):
        raise ValueError("join_maps: the maps must share their alpha grid, P and EA")
    return ReferenceMap(alpha=first.alpha, delta=np.concatenate([m.delta for m in maps]),
                        status=np.vstack([m.status for m in maps]), min_tension=np.vstack([m.min_tension for m in maps]),
                        if_tension=np.vstack([m.if_tension for m in maps]), P=first.P, EA=first.EA)


# ---- the cylindrical reference: form-finding with the stability test of linear/ ----------------------------
def _turn_orbits(structure: Structure) -> np.ndarray:
    """Orbit number of each tendon under the +120° turn; the 12 IFs share one orbit (equal IF tension)."""
    key = {frozenset(t): j for j, t in enumerate(structure.tendons)}
    orbit = -np.ones(structure.n_tendons, dtype=int)
    n = 0
    for j in range(structure.n_tendons):
        if orbit[j] >= 0:
            continue
        k = j
        for _ in range(3):
            orbit[k] = n
            a, b = structure.tendons[k]
            k = key[frozenset((TURN[a], TURN[b]))]
        n += 1
    ifs = structure.family_indices(INTERMEDIATE_FILAMENT)
    orbit[ifs] = orbit[ifs].min()
    _, orbit = np.unique(orbit, return_inverse=True)
    return orbit


def _cylindrical_residual(base: Structure, orbit: np.ndarray):
    """``z -> (A(q)·T, ‖T‖ − 1)`` for z = (5 shape parameters, class tensions): equilibrium of the cylindrical cell."""

    def residual(z):
        try:
            nodes = cylindrical_nodes(z[:5], 1.0)
        except ValueError:
            return np.full(25, 1e3)
        st = Structure(nodes=nodes, struts=base.struts, tendons=base.tendons, families=base.families,
                       fixed=base.fixed, load=base.load, probe=base.probe)
        co = make_coordinates(st, "angles")
        A = equilibrium_matrix(member_geometry(co, co.q0), sparse=False)
        T = z[5:][orbit]
        return np.concatenate([A @ T, [np.linalg.norm(T) - 1.0]])

    return residual


def find_cylindrical_reference(
    start=None, *, min_tension: float = 0.02, stiffness_check=(1000.0, 1.0), n_starts: int = 10, seed: int = 0
) -> tuple[float, ...]:
    """Form-find a threefold-symmetric prestressable cell with every strut end on a cylinder.

    Unknowns: the 5 shape parameters of :func:`cylindrical_nodes` (L = 1)
    and the tensions of the 8 symmetry classes of tendons (7 actin orbits of
    the +120° turn and one common IF tension). Equations: equilibrium
    ``A(q)·T = 0`` (24 rows), ``‖T‖ = 1``, with every class tension ≥
    ``min_tension``: a bound-constrained nonlinear least-squares problem
    (``scipy.optimize.least_squares``), underdetermined, so it has a family
    of solutions; the first one reached from ``start`` whose K0 is positive
    definite is returned. If the solution reached from ``start`` is unstable,
    the search restarts from seeded random perturbations of it (σ = 0.3 in
    every parameter).

    Parameters
    ----------
    start : sequence of 5 floats, optional
        Default: the spherical reference (α = 0, δ = 50°) projected onto the
        cylinder (same azimuths and heights of C1, B1, D1, N).
    min_tension : float
        Lower bound of each normalized class tension (dimensionless).
    stiffness_check : (P, EA)
        The reference must have K0 = P·Kp + Σ EA a aᵀ/l positive definite at
        this prestress (N) and stiffness (N).
    n_starts : int
        Number of starts in all (the first is ``start`` itself).
    seed : int
        Seed of the random restarts.

    Returns
    -------
    tuple of 5 floats
        Parameters for :func:`cylindrical_cell`.

    Raises
    ------
    NotPrestressableError
        If no start leads to a stable, prestressable reference.
    """
    base = paper_structure(0.0, DEFAULT_DELTA, 1.0, intermediate_filaments=True)
    orbit = _turn_orbits(base)
    n_orb = int(orbit.max()) + 1
    if start is None:
        x = paper_nodes(0.0, DEFAULT_DELTA, 1.0)
        az = lambda v: math.atan2(v[1], v[0])  # noqa: E731
        start = (az(x[3]), az(x[6]), az(x[7]), x[6, 2], x[12, 2])
    p0 = np.array([finite_scalar("start", v) for v in start], dtype=float)
    if p0.shape != (5,):
        raise ValueError(f"start must have 5 entries (θ_C1, θ_B1, θ_D1, z_B1/L, z_N/L), got {p0.size}")
    P, EA = stiffness_check
    residual = _cylindrical_residual(base, orbit)

    from scipy.optimize import least_squares  # here, not at import: only this search needs it

    lb = np.concatenate([np.full(5, -np.inf), np.full(n_orb, min_tension)])
    rng = np.random.default_rng(seed)
    reasons = []
    for k in range(max(int(n_starts), 1)):
        p = p0 if k == 0 else p0 + 0.3 * rng.standard_normal(5)
        z0 = np.concatenate([p, np.full(n_orb, 1.0 / math.sqrt(base.n_tendons))])
        res = least_squares(residual, z0, bounds=(lb, np.inf), xtol=1e-15, ftol=1e-15, gtol=1e-15)
        eq = float(np.linalg.norm(residual(res.x)))
        if eq > 1e-12:
            reasons.append(f"start {k}: no equilibrium (residual {eq:.2g})")
            continue
        params = tuple(float(v) for v in res.x[:5])
        try:
            cell = cylindrical_cell(params)
        except ValueError as err:
            reasons.append(f"start {k}: {type(err).__name__}")
            continue
        if is_positive_definite(voigt_stiffness(cell, P, np.full(cell.m, float(EA)))):  # the one criterion
            return params
        reasons.append(f"start {k}: unstable (K0 = P·Kp + Σ EA a aᵀ/l is not positive definite)")
    raise NotPrestressableError("no stable cylindrical reference found: " + "; ".join(reasons))


# ---- the study protocol (tenscell study references) ------------------------------------------------------------
#: the map's δ rows are computed in this many blocks (tasks that may run in parallel)
MAP_BLOCKS = 4
#: the work of one point of the IF-free curve (a root of det A in δ: about 170 determinants) and of the four
#: cells' moduli (the IF-free cell's reference is such a root), in units of one point of the validity map (:func:`reference_probe`), as
#: measured (bench/calibrate_study_units.py)
ROOT_UNITS = 95.0
RESPONSES_UNITS = 100.0


def _map_block(alpha, delta, P: float) -> ReferenceMap:
    return prestress_map(alpha, delta, P=P)


class _References:
    """``tenscell study references``: the validity map in blocks of δ rows, each point of the IF-free curve, the four
    cells' moduli; all independent tasks."""

    name = "references"
    options: dict = {}

    def plan(self, options):
        from .._parallel import usable_cpus
        from .protocol import Plan, Task, study_options

        P = float(PRESTRESS[len(PRESTRESS) // 2])
        blocks = np.array_split(np.arange(MAP_DELTA.size), MAP_BLOCKS)
        tasks = [Task(f"validity map, δ rows {b[0] + 1}-{b[-1] + 1} of {MAP_DELTA.size}", "reference point",
                      _map_block, (MAP_ALPHA, MAP_DELTA[b], P), weight=float(b.size * MAP_ALPHA.size)) for b in blocks]
        tasks += [Task(f"IF-free curve at α = {math.degrees(a):g}°", "reference point", if_free_point, (float(a),),
                       weight=ROOT_UNITS) for a in CURVE_ALPHA]
        tasks.append(Task("moduli of the four references", "reference point", reference_responses,
                          weight=RESPONSES_UNITS))
        return Plan(self.name, study_options(self, options), tuple(tasks),
                    calibration=(REFERENCE_PROBE,), figures=6.3, jobs=min(usable_cpus(), len(tasks)))

    def assemble(self, plan, results):
        from .._results import reporter
        from .protocol import Figure, StudyResult, Table

        mp = join_maps([results[t.key] for t in plan.tasks[:MAP_BLOCKS]])
        curve = [results[t.key] for t in plan.tasks[MAP_BLOCKS:-1]]
        s = _references(mp, curve, results[plan.tasks[-1].key], 1.0, 1.0)
        status = ("valid", "not prestressable", "K0 not positive definite")
        ref_map = Table.from_records("reference_map", [
            {"alpha_deg": math.degrees(a), "delta_deg": math.degrees(d), "status": status[mp.status[i, k]],
             "min_tension": float(mp.min_tension[i, k]), "if_tension": float(mp.if_tension[i, k])}
            for i, d in enumerate(mp.delta) for k, a in enumerate(mp.alpha)])
        moduli = Table.from_records("references_moduli", [
            {"reference": name, "prestress": P, "frequency_Hz": f, "G_storage": a, "G_loss": b}
            for name, r in s.responses.items() for P, f, a, b in r.rows()])
        first = next(iter(s.responses.values()))
        P = float(first.prestress[len(first.prestress) // 2])
        return StudyResult(self.name, tables=(ref_map, moduli),
                           figures=(Figure("reference_map.png", "reference_map_figure", (mp, s.if_free_curve)),
                                    Figure("references.png", "references_figure", (s.responses, P))),
                           pages=(("references.md", reporter("references_markdown")(s)),), data=s)


#: the study of ``tenscell study references`` (:mod:`tenscell.studies.protocol`)
STUDY = _References()


def reference_probe():
    """Four points of the references' validity map (:func:`prestress_map`): the paper
    cell built at four references q0(α, δ) and linearized. One point is the unit of work of the studies that build
    reference cells (a study's estimate, :mod:`tenscell.studies.protocol`)."""
    return prestress_map(MAP_ALPHA[10:12], MAP_DELTA[10:12], P=PRESTRESS[1])


def _probe_task():
    from .protocol import Task

    return Task("four reference cells", "reference point", reference_probe, weight=4.0)


#: the calibration probe of one unit "reference point" (4 units)
REFERENCE_PROBE = _probe_task()

"""A power law the structure makes? Networks of plain members only (issue 34).

Every member here is a Voigt (or Maxwell) element with one EA and one c per family, or a c that follows from the
member's own length or force (:func:`tenscell.model.networks.damping_by_length`,
:func:`~tenscell.model.networks.damping_by_tension`): no springpot, no distribution put in by hand. The study
computes G'(f), G''(f) from 10⁻³ to 10⁴ Hz (and a decade beyond each end, for the fits) at several prestresses for
three families of structures (:mod:`tenscell.model.networks`):

* ``diluted`` — diluted prestressed cable networks near their rigidity threshold (knob: the connectivity z, 6 is
  isostatic; size);
* ``hierarchical`` — self-similar nets of modules made of modules, pulled out of their plane, damped by tethers
  (knobs: the module's node count, which sets the self-similarity, and the depth);
* ``structural`` — member time constants set by the structure: the tensegrity lattice and a diluted network whose
  members' damping follows their length (``c ∝ l^k``) or their force (Bell's law).

and maps the local exponent α(f) = d ln G'/d ln f over frequency × prestress × the family's knobs, with the loss
tangent against tan(απ/2) (:mod:`tenscell.studies.powerlaw_metrics`). It follows the study protocol
(:mod:`tenscell.studies.protocol`): :func:`plan` → one task per structure (every prestress of it) and one fit task
per family, :func:`assemble` → tables, figures, the Markdown page and the checks of goal G6.

Scales. Cables have EA = 1 N and the damping that gives a cable of the mean length the time constant
1/(2π·1 Hz) (:data:`MEMBER_HZ`); the lattice's struts EA = 10³ N; the simplex nets' tethers EA = 10⁻⁹ N (a
dashpot) and the damping that puts a free node's out-of-plane rate at :data:`NODE_HZ` at the middle prestrain.
The prestress is given as the mean cable prestrain ε = P·mean(T0)/EA. Both scales only place the curves: the
Voigt structures are exactly invariant under (EA, c, P) → (λEA, μc, λP) with f → f/μ and G → λG, which is
also what the fits to measured data move (:func:`scaled_fit`).
"""
from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Mapping

import numpy as np

from ..model.equilibrium import Cell
from ..model.lattices import LATTICE_STRUT_EA, lattice_cell
from ..model.networks import (TETHER, DilutedNet, SimplexNet, damping_by_length, damping_by_tension, diluted_net,
                              simplex_net)
from ..model.structure import STRUT, cable_mask
from .powerlaw_metrics import (ALPHA_BAND, TAN_TOLERANCE, TOLERANCE, Stretch, flat_stretch,
                               local_exponent, prestress_trend)
from .protocol import Check, Figure, Plan, StudyResult, Table, Task

__all__ = ["MapPoint", "PointResult", "PowerLawStudy", "ScaledFit", "plan", "assemble", "evaluate_point",
           "map_points", "build_cell", "member_properties", "scaled_fit", "STUDY", "NAME", "SCALES",
           "PRESTRAINS", "MAP_BAND_HZ", "G6_BAND_HZ", "MEMBER_HZ", "NODE_HZ", "frequencies"]

NAME = "powerlaw"
#: what each scale of the study computes (``tiny``: the tests' map, seconds)
SCALES = ("full", "quick", "tiny")
#: mean cable prestrains ε = P·mean(T0)/EA of the map
PRESTRAINS = (0.01, 0.03, 0.1, 0.3)
#: the band the map reports (Hz)
MAP_BAND_HZ = (1e-3, 1e4)
#: the band goal G6 needs the power law over (Hz)
G6_BAND_HZ = (1e-2, 10.0)
#: the band computed: the map's and a decade beyond each end, room for the fits' time scale (Hz)
COMPUTED_BAND_HZ = (1e-4, 1e5)
#: frequencies per decade
PER_DECADE = 8
#: a cable of the mean length relaxes at this frequency (Hz): c = EA/(2π·MEMBER_HZ·l̄)
MEMBER_HZ = 1.0
#: a simplex net's free node, out of the plane, relaxes at this frequency at the middle prestrain (Hz)
NODE_HZ = 100.0
#: the prestrain at which NODE_HZ holds and the tension rule's force scale is taken
REFERENCE_PRESTRAIN = 0.1
#: axial stiffness of cables (N) and of the simplex nets' tethers (N)
CABLE_EA, TETHER_EA = 1.0, 1e-9
FAMILIES = ("diluted", "hierarchical", "structural")
LAWS = ("voigt", "maxwell")
DAMPINGS = ("uniform", "length", "tension")
STRUCTURES = ("diluted net", "simplex net", "lattice")


def frequencies(band=COMPUTED_BAND_HZ, per_decade: int = PER_DECADE) -> np.ndarray:
    """The study's frequency grid (Hz): ``per_decade`` points per decade over ``band``, ends included."""
    lo, hi = (math.log10(b) for b in band)
    return np.logspace(lo, hi, int(round((hi - lo) * per_decade)) + 1)


# ---- the map's points ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MapPoint:
    """One structure of the map with its member laws.

    Attributes
    ----------
    family : str
        ``"diluted"``, ``"hierarchical"`` or ``"structural"``.
    structure : str
        ``"diluted net"`` (knobs ``size``, ``connectivity``, ``seed``), ``"simplex net"`` (``module_nodes``,
        ``depth``) or ``"lattice"`` (``modules`` per side).
    knobs : tuple of (str, number)
        The structure's knobs.
    law : str
        ``"voigt"`` or ``"maxwell"`` (every cable; the lattice's struts stay Voigt springs).
    damping : str
        ``"uniform"``: one c per family; ``"length"``: ``c ∝ l^k`` with ``k = damping_value``; ``"tension"``:
        Bell's law with the force scale ``damping_value`` × the mean cable force at the reference prestrain.
    damping_value : float
    """

    family: str
    structure: str
    knobs: tuple
    law: str = "voigt"
    damping: str = "uniform"
    damping_value: float = 0.0

    def __post_init__(self):
        for name, value, allowed in (("family", self.family, FAMILIES), ("structure", self.structure, STRUCTURES),
                                     ("law", self.law, LAWS), ("damping", self.damping, DAMPINGS)):
            if value not in allowed:
                raise ValueError(f"MapPoint: {name} must be one of {', '.join(allowed)}, got {value!r}")
        object.__setattr__(self, "knobs", tuple((str(k), v) for k, v in self.knobs))
        if self.law == "maxwell" and self.structure == "lattice":
            raise ValueError("MapPoint: Maxwell members leave the lattice without a static state (its prestress "
                             "stiffness is singular); use them on the nets")

    def knob(self, name: str, default=None):
        return dict(self.knobs).get(name, default)

    @property
    def key(self) -> str:
        """The point's task key: its family and label."""
        return f"{self.family}/{self.label}"

    @property
    def label(self) -> str:
        """A unique name: the structure, its knobs, its law and damping rule."""
        ks = ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in self.knobs)
        tail = "" if self.law == "voigt" else f" {self.law}"
        if self.damping != "uniform":
            tail += f" c~{self.damping}" + (f"^{self.damping_value:g}" if self.damping == "length"
                                             else f"(F={self.damping_value:g}T)")
        return f"{self.structure} ({ks}){tail}"


def build_cell(point: MapPoint) -> Cell:
    """The prestressable cell of ``point`` (a pure function of its structure and knobs)."""
    k = dict(point.knobs)
    if point.structure == "diluted net":
        return diluted_net(DilutedNet(size=int(k["size"]), connectivity=float(k["connectivity"]),
                                      seed=int(k.get("seed", 0))))
    if point.structure == "simplex net":
        return simplex_net(SimplexNet(module_nodes=int(k["module_nodes"]), depth=int(k["depth"])))
    n = int(k["modules"])
    return lattice_cell(n, n, n)


def _net_cables(cell: Cell) -> np.ndarray:
    """The cables of the network proper (not tethers, not struts)."""
    fam = np.array(cell.structure.families)
    return cable_mask(cell.structure.families) & (fam != TETHER)


def prestress_of(cell: Cell, prestrain: float) -> float:
    """P (N) at which the network's cables carry the mean prestrain ``prestrain`` = P·mean(T0)/EA."""
    return float(prestrain) * CABLE_EA / float(np.mean(cell.T0[_net_cables(cell)]))


def member_properties(point: MapPoint, cell: Cell, P: float) -> tuple[np.ndarray, np.ndarray]:
    """(EA, c) of every member of ``cell`` (N, N·s/m) for ``point``'s laws at prestress ``P`` (N)."""
    fam = np.array(cell.structure.families)
    net = _net_cables(cell)
    c_mean = CABLE_EA / (2 * math.pi * MEMBER_HZ * float(np.mean(cell.lengths[net])))
    EA = np.where(fam == STRUT, LATTICE_STRUT_EA, np.where(fam == TETHER, TETHER_EA, CABLE_EA))
    if point.damping == "length":
        c = damping_by_length(cell, c_mean, point.damping_value)
    elif point.damping == "tension":
        T_ref = prestress_of(cell, REFERENCE_PRESTRAIN) * float(np.mean(cell.T0[net]))
        c = damping_by_tension(cell, c_mean, P, point.damping_value * T_ref)
    else:
        c = np.full(cell.m, c_mean)
    if np.any(fam == TETHER):
        # the out-of-plane stiffness of a free node is P·q·(its cables) (q = T0/l, one value on a form-found net);
        # its two tethers damp it: rate P_ref·q·d/(2·c_t) = 2π·NODE_HZ
        q = float(np.mean(cell.T0[net] / cell.lengths[net]))
        degree = 2 * (int(point.knob("module_nodes")) - 1)
        P_ref = prestress_of(cell, REFERENCE_PRESTRAIN)
        c = np.where(fam == TETHER, P_ref * q * degree / (2 * 2 * math.pi * NODE_HZ), c)
    return EA, c


@dataclass(frozen=True, eq=False)
class PointResult:
    """The moduli of one structure of the map at every prestrain.

    Attributes
    ----------
    point : MapPoint
    coordinates, members : int
        The cell's generalized coordinates and members.
    prestrain : ndarray, shape (nP,)
        Mean cable prestrain ε (dimensionless).
    prestress : ndarray, shape (nP,)
        P (N).
    frequency_hz : ndarray, shape (nf,)
    G_storage, G_loss : ndarray, shape (nP, nf)
        G', G'' (Pa).
    build_cpu_s : float
        CPU seconds to build and equilibrate the cell.
    spectrum_cpu_s : ndarray, shape (nP,)
        CPU seconds of each prestress's linearization and moduli.
    connectivity : float
        2·(members)/(free nodes) of the cell (dimensionless).
    """

    point: MapPoint
    coordinates: int
    members: int
    prestrain: np.ndarray
    prestress: np.ndarray
    frequency_hz: np.ndarray
    G_storage: np.ndarray
    G_loss: np.ndarray
    build_cpu_s: float
    spectrum_cpu_s: np.ndarray
    connectivity: float

    @property
    def alpha(self) -> np.ndarray:
        """Local exponent d ln G'/d ln f, shape (nP, nf)."""
        return local_exponent(self.frequency_hz, self.G_storage)

    @property
    def tan_delta(self) -> np.ndarray:
        """Loss tangent G''/G', shape (nP, nf)."""
        return self.G_loss / self.G_storage


#: decades of frequency one Lanczos run (one shift) serves: a run over the whole band needs hundreds of steps on a
#: network near its rigidity threshold (its relaxation spectrum spans as many decades), a run per two decades
#: a few dozen each (a 5,061-coordinate isostatic net: 714 steps and 32 s against 135 steps and 0.6 s, both
#: converged to 1e-12)
DECADES_PER_SHIFT = 2.0


def sparse_compliance(lin, f_hz) -> np.ndarray:
    """J(f) (m/N) of a linear model, on the sparse path one shifted Lanczos run per :data:`DECADES_PER_SHIFT`
    decades of frequency (each converged to the library's 1e-12); dense models through their modal sum."""
    from ..linear.krylov import krylov_compliance
    from ..response import compliance

    f = np.asarray(f_hz, dtype=float)
    if not lin.pencil.sparse:
        return compliance(lin, f)
    J = np.empty(f.size, dtype=complex)
    group = np.floor((np.log10(f) - math.log10(f[0])) / DECADES_PER_SHIFT + 1e-9).astype(int)
    for g in np.unique(group):
        sel = group == g
        J[sel] = krylov_compliance(lin, f[sel]).J
    return J


def point_model(point: MapPoint, cell: Cell, P: float):
    """The linear model of ``point``'s cell at prestress ``P`` (N): Voigt members linearized, Maxwell members
    realized exactly (one internal variable per member, :func:`tenscell.linear.linearize.linearize_law`)."""
    from ..linear.linearize import linearize, linearize_law

    EA, c = member_properties(point, cell, P)
    if point.law == "maxwell":
        from ..laws import Maxwell

        return linearize_law(cell, Maxwell(EA=EA, c=c), P)
    return linearize(cell, P=P, EA=EA, c=c)


def _moduli(point: MapPoint, cell: Cell, P: float, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    from ..linear.assembly import modulus

    lin = point_model(point, cell, P)
    G = modulus(sparse_compliance(lin, f), lin.L)
    return G.real, G.imag


def evaluate_point(point: MapPoint, prestrains, f_hz) -> PointResult:
    """Build ``point``'s cell and compute G', G'' at every prestrain and frequency (a task of the plan)."""
    from ..model.networks import free_connectivity

    f = np.asarray(f_hz, dtype=float)
    t0 = time.process_time()
    cell = build_cell(point)
    build = time.process_time() - t0
    eps = np.asarray(prestrains, dtype=float)
    P = np.array([prestress_of(cell, e) for e in eps])
    Gs, Gl, cpu = [], [], []
    for p in P:
        t0 = time.process_time()
        a, b = _moduli(point, cell, float(p), f)
        cpu.append(time.process_time() - t0)
        Gs.append(a)
        Gl.append(b)
    return PointResult(point=point, coordinates=int(cell.n), members=int(cell.m), prestrain=eps, prestress=P,
                       frequency_hz=f, G_storage=np.array(Gs), G_loss=np.array(Gl), build_cpu_s=build,
                       spectrum_cpu_s=np.array(cpu), connectivity=float(free_connectivity(cell.structure)))


# ---- the plan --------------------------------------------------------------------------------------------
def _diluted(size, z, seed=0, **kw) -> MapPoint:
    return MapPoint("diluted", "diluted net", (("size", size), ("connectivity", float(z)), ("seed", seed)), **kw)


def _simplex(k, depth) -> MapPoint:
    return MapPoint("hierarchical", "simplex net", (("module_nodes", k), ("depth", depth)))


def _structural(structure_knobs, damping, value) -> MapPoint:
    structure, knobs = structure_knobs
    return MapPoint("structural", structure, knobs, damping=damping, damping_value=float(value))


@dataclass(frozen=True)
class _Grid:
    """What one scale of the map computes."""

    size: int  # the diluted nets' size
    z: tuple  # their connectivities
    sizes: tuple  # other sizes, for the size series ...
    size_z: tuple  # ... at these connectivities
    seeds: tuple  # other realizations of the main size ...
    seed_z: tuple  # ... at these connectivities
    maxwell_size: int  # Maxwell nets: size ...
    maxwell_z: tuple  # ... and connectivities
    simplex: tuple  # (module nodes, depths) pairs
    lattice: int  # the structural family's lattice (modules per side) ...
    net: int  # ... and diluted net (size)


_GRID = {
    "full": _Grid(size=10, z=(4.0, 4.5, 5.0, 5.5, 6.0, 6.5, 7.0, 8.0, 10.0, 12.0), sizes=(4, 6, 8, 12),
                  size_z=(5.0, 6.0), seeds=(1, 2), seed_z=(5.5, 6.0), maxwell_size=8, maxwell_z=(4.5, 5.0, 6.0, 8.0),
                  simplex=((3, range(2, 9)), (4, range(2, 8)), (5, range(2, 6)), (6, range(2, 5))), lattice=8, net=10),
    "quick": _Grid(size=6, z=(4.5, 5.0, 6.0, 8.0, 12.0), sizes=(4, 8), size_z=(6.0,), seeds=(1,), seed_z=(6.0,),
                   maxwell_size=6,
                   maxwell_z=(5.0, 6.0), simplex=((3, range(2, 7)), (4, range(2, 6)), (5, range(2, 5))), lattice=5,
                   net=6),
    "tiny": _Grid(size=3, z=(5.0, 8.0), sizes=(), size_z=(), seeds=(), seed_z=(), maxwell_size=3, maxwell_z=(6.0,),
                  simplex=((3, range(2, 4)), (4, range(2, 3))), lattice=2, net=3),
}
#: the structural family's damping rules: (rule, value) — c ∝ l^k, Bell's law with F = value × the mean cable force
_RULES = (("uniform", 0.0), ("length", 1.0), ("length", 2.0), ("length", 4.0), ("tension", 0.3), ("tension", 1.0))


def map_points(scale: str = "full") -> tuple[MapPoint, ...]:
    """Every structure of the map at ``scale`` (``"full"``, ``"quick"`` or ``"tiny"``), family by family."""
    if scale not in _GRID:
        raise ValueError(f"scale must be one of {', '.join(SCALES)}, got {scale!r}")
    g = _GRID[scale]
    pts = [_diluted(g.size, z) for z in g.z]
    pts += [_diluted(n, z) for z in g.size_z for n in g.sizes if n != g.size]
    pts += [_diluted(g.size, z, seed=k) for z in g.seed_z for k in g.seeds]
    pts += [_diluted(g.maxwell_size, z, law="maxwell") for z in g.maxwell_z]
    pts += [_simplex(k, d) for k, depths in g.simplex for d in depths]
    structures = (("lattice", (("modules", g.lattice),)),
                  ("diluted net", (("size", g.net), ("connectivity", ISOSTATIC), ("seed", 0))))
    pts += [_structural(s, rule, v) for s in structures for rule, v in _RULES]
    return tuple(pts)


ISOSTATIC = 6.0


def _weight(point: MapPoint) -> float:
    """A point's cost in units of a 10⁴-coordinate structure's spectrum at one prestress (its kind's rate)."""
    k = dict(point.knobs)
    if point.structure == "diluted net":
        coords = 12.0 * (int(k["size"]) - 1) ** 3  # about 4 sites per cell, three coordinates each
    elif point.structure == "simplex net":
        coords = 1.5 * int(k["module_nodes"]) ** int(k["depth"]) * 3
    else:
        coords = 22.0 * int(k["modules"]) ** 3
    return max(coords / 1e4, 0.01) * len(PRESTRAINS)


#: CPU seconds per unit of weight (a 10⁴-coordinate structure's spectrum at one prestrain) as the plan's probes
#: measured them at load 1 on 2 cores (spectrum 1.18, Maxwell 1.08, fit 0.49: the full map estimated at 265 s of CPU,
#: measured 283 s): what a run's estimate starts from is its own probes; these are for reading a plan without them
CALIBRATION = {"spectrum": 1.2, "spectrum-maxwell": 1.1, "fit": 0.5}


def plan(options: Mapping[str, Any] | None = None) -> Plan:
    """The checked options (``scale``: ``"full"``, ``"quick"`` or ``"tiny"``) and the tasks: one per structure
    (all its prestrains) and one fit per family (after that family's structures)."""
    opts = dict(options or {})
    unknown = sorted(set(opts) - {"scale"})
    if unknown:
        raise ValueError(f"study {NAME}: unknown option {unknown[0]!r} (options: scale)")
    scale = opts.setdefault("scale", "full")
    points = map_points(scale)
    f = frequencies()
    tasks = [Task(key=p.key, kind="spectrum" if p.law == "voigt" else "spectrum-maxwell", fn=evaluate_point,
                  args=(p, PRESTRAINS, f), weight=_weight(p)) for p in points]
    for fam in FAMILIES:
        members = [p for p in points if p.family == fam]
        if members:
            tasks.append(Task(key=f"fit/{fam}", kind="fit", fn=fit_family, args=(fam,),
                              needs=tuple(p.key for p in members), weight=_fit_weight(members)))
    return Plan(study=NAME, options=opts, tasks=tuple(tasks), calibration=_probes(f), figures=float(len(FIGURES)),
                sized_by=("--scale",))


def _fit_weight(points) -> float:
    """A family fit's cost in units of a 10⁴-coordinate structure's spectrum at one prestrain: the family's largest
    structure (its best one is usually among the largest) at each of :data:`FIT_PRESTRAINS`."""
    return max(_weight(p) for p in points) / len(PRESTRAINS) * len(FIT_PRESTRAINS)


#: the calibration probes' structures: a diluted net of Voigt cables, one of Maxwell cables, a small hierarchical
#: net whose map point and fit are computed (a second or so each)
_PROBE_POINTS = {"spectrum": _diluted(8, ISOSTATIC), "spectrum-maxwell": _diluted(6, ISOSTATIC, law="maxwell"),
                 "fit": _simplex(4, 5)}


def _fit_probe(point: MapPoint, f_hz) -> FamilyFit:
    """One unit of the fit kind's work (calibration): a small structure's map point, then its family fit."""
    return fit_family(point.family, evaluate_point(point, PRESTRAINS, f_hz))


def _probes(f_hz) -> tuple:
    """The plan's calibration probes, one per kind of task, each weighted as the plan weighs its tasks."""
    spectrum, maxwell, small = (_PROBE_POINTS[k] for k in ("spectrum", "spectrum-maxwell", "fit"))
    return (Task("a diluted net's spectrum", "spectrum", evaluate_point, (spectrum, PRESTRAINS, f_hz),
                 weight=_weight(spectrum)),
            Task("a Maxwell net's spectrum", "spectrum-maxwell", evaluate_point, (maxwell, PRESTRAINS, f_hz),
                 weight=_weight(maxwell)),
            # the probe computes the point's four prestrains too: its weight counts them beside the fit's nine
            Task("a small net's map point and fit", "fit", _fit_probe, (small, f_hz),
                 weight=_fit_weight([small]) + _weight(small)))


# ---- what each curve says --------------------------------------------------------------------------------
def _in_map(f: np.ndarray) -> np.ndarray:
    return (f >= MAP_BAND_HZ[0] * (1 - 1e-9)) & (f <= MAP_BAND_HZ[1] * (1 + 1e-9))


@dataclass(frozen=True)
class Assessment:
    """What one curve (a structure at one prestrain) says over the map's band.

    Attributes
    ----------
    power_law : Stretch
        The longest stretch with α ≥ 0.05 within ±0.05 (any weak or strong power law).
    band : Stretch
        The longest stretch with α in 0.1–0.3 within ±0.05.
    g6 : Stretch
        The longest stretch of ``band`` whose loss tangent is also within 20 % of tan(ᾱπ/2).
    """

    power_law: Stretch
    band: Stretch
    g6: Stretch


def assess(f_hz, G_storage, G_loss) -> Assessment:
    """The three stretches of one curve over the map's band (:mod:`.powerlaw_metrics`)."""
    f = np.asarray(f_hz, dtype=float)
    alpha = local_exponent(f, G_storage)
    tan = np.asarray(G_loss) / np.asarray(G_storage)
    m = _in_map(f)
    f, alpha, tan = f[m], alpha[m], tan[m]
    return Assessment(power_law=flat_stretch(f, alpha, tan, band=(0.05, 2.0)),
                      band=flat_stretch(f, alpha, tan, band=ALPHA_BAND),
                      g6=flat_stretch(f, alpha, tan, band=ALPHA_BAND, tan_tolerance=TAN_TOLERANCE))


def _score(a: Assessment) -> tuple[float, float]:
    return (a.g6.decades, a.band.decades)


def best_prestrain(result: PointResult, marks: list[Assessment] | None = None) -> tuple[int, Assessment]:
    """The prestrain index whose curve has the longest G6 stretch (then the longest 0.1–0.3 stretch); ``marks``:
    the curves' assessments if already computed."""
    if marks is None:
        marks = [assess(result.frequency_hz, result.G_storage[i], result.G_loss[i])
                 for i in range(result.prestrain.size)]
    i = max(range(len(marks)), key=lambda k: _score(marks[k]))
    return i, marks[i]


def best_point(results, marks: Mapping[str, list[Assessment]] | None = None) -> PointResult:
    """The structure whose best prestrain comes closest to G6 (longest G6 stretch, then longest 0.1–0.3 stretch);
    ``marks``: assessments by point key, if already computed."""
    return max(results, key=lambda r: _score(best_prestrain(r, None if marks is None else marks[r.point.key])[1]))


def trend(result: PointResult) -> dict[str, float]:
    """dα/d ln P at 0.01, 0.1, 1 and 10 Hz, and averaged over the frequencies where α lies in 0.1–0.3 at every
    prestrain (NaN where there are none); Δα from the lowest to the highest prestrain at 0.1 Hz."""
    f = result.frequency_hz
    alpha = result.alpha
    slope = prestress_trend(result.prestress, alpha)
    out = {}
    for name, f0 in (("0p01Hz", 0.01), ("0p1Hz", 0.1), ("1Hz", 1.0), ("10Hz", 10.0)):
        out[f"dalpha_dlnP_{name}"] = float(np.interp(math.log(f0), np.log(f), slope))
    common = _in_map(f) & np.all((alpha >= ALPHA_BAND[0]) & (alpha <= ALPHA_BAND[1]), axis=0)
    out["dalpha_dlnP_common_band"] = float(slope[common].mean()) if common.any() else math.nan
    out["common_band_decades"] = float(math.log10(f[common].max() / f[common].min())) if common.sum() > 1 else 0.0
    a01 = [float(np.interp(math.log(0.1), np.log(f), a)) for a in alpha]
    out["delta_alpha_0p1Hz"] = a01[-1] - a01[0]
    return out


# ---- fits of a family's best structure to the bundled data, under its exact scalings ----------------------
#: prestrains of the fit's grid: the map's range, finer (its four are too coarse to interpolate between)
FIT_PRESTRAINS = tuple(float(x) for x in np.logspace(-2.0, math.log10(0.3), 9))
#: the bundled data sets the fits use: the Fabry frequency sweep and the Stamenović prestress series at 0.1 Hz
FIT_DATA = ("fabry2001", "stamenovic2002")


@dataclass(frozen=True)
class ScaledFit:
    """A structure fitted to bundled data through its exact scalings: stiffness ×λ (EA, c, P together), time ×μ
    (c alone), the Fabry cells' prestrain and, for the prestress series, the prestrain per pascal.

    Attributes
    ----------
    data : tuple of str
        The data sets fitted jointly.
    rms_log10 : tuple of float
        RMS of the log10 errors of G' and G'' of each data set (decades).
    stiffness_scale, time_scale : float
        λ and μ (dimensionless): G = λ·G_structure(f·μ).
    prestrain : float
        ε of the frequency sweep (NaN if none).
    prestrain_per_Pa : float
        ε per pascal of the prestress series (1/Pa; NaN if none).
    success : bool
        Whether the least-squares search converged.
    curves : tuple of FitCurve
        Each data set beside the fitted structure.
    at_bound : bool
        Whether a scale ended on the edge of what the computed grid allows (the frequency band, the prestrain
        range): the fit then wants a wider grid than the map computed.
    """

    data: tuple
    rms_log10: tuple
    stiffness_scale: float
    time_scale: float
    prestrain: float
    prestrain_per_Pa: float
    success: bool
    curves: tuple = ()
    at_bound: bool = False


@dataclass(frozen=True, eq=False)
class FitCurve:
    """One data set beside the fitted structure: ``x`` its frequencies (Hz) or prestresses (Pa), the measured and
    the fitted G', G'' (Pa)."""

    name: str
    x: np.ndarray
    is_prestress: bool
    G_storage: np.ndarray
    G_loss: np.ndarray
    model_storage: np.ndarray
    model_loss: np.ndarray


@dataclass(frozen=True, eq=False)
class FamilyFit:
    """A family's best structure on a fine prestrain grid and its fits to the bundled data."""

    family: str
    point: MapPoint
    prestrain: np.ndarray
    frequency_hz: np.ndarray
    G: np.ndarray  # (n_prestrain, nf) complex, Pa
    fits: tuple
    cpu_s: float


def _surface(f, eps, G):
    from scipy.interpolate import RegularGridInterpolator

    grid = (np.log(eps), np.log(f))
    return (RegularGridInterpolator(grid, np.log(G.real), method="cubic"),
            RegularGridInterpolator(grid, np.log(G.imag), method="cubic"))


def scaled_fit(f_hz, prestrains, G, datasets: Mapping[str, Any]) -> ScaledFit:
    """Fit G(f, ε) (complex, shape (nε, nf), Pa) to ``datasets`` (name → :class:`tenscell.io.rheology.RheologyData`:
    at most one frequency sweep and one prestress series) under the exact scalings of the structure (class docstring of :class:`ScaledFit`): ln λ, ln μ, and ln ε of a
    frequency sweep or ln(ε per Pa) of a prestress series; log10 residuals of G' and G''."""
    from scipy.optimize import least_squares

    names, sets = tuple(datasets), tuple(datasets.values())
    f, eps = np.asarray(f_hz, dtype=float), np.asarray(prestrains, dtype=float)
    Gs, Gl = _surface(f, eps, np.asarray(G))
    lf, le = (math.log(f[0]), math.log(f[-1])), (math.log(eps[0]), math.log(eps[-1]))
    sweep = next((d for d in sets if d.prestress is None), None)
    series = next((d for d in sets if d.prestress is not None), None)
    fd = np.concatenate([np.log(d.frequency_hz) for d in sets])
    lo, hi = [0.0, lf[0] - fd.min()], [0.0, lf[1] - fd.max()]
    lo[0], hi[0] = -50.0, 50.0
    if sweep is not None:
        lo.append(le[0])
        hi.append(le[1])
    if series is not None:
        lp = np.log(series.prestress)
        lo.append(le[0] - lp.min())
        hi.append(le[1] - lp.max())
    lo_a, hi_a = np.array(lo) + 1e-9, np.array(hi) - 1e-9

    def model(theta, d):
        lnf = np.log(d.frequency_hz) + theta[1]
        if d.prestress is None:
            lne = np.full(lnf.shape, theta[2])
        else:
            lne = np.log(d.prestress) + theta[2 + (sweep is not None)]
        x = np.column_stack([np.clip(lne, *le), np.clip(lnf, *lf)])
        return theta[0] + Gs(x), theta[0] + Gl(x)

    def residuals(theta):
        out = []
        for d in sets:
            a, b = model(theta, d)
            out += [(a - np.log(d.G_storage)) / math.log(10), (b - np.log(d.G_loss)) / math.log(10)]
        return np.concatenate(out)

    best = None
    for start in itertools.product(*(np.linspace(a, b, 7)[1:-1] for a, b in zip(lo_a[1:], hi_a[1:]))):
        theta = np.r_[0.0, start]
        theta[0] = -float(np.mean(residuals(theta))) * math.log(10)
        cost = float(np.sum(residuals(theta) ** 2))
        if best is None or cost < best[0]:
            best = (cost, theta)
    assert best is not None
    res = least_squares(residuals, np.clip(best[1], lo_a, hi_a), bounds=(lo_a, hi_a), x_scale="jac")
    r = residuals(res.x)
    rms, at = [], 0
    for d in sets:
        n = 2 * d.frequency_hz.size
        rms.append(float(np.sqrt(np.mean(r[at:at + n] ** 2))))
        at += n
    th = res.x
    curves = []
    for name, d in zip(names, sets):
        a, b = model(th, d)
        curves.append(FitCurve(name, np.asarray(d.frequency_hz if d.prestress is None else d.prestress),
                               d.prestress is not None, np.asarray(d.G_storage), np.asarray(d.G_loss), np.exp(a),
                               np.exp(b)))
    return ScaledFit(data=names, rms_log10=tuple(rms), stiffness_scale=float(np.exp(th[0])),
                     time_scale=float(np.exp(th[1])),
                     prestrain=float(np.exp(th[2])) if sweep is not None else math.nan,
                     prestrain_per_Pa=float(np.exp(th[-1])) if series is not None else math.nan,
                     success=bool(res.success), curves=tuple(curves),
                     at_bound=bool(np.any(np.minimum(th[1:] - lo_a[1:], hi_a[1:] - th[1:]) < 1e-6)))


def fit_family(family: str, *results: PointResult) -> FamilyFit:
    """A task of the plan: the family's best structure on :data:`FIT_PRESTRAINS`, fitted to the Fabry sweep alone
    and jointly with the Stamenović prestress series (:func:`scaled_fit`)."""
    from ..io.data import bundled

    t0 = time.process_time()
    point = best_point(results).point
    cell = build_cell(point)
    f = frequencies()
    rows = []
    for e in FIT_PRESTRAINS:
        a, b = _moduli(point, cell, prestress_of(cell, e), f)
        rows.append(a + 1j * b)
    G = np.array(rows)
    data = {name: bundled(name) for name in FIT_DATA}
    fits = (scaled_fit(f, FIT_PRESTRAINS, G, {FIT_DATA[0]: data[FIT_DATA[0]]}), scaled_fit(f, FIT_PRESTRAINS, G, data))
    return FamilyFit(family=family, point=point, prestrain=np.array(FIT_PRESTRAINS), frequency_hz=f, G=G, fits=fits,
                     cpu_s=time.process_time() - t0)


# ---- the result ------------------------------------------------------------------------------------------
#: goal G6: the least span of a power law in 0.1–0.3 (decades) and the fits' RMS (log10)
G6_DECADES, G6_RMS = 3.0, 0.03
#: the whole map's CPU budget on two cores (s)
MAP_BUDGET_CPU_S = 600.0


@dataclass(frozen=True, eq=False)
class PowerLawStudy:
    """The power-law map: every structure's moduli, what each curve says, the prestress trends, the fits.

    Attributes
    ----------
    scale : str
    points : tuple of PointResult
    fits : tuple of FamilyFit
        One per family (its best structure).
    """

    scale: str
    points: tuple
    fits: tuple = field(default=())

    def family(self, name: str) -> tuple:
        """The points of family ``name``."""
        return tuple(p for p in self.points if p.point.family == name)

    @cached_property
    def assessments(self) -> dict[str, list[Assessment]]:
        """Per point key, the assessment of each prestrain's curve (computed once)."""
        return {r.point.key: [assess(r.frequency_hz, r.G_storage[i], r.G_loss[i]) for i in range(r.prestrain.size)]
                for r in self.points}

    def fit(self, family: str) -> FamilyFit | None:
        """The fit of family ``name``'s best structure (None if the plan had none)."""
        return next((x for x in self.fits if x.family == family), None)

    def best(self, family: str) -> PointResult | None:
        """The family's structure that comes closest to G6 (:func:`best_point`; None for a family not mapped)."""
        pts = self.family(family)
        return best_point(pts, self.assessments) if pts else None

    @property
    def families(self) -> tuple[str, ...]:
        """The families mapped, in the study's order."""
        return tuple(f for f in FAMILIES if self.family(f))

    @property
    def cpu_s(self) -> float:
        """CPU seconds of the structures' builds and spectra and of the fits (as the tasks measured them)."""
        return float(sum(r.build_cpu_s + r.spectrum_cpu_s.sum() for r in self.points) + sum(x.cpu_s for x in self.fits))


def _knob_columns(p: MapPoint) -> dict[str, Any]:
    k = dict(p.knobs)
    nan = math.nan
    return {"structure": p.structure, "size_cells": k.get("size", nan), "connectivity_target": k.get("connectivity", nan),
            "module_nodes": k.get("module_nodes", nan), "depth": k.get("depth", nan),
            "lattice_modules": k.get("modules", nan), "law": p.law, "damping": p.damping,
            "damping_value": p.damping_value}


def _stretch_columns(prefix: str, s: Stretch) -> dict[str, float]:
    return {f"{prefix}_decades": s.decades, f"{prefix}_alpha": s.alpha, f"{prefix}_f_low_Hz": s.f_low,
            f"{prefix}_f_high_Hz": s.f_high, f"{prefix}_tan_error": s.tan_ratio}


def map_records(study: PowerLawStudy) -> list[dict]:
    """One record per structure and prestrain: its knobs and the three stretches of its curve."""
    marks = study.assessments
    rows = []
    for r in study.points:
        for i, a in enumerate(marks[r.point.key]):
            f = r.frequency_hz
            rows.append({"family": r.point.family, "label": r.point.label, **_knob_columns(r.point),
                         "coordinates": r.coordinates, "connectivity": r.connectivity,
                         "prestrain": float(r.prestrain[i]), "prestress_N": float(r.prestress[i]),
                         **_stretch_columns("power_law", a.power_law), **_stretch_columns("band", a.band),
                         **_stretch_columns("g6", a.g6),
                         "alpha_at_0p1Hz": float(np.interp(math.log(0.1), np.log(f), r.alpha[i])),
                         "alpha_at_1Hz": float(np.interp(0.0, np.log(f), r.alpha[i])),
                         "loss_tangent_at_1Hz": float(np.interp(0.0, np.log(f), r.tan_delta[i]))})
    return rows


def moduli_records(study: PowerLawStudy) -> list[dict]:
    """One record per structure, prestrain and frequency: G', G'', α and the loss tangent."""
    rows = []
    for r in study.points:
        al, tan = r.alpha, r.tan_delta
        for i in range(r.prestrain.size):
            for k, f in enumerate(r.frequency_hz):
                rows.append({"family": r.point.family, "label": r.point.label, "prestrain": float(r.prestrain[i]),
                             "prestress_N": float(r.prestress[i]), "frequency_Hz": float(f),
                             "G_storage_Pa": float(r.G_storage[i, k]), "G_loss_Pa": float(r.G_loss[i, k]),
                             "alpha": float(al[i, k]), "loss_tangent": float(tan[i, k])})
    return rows


def trend_records(study: PowerLawStudy) -> list[dict]:
    """One record per structure: dα/d ln P at fixed frequencies and over the band common to its prestrains."""
    return [{"family": r.point.family, "label": r.point.label, **trend(r)} for r in study.points]


def cost_records(study: PowerLawStudy) -> list[dict]:
    """One record per structure: its size and the CPU its build and spectra took."""
    return [{"family": r.point.family, "label": r.point.label, "coordinates": r.coordinates, "members": r.members,
             "frequencies": int(r.frequency_hz.size), "prestrains": int(r.prestrain.size),
             "build_cpu_s": r.build_cpu_s, "spectrum_cpu_s_mean": float(r.spectrum_cpu_s.mean()),
             "spectrum_cpu_s_total": float(r.spectrum_cpu_s.sum())} for r in study.points]


def _best_tan(study: PowerLawStudy, points) -> tuple[float, str]:
    """The smallest loss-tangent error over the family's 0.1–0.3 stretches of at least one decade."""
    best = (math.inf, "")
    for r in points:
        for i, a in enumerate(study.assessments[r.point.key]):
            if a.band.decades >= 1.0 and a.band.tan_ratio < best[0]:
                best = (a.band.tan_ratio, f"{r.point.label}, ε = {r.prestrain[i]:g}")
    return best


def family_records(study: PowerLawStudy) -> list[dict]:
    """One record per family: its best structure and prestrain, how close it comes to each part of G6."""
    rows = []
    for fam in FAMILIES:
        pts = study.family(fam)
        if not pts:
            continue
        best = best_point(pts, study.assessments)
        i, a = best_prestrain(best, study.assessments[best.point.key])
        tr = trend(best)
        tan_err, tan_where = _best_tan(study, pts)
        longest = max(pts, key=lambda r: max(x.power_law.decades for x in study.assessments[r.point.key]))
        j, pl = max(enumerate(study.assessments[longest.point.key]), key=lambda t: t[1].power_law.decades)
        slopes = [(trend(r)["dalpha_dlnP_1Hz"], r.point.label) for r in pts]
        lowest, highest = min(slopes), max(slopes)
        ff = study.fit(fam)
        fabry = ff.fits[0] if ff else None
        pair = ff.fits[1] if ff else None
        rows.append({"family": fam, "best_structure": best.point.label, "coordinates": best.coordinates,
                     "prestrain": float(best.prestrain[i]), "band_decades": a.band.decades, "band_alpha": a.band.alpha,
                     "g6_decades": a.g6.decades, "g6_alpha": a.g6.alpha, "g6_tan_error": a.g6.tan_ratio,
                     "best_tan_error": tan_err, "best_tan_where": tan_where,
                     "longest_power_law": f"{longest.point.label}, ε = {longest.prestrain[j]:g}",
                     "longest_power_law_decades": pl.power_law.decades, "longest_power_law_alpha": pl.power_law.alpha,
                     "dalpha_dlnP_common_band": tr["dalpha_dlnP_common_band"],
                     "dalpha_dlnP_0p1Hz": tr["dalpha_dlnP_0p1Hz"], "dalpha_dlnP_1Hz": tr["dalpha_dlnP_1Hz"],
                     "dalpha_dlnP_1Hz_median_family": float(np.median([v for v, _ in slopes])),
                     "dalpha_dlnP_1Hz_lowest": lowest[0], "dalpha_dlnP_1Hz_lowest_where": lowest[1],
                     "dalpha_dlnP_1Hz_highest": highest[0], "dalpha_dlnP_1Hz_highest_where": highest[1],
                     "fit_structure": ff.point.label if ff else "",
                     "rms_fabry_alone_log10": fabry.rms_log10[0] if fabry else math.nan,
                     "rms_pair_fabry_log10": pair.rms_log10[0] if pair else math.nan,
                     "rms_pair_stamenovic_log10": pair.rms_log10[1] if pair else math.nan})
    return rows


def fit_records(study: PowerLawStudy) -> list[dict]:
    """One record per family and fit: the data, the RMS per data set and the fitted scales."""
    rows = []
    for ff in study.fits:
        for x in ff.fits:
            rows.append({"family": ff.family, "structure": ff.point.label, "data": "+".join(x.data),
                         "rms_fabry2001_log10": x.rms_log10[0],
                         "rms_stamenovic2002_log10": x.rms_log10[1] if len(x.rms_log10) > 1 else math.nan,
                         "stiffness_scale": x.stiffness_scale, "time_scale": x.time_scale,
                         "prestrain_fabry": x.prestrain, "prestrain_per_Pa": x.prestrain_per_Pa,
                         "converged": x.success, "at_grid_edge": x.at_bound})
    return rows


def checks(study: PowerLawStudy) -> tuple[Check, ...]:
    """Goal G6, part by part, and the map's CPU budget, as this run measured them."""
    fams = family_records(study)
    if not fams:
        return ()
    top = max(fams, key=lambda r: (r["g6_decades"], r["band_decades"]))
    law = Check(f"G6a: G' slope within 0.1–0.3 (±{TOLERANCE}) over ≥ {G6_DECADES:g} decades with G''/G' within "
                f"{100 * TAN_TOLERANCE:g} % of tan(απ/2)", met=top["g6_decades"] >= G6_DECADES,
                closest=top["best_structure"],
                detail=f"{top['g6_decades']:.2f} decades at α = {top['g6_alpha']:.3f} (prestrain {top['prestrain']:g})")
    d = top["dalpha_dlnP_common_band"]
    falls = Check("G6b: α falls as the prestress rises (inside the power law)", met=bool(d < -0.01),
                  closest=top["best_structure"],
                  detail=(f"dα/d ln P = {d:+.3f} over the frequencies where α lies in 0.1–0.3 at every prestrain"
                          if math.isfinite(d) else "no frequency has α in 0.1–0.3 at every prestrain"))
    fitted = [r for r in fams if math.isfinite(r["rms_fabry_alone_log10"])]
    out = [law, falls]
    if fitted:
        b = min(fitted, key=lambda r: max(r["rms_pair_fabry_log10"], r["rms_pair_stamenovic_log10"]))
        worst = max(b["rms_pair_fabry_log10"], b["rms_pair_stamenovic_log10"])
        out.append(Check(f"G6c: fitted to the Fabry sweep and jointly with the Stamenović series at RMS ≤ {G6_RMS} "
                         "decades each", met=bool(b["rms_fabry_alone_log10"] <= G6_RMS and worst <= G6_RMS),
                         closest=b["fit_structure"],
                         detail=f"Fabry alone {b['rms_fabry_alone_log10']:.3f}; jointly {b['rms_pair_fabry_log10']:.3f} "
                                f"(Fabry) and {b['rms_pair_stamenovic_log10']:.3f} (Stamenović)"))
    out.append(Check(f"the map in ≤ {MAP_BUDGET_CPU_S:g} s of CPU", met=study.cpu_s <= MAP_BUDGET_CPU_S,
                     detail=f"{study.cpu_s:.0f} s of CPU (builds, spectra and fits, as the tasks measured them)"))
    return tuple(out)


FIGURES = (("powerlaw_moduli.png", "powerlaw_moduli_figure"), ("powerlaw_map.png", "powerlaw_map_figure"),
           ("powerlaw_loss_tangent.png", "powerlaw_loss_tangent_figure"),
           ("powerlaw_convergence.png", "powerlaw_convergence_figure"),
           ("powerlaw_prestress.png", "powerlaw_prestress_figure"), ("powerlaw_fits.png", "powerlaw_fits_figure"))


def assemble(plan: Plan, results: Mapping[str, Any]) -> StudyResult:
    """The study's tables, figures, page and checks from every task's result (protocol step 3)."""
    from .._results import reporter

    points = tuple(results[t.key] for t in plan.tasks if t.kind != "fit")
    fits = tuple(results[t.key] for t in plan.tasks if t.kind == "fit")
    study = PowerLawStudy(scale=plan.options["scale"], points=points, fits=fits)
    tables = (
        Table.from_records("powerlaw_map", map_records(study),
                           description="per structure and prestrain: the longest stretches of its local exponent"),
        Table.from_records("powerlaw_families", family_records(study),
                           description="per family: how close its best structure comes to goal G6"),
        Table.from_records("powerlaw_prestress", trend_records(study),
                           description="per structure: dα/d ln P at fixed frequencies"),
        Table.from_records("powerlaw_fits", fit_records(study),
                           description="per family: its best structure fitted to the bundled data"),
        Table.from_records("powerlaw_cost", cost_records(study),
                           description="per structure: coordinates and CPU seconds"),
        Table.from_records("powerlaw_moduli", moduli_records(study),
                           description="G', G'', α and the loss tangent of every structure, prestrain, frequency"),
    )
    ch = checks(study)
    page = reporter("powerlaw_markdown")(study, tables, ch)
    summary = "\n".join(f"{'met' if c.met else 'NOT met'}: {c.label}: {c.detail}" for c in ch)
    return StudyResult(study=NAME, tables=tables, figures=tuple(Figure(n, p, args=(study,)) for n, p in FIGURES),
                       pages=(("powerlaw.md", page),), checks=ch, data=study, summary=summary)


class _PowerLaw:
    """The study, as the command line's registry of studies holds it (:class:`tenscell.studies.protocol.Study`)."""

    name = NAME
    #: the option the command line gives it (``--scale``), with its default
    options = {"scale": "full"}

    def plan(self, options: Mapping[str, Any] | None = None) -> Plan:
        return plan(options)

    def assemble(self, plan_: Plan, results: Mapping[str, Any]) -> StudyResult:
        return assemble(plan_, results)


#: the power-law study (``tenscell study powerlaw``)
STUDY = _PowerLaw()

"""The physical prestress of a structure: the tendons' virial stress, in Pa, from its own member forces.

The model's prestress P (N) is a force scale: the tensions at the reference are ``T = P·T0``. A measured prestress
is a stress (Pa). One continuum convention turns the first into the second, the same for every structure:

``σ = Σ_tendons T_j l_j / (3V)``  (Pa), with ``T_j = P·T0_j``,

the **mean normal stress** (one third of the trace) of the tendons' virial stress tensor

``S = (1/V) Σ_tendons T_j l_j e_j e_jᵀ``  (Pa; ``e_j`` the tendon's unit direction),

where V is the volume of the **convex hull of the structure's nodes** (every node, the anchors included: the
region the structure spans; 0.385 L³ for the paper cell's 13 nodes).

Why these choices (``docs/conventions.md``, "Physical prestress", has the argument with its sources):

* *Which members*: the tendons, i.e. the cables (members whose family is not in
  :data:`~tenscell.model.structure.COMPRESSIBLE_FAMILIES`). Over **all** the members of a free self-stressed structure
  ``Σ T·l = 0`` (the virial theorem: no external force), so the stress of the whole structure says nothing; the
  prestress is the stress the tension-bearing filaments carry, balanced by the compression members (rigid struts,
  elastic struts of family ``"strut"``, the nucleus) and, in an adherent cell, by the substrate (the anchors). The
  elastic struts of a semiflexible cell and the nucleus shell are members with their own forces, and are left out
  for the same reason the rigid struts are: they balance the tendons.
* *Which scalar*: a measured prestress (Wang et al. 2002, traction microscopy) is a tensile stress across the cell's
  sections: a **normal** stress. The normal stress of S across a plane of normal n is ``nᵀ S n``; its mean over all
  orientations is ``tr S / 3``. ``Σ T l / V = tr S`` is the *sum* of three normal stresses: it equals the stress
  across a section only for a uniaxial state (all tendons parallel), and is three times it for an isotropic one.
* *Which volume*: the hull is the smallest convex region holding every member, defined for every structure
  (anchored or free, rigid or elastic struts, lattices) without a choice of surface, and it scales as L³ under the
  strut-length gauge.

The convention is invariant under the exact gauge ``(P, EA, c, L) → (λ²P, λ²EA, λc, λL)``: ``Σ T l ∝ λ²·λ`` and
``V ∝ λ³``. Its cost is O(m) for the sum and O(n log n) for the hull (qhull), so lattices of any size take it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import positive_scalar
from .._results import format_repr
from .equilibrium import Cell
from .structure import cable_mask

__all__ = ["VirialPrestress", "virial_prestress", "hull_volume", "tendon_forces", "PRESTRESS_CONVENTION"]

#: the convention in one line (reports and fit.json quote it)
PRESTRESS_CONVENTION = ("σ = Σ_tendons T_j·l_j / (3V): the mean normal stress of the tendons' virial stress, "
                        "V the convex hull of the nodes")


@dataclass(frozen=True, eq=False, repr=False)
class VirialPrestress:
    """The tendons' virial stress of a cell per unit model prestress P (:func:`virial_prestress`).

    Attributes
    ----------
    structure : str
        The structure's name.
    volume_m3 : float
        V, the volume of the convex hull of the nodes (m³).
    tension_virial_m : float
        ``Σ_tendons T0_j l_j``: N·m per N of P (so m).
    tensor_per_N : ndarray, shape (3, 3)
        ``S/P = Σ T0_j l_j e_j e_jᵀ / V`` (Pa per N of P), in the structure's frame.
    n_tendons : int
        The members counted (cables); the others (struts, nucleus) balance them.
    strut_length_m : float
        The cell's continuum length L (m), for the dimensionless groups (``σ L²`` is a force).
    """

    structure: str
    volume_m3: float
    tension_virial_m: float
    tensor_per_N: np.ndarray
    n_tendons: int
    strut_length_m: float

    @property
    def sigma_per_P(self) -> float:
        """σ per unit model prestress: ``Σ T0 l / (3V)`` (Pa/N)."""
        return self.tension_virial_m / (3.0 * self.volume_m3)

    @property
    def trace_per_P(self) -> float:
        """``tr S / P = Σ T0 l / V`` (Pa/N): three times :attr:`sigma_per_P` (the sum of three normal stresses)."""
        return self.tension_virial_m / self.volume_m3

    @property
    def normal_stresses_per_P(self) -> np.ndarray:
        """The normal stresses ``S_xx, S_yy, S_zz`` per unit P (Pa/N) across the frame's planes (z: the anchors'
        normal for an anchored cell): how far the tendons' stress is from isotropic."""
        return np.diag(self.tensor_per_N).copy()

    def sigma(self, P) -> np.ndarray | float:
        """σ (Pa) at model prestress P (N, scalar or array)."""
        out = np.asarray(P, dtype=float) * self.sigma_per_P
        return float(out) if out.ndim == 0 else out

    def prestress_at(self, sigma_pa) -> np.ndarray | float:
        """The model prestress P (N) at which σ equals ``sigma_pa`` (Pa)."""
        out = np.asarray(sigma_pa, dtype=float) / self.sigma_per_P
        return float(out) if out.ndim == 0 else out

    @property
    def scale_m2(self) -> float:
        """``s_σ = 1/sigma_per_P`` (m²): the prestress scale ``P = s·p`` at which σ equals the measured p."""
        return 1.0 / self.sigma_per_P

    def __repr__(self) -> str:
        sxx, syy, szz = self.normal_stresses_per_P
        return format_repr(
            f"VirialPrestress of {self.structure}",
            f"σ = {self.sigma_per_P:.4g} Pa per N of P (Σ T0·l = {self.tension_virial_m:.4g} m over 3V, "
            f"V = {self.volume_m3:.4g} m³, {self.n_tendons} tendons)",
            f"normal stresses S_xx, S_yy, S_zz = {sxx:.4g}, {syy:.4g}, {szz:.4g} Pa/N; s_σ = {self.scale_m2:.4g} m²",
        )

    def to_dict(self) -> dict:
        """JSON-ready dict (SI units in the keys)."""
        return {"convention": PRESTRESS_CONVENTION, "structure": self.structure, "volume_m3": self.volume_m3,
                "tension_virial_m": self.tension_virial_m, "sigma_per_P_Pa_per_N": self.sigma_per_P,
                "trace_per_P_Pa_per_N": self.trace_per_P, "scale_m2": self.scale_m2,
                "tensor_per_N_Pa": self.tensor_per_N.tolist(), "n_tendons": self.n_tendons,
                "strut_length_m": self.strut_length_m}


def hull_volume(nodes) -> float:
    """The volume (m³) of the convex hull of node positions (shape (n, 3), m).

    ValueError when the nodes span no volume (all on a plane or a line: a planar structure has no virial stress
    per unit volume).
    """
    from scipy.spatial import ConvexHull, QhullError

    x = np.asarray(nodes, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3 or x.shape[0] < 4:
        raise ValueError(f"the convex hull needs at least 4 nodes in 3D, got shape {x.shape}")
    try:
        volume = float(ConvexHull(x).volume)
    except QhullError:
        volume = 0.0
    if not volume > 1e-12 * float(np.ptp(x, axis=0).max()) ** 3:
        raise ValueError("the nodes span no volume (they lie on a plane or a line): the virial stress per unit "
                         "volume is not defined")
    return volume


def _tendons(cell: Cell) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(node pairs, T0, lengths) of the cell's tendons (cables)."""
    st = cell.structure
    cable = cable_mask(st.families)
    pairs = np.asarray(st.tendons, dtype=np.int64).reshape(-1, 2)[cable]
    return pairs, np.asarray(cell.T0, dtype=float)[cable], np.asarray(cell.lengths, dtype=float)[cable]


def tendon_forces(cell: Cell, P: float = 1.0) -> np.ndarray:
    """The forces (N) the tendons alone exert on each node at model prestress P (N), shape (n_nodes, 3).

    A tendon of tension T between nodes a and b pulls a towards b with ``T·(x_b − x_a)/l``, and b towards a. The
    tendons' virial ``−Σ_nodes x_n·f_n`` equals ``Σ T_j l_j`` whatever the origin (the forces sum to zero): the
    nodal route of :func:`virial_prestress`.
    """
    P = positive_scalar("P (prestress)", P, "N")
    pairs, T0, _ = _tendons(cell)
    x = np.asarray(cell.structure.nodes, dtype=float)
    d = x[pairs[:, 1]] - x[pairs[:, 0]]
    pull = (P * T0 / np.linalg.norm(d, axis=1))[:, None] * d
    f = np.zeros_like(x)
    np.add.at(f, pairs[:, 0], pull)
    np.add.at(f, pairs[:, 1], -pull)
    return f


def virial_prestress(cell: Cell) -> VirialPrestress:
    """The tendons' virial stress of ``cell`` per unit model prestress (module docstring: the convention).

    Parameters
    ----------
    cell : Cell
        Any prestressable cell: the paper's, spheres, lattices, a structure file's, a semiflexible or nucleated
        cell (its struts and nucleus are members that balance the tendons, and are not counted).

    Returns
    -------
    VirialPrestress
        ``.sigma(P)`` is the physical prestress (Pa) at model prestress P (N); ``.scale_m2`` the prestress scale at
        which it equals a measured prestress.

    Raises
    ------
    ValueError
        A cell without tendons in tension, or whose nodes span no volume.
    """
    if not isinstance(cell, Cell):
        raise ValueError(f"cell must be a tenscell Cell, got {type(cell).__name__}")
    pairs, T0, l = _tendons(cell)
    if pairs.shape[0] == 0 or not np.any(T0 > 0):
        raise ValueError(f"{cell.describe()}: no tendon in tension, so no prestress to measure")
    x = np.asarray(cell.structure.nodes, dtype=float)
    e = (x[pairs[:, 0]] - x[pairs[:, 1]]) / l[:, None]
    V = hull_volume(x)
    Tl = T0 * l
    tensor = np.einsum("j,ja,jb->ab", Tl, e, e) / V
    virial = float(Tl.sum())
    if not (math.isfinite(virial) and virial > 0):
        raise ValueError(f"{cell.describe()}: the tendons' virial Σ T0·l = {virial!r} is not positive")
    tensor.setflags(write=False)
    return VirialPrestress(structure=cell.describe(), volume_m3=V, tension_virial_m=virial, tensor_per_N=tensor,
                           n_tendons=int(pairs.shape[0]), strut_length_m=float(cell.strut_length))

"""The paper's placements: laws of a cell at a prestress P (rest lengths from Eq. 11)."""
from __future__ import annotations

import numpy as np

from .._checks import finite_scalar, positive_array
from ..model.equilibrium import Cell
from .base import TendonLaw
from .composite import CompositeLaw
from .filaments import StiffeningFilament
from .springs import DEFAULT_VELOCITY_SCALE, PowerDashpot, Voigt

__all__ = ["rest_lengths", "voigt_law", "power_dashpot_law", "stiffening_law"]


def _per_tendon(cell: Cell, **arrays) -> tuple[np.ndarray, ...]:
    """Validate per-tendon inputs given as scalars or (m,) arrays; return (m,) arrays."""
    out = []
    for name, (value, unit, allow_zero) in arrays.items():
        if np.ndim(value) == 1 and np.shape(value) != (cell.m,):
            raise ValueError(f"{name} must have {cell.m} entries (one per working tendon), got {np.shape(value)[0]}")
        out.append(positive_array(name, value, (cell.m,), unit, allow_zero=allow_zero))
    return tuple(out)


def rest_lengths(cell: Cell, P: float, EA) -> np.ndarray:
    """Rest lengths giving ``T = P·T0`` at the reference (paper Eq. 11), in m.

    ``l0_j = l_j(q0)·EA_j / (T0_j·P + EA_j)``.
    """
    EA = np.broadcast_to(np.asarray(EA, dtype=float), cell.T0.shape)
    return Voigt._trusted(EA=EA, c=0.0).rest_lengths(cell.lengths, P * cell.T0)


def voigt_law(cell: Cell, P: float = 1000.0, EA=1.0, c=1.0) -> Voigt:
    """The Voigt law of a cell at prestress ``P`` (rest lengths from Eq. 11).

    Parameters
    ----------
    cell : Cell
    P : float
        Prestress scale (N): tensions ``P·T0`` at the reference.
    EA : float or array_like, shape (m,)
        Stiffness (N).
    c : float or array_like, shape (m,)
        Damping (N·s/m).
    """
    EA, c = _per_tendon(cell, EA=(EA, "N", False), c=(c, "N·s/m", False))
    return Voigt(EA=EA, c=c).at_prestress(cell, P)


def power_dashpot_law(cell: Cell, P: float = 1000.0, EA=1.0, c=1.0, beta: float = 2.0,
                      velocity_scale: float = DEFAULT_VELOCITY_SCALE) -> PowerDashpot:
    """The power-law dashpot of a cell at prestress ``P`` (rest lengths from Eq. 11).

    Parameters
    ----------
    cell : Cell
    P : float
        Prestress scale (N).
    EA : float or array_like, shape (m,)
        Stiffness (N).
    c : float or array_like, shape (m,)
        Dashpot coefficient (N·(s/m)^β).
    beta : float
        Exponent β > 0.
    velocity_scale : float
        Smoothing velocity ε (m/s), see :class:`PowerDashpot`.
    """
    finite_scalar("beta (dashpot exponent)", beta)
    EA, c = _per_tendon(cell, EA=(EA, "N", False), c=(c, "N·(s/m)^beta", False))
    return PowerDashpot(EA=EA, c=c, beta=beta, velocity_scale=velocity_scale).at_prestress(cell, P)


def stiffening_law(cell: Cell, P: float | None = 1000.0, EA=1.0, c=1.0, *, b: float = 0.0,
                   family: str = "intermediate_filament") -> CompositeLaw:
    """Stiffening filaments on one tendon family, Voigt on the others (at prestress ``P``).

    Parameters
    ----------
    cell : Cell
    P : float or None
        Prestress (N); None leaves the law without rest lengths.
    EA : float or array_like, shape (m,)
        Small-strain stiffness (N).
    c : float or array_like, shape (m,)
        Damping (N·s/m).
    b : float
        Stiffening exponent of ``family`` (dimensionless), ≥ 0.
    family : str
        The tendon family that stiffens (the intermediate filaments by default).
    """
    EA, c = _per_tendon(cell, EA=(EA, "N", False), c=(c, "N·s/m", True))
    b = finite_scalar("b (stiffening exponent)", b, "a finite number >= 0 (dimensionless; 0 = linear)")
    if b < 0:
        raise ValueError(f"b (stiffening exponent) must be a finite number >= 0 (dimensionless; 0 = linear), got {b!r}")
    stiff = cell.structure.family_indices(family)
    if stiff.size == 0:
        raise ValueError(f"{cell.describe()} has no tendons of family {family!r}")
    rest = np.setdiff1d(np.arange(cell.m), stiff)
    parts: list[TendonLaw] = [StiffeningFilament(EA=EA[stiff], c=c[stiff], b=np.full(stiff.size, b))]
    idx = [stiff]
    if rest.size:
        parts.append(Voigt(EA=EA[rest], c=c[rest]))
        idx.append(rest)
    law = CompositeLaw(tuple(parts), tuple(idx))
    return law if P is None else law.at_prestress(cell, P)

"""Strain-stiffening intermediate filaments (the paper's future work): their effect on G', G'' against P.

The IFs follow :class:`tenscell.laws.StiffeningFilament`, the actin the
paper's Voigt law (:func:`tenscell.laws.stiffening_law`); the cell is
linearized through the law (:func:`tenscell.linear.linearize.linearize_law`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import positive_scalar
from .._results import dataframe, format_repr
from ..laws import stiffening_law
from ..linear.linearize import LinearModel, linearize_law
from ..linear.assembly import modulus
from ..model.equilibrium import Cell
from ..model.shapes import paper_cell
from ..model.structure import INTERMEDIATE_FILAMENT
from ..response import compliance, static_modulus
from ._common import grid

__all__ = ["linearize_stiffening", "StiffeningStudy", "stiffening_study"]


def linearize_stiffening(
    cell: Cell, P: float = 1000.0, EA=1.0, c=1.0, *, b: float = 0.0, family: str = INTERMEDIATE_FILAMENT,
    check: bool = True,
) -> LinearModel:
    """Linearize with strain-stiffening filaments on one tendon family (the IFs by default).

    ``linearize_law(cell, stiffening_law(cell, None, EA, c, b=b, family=family), P)``:
    the members of ``family`` follow :class:`tenscell.laws.StiffeningFilament`,
    the others the paper's Voigt law (parameters as in
    :func:`tenscell.laws.stiffening_law`). ``b = 0`` reproduces
    :func:`tenscell.linearize`.
    """
    return linearize_law(cell, stiffening_law(cell, None, EA, c, b=b, family=family), P, check=check)


@dataclass(frozen=True, eq=False, repr=False)
class StiffeningStudy:
    """G', G'' against prestress for several IF stiffening exponents.

    Attributes
    ----------
    b : ndarray, shape (nb,)
        Stiffening exponents.
    prestress : ndarray, shape (nP,)
        P (N).
    frequency_hz : ndarray, shape (nf,)
    G : ndarray of complex, shape (nb, nP, nf)
        Moduli (Pa).
    static : ndarray, shape (nb, nP)
        Static G' (Pa).
    if_tangent : ndarray, shape (nb, nP)
        Tangent stiffness of a stiffening tendon at the reference (N/m).
    EA, c : float
        Uniform small-strain stiffness (N) and damping (N·s/m).
    family : str
        The tendon family that stiffens (the others are Voigt).
    cell : Cell
    """

    b: np.ndarray
    prestress: np.ndarray
    frequency_hz: np.ndarray
    G: np.ndarray
    static: np.ndarray
    if_tangent: np.ndarray
    EA: float = 1.0
    c: float = 1.0
    family: str = INTERMEDIATE_FILAMENT
    cell: Cell | None = None

    def exponent(self) -> np.ndarray:
        """Log-log slope of G' against P over the whole P range, shape (nb, nf)."""
        P = self.prestress
        return np.log(self.G.real[:, -1] / self.G.real[:, 0]) / math.log(P[-1] / P[0])

    @property
    def stiffening_indices(self) -> np.ndarray:
        """Indices of the stiffening tendons in the cell."""
        if self.cell is None:
            raise ValueError("this study was built without its cell: the stiffening tendons are unknown")
        return self.cell.structure.family_indices(self.family)

    def __repr__(self) -> str:
        i1 = int(np.argmin(np.abs(np.log(self.frequency_hz))))
        ex = self.exponent()[:, i1]
        return format_repr(
            f"StiffeningStudy: {self.b.size} exponents b = {self.b.min():g}…{self.b.max():g} on {self.family}, "
            f"{self.prestress.size} prestresses {self.prestress[0]:g}…{self.prestress[-1]:g} N",
            f"EA = {self.EA:g} N, c = {self.c:g} N·s/m",
            f"G' ∝ P^{ex.min():.3f}…P^{ex.max():.3f} at {self.frequency_hz[i1]:g} Hz",
        )

    def to_dataframe(self):
        """One row per (b, P, f): G', G'' (Pa), static G' (Pa) and the stiffening tendon's tangent (N/m)."""
        nb, nP, nf = self.G.shape
        ib, iP, jf = (a.ravel() for a in np.meshgrid(np.arange(nb), np.arange(nP), np.arange(nf), indexing="ij"))
        G = self.G.ravel()
        return dataframe({
            "b": self.b[ib], "prestress_N": self.prestress[iP], "frequency_Hz": self.frequency_hz[jf],
            "G_storage_Pa": G.real, "G_loss_Pa": G.imag, "G_static_Pa": self.static[ib, iP],
            "tangent_stiffness_N_per_m": self.if_tangent[ib, iP],
        }, {"EA_N": self.EA, "c_Ns_per_m": self.c, "family": self.family})

    def plot(self, ax=None, **kw):
        """G'(P) and G''(P) near 1 Hz for each b, on a pair of axes (or a new figure); returns them."""
        from .._results import plotter

        stiffening_figure = plotter("stiffening_figure")

        return stiffening_figure(self, axes=ax, **kw)


def stiffening_study(
    b=(0.0, 0.003, 0.01, 0.03, 0.1, 1.0),
    prestress=np.linspace(500.0, 4500.0, 41),
    f_hz=(1.0, 10.0),
    *,
    EA: float = 1.0,
    c: float = 1.0,
    family: str = INTERMEDIATE_FILAMENT,
) -> StiffeningStudy:
    """G', G'' of the paper cell against P with exponentially stiffening IFs.

    Parameters
    ----------
    b : array_like
        IF stiffening exponents (dimensionless, ≥ 0; 0 = the paper's linear IFs).
    prestress : array_like
        P (N).
    f_hz : array_like
        Frequencies (Hz).
    EA, c : float
        Uniform small-strain stiffness (N) and damping (N·s/m).
    family : str
        The tendon family that stiffens.
    """
    EA, c = positive_scalar("EA", EA, "N"), positive_scalar("c", c, "N·s/m")
    bs = np.atleast_1d(np.asarray(b, dtype=float)).ravel()
    if not np.all(np.isfinite(bs)) or np.any(bs < 0):
        raise ValueError(f"b (stiffening exponents) must be finite numbers >= 0, got {b!r}")
    Ps = grid("prestress", prestress, "N")
    f = grid("frequency", f_hz, "Hz")
    cell = paper_cell()
    idx = cell.structure.family_indices(family)
    if idx.size == 0:
        raise ValueError(f"{cell.describe()} has no tendons of family {family!r}")
    j = int(idx[0])
    G = np.zeros((bs.size, Ps.size, f.size), dtype=complex)
    st = np.zeros((bs.size, Ps.size))
    kt = np.zeros((bs.size, Ps.size))
    for i, bb in enumerate(bs):
        for k, P in enumerate(Ps):
            lin = linearize_stiffening(cell, P, EA, c, b=bb, family=family)
            G[i, k] = modulus(compliance(lin, f), cell.strut_length)
            st[i, k] = static_modulus(lin)
            kt[i, k] = lin.law.tangent_at_rest(cell.lengths, P * cell.T0)[0][j]
    return StiffeningStudy(b=bs, prestress=Ps, frequency_hz=f, G=G, static=st, if_tangent=kt, EA=EA, c=c,
                           family=family, cell=cell)


# ---- the study protocol (tenscell study stiffening) ------------------------------------------------------------
#: the study's work (its defaults: 6 exponents × 41 prestresses) in units of :func:`_probe` (one exponent at 4
#: prestresses), as measured
STIFFENING_UNITS = 36.0


def _probe() -> StiffeningStudy:
    """One unit of the study's work: one exponent at four prestresses."""
    return stiffening_study(b=(0.01,), prestress=(500.0, 1000.0, 2000.0, 4500.0))


class _Stiffening:
    """``tenscell study stiffening``: one task (the study's defaults), calibrated by a small grid of it."""

    name = "stiffening"
    options: dict = {}

    def plan(self, options):
        from .protocol import Plan, Task, study_options

        return Plan(self.name, study_options(self, options),
                    (Task("stiffening: G', G'' against P for each exponent", "grid", stiffening_study,
                          weight=STIFFENING_UNITS),),
                    calibration=(Task("one exponent at four prestresses", "grid", _probe),), figures=2.3)

    def assemble(self, plan, results):
        from .._results import reporter
        from .protocol import Figure, StudyResult, Table

        s = next(iter(results.values()))
        rows = [{"b": float(b), "prestress": float(P), "frequency_Hz": float(f), "G_storage": float(s.G[i, k, j].real),
                 "G_loss": float(s.G[i, k, j].imag), "G_static": float(s.static[i, k]),
                 "IF_tangent_N_per_m": float(s.if_tangent[i, k])}
                for i, b in enumerate(s.b) for k, P in enumerate(s.prestress) for j, f in enumerate(s.frequency_hz)]
        return StudyResult(self.name, tables=(Table.from_records("stiffening", rows),),
                           figures=(Figure("stiffening.png", "stiffening_figure", (s,)),),
                           pages=(("stiffening.md", reporter("stiffening_markdown")(s)),), data=s)


#: the study of ``tenscell study stiffening`` (:mod:`tenscell.studies.protocol`)
STUDY = _Stiffening()

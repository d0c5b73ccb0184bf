"""Semiflexible struts: struts as elastic (Voigt) members, convergence to rigid struts, Euler buckling."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._errors import TenscellError
from .._checks import positive_array, positive_scalar
from .._results import dataframe, format_repr
from ..laws import Voigt
from ..linear.linearize import LinearModel, linearize, linearize_law
from ..linear.assembly import modulus
from ..model.equilibrium import Cell
from ..model.shapes import paper_cell, semiflexible_paper_cell
from ..model.structure import STRUT
from ..response import compliance
from ._common import grid

__all__ = ["BucklingError", "euler_critical_prestress", "linearize_semiflexible", "SemiflexibleStudy",
           "semiflexible_study"]


class BucklingError(TenscellError, ValueError):
    """A strut's compression exceeds its Euler load π²EI/l²: the linear model does not apply."""


def _strut_indices(cell: Cell) -> np.ndarray:
    idx = cell.structure.family_indices(STRUT)
    if idx.size == 0:
        raise ValueError(
            f"{cell.describe()} has no elastic struts (members of family 'strut'); "
            "build it with tenscell.model.shapes.semiflexible_paper_cell or semiflexible_structure"
        )
    return idx


def euler_critical_prestress(cell: Cell, EI: float) -> float:
    """Prestress P (N) at which the most compressed strut reaches its Euler load ``π²EI/l²``.

    Pinned-pinned struts (ball joints and cable nodes do not resist bending).

    Parameters
    ----------
    cell : Cell
        With elastic struts (:func:`tenscell.model.shapes.semiflexible_paper_cell`).
    EI : float
        Bending stiffness of a strut (N·m²).
    """
    EI = positive_scalar("EI", EI, "N·m²")
    s = _strut_indices(cell)
    comp = -cell.T0[s]  # compression per unit P
    if np.any(comp <= 0):
        raise ValueError("a strut member carries tension in the self-stress; Euler buckling does not apply")
    return float(np.min(math.pi ** 2 * EI / cell.lengths[s] ** 2 / comp))


def linearize_semiflexible(
    cell: Cell,
    P: float = 1000.0,
    EA=1.0,
    c=1.0,
    *,
    EA_strut=1e6,
    c_strut=0.0,
    EI: float | None = None,
    check: bool = True,
) -> LinearModel:
    """Linearize a cell whose struts are elastic members (axial stiffness ``EA_strut``).

    Every member is a Voigt element with the rest length of Eq. (11), so its
    tangent stiffness is ``(EA_j + P·T0_j)/l_j``; a strut's ``T0`` is negative,
    so compression softens it, and it must satisfy ``EA_strut > P·|T0_s|``.

    Parameters
    ----------
    cell : Cell
        From :func:`tenscell.model.shapes.semiflexible_paper_cell` (struts last).
    P : float
        Prestress (N).
    EA, c : float or array_like over the tendons
        Tendon stiffness (N) and damping (N·s/m) (the non-strut members).
    EA_strut : float or array_like over the struts
        Strut axial stiffness (N), > P·|T0_s|.
    c_strut : float or array_like over the struts
        Strut damping (N·s/m), ≥ 0 (default 0: C0 is then singular and the
        compliance uses direct solves).
    EI : float, optional
        Strut bending stiffness (N·m²): if given, raise :class:`BucklingError`
        when P·|T0_s| exceeds the Euler load π²EI/l_s².

    Raises
    ------
    BucklingError, ValueError, NotPositiveDefiniteError
    """
    P = positive_scalar("P (prestress)", P, "N")
    s = _strut_indices(cell)
    t = np.setdiff1d(np.arange(cell.m), s)
    EA_all = np.empty(cell.m)
    c_all = np.empty(cell.m)
    EA_all[t] = positive_array("EA", EA, (t.size,), "N")
    c_all[t] = positive_array("c", c, (t.size,), "N·s/m")
    EA_all[s] = positive_array("EA_strut", EA_strut, (s.size,), "N")
    c_all[s] = positive_array("c_strut", c_strut, (s.size,), "N·s/m", allow_zero=True)
    comp = -P * cell.T0[s]
    if EI is not None:
        Pcr = euler_critical_prestress(cell, EI)
        if P > Pcr:
            raise BucklingError(
                f"at P={P:g} the struts carry {comp.max():.4g} N of compression, above their Euler load "
                f"π²EI/l² = {math.pi ** 2 * positive_scalar('EI', EI) / cell.lengths[s].max() ** 2:.4g} N (EI={EI:g} N·m²): "
                f"they buckle for P above {Pcr:.4g} N, and this linear model does not describe a buckled strut"
            )
    if np.any(EA_all[s] <= comp):
        j = int(np.argmax(comp - EA_all[s]))
        raise ValueError(
            f"EA_strut must exceed the strut compression P·|T0| = {comp[j]:.6g} N at P={P:g} "
            f"(got {EA_all[s][j]:.6g} N): a softer strut would need a non-positive rest length"
        )
    return linearize_law(cell, Voigt(EA=EA_all, c=c_all), P, check=check)


@dataclass(frozen=True, eq=False, repr=False)
class SemiflexibleStudy:
    """Convergence of the semiflexible cell to the rigid one as the strut stiffness grows.

    Attributes
    ----------
    EA_strut : ndarray, shape (k,)
        Strut stiffnesses (N).
    G : ndarray of complex, shape (k, nf)
        Moduli (Pa) of the semiflexible cell (NaN where K0 is not positive definite).
    G_rigid : ndarray of complex, shape (nf,)
        Moduli of the rigid-strut cell (Pa).
    frequency_hz : ndarray, shape (nf,)
    error_storage, error_loss : ndarray, shape (k,)
        max over f of |G'/G'_rigid − 1|, |G''/G''_rigid − 1|.
    rate_storage, rate_loss : float
        Fitted exponents of the errors against EA_s on the stiff end (−1 means ∝ 1/EA_s).
    constant_storage, constant_loss : float
        ``EA_s × error`` on the stiff end (N): the error is about constant/EA_s.
    critical_EA : float
        Smallest EA_s (N) for which the model exists and K0 is positive definite
        at P: the strut compression P·|T0_s| itself when K0 stays definite
        down to it (bisection otherwise).
    G_softest : ndarray of complex, shape (nf,)
        Moduli (Pa) at ``critical_EA``.
    strut_compression : float
        P·|T0_s| (N), the strut force (the same in the rigid cell).
    euler_EI_per_P : float
        Bending stiffness per unit prestress at which the struts buckle (N·m²/N):
        the struts buckle when P > EI / euler_EI_per_P.
    P, c_strut : float
        Prestress (N) and strut damping (N·s/m).
    EA, c : float
        Tendon stiffness (N) and damping (N·s/m).
    cell : Cell
        The semiflexible cell.
    """

    EA_strut: np.ndarray
    G: np.ndarray
    G_rigid: np.ndarray
    frequency_hz: np.ndarray
    error_storage: np.ndarray
    error_loss: np.ndarray
    rate_storage: float
    rate_loss: float
    constant_storage: float
    constant_loss: float
    critical_EA: float
    G_softest: np.ndarray
    strut_compression: float
    euler_EI_per_P: float
    P: float
    c_strut: float
    EA: float = 1.0
    c: float = 1.0
    cell: Cell | None = None

    @property
    def n_struts(self) -> int:
        """Number of elastic struts."""
        return int(self.cell.structure.family_indices(STRUT).size) if self.cell is not None else 0

    def __repr__(self) -> str:
        return format_repr(
            f"SemiflexibleStudy: {self.EA_strut.size} strut stiffnesses {self.EA_strut[0]:.3g}…{self.EA_strut[-1]:.3g} N, "
            f"{self.frequency_hz.size} frequencies",
            f"P = {self.P:g} N, tendons EA = {self.EA:g} N, c = {self.c:g} N·s/m, struts c_s = {self.c_strut:g} N·s/m",
            f"error ∝ EA_s^{self.rate_storage:.3f} (G'), EA_s^{self.rate_loss:.3f} (G''); stable down to "
            f"EA_s = {self.critical_EA:.4g} N",
        )

    def to_dataframe(self):
        """One row per strut stiffness: largest relative difference of G', G'' from rigid struts."""
        return dataframe({"EA_strut_N": self.EA_strut, "max_rel_diff_storage": self.error_storage,
                          "max_rel_diff_loss": self.error_loss},
                         {"prestress_N": self.P, "EA_N": self.EA, "c_Ns_per_m": self.c, "c_strut_Ns_per_m": self.c_strut})

    def plot(self, ax=None, **kw):
        """Convergence to rigid struts against EA_s, and the 1 Hz moduli, on a pair of axes (or a new figure)."""
        from .._results import plotter

        semiflexible_figure = plotter("semiflexible_figure")

        return semiflexible_figure(self, axes=ax, **kw)


def semiflexible_study(
    EA_strut=np.logspace(3, 9, 25),
    f_hz=np.logspace(-2, 3, 51),
    *,
    P: float = 1000.0,
    EA: float = 1.0,
    c: float = 1.0,
    c_strut: float = 0.0,
) -> SemiflexibleStudy:
    """G', G'' of the paper cell with elastic struts, from soft to stiff, against the rigid cell.

    Parameters
    ----------
    EA_strut : array_like
        Strut axial stiffnesses (N).
    f_hz : array_like
        Frequencies (Hz).
    P, EA, c : float
        Prestress (N), tendon stiffness (N) and damping (N·s/m).
    c_strut : float
        Strut damping (N·s/m), ≥ 0.
    """
    EAs = grid("EA_strut", EA_strut, "N")
    f = grid("frequency", f_hz, "Hz")
    P = positive_scalar("P (prestress)", P, "N")
    EA, c = positive_scalar("EA", EA, "N"), positive_scalar("c", c, "N·s/m")
    rigid = paper_cell()
    G_r = modulus(compliance(linearize(rigid, P=P, EA=EA, c=c), f), rigid.strut_length)
    cell = semiflexible_paper_cell()
    comp = float(-P * cell.T0[_strut_indices(cell)].min())
    G = np.full((EAs.size, f.size), np.nan + 0j)
    for i, e in enumerate(EAs):
        try:
            lin = linearize_semiflexible(cell, P, EA, c, EA_strut=e, c_strut=c_strut)
        except ValueError:
            continue
        G[i] = modulus(compliance(lin, f), cell.strut_length)
    es = np.max(np.abs(G.real / G_r.real - 1), axis=1)
    el = np.max(np.abs(G.imag / G_r.imag - 1), axis=1)
    stiff = EAs >= EAs.max() / 1e3  # the three stiffest decades: the asymptotic regime
    stiff &= np.isfinite(es) & (es > 0) & (el > 0)
    rs = float(np.polyfit(np.log(EAs[stiff]), np.log(es[stiff]), 1)[0]) if stiff.sum() > 1 else math.nan
    rl = float(np.polyfit(np.log(EAs[stiff]), np.log(el[stiff]), 1)[0]) if stiff.sum() > 1 else math.nan
    ks = float(np.median(es[stiff] * EAs[stiff])) if stiff.any() else math.nan
    kl = float(np.median(el[stiff] * EAs[stiff])) if stiff.any() else math.nan

    def stable(e):
        try:
            linearize_semiflexible(cell, P, EA, c, EA_strut=e, c_strut=c_strut)
            return True
        except ValueError:
            return False

    # the Voigt strut needs EA_s > P·|T0_s| (positive rest length); is K0 still definite at that limit?
    lo, hi = comp * (1 + 1e-9), comp * 1e6
    if stable(lo):
        crit = lo
    elif stable(hi):
        for _ in range(60):
            mid = math.sqrt(lo * hi)
            lo, hi = (lo, mid) if stable(mid) else (mid, hi)
        crit = hi
    else:
        crit = math.nan
    soft = np.full(f.size, np.nan + 0j)
    if not math.isnan(crit):
        lin = linearize_semiflexible(cell, P, EA, c, EA_strut=crit, c_strut=c_strut)
        soft = modulus(compliance(lin, f), cell.strut_length)
    return SemiflexibleStudy(
        EA_strut=EAs, G=G, G_rigid=G_r, frequency_hz=f, error_storage=es, error_loss=el, rate_storage=rs, rate_loss=rl,
        constant_storage=ks, constant_loss=kl, critical_EA=float(crit), G_softest=soft, strut_compression=comp,
        euler_EI_per_P=float(1.0 / euler_critical_prestress(cell, 1.0)), P=P, c_strut=float(c_strut),
        EA=float(EA), c=float(c), cell=cell,
    )


# ---- the study protocol (tenscell study semiflexible) ----------------------------------------------------------
#: the study's work (its defaults: 25 strut stiffnesses, the bisection for the softest stable strut) in units of
#: :func:`_probe`, as measured
SEMIFLEXIBLE_UNITS = 2.4


def _probe() -> SemiflexibleStudy:
    """One unit of the study's work: the study at three strut stiffnesses."""
    return semiflexible_study(EA_strut=(1e4, 1e6, 1e8))


class _Semiflexible:
    """``tenscell study semiflexible``: one task (the study's defaults), calibrated by a small grid of it."""

    name = "semiflexible"
    options: dict = {}

    def plan(self, options):
        from .protocol import Plan, Task, study_options

        return Plan(self.name, study_options(self, options),
                    (Task("semiflexible: G', G'' against the strut stiffness", "grid", semiflexible_study,
                          weight=SEMIFLEXIBLE_UNITS),),
                    calibration=(Task("three strut stiffnesses", "grid", _probe),), figures=4.1)

    def assemble(self, plan, results):
        from .._results import reporter
        from .protocol import Figure, StudyResult, Table

        s = next(iter(results.values()))
        f = s.frequency_hz
        moduli = Table.from_records("semiflexible", [
            {"EA_strut": float(e), "frequency_Hz": float(f[k]), "G_storage": float(s.G[i, k].real),
             "G_loss": float(s.G[i, k].imag), "G_storage_rigid": float(s.G_rigid[k].real),
             "G_loss_rigid": float(s.G_rigid[k].imag)} for i, e in enumerate(s.EA_strut) for k in range(f.size)])
        convergence = Table.from_records("semiflexible_convergence", [
            {"EA_strut": float(e), "max_rel_diff_storage": float(a), "max_rel_diff_loss": float(b)}
            for e, a, b in zip(s.EA_strut, s.error_storage, s.error_loss)])
        return StudyResult(self.name, tables=(moduli, convergence),
                           figures=(Figure("semiflexible.png", "semiflexible_figure", (s,)),),
                           pages=(("semiflexible.md", reporter("semiflexible_markdown")(s)),), data=s)


#: the study of ``tenscell study semiflexible`` (:mod:`tenscell.studies.protocol`)
STUDY = _Semiflexible()

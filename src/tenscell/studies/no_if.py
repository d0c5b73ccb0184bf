"""The cell without intermediate filaments: a singular damping matrix and a peak of G'' in frequency.

The paper remarks that without IFs G'' has a peak; :func:`no_if_study` finds
where and how high, against prestress, stiffness and damping, and checks that
the null vector of C0 is a mechanism held by the prestress alone.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize

from .._checks import positive_scalar
from .._results import dataframe, format_repr
from ..linear.linearize import LinearModel, linearize
from ..linear.assembly import continuum_factor, modulus
from ..model.equilibrium import Cell
from ..model.shapes import paper_cell
from ..response import FrequencyResponse, compliance, frequency_response
from ._common import grid

__all__ = ["LossPeak", "loss_peak", "NoIFStudy", "no_if_study", "PAPER_WINDOW_HZ"]

#: the upper end of the paper's frequency window (Hz)
PAPER_WINDOW_HZ = 1000.0


@dataclass(frozen=True, repr=False)
class LossPeak:
    """A maximum of G'' over frequency.

    Attributes
    ----------
    frequency_hz : float
        Where G'' peaks (Hz).
    height : float
        G'' there (Pa).
    storage : float
        G' there (Pa).
    """

    frequency_hz: float
    height: float
    storage: float

    def __repr__(self) -> str:
        return f"LossPeak(f = {self.frequency_hz:.5g} Hz, G'' = {self.height:.5g} Pa, G' = {self.storage:.5g} Pa)"


def loss_peak(lin: LinearModel, f_min: float = 1e-4, f_max: float = 1e8, n: int = 121) -> LossPeak:
    """The maximum of G''(f) between ``f_min`` and ``f_max`` (Hz), refined to ~1e-8 in log10 f.

    Raises
    ------
    ValueError
        If G'' has no interior maximum in the range (it is largest at an end).
    """
    f_min, f_max = positive_scalar("f_min", f_min, "Hz"), positive_scalar("f_max", f_max, "Hz")
    if f_max <= f_min:
        raise ValueError(f"f_max must exceed f_min, got {f_min!r} and {f_max!r} Hz")
    f = np.logspace(math.log10(f_min), math.log10(f_max), n)
    Gl = (modulus(compliance(lin, f), lin.L)).imag
    k = int(np.argmax(Gl))
    if k == 0 or k == n - 1:
        raise ValueError(
            f"G'' has no peak between {f_min:g} and {f_max:g} Hz for {lin.cell.describe()} at P={lin.P:g}: "
            f"it is largest at {f[k]:g} Hz, the end of the range"
        )

    def neg(u):
        return -float((modulus(compliance(lin, [10.0 ** u]), lin.L)).imag[0])

    r = scipy.optimize.minimize_scalar(neg, bounds=(math.log10(f[k - 1]), math.log10(f[k + 1])), method="bounded",
                                       options={"xatol": 1e-8})
    fp = 10.0 ** r.x
    G = modulus(compliance(lin, [fp])[0], lin.L)
    return LossPeak(frequency_hz=float(fp), height=float(G.imag), storage=float(G.real))


@dataclass(frozen=True, eq=False, repr=False)
class NoIFStudy:
    """The cell without intermediate filaments against the cell with them.

    Attributes
    ----------
    without, with_ifs : FrequencyResponse
        Moduli over prestress × frequency.
    peaks : list of LossPeak
        The G'' peak at each prestress of ``without``.
    peaks_EA, peaks_c : list of (float, LossPeak)
        The peak at P = ``reference_P`` for other uniform EA (N) and c (N·s/m).
    c0_eigenvalues : ndarray
        Eigenvalues of C0 (N·s/m) at the study's ``c``, ascending.
    mechanism_residual : float
        ``|Aᵀv|/|A|`` for the null vector v of C0 (≈ 0: an infinitesimal mechanism).
    storage_limit_per_P : float
        ``lim_{f→∞} G'/P`` (Pa/N): the mechanism, stiffened by prestress only.
    peak_exponents : (float, float)
        Fitted ``f_peak ∝ P^a`` and ``G''_peak ∝ P^b`` over the prestresses.
    window_prestress : float
        Prestress (N) above which the peak leaves the frequency window (f ≤ ``window_hz``).
    cell, cell_if : Cell
    EA, c : float
        Uniform tendon stiffness (N) and damping (N·s/m).
    reference_P : float
        Prestress (N) of the EA and c scans and of ``c0_eigenvalues``.
    window_hz : float
        Upper end of the frequency window (Hz; the paper's is 1000 Hz).
    """

    without: FrequencyResponse
    with_ifs: FrequencyResponse
    peaks: list
    peaks_EA: list
    peaks_c: list
    c0_eigenvalues: np.ndarray
    mechanism_residual: float
    storage_limit_per_P: float
    peak_exponents: tuple
    window_prestress: float
    cell: Cell
    cell_if: Cell
    EA: float
    c: float
    reference_P: float
    window_hz: float = PAPER_WINDOW_HZ

    def __repr__(self) -> str:
        Ps = self.without.prestress
        return format_repr(
            f"NoIFStudy: {self.cell.describe()}, {Ps.size} prestresses {Ps[0]:g}…{Ps[-1]:g} N",
            f"EA = {self.EA:g} N, c = {self.c:g} N·s/m; C0 singular (smallest eigenvalue {self.c0_eigenvalues[0]:.2e})",
            f"G'' peak at {self.peaks[0].frequency_hz:.4g}…{self.peaks[-1].frequency_hz:.4g} Hz; "
            f"f_peak ∝ P^{self.peak_exponents[0]:.3f}",
            f"inside f ≤ {self.window_hz:g} Hz for P below {self.window_prestress:.4g} N",
        )

    def to_dataframe(self):
        """The G'' peak at each prestress: frequency, height and G' there."""
        return dataframe({
            "prestress_N": self.without.prestress, "peak_frequency_Hz": [p.frequency_hz for p in self.peaks],
            "peak_G_loss_Pa": [p.height for p in self.peaks], "G_storage_at_peak_Pa": [p.storage for p in self.peaks],
        }, {"EA_N": self.EA, "c_Ns_per_m": self.c, "window_Hz": self.window_hz})

    def plot(self, ax=None, **kw):
        """G', G'' against f with and without IFs, peaks marked, on a pair of axes (or a new figure); returns them."""
        from .._results import plotter

        no_if_figure = plotter("no_if_figure")

        return no_if_figure(self, axes=ax, **kw)


def no_if_study(
    prestress=(100.0, 250.0, 500.0, 1000.0, 2000.0, 4500.0),
    f_hz=np.logspace(-2, 5, 71),
    *,
    EA: float = 1.0,
    c: float = 1.0,
    reference_P: float = 1000.0,
    EA_values=(0.1, 1.0, 10.0, 100.0, 1000.0),
    c_values=(0.1, 1.0, 10.0),
    window_hz: float = PAPER_WINDOW_HZ,
) -> NoIFStudy:
    """The cell without intermediate filaments: moduli, the G'' peak and its dependence on P, EA, c.

    Parameters
    ----------
    prestress : array_like
        Prestresses P (N).
    f_hz : array_like
        Frequencies (Hz) of the curves (the peak search spans 10⁻⁴–10⁸ Hz).
    EA, c : float
        Uniform tendon stiffness (N) and damping (N·s/m).
    reference_P : float
        Prestress (N) of the EA and c scans.
    EA_values, c_values : array_like
        The uniform EA (N) and c (N·s/m) of the scans.
    window_hz : float
        Upper end of the frequency window (Hz) for ``window_prestress``.
    """
    Ps = grid("prestress", prestress, "N")
    f = grid("frequency", f_hz, "Hz")
    EA, c = positive_scalar("EA", EA, "N"), positive_scalar("c", c, "N·s/m")
    cell = paper_cell(intermediate_filaments=False)
    cell_if = paper_cell()
    without = frequency_response(cell, f, Ps, EA=EA, c=c)
    with_ifs = frequency_response(cell_if, f, Ps, EA=EA, c=c)
    peaks = [loss_peak(linearize(cell, P=P, EA=EA, c=c)) for P in Ps]
    peaks_EA = [(float(e), loss_peak(linearize(cell, P=reference_P, EA=e, c=c))) for e in grid("EA_values", EA_values, "N")]
    peaks_c = [(float(x), loss_peak(linearize(cell, P=reference_P, EA=EA, c=x))) for x in grid("c_values", c_values, "N·s/m")]
    lin = linearize(cell, P=reference_P, EA=EA, c=c)
    lam, V = lin.pencil.damping_modes  # C0's eigenpairs: V[:, 0] is the undamped mechanism
    v = V[:, 0]
    resid = float(np.linalg.norm(cell.A.T @ v) / np.linalg.norm(cell.A))
    # as ω → ∞ only the undamped mechanism v can move: J → (D0·v)²/(vᵀK0v), and vᵀK0v = P·vᵀKp v
    limit = float(continuum_factor(cell.strut_length) * (v @ cell.Kp @ v) / (lin.D0 @ v) ** 2)
    fp = np.array([p.frequency_hz for p in peaks])
    hp = np.array([p.height for p in peaks])
    a = float(np.polyfit(np.log(Ps), np.log(fp), 1)[0]) if Ps.size > 1 else math.nan
    b = float(np.polyfit(np.log(Ps), np.log(hp), 1)[0]) if Ps.size > 1 else math.nan
    window_hz = positive_scalar("window_hz", window_hz, "Hz")
    window = _crossing(Ps, fp, window_hz, a)
    return NoIFStudy(
        without=without, with_ifs=with_ifs, peaks=peaks, peaks_EA=peaks_EA, peaks_c=peaks_c, c0_eigenvalues=lam,
        mechanism_residual=resid, storage_limit_per_P=limit, peak_exponents=(a, b), window_prestress=window,
        cell=cell, cell_if=cell_if, EA=EA, c=c, reference_P=float(reference_P), window_hz=window_hz,
    )


def _crossing(Ps, fp, f_cross, exponent) -> float:
    """Prestress (N) where the peak frequency reaches ``f_cross``: log-log interpolation within the
    computed prestresses, the fitted power law ``f_peak ∝ P^exponent`` beyond them (NaN from one prestress)."""
    if Ps.size < 2:
        return math.nan
    lf, lP = np.log(fp), np.log(Ps)
    order = np.argsort(lf)
    x = math.log(f_cross)
    if lf[order[0]] <= x <= lf[order[-1]]:
        return float(math.exp(np.interp(x, lf[order], lP[order])))
    k = int(order[0] if x < lf[order[0]] else order[-1])
    return float(math.exp(lP[k] + (x - lf[k]) / exponent))


# ---- the study protocol (tenscell study no-if) -----------------------------------------------------------------
#: the study's work in units of one point of the references' validity map (:func:`tenscell.studies._common.
#: reference_probe`): the cell without IFs (its reference a root of det A in δ) and then 14 G'' peaks, 12 moduli
#: curves and C0's eigenpairs, as measured (bench/calibrate_study_units.py)
NO_IF_UNITS = 80.0


class _NoIF:
    """``tenscell study no-if``: one task (the study's defaults), calibrated by a few reference cells."""

    name = "no-if"
    options: dict = {}

    def plan(self, options):
        from .references import REFERENCE_PROBE
        from .protocol import Plan, Task, study_options

        return Plan(self.name, study_options(self, options), (Task("no-if: moduli and G'' peaks", "reference point",
                                                                   no_if_study, weight=NO_IF_UNITS),),
                    calibration=(REFERENCE_PROBE,), figures=6.8)

    def assemble(self, plan, results):
        from .._results import reporter
        from .protocol import Figure, StudyResult, Table

        s = results["no-if: moduli and G'' peaks"]
        moduli = Table.from_records("no_if_moduli", [
            {"prestress": P, "frequency_Hz": f, "G_storage_noIF": a, "G_loss_noIF": b, "G_storage_IF": c,
             "G_loss_IF": d} for (P, f, a, b), (_, _, c, d) in zip(s.without.rows(), s.with_ifs.rows())])
        peaks = Table.from_records("no_if_peaks", [
            {"prestress": float(P), "peak_frequency_Hz": p.frequency_hz, "peak_G_loss": p.height,
             "G_storage_at_peak": p.storage} for P, p in zip(s.without.prestress, s.peaks)])
        return StudyResult(self.name, tables=(moduli, peaks),
                           figures=(Figure("no_if_moduli.png", "no_if_figure", (s,)),
                                    Figure("no_if_peaks.png", "no_if_peaks_figure", (s,))),
                           pages=(("no_if.md", reporter("no_if_markdown")(s)),), data=s)


#: the study of ``tenscell study no-if`` (:mod:`tenscell.studies.protocol`)
STUDY = _NoIF()

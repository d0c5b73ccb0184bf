"""What the structure carries: the share of dG'/dP and dG''/dP due to the geometric prestress stiffness.

The prestress enters the dynamic stiffness of a cell (:mod:`tenscell.linear.dynamic`)

``K(ω; P) = P·Σ_j T0_j ∇²l_j + Σ_j k*_j(ω; P·T0_j) a_j a_jᵀ``

in two ways, and its derivative splits exactly into three parts:

``dK/dP = Σ T0_j ∇²l_j``                      (*transverse*: a taut tendon resists rotation),
``      + Σ T0_j (1/l_j) a_j a_jᵀ``            (*axial*: the rest length follows the tension, Eq. 11),
``      + Σ T0_j (∂k*_j/∂T − 1/l_j) a_j a_jᵀ``  (*constitutive*: a tension term of the tendon law).

The first two together are the paper's geometric prestress stiffness ``Kp``
(``K0 = P·Kp + Σ EA_j K_j``, Sultan et al. 2004, model notes "Linearization"):
the mechanism by which a tensegrity stiffens with its prestress. The third is
whatever the tendon law adds on top — the active springpot ``beta·T`` of
:class:`~tenscell.laws.TensionSpringpot`, a strain-stiffening filament — and
is zero for the paper's Voigt tendons, :class:`~tenscell.laws.Maxwell`,
:class:`~tenscell.laws.StandardLinearSolid` and :class:`~tenscell.laws.Springpot`.

Because ``J = D0 K⁻¹ b`` is linear in a perturbation of K, each part gives its
own ``dJ`` from the same solves as J (:func:`tenscell.linear.dynamic.dynamic_compliance`
with directions in k*; the transverse part through the homogeneity of K in
(P, k*): ``P ∂J/∂P|_k* = −J − dJ[k*]``), and ``dG*/dP = −G*·(dJ/dP)/J``
splits the same way (the cytoplasm's ``iωη`` does not depend on P). Exact,
with no finite differences.

Over a range of prestresses the *share* of a part is its integral over the
range divided by the whole change: ``ΔG'_geometric / ΔG'`` with
``ΔG' = G'(P_hi) − G'(P_lo)`` (Simpson's rule on an odd number of prestresses,
checked against the direct difference: :attr:`StructureShares.closure`).
A share is undefined where the whole change is within rounding of zero (then NaN),
and it can lie outside [0, 1] when the parts have opposite signs.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._checks import positive_array, positive_scalar
from .._results import format_repr
from .. import laws as _laws
from ..linear.assembly import modulus
from ..model.prestress import PRESTRESS_CONVENTION
from .anchor import Anchor, anchor_of, sigma_per_model_prestress

if TYPE_CHECKING:
    from .derived import DerivedQuantities

__all__ = ["StructureShares", "structure_shares", "prestress_parts", "StructureSummary", "structure_summary",
           "PrestressScale", "prestress_scale", "share_quantities", "GAUGE_WINDOW_L", "GAUGE_WINDOW_S",
           "PASSENGER_SHARE", "CARRIES_SHARE"]

#: prestresses (odd: Simpson's rule) on which the parts are integrated over the range
DEFAULT_POINTS = 17


@dataclass(frozen=True, eq=False, repr=False)
class StructureShares:
    """The prestress derivative of G* split into what the structure and the tendon law carry.

    Attributes
    ----------
    mechanism : str
    frequency_hz : ndarray, shape (nf,)
        Frequencies (Hz) at which the derivatives are taken.
    prestress_pa : ndarray, shape (np,)
        Measured prestresses (Pa) of the grid; NaN when the data state no prestress (then
        :attr:`prestress_n` is the fitted model prestress, a single point).
    prestress_n : ndarray, shape (np,)
        Model prestress P (N) on the reference cell at each grid point (``s × prestress_pa``).
    G : ndarray of complex, shape (np, nf)
        G' + iG'' (Pa), cytoplasm included.
    dG_transverse, dG_axial, dG_constitutive : ndarray of complex, shape (np, nf)
        The three parts of ``dG*/dP`` (Pa per Pa of measured prestress when it is stated, else Pa per N of
        model prestress); their sum is ``dG*/dP``.
    """

    mechanism: str
    frequency_hz: np.ndarray
    prestress_pa: np.ndarray
    prestress_n: np.ndarray
    G: np.ndarray
    dG_transverse: np.ndarray
    dG_axial: np.ndarray
    dG_constitutive: np.ndarray

    @property
    def dG_geometric(self) -> np.ndarray:
        """The paper's ``P·Kp`` part of ``dG*/dP`` (transverse + axial), shape (np, nf)."""
        return self.dG_transverse + self.dG_axial

    @property
    def dG(self) -> np.ndarray:
        """``dG*/dP``, shape (np, nf)."""
        return self.dG_geometric + self.dG_constitutive

    @property
    def _x(self) -> np.ndarray:
        return self.prestress_pa if np.all(np.isfinite(self.prestress_pa)) else self.prestress_n

    def _integral(self, d: np.ndarray) -> np.ndarray:
        """∫ d over the prestress grid (Simpson), shape (nf,); the value itself for a single point."""
        x = self._x
        if x.size == 1:
            return d[0]
        from scipy.integrate import simpson

        return simpson(d, x=x, axis=0)

    def share(self, part: str = "geometric", modulus_part: str = "storage") -> np.ndarray:
        """Share of the change of G' (``"storage"``) or G'' (``"loss"``) over the range carried by a part.

        ``part`` is ``"geometric"`` (the paper's P·Kp), ``"transverse"``, ``"axial"`` or ``"constitutive"``.
        Shape (nf,); NaN where the whole change is within 1e-9 of the modulus (no change to share).
        """
        parts = {"geometric": self.dG_geometric, "transverse": self.dG_transverse, "axial": self.dG_axial,
                 "constitutive": self.dG_constitutive}
        if part not in parts:
            raise ValueError(f"part must be one of {', '.join(parts)}, got {part!r}")
        if modulus_part not in ("storage", "loss"):
            raise ValueError(f"modulus_part must be 'storage' or 'loss', got {modulus_part!r}")
        take = np.real if modulus_part == "storage" else np.imag
        num, den = take(self._integral(parts[part])), take(self._integral(self.dG))
        scale = np.max(np.abs(take(self.G)), axis=0)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(np.abs(den) > 1e-9 * scale, num / den, np.nan)

    @property
    def geometric_share_storage(self) -> float:
        """Share of ΔG' over the range carried by the geometric prestress stiffness (first frequency)."""
        return float(self.share("geometric", "storage")[0])

    @property
    def geometric_share_loss(self) -> float:
        """Share of ΔG'' over the range carried by the geometric prestress stiffness (first frequency)."""
        return float(self.share("geometric", "loss")[0])

    @property
    def closure(self) -> float:
        """Largest |∫dG*/dP − (G*(hi) − G*(lo))| / |G*(hi)| over the frequencies: the integration's error (0 for one point)."""
        if self._x.size == 1:
            return 0.0
        direct = self.G[-1] - self.G[0]
        return float(np.max(np.abs(self._integral(self.dG) - direct) / np.abs(self.G[-1])))

    def __repr__(self) -> str:
        from .._results import span

        x = self.prestress_pa if np.all(np.isfinite(self.prestress_pa)) else None
        where = f"{span(x, 'Pa')}" if x is not None else f"P = {self.prestress_n[0]:.4g} N (fitted)"
        return format_repr(
            f"StructureShares of {self.mechanism} over {where} at {span(self.frequency_hz, 'Hz')}",
            f"geometric prestress stiffness (P·Kp): {self.share('geometric', 'storage')[0]:.1%} of ΔG', "
            f"{self.share('geometric', 'loss')[0]:.1%} of ΔG''",
            f"constitutive tension terms: {self.share('constitutive', 'storage')[0]:.1%} of ΔG', "
            f"{self.share('constitutive', 'loss')[0]:.1%} of ΔG''",
        )

    def to_dataframe(self):
        """One row per (prestress, frequency): G', G'' and the three parts of dG'/dP and dG''/dP."""
        from .._results import dataframe

        npts, nf = self.G.shape
        unit = "per_Pa" if np.all(np.isfinite(self.prestress_pa)) else "Pa_per_N"
        cols = {"prestress_Pa": np.repeat(self.prestress_pa, nf), "prestress_model_N": np.repeat(self.prestress_n, nf),
                "frequency_Hz": np.tile(self.frequency_hz, npts),
                "G_storage_Pa": self.G.real.ravel(), "G_loss_Pa": self.G.imag.ravel()}
        for name, d in (("transverse", self.dG_transverse), ("axial", self.dG_axial),
                        ("constitutive", self.dG_constitutive)):
            cols[f"dG_storage_dP_{name}_{unit}"] = d.real.ravel()
            cols[f"dG_loss_dP_{name}_{unit}"] = d.imag.ravel()
        return dataframe(cols, {"mechanism": self.mechanism})


def prestress_parts(problem, phi, P: float, omega) -> tuple[np.ndarray, np.ndarray]:
    """G* (Pa) and ``P·dG*/dP`` in its three parts at one model prestress, averaged over the assignments.

    Parameters
    ----------
    problem : MechanismProblem
        Gives the mechanism's law values per tendon (:meth:`~MechanismProblem.law_values`), cell and viscosity.
    phi : ndarray
        The problem's log-parameters (all of them, :meth:`~MechanismProblem.full`).
    P : float
        Model prestress (N).
    omega : ndarray, shape (nf,)
        Angular frequencies (rad/s).

    Returns
    -------
    G : ndarray of complex, shape (nf,)
    PdG : ndarray of complex, shape (3, nf)
        ``P·dG*/dP`` (Pa): transverse, axial, constitutive.
    """
    from ..linear.dynamic import dynamic_compliance

    P = positive_scalar("P (prestress)", P, "N")
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    vals, _ = problem.law_values(phi)
    K, m = next(iter(vals.values())).shape
    law_cls = getattr(_laws, problem.mechanism.law)
    G_all = np.zeros((K, w.size), dtype=complex)
    parts = np.zeros((K, 3, w.size), dtype=complex)
    l, T0 = problem.lengths, problem.T0
    T = P * T0
    for k in range(K):
        law = law_cls._trusted(**{n: v[k] for n, v in vals.items()})
        kstar = law.complex_stiffness(l, T, w)
        dk_dT, _ = law.complex_stiffness_derivatives(l, T, w)
        axial = np.broadcast_to(T / l, kstar.shape)
        constitutive = dk_dT * T[None] - axial
        J, dJ = dynamic_compliance(problem.cell, P, kstar, np.stack([kstar, axial, constitutive]))
        PdJ = np.stack([-J - dJ[0], dJ[1], dJ[2]])  # P ∂J/∂P by part (module docstring)
        Gs = modulus(J, problem.L_ref)
        G_all[k] = Gs
        parts[k] = -Gs[None] * PdJ / J[None]
    G = G_all.mean(axis=0)
    if problem.eta_index is not None:
        G = G + 1j * w * math.exp(phi[problem.eta_index])
    return G, parts.mean(axis=0)


def _scale_and_range(problem, phi, prestress_pa, frequency_hz):
    """(s or None, the prestress grid's ends in Pa or the fitted P in N, frequencies in Hz) for a problem."""
    names = list(problem.names)
    s = math.exp(phi[names.index("s")]) if "s" in names else None
    measured = np.asarray(problem.group_measured, dtype=float)
    known = np.isfinite(measured)
    if frequency_hz is None:
        if problem.omega.size == 0:
            raise ValueError("frequency_hz is required: this problem has no data points")
        pts = np.isin(problem.group_index, np.flatnonzero(known)) if known.any() else np.ones(problem.n_points, bool)
        frequency_hz = np.unique(problem.omega[pts]) / (2 * np.pi)
    if s is not None and prestress_pa is None:
        if not known.any():
            raise ValueError("prestress_pa is required: no data set of this problem states a prestress")
        prestress_pa = (float(measured[known].min()), float(measured[known].max()))
    P_fit = None
    if s is None:
        P_fit = float(np.exp(problem.group_log_offset + problem.group_map @ phi[problem.prestress_slice])[0])
    return s, prestress_pa, P_fit, frequency_hz


def structure_shares(model, theta=None, *, prestress_pa=None, frequency_hz=None,
                     points: int = DEFAULT_POINTS) -> StructureShares:
    """The share of dG'/dP and dG''/dP carried by the geometric prestress stiffness, over a prestress range.

    Parameters
    ----------
    model : MechanismProblem or FittedMechanism
        A mechanism problem at free log-parameters ``theta`` (as the search returns them), or a
        fitted mechanism.
    theta : array_like, optional
        The free log-parameters; required with a problem, refused with a fitted mechanism.
    prestress_pa : (float, float), optional
        The measured prestress range (Pa); default the range the data state (a problem), or the
        prestresses the fit saw (a fitted mechanism). A fit with no stated prestress (its prestress P
        is fitted in N) gives the local derivative at that P instead.
    frequency_hz : float or array_like, optional
        Frequencies (Hz); default those of the data sets that state a prestress (all points when none does).
    points : int
        Prestresses of the grid (odd, ≥ 3: Simpson's rule).

    Returns
    -------
    StructureShares

    Raises
    ------
    ValueError
        Missing ``theta`` or frequencies, a bad range, an even or too small ``points``, or a cell that is not
        stable at a prestress of the range.
    """
    from .models.mechanism import FittedMechanism

    if isinstance(points, bool) or not isinstance(points, int) or points < 3 or points % 2 == 0:
        raise ValueError(f"points must be an odd integer >= 3 (Simpson's rule), got {points!r}")
    if isinstance(model, FittedMechanism):
        if theta is not None:
            raise ValueError("theta is given by the fitted mechanism itself; pass theta only with a MechanismProblem")
        problem, phi = model._problem, model._phi
        s, P_fit = model.s, model.P
        if s is not None and prestress_pa is None:
            if not model.prestress_pa:
                raise ValueError("prestress_pa is required: the fitted mechanism records no prestress")
            prestress_pa = (min(model.prestress_pa), max(model.prestress_pa))
        if frequency_hz is None:
            raise ValueError("frequency_hz is required with a fitted mechanism (it records no frequencies)")
    else:
        if theta is None:
            raise ValueError("theta (the free log-parameters) is required with a MechanismProblem")
        phi = problem_phi = model.full(np.asarray(theta, dtype=float))
        problem = model
        s, prestress_pa, P_fit, frequency_hz = _scale_and_range(model, problem_phi, prestress_pa, frequency_hz)
    f = np.atleast_1d(positive_array("frequency", frequency_hz, unit="Hz")).ravel()
    if s is not None:
        lo, hi = (positive_scalar("prestress_pa lower", prestress_pa[0], "Pa"),
                  positive_scalar("prestress_pa upper", prestress_pa[1], "Pa"))
        if lo > hi:
            raise ValueError(f"prestress_pa must be (low, high) with low <= high (Pa), got {prestress_pa!r}")
        # one stated prestress (a frequency sweep at 1000 Pa): the local derivative there, as without a scale
        p_pa = np.linspace(lo, hi, points) if lo < hi else np.array([lo])
        P_n = s * p_pa
    else:
        p_pa, P_n = np.array([np.nan]), np.array([positive_scalar("P (fitted prestress)", P_fit, "N")])
    G = np.empty((P_n.size, f.size), dtype=complex)
    parts = np.empty((3, P_n.size, f.size), dtype=complex)
    for i, P in enumerate(P_n):
        try:
            G[i], PdG = prestress_parts(problem, phi, float(P), 2 * np.pi * f)
        except np.linalg.LinAlgError:
            raise ValueError(f"the {problem.mechanism.name} cell is not stable at P = {P:.4g} N") from None
        per = p_pa[i] if s is not None else P  # d/d(measured Pa) = (P dG/dP)/p; d/dP (N) when no scale
        parts[:, i] = PdG / per
    return StructureShares(mechanism=problem.mechanism.name, frequency_hz=f, prestress_pa=p_pa, prestress_n=P_n,
                           G=G, dG_transverse=parts[0], dG_axial=parts[1], dG_constitutive=parts[2])


# ---- what a fit report shows: the shares with their standard errors, the prestress against the measured one ----
#: the gauge window: strut lengths (m, on the paper's convention: the model prestress in N equal to the measured
#: prestress in Pa) of 0.1–10, i.e. s ∈ [0.01, 100] m² on a cell of strut length 1 m. A window on the gauge, not an
#: anchor: it spans 10⁴ in P/L² and never binds on the bundled data; the physical anchor is
#: :class:`tenscell.fitting.anchor.Anchor` (σ held to the measured prestress)
GAUGE_WINDOW_L = (0.1, 10.0)
#: the same window as the prestress scale s = (L_cell/L)² (m², L_cell = 1 m): `tenscell fit --gauge-window`
GAUGE_WINDOW_S = (1.0 / GAUGE_WINDOW_L[1] ** 2, 1.0 / GAUGE_WINDOW_L[0] ** 2)
#: names of tenscell 0.x kept for one release: {old name: new name}
_RENAMED = {"ANCHORED_L": "GAUGE_WINDOW_L", "ANCHORED_S": "GAUGE_WINDOW_S"}


def __getattr__(name: str):
    if name in _RENAMED:
        import warnings

        new = _RENAMED[name]
        warnings.warn(f"tenscell.fitting.shares.{name} is deprecated: it is the gauge window, "
                      f"tenscell.fitting.shares.{new}; the prestress anchor is tenscell.fitting.anchor.Anchor",
                      DeprecationWarning, stacklevel=2)
        return globals()[new]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
#: a geometric share of ΔG' below this: the structure is a passenger (the tendon law's tension terms do the work)
PASSENGER_SHARE = 0.1
#: ... at or above this: the structure carries the prestress dependence (goal G1 of issue 26)
CARRIES_SHARE = 0.5
#: the tension terms of the laws that have them, in words (other laws: "the law's tension terms")
TENSION_TERMS = {"TensionSpringpot": "the active springpot β·T·(iω)^α_T"}
#: parts of the prestress derivative a summary reports, in the order of its table
SHARE_PARTS = ("geometric", "transverse", "axial", "constitutive")


def share_quantities(result) -> dict:
    """The shares of a fitted mechanism as flat arrays (per frequency of :func:`structure_shares`' default grid):
    ``{part}_{storage|loss}`` for each of :data:`SHARE_PARTS` and ``change_storage`` / ``change_loss``, the whole
    change ΔG', ΔG'' over the prestress range (Pa). Module level: :func:`tenscell.fitting.derived.derived_quantities`
    gives each its standard error (and may evaluate it in a worker)."""
    sh = structure_shares(result.problem, result.theta)
    out = {f"{part}_{mod}": sh.share(part, mod) for part in SHARE_PARTS for mod in ("storage", "loss")}
    total = sh._integral(sh.dG)
    out["change_storage"], out["change_loss"] = np.real(total), np.imag(total)
    return out


@dataclass(frozen=True, eq=False, repr=False)
class PrestressScale:
    """The fitted prestress against the measured one, and the strut length it means in the paper's convention.

    With a prestress scale ``s`` the model prestress on the fit's cell (strut length ``L_cell``) is ``P = s·p`` (N)
    for a measured prestress p (Pa). Moved along the exact gauge ``(P, EA, c, L) → (λ²P, λ²EA, λc, λL)`` to the
    cell whose prestress in N equals the measured one in Pa (the paper's convention), the strut length is
    ``L = L_cell/√s`` (s in m²); the gauge window is L in :data:`GAUGE_WINDOW_L`.

    The physical comparison is σ/measured (:attr:`sigma_ratio`): the model's prestress as a stress
    (:mod:`tenscell.model.prestress`, the mean normal stress of the tendons' virial stress) over the measured one,
    ``σ_P·s`` with ``σ_P`` the stress per unit P of the fit's cell; an anchored fit (:mod:`tenscell.fitting.anchor`)
    holds it within a factor (``anchor``).

    Attributes
    ----------
    s : float or None
        The prestress scale (m²); None when no data set states its prestress.
    s_error_ln : float or None
        Standard error of ln s (of s/L² under the Voigt cell's gauge); None when not determined.
    s_note : str
        Why there is no error, or which combination it is of.
    L_cell : float
        Strut length (m) of the cell the fit's prestresses refer to (the reference for a mechanism, the fitted L for
        the Voigt cell).
    measured_pa : tuple of float
        The prestresses the data state (Pa).
    fitted_pa : tuple of (int, float, float or None)
        ``(data set, fitted prestress in Pa, standard error)`` of the data sets that state none.
    P_N : float or None
        The fitted model prestress (N) when no data set states one.
    profile_s : tuple or None
        ``(lower, upper)`` of s at 95 % from its profile likelihood (None: no profile; an end None: open).
    s_at_bound : str or None
        ``"lower"`` or ``"upper"`` when s sits at a bound of the fit (then L_paper is a limit, not an estimate).
    sigma_per_P : float or None
        σ per unit model prestress (Pa/N) on the fit's cell (strut length ``L_cell``).
    anchor : Anchor or None
        The anchor the fit was made under (read from its bounds of s), None for a free fit.
    """

    s: float | None
    s_error_ln: float | None
    s_note: str
    L_cell: float
    measured_pa: tuple
    fitted_pa: tuple
    P_N: float | None = None
    profile_s: tuple | None = None
    s_at_bound: str | None = None
    sigma_per_P: float | None = None
    anchor: Anchor | None = None

    @property
    def sigma_ratio(self) -> float | None:
        """σ/measured: the model's physical prestress over the measured one (the same at every stated prestress:
        one scale s links them); None without a scale."""
        return None if self.s is None or self.sigma_per_P is None else self.sigma_per_P * self.s

    @property
    def L_paper(self) -> float | None:
        """``L_cell/√s`` (m): the strut length of the same fit with model prestress (N) = measured prestress (Pa)."""
        return None if self.s is None else self.L_cell / math.sqrt(self.s)

    @property
    def L_paper_error_ln(self) -> float | None:
        """Standard error of ln L_paper (half that of ln s)."""
        return None if self.s_error_ln is None else 0.5 * self.s_error_ln

    @property
    def ratio(self) -> float | None:
        """Model prestress on the reference cell (N) per measured prestress (Pa) at L_cell = 1 m: s/L_cell² (m²/m²),
        as a fraction of the measured one."""
        return None if self.s is None else self.s / self.L_cell**2

    @property
    def in_gauge_window(self) -> bool | None:
        """L_paper within :data:`GAUGE_WINDOW_L` (None without a scale)."""
        L = self.L_paper
        return None if L is None else bool(GAUGE_WINDOW_L[0] <= L <= GAUGE_WINDOW_L[1])

    @property
    def anchored(self) -> bool | None:
        """Deprecated: :attr:`in_gauge_window` (the window is not an anchor; see :attr:`anchor`)."""
        import warnings

        warnings.warn("tenscell.fitting.shares.PrestressScale.anchored is deprecated: it is "
                      "PrestressScale.in_gauge_window; the prestress anchor is PrestressScale.anchor",
                      DeprecationWarning, stacklevel=2)
        return self.in_gauge_window

    @property
    def profile_L(self) -> tuple | None:
        """The 95 % profile interval of s as strut lengths ``(shortest, longest)`` (m; None: open)."""
        if self.profile_s is None:
            return None
        lo, hi = self.profile_s
        return (None if hi is None else self.L_cell / math.sqrt(hi), None if lo is None else self.L_cell / math.sqrt(lo))

    def to_dict(self) -> dict:
        """JSON-ready dict."""
        return {"s_m2": self.s, "s_stderr_ln": self.s_error_ln, "s_note": self.s_note, "L_cell_m": self.L_cell,
                "model_over_measured": self.ratio, "L_paper_convention_m": self.L_paper,
                "L_paper_convention_stderr_ln": self.L_paper_error_ln, "gauge_window_m": list(GAUGE_WINDOW_L),
                "in_gauge_window": self.in_gauge_window, "sigma_per_P_Pa_per_N": self.sigma_per_P,
                "sigma_over_measured": self.sigma_ratio, "prestress_convention": PRESTRESS_CONVENTION,
                "anchor": None if self.anchor is None else self.anchor.to_dict(),
                "measured_prestress_Pa": list(self.measured_pa),
                "fitted_prestress_Pa": [{"dataset": k, "value": v, "stderr": e} for k, v, e in self.fitted_pa],
                "fitted_model_prestress_N": self.P_N,
                "s_at_bound": self.s_at_bound,
                "profile_s_95": None if self.profile_s is None else list(self.profile_s),
                "profile_L_paper_95": None if self.profile_L is None else list(self.profile_L)}


def prestress_scale(result) -> PrestressScale | None:
    """The fitted prestress against the measured one (:class:`PrestressScale`); None for a model without a cell."""
    if result.cell is None:
        return None
    pr = result.problem
    named = {p.name: p for p in result.parameters}
    errors = dict(zip((p.name for p in result.parameters), result.standard_errors))
    L_cell = named["L"].value if "L" in named else float(result.cell.strut_length)
    measured = tuple(float(x) for x in pr.group_measured if np.isfinite(x))
    fitted = tuple((int(n[7:-1]), named[n].value, errors[n][0]) for n in named if n.startswith("P_data["))
    if "s" not in named:
        P = [p.value for n, p in named.items() if n == "P" or n.startswith("P[")]
        return PrestressScale(s=None, s_error_ln=None, s_note="no data set states its prestress", L_cell=L_cell,
                              measured_pa=measured, fitted_pa=fitted, P_N=P[0] if P else None)
    rel, note = result.identifiability().relative_error("s")
    profile = getattr(result, "profile", None)
    span = None
    if profile is not None:
        try:
            iv = profile["s"].interval(0.95)
            span = (iv.lower, iv.upper)
        except KeyError:
            span = None
    return PrestressScale(s=named["s"].value, s_error_ln=rel, s_note=note, L_cell=L_cell, measured_pa=measured,
                          fitted_pa=fitted, profile_s=span, s_at_bound=named["s"].at_bound,
                          sigma_per_P=_sigma_per_P(result), anchor=anchor_of(result))


def _sigma_per_P(result) -> float | None:
    """σ per unit P of the fit's cell (Pa/N); None where the cell's nodes span no volume (a planar structure)."""
    try:
        return sigma_per_model_prestress(result)
    except ValueError:
        return None


@dataclass(frozen=True, eq=False, repr=False)
class StructureSummary:
    """What the structure carries in a fit (the numbers of the report's section and of fit.json ``structure``).

    Attributes
    ----------
    model : str
    law : str or None
        The tendon law of a mechanism (None for the Voigt cell: its tendons have no tension terms, and its prestress
        activity is :mod:`tenscell.fitting.prestress`).
    shares : StructureShares or None
        A mechanism's shares over the data's prestress range (None for the Voigt cell).
    quantities : DerivedQuantities or None
        :func:`share_quantities` with their standard errors (delta method).
    scale : PrestressScale
    """

    model: str
    law: str | None
    shares: StructureShares | None
    quantities: DerivedQuantities | None
    scale: PrestressScale

    def share_text(self, part: str = "geometric", modulus_part: str = "storage", i: int = 0) -> str:
        """``"2.1 ± 0.01 %"``: a share at frequency ``i`` with its standard error, both in percent."""
        q = self.quantities
        assert q is not None, "a mechanism's summary"
        key = f"{part}_{modulus_part}"
        v = float(q.values[key][i])
        if not math.isfinite(v):
            return "undefined (no change over the range)"
        if part in ("geometric", "constitutive") and self.law not in TENSION_TERMS:
            # no tension term in the law: P·Kp carries all of dG*/dP whatever the parameters (no error to give)
            exact = 100 if part == "geometric" else 0  # v is that to rounding
            return f"{exact} % (by construction: {self.law} tendons have no tension terms)"
        se, note = q.error(key, i)
        if se is None:
            return f"{100 * v:.3g} % (± not determined{' ' + note if note else ''})"
        return f"{100 * v:.3g} ± {100 * se:.2g} %"

    def share_verdict(self) -> str:
        """Who carries dG'/dP, in words ("" for the Voigt cell, whose tendons have no tension terms)."""
        if self.shares is None or self.quantities is None:
            return ""
        g = self.quantities.values["geometric_storage"]
        terms = TENSION_TERMS.get(self.law or "", "the tendon law's tension terms")
        f = self.shares.frequency_hz
        at = f"at {f[0]:.3g} Hz" if f.size == 1 else f"at {f[0]:.3g}–{f[-1]:.3g} Hz"
        over = (f"over {self.shares.prestress_pa[0]:.4g}–{self.shares.prestress_pa[-1]:.4g} Pa"
                if np.all(np.isfinite(self.shares.prestress_pa)) else
                f"at the fitted P = {self.shares.prestress_n[0]:.4g} N (locally)")
        share = (f"{self.share_text('geometric', 'storage')} of the change of G′ and "
                 f"{self.share_text('geometric', 'loss')} of G″ {over} {at}")
        if np.all(~np.isfinite(g)):
            return f"G′ does not change with the prestress {over}: there is no change to share."
        if np.nanmax(g) < PASSENGER_SHARE:
            return (f"**The structure is a passenger**: the geometric prestress stiffness P·Kp carries {share}; the "
                    f"rest is carried by {terms}. The prestress acts through the tendon law, not through the paper's "
                    "mechanism.")
        if np.nanmin(g) >= CARRIES_SHARE:
            return f"**The structure carries the prestress dependence**: the geometric prestress stiffness P·Kp carries {share}."
        return (f"The structure and the tendon law share the prestress dependence: the geometric prestress stiffness "
                f"P·Kp carries {share}; the rest is carried by {terms}.")

    def scale_verdict(self) -> str:
        """The fitted prestress against the measured one, in words ("" when no data set states its prestress)."""
        sc = self.scale
        if sc.s is None or sc.ratio is None or sc.L_paper is None:
            return ""
        where = "inside" if sc.in_gauge_window else "outside"
        held = "" if sc.anchor is None else f" (the fit held {sc.anchor.words})"
        sigma = "" if sc.sigma_ratio is None else (f"The model's physical prestress σ (the tendons' virial stress) is "
                                                   f"{sc.sigma_ratio:.3g} × the measured one{held}. ")
        return (f"{sigma}The model prestress P/L_cell² is {100 * sc.ratio:.3g} % of the measured one (s = {sc.s:.3g} "
                f"m²): a strut length L = {sc.L_paper:.3g} m in the paper's convention, {where} the gauge window "
                f"{GAUGE_WINDOW_L[0]:g}–{GAUGE_WINDOW_L[1]:g} m.")

    def verdict(self) -> str:
        """The finding in words: who carries dG'/dP, and whether the prestress is anchored."""
        return " ".join(t for t in (self.share_verdict(), self.scale_verdict()) if t)

    def __repr__(self) -> str:
        return format_repr(f"StructureSummary of {self.model}", self.verdict())

    def to_dict(self) -> dict:
        """JSON-ready dict (fit.json ``structure``): shares per frequency with standard errors, the prestress scale."""
        doc: dict = {"model": self.model, "law": self.law, "verdict": self.verdict(), "prestress": self.scale.to_dict(),
                     "shares": None}
        if self.shares is not None and self.quantities is not None:
            sh = self.shares
            doc["shares"] = {
                "frequency_Hz": sh.frequency_hz.tolist(),
                "prestress_range_Pa": ([float(sh.prestress_pa[0]), float(sh.prestress_pa[-1])]
                                       if np.all(np.isfinite(sh.prestress_pa)) else None),
                "prestress_model_N": [float(sh.prestress_n[0]), float(sh.prestress_n[-1])],
                "closure": sh.closure, "tension_terms": TENSION_TERMS.get(self.law or "", "the law's tension terms"),
                **self.quantities.to_dict()}
        return doc


def structure_summary(result) -> StructureSummary | None:
    """What the structure carries in a fit: a mechanism's shares of dG'/dP and dG''/dP with standard errors, and for
    every model with a cell the fitted prestress against the measured one. None for a structure-free formula.

    Parameters
    ----------
    result : FitResult

    Returns
    -------
    StructureSummary or None
    """
    from .derived import derived_quantities
    from .models.mechanism import MechanismProblem

    scale = prestress_scale(result)
    if scale is None:
        return None
    pr = result.problem
    if not isinstance(pr, MechanismProblem):
        return StructureSummary(model=result.spec.name, law=None, shares=None, quantities=None, scale=scale)
    shares = structure_shares(pr, result.theta)
    return StructureSummary(model=result.spec.name, law=pr.mechanism.law, shares=shares,
                            quantities=derived_quantities(result, share_quantities), scale=scale)

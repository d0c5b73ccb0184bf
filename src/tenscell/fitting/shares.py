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

import numpy as np

from .._checks import positive_array, positive_scalar
from .. import laws as _laws
from ..linear.assembly import modulus

__all__ = ["StructureShares", "structure_shares", "prestress_parts"]

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
        from .._results import format_repr, span

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
        if not lo < hi:
            raise ValueError(f"prestress_pa must be (low, high) with low < high (Pa), got {prestress_pa!r}")
        p_pa = np.linspace(lo, hi, points)
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

"""What a fit returns: FitResult with its parameters, curves and slopes."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._checks import positive_scalar
from ..io.data import RheologyData
from ..linear.linearize import linearize
from ..model.equilibrium import Cell
from ..response import compliance, log_slope

if TYPE_CHECKING:
    from .problem import FitProblem

__all__ = ["FitParameter", "FitAlternative", "FitCurve", "FitResult", "model_curve", "frequency_slopes",
           "prestress_slopes"]

# ---------------------------------------------------------------------------------
# public records
# ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class FitParameter:
    """One fitted (or fixed) parameter.

    Attributes
    ----------
    name : str
        ``"EA[j]"``, ``"EA_actin"``, ``"EA"``, ``"c"``, ``"c_actin"``, ``"P"``,
        ``"s"`` or ``"L"``.
    value : float
        In ``unit``.
    lower, upper : float
        Bounds (same unit); the fit works in log space between them.
    unit : str
    vary : bool
        False if the user fixed it.
    description : str
        What the parameter is (for a tendon: its nodes and family).
    """

    name: str
    value: float
    lower: float
    upper: float
    unit: str
    vary: bool = True
    description: str = ""

    @property
    def at_bound(self) -> str | None:
        """``"lower"`` or ``"upper"`` if a varied parameter sits at a bound (within 0.1 % in log), else None."""
        if not self.vary:
            return None
        span = math.log(self.upper / self.lower)
        x = math.log(self.value)
        if x - math.log(self.lower) <= 1e-3 * span:
            return "lower"
        if math.log(self.upper) - x <= 1e-3 * span:
            return "upper"
        return None

    def to_dict(self) -> dict:
        """JSON-ready dict."""
        return {
            "name": self.name, "value": self.value, "unit": self.unit, "lower": self.lower, "upper": self.upper,
            "vary": self.vary, "at_bound": self.at_bound, "description": self.description,
        }


@dataclass(frozen=True)
class FitAlternative:
    """A solution from another start that fits almost as well as the best.

    Attributes
    ----------
    start : int
        Index of the start (0-based).
    rms_log10_error : float
        RMS of the unweighted log10 residuals.
    parameters : tuple of FitParameter
    """

    start: int
    rms_log10_error: float
    parameters: tuple

    def to_dict(self) -> dict:
        """JSON-ready dict."""
        return {"start": self.start, "rms_log10_error": self.rms_log10_error,
                "parameters": {p.name: p.value for p in self.parameters}}


@dataclass(frozen=True, eq=False)
class FitCurve:
    """A model curve to draw beside the data (computed here, drawn by plotting).

    Attributes
    ----------
    x : ndarray, shape (k,)
        Frequency (Hz) for a frequency sweep, prestress (Pa) for a prestress sweep.
    G_storage, G_loss : ndarray, shape (k,)
        Model moduli (Pa).
    label : str
    rms_log10_error : float
    kind : {"frequency", "prestress"}
    """

    x: np.ndarray
    G_storage: np.ndarray
    G_loss: np.ndarray
    label: str
    rms_log10_error: float
    kind: str


# ---------------------------------------------------------------------------------
# the result
# ---------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class FitResult:
    """The outcome of :func:`fit`.

    Attributes
    ----------
    parameters : tuple of FitParameter
        Best-fit parameters (named, with bounds and whether a bound is hit).
    residuals : ndarray, shape (2N,)
        Unweighted ``log10 G_model − log10 G_data``: the N G' residuals, then the N G'' ones.
    rms_log10_error : float
        RMS of ``residuals`` (decades).
    tolerance : float
        The RMS the fit had to reach.
    converged : bool
        True if ``rms_log10_error <= tolerance``.
    message : str
        What happened, in words (including the optimizer's last message).
    data : RheologyData
    cell : Cell
        The reference cell (strut length ``L_ref``); the model at the fitted L is its scaled copy.
    problem : FitProblem
    theta : ndarray
        Free log-parameters of the best fit.
    tendons, damping : str
        The parametrization.
    starts : int
    seed : int or None
    elapsed_s : float
        Wall-clock time of the whole fit, all starts (s).
    n_evaluations : int
        Model evaluations over all starts.
    alternatives : tuple of FitAlternative
        Other starts' solutions with RMS within ``max(tolerance, 1.5 × best)``, best first.
    start_rms : tuple of float
        Final RMS of every start, in start order.
    history : tuple of (float, float)
        ``(seconds since the fit began, best RMS so far)`` at each improvement over all starts.
    history_theta : tuple of ndarray
        The free log-parameters at each entry of ``history``.
    """

    parameters: tuple
    residuals: np.ndarray
    rms_log10_error: float
    tolerance: float
    converged: bool
    message: str
    data: RheologyData
    cell: Cell
    problem: FitProblem
    theta: np.ndarray
    tendons: str
    damping: str
    starts: int
    seed: int | None
    elapsed_s: float
    n_evaluations: int
    alternatives: tuple
    start_rms: tuple
    history: tuple
    history_theta: tuple

    # -- accessors ------------------------------------------------------------------
    def value(self, name: str) -> float:
        """The value of parameter ``name`` (SI units)."""
        for p in self.parameters:
            if p.name == name:
                return p.value
        raise ValueError(f"no parameter named {name!r}; parameters: {', '.join(p.name for p in self.parameters)}")

    @property
    def EA(self) -> np.ndarray:
        """Stiffness of every tendon (N), shape (m,)."""
        vals = self.problem.values(self.theta)
        return vals[: self.problem.n_ea][self.problem.ea_groups]

    @property
    def c(self) -> np.ndarray:
        """Damping of every tendon (N·s/m), shape (m,)."""
        vals = self.problem.values(self.theta)
        return vals[self.problem.n_ea: self.problem.n_ea + self.problem.n_c][self.problem.c_groups]

    @property
    def L(self) -> float:
        """Fitted strut length (m)."""
        return float(self.problem.values(self.theta)[-1])

    @property
    def stiffness_spread(self) -> tuple[float, float, float]:
        """(min EA, max EA, decades = log10(max/min)) over the tendons (N, N, -)."""
        EA = self.EA
        return float(EA.min()), float(EA.max()), float(math.log10(EA.max() / EA.min()))

    @property
    def stiffness_spread_interior(self) -> tuple[float, float, float] | None:
        """Like :attr:`stiffness_spread`, over the tendons whose stiffness is not at a bound (None if none is)."""
        inside = np.array([self.parameters[g].at_bound is None for g in self.problem.ea_groups])
        if not inside.any():
            return None
        e = self.EA[inside]
        return float(e.min()), float(e.max()), float(math.log10(e.max() / e.min()))

    @property
    def n_at_bound(self) -> int:
        """How many varied parameters sit at a bound."""
        return sum(p.at_bound is not None for p in self.parameters)

    def prestress_model(self, prestress_pa=None) -> np.ndarray:
        """Model prestress P (N) for measured prestresses (Pa) of a prestress sweep, or the fitted P."""
        vals = self.problem.values(self.theta)
        if self.problem.kind == "prestress":
            if prestress_pa is None:
                raise ValueError("prestress_pa (Pa) is required for a prestress-sweep fit")
            return vals[-2] * np.asarray(prestress_pa, dtype=float)
        return np.array([vals[-2]])

    def moduli(self, f_hz, prestress_pa=None) -> tuple[np.ndarray, np.ndarray]:
        """Fitted model's G', G'' (Pa) at frequencies ``f_hz`` (Hz), computed by the core pipeline.

        For a prestress-sweep fit ``prestress_pa`` (Pa) is required and must
        broadcast with ``f_hz``; the model prestress is ``s·prestress_pa``.
        """
        f = np.atleast_1d(np.asarray(f_hz, dtype=float))
        if self.problem.kind == "prestress":
            Pm = np.atleast_1d(self.prestress_model(prestress_pa))
        else:
            Pm = self.prestress_model()
        f, Pm = np.broadcast_arrays(f, Pm)
        lam = self.L / self.problem.L_ref
        EA, c = self.EA / lam**2, self.c / lam
        Gs = np.empty(f.shape)
        Gl = np.empty(f.shape)
        for P in np.unique(Pm):
            sel = Pm == P
            lin = linearize(self.cell, P=P / lam**2, EA=EA, c=c, check=False)
            G = (0.5 / self.problem.L_ref) / compliance(lin, f[sel])
            Gs[sel], Gl[sel] = G.real, G.imag
        return Gs, Gl

    # -- output ---------------------------------------------------------------------
    def to_dict(self) -> dict:
        """JSON-ready summary: parameters, rms_log10_error, converged, time taken, alternatives..."""
        lo, hi, dec = self.stiffness_spread
        return {
            "data": self.data.source,
            "kind": self.data.kind,
            "n_points": self.data.n,
            "cell": self.cell.describe(),
            "tendons": self.tendons,
            "damping": self.damping,
            "rms_log10_error": self.rms_log10_error,
            "rms_log10_error_storage": float(np.sqrt(np.mean(self.residuals[: self.data.n] ** 2))),
            "rms_log10_error_loss": float(np.sqrt(np.mean(self.residuals[self.data.n:] ** 2))),
            "tolerance": self.tolerance,
            "converged": self.converged,
            "message": self.message,
            "time_s": self.elapsed_s,
            "starts": self.starts,
            "seed": None if self.seed is None else int(self.seed),
            "n_evaluations": self.n_evaluations,
            "n_free_parameters": self.problem.n_free,
            "n_residuals": self.problem.n_residuals,
            "parameters": [p.to_dict() for p in self.parameters],
            "tendon_stiffness_spread": {"min_N": lo, "max_N": hi, "decades": dec},
            "tendon_stiffness_spread_not_at_bounds": (
                None if self.stiffness_spread_interior is None else dict(
                    zip(("min_N", "max_N", "decades"), self.stiffness_spread_interior))),
            "residuals_log10": {"G_storage": self.residuals[: self.data.n].tolist(),
                                "G_loss": self.residuals[self.data.n:].tolist()},
            "start_rms": list(self.start_rms),
            "alternatives": [a.to_dict() for a in self.alternatives],
            "history": [{"time_s": t, "rms_log10_error": r} for t, r in self.history],
        }

    def _interior_text(self) -> str:
        inner = self.stiffness_spread_interior
        full = self.stiffness_spread
        if inner is None or inner == full:
            return ""
        return f"; {inner[0]:.3g} .. {inner[1]:.3g} N ({inner[2]:.1f} decades) without those at bounds"

    def report(self) -> str:
        """A readable plain-text report (in the spirit of lmfit's ``fit_report``)."""
        d = self.data
        lo, hi, dec = self.stiffness_spread
        lines = [
            "[[Fit statistics]]",
            f"    data:               {d.source} ({d.n} points, {d.kind} sweep)",
            f"    model:              {self.cell.describe()}; stiffness {self.tendons}, damping {self.damping}",
            f"    free parameters:    {self.problem.n_free} (residuals: {self.problem.n_residuals})",
            f"    rms log10 error:    {self.rms_log10_error:.5f} (tolerance {self.tolerance:g}): "
            + ("converged" if self.converged else "NOT converged"),
            f"    starts:             {self.starts} (seed {self.seed}), {self.n_evaluations} model evaluations, "
            f"{self.elapsed_s:.1f} s",
            f"    stiffness spread:   {lo:.3g} .. {hi:.3g} N ({dec:.1f} decades)" + self._interior_text(),
            f"    message:            {self.message}",
            "[[Parameters]]",
        ]
        width = max(len(p.name) for p in self.parameters)
        for p in self.parameters:
            flag = "" if p.vary else " (fixed)"
            if p.at_bound:
                flag += f" at {p.at_bound} bound"
            lines.append(f"    {p.name:<{width}} = {p.value:<12.6g} {p.unit:<6} "
                         f"[{p.lower:.3g}, {p.upper:.3g}]{flag}  {p.description}")
        lines.append("[[Residuals log10(model/data)]]")
        x = d.prestress if d.kind == "prestress" else d.frequency_hz
        xname = "P (Pa)" if d.kind == "prestress" else "f (Hz)"
        lines.append(f"    {xname:>10}  {'G_storage':>10}  {'G_loss':>10}")
        for i in range(d.n):
            lines.append(f"    {x[i]:>10.4g}  {self.residuals[i]:>+10.5f}  {self.residuals[d.n + i]:>+10.5f}")
        if self.alternatives:
            lines.append(f"[[Alternatives]] {len(self.alternatives)} other start(s) fit almost as well:")
            for a in self.alternatives:
                lines.append(f"    start {a.start}: rms {a.rms_log10_error:.5f}")
        return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------
# analyses of a fit
# ---------------------------------------------------------------------------------
def model_curve(result: FitResult, n: int = 200, label: str | None = None) -> FitCurve:
    """The fitted model on a dense grid spanning the data (for plots).

    Frequency sweep: ``n`` log-spaced frequencies over the data's range (Hz).
    Prestress sweep: ``n`` prestresses over the data's range (Pa) at the
    data's (first) frequency.
    """
    d = result.data
    if d.kind == "prestress":
        x = np.linspace(d.prestress.min(), d.prestress.max(), n)
        Gs, Gl = result.moduli(np.full(n, d.frequency_hz[0]), prestress_pa=x)
    else:
        x = np.logspace(math.log10(d.frequency_hz.min()), math.log10(d.frequency_hz.max()), n)
        Gs, Gl = result.moduli(x)
    if label is None:
        label = {"uniform": "homogeneous", "per-family": "per family", "per-tendon": "heterogeneous"}[result.tendons]
    return FitCurve(x=x, G_storage=Gs, G_loss=Gl, label=label, rms_log10_error=result.rms_log10_error, kind=d.kind)


def frequency_slopes(result: FitResult, f_lo: float = 0.01, f_hi: float = 100.0, n: int = 1000):
    """Local log-log slopes of the fitted G' and G'' on ``n`` log-spaced frequencies in [f_lo, f_hi] Hz.

    Returns
    -------
    f : ndarray (Hz), slope_storage : ndarray, slope_loss : ndarray
    """
    f = np.logspace(math.log10(positive_scalar("f_lo", f_lo, "Hz")), math.log10(positive_scalar("f_hi", f_hi, "Hz")),
                    int(n))
    if result.data.kind == "prestress":
        Gs, Gl = result.moduli(f, prestress_pa=float(np.median(result.data.prestress)))
    else:
        Gs, Gl = result.moduli(f)
    return f, log_slope(f, Gs), log_slope(f, Gl)


def prestress_slopes(result: FitResult, n: int = 100) -> tuple[float, float, float, float]:
    """Straight-line fit of the model's G', G'' against prestress over the data's range.

    Returns
    -------
    (dG'/dP, G'(0) intercept, dG''/dP, G''(0) intercept): slopes dimensionless (Pa/Pa),
    intercepts in Pa, from ``n`` prestresses spanning the data at its first frequency.
    """
    if result.data.kind != "prestress":
        raise ValueError("prestress_slopes needs a prestress-sweep fit")
    curve = model_curve(result, n=n)
    a1, b1 = np.polyfit(curve.x, curve.G_storage, 1)
    a2, b2 = np.polyfit(curve.x, curve.G_loss, 1)
    return float(a1), float(b1), float(a2), float(b2)

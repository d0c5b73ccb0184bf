"""The tensegrity against the phenomenological standard: the structural-damping law, AIC/BIC, held-out error.

The structural-damping law (Fabry et al., Phys Rev Lett 87:148102, 2001)

``G*(ω) = G0 (ω/Φ0)^(x−1) (1 + iη) Γ(2−x) cos(π(x−1)/2) + iωμ``,  ``η = tan(π(x−1)/2)``

is the curve cell rheology is usually summarized by. With ``α = x − 1`` the
power-law part is ``G0 Γ(1−α) (ω/Φ0)^α e^{iπα/2}``. ``Φ0`` is a fixed
frequency scale, not fitted (it only rescales G0): :data:`PHI0` = 1 rad/s
unless given, so that G0 is the modulus scale at ω = 1 rad/s. The fitted
parameters are G0 (Pa), x (between 1 and 2) and μ (Pa·s).

Information criteria, for residuals in log10 G with independent Gaussian errors
------------------------------------------------------------------------------
With ``n`` residuals (G′ and G″ of every point count separately):

* data with standard deviations (every residual divided by its ``s_i``, in
  decades): ``−2 ln L = Σ r_i² + Σ ln(2π s_i²)`` and ``k`` = number of
  model parameters;
* without them, one common σ is estimated by maximum likelihood,
  ``σ̂² = RSS/n``: ``−2 ln L = n ln(2π RSS/n) + n`` and ``k`` = model
  parameters + 1 (σ).

``AIC = −2 ln L + 2k`` and ``BIC = −2 ln L + k ln n``. The model parameters of
a tensegrity fit are its free parameters minus the exact strut-length gauge
(:meth:`FitProblem.gauge`). The likelihood is that of log10 G; every model is
scored on the same residuals, so the differences between models are what
count. A model with at least as many parameters as residuals can fit
anything; its AIC then says little, and the small-sample correction (AICc) is
undefined.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize
import scipy.special

from .._checks import positive_scalar
from .._results import CORRELATION_THRESHOLD, dataframe, format_repr, plus_minus
from .._threads import hot_path
from ..io.data import DataError, RheologyData

__all__ = [
    "PHI0",
    "structural_damping_moduli",
    "StructuralDampingProblem",
    "StructuralDampingFit",
    "fit_structural_damping",
    "information_criteria",
    "split_holdout",
    "ModelScore",
    "ModelComparison",
    "compare_models",
]

#: the fixed frequency scale Φ0 of the structural-damping law (rad/s)
PHI0 = 1.0
_LN10 = math.log(10.0)
_ALPHA_BOUNDS = (1e-3, 0.99)  # x − 1


def structural_damping_moduli(omega, G0: float, x: float, mu: float, phi0: float = PHI0) -> np.ndarray:
    """Complex modulus ``G*(ω)`` (Pa) of the structural-damping law at angular frequencies ``omega`` (rad/s).

    Parameters
    ----------
    omega : array_like, shape (k,)
        Angular frequencies ω = 2πf (rad/s).
    G0 : float
        Modulus scale (Pa) at ω = Φ0.
    x : float
        Power-law exponent plus one, 1 < x < 2 (G′ ∝ ω^(x−1)).
    mu : float
        Newtonian viscosity (Pa·s), ≥ 0.
    phi0 : float
        Frequency scale Φ0 (rad/s).
    """
    omega = np.asarray(omega, dtype=float)
    a = x - 1.0
    eta = math.tan(math.pi * a / 2)
    pl = G0 * (omega / phi0) ** a * (1 + 1j * eta) * math.gamma(2 - x) * math.cos(math.pi * a / 2)
    return pl + 1j * omega * mu


@dataclass(frozen=True, eq=False)
class StructuralDampingProblem:
    """Residuals and analytic Jacobian of the structural-damping law against a frequency sweep.

    ``theta = (ln G0, x − 1, ln μ)`` (``ln μ`` absent when ``newtonian`` is
    False). Residuals ``w·(log10 G_model − log10 G_data)``, G′ block then G″,
    as in :class:`tenscell.fitting.FitProblem`.
    """

    omega: np.ndarray
    y_obs: np.ndarray
    weights: np.ndarray
    phi0: float = PHI0
    newtonian: bool = True

    @property
    def n_params(self) -> int:
        """Number of parameters (3 with the Newtonian term, 2 without)."""
        return 3 if self.newtonian else 2

    @property
    def names(self) -> tuple:
        return ("G0", "x", "mu")[: self.n_params]

    def _parts(self, theta):
        G0, a = math.exp(theta[0]), float(theta[1])
        mu = math.exp(theta[2]) if self.newtonian else 0.0
        power = G0 * math.gamma(1 - a) * (self.omega / self.phi0) ** a * np.exp(0.5j * math.pi * a)
        return power, 1j * self.omega * mu, a

    def moduli(self, theta) -> np.ndarray:
        """Complex G* (Pa) at the data's frequencies."""
        power, newton, _ = self._parts(theta)
        return power + newton

    def residuals(self, theta) -> np.ndarray:
        """Weighted log10 residuals, shape (2N,)."""
        G = self.moduli(theta)
        return self.weights * (np.concatenate([np.log10(G.real), np.log10(G.imag)]) - self.y_obs)

    def jacobian(self, theta) -> np.ndarray:
        """Analytic Jacobian of :meth:`residuals`, shape (2N, n_params)."""
        power, newton, a = self._parts(theta)
        G = power + newton
        cols = [power, power * (np.log(self.omega / self.phi0) - scipy.special.digamma(1 - a) + 0.5j * math.pi)]
        if self.newtonian:
            cols.append(newton)
        dG = np.stack(cols, axis=1)
        rows = np.vstack([dG.real / (G.real[:, None] * _LN10), dG.imag / (G.imag[:, None] * _LN10)])
        return self.weights[:, None] * rows

    def jacobian_fd(self, theta, step: float = 1e-6) -> np.ndarray:
        """Central finite differences of :meth:`residuals` (the reference for tests)."""
        from .models.voigt import _central

        return _central(self.residuals, theta, step)


@dataclass(frozen=True, eq=False, repr=False)
class StructuralDampingFit:
    """The structural-damping law fitted to a frequency sweep.

    Attributes
    ----------
    G0 : float
        Modulus scale at ω = Φ0 (Pa).
    x : float
        1 + the power-law exponent of G′.
    mu : float
        Newtonian viscosity (Pa·s); 0 without the Newtonian term.
    phi0 : float
        Φ0 (rad/s), fixed.
    residuals : ndarray, shape (2N,)
        Unweighted ``log10 G_model − log10 G_data`` (G′ block, then G″).
    weighted_residuals : ndarray, shape (2N,)
    rms_log10_error : float
        RMS of ``residuals`` (decades).
    n_params : int
        Fitted parameters (3, or 2 without the Newtonian term).
    data : RheologyData
    message : str
        The optimizer's message.
    standard_errors : dict
        ``{"G0": (se Pa, note), "x": (se, note), "mu": (se Pa·s, note)}``:
        one standard error linearized at the optimum, by the same computation
        as a tensegrity fit's (:func:`tenscell.fitting.identifiability.identifiability`,
        σ from the residuals unless the data carry standard deviations); se
        None, with the reason in the note, when not determined.
    correlations : tuple of (str, str, float)
        Pairs of parameters with ``|ρ| >=`` :data:`~tenscell._results.CORRELATION_THRESHOLD`.
    """

    G0: float
    x: float
    mu: float
    phi0: float
    residuals: np.ndarray
    weighted_residuals: np.ndarray
    rms_log10_error: float
    n_params: int
    data: RheologyData
    message: str
    standard_errors: dict | None = None
    correlations: tuple = ()

    @property
    def eta(self) -> float:
        """Hysteresivity η = tan(π(x−1)/2) = G″/G′ of the power-law part."""
        return math.tan(math.pi * (self.x - 1) / 2)

    def moduli(self, f_hz) -> tuple[np.ndarray, np.ndarray]:
        """G′, G″ (Pa) at frequencies ``f_hz`` (Hz)."""
        G = structural_damping_moduli(2 * np.pi * np.atleast_1d(np.asarray(f_hz, dtype=float)), self.G0, self.x,
                                      self.mu, self.phi0)
        return G.real, G.imag

    def error(self, name: str) -> tuple[float | None, str]:
        """``(standard error, note)`` of ``"G0"`` (Pa), ``"x"`` or ``"mu"`` (Pa·s)."""
        if name == "mu" and self.n_params == 2:
            return None, "(no Newtonian term)"
        return (self.standard_errors or {}).get(name, (None, "(not computed)"))

    def report(self) -> str:
        """The fitted law, each value with its standard error (lmfit's convention), and the strong correlations."""
        lines = [f"[[Structural damping]] {self.data.source}: {self.data.n} points, rms log10 error "
                 f"{self.rms_log10_error:.5f}; Φ0 = {self.phi0:g} rad/s (fixed)"]
        for name, value, unit in (("G0", self.G0, "Pa"), ("x", self.x, ""), ("mu", self.mu, "Pa·s")):
            se, note = self.error(name)
            lines.append(f"    {name + ':':<4} {plus_minus(value, se, unit, note)}")
        lines.append(f"[[Correlations]] (unreported correlations are < {CORRELATION_THRESHOLD:.3f})")
        lines += [f"    C({a}, {b}) = {r:+.4f}" for a, b, r in self.correlations] or ["    none"]
        return "\n".join(lines) + "\n"

    def __repr__(self) -> str:
        return format_repr(
            "StructuralDampingFit",
            f"G0 = {plus_minus(self.G0, self.error('G0')[0], 'Pa', digits=4)} at Φ0 = {self.phi0:g} rad/s; "
            f"x = {plus_minus(self.x, self.error('x')[0], digits=4)} (η = {self.eta:.3f}); "
            f"μ = {plus_minus(self.mu, self.error('mu')[0], 'Pa·s', self.error('mu')[1], digits=4)}",
            f"{self.data.n} points; rms log10 error {self.rms_log10_error:.4g} decades",
        )

    def to_dict(self) -> dict:
        """JSON-ready dict (standard errors as ``*_stderr``, None when not determined, with ``*_stderr_note``)."""
        doc = {"G0_Pa": self.G0, "x": self.x, "eta": self.eta, "mu_Pa_s": self.mu, "phi0_rad_per_s": self.phi0,
               "rms_log10_error": self.rms_log10_error, "n_params": self.n_params, "message": self.message}
        for name, key in (("G0", "G0_Pa"), ("x", "x"), ("mu", "mu_Pa_s")):
            se, note = self.error(name)
            doc[f"{key}_stderr"] = se
            doc[f"{key}_stderr_note"] = note
        doc["correlations"] = [{"a": a, "b": b, "rho": r} for a, b, r in self.correlations]
        return doc

    def to_dataframe(self):
        """Data and model at the data's frequencies (``frequency_Hz``, ``G_storage_Pa``, ...)."""
        d = self.data
        Gs, Gl = self.moduli(d.frequency_hz)
        return dataframe({"frequency_Hz": d.frequency_hz, "G_storage_Pa": d.G_storage, "G_loss_Pa": d.G_loss,
                          "G_storage_model_Pa": Gs, "G_loss_model_Pa": Gl},
                         {"model": "structural damping", "phi0_rad_per_s": self.phi0})


def _one_prestress(data: RheologyData) -> bool:
    """A frequency sweep: no prestress column, or one stated prestress for every point."""
    return data.prestress is None or np.unique(data.prestress).size == 1


def _frequency_sweep(data, what: str) -> RheologyData:
    if not isinstance(data, RheologyData):
        raise ValueError(f"{what}: data must be a tenscell.io.data.RheologyData, got {type(data).__name__}")
    if not _one_prestress(data):
        raise DataError(f"{data.source}: {what} needs a frequency sweep; the structural-damping law has no "
                        "prestress dependence to fit a prestress sweep with")
    return data


def fit_structural_damping(data: RheologyData, *, phi0: float = PHI0, newtonian: bool = True) -> StructuralDampingFit:
    """Fit the structural-damping law to a frequency sweep (least squares on log10 G′, log10 G″).

    Parameters
    ----------
    data : RheologyData
        A frequency sweep with at least 2 points (3 with the Newtonian term).
        Standard deviations, when given, weight the residuals as in
        :func:`tenscell.fitting.fit`.
    phi0 : float
        Frequency scale Φ0 (rad/s), fixed.
    newtonian : bool
        Include the Newtonian term ``iωμ``.

    Returns
    -------
    StructuralDampingFit
    """
    data = _frequency_sweep(data, "fit_structural_damping")
    phi0 = positive_scalar("phi0", phi0, "rad/s")
    if data.n < 2:  # 2 residuals per point: 2 points carry 3 parameters
        raise DataError(f"{data.source}: {data.n} data point; the structural-damping law needs at least 2")
    omega = 2 * np.pi * data.frequency_hz
    prob = StructuralDampingProblem(
        omega=omega, y_obs=np.concatenate([np.log10(data.G_storage), np.log10(data.G_loss)]),
        weights=np.concatenate([data.weights_storage, data.weights_loss]), phi0=phi0, newtonian=newtonian)
    best = None
    for theta0 in _starts(data, omega, phi0, newtonian):
        lo, hi = _bounds(data, omega, newtonian)
        res = scipy.optimize.least_squares(prob.residuals, np.clip(theta0, lo + 1e-9, hi - 1e-9), jac=prob.jacobian,
                                           bounds=(lo, hi), method="trf", x_scale="jac", xtol=1e-12, ftol=1e-12,
                                           gtol=1e-12)
        if best is None or res.cost < best.cost:
            best = res
    assert best is not None  # _starts yields at least one start
    theta = best.x
    r_w = prob.residuals(theta)
    r = r_w / prob.weights
    errors, corr = _errors(prob, theta, *_bounds(data, omega, newtonian), sigma_known=data.has_sd)
    return StructuralDampingFit(
        G0=math.exp(theta[0]), x=1.0 + float(theta[1]), mu=math.exp(theta[2]) if newtonian else 0.0, phi0=phi0,
        residuals=r, weighted_residuals=r_w, rms_log10_error=float(np.sqrt(np.mean(r**2))),
        n_params=prob.n_params, data=data, message=str(best.message), standard_errors=errors, correlations=corr,
    )


@dataclass(frozen=True)
class _Named:
    """A parameter as :func:`~tenscell.fitting.identifiability.identifiability` reads it."""

    name: str
    value: float
    at_bound: str | None


@dataclass(frozen=True, eq=False)
class _LogParameters:
    """The structural-damping problem in ln-parameters ``(ln G0, ln(x − 1), ln μ)``, shaped as the problem
    :func:`~tenscell.fitting.identifiability.identifiability` analyses (no gauge, nothing fixed)."""

    problem: StructuralDampingProblem
    lower: np.ndarray  # bounds of the problem's own theta
    upper: np.ndarray

    @property
    def n_params(self) -> int:
        return self.problem.n_params

    @property
    def names(self) -> tuple:
        return ("G0", "x-1", "mu")[: self.n_params]

    @property
    def free(self) -> np.ndarray:
        return np.ones(self.n_params, dtype=bool)

    def gauge(self) -> np.ndarray:
        return np.zeros(self.n_params)

    def _theta(self, phi) -> np.ndarray:
        theta = np.array(phi, dtype=float)
        theta[1] = math.exp(phi[1])
        return theta

    def residuals(self, phi) -> np.ndarray:
        return self.problem.residuals(self._theta(phi))

    def jacobian(self, phi) -> np.ndarray:
        J = self.problem.jacobian(self._theta(phi))
        J[:, 1] *= math.exp(phi[1])  # d/d ln(x−1) = (x−1) d/d(x−1)
        return J

    def parameters(self, phi) -> list[_Named]:
        theta = self._theta(phi)
        span = self.upper - self.lower
        out = []
        for k, name in enumerate(self.names):
            at = ("lower" if theta[k] - self.lower[k] <= 1e-3 * span[k] else
                  "upper" if self.upper[k] - theta[k] <= 1e-3 * span[k] else None)
            out.append(_Named(name, float(math.exp(phi[k])), at))
        return out


def _errors(prob: StructuralDampingProblem, theta, lower, upper, *, sigma_known: bool) -> tuple[dict, tuple]:
    """Standard errors ``{"G0", "x", "mu"}`` and strong correlations, through the tensegrity fit's computation."""
    from .identifiability import identifiability

    phi = np.array(theta, dtype=float)
    phi[1] = math.log(theta[1])
    ident = identifiability(_LogParameters(prob, lower, upper), phi, sigma_known=sigma_known)
    values = {"G0": math.exp(theta[0]), "x-1": float(theta[1]), "mu": math.exp(theta[2]) if prob.newtonian else 0.0}
    out = {}
    pairs = [("G0", "G0"), ("x-1", "x")] + ([("mu", "mu")] if prob.newtonian else [])
    for name, key in pairs:
        rel, note = ident.relative_error(name)
        out[key] = (None if rel is None else values[name] * rel, note)
    rename = {"x-1": "x"}
    corr = tuple((rename.get(a, a), rename.get(b, b), r)
                 for a, b, r in ident.strong_correlations(CORRELATION_THRESHOLD))
    return out, corr


def _bounds(data, omega, newtonian):
    scale = float(np.median(np.hypot(data.G_storage, data.G_loss)))
    lo = [math.log(1e-8 * scale), _ALPHA_BOUNDS[0]]
    hi = [math.log(1e8 * scale), _ALPHA_BOUNDS[1]]
    if newtonian:
        w = float(np.exp(np.mean(np.log(omega))))
        lo.append(math.log(1e-12 * scale / w))
        hi.append(math.log(1e4 * scale / w))
    return np.array(lo), np.array(hi)


def _starts(data, omega, phi0, newtonian):
    """Starting points: the exponent from the G′ slope, G0 matched at the middle, μ on a grid."""
    slope = np.polyfit(np.log(omega), np.log(data.G_storage), 1)[0] if data.n >= 2 else 0.2
    a = float(np.clip(slope, 0.02, 0.9))
    i = data.n // 2
    G0 = data.G_storage[i] / (math.gamma(1 - a) * (omega[i] / phi0) ** a * math.cos(math.pi * a / 2))
    base = [math.log(G0), a]
    if not newtonian:
        return [np.array(base)]
    w_top = float(omega.max())
    mus = [float(np.median(data.G_loss)) / w_top * k for k in (1e-3, 1e-1, 1.0)]
    return [np.array(base + [math.log(m)]) for m in mus]


# ---------------------------------------------------------------------------------------
# information criteria and the comparison table
# ---------------------------------------------------------------------------------------
def information_criteria(weighted_residuals, k: int, *, sigma_known: bool, weights=None) -> tuple[float, float, float]:
    """``(AIC, BIC, −2 ln L)`` of Gaussian residuals in log10 G (see the module docstring for the convention).

    Parameters
    ----------
    weighted_residuals : array_like, shape (n,)
        ``w_i·(log10 G_model − log10 G_data)``.
    k : int
        Number of model parameters (σ is added here when it is estimated).
    sigma_known : bool
        True when the weights are ``1/s_i`` from the data's standard deviations.
    weights : array_like, shape (n,), optional
        The weights ``w_i = 1/s_i`` (decades⁻¹); required when ``sigma_known``.
    """
    r = np.asarray(weighted_residuals, dtype=float)
    n = r.size
    if sigma_known:
        if weights is None:
            raise ValueError("weights (1/standard deviation, per residual) are required when sigma_known is True")
        s = 1.0 / np.asarray(weights, dtype=float)
        m2logl = float(r @ r + np.sum(np.log(2 * np.pi * s**2)))
        kk = int(k)
    else:
        rss = float(r @ r)
        m2logl = n * math.log(2 * math.pi * rss / n) + n if rss > 0 else -math.inf
        kk = int(k) + 1
    return m2logl + 2 * kk, m2logl + kk * math.log(n), m2logl


def split_holdout(data: RheologyData, f_min: float, f_max: float) -> tuple[RheologyData, RheologyData]:
    """Split a frequency sweep into (training, held-out) at the frequencies in ``[f_min, f_max]`` (Hz).

    Raises
    ------
    ValueError
        For creep data or a prestress sweep, bad limits, or a window that leaves no point on one side.
    """
    if getattr(data, "kind", None) == "creep":  # CreepData: times, no frequencies to hold out
        raise ValueError(f"holdout: {data.source} is creep compliance J(t); a frequency window needs a frequency "
                         "sweep of G', G''")
    f_min = positive_scalar("holdout f_min", f_min, "Hz")
    f_max = positive_scalar("holdout f_max", f_max, "Hz")
    if not f_min < f_max:
        raise ValueError(f"holdout: FMIN must be below FMAX, got {f_min:g}:{f_max:g} Hz")
    if not _one_prestress(data):
        raise ValueError(f"holdout: {data.source} is a prestress sweep; a frequency window needs a frequency sweep")
    held = (data.frequency_hz >= f_min) & (data.frequency_hz <= f_max)
    if not held.any() or held.all():
        raise ValueError(f"holdout: the window {f_min:g}:{f_max:g} Hz holds {int(held.sum())} of the {data.n} points "
                         f"of {data.source}; it must leave points on both sides")
    return _subset(data, ~held, "training"), _subset(data, held, "held out")


def _subset(data: RheologyData, mask, what: str) -> RheologyData:
    def pick(a):
        return None if a is None else a[mask]

    return RheologyData(frequency_hz=data.frequency_hz[mask], G_storage=data.G_storage[mask],
                        G_loss=data.G_loss[mask], prestress=pick(data.prestress),
                        G_storage_sd=pick(data.G_storage_sd), G_loss_sd=pick(data.G_loss_sd),
                        source=f"{data.source} ({what})", comments=data.comments)


@dataclass(frozen=True)
class ModelScore:
    """One model's row in the comparison.

    Attributes
    ----------
    name : str
    n_params : int
        Model parameters (without σ; exact gauges removed).
    rms_log10_error : float
        RMS of the unweighted log10 residuals on the training data (decades).
    aic, bic : float
    holdout_rms_log10_error : float or None
        RMS of the log10 errors at the held-out points (decades).
    """

    name: str
    n_params: int
    rms_log10_error: float
    aic: float
    bic: float
    holdout_rms_log10_error: float | None = None

    def to_dict(self) -> dict:
        return {"model": self.name, "n_params": self.n_params, "rms_log10_error": self.rms_log10_error,
                "aic": self.aic, "bic": self.bic, "holdout_rms_log10_error": self.holdout_rms_log10_error}


@dataclass(frozen=True, eq=False, repr=False)
class ModelComparison:
    """Models fitted to the same data, with RMS, parameters, AIC, BIC and (optionally) held-out error.

    Attributes
    ----------
    scores : tuple of ModelScore
    n_residuals : int
        Residuals every model was scored on (training data).
    sigma_known : bool
        Whether the data's standard deviations set the likelihood.
    holdout : tuple of (float, float) or None
        The held-out window (Hz).
    n_holdout : int
        Held-out data points.
    convention : str
        How AIC and BIC are computed, in words.
    structural : StructuralDampingFit or None
        The structural-damping law's fit (its parameters with standard errors), when it was scored.
    """

    scores: tuple
    n_residuals: int
    sigma_known: bool
    holdout: tuple | None
    n_holdout: int
    convention: str
    structural: StructuralDampingFit | None = None

    def score(self, name: str) -> ModelScore:
        """The row of model ``name``."""
        for s in self.scores:
            if s.name == name:
                return s
        raise ValueError(f"no model named {name!r}; models: {', '.join(s.name for s in self.scores)}")

    def best(self, criterion: str = "aic") -> str:
        """Name of the model with the lowest ``criterion`` (``"aic"``, ``"bic"``, ``"holdout"``)."""
        key = {"aic": lambda s: s.aic, "bic": lambda s: s.bic,
               "holdout": lambda s: math.inf if s.holdout_rms_log10_error is None else s.holdout_rms_log10_error}
        if criterion not in key:
            raise ValueError(f"criterion must be one of {', '.join(key)}, got {criterion!r}")
        return min(self.scores, key=key[criterion]).name

    def __repr__(self) -> str:
        lines = [f"{s.name}: k={s.n_params}, rms {s.rms_log10_error:.3g}, AIC {s.aic:.1f}, BIC {s.bic:.1f}"
                 + ("" if s.holdout_rms_log10_error is None else f", held out {s.holdout_rms_log10_error:.3g}")
                 for s in self.scores]
        return format_repr(f"ModelComparison of {len(self.scores)} models on {self.n_residuals} residuals", *lines[:5])

    def to_dict(self) -> dict:
        return {"models": [s.to_dict() for s in self.scores], "n_residuals": self.n_residuals,
                "sigma_known": self.sigma_known, "holdout_Hz": None if self.holdout is None else list(self.holdout),
                "n_holdout_points": self.n_holdout, "convention": self.convention,
                "structural_damping": None if self.structural is None else self.structural.to_dict()}

    def to_dataframe(self):
        return dataframe({
            "model": [s.name for s in self.scores], "n_params": [s.n_params for s in self.scores],
            "rms_log10_error": [s.rms_log10_error for s in self.scores], "AIC": [s.aic for s in self.scores],
            "BIC": [s.bic for s in self.scores],
            "holdout_rms_log10_error": [s.holdout_rms_log10_error for s in self.scores]})


def _holdout_rms(moduli, held: RheologyData | None) -> float | None:
    if held is None:
        return None
    Gs, Gl = moduli(held.frequency_hz)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.concatenate([np.log10(Gs / held.G_storage), np.log10(Gl / held.G_loss)])
    return float(np.sqrt(np.mean(r**2))) if np.all(np.isfinite(r)) else math.inf


def _tensegrity_params(result) -> int:
    p = result.problem
    g = p.gauge()
    return p.n_free - (1 if np.all(p.free[g != 0]) else 0)


@hot_path
def compare_models(result, *, homogeneous=None, structural: StructuralDampingFit | bool | None = True,
                   held_out: RheologyData | None = None, holdout: tuple | None = None,
                   name: str | None = None) -> ModelComparison:
    """Score a tensegrity fit beside the homogeneous tensegrity and the structural-damping law.

    Parameters
    ----------
    result : FitResult
        The (heterogeneous) tensegrity fit; its data are the training data
        (several data sets for a joint fit: the law then is left out).
    homogeneous : FitResult, optional
        The homogeneous tensegrity (``tendons="uniform"``) fitted to the same data.
    structural : StructuralDampingFit or bool
        The structural-damping law fitted to the same data; True fits it here
        (frequency sweeps only), False leaves it out.
    held_out : RheologyData, optional
        Points the models were not fitted to (see :func:`split_holdout`); their
        RMS log10 error is reported for each model.
    holdout : (float, float), optional
        The held-out window (Hz), for the record.
    name : str, optional
        Row name of ``result`` (default from its stiffness layout).

    Returns
    -------
    ModelComparison
    """
    datasets = result.datasets
    sigma_known = all(d.has_sd for d in datasets)
    w = result.problem.weights
    rows = []

    def add(label, r_w, k, rms, moduli):
        aic, bic, _ = information_criteria(r_w, k, sigma_known=sigma_known, weights=w)
        rows.append(ModelScore(name=label, n_params=int(k), rms_log10_error=float(rms), aic=aic, bic=bic,
                               holdout_rms_log10_error=_holdout_rms(moduli, held_out)))

    label = name or {"per-tendon": "heterogeneous tensegrity", "per-family": "tensegrity, per-family stiffness",
                     "uniform": "homogeneous tensegrity"}[result.tendons]
    add(label, result.problem.residuals(result.theta), _tensegrity_params(result), result.rms_log10_error,
        result.moduli)
    if homogeneous is not None and homogeneous is not result:
        add("homogeneous tensegrity", homogeneous.problem.residuals(homogeneous.theta),
            _tensegrity_params(homogeneous), homogeneous.rms_log10_error, homogeneous.moduli)
    if structural is True:  # the law has no prestress dependence: one frequency sweep only
        one = len(datasets) == 1 and datasets[0].kind != "creep" and _one_prestress(datasets[0])
        structural = fit_structural_damping(datasets[0]) if one else None
    if isinstance(structural, StructuralDampingFit):
        add("structural damping (power law)", structural.weighted_residuals, structural.n_params,
            structural.rms_log10_error, structural.moduli)
    convention = (
        "Gaussian errors in log10 G with the data's standard deviations: −2 ln L = Σ r² + Σ ln(2π s²); "
        "k = model parameters" if sigma_known else
        "Gaussian errors in log10 G with one unknown σ (maximum likelihood, σ² = RSS/n): "
        "−2 ln L = n ln(2π RSS/n) + n; k = model parameters + 1 (σ)"
    ) + "; AIC = −2 ln L + 2k, BIC = −2 ln L + k ln n; tensegrity parameters exclude the exact strut-length gauge"
    return ModelComparison(scores=tuple(rows), n_residuals=int(w.size), sigma_known=sigma_known,
                           holdout=None if holdout is None else (float(holdout[0]), float(holdout[1])),
                           n_holdout=0 if held_out is None else held_out.n, convention=convention,
                           structural=structural if isinstance(structural, StructuralDampingFit) else None)

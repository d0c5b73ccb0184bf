"""Nonlinear equations of motion in time: oscillatory and step loading, slack, harmonics.

The paper's Eq. (6) without inertia (massless struts and nodes):

``A(q)·T(l(q), l'(q, q')) + H(q)·F(t) = 0``,  ``l' = A(q)ᵀ q'``,

with the exact ``A(q) = ∂l/∂q``, ``−H(q) = (∂x_load/∂q)ᵀ d`` (the load point's
virtual displacement along the load direction d) and a tendon law
``T(l, l')`` from :mod:`tenscell.laws`. For the Voigt law the
equation is linear in the velocities, ``C(q)·q' = −A(q)·T_el(q) − H(q)·F(t)``
with ``C(q) = Σ c_j a_j a_jᵀ``; for a nonlinear dashpot it is solved for ``q'``
by a Newton iteration at every evaluation. Either way the state is
``y = q − q0`` and ``q' = v(t, q)`` is integrated with a stiff implicit
method of :func:`scipy.integrate.solve_ivp` (BDF by default, Radau on
request) with the exact Jacobian ``∂v/∂q`` from the implicit-function
theorem:

``∂v/∂q = −C_eff⁻¹ [Σ_j (T_j ∇²l_j + ∂T_j/∂l a_j a_jᵀ + ∂T_j/∂l' a_j (∇²l_j q')ᵀ)
− F·∇²(d·x_load)]``,

``C_eff = Σ_j ∂T_j/∂l' a_j a_jᵀ`` over the taut tendons (the exact member
Hessians come from :func:`tenscell.model.equilibrium.member_geometry`).

**Slack.** Tendons are cables: each carries ``max(0, T(l, l'))``, spring
and dashpot alike, so a tendon whose tension would become negative goes
slack and carries nothing until its would-be tension is positive again.
The velocities then solve a complementarity problem (an active-set
iteration of exact linear solves for Voigt tendons, a semismooth Newton
iteration otherwise); its solution is continuous in q, so no restart is
needed and a tendon sliding at zero force causes no chattering. Every
switch is located by solve_ivp's event root finding on the tendon's
constitutive tension and recorded as a :class:`SlackEvent` (time, tendon,
family, kind). No tendon ever carries compression. Members of family
``"strut"`` are bilateral and never go slack.

**Loads.** :class:`SineForce` and :class:`StepForce` prescribe the force F
at the load point; :class:`SineDisplacement` prescribes the probe
displacement z(t), the force being the Lagrange multiplier of the
constraint ``D(q)·q' = z'(t) + γ(z(t) − z(q))`` (γ = 10ω removes drift).

**Steady state.** :func:`oscillatory_response` starts from the linear
periodic steady state (so only the nonlinear part of the transient is
left), integrates whole cycles sampled uniformly, and projects the last
cycle(s) on the harmonics of the forcing: ``J = ẑ₁/F̂₁`` (m/N), ``G' + iG'' =
(0.5/L)/J`` (Pa, the sign convention of :func:`tenscell.compliance`), the
total harmonic distortion, the work done by the load per cycle and the
energy dissipated in the tendons per cycle (they are equal in a periodic
state). The periodicity error compares the last two cycles.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

from ._checks import finite_scalar, positive_array, positive_scalar
from .laws import LinearizationError, TendonLaw
from .model.coordinates import kinematics
from .model.equilibrium import Cell, assemble_hessian, equilibrium_matrix, member_geometry, point_vector
from .linear.linearize import LinearModel, NotPositiveDefiniteError
from .response import compliance
from .model.structure import STRUT
from .timedomain import creep_spectrum

__all__ = [
    "SineForce",
    "StepForce",
    "SineDisplacement",
    "SimulationError",
    "SlackEvent",
    "MotionState",
    "EquationsOfMotion",
    "Simulation",
    "simulate",
    "linearize_law",
    "linear_steady_state",
    "Harmonics",
    "harmonics",
    "OscillatoryResponse",
    "oscillatory_response",
    "AmplitudeSweep",
    "amplitude_sweep",
    "CreepResponse",
    "creep_response",
]


class SimulationError(ValueError):
    """The time integration cannot proceed (singular damping, no convergence, forbidden slack)."""


# ---- loads ---------------------------------------------------------------------------
@dataclass(frozen=True)
class _Sinusoid:
    """``amplitude·sin(2π f t)``: shared by the force- and displacement-controlled loads."""

    amplitude: float
    frequency_hz: float
    _unit = ""

    def __post_init__(self):
        object.__setattr__(self, "amplitude", positive_scalar("amplitude", self.amplitude, self._unit))
        object.__setattr__(self, "frequency_hz", positive_scalar("frequency", self.frequency_hz, "Hz"))

    @property
    def omega(self) -> float:
        """Angular frequency ω = 2πf (rad/s)."""
        return 2.0 * math.pi * self.frequency_hz

    @property
    def period(self) -> float:
        """Period 1/f (s)."""
        return 1.0 / self.frequency_hz

    @property
    def phasor(self) -> complex:
        """Complex amplitude X with ``value(t) = Re(X e^{iωt})``: ``−i·amplitude`` (N or m)."""
        return -1j * self.amplitude

    def value(self, t) -> float:
        """The force F(t) (N) or the prescribed displacement z(t) (m)."""
        return self.amplitude * np.sin(self.omega * t)

    def rate(self, t) -> float:
        """Its time derivative (N/s or m/s)."""
        return self.amplitude * self.omega * np.cos(self.omega * t)


@dataclass(frozen=True)
class SineForce(_Sinusoid):
    """``F(t) = amplitude·sin(2π f t)`` at the load point, along its direction.

    Parameters
    ----------
    amplitude : float
        Force amplitude (N), > 0.
    frequency_hz : float
        Forcing frequency f (Hz), > 0.
    """

    controls = "force"
    _unit = "N"


@dataclass(frozen=True)
class SineDisplacement(_Sinusoid):
    """Prescribed probe displacement ``z(t) = amplitude·sin(2π f t)``; the load force follows.

    Parameters
    ----------
    amplitude : float
        Displacement amplitude (m), > 0.
    frequency_hz : float
        Frequency f (Hz), > 0.
    """

    controls = "displacement"
    _unit = "m"


@dataclass(frozen=True)
class StepForce:
    """A force ``amplitude`` applied at t = 0 and held (creep test).

    Parameters
    ----------
    amplitude : float
        Step force (N), finite and nonzero; positive along the load direction.
    """

    amplitude: float
    controls = "force"

    def __post_init__(self):
        a = finite_scalar("amplitude", self.amplitude, "a finite, nonzero force (N)")
        if a == 0:
            raise ValueError("amplitude must be a finite, nonzero force (N), got 0.0")
        object.__setattr__(self, "amplitude", a)

    period = None

    def value(self, t) -> float:
        """Force (N) for t ≥ 0 (the state at t = 0 is the unloaded reference)."""
        return self.amplitude

    def rate(self, t) -> float:
        """dF/dt = 0 for t > 0 (N/s)."""
        return 0.0


_LOADS = (SineForce, StepForce, SineDisplacement)


# ---- one evaluation of the equations of motion -----------------------------------------
@dataclass(frozen=True, eq=False)
class SlackEvent:
    """A tendon going slack (``kind="slack"``) or taut again (``kind="taut"``).

    Attributes
    ----------
    time : float
        When (s).
    tendon : int
        Tendon index (order of ``cell.structure.tendons``).
    family : str
        Its family (``"actin"``, ``"intermediate_filament"``, ...).
    kind : str
        ``"slack"`` or ``"taut"``.
    """

    time: float
    tendon: int
    family: str
    kind: str


@dataclass(frozen=True, eq=False)
class MotionState:
    """Everything the equations of motion give at one time and configuration.

    Attributes
    ----------
    t : float
        Time (s).
    q : ndarray, shape (n,)
        Generalized coordinates (m, rad).
    v : ndarray, shape (n,)
        Their rates q' (m/s, rad/s).
    force : float
        Load force F (N): prescribed, or the reaction under displacement control.
    z : float
        Probe displacement from the reference, along the probe direction (m).
    u : float
        Load-point displacement along the load direction (m).
    u_rate : float
        Its rate (m/s); ``F·u_rate`` is the power the load puts in (W).
    lengths, rates : ndarray, shape (m,)
        Tendon lengths l (m) and rates l' (m/s).
    tensions : ndarray, shape (m,)
        Tensions carried (N); 0 for slack tendons.
    trial : ndarray, shape (m,)
        Constitutive tension ``T(l, l')`` (N), also for slack tendons (where it is ≤ 0).
    taut : ndarray of bool, shape (m,)
        Which tendons carry load.
    power : float
        Power dissipated in the tendons (W): ``Σ (T_j − max(T_el,j, 0))·l'_j`` (≥ 0).
    """

    t: float
    q: np.ndarray
    v: np.ndarray
    force: float
    z: float
    u: float
    u_rate: float
    lengths: np.ndarray
    rates: np.ndarray
    tensions: np.ndarray
    trial: np.ndarray
    taut: np.ndarray
    power: float


class EquationsOfMotion:
    """The massless equations of motion of a cell with a tendon law under a load.

    Parameters
    ----------
    cell : Cell
    law : TendonLaw
        One entry per working tendon (e.g. :func:`tenscell.laws.voigt_law`).
    loading : SineForce, StepForce or SineDisplacement

    Notes
    -----
    The public methods take the state ``y = q − q0`` (what is integrated).
    A cable carries ``max(0, T(l, l'))``, so the velocities solve the
    complementarity problem ``Σ_j a_j max(0, T_j(l_j, a_jᵀq')) = −H·F``;
    it is solved by a semismooth Newton iteration with a line search,
    started from the previous solution (for a Voigt law with the right
    taut set that is a single linear solve). Its solution is a continuous
    function of the configuration, so a tendon may even stay taut at zero
    force (shortening at the free rate of its Voigt element) without any
    chattering. Passing ``taut`` instead imposes which tendons carry load
    (no complementarity), e.g. to test the Jacobian of one branch.

    The object remembers its last few evaluations and the last velocity (the
    Newton starting guess); that is the only state it keeps.

    Raises
    ------
    SimulationError
        If the damping matrix ``C(q0)`` is singular (e.g. the cell without
        intermediate filaments: its massless equations are then a
        differential-algebraic system this integrator does not handle).
    """

    def __init__(self, cell: Cell, law: TendonLaw, loading):
        if not isinstance(loading, _LOADS):
            raise ValueError(f"loading must be a SineForce, StepForce or SineDisplacement, got {type(loading).__name__}")
        if getattr(law, "m", None) != cell.m:
            raise ValueError(f"the tendon law has {getattr(law, 'm', '?')} tendons but the cell has {cell.m}")
        self.cell, self.law, self.loading = cell, law, loading
        self.coords = cell.coords
        self.q0 = np.asarray(cell.q0, dtype=float)
        self.n, self.m = cell.n, cell.m
        self.cable = np.array([f != STRUT for f in cell.structure.families], dtype=bool)
        self.displacement_control = loading.controls == "displacement"
        self.gamma = 10.0 * loading.omega if self.displacement_control else 0.0
        geom0 = cell.geometry
        idx = np.where(geom0.index < 0, self.n, geom0.index)
        self._idx = idx
        self._flatK = (idx[:, :, None] * (self.n + 1) + idx[:, None, :]).ravel()
        self._memo: dict = {}
        self._warm: tuple | None = None
        kin0 = kinematics(self.coords, self.q0)
        self._p_load0 = self._position(cell.structure.load, kin0)
        self._p_probe0 = self._position(cell.structure.probe, kin0)
        #: tension below which a cable counts as slack in reports and events (N): 1e-9 of the largest tension at rest
        self.slack_tolerance = 1e-9 * max(float(np.abs(law.elastic(cell.lengths)).max()), 1e-300)
        try:
            self.state(0.0, np.zeros(self.n), np.ones(self.m, dtype=bool))
        except SimulationError as err:
            raise SimulationError(
                f"{cell.describe()}: {err}. The massless equations need a positive definite damping matrix "
                "C(q) = Σ dT/dl'·a aᵀ (for the cell without intermediate filaments C0 is singular)"
            ) from None

    # -- geometry helpers
    @staticmethod
    def _position(point, kin) -> float:
        d = np.asarray(point.direction)
        return float(sum(w * (kin.x[nd] @ d) for nd, w in zip(point.nodes, point.weights)))

    def _point_hessian(self, point, kin) -> np.ndarray:
        H = np.zeros((self.n + 1, self.n + 1))
        d = np.asarray(point.direction)
        for nd, w in zip(point.nodes, point.weights):
            ix = np.where(kin.index[nd] < 0, self.n, kin.index[nd])
            np.add.at(H, (ix[:, None], ix[None, :]), w * np.einsum("x,xkl->kl", d, kin.hess[nd]))
        return H[: self.n, : self.n]

    def _geometry(self, q):
        # lengths and A(q) only: the member Hessians are needed by the Jacobian alone
        kin = kinematics(self.coords, q)
        try:
            geom = member_geometry(self.coords, q, kin, hessians=False)
        except ValueError as err:  # a tendon collapsed to zero length
            raise SimulationError(str(err)) from None
        l, grad = geom.lengths, geom.grad
        A = equilibrium_matrix(geom, sparse=False)
        st = self.cell.structure
        g = point_vector(self.coords, st.load, kin)
        D = g if st.probe == st.load else point_vector(self.coords, st.probe, kin)
        return kin, l, grad, A, g, D

    # -- the velocity solve
    def _solve(self, t, y, taut):
        key = (float(t), y.tobytes(), None if taut is None else taut.tobytes())
        hit = self._memo.get(key)
        if hit is not None:
            return hit
        q = self.q0 + y
        kin, l, grad, A, g, D = self._geometry(q)
        z = self._position(self.cell.structure.probe, kin) - self._p_probe0
        zrhs = None
        if self.displacement_control:
            zrhs = self.loading.rate(t) + self.gamma * (self.loading.value(t) - z)
            F = 0.0
        else:
            F = float(self.loading.value(t))
        if self.law.rate_linear:
            if taut is not None:
                v, F, T, active, fac = self._linear_solve(A, g, D, l, F, zrhs, t, taut)
            else:
                v, F, T, active, fac = self._active_set(A, g, D, l, F, zrhs, t)
        else:
            v, F, T, active, fac = self._newton(A, g, D, l, F, zrhs, t, taut)
        u = A.T @ v
        _, dTdl, dTdv = self.law.derivatives(l, u)
        Tel = self.law.elastic(l)
        carried = np.where(active, T, 0.0)
        if taut is None:
            carried = np.where(self.cable, np.maximum(T, 0.0), T)
        power = float(np.sum((carried - np.where(self.cable, np.maximum(Tel, 0.0), Tel)) * u))
        shown = (~self.cable) | (T >= -self.slack_tolerance) if taut is None else taut.copy()
        state = MotionState(
            t=float(t), q=q, v=v, force=float(F), z=float(z),
            u=self._position(self.cell.structure.load, kin) - self._p_load0, u_rate=float(g @ v),
            lengths=l, rates=u, tensions=carried, trial=T, taut=shown, power=power,
        )
        extras = (kin, grad, A, g, D, dTdl, dTdv, active, fac)
        if len(self._memo) > 8:
            self._memo.clear()
        self._memo[key] = (state, extras)
        return state, extras

    def _factor(self, C, g, D, t, active):
        if self.displacement_control:
            M = np.zeros((self.n + 1, self.n + 1))
            M[: self.n, : self.n] = C
            M[: self.n, self.n] = -g
            M[self.n, : self.n] = D
            lu = scipy.linalg.lu_factor(M, check_finite=False)
            if not np.all(np.isfinite(lu[0])) or np.min(np.abs(np.diag(lu[0]))) <= 1e-14 * np.abs(lu[0]).max():
                raise SimulationError(f"the constrained damping system is singular at t={t:.6g} s")
            return ("lu", lu)
        try:
            return ("chol", scipy.linalg.cho_factor(C, lower=True, check_finite=False))
        except (np.linalg.LinAlgError, ValueError):
            slack = np.flatnonzero(~active & self.cable).tolist()
            raise SimulationError(
                f"the damping matrix C(q) is singular at t={t:.6g} s"
                + (f" with tendons {slack} slack" if slack else "")
                + ": part of the structure has no damping, so the massless equations do not determine its velocity"
            ) from None

    @staticmethod
    def _apply(fac, b):
        kind, f = fac
        return scipy.linalg.cho_solve(f, b, check_finite=False) if kind == "chol" else scipy.linalg.lu_solve(f, b, check_finite=False)

    def _linear_solve(self, A, g, D, l, F, zrhs, t, taut):
        """Rate-linear law with an imposed taut set: one linear solve."""
        Tel, _, cv = self.law.derivatives(l, np.zeros(self.m))
        w = taut.astype(float)
        fac = self._factor((A * (w * cv)) @ A.T, g, D, t, taut)
        rhs = -(A @ (w * Tel))
        if zrhs is None:
            v = self._apply(fac, rhs + g * F)
        else:
            x = self._apply(fac, np.r_[rhs, zrhs])
            v, F = x[: self.n], float(x[self.n])
        return v, F, Tel + cv * (A.T @ v), taut.copy(), fac

    def _active_set(self, A, g, D, l, F, zrhs, t):
        """Rate-linear law: primal-dual active-set iteration for the taut set (exact linear solves).

        Each pass solves with the current set and retakes as taut every cable
        whose (would-be) tension is positive; a consistent set ends it. The
        result depends on the configuration only, not on the starting set
        (the starting set is the previous one, so usually one pass).
        """
        S = self._warm[2] if self._warm is not None else np.ones(self.m, dtype=bool)
        seen = set()
        for _ in range(2 * self.m + 2):
            v, Fs, T, _, fac = self._linear_solve(A, g, D, l, F, zrhs, t, S)
            if np.all(T[S & self.cable] >= 0.0) and np.all(T[~S] <= 0.0):
                self._warm = (v, Fs, S.copy())
                return v, Fs, T, S.copy(), fac
            new = (~self.cable) | (T > 0.0)
            key = new.tobytes()
            if key in seen:
                break
            seen.add(key)
            S = new
        # the iteration cycles (possible at near-ties): fall back to the globalized semismooth Newton
        return self._newton(A, g, D, l, F, zrhs, t, None)

    def _newton(self, A, g, D, l, F, zrhs, t, taut):
        """Semismooth Newton with backtracking on |R| for ``A·[max(0, T)] = g·F`` (+ the displacement constraint)."""
        law, n = self.law, self.n
        disp = zrhs is not None
        v = np.zeros(n) if self._warm is None else self._warm[0].copy()
        if disp and self._warm is not None:
            F = self._warm[1]

        def evaluate(v, F):
            T, _, dTdv = law.derivatives(l, A.T @ v)
            if taut is None:
                act = (~self.cable) | (T > 0.0)
            else:
                act = taut
            Tc = np.where(act, T, 0.0)
            R = A @ Tc - g * F
            if disp:
                R = np.r_[R, D @ v - zrhs]
            return R, T, dTdv, act

        R, T, dTdv, act = evaluate(v, F)
        for _ in range(100):
            scale = np.abs(A) @ np.abs(np.where(act, T, 0.0)) + np.abs(g * F) + 1e-300
            fac = self._factor((A * np.where(act, dTdv, 0.0)) @ A.T, g, D, t, act)
            ok = np.abs(R[:n]).max() <= 1e-12 * scale.max()
            if ok and disp:
                ok = abs(R[n]) <= 1e-12 * (abs(zrhs) + np.abs(D).max() * np.abs(v).max() + 1e-300)
            if ok:
                break
            step = self._apply(fac, -R)
            if np.abs(step[:n]).max() <= 1e-13 * np.abs(v).max():
                # at the round-off floor of the force balance: take the last full step and stop
                v = v + step[:n]
                F = F + step[n] if disp else F
                R, T, dTdv, act = evaluate(v, F)
                fac = self._factor((A * np.where(act, dTdv, 0.0)) @ A.T, g, D, t, act)
                break
            r0 = np.linalg.norm(R)
            a = 1.0
            while True:
                vn = v + a * step[:n]
                Fn = F + a * step[n] if disp else F
                out = evaluate(vn, Fn)
                if np.linalg.norm(out[0]) <= (1.0 - 1e-4 * a) * r0:
                    break
                a *= 0.5
                if a < 1e-6:  # no descent along the Newton direction: the residual is at its round-off floor
                    out = None
                    break
            if out is None:
                break
            v, F = vn, Fn
            R, T, dTdv, act = out
        else:
            raise SimulationError(f"the velocity solve did not converge at t={t:.6g} s")
        self._warm = (v, F, np.asarray(act, dtype=bool).copy())
        return v, F, T, act, fac

    # -- public interface
    def state(self, t: float, y: np.ndarray, taut: np.ndarray | None = None) -> MotionState:
        """The :class:`MotionState` at time ``t`` (s) and ``y = q − q0``.

        ``taut`` (bool, shape (m,)) imposes which tendons carry load; by
        default cables carry ``max(0, T)`` (complementarity).
        """
        taut = None if taut is None else np.asarray(taut, dtype=bool)
        return self._solve(t, np.asarray(y, dtype=float), taut)[0]

    def velocity(self, t: float, y: np.ndarray, taut: np.ndarray | None = None) -> np.ndarray:
        """``q' = v(t, q0 + y)`` (m/s, rad/s), shape (n,)."""
        return self.state(t, y, taut).v

    def jacobian(self, t: float, y: np.ndarray, taut: np.ndarray | None = None) -> np.ndarray:
        """Exact ``∂q'/∂q`` (1/s), shape (n, n), by the implicit-function theorem (see module docstring).

        With slack possible it is the Jacobian of the branch (set of taut
        tendons) active at ``(t, y)``.
        """
        taut = None if taut is None else np.asarray(taut, dtype=bool)
        state, (kin, G, A, g, D, dTdl, dTdv, active, fac) = self._solve(t, np.asarray(y, dtype=float), taut)
        n = self.n
        w = active.astype(float)
        Hs = member_geometry(self.coords, state.q, kin).hess
        vloc = np.r_[state.v, 0.0][self._idx]
        Hv = np.einsum("mkl,ml->mk", Hs, vloc)
        T = state.trial
        blocks = (w * T)[:, None, None] * Hs + G[:, :, None] * ((w * dTdl)[:, None] * G + (w * dTdv)[:, None] * Hv)[:, None, :]
        K = np.bincount(self._flatK, weights=blocks.ravel(), minlength=(n + 1) ** 2).reshape(n + 1, n + 1)[:n, :n]
        st = self.cell.structure
        Hg = self._point_hessian(st.load, kin)
        if np.any(Hg):
            K = K - state.force * Hg
        if not self.displacement_control:
            return -self._apply(fac, K)
        Hp = Hg if st.probe == st.load else self._point_hessian(st.probe, kin)
        rhs = np.vstack([-K, -(Hp @ state.v + self.gamma * D)[None, :]])
        return self._apply(fac, rhs)[:n]


# ---- simulation ----------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Simulation:
    """A time history of the nonlinear model.

    Attributes
    ----------
    cell : Cell
    law : TendonLaw
    loading : SineForce, StepForce or SineDisplacement
    t : ndarray, shape (k,)
        Sample times (s).
    q : ndarray, shape (k, n)
        Generalized coordinates (m, rad).
    force : ndarray, shape (k,)
        Load force (N).
    z : ndarray, shape (k,)
        Probe displacement from the reference (m).
    u : ndarray, shape (k,)
        Load-point displacement along the load direction (m).
    u_rate : ndarray, shape (k,)
        Its rate (m/s).
    tensions : ndarray, shape (k, m)
        Tendon tensions (N), exactly 0 while slack.
    power : ndarray, shape (k,)
        Power dissipated in the tendons (W).
    taut : ndarray of bool, shape (k, m)
        Which tendons carry load at each sample.
    events : tuple of SlackEvent
        Every slack/taut switch, in time order.
    stats : dict
        Solver statistics: ``nfev``, ``njev``, ``nlu``.

    Notes
    -----
    Positions at the samples come from the solver's dense output. Rates
    recomputed there (``u_rate``, ``power``, and the force under displacement
    control) also carry the interpolation error of the fast relaxation modes
    multiplied by their rates; :func:`harmonics` therefore computes the work
    from the harmonics of positions and force.
    """

    cell: Cell
    law: object
    loading: object
    t: np.ndarray
    q: np.ndarray
    force: np.ndarray
    z: np.ndarray
    u: np.ndarray
    u_rate: np.ndarray
    tensions: np.ndarray
    power: np.ndarray
    taut: np.ndarray
    events: tuple
    stats: dict = field(default_factory=dict)

    @property
    def slack_tendons(self) -> list[int]:
        """Indices of the tendons that went slack at some time, ascending."""
        return sorted({e.tendon for e in self.events if e.kind == "slack"})

    def slack_summary(self) -> list[dict]:
        """One dict per tendon that went slack: index, family, first slack time (s), total slack time (s)."""
        out = []
        t_end = float(self.t[-1]) if self.t.size else 0.0
        for j in self.slack_tendons:
            evs = [e for e in self.events if e.tendon == j]
            first = next(e.time for e in evs if e.kind == "slack")
            total, since = 0.0, None
            for e in evs:
                if e.kind == "slack":
                    since = e.time
                elif since is not None:
                    total += e.time - since
                    since = None
            if since is not None:
                total += t_end - since
            out.append({"tendon": j, "family": evs[0].family, "first_slack_s": first, "slack_time_s": total,
                        "switches": len(evs)})
        return out


def _scale(eq: EquationsOfMotion, loading) -> float:
    """Size of the expected displacement of the coordinates (m or rad), for absolute tolerances."""
    law, cell = eq.law, eq.cell
    A = cell.A.toarray() if hasattr(cell.A, "toarray") else np.asarray(cell.A)
    T = law.elastic(cell.lengths)
    K = assemble_hessian(cell.geometry, T, sparse=False) + (A * law.stiffness_at_rest(cell.lengths)) @ A.T
    x = np.linalg.lstsq(K, np.asarray(cell.load), rcond=None)[0]
    if loading.controls == "displacement":
        zx = float(np.asarray(cell.probe) @ x)
        amp = abs(loading.amplitude) / abs(zx) if zx != 0 else 1.0
    else:
        amp = abs(loading.amplitude)
    return float(np.abs(x).max() * amp) or 1.0


def simulate(
    cell: Cell,
    law: TendonLaw,
    loading,
    t_end: float,
    *,
    t_eval=None,
    q_start=None,
    t_start: float = 0.0,
    method: str = "BDF",
    rtol: float = 1e-8,
    atol: float | None = None,
    jacobian: str = "analytic",
    slack: str = "allow",
    max_step: float | None = None,
) -> Simulation:
    """Integrate the nonlinear equations of motion from ``t_start`` to ``t_end``.

    Parameters
    ----------
    cell : Cell
    law : TendonLaw
        Tendon law with one entry per tendon, e.g. ``voigt_law(cell, P=1000)``.
    loading : SineForce, StepForce or SineDisplacement
    t_end : float
        Final time (s), > 0.
    t_eval : array_like, optional
        Output times (s) in ``[t_start, t_end]``; default: the solver's own steps.
    q_start : array_like, shape (n,), optional
        Initial coordinates (m, rad); default the reference ``q0`` (at rest).
    t_start : float
        Initial time (s), ``0 <= t_start < t_end``; to continue a simulation.
    method : {"BDF", "Radau", "LSODA"}
        Stiff solver of :func:`scipy.integrate.solve_ivp` (BDF is the fastest
        at equal accuracy on the paper cell; Radau is the alternative).
    rtol : float
        Relative tolerance; the state is ``q − q0``, so it is relative to the
        displacement, not to the coordinates. Below ~1e-9 the round-off of
        the prestress forces (~P, cancelling to ~F) sets a floor.
    atol : float, optional
        Absolute tolerance (m, rad); default ``rtol ×`` the size of the static
        linear response to the load amplitude.
    jacobian : {"analytic", "numeric"}
        Exact Jacobian (default) or solve_ivp's finite differences.
    slack : {"allow", "error"}
        Let tendons go slack and record it (default), or raise
        :class:`SimulationError` when one would go into compression.
    max_step : float, optional
        Largest step (s); default a sixteenth of the period for periodic loads.

    Returns
    -------
    Simulation
        Slack/taut switches are located by solve_ivp's event root finding on
        each cable's constitutive tension (slack below
        :attr:`EquationsOfMotion.slack_tolerance`).
    """
    t_end = positive_scalar("t_end", t_end, "s")
    t_start = finite_scalar("t_start", t_start, "a finite time (s)")
    if not 0.0 <= t_start < t_end:
        raise ValueError(f"t_start must satisfy 0 <= t_start < t_end={t_end:g} s, got {t_start!r}")
    rtol = positive_scalar("rtol", rtol)
    if method not in ("Radau", "BDF", "LSODA"):
        raise ValueError(f"method must be 'Radau', 'BDF' or 'LSODA' (stiff solvers), got {method!r}")
    if jacobian not in ("analytic", "numeric"):
        raise ValueError(f"jacobian must be 'analytic' or 'numeric', got {jacobian!r}")
    if slack not in ("allow", "error"):
        raise ValueError(f"slack must be 'allow' or 'error', got {slack!r}")
    eq = EquationsOfMotion(cell, law, loading)
    n = eq.n
    if t_eval is not None:
        t_eval = np.asarray(t_eval, dtype=float).ravel()
        if (t_eval.size == 0 or not np.all(np.isfinite(t_eval)) or t_eval.min() < t_start
                or t_eval.max() > t_end * (1 + 1e-12)):
            raise ValueError(f"t_eval must be finite times within [t_start={t_start:g}, t_end={t_end:g}] s")
        if np.any(np.diff(t_eval) <= 0):
            raise ValueError("t_eval must be strictly increasing")
        t_eval = np.minimum(t_eval, t_end)
    y = np.zeros(n) if q_start is None else np.asarray(q_start, dtype=float) - eq.q0
    if y.shape != (n,) or not np.all(np.isfinite(y)):
        raise ValueError(f"q_start must be {n} finite coordinates")
    if atol is None:
        atol = rtol * _scale(eq, loading)
    atol = positive_scalar("atol", atol)
    if max_step is None:
        max_step = loading.period / 16.0 if loading.period else np.inf
    max_step = positive_scalar("max_step", max_step, "s") if np.isfinite(max_step) else np.inf

    fam = cell.structure.families
    tol = eq.slack_tolerance
    cables = np.flatnonzero(eq.cable)
    st0 = eq.state(t_start, y)
    events: list[SlackEvent] = [SlackEvent(t_start, int(j), fam[j], "slack") for j in cables if not st0.taut[j]]
    if slack == "error" and events:
        raise SimulationError(f"tendon {events[0].tendon} ({events[0].family}) is slack at t={t_start:g} s")

    def make_event(j):
        def ev(t, yy):
            return float(eq.state(t, yy).trial[j]) + tol
        ev.terminal = slack == "error"
        ev.direction = -1 if slack == "error" else 0
        return ev

    sol = solve_ivp(
        lambda t, yy: eq.velocity(t, yy), (t_start, t_end), y, method=method, t_eval=t_eval,
        events=[make_event(j) for j in cables], rtol=rtol, atol=atol,
        jac=(lambda t, yy: eq.jacobian(t, yy)) if jacobian == "analytic" else None, max_step=max_step,
    )
    if sol.status == -1:
        raise SimulationError(f"time integration failed at t={sol.t[-1] if sol.t.size else t_start:.6g} s: {sol.message}")
    if sol.status == 1:
        k = next(i for i, te in enumerate(sol.t_events) if te.size)
        j = int(cables[k])
        raise SimulationError(
            f"tendon {j} ({fam[j]}) would go into compression at t={float(sol.t_events[k][0]):.6g} s "
            f"(load {loading!r}); run with slack='allow' to let it go slack"
        )
    for k, j in enumerate(cables):
        # the constitutive tension changes sign at each root, so the switches alternate
        slack_now = not st0.taut[j]
        for te in sol.t_events[k]:
            slack_now = not slack_now
            events.append(SlackEvent(float(te), int(j), fam[j], "slack" if slack_now else "taut"))
    events.sort(key=lambda e: (e.time, e.tendon))
    ts, ys = np.asarray(sol.t, dtype=float), np.asarray(sol.y, dtype=float).reshape(n, -1).T
    states = [eq.state(tk, yk) for tk, yk in zip(ts, ys)]

    def col(name):
        return np.array([getattr(s, name) for s in states], dtype=float)

    return Simulation(
        cell=cell, law=law, loading=loading, t=ts, q=np.array([s.q for s in states]).reshape(-1, n),
        force=col("force"), z=col("z"), u=col("u"), u_rate=col("u_rate"),
        tensions=np.array([s.tensions for s in states]).reshape(-1, eq.m), power=col("power"),
        taut=np.array([s.taut for s in states], dtype=bool).reshape(-1, eq.m), events=tuple(events),
        stats={"nfev": int(sol.nfev), "njev": int(sol.njev), "nlu": int(sol.nlu)},
    )


def _concat(a: Simulation, b: Simulation) -> Simulation:
    """``b`` continues ``a`` (its first sample repeats a's last one and is dropped)."""
    k = 1 if (a.t.size and b.t.size and b.t[0] <= a.t[-1]) else 0
    cat = lambda x, y: np.concatenate([x, y[k:]])  # noqa: E731
    stats = {key: a.stats.get(key, 0) + b.stats.get(key, 0) for key in set(a.stats) | set(b.stats)}
    # b records tendons already slack at its start as switches at that instant: they are not new
    t0 = b.t[0] if b.t.size else None
    new = tuple(e for e in b.events if not (e.time == t0 and e.kind == "slack" and not a.taut[-1, e.tendon]))
    return Simulation(
        cell=a.cell, law=a.law, loading=a.loading, t=cat(a.t, b.t), q=cat(a.q, b.q), force=cat(a.force, b.force),
        z=cat(a.z, b.z), u=cat(a.u, b.u), u_rate=cat(a.u_rate, b.u_rate), tensions=cat(a.tensions, b.tensions),
        power=cat(a.power, b.power), taut=cat(a.taut, b.taut), events=a.events + new, stats=stats,
    )


# ---- linearization of a law -----------------------------------------------------------
def linearize_law(cell: Cell, law: TendonLaw) -> LinearModel:
    """The linear model of a cell with any tendon law, about its reference at rest.

    ``K0 = Σ T_j ∇²l_j + Σ (∂T_j/∂l) a_j a_jᵀ`` and ``C0 = Σ (∂T_j/∂l')|₀ a_j a_jᵀ``
    with the exact law's rate derivative at ``l' = 0`` (for a power-law
    dashpot with β > 1 that is 0, so ``C0 = 0`` and ``G'' = 0``).

    Returns
    -------
    LinearModel
        ``P`` is the projection of the reference tensions on ``T0`` (N);
        ``EA`` holds ``l0·∂T/∂l`` (N), ``c`` the linearized damping (N·s/m).

    Raises
    ------
    LinearizationError
        If the law has no linearization at rest (power-law dashpot, β < 1).
    ValueError
        If the law's rest lengths do not hold the cell in equilibrium at its reference.
    NotPositiveDefiniteError
        If K0 is not positive definite.
    """
    if getattr(law, "m", None) != cell.m:
        raise ValueError(f"the tendon law has {getattr(law, 'm', '?')} tendons but the cell has {cell.m}")
    A = cell.A.toarray() if hasattr(cell.A, "toarray") else np.asarray(cell.A)
    l = cell.lengths
    T = law.elastic(l)
    k = np.asarray(law.stiffness_at_rest(l), dtype=float)
    # tolerance relative to the tensions and to their round-off: T = EA(l/l0 − 1) carries an
    # error of order eps·EA, which dominates for stiff tendons at a small prestress (a fitted cell)
    resid = np.abs(A @ T)
    bound = np.abs(A) @ (1e-8 * np.abs(T) + 16 * np.finfo(float).eps * np.abs(k) * l)
    if np.any(resid > bound):
        i = int(np.argmax(resid - bound))
        raise ValueError(
            f"the tendon law's rest lengths do not hold {cell.describe()} in equilibrium at its reference "
            f"(|A·T| = {resid[i]:.3g} N at coordinate {i}, tolerance {bound[i]:.3g} N); build it with "
            "voigt_law/power_dashpot_law, which use Eq. (11)"
        )
    c0 = np.asarray(law.damping_at_rest(l), dtype=float)  # raises LinearizationError for β < 1
    K0 = assemble_hessian(cell.geometry, T, sparse=False) + (A * k) @ A.T
    C0 = (A * c0) @ A.T
    try:
        np.linalg.cholesky(K0)
    except np.linalg.LinAlgError:
        raise NotPositiveDefiniteError(
            f"K0 of {cell.describe()} with this tendon law is not positive definite: the reference is not stable"
        ) from None
    return LinearModel(
        cell=cell, P=float(T @ cell.T0), EA=k * law.l0, c=c0, K0=K0, C0=C0,
        H0=-np.asarray(cell.load), D0=np.asarray(cell.probe), l0=np.asarray(law.l0),
    )


def linear_steady_state(lin: LinearModel, loading) -> np.ndarray:
    """Coordinates ``q(0)`` (m, rad) of the linear periodic steady state under a sinusoidal load.

    ``q(t) = q0 + Re(q̂ e^{iωt})`` with ``q̂ = (K0 + iωC0)⁻¹ b F̂``; for a
    prescribed displacement ``F̂ = ẑ/J(ω)``.
    """
    if not isinstance(loading, (SineForce, SineDisplacement)):
        raise ValueError("a periodic steady state needs a SineForce or SineDisplacement loading")
    w = loading.omega
    Z = lin.K0 + 1j * w * lin.C0
    x = np.linalg.solve(Z, (-lin.H0).astype(complex))
    Fhat = loading.phasor if loading.controls == "force" else loading.phasor / (lin.D0 @ x)
    return np.asarray(lin.cell.q0) + (x * Fhat).real


# ---- harmonic analysis ---------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Harmonics:
    """Fourier analysis of a periodic steady state over whole forcing cycles.

    Complex amplitudes ``X_h`` are such that a signal is
    ``X_0 + Σ_h Re(X_h e^{i h ω t})`` (``X_0`` the mean).

    Attributes
    ----------
    frequency_hz : float
        Forcing frequency (Hz).
    cycles : int
        Number of cycles analysed (the last ones of the simulation).
    response : ndarray of complex, shape (H+1,)
        Probe displacement harmonics (m).
    force : ndarray of complex, shape (H+1,)
        Load force harmonics (N).
    L : float
        Strut length (m).
    thd : float
        Total harmonic distortion of the response signal (z under force
        control, F under displacement control): ``sqrt(Σ_{h≥2}|X_h|²)/|X_1|``.
    periodicity : float
        ``max|x(t) − x(t − T)|/max|x − mean|`` over the last cycle (NaN if
        only one cycle was simulated).
    work_per_cycle : float
        Work done by the load per cycle, ``∮ F du`` (J).
    dissipated_per_cycle : float
        Energy dissipated in the tendons per cycle (J).
    """

    frequency_hz: float
    cycles: int
    response: np.ndarray
    force: np.ndarray
    L: float
    thd: float
    periodicity: float
    work_per_cycle: float
    dissipated_per_cycle: float

    @property
    def J(self) -> complex:
        """Fundamental compliance ``ẑ₁/F̂₁`` (m/N), same convention as :func:`tenscell.compliance`."""
        return complex(self.response[1] / self.force[1])

    @property
    def G(self) -> complex:
        """``G' + iG'' = (0.5/L)/J`` (Pa)."""
        return (0.5 / self.L) / self.J

    @property
    def G_storage(self) -> float:
        """G' (Pa)."""
        return float(self.G.real)

    @property
    def G_loss(self) -> float:
        """G'' (Pa)."""
        return float(self.G.imag)

    @property
    def harmonic_numbers(self) -> np.ndarray:
        """0, 1, ..., H."""
        return np.arange(self.response.size)


def harmonics(sim: Simulation, cycles: int = 1, n_harmonics: int = 20) -> Harmonics:
    """Project the last ``cycles`` forcing periods of a simulation on the forcing harmonics.

    The simulation must be sampled uniformly with a whole number of samples
    per period, ending on a period boundary (as :func:`oscillatory_response`
    does); the rectangle rule on such samples is exact for every harmonic
    below half the sampling rate.

    Parameters
    ----------
    sim : Simulation
        Under a SineForce or SineDisplacement.
    cycles : int
        Periods to analyse (≥ 1).
    n_harmonics : int
        Highest harmonic kept (≥ 2).
    """
    load = sim.loading
    if not isinstance(load, (SineForce, SineDisplacement)):
        raise ValueError("harmonic analysis needs a SineForce or SineDisplacement simulation")
    cycles, n_harmonics = int(cycles), int(n_harmonics)
    if cycles < 1 or n_harmonics < 2:
        raise ValueError(f"cycles must be >= 1 and n_harmonics >= 2, got {cycles}, {n_harmonics}")
    T = load.period
    t = sim.t
    dt = np.diff(t)
    N = int(round(T / dt[-1])) if dt.size else 0
    n_total = int(round(t[-1] / T))
    ok = (N >= 4 and abs(N * dt[-1] - T) <= 1e-9 * T and abs(n_total * T - t[-1]) <= 1e-9 * T and n_total >= cycles
          and t.size >= cycles * N + 1)
    if ok:
        sel = slice(t.size - 1 - cycles * N, t.size - 1)
        ok = np.allclose(np.diff(t[t.size - 1 - cycles * N:]), T / N, rtol=1e-9, atol=0)
    if not ok:
        raise ValueError(
            "the simulation is not sampled uniformly with a whole number of samples per period up to a period "
            "boundary; use oscillatory_response (or t_eval = k·T/N) for harmonic analysis"
        )
    if 2 * n_harmonics >= N:
        raise ValueError(f"{N} samples per period resolve harmonics below {N // 2}; n_harmonics={n_harmonics} is too many")
    ns = cycles * N

    def spectrum(x):
        X = np.fft.rfft(x[sel]) / ns
        out = np.empty(n_harmonics + 1, dtype=complex)
        out[0] = X[0].real
        out[1:] = 2.0 * X[cycles: cycles * (n_harmonics + 1): cycles]
        return out

    Z, F = spectrum(sim.z), spectrum(sim.force)
    sig = F if load.controls == "displacement" else Z
    thd = float(np.sqrt(np.sum(np.abs(sig[2:]) ** 2)) / abs(sig[1]))
    x = sim.force if load.controls == "displacement" else sim.z
    if n_total >= 2 and t.size >= N + 1 + N:
        last = x[t.size - 1 - N: t.size - 1]
        prev = x[t.size - 1 - 2 * N: t.size - 1 - N]
        periodicity = float(np.abs(last - prev).max() / max(np.abs(last - last.mean()).max(), 1e-300))
    else:
        periodicity = float("nan")
    # work from the harmonics of F and u (∮F du = −π Σ h·Im(conj(F_h)·U_h)): positions interpolated by
    # the solver's dense output are accurate, whereas rates recomputed there pick up its stiff error modes
    U = spectrum(sim.u)
    hh = np.arange(n_harmonics + 1)
    work = float(-np.pi * np.sum(hh * np.imag(np.conj(F) * U)))
    diss = float(np.sum(sim.power[sel]) * (T / N) / cycles)
    return Harmonics(
        frequency_hz=load.frequency_hz, cycles=cycles, response=Z, force=F, L=sim.cell.strut_length, thd=thd,
        periodicity=periodicity, work_per_cycle=work, dissipated_per_cycle=diss,
    )


# ---- oscillatory moduli --------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class OscillatoryResponse:
    """Moduli from a simulated periodic steady state, beside the linear ones.

    Attributes
    ----------
    simulation : Simulation
    harmonics : Harmonics
    linear : LinearModel or None
        The law's linearization, or None when it does not exist.
    linear_note : str
        Why ``linear`` is None (empty otherwise).
    settle_cycles : int
        Cycles simulated before the analysed ones.
    """

    simulation: Simulation
    harmonics: Harmonics
    linear: LinearModel | None
    linear_note: str = ""
    settle_cycles: int = 0

    @property
    def G_storage(self) -> float:
        """G' from the time domain (Pa)."""
        return self.harmonics.G_storage

    @property
    def G_loss(self) -> float:
        """G'' from the time domain (Pa)."""
        return self.harmonics.G_loss

    @property
    def thd(self) -> float:
        """Total harmonic distortion (dimensionless)."""
        return self.harmonics.thd

    def _lin(self) -> complex:
        if self.linear is None:
            return complex(float("nan"), float("nan"))
        J = complex(compliance(self.linear, self.harmonics.frequency_hz))
        return (0.5 / self.linear.L) / J

    @property
    def G_storage_linear(self) -> float:
        """G' of the linear model at the same frequency (Pa; NaN without a linearization)."""
        return float(self._lin().real)

    @property
    def G_loss_linear(self) -> float:
        """G'' of the linear model (Pa; NaN without a linearization)."""
        return float(self._lin().imag)

    @property
    def J_linear(self) -> complex:
        """Linear compliance J(ω) (m/N)."""
        return complex((0.5 / self.linear.L) / self._lin()) if self.linear is not None else complex("nan")

    def cycle(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(t, z, F)`` over the analysed cycles, both ends included (a closed loop); s, m, N."""
        sim, h = self.simulation, self.harmonics
        N = int(round(sim.loading.period / (sim.t[-1] - sim.t[-2])))
        sel = slice(sim.t.size - 1 - h.cycles * N, sim.t.size)
        return sim.t[sel], sim.z[sel], sim.force[sel]

    def linear_cycle(self) -> tuple[np.ndarray, np.ndarray]:
        """``(z, F)`` of the linear model on the times of :meth:`cycle` (m, N); NaN without a linearization.

        Under force control F is the prescribed force and z the linear
        response; under displacement control the reverse.
        """
        t, z, F = self.cycle()
        load = self.simulation.loading
        if self.linear is None:
            nan = np.full(t.shape, np.nan)
            return (nan, F) if load.controls == "force" else (z, nan)
        e = np.exp(1j * load.omega * t)
        if load.controls == "force":
            return (self.J_linear * load.phasor * e).real, np.asarray(load.value(t))
        return np.asarray(load.value(t)), (load.phasor / self.J_linear * e).real

    def summary(self) -> dict:
        """JSON-ready numbers: moduli (Pa), THD, periodicity, energies (J), slack tendons."""
        h, sim = self.harmonics, self.simulation
        load = sim.loading
        return {
            "frequency_Hz": h.frequency_hz,
            "control": load.controls,
            "amplitude": load.amplitude,
            "amplitude_unit": "N" if load.controls == "force" else "m",
            "prestress": self.linear.P if self.linear is not None else None,
            "G_storage": self.G_storage,
            "G_loss": self.G_loss,
            "G_storage_linear": self.G_storage_linear,
            "G_loss_linear": self.G_loss_linear,
            "thd": self.thd,
            "periodicity": h.periodicity,
            "cycles_simulated": int(round(sim.t[-1] * h.frequency_hz)),
            "cycles_analysed": h.cycles,
            "work_per_cycle_J": h.work_per_cycle,
            "dissipated_per_cycle_J": h.dissipated_per_cycle,
            "displacement_amplitude_m": abs(h.response[1]),
            "force_amplitude_N": abs(h.force[1]),
            "min_tension_N": float(sim.tensions.min()),
            "slack_tendons": sim.slack_summary(),
            "linear_note": self.linear_note,
            "solver": dict(sim.stats),
        }


def _linear_or_note(cell, law):
    try:
        return linearize_law(cell, law), ""
    except LinearizationError as err:
        return None, str(err)


def oscillatory_response(
    cell: Cell,
    law: TendonLaw,
    amplitude: float,
    frequency_hz: float,
    *,
    control: str = "force",
    cycles: int | None = None,
    analyse: int = 1,
    samples_per_cycle: int = 128,
    start: str = "auto",
    periodicity_tol: float = 1e-5,
    max_cycles: int = 400,
    n_harmonics: int = 20,
    **solver,
) -> OscillatoryResponse:
    """Simulate a sinusoidal load to a periodic steady state and extract G', G'', THD.

    Parameters
    ----------
    cell : Cell
    law : TendonLaw
    amplitude : float
        Force amplitude (N) under ``control="force"``, displacement amplitude
        (m) under ``control="displacement"``.
    frequency_hz : float
        Forcing frequency (Hz).
    control : {"force", "displacement"}
    cycles : int, optional
        Cycles to simulate in all (≥ ``analyse``). Default: adaptive. First
        ``analyse + 1`` cycles, then more (doubling the total) until the last
        two cycles differ by less than ``periodicity_tol`` relative to the
        amplitude, the difference stops shrinking (the integration-error
        floor), or ``max_cycles`` is reached.
    analyse : int
        Last cycles used for the harmonic analysis.
    samples_per_cycle : int
        Uniform output samples per period (≥ 8).
    start : {"auto", "linear", "rest"}
        Initial state: the linear periodic steady state ("linear"; "auto"
        uses it when the law has a linearization, otherwise rest) or the
        reference at rest. From the linear steady state only the nonlinear
        part of the transient remains, so small amplitudes are periodic from
        the first cycle.
    periodicity_tol : float
        Target periodicity error of the adaptive mode (dimensionless).
    max_cycles : int
        Upper bound on the cycles of the adaptive mode.
    n_harmonics : int
        Highest harmonic analysed.
    **solver
        Passed to :func:`simulate` (``method``, ``rtol``, ``jacobian``, ``slack``, ...).

    Returns
    -------
    OscillatoryResponse
    """
    if control not in ("force", "displacement"):
        raise ValueError(f"control must be 'force' or 'displacement', got {control!r}")
    if start not in ("auto", "linear", "rest"):
        raise ValueError(f"start must be 'auto', 'linear' or 'rest', got {start!r}")
    loading = (SineForce if control == "force" else SineDisplacement)(amplitude, frequency_hz)
    analyse = int(analyse)
    if analyse < 1:
        raise ValueError(f"analyse must be at least 1 cycle, got {analyse}")
    N = int(samples_per_cycle)
    if N < 8:
        raise ValueError(f"samples_per_cycle must be at least 8, got {samples_per_cycle!r}")
    tol = positive_scalar("periodicity_tol", periodicity_tol)
    max_cycles = int(max_cycles)
    if cycles is not None:
        cycles = int(cycles)
        if cycles < analyse:
            raise ValueError(f"cycles ({cycles}) must be at least analyse ({analyse})")
    lin, note = _linear_or_note(cell, law)
    if start == "linear" and lin is None:
        raise LinearizationError(f"start='linear' needs a linearization: {note}")
    q_start = linear_steady_state(lin, loading) if (start != "rest" and lin is not None) else None
    T = loading.period

    def run(k0, k1, q):
        t_eval = np.arange(k0 * N, k1 * N + 1) * (T / N)
        t_eval[0], t_eval[-1] = k0 * T, k1 * T
        return simulate(cell, law, loading, k1 * T, t_eval=t_eval, q_start=q, t_start=k0 * T, **solver)

    if cycles is not None:
        sim = run(0, cycles, q_start)
    else:
        total = analyse + 1
        sim = run(0, total, q_start)
        prev = float("inf")
        while total < max_cycles:
            p = harmonics(sim, cycles=analyse, n_harmonics=2).periodicity
            if p <= tol or p > 0.5 * prev:
                break
            prev = p
            more = min(total, max_cycles - total)
            sim = _concat(sim, run(total, total + more, sim.q[-1]))
            total += more
        cycles = total
    h = harmonics(sim, cycles=analyse, n_harmonics=n_harmonics)
    return OscillatoryResponse(simulation=sim, harmonics=h, linear=lin, linear_note=note, settle_cycles=cycles - analyse)


# ---- amplitude sweeps ----------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class AmplitudeSweep:
    """Time-domain moduli against load amplitude at one frequency.

    Attributes
    ----------
    frequency_hz : float
    amplitudes : ndarray, shape (k,)
        Force amplitudes (N), ascending.
    G_storage, G_loss : ndarray, shape (k,)
        Time-domain moduli (Pa).
    thd : ndarray, shape (k,)
    periodicity : ndarray, shape (k,)
    n_slack : ndarray of int, shape (k,)
        Number of tendons that went slack.
    G_storage_linear, G_loss_linear : float
        Linear moduli (Pa; NaN without a linearization).
    """

    frequency_hz: float
    amplitudes: np.ndarray
    G_storage: np.ndarray
    G_loss: np.ndarray
    thd: np.ndarray
    periodicity: np.ndarray
    n_slack: np.ndarray
    G_storage_linear: float
    G_loss_linear: float

    @property
    def storage_departure(self) -> np.ndarray:
        """``|G'/G'_lin − 1|`` (dimensionless)."""
        return np.abs(self.G_storage / self.G_storage_linear - 1.0)

    @property
    def loss_departure(self) -> np.ndarray:
        """``|G''/G''_lin − 1|`` (dimensionless)."""
        return np.abs(self.G_loss / self.G_loss_linear - 1.0)

    @property
    def departure(self) -> np.ndarray:
        """The larger of the two departures (dimensionless)."""
        return np.maximum(self.storage_departure, self.loss_departure)

    def threshold(self, quantity: str = "departure", level: float = 0.01) -> float:
        """Smallest amplitude (N) at which ``quantity`` reaches ``level``, by log-log interpolation.

        ``quantity`` is ``"departure"``, ``"storage_departure"``,
        ``"loss_departure"`` or ``"thd"``. NaN if it stays below ``level``
        over the sweep; the smallest amplitude if it is already above there.
        """
        if quantity not in ("departure", "storage_departure", "loss_departure", "thd"):
            raise ValueError(f"quantity must be departure, storage_departure, loss_departure or thd, got {quantity!r}")
        level = positive_scalar("level", level)
        y = np.asarray(getattr(self, quantity), dtype=float)
        x = self.amplitudes
        above = np.flatnonzero(y >= level)
        if above.size == 0:
            return float("nan")
        i = int(above[0])
        if i == 0:
            return float(x[0])
        x0, x1, y0, y1 = x[i - 1], x[i], max(y[i - 1], 1e-300), y[i]
        s = (math.log(level) - math.log(y0)) / (math.log(y1) - math.log(y0))
        return float(math.exp(math.log(x0) + s * (math.log(x1) - math.log(x0))))

    def rows(self):
        """``(F, G', G'', departure', departure'', thd, periodicity, n_slack)`` tuples."""
        sd, ld = self.storage_departure, self.loss_departure
        for k, F in enumerate(self.amplitudes):
            yield (float(F), float(self.G_storage[k]), float(self.G_loss[k]), float(sd[k]), float(ld[k]),
                   float(self.thd[k]), float(self.periodicity[k]), int(self.n_slack[k]))


def amplitude_sweep(cell: Cell, law: TendonLaw, frequency_hz: float, amplitudes, *, progress: bool | None = None,
                    **kwargs) -> AmplitudeSweep:
    """Time-domain G', G'' and THD over force amplitudes (N) at one frequency (Hz).

    ``kwargs`` go to :func:`oscillatory_response`. A tqdm bar on stderr is
    shown when stderr is a terminal (``progress=None``).
    """
    from tqdm import tqdm

    amps = np.sort(positive_array("amplitudes", amplitudes, unit="N").ravel())
    res = []
    disable = (not sys.stderr.isatty()) if progress is None else not progress
    for F in tqdm(amps, desc=f"amplitudes at {frequency_hz:g} Hz", disable=disable, file=sys.stderr):
        res.append(oscillatory_response(cell, law, float(F), frequency_hz, **kwargs))
    lin = res[0]
    return AmplitudeSweep(
        frequency_hz=float(frequency_hz), amplitudes=amps,
        G_storage=np.array([r.G_storage for r in res]), G_loss=np.array([r.G_loss for r in res]),
        thd=np.array([r.thd for r in res]), periodicity=np.array([r.harmonics.periodicity for r in res]),
        n_slack=np.array([len(r.simulation.slack_tendons) for r in res]),
        G_storage_linear=lin.G_storage_linear, G_loss_linear=lin.G_loss_linear,
    )


# ---- creep ---------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class CreepResponse:
    """Simulated creep: probe displacement per newton after a force step.

    Attributes
    ----------
    t : ndarray, shape (k,)
        Times after the step (s).
    compliance : ndarray, shape (k,)
        ``z(t)/F`` (m/N).
    linear : ndarray or None, shape (k,)
        Linear creep compliance at the same times (m/N), when a linearization exists.
    amplitude : float
        Step force F (N).
    simulation : Simulation
    """

    t: np.ndarray
    compliance: np.ndarray
    linear: np.ndarray | None
    amplitude: float
    simulation: Simulation


def creep_response(cell: Cell, law: TendonLaw, amplitude: float, t, **solver) -> CreepResponse:
    """Simulate a force step of ``amplitude`` (N) at t = 0 and return ``J(t) = z(t)/F`` (m/N).

    Parameters
    ----------
    cell : Cell
    law : TendonLaw
    amplitude : float
        Step force (N), nonzero.
    t : array_like
        Increasing output times (s), > 0.
    **solver
        Passed to :func:`simulate`.
    """
    t = positive_array("t (time)", t, unit="s").ravel()
    if np.any(np.diff(t) <= 0):
        raise ValueError("t must be strictly increasing")
    load = StepForce(amplitude)
    solver.setdefault("max_step", np.inf)
    sim = simulate(cell, law, load, float(t[-1]), t_eval=t, **solver)
    lin, _ = _linear_or_note(cell, law)
    Jlin = creep_spectrum(lin).compliance(t) if lin is not None else None
    return CreepResponse(t=sim.t, compliance=sim.z / load.amplitude, linear=Jlin, amplitude=load.amplitude, simulation=sim)

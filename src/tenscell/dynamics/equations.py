"""The massless equations of motion of a cell with a tendon law, one evaluation at a time.

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
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from .._errors import TenscellError
from ..laws import DynamicLawError, TendonLaw
from ..model.coordinates import kinematics
from ..model.equilibrium import Cell, equilibrium_matrix, member_geometry, point_vector
from ..model.structure import cable_mask
from .loads import LOADS

__all__ = ["SimulationError", "SlackEvent", "MotionState", "EquationsOfMotion"]


class SimulationError(TenscellError, ValueError):
    """The time integration cannot proceed (singular damping, no convergence, forbidden slack)."""


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
        if not isinstance(loading, LOADS):
            raise ValueError(f"loading must be a SineForce, StepForce or SineDisplacement, got {type(loading).__name__}")
        if not isinstance(law, TendonLaw):
            raise ValueError(f"law must be a tenscell.laws.TendonLaw, got {type(law).__name__}")
        if law.dynamic:
            raise DynamicLawError(
                f"the nonlinear time domain integrates tendon laws T(l, l') without internal state; this "
                f"{type(law).__name__} law has internal dynamics: use tenscell.linear.linearize_law(cell, law, P) for its "
                "linear creep and relaxation and tenscell.linear.dynamic.dynamic_moduli for its moduli")
        if law.l0 is None:
            raise ValueError("the tendon law has no rest lengths: place it at the cell's reference with "
                             "law.at_prestress(cell, P) (or build it with voigt_law, power_dashpot_law, stiffening_law)")
        if law.m != cell.m:
            raise ValueError(f"the tendon law has {law.m} tendons but the cell has {cell.m}")
        self.cell, self.law, self.loading = cell, law, loading
        self.coords = cell.coords
        self.q0 = np.asarray(cell.q0, dtype=float)
        self.n, self.m = cell.n, cell.m
        self.cable = cable_mask(cell.structure.families)
        self.displacement_control = loading.controls == "displacement"
        self.gamma = 10.0 * getattr(loading, "omega") if self.displacement_control else 0.0  # noqa: B009 - a SineDisplacement (mypy sees the union)
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
            raise SimulationError(_undamped_message(cell, err)) from None

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
            chol = scipy.linalg.cho_factor(C, lower=True, check_finite=False)
            pivots = np.abs(np.diag(chol[0]))
            # the same rule as the constrained system's LU above, on the squared pivots: a C(q) singular in exact
            # arithmetic (an undamped part) factors on some BLAS kernels with a pivot of rounding size, and the
            # integration would only meet it later
            if not np.all(np.isfinite(pivots)) or pivots.min() ** 2 <= 1e-14 * pivots.max() ** 2:
                raise np.linalg.LinAlgError("a pivot of rounding size")
            return ("chol", chol)
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
            found = _backtrack(evaluate, v, F, step, n, disp, float(np.linalg.norm(R)))
            if found is None:  # no descent along the Newton direction: the residual is at its round-off floor
                break
            v, F, (R, T, dTdv, act) = found
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
        assert Hs is not None  # member_geometry computes the Hessians unless told not to
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


def _undamped_message(cell, err) -> str:
    """Why the massless equations cannot start: a free-standing structure (rigid-body motions no tendon damps),
    said in one line, or a part of the structure without damping."""
    from ..linear.rigid import deformation_basis

    N = deformation_basis(cell)
    if N is not None:
        k = cell.n - N.shape[1]
        return (f"{cell.describe()} is free-standing: its supports leave {k} rigid-body motion(s) free, which no "
                "tendon resists or damps, so the massless nonlinear equations cannot determine them; hold it (fixed "
                "nodes or per-direction supports) for the time domain, or use its linear response (tenscell.moduli, "
                "tenscell.dynamics.linear_steady_state), from which the rigid-body motions are removed")
    return (f"{cell.describe()}: {err}. The massless equations need a positive definite damping matrix "
            "C(q) = Σ dT/dl'·a aᵀ (for the cell without intermediate filaments C0 is singular)")


def _backtrack(evaluate, v, F, step, n: int, disp: bool, r0: float):
    """Backtracking along the Newton ``step`` from ``(v, F)``: the first of the steps 1, ½, ¼, ... that lowers the
    residual norm below ``(1 − 1e-4·a)·r0``, as ``(v, F, evaluate(v, F))``; None when none above 1e-6 does."""
    a = 1.0
    while a >= 1e-6:
        vn = v + a * step[:n]
        Fn = F + a * step[n] if disp else F
        out = evaluate(vn, Fn)
        if np.linalg.norm(out[0]) <= (1.0 - 1e-4 * a) * r0:
            return vn, Fn, out
        a *= 0.5
    return None

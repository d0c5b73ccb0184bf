"""Time integration of the equations of motion (stiff implicit solvers, exact Jacobian, slack events)."""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from .._checks import finite_scalar, positive_scalar
from .._errors import option
from ..laws import TendonLaw
from ..model.equilibrium import Cell, tangent_stiffness
from .equations import EquationsOfMotion, SimulationError, SlackEvent
from .loads import describe
from .results import Simulation

__all__ = ["simulate"]


def _scale(eq: EquationsOfMotion, loading) -> float:
    """Size of the expected displacement of the coordinates (m or rad), for absolute tolerances."""
    law, cell = eq.law, eq.cell
    K = tangent_stiffness(cell.geometry, law.elastic(cell.lengths), law.stiffness_at_rest(cell.lengths))
    K = K.toarray() if hasattr(K, "toarray") else K
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
    t_start, t_end, rtol = _check_options(t_start, t_end, rtol, method, jacobian, slack)
    eq = EquationsOfMotion(cell, law, loading)
    t_eval = None if t_eval is None else _check_times(t_eval, t_start, t_end)
    y, atol, max_step = _start(eq, loading, q_start, rtol, atol, max_step)

    fam = cell.structure.families
    cables = np.flatnonzero(eq.cable)
    taut0 = eq.state(t_start, y).taut
    events: list[SlackEvent] = [SlackEvent(t_start, int(j), fam[j], "slack") for j in cables if not taut0[j]]
    if slack == "error" and events:
        raise SimulationError(f"tendon {events[0].tendon} ({events[0].family}) is slack at t={t_start:g} s")
    sol = solve_ivp(
        lambda t, yy: eq.velocity(t, yy), (t_start, t_end), y, method=method, t_eval=t_eval,
        events=[_slack_event(eq, int(j), slack == "error") for j in cables], rtol=rtol, atol=atol,
        jac=(lambda t, yy: eq.jacobian(t, yy)) if jacobian == "analytic" else None, max_step=max_step,
    )
    events += _switches(sol, cables, taut0, fam, loading, t_start)
    return _record(eq, law, loading, sol, events)


def _slack_event(eq: EquationsOfMotion, j: int, stop: bool):
    """solve_ivp event: cable ``j``'s constitutive tension crosses the slack tolerance (stop at going slack)."""

    def event(t, yy):
        return float(eq.state(t, yy).trial[j]) + eq.slack_tolerance

    event.terminal = stop  # type: ignore[attr-defined]
    event.direction = -1 if stop else 0  # type: ignore[attr-defined]
    return event


def _check_options(t_start, t_end, rtol, method: str, jacobian: str, slack: str) -> tuple[float, float, float]:
    """The scalar options of :func:`simulate`, checked: (t_start, t_end, rtol)."""
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
    return t_start, t_end, rtol


def _start(eq: EquationsOfMotion, loading, q_start, rtol: float, atol, max_step) -> tuple[np.ndarray, float, float]:
    """(initial state q − q0, absolute tolerance, largest step), checked, with their defaults (see :func:`simulate`)."""
    n = eq.n
    y = np.zeros(n) if q_start is None else np.asarray(q_start, dtype=float) - eq.q0
    if y.shape != (n,) or not np.all(np.isfinite(y)):
        raise ValueError(f"q_start must be {n} finite coordinates")
    if atol is None:
        atol = rtol * _scale(eq, loading)
    atol = positive_scalar("atol", atol)
    if max_step is None:
        max_step = loading.period / 16.0 if loading.period else np.inf
    max_step = positive_scalar("max_step", max_step, "s") if np.isfinite(max_step) else np.inf
    return y, atol, max_step


def _check_times(t_eval, t_start: float, t_end: float) -> np.ndarray:
    """Output times (s): finite, strictly increasing, within [t_start, t_end] (a last time a hair over is t_end)."""
    t_eval = np.asarray(t_eval, dtype=float).ravel()
    if (t_eval.size == 0 or not np.all(np.isfinite(t_eval)) or t_eval.min() < t_start
            or t_eval.max() > t_end * (1 + 1e-12)):
        raise ValueError(f"t_eval must be finite times within [t_start={t_start:g}, t_end={t_end:g}] s")
    if np.any(np.diff(t_eval) <= 0):
        raise ValueError("t_eval must be strictly increasing")
    return np.minimum(t_eval, t_end)


def _switches(sol, cables: np.ndarray, taut0: np.ndarray, fam, loading, t_start: float) -> list[SlackEvent]:
    """The slack/taut switches found by the solver's events; SimulationError if it failed or stopped at one."""
    if sol.status == -1:
        raise SimulationError(f"time integration failed at t={sol.t[-1] if sol.t.size else t_start:.6g} s: {sol.message}")
    if sol.status == 1:
        k = next(i for i, te in enumerate(sol.t_events) if te.size)
        j = int(cables[k])
        raise SimulationError(
            f"tendon {j} ({fam[j]}) would go into compression at t={float(sol.t_events[k][0]):.6g} s "
            f"under {describe(loading)}; run with {option('slack', 'allow')} to let it go slack"
        )
    events = []
    for k, j in enumerate(map(int, cables)):
        # the constitutive tension changes sign at each root, so the switches alternate
        slack_now = not taut0[j]
        for te in sol.t_events[k]:
            slack_now = not slack_now
            events.append(SlackEvent(float(te), int(j), fam[j], "slack" if slack_now else "taut"))
    return events


def _record(eq: EquationsOfMotion, law: TendonLaw, loading, sol, events: list[SlackEvent]) -> Simulation:
    """The :class:`Simulation` of a finished solve: every output sample's state, events in time order."""
    events = sorted(events, key=lambda e: (e.time, e.tendon))
    n = eq.n
    ts, ys = np.asarray(sol.t, dtype=float), np.asarray(sol.y, dtype=float).reshape(n, -1).T
    states = [eq.state(tk, yk) for tk, yk in zip(ts, ys)]

    def col(name):
        return np.array([getattr(s, name) for s in states], dtype=float)

    return Simulation(
        cell=eq.cell, law=law, loading=loading, t=ts, q=np.array([s.q for s in states]).reshape(-1, n),
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



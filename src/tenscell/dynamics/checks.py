"""Checks before integrating: what the integration would find at its first step, found without it.

The massless equations need a positive definite damping matrix over the taut tendons; a load large enough to
take tendons slack at once can leave part of the structure undamped (the cell without intermediate filaments
has no damping as soon as it is loaded), and with ``slack="error"`` a tendon slack at the start stops the run.
:func:`check_start` evaluates the nonlinear equations (:meth:`EquationsOfMotion.state`, a few ms) at the state
the integration starts from — the linear periodic state at t = 0 for a sinusoidal load (what
:func:`~tenscell.dynamics.oscillatory_response` starts from), rest with the step applied for a creep test —
exactly as the integrator will, for every load of a run, before the first is integrated.

What happens later in a run is not predicted here: along the cycle the nonlinear response departs from the
linear one exactly where tendons go slack (on the paper cell at 1 Hz the linear response takes the first
tendon slack at 334 N, the simulation at less than 250 N, and runs at 1000 N that the linear path would call
undamped), so a refusal from the linear path would be wrong both ways.
"""
from __future__ import annotations

import numpy as np

from .._errors import option
from ..laws import LinearizationError, TendonLaw
from ..model.equilibrium import Cell
from .equations import EquationsOfMotion, SimulationError
from .harmonic import linear_steady_state
from .loads import StepForce, describe

__all__ = ["check_start"]


def _start(cell: Cell, law: TendonLaw, loading) -> np.ndarray:
    """The integration's first state y = q - q0: the linear periodic state at t = 0, or rest."""
    if isinstance(loading, StepForce):
        return np.zeros(cell.n)
    from ..linear.linearize import linearize_law

    try:
        lin = linearize_law(cell, law)
    except LinearizationError:  # no linearization: the oscillation starts from rest
        return np.zeros(cell.n)
    return linear_steady_state(lin, loading) - np.asarray(cell.q0, dtype=float)


def check_start(cell: Cell, law: TendonLaw, loading, *, slack: str = "allow", name: str | None = None) -> None:
    """Refuse (:class:`SimulationError`) a run the integration would stop at its first step.

    Parameters
    ----------
    cell, law : the cell and its tendon law (as for :func:`tenscell.dynamics.simulate`)
    loading : SineForce, SineDisplacement or StepForce
    slack : {"allow", "error"}
        With ``"error"``, a tendon slack at the start is refused too.
    name : str, optional
        How messages name the load (default :func:`~tenscell.dynamics.loads.describe`).

    Raises
    ------
    SimulationError
        The damping system singular at the state the integration starts from (part of the structure undamped),
        or, with ``slack="error"``, a tendon slack there; the message names the load and the tendons.
    """
    name = name or describe(loading)
    problem = _problem(cell, law, loading, slack)
    if problem is None:
        return
    unit = "m" if loading.controls == "displacement" else "N"
    limit = _largest_start(cell, law, loading, slack)
    hint = "" if limit is None else f"; the integration starts up to about {limit:.2g} {unit}"
    raise SimulationError(f"{name}: {problem} at the state the integration starts from{hint}")


def _problem(cell: Cell, law: TendonLaw, loading, slack: str) -> str | None:
    """What stops the integration at its first state under ``loading``, in words, or None."""
    eq = EquationsOfMotion(cell, law, loading)  # refuses a damping matrix singular at rest
    try:
        state = eq.state(0.0, _start(cell, law, loading))
    except SimulationError as err:
        return str(err).split(" at t=")[0] + (f" ({str(err).split(' slack: ')[0].split(' with ')[-1]} slack)"
                                             if " with tendons " in str(err) else "")
    slack_now = np.flatnonzero(eq.cable & ~state.taut)
    if slack == "error" and slack_now.size:
        j = int(slack_now[0])
        return (f"tendon {j} ({cell.structure.families[j]}) is slack ({slack_now.size} tendon(s) in all), and "
                f"{option('slack', 'error')} stops the run")
    return None


def _largest_start(cell: Cell, law: TendonLaw, loading, slack: str, steps: int = 14) -> float | None:
    """About the largest amplitude (within 10 %) whose first state is fine, by bisection in log amplitude down to
    1e-9 of ``loading``'s; None when even that fails (the load's size is not the reason)."""
    lo, hi = -9.0, 0.0  # log10 of the factor on the amplitude: fine at lo, failing at hi
    if _problem(cell, law, _scaled(loading, 10.0 ** lo), slack) is not None:
        return None
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        if _problem(cell, law, _scaled(loading, 10.0 ** mid), slack) is None:
            lo = mid
        else:
            hi = mid
        if hi - lo < 0.04:
            break
    amplitude = loading.amplitude * 10.0 ** lo
    step = 10.0 ** (np.floor(np.log10(amplitude)) - 1)  # two significant digits, rounded down: it still starts
    return float(np.floor(amplitude / step) * step)


def _scaled(loading, factor: float):
    """The same load at ``factor`` of its amplitude."""
    if isinstance(loading, StepForce):
        return StepForce(loading.amplitude * factor)
    return type(loading)(loading.amplitude * factor, loading.frequency_hz)

"""Nonlinear time domain: the massless equations of motion of a cell with any tendon law.

One module per job:

* :mod:`~tenscell.dynamics.loads` — what is prescribed (sinusoidal force or
  displacement, force step);
* :mod:`~tenscell.dynamics.equations` — the equations of motion, one evaluation
  at a time: velocities (with slack as a complementarity problem) and their
  exact Jacobian;
* :mod:`~tenscell.dynamics.integration` — :func:`simulate` (stiff implicit
  integration, slack/taut events);
* :mod:`~tenscell.dynamics.harmonic` — periodic steady states, harmonic
  analysis, oscillatory moduli and amplitude sweeps;
* :mod:`~tenscell.dynamics.creep` — a held force step;
* :mod:`~tenscell.dynamics.results` — the result objects.

The tendon law is a :class:`tenscell.laws.TendonLaw` placed at the reference
(e.g. ``voigt_law(cell, P)``, ``stiffening_law(cell, P, b=...)`` or
``law.at_prestress(cell, P)``); its linearization, against which the
small-amplitude limit is compared, is :func:`tenscell.linear.linearize.linearize_law`.
"""
from __future__ import annotations

from ..linear.linearize import linearize_law
from .creep import creep_response
from .equations import EquationsOfMotion, MotionState, SimulationError, SlackEvent
from .harmonic import amplitude_sweep, harmonics, linear_steady_state, oscillatory_response
from .integration import simulate
from .loads import SineDisplacement, SineForce, StepForce
from .results import AmplitudeSweep, CreepResponse, Harmonics, OscillatoryResponse, Simulation

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

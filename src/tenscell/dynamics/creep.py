"""A force step held in time: simulated creep beside the linear creep compliance."""
from __future__ import annotations

import numpy as np

from .._checks import positive_array
from ..laws import TendonLaw
from ..model.equilibrium import Cell
from ..timedomain import creep_spectrum
from .harmonic import _linear_or_note
from .integration import simulate
from .loads import StepForce
from .results import CreepResponse

__all__ = ["creep_response"]


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


"""Loads of the time-domain experiments: what is prescribed at the load point.

**Loads.** :class:`SineForce` and :class:`StepForce` prescribe the force F
at the load point; :class:`SineDisplacement` prescribes the probe
displacement z(t), the force being the Lagrange multiplier of the
constraint ``D(q)·q' = z'(t) + γ(z(t) − z(q))`` (γ = 10ω removes drift).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import finite_scalar, positive_scalar

__all__ = ["SineForce", "SineDisplacement", "StepForce", "LOADS", "describe"]


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


def describe(loading) -> str:
    """A load in words, for messages: ``"a force amplitude of 300 N at 1 Hz"``, ``"a step force of 30 N"``."""
    if isinstance(loading, StepForce):
        return f"a step force of {loading.amplitude:g} N"
    kind, unit = ("force", "N") if loading.controls == "force" else ("displacement", "m")
    return f"a {kind} amplitude of {loading.amplitude:g} {unit} at {loading.frequency_hz:g} Hz"


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


LOADS = (SineForce, StepForce, SineDisplacement)

"""What the time-domain experiments return: simulations, harmonics, oscillatory moduli, sweeps, creep."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._checks import positive_scalar
from .._results import dataframe, format_repr
from ..linear.linearize import LinearModel
from ..linear.assembly import modulus
from ..model.equilibrium import Cell
from ..response import compliance

__all__ = ["Simulation", "Harmonics", "OscillatoryResponse", "AmplitudeSweep", "CreepResponse"]


@dataclass(frozen=True, eq=False, repr=False)
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
    law: Any
    loading: Any
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

    def __repr__(self) -> str:
        slack = self.slack_tendons
        return format_repr(
            f"Simulation of {self.cell.describe()}",
            f"{type(self.law).__name__} law, loading {self.loading!r}",
            f"t = {self.t[0]:.4g}…{self.t[-1]:.4g} s, {self.t.size} samples, {self.q.shape[1]} coordinates",
            f"probe z = {self.z.min():.4g}…{self.z.max():.4g} m, force = {self.force.min():.4g}…{self.force.max():.4g} N",
            f"{len(slack)} tendon(s) went slack" + (f" ({len(self.events)} switches)" if slack else ""),
        )

    def to_dataframe(self, tensions: bool = False):
        """One row per sample: time, force, displacements, power, slack count (and each tension if asked)."""
        cols = {"time_s": self.t, "force_N": self.force, "probe_displacement_m": self.z,
                "load_displacement_m": self.u, "load_rate_m_per_s": self.u_rate, "dissipated_power_W": self.power,
                "n_slack": (~self.taut).sum(axis=1)}
        if tensions:
            for j in range(self.tensions.shape[1]):
                cols[f"tension_{j}_N"] = self.tensions[:, j]
        return dataframe(cols, {"loading": repr(self.loading), "law": type(self.law).__name__})

    def plot(self, ax=None, **kw):
        """Probe displacement against time (slack intervals shaded); returns the axes."""
        from .._results import plotter

        simulation_axes = plotter("simulation_axes")

        return simulation_axes(self, ax=ax, **kw)


@dataclass(frozen=True, eq=False, repr=False)
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
        return modulus(self.J, self.L)

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

    def __repr__(self) -> str:
        return format_repr(
            f"Harmonics at {self.frequency_hz:g} Hz ({self.cycles} cycle(s), up to {self.response.size - 1})",
            f"G' = {self.G_storage:.5g} Pa, G'' = {self.G_loss:.5g} Pa, THD = {100 * self.thd:.3g} %",
            f"periodicity {self.periodicity:.2e}; work/cycle {self.work_per_cycle:.4g} J, "
            f"dissipated/cycle {self.dissipated_per_cycle:.4g} J",
        )

    def to_dataframe(self):
        """One row per harmonic h: frequency, amplitude and phase of the probe displacement and the force."""
        return dataframe({
            "harmonic": self.harmonic_numbers, "frequency_Hz": self.harmonic_numbers * self.frequency_hz,
            "displacement_amplitude_m": np.abs(self.response), "displacement_phase_rad": np.angle(self.response),
            "force_amplitude_N": np.abs(self.force), "force_phase_rad": np.angle(self.force),
        }, {"G_storage_Pa": self.G_storage, "G_loss_Pa": self.G_loss, "thd": self.thd})

    def plot(self, ax=None, **kw):
        """Harmonic amplitudes relative to the fundamental (log scale); returns the axes."""
        from .._results import plotter

        harmonics_axes = plotter("harmonics_axes")

        return harmonics_axes(self, ax=ax, **kw)


@dataclass(frozen=True, eq=False, repr=False)
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
        return complex(modulus(self.J_linear, self.linear.L))

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
        if self.linear is None:
            return complex("nan")
        return complex(compliance(self.linear, self.harmonics.frequency_hz))

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

    def __repr__(self) -> str:
        h, load = self.harmonics, self.simulation.loading
        unit = "N" if load.controls == "force" else "m"
        return format_repr(
            f"OscillatoryResponse at {h.frequency_hz:g} Hz, {load.controls} amplitude {load.amplitude:g} {unit}",
            f"G' = {self.G_storage:.5g} Pa (linear {self.G_storage_linear:.5g}), "
            f"G'' = {self.G_loss:.5g} Pa (linear {self.G_loss_linear:.5g})",
            f"THD = {100 * self.thd:.3g} %, periodicity {h.periodicity:.2e}, "
            f"{len(self.simulation.slack_tendons)} tendon(s) went slack",
        )

    def to_dataframe(self):
        """The analysed cycle(s): time, probe displacement and force, beside the linear model's."""
        t, z, F = self.cycle()
        zl, Fl = self.linear_cycle()
        return dataframe({"time_s": t, "probe_displacement_m": z, "force_N": F,
                          "linear_probe_displacement_m": zl, "linear_force_N": Fl},
                         {k: v for k, v in self.summary().items() if not isinstance(v, (list, dict))})

    def plot(self, ax=None, **kw):
        """Force against probe displacement over the analysed cycle(s), with the linear ellipse; returns the axes."""
        from .._results import plotter

        loop_axes = plotter("loop_axes")

        return loop_axes(self, ax=ax, **kw)


@dataclass(frozen=True, eq=False, repr=False)
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

    def __repr__(self) -> str:
        return format_repr(
            f"AmplitudeSweep at {self.frequency_hz:g} Hz, {self.amplitudes.size} amplitudes "
            f"{self.amplitudes[0]:.4g}…{self.amplitudes[-1]:.4g} N",
            f"linear G' = {self.G_storage_linear:.5g} Pa, G'' = {self.G_loss_linear:.5g} Pa",
            f"1% departure at {self.threshold():.4g} N; largest THD {100 * np.nanmax(self.thd):.3g} %",
        )

    def to_dataframe(self):
        """One row per amplitude: moduli (Pa), departures from linear, THD, periodicity, slack count."""
        return dataframe({
            "amplitude_N": self.amplitudes, "G_storage_Pa": self.G_storage, "G_loss_Pa": self.G_loss,
            "storage_departure": self.storage_departure, "loss_departure": self.loss_departure, "thd": self.thd,
            "periodicity": self.periodicity, "n_slack": self.n_slack,
        }, {"frequency_Hz": self.frequency_hz, "G_storage_linear_Pa": self.G_storage_linear,
            "G_loss_linear_Pa": self.G_loss_linear})

    def plot(self, ax=None, **kw):
        """Departure from the linear moduli and THD against amplitude (log-log); returns the axes."""
        from .._results import plotter

        amplitude_sweep_axes = plotter("amplitude_sweep_axes")

        return amplitude_sweep_axes(self, ax=ax, **kw)


@dataclass(frozen=True, eq=False, repr=False)
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

    def __repr__(self) -> str:
        J = self.compliance
        lin = "" if self.linear is None else f"; linear {self.linear[0]:.4g}…{self.linear[-1]:.4g} m/N"
        return format_repr(
            f"CreepResponse to a {self.amplitude:g} N step, {self.t.size} times {self.t[0]:.3g}…{self.t[-1]:.3g} s",
            f"J(t) = z/F = {J[0]:.4g}…{J[-1]:.4g} m/N{lin}",
            f"{len(self.simulation.slack_tendons)} tendon(s) went slack",
        )

    def to_dataframe(self):
        """One row per time: simulated and linear creep compliance z(t)/F (m/N)."""
        lin = self.linear if self.linear is not None else np.full(self.t.shape, np.nan)
        return dataframe({"time_s": self.t, "creep_compliance_m_per_N": self.compliance,
                          "linear_creep_compliance_m_per_N": lin}, {"step_force_N": self.amplitude})

    def plot(self, ax=None, **kw):
        """J(t) on log-log axes, simulated and linear; returns the axes."""
        from .._results import plotter

        creep_axes = plotter("creep_axes")

        return creep_axes(self, ax=ax, **kw)

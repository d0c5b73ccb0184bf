"""Periodic steady states and their harmonics: oscillatory moduli and amplitude sweeps.

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

import numpy as np

from .._checks import positive_array, positive_scalar
from .._progress import progress_bar
from ..laws import LinearizationError, TendonLaw
from ..linear.linearize import LinearModel, linearize_law
from ..linear.rigid import solve_full
from ..model.equilibrium import Cell
from .integration import _concat, simulate
from .loads import SineDisplacement, SineForce
from .results import AmplitudeSweep, Harmonics, OscillatoryResponse, Simulation

__all__ = ["linear_steady_state", "harmonics", "oscillatory_response", "amplitude_sweep"]


def linear_steady_state(lin: LinearModel, loading) -> np.ndarray:
    """Coordinates ``q(0)`` (m, rad) of the linear periodic steady state under a sinusoidal load.

    ``q(t) = q0 + Re(q̂ e^{iωt})`` with ``q̂ = (K0 + iωC0)⁻¹ b F̂``; for a
    prescribed displacement ``F̂ = ẑ/J(ω)``.
    """
    if not isinstance(loading, (SineForce, SineDisplacement)):
        raise ValueError("a periodic steady state needs a SineForce or SineDisplacement loading")
    w = loading.omega
    x = solve_full(lin, 1j * w, -lin.H0)  # a free-standing structure: on the complement of its rigid-body motions
    Fhat = loading.phasor if loading.controls == "force" else loading.phasor / (lin.D0 @ x)
    return np.asarray(lin.cell.q0) + (x * Fhat).real


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
    analyse, N, tol, cycles = _check_oscillation(control, start, analyse, samples_per_cycle, periodicity_tol, cycles)
    loading = (SineForce if control == "force" else SineDisplacement)(amplitude, frequency_hz)
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
        sim, cycles = _until_periodic(run, q_start, analyse, tol, int(max_cycles))
    h = harmonics(sim, cycles=analyse, n_harmonics=n_harmonics)
    return OscillatoryResponse(simulation=sim, harmonics=h, linear=lin, linear_note=note, settle_cycles=cycles - analyse)


def _check_oscillation(control, start, analyse, samples_per_cycle, periodicity_tol, cycles):
    """The options of :func:`oscillatory_response`, checked: (analyse, samples per cycle, tolerance, cycles)."""
    if control not in ("force", "displacement"):
        raise ValueError(f"control must be 'force' or 'displacement', got {control!r}")
    if start not in ("auto", "linear", "rest"):
        raise ValueError(f"start must be 'auto', 'linear' or 'rest', got {start!r}")
    analyse = int(analyse)
    if analyse < 1:
        raise ValueError(f"analyse must be at least 1 cycle, got {analyse}")
    N = int(samples_per_cycle)
    if N < 8:
        raise ValueError(f"samples_per_cycle must be at least 8, got {samples_per_cycle!r}")
    tol = positive_scalar("periodicity_tol", periodicity_tol)
    if cycles is not None:
        cycles = int(cycles)
        if cycles < analyse:
            raise ValueError(f"cycles ({cycles}) must be at least analyse ({analyse})")
    return analyse, N, tol, cycles


def _until_periodic(run, q_start, analyse: int, tol: float, max_cycles: int) -> tuple[Simulation, int]:
    """``analyse + 1`` cycles, then more (doubling the total) until periodic to ``tol``, stalled or at ``max_cycles``.

    ``run(k0, k1, q)`` simulates cycles k0..k1 from state q. Returns the
    simulation of every cycle and their number.
    """
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
    return sim, total


def amplitude_sweep(cell: Cell, law: TendonLaw, frequency_hz: float, amplitudes, *, progress: bool | None = None,
                    **kwargs) -> AmplitudeSweep:
    """Time-domain G', G'' and THD over force amplitudes (N) at one frequency (Hz).

    ``kwargs`` go to :func:`oscillatory_response`. ``progress``: the
    :mod:`tenscell._progress` convention (a bar when someone is watching).
    """
    amps = np.sort(positive_array("amplitudes", amplitudes, unit="N").ravel())
    res = []
    for F in progress_bar(amps, desc=f"amplitudes at {frequency_hz:g} Hz", unit="amplitude", progress=progress):
        res.append(oscillatory_response(cell, law, float(F), frequency_hz, **kwargs))
    lin = res[0]
    return AmplitudeSweep(
        frequency_hz=float(frequency_hz), amplitudes=amps,
        G_storage=np.array([r.G_storage for r in res]), G_loss=np.array([r.G_loss for r in res]),
        thd=np.array([r.thd for r in res]), periodicity=np.array([r.harmonics.periodicity for r in res]),
        n_slack=np.array([len(r.simulation.slack_tendons) for r in res]),
        G_storage_linear=lin.G_storage_linear, G_loss_linear=lin.G_loss_linear,
    )



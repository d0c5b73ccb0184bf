"""``tenscell simulate`` and ``tenscell creep``: the nonlinear time domain of the paper cell."""
from __future__ import annotations

import argparse
import math
import sys

from ._cost import Cost, announce, check, measure
from ._args import (RANGES, add_model_options, add_out, add_prestress, frequencies, hidden_alias, integer, number,
                    number_list)

#: load amplitudes: force (N) or displacement (m); beyond this every tendon is far outside the model
AMPLITUDE_RANGE = (1e-30, 1e30)


def _one_frequency(text):
    f = frequencies(max_points=10_000)(text)
    if len(f) != 1:
        raise argparse.ArgumentTypeError(
            f"simulate takes one frequency, got {len(f)} (sweep frequencies with `tenscell moduli`, "
            "amplitudes with a comma list in --amplitude)")
    return f[0]


_one_frequency.__name__ = "frequency"


def _add_law_options(p) -> None:
    add_prestress(p, sweep=False, from_fit=True)
    p.add_argument("--beta", type=number(0.05, 20.0), default=1.0,
                   help="dashpot exponent: T = EA(l/l0-1) + c·sign(l')|l'|^beta (1 is the Voigt law)")
    p.add_argument("--velocity-scale", type=number(1e-30, 1e30, "m/s"), default=None,
                   help="smoothing velocity of the power-law dashpot near l' = 0 (m/s, default 1e-3; beta != 1 only)")
    p.add_argument("--rtol", type=number(1e-13, 1e-2), default=None,
                   help="relative tolerance of the integrator (default 1e-8; 1e-6 when beta != 1)")
    p.add_argument("--slack", choices=("allow", "error"), default="allow",
                   help="let tendons go slack and record it, or stop with an error")


def register(sub) -> None:
    lo, hi = AMPLITUDE_RANGE
    p = sub.add_parser("simulate", help="nonlinear time-domain simulation under a sinusoidal load",
                       description="Integrate the nonlinear equations of motion of the paper cell under a sinusoidal "
                                   "load to a periodic steady state; write time traces, the force-displacement loop, "
                                   "the harmonic spectrum (CSV + PNG) and simulate.json (G', G'' from the time domain "
                                   "and from the linear model, THD, slack tendons). With several amplitudes, also "
                                   "sweep them and report where G', G'' depart from the linear values by 1% and "
                                   "where THD reaches 1% (sweep.csv).")
    p.add_argument("--amplitude", type=number_list(lo, hi, "N or m", max_items=200), required=True,
                   help="load amplitude(s): force F at the load point (N), or displacement (m) with "
                        "--control displacement; a comma list also runs the amplitude sweep (the first value's "
                        "traces are written)")
    hidden_alias(p, "--amplitudes", "sweep_amplitudes", type=number_list(lo, hi, "N", max_items=200))
    p.add_argument("--freq", type=_one_frequency, required=True, metavar="F", help="forcing frequency f (Hz)")
    p.add_argument("--cycles", type=_cycles, default=None,
                   help="cycles to simulate, at least 2: the last two are compared to judge the periodic state "
                        "(default: adaptive, until two consecutive cycles agree)")
    p.add_argument("--control", choices=("force", "displacement"), default="force",
                   help="prescribe the force or the probe displacement")
    # the harmonic analysis reads 20 harmonics, which takes more than 40 samples per period (Nyquist)
    p.add_argument("--samples", type=integer(41, 100_000), default=128, help="samples per cycle")
    add_out(p)
    add_model_options(p)
    _add_law_options(p)
    p.set_defaults(func=run_simulate)

    p = sub.add_parser("creep", help="creep compliance J(t): linear (exact) vs nonlinear (simulated)",
                       description="Creep after a force step at the load point: the linear model's exact J(t) from "
                                   "its relaxation spectrum and the nonlinear simulation for each step force; "
                                   "log-log plot, local exponent, power-law fit over a window, relaxation modulus.")
    p.add_argument("--amplitude", type=number_list(lo, hi, "N", max_items=50), default=None,
                   help="step forces of the nonlinear simulations (N, comma list; default 0.1,30, and none with "
                        "--from-fit: a fitted cell's tensions can be far below 1 N)")
    p.add_argument("--t-min", type=number(1e-15, 1e15, "s"), default=1e-5, help="first output time (s)")
    p.add_argument("--t-max", type=number(1e-15, 1e15, "s"), default=1.0, help="last output time (s)")
    p.add_argument("--points", type=integer(3, 100_000), default=61, help="log-spaced output times")
    p.add_argument("--window", type=_window, default=None, help="power-law fit window a:b (s; default the whole range)")
    add_out(p)
    add_model_options(p)
    _add_law_options(p)
    p.set_defaults(func=run_creep)


def _cycles(text):
    n = integer(1, 10_000, "cycles")(text)
    if n < 2:
        raise argparse.ArgumentTypeError(f"{n} cycle: at least 2, since the last two cycles are compared to judge "
                                         "whether the state is periodic")
    return n


_cycles.__name__ = "integer"


def _window(text):
    parts = str(text).replace(":", ",").split(",")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"expected a:b (s), got {str(text)[:40]!r}")
    a, b = (number(1e-15, 1e15, "s")(x) for x in parts)
    if not a < b:
        raise argparse.ArgumentTypeError(f"expected a < b, got {a:g}:{b:g}")
    return a, b


_window.__name__ = "window"


def law_from_args(args):
    """(cell, law, solver options) from the model and law options."""
    from ._args import fitted_from_args, model_from_args, prestress_from_args
    from ..laws import power_dashpot_law, voigt_law

    if args.velocity_scale is not None and args.beta == 1.0:
        raise ValueError(f"--velocity-scale {args.velocity_scale:g} m/s smooths the power-law dashpot; with --beta 1 "
                         "(the Voigt law) there is none (give --beta too)")
    fitted = fitted_from_args(args)
    if fitted is None:
        cell, EA, c = model_from_args(args)
        P = prestress_from_args(args)
    else:
        model, P = fitted
        EA, c = time_domain_tendons(model, P, args.from_fit)
        cell = model.cell
    args.prestress_N = P
    if args.beta == 1.0:
        law = voigt_law(cell, P=P, EA=EA, c=c)
    else:
        kw = {} if args.velocity_scale is None else {"velocity_scale": args.velocity_scale}
        law = power_dashpot_law(cell, P=P, EA=EA, c=c, beta=args.beta, **kw)
    rtol = args.rtol if args.rtol is not None else (1e-8 if args.beta == 1.0 else 1e-6)
    return cell, law, {"rtol": rtol, "slack": args.slack}


def time_domain_tendons(model, P: float, path):
    """(EA, c) of the Voigt tendons the nonlinear time domain integrates for a fitted model (ValueError in one line
    for a model it cannot: no cell, tendons with internal dynamics, a cytoplasm in parallel)."""
    if not model.structural:
        raise ValueError(f"--from-fit {path}: {model.describe()} has no cell to simulate: it is a structure-free "
                         "formula (use `tenscell moduli --from-fit`)")
    law = model.tendon_law()
    if law.dynamic:
        raise ValueError(f"--from-fit {path}: the nonlinear time domain integrates tendon laws without internal "
                         f"state; {model.describe()} has {type(law).__name__} tendons (internal dynamics): use "
                         "`tenscell moduli --from-fit` for its moduli")
    if model.viscosity:
        raise ValueError(f"--from-fit {path}: {model.describe()} has a cytoplasm viscosity in parallel with the "
                         "structure, which the nonlinear time domain does not integrate: use `tenscell moduli "
                         "--from-fit` for its moduli")
    return model.voigt_tendons(P)


def check_resolvable_prestrain(cell, law, rtol: float, flag: str) -> None:
    """ValueError if some tendon's strain at rest, ``T/EA``, is below the integrator's tolerance.

    Such a tendon's tension is smaller than the integration noise of its length
    times its stiffness: the nonlinear equations cannot resolve it, and the
    simulation would report spurious slack (a fit whose prestress is inert
    against its stiffest tendons gives such a cell).
    """
    import numpy as np

    strain = np.abs(law.elastic(cell.lengths)) / np.asarray(law.EA, dtype=float)
    j = int(np.argmin(strain))
    if strain[j] < 10 * rtol:
        raise ValueError(
            f"{flag}: tendon {j} carries a strain of {strain[j]:.2g} at rest (tension {law.elastic(cell.lengths)[j]:.3g} N "
            f"against EA = {law.EA[j]:.3g} N), below 10 × the integrator's --rtol {rtol:g}: its tension is integration "
            "noise, so the nonlinear simulation cannot resolve this cell (lower --rtol, raise the prestress, or fit with "
            "the prestress kept active; the linear results — creep, moduli — are exact)")


def check_resolvable_frequency(cell, law, f: float, rtol: float) -> None:
    """ValueError if the integrator cannot resolve G' at ``f`` Hz to about 1 %.

    The integrator's absolute tolerance is ``rtol`` × the static displacement;
    G' comes from the part of the response in phase with the load,
    ``Re J(f) / J(0)`` of the static one, which falls as 1/f² at high
    frequency. Measured on the paper cell, G' carries an error of about
    ``10 rtol J(0) / Re J(f)`` of G', so the part in phase must stay above
    ``1000 rtol`` of the static response (at 1 GHz it is 1e-15 of it and the
    simulated G' was 1.3e8 Pa against 2.1e3 Pa). Checked on the linear model;
    laws without a linearization (beta < 1) are not checked.
    """
    import numpy as np

    from ..dynamics import linearize_law
    from ..laws import LinearizationError
    from ..response import compliance

    try:
        lin = linearize_law(cell, law)
    except LinearizationError:
        return
    floor = 1000.0 * rtol
    lo, hi, unit = RANGES["frequency"]
    with np.errstate(all="ignore"):
        J0 = abs(compliance(lin, np.array([lo]))[0])
        ratio = abs(compliance(lin, np.array([f]))[0].real) / J0
        if ratio >= floor:
            return
        grid = np.logspace(math.log10(lo), math.log10(hi), 481)  # 20 per decade
        ok = (np.abs(compliance(lin, grid).real) / J0 >= floor) & (grid < f)
    f_max = float(grid[ok].max()) if ok.any() else lo
    raise ValueError(f"--freq {f:g} Hz: the response in phase with the load is {ratio:.2g} of the static one, too "
                     f"small for the integrator at --rtol {rtol:g} to give G' to 1%; allowed up to about "
                     f"{f_max:.2g} Hz for this cell (or a smaller --rtol; linear G', G'' at any frequency: "
                     "`tenscell moduli`)")


#: most samples a simulation may store (samples per cycle × cycles; 1e6 samples of the 36 tensions
#: are about 300 MB of traces)
MAX_SAMPLES = 1_000_000
#: cycles the adaptive mode of oscillatory_response runs at most (its max_cycles default)
ADAPTIVE_MAX_CYCLES = 400


def check_samples(samples: int, cycles: int | None) -> None:
    """ValueError if --samples × --cycles (or the adaptive maximum) exceeds :data:`MAX_SAMPLES`."""
    n_cycles = cycles if cycles is not None else ADAPTIVE_MAX_CYCLES
    n = samples * n_cycles
    if n > MAX_SAMPLES:
        what = f"--cycles {cycles}" if cycles is not None else f"up to {ADAPTIVE_MAX_CYCLES} adaptive cycles"
        from ._cost import size

        raise ValueError(f"--samples {samples} × {what} is {n:,} samples (about {size(n * 40 * 8)} of "
                         f"traces); at most {MAX_SAMPLES:,}")


def simulate_cost(cell, law, f: float, amplitudes, cycles: int | None, kw: dict):
    """The simulations' cost from one cycle at the largest amplitude, timed here; None for one short simulation.

    Every simulation runs ``cycles`` cycles, or in the adaptive mode 2 to :data:`ADAPTIVE_MAX_CYCLES` (the
    line states both). The first cycle also carries the setup, so the rate is on the high side for small
    amplitudes.
    """
    from ..dynamics import oscillatory_response

    n_sims = len(amplitudes)
    if n_sims == 1 and (cycles or 0) <= 10:
        return None
    big = max(amplitudes)
    per = measure(lambda: oscillatory_response(cell, law, big, f, **{**kw, "cycles": 1}), max_calls=1)
    unit = "N" if kw.get("control", "force") == "force" else "m"
    timed = f"; one cycle at {big:g} {unit} timed"
    if cycles:
        return Cost("cycle", n_sims * cycles, per, 1, detail=f"= {n_sims} simulations × {cycles} cycles{timed}")
    return Cost("cycle", n_sims * 2, per, 1, count_max=n_sims * ADAPTIVE_MAX_CYCLES,
                detail=f"= {n_sims} simulations × 2 to {ADAPTIVE_MAX_CYCLES} adaptive cycles{timed}")


def _simulate_setup(args):
    """Every check of `tenscell simulate` before its work: (output set, cell, law, amplitudes swept, the
    keyword arguments of oscillatory_response)."""
    from ..dynamics import EquationsOfMotion, SineDisplacement, SineForce
    from ..dynamics.checks import check_start
    from ..io.outputs import OutputSet

    check_samples(args.samples, args.cycles)
    sweep_amps = getattr(args, "sweep_amplitudes", None) or (args.amplitude if len(args.amplitude) > 1 else None)
    if sweep_amps and args.control == "displacement":
        raise ValueError("--control displacement takes one --amplitude (m): the amplitude sweep prescribes forces (N)")
    out = OutputSet(args.out, command=args.command_line, flag="--out")
    cell, law, solver = law_from_args(args)
    check_resolvable_prestrain(cell, law, solver["rtol"], "--from-fit" if args.from_fit else "--prestress")
    check_resolvable_frequency(cell, law, args.freq, solver["rtol"])
    EquationsOfMotion(cell, law, SineForce(1.0, args.freq))  # refuses a singular damping matrix before any output
    load = SineForce if args.control == "force" else SineDisplacement
    unit = "N" if args.control == "force" else "m"
    if args.control == "displacement" and args.amplitude[0] >= cell.strut_length:
        raise ValueError(f"--amplitude {args.amplitude[0]:g} m with --control displacement: the probe would move "
                         f"farther than the cell's struts are long ({cell.strut_length:g} m); a displacement "
                         "amplitude is a small fraction of the cell")
    for a in dict.fromkeys([args.amplitude[0], *(sweep_amps or ())]):  # where each run starts, before the first runs
        check_start(cell, law, load(a, args.freq), slack=args.slack, name=f"--amplitude {a:g} {unit}")
    kw = dict(control=args.control, cycles=args.cycles, samples_per_cycle=args.samples, **solver)
    cost = simulate_cost(cell, law, args.freq, [args.amplitude[0], *(sweep_amps or ())], args.cycles, kw)
    if cost is not None:
        announce(check(cost, "--amplitude × --cycles" if args.cycles else "--amplitude"))
    return out, cell, law, sweep_amps, kw


def run_simulate(args) -> int:
    out, cell, law, sweep_amps, kw = _simulate_setup(args)
    import numpy as np

    from .. import plotting
    from .._progress import stage
    from ..dynamics import amplitude_sweep, oscillatory_response
    from ..io.outputs import write_csv_rows, write_json
    from ..io.tables import finite

    amplitude = args.amplitude[0]
    f = args.freq
    stage(f"simulating {args.cycles or 'until periodic,'} cycles at {f:g} Hz, amplitude {amplitude:g} "
          f"{'N' if args.control == 'force' else 'm'}")
    res = oscillatory_response(cell, law, amplitude, f, **kw)
    finite([res.G_storage, res.G_loss], "G', G'' of the simulation")
    sim, h = res.simulation, res.harmonics
    sweep = None
    if sweep_amps:
        stage(f"amplitude sweep: {len(sweep_amps)} simulations")
        sweep = amplitude_sweep(cell, law, f, np.asarray(sweep_amps), **{k: v for k, v in kw.items() if k != "control"})
    unit = "N" if args.control == "force" else "m"
    label = f"{args.control} amplitude {amplitude:g} {unit}, {f:g} Hz"
    t, z, F = res.cycle()
    zl, Fl = res.linear_cycle()
    lin_ok = res.linear is not None
    ref = abs(h.response[1])
    summary = res.summary()
    summary["model"] = {"cell": cell.describe(), "law": type(law).__name__, "beta": args.beta,
                        "EA": _jsonable(args.EA) if args.from_fit is None else law.EA.tolist(),
                        "c": _jsonable(args.c) if args.from_fit is None else law.c.tolist(),
                        "prestress_N": args.prestress_N, "from_fit": args.from_fit}
    written = ["traces.csv", "traces.png", "loop.csv", "loop.png", "harmonics.csv", "harmonics.png"]
    if sweep is not None:
        summary["sweep"] = {
            "amplitudes_N": sweep.amplitudes.tolist(),
            "amplitude_for_1pct_departure_N": sweep.threshold("departure", 0.01),
            "amplitude_for_1pct_storage_departure_N": sweep.threshold("storage_departure", 0.01),
            "amplitude_for_1pct_loss_departure_N": sweep.threshold("loss_departure", 0.01),
            "amplitude_for_1pct_thd_N": sweep.threshold("thd", 0.01),
        }
        written.append("sweep.csv")
    written.append("simulate.json")
    with out as d:
        write_csv_rows(d / "traces.csv", ["t_s", "force_N", "z_m", "load_displacement_m"]
                       + [f"T{j}_N" for j in range(cell.m)],
                       ([float(sim.t[k]), float(sim.force[k]), float(sim.z[k]), float(sim.u[k])]
                        + [float(x) for x in sim.tensions[k]] for k in range(sim.t.size)))
        plotting.save(plotting.time_traces(sim, f"Nonlinear simulation: {label}"), d / "traces.png")
        write_csv_rows(d / "loop.csv", ["t_s", "force_N", "z_m", "z_linear_m", "force_linear_N"],
                       ([float(a), float(b), float(c_), float(e), float(g)] for a, b, c_, e, g in zip(t, F, z, zl, Fl)))
        plotting.save(plotting.force_displacement_loop(z, F, zl if lin_ok else None, Fl if lin_ok else None,
                                                       f"Force-displacement loop: {label}"), d / "loop.png")
        write_csv_rows(d / "harmonics.csv", ["harmonic", "frequency_Hz", "z_amplitude_m", "z_phase_rad", "z_relative",
                                             "force_amplitude_N"],
                       ([k, k * f, float(abs(h.response[k])), float(np.angle(h.response[k])),
                         float(abs(h.response[k]) / ref), float(abs(h.force[k]))] for k in range(1, h.response.size)))
        plotting.save(plotting.harmonic_spectrum(h), d / "harmonics.png")
        if sweep is not None:
            write_csv_rows(d / "sweep.csv", ["amplitude_N", "G_storage_Pa", "G_loss_Pa", "storage_departure",
                                             "loss_departure", "thd", "periodicity", "n_slack"], sweep.rows())
        write_json(d / "simulate.json", summary)
    print(f"G' = {res.G_storage:.6g} Pa (linear {res.G_storage_linear:.6g}), G'' = {res.G_loss:.6g} Pa "
          f"(linear {res.G_loss_linear:.6g}), THD = {100 * res.thd:.3g} %, slack tendons: {sim.slack_tendons or 'none'}")
    if not (h.periodicity <= 1e-4):
        print(f"tenscell simulate: warning: the last two cycles differ by {h.periodicity:.2g} of the amplitude; "
              "the state may not be periodic yet (raise --cycles or omit it for the adaptive default)", file=sys.stderr)
    print(f"tenscell: wrote {', '.join(written)} in {out.target}/", file=sys.stderr)
    return 0


def _jsonable(v):
    if isinstance(v, tuple):
        return list(v)
    return v


def creep_times(t_min: float, t_max: float, points: int):
    """The output times of `tenscell creep` (s): ``points`` log-spaced from ``t_min`` to ``t_max``."""
    import numpy as np

    return np.logspace(math.log10(t_min), math.log10(t_max), points)


def check_window(t, window) -> None:
    """ValueError unless --window holds at least two of the output times ``t`` (a power law needs two points)."""
    if window is None:
        return
    a, b = window
    inside = int(((t >= a) & (t <= b)).sum())
    if inside < 2:
        raise ValueError(f"--window {a:g}:{b:g} s holds {inside} of the {t.size} output times "
                         f"({t[0]:g} to {t[-1]:g} s, --t-min/--t-max/--points); a power-law fit needs at least 2")


#: output times × steps below which creep runs without an estimate (the default 61 × 2 take a few seconds)
_QUICK_CREEP_POINTS = 1000


def creep_cost(eq, cell, force: float, steps: int, points: int):
    """A lower bound on the nonlinear steps' cost: the state at each output time, timed here once.

    Every output time of every step costs one solve of the state (tensions, velocities, slack set; about
    1.6 ms for the paper cell), on top of the integration itself, which is not counted. None for short runs.
    """
    import numpy as np

    from ..dynamics import EquationsOfMotion, StepForce

    if steps * points <= _QUICK_CREEP_POINTS:
        return None
    loaded = EquationsOfMotion(cell, eq.law, StepForce(force)) if force else eq
    # a new state each call, as along a trajectory (the solver warm-starts from the last one: a repeated state
    # would take 21 µs instead of the 1.6 ms of a new one)
    rng = np.random.default_rng(0)
    scale = 1e-3 * float(np.max(cell.lengths))
    per = measure(lambda: loaded.state(1.0, rng.normal(scale=scale, size=cell.n)), max_calls=20)
    return Cost("output time", steps * points, per, 1,
                detail=f"= {steps} steps × {points} --points; at least: the integration adds to it")


def _creep_setup(args):
    """Every check of `tenscell creep` before its work: (output set, times, cell, law, solver options, step forces)."""
    from ..dynamics import EquationsOfMotion, StepForce
    from ..dynamics.checks import check_start
    from ..io.outputs import OutputSet

    if not args.t_min < args.t_max:
        raise ValueError(f"--t-min must be below --t-max, got {args.t_min:g} s and {args.t_max:g} s")
    t = creep_times(args.t_min, args.t_max, args.points)
    check_window(t, args.window)
    out = OutputSet(args.out, command=args.command_line, flag="--out")
    cell, law, solver = law_from_args(args)
    amplitudes = args.amplitude if args.amplitude is not None else (() if args.from_fit else (0.1, 30.0))
    if len(amplitudes):
        check_resolvable_prestrain(cell, law, solver["rtol"], "--from-fit" if args.from_fit else "--prestress")
    eq = EquationsOfMotion(cell, law, StepForce(1.0))  # refuses a singular damping matrix before any output
    for F in dict.fromkeys(amplitudes):  # where each step starts, before the first is integrated
        check_start(cell, law, StepForce(float(F)), slack=args.slack, name=f"--amplitude {F:g} N (a step force)")
    cost = creep_cost(eq, cell, max(amplitudes, default=0.0), len(amplitudes), t.size)
    if cost is not None:
        announce(check(cost, "--amplitude × --points"))
    return out, t, cell, law, solver, amplitudes


def run_creep(args) -> int:
    out, t, cell, law, solver, amplitudes = _creep_setup(args)
    from ..dynamics import linearize_law
    from ..laws import LinearizationError

    win = args.window or (float(t[0]), float(t[-1]))
    P0 = args.prestress_N
    try:
        lin, note = linearize_law(cell, law), ""
    except LinearizationError as err:  # beta < 1: only the nonlinear curves exist
        lin, note = None, str(err)
    curves, expo = {}, {}
    summary: dict = {"model": {"cell": cell.describe(), "law": type(law).__name__, "beta": args.beta, "prestress_N": P0,
                         "from_fit": args.from_fit},
               "linear_note": note, "power_law_window_s": [float(win[0]), float(win[1])]}
    tables = {}
    if lin is not None:
        curves["linear"], expo["linear"], tables, linear_summary = _linear_creep(lin, t)
        summary.update(linear_summary)
    summary["steps"], step_curves, step_expo = _creep_steps(cell, law, amplitudes, t, solver, curves.get("linear"))
    curves.update(step_curves)
    expo.update(step_expo)
    fits, summary["power_law_fits"], fit_lines = _creep_power_laws(t, win, curves, expo)
    figure = _creep_figure(t, curves, expo, fits.get("linear"), P0)
    _write_creep(out, t, curves, expo, tables, figure, summary)
    for line in fit_lines:
        print(line)
    if note:
        print(f"tenscell creep: note: {note}", file=sys.stderr)
    files = ["creep.csv", "creep.png", *tables, "creep.json"]
    print(f"tenscell: wrote {', '.join(files)} in {out.target}/", file=sys.stderr)
    return 0


def _linear_creep(lin, t):
    """The linear model's creep compliance (m/N) and local exponent at times ``t`` (s), its tables and summary."""
    from ..io.tables import finite
    from ..linear.assembly import continuum_factor
    from ..timedomain import creep_spectrum, stress_relaxation

    spec = creep_spectrum(lin)
    curve = finite(spec.compliance(t), "the linear creep compliance")
    exponent = spec.exponent(t)
    rel = stress_relaxation(lin)
    tables = {
        "spectrum.csv": (["retardation_time_s", "weight_m_per_N"],
                         [[float(a), float(b)] for a, b in zip(spec.times, spec.weights)]),
        "relaxation.csv": (["t_s", "G_relaxation_Pa"], [[float(a), float(b)] for a, b in zip(t, rel.modulus(t))]),
    }
    summary = {
        "static_compliance_m_per_N": spec.static,
        "instantaneous_compliance_m_per_N": spec.instantaneous,
        "retardation_times_s": spec.times.tolist(),
        "retardation_weights_m_per_N": spec.weights.tolist(),
        "relaxation": {"equilibrium_modulus_Pa": continuum_factor(rel.L) * rel.equilibrium, "viscosity_Pa_s": rel.viscosity,
                       "times_s": rel.times.tolist(), "weights_N_per_m": rel.weights.tolist()},
    }
    return curve, exponent, tables, summary


def _creep_steps(cell, law, amplitudes, t, solver, linear):
    """The creep after each force step (N) at times ``t`` (s): (step summaries, compliances (m/N), local exponents).

    ``linear`` is the linear compliance (m/N) each step is compared with, or None; a compliance that is not
    positive throughout has no local exponent.
    """
    import numpy as np

    from .._progress import stage
    from ..dynamics import creep_response
    from ..io.tables import finite
    from ..timedomain import local_exponent

    steps, curves, expo = [], {}, {}
    for n_step, F in enumerate(amplitudes, 1):
        stage(f"creep after a {F:g} N step ({n_step}/{len(amplitudes)})")
        cr = creep_response(cell, law, float(F), t, **solver)
        key = f"step {F:g} N"
        curves[key] = finite(cr.compliance, f"the creep compliance after the {F:g} N step")
        step = {"force_N": float(F), "slack_tendons": cr.simulation.slack_summary()}
        if linear is not None:
            step["max_relative_departure_from_linear"] = float(np.abs(cr.compliance / linear - 1).max())
        steps.append(step)
        if np.all(cr.compliance > 0):
            expo[key] = local_exponent(t, cr.compliance)
    return steps, curves, expo


def _creep_power_laws(t, win, curves: dict, expo: dict):
    """Power-law fits of the compliances (m/N) over the window ``win`` (s): (fits, their summary, report lines)."""
    import numpy as np

    from ..timedomain import fit_power_law

    inwin = (t >= win[0]) & (t <= win[1])
    fits, summary, lines = {}, {}, []
    for k, J in curves.items():
        if np.all(J[inwin] > 0) and inwin.sum() >= 2:
            fits[k] = fit_power_law(t, J, win[0], win[1])
    for k, v in fits.items():
        e = expo.get(k)
        rng = [float(e[inwin].min()), float(e[inwin].max())] if e is not None else None
        summary[k] = {"A_m_per_N": v.A, "alpha": v.alpha, "rms_log": v.rms_log, "max_rel": v.max_rel,
                      "points": v.n, "local_exponent_range": rng}
        lines.append(f"{k}: J(t) ~ {v.A:.4g}·t^{v.alpha:.4f} over [{v.t_min:g}, {v.t_max:g}] s "
                     f"(rms log residual {v.rms_log:.3g})"
                     + (f"; local exponent in the window {rng[0]:.3g}..{rng[1]:.3g}" if rng else ""))
    return fits, summary, lines


def _creep_figure(t, curves: dict, expo: dict, linear_fit, P0: float):
    """The log-log plot of the compliances (m/N) against time (s) for prestress ``P0`` (N)."""
    from .. import plotting

    return plotting.creep_loglog(t, curves, expo, linear_fit, f"Creep after a force step (P = {P0:g} N)")


def _write_creep(out, t, curves: dict, expo: dict, tables: dict, figure, summary: dict) -> None:
    """Write creep.csv (times in s, compliances in m/N, exponents), the extra tables, creep.png and creep.json."""
    from .. import plotting
    from ..io.outputs import write_csv_rows, write_json

    keys = list(curves)
    with out as d:
        write_csv_rows(d / "creep.csv", ["t_s"] + [f"J_{k.replace(' ', '_')}_m_per_N" for k in keys]
                       + [f"exponent_{k.replace(' ', '_')}" for k in expo],
                       ([float(t[i])] + [float(curves[k][i]) for k in keys] + [float(e[i]) for e in expo.values()]
                        for i in range(t.size)))
        for name, (header, rows) in tables.items():
            write_csv_rows(d / name, header, rows)
        plotting.save(figure, d / "creep.png")
        write_json(d / "creep.json", summary)

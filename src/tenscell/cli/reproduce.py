"""``tenscell reproduce``: the paper's figures, tables and claims, plus the studies, into one output set.

Each stage is ``(title, function(out_dir, log))``; the whole directory is one
output set (staged, committed when every stage succeeded).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

from ._args import add_out


def reproduce_homogeneous(out: Path, log) -> None:
    """Paper Figs. 2–3 and claims.md into ``out``."""
    from .. import plotting
    from ..io.outputs import write_csv_rows, write_text
    from ..io.tables import moduli_table
    from ..studies import claims as studies

    study = studies.homogeneous_study()
    write_csv_rows(out / "fig2_prestress.csv", *moduli_table(study.fig2))
    plotting.save(plotting.fig2_prestress(study.fig2), out / "fig2_prestress.png")
    log("fig2_prestress.png, fig2_prestress.csv")
    write_csv_rows(out / "fig3_frequency.csv", *moduli_table(study.fig3))
    plotting.save(plotting.fig3_frequency(study.fig3), out / "fig3_frequency.png")
    log("fig3_frequency.png, fig3_frequency.csv")
    claims = studies.paper_claims(study, studies.robustness())
    write_text(out / "claims.md", studies.claims_markdown(claims, study))
    log("claims.md")


def _write_fit(out: Path, stem: str, result, baseline, title: str, log) -> None:
    from ..fitting.prestress import prestress_activity
    from .fit import fit_outputs

    outputs = fit_outputs(result, baseline, title=title)
    for ext in ("png", "csv", "json", "md", "html"):
        outputs[ext](out / f"{stem}.{ext}")
    pa = prestress_activity(result)
    each = ", ".join(f"{f.rms_log10_error:.4f}" for f in result.fits)
    log(f"{stem}.png, .csv, .json, .md, .html (rms {each}, homogeneous {baseline.rms_log10_error:.3f}; "
        f"dlnG'/dlnP at {pa.reference_frequency_hz:g} Hz {pa.reference_storage.min():.3g} to "
        f"{pa.reference_storage.max():.3g})")


#: the search of the paper's fits: the command's default search on 2 processes, polishing longer so that the figures
#: sit well inside the tolerance; the searches stop at their target, which keeps `make reproduce` fast
FIT_SEARCH: dict[str, Any] = {"starts": 4, "seed": 0, "jobs": 2, "tolerance": 0.01, "baseline_starts": 1,
                              "polish_effort": 4.0}


def reproduce_fit(out: Path, log) -> None:
    """Paper Figs. 4 and 5, Fig. 5 with its prestress kept active, and the joint fit of both data sets."""
    from ..fitting.models import VoigtModel
    from ..io.data import bundled
    from .fit import BUNDLED_FREQUENCY_PRESTRESS_PA, run_fit

    search = FIT_SEARCH
    active: dict[str, Any] = {"min_prestress_elasticity": 0.7}  # ∂lnG'/∂lnP at 0.1 Hz as in adherent cells
    for name, stem, title, damping, extra in (
        ("stamenovic2002", "fig4_prestress_fit", "Fig. 4: moduli versus prestress at 0.1 Hz (Stamenović 2002)",
         "uniform", {}),
        ("fabry2001", "fig5_frequency_fit", "Fig. 5: moduli versus frequency (Fabry 2001)", "uniform", {}),
        ("fabry2001", "fig5_frequency_fit_active_prestress",
         "Fig. 5 with the prestress kept active (dlnG'/dlnP >= 0.7 at 0.1 Hz), per-family damping", "per-family",
         active),
        ("fabry2001", "fig5_frequency_fit_active_prestress_uniform_damping",
         "Fig. 5 with the prestress kept active (dlnG'/dlnP >= 0.7 at 0.1 Hz), the paper's single damping",
         "uniform", active),
    ):
        result, baseline = run_fit(bundled(name), VoigtModel("per-tendon", damping, **extra), **search)
        _write_fit(out, stem, result, baseline, title, log)
    data = [bundled("stamenovic2002"), bundled("fabry2001").with_prestress(BUNDLED_FREQUENCY_PRESTRESS_PA)]
    result, baseline = run_fit(data, VoigtModel("per-tendon", "per-family"), **search)
    _write_fit(out, "joint_fit", result, baseline,
               f"Joint fit: prestress sweep and frequency sweep (at {BUNDLED_FREQUENCY_PRESTRESS_PA:g} Pa), one "
               "parameter set, per-family damping", log)
    _reproduce_mechanisms(out, data, result, log)


def _reproduce_mechanisms(out: Path, data, per_tendon, log) -> None:
    """The study's answer on the bundled data: the leading mechanisms beside the joint per-tendon fit (one table)."""
    from ..io.outputs import write_csv_rows, write_json, write_text
    from ..studies.leading import leading_mechanisms

    c = leading_mechanisms(data, per_tendon, jobs=2)
    t = c.table()
    write_csv_rows(out / f"{t.name}.csv", list(t.columns), t.rows)
    write_text(out / "mechanisms_vs_per_tendon.md", c.markdown())
    win = c.winner
    write_json(out / f"mechanism_{win.model}.json", c.fits[win.model].to_dict())
    log(f"mechanisms_vs_per_tendon.csv, .md, mechanism_{win.model}.json ({win.model} with the frequency sweep stated "
        f"at {c.prestress_pa:g} Pa: {win.free_parameters} parameters, rms {win.rms[0]:.4f}/{win.rms[1]:.4f}, BIC "
        f"{win.bic:.1f} against {c.per_tendon.bic:.1f} for the per-tendon fit)")


def reproduce_dynamics(out: Path, log) -> None:
    """Time-domain checks into ``out/dynamics``: small-amplitude moduli, a nonlinear loop, creep."""
    import numpy as np

    from .. import plotting
    from ..dynamics import creep_response, oscillatory_response
    from ..io.outputs import write_json
    from ..laws import voigt_law
    from ..model.shapes import paper_cell
    from ..timedomain import creep_spectrum

    d = out / "dynamics"
    cell = paper_cell()
    law = voigt_law(cell, P=1000.0, EA=1.0, c=1.0)
    small = oscillatory_response(cell, law, 0.1, 1.0, samples_per_cycle=64)
    big = oscillatory_response(cell, law, 30.0, 1.0, samples_per_cycle=64)
    t, z, F = big.cycle()
    zl, _ = big.linear_cycle()
    plotting.save(plotting.force_displacement_loop(z, F, zl, None, "Default cell, 30 N at 1 Hz: nonlinear vs linear"),
                  d / "loop_30N_1Hz.png")
    plotting.save(plotting.harmonic_spectrum(big.harmonics), d / "harmonics_30N_1Hz.png")
    ts = np.logspace(-5, 0, 31)
    spec = creep_spectrum(small.linear)
    creep = {f"step {F_:g} N": creep_response(cell, law, F_, ts).compliance for F_ in (0.1, 30.0)}
    plotting.save(plotting.creep_loglog(ts, {"linear": spec.compliance(ts), **creep}, {"linear": spec.exponent(ts)},
                                        None, "Default cell: creep after a force step"), d / "creep.png")
    rows = {}
    for name, r in (("0.1 N, 1 Hz", small), ("30 N, 1 Hz", big)):
        rows[name] = {k: r.summary()[k] for k in ("G_storage", "G_loss", "G_storage_linear", "G_loss_linear", "thd",
                                                   "periodicity", "work_per_cycle_J", "dissipated_per_cycle_J")}
        rows[name]["slack_tendons"] = r.simulation.slack_tendons
    rows["creep_max_departure"] = {k: float(np.abs(v / spec.compliance(ts) - 1).max()) for k, v in creep.items()}
    write_json(d / "dynamics.json", rows)
    log("dynamics/loop_30N_1Hz.png, dynamics/harmonics_30N_1Hz.png, dynamics/creep.png, dynamics/dynamics.json")


def reproduce_variants(out: Path, log) -> None:
    """All five variant studies into ``out/variants/<name>/``."""
    from ..studies.protocol import run_study
    from ._study_output import write_study_result
    from .study import VARIANTS, load_study

    for name in VARIANTS:
        d = out / "variants" / name
        d.mkdir(parents=True, exist_ok=True)
        result = run_study(load_study(name), {})
        write_study_result(d, result)
        log(f"variants/{name}: {', '.join(result.files())}")


def reproduce_show(out: Path, log) -> None:
    """`tenscell show paper`: the cell in 3D (paper Fig. 1 colours), its slowest modes and summary."""
    from .. import plotting
    from ..io.outputs import write_text
    from ..model.shapes import paper_cell
    from ..summary import relaxation_modes, summarize

    summary, cell, lin = summarize(paper_cell())
    modes = relaxation_modes(lin, 3)
    text = summary.text() + "slowest modes  " + ", ".join(f"{r:.6g}" for r in modes.rates) + " 1/s\n"
    write_text(out / "show_paper_summary.txt", text)
    plotting.save(plotting.structure_3d(cell.structure, title="paper cell (Fig. 1 colours)"),
                  out / "show_paper_structure.png")
    plotting.save(plotting.relaxation_modes_3d(cell.structure, modes.rates, modes.displacements),
                  out / "show_paper_modes.png")
    log("show_paper_structure.png, show_paper_modes.png, show_paper_summary.txt")


#: the stages of `tenscell reproduce`, in order: (title, function(out_dir, log))
REPRODUCE_STAGES = [
    ("homogeneous study (Figs. 2-3, claims)", reproduce_homogeneous),
    ("heterogeneous fits (Figs. 4-5, Fig. 5 with an active prestress, joint fit of both data sets, the winning "
     "mechanism beside it)", reproduce_fit),
    ("time domain (small-amplitude moduli, nonlinear loop, creep)", reproduce_dynamics),
    ("discussion variants and future work (no-IF, sensitivity, references, semiflexible, stiffening)",
     reproduce_variants),
    ("3D view and summary of the paper cell (tenscell show paper)", reproduce_show),
]


def register(sub) -> None:
    p = sub.add_parser("reproduce", help="write the paper's figures, tables and claims",
                       description="Reproduce the paper's figures and tables into a directory (one output set: "
                                   "the directory is replaced as a whole when every stage succeeded).")
    add_out(p, default="out")
    p.set_defaults(func=run)


#: CPU seconds of a whole `tenscell reproduce` (this process and its workers: /usr/bin/time's user time), calibrated
#: on 2 cores (load 21: 861 s of wall time); the estimate scales it by the CPUs the present load leaves
REPRODUCE_CPU_S = 134.0


def reproduce_cost():
    """The run's estimate: :data:`REPRODUCE_CPU_S` of CPU over the share of the machine's CPUs the present load leaves
    (:func:`tenscell.cli._cost.cpu_share`, for the two processes its fits use)."""
    import os

    from ._cost import Cost, cpu_share

    workers = 2
    share = cpu_share(workers)
    load = os.getloadavg()[0]
    return Cost("stage", len(REPRODUCE_STAGES), REPRODUCE_CPU_S / len(REPRODUCE_STAGES) / share, workers,
                basis="calibrated",
                detail=f"({REPRODUCE_CPU_S:g} s of CPU on 2 cores, at {share:.0%} of a CPU per process: load "
                       f"{load:.1f} on {os.cpu_count()} CPUs; the fits' stage is most of it)")


def run(args) -> int:
    from .._progress import stage
    from ..io.outputs import OutputSet
    from ._cost import announce

    out = OutputSet(args.out, command=args.command_line, flag="--out")
    announce(reproduce_cost())
    t0 = time.perf_counter()
    with out as d:
        for k, (title, run_stage) in enumerate(REPRODUCE_STAGES, 1):
            t = time.perf_counter()
            stage(f"[{k}/{len(REPRODUCE_STAGES)}] {title} ...")
            run_stage(d, lambda msg: stage(f"    wrote {msg}"))
            stage(f"    done in {time.perf_counter() - t:.1f} s")
    print(f"tenscell: reproduce finished in {time.perf_counter() - t0:.1f} s; results in {out.target}/",
          file=sys.stderr)
    return 0

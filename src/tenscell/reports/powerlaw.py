"""The power-law study's page (:mod:`tenscell.studies.powerlaw`): the answers, the map's table, the fits, the cost.

Rendered from the study's tables and checks only: every number printed is one the run computed.
"""
from __future__ import annotations

import math

from ._format import num, table

__all__ = ["powerlaw_markdown"]

_WHY = {
    "diluted": (
        "One member time constant (τ = c·l/EA: one c, one EA) and member damping: the spread of relaxation rates comes "
        "only from the ratio of the prestress stiffness to the cables' own, mode by mode. Far above the rigidity "
        "threshold every mode stretches cables: one rate, a solid beside a dashpot. Near it, the cables' soft modes, "
        "held by the prestress, relax from the members' rate upwards, and above a crossover that the prestress "
        "raises (the prestress plateau, ∝ P) G' follows a power law; its exponent is set by how many nearly floppy "
        "modes the particular network has near the probe, which changes from one random network to the next at the "
        "same connectivity and does not settle as the network grows (the realizations' table). Below z = 6 the "
        "floppy modes stretch no cable, so no member damps them: they answer at once, G' levels off and G'' falls "
        "at high frequency. The prestress moves the crossover, not the exponent."
    ),
    "hierarchical": (
        "The prestress is the restoring spring of the out-of-plane motion (P·q times the graph Laplacian of the net) "
        "and the tethers its only damping: the compliance is the local resolvent of diffusion on a self-similar net, "
        "J ∝ (iω)^(d_s/2 − 1), α = 1 − d_s/2 = 1 − ln k/ln(k + 2) for modules of k nodes. The power law runs "
        "between the whole net's slowest rate (each level adds a factor k + 2 in time) and a node's own rate; above "
        "it the tethers' dashpots take over (G'' ∝ f), below it the anchors hold the net (a plateau ∝ P). Every "
        "stiffness in that range is P·q and every damping a tether's, so G(f, P) = P·g(f·c/P): the prestress only "
        "slides the curve along f, and inside the window α does not change with P (it falls at a fixed frequency "
        "only where the low-frequency plateau moves in)."
    ),
    "structural": (
        "A lattice's members take a few lengths and forces (one per family: cables, struts, filaments), and a "
        "form-found network's lengths and forces spread by less than a decade, so damping set by length (c ∝ l^k) "
        "or by force (Bell's law) gives a few time constants, or a band of them less than a decade or two wide: a "
        "broadened Debye step, α passing through 0.1–0.3 on its way from 0 to 1 rather than staying there. A broad "
        "spectrum needs lengths over decades, i.e. a hierarchy, which is the previous family's."
    ),
}


def _rows(tables, name):
    return next(t for t in tables if t.name == name).records()


def _answers(fams, fits, checks) -> list[str]:
    law = next((c for c in checks if c.label.startswith("G6a")), None)
    falls = next((c for c in checks if c.label.startswith("G6b")), None)
    out = ["## The answers", ""]
    if law is not None:
        out.append(f"**(a) A power law in 0.1–0.3 over ≥ 3 decades with the loss tangent of one:** "
                   f"{'yes' if law.met else 'no'}. Closest: {law.closest}: {law.detail}.")
    if falls is not None:
        best = next((r for r in fams if r["best_structure"] == falls.closest), None)
        extra = ""
        if best is not None:
            extra = (f" At 0.1 Hz, dα/d ln P = {num(best['dalpha_dlnP_0p1Hz'], 3)}; at 1 Hz "
                     f"{num(best['dalpha_dlnP_1Hz'], 3)}.")
        out.append(f"**(b) Does raising the prestress lower α in it?** {'yes' if falls.met else 'no'}: "
                   f"{falls.detail}.{extra}")
    fit = next((c for c in checks if c.label.startswith("G6c")), None)
    if fit is not None:
        out.append(f"**Fits (exact scalings of the structure; goal RMS ≤ 0.03 decades):** "
                   f"{'met' if fit.met else 'not met'}: {fit.closest}: {fit.detail}.")
    return out + [""]


def _smallest(map_rows) -> list[str]:
    ok = [r for r in map_rows if r["g6_decades"] >= 3.0]
    out = ["**(c) The smallest such structure and the convergence of α with size:** "]
    if ok:
        per = []
        for fam in sorted({r["family"] for r in ok}):
            r = min((r for r in ok if r["family"] == fam), key=lambda r: r["coordinates"])
            per.append(f"{fam}: {r['label']} at prestrain {num(r['prestrain'])}, {r['coordinates']} coordinates, "
                       f"α = {num(r['g6_alpha'], 3)} over {num(r['g6_decades'], 3)} decades")
        out[0] += "; ".join(per) + "."
    else:
        out[0] += "none of the map's structures reaches 3 decades."
    hier = [r for r in map_rows if r["family"] == "hierarchical"]
    if hier:
        rows = []
        for k in sorted({int(r["module_nodes"]) for r in hier}):
            for d in sorted({int(r["depth"]) for r in hier if int(r["module_nodes"]) == k}):
                rs = [r for r in hier if int(r["module_nodes"]) == k and int(r["depth"]) == d]
                b = max(rs, key=lambda r: (r["band_decades"], r["power_law_decades"]))
                theory = 1.0 - math.log(k) / math.log(k + 2)
                rows.append((k, d, b["coordinates"], num(b["power_law_alpha"], 3), num(b["power_law_decades"], 3),
                             num(b["band_decades"], 3), num(b["g6_decades"], 3), num(theory, 3)))
        out += ["", "The hierarchical nets, depth by depth (each row its best prestrain; α of the longest ±0.05 "
                "stretch with α ≥ 0.05; 1 − ln k/ln(k + 2) is the infinite net's exponent):", "",
                table(["module nodes k", "depth", "coordinates", "α", "decades (±0.05)", "decades in 0.1–0.3",
                       "decades with tan δ", "1 − ln k/ln(k+2)"], rows)]
    return out


def _realizations(map_rows) -> list[str]:
    """The diluted Voigt nets at the connectivities mapped in more than one network (sizes, seeds)."""
    rows = [r for r in map_rows if r["family"] == "diluted" and r["law"] == "voigt"]
    zs = sorted({r["connectivity_target"] for r in rows})
    out = []
    for z in zs:
        nets = sorted({(int(r["size_cells"]), r["label"]) for r in rows if r["connectivity_target"] == z})
        if len(nets) < 2:
            continue
        for _, label in nets:
            rs = [r for r in rows if r["label"] == label]
            g = max(rs, key=lambda r: (r["g6_decades"], r["band_decades"]))
            p = max(rs, key=lambda r: r["power_law_decades"])
            out.append((num(z), label, rs[0]["coordinates"], f"{num(g['g6_decades'], 3)} ({num(g['g6_alpha'], 3)})",
                        f"{num(p['power_law_decades'], 3)} ({num(p['power_law_alpha'], 3)})"))
    if not out:
        return []
    return ["The diluted networks mapped more than once at one connectivity (other sizes, other random networks), "
            "each at its best prestrain:", "",
            table(["z", "network", "coordinates", "decades in 0.1–0.3 with tan δ (α)",
                   "longest ±0.05 stretch, α ≥ 0.05 (α)"], out), ""]


def powerlaw_markdown(study, tables, checks) -> str:
    """The page of a :class:`tenscell.studies.powerlaw.PowerLawStudy` (with the study's tables and checks)."""
    fams = _rows(tables, "powerlaw_families")
    map_rows = _rows(tables, "powerlaw_map")
    fits = _rows(tables, "powerlaw_fits")
    cost = _rows(tables, "powerlaw_cost")
    pts = study.points
    lines = [
        "# A power law the structure makes? Networks of plain members",
        "",
        f"Scale `{study.scale}`: {len(pts)} structures, {len({p.point.family for p in pts})} families, prestrains "
        f"{', '.join(num(e) for e in pts[0].prestrain)} (mean cable tension over EA), "
        f"{pts[0].frequency_hz.size} frequencies from {num(pts[0].frequency_hz[0])} to {num(pts[0].frequency_hz[-1])} Hz "
        "(the map reads 10⁻³–10⁴ Hz). Every member is a Voigt or Maxwell element; no springpot, no distribution.",
        "",
    ]
    lines += _answers(fams, fits, checks)
    lines += _smallest(map_rows) + [""]
    lines += ["## Each family: how close it comes, and why it stops there", ""]
    lines.append(table(
        ["family", "best structure (prestrain)", "decades in 0.1–0.3 (α)", "decades with tan δ (α, tan error)",
         "best tan error (≥ 1 decade)", "longest ±0.05 stretch (α)", "dα/d ln P in its band"],
        [(r["family"], f"{r['best_structure']} ({num(r['prestrain'])})",
          f"{num(r['band_decades'], 3)} ({num(r['band_alpha'], 3)})",
          f"{num(r['g6_decades'], 3)} ({num(r['g6_alpha'], 3)}, {num(r['g6_tan_error'], 2)})",
          num(r["best_tan_error"], 2), f"{num(r['longest_power_law_decades'], 3)} ({num(r['longest_power_law_alpha'], 3)})",
          num(r["dalpha_dlnP_common_band"], 3)) for r in fams]))
    lines += ["The prestress trend at 1 Hz over every structure of each family (dα/d ln P, by least squares over the four "
              "prestrains):", "",
              table(["family", "its best structure", "median of the family", "lowest (structure)", "highest (structure)"],
                    [(r["family"], num(r["dalpha_dlnP_1Hz"], 3), num(r["dalpha_dlnP_1Hz_median_family"], 3),
                      f"{num(r['dalpha_dlnP_1Hz_lowest'], 3)} ({r['dalpha_dlnP_1Hz_lowest_where']})",
                      f"{num(r['dalpha_dlnP_1Hz_highest'], 3)} ({r['dalpha_dlnP_1Hz_highest_where']})") for r in fams])]
    for r in fams:
        lines += [f"**{r['family']}.** {_WHY.get(r['family'], '')}", ""]
    lines += _realizations(map_rows)
    if fits:
        lines += ["## Fits to the bundled data", "",
                  "Each family's best structure on a finer prestrain grid, fitted through its exact scalings only "
                  "(stiffness ×λ: EA, c and P together; time ×μ: c alone), the Fabry cells' prestrain and, jointly "
                  "with the Stamenović series, a prestrain per pascal. RMS of the log10 errors of G' and G''. A fit on the "
                  "grid's edge wanted a scale beyond the computed frequencies or prestrains: its RMS is an upper "
                  "bound of what the structure can do.", "",
                  table(["family", "structure", "data", "RMS Fabry", "RMS Stamenović", "λ", "μ", "ε (Fabry)",
                         "ε per Pa", "converged", "on the grid's edge"],
                        [(r["family"], r["structure"], r["data"], num(r["rms_fabry2001_log10"], 3),
                          num(r["rms_stamenovic2002_log10"], 3), num(r["stiffness_scale"], 3), num(r["time_scale"], 3),
                          num(r["prestrain_fabry"], 3), num(r["prestrain_per_Pa"], 3), r["converged"],
                          r["at_grid_edge"]) for r in fits]),
                  ""]
    lines += ["## Goals", ""] + [f"- {'met' if c.met else 'NOT met'}: {c.label} — {c.closest + ': ' if c.closest else ''}"
                                  f"{c.detail}" for c in checks] + [""]
    big = [r for r in cost if r["coordinates"] >= 10_000]
    lines += ["## Cost", "",
              f"{num(study.cpu_s, 4)} s of CPU for the whole map (builds, spectra, fits), as each task measured it. "
              f"Structures of at least 10⁴ coordinates ({len(big)}), one prestrain's spectrum of "
              f"{pts[0].frequency_hz.size} frequencies on the sparse path:", ""]
    if big:
        lines.append(table(["structure", "coordinates", "build (s)", "spectrum (s, mean)"],
                           [(r["label"], r["coordinates"], num(r["build_cpu_s"], 3), num(r["spectrum_cpu_s_mean"], 3))
                            for r in big]))
    return "\n".join(lines) + "\n"

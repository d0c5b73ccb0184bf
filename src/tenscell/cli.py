"""The ``tenscell`` command line: parse arguments, call the library, write files.

Bad input (a ValueError from the library, an unreadable file) becomes one line
on stderr and exit status 2; no traceback.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

__all__ = ["main", "parse_frequencies", "parse_list"]


# ---- argument helpers -------------------------------------------------------------
def parse_list(text: str, name: str) -> np.ndarray:
    """``"500,1000"`` -> array; ValueError naming ``name`` on bad items."""
    out = []
    for item in str(text).split(","):
        item = item.strip()
        try:
            v = float(item)
        except ValueError:
            raise ValueError(f"{name}: {item!r} is not a number") from None
        out.append(v)
    return np.array(out)


def parse_frequencies(text: str) -> np.ndarray:
    """``"a:b:n"`` (n log-spaced points from a to b Hz) or a comma list (Hz)."""
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise ValueError(f"--freq: expected a:b:n or a comma list, got {text!r}")
        a, b = parse_list(parts[0], "--freq")[0], parse_list(parts[1], "--freq")[0]
        try:
            n = int(parts[2])
        except ValueError:
            raise ValueError(f"--freq: the point count {parts[2]!r} is not a whole number") from None
        if not (a > 0 and b > 0 and np.isfinite(a) and np.isfinite(b)):
            raise ValueError(f"--freq: the ends of a:b:n must be finite frequencies > 0 Hz, got {float(a)!r} and {float(b)!r}")
        if n < 1:
            raise ValueError(f"--freq: the point count must be at least 1, got {n}")
        return np.logspace(math.log10(a), math.log10(b), n)
    return parse_list(text, "--freq")


def add_model_options(p: argparse.ArgumentParser) -> None:
    """The options that choose the paper cell and its tendon properties (shared by commands)."""
    p.add_argument("--alpha-deg", type=float, default=0.0, help="reference azimuth α (degrees, default 0)")
    p.add_argument("--delta-deg", type=float, default=None,
                   help="reference declination δ (degrees; default 50 with IFs, the IF-free curve without)")
    p.add_argument("--EA", default="1", help="tendon stiffness EA (N), one value or one per tendon (comma list)")
    p.add_argument("--c", default="1", help="tendon damping c (N·s/m), one value or one per tendon (comma list)")
    p.add_argument("--L", type=float, default=1.0, help="strut length L (m, default 1)")
    p.add_argument("--no-if", action="store_true", help="remove the 12 intermediate filaments")


def model_from_args(args):
    """(cell, EA, c) from the shared model options."""
    from . import paper_cell

    delta = None if args.delta_deg is None else math.radians(args.delta_deg)
    cell = paper_cell(alpha=math.radians(args.alpha_deg), delta=delta, L=args.L,
                      intermediate_filaments=not args.no_if)
    EA = parse_list(args.EA, "--EA")
    c = parse_list(args.c, "--c")
    return cell, (EA[0] if EA.size == 1 else EA), (c[0] if c.size == 1 else c)


# ---- commands -----------------------------------------------------------------------
def _cmd_moduli(args) -> int:
    from . import frequency_response

    cell, EA, c = model_from_args(args)
    resp = frequency_response(cell, parse_frequencies(args.freq), parse_list(args.prestress, "--prestress"), EA=EA, c=c)
    out = sys.stdout
    out.write("prestress,frequency_Hz,G_storage,G_loss\n")
    for P, f, gs, gl in resp.rows():
        out.write(f"{P:.10g},{f:.10g},{gs:.10g},{gl:.10g}\n")
    return 0


def _add_moduli(sub) -> None:
    p = sub.add_parser("moduli", help="G', G'' of the paper cell as CSV on stdout",
                       description="Storage and loss moduli (Pa) of the paper cell, as CSV on standard output.")
    p.add_argument("--prestress", default="1000", help="prestresses P (comma list; N, the paper's Pa)")
    p.add_argument("--freq", default="0.01:1000:61", help="frequencies (Hz): comma list or a:b:n log-spaced")
    add_model_options(p)
    p.set_defaults(func=_cmd_moduli)


def reproduce_homogeneous(out: Path, log) -> None:
    """Paper Figs. 2–3 and claims.md into ``out``."""
    from . import plotting, studies
    from ._io import write_csv_rows, write_text

    study = studies.homogeneous_study()
    header = ["prestress", "frequency_Hz", "G_storage", "G_loss"]
    write_csv_rows(out / "fig2_prestress.csv", header, study.fig2.rows())
    plotting.save(plotting.fig2_prestress(study.fig2), out / "fig2_prestress.png")
    log("fig2_prestress.png, fig2_prestress.csv")
    write_csv_rows(out / "fig3_frequency.csv", header, study.fig3.rows())
    plotting.save(plotting.fig3_frequency(study.fig3), out / "fig3_frequency.png")
    log("fig3_frequency.png, fig3_frequency.csv")
    claims = studies.paper_claims(study, studies.robustness())
    write_text(out / "claims.md", studies.claims_markdown(claims, study))
    log("claims.md")


#: the stages of `tenscell reproduce`, in order: (name, function(out_dir, log))
REPRODUCE_STAGES = [
    ("homogeneous study (Figs. 2-3, claims)", reproduce_homogeneous),
]


def _cmd_reproduce(args) -> int:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    for name, stage in REPRODUCE_STAGES:
        t = time.perf_counter()
        print(f"[tenscell] {name} ...", file=sys.stderr, flush=True)
        stage(out, lambda msg: print(f"    wrote {out / msg}" if "," not in msg else f"    wrote {msg} in {out}",
                                     file=sys.stderr, flush=True))
        print(f"    done in {time.perf_counter() - t:.1f} s", file=sys.stderr, flush=True)
    print(f"[tenscell] reproduce finished in {time.perf_counter() - t0:.1f} s; results in {out}/", file=sys.stderr)
    return 0


def _add_reproduce(sub) -> None:
    p = sub.add_parser("reproduce", help="write the paper's figures, tables and claims",
                       description="Reproduce the paper's figures and tables into a directory.")
    p.add_argument("--out", default="out", help="output directory (default out/)")
    p.set_defaults(func=_cmd_reproduce)


# ---- show (issue 6): any structure, its summary and 3D pictures ---------------------------
#: built-in structures `tenscell show` knows by name
SHOW_BUILTINS = ("paper", "sphere6", "sphere12", "sphere30", "sheet", "block")


def _parse_member_values(text: str, name: str):
    """``"1"`` -> 1.0; ``"strut=1000,default=1"`` -> dict by family; ``"1,2,3"`` -> array."""
    text = str(text).strip()
    if "=" in text:
        out = {}
        for item in text.split(","):
            key, sep, val = item.partition("=")
            key = key.strip()
            if not key or not sep:
                raise ValueError(f"{name}: expected family=value items, got {item!r}")
            out[key] = float(parse_list(val, name)[0])
        return out
    vals = parse_list(text, name)
    return float(vals[0]) if vals.size == 1 else vals


def _show_target(args):
    """(stem, cell or structure, EA, c, T0 or None) for a file or a built-in name."""
    from . import lattices, paper_cell
    from .structio import load_structure_file

    target = args.target
    if target in SHOW_BUILTINS:
        lattice_ea = {"strut": lattices.LATTICE_STRUT_EA, "default": 1.0}
        if target == "paper":
            return "paper", paper_cell(L=args.L), 1.0, 1.0
        if target.startswith("sphere"):
            return target, lattices.sphere_cell(int(target[6:]), L=args.L), 1.0, 1.0
        dims = [int(v) for v in parse_list(args.size.replace("x", ","), "--size")] if args.size else None
        if target == "sheet":
            nx, ny, nz = (dims + [1])[:3] if dims else (4, 4, 1)
        else:
            nx, ny, nz = dims if dims and len(dims) == 3 else (3, 3, 3)
        return target, lattices.lattice_cell(nx, ny, nz, L=args.L), lattice_ea, 1.0
    path = Path(target)
    if not path.exists():
        raise ValueError(f"show: {target!r} is neither a file nor a built-in ({', '.join(SHOW_BUILTINS)})")
    sf = load_structure_file(path)
    return path.stem, (sf.structure, sf.T0), sf.EA, sf.c


def _cmd_show(args) -> int:
    from . import plotting

    from ._io import write_text
    from .equilibrium import NotPrestressableError, equilibrate
    from .structio import member_values, save_structure
    from .summary import relaxation_modes, summarize

    out = Path(args.out)
    stem, obj, EA, c = _show_target(args)
    if args.EA is not None:
        EA = _parse_member_values(args.EA, "--EA")
    if args.c is not None:
        c = _parse_member_values(args.c, "--c")
    if isinstance(obj, tuple):  # a file: use its self-stress when it has one
        structure, T0 = obj
        target = structure
        if T0 is not None:
            try:
                target = equilibrate(structure, "local", T0=T0)
            except NotPrestressableError:
                target = structure
    else:
        target, structure = obj, obj.structure
    EA = member_values(structure, EA, "--EA", "N")
    c = member_values(structure, c, "--c", "N·s/m")
    summary, cell, lin = summarize(target, P=args.P, EA=EA, c=c)
    text = summary.text()
    modes = None
    if lin is not None and args.modes > 0:
        try:
            modes = relaxation_modes(lin, args.modes)
            text += "slowest modes  " + ", ".join(f"{r:.6g}" for r in modes.rates) + " 1/s"
            if modes.residuals is not None:
                text += f" (the slowest the load excites; Ritz residuals <= {modes.residuals.max():.1g})"
            text += "\n"
        except RuntimeError as err:  # an eigensolver that did not converge: still draw the structure
            text += f"slowest modes  not computed: {err}\n"
    sys.stdout.write(text)
    written = []
    write_text(out / f"{stem}_summary.txt", text)
    written.append(f"{stem}_summary.txt")
    plotting.save(plotting.structure_3d(structure), out / f"{stem}_structure.png")
    written.append(f"{stem}_structure.png")
    if modes is not None:
        plotting.save(plotting.relaxation_modes_3d(structure, modes.rates, modes.displacements),
                      out / f"{stem}_modes.png")
        written.append(f"{stem}_modes.png")
    if args.save:
        save_structure(args.save, structure, EA=EA, c=c, T0=None if cell is None else cell.T0)
        written.append(str(args.save))
    where = f" and {args.save}" if args.save else ""
    print(f"wrote {', '.join(written[:3] if args.save else written)} in {out}/{where}", file=sys.stderr)
    return 0


def _add_show(sub) -> None:
    p = sub.add_parser("show", help="summary and 3D pictures of any structure (file or built-in)",
                       description="Print a structure's summary (counts, rank of A, self-stress dimension, "
                                   "mechanisms, prestressability) and draw it in 3D with its slowest relaxation "
                                   "modes. TARGET is a structure file (JSON, docs/structure-format.md) or one of: "
                                   + ", ".join(SHOW_BUILTINS) + ".")
    p.add_argument("target", metavar="TARGET", help="structure file or built-in name")
    p.add_argument("--out", default="out", help="output directory for the PNGs and summary (default out/)")
    p.add_argument("--modes", type=int, default=3, help="number of slowest relaxation modes to draw (0: none)")
    p.add_argument("--P", type=float, default=1000.0, help="prestress P (N) for the stability verdict and modes")
    p.add_argument("--EA", default=None,
                   help="member stiffness EA (N): one value, family=value pairs (e.g. strut=1000,default=1) "
                        "or one per member; default: the file's values, 1 N for built-ins "
                        "(lattice struts 1000 N)")
    p.add_argument("--c", default=None, help="member damping c (N·s/m), same forms as --EA; default 1")
    p.add_argument("--L", type=float, default=1.0, help="strut length of a built-in (m, default 1)")
    p.add_argument("--size", default=None, help="modules of a built-in lattice: NXxNY (sheet) or NXxNYxNZ (block)")
    p.add_argument("--save", default=None, help="also write the structure to this JSON file")
    p.set_defaults(func=_cmd_show)


def reproduce_show(out: Path, log) -> None:
    """`tenscell show paper`: the cell in 3D (paper Fig. 1 colours), its slowest modes and summary."""
    from . import paper_cell, plotting
    from ._io import write_text
    from .summary import relaxation_modes, summarize

    summary, cell, lin = summarize(paper_cell())
    modes = relaxation_modes(lin, 3)
    text = summary.text() + "slowest modes  " + ", ".join(f"{r:.6g}" for r in modes.rates) + " 1/s\n"
    write_text(out / "show_paper_summary.txt", text)
    plotting.save(plotting.structure_3d(cell.structure, title="paper cell (Fig. 1 colours)"),
                  out / "show_paper_structure.png")
    plotting.save(plotting.relaxation_modes_3d(cell.structure, modes.rates, modes.displacements),
                  out / "show_paper_modes.png")
    log("show_paper_structure.png, show_paper_modes.png, show_paper_summary.txt")


REPRODUCE_STAGES.append(("3D view and summary of the paper cell (tenscell show paper)", reproduce_show))


#: subcommand registrars, in the order they appear in --help
COMMANDS = [_add_moduli, _add_reproduce, _add_show]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    from . import __version__

    parser = argparse.ArgumentParser(
        prog="tenscell",
        description="Tensegrity models of the cytoskeleton: moduli G'(f, P), G''(f, P), fits and studies.",
    )
    parser.add_argument("--version", action="version", version=f"tenscell {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for add in COMMANDS:
        add(sub)
    return parser


def main(argv=None) -> int:
    """Entry point of the ``tenscell`` command; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (ValueError, OSError) as err:
        print(f"tenscell {args.command}: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("tenscell: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

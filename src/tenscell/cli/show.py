"""``tenscell show``: a structure's summary and 3D pictures (a structure file or a built-in)."""
from __future__ import annotations

import sys
from pathlib import Path

from ._args import (add_out, add_prestress, fitted_from_args, integer, lattice_size, member_values, number, path,
                    prestress_from_args)

#: built-in structures `tenscell show` knows by name
SHOW_BUILTINS = ("paper", "sphere6", "sphere12", "sphere30", "sheet", "block")
#: most modules of a built-in lattice: about 1.2e5 coordinates, some 1.5 GB and minutes for the sparse
#: factorization (the README's 11x11x12 block has 1452 modules)
MAX_LATTICE_MODULES = 5000
#: relative accuracy of the slowest rates of a large (sparse) structure: three significant digits, what the
#: summary prints (bench/bench_startup.py: 18 shifted Lanczos steps on the 10⁴-node block, against 52 for 5e-5)
MODES_TOL = 5e-4


def register(sub) -> None:
    p = sub.add_parser("show", help="summary and 3D pictures of any structure (file or built-in)",
                       description="Print a structure's summary (counts, rank of A, self-stress dimension, "
                                   "mechanisms, prestressability) and draw it in 3D with its slowest relaxation "
                                   "modes. TARGET is a structure file (JSON, docs/structure-format.md) or one of: "
                                   + ", ".join(SHOW_BUILTINS) + ".")
    p.add_argument("target", metavar="TARGET", nargs="?", default=None,
                   help="structure file or built-in name (omit it with --from-fit)")
    add_out(p, derived="show-TARGET, TARGET's file name without .json; show-fit with --from-fit")
    p.add_argument("--modes", type=integer(0, 50), default=3, help="number of slowest relaxation modes to draw (0: none)")
    add_prestress(p, sweep=False, from_fit=True)
    p.add_argument("--EA", type=member_values("EA"), default=None,
                   help="member stiffness EA (N): one value, family=value pairs (e.g. strut=1000,default=1) "
                        "or one per member; default: the file's values, 1 N for built-ins "
                        "(lattice struts 1000 N)")
    p.add_argument("--c", type=member_values("c"), default=None,
                   help="member damping c (N·s/m), same forms as --EA; default: the file's values, 1 for built-ins")
    p.add_argument("--L", type=number(quantity="L"), default=1.0, help="strut length of a built-in (m)")
    p.add_argument("--size", type=lattice_size(MAX_LATTICE_MODULES), default=None,
                   help="modules of a built-in lattice: NXxNY (sheet) or NXxNYxNZ (block); default 4x4 and 3x3x3")
    p.add_argument("--save", type=path("a file name"), default=None, help="also write the structure to this JSON file")
    p.set_defaults(func=run)


#: show's own model options: with --from-fit any other value is a conflict
_SHOW_MODEL_DEFAULTS = {"EA": (None, "--EA"), "c": (None, "--c"), "L": (1.0, "--L"), "size": (None, "--size")}


def _check_target(args) -> None:
    """Refuse a bad TARGET/--size combination before any computation."""
    t = args.target
    if args.from_fit is not None:
        if t is not None:
            raise ValueError(f"TARGET {t!r} cannot be combined with --from-fit: the fit gives the structure")
        return
    if t is None:
        raise ValueError("give a TARGET (a structure file or a built-in name) or --from-fit FIT_JSON")
    if t in SHOW_BUILTINS:
        if args.size is not None and t not in ("sheet", "block"):
            raise ValueError(f"--size applies to the lattices (sheet, block), not to {t!r}")
        if args.size is not None and t == "sheet" and len(args.size) == 3 and args.size[2] != 1:
            raise ValueError(f"--size: a sheet is NXxNY (one layer), got {'x'.join(map(str, args.size))}")
        if args.size is not None and t == "block" and len(args.size) != 3:
            raise ValueError(f"--size: a block is NXxNYxNZ, got {'x'.join(map(str, args.size))}")
        return
    if not Path(t).is_file():
        raise ValueError(f"{t!r} is neither a file nor a built-in ({', '.join(SHOW_BUILTINS)})")
    for typed, flag in ((args.L != 1.0, f"--L {args.L:g}"), (args.size is not None, "--size")):
        if typed:
            raise ValueError(f"{flag} applies to the built-in structures; the file {t} gives its own geometry")


def show_target(args):
    """(stem, cell or (structure, T0), EA, c) for a file or a built-in name."""
    from ..io.structure_files import load_structure_file
    from ..model import lattices
    from ..model.shapes import paper_cell

    target = args.target
    if target in SHOW_BUILTINS:
        lattice_ea = {"strut": lattices.LATTICE_STRUT_EA, "default": 1.0}
        if target == "paper":
            return "paper", paper_cell(L=args.L), 1.0, 1.0
        if target.startswith("sphere"):
            return target, lattices.sphere_cell(int(target[6:]), L=args.L), 1.0, 1.0
        dims = args.size
        if target == "sheet":
            nx, ny, nz = (tuple(dims) + (1,))[:3] if dims else (4, 4, 1)
        else:
            nx, ny, nz = dims if dims else (3, 3, 3)
        return target, lattices.lattice_cell(nx, ny, nz, L=args.L), lattice_ea, 1.0
    sf = load_structure_file(Path(target))
    return Path(target).stem, (sf.structure, sf.T0), sf.EA, sf.c


def _arrayish(v):
    if isinstance(v, tuple):
        import numpy as np
        return np.asarray(v, dtype=float)
    return v


def run(args) -> int:
    from ..io.outputs import OutputSet, check_output_file

    _check_target(args)
    default_out = f"show-{Path(args.target).stem}" if args.target else "show-fit"
    out = OutputSet(args.out or default_out, command=args.command_line, flag="--out")
    save = check_output_file(args.save, "--save") if args.save else None

    from .. import plotting
    from .._progress import stage
    from ..io.outputs import write_text
    from ..io.structure_files import member_values as expand, save_structure
    from ..summary import summarize

    fitted = fitted_from_args(args, _SHOW_MODEL_DEFAULTS)
    no_modes = ""
    if fitted is not None:
        (model, P), stem = fitted, "fit"
        obj, EA, c, no_modes = _fitted_tendons(args, model, P)
    else:
        stem, obj, EA, c = show_target(args)
        P = prestress_from_args(args)
    if args.EA is not None:
        EA = _arrayish(args.EA)
    if args.c is not None:
        c = _arrayish(args.c)
    target, structure = _target_structure(args, obj)
    EA = expand(structure, EA, "--EA", "N")
    c = expand(structure, c, "--c", "N·s/m")
    big = structure.n_tendons > 2000
    if big:
        stage(f"{stem}: {structure.n_tendons:,} members; summary and linearization")
    summary, cell, lin = summarize(target, P=P, EA=EA, c=c)
    modes, modes_text = _slowest_modes(args, lin, stem, big)
    text = summary.text() + no_modes + modes_text
    if big:
        stage(f"{stem}: drawing")
    written = [f"{stem}_summary.txt", f"{stem}_structure.png"] + ([f"{stem}_modes.png"] if modes is not None else [])
    with out as d:
        write_text(d / f"{stem}_summary.txt", text)
        plotting.save(plotting.structure_3d(structure), d / f"{stem}_structure.png")
        if modes is not None:
            plotting.save(plotting.relaxation_modes_3d(structure, modes.rates, modes.displacements),
                          d / f"{stem}_modes.png")
        if save is not None:
            # inside --out: part of the set; elsewhere: written (atomically) just before the set is committed
            inside = _relative_to(save, out.target)
            save_structure(d / inside if inside else save, structure, EA=EA, c=c,
                           T0=None if cell is None else cell.T0)
    sys.stdout.write(text)
    where = f" and {args.save}" if args.save else ""
    print(f"tenscell: wrote {', '.join(written)} in {out.target}/{where}", file=sys.stderr)
    return 0


def _fitted_tendons(args, model, P):
    """``(cell, EA, c, note)`` of a fitted model at model prestress ``P`` (N): its Voigt tendons at rest, or for
    tendons with internal dynamics unit dashpots and no modes (``args.modes`` set to 0, ``note`` says why)."""
    import numpy as np

    if not model.structural:
        raise ValueError(f"--from-fit {args.from_fit}: {model.describe()} has no structure to show: it is a "
                         "structure-free formula")
    EA, c = model.voigt_tendons(P)  # a law with internal dynamics: its tangents at rest
    if (c > 0).all():
        return model.cell, EA, c, ""
    # tendons with internal dynamics (a springpot's continuous spectrum) have no dashpot of their own: the
    # summary's verdict (rank, self-stress, stability) depends on K0 only, and no modes are computed from a
    # damping that is not the model's
    args.modes = 0
    return model.cell, EA, np.ones_like(EA), (f"slowest modes  not computed: {model.describe()} has tendons with "
                                              "internal dynamics, not a dashpot per tendon\n")


def _target_structure(args, obj):
    """``(what to summarize, its Structure)``: a cell as it is; a file's structure equilibrated at its own
    self-stress when it states one."""
    from ..model.equilibrium import NotPrestressableError, equilibrate

    if not isinstance(obj, tuple):
        return obj, obj.structure
    structure, T0 = obj  # a file: use its self-stress when it has one
    if T0 is None:
        return structure, structure
    try:
        return equilibrate(structure, "local", T0=T0), structure
    except NotPrestressableError as err:
        # the file states a self-stress: searching for another one would answer a different question
        raise ValueError(f"{args.target}: {str(err).replace('the given T0', 'its T0')}; correct it or omit "
                         "T0 to let tenscell find a self-stress") from None


def _slowest_modes(args, lin, stem: str, big: bool):
    """``(modes or None, the summary's lines on them)``: the ``args.modes`` slowest relaxation modes of ``lin``."""
    from .._progress import stage
    from ..summary import relaxation_modes

    if lin is None or args.modes <= 0:
        return None, ""
    if big:
        stage(f"{stem}: the {args.modes} slowest relaxation modes")
    try:
        modes = relaxation_modes(lin, args.modes, tol=MODES_TOL)
    except RuntimeError as err:  # an eigensolver that did not converge: still draw the structure
        return None, f"slowest modes  not computed: {err}\n"
    text = "slowest modes  " + modes.rates_text() + " 1/s"
    if modes.residuals is not None:
        # a single-vector Lanczos run finds the members of a cluster narrower than the tolerance late: on
        # the 10^4-node block tol 5e-4 gives 1.66, 1.66, 1.74 and tol 1e-6 (109 steps) three at 1.6619
        text += (f" (Lanczos from the load; each within {modes.residuals.max():.1g} (relative) of a rate of the "
                 "model, by its Ritz residual; more rates of a tight cluster may lie below the last)")
    return modes, text + "\n"


def _relative_to(path: Path, directory: Path):
    try:
        return path.absolute().relative_to(directory.absolute())
    except ValueError:
        return None

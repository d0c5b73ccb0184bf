"""TA Instruments TRIOS text exports: the LIMS export, the plain labelled layout and the ``[step]`` text layout.

Layouts (tab-separated)
-----------------------
LIMS export and plain labelled layout
    Rows labelled in their first field: ``Step name``, ``Number of points``, ``Variables`` (the column names),
    ``Units`` (or a row with an empty first field holding the units) and ``Data point`` rows. The LIMS export
    (``TA Instruments LIMS export format``) has ``[Header]``, ``[Sample]``, ``[Parameters...]`` sections and puts
    each step after a ``[Step]`` line; the plain layout has a metadata block and no ``[Step]`` line. Each
    ``Variables`` row begins a table; a ``Step`` column with several values splits one table into its steps.
``[step]`` text layout
    A metadata block, then per step a ``[step]`` line, the step's name (``Frequency sweep - 2``), a names row, a
    units row and the data rows, up to a blank line. Anything else before the next ``[step]`` line is refused:
    a step whose ``[step]`` line is missing would otherwise be read as part of another, or not at all.

A step's ``Number of points`` must match the rows it holds (``point-count``, :mod:`tenscell.io.checks`).
A file that looks like a TRIOS export (``TA Instruments``, ``Trios version``, a ``.tri`` file name...) but
holds none of these layouts is refused saying so.
"""
from __future__ import annotations

import os
import re
from typing import Any, Mapping

from ..columns import ColumnMap, DataError, _Table, _trimmed
from ..provenance import Provenance
from ._blocks import Block, Probe, Request, check_declared, choose, decimal_mark, read_block, temperature_of

__all__ = ["LAYOUT", "EXPECTED", "detect", "read", "read_trios"]

LAYOUT = "TA TRIOS export"
#: what this reader expects, for the message of a file no reader recognises
EXPECTED = "a TA TRIOS text export ([Step] sections, or Variables/Data point rows, or [step] blocks)"
#: text that marks a file written by TRIOS, with no table of its own
_LOOKS = ("ta instruments", "trios version", "lims export", ".tri\t", ".tri\n", "instrument serial number",
          "procedure name", "proceduresegments")
_LABELS = ("Step name", "Number of points", "Variables", "Units", "Data point")


def _label(line: str) -> str:
    return line.split("\t", 1)[0].strip()


def _is_step_line(s: str) -> bool:
    return s.strip().lower() == "[step]"


def _labelled(lines: list[str]) -> bool:
    return any(_label(s) == "Variables" for s in lines) and any(_label(s) == "Data point" for s in lines)


def detect(probe: Probe) -> int:
    """2: a TRIOS layout (labelled rows, or ``[step]`` lines); 1: TRIOS metadata without one; 0: not TRIOS."""
    if probe.suffix in (".xlsx", ".xlsm"):
        return 0
    lines = probe.lines
    if _labelled(lines) or any(_is_step_line(s) for s in lines):
        return 2
    return 1 if probe.first_line(*_LOOKS, limit=80) else 0


def _evidence(probe: Probe) -> str:
    hit = probe.first_line(*_LOOKS, limit=80) or probe.first_line("[step]", "variables\t")
    return f" (line {hit[0]}: {hit[1][:60]!r})" if hit else ""


# ---- the labelled layouts (LIMS, plain) ------------------------------------------------------------------
def _labelled_blocks(source: str, lines: list[str]) -> list[Block]:
    """One block per ``Variables`` row (split further by a ``Step`` column with several values)."""
    meta: list[str] = []
    blocks: list[dict] = []
    pending: dict[str, Any] = {}
    current: dict | None = None
    step_lines = any(_is_step_line(s) for s in lines)  # then every step has one (a LIMS export)
    for k, raw in enumerate(lines, start=1):
        f = raw.rstrip("\r\n").split("\t")
        label = f[0].strip()
        if _is_step_line(raw):
            pending, current = {}, None
        elif label == "Step name":
            if step_lines and current is not None:
                raise DataError(f"{source}, line {k}: 'Step name' follows the data of the step named at line "
                                f"{current.get('name_line', current['line'])} without a [Step] line between them: "
                                "is a [Step] line missing?")
            pending = {"name": f[1].strip() if len(f) > 1 else "", "name_line": k}
            current = None
        elif label == "Number of points":
            pending["declared"] = (f[1].strip() if len(f) > 1 else "", k)
        elif label == "Variables":
            current = {**pending, "names": [s.strip() for s in f[1:]], "units": None, "rows": [], "where": [],
                       "line": k}
            pending = {}
            blocks.append(current)
        elif current is not None and not current["rows"] and current["units"] is None and (
                label == "Units" or (not label and len(_trimmed(f)) > 1)):
            current["units"] = [s.strip() for s in f[1:]]
        elif label == "Data point":
            _data_point(source, k, f, current)
        elif current is None and raw.strip() and not raw.startswith("["):
            meta.append(raw.strip().replace("\t", " "))
    out: list[Block] = []
    for b in blocks:
        out.extend(_split_by_step_column(source, b, tuple(meta), len(out)))
    return out


def _data_point(source: str, k: int, f: list[str], current: dict | None) -> None:
    """Add the ``Data point`` row ``f`` (line ``k``) to the block ``current`` (DataError before any block, or with
    more or fewer fields than the block has columns)."""
    if current is None:
        raise DataError(f"{source}, line {k}: a 'Data point' row before any 'Variables' row (column names)")
    width = len(_trimmed(current["names"]))
    if len(_trimmed(f[1:])) > width:
        raise DataError(f"{source}, line {k}: expected {width} fields after 'Data point', found {len(_trimmed(f[1:]))}")
    if len(f) - 1 < width:
        raise DataError(f"{source}, line {k}: a 'Data point' row with {len(f) - 1} of the {width} fields its "
                        f"'Variables' row names (column {current['names'][len(f) - 1].strip()!r} missing): a row cut "
                        "short, a truncated export?")
    current["rows"].append([s.strip() for s in f[1:]])
    current["where"].append(f"line {k}")


def _declared(source: str, b: dict) -> tuple[int | None, str]:
    if "declared" not in b:
        return None, ""
    text, k = b["declared"]
    if not re.fullmatch(r"\d+", text):
        raise DataError(f"{source}, line {k}: 'Number of points' is {text!r}, not a count")
    return int(text), f"'Number of points {text}' (line {k})"


def _split_by_step_column(source: str, b: dict, meta: tuple[str, ...], before: int) -> list[Block]:
    names, rows, where = b["names"], b["rows"], b["where"]
    declared, declared_where = _declared(source, b)
    bare = [n.strip().lower() for n in names]
    groups: dict[str, list[int]] = {}
    if "step" in bare and not b.get("name"):
        j = bare.index("step")
        for i, r in enumerate(rows):
            groups.setdefault(r[j] if j < len(r) else "", []).append(i)
        if "" in groups and len(groups) > 1:  # a row cut in its Step field is not a step of its own
            raise DataError(f"{source}, {where[groups[''][0]]}: column {names[j].strip()!r} is empty where the other "
                            "rows name their step: a row cut short, a truncated export?")
    if len(groups) <= 1:
        groups = {"": list(range(len(rows)))}
    out = []
    for n, (value, idx) in enumerate(groups.items(), start=before + 1):
        name = b.get("name") or (f"Step {value}" if value else "")
        sub = [rows[i] for i in idx]
        table = _Table(source, names, sub, [where[i] for i in idx], b["units"], decimal_mark(sub),
                       meta + ((f"step {n}: {name}",) if name else ()))
        out.append(Block(n, name, table, temperature_of(name, names, sub, " ".join(meta)), declared, declared_where,
                         None if len(groups) == 1 else len(rows)))  # the declared count is the whole table's
    return out


# ---- the [step] text layout -------------------------------------------------------------------------------
def _text_blocks(source: str, lines: list[str]) -> list[Block]:
    starts = [k for k, s in enumerate(lines) if _is_step_line(s)]
    meta = tuple(s.strip().replace("\t", " ") for s in lines[:starts[0]] if s.strip() and not s.startswith("["))
    blocks = []
    for n, k0 in enumerate(starts, start=1):
        end = starts[n] if n < len(starts) else len(lines)
        section = next((k for k in range(k0 + 1, end) if lines[k].startswith("[")), end)
        name, names, units, rows, where = _text_step(source, lines, list(range(k0 + 1, section)), k0)
        table = _Table(source, names, rows, where, units, decimal_mark(rows), meta + (f"step {n}: {name}",))
        blocks.append(Block(n, name, table, temperature_of(name, names, rows)))
    return blocks


def _text_step(source: str, lines: list[str], body: list[int], k0: int):
    """A ``[step]``: its name, a names row, a units row, then data rows up to a blank line, and nothing after."""
    filled = [k for k in body if lines[k].strip()]
    if len(filled) < 3:
        raise DataError(f"{source}, line {k0 + 1}: a [step] needs its name, a names row and a units row")
    name = lines[filled[0]].strip()
    names = [s.strip() for s in lines[filled[1]].rstrip("\r\n").split("\t")]
    units = [s.strip() for s in lines[filled[2]].rstrip("\r\n").split("\t")]
    rows, where, k = [], [], filled[2] + 1
    while k <= body[-1] and lines[k].strip():
        f = [s.strip() for s in lines[k].rstrip("\r\n").split("\t")]
        if len(_trimmed(f)) > len(names) or len(f) < len(_trimmed(names)):
            raise DataError(f"{source}, line {k + 1}: expected {len(_trimmed(names))} fields, found {len(_trimmed(f))}"
                            + (": a row cut short, a truncated export?" if len(f) < len(_trimmed(names)) else ""))
        rows.append(f)
        where.append(f"line {k + 1}")
        k += 1
    rest = next((j for j in range(k, body[-1] + 1) if lines[j].strip()), None)
    if rest is not None:
        raise DataError(f"{source}, line {rest + 1}: {lines[rest].strip()[:40]!r} follows the data of step {name!r} "
                        f"(the [step] at line {k0 + 1}) before the next [step] line: a step whose [step] line is "
                        "missing? tenscell does not guess where a step begins")
    return name, names, units, rows, where


# ---- the reader ---------------------------------------------------------------------------------------------
def blocks_of(probe: Probe) -> tuple[list[Block], str]:
    """The file's steps and which TRIOS layout holds them; DataError when it looked like TRIOS but holds none."""
    lines = probe.lines
    if _labelled(lines):
        lims = probe.first_line("lims export", limit=5) is not None or any(_is_step_line(s) for s in lines)
        return _labelled_blocks(probe.source, lines), "TA TRIOS LIMS export" if lims else "TA TRIOS export"
    if any(_is_step_line(s) for s in lines):
        return _text_blocks(probe.source, lines), "TA TRIOS text export"
    raise DataError(f"{probe.source}: looks like a TA TRIOS export{_evidence(probe)} but holds no table of data "
                    "points tenscell reads: no 'Variables' row with 'Data point' rows and no '[step]' line (export "
                    "the steps as text, with their data points, from TRIOS)")


def read(probe: Probe, request: Request):
    """The step the request chooses, as RheologyData or CreepData."""
    blocks, layout = blocks_of(probe)
    check_declared(blocks, request)
    block = choose(probe.source, blocks, request)
    return read_block(block, request, Provenance(file=probe.source, layout=layout, steps=len(blocks)))


def read_trios(path: str | os.PathLike[str], step: int | str | None = None, *, temperature: float | None = None,
               columns: ColumnMap | Mapping[str, Any] | None = None, min_points: int = 1, accept=(),
               **units: Any):
    """Moduli or creep compliance from a TA Instruments TRIOS text export (LIMS, plain or ``[step]`` layout).

    Parameters
    ----------
    path : str or PathLike
    step : int or str, optional
        The step to read: 1-based number in the file's order, or the step's
        name (``"Frequency sweep (25.0 °C)"``; refused when several steps
        share it: choose by number). Needed when several steps could be read,
        unless ``temperature`` picks one.
    temperature : float, optional
        °C: read the step at this temperature (within
        :data:`~tenscell.io.readers._blocks.TEMPERATURE_TOLERANCE_C`).
    columns : ColumnMap or dict, optional
        Which column holds what; default recognised from the names row
        (``Angular frequency``, ``Storage modulus``, ``Loss modulus``; else
        ``Tan(delta)`` or ``Complex modulus`` with ``Phase angle``; for creep
        ``Step time`` or ``Time`` with ``Compliance``).
    min_points : int
    accept : str or sequence of str, optional
        Checks of :mod:`tenscell.io.checks` to skip (``"point-count"``, ``"one-frequency"``, ``"outliers"``...).
    **units
        Unit fields of :class:`~tenscell.io.columns.ColumnMap`, overriding the units row.

    Returns
    -------
    RheologyData or CreepData
        ``provenance`` names the file, its layout, the step and its temperature, the columns and the unit
        conversions; ``comments`` keep the file's metadata.
    """
    probe = Probe(path)
    if detect(probe) == 0:
        raise DataError(f"{path}: no TRIOS table (no 'Variables'/'Data point' rows and no '[step]' line); expected "
                        f"{EXPECTED}")
    return read(probe, Request(columns=columns, units=units, step=step, temperature=temperature,
                               min_points=min_points, accept=accept))


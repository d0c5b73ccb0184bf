"""What every reader shares: a look at the file (:class:`Probe`), the request (:class:`Request`), files cut into
blocks (a TRIOS step, a RheoCompass interval) and the choice among them, and the one way a table becomes data.

A block's table goes through :func:`tenscell.io.columns.parse` (units converted explicitly, each value checked
where it sits) and :func:`tenscell.io.importers.build` (the data object, the checks of :mod:`tenscell.io.checks`,
the provenance): every reader ends the same way.
"""
from __future__ import annotations

import re
import statistics
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, Mapping

from ..._errors import option
from ..checks import accepted_checks, refuse
from ..columns import ColumnMap, DataError, _as_map, _read_text, _Table, guess_columns
from ..importers import build
from ..provenance import Provenance

__all__ = ["Probe", "Request", "Block", "choose", "check_declared", "read_block", "temperature_of", "decimal_mark",
           "TEMPERATURE_TOLERANCE_C"]

#: a block is "at" a requested temperature when its own is within this many °C
TEMPERATURE_TOLERANCE_C = 1.0
_TEMP_IN_NAME = re.compile(r"(-?\d+(?:[.,]\d+)?)\s*°\s*C")


class Probe:
    """A file as the readers see it while recognising its layout: its path and, read once when asked, its text."""

    def __init__(self, path) -> None:
        self.path = Path(path)
        self.source = str(path)
        self.suffix = self.path.suffix.lower()

    @cached_property
    def text(self) -> str:
        return _read_text(self.path)

    @cached_property
    def lines(self) -> list[str]:
        return self.text.splitlines()

    def first_line(self, *words: str, limit: int | None = None) -> tuple[int, str] | None:
        """(1-based number, text) of the first line holding one of ``words`` (case-insensitive), or None."""
        wanted = [w.lower() for w in words]
        for k, line in enumerate(self.lines[:limit], start=1):
            low = line.lower()
            if any(w in low for w in wanted):
                return k, line.strip()
        return None


@dataclass(frozen=True)
class Request:
    """What the caller asked for: which columns (a :class:`ColumnMap`, a dict of its fields, or None to recognise
    them), units overriding the file's, the step (number or name) or temperature, the Excel sheet, the fewest
    points, and the checks to skip (:data:`tenscell.io.checks.CHECKS`)."""

    columns: ColumnMap | Mapping[str, Any] | None = None
    units: Mapping[str, Any] = field(default_factory=dict)
    step: int | str | None = None
    temperature: float | None = None
    sheet: str | int | None = None
    min_points: int = 1
    accept: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "accept", accepted_checks(self.accept))
        object.__setattr__(self, "units", dict(self.units))
        if self.step is not None and self.temperature is not None:
            raise DataError(f"{option('step', self.step)} and {option('temperature', self.temperature)} both "
                            "choose the step; give one")

    def map_for(self, names) -> ColumnMap | None:
        """The map for a table with these column names: the one asked for, else the one its headers say (None when
        they say nothing tenscell recognises); the units asked for override the map's."""
        cmap = guess_columns(names) if self.columns is None else self.columns
        return None if cmap is None else _as_map(cmap, self.units)


@dataclass(frozen=True)
class Block:
    """One table of a file with several: its number (as the reader numbers them), name, table and temperature (°C),
    and the number of points the file says it holds (with where it says so), if it does, and the rows that number
    counts (``declared_rows``: the table before a ``Step`` column split it into steps; None: this block's rows)."""

    number: int
    name: str
    table: _Table
    temperature_c: float | None
    declared_points: int | None = None
    declared_where: str = ""
    declared_rows: int | None = None

    @property
    def counted_rows(self) -> int:
        """The rows the declared number of points counts."""
        return len(self.table.rows) if self.declared_rows is None else self.declared_rows


def decimal_mark(rows: list[list[str]]) -> str:
    """``","`` when the rows write numbers with a decimal comma (and never a decimal point), else ``"."``."""
    sample = " ".join(" ".join(r) for r in rows[:5])
    return "," if re.search(r"\d,\d", sample) and not re.search(r"\d\.\d", sample) else "."


def temperature_of(name: str, names: list[str], rows: list[list[Any]], meta: str = "") -> float | None:
    """A block's temperature (°C): the median of its Temperature column, else the one its name or metadata states."""
    bare = [n.strip().lower() for n in names]
    if "temperature" in bare:
        j = bare.index("temperature")
        values = []
        for r in rows:
            try:
                values.append(float(str(r[j]).replace(",", ".")))
            except (ValueError, IndexError):
                pass
        if values:
            return statistics.median(values)
    m = _TEMP_IN_NAME.search(name) or _TEMP_IN_NAME.search(meta)
    return float(m.group(1).replace(",", ".")) if m else None


def _readable(block: Block, columns) -> bool:
    """The block holds data this map (or the recognised headers) reads: creep, or moduli over more than one
    frequency (an amplitude sweep at one frequency is not a frequency sweep)."""
    try:
        cmap = guess_columns(block.table.names) if columns is None else _as_map(columns, {})
    except ValueError:
        return False
    if cmap is None:
        return False
    if cmap.layout == "creep":
        return True
    names = [n.strip() for n in block.table.names]
    if cmap.frequency not in names:
        return True  # the map names a column with its unit ("G' [Pa]"); let the reader say what is wrong
    j = names.index(cmap.frequency)
    return len({r[j] for r in block.table.rows if j < len(r)}) > 1


def _listing(blocks: list[Block]) -> str:
    return "; ".join(f"{b.number} {b.name!r}" + ("" if b.temperature_c is None else f" ({b.temperature_c:.4g} °C)")
                     for b in blocks[:6]) + ("; ..." if len(blocks) > 6 else "")


def choose(source: str, blocks: list[Block], request: Request, what: str = "step") -> Block:
    """The block the request asks for: by number, by name (refused when several share it), at a temperature, or the
    only one that holds data tenscell reads. DataError naming the blocks otherwise."""
    if not blocks:
        raise DataError(f"{source}: no {what} holds a table of data points")
    columns = request.columns
    pick, temperature = request.step, request.temperature
    if isinstance(pick, str) and pick.strip().isdigit():
        pick = int(pick.strip())
    if temperature is not None:
        near = [b for b in blocks if b.temperature_c is not None
                and abs(b.temperature_c - float(temperature)) <= TEMPERATURE_TOLERANCE_C and _readable(b, columns)]
        if len(near) != 1:
            said = int(temperature) if float(temperature).is_integer() else temperature  # 99, as it was typed
            raise DataError(f"{source}: {option('temperature', said)}: {len(near)} {what}s at {temperature:g} ± "
                            f"{TEMPERATURE_TOLERANCE_C:g} °C "
                            f"(the {what}s: {_listing(blocks)})" + ("; choose one by its number with "
                                                                     f"{option('step')}" if near else ""))
        return near[0]
    if pick is not None:
        if isinstance(pick, str):
            hit = [b for b in blocks if b.name.strip().lower() == pick.strip().lower()]
            if len(hit) > 1:
                raise DataError(f"{source}: {len(hit)} {what}s are named {pick!r} ({', '.join(str(b.number) for b in hit)})"
                                f"; choose one by its number with {option('step', hit[0].number)}")
        else:
            hit = [b for b in blocks if b.number == int(pick)]
        if len(hit) != 1:
            raise DataError(f"{source}: {option('step', pick)}: no {what} {pick!r}; the file has {len(blocks)} "
                            f"({_listing(blocks)})")
        return hit[0]
    readable = [b for b in blocks if _readable(b, columns)]
    if len(blocks) == 1 or len(readable) == 1:
        return (readable or blocks)[0]
    raise DataError(f"{source}: {len(readable) or len(blocks)} {what}s hold data tenscell reads; choose one with "
                    f"{option('step')} or {option('temperature')} ({_listing(blocks)})")


def check_declared(blocks: list[Block], request: Request, what: str = "step") -> tuple[str, ...]:
    """Every block's declared number of points against the rows it counts, before one is chosen (a cut row must
    not pass for a step of its own): DataError for the first that differs (``point-count``), unless accepted; then
    the problems, for the provenance."""
    found = []
    for block in blocks:
        n, table = block.counted_rows, block.table
        if block.declared_points is None or block.declared_points == n:
            continue
        where = f"{table.where[0]} to {table.where[-1]}" if table.rows else "none"
        split = "" if block.declared_rows is None else " (with the steps its Step column splits it into)"
        found.append(refuse(table.source, "point-count",
                            f"{what} {block.number} {block.name!r}: {block.declared_where} says {block.declared_points} "
                            f"points but the table holds {n} data rows{split} ({where}): a truncated or edited export",
                            request.accept))
    return tuple(found)


def read_block(block: Block, request: Request, base: Provenance, what: str = "step"):
    """The data a chosen block holds (RheologyData or CreepData), through the shared parse, checks and provenance
    (its declared number of points is checked first, :func:`check_declared`)."""
    table = block.table
    check_declared([block], request, what)
    cmap = request.map_for(table.names)
    if cmap is None:
        raise DataError(f"{table.source}: {what} {block.number} {block.name!r} has no columns tenscell recognises "
                        "(frequency with G' and G'', or time with compliance); say which column holds what with "
                        f"{option('columns')}")
    own_name = block.name and block.name != f"{what} {block.number}"  # a name of its own, not "interval 2"
    base = Provenance(file=base.file, layout=base.layout, step=block.number, step_word=what,
                      step_name=block.name if own_name else None, steps=base.steps, temperature_c=block.temperature_c)
    return build(table, cmap, request.min_points, base, request.accept, what=f"{what} {block.number} {block.name!r}")

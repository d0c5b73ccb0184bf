"""Anton Paar RheoCompass text exports.

Layout
------
A metadata block (``Project:``, ``Test:``, ``Measuring System:``...), then per interval an ``Interval and data
points:`` line (the interval's number and its point count), optional lines such as ``Temperature:``, an
``Interval data:`` line with the column names (long ``Storage Modulus`` or short ``G'``), a row of bracketed
units and the data rows, with or without a leading empty field. Fields are separated by tabs, or by semicolons
(RheoCompass's CSV export); a decimal comma is recognised. Other columns (``Point No.``, ``Torque``,
``Status``...) are ignored. An interval whose point count contradicts its rows is refused (``point-count``).
"""
from __future__ import annotations

import os
import re
from typing import Any, Mapping

from ..columns import ColumnMap, DataError, _Table, _trimmed
from ..provenance import Provenance
from ._blocks import Block, Probe, Request, check_declared, choose, decimal_mark, read_block, temperature_of

__all__ = ["LAYOUT", "EXPECTED", "detect", "read", "read_rheocompass"]

LAYOUT = "Anton Paar RheoCompass export"
EXPECTED = "an Anton Paar RheoCompass export ('Interval data:' lines)"
_DATA = "Interval data:"
_POINTS = "Interval and data points:"


def detect(probe: Probe) -> int:
    """2: ``Interval data:`` lines; 1: other RheoCompass marks (``Interval and data points:``, the name); 0: not."""
    if probe.suffix in (".xlsx", ".xlsm"):
        return 0
    if any(s.lstrip().startswith(_DATA) for s in probe.lines):
        return 2
    return 1 if probe.first_line(_POINTS.lower(), "rheocompass", "anton paar", limit=80) else 0


def _separator(line: str) -> str:
    """The field separator of an ``Interval data:`` line: a tab, else a semicolon, else a comma."""
    rest = line.lstrip()[len(_DATA):]
    return next((d for d in ("\t", ";", ",") if d in rest), "\t")


def _split(line: str, sep: str) -> list[str]:
    return line.rstrip("\r\n").split(sep)


def blocks_of(probe: Probe) -> list[Block]:
    """Every interval of the file (numbered as the file numbers them)."""
    source, lines = probe.source, probe.lines
    starts = [k for k, s in enumerate(lines) if s.lstrip().startswith(_DATA)]
    if not starts:
        hit = probe.first_line(_POINTS.lower(), "rheocompass", "anton paar", limit=80)
        seen = f" (line {hit[0]}: {hit[1][:60]!r})" if hit else ""
        raise DataError(f"{source}: looks like an Anton Paar RheoCompass export{seen} but has no "
                        f"'{_DATA}' line (the column names of an interval): export the intervals' data as text")
    first = min([k for k, s in enumerate(lines) if s.lstrip().startswith(_POINTS)] + starts)
    meta = tuple(s.strip().replace("\t", " ") for s in lines[:first] if s.strip())
    blocks = []
    for pos, k0 in enumerate(starts, start=1):
        sep = _separator(lines[k0])
        head = k0
        while head > 0 and lines[head - 1].strip() and not lines[head - 1].lstrip().startswith(_DATA):
            head -= 1  # the interval's own lines: "Interval and data points:", "Temperature:", "Test Type:"...
        preamble = [lines[k] for k in range(head, k0)]
        number, declared, declared_where = pos, None, ""
        marker = next((k for k in range(head, k0) if lines[k].lstrip().startswith(_POINTS)), None)
        if marker is not None:
            counts = re.findall(r"\d+", lines[marker].split(":", 1)[1])
            number = int(counts[0]) if counts else pos
            if len(counts) > 1:
                declared, declared_where = int(counts[1]), f"'{_POINTS} {counts[0]} {counts[1]}' (line {marker + 1})"
        names = _trimmed([s.strip() for s in _split(lines[k0].lstrip(), sep)][1:])
        if k0 + 1 >= len(lines):
            raise DataError(f"{source}, line {k0 + 2}: the units line of the interval is missing")
        unit_fields = _split(lines[k0 + 1], sep)
        units = [s.strip() for s in (unit_fields[1:] if not unit_fields[0].strip() else unit_fields)]
        rows, where = _rows(source, lines, k0 + 2, sep, len(names))
        text = " ".join(preamble)
        decimal = decimal_mark(rows) if sep != "," else "."
        table = _Table(source, names, rows, where, units, decimal,
                       meta + tuple(s.strip().replace(sep, " ") for s in preamble if s.strip()))
        blocks.append(Block(number, f"interval {number}", table, temperature_of(text, names, rows, text),
                            declared, declared_where))
    return blocks


def _rows(source: str, lines: list[str], k: int, sep: str, width: int) -> tuple[list[list[str]], list[str]]:
    """The data rows from line index ``k``: with or without a leading empty field, up to a blank or metadata line;
    DataError for a row with fewer fields than the ``width`` columns named (a row cut short)."""
    rows, where = [], []
    while k < len(lines) and lines[k].strip():
        f = _split(lines[k], sep)
        if f[0].strip().endswith(":"):  # "Result:", "Interval and data points:": the table has ended
            break
        if not f[0].strip() and len(_trimmed(f)) > 0:
            f = f[1:]  # the leading empty field of the long layout
        if len(f) < width:
            raise DataError(f"{source}, line {k + 1}: expected {width} fields, found {len(f)}: a row cut short, a "
                            "truncated export?")
        rows.append([s.strip() for s in f])
        where.append(f"line {k + 1}")
        k += 1
    return rows, where


def read(probe: Probe, request: Request):
    """The interval the request chooses, as RheologyData or CreepData."""
    blocks = blocks_of(probe)
    check_declared(blocks, request, "interval")
    block = choose(probe.source, blocks, request, "interval")
    return read_block(block, request, Provenance(file=probe.source, layout=LAYOUT, steps=len(blocks)), "interval")


def read_rheocompass(path: str | os.PathLike[str], interval: int | None = None, *, temperature: float | None = None,
                     columns: ColumnMap | Mapping[str, Any] | None = None, min_points: int = 1, accept=(),
                     **units: Any):
    """Moduli or creep compliance from an Anton Paar RheoCompass text export (layout above).

    Columns are recognised from long headers (``Angular Frequency``,
    ``Storage Modulus``, ``Loss Modulus``, ``Loss Factor``, ``Complex
    Modulus``, ``Phase Angle``; ``Time`` with ``Compliance`` for creep) or
    short ones (``ω``, ``G'``, ``G''``, ``|G*|``, ``δ``); units from the units
    line (``[rad/s]``, ``[Pa]``, ``[°]``); a decimal comma is recognised.

    Parameters
    ----------
    path : str or PathLike
    interval : int, optional
        The interval to read, as the file numbers it (``Interval and data
        points: 2``); needed when the file holds several, unless
        ``temperature`` picks one.
    temperature : float, optional
        °C: the interval at this temperature (within 1 °C).
    columns : ColumnMap or dict, optional
        Which column holds what, when the headers are not recognised.
    min_points : int
    accept : str or sequence of str, optional
        Checks of :mod:`tenscell.io.checks` to skip.
    **units
        Unit fields of :class:`~tenscell.io.columns.ColumnMap`, to override what the file states
        (e.g. ``modulus_unit="ratio", geometric_factor=...`` for raw ratios).

    Returns
    -------
    RheologyData or CreepData
        ``provenance`` names the file, the interval, its temperature, the columns and conversions; ``comments``
        keep the metadata block and record the columns used.
    """
    probe = Probe(path)
    if detect(probe) < 2:
        raise DataError(f"{path}: no '{_DATA}' line; expected {EXPECTED}")
    return read(probe, Request(columns=columns, units=units, step=interval, temperature=temperature,
                               min_points=min_points, accept=accept))

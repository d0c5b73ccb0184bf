"""Rheometer exports and the one reader that recognises them: TA TRIOS, Anton Paar RheoCompass, lab tables.

Every reader here cuts the file into blocks (a TRIOS ``[step]``, a RheoCompass
interval), picks one, and hands its names row, units row and data rows to the
same :class:`~tenscell.io.importers.ColumnMap` machinery as
:func:`~tenscell.io.importers.read_table`: units come from the units row or the
headers and are converted explicitly, errors name the file, the line and the
column, and the result is built by :class:`~tenscell.io.data.RheologyData` or
:class:`~tenscell.io.creep_data.CreepData`, whose checks every file passes.

Layouts
-------
TRIOS "LIMS" text export
    ``[Header]``, ``[Sample]``, ``[Parameters...]`` sections, then one
    ``[Step]`` section per step: ``Step name``, ``Number of points``, a
    ``Variables`` row (column names), a ``Units`` row and ``Data point`` rows,
    tab-separated.
TRIOS text export
    A metadata block, then per step a ``[step]`` line, the step's name
    (``Frequency sweep - 2``), a names row, a units row and the data rows.
RheoCompass text export
    A metadata block, then per interval ``Interval and data points:``, optional
    lines such as ``Temperature:``, an ``Interval data:`` line with the column
    names (long ``Storage Modulus`` or short ``G'``), a row of bracketed units
    and the data rows, with or without a leading empty field.

A file with several blocks needs a choice: ``step=`` (1-based, as the file
orders them, or the step's name) or ``temperature=`` (°C: the block whose
temperature, from its Temperature column, name or metadata, is within
``TEMPERATURE_TOLERANCE_C``).
"""
from __future__ import annotations

import csv
import os
import re
import statistics
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from .creep_data import CreepData, is_creep_header, read_creep_csv
from .data import DataError, RheologyData, read_csv
from .columns import ColumnMap, _as_map, _read_text, _Table, _trimmed, guess_columns
from .importers import _data, read_table

__all__ = ["read_data", "read_trios", "read_rheocompass", "detect_layout", "TEMPERATURE_TOLERANCE_C"]

#: a block is "at" a requested temperature when its own is within this many °C
TEMPERATURE_TOLERANCE_C = 1.0
_RC_DATA = "Interval data:"
_RC_POINTS = "Interval and data points:"
_TEMP_IN_NAME = re.compile(r"(-?\d+(?:[.,]\d+)?)\s*°\s*C")


@dataclass(frozen=True)
class _Block:
    number: int                 # 1-based, as the file orders the blocks (or as it numbers its intervals)
    name: str
    table: _Table
    temperature_c: float | None


def _decimal(rows: list[list[str]]) -> str:
    sample = " ".join(" ".join(r) for r in rows[:5])
    return "," if re.search(r"\d,\d", sample) and not re.search(r"\d\.\d", sample) else "."


def _temperature(name: str, names: list[str], rows: list[list[Any]], meta: str = "") -> float | None:
    """The block's temperature (°C): the median of its Temperature column, else the one its name or metadata states."""
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


# ---- TA TRIOS ---------------------------------------------------------------------------------
def _is_step_line(s: str) -> bool:
    return s.strip().lower() == "[step]"


def _trios_blocks(source: str, lines: list[str]) -> tuple[list[_Block], tuple[str, ...]]:
    starts = [k for k, s in enumerate(lines) if _is_step_line(s)]
    meta = tuple(s.strip().replace("\t", " ") for s in lines[:starts[0]] if s.strip() and not s.startswith("["))
    blocks = []
    for n, k0 in enumerate(starts, start=1):
        end = starts[n] if n < len(starts) else len(lines)
        section = next((k for k in range(k0 + 1, end) if lines[k].startswith("[")), end)
        body = list(range(k0 + 1, section))
        lims = bool(body) and lines[body[0]].startswith("Step name\t")
        name, names, units, rows, where = (_lims_step if lims else _text_step)(source, lines, body, k0)
        table = _Table(source, names, rows, where, units, _decimal(rows), meta + (f"step {n}: {name}",))
        blocks.append(_Block(n, name, table, _temperature(name, names, rows)))
    return blocks, meta


def _lims_step(source: str, lines: list[str], body: list[int], k0: int):
    """A LIMS ``[Step]``: labelled rows (``Step name``, ``Variables``, ``Units``, ``Data point``)."""
    name, names, units, rows, where = "", None, None, [], []
    for k in body:
        f = lines[k].rstrip("\r\n").split("\t")
        label = f[0].strip()
        if label == "Step name":
            name = f[1].strip() if len(f) > 1 else ""
        elif label == "Variables":
            names = [s.strip() for s in f[1:]]
        elif label == "Units":
            units = [s.strip() for s in f[1:]]
        elif label == "Data point":
            rows.append([s.strip() for s in f[1:]])
            where.append(f"line {k + 1}")
    if names is None:
        raise DataError(f"{source}, line {k0 + 1}: the [Step] has no 'Variables' row (column names)")
    return name, names, units, rows, where


def _text_step(source: str, lines: list[str], body: list[int], k0: int):
    """A TRIOS text ``[step]``: the step's name, a names row, a units row, then data rows up to a blank line."""
    filled = [k for k in body if lines[k].strip()]
    if len(filled) < 3:
        raise DataError(f"{source}, line {k0 + 1}: a [step] needs its name, a names row and a units row")
    name = lines[filled[0]].strip()
    names = [s.strip() for s in lines[filled[1]].rstrip("\r\n").split("\t")]
    units = [s.strip() for s in lines[filled[2]].rstrip("\r\n").split("\t")]
    rows, where = [], []
    for k in range(filled[2] + 1, body[-1] + 1):
        if not lines[k].strip():
            break
        f = [s.strip() for s in lines[k].rstrip("\r\n").split("\t")]
        if len(_trimmed(f)) > len(names):
            raise DataError(f"{source}, line {k + 1}: expected {len(_trimmed(names))} fields, found {len(_trimmed(f))}")
        rows.append(f)
        where.append(f"line {k + 1}")
    return name, names, units, rows, where


def read_trios(path: str | os.PathLike[str], step: int | str | None = None, *, temperature: float | None = None,
               columns: ColumnMap | Mapping[str, Any] | None = None, min_points: int = 1,
               **units: Any) -> RheologyData | CreepData:
    """Moduli or creep compliance from a TA Instruments TRIOS text export (LIMS or plain; layouts above).

    Parameters
    ----------
    path : str or PathLike
    step : int or str, optional
        The step to read: 1-based number in the file's order, or the step's
        name (``"Frequency sweep (25.0 °C)"``). Needed when several steps
        could be read, unless ``temperature`` picks one.
    temperature : float, optional
        °C: read the step at this temperature (within
        :data:`TEMPERATURE_TOLERANCE_C`).
    columns : ColumnMap or dict, optional
        Which column holds what; default recognised from the names row
        (``Angular frequency``, ``Storage modulus``, ``Loss modulus``; else
        ``Tan(delta)`` or ``Complex modulus`` with ``Phase angle``; for creep
        ``Step time`` or ``Time`` with ``Compliance``).
    min_points : int
    **units
        Unit fields of :class:`ColumnMap`, overriding the units row.

    Returns
    -------
    RheologyData or CreepData
        ``comments`` keep the file's metadata, the step's name and the
        columns and units used.
    """
    source = str(path)
    lines = _read_text(Path(path)).splitlines()
    if not any(_is_step_line(s) for s in lines):
        raise DataError(f"{source}: no '[step]' line; expected a TA TRIOS text export (LIMS or plain)")
    blocks, _ = _trios_blocks(source, lines)
    block = _choose(source, blocks, step, temperature, "step", columns)
    return _read_block(block, columns, min_points, units)


# ---- Anton Paar RheoCompass --------------------------------------------------------------------
def _rheocompass_blocks(source: str, lines: list[str]) -> list[_Block]:
    starts = [k for k, s in enumerate(lines) if s.lstrip().startswith(_RC_DATA)]
    first = min([k for k, s in enumerate(lines) if s.lstrip().startswith(_RC_POINTS)] + starts)
    meta = tuple(s.strip().replace("\t", " ") for s in lines[:first] if s.strip())
    blocks = []
    for pos, k0 in enumerate(starts, start=1):
        head = k0
        while head > 0 and lines[head - 1].strip() and not lines[head - 1].lstrip().startswith(_RC_DATA):
            head -= 1  # the interval's own lines: "Interval and data points:", "Temperature:", "Test Type:"...
        preamble = [lines[k] for k in range(head, k0)]
        marker = next((s for s in preamble if s.lstrip().startswith(_RC_POINTS)), None)
        number = pos
        if marker is not None:
            m = re.search(r"\d+", marker.split(":", 1)[1])
            number = int(m.group()) if m else pos
        names = _trimmed([s.strip() for s in lines[k0].strip("\r\n").split("\t")][1:])
        if k0 + 1 >= len(lines):
            raise DataError(f"{source}, line {k0 + 2}: the units line of the interval is missing")
        unit_fields = lines[k0 + 1].rstrip("\r\n").split("\t")
        units = [s.strip() for s in (unit_fields[1:] if not unit_fields[0].strip() else unit_fields)]
        rows, where = _rheocompass_rows(lines, k0 + 2, len(names))
        text = " ".join(preamble)
        table = _Table(source, names, rows, where, units, _decimal(rows),
                       meta + tuple(s.strip().replace("\t", " ") for s in preamble if s.strip()))
        blocks.append(_Block(number, f"interval {number}", table, _temperature(text, names, rows, text)))
    return blocks


def _rheocompass_rows(lines: list[str], k: int, n: int) -> tuple[list[list[str]], list[str]]:
    """The data rows from line index ``k``: with or without a leading empty field, up to a blank or metadata line."""
    rows, where = [], []
    while k < len(lines) and lines[k].strip():
        f = lines[k].rstrip("\r\n").split("\t")
        if f[0].strip().endswith(":"):  # "Result:", "Interval and data points:": the table has ended
            break
        if not f[0].strip() and len(_trimmed(f)) > 0:
            f = f[1:]  # the leading empty field of the long layout
        rows.append([s.strip() for s in f])
        where.append(f"line {k + 1}")
        k += 1
    return rows, where


def read_rheocompass(path: str | os.PathLike[str], interval: int | None = None, *, temperature: float | None = None,
                     columns: ColumnMap | Mapping[str, Any] | None = None, min_points: int = 1,
                     **units: Any) -> RheologyData | CreepData:
    """Moduli or creep compliance from an Anton Paar RheoCompass text export (layout above).

    Columns are recognised from long headers (``Angular Frequency``,
    ``Storage Modulus``, ``Loss Modulus``, ``Loss Factor``, ``Complex
    Modulus``, ``Phase Angle``; ``Time`` with ``Compliance`` for creep) or
    short ones (``ω``, ``G'``, ``G''``, ``|G*|``, ``δ``); units from the units
    line (``[rad/s]``, ``[Pa]``, ``[°]``); a decimal comma is recognised.
    Other columns (``Point No.``, ``Torque``, ``Status``...) are ignored.

    Parameters
    ----------
    path : str or PathLike
    interval : int, optional
        The interval to read, as the file numbers it (``Interval and data
        points: 2``); needed when the file holds several, unless
        ``temperature`` picks one.
    temperature : float, optional
        °C: the interval at this temperature (within :data:`TEMPERATURE_TOLERANCE_C`).
    columns : ColumnMap or dict, optional
        Which column holds what, when the headers are not recognised.
    min_points : int
    **units
        Unit fields of :class:`ColumnMap`, to override what the file states
        (e.g. ``modulus_unit="ratio", geometric_factor=...`` for raw ratios).

    Returns
    -------
    RheologyData or CreepData
        ``comments`` keep the metadata block and record the columns used.
    """
    source = str(path)
    lines = _read_text(Path(path)).splitlines()
    if not any(s.lstrip().startswith(_RC_DATA) for s in lines):
        raise DataError(f"{source}: no '{_RC_DATA}' line; expected an Anton Paar RheoCompass text export")
    block = _choose(source, _rheocompass_blocks(source, lines), interval, temperature, "interval", columns)
    return _read_block(block, columns, min_points, units)


# ---- choosing a block ----------------------------------------------------------------------------
def _readable(block: _Block, columns) -> bool:
    """The block holds data this map (or the recognised headers) reads: creep, or moduli over more than one
    frequency (an amplitude sweep at one frequency is not a frequency sweep)."""
    cmap = guess_columns(block.table.names) if columns is None else _as_map(columns, {})
    if cmap is None:
        return False
    if cmap.layout == "creep":
        return True
    names = [n.strip() for n in block.table.names]
    if cmap.frequency not in names:
        return True  # the map names a column with its unit ("G' [Pa]"); let the reader say what is wrong
    j = names.index(cmap.frequency)
    return len({r[j] for r in block.table.rows if j < len(r)}) > 1


def _choose(source: str, blocks: list[_Block], pick: int | str | None, temperature: float | None, what: str,
            columns) -> _Block:
    if pick is not None and temperature is not None:
        raise ValueError(f"{what}= and temperature= both choose the {what}; give one")
    listing = "; ".join(f"{b.number} {b.name!r}" + ("" if b.temperature_c is None else f" ({b.temperature_c:.4g} °C)")
                        for b in blocks[:6]) + ("; ..." if len(blocks) > 6 else "")
    if temperature is not None:
        near = [b for b in blocks if b.temperature_c is not None
                and abs(b.temperature_c - float(temperature)) <= TEMPERATURE_TOLERANCE_C and _readable(b, columns)]
        if len(near) != 1:
            raise DataError(f"{source}: {len(near)} {what}s at {temperature:g} ± {TEMPERATURE_TOLERANCE_C:g} °C "
                            f"(the {what}s: {listing})")
        return near[0]
    if pick is not None:
        hit = [b for b in blocks if (b.name.strip().lower() == pick.strip().lower() if isinstance(pick, str)
                                     else b.number == int(pick))]
        if len(hit) != 1:
            raise DataError(f"{source}: no {what} {pick!r}; the file has {len(blocks)} ({listing})")
        return hit[0]
    readable = [b for b in blocks if _readable(b, columns)]
    if len(blocks) == 1 or len(readable) == 1:
        return (readable or blocks)[0]
    raise DataError(f"{source}: {len(readable) or len(blocks)} {what}s hold data tenscell reads; choose one with "
                    f"{what}= (command line --{what}) or temperature= ({listing})")


def _read_block(block: _Block, columns, min_points: int, units: Mapping[str, Any]) -> RheologyData | CreepData:
    table = block.table
    if columns is None:
        cmap = guess_columns(table.names)
        if cmap is None:
            raise DataError(f"{table.source}: {block.name!r} has no columns tenscell recognises (frequency with "
                            "G' and G'', or time with compliance); give columns=")
        columns = cmap
    return _data(table, _as_map(columns, dict(units)), min_points)


# ---- any file -------------------------------------------------------------------------------------
def detect_layout(path: str | os.PathLike[str]) -> str:
    """``"trios"``, ``"rheocompass"``, ``"excel"`` or ``"table"`` (delimited text), from the file's content."""
    p = Path(path)
    if p.suffix.lower() in (".xlsx", ".xlsm"):
        return "excel"
    lines = _read_text(p).splitlines()
    if any(_is_step_line(s) for s in lines):
        return "trios"
    if any(s.lstrip().startswith(_RC_DATA) for s in lines):
        return "rheocompass"
    return "table"


def read_data(path: str | os.PathLike[str], columns: ColumnMap | Mapping[str, Any] | None = None, *,
              step: int | str | None = None, temperature: float | None = None, sheet: str | int | None = None,
              min_points: int = 1, **units: Any) -> RheologyData | CreepData:
    """Measured moduli or creep compliance from any file tenscell reads, whatever wrote it.

    The layout is recognised from the content: a TRIOS export (``[step]``
    blocks, :func:`read_trios`), a RheoCompass export (``Interval data:``,
    :func:`read_rheocompass`), tenscell's own CSV (moduli or creep), or a
    CSV/TSV/Excel table whose headers say what they hold (``Angular
    Frequency``, ``G' [Pa]``, ``time (s)``, ``J(t) (1/Pa)``, ``Creep
    Compliance``...; see :data:`~tenscell.io.importers.KNOWN_HEADERS`), with
    units in the headers or in a units row under them. ``columns`` (a
    :class:`ColumnMap` or dict) says what a table's columns hold when the
    headers do not.

    Parameters
    ----------
    path : str or PathLike
    columns : ColumnMap or dict, optional
    step : int or str, optional
        TRIOS step or RheoCompass interval (see :func:`read_trios`).
    temperature : float, optional
        °C: choose the step or interval at this temperature.
    sheet : str or int, optional
        Excel sheet; default the first.
    min_points : int
    **units
        Unit fields of :class:`ColumnMap` (``modulus_unit="Pa"``...).

    Returns
    -------
    RheologyData or CreepData

    Raises
    ------
    DataError
        One line naming the file: what is wrong and where, or, for a layout
        tenscell does not recognise, what it expected.
    """
    layout = detect_layout(path)
    if layout == "trios":
        return read_trios(path, step, temperature=temperature, columns=columns, min_points=min_points, **units)
    if layout == "rheocompass":
        return read_rheocompass(path, None if step is None else int(step), temperature=temperature,
                                columns=columns, min_points=min_points, **units)
    if step is not None or temperature is not None:
        raise ValueError(f"{path}: step= and temperature= choose a block of a TRIOS or RheoCompass export; "
                         "this file is a plain table")
    if layout == "excel":
        return _read_sheet(Path(path), columns, sheet, min_points, units)
    return _read_delimited(Path(path), columns, min_points, units)


_EXPECTED = ("tenscell's CSV (frequency_Hz, G_storage_Pa, G_loss_Pa; or time_s, creep_compliance_per_Pa), a TA TRIOS "
             "text export ([step] blocks), an Anton Paar RheoCompass export ('Interval data:'), or a table whose "
             "headers name frequency with G' and G'' (or time with creep compliance); else give columns= "
             "(command line --columns)")


def _read_delimited(path: Path, columns, min_points: int, units: Mapping[str, Any]) -> RheologyData | CreepData:
    text = _read_text(path)
    body = [(k, s) for k, s in enumerate(text.splitlines(), start=1) if s.strip() and not s.lstrip().startswith("#")]
    if not body:
        raise DataError(f"{path}: no header line (the file has no non-comment lines)")
    k, header = body[0]
    try:
        sep = csv.Sniffer().sniff(header, delimiters=",;\t").delimiter
    except csv.Error:
        sep = "\t" if "\t" in header else ","
    names = next(csv.reader([header], delimiter=sep))
    if columns is None and not units and _own_layout(names):
        return (read_creep_csv(path, min_points=min_points) if is_creep_header(text, str(path))
                else read_csv(path, min_points=min_points))
    if columns is None and guess_columns(names) is None:
        raise DataError(f"{path}, line {k}: the columns {', '.join(repr(n.strip()) for n in names)} are not a layout "
                        f"tenscell recognises; expected {_EXPECTED}")
    columns = columns if columns is not None else guess_columns(names)
    units_line = len(body) > 1 and _is_units_row(next(csv.reader([body[1][1]], delimiter=sep)))
    decimal = "," if sep != "," and re.search(r"\d,\d", " ".join(s for _, s in body[1 + units_line:6])) else "."
    return read_table(path, columns, sep=sep, header_line=k, units_line=units_line, decimal=decimal,
                      min_points=min_points, **units)


def _own_layout(names: list[str]) -> bool:
    """The header is tenscell's own layout (read by :func:`read_csv` / :func:`read_creep_csv`)."""
    own = {"frequency_hz", "prestress_pa", "g_storage_pa", "g_loss_pa", "g_storage_sd_pa", "g_loss_sd_pa",
           "g_abs_pa", "phase_deg", "g_abs_sd_pa", "phase_sd_deg", "time_s", "creep_compliance_per_pa",
           "creep_compliance_sd_per_pa"}
    return all(n.strip().lower() in own for n in names)


def _is_units_row(fields_: list[str]) -> bool:
    """A row of units (``[Pa]``, ``rad/s``, empty) rather than numbers."""
    filled = [f.strip() for f in fields_ if f.strip()]
    if not filled:
        return False
    for f in filled:
        try:
            float(f.replace(",", "."))
            return False
        except ValueError:
            pass
    return True


def _read_sheet(path: Path, columns, sheet, min_points: int, units: Mapping[str, Any]) -> RheologyData | CreepData:
    """An Excel sheet (a TRIOS Excel export has one per step): the header is the first row whose names say what
    the columns hold (or that ``columns`` names), with a units row under it if the next row is one."""
    from .columns import _excel_table

    probe = _excel_table(path, sheet, None, False)
    rows = [probe.names] + [["" if c is None else str(c) for c in r] for r in probe.rows]
    for i, r in enumerate(rows[:50]):
        if (columns is None and guess_columns(r) is not None) or (
                columns is not None and _names_all(_as_map(columns, dict(units)), r)):
            line = int(probe.where[i - 1].split()[-1]) if i else None
            units_row = i + 1 < len(rows) and _is_units_row(rows[i + 1])
            return read_table(path, columns if columns is not None else guess_columns(r), header_line=line,
                              units_line=units_row, sheet=sheet, min_points=min_points, **units)
    raise DataError(f"{probe.source}: no row of column names tenscell recognises in the first 50 rows; expected "
                    f"{_EXPECTED}")


def _names_all(cmap: ColumnMap, row: list[str]) -> bool:
    cells = {str(c).strip() for c in row}
    return all(c.strip() in cells or any(str(x).strip().startswith(c.strip()) for x in cells)
               for c in cmap.columns().values())

"""Delimited text tables (CSV, TSV, semicolons) whose headers say what their columns hold, or that a column map
names: the reader of last resort.

The separator is sniffed from the header (comma, semicolon, tab); a units row under the header is recognised
(``[Pa]``, ``rad/s``); with a semicolon or tab separator a decimal comma is too. A table whose columns identify
several cells or samples (``cell``, ``cell_index``, ``sample`` with several values) is refused: ``tenscell fit``
fits one cell's sweep, ``tenscell fit-population`` many cells.
"""
from __future__ import annotations

import csv
import re

from ..._errors import option
from ..columns import DataError, guess_columns
from ..importers import read_table
from ._blocks import Probe, Request

__all__ = ["LAYOUT", "EXPECTED", "detect", "read", "is_units_row"]

LAYOUT = "table"
EXPECTED = ("a table whose headers name frequency with G' and G'' (or time with creep compliance), with units in "
            "the headers or a units row")
#: columns that identify a cell or sample: a table with several values in one holds several data sets
_IDENTIFIERS = ("cell", "cell_index", "cell_id", "cell index", "sample", "sample_id", "specimen")


def _body(probe: Probe) -> list[tuple[int, str]]:
    return [(k, s) for k, s in enumerate(probe.lines, start=1) if s.strip() and not s.lstrip().startswith("#")]


def _separator(header: str) -> str:
    try:
        return csv.Sniffer().sniff(header, delimiters=",;\t").delimiter
    except csv.Error:
        return "\t" if "\t" in header else ("," if "," in header else ";" if ";" in header else ",")


def detect(probe: Probe) -> int:
    """2 when the header's names are recognised (:func:`~tenscell.io.columns.guess_columns`), 1 for any other text."""
    if probe.suffix in (".xlsx", ".xlsm"):
        return 0
    body = _body(probe)
    if not body:
        return 1
    header = body[0][1]
    names = next(csv.reader([header], delimiter=_separator(header)))
    return 2 if guess_columns(names) is not None else 1


def is_units_row(fields_: list[str]) -> bool:
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


def read(probe: Probe, request: Request):
    """The table, with the request's map (or the one its headers say)."""
    from . import expected

    body = _body(probe)
    if not body:
        raise DataError(f"{probe.source}: no header line (the file has no non-comment lines)")
    k, header = body[0]
    sep = _separator(header)
    names = next(csv.reader([header], delimiter=sep))
    cmap = request.map_for(names)
    if cmap is None:
        shown = ", ".join(repr(n.strip()) for n in names[:8]) + (f", ... ({len(names)} columns)" if len(names) > 8 else "")
        raise DataError(f"{probe.source}, line {k}: the columns {shown} are not a layout tenscell recognises; say "
                        f"which column holds what with {option('columns')} (tenscell reads {expected()})")
    rows = [next(csv.reader([s], delimiter=sep)) for _, s in body[1:]]
    _refuse_several_cells(probe.source, names, rows, k)
    units_line = bool(rows) and is_units_row(rows[0])
    values = " ".join(s for _, s in body[1 + units_line:6])
    decimal = "," if sep != "," and re.search(r"\d,\d", values) else "."
    return read_table(probe.path, cmap, sep=sep, header_line=k, units_line=units_line, decimal=decimal,
                      min_points=request.min_points, accept=request.accept)


def _refuse_several_cells(source: str, names: list[str], rows: list[list[str]], line: int) -> None:
    for j, name in enumerate(names):
        if name.strip().lower() in _IDENTIFIERS:
            values = {r[j].strip() for r in rows if j < len(r) and r[j].strip()}
            if len(values) > 1:
                raise DataError(f"{source}, line {line}: column {name.strip()!r} names {len(values)} cells or samples: "
                                "a table of several data sets (fit one cell per file, or all of them with `tenscell "
                                "fit-population`)")

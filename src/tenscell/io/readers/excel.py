"""Excel workbooks (``.xlsx``, ``.xlsm``): a sheet whose header row names what its columns hold.

A TRIOS Excel export has one sheet per step, a names row and a units row: the header is the first row (of the
first 50) whose names are recognised (or that the column map names), with a units row under it if the next row
is one. Read with openpyxl (``pip install "tenscell[excel]"``).
"""
from __future__ import annotations

from ..columns import DataError, column_map, excel_table, guess_columns
from ..importers import read_table
from ._blocks import Probe, Request
from .table import is_units_row

__all__ = ["LAYOUT", "EXPECTED", "detect", "read"]

LAYOUT = "Excel workbook"
EXPECTED = "an Excel workbook (.xlsx) with a header row naming its columns"


def detect(probe: Probe) -> int:
    """2 for an .xlsx/.xlsm file, else 0."""
    return 2 if probe.suffix in (".xlsx", ".xlsm") else 0


def read(probe: Probe, request: Request):
    """The sheet the request names (default the first), from its first recognised header row."""
    probe_table = excel_table(probe.path, request.sheet, None, False)
    rows = [probe_table.names] + [["" if c is None else str(c) for c in r] for r in probe_table.rows]
    for i, r in enumerate(rows[:50]):
        if (request.columns is None and guess_columns(r) is not None) or (
                request.columns is not None and _names_all(column_map(request.columns, request.units), r)):
            line = int(probe_table.where[i - 1].split()[-1]) if i else None
            units_row = i + 1 < len(rows) and is_units_row(rows[i + 1])
            columns = request.columns if request.columns is not None else guess_columns(r)
            return read_table(probe.path, columns, header_line=line, units_line=units_row, sheet=request.sheet,
                              min_points=request.min_points, accept=request.accept, **request.units)
    from . import expected

    raise DataError(f"{probe_table.source}: no row of column names tenscell recognises in the first 50 rows; "
                    f"expected {expected()}")


def _names_all(cmap, row) -> bool:
    cells = {str(c).strip() for c in row}
    return all(c.strip() in cells or any(str(x).strip().startswith(c.strip()) for x in cells)
               for c in cmap.columns().values())

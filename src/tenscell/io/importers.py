"""Measured moduli from the user's own tables: DataFrames, CSV/TSV/Excel files, instrument exports.

:mod:`tenscell.io.data` reads the package's own CSV layout (``frequency_Hz,
G_storage_Pa, G_loss_Pa``). Here a :class:`ColumnMap` says which of *your*
columns holds which quantity and in which unit; every unit is converted
explicitly, and a unit the map does not state is taken from the column's
header (``"G' [kPa]"``, ``"f (rad/s)"``, ``"G_storage_Pa"``) or a units row,
never assumed.

Quantities and units
--------------------
frequency
    ``"Hz"`` or ``"rad/s"`` (divided by 2π).
moduli (G', G'', |G| and their standard deviations)
    ``"Pa"``, ``"kPa"``, ``"MPa"``, or ``"ratio"``: a measured ratio (e.g.
    torque or force per displacement) converted to a modulus by the stated
    ``geometric_factor`` (Pa per unit of the ratio): ``G = factor × ratio``.
    The factor depends on the probe and its contact with the cell and comes
    from your method, never from tenscell.
phase
    ``"deg"`` or ``"rad"``; ``G' = |G| cos φ``, ``G'' = |G| sin φ``, with
    0 < φ < 90°.
loss tangent
    ``tan δ = G''/G'`` (dimensionless), with G' or G'' or |G|.
prestress
    ``"Pa"`` or ``"kPa"``.
time (creep)
    ``"s"``, ``"ms"`` or ``"min"``.
creep compliance J(t)
    ``"1/Pa"``, ``"1/kPa"`` or ``"1/MPa"``.

Accepted combinations: G' and G''; G' or G'' with tan δ; |G| with the phase
or with tan δ; for creep, time with J(t). Standard deviations (fit weights)
are read with G' and G'' and with J(t).

Errors are :class:`~tenscell.io.data.DataError` naming the file (or
DataFrame), the line (text files), row (Excel, as the spreadsheet numbers it)
or index label (DataFrames), and the column.

Instrument exports (TA TRIOS, Anton Paar RheoCompass) are read by
:mod:`tenscell.io.instruments` through the same maps; see
``docs/importing-data.md``.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

from .columns import (COMPLIANCE_UNITS, FREQUENCY_UNITS, KNOWN_HEADERS, MODULUS_UNITS, PHASE_UNITS, PRESTRESS_UNITS,
                      TIME_UNITS, ColumnMap, DataError, column_map, excel_table, CellTable, _text_table, frame_table,
                      guess_columns, parse)
from .creep_data import CreepData
from .data import RheologyData
from .provenance import Provenance

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["ColumnMap", "from_dataframe", "read_table", "guess_columns", "KNOWN_HEADERS", "FREQUENCY_UNITS",
           "MODULUS_UNITS", "PHASE_UNITS", "PRESTRESS_UNITS", "TIME_UNITS", "COMPLIANCE_UNITS", "DataError"]


def build(table: CellTable, cmap: ColumnMap, min_points: int = 1, provenance: Provenance | None = None, accept=(),
          *, what: str | None = None, want: str | None = None) -> RheologyData | CreepData:
    """The data a table holds under a map, as every reader ends: parsed (:func:`tenscell.io.columns.parse`),
    built (CreepData for the creep layout, RheologyData otherwise) with its provenance (``provenance`` as the
    reader knows it, completed with the columns and units read), and checked (:mod:`tenscell.io.checks`;
    ``accept`` skips checks, ``what`` names the step in their messages). ``want`` (``"moduli"`` or
    ``"creep"``) refuses the other kind."""
    parsed = parse(table, cmap, min_points)
    cls = CreepData if parsed.layout == "creep" else RheologyData
    if want is not None and (cls is CreepData) != (want == "creep"):
        held, other = ("creep compliance", "tenscell.io.CreepData") if cls is CreepData else \
            ("moduli", "tenscell.RheologyData")
        raise DataError(f"{parsed.source}: the columns hold {held}, not {want}; use {other}.from_dataframe")
    base = provenance or Provenance(file=parsed.source, layout="table")
    return cls.from_parsed(parsed, base, accept, what)


# ---- sources ----------------------------------------------------------------------------------
def from_dataframe(df: pd.DataFrame, columns: ColumnMap | Mapping[str, Any] | None = None, *,
                   source: str = "<DataFrame>", min_points: int = 1, accept=(), want: str | None = None,
                   **units: Any) -> RheologyData | CreepData:
    """Measured moduli (or creep compliance) from a pandas DataFrame.

    Parameters
    ----------
    df : pandas.DataFrame
        One row per measurement.
    columns : ColumnMap or dict, optional
        Which column holds what (a dict is passed to :class:`ColumnMap`);
        default recognised from the column names (:func:`guess_columns`:
        tenscell's own ``frequency_Hz, G_storage_Pa, G_loss_Pa`` or
        ``time_s, creep_compliance_per_Pa``, and instruments' spellings).
    source : str
        Name used in error messages and recorded as the data's source.
    min_points : int
        Fewest rows accepted.
    accept : str or sequence of str, optional
        Checks of :mod:`tenscell.io.checks` to skip.
    want : {"moduli", "creep"}, optional
        Refuse the other kind of data.
    **units
        Unit fields of :class:`ColumnMap` (``frequency_unit="rad/s"``...), overriding the map's.

    Returns
    -------
    RheologyData or CreepData
        CreepData when the map reads ``time`` and ``compliance``.
    """
    table = frame_table(df, source)
    cmap = column_map(columns if columns is not None else guess_columns(table.names), units)
    return build(table, cmap, min_points, Provenance(file=source, layout="DataFrame"), accept, want=want)


def read_table(path: str | os.PathLike[str], columns: ColumnMap | Mapping[str, Any] | None, *, sep: str | None = None,
               header_line: int | None = None, units_line: bool = False, decimal: str = ".",
               sheet: str | int | None = None, min_points: int = 1, accept=(),
               **units: Any) -> RheologyData | CreepData:
    """Measured moduli (or creep compliance) from a CSV, TSV or Excel file with your own column names.

    Parameters
    ----------
    path : str or PathLike
        ``.xlsx``/``.xlsm`` files are read with openpyxl (``pip install
        tenscell[excel]``); anything else as delimited text.
    columns : ColumnMap or dict or None
        Which column holds what, and units; None: tenscell's own names.
    sep : str, optional
        Field separator of a text file; default sniffed from the header
        among comma, semicolon and tab.
    header_line : int, optional
        1-based line (text) or row (Excel) of the column names; default the
        first line that is neither blank nor a ``#`` comment.
    units_line : bool
        The line after the header holds each column's unit (``[Pa]``, ``Hz``...).
    decimal : {".", ","}
        Decimal mark of a text file.
    sheet : str or int, optional
        Excel sheet name or 0-based index; default the first.
    min_points : int
        Fewest data rows accepted.
    accept : str or sequence of str, optional
        Checks of :mod:`tenscell.io.checks` to skip (``"outliers"``...).
    **units
        Unit fields of :class:`ColumnMap`, overriding the map's.

    Returns
    -------
    RheologyData or CreepData
        ``comments`` hold the file's ``#`` lines and a line recording the
        columns and units used; ``provenance`` says the same.

    Raises
    ------
    DataError
        Naming the file, the line (row) and the column.
    """
    cmap = column_map(columns, units)
    if decimal not in (".", ","):
        raise ValueError(f"decimal: expected '.' or ',', got {decimal!r}")
    p = Path(path)
    if p.suffix.lower() in (".xlsx", ".xlsm"):
        table = excel_table(p, sheet, header_line, units_line)
        layout = f"Excel sheet {table.source.rsplit('[', 1)[-1].rstrip(']')!r}"
    else:
        table = _text_table(p, sep, header_line, units_line, decimal)
        layout = "table"
    return build(table, cmap, min_points, Provenance(file=str(path), layout=layout), accept)



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

Accepted combinations: G' and G''; G' or G'' with tan δ; |G| with the phase
or with tan δ. Standard deviations (fit weights) are read with G' and G''.

Errors are :class:`~tenscell.io.data.DataError` naming the file (or
DataFrame), the line (text files), row (Excel, as the spreadsheet numbers it)
or index label (DataFrames), and the column.

Instrument exports
------------------
:func:`read_rheocompass` reads the tab-separated text export of an Anton
Paar rheometer (RheoCompass "Interval data" tables: a metadata block, then a
names row, a row of bracketed units and the data points, decimal point or
comma). See ``docs/importing-data.md`` for the mapping.
"""
from __future__ import annotations

import csv
import math
import os
import re
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

from .data import DataError, RheologyData

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["ColumnMap", "from_dataframe", "read_table", "read_rheocompass", "FREQUENCY_UNITS", "MODULUS_UNITS",
           "PHASE_UNITS", "PRESTRESS_UNITS"]

#: frequency units -> factor to Hz
FREQUENCY_UNITS = {"Hz": 1.0, "rad/s": 1.0 / (2.0 * math.pi)}
#: modulus units -> factor to Pa ("ratio" uses the map's geometric_factor)
MODULUS_UNITS = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "ratio": math.nan}
#: phase units -> factor to radians
PHASE_UNITS = {"deg": math.pi / 180.0, "rad": 1.0}
#: prestress units -> factor to Pa
PRESTRESS_UNITS = {"Pa": 1.0, "kPa": 1e3}

# spellings found in headers and units rows -> the canonical unit
_ALIASES = {
    "hz": "Hz", "1/s": None, "rad/s": "rad/s", "rad s-1": "rad/s", "rad_per_s": "rad/s", "pa": "Pa", "kpa": "kPa",
    "mpa": "MPa", "deg": "deg", "°": "deg", "degree": "deg", "degrees": "deg", "rad": "rad", "1": "", "-": "",
    "": "",
}
_BRACKETED = re.compile(r"^(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]\s*$")
_SUFFIX = re.compile(r"_(Hz|rad_per_s|Pa|kPa|MPa|deg|rad)$")


@dataclass(frozen=True)
class ColumnMap:
    """Which of your columns holds which quantity, and the unit it is in.

    Column names are matched exactly (after stripping spaces). A unit left as
    None is read from the column's header (``"G' [kPa]"``, ``"G' (kPa)"``,
    ``"G_storage_kPa"``) or the file's units row; if the file does not say
    either, reading stops with an error asking you to state it.

    Parameters
    ----------
    frequency : str
        Column of the oscillation frequency.
    storage, loss : str, optional
        Columns of G' and G''.
    magnitude, phase : str, optional
        Columns of |G| and the phase angle.
    loss_tangent : str, optional
        Column of tan δ = G''/G'.
    prestress : str, optional
        Column of the cells' prestress (a prestress sweep).
    storage_sd, loss_sd : str, optional
        Standard deviations of G' and G'' (same unit as the moduli).
    frequency_unit : {"Hz", "rad/s"}, optional
    modulus_unit : {"Pa", "kPa", "MPa", "ratio"}, optional
    phase_unit : {"deg", "rad"}, optional
    prestress_unit : {"Pa", "kPa"}, optional
    geometric_factor : float, optional
        Pa per unit of the measured ratio; required with ``modulus_unit="ratio"``
        and refused otherwise.

    Examples
    --------
    >>> ColumnMap(frequency="omega", frequency_unit="rad/s", storage="Gp", loss="Gpp", modulus_unit="kPa")
    ... # doctest: +SKIP
    """

    frequency: str
    storage: str | None = None
    loss: str | None = None
    magnitude: str | None = None
    phase: str | None = None
    loss_tangent: str | None = None
    prestress: str | None = None
    storage_sd: str | None = None
    loss_sd: str | None = None
    frequency_unit: str | None = None
    modulus_unit: str | None = None
    phase_unit: str | None = None
    prestress_unit: str | None = None
    geometric_factor: float | None = None

    def __post_init__(self) -> None:
        for name, table in (("frequency_unit", FREQUENCY_UNITS), ("modulus_unit", MODULUS_UNITS),
                            ("phase_unit", PHASE_UNITS), ("prestress_unit", PRESTRESS_UNITS)):
            unit = getattr(self, name)
            if unit is not None and unit not in table:
                raise ValueError(f"{name}: {unit!r} is not one of {', '.join(table)}")
        if (self.modulus_unit == "ratio") != (self.geometric_factor is not None):
            raise ValueError("geometric_factor: give it (Pa per unit of the ratio) exactly when modulus_unit='ratio'")
        if self.geometric_factor is not None and not (math.isfinite(self.geometric_factor)
                                                      and self.geometric_factor > 0):
            raise ValueError(f"geometric_factor must be a finite number > 0 (Pa per unit), got {self.geometric_factor!r}")
        layout = self.layout
        if (self.storage_sd or self.loss_sd) and layout != "storage+loss":
            raise ValueError("storage_sd, loss_sd: standard deviations are read only with G' and G'' columns")

    @property
    def layout(self) -> str:
        """Which moduli the map reads: ``"storage+loss"``, ``"storage+tan"``, ``"loss+tan"``, ``"magnitude+phase"``
        or ``"magnitude+tan"``."""
        given = {k for k in ("storage", "loss", "magnitude", "phase", "loss_tangent") if getattr(self, k)}
        for layout, need in _LAYOUTS.items():
            if given == need:
                return layout
        raise ValueError(f"columns: {', '.join(sorted(given)) or 'no moduli'} is not a layout tenscell reads; give "
                         "storage and loss, storage or loss with loss_tangent, or magnitude with phase or loss_tangent")

    def columns(self) -> dict[str, str]:
        """Quantity -> column name, for the quantities this map reads."""
        return {f.name: getattr(self, f.name) for f in fields(self)
                if f.name in _QUANTITIES and getattr(self, f.name) is not None}


_LAYOUTS = {
    "storage+loss": {"storage", "loss"}, "storage+tan": {"storage", "loss_tangent"},
    "loss+tan": {"loss", "loss_tangent"}, "magnitude+phase": {"magnitude", "phase"},
    "magnitude+tan": {"magnitude", "loss_tangent"},
}
# quantity -> the map field holding its unit ("" for dimensionless)
_QUANTITIES = {
    "frequency": "frequency_unit", "storage": "modulus_unit", "loss": "modulus_unit", "magnitude": "modulus_unit",
    "phase": "phase_unit", "loss_tangent": "", "prestress": "prestress_unit", "storage_sd": "modulus_unit",
    "loss_sd": "modulus_unit",
}
_NAMES = {"frequency": "frequency", "storage": "G'", "loss": "G''", "magnitude": "|G|", "phase": "phase",
          "loss_tangent": "loss tangent", "prestress": "prestress", "storage_sd": "SD of G'", "loss_sd": "SD of G''"}


# ---- one table, whatever it came from -----------------------------------------------------
@dataclass(frozen=True)
class _Table:
    """Cells as text or numbers, with where each row and column sits in the source (for messages)."""

    source: str
    names: list[str]
    rows: list[list[Any]]
    where: list[str]          # "line 12", "row 12", "index 'a'"
    units: list[str] | None = None  # a units row, if the source has one
    decimal: str = "."
    comments: tuple[str, ...] = ()


def _error(table: _Table, problem: str, row: int | None = None, column: str | None = None) -> DataError:
    parts = [table.source] + ([table.where[row]] if row is not None else [])
    return DataError(", ".join(parts) + ": " + (f"column {column!r}: " if column else "") + problem)


def _unit_in_name(name: str) -> tuple[str, str | None]:
    """``("G'", "kPa")`` from ``"G' [kPa]"``, ``"G' (kPa)"`` or ``"G_kPa"``; unit None when the name has none."""
    m = _BRACKETED.match(name)
    if m:
        return m.group(1).strip(), m.group(2)
    m = _SUFFIX.search(name)
    if m:
        return name, m.group(1).replace("_per_", "/")
    return name, None


def _canonical_unit(text: str) -> str | None:
    """A unit as written in a file, in tenscell's spelling; None when not understood."""
    t = text.strip().strip("[]()").strip()
    if t in ("Hz", "rad/s", "Pa", "kPa", "MPa", "deg", "rad"):
        return t
    return _ALIASES.get(t.lower().replace("·", " ").replace("**", "^"))


def _resolve(table: _Table, cmap: ColumnMap) -> dict[str, tuple[int, str]]:
    """Quantity -> (column index, unit), checking that every column exists and every unit is known."""
    stripped = [n.strip() for n in table.names]
    bare = [_unit_in_name(n)[0] for n in stripped]
    out = {}
    for quantity, column in cmap.columns().items():
        col = column.strip()
        if col in stripped:
            j = stripped.index(col)
        elif bare.count(col) == 1:  # the map names "G'" and the header says "G' [kPa]"
            j = bare.index(col)
        else:
            raise _error(table, f"no such column for {_NAMES[quantity]}; the columns are "
                                f"{', '.join(repr(n) for n in stripped)}")
        out[quantity] = (j, _unit_of(table, cmap, quantity, j))
    return out


def _unit_of(table: _Table, cmap: ColumnMap, quantity: str, j: int) -> str:
    field = _QUANTITIES[quantity]
    if not field:
        return ""
    stated = getattr(cmap, field)
    written = _unit_in_name(table.names[j].strip())[1]
    if written is None and table.units is not None and j < len(table.units) and table.units[j].strip():
        written = table.units[j]
    in_file = None if written is None else _canonical_unit(written)
    column = table.names[j].strip()
    if written is not None and in_file is None and stated is None:
        raise _error(table, f"unit {written!r} of {_NAMES[quantity]} is not one tenscell converts; state "
                            f"{field}= in the ColumnMap", column=column)
    if stated is not None:
        if in_file not in (None, "") and in_file != stated and stated != "ratio":
            raise _error(table, f"the file says {written!r} but the ColumnMap says {field}={stated!r}", column=column)
        return stated
    if in_file in (None, ""):
        raise _error(table, f"the file does not state the unit of {_NAMES[quantity]}; give {field}= "
                            f"(one of {', '.join(_units_table(field))})", column=column)
    if in_file not in _units_table(field):
        raise _error(table, f"unit {written!r} does not fit {_NAMES[quantity]} (expected one of "
                            f"{', '.join(_units_table(field))})", column=column)
    return in_file


def _units_table(field: str) -> dict[str, float]:
    return {"frequency_unit": FREQUENCY_UNITS, "modulus_unit": MODULUS_UNITS, "phase_unit": PHASE_UNITS,
            "prestress_unit": PRESTRESS_UNITS}[field]


def _number(table: _Table, value: Any, i: int, column: str) -> float:
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        x = float(value)
    else:
        text = "" if value is None else str(value).strip()
        if table.decimal != ".":
            text = text.replace(table.decimal, ".")  # a field such as "1.234,5" then fails, as it should
        try:
            x = float(text) if text and "_" not in text else math.nan
        except ValueError:
            x = math.nan
        if math.isnan(x):
            found = repr(str(value).strip()) if text else "an empty field"
            raise _error(table, f"not a number: {found}", i, column)
    if not math.isfinite(x):
        raise _error(table, f"value {value!r} is not finite", i, column)
    return x


def _columns(table: _Table, cmap: ColumnMap, resolved: Mapping[str, tuple[int, str]]) -> dict[str, np.ndarray]:
    """Each quantity's values converted to SI (Hz, Pa, rad), checked row by row."""
    out: dict[str, np.ndarray] = {}
    for quantity, (j, unit) in resolved.items():
        column = table.names[j].strip()
        raw = np.array([_number(table, row[j] if j < len(row) else None, i, column)
                        for i, row in enumerate(table.rows)])
        bad = np.flatnonzero(raw <= 0)
        if bad.size:
            i = int(bad[0])
            raise _error(table, f"{_NAMES[quantity]} {raw[i]:g} must be > 0", i, column)
        if quantity == "phase":
            top = math.pi / 2 / PHASE_UNITS[unit]
            over = np.flatnonzero(raw >= top)
            if over.size:
                i = int(over[0])
                raise _error(table, f"phase {raw[i]:g} {unit} must be below {top:g} {unit} (G' > 0)", i, column)
        out[quantity] = raw * _factor(quantity, unit, cmap)
    return out


def _factor(quantity: str, unit: str, cmap: ColumnMap) -> float:
    field = _QUANTITIES[quantity]
    if not field:
        return 1.0
    if unit == "ratio":
        return float(cmap.geometric_factor)  # type: ignore[arg-type]
    return _units_table(field)[unit]


def _moduli(v: Mapping[str, np.ndarray], layout: str) -> tuple[np.ndarray, np.ndarray]:
    """G', G'' (Pa) from the layout's columns (already in Pa, rad)."""
    if layout == "storage+loss":
        return v["storage"], v["loss"]
    if layout == "storage+tan":
        return v["storage"], v["storage"] * v["loss_tangent"]
    if layout == "loss+tan":
        return v["loss"] / v["loss_tangent"], v["loss"]
    phase = v["phase"] if layout == "magnitude+phase" else np.arctan(v["loss_tangent"])
    return v["magnitude"] * np.cos(phase), v["magnitude"] * np.sin(phase)


def _data(table: _Table, cmap: ColumnMap, min_points: int) -> RheologyData:
    if not table.rows:
        raise _error(table, "no data rows")
    if len(table.rows) < min_points:
        raise _error(table, f"{len(table.rows)} data points, fewer than min_points={min_points}")
    resolved = _resolve(table, cmap)
    v = _columns(table, cmap, resolved)
    Gs, Gl = _moduli(v, cmap.layout)
    how = "; ".join(f"{_NAMES[q]} = {table.names[j].strip()!r}" + (f" [{u}]" if u else "")
                    for q, (j, u) in resolved.items())
    if cmap.geometric_factor is not None:
        how += f"; moduli = {cmap.geometric_factor:g} Pa × ratio"
    return RheologyData(
        frequency_hz=v["frequency"], G_storage=Gs, G_loss=Gl, prestress=v.get("prestress"),
        G_storage_sd=v.get("storage_sd"), G_loss_sd=v.get("loss_sd"), source=table.source,
        comments=(*table.comments, f"imported by tenscell: {how}"), locations=tuple(table.where),
    )


def _as_map(columns: ColumnMap | Mapping[str, Any] | None, units: Mapping[str, Any]) -> ColumnMap:
    if columns is None:
        columns = {"frequency": "frequency_Hz", "storage": "G_storage_Pa", "loss": "G_loss_Pa"}
    try:
        cmap = columns if isinstance(columns, ColumnMap) else ColumnMap(**dict(columns))
        return replace(cmap, **units) if units else cmap
    except TypeError as err:  # an unknown field name
        raise ValueError(f"columns: {err}; the fields are {', '.join(f.name for f in fields(ColumnMap))}") from None


# ---- sources ----------------------------------------------------------------------------------
def from_dataframe(df: pd.DataFrame, columns: ColumnMap | Mapping[str, Any] | None = None, *,
                   source: str = "<DataFrame>", min_points: int = 1, **units: Any) -> RheologyData:
    """Measured moduli from a pandas DataFrame.

    Parameters
    ----------
    df : pandas.DataFrame
        One row per measurement.
    columns : ColumnMap or dict, optional
        Which column holds what (a dict is passed to :class:`ColumnMap`);
        default tenscell's own names ``frequency_Hz, G_storage_Pa, G_loss_Pa``.
    source : str
        Name used in error messages and recorded as the data's source.
    min_points : int
        Fewest rows accepted.
    **units
        Unit fields of :class:`ColumnMap` (``frequency_unit="rad/s"``...), overriding the map's.

    Returns
    -------
    RheologyData
    """
    cmap = _as_map(columns, units)
    names = [str(c) for c in df.columns]
    rows = df.to_numpy(dtype=object).tolist()
    where = [f"index {label!r}" for label in df.index]
    return _data(_Table(source, names, rows, where), cmap, min_points)


def read_table(path: str | os.PathLike[str], columns: ColumnMap | Mapping[str, Any], *, sep: str | None = None,
               header_line: int | None = None, units_line: bool = False, decimal: str = ".",
               sheet: str | int | None = None, min_points: int = 1, **units: Any) -> RheologyData:
    """Measured moduli from a CSV, TSV or Excel file with your own column names.

    Parameters
    ----------
    path : str or PathLike
        ``.xlsx``/``.xlsm`` files are read with openpyxl (``pip install
        tenscell[excel]``); anything else as delimited text.
    columns : ColumnMap or dict
        Which column holds what, and units.
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
    **units
        Unit fields of :class:`ColumnMap`, overriding the map's.

    Returns
    -------
    RheologyData
        ``comments`` hold the file's ``#`` lines and a line recording the
        columns and units used.

    Raises
    ------
    DataError
        Naming the file, the line (row) and the column.
    """
    cmap = _as_map(columns, units)
    if decimal not in (".", ","):
        raise ValueError(f"decimal: expected '.' or ',', got {decimal!r}")
    p = Path(path)
    if p.suffix.lower() in (".xlsx", ".xlsm"):
        table = _excel_table(p, sheet, header_line, units_line)
    else:
        table = _text_table(p, sep, header_line, units_line, decimal)
    return _data(table, cmap, min_points)


def _read_text(path: Path) -> str:
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            return fh.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise DataError(f"{path}: cannot read file: {exc}") from exc


def _text_table(path: Path, sep: str | None, header_line: int | None, units_line: bool, decimal: str) -> _Table:
    source = str(path)
    lines = _read_text(path).splitlines()
    comments = tuple(s.strip()[1:].strip() for s in lines if s.strip().startswith("#"))
    body = [(k, s) for k, s in enumerate(lines, start=1) if s.strip() and not s.strip().startswith("#")]
    if header_line is not None:
        body = [(k, s) for k, s in body if k >= header_line]
        if not body or body[0][0] != header_line:
            raise DataError(f"{source}, line {header_line}: header_line is blank, a comment or past the end")
    if not body:
        raise DataError(f"{source}: no header line (the file has no non-comment lines)")
    if sep is None:
        try:
            sep = csv.Sniffer().sniff(body[0][1], delimiters=",;\t").delimiter
        except csv.Error:
            sep = "\t" if "\t" in body[0][1] else ","
    split = [(k, next(csv.reader([s], delimiter=sep))) for k, s in body]
    names = split[0][1]
    units = split[1][1] if units_line and len(split) > 1 else None
    data = split[2:] if units_line else split[1:]
    for k, fields_ in data:
        if len(fields_) != len(names):
            raise DataError(f"{source}, line {k}: expected {len(names)} fields, found {len(fields_)}")
    return _Table(source, names, [f for _, f in data], [f"line {k}" for k, _ in data], units, decimal, comments)


def _excel_table(path: Path, sheet: str | int | None, header_row: int | None, units_row: bool) -> _Table:
    try:
        import openpyxl
    except ImportError:  # pragma: no cover - depends on the installation
        raise DataError(f"{path}: reading Excel files needs openpyxl (pip install 'tenscell[excel]')") from None
    try:
        book = openpyxl.load_workbook(path, read_only=True, data_only=True)
    except Exception as exc:  # openpyxl raises many types for a bad file
        raise DataError(f"{path}: cannot read workbook: {exc}") from exc
    try:
        names_ = book.sheetnames
        if sheet is None:
            ws = book[names_[0]]
        elif isinstance(sheet, int):
            ws = book[names_[sheet]] if 0 <= sheet < len(names_) else None
        else:
            ws = book[sheet] if sheet in names_ else None
        if ws is None:
            raise DataError(f"{path}: no sheet {sheet!r}; the sheets are {', '.join(map(repr, names_))}")
        rows = [(k, list(r)) for k, r in enumerate(ws.iter_rows(values_only=True), start=1)
                if any(c is not None and str(c).strip() for c in r)]
    finally:
        book.close()
    source = f"{path} [{ws.title}]"
    if header_row is not None:
        rows = [(k, r) for k, r in rows if k >= header_row]
    if not rows:
        raise DataError(f"{source}: no header row")
    names = ["" if c is None else str(c) for c in rows[0][1]]
    units = ["" if c is None else str(c) for c in rows[1][1]] if units_row and len(rows) > 1 else None
    data = rows[2:] if units_row else rows[1:]
    return _Table(source, names, [r for _, r in data], [f"row {k}" for k, _ in data], units)


# ---- instrument exports -----------------------------------------------------------------------
#: RheoCompass column names -> quantity (the first present of each quantity is used)
RHEOCOMPASS_COLUMNS: dict[str, Sequence[str]] = {
    "frequency": ("Angular Frequency", "Frequency"),
    "storage": ("Storage Modulus",),
    "loss": ("Loss Modulus",),
    "loss_tangent": ("Loss Factor", "Damping Factor"),
    "magnitude": ("Complex Modulus",),
    "phase": ("Phase Angle",),
}
_RHEOCOMPASS_MARK = "Interval data:"


def read_rheocompass(path: str | os.PathLike[str], *, interval: int | None = None, min_points: int = 1,
                     **units: Any) -> RheologyData:
    """Measured moduli from an Anton Paar RheoCompass text export (a frequency sweep).

    The export is tab-separated: a metadata block (``Project:``, ``Test:``,
    ``Result:``...), then for each interval a line starting ``Interval data:``
    followed by the column names, a line of bracketed units (``[rad/s]``,
    ``[Pa]``, ``[1]``, ``[°]``), and one line per data point (first field
    empty). Numbers may use a decimal comma. Columns used, in order of
    preference: ``Angular Frequency`` [rad/s] or ``Frequency`` [Hz];
    ``Storage Modulus`` and ``Loss Modulus``; else ``Loss Factor``/``Damping
    Factor`` (tan δ) with one of them; else ``Complex Modulus`` with ``Phase
    Angle``. Units are read from the units line. Other columns (``Point No.``,
    ``Time``, ``Torque``, ``Deflection Angle``, ``Status``...) are ignored.

    Parameters
    ----------
    path : str or PathLike
    interval : int, optional
        1-based interval to read when the file holds several; required then.
    min_points : int
    **units
        Unit fields of :class:`ColumnMap`, to override what the file states
        (e.g. ``modulus_unit="ratio", geometric_factor=...`` for raw ratios).

    Returns
    -------
    RheologyData
        ``comments`` keep the metadata block and record the columns used.
    """
    source = str(path)
    lines = _read_text(Path(path)).splitlines()
    starts = [k for k, s in enumerate(lines) if s.lstrip().startswith(_RHEOCOMPASS_MARK)]
    if not starts:
        raise DataError(f"{source}: no '{_RHEOCOMPASS_MARK}' line; is this a RheoCompass text export?")
    if interval is None and len(starts) > 1:
        raise DataError(f"{source}: {len(starts)} intervals (lines {', '.join(str(k + 1) for k in starts)}); "
                        "choose one with interval=")
    pick = 1 if interval is None else int(interval)
    if not 1 <= pick <= len(starts):
        raise DataError(f"{source}: interval={interval} but the file has {len(starts)} interval(s)")
    table = _rheocompass_block(source, lines, starts, pick)
    found = {q: next((n for n in names if n in table.names), None) for q, names in RHEOCOMPASS_COLUMNS.items()}
    return _data(table, _rheocompass_map(table, found, units), min_points)


def _rheocompass_block(source: str, lines: list[str], starts: list[int], pick: int) -> _Table:
    k0 = starts[pick - 1]
    end = starts[pick] if pick < len(starts) else len(lines)
    names = [s.strip() for s in lines[k0].split("\t")]
    names[0] = names[0].replace(_RHEOCOMPASS_MARK, "").strip()
    if k0 + 1 >= end:
        raise DataError(f"{source}, line {k0 + 2}: the units line of the interval is missing")
    units = [s.strip() for s in lines[k0 + 1].split("\t")]
    rows, where = [], []
    for k in range(k0 + 2, end):
        f = lines[k].split("\t")
        if not lines[k].strip():
            continue
        if f[0].strip():  # a new metadata line (e.g. the next "Result:") ends the table
            break
        rows.append([s.strip() for s in f])
        where.append(f"line {k + 1}")
    sample = " ".join(" ".join(r) for r in rows[:5])
    decimal = "," if re.search(r"\d,\d", sample) and not re.search(r"\d\.\d", sample) else "."
    meta = tuple(s.strip().replace("\t", " ") for s in lines[:starts[0]] if s.strip())
    return _Table(source, names, rows, where, units, decimal, meta)


def _rheocompass_map(table: _Table, found: Mapping[str, str | None], units: Mapping[str, Any]) -> ColumnMap:
    if found["frequency"] is None:
        raise _error(table, "no 'Angular Frequency' or 'Frequency' column")
    f = found["frequency"]
    cols: dict[str, str | None]
    if found["storage"] and found["loss"]:
        cols = {"storage": found["storage"], "loss": found["loss"]}
    elif found["loss_tangent"] and (found["storage"] or found["loss"]):
        which = "storage" if found["storage"] else "loss"
        cols = {which: found[which], "loss_tangent": found["loss_tangent"]}
    elif found["magnitude"] and found["phase"]:
        cols = {"magnitude": found["magnitude"], "phase": found["phase"]}
    else:
        raise _error(table, "no Storage/Loss Modulus columns (nor Loss Factor with one of them, nor Complex Modulus "
                            "with Phase Angle)")
    return ColumnMap(frequency=f, **cols, **units)  # type: ignore[arg-type]

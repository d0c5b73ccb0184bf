"""Columns of a user's table: which holds what, in which unit (:class:`ColumnMap`), read into SI arrays.

The machinery under :mod:`tenscell.io.importers`, :mod:`tenscell.io.instruments`
and the ``from_dataframe`` constructors of :class:`~tenscell.io.data.RheologyData`
and :class:`~tenscell.io.creep_data.CreepData`: a table (names, an optional
units row, rows, where each row sits in its source) and a map give the values
of each quantity in SI units (Hz, Pa, rad, s, 1/Pa), every unit converted
explicitly and recorded. It builds no data object (so the data modules can use
it without an import cycle); the units and layouts it reads are described in
:mod:`tenscell.io.importers`. :class:`DataError` lives here, the one error of
every reader.
"""
from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

from .._errors import TenscellError, option
from .._ranges import RANGES, range_problem

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["DataError", "ColumnMapError", "ColumnMap", "guess_columns", "KNOWN_HEADERS", "Parsed", "parse", "parse_frame", "frame_table",
           "FREQUENCY_UNITS", "MODULUS_UNITS", "PHASE_UNITS", "PRESTRESS_UNITS", "TIME_UNITS", "COMPLIANCE_UNITS",
           "CellTable", "column_map", "trimmed", "excel_table", "read_text_file"]


class DataError(TenscellError, ValueError):
    """Invalid or unreadable rheology data.

    The message names the file (or data source), the 1-based line number in
    the file where one applies (comment and blank lines are counted), and the
    problem.
    """


class ColumnMapError(TenscellError, ValueError):
    """A :class:`ColumnMap` that cannot be (an unknown field, unit or combination of columns): the options are
    wrong, whatever the file holds."""


#: frequency units -> factor to Hz
FREQUENCY_UNITS = {"Hz": 1.0, "rad/s": 1.0 / (2.0 * math.pi)}
#: modulus units -> factor to Pa ("ratio" uses the map's geometric_factor)
MODULUS_UNITS = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "ratio": math.nan}
#: phase units -> factor to radians
PHASE_UNITS = {"deg": math.pi / 180.0, "rad": 1.0}
#: prestress units -> factor to Pa
PRESTRESS_UNITS = {"Pa": 1.0, "kPa": 1e3}
#: time units -> factor to s
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "min": 60.0}
#: creep compliance units -> factor to 1/Pa
COMPLIANCE_UNITS = {"1/Pa": 1.0, "1/kPa": 1e-3, "1/MPa": 1e-6}

# spellings found in headers and units rows -> the canonical unit
_ALIASES = {
    "hz": "Hz", "1/s": None, "rad/s": "rad/s", "rad s-1": "rad/s", "rads-1": "rad/s", "rad_per_s": "rad/s", "pa": "Pa", "kpa": "kPa",
    "mpa": "MPa", "deg": "deg", "°": "deg", "degree": "deg", "degrees": "deg", "rad": "rad", "1": "", "-": "",
    "": "", "s": "s", "sec": "s", "ms": "ms", "min": "min", "1/pa": "1/Pa", "pa^-1": "1/Pa", "pa-1": "1/Pa",
    "1/kpa": "1/kPa", "kpa^-1": "1/kPa", "kpa-1": "1/kPa", "1/mpa": "1/MPa", "mpa^-1": "1/MPa", "mpa-1": "1/MPa",
}
_CANONICAL_UNITS = ("Hz", "rad/s", "Pa", "kPa", "MPa", "deg", "rad", "s", "ms", "min", "1/Pa", "1/kPa", "1/MPa")
# "(1/Pa)" holds a bracket pair of its own only in "J(t) (1/Pa)": the unit is the last bracketed group
_BRACKETED = re.compile(r"^(.*?)\s*[\[(]\s*([^\[\]()]*?)\s*[\])]\s*$")
_SUFFIX = re.compile(r"_(Hz|rad_per_s|Pa|kPa|MPa|deg|rad|s|ms|min|per_Pa|per_kPa|per_MPa)$")


@dataclass(frozen=True)
class ColumnMap:
    """Which of your columns holds which quantity, and the unit it is in.

    Column names are matched exactly (after stripping spaces). A unit left as
    None is read from the column's header (``"G' [kPa]"``, ``"G' (kPa)"``,
    ``"G_storage_kPa"``) or the file's units row; if the file does not say
    either, reading stops with an error asking you to state it.

    A map reads moduli (``frequency`` with G', G'' or an equivalent pair) or
    creep compliance (``time`` with ``compliance``), never both.

    Parameters
    ----------
    frequency : str, optional
        Column of the oscillation frequency (moduli).
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
    time, compliance : str, optional
        Columns of the time after the stress step and of the creep
        compliance J(t) (creep data).
    compliance_sd : str, optional
        Standard deviation of J (same unit as J).
    frequency_unit : {"Hz", "rad/s"}, optional
    modulus_unit : {"Pa", "kPa", "MPa", "ratio"}, optional
    phase_unit : {"deg", "rad"}, optional
    prestress_unit : {"Pa", "kPa"}, optional
    time_unit : {"s", "ms", "min"}, optional
    compliance_unit : {"1/Pa", "1/kPa", "1/MPa"}, optional
    geometric_factor : float, optional
        Pa per unit of the measured ratio; required with ``modulus_unit="ratio"``
        and refused otherwise.

    Examples
    --------
    >>> ColumnMap(frequency="omega", frequency_unit="rad/s", storage="Gp", loss="Gpp", modulus_unit="kPa")
    ... # doctest: +SKIP
    >>> ColumnMap(time="Time", time_unit="s", compliance="Creep Compliance", compliance_unit="1/Pa")
    ... # doctest: +SKIP
    """

    frequency: str | None = None
    storage: str | None = None
    loss: str | None = None
    magnitude: str | None = None
    phase: str | None = None
    loss_tangent: str | None = None
    prestress: str | None = None
    storage_sd: str | None = None
    loss_sd: str | None = None
    time: str | None = None
    compliance: str | None = None
    compliance_sd: str | None = None
    frequency_unit: str | None = None
    modulus_unit: str | None = None
    phase_unit: str | None = None
    prestress_unit: str | None = None
    time_unit: str | None = None
    compliance_unit: str | None = None
    geometric_factor: float | None = None

    def __post_init__(self) -> None:
        for name in _QUANTITIES:
            column = getattr(self, name)
            if column is not None and (not isinstance(column, str) or not column.strip()):
                raise ColumnMapError(f"{option(name, column)}: a column is named by a non-empty string")
        for name in _UNIT_FIELDS:
            table = _units_table(name)
            unit = getattr(self, name)
            if unit is not None and unit not in table:
                raise ColumnMapError(f"{option(name, unit)} is not one of {', '.join(table)}")
        if (self.modulus_unit == "ratio") != (self.geometric_factor is not None):
            raise ColumnMapError(f"{option('geometric_factor')} (Pa per unit of the ratio) is given exactly when "
                                 f"{option('modulus_unit', 'ratio')}")
        if self.geometric_factor is not None and (
                isinstance(self.geometric_factor, bool) or not isinstance(self.geometric_factor, (int, float))
                or not (math.isfinite(self.geometric_factor) and self.geometric_factor > 0)):
            raise ColumnMapError(f"{option('geometric_factor', self.geometric_factor)}: must be a finite number > 0 "
                                 "(Pa per unit of the ratio)")
        layout = self.layout
        if (self.storage_sd or self.loss_sd) and layout != "storage+loss":
            raise ColumnMapError(f"{option('storage_sd')}, {option('loss_sd')}: standard deviations are read only "
                                 "with G' and G'' columns")

    @property
    def layout(self) -> str:
        """What the map reads: ``"storage+loss"``, ``"storage+tan"``, ``"loss+tan"``, ``"magnitude+phase"``,
        ``"magnitude+tan"`` (moduli) or ``"creep"`` (time and J(t))."""
        given = {k for k in ("storage", "loss", "magnitude", "phase", "loss_tangent") if getattr(self, k)}
        creep = {k for k in ("time", "compliance") if getattr(self, k)}
        if creep or self.compliance_sd:
            if given or self.frequency or creep != {"time", "compliance"}:
                got = sorted(given | creep | ({"frequency"} if self.frequency else set()))
                raise ColumnMapError(f"{option('columns')}: a creep map gives time and compliance (and no frequency "
                                     f"or moduli); got {', '.join(got)}")
            return "creep"
        if not self.frequency:
            raise ColumnMapError(f"{option('columns')}: give frequency (with G', G'' or an equivalent pair) or time "
                                 "with compliance")
        for layout, need in _LAYOUTS.items():
            if given == need:
                return layout
        raise ColumnMapError(f"{option('columns')}: {', '.join(sorted(given)) or 'no moduli'} is not a layout "
                             "tenscell reads; give storage and loss, storage or loss with loss_tangent, or magnitude "
                             "with phase or loss_tangent")

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
    "loss_sd": "modulus_unit", "time": "time_unit", "compliance": "compliance_unit",
    "compliance_sd": "compliance_unit",
}
_UNIT_FIELDS = ("frequency_unit", "modulus_unit", "phase_unit", "prestress_unit", "time_unit", "compliance_unit")
# quantity -> the quantity of the one ranges table (tenscell._ranges) its values must lie in (SI); the phase has
# its own range (below 90°) and tan δ none
_RANGE_OF = {"frequency": "frequency", "storage": "modulus", "loss": "modulus", "magnitude": "modulus",
             "storage_sd": "modulus", "loss_sd": "modulus", "prestress": "prestress", "time": "time",
             "compliance": "compliance", "compliance_sd": "compliance"}
_NAMES = {"frequency": "frequency", "storage": "G'", "loss": "G''", "magnitude": "|G|", "phase": "phase",
          "loss_tangent": "loss tangent", "prestress": "prestress", "storage_sd": "SD of G'", "loss_sd": "SD of G''",
          "time": "time", "compliance": "creep compliance", "compliance_sd": "SD of J"}


# ---- one table, whatever it came from -----------------------------------------------------
@dataclass(frozen=True)
class CellTable:
    """Cells as text or numbers, with where each row and column sits in the source (for messages)."""

    source: str
    names: list[str]
    rows: list[list[Any]]
    where: list[str]          # "line 12", "row 12", "index 'a'"
    units: list[str] | None = None  # a units row, if the source has one
    decimal: str = "."
    comments: tuple[str, ...] = ()


def _error(table: CellTable, problem: str, row: int | None = None, column: str | None = None) -> DataError:
    parts = [table.source] + ([table.where[row]] if row is not None else [])
    return DataError(", ".join(parts) + ": " + (f"column {column!r}: " if column else "") + problem)


def _unit_in_name(name: str) -> tuple[str, str | None]:
    """``("G'", "kPa")`` from ``"G' [kPa]"``, ``"G' (kPa)"`` or ``"G_kPa"``; unit None when the name has none.

    A bracket that is part of a quantity's name (``J(t)``, ``tan(delta)``) is not a unit.
    """
    m = _BRACKETED.match(name)
    if m and m.group(2).strip().lower() not in _NOT_UNITS:
        return m.group(1).strip(), m.group(2)
    m = _SUFFIX.search(name)
    if m and m.start() > 0:
        unit = m.group(1).replace("_per_", "/")
        return name[:m.start()], "1/" + unit[4:] if unit.startswith("per_") else unit
    return name, None


_ANGULAR = {"angular frequency", "angular_frequency", "ω", "omega"}
_NOT_UNITS = {"t", "delta", "δ", "ω", "omega", "f", "step", "cmd", "sample"}


def _canonical_unit(text: str) -> str | None:
    """A unit as written in a file, in tenscell's spelling; None when not understood."""
    t = text.strip().strip("[]()").strip()
    if t in _CANONICAL_UNITS:
        return t
    if "mPa" in t:  # millipascal: never read as MPa by a case-insensitive match
        return None
    return _ALIASES.get(t.lower().replace("·", " ").replace("**", "^").replace(" ", ""))


def _resolve(table: CellTable, cmap: ColumnMap) -> dict[str, tuple[int, str]]:
    """Quantity -> (column index, unit), checking that every column exists and every unit is known.

    Every unit the file leaves unstated is asked for in one message (not one per run).
    """
    stripped = [n.strip() for n in table.names]
    bare = [_unit_in_name(n)[0] for n in stripped]
    found: dict[str, int] = {}
    for quantity, column in cmap.columns().items():
        col = column.strip()
        if col in stripped:
            found[quantity] = stripped.index(col)
        elif bare.count(col) == 1:  # the map names "G'" and the header says "G' [kPa]"
            found[quantity] = bare.index(col)
        else:
            listed = ", ".join(repr(n) for n in stripped if n)
            raise _error(table, f"no column {col!r} for {_NAMES[quantity]} ({option(quantity, col)}); "
                                + (f"the columns are {listed}" if listed else "the header names no columns"))
    out: dict[str, tuple[int, str]] = {}
    unstated = []
    for quantity, j in found.items():
        unit = _unit_of(table, cmap, quantity, j)
        if unit is None:
            unstated.append(quantity)
        else:
            out[quantity] = (j, unit)
    if unstated:
        fields_ = list(dict.fromkeys(_QUANTITIES[q] for q in unstated))
        named = " and ".join(f"{_NAMES[q]} ({table.names[found[q]].strip()!r})" for q in unstated)
        asks = " and ".join(f"{option(f)} (one of {', '.join(_units_table(f))})" for f in fields_)
        raise _error(table, f"no unit is stated for {named}, neither in its header nor in a units row; give {asks}")
    return out


def _unit_of(table: CellTable, cmap: ColumnMap, quantity: str, j: int) -> str | None:
    """The unit of column ``j`` holding ``quantity``: stated by the map, else written in the file; None when
    neither says it (the caller asks for every such unit at once)."""
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
        raise _error(table, f"unit {written!r} of {_NAMES[quantity]} is not one tenscell converts; state it with "
                            f"{option(field)} (one of {', '.join(_units_table(field))})", column=column)
    if stated is not None:
        if in_file not in (None, "") and in_file != stated and stated != "ratio":
            raise _error(table, f"the file says {written!r} but {option(field, stated)} was given", column=column)
        return stated
    if in_file in (None, "") and quantity == "frequency" and _unit_in_name(column)[0].lower() in _ANGULAR:
        return "rad/s"  # an angular frequency is in rad/s by definition, not by assumption
    if in_file in (None, ""):
        return None
    if in_file not in _units_table(field):
        raise _error(table, f"unit {written!r} does not fit {_NAMES[quantity]} (expected one of "
                            f"{', '.join(_units_table(field))})", column=column)
    return in_file


def _units_table(field: str) -> dict[str, float]:
    return {"frequency_unit": FREQUENCY_UNITS, "modulus_unit": MODULUS_UNITS, "phase_unit": PHASE_UNITS,
            "prestress_unit": PRESTRESS_UNITS, "time_unit": TIME_UNITS, "compliance_unit": COMPLIANCE_UNITS}[field]


def _number(table: CellTable, value: Any, i: int, column: str) -> float:
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


def _columns(table: CellTable, cmap: ColumnMap, resolved: Mapping[str, tuple[int, str]]) -> dict[str, np.ndarray]:
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
    _check_ranges(table, cmap, resolved, out)
    return out


def _check_ranges(table: CellTable, cmap: ColumnMap, resolved: Mapping[str, tuple[int, str]],
                  si: Mapping[str, np.ndarray]) -> None:
    """Every value in the range of its quantity (:data:`tenscell._ranges.RANGES`), else DataError naming the
    first offending row, the user's header and the value and range in the user's unit."""
    first = None
    for quantity, (j, unit) in resolved.items():
        if quantity not in _RANGE_OF:
            continue
        lo, hi, _ = RANGES[_RANGE_OF[quantity]]
        bad = np.flatnonzero((si[quantity] < lo) | (si[quantity] > hi))
        if bad.size and (first is None or bad[0] < first[0]):
            first = (int(bad[0]), quantity, j, unit)
    if first is None:
        return
    i, quantity, j, unit = first
    factor = _factor(quantity, unit, cmap)
    if unit == "ratio":
        problem = (f"ratio {si[quantity][i] / factor:g} × geometric_factor {factor:g} Pa = "
                   f"{range_problem('modulus', si[quantity][i])}")
    else:
        # a data file's prestress is in Pa (the table's N for the flag): the same numbers
        problem = str(range_problem(_RANGE_OF[quantity], si[quantity][i], unit or None, factor))
    raise _error(table, problem, i, table.names[j].strip())


def _check_formed(table: CellTable, cmap: ColumnMap, resolved: Mapping[str, tuple[int, str]],
                  v: Mapping[str, np.ndarray]) -> None:
    """G' and G'' formed from another pair of columns (|G| with the phase, one modulus with tan δ) inside the
    modulus range, else DataError naming the row, the columns they came from, and the user's modulus unit."""
    given = [q for q in ("storage", "loss", "magnitude", "phase", "loss_tangent") if q in resolved]
    unit = next(resolved[q][1] for q in given if q in ("storage", "loss", "magnitude"))
    factor = _factor("storage", unit, cmap)
    lo, hi, _ = RANGES["modulus"]
    for quantity in ("storage", "loss"):
        bad = np.flatnonzero((v[quantity] < lo) | (v[quantity] > hi))
        if bad.size:
            i = int(bad[0])
            cols = " and ".join(repr(table.names[resolved[q][0]].strip()) for q in given)
            shown = "Pa" if unit == "ratio" else unit
            raise _error(table, f"{_NAMES[quantity]} formed from columns {cols}: " + str(range_problem(
                "modulus", v[quantity][i], shown, 1.0 if unit == "ratio" else factor)), i)


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


@dataclass(frozen=True, eq=False)
class Parsed:
    """What a table holds under a map: ``layout`` (:attr:`ColumnMap.layout`), each quantity's values in SI
    units (``values``: frequency Hz, storage/loss Pa, prestress Pa, time s, compliance 1/Pa...; G', G'' already
    formed from the layout's columns), the comments recording the columns and units used, and where each row
    sits in its source (``where``: for the range checks' messages)."""

    layout: str
    values: dict
    source: str
    comments: tuple
    where: tuple = ()  # each value row's place in its source ("line 12", "row 3", "index 'a'"), for range errors
    columns: tuple = ()  # (quantity, the header as in the source, the unit it was read in), for the provenance
    notes: tuple = ()  # what was done while reading (points dropped), for the provenance


def parse(table: CellTable, cmap: ColumnMap, min_points: int) -> Parsed:
    """The values a table holds under a map, checked row by row (:class:`DataError` naming the line and column)."""
    resolved = _resolve(table, cmap)
    notes: tuple[str, ...] = ()
    if cmap.layout == "creep":
        table, notes = _without_onset(table, resolved["time"][0])
    if not table.rows:
        raise _error(table, "no data rows")
    if len(table.rows) < min_points:
        raise _error(table, f"{len(table.rows)} data points, fewer than {option('min_points', min_points)}")
    v = _columns(table, cmap, resolved)
    how = "; ".join(f"{_NAMES[q]} = {table.names[j].strip()!r}" + (f" [{u}]" if u else "")
                    for q, (j, u) in resolved.items())
    if cmap.geometric_factor is not None:
        how += f"; moduli = {cmap.geometric_factor:g} Pa × ratio"
    if cmap.layout != "creep":
        v["storage"], v["loss"] = _moduli(v, cmap.layout)
        if cmap.layout != "storage+loss":
            _check_formed(table, cmap, resolved, v)
    used = tuple((q, table.names[j].strip(), u) for q, (j, u) in resolved.items())
    return Parsed(cmap.layout, v, table.source, (*table.comments, *notes, f"imported by tenscell: {how}"),
                  tuple(table.where), used, notes)


def frame_table(df: pd.DataFrame, source: str) -> CellTable:
    """A DataFrame as a table (rows named by their index labels in messages)."""
    names = [str(c) for c in df.columns]
    return CellTable(source, names, df.to_numpy(dtype=object).tolist(), [f"index {label!r}" for label in df.index])


def parse_frame(df: pd.DataFrame, columns: ColumnMap | Mapping[str, Any] | None, source: str, min_points: int,
                units: Mapping[str, Any]) -> Parsed:
    """:func:`parse` of a DataFrame; ``columns`` None: recognised from the column names (:func:`guess_columns`)."""
    table = frame_table(df, source)
    return parse(table, column_map(columns if columns is not None else guess_columns(table.names), units), min_points)


def _without_onset(table: CellTable, j: int) -> tuple[CellTable, tuple[str, ...]]:
    """The rows after the stress step: a point at t = 0 (the step's onset, where J is 0 or undefined) is
    dropped, and the drop recorded; any other t <= 0 is an error later, with its line."""
    keep = [i for i, row in enumerate(table.rows)
            if not (j < len(row) and _number(table, row[j], i, table.names[j].strip()) == 0.0)]
    dropped = len(table.rows) - len(keep)
    if not dropped:
        return table, ()
    kept = set(keep)
    lines = ", ".join(table.where[i] for i in range(len(table.rows)) if i not in kept)
    note = f"dropped {dropped} point(s) at t = 0 (the onset of the stress step): {lines}"
    return replace(table, rows=[table.rows[i] for i in keep], where=[table.where[i] for i in keep]), (note,)


def column_map(columns: ColumnMap | Mapping[str, Any] | None, units: Mapping[str, Any]) -> ColumnMap:
    """The :class:`ColumnMap` of ``columns`` (a map, a dict of its fields, or None: tenscell's own headers) with the
    unit fields ``units`` (ValueError naming an unknown field)."""
    if columns is None:
        columns = {"frequency": "frequency_Hz", "storage": "G_storage_Pa", "loss": "G_loss_Pa"}
    known = {f.name for f in fields(ColumnMap)}
    given = {} if isinstance(columns, ColumnMap) else dict(columns)
    unknown = [k for k in (*given, *units) if k not in known]
    if unknown:
        raise ColumnMapError(f"{option('columns')}: {unknown[0]!r} is not a field of a column map; the fields are "
                             f"{', '.join(f.name for f in fields(ColumnMap))}")
    cmap = columns if isinstance(columns, ColumnMap) else ColumnMap(**given)
    return replace(cmap, **units) if units else cmap


# ---- headers that say what they hold ----------------------------------------------------------
#: header names (lower case, units removed) recognised without a map, quantity -> names in order of preference;
#: the spellings of tenscell's own files, TA TRIOS, Anton Paar RheoCompass (long and short) and common lab tables
KNOWN_HEADERS: dict[str, tuple[str, ...]] = {
    "frequency": ("angular frequency", "angular_frequency", "ω", "omega", "frequency", "freq", "f",
                  "frequency_hz"),
    "storage": ("storage modulus", "storage_modulus", "g'", "g′", "g_storage", "g_storage_pa", "gp",
                "g_prime", "gprime"),
    "loss": ("loss modulus", "loss_modulus", "g''", "g″", 'g"', "g_loss", "g_loss_pa", "gpp", "g_double_prime",
             "gdoubleprime"),
    "loss_tangent": ("tan(delta)", "tan(δ)", "tan δ", "tan delta", "tan_delta", "loss factor", "damping factor"),
    "magnitude": ("complex modulus", "|g*|", "g*", "|g|", "g_abs", "g_abs_pa"),
    "phase": ("phase angle", "δ", "phase", "phase_deg"),
    "time": ("step time", "time", "t", "time_s"),
    "compliance": ("creep compliance", "creep_compliance", "compliance", "j(t)", "j", "creep_compliance_per_pa"),
    "prestress": ("prestress", "prestress_pa"),
}


def guess_columns(names: Sequence[str]) -> ColumnMap | None:
    """A :class:`ColumnMap` from header names alone (:data:`KNOWN_HEADERS`), or None.

    Moduli when a frequency column and a pair the map reads are present
    (G' and G'', else G' or G'' with tan δ, else |G*| with the phase);
    creep when there is no frequency column and a time and a compliance
    column are. Units are not guessed: they come from the headers or a
    units row as for any map.
    """
    bare = [_unit_in_name(str(n).strip())[0].strip().lower() for n in names]
    stripped = [str(n).strip() for n in names]

    def find(quantity: str) -> str | None:
        for alias in KNOWN_HEADERS[quantity]:
            hits = [k for k, b in enumerate(bare) if b == alias]
            if hits:
                return stripped[hits[0]]
        return None

    found = {q: find(q) for q in KNOWN_HEADERS}
    extra: dict[str, Any] = {"prestress": found["prestress"]} if found["prestress"] else {}
    if found["frequency"]:
        for pair in (("storage", "loss"), ("storage", "loss_tangent"), ("loss", "loss_tangent"),
                     ("magnitude", "phase"), ("magnitude", "loss_tangent")):
            if all(found[q] for q in pair):
                named: dict[str, Any] = {q: found[q] for q in pair}
                return ColumnMap(frequency=found["frequency"], **named, **extra)
        return None
    if found["time"] and found["compliance"]:
        return ColumnMap(time=found["time"], compliance=found["compliance"], **extra)
    return None


def read_text_file(path, *, newline: str | None = "") -> str:
    """A data file's text: UTF-8 (a byte-order mark dropped), UTF-16 with its byte-order mark (Excel's "Unicode
    text"), else Windows-1252 (spreadsheets in Western locales) when the bytes hold no NUL (binary files do).
    ``newline`` as for :func:`open` ("" keeps line ends for ``splitlines``, None turns them into "\n").

    Raises DataError naming the file and the operating system's reason (``No such file or directory``).
    """
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as exc:
        raise DataError(f"{path}: cannot read the file: {exc.strerror or type(exc).__name__}") from None
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        encodings: tuple[str, ...] = ("utf-16",)
    elif b"\x00" in raw:  # valid UTF-8 may hold a NUL; a single-byte encoding would read any binary file
        encodings = ("utf-8-sig",)
    else:
        encodings = ("utf-8-sig", "cp1252", "latin-1")
    for encoding in encodings:
        try:
            text = raw.decode(encoding)
        except UnicodeDecodeError:
            continue
        return text if newline == "" else text.replace("\r\n", "\n").replace("\r", "\n")
    raise DataError(f"{path}: not a text file (binary bytes); tenscell reads text exports (CSV, TSV, TRIOS and "
                    "RheoCompass text) and Excel workbooks (.xlsx)")


def _read_text(path: Path) -> str:
    return read_text_file(path)


def _text_table(path: Path, sep: str | None, header_line: int | None, units_line: bool, decimal: str) -> CellTable:
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
        # instruments end rows with a separator (trailing empty fields); only values beyond the header count
        if len(trimmed(fields_)) > len(names) or len(fields_) < len(trimmed(names)):
            raise DataError(f"{source}, line {k}: expected {len(trimmed(names))} fields, found "
                            f"{len(trimmed(fields_))}")
    return CellTable(source, names, [f for _, f in data], [f"line {k}" for k, _ in data], units, decimal, comments)


def trimmed(fields_: Sequence[Any]) -> list[Any]:
    """``fields_`` without trailing empty fields."""
    out = list(fields_)
    while out and (out[-1] is None or not str(out[-1]).strip()):
        out.pop()
    return out


def excel_table(path: Path, sheet: str | int | None, header_row: int | None, units_row: bool) -> CellTable:
    try:
        import openpyxl
    except ImportError:  # pragma: no cover - depends on the installation
        raise DataError(f"{path}: reading Excel files needs openpyxl (pip install 'tenscell[excel]')") from None
    try:
        book = openpyxl.load_workbook(path, read_only=True, data_only=True)
    except Exception as exc:  # openpyxl raises many types for a bad file
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else "not an Excel workbook (.xlsx)"
        raise DataError(f"{path}: cannot read the workbook: {reason}") from None
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
    return CellTable(source, names, [r for _, r in data], [f"row {k}" for k, _ in data], units)

"""Reading and writing measured cell rheology data (storage and loss moduli).

Files are plain CSV. Lines whose first non-blank character is ``#`` are
comments (kept, e.g. for the source citation) and blank lines are ignored.
The first other line is the header. Column names are matched
case-insensitively, ignoring surrounding whitespace, in any order.

Supported layouts
-----------------
1. Frequency sweep: ``frequency_Hz, G_storage_Pa, G_loss_Pa``.
2. Prestress sweep: ``prestress_Pa, frequency_Hz, G_storage_Pa, G_loss_Pa``.
3. Magnitude and phase: ``frequency_Hz, G_abs_Pa, phase_deg``, converted to
   ``G' = |G| cos(phase)`` and ``G'' = |G| sin(phase)``. A ``prestress_Pa``
   column is accepted here too, giving a prestress sweep.

Optional standard deviations (used as fit weights): ``G_storage_sd_Pa`` and
``G_loss_sd_Pa`` (layouts 1 and 2), or ``G_abs_sd_Pa`` and ``phase_sd_deg``
together (layout 3; propagated to G' and G'' to first order).

Any other column is an error, so that a misspelt name is not silently ignored.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from .._errors import option
from .._ranges import RANGES, range_problem
from .columns import DataError, parse_frame, read_text_file
from .outputs import atomic_path
from .provenance import Provenance

__all__ = [
    "DataError",
    "RheologyData",
    "read_csv",
    "parse_text",
    "write_csv",
    "bundled",
    "bundled_names",
    "generated_note",
]

# Canonical spellings, used for writing and in messages; matching is on the
# lower-cased form.
_FREQUENCY = "frequency_Hz"
_PRESTRESS = "prestress_Pa"
_STORAGE = "G_storage_Pa"
_LOSS = "G_loss_Pa"
_STORAGE_SD = "G_storage_sd_Pa"
_LOSS_SD = "G_loss_sd_Pa"
_ABS = "G_abs_Pa"
_PHASE = "phase_deg"
_ABS_SD = "G_abs_sd_Pa"
_PHASE_SD = "phase_sd_deg"

_CARTESIAN_COLUMNS = (_STORAGE, _LOSS, _STORAGE_SD, _LOSS_SD)
_POLAR_COLUMNS = (_ABS, _PHASE, _ABS_SD, _PHASE_SD)
_ALL_COLUMNS = (_PRESTRESS, _FREQUENCY) + _CARTESIAN_COLUMNS + _POLAR_COLUMNS
_CANONICAL = {name.lower(): name for name in _ALL_COLUMNS}

# Column -> quantity of the one ranges table (tenscell._ranges) its values must lie in; the phase has
# its own range, [0, 90] deg, checked with the row.
_COLUMN_QUANTITY = {
    _FREQUENCY: "frequency", _PRESTRESS: "prestress", _STORAGE: "modulus", _LOSS: "modulus",
    _STORAGE_SD: "modulus", _LOSS_SD: "modulus", _ABS: "modulus", _ABS_SD: "modulus",
}
# column -> the quantity of a column map (tenscell.io.columns) it holds, and its unit, for the provenance
_QUANTITY_OF = {_FREQUENCY: "frequency", _PRESTRESS: "prestress", _STORAGE: "storage", _LOSS: "loss",
                _STORAGE_SD: "storage_sd", _LOSS_SD: "loss_sd", _ABS: "magnitude", _PHASE: "phase",
                _ABS_SD: "magnitude_sd", _PHASE_SD: "phase_sd"}
_UNIT_OF = {_FREQUENCY: "Hz", _PRESTRESS: "Pa", _STORAGE: "Pa", _LOSS: "Pa", _STORAGE_SD: "Pa", _LOSS_SD: "Pa",
            _ABS: "Pa", _PHASE: "deg", _ABS_SD: "Pa", _PHASE_SD: "deg"}
# RheologyData field -> its column in the package's layout
_FIELD_COLUMN = {"frequency_hz": _FREQUENCY, "prestress": _PRESTRESS, "G_storage": _STORAGE, "G_loss": _LOSS,
                 "G_storage_sd": _STORAGE_SD, "G_loss_sd": _LOSS_SD}

# Short name -> file in the package's data directory. A tuple, not a dict,
# so that no caller can alter the registry.
_BUNDLED = (
    ("fabry2001", "fabry2001_hasm_powerlaw.csv"),
    ("stamenovic2002", "stamenovic2002_hasm_0p1Hz.csv"),
)


def _error(source: str, problem: str, line: int | None = None) -> DataError:
    where = f"{source}, line {line}" if line is not None else f"{source}"
    return DataError(f"{where}: {problem}")


def _locations(source: str, locations, n: int) -> tuple[str, ...] | None:
    """``locations`` checked: None, or one str per point."""
    if locations is None:
        return None
    if isinstance(locations, str) or len(locations) != n or not all(isinstance(x, str) for x in locations):
        raise _error(source, f"locations must be one str per point ({n}), got {locations!r:.80}")
    return tuple(locations)


def check_ranges(source: str, columns: dict, locations: tuple[str, ...] | None) -> None:
    """Every value within the range of its quantity (:data:`tenscell._ranges.RANGES`), else DataError.

    ``columns``: column name -> (values, quantity, unit or None for the table's). The message names
    ``source``, the location of the first offending point (its index without ``locations``), the
    column, the value in its unit and the range: one line.
    """
    first = None
    for column, (values, quantity, unit) in columns.items():
        lo, hi, _ = RANGES[quantity]
        for i in np.flatnonzero((values < lo) | (values > hi))[:1]:
            if first is None or i < first[0]:
                first = (int(i), column, quantity, unit, float(values[i]))
    if first is not None:
        i, column, quantity, unit, value = first
        where = f"{source}, {locations[i]}" if locations is not None else f"{source}: point {i}"
        raise DataError(f"{where}: column {column!r}: {range_problem(quantity, value, unit)}")


@dataclass(frozen=True, eq=False, repr=False)
class RheologyData:
    """Measured complex shear modulus of cells, as storage and loss moduli.

    Array fields are stored as read-only float64 copies. ``eq=False``
    because element-wise array comparison has no single truth value; compare
    the arrays themselves.

    Parameters
    ----------
    frequency_hz : array_like, shape (n,)
        Oscillation frequency f in Hz (not angular frequency); > 0.
    G_storage : array_like, shape (n,)
        Storage modulus G' in Pa; > 0.
    G_loss : array_like, shape (n,)
        Loss modulus G'' in Pa; > 0.
    prestress : array_like, shape (n,), optional
        Cytoskeletal prestress in Pa (> 0) for a prestress sweep; None for a
        frequency sweep.
    G_storage_sd, G_loss_sd : array_like, shape (n,), optional
        Standard deviations of G' and G'' in Pa (> 0), or None if unknown.
    source : str, optional
        File path or name the data came from; used in error messages.
    comments : tuple of str, optional
        Comment lines of the file, without the leading ``#``, stripped.
        Must not contain line breaks.
    kind : {"frequency", "prestress", None}, optional
        ``"prestress"`` when `prestress` is given, else ``"frequency"``.
        Derived when None; an inconsistent value is an error.
    locations : tuple of str, optional
        Where each point is in `source`, in the order given (e.g. ``"line 12"``
        of a file, ``"row 7"`` of a sheet): readers pass it so that an error
        names the line; reordered with the points.
    provenance : Provenance, optional
        What the data were read from and how (:class:`tenscell.io.provenance.Provenance`:
        file, layout, step, temperature, columns and unit conversions, notes); readers
        set it. Default: the source alone.
    counts : array_like, shape (n,), optional
        How many measured points each point stands for (binned data, see
        :mod:`tenscell.io.thinning`); None: one each. Without standard
        deviations a point weighs √count in a fit (the SDs of binned data
        already carry their counts).

    Every value must lie in the range tenscell accepts for its quantity (the
    table :data:`tenscell._ranges.RANGES` that the command-line flags use):
    frequency 1e-12..1e12 Hz, moduli, their SDs and prestress 1e-30..1e30 Pa.

    The points are stored in a canonical order (by prestress, then frequency),
    whatever order they were given in, so that results depend on the data set
    and not on the order of its rows.

    Raises
    ------
    DataError
        If arrays are not 1-D of equal non-zero length, contain NaN or inf,
        or have non-positive frequencies, prestresses, moduli or SDs, or a
        value outside its range (naming the column and the location).
    """

    frequency_hz: np.ndarray
    G_storage: np.ndarray
    G_loss: np.ndarray
    prestress: np.ndarray | None = None
    G_storage_sd: np.ndarray | None = None
    G_loss_sd: np.ndarray | None = None
    source: str = "<memory>"
    comments: tuple[str, ...] = ()
    kind: str | None = None
    locations: tuple[str, ...] | None = None
    provenance: Provenance | None = None
    counts: np.ndarray | None = None

    def __post_init__(self) -> None:
        source = str(self.source)
        # object.__setattr__ because the dataclass is frozen; normalising
        # here means every instance, however built, satisfies the invariants.
        object.__setattr__(self, "source", source)

        def as_array(name: str, value, *, optional: bool) -> np.ndarray | None:
            if value is None:
                if optional:
                    return None
                raise _error(source, f"{name} is required")
            try:
                arr = np.array(value, dtype=np.float64)
            except (TypeError, ValueError) as exc:
                raise _error(source, f"{name} is not numeric: {exc}") from exc
            if arr.ndim != 1:
                raise _error(source, f"{name} must be 1-D, got shape {arr.shape}")
            if not np.all(np.isfinite(arr)):
                bad = int(np.flatnonzero(~np.isfinite(arr))[0])
                raise _error(source, f"{name}[{bad}] = {arr[bad]} is not finite")
            if np.any(arr <= 0):
                bad = int(np.flatnonzero(arr <= 0)[0])
                raise _error(source, f"{name}[{bad}] = {arr[bad]} must be > 0")
            arr.flags.writeable = False
            return arr

        arrays = {
            "frequency_hz": as_array("frequency_hz", self.frequency_hz, optional=False),
            "G_storage": as_array("G_storage", self.G_storage, optional=False),
            "G_loss": as_array("G_loss", self.G_loss, optional=False),
            "prestress": as_array("prestress", self.prestress, optional=True),
            "G_storage_sd": as_array("G_storage_sd", self.G_storage_sd, optional=True),
            "G_loss_sd": as_array("G_loss_sd", self.G_loss_sd, optional=True),
            "counts": as_array("counts", self.counts, optional=True),
        }
        lengths = {k: len(v) for k, v in arrays.items() if v is not None}
        if len(set(lengths.values())) != 1:
            raise _error(source, f"arrays have different lengths: {lengths}")
        if lengths["frequency_hz"] == 0:
            raise _error(source, "no data points")
        locations = _locations(source, self.locations, lengths["frequency_hz"])
        check_ranges(source, {col: (a, _COLUMN_QUANTITY[col], "Pa" if col == _PRESTRESS else None)
                              for k, a in arrays.items() if a is not None and k in _FIELD_COLUMN
                              for col in (_FIELD_COLUMN[k],)}, locations)
        # canonical row order (prestress, then frequency, then the values): the same data set gives
        # the same object, and the same fit, whatever the order of the rows in its file
        keys = [a for k in ("G_loss_sd", "G_storage_sd", "G_loss", "G_storage", "frequency_hz", "prestress")
                if (a := arrays[k]) is not None]
        order = np.lexsort(keys)
        if np.any(order != np.arange(order.size)):
            for name, arr in arrays.items():
                if arr is not None:
                    arr = arr[order]
                    arr.flags.writeable = False
                    arrays[name] = arr
            locations = None if locations is None else tuple(locations[i] for i in order)
        for name, arr in arrays.items():
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "locations", locations)
        object.__setattr__(self, "provenance", _provenance(self.provenance, source, lengths["frequency_hz"]))

        if isinstance(self.comments, str):
            raise _error(source, "comments must be a sequence of strings, not a str")
        comments = tuple(self.comments)
        for c in comments:
            if not isinstance(c, str):
                raise _error(source, f"comment {c!r} is not a str")
            # A line break would turn the rest of the comment into a data
            # line when written by write_csv.
            if "\n" in c or "\r" in c:
                raise _error(source, f"comment {c!r} contains a line break")
        object.__setattr__(self, "comments", comments)

        expected_kind = "frequency" if arrays["prestress"] is None else "prestress"
        if self.kind is None:
            object.__setattr__(self, "kind", expected_kind)
        elif self.kind != expected_kind:
            raise _error(
                source,
                f"kind={self.kind!r} is inconsistent with prestress "
                f"{'absent' if arrays['prestress'] is None else 'present'} "
                f"(expected {expected_kind!r})",
            )

    @property
    def n(self) -> int:
        """Number of data points."""
        return int(self.frequency_hz.shape[0])

    def binned(self, max_points: int | None = None, weighting: str = "counts") -> "RheologyData":
        """At most ``max_points`` points by log-frequency binning (see :mod:`tenscell.io.thinning`; without SDs a
        bin weighs √(its points), or as one point with ``weighting="bins"``).

        Returns ``self`` when it has no more points than that; the binned data's
        provenance and comments state the rule and the counts.
        """
        from .thinning import DEFAULT_MAX_POINTS, bin_log_frequency

        return bin_log_frequency(self, DEFAULT_MAX_POINTS if max_points is None else max_points, weighting)

    def with_prestress(self, prestress_pa: float) -> "RheologyData":
        """A copy that states the prestress (Pa) at which the data were measured (a constant ``prestress`` column).

        A frequency sweep that states its prestress can be fitted jointly
        with prestress sweeps on one prestress scale
        (:func:`tenscell.fitting.fit`). Raises DataError if the data already
        state prestresses, or for a non-positive value.
        """
        p = _stated_prestress(self, prestress_pa)
        assert self.provenance is not None  # set by __post_init__
        return RheologyData(frequency_hz=self.frequency_hz, G_storage=self.G_storage, G_loss=self.G_loss,
                            prestress=np.full(self.n, p), G_storage_sd=self.G_storage_sd,
                            G_loss_sd=self.G_loss_sd, source=self.source, comments=self.comments,
                            locations=self.locations, provenance=self.provenance.noted(f"prestress stated: {p:g} Pa"),
                            counts=self.counts)

    @property
    def has_sd(self) -> bool:
        """True when both G' and G'' carry standard deviations (the fit's residuals are then in their units)."""
        return self.G_storage_sd is not None and self.G_loss_sd is not None

    @property
    def weights_storage(self) -> np.ndarray:
        """Weights for residuals of log10 G', shape (n,).

        ``G' ln(10) / sd(G')``, the inverse of the first-order SD of log10 G',
        if `G_storage_sd` is given; otherwise √counts (ones when each point is one measurement).
        """
        return _log_weights(self.G_storage, self.G_storage_sd, self.n, self.counts)

    @property
    def weights_loss(self) -> np.ndarray:
        """Weights for residuals of log10 G'', shape (n,).

        ``G'' ln(10) / sd(G'')``, the inverse of the first-order SD of
        log10 G'', if `G_loss_sd` is given; otherwise √counts (ones when each point is one measurement).
        """
        return _log_weights(self.G_loss, self.G_loss_sd, self.n, self.counts)

    # ---- notebook conventions (tenscell._results) and DataFrames in --------------
    @classmethod
    def from_dataframe(cls, df, columns=None, *, source: str = "<DataFrame>", min_points: int = 1, accept=(),
                       **units) -> RheologyData:
        """Measured moduli from a pandas DataFrame with your own column names and units.

        See :func:`tenscell.io.importers.from_dataframe` (``columns`` is a
        :class:`~tenscell.io.importers.ColumnMap` or a dict of its fields;
        default recognised from the column names). A map that reads creep
        compliance is refused here: use ``CreepData.from_dataframe``.
        """
        parsed = parse_frame(df, columns, source, min_points, units)
        if parsed.layout == "creep":
            raise DataError(f"{source}: the columns hold creep compliance, not moduli; use "
                            "tenscell.io.CreepData.from_dataframe")
        return cls.from_parsed(parsed, Provenance(file=source, layout="DataFrame"), accept)

    @classmethod
    def from_parsed(cls, parsed, provenance: Provenance, accept=(), what: str | None = None) -> "RheologyData":
        """The moduli a parsed table holds (:class:`tenscell.io.columns.Parsed`), with the provenance as the
        reader knows it (completed with the columns read), through the checks of :mod:`tenscell.io.checks`."""
        v = parsed.values
        data = cls(frequency_hz=v["frequency"], G_storage=v["storage"], G_loss=v["loss"], prestress=v.get("prestress"),
                   G_storage_sd=v.get("storage_sd"), G_loss_sd=v.get("loss_sd"), source=parsed.source,
                   comments=parsed.comments, locations=parsed.where or None, provenance=provenance.read(parsed))
        headers = {q: h for q, h, _ in parsed.columns if q in ("storage", "loss")}
        return checked(data, accept, headers, what)

    def __repr__(self) -> str:
        from .._results import format_repr, span

        sweep = (f"prestress sweep, P {span(self.prestress, 'Pa')}" if self.prestress is not None
                 else "frequency sweep")
        sd = "with" if self.G_storage_sd is not None else "without"
        return format_repr(
            f"RheologyData: {self.n} points, {sweep}",
            f"f {span(self.frequency_hz, 'Hz')}; G' {span(self.G_storage, 'Pa')}; G'' {span(self.G_loss, 'Pa')}",
            f"{sd} standard deviations; source {self.source}",
        )

    def to_dataframe(self):
        """``[prestress_Pa,] frequency_Hz, G_storage_Pa, G_loss_Pa[, G_storage_sd_Pa, G_loss_sd_Pa]``."""
        from .._results import dataframe

        cols = {} if self.prestress is None else {_PRESTRESS: self.prestress}
        cols.update({_FREQUENCY: self.frequency_hz, _STORAGE: self.G_storage, _LOSS: self.G_loss})
        if self.G_storage_sd is not None:
            cols[_STORAGE_SD] = self.G_storage_sd
        if self.G_loss_sd is not None:
            cols[_LOSS_SD] = self.G_loss_sd
        return dataframe(cols, {"source": self.source, "comments": self.comments})

    def plot(self, ax=None, **kw):
        """G' (filled) and G'' (open circles) against f (log-log) or prestress (:func:`tenscell.plotting.measured`)."""
        from .._results import plotter

        measured = plotter("measured")

        return measured(self, ax=ax, **kw)


def _stated_prestress(data, prestress_pa) -> float:
    """The prestress (Pa) a data set is said to be measured at, checked (DataError naming the source)."""
    if data.prestress is not None:
        raise _error(data.source, "the data already state their prestress (a prestress column)")
    try:
        p = float(prestress_pa)
    except (TypeError, ValueError):
        raise _error(data.source, f"prestress {prestress_pa!r} is not a number (Pa)") from None
    if not (math.isfinite(p) and p > 0):
        raise _error(data.source, f"prestress {prestress_pa!r} Pa must be a finite number > 0")
    problem = range_problem("prestress", p, "Pa")  # the range of a prestress_Pa column
    if problem is not None:
        raise _error(data.source, f"stated prestress: {problem}")
    return p


def _log_weights(G: np.ndarray, sd: np.ndarray | None, n: int, counts: np.ndarray | None = None) -> np.ndarray:
    # sd(log10 G) ~= sd(G) / (G ln 10) to first order; a point that stands for m measurements without a stated SD
    # weighs sqrt(m) (the SD of a mean of m points of equal, unknown noise)
    if sd is None:
        return np.ones(n) if counts is None else np.sqrt(counts)
    return G * math.log(10.0) / sd


def _provenance(given, source: str, n: int) -> Provenance:
    """The data's provenance: as given (a Provenance), or the source alone."""
    if given is None:
        return Provenance(file=source, points=n)
    if not isinstance(given, Provenance):
        raise _error(source, f"provenance must be a tenscell.io.provenance.Provenance, got {type(given).__name__}")
    return given


def _parse_float(text: str) -> float | None:
    # float() also accepts digit separators like "1_000"; in a data file that
    # is more likely a typo than intent.
    if "_" in text:
        return None
    try:
        return float(text)
    except ValueError:
        return None


def _looks_numeric(names: list[str]) -> bool:
    return bool(names) and all(_parse_float(s.strip()) is not None for s in names)


def _parse_header(raw: list[str], source: str, line: int) -> list[str]:
    """Return the canonical column names of a header row, checking the layout."""
    names = [s.strip() for s in raw]
    lowered = [s.lower() for s in names]

    unknown = [s for s, lo in zip(names, lowered) if lo not in _CANONICAL]
    if unknown:
        hint = " (is the header line missing?)" if _looks_numeric(names) else ""
        raise _error(
            source,
            f"unknown column(s) {', '.join(repr(s) for s in unknown)}{hint}; "
            f"recognised columns are {', '.join(_ALL_COLUMNS)}",
            line,
        )
    canonical = [_CANONICAL[lo] for lo in lowered]
    duplicates = sorted({c for c in canonical if canonical.count(c) > 1})
    if duplicates:
        raise _error(source, f"duplicate column(s) {', '.join(duplicates)}", line)

    present = set(canonical)
    cartesian = [c for c in _CARTESIAN_COLUMNS if c in present]
    polar = [c for c in _POLAR_COLUMNS if c in present]
    if cartesian and polar:
        raise _error(
            source,
            f"header mixes G'/G'' columns ({', '.join(cartesian)}) with "
            f"|G|/phase columns ({', '.join(polar)}); use one layout",
            line,
        )
    if polar:
        required = (_FREQUENCY, _ABS, _PHASE)
    else:
        required = (_FREQUENCY, _STORAGE, _LOSS)
    missing = [c for c in required if c not in present]
    if missing:
        raise _error(
            source,
            f"missing required column(s) {', '.join(missing)}; "
            f"columns found: {', '.join(names)}",
            line,
        )
    if polar and (_ABS_SD in present) != (_PHASE_SD in present):
        have, lack = (_ABS_SD, _PHASE_SD) if _ABS_SD in present else (_PHASE_SD, _ABS_SD)
        raise _error(
            source,
            f"column {have} needs {lack} as well: both are needed to propagate "
            f"the uncertainty to G' and G''",
            line,
        )
    return canonical


def _csv_lines(text: str, source: str, comments: list[str]):
    """Yield ``(line number, fields)`` of every non-blank, non-comment line; comments go to ``comments``.

    The separator is the header's (the first such line): a comma, else a semicolon or a tab (as spreadsheets
    write CSV in locales with a decimal comma); with a semicolon or a tab a decimal comma in the values is read
    as a decimal point.
    """
    # Split on "\n" only (the file was opened in universal-newline mode), so
    # that line numbers agree with what an editor shows; str.splitlines()
    # would also break on form feeds and other rare separators.
    delimiter: str | None = None
    for lineno, line in enumerate(text.split("\n"), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            comments.append(stripped[1:].strip())
            continue
        header = delimiter is None
        if header:
            delimiter = next((d for d in (",", ";", "\t") if d in stripped), ",")
        try:
            fields = next(csv.reader([line], delimiter=delimiter or ",", strict=True))
        except csv.Error as exc:
            raise _error(source, f"malformed CSV: {exc}", lineno) from exc
        yield lineno, fields if header or delimiter == "," else [f.replace(",", ".") for f in fields]


def _parse_text(text: str, source: str, min_points: int, accept=(), layout: str = "tenscell CSV") -> RheologyData:
    comments: list[str] = []
    columns: list[str] | None = None
    header_line = 0
    values: dict[str, list[float]] = {}
    row_lines: list[int] = []

    for lineno, fields in _csv_lines(text, source, comments):
        if columns is None:
            columns = _parse_header(fields, source, lineno)
            header_line = lineno
            values = {c: [] for c in columns}
            continue

        if len(fields) != len(columns):
            raise _error(
                source,
                f"expected {len(columns)} fields ({', '.join(columns)}), "
                f"found {len(fields)}",
                lineno,
            )
        row: dict[str, float] = {}
        for col, field in zip(columns, fields):
            text_value = field.strip()
            value = _parse_float(text_value)
            if value is None:
                found = repr(text_value) if text_value else "an empty field"
                raise _error(source, f"column {col}: not a number: {found}", lineno)
            if not math.isfinite(value):
                raise _error(source, f"column {col}: value {text_value!r} is not finite", lineno)
            row[col] = value
        _check_row(row, source, lineno)
        for col, value in row.items():
            values[col].append(value)
        row_lines.append(lineno)

    if columns is None:
        raise _error(source, "no header line (the file has no non-comment lines)")
    n = len(row_lines)
    if n == 0:
        raise _error(source, "no data rows after the header", header_line)
    if n < min_points:
        raise _error(
            source,
            f"{n} data point{'s' if n != 1 else ''}, fewer than {option('min_points', min_points)}",
        )

    arr = {c: np.asarray(v, dtype=np.float64) for c, v in values.items()}
    if _ABS in arr:
        G_storage, G_loss, storage_sd, loss_sd = _polar_to_cartesian(
            arr[_ABS], arr[_PHASE], arr.get(_ABS_SD), arr.get(_PHASE_SD)
        )
    else:
        G_storage, G_loss = arr[_STORAGE], arr[_LOSS]
        storage_sd, loss_sd = arr.get(_STORAGE_SD), arr.get(_LOSS_SD)

    provenance = Provenance(file=source, layout=layout, points=n,
                            columns=tuple((_QUANTITY_OF[c], c, _UNIT_OF.get(c, "")) for c in columns))
    data = RheologyData(
        frequency_hz=arr[_FREQUENCY],
        G_storage=G_storage,
        G_loss=G_loss,
        prestress=arr.get(_PRESTRESS),
        G_storage_sd=storage_sd,
        G_loss_sd=loss_sd,
        source=source,
        comments=tuple(comments),
        locations=tuple(f"line {k}" for k in row_lines),
        provenance=provenance,
    )
    return checked(data, accept, {"storage": _STORAGE, "loss": _LOSS} if _STORAGE in arr else {})


def checked(data, accept, columns: dict | None = None, what: str | None = None):
    """``data`` as read, through :func:`tenscell.io.checks.check_measurement` (``accept``: checks to skip;
    ``what`` names the step in the messages); the problems accepted are recorded in its provenance."""
    from dataclasses import replace

    from .checks import accepted_checks, check_measurement

    found = check_measurement(data, accepted_checks(accept), columns, what)
    if not found:
        return data
    return replace(data, provenance=replace(data.provenance, accepted=data.provenance.accepted + found))


def _check_row(row: dict[str, float], source: str, lineno: int) -> None:
    """Check the physical ranges of one parsed data row (in its own columns: before |G|, phase become G', G'')."""
    positive = {
        _FREQUENCY: "frequency",
        _PRESTRESS: "prestress",
        _STORAGE: "storage modulus G'",
        _LOSS: "loss modulus G''",
        _ABS: "modulus |G|",
        _STORAGE_SD: "standard deviation of G'",
        _LOSS_SD: "standard deviation of G''",
        _ABS_SD: "standard deviation of |G|",
        _PHASE_SD: "standard deviation of the phase",
    }
    for col, what in positive.items():
        if col in row and row[col] <= 0:
            kind = "zero" if row[col] == 0 else "negative"
            raise _error(
                source, f"column {col}: {kind} {what} ({row[col]:g}); must be > 0", lineno
            )
    for col, quantity in _COLUMN_QUANTITY.items():
        problem = range_problem(quantity, row[col], "Pa" if col == _PRESTRESS else None) if col in row else None
        if problem is not None:
            raise _error(source, f"column {col!r}: {problem}", lineno)
    if _PHASE in row:
        phase = row[_PHASE]
        if not 0.0 <= phase <= 90.0:
            raise _error(
                source,
                f"column {_PHASE}: phase {phase:g} deg outside [0, 90] deg",
                lineno,
            )
        # The bounds are allowed by the range check but give a zero modulus,
        # which cannot be fitted on a log scale.
        if phase == 0.0:
            raise _error(
                source,
                f"column {_PHASE}: phase 0 deg gives a zero loss modulus "
                f"G'' = |G| sin(phase); must be > 0",
                lineno,
            )
        if phase == 90.0:
            raise _error(
                source,
                f"column {_PHASE}: phase 90 deg gives a zero storage modulus "
                f"G' = |G| cos(phase); must be > 0",
                lineno,
            )


def _polar_to_cartesian(
    G_abs: np.ndarray,
    phase_deg: np.ndarray,
    abs_sd: np.ndarray | None,
    phase_sd_deg: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Convert |G| (Pa) and phase (deg) to G', G'' (Pa) and their SDs."""
    phi = np.deg2rad(phase_deg)
    cos, sin = np.cos(phi), np.sin(phi)
    G_storage = G_abs * cos
    G_loss = G_abs * sin
    if abs_sd is None or phase_sd_deg is None:
        return G_storage, G_loss, None, None
    # First-order propagation assuming independent errors in |G| and phase;
    # the phase SD must be in radians for the derivative d(cos)/dphi = -sin.
    s_phi = np.deg2rad(phase_sd_deg)
    storage_sd = np.hypot(cos * abs_sd, G_abs * sin * s_phi)
    loss_sd = np.hypot(sin * abs_sd, G_abs * cos * s_phi)
    return G_storage, G_loss, storage_sd, loss_sd


def read_csv(path: str | os.PathLike[str], *, min_points: int = 1, accept=()) -> RheologyData:
    """Read a rheology data file.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file in one of the layouts described in the module docstring.
        Frequencies in Hz, moduli and prestress in Pa, phase in degrees.
    min_points : int, optional
        Minimum number of data points required, e.g. the number of free
        parameters of the model to be fitted. Default 1.
    accept : str or sequence of str, optional
        Checks of :mod:`tenscell.io.checks` to skip (``"one-frequency"``,
        ``"outliers"``): read data they would refuse.

    Returns
    -------
    RheologyData
        With ``source`` set to `path`, ``comments`` holding every ``#``
        line of the file (before or after the header) in file order, and its
        ``provenance``.

    Raises
    ------
    DataError
        If the file is missing, unreadable or not UTF-8; has no header or no
        data rows; has unknown, duplicate, missing or mixed-layout columns;
        a row with the wrong number of fields; a non-numeric, NaN or infinite
        value; a non-positive frequency, prestress, modulus or SD; a phase
        outside [0, 90] deg or at 0 or 90 deg (a zero modulus); fewer
        than `min_points` rows; or data a check of :mod:`tenscell.io.checks`
        refuses (one frequency, a value many decades from its neighbours).
    """
    source = os.fspath(path)
    if isinstance(source, bytes):
        source = os.fsdecode(source)
    # the byte-order mark spreadsheet programs often add is dropped (it would become part of the first name)
    text = read_text_file(source, newline=None)
    return _parse_text(text, source, min_points, accept)


def parse_text(text: str, source: str = "<text>", *, min_points: int = 1, accept=()) -> RheologyData:
    """Parse rheology data from CSV text (what :func:`read_csv` does after reading the file).

    For data that arrive as text rather than as a file, e.g. one cell's rows
    of a long table sent to a worker. ``source`` names the data in error
    messages; see :func:`read_csv` for the layouts and the errors raised.
    """
    return _parse_text(text, str(source), min_points, accept)


def _format(x: float) -> str:
    # repr gives the shortest string that reads back to the same float.
    return repr(float(x))


def write_csv(data: RheologyData, path: str | os.PathLike[str]) -> None:
    """Write data as CSV in layout 1 (frequency sweep) or 2 (prestress sweep).

    Comments are written first as ``# ...`` lines, then the header
    (``[prestress_Pa,] frequency_Hz, G_storage_Pa, G_loss_Pa`` plus
    ``G_storage_sd_Pa`` / ``G_loss_sd_Pa`` when present) and the rows.
    Floats are written so that :func:`read_csv` recovers them exactly.

    The file is written to a temporary file in the same directory and then
    moved into place with :func:`os.replace`, so readers see either the old
    file or the complete new one, and a failure leaves no partial file.

    Parameters
    ----------
    data : RheologyData
        Data to write.
    path : str or os.PathLike
        Destination file; replaced if it exists.

    Raises
    ------
    OSError
        If the directory does not exist or is not writable.
    """
    target = Path(os.fspath(path))
    columns: list[tuple[str, np.ndarray]] = []
    if data.prestress is not None:
        columns.append((_PRESTRESS, data.prestress))
    columns += [
        (_FREQUENCY, data.frequency_hz),
        (_STORAGE, data.G_storage),
        (_LOSS, data.G_loss),
    ]
    if data.G_storage_sd is not None:
        columns.append((_STORAGE_SD, data.G_storage_sd))
    if data.G_loss_sd is not None:
        columns.append((_LOSS_SD, data.G_loss_sd))

    with atomic_path(target, make_parents=False) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
        for comment in data.comments:
            fh.write(f"# {comment}\n" if comment else "#\n")
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow([name for name, _ in columns])
        for i in range(data.n):
            writer.writerow([_format(arr[i]) for _, arr in columns])


def bundled_names() -> tuple[str, ...]:
    """Short names of the data sets shipped with tenscell.

    Returns
    -------
    tuple of str
        ``("fabry2001", "stamenovic2002")``: human airway smooth muscle
        frequency sweep (power law, Fabry et al. 2001) and prestress sweep at
        0.1 Hz (Stamenovic et al. 2002).
    """
    return tuple(short for short, _ in _BUNDLED)


def bundled(name: str) -> RheologyData:
    """Load a data set shipped with tenscell.

    Parameters
    ----------
    name : str
        A short name from :func:`bundled_names` (``"fabry2001"``,
        ``"stamenovic2002"``) or the full file name (e.g.
        ``"fabry2001_hasm_powerlaw.csv"``); case-insensitive.

    Returns
    -------
    RheologyData
        ``source`` is the file's name marked as bundled (not its install path).

    Raises
    ------
    DataError
        If `name` is not a bundled data set; the message lists the names.
    """
    key = str(name).strip().lower()
    for short, filename in _BUNDLED:
        if key in (short, filename.lower()):
            break
    else:
        available = ", ".join(f"{s!r} ({f})" for s, f in _BUNDLED)
        raise DataError(f"{name!r}: no bundled data set of that name; available: {available}")
    resource = resources.files("tenscell") / "data" / filename
    # the name, not the install path: reports and messages say which data set, the same on every machine
    source = f"{filename} (bundled with tenscell)"
    # Read through the resource API rather than open() so that this also
    # works when the package is installed as a zip file.
    try:
        text = resource.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise _error(source, f"cannot read bundled file: {exc}") from exc
    return _parse_text(text, source, min_points=1, layout="bundled with tenscell")


def generated_note(data) -> str | None:
    """A phrase saying the data are generated from a published fit law, when their file's comments say so.

    The bundled data sets are not raw measurements: each file's comments say
    it was generated from a published law. Reports, figures and claims that
    call them data repeat it; this reads it from the comments (``"not raw
    measurements"`` or ``"generated from"``) rather than from the file name.

    Parameters
    ----------
    data : RheologyData or CreepData
        Anything with ``comments``.

    Returns
    -------
    str or None
    """
    text = " ".join(getattr(data, "comments", ()) or ()).lower()
    if "not raw measurement" in text or "generated from" in text:
        return "generated from a published fit law, not raw measurements (the file's own comments say so)"
    return None

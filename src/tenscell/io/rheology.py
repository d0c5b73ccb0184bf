"""The measured moduli as one object: :class:`RheologyData`, validated at construction.

Frequencies, moduli, prestresses and standard deviations are checked against the one table of physical ranges
(:mod:`tenscell._ranges`) when a data set is built, naming the file, line and column of a value outside; the
checks of :mod:`tenscell.io.checks` run on what a reader built (:func:`checked`). The package's own CSV layout
is read and written by :mod:`tenscell.io.data`; instruments' exports by :mod:`tenscell.io.readers`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._ranges import RANGES, range_problem
from .columns import DataError, parse_frame
from .provenance import Provenance

__all__ = ["RheologyData", "DataError", "check_ranges", "checked"]

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
        arrays = {name: _column(source, name, getattr(self, name), optional=name not in _REQUIRED)
                  for name in _ARRAY_FIELDS}
        lengths = {k: len(v) for k, v in arrays.items() if v is not None}
        if len(set(lengths.values())) != 1:
            raise _error(source, f"arrays have different lengths: {lengths}")
        if lengths["frequency_hz"] == 0:
            raise _error(source, "no data points")
        locations = _locations(source, self.locations, lengths["frequency_hz"])
        check_ranges(source, {col: (a, _COLUMN_QUANTITY[col], "Pa" if col == _PRESTRESS else None)
                              for k, a in arrays.items() if a is not None and k in _FIELD_COLUMN
                              for col in (_FIELD_COLUMN[k],)}, locations)
        locations = _canonical_order(arrays, locations)
        for name, arr in arrays.items():
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "locations", locations)
        object.__setattr__(self, "provenance", _provenance(self.provenance, source, lengths["frequency_hz"]))
        object.__setattr__(self, "comments", _comments(source, self.comments))
        object.__setattr__(self, "kind", _kind(source, self.kind, arrays["prestress"]))

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

    def _repr_html_(self) -> str:
        from .._results import reporter  # as __repr__: the conventions are imported when a result is shown

        return reporter("data_html")(self)  # what, where from (provenance), first and last points (reports/html.py)

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


#: the array fields of RheologyData, in the order they are checked; the first three are required
_ARRAY_FIELDS = ("frequency_hz", "G_storage", "G_loss", "prestress", "G_storage_sd", "G_loss_sd", "counts")
_REQUIRED = _ARRAY_FIELDS[:3]


def _column(source: str, name: str, value, *, optional: bool) -> np.ndarray | None:
    """``value`` as a read-only 1-D array of finite numbers > 0 (None when optional and absent); DataError naming
    the field and the first bad entry."""
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


def _canonical_order(arrays: dict, locations):
    """Sort ``arrays`` in place into the canonical row order (prestress, then frequency, then the values) and return
    ``locations`` in that order: the same data set gives the same object, and the same fit, whatever the order of
    the rows in its file."""
    keys = [a for k in ("G_loss_sd", "G_storage_sd", "G_loss", "G_storage", "frequency_hz", "prestress")
            if (a := arrays[k]) is not None]
    order = np.lexsort(keys)
    if not np.any(order != np.arange(order.size)):
        return locations
    for name, arr in arrays.items():
        if arr is not None:
            arr = arr[order]
            arr.flags.writeable = False
            arrays[name] = arr
    return None if locations is None else tuple(locations[i] for i in order)


def _comments(source: str, comments) -> tuple[str, ...]:
    """The comments as a tuple of one-line strings (DataError otherwise)."""
    if isinstance(comments, str):
        raise _error(source, "comments must be a sequence of strings, not a str")
    comments = tuple(comments)
    for c in comments:
        if not isinstance(c, str):
            raise _error(source, f"comment {c!r} is not a str")
        # A line break would turn the rest of the comment into a data
        # line when written by write_csv.
        if "\n" in c or "\r" in c:
            raise _error(source, f"comment {c!r} contains a line break")
    return comments


def _kind(source: str, kind: str | None, prestress) -> str:
    """``"frequency"`` without a prestress column, ``"prestress"`` with one (DataError if ``kind`` says otherwise)."""
    expected = "frequency" if prestress is None else "prestress"
    if kind is not None and kind != expected:
        raise _error(source, f"kind={kind!r} is inconsistent with prestress "
                             f"{'absent' if prestress is None else 'present'} (expected {expected!r})")
    return expected


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


def checked(data, accept, columns: dict | None = None, what: str | None = None):
    """``data`` as read, through :func:`tenscell.io.checks.check_measurement` (``accept``: checks to skip;
    ``what`` names the step in the messages); the problems accepted are recorded in its provenance."""
    from dataclasses import replace

    from .checks import accepted_checks, check_measurement

    found = check_measurement(data, accepted_checks(accept), columns, what)
    if not found:
        return data
    return replace(data, provenance=replace(data.provenance, accepted=data.provenance.accepted + found))

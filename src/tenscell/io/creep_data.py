"""Measured creep compliance J(t) of cells: reading, writing, and telling it apart from moduli files.

Layout (CSV, ``#`` comment lines and blank lines as in :mod:`tenscell.io.data`)::

    time_s, creep_compliance_per_Pa [, creep_compliance_sd_per_Pa] [, prestress_Pa]

``time_s`` is the time after the stress step (s, > 0), ``creep_compliance_per_Pa``
the strain per unit stress J(t) (1/Pa, > 0; the model's J(t)·2L, see
:func:`tenscell.timedomain.creep_compliance`), the optional standard deviation
(1/Pa) weights the fit residuals, and the optional ``prestress_Pa`` states the
prestress at which the creep was measured (it links the data set to others in
a joint fit). Columns are matched case-insensitively, in any order; any other
column is an error.
"""
from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass

import numpy as np

from .._errors import option
from .._results import dataframe, format_repr, reporter
from .columns import parse_frame, read_text_file
from .data import _csv_lines, _parse_float, read_csv
from .rheology import (RheologyData, _error, _locations, _provenance, _stated_prestress, check_ranges, checked)
from .outputs import atomic_path
from .provenance import Provenance

__all__ = ["CreepData", "read_creep_csv", "write_creep_csv", "is_creep_header", "read_measurements"]

_TIME = "time_s"
_J = "creep_compliance_per_Pa"
_J_SD = "creep_compliance_sd_per_Pa"
_PRESTRESS = "prestress_Pa"
_COLUMNS = (_TIME, _J, _J_SD, _PRESTRESS)
_CANONICAL = {c.lower(): c for c in _COLUMNS}
# field -> (its column, the quantity of the one ranges table, tenscell._ranges, its values must lie in, unit)
_FIELDS = {"time_s": (_TIME, "time", None), "compliance": (_J, "compliance", None),
           "compliance_sd": (_J_SD, "compliance", None), "prestress": (_PRESTRESS, "prestress", "Pa")}


@dataclass(frozen=True, eq=False, repr=False)
class CreepData:
    """Measured creep compliance J(t) after a stress step.

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Times after the step (s), > 0.
    compliance : array_like, shape (n,)
        Creep compliance J(t) (1/Pa), > 0.
    compliance_sd : array_like, shape (n,), optional
        Standard deviations of J (1/Pa), > 0.
    prestress : array_like, shape (n,), optional
        Prestress at which each point was measured (Pa), > 0.
    source : str
    comments : tuple of str
    locations : tuple of str, optional
        Where each point is in `source` (e.g. ``"line 12"``), for messages.
    provenance : Provenance, optional
        What the data were read from and how (:class:`tenscell.io.provenance.Provenance`); readers set it.
    counts : array_like, shape (n,), optional
        How many measured points each point stands for (binned data, :mod:`tenscell.io.thinning`); None: one
        each. Without standard deviations a point weighs √count in a fit.

    Every value must lie in the range tenscell accepts for its quantity (the
    table :data:`tenscell._ranges.RANGES` that the command-line flags use):
    times 1e-12..1e12 s, compliances 1e-30..1e30 1/Pa, prestress 1e-30..1e30 Pa.

    Raises
    ------
    DataError
        For arrays that are not 1-D of one non-zero length, values that are
        not finite and positive, or a value outside its range (naming the
        column and the location).
    """

    time_s: np.ndarray
    compliance: np.ndarray
    compliance_sd: np.ndarray | None = None
    prestress: np.ndarray | None = None
    source: str = "<memory>"
    comments: tuple = ()
    locations: tuple[str, ...] | None = None
    provenance: Provenance | None = None
    counts: np.ndarray | None = None

    def __post_init__(self) -> None:
        source = str(self.source)
        object.__setattr__(self, "source", source)
        n = None
        for name in ("time_s", "compliance", "compliance_sd", "prestress", "counts"):
            value = getattr(self, name)
            if value is None:
                continue
            try:
                arr = np.array(value, dtype=np.float64)
            except (TypeError, ValueError) as exc:
                raise _error(source, f"{name} is not numeric: {exc}") from exc
            if arr.ndim != 1 or arr.size == 0:
                raise _error(source, f"{name} must be 1-D and non-empty, got shape {arr.shape}")
            bad = np.flatnonzero(~np.isfinite(arr) | (arr <= 0))
            if bad.size:
                raise _error(source, f"{name}[{bad[0]}] = {arr[bad[0]]} must be finite and > 0")
            if n is not None and arr.size != n:
                raise _error(source, f"{name} has {arr.size} values, time_s has {n}")
            n = arr.size
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)
        locations = _locations(source, self.locations, self.n)
        check_ranges(source, {col: (getattr(self, name), quantity, unit)
                              for name, (col, quantity, unit) in _FIELDS.items() if getattr(self, name) is not None},
                     locations)
        object.__setattr__(self, "locations", locations)
        object.__setattr__(self, "comments", tuple(str(c) for c in self.comments))
        object.__setattr__(self, "provenance", _provenance(self.provenance, source, self.n))

    kind = "creep"

    @property
    def n(self) -> int:
        """Number of data points."""
        return int(self.time_s.size)

    @property
    def has_sd(self) -> bool:
        """True when J carries standard deviations."""
        return self.compliance_sd is not None

    @property
    def weights(self) -> np.ndarray:
        """Weights of the log10 J residuals: ``J ln10/sd(J)`` (1/sd(log10 J) to first order), or √counts (ones
        when each point is one measurement)."""
        if self.compliance_sd is None:
            return np.ones(self.n) if self.counts is None else np.sqrt(self.counts)
        return self.compliance * math.log(10.0) / self.compliance_sd

    def binned(self, max_points: int | None = None, weighting: str = "bins") -> "CreepData":
        """At most ``max_points`` points by log-time binning (:func:`tenscell.io.thinning.bin_log_time`; without
        SDs each bin weighs as one point, or √(its points) with ``weighting="counts"``).

        Returns ``self`` when it has no more points than that; the binned data's provenance and comments state
        the rule, the counts and the weights.
        """
        from .thinning import DEFAULT_MAX_POINTS, bin_log_time

        return bin_log_time(self, DEFAULT_MAX_POINTS if max_points is None else max_points, weighting)

    def with_prestress(self, prestress_pa: float) -> "CreepData":
        """A copy that states the prestress (Pa) at which the creep was measured (links it in a joint fit)."""
        p = _stated_prestress(self, prestress_pa)
        assert self.provenance is not None  # set by __post_init__
        return CreepData(time_s=self.time_s, compliance=self.compliance, compliance_sd=self.compliance_sd,
                         prestress=np.full(self.n, p), source=self.source, comments=self.comments,
                         locations=self.locations, provenance=self.provenance.noted(f"prestress stated: {p:g} Pa"),
                         counts=self.counts)

    def __repr__(self) -> str:
        t, J = self.time_s, self.compliance
        return format_repr(
            f"CreepData {self.source}",
            f"{self.n} points, t = {t.min():.3g} .. {t.max():.3g} s, J = {J.min():.3g} .. {J.max():.3g} 1/Pa"
            + ("" if self.prestress is None else f", prestress {self.prestress.min():.4g} .. "
               f"{self.prestress.max():.4g} Pa"),
        )

    def _repr_html_(self) -> str:
        return reporter("data_html")(self)  # what, where from (provenance), first and last points (reports/html.py)

    @classmethod
    def from_dataframe(cls, df, columns=None, *, source: str = "<DataFrame>", min_points: int = 1, accept=(),
                       **units) -> "CreepData":
        """Measured creep compliance from a pandas DataFrame with your own column names and units.

        See :func:`tenscell.io.importers.from_dataframe`: ``columns`` is a
        :class:`~tenscell.io.importers.ColumnMap` (``time=``, ``compliance=``,
        ``time_unit=``, ``compliance_unit=``) or a dict of its fields; default
        recognised from the column names (``time_s``, ``time (s)``, ``J(t) (1/Pa)``...).
        """
        parsed = parse_frame(df, columns, source, min_points, units)
        if parsed.layout != "creep":
            raise _error(source, "the columns hold moduli, not creep compliance; use "
                                 "tenscell.RheologyData.from_dataframe")
        return cls.from_parsed(parsed, Provenance(file=source, layout="DataFrame"), accept)

    @classmethod
    def from_parsed(cls, parsed, provenance: Provenance, accept=(), what: str | None = None) -> "CreepData":
        """The creep compliance a parsed table holds (:class:`tenscell.io.columns.Parsed`), with the provenance as
        the reader knows it (completed with the columns read), through the checks of :mod:`tenscell.io.checks`."""
        v = parsed.values
        data = cls(time_s=v["time"], compliance=v["compliance"], compliance_sd=v.get("compliance_sd"),
                   prestress=v.get("prestress"), source=parsed.source, comments=parsed.comments,
                   locations=parsed.where or None, provenance=provenance.read(parsed))
        headers = {q: h for q, h, _ in parsed.columns if q == "compliance"}
        return checked(data, accept, headers, what)

    def to_dataframe(self):
        """``time_s``, ``creep_compliance_per_Pa`` (and the SD and prestress columns when present)."""
        cols = {_TIME: self.time_s, _J: self.compliance}
        if self.compliance_sd is not None:
            cols[_J_SD] = self.compliance_sd
        if self.prestress is not None:
            cols[_PRESTRESS] = self.prestress
        return dataframe(cols, {"source": self.source})


def _header(fields: list[str], source: str, line: int) -> list[str]:
    names = [f.strip() for f in fields]
    unknown = [s for s in names if s.lower() not in _CANONICAL]
    if unknown:
        raise _error(source, f"unknown column(s) {', '.join(map(repr, unknown))} in a creep file; recognised "
                             f"columns are {', '.join(_COLUMNS)}", line)
    canonical = [_CANONICAL[s.lower()] for s in names]
    dup = sorted({c for c in canonical if canonical.count(c) > 1})
    if dup:
        raise _error(source, f"duplicate column(s) {', '.join(dup)}", line)
    missing = [c for c in (_TIME, _J) if c not in canonical]
    if missing:
        raise _error(source, f"missing required column(s) {', '.join(missing)}", line)
    return canonical


def is_creep_header(text: str, source: str = "<text>") -> bool:
    """True if the first non-comment line of ``text`` names a ``time_s`` column (a creep file)."""
    for _, fields in _csv_lines(text, source, []):
        return _TIME.lower() in [f.strip().lower() for f in fields]
    return False


def _parse(text: str, source: str) -> CreepData:
    comments: list[str] = []
    columns, rows, lines = None, [], []
    for lineno, fields in _csv_lines(text, source, comments):
        if columns is None:
            columns = _header(fields, source, lineno)
            continue
        if len(fields) != len(columns):
            raise _error(source, f"expected {len(columns)} fields ({', '.join(columns)}), found {len(fields)}", lineno)
        row = []
        for col, field in zip(columns, fields):
            v = _parse_float(field.strip())
            if v is None or not math.isfinite(v):
                raise _error(source, f"column {col}: not a finite number: {field.strip()!r}", lineno)
            if v <= 0:
                raise _error(source, f"column {col}: {v:g} must be > 0", lineno)
            row.append(v)
        rows.append(row)
        lines.append(f"line {lineno}")
    if columns is None:
        raise _error(source, "no header line (the file has no non-comment lines)")
    if not rows:
        raise _error(source, "no data rows after the header")
    arr = dict(zip(columns, np.array(rows, dtype=float).T))
    units = {_TIME: ("time", "s"), _J: ("compliance", "1/Pa"), _J_SD: ("compliance_sd", "1/Pa"),
             _PRESTRESS: ("prestress", "Pa")}
    provenance = Provenance(file=source, layout="tenscell creep CSV", points=len(rows),
                            columns=tuple((units[c][0], c, units[c][1]) for c in columns))
    return CreepData(time_s=arr[_TIME], compliance=arr[_J], compliance_sd=arr.get(_J_SD),
                     prestress=arr.get(_PRESTRESS), source=source, comments=tuple(comments), locations=tuple(lines),
                     provenance=provenance)


def _read_text(path) -> tuple[str, str]:
    source = os.fsdecode(os.fspath(path))
    return read_text_file(source, newline=None), source


def read_creep_csv(path, *, min_points: int = 1, accept=()) -> CreepData:
    """Read a creep compliance file (layout in the module docstring).

    ``accept``: checks of :mod:`tenscell.io.checks` to skip (``"decreasing"``, ``"outliers"``).

    Raises
    ------
    DataError
        Missing or unreadable file, unknown/duplicate/missing columns, a bad
        value (with its line number), fewer than ``min_points`` rows, or a
        compliance a check refuses (one that decreases with time, a value
        many decades from its neighbours).
    """
    text, source = _read_text(path)
    data = _parse(text, source)
    if data.n < min_points:
        raise _error(source, f"{data.n} data point(s), fewer than {option('min_points', min_points)}")
    return checked(data, accept, {"compliance": _J})


def read_measurements(path, *, min_points: int = 1, accept=()) -> RheologyData | CreepData:
    """Read moduli (:func:`tenscell.io.data.read_csv`) or creep compliance, whichever layout the header names."""
    text, source = _read_text(path)
    if is_creep_header(text, source):
        return read_creep_csv(path, min_points=min_points, accept=accept)
    return read_csv(path, min_points=min_points, accept=accept)


def write_creep_csv(data: CreepData, path) -> None:
    """Write creep data in the layout :func:`read_creep_csv` reads back exactly (atomic replace)."""
    cols = [(_TIME, data.time_s), (_J, data.compliance)]
    if data.compliance_sd is not None:
        cols.append((_J_SD, data.compliance_sd))
    if data.prestress is not None:
        cols.append((_PRESTRESS, data.prestress))
    with atomic_path(os.fspath(path), make_parents=False) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
        for c in data.comments:
            fh.write(f"# {c}\n" if c else "#\n")
        w = csv.writer(fh, lineterminator="\n")
        w.writerow([c for c, _ in cols])
        for i in range(data.n):
            w.writerow([repr(float(a[i])) for _, a in cols])



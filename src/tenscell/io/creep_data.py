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

from .._results import dataframe, format_repr
from .data import (RheologyData, _csv_lines, _error, _locations, _parse_float, _stated_prestress, check_ranges,
                   read_csv)
from .outputs import atomic_path

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

    def __post_init__(self) -> None:
        source = str(self.source)
        object.__setattr__(self, "source", source)
        n = None
        for name in ("time_s", "compliance", "compliance_sd", "prestress"):
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
        """Weights of the log10 J residuals: ``J ln10/sd(J)`` (1/sd(log10 J) to first order), or ones."""
        if self.compliance_sd is None:
            return np.ones(self.n)
        return self.compliance * math.log(10.0) / self.compliance_sd

    def with_prestress(self, prestress_pa: float) -> "CreepData":
        """A copy that states the prestress (Pa) at which the creep was measured (links it in a joint fit)."""
        p = _stated_prestress(self, prestress_pa)
        return CreepData(time_s=self.time_s, compliance=self.compliance, compliance_sd=self.compliance_sd,
                         prestress=np.full(self.n, p), source=self.source, comments=self.comments)

    def __repr__(self) -> str:
        t, J = self.time_s, self.compliance
        return format_repr(
            f"CreepData {self.source}",
            f"{self.n} points, t = {t.min():.3g} .. {t.max():.3g} s, J = {J.min():.3g} .. {J.max():.3g} 1/Pa"
            + ("" if self.prestress is None else f", prestress {self.prestress.min():.4g} .. "
               f"{self.prestress.max():.4g} Pa"),
        )

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
    return CreepData(time_s=arr[_TIME], compliance=arr[_J], compliance_sd=arr.get(_J_SD),
                     prestress=arr.get(_PRESTRESS), source=source, comments=tuple(comments), locations=tuple(lines))


def _read_text(path) -> tuple[str, str]:
    source = os.fsdecode(os.fspath(path))
    try:
        with open(source, encoding="utf-8-sig") as fh:
            return fh.read(), source
    except (OSError, UnicodeDecodeError) as exc:
        raise _error(source, f"cannot read file: {exc}") from exc


def read_creep_csv(path, *, min_points: int = 1) -> CreepData:
    """Read a creep compliance file (layout in the module docstring).

    Raises
    ------
    DataError
        Missing or unreadable file, unknown/duplicate/missing columns, a bad
        value (with its line number), or fewer than ``min_points`` rows.
    """
    text, source = _read_text(path)
    data = _parse(text, source)
    if data.n < min_points:
        raise _error(source, f"{data.n} data point(s), fewer than the {min_points} the fit needs")
    return data


def read_measurements(path, *, min_points: int = 1) -> RheologyData | CreepData:
    """Read moduli (:func:`tenscell.io.data.read_csv`) or creep compliance, whichever layout the header names."""
    text, source = _read_text(path)
    if is_creep_header(text, source):
        return read_creep_csv(path, min_points=min_points)
    return read_csv(path, min_points=min_points)


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



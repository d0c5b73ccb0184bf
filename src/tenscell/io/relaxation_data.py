"""Measured stress relaxation G(t) of cells: the modulus after a strain step, or its shape when its scale is unknown.

Layout (CSV, ``#`` comment lines and blank lines as in :mod:`tenscell.io.data`)::

    time_s, relaxation_modulus_Pa [, relaxation_modulus_sd_Pa] [, prestress_Pa]
    time_s, relaxation_modulus_relative [, relaxation_modulus_relative_sd]

``time_s`` is the time after the strain step (s, > 0) and ``relaxation_modulus_Pa`` the stress per unit strain
G(t) (Pa, > 0; the model's :func:`tenscell.timedomain.relaxation_modulus` times its continuum factor); the
optional standard deviation weights the fit residuals and ``prestress_Pa`` states the prestress the relaxation was
measured at (it links the data set to others in a joint fit). A relaxation whose modulus scale is unknown (an AFM
force at constant height with an unknown probe radius) is given as ``relaxation_modulus_relative``: any positive
multiple of G(t); a fit then compares shapes, the model's ``G(t)/G(t_ref)`` against ``values/values[0]`` at the
first time ``t_ref`` (which is the reference, not a residual). Columns are matched case-insensitively, in any order.
"""
from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass

import numpy as np

from .._results import dataframe, format_repr, reporter
from .columns import read_text_file
from .data import _csv_lines, _parse_float
from .outputs import atomic_path
from .provenance import Provenance
from .rheology import _error, _locations, _provenance, _stated_prestress, check_ranges

__all__ = ["RelaxationData", "read_relaxation_csv", "write_relaxation_csv", "is_relaxation_header", "COLUMNS"]

_TIME = "time_s"
_G, _G_SD = "relaxation_modulus_Pa", "relaxation_modulus_sd_Pa"
_REL, _REL_SD = "relaxation_modulus_relative", "relaxation_modulus_relative_sd"
_PRESTRESS = "prestress_Pa"
#: every column of the layout (module docstring)
COLUMNS = (_TIME, _G, _G_SD, _REL, _REL_SD, _PRESTRESS)
_CANONICAL = {c.lower(): c for c in COLUMNS}
#: field -> (quantity of the ranges table, tenscell._ranges, unit or None for the table's), of the absolute layout
_RANGES = {"time_s": ("time", None), "modulus": ("modulus", None), "modulus_sd": ("modulus", None),
           "prestress": ("prestress", "Pa")}


@dataclass(frozen=True, eq=False, repr=False)
class RelaxationData:
    """Measured stress relaxation G(t) after a strain step (or its shape: ``relative``).

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Times after the step (s), > 0, increasing.
    modulus : array_like, shape (n,)
        G(t) (Pa), > 0; with ``relative`` any positive multiple of it (dimensionless).
    modulus_sd : array_like, shape (n,), optional
        Standard deviations of ``modulus`` (its unit), > 0.
    prestress : array_like, shape (n,), optional
        Prestress at which each point was measured (Pa), > 0.
    relative : bool
        The modulus scale is unknown: only the shape ``modulus/modulus[0]`` is fitted (module docstring).
    source : str
    comments : tuple of str
    locations : tuple of str, optional
        Where each point is in ``source`` (``"line 12"``), for messages.
    provenance : Provenance, optional
    counts : None
        Relaxation data are not binned (one measurement a point); the field is every data type's.

    Raises
    ------
    DataError
        Arrays that are not 1-D of one length of at least 2, values that are not finite and positive, times that do
        not increase, or a value outside its range (naming the column and the location).
    """

    time_s: np.ndarray
    modulus: np.ndarray
    modulus_sd: np.ndarray | None = None
    prestress: np.ndarray | None = None
    relative: bool = False
    source: str = "<memory>"
    comments: tuple = ()
    locations: tuple[str, ...] | None = None
    provenance: Provenance | None = None
    counts: None = None

    kind = "relaxation"

    def __post_init__(self) -> None:
        source = str(self.source)
        object.__setattr__(self, "source", source)
        n = None
        for name in ("time_s", "modulus", "modulus_sd", "prestress"):
            arr = _positive(source, name, getattr(self, name), n)
            if arr is not None:
                n = arr.size
                object.__setattr__(self, name, arr)
        if self.n < 2 or np.any(np.diff(self.time_s) <= 0):
            raise _error(source, "a relaxation needs at least 2 points at increasing times (time_s)")
        if self.counts is not None:
            raise _error(source, "relaxation data are not binned: counts must be None")
        object.__setattr__(self, "relative", bool(self.relative))
        locations = _locations(source, self.locations, self.n)
        fields = {"time_s": _TIME, "prestress": _PRESTRESS} if self.relative else \
            {"time_s": _TIME, "modulus": _G, "modulus_sd": _G_SD, "prestress": _PRESTRESS}
        check_ranges(source, {col: (getattr(self, name), *_RANGES[name]) for name, col in fields.items()
                              if getattr(self, name) is not None}, locations)
        object.__setattr__(self, "locations", locations)
        object.__setattr__(self, "comments", tuple(str(c) for c in self.comments))
        object.__setattr__(self, "provenance", _provenance(self.provenance, source, self.n))

    @property
    def n(self) -> int:
        """Number of data points."""
        return int(self.time_s.size)

    @property
    def has_sd(self) -> bool:
        """True when the modulus carries standard deviations."""
        return self.modulus_sd is not None

    @property
    def weights(self) -> np.ndarray:
        """Weights of the log10 G residuals: ``G ln10/sd(G)`` (1/sd(log10 G) to first order), or ones."""
        if self.modulus_sd is None:
            return np.ones(self.n)
        return self.modulus * math.log(10.0) / self.modulus_sd

    def binned(self, max_points: int | None = None) -> RelaxationData:
        """Itself: a relaxation is fitted at every point (its first time may be the shape's reference)."""
        return self

    def with_prestress(self, prestress_pa: float) -> RelaxationData:
        """A copy that states the prestress (Pa) at which the relaxation was measured (links it in a joint fit)."""
        p = _stated_prestress(self, prestress_pa)
        assert self.provenance is not None  # set by __post_init__
        return RelaxationData(time_s=self.time_s, modulus=self.modulus, modulus_sd=self.modulus_sd,
                              prestress=np.full(self.n, p), relative=self.relative, source=self.source,
                              comments=self.comments, locations=self.locations,
                              provenance=self.provenance.noted(f"prestress stated: {p:g} Pa"))

    def __repr__(self) -> str:
        t, G = self.time_s, self.modulus
        what = f"G/G(t0) = {G.min() / G[0]:.3g} .. {G.max() / G[0]:.3g} (shape)" if self.relative else \
            f"G = {G.min():.3g} .. {G.max():.3g} Pa"
        return format_repr(f"RelaxationData {self.source}", f"{self.n} points, t = {t.min():.3g} .. {t.max():.3g} s, "
                           + what)

    def _repr_html_(self) -> str:
        return reporter("data_html")(self)

    def to_dataframe(self):
        """The file's columns (:data:`COLUMNS`) present in the data."""
        value, sd = (_REL, _REL_SD) if self.relative else (_G, _G_SD)
        cols = {_TIME: self.time_s, value: self.modulus}
        if self.modulus_sd is not None:
            cols[sd] = self.modulus_sd
        if self.prestress is not None:
            cols[_PRESTRESS] = self.prestress
        return dataframe(cols, {"source": self.source})


def _positive(source: str, name: str, value, n: int | None) -> np.ndarray | None:
    """``value`` as a read-only 1-D array of finite numbers > 0 with ``n`` entries (None when absent)."""
    if value is None:
        return None
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
    arr.flags.writeable = False
    return arr


def is_relaxation_header(text: str, source: str = "<text>") -> bool:
    """True if the first non-comment line of ``text`` names ``time_s`` and a relaxation modulus column."""
    for _, fields in _csv_lines(text, source, []):
        names = {f.strip().lower() for f in fields}
        return _TIME.lower() in names and bool({_G.lower(), _REL.lower()} & names)
    return False


def _header(fields: list[str], source: str, line: int) -> list[str]:
    names = [f.strip() for f in fields]
    unknown = [s for s in names if s.lower() not in _CANONICAL]
    if unknown:
        raise _error(source, f"unknown column(s) {', '.join(map(repr, unknown))} in a relaxation file; recognised "
                             f"columns are {', '.join(COLUMNS)}", line)
    canonical = [_CANONICAL[s.lower()] for s in names]
    dup = sorted({c for c in canonical if canonical.count(c) > 1})
    if dup:
        raise _error(source, f"duplicate column(s) {', '.join(dup)}", line)
    values = [c for c in (_G, _REL) if c in canonical]
    if _TIME not in canonical or len(values) != 1:
        raise _error(source, f"a relaxation file has {_TIME} and one of {_G}, {_REL}", line)
    if (_REL in canonical and (_G_SD in canonical or _PRESTRESS in canonical)) or (_G in canonical and _REL_SD in canonical):
        raise _error(source, f"{_REL} (a shape) goes with {_REL_SD} only; {_G} with {_G_SD} and {_PRESTRESS}", line)
    return canonical


def _rows(text: str, source: str):
    """``(columns, rows, locations, comments)`` of a relaxation table (DataError naming the line)."""
    comments: list[str] = []
    columns, rows, lines = None, [], []
    for lineno, fields in _csv_lines(text, source, comments):
        if columns is None:
            columns = _header(fields, source, lineno)
            continue
        if len(fields) != len(columns):
            raise _error(source, f"expected {len(columns)} fields ({', '.join(columns)}), found {len(fields)}", lineno)
        row = [_parse_float(f.strip()) for f in fields]
        for col, f, v in zip(columns, fields, row):
            if v is None or not math.isfinite(v) or v <= 0:
                raise _error(source, f"column {col}: {f.strip()!r} is not a finite number > 0", lineno)
        rows.append(row)
        lines.append(f"line {lineno}")
    if columns is None:
        raise _error(source, "no header line (the file has no non-comment lines)")
    if not rows:
        raise _error(source, "no data rows after the header")
    return columns, np.array(rows, dtype=float), tuple(lines), tuple(comments)


def read_relaxation_csv(path, *, min_points: int = 2) -> RelaxationData:
    """Read a stress relaxation file (layout in the module docstring).

    Raises
    ------
    DataError
        Missing or unreadable file, unknown/duplicate/missing columns, a bad value (with its line number), times
        that do not increase, or fewer than ``min_points`` rows.
    """
    from .._errors import option

    source = os.fsdecode(os.fspath(path))
    columns, table, lines, comments = _rows(read_text_file(source, newline=None), source)
    if table.shape[0] < min_points:
        raise _error(source, f"{table.shape[0]} data point(s), fewer than {option('min_points', min_points)}")
    arr = dict(zip(columns, table.T))
    relative = _REL in arr
    units = {_TIME: ("time", "s"), _G: ("modulus", "Pa"), _G_SD: ("modulus_sd", "Pa"), _REL: ("modulus", ""),
             _REL_SD: ("modulus_sd", ""), _PRESTRESS: ("prestress", "Pa")}
    provenance = Provenance(file=source, layout="tenscell relaxation CSV", points=table.shape[0],
                            columns=tuple((units[c][0], c, units[c][1]) for c in columns))
    return RelaxationData(time_s=arr[_TIME], modulus=arr[_REL if relative else _G],
                          modulus_sd=arr.get(_REL_SD if relative else _G_SD), prestress=arr.get(_PRESTRESS),
                          relative=relative, source=source, comments=comments, locations=lines, provenance=provenance)


def write_relaxation_csv(data: RelaxationData, path) -> None:
    """Write relaxation data in the layout :func:`read_relaxation_csv` reads back exactly (atomic replace)."""
    df = data.to_dataframe()
    with atomic_path(os.fspath(path), make_parents=False) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
        for c in data.comments:
            fh.write(f"# {c}\n" if c else "#\n")
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(list(df.columns))
        for row in df.itertuples(index=False):
            w.writerow([repr(float(x)) for x in row])

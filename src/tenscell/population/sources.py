"""Where a population's data come from: per-cell files, a glob, or one long table.

:func:`read_sources` turns any of these into :class:`CellSource` records, each
holding one cell's id, condition and its data as CSV text (or an in-memory
:class:`~tenscell.io.data.RheologyData`). The text travels to the worker
that parses and fits it, so a cluster needs no shared file system and a
malformed cell fails in its own task, recorded with its error, without
stopping the others.

Inputs
------
directory
    every ``*.csv`` under it (recursively, in sorted order). A file directly
    in the directory has no condition; a file in a subdirectory takes the
    subdirectory's path as its condition (``histamine/cell-07.csv`` → condition
    ``histamine``). The cell id is the path relative to the directory without
    ``.csv``. Files and directories whose names start with ``_`` or ``.`` are
    skipped (e.g. the synthetic population's ``_generating_parameters.csv``).
glob
    a pattern such as ``"runs/*/cell*.csv"``; ids and conditions as for a
    directory, relative to the pattern's fixed leading directory.
long table
    one ``.csv`` or ``.parquet`` file with a ``cell`` column, optionally a
    ``condition`` column, and the columns of one layout of
    :mod:`tenscell.io.data` (``frequency_Hz, G_storage_Pa, G_loss_Pa``...).
    A file without a ``cell`` column is one cell.
in memory
    a sequence of ``RheologyData``, of ``(cell, RheologyData)`` or
    ``(cell, condition, RheologyData)``, or a
    :class:`~tenscell.population.synth.SyntheticPopulation`.
"""
from __future__ import annotations

import glob as _glob
import hashlib
import io
import os
from dataclasses import dataclass
from typing import Any
from pathlib import Path, PurePosixPath

import numpy as np

from .._errors import TenscellError

__all__ = ["CellSource", "SourceError", "read_sources", "CELL_COLUMN", "CONDITION_COLUMN"]

CELL_COLUMN = "cell"
CONDITION_COLUMN = "condition"
_TABLE_SUFFIXES = (".csv", ".parquet", ".pq")


class SourceError(TenscellError, ValueError):
    """The population input cannot be listed at all (missing, empty, duplicate ids): one line naming it."""


@dataclass(frozen=True, eq=False)
class CellSource:
    """One cell's data, ready to send to a worker.

    Attributes
    ----------
    cell : str
        Unique id within the population.
    condition : str
        Experimental condition ("" if none).
    source : str
        Where the data came from (file, or file and cell for a long table).
    text : str or None
        The cell's data as CSV text in a :mod:`tenscell.io.data` layout.
    data : RheologyData or None
        The cell's data when given in memory (then ``text`` is None).
    error : str or None
        Why the cell's data could not even be read (unreadable file, two
        conditions for one cell); :meth:`load` raises it as a DataError.
    """

    cell: str
    condition: str
    source: str
    text: str | None = None
    data: Any = None
    error: str | None = None

    @property
    def digest(self) -> str:
        """SHA-256 of the cell's data (its text, or its arrays): a resumed run refits a cell whose data changed."""
        h = hashlib.sha256((self.error or "").encode())
        if self.text is not None:
            h.update(self.text.encode())
        else:
            d = self.data
            for a in (d.frequency_hz, d.G_storage, d.G_loss, d.prestress, d.G_storage_sd, d.G_loss_sd):
                h.update(b"-" if a is None else np.ascontiguousarray(a).tobytes())
        return h.hexdigest()

    def load(self):
        """Parse the cell's data (raises :class:`tenscell.io.data.DataError` if malformed)."""
        from ..io.data import DataError, RheologyData, parse_text

        if self.error is not None:
            raise DataError(f"{self.source}: {self.error}")
        if self.text is None:
            if not isinstance(self.data, RheologyData):
                raise TypeError(f"{self.source}: data must be a RheologyData, got {type(self.data).__name__}")
            return self.data
        return parse_text(self.text, self.source)


def read_sources(inputs) -> tuple[CellSource, ...]:
    """List a population's cells (see the module docstring for what ``inputs`` may be).

    Files are read here (their text is kept) but not parsed: a malformed file
    is reported by its own fit. Raises :class:`SourceError` when nothing can be
    listed: a missing path, a pattern or directory without cell files, an
    unreadable table, duplicate cell ids.
    """
    from .synth import SyntheticPopulation

    if isinstance(inputs, SyntheticPopulation):
        out = [CellSource(c.cell, c.condition, c.cell, data=c.data) for c in inputs.cells]
    elif isinstance(inputs, (str, os.PathLike)):
        out = _from_path(inputs)
    else:
        out = _from_memory(inputs)
    if not out:
        raise SourceError(f"{_name(inputs)}: no cells found")
    seen, dup = set(), []
    for s in out:
        (dup.append(s.cell) if s.cell in seen else seen.add(s.cell))
    if dup:
        raise SourceError(f"{_name(inputs)}: duplicate cell id(s) {', '.join(sorted(set(dup))[:5])}")
    return tuple(out)


def _name(inputs) -> str:
    return os.fspath(inputs) if isinstance(inputs, (str, os.PathLike)) else type(inputs).__name__


def _from_memory(items) -> list[CellSource]:
    from ..io.data import RheologyData

    out = []
    for k, item in enumerate(items):
        if isinstance(item, RheologyData):
            cell, cond, data = f"cell-{k:04d}", "", item
        elif isinstance(item, tuple) and len(item) in (2, 3) and isinstance(item[-1], RheologyData):
            cell, cond, data = str(item[0]), (str(item[1]) if len(item) == 3 else ""), item[-1]
        else:
            raise SourceError(f"item {k}: expected RheologyData, (cell, data) or (cell, condition, data), "
                              f"got {type(item).__name__}")
        out.append(CellSource(cell, cond, data.source if data.source != "<memory>" else cell, data=data))
    return out


def _skipped(parts) -> bool:
    return any(p.startswith(("_", ".")) for p in parts)


def _from_path(inputs) -> list[CellSource]:
    text = os.fspath(inputs)
    path = Path(text)
    if path.is_dir():
        files = sorted(p for p in path.rglob("*.csv") if p.is_file())
        return _from_files(path, files)
    if path.is_file():
        if path.suffix.lower() not in _TABLE_SUFFIXES:
            raise SourceError(f"{text}: not a directory, a pattern or a .csv/.parquet table")
        return _from_table(path)
    if _glob.has_magic(text):
        files = sorted(Path(p) for p in _glob.glob(text, recursive=True) if Path(p).is_file())
        base = Path(*_fixed_prefix(text)) if _fixed_prefix(text) else Path(".")
        return _from_files(base, files)
    raise SourceError(f"{text}: no such file or directory")


def _fixed_prefix(pattern: str) -> list[str]:
    parts = list(Path(pattern).parts[:-1])
    fixed = []
    for p in parts:
        if _glob.has_magic(p):
            break
        fixed.append(p)
    return fixed


def _from_files(base: Path, files) -> list[CellSource]:
    out = []
    for p in files:
        rel = PurePosixPath(p.relative_to(base).as_posix()) if p.is_relative_to(base) else PurePosixPath(p.name)
        if _skipped(rel.parts):
            continue
        text, error = "", None
        try:
            text = p.read_text(encoding="utf-8-sig")
        except (OSError, UnicodeDecodeError) as err:
            error = f"cannot read file: {err}"  # recorded as this cell's error, like any malformed file
        cond = str(rel.parent) if str(rel.parent) != "." else ""
        out.append(CellSource(str(rel.with_suffix("")), cond, str(p), text=text, error=error))
    return out


def _from_table(path: Path) -> list[CellSource]:
    import pandas as pd

    try:
        if path.suffix.lower() == ".csv":
            df = pd.read_csv(path, comment="#", dtype=str, keep_default_na=False, skipinitialspace=True)
        else:
            df = pd.read_parquet(path).astype(str)
    except Exception as err:  # noqa: BLE001 - any reader failure is one line naming the file
        raise SourceError(f"{path}: cannot read the table: {err}") from None
    lower = {c.strip().lower(): c for c in df.columns}
    if CELL_COLUMN not in lower:
        return [CellSource(path.stem, "", str(path), text=path.read_text(encoding="utf-8-sig"))]
    cell_col = lower[CELL_COLUMN]
    cond_col = lower.get(CONDITION_COLUMN)
    data_cols = [c for c in df.columns if c not in (cell_col, cond_col)]
    out = []
    for cell, group in df.groupby(cell_col, sort=False):
        conds = sorted(set(group[cond_col])) if cond_col else [""]
        buf = io.StringIO()
        group[data_cols].to_csv(buf, index=False)
        error = f"more than one condition for one cell: {', '.join(conds)}" if len(conds) > 1 else None
        out.append(CellSource(str(cell), conds[0], f"{path} (cell {cell})", text=buf.getvalue(), error=error))
    return out

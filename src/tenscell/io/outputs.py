"""Atomic output: a failed run leaves no half-written file."""
from __future__ import annotations

import contextlib
import csv
import json
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_path", "write_csv_rows", "write_json", "write_text"]


@contextlib.contextmanager
def atomic_path(path, *, make_parents: bool = True):
    """Yield a temporary path beside ``path``; move it into place only if the block succeeds.

    The finished file is flushed to disk before the rename; it keeps the
    permissions of the file it replaces (0644 for a new file). With
    ``make_parents=False`` a missing directory raises OSError instead of
    being created.
    """
    path = Path(path)
    if make_parents:
        path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix or ".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        try:
            mode = path.stat().st_mode & 0o777
        except OSError:
            mode = 0o644  # mkstemp makes 0600; a new output file gets the usual mode
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def write_csv_rows(path, header, rows) -> None:
    """Write a CSV file (header + rows) atomically; floats with full precision."""
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for r in rows:
            w.writerow([repr(float(v)) if isinstance(v, float) else v for v in r])


def write_json(path, obj) -> None:
    """Write JSON atomically (indented, NaN written as null)."""
    def clean(o):
        if isinstance(o, float) and o != o:
            return None
        if isinstance(o, dict):
            return {k: clean(v) for k, v in o.items()}
        if isinstance(o, (list, tuple)):
            return [clean(v) for v in o]
        return o

    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(clean(obj), indent=2, allow_nan=False) + "\n")


def write_text(path, text: str) -> None:
    """Write a text file atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)

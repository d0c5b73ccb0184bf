"""Atomic output: a failed run leaves no half-written file, and a run's files appear as a set.

Two levels:

:func:`atomic_path`
    one file: written beside its target, flushed, renamed into place.
:class:`OutputSet`
    a run's whole output directory: validated before any computation, filled
    in a staging directory beside the target, and swapped into place only when
    the run succeeded, replacing the previous set as a whole, with a
    ``manifest.json`` (command, version, time, files). On any failure or
    interrupt the previous set is untouched and the staging directory is
    removed; staging left by a killed run (SIGKILL) is removed by the next run
    that writes beside it.
"""
from __future__ import annotations

import contextlib
import csv
import ctypes
import ctypes.util
import datetime as _dt
import glob
import json
import math
import os
import shutil
import tempfile
from typing import Literal
from pathlib import Path

from .._errors import TenscellError
from .._parallel import sigint_deferred

__all__ = ["atomic_path", "write_csv_rows", "write_json", "json_ready", "json_text", "NULL_MEANS", "write_text",
           "write_bytes", "OutputSet",
           "OutputLocationError", "check_output_dir", "check_output_file", "read_manifest", "MANIFEST"]

#: name of the manifest file written into every output set
MANIFEST = "manifest.json"
_STAGING = ".tenscell-staging-"
_OLD = ".tenscell-old-"
_TEMP = ".tenscell-tmp-"


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
    _clean_stale_temps(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}{_TEMP}{os.getpid()}-", suffix=path.suffix or ".tmp",
                               dir=path.parent)
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


def _clean_stale_temps(path: Path) -> None:
    """Remove temporary files that killed writers (SIGKILL) left beside ``path``."""
    for entry in path.parent.glob(f".{glob.escape(path.name)}{_TEMP}*"):
        pid = entry.name[len(path.name) + 1 + len(_TEMP):].split("-", 1)[0]
        if pid.isdigit() and not _pid_alive(int(pid)):
            with contextlib.suppress(OSError):
                entry.unlink()


def write_csv_rows(path, header, rows) -> None:
    """Write a CSV file (header + rows) atomically; floats with full precision."""
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for r in rows:
            w.writerow([repr(float(v)) if isinstance(v, float) else v for v in r])


#: what a null stands for in tenscell's JSON files: the ``null_means`` entry of a document that has one
NULL_MEANS = ("null: no value. Either not applicable or not computed (each field's documentation says when), "
              "or a computed number that is not finite: those are listed in this document's 'non_finite' "
              "entry (JSON pointer -> 'inf', '-inf' or 'nan'), so no computed value is lost")


def json_ready(obj, *, found: dict | None = None, _at: str = ""):
    """``obj`` as plain JSON data: every non-finite float (NaN, ±inf) becomes None, recursively.

    The one JSON cleaner of tenscell: dicts, lists and tuples are walked
    (tuples become lists, keys become str), numpy scalars and arrays become
    Python numbers and lists; anything else is returned as it is. With
    ``found`` (a dict), each replaced value is recorded there under its JSON
    pointer (``"/start_rms/2": "inf"``).
    """
    if type(obj).__module__ == "numpy" and hasattr(obj, "tolist"):
        obj = obj.tolist()  # numpy scalars and arrays (any shape) as Python numbers and nested lists
    if isinstance(obj, float) and not math.isfinite(obj):
        if found is not None:
            found[_at or "/"] = "nan" if obj != obj else ("inf" if obj > 0 else "-inf")
        return None
    if isinstance(obj, dict):
        return {str(k): json_ready(v, found=found, _at=f"{_at}/{_pointer(k)}") for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_ready(v, found=found, _at=f"{_at}/{i}") for i, v in enumerate(obj)]
    return obj


def _pointer(key) -> str:
    """A JSON pointer reference token (RFC 6901)."""
    return str(key).replace("~", "~0").replace("/", "~1")


def json_text(obj, *, indent: int | None = 2, null_means: str | None = None) -> str:
    """``obj`` as JSON text: cleaned by :func:`json_ready`, never refused for a non-finite number.

    A dict document whose cleaning replaced a non-finite number gets a
    ``non_finite`` entry (JSON pointer -> ``"inf"``, ``"-inf"``, ``"nan"``)
    and a ``null_means`` entry (``null_means``, or :data:`NULL_MEANS`), so the
    value is still there for whoever reads the file; ``null_means`` given
    explicitly is written whether or not anything was replaced.
    """
    found: dict = {}
    doc = json_ready(obj, found=found)
    if isinstance(doc, dict) and (found or null_means):
        doc.setdefault("null_means", null_means or NULL_MEANS)
        if found:
            doc["non_finite"] = found
    return json.dumps(doc, indent=indent, allow_nan=False)


def write_json(path, obj, *, null_means: str | None = None) -> None:
    """Write JSON atomically (indented; non-finite numbers as null, recorded: see :func:`json_text`)."""
    with atomic_path(path) as tmp:
        tmp.write_text(json_text(obj, null_means=null_means) + "\n")


def write_text(path, text: str) -> None:
    """Write a text file atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def write_bytes(path, data: bytes) -> None:
    """Write a binary file atomically."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


class OutputLocationError(TenscellError, ValueError):
    """The output location cannot receive a run's files (message names the flag)."""


def check_output_dir(path, flag: str = "--out") -> Path:
    """Validate an output directory before any computation; return it as a Path.

    It may be missing (it is created), an empty directory, or a directory
    that holds a previous tenscell output set (it has a ``manifest.json``) —
    anything else could hold a user's own files, which a run must not replace.
    Its parent must exist or be creatable and be writable.

    Raises
    ------
    OutputLocationError
        With a one-line message naming ``flag``.
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputLocationError(f"{flag} {path}: exists and is not a directory")
    if path.is_dir() and any(path.iterdir()) and read_manifest(path) is None:
        raise OutputLocationError(
            f"{flag} {path}: directory is not empty and holds no tenscell {MANIFEST}; "
            "choose a new or empty directory (a run replaces its output directory as a whole)")
    for ancestor in path.absolute().parents:
        found = read_manifest(ancestor)
        if found is not None:
            raise OutputLocationError(
                f"{flag} {path}: inside the output set {ancestor} (of `{found.get('command') or 'tenscell'}`), "
                "which its next run replaces as a whole; choose a directory outside it")
    _check_parent(path, flag)
    if path.is_dir():
        _check_replaceable(path, flag)
    return path


#: Linux inode flags (linux/fs.h) that forbid renaming or removing a directory: immutable, append-only
_FS_IOC_GETFLAGS, _FS_IMMUTABLE_FL, _FS_APPEND_FL = 0x80086601, 0x10, 0x20


def _locked(path: Path) -> str | None:
    """"immutable" or "append-only" when the file system forbids renaming ``path`` (chattr +i / +a), else None
    (also where the flags cannot be read: another OS or file system)."""
    try:
        import array
        import fcntl

        fd = os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except (ImportError, OSError):
        return None
    try:
        buf = array.array("l", [0])
        fcntl.ioctl(fd, _FS_IOC_GETFLAGS, buf, True)
    except OSError:
        return None
    finally:
        os.close(fd)
    flags = buf[0]
    return "immutable" if flags & _FS_IMMUTABLE_FL else "append-only" if flags & _FS_APPEND_FL else None


def _check_replaceable(path: Path, flag: str) -> None:
    """A previous set at ``path`` can be swapped out at the end of the run (checked now, not after the work)."""
    locked = _locked(path)
    if locked is not None:
        raise OutputLocationError(f"{flag} {path}: the directory is {locked} (chattr), so a run cannot replace it; "
                                  f"choose another directory, or lift the flag (chattr -{locked[0]} {path})")
    parent = path.absolute().parent
    st = parent.stat()
    if st.st_mode & 0o1000 and os.geteuid() not in (0, path.stat().st_uid, st.st_uid):
        raise OutputLocationError(f"{flag} {path}: belongs to another user in the sticky directory {parent}, so a "
                                  "run cannot replace it; choose another directory")


def read_manifest(directory) -> dict | None:
    """The tenscell manifest of an output set in ``directory``, or None if it holds none."""
    try:
        text = (Path(directory) / MANIFEST).read_text(encoding="utf-8")
        doc = json.loads(text)
    except (OSError, ValueError, RecursionError):
        return None
    return doc if isinstance(doc, dict) and "tenscell_version" in doc else None


def _command_name(command: str) -> str:
    """``"tenscell fit data.csv --out x"`` -> ``"tenscell fit"`` (what kind of set it is)."""
    return " ".join(str(command).split()[:2])


def _check_parent(path: Path, flag: str) -> None:
    """The nearest existing ancestor of ``path``'s directory is a writable directory."""
    probe = path.absolute().parent
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        raise OutputLocationError(f"{flag} {path}: {probe} is not a directory")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise OutputLocationError(f"{flag} {path}: {probe} is not writable")
    # os.access trusts the permission bits; a read-only mount, /proc or a full quota refuse only an actual
    # write, which would otherwise come after the computation: try one (an empty directory, removed at once)
    try:
        os.rmdir(tempfile.mkdtemp(prefix=_TEMP, dir=probe))
    except OSError as err:
        raise OutputLocationError(f"{flag} {path}: cannot create anything in {probe} "
                                  f"({err.strerror or type(err).__name__})") from None


def check_output_file(path, flag: str) -> Path:
    """Validate a single output file's location before any computation; return it as a Path.

    It must not be a directory, and its directory must exist (or be creatable)
    and be writable.

    Raises
    ------
    OutputLocationError
        With a one-line message naming ``flag``.
    """
    trailing = str(path).endswith(("/", os.sep))
    path = Path(path)
    if trailing or path.is_dir():
        raise OutputLocationError(f"{flag} {path}: is a directory; give a file name")
    _check_parent(path, flag)
    return path


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _clean_stale(target: Path) -> None:
    """Remove staging left by dead runs beside ``target``; restore a set a dead run moved aside."""
    parent = target.absolute().parent
    if not parent.is_dir():
        return
    for entry in parent.glob(f".{glob.escape(target.name)}{_STAGING}*"):
        pid = entry.name.rsplit("-", 1)[-1]
        if not pid.isdigit() or not _pid_alive(int(pid)):
            shutil.rmtree(entry, ignore_errors=True)
    for entry in parent.glob(f".{glob.escape(target.name)}{_OLD}*"):
        pid = entry.name.rsplit("-", 1)[-1]
        if pid.isdigit() and _pid_alive(int(pid)):
            continue
        if not target.exists():
            os.rename(entry, target)  # a run died between its two renames: the old set comes back
        else:
            shutil.rmtree(entry, ignore_errors=True)


_RENAME_EXCHANGE = 2


def _exchange(a: Path, b: Path) -> bool:
    """Atomically swap two directories (Linux renameat2); False where unsupported."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd = -100
    rc = fn(at_fdcwd, os.fsencode(str(a)), at_fdcwd, os.fsencode(str(b)), _RENAME_EXCHANGE)
    return rc == 0


class OutputSet:
    """A run's output directory, committed as a whole.

    Parameters
    ----------
    target : path
        The output directory (validated by :func:`check_output_dir` at construction).
    command : str
        What produced the set, recorded in the manifest (e.g. ``"tenscell fit data.csv"``).
    flag : str
        The option that named ``target``, for error messages.

    Notes
    -----
    Entering may happen long after construction; everything written inside
    the block goes to the staging directory, and leaving it without an
    exception moves the set into place. An exception (including
    KeyboardInterrupt) removes the staging directory and leaves the previous
    set as it was.

    Examples
    --------
    ::

        out = OutputSet(args.out, command="tenscell fit ...")   # validate first
        ...                                                        # compute
        with out as d:                                             # d: the staging directory
            write_csv_rows(d / "fit.csv", header, rows)
        # here the complete set is at args.out
    """

    def __init__(self, target, *, command: str = "", flag: str = "--out"):
        self.target = check_output_dir(target, flag)
        self.command = command
        self.flag = flag
        self.staging: Path | None = None
        _clean_stale(self.target)
        previous = read_manifest(self.target)
        if previous is not None and command and previous.get("command"):
            mine, theirs = _command_name(command), _command_name(previous["command"])
            if mine != theirs:
                raise OutputLocationError(
                    f"{flag} {self.target}: holds the output set of `{previous['command']}`; `{mine}` would "
                    "replace it as a whole; choose another directory (or delete that one)")

    def __enter__(self) -> Path:
        check_output_dir(self.target, self.flag)
        parent = self.target.absolute().parent
        parent.mkdir(parents=True, exist_ok=True)
        self.staging = parent / f".{self.target.name}{_STAGING}{os.getpid()}"
        shutil.rmtree(self.staging, ignore_errors=True)
        self.staging.mkdir()
        return self.staging

    def __exit__(self, exc_type, exc, tb) -> Literal[False]:
        staging, self.staging = self.staging, None
        assert staging is not None
        # a second Ctrl-C must not cut the clean-up or the swap in half: it is held until they are done
        with sigint_deferred():
            if exc_type is not None:
                shutil.rmtree(staging, ignore_errors=True)
                return False
            try:
                self._write_manifest(staging)
                self._commit(staging)
            except OSError as err:
                shutil.rmtree(staging, ignore_errors=True)
                raise OutputLocationError(f"{self.flag} {self.target}: the new set could not be put in place "
                                          f"({err.strerror or type(err).__name__}); the previous one is as it "
                                          "was") from err
            except BaseException:
                shutil.rmtree(staging, ignore_errors=True)
                raise
        return False

    def _write_manifest(self, staging: Path) -> None:
        from .._version import __version__
        files = sorted(str(p.relative_to(staging)) for p in staging.rglob("*") if p.is_file())
        write_json(staging / MANIFEST, {
            "command": self.command, "tenscell_version": __version__,
            "finished_utc": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
            "files": files})

    def _commit(self, staging: Path) -> None:
        target = self.target.absolute()
        if not target.exists():
            os.rename(staging, target)
            return
        if _exchange(staging, target):
            shutil.rmtree(staging, ignore_errors=True)  # now holds the previous set
            return
        old = target.parent / f".{target.name}{_OLD}{os.getpid()}"
        os.rename(target, old)
        try:
            os.rename(staging, target)
        except BaseException:
            os.rename(old, target)  # the previous set goes back; a crash right here is undone by _clean_stale
            raise
        shutil.rmtree(old, ignore_errors=True)

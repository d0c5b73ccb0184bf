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
from importlib import resources
from pathlib import Path

import numpy as np

from .._errors import option
from .._ranges import range_problem
from .columns import DataError, read_text_file
from .outputs import atomic_path
from .provenance import Provenance
from .rheology import (_ABS, _ABS_SD, _ALL_COLUMNS, _CANONICAL, _CARTESIAN_COLUMNS, _COLUMN_QUANTITY, _FREQUENCY,
                       _LOSS, _LOSS_SD, _PHASE, _PHASE_SD, _POLAR_COLUMNS, _PRESTRESS, _QUANTITY_OF, _STORAGE,
                       _STORAGE_SD, _UNIT_OF, RheologyData, _error, checked)

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

# Short name -> file in the package's data directory. A tuple, not a dict,
# so that no caller can alter the registry.
_BUNDLED = (
    ("fabry2001", "fabry2001_hasm_powerlaw.csv"),
    ("stamenovic2002", "stamenovic2002_hasm_0p1Hz.csv"),
)


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

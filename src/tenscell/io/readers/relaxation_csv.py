"""tenscell's stress relaxation CSV (``time_s, relaxation_modulus_Pa`` or ``time_s, relaxation_modulus_relative``),
read by :func:`tenscell.io.relaxation_data.read_relaxation_csv` (comma, semicolon or tab separated)."""
from __future__ import annotations

from ..relaxation_data import COLUMNS, is_relaxation_header, read_relaxation_csv
from ._blocks import Probe, Request

__all__ = ["LAYOUT", "EXPECTED", "detect", "read"]

LAYOUT = "tenscell relaxation CSV"
EXPECTED = "tenscell's relaxation CSV (time_s, relaxation_modulus_Pa; or time_s, relaxation_modulus_relative)"
_OWN = frozenset(c.lower() for c in COLUMNS)


def detect(probe: Probe) -> int:
    """2 when the header names only the relaxation layout's columns, a time and a modulus among them; else 0."""
    if probe.suffix in (".xlsx", ".xlsm"):
        return 0
    for s in probe.lines:
        if s.strip() and not s.lstrip().startswith("#"):
            sep = next((d for d in (",", ";", "\t") if d in s), ",")
            names = {n.strip().lower() for n in s.split(sep)}
            return 2 if names <= _OWN and is_relaxation_header(s, probe.source) else 0
    return 0


def read(probe: Probe, request: Request):
    """The file through :func:`~tenscell.io.relaxation_data.read_relaxation_csv` (its own columns: a column map,
    units, a step or a sheet do not apply)."""
    from ..columns import DataError

    if request.columns is not None or request.units:
        raise DataError(f"{probe.source}: a relaxation file names its own columns and units ({EXPECTED}); a column "
                        "map or units do not apply")
    return read_relaxation_csv(probe.path, min_points=max(2, request.min_points))

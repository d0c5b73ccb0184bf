"""tenscell's own CSV layouts: moduli (``frequency_Hz, G_storage_Pa, G_loss_Pa``...) and creep compliance
(``time_s, creep_compliance_per_Pa``), read by :func:`tenscell.io.data.read_csv` and
:func:`tenscell.io.creep_data.read_creep_csv` (comma, semicolon or tab separated)."""
from __future__ import annotations

from ..creep_data import is_creep_header, read_creep_csv
from ..data import read_csv
from ._blocks import Probe, Request

__all__ = ["LAYOUT", "EXPECTED", "detect", "read", "OWN_COLUMNS"]

LAYOUT = "tenscell CSV"
EXPECTED = ("tenscell's CSV (frequency_Hz, G_storage_Pa, G_loss_Pa; or time_s, creep_compliance_per_Pa)")
#: the column names of tenscell's own layouts (lower case)
OWN_COLUMNS = frozenset({"frequency_hz", "prestress_pa", "g_storage_pa", "g_loss_pa", "g_storage_sd_pa",
                         "g_loss_sd_pa", "g_abs_pa", "phase_deg", "g_abs_sd_pa", "phase_sd_deg", "time_s",
                         "creep_compliance_per_pa", "creep_compliance_sd_per_pa"})


def header(probe: Probe) -> tuple[int, str] | None:
    """(1-based line, text) of the first line that is neither blank nor a ``#`` comment, or None."""
    for k, s in enumerate(probe.lines, start=1):
        if s.strip() and not s.lstrip().startswith("#"):
            return k, s
    return None


def detect(probe: Probe) -> int:
    """2 when the header names only tenscell's own columns, else 0."""
    if probe.suffix in (".xlsx", ".xlsm"):
        return 0
    found = header(probe)
    if found is None:
        return 0
    line = found[1]
    sep = next((d for d in (",", ";", "\t") if d in line), ",")
    names = [n.strip().lower() for n in line.split(sep)]
    return 2 if names and all(n in OWN_COLUMNS for n in names) else 0


def read(probe: Probe, request: Request):
    """The file through :func:`~tenscell.io.data.read_csv` or :func:`~tenscell.io.creep_data.read_creep_csv`;
    with a column map or units asked for, as a table (:mod:`.table`)."""
    if request.columns is not None or request.units:
        from .table import read as read_as_table

        return read_as_table(probe, request)
    if is_creep_header(probe.text, probe.source):
        return read_creep_csv(probe.path, min_points=request.min_points, accept=request.accept)
    return read_csv(probe.path, min_points=request.min_points, accept=request.accept)

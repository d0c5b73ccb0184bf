"""What a study on the protocol (:mod:`tenscell.studies.protocol`) writes: every table, figure and page of its
result, into an open output set."""
from __future__ import annotations

from pathlib import Path

__all__ = ["write_study_result"]


def write_study_result(out: Path, result) -> list[str]:
    """Every table (``NAME.csv``), figure and page of a :class:`~tenscell.studies.protocol.StudyResult` into
    ``out``: the names written."""
    from .. import plotting
    from ..io.outputs import write_csv_rows, write_text

    for t in result.tables:
        write_csv_rows(out / f"{t.name}.csv", list(t.columns), t.rows)
    for f in result.figures:
        plotting.save(f.draw(), out / f.name)
    for name, text in result.pages:
        write_text(out / name, text)
    return list(result.files())

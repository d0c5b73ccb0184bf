"""What a study on the protocol (:mod:`tenscell.studies.protocol`) writes: every table, figure and page of its
result, into an open output set."""
from __future__ import annotations

from pathlib import Path

__all__ = ["write_study_result"]


def write_study_result(out: Path, result, log=None) -> list[str]:
    """Every table (``NAME.csv``, its named columns), figure (drawn through its plotter) and page of a
    :class:`~tenscell.studies.protocol.StudyResult` into ``out``: the names written. ``log`` (if given) hears of
    each figure as it is drawn."""
    from .. import plotting
    from ..io.outputs import write_csv_rows, write_text

    for t in result.tables:
        write_csv_rows(out / f"{t.name}.csv", list(t.columns), t.rows)
    for f in result.figures:
        if log is not None:
            log(f"drawing {f.name}")
        plotting.save(f.draw(), out / f.name)
    for name, text in result.pages:
        write_text(out / name, text)
    return list(result.files())

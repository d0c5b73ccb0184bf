"""What a data set was read from and how: the file, its layout, the step, the temperature, the unit conversions.

Every reader attaches a :class:`Provenance` to the :class:`~tenscell.io.data.RheologyData` or
:class:`~tenscell.io.creep_data.CreepData` it builds (``data.provenance``); transformations of the data
(a stated prestress, binning) add a note. It is frozen, a read-only mapping (``dict(data.provenance)`` is
plain JSON data for fit.json), and :meth:`Provenance.line` is the one line the command line prints and a
report can quote: ``read sweeps.txt (TA TRIOS LIMS export, step 9 of 20 'Frequency sweep (70.0 °C)',
70 °C): 17 points; frequency 'Angular frequency' rad/s → Hz; G' 'Storage modulus' MPa → Pa; ...``.
"""
from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, fields, replace
from typing import Any

__all__ = ["Provenance", "SI_UNITS"]

#: the unit tenscell works in for each quantity a column can hold (what a conversion ends in)
SI_UNITS = {"frequency": "Hz", "storage": "Pa", "loss": "Pa", "magnitude": "Pa", "phase": "rad", "loss_tangent": "",
            "prestress": "Pa", "storage_sd": "Pa", "loss_sd": "Pa", "time": "s", "compliance": "1/Pa",
            "compliance_sd": "1/Pa"}
# short names of the quantities in the one-line text
_SHORT = {"frequency": "frequency", "storage": "G'", "loss": "G''", "magnitude": "|G*|", "phase": "phase",
          "loss_tangent": "tan δ", "prestress": "prestress", "storage_sd": "sd G'", "loss_sd": "sd G''",
          "time": "time", "compliance": "J", "compliance_sd": "sd J"}


@dataclass(frozen=True)
class Provenance(Mapping):
    """Where a data set came from and what was done to read it (frozen; a read-only mapping of its fields).

    Parameters
    ----------
    file : str
        The file as given (or the name of the source: ``"<DataFrame>"``, a bundled data set).
    layout : str
        What the file was read as: ``"TA TRIOS LIMS export"``, ``"tenscell CSV"``, ``"table"``...
    step : int, optional
        The step (TRIOS) or interval (RheoCompass) read, 1-based as the reader numbers them.
    step_name : str, optional
        Its name in the file.
    step_word : str
        What the format calls a step: ``"step"`` (TRIOS), ``"interval"`` (RheoCompass).
    steps : int, optional
        How many steps the file holds.
    temperature_c : float, optional
        The step's temperature (°C), from its Temperature column, name or metadata.
    columns : tuple of (quantity, header, unit)
        Each quantity read (``"frequency"``, ``"storage"``, ``"loss"``, ``"time"``, ``"compliance"``...), the
        column's header as in the file and the unit it was read in ("" for dimensionless).
    points : int, optional
        The number of points read.
    notes : tuple of str
        What was done after reading, in order: points dropped, a prestress stated, binning.
    accepted : tuple of str
        The reader's checks the user overrode (``accept=``; :data:`tenscell.io.checks.CHECKS`).
    """

    file: str
    layout: str = ""
    step: int | None = None
    step_name: str | None = None
    step_word: str = "step"
    steps: int | None = None
    temperature_c: float | None = None
    columns: tuple[tuple[str, str, str], ...] = ()
    points: int | None = None
    notes: tuple[str, ...] = ()
    accepted: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "file", str(self.file))
        object.__setattr__(self, "columns", tuple((str(q), str(h), str(u)) for q, h, u in self.columns))
        object.__setattr__(self, "notes", tuple(str(n) for n in self.notes))
        object.__setattr__(self, "accepted", tuple(str(a) for a in self.accepted))

    # ---- a read-only mapping of plain JSON data ----------------------------------------------------
    def as_dict(self) -> dict[str, Any]:
        """The fields as plain JSON data (columns as a list of {quantity, column, unit, to}); the one-line text too."""
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "columns":
                value = [{"quantity": q, "column": h, "unit": u, "to": SI_UNITS.get(q, u)} for q, h, u in value]
            elif isinstance(value, tuple):
                value = list(value)
            out[f.name] = value
        out["text"] = self.line()
        return out

    def __getitem__(self, key: str) -> Any:
        return self.as_dict()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.as_dict())

    def __len__(self) -> int:
        return len(self.as_dict())

    # ---- derived copies --------------------------------------------------------------------------------
    def read(self, parsed) -> "Provenance":
        """A copy completed by what a table parse found (:class:`tenscell.io.columns.Parsed`): the columns and
        units read, the number of points, what was dropped while reading."""
        return replace(self, columns=tuple(parsed.columns), points=len(parsed.where) or None,
                       notes=self.notes + tuple(parsed.notes))

    def noted(self, note: str) -> "Provenance":
        """A copy with one more note (what was done to the data after reading)."""
        return replace(self, notes=self.notes + (str(note),))

    def conversions(self) -> tuple[str, ...]:
        """The unit conversions applied, e.g. ``"G' MPa → Pa"`` (none for a column already in tenscell's unit)."""
        out = []
        for q, _, unit in self.columns:
            si = SI_UNITS.get(q, unit)
            if unit and unit != si and q != "phase":
                out.append(f"{_SHORT.get(q, q)} {unit} → {si}")
        return tuple(out)

    def line(self) -> str:
        """One line naming what was read: file, layout, step, temperature, points, columns and conversions."""
        # a bundled data set's name already says where it comes from
        where = [self.layout] if self.layout and self.layout not in self.file else []
        if self.step is not None:
            of = f" of {self.steps}" if self.steps else ""
            where.append(f"{self.step_word} {self.step}{of}" + (f" {self.step_name!r}" if self.step_name else ""))
        if self.temperature_c is not None:
            where.append(f"{self.temperature_c:g} °C")
        head = f"read {os.path.basename(self.file) or self.file}" + (f" ({', '.join(where)})" if where else "")
        parts = [f"{self.points:,} points" if self.points is not None else ""]
        for q, header, unit in self.columns:
            si = SI_UNITS.get(q, unit)
            shown = f"{unit} → {si}" if unit and unit != si and q != "phase" else unit
            parts.append(f"{_SHORT.get(q, q)} {header!r}" + (f" {shown}" if shown else ""))
        parts += list(self.notes)
        if self.accepted:  # each "check: problem"; the line names the checks, the mapping keeps the problems
            parts.append(f"read despite the checks: {', '.join(a.split(':', 1)[0] for a in self.accepted)}")
        body = "; ".join(p for p in parts if p)
        return head + (f": {body}" if body else "")

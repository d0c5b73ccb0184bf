"""The allowed range of every physical quantity a user gives: one table for command-line flags and data files.

The command line (:mod:`tenscell.cli._args`) checks its flags against :data:`RANGES`
at parse time; the data readers (:class:`tenscell.io.data.RheologyData`,
:class:`tenscell.io.creep_data.CreepData`, and so every reader and importer that
builds them) check each value of a data file against the same table when the file
is read, naming file, line and column, before any computation.

Standard library only: building the command-line parser imports this module.
"""
from __future__ import annotations

__all__ = ["RANGES", "range_problem"]

#: allowed range of each physical quantity: (lowest, highest, unit), a closed interval in that unit.
#: The model is linear algebra on these values and their products (ω·c, P·Kp + EA/l, |J|², G'/G'');
#: inside these bounds every such product stays far from float64 overflow and underflow (1e±308),
#: and outside them a result would be inf, NaN or rounding noise. They are far beyond any cell or
#: instrument. A data file's prestress is in Pa, the flag's in N (the paper's Pa): the same numbers.
#: The moduli share the prestress range (G' scales with P), a compliance is its reciprocal, a time
#: the reciprocal of a frequency.
RANGES: dict[str, tuple[float, float, str]] = {
    "prestress": (1e-30, 1e30, "N"),
    "EA": (1e-30, 1e30, "N"),
    "c": (1e-30, 1e30, "N·s/m"),
    "L": (1e-9, 1e6, "m"),
    "frequency": (1e-12, 1e12, "Hz"),
    "modulus": (1e-30, 1e30, "Pa"),
    "compliance": (1e-30, 1e30, "1/Pa"),
    "time": (1e-12, 1e12, "s"),
}

#: the flag that takes each quantity, for messages about data files (the user knows the flags' ranges)
_FLAGS = {"prestress": "--prestress", "EA": "--EA", "c": "--c", "L": "--L", "frequency": "--freq"}


def range_problem(quantity: str, value: float, unit: str | None = None, scale: float = 1.0) -> str | None:
    """None if ``value`` lies in the range of ``quantity``; else what is wrong, in words.

    ``value`` is in the table's unit. ``unit`` overrides the table's unit in the message (a data file's
    prestress is in Pa); with ``scale``, the value of one ``unit`` in the table's unit (1e6 for MPa against
    Pa, 1/2π for rad/s against Hz), the value and the bounds are stated in ``unit``, as the user typed them.
    E.g. ``"1e+300 Hz is outside [1e-12, 1e+12] Hz, the range tenscell accepts for a frequency (as for --freq)"``.
    """
    lo, hi, default_unit = RANGES[quantity]
    if lo <= value <= hi:
        return None
    u = default_unit if unit is None else unit
    flag = f" (as for {_FLAGS[quantity]})" if quantity in _FLAGS else ""
    return (f"{value / scale:g} {u} is outside [{lo / scale:g}, {hi / scale:g}] {u}, the range tenscell accepts "
            f"for a {quantity}{flag}")

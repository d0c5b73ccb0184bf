"""Every file tenscell reads, one module per format behind one registry.

:func:`read_data` asks each reader of :data:`READERS` how sure it is that a file is its format and hands the
file to the surest (ties in the registry's order); every reader ends through the same parse, checks and
provenance (:mod:`._blocks`, :func:`tenscell.io.importers.build`).

Adding a format
---------------
A module in this package with

``LAYOUT``
    what it reads, in words (``"TA TRIOS export"``);
``EXPECTED``
    how a file of that format looks, for the message of a file no reader recognises;
``detect(probe) -> int``
    2: the file is this format; 1: it looks like it (the reader is then asked to read it only when no reader is
    sure, and says what it found); 0: not this format. ``probe`` (:class:`~._blocks.Probe`) holds the path and,
    read once, the text;
``read(probe, request)``
    the :class:`~tenscell.io.data.RheologyData` or :class:`~tenscell.io.creep_data.CreepData` the file holds, for
    a :class:`~._blocks.Request` (columns, units, step, temperature, sheet, min_points, accept) — usually through
    :func:`~._blocks.choose` and :func:`~._blocks.read_block`, or :func:`tenscell.io.importers.build`;

and its name in :data:`READERS`: two files in all.
"""
from __future__ import annotations

import os
from importlib import import_module
from typing import Any, Mapping

from ..._errors import option
from ..columns import ColumnMap, DataError
from ._blocks import TEMPERATURE_TOLERANCE_C, Probe, Request

__all__ = ["READERS", "read_data", "detect_layout", "expected", "TEMPERATURE_TOLERANCE_C", "Probe", "Request"]

#: the readers, in the order that breaks ties (module names in this package)
READERS = ("trios", "rheocompass", "excel", "tenscell_csv", "relaxation_csv", "table")


def _reader(name: str):
    return import_module(f".{name}", __name__)


def expected() -> str:
    """Every format tenscell reads, for the message of a file none recognises."""
    return "; ".join(_reader(name).EXPECTED for name in READERS)


def detect_layout(path: str | os.PathLike[str] | Probe) -> str:
    """The name of the reader that reads ``path`` (one of :data:`READERS`), from the file's content: the surest,
    ties broken by the registry's order."""
    probe = path if isinstance(path, Probe) else Probe(path)
    scores = [(_reader(name).detect(probe), -k, name) for k, name in enumerate(READERS)]
    return max(scores)[2]


def read_data(path: str | os.PathLike[str], columns: ColumnMap | Mapping[str, Any] | None = None, *,
              step: int | str | None = None, temperature: float | None = None, sheet: str | int | None = None,
              min_points: int = 1, accept=(), **units: Any):
    """Measured moduli, creep compliance or stress relaxation from any file tenscell reads, whatever wrote it.

    The layout is recognised from the content: a TRIOS export (:func:`~tenscell.io.readers.trios.read_trios`),
    a RheoCompass export (:func:`~tenscell.io.readers.rheocompass.read_rheocompass`), an Excel workbook,
    tenscell's own CSV (moduli or creep), or a CSV/TSV table whose headers say what they hold (``Angular
    Frequency``, ``G' [Pa]``, ``time (s)``, ``J(t) (1/Pa)``, ``Creep Compliance``...; see
    :data:`~tenscell.io.importers.KNOWN_HEADERS`), with units in the headers or in a units row under them.
    ``columns`` (a :class:`ColumnMap` or dict) says what a table's columns hold when the headers do not.

    Parameters
    ----------
    path : str or PathLike
        A file, or ``"bundled:NAME"`` for a data set shipped with tenscell (:func:`tenscell.io.data.bundled`:
        ``bundled:fabry2001``, ``bundled:stamenovic2002``), read in its own layout.
    columns : ColumnMap or dict, optional
    step : int or str, optional
        TRIOS step or RheoCompass interval: its number, or its name.
    temperature : float, optional
        °C: choose the step or interval at this temperature.
    sheet : str or int, optional
        Excel sheet; default the first.
    min_points : int
    accept : str or sequence of str, optional
        Checks of :mod:`tenscell.io.checks` to skip (``"outliers"``, ``"one-frequency"``, ``"decreasing"``,
        ``"point-count"``): read data they would refuse, recorded in the data's provenance.
    **units
        Unit fields of :class:`ColumnMap` (``modulus_unit="Pa"``...).

    Returns
    -------
    RheologyData, CreepData or RelaxationData
        With ``provenance``: the file, the layout, the step and temperature, the columns, the unit conversions.

    Raises
    ------
    DataError
        One line naming the file: what is wrong and where, or, for a layout tenscell does not recognise, what it
        expected.
    """
    if isinstance(path, str) and path.lower().startswith("bundled:"):  # as on the command line
        return _bundled(path, columns, step, temperature, sheet, units)
    request = Request(columns=columns, units=units, step=step, temperature=temperature, sheet=sheet,
                      min_points=min_points, accept=accept)
    probe = Probe(path)
    name = detect_layout(probe)
    if name in ("table", "tenscell_csv", "excel") and (step is not None or temperature is not None):
        chosen = option("step", step) if step is not None else option("temperature", temperature)
        raise DataError(f"{path}: {chosen} chooses a step of a TRIOS or RheoCompass export; this file is "
                        f"{'an Excel workbook' if name == 'excel' else 'a plain table'}")
    if name != "excel" and sheet is not None:
        raise DataError(f"{path}: {option('sheet', sheet)} chooses a sheet of an Excel workbook; this file is not one")
    return _reader(name).read(probe, request)


def _bundled(path: str, columns, step, temperature, sheet, units):
    """A data set shipped with tenscell; the options that say how to read a file are refused (it has its own
    layout)."""
    from ..data import bundled

    given = ([option("columns")] if columns is not None else []) + [
        option(name, value) for name, value in (("step", step), ("temperature", temperature), ("sheet", sheet),
                                                *sorted(units.items())) if value is not None]
    if given:  # option() marks: a Python keyword here, the flag on the command line
        raise DataError(f"{path}: {given[0]} says how to read a file; this is a data set shipped with tenscell, in "
                        "its own layout")
    return bundled(path.split(":", 1)[1])

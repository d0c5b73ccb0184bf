"""Helpers shared by the studies."""
from __future__ import annotations

import numpy as np

from .._checks import positive_array

__all__ = ["grid", "reference_probe", "REFERENCE_PROBE"]


def grid(name, values, unit):
    """A 1-D grid of positive values (``unit`` for the message)."""
    return np.atleast_1d(positive_array(name, values, unit=unit)).ravel()


def reference_probe():
    """Four points of the references' validity map (:func:`tenscell.studies.references.prestress_map`): the paper
    cell built at four references q0(α, δ) and linearized. One point is the unit of work of the studies that build
    reference cells (a study's estimate, :mod:`tenscell.studies.protocol`)."""
    from .references import MAP_ALPHA, MAP_DELTA, PRESTRESS, prestress_map

    return prestress_map(MAP_ALPHA[10:12], MAP_DELTA[10:12], P=PRESTRESS[1])


def _probe_task():
    from .protocol import Task

    return Task("four reference cells", "reference point", reference_probe, weight=4.0)


#: the calibration probe of one unit "reference point" (4 units)
REFERENCE_PROBE = _probe_task()

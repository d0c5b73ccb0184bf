"""Helpers shared by the studies."""
from __future__ import annotations

import numpy as np

from .._checks import positive_array

__all__ = ["grid"]


def grid(name, values, unit):
    """A 1-D grid of positive values (``unit`` for the message)."""
    return np.atleast_1d(positive_array(name, values, unit=unit)).ravel()

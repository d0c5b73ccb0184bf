"""Rheometer exports and the one reader that recognises any layout: the names of :mod:`tenscell.io.readers`.

Kept for code that imports them from here; each format is a module of :mod:`tenscell.io.readers`
(:mod:`~tenscell.io.readers.trios`, :mod:`~tenscell.io.readers.rheocompass`, ...) behind its registry.
"""
from __future__ import annotations

from .readers import TEMPERATURE_TOLERANCE_C, detect_layout, read_data
from .readers.rheocompass import read_rheocompass
from .readers.trios import read_trios

__all__ = ["read_data", "read_trios", "read_rheocompass", "detect_layout", "TEMPERATURE_TOLERANCE_C"]

"""Deprecated since 0.3.0, removed in 0.4.0: this module of tenscell 0.2.0 is gone; importing it warns, and so
does each of its names, found in its new home (:data:`tenscell._deprecated.MOVED`)."""
from .._deprecated import gone_module

__all__, __getattr__ = gone_module(__name__)

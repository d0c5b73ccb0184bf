"""Deprecated since 0.3.0, removed in 0.4.0: this module of tenscell 0.2.0 is gone (one fitting stack: every fit is
a model). Importing it warns, and so does each of its names, found in its new home
(:data:`tenscell._deprecated.MOVED`); ``fit_mechanism`` calls :func:`tenscell.fitting.fit`."""
import warnings

from .._deprecated import REMOVED_IN, SINCE, gone_module

__all__, __getattr__ = gone_module(__name__)
__all__ += ["fit_mechanism"]


def fit_mechanism(data, model, cell=None, **options):
    """Deprecated: ``fit(data, cell, model=model, **options)`` (:func:`tenscell.fitting.fit`), a FitResult."""
    from .entry import fit

    warnings.warn(f"tenscell.fitting.fit_mechanism is deprecated since {SINCE} and will be removed in {REMOVED_IN}: "
                  "use tenscell.fitting.fit(data, model=mechanism), which returns a FitResult", DeprecationWarning,
                  stacklevel=2)
    return fit(data, cell, model=model, **options)

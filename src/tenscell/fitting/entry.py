"""``tenscell.fitting.fit``: the per-tendon Voigt cell, or with ``model=`` any mechanism, through the same search."""
from __future__ import annotations

import functools

from . import search
from .models.mechanism import PER_TENDON_VOIGT

__all__ = ["fit"]

#: the options of :func:`tenscell.fitting.search.fit` a mechanism fit takes too
MECHANISM_OPTIONS = ("starts", "seed", "jobs", "tolerance", "hops", "patience", "max_nfev", "polish",
                     "polish_effort", "bounds", "fixed", "max_points", "progress")


@functools.wraps(search.fit)
def fit(data, cell=None, *, model=None, **options):
    if model is None or model == PER_TENDON_VOIGT:
        return search.fit(data, cell, **options)
    from .mechanism_fit import fit_mechanism

    other = sorted(set(options) - set(MECHANISM_OPTIONS))
    if other:
        raise ValueError(f"{', '.join(other)}: option(s) of the per-tendon fit, not of model={model!r}")
    return fit_mechanism(data, model, cell, **options)


_MODEL_DOC = """    model : str or Mechanism, optional
        Fit a mechanism instead of the per-tendon Voigt cell (a name of
        :data:`tenscell.fitting.models.mechanism.MECHANISMS` or a spec): delegates to
        :func:`tenscell.fitting.mechanism_fit.fit_mechanism` with the search
        options above and returns a
        :class:`~tenscell.fitting.mechanism_fit.MechanismFit`; ``tendons``,
        ``damping``, ``initial`` and the activity constraints do not apply.
        ``"voigt-per-tendon"`` is the per-tendon fit itself.

"""
_doc = search.fit.__doc__ or ""
fit.__doc__ = _doc.replace("    Returns\n    -------\n    FitResult", _MODEL_DOC + "    Returns\n    -------\n"
                           "    FitResult, or MechanismFit with ``model``", 1)

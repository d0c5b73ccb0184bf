"""The conventions every public result object follows (cells, linear models, responses, fits, studies...).

A result is a frozen dataclass declared with ``repr=False`` and gives

``__repr__``
    a few lines built with :func:`format_repr`: what it is, its size, its
    headline numbers — never the arrays themselves;
``to_dataframe()``
    a :class:`pandas.DataFrame` whose column names carry their units
    (``frequency_Hz``, ``G_storage_Pa``, ``time_s``, ``EA_N``...), built with
    :func:`dataframe` so pandas is imported only when asked for; a float
    column either ends in one of :data:`UNIT_SUFFIXES` or is one of the
    dimensionless names in :data:`DIMENSIONLESS`;
``plot(ax=None, ...)``
    draws on the given matplotlib axes (or a new figure's) and returns the
    axes; the drawing code lives in :mod:`tenscell.plotting`, which never
    chooses a backend.

How a result reaches the plotting layer
---------------------------------------
Results are computed in early stages of the pipeline (``model/``,
``linear/``, ``response``...) and drawn by the last one (``plotting/``), which
imports them; an import the other way would run back up the pipeline (and
load matplotlib with the physics). As python-control keeps its response
objects apart from its plotting module, a result's ``plot()`` only names the
drawing function it wants: ``plotter("structure_3d")(self, ax=ax)``.
:func:`plotter` imports :mod:`tenscell.plotting` on first use; on import, that
package registers every drawing function it defines
(:func:`register_plotters`). This is the one place a result reaches
``plotting/``; ``tests/test_architecture.py`` checks that no other does. A
result that writes its own report reaches ``reports/`` the same way:
``reporter("population_markdown")``, filled by :mod:`tenscell.reports` on
import (:func:`register_reporters`).
"""
from __future__ import annotations

import math
from collections import Counter
from importlib import import_module
from typing import TYPE_CHECKING, Any, Callable, Iterable, Mapping

import numpy as np

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["format_repr", "dataframe", "span", "counts", "UNIT_SUFFIXES", "DIMENSIONLESS", "has_unit", "plotter",
           "register_plotters", "reporter", "register_reporters", "plus_minus", "ln_error", "CORRELATION_THRESHOLD",
           "LN_FACTOR_FROM", "MAX_LISTED_CORRELATIONS", "correlation_text"]

#: unit suffixes of DataFrame columns (SI, written out without symbols so they are valid identifiers)
UNIT_SUFFIXES = (
    "_Hz", "_rad_per_s", "_Pa", "_kPa", "_N", "_m", "_s", "_per_s", "_rad", "_deg", "_N_per_m", "_Ns_per_m",
    "_m_per_N", "_per_Pa", "_m_per_Ns", "_Pa_s", "_J", "_percent",
)
#: float columns that are dimensionless by definition (the name says what they are)
DIMENSIONLESS = frozenset({
    "T0", "min_T0", "loss_tangent", "alpha", "exponent", "rms_log", "max_rel", "rms_log10_error", "relative_error",
    "weight_fraction", "elasticity", "thd",
})


def format_repr(title: str, *lines: str) -> str:
    """``<title>`` then each line indented by two spaces (keep it to a handful of lines)."""
    return "\n".join([f"<{title}>", *("  " + line for line in lines)])


def dataframe(columns: Mapping[str, Any], attrs: Mapping[str, Any] | None = None) -> pd.DataFrame:
    """A DataFrame from unit-named columns; ``attrs`` (units, parameters) go to ``DataFrame.attrs``."""
    import pandas as pd

    df = pd.DataFrame(dict(columns))
    if attrs:
        df.attrs.update(attrs)
    return df


def span(values: Any, unit: str = "", fmt: str = ".4g") -> str:
    """``"a – b unit"`` for the finite range of ``values``, ``"a unit (all)"`` when they are all equal."""
    v = np.asarray(values, dtype=float).ravel()
    v = v[np.isfinite(v)]
    u = f" {unit}" if unit else ""
    if v.size == 0:
        return "none"
    lo, hi = float(v.min()), float(v.max())
    if lo == hi:
        return f"{lo:{fmt}}{u}" + (" (all)" if v.size > 1 else "")
    return f"{lo:{fmt}} – {hi:{fmt}}{u}"


def counts(labels: Iterable[str]) -> str:
    """``"24 actin, 9 intermediate_filament"`` in order of first appearance."""
    return ", ".join(f"{n} {name}" for name, n in Counter(labels).items())


def has_unit(column: str) -> bool:
    """Whether a float column's name states its unit (or is a known dimensionless quantity)."""
    return column in DIMENSIONLESS or column.endswith(UNIT_SUFFIXES)


#: correlations at least this strong (in absolute value) are listed beside the standard errors, strongest first:
#: lmfit's default (``fit_report(min_correl=0.1)``); fit.json keeps every such pair, a text shows the strongest
#: :data:`MAX_LISTED_CORRELATIONS` and says how many more there are
CORRELATION_THRESHOLD = 0.1
#: most correlation pairs a report or repr lists ("and N more" after them)
MAX_LISTED_CORRELATIONS = 20
#: a relative error of an ln-parameter at least this large is shown as a factor ×/÷ f, not as ±x %: the fit works in
#: ln-parameters, so one standard error moves the value by a factor exp(σ) (±103 % would suggest a negative value)
LN_FACTOR_FROM = 0.5


def ln_error(sigma_ln: float | None) -> str:
    """One standard error of a positive quantity fitted in its logarithm: ``"±4.8 %"`` below
    :data:`LN_FACTOR_FROM`, else the factor ``"×/÷ 2.8"`` (exp σ); ``""`` when there is none (not determined)."""
    if sigma_ln is None or not math.isfinite(sigma_ln):
        return ""
    if sigma_ln < LN_FACTOR_FROM:
        return f"±{100 * sigma_ln:.2g} %"
    return f"×/÷ {math.exp(min(sigma_ln, 700.0)):.3g}"


def correlation_text(pairs, limit: int = MAX_LISTED_CORRELATIONS) -> list[str]:
    """``C(a, b) = +0.9412`` for the strongest ``limit`` pairs (``pairs`` as :meth:`FitResult.correlations` gives
    them, strongest first), then ``"... and N more"`` when there are more."""
    shown = [f"C({a}, {b}) = {r:+.4f}" for a, b, r in pairs[:limit]]
    if len(pairs) > limit:
        shown.append(f"... and {len(pairs) - limit} more")
    return shown


def plus_minus(value: float, stderr: float | None, unit: str = "", note: str = "", digits: int = 6, *,
               ln: bool = False) -> str:
    """A value with its standard error in lmfit's convention, ``"0.231 +/- 0.0133 (5.76%)"``, then the unit.

    Without a standard error: ``"0.231 +/- not determined"``; ``note`` (why:
    at a bound, fixed, not seen by the data; or which combination the error is
    of) follows, so that no value is shown without what is known of its
    uncertainty.

    ``ln=True`` marks a positive quantity whose error is that of its logarithm (a fitted parameter, a tendon
    stiffness): an error of :data:`LN_FACTOR_FROM` of the value or more is then a factor, ``"6.675 N ×/÷ 2.8"``.
    Otherwise an error larger than the value is said as a multiple of it (``"(18× the value)"``), not as a
    percentage in the thousands.
    """
    u = f" {unit}" if unit else ""
    shown = f"{value:.{digits}g}"
    if stderr is None or not math.isfinite(stderr):
        return f"{shown}{u} +/- not determined" + (f" {note}" if note else "")
    rel = stderr / abs(value) if value else math.inf
    if ln and value > 0 and rel >= LN_FACTOR_FROM:
        return f"{shown}{u} {ln_error(rel)}" + (f" {note}" if note else "")
    share = "" if not value else f" ({100 * rel:.2f}%)" if rel < 1 else f" ({rel:.2g}× the value)"
    return f"{shown} +/- {stderr:.{max(digits - 2, 2)}g}{share}{u}" + (f" {note}" if note else "")


#: renderers by later-stage package and name: tenscell.plotting's drawing functions, tenscell.reports'
#: Markdown renderers; each package fills its own table when it is imported
_RENDERERS: dict[str, dict[str, Callable[..., Any]]] = {"tenscell.plotting": {}, "tenscell.reports": {}}


def _register(package: str, functions: Mapping[str, Callable[..., Any]], what: str) -> None:
    table = _RENDERERS[package]
    for name, function in functions.items():
        if table.setdefault(name, function) is not function:
            raise ValueError(f"two {what}s are named {name!r}")


def _renderer(package: str, name: str, what: str) -> Callable[..., Any]:
    table = _RENDERERS[package]
    if name not in table:
        import_module(package)  # registers every renderer it defines
    try:
        return table[name]
    except KeyError:
        raise LookupError(f"{package} has no {what} {name!r}") from None


def register_plotters(functions: Mapping[str, Callable[..., Any]]) -> None:
    """Make drawing functions available to :func:`plotter` (called by :mod:`tenscell.plotting` on import)."""
    _register("tenscell.plotting", functions, "drawing function")


def plotter(name: str) -> Callable[..., Any]:
    """The drawing function ``name`` of :mod:`tenscell.plotting` (which is imported on first use).

    The one way a result's ``plot()`` reaches the plotting layer (module docstring).
    """
    return _renderer("tenscell.plotting", name, "drawing function")


def register_reporters(functions: Mapping[str, Callable[..., Any]]) -> None:
    """Make report renderers available to :func:`reporter` (called by :mod:`tenscell.reports` on import)."""
    _register("tenscell.reports", functions, "report renderer")


def reporter(name: str) -> Callable[..., Any]:
    """The report renderer ``name`` of :mod:`tenscell.reports` (which is imported on first use).

    The one way a result reaches the reports layer, as :func:`plotter` is for plotting (module docstring).
    """
    return _renderer("tenscell.reports", name, "report renderer")

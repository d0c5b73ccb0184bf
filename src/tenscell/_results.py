"""The conventions every public result object follows (cells, linear models, responses, fits, studies...).

A result is a frozen dataclass declared with ``repr=False`` and gives

``__repr__``
    a few lines built with :func:`format_repr`: what it is, its size, its
    headline numbers — never the arrays themselves;
``to_dataframe()``
    a :class:`pandas.DataFrame` whose column names carry their units
    (``frequency_Hz``, ``G_storage_Pa``, ``time_s``, ``EA_N``...), built with
    :func:`dataframe` so pandas is imported only when asked for;
``plot(ax=None, ...)``
    draws on the given matplotlib axes (or a new figure's) and returns the
    axes; the drawing code lives in :mod:`tenscell.plotting`, which never
    chooses a backend.
"""
from __future__ import annotations

from typing import Any, Mapping

__all__ = ["format_repr", "dataframe"]


def format_repr(title: str, *lines: str) -> str:
    """``<title>`` then each line indented by two spaces (keep it to a handful of lines)."""
    return "\n".join([f"<{title}>", *("  " + line for line in lines)])


def dataframe(columns: Mapping[str, Any], attrs: Mapping[str, Any] | None = None):
    """A DataFrame from unit-named columns; ``attrs`` (units, parameters) go to ``DataFrame.attrs``."""
    import pandas as pd

    df = pd.DataFrame(dict(columns))
    if attrs:
        df.attrs.update(attrs)
    return df

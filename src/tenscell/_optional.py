"""Optional dependencies: imported where they are needed, with a one-line hint when they are missing.

Fitting a sweep needs numpy, scipy, pandas and matplotlib only. Populations (Dask, Parquet) and structures above
1500 coordinates (sparse Cholesky through cvxopt) need the extras ``tenscell[populations]`` and
``tenscell[large]``; ``make test`` and ``make reproduce`` install everything.
"""
from __future__ import annotations

import importlib
from types import ModuleType

from ._errors import TenscellError

__all__ = ["MissingDependency", "require", "EXTRAS"]

#: import name -> (extra that installs it, what needs it)
EXTRAS = {
    "pyarrow": ("populations", "Parquet tables of cells and studies"),
    "distributed": ("populations", "a Dask cluster for populations and large studies"),
    "dask": ("populations", "a Dask cluster for populations and large studies"),
    "cvxopt": ("large", "the sparse Cholesky factorization of structures above 1500 coordinates"),
    "xarray": ("exchange", "an xarray Dataset"),
    "rheojax": ("exchange", "rheojax's RheoData (pip install rheojax; it needs Python >= 3.12)"),
}


class MissingDependency(TenscellError, ImportError, ValueError):
    """An optional dependency is not installed (an ImportError; also a ValueError, so that a command reports it
    in one line with the install hint instead of a traceback)."""


def require(name: str) -> ModuleType:
    """``import name``, or :class:`MissingDependency` saying what needs it and which extra installs it."""
    try:
        return importlib.import_module(name)
    except ImportError as err:
        top = name.split(".")[0]
        extra, purpose = EXTRAS.get(top, ("all", "this feature"))
        raise MissingDependency(f"{purpose} needs {top}, an optional dependency: pip install 'tenscell[{extra}]' "
                                f"({err})", name=top) from None

"""Optional dependencies: imported where they are needed, with a one-line hint when they are missing.

Fitting a sweep needs numpy, scipy, pandas and matplotlib only. Populations (Dask, Parquet) and structures above
1500 coordinates (sparse Cholesky through cvxopt) need the extras ``tenscell[populations]`` and
``tenscell[large]``, xarray datasets and netCDF files ``tenscell[exchange]``, Excel workbooks ``tenscell[excel]``,
the interactive 3D view of a structure ``tenscell[view]`` (plotly);
rheojax is installed by itself (``pip install rheojax``, Python >= 3.12). ``make test`` and ``make reproduce``
install every extra.
"""
from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType

from ._errors import TenscellError

__all__ = ["MissingDependency", "require", "EXTRAS", "install_hint", "netcdf_engine", "NETCDF_ENGINES"]

#: import name -> (the install command that brings it, what needs it). Each command installs the module: an extra
#: of tenscell where one lists it, else the package itself (rheojax is no extra: it needs Python >= 3.12, which
#: tenscell does not, so no extra could promise it)
EXTRAS = {
    "pyarrow": ("pip install 'tenscell[populations]'", "Parquet tables of cells and studies"),
    "distributed": ("pip install 'tenscell[populations]'", "a Dask cluster for populations and large studies"),
    "dask": ("pip install 'tenscell[populations]'", "a Dask cluster for populations and large studies"),
    "cvxopt": ("pip install 'tenscell[large]'", "the sparse Cholesky factorization of structures above 1500 "
               "coordinates"),
    "xarray": ("pip install 'tenscell[exchange]'", "an xarray Dataset (and netCDF files)"),
    "openpyxl": ("pip install 'tenscell[excel]'", "reading Excel workbooks"),
    "rheojax": ("pip install rheojax", "rheojax's RheoData (rheojax needs Python >= 3.12)"),
    "plotly": ("pip install 'tenscell[view]'", "the interactive 3D view of a structure"),
}

#: xarray's netCDF writers, best first: h5netcdf and netCDF4 write netCDF-4 (HDF5), scipy (a core dependency of
#: tenscell) writes netCDF-3, which holds no complex numbers: tenscell's datasets store real and imaginary parts
NETCDF_ENGINES = ("h5netcdf", "netCDF4", "scipy")


class MissingDependency(TenscellError, ImportError, ValueError):
    """An optional dependency is not installed (an ImportError; also a ValueError, so that a command reports it
    in one line with the install hint instead of a traceback)."""


def install_hint(name: str) -> str:
    """The command that installs module ``name`` (``pip install 'tenscell[large]'``, ``pip install rheojax``)."""
    top = name.split(".")[0]
    return EXTRAS[top][0] if top in EXTRAS else f"pip install {top}"


def require(name: str) -> ModuleType:
    """``import name``, or :class:`MissingDependency` saying what needs it and the command that installs it."""
    try:
        return importlib.import_module(name)
    except ImportError as err:
        top = name.split(".")[0]
        purpose = EXTRAS.get(top, ("", "this feature"))[1]
        raise MissingDependency(f"{purpose} needs {top}, an optional dependency: {install_hint(top)} ({err})",
                                name=top) from None


def netcdf_engine() -> str:
    """The first of :data:`NETCDF_ENGINES` that is installed (scipy always is, with tenscell's core)."""
    for engine in NETCDF_ENGINES:
        try:
            if importlib.util.find_spec(engine) is not None:
                return engine
        except (ImportError, ValueError):  # a module set to None in sys.modules, or a broken installation
            continue
    raise MissingDependency(f"writing netCDF needs one of {', '.join(NETCDF_ENGINES)}: pip install scipy",
                            name="scipy")  # pragma: no cover - scipy is a core dependency

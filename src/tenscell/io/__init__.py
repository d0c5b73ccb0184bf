"""Files in and out: measured data, structure files, output sets.

The public names of :mod:`~tenscell.io.data` (the package's CSV layouts and
bundled data), :mod:`~tenscell.io.importers` (your own headers and units),
:mod:`~tenscell.io.readers` (every format behind one registry, and ``read_data``,
which recognises any of them), :mod:`~tenscell.io.exchange` (xarray, rheojax),
:mod:`~tenscell.io.creep_data`, :mod:`~tenscell.io.provenance`, :mod:`~tenscell.io.checks`,
:mod:`~tenscell.io.structure_files` and :mod:`~tenscell.io.outputs`, importable from here.

``import tenscell.io`` loads none of them: each name is imported from its module the
first time it is used (PEP 562), so a command that writes an output set or reads a
structure file does not import the data readers (and pandas) with it.
"""
from __future__ import annotations

from importlib import import_module

# typing.TYPE_CHECKING without importing typing (mypy and pyright treat this name as true)
TYPE_CHECKING = False

#: public name -> the module of this package that defines it
_EXPORTS: dict[str, tuple[str, ...]] = {
    "data": ("RheologyData", "DataError", "bundled", "bundled_names", "read_csv"),
    "readers": ("read_data",),
    "readers.trios": ("read_trios",),
    "readers.rheocompass": ("read_rheocompass",),
    "importers": ("read_table", "from_dataframe", "ColumnMap", "guess_columns"),
    "creep_data": ("CreepData", "read_creep_csv", "write_creep_csv"),
    "relaxation_data": ("RelaxationData", "read_relaxation_csv", "write_relaxation_csv"),
    "provenance": ("Provenance",),
    "checks": ("CHECKS",),
    "exchange": ("from_rheojax", "to_rheojax"),
    "structure_files": ("StructureFile", "load_structure", "load_structure_file", "save_structure", "member_values"),
    "outputs": ("OutputSet", "OutputLocationError"),
}
_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}

__all__ = [
    # measured moduli and creep
    "RheologyData", "DataError", "read_data", "read_csv", "read_table", "read_trios", "read_rheocompass",
    "from_dataframe", "ColumnMap", "guess_columns", "bundled", "bundled_names", "CreepData", "read_creep_csv",
    "write_creep_csv", "RelaxationData", "read_relaxation_csv", "write_relaxation_csv", "Provenance", "CHECKS",
    # exchange with xarray and rheojax
    "from_rheojax", "to_rheojax",
    # structure files
    "StructureFile", "load_structure", "load_structure_file", "save_structure", "member_values",
    # output sets
    "OutputSet", "OutputLocationError",
]


def __getattr__(name: str) -> object:
    """Import a public name, or a submodule (``tenscell.io.thinning``), on first use."""
    module = _WHERE.get(name)
    if module is not None:
        value = getattr(import_module(f".{module}", __name__), name)
    elif not name.startswith("_"):
        try:
            value = import_module(f".{name}", __name__)
        except ModuleNotFoundError as err:
            if err.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)


if TYPE_CHECKING:  # what type checkers and IDEs see; keep in step with _EXPORTS
    from .checks import CHECKS
    from .creep_data import CreepData, read_creep_csv, write_creep_csv
    from .data import DataError, RheologyData, bundled, bundled_names, read_csv
    from .exchange import from_rheojax, to_rheojax
    from .importers import ColumnMap, from_dataframe, guess_columns, read_table
    from .outputs import OutputLocationError, OutputSet
    from .provenance import Provenance
    from .readers import read_data
    from .readers.rheocompass import read_rheocompass
    from .readers.trios import read_trios
    from .structure_files import StructureFile, load_structure, load_structure_file, member_values, save_structure

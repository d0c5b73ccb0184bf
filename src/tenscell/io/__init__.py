"""Files in and out: measured data, structure files, output sets.

The public names of :mod:`~tenscell.io.data` (the package's CSV layouts and
bundled data), :mod:`~tenscell.io.importers` (your own headers, units and
instrument exports), :mod:`~tenscell.io.creep_data`,
:mod:`~tenscell.io.structure_files` and :mod:`~tenscell.io.outputs`,
importable from here.
"""
from .creep_data import CreepData, read_creep_csv, write_creep_csv
from .data import DataError, RheologyData, bundled, bundled_names, read_csv
from .importers import ColumnMap, from_dataframe, read_rheocompass, read_table
from .outputs import OutputLocationError, OutputSet
from .structure_files import StructureFile, load_structure, load_structure_file, member_values, save_structure

__all__ = [
    # measured moduli and creep
    "RheologyData", "DataError", "read_csv", "read_table", "read_rheocompass", "from_dataframe", "ColumnMap",
    "bundled", "bundled_names", "CreepData", "read_creep_csv", "write_creep_csv",
    # structure files
    "StructureFile", "load_structure", "load_structure_file", "save_structure", "member_values",
    # output sets
    "OutputSet", "OutputLocationError",
]

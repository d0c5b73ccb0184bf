"""tenscell: tensegrity models of the cytoskeleton and the rheology they predict.

The pipeline, one stage per subpackage or module::

    model (structure -> coordinates -> equilibrium -> shapes) -> laws -> linear -> response, timedomain
          -> io (data in) -> analyses (dynamics, fitting, sensitivity, summary, studies, population)
          -> reports, plotting -> cli

Quick start::

    import numpy as np, tenscell
    cell = tenscell.paper_cell()                     # the paper's 6-strut cell, alpha=0, delta=50°
    lin = tenscell.linearize(cell, P=1000.0, EA=1.0, c=1.0)
    f = np.logspace(-2, 3, 61)                       # Hz
    Gp, Gpp = tenscell.moduli(lin, f)                # Pa

The top level holds the entry points (``paper_cell``, ``linearize``,
``moduli``, ``frequency_response``, ``fit``, ``read_data``, ``read_csv``...); everything else
is reached through its subpackage, each with its own ``__all__``
(``tenscell.model.regular_cell``, ``tenscell.laws.Voigt``,
``tenscell.io.DataError``...). Every error tenscell raises on purpose is a
``tenscell.TenscellError``.

``import tenscell`` loads nothing heavy: each public name below is imported
from its module the first time it is used (PEP 562), so the command line and
scripts that need one corner of the package do not pay for all of it.
"""
from __future__ import annotations

from importlib import import_module

# typing.TYPE_CHECKING without importing typing (mypy and pyright treat this name as true)
TYPE_CHECKING = False

from ._version import __version__  # noqa: E402

# The entry points a user types in the first hour: public name -> the module (relative to this package) that
# defines it. To export a new name here: add it to its module's tuple AND to the TYPE_CHECKING imports below
# (tests/test_startup.py checks that both agree). Everything else is reached through its subpackage
# (``tenscell.model``, ``tenscell.laws``, ``tenscell.io``...), each with its own ``__all__``.
_EXPORTS: dict[str, tuple[str, ...]] = {
    "model.shapes": ("paper_cell",),
    "model.structure": ("Structure",),
    "model.equilibrium": ("Cell",),
    "io.structure_files": ("load_structure",),
    "linear.linearize": ("LinearModel", "linearize"),
    "response": ("FrequencyResponse", "compliance", "frequency_response", "moduli"),
    "timedomain": ("creep_compliance", "stress_relaxation"),
    "io.data": ("RheologyData", "bundled", "read_csv"),
    "io.importers": ("read_table",),
    "io.instruments": ("read_data",),
    "fitting": ("FitResult", "fit"),
    "summary": ("summarize",),
    "_threads": ("set_threads", "threads"),
    "_errors": ("TenscellError",),
}

_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}

__all__ = list(_WHERE)

# Names that were top-level before 0.2.0: name -> the public subpackage or module that has it now. They warned
# through 0.2 (a DeprecationWarning naming the new place) and are gone in 0.3.0, as announced: using one is an
# AttributeError that names its home. (The names of 0.2.0's own __all__s that moved: tenscell._deprecated.)
_MOVED_FROM = {
    "model": ("Point", "StructureError", "NotPrestressableError", "equilibrate", "FormFindingError",
              "FormFindingResult", "find_form", "pin_jointed", "rigid_body_modes", "DEFAULT_DELTA", "REGULAR_DELTA",
              "cylindrical_cell", "if_free_delta", "paper_structure", "regular_cell", "semiflexible_paper_cell",
              "expanded_octahedron", "lattice_cell", "lattice_structure", "sphere_cell", "sphere_structure"),
    "io": ("StructureFile", "load_structure_file", "member_values", "save_structure", "DataError", "bundled_names",
           "ColumnMap", "read_rheocompass"),
    "laws": ("CompositeLaw", "LinearSpring", "LinearizationError", "PowerDashpot", "StiffeningFilament", "Tangent",
             "TendonLaw", "Voigt", "family_laws", "power_dashpot_law", "rest_lengths", "stiffening_law", "voigt_law"),
    "linear": ("NotPositiveDefiniteError", "RelaxationSpectrum", "linearize_law", "linearize_tangent",
               "relaxation_spectrum", "krylov_compliance"),
    "response": ("log_slope", "loss_tangent", "static_modulus", "viscosity_limit"),
    "timedomain": ("CreepSpectrum", "PowerLawFit", "StressRelaxation", "creep_spectrum", "fit_power_law",
                   "local_exponent", "relaxation_modulus"),
    "summary": ("relaxation_modes",),
    "dynamics": ("SimulationError", "SineDisplacement", "SineForce", "StepForce", "amplitude_sweep",
                 "creep_response", "oscillatory_response", "simulate"),
    "fitting": ("FitParameter",),
    "sensitivity": ("analytic_elasticities", "elasticities", "monte_carlo", "perturbation_table"),
    "studies": ("sensitivity_study", "loss_peak", "no_if_study", "prestress_map", "references_study", "linearize_semiflexible",
                "semiflexible_study", "linearize_stiffening", "stiffening_study"),
}
_REMOVED = {name: home for home, names in _MOVED_FROM.items() for name in names}


def __getattr__(name: str) -> object:
    """Import a public name, or a submodule (``tenscell.plotting``), on first use."""
    module = _WHERE.get(name)
    if module is not None:
        value = getattr(import_module(f".{module}", __name__), name)
    elif name in _REMOVED:
        home = _REMOVED[name]
        raise AttributeError(f"tenscell.{name} was removed in 0.3.0 (deprecated since 0.2.0): use "
                             f"tenscell.{home}.{name} (from tenscell.{home} import {name})")
    elif not name.startswith("_"):
        try:
            value = import_module(f".{name}", __name__)
        except ModuleNotFoundError as err:
            if err.name != f"{__name__}.{name}":
                raise  # the submodule exists but one of its imports is missing
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value  # later look-ups skip this function
    return value


def _submodules() -> list[str]:
    import pkgutil

    return [m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_")]


def __dir__() -> list[str]:
    return sorted({"__version__", *__all__, *_submodules()})


if TYPE_CHECKING:  # what type checkers and IDEs see; keep in step with _EXPORTS
    from ._errors import TenscellError
    from ._threads import set_threads, threads
    from .fitting import FitResult, fit
    from .io.data import RheologyData, bundled, read_csv
    from .io.importers import read_table
    from .io.instruments import read_data
    from .io.structure_files import load_structure
    from .linear.linearize import LinearModel, linearize
    from .model.equilibrium import Cell
    from .model.shapes import paper_cell
    from .model.structure import Structure
    from .response import FrequencyResponse, compliance, frequency_response, moduli
    from .summary import summarize
    from .timedomain import creep_compliance, stress_relaxation
    from . import dynamics, fitting, io, laws, linear, model, plotting, reports, response, sensitivity, studies
    from . import population, summary, timedomain

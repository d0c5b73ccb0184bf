"""tenscell: tensegrity models of the cytoskeleton and the rheology they predict.

The pipeline, one stage per subpackage or module::

    model (structure -> coordinates -> equilibrium -> shapes) -> laws -> linear -> response
          -> timedomain -> analyses (dynamics, fitting, sensitivity, studies) -> io, plotting, cli

Quick start::

    import numpy as np, tenscell
    cell = tenscell.paper_cell()                     # the paper's 6-strut cell, alpha=0, delta=50°
    lin = tenscell.linearize(cell, P=1000.0, EA=1.0, c=1.0)
    f = np.logspace(-2, 3, 61)                       # Hz
    Gp, Gpp = tenscell.moduli(lin, f)                # Pa

``import tenscell`` loads nothing heavy: each public name below is imported
from its module the first time it is used (PEP 562), so the command line and
scripts that need one corner of the package do not pay for all of it.
"""
from __future__ import annotations

from importlib import import_module

# typing.TYPE_CHECKING without importing typing (mypy and pyright treat this name as true)
TYPE_CHECKING = False

from ._version import __version__

# Public name -> the module (relative to this package) that defines it.
# To export a new name: add it to its module's tuple here AND to the
# TYPE_CHECKING imports below (tests/test_startup.py checks that both agree).
_EXPORTS: dict[str, tuple[str, ...]] = {
    # structure and reference
    "model.structure": ("Point", "Structure", "StructureError"),
    "io.structure_files": ("StructureFile", "load_structure", "load_structure_file", "member_values",
                           "save_structure"),
    "model.equilibrium": ("Cell", "NotPrestressableError", "equilibrate"),
    "model.formfinding": ("FormFindingError", "FormFindingResult", "find_form", "pin_jointed", "rigid_body_modes"),
    "model.shapes": ("DEFAULT_DELTA", "REGULAR_DELTA", "cylindrical_cell", "if_free_delta", "paper_cell",
                     "paper_structure", "regular_cell", "semiflexible_paper_cell"),
    "model.lattices": ("expanded_octahedron", "lattice_cell", "lattice_structure", "sphere_cell",
                       "sphere_structure"),
    # laws, linearization, response
    "laws": ("CompositeLaw", "LinearSpring", "LinearizationError", "PowerDashpot", "StiffeningFilament", "Tangent",
             "TendonLaw", "Voigt", "family_laws", "power_dashpot_law", "rest_lengths", "stiffening_law", "voigt_law"),
    "linear.linearize": ("LinearModel", "NotPositiveDefiniteError", "RelaxationSpectrum", "linearize",
                         "linearize_law", "linearize_tangent", "relaxation_spectrum"),
    "response": ("FrequencyResponse", "compliance", "frequency_response", "log_slope", "loss_tangent", "moduli",
                 "static_modulus", "viscosity_limit"),
    "linear.krylov": ("krylov_compliance",),
    "_threads": ("set_threads", "threads"),
    "timedomain": ("CreepSpectrum", "PowerLawFit", "StressRelaxation", "creep_compliance", "creep_spectrum",
                   "fit_power_law", "local_exponent", "relaxation_modulus", "stress_relaxation"),
    # measured data
    "io.data": ("DataError", "RheologyData", "bundled", "bundled_names", "read_csv"),
    "io.importers": ("ColumnMap", "read_rheocompass", "read_table"),
    # analyses
    "summary": ("relaxation_modes", "summarize"),
    "dynamics": ("SimulationError", "SineDisplacement", "SineForce", "StepForce", "amplitude_sweep",
                 "creep_response", "oscillatory_response", "simulate"),
    "fitting": ("FitParameter", "FitResult", "fit"),
    "sensitivity": ("analytic_elasticities", "elasticities", "monte_carlo", "perturbation_table", "sensitivity_study"),
    "studies.no_if": ("loss_peak", "no_if_study"),
    "studies.references": ("prestress_map", "references_study"),
    "studies.semiflexible": ("linearize_semiflexible", "semiflexible_study"),
    "studies.stiffening": ("linearize_stiffening", "stiffening_study"),
}

_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}

__all__ = list(_WHERE)


def __getattr__(name: str) -> object:
    """Import a public name, or a submodule (``tenscell.plotting``), on first use."""
    module = _WHERE.get(name)
    if module is not None:
        value = getattr(import_module(f".{module}", __name__), name)
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
    from .dynamics import (
        SimulationError, SineDisplacement, SineForce, StepForce, amplitude_sweep, creep_response, oscillatory_response,
        simulate,
    )
    from ._threads import set_threads, threads
    from .fitting import FitParameter, FitResult, fit
    from .io.data import DataError, RheologyData, bundled, bundled_names, read_csv
    from .io.importers import ColumnMap, read_rheocompass, read_table
    from .io.structure_files import StructureFile, load_structure, load_structure_file, member_values, save_structure
    from .laws import (
        CompositeLaw, LinearSpring, LinearizationError, PowerDashpot, StiffeningFilament, Tangent, TendonLaw, Voigt,
        family_laws, power_dashpot_law, rest_lengths, stiffening_law, voigt_law,
    )
    from .linear.krylov import krylov_compliance
    from .linear.linearize import (
        LinearModel, NotPositiveDefiniteError, RelaxationSpectrum, linearize, linearize_law, linearize_tangent,
        relaxation_spectrum,
    )
    from .model.equilibrium import Cell, NotPrestressableError, equilibrate
    from .model.formfinding import FormFindingError, FormFindingResult, find_form, pin_jointed, rigid_body_modes
    from .model.lattices import expanded_octahedron, lattice_cell, lattice_structure, sphere_cell, sphere_structure
    from .model.shapes import (
        DEFAULT_DELTA, REGULAR_DELTA, cylindrical_cell, if_free_delta, paper_cell, paper_structure, regular_cell,
        semiflexible_paper_cell,
    )
    from .model.structure import Point, Structure, StructureError
    from .response import (
        FrequencyResponse, compliance, frequency_response, log_slope, loss_tangent, moduli, static_modulus,
        viscosity_limit,
    )
    from .sensitivity import analytic_elasticities, elasticities, monte_carlo, perturbation_table, sensitivity_study
    from .studies.no_if import loss_peak, no_if_study
    from .studies.references import prestress_map, references_study
    from .studies.semiflexible import linearize_semiflexible, semiflexible_study
    from .studies.stiffening import linearize_stiffening, stiffening_study
    from .summary import relaxation_modes, summarize
    from .timedomain import (
        CreepSpectrum, PowerLawFit, StressRelaxation, creep_compliance, creep_spectrum, fit_power_law,
        local_exponent, relaxation_modulus, stress_relaxation,
    )
    from . import dynamics, fitting, io, laws, linear, model, plotting, reports, response, sensitivity, studies
    from . import summary, timedomain

"""tenscell: tensegrity models of the cytoskeleton and the rheology they predict.

The pipeline, one module per stage::

    structure -> coordinates -> equilibrium -> shapes -> linear -> response -> analyses -> plotting, cli

Quick start::

    import numpy as np, tenscell
    cell = tenscell.paper_cell()                     # the paper's 6-strut cell, alpha=0, delta=50°
    lin = tenscell.linearize(cell, P=1000.0, EA=1.0, c=1.0)
    f = np.logspace(-2, 3, 61)                       # Hz
    Gp, Gpp = tenscell.moduli(lin, f)                # Pa
"""
from .equilibrium import Cell, NotPrestressableError, equilibrate, rest_lengths
from .linear import LinearModel, NotPositiveDefiniteError, RelaxationSpectrum, linearize, relaxation_spectrum
from .response import (
    FrequencyResponse,
    compliance,
    frequency_response,
    log_slope,
    loss_tangent,
    moduli,
    static_modulus,
    viscosity_limit,
)
from .shapes import DEFAULT_DELTA, REGULAR_DELTA, if_free_delta, paper_cell, paper_structure
from .structure import Point, Structure, StructureError
from .linear import linearize_tangent  # issue 5: variants, sensitivity, future work
from .shapes import cylindrical_cell, regular_cell, semiflexible_paper_cell
from .sensitivity import analytic_elasticities, elasticities, monte_carlo, perturbation_table
from .variants import (
    linearize_semiflexible, linearize_stiffening, loss_peak, no_if_study, prestress_map, references_study,
    semiflexible_study, stiffening_study,
)
from .fitting import FitParameter, FitResult, fit
from .constitutive import LinearizationError, PowerDashpot, Voigt, power_dashpot_law, voigt_law
from .timedomain import (CreepSpectrum, PowerLawFit, StressRelaxation, creep_compliance, creep_spectrum, fit_power_law,
                         local_exponent, relaxation_modulus, stress_relaxation)
from .dynamics import (SimulationError, SineDisplacement, SineForce, StepForce, amplitude_sweep, creep_response,
                       linearize_law, oscillatory_response, simulate)
from .structio import StructureFile, load_structure, load_structure_file, member_values, save_structure
from .formfinding import FormFindingError, FormFindingResult, find_form, pin_jointed, rigid_body_modes
from .lattices import expanded_octahedron, lattice_cell, lattice_structure, sphere_cell, sphere_structure
from .krylov import krylov_compliance
from .summary import relaxation_modes, summarize

__version__ = "0.1.0"

__all__ = [
    "Structure", "Point", "StructureError",
    "Cell", "equilibrate", "rest_lengths", "NotPrestressableError",
    "paper_cell", "paper_structure", "if_free_delta", "DEFAULT_DELTA", "REGULAR_DELTA",
    "LinearModel", "linearize", "RelaxationSpectrum", "relaxation_spectrum", "NotPositiveDefiniteError",
    "compliance", "moduli", "frequency_response", "FrequencyResponse", "static_modulus", "viscosity_limit",
    "loss_tangent", "log_slope",
    "linearize_tangent", "cylindrical_cell", "regular_cell", "semiflexible_paper_cell",
    "analytic_elasticities", "elasticities", "monte_carlo", "perturbation_table",
    "linearize_semiflexible", "linearize_stiffening", "loss_peak", "no_if_study", "prestress_map",
    "references_study", "semiflexible_study", "stiffening_study",
    "fit", "FitResult", "FitParameter",
    "Voigt", "PowerDashpot", "voigt_law", "power_dashpot_law", "LinearizationError",
    "CreepSpectrum", "creep_spectrum", "creep_compliance", "StressRelaxation", "stress_relaxation",
    "relaxation_modulus", "local_exponent", "PowerLawFit", "fit_power_law",
    "simulate", "SineForce", "StepForce", "SineDisplacement", "SimulationError", "linearize_law",
    "oscillatory_response", "amplitude_sweep", "creep_response",
    "StructureFile", "load_structure", "load_structure_file", "save_structure", "member_values",
    "find_form", "FormFindingResult", "FormFindingError", "pin_jointed", "rigid_body_modes",
    "sphere_cell", "sphere_structure", "lattice_cell", "lattice_structure", "expanded_octahedron",
    "krylov_compliance",
    "summarize", "relaxation_modes",
]

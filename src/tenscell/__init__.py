"""tenscell: tensegrity models of the cytoskeleton and the rheology they predict.

The pipeline, one module per stage::

    structure -> coordinates -> equilibrium -> shapes -> constitutive -> linear -> response
              -> timedomain -> analyses (dynamics, fitting, sensitivity, variants, studies) -> plotting, cli

Quick start::

    import numpy as np, tenscell
    cell = tenscell.paper_cell()                     # the paper's 6-strut cell, alpha=0, delta=50°
    lin = tenscell.linearize(cell, P=1000.0, EA=1.0, c=1.0)
    f = np.logspace(-2, 3, 61)                       # Hz
    Gp, Gpp = tenscell.moduli(lin, f)                # Pa
"""

# structure -> coordinates -> equilibrium -> shapes
from .model.structure import Point, Structure, StructureError
from .io.structure_files import StructureFile, load_structure, load_structure_file, member_values, save_structure
from .model.equilibrium import Cell, NotPrestressableError, equilibrate
from .model.formfinding import FormFindingError, FormFindingResult, find_form, pin_jointed, rigid_body_modes
from .model.shapes import (
    DEFAULT_DELTA, REGULAR_DELTA, cylindrical_cell, if_free_delta, paper_cell, paper_structure, regular_cell,
    semiflexible_paper_cell,
)
from .model.lattices import expanded_octahedron, lattice_cell, lattice_structure, sphere_cell, sphere_structure
# constitutive laws -> linearization -> response
from .laws import (
    CompositeLaw, LinearSpring, LinearizationError, PowerDashpot, StiffeningFilament, Tangent, TendonLaw, Voigt,
    family_laws, power_dashpot_law, rest_lengths, stiffening_law, voigt_law,
)
from .linear.linearize import (
    LinearModel, NotPositiveDefiniteError, RelaxationSpectrum, linearize, linearize_law, linearize_tangent,
    relaxation_spectrum,
)
from .response import (
    FrequencyResponse, compliance, frequency_response, log_slope, loss_tangent, moduli, static_modulus,
    viscosity_limit,
)
from .linear.krylov import krylov_compliance
from .timedomain import (
    CreepSpectrum, PowerLawFit, StressRelaxation, creep_compliance, creep_spectrum, fit_power_law, local_exponent,
    relaxation_modulus, stress_relaxation,
)
# analyses
from .summary import relaxation_modes, summarize
from .dynamics import (
    SimulationError, SineDisplacement, SineForce, StepForce, amplitude_sweep, creep_response, oscillatory_response,
    simulate,
)
from .fitting import FitParameter, FitResult, fit
from .sensitivity import analytic_elasticities, elasticities, monte_carlo, perturbation_table
from .studies.no_if import loss_peak, no_if_study
from .studies.references import prestress_map, references_study
from .studies.semiflexible import linearize_semiflexible, semiflexible_study
from .studies.stiffening import linearize_stiffening, stiffening_study

__version__ = "0.1.0"

__all__ = [
    # structure and reference
    "Structure", "Point", "StructureError", "StructureFile", "load_structure", "load_structure_file",
    "member_values", "save_structure",
    "Cell", "equilibrate", "NotPrestressableError",
    "FormFindingError", "FormFindingResult", "find_form", "pin_jointed", "rigid_body_modes",
    "paper_cell", "paper_structure", "if_free_delta", "DEFAULT_DELTA", "REGULAR_DELTA",
    "cylindrical_cell", "regular_cell", "semiflexible_paper_cell",
    "expanded_octahedron", "lattice_cell", "lattice_structure", "sphere_cell", "sphere_structure",
    # laws, linearization, response
    "TendonLaw", "Tangent", "Voigt", "PowerDashpot", "StiffeningFilament", "LinearSpring", "CompositeLaw",
    "family_laws", "rest_lengths", "voigt_law", "power_dashpot_law", "stiffening_law", "LinearizationError",
    "LinearModel", "linearize", "linearize_law", "linearize_tangent", "RelaxationSpectrum", "relaxation_spectrum",
    "NotPositiveDefiniteError",
    "compliance", "moduli", "frequency_response", "FrequencyResponse", "static_modulus", "viscosity_limit",
    "loss_tangent", "log_slope", "krylov_compliance",
    "CreepSpectrum", "PowerLawFit", "StressRelaxation", "creep_compliance", "creep_spectrum", "fit_power_law",
    "local_exponent", "relaxation_modulus", "stress_relaxation",
    # analyses
    "relaxation_modes", "summarize",
    "SimulationError", "SineDisplacement", "SineForce", "StepForce", "amplitude_sweep", "creep_response",
    "oscillatory_response", "simulate",
    "fit", "FitResult", "FitParameter",
    "analytic_elasticities", "elasticities", "monte_carlo", "perturbation_table",
    "linearize_semiflexible", "linearize_stiffening", "loss_peak", "no_if_study", "prestress_map",
    "references_study", "semiflexible_study", "stiffening_study",
]

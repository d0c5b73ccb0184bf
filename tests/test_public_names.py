"""Every public name of tenscell 0.2.0 still imports, with a DeprecationWarning naming its new home where it moved.

The list below is every ``__all__`` of every public module (no ``_`` in its path) of the 0.2.0 release, commit
fbdf66e ("CHANGELOG.md for 0.2.0", ``__version__ = "0.2.0"``), collected by importing that tree. A name that moved
or went in 0.3 is in :data:`tenscell._deprecated.MOVED` (a module that went: ``GONE_MODULES``) and warns; every
other name imports without a warning. Removed in 0.4.0, with the shims.

``make release-check`` runs this file with the Python of a fresh virtual environment holding only the built wheel
(``python tests/test_public_names.py``: no pytest needed there).
"""
from __future__ import annotations

import importlib
import sys
import warnings

#: module (relative to ``tenscell``; "" for the package) -> its 0.2.0 ``__all__``, space-separated
NAMES_0_2_0 = {
    "": (
        "paper_cell Structure Cell load_structure LinearModel linearize FrequencyResponse compliance "
        "frequency_response moduli creep_compliance stress_relaxation RheologyData bundled read_csv "
        "read_table read_data FitResult fit summarize set_threads threads TenscellError"
    ),
    "cli": "main build_parser COMMAND_MODULES EXIT_INTERNAL",
    "cli.dynamics": "",
    "cli.fit": "",
    "cli.moduli": "",
    "cli.population": "",
    "cli.reproduce": "",
    "cli.show": "",
    "cli.study": "",
    "dynamics": (
        "SineForce StepForce SineDisplacement SimulationError SlackEvent MotionState EquationsOfMotion "
        "Simulation simulate linearize_law linear_steady_state Harmonics harmonics OscillatoryResponse "
        "oscillatory_response AmplitudeSweep amplitude_sweep CreepResponse creep_response"
    ),
    "dynamics.creep": "creep_response",
    "dynamics.equations": "SimulationError SlackEvent MotionState EquationsOfMotion",
    "dynamics.harmonic": "linear_steady_state harmonics oscillatory_response amplitude_sweep",
    "dynamics.integration": "simulate",
    "dynamics.loads": "SineForce SineDisplacement StepForce LOADS",
    "dynamics.results": "Simulation Harmonics OscillatoryResponse AmplitudeSweep CreepResponse",
    "fitting": (
        "TENDON_MODES DAMPING_MODES FitParameter FitAlternative FitResult FitCurve DatasetFit "
        "PrestressActivity prestress_activity data_axis FitProblem make_problem fit model_curve "
        "frequency_slopes prestress_slopes required_points MECHANISMS Mechanism Field mechanism_names "
        "MechanismFit FittedMechanism fit_mechanism load_any_fit"
    ),
    "fitting.creep": "step_kernel pair_kernels creep_from_modes creep_derivatives",
    "fitting.derivatives": (
        "spectrum evaluate log_derivatives activity static_share storage_elasticity creep_compliance "
        "modal_products"
    ),
    "fitting.entry": "fit",
    "fitting.fitted": "FittedModel scaled_cell load_fit PredictedCreep predicted_creep MODEL_FORMAT",
    "fitting.heterogeneity": "Distribution LogNormal LogUniform PowerLaw DISTRIBUTIONS assignments",
    "fitting.identifiability": "Identifiability Combination identifiability GAUGE NULL_SHARE",
    "fitting.layout": (
        "TENDON_MODES DAMPING_MODES required_points as_datasets parameter_layout data_arrays default_bounds "
        "check_options prestress_varies"
    ),
    "fitting.mechanism_fit": "MechanismFit FittedMechanism fit_mechanism load_any_fit MECHANISM_FORMAT noise_rms",
    "fitting.mechanism_problem": "MechanismProblem make_mechanism_problem MechanismEvaluation",
    "fitting.mechanisms": "Field Mechanism MECHANISMS mechanism KINDS PER_TENDON_VOIGT",
    "fitting.models": (
        "PHI0 structural_damping_moduli StructuralDampingProblem StructuralDampingFit fit_structural_damping "
        "information_criteria split_holdout ModelScore ModelComparison compare_models"
    ),
    "fitting.prestress": "PrestressActivity prestress_activity INERT_SHARE INERT_ELASTICITY CELL_ELASTICITY",
    "fitting.problem": "TENDON_MODES DAMPING_MODES FitProblem make_problem required_points as_datasets",
    "fitting.result": (
        "FitParameter FitAlternative FitCurve DatasetFit CreepFit FitResult model_curve frequency_slopes "
        "prestress_slopes data_axis"
    ),
    "fitting.search": "fit run_search",
    "io": (
        "RheologyData DataError read_data read_csv read_table read_trios read_rheocompass from_dataframe "
        "ColumnMap guess_columns bundled bundled_names CreepData read_creep_csv write_creep_csv from_rheojax "
        "to_rheojax StructureFile load_structure load_structure_file save_structure member_values OutputSet "
        "OutputLocationError"
    ),
    "io.columns": (
        "DataError ColumnMap guess_columns KNOWN_HEADERS Parsed parse parse_frame frame_table FREQUENCY_UNITS "
        "MODULUS_UNITS PHASE_UNITS PRESTRESS_UNITS TIME_UNITS COMPLIANCE_UNITS"
    ),
    "io.creep_data": "CreepData read_creep_csv write_creep_csv is_creep_header read_measurements",
    "io.data": "DataError RheologyData read_csv parse_text write_csv bundled bundled_names generated_note",
    "io.exchange": "to_rheojax from_rheojax",
    "io.importers": (
        "ColumnMap from_dataframe read_table guess_columns KNOWN_HEADERS FREQUENCY_UNITS MODULUS_UNITS "
        "PHASE_UNITS PRESTRESS_UNITS TIME_UNITS COMPLIANCE_UNITS DataError"
    ),
    "io.instruments": "read_data read_trios read_rheocompass detect_layout TEMPERATURE_TOLERANCE_C",
    "io.outputs": (
        "atomic_path write_csv_rows write_json json_ready json_text NULL_MEANS write_text write_bytes "
        "OutputSet OutputLocationError check_output_dir check_output_file read_manifest MANIFEST"
    ),
    "io.structure_files": (
        "StructureFile load_structure load_structure_file save_structure structure_to_dict "
        "structure_from_dict member_values FORMAT_NAME FORMAT_VERSION LENGTH_UNITS FORCE_UNITS TIME_UNITS"
    ),
    "io.tables": "MODULI_HEADER moduli_table fit_table check_finite_rows",
    "io.thinning": "bin_log_frequency bin_datasets binning_notes DEFAULT_MAX_POINTS",
    "laws": (
        "TendonLaw Parameter Tangent Voigt PowerDashpot StiffeningFilament LinearSpring Maxwell "
        "StandardLinearSolid Springpot SPRINGPOT_TIME Realization springpot_prony DEFAULT_REALIZATION_TOL "
        "DEFAULT_REALIZATION_BAND_HZ DynamicLawError CompositeLaw family_laws LinearizationError rest_lengths "
        "voigt_law power_dashpot_law stiffening_law DEFAULT_VELOCITY_SCALE"
    ),
    "laws.base": (
        "TendonLaw Parameter Tangent Realization LinearizationError DynamicLawError angular_frequencies "
        "DEFAULT_REALIZATION_TOL"
    ),
    "laws.composite": "CompositeLaw family_laws",
    "laws.constructors": "rest_lengths voigt_law power_dashpot_law stiffening_law",
    "laws.filaments": "StiffeningFilament",
    "laws.springs": "Voigt PowerDashpot LinearSpring DEFAULT_VELOCITY_SCALE",
    "laws.viscoelastic": "Maxwell StandardLinearSolid Springpot SPRINGPOT_TIME DEFAULT_REALIZATION_BAND_HZ springpot_prony",
    "linear": (
        "LinearModel linearize linearize_law linearize_tangent NotPositiveDefiniteError Pencil "
        "positive_definite_factor RelaxationSpectrum relaxation_spectrum continuum_factor modulus "
        "krylov_compliance KrylovResponse dynamic_moduli dynamic_compliance realize with_cytoplasm"
    ),
    "linear.dynamic": (
        "dynamic_stiffness dynamic_compliance dynamic_moduli dynamic_complex_modulus check_static_stability "
        "cytoplasm_damping exact_compliance"
    ),
    "linear.krylov": "KrylovResponse LanczosRun converge krylov_compliance default_shift load_modes DEFAULT_BAND_HZ",
    "linear.linearize": (
        "LinearModel RelaxationSpectrum linearize linearize_tangent linearize_law realize with_cytoplasm "
        "relaxation_spectrum NotPositiveDefiniteError"
    ),
    "linear.modal": (
        "NotPositiveDefiniteError positive_definite_factor complement_basis continuum_factor modulus "
        "assemble_stiffness assemble_damping Modes Pencil RelaxationSpectrum relaxation_spectrum "
        "modal_compliance prestress_grid_compliance prestress_grid_modes ZERO_TIME"
    ),
    "linear.rigid": "deformation_basis unresisted_share",
    "linear.sparse": "NotPositiveDefinite SparseCholesky factorize_spd",
    "linear.whitening": "whiten whitened_basis unit_damping_basis rescaled_basis",
    "model": (
        "Point Structure StructureError member_values ACTIN INTERMEDIATE_FILAMENT STRUT NUCLEUS cable_mask "
        "Cell NotPrestressableError equilibrate FormFindingError FormFindingResult find_form pin_jointed "
        "rigid_body_modes paper_cell paper_structure regular_cell cylindrical_cell semiflexible_paper_cell "
        "if_free_delta DEFAULT_DELTA REGULAR_DELTA nucleated_cell nucleated_structure sphere_cell "
        "sphere_structure lattice_cell lattice_structure expanded_octahedron"
    ),
    "model.coordinates": "Coordinates NodeKinematics make_coordinates kinematics positions PARAMETRIZATIONS",
    "model.equilibrium": (
        "NotPrestressableError MemberGeometry Cell member_geometry equilibrium_matrix assemble_hessian "
        "point_vector self_stress_basis self_stress self_stress_lp equilibrate generalized_forces "
        "damping_matrix tangent_stiffness weighted_gram SPARSE_THRESHOLD"
    ),
    "model.formfinding": "FormFindingError FormFindingResult find_form rigid_body_modes pin_jointed",
    "model.lattices": (
        "sphere_structure sphere_cell lattice_structure lattice_cell lattice_module_tensions "
        "expanded_octahedron SPHERE_STRUTS DEFAULT_OFFSET LATTICE_STRUT_EA"
    ),
    "model.shapes": (
        "paper_cell paper_structure nucleated_cell nucleated_structure paper_nodes if_free_delta "
        "DEFAULT_DELTA REGULAR_DELTA PAPER_NODE_NAMES regular_cell semiflexible_structure "
        "semiflexible_paper_cell cylindrical_nodes cylindrical_structure cylindrical_cell "
        "find_cylindrical_reference CYLINDRICAL_PARAMETERS"
    ),
    "model.structure": (
        "Point Structure StructureError ACTIN INTERMEDIATE_FILAMENT STRUT NUCLEUS COMPRESSIBLE_FAMILIES "
        "cable_mask member_values"
    ),
    "plotting": (
        "STYLE style colors moduli_panels figure_of save png_bytes fig2_prestress fig3_frequency "
        "moduli_vs_frequency moduli_vs_prestress no_if_figure no_if_peaks_figure elasticities_figure "
        "monte_carlo_figure reference_map_figure references_figure semiflexible_figure stiffening_figure "
        "fit_figure data_points measured plot_fit fit_panels compactness_front stiffness_histogram "
        "time_traces force_displacement_loop harmonic_spectrum creep_loglog spectrum_stems loglog_curve "
        "rates_bar structure_3d relaxation_modes_3d MEMBER_STYLE"
    ),
    "plotting.dynamics": (
        "time_traces force_displacement_loop harmonic_spectrum creep_loglog simulation_axes harmonics_axes "
        "loop_axes amplitude_sweep_axes creep_axes"
    ),
    "plotting.fits": "fit_figure data_points plot_fit fit_panels compactness_front stiffness_histogram measured",
    "plotting.mechanisms": "mechanisms_figure",
    "plotting.paper": "fig2_prestress fig3_frequency moduli_vs_frequency moduli_vs_prestress linear_model_moduli",
    "plotting.population": "parameter_distributions population_moduli",
    "plotting.spectra": "spectrum_stems loglog_curve rates_bar",
    "plotting.structures": "MEMBER_STYLE MAX_MEMBERS_DRAWN structure_3d relaxation_modes_3d",
    "plotting.variants": (
        "no_if_figure no_if_peaks_figure elasticities_figure monte_carlo_figure reference_map_figure "
        "references_figure semiflexible_figure stiffening_figure"
    ),
    "population": (
        "CellSource Condition PopulationFitOptions PopulationResult SyntheticPopulation cell_seed "
        "condition_summary fit_cell fit_population monte_carlo_study parse_condition read_sources read_study "
        "recovery sweep_study synth_population"
    ),
    "population.run": "PopulationFitOptions cell_seed fit_cell fit_population CURVE_FREQUENCIES STATUSES WorkDirError",
    "population.sources": "CellSource SourceError read_sources CELL_COLUMN CONDITION_COLUMN",
    "population.studies": "StudyResult monte_carlo_study sweep_study read_study PARTS",
    "population.synth": (
        "MODELS GENERATING_FILE TENSEGRITY_MEDIANS POWERLAW_MEDIANS Condition parse_condition SyntheticCell "
        "SyntheticPopulation synth_population reference_frequency"
    ),
    "population.table": (
        "PopulationResult condition_summary recovery FIXED_COLUMNS SUMMARY_COLUMNS read_table "
        "CURVE_FREQUENCIES"
    ),
    "reports": (
        "fit_markdown sensitivity_markdown compactness_markdown no_if_markdown references_markdown "
        "semiflexible_markdown stiffening_markdown population_markdown study_markdown"
    ),
    "reports.compactness": "compactness_markdown",
    "reports.fit": (
        "fit_markdown SECTIONS section_summary section_datasets section_baseline section_shape "
        "section_prestress section_stiffness section_parameters section_errors section_alternatives"
    ),
    "reports.fit_analysis": (
        "identifiability_section comparison_section creep_section provenance_line section_provenance "
        "section_identifiability section_comparison section_creep"
    ),
    "reports.mechanisms": "mechanism_fit_markdown mechanisms_markdown study_table_rows STUDY_COLUMNS",
    "reports.population": "population_markdown study_markdown",
    "reports.sensitivity": "sensitivity_markdown",
    "reports.studies": "no_if_markdown references_markdown semiflexible_markdown stiffening_markdown",
    "response": (
        "compliance moduli FrequencyResponse frequency_response static_modulus viscosity_limit loss_tangent "
        "log_slope"
    ),
    "sensitivity": (
        "Elasticities analytic_elasticities elasticities PerturbationRow perturbation_table GroupSummary "
        "summarize MonteCarloResult monte_carlo monte_carlo_draws monte_carlo_factors monte_carlo_names "
        "SensitivityStudy sensitivity_study SENSITIVITY_FREQUENCIES PAPER_BOUND"
    ),
    "studies": (
        "homogeneous_study paper_claims no_if_study NoIFStudy loss_peak LossPeak references_study "
        "ReferencesStudy prestress_map semiflexible_study SemiflexibleStudy linearize_semiflexible "
        "BucklingError stiffening_study StiffeningStudy linearize_stiffening compactness_study "
        "CompactnessStudy"
    ),
    "studies.claims": (
        "HomogeneousStudy homogeneous_study robustness Claim paper_claims claims_markdown CellComparison "
        "against_cells FIG2_FREQUENCIES FIG3_PRESTRESSES"
    ),
    "studies.compactness": "CompactnessStudy compactness_study DEFAULT_DECADES",
    "studies.mechanisms": "MechanismRow MechanismStudy mechanisms_study GOALS SLOPE_GRID_PER_DECADE",
    "studies.no_if": "LossPeak loss_peak NoIFStudy no_if_study PAPER_WINDOW_HZ",
    "studies.references": "ReferenceMap prestress_map ReferencesStudy references_study VALID NOT_PRESTRESSABLE NOT_STABLE",
    "studies.semiflexible": "BucklingError euler_critical_prestress linearize_semiflexible SemiflexibleStudy semiflexible_study",
    "studies.stiffening": "linearize_stiffening StiffeningStudy stiffening_study",
    "summary": "StructureSummary summarize relaxation_modes RelaxationModes node_displacements",
    "timedomain": (
        "CreepSpectrum creep_spectrum creep_compliance StressRelaxation stress_relaxation relaxation_modulus "
        "local_exponent PowerLawFit fit_power_law"
    ),
}


def _import(module: str):
    """(the module, the DeprecationWarnings its import gave); a module that went is imported afresh, so that its
    warning is seen whatever imported it before."""
    from tenscell._deprecated import GONE_MODULES

    if module in GONE_MODULES:
        sys.modules.pop(module, None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mod = importlib.import_module(module)
    return mod, [w for w in caught if issubclass(w.category, DeprecationWarning)]


def _attribute(mod, name: str):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        value = getattr(mod, name)
    return value, [w for w in caught if issubclass(w.category, DeprecationWarning)]


def problems() -> tuple[list[str], int, int]:
    """(what is wrong, names imported, names that warned): every 0.2.0 name imports; a moved name warns naming its
    new home and is the object found there; a module that went warns when imported; no other name warns."""
    from tenscell._deprecated import GONE_MODULES, MOVED, REMOVED_IN

    wrong: list[str] = []
    count = warned = 0
    for rel, text in NAMES_0_2_0.items():
        module = "tenscell" + (f".{rel}" if rel else "")
        try:
            mod, said = _import(module)
        except Exception as err:  # noqa: BLE001 - every failure is listed
            wrong.append(f"import {module}: {type(err).__name__}: {err}")
            continue
        if (module in GONE_MODULES) != bool(said):
            wrong.append(f"import {module}: {'no DeprecationWarning' if not said else 'warns: ' + str(said[0].message)}")
        for name in text.split():
            count += 1
            try:
                value, said = _attribute(mod, name)
            except Exception as err:  # noqa: BLE001
                wrong.append(f"{module}.{name}: {type(err).__name__}: {err}")
                continue
            entry = MOVED.get(module, {}).get(name)
            if entry is None:
                if said:
                    wrong.append(f"{module}.{name} warns but is not deprecated: {said[0].message}")
                continue
            warned += 1
            home, new, _ = entry
            message = str(said[0].message) if said else ""
            if f"{module}.{name} is deprecated" not in message or f"removed in {REMOVED_IN}" not in message:
                wrong.append(f"{module}.{name}: no DeprecationWarning naming it and its removal ({message!r})")
            elif not (home.split(" ")[0] in message or new in message):
                wrong.append(f"{module}.{name}: the warning does not name its new home {home} ({message!r})")
            if value is not getattr(importlib.import_module(home), new):
                wrong.append(f"{module}.{name} is not {home}.{new}")
    return wrong, count, warned


def test_every_public_name_of_0_2_0_imports():
    wrong, count, warned = problems()
    assert count == 748 and warned >= 69, (count, warned)
    assert not wrong, "\n".join(wrong)


def test_the_five_names_the_issue_found_removed_warn_and_work():
    """fitting.models.fit_structural_damping, fitting.mechanisms, fitting.mechanism_fit, fitting.mechanism_problem
    and fit_mechanism (issue 36): each warns naming where to go, and what it gives works there."""
    import pytest

    import tenscell.fitting
    import tenscell.fitting.models

    with pytest.warns(DeprecationWarning, match=r"fitting\.models\.fit_structural_damping .*fitting\.scores"):
        fsd = tenscell.fitting.models.fit_structural_damping
    from tenscell.fitting.scores import fit_structural_damping
    assert fsd is fit_structural_damping
    for module, home in [("mechanisms", "models.mechanism"), ("mechanism_fit", "fitting"),
                         ("mechanism_problem", "models.mechanism")]:
        sys.modules.pop(f"tenscell.fitting.{module}", None)
        with pytest.warns(DeprecationWarning, match=rf"tenscell\.fitting\.{module} is deprecated .*{home}"):
            importlib.import_module(f"tenscell.fitting.{module}")
    with pytest.warns(DeprecationWarning, match=r"fit_mechanism is deprecated .*fit\(data, model=mechanism\)"):
        fit_mechanism = tenscell.fitting.fit_mechanism
    from tenscell.io.data import bundled
    with pytest.warns(DeprecationWarning, match="fit_mechanism is deprecated"):
        result = fit_mechanism(bundled("fabry2001"), "springpot+visc", starts=1, hops=0, progress=False)
    assert isinstance(result, tenscell.fitting.FitResult) and result.spec.name == "springpot+visc"


def test_the_shims_go_in_the_release_after_this_one():
    from tenscell import __version__
    from tenscell._deprecated import REMOVED_IN, SINCE

    assert SINCE == __version__ and int(REMOVED_IN.split(".")[1]) == int(SINCE.split(".")[1]) + 1


if __name__ == "__main__":  # make release-check: a fresh environment with only the wheel installed
    found, n, n_warned = problems()
    print("\n".join(found))
    print(f"{n} public names of tenscell 0.2.0 imported, {n_warned} of them with a DeprecationWarning naming their new "
          f"home; {len(found)} problem(s)")
    sys.exit(1 if found else 0)

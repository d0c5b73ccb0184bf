"""The public names of tenscell 0.2.0 that moved or went: each keeps importing for one release, with a warning.

Every name of a 0.2.0 ``__all__`` still imports in 0.3 (``tests/test_public_names.py`` walks them all). A name
that moved is found in its new home and a :class:`DeprecationWarning` names that home; a module that went is a
few lines (``tenscell/fitting/mechanisms.py``...) whose import warns and whose names come from their new homes.
They are removed in 0.4.0.

A module that lost names ends with ``__getattr__ = moved_away(__name__)``.

Standard library only, and nothing of tenscell is imported here: each new home is imported, by its dotted name,
only when an old name is used.
"""
from __future__ import annotations

import importlib
import warnings

__all__ = ["MOVED", "GONE_MODULES", "SINCE", "REMOVED_IN", "moved", "moved_away", "gone_module"]

#: the release that moved or removed the names below, and the one that drops their shims
SINCE, REMOVED_IN = "0.3.0", "0.4.0"

_VOIGT_CREEP = "tenscell.fitting.models.voigt_creep"
_VOIGT_KERNEL = "tenscell.fitting.models.voigt_kernel"
_MECHANISM = "tenscell.fitting.models.mechanism"
_CATALOG = "tenscell.fitting.models.catalog"
_SCORES = "tenscell.fitting.scores"
_VOIGT = "tenscell.fitting.models.voigt"
_CURVES = "tenscell.fitting.curves"
_RECORDS = "tenscell.fitting.records"
_PARAMETERS = "tenscell.fitting.parameters"


def _same(home: str, *names: str) -> dict[str, tuple[str, str, str]]:
    return {n: (home, n, "") for n in names}


#: old module -> {old name: (new module, new name, what to do instead, when it is not a plain move)}
MOVED: dict[str, dict[str, tuple[str, str, str]]] = {
    "tenscell.fitting": {
        "fit_mechanism": ("tenscell.fitting.mechanism_fit", "fit_mechanism",
                          "use tenscell.fitting.fit(data, model=mechanism), which returns a FitResult"),
    },
    "tenscell.fitting.models": {
        **_same("tenscell.fitting.models.formulas", "PHI0", "structural_damping_moduli"),
        **_same(_SCORES, "fit_structural_damping", "split_holdout", "ModelScore", "ModelComparison", "compare_models"),
        "information_criteria": (_RECORDS, "information_criteria", ""),
        "StructuralDampingProblem": ("tenscell.fitting.models.formulas", "FormulaProblem",
                                     "fit_structural_damping builds the problem of the formula "
                                     "structural-damping+newtonian: tenscell.fitting.models.formulas.FormulaProblem"),
        "StructuralDampingFit": ("tenscell.fitting.result", "FitResult",
                                 "fit_structural_damping returns a tenscell.fitting.FitResult"),
    },
    "tenscell.fitting.problem": {
        **_same(_VOIGT, "TENDON_MODES", "DAMPING_MODES", "FitProblem", "make_problem"),
        **_same(_PARAMETERS, "required_points", "as_datasets"),
    },
    "tenscell.fitting.result": {
        **_same(_RECORDS, "FitParameter", "FitAlternative", "FitCurve"),
        **_same(_CURVES, "model_curve", "frequency_slopes", "prestress_slopes"),
    },
    "tenscell.fitting.search": {"fit": ("tenscell.fitting", "fit", "")},
    "tenscell.model.shapes": {"find_cylindrical_reference": ("tenscell.studies.references",
                                                             "find_cylindrical_reference", "")},
    "tenscell.reports.mechanisms": {
        "mechanism_fit_markdown": ("tenscell.reports.fit", "fit_markdown",
                                   "use tenscell.reports.fit.fit_markdown(result), the one report of every fit"),
    },
    "tenscell.sensitivity": _same("tenscell.studies.sensitivity", "SensitivityStudy", "sensitivity_study"),
    # the modules that went (GONE_MODULES): every name of their 0.2.0 __all__
    "tenscell.fitting.creep": _same(_VOIGT_CREEP, "step_kernel", "pair_kernels", "creep_from_modes",
                                    "creep_derivatives"),
    "tenscell.fitting.derivatives": _same(_VOIGT_KERNEL, "spectrum", "evaluate", "log_derivatives", "activity",
                                          "static_share", "storage_elasticity", "creep_compliance", "modal_products"),
    "tenscell.fitting.heterogeneity": _same("tenscell.fitting.models.heterogeneity", "Distribution", "LogNormal",
                                            "LogUniform", "PowerLaw", "DISTRIBUTIONS", "assignments"),
    "tenscell.fitting.layout": _same(_PARAMETERS, "TENDON_MODES", "DAMPING_MODES", "required_points", "as_datasets",
                                     "parameter_layout", "data_arrays", "default_bounds", "check_options",
                                     "prestress_varies"),
    "tenscell.fitting.mechanism_fit": {
        "MechanismFit": ("tenscell.fitting.result", "FitResult", "a mechanism's fit is a tenscell.fitting.FitResult"),
        "FittedMechanism": (_MECHANISM, "FittedMechanism", ""),
        "load_any_fit": ("tenscell.fitting.fitted", "load_fit", "use tenscell.fitting.load_fit, which reads every "
                                                                "kind of fit.json"),
        "MECHANISM_FORMAT": (_MECHANISM, "MECHANISM_FORMAT", ""),
        "noise_rms": (_RECORDS, "noise_rms", ""),
    },
    "tenscell.fitting.mechanism_problem": _same(_MECHANISM, "MechanismProblem", "make_mechanism_problem",
                                                "MechanismEvaluation"),
    "tenscell.fitting.mechanisms": {**_same(_MECHANISM, "Field", "Mechanism", "KINDS"),
                                    **_same(_CATALOG, "MECHANISMS", "mechanism", "PER_TENDON_VOIGT")},
}

#: the modules of 0.2.0 that went -> where their names are now (one home, or the one to read first)
GONE_MODULES = {
    "tenscell.fitting.creep": _VOIGT_CREEP,
    "tenscell.fitting.derivatives": _VOIGT_KERNEL,
    "tenscell.fitting.heterogeneity": "tenscell.fitting.models.heterogeneity",
    "tenscell.fitting.layout": _PARAMETERS,
    "tenscell.fitting.mechanism_fit": "tenscell.fitting (fit(data, model=m) returns a FitResult; load_fit)",
    "tenscell.fitting.mechanism_problem": _MECHANISM,
    "tenscell.fitting.mechanisms": f"{_MECHANISM} (the built-in ones: {_CATALOG})",
}


def _advice(module: str, name: str) -> str:
    home, new, how = MOVED[module][name]
    if how:
        return how
    return f"use {home}.{new} (from {home} import {new})"


def moved(module: str, name: str):
    """The value of ``module.name``, a public name of 0.2.0 that moved, with a DeprecationWarning naming its new
    home; AttributeError (as for any missing attribute) when ``name`` is not one of them."""
    entry = MOVED.get(module, {}).get(name)
    if entry is None:
        raise AttributeError(f"module {module!r} has no attribute {name!r}")
    warnings.warn(f"{module}.{name} is deprecated since {SINCE} and will be removed in {REMOVED_IN}: "
                  f"{_advice(module, name)}", DeprecationWarning, stacklevel=3)
    home, new, _ = entry
    return getattr(importlib.import_module(home), new)


def gone_module(module: str):
    """``(__all__, __getattr__)`` of ``module``, one of :data:`GONE_MODULES`, with a DeprecationWarning for its
    import (called by the module's body) and one for each name used."""
    warnings.warn(f"{module} is deprecated since {SINCE} and will be removed in {REMOVED_IN}: its names are in "
                  f"{GONE_MODULES[module]}", DeprecationWarning, stacklevel=3)  # importlib's frames are skipped

    return list(MOVED[module]), moved_away(module)


def moved_away(module: str):
    """The ``__getattr__`` of ``module``: its public names of the last release that moved or went
    (:func:`moved`)."""

    def __getattr__(name: str):
        return moved(module, name)

    return __getattr__

"""Fits of models to measured cell rheology: one stack for every model.

In the manner of lmfit, every fit has the same layers:

- :mod:`~tenscell.fitting.models`: what is fitted — a :class:`~tenscell.fitting.models.base.FitModel` builds its
  problem against data; one registry (:data:`MODELS`, :func:`get_model`) holds the paper's Voigt cell
  (:mod:`~.models.voigt`), the few-parameter mechanisms (:mod:`~.models.mechanism`) and the structure-free
  formulas every tensegrity has to beat (:mod:`~.models.formulas`); a :class:`Population` fits any of them to many
  cells at once, with shared and per-cell parameters (:mod:`~.models.population`);
- :mod:`~tenscell.fitting.parameters` and :mod:`~tenscell.fitting.problem`: the parameters' layout (names, units,
  bounds, fixes, the data's prestress groups) and the protocol every problem follows (residuals, Jacobian, starts,
  moves, and what the result reads);
- :mod:`~tenscell.fitting.search`: starts, basin hopping, least squares, stopping;
- :mod:`~tenscell.fitting.result`: the one result type (:class:`FitResult`) with its records
  (:mod:`~tenscell.fitting.records`), curves and slopes (:mod:`~tenscell.fitting.curves`), identifiability
  (:mod:`~tenscell.fitting.identifiability`), derived numbers with ± (:mod:`~tenscell.fitting.derived`), scores
  against other models and held-out data (:mod:`~tenscell.fitting.scores`);
- :mod:`~tenscell.fitting.fitted`: the fitted model every consumer takes (``moduli``, ``creep``, ``simulate``,
  ``show --from-fit``, ensembles) and fit.json.
- :mod:`~tenscell.fitting.shares`: what the structure carries, the geometric prestress stiffness's share of dG′/dP
  and dG″/dP against the law's tension terms (:func:`structure_shares`; with ± and the fitted prestress against the
  measured one, :func:`structure_summary`);
- :mod:`~tenscell.fitting.anchor`: the prestress anchor, the model's physical prestress σ held to the measured one
  within a factor (:class:`Anchor`; σ/measured of any fit, :func:`prestress_ratio`);
- :mod:`~tenscell.fitting.profile`: profile-likelihood intervals of the parameters the local analysis cannot bound
  (:func:`profile_intervals`, :meth:`FitResult.compute_profile`).

:func:`fit` runs them: ``fit(data)`` is the paper's per-tendon fit, ``fit(data, model=NAME)`` any other model.
The Markdown report is :func:`tenscell.reports.fit.fit_markdown`.
"""
from .entry import fit
from .fitted import FittedCell, FittedFormula, FittedMechanism, FittedModel, load_fit
from .models import (GROUPS, MODELS, RECOMMENDED, FitModel, Formula, Mechanism, Population, VoigtModel, get_model,
                     model_names)
from .models.population import FittedPopulation
from .models.catalog import MECHANISMS, PER_TENDON_VOIGT, mechanism_names
from .models.mechanism import Field
from .models.voigt import DAMPING_MODES, TENDON_MODES, FitProblem, make_problem, required_points
from .prestress import PrestressActivity, prestress_activity
from .records import DatasetFit, FitAlternative, FitCurve, FitParameter, data_axis
from .curves import frequency_slopes, model_curve, prestress_slopes
from .result import FitResult
from .shares import PrestressScale, StructureShares, StructureSummary, structure_shares, structure_summary
from .anchor import Anchor, prestress_ratio
from .profile import ParameterProfile, ProfileInterval, ProfileSet, profile_intervals, profile_parameter

#: one result type for every model: a mechanism's fit is a FitResult (the name of tenscell 0.2)
MechanismFit = FitResult
#: the fitted-model family's reader (the name of tenscell 0.2): any fit.json
load_any_fit = load_fit

__all__ = [
    "fit",
    "FitModel",
    "VoigtModel",
    "Mechanism",
    "Formula",
    "Population",
    "Field",
    "MODELS",
    "GROUPS",
    "RECOMMENDED",
    "get_model",
    "model_names",
    "MECHANISMS",
    "PER_TENDON_VOIGT",
    "mechanism_names",
    "TENDON_MODES",
    "DAMPING_MODES",
    "FitParameter",
    "FitAlternative",
    "FitResult",
    "FitCurve",
    "DatasetFit",
    "FittedModel",
    "FittedCell",
    "FittedMechanism",
    "FittedFormula",
    "FittedPopulation",
    "load_fit",
    "PrestressActivity",
    "prestress_activity",
    "data_axis",
    "FitProblem",
    "make_problem",
    "model_curve",
    "frequency_slopes",
    "prestress_slopes",
    "required_points",
    "MechanismFit",
    "load_any_fit",
    "StructureShares",
    "structure_shares",
    "StructureSummary",
    "structure_summary",
    "PrestressScale",
    "Anchor",
    "prestress_ratio",
    "ProfileSet",
    "ParameterProfile",
    "ProfileInterval",
    "profile_intervals",
    "profile_parameter",
]

from .._deprecated import moved_away  # noqa: E402

__getattr__ = moved_away(__name__)  # the public names of 0.2.0 that moved away: a DeprecationWarning names their home

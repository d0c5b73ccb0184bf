"""Heterogeneous fits of the linear tensegrity model to measured cell rheology.

The paper (Sultan, Stamenović & Ingber 2004, Figs. 4–5) fits tendon
stiffnesses, the damping c, the prestress P and the strut length L so that the
model's G', G'' match measured data; a homogeneous cell cannot do it. This
package does the same for any :class:`tenscell.io.data.RheologyData`:

- :mod:`~tenscell.fitting.layout`: the parameters, their names, units, bounds
  and fixes, and the data's arrays (:func:`required_points`, :data:`TENDON_MODES`);
- :mod:`~tenscell.fitting.problem`: residuals and their analytic Jacobian
  (:class:`FitProblem`, :func:`make_problem`), from the model and its
  derivatives in :mod:`~tenscell.fitting.derivatives`;
- :mod:`~tenscell.fitting.search`: starts, basin hopping, least squares,
  stopping (:func:`fit`);
- :mod:`~tenscell.fitting.result`: what a fit returns (:class:`FitResult`,
  :class:`FitParameter`, per-data-set :class:`DatasetFit`, model curves and slopes);
- :mod:`~tenscell.fitting.prestress`: is the prestress doing anything
  (:class:`PrestressActivity`);
- :mod:`~tenscell.fitting.mechanisms`, :mod:`~tenscell.fitting.mechanism_problem`,
  :mod:`~tenscell.fitting.mechanism_fit`, :mod:`~tenscell.fitting.heterogeneity`:
  few-parameter mechanisms (tendon laws with dynamics, cytoplasm, distributions of
  tendon properties) fitted by the same search (``fit(data, model=NAME)``);
- :mod:`~tenscell.fitting.shares`: what the structure carries, the geometric prestress stiffness's
  share of dG′/dP and dG″/dP against the law's tension terms (:func:`structure_shares`).

The Markdown report is :func:`tenscell.reports.fit.fit_markdown`.
"""
from .prestress import PrestressActivity, prestress_activity
from .problem import DAMPING_MODES, TENDON_MODES, FitProblem, make_problem, required_points
from .result import (DatasetFit, FitAlternative, FitCurve, FitParameter, FitResult, data_axis, frequency_slopes,
                     model_curve, prestress_slopes)
from .entry import fit
from .mechanisms import MECHANISMS, Field, Mechanism, mechanism_names
from .mechanism_fit import FittedMechanism, MechanismFit, fit_mechanism, load_any_fit
from .shares import StructureShares, structure_shares

__all__ = [
    "TENDON_MODES",
    "DAMPING_MODES",
    "FitParameter",
    "FitAlternative",
    "FitResult",
    "FitCurve",
    "DatasetFit",
    "PrestressActivity",
    "prestress_activity",
    "data_axis",
    "FitProblem",
    "make_problem",
    "fit",
    "model_curve",
    "frequency_slopes",
    "prestress_slopes",
    "required_points",
    "MECHANISMS",
    "Mechanism",
    "Field",
    "mechanism_names",
    "MechanismFit",
    "FittedMechanism",
    "fit_mechanism",
    "load_any_fit",
    "StructureShares",
    "structure_shares",
]

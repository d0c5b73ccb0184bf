"""Heterogeneous fits of the linear tensegrity model to measured cell rheology.

The paper (Sultan, Stamenović & Ingber 2004, Figs. 4–5) fits tendon
stiffnesses, the damping c, the prestress P and the strut length L so that the
model's G', G'' match measured data; a homogeneous cell cannot do it. This
package does the same for any :class:`tenscell.io.data.RheologyData`:

- :mod:`~tenscell.fitting.parameters`: the parameters, their names, units, bounds
  and fixes, and the data's arrays (:func:`required_points`, :data:`TENDON_MODES`);
- :mod:`~tenscell.fitting.models.voigt`: residuals and their analytic Jacobian
  (:class:`FitProblem`, :func:`make_problem`), from the model and its
  derivatives in :mod:`~tenscell.fitting.models.voigt_kernel`;
- :mod:`~tenscell.fitting.search`: starts, basin hopping, least squares,
  stopping (:func:`fit`);
- :mod:`~tenscell.fitting.result`: what a fit returns (:class:`FitResult`,
  :class:`FitParameter`, per-data-set :class:`DatasetFit`, model curves and slopes);
- :mod:`~tenscell.fitting.prestress`: is the prestress doing anything
  (:class:`PrestressActivity`);
- :mod:`~tenscell.fitting.models.mechanism`, :mod:`~tenscell.fitting.models.mechanism_problem`,
  :mod:`~tenscell.fitting.mechanism_fit`, :mod:`~tenscell.fitting.models.heterogeneity`:
  few-parameter mechanisms (tendon laws with dynamics, cytoplasm, distributions of
  tendon properties) fitted by the same search (``fit(data, model=NAME)``).

The Markdown report is :func:`tenscell.reports.fit.fit_markdown`.
"""
from .prestress import PrestressActivity, prestress_activity
from .models.voigt import DAMPING_MODES, TENDON_MODES, FitProblem, make_problem, required_points
from .result import (DatasetFit, FitAlternative, FitCurve, FitParameter, FitResult, data_axis, frequency_slopes,
                     model_curve, prestress_slopes)
from .entry import fit
from .models.mechanism import MECHANISMS, Field, Mechanism, mechanism_names
from .mechanism_fit import FittedMechanism, MechanismFit, fit_mechanism, load_any_fit

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
]

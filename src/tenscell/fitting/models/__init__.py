"""Every fittable model, one module per family, behind one registry.

* :mod:`~.voigt` — the paper's cell with Voigt tendons (per tendon, per family, homogeneous) and its kernel
  (:mod:`~.voigt_kernel`, :mod:`~.voigt_creep`);
* :mod:`~.mechanism` — few-parameter mechanisms (a tendon law, its parameters' layout, a cytoplasm, distributed
  properties: :mod:`~.heterogeneity`) and their problem (:mod:`~.mechanism_kernel`);
* :mod:`~.formulas` — structure-free formulas: the baselines a tensegrity has to beat;
* :mod:`~.population` — populations: any of these over many cells, with shared and per-cell parameters.

:data:`MODELS` holds every built-in model by name; :func:`get_model` looks one up (a
:class:`~.base.FitModel` passes through). A new mechanism on an existing law is one entry of the catalog
(:func:`.mechanism._builtin`) and its name in the command line's list (``cli/fit.py``; a test checks they agree).
"""
from __future__ import annotations

from .base import Capabilities, FitModel, model_from_dict
from .formulas import FORMULAS, Formula
from .catalog import MECHANISMS, PER_TENDON_VOIGT
from .mechanism import Field, Mechanism
from .population import Population
from .voigt import VoigtModel

__all__ = ["Capabilities", "FitModel", "VoigtModel", "Mechanism", "Field", "Formula", "Population", "MODELS", "GROUPS", "RECOMMENDED",
           "get_model", "model_names", "model_from_dict", "PER_TENDON_VOIGT", "baseline_of"]

#: the recommended model for a lab's first fit: the few-parameter mechanism of `tenscell study mechanisms` on the
#: bundled data in which the tensegrity earns its place — the paper's geometric prestress stiffness carries the
#: prestress dependence (issue 26, G1), anchored to the measured prestress, and it beats its structure-free formula
#: out of sample. `springpot-tension+visc` has the lowest BIC but writes G ∝ P into its tendon law (the structure
#: carries 2 %); docs/fitting.md gives both sets of numbers
RECOMMENDED = "springpot-alpha-family+visc"


def _registry() -> dict[str, FitModel]:
    voigt = [VoigtModel(), VoigtModel("per-family"), VoigtModel("uniform")]
    return {**{m.name: m for m in voigt}, **MECHANISMS, **FORMULAS}


#: every built-in model by name
MODELS: dict[str, FitModel] = _registry()


#: the models by group (FitModel.group), in the order the command line's help lists them
GROUPS: dict[str, tuple[str, ...]] = {}
for _name, _m in MODELS.items():
    GROUPS[_m.group] = GROUPS.get(_m.group, ()) + (_name,)
del _name, _m


def baseline_of(spec: FitModel) -> FitModel | None:
    """The baseline a fit of ``spec`` is shown beside (:meth:`FitModel.baseline`); None where there is none."""
    return spec.baseline()


def model_names() -> tuple[str, ...]:
    """Every name ``fit(model=...)`` and ``tenscell fit --model`` accept, the per-tendon Voigt fit first."""
    return tuple(MODELS)


def get_model(spec) -> FitModel:
    """A model from its name (a key of :data:`MODELS`) or itself (a :class:`FitModel`)."""
    if isinstance(spec, FitModel):
        return spec
    if isinstance(spec, str) and spec in MODELS:
        return MODELS[spec]
    raise ValueError(f"model must be a FitModel or one of {', '.join(MODELS)}, got {spec!r}")

from ..._deprecated import moved_away  # noqa: E402

__getattr__ = moved_away(__name__)  # the public names of 0.2.0 that moved away: a DeprecationWarning names their home

"""The model protocol: a fittable model is a frozen specification that builds its problem against data; a fit of
it gives a fitted model of the :class:`FittedModel` family.

In the manner of lmfit's ``Model``: a :class:`FitModel` says *what* is
fitted (a per-tendon Voigt cell, a mechanism, a structure-free formula, a
population of cells); :meth:`FitModel.problem` lays its parameters out
against data sets and returns a :class:`tenscell.fitting.problem.Problem`
(residuals, Jacobian, starts and moves); :func:`tenscell.fitting.fit` searches
it and returns the one result type, :class:`tenscell.fitting.FitResult`,
whose fitted model (:mod:`tenscell.fitting.fitted`) every consumer accepts.

A model round-trips through fit.json: :meth:`FitModel.to_dict` writes its
class name and fields, :func:`model_from_dict` rebuilds it (the classes
register themselves by subclassing).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..._checks import positive_scalar
from ..._errors import CapabilityError, TenscellError
from ..._results import reporter
from ...linear.linearize import LinearModel
from ...model.equilibrium import Cell

__all__ = ["Capabilities", "CapabilityError", "DATA_KINDS", "FitModel", "model_from_dict", "FittedModel", "FitFileError",
           "FITTED_KINDS", "cell_to_dict", "cell_from_dict", "frequencies_of", "field_of", "positive_values",
           "prestress_from"]

#: every fitted-model kind by its ``format`` tag (filled by FittedModel.__init_subclass__)
FITTED_KINDS: dict[str, type[FittedModel]] = {}

#: the kinds of data a model may fit: moduli G′, G″ against frequency and prestress; creep compliance J(t);
#: stress relaxation G(t)
DATA_KINDS = ("moduli", "creep", "relaxation")


@dataclass(frozen=True)
class Capabilities:
    """What a fittable model can do: generic code (the search, the result, shares, profiles, reports, studies and
    the command line) asks these, never the model's class (pyMOR's way: a model declares, consumers ask).

    Attributes
    ----------
    data_kinds : frozenset of str
        The kinds of :data:`DATA_KINDS` the model fits (a data set of another kind is refused in one line).
    structural : bool
        The model has a cell: a structure whose geometry and prestress carry the response (False for a
        structure-free formula).
    structure_shares : bool
        The split of dG*/dP into the geometric prestress stiffness P·Kp and the law's tension terms is defined
        (:mod:`tenscell.fitting.shares`).
    profile_fields : bool
        The model has held (fixed) law fields whose profile likelihood can be computed
        (:mod:`tenscell.fitting.profile`).
    lumped_terms : bool
        The model has its own structure-free formula (:meth:`FitModel.formula`): the baseline it must beat.
    voigt_options : bool
        The model takes the Voigt cell's options (``tendons``, ``damping``, the activity constraints).
    multimodal : bool
        Fits of the model have several basins on typical data: the search keeps its basin-hopping moves after two
        starts agree (the catalog marks these models).
    heterogeneous : bool
        A property is drawn from a distribution over the tendons (the fitted model has an ensemble).
    per_cell : bool
        A population: parameters of each cell's own beside shared ones.
    """

    data_kinds: frozenset = frozenset({"moduli"})
    structural: bool = True
    structure_shares: bool = False
    profile_fields: bool = False
    lumped_terms: bool = False
    voigt_options: bool = False
    multimodal: bool = False
    heterogeneous: bool = False
    per_cell: bool = False

    def __post_init__(self):
        kinds = frozenset(self.data_kinds)
        unknown = sorted(kinds - set(DATA_KINDS))
        if unknown or not kinds:
            raise ValueError(f"Capabilities.data_kinds: some of {', '.join(DATA_KINDS)}, got {sorted(kinds)!r}")
        object.__setattr__(self, "data_kinds", kinds)

    def fits(self, kind: str) -> bool:
        """Whether the model fits data of ``kind`` (one of :data:`DATA_KINDS`)."""
        return kind in self.data_kinds


#: every FitModel subclass by class name (filled by __init_subclass__): what model_from_dict rebuilds
_CLASSES: dict[str, type[FitModel]] = {}


class FitModel:
    """Base of every fittable model: a frozen dataclass with a ``name`` and a ``description``.

    Class attributes
    ----------------
    family : str
        ``"tensegrity"`` (a cell whose structure carries the response), ``"formula"`` (a structure-free law:
        the baselines a tensegrity has to beat) or ``"population"``.
    """

    family: ClassVar[str] = "tensegrity"
    name: str
    description: str

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        _CLASSES[cls.__name__] = cls

    def problem(self, data, cell=None, *, bounds: dict | None = None, fixed: dict | None = None):
        """The :class:`~tenscell.fitting.problem.Problem` of this model against ``data`` (one data set or a list).

        ``bounds``: ``{parameter name or kind: (lo, hi)}`` in SI units; ``fixed``: ``{parameter name: value}``.
        Bad input raises ValueError (or :class:`tenscell.io.data.DataError` for the data) naming it.
        """
        raise NotImplementedError

    @property
    def capabilities(self) -> Capabilities:
        """What this model can do (:class:`Capabilities`); every subclass declares its own."""
        return Capabilities(structural=self.structural, heterogeneous=self.heterogeneous,
                            lumped_terms=self.formula() is not None)

    @property
    def heterogeneous(self) -> bool:
        """Whether a property is drawn from a distribution over the tendons (the fitted model has an ensemble)."""
        return False

    @property
    def group(self) -> str:
        """The group the command line's help lists the model in."""
        return "other models"

    def baseline(self) -> FitModel | None:
        """The model a fit of this one is shown beside in its report (None: none)."""
        return None

    def formula(self) -> FitModel | None:
        """This model's own structure-free formula: its terms lumped into one element with the same prestress
        coupling, the baseline a tensegrity must beat out of sample (None for a formula itself)."""
        return None

    @property
    def structural(self) -> bool:
        """Whether the model has a cell (a structure whose geometry and prestress carry the response)."""
        return self.family != "formula"

    def with_options(self, **options) -> FitModel:
        """The same model with the Voigt cell's options (``tendons``, ``damping``, ``min_prestress_share``,
        ``max_decades``, ``min_prestress_elasticity``, ``elasticity_frequency_hz``) set; itself when none is given.
        CapabilityError naming them for a model without them (``capabilities.voigt_options`` False)."""
        if options:
            raise CapabilityError(f"{', '.join(options)}: option(s) of the Voigt cell, not of model={self.name!r}")
        return self

    def min_points(self) -> int:
        """The fewest points one data set needs for this model (an early check; the problem's own is exact)."""
        return 2

    def held_fields(self) -> tuple[tuple[str, float], ...]:
        """``(name, value)`` of every law parameter the model holds at a value (not fitted, not counted; their
        profiles free them one at a time: :meth:`freed`); none by default."""
        return ()

    def freed(self, name: str) -> FitModel:
        """The model with its held field ``name`` (:meth:`held_fields`) laid out as one fitted parameter.
        CapabilityError for a model without held fields."""
        raise CapabilityError(f"model {self.name!r} holds no field {name!r} (it has no held fields to free)")

    def to_dict(self) -> dict:
        """JSON-ready: the class name and every field (rebuilt by :func:`model_from_dict`)."""
        return {"class": type(self).__name__, **dataclasses.asdict(self)}  # type: ignore[call-overload]

    @classmethod
    def from_fields(cls, fields: dict) -> FitModel:
        """The model from the fields :meth:`to_dict` wrote (a subclass with nested fields rebuilds them)."""
        return cls(**fields)


def model_from_dict(obj: dict) -> FitModel:
    """The model written by :meth:`FitModel.to_dict` (ValueError naming what is wrong)."""
    if not isinstance(obj, dict) or obj.get("class") not in _CLASSES:
        known = ", ".join(sorted(_CLASSES))
        got = obj.get("class") if isinstance(obj, dict) else type(obj).__name__
        raise ValueError(f"not a tenscell model description: class {got!r} (known: {known})")
    cls = _CLASSES[obj["class"]]
    fields = {k: v for k, v in obj.items() if k != "class"}
    try:
        return cls.from_fields(fields)
    except TypeError as err:  # a missing or unknown field
        raise ValueError(f"model {obj.get('name', obj['class'])!r}: {err}") from None


# ---------------------------------------------------------------------------------------
# what a fit of a model gives
# ---------------------------------------------------------------------------------------
class FitFileError(TenscellError, ValueError):
    """A fit.json that cannot be used: unreadable, of another version, or with a missing or out-of-range field."""


class FittedModel:
    """What every fitted model answers (the subclasses are frozen dataclasses with these fields).

    Attributes
    ----------
    s : float or None
        Prestress scale (m²): the model prestress is ``s × prestress (Pa)``.
    P : float or None
        Model prestress (N) when the data stated no prestress.
    prestress_pa : tuple of float
        The data's prestresses (Pa), measured or fitted, when ``s`` is used (the default is their median).
    source : str
        What was fitted (for messages).
    """

    s: float | None
    P: float | None
    prestress_pa: tuple
    source: str
    #: the ``format`` tag of :meth:`to_dict` (each kind registers itself under it: :func:`fitted_from_dict`)
    FORMAT = ""

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        if cls.FORMAT:
            FITTED_KINDS[cls.FORMAT] = cls

    @classmethod
    def from_dict(cls, obj: dict) -> FittedModel:
        """Rebuild from :meth:`to_dict`."""
        raise NotImplementedError

    def _check_prestress(self) -> None:
        if (self.P is None) == (self.s is None):
            raise ValueError("a fitted model has either a prestress P (N) or a prestress scale s (m²), not both")
        object.__setattr__(self, "prestress_pa", tuple(float(x) for x in self.prestress_pa))

    # -- the prestress --------------------------------------------------------------------
    @property
    def default_prestress_pa(self) -> float | None:
        """The median measured prestress (Pa) when the model uses ``s``; None otherwise."""
        return float(np.median(self.prestress_pa)) if self.s is not None and self.prestress_pa else None

    def prestress(self, prestress_pa: float | None = None) -> float:
        """Model prestress P (N): the fitted P, or ``s × prestress_pa`` (default the data's median prestress)."""
        if self.s is None:
            if prestress_pa is not None:
                raise ValueError("this fit has a fitted prestress P (N): no data set stated its prestress, so a "
                                 "prestress in Pa has no model equivalent")
            assert self.P is not None  # a fit without a prestress scale fits P itself
            return float(self.P)
        if prestress_pa is None:
            prestress_pa = self.default_prestress_pa
            if prestress_pa is None:
                raise ValueError("prestress_pa (Pa) is required: the fit scales measured prestresses by s")
        return float(self.s) * positive_scalar("prestress", prestress_pa, "Pa")

    def prestress_label(self, prestress_pa: float | None = None) -> tuple[str, float]:
        """``(column, value)`` naming the prestress a table row is at: ``("prestress_Pa", Pa)`` for a model with a
        prestress scale, ``("prestress_N", N)`` (the fitted model prestress) otherwise."""
        if self.s is not None:
            shown = prestress_pa if prestress_pa is not None else self.default_prestress_pa
            assert shown is not None  # a model with a prestress scale keeps its data's prestresses
            return "prestress_Pa", float(shown)
        return "prestress_N", self.prestress(None)

    def _prestress_fields(self) -> dict:
        return {"s_m2": self.s, "P_N": self.P, "prestress_Pa": list(self.prestress_pa), "source": self.source}

    # -- what each kind computes ------------------------------------------------------------
    @property
    def spec(self) -> FitModel:
        """The model that was fitted (:class:`FitModel`)."""
        raise NotImplementedError

    @property
    def capabilities(self) -> Capabilities:
        """What the fitted model can do: its model's :class:`Capabilities`."""
        return self.spec.capabilities

    @property
    def structural(self) -> bool:
        """Whether the model has a cell (False for a structure-free formula)."""
        return True

    def evaluation(self):
        """``(problem, phi)``: a problem without data that evaluates the fitted model anywhere, at its fitted
        log-parameters ``phi`` (what :func:`tenscell.fitting.shares.structure_shares` differentiates).
        CapabilityError for a model without one."""
        raise CapabilityError(f"{self.describe()} has no law tension terms to split from the geometric prestress "
                              "stiffness (structure shares are defined for a mechanism)")

    @property
    def assignments(self) -> int:
        """K, the assignments of a distributed tendon property the fitted moduli average over (1: none)."""
        return 1

    def ensemble_problem(self, K: int, seed: int | None = None):
        """``(problem, phi, seed)``: a problem without data whose evaluation gives the moduli of K assignments of the
        distributed tendon property (seed: the model's own when None), at the fitted log-parameters ``phi``.
        CapabilityError for a model without a distributed property (``capabilities.heterogeneous`` False)."""
        raise CapabilityError(f"{self.describe()} draws no tendon property from a distribution: every assignment is "
                              "the same cell, so it has no ensemble")

    @property
    def viscosity(self) -> float:
        """A cytoplasm viscosity η (Pa·s) in parallel with the structure; 0 without one."""
        return 0.0

    def moduli(self, f_hz, prestress_pa: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """G′, G″ (Pa) at frequencies ``f_hz`` (Hz) and one prestress (Pa, see :meth:`prestress`)."""
        raise NotImplementedError

    def parameter_values(self) -> dict:
        """The fitted parameters by name (SI units): a number per named parameter, or an array over the tendons (the
        Voigt cell's ``EA``, ``c``); what a fitted model shows of itself."""
        return {}

    def with_values(self, values: dict, **prestress) -> FittedModel:
        """The same fitted model with some of its named parameters (``values``, SI units) and its prestress mapping
        (``P`` or ``s``) replaced: one cell of a population. CapabilityError for a model whose parameters are not
        named values (the Voigt cell's per-tendon stiffnesses); ValueError naming an unknown parameter."""
        raise CapabilityError(f"{self.describe()} has no named parameter values to set")

    def tendon_law(self, assignment: int = 0):
        """The tendon law of every tendon (a :class:`tenscell.laws.TendonLaw`), for the time domain and ``show``."""
        raise CapabilityError(f"{self.describe()} has no tendons: it is a structure-free formula (a baseline), not a "
                         "tensegrity")

    def linear(self, prestress_pa: float | None = None, *, P_N: float | None = None) -> LinearModel:
        """The linear model at the fitted parameters (see :meth:`prestress`), or at model prestress ``P_N`` (N)."""
        raise CapabilityError(f"{self.describe()} has no cell: it is a structure-free formula (a baseline), not a "
                         "tensegrity")

    def voigt_tendons(self, P_N: float) -> tuple[np.ndarray, np.ndarray]:
        """(EA in N, c in N·s/m) per tendon of the Voigt tendons equivalent at rest at model prestress ``P_N``:
        the fitted ones for Voigt tendons, the tangent stiffness and damping of the linear model otherwise
        (what ``show`` and the time domain's Voigt law take)."""
        raise CapabilityError(f"{self.describe()} has no tendons: it is a structure-free formula (a baseline), not a "
                         "tensegrity")

    def describe(self) -> str:
        """One line: what this fitted model is."""
        raise NotImplementedError

    def _repr_html_(self) -> str:
        return reporter("fitted_model_html")(self)  # what it is, its values, its prestress (reports/html.py)

    def to_dict(self) -> dict:
        """JSON-ready (fit.json's ``"model"`` entry); :func:`fitted_from_dict` rebuilds it."""
        raise NotImplementedError

    def _named_values(self) -> dict:
        """``parameter_values`` of a model whose parameters are its ``values`` dict (a mechanism, a formula)."""
        return dict(self.values)  # type: ignore[attr-defined]  # the subclasses that call this have named values

    def _replaced_values(self, values: dict, prestress: dict) -> FittedModel:
        """``with_values`` of a model whose parameters are its ``values`` dict (a mechanism, a formula)."""
        own = self.values  # type: ignore[attr-defined]  # the subclasses that call this have named values
        unknown = sorted(set(values) - set(own))
        if unknown:
            raise ValueError(f"{unknown[0]!r} is not a parameter of {self.describe()} (parameters: {', '.join(own)})")
        return dataclasses.replace(self, values={**own, **values}, **prestress)  # type: ignore[type-var]

    def _resolve_P(self, prestress_pa, P_N) -> float:
        return self.prestress(prestress_pa) if P_N is None else positive_scalar("P_N", P_N, "N")


def frequencies_of(f_hz) -> np.ndarray:
    f = np.atleast_1d(np.asarray(f_hz, dtype=float)).ravel()
    if not (f.size and np.all(np.isfinite(f)) and np.all(f > 0)):
        raise ValueError("frequencies must be finite numbers > 0 (Hz)")
    return f


def field_of(obj: dict, key: str, kind: type):
    if key not in obj:
        raise FitFileError(f"model.{key}: missing")
    value = obj[key]
    if not isinstance(value, kind):
        raise FitFileError(f"model.{key}: expected {kind.__name__}, got {type(value).__name__}")
    return value


def positive_field(where: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise FitFileError(f"{where}: expected a finite number > 0, got {value!r}")
    return float(value)


def positive_values(obj: dict) -> dict:
    return {str(k): positive_field(f"model.values.{k}", v) for k, v in field_of(obj, "values", dict).items()}


def prestress_from(obj: dict) -> dict:
    s, P = obj.get("s_m2"), obj.get("P_N")
    if (s is None) == (P is None):
        raise FitFileError("model: exactly one of s_m2 (prestress scale, m²) and P_N (model prestress, N) is given")
    pres = obj.get("prestress_Pa") or []
    if not isinstance(pres, list):
        raise FitFileError(f"model.prestress_Pa: expected a list of prestresses (Pa), got {type(pres).__name__}")
    return {"s": None if s is None else positive_field("model.s_m2", s), "P": None if P is None else positive_field("model.P_N", P),
            "prestress_pa": tuple(positive_field("model.prestress_Pa[]", p) for p in pres),
            "source": str(obj.get("source", ""))}


def cell_to_dict(cell: Cell, **member_values) -> dict:
    """The JSON entries that rebuild ``cell`` (:func:`cell_from_dict`): its structure file with ``T0``
    (and any per-member values such as ``EA``, ``c``), its parametrization and its construction parameters."""
    from ...io.structure_files import structure_to_dict

    return {"structure": structure_to_dict(cell.structure, T0=cell.T0, **member_values),
            "parametrization": cell.coords.kind,
            "cell_parameters": {k: (v if isinstance(v, (bool, str)) else float(v)) for k, v in cell.parameters.items()}}


def cell_from_dict(obj: dict):
    """``(cell, structure_file)`` from the entries :func:`cell_to_dict` wrote (the file keeps its member values)."""
    from ...io.structure_files import structure_from_dict

    sf = structure_from_dict(field_of(obj, "structure", dict))
    from ...model.equilibrium import equilibrate

    cell = equilibrate(sf.structure, obj.get("parametrization", "angles"), T0=sf.T0,
                       parameters=obj.get("cell_parameters") or {})
    return cell, sf

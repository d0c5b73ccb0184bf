"""Mechanisms: frozen, few-parameter specifications of what sets a cell's moduli, each one fittable.

A :class:`Mechanism` names a tendon law (a class of :mod:`tenscell.laws` with a
dynamic tangent ``complex_stiffness``) and says how each of the law's
parameters is laid out over the tendons (:class:`Field`): one value per
family (actin / intermediate filament), one value shared by every tendon, a
fixed value, or drawn from a named distribution
(:mod:`tenscell.fitting.models.heterogeneity`) whose scale is per family or shared
and whose shape (spread in decades, or a trap-model exponent) is one more
parameter. Optionally a cytoplasm viscosity η (Pa·s) acts in parallel with the
structure. The prestress parameters come from the data exactly as in the
per-tendon fit (:mod:`tenscell.fitting.models.voigt`).

The per-tendon stiffnesses, damping and prestress of a mechanism are those of
the reference cell (strut length ``L_ref``, 1 m for the paper cell): the
strut length is not a parameter, because ``(P, EA, c, L) -> (λ²P, λ²EA, λc,
λL)`` leaves the moduli unchanged; a mechanism has no gauge.

The built-in ones are in :mod:`~tenscell.fitting.models.catalog`.

Against data a mechanism is a :class:`MechanismProblem`: parameter layout, moduli averaged over assignments,
residuals, exact Jacobian (:mod:`~tenscell.fitting.models.mechanism_kernel`). For parameters ``φ`` (natural logs), each field of the :class:`Mechanism`
gives the law parameter of every tendon in every assignment k (K × m values,
:mod:`~tenscell.fitting.models.heterogeneity`), the law gives the dynamic tangent
``k*_j(ω)`` at the tensions ``P·T0`` and its exact derivatives
(``complex_stiffness_derivatives``), and the kernel
:func:`tenscell.linear.dynamic.dynamic_compliance` gives J(ω) and the exact
``dJ`` along any set of directions in k*. Three kinds of direction:

* a mechanism parameter q: ``Σ_p (∂k*/∂x_p)·x_p·∂ln x_p/∂φ_q``;
* the prestress: J is homogeneous of degree −1 in (P, k*) together
  (K(ω) = P·H + Σ k*_j a_j a_jᵀ), so ``P ∂J/∂P|_k* = −J − Σ_j k*_j ∂J/∂k*_j``,
  i.e. ``−J − dJ[k*]``, plus ``dJ[P·(∂k*/∂T)·T0]`` for the law's tension
  dependence: exact, from the kernel alone;
* the viscosity adds ``iωη`` to G*: its derivative is itself.

The moduli are ``G* = mean_k (0.5/L)/J_k + iωη``; their spread between the
assignments (decades, per point) is reported.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ... import laws as _laws
from ...io.data import DataError
from ...model.equilibrium import Cell
from .heterogeneity import DISTRIBUTIONS, assignments
from .mechanism_kernel import (EvaluationPlan, MechanismEvaluation, evaluate, evaluate_cells, evaluate_planned,
                               law_values, plan_points)
from ..parameters import (Parameters, as_datasets, bounds_by_name, default_bounds, family_groups, fixed_by_name,
                          prestress_layout)
from ..._results import format_repr
from ...linear.dynamic import DynamicKernel, dynamic_kernel
from ...linear.linearize import LinearModel
from .base import (Capabilities, FitFileError, FitModel, FittedModel, cell_from_dict, cell_to_dict, field_of, frequencies_of, model_from_dict,
                   positive_values, prestress_from)
from ..problem import PENALTY as _PENALTY, Problem, draw_start, jitter, log_residual_blocks
from ..time_series import (TimeLayout, data_layout, modulus_scales, relative_values, time_residual_values,
                           time_values)

__all__ = ["Field", "Mechanism", "KINDS", "MechanismProblem", "make_mechanism_problem", "MechanismEvaluation", "bare_problem",
           "FittedMechanism", "MECHANISM_FORMAT"]

#: what a parameter kind is, for bounds and starts: (unit, scales G when all scalable ones scale together)
KINDS = {
    "stiffness": ("N", True),
    "damping": ("N·s/m", True),
    "coefficient": ("N (at 1 rad/s)", True),
    "time": ("s", False),
    "exponent": ("", False),
    "decades": ("decades", False),
    "tail": ("", False),
    "viscosity": ("Pa·s", True),
    "ratio": ("", False),  # a dimensionless modulus per unit tension (TensionSpringpot's beta)
}
#: the layouts of a law parameter over the tendons
LAYOUTS = ("family", "shared", "fixed")


@dataclass(frozen=True)
class Field:
    """How one law parameter is laid out over the tendons.

    Attributes
    ----------
    law_parameter : str
        The parameter's name in the law (e.g. ``"EA"``, ``"c"``, ``"alpha"``).
    kind : str
        A key of :data:`KINDS` (bounds and starts).
    layout : {"family", "shared", "fixed"}
        One fitted value per family, one for all tendons, or ``value`` for all.
    distribution : str or None
        A key of :data:`~tenscell.fitting.models.heterogeneity.DISTRIBUTIONS`: the
        layout's value(s) are the distribution's scale and one more parameter
        (its shape, shared by the families) spreads the tendons.
    value : float or None
        The value of a fixed parameter (SI units).
    """

    law_parameter: str
    kind: str
    layout: str = "family"
    distribution: str | None = None
    value: float | None = None

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"Field {self.law_parameter!r}: kind must be one of {', '.join(KINDS)}, got {self.kind!r}")
        if self.layout not in LAYOUTS:
            raise ValueError(f"Field {self.law_parameter!r}: layout must be one of {', '.join(LAYOUTS)}, "
                             f"got {self.layout!r}")
        if (self.layout == "fixed") != (self.value is not None):
            raise ValueError(f"Field {self.law_parameter!r}: a value is given exactly for the fixed layout")
        if self.distribution is not None and self.distribution not in DISTRIBUTIONS:
            raise ValueError(f"Field {self.law_parameter!r}: distribution must be one of "
                             f"{', '.join(DISTRIBUTIONS)}, got {self.distribution!r}")
        if self.distribution is not None and self.layout == "fixed":
            raise ValueError(f"Field {self.law_parameter!r}: a fixed parameter has no distribution")


@dataclass(frozen=True)
class Mechanism(FitModel):
    """A fittable mechanism: a tendon law, its parameters' layout, a cytoplasm, the heterogeneity's sampling.

    Attributes
    ----------
    name : str
    law : str
        Class name in :mod:`tenscell.laws` (``"Voigt"``, ...).
    fields : tuple of Field
        One per parameter of the law, in any order.
    viscosity : bool
        A cytoplasm viscosity η (Pa·s) in parallel with the structure.
    assignments : int
        K, the number of stratified assignments the moduli are averaged over
        (used only when a field has a distribution).
    seed : int
        Seed of the assignments.
    description : str
    multimodal : bool
        Fits of the mechanism have several basins on typical data (measured on the bundled pair:
        ``bench/multimodal_catalog.py``): the search keeps its basin hops after two starts agree. A fit.json written
        before this field existed reads False.
    """

    name: str
    law: str
    fields: tuple
    viscosity: bool = False
    assignments: int = 8
    seed: int = 0
    description: str = ""
    multimodal: bool = False

    def __post_init__(self):
        names = [f.law_parameter for f in self.fields]
        if len(set(names)) != len(names):
            raise ValueError(f"mechanism {self.name!r}: a law parameter is laid out twice")
        if isinstance(self.assignments, bool) or not isinstance(self.assignments, int) or self.assignments < 1:
            raise ValueError(f"mechanism {self.name!r}: assignments must be an integer >= 1")
        _check_law(self.name, self.law)

    @property
    def law_class(self) -> type[_laws.TendonLaw]:
        """The tendon law's class (:data:`tenscell.laws.LAWS`)."""
        return _laws.LAWS[self.law]

    @property
    def heterogeneous(self) -> bool:
        """Whether a field is drawn from a distribution (the moduli are then averaged over K assignments)."""
        return any(f.distribution is not None for f in self.fields)

    @property
    def K(self) -> int:
        """Assignments actually used: :attr:`assignments` if heterogeneous, else 1."""
        return self.assignments if self.heterogeneous else 1

    @property
    def capabilities(self) -> Capabilities:
        """Moduli, creep and relaxation; the structure's share of dG*/dP; held fields to profile; its lumped formula;
        multimodal when the catalog says so."""
        return Capabilities(data_kinds=frozenset({"moduli", "creep", "relaxation"}), structure_shares=True,
                            profile_fields=any(f.layout == "fixed" for f in self.fields), lumped_terms=True,
                            heterogeneous=self.heterogeneous, multimodal=bool(self.multimodal))

    @property
    def group(self) -> str:
        """The law's own group (its ``mechanism_group``)."""
        return str(self.law_class.mechanism_group)

    def held_fields(self) -> tuple[tuple[str, float], ...]:
        """``(law parameter, value)`` of every field of the fixed layout."""
        return tuple((f.law_parameter, float(f.value)) for f in self.fields if f.layout == "fixed")

    def freed(self, name: str) -> Mechanism:
        """The mechanism with the held field ``name`` laid out as one shared parameter."""
        if name not in dict(self.held_fields()):
            return super().freed(name)  # type: ignore[return-value]  # it raises
        fields = tuple(dataclasses.replace(f, layout="shared", value=None) if f.law_parameter == name else f
                       for f in self.fields)
        return dataclasses.replace(self, fields=fields)

    def baseline(self):
        """Its own structure-free formula (:func:`tenscell.fitting.models.formulas.lumped_formula`)."""
        return self.formula()

    def formula(self):
        from .formulas import lumped_formula

        return lumped_formula(self)

    def problem(self, data, cell=None, *, bounds=None, fixed=None):
        return make_mechanism_problem(data, self, cell, bounds=bounds, fixed=fixed)

    @classmethod
    def from_fields(cls, fields: dict) -> Mechanism:
        return cls(**{**fields, "fields": tuple(Field(**f) for f in fields["fields"])})




def _check_law(name: str, law: str) -> None:
    """ValueError naming the law and what it lacks, unless ``law`` is a law of :data:`tenscell.laws.LAWS` that can
    carry a mechanism: per-tendon parameters, the group the command line lists it in and its lumped formula's terms
    (class attributes of the law: a mechanism on any law needs no table of its own here)."""
    from .formulas import TERMS

    cls = _laws.LAWS.get(law)
    if cls is None:
        raise ValueError(f"mechanism {name!r}: tenscell.laws has no law {law!r} (laws: {', '.join(_laws.LAWS)})")
    lacks = [what for what, ok in (
        ("per-tendon parameters (parameters)", bool(cls.parameters)),
        ("the group the command line lists its mechanisms in (mechanism_group)", bool(cls.mechanism_group)),
        (f"the terms of its lumped formula (lumped_terms, some of {', '.join(TERMS)})",
         bool(cls.lumped_terms) and set(cls.lumped_terms or ()) <= set(TERMS)),
    ) if not ok]
    if lacks:
        raise ValueError(f"mechanism {name!r}: law {law} cannot carry a mechanism: it lacks {'; '.join(lacks)}")


def _field_params(f: Field, fams: list[str]) -> list[tuple[str, str, str, str]]:
    """(name, unit, kind, description) of a field's parameters: its scale(s), then its distribution's shape."""
    unit = KINDS[f.kind][0]
    what = f"{f.law_parameter} ({f.kind})"
    if f.layout == "fixed":
        return []
    if f.layout == "family":
        out = [(f"{f.law_parameter}_{fam}", unit, f.kind, f"{what} of every {fam} tendon") for fam in fams]
    else:
        out = [(f.law_parameter, unit, f.kind, f"{what} of every tendon")]
    if f.distribution is not None:
        dist = DISTRIBUTIONS[f.distribution]
        shape, sunit = dist.parameters[1], dist.shape_unit
        out = [(n, u, k, d.replace(f"{what} of", f"{f.distribution} {dist.parameters[0]} of {what} over"))
               for n, u, k, d in out]
        kind = "decades" if sunit == "decades" else "tail"
        out.append((f"{f.law_parameter}_{shape}", sunit, kind,
                    f"{f.distribution} {shape} of {f.law_parameter} over the tendons"))
    return out


@dataclass(frozen=True, eq=False, repr=False)
class MechanismProblem(Problem):
    """A mechanism's moduli against one or several data sets (built by :func:`make_mechanism_problem`).

    Duck-types the parts of :class:`~tenscell.fitting.models.voigt.FitProblem` that
    the search (:func:`tenscell.fitting.search.run_search`) and
    :func:`~tenscell.fitting.identifiability.identifiability` use, and adds
    its own starts (:meth:`initial_guess`) and moves (:meth:`perturb`).
    """

    mechanism: Mechanism
    cell: Cell
    params: Parameters
    n_field: int  # parameters of the fields (they come first)
    field_maps: tuple  # per field: (law parameter, D (K, m, n_params) d ln x/d φ, const (K, m)) ln x = const + D φ
    shape_maps: tuple  # per field with a distribution: (law parameter, shape's index, distribution, u (K, m))
    eta_index: int | None
    L_ref: float
    lengths: np.ndarray
    T0: np.ndarray
    sources: tuple
    omega: np.ndarray
    dataset_index: np.ndarray
    group_index: np.ndarray
    group_log_offset: np.ndarray
    group_map: np.ndarray
    group_measured: np.ndarray
    y_obs: np.ndarray
    weights: np.ndarray
    prestress_start: int

    tendons: str = "mechanism"
    #: the cell's matrices for the batched solve and the data points' plan (:mod:`.mechanism_kernel`): made once,
    #: when the problem is built (None: made in ``__post_init__``), never on first use
    kernel: DynamicKernel | None = None
    plan: EvaluationPlan | None = None
    #: creep and relaxation points (:mod:`tenscell.fitting.time_series`) and the plan of their contour nodes
    time: TimeLayout | None = None
    time_plan: EvaluationPlan | None = None

    def __post_init__(self):
        if self.kernel is None:
            object.__setattr__(self, "kernel", dynamic_kernel(self.cell))
        if self.plan is None:
            object.__setattr__(self, "plan", plan_points(self.omega, self.group_index))
        if self.time is not None and self.time_plan is None:
            object.__setattr__(self, "time_plan", plan_points(self.time.nodes, self.time.node_group))
        for _, D, const in self.field_maps:  # shared by every evaluation (law_values hands them out)
            D.setflags(write=False)
            const.setflags(write=False)

    def __repr__(self) -> str:
        return (f"MechanismProblem({self.mechanism.name}: {self.n_free} free of {self.n_params} parameters, "
                f"{self.n_datasets} data set(s), {self.n_points} points)")

    @property
    def spec(self) -> Mechanism:
        """The :class:`~tenscell.fitting.models.mechanism.Mechanism` of this problem."""
        return self.mechanism

    # -- layout (the rest in fitting.problem.Problem) ---------------------------
    @property
    def prestress_slice(self) -> slice:
        return slice(self.prestress_start, self.n_params)

    def gauge(self) -> np.ndarray:
        """No gauge: the strut length is not a parameter (module docstring of :mod:`.mechanisms`)."""
        return np.zeros(self.n_params)

    def coordinate_map(self) -> np.ndarray:
        return np.eye(self.n_free)

    def coordinate_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.bounds

    def to_coordinates(self, theta) -> np.ndarray:
        return np.asarray(theta, dtype=float).copy()

    # -- the model ---------------------------------------------------------------------
    @property
    def law_class(self) -> type[_laws.TendonLaw]:
        """The tendon law's class (:mod:`tenscell.laws`)."""
        return self.mechanism.law_class

    @property
    def law_names(self) -> tuple:
        """The law's parameters, in the order of its derivatives."""
        return tuple(p.name for p in self.law_class.parameters)

    def law_values(self, phi) -> tuple[dict, dict]:
        """Per law parameter: values (K, m) and d ln value / d φ (K, m, n_params), at log-parameters ``phi``."""
        return law_values(self, phi)

    def _group_P(self, phi) -> np.ndarray:
        """Model prestress (N) of each group on the reference cell, at log-parameters ``phi``."""
        return np.exp(self.group_log_offset + self.group_map @ phi[self.prestress_slice])

    def evaluate(self, phi, omega, P, jac: bool, dP=None) -> MechanismEvaluation | None:
        """Moduli at angular frequencies ``omega`` (rad/s) and model prestresses ``P`` (N), per point
        (:func:`~tenscell.fitting.models.mechanism_kernel.evaluate`); None where not a stable cell."""
        return evaluate(self, phi, omega, P, jac, dP)

    # -- at the data points ----------------------------------------------------------------
    def _at_data(self, phi, jac: bool) -> MechanismEvaluation | None:
        if not self.n_points:  # time data only
            return MechanismEvaluation(G=np.zeros(0, complex), G_assign=np.zeros((1, 0), complex),
                                       dG=np.zeros((0, self.n_params), complex) if jac else None)
        dP = None
        if jac:
            dP = np.zeros((self.n_points, self.n_params))
            dP[:, self.prestress_slice] = self.group_map[self.group_index]
        assert self.plan is not None
        return evaluate_planned(self, phi, self.plan, self.omega, self._group_P(phi), jac, dP)

    def _at_times(self, phi, jac: bool):
        """``(time function at every time point, its d/dφ or None)`` from ``G*(s)`` at the contour nodes
        (:func:`~tenscell.fitting.time_series.time_values`); None where the cell is not stable."""
        assert self.time is not None and self.time_plan is not None
        dP = None
        if jac:
            dP = np.zeros((self.time.nodes.size, self.n_params))
            dP[:, self.prestress_slice] = self.group_map[self.time.node_group]
        out = evaluate_planned(self, phi, self.time_plan, self.time.nodes, self._group_P(phi), jac, dP, laplace=True)
        return None if out is None else time_values(self.time, out.G, out.dG)

    def _evaluate_constrained(self, phi, jac: bool):
        return self._at_data(phi, jac), (None if self.time is None else self._at_times(phi, jac))

    def _evaluate_cells(self, cells, phis, jac: bool) -> tuple:
        if any(pb.time is not None for pb in cells):  # time data: each cell's own contour, one by one
            return super()._evaluate_cells(cells, phis, jac)
        # moduli only: many cells in one batched solve (a population), each as _evaluate_constrained pairs it
        return tuple((mod, None) for mod in evaluate_cells(cells, phis, jac))

    def _moduli_of(self, out):
        mod = out[0]
        return None if mod is None else (mod.G, mod.dG)

    def _residuals_from(self, out) -> np.ndarray:
        mod, tim = out
        if mod is None or not (np.all(mod.G.real > 0) and np.all(mod.G.imag > 0)):
            return np.full(self.y_obs.size, _PENALTY)
        parts = [np.log10(mod.G.real), np.log10(mod.G.imag)]
        if self.time is not None:
            lt = None if tim is None else time_residual_values(self.time, tim[0])[0]
            if lt is None or not np.all(np.isfinite(lt)):
                return np.full(self.y_obs.size, _PENALTY)
            parts.append(lt)
        return self.weights * (np.concatenate(parts) - self.y_obs)

    def _jacobian_from(self, out) -> np.ndarray:
        mod, tim = out
        if mod is None or mod.dG is None or (self.time is not None and tim is None):
            return np.zeros((self.y_obs.size, self.n_free))
        blocks = [log_residual_blocks(mod.G, mod.dG[:, self.free])]
        if self.time is not None:
            dl = time_residual_values(self.time, *tim)[1]
            assert dl is not None  # asked with the derivatives
            blocks.append(np.nan_to_num(dl[:, self.free]))
        return self.weights[:, None] * np.vstack(blocks)

    def moduli(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """Model G', G'' (Pa) at the data points; NaN where the model is not a stable cell."""
        out = self._at_data(self.full(theta), jac=False)
        if out is None:
            return np.full(self.n_points, np.nan), np.full(self.n_points, np.nan)
        return out.G.real, out.G.imag

    def time_model(self, theta) -> np.ndarray:
        """J(t) (1/Pa), G(t) (Pa) or a shape's G(t)/G(t_ref) at every time point; NaN where not a stable cell."""
        assert self.time is not None
        tim = self._at_times(self.full(theta), jac=False)
        return relative_values(self.time, None if tim is None else tim[0])

    def laplace_moduli(self, phi, s, P_N) -> np.ndarray:
        """``G*(s)`` (Pa) at complex Laplace variables ``s`` (1/s) and model prestresses ``P_N`` (N), broadcast, at
        log-parameters ``phi``; NaN where not a stable cell."""
        s, P = np.broadcast_arrays(np.asarray(s, dtype=complex), np.asarray(P_N, dtype=float))
        out = evaluate(self, phi, s, P, False, laplace=True)
        return np.full(s.shape, np.nan + 0j) if out is None else out.G.reshape(s.shape)

    def assignments_subset(self, lo: int, hi: int) -> "MechanismProblem":
        """The same problem restricted to assignments ``lo .. hi-1`` (a slice of every field's and shape's map).

        Each assignment's moduli depend only on its own row of the maps, so the moduli of a subset are those
        rows of :attr:`MechanismEvaluation.G_assign`: an ensemble can be evaluated in pieces, anywhere.
        """
        K = self.field_maps[0][1].shape[0]
        if not (0 <= lo < hi <= K):
            raise ValueError(f"assignments {lo}..{hi - 1}: outside the problem's {K} assignments")
        fields = tuple((name, D[lo:hi], const[lo:hi]) for name, D, const in self.field_maps)
        shapes = tuple((name, idx, dist, u[lo:hi]) for name, idx, dist, u in self.shape_maps)
        return dataclasses.replace(self, field_maps=fields, shape_maps=shapes)

    def assignment_spread(self, theta) -> tuple[float, float]:
        """Largest spread (decades) of G' and of G'' between the K assignments over the data points."""
        out = self._at_data(self.full(theta), jac=False)
        if out is None or out.G_assign.shape[0] < 2 or not out.G.size:
            return 0.0, 0.0
        Ga = out.G_assign
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.std(np.log10(Ga.real), axis=0), np.std(np.log10(Ga.imag), axis=0)
        return float(np.nanmax(s[0])), float(np.nanmax(s[1]))

    def feasible(self, theta) -> bool:
        """No activity constraints: always True."""
        return True

    def stiffness_spread(self, theta) -> tuple[float, float, float]:
        """(min, max, decades) over the tendons and assignments of the stiffness fields (stiffnesses, springpot
        moduli): the widest field's (its own unit); (0, 0, 0) when no field is a stiffness."""
        vals, _ = self.law_values(self.full(theta))
        spreads = [(float(vals[f.law_parameter].min()), float(vals[f.law_parameter].max()))
                   for f in self.mechanism.fields if f.kind in ("stiffness", "coefficient")]
        if not spreads:
            return 0.0, 0.0, 0.0
        lo, hi = max(spreads, key=lambda s: s[1] / s[0])
        return lo, hi, float(np.log10(hi / lo))

    # -- the search's starts and moves ------------------------------------------------------
    def initial_guess(self, rng: np.random.Generator, candidates: int = 24) -> np.ndarray:
        """A start: the best of a few log-uniform draws in the middle of the bounds, scaled onto the data
        (:func:`~tenscell.fitting.problem.draw_start`; the stiffness-like kinds of :data:`KINDS` scale G*)."""
        return draw_start(self, rng, tuple(k for k, (_, scales) in KINDS.items() if scales), candidates)

    def perturb(self, theta, rng: np.random.Generator) -> np.ndarray:
        """A basin-hopping move: every free log-parameter jittered by about half a decade, within the bounds."""
        return jitter(self, theta, rng)

    # -- anywhere, and what the result reads -------------------------------------------------------
    def tendon_law(self, phi, assignment: int = 0):
        """The law of every tendon in assignment ``assignment`` at log-parameters ``phi``."""
        K = self.field_maps[0][1].shape[0]
        if not 0 <= int(assignment) < K:
            raise ValueError(f"assignment must lie in 0..{K - 1}, got {assignment!r}")
        vals, _ = self.law_values(phi)
        return self.law_class._trusted(**{n: v[int(assignment)] for n, v in vals.items()})

    def moduli_at(self, theta, f_hz, P_N) -> tuple[np.ndarray, np.ndarray]:
        f, P = np.broadcast_arrays(np.asarray(f_hz, dtype=float), np.asarray(P_N, dtype=float))
        out = self.evaluate(self.full(theta), 2 * np.pi * f.ravel(), P.ravel(), jac=False)
        if out is None:
            nan = np.full(f.shape, np.nan)
            return nan, nan.copy()
        return out.G.real.reshape(f.shape), out.G.imag.reshape(f.shape)

    def fitted(self, theta, result):
        pars = self.parameters(theta)
        vals = {p.name: p.value for p in pars[: self.prestress_start]}
        named = {p.name: p.value for p in pars}
        s = named.get("s")
        P = None if s is not None else next(v for n, v in named.items() if n == "P" or n.startswith("P["))
        measured = [float(x) for x in self.group_measured if np.isfinite(x)]
        fitted = [v for n, v in named.items() if n.startswith("P_data")]
        return FittedMechanism(mechanism=self.mechanism, cell=self.cell, values=vals, s=s, P=P,
                               prestress_pa=tuple(measured + fitted), source=" + ".join(self.sources))

    def report_quantities(self, result) -> dict:
        """The shape of the fit (:func:`~tenscell.fitting.curves.shape_quantities`), the tendon-stiffness spread
        (min, max in the field's unit, decades) and the largest sd of G', G'' between assignments (decades)."""
        from ..curves import shape_quantities

        theta = result.theta
        return {**shape_quantities(result), "stiffness_spread": np.array(self.stiffness_spread(theta)),
                "assignment_spread": np.asarray(self.assignment_spread(theta), dtype=float)}

    def summary(self, result) -> dict:
        return {"mechanism": self.mechanism.name, "assignments_K": self.mechanism.K,
                "stiffness_spread_decades": self.stiffness_spread(result.theta)[2],
                "assignment_spread_decades": list(self.assignment_spread(result.theta)),
                "held_fields": {f.law_parameter: f.value for f in self.mechanism.fields if f.layout == "fixed"}}

    def describe(self) -> str:
        return f"mechanism {self.mechanism.name}: {self.mechanism.description}, on the {self.cell.describe()}"

    @property
    def report_sections(self) -> tuple:
        return ("held", "assignments")


# ---------------------------------------------------------------------------------------
# building a problem
# ---------------------------------------------------------------------------------------
def _layout(mech: Mechanism, cell: Cell, law_cls):
    """Field parameters (names, units, kinds, descriptions) and the maps of :attr:`MechanismProblem.field_maps`."""
    groups, fams = family_groups(cell)
    law_names = tuple(p.name for p in law_cls.parameters)
    given = {f.law_parameter for f in mech.fields}
    if given != set(law_names):
        raise ValueError(f"mechanism {mech.name!r}: law {mech.law} has parameters {', '.join(law_names)}; the fields "
                         f"lay out {', '.join(sorted(given)) or 'none'}")
    rows: list[tuple[str, str, str, str]] = []
    per_field: list[tuple[Field, int]] = []
    for f in mech.fields:
        start = len(rows)
        rows += _field_params(f, fams)
        per_field.append((f, start))
    return rows, per_field, groups


def _maps(per_field, groups, n_params: int, K: int, seed: int):
    m = groups.size
    field_maps, shape_maps = [], []
    for i, (f, start) in enumerate(per_field):
        D = np.zeros((K, m, n_params))
        const = np.zeros((K, m))
        if f.layout == "fixed":
            const[:] = math.log(f.value)
        elif f.layout == "family":
            D[:, np.arange(m), start + groups] = 1.0
        else:
            D[:, :, start] = 1.0
        if f.distribution is not None:
            n_scale = int(groups.max()) + 1 if f.layout == "family" else 1
            u = assignments(groups, K, seed + 7919 * i)
            shape_maps.append((f.law_parameter, start + n_scale, f.distribution, u))
        field_maps.append((f.law_parameter, D, const))
    return tuple(field_maps), tuple(shape_maps)


def make_mechanism_problem(data, model, cell: Cell | None = None, *, bounds: dict | None = None,
                           fixed: dict | None = None) -> MechanismProblem:
    """Set up the fit of a mechanism's moduli to one or several data sets.

    Parameters
    ----------
    data : RheologyData, CreepData or RelaxationData, or a sequence of them
        As for :func:`tenscell.fitting.fit`: moduli, creep and relaxation (:mod:`tenscell.fitting.time_series`).
    model : Mechanism
        The spec (a built-in one: :data:`~tenscell.fitting.models.catalog.MECHANISMS`).
    cell : Cell, optional
        The reference cell (default the paper cell).
    bounds : dict, optional
        ``{parameter name or kind: (lo, hi)}`` in SI units; a kind
        (``"stiffness"``, ``"damping"``, ``"time"``, ``"exponent"``,
        ``"decades"``, ``"viscosity"``, ``"s"``, ``"P"``, ``"P_data"``)
        applies to every parameter of that kind.
    fixed : dict, optional
        ``{parameter name: value}`` (SI units) held fixed.

    Raises
    ------
    ValueError
        Unknown mechanism or names, bad bounds or fixed values, too few points.
    """
    from ...model.shapes import paper_cell

    if not isinstance(model, Mechanism):  # a name is looked up in the registry (tenscell.fitting.get_model)
        raise ValueError(f"model must be a Mechanism (look a built-in one up with tenscell.fitting.get_model), "
                         f"got {model!r}")
    mech = model
    datasets = as_datasets(data)
    cell = paper_cell() if cell is None else cell
    rows, per_field, groups = _layout(mech, cell, mech.law_class)
    if mech.viscosity:
        rows.append(("eta_cytoplasm", "Pa·s", "viscosity", "cytoplasm viscosity in parallel with the structure"))
    p_names, p_units, p_desc, p_kinds, pgroups, point_group = prestress_layout(datasets)
    n_field = len(rows) - int(mech.viscosity)
    names = tuple([r[0] for r in rows] + p_names)
    units = tuple([r[1] for r in rows] + p_units)
    kinds = tuple([r[2] for r in rows] + p_kinds)
    descs = tuple([r[3] for r in rows] + p_desc)
    layout = data_layout(datasets, point_group)
    if layout["y_obs"].size < len(names):
        raise DataError(f"{len(datasets)} data set(s) give {layout['y_obs'].size} residuals, fewer than the "
                        f"{len(names)} parameters of mechanism {mech.name!r}")
    L_ref = float(cell.strut_length)
    defaults, S, w_m, P_med = default_bounds(datasets, L_ref)
    G_loss = modulus_scales(datasets)[2]
    lower, upper = bounds_by_name(names, kinds, bounds, defaults, S, w_m, G_loss)
    free, fixed_log = fixed_by_name(names, lower, upper, fixed)
    field_maps, shape_maps = _maps(per_field, groups, len(names), mech.K, mech.seed)
    group_map = np.zeros((len(pgroups), len(p_names)))
    for g, (_, _, _, links) in enumerate(pgroups):
        for j, v in links.items():
            group_map[g, j] = v
    params = Parameters(names=names, units=units, descriptions=descs, kinds=kinds, lower=lower, upper=upper,
                        free=free, fixed_log=fixed_log)
    return MechanismProblem(
        mechanism=mech, cell=cell, params=params, n_field=n_field, field_maps=field_maps, shape_maps=shape_maps,
        eta_index=n_field if mech.viscosity else None, L_ref=L_ref,
        lengths=np.asarray(cell.lengths, dtype=float), T0=np.asarray(cell.T0, dtype=float),
        sources=tuple(d.source for d in datasets), group_log_offset=np.array([g[2] for g in pgroups]),
        group_map=group_map, group_measured=np.array([g[1] for g in pgroups]), prestress_start=len(rows), **layout)


def bare_problem(mech: Mechanism, cell: Cell) -> MechanismProblem:
    """A problem without data: the mechanism's own parameters only, for :meth:`MechanismProblem.evaluate`."""
    rows, per_field, groups = _layout(mech, cell, mech.law_class)
    if mech.viscosity:
        rows.append(("eta_cytoplasm", "Pa·s", "viscosity", "cytoplasm viscosity"))
    n = len(rows)
    field_maps, shape_maps = _maps(per_field, groups, n, mech.K, mech.seed)
    z = np.zeros(0)
    params = Parameters.from_rows(rows, np.full(n, -np.inf), np.full(n, np.inf), np.ones(n, bool), np.zeros(n))
    return MechanismProblem(
        mechanism=mech, cell=cell, params=params, n_field=n - int(mech.viscosity), field_maps=field_maps, shape_maps=shape_maps,
        eta_index=n - 1 if mech.viscosity else None, L_ref=float(cell.strut_length),
        lengths=np.asarray(cell.lengths, float), T0=np.asarray(cell.T0, float), sources=(), omega=z,
        dataset_index=z.astype(int), group_index=z.astype(int), group_log_offset=z, group_map=np.zeros((0, 0)),
        group_measured=z, y_obs=z, weights=z, prestress_start=n)


# ---------------------------------------------------------------------------------------
# the fitted mechanism
# ---------------------------------------------------------------------------------------
#: the ``format`` tag of a fitted mechanism in fit.json's ``"model"`` entry
MECHANISM_FORMAT = "tenscell-fitted-mechanism"


@dataclass(frozen=True, eq=False, repr=False)
class FittedMechanism(FittedModel):
    """A fitted mechanism: its law values per tendon, prestress mapping and moduli anywhere.

    Attributes
    ----------
    mechanism : Mechanism
    cell : Cell
        The reference cell the parameters refer to.
    values : dict
        The mechanism's own parameters (fields and viscosity), SI units.
    P, s, prestress_pa, source
        See :class:`FittedModel`.
    """

    mechanism: Mechanism
    cell: Cell
    values: dict
    s: float | None = None
    P: float | None = None
    prestress_pa: tuple = ()
    source: str = ""
    FORMAT = MECHANISM_FORMAT

    def __post_init__(self):
        self._check_prestress()
        object.__setattr__(self, "values", {k: float(v) for k, v in self.values.items()})

    def __repr__(self) -> str:
        vals = ", ".join(f"{k} = {v:.4g}" for k, v in self.values.items())
        pre = f"s = {self.s:.4g} m²" if self.s is not None else f"P = {self.P:.4g} N"
        return format_repr(f"FittedMechanism {self.mechanism.name}", vals, pre)

    @property
    def spec(self):
        """The :class:`~tenscell.fitting.models.mechanism.Mechanism`."""
        return self.mechanism

    def describe(self) -> str:
        return f"the fitted mechanism {self.mechanism.name} ({self.mechanism.description})"

    @property
    def _problem(self):
        # built on each call (a few small arrays), not cached: a fitted model crosses process boundaries and holds
        # nothing that could change while it is pickled
        return bare_problem(self.mechanism, self.cell)

    @property
    def _phi(self) -> np.ndarray:
        return np.log([self.values[n] for n in self._problem.names])

    def moduli(self, f_hz, prestress_pa: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        f = frequencies_of(f_hz)
        pb = self._problem
        P = np.full(f.size, self.prestress(prestress_pa))
        out = pb.evaluate(self._phi, 2 * np.pi * f, P, jac=False)
        if out is None:
            raise ValueError(f"the fitted {self.mechanism.name} cell is not stable at this prestress")
        return out.G.real, out.G.imag

    @property
    def viscosity(self) -> float:
        """The cytoplasm viscosity η (Pa·s), 0 without one."""
        return float(self.values.get("eta_cytoplasm", 0.0))

    def parameter_values(self) -> dict:
        return self._named_values()

    def with_values(self, values: dict, **prestress) -> FittedMechanism:
        return self._replaced_values(values, prestress)  # type: ignore[return-value]

    @property
    def assignments(self) -> int:
        return self.mechanism.K

    def evaluation(self):
        return self._problem, self._phi

    def ensemble_problem(self, K: int, seed: int | None = None):
        """``(problem, phi, seed)``: the mechanism's K assignments (seed: the mechanism's own when None) as a problem
        without data (:func:`bare_problem`), at the fitted log-parameters ``phi``."""
        if not self.mechanism.heterogeneous:
            return super().ensemble_problem(K, seed)
        seed = self.mechanism.seed if seed is None else int(seed)
        pb = bare_problem(dataclasses.replace(self.mechanism, assignments=int(K), seed=seed), self.cell)
        return pb, np.log([self.values[n] for n in pb.names]), seed

    def tendon_law(self, assignment: int = 0):
        """The law of every tendon in assignment ``assignment`` (0 ≤ k < K) of a distributed property."""
        return self._problem.tendon_law(self._phi, assignment)

    def voigt_tendons(self, P_N: float, assignment: int = 0) -> tuple[np.ndarray, np.ndarray]:
        if self.mechanism.law == "Voigt":  # the fitted values themselves
            law = self.tendon_law(assignment)
            m = self.cell.m
            return np.broadcast_to(law.EA, (m,)).astype(float), np.broadcast_to(law.c, (m,)).astype(float)
        lin = self.linear(P_N=P_N, assignment=assignment)  # the tangents at rest of the law's realization
        return np.asarray(lin.EA, dtype=float), np.asarray(lin.c, dtype=float)

    def linear(self, prestress_pa: float | None = None, *, P_N: float | None = None, assignment: int = 0,
               band_hz=None) -> LinearModel:
        """The linear model of assignment ``assignment`` (laws with internal dynamics are realized over
        ``band_hz``, see :func:`tenscell.linear.linearize.linearize_law`), with the cytoplasm viscosity."""
        from ...linear.linearize import linearize_law

        return linearize_law(self.cell, self.tendon_law(assignment), self._resolve_P(prestress_pa, P_N),
                             viscosity=self.viscosity, band_hz=band_hz)

    def to_dict(self) -> dict:
        return {"format": MECHANISM_FORMAT, "mechanism": self.mechanism.to_dict(), **cell_to_dict(self.cell),
                "values": dict(self.values), **self._prestress_fields()}

    @classmethod
    def from_dict(cls, obj: dict) -> FittedMechanism:
        mech = field_of(obj, "mechanism", dict)
        if "class" not in mech:  # written by tenscell 0.2 (dataclasses.asdict of the spec, no class name)
            mech = {"class": "Mechanism", **mech}
        cell, _ = cell_from_dict(obj)
        values = positive_values(obj)
        spec = model_from_dict(mech)
        if not isinstance(spec, Mechanism):
            raise ValueError(f"model.mechanism: a {type(spec).__name__}, not a mechanism")
        fitted = cls(mechanism=spec, cell=cell, values=values, **prestress_from(obj))
        fitted.check()
        return fitted

    def check(self) -> None:
        """FitFileError naming the value when the parameters are not the mechanism's, or a value lies outside what
        its law accepts (e.g. a springpot exponent outside (0, 1])."""
        names = self._problem.names
        for n in names:
            if n not in self.values:
                raise FitFileError(f"model.values.{n}: missing (mechanism {self.mechanism.name} has "
                                   f"{', '.join(names)})")
        extra = sorted(set(self.values) - set(names))
        if extra:
            raise FitFileError(f"model.values.{extra[0]}: not a parameter of mechanism {self.mechanism.name} "
                               f"({', '.join(names)})")
        vals, _ = self._problem.law_values(self._phi)
        try:  # the law's own checks (the hot paths build it unchecked)
            self.mechanism.law_class(**{n: v.ravel() for n, v in vals.items()})
        except ValueError as err:
            raise FitFileError(f"model.values: {err}") from None

"""Structure-free formulas: the baselines a tensegrity has to beat.

A :class:`Formula` is a sum of terms of a complex modulus (Pa) at angular frequency ω (rad/s) and prestress P (Pa,
the data's own units), with no structure behind it:

=================  ===============================================  ==========================================
term               G*(ω, P)                                         parameters
=================  ===============================================  ==========================================
``E0``             E0                                               E0 (Pa)
``aP``             a·P                                              a (Pa/Pa): a modulus proportional to P
``structural``     G0·Γ(1−α)·(iω/Φ0)^α, Φ0 = 1 rad/s                G0 (Pa), alpha
``structural_P``   (G0 + g·P)·Γ(1−α)·(iω/Φ0)^α                      G0 (Pa), g (Pa/Pa), alpha
``springpot``      A·(iω)^α                                         A (Pa at 1 rad/s), alpha
``springpot_2``    A_2·(iω)^α_2: a second springpot                 A_2 (Pa at 1 rad/s), alpha_2
``springpot_P``    B·P·(iω)^α_T                                     B (Pa/Pa at 1 rad/s), alpha_T
``maxwell``        E_M·iωτ/(1 + iωτ)                                E_M (Pa), tau (s)
``mpl``            E_1·(iωτ_1)^α_1/(1 + (iωτ_1)^α_1)                E_1 (Pa), tau_1 (s), alpha_1
``newtonian``      iωη                                              eta (Pa·s)
=================  ===============================================  ==========================================

``mpl`` is a modified power law: a spring in series with a springpot (the fractional Maxwell element), whose
relaxation ``E_1·E_α(−(t/τ_1)^α)`` (Mittag-Leffler) starts at a finite modulus E_1 and decays as a power law
``t^−α`` after τ_1 (as ``(1 + t/τ_1)^−α`` does); beside ``E0`` (the formula ``modified-power-law+constant``) it
relaxes to a constant: the 4-parameter law creep and relaxation data are judged against.

**Networks.** A formula sums its terms (a parallel network), unless ``series`` names two groups of its terms whose
sums are put in series, ``G_A·G_B/(G_A + G_B)``, the other terms in parallel to them: :func:`series_formula` puts a
mechanism's lumped elastic terms (``aP``, ``E0``) in series with its law's other terms (the cytoplasm's Newtonian
term stays in parallel), so that P, entering an elastic term, moves G′ and G″ alike.

``structural`` is the structural-damping law of Fabry et al. (Phys Rev Lett 87:148102, 2001):
``G0 (ω/Φ0)^α (1 + iη) Γ(1−α) cos(πα/2)`` with ``η = tan(πα/2)`` is exactly ``G0 Γ(1−α) (iω/Φ0)^α``.

:data:`FORMULAS` holds the standard baselines: the structural-damping law with and without a Newtonian term, and
the same with a modulus that grows linearly with the prestress (for prestress sweeps). :func:`lumped_formula` gives
each mechanism's own structure-free formula: its tendon law's terms lumped into one element, with the same prestress
coupling — the terms the law writes P into (a tension-scaled springpot: ``springpot_P``), or else a modulus
proportional to P (``aP``: what the geometric prestress stiffness P·Kp would give without a structure).

The prestress in a formula is the data's prestress in Pa, never rescaled: a data set that states it is fitted at
it; one that does not, in a joint fit with one that does, gets its own fitted ``P_data[k]`` (Pa); without any stated
prestress every point is at P = 1 Pa (the P terms then act as P-independent terms).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.special

from ...io.data import DataError
from ..parameters import Parameters, as_datasets, bounds_by_name, fixed_by_name, kind_bounds
from ..problem import PENALTY, Problem, draw_start, jitter, log_residual_blocks
from ..time_series import (TimeLayout, data_layout, modulus_scales, relative_values, time_residual_values,
                           time_values)
from ..._results import format_repr
from .base import Capabilities, FitFileError, FitModel, FittedModel, field_of, frequencies_of, model_from_dict, positive_values, prestress_from

__all__ = ["Formula", "FormulaProblem", "FittedFormula", "FORMULA_FORMAT", "FORMULAS", "TERMS", "lumped_formula",
           "series_formula", "structural_damping_moduli", "PHI0"]

#: the fixed frequency scale Φ0 of the structural-damping law (rad/s)
PHI0 = 1.0
#: per term: its parameters as (name, unit, kind); kinds set bounds and starts as for the mechanisms
TERMS: dict[str, tuple[tuple[str, str, str], ...]] = {
    "E0": (("E0", "Pa", "stiffness"),),
    "aP": (("a", "Pa/Pa", "ratio"),),
    "structural": (("G0", "Pa", "stiffness"), ("alpha", "", "exponent")),
    "structural_P": (("G0", "Pa", "stiffness"), ("g", "Pa/Pa", "ratio"), ("alpha", "", "exponent")),
    "springpot": (("A", "Pa (at 1 rad/s)", "coefficient"), ("alpha", "", "exponent")),
    "springpot_2": (("A_2", "Pa (at 1 rad/s)", "coefficient"), ("alpha_2", "", "exponent")),
    "springpot_P": (("B", "Pa/Pa (at 1 rad/s)", "ratio"), ("alpha_T", "", "exponent")),
    "maxwell": (("E_M", "Pa", "stiffness"), ("tau", "s", "time")),
    "mpl": (("E_1", "Pa", "stiffness"), ("tau_1", "s", "time"), ("alpha_1", "", "exponent")),
    "newtonian": (("eta", "Pa·s", "viscosity"),),
}
#: terms in which the prestress appears
_PRESTRESS_TERMS = ("aP", "structural_P", "springpot_P")


def structural_damping_moduli(omega, G0: float, x: float, mu: float, phi0: float = PHI0) -> np.ndarray:
    """Complex modulus ``G*(ω)`` (Pa) of the structural-damping law at angular frequencies ``omega`` (rad/s).

    ``G0 (ω/Φ0)^(x−1) (1 + iη) Γ(2−x) cos(π(x−1)/2) + iωμ`` with ``η = tan(π(x−1)/2)``: G0 the modulus scale (Pa)
    at ω = Φ0, 1 < x < 2 (G′ ∝ ω^(x−1)), μ the Newtonian viscosity (Pa·s).
    """
    omega = np.asarray(omega, dtype=float)
    a = x - 1.0
    eta = math.tan(math.pi * a / 2)
    pl = G0 * (omega / phi0) ** a * (1 + 1j * eta) * math.gamma(2 - x) * math.cos(math.pi * a / 2)
    return pl + 1j * omega * mu


def _term(term: str, p: dict, z: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, dict]:
    """A term's G* at complex Laplace variables ``z`` (``iω`` for the moduli; principal branch of every power) and
    its derivatives by the ln of each of its parameters (a dict name -> array)."""
    if term == "E0":
        G = np.full(z.shape, p["E0"], dtype=complex)
        return G, {"E0": G}
    if term == "aP":
        G = (p["a"] * P).astype(complex)
        return G, {"a": G}
    if term in ("structural", "structural_P"):
        a = p["alpha"]
        base = math.gamma(1 - a) * (z / PHI0) ** a
        mod = p["G0"] + (p["g"] * P if term == "structural_P" else 0.0)
        G = mod * base
        d = {"G0": p["G0"] * base, "alpha": G * a * (np.log(z / PHI0) - scipy.special.digamma(1 - a))}
        if term == "structural_P":
            d["g"] = p["g"] * P * base
        return G, d
    if term in ("springpot", "springpot_2"):
        A, a = ("A", "alpha") if term == "springpot" else ("A_2", "alpha_2")
        G = p[A] * z ** p[a]
        return G, {A: G, a: G * p[a] * np.log(z)}
    if term == "springpot_P":
        G = p["B"] * P * z ** p["alpha_T"]
        return G, {"B": G, "alpha_T": G * p["alpha_T"] * np.log(z)}
    if term == "maxwell":
        x = z * p["tau"]
        G = p["E_M"] * x / (1 + x)
        return G, {"E_M": G, "tau": p["E_M"] * x / (1 + x) ** 2}
    if term == "mpl":
        a = p["alpha_1"]
        log_zt = np.log(z * p["tau_1"])
        x = np.exp(a * log_zt)
        G = p["E_1"] * x / (1 + x)
        dx = p["E_1"] * a * x / (1 + x) ** 2  # dG/d ln x times d ln x / d ln τ_1 (= α)
        return G, {"E_1": G, "tau_1": dx, "alpha_1": dx * log_zt}
    G = z * p["eta"]  # newtonian
    return G, {"eta": G}


def _sum_terms(terms, values: dict, z: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, dict]:
    """The sum of ``terms``' G* at Laplace variables ``z`` (a parallel network) and its derivatives by the ln of
    each parameter."""
    G = np.zeros(z.shape, dtype=complex)
    dG: dict[str, np.ndarray] = {}
    for t in terms:
        g, d = _term(t, values, z, P)
        G = G + g
        for k, v in d.items():
            dG[k] = dG.get(k, 0.0) + v
    return G, dG


@dataclass(frozen=True)
class Formula(FitModel):
    """A structure-free formula: a sum of :data:`TERMS` (module docstring).

    Attributes
    ----------
    name, description : str
    terms : tuple of str
        Keys of :data:`TERMS`; a parameter name shared by two terms (``alpha``, ``G0``) is one parameter.
    """

    name: str
    terms: tuple
    description: str = ""
    series: tuple = ()
    family = "formula"

    def __post_init__(self):
        object.__setattr__(self, "terms", tuple(self.terms))
        bad = [t for t in self.terms if t not in TERMS]
        if bad or not self.terms:
            raise ValueError(f"formula {self.name!r}: terms must be some of {', '.join(TERMS)}, got {self.terms!r}")
        groups = tuple(tuple(g) for g in self.series)
        if groups and (len(groups) != 2 or not all(groups) or set(groups[0]) & set(groups[1])
                       or not set(groups[0]) | set(groups[1]) <= set(self.terms)):
            raise ValueError(f"formula {self.name!r}: series must be two disjoint, non-empty groups of its terms, "
                             f"got {self.series!r}")
        object.__setattr__(self, "series", groups)

    @property
    def group(self) -> str:
        return "structure-free formulas (baselines)"

    @property
    def capabilities(self) -> Capabilities:
        """Moduli, creep and relaxation (its modulus continued to the Laplace variable); no cell."""
        return Capabilities(data_kinds=frozenset({"moduli", "creep", "relaxation"}), structural=False)

    @property
    def parameter_rows(self) -> tuple[tuple[str, str, str], ...]:
        """(name, unit, kind) of every parameter, in order of first appearance."""
        seen: dict[str, tuple[str, str, str]] = {}
        for t in self.terms:
            for row in TERMS[t]:
                seen.setdefault(row[0], row)
        return tuple(seen.values())

    @property
    def uses_prestress(self) -> bool:
        """Whether a term depends on the prestress."""
        return any(t in _PRESTRESS_TERMS for t in self.terms)

    def complex_modulus(self, values: dict, omega, P, *, derivatives: bool = False):
        """G* (Pa) at angular frequencies ``omega`` (rad/s) and prestresses ``P`` (Pa), broadcast; with
        ``derivatives`` also ``{name: dG*/d ln value}``."""
        return self.laplace_modulus(values, 1j * np.asarray(omega, dtype=float), P, derivatives=derivatives)

    def laplace_modulus(self, values: dict, s, P, *, derivatives: bool = False):
        """G*(s) (Pa) continued to complex Laplace variables ``s`` (1/s; ``iω`` gives :meth:`complex_modulus`) at
        prestresses ``P`` (Pa), broadcast; with ``derivatives`` also ``{name: dG*/d ln value}``."""
        z, P = np.broadcast_arrays(np.asarray(s, dtype=complex), np.asarray(P, dtype=float))
        in_series = {t for g in self.series for t in g}
        G, dG = _sum_terms([t for t in self.terms if t not in in_series], values, z, P)
        if self.series:
            Ga, dA = _sum_terms(self.series[0], values, z, P)
            Gb, dB = _sum_terms(self.series[1], values, z, P)
            # G_A·G_B/(G_A + G_B): d = (G_B² dG_A + G_A² dG_B)/(G_A + G_B)²
            G = G + Ga * Gb / (Ga + Gb)
            for k in {*dA, *dB}:
                dG[k] = dG.get(k, 0.0) + (Gb**2 * dA.get(k, 0.0) + Ga**2 * dB.get(k, 0.0)) / (Ga + Gb) ** 2
        return (G, dG) if derivatives else G

    def problem(self, data, cell=None, *, bounds=None, fixed=None) -> FormulaProblem:
        if cell is not None:
            raise ValueError(f"cell: formula {self.name!r} has no cell")
        return make_formula_problem(data, self, bounds=bounds, fixed=fixed)


def _builtin() -> dict[str, Formula]:
    out = [
        Formula("structural-damping", ("structural",),
                "the structural-damping (power-law) law of Fabry et al. 2001: G0·Γ(1−α)·(iω)^α"),
        Formula("structural-damping+newtonian", ("structural", "newtonian"),
                "the structural-damping law with a Newtonian term: G0·Γ(1−α)·(iω)^α + iωη"),
        Formula("structural-damping-prestress", ("structural_P",),
                "the structural-damping law with a modulus linear in the prestress: (G0 + g·P)·Γ(1−α)·(iω)^α"),
        Formula("structural-damping-prestress+newtonian", ("structural_P", "newtonian"),
                "the structural-damping law with a modulus linear in the prestress and a Newtonian term"),
        Formula("modified-power-law+constant", ("E0", "mpl"),
                "a modified power law with a constant: E0 + E_1·(iωτ_1)^α_1/(1 + (iωτ_1)^α_1), relaxing from "
                "E0 + E_1 as a power law to E0"),
    ]
    return {f.name: f for f in out}


#: the standard baselines by name
FORMULAS: dict[str, Formula] = _builtin()

def lumped_formula(mechanism) -> Formula:
    """A mechanism's own structure-free formula: its law's terms as one lumped element (a distribution of a
    property lumped with it), its cytoplasm, and the same prestress coupling — the law's tension term where it has
    one, else a modulus proportional to P (what P·Kp gives without a structure); a springpot law with an exponent
    per family lumps into two springpots (``springpot_2``), as many exponents as the mechanism has. Module
    docstring. The law's terms are its class attribute ``lumped_terms`` (:class:`tenscell.laws.TendonLaw`)."""
    terms = tuple(mechanism.law_class.lumped_terms)  # the law's own (checked when the mechanism was built)
    if "springpot_P" not in terms:
        terms = ("aP", *terms)
    if "springpot" in terms and any(f.kind == "exponent" and f.layout == "family" for f in mechanism.fields):
        # an exponent per family: two springpots side by side, as many exponents as the mechanism has
        i = terms.index("springpot") + 1
        terms = (*terms[:i], "springpot_2", *terms[i:])
    if mechanism.viscosity and "newtonian" not in terms:
        terms = (*terms, "newtonian")
    return Formula(f"{mechanism.name} (lumped)", terms,
                   f"the structure-free formula of {mechanism.name}: " + " + ".join(terms))


#: the lumped terms a mechanism's series network puts on the elastic side (the prestress enters here)
_ELASTIC_TERMS = ("aP", "E0")


def series_formula(parallel: Formula) -> Formula | None:
    """The same lumped terms as a series network: ``parallel``'s elastic terms (``aP``, ``E0``) in series with its
    other terms (the law's dissipative ones; a Newtonian term stays in parallel, as the cytoplasm, unless it is the
    only one: a Voigt element's lumped terms become a Maxwell element). None when a side is empty. Module
    docstring."""
    elastic = tuple(t for t in parallel.terms if t in _ELASTIC_TERMS)
    rest = tuple(t for t in parallel.terms if t not in _ELASTIC_TERMS)
    other = tuple(t for t in rest if t != "newtonian") or rest
    if not elastic or not other:
        return None
    base = parallel.name[: -len(" (lumped)")] if parallel.name.endswith(" (lumped)") else parallel.name
    return Formula(f"{base} (lumped in series)", parallel.terms,
                   f"the structure-free formula of {base} as a series network: (" + " + ".join(elastic)
                   + ") in series with (" + " + ".join(other) + ")"
                   + "".join(f" + {t}" for t in rest if t not in other), series=(elastic, other))


# ---------------------------------------------------------------------------------------
# the problem
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class FormulaProblem(Problem):
    """A formula against one or several data sets (built by :func:`make_formula_problem`)."""

    formula: Formula
    params: Parameters
    n_formula: int  # the formula's own parameters (they come first; then P_data[k])
    sources: tuple
    omega: np.ndarray
    dataset_index: np.ndarray
    group_index: np.ndarray
    group_log_offset: np.ndarray
    group_map: np.ndarray
    group_measured: np.ndarray
    y_obs: np.ndarray
    weights: np.ndarray
    cell: None = None
    #: creep and relaxation points (:mod:`tenscell.fitting.time_series`)
    time: TimeLayout | None = None

    def __repr__(self) -> str:
        return (f"FormulaProblem({self.formula.name}: {self.n_free} free of {self.n_params} parameters, "
                f"{self.n_datasets} data set(s), {self.n_points} points)")

    @property
    def spec(self) -> Formula:
        return self.formula

    @property
    def prestress_slice(self) -> slice:
        return slice(self.n_formula, self.n_params)

    def model_prestress(self, theta, prestress_pa) -> np.ndarray:
        """A formula's prestress is the data's own (Pa), when some data set stated one."""
        if not np.any(np.isfinite(self.group_measured)):
            raise ValueError("no data set of this fit stated its prestress, so the formula has no prestress in Pa")
        return np.asarray(prestress_pa, dtype=float)

    def _values(self, phi) -> dict:
        return dict(zip(self.names[: self.n_formula], np.exp(phi[: self.n_formula])))

    def _at(self, phi, z, P, jac: bool, groups=None):
        """G* (Pa) at complex Laplace variables ``z`` (``iω`` for the moduli) and prestresses ``P`` (Pa), with
        ``jac`` its derivatives by every parameter (the prestress ones through each point's group ``groups``)."""
        G, dG = self.formula.laplace_modulus(self._values(phi), z, P, derivatives=True)
        if not jac:
            return G, None
        D = np.zeros((z.size, self.n_params), dtype=complex)
        for i, n in enumerate(self.names[: self.n_formula]):
            D[:, i] = dG[n]
        if self.n_params > self.n_formula:
            # P enters the prestress terms linearly, each through one coefficient (a, g, B): d G/d ln P is the sum of
            # their derivatives by the ln of that coefficient
            G_P = sum((dG[n] for n in ("a", "g", "B") if n in dG), np.zeros_like(G))
            D[:, self.prestress_slice] = G_P[:, None] * self.group_map[groups]
        return G, D

    def _evaluate_constrained(self, phi, jac: bool):
        Pg = np.exp(self.group_log_offset + self.group_map @ phi[self.prestress_slice])
        mod = self._at(phi, 1j * self.omega, Pg[self.group_index], jac, self.group_index)
        if self.time is None:
            return mod, None
        groups = self.time.node_group
        G, D = self._at(phi, self.time.nodes, Pg[groups], jac, groups)
        return mod, time_values(self.time, G, D)

    def _moduli_of(self, out):
        return out[0]

    def _residuals_from(self, out) -> np.ndarray:
        (G, _), tim = out
        if not (np.all(np.isfinite(G)) and np.all(G.real > 0) and np.all(G.imag > 0)):
            return np.full(self.y_obs.size, PENALTY)
        parts = [np.log10(G.real), np.log10(G.imag)]
        if tim is not None:
            assert self.time is not None  # time values come with a time layout
            lt = time_residual_values(self.time, tim[0])[0]
            if not np.all(np.isfinite(lt)):
                return np.full(self.y_obs.size, PENALTY)
            parts.append(lt)
        return self.weights * (np.concatenate(parts) - self.y_obs)

    def _jacobian_from(self, out) -> np.ndarray:
        (G, D), tim = out
        blocks = [log_residual_blocks(G, D[:, self.free])]
        if tim is not None:
            assert self.time is not None
            dl = time_residual_values(self.time, *tim)[1]
            assert dl is not None  # asked with the derivatives
            blocks.append(np.nan_to_num(dl[:, self.free]))
        return self.weights[:, None] * np.vstack(blocks)

    def moduli(self, theta) -> tuple[np.ndarray, np.ndarray]:
        G = self._evaluate_constrained(self.full(theta), jac=False)[0][0]
        return G.real, G.imag

    def moduli_at(self, theta, f_hz, P_N) -> tuple[np.ndarray, np.ndarray]:
        f, P = np.broadcast_arrays(np.asarray(f_hz, dtype=float), np.asarray(P_N, dtype=float))
        G = self._at(self.full(theta), 2j * np.pi * f, P, jac=False)[0]
        return G.real, G.imag

    def time_model(self, theta) -> np.ndarray:
        """J(t) (1/Pa), G(t) (Pa) or a shape's G(t)/G(t_ref) at every time point."""
        assert self.time is not None
        tim = self._evaluate_constrained(self.full(theta), jac=False)[1]
        return relative_values(self.time, tim[0])

    def initial_guess(self, rng: np.random.Generator) -> np.ndarray:
        return draw_start(self, rng, _SCALABLE)

    def perturb(self, theta, rng: np.random.Generator) -> np.ndarray:
        return jitter(self, theta, rng)

    def fitted(self, theta, result):
        vals = self.values(theta)
        named = dict(zip(self.names, vals))
        measured = [float(x) for x in self.group_measured if np.isfinite(x)]
        fitted = [v for n, v in named.items() if n.startswith("P_data")]
        pre = {"s": 1.0, "prestress_pa": tuple(measured + fitted)} if measured else {"P": 1.0}
        return FittedFormula(formula=self.formula, values=dict(zip(self.names[: self.n_formula],
                                                                   vals[: self.n_formula])),
                             source=" + ".join(self.sources), **pre)

    def report_quantities(self, result) -> dict:
        from ..curves import shape_quantities

        return shape_quantities(result)

    def describe(self) -> str:
        return f"formula {self.formula.name}: {self.formula.description} (no structure)"


#: parameter kinds whose common scaling scales G* (the centred starts shift them together)
_SCALABLE = ("stiffness", "coefficient", "viscosity", "ratio")


def _prestress(datasets, uses_prestress: bool):
    """(names, units, descriptions, kinds, groups, point_group): the data's prestress in Pa; a fitted P_data[k]
    (Pa) for a data set that states none beside one that does (only when a term uses P); else 1 Pa."""
    known = [d.prestress is not None for d in datasets]
    names: list[str] = []
    units: list[str] = []
    descs: list[str] = []
    kinds: list[str] = []
    groups: list[tuple[float, float, dict]] = []
    point_group: list[np.ndarray] = []
    P_med = float(np.median(np.concatenate([d.prestress for d in datasets if d.prestress is not None]))) \
        if any(known) else 1.0
    for k, d in enumerate(datasets):
        if known[k]:
            uniq, inv = np.unique(d.prestress, return_inverse=True)
            base = len(groups)
            groups += [(float(p), math.log(p), {}) for p in uniq]
            point_group.append(base + np.asarray(inv).ravel())
            continue
        links = {}
        if any(known) and uses_prestress:
            links = {len(names): 1.0}
            names.append(f"P_data[{k}]")
            units.append("Pa")
            kinds.append("P_data")
            descs.append(f"prestress (Pa) at which data set {k} ({d.source}) was measured: not stated, so fitted")
        groups.append((math.nan, 0.0, links))
        point_group.append(np.full(d.n, len(groups) - 1))
    return names, units, descs, kinds, groups, point_group, P_med


def make_formula_problem(data, formula: Formula, *, bounds: dict | None = None,
                         fixed: dict | None = None) -> FormulaProblem:
    """Set up the fit of a formula to one or several data sets (moduli, creep, relaxation: its modulus continued to
    the Laplace variable, :mod:`tenscell.fitting.time_series`; ``bounds`` and ``fixed`` as for
    :func:`tenscell.fitting.models.mechanism.make_mechanism_problem`)."""
    datasets = as_datasets(data)
    rows = formula.parameter_rows
    p_names, p_units, p_desc, p_kinds, groups, point_group, P_med = _prestress(datasets, formula.uses_prestress)
    names = tuple([r[0] for r in rows] + p_names)
    units = tuple([r[1] for r in rows] + p_units)
    kinds = tuple([r[2] for r in rows] + p_kinds)
    descs = tuple([f"{r[0]} of {formula.name}" for r in rows] + p_desc)
    layout = data_layout(datasets, point_group)
    if layout["y_obs"].size < len(names):
        raise DataError(f"{len(datasets)} data set(s) give {layout['y_obs'].size} residuals, fewer than the "
                        f"{len(names)} parameters of formula {formula.name!r}")
    S, w_m, G_loss = modulus_scales(datasets)
    defaults = {"ratio": (1e-6 * S / P_med, 1e3 * S / P_med), "P_data": (1e-3 * P_med, 1e3 * P_med),
                "stiffness": (1e-6 * S, 1e3 * S)}
    for k in ("coefficient", "time", "exponent", "viscosity"):
        defaults[k] = kind_bounds(k, S, w_m, G_loss)
    lower, upper = bounds_by_name(names, kinds, bounds, defaults, S, w_m, G_loss)
    free, fixed_log = fixed_by_name(names, lower, upper, fixed)
    group_map = np.zeros((len(groups), len(p_names)))
    for g, (_, _, links) in enumerate(groups):
        for j, v in links.items():
            group_map[g, j] = v
    params = Parameters(names=names, units=units, descriptions=descs, kinds=kinds, lower=lower, upper=upper,
                        free=free, fixed_log=fixed_log)
    return FormulaProblem(
        formula=formula, params=params, n_formula=len(rows), sources=tuple(d.source for d in datasets),
        group_log_offset=np.array([g[1] for g in groups]), group_map=group_map,
        group_measured=np.array([g[0] for g in groups]), **layout)


# ---------------------------------------------------------------------------------------
# the fitted formula
# ---------------------------------------------------------------------------------------
#: the ``format`` tag of a fitted formula in fit.json's ``"model"`` entry
FORMULA_FORMAT = "tenscell-fitted-formula"


@dataclass(frozen=True, eq=False, repr=False)
class FittedFormula(FittedModel):
    """A fitted structure-free formula (a baseline): its parameters and moduli anywhere; no cell, no tendons.

    Attributes
    ----------
    formula : Formula
        The spec (:mod:`tenscell.fitting.models.formulas`).
    values : dict
        Its parameters (SI units).
    P, s, prestress_pa, source
        See :class:`FittedModel`.
    """

    formula: Formula
    values: dict
    s: float | None = None
    P: float | None = None
    prestress_pa: tuple = ()
    source: str = ""
    FORMAT = FORMULA_FORMAT

    #: a formula has no cell (what :attr:`FitResult.cell` and the consumers of a fitted model read)
    cell = None

    def __post_init__(self):
        self._check_prestress()
        object.__setattr__(self, "values", {k: float(v) for k, v in self.values.items()})

    @property
    def structural(self) -> bool:
        return False

    def parameter_values(self) -> dict:
        return self._named_values()

    def with_values(self, values: dict, **prestress) -> FittedFormula:
        return self._replaced_values(values, prestress)  # type: ignore[return-value]

    @property
    def spec(self):
        return self.formula

    def describe(self) -> str:
        return f"the fitted formula {self.formula.name} ({self.formula.description})"

    def __repr__(self) -> str:
        vals = ", ".join(f"{k} = {v:.4g}" for k, v in self.values.items())
        return format_repr(f"FittedFormula {self.formula.name}", vals)

    def moduli(self, f_hz, prestress_pa: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        f = frequencies_of(f_hz)
        G = self.formula.complex_modulus(self.values, 2 * np.pi * f, np.full(f.size, self.prestress(prestress_pa)))
        return G.real, G.imag

    def to_dict(self) -> dict:
        return {"format": FORMULA_FORMAT, "formula": self.formula.to_dict(), "values": dict(self.values),
                **self._prestress_fields()}

    @classmethod
    def from_dict(cls, obj: dict) -> FittedFormula:
        formula = model_from_dict(field_of(obj, "formula", dict))
        if not isinstance(formula, Formula):
            raise ValueError(f"model.formula: a {type(formula).__name__}, not a formula")
        values = positive_values(obj)
        rows = formula.parameter_rows
        for name, _, kind in rows:
            if name not in values:
                raise FitFileError(f"model.values.{name}: missing (formula {formula.name} has "
                                   f"{', '.join(r[0] for r in rows)})")
            if kind == "exponent" and not values[name] < 1:
                raise FitFileError(f"model.values.{name}: an exponent must lie in (0, 1), got {values[name]!r}")
        return cls(formula=formula, values=values, **prestress_from(obj))

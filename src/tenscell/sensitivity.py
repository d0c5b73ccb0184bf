"""Sensitivity of the moduli to every parameter (the paper's "10% in, at most 8% out").

Three tools:

* :func:`analytic_elasticities` — exact local elasticities ``∂ln G/∂ln p`` of
  the complex modulus for every tendon stiffness ``EA_j``, every damping
  ``c_j`` and the prestress ``P``, from the derivatives of
  ``J = D0ᵀ Z⁻¹ (−H0)`` with ``Z = K0 + iωC0``: with ``x = Z⁻¹(−H0)`` and
  ``y = Z⁻ᵀ D0``,

  ``∂J/∂EA_j = −(yᵀa_j)(a_jᵀx)/l_j``, ``∂J/∂c_j = −iω (yᵀa_j)(a_jᵀx)``,
  ``∂J/∂P = −yᵀ Kp x``,

  and ``∂ln G/∂ln p = −p·(∂J/∂p)/J`` (``G = (0.5/L)/J``). The storage and loss
  elasticities follow as ``∂ln G'/∂ln p = Re(G·e)/G'`` and
  ``∂ln G''/∂ln p = Im(G·e)/G''``.
* :func:`elasticities` — the same plus the geometry of the paper cell (L, α,
  δ) by central differences through :func:`tenscell.paper_cell` (the
  self-stress comes from an SVD, which complex steps do not pass through).
  The step is checked: each derivative is also taken with twice the step and
  the difference is reported as its error estimate. α is 0 in the default
  reference, so for α the *semi*-elasticity ``∂ln G/∂α`` (1/rad) is given.
* :func:`perturbation_table` and :func:`monte_carlo` — the finite ±10%
  changes themselves, one parameter at a time and all at once (seeded).

The whole study at one base point is :func:`tenscell.studies.sensitivity_study`.

Scaling laws give exact sum rules that the tests check: multiplying P, every
EA and every c by s multiplies G by s, so ``e_P + Σ e_EA + Σ e_c = 1``;
multiplying every c by s maps G(f) to G(s·f), so ``Σ e_c = ∂ln G/∂ln f``; and
``G_L(f) = G_1(L·f)/L²`` gives ``e_L = ∂ln G/∂ln f − 2``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ._checks import finite_scalar, positive_array, positive_scalar
from ._progress import progress_bar
from ._results import dataframe, format_repr
from ._threads import hot_path
from .linear.linearize import LinearModel, linearize
from .linear.assembly import modulus
from .linear.rigid import resolvent_full
from .response import compliance
from .model.shapes import paper_cell
from .model.structure import STRUT

__all__ = [
    "Elasticities",
    "analytic_elasticities",
    "elasticities",
    "PerturbationRow",
    "perturbation_table",
    "GroupSummary",
    "summarize",
    "MonteCarloResult",
    "monte_carlo",
    "monte_carlo_draws",
    "monte_carlo_factors",
    "monte_carlo_names",
    "SENSITIVITY_FREQUENCIES",
    "PAPER_BOUND",
]

#: default frequency grid of the sensitivity study (Hz): the paper's 10⁻² to 10³ Hz
SENSITIVITY_FREQUENCIES = np.logspace(-2, 3, 51)
#: the paper's bound: a 10% change of a parameter changes the moduli by at most 8%
PAPER_BOUND = 0.08


@dataclass(frozen=True, eq=False, repr=False)
class Elasticities:
    """Local elasticities of the complex modulus over frequency.

    Attributes
    ----------
    frequency_hz : ndarray, shape (nf,)
        Frequencies (Hz).
    names : tuple of str
        One per parameter: ``"EA[j]"``, ``"c[j]"``, ``"P"``, and for the paper
        cell ``"L"``, ``"alpha"``, ``"delta"``.
    groups : tuple of str
        A group per parameter for summaries, e.g. ``"EA actin"``, ``"c IF"``, ``"P"``.
    values : ndarray, shape (np,)
        The parameters' base values (N, N·s/m, N, m, rad).
    complex : ndarray of complex, shape (np, nf)
        ``∂ln G/∂ln p`` (dimensionless); for ``"alpha"`` ``∂ln G/∂α`` (1/rad).
    G : ndarray of complex, shape (nf,)
        The base modulus ``G' + iG''`` (Pa).
    methods : tuple of str
        How each row was computed ("analytic" or the finite-difference rule and step).
    errors : ndarray, shape (np,)
        Estimated absolute error of each row (max over f; 0 for analytic rows).
    """

    frequency_hz: np.ndarray
    names: tuple[str, ...]
    groups: tuple[str, ...]
    values: np.ndarray
    complex: np.ndarray
    G: np.ndarray
    methods: tuple[str, ...]
    errors: np.ndarray

    @property
    def storage(self) -> np.ndarray:
        """``∂ln G'/∂ln p``, shape (np, nf) (per rad for α)."""
        return (self.G * self.complex).real / self.G.real

    @property
    def loss(self) -> np.ndarray:
        """``∂ln G''/∂ln p``, shape (np, nf) (per rad for α)."""
        return (self.G * self.complex).imag / self.G.imag

    def index(self, name: str) -> int:
        """Row of a parameter by name."""
        try:
            return self.names.index(name)
        except ValueError:
            raise ValueError(f"unknown parameter {name!r}; known: {', '.join(self.names[:3])}, ..., {self.names[-1]}") from None

    def group_sum(self, group: str) -> np.ndarray:
        """Complex elasticity of scaling a whole group together (sum of its rows), shape (nf,)."""
        rows = [k for k, g in enumerate(self.groups) if g == group or g.startswith(group + " ")]
        if not rows:
            raise ValueError(f"unknown group {group!r}")
        return self.complex[rows].sum(axis=0)

    def __repr__(self) -> str:
        k = self.names.index("P") if "P" in self.names else None
        head = (f"∂ln G'/∂ln P = {self.storage[k].min():.4g}…{self.storage[k].max():.4g}, "
                f"∂ln G''/∂ln P = {self.loss[k].min():.4g}…{self.loss[k].max():.4g}") if k is not None else ""
        kinds = ", ".join(dict.fromkeys(n.split("[")[0] for n in self.names))
        return format_repr(
            f"Elasticities of G: {len(self.names)} parameters × {self.frequency_hz.size} frequencies "
            f"{self.frequency_hz[0]:g}…{self.frequency_hz[-1]:g} Hz",
            f"parameters: {kinds}",
            head,
            f"{self.methods.count('analytic')} analytic, {len(self.methods) - self.methods.count('analytic')} by finite differences",
        )

    def to_dataframe(self):
        """One row per (parameter, frequency): value and ∂ln G'/∂ln p, ∂ln G''/∂ln p (per rad for α)."""
        nf = self.frequency_hz.size
        return dataframe({
            "parameter": np.repeat(self.names, nf), "group": np.repeat(self.groups, nf),
            "value": np.repeat(self.values, nf), "method": np.repeat(self.methods, nf),
            "frequency_Hz": np.tile(self.frequency_hz, len(self.names)),
            "dlnGstorage_dlnp": self.storage.ravel(), "dlnGloss_dlnp": self.loss.ravel(),
        })

    def plot(self, ax=None, **kw):
        """Elasticities of G' and G'' against f (groups, largest members) on a pair of axes (or a new figure)."""
        from ._results import plotter

        elasticities_figure = plotter("elasticities_figure")

        return elasticities_figure(self, axes=ax, **kw)


def _family_tag(family: str) -> str:
    return {"actin": "actin", "intermediate_filament": "IF", STRUT: "strut"}.get(family, family)


@hot_path
def analytic_elasticities(lin: LinearModel, f_hz=SENSITIVITY_FREQUENCIES) -> Elasticities:
    """Exact elasticities of G for every parameter of the tendon law and for P.

    The linear model's tendon law (``lin.law``; Voigt with ``lin.EA``,
    ``lin.c`` for a hand-built model) gives the tangents ``k_j``, ``c_j`` and
    their derivatives (:meth:`tenscell.laws.TendonLaw.tangent`). With
    ``x = Z⁻¹(−H0)``, ``y = Z⁻ᵀD0``, ``Z = K0 + iωC0`` and
    ``K0 = P·Kp + Σ (k_j − P·T0_j/l_j) a_j a_jᵀ``:

    * ``∂J/∂θ_j = −(∂k_j/∂θ_j + iω ∂c_j/∂θ_j)(yᵀa_j)(a_jᵀx)`` for each law parameter θ of tendon j;
    * ``∂J/∂P = −yᵀKp x − Σ_j (T0_j ∂k_j/∂T_j − T0_j/l_j + iω T0_j ∂c_j/∂T_j)(yᵀa_j)(a_jᵀx)``,

    since ``T = P·T0`` moves every tangent (for Voigt tendons ``∂k/∂T = 1/l``
    and the sum vanishes). Works for dense models, including singular C0
    (direct solves).

    Parameters
    ----------
    lin : LinearModel
    f_hz : array_like, shape (nf,)
        Frequencies (Hz), > 0.

    Returns
    -------
    Elasticities
        Rows ``<θ>[j]`` for each law parameter θ (``EA``, ``c``, and e.g.
        ``b`` for stiffening filaments) and each tendon that has it, then ``P``.
    """
    f = np.atleast_1d(positive_array("frequency", f_hz, unit="Hz")).ravel()
    w = 2 * np.pi * f
    if lin.realization is not None:
        return _dynamic_elasticities(lin, f)
    dense = lambda M: M.toarray() if sp.issparse(M) else np.asarray(M)  # noqa: E731
    Kp, A = dense(lin.Kp), dense(lin.cell.A)
    # the model's one modal decomposition (tenscell.linear.modal); for a free-standing structure on the complement
    # N of its rigid-body motions, lifted back (x = N x̃): N does not depend on the law or P, so every formula
    # below holds on the lifted vectors
    X = resolvent_full(lin, w, -lin.H0)
    Y = resolvent_full(lin, w, lin.D0)  # Z = K0 + iωC0 is symmetric: Z⁻ᵀD0 = Z⁻¹D0
    J = X @ lin.D0
    prod = (Y @ A) * (X @ A)  # (nf, m): (yᵀa_j)(a_jᵀx)
    cell, l = lin.cell, lin.cell.lengths
    tan = lin.tendon_law.tangent(l, lin.P * cell.T0)
    dk_dP, dc_dP = tan.dP(cell.T0)
    dJ_P = -np.einsum("fi,ij,fj->f", Y, Kp, X) - prod @ (dk_dP - cell.T0 / l) - 1j * w * (prod @ dc_dP)
    fam = [_family_tag(x) for x in cell.structure.families]
    rows, names, groups, values = [], [], [], []
    for i, name in enumerate(tan.names):
        js = np.flatnonzero(tan.present[i])
        dJ = -prod[:, js] * (tan.dk[i, js] + 1j * w[:, None] * tan.dc[i, js])
        rows.append(-(tan.values[i, js] * dJ / J[:, None]).T)
        names += [f"{name}[{j}]" for j in js]
        groups += [f"{name} {fam[j]}" for j in js]
        values.append(tan.values[i, js])
    rows.append(-(lin.P * dJ_P / J)[None])
    names.append("P")
    groups.append("P")
    values.append([lin.P])
    n = len(names)
    return Elasticities(
        frequency_hz=f, names=tuple(names), groups=tuple(groups), values=np.concatenate(values),
        complex=np.vstack(rows), G=modulus(J, lin.L), methods=("analytic",) * n, errors=np.zeros(n),
    )


@hot_path
def _dynamic_elasticities(lin: LinearModel, f: np.ndarray) -> Elasticities:
    """Exact elasticities for a law with internal dynamics, from its dynamic tangent (not its realization).

    ``K(ω) = P·Σ T0∇²l + Σ k*_j(ω) a_j a_jᵀ`` with ``k*`` at tensions ``P·T0``:
    ``∂J/∂θ = −(∂k*_j/∂θ)(yᵀa_j)(a_jᵀx)`` and
    ``∂J/∂P = −yᵀ(Σ T0∇²l)x − Σ_j T0_j ∂k*_j/∂T (yᵀa_j)(a_jᵀx)``; a cytoplasm
    (``lin.viscosity``) adds ``iωη`` to G and depends on none of them.
    """
    from .linear.dynamic import _solves

    if lin.basis is not None:  # the per-frequency solves of linear.dynamic work on the full, singular K(ω)
        raise ValueError(f"exact elasticities of a law with internal dynamics ({type(lin.law).__name__}) are not "
                         f"available for a free-standing structure ({lin.cell.describe()}): hold it with fixed nodes "
                         "or supports, or use a law without internal variables")
    cell, law, w = lin.cell, lin.law, 2 * np.pi * f
    l, T = cell.lengths, lin.P * cell.T0
    dT, dk = law.complex_stiffness_derivatives(l, T, w)
    x, y = _solves(cell, lin.P, law.complex_stiffness(l, T, w), both=True)  # one LU per frequency
    assert y is not None
    Js = x @ np.asarray(cell.probe, dtype=float)
    prod = (cell.A.T @ y.T).T * (cell.A.T @ x.T).T  # (nf, m): (yᵀa_j)(a_jᵀx)
    H = cell.prestress_hessian
    Hx = (H @ x.T).T if sp.issparse(H) else x @ np.asarray(H).T
    dJ_P = -np.einsum("wi,wi->w", y, Hx) - (prod * dT) @ cell.T0
    G = modulus(Js, lin.L) + 1j * w * lin.viscosity
    dG = lambda dJ_: -modulus(Js, lin.L) * dJ_ / Js  # noqa: E731  ∂G/∂θ = −(0.5/L)·∂J/∂θ/J²
    vals = law.parameter_values(cell.m)
    rows = [(i, j) for i in range(len(law.names)) for j in np.flatnonzero(~np.isnan(vals[i]))]
    fam = [_family_tag(x) for x in cell.structure.families]
    out = [vals[i, j] * dG(-dk[i][:, j] * prod[:, j]) / G for i, j in rows] + [lin.P * dG(dJ_P) / G]
    names = [f"{law.names[i]}[{j}]" for i, j in rows] + ["P"]
    groups = [f"{law.names[i]} {fam[j]}" for i, j in rows] + ["P"]
    values = np.array([vals[i, j] for i, j in rows] + [lin.P])
    n = len(names)
    return Elasticities(frequency_hz=f, names=tuple(names), groups=tuple(groups), values=values,
                        complex=np.vstack(out), G=G, methods=("analytic",) * n, errors=np.zeros(n))


def _modulus(alpha, delta, L, P, EA, c, f, intermediate_filaments=True):
    cell = paper_cell(alpha=alpha, delta=delta, L=L, intermediate_filaments=intermediate_filaments)
    return modulus(compliance(linearize(cell, P=P, EA=EA, c=c), f), cell.strut_length)


def _geometry_derivative(G_of, x0, h, relative):
    """d ln G/d ln x (``relative``) or d ln G/dx by central differences, with a step check.

    Relative steps move ln x by ±h (points ``x0·e^{±h}``), so the central
    quotient is a derivative in ln x. The error estimate is the difference
    from the quotient with step 2h (the truncation error of the h quotient is
    a quarter of it). Where one side is not a valid reference, a one-sided
    second-order rule is used instead and the method says so.

    Returns (derivative (nf,), error estimate, method).
    """
    def at(k):
        return x0 * math.exp(k * h) if relative else x0 + k * h

    vals = {}
    for k in (-2, -1, 1, 2):
        try:
            vals[k] = np.log(G_of(at(k)))
        except ValueError:
            vals[k] = None
    base = np.log(G_of(at(0)))
    unit = " (in ln x)" if relative else " rad"
    if vals[1] is not None and vals[-1] is not None:
        d1 = (vals[1] - vals[-1]) / (2 * h)
        if vals[2] is not None and vals[-2] is not None:
            err = float(np.max(np.abs(d1 - (vals[2] - vals[-2]) / (4 * h))))
        else:
            err = math.nan
        return d1, err, f"central difference, step {h:g}{unit}"
    for side, word in ((1, "forward"), (-1, "backward")):
        if vals[side] is not None and vals[2 * side] is not None:
            d1 = side * (-3 * base + 4 * vals[side] - vals[2 * side]) / (2 * h)
            other = "backward" if side > 0 else "forward"
            return d1, math.nan, (f"one-sided {word} difference (2nd order), step {h:g}{unit}: "
                                  f"the {other} side is not a valid reference")
    raise ValueError("no valid reference on either side of the base point within two steps")


@hot_path
def elasticities(
    *,
    alpha: float = 0.0,
    delta: float | None = None,
    L: float = 1.0,
    P: float = 1000.0,
    EA=1.0,
    c=1.0,
    f_hz=SENSITIVITY_FREQUENCIES,
    intermediate_filaments: bool = True,
    step: float = 1e-4,
) -> Elasticities:
    """Elasticities of the paper cell's G for every parameter: EA_j, c_j, P, L, α, δ.

    EA_j, c_j and P analytically (:func:`analytic_elasticities`); L, α and δ by
    central differences through :func:`tenscell.paper_cell` with relative
    step ``step`` (L, δ) or absolute step ``step`` rad (α), one-sided where
    one side leaves the valid region. Without intermediate filaments δ is not
    free (it follows the curve δ*(α)), so the δ row is omitted and α moves
    along the curve.

    Parameters
    ----------
    alpha, delta : float
        Reference angles (rad); ``delta=None``: 50° with IFs, δ*(α) without.
    L : float
        Strut length (m).
    P : float
        Prestress (N).
    EA, c : float or array_like, shape (m,)
        Tendon stiffness (N) and damping (N·s/m).
    f_hz : array_like
        Frequencies (Hz).
    intermediate_filaments : bool
    step : float
        Finite-difference step (relative for L and δ, rad for α), in (0, 0.01].

    Returns
    -------
    Elasticities
    """
    step = positive_scalar("step", step)
    if step > 0.01:
        raise ValueError(f"step must be at most 0.01 (a relative step, or rad for alpha), got {step!r}")
    alpha = finite_scalar("alpha", alpha, "a finite angle in radians")
    f = np.atleast_1d(positive_array("frequency", f_hz, unit="Hz")).ravel()
    cell = paper_cell(alpha=alpha, delta=delta, L=L, intermediate_filaments=intermediate_filaments)
    delta0 = float(cell.parameters["delta"])
    lin = linearize(cell, P=P, EA=EA, c=c)
    base = analytic_elasticities(lin, f)
    EA_, c_ = lin.EA, lin.c
    rows, names, groups, values, methods, errors = [], [], [], [], [], []
    geo = [
        ("L", L, True, lambda x: _modulus(alpha, None if not intermediate_filaments else delta0, x, P, EA_, c_, f,
                                          intermediate_filaments)),
        ("alpha", alpha, False, lambda x: _modulus(x, None if not intermediate_filaments else delta0, L, P, EA_, c_, f,
                                                   intermediate_filaments)),
    ]
    if intermediate_filaments:
        geo.append(("delta", delta0, True, lambda x: _modulus(alpha, x, L, P, EA_, c_, f)))
    for name, x0, relative, G_of in geo:
        d, err, method = _geometry_derivative(G_of, x0, step, relative)
        rows.append(d)
        names.append(name)
        groups.append(name)
        values.append(x0)
        methods.append(method)
        errors.append(err)
    return Elasticities(
        frequency_hz=f, names=base.names + tuple(names), groups=base.groups + tuple(groups),
        values=np.concatenate([base.values, values]), complex=np.vstack([base.complex, np.array(rows)]),
        G=base.G, methods=base.methods + tuple(methods), errors=np.concatenate([base.errors, errors]),
    )


# ---- finite ±10% changes -------------------------------------------------------------------------
@dataclass(frozen=True)
class PerturbationRow:
    """Largest relative change of G' and G'' (over frequency) for one parameter changed by ±``change``.

    ``storage``/``loss`` are ``(at −change, at +change)``, as fractions;
    NaN where that perturbation leaves the valid region (``note`` says why).
    """

    name: str
    group: str
    storage: tuple[float, float]
    loss: tuple[float, float]
    note: str = ""

    @property
    def worst(self) -> float:
        """Largest change of either modulus over both signs (fraction; NaN if both signs invalid)."""
        v = [x for x in self.storage + self.loss if not math.isnan(x)]
        return max(v) if v else math.nan


def _base_parameters(alpha, delta, L, P, EA, c, intermediate_filaments):
    cell = paper_cell(alpha=alpha, delta=delta, L=L, intermediate_filaments=intermediate_filaments)
    m = cell.m
    return cell, positive_array("EA", EA, (m,), "N"), positive_array("c", c, (m,), "N·s/m")


@hot_path
def perturbation_table(
    *,
    change: float = 0.10,
    alpha_change: float | None = None,
    alpha: float = 0.0,
    delta: float | None = None,
    L: float = 1.0,
    P: float = 1000.0,
    EA=1.0,
    c=1.0,
    f_hz=SENSITIVITY_FREQUENCIES,
    intermediate_filaments: bool = True,
) -> list[PerturbationRow]:
    """Change one parameter at a time by ±``change`` and record the largest change of G', G''.

    Parameters: each EA_j and each c_j individually, all EA together, all c
    together, P, L, δ (relative changes ``1 ± change``) and α (shifted by
    ``± alpha_change`` rad, default ``change`` rad: α = 0 in the default
    reference, so a relative change would be no change).

    Returns
    -------
    list of PerturbationRow
    """
    change = positive_scalar("change", change)
    if change >= 1:
        raise ValueError(f"change must be a fraction below 1, got {change!r}")
    alpha_change = change if alpha_change is None else positive_scalar("alpha_change", alpha_change, "rad")
    f = np.atleast_1d(positive_array("frequency", f_hz, unit="Hz")).ravel()
    cell, EA, c = _base_parameters(alpha, delta, L, P, EA, c, intermediate_filaments)
    delta0 = float(cell.parameters["delta"])
    fam = [_family_tag(x) for x in cell.structure.families]

    def G_material(P_, EA_, c_):
        return modulus(compliance(linearize(cell, P=P_, EA=EA_, c=c_), f), cell.strut_length)

    G0 = G_material(P, EA, c)
    rows = []

    def record(name, group, evaluate):
        s, lo, notes = [math.nan, math.nan], [math.nan, math.nan], []
        for k, sgn in enumerate((-1.0, 1.0)):
            try:
                G1 = evaluate(sgn)
            except ValueError as err:
                notes.append(f"{'−' if sgn < 0 else '+'}: not a valid reference ({type(err).__name__})")
                continue
            s[k] = float(np.max(np.abs(G1.real / G0.real - 1)))
            lo[k] = float(np.max(np.abs(G1.imag / G0.imag - 1)))
        rows.append(PerturbationRow(name, group, tuple(s), tuple(lo), "; ".join(notes)))

    def scaled(v, j, sgn):
        out = v.copy()
        out[j] *= 1 + sgn * change
        return out

    m = cell.m
    for j in range(m):
        record(f"EA[{j}]", f"EA {fam[j]}", lambda sgn, j=j: G_material(P, scaled(EA, j, sgn), c))
    for j in range(m):
        record(f"c[{j}]", f"c {fam[j]}", lambda sgn, j=j: G_material(P, EA, scaled(c, j, sgn)))
    record("EA (all)", "EA (all)", lambda sgn: G_material(P, EA * (1 + sgn * change), c))
    record("c (all)", "c (all)", lambda sgn: G_material(P, EA, c * (1 + sgn * change)))
    record("P", "P", lambda sgn: G_material(P * (1 + sgn * change), EA, c))
    dgeo = None if not intermediate_filaments else delta0
    record("L", "L", lambda sgn: _modulus(alpha, dgeo, L * (1 + sgn * change), P, EA, c, f, intermediate_filaments))
    # the reference angles are the tightest parameters (the valid band is narrow), so each is also
    # changed by half as much: those rows give numbers where ±change leaves the band
    for frac, tag in ((1.0, ""), (0.5, " (half)")):
        da = frac * alpha_change
        record(f"alpha (±{da:g} rad)", "alpha" + tag,
               lambda sgn, da=da: _modulus(alpha + sgn * da, dgeo, L, P, EA, c, f, intermediate_filaments))
        if intermediate_filaments:
            dd = frac * change
            record(f"delta (±{100 * dd:g}%)", "delta" + tag,
                   lambda sgn, dd=dd: _modulus(alpha, delta0 * (1 + sgn * dd), L, P, EA, c, f))
    return rows


@dataclass(frozen=True)
class GroupSummary:
    """One line of the sensitivity table: a parameter group.

    Attributes
    ----------
    group : str
    n : int
        Number of parameters in the group.
    max_elasticity_storage, max_elasticity_loss : float
        Largest |∂ln G'/∂ln p|, |∂ln G''/∂ln p| over the group's members and
        the frequencies (per rad for α); NaN if not computed.
    max_change_storage, max_change_loss : float
        Largest |ΔG'/G'|, |ΔG''/G''| (fractions) for ±10% of one member.
    holds : bool or None
        Whether "10% in, at most 8% out" holds; None if part of the
        perturbations were invalid references.
    note : str
    """

    group: str
    n: int
    max_elasticity_storage: float
    max_elasticity_loss: float
    max_change_storage: float
    max_change_loss: float
    holds: bool | None
    note: str = ""


def summarize(el: Elasticities, table: list[PerturbationRow], bound: float = PAPER_BOUND) -> list[GroupSummary]:
    """Collapse elasticities and ±10% changes into one line per parameter group."""
    out = []
    order = []
    for r in table:
        if r.group not in order:
            order.append(r.group)
    for g in order:
        members = [r for r in table if r.group == g]
        if g in ("EA (all)", "c (all)"):
            key = g.split()[0]
            e = np.vstack([el.group_sum(key)])
            es, elo = (el.G * e).real / el.G.real, (el.G * e).imag / el.G.imag
        else:
            base = g.replace(" (half)", "")
            idx = [k for k, gg in enumerate(el.groups) if gg == base]
            es, elo = el.storage[idx], el.loss[idx]
        ms = max((x for r in members for x in r.storage if not math.isnan(x)), default=math.nan)
        ml = max((x for r in members for x in r.loss if not math.isnan(x)), default=math.nan)
        notes = "; ".join(sorted({r.note for r in members if r.note}))
        holds = None if notes else bool(max(ms, ml) <= bound)
        if notes and not math.isnan(max(ms, ml)) and max(ms, ml) > bound:
            holds = False
        out.append(GroupSummary(
            group=g, n=len(members), max_elasticity_storage=float(np.max(np.abs(es))) if np.size(es) else math.nan,
            max_elasticity_loss=float(np.max(np.abs(elo))) if np.size(elo) else math.nan,
            max_change_storage=ms, max_change_loss=ml, holds=holds, note=notes,
        ))
    return out


# ---- Monte Carlo -----------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class MonteCarloResult:
    """Simultaneous random perturbations of the parameters.

    Attributes
    ----------
    names : tuple of str
        The perturbed parameters.
    factors : ndarray, shape (n, np)
        The draws: multiplicative factors (α: additive shifts in rad).
    change_storage, change_loss : ndarray, shape (n,)
        Largest |ΔG'/G'| and |ΔG''/G''| over frequency per draw (fractions);
        NaN where the draw is not a valid reference.
    reasons : tuple of str
        For invalid draws, the error type; "" for valid draws.
    spread : float
    seed : int
    """

    names: tuple[str, ...]
    factors: np.ndarray
    change_storage: np.ndarray
    change_loss: np.ndarray
    reasons: tuple[str, ...]
    spread: float
    seed: int
    alpha_spread: float = 0.0
    label: str = ""
    frequency_hz: np.ndarray = field(default_factory=lambda: SENSITIVITY_FREQUENCIES)

    @property
    def valid(self) -> np.ndarray:
        """Mask of the draws that gave a valid reference."""
        return ~np.isnan(self.change_storage)

    @property
    def worst(self) -> np.ndarray:
        """max(|ΔG'/G'|, |ΔG''/G''|) per valid draw."""
        v = self.valid
        return np.maximum(self.change_storage[v], self.change_loss[v])

    def fraction_within(self, bound: float = PAPER_BOUND) -> float:
        """Fraction of the valid draws whose moduli all changed by at most ``bound``."""
        w = self.worst
        return float(np.mean(w <= bound)) if w.size else math.nan

    def percentiles(self, q=(50, 95, 100)) -> dict[str, np.ndarray]:
        """Percentiles of the storage and loss changes over the valid draws (fractions)."""
        v = self.valid
        return {"storage": np.percentile(self.change_storage[v], q), "loss": np.percentile(self.change_loss[v], q)}

    def __repr__(self) -> str:
        p = self.percentiles((95,))
        return format_repr(
            f"MonteCarloResult: {self.factors.shape[0]} draws of {self.label or 'the parameters'} (seed {self.seed}), "
            f"±{100 * self.spread:g}%",
            f"{int(self.valid.sum())} valid; 95th percentile |ΔG'/G'| {100 * p['storage'][0]:.2f}%, "
            f"|ΔG''/G''| {100 * p['loss'][0]:.2f}%",
            f"within {100 * PAPER_BOUND:g}%: {100 * self.fraction_within():.1f}% of valid draws",
        )

    def to_dataframe(self):
        """One row per draw: largest |ΔG'/G'|, |ΔG''/G''| over f (fractions), validity, and the factors."""
        cols = {"draw": np.arange(self.factors.shape[0]), "valid": self.valid,
                "max_change_storage": self.change_storage, "max_change_loss": self.change_loss,
                "reason": list(self.reasons)}
        for k, n in enumerate(self.names):
            cols[f"factor_{n}" if n != "alpha" else "shift_alpha_rad"] = self.factors[:, k]
        return dataframe(cols, {"spread": self.spread, "seed": self.seed, "label": self.label})

    def plot(self, ax=None, **kw):
        """Histograms of the largest change of G' and G'' per valid draw, on a pair of axes (or a new figure)."""
        from ._results import plotter

        monte_carlo_figure = plotter("monte_carlo_figure")

        return monte_carlo_figure([self], axes=ax, **kw)


@hot_path
def monte_carlo(
    n: int = 200,
    *,
    spread: float = 0.10,
    seed: int = 0,
    parameters: str = "all",
    alpha_spread: float | None = None,
    alpha: float = 0.0,
    delta: float | None = None,
    L: float = 1.0,
    P: float = 1000.0,
    EA=1.0,
    c=1.0,
    f_hz=SENSITIVITY_FREQUENCIES,
    progress: bool | None = None,
) -> MonteCarloResult:
    """Seeded Monte Carlo of simultaneous uniform ±``spread`` perturbations of the paper cell.

    Every EA_j, every c_j, P, and (for ``parameters="all"``) L and δ are
    multiplied by independent factors uniform in ``[1 − spread, 1 + spread]``;
    α is shifted by a uniform amount in ``±alpha_spread`` rad (default
    ``spread`` rad). ``parameters="material"`` perturbs EA_j, c_j and P only.

    Parameters
    ----------
    n : int
        Number of draws, ≥ 1.
    progress : bool or None
        A progress bar: None shows one when someone watches (a terminal or a
        notebook), True always, False never (see :mod:`tenscell._progress`).

    Returns
    -------
    MonteCarloResult
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n (number of draws) must be a whole number >= 1, got {n!r}")
    spread, alpha_spread = _mc_spreads(spread, alpha_spread, parameters)
    names = monte_carlo_names(paper_cell().m, parameters)
    factors = monte_carlo_factors(np.random.default_rng(seed), n, len(names), spread, alpha_spread, parameters)
    cs, cl, reasons = monte_carlo_draws(factors, parameters=parameters, alpha=alpha, delta=delta, L=L, P=P, EA=EA,
                                        c=c, f_hz=f_hz, progress=progress)
    f = np.atleast_1d(np.asarray(f_hz, dtype=float)).ravel()
    label = "all parameters" if parameters == "all" else "material parameters (EA_j, c_j, P)"
    return MonteCarloResult(names=names, factors=factors, change_storage=cs, change_loss=cl, reasons=tuple(reasons),
                            spread=spread, seed=seed, alpha_spread=alpha_spread if parameters == "all" else 0.0,
                            label=label, frequency_hz=f)


def _mc_spreads(spread, alpha_spread, parameters):
    spread = positive_scalar("spread", spread)
    if spread >= 1:
        raise ValueError(f"spread must be a fraction below 1, got {spread!r}")
    if parameters not in ("all", "material"):
        raise ValueError(f"parameters must be 'all' or 'material', got {parameters!r}")
    alpha_spread = spread if alpha_spread is None else positive_scalar("alpha_spread", alpha_spread, "rad")
    return spread, alpha_spread


def monte_carlo_names(m: int, parameters: str = "all") -> tuple[str, ...]:
    """Names of the perturbed parameters of :func:`monte_carlo` for a cell of ``m`` tendons (factor columns)."""
    names = tuple(f"EA[{j}]" for j in range(m)) + tuple(f"c[{j}]" for j in range(m)) + ("P",)
    return names + (("L", "delta", "alpha") if parameters == "all" else ())


def monte_carlo_factors(rng: np.random.Generator, n: int, k: int, spread: float, alpha_spread: float,
                        parameters: str = "all") -> np.ndarray:
    """Draw ``n`` rows of ``k`` factors as :func:`monte_carlo` does, shape (n, k) (α column: shifts in rad)."""
    factors = 1 + spread * rng.uniform(-1.0, 1.0, size=(n, k))
    if parameters == "all":
        factors[:, -1] = alpha_spread * rng.uniform(-1.0, 1.0, size=n)
    return factors


def monte_carlo_draws(factors, *, parameters: str = "all", alpha: float = 0.0, delta: float | None = None,
                      L: float = 1.0, P: float = 1000.0, EA=1.0, c=1.0, f_hz=SENSITIVITY_FREQUENCIES,
                      progress: bool | None = False):
    """Evaluate given draws of :func:`monte_carlo` (a pure function: the same factors, the same numbers).

    Parameters
    ----------
    factors : ndarray, shape (n, k)
        Rows as drawn by :func:`monte_carlo_factors`, columns :func:`monte_carlo_names`.
    parameters, alpha, delta, L, P, EA, c, f_hz
        The reference, as in :func:`monte_carlo`.

    Returns
    -------
    change_storage, change_loss : ndarray, shape (n,)
        Largest |ΔG'/G'| and |ΔG''/G''| over frequency (NaN for an invalid draw).
    reasons : list of str
        The error type of each invalid draw, "" for valid ones.
    """

    factors = np.atleast_2d(np.asarray(factors, dtype=float))
    n = factors.shape[0]
    f = np.atleast_1d(positive_array("frequency", f_hz, unit="Hz")).ravel()
    cell, EA, c = _base_parameters(alpha, delta, L, P, EA, c, True)
    delta0 = float(cell.parameters["delta"])
    m = cell.m
    G0 = modulus(compliance(linearize(cell, P=P, EA=EA, c=c), f), cell.strut_length)
    cs, cl, reasons = np.full(n, np.nan), np.full(n, np.nan), []
    for i in progress_bar(range(n), desc="Monte Carlo", unit="draw", progress=progress):
        fa = factors[i]
        try:
            if parameters == "all":
                cell_i = paper_cell(alpha=alpha + fa[-1], delta=delta0 * fa[-2], L=L * fa[-3])
            else:
                cell_i = cell
            lin = linearize(cell_i, P=P * fa[2 * m], EA=EA * fa[:m], c=c * fa[m:2 * m])
            G1 = modulus(compliance(lin, f), cell_i.strut_length)
        except ValueError as err:
            reasons.append(type(err).__name__)
            continue
        cs[i] = np.max(np.abs(G1.real / G0.real - 1))
        cl[i] = np.max(np.abs(G1.imag / G0.imag - 1))
        reasons.append("")
    return cs, cl, reasons

from ._deprecated import moved_away  # noqa: E402

__getattr__ = moved_away(__name__)  # the public names of 0.2.0 that moved away: a DeprecationWarning names their home

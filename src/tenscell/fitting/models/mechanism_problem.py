"""A mechanism against data: parameter layout, moduli averaged over assignments, residuals, exact Jacobian.

For parameters ``φ`` (natural logs), each field of the :class:`Mechanism`
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
from ...linear.modal import modulus
from ...model.equilibrium import Cell
from .heterogeneity import DISTRIBUTIONS, assignments
from .mechanism import KINDS, Field, Mechanism
from ..parameters import ProblemLayout, _family_groups, _is_creep, _prestress_layout, as_datasets, default_bounds
from .voigt import _LN10, _PENALTY, centred_start

__all__ = ["MechanismProblem", "make_mechanism_problem", "MechanismEvaluation"]



@dataclass(frozen=True, eq=False)
class MechanismEvaluation:
    """Moduli at one parameter vector (points of a problem, or any grid)."""

    G: np.ndarray  # (N,) complex moduli (Pa), averaged over assignments, viscosity included
    G_assign: np.ndarray  # (K, N) complex moduli of each assignment (structure + viscosity)
    dG: np.ndarray | None  # (N, n_params) complex dG/dφ


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


def _bounds_of(kind: str, S: float, w_m: float, G_loss: float) -> tuple[float, float]:
    """Default bounds of a parameter kind, from the data's scales (module :mod:`.problem` conventions)."""
    if kind == "stiffness":
        return 1e-6 * S, 1e6 * S
    if kind == "damping":
        return 1e-6 * S / w_m, 1e6 * S / w_m
    if kind == "coefficient":
        return 1e-8 * S * min(1.0, 1.0 / w_m), 1e6 * S * max(1.0, 1.0 / w_m)
    if kind == "time":
        return 1e-6 / w_m, 1e6 / w_m
    if kind == "exponent":
        return 0.01, 0.99
    if kind == "ratio":  # TensionSpringpot's beta: from the geometric prestress stiffness dominating to negligible
        return 1e-3, 1e5
    if kind == "decades":
        return 0.01, 4.0
    if kind == "tail":  # a trap model's tail exponent: below 0.5 the m·K values span > 6 decades per stratum
        # and K(ω) becomes too ill-conditioned for its derivatives to be trusted
        return 0.5, 5.0
    return 1e-8 * G_loss / w_m, 1e2 * G_loss / w_m  # viscosity (Pa·s)


@dataclass(frozen=True, eq=False, repr=False)
class MechanismProblem(ProblemLayout):
    """A mechanism's moduli against one or several data sets (built by :func:`make_mechanism_problem`).

    Duck-types the parts of :class:`~tenscell.fitting.models.voigt.FitProblem` that
    the search (:func:`tenscell.fitting.search.run_search`) and
    :func:`~tenscell.fitting.identifiability.identifiability` use, and adds
    its own starts (:meth:`initial_guess`) and moves (:meth:`perturb`).
    """

    mechanism: Mechanism
    cell: Cell
    names: tuple
    units: tuple
    descriptions: tuple
    kinds: tuple
    lower: np.ndarray
    upper: np.ndarray
    free: np.ndarray
    fixed_log: np.ndarray
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
    n_penalties: int = 0

    def __repr__(self) -> str:
        return (f"MechanismProblem({self.mechanism.name}: {self.n_free} free of {self.n_params} parameters, "
                f"{self.n_datasets} data set(s), {self.n_points} points)")

    # -- layout (the rest in fitting.layout.ProblemLayout) ---------------------------
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
    def law_values(self, phi) -> tuple[dict, dict]:
        """Per law parameter: values (K, m) and d ln value / d φ (K, m, n_params), at log-parameters ``phi``."""
        vals, dln = {}, {}
        for name, D, const in self.field_maps:
            lnx = const + D @ phi
            dl = D.copy()
            for fname, idx, dist, u in self.shape_maps:
                if fname == name:  # ln x = ln scale + q(u; shape), with q the distribution's log quantile at scale 1
                    q, _, dq = DISTRIBUTIONS[dist](1.0, math.exp(phi[idx])).log_quantile(u)
                    lnx = lnx + q
                    dl[..., idx] = dq
            vals[name], dln[name] = np.exp(lnx), dl
        return vals, dln

    def group_prestress(self, phi) -> np.ndarray:
        """Model prestress (N) of each group on the reference cell."""
        return np.exp(self.group_log_offset + self.group_map @ phi[self.prestress_slice])

    def evaluate(self, phi, omega, P, jac: bool, dP=None) -> MechanismEvaluation | None:
        """Moduli at angular frequencies ``omega`` (rad/s) and model prestresses ``P`` (N), per point.

        ``dP`` (N, n_params): d ln P / d φ of each point (for the Jacobian). None where not a stable cell.
        """
        from ...linear.dynamic import dynamic_compliance

        vals, dln = self.law_values(phi)
        law_cls = getattr(_laws, self.mechanism.law)
        K, m = next(iter(vals.values())).shape
        N = omega.size
        G_assign = np.empty((K, N), dtype=complex)
        dG = np.zeros((N, self.n_params), dtype=complex) if jac else None
        l, T0 = np.tile(self.lengths, K), np.tile(self.T0, K)
        law = law_cls._trusted(**{n: v.ravel() for n, v in vals.items()})
        for Pg in np.unique(P):
            sel = np.flatnonzero(P == Pg)
            w = omega[sel]
            out = self._kernel(dynamic_compliance, law, l, float(Pg), Pg * T0, w, vals, dln, K, m, jac)
            if out is None:
                return None
            G_assign[:, sel], dGk, dGP = out
            if jac:
                assert dG is not None and dP is not None
                dG[sel] = dGk + dGP[:, None] * dP[sel]
        if self.eta_index is not None:
            visc = 1j * omega * math.exp(phi[self.eta_index])
            G_assign = G_assign + visc[None]
            if jac:
                assert dG is not None
                dG[:, self.eta_index] += visc
        return MechanismEvaluation(G=G_assign.mean(axis=0), G_assign=G_assign, dG=dG)

    def _kernel(self, dynamic_compliance, law, l, P, T, w, vals, dln, K, m, jac):
        """Structural G of each assignment (K, n_w) and, with ``jac``, dG by φ (n_w, n_params), P dG/dP (n_w,)."""
        nw = w.size

        def stack(a):  # (n_w, K·m) -> (K·n_w, m): assignments stacked along the frequency axis of the kernel
            return np.transpose(a.reshape(nw, K, m), (1, 0, 2)).reshape(K * nw, m)

        ks = law.complex_stiffness(l, T, w)
        kstar = stack(ks)
        if jac:
            dk_dT, dk = law.complex_stiffness_derivatives(l, T, w)
            dirs = np.zeros((self.n_params + 2, K * nw, m), dtype=complex)
            for p, name in enumerate(law.names):
                if name not in vals:
                    continue
                chain = (vals[name][..., None] * dln[name]).reshape(K * m, self.n_params)  # x_p ∂ln x_p/∂φ
                contrib = dk[p][:, :, None] * chain[None]  # (n_w, K·m, n_params)
                for q in np.flatnonzero(np.any(chain != 0, axis=0)):
                    dirs[q] += stack(contrib[..., q])
            dirs[-2] = stack(dk_dT * T[None])  # P ∂k*/∂P at fixed parameters: (∂k*/∂T)·P·T0
            dirs[-1] = kstar  # the Euler direction
        try:
            if jac:
                J, dJ = dynamic_compliance(self.cell, P, kstar, dirs)
            else:
                J = dynamic_compliance(self.cell, P, kstar)
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(J)):
            return None
        G = modulus(J, self.L_ref)
        Gk = G.reshape(K, nw)
        if not jac:
            return Gk, None, None
        dlnG = -dJ / J[None]  # (q, K·n_w)
        dG = (G[None] * dlnG).reshape(-1, K, nw).mean(axis=1)  # d mean_k G_k, (q, n_w)
        dGP = G * (1.0 + (dJ[-1] - dJ[-2]) / J)  # P dG/dP = −G·P ∂ln J/∂P (module docstring)
        dGP = dGP.reshape(K, nw).mean(axis=0)
        return Gk, dG[: self.n_params].T, dGP

    # -- at the data points ----------------------------------------------------------------
    def _at_data(self, phi, jac: bool) -> MechanismEvaluation | None:
        P = self.group_prestress(phi)[self.group_index]
        dP = None
        if jac:
            dP = np.zeros((self.n_points, self.n_params))
            dP[:, self.prestress_slice] = self.group_map[self.group_index]
        return self.evaluate(phi, self.omega, P, jac, dP)

    def _evaluate_constrained(self, phi, jac: bool):
        return self._at_data(phi, jac)

    def _residuals_from(self, out) -> np.ndarray:
        if out is None or not (np.all(out.G.real > 0) and np.all(out.G.imag > 0)):
            return np.full(self.y_obs.size, _PENALTY)
        return self.weights * (np.concatenate([np.log10(out.G.real), np.log10(out.G.imag)]) - self.y_obs)

    def _jacobian_from(self, out) -> np.ndarray:
        if out is None or out.dG is None:
            return np.zeros((self.y_obs.size, self.n_free))
        G, dG = out.G, out.dG[:, self.free]
        with np.errstate(divide="ignore", invalid="ignore"):
            blocks = [dG.real / (G.real[:, None] * _LN10), dG.imag / (G.imag[:, None] * _LN10)]
        return self.weights[:, None] * np.nan_to_num(np.vstack(blocks))

    def _penalty_from(self, out, jac: bool):
        return np.zeros(0), (np.zeros((0, self.n_free)) if jac else None)

    def residuals(self, theta) -> np.ndarray:
        """Weighted residuals ``w·(log10 G_model − log10 G_data)``, shape (2N,) (G' block, then G'')."""
        return self._residuals_from(self._at_data(self.full(theta), jac=False))

    def jacobian(self, theta) -> np.ndarray:
        """Exact Jacobian of :meth:`residuals` by the free log-parameters, shape (2N, n_free)."""
        return self._jacobian_from(self._at_data(self.full(theta), jac=True))

    def jacobian_fd(self, theta, step: float = 1e-5) -> np.ndarray:
        """Central finite differences of :meth:`residuals` (the slow reference)."""
        from .voigt import _central

        return _central(self.residuals, theta, step)

    def moduli(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """Model G', G'' (Pa) at the data points; NaN where the model is not a stable cell."""
        out = self._at_data(self.full(theta), jac=False)
        if out is None:
            return np.full(self.n_points, np.nan), np.full(self.n_points, np.nan)
        return out.G.real, out.G.imag

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
        if out is None or out.G_assign.shape[0] < 2:
            return 0.0, 0.0
        Ga = out.G_assign
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.std(np.log10(Ga.real), axis=0), np.std(np.log10(Ga.imag), axis=0)
        return float(np.nanmax(s[0])), float(np.nanmax(s[1]))

    def feasible(self, theta) -> bool:
        """No activity constraints: always True."""
        return True

    def stiffness_spread(self, theta) -> float:
        """Largest spread log10(max/min) over the tendons of any stiffness field (stiffnesses, springpot moduli), decades."""
        vals, _ = self.law_values(self.full(theta))
        spreads = [float(np.log10(vals[f.law_parameter].max() / vals[f.law_parameter].min()))
                   for f in self.mechanism.fields if f.kind in ("stiffness", "coefficient")]
        return max(spreads, default=0.0)

    # -- the search's starts and moves ------------------------------------------------------
    def initial_guess(self, rng: np.random.Generator, candidates: int = 24) -> np.ndarray:
        """A start: the best of a few log-uniform draws in the middle of the bounds, scaled onto the data.

        Every scalable parameter (stiffnesses, damping, coefficients, viscosity, prestress) scaled by λ
        scales G* by λ exactly, so the mean log residual of a draw is removed by one shift.
        """
        lo, hi = self.lower, self.upper
        mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        scal = np.array([KINDS[k][1] if k in KINDS else k in ("s", "P") for k in self.kinds]) & self.free
        best = None
        for _ in range(candidates):
            phi = self.fixed_log.copy()
            draw = mid + rng.uniform(-0.6, 0.6, mid.size) * half
            phi[self.free] = draw[self.free]
            score = centred_start(self, self._at_data(phi, jac=False), phi, scal)
            if score is None:
                continue
            if best is None or score < best[0]:
                best = (score, phi)
        phi = best[1] if best is not None else self.fixed_log.copy()
        return np.clip(phi[self.free], lo[self.free], hi[self.free])

    def perturb(self, theta, rng: np.random.Generator) -> np.ndarray:
        """A basin-hopping move: every free log-parameter jittered by about half a decade, within the bounds."""
        lo, hi = self.bounds
        step = np.minimum(0.5 * _LN10, 0.25 * (hi - lo))
        return np.clip(np.asarray(theta) + rng.normal(0.0, 1.0, theta.size) * step, lo, hi)


# ---------------------------------------------------------------------------------------
# building a problem
# ---------------------------------------------------------------------------------------
def _layout(mech: Mechanism, cell: Cell, law_cls):
    """Field parameters (names, units, kinds, descriptions) and the maps of :attr:`MechanismProblem.field_maps`."""
    groups, fams = _family_groups(cell)
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
    data : RheologyData or sequence of RheologyData
        As for :func:`tenscell.fitting.fit` (creep data are not supported here).
    model : str or Mechanism
        A name of :data:`~tenscell.fitting.models.mechanism.MECHANISMS` or a spec.
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
        Unknown mechanism or names, bad bounds or fixed values, creep data, too few points.
    """
    from ...model.shapes import paper_cell
    from .mechanism import mechanism

    mech = mechanism(model)
    datasets = as_datasets(data)
    if any(_is_creep(d) for d in datasets):
        raise ValueError(f"model={mech.name!r}: creep data are fitted by the per-tendon Voigt fit only")
    cell = paper_cell() if cell is None else cell
    law_cls = getattr(_laws, mech.law, None)
    if law_cls is None or not hasattr(law_cls, "complex_stiffness"):
        raise ValueError(f"mechanism {mech.name!r}: tenscell.laws has no law {mech.law!r} with a dynamic tangent")
    rows, per_field, groups = _layout(mech, cell, law_cls)
    if mech.viscosity:
        rows.append(("eta_cytoplasm", "Pa·s", "viscosity", "cytoplasm viscosity in parallel with the structure"))
    p_names, p_units, p_desc, p_kinds, pgroups, point_group = _prestress_layout(datasets)
    n_field = len(rows) - int(mech.viscosity)
    names = tuple([r[0] for r in rows] + p_names)
    units = tuple([r[1] for r in rows] + p_units)
    kinds = tuple([r[2] for r in rows] + p_kinds)
    descs = tuple([r[3] for r in rows] + p_desc)
    n_points = sum(d.n for d in datasets)
    if 2 * n_points < len(names):
        raise DataError(f"{len(datasets)} data set(s) with {n_points} points give {2 * n_points} residuals, fewer "
                        f"than the {len(names)} parameters of mechanism {mech.name!r}")
    L_ref = float(cell.strut_length)
    defaults, S, w_m, P_med = default_bounds(datasets, L_ref)
    G_loss = float(np.median(np.concatenate([d.G_loss for d in datasets])))
    lower, upper = _mech_bounds(names, kinds, bounds, defaults, S, w_m, G_loss)
    free, fixed_log = _mech_fixed(names, lower, upper, fixed)
    field_maps, shape_maps = _maps(per_field, groups, len(names), mech.K, mech.seed)
    group_map = np.zeros((len(pgroups), len(p_names)))
    for g, (_, _, _, links) in enumerate(pgroups):
        for j, v in links.items():
            group_map[g, j] = v
    return MechanismProblem(
        mechanism=mech, cell=cell, names=names, units=units, descriptions=descs, kinds=kinds, lower=lower,
        upper=upper, free=free, fixed_log=fixed_log, n_field=n_field, field_maps=field_maps, shape_maps=shape_maps,
        eta_index=n_field if mech.viscosity else None, L_ref=L_ref,
        lengths=np.asarray(cell.lengths, dtype=float), T0=np.asarray(cell.T0, dtype=float),
        sources=tuple(d.source for d in datasets),
        omega=2 * np.pi * np.concatenate([d.frequency_hz for d in datasets]),
        dataset_index=np.concatenate([np.full(d.n, k) for k, d in enumerate(datasets)]),
        group_index=np.concatenate(point_group).astype(int),
        group_log_offset=np.array([g[2] for g in pgroups]), group_map=group_map,
        group_measured=np.array([g[1] for g in pgroups]),
        y_obs=np.concatenate([np.log10(np.concatenate([d.G_storage for d in datasets])),
                              np.log10(np.concatenate([d.G_loss for d in datasets]))]),
        weights=np.concatenate([np.concatenate([d.weights_storage for d in datasets]),
                                np.concatenate([d.weights_loss for d in datasets])]),
        prestress_start=len(rows),
    )


def _mech_bounds(names, kinds, bounds, defaults, S, w_m, G_loss):
    bounds = dict(bounds or {})
    unknown = [k for k in bounds if k not in names and k not in kinds]
    if unknown:
        raise ValueError(f"bounds: {unknown[0]!r} is neither a parameter nor a kind here (parameters: "
                         f"{', '.join(names)}; kinds: {', '.join(dict.fromkeys(kinds))})")
    lower, upper = np.empty(len(names)), np.empty(len(names))
    for i, (n, k) in enumerate(zip(names, kinds)):
        lo, hi = bounds.get(n, bounds.get(k, defaults[k] if k in defaults else _bounds_of(k, S, w_m, G_loss)))
        if not (0 < float(lo) < float(hi) < math.inf):
            raise ValueError(f"bounds[{n!r}]: need 0 < lower < upper < inf, got ({lo!r}, {hi!r})")
        lower[i], upper[i] = math.log(lo), math.log(hi)
    return lower, upper


def _mech_fixed(names, lower, upper, fixed):
    free = np.ones(len(names), dtype=bool)
    fixed_log = 0.5 * (lower + upper)
    for key, value in dict(fixed or {}).items():
        if key not in names:
            raise ValueError(f"fixed: cannot fix {key!r}; parameters here: {', '.join(names)}")
        v = float(value)
        i = names.index(key)
        if not (v > 0 and lower[i] <= math.log(v) <= upper[i]):
            raise ValueError(f"fixed[{key!r}] = {value!r} lies outside its bounds [{math.exp(lower[i]):.6g}, "
                             f"{math.exp(upper[i]):.6g}]")
        free[i], fixed_log[i] = False, math.log(v)
    return free, fixed_log

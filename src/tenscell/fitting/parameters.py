"""Parameters and layout of a fit: which parameters exist, their names, units, bounds and fixed values, and the data's arrays.

This is the first of the fit's three layers (as in lmfit: parameters →
problem → minimizer): :func:`parameter_layout` and :func:`data_arrays` turn
a cell, data sets and the user's options into the plain arrays of a
:class:`~tenscell.fitting.models.voigt.FitProblem`; the problem computes
residuals and their Jacobians (:mod:`~tenscell.fitting.models.voigt`,
:mod:`~tenscell.fitting.models.voigt_kernel`); :func:`tenscell.fitting.fit` searches.
A new parametrization (a mode of :data:`TENDON_MODES`, a new parameter kind)
is a change here only.

Parameters are laid out as stiffness groups, damping groups, prestress
parameters, then ``L``; every parameter has a kind (``"EA"``, ``"c"``,
``"P"``, ``"s"``, ``"P_data"``, ``"L"``) whose default bounds scale with the
data (:func:`default_bounds`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._checks import positive_scalar
from .._results import format_repr
from ..io.data import DataError, RheologyData
from ..model.equilibrium import Cell

__all__ = ["Parameters", "ParameterSpec", "TENDON_MODES", "DAMPING_MODES", "required_points", "as_datasets",
           "parameter_layout", "data_arrays", "default_bounds", "check_options", "prestress_varies", "kind_bounds",
           "bounds_by_name", "fixed_by_name", "family_groups", "prestress_layout"]

@dataclass(frozen=True)
class ParameterSpec:
    """One parameter of a fit's layout (an entry of :class:`Parameters`), in SI units.

    Attributes
    ----------
    name, unit, kind, description : str
        ``kind`` sets default bounds and starts (``"EA"``, ``"stiffness"``, ``"exponent"``, ``"s"``...).
    lower, upper : float
        Bounds (the fit works in the log between them).
    fixed : float or None
        The value a fixed parameter is held at; None for a free one.
    start : float
        Where a free parameter sits when a start does not place it (the layout's reference: the cell's own strut
        length, the middle of the bounds in log...); the value of a fixed one.
    """

    name: str
    unit: str
    kind: str
    description: str
    lower: float
    upper: float
    fixed: float | None
    start: float

    @property
    def vary(self) -> bool:
        """Whether the parameter is free."""
        return self.fixed is None


@dataclass(frozen=True, eq=False, repr=False)
class Parameters:
    """Every parameter of a fit, built once by the layout of its model (lmfit's ``Parameters``): names, units, kinds,
    descriptions, bounds and what is held fixed, as plain read-only arrays a problem pickles to its workers.

    Attributes
    ----------
    names, units, descriptions, kinds : tuple of str
    lower, upper : ndarray
        Natural logs of the bounds (SI units); ``-inf``/``inf`` for a layout without data (a model evaluated
        anywhere).
    free : ndarray of bool
    fixed_log : ndarray
        Natural logs of the fixed parameters' values, and of the free ones' reference values
        (:attr:`ParameterSpec.start`).

    ``params["s"]`` (a name) or ``params[3]`` is one :class:`ParameterSpec`; iterating gives them in order.
    """

    names: tuple
    units: tuple
    descriptions: tuple
    kinds: tuple
    lower: np.ndarray
    upper: np.ndarray
    free: np.ndarray
    fixed_log: np.ndarray

    def __post_init__(self):
        for name in ("names", "units", "descriptions", "kinds"):
            object.__setattr__(self, name, tuple(str(x) for x in getattr(self, name)))
        n = len(self.names)
        for name, dtype in (("lower", float), ("upper", float), ("free", bool), ("fixed_log", float)):
            arr = np.array(getattr(self, name), dtype=dtype).ravel()
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        sizes = {len(self.units), len(self.descriptions), len(self.kinds), self.lower.size, self.upper.size,
                 self.free.size, self.fixed_log.size}
        if sizes != {n}:
            raise ValueError(f"Parameters: {n} names but fields of lengths {sorted(sizes)}")
        if len(set(self.names)) != n:
            raise ValueError(f"Parameters: a name appears twice in {', '.join(self.names)}")

    def __len__(self) -> int:
        return len(self.names)

    def __iter__(self):
        return (self[i] for i in range(len(self)))

    def __contains__(self, name) -> bool:
        return name in self.names

    def __getitem__(self, key) -> ParameterSpec:
        i = self.index(key) if isinstance(key, str) else int(key)
        fixed = None if self.free[i] else math.exp(self.fixed_log[i])
        return ParameterSpec(name=self.names[i], unit=self.units[i], kind=self.kinds[i],
                             description=self.descriptions[i], lower=math.exp(self.lower[i]),
                             upper=math.exp(self.upper[i]), fixed=fixed, start=math.exp(self.fixed_log[i]))

    def index(self, name: str) -> int:
        """Position of parameter ``name`` (ValueError naming the parameters otherwise)."""
        try:
            return self.names.index(name)
        except ValueError:
            raise ValueError(f"no parameter named {name!r}; parameters: {', '.join(self.names)}") from None

    def __repr__(self) -> str:
        rows = [f"{p.name} ({p.unit or '-'}, {p.kind}): "
                + (f"fixed at {p.fixed:.4g}" if p.fixed is not None else f"free in [{p.lower:.3g}, {p.upper:.3g}]")
                for p in self]
        return format_repr(f"Parameters: {int(self.free.sum())} free of {len(self)}", *rows[:12],
                           *(["..."] if len(rows) > 12 else []))

    def replaced(self, *, free=None, fixed_log=None, lower=None, upper=None) -> Parameters:
        """The same parameters with the free mask, the (log) values or the (log) bounds replaced."""
        return Parameters(self.names, self.units, self.descriptions, self.kinds,
                          self.lower if lower is None else lower, self.upper if upper is None else upper,
                          self.free if free is None else free, self.fixed_log if fixed_log is None else fixed_log)

    def subset(self, index) -> Parameters:
        """The parameters at positions ``index`` (in that order)."""
        index = np.asarray(index, dtype=int)
        pick = lambda xs: tuple(xs[i] for i in index)  # noqa: E731
        return Parameters(pick(self.names), pick(self.units), pick(self.descriptions), pick(self.kinds),
                          self.lower[index], self.upper[index], self.free[index], self.fixed_log[index])

    @classmethod
    def from_rows(cls, rows, lower, upper, free, fixed_log) -> Parameters:
        """From ``(name, unit, kind, description)`` rows and the log bounds, free mask and log values."""
        rows = list(rows)
        return cls(tuple(r[0] for r in rows), tuple(r[1] for r in rows), tuple(r[3] for r in rows),
                   tuple(r[2] for r in rows), lower, upper, free, fixed_log)


#: how tendon stiffnesses are parametrized
TENDON_MODES = ("per-tendon", "per-family", "uniform")
#: how tendon damping is parametrized
DAMPING_MODES = ("uniform", "per-family")


def required_points(tendons: str = "per-tendon", damping: str = "uniform", n_families: int = 2) -> int:
    """Minimum number of data points for a fit of one data set.

    Each point gives two residuals. Per-tendon stiffnesses are deliberately
    over-parametrized (as in the paper: 36 parameters against 32 residuals
    for the 16-point frequency data; the trust-region solver handles it, and
    the alternatives show the non-uniqueness), so they count as one stiffness
    here; the other parameters (c, P or s, L) each count. A joint fit needs
    one more point per data set whose prestress is fitted.
    """
    n_ea = {"per-tendon": 1, "per-family": n_families, "uniform": 1}[_choice("tendons", tendons, TENDON_MODES)]
    n_c = n_families if _choice("damping", damping, DAMPING_MODES) == "per-family" else 1
    return n_ea + n_c + 2


def _choice(name, value, allowed):
    if value not in allowed:
        raise ValueError(f"{name} must be one of {', '.join(repr(a) for a in allowed)}, got {value!r}")
    return value


def _tendon_labels(cell: Cell) -> list[str]:
    st = cell.structure
    names = st.node_names if st.node_names else tuple(str(i) for i in range(st.n_nodes))
    return [f"{names[a]}-{names[b]} ({fam})" for (a, b), fam in zip(st.tendons, st.families)]


def family_groups(cell: Cell) -> tuple[np.ndarray, list[str]]:
    """``(family index of every tendon, the families in order of appearance)`` of ``cell``."""
    fams = list(dict.fromkeys(cell.structure.families))  # in order of appearance
    groups = np.array([fams.index(f) for f in cell.structure.families])
    return groups, fams


def _is_creep(d) -> bool:
    return d.kind == "creep"


def as_datasets(data) -> tuple:
    """One data set or a sequence of them as a tuple of :class:`RheologyData`,
    :class:`~tenscell.io.creep_data.CreepData` or :class:`~tenscell.io.relaxation_data.RelaxationData`
    (ValueError otherwise)."""
    from ..io.creep_data import CreepData
    from ..io.relaxation_data import RelaxationData

    kinds = (RheologyData, CreepData, RelaxationData)
    items = (data,) if isinstance(data, kinds) else tuple(data) if isinstance(data, (list, tuple)) else None
    if not items or not all(isinstance(d, kinds) for d in items):
        raise ValueError("data must be a tenscell.io.data.RheologyData, CreepData or RelaxationData, or a non-empty "
                         f"list of them, got {type(data).__name__}")
    return items


def _stiffness_layout(cell: Cell, tendons: str, damping: str):
    """(ea_groups, ea_names, ea_desc, c_groups, c_names, c_desc) for the parametrization."""
    m = cell.m
    fam_groups, fams = family_groups(cell)
    labels = _tendon_labels(cell)
    if tendons == "per-tendon":
        ea = (np.arange(m), [f"EA[{j}]" for j in range(m)],
              [f"stiffness of tendon {j}, {lab}" for j, lab in enumerate(labels)])
    elif tendons == "per-family":
        ea = (fam_groups, [f"EA_{f}" for f in fams], [f"stiffness of every {f} tendon" for f in fams])
    else:
        ea = (np.zeros(m, dtype=int), ["EA"], ["stiffness of every tendon"])
    if damping == "per-family":
        cc = (fam_groups, [f"c_{f}" for f in fams], [f"damping of every {f} tendon" for f in fams])
    else:
        cc = (np.zeros(m, dtype=int), ["c"], ["damping of every tendon"])
    return (*ea, *cc)


def prestress_layout(datasets):
    """Prestress parameters and groups: (names, units, descs, kinds, groups) with groups a list of
    (dataset, measured Pa or NaN, log offset, {parameter position: 1}) and point -> group index."""
    known = [d.prestress is not None for d in datasets]
    joint = len(datasets) > 1
    names, units, descs, kinds = [], [], [], []
    if any(known):
        names.append("s")
        units.append("m²")
        kinds.append("s")
        descs.append("prestress scale: model prestress (N) = s × prestress (Pa) of the data"
                     + (" (one scale links the data sets)" if joint else ""))
    own = {}
    for k, d in enumerate(datasets):
        if known[k]:
            continue
        own[k] = len(names)
        if any(known):
            names.append(f"P_data[{k}]")
            units.append("Pa")
            kinds.append("P_data")
            descs.append(f"prestress (Pa) at which data set {k} ({d.source}) was measured: not stated, so fitted")
        else:
            names.append(f"P[{k}]" if joint else "P")
            units.append("N")
            kinds.append("P")
            descs.append("prestress: tendon tensions are P·T0" + (f" for data set {k} ({d.source})" if joint else ""))
    groups, point_group = [], []
    for k, d in enumerate(datasets):
        if known[k]:
            uniq, inv = np.unique(d.prestress, return_inverse=True)
            base = len(groups)
            groups += [(k, float(p), math.log(p), {0: 1.0}) for p in uniq]
            point_group.append(base + np.asarray(inv).ravel())
        else:
            links = {own[k]: 1.0}
            if any(known):
                links[0] = 1.0
            groups.append((k, math.nan, 0.0, links))
            point_group.append(np.full(d.n, len(groups) - 1))
    return names, units, descs, kinds, groups, point_group


def default_bounds(datasets, L_ref):
    """Default bounds per parameter kind and the scales used by the initial guess.

    A creep point at time t counts as a modulus 1/J at the angular frequency 1/t, a relaxation point as G(t) there
    (:func:`~tenscell.fitting.time_series.modulus_scales`).
    """
    from .time_series import modulus_scales

    G, w_m, _ = modulus_scales(datasets)
    S = G * L_ref**2
    known = [d.prestress for d in datasets if d.prestress is not None]
    P_med = float(np.median(np.concatenate(known))) if known else 1.0
    defaults = {
        "EA": (1e-8 * S, 1e6 * S),
        "c": (1e-6 * S / w_m, 1e6 * S / w_m),
        "P": (1e-10 * S, 1e4 * S),
        "s": (1e-10 * S / P_med, 1e4 * S / P_med),
        "P_data": (1e-3 * P_med, 1e3 * P_med),
        "L": (1e-3 * L_ref, 1e3 * L_ref),
    }
    return defaults, S, w_m, P_med


def _apply_bounds(kinds, bounds, defaults):
    bounds = dict(bounds or {})
    for key in bounds:
        if key not in defaults:
            raise ValueError(f"bounds: unknown parameter kind {key!r}; allowed: {', '.join(defaults)}")
        if key not in kinds:
            raise ValueError(f"bounds: {key!r} does not apply to these data (parameters here: "
                             f"{', '.join(dict.fromkeys(kinds))})")
    lower = np.empty(len(kinds))
    upper = np.empty(len(kinds))
    for i, k in enumerate(kinds):
        lo, hi = bounds.get(k, defaults[k])
        lo = positive_scalar(f"bounds[{k!r}] lower", lo)
        hi = positive_scalar(f"bounds[{k!r}] upper", hi)
        if not lo < hi:
            raise ValueError(f"bounds[{k!r}]: the lower bound {lo!r} must be below the upper bound {hi!r}")
        lower[i], upper[i] = math.log(lo), math.log(hi)
    return lower, upper


def _apply_fixed(names, kinds, lower, upper, fixed, L_ref, P_med):
    free = np.ones(len(names), dtype=bool)
    fixed_log = 0.5 * (lower + upper)
    fixed_log[-1] = math.log(L_ref) if lower[-1] < math.log(L_ref) < upper[-1] else fixed_log[-1]
    for i, k in enumerate(kinds):  # a data set's own prestress starts at the others' median
        if k == "P_data" and lower[i] < math.log(P_med) < upper[i]:
            fixed_log[i] = math.log(P_med)
    for key, value in dict(fixed or {}).items():
        if key not in names:  # any parameter may be held fixed (a stiffness group, a damping, a prestress, L)
            raise ValueError(f"fixed: cannot fix {key!r}; parameters here: {', '.join(names)}")
        v = positive_scalar(f"fixed[{key!r}]", value)
        i = names.index(key)
        if not lower[i] <= math.log(v) <= upper[i]:
            raise ValueError(f"fixed[{key!r}] = {v!r} lies outside its bounds [{math.exp(lower[i]):.6g}, "
                             f"{math.exp(upper[i]):.6g}]")
        free[i] = False
        fixed_log[i] = math.log(v)
    return free, fixed_log


def check_options(min_prestress_share, max_decades, min_prestress_elasticity, elasticity_frequency_hz) -> dict:
    """The search-space options, checked, as :class:`FitProblem` fields (module docstring of :mod:`.problem`)."""
    if min_prestress_elasticity is not None:
        min_prestress_elasticity = positive_scalar("min_prestress_elasticity", min_prestress_elasticity)
    elasticity_frequency_hz = positive_scalar("elasticity_frequency_hz", elasticity_frequency_hz, "Hz")
    if min_prestress_share is not None:
        min_prestress_share = positive_scalar("min_prestress_share", min_prestress_share)
        if min_prestress_share >= 1.0:
            raise ValueError(f"min_prestress_share must be below 1 (a share of the static stiffness), "
                             f"got {min_prestress_share!r}")
    if max_decades is not None:
        max_decades = positive_scalar("max_decades", max_decades, "decades")
    return dict(min_prestress_share=min_prestress_share, max_decades=max_decades,
                min_prestress_elasticity=min_prestress_elasticity,
                elasticity_omega=2 * math.pi * elasticity_frequency_hz)


def parameter_layout(cell: Cell, datasets, tendons: str, damping: str, bounds, fixed) -> tuple[dict, list]:
    """The parameters of a fit of ``cell`` to ``datasets`` as :class:`FitProblem` fields, and each data set's groups.

    Returns ``(fields, point_group)``: the :class:`Parameters` (names, units, descriptions, kinds,
    log bounds, free mask and fixed values), stiffness and damping groups,
    prestress groups and the scales of the initial guess; ``point_group[k]``
    is the prestress group of each point of data set ``k``. DataError if the
    data have fewer points than the layout needs (:func:`required_points`).
    """
    _choice("tendons", tendons, TENDON_MODES)
    _choice("damping", damping, DAMPING_MODES)
    ea_groups, ea_names, ea_desc, c_groups, c_names, c_desc = _stiffness_layout(cell, tendons, damping)
    p_names, p_units, p_desc, p_kinds, groups, point_group = prestress_layout(datasets)
    n_points = sum(d.n for d in datasets)
    need = required_points(tendons, damping, n_families=len(family_groups(cell)[1])) + len(p_names) - 1
    if n_points < need:
        src = datasets[0].source if len(datasets) == 1 else f"{len(datasets)} data sets"
        raise DataError(
            f"{src}: {n_points} data point{'s' if n_points != 1 else ''}, fewer than the {need} the fit "
            f"needs (tendons={tendons!r}, damping={damping!r}: at least as many points as stiffness groups "
            f"+ damping groups + prestress parameters + L)"
        )
    names = tuple(ea_names + c_names + p_names + ["L"])
    kinds = tuple(["EA"] * len(ea_names) + ["c"] * len(c_names) + p_kinds + ["L"])
    L_ref = float(cell.strut_length)
    defaults, S, w_m, P_med = default_bounds(datasets, L_ref)
    lower, upper = _apply_bounds(kinds, bounds, defaults)
    free, fixed_log = _apply_fixed(names, kinds, lower, upper, fixed, L_ref, P_med)
    group_map = np.zeros((len(groups), len(p_names)))
    for g, (_, _, _, links) in enumerate(groups):
        for j, v in links.items():
            group_map[g, j] = v
    params = Parameters(
        names=names, units=tuple(["N"] * len(ea_names) + ["N·s/m"] * len(c_names) + p_units + ["m"]),
        descriptions=tuple(ea_desc + c_desc + p_desc + ["strut length (redundant with P, EA, c: see docs)"]),
        kinds=kinds, lower=lower, upper=upper, free=free, fixed_log=fixed_log)
    fields = dict(
        params=params, tendons=tendons, damping=damping,
        n_ea=len(ea_names), n_c=len(c_names), ea_groups=np.asarray(ea_groups), c_groups=np.asarray(c_groups),
        group_log_offset=np.array([g[2] for g in groups]), group_map=group_map,
        group_measured=np.array([g[1] for g in groups]), group_dataset=np.array([g[0] for g in groups]),
        scale_stiffness=S, scale_damping=S / w_m,
    )
    return fields, point_group


def _cat(parts, dtype=float) -> np.ndarray:
    return np.concatenate(parts) if parts else np.zeros(0, dtype=dtype)


def data_arrays(datasets, point_group) -> dict:
    """The data as :class:`FitProblem` fields: moduli points first (G' block, then G''), creep points last."""
    moduli = [k for k, d in enumerate(datasets) if not _is_creep(d)]
    creep = [k for k, d in enumerate(datasets) if _is_creep(d)]
    mod = [datasets[k] for k in moduli]
    y_mod = [np.log10(_cat([d.G_storage for d in mod])), np.log10(_cat([d.G_loss for d in mod]))]
    w_mod = [_cat([d.weights_storage for d in mod]), _cat([d.weights_loss for d in mod])]
    return dict(
        sources=tuple(d.source for d in datasets),
        omega=2 * np.pi * _cat([d.frequency_hz for d in mod]),
        dataset_index=_cat([np.full(datasets[k].n, k) for k in moduli], int),
        group_index=_cat([point_group[k] for k in moduli], int),
        y_obs=np.concatenate(y_mod + [np.log10(datasets[k].compliance) for k in creep]),
        weights=np.concatenate(w_mod + [datasets[k].weights for k in creep]),
        creep_t=_cat([datasets[k].time_s for k in creep]),
        creep_dataset=_cat([np.full(datasets[k].n, k) for k in creep], int),
        creep_group=_cat([point_group[k] for k in creep], int),
    )


def prestress_varies(datasets) -> bool:
    """Whether the data state more than one prestress."""
    measured = [d.prestress for d in datasets if d.prestress is not None]
    return bool(measured) and np.unique(np.concatenate(measured)).size > 1


def kind_bounds(kind: str, S: float, w_m: float, G_loss: float) -> tuple[float, float]:
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


def bounds_by_name(names, kinds, bounds, defaults, S, w_m, G_loss):
    bounds = dict(bounds or {})
    unknown = [k for k in bounds if k not in names and k not in kinds]
    if unknown:
        raise ValueError(f"bounds: {unknown[0]!r} is neither a parameter nor a kind here (parameters: "
                         f"{', '.join(names)}; kinds: {', '.join(dict.fromkeys(kinds))})")
    lower, upper = np.empty(len(names)), np.empty(len(names))
    for i, (n, k) in enumerate(zip(names, kinds)):
        lo, hi = bounds.get(n, bounds.get(k, defaults[k] if k in defaults else kind_bounds(k, S, w_m, G_loss)))
        if not (0 < float(lo) < float(hi) < math.inf):
            raise ValueError(f"bounds[{n!r}]: need 0 < lower < upper < inf, got ({lo!r}, {hi!r})")
        lower[i], upper[i] = math.log(lo), math.log(hi)
    return lower, upper


def fixed_by_name(names, lower, upper, fixed):
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

"""Time series in the one stack: creep J(t) and stress relaxation G(t) of any model with a Laplace-domain modulus.

A model that gives its complex modulus ``G*(s)`` (Pa) anywhere off the negative real axis — a mechanism (its laws'
``k*(s)`` in the cell's exact compliance, :meth:`tenscell.laws.TendonLaw.laplace_stiffness`) or a structure-free
formula (its terms continued from ``iω`` to ``s``) — fits time data through the transforms

* creep after a stress step: ``J̄(s) = 1/(s·G*(s))`` (1/Pa);
* relaxation after a strain step: ``Ḡ(s) = G*(s)/s`` (Pa); a Newtonian term ``sη`` gives ``η``, an impulse at t = 0
  that the contour sees as ``η·c_M/t`` with ``|c_M|`` about 1e-9 (a constant inverts to that), far below any data,

each inverted at every data time by the fixed Talbot contour of :func:`tenscell.timedomain.invert_laplace`
(:func:`~tenscell.timedomain.talbot_contour`: ``f(t) = Re Σ_k w_k F(s_k)``). The contour is linear in ``F``, so the
exact Jacobian is the same sum over ``dF``: ``dJ̄ = −J̄·dG*/G*``, ``dḠ = dG*/s``, with ``dG*`` the model's own exact
derivatives at the nodes (the mechanism kernel's, from its laws' ``∂k*(s)/∂θ``).

A relaxation whose modulus scale is unknown (:attr:`tenscell.io.relaxation_data.RelaxationData.relative`) is
fitted by its shape: the model's ``G(t)/G(t_ref)`` against the data's ``G(t)/G(t_ref)``, ``t_ref`` its first time
(the reference, not a residual); a fit to shapes only cannot see the scale of the stiffnesses (an exact gauge of
the residuals, :meth:`TimeLayout.scale_blind`).

:class:`TimeLayout` holds the time points of a problem's data (planned once, when the problem is built), their
contour nodes and weights; :func:`time_values` turns ``G*`` at the nodes into the time functions and their
derivatives; :func:`time_residual_values` into the residuals' model values (log10).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..timedomain import talbot_contour

__all__ = ["TIME_KINDS", "FIT_NODES", "data_kind", "TimeLayout", "time_layout", "observed", "time_values",
           "time_residual_values", "relative_values", "data_layout", "modulus_scales"]

#: the kinds of time data (``data.kind``): creep compliance J(t), stress relaxation G(t)
TIME_KINDS = ("creep", "relaxation")
#: Talbot nodes of a fit's inversions (relative error about 1e-7 for the transforms of passive laws, far below any
#: data's scatter; the reported curves use :data:`tenscell.timedomain.TALBOT_NODES`)
FIT_NODES = 16


def data_kind(data) -> str:
    """The kind of :data:`tenscell.fitting.models.base.DATA_KINDS` a data set is: ``"moduli"`` (a frequency or
    prestress sweep), ``"creep"`` or ``"relaxation"``."""
    return data.kind if data.kind in TIME_KINDS else "moduli"


@dataclass(frozen=True, eq=False)
class TimeLayout:
    """The time points of a problem's creep and relaxation data, in the order of its time residuals' data sets.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Times (s) of every time point, data set after data set.
    dataset, group : ndarray of int, shape (n,)
        Each point's data set and prestress group.
    relaxation : ndarray of bool, shape (n,)
        True for a relaxation point, False for creep.
    reference : ndarray of int, shape (n,)
        For a point of a relative relaxation (a shape), the index of its data set's first point (its reference
        time); −1 otherwise.
    residual : ndarray of int, shape (r,)
        The points that are residuals (every point but the references of shapes), in order.
    s, w : ndarray of complex, shape (n, M)
        Contour nodes (1/s) and weights of each point (:func:`tenscell.timedomain.talbot_contour`).
    """

    t: np.ndarray
    dataset: np.ndarray
    group: np.ndarray
    relaxation: np.ndarray
    reference: np.ndarray
    residual: np.ndarray
    s: np.ndarray
    w: np.ndarray

    @property
    def n(self) -> int:
        """Time points."""
        return int(self.t.size)

    @property
    def n_residuals(self) -> int:
        """Time residuals (the points less the shapes' references)."""
        return int(self.residual.size)

    @property
    def nodes(self) -> np.ndarray:
        """Every contour node, flattened (n·M,)."""
        return self.s.ravel()

    @property
    def node_group(self) -> np.ndarray:
        """The prestress group of every node, flattened (n·M,)."""
        return np.repeat(self.group, self.s.shape[1])

    @property
    def scale_blind(self) -> bool:
        """Every time point belongs to a shape (a relative relaxation): the residuals cannot see a common scale of
        the moduli."""
        return bool(self.n) and bool(np.all(self.reference >= 0))

    def rows(self, dataset: int) -> np.ndarray:
        """Positions among the time residuals of data set ``dataset``'s."""
        return np.flatnonzero(self.dataset[self.residual] == dataset)

    def points(self, dataset: int) -> np.ndarray:
        """Positions among the time points of data set ``dataset``'s (every point, its reference included)."""
        return np.flatnonzero(self.dataset == dataset)


def time_layout(datasets, point_group, nodes: int = FIT_NODES) -> TimeLayout | None:
    """The :class:`TimeLayout` of the creep and relaxation sets among ``datasets`` (``point_group[k]``: the prestress
    group of each point of data set k); None when there are none."""
    ks = [k for k, d in enumerate(datasets) if d.kind in TIME_KINDS]
    if not ks:
        return None
    t = np.concatenate([datasets[k].time_s for k in ks])
    dataset = np.concatenate([np.full(datasets[k].n, k) for k in ks])
    group = np.concatenate([np.asarray(point_group[k], dtype=int) for k in ks])
    relaxation = np.concatenate([np.full(datasets[k].n, datasets[k].kind == "relaxation") for k in ks])
    reference = np.full(t.size, -1)
    start = 0
    for k in ks:
        d = datasets[k]
        if d.kind == "relaxation" and d.relative:
            reference[start:start + d.n] = start
        start += d.n
    residual = np.flatnonzero(reference != np.arange(t.size))
    s, w = talbot_contour(t, nodes)
    return TimeLayout(t=t, dataset=dataset, group=group, relaxation=relaxation, reference=reference,
                      residual=residual, s=s, w=w)


def observed(datasets, layout: TimeLayout) -> tuple[np.ndarray, np.ndarray]:
    """``(log10 of the data, weights)`` at the time residuals: J or G, a shape over its value at the reference."""
    ks = list(dict.fromkeys(layout.dataset.tolist()))
    values = np.concatenate([datasets[k].compliance if datasets[k].kind == "creep" else datasets[k].modulus
                             for k in ks])
    weights = np.concatenate([datasets[k].weights for k in ks])
    y = np.log10(values)
    rel = layout.reference >= 0
    y[rel] -= y[layout.reference[rel]]
    return y[layout.residual], weights[layout.residual]


def time_values(layout: TimeLayout, G, dG=None) -> tuple[np.ndarray, np.ndarray | None]:
    """The time function at every time point from ``G*`` (Pa) at the contour nodes (shape (n, M) or flat), and its
    derivatives from ``dG`` (shape (n·M, p)): creep J(t) (1/Pa), relaxation G(t) (Pa)."""
    n, M = layout.s.shape
    G = np.asarray(G).reshape(n, M)
    rel = layout.relaxation[:, None]
    F = np.where(rel, G / layout.s, 1.0 / (layout.s * G))
    y = np.sum((layout.w * F).real, axis=1)
    if dG is None:
        return y, None
    dG = np.asarray(dG).reshape(n, M, -1)
    dF = np.where(rel[..., None], dG / layout.s[..., None], -(F / G)[..., None] * dG)
    return y, np.einsum("nk,nkp->np", layout.w, dF).real


def time_residual_values(layout: TimeLayout, y, dy=None) -> tuple[np.ndarray, np.ndarray | None]:
    """``(log10 model, its derivatives)`` at the time residuals from the time function ``y`` (n,) and ``dy`` (n, p):
    ``log10 y``, or for a shape ``log10(y/y_ref)``. NaN where ``y`` is not positive (the caller's penalty)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ly = np.where(y > 0, np.log10(np.where(y > 0, y, 1.0)), np.nan)
        rel = layout.reference >= 0
        out = ly.copy()
        out[rel] -= ly[layout.reference[rel]]
        if dy is None:
            return out[layout.residual], None
        dl = dy / (y[:, None] * np.log(10.0))
        dl[rel] -= dl[layout.reference[rel]]
    return out[layout.residual], dl[layout.residual]


def relative_values(layout: TimeLayout, y) -> np.ndarray:
    """The time function ``y`` at every time point as the data state it: a shape's points over its reference's value
    (NaN everywhere when ``y`` is None: not a stable cell)."""
    if y is None:
        return np.full(layout.n, np.nan)
    out = np.asarray(y, dtype=float).copy()
    rel = layout.reference >= 0
    out[rel] = out[rel] / y[layout.reference[rel]]
    return out


def data_layout(datasets, point_group, nodes: int = FIT_NODES) -> dict:
    """The data of a problem with time series as its fields (moduli points first — every G', then every G'' —,
    then the time residuals): ``omega``, ``dataset_index``, ``group_index`` (the moduli points), ``y_obs``,
    ``weights`` and ``time`` (:class:`TimeLayout` or None); ``point_group[k]`` is the prestress group of each point of
    data set k."""
    mod = [k for k, d in enumerate(datasets) if data_kind(d) == "moduli"]
    cat = lambda parts, dtype=float: np.concatenate(parts) if parts else np.zeros(0, dtype=dtype)  # noqa: E731
    time = time_layout(datasets, point_group, nodes)
    y_t, w_t = observed(datasets, time) if time is not None else (np.zeros(0), np.zeros(0))
    return dict(
        omega=2 * np.pi * cat([datasets[k].frequency_hz for k in mod]),
        dataset_index=cat([np.full(datasets[k].n, k) for k in mod], int),
        group_index=cat([np.asarray(point_group[k]) for k in mod], int),
        y_obs=np.concatenate([np.log10(cat([datasets[k].G_storage for k in mod])),
                              np.log10(cat([datasets[k].G_loss for k in mod])), y_t]),
        weights=np.concatenate([cat([datasets[k].weights_storage for k in mod]),
                                cat([datasets[k].weights_loss for k in mod]), w_t]),
        time=time)


def modulus_scales(datasets) -> tuple[float, float, float]:
    """``(G, ω_m, G'')``: the median modulus (Pa), the geometric mean angular frequency (rad/s) and the median loss
    modulus (Pa) of the data, what default bounds scale with; a time point at t counts as a modulus (1/J(t) or G(t))
    at ω = 1/t, and its loss modulus as that modulus (time data do not separate them)."""
    G = np.concatenate([1.0 / d.compliance if d.kind == "creep" else d.modulus if d.kind == "relaxation"
                        else d.G_storage for d in datasets])
    w = np.concatenate([1.0 / d.time_s if d.kind in TIME_KINDS else 2 * np.pi * d.frequency_hz for d in datasets])
    loss = [d.G_loss for d in datasets if data_kind(d) == "moduli"]
    G_loss = float(np.median(np.concatenate(loss))) if loss else float(np.median(G))
    return float(np.median(G)), float(np.exp(np.mean(np.log(w)))), G_loss

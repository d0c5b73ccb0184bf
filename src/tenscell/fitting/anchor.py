"""The prestress anchor: a fit whose physical prestress σ is held to the measured one.

In the fits' parametrization (:func:`tenscell.fitting.parameters` ``_prestress_layout``) the model prestress on the
reference cell is ``P = s·p`` (N) for a measured prestress p (Pa), with one scale s (m²) for every data set. The
structure's physical prestress (:mod:`tenscell.model.prestress`: the mean normal stress of the tendons' virial
stress) is ``σ = σ_P·P`` with ``σ_P`` its value per unit P (Pa/N), so

``σ = p  ⇔  s = s_σ := 1/σ_P``  (m²).

An :class:`Anchor` holds σ within a factor f of the measured prestress: the bounds ``s ∈ [s_σ/f, s_σ·f]``
(``Anchor(1.5)``, the default of ``tenscell fit --anchored``), or equal to it: s fixed at ``s_σ``
(``Anchor.exact()``, ``--anchored exact``). A model whose strut length L is a parameter (the paper's Voigt cell)
has the exact gauge ``(P, EA, c, L) → (λ²P, λ²EA, λc, λL)`` and ``σ ∝ P/L²``: the anchor holds L at the
reference cell's (the gauge loses nothing), or, when the caller fixes L, scales the window by ``(L/L_ref)²``.

Why ×/÷1.5 by default (``docs/conventions.md``, "Physical prestress"): a traction-based prestress is the stress
the substrate balances, not all the tension the filaments carry (in maximally activated airway smooth muscle cells
the microtubules balance about 13 % of it: Stamenović et al. 2002, Cell prestress II), its volume rests on an
assumed cell height, and the model's tendons are not isotropically stressed (the paper cell's normal stresses
range over 0.82–1.35 × their mean). Together these make the measured and the model's prestress the same quantity
to within about half again, not to within a few per cent; a factor of 1.5 says so, ``exact`` tests the limit.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.prestress import PRESTRESS_CONVENTION, virial_prestress

__all__ = ["Anchor", "DEFAULT_FACTOR", "prestress_ratio", "sigma_per_model_prestress", "anchor_of", "parse_anchor"]

#: σ held within ×/÷ this factor of the measured prestress unless told otherwise (`tenscell fit --anchored`)
DEFAULT_FACTOR = 1.5
#: largest factor an anchor takes (beyond it the window no longer anchors anything: the gauge window is 10⁴ wide)
MAX_FACTOR = 100.0
#: two anchors' windows, or a fit's bounds and an anchor's, agree within this (relative)
_RTOL = 1e-9


@dataclass(frozen=True)
class Anchor:
    """σ held within ``×/÷ factor`` of the measured prestress (``factor == 1``: held equal).

    Attributes
    ----------
    factor : float
        ≥ 1 (dimensionless); :data:`DEFAULT_FACTOR` by default, 1 for :meth:`exact`.
    """

    factor: float = DEFAULT_FACTOR

    def __post_init__(self):
        f = self.factor
        if isinstance(f, bool) or not isinstance(f, (int, float)) or not math.isfinite(f) or not 1.0 <= f <= MAX_FACTOR:
            raise ValueError(f"Anchor: factor must be a number in [1, {MAX_FACTOR:g}] (σ held within ×/÷factor of the "
                             f"measured prestress; 1: equal), got {f!r}")
        object.__setattr__(self, "factor", float(f))

    @classmethod
    def exact(cls) -> Anchor:
        """σ held equal to the measured prestress."""
        return cls(1.0)

    @property
    def is_exact(self) -> bool:
        return self.factor == 1.0

    @property
    def label(self) -> str:
        """``"σ exact"`` or ``"σ ×/÷1.5"``."""
        return "σ exact" if self.is_exact else f"σ ×/÷{self.factor:g}"

    @property
    def words(self) -> str:
        """``"σ equal to the measured prestress"`` or ``"σ within ×/÷1.5 of the measured prestress"``."""
        return ("σ equal to the measured prestress" if self.is_exact else
                f"σ within ×/÷{self.factor:g} of the measured prestress")

    def scale(self, cell) -> float:
        """``s_σ`` (m²): the prestress scale at which σ equals the measured prestress on ``cell``."""
        return virial_prestress(cell).scale_m2

    def window(self, cell) -> tuple[float, float]:
        """``(s_σ/factor, s_σ·factor)`` (m²); a single value twice for an exact anchor."""
        s = self.scale(cell)
        return s / self.factor, s * self.factor

    def fit_options(self, cell, names=(), fixed=None) -> dict:
        """``{"bounds": ..., "fixed": ...}`` for :func:`tenscell.fitting.fit` (and ``model.problem``).

        Parameters
        ----------
        cell : Cell
            The fit's reference cell.
        names : sequence of str
            The problem's parameter names (``problem.names``): with ``"L"`` among them (the Voigt cell) L is held at
            the cell's strut length, or the window follows a given ``fixed["L"]`` as ``(L/L_ref)²``.
        fixed : dict, optional
            The caller's own fixed values (merged; ValueError if they fix ``s``).
        """
        fixed = dict(fixed or {})
        if "s" in fixed:
            raise ValueError("the anchor sets the prestress scale s itself: fixed['s'] contradicts it")
        lam2 = 1.0
        if "L" in names:
            L_ref = float(cell.strut_length)
            L = float(fixed.setdefault("L", L_ref))
            lam2 = (L / L_ref) ** 2
        lo, hi = self.window(cell)
        if self.is_exact:
            return {"bounds": {}, "fixed": {**fixed, "s": lo * lam2}}
        return {"bounds": {"s": (lo * lam2, hi * lam2)}, "fixed": fixed}

    def options_for(self, model, datasets, cell=None, *, bounds=None, fixed=None) -> dict:
        """:meth:`fit_options` for ``model`` (a name or FitModel) on ``datasets``, merged with the caller's own
        ``bounds`` and ``fixed``.

        ValueError (naming the option) when no data set states its prestress (no scale s), when the model has no
        cell, or when the caller bounds or fixes s.
        """
        from ..model.shapes import paper_cell
        from .models import get_model
        from .parameters import as_datasets

        spec = get_model(model)
        if not spec.structural:
            raise ValueError(f"model {spec.name!r} is a structure-free formula: it has no structure, so no σ to anchor")
        datasets = as_datasets(datasets)
        cell = paper_cell() if cell is None else cell  # the default of tenscell.fitting.fit
        bounds = dict(bounds or {})
        if "s" in bounds:
            raise ValueError("the anchor sets the prestress scale s itself: bounds['s'] contradicts it")
        names = spec.problem(datasets, cell).names
        if "s" not in names:
            raise ValueError("no data set states its prestress (Pa), so there is no measured prestress to anchor σ to")
        opts = self.fit_options(cell, names, fixed)
        return {"bounds": {**bounds, **opts["bounds"]} or None, "fixed": opts["fixed"] or None}

    def holds(self, ratio: float) -> bool:
        """Whether σ/measured = ``ratio`` lies within the anchor's factor."""
        return 1.0 / (self.factor * (1 + _RTOL)) <= ratio <= self.factor * (1 + _RTOL)

    def to_dict(self) -> dict:
        return {"factor": self.factor, "exact": self.is_exact, "label": self.label,
                "convention": PRESTRESS_CONVENTION}


def parse_anchor(text) -> Anchor:
    """An anchor from its command-line spelling: ``""``/None (the default factor), ``"exact"``, or a factor > 1.

    ValueError naming ``--anchored`` and its syntax otherwise.
    """
    syntax = (f"--anchored [FACTOR|exact]: σ held within ×/÷FACTOR (a number > 1, default {DEFAULT_FACTOR:g}) of the "
              "measured prestress, or equal to it")
    if text is None or str(text).strip() == "":
        return Anchor()
    word = str(text).strip()
    if word.lower() == "exact":
        return Anchor.exact()
    try:
        f = float(word)
    except ValueError:
        raise ValueError(f"--anchored {word[:40]}: not a factor; {syntax}") from None
    if not (math.isfinite(f) and 1.0 < f <= MAX_FACTOR):
        raise ValueError(f"--anchored {word[:40]}: the factor must lie in (1, {MAX_FACTOR:g}] ('exact' for 1); {syntax}")
    return Anchor(f)


def sigma_per_model_prestress(result) -> float | None:
    """σ per unit model prestress of a fit (Pa/N) on the cell its prestresses refer to; None without a cell.

    For a model whose strut length L is a parameter, the fitted cell is the reference cell scaled by ``L/L_ref``,
    and σ per unit P scales as ``(L_ref/L)²``.
    """
    cell = result.cell
    if cell is None:
        return None
    per = virial_prestress(cell).sigma_per_P
    names = result.problem.names
    if "L" in names:
        per *= (float(cell.strut_length) / float(result.value("L"))) ** 2
    return per


def prestress_ratio(result) -> tuple[float, float] | None:
    """``(min, max)`` of σ/measured over the prestresses the data state (None: no cell, or no stated prestress).

    σ is the model's physical prestress (:mod:`tenscell.model.prestress`) at each prestress group's model P.
    """
    per = sigma_per_model_prestress(result)
    if per is None:
        return None
    pr = result.problem
    measured = np.asarray(pr.group_measured, dtype=float)
    known = np.isfinite(measured)
    if not known.any():
        return None
    ratio = per * np.asarray(result.group_prestress(), dtype=float)[known] / measured[known]
    return float(ratio.min()), float(ratio.max())


def anchor_of(result) -> Anchor | None:
    """The anchor a fit was made under, read from its bounds of s (or s held fixed at ``s_σ``); None otherwise."""
    if result.cell is None or "s" not in result.problem.names:
        return None
    p = next(q for q in result.parameters if q.name == "s")
    try:
        per = sigma_per_model_prestress(result)
    except ValueError:  # a cell whose nodes span no volume has no σ
        return None
    if per is None:
        return None
    s_sigma = 1.0 / per
    if not p.vary:
        return Anchor.exact() if math.isclose(p.value, s_sigma, rel_tol=1e-6) else None
    f = math.sqrt(p.upper / p.lower)
    if 1.0 < f <= MAX_FACTOR and math.isclose(math.sqrt(p.upper * p.lower), s_sigma, rel_tol=1e-6):
        return Anchor(f)
    return None

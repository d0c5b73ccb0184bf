"""What a fit.json says about its model, checked against what it is: names of the catalog, a cell's parameters.

:func:`~tenscell.fitting.fitted.load_fit` validates every number of a fitted model (values, prestress, the
structure); the labels beside them are checked here, because an edited label changes what a report, ``show`` or a
reader believes without changing a number:

* a mechanism or formula named as one of the catalog (:data:`~tenscell.fitting.models.catalog.MECHANISMS`,
  :data:`~tenscell.fitting.models.formulas.FORMULAS`, a mechanism's ``(lumped)`` formula) must be that model: its
  law, fields and viscosity (a formula: its terms) as the catalog has them; a model laid out as one of the catalog
  must carry its name. A model of your own, under a name of your own, passes;
* the document's ``model_name`` and ``spec`` name the model it holds;
* a cell's construction parameters (``cell_parameters``) lie in their ranges (δ strictly between 0 and 90°, L a
  strut length tenscell accepts, α finite, ``intermediate_filaments`` a boolean) and, for the paper's cell, are
  those of its structure: the nodes rebuilt from α, δ, L are the stored ones.

Each refusal is a :class:`~tenscell.fitting.models.base.FitFileError` naming the field.
"""
from __future__ import annotations

import math

import numpy as np

from .._ranges import range_problem
from .models.base import FitFileError, model_from_dict

__all__ = ["check_model_labels", "check_document_labels", "check_cell_parameters"]

#: fields of a model's description that do not change what it computes (a fit may set K, the seed, its words)
_LABELS = ("name", "description", "assignments", "seed")


def _essence(spec) -> dict:
    return {k: v for k, v in spec.to_dict().items() if k not in _LABELS}


def _catalog(kind: str) -> dict:
    """The built-in models of a kind (``"mechanism"``, ``"formula"``) by name, a mechanism's lumped formula too."""
    if kind == "mechanism":
        from .models.catalog import MECHANISMS

        return dict(MECHANISMS)
    from .models.catalog import MECHANISMS
    from .models.formulas import FORMULAS, lumped_formula

    out = dict(FORMULAS)
    for m in MECHANISMS.values():
        try:
            lumped = lumped_formula(m)
        except ValueError:  # a law without a lumped formula
            continue
        out[lumped.name] = lumped
    return out


def check_model_labels(model: dict) -> None:
    """FitFileError when the ``"model"`` entry of a fit.json names a mechanism or formula of the catalog that it is
    not, or lays out one of the catalog under another name (``model.mechanism.name``, ``model.formula.name``)."""
    for kind in ("mechanism", "formula"):
        described = model.get(kind) if isinstance(model, dict) else None
        if not isinstance(described, dict):
            continue
        try:
            spec = model_from_dict(described if "class" in described else {"class": "Mechanism", **described})
        except (ValueError, TypeError):
            return  # the model's own reader names what is wrong
        catalog = _catalog(kind)
        built_in = catalog.get(spec.name)
        if built_in is not None and _essence(built_in) != _essence(spec):
            differ = sorted(k for k, v in _essence(spec).items() if _essence(built_in).get(k) != v)
            raise FitFileError(f"model.{kind}.name: {spec.name!r} is a {kind} of the catalog, but this one differs in "
                               f"{', '.join(differ)}: an edited file? (refit, or give your own {kind} a name of its own)")
        if built_in is None:
            same = [n for n, m in catalog.items() if _essence(m) == _essence(spec)]
            if same:
                raise FitFileError(f"model.{kind}.name: {spec.name!r} is not a {kind} of the catalog, but this one is "
                                   f"{same[0]!r} of the catalog: an edited name?")


def check_document_labels(doc: dict, fitted_name: str | None) -> None:
    """FitFileError when the document's ``model_name`` or ``spec.name`` is not the name of the model it holds."""
    if fitted_name is None:
        return
    for key, said in (("model_name", doc.get("model_name")),
                      ("spec.name", doc["spec"].get("name") if isinstance(doc.get("spec"), dict) else None)):
        if said is not None and said != fitted_name:
            raise FitFileError(f"{key}: {said!r}, but the fitted model is {fitted_name!r}: an edited file?")


def _number(key: str, value, lo: float, hi: float, unit: str, open_: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise FitFileError(f"model.cell_parameters.{key}: expected a finite number ({unit}), got {value!r}")
    x = float(value)
    if (x <= lo or x >= hi) if open_ else (x < lo or x > hi):
        raise FitFileError(f"model.cell_parameters.{key}: {value!r} {unit} is outside "
                           f"{'(' if open_ else '['}{lo:g}, {hi:g}{')' if open_ else ']'} {unit}")
    return x


def check_cell_parameters(parameters, structure: dict | None) -> None:
    """FitFileError when a cell's construction parameters (``model.cell_parameters``) are out of their ranges or,
    for the paper's cell, are not those of the stored structure's nodes (``model.structure``, as written)."""
    if parameters is None or structure is None:
        return
    if not isinstance(parameters, dict):
        raise FitFileError(f"model.cell_parameters: expected an object, got {type(parameters).__name__}")
    p = dict(parameters)
    for key, value in p.items():
        if isinstance(value, (bool, str)):
            continue
        if not isinstance(value, (int, float)) or not math.isfinite(value):
            raise FitFileError(f"model.cell_parameters.{key}: expected a finite number, got {value!r}")
    if "delta" in p:
        _number("delta", p["delta"], 0.0, math.pi / 2, "rad", open_=True)  # (0, 90°): the paper's declination
    if "alpha" in p:
        _number("alpha", p["alpha"], -math.inf, math.inf, "rad")
    if "L" in p:
        L = _number("L", p["L"], 0.0, math.inf, "m", open_=True)
        problem = range_problem("L", L)
        if problem is not None:
            raise FitFileError(f"model.cell_parameters.L: {problem}")
    if "intermediate_filaments" in p and not isinstance(p["intermediate_filaments"], bool):
        raise FitFileError(f"model.cell_parameters.intermediate_filaments: expected true or false, got "
                           f"{p['intermediate_filaments']!r}")
    if structure.get("name") == "paper cell" and {"alpha", "delta", "L", "intermediate_filaments"} <= set(p):
        _check_paper_nodes(p, structure)


def _check_paper_nodes(p: dict, structure: dict) -> None:
    from ..io.structure_files import structure_from_dict
    from ..model.shapes import paper_structure

    built = paper_structure(float(p["alpha"]), float(p["delta"]), float(p["L"]), p["intermediate_filaments"])
    stored = np.asarray(structure_from_dict(structure).structure.nodes, dtype=float)
    scale = max(float(np.abs(stored).max()), 1e-300)
    if built.nodes.shape != stored.shape or float(np.abs(built.nodes - stored).max()) > 1e-9 * scale:
        raise FitFileError(
            f"model.cell_parameters: alpha={math.degrees(p['alpha']):.6g}°, delta={math.degrees(p['delta']):.6g}°, "
            f"L={p['L']:g} m are not the parameters of the stored structure (its nodes are those of another paper "
            "cell): an edited file?")

"""A fitted Voigt cell: the cell at the fitted strut length, every tendon's EA and c, the prestress mapping.

Its :meth:`~FittedCell.to_dict` is the ``"model"`` entry of fit.json: the structure at the fitted L with EA, c and
the self-stress (the ``docs/structure-format.md`` object), so that it rebuilds the same cell and the same moduli to
rounding.
"""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import numpy as np

from ..._checks import positive_scalar
from ..._results import format_repr
from ...linear.linearize import LinearModel, linearize
from ...model.equilibrium import Cell, equilibrate
from .base import FitFileError, FittedModel, cell_from_dict, cell_to_dict, model_from_dict, prestress_from

__all__ = ["FittedCell", "scaled_cell", "MODEL_FORMAT"]

#: the ``format`` tag of a fitted Voigt cell in fit.json's ``"model"`` entry
MODEL_FORMAT = "tenscell-fitted-model"


def scaled_cell(cell: Cell, L: float) -> Cell:
    """The cell with every length scaled so that its strut length is ``L`` (m); same self-stress.

    Scaling a structure leaves its member directions, hence its self-stress
    ``T0``, unchanged; with ``(P, EA, c) -> (λ²P, λ²EA, λc)`` the scaled cell
    has the same G′, G″ (the strut-length gauge).
    """
    L = positive_scalar("L", L, "m")
    if L / cell.strut_length == 1.0:
        return cell
    return _scaled(cell, L)


# a process-wide cache of 2 cells (listed in docs/architecture.md): the fit report's uncertainties move every
# parameter but L, so the same scaled cell is asked for many times
@functools.lru_cache(maxsize=2)
def _scaled(cell: Cell, L: float) -> Cell:
    lam = L / cell.strut_length
    st = dataclasses.replace(cell.structure, nodes=np.asarray(cell.structure.nodes) * lam)
    params = dict(cell.parameters)
    if "L" in params:
        params["L"] = L
    return equilibrate(st, cell.coords.kind, T0=np.asarray(cell.T0), parameters=params)


@dataclass(frozen=True, eq=False, repr=False)
class FittedCell(FittedModel):
    """A fitted cell with Voigt tendons (the per-tendon, per-family or homogeneous fit).

    Attributes
    ----------
    cell : Cell
        At the fitted strut length.
    EA : ndarray, shape (m,)
        Tendon stiffnesses (N).
    c : ndarray, shape (m,)
        Tendon damping (N·s/m).
    P, s, prestress_pa, source
        See :class:`FittedModel`.
    tendons, damping : str or None
        How the fit laid the stiffnesses and the damping out (``"per-tendon"``, ``"per-family"``, ``"uniform"``;
        ``"uniform"``, ``"per-family"``): the :class:`~tenscell.fitting.models.voigt.VoigtModel` fitted. None in a
        fit.json written before tenscell recorded them.
    """

    cell: Cell
    EA: np.ndarray
    c: np.ndarray
    P: float | None = None
    s: float | None = None
    prestress_pa: tuple = ()
    source: str = ""
    tendons: str | None = None
    damping: str | None = None
    FORMAT = MODEL_FORMAT

    def __post_init__(self):
        self._check_prestress()
        for name in ("EA", "c"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @property
    def L(self) -> float:
        """Strut length (m)."""
        return float(self.cell.strut_length)

    @property
    def spec(self):
        """The :class:`~tenscell.fitting.models.voigt.VoigtModel` of this fit's layout (the paper's per-tendon
        stiffnesses and one damping where the fit.json does not record it)."""
        # by the registry of model classes: this module is imported by the Voigt model's own
        return model_from_dict({"class": "VoigtModel", "tendons": self.tendons or "per-tendon",
                                "damping": self.damping or "uniform"})

    def parameter_values(self) -> dict:
        """``EA`` (N) and ``c`` (N·s/m) of every tendon."""
        return {"EA": self.EA, "c": self.c}

    def tendon_law(self, assignment: int = 0):
        from ...laws import Voigt

        return Voigt(EA=self.EA, c=self.c)

    def voigt_tendons(self, P_N: float) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(self.EA), np.asarray(self.c)

    def linear(self, prestress_pa: float | None = None, *, P_N: float | None = None) -> LinearModel:
        return linearize(self.cell, P=self._resolve_P(prestress_pa, P_N), EA=self.EA, c=self.c)

    def moduli(self, f_hz, prestress_pa: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        from ...response import moduli as _moduli

        return _moduli(self.linear(prestress_pa), f_hz)

    def describe(self) -> str:
        return f"the fitted {self.cell.describe()} with Voigt tendons"

    def __repr__(self) -> str:
        pre = f"P = {self.P:.4g} N" if self.s is None else f"s = {self.s:.4g} m² (P = s × prestress in Pa)"
        return format_repr(
            "FittedCell",
            f"{self.cell.describe()}",
            f"EA {self.EA.min():.3g} .. {self.EA.max():.3g} N, c {self.c.min():.3g} .. {self.c.max():.3g} N·s/m, "
            + pre,
        )

    def to_dict(self) -> dict:
        """JSON-ready description that :func:`fitted_from_dict` turns back into the same model (floats exact)."""
        return {"format": MODEL_FORMAT, **cell_to_dict(self.cell, EA=self.EA, c=self.c), "strut_length_m": self.L,
                **self._prestress_fields(), "tendons": self.tendons, "damping": self.damping}

    @classmethod
    def from_dict(cls, obj: dict) -> FittedCell:
        cell, sf = cell_from_dict(obj)
        if sf.EA is None or sf.c is None:
            raise FitFileError("model.structure: the fitted cell's tendons have no EA or c")
        layout: dict[str, str | None] = {}
        for key, allowed in (("tendons", ("per-tendon", "per-family", "uniform")), ("damping", ("uniform", "per-family"))):
            value = obj.get(key)  # absent from a fit.json written before tenscell recorded the layout
            if value is not None and value not in allowed:
                raise FitFileError(f"model.{key}: one of {', '.join(allowed)}, got {value!r}")
            layout[key] = value
        return cls(cell=cell, EA=sf.EA, c=sf.c, tendons=layout["tendons"], damping=layout["damping"],
                   **prestress_from(obj))

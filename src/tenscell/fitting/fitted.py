"""A fitted cell is a model like any other: the cell at the fitted strut length, its linear model, fit.json.

:class:`FittedModel` holds what a fit determined — the cell scaled to the fitted
strut length L, every tendon's EA and c, and the prestress (the model
prestress P in N, or the scale s in m² that turns a measured prestress in Pa
into P) — and gives the :class:`~tenscell.linear.linearize.LinearModel` that
creep, relaxation, simulation, sensitivity and ``show`` take. Its
:meth:`~FittedModel.to_dict` is the ``"model"`` entry of ``fit.json``: the
structure at the fitted L with EA, c and the self-stress (the
``docs/structure-format.md`` object), so that :func:`load_fit` rebuilds the
same cell and the same moduli to rounding.
"""
from __future__ import annotations

import dataclasses
import functools
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._checks import positive_scalar
from .._results import format_repr
from ..linear.linearize import LinearModel, linearize
from ..model.equilibrium import Cell, equilibrate
from ..response import moduli as _moduli

__all__ = ["FittedModel", "scaled_cell", "load_fit", "PredictedCreep", "predicted_creep", "MODEL_FORMAT"]

#: the ``format`` tag of fit.json's ``"model"`` entry
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


@functools.lru_cache(maxsize=2)  # the fit report's uncertainties move every parameter but L: one cell, many times
def _scaled(cell: Cell, L: float) -> Cell:
    lam = L / cell.strut_length
    st = dataclasses.replace(cell.structure, nodes=np.asarray(cell.structure.nodes) * lam)
    params = dict(cell.parameters)
    if "L" in params:
        params["L"] = L
    return equilibrate(st, cell.coords.kind, T0=np.asarray(cell.T0), parameters=params)


@dataclass(frozen=True, eq=False, repr=False)
class FittedModel:
    """The fitted cell and its tendon properties.

    Attributes
    ----------
    cell : Cell
        At the fitted strut length.
    EA : ndarray, shape (m,)
        Tendon stiffnesses (N).
    c : ndarray, shape (m,)
        Tendon damping (N·s/m).
    P : float or None
        Model prestress (N) when the data stated no prestress.
    s : float or None
        Prestress scale (m²): the model prestress is ``s × prestress (Pa)``.
    prestress_pa : tuple of float
        The measured (or fitted) prestresses of the data (Pa), when ``s`` is used.
    source : str
        What was fitted (for messages).
    """

    cell: Cell
    EA: np.ndarray
    c: np.ndarray
    P: float | None = None
    s: float | None = None
    prestress_pa: tuple = ()
    source: str = ""

    def __post_init__(self):
        if (self.P is None) == (self.s is None):
            raise ValueError("a fitted model has either a prestress P (N) or a prestress scale s (m²), not both")
        for name in ("EA", "c"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        object.__setattr__(self, "prestress_pa", tuple(float(x) for x in self.prestress_pa))

    @property
    def L(self) -> float:
        """Strut length (m)."""
        return float(self.cell.strut_length)

    @property
    def default_prestress_pa(self) -> float | None:
        """The median measured prestress (Pa) when the model uses ``s``; None otherwise."""
        return float(np.median(self.prestress_pa)) if self.s is not None and self.prestress_pa else None

    def prestress(self, prestress_pa: float | None = None) -> float:
        """Model prestress P (N): the fitted P, or ``s × prestress_pa`` (default the median measured one)."""
        if self.s is None:
            if prestress_pa is not None:
                raise ValueError("this fit has a fitted prestress P (N); prestress_pa applies to fits with a "
                                 "measured prestress (a prestress scale s)")
            assert self.P is not None  # a fit without a prestress scale fits P itself
            return float(self.P)
        if prestress_pa is None:
            prestress_pa = self.default_prestress_pa
            if prestress_pa is None:
                raise ValueError("prestress_pa (Pa) is required: the fit scales measured prestresses by s")
        return float(self.s) * positive_scalar("prestress_pa", prestress_pa, "Pa")

    def linear(self, prestress_pa: float | None = None, *, P_N: float | None = None) -> LinearModel:
        """The linear model at the fitted parameters (see :meth:`prestress`), or at model prestress ``P_N`` (N)."""
        P = self.prestress(prestress_pa) if P_N is None else positive_scalar("P_N", P_N, "N")
        return linearize(self.cell, P=P, EA=self.EA, c=self.c)

    def moduli(self, f_hz, prestress_pa: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """G′, G″ (Pa) at frequencies ``f_hz`` (Hz) through the core pipeline."""
        return _moduli(self.linear(prestress_pa), f_hz)

    def __repr__(self) -> str:
        pre = f"P = {self.P:.4g} N" if self.s is None else f"s = {self.s:.4g} m² (P = s × prestress in Pa)"
        return format_repr(
            "FittedModel",
            f"{self.cell.describe()}",
            f"EA {self.EA.min():.3g} .. {self.EA.max():.3g} N, c {self.c.min():.3g} .. {self.c.max():.3g} N·s/m, "
            + pre,
        )

    # -- fit.json ---------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """JSON-ready description that :meth:`from_dict` turns back into the same model (floats exact)."""
        return {
            "format": MODEL_FORMAT,
            **cell_to_dict(self.cell, EA=self.EA, c=self.c),
            "strut_length_m": self.L,
            "P_N": self.P,
            "s_m2": self.s,
            "prestress_Pa": list(self.prestress_pa),
            "source": self.source,
        }

    @classmethod
    def from_dict(cls, obj: dict) -> "FittedModel":
        """Rebuild from :meth:`to_dict` (e.g. ``json.load(fit.json)["model"]``)."""
        if not isinstance(obj, dict) or obj.get("format") != MODEL_FORMAT:
            raise ValueError(f"not a fitted model (expected an object with format {MODEL_FORMAT!r})")
        cell, sf = cell_from_dict(obj)
        return cls(cell=cell, EA=sf.EA, c=sf.c, P=obj.get("P_N"), s=obj.get("s_m2"),
                   prestress_pa=tuple(obj.get("prestress_Pa") or ()), source=str(obj.get("source", "")))


def cell_to_dict(cell: Cell, **member_values) -> dict:
    """The JSON entries that rebuild ``cell`` (:func:`cell_from_dict`): its structure file with ``T0``
    (and any per-member values such as ``EA``, ``c``), its parametrization and its construction parameters."""
    from ..io.structure_files import structure_to_dict

    return {"structure": structure_to_dict(cell.structure, T0=cell.T0, **member_values),
            "parametrization": cell.coords.kind,
            "cell_parameters": {k: (v if isinstance(v, (bool, str)) else float(v)) for k, v in cell.parameters.items()}}


def cell_from_dict(obj: dict):
    """``(cell, structure_file)`` from the entries :func:`cell_to_dict` wrote (the file keeps its member values)."""
    from ..io.structure_files import structure_from_dict

    sf = structure_from_dict(obj["structure"])
    cell = equilibrate(sf.structure, obj.get("parametrization", "angles"), T0=sf.T0,
                       parameters=obj.get("cell_parameters") or {})
    return cell, sf


def load_fit(path) -> FittedModel:
    """The fitted model stored in a ``fit.json`` written by ``tenscell fit`` (its ``"model"`` entry).

    Raises
    ------
    ValueError
        If the file is not JSON or has no fitted model; the message names the file.
    """
    path = Path(path)
    try:
        obj = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        raise ValueError(f"--from-fit {path}: cannot read the file ({err})") from None
    except json.JSONDecodeError as err:
        raise ValueError(f"--from-fit {path}: not valid JSON (line {err.lineno}: {err.msg})") from None
    model = obj.get("model") if isinstance(obj, dict) else None
    if model is None:
        raise ValueError(f"--from-fit {path}: no fitted model in the file (a fit.json written by `tenscell fit` "
                         "has a \"model\" entry)")
    try:
        return FittedModel.from_dict(model)
    except (KeyError, TypeError, ValueError) as err:
        raise ValueError(f"--from-fit {path}: the fitted model cannot be rebuilt: {err}") from None


# ---------------------------------------------------------------------------------------
# predicted creep of the fitted cell
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class PredictedCreep:
    """Creep compliance of a fitted cell and its power-law exponent over a window.

    Attributes
    ----------
    t : ndarray, shape (k,)
        Times after the stress step (s).
    J : ndarray, shape (k,)
        Creep compliance (1/Pa): the model's J(t)·2L.
    exponent : ndarray, shape (k,)
        Local exponent ``d ln J/d ln t``.
    alpha : float
        Exponent of the straight-line fit of ln J against ln t over the window.
    A : float
        ``J`` at t = 1 s of that fit (1/Pa).
    rms_log : float
        RMS of the fit's ln residuals.
    window : (float, float)
        The window (s).
    prestress_N : float
    """

    t: np.ndarray
    J: np.ndarray
    exponent: np.ndarray
    alpha: float
    A: float
    rms_log: float
    window: tuple
    prestress_N: float

    def __repr__(self) -> str:
        return format_repr("PredictedCreep", f"J(t) ~ {self.A:.4g}·t^{self.alpha:.4f} 1/Pa over "
                                             f"{self.window[0]:g}..{self.window[1]:g} s (rms ln {self.rms_log:.2g})")

    def to_dict(self) -> dict:
        return {"window_s": list(self.window), "alpha": self.alpha, "A_per_Pa": self.A, "rms_log": self.rms_log,
                "local_exponent_range": [float(self.exponent.min()), float(self.exponent.max())],
                "prestress_N": self.prestress_N, "time_s": self.t.tolist(), "creep_compliance_per_Pa": self.J.tolist()}

    def to_dataframe(self):
        from .._results import dataframe

        return dataframe({"time_s": self.t, "creep_compliance_per_Pa": self.J, "local_exponent": self.exponent},
                         {"alpha": self.alpha, "window_s": self.window})


def predicted_creep(lin: LinearModel, t_min: float = 0.1, t_max: float = 10.0, n: int = 41) -> PredictedCreep:
    """Creep compliance of a linear model on ``n`` log-spaced times over [t_min, t_max] s and its exponent."""
    from ..timedomain import creep_spectrum, fit_power_law

    t_min = positive_scalar("t_min", t_min, "s")
    t_max = positive_scalar("t_max", t_max, "s")
    if not t_min < t_max:
        raise ValueError(f"t_min must be below t_max, got {t_min:g}, {t_max:g} s")
    t = np.logspace(math.log10(t_min), math.log10(t_max), int(n))
    spec = creep_spectrum(lin)
    J = spec.compliance(t) * (2.0 * spec.L)
    pl = fit_power_law(t, J)
    return PredictedCreep(t=t, J=J, exponent=spec.exponent(t), alpha=pl.alpha, A=pl.A, rms_log=pl.rms_log,
                          window=(t_min, t_max), prestress_N=float(lin.P))

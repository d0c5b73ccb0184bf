"""Exchange with rheojax's ``RheoData``, optional (grids go to xarray by ``FrequencyResponse.to_xarray()``).

rheojax
    :func:`to_rheojax` and :func:`from_rheojax` convert measured data to and
    from rheojax's ``RheoData`` by duck typing (rheojax needs Python ≥ 3.12
    and stays optional): an oscillation sweep is ``x`` = ω (rad/s), ``y`` =
    G′ + iG″ (Pa), ``domain="frequency"``, test mode ``"oscillation"``; a creep
    curve ``x`` = t (s), ``y`` = J(t) (1/Pa), ``domain="time"``, test mode
    ``"creep"``. Units a ``RheoData`` states (``x_units``, ``y_units``) are
    converted by the same tables as every other import
    (:mod:`tenscell.io.importers`), and the result passes the same checks.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._optional import require
from .creep_data import CreepData
from .data import DataError, RheologyData
from .importers import from_dataframe

__all__ = ["to_rheojax", "from_rheojax"]


def _rheodata_class():
    return require("rheojax.core.data").RheoData


def to_rheojax(data: RheologyData | CreepData, cls: Any = None) -> Any:
    """Measured data as a rheojax ``RheoData`` (or as ``cls``, any class with its constructor).

    Parameters
    ----------
    data : RheologyData or CreepData
        A frequency sweep (one prestress, or none) or a creep curve.
    cls : type, optional
        The class to build; default ``rheojax.core.data.RheoData``.

    Returns
    -------
    RheoData
        ``metadata`` carries the source, tenscell's comments and the stated prestress (Pa), if any.
    """
    cls = _rheodata_class() if cls is None else cls
    meta: dict[str, Any] = {"source": data.source, "comments": list(data.comments), "exported_by": "tenscell"}
    if data.prestress is not None:
        values = np.unique(data.prestress)
        if values.size > 1:
            raise DataError(f"{data.source}: a prestress sweep has no RheoData form (one curve per RheoData); "
                            "export one prestress at a time")
        meta["prestress_Pa"] = float(values[0])
    if isinstance(data, CreepData):
        return cls(x=np.array(data.time_s), y=np.array(data.compliance), x_units="s", y_units="1/Pa", domain="time",
                   metadata=meta, initial_test_mode="creep")
    order = np.argsort(data.frequency_hz)
    omega = 2 * math.pi * np.asarray(data.frequency_hz)[order]
    G = (np.asarray(data.G_storage) + 1j * np.asarray(data.G_loss))[order]
    return cls(x=omega, y=G, x_units="rad/s", y_units="Pa", domain="frequency", metadata=meta,
               initial_test_mode="oscillation")


def from_rheojax(obj: Any, *, source: str | None = None, **units: Any) -> RheologyData | CreepData:
    """Measured data from a rheojax ``RheoData`` (anything with ``x``, ``y``, ``x_units``, ``y_units``, ``domain``).

    Oscillation data (``domain="frequency"``): ``y`` complex G* (or an
    ``(n, 2)`` array of G′, G″); ``x_units`` rad/s or Hz, ``y_units`` Pa, kPa
    or MPa. Creep data (``domain="time"`` with test mode ``"creep"``): ``y``
    = J(t), ``x_units`` s, ms or min, ``y_units`` 1/Pa, 1/kPa or 1/MPa.
    ``**units`` (ColumnMap unit fields, e.g. ``frequency_unit="rad/s"``) state
    what the object leaves as None. A prestress in ``metadata["prestress_Pa"]``
    is kept.
    """
    import pandas as pd

    for name in ("x", "y", "domain"):
        if not hasattr(obj, name):
            raise TypeError(f"from_rheojax: {type(obj).__name__} has no {name!r}; expected a rheojax RheoData")
    meta = dict(getattr(obj, "metadata", None) or {})
    src = source or str(meta.get("source") or f"<{type(obj).__name__}>")
    x = np.asarray(obj.x)
    y = np.asarray(obj.y)
    xu, yu = getattr(obj, "x_units", None), getattr(obj, "y_units", None)
    mode = meta.get("test_mode") or meta.get("detected_test_mode")
    if obj.domain == "time":
        if mode not in (None, "creep"):
            raise DataError(f"{src}: test mode {mode!r}; tenscell reads oscillation sweeps and creep curves")
        df = pd.DataFrame({_named("t", xu): x.real, _named("J", yu): y.real})
        cmap: dict[str, Any] = {"time": df.columns[0], "compliance": df.columns[1]}
    elif obj.domain == "frequency":
        Gs, Gl = (y.real, y.imag) if np.iscomplexobj(y) else (y[:, 0], y[:, 1]) if y.ndim == 2 else (None, None)
        if Gs is None:
            raise DataError(f"{src}: y holds neither complex G* nor (G', G'') columns")
        df = pd.DataFrame({_named("f", xu): x, _named("Gp", yu): Gs, _named("Gpp", yu): Gl})
        cmap = {"frequency": df.columns[0], "storage": df.columns[1], "loss": df.columns[2]}
    else:
        raise DataError(f"{src}: domain {obj.domain!r}; expected 'frequency' or 'time'")
    if "prestress_Pa" in meta:
        df["P [Pa]"] = float(meta["prestress_Pa"])
        cmap["prestress"] = "P [Pa]"
    return from_dataframe(df, {**cmap, **units}, source=src)


def _named(name: str, unit: str | None) -> str:
    """A column name carrying the unit, as the importers read it (``"f [rad/s]"``); no unit, no brackets."""
    return f"{name} [{unit}]" if unit else name

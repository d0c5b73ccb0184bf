"""Input validation shared by every stage: one clear ValueError per bad value."""
from __future__ import annotations

import numbers

import numpy as np

__all__ = ["positive_scalar", "positive_array", "finite_scalar", "MAGNITUDE"]

#: positive physical inputs must lie in [1/MAGNITUDE, MAGNITUDE] (in their SI unit): far beyond any
#: cell or instrument, and the widest window in which products and squares of a few such values (ω·c,
#: K0 = P·Kp + EA/l, |J|²) stay inside float64 instead of overflowing to inf or underflowing to 0
MAGNITUDE = 1e100


def finite_scalar(name: str, value, allowed: str = "a finite number") -> float:
    """``value`` as a float; ValueError naming ``name`` if it is not a finite real number."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.ndarray, np.generic)):
        raise ValueError(f"{name} must be {allowed}, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be {allowed}, got {value!r}") from None
    if not np.isfinite(v):
        raise ValueError(f"{name} must be {allowed}, got {v!r}")
    return v


def positive_scalar(name: str, value, unit: str = "") -> float:
    """``value`` as a float in [1/MAGNITUDE, MAGNITUDE]; ValueError naming ``name`` and what is allowed otherwise."""
    if type(value) in (float, np.float64) and 1.0 / MAGNITUDE <= value <= MAGNITUDE:  # hot loops (NaN fails)
        return value
    allowed = f"a finite number > 0{(' (' + unit + ')') if unit else ''}"
    v = finite_scalar(name, value, allowed)
    if v <= 0:
        raise ValueError(f"{name} must be {allowed}, got {v!r}")
    if not 1.0 / MAGNITUDE <= v <= MAGNITUDE:
        raise ValueError(f"{name} must lie in [{1 / MAGNITUDE:g}, {MAGNITUDE:g}]{(' ' + unit) if unit else ''} "
                         f"(beyond, float64 overflows), got {v!r}")
    return v


def positive_array(name: str, value, shape: tuple[int, ...] | None = None, unit: str = "",
                   allow_zero: bool = False) -> np.ndarray:
    """``value`` as a float array of positive entries, broadcast to ``shape`` if given."""
    # fast paths for the common clean cases, which sit on the hot path of parameter sweeps
    if shape is not None and type(value) is float and 1.0 / MAGNITUDE <= value <= MAGNITUDE:
        return np.full(shape, value)
    if (shape is None and type(value) is np.ndarray and value.dtype == np.float64 and value.size
            and (value.min() >= 0.0 if allow_zero else value.min() >= 1.0 / MAGNITUDE)
            and value.max() <= MAGNITUDE):
        return value  # NaN makes min() NaN, fails the test and takes the checked path below
    bound = ">= 0" if allow_zero else "> 0"
    allowed = f"finite numbers {bound}{(' (' + unit + ')') if unit else ''}"
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be {allowed}, got {value!r}") from None
    if shape is not None:
        if arr.ndim == 0:
            arr = np.full(shape, float(arr))
        elif arr.shape != shape:
            raise ValueError(f"{name} must be a scalar or have shape {shape}, got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError(f"{name} must not be empty")
    bad = ~np.isfinite(arr) | ((arr < 0) if allow_zero else (arr <= 0))
    if np.any(bad):
        i = int(np.flatnonzero(bad.ravel())[0])
        where = f" (entry {i})" if arr.ndim else ""
        raise ValueError(f"{name} must be {allowed}, got {arr.ravel()[i].item()!r}{where}")
    extreme = (arr > MAGNITUDE) | ((arr < 1.0 / MAGNITUDE) & ((arr != 0) if allow_zero else True))
    if np.any(extreme):
        i = int(np.flatnonzero(extreme.ravel())[0])
        where = f" (entry {i})" if arr.ndim else ""
        raise ValueError(f"{name} must lie in [{1 / MAGNITUDE:g}, {MAGNITUDE:g}]{(' ' + unit) if unit else ''}"
                         f"{' or be 0' if allow_zero else ''} (beyond, float64 overflows), "
                         f"got {arr.ravel()[i].item()!r}{where}")
    return arr

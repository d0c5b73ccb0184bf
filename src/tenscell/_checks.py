"""Input validation shared by every stage: one clear ValueError per bad value."""
from __future__ import annotations

import numbers

import numpy as np

__all__ = ["positive_scalar", "positive_array", "finite_scalar"]


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
    """``value`` as a float > 0; ValueError naming ``name`` and what is allowed otherwise."""
    allowed = f"a finite number > 0{(' (' + unit + ')') if unit else ''}"
    v = finite_scalar(name, value, allowed)
    if v <= 0:
        raise ValueError(f"{name} must be {allowed}, got {v!r}")
    return v


def positive_array(name: str, value, shape: tuple[int, ...] | None = None, unit: str = "",
                   allow_zero: bool = False) -> np.ndarray:
    """``value`` as a float array of positive entries, broadcast to ``shape`` if given."""
    # fast paths for the common clean cases, which sit on the hot path of parameter sweeps
    if shape is not None and type(value) is float and value > 0 and value != np.inf:
        return np.full(shape, value)
    if (shape is None and type(value) is np.ndarray and value.dtype == np.float64 and value.size
            and (value.min() >= 0.0 if allow_zero else value.min() > 0.0) and value.max() < np.inf):
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
    return arr

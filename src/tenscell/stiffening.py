"""A strain-stiffening filament law (the paper's future work for intermediate filaments).

Intermediate filaments are "known sources of nonlinear elastic behavior" (the
paper's discussion). tenscell models them with the exponential law

``T = (EA/b)·(exp(b·ε) − 1)``,  ``ε = l/l0 − 1``,

with small-strain stiffness ``EA`` (N) and dimensionless stiffening exponent
``b ≥ 0``. At ``b = 0`` it is the linear spring ``T = EA·ε`` of the paper's
Voigt element. Its tangent stiffness is ``dT/dl = (EA/l0)·exp(b·ε) =
(EA + b·T)/l0``: it grows linearly with the tension, the signature of
strain-stiffening biopolymer networks.

The linearization about a prestressed reference needs, per member, the rest
length that gives the reference tension (the inverse law) and the tangent
stiffness there; :func:`tangent_at_tension` returns both, and
:func:`tenscell.linear.linearize.linearize_tangent` builds the linear model from them.

Pure functions of arrays (broadcasting); this module sits at the constitutive
stage of the pipeline and imports nothing later.
"""
from __future__ import annotations

import numpy as np

__all__ = ["exponential_tension", "exponential_tangent", "exponential_rest_length", "tangent_at_tension"]


def _check(EA, b):
    EA = np.asarray(EA, dtype=float)
    b = np.asarray(b, dtype=float)
    if not np.all(np.isfinite(EA)) or np.any(EA <= 0):
        raise ValueError(f"EA (small-strain stiffness) must be finite numbers > 0 (N), got {EA!r}")
    if not np.all(np.isfinite(b)) or np.any(b < 0):
        raise ValueError(f"b (stiffening exponent) must be finite numbers >= 0 (dimensionless; 0 = linear), got {b!r}")
    return EA, b


def _expm1_over_b(b, x):
    """``(exp(b·x) − 1)/b``, equal to ``x`` at ``b = 0``."""
    safe = np.where(b > 0, b, 1.0)
    return np.where(b > 0, np.expm1(safe * x) / safe, x)


def _log1p_over_b(b, y):
    """``log(1 + b·y)/b``, equal to ``y`` at ``b = 0`` (the inverse of :func:`_expm1_over_b`)."""
    safe = np.where(b > 0, b, 1.0)
    return np.where(b > 0, np.log1p(safe * y) / safe, y)


def exponential_tension(l, l0, EA, b):
    """Tension ``T = (EA/b)(exp(b(l/l0 − 1)) − 1)`` (N); ``EA·(l/l0 − 1)`` at ``b = 0``.

    Parameters
    ----------
    l, l0 : array_like
        Length and rest length (m), > 0.
    EA : array_like
        Small-strain stiffness (N), > 0.
    b : array_like
        Stiffening exponent (dimensionless), ≥ 0.
    """
    EA, b = _check(EA, b)
    eps = np.asarray(l, dtype=float) / np.asarray(l0, dtype=float) - 1.0
    return EA * _expm1_over_b(b, eps)


def exponential_tangent(l, l0, EA, b):
    """Tangent stiffness ``dT/dl = (EA/l0)·exp(b(l/l0 − 1))`` (N/m)."""
    EA, b = _check(EA, b)
    l0 = np.asarray(l0, dtype=float)
    eps = np.asarray(l, dtype=float) / l0 - 1.0
    return EA / l0 * np.exp(b * eps)


def exponential_rest_length(l, T, EA, b):
    """Rest length (m) at which the law gives tension ``T`` (N) at length ``l`` (m).

    ``ε = log(1 + b·T/EA)/b`` (``T/EA`` at ``b = 0``) and ``l0 = l/(1 + ε)``.

    Raises
    ------
    ValueError
        If ``T ≤ −EA/b`` (the law cannot compress that far) or the strain
        would be ≤ −1.
    """
    EA, b = _check(EA, b)
    y = np.asarray(T, dtype=float) / EA
    if np.any(1.0 + b * y <= 0):
        raise ValueError("tension T is below -EA/b, which the exponential law never reaches")
    eps = _log1p_over_b(b, y)
    if np.any(eps <= -1.0):
        raise ValueError("the requested tension needs a strain <= -1 (a non-positive rest length)")
    return np.asarray(l, dtype=float) / (1.0 + eps)


def tangent_at_tension(l, T, EA, b):
    """Rest length (m) and tangent stiffness (N/m) of members at length ``l`` carrying ``T``.

    ``dT/dl = (EA + b·T)/l0``; at ``b = 0`` this is ``(EA + T)/l``, the
    stiffness the paper's Eq. (11) rest lengths give a Voigt spring.

    Returns
    -------
    l0 : ndarray
        Rest lengths (m).
    k : ndarray
        Tangent stiffnesses (N/m).
    """
    EA, b = _check(EA, b)
    l0 = exponential_rest_length(l, T, EA, b)
    return l0, (EA + b * np.asarray(T, dtype=float)) / l0

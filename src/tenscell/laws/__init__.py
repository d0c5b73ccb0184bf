"""Tendon laws: the one source of tension, tangent stiffness and tangent damping.

Every consumer — the linearization (:func:`tenscell.linear.linearize.linearize_law`),
the sensitivity analysis, the fitting Jacobians and the nonlinear time
integration (:mod:`tenscell.dynamics`) — asks a law object, never a formula of
its own. A law is a frozen dataclass subclassing :class:`TendonLaw`, with
per-tendon material parameters (scalars, or arrays of shape ``(m,)``) and
optional rest lengths ``l0`` (m).

Two levels
----------
*At a reference* (no rest lengths needed): a tendon of length ``l`` (m)
carrying tension ``T`` (N) at rest has the rest length that the law's inverse
gives, and from it a tangent. This is what linearization needs.

``rest_lengths(l, T)``
    rest lengths (m) at which the law carries ``T`` at length ``l`` and ``l' = 0``;
``tangent_at_rest(l, T)``
    ``(k, c)``: tangent stiffness ``k = ∂T/∂l`` (N/m) and tangent damping
    ``c = ∂T/∂l'`` (N·s/m) of the exact law at rest, with those rest lengths;
``tangent(l, T)``
    a :class:`Tangent`: ``k``, ``c`` and their derivatives with respect to
    the reference tension (at fixed parameters; the rest length follows) and
    to each of the law's own parameters (at fixed tension). With ``T = P·T0``
    the prestress derivative is ``∂k/∂P = (∂k/∂T)·T0`` (:meth:`Tangent.dP`).

*In motion* (rest lengths set, e.g. by :meth:`TendonLaw.at_prestress`):

``tension(l, ldot)``
    tension ``T`` (N) for lengths ``l`` (m) and rates ``ldot = dl/dt`` (m/s);
``derivatives(l, ldot)``
    ``(T, ∂T/∂l, ∂T/∂l')`` in (N, N/m, N·s/m);
``elastic(l)``
    the rate-independent part ``T(l, 0)`` (N);
``stiffness_at_rest(l)``, ``damping_at_rest(l)``
    ``∂T/∂l`` and ``∂T/∂l'`` at ``l' = 0`` (the latter of the *exact* law;
    :class:`LinearizationError` when it does not exist);
``rate_linear``
    ``True`` when ``T`` is affine in ``l'``.

The laws give the constitutive tension only; that a tendon is a cable (goes
slack rather than carry compression) is handled by :mod:`tenscell.dynamics`.

Laws
----
:class:`Voigt`
    the paper's Eq. (1), ``T = EA(l/l0 − 1) + c·l'``; rest lengths Eq. (11).
:class:`PowerDashpot`
    ``T = EA(l/l0 − 1) + c·sign(l')|l'|^β`` (the paper's discussion), smoothed near ``l' = 0``.
:class:`StiffeningFilament`
    ``T = (EA/b)(exp(b·ε) − 1) + c·l'``, ``ε = l/l0 − 1``: strain-stiffening
    intermediate filaments (the paper's future work); ``b = 0`` is Voigt.
:class:`LinearSpring`
    ``T = k(l − l0) + c·l'``: a spring given by its stiffness in N/m (the law
    behind :func:`tenscell.linear.linearize.linearize_tangent`).
:class:`Maxwell`, :class:`StandardLinearSolid`, :class:`Springpot`, :class:`TensionSpringpot`
    tendons with dynamics of their own (filament turnover, a Zener solid, a
    fractional element, a passive and a tension-scaled active fractional element): ``dynamic = True``, an exact frequency-dependent
    tangent ``complex_stiffness(l, T, ω)`` and its derivatives, no constant
    (k, c) (:mod:`tenscell.laws.viscoelastic`).
:class:`CompositeLaw`
    different laws on different tendons (e.g. Voigt actin and stiffening
    IFs); :func:`family_laws` builds one from tendon families.

Writing a law
-------------
Subclass :class:`TendonLaw` as a frozen dataclass whose fields are the
per-tendon parameters named in ``parameters`` (name, unit, whether 0 is
allowed) plus ``l0: object = None``; call ``self._validate()`` in
``__post_init__``; implement ``tension``, ``derivatives`` and
``rest_lengths``. Everything else has a default: :meth:`TendonLaw.tangent`
then differentiates by central differences through your law (override it
with exact derivatives, as the built-in laws do, for exact elasticities and
fitting Jacobians; ``tests/test_laws.py`` checks any law against finite
differences). The law then works in every consumer.

Layout
------
``base`` (the protocol: :class:`TendonLaw`, :class:`Tangent`, :class:`Parameter`),
``springs`` (Voigt, power-law dashpot, linear spring), ``filaments`` (stiffening
filaments), ``viscoelastic`` (laws with internal dynamics), ``composite`` (per-family laws), ``constructors`` (the paper's placements at
a prestress). A new law is one new module here, re-exported below.
"""
from __future__ import annotations

from .base import DEFAULT_REALIZATION_TOL, DynamicLawError, LinearizationError, Parameter, Realization, Tangent, TendonLaw
from .composite import CompositeLaw, family_laws
from .constructors import power_dashpot_law, rest_lengths, stiffening_law, voigt_law
from .filaments import StiffeningFilament
from .springs import DEFAULT_VELOCITY_SCALE, LinearSpring, PowerDashpot, Voigt
from .viscoelastic import (DEFAULT_REALIZATION_BAND_HZ, SPRINGPOT_TIME, Maxwell, Springpot, StandardLinearSolid,
                           TensionSpringpot, springpot_prony)


__all__ = [
    "LAWS",
    "TendonLaw",
    "Parameter",
    "Tangent",
    "Voigt",
    "PowerDashpot",
    "StiffeningFilament",
    "LinearSpring",
    "Maxwell",
    "StandardLinearSolid",
    "Springpot",
    "TensionSpringpot",
    "SPRINGPOT_TIME",
    "Realization",
    "springpot_prony",
    "DEFAULT_REALIZATION_TOL",
    "DEFAULT_REALIZATION_BAND_HZ",
    "DynamicLawError",
    "CompositeLaw",
    "family_laws",
    "LinearizationError",
    "rest_lengths",
    "voigt_law",
    "power_dashpot_law",
    "stiffening_law",
    "DEFAULT_VELOCITY_SCALE",
]

#: every law class by name (what a :class:`~tenscell.fitting.models.mechanism.Mechanism` names in ``law``)
LAWS: dict[str, type[TendonLaw]] = {cls.__name__: cls for cls in (Voigt, PowerDashpot, StiffeningFilament, LinearSpring,
                                                                  Maxwell, StandardLinearSolid, Springpot,
                                                                  TensionSpringpot, CompositeLaw)}

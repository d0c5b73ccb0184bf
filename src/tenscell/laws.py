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
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar, Mapping, NamedTuple, Self

import numpy as np

from ._checks import finite_scalar, positive_array, positive_scalar
from ._results import dataframe, format_repr
from .model.equilibrium import Cell

__all__ = [
    "TendonLaw",
    "Parameter",
    "Tangent",
    "Voigt",
    "PowerDashpot",
    "StiffeningFilament",
    "LinearSpring",
    "CompositeLaw",
    "family_laws",
    "LinearizationError",
    "rest_lengths",
    "voigt_law",
    "power_dashpot_law",
    "stiffening_law",
    "DEFAULT_VELOCITY_SCALE",
]

#: default smoothing velocity ε of :class:`PowerDashpot` (m/s)
DEFAULT_VELOCITY_SCALE = 1e-3


class LinearizationError(ValueError):
    """The tendon law has no linearization at rest (its rate derivative at l' = 0 is infinite)."""


class Parameter(NamedTuple):
    """A per-tendon parameter of a law: its field name, unit, and whether 0 is allowed (else > 0)."""

    name: str
    unit: str
    allow_zero: bool = False


# ---- tangents ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class Tangent:
    """Tangent stiffness and damping of each tendon at a reference, with their derivatives.

    Attributes
    ----------
    l, T : ndarray, shape (m,)
        Reference lengths (m) and tensions (N) the tangent was taken at.
    k : ndarray, shape (m,)
        Tangent stiffness ``∂T/∂l`` at rest (N/m).
    c : ndarray, shape (m,)
        Tangent damping ``∂T/∂l'`` at rest (N·s/m).
    dk_dT, dc_dT : ndarray, shape (m,)
        ``∂k_j/∂T_j`` (1/m) and ``∂c_j/∂T_j`` (s/m) at fixed law parameters
        (the rest length follows the tension).
    names : tuple of str
        The law's per-tendon parameters, e.g. ``("EA", "c")``.
    units : tuple of str
        Their units.
    values : ndarray, shape (p, m)
        Parameter values; NaN where tendon ``j`` has no such parameter (a composite law).
    dk, dc : ndarray, shape (p, m)
        ``∂k_j/∂θ_pj`` and ``∂c_j/∂θ_pj`` at fixed tension (0 where absent).
        A tendon's tangent depends on its own parameters only.
    """

    l: np.ndarray
    T: np.ndarray
    k: np.ndarray
    c: np.ndarray
    dk_dT: np.ndarray
    dc_dT: np.ndarray
    names: tuple
    units: tuple
    values: np.ndarray
    dk: np.ndarray
    dc: np.ndarray

    @property
    def m(self) -> int:
        """Number of tendons."""
        return self.k.size

    @property
    def present(self) -> np.ndarray:
        """``values`` is defined, shape (p, m)."""
        return ~np.isnan(self.values)

    def dP(self, T0) -> tuple[np.ndarray, np.ndarray]:
        """``(∂k/∂P, ∂c/∂P)`` for tensions ``T = P·T0`` (N/m per N, N·s/m per N), shape (m,) each."""
        T0 = np.asarray(T0, dtype=float)
        return self.dk_dT * T0, self.dc_dT * T0

    def row(self, name: str) -> int:
        """Index of a parameter in ``names``."""
        try:
            return self.names.index(name)
        except ValueError:
            raise ValueError(f"the law has no parameter {name!r}; it has {', '.join(self.names)}") from None

    def __repr__(self) -> str:
        return format_repr(
            f"Tangent of {self.m} tendons",
            f"k = {self.k.min():.4g}…{self.k.max():.4g} N/m, c = {self.c.min():.4g}…{self.c.max():.4g} N·s/m",
            f"parameters: {', '.join(f'{n} ({u})' for n, u in zip(self.names, self.units))}",
        )

    def to_dataframe(self):
        """One row per tendon: length, tension, k, c, ∂k/∂T and each parameter with ∂k, ∂c."""
        cols = {"tendon": np.arange(self.m), "length_m": self.l, "tension_N": self.T,
                "k_N_per_m": self.k, "c_Ns_per_m": self.c, "dk_dT_per_m": self.dk_dT, "dc_dT_s_per_m": self.dc_dT}
        for i, (n, u) in enumerate(zip(self.names, self.units)):
            cols[f"{n}_{_unit_tag(u)}"] = self.values[i]
            cols[f"dk_d{n}"] = self.dk[i]
            cols[f"dc_d{n}"] = self.dc[i]
        return dataframe(cols)


def _unit_tag(unit: str) -> str:
    return {"N": "N", "N·s/m": "Ns_per_m", "N/m": "N_per_m", "": "1", "N·(s/m)^beta": "N_sbeta_per_mbeta"}.get(
        unit, unit.replace("·", "").replace("/", "_per_") or "1")


# ---- the base class -----------------------------------------------------------------------------------
class TendonLaw:
    """Base class of every tendon law (see the module docstring for the interface).

    Subclasses are frozen dataclasses whose per-tendon parameter fields are
    listed in :attr:`parameters`, plus ``l0`` (rest lengths, m, or None
    until the law is placed at a reference).
    """

    #: the per-tendon parameters, in order (their fields hold scalars or (m,) arrays)
    parameters: ClassVar[tuple[Parameter, ...]] = ()
    rate_linear: ClassVar[bool] = True
    l0: Any = None

    # -- to implement -----------------------------------------------------------------------------
    def tension(self, l, ldot):
        """Tension (N) at lengths ``l`` (m) and rates ``ldot`` (m/s); needs ``l0``."""
        raise NotImplementedError

    def derivatives(self, l, ldot):
        """``(T, ∂T/∂l, ∂T/∂l')`` in (N, N/m, N·s/m); needs ``l0``."""
        raise NotImplementedError

    def rest_lengths(self, l, T):
        """Rest lengths (m) at which the law carries ``T`` (N) at length ``l`` (m) and ``l' = 0``."""
        raise NotImplementedError

    # -- validation and placement -----------------------------------------------------------------
    def _validate(self) -> None:
        """Check every parameter (finite, > 0 or ≥ 0) and ``l0``; store read-only float arrays."""
        shape = None
        specs = list(self.parameters) + ([Parameter("l0", "m")] if self.l0 is not None else [])
        for p in specs:
            arr = positive_array(f"{p.name} (rest length)" if p.name == "l0" else p.name, getattr(self, p.name),
                                 None, p.unit, allow_zero=p.allow_zero)
            if arr.ndim > 1:
                raise ValueError(f"{p.name} must be a scalar or a 1-D array (one value per tendon), got shape {arr.shape}")
            if arr.ndim == 1:
                if shape is not None and arr.shape != shape:
                    raise ValueError(f"{p.name} has {arr.shape[0]} entries but another parameter has {shape[0]}")
                shape = arr.shape
            arr = np.array(arr, dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, p.name, arr)
        if shape is not None:  # one value per tendon everywhere, so that m and indexing are unambiguous
            for p in specs:
                arr = getattr(self, p.name)
                if arr.ndim == 0:
                    arr = np.full(shape, float(arr))
                    arr.setflags(write=False)
                    object.__setattr__(self, p.name, arr)

    @property
    def m(self) -> int | None:
        """Number of tendons (None while every parameter is a scalar and no rest lengths are set)."""
        for p in ([Parameter("l0", "m")] if self.l0 is not None else []) + list(self.parameters):
            a = getattr(self, p.name)
            if np.ndim(a) == 1:
                return int(np.shape(a)[0])
        return None

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the per-tendon parameters."""
        return tuple(p.name for p in self.parameters)

    def _l0(self) -> np.ndarray:
        if self.l0 is None:
            raise ValueError(
                f"this {type(self).__name__} law has no rest lengths yet: place it at a reference with "
                "law.at_prestress(cell, P) or law.at_tension(lengths, tensions)"
            )
        return self.l0

    def with_rest_lengths(self, l0) -> Self:
        """The same law with rest lengths ``l0`` (m)."""
        return dataclasses.replace(self, l0=l0)  # type: ignore[type-var]  # every law is a dataclass

    def _placed(self, l0) -> Self:
        """The same law with rest lengths ``l0`` already known to be valid (no re-validation)."""
        obj = object.__new__(type(self))
        obj.__dict__.update(self.__dict__)
        obj.__dict__["l0"] = np.asarray(l0, dtype=float)
        return obj

    def at_tension(self, l, T) -> Self:
        """The law with the rest lengths that give tensions ``T`` (N) at lengths ``l`` (m) at rest."""
        return self.with_rest_lengths(self.rest_lengths(l, T))

    def at_prestress(self, cell: Cell, P: float) -> Self:
        """The law placed at ``cell``'s reference with tensions ``P·T0`` (rest lengths from the inverse law)."""
        P = positive_scalar("P (prestress)", P, "N")
        m = self.m
        if m is not None and m != cell.m:
            raise ValueError(f"the tendon law has {m} tendons but the cell has {cell.m}")
        return self.at_tension(cell.lengths, P * cell.T0)

    # -- in motion: defaults --------------------------------------------------------------------------
    def elastic(self, l):
        """``T(l, 0)`` (N): the rate-independent part."""
        l = np.asarray(l, dtype=float)
        return self.tension(l, np.zeros_like(l))

    def stiffness_at_rest(self, l):
        """``∂T/∂l`` at ``l' = 0`` (N/m)."""
        l = np.asarray(l, dtype=float)
        return np.asarray(self.derivatives(l, np.zeros_like(l))[1], dtype=float)

    def damping_at_rest(self, l):
        """``∂T/∂l'`` at ``l' = 0`` of the exact law (N·s/m)."""
        l = np.asarray(l, dtype=float)
        return np.asarray(self.derivatives(l, np.zeros_like(l))[2], dtype=float)

    # -- at a reference -----------------------------------------------------------------------------
    def tangent_at_rest(self, l, T) -> tuple[np.ndarray, np.ndarray]:
        """``(k, c)``: tangent stiffness (N/m) and damping (N·s/m) at rest, lengths ``l`` (m), tensions ``T`` (N)."""
        l = np.asarray(l, dtype=float)
        placed = self.at_tension(l, T)
        return placed.stiffness_at_rest(l), placed.damping_at_rest(l)

    def _reference(self, l, T) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(l0, k, c)`` at a reference in one pass (what a linearization needs)."""
        k, c = self.tangent_at_rest(l, T)
        return self.rest_lengths(l, T), k, c

    def parameter_values(self, m: int) -> np.ndarray:
        """The parameters as an array of shape ``(p, m)``."""
        return np.array([np.broadcast_to(np.asarray(getattr(self, n), dtype=float), (m,)) for n in self.names],
                        dtype=float).reshape(len(self.names), m)

    def tangent(self, l, T) -> Tangent:
        """:class:`Tangent` with derivatives, here by central differences (built-in laws are exact).

        Steps: ``1e-5·(|T| + k·l)`` in the tension and ``1e-5·|θ|`` in each
        parameter (second-order one-sided where a parameter is 0).
        """
        l = np.asarray(l, dtype=float)
        T = np.broadcast_to(np.asarray(T, dtype=float), l.shape).copy()
        k, c = self.tangent_at_rest(l, T)
        h = 1e-5 * (np.abs(T) + np.abs(k) * l)
        kp, cp = self.tangent_at_rest(l, T + h)
        km, cm = self.tangent_at_rest(l, T - h)
        vals = self.parameter_values(l.size)
        dk, dc = np.zeros_like(vals), np.zeros_like(vals)
        for i, name in enumerate(self.names):
            v = vals[i]
            hv = 1e-5 * np.where(v != 0, np.abs(v), 1.0)

            def at(s, name=name, v=v, hv=hv):
                return dataclasses.replace(self, **{name: v + s * hv}).tangent_at_rest(l, T)

            (k1, c1) = at(1)
            if np.all(v - hv > 0):
                km1, cm1 = at(-1)
                dk[i], dc[i] = (k1 - km1) / (2 * hv), (c1 - cm1) / (2 * hv)
            else:  # a parameter at its lower bound 0: second-order forward difference
                k2, c2 = at(2)
                dk[i], dc[i] = (-3 * k + 4 * k1 - k2) / (2 * hv), (-3 * c + 4 * c1 - c2) / (2 * hv)
        return Tangent(l=l, T=T, k=k, c=c, dk_dT=(kp - km) / (2 * h), dc_dT=(cp - cm) / (2 * h), names=self.names,
                       units=tuple(p.unit for p in self.parameters), values=vals, dk=dk, dc=dc)

    def _tangent(self, l, T, k, c, dk_dT, dk: dict, dc: dict) -> Tangent:
        """Assemble an exact :class:`Tangent` from per-parameter derivative arrays (missing = 0)."""
        m = l.size
        z = np.zeros(m)
        vals = self.parameter_values(m)
        bc = lambda x: np.broadcast_to(np.asarray(x, dtype=float), (m,))  # noqa: E731
        return Tangent(
            l=l, T=T, k=bc(k).copy(), c=bc(c).copy(), dk_dT=bc(dk_dT).copy(), dc_dT=z, names=self.names,
            units=tuple(p.unit for p in self.parameters), values=vals,
            dk=np.array([bc(dk.get(n, z)) for n in self.names]).reshape(len(self.names), m),
            dc=np.array([bc(dc.get(n, z)) for n in self.names]).reshape(len(self.names), m),
        )

    @classmethod
    def _trusted(cls, **fields):
        """Build without validation, from arrays already checked by the caller (hot paths)."""
        obj = object.__new__(cls)
        for f in dataclasses.fields(cls):
            object.__setattr__(obj, f.name, fields.get(f.name, f.default))
        return obj


def _refs(l, T) -> tuple[np.ndarray, np.ndarray]:
    l = np.asarray(l, dtype=float)
    T = np.asarray(T, dtype=float)
    return l, (T if T.shape == l.shape else np.broadcast_to(T, l.shape))


def _per(x, shape) -> np.ndarray:
    """A parameter as an array of ``shape`` (no copy when it already is one)."""
    return x if np.shape(x) == shape else np.broadcast_to(np.asarray(x, dtype=float), shape).copy()


# ---- the linear spring part shared by Voigt and the power-law dashpot --------------------------------
class _SpringEA(TendonLaw):
    """``EA(l/l0 − 1)``: the paper's linear spring, with the rest lengths of Eq. (11)."""

    def elastic(self, l):
        """``EA(l/l0 − 1)`` (N)."""
        return self.EA * (np.asarray(l) / self._l0() - 1.0)

    def stiffness_at_rest(self, l):
        """``EA/l0`` (N/m)."""
        return self.EA / self._l0()

    def rest_lengths(self, l, T):
        """Eq. (11): ``l0 = l·EA/(EA + T)`` (m).

        Raises
        ------
        ValueError
            Where ``T ≤ −EA`` (a compressed member softer than its load would need ``l0 ≤ 0``).
        """
        l, T = _refs(l, T)
        d = self.EA + T
        if not d.min() > 0:
            j = int(np.flatnonzero(np.broadcast_to(d, l.shape) <= 0)[0])
            raise ValueError(
                f"EA must exceed the compression −T = {-np.broadcast_to(T, l.shape)[j]:.6g} N of member {j} "
                f"(got EA = {np.broadcast_to(self.EA, l.shape)[j]:.6g} N): the spring would need a non-positive rest length"
            )
        return l * self.EA / d

    def _spring_tangent(self, l, T):
        """``k = (EA + T)/l`` (N/m): Eq. (11) rest lengths make ``EA/l0`` this."""
        return (self.EA + T) / l


@dataclass(frozen=True, eq=False)
class Voigt(_SpringEA):
    """Voigt tendon (paper Eq. 1): ``T = EA·(l/l0 − 1) + c·l'``.

    Parameters
    ----------
    EA : float or ndarray, shape (m,)
        Axial stiffness (N), > 0.
    c : float or ndarray, shape (m,)
        Damping coefficient (N·s/m), ≥ 0.
    l0 : ndarray, shape (m,), optional
        Rest lengths (m); set by :meth:`at_prestress` (Eq. 11).

    Notes
    -----
    At a reference with tension ``T``: ``k = EA/l0 = (EA + T)/l``,
    ``∂k/∂T = 1/l``, ``∂k/∂EA = 1/l``, ``∂c/∂c = 1``.
    """

    EA: Any
    c: Any
    l0: Any = None
    parameters: ClassVar = (Parameter("EA", "N"), Parameter("c", "N·s/m", True))
    rate_linear: ClassVar = True

    def __post_init__(self):
        self._validate()

    def tension(self, l, ldot):
        """``EA(l/l0 − 1) + c·l'`` (N)."""
        return self.elastic(l) + self.c * ldot

    def derivatives(self, l, ldot):
        """``(T, EA/l0, c)`` in (N, N/m, N·s/m)."""
        return self.tension(l, ldot), self.EA / self._l0(), np.broadcast_to(self.c, np.shape(self._l0()))

    def damping_at_rest(self, l):
        """``c`` (N·s/m)."""
        return np.broadcast_to(self.c, np.shape(l)).astype(float)

    def tangent_at_rest(self, l, T):
        """``((EA + T)/l, c)``."""
        return self._reference(l, T)[1:]

    def _reference(self, l, T):
        l, T = _refs(l, T)
        return self.rest_lengths(l, T), self._spring_tangent(l, T), _per(self.c, l.shape)

    def tangent(self, l, T) -> Tangent:
        """Exact: ``∂k/∂T = ∂k/∂EA = 1/l``, ``∂c/∂c = 1``."""
        l, T = _refs(l, T)
        k, c = self.tangent_at_rest(l, T)
        return self._tangent(l, T, k, c, 1.0 / l, {"EA": 1.0 / l}, {"c": 1.0})


@dataclass(frozen=True, eq=False)
class PowerDashpot(_SpringEA):
    """Spring in parallel with a power-law dashpot (the paper's discussion).

    The exact law is ``T = EA(l/l0 − 1) + c·sign(l')·|l'|^β``. Its rate
    derivative at ``l' = 0`` is 0 for β > 1 and infinite for β < 1; either
    way the velocities of the massless equations of motion are not a smooth
    function of the configuration where some ``l' = 0``. The time integration
    therefore uses the smoothed dashpot

    ``φ_ε(l') = c·l'·(l'² + ε²)^((β−1)/2)``,

    which equals the exact law to relative accuracy ``(β−1)/2·(ε/l')²`` for
    ``|l'| ≫ ε``, is odd and strictly increasing, and acts as a linear
    dashpot of coefficient ``c·ε^(β−1)`` for ``|l'| ≪ ε``. Choose the
    velocity scale ε (m/s) well below the tendon rates of interest (the
    default :data:`DEFAULT_VELOCITY_SCALE` = 1e-3 m/s is ~1/30 of the peak
    tendon rates of a 3 N, 1 Hz load on the default cell, where going down to
    3e-4 m/s changes G'' by 0.1 %) and check that a smaller ε leaves the
    result unchanged; smaller ε makes the equations stiffer at velocity
    reversals. β = 1 is the Voigt law exactly, for any ε.

    The linearization (:meth:`damping_at_rest`) refers to the exact law, not
    the smoothing: 0 for β > 1 (so C0 = 0 and G'' = 0, the paper's argument),
    ``c`` for β = 1, and no linearization for β < 1.

    Parameters
    ----------
    EA : float or ndarray, shape (m,)
        Axial stiffness (N).
    c : float or ndarray, shape (m,)
        Dashpot coefficient (N·(s/m)^β).
    l0 : ndarray, shape (m,), optional
        Rest lengths (m).
    beta : float
        Dashpot exponent β > 0 (dimensionless).
    velocity_scale : float
        Smoothing velocity ε > 0 (m/s).
    """

    EA: Any
    c: Any
    l0: Any = None
    beta: float = 2.0
    velocity_scale: float = DEFAULT_VELOCITY_SCALE
    parameters: ClassVar = (Parameter("EA", "N"), Parameter("c", "N·(s/m)^beta", True))

    def __post_init__(self):
        self._validate()
        object.__setattr__(self, "beta", positive_scalar("beta (dashpot exponent)", self.beta))
        object.__setattr__(self, "velocity_scale", positive_scalar("velocity_scale", self.velocity_scale, "m/s"))

    @property
    def rate_linear(self) -> bool:  # type: ignore[override]  # per instance here, a class constant elsewhere
        """True only for β = 1 (then the law is exactly Voigt)."""
        return self.beta == 1.0

    def _dashpot(self, ldot):
        ldot = np.asarray(ldot, dtype=float)
        b, eps2 = self.beta, self.velocity_scale ** 2
        s = ldot * ldot + eps2
        g = s ** (0.5 * (b - 1.0))
        f = self.c * ldot * g
        # d/dl' [l' s^((β−1)/2)] = s^((β−1)/2) (1 + (β−1) l'^2/s)
        df = self.c * g * (1.0 + (b - 1.0) * ldot * ldot / s)
        return f, df

    def tension(self, l, ldot):
        """Smoothed ``EA(l/l0 − 1) + c·sign(l')|l'|^β`` (N)."""
        return self.elastic(l) + self._dashpot(ldot)[0]

    def derivatives(self, l, ldot):
        """``(T, dT/dl, dT/dl')`` of the smoothed law, in (N, N/m, N·s/m)."""
        f, df = self._dashpot(ldot)
        return self.elastic(l) + f, self.EA / self._l0(), df

    def _exact_rate_slope(self, shape) -> np.ndarray:
        if self.beta > 1.0:
            return np.zeros(shape)
        if self.beta == 1.0:
            return np.broadcast_to(self.c, shape).astype(float)
        raise LinearizationError(
            f"the dashpot law T = c·sign(l')·|l'|^beta with beta={self.beta:g} < 1 has an infinite slope at "
            "l' = 0, so the equations of motion have no linearization about the prestressed rest state and no "
            "linear moduli G', G'' exist; simulate the finite-amplitude response in the time domain instead "
            "(tenscell.dynamics.oscillatory_response)"
        )

    def damping_at_rest(self, l):
        """Rate derivative of the exact law at ``l' = 0`` (N·s/m): 0 for β > 1, ``c`` for β = 1.

        Raises
        ------
        LinearizationError
            For β < 1, where ``d(c|l'|^β)/dl'`` is infinite at ``l' = 0``.
        """
        return self._exact_rate_slope(np.shape(l))

    def tangent_at_rest(self, l, T):
        """``((EA + T)/l, c_lin)`` with the exact law's rate slope (raises for β < 1)."""
        l, T = _refs(l, T)
        self.rest_lengths(l, T)
        return self._spring_tangent(l, T), self._exact_rate_slope(l.shape)

    def tangent(self, l, T) -> Tangent:
        """Exact: ``∂k/∂T = ∂k/∂EA = 1/l``; ``∂c/∂c`` is 1 for β = 1, else 0."""
        l, T = _refs(l, T)
        k, c = self.tangent_at_rest(l, T)
        return self._tangent(l, T, k, c, 1.0 / l, {"EA": 1.0 / l}, {"c": 1.0 if self.beta == 1.0 else 0.0})


# ---- strain-stiffening filaments ---------------------------------------------------------------------
def _expm1_over_b(b, x):
    """``(exp(b·x) − 1)/b``, equal to ``x`` at ``b = 0``."""
    safe = np.where(b > 0, b, 1.0)
    return np.where(b > 0, np.expm1(safe * x) / safe, x)


def _log1p_over_b(b, y):
    """``log(1 + b·y)/b``, equal to ``y`` at ``b = 0`` (the inverse of :func:`_expm1_over_b`)."""
    safe = np.where(b > 0, b, 1.0)
    return np.where(b > 0, np.log1p(safe * y) / safe, y)


def _dlog1p_over_b_db(b, y):
    """``∂/∂b [log(1 + b·y)/b] = (y/(1 + b·y) − log(1 + b·y)/b)/b``; its series where ``|b·y|`` is small.

    The series ``Σ_{n≥1} (−1)ⁿ n/(n+1) bⁿ⁻¹ yⁿ⁺¹`` avoids the cancellation
    (−y²/2 at b = 0); 8 terms are exact to round-off for ``|b·y| < 0.02``.
    """
    b, y = np.broadcast_arrays(np.asarray(b, dtype=float), np.asarray(y, dtype=float))
    x = b * y
    small = np.abs(x) < 0.02
    series = np.zeros_like(x)
    for n in range(8, 0, -1):
        series = (-1) ** n * n / (n + 1) * y ** 2 * x ** (n - 1) + series
    safe = np.where(small, 1.0, b)
    direct = (y / (1.0 + safe * y) - np.log1p(safe * y) / safe) / safe
    return np.where(small, series, direct)


@dataclass(frozen=True, eq=False)
class StiffeningFilament(TendonLaw):
    """A strain-stiffening filament: ``T = (EA/b)(exp(b·ε) − 1) + c·l'``, ``ε = l/l0 − 1``.

    Intermediate filaments are "known sources of nonlinear elastic behavior"
    (the paper's discussion). ``EA`` is the small-strain stiffness (N) and
    ``b ≥ 0`` the dimensionless stiffening exponent; ``b = 0`` is the Voigt
    spring ``EA·ε``. The tangent stiffness ``∂T/∂l = (EA/l0)·exp(b·ε) =
    (EA + b·T)/l0`` grows linearly with the tension, the signature of
    strain-stiffening biopolymer networks.

    At a reference with tension ``T`` and length ``l``: ``ε = log(1 +
    b·T/EA)/b``, ``l0 = l/(1 + ε)`` and ``k = (EA + b·T)(1 + ε)/l``, with

    * ``∂k/∂T = (1 + b(1 + ε))/l``,
    * ``∂k/∂EA = (1 + ε − T/EA)/l``,
    * ``∂k/∂b = (T(1 + ε) + (EA + b·T)·∂ε/∂b)/l``, ``∂ε/∂b = (T/(EA + b·T) − ε)/b``.

    Parameters
    ----------
    EA : float or ndarray, shape (m,)
        Small-strain stiffness (N), > 0.
    c : float or ndarray, shape (m,)
        Damping (N·s/m), ≥ 0.
    b : float or ndarray, shape (m,)
        Stiffening exponent (dimensionless), ≥ 0.
    l0 : ndarray, shape (m,), optional
        Rest lengths (m).
    """

    EA: Any
    c: Any
    b: object = 0.0
    l0: Any = None
    parameters: ClassVar = (Parameter("EA", "N"), Parameter("c", "N·s/m", True), Parameter("b", "", True))
    rate_linear: ClassVar = True

    def __post_init__(self):
        self._validate()

    def elastic(self, l):
        """``(EA/b)(exp(b·ε) − 1)`` (N)."""
        return self.EA * _expm1_over_b(self.b, np.asarray(l, dtype=float) / self._l0() - 1.0)

    def tension(self, l, ldot):
        """``(EA/b)(exp(b·ε) − 1) + c·l'`` (N)."""
        return self.elastic(l) + self.c * ldot

    def stiffness_at_rest(self, l):
        """``(EA/l0)·exp(b·ε)`` (N/m)."""
        l0 = self._l0()
        return self.EA / l0 * np.exp(self.b * (np.asarray(l, dtype=float) / l0 - 1.0))

    def derivatives(self, l, ldot):
        """``(T, (EA/l0)exp(b·ε), c)`` in (N, N/m, N·s/m)."""
        return self.tension(l, ldot), self.stiffness_at_rest(l), np.broadcast_to(self.c, np.shape(self._l0()))

    def damping_at_rest(self, l):
        """``c`` (N·s/m)."""
        return np.broadcast_to(self.c, np.shape(l)).astype(float)

    def _strain(self, T):
        y = np.asarray(T, dtype=float) / self.EA
        if np.any(1.0 + self.b * y <= 0):
            raise ValueError("tension T is below -EA/b, which the exponential law never reaches")
        eps = _log1p_over_b(self.b, y)
        if np.any(eps <= -1.0):
            raise ValueError("the requested tension needs a strain <= -1 (a non-positive rest length)")
        return eps

    def rest_lengths(self, l, T):
        """``l0 = l/(1 + ε)``, ``ε = log(1 + b·T/EA)/b`` (``T/EA`` at ``b = 0``) (m)."""
        l, T = _refs(l, T)
        return l / (1.0 + self._strain(T))

    def tangent_at_rest(self, l, T):
        """``((EA + b·T)(1 + ε)/l, c)``."""
        l, T = _refs(l, T)
        eps = self._strain(T)
        return (self.EA + self.b * T) * (1.0 + eps) / l, np.broadcast_to(self.c, l.shape).astype(float)

    def tangent(self, l, T) -> Tangent:
        """Exact derivatives (see the class docstring)."""
        l, T = _refs(l, T)
        eps = self._strain(T)
        k = (self.EA + self.b * T) * (1.0 + eps) / l
        deps_db = _dlog1p_over_b_db(self.b, T / self.EA)
        return self._tangent(
            l, T, k, np.broadcast_to(self.c, l.shape), (1.0 + self.b * (1.0 + eps)) / l,
            {"EA": (1.0 + eps - T / self.EA) / l, "b": (T * (1.0 + eps) + (self.EA + self.b * T) * deps_db) / l},
            {"c": 1.0},
        )


@dataclass(frozen=True, eq=False)
class LinearSpring(TendonLaw):
    """A spring of given stiffness: ``T = k(l − l0) + c·l'``.

    Its tangent stiffness is ``k`` (N/m) whatever the tension (``∂k/∂T = 0``);
    :func:`tenscell.linear.linearize.linearize_tangent` linearizes with it.

    Parameters
    ----------
    k : float or ndarray, shape (m,)
        Stiffness (N/m), > 0.
    c : float or ndarray, shape (m,)
        Damping (N·s/m), ≥ 0.
    l0 : ndarray, shape (m,), optional
        Rest lengths (m).
    """

    k: Any
    c: Any
    l0: Any = None
    parameters: ClassVar = (Parameter("k", "N/m"), Parameter("c", "N·s/m", True))
    rate_linear: ClassVar = True

    def __post_init__(self):
        self._validate()

    def tension(self, l, ldot):
        """``k(l − l0) + c·l'`` (N)."""
        return self.k * (np.asarray(l, dtype=float) - self._l0()) + self.c * ldot

    def derivatives(self, l, ldot):
        """``(T, k, c)``."""
        return self.tension(l, ldot), np.broadcast_to(self.k, np.shape(self._l0())), np.broadcast_to(self.c, np.shape(self._l0()))

    def rest_lengths(self, l, T):
        """``l − T/k`` (m); ValueError where that is not positive."""
        l, T = _refs(l, T)
        l0 = l - T / self.k
        if np.any(l0 <= 0):
            raise ValueError("a member's tension exceeds k·l: the spring would need a non-positive rest length")
        return l0

    def tangent_at_rest(self, l, T):
        """``(k, c)``."""
        l, T = _refs(l, T)
        return np.broadcast_to(self.k, l.shape).astype(float), np.broadcast_to(self.c, l.shape).astype(float)

    def tangent(self, l, T) -> Tangent:
        """Exact: ``∂k/∂T = 0``, ``∂k/∂k = 1``, ``∂c/∂c = 1``."""
        l, T = _refs(l, T)
        k, c = self.tangent_at_rest(l, T)
        return self._tangent(l, T, k, c, 0.0, {"k": 1.0}, {"c": 1.0})


# ---- different laws on different tendons -------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class CompositeLaw(TendonLaw):
    """Different laws on disjoint sets of tendons (e.g. Voigt actin and stiffening IFs).

    Parameters
    ----------
    laws : tuple of TendonLaw
        One law per tendon set; its per-tendon arrays (if any) follow the set's order.
    indices : tuple of array_like of int
        The tendon indices of each law; together exactly ``0..m−1``, each once.

    The composite's parameters are the union of its parts' names (in order of
    first appearance); in :meth:`tangent`, a tendon's value of a parameter its
    law does not have is NaN.
    """

    laws: tuple
    indices: tuple

    def __post_init__(self):
        laws, idx = tuple(self.laws), tuple(np.asarray(i, dtype=int).ravel() for i in self.indices)
        if len(laws) != len(idx) or not laws:
            raise ValueError(f"CompositeLaw needs one index set per law, got {len(laws)} laws and {len(idx)} sets")
        for law in laws:
            if not isinstance(law, TendonLaw):
                raise ValueError(f"every part of a CompositeLaw must be a TendonLaw, got {type(law).__name__}")
        allidx = np.concatenate(idx)
        m = allidx.size
        if not np.array_equal(np.sort(allidx), np.arange(m)):
            raise ValueError(f"the index sets of a CompositeLaw must cover tendons 0..{m - 1} exactly once")
        for law, i in zip(laws, idx):
            if law.m is not None and law.m != i.size:
                raise ValueError(f"a {type(law).__name__} part has {law.m} tendons but its index set has {i.size}")
            i.setflags(write=False)
        object.__setattr__(self, "laws", laws)
        object.__setattr__(self, "indices", idx)

    @property
    def m(self) -> int:
        """Number of tendons."""
        return int(sum(i.size for i in self.indices))

    @property
    def l0(self):
        """Rest lengths (m), or None if any part has none."""
        if any(law.l0 is None for law in self.laws):
            return None
        return self._gather(lambda law, i: np.broadcast_to(law.l0, i.shape))

    @property
    def rate_linear(self) -> bool:  # type: ignore[override]  # per instance here, a class constant elsewhere
        """Every part is rate-linear."""
        return all(law.rate_linear for law in self.laws)

    @property
    def names(self) -> tuple[str, ...]:
        """The union of the parts' parameter names."""
        out: list[str] = []
        for law in self.laws:
            out += [n for n in law.names if n not in out]
        return tuple(out)

    def _gather(self, fn, m=None):
        out = np.empty(self.m if m is None else m)
        for law, i in zip(self.laws, self.indices):
            out[i] = fn(law, i)
        return out

    def _sub(self, x, i):
        return np.broadcast_to(np.asarray(x, dtype=float), (self.m,))[i]

    def with_rest_lengths(self, l0) -> "CompositeLaw":
        """Each part with its tendons' rest lengths."""
        l0 = positive_array("l0 (rest length)", l0, (self.m,), "m")
        return CompositeLaw(tuple(law.with_rest_lengths(l0[i]) for law, i in zip(self.laws, self.indices)), self.indices)

    def _placed(self, l0) -> "CompositeLaw":
        return CompositeLaw(tuple(law._placed(np.asarray(l0)[i]) for law, i in zip(self.laws, self.indices)),
                            self.indices)

    def tension(self, l, ldot):
        """Each part's tension on its tendons (N)."""
        return self._gather(lambda law, i: law.tension(self._sub(l, i), self._sub(ldot, i)))

    def elastic(self, l):
        """Each part's ``T(l, 0)`` (N)."""
        return self._gather(lambda law, i: law.elastic(self._sub(l, i)))

    def derivatives(self, l, ldot):
        """``(T, ∂T/∂l, ∂T/∂l')`` assembled from the parts."""
        T, dl, dv = np.empty(self.m), np.empty(self.m), np.empty(self.m)
        for law, i in zip(self.laws, self.indices):
            T[i], dl[i], dv[i] = law.derivatives(self._sub(l, i), self._sub(ldot, i))
        return T, dl, dv

    def stiffness_at_rest(self, l):
        """Each part's ``∂T/∂l`` at rest (N/m)."""
        return self._gather(lambda law, i: law.stiffness_at_rest(self._sub(l, i)))

    def damping_at_rest(self, l):
        """Each part's exact ``∂T/∂l'`` at rest (N·s/m)."""
        return self._gather(lambda law, i: law.damping_at_rest(self._sub(l, i)))

    def rest_lengths(self, l, T):
        """Each part's inverse law (m)."""
        return self._gather(lambda law, i: law.rest_lengths(self._sub(l, i), self._sub(T, i)))

    def tangent_at_rest(self, l, T):
        """Each part's ``(k, c)``."""
        k, c = np.empty(self.m), np.empty(self.m)
        for law, i in zip(self.laws, self.indices):
            k[i], c[i] = law.tangent_at_rest(self._sub(l, i), self._sub(T, i))
        return k, c

    def parameter_values(self, m: int) -> np.ndarray:
        """Parameters, shape ``(p, m)``, NaN where a tendon's law lacks one."""
        names = self.names
        vals = np.full((len(names), self.m), np.nan)
        for law, i in zip(self.laws, self.indices):
            sub = law.parameter_values(i.size)
            for r, n in enumerate(law.names):
                vals[names.index(n), i] = sub[r]
        return vals

    def tangent(self, l, T) -> Tangent:
        """Each part's :class:`Tangent`, assembled (exact where the parts are)."""
        l, T = _refs(l, T)
        names, m = self.names, self.m
        units: dict[str, str] = {}
        k, c, dkT, dcT = (np.empty(m) for _ in range(4))
        dk, dc = np.zeros((len(names), m)), np.zeros((len(names), m))
        for law, i in zip(self.laws, self.indices):
            t = law.tangent(l[i], T[i])
            k[i], c[i], dkT[i], dcT[i] = t.k, t.c, t.dk_dT, t.dc_dT
            for r, n in enumerate(t.names):
                dk[names.index(n), i], dc[names.index(n), i] = t.dk[r], t.dc[r]
                units.setdefault(n, t.units[r])
        return Tangent(l=l, T=np.array(T, dtype=float), k=k, c=c, dk_dT=dkT, dc_dT=dcT, names=names,
                       units=tuple(units[n] for n in names), values=self.parameter_values(m), dk=dk, dc=dc)


def family_laws(cell: Cell, laws: Mapping[str, TendonLaw], default: TendonLaw | None = None) -> CompositeLaw:
    """A :class:`CompositeLaw` giving each tendon family of ``cell`` its own law.

    Parameters
    ----------
    cell : Cell
    laws : mapping of family name -> TendonLaw
        E.g. ``{"actin": Voigt(EA=1.0, c=1.0), "intermediate_filament":
        StiffeningFilament(EA=1.0, c=1.0, b=0.05)}``; per-tendon arrays follow
        the order of the family's tendons in the cell.
    default : TendonLaw, optional
        The law of every family not named (its arrays, if any, follow the
        order of the remaining tendons).

    Returns
    -------
    CompositeLaw
        Without rest lengths: place it with :meth:`TendonLaw.at_prestress`.
    """
    fams = cell.structure.families
    known = sorted(set(fams))
    parts, idx = [], []
    for name, law in laws.items():
        i = cell.structure.family_indices(name)
        if i.size == 0:
            raise ValueError(f"{cell.describe()} has no tendons of family {name!r}; its families are {', '.join(known)}")
        parts.append(law)
        idx.append(i)
    rest = np.setdiff1d(np.arange(cell.m), np.concatenate(idx) if idx else np.array([], dtype=int))
    if rest.size:
        if default is None:
            missing = sorted({fams[j] for j in rest})
            raise ValueError(f"no law given for the tendon families {', '.join(missing)} (pass default=...)")
        parts.append(default)
        idx.append(rest)
    return CompositeLaw(tuple(parts), tuple(idx))


# ---- the paper's placements ----------------------------------------------------------------------------
def _per_tendon(cell: Cell, **arrays) -> tuple[np.ndarray, ...]:
    """Validate per-tendon inputs given as scalars or (m,) arrays; return (m,) arrays."""
    out = []
    for name, (value, unit, allow_zero) in arrays.items():
        if np.ndim(value) == 1 and np.shape(value) != (cell.m,):
            raise ValueError(f"{name} must have {cell.m} entries (one per working tendon), got {np.shape(value)[0]}")
        out.append(positive_array(name, value, (cell.m,), unit, allow_zero=allow_zero))
    return tuple(out)


def rest_lengths(cell: Cell, P: float, EA) -> np.ndarray:
    """Rest lengths giving ``T = P·T0`` at the reference (paper Eq. 11), in m.

    ``l0_j = l_j(q0)·EA_j / (T0_j·P + EA_j)``.
    """
    EA = np.broadcast_to(np.asarray(EA, dtype=float), cell.T0.shape)
    return Voigt._trusted(EA=EA, c=0.0).rest_lengths(cell.lengths, P * cell.T0)


def voigt_law(cell: Cell, P: float = 1000.0, EA=1.0, c=1.0) -> Voigt:
    """The Voigt law of a cell at prestress ``P`` (rest lengths from Eq. 11).

    Parameters
    ----------
    cell : Cell
    P : float
        Prestress scale (N): tensions ``P·T0`` at the reference.
    EA : float or array_like, shape (m,)
        Stiffness (N).
    c : float or array_like, shape (m,)
        Damping (N·s/m).
    """
    EA, c = _per_tendon(cell, EA=(EA, "N", False), c=(c, "N·s/m", False))
    return Voigt(EA=EA, c=c).at_prestress(cell, P)


def power_dashpot_law(cell: Cell, P: float = 1000.0, EA=1.0, c=1.0, beta: float = 2.0,
                      velocity_scale: float = DEFAULT_VELOCITY_SCALE) -> PowerDashpot:
    """The power-law dashpot of a cell at prestress ``P`` (rest lengths from Eq. 11).

    Parameters
    ----------
    cell : Cell
    P : float
        Prestress scale (N).
    EA : float or array_like, shape (m,)
        Stiffness (N).
    c : float or array_like, shape (m,)
        Dashpot coefficient (N·(s/m)^β).
    beta : float
        Exponent β > 0.
    velocity_scale : float
        Smoothing velocity ε (m/s), see :class:`PowerDashpot`.
    """
    finite_scalar("beta (dashpot exponent)", beta)
    EA, c = _per_tendon(cell, EA=(EA, "N", False), c=(c, "N·(s/m)^beta", False))
    return PowerDashpot(EA=EA, c=c, beta=beta, velocity_scale=velocity_scale).at_prestress(cell, P)


def stiffening_law(cell: Cell, P: float | None = 1000.0, EA=1.0, c=1.0, *, b: float = 0.0,
                   family: str = "intermediate_filament") -> CompositeLaw:
    """Stiffening filaments on one tendon family, Voigt on the others (at prestress ``P``).

    Parameters
    ----------
    cell : Cell
    P : float or None
        Prestress (N); None leaves the law without rest lengths.
    EA : float or array_like, shape (m,)
        Small-strain stiffness (N).
    c : float or array_like, shape (m,)
        Damping (N·s/m).
    b : float
        Stiffening exponent of ``family`` (dimensionless), ≥ 0.
    family : str
        The tendon family that stiffens (the intermediate filaments by default).
    """
    EA, c = _per_tendon(cell, EA=(EA, "N", False), c=(c, "N·s/m", True))
    b = finite_scalar("b (stiffening exponent)", b, "a finite number >= 0 (dimensionless; 0 = linear)")
    if b < 0:
        raise ValueError(f"b (stiffening exponent) must be a finite number >= 0 (dimensionless; 0 = linear), got {b!r}")
    stiff = cell.structure.family_indices(family)
    if stiff.size == 0:
        raise ValueError(f"{cell.describe()} has no tendons of family {family!r}")
    rest = np.setdiff1d(np.arange(cell.m), stiff)
    parts: list[TendonLaw] = [StiffeningFilament(EA=EA[stiff], c=c[stiff], b=np.full(stiff.size, b))]
    idx = [stiff]
    if rest.size:
        parts.append(Voigt(EA=EA[rest], c=c[rest]))
        idx.append(rest)
    law = CompositeLaw(tuple(parts), tuple(idx))
    return law if P is None else law.at_prestress(cell, P)

"""The tendon-law protocol: :class:`TendonLaw`, its :class:`Tangent` and :class:`Parameter`.

Every law in :mod:`tenscell.laws` subclasses :class:`TendonLaw`; see the package docstring for the interface.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple, Self

import numpy as np

from .._errors import TenscellError
from .._checks import positive_array, positive_scalar
from .._results import dataframe, format_repr
from ..model.equilibrium import Cell

__all__ = ["TendonLaw", "Parameter", "Tangent", "Realization", "LinearizationError", "DynamicLawError",
           "angular_frequencies", "laplace_variables", "DEFAULT_REALIZATION_TOL"]

#: default relative accuracy of an approximate internal-variable realization over its band (|Δk*|/|k*|)
DEFAULT_REALIZATION_TOL = 1e-3


class LinearizationError(TenscellError, ValueError):
    """The tendon law has no linearization at rest (its rate derivative at l' = 0 is infinite)."""


class DynamicLawError(LinearizationError):
    """The tendon law's tangent depends on frequency: it has no constant pair (k, c), or no state-free motion."""


def angular_frequencies(omega) -> np.ndarray:
    """``omega`` (rad/s) as a finite, non-negative 1-D float array (a scalar becomes shape (1,))."""
    w = np.atleast_1d(np.asarray(omega, dtype=float)).ravel()
    if not (np.all(np.isfinite(w)) and np.all(w >= 0)):
        raise ValueError(f"omega (angular frequency) must be finite numbers >= 0 (rad/s), got {omega!r}")
    return w


def laplace_variables(s) -> np.ndarray:
    """``s`` (1/s) as a finite 1-D complex array (a scalar becomes shape (1,))."""
    z = np.atleast_1d(np.asarray(s, dtype=complex)).ravel()
    if not np.all(np.isfinite(z)):
        raise ValueError(f"s (Laplace variable) must be finite complex numbers (1/s), got {s!r}")
    return z


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


# ---- internal-variable realizations ---------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class Realization:
    """Tendons as springs, dashpots and Maxwell arms: the law with internal variables, for constant matrices.

    Tendon j carries ``k_j`` (N/m) and ``c_j`` (N·s/m) in parallel, plus the
    Maxwell arms ``a`` with ``tendon[a] = j``: a spring ``arm_k[a]`` (N/m) in
    series with a dashpot ``arm_c[a]`` (N·s/m), whose dashpot extension is one
    internal variable. Its dynamic tangent is
    ``k_j + iωc_j + Σ_{a∈j} arm_k·iωτ_a/(1 + iωτ_a)``, ``τ_a = arm_c/arm_k``.

    Attributes
    ----------
    k, c : ndarray, shape (m,)
    tendon : ndarray of int, shape (r,)
    arm_k, arm_c : ndarray, shape (r,)
    error : float
        Largest relative error ``|k*_realized − k*|/|k*|`` over ``band_hz``
        (0 when the realization is exact at every frequency).
    band_hz : tuple of float, or None
        The band (Hz) the error refers to; None for an exact realization.
    """

    k: np.ndarray
    c: np.ndarray
    tendon: np.ndarray
    arm_k: np.ndarray
    arm_c: np.ndarray
    error: float = 0.0
    band_hz: tuple | None = None

    @property
    def r(self) -> int:
        """Number of internal variables (Maxwell arms)."""
        return int(self.tendon.size)

    def complex_stiffness(self, omega) -> np.ndarray:
        """The realization's dynamic tangent (N/m), shape (n_omega, m), ω in rad/s."""
        w = angular_frequencies(omega)
        out = self.k[None, :] + 1j * np.multiply.outer(w, self.c)
        z = 1j * np.multiply.outer(w, self.arm_c)
        arms = self.arm_k * z / (self.arm_k + z)
        for i in range(w.size):
            np.add.at(out[i], self.tendon, arms[i])
        return out

    def __repr__(self) -> str:
        acc = "exact" if self.band_hz is None else f"within {self.error:.2g} relative over {self.band_hz[0]:g}–{self.band_hz[1]:g} Hz"
        return format_repr(f"Realization of {self.k.size} tendons with {self.r} internal variables ({acc})")


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
    #: True for laws whose tangent depends on frequency (internal dynamics: Maxwell, standard linear solid,
    #: springpot); they define :meth:`complex_stiffness` and have no constant (k, c)
    dynamic: ClassVar[bool] = False
    #: the group the command line's help lists a fittable mechanism on this law in
    #: (:class:`tenscell.fitting.models.mechanism.Mechanism`); None: the law carries no mechanism
    mechanism_group: ClassVar[str | None] = None
    #: the law's terms lumped into one element, as terms of a structure-free formula
    #: (:data:`tenscell.fitting.models.formulas.TERMS`): the baseline a mechanism on this law must beat; None: none
    lumped_terms: ClassVar[tuple[str, ...] | None] = None
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

    def realization(self, l, T, band_hz=None, tol: float = DEFAULT_REALIZATION_TOL) -> Realization:
        """The law at a reference as springs, dashpots and Maxwell arms (:class:`Realization`).

        Rate-linear laws: ``(k, c)`` of :meth:`tangent_at_rest`, no arms (exact).
        Laws with internal dynamics override it: exact for Maxwell and the standard
        linear solid (one arm per tendon), a Prony series accurate to ``tol`` over
        ``band_hz`` (Hz) for the springpot.
        """
        k, c = self.tangent_at_rest(l, T)
        none = np.zeros(0)
        return Realization(k=np.asarray(k, dtype=float), c=np.asarray(c, dtype=float), tendon=np.zeros(0, dtype=int),
                           arm_k=none, arm_c=none)

    # -- the dynamic tangent (frequency domain) ---------------------------------------------------------
    def complex_stiffness(self, l, T, omega) -> np.ndarray:
        """Dynamic tangent ``k*_j(ω) = ∂T_j/∂l_j`` (N/m, complex) about tensions ``T`` (N) at lengths ``l`` (m).

        Shape ``(n_omega, m)`` for ``omega`` (rad/s, ≥ 0). For a rate-linear law
        it is ``k + iω·c`` from :meth:`tangent_at_rest`; laws with internal
        dynamics (``dynamic = True``) override it with their exact form.
        """
        w = angular_frequencies(omega)
        k, c = self.tangent_at_rest(l, T)
        return np.asarray(k, dtype=float)[None, :] + 1j * np.multiply.outer(w, np.asarray(c, dtype=float))

    def laplace_stiffness(self, l, T, s) -> np.ndarray:
        """The dynamic tangent at complex Laplace variables ``s`` (1/s): ``k*(s)``, with ``k*(iω)`` = :meth:`complex_stiffness`.

        Shape ``(n_s, m)``, complex (N/m). For a rate-linear law it is ``k + s·c``; laws with
        internal dynamics override it with the analytic continuation of their exact form (principal
        branch of any fractional power), which is what an exact inversion of creep or relaxation
        (:func:`tenscell.timedomain.creep_compliance`) evaluates off the imaginary axis.
        """
        z = laplace_variables(s)
        k, c = self.tangent_at_rest(l, T)
        return np.asarray(k, dtype=float)[None, :] + np.multiply.outer(z, np.asarray(c, dtype=float))

    def complex_stiffness_derivatives(self, l, T, omega) -> tuple[np.ndarray, np.ndarray]:
        """``(∂k*/∂T, ∂k*/∂θ)``: shapes ``(n_omega, m)`` (1/m) and ``(p, n_omega, m)``, θ in :attr:`names` order.

        Derivatives at fixed parameters (the rest length follows the tension)
        and at fixed tension respectively; 0 where a tendon has no such
        parameter. Default: from :meth:`tangent`, ``∂k + iω·∂c``.
        """
        w = angular_frequencies(omega)
        t = self.tangent(l, T)
        dk_dT = t.dk_dT[None, :] + 1j * np.multiply.outer(w, t.dc_dT)
        dk = t.dk[:, None, :] + 1j * w[None, :, None] * t.dc[:, None, :]
        return dk_dT, dk

    def laplace_stiffness_derivatives(self, l, T, s) -> tuple[np.ndarray, np.ndarray]:
        """``(∂k*/∂T, ∂k*/∂θ)`` of :meth:`laplace_stiffness` at Laplace variables ``s`` (1/s): shapes ``(n_s, m)``
        and ``(p, n_s, m)``, θ in :attr:`names` order; at ``s = iω`` those of :meth:`complex_stiffness_derivatives`
        (what the exact Jacobian of a creep or relaxation fit inverts). Default: from :meth:`tangent`,
        ``∂k + s·∂c``."""
        z = laplace_variables(s)
        t = self.tangent(l, T)
        return (t.dk_dT[None, :] + np.multiply.outer(z, t.dc_dT),
                t.dk[:, None, :] + z[None, :, None] * t.dc[:, None, :])

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



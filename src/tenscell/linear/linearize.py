"""Linearization about the prestressed reference (paper Eqs. 12–14).

``C0·q̇ + K0·q + H0·F = 0`` and ``z = D0·q`` with

* ``K0 = P·Kp + Σ_j EA_j·K_j``, ``Kp = Σ T0_j (∇²l_j + a_j a_jᵀ/l_j)``,
  ``K_j = a_j a_jᵀ/l_j`` (N/m in length coordinates; the paper's Eq. 13);
* ``C0 = Σ c_j a_j a_jᵀ`` (N·s/m);
* ``H0 = −(∂x_load/∂q)ᵀ·d`` and ``D0 = (∂x_probe/∂q)ᵀ·d`` at q0.

The relaxation spectrum solves ``K0 v = λ C0 v`` (rates λ in 1/s) with
``vᵀ C0 v = 1``, so that ``(K0 + iωC0)⁻¹ = Σ v vᵀ/(λ + iω)``.
"""
from __future__ import annotations

import dataclasses
import weakref
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from .._checks import positive_array, positive_scalar
from ..laws import DynamicLawError, LinearSpring, TendonLaw, Voigt
from ..laws.base import DEFAULT_REALIZATION_TOL, Realization
from .._errors import NotPositiveDefiniteError
from ..model.equilibrium import Cell, tangent_stiffness
from .assembly import assemble_damping, assemble_stiffness, spring_stiffness
from .definite import _dense_factor
from .dynamic import cytoplasm_damping, viscosity_value
from .family import PrestressFamily
from .pencil import Pencil
from .spectrum import RelaxationSpectrum, relaxation_spectrum
from .._threads import hot_path
from .ordering import coordinate_locations
from .rigid import deformation_basis, unresisted_share

__all__ = [
    "LinearModel",
    "RelaxationSpectrum",
    "linearize",
    "linearize_tangent",
    "linearize_law",
    "realize",
    "with_cytoplasm",
    "relaxation_spectrum",
    "NotPositiveDefiniteError",
]


#: advice appended to the not-positive-definite message
_STABILITY_HINT = "For the paper cell keep delta between about 45.5° and 54.7° at alpha=0."


@dataclass(frozen=True, eq=False, repr=False)
class LinearModel:
    """The linearized cell at one prestress and one set of tendon properties.

    Attributes
    ----------
    cell : Cell
    P : float
        Prestress: tendon tensions at the reference are ``P·T0`` (N; the
        paper's "Pa" is this scale, see ``docs/conventions.md``).
    EA : ndarray, shape (m,)
        Tendon stiffnesses (N).
    c : ndarray, shape (m,)
        Tendon damping coefficients (N·s/m).
    K0 : ndarray or sparse, shape (n, n)
        Stiffness matrix (N/m in length coordinates, N·m/rad² in angles).
    C0 : ndarray or sparse, shape (n, n)
        Damping matrix (N·s/m in length coordinates).
    H0 : ndarray, shape (n,)
        Disturbance vector for the single load F1.
    D0 : ndarray, shape (n,)
        Output row for the probe z1.
    l0 : ndarray, shape (m,)
        Rest lengths (m) giving ``T = P·T0`` at the reference (Eq. 11 for Voigt tendons).
    law : TendonLaw
        The tendon law, placed at the reference (rest lengths ``l0``): what
        :func:`tenscell.sensitivity.analytic_elasticities` differentiates.
        None only for models built by hand, which are then read as Voigt
        tendons with ``EA`` and ``c``.
    viscosity : float
        Newtonian cytoplasm in parallel with the structure (Pa·s): a dashpot
        ``2L·η`` (N·s/m) on the probe, in C0, so that ``G* = G*_structure + iωη``
        (probe = load); 0 for none.
    realization : Realization or None
        For a law with internal dynamics (:mod:`tenscell.laws.viscoelastic`):
        its internal-variable realization; K0, C0, H0, D0 then have
        ``n + realization.r`` rows, the last ``r`` the arms' dashpot
        extensions (:func:`tenscell.linear.linearize.realize`). None otherwise.
    basis : ndarray, shape (n, n − k), optional
        For a structure its supports do not hold (free-standing): the
        orthonormal complement of its ``k`` rigid-body motions; :attr:`pencil`
        (every compliance, creep, relaxation and mode) then works on it
        (:mod:`tenscell.linear.rigid`, :attr:`notes`). K0, C0, H0, D0 keep
        the full size. None when the supports hold the structure.
    """

    cell: Cell
    P: float
    EA: np.ndarray
    c: np.ndarray
    K0: Any  # ndarray or scipy.sparse matrix
    C0: Any
    H0: np.ndarray
    D0: np.ndarray
    l0: np.ndarray
    law: Any = None
    viscosity: float = 0.0
    realization: Any = None
    basis: np.ndarray | None = None

    @property
    def tendon_law(self):
        """The law (a :class:`tenscell.laws.Voigt` with ``EA``, ``c`` when ``law`` is None)."""
        return self.law if self.law is not None else Voigt(EA=self.EA, c=self.c, l0=self.l0)

    @property
    def L(self) -> float:
        """Strut length used for the equivalent-continuum factor ``0.5/L`` (m)."""
        return self.cell.strut_length

    @property
    def Kp(self):
        """Prestress stiffness ``Kp`` (per unit P), from the cell."""
        return self.cell.Kp

    @property
    def K_j(self) -> np.ndarray:
        """Material stiffness matrices ``K_j = a_j a_jᵀ/l_j``, shape (m, n, n) (dense)."""
        A = self.cell.A.toarray() if sp.issparse(self.cell.A) else self.cell.A
        return np.einsum("im,jm->mij", A, A) / self.cell.lengths[:, None, None]

    @property
    def tensions(self) -> np.ndarray:
        """Tendon tensions at the reference, ``P·T0`` (N)."""
        return self.P * self.cell.T0

    @cached_property
    def pencil(self) -> Pencil:
        """The pencil (K0, C0) with its decompositions, each computed once for this model (:mod:`tenscell.linear.pencil`);
        for a free-standing structure the pencil on the complement of its rigid-body motions (``basis``)."""
        return self._new_pencil()

    def _new_pencil(self, family: PrestressFamily | None = None) -> Pencil:
        points = self._locations() if sp.issparse(self.K0) and self.basis is None else None
        pencil = Pencil(self.K0, self.C0, -np.asarray(self.H0), self.D0,
                        describe=f"{self.cell.describe()} at P={self.P:.6g}", hint=_STABILITY_HINT, points=points,
                        family=None if family is None else (family, self.P))
        return pencil if self.basis is None else pencil.restricted(self.basis)

    def _locations(self) -> np.ndarray:
        """A location (m) for each row of K0: the coordinates' nodes, and each internal variable's tendon midpoint."""
        x = coordinate_locations(self.cell.coords)
        if self.realization is None:
            return x
        s = self.cell.structure
        ends = np.asarray(s.tendons, dtype=np.int64)[np.asarray(self.realization.tendon)]
        return np.vstack([x, s.nodes[ends].mean(axis=1)])

    @property
    def notes(self) -> tuple[str, ...]:
        """What a reader of this model's results must know (rigid-body motions removed, and the share of the load
        along them that nothing resists)."""
        if self.basis is None:
            return ()
        k = self.K0.shape[0] - self.basis.shape[1]  # internal variables (a realized law) are kept whole
        return (f"{k} rigid-body motion(s) removed: the supports do not hold {self.cell.describe()}; "
                f"{100 * unresisted_share(self.H0, self.basis):.3g}% of the load vector is along them (a net force "
                "or moment nothing resists) and is left out",)

    def __getstate__(self):
        state = self.__dict__.copy()
        pencil = state.pop("pencil", None)  # factorizations are rebuilt on demand (native factors do not pickle)
        if pencil is not None and pencil.family is not None:
            state["_in_family"] = True  # rebuilt from the same family, so the copy gives the same numbers
        return state

    def __setstate__(self, state):
        in_family = state.pop("_in_family", False)
        self.__dict__.update(state)
        if in_family:
            self.__dict__["pencil"] = self._new_pencil(_prestress_family(self.cell, self.EA, self.c))

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from .._results import format_repr, span

        extra = []
        if self.realization is not None:
            R = self.realization
            acc = "exact" if R.band_hz is None else f"within {R.error:.2g} over {R.band_hz[0]:g}–{R.band_hz[1]:g} Hz"
            extra.append(f"{type(self.law).__name__} tendons realized with {R.r} internal variables ({acc}); "
                         "moduli from the exact dynamic tangent")
        return format_repr(
            f"LinearModel of {self.cell.describe()} at P = {self.P:.6g} N",
            f"{self.cell.n} coordinates, {self.cell.m} tendons; {'sparse' if sp.issparse(self.K0) else 'dense'} "
            "K0, C0",
            f"EA {span(self.EA, 'N')}; c {span(self.c, 'N·s/m')}; tensions {span(self.tensions, 'N')}",
            f"strut length L = {self.L:.4g} m" + (f"; cytoplasm η = {self.viscosity:.4g} Pa·s" if self.viscosity else ""),
            *extra,
        )

    def to_dataframe(self):
        """One row per tendon: the cell's columns and ``EA_N, c_Ns_per_m, rest_length_m, tension_N``."""
        df = self.cell.to_dataframe()
        df["EA_N"] = self.EA
        df["c_Ns_per_m"] = self.c
        df["rest_length_m"] = self.l0
        df["tension_N"] = self.tensions
        df.attrs["P_N"] = self.P
        return df

    def plot(self, ax=None, f_hz=None, *, axes=None, **kw):
        """G' and G'' of this model against frequency (log-log), on a pair of axes ``ax`` (``axes=`` is the older
        spelling; default a new figure).

        ``f_hz`` defaults to 61 frequencies from 0.01 to 1000 Hz (the paper's
        window). The moduli come from :func:`tenscell.compliance`; for several
        prestresses use :func:`tenscell.frequency_response` and its ``plot``.
        Returns the two axes.
        """
        from .._results import plotter

        return plotter("linear_model_moduli")(self, axes=ax if ax is not None else axes, f_hz=f_hz, **kw)


@hot_path
def linearize(cell: Cell, P: float = 1000.0, EA=1.0, c=1.0, *, check: bool = True, viscosity: float = 0.0) -> LinearModel:
    """Linearize the cell's equations of motion at prestress ``P`` (Voigt tendons, the paper's model).

    The paper-facing convenience for :func:`linearize_law` with
    :class:`tenscell.laws.Voigt`: ``K0 = P·Kp + Σ EA_j a_j a_jᵀ/l_j``,
    ``C0 = Σ c_j a_j a_jᵀ``.

    Parameters
    ----------
    cell : Cell
        A prestressable reference, e.g. :func:`tenscell.paper_cell`.
    P : float
        Prestress scale (N): tensions ``P·T0``. Must be > 0.
    EA : float or array_like, shape (m,)
        Tendon stiffness (N), one value for all or one per tendon.
    c : float or array_like, shape (m,)
        Tendon damping (N·s/m), one value for all or one per tendon.
    check : bool
        Verify that K0 is positive definite (default). Turn off only in
        inner loops that have already checked.
    viscosity : float
        Cytoplasm viscosity η (Pa·s), ≥ 0, in parallel with the structure
        (``G* += iωη``; see :attr:`LinearModel.viscosity`).

    Returns
    -------
    LinearModel

    Raises
    ------
    ValueError
        For a non-numeric, non-positive or NaN ``P``, ``EA`` or ``c``.
    NotPositiveDefiniteError
        If K0 is not positive definite (the reference is unstable).

    Notes
    -----
    A loop over prestresses reuses what does not depend on P: on a dense
    cell its supports hold, the models of one set of tendons belong to one
    :class:`tenscell.linear.family.PrestressFamily` (``K0 = P·Kp + Km``, C0
    whitened once; the cell keeps the family of the tendons it last served),
    so each model costs one eigensolve and its check is that every
    relaxation rate is positive. For a whole grid of prestresses,
    ``tenscell.frequency_response(cell, f, P=[...])`` is still the faster
    call: one batched eigensolve, and the per-call overhead paid once
    (``bench/bench_sweep.py`` times both against the floor).
    """
    P = positive_scalar("P (prestress)", P, "N")
    if not viscosity:  # the fast path of prestress loops: the tendons the cell's kept family last served
        kept = _kept_tendons(cell, EA, c)
        lin = None if kept is None else kept.model(cell, P, check)
        if lin is not None:
            return lin
    m = cell.m
    EA_v = positive_array("EA", EA, (m,), "N")
    c_v = positive_array("c", c, (m,), "N·s/m")
    # validated above: skip the law's own checks on this hot path (parameter sweeps, fits)
    # a cytoplasm adds to C0: that model is not a member of the tendons' family (its pencil is its own)
    family = None if viscosity else _prestress_family(cell, EA_v, c_v, EA, c)
    lin = _from_law(cell, P, Voigt._trusted(EA=EA_v, c=c_v), check=check, EA=EA_v, family=family)
    return with_cytoplasm(lin, viscosity) if viscosity else lin


#: the largest dense cell whose family is kept (five n×n matrices of its own, 10 MB at 500 coordinates): beyond it the
#: eigensolve dominates each model and the family would save little
_FAMILY_MAX_N = 500
#: per cell, the prestress family of the Voigt tendons it last served, with those tendons validated (a
#: :class:`_KeptTendons`). A cache only: a model's numbers do not depend on whether its family was found here or
#: built anew. Bound: one record per live dense cell of at most ``_FAMILY_MAX_N`` coordinates (weak keys: it lives
#: as long as the cell), five n×n matrices and a few n-vectors, 10 MB at 500 coordinates
_families: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


@dataclass(frozen=True, eq=False)
class _KeptTendons:
    """One cell's prestress family and the Voigt tendons it serves, validated once (read-only arrays).

    ``EA_in``, ``c_in``: the scalars the tendons were given as (None for arrays), so that a loop passing the same
    numbers is recognised without validating them again; arrays are recognised by their values.
    """

    key: tuple
    family: PrestressFamily | None
    EA: np.ndarray
    c: np.ndarray
    EA_in: float | None
    c_in: float | None
    law: Voigt
    H0: np.ndarray
    load: np.ndarray

    def matches(self, EA, c) -> bool:
        return _same(EA, self.EA_in, self.EA) and _same(c, self.c_in, self.c)

    def model(self, cell: Cell, P: float, check: bool) -> LinearModel | None:
        """The model at prestress ``P`` (N) of a member of this family: Eq. 11 rest lengths, ``K0 = P·Kp + Km``;
        None when there is no family or a member's rest length would not be positive (the general path reports it)."""
        family = self.family
        if family is None:
            return None
        d = self.EA + P * cell.T0
        if not d.min() > 0:
            return None
        l0 = cell.lengths * self.EA / d  # Eq. 11, as Voigt.rest_lengths writes it
        # every field is known valid: set them without the frozen dataclass's field-by-field __init__
        lin = object.__new__(LinearModel)
        lin.__dict__.update(cell=cell, P=P, EA=self.EA, c=self.c, K0=family.stiffness(P), C0=family.C0, H0=self.H0,
                            D0=np.asarray(cell.probe), l0=l0, law=self.law._placed(l0), viscosity=0.0,
                            realization=None, basis=None)
        pencil = lin.__dict__["pencil"] = Pencil(lin.K0, family.C0, self.load, lin.D0, describe=f"{cell.describe()} at "
                                                 f"P={P:.6g}", hint=_STABILITY_HINT, family=(family, P))
        if check:  # the one criterion, as Pencil.check asks it, without its wrappers (a loop's hot path)
            L = _dense_factor(lin.K0)
            if L is None:
                pencil.check()  # raises, with the model's message
            pencil.__dict__["cholesky"] = L  # kept for static solves, as Pencil.cholesky keeps it
        return lin


def _same(given, scalar: float | None, validated: np.ndarray) -> bool:
    """Whether tendon values ``given`` are those a record was validated from (a scalar, or equal array values)."""
    if type(given) in (float, int):
        return scalar is not None and given == scalar
    return type(given) is np.ndarray and given.shape == validated.shape and bool(np.array_equal(given, validated))


def _kept_tendons(cell: Cell, EA, c) -> _KeptTendons | None:
    """The cell's kept record when it serves these tendons (no validation needed), else None."""
    kept = _families.get(cell)
    return kept if kept is not None and kept.matches(EA, c) else None


def _prestress_family(cell: Cell, EA: np.ndarray, c: np.ndarray, EA_in=None, c_in=None) -> PrestressFamily | None:
    """C0 whitened once for every prestress of these Voigt tendons (EA in N, c in N·s/m), for a dense cell its
    supports hold; None for a sparse or free-standing cell or a C0 the conditioning rule refuses (the model's own K0
    path)."""
    if cell.sparse or cell.n > _FAMILY_MAX_N or deformation_basis(cell) is not None:
        return None
    key = (EA.tobytes(), c.tobytes())
    kept = _families.get(cell)
    if kept is not None and kept.key == key:
        return kept.family
    family = PrestressFamily.build(cell.Kp, spring_stiffness(cell, EA), assemble_damping(cell, c), cell.load,
                                   cell.probe)
    EA_r, c_r = np.array(EA, dtype=float), np.array(c, dtype=float)
    load = np.array(cell.load, dtype=float)
    H0 = -load
    for arr in (EA_r, c_r, H0, load):
        arr.flags.writeable = False
    _families[cell] = _KeptTendons(key=key, family=family, EA=EA_r, c=c_r, law=Voigt._trusted(EA=EA_r, c=c_r), H0=H0,
                                   load=load,
                                   EA_in=EA_in if type(EA_in) in (float, int) else None,
                                   c_in=c_in if type(c_in) in (float, int) else None)
    return family


@hot_path
def linearize_tangent(cell: Cell, P: float, k, c=1.0, *, l0=None, check: bool = True) -> LinearModel:
    """Linearize with given tangent stiffnesses ``k_j = dT_j/dl_j`` of the members at the reference.

    The law is :class:`tenscell.laws.LinearSpring` (stiffness ``k`` in N/m at
    any tension): ``K0 = P·Σ T0_j ∇²l_j + Σ k_j a_j a_jᵀ``. With
    ``k_j = (EA_j + P·T0_j)/l_j`` (the Voigt spring with the rest lengths of
    Eq. 11) this is exactly :func:`linearize`. For a law of your own, prefer
    :func:`linearize_law`, which also gives exact prestress derivatives.

    Parameters
    ----------
    cell : Cell
    P : float
        Prestress scale (N), > 0: tensions ``P·T0``.
    k : array_like, shape (m,)
        Tangent stiffness of each member at its reference tension (N/m), > 0.
    c : float or array_like, shape (m,)
        Damping (N·s/m), ≥ 0: a zero marks an undamped member (C0 may then be
        singular; :func:`tenscell.compliance` uses direct solves).
    l0 : array_like, shape (m,), optional
        Rest lengths of the members' laws (m), stored for reference. Default:
        ``l − P·T0/k``, the rest length of the linear spring with this tangent.
    check : bool
        Verify that K0 is positive definite.

    Returns
    -------
    LinearModel
        Its ``EA`` holds the Voigt stiffness with the same tangent,
        ``k_j·l_j − P·T0_j`` (N).

    Raises
    ------
    ValueError
        For a bad ``P``, ``k``, ``c`` or ``l0``.
    NotPositiveDefiniteError
        If K0 is not positive definite.
    """
    P = positive_scalar("P (prestress)", P, "N")
    m = cell.m
    k = positive_array("k (tangent stiffness)", k, (m,), "N/m")
    c = positive_array("c", c, (m,), "N·s/m", allow_zero=True)
    if l0 is not None:
        l0 = positive_array("l0 (rest length)", l0, (m,), "m")
    return _from_law(cell, P, LinearSpring._trusted(k=k, c=c), check=check, l0=l0)


def linearize_law(cell: Cell, law, P: float | None = None, *, check: bool = True, viscosity: float = 0.0,
                  band_hz=None, tol: float | None = None) -> LinearModel:
    """The linear model of a cell with any tendon law, about its reference at rest.

    ``K0 = Σ T_j ∇²l_j + Σ k_j a_j a_jᵀ`` and ``C0 = Σ c_j a_j a_jᵀ`` with the
    law's tangent stiffness ``k_j = ∂T_j/∂l_j`` and tangent damping
    ``c_j = ∂T_j/∂l'_j`` at rest (:meth:`tenscell.laws.TendonLaw.tangent_at_rest`;
    for a power-law dashpot with β > 1 that is 0, so ``C0 = 0`` and ``G'' = 0``).
    With ``T = P·T0`` this is ``K0 = P·Kp + Σ (k_j − P·T0_j/l_j) a_j a_jᵀ``.

    Parameters
    ----------
    cell : Cell
    law : TendonLaw
        One entry per tendon (see :mod:`tenscell.laws`).
    P : float, optional
        Prestress (N): linearize at tensions ``P·T0``, the law's rest lengths
        following from its inverse. Default: use the law's own rest lengths
        (``law.l0``, e.g. from :func:`tenscell.laws.voigt_law`), which must
        hold the cell in equilibrium at its reference; ``P`` is then the
        projection of those tensions on ``T0``.
    check : bool
        Verify that K0 is positive definite.
    viscosity : float
        Cytoplasm viscosity η (Pa·s), ≥ 0, in parallel with the structure
        (see :attr:`LinearModel.viscosity`).
    band_hz, tol
        For a law with internal dynamics only (``law.dynamic``): the band (Hz)
        and relative tolerance of its internal-variable realization
        (:func:`tenscell.linear.linearize.realize`; exact for Maxwell and the
        standard linear solid, a Prony series for the springpot). Needs ``P``;
        ignored for rate-linear laws, whose linearization is exact.

    Returns
    -------
    LinearModel
        ``EA`` holds the Voigt stiffness with the same tangent, ``k·l − T``
        (N); ``c`` the tangent damping (N·s/m); ``law`` the law, placed.

    Raises
    ------
    LinearizationError
        If the law has no linearization at rest (power-law dashpot, β < 1).
    ValueError
        If the law's rest lengths do not hold the cell in equilibrium at its reference.
    NotPositiveDefiniteError
        If K0 is not positive definite.
    """
    if not isinstance(law, TendonLaw):
        raise ValueError(f"law must be a tenscell.laws.TendonLaw, got {type(law).__name__}")
    if law.m is not None and law.m != cell.m:
        raise ValueError(f"the tendon law has {law.m} tendons but the cell has {cell.m}")
    if law.dynamic:
        if P is None:
            raise DynamicLawError(f"a {type(law).__name__} law has internal dynamics: pass the prestress P to "
                                  "linearize_law (its realization is built at tensions P·T0)")
        return realize(cell, law, P, band_hz=band_hz, tol=tol, viscosity=viscosity, check=check)
    if viscosity:
        return with_cytoplasm(linearize_law(cell, law, P, check=check), viscosity)
    if P is not None:
        return _from_law(cell, positive_scalar("P (prestress)", P, "N"), law, check=check)
    T = np.asarray(law.elastic(cell.lengths), dtype=float)
    # tolerance relative to the tensions and to their round-off: T = EA(l/l0 − 1) carries an error of
    # order eps·k·l ≈ eps·EA, which dominates for stiff tendons at a small prestress (a fitted cell)
    k = np.asarray(law.tangent_at_rest(cell.lengths, T)[0], dtype=float)
    absA = abs(cell.A)
    resid = np.abs(cell.A @ T)
    bound = absA @ (1e-8 * np.abs(T) + 16 * np.finfo(float).eps * np.abs(k) * cell.lengths)
    if np.any(resid > bound):
        i = int(np.argmax(resid - bound))
        raise ValueError(
            f"the tendon law's rest lengths do not hold {cell.describe()} in equilibrium at its reference "
            f"(|A·T| = {resid[i]:.3g} N at coordinate {i}, tolerance {bound[i]:.3g} N); place it with "
            "law.at_prestress(cell, P) (voigt_law and power_dashpot_law do)"
        )
    T0 = cell.T0
    P = float(T @ T0 / (T0 @ T0))
    return _from_law(cell, P, law, check=check, T=T, own=True)


def _from_law(cell: Cell, P: float, law, *, check: bool, T=None, EA=None, l0=None, own: bool = False,
              family: PrestressFamily | None = None) -> LinearModel:
    """The one assembly of (K0, C0) from a law's tangents at tensions ``T`` (default ``P·T0``).

    ``own``: the law is already placed (its rest lengths give ``T``) and is kept as it is. ``family``: the
    :class:`PrestressFamily` of these tendons, whose one whitening of C0 gives the model's modes.
    """
    l = cell.lengths
    TP = P * cell.T0
    if T is None or np.abs(T - TP).max() <= 1e-12 * np.abs(TP).max():
        T = TP
    if own:
        (k, c), l0 = law.tangent_at_rest(l, T), law.l0
    else:
        l0_law, k, c = law._reference(l, T)
        l0 = l0_law if l0 is None else l0
    k, c = np.asarray(k, dtype=float), np.asarray(c, dtype=float)
    if not np.isfinite(k.sum() + c.sum()):  # a NaN or ±inf in either makes the sum non-finite
        raise ValueError("the tendon law gave a non-finite tangent stiffness or damping at the reference")
    if T is not TP:  # a self-stress other than P·T0 (several self-stress states): assemble its Hessian term
        family, K0 = None, tangent_stiffness(cell.geometry, T, k)
    elif family is not None:  # K0 = P·Kp + Km, and C0, from the family of these tendons
        K0 = family.stiffness(P)
    else:
        K0 = assemble_stiffness(cell, P, k)
    placed = law if own else law._placed(l0)
    lin = LinearModel(
        cell=cell, P=P, EA=EA if EA is not None else k * l - T, c=c, K0=K0,
        C0=assemble_damping(cell, c) if family is None else family.C0,
        H0=-np.asarray(cell.load), D0=np.asarray(cell.probe), l0=np.asarray(l0, dtype=float), law=placed,
        basis=None if sp.issparse(K0) else deformation_basis(cell),  # free-standing: rigid-body motions removed
    )
    if family is not None:
        lin.__dict__["pencil"] = lin._new_pencil(family)
    if check:
        lin.pencil.check()
    return lin


# ---- laws with internal dynamics and the cytoplasm ------------------------------------------------------
def with_cytoplasm(lin, viscosity: float):
    """The linear model with a Newtonian cytoplasm η (Pa·s) in parallel: C0 += 2Lη·D0ᵀD0 (``G* += iωη``)."""
    eta = viscosity_value(viscosity)
    if eta == lin.viscosity:
        return lin
    n = lin.cell.n
    extra = (eta - lin.viscosity) * cytoplasm_damping(lin.cell, 1.0)
    if lin.K0.shape[0] > n:  # a realized model: the cytoplasm acts on the structure's coordinates only
        extra = sp.block_diag([extra, sp.csr_matrix((lin.K0.shape[0] - n,) * 2)]).tocsr() if sp.issparse(lin.C0) \
            else np.pad(extra, (0, lin.K0.shape[0] - n))
    lin2 = dataclasses.replace(lin, C0=lin.C0 + extra, viscosity=eta)
    lin2.__dict__.pop("pencil", None)
    return lin2


def _augmented(cell: Cell, P: float, R: Realization):
    """``(K, C)`` of the realized pencil (:mod:`tenscell.linear.dynamic`), dense or sparse like the cell."""
    A = cell.A
    Kq = assemble_stiffness(cell, P, R.k)
    Cq = assemble_damping(cell, R.c)
    if cell.sparse:
        B = sp.csr_matrix(A)[:, R.tendon]
        G = sp.diags(R.arm_k)
        K = sp.bmat([[Kq + B @ G @ B.T, -(B @ G)], [-(G @ B.T), G]]).tocsr()
        C = sp.bmat([[Cq, None], [None, sp.diags(R.arm_c)]]).tocsr()
        return K, C
    B = np.asarray(A)[:, R.tendon]
    BG = B * R.arm_k
    K = np.block([[Kq + BG @ B.T, -BG], [-BG.T, np.diag(R.arm_k)]])
    C = np.block([[Cq, np.zeros((cell.n, R.r))], [np.zeros((R.r, cell.n)), np.diag(R.arm_c)]])
    return K, C


@hot_path
def realize(cell: Cell, law: TendonLaw, P: float, *, band_hz=None, tol: float | None = None, viscosity: float = 0.0,
            check: bool = True):
    """The linear model of a cell whose tendon law has internal dynamics, with internal variables.

    Maxwell and standard-linear-solid tendons are realized exactly (one
    internal variable per tendon); springpots by a Prony series accurate to
    ``tol`` (relative, in k*) over ``band_hz``
    (:meth:`tenscell.laws.Springpot.realization`). The frequency domain of
    the returned model (``tenscell.compliance``, ``tenscell.moduli``) uses the
    exact kernel, not the realization; the time domain (creep, relaxation,
    the retardation spectrum) uses the realized pencil.

    Parameters
    ----------
    cell : Cell
    law : TendonLaw
    P : float
        Prestress scale (N).
    band_hz : (float, float), optional
        Band (Hz) of an approximate realization; default the paper's 10⁻² to 10³ Hz.
    tol : float, optional
        Its relative accuracy (default :data:`tenscell.laws.base.DEFAULT_REALIZATION_TOL` = 1e-3).
    viscosity : float
        Cytoplasm viscosity η (Pa·s), see :func:`with_cytoplasm`.
    check : bool
        Verify that the realized K is positive definite (the relaxed static state is stable).

    Returns
    -------
    LinearModel
        With ``realization`` set; K0, C0 of size ``n + realization.r``.
    """
    P = positive_scalar("P (prestress)", P, "N")
    if law.m is not None and law.m != cell.m:
        raise ValueError(f"the tendon law has {law.m} tendons but the cell has {cell.m}")
    l, T = cell.lengths, P * cell.T0
    R = law.realization(l, T, band_hz, DEFAULT_REALIZATION_TOL if tol is None else positive_scalar("tol", tol))
    K, C = _augmented(cell, P, R)
    z = np.zeros(R.r)
    if "EA" in law.names and not np.isnan(vals := law.parameter_values(cell.m)[law.names.index("EA")]).any():
        EA = vals
    else:
        EA = R.k * l - T
    placed = law.at_prestress(cell, P)
    N = None if sp.issparse(K) else deformation_basis(cell)
    # free-standing: a rigid-body motion stretches no tendon, so no arm moves with it: the motions are (R, 0)
    basis = None if N is None else scipy.linalg.block_diag(N, np.eye(R.r))
    lin = LinearModel(cell=cell, P=P, EA=EA, c=R.c, K0=K, C0=C, H0=np.concatenate([-np.asarray(cell.load), z]),
                      D0=np.concatenate([np.asarray(cell.probe), z]), l0=np.asarray(placed.l0, dtype=float),
                      law=placed, realization=R, basis=basis)
    lin = with_cytoplasm(lin, viscosity)
    if check:
        try:
            lin.pencil.check()
        except NotPositiveDefiniteError:
            raise NotPositiveDefiniteError(
                f"the relaxed static stiffness of {cell.describe()} with {type(law).__name__} tendons at P={P:.6g} N "
                f"is not positive definite: the reference is not a stable equilibrium. {_STABILITY_HINT}") from None
    return lin

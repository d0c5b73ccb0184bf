"""Different laws on different tendons: :class:`CompositeLaw` and :func:`family_laws`."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from .._checks import positive_array
from ..model.equilibrium import Cell
from .base import DEFAULT_REALIZATION_TOL, Realization, Tangent, TendonLaw, _refs, angular_frequencies, laplace_variables

__all__ = ["CompositeLaw", "family_laws"]


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
    def dynamic(self) -> bool:  # type: ignore[override]  # per instance here, a class constant elsewhere
        """Some part has a frequency-dependent tangent."""
        return any(law.dynamic for law in self.laws)

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


    def realization(self, l, T, band_hz=None, tol: float = DEFAULT_REALIZATION_TOL) -> Realization:
        """Each part's realization on its tendons (error: the largest of the parts')."""
        l, T = _refs(l, T)
        k, c = np.empty(self.m), np.empty(self.m)
        tendon, ak, ac, err, band = [], [], [], 0.0, None
        for law, i in zip(self.laws, self.indices):
            r = law.realization(l[i], T[i], band_hz, tol)
            k[i], c[i] = r.k, r.c
            tendon.append(i[r.tendon])
            ak.append(r.arm_k)
            ac.append(r.arm_c)
            err, band = max(err, r.error), (r.band_hz or band)
        return Realization(k=k, c=c, tendon=np.concatenate(tendon).astype(int), arm_k=np.concatenate(ak),
                           arm_c=np.concatenate(ac), error=err, band_hz=band)

    def _each_part(self, method: str, l, T, z) -> np.ndarray:
        """Each part's ``method(l, T, z)`` (a dynamic tangent, shape ``(z.size, m_part)``) on its tendons."""
        l, T = _refs(l, T)
        out = np.empty((z.size, self.m), dtype=complex)
        for law, i in zip(self.laws, self.indices):
            out[:, i] = getattr(law, method)(l[i], T[i], z)
        return out

    def complex_stiffness(self, l, T, omega) -> np.ndarray:
        """Each part's dynamic tangent on its tendons (N/m), shape ``(n_omega, m)``."""
        return self._each_part("complex_stiffness", l, T, angular_frequencies(omega))

    def laplace_stiffness(self, l, T, s) -> np.ndarray:
        """Each part's ``k*(s)`` on its tendons (N/m), shape ``(n_s, m)``."""
        return self._each_part("laplace_stiffness", l, T, laplace_variables(s))

    def complex_stiffness_derivatives(self, l, T, omega) -> tuple[np.ndarray, np.ndarray]:
        """Each part's ``(∂k*/∂T, ∂k*/∂θ)`` assembled on the union of names (0 where a tendon lacks θ)."""
        return self._each_derivative("complex_stiffness_derivatives", l, T, angular_frequencies(omega))

    def laplace_stiffness_derivatives(self, l, T, s) -> tuple[np.ndarray, np.ndarray]:
        """Each part's ``(∂k*/∂T, ∂k*/∂θ)`` at Laplace variables ``s``, on the union of names."""
        return self._each_derivative("laplace_stiffness_derivatives", l, T, laplace_variables(s))

    def _each_derivative(self, method: str, l, T, z) -> tuple[np.ndarray, np.ndarray]:
        l, T = _refs(l, T)
        names = self.names
        dT = np.empty((z.size, self.m), dtype=complex)
        dk = np.zeros((len(names), z.size, self.m), dtype=complex)
        for law, i in zip(self.laws, self.indices):
            sub_T, sub = getattr(law, method)(l[i], T[i], z)
            dT[:, i] = sub_T
            for r, n in enumerate(law.names):
                dk[names.index(n)][:, i] = sub[r]
        return dT, dk


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


"""Frequency response: J(ω, P), G'(f, P), G''(f, P) (paper Eqs. 15–16).

Convention, used everywhere in tenscell: frequencies enter and leave the API
as ``f`` in hertz; internally ``ω = 2π·f`` (rad/s).

``J(ω) = −D0 (K0 + iωC0)⁻¹ H0`` (m/N) and ``G' + iG'' = (0.5/L)/J`` (Pa), the
paper's equivalent-continuum factor with strut length L.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ._checks import positive_array
from .model.equilibrium import Cell
from .linear.krylov import factorize_stiffness, krylov_compliance
from .linear.linearize import LinearModel, _cholesky_or_none, _spectrum_or_none, linearize

__all__ = [
    "compliance",
    "moduli",
    "FrequencyResponse",
    "frequency_response",
    "static_modulus",
    "viscosity_limit",
    "loss_tangent",
    "log_slope",
]


def _frequencies(f_hz) -> np.ndarray:
    return positive_array("frequency", f_hz, unit="Hz")


def _c0_positive_definite(lin: LinearModel) -> bool:
    return not sp.issparse(lin.C0) and _cholesky_or_none(lin.C0) is not None


def compliance(lin: LinearModel, f_hz) -> np.ndarray:
    """Transfer function ``J = z1/F1`` (m/N) at frequencies ``f_hz`` (Hz).

    Through the relaxation spectrum when C0 is positive definite, by direct
    complex solves otherwise (singular C0); sparse models (more than
    ``SPARSE_THRESHOLD`` coordinates) use one factorization and a shifted
    Lanczos iteration (:func:`tenscell.linear.krylov.krylov_compliance`, relative
    accuracy 1e-12).

    Parameters
    ----------
    lin : LinearModel
    f_hz : float or array_like
        Frequencies (Hz), > 0.

    Returns
    -------
    ndarray of complex, same shape as ``f_hz``
    """
    f = _frequencies(f_hz)
    w = 2 * np.pi * f.ravel()
    spec = _spectrum_or_none(lin)
    if spec is not None:
        lam, r = spec.rates, spec.residues
        # Σ r/(λ + iω) in real arithmetic: one (2 × n)(n × nf) product gives both parts
        den = np.add.outer(lam * lam, w * w)
        np.reciprocal(den, out=den)
        re, im = np.stack([r * lam, r]) @ den
        J = re - 1j * (w * im)
    else:
        J = _direct(lin, w)
    return J.reshape(f.shape)


def _direct(lin: LinearModel, w: np.ndarray) -> np.ndarray:
    b = -lin.H0
    if sp.issparse(lin.K0):
        # large models: one factorization and a shifted Lanczos run for all frequencies (tenscell.linear.krylov)
        return krylov_compliance(lin, w / (2 * np.pi)).J
    Z = lin.K0[None, :, :] + 1j * w[:, None, None] * lin.C0[None, :, :]
    x = np.linalg.solve(Z, np.broadcast_to(b.astype(complex), (w.size, b.size))[..., None])[..., 0]
    return x @ lin.D0


def moduli(lin: LinearModel, f_hz) -> tuple[np.ndarray, np.ndarray]:
    """Storage and loss moduli ``G'``, ``G''`` (Pa) at frequencies ``f_hz`` (Hz).

    ``G' + iG'' = (0.5/L)/J``.
    """
    G = (0.5 / lin.L) / compliance(lin, f_hz)
    return G.real, G.imag


def static_modulus(lin: LinearModel) -> float:
    """Low-frequency limit ``G'(f→0) = (0.5/L)/(D0 K0⁻¹ (−H0))`` (Pa)."""
    K0 = lin.K0
    x = factorize_stiffness(lin).solve(-lin.H0) if sp.issparse(K0) else np.linalg.solve(K0, -lin.H0)
    return float((0.5 / lin.L) / (lin.D0 @ x))


def viscosity_limit(lin: LinearModel) -> float:
    """High-frequency limit ``G''/ω → (0.5/L)/(D0 C0⁻¹ (−H0))`` (Pa·s); needs C0 positive definite."""
    if not _c0_positive_definite(lin):
        raise ValueError("C0 is singular: G''/ω has no finite high-frequency limit")
    return float((0.5 / lin.L) / (lin.D0 @ np.linalg.solve(lin.C0, -lin.H0)))


def loss_tangent(G_storage, G_loss) -> np.ndarray:
    """Loss tangent ``η = G''/G'`` (dimensionless)."""
    return np.asarray(G_loss) / np.asarray(G_storage)


def log_slope(f_hz, G) -> np.ndarray:
    """Local power-law exponent ``d ln G / d ln f`` along the last axis (second-order differences)."""
    return np.gradient(np.log(np.asarray(G)), np.log(np.asarray(f_hz)), axis=-1)


@dataclass(frozen=True, eq=False, repr=False)
class FrequencyResponse:
    """Compliance and moduli over a grid of prestresses × frequencies.

    Attributes
    ----------
    frequency_hz : ndarray, shape (nf,)
        Frequencies (Hz).
    prestress : ndarray, shape (nP,)
        Prestresses P (N).
    J : ndarray of complex, shape (nP, nf)
        Compliance (m/N).
    L : float
        Strut length of the cell (m).
    """

    frequency_hz: np.ndarray
    prestress: np.ndarray
    J: np.ndarray
    L: float

    @property
    def G(self) -> np.ndarray:
        """Complex modulus ``G' + iG''`` (Pa), shape (nP, nf)."""
        return (0.5 / self.L) / self.J

    @property
    def G_storage(self) -> np.ndarray:
        """Storage modulus G' (Pa), shape (nP, nf)."""
        return self.G.real

    @property
    def G_loss(self) -> np.ndarray:
        """Loss modulus G'' (Pa), shape (nP, nf)."""
        return self.G.imag

    @property
    def loss_tangent(self) -> np.ndarray:
        """G''/G' (dimensionless), shape (nP, nf)."""
        return loss_tangent(self.G_storage, self.G_loss)

    def slopes(self) -> tuple[np.ndarray, np.ndarray]:
        """Local log-log slopes ``d ln G'/d ln f`` and ``d ln G''/d ln f``, shape (nP, nf)."""
        return log_slope(self.frequency_hz, self.G_storage), log_slope(self.frequency_hz, self.G_loss)

    def rows(self):
        """Yield ``(P, f, G', G'')`` tuples in prestress-major order (for CSV output)."""
        Gs, Gl = self.G_storage, self.G_loss
        for i, P in enumerate(self.prestress):
            for k, f in enumerate(self.frequency_hz):
                yield float(P), float(f), float(Gs[i, k]), float(Gl[i, k])

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from ._results import format_repr, span

        nP, nf = self.J.shape
        return format_repr(
            f"FrequencyResponse: {nP} prestress(es) × {nf} frequencies",
            f"f {span(self.frequency_hz, 'Hz')}; P {span(self.prestress, 'N')}; L = {self.L:.4g} m",
            f"G' {span(self.G_storage, 'Pa')}; G'' {span(self.G_loss, 'Pa')}",
        )

    def to_dataframe(self):
        """Long format, one row per (P, f): ``prestress_N, frequency_Hz, G_storage_Pa, G_loss_Pa, loss_tangent``.

        ``df.pivot(index="frequency_Hz", columns="prestress_N", values="G_storage_Pa")``
        gives the grid back.
        """
        from ._results import dataframe

        nP, nf = self.J.shape
        return dataframe({
            "prestress_N": np.repeat(self.prestress, nf), "frequency_Hz": np.tile(self.frequency_hz, nP),
            "G_storage_Pa": self.G_storage.ravel(), "G_loss_Pa": self.G_loss.ravel(),
            "loss_tangent": self.loss_tangent.ravel(),
        }, {"L_m": self.L})

    def plot(self, axes=None, x: str = "frequency", **kw):
        """G' and G'' on a pair of axes: against frequency (log-log, one curve per P) or prestress.

        Parameters
        ----------
        axes : pair of Axes, optional
        x : {"frequency", "prestress"}
        **kw
            Passed to :func:`tenscell.plotting.moduli_vs_frequency` or
            :func:`~tenscell.plotting.moduli_vs_prestress` (``title``, ``legend``, line styles).

        Returns
        -------
        ndarray of two Axes
        """
        from . import plotting

        if x not in ("frequency", "prestress"):
            raise ValueError(f"x: expected 'frequency' or 'prestress', got {x!r}")
        draw = plotting.moduli_vs_frequency if x == "frequency" else plotting.moduli_vs_prestress
        return draw(self, axes, **kw)


def frequency_response(cell: Cell, f_hz, P, EA=1.0, c=1.0) -> FrequencyResponse:
    """Compliance and moduli for arrays of prestresses and frequencies in one call.

    Parameters
    ----------
    cell : Cell
    f_hz : array_like, shape (nf,)
        Frequencies (Hz), > 0.
    P : float or array_like, shape (nP,)
        Prestresses (N), > 0.
    EA, c : float or array_like, shape (m,)
        Tendon stiffness (N) and damping (N·s/m).

    Returns
    -------
    FrequencyResponse
    """
    f = np.atleast_1d(_frequencies(f_hz)).ravel()
    Ps = np.atleast_1d(positive_array("P (prestress)", P, unit="N")).ravel()
    J = np.stack([compliance(linearize(cell, P=p, EA=EA, c=c), f) for p in Ps])
    return FrequencyResponse(frequency_hz=f, prestress=Ps, J=J, L=cell.strut_length)

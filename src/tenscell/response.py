"""Frequency response: J(ω, P), G'(f, P), G''(f, P) (paper Eqs. 15–16).

Convention, used everywhere in tenscell: frequencies enter and leave the API
as ``f`` in hertz; internally ``ω = 2π·f`` (rad/s).

``J(ω) = −D0 (K0 + iωC0)⁻¹ H0`` (m/N) and ``G' + iG'' = (0.5/L)/J`` (Pa), the
paper's equivalent-continuum factor with strut length L.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._checks import positive_array
from .model.equilibrium import Cell
from .linear.krylov import krylov_compliance
from .linear.linearize import LinearModel, linearize
from .linear.assembly import assemble_damping, continuum_factor, modulus, spring_stiffness
from .linear.family import prestress_grid_compliance
from .linear.spectrum import modal_compliance
from ._threads import hot_path

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


def _voigt(cell: Cell, EA, c):
    from .laws import Voigt

    return Voigt(EA=positive_array("EA", EA, (cell.m,), "N"), c=positive_array("c", c, (cell.m,), "N·s/m"))


def _frequencies(f_hz) -> np.ndarray:
    return positive_array("frequency", f_hz, unit="Hz")


@hot_path
def compliance(lin: LinearModel, f_hz) -> np.ndarray:
    """Transfer function ``J = z1/F1`` (m/N) at frequencies ``f_hz`` (Hz).

    Dense models: the modal sum ``Σ ρ_k/(1 + iωτ_k)`` of the model's one
    modal decomposition (cached on ``lin.pencil``; exact also for singular
    C0). Sparse models (more than ``SPARSE_THRESHOLD`` coordinates): the
    model's one shifted factorization and Lanczos run
    (:func:`tenscell.linear.krylov.krylov_compliance`, relative accuracy 1e-12).

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
    if lin.realization is not None:  # a law with internal dynamics: its exact tangent, not the realization
        from .linear.dynamic import exact_compliance

        return exact_compliance(lin, f)
    if lin.pencil.sparse:
        return krylov_compliance(lin, f).J
    m = lin.pencil.modes
    return modal_compliance(m.tau, m.weights, 2 * np.pi * f.ravel()).reshape(f.shape)


@hot_path
def moduli(lin: LinearModel, f_hz) -> tuple[np.ndarray, np.ndarray]:
    """Storage and loss moduli ``G'``, ``G''`` (Pa) at frequencies ``f_hz`` (Hz).

    ``G' + iG'' = (0.5/L)/J``.
    """
    G = modulus(compliance(lin, f_hz), lin.L)
    return G.real, G.imag


@hot_path
def static_modulus(lin: LinearModel) -> float:
    """Low-frequency limit ``G'(f→0) = (0.5/L)/(D0 K0⁻¹ (−H0))`` (Pa)."""
    return float(modulus(lin.pencil.static_compliance(), lin.L))


@hot_path
def viscosity_limit(lin: LinearModel) -> float:
    """High-frequency limit ``G''/ω → (0.5/L)/(D0 C0⁻¹ (−H0))`` (Pa·s); needs C0 positive definite.

    ``D0 C0⁻¹ b = Σ ρ_k/τ_k`` over the model's retardation spectrum (dense or sparse).
    """
    from .linear.spectrum import ZERO_TIME

    if lin.realization is not None:
        from .laws import DynamicLawError

        raise DynamicLawError(f"the {type(lin.law).__name__} tendons have internal dynamics: G''/ω of the exact law tends to "
                         f"the cytoplasm's viscosity ({lin.viscosity:g} Pa·s) alone, its realization's C0 is not that law's "
                         "high-frequency limit; evaluate moduli(lin, f) at the frequencies you need")
    tau, rho, _ = lin.pencil.retardation()
    if tau.size == 0 or tau.min() <= ZERO_TIME * tau.max():
        raise ValueError("C0 is singular: G''/ω has no finite high-frequency limit")
    return float(modulus(np.sum(rho / tau), lin.L))


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
    viscosity : float
        Cytoplasm viscosity η (Pa·s) in parallel with the structure, included in ``J``
        (``G = (0.5/L)/J = G_structure + iωη``); 0 for none.
    """

    frequency_hz: np.ndarray
    prestress: np.ndarray
    J: np.ndarray
    L: float
    viscosity: float = 0.0

    @property
    def G(self) -> np.ndarray:
        """Complex modulus ``G' + iG''`` (Pa), shape (nP, nf), the cytoplasm included."""
        return modulus(self.J, self.L)

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

    def _repr_html_(self) -> str:
        from ._results import reporter

        return reporter("frequency_response_html")(self)  # the grid and G', G'' at three frequencies

    def to_xarray(self):
        """The grid as an ``xarray.Dataset`` (dims ``prestress`` in N, ``frequency`` in Hz; ``J_real``, ``J_imag``
        in m/N (the compliance's real and imaginary parts: every netCDF engine writes them), ``G_storage``,
        ``G_loss`` in Pa, ``loss_tangent``); xarray is optional (``pip install 'tenscell[exchange]'``).
        :meth:`from_xarray` reads it back exactly."""
        return _to_xarray(self)

    @classmethod
    def from_xarray(cls, ds) -> "FrequencyResponse":
        """The response a :meth:`to_xarray` dataset holds (or one with a complex ``J``)."""
        return _from_xarray(cls, ds)

    def to_netcdf(self, path) -> None:
        """Write :meth:`to_xarray` to the netCDF file ``path`` with the best engine installed (h5netcdf, netCDF4,
        or scipy's netCDF-3 writer, which comes with tenscell's core); needs xarray (``tenscell[exchange]``)."""
        from ._optional import netcdf_engine

        self.to_xarray().to_netcdf(path, engine=netcdf_engine())

    @classmethod
    def from_netcdf(cls, path) -> "FrequencyResponse":
        """The response a :meth:`to_netcdf` file holds (exactly: float64 real and imaginary parts)."""
        from ._optional import require

        with require("xarray").open_dataset(path) as ds:
            return _from_xarray(cls, ds.load())

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
        }, {"L_m": self.L, "viscosity_Pa_s": self.viscosity})

    def plot(self, ax=None, x: str = "frequency", *, axes=None, **kw):
        """G' and G'' on a pair of axes: against frequency (log-log, one curve per P) or prestress.

        Parameters
        ----------
        ax : pair of Axes, optional
            Where to draw G' and G'' (``axes=`` is the older spelling); default a new figure.
        x : {"frequency", "prestress"}
        **kw
            Passed to :func:`tenscell.plotting.moduli_vs_frequency` or
            :func:`~tenscell.plotting.moduli_vs_prestress` (``title``, ``legend``, line styles).

        Returns
        -------
        ndarray of two Axes
        """
        from ._results import plotter

        if x not in ("frequency", "prestress"):
            raise ValueError(f"x: expected 'frequency' or 'prestress', got {x!r}")
        return plotter("moduli_vs_frequency" if x == "frequency" else "moduli_vs_prestress")(
            self, ax if ax is not None else axes, **kw)


def _to_xarray(resp):
    """A :class:`FrequencyResponse` as an ``xarray.Dataset`` (:meth:`FrequencyResponse.to_xarray`)."""
    from ._optional import require

    xr = require("xarray")
    dims = ("prestress", "frequency")
    return xr.Dataset(
        data_vars={
            # real and imaginary parts: netCDF-3 (scipy's writer, always installed) has no complex type
            "J_real": (dims, np.asarray(resp.J).real, {"units": "m/N", "long_name": "compliance J(omega), real part"}),
            "J_imag": (dims, np.asarray(resp.J).imag, {"units": "m/N",
                                                       "long_name": "compliance J(omega), imaginary part"}),
            "G_storage": (dims, resp.G_storage, {"units": "Pa", "long_name": "storage modulus G'"}),
            "G_loss": (dims, resp.G_loss, {"units": "Pa", "long_name": "loss modulus G''"}),
            "loss_tangent": (dims, resp.loss_tangent, {"units": "1", "long_name": "loss tangent G''/G'"}),
        },
        coords={"prestress": ("prestress", np.asarray(resp.prestress), {"units": "N", "long_name": "prestress P"}),
                "frequency": ("frequency", np.asarray(resp.frequency_hz), {"units": "Hz", "long_name": "frequency f"})},
        attrs={"L_m": float(resp.L), "viscosity_Pa_s": float(resp.viscosity), "source": "tenscell FrequencyResponse"},
    )


def _from_xarray(cls, ds):
    """The response a :func:`_to_xarray` dataset holds (``J_real``/``J_imag``, or a complex ``J``)."""
    parts = ("J_real", "J_imag") if "J_real" in ds.variables else ("J",)
    for name in (*parts, "prestress", "frequency"):
        if name not in ds.variables:
            raise ValueError(f"dataset: no {name!r}; expected what FrequencyResponse.to_xarray() writes")
    units = {k: ds[k].attrs.get("units") for k in (*parts, "prestress", "frequency")}
    if units != {**dict.fromkeys(parts, "m/N"), "prestress": "N", "frequency": "Hz"}:
        raise ValueError(f"dataset: units {units}; expected J m/N, prestress N, frequency Hz")
    J = [np.asarray(ds[k].transpose("prestress", "frequency").values) for k in parts]
    return cls(frequency_hz=np.asarray(ds["frequency"].values, dtype=float),
               prestress=np.asarray(ds["prestress"].values, dtype=float),
               J=(J[0] + 1j * J[1]) if len(J) == 2 else np.asarray(J[0], dtype=complex),
               L=float(ds.attrs["L_m"]), viscosity=float(ds.attrs.get("viscosity_Pa_s", 0.0)))


@hot_path
@hot_path
def frequency_response(cell: Cell, f_hz, P, EA=1.0, c=1.0, *, law=None, viscosity: float = 0.0) -> FrequencyResponse:
    """Compliance and moduli for arrays of prestresses and frequencies in one call.

    Parameters
    ----------
    cell : Cell
    f_hz : array_like, shape (nf,)
        Frequencies (Hz), > 0.
    P : float or array_like, shape (nP,)
        Prestresses (N), > 0.
    EA, c : float or array_like, shape (m,)
        Tendon stiffness (N) and damping (N·s/m) of Voigt tendons (the paper's model).
    law : TendonLaw, optional
        Any tendon law instead of Voigt(EA, c), e.g. :class:`tenscell.laws.Springpot`
        (its tangent is taken at tensions ``P·T0`` for each P; laws with internal
        dynamics through :func:`tenscell.linear.dynamic.dynamic_compliance`, exact).
    viscosity : float
        Cytoplasm viscosity η (Pa·s), ≥ 0, in parallel with the structure: ``G* += iωη``.

    Returns
    -------
    FrequencyResponse
    """
    f = np.atleast_1d(_frequencies(f_hz)).ravel()
    Ps = np.atleast_1d(positive_array("P (prestress)", P, unit="N")).ravel()
    if law is not None or viscosity:
        from .linear.dynamic import dynamic_complex_modulus, viscosity_value

        eta = viscosity_value(viscosity)
        the_law = law if law is not None else _voigt(cell, EA, c)
        G = np.stack([dynamic_complex_modulus(cell, the_law, p, f, viscosity=eta) for p in Ps])
        return FrequencyResponse(frequency_hz=f, prestress=Ps, J=continuum_factor(cell.strut_length) / G, L=cell.strut_length,
                                 viscosity=eta)
    J = None
    if not cell.sparse and Ps.size > 1:
        # K0(P) = P·Kp + Σ EA_j a_j a_jᵀ/l_j is affine in P and C0 does not depend on it: one batched eigensolve
        EA_ = positive_array("EA", EA, (cell.m,), "N")
        c_ = positive_array("c", c, (cell.m,), "N·s/m")
        J = prestress_grid_compliance(cell.Kp, spring_stiffness(cell, EA_), assemble_damping(cell, c_), cell.load,
                                      cell.probe, Ps, 2 * np.pi * f, describe=cell.describe())
    if J is None:
        J = np.stack([compliance(linearize(cell, P=p, EA=EA, c=c), f) for p in Ps])
    return FrequencyResponse(frequency_hz=f, prestress=Ps, J=J, L=cell.strut_length)

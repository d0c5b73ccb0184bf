"""What a fit of the Voigt cell gives its result: moduli anywhere, the fitted cell, the report's numbers.

:class:`VoigtResults` is the part of :class:`~tenscell.fitting.models.voigt.FitProblem` the result reads
(:class:`tenscell.fitting.problem.Problem`'s result hooks), with the prestress activity analysis
(:mod:`tenscell.fitting.prestress`).
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..._threads import hot_path
from ...linear.linearize import linearize
from ...model.equilibrium import Cell
from ..prestress import REFERENCE_FREQUENCY_HZ, PrestressActivity, prestress_activity as activity_of
from .voigt_fitted import FittedCell, scaled_cell

__all__ = ["VoigtResults", "GRID_POINTS", "prestress_activity"]

#: largest prestress × frequency grid that FitProblem.moduli_at evaluates in one batch (else per prestress)
GRID_POINTS = 200_000


class VoigtResults:
    """The result hooks of :class:`~tenscell.fitting.models.voigt.FitProblem` (a mixin: it reads the problem's
    fields, declared here for the type checker)."""

    cell: Cell
    L_ref: float
    tendons: str
    damping: str
    n_ea: int
    n_c: int
    ea_groups: np.ndarray
    c_groups: np.ndarray
    min_prestress_share: float | None
    max_decades: float | None
    min_prestress_elasticity: float | None
    elasticity_omega: float

    if TYPE_CHECKING:  # Problem's, which FitProblem also derives from (defining them here would shadow those)
        @property
        def names(self) -> tuple: ...

        @property
        def compact(self) -> bool: ...

        def values(self, theta) -> np.ndarray: ...

        def parameters(self, theta) -> tuple: ...

    # -- anywhere, and what the result reads -------------------------------------------------------
    @property
    def label(self) -> str:
        """``"heterogeneous"``, ``"per family"`` or ``"homogeneous"`` (the stiffness parametrization)."""
        return {"uniform": "homogeneous", "per-family": "per family", "per-tendon": "heterogeneous"}[self.tendons]

    def describe(self) -> str:
        return f"{self.cell.describe()}; stiffness {self.tendons}, damping {self.damping}"

    @property
    def comparison_name(self) -> str:
        return {"per-tendon": "heterogeneous tensegrity", "per-family": "tensegrity, per-family stiffness",
                "uniform": "homogeneous tensegrity"}[self.tendons]

    def tendon_values(self, theta) -> tuple[np.ndarray, np.ndarray, float]:
        """(EA (m,) in N, c (m,) in N·s/m, L in m) at the fitted strut length."""
        vals = self.values(theta)
        EA = vals[: self.n_ea][self.ea_groups]
        c = vals[self.n_ea: self.n_ea + self.n_c][self.c_groups]
        return EA, c, float(vals[-1])

    def stiffness_spread(self, theta) -> tuple[float, float, float]:
        EA = self.tendon_values(theta)[0]
        return float(EA.min()), float(EA.max()), float(math.log10(EA.max() / EA.min()))

    def stiffness_spread_interior(self, theta) -> tuple[float, float, float] | None:
        """Like :meth:`stiffness_spread`, over the tendons whose stiffness is not at a bound (None if none is)."""
        pars = self.parameters(theta)
        inside = np.array([pars[g].at_bound is None for g in self.ea_groups])
        if not inside.any():
            return None
        e = self.tendon_values(theta)[0][inside]
        return float(e.min()), float(e.max()), float(math.log10(e.max() / e.min()))

    def stiffness_at_bound(self, theta) -> bool:
        pars = self.parameters(theta)
        return any(pars[g].at_bound for g in set(self.ea_groups.tolist()))

    def stiffness_bound(self) -> tuple[float | None, bool]:
        return self.max_decades, bool(self.compact)

    def moduli_at(self, theta, f_hz, P_N) -> tuple[np.ndarray, np.ndarray]:
        """G', G'' (Pa) at ``f_hz`` (Hz) and model prestresses ``P_N`` (N, at the fitted strut length), broadcast:
        many prestresses in one batched eigensolve over the grid (up to :data:`GRID_POINTS`), else one
        linearization per prestress."""
        from ...linear.assembly import modulus
        from ...response import compliance, frequency_response

        EA, c, L = self.tendon_values(theta)
        lam = L / self.L_ref
        f, Pm = np.broadcast_arrays(np.atleast_1d(np.asarray(f_hz, dtype=float)),
                                    np.atleast_1d(np.asarray(P_N, dtype=float)))
        Pu, at_P = np.unique(Pm, return_inverse=True)
        fu, at_f = np.unique(f, return_inverse=True)
        if 1 < Pu.size and Pu.size * fu.size <= GRID_POINTS:
            J = frequency_response(self.cell, fu, Pu / lam**2, EA=EA / lam**2, c=c / lam).J
            G = modulus(J[at_P.ravel(), at_f.ravel()].reshape(f.shape), self.L_ref)
            return G.real, G.imag
        Gs, Gl = np.empty(f.shape), np.empty(f.shape)
        for P in Pu:
            sel = Pm == P
            lin = linearize(self.cell, P=float(P) / lam**2, EA=EA / lam**2, c=c / lam, check=False)
            G = modulus(compliance(lin, f[sel]), self.L_ref)
            Gs[sel], Gl[sel] = G.real, G.imag
        return Gs, Gl

    def linear_at(self, theta, P_N: float):
        """The linear model of the reference cell equivalent to the fitted cell at model prestress ``P_N`` (N).

        The fitted cell is the reference scaled by λ = L/L_ref; on the reference the equivalent properties are
        (P/λ², EA/λ², c/λ) and the moduli are identical (strut-length gauge).
        """
        EA, c, L = self.tendon_values(theta)
        lam = L / self.L_ref
        return linearize(self.cell, P=float(P_N) / lam**2, EA=EA / lam**2, c=c / lam, check=False)

    def fitted(self, theta, result):
        """The fitted cell (:class:`~tenscell.fitting.fitted.FittedCell`) at the fitted L, EA, c and prestress."""
        EA, c, L = self.tendon_values(theta)
        if "s" in self.names:  # some data set stated its prestress: P = s × prestress (Pa)
            stated = [p for f in result.fits for p in (
                np.unique(f.data.prestress) if f.data.prestress is not None else [f.prestress_fitted_pa])
                if p is not None]
            pre = {"s": float(self.values(theta)[self.names.index("s")]),
                   "prestress_pa": tuple(float(p) for p in stated)}
        else:
            pre = {"P": float(result.prestress_model(dataset=result.single_prestress_dataset())[0])}
        return FittedCell(cell=scaled_cell(self.cell, L), EA=EA, c=c, tendons=self.tendons, damping=self.damping,
                          source=" + ".join(d.source for d in result.datasets), **pre)

    def prestress_activity(self, result, reference_frequency_hz: float = REFERENCE_FREQUENCY_HZ):
        """Is the prestress doing anything? (:mod:`tenscell.fitting.prestress`)."""
        return prestress_activity(result, reference_frequency_hz)

    def report_quantities(self, result) -> dict:
        """Every number the Voigt fit's report derives from the parameters, as flat arrays.

        The shape (:func:`~tenscell.fitting.curves.shape_quantities`); ``prestress_share`` and
        ``prestress_storage`` (min, max over the data points of the share of the static stiffness carried by
        P·Kp and of ∂lnG'/∂lnP), ``reference_prestress_N`` (N), ``reference_storage``, ``reference_loss``,
        ``reference_share`` (per prestress at the reference frequency), ``creep_A`` (1/Pa), ``creep_alpha``,
        ``creep_J`` (1/Pa) and ``creep_exponent`` (at the predicted creep's times), ``creep_prestress_N`` (N, the
        prestress the creep is predicted at), ``creep_window_slope`` (min, max of the G' slope over the
        frequencies 1/(2πt) of the creep window), and ``stiffness_spread`` (min EA, max EA in N, decades).
        """
        from ..curves import frequency_slopes, shape_quantities

        out = shape_quantities(result)
        pa = activity_of(result)
        summary = pa.to_dict()
        out["prestress_share"] = np.array([summary["share_min"], summary["share_max"]])
        out["prestress_storage"] = np.array([summary["dlnGstorage_dlnP"]["min"], summary["dlnGstorage_dlnP"]["max"]])
        for name in ("prestress_N", "storage", "loss", "share"):
            out[f"reference_{name}"] = np.asarray(getattr(pa, f"reference_{name}"), dtype=float)
        creep = result.predicted_creep()
        out.update(creep_A=np.array([creep.A]), creep_alpha=np.array([creep.alpha]), creep_J=creep.J,
                   creep_exponent=creep.exponent, creep_prestress_N=np.array([creep.prestress_N]))
        lo, hi = creep.window
        _, s1, _ = frequency_slopes(result, 1 / (2 * math.pi * hi), 1 / (2 * math.pi * lo), 200)
        out["creep_window_slope"] = np.array([s1.min(), s1.max()])
        out["stiffness_spread"] = np.array(self.stiffness_spread(result.theta))
        return out

    def summary(self, result) -> dict:
        lo, hi, dec = self.stiffness_spread(result.theta)
        inner = self.stiffness_spread_interior(result.theta)
        return {
            "tendons": self.tendons, "damping": self.damping,
            "constraints": {"min_prestress_share": self.min_prestress_share,
                            "min_prestress_elasticity": self.min_prestress_elasticity,
                            "elasticity_frequency_Hz": float(self.elasticity_omega / (2 * math.pi)),
                            "max_decades": self.max_decades},
            "tendon_stiffness_spread": {"min_N": lo, "max_N": hi, "decades": dec},
            "tendon_stiffness_spread_not_at_bounds": (
                None if inner is None else dict(zip(("min_N", "max_N", "decades"), inner))),
            "prestress_activity": activity_of(result).to_dict(),
            "predicted_creep": result.predicted_creep().to_dict(),
        }

    @property
    def report_sections(self) -> tuple:
        return ("prestress", "creep")


def _elasticity_P(result, P: float, f_hz) -> tuple[np.ndarray, np.ndarray]:
    """(∂lnG'/∂lnP, ∂lnG''/∂lnP) of the fitted cell at model prestress P (N), frequencies f_hz."""
    from ...sensitivity import analytic_elasticities

    el = analytic_elasticities(result.problem.linear_at(result.theta, P), f_hz)
    k = el.index("P")
    return el.storage[k], el.loss[k]


@hot_path
def prestress_activity(result, reference_frequency_hz: float = REFERENCE_FREQUENCY_HZ) -> PrestressActivity:
    """The prestress elasticities and share of a fit, at its data points and at a reference frequency.

    Parameters
    ----------
    result : FitResult
    reference_frequency_hz : float
        Frequency (Hz) of the per-prestress summary (default 0.1 Hz).
    """
    pr = result.problem
    P_groups = result.group_prestress()
    share_groups = pr.prestress_share(result.theta)
    f = pr.omega / (2 * np.pi)
    storage = np.empty(f.size)
    loss = np.empty(f.size)
    ref = np.empty((2, P_groups.size))
    for g, P in enumerate(P_groups):
        sel = pr.group_index == g  # a creep data set's group has no moduli points, only the reference
        # the group's points and the reference frequency in one linearization and one elasticity solve
        a, b = _elasticity_P(result, P, np.append(f[sel], reference_frequency_hz))
        storage[sel], loss[sel] = a[:-1], b[:-1]
        ref[:, g] = a[-1], b[-1]
    return PrestressActivity(
        dataset=pr.dataset_index.copy(), frequency_hz=f, prestress_model_N=P_groups[pr.group_index],
        storage=storage, loss=loss, share=share_groups[pr.group_index],
        reference_frequency_hz=float(reference_frequency_hz), reference_prestress_N=P_groups,
        reference_dataset=pr.group_dataset.copy(), reference_storage=ref[0], reference_loss=ref[1],
        reference_share=share_groups, min_share_bound=pr.min_prestress_share,
        min_elasticity_bound=pr.min_prestress_elasticity,
        elasticity_bound_frequency_hz=float(pr.elasticity_omega / (2 * np.pi)),
    )

"""Is the prestress doing anything? Prestress elasticities and the prestress share of a fitted cell.

A tensegrity model is worth fitting because its stiffness comes from its
prestress: in cells ∂ln G'/∂ln P is about 0.7 (G' proportional to the
tension). A fit can nevertheless put P at its lower bound, where the tendons'
elastic stiffness carries everything and the model is a network of Voigt
springs. For every data point this module reports, at the fitted parameters,

* ``∂ln G'/∂ln P`` and ``∂ln G''/∂ln P`` (exact, from
  :func:`tenscell.sensitivity.analytic_elasticities` on the fitted linear
  model), and
* the share of the static stiffness carried by ``P·Kp``:
  ``P·yᵀKp x / yᵀK0 x`` with ``x = K0⁻¹(−H0)``, ``y = K0⁻ᵀD0ᵀ`` — the
  ω → 0 limit of ``∂ln G/∂ln P``,

and says in words when the prestress is inert.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._results import dataframe, format_repr

if TYPE_CHECKING:
    from .result import FitResult

__all__ = ["PrestressActivity", "prestress_activity", "INERT_SHARE", "INERT_ELASTICITY", "CELL_ELASTICITY"]

#: a prestress share of the static stiffness below this is "inert" (together with INERT_ELASTICITY)
INERT_SHARE = 0.01
#: ... and so is a ∂ln G'/∂ln P below this at every data point
INERT_ELASTICITY = 0.01
#: ∂ln G'/∂ln P measured in adherent cells (G' about proportional to the prestress; Stamenović 2002, Wang 2002)
CELL_ELASTICITY = 0.7
#: frequency (Hz) at which the elasticity is also reported for every prestress (the prestress data's frequency)
REFERENCE_FREQUENCY_HZ = 0.1


@dataclass(frozen=True, eq=False, repr=False)
class PrestressActivity:
    """Prestress elasticities and share at the fitted parameters.

    Attributes
    ----------
    dataset : ndarray of int, shape (N,)
        Data set of each point.
    frequency_hz : ndarray, shape (N,)
        The data's frequencies (Hz).
    prestress_model_N : ndarray, shape (N,)
        Model prestress P (N) at each point.
    storage, loss : ndarray, shape (N,)
        ``∂ln G'/∂ln P`` and ``∂ln G''/∂ln P`` at each point.
    share : ndarray, shape (N,)
        Share of the static stiffness carried by ``P·Kp`` at each point's prestress.
    reference_frequency_hz : float
    reference_prestress_N : ndarray, shape (groups,)
        Each distinct model prestress of the fit.
    reference_dataset : ndarray of int, shape (groups,)
    reference_storage, reference_loss : ndarray, shape (groups,)
        The elasticities at ``reference_frequency_hz`` for each distinct prestress.
    reference_share : ndarray, shape (groups,)
    min_share_bound : float or None
        The lower bound the fit imposed on the share (``min_prestress_share``), if any.
    min_elasticity_bound : float or None
        The lower bound the fit imposed on ``∂ln G'/∂ln P`` (``min_prestress_elasticity``), if any.
    elasticity_bound_frequency_hz : float
        The frequency (Hz) of that bound.
    """

    dataset: np.ndarray
    frequency_hz: np.ndarray
    prestress_model_N: np.ndarray
    storage: np.ndarray
    loss: np.ndarray
    share: np.ndarray
    reference_frequency_hz: float
    reference_prestress_N: np.ndarray
    reference_dataset: np.ndarray
    reference_storage: np.ndarray
    reference_loss: np.ndarray
    reference_share: np.ndarray
    min_share_bound: float | None = None
    min_elasticity_bound: float | None = None
    elasticity_bound_frequency_hz: float = REFERENCE_FREQUENCY_HZ

    def _at_points(self, name: str) -> np.ndarray:
        # a fit to creep data only has no moduli points: its reference values stand for them
        values = getattr(self, name)
        return values if values.size else getattr(self, f"reference_{name}")

    @property
    def inert(self) -> bool:
        """True if the prestress carries (almost) none of the stiffness and G' does not respond to it."""
        return bool(np.nanmax(self._at_points("share")) < INERT_SHARE
                    and np.nanmax(np.abs(self._at_points("storage"))) < INERT_ELASTICITY)

    def verdict(self) -> str:
        """The finding in plain words."""
        share, storage = self._at_points("share"), self._at_points("storage")
        s_lo, s_hi = float(np.nanmin(share)), float(np.nanmax(share))
        e_lo, e_hi = float(np.nanmin(storage)), float(np.nanmax(storage))
        share_text = f"{s_lo:.3g}" if np.isclose(s_lo, s_hi, rtol=1e-3) else f"{s_lo:.3g} to {s_hi:.3g}"
        text = (f"P·Kp carries {share_text} of the static stiffness; ∂lnG'/∂lnP is {e_lo:.3g} to {e_hi:.3g} at the "
                f"data's frequencies (adherent cells: about {CELL_ELASTICITY:g}).")
        if self.inert:
            return ("The prestress is mechanically inert: " + text + " This fit is a network of Voigt springs, "
                    "not a prestressed tensegrity; its stiffness does not come from the prestress.")
        if e_hi < 0.1 * CELL_ELASTICITY:
            return "The prestress is nearly inert: " + text
        return "The prestress is mechanically active: " + text

    def __repr__(self) -> str:
        return format_repr(
            f"PrestressActivity: {self.storage.size} points, {self.reference_prestress_N.size} prestress(es)",
            f"share of the static stiffness {np.nanmin(self._at_points('share')):.3g} to "
            f"{np.nanmax(self._at_points('share')):.3g}",
            f"dlnG'/dlnP {np.nanmin(self._at_points('storage')):.3g} to {np.nanmax(self._at_points('storage')):.3g}; "
            f"dlnG''/dlnP {np.nanmin(self._at_points('loss')):.3g} to {np.nanmax(self._at_points('loss')):.3g}",
            "inert" if self.inert else "active",
        )

    def to_dataframe(self):
        """One row per data point: dataset, frequency_Hz, prestress_model_N, elasticities, share."""
        return dataframe({"dataset": self.dataset, "frequency_Hz": self.frequency_hz,
                          "prestress_model_N": self.prestress_model_N, "dlnGstorage_dlnP": self.storage,
                          "dlnGloss_dlnP": self.loss, "prestress_share": self.share})

    def to_dict(self) -> dict:
        """JSON-ready summary, with the verdict."""
        return {
            "inert": self.inert,
            "verdict": self.verdict(),
            "min_share_bound": self.min_share_bound,
            "min_elasticity_bound": self.min_elasticity_bound,
            "elasticity_bound_frequency_Hz": self.elasticity_bound_frequency_hz,
            "share_min": float(np.nanmin(self._at_points("share"))),
            "share_max": float(np.nanmax(self._at_points("share"))),
            "dlnGstorage_dlnP": {"min": float(np.nanmin(self._at_points("storage"))),
                                 "max": float(np.nanmax(self._at_points("storage")))},
            "dlnGloss_dlnP": {"min": float(np.nanmin(self._at_points("loss"))),
                              "max": float(np.nanmax(self._at_points("loss")))},
            "at_reference_frequency": {
                "frequency_Hz": self.reference_frequency_hz,
                "rows": [{"dataset": int(k), "prestress_model_N": float(P), "dlnGstorage_dlnP": float(a),
                          "dlnGloss_dlnP": float(b), "prestress_share": float(s)}
                         for k, P, a, b, s in zip(self.reference_dataset, self.reference_prestress_N,
                                                  self.reference_storage, self.reference_loss, self.reference_share)],
            },
        }


def prestress_activity(result: FitResult, reference_frequency_hz: float = REFERENCE_FREQUENCY_HZ) -> PrestressActivity:
    """The prestress elasticities and share of a fit of the Voigt cell, at its data points and at a reference
    frequency (:meth:`tenscell.fitting.models.voigt.FitProblem.prestress_activity`); CapabilityError for another
    model (:class:`tenscell.fitting.models.base.CapabilityError`).

    Parameters
    ----------
    result : FitResult
    reference_frequency_hz : float
        Frequency (Hz) of the per-prestress summary (default 0.1 Hz).
    """
    if reference_frequency_hz == REFERENCE_FREQUENCY_HZ:
        return result._prestress_activity  # computed once per result (the report reads it several times)
    return result.problem.prestress_activity(result, reference_frequency_hz)

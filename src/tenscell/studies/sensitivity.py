"""The sensitivity study: elasticities, the ±10 % table, its summary by group and Monte Carlo at one base point.

The paper's claim "a 10 % change of a parameter changes the moduli by a few percent (at most 8 %)" checked with
the tools of :mod:`tenscell.sensitivity`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._checks import positive_scalar
from .._progress import stage
from .._results import dataframe, format_repr
from .._threads import hot_path
from ..sensitivity import (PAPER_BOUND, SENSITIVITY_FREQUENCIES, Elasticities, base_parameters, elasticities,
                           monte_carlo, perturbation_table, summarize)

__all__ = ["SensitivityStudy", "sensitivity_study"]


@dataclass(frozen=True, eq=False, repr=False)
class SensitivityStudy:
    """Elasticities, the ±change table, its group summary and Monte Carlo, for one base point.

    Attributes
    ----------
    elasticities : Elasticities
    table : list of PerturbationRow
    summary : list of GroupSummary
    monte_carlo : tuple of MonteCarloResult
        All parameters, then the material parameters only.
    change : float
        Relative change of the one-at-a-time table (fraction).
    alpha_change : float
        Shift of α in the table (rad).
    bound : float
        The claim checked: a ``change`` in gives at most ``bound`` out (fraction).
    describe : str
        The base cell.
    P, L, alpha, delta : float
        Base prestress (N), strut length (m), reference angles (rad).
    EA, c : ndarray, shape (m,)
        Base tendon stiffness (N) and damping (N·s/m).
    """

    elasticities: Elasticities
    table: list
    summary: list
    monte_carlo: tuple
    change: float
    alpha_change: float
    bound: float
    describe: str
    P: float
    L: float
    alpha: float
    delta: float
    EA: np.ndarray
    c: np.ndarray

    def __repr__(self) -> str:
        holds = [g.group for g in self.summary if g.holds]
        fails = [g.group for g in self.summary if g.holds is False]
        return format_repr(
            f"SensitivityStudy of {self.describe} at P = {self.P:g} N",
            f"±{100 * self.change:g}% one at a time: holds ≤ {100 * self.bound:g}% for {len(holds)} groups, "
            f"fails for {len(fails)}" + (f" ({', '.join(fails)})" if fails else ""),
            f"Monte Carlo: {', '.join(f'{100 * m.fraction_within(self.bound):.1f}% within' for m in self.monte_carlo)}",
        )

    def to_dataframe(self):
        """The group summary: one row per parameter group."""
        s = self.summary
        return dataframe({
            "group": [x.group for x in s], "n": [x.n for x in s],
            "max_abs_elasticity_storage": [x.max_elasticity_storage for x in s],
            "max_abs_elasticity_loss": [x.max_elasticity_loss for x in s],
            "max_change_storage": [x.max_change_storage for x in s], "max_change_loss": [x.max_change_loss for x in s],
            "holds": [x.holds for x in s], "note": [x.note for x in s],
        }, {"change": self.change, "bound": self.bound, "prestress_N": self.P})

    def plot(self, ax=None, **kw):
        """The elasticities of G' against frequency (see :meth:`Elasticities.plot`)."""
        return self.elasticities.plot(ax=ax, **kw)


@hot_path
def sensitivity_study(
    draws: int = 200,
    *,
    seed: int = 0,
    change: float = 0.10,
    alpha_change: float | None = None,
    bound: float = PAPER_BOUND,
    alpha: float = 0.0,
    delta: float | None = None,
    L: float = 1.0,
    P: float = 1000.0,
    EA=1.0,
    c=1.0,
    f_hz=SENSITIVITY_FREQUENCIES,
    progress: bool | None = None,
) -> SensitivityStudy:
    """The paper's "10% in, at most 8% out", checked every way: elasticities, ±change table, Monte Carlo.

    Parameters as in :func:`elasticities`, :func:`perturbation_table` and
    :func:`monte_carlo` (``change`` is also the Monte Carlo spread).
    """
    bound = positive_scalar("bound", bound)
    stage("sensitivity: elasticities", progress=progress)
    el = elasticities(alpha=alpha, delta=delta, L=L, P=P, EA=EA, c=c, f_hz=f_hz)
    stage(f"sensitivity: ±{100 * change:g}% one at a time", progress=progress)
    table = perturbation_table(change=change, alpha_change=alpha_change, alpha=alpha, delta=delta, L=L, P=P, EA=EA,
                               c=c, f_hz=f_hz)
    mcs = tuple(monte_carlo(draws, spread=change, seed=seed, parameters=which, alpha_spread=alpha_change, alpha=alpha,
                            delta=delta, L=L, P=P, EA=EA, c=c, f_hz=f_hz, progress=progress)
                for which in ("all", "material"))
    cell, EA_, c_ = base_parameters(alpha, delta, L, P, EA, c, True)
    return SensitivityStudy(
        elasticities=el, table=table, summary=summarize(el, table, bound), monte_carlo=mcs, change=float(change),
        alpha_change=float(change if alpha_change is None else alpha_change), bound=bound, describe=cell.describe(),
        P=float(P), L=float(L), alpha=float(alpha), delta=float(cell.parameters["delta"]), EA=EA_, c=c_,
    )

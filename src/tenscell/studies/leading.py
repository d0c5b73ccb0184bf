"""The leading few-parameter mechanisms beside the paper's per-tendon fit (``tenscell reproduce``).

Both bundled data sets fitted jointly, the frequency sweep stated at one prestress: the per-tendon Voigt cell (the
paper's fit, given) and each mechanism of :data:`MECHANISMS`, fitted with ``tenscell fit``'s default search, are
compared on one table: free parameters, the stiffness spread, RMS per data set, AIC, BIC and the share of dG′/dP
the geometric prestress stiffness carries. Built on public results only (:meth:`FitResult.information_criteria`,
:func:`tenscell.fitting.shares.structure_shares`); the prose is :func:`tenscell.reports.leading.leading_markdown`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .._results import format_repr

__all__ = ["MECHANISMS", "SEARCH", "LeadingRow", "LeadingMechanisms", "leading_mechanisms", "geometric_share",
           "fit_command"]

#: the mechanisms compared with the joint per-tendon fit: the one-exponent springpot, the few-parameter mechanism
#: with the lowest BIC in `tenscell study mechanisms` on the bundled data (its structure a passenger) and the
#: recommended one, whose geometric prestress stiffness carries the prestress dependence (docs/fitting.md)
MECHANISMS = ("springpot+visc", "springpot-tension+visc", "springpot-alpha-family+visc")
#: the search of those fits: `tenscell fit`'s defaults (4 starts, seed 0), so that the command the report prints
#: gives the same numbers
SEARCH: dict[str, Any] = {"starts": 4, "seed": 0}


def geometric_share(result) -> float | None:
    """The share of dG′/dP over the data's prestress range carried by the geometric prestress stiffness P·Kp, for a
    model whose capabilities define it (:mod:`tenscell.fitting.shares`); None otherwise, or where the cell is not
    stable over the whole range."""
    from ..fitting.shares import structure_shares

    if not result.problem.spec.capabilities.structure_shares:
        return None
    try:
        return float(structure_shares(result.problem, result.theta).geometric_share_storage)
    except ValueError:  # not a stable cell at some prestress of the range
        return None


@dataclass(frozen=True)
class LeadingRow:
    """One model of the comparison: its name, free parameters (less an exact gauge: what AIC and BIC count), the
    tendon-stiffness spread (decades; NaN without tendons), RMS of the log10 errors per data set (decades), AIC,
    BIC and the geometric share of dG′/dP (None where undefined)."""

    model: str
    free_parameters: int
    spread_decades: float
    rms: tuple
    aic: float
    bic: float
    geometric_share: float | None

    @classmethod
    def of(cls, model: str, result) -> LeadingRow:
        aic, bic = result.information_criteria()
        spread = result.stiffness_spread
        return cls(model=model, free_parameters=int(result.problem.n_model_parameters),
                   spread_decades=math.nan if spread is None else float(spread[2]), rms=tuple(result.dataset_rms),
                   aic=float(aic), bic=float(bic), geometric_share=geometric_share(result))


@dataclass(frozen=True, eq=False, repr=False)
class LeadingMechanisms:
    """The comparison: the per-tendon fit's row first, then each mechanism's.

    Attributes
    ----------
    rows : tuple of LeadingRow
    fits : dict of str -> FitResult
        By model name (``"voigt-per-tendon"`` for the per-tendon fit).
    prestress_pa : float
        The frequency sweep's stated prestress (Pa).
    search : dict
        The mechanisms' search options.
    """

    rows: tuple
    fits: dict
    prestress_pa: float
    search: dict

    @property
    def winner(self) -> LeadingRow:
        """The mechanism with the lowest BIC."""
        return min(self.rows[1:], key=lambda r: r.bic)

    @property
    def per_tendon(self) -> LeadingRow:
        return self.rows[0]

    def same_fit_command(self, name: str) -> str:
        """The ``tenscell fit`` command that repeats this comparison's fit of mechanism ``name``."""
        return fit_command(name, self.prestress_pa, self.search)

    def table(self):
        """The comparison as a :class:`~tenscell.studies.protocol.Table` (``mechanisms_vs_per_tendon``)."""
        from .protocol import Table

        return Table.from_records("mechanisms_vs_per_tendon", [
            {"model": r.model, "free_parameters": r.free_parameters, "stiffness_spread_decades": r.spread_decades,
             "rms_prestress_sweep": r.rms[0], "rms_frequency_sweep": r.rms[1], "AIC": r.aic, "BIC": r.bic,
             "geometric_share_dGstorage_dP": r.geometric_share} for r in self.rows])

    def markdown(self) -> str:
        from .._results import reporter

        return reporter("leading_markdown")(self)

    def __repr__(self) -> str:
        w = self.winner
        return format_repr(f"LeadingMechanisms: {len(self.rows) - 1} mechanisms beside the per-tendon fit",
                           f"lowest BIC: {w.model} ({w.free_parameters} parameters, BIC {w.bic:.1f} against "
                           f"{self.per_tendon.bic:.1f})")


def fit_command(name: str, prestress_pa: float, search=None) -> str:
    """The ``tenscell fit`` command of the comparison's fit of mechanism ``name`` to the bundled pair, the frequency
    sweep stated at ``prestress_pa`` (Pa), with ``search`` (default :data:`SEARCH`); ``DIR`` is the output."""
    search = SEARCH if search is None else search
    return (f"tenscell fit bundled:stamenovic2002 bundled:fabry2001 --prestress bundled:fabry2001={prestress_pa:g} "
            f"--model {name} --starts {search['starts']} --seed {search['seed']} --out DIR")


def leading_mechanisms(data, per_tendon, mechanisms=MECHANISMS, *, search=None, jobs: int = 2) -> LeadingMechanisms:
    """Fit each of ``mechanisms`` to ``data`` (the prestress sweep, then the frequency sweep stated at one
    prestress) and compare them with the per-tendon fit ``per_tendon`` of the same data."""
    from ..fitting import fit

    search = dict(SEARCH if search is None else search)
    fits = {"voigt-per-tendon": per_tendon}
    fits.update({m: fit(data, model=m, jobs=jobs, progress=False, **search) for m in mechanisms})
    rows = tuple(LeadingRow.of(name, r) for name, r in fits.items())
    return LeadingMechanisms(rows=rows, fits=fits, prestress_pa=float(data[1].prestress[0]), search=search)

"""Markdown of a mechanism's large ensemble (:class:`tenscell.population.EnsembleResult`), from its fields only."""
from __future__ import annotations

from ._format import num

__all__ = ["ensemble_markdown", "ENSEMBLE_Z_OK"]

#: the fit's average is called representative when it lies within this many sampling standard errors of the
#: ensemble mean at every point (the largest of tens of correlated z-scores of one honest estimate is 2–3)
ENSEMBLE_Z_OK = 4.0


def ensemble_markdown(result, title: str | None = None) -> str:
    """What the ensemble says about one cell of the mechanism, and about the fit's own few-assignment average."""
    nP, nf = result.reference.shape
    rs, rl = result.relative_spread()
    zs, zl = result.reference_z()
    where = "in this process" if result.workers == 0 else f"on {result.workers} Dask worker(s)"
    z = max(zs, zl)
    verdict = (f"the fit's {result.reference_K} assignments were enough for its average to stand for the ensemble"
               if z <= ENSEMBLE_Z_OK else
               f"beyond {ENSEMBLE_Z_OK:g}: the fit's average is not the ensemble's (fit with more assignments)")
    out = [f"# {title or f'Ensemble of mechanism `{result.mechanism}`'}", "",
           f"{result.K} assignments of the fitted tendon values to the tendons (seed {result.seed}; the fit averaged "
           f"{result.reference_K}), at {nP} prestress(es) × {nf} frequencies ({result.prestress_unit}, Hz: "
           f"`ensemble.csv`), computed {where} in {result.elapsed_s:.1f} s.", "",
           f"- **Spread between assignments** (largest sd/mean over the grid): G′ {num(100 * rs, 3)} %, "
           f"G″ {num(100 * rl, 3)} %. One cell of this mechanism differs from the mean by about that much; "
           "the 5–95 % band per point is in `ensemble.csv`.",
           f"- **The fit's own average** lies within {num(zs, 2)} (G′) and {num(zl, 2)} (G″) sampling standard "
           f"errors (sd·√(1/{result.reference_K} + 1/{result.K})) of the ensemble mean at every point: {verdict}.",
           f"- {result.n_failed} assignment(s) not a stable cell; every stable one passive (G″ ≥ 0): "
           f"{'yes' if result.passive else 'NO'}.",
           "- What this does not show: the ensemble varies only which tendon gets which value of the fitted "
           "distribution; the distribution's own parameters are the fit's, and their uncertainty is not in the band.",
           ""]
    return "\n".join(out)

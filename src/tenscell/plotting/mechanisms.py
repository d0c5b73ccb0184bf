"""The mechanisms study's figure: the frequency sweep against the best mechanisms, and every mechanism's G' slope."""
from __future__ import annotations

from typing import Sequence

import numpy as np
from matplotlib.axes import Axes

from ._style import new_panels, styled
from .fits import data_points

__all__ = ["mechanisms_figure"]


@styled
def mechanisms_figure(study, datasets, axes: Sequence[Axes] | None = None, *, show: int = 3) -> np.ndarray:
    """(a) the frequency sweep with the ``show`` lowest-BIC mechanisms and the per-tendon fit; (b) local G' slopes.

    ``datasets`` are the study's data sets (the frequency sweep is the one the rows have curves for).
    """
    from ..fitting.models.catalog import PER_TENDON_VOIGT
    from ..studies.mechanisms import GOALS, SLOPE_BAND_HZ

    ax = new_panels(axes, 2, (10.0, 4.0), title="Mechanisms fitted to the same data")
    with_curves = [r for r in study.rows if r.curves]
    if not with_curves:
        for a in ax:
            a.text(0.5, 0.5, "no frequency sweep in the data", ha="center", transform=a.transAxes)
        return ax
    k = next(iter(with_curves[0].curves))
    data_points(datasets[k], ax[0])
    ranked = sorted(with_curves, key=lambda r: r.bic)[:show]
    ref = [r for r in with_curves if r.name == PER_TENDON_VOIGT and r not in ranked]
    for i, r in enumerate(ranked + ref):
        f, Gs, Gl = r.curves[k]
        ax[0].plot(f, Gs, "-", color=f"C{i + 1}", label=f"{r.name} (BIC {r.bic:.0f})")
        ax[0].plot(f, Gl, "--", color=f"C{i + 1}")
    ax[0].set_xscale("log")
    ax[0].set_yscale("log")
    ax[0].set_xlabel("frequency f (Hz)")
    ax[0].set_ylabel("G′ (solid), G″ (dashed) (Pa)")
    ax[0].legend(fontsize="small")
    lo, hi = GOALS["slope"] - GOALS["slope_tol"], GOALS["slope"] + GOALS["slope_tol"]
    ax[1].axhspan(lo, hi, color="0.85", label=f"goal {GOALS['slope']:g} ± {GOALS['slope_tol']:g}")
    for i, r in enumerate(with_curves):
        f, Gs, _ = r.curves[k]
        ax[1].plot(f, np.gradient(np.log10(Gs), np.log10(f)), lw=1.0, label=r.name, color=f"C{i % 10}",
                   ls="-" if i < 10 else ":")
    ax[1].set_xscale("log")
    ax[1].set_xlim(*SLOPE_BAND_HZ)
    ax[1].set_xlabel("frequency f (Hz)")
    ax[1].set_ylabel("local slope d log G′ / d log f")
    ax[1].legend(fontsize="x-small", ncol=2)
    return ax

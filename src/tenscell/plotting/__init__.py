"""Figures. Nothing here computes physics, and nothing here chooses a matplotlib backend.

Every function takes results computed elsewhere, draws on the axes it is
given (``ax=`` for one panel, ``axes=`` for several) or on a new figure's,
and returns the axes — an :class:`~matplotlib.axes.Axes` or an array of them,
as pandas' ``DataFrame.plot`` does. New figures get the house look
(:data:`STYLE`, applied as a context, never globally); axes you pass keep
yours. :func:`save` writes a figure (or the figure behind returned axes)
atomically.

Topics: :mod:`~tenscell.plotting.paper` (Figs. 2–3),
:mod:`~tenscell.plotting.variants` (variants, sensitivity),
:mod:`~tenscell.plotting.fits` (data against fits),
:mod:`~tenscell.plotting.dynamics` (time domain),
:mod:`~tenscell.plotting.spectra` (modes, creep and relaxation curves),
:mod:`~tenscell.plotting.structures` (3D views),
:mod:`~tenscell.plotting.interactive` (the interactive 3D view, with plotly: ``tenscell[view]``),
:mod:`~tenscell.plotting.powerlaw` (the power-law study).
"""
from __future__ import annotations

from ._style import STYLE, calibration_figure, colors, figure_of, moduli_panels, png_bytes, save, style
from .dynamics import creep_loglog, force_displacement_loop, harmonic_spectrum, time_traces
from .fits import (compactness_front, data_points, fit_figure, fit_panels, measured, plot_fit, plot_profile,
                   plot_residuals, profile_panels, residual_panels, stiffness_histogram)
from .spectra import loglog_curve, rates_bar, spectrum_stems
from .paper import fig2_prestress, fig3_frequency, moduli_vs_frequency, moduli_vs_prestress
from .structures import MEMBER_STYLE, relaxation_modes_3d, structure_3d
from .interactive import structure_view, structure_view_html
from . import dynamics, fits, interactive, paper, population, powerlaw, spectra, structures, variants
from .variants import (
    elasticities_figure, monte_carlo_figure, no_if_figure, no_if_peaks_figure, reference_map_figure,
    references_figure, semiflexible_figure, stiffening_figure,
)

__all__ = [
    # style and output
    "STYLE", "style", "colors", "moduli_panels", "figure_of", "save", "png_bytes",
    # the paper's figures
    "fig2_prestress", "fig3_frequency", "moduli_vs_frequency", "moduli_vs_prestress",
    # variants and sensitivity
    "no_if_figure", "no_if_peaks_figure", "elasticities_figure", "monte_carlo_figure", "reference_map_figure",
    "references_figure", "semiflexible_figure", "stiffening_figure",
    # fits
    "fit_figure", "data_points", "measured", "plot_fit", "fit_panels", "compactness_front", "stiffness_histogram",
    "residual_panels", "plot_residuals", "profile_panels", "plot_profile",
    # time domain
    "time_traces", "force_displacement_loop", "harmonic_spectrum", "creep_loglog",
    # spectra and time curves of the linear model
    "spectrum_stems", "loglog_curve", "rates_bar",
    # structures
    "structure_3d", "relaxation_modes_3d", "MEMBER_STYLE", "structure_view", "structure_view_html",
]


def _register() -> None:
    """Every drawing function of the topic modules, for the results' ``plot()`` (:func:`tenscell._results.plotter`)."""
    from .._results import register_plotters
    from . import mechanisms, real_cells, validation  # the studies' figures (studies.protocol.Figure names them)

    register_plotters({name: getattr(module, name) for module in (dynamics, fits, interactive, paper, population,
                                                                  powerlaw, spectra, structures, variants, mechanisms,
                                                                  real_cells, validation)
                       for name in module.__all__ if callable(getattr(module, name))})
    register_plotters({"save": save, "png_bytes": png_bytes, "calibration_figure": calibration_figure})


_register()

"""Reports: Markdown rendered only from result fields, one module per kind of result.

Nothing here computes physics; every number printed comes from a result object
that the run produced from its own inputs.
"""
from .compactness import compactness_markdown
from .ensemble import ensemble_markdown
from .fit import fit_markdown
from .fit_text import fit_text
from .leading import leading_markdown
from .mechanisms import mechanisms_markdown, mechanisms_summary
from .real_cells import real_cells_markdown, real_cells_tables, validation_tables
from .html import (comparison_html, data_html, ensemble_html, fit_html, fitted_model_html, frequency_response_html,
                   population_html, structure_html)
from .html_page import fit_report_html, markdown_report_html
from .population import population_markdown, study_markdown
from .population_fit import population_fit_markdown
from .powerlaw import powerlaw_markdown
from .sensitivity import sensitivity_markdown
from .structures import structures_markdown
from .studies import no_if_markdown, references_markdown, semiflexible_markdown, stiffening_markdown

__all__ = [
    "fit_markdown", "fit_text", "sensitivity_markdown", "compactness_markdown", "no_if_markdown", "references_markdown",
    "semiflexible_markdown", "stiffening_markdown", "population_markdown", "study_markdown",
    "ensemble_markdown", "population_fit_markdown", "leading_markdown", "fit_html", "data_html", "frequency_response_html",
    "fitted_model_html", "comparison_html", "population_html", "ensemble_html", "structures_markdown",
    "structure_html", "fit_report_html", "markdown_report_html", "mechanisms_markdown", "mechanisms_summary",
    "real_cells_markdown", "real_cells_tables", "validation_tables", "powerlaw_markdown",
]


def _register() -> None:
    """Every renderer above, for results that write their own report (:func:`tenscell._results.reporter`)."""
    from .._results import register_reporters

    register_reporters({name: globals()[name] for name in __all__})


_register()

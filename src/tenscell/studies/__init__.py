"""The paper's studies: claims, variants of the discussion, future work.

One module per study (:mod:`~tenscell.studies.claims`, :mod:`~tenscell.studies.no_if`,
:mod:`~tenscell.studies.references`, :mod:`~tenscell.studies.semiflexible`,
:mod:`~tenscell.studies.stiffening`, :mod:`~tenscell.studies.compactness`,
:mod:`~tenscell.studies.sensitivity`); their
entry points and results are importable from here, with the pieces the studies of measured
cells use: :mod:`~tenscell.studies.falsification` (data cells do not show) and
:mod:`~tenscell.studies.real_cells` (the measured cells, read from ``../shared/data/real-cells``); the structure
with no fitted parameter and at the prestress anchor: :mod:`~tenscell.studies.a_priori` (parameter-free slopes),
:mod:`~tenscell.studies.structures` (each mechanism on each structure, σ anchored).
"""
from .claims import homogeneous_study, paper_claims
from .compactness import CompactnessStudy, compactness_study
from .falsification import UNLIKE_KINDS, unlike_data, unlike_sets
from .no_if import LossPeak, NoIFStudy, loss_peak, no_if_study
from .real_cells import (RealCellsMissing, XieCell, hl60_creep, oocyte_relaxation, real_cells_directory, xie_cells,
                         xie_median)
from .references import ReferencesStudy, prestress_map, references_study
from .sensitivity import SensitivityStudy, sensitivity_study
from .semiflexible import BucklingError, SemiflexibleStudy, linearize_semiflexible, semiflexible_study
from .stiffening import StiffeningStudy, linearize_stiffening, stiffening_study
from .a_priori import a_priori_table
from .structures import StructuresStudy, structures_study

__all__ = [
    "homogeneous_study", "paper_claims",
    "no_if_study", "NoIFStudy", "loss_peak", "LossPeak",
    "references_study", "ReferencesStudy", "prestress_map",
    "semiflexible_study", "SemiflexibleStudy", "linearize_semiflexible", "BucklingError",
    "stiffening_study", "StiffeningStudy", "linearize_stiffening",
    "compactness_study", "CompactnessStudy",
    "sensitivity_study", "SensitivityStudy",
    "unlike_data", "unlike_sets", "UNLIKE_KINDS",
    "a_priori_table", "structures_study", "StructuresStudy",
    "xie_cells", "xie_median", "hl60_creep", "oocyte_relaxation", "real_cells_directory", "XieCell", "RealCellsMissing",
]

"""The linear-algebra core's names in one place (their former home, kept so that imports keep working).

The core is split by concern; each name lives in one module and is re-exported here:

* :mod:`~tenscell.linear.assembly` — K0 and C0 from member tangents, the continuum factor;
* :mod:`~tenscell.linear.definite` — the one positive-definiteness criterion and the one
  conditioning rule for C0;
* :mod:`~tenscell.linear.pencil` — :class:`Pencil`, every decomposition of one model (dense and sparse);
* :mod:`~tenscell.linear.family` — grids and loops of prestresses (:class:`PrestressFamily`);
* :mod:`~tenscell.linear.spectrum` — modal sums, :class:`Modes`, the relaxation spectrum.
"""
from __future__ import annotations

import numpy as np

from .._errors import NotPositiveDefiniteError
from .assembly import assemble_damping, assemble_stiffness, continuum_factor, modulus, spring_stiffness
from .definite import EXACT_RTOL, positive_definite_factor
from .family import PrestressFamily, prestress_grid_compliance, prestress_grid_modes
from .pencil import Pencil, complement_basis
from .spectrum import ZERO_TIME, Modes, RelaxationSpectrum, modal_compliance, relaxation_spectrum

__all__ = [
    "NotPositiveDefiniteError",
    "positive_definite_factor",
    "complement_basis",
    "continuum_factor",
    "modulus",
    "assemble_stiffness",
    "assemble_damping",
    "spring_stiffness",
    "Modes",
    "Pencil",
    "RelaxationSpectrum",
    "relaxation_spectrum",
    "modal_compliance",
    "prestress_grid_compliance",
    "PrestressFamily",
    "FAMILY_PIVOT_RATIO",
    "prestress_grid_modes",
    "ZERO_TIME",
]

#: the family's conditioning rule (:func:`tenscell.linear.definite.damping_factor` at ``EXACT_RTOL``) as the
#: smallest ratio ``min d/max d`` of C0's squared Cholesky pivots it accepts (the name of releases up to 0.2)
FAMILY_PIVOT_RATIO = float(np.finfo(float).eps) / EXACT_RTOL

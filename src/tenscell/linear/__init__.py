"""Linearization about the reference and its linear algebra (dense and sparse).

:mod:`~tenscell.linear.linearize` builds the :class:`LinearModel` (K0, C0, H0,
D0); :mod:`~tenscell.linear.modal` owns every decomposition of its pencil
(:class:`Pencil`); :mod:`~tenscell.linear.sparse` and
:mod:`~tenscell.linear.krylov` serve large structures;
:mod:`~tenscell.linear.whitening` is the fits' view of the pencil;
:mod:`~tenscell.linear.dynamic` is the frequency-dependent kernel of laws with
dynamics of their own (whose time domain :func:`realize` builds).
"""
from .._errors import NotPositiveDefiniteError
from .krylov import KrylovResponse, krylov_compliance
from .dynamic import dynamic_compliance, dynamic_moduli
from .linearize import LinearModel, linearize, linearize_law, linearize_tangent, realize, with_cytoplasm
from .modal import (Pencil, RelaxationSpectrum, continuum_factor, modulus, positive_definite_factor,
                    relaxation_spectrum)

__all__ = [
    "LinearModel", "linearize", "linearize_law", "linearize_tangent", "NotPositiveDefiniteError",
    "Pencil", "positive_definite_factor", "RelaxationSpectrum", "relaxation_spectrum", "continuum_factor", "modulus",
    "krylov_compliance", "KrylovResponse", "dynamic_moduli", "dynamic_compliance", "realize", "with_cytoplasm",
]

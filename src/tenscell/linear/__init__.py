"""Linearization about the reference and its linear algebra (dense and sparse).

:mod:`~tenscell.linear.linearize` builds the :class:`LinearModel` (K0, C0, H0,
D0) from the assembly of :mod:`~tenscell.linear.assembly`;
:mod:`~tenscell.linear.pencil` owns every decomposition of its pencil
(:class:`Pencil`), with the one positive-definiteness criterion and the one
conditioning rule for C0 of :mod:`~tenscell.linear.definite`, the prestress
family of :mod:`~tenscell.linear.family` and the modal sums of
:mod:`~tenscell.linear.spectrum` (:mod:`~tenscell.linear.modal` re-exports
them all); :mod:`~tenscell.linear.ordering`, :mod:`~tenscell.linear.sparse`
and :mod:`~tenscell.linear.krylov` serve large structures;
:mod:`~tenscell.linear.whitening` is the fits' view of the pencil;
:mod:`~tenscell.linear.dynamic` is the frequency-dependent kernel of laws with
dynamics of their own (whose time domain :func:`realize` builds).
"""
from .._errors import NotPositiveDefiniteError
from .krylov import KrylovResponse, krylov_compliance
from .dynamic import dynamic_compliance, dynamic_moduli
from .linearize import LinearModel, linearize, linearize_law, linearize_tangent, realize, with_cytoplasm
from .assembly import continuum_factor, modulus
from .definite import is_positive_definite, positive_definite_factor
from .pencil import Pencil
from .spectrum import RelaxationSpectrum, relaxation_spectrum

__all__ = [
    "LinearModel", "linearize", "linearize_law", "linearize_tangent", "NotPositiveDefiniteError",
    "Pencil", "positive_definite_factor", "is_positive_definite", "RelaxationSpectrum", "relaxation_spectrum", "continuum_factor", "modulus",
    "krylov_compliance", "KrylovResponse", "dynamic_moduli", "dynamic_compliance", "realize", "with_cytoplasm",
]

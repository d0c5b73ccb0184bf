"""Linearization about the reference and its linear algebra (dense and sparse)."""

"""The slowest relaxation modes of a sparse model: a Lanczos run shifted just below the slowest rate.

Checked against the dense generalized eigenproblem K0 v = λ C0 v of the same matrices: each rate returned lies
within its residual bound of a rate of the model, the shift is proven below every rate (its factor exists), a
shift that is not below them is refused and the next one tried, and `tenscell show` prints only the digits the
bound supports.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

import tenscell
import tenscell.linear.krylov as krylov
from tenscell.model.structure import member_values
from tenscell.summary import RelaxationModes, relaxation_modes


def _lattice_lin():
    cell = tenscell.model.lattice_cell(4, 4, 4)
    assert cell.sparse
    return tenscell.linearize(cell, 1000.0, member_values(cell.structure, {"strut": 1e3, "default": 1.0}), 1.0)


@pytest.fixture(scope="module")
def dense_rates():
    lin = _lattice_lin()
    return scipy.linalg.eigh(lin.K0.toarray(), lin.C0.toarray(), eigvals_only=True)


def _shifts(lin):
    return sorted(s for s in lin.pencil._runs if s < 0)


@pytest.mark.parametrize("tol", [1e-6, 5e-4])
def test_rates_lie_within_their_bounds_of_model_rates(dense_rates, tol):
    lin = _lattice_lin()
    modes = relaxation_modes(lin, 3, tol=tol)
    assert np.all(np.diff(modes.rates) >= 0)
    assert modes.residuals is not None and np.all(modes.residuals < tol)
    for rate, bound in zip(modes.rates, modes.residuals):
        nearest = np.min(np.abs(dense_rates - rate)) / rate
        # the residual bounds the relative error to first order; 2x covers the second-order term
        assert nearest <= 2 * bound + 1e-12, (rate, nearest, bound)
    # the run was shifted below every rate of the model: its factor proves it
    (sigma,) = _shifts(lin)
    assert -sigma < dense_rates.min()
    # the slowest rate found is in the model's slowest cluster (one local mode per module, relative width ~1e-5
    # here): within the cluster, which member a Ritz value settles on is not determined
    assert modes.rates[0] / dense_rates.min() - 1 < 1e-4


def test_a_shift_above_the_slowest_rate_is_refused_and_the_next_tried(monkeypatch, dense_rates):
    lin = _lattice_lin()
    monkeypatch.setattr(krylov, "SLOW_SHIFT_FRACTIONS", (50.0, 0.9))  # 50x the estimate: above some rate
    rates, _, resid = krylov.load_modes(lin, 2, tol=1e-6)
    (sigma,) = _shifts(lin)
    assert -sigma < dense_rates.min()
    assert all(s >= sigma for s in lin.pencil._shifted)  # the refused shift's matrix was not kept
    assert np.min(np.abs(dense_rates - rates[0])) / rates[0] <= 2 * resid[0] + 1e-12


def test_no_shift_below_the_rates_falls_back_to_the_unshifted_run(monkeypatch, dense_rates):
    lin = _lattice_lin()
    monkeypatch.setattr(krylov, "SLOW_SHIFT_FRACTIONS", (50.0,))
    rates, _, resid = krylov.load_modes(lin, 1, tol=1e-6, max_steps=400)
    assert _shifts(lin) == [] and 0.0 in lin.pencil._runs
    assert np.min(np.abs(dense_rates - rates[0])) / rates[0] <= 2 * resid[0] + 1e-12


def test_printed_digits_follow_the_bound():
    rates = np.array([1.661955, 1.662106, 1.738482])
    approx = RelaxationModes(rates=rates, displacements=np.zeros((3, 1, 3)), vectors=np.zeros((1, 3)),
                             residuals=np.array([1e-5, 2.3e-4, 1e-6]))
    assert approx.rates_text() == "1.66, 1.66, 1.74"  # bound 2.3e-4: three digits
    exact = RelaxationModes(rates=rates, displacements=np.zeros((3, 1, 3)), vectors=np.zeros((1, 3)))
    assert exact.rates_text() == "1.66196, 1.66211, 1.73848"
    tight = RelaxationModes(rates=rates, displacements=np.zeros((3, 1, 3)), vectors=np.zeros((1, 3)),
                            residuals=np.full(3, 4e-6))
    assert tight.rates_text() == "1.6620, 1.6621, 1.7385"  # 2·4e-6 = 8e-6: five digits, trailing zero kept

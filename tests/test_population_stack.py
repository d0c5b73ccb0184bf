"""A mechanism population evaluates its cells in stacked calls (one law evaluation per grid, one batched solve for
every cell's points): the same moduli and exact derivatives as each cell's own problem, cell by cell."""
from __future__ import annotations

import math

import numpy as np
import pytest

from tenscell.fitting import Population
from tenscell.fitting.models.catalog import MECHANISMS
from tenscell.fitting.problem import Problem
from tenscell.io.data import RheologyData

F = np.array([1.0, 3.0, 10.0, 30.0, 100.0, 200.0])


def _cells(name, n, seed=3, other_frequencies=()):
    """``n`` cells of mechanism ``name`` at log-normal prestresses (cells listed in ``other_frequencies`` on a grid of
    their own: a batch of one)."""
    rng = np.random.default_rng(seed)
    template = RheologyData(F, np.full(F.size, 100.0), np.full(F.size, 30.0), source="template")
    pb = MECHANISMS[name].problem(template)
    theta = 0.5 * (pb.bounds[0] + pb.bounds[1]) + 0.2 * rng.standard_normal(pb.n_free)
    cells = []
    for k in range(n):
        f = F * 1.7 if k in other_frequencies else F
        P = math.exp(rng.normal(math.log(2.0), 0.5))
        Gs, Gl = pb.moduli_at(theta, f, np.full(f.size, P))
        cells.append(RheologyData(f, Gs, Gl, source=f"cell{k}"))
    return cells


@pytest.mark.parametrize("name, per_cell, other", [("springpot-tension+visc", ("P",), ()),
                                                    ("springpot+visc", ("P", "kappa_actin"), (1, 3)),
                                                    ("springpot-lognormal-kappa+visc", ("P",), (2,))])
def test_stacked_cells_equal_each_cell_alone(name, per_cell, other):
    pb = Population(name, per_cell=per_cell).problem(_cells(name, 5, other_frequencies=other))
    rng = np.random.default_rng(1)
    lo, hi = pb.bounds
    theta = np.clip(0.5 * (lo + hi) + 0.3 * rng.standard_normal(pb.n_free), lo, hi)
    phis = pb.cell_phis(pb.full(theta))
    stacked = pb.cells[0]._evaluate_cells(pb.cells, phis, True)
    alone = Problem._evaluate_cells(pb.cells[0], pb.cells, phis, True)  # the generic one-by-one evaluation
    assert len(stacked) == len(alone) == 5
    for (a, a_times), (b, b_times) in zip(stacked, alone):  # (moduli, time data) pairs: no time data here
        assert a_times is None and b_times is None
        assert (a is None) == (b is None)
        if a is None:
            continue
        # the same sums in another order: equal to the rounding of the batched solve
        np.testing.assert_allclose(a.G, b.G, rtol=1e-12)
        np.testing.assert_allclose(a.G_assign, b.G_assign, rtol=1e-12)
        np.testing.assert_allclose(a.dG, b.dG, rtol=1e-9, atol=1e-12 * np.abs(b.dG).max())
    # and the population's residuals and Jacobian are those of its cells
    out = pb._evaluate_constrained(pb.full(theta), jac=True)
    r = pb._residuals_from(out)
    for k, cell in enumerate(pb.cells):
        np.testing.assert_allclose(r[pb.rows(k)], cell.residuals(pb.cell_theta(theta, k)), rtol=1e-11, atol=1e-13)

"""Tendon laws with dynamics of their own (Maxwell, standard linear solid, springpot) and the dynamic kernel.

Invariants a wrong law fails: each analytic derivative of k*(ω) against
central differences through the same law; the kernel equals the pencil's
moduli for rate-linear laws; the kernel's exact ∂J/∂θ against differences.
"""
from __future__ import annotations

import numpy as np
import pytest

import tenscell
from tenscell.laws import Maxwell, Springpot, StandardLinearSolid, Voigt, family_laws
from tenscell.linear.dynamic import dynamic_compliance, dynamic_moduli
from tenscell.linear.linearize import linearize_law

CELL = tenscell.paper_cell()
P0 = 1000.0
RNG = np.random.default_rng(18)
EA = RNG.uniform(0.5, 2.0, CELL.m)
C = RNG.uniform(0.5, 2.0, CELL.m)
W = 2 * np.pi * np.logspace(-3, 4, 15)

DYNAMIC = {
    "maxwell": Maxwell(EA=EA, c=C),
    "sls": StandardLinearSolid(EA=EA, EA_arm=RNG.uniform(0.5, 5.0, CELL.m), c=C),
    "springpot": Springpot(EA=EA, kappa=RNG.uniform(0.1, 2.0, CELL.m), alpha=RNG.uniform(0.1, 0.9, CELL.m)),
    "mixed": family_laws(CELL, {"actin": Maxwell(EA=1.5, c=0.3)}, default=Springpot(EA=0.8, kappa=0.5, alpha=0.25)),
}


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def test_kernel_is_the_pencil_for_a_voigt_law():
    """For k* = k + iωc the kernel's direct solves equal the modal sum of linearize_law (round-off, ~1e-15)."""
    f = np.logspace(-2, 3, 11)
    law = Voigt(EA=EA, c=C)
    Gs, Gl = dynamic_moduli(CELL, law, P0, f)
    Gs0, Gl0 = tenscell.moduli(linearize_law(CELL, law, P0), f)
    assert _rel(Gs, Gs0) < 1e-11 and _rel(Gl, Gl0) < 1e-11


@pytest.mark.parametrize("name", list(DYNAMIC))
def test_complex_stiffness_derivative_in_tension(name):
    """∂k*/∂T against central differences (step 1e-6·T: truncation ~1e-12, round-off ~1e-10 relative)."""
    law, l, T = DYNAMIC[name], CELL.lengths, P0 * CELL.T0
    dT, _ = law.complex_stiffness_derivatives(l, T, W)
    h = 1e-6 * T
    fd = (law.complex_stiffness(l, T + h, W) - law.complex_stiffness(l, T - h, W)) / (2 * h)
    assert _rel(dT, fd) < 1e-7

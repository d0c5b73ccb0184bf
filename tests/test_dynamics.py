"""Nonlinear time-domain simulation: laws, Jacobian, small-amplitude limit, energy, slack, dashpots.

The checks are physical: the linear model is the small-amplitude limit, the
load's work per cycle equals what the tendons dissipate (with and without
slack), the exact time-rescaling symmetry of the massless equations holds
at finite amplitude, nonlinear departures scale with the right power of the
amplitude, and analytic derivatives match finite differences.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import tenscell
from tenscell.laws import (
    LinearizationError,
    PowerDashpot,
    Voigt,
    power_dashpot_law,
    voigt_law,
)
from tenscell.dynamics import (
    EquationsOfMotion,
    SimulationError,
    SineDisplacement,
    SineForce,
    StepForce,
    harmonics,
    linearize_law,
    oscillatory_response,
    simulate,
)


@pytest.fixture(scope="module")
def cell():
    return tenscell.paper_cell()


@pytest.fixture(scope="module")
def law(cell):
    return voigt_law(cell, P=1000.0, EA=1.0, c=1.0)


@pytest.fixture(scope="module")
def small(cell, law):
    """Small-amplitude (0.1 N, tensions ~120-230 N) periodic responses at the three test frequencies."""
    return {f: oscillatory_response(cell, law, 0.1, f) for f in (0.01, 1.0, 100.0)}


# ---- constitutive laws ---------------------------------------------------------------
@pytest.mark.parametrize("make", [
    lambda m: Voigt(EA=np.full(m, 2.0), c=np.full(m, 0.3), l0=np.full(m, 0.5)),
    lambda m: PowerDashpot(EA=np.full(m, 2.0), c=np.full(m, 0.3), l0=np.full(m, 0.5), beta=2.0, velocity_scale=1e-2),
    lambda m: PowerDashpot(EA=np.full(m, 2.0), c=np.full(m, 0.3), l0=np.full(m, 0.5), beta=0.4, velocity_scale=1e-2),
])
def test_law_derivatives_match_finite_differences(make):
    m = 7
    law = make(m)
    rng = np.random.default_rng(1)
    l = 0.5 + rng.random(m)
    v = rng.standard_normal(m) * np.logspace(-3, 0, m)
    T, dl, dv = law.derivatives(l, v)
    h = 1e-7
    assert np.allclose(T, law.tension(l, v))
    assert np.allclose(dl, (law.tension(l + h, v) - law.tension(l - h, v)) / (2 * h), rtol=1e-6)
    hv = 1e-5 * (np.abs(v) + 1e-2)
    assert np.allclose(dv, (law.tension(l, v + hv) - law.tension(l, v - hv)) / (2 * hv), rtol=1e-6)
    assert np.allclose(law.elastic(l), law.tension(l, 0.0))


def test_power_dashpot_smoothing():
    m = 3
    base = dict(EA=np.ones(m), c=np.full(m, 2.0), l0=np.ones(m))
    eps = 1e-3
    for beta in (0.5, 2.0):
        law = PowerDashpot(**base, beta=beta, velocity_scale=eps)
        v = np.array([1e-1, -3e-2, 5e-1])
        exact = 2.0 * np.sign(v) * np.abs(v) ** beta
        # documented accuracy away from zero: relative (β−1)/2·(ε/l')²
        bound = abs(beta - 1) / 2 * (eps / np.abs(v)) ** 2 * 1.01
        assert np.all(np.abs(law.tension(np.ones(m), v) / exact - 1) <= bound)
        # odd, strictly increasing, linear with slope c·ε^(β−1) at zero
        assert np.allclose(law.tension(np.ones(m), -v), -law.tension(np.ones(m), v))
        assert np.allclose(law.derivatives(np.ones(m), np.zeros(m))[2], 2.0 * eps ** (beta - 1))
    # β = 1 is the Voigt law for any smoothing
    pd = PowerDashpot(**base, beta=1.0, velocity_scale=0.3)
    vg = Voigt(**base)
    v = np.array([0.0, 1e-4, -2.0])
    assert np.allclose(pd.tension(np.ones(m), v), vg.tension(np.ones(m), v), rtol=1e-14, atol=0)
    assert pd.rate_linear


def test_voigt_law_reproduces_linear_model(cell, law):
    lin = linearize_law(cell, law)
    ref = tenscell.linearize(cell, P=1000.0, EA=1.0, c=1.0)
    assert lin.P == pytest.approx(1000.0, rel=1e-12)
    assert np.allclose(lin.K0, ref.K0, rtol=1e-12, atol=1e-9)
    assert np.allclose(lin.C0, ref.C0, rtol=1e-12, atol=1e-12)
    assert np.allclose(law.elastic(cell.lengths), 1000.0 * cell.T0)


def test_power_dashpot_linearization(cell):
    """The paper's argument: β > 1 gives C0 = 0 and G'' = 0; β < 1 has no linearization."""
    lin2 = linearize_law(cell, power_dashpot_law(cell, beta=2.0))
    assert np.all(lin2.C0 == 0.0)
    Gp, Gpp = tenscell.moduli(lin2, [0.01, 1.0, 100.0])
    assert np.all(Gpp == 0.0)
    assert np.allclose(Gp, tenscell.response.static_modulus(lin2), rtol=1e-12)
    lin1 = linearize_law(cell, power_dashpot_law(cell, beta=1.0))
    assert np.allclose(lin1.C0, tenscell.linearize(cell).C0)
    with pytest.raises(LinearizationError, match="no linearization"):
        linearize_law(cell, power_dashpot_law(cell, beta=0.5))
    with pytest.raises(ValueError):  # LinearizationError is a ValueError: the CLI reports it in one line
        power_dashpot_law(cell, beta=0.5).damping_at_rest(cell.lengths)


# ---- equations of motion ---------------------------------------------------------------
def _fd_jacobian(eq, t, y, taut, h=1e-7):
    cols = []
    for k in range(y.size):
        e = np.zeros_like(y)
        e[k] = h
        cols.append((eq.velocity(t, y + e, taut) - eq.velocity(t, y - e, taut)) / (2 * h))
    return np.array(cols).T


@pytest.mark.parametrize("case", ["voigt-force", "voigt-displacement", "voigt-slack", "dashpot2-force",
                                  "dashpot05-displacement"])
def test_jacobian_matches_finite_differences(cell, case):
    kind, control = case.split("-")
    law = {"voigt": voigt_law(cell), "dashpot2": power_dashpot_law(cell, beta=2.0, velocity_scale=1e-2),
           "dashpot05": power_dashpot_law(cell, beta=0.5, velocity_scale=1e-2)}[kind]
    load = SineDisplacement(0.01, 1.0) if control == "displacement" else SineForce(10.0, 1.0)
    eq = EquationsOfMotion(cell, law, load)
    y = 1e-2 * np.random.default_rng(3).standard_normal(cell.n)
    taut = np.ones(cell.m, dtype=bool)
    if control == "slack":
        taut[[3, 25]] = False
    J = eq.jacobian(0.3, y, taut)
    tol = 1e-6 if kind == "voigt" else 2e-5  # the dashpot's velocity comes from a Newton solve
    assert np.abs(J - _fd_jacobian(eq, 0.3, y, taut)).max() <= tol * np.abs(J).max()


def test_equations_are_exactly_in_equilibrium_at_rest(cell, law):
    eq = EquationsOfMotion(cell, law, StepForce(1.0))
    st = eq.state(0.0, np.zeros(cell.n))
    # the instantaneous response to a step is the pure-dashpot one, C0⁻¹·(−H0)·F
    lin = tenscell.linearize(cell)
    assert np.allclose(st.v, np.linalg.solve(lin.C0, -lin.H0), rtol=1e-8, atol=1e-12)
    assert np.all(st.taut) and np.allclose(st.tensions, st.trial)


# ---- small amplitude: the linear model ------------------------------------------------------
@pytest.mark.parametrize("f", [0.01, 1.0, 100.0])
def test_small_amplitude_moduli_agree_with_linear(small, f):
    r = small[f]
    # the issue asks for 0.5%; the nonlinear correction at 0.1 N is ~1e-7, so hold it to 1e-4
    assert abs(r.G_storage / r.G_storage_linear - 1) < 1e-4
    assert abs(r.G_loss / r.G_loss_linear - 1) < 1e-4
    assert r.harmonics.periodicity < 1e-4
    assert r.thd < 1e-3
    assert r.simulation.slack_tendons == []


@pytest.mark.parametrize("f", [0.01, 1.0, 100.0])
def test_energy_per_cycle_equals_pi_F2_ImJ(small, f):
    r = small[f]
    F = r.simulation.loading.amplitude
    expected = math.pi * F ** 2 * abs(r.J_linear.imag)
    assert r.harmonics.work_per_cycle == pytest.approx(expected, rel=1e-4)
    # independent route: the power dissipated in the tendon dashpots
    assert r.harmonics.dissipated_per_cycle == pytest.approx(expected, rel=1e-4)


def test_departure_is_second_order_and_distortion_first_order(cell, law):
    a = oscillatory_response(cell, law, 3.0, 1.0)
    b = oscillatory_response(cell, law, 6.0, 1.0)
    da = abs(a.G_storage / a.G_storage_linear - 1)
    db = abs(b.G_storage / b.G_storage_linear - 1)
    assert 3.6 < db / da < 4.4
    assert 1.8 < b.thd / a.thd < 2.2
    # a finite amplitude is a nonlinear periodic state: energy still balances
    assert b.harmonics.work_per_cycle == pytest.approx(b.harmonics.dissipated_per_cycle, rel=1e-5)


def test_time_rescaling_symmetry_at_finite_amplitude(cell):
    """Massless equations: doubling every c and halving f maps the trajectory onto itself exactly."""
    r1 = oscillatory_response(cell, voigt_law(cell, c=1.0), 20.0, 2.0, cycles=2, rtol=1e-9)
    r2 = oscillatory_response(cell, voigt_law(cell, c=2.0), 20.0, 1.0, cycles=2, rtol=1e-9)
    assert r1.thd > 0.02  # genuinely nonlinear
    assert r2.G_storage == pytest.approx(r1.G_storage, rel=1e-6)
    assert r2.G_loss == pytest.approx(r1.G_loss, rel=1e-6)
    assert r2.thd == pytest.approx(r1.thd, rel=1e-5)


def test_displacement_control_matches_linear(cell, law):
    r = oscillatory_response(cell, law, 1e-4, 1.0, control="displacement")
    assert abs(r.G_storage / r.G_storage_linear - 1) < 1e-4
    assert abs(r.G_loss / r.G_loss_linear - 1) < 1e-4
    assert np.abs(r.simulation.z - SineDisplacement(1e-4, 1.0).value(r.simulation.t)).max() < 1e-9


# ---- slack -----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def slack_run(cell):
    # stiff tendons (rest lengths within 0.2% of the lengths) at low prestress: 40 N unloads an IF
    law = voigt_law(cell, P=100.0, EA=1e4, c=1e4)
    return law, oscillatory_response(cell, law, 40.0, 1.0, cycles=3)


def test_slack_tendons_are_detected_and_never_compressed(cell, slack_run):
    _, r = slack_run
    sim = r.simulation
    assert sim.slack_tendons == [23]
    assert cell.structure.families[23] == "intermediate_filament"
    ev = [e for e in sim.events if e.tendon == 23]
    assert [e.kind for e in ev] == ["slack", "taut"] * 3
    # about one period apart, and the tendon is slack for a finite part of each cycle
    assert ev[2].time - ev[0].time == pytest.approx(1.0, abs=1e-3)
    assert 0.05 < ev[1].time - ev[0].time < 0.5
    # no tendon ever carries compression; a slack tendon carries exactly nothing
    assert sim.tensions.min() >= 0.0
    slack = ~sim.taut[:, 23]
    assert slack.sum() > 10 and np.all(sim.tensions[slack, 23] == 0.0)
    # its tension goes continuously to zero at the switch
    k = np.flatnonzero(slack)[0]
    assert sim.tensions[k - 1, 23] < 0.05 * sim.tensions[:, 23].max()
    # the nonsmooth switches keep the energy balance
    assert r.harmonics.work_per_cycle == pytest.approx(r.harmonics.dissipated_per_cycle, rel=1e-4)


def test_slack_can_be_forbidden(cell, slack_run):
    law, _ = slack_run
    with pytest.raises(SimulationError, match=r"tendon 23 \(intermediate_filament\) would go into compression"):
        simulate(cell, law, SineForce(40.0, 1.0), 1.0, slack="error")


# ---- nonlinear dashpots -----------------------------------------------------------------
def test_beta_above_one_dissipates_at_finite_amplitude(cell):
    law = power_dashpot_law(cell, beta=2.0, velocity_scale=1e-3)
    runs = {F: oscillatory_response(cell, law, F, 1.0, cycles=2, samples_per_cycle=64, rtol=1e-6) for F in (3.0, 10.0)}
    for r in runs.values():
        assert r.G_loss_linear == 0.0  # C0 = 0
        assert r.G_loss > 0.0
        assert r.harmonics.work_per_cycle > 0
        assert r.harmonics.work_per_cycle == pytest.approx(r.harmonics.dissipated_per_cycle, rel=1e-3)
    # effective damping ~ c·|l'|^(β−1), so G'' grows like F^(β−1) and vanishes as F → 0
    ratio = runs[10.0].G_loss / runs[3.0].G_loss
    assert ratio == pytest.approx((10.0 / 3.0) ** 1.0, rel=0.03)


def test_beta_below_one_has_no_linear_limit(cell):
    law = power_dashpot_law(cell, beta=0.5, velocity_scale=1e-3)
    runs = {F: oscillatory_response(cell, law, F, 1.0, cycles=2, samples_per_cycle=64, rtol=1e-6) for F in (3.0, 10.0)}
    for r in runs.values():
        assert r.linear is None and "no linearization" in r.linear_note
        assert math.isnan(r.G_loss_linear)
        # from rest the second cycle is not yet periodic (work = dissipation + change of stored energy)
        assert r.harmonics.work_per_cycle == pytest.approx(r.harmonics.dissipated_per_cycle, rel=1e-2)
    # effective damping ~ |l'|^(β−1) grows without bound as the amplitude falls
    assert runs[3.0].G_loss > 1.5 * runs[10.0].G_loss


# ---- bad input -------------------------------------------------------------------------
def test_bad_input(cell, law):
    with pytest.raises(ValueError, match="amplitude"):
        SineForce(-1.0, 1.0)
    with pytest.raises(ValueError, match="frequency"):
        SineForce(1.0, 0.0)
    with pytest.raises(ValueError, match="amplitude"):
        StepForce(0.0)
    with pytest.raises(ValueError, match="33"):
        simulate(cell, Voigt(EA=np.ones(5), c=np.ones(5), l0=np.ones(5)), SineForce(1.0, 1.0), 1.0)
    with pytest.raises(ValueError, match="method"):
        simulate(cell, law, SineForce(1.0, 1.0), 1.0, method="RK45")
    with pytest.raises(ValueError, match="t_end"):
        simulate(cell, law, SineForce(1.0, 1.0), -1.0)
    with pytest.raises(ValueError, match="beta"):
        power_dashpot_law(cell, beta=-1.0)
    with pytest.raises(ValueError, match="loading"):
        EquationsOfMotion(cell, law, 3.0)
    step = simulate(cell, law, StepForce(0.1), 0.01)
    with pytest.raises(ValueError, match="SineForce"):
        harmonics(step)
    noif = tenscell.paper_cell(intermediate_filaments=False)
    with pytest.raises(SimulationError, match="damping matrix"):
        simulate(noif, voigt_law(noif), SineForce(1.0, 1.0), 1.0)


# ---- command line ---------------------------------------------------------------------
def test_cli_simulate_and_creep(tmp_path, capsys):
    import json

    from tenscell.cli import main

    out = tmp_path / "sim"
    assert main(["simulate", "--amplitude", "5", "--freq", "1", "--cycles", "3", "--samples", "64",
                 "--out", str(out)]) == 0
    names = {p.name for p in out.iterdir()}
    assert {"traces.csv", "traces.png", "loop.csv", "loop.png", "harmonics.csv", "harmonics.png",
            "simulate.json"} <= names
    assert not any(n.startswith(".") for n in names)  # no temporary files left behind
    d = json.loads((out / "simulate.json").read_text())
    for key in ("G_storage", "G_loss", "G_storage_linear", "G_loss_linear", "thd", "slack_tendons"):
        assert key in d
    assert d["G_storage"] == pytest.approx(d["G_storage_linear"], rel=2e-3)
    assert d["slack_tendons"] == [] and d["cycles_simulated"] == 3
    out2 = tmp_path / "creep"
    assert main(["creep", "--amplitude", "0.1", "--points", "21", "--out", str(out2)]) == 0
    d2 = json.loads((out2 / "creep.json").read_text())
    assert d2["steps"][0]["max_relative_departure_from_linear"] < 1e-3
    assert (out2 / "creep.png").exists() and (out2 / "relaxation.csv").exists()


def test_cli_bad_input_is_one_line_and_no_output(tmp_path, capsys):
    from tenscell.cli import main

    out = tmp_path / "bad"
    assert main(["simulate", "--amplitude", "-3", "--freq", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "amplitude" in err and len(err.strip().splitlines()) == 1
    assert not out.exists() or not any(out.iterdir())
    assert main(["simulate", "--amplitude", "1", "--freq", "1", "--no-if", "--out", str(out)]) == 2
    assert "damping matrix" in capsys.readouterr().err

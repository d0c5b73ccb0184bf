"""Unlike data (tenscell.studies.falsification): the trend changes, the grid and each point's noise do not."""
from __future__ import annotations

import math

import numpy as np
import pytest

from tenscell.io import bundled
from tenscell.io.data import DataError, RheologyData
from tenscell.studies.falsification import (DEFAULT_EXPONENT_RISE, FLAT_LOSS_TANGENT, UNLIKE_KINDS, unlike_data,
                                            unlike_sets)

STAM, FABRY = bundled("stamenovic2002"), bundled("fabry2001")


def _noisy(data, sd=0.03, seed=4):
    """The data with seeded multiplicative noise (relative sd) and matching sd columns."""
    rng = np.random.default_rng(seed)
    a, b = np.exp(rng.normal(0, sd, data.n)), np.exp(rng.normal(0, sd, data.n))
    return RheologyData(frequency_hz=data.frequency_hz, G_storage=data.G_storage * a, G_loss=data.G_loss * b,
                        prestress=data.prestress, G_storage_sd=sd * data.G_storage * a, G_loss_sd=sd * data.G_loss * b,
                        source="noisy")


def _grid():
    """A structural-damping law on a prestress × frequency grid, exponent falling with P (as cells show)."""
    P = np.repeat([400.0, 800.0, 1600.0], 5)
    f = np.tile(np.logspace(-1, 2, 5), 3)
    x = 0.22 - 0.03 * np.log(P / 400.0) / math.log(4.0)
    G = (0.2 * P) * (2j * np.pi * f) ** x
    return RheologyData(frequency_hz=f, G_storage=G.real, G_loss=G.imag, prestress=P, source="grid")


def _local_exponent(d, P):
    sel = d.prestress == P
    return np.polyfit(np.log(d.frequency_hz[sel]), np.log(np.hypot(d.G_storage[sel], d.G_loss[sel])), 1)[0]


def test_flat_keeps_grid_and_noise_and_removes_the_trend():
    d = _noisy(STAM)
    u = unlike_data(d, "prestress-independent")
    assert np.array_equal(u.prestress, d.prestress) and np.array_equal(u.frequency_hz, d.frequency_hz)
    lp = np.log(d.prestress)
    for G, Gu in ((d.G_storage, u.G_storage), (d.G_loss, u.G_loss)):
        c, cu = np.polyfit(lp, np.log(G), 2), np.polyfit(lp, np.log(Gu), 2)
        assert abs(cu[0]) < 1e-10 and abs(cu[1]) < 1e-9  # no trend left
        # each point keeps its deviation from the trend
        assert np.allclose(np.log(Gu) - np.polyval(cu, lp), np.log(G) - np.polyval(c, lp), atol=1e-12)
    assert np.allclose(u.G_storage_sd / u.G_storage, d.G_storage_sd / d.G_storage, rtol=1e-12)
    assert "prestress-independent" in u.source and "noisy" in u.source


def _trend_coefficients(d, values):
    return np.polyfit(np.log(d.prestress), np.log(values), 2)


def test_loss_independent_flattens_g_loss_only_and_keeps_each_point_off_the_trend():
    d = _noisy(STAM)
    u = unlike_data(d, "loss-independent-of-prestress")
    assert np.array_equal(u.G_storage, d.G_storage) and np.array_equal(u.prestress, d.prestress)
    c, cu = _trend_coefficients(d, d.G_loss), _trend_coefficients(u, u.G_loss)
    assert abs(cu[0]) < 1e-10 and abs(cu[1]) < 1e-9
    lp = np.log(d.prestress)
    assert np.allclose(np.log(u.G_loss) - np.polyval(cu, lp), np.log(d.G_loss) - np.polyval(c, lp), atol=1e-12)


def test_flat_loss_tangent_keeps_g_storage_and_flattens_the_loss_tangent_to_its_median_value():
    u = unlike_data(STAM, FLAT_LOSS_TANGENT)
    assert np.array_equal(u.G_storage, STAM.G_storage)
    tan, tan_u = STAM.G_loss / STAM.G_storage, u.G_loss / u.G_storage
    # the data's fall (0.33 -> 0.27) is gone; what is left is each point's deviation from the quadratic trend
    assert np.ptp(tan) > 0.05 and np.ptp(tan_u) < 0.02 * np.ptp(tan)
    c, cu = _trend_coefficients(STAM, tan), _trend_coefficients(u, tan_u)
    assert abs(cu[0]) < 1e-10 and abs(cu[1]) < 1e-9
    assert math.exp(cu[2]) == pytest.approx(math.exp(np.polyval(c, math.log(np.median(STAM.prestress)))), rel=1e-9)


def test_exponent_rising_adds_the_rise_to_the_exponent_and_to_the_phase():
    d = _grid()
    u = unlike_data(d, "exponent-rising", exponent_rise=0.1)
    delta = {400.0: -0.05, 800.0: 0.0, 1600.0: 0.05}
    for P, dlt in delta.items():
        assert _local_exponent(u, P) - _local_exponent(d, P) == pytest.approx(dlt, abs=1e-12)
        sel = d.prestress == P
        turn = np.angle(u.G_storage[sel] + 1j * u.G_loss[sel]) - np.angle(d.G_storage[sel] + 1j * d.G_loss[sel])
        assert np.allclose(turn, 0.5 * math.pi * dlt, atol=1e-12)
    # the data's exponent falls by 0.03 over the range; the unlike set's rises by 0.07
    assert _local_exponent(u, 1600.0) - _local_exponent(u, 400.0) == pytest.approx(0.07, abs=1e-9)


def test_exponent_rising_at_one_frequency_turns_the_loss_tangent():
    u = unlike_data(STAM, "exponent-rising")
    phase = np.arctan2(u.G_loss, u.G_storage) - np.arctan2(STAM.G_loss, STAM.G_storage)
    assert phase[0] == pytest.approx(-0.25 * math.pi * DEFAULT_EXPONENT_RISE, rel=1e-9)
    assert phase[-1] == pytest.approx(0.25 * math.pi * DEFAULT_EXPONENT_RISE, rel=1e-9)
    assert np.allclose(np.hypot(u.G_storage, u.G_loss), np.hypot(STAM.G_storage, STAM.G_loss), rtol=1e-12)


def test_joint_sets_change_only_the_prestress_sweeps():
    sets = unlike_sets([STAM, FABRY])
    assert set(sets) == set(UNLIKE_KINDS)
    for kind, (s, f) in sets.items():
        assert f is FABRY and s is not STAM and kind in s.source
        assert any("not what cells show" in c for c in s.comments)


def test_bad_requests():
    with pytest.raises(ValueError, match="prestress sweep"):
        unlike_sets([FABRY])
    with pytest.raises(ValueError, match="kind"):
        unlike_data(STAM, "stiffer")
    assert FLAT_LOSS_TANGENT not in UNLIKE_KINDS and set(unlike_sets([STAM], [FLAT_LOSS_TANGENT])) == {FLAT_LOSS_TANGENT}
    with pytest.raises(ValueError, match="exponent_rise"):
        unlike_data(STAM, "exponent-rising", exponent_rise=-0.1)
    with pytest.raises(DataError, match="smaller rise"):
        unlike_data(STAM, "exponent-rising", exponent_rise=5.0)
    assert unlike_data(FABRY, "prestress-independent") is FABRY  # one prestress: nothing to change

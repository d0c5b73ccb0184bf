"""Exchange with xarray and rheojax: round trips exact, units converted, rheojax by duck typing (a stand-in)."""
from dataclasses import InitVar, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tenscell as tc
from tenscell.io.creep_data import CreepData
from tenscell.io.data import DataError, RheologyData
from tenscell.io.exchange import from_rheojax, to_rheojax

DATA = Path(__file__).parent / "data"


@dataclass
class RheoData:
    """The constructor and fields of rheojax.core.data.RheoData (rheojax 0.7) that the adapters use."""

    x: Any = None
    y: Any = None
    x_units: str | None = None
    y_units: str | None = None
    domain: str = "time"
    initial_test_mode: InitVar[str | None] = None
    metadata: dict = field(default_factory=dict)

    def __post_init__(self, initial_test_mode):
        if initial_test_mode is not None:
            self.metadata["test_mode"] = initial_test_mode


def test_xarray_round_trip():
    pytest.importorskip("xarray")
    resp = tc.frequency_response(tc.paper_cell(), np.logspace(-1, 2, 7), [500.0, 1000.0, 2000.0])
    ds = resp.to_xarray()
    assert ds["G_storage"].dims == ("prestress", "frequency") and ds["G_loss"].attrs["units"] == "Pa"
    np.testing.assert_array_equal(ds["G_storage"].sel(prestress=1000.0).values, resp.G_storage[1])
    back = type(resp).from_xarray(ds)
    np.testing.assert_array_equal(back.J, resp.J)
    np.testing.assert_array_equal(back.G_loss, resp.G_loss)
    assert back.L == resp.L and back.viscosity == resp.viscosity


def test_rheojax_round_trips_for_moduli_and_creep():
    sweep = tc.read_data(DATA / "trios_lims_temperature_steps.txt", step=2)
    rd = to_rheojax(sweep, cls=RheoData)
    assert rd.domain == "frequency" and rd.x_units == "rad/s" and rd.metadata["test_mode"] == "oscillation"
    np.testing.assert_allclose(rd.x, 2 * np.pi * np.sort(sweep.frequency_hz), rtol=1e-15)
    back = from_rheojax(rd)
    np.testing.assert_allclose(back.frequency_hz, sweep.frequency_hz, rtol=1e-15)
    np.testing.assert_array_equal(back.G_storage, sweep.G_storage)
    np.testing.assert_array_equal(back.G_loss, sweep.G_loss)
    creep = tc.read_data(DATA / "creep_compliance.tsv").with_prestress(800.0)
    rc = to_rheojax(creep, cls=RheoData)
    assert rc.domain == "time" and rc.y_units == "1/Pa" and rc.metadata["prestress_Pa"] == 800.0
    cb = from_rheojax(rc)
    assert isinstance(cb, CreepData)
    np.testing.assert_array_equal(cb.compliance, creep.compliance)
    np.testing.assert_array_equal(cb.prestress, creep.prestress)


def test_rheojax_units_are_converted_and_checked():
    f = np.array([0.1, 1.0, 10.0])
    G = 0.2 * f ** 0.2 + 0.05j * f ** 0.2  # kPa
    d = from_rheojax(RheoData(x=f, y=G, x_units="Hz", y_units="kPa", domain="frequency"))
    np.testing.assert_allclose(d.G_storage, 200 * f ** 0.2, rtol=1e-15)
    np.testing.assert_allclose(d.frequency_hz, f, rtol=0)
    with pytest.raises(DataError, match="no unit is stated for G'"):
        from_rheojax(RheoData(x=f, y=G, x_units="Hz", domain="frequency"))
    with pytest.raises(DataError, match="must be > 0"):
        from_rheojax(RheoData(x=f, y=-G, x_units="Hz", y_units="Pa", domain="frequency"))
    with pytest.raises(DataError, match="test mode 'relaxation'"):
        from_rheojax(RheoData(x=f, y=f, x_units="s", y_units="Pa", domain="time", initial_test_mode="relaxation"))
    two = RheologyData(np.r_[f, f], np.ones(6), np.ones(6), prestress=[1.0] * 3 + [2.0] * 3)
    with pytest.raises(DataError, match="a prestress sweep has no RheoData form"):
        to_rheojax(two, cls=RheoData)

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


def test_netcdf_round_trip_with_the_core_install_alone(tmp_path):
    # scipy's netCDF-3 writer (a core dependency) is the engine when neither h5netcdf nor netCDF4 is installed; the
    # complex compliance is written as its real and imaginary parts, so it round-trips exactly
    pytest.importorskip("xarray")
    code = ("import sys\nfor m in ('h5netcdf', 'netCDF4'):\n    sys.modules[m] = None\n"
            "import numpy as np, tenscell as tc\nfrom tenscell._optional import netcdf_engine\n"
            "r = tc.frequency_response(tc.paper_cell(), np.logspace(-1, 2, 7), [500.0, 1000.0])\n"
            f"r.to_netcdf({str(tmp_path / 'grid.nc')!r})\n"
            f"b = type(r).from_netcdf({str(tmp_path / 'grid.nc')!r})\n"
            "print(netcdf_engine(), np.array_equal(b.J, r.J), b.L == r.L, b.viscosity == r.viscosity)\n")
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["scipy", "True", "True", "True"]


def test_from_xarray_reads_a_complex_J_too():
    xr = pytest.importorskip("xarray")
    resp = tc.frequency_response(tc.paper_cell(), np.logspace(-1, 2, 5), [800.0])
    ds = resp.to_xarray()
    old = ds.drop_vars(["J_real", "J_imag"]).assign(J=(("prestress", "frequency"), resp.J, {"units": "m/N"}))
    assert isinstance(old, xr.Dataset)
    np.testing.assert_array_equal(type(resp).from_xarray(old).J, resp.J)


@pytest.mark.parametrize("module, hint", [("rheojax.core.data", "pip install rheojax"),
                                          ("xarray", "pip install 'tenscell[exchange]'"),
                                          ("openpyxl", "pip install 'tenscell[excel]'")])
def test_every_missing_dependency_names_an_install_that_brings_it(module, hint):
    # every hint is a command that installs the module: an extra that lists it (pyproject.toml), or the package
    import subprocess
    import sys
    import tomllib

    from tenscell._optional import EXTRAS

    with open(Path(__file__).parents[1] / "pyproject.toml", "rb") as fh:
        extras = tomllib.load(fh)["project"]["optional-dependencies"]
    for name, (command, _) in EXTRAS.items():
        if "tenscell[" in command:
            extra = command.split("[")[1].split("]")[0]
            assert any(r.split(">")[0].split("[")[0].replace("-", "_") in (name, "dask") for r in extras[extra]), name
        else:
            assert command == f"pip install {name}"
    top = module.split(".")[0]
    code = (f"import sys; sys.modules[{top!r}] = None\n"
            "from tenscell._optional import require, MissingDependency\n"
            f"try:\n    require({module!r})\nexcept MissingDependency as e:\n    print(e)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert "\n" not in out and hint in out


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

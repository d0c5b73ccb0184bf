"""Result objects behave in a notebook: short repr, unit-named DataFrame, plot on the given axes.

``BUILDERS`` maps a result class name to a function building one (cheaply);
add your result classes there.
"""
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

import tenscell as tc
from tenscell._results import has_unit

MAX_REPR = 800  # characters
MAX_LINES = 7


@pytest.fixture(scope="module")
def cell():
    return tc.paper_cell()


@pytest.fixture(scope="module")
def lin(cell):
    return tc.linearize(cell, P=1000.0, EA=np.linspace(0.5, 2.0, cell.m), c=1.0)


def _structure_file(tmp_path_factory, cell):
    path = tmp_path_factory.mktemp("sf") / "cell.json"
    tc.io.save_structure(path, cell.structure, EA=2.0, c=0.5, T0=cell.T0, description="the paper cell\nsecond line")
    return tc.io.load_structure_file(path)


BUILDERS = {
    "Structure": lambda cell, lin, tmp: cell.structure,
    "Cell": lambda cell, lin, tmp: cell,
    "LinearModel": lambda cell, lin, tmp: lin,
    "RelaxationSpectrum": lambda cell, lin, tmp: tc.linear.relaxation_spectrum(lin),
    "FrequencyResponse": lambda cell, lin, tmp: tc.frequency_response(cell, np.logspace(-1, 2, 7), [500.0, 2000.0]),
    "CreepSpectrum": lambda cell, lin, tmp: tc.timedomain.creep_spectrum(lin),
    "StressRelaxation": lambda cell, lin, tmp: tc.stress_relaxation(lin),
    "PowerLawFit": lambda cell, lin, tmp: tc.timedomain.fit_power_law(np.logspace(-2, 1, 12), 2e-3 * np.logspace(-2, 1, 12) ** 0.3),
    "RelaxationModes": lambda cell, lin, tmp: tc.summary.relaxation_modes(lin, 3),
    "StructureSummary": lambda cell, lin, tmp: tc.summarize(cell)[0],
    "StructureFile": lambda cell, lin, tmp: _structure_file(tmp, cell),
    "FormFindingResult": lambda cell, lin, tmp: tc.model.find_form(tc.model.expanded_octahedron(), force_density=1.0),
    "RheologyData": lambda cell, lin, tmp: tc.bundled("stamenovic2002"),
    "EnsembleResult": lambda cell, lin, tmp: _ensemble(cell),
}


def _ensemble(cell):
    from tenscell.fitting.fitted import FittedMechanism
    from tenscell.fitting.models.catalog import MECHANISMS
    from tenscell.population import mechanism_ensemble

    model = FittedMechanism(MECHANISMS["voigt-lognormal-damping"], cell, {"EA_actin": 1.0, "EA_intermediate_filament": 0.2,
                                                                           "c": 0.3, "c_decades": 1.0}, s=1e-3,
                            prestress_pa=(1000.0,))
    return mechanism_ensemble(model, np.logspace(-1, 2, 7), [500.0, 2000.0], K=20, workers=0, progress=False)


@pytest.fixture(scope="module", params=sorted(BUILDERS))
def result(request, cell, lin, tmp_path_factory):
    obj = BUILDERS[request.param](cell, lin, tmp_path_factory)
    assert type(obj).__name__ == request.param
    return obj


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_repr_is_short_and_says_what_it_is(result):
    text = repr(result)
    assert len(text) < MAX_REPR and len(text.splitlines()) <= MAX_LINES, text
    assert text.startswith(f"<{type(result).__name__}")
    assert "array(" not in text


def test_dataframe_columns_carry_units(result):
    df = result.to_dataframe()
    assert isinstance(df, pd.DataFrame) and len(df) > 0
    floats = [c for c in df.columns if pd.api.types.is_float_dtype(df[c])]
    assert floats, "a result table without a single quantity"
    missing = [c for c in floats if not has_unit(c)]
    assert not missing, f"{type(result).__name__}: columns without a unit: {missing}"


def test_plot_draws_on_the_given_axes(result):
    if not hasattr(result, "plot"):
        pytest.skip(f"{type(result).__name__} has nothing to draw")
    three_d = type(result).__name__ in ("Structure", "Cell", "StructureFile", "FormFindingResult")
    two = type(result).__name__ in ("FrequencyResponse", "LinearModel")
    fig = plt.figure()
    if two:
        axes = fig.subplots(1, 2)
        got = result.plot(axes=axes)
        assert list(got) == list(axes)
    else:
        ax = fig.add_subplot(projection="3d" if three_d else None)
        assert result.plot(ax=ax) is ax
    assert len(fig.axes) == (2 if two else 1)  # nothing drawn elsewhere
    assert all(a.has_data() for a in fig.axes)


# ---- the tables hold the result's own numbers -------------------------------------------------
def test_response_table_is_the_grid(cell):
    resp = BUILDERS["FrequencyResponse"](cell, None, None)
    df = resp.to_dataframe()
    grid = df.pivot(index="prestress_N", columns="frequency_Hz", values="G_storage_Pa")
    np.testing.assert_array_equal(grid.to_numpy(), resp.G_storage)
    np.testing.assert_allclose(df["loss_tangent"], df["G_loss_Pa"] / df["G_storage_Pa"], rtol=1e-14)


def test_linear_model_table_tensions_are_P_T0(lin):
    df = lin.to_dataframe()
    np.testing.assert_allclose(df["tension_N"], lin.P * lin.cell.T0, rtol=1e-15)
    np.testing.assert_array_equal(df["EA_N"], lin.EA)
    assert df.attrs["P_N"] == lin.P


def test_structure_table_lengths_are_member_lengths(cell):
    df = cell.structure.to_dataframe("struts")
    np.testing.assert_allclose(df["length_m"], cell.structure.strut_lengths, rtol=1e-15)
    nodes = cell.structure.to_dataframe("nodes")
    np.testing.assert_array_equal(nodes[["x_m", "y_m", "z_m"]].to_numpy(), cell.structure.nodes)
    with pytest.raises(ValueError, match="members"):
        cell.structure.to_dataframe("bars")


def test_spectrum_tables_add_up_to_the_static_compliance(lin):
    creep = tc.timedomain.creep_spectrum(lin)
    df = creep.to_dataframe()
    assert df["weight_m_per_N"].sum() + df.attrs["instantaneous_m_per_N"] == pytest.approx(creep.static, rel=1e-12)
    rel = tc.linear.relaxation_spectrum(lin).to_dataframe()
    np.testing.assert_allclose(rel["time_s"] * rel["rate_per_s"], 1.0, rtol=1e-15)
    assert rel["weight_m_per_N"].sum() == pytest.approx(creep.static, rel=1e-9)  # two routes to J(∞)


def test_linear_model_plot_draws_its_own_moduli(lin):
    f = np.logspace(-1, 2, 5)
    axes = lin.plot(f_hz=f)
    G = (0.5 / lin.L) / tc.compliance(lin, f)
    np.testing.assert_allclose(axes[0].get_lines()[0].get_ydata(), G.real, rtol=1e-12)
    np.testing.assert_allclose(axes[1].get_lines()[0].get_ydata(), G.imag, rtol=1e-12)

"""Plotting draws where it is told, returns what it drew on, and never touches global matplotlib state."""
import os
import subprocess
import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest

import tenscell as tc
from tenscell import plotting
from tenscell.io.data import bundled


@pytest.fixture(scope="module")
def resp():
    return tc.frequency_response(tc.paper_cell(), np.logspace(-1, 2, 5), [500.0, 1000.0, 2000.0])


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_import_does_not_choose_a_backend():
    # The user's choice (here the headless SVG backend) survives importing and using tenscell.plotting.
    env = {**os.environ, "MPLBACKEND": "svg"}
    code = ("import matplotlib as m; before = dict(m.rcParams); "
            "import tenscell.plotting as p; "
            "p.creep_loglog([1.0, 2.0], {'J': [1.0, 2.0]}); "
            "after = dict(m.rcParams); "
            "assert before == after, [k for k in before if before[k] != after[k]]; "
            "print(m.get_backend())")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip().lower() == "svg"


def test_draws_on_given_axes_and_returns_them(resp):
    fig, axes = plt.subplots(1, 2)
    got = plotting.fig3_frequency(resp, axes=axes)
    assert list(got) == list(axes)
    assert len(fig.axes) == 2  # no new figure, no extra axes
    lines = axes[0].get_lines()
    assert len(lines) == len(resp.prestress)
    for line, Gs in zip(lines, resp.G_storage):
        np.testing.assert_array_equal(line.get_ydata(), Gs)
    for line, Gl in zip(axes[1].get_lines(), resp.G_loss):
        np.testing.assert_array_equal(line.get_ydata(), Gl)
    assert axes[0].get_xscale() == "log"


def test_prestress_panels_are_columns_of_the_response(resp):
    ax = plotting.fig2_prestress(resp)
    assert len(ax) == 2
    for k, line in enumerate(ax[1].get_lines()):
        np.testing.assert_array_equal(line.get_xdata(), resp.prestress)
        np.testing.assert_array_equal(line.get_ydata(), resp.G_loss[:, k])


def test_house_style_only_on_own_figures(resp):
    before = dict(matplotlib.rcParams)
    own = plotting.fig3_frequency(resp)
    assert dict(matplotlib.rcParams) == before  # a context, never global
    assert own[0].figure.dpi == plotting.STYLE["figure.dpi"]
    with plt.rc_context({"figure.dpi": 72, "axes.grid": False}):
        fig, axes = plt.subplots(1, 2)
        plotting.fig3_frequency(resp, axes=axes)
        assert fig.dpi == 72
        assert not any(gl.get_visible() for gl in axes[0].xaxis.get_gridlines())


def test_wrong_number_of_axes_is_a_clear_error(resp):
    fig, ax = plt.subplots()
    with pytest.raises(ValueError, match="axes: .*2 panel"):
        plotting.fig3_frequency(resp, axes=[ax])


def test_structure_needs_a_3d_axes_and_draws_every_member():
    cell = tc.paper_cell()
    fig, flat = plt.subplots()
    with pytest.raises(ValueError, match="ax: .*3d"):
        plotting.structure_3d(cell.structure, ax=flat)
    ax = plt.figure().add_subplot(projection="3d")
    assert plotting.structure_3d(cell.structure, ax=ax) is ax
    s = cell.structure
    ax.figure.canvas.draw()  # 3D segments are projected at draw time
    drawn = sum(len(c.get_segments()) for c in ax.collections if hasattr(c, "get_segments") and c.get_label()
                in ("struts (microtubules)", "actin", "intermediate filaments"))
    assert drawn == len(s.struts) + len(s.tendons)


def test_fit_panels_show_the_data(resp):
    data = bundled("fabry2001")
    fig, ax = plt.subplots()
    plotting.data_points(data, ax)
    np.testing.assert_array_equal(ax.get_lines()[0].get_xdata(), data.frequency_hz)
    np.testing.assert_array_equal(ax.get_lines()[1].get_ydata(), data.G_loss)


def test_creep_single_or_two_panels():
    t = np.logspace(-2, 1, 7)
    J = 1e-3 * t ** 0.2
    one = plotting.creep_loglog(t, {"model": J})
    assert one.get_yscale() == "log"
    two = plotting.creep_loglog(t, {"model": J}, {"model": np.full_like(t, 0.2)})
    assert len(two) == 2 and two[0].figure is two[1].figure


def test_save_takes_what_a_plot_returned(tmp_path, resp):
    axes = plotting.fig3_frequency(resp)
    fig = axes[0].figure
    plotting.save(axes, tmp_path / "f.png")
    assert (tmp_path / "f.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not plt.fignum_exists(fig.number)  # closed after saving
    with pytest.raises(TypeError, match="save"):
        plotting.save("not a figure", tmp_path / "g.png")


def test_png_bytes_are_what_save_writes(resp, tmp_path):
    """The fit command draws its figure in a worker and writes the bytes: they must be the saved PNG."""
    data = plotting.png_bytes(resp.plot())
    plotting.save(resp.plot(), tmp_path / "f.png")
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert data == (tmp_path / "f.png").read_bytes()
    assert not plt.get_fignums()  # both closed their figure




def test_a_large_lattice_and_its_modes_are_drawn_as_the_same_section():
    # above max_members both figures draw the members in one slab across y (midpoints within the slab, every
    # member outside it left out), one collection per family, and say how many of how many they drew
    block = tc.model.lattice_cell(4, 4, 3).structure
    S, T = np.asarray(block.struts, dtype=int).reshape(-1, 2), np.asarray(block.tendons, dtype=int)
    n = len(S) + len(T)
    most = n // 5
    x = block.nodes
    mid_y = 0.5 * (x[np.r_[S[:, 0], T[:, 0]], 1] + x[np.r_[S[:, 1], T[:, 1]], 1])
    centre = 0.5 * (x[:, 1].min() + x[:, 1].max())
    half = np.sort(np.abs(mid_y - centre))[most - 1]
    expected = int((np.abs(mid_y - centre) <= half).sum())
    assert most <= expected < n / 2

    ax = plotting.structure_3d(block, max_members=most)
    families = {c.get_label() for c in ax.collections if c.get_label() and not c.get_label().startswith("_")}
    member_collections = [c for c in ax.collections if c.get_label() in
                          ("struts (microtubules)", "actin", "intermediate filaments")]
    assert len(member_collections) == len(families - {"anchors", "load"})  # one collection per family
    seg = np.concatenate([np.asarray(c._segments3d, dtype=float) for c in member_collections])
    assert len(seg) == expected
    assert np.all(np.abs(seg[:, :, 1].mean(axis=1) - centre) <= half + 1e-12)
    assert f"{expected:,} of {n:,} members drawn" in ax.get_title()

    modes = np.random.default_rng(0).normal(size=(2, len(x), 3))
    panels = plotting.relaxation_modes_3d(block, [1.0, 2.0], modes, max_members=most)
    for p in panels:
        lines = [c for c in p.collections if type(c).__name__ == "Line3DCollection" and c.get_alpha() == 0.35]
        assert sum(len(c._segments3d) for c in lines) == expected
        assert f"{expected:,} of {n:,} members drawn" in p.get_title()
    assert "section" in panels[0].figure._suptitle.get_text()
    # below the threshold every member is drawn and the titles say nothing of a section
    every = plotting.relaxation_modes_3d(block, [1.0, 2.0], modes, max_members=n)
    assert "members drawn" not in every[0].get_title()

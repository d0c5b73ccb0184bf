"""Figures a journal would take: every title, label, tick label and legend inside the canvas; no legend over data.

Each figure the package saves (reproduce, fit, show, the studies) is drawn here on small inputs, rendered with the
Agg renderer, and checked with the artists' own window extents (``get_window_extent``, ``Axes.get_tightbbox``):
a clipped title or a legend covering curves fails, whatever the figure looks like otherwise.
"""
import matplotlib

matplotlib.use("Agg")  # noqa: E402 - the measuring renderer; the package itself never chooses a backend

import matplotlib.pyplot as plt
import numpy as np
import pytest

import tenscell as tc
from tenscell import plotting
from tenscell.io.data import bundled

#: a pixel of slack for rounding of extents (at the figures' 150 dpi)
TOL_PX = 1.0


def problems(fig) -> list[str]:
    """What lies outside the canvas, and which legends cover data points."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    W, H = fig.bbox.width, fig.bbox.height
    out = []

    def check(what, bb):
        if bb.x0 < -TOL_PX or bb.y0 < -TOL_PX or bb.x1 > W + TOL_PX or bb.y1 > H + TOL_PX:
            out.append(f"{what} at {[round(v) for v in bb.extents]} outside {round(W)}x{round(H)}")

    for t in fig.texts:
        if t.get_visible() and t.get_text().strip():
            check(f"figure text {t.get_text()[:40]!r}", t.get_window_extent(r))
    for leg in fig.legends:
        check("figure legend", leg.get_window_extent(r))
    for ax in fig.axes:
        if ax.get_visible():
            out += _axes_problems(ax, r, check)
    return out


def _axes_problems(ax, r, check) -> list[str]:
    """An axes' labels, tick labels and legend inside the canvas (``check``), and its legend over no data point."""
    labels = [("title", ax.title), ("xlabel", ax.xaxis.label), ("ylabel", ax.yaxis.label)]
    if hasattr(ax, "zaxis"):
        labels.append(("zlabel", ax.zaxis.label))
    for name, t in labels:
        if t.get_visible() and t.get_text().strip():
            check(f"{name} {t.get_text()[:40]!r}", t.get_window_extent(r))
    check(f"axes {ax.get_title()[:30]!r} (tick labels)", ax.get_tightbbox(r))
    leg = ax.get_legend()
    if leg is None:
        return []
    check("legend", leg.get_window_extent(r))
    if ax.name == "3d":
        return []
    box = leg.get_window_extent(r)
    covered = 0
    for line in ax.get_lines():
        xy = line.get_xydata()
        if xy.size:
            p = ax.transData.transform(xy)
            covered += int(np.sum((p[:, 0] > box.x0) & (p[:, 0] < box.x1) & (p[:, 1] > box.y0) & (p[:, 1] < box.y1)))
    return [f"legend of {ax.get_title()[:30]!r} covers {covered} data points"] if covered else []


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def resp():
    return tc.frequency_response(tc.paper_cell(), np.logspace(-2, 3, 41), np.linspace(100.0, 3000.0, 12))


@pytest.fixture(scope="module")
def fits():
    prestress = tc.fit(bundled("stamenovic2002"), tendons="uniform", starts=1, progress=False)
    frequency = tc.fit(bundled("fabry2001"), tendons="uniform", starts=1, progress=False)
    creep = tc.fit(tc.read_data(__import__("pathlib").Path(__file__).parent / "data" / "creep_compliance.tsv"),
                   tendons="uniform", starts=1, progress=False)
    return prestress, frequency, creep


def _fig(obj):
    return plotting.figure_of(obj)


def test_paper_figures(resp):
    r2 = tc.frequency_response(tc.paper_cell(), [0.01, 0.1, 1.0, 10.0, 100.0], np.linspace(100.0, 3000.0, 30))
    assert problems(_fig(plotting.fig2_prestress(r2))) == []
    assert problems(_fig(plotting.fig3_frequency(resp))) == []
    # the legends name their unit
    ax = plotting.fig3_frequency(resp)
    assert "(N)" in ax[1].get_legend().get_title().get_text()
    assert "(Hz)" in plotting.fig2_prestress(r2)[1].get_legend().get_title().get_text()


def test_fit_figures(fits):
    prestress, frequency, creep = fits
    title = "Fig. 4: moduli versus prestress at 0.1 Hz (Stamenović 2002), a title longer than the panel"
    assert problems(_fig(plotting.fit_panels(prestress, baseline=prestress, title=title))) == []
    assert problems(_fig(plotting.fit_panels(frequency, baseline=frequency, title="Fig. 5"))) == []
    assert problems(_fig(plotting.fit_panels(creep, baseline=creep, title="creep"))) == []
    assert problems(_fig(plotting.measured(bundled("fabry2001"), title="measured"))) == []
    assert problems(_fig(plotting.compactness_front([1, 2, 3], [0.3, 0.02, 0.005], 0.01, 2.0, title="front"))) == []
    assert problems(_fig(plotting.stiffness_histogram(np.logspace(-2, 2, 24), families=["a"] * 12 + ["b"] * 12))) == []


def test_structures_and_modes():
    cell = tc.paper_cell()
    assert problems(_fig(plotting.structure_3d(cell.structure, title="paper cell (Fig. 1 colours)"))) == []
    modes = tc.summary.relaxation_modes(tc.linearize(cell), 3)
    assert problems(_fig(plotting.relaxation_modes_3d(cell.structure, modes.rates, modes.displacements))) == []


def test_a_large_lattice_is_drawn_as_a_section():
    block = tc.model.lattice_cell(4, 4, 4).structure
    n = len(block.struts) + len(block.tendons)
    ax = plotting.structure_3d(block, max_members=n // 4)
    drawn = sum(len(c.get_segments()) for c in ax.collections if hasattr(c, "get_segments"))
    assert drawn < n / 2 and "section" in ax.get_title()
    assert problems(_fig(ax)) == []


def test_time_domain_and_result_plots(resp):
    t = np.logspace(-1, 1, 30)
    assert problems(_fig(plotting.creep_loglog(t, {"linear": t ** 0.2, "nonlinear": 1.1 * t ** 0.2},
                                               {"linear": np.full(30, 0.2)}, None, "creep after a step"))) == []
    assert problems(_fig(resp.plot())) == []
    assert problems(_fig(tc.linearize(tc.paper_cell()).plot())) == []


def test_every_plot_takes_ax(resp):
    """One keyword for every result's plot: ``ax=`` (a pair of axes for the two-panel moduli plots)."""
    fig, axes = plt.subplots(1, 2)
    assert list(resp.plot(ax=axes)) == list(axes)
    fig, axes = plt.subplots(1, 2)
    assert list(tc.linearize(tc.paper_cell()).plot(ax=axes)) == list(axes)
    fig, axes = plt.subplots(1, 2)
    assert list(resp.plot(axes=axes)) == list(axes)  # the older spelling still works


def test_the_check_sees_a_clipped_title_and_a_covering_legend():
    fig, ax = plt.subplots(figsize=(3, 2), layout="constrained")
    x = np.linspace(0, 1, 50)
    ax.plot(x, x, label="a curve under the legend")
    ax.legend(loc="center")
    fig.suptitle("a title far longer than a three-inch figure can hold on one line")
    found = problems(fig)
    assert any(p.startswith("figure text") for p in found) and any("covers" in p for p in found)


def test_variant_figures():
    from tenscell.studies.no_if import no_if_study
    from tenscell.studies.semiflexible import semiflexible_study
    from tenscell.studies.stiffening import stiffening_study

    s = no_if_study(prestress=(500.0, 1000.0, 2000.0), f_hz=np.logspace(-1, 3, 20), EA_values=(1.0,), c_values=(1.0,))
    assert problems(_fig(plotting.no_if_figure(s))) == []
    assert problems(_fig(plotting.no_if_peaks_figure(s))) == []
    st = stiffening_study(b=(0.0, 0.01), prestress=(500.0, 1000.0, 4500.0), f_hz=(1.0,))
    assert problems(_fig(plotting.stiffening_figure(st))) == []
    sf = semiflexible_study(EA_strut=np.logspace(6, 9, 4), f_hz=np.logspace(-1, 2, 5))
    assert problems(_fig(plotting.semiflexible_figure(sf))) == []
    el = tc.sensitivity.elasticities(f_hz=np.logspace(-1, 2, 5))
    assert problems(_fig(plotting.elasticities_figure(el))) == []

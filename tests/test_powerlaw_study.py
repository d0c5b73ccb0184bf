"""The power-law study: its metrics on curves whose answers are known (a pure power law, a Voigt element, a
Zener step), its plan, and its assembly on a map of synthetic results and on one real tiny structure."""
from __future__ import annotations

import math

import numpy as np
import pytest

from tenscell.studies import powerlaw as pl
from tenscell.studies.powerlaw_metrics import NO_STRETCH, flat_stretch, local_exponent, prestress_trend
from tenscell.studies.protocol import Plan, Task


def _power_law(f, alpha, G0=100.0):
    G = G0 * (2j * math.pi * f) ** alpha
    return G.real, G.imag


def test_a_pure_power_law_is_flat_over_the_whole_band_with_its_own_loss_tangent():
    f = pl.frequencies((1e-3, 1e4))
    Gs, Gl = _power_law(f, 0.2)
    a = local_exponent(f, Gs)
    assert np.allclose(a, 0.2, atol=1e-12)
    s = flat_stretch(f, a, Gl / Gs, band=(0.1, 0.3), tan_tolerance=0.2)
    assert s.decades == pytest.approx(7.0)
    assert s.alpha == pytest.approx(0.2)
    assert s.tan_ratio == pytest.approx(0.0, abs=1e-12)


def test_a_voigt_element_has_no_weak_power_law():
    f = pl.frequencies((1e-3, 1e4))
    G = 1.0 + 2j * math.pi * f * 0.1  # k(1 + iωτ): G' flat, G'' ∝ f
    a = local_exponent(f, G.real)
    assert flat_stretch(f, a, G.imag / G.real, band=(0.1, 0.3)) == NO_STRETCH


def test_a_zener_step_passes_through_the_band_in_less_than_a_decade():
    f = pl.frequencies((1e-3, 1e4))
    w = 2 * math.pi * f
    G = 1.0 + 10.0 * 1j * w / (1 + 1j * w)  # one relaxation time: G' rises tenfold around 0.16 Hz
    a = local_exponent(f, G.real)
    s = flat_stretch(f, a, G.imag / G.real, band=(0.1, 0.3))
    assert 0 < s.decades < 1.0


def test_the_tolerance_bounds_the_spread_of_alpha():
    f = np.logspace(0, 4, 41)
    a = np.linspace(0.1, 0.3, 41)  # α drifts 0.2 over four decades
    s = flat_stretch(f, a, tolerance=0.05)
    assert s.decades == pytest.approx(2.0)  # a spread of 0.1 is half the drift


def test_prestress_trend_is_the_slope_in_log_prestress():
    P = np.array([1.0, 3.0, 10.0, 30.0])
    alpha = 0.25 - 0.02 * np.log(P)[:, None] + np.zeros((4, 5))
    assert np.allclose(prestress_trend(P, alpha), -0.02)
    with pytest.raises(ValueError, match="two prestresses"):
        prestress_trend([1.0], alpha[:1])


def test_plan_counts_every_structure_and_one_fit_per_family():
    plan = pl.plan({"scale": "tiny"})
    points = pl.map_points("tiny")
    assert plan.count("fit") == 3
    assert plan.count() == len(points) + 3
    assert len({t.key for t in plan.tasks}) == plan.count()
    for t in plan.tasks:
        assert t.fn.__module__ == pl.__name__ and "." not in t.fn.__qualname__  # module-level: it pickles
    assert math.isfinite(plan.estimate_cpu(pl.CALIBRATION))
    with pytest.raises(ValueError, match="scale"):
        pl.plan({"scale": "huge"})
    with pytest.raises(ValueError, match="unknown option"):
        pl.plan({"depth": 3})


def _synthetic(family, structure, knobs, G_of, prestrains=pl.PRESTRAINS):
    f = pl.frequencies()
    G = np.array([G_of(f, e) for e in prestrains])
    return pl.PointResult(point=pl.MapPoint(family, structure, knobs), coordinates=10, members=20,
                          prestrain=np.array(prestrains), prestress=np.array(prestrains) * 10,
                          frequency_hz=f, G_storage=G.real, G_loss=G.imag, build_cpu_s=0.1,
                          spectrum_cpu_s=np.full(len(prestrains), 0.1), connectivity=6.0)


def test_assemble_finds_a_power_law_and_its_prestress_trend():
    """A map whose 'hierarchical' curve is a pure power law (α = 0.2 at every prestrain, G ∝ P) meets G6a and
    shows no trend with P; its 'diluted' curves are Voigt elements and show no power law at all."""
    power = _synthetic("hierarchical", "simplex net", (("module_nodes", 4), ("depth", 3)),
                       lambda f, e: 10 * e * (2j * math.pi * f) ** 0.2)
    voigt = _synthetic("diluted", "diluted net", (("size", 3), ("connectivity", 6.0), ("seed", 0)),
                       lambda f, e: e * (1 + 2j * math.pi * f))
    plan = Plan(study=pl.NAME, options={"scale": "tiny"},
                tasks=(Task(power.point.key, "spectrum", pl.evaluate_point),
                       Task(voigt.point.key, "spectrum", pl.evaluate_point)))
    res = pl.assemble(plan, {power.point.key: power, voigt.point.key: voigt})
    fams = {r["family"]: r for r in res.table("powerlaw_families").records()}
    assert fams["hierarchical"]["g6_decades"] == pytest.approx(7.0)
    assert fams["hierarchical"]["g6_alpha"] == pytest.approx(0.2)
    assert fams["hierarchical"]["dalpha_dlnP_common_band"] == pytest.approx(0.0, abs=1e-12)
    assert fams["diluted"]["band_decades"] == 0.0
    checks = {c.label[:4]: c for c in res.checks}
    assert checks["G6a:"].met and not checks["G6b:"].met
    assert "powerlaw_map.png" in res.files() and "powerlaw.md" in res.files()
    page = dict(res.pages)["powerlaw.md"]
    assert "(a) A power law" in page and "(b) Does raising the prestress" in page
    rows = res.table("powerlaw_moduli").records()
    assert len(rows) == 2 * len(pl.PRESTRAINS) * pl.frequencies().size


def test_a_falling_exponent_is_seen_as_falling():
    """α = 0.2 − 0.02 ln(ε/0.1): the study's trend is −0.02 per e-fold of prestress."""
    def G(f, e):
        a = 0.2 - 0.02 * math.log(e / 0.1)
        return (2j * math.pi * f) ** a
    r = _synthetic("hierarchical", "simplex net", (("module_nodes", 4), ("depth", 3)), G)
    t = pl.trend(r)
    assert t["dalpha_dlnP_common_band"] == pytest.approx(-0.02, abs=1e-9)
    assert t["common_band_decades"] == pytest.approx(7.0)  # the map reads 10⁻³–10⁴ Hz
    assert t["delta_alpha_0p1Hz"] == pytest.approx(-0.02 * math.log(30), abs=1e-9)


def test_one_tiny_structure_end_to_end():
    """A real structure through the task: passive, its G' rising with f, and the exact scaling of a scaled fit."""
    point = pl.map_points("tiny")[0]
    f = pl.frequencies((1e-2, 1e2), 4)
    r = pl.evaluate_point(point, (0.03, 0.3), f)
    assert r.G_storage.shape == (2, f.size)
    assert np.all(r.G_loss > 0)
    assert np.all(np.diff(r.G_storage, axis=1) >= -1e-9 * r.G_storage[:, 1:])  # a passive G' never falls with f
    assert r.coordinates > 0 and r.build_cpu_s >= 0


def test_scaled_fit_recovers_the_scales_of_a_scaled_copy():
    """Data made from the structure itself, stiffness ×3 and time ×0.5 at one prestrain: RMS ~0, scales found."""
    from tenscell.io.rheology import RheologyData

    f = pl.frequencies()
    eps = np.logspace(-2, 0, 5)
    G = np.array([e * (1 + (2j * math.pi * f) ** (0.2 + 0.02 * math.log(e))) for e in eps])
    fd = np.logspace(-2, 2, 9)
    e0 = eps[2]
    Gd = 3.0 * e0 * (1 + (2j * math.pi * fd * 0.5) ** (0.2 + 0.02 * math.log(e0)))
    data = RheologyData(frequency_hz=fd, G_storage=Gd.real, G_loss=Gd.imag)
    fit = pl.scaled_fit(f, eps, G, {"made": data})
    assert fit.rms_log10[0] < 1e-4
    assert fit.stiffness_scale == pytest.approx(3.0, rel=1e-3)
    assert fit.time_scale == pytest.approx(0.5, rel=1e-3)
    assert fit.prestrain == pytest.approx(e0, rel=1e-3)


def _synthetic_study():
    power = _synthetic("hierarchical", "simplex net", (("module_nodes", 4), ("depth", 3)),
                       lambda f, e: 10 * e * (2j * math.pi * f) ** 0.2)
    voigt = _synthetic("diluted", "diluted net", (("size", 3), ("connectivity", 6.0), ("seed", 0)),
                       lambda f, e: e * (1 + 2j * math.pi * f))
    zener = pl.PointResult(**{**_synthetic("structural", "lattice", (("modules", 2),),
                                           lambda f, e: e * (1 + 10j * f / (1 + 1j * f))).__dict__,
                              "point": pl.MapPoint("structural", "lattice", (("modules", 2),), damping="length",
                                                   damping_value=2.0)})
    return pl.PowerLawStudy(scale="tiny", points=(voigt, power, zener))


@pytest.mark.parametrize("name, plotter", pl.FIGURES)
def test_figures_keep_everything_inside_the_canvas(name, plotter):
    """Publication quality as the other studies' figures are held to it (tests/test_figures_inside.py)."""
    import matplotlib.pyplot as plt
    from test_figures_inside import problems

    from tenscell._results import plotter as draw
    from tenscell.plotting import figure_of

    fig = figure_of(draw(plotter)(_synthetic_study()))
    try:
        assert problems(fig) == [], name
    finally:
        plt.close(fig)

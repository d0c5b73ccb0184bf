"""claims.md compares the homogeneous model with cells as exponents and ratios, and says what the data are."""
from __future__ import annotations

import numpy as np
import pytest

from tenscell.studies.claims import against_cells, claims_markdown, homogeneous_study, paper_claims


@pytest.fixture(scope="module")
def study():
    return homogeneous_study(prestress=np.linspace(500.0, 4500.0, 9))


def test_against_cells_by_hand(study):
    rows = {(r.quantity, r.where.split(",")[0]): r for r in against_cells(study)}
    # the bundled prestress data follow G' = 0.20 P + 82, G'' = 0.05 P + 32 (their own comment): at 1000 Pa
    assert rows[("∂lnG'/∂lnP", "0.1 Hz")].cells == pytest.approx(200 / 282, abs=0.01)
    assert rows[("∂lnG''/∂lnP", "0.1 Hz")].cells == pytest.approx(50 / 82, abs=0.01)
    # the bundled frequency data follow the structural-damping law with x − 1 = 0.20: G''/G' ≈ tan(0.1π) at 0.1 Hz
    assert rows[("G''/G'", "0.1 Hz")].cells == pytest.approx(np.tan(0.1 * np.pi), rel=0.01)
    assert rows[("G' frequency exponent", "0.1–1 Hz")].cells == pytest.approx(0.20, abs=0.01)
    # the homogeneous model: G'' nearly blind to P, G'' ≪ G' at low frequency, G' flat
    model = {k: r.model for k, r in rows.items()}
    assert model[("∂lnG''/∂lnP", "0.1 Hz")] < 0.1 < model[("∂lnG'/∂lnP", "0.1 Hz")]
    assert model[("G''/G'", "0.1 Hz")] < 0.05 and model[("G' frequency exponent", "0.1–1 Hz")] < 0.05


def test_claims_markdown_has_no_nan_and_says_the_data_are_generated(study):
    robust = {"EA (all)": (0.003, 0.004, ""), "delta": (float("nan"), float("nan"), "−: not a valid reference")}
    md = claims_markdown(paper_claims(study, robust), study)
    assert "nan" not in md.lower()
    assert "not measurable" in md
    assert "## Against cells" in md and "∂lnG''/∂lnP" in md
    assert "not raw measurements" in md

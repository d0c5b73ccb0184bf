"""A fit inside the data's own noise is not a failure (issue 18 item 6): verdict, fit.json and exit status agree.

The data: the paper cell's own moduli at 8 frequencies, each point moved by ±5 % (0.021 decades, alternating
in sign, which no smooth model follows), with standard deviations stated in sd columns. With sd = 30 % of G
(0.13 decades in log10 G) the best fit lies far inside the noise; with sd = 1 % (0.0043 decades) far outside.
The tolerance asked, 1e-6 decades, is out of reach either way. Both kinds of fit (per-tendon `fit`, and
`fit --model`) must say the same thing: inside the noise is converged (exit 0), with the report stating that
the optimizer's tolerance was not met and that it lies below the noise; outside it, not converged (exit 1).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from tenscell import linearize, moduli, paper_cell
from tenscell.cli import main as cli_main

F = np.logspace(-1, 2, 8)


def _write(path, sd_fraction: float):
    cell = paper_cell()
    EA = np.where(np.asarray(cell.structure.families) == "actin", 1.0, 0.1)
    Gs, Gl = moduli(linearize(cell, P=1.0, EA=EA, c=0.5), F)
    wiggle = 1.05 ** np.resize([1.0, -1.0], F.size)
    rows = ["frequency_Hz,G_storage_Pa,G_loss_Pa,G_storage_sd_Pa,G_loss_sd_Pa"]
    for f, a, b in zip(F, Gs * wiggle, Gl / wiggle):
        rows.append(f"{f:.10g},{a:.10g},{b:.10g},{sd_fraction * a:.10g},{sd_fraction * b:.10g}")
    path.write_text("\n".join(rows) + "\n")
    return path


FITS = {
    "per-tendon": ["--tendons", "per-family", "--damping", "per-family", "--baseline-starts", "1"],
    "mechanism": ["--model", "voigt-compact"],
}


@pytest.mark.parametrize("kind", sorted(FITS))
def test_a_fit_inside_the_noise_exits_0_and_says_why(kind, tmp_path, capsys):
    data = _write(tmp_path / "noisy.csv", 0.30)
    out = tmp_path / "fit"
    code = cli_main(["fit", str(data), *FITS[kind], "--starts", "1", "--tolerance", "1e-6", "--out", str(out)])
    doc = json.loads((out / "fit.json").read_text())
    rms = doc.get("rms_log10_error_per_dataset", [d["rms_log10_error"] for d in doc.get("datasets", [])])
    noise = doc["noise_rms_log10_per_dataset"]
    # the premise: the tolerance is missed, the fit is inside the stated noise (0.13 decades)
    assert rms[0] > 1e-6 and rms[0] <= noise[0] and noise[0] > 0.1
    assert doc["converged"] is True and doc["tolerance_met"] is False
    assert code == 0
    report = (out / "report.md").read_text()
    assert "inside the data's noise" in report.lower() and "NOT converged" not in report
    assert "not met" in report and "below" in report  # the tolerance was not met; it is below the noise
    assert "inside the data's noise" in capsys.readouterr().err


@pytest.mark.parametrize("kind", sorted(FITS))
def test_a_fit_outside_the_noise_is_not_converged(kind, tmp_path):
    data = _write(tmp_path / "precise.csv", 0.01)
    out = tmp_path / "fit"
    code = cli_main(["fit", str(data), *FITS[kind], "--starts", "1", "--tolerance", "1e-6", "--out", str(out)])
    doc = json.loads((out / "fit.json").read_text())
    rms = doc.get("rms_log10_error_per_dataset", [d["rms_log10_error"] for d in doc.get("datasets", [])])
    # ±5 % points leave at least ~0.01 decades that no smooth fit removes: far outside sd = 1 % (0.0043)
    assert rms[0] > doc["noise_rms_log10_per_dataset"][0]
    assert doc["converged"] is False and doc["tolerance_met"] is False and code == 1
    assert doc["status"] in ("optimum, tolerance not met", "stopped by budget")
    assert doc["information_criteria"]["status_means"] in (out / "report.md").read_text()

"""The command line: CSV output, bad input as one line and exit status 2, reproduce outputs."""
from __future__ import annotations

import csv
import io
import math
import subprocess
import sys

import numpy as np
import pytest

import tenscell
from tenscell.cli import main
from tenscell.cli._args import frequencies


def run(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_moduli_csv_matches_api(capsys):
    code, out, err = run(["moduli", "--prestress", "500,1000", "--freq", "0.01:1000:5"], capsys)
    assert code == 0 and err == ""
    rows = list(csv.reader(io.StringIO(out)))
    assert rows[0] == ["prestress_Pa", "frequency_Hz", "G_storage_Pa", "G_loss_Pa"]
    data = np.array(rows[1:], dtype=float)
    assert data.shape == (10, 4)
    f = np.logspace(-2, 3, 5)
    Gp, Gpp = tenscell.moduli(tenscell.linearize(tenscell.paper_cell(), 1000.0), f)
    np.testing.assert_allclose(data[5:, 1], f, rtol=1e-9)
    np.testing.assert_allclose(data[5:, 2], Gp, rtol=1e-9)
    np.testing.assert_allclose(data[5:, 3], Gpp, rtol=1e-9)


def test_moduli_options(capsys):
    code, out, _ = run(["moduli", "--freq", "1,10", "--alpha-deg", "2", "--delta-deg", "49", "--EA", "2",
                        "--c", "0.5", "--L", "1.5"], capsys)
    assert code == 0
    data = np.array([r.split(",") for r in out.strip().splitlines()[1:]], dtype=float)
    cell = tenscell.paper_cell(alpha=math.radians(2), delta=math.radians(49), L=1.5)
    Gp, _ = tenscell.moduli(tenscell.linearize(cell, 1000.0, EA=2.0, c=0.5), [1.0, 10.0])
    np.testing.assert_allclose(data[:, 2], Gp, rtol=1e-9)
    code, out, _ = run(["moduli", "--no-if", "--freq", "1"], capsys)
    assert code == 0 and len(out.strip().splitlines()) == 2


@pytest.mark.parametrize("argv, word", [
    (["moduli", "--prestress", "-5"], "--prestress"),
    (["moduli", "--prestress", "abc"], "--prestress"),
    (["moduli", "--freq", "0:1:3"], "--freq"),
    (["moduli", "--freq", "nan"], "--freq"),
    (["moduli", "--freq", "1:10"], "--freq"),
    (["moduli", "--EA", "0"], "--EA"),
    (["moduli", "--c", "-1"], "--c"),
    (["moduli", "--L", "0"], "--L"),
    (["moduli", "--L", "nan"], "--L"),
    (["moduli", "--delta-deg", "40"], "positive definite"),
    (["moduli", "--delta-deg", "54.7356103172"], "not prestressable"),
    (["moduli", "--EA", "1,2,3"], "--EA"),
])
def test_bad_input_is_one_line_exit_2(argv, word, capsys):
    try:
        code = main(argv)
    except SystemExit as stop:  # refused by the parser
        code = stop.code
    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1 and word in err and "Traceback" not in err


def test_console_script_exit_status_no_traceback():
    r = subprocess.run([sys.executable, "-m", "tenscell", "moduli", "--L", "-1"], capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr and "--L" in r.stderr


def test_parse_frequencies():
    np.testing.assert_allclose(frequencies()("0.01:1000:6"), np.logspace(-2, 3, 6), rtol=1e-14)
    np.testing.assert_allclose(frequencies()("1, 2,5"), [1, 2, 5])


def test_reproduce_homogeneous_outputs(tmp_path):
    from tenscell.cli.reproduce import reproduce_homogeneous

    reproduce_homogeneous(tmp_path, lambda msg: None)
    for name in ("fig2_prestress.png", "fig3_frequency.png", "fig2_prestress.csv", "fig3_frequency.csv", "claims.md"):
        assert (tmp_path / name).stat().st_size > 0
    with open(tmp_path / "fig3_frequency.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["prestress_Pa", "frequency_Hz", "G_storage_Pa", "G_loss_Pa"]
    claims = (tmp_path / "claims.md").read_text()
    for k in range(1, 5):
        assert f"Claim {k}" in claims
    assert not list(tmp_path.glob(".*"))  # no temporary files left behind


def test_failed_write_leaves_no_file(tmp_path, monkeypatch):
    from tenscell.io import outputs as _io

    target = tmp_path / "x.csv"

    def rows():
        yield (1.0, 2.0)
        raise RuntimeError("boom")

    with pytest.raises(RuntimeError):
        _io.write_csv_rows(target, ["a", "b"], rows())
    assert not target.exists() and list(tmp_path.iterdir()) == []


def test_the_reproduce_command_announces_its_estimate_and_runs_every_stage(tmp_path, monkeypatch, capsys):
    """`tenscell reproduce` itself, its stages replaced by recorders: the estimate line comes first, then each
    stage in order, and the output set is written (the command once died with exit 70 at its estimate, importing a
    helper that had moved; the stage tests call the stages directly and never met it)."""
    from tenscell.cli import reproduce

    ran = []

    def recorder(title):
        def run_stage(out, log):
            ran.append(title)
            (out / f"stage{len(ran)}.txt").write_text(title)
            log(f"stage{len(ran)}.txt")
        return run_stage

    monkeypatch.setattr(reproduce, "REPRODUCE_STAGES", [(t, recorder(t)) for t, _ in reproduce.REPRODUCE_STAGES])
    monkeypatch.setenv("TENSCELL_PROGRESS", "1")
    assert main(["reproduce", "--out", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    assert err.index("estimated") < err.index("[1/") and ran == [t for t, _ in reproduce.REPRODUCE_STAGES]
    assert len(list((tmp_path / "out").glob("stage*.txt"))) == len(ran)


def test_reproduce_fit_stage_runs_and_writes_every_file(tmp_path, monkeypatch):
    """`make reproduce`'s fitting stage end to end with a tiny search (one start, no hops): every figure's files and
    the mechanisms table are written (the stage once called `run_fit` with the arguments of an older signature and
    ended in exit 70 before any fit; only the full command met it)."""
    from tenscell.cli import reproduce

    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    monkeypatch.setattr(reproduce, "FIT_SEARCH", {"starts": 1, "seed": 0, "jobs": 1, "tolerance": 1.0,
                                                  "baseline_starts": 1, "hops": 0})
    from tenscell.studies import leading

    monkeypatch.setattr(leading, "SEARCH", {"starts": 1, "seed": 0, "hops": 0})
    said = []
    reproduce.reproduce_fit(tmp_path, said.append)
    for stem in ("fig4_prestress_fit", "fig5_frequency_fit", "fig5_frequency_fit_active_prestress",
                 "fig5_frequency_fit_active_prestress_uniform_damping", "joint_fit"):
        assert (tmp_path / f"{stem}.json").is_file() and (tmp_path / f"{stem}.png").is_file(), stem
        assert "<!DOCTYPE html>" in (tmp_path / f"{stem}.html").read_text(encoding="utf-8"), stem
    table = (tmp_path / "mechanisms_vs_per_tendon.md").read_text()
    assert all(f"| {m} |" in table for m in leading.MECHANISMS)

"""Data files checked like flags, and no computed result lost to its writer.

Through the command line (``tenscell.cli.main`` in this process): a value outside the range tenscell
accepts is refused with exit 2 and one line naming file, line and column, before any computation and
without touching a previous output set; a fit that converges on its first start (the model's own output)
is written completely, its unused starts as null with their meaning; an internal error exits with its
own status (70) and one line naming a log. Hypothesis writes data files with extreme values: each run
ends in exit 2 naming the file and line, or in a complete fit; never a traceback, never exit 1 for
data outside the ranges.
"""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tenscell.cli.moduli
from tenscell import fitting
from tenscell._ranges import RANGES
from tenscell.cli import EXIT_INTERNAL, main
from tenscell.cli import _args
from tenscell.io.creep_data import CreepData, read_measurements
from tenscell.io.data import DataError, RheologyData, read_csv
from tenscell.io.outputs import MANIFEST, OutputSet, json_text, write_json
from tenscell.fitting import VoigtModel

#: a fit that stays short: one stiffness, a few starts; enough to reach the end of the command
FAST = ["--tendons", "uniform", "--starts", "1", "--baseline-starts", "1"]


def _strict_json(path):
    """The file as JSON, refusing NaN and Infinity (which the JSON standard does not have)."""
    def refuse(name):
        raise AssertionError(f"{path}: {name} in a JSON file")
    return json.loads(path.read_text(), parse_constant=refuse)


def _one_line(err: str) -> str:
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err.strip()


@pytest.fixture
def quiet(monkeypatch):
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")  # stderr then holds only what the command says at its end


# ---- the README's own lines: a fit that converges on its first start ----------------------------------------
@pytest.mark.parametrize("moduli_args", [["--EA", "actin=2,intermediate_filament=0.5"], ["--freq", "0.01:100:20"]],
                         ids=["readme-EA", "readme-freq"])
def test_fitting_the_models_own_output_is_written(tmp_path, capsys, quiet, moduli_args):
    """``tenscell moduli ... > m.csv && tenscell fit m.csv --out f``: exit 0 and the complete set."""
    assert main(["moduli", *moduli_args]) == 0
    data = tmp_path / "m.csv"
    data.write_text(capsys.readouterr().out)
    out = tmp_path / "f"
    code = main(["fit", str(data), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 0, err
    assert {"fit.json", "fit.csv", "fit.png", "report.md", MANIFEST} <= {p.name for p in out.iterdir()}
    doc = _strict_json(out / "fit.json")
    assert doc["converged"] is True
    # the model's own output is met at once: some starts never ran, and say so as null, not inf
    assert len(doc["start_rms"]) == 4 and None in doc["start_rms"]
    assert "start_rms" in doc["null_means"] and "never ran" in doc["null_means"]


def test_a_fit_converging_on_its_first_start_keeps_every_value(tmp_path):
    """The library's result: unused starts are inf in Python, null in JSON; every finite value is kept."""
    d = read_csv(_model_csv(tmp_path))
    r = fitting.fit(d, model=VoigtModel(tendons="uniform"), starts=3, seed=0, progress=False)
    assert r.converged and not all(math.isfinite(x) for x in r.start_rms)
    doc = r.to_dict()
    write_json(tmp_path / "r.json", doc)
    back = _strict_json(tmp_path / "r.json")
    assert back["start_rms"] == [x if math.isfinite(x) else None for x in r.start_rms]
    assert back["rms_log10_error"] == r.rms_log10_error and "non_finite" not in back


def _model_csv(tmp_path):
    path = tmp_path / "model.csv"
    import contextlib
    import io
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        assert main(["moduli", "--freq", "0.01:100:12"]) == 0
    path.write_text(text.getvalue())
    return path


def test_json_writer_keeps_non_finite_values_as_null_with_their_value():
    doc = {"a": [1.0, math.inf], "b": {"c/d": -math.inf, "e": float("nan")}, "n": np.float32(2.5),
           "arr": np.array([[1.0, np.nan]]), "i": np.int64(3), "t": np.bool_(True)}
    back = json.loads(json_text(doc), parse_constant=lambda name: pytest.fail(name))
    assert back["a"] == [1.0, None] and back["b"] == {"c/d": None, "e": None}
    assert back["n"] == 2.5 and back["arr"] == [[1.0, None]] and back["i"] == 3 and back["t"] is True
    assert back["non_finite"] == {"/a/1": "inf", "/b/c~1d": "-inf", "/b/e": "nan", "/arr/0/1": "nan"}
    assert "non_finite" in back["null_means"]
    assert "null_means" not in json.loads(json_text({"a": 1.0}))  # nothing replaced, nothing added


# ---- internal errors --------------------------------------------------------------------------------------
def test_internal_error_has_its_own_status_one_line_and_a_log(monkeypatch, capsys):
    def broken(args):
        from tenscell._progress import stage
        stage("computed the first half")
        raise AttributeError("'Thing' object has no attribute 'x'")

    monkeypatch.delenv("TENSCELL_PROGRESS", raising=False)
    monkeypatch.setattr(tenscell.cli.moduli, "run", broken)
    code = main(["moduli"])
    err = capsys.readouterr().err
    assert code == EXIT_INTERNAL == 70
    last = err.strip().splitlines()[-1]
    assert "internal error" in last and "AttributeError" in last and "Traceback" not in err
    log = re.search(r"details in (\S+\.log)$", last).group(1)
    text = Path(log).read_text(encoding="utf-8")
    assert "tenscell moduli" in text and "computed the first half" in text and "Traceback" in text


def test_help_states_the_exit_statuses(capsys):
    assert main(["--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "2 bad input" in text and f"{EXIT_INTERNAL} an internal error" in text


# ---- data files checked like flags ------------------------------------------------------------------------
GOOD = [(0.1, 100.0, 10.0), (0.3, 120.0, 12.0), (1.0, 150.0, 15.0), (3.0, 180.0, 18.0), (10.0, 220.0, 22.0)]


def _moduli_file(path, rows, header="frequency_Hz,G_storage_Pa,G_loss_Pa"):
    path.write_text("# measured somewhere\n" + header + "\n" + "".join(",".join(map(repr, r)) + "\n" for r in rows))
    return path


def _refused(argv, capsys, *, names):
    code = main(argv)
    line = _one_line(capsys.readouterr().err)
    assert code == 2, line
    for name in names:
        assert name in line, (name, line)
    return line


@pytest.mark.parametrize("case,row,column,line", [
    ("storage 1e300", (1.0, 1e300, 15.0), "G_storage_Pa", 5),
    ("loss 1e-300", (1.0, 150.0, 1e-300), "G_loss_Pa", 5),
    ("frequency 1e300 Hz", (1e300, 150.0, 15.0), "frequency_Hz", 5),
    ("frequency 1e-20 Hz", (1e-20, 150.0, 15.0), "frequency_Hz", 5),
])
def test_moduli_file_values_outside_the_ranges_are_refused_before_the_fit(tmp_path, capsys, quiet, monkeypatch, case,
                                                                        row, column, line):
    def no_fit(*a, **k):
        raise AssertionError("the fit ran")  # an internal error (exit 70), not the refusal the test expects

    monkeypatch.setattr(fitting, "fit", no_fit)
    monkeypatch.setattr(fitting, "make_problem", no_fit)
    rows = GOOD[:2] + [row] + GOOD[2:]
    data = _moduli_file(tmp_path / "cells.csv", rows)
    out = tmp_path / "fit"
    with OutputSet(out, command="tenscell fit earlier.csv") as d:  # a previous good set
        (d / "fit.json").write_text("{}")
    before = sorted(p.name for p in out.iterdir())
    msg = _refused(["fit", str(data), "--out", str(out), *FAST], capsys,
                   names=[f"cells.csv, line {line}", f"column {column!r}", "outside"])
    assert "Hz" in msg if column == "frequency_Hz" else "Pa" in msg
    assert sorted(p.name for p in out.iterdir()) == before  # the previous set stays


@pytest.mark.parametrize("header,row,column", [
    ("prestress_Pa,frequency_Hz,G_storage_Pa,G_loss_Pa", (1e300, 1.0, 150.0, 15.0), "prestress_Pa"),
    ("frequency_Hz,G_storage_Pa,G_loss_Pa,G_storage_sd_Pa,G_loss_sd_Pa", (1.0, 150.0, 15.0, 1e31, 1.0),
     "G_storage_sd_Pa"),
    ("frequency_Hz,G_abs_Pa,phase_deg", (1.0, 1e300, 10.0), "G_abs_Pa"),
])
def test_every_column_has_its_range(tmp_path, header, row, column):
    good = [(500.0, *r) for r in GOOD] if header.startswith("prestress") else \
        [(*r, 1.0, 1.0) for r in GOOD] if "sd" in header else [(f, 150.0, 10.0) for f, *_ in GOOD]
    path = _moduli_file(tmp_path / "x.csv", good + [row], header)
    with pytest.raises(DataError, match=rf"x\.csv, line 8: column {column!r}: .* is outside"):
        read_csv(path)


@pytest.mark.parametrize("column,value", [("time_s", 1e300), ("creep_compliance_per_Pa", 1e300),
                                          ("creep_compliance_per_Pa", 1e-300), ("prestress_Pa", 1e31)])
def test_creep_file_values_outside_the_ranges_are_refused_before_the_fit(tmp_path, capsys, quiet, monkeypatch, column,
                                                                        value):
    cols = ["time_s", "creep_compliance_per_Pa", "prestress_Pa"]
    rows = [[0.01 * 10 ** k, 1e-3 * (1 + k), 800.0] for k in range(5)]
    rows[3][cols.index(column)] = value
    path = tmp_path / "creep.csv"
    path.write_text(",".join(cols) + "\n" + "".join(",".join(map(repr, r)) + "\n" for r in rows))
    monkeypatch.setattr(fitting, "fit", lambda *a, **k: pytest.fail("the fit ran"))
    _refused(["fit", str(path), "--out", str(tmp_path / "o"), *FAST], capsys,
             names=["creep.csv, line 5", f"column {column!r}", "outside"])
    assert not (tmp_path / "o").exists()


def test_holdout_on_a_creep_file_is_refused_in_one_line(tmp_path, capsys, quiet):
    path = tmp_path / "creep.csv"
    path.write_text("time_s,creep_compliance_per_Pa\n" + "".join(f"{t},{1e-3 * (1 + t) ** 0.2}\n"
                                                                for t in (0.01, 0.1, 1, 10, 100)))
    _refused(["fit", str(path), "--holdout", "1:10", "--out", str(tmp_path / "o"), *FAST], capsys,
             names=["--holdout", "creep.csv", "creep compliance"])


def test_a_stated_prestress_has_the_range_of_a_prestress_column(tmp_path):
    d = read_csv(_moduli_file(tmp_path / "sweep.csv", GOOD))
    with pytest.raises(DataError, match=r"sweep\.csv: stated prestress: 1e\+300 Pa is outside \[1e-30, 1e\+30\] Pa"):
        d.with_prestress(1e300)
    assert d.with_prestress(RANGES["prestress"][1]).prestress[0] == 1e30


def test_files_and_flags_share_one_table(tmp_path):
    """The same value is accepted, or refused, as a flag and as a data file's value: the ranges are one table."""
    assert _args.RANGES is RANGES
    lo, hi, _ = RANGES["frequency"]
    for f, ok in ((lo, True), (hi, True), (hi * 1.01, False), (lo / 1.01, False)):
        try:
            _args.frequencies()(repr(f))
            flag_ok = True
        except Exception:
            flag_ok = False
        path = _moduli_file(tmp_path / "f.csv", [(f, 100.0, 10.0)])
        try:
            read_csv(path, accept="one-frequency")  # one row: the range is the question here
            file_ok = True
        except DataError:
            file_ok = False
        assert flag_ok == file_ok == ok, f


def test_arrays_built_in_python_are_checked_too():
    """Every reader (and importer) builds RheologyData or CreepData: the check is at construction."""
    with pytest.raises(DataError, match=r"row 3: column 'frequency_Hz': 1e\+20 Hz is outside"):
        RheologyData([1.0, 2.0, 1e20], [1.0, 2.0, 3.0], [1.0, 2.0, 3.0], source="sheet",
                     locations=("row 1", "row 2", "row 3"))
    with pytest.raises(DataError, match=r"point 1: column 'creep_compliance_per_Pa'"):
        CreepData(time_s=[1.0, 2.0], compliance=[1.0, 1e40])
    d = RheologyData([3.0, 1.0], [1.0, 2.0], [1.0, 2.0], locations=("line 2", "line 3"))
    assert d.locations == ("line 3", "line 2")  # reordered with the points


# ---- hypothesis: data files with extreme values -----------------------------------------------------------
extreme = st.one_of(
    st.sampled_from([0.0, -1.0, 1e-320, 1e-300, 1e-31, 1e-30, 1e-13, 1e-12, 1e12, 1e13, 1e30, 1e31, 1e300,
                     1.7976931348623157e308, math.inf, -math.inf, math.nan]),
    st.floats(min_value=1e-300, max_value=1e300),
)
ordinary = st.floats(min_value=0.01, max_value=1e4)
_FILES = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@st.composite
def moduli_rows(draw):
    """Six rows of plausible values, with extreme values drawn into some of the cells."""
    rows = [[0.05 * 3 ** k, 100.0 * (1 + k) ** 0.3, 10.0 * (1 + k) ** 0.3] for k in range(6)]
    for _ in range(draw(st.integers(0, 3))):
        rows[draw(st.integers(0, 5))][draw(st.integers(0, 2))] = draw(extreme)
    return rows


def _implausible(rows) -> bool:
    """A modulus more decades from another of its column than a passive material allows plus 3 (checks.py)."""
    f = np.log10([r[0] for r in rows])
    for j, slope in ((1, 2.0), (2, 1.0)):
        g = np.log10([r[j] for r in rows])
        if np.max(np.abs(g[:, None] - g[None, :]) - slope * np.abs(f[:, None] - f[None, :])) > 3.0:
            return True
    return False


def _in_ranges(rows) -> bool:
    quantities = ("frequency", "modulus", "modulus")
    return all(RANGES[q][0] <= v <= RANGES[q][1] for r in rows for q, v in zip(quantities, r))


@_FILES
@given(rows=moduli_rows())
def test_extreme_values_are_read_or_refused_naming_file_line_and_column(tmp_path, rows):
    path = _moduli_file(tmp_path / "extreme.csv", rows)
    try:
        d = read_measurements(path)
    except DataError as err:
        text = str(err)
        assert "\n" not in text and re.match(r".*extreme\.csv, line [3-8]: column '?[A-Za-z_]+'?:", text), text
        # out of its range, not positive, or in range but decades from its neighbours (tenscell.io.checks)
        assert not _in_ranges(rows) or any(v <= 0 for r in rows for v in r) or "accept='outliers'" in text
        if "accept='outliers'" in text:
            assert _implausible(rows), text
    else:
        assert _in_ranges(rows)
        assert d.n == 6 and d.locations is not None


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=moduli_rows())
def test_extreme_data_files_through_the_fit_command(tmp_path_factory, rows):
    """exit 2 with one line naming file and line, or a complete fit (0 or 1): never a traceback, never 1 for data
    outside the ranges."""
    import contextlib
    import io
    import os

    tmp = tmp_path_factory.mktemp("extreme")
    path = _moduli_file(tmp / "extreme.csv", rows)
    out = tmp / "fit"
    err = io.StringIO()
    old = os.environ.get("TENSCELL_PROGRESS")
    os.environ["TENSCELL_PROGRESS"] = "0"
    try:
        with contextlib.redirect_stderr(err):
            code = main(["fit", str(path), "--out", str(out), *FAST, "--max-points", "6"])
    finally:
        if old is None:
            del os.environ["TENSCELL_PROGRESS"]
        else:
            os.environ["TENSCELL_PROGRESS"] = old
    text = err.getvalue()
    assert "Traceback" not in text and code in (0, 1, 2), (code, text)
    if code == 2:
        assert re.match(r"tenscell fit: error: .*extreme\.csv, line [3-8]: ", _one_line(text)), text
        assert not out.exists()
        assert not _in_ranges(rows) or any(v <= 0 for r in rows for v in r) or "--accept outliers" in text
    else:
        assert _in_ranges(rows), (code, text)
        assert {"fit.json", "fit.csv", "fit.png", "report.md", MANIFEST} <= {p.name for p in out.iterdir()}
        _strict_json(out / "fit.json")

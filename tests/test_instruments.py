"""Rheometer exports and lab tables read as they are: TRIOS (LIMS and plain), RheoCompass, creep tables.

The fixtures in tests/data are written by make_instrument_fixtures.py on the layouts of real exports (studied from
the anonymised TRIOS LIMS export in rheojax's examples/data and RheoCompass exports), with our own numbers. The
checks are consistency between columns the instrument computes independently (|G*| and tan δ against G', G'';
the Hz column against the rad/s one; J against strain/stress), so a wrong unit or a wrong column fails them.
"""
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tenscell.cli import main
from tenscell.io.creep_data import CreepData
from tenscell.io.data import DataError
from tenscell.io.importers import ColumnMap, from_dataframe, guess_columns
from tenscell.io.instruments import read_data, read_rheocompass, read_trios

DATA = Path(__file__).parent / "data"
LIMS = DATA / "trios_lims_temperature_steps.txt"
TEXT = DATA / "trios_text_steps.txt"
CREEP = DATA / "trios_text_creep.txt"
SHORT = DATA / "rheocompass_short_headers.txt"
TSV = DATA / "creep_compliance.tsv"
# the fixtures write 15 significant digits (TRIOS) or 5 (RheoCompass): columns computed from one another agree to this
RTOL_TRIOS, RTOL_RC = 1e-12, 2e-4


def test_trios_lims_steps_by_number_name_and_temperature():
    with pytest.raises(DataError, match=r"trios_lims_temperature_steps.txt: 3 steps .* choose one with step="):
        read_trios(LIMS)
    by_t = read_data(LIMS, temperature=25)
    by_n = read_trios(LIMS, 2)
    by_name = read_trios(LIMS, "Frequency sweep (25.0 °C)")
    for d in (by_n, by_name):
        np.testing.assert_array_equal(d.G_storage, by_t.G_storage)
    assert "step 2: Frequency sweep (25.0 °C)" in by_t.comments
    assert "'Storage modulus' [MPa]" in by_t.comments[-1]
    # MPa -> Pa: the cells' moduli are 1e2..1e3 Pa, written as 1e-4..1e-3 MPa
    assert 50 < by_t.G_storage.min() < by_t.G_storage.max() < 2e3
    # independent columns of the same step: |G*| with tan δ, and the frequency in Hz
    polar = read_trios(LIMS, 2, columns={"frequency": "Frequency", "magnitude": "Complex modulus",
                                         "loss_tangent": "Tan(delta)"})
    np.testing.assert_allclose(polar.frequency_hz, by_t.frequency_hz, rtol=RTOL_TRIOS)
    np.testing.assert_allclose(polar.G_storage, by_t.G_storage, rtol=RTOL_TRIOS)
    np.testing.assert_allclose(polar.G_loss, by_t.G_loss, rtol=RTOL_TRIOS)
    # each step is its own data: the colder step is stiffer
    assert read_trios(LIMS, temperature=15).G_storage.mean() > by_t.G_storage.mean() > read_trios(
        LIMS, temperature=37).G_storage.mean()
    with pytest.raises(DataError, match=r"0 steps at 30 ± 1 °C"):
        read_trios(LIMS, temperature=30)
    with pytest.raises(DataError, match=r"no step 4; the file has 3"):
        read_trios(LIMS, 4)


def test_trios_text_export_skips_the_amplitude_sweep():
    d = read_data(TEXT)  # step 1 is an amplitude sweep at one frequency: not a frequency sweep
    assert "step 2: Frequency sweep - 2" in d.comments and d.n == 9
    hz = read_trios(TEXT, columns={"frequency": "Frequency", "storage": "Storage modulus", "loss_tangent": "Tan(delta)"})
    np.testing.assert_allclose(hz.frequency_hz, d.frequency_hz, rtol=RTOL_TRIOS)
    np.testing.assert_allclose(hz.G_loss, d.G_loss, rtol=RTOL_TRIOS)
    with pytest.raises(DataError, match=r"step 1 'Amplitude sweep - 1' holds 5 points at one frequency \(1 Hz\)"):
        read_trios(TEXT, 1)  # chosen by number, the amplitude sweep is refused (docs/importing-data.md)
    amp = read_trios(TEXT, 1, accept="one-frequency")
    assert np.unique(amp.frequency_hz).size == 1


def test_trios_creep_in_minutes_and_per_megapascal():
    d = read_data(CREEP)
    assert isinstance(d, CreepData) and d.n == 12
    assert any(c.startswith("dropped 1 point(s) at t = 0") for c in d.comments)
    lines = [s.split("\t") for s in CREEP.read_text(encoding="utf-8").splitlines()]
    k = next(i for i, f in enumerate(lines) if f[0] == "Torque") + 3  # names, units, the t = 0 point
    rows = np.array([[float(f[1]), float(f[4]), float(f[5])] for f in lines[k:] if len(f) > 5])
    np.testing.assert_allclose(d.time_s, 60 * rows[:, 0], rtol=RTOL_TRIOS)  # min -> s
    np.testing.assert_allclose(d.compliance, rows[:, 2] / 100 / rows[:, 1], rtol=1e-12)  # J = strain / stress


def test_rheocompass_short_headers_without_the_leading_field():
    d = read_rheocompass(SHORT)
    assert d.n == 10 and "frequency = 'ω' [rad/s]" in d.comments[-1]
    polar = read_rheocompass(SHORT, columns={"frequency": "ω", "magnitude": "|G*|", "phase": "δ"})
    np.testing.assert_allclose(polar.G_storage, d.G_storage, rtol=RTOL_RC)
    np.testing.assert_allclose(polar.G_loss, d.G_loss, rtol=RTOL_RC)
    np.testing.assert_allclose(d.frequency_hz, np.logspace(-1, 2, 10) / (2 * np.pi), rtol=RTOL_RC)


def test_creep_tables_through_the_column_maps(tmp_path):
    d = read_data(TSV)
    assert isinstance(d, CreepData) and d.n == 15 and "[1/Pa]" in d.comments[-1]
    t, J = d.time_s, d.compliance
    csv = tmp_path / "creep.csv"
    pd.DataFrame({"time (s)": t, "J(t) (1/Pa)": J}).to_csv(csv, index=False)
    np.testing.assert_array_equal(read_data(csv).compliance, J)
    ms = tmp_path / "creep_ms.tsv"
    pd.DataFrame({"Time": 1e3 * t, "Creep Compliance": 1e3 * J}).to_csv(ms, sep="\t", index=False)  # 1/Pa = 1e3/kPa
    with pytest.raises(DataError, match=r"no unit is stated for time \('Time'\) and creep compliance \('Creep "
                                        r"Compliance'\), .*; give time_unit= .* and compliance_unit="):
        read_data(ms)
    back = read_data(ms, time_unit="ms", compliance_unit="1/kPa")
    np.testing.assert_allclose(back.time_s, t, rtol=1e-15)
    np.testing.assert_allclose(back.compliance, J, rtol=1e-15)
    df = from_dataframe(pd.DataFrame({"t_min": t / 60, "J_per_MPa": 1e6 * J}),
                        ColumnMap(time="t_min", compliance="J_per_MPa", time_unit="min", compliance_unit="1/MPa"))
    np.testing.assert_allclose(df.compliance, J, rtol=1e-14)
    own = from_dataframe(d.to_dataframe())  # tenscell's own names need no map
    np.testing.assert_array_equal(own.compliance, J)
    with pytest.raises(ValueError, match="a creep map gives time and compliance"):
        ColumnMap(frequency="f", time="t", compliance="J")


def test_lab_table_with_instrument_headers(tmp_path):
    f = np.logspace(-1, 1, 7)
    table = pd.DataFrame({"Angular Frequency": 2 * np.pi * f, "Storage Modulus (kPa)": 0.1 * f ** 0.2,
                          "Loss Modulus (kPa)": 0.03 * f ** 0.2})
    p = tmp_path / "lab_sweep.csv"
    table.to_csv(p, index=False)
    d = read_data(p)  # an angular frequency is in rad/s by definition; the moduli state kPa
    np.testing.assert_allclose(d.frequency_hz, f, rtol=1e-14)
    np.testing.assert_allclose(d.G_storage, 100 * f ** 0.2, rtol=1e-14)
    bare = tmp_path / "bare.csv"
    table.rename(columns=lambda c: c.replace(" (kPa)", "")).to_csv(bare, index=False)
    with pytest.raises(DataError, match=r"no unit is stated for G' \('Storage Modulus'\) and G'' \('Loss Modulus'\)"
                                        r", .*; give modulus_unit="):
        read_data(bare)
    np.testing.assert_allclose(read_data(bare, modulus_unit="kPa").G_loss, d.G_loss, rtol=1e-15)


def test_millipascal_is_not_megapascal(tmp_path):
    p = tmp_path / "mpa.csv"
    p.write_text("Frequency (Hz),G' (mPa),G'' (mPa)\n1,5,2\n2,6,3\n", encoding="utf-8")
    with pytest.raises(DataError, match=r"unit 'mPa' of G' is not one tenscell converts"):
        read_data(p)


def test_unknown_layouts_fail_with_one_line_naming_the_file(tmp_path):
    p = tmp_path / "notes.csv"
    p.write_text("sample,comment\nA,ok\n", encoding="utf-8")
    with pytest.raises(DataError) as err:
        read_data(p)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(str(p)) and "TA TRIOS" in msg and "RheoCompass" in msg
    assert guess_columns(["sample", "comment"]) is None


def test_excel_trios_sheet_found_by_its_headers(tmp_path):
    openpyxl = pytest.importorskip("openpyxl")
    ref = read_trios(TEXT, 2)
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = "Frequency sweep - 2"
    ws.append(["Frequency sweep - 2"])
    ws.append(["Angular frequency", "Storage modulus", "Loss modulus"])
    ws.append(["rad/s", "kPa", "kPa"])
    for f, a, b in zip(ref.frequency_hz, ref.G_storage, ref.G_loss):
        ws.append([2 * np.pi * f, a / 1e3, b / 1e3])
    p = tmp_path / "trios.xlsx"
    wb.save(p)
    d = read_data(p)
    np.testing.assert_allclose(d.G_storage, ref.G_storage, rtol=1e-14)
    np.testing.assert_allclose(d.frequency_hz, ref.frequency_hz, rtol=1e-14)


# ---- the command line reads the same files -----------------------------------------------------------
def _fit(args, tmp_path, capsys):
    status = main(["fit", *args, "--starts", "1", "--baseline-starts", "1", "--tendons", "uniform", "--out",
                   str(tmp_path / "out")])
    return status, capsys.readouterr().err


@pytest.mark.parametrize("args", [[str(LIMS), "--temperature", "25"], [str(SHORT)], [str(TSV)]])
def test_cli_fits_instrument_files(args, tmp_path, capsys):
    status, err = _fit(args, tmp_path, capsys)
    assert status in (0, 1), err  # converged or not: the fit ran and wrote its outputs
    fit = json.loads((tmp_path / "out" / "fit.json").read_text())
    assert fit["datasets"][0]["data"].endswith(Path(args[0]).name)


def test_cli_column_flags_and_their_errors(tmp_path, capsys):
    f = np.logspace(-1, 1, 7)
    p = tmp_path / "odd.tsv"
    pd.DataFrame({"w": 2 * np.pi * f, "a": 100 * f ** 0.2, "b": 30 * f ** 0.2}).to_csv(p, sep="\t", index=False)
    status, err = _fit([str(p), "--columns", "frequency=w", "--columns", "storage=a", "--columns", "loss=b",
                        "--units", "frequency=rad/s", "--units", "modulus=Pa"], tmp_path, capsys)
    assert status in (0, 1), err
    mapping = tmp_path / "map.json"
    mapping.write_text(json.dumps({"frequency": "w", "storage": "a", "loss": "b", "frequency_unit": "rad/s"}))
    status, err = _fit([str(p), "--columns-file", str(mapping), "--units", "modulus=kPa"], tmp_path, capsys)
    assert status in (0, 1), err
    status, err = _fit([str(p), "--columns-file", str(mapping)], tmp_path, capsys)
    assert status == 2 and "no unit is stated for G'" in err and len(err.strip().splitlines()) == 1
    assert "give --units modulus=UNIT" in err and "modulus_unit" not in err  # the flag, not the Python keyword
    status, err = _fit([str(p), "--units", "modulus=psi", "--columns-file", str(mapping)], tmp_path, capsys)
    assert status == 2 and "--units modulus=psi is not one of Pa, kPa, MPa, ratio" in err
    status, err = _fit([str(p), "--columns", "G=a"], tmp_path, capsys)
    assert status == 2 and "--columns" in err and "'G' is not one of" in err
    status, err = _fit([str(LIMS), "--step", "1", "--temperature", "25"], tmp_path, capsys)
    assert status == 2 and "--step and --temperature" in err


def test_fit_population_reads_lab_files_with_a_column_map(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    cells = tmp_path / "cells"
    cells.mkdir()
    f = np.logspace(-1, 1, 6)
    for k, scale in enumerate((1.0, 1.5, 2.0)):
        pd.DataFrame({"w": 2 * np.pi * f, "a": 0.1 * scale * f ** 0.2, "b": 0.03 * scale * f ** 0.2}).to_csv(
            cells / f"cell{k}.csv", index=False)
    (cells / "cell3.csv").write_text("w,a,b\n1,0.1,x\n2,0.1,0.03\n", encoding="utf-8")
    out = tmp_path / "fits"
    status = main(["fit-population", str(cells), "--out", str(out), "--workers", "0", "--starts", "1", "--hops", "0",
                   "--columns", "frequency=w", "--columns", "storage=a", "--columns", "loss=b",
                   "--units", "frequency=rad/s", "--units", "modulus=kPa"])
    assert status == 0, capsys.readouterr().err
    table = pd.read_csv(out / "population.csv")
    ok = table[table["status"] == "ok"]
    assert len(table) == 4 and len(ok) == 3
    bad = table[table["status"] != "ok"].iloc[0]
    assert "not a number: 'x'" in str(bad.get("error", bad.to_dict()))

"""A value out of its physical range (tenscell._ranges) is refused in the user's own words: the file, the line
(row, index label), the header the file has and the unit it is typed in.

Each case plants one out-of-range number in a real-layout fixture (tests/data) and finds the line it sits on by
searching the text, independently of the reader. The bounds in the user's unit are the table's SI bounds
divided by the unit's factor (1e6 for MPa, 60 for min, 1/2π for rad/s...); %g prints 6 digits, so they are
compared as the reader formats them.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tenscell.cli import main
from tenscell.io.data import DataError
from tenscell.io.importers import from_dataframe, read_table
from tenscell.io.instruments import read_data, read_rheocompass, read_trios

DATA = Path(__file__).parent / "data"


def _plant(tmp_path, fixture: str, old: str, new: str) -> tuple[Path, int]:
    """A copy of a fixture with the one occurrence of ``old`` replaced by ``new``, and that line (from 1)."""
    text = (DATA / fixture).read_text(encoding="utf-8")
    assert text.count(old) == 1, old
    line = text[:text.index(old)].count("\n") + 1
    path = tmp_path / fixture
    path.write_text(text.replace(old, new), encoding="utf-8")
    return path, line


def _bounds(lo_si: float, hi_si: float, factor: float, unit: str) -> str:
    return f"[{lo_si / factor:g}, {hi_si / factor:g}] {unit}"


def test_trios_lims_names_its_header_and_megapascal(tmp_path):
    # 2e25 MPa = 2e31 Pa: beyond 1e30 Pa, although the number as typed is not
    path, line = _plant(tmp_path, "trios_lims_temperature_steps.txt", "6.883483062291414E-05", "2E+25")
    with pytest.raises(DataError) as info:
        read_trios(path, temperature=37)
    msg = str(info.value)
    assert msg == (f"{path}, line {line}: column 'Storage modulus': 2e+25 MPa is outside "
                   f"{_bounds(1e-30, 1e30, 1e6, 'MPa')}, the range tenscell accepts for a modulus"), msg
    assert "G_storage_Pa" not in msg


def test_trios_creep_in_minutes_and_per_megapascal(tmp_path):
    # the time column in minutes: 1e11 min = 6e12 s, beyond the 1e12 s bound
    path, line = _plant(tmp_path, "trios_text_creep.txt", "15.0\t0.7305271542664457\t37.0",
                        "15.0\t1e11\t37.0")
    with pytest.raises(DataError, match=rf"^{path}, line {line}: column 'Step time': 1e\+11 min is outside "
                                        rf"\[1\.66667e-14, 1\.66667e\+10\] min, the range tenscell accepts for a time$"):
        read_data(path)
    # J in 1/MPa: 1e37 1/MPa = 1e31 1/Pa
    path, line = _plant(tmp_path, "trios_text_creep.txt", "\t4848.603919989065\t", "\t1e37\t")
    with pytest.raises(DataError, match=rf"^{path}, line {line}: column 'Compliance': 1e\+37 1/MPa is outside "
                                        r"\[1e-24, 1e\+36\] 1/MPa"):
        read_data(path)


def test_rheocompass_short_and_long_headers(tmp_path):
    path, line = _plant(tmp_path, "rheocompass_short_headers.txt", "67.227", "6.7e31")
    with pytest.raises(DataError, match=rf"^{path}, line {line}: column \"G'\": 6\.7e\+31 Pa is outside "
                                        r"\[1e-30, 1e\+30\] Pa"):
        read_rheocompass(path)
    # the long headers, a decimal comma, the frequency in rad/s: 7e12 rad/s = 1.1e12 Hz
    path, line = _plant(tmp_path, "rheocompass_frequency_sweep.txt", "6,280E+2", "7,000E+12")
    with pytest.raises(DataError) as info:
        read_rheocompass(path, interval=2)
    lo, hi = 1e-12 * 2 * math.pi, 1e12 * 2 * math.pi
    assert str(info.value).startswith(f"{path}, line {line}: column 'Angular Frequency': 7e+12 rad/s is outside "
                                      f"[{lo:g}, {hi:g}] rad/s, the range tenscell accepts for a frequency"), info.value


def _lab_csv(tmp_path, rows) -> Path:
    path = tmp_path / "lab.csv"
    path.write_text("# cells, 37 °C\nomega,Gp,tand,P\n" + "".join(",".join(map(str, r)) + "\n" for r in rows))
    return path


def test_csv_through_a_column_map_and_formed_moduli(tmp_path):
    cmap = {"frequency": "omega", "frequency_unit": "rad/s", "storage": "Gp", "loss_tangent": "tand",
            "modulus_unit": "kPa", "prestress": "P", "prestress_unit": "kPa"}
    ok = [1.0, 0.2, 0.3, 0.5]
    path = _lab_csv(tmp_path, [ok, ok[:3] + [2e28], ok])  # 2e28 kPa of prestress = 2e31 Pa
    with pytest.raises(DataError, match=rf"^{path}, line 4: column 'P': 2e\+28 kPa is outside \[1e-33, 1e\+27\] kPa"):
        read_table(path, cmap)
    # G'' = G' tan δ, formed by tenscell: named by the columns it came from, in their unit
    path = _lab_csv(tmp_path, [ok, ok, [1.0, 0.2, 1e40, 0.5]])
    with pytest.raises(DataError, match=rf"^{path}, line 5: G'' formed from columns 'Gp' and 'tand': 2e\+39 kPa "
                                        r"is outside \[1e-33, 1e\+27\] kPa"):
        read_table(path, cmap)


def test_dataframe_rows_are_named_by_their_index():
    df = pd.DataFrame({"f (Hz)": [0.1, 1.0, 10.0], "G' (Pa)": [100.0, 120.0, 1e-31], "G'' (Pa)": [30.0, 40.0, 50.0]},
                      index=["a", "b", "c"])
    with pytest.raises(DataError, match=r"^<DataFrame>, index 'c': column \"G' \(Pa\)\": 1e-31 Pa is outside"):
        from_dataframe(df)


def test_excel_rows_are_named_as_the_spreadsheet_numbers_them(tmp_path):
    openpyxl = pytest.importorskip("openpyxl")
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.append(["Angular frequency", "Storage modulus", "Loss modulus"])
    ws.append(["rad/s", "kPa", "kPa"])
    for w, a, b in ((1.0, 0.1, 0.03), (2.0, 5e27, 0.04)):
        ws.append([w, a, b])
    p = tmp_path / "trios.xlsx"
    wb.save(p)
    with pytest.raises(DataError, match=r"trios\.xlsx \[Sheet\], row 4: column 'Storage modulus': 5e\+27 kPa is "
                                        r"outside \[1e-33, 1e\+27\] kPa"):
        read_data(p)


def test_the_cli_speaks_the_files_words_and_exits_2(tmp_path, capsys):
    path, line = _plant(tmp_path, "trios_lims_temperature_steps.txt", "6.883483062291414E-05", "2E+25")
    status = main(["fit", str(path), "--temperature", "37", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1, err
    assert f"line {line}: column 'Storage modulus': 2e+25 MPa is outside" in err[0]
    assert not (tmp_path / "out").exists()


def test_values_in_range_still_read():
    """The checks refuse only what is out of range: the fixtures themselves read, in SI."""
    d = read_trios(DATA / "trios_lims_temperature_steps.txt", temperature=37)
    assert np.all((d.G_storage > 1) & (d.G_storage < 1e4))

"""Measured data from users' own tables: units converted explicitly, errors that say where."""
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tenscell.io.data import DataError, RheologyData
from tenscell.io.importers import ColumnMap, from_dataframe, read_table
from tenscell.io.instruments import read_rheocompass

DATA = Path(__file__).parent / "data"
ALPHA, G0, ETA = 0.2, 50.0, 0.05  # the law the RheoCompass-style fixture was written from (Pa at 1 rad/s, Pa·s)


def law(f_hz):
    """G', G'' (Pa) of the fixture's structural-damping law at f (Hz)."""
    w = 2 * np.pi * np.asarray(f_hz)
    Gp = G0 * w ** ALPHA * math.cos(ALPHA * math.pi / 2)
    return Gp, G0 * w ** ALPHA * math.sin(ALPHA * math.pi / 2) + ETA * w


@pytest.fixture
def reference():
    f = np.logspace(-1, 2, 9)
    Gs, Gl = law(f)
    return f, Gs, Gl


def same(a: RheologyData, f, Gs, Gl, rtol=1e-12):
    np.testing.assert_allclose(a.frequency_hz, f, rtol=rtol)
    np.testing.assert_allclose(a.G_storage, Gs, rtol=rtol)
    np.testing.assert_allclose(a.G_loss, Gl, rtol=rtol)


# ---- every unit and layout gives the same moduli ----------------------------------------------
def test_layouts_and_units_agree(reference):
    f, Gs, Gl = reference
    w = 2 * np.pi * f
    Gabs, phase = np.hypot(Gs, Gl), np.arctan2(Gl, Gs)
    df = pd.DataFrame({"omega": w, "Gp_kPa": Gs / 1e3, "Gpp": Gl, "tan_d": Gl / Gs, "G abs (MPa)": Gabs / 1e6,
                       "phi": np.degrees(phase), "phi_rad": phase})
    with pytest.raises(DataError, match="column 'Gp_kPa': the file says 'kPa' but modulus_unit='Pa' was given"):
        from_dataframe(df, ColumnMap("omega", storage="Gp_kPa", loss="Gpp", frequency_unit="rad/s", modulus_unit="Pa"))
    base = {"frequency": "omega", "frequency_unit": "rad/s"}
    same(from_dataframe(df, {**base, "storage": "Gp_kPa", "loss_tangent": "tan_d"}), f, Gs, Gl)
    same(from_dataframe(df, {**base, "magnitude": "G abs (MPa)", "phase": "phi", "phase_unit": "deg"}), f, Gs, Gl)
    same(from_dataframe(df, {**base, "magnitude": "G abs (MPa)", "phase": "phi_rad", "phase_unit": "rad"}), f, Gs, Gl)
    same(from_dataframe(df, {**base, "magnitude": "G abs (MPa)", "loss_tangent": "tan_d"}), f, Gs, Gl)
    same(RheologyData.from_dataframe(df, {**base, "loss": "Gpp", "loss_tangent": "tan_d"}, modulus_unit="Pa"),
         f, Gs, Gl)


def test_ratio_with_a_stated_geometric_factor(reference):
    f, Gs, Gl = reference
    factor = 2.7e3  # Pa per unit of the ratio (the user's, from their probe geometry)
    df = pd.DataFrame({"f": f, "re": Gs / factor, "im": Gl / factor})
    got = from_dataframe(df, ColumnMap("f", storage="re", loss="im", frequency_unit="Hz", modulus_unit="ratio",
                                       geometric_factor=factor))
    same(got, f, Gs, Gl)
    assert "2700 Pa × ratio" in got.comments[-1]
    with pytest.raises(ValueError, match="geometric_factor"):
        ColumnMap("f", storage="re", loss="im", modulus_unit="Pa", geometric_factor=factor)
    with pytest.raises(ValueError, match="geometric_factor"):
        ColumnMap("f", storage="re", loss="im", modulus_unit="ratio")


def test_package_layout_is_the_default_and_round_trips(reference):
    data = RheologyData(*reference)
    back = RheologyData.from_dataframe(data.to_dataframe())
    same(back, *reference, rtol=0)


# ---- units must be stated, by the map or by the file -----------------------------------------
def test_a_unit_nobody_states_is_an_error(reference):
    f, Gs, Gl = reference
    df = pd.DataFrame({"f": f, "Gp": Gs, "Gpp": Gl})
    with pytest.raises(DataError, match=r"<DataFrame>: no unit is stated for frequency \('f'\), .*; give "
                                        r"frequency_unit= \(one of Hz, rad/s\)"):
        from_dataframe(df, {"frequency": "f", "storage": "Gp", "loss": "Gpp", "modulus_unit": "Pa"})


def test_a_unit_that_contradicts_the_file_is_an_error(tmp_path, reference):
    f, Gs, Gl = reference
    p = tmp_path / "m.csv"
    p.write_text("f [Hz],G' [kPa],G'' [kPa]\n" + "".join(f"{a},{b / 1e3},{c / 1e3}\n" for a, b, c in zip(f, Gs, Gl)))
    with pytest.raises(DataError, match=r"m.csv: column \"G' \[kPa\]\": the file says 'kPa' but .*modulus_unit='Pa'"):
        read_table(p, {"frequency": "f", "storage": "G'", "loss": "G''", "modulus_unit": "Pa"})
    same(read_table(p, {"frequency": "f", "storage": "G'", "loss": "G''"}), f, Gs, Gl)  # units from the header


def test_bad_layouts_are_refused_at_construction():
    with pytest.raises(ValueError, match="not a layout"):
        ColumnMap("f", storage="a")
    with pytest.raises(ValueError, match="not a layout"):
        ColumnMap("f", storage="a", loss="b", phase="c")
    with pytest.raises(ValueError, match="frequency_unit"):
        ColumnMap("f", storage="a", loss="b", frequency_unit="kHz")
    with pytest.raises(ValueError, match="standard deviations"):
        ColumnMap("f", magnitude="a", phase="b", storage_sd="s")
    with pytest.raises(ValueError, match="columns=: 'storag' is not a field of a column map; the fields are"):
        from_dataframe(pd.DataFrame({"f": [1.0]}), {"frequency": "f", "storag": "x"})


# ---- errors name the file, the line and the column -------------------------------------------
def test_text_errors_name_line_and_column(tmp_path):
    p = tmp_path / "lab.tsv"
    p.write_text("# HASM cells, bead 4.5 um\nfreq\tGp\tGpp\n0.1\t100\t10\n\n1.0\t12x\t20\n")
    cmap = {"frequency": "freq", "storage": "Gp", "loss": "Gpp", "frequency_unit": "Hz", "modulus_unit": "Pa"}
    with pytest.raises(DataError, match=r"lab.tsv, line 5: column 'Gp': not a number: '12x'"):
        read_table(p, cmap)
    p.write_text("freq\tGp\tGpp\n0.1\t100\t10\n1.0\t-3\t20\n")
    with pytest.raises(DataError, match=r"lab.tsv, line 3: column 'Gp': G' -3 must be > 0"):
        read_table(p, cmap)
    with pytest.raises(DataError, match=r"lab.tsv: no column 'Gq' for G' \(storage='Gq'\); the columns are 'freq', "
                                        r"'Gp', 'Gpp'"):
        read_table(p, {**cmap, "storage": "Gq"})
    p.write_text("freq\tGp\tGpp\n0.1\t100\n")
    with pytest.raises(DataError, match=r"lab.tsv, line 2: expected 3 fields, found 2"):
        read_table(p, cmap)


def test_phase_out_of_range_names_the_row(tmp_path):
    df = pd.DataFrame({"f": [1.0, 2.0], "G": [10.0, 11.0], "ph": [30.0, 95.0]}, index=["a", "b"])
    with pytest.raises(DataError, match=r"<DataFrame>, index 'b': column 'ph': phase 95 deg must be below 90 deg"):
        from_dataframe(df, {"frequency": "f", "magnitude": "G", "phase": "ph", "frequency_unit": "Hz",
                            "modulus_unit": "Pa", "phase_unit": "deg"})


def test_decimal_comma_and_semicolons(tmp_path, reference):
    f, Gs, Gl = reference
    p = tmp_path / "de.csv"
    rows = "".join(f"{float(a)!r};{float(b)!r};{float(c)!r}\n".replace(".", ",") for a, b, c in zip(f, Gs, Gl))
    p.write_text("Frequenz (Hz);G' (Pa);G'' (Pa)\n" + rows)
    same(read_table(p, {"frequency": "Frequenz", "storage": "G'", "loss": "G''"}, decimal=","), f, Gs, Gl)


def test_excel_with_a_units_row(tmp_path, reference):
    openpyxl = pytest.importorskip("openpyxl")
    f, Gs, Gl = reference
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = "Frequency sweep"
    ws.append(["Run 7, 37 °C"])
    ws.append(["Angular frequency", "Storage modulus", "Loss modulus"])
    ws.append(["rad/s", "kPa", "kPa"])
    for a, b, c in zip(f, Gs, Gl):
        ws.append([2 * np.pi * a, b / 1e3, c / 1e3])
    ws.append([2 * np.pi * 200.0, "n/a", 0.5])
    p = tmp_path / "trios.xlsx"
    wb.save(p)
    cmap = {"frequency": "Angular frequency", "storage": "Storage modulus", "loss": "Loss modulus"}
    with pytest.raises(DataError, match=r"trios.xlsx \[Frequency sweep\], row 13: column 'Storage modulus': "
                                        r"not a number: 'n/a'"):
        read_table(p, cmap, header_line=2, units_line=True)
    wb["Frequency sweep"].delete_rows(13)
    wb.save(p)
    same(read_table(p, cmap, header_line=2, units_line=True), f, Gs, Gl)


# ---- an instrument export: Anton Paar RheoCompass text table ---------------------------------
def test_rheocompass_export():
    path = DATA / "rheocompass_frequency_sweep.txt"
    # interval 1 is an amplitude sweep at one frequency: not a frequency sweep, so the sweep is read by default
    auto = read_rheocompass(path)
    data = read_rheocompass(path, interval=2)
    np.testing.assert_array_equal(auto.frequency_hz, data.frequency_hz)
    assert data.n == 16 and data.kind == "frequency"
    # rad/s -> Hz: the sweep ran from 628 to 0.628 rad/s, i.e. 100 Hz down to 0.1 Hz
    assert data.frequency_hz.max() == pytest.approx(628.0 / (2 * np.pi), rel=1e-3)
    Gs, Gl = law(data.frequency_hz)
    np.testing.assert_allclose(data.G_storage, Gs, rtol=1e-3)  # the export keeps 4 significant digits
    np.testing.assert_allclose(data.G_loss, Gl, rtol=1e-3)
    assert any("Measuring System: PP25" in c for c in data.comments)
    assert "'Angular Frequency' [rad/s]" in data.comments[-1]
    # chosen by its number it is refused, saying why, unless the check is accepted
    with pytest.raises(DataError, match=r"interval 1 'interval 1' holds 6 points at one frequency \(1.592 Hz\).*"
                                        r"accept='one-frequency'"):
        read_rheocompass(path, interval=1)
    amp = read_rheocompass(path, interval=1, accept="one-frequency")
    assert amp.n == 6 and np.allclose(amp.frequency_hz, 10 / (2 * np.pi), rtol=1e-3)
    assert amp.provenance.accepted and amp.provenance.accepted[0].startswith("one-frequency:")


def test_rheocompass_errors_name_the_line(tmp_path):
    text = (DATA / "rheocompass_frequency_sweep.txt").read_text(encoding="utf-8").splitlines()
    k = next(i for i, s in enumerate(text) if s.startswith("\t3\t") and i > 20)
    fields = text[k].split("\t")
    fields[5] = "-"  # an empty cell as the instrument writes it for a missing point
    text[k] = "\t".join(fields)
    p = tmp_path / "broken.txt"
    p.write_text("\n".join(text) + "\n", encoding="utf-8")
    with pytest.raises(DataError, match=rf"broken.txt, line {k + 1}: column 'Storage Modulus': not a number: '-'"):
        read_rheocompass(p, interval=2)
    other = tmp_path / "other.txt"
    other.write_text("Project:\tx\nPoint\tG\n")
    with pytest.raises(DataError, match="other.txt: no 'Interval data:' line; expected an Anton Paar RheoCompass"):
        read_rheocompass(other)

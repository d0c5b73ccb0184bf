"""Tests for tenscell.io.data: reading, validating and writing rheology CSV files."""

from __future__ import annotations

import math
import os
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tenscell._ranges import RANGES
from tenscell.io.checks import CHECKS
import tenscell.io.data as data_module
from tenscell.io.data import (
    DataError,
    RheologyData,
    bundled,
    bundled_names,
    read_csv,
    write_csv,
)

LN10 = math.log(10.0)
#: tests of how one row is parsed read it although one frequency is no frequency sweep (tenscell.io.checks)
ONE_ROW = "one-frequency"


def write(tmp_path: Path, text: str, name: str = "sample.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def read_error(path: Path, **kwargs) -> str:
    with pytest.raises(DataError) as info:
        read_csv(path, **kwargs)
    message = str(info.value)
    assert path.name in message, message
    return message


# --- bundled data -----------------------------------------------------------


def test_bundled_names():
    assert bundled_names() == ("fabry2001", "stamenovic2002")


def test_bundled_fabry2001():
    d = bundled("fabry2001")
    assert d.kind == "frequency"
    assert d.n == 16
    assert d.prestress is None
    assert d.G_storage_sd is None and d.G_loss_sd is None
    assert d.frequency_hz[0] == 0.01 and d.frequency_hz[-1] == 1000.0
    # Rows "0.1,280.0000,91.1279" and "1000,1766.6806,2077.9920".
    i = int(np.flatnonzero(d.frequency_hz == 0.1)[0])
    assert d.G_storage[i] == 280.0 and d.G_loss[i] == 91.1279
    assert d.G_storage[-1] == 1766.6806 and d.G_loss[-1] == 2077.9920
    assert np.all(np.diff(d.frequency_hz) > 0)
    assert len(d.comments) == 4
    assert d.comments[0].startswith("Human airway smooth muscle cells")
    assert "fabry2001_hasm_powerlaw.csv" in d.source
    np.testing.assert_array_equal(d.weights_storage, np.ones(16))
    np.testing.assert_array_equal(d.weights_loss, np.ones(16))


def test_bundled_stamenovic2002():
    d = bundled("stamenovic2002")
    assert d.kind == "prestress"
    assert d.n == 8
    assert d.prestress is not None
    assert d.prestress[0] == 350.0 and d.prestress[-1] == 1900.0
    assert d.prestress.min() == 350.0 and d.prestress.max() == 1900.0
    np.testing.assert_array_equal(d.frequency_hz, np.full(8, 0.1))
    # Rows "350.0,0.1,152.00,49.50" and "1014.3,0.1,284.86,82.71".
    assert d.G_storage[0] == 152.0 and d.G_loss[0] == 49.5
    assert d.prestress[3] == 1014.3
    assert d.G_storage[3] == 284.86 and d.G_loss[3] == 82.71
    # The file was generated from G' = 0.20 P + 82 and G'' = 0.05 P + 32.
    np.testing.assert_allclose(d.G_storage, 0.20 * d.prestress + 82, atol=0.01)
    np.testing.assert_allclose(d.G_loss, 0.05 * d.prestress + 32, atol=0.01)
    assert any("Stamenovic" in c for c in d.comments)


@pytest.mark.parametrize(
    "name",
    ["fabry2001_hasm_powerlaw.csv", "FABRY2001", " stamenovic2002 ", "stamenovic2002_hasm_0p1Hz.csv"],
)
def test_bundled_accepts_file_names_and_case(name):
    assert bundled(name).n in (16, 8)


def test_bundled_unknown_name_lists_available():
    with pytest.raises(DataError) as info:
        bundled("fabry2002")
    message = str(info.value)
    assert "fabry2002" in message
    for name in bundled_names():
        assert name in message


def test_bundled_files_are_package_data():
    from importlib import resources

    folder = resources.files("tenscell") / "data"
    names = {p.name for p in folder.iterdir()}
    assert {"fabry2001_hasm_powerlaw.csv", "stamenovic2002_hasm_0p1Hz.csv"} <= names
    assert not (folder / "__init__.py").is_file()


# --- header handling --------------------------------------------------------


def test_headers_case_insensitive_with_spaces(tmp_path):
    path = write(
        tmp_path,
        "# comment one\n"
        "  FREQUENCY_HZ ,  g_storage_pa,G_LOSS_Pa  \n"
        "1, 100, 20\n"
        "\n"
        "2 ,150 , 30\n",
    )
    d = read_csv(path)
    np.testing.assert_array_equal(d.frequency_hz, [1.0, 2.0])
    np.testing.assert_array_equal(d.G_storage, [100.0, 150.0])
    np.testing.assert_array_equal(d.G_loss, [20.0, 30.0])
    assert d.comments == ("comment one",)
    assert d.kind == "frequency"
    assert d.source == str(path)


def test_reordered_columns(tmp_path):
    path = write(
        tmp_path,
        "G_loss_Pa,G_storage_Pa,frequency_Hz,prestress_Pa\n"
        "20,100,0.5,400\n"
        "30,150,0.5,800\n",
    )
    d = read_csv(path)
    assert d.kind == "prestress"
    np.testing.assert_array_equal(d.frequency_hz, [0.5, 0.5])
    np.testing.assert_array_equal(d.G_storage, [100.0, 150.0])
    np.testing.assert_array_equal(d.G_loss, [20.0, 30.0])
    np.testing.assert_array_equal(d.prestress, [400.0, 800.0])


def test_quoted_header_and_byte_order_mark(tmp_path):
    path = tmp_path / "bom.csv"
    path.write_bytes('\ufeff"frequency_Hz","G_storage_Pa","G_loss_Pa"\r\n1,2,3\r\n'.encode("utf-8"))
    d = read_csv(path, accept=ONE_ROW)
    assert d.n == 1 and d.G_loss[0] == 3.0


def test_comments_anywhere_are_kept_in_order(tmp_path):
    path = write(
        tmp_path,
        "#first\n"
        "frequency_Hz,G_storage_Pa,G_loss_Pa\n"
        "   # second, indented\n"
        "1,2,3\n"
        "#\n",
    )
    d = read_csv(path, accept=ONE_ROW)
    assert d.comments == ("first", "second, indented", "")


# --- magnitude / phase ------------------------------------------------------


def test_magnitude_phase_conversion(tmp_path):
    path = write(
        tmp_path,
        "# polar\nfrequency_Hz,G_abs_Pa,phase_deg\n1,100,30\n10,200,45\n100,50,89.5\n",
    )
    d = read_csv(path)
    G_abs = np.array([100.0, 200.0, 50.0])
    phi = np.radians([30.0, 45.0, 89.5])
    np.testing.assert_allclose(d.G_storage, G_abs * np.cos(phi), rtol=1e-14)
    np.testing.assert_allclose(d.G_loss, G_abs * np.sin(phi), rtol=1e-14)
    assert d.G_storage[0] == pytest.approx(50.0 * math.sqrt(3.0), rel=1e-14)
    assert d.G_loss[0] == pytest.approx(50.0, rel=1e-14)
    assert d.kind == "frequency"
    assert d.G_storage_sd is None and d.G_loss_sd is None


def test_magnitude_phase_sd_propagation(tmp_path):
    path = write(
        tmp_path,
        "phase_sd_deg,phase_deg,G_abs_sd_Pa,G_abs_Pa,frequency_Hz\n2,30,10,100,1\n",
    )
    d = read_csv(path, accept=ONE_ROW)
    A, sA = 100.0, 10.0
    phi, s_phi = math.radians(30.0), math.radians(2.0)
    expected_storage_sd = math.hypot(math.cos(phi) * sA, A * math.sin(phi) * s_phi)
    expected_loss_sd = math.hypot(math.sin(phi) * sA, A * math.cos(phi) * s_phi)
    assert d.G_storage_sd[0] == pytest.approx(expected_storage_sd, rel=1e-12)
    assert d.G_loss_sd[0] == pytest.approx(expected_loss_sd, rel=1e-12)


def test_magnitude_phase_sd_matches_numerical_derivative(tmp_path):
    # With no phase error, sd(G') = cos(phi) sd(|G|) exactly; with no |G|
    # error, sd(G') = |dG'/dphi| sd(phi), checked by finite differences.
    A, phi_deg = 300.0, 40.0
    h = 1e-6
    dGs_dphi = (A * math.cos(math.radians(phi_deg + h)) - A * math.cos(math.radians(phi_deg - h))) / (
        2 * math.radians(h)
    )
    path = write(tmp_path, "frequency_Hz,G_abs_Pa,phase_deg,G_abs_sd_Pa,phase_sd_deg\n1,300,40,1e-12,1\n")
    d = read_csv(path, accept=ONE_ROW)
    assert d.G_storage_sd[0] == pytest.approx(abs(dGs_dphi) * math.radians(1.0), rel=1e-6)


def test_prestress_with_magnitude_phase(tmp_path):
    path = write(tmp_path, "prestress_Pa,frequency_Hz,G_abs_Pa,phase_deg\n500,0.1,100,10\n")
    d = read_csv(path, accept=ONE_ROW)
    assert d.kind == "prestress" and d.prestress[0] == 500.0


# --- weights ----------------------------------------------------------------


def test_sd_weights(tmp_path):
    path = write(
        tmp_path,
        "frequency_Hz,G_storage_Pa,G_loss_Pa,G_storage_sd_Pa,G_loss_sd_Pa\n"
        "1,100,20,10,4\n"
        "2,200,40,50,2\n",
    )
    d = read_csv(path)
    np.testing.assert_array_equal(d.G_storage_sd, [10.0, 50.0])
    np.testing.assert_array_equal(d.G_loss_sd, [4.0, 2.0])
    # Inverse SD of log10 G: 1 / (sd / (G ln 10)).
    np.testing.assert_allclose(d.weights_storage, [100 * LN10 / 10, 200 * LN10 / 50], rtol=1e-15)
    np.testing.assert_allclose(d.weights_loss, [20 * LN10 / 4, 40 * LN10 / 2], rtol=1e-15)


def test_only_one_sd_column(tmp_path):
    path = write(tmp_path, "frequency_Hz,G_storage_Pa,G_loss_Pa,G_loss_sd_Pa\n1,100,20,2\n")
    d = read_csv(path, accept=ONE_ROW)
    assert d.G_storage_sd is None
    np.testing.assert_array_equal(d.weights_storage, [1.0])
    np.testing.assert_allclose(d.weights_loss, [20 * LN10 / 2])


def test_weights_without_sd_are_ones():
    d = RheologyData(frequency_hz=[1.0, 2.0, 3.0], G_storage=[1.0, 2.0, 3.0], G_loss=[1.0, 1.0, 1.0])
    np.testing.assert_array_equal(d.weights_storage, np.ones(3))
    np.testing.assert_array_equal(d.weights_loss, np.ones(3))


# --- RheologyData validation -----------------------------------------------


def test_dataclass_is_frozen_and_arrays_read_only():
    d = RheologyData(frequency_hz=[1.0], G_storage=[2.0], G_loss=[3.0], source="x")
    assert d.kind == "frequency" and d.n == 1
    with pytest.raises(AttributeError):
        d.source = "y"  # type: ignore[misc]
    with pytest.raises(ValueError):
        d.G_storage[0] = 5.0
    assert d.frequency_hz.dtype == np.float64


def test_dataclass_does_not_alias_input():
    f = np.array([1.0, 2.0])
    d = RheologyData(frequency_hz=f, G_storage=[1.0, 1.0], G_loss=[1.0, 1.0])
    f[0] = 99.0
    assert d.frequency_hz[0] == 1.0


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        (dict(frequency_hz=[1.0, 2.0], G_storage=[1.0], G_loss=[1.0]), "different lengths"),
        (dict(frequency_hz=[1.0], G_storage=[np.nan], G_loss=[1.0]), "not finite"),
        (dict(frequency_hz=[np.inf], G_storage=[1.0], G_loss=[1.0]), "not finite"),
        (dict(frequency_hz=[0.0], G_storage=[1.0], G_loss=[1.0]), "frequency_hz"),
        (dict(frequency_hz=[1.0], G_storage=[-1.0], G_loss=[1.0]), "G_storage"),
        (dict(frequency_hz=[1.0], G_storage=[1.0], G_loss=[0.0]), "G_loss"),
        (dict(frequency_hz=[1.0], G_storage=[1.0], G_loss=[1.0], prestress=[-5.0]), "prestress"),
        (dict(frequency_hz=[1.0], G_storage=[1.0], G_loss=[1.0], G_loss_sd=[0.0]), "G_loss_sd"),
        (dict(frequency_hz=[], G_storage=[], G_loss=[]), "no data points"),
        (dict(frequency_hz=[[1.0]], G_storage=[[1.0]], G_loss=[[1.0]]), "1-D"),
        (dict(frequency_hz=["a"], G_storage=[1.0], G_loss=[1.0]), "not numeric"),
        (dict(frequency_hz=[1.0], G_storage=[1.0], G_loss=[1.0], kind="prestress"), "kind"),
        (dict(frequency_hz=[1.0], G_storage=[1.0], G_loss=[1.0], prestress=[1.0], kind="frequency"), "kind"),
        (dict(frequency_hz=[1.0], G_storage=[1.0], G_loss=[1.0], comments=("a\nb",)), "line break"),
    ],
)
def test_dataclass_validation(kwargs, fragment):
    with pytest.raises(DataError) as info:
        RheologyData(source="my_source.csv", **kwargs)
    assert "my_source.csv" in str(info.value)
    assert fragment in str(info.value)


# --- read_csv errors: each names the file and the line -----------------------

HEADER = "frequency_Hz,G_storage_Pa,G_loss_Pa\n"
PREAMBLE = "# a comment\n\n# another\n" + HEADER  # header on line 4


@pytest.mark.parametrize(
    "body, line, fragments",
    [
        # Data rows start on line 5; each case breaks the row on `line`.
        ("1,2,3\n2,3\n", 6, ["expected 3 fields", "found 2"]),
        ("1,2,3,4\n", 5, ["expected 3 fields", "found 4"]),
        ("1,2,3\n\n# c\n2,abc,3\n", 8, ["G_storage_Pa", "'abc'"]),
        ("1,2,\n", 5, ["G_loss_Pa", "empty"]),
        ("1,2,3\n1,2,1_000\n", 6, ["G_loss_Pa", "'1_000'"]),
        ("nan,2,3\n", 5, ["frequency_Hz", "not finite"]),
        ("1,inf,3\n", 5, ["G_storage_Pa", "not finite"]),
        ("1,2,-Infinity\n", 5, ["G_loss_Pa", "not finite"]),
        ("1,2,3\n2,0,3\n", 6, ["G_storage_Pa", "zero", "storage modulus"]),
        ("1,2,3\n2,3,-4\n", 6, ["G_loss_Pa", "negative", "loss modulus"]),
        ("0,2,3\n", 5, ["frequency_Hz", "zero", "frequency"]),
        ("-1,2,3\n", 5, ["frequency_Hz", "negative"]),
        ('1,2,"3\n', 5, ["malformed CSV"]),
    ],
)
def test_read_errors_name_file_and_line(tmp_path, body, line, fragments):
    path = write(tmp_path, PREAMBLE + body, name="broken_data.csv")
    message = read_error(path)
    assert re.search(rf"\bline {line}\b", message), message
    for fragment in fragments:
        assert fragment in message, message


@pytest.mark.parametrize(
    "text, line, fragments",
    [
        ("prestress_Pa,frequency_Hz,G_storage_Pa,G_loss_Pa\n100,1,2,3\n0,1,2,3\n", 3, ["prestress_Pa", "zero"]),
        ("prestress_Pa,frequency_Hz,G_storage_Pa,G_loss_Pa\n-100,1,2,3\n", 2, ["prestress", "negative"]),
        ("frequency_Hz,G_abs_Pa,phase_deg\n1,10,30\n1,10,95\n", 3, ["phase_deg", "outside [0, 90]"]),
        ("frequency_Hz,G_abs_Pa,phase_deg\n1,10,-1\n", 2, ["phase_deg", "outside [0, 90]"]),
        ("frequency_Hz,G_abs_Pa,phase_deg\n1,10,0\n", 2, ["zero loss modulus"]),
        ("frequency_Hz,G_abs_Pa,phase_deg\n1,10,90\n", 2, ["zero storage modulus"]),
        ("frequency_Hz,G_abs_Pa,phase_deg\n1,0,45\n", 2, ["G_abs_Pa", "zero", "|G|"]),
        ("frequency_Hz,G_abs_Pa,phase_deg\n1,-2,45\n", 2, ["G_abs_Pa", "negative"]),
        ("frequency_Hz,G_storage_Pa,G_loss_Pa,G_storage_sd_Pa\n1,2,3,0\n", 2, ["G_storage_sd_Pa", "zero"]),
        (
            "frequency_Hz,G_abs_Pa,phase_deg,G_abs_sd_Pa,phase_sd_deg\n1,2,3,1,-1\n",
            2,
            ["phase_sd_deg", "negative"],
        ),
    ],
)
def test_range_errors(tmp_path, text, line, fragments):
    path = write(tmp_path, text, name="ranges.csv")
    message = read_error(path)
    assert re.search(rf"\bline {line}\b", message), message
    for fragment in fragments:
        assert fragment in message, message


@pytest.mark.parametrize(
    "header, fragments",
    [
        ("frequency_Hz,G_storge_Pa,G_loss_Pa", ["unknown column", "'G_storge_Pa'"]),
        ("frequency_Hz,G_storage_Pa,G_loss_Pa,temperature_C,note", ["'temperature_C'", "'note'"]),
        ("frequency_Hz,G_storage_Pa,G_loss_Pa,", ["unknown column", "''"]),
        ("frequency_Hz,G_storage_Pa", ["missing", "G_loss_Pa", "columns found: frequency_Hz, G_storage_Pa"]),
        ("G_storage_Pa,G_loss_Pa", ["missing", "frequency_Hz"]),
        ("frequency_Hz,G_abs_Pa", ["missing", "phase_deg"]),
        ("frequency_Hz,G_storage_Pa,G_loss_Pa,frequency_hz", ["duplicate", "frequency_Hz"]),
        ("frequency_Hz,G_storage_Pa,G_loss_Pa,phase_deg", ["mixes"]),
        ("frequency_Hz,G_abs_Pa,phase_deg,G_abs_sd_Pa", ["phase_sd_deg"]),
        ("1,2,3", ["header line missing"]),
    ],
)
def test_header_errors(tmp_path, header, fragments):
    path = write(tmp_path, f"# c1\n# c2\n{header}\n1,2,3\n", name="header_case.csv")
    message = read_error(path)
    assert "line 3" in message, message
    for fragment in fragments:
        assert fragment in message, message


def test_missing_file(tmp_path):
    path = tmp_path / "does_not_exist.csv"
    message = read_error(path)
    assert "cannot read the file: No such file or directory" in message and "Errno" not in message


def test_directory_is_unreadable(tmp_path):
    path = tmp_path / "a_directory.csv"
    path.mkdir()
    read_error(path)


def test_not_utf8(tmp_path):
    """A spreadsheet in a Western locale writes Windows-1252; Excel's "Unicode text" UTF-16 with a byte-order mark;
    both are read as such. A binary file (NUL bytes) is refused saying so."""
    path = tmp_path / "latin1.csv"
    path.write_bytes("# 25 °C, G' in Pa\n".encode("cp1252") + HEADER.encode() + b"1,2,3\n2,3,4\n")
    assert read_csv(path).comments == ("25 °C, G' in Pa",)
    wide = tmp_path / "utf16.csv"
    wide.write_bytes(("# µm\n" + HEADER + "1,2,3\n2,3,4\n").encode("utf-16"))
    assert read_csv(wide).comments == ("µm",) and read_csv(wide).n == 2
    binary = tmp_path / "image.csv"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR")
    assert "not a text file" in read_error(binary)


@pytest.mark.parametrize("text", ["", "\n\n", "# only comments\n#\n"])
def test_no_header(tmp_path, text):
    message = read_error(write(tmp_path, text, name="empty_file.csv"))
    assert "no header" in message


def test_header_only_is_an_error(tmp_path):
    message = read_error(write(tmp_path, "# x\n" + HEADER + "\n# trailing\n", name="header_only.csv"))
    assert "no data rows" in message and "line 2" in message


def test_min_points(tmp_path):
    path = write(tmp_path, HEADER + "1,2,3\n2,3,4\n3,4,5\n", name="three_points.csv")
    assert read_csv(path, min_points=3).n == 3
    message = read_error(path, min_points=5)
    assert "3 data points" in message and "5" in message


def test_error_is_value_error(tmp_path):
    with pytest.raises(ValueError):
        read_csv(tmp_path / "missing.csv")


def test_accepts_str_path(tmp_path):
    path = write(tmp_path, HEADER + "1,2,3\n")
    assert read_csv(str(path), accept=ONE_ROW).n == 1


# --- write_csv --------------------------------------------------------------


def test_write_prestress_layout_and_comments(tmp_path):
    d = bundled("stamenovic2002")
    out = tmp_path / "out.csv"
    write_csv(d, out)
    lines = out.read_text(encoding="utf-8").splitlines()
    n_comments = len(d.comments)
    assert all(line.startswith("#") for line in lines[:n_comments])
    assert lines[n_comments] == "prestress_Pa,frequency_Hz,G_storage_Pa,G_loss_Pa"
    assert len(lines) == n_comments + 1 + d.n
    back = read_csv(out)
    assert back.comments == d.comments
    assert back.kind == "prestress"
    for field in ("frequency_hz", "G_storage", "G_loss", "prestress"):
        np.testing.assert_array_equal(getattr(back, field), getattr(d, field))


def test_write_sd_columns(tmp_path):
    d = RheologyData(
        frequency_hz=[1.0, 2.0],
        G_storage=[10.0, 20.0],
        G_loss=[1.0, 2.0],
        G_storage_sd=[0.5, 0.25],
        G_loss_sd=[0.1, 0.2],
    )
    out = tmp_path / "sd.csv"
    write_csv(d, out)
    header = out.read_text().splitlines()[0]
    assert header == "frequency_Hz,G_storage_Pa,G_loss_Pa,G_storage_sd_Pa,G_loss_sd_Pa"
    back = read_csv(out)
    np.testing.assert_array_equal(back.G_storage_sd, d.G_storage_sd)
    np.testing.assert_array_equal(back.G_loss_sd, d.G_loss_sd)
    np.testing.assert_array_equal(back.weights_loss, d.weights_loss)


def test_write_replaces_existing_file_keeping_mode(tmp_path):
    out = tmp_path / "existing.csv"
    out.write_text("old contents\n")
    os.chmod(out, 0o640)
    write_csv(bundled("fabry2001"), out)
    assert read_csv(out).n == 16
    assert (out.stat().st_mode & 0o777) == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["existing.csv"]


def test_write_failure_leaves_no_file(tmp_path, monkeypatch):
    d = bundled("fabry2001")
    out = tmp_path / "never.csv"
    calls = {"n": 0}

    def failing_format(x):
        calls["n"] += 1
        if calls["n"] > 10:  # fail part-way through the rows
            raise RuntimeError("disk full (simulated)")
        return repr(float(x))

    monkeypatch.setattr(data_module, "_format", failing_format)
    with pytest.raises(RuntimeError, match="simulated"):
        write_csv(d, out)
    assert list(tmp_path.iterdir()) == []


def test_write_failure_keeps_old_file(tmp_path, monkeypatch):
    out = tmp_path / "keep.csv"
    out.write_text("old contents\n")

    def failing_replace(src, dst):
        raise OSError("simulated rename failure")

    monkeypatch.setattr(data_module.os, "replace", failing_replace)
    with pytest.raises(OSError, match="simulated"):
        write_csv(bundled("fabry2001"), out)
    assert out.read_text() == "old contents\n"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.csv"]


def test_write_to_missing_directory_raises(tmp_path):
    with pytest.raises(OSError):
        write_csv(bundled("fabry2001"), tmp_path / "no_such_dir" / "x.csv")


def _in_range(quantity):
    """Any float that tenscell accepts for ``quantity`` (its range in tenscell._ranges.RANGES, ends included)."""
    lo, hi, _ = RANGES[quantity]
    return st.floats(min_value=lo, max_value=hi, allow_nan=False, allow_infinity=False)


positive = _in_range("modulus")  # moduli, their SDs and prestress (Pa) share one range
comment_text = st.text(
    alphabet=st.characters(blacklist_categories=("Cs",), blacklist_characters="\r\n\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029"),
    max_size=30,
).map(str.strip)


@st.composite
def rheology_data(draw):
    n = draw(st.integers(min_value=1, max_value=12))
    column = st.lists(positive, min_size=n, max_size=n)
    maybe = lambda: draw(st.one_of(st.none(), column))  # noqa: E731
    return RheologyData(
        frequency_hz=draw(st.lists(_in_range("frequency"), min_size=n, max_size=n)),
        G_storage=draw(column),
        G_loss=draw(column),
        prestress=maybe(),
        G_storage_sd=maybe(),
        G_loss_sd=maybe(),
        comments=tuple(draw(st.lists(comment_text, max_size=4))),
    )


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(d=rheology_data())
def test_write_read_round_trip(tmp_path, d):
    out = tmp_path / "round_trip.csv"
    write_csv(d, out)
    back = read_csv(out, accept=CHECKS)  # random numbers: any point may be an "outlier" of its column
    assert back.n == d.n
    assert back.kind == d.kind
    assert back.comments == d.comments
    for field in ("frequency_hz", "G_storage", "G_loss", "prestress", "G_storage_sd", "G_loss_sd"):
        original, read_back = getattr(d, field), getattr(back, field)
        if original is None:
            assert read_back is None
        else:
            np.testing.assert_array_equal(read_back, original)

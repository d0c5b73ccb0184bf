"""Robustness against malformed input files (CSV data, JSON structures), listed and fuzzed.

Listed cases go through the command line (`tenscell fit`, `tenscell show`):
exit 2, one line naming the file, no traceback, nothing written. Fuzzed
cases (hypothesis) go through the readers: every input either reads or raises
the reader's own error (a ValueError subclass with a one-line message); no
other exception escapes.
"""
from __future__ import annotations

import json
import random

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tenscell.cli import main
from tenscell.io.data import DataError, RheologyData, read_csv
from tenscell.io.structure_files import load_structure_file
from tenscell.model.structure import StructureError
from tenscell.fitting import VoigtModel

HEADER = "frequency_Hz,G_storage_Pa,G_loss_Pa\n"
GOOD_ROWS = "".join(f"{f},{100 * f ** 0.2},{10 * f ** 0.2}\n" for f in (0.1, 0.3, 1, 3, 10, 30, 100))

BAD_CSV = {
    "binary": bytes(range(256)) * 8,
    "empty": b"",
    "header only": HEADER.encode(),
    "comments only": b"# nothing here\n# at all\n",
    "unknown column": b"frequency_Hz,G_storage_Pa,G_loss_Pa,colour\n1,1,1,red\n",
    "missing column": b"frequency_Hz,G_storage_Pa\n1,1\n2,2\n",
    "duplicate column": b"frequency_Hz,frequency_Hz,G_loss_Pa\n1,1,1\n",
    "nan": (HEADER + "nan,1,1\n" + GOOD_ROWS).encode(),
    "inf": (HEADER + "1e400,1,1\n" + GOOD_ROWS).encode(),
    "negative modulus": (HEADER + "1,-5,1\n" + GOOD_ROWS).encode(),
    "zero frequency": (HEADER + "0,5,1\n" + GOOD_ROWS).encode(),
    "over-long integer": (HEADER + "1" * 5000 + ",1,1\n" + GOOD_ROWS).encode(),
    "text in a number": (HEADER + "1,abc,1\n" + GOOD_ROWS).encode(),
    "NUL byte": (HEADER + "1,1\x00,1\n" + GOOD_ROWS).encode(),
    "unterminated quote": (HEADER + '"1,1,1\n').encode(),
    "ragged row": (HEADER + "1,1\n" + GOOD_ROWS).encode(),
    "too few points": (HEADER + "1,1,1\n2,1,1\n").encode(),
    # UTF-16 with its byte-order mark (Excel's "Unicode text") is read; without it, it is bytes with NULs
    "UTF-16 without a byte-order mark": (HEADER + GOOD_ROWS).encode("utf-16-le"),
}

_STRUT = {"nodes": [[0, 0, 0], [1, 0, 0]], "struts": [[0, 1]]}
BAD_JSON = {
    "binary": bytes(range(256)) * 8,
    "empty": b"",
    "not JSON": b"nodes: [1, 2]",
    "a list": b"[1, 2, 3]",
    "deeply nested": b"[" * 100_000 + b"]" * 100_000,
    "over-long integer in a position": b'{"nodes": [[' + b"1" * 5000 + b',0,0],[1,0,0]], "struts": [[0,1]]}',
    "over-long node index": b'{"nodes": [[0,0,0],[1,0,0]], "struts": [[0,' + b"9" * 4000 + b"]]}",
    "NaN position": b'{"nodes": [[NaN,0,0],[1,0,0]], "struts": [[0,1]]}',
    "infinite position": b'{"nodes": [[1e400,0,0],[1,0,0]], "struts": [[0,1]]}',
    "unknown key": json.dumps({**_STRUT, "colour": "red"}).encode(),
    "no nodes": json.dumps({"struts": [[0, 1]]}).encode(),
    "self loop": json.dumps({"nodes": [[0, 0, 0], [1, 0, 0]], "tendons": [[1, 1]]}).encode(),
    "unknown node": json.dumps({"nodes": [[0, 0, 0], [1, 0, 0]], "struts": [[0, 7]]}).encode(),
    "string position": json.dumps({"nodes": [["a", 0, 0], [1, 0, 0]], "struts": [[0, 1]]}).encode(),
    "bool node": json.dumps({"nodes": [[0, 0, 0], [1, 0, 0]], "struts": [[True, 1]]}).encode(),
    "wrong version": json.dumps({**_STRUT, "version": 99}).encode(),
}


@pytest.fixture
def dirs(tmp_path, monkeypatch):
    (tmp_path / "in").mkdir()
    (tmp_path / "work").mkdir()
    monkeypatch.chdir(tmp_path / "work")
    return tmp_path


def _refused_naming(argv, name, capsys, dirs):
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2, (name, err)
    assert err.count("\n") == 1 and "Traceback" not in err, (name, err)
    assert name in err, (name, err)
    assert len(err) < 800, "the message stays one readable line"
    assert list((dirs / "work").iterdir()) == [], (name, "wrote files")


@pytest.mark.parametrize("case", sorted(BAD_CSV))
def test_malformed_csv_is_refused_by_fit(case, capsys, dirs):
    path = dirs / "in" / "bad data.csv"
    path.write_bytes(BAD_CSV[case])
    _refused_naming(["fit", str(path), "--tendons", "uniform", "--out", str(dirs / "work" / "o")],
                    "bad data.csv", capsys, dirs)


@pytest.mark.parametrize("case", sorted(BAD_JSON))
def test_malformed_structure_is_refused_by_show(case, capsys, dirs):
    path = dirs / "in" / "cell.json"
    path.write_bytes(BAD_JSON[case])
    _refused_naming(["show", str(path), "--out", str(dirs / "work" / "o")], "cell.json", capsys, dirs)


# ---- fuzzing the readers ------------------------------------------------------------------------
_FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])

cells = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr), st.integers().map(str),
                  st.text(max_size=6), st.sampled_from(["", " ", "nan", "1e999", "-0", '"', "#", "1_0"]))
columns = st.sampled_from(["frequency_Hz", "G_storage_Pa", "G_loss_Pa", "prestress_Pa", "G_abs_Pa", "phase_deg",
                           "G_storage_sd_Pa", "x", ""])


@st.composite
def csv_texts(draw):
    header = draw(st.lists(columns, min_size=0, max_size=5))
    rows = draw(st.lists(st.lists(cells, min_size=0, max_size=6), max_size=8))
    lines = [",".join(header)] + [",".join(r) for r in rows]
    return "\n".join(lines) + draw(st.sampled_from(["", "\n", "\r\n"]))


@_FUZZ
@given(text=csv_texts())
def test_fuzzed_csv_reads_or_raises_data_error(tmp_path, text):
    path = tmp_path / "fuzz.csv"
    path.write_text(text)
    try:
        d = read_csv(path)
    except DataError as err:
        assert "\n" not in str(err) and "fuzz.csv" in str(err)
    else:
        assert d.n >= 1 and np.all(np.isfinite(d.G_storage)) and np.all(d.frequency_hz > 0)


@_FUZZ
@given(blob=st.binary(max_size=400))
def test_fuzzed_bytes_as_csv(tmp_path, blob):
    path = tmp_path / "fuzz.csv"
    path.write_bytes(blob)
    try:
        read_csv(path)
    except DataError as err:
        assert "fuzz.csv" in str(err)


json_values = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(), st.floats(allow_nan=True), st.text(max_size=5)),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(
        st.sampled_from(["nodes", "struts", "tendons", "name", "xyz", "EA", "c", "T0", "family", "format",
                         "version", "units", "length", "description", "x"]), children, max_size=4),
    max_leaves=25)


@_FUZZ
@given(obj=json_values)
def test_fuzzed_structure_json_reads_or_raises_structure_error(tmp_path, obj):
    path = tmp_path / "fuzz.json"
    path.write_text(json.dumps(obj))
    try:
        load_structure_file(path)
    except StructureError as err:
        assert "fuzz.json" in str(err)


@_FUZZ
@given(blob=st.binary(max_size=400))
def test_fuzzed_bytes_as_structure(tmp_path, blob):
    path = tmp_path / "fuzz.json"
    path.write_bytes(blob)
    with pytest.raises(StructureError, match="fuzz.json"):
        load_structure_file(path)


# ---- the same data in any row order gives the same data set (and so the same fit) ---------------
def test_row_order_does_not_change_the_data_or_the_fit(tmp_path):
    from tenscell import fitting
    from tenscell.io.data import bundled

    d = bundled("fabry2001")
    rng = random.Random(3)
    order = list(range(d.n))
    rng.shuffle(order)
    shuffled = RheologyData(frequency_hz=d.frequency_hz[order], G_storage=d.G_storage[order],
                            G_loss=d.G_loss[order], source="shuffled")
    for name in ("frequency_hz", "G_storage", "G_loss"):
        np.testing.assert_array_equal(getattr(shuffled, name), getattr(d, name))
    a = fitting.fit(d, model=VoigtModel(tendons="uniform"), starts=1, hops=2, seed=5, progress=False)
    b = fitting.fit(shuffled, model=VoigtModel(tendons="uniform"), starts=1, hops=2, seed=5, progress=False)
    assert a.rms_log10_error == b.rms_log10_error
    np.testing.assert_array_equal(a.theta, b.theta)


def test_moduli_csv_is_read_by_fit(tmp_path, capsys):
    """The table `tenscell moduli` writes is a data set `tenscell fit` reads."""
    assert main(["moduli", "--prestress", "500,1000", "--freq", "0.1:10:4"]) == 0
    path = tmp_path / "moduli.csv"
    path.write_text(capsys.readouterr().out)
    d = read_csv(path)
    assert d.kind == "prestress" and d.n == 8


def test_binning_keeps_the_objective_and_states_its_rule():
    """Binned data: at most max_points, the weighted least-squares objective up to the within-bin scatter."""
    from tenscell.io.thinning import binning_notes

    rng = np.random.default_rng(0)
    n = 5000
    f = np.logspace(-2, 3, n)
    P = rng.choice([300.0, 1000.0], n)
    Gs, Gl = 100 * f ** 0.2 * np.exp(rng.normal(0, 0.05, n)), 10 * f ** 0.3 * np.exp(rng.normal(0, 0.05, n))
    d = RheologyData(frequency_hz=f, G_storage=Gs, G_loss=Gl, prestress=P)
    b = d.binned(60)
    assert b.n <= 60 and b.kind == "prestress" and set(np.unique(b.prestress)) == {300.0, 1000.0}
    assert binning_notes(b) and "5,000" in binning_notes(b)[0] and "√" in binning_notes(b)[0]
    assert d.binned(10_000) is d
    # no SDs stated: the bins carry their counts as weights, not a made-up noise (the fit's noise rule needs SDs)
    assert not b.has_sd and b.counts.sum() == n and b.provenance.points == b.n
    np.testing.assert_allclose(b.weights_storage, np.sqrt(b.counts), rtol=0)

    # objective of a smooth model m(f) = a f^k: raw minus binned = within-bin scatter, whatever (a, k)
    def objective(data, a, k):
        r = (np.log10(data.G_storage) - np.log10(a * data.frequency_hz ** k)) * data.weights_storage
        return float(np.sum(r ** 2))

    diffs = [objective(d, a, k) - objective(b, a, k) for a, k in ((100, 0.2), (80, 0.25), (150, 0.1))]
    # equal up to the model's variation across a bin (a decade / 30 bins): far below the objective itself
    assert np.ptp(diffs) < 0.02 * objective(d, 150, 0.1)


def test_fit_from_python_bins_dense_data_as_the_command_does():
    """fitting.fit bins a dense sweep by the same rule as `tenscell fit --max-points` (None: every point)."""
    from tenscell import fitting
    from tenscell.io.data import bundled
    from tenscell.io.thinning import binning_notes

    f = np.logspace(-2, 2, 2000)
    d = RheologyData(frequency_hz=f, G_storage=300 * f ** 0.2, G_loss=60 * f ** 0.2, source="dense")
    quick = dict(model=fitting.VoigtModel("uniform"), starts=1, hops=0, seed=0, progress=False)
    r = fitting.fit(d, max_points=40, **quick)
    assert r.data.n <= 40 and binning_notes(r.data) and r.problem.n_points == r.data.n
    assert f.min() <= r.data.frequency_hz.min() and r.data.frequency_hz.max() <= f.max()
    small = fitting.fit(bundled("fabry2001"), **quick)  # default max_points: small data are fitted as they are
    assert small.data.n == bundled("fabry2001").n and not binning_notes(small.data)
    part = RheologyData(frequency_hz=f[:200], G_storage=d.G_storage[:200], G_loss=d.G_loss[:200])
    assert fitting.fit(part, max_points=None, **quick).data.n == 200
    with pytest.raises(ValueError, match="max_points"):
        fitting.fit(d, max_points=2, **quick)

"""Damaged files (issue 36): every reader refuses a file cut short or edited, in one line, before any computation.

Each case builds a damaged file in ``tmp_path`` from a real format: the instrument fixtures of ``tests/data`` (TRIOS
LIMS, ``[step]`` text, RheoCompass), tenscell's CSV layouts, the measured-cell files' layout, a fit.json of a real
fit; and, where ``../shared/data`` is beside the repository, the real exports and cells themselves (cut in
``tmp_path``, never copied into the repository; skipped with the reason where absent). Through the command line:
exit 2, one line naming the file (and the line, column or field), nothing on stdout, nothing written. From Python:
the same message as a ``DataError`` (a ``FitFileError`` for a fit.json). The undamaged files read, so that no check
passes by refusing everything.
"""
from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from tenscell.cli import main
from tenscell.fitting.fitted import FitFileError, load_fit
from tenscell.io.columns import DataError
from tenscell.io.readers import read_data

DATA = Path(__file__).parent / "data"
SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data"
EXPORTS = SHARED / "instrument-exports"
CELLS = SHARED / "real-cells"
needs_exports = pytest.mark.skipif(not EXPORTS.is_dir(), reason=f"the instrument exports are not at {EXPORTS}")
needs_cells = pytest.mark.skipif(not CELLS.is_dir(), reason=f"the measured-cell data are not at {CELLS} (not shipped)")

PLAIN_TRIOS = ("Filename\tfrequency_sweep_sample.tri\nInstrument name\tDiscovery HR-2\nSample name\tcells\n"
               "Number of points\t5\nVariables\tAngular Frequency\tStorage Modulus\tLoss Modulus\tStep\n"
               "\trad/s\tPa\tPa\n"
               + "".join(f"Data point\t{w}\t{g1}\t{g2}\t{s}\n" for w, g1, g2, s in [
                   (6.28, 1000.5, 250.3, 1), (12.56, 1050.2, 275.1, 1), (25.13, 1120.8, 310.5, 1),
                   (50.27, 1200.3, 350.2, 1), (100.53, 1305.7, 400.8, 1)]))
MODULI = "# a lab's sweep\nfrequency_Hz,G_storage_Pa,G_loss_Pa\n" + "".join(
    f"{f:g},{100 * f ** 0.2:.6g},{12.3456 * f ** 0.3:.6g}\n" for f in (0.1, 0.3, 1, 3, 10, 30, 100))
CREEP = "time_s,creep_compliance_per_Pa\n" + "".join(f"{t:.6g},{1e-3 * t ** 0.2:.6g}\n"
                                                      for t in np.logspace(-2, 2, 30))


# ---- ways of damaging a text file ---------------------------------------------------------------------------------
def cut_row(text: str, keep: float = 0.5) -> str:
    """The file cut in the middle of its last data row (the last non-blank line), no line break after it."""
    body = text.rstrip("\n")
    start = body.rfind("\n") + 1
    return body[:start + max(1, int((len(body) - start) * keep))]


def cut_number(text: str, lose: int = 3) -> str:
    """The file cut ``lose`` characters before the end of its last number (no line break after it)."""
    body = text.rstrip("\n").rstrip("\t")
    return body[:-lose]


def drop_rows(text: str, n: int = 1) -> str:
    """The file without its last ``n`` data rows, cut at a line end (a line break after the last row kept)."""
    lines = text.rstrip("\n").split("\n")
    return "\n".join(lines[:-n]) + "\n"


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_bytes(text.encode("utf-8"))
    return path


def _refused_cli(argv, words, capsys, root: Path) -> str:
    before = sorted(p.name for p in root.iterdir())
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert code == 2, (argv, code, err)
    assert out == "" and err.count("\n") == 1 and "Traceback" not in err, (argv, out, err)
    for w in words:
        assert w in err, (w, err)
    assert sorted(p.name for p in root.iterdir()) == before, "a refused command wrote files"
    return err


# ---- the table: (name, file name, its damaged text, read options, flags, the words of the message) -----------------
def _lims() -> str:
    return (DATA / "trios_lims_temperature_steps.txt").read_text(encoding="utf-8")


def _rheocompass() -> str:
    return (DATA / "rheocompass_frequency_sweep.txt").read_text(encoding="utf-8")


def _text_steps() -> str:
    return (DATA / "trios_text_steps.txt").read_text(encoding="utf-8")


def _collapsed_creep(n: int = 100_000, fraction: float = 0.01, factor: float = 80.0) -> str:
    t = np.logspace(-2, 2, n)
    J = 1e-3 * t ** 0.2 * (1 + 0.01 * np.sin(np.arange(n)))
    J[-int(n * fraction):] /= factor
    return "time_s,creep_compliance_per_Pa\n" + "".join(f"{a:.7g},{b:.7g}\n" for a, b in zip(t, J))


def _damaged_run_creep() -> str:
    t = np.logspace(-2, 2, 500)
    J = 1e-3 * t ** 0.2
    J[200:210] *= 1e5  # ten damaged rows in a row: each has a damaged neighbour
    return "time_s,creep_compliance_per_Pa\n" + "".join(f"{a:.7g},{b:.7g}\n" for a, b in zip(t, J))


CASES = [
    ("plain TRIOS cut in its last row", "sweep.txt", cut_row(PLAIN_TRIOS, 0.6), {}, [],
     ["line 11", "fields its 'Variables' row names", "cut short"]),
    ("plain TRIOS cut in its Step field", "sweep.txt", PLAIN_TRIOS.rstrip("\n")[:-1], {}, [],
     ["line 11", "column 'Step'"]),
    ("plain TRIOS cut at a line end: 4 of 5 points", "sweep.txt", drop_rows(PLAIN_TRIOS), {}, [],
     ["'Number of points 5' (line 4)", "4 data rows", "--accept point-count"]),
    ("plain TRIOS with two steps, cut at a line end", "sweep.txt",
     drop_rows(PLAIN_TRIOS.replace("350.2\t1", "350.2\t2").replace("400.8\t1", "400.8\t2")), {"step": 1},
     ["--step", "1"], ["says 5 points", "4 data rows", "Step column"]),
    ("LIMS export cut in its last row", "lims.txt", cut_row(_lims()), {"step": 1}, ["--step", "1"],
     ["lims.txt, line", "fields", "cut short"]),
    ("LIMS export cut at a line end (its last step)", "lims.txt", drop_rows(_lims(), 2), {"step": 1},
     ["--step", "1"], ["step 3", "'Number of points", "--accept point-count"]),
    ("[step] text export cut in a number", "steps.txt", cut_number(_text_steps()), {"step": 2}, ["--step", "2"],
     ["steps.txt, line"]),
    ("RheoCompass export cut in its last row", "rc.txt", cut_row(_rheocompass(), 0.4), {"step": 2},
     ["--step", "2"], ["rc.txt, line", "cut short"]),
    ("RheoCompass export cut at a line end", "rc.txt", drop_rows(_rheocompass()), {"step": 2},
     ["--step", "2"], ["interval 2", "says 16 points", "15 data rows"]),
    ("tenscell CSV cut in a number", "m.csv", cut_number(MODULI, 3), {}, [],
     ["m.csv, line 9", "column 'G_loss_Pa'", "--accept truncated"]),
    ("tenscell CSV cut in a row", "m.csv", cut_row(MODULI, 0.3), {}, [], ["m.csv, line 9"]),
    ("a lab's table cut in a number", "lab.csv",
     cut_number(MODULI.replace("frequency_Hz,G_storage_Pa,G_loss_Pa", "f (Hz),G' (Pa),G'' (Pa)"), 3), {}, [],
     ["lab.csv, line 9", "column \"G'' (Pa)\"", "--accept truncated"]),
    ("creep CSV cut in a number", "creep.csv", cut_number(CREEP, 2), {}, [], ["creep.csv, line 31", "truncated"]),
    ("creep table of one time", "creep.csv",
     "time_s,creep_compliance_per_Pa\n" + "".join(f"1.0,{1e-3 * (1 + 0.01 * i):.6g}\n" for i in range(10)), {}, [],
     ["10 points at one time", "--accept one-time"]),
    ("creep table whose times repeat", "creep.csv", CREEP + "".join(f"5.0,{1e-3 * (1 + 0.1 * i):.6g}\n"
                                                                    for i in range(5)), {}, [],
     ["5 of 35 rows are at t = 5 s", "--accept repeated-times"]),
    ("creep table whose last 1 % collapses 80-fold", "creep.csv", _collapsed_creep(), {}, [],
     ["creep.csv, lines", "column 'creep_compliance_per_Pa'", "falls", "--accept collapse"]),
    ("creep table with a run of damaged rows", "creep.csv", _damaged_run_creep(), {}, [],
     ["creep.csv, lines", "--accept outliers"]),
    ("creep table with another run appended", "creep.csv",
     CREEP + "".join(f"{t:.6g},{3e-4 * t ** 0.2:.6g}\n" for t in np.logspace(2.1, 3, 30)), {}, [],
     ["creep.csv, lines", "--accept collapse"]),
]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_a_damaged_file_is_refused_by_the_command_line(case, tmp_path, capsys, monkeypatch):
    _, name, text, _, flags, words = case
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    path = _write(tmp_path, name, text)
    _refused_cli(["fit", path, *flags, "--tendons", "uniform", "--out", tmp_path / "o"], [name, *words], capsys,
                 tmp_path)


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_a_damaged_file_is_refused_from_python(case, tmp_path):
    _, name, text, options, _, words = case
    path = _write(tmp_path, name, text)
    with pytest.raises(DataError) as err:
        read_data(path, **options)
    message = str(err.value)
    assert "\n" not in message and name in message
    for w in words:
        # Python names the keyword (accept=..., step=...) where the command line names the flag
        if w.startswith("--accept "):
            w = f"accept={w.removeprefix('--accept ')!r}"
        assert w in message, (w, message)


@pytest.mark.parametrize("text, options", [(PLAIN_TRIOS, {}), (_lims(), {"step": 1}), (_rheocompass(), {"step": 2}),
                                           (MODULI, {}), (CREEP, {}), (_text_steps(), {"step": 2})],
                         ids=["plain TRIOS", "LIMS", "RheoCompass", "tenscell CSV", "creep CSV", "[step] text"])
def test_the_same_files_undamaged_read_with_or_without_their_last_line_break(text, options, tmp_path):
    for variant in (text, text.rstrip("\n")):
        path = _write(tmp_path, "ok.txt" if "\t" in text else "ok.csv", variant)
        assert read_data(path, **options).n >= 5


def test_a_complete_creep_table_that_is_dense_noisy_and_rounded_reads(tmp_path):
    """Times rounded to their resolution (pairs of rows at one time) and noise are not a collapse."""
    rng = np.random.default_rng(0)
    t = np.round(np.linspace(1, 7200, 7199), 0)
    J = 1e-5 * t ** 0.6 * np.exp(rng.normal(0, 0.05, t.size))
    path = _write(tmp_path, "dense.csv", "time_s,creep_compliance_per_Pa\n"
                  + "".join(f"{a:.6g},{b:.6g}\n" for a, b in zip(t, J)))
    assert read_data(path).n == 7199


# ---- flags that choose a step -----------------------------------------------------------------------------------
@pytest.mark.parametrize("flags, words", [(["--temperature", "99"], ["--temperature 99", "0 steps at 99"]),
                                          (["--step", "99"], ["--step 99", "no step 99"])])
def test_a_step_that_is_not_there_names_the_flag(flags, words, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = _write(tmp_path, "lims.txt", _lims())
    _refused_cli(["fit", path, *flags, "--out", tmp_path / "o"], ["lims.txt", *words], capsys, tmp_path)
    with pytest.raises(DataError, match=r"temperature=99|step=99"):
        read_data(path, **{flags[0].lstrip("-"): 99})


# ---- the measured cells' files ---------------------------------------------------------------------------------
_CELL_HEADER = ("# Measured: AFM oscillatory indentation (1 nN set point), Xie et al., Soft Matter 2024.\n"
                "# cell_line=MCF-10A cell_index={i} aspect_ratio=1.385 area=165.5 hertz_E_Pa=696.02; "
                "{dropped} point(s) with G<=0 dropped\nfrequency_Hz,G_storage_Pa,G_loss_Pa\n")
_CELL_ROWS = [(1, 355.455, 61.1138), (3, 417.932, 81.8119), (10, 476.28, 99.4496), (30, 519.711, 148.132),
              (100, 712.221, 157.858), (200, 989.834, 414.574)]


def _cells(tmp_path: Path, text: str) -> Path:
    folder = tmp_path / "real-cells" / "xie2024_population" / "MCF-10A"
    folder.mkdir(parents=True)
    rows = "".join(f"{f},{a},{b}\n" for f, a, b in _CELL_ROWS)
    (folder / "cell_01.csv").write_text(_CELL_HEADER.format(i=1, dropped=0) + rows)
    (folder / "cell_02.csv").write_text(text)
    return tmp_path / "real-cells"


@pytest.mark.parametrize("damage, words", [
    (lambda t: t.rstrip("\n").rsplit("\n", 1)[0][:-5], ["line 8", "column 'G_loss_Pa'", "restore the file"]),
    (drop_rows, ["holds 5 points", "missing: 200 Hz", "none was dropped"]),
    (lambda t: t.replace("0 point(s)", "1 point(s)"), ["holds 6 points", "1 point(s) dropped"]),
    (lambda t: t.replace("\n30,", "\n31,"), ["not the line's: 31 Hz"]),
], ids=["100 Hz G'' cut to 15, 200 Hz gone", "cut at a line end", "header edited", "frequency edited"])
def test_a_damaged_cell_file_is_refused_against_its_lines_frequencies(damage, words, tmp_path):
    from tenscell.studies.real_cells import xie_cells

    text = _CELL_HEADER.format(i=2, dropped=0) + "".join(f"{f},{a},{b}\n" for f, a, b in _CELL_ROWS)
    folder = _cells(tmp_path, damage(text))
    with pytest.raises(DataError) as err:
        xie_cells("MCF-10A", folder)
    message = str(err.value)
    assert "cell_02.csv" in message and "\n" not in message
    for w in words:
        assert w in message, (w, message)
    (folder / "xie2024_population" / "MCF-10A" / "cell_02.csv").write_text(text)
    assert len(xie_cells("MCF-10A", folder)) == 2  # undamaged, it reads


@needs_cells
def test_the_real_cells_study_refuses_a_cut_cell_file_in_one_line(tmp_path, capsys, monkeypatch):
    data = tmp_path / "real-cells"
    shutil.copytree(CELLS, data)
    cell = data / "xie2024_population" / "MCF-10A" / "cell_05.csv"
    cell.chmod(0o644)
    lines = cell.read_text().rstrip("\n").split("\n")
    cell.write_text("\n".join(lines[:-2] + [lines[-2][:-4]]))  # the 100 Hz row cut in its G'', 200 Hz gone
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    _refused_cli(["study", "real-cells", "--data", data, "--out", tmp_path / "o"],
                 ["cell_05.csv", "line 8", "G_loss_Pa"], capsys, tmp_path)


# ---- the real exports, cut -------------------------------------------------------------------------------------------
@needs_exports
@pytest.mark.parametrize("name, options, damage, words", [
    ("tests_fixtures_trios_frequency_sweep.csv", {}, lambda t: cut_row(t, 0.7), ["line 16", "cut short"]),
    ("tests_fixtures_trios_frequency_sweep.csv", {}, drop_rows, ["'Number of points 5'", "4 data rows"]),
    ("frequency_sweep_tts.txt", {"step": 1}, cut_row, ["fields", "cut short"]),
    ("frequency_sweep_tts.txt", {"temperature": 150}, lambda t: drop_rows(t, 3), ["step 20", "Number of points"]),
    ("tests_fixtures_rheocompass_frequency_sweep.csv", {}, lambda t: cut_row(t, 0.3), ["line 25", "cut short"]),
    ("tests_fixtures_rheocompass_frequency_sweep.csv", {}, drop_rows, ["says 10 points", "9 data rows"]),
], ids=["plain TRIOS cut in a row", "plain TRIOS cut at a line end", "LIMS cut in a row", "LIMS cut at a line end",
        "RheoCompass cut in a row", "RheoCompass cut at a line end"])
def test_the_real_exports_cut_are_refused(name, options, damage, words, tmp_path):
    text = (EXPORTS / name).read_text(encoding="utf-8")
    assert read_data(EXPORTS / name, **options).n >= 5  # whole, it reads
    path = _write(tmp_path, name, damage(text))
    with pytest.raises(DataError) as err:
        read_data(path, **options)
    assert name in str(err.value) and "\n" not in str(err.value)
    for w in words:
        assert w in str(err.value), (w, str(err.value))


@needs_exports
def test_the_real_dense_creep_table_reads(tmp_path):
    """7,199 measured points with times rounded to 1 s past 1000 s (218 pairs at one time) and noise: no check
    refuses it."""
    data = read_data(EXPORTS / "creep_ps145_data.csv", time_unit="s", compliance_unit="1/Pa")
    assert data.n == 7199 and data.provenance.accepted == ()


@needs_cells
def test_the_real_measured_cells_read():
    from tenscell.studies.real_cells import XIE_LINES, hl60_creep, xie_cells, xie_median

    assert [len(xie_cells(line, CELLS)) for line in XIE_LINES] == [59, 46]
    assert [xie_median(line, CELLS).n for line in XIE_LINES] == [6, 6] and hl60_creep(CELLS).n == 48


# ---- fit.json: labels edited ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def fit_json(tmp_path_factory):
    from tenscell.fitting import fit
    from tenscell.io.data import bundled
    from tenscell.io.outputs import write_json

    result = fit(bundled("fabry2001"), model="springpot+visc", starts=1, hops=0, progress=False)
    path = tmp_path_factory.mktemp("fit") / "fit.json"
    write_json(path, result.to_dict())
    return json.loads(path.read_text())


def _set(doc, keys, value):
    for k in keys[:-1]:
        doc = doc[k]
    doc[keys[-1]] = value


EDITS = [
    ("mechanism renamed to another of the catalog", [("model", "mechanism", "name"), ("spec", "name"),
                                                     ("model_name",)], "maxwell+visc",
     ["model.mechanism.name", "'maxwell+visc' is a mechanism of the catalog"]),
    ("mechanism renamed to one outside the catalog", [("model", "mechanism", "name"), ("spec", "name"),
                                                      ("model_name",)], "springpot-visc",
     ["model.mechanism.name", "'springpot+visc' of the catalog"]),
    ("mechanism renamed in the model only", [("model", "mechanism", "name")], "springpot",
     ["model.mechanism.name", "differs in viscosity"]),
    ("delta = 90°", [("model", "cell_parameters", "delta")], math.pi / 2, ["model.cell_parameters.delta"]),
    ("delta = 90 (degrees)", [("model", "cell_parameters", "delta")], 90, ["model.cell_parameters.delta"]),
    ("L = -1", [("model", "cell_parameters", "L")], -1, ["model.cell_parameters.L", "-1 m"]),
    ("L = 2, another cell than the structure", [("model", "cell_parameters", "L")], 2.0,
     ["model.cell_parameters", "not the parameters of the stored structure"]),
    ("delta = 60°, another cell than the structure", [("model", "cell_parameters", "delta")], math.radians(60),
     ["not the parameters of the stored structure"]),
    ("intermediate filaments as a string", [("model", "cell_parameters", "intermediate_filaments")], "yes",
     ["model.cell_parameters.intermediate_filaments"]),
    ("model_name edited", [("model_name",)], "springpot-tension+visc", ["model_name", "'springpot-tension+visc'"]),
]


@pytest.mark.parametrize("edit", EDITS, ids=[e[0] for e in EDITS])
def test_an_edited_fit_json_is_refused(edit, fit_json, tmp_path, capsys, monkeypatch):
    _, where, value, words = edit
    doc = json.loads(json.dumps(fit_json))
    for keys in where:
        _set(doc, keys, value)
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(FitFileError) as err:
        load_fit(path)
    for w in words:
        assert w in str(err.value), (w, str(err.value))
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    _refused_cli(["moduli", "--from-fit", path], ["fit.json", *words], capsys, tmp_path)


def test_the_fit_json_as_written_reads(fit_json, tmp_path):
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(fit_json))
    assert load_fit(path).describe()

"""Every file an instrument writes is read right or refused in one line (issue 28): the readers' registry, their
refusals, what they record (provenance), creep binned in log time, and every file of ../shared/data through
`tenscell fit`.

The refusals are checked through the command line (exit 2, one line naming the file, the line where there is one,
and the flag that reads the file anyway; nothing written) and through the Python readers (the same message with
the keyword). The walk reads every instrument export and measured-cell file of ../shared/data (read at run time,
never copied: several state no licence) and skips, saying why, where that folder is absent.
"""
from __future__ import annotations

import ast
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

import tenscell.cli.fit as cli_fit
from tenscell.cli import main
from tenscell.cli._args import ACCEPT_CHECKS, FLAG_SPELLING
from tenscell.io.checks import CHECKS
from tenscell.io.creep_data import CreepData
from tenscell.io.data import DataError, RheologyData
from tenscell.io.readers import READERS, detect_layout, read_data
from tenscell.io.readers.trios import read_trios

TESTS = Path(__file__).parent
DATA = TESTS / "data"
LIMS = DATA / "trios_lims_temperature_steps.txt"
TEXT = DATA / "trios_text_steps.txt"
RHEOCOMPASS = DATA / "rheocompass_frequency_sweep.txt"
SHARED = TESTS.parent.parent / "shared" / "data"
needs_shared = pytest.mark.skipif(not SHARED.is_dir(), reason=f"{SHARED} is absent (a clone without the reference "
                                                                "data: ../shared/data is never copied into the repository)")


class Loaded(BaseException):
    """Raised by the fit command's reading function once the data are read: the walk needs no fit."""

    def __init__(self, datasets, lines):
        super().__init__("loaded")
        self.datasets, self.lines = datasets, lines


@pytest.fixture
def read_only(monkeypatch):
    """`tenscell fit` up to its data (every check of the reading path), then stop: no fit is computed."""
    original = cli_fit.read_inputs

    def stop(args, min_points):
        raise Loaded(*original(args, min_points))

    monkeypatch.setattr(cli_fit, "read_inputs", stop)


def fit_reads(path, *flags, tmp_path) -> tuple[int | Loaded, str]:
    """(Loaded, "") when `tenscell fit PATH FLAGS` reads its data; (exit status, stderr) when it is refused."""
    import contextlib
    import io

    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            code = main(["fit", str(path), *map(str, flags), "--out", str(tmp_path / "o")])
    except Loaded as done:
        return done, err.getvalue()
    return code, err.getvalue()


def refused(path, *flags, tmp_path, words=()) -> str:
    """Exit 2, one line naming the file and ``words``, no Python text, nothing written."""
    code, err = fit_reads(path, *flags, tmp_path=tmp_path)
    assert code == 2, (path, flags, code, err)
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert Path(path).name in err, err
    for w in words:
        assert w in err, (w, err)
    assert not (tmp_path / "o").exists()
    assert not re.search(r"\b[a-z]+_[a-z_]+=", err.split(": error: ", 1)[1]), f"a Python keyword: {err}"
    return err


# ---- the registry ----------------------------------------------------------------------------------------------
def test_every_reader_has_the_registry_interface():
    """A format is one module with LAYOUT, EXPECTED, detect and read, named once in READERS."""
    from importlib import import_module

    for name in READERS:
        mod = import_module(f"tenscell.io.readers.{name}")
        assert isinstance(mod.LAYOUT, str) and isinstance(mod.EXPECTED, str)
        assert callable(mod.detect) and callable(mod.read)
    assert detect_layout(LIMS) == "trios" and detect_layout(RHEOCOMPASS) == "rheocompass"
    assert detect_layout(DATA / "creep_compliance.tsv") == "table"


def test_a_new_format_is_one_module_and_one_registry_line(tmp_path, monkeypatch):
    """A reader added to the registry is used by read_data (and by `tenscell fit`) with nothing else changed."""
    import sys
    import types

    import tenscell.io.readers as readers
    from tenscell.io.provenance import Provenance

    mod = types.ModuleType("tenscell.io.readers.demo")
    mod.LAYOUT, mod.EXPECTED = "demo export", "a demo export ('DEMO' on its first line)"
    mod.detect = lambda probe: 2 if probe.lines[:1] == ["DEMO"] else 0

    def read(probe, request):
        f, g = np.array([1.0, 10.0]), np.array([100.0, 150.0])
        return RheologyData(f, g, g / 10, source=probe.source, provenance=Provenance(file=probe.source,
                                                                                      layout=mod.LAYOUT, points=2))

    mod.read = read
    monkeypatch.setitem(sys.modules, "tenscell.io.readers.demo", mod)
    monkeypatch.setattr(readers, "READERS", ("demo", *readers.READERS))
    p = tmp_path / "x.demo"
    p.write_text("DEMO\n")
    d = read_data(p)
    assert d.n == 2 and d.provenance.layout == "demo export"


def test_the_checks_are_named_alike_for_the_parser():
    assert ACCEPT_CHECKS == CHECKS


def test_every_option_a_message_names_has_a_flag():
    """Every option() the library names in a message (tenscell._errors.option) is spelled as a flag on the command
    line: no message reaches the user with a Python keyword."""
    src = TESTS.parent / "src" / "tenscell"
    named = set()
    for path in src.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "option" and node.args \
                    and isinstance(node.args[0], ast.Constant):
                named.add(node.args[0].value)
    assert named >= {"columns", "step", "temperature", "accept", "min_points", "geometric_factor"}
    assert named <= set(FLAG_SPELLING), named - set(FLAG_SPELLING)
    # option(field) with a column map's field (its columns and units) in the readers' messages
    from tenscell.io.columns import ColumnMap

    assert set(ColumnMap.__dataclass_fields__) <= set(FLAG_SPELLING)


# ---- refusals, and the flag that reads the file anyway ------------------------------------------------------
def _lines(path: Path) -> list[str]:
    return path.read_text(encoding="utf-8").splitlines()


def _write(tmp_path, name, lines) -> Path:
    p = tmp_path / name
    p.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return p


def test_a_trios_export_missing_a_step_line_is_refused_not_read_as_another_step(tmp_path, read_only):
    lines = _lines(TEXT)
    second = [k for k, s in enumerate(lines) if s.strip() == "[step]"][1]
    p = _write(tmp_path, "missing_step.txt", lines[:second] + lines[second + 1:])
    err = refused(p, tmp_path=tmp_path, words=(f"line {second + 1}", "'Frequency sweep - 2'", "[step] line"))
    assert "missing" in err
    with pytest.raises(DataError, match=r"a step whose \[step\] line is missing"):
        read_trios(p)


def test_a_lims_step_without_its_step_line_is_refused(tmp_path):
    lines = _lines(LIMS)
    second = [k for k, s in enumerate(lines) if s.strip() == "[Step]"][1]
    p = _write(tmp_path, "lims.txt", lines[:second] + lines[second + 1:])
    with pytest.raises(DataError, match=rf"line {second + 1}: 'Step name' follows the data .* is a \[Step\] line"):
        read_trios(p, 1)


def test_a_step_holding_one_frequency_is_refused_even_when_chosen(tmp_path, read_only):
    refused(TEXT, "--step", 1, tmp_path=tmp_path, words=("step 1 'Amplitude sweep - 1' holds 5 points at one "
                                                          "frequency (1 Hz)", "--accept one-frequency"))
    done, _ = fit_reads(TEXT, "--step", 1, "--accept", "one-frequency", tmp_path=tmp_path)
    assert isinstance(done, Loaded) and done.datasets[0].n == 5
    assert done.datasets[0].provenance.accepted[0].startswith("one-frequency: ")


@pytest.mark.parametrize("fixture, count", [("lims", 12), ("plain", 12), ("rheocompass", 9)])
def test_a_point_count_that_contradicts_the_header_is_refused(fixture, count, tmp_path, read_only):
    if fixture == "plain":
        if not SHARED.is_dir():
            pytest.skip(f"{SHARED} is absent")
        source = SHARED / "instrument-exports" / "tests_fixtures_trios_frequency_sweep.csv"
    else:
        source = {"lims": LIMS, "rheocompass": RHEOCOMPASS}[fixture]
    lines = _lines(source)
    if fixture == "rheocompass":
        k = next(i for i, s in enumerate(lines) if s.startswith("Interval and data points:\t2"))
        lines[k] = f"Interval and data points:\t2\t{count}"
        flags, said = ("--step", 2), f"'Interval and data points: 2 {count}' (line {k + 1}) says {count} points"
    else:
        k = next(i for i, s in enumerate(lines) if s.startswith("Number of points"))
        lines[k] = f"Number of points\t{count}"
        flags, said = (("--step", 1) if fixture == "lims" else ()), f"'Number of points {count}' (line {k + 1})"
    p = _write(tmp_path, f"{fixture}.txt", lines)
    refused(p, *flags, tmp_path=tmp_path, words=(said, "a truncated or edited export", "--accept point-count"))
    done, _ = fit_reads(p, *flags, "--accept", "point-count", tmp_path=tmp_path)
    assert isinstance(done, Loaded)


def test_a_creep_compliance_that_decreases_is_refused(tmp_path, read_only):
    t = np.logspace(-1, 2, 12)
    p = tmp_path / "relaxation.csv"
    p.write_text("time_s,creep_compliance_per_Pa\n" + "".join(f"{a},{1e-3 * a ** -0.2}\n" for a in t))
    refused(p, tmp_path=tmp_path, words=("the creep compliance decreases with time", "--accept decreasing"))
    # noisy but rising, like a measured cell (HL60 in the optical stretcher): read
    noisy = tmp_path / "noisy.csv"
    J = 1e-3 * t ** 0.3 * np.exp(np.random.default_rng(1).normal(0, 0.2, t.size))
    noisy.write_text("time_s,creep_compliance_per_Pa\n" + "".join(f"{a},{b}\n" for a, b in zip(t, J)))
    assert isinstance(fit_reads(noisy, tmp_path=tmp_path)[0], Loaded)


def test_a_value_decades_from_its_column_is_refused_naming_its_line(tmp_path, read_only):
    """2e25 Pa among 250-600 Pa (issue 28: it was fitted, rms 4.47 decades)."""
    f = [0.1, 0.3, 1, 3, 10, 30, 100]
    G = [250, 300, 350, 2e25, 450, 520, 600]
    p = tmp_path / "sweep.csv"
    p.write_text("frequency_Hz,G_storage_Pa,G_loss_Pa\n" + "".join(f"{a},{b},{b / 5}\n" for a, b in zip(f, G)))
    err = refused(p, tmp_path=tmp_path, words=("line 5", "column 'G_storage_Pa'", "2e+25 Pa", "--accept outliers"))
    assert "decades" in err
    done, _ = fit_reads(p, "--accept", "outliers", tmp_path=tmp_path)
    assert isinstance(done, Loaded) and done.datasets[0].provenance.accepted[0].startswith("outliers: ")


def test_a_wide_real_sweep_is_not_an_outlier():
    """The check allows what a passive material can do between neighbours (G' up to f², G'' up to f) plus 3 decades:
    a Maxwell fluid's terminal region (G' ∝ f² over 4 decades) is read."""
    f = np.logspace(-3, 3, 25)
    w, tau, G0 = 2 * np.pi * f, 1.0, 1e3
    Gs, Gl = G0 * (w * tau) ** 2 / (1 + (w * tau) ** 2), G0 * w * tau / (1 + (w * tau) ** 2)
    from tenscell.io.checks import check_measurement

    assert check_measurement(RheologyData(f, Gs, Gl)) == ()
    bad = Gs.copy()
    bad[12] *= 1e4  # four decades off at one frequency: no material does that between neighbours
    with pytest.raises(DataError, match="point 12: column \"G'\""):
        check_measurement(RheologyData(f, bad, Gl))


def test_a_file_that_looks_like_trios_says_so(tmp_path, read_only):
    lines = _lines(LIMS)
    first = next(k for k, s in enumerate(lines) if s.strip() == "[Step]")
    p = _write(tmp_path, "header_only.txt", lines[:first])
    refused(p, tmp_path=tmp_path, words=("looks like a TA TRIOS export (line 2", "no 'Variables' row"))
    q = _write(tmp_path, "rc.txt", ["Project:\tx", "", "Interval and data points:\t1\t3", "Test Type:\tOscillation"])
    refused(q, tmp_path=tmp_path, words=("looks like an Anton Paar RheoCompass export", "'Interval data:'"))


def test_steps_that_share_a_name_are_chosen_by_number(tmp_path, read_only):
    lines = _lines(LIMS)
    names = [k for k, s in enumerate(lines) if s.startswith("Step name")]
    lines[names[2]] = lines[names[1]]  # two steps named 'Frequency sweep (25.0 °C)'
    p = _write(tmp_path, "twins.txt", lines)
    name = lines[names[1]].split("\t")[1]
    refused(p, "--step", name, tmp_path=tmp_path, words=("2 steps are named", "(2, 3)", "--step 2"))
    done, _ = fit_reads(p, "--step", 3, tmp_path=tmp_path)
    assert isinstance(done, Loaded) and done.datasets[0].provenance.step == 3
    assert read_trios(p, 3).provenance.step_name == name


def test_semicolon_files_are_read(tmp_path, read_only):
    """tenscell's own CSV and a RheoCompass export written with semicolons (issue 28: unknown column
    'frequency_Hz;G_storage_Pa;G_loss_Pa', and 'the columns are ' with an empty list)."""
    own = tmp_path / "own.csv"
    rows = [(round(10 ** (k / 10 - 1), 4), round(100 + 3.25 * k, 2), round(10 + 0.75 * k, 2)) for k in range(40)]
    own.write_text("frequency_Hz;G_storage_Pa;G_loss_Pa\n" + "".join(f"{a};{b};{c}\n".replace(".", ",")
                                                                     for a, b, c in rows))
    done, _ = fit_reads(own, tmp_path=tmp_path)
    assert isinstance(done, Loaded)
    np.testing.assert_array_equal(done.datasets[0].G_storage, [r[1] for r in rows])
    rc = _write(tmp_path, "rc_semicolons.txt", [s.replace("\t", ";") for s in _lines(RHEOCOMPASS)])
    semi, tab = read_data(rc, step=2), read_data(RHEOCOMPASS, step=2)
    np.testing.assert_array_equal(semi.G_storage, tab.G_storage)
    np.testing.assert_array_equal(semi.frequency_hz, tab.frequency_hz)


@needs_shared
def test_the_plain_trios_layout_reads_everywhere(tmp_path, read_only):
    """Variables/Data point rows without a [step] line (rheojax's fixture): read_data, read_trios and the CLI."""
    p = SHARED / "instrument-exports" / "tests_fixtures_trios_frequency_sweep.csv"
    a, b = read_data(p), read_trios(p)
    np.testing.assert_array_equal(a.G_storage, b.G_storage)
    lines = _lines(p)
    rows = [list(map(float, s.split("\t")[1:4])) for s in lines if s.startswith("Data point")]
    np.testing.assert_allclose(np.sort(a.frequency_hz), np.sort([r[0] / (2 * math.pi) for r in rows]), rtol=1e-15)
    np.testing.assert_array_equal(np.sort(a.G_storage), np.sort([r[1] for r in rows]))
    assert a.provenance.layout == "TA TRIOS export" and a.provenance.points == 5
    done, err = fit_reads(p, tmp_path=tmp_path)
    assert isinstance(done, Loaded) and "frequency 'Angular Frequency' rad/s → Hz" in done.lines[0]


# ---- what was read is recorded -------------------------------------------------------------------------------
def test_the_provenance_names_file_step_temperature_and_conversions(tmp_path, capsys):
    d = read_data(LIMS, temperature=25)
    p = d.provenance
    assert (p.layout, p.step, p.steps, p.step_name) == ("TA TRIOS LIMS export", 2, 3, "Frequency sweep (25.0 °C)")
    assert abs(p.temperature_c - 25) < 0.1 and p.points == d.n
    assert "G' MPa → Pa" in p.conversions() and "frequency rad/s → Hz" in p.conversions()
    doc = json.loads(json.dumps(dict(p)))  # plain JSON data for fit.json
    assert doc["step"] == 2 and doc["text"] == p.line() and doc["columns"][0]["to"] == "Hz"
    assert "\n" not in p.line() and "step 2 of 3 'Frequency sweep (25.0 °C)'" in p.line()
    # it survives what the fit does to the data: a stated prestress, binning, pickling to a worker
    import pickle

    moved = pickle.loads(pickle.dumps(d.with_prestress(1000.0)))
    assert moved.provenance.step == 2 and moved.provenance.notes[-1] == "prestress stated: 1000 Pa"
    # the command prints it, once every check has passed, before the fit
    import os

    os.environ.pop("TENSCELL_PROGRESS", None)
    assert main(["fit", str(LIMS), "--temperature", "25", "--tendons", "uniform", "--starts", "1",
                 "--baseline-starts", "1", "--out", str(tmp_path / "o")]) in (0, 1)
    err = capsys.readouterr().err
    assert err.splitlines()[0] == f"tenscell: {p.line()}"


# ---- creep binned in log time ---------------------------------------------------------------------------------
def _dense_creep(n=7000, sd=False):
    t = 0.2 + 0.1 * np.arange(n)  # sampled evenly in time, as a rheometer logs a creep test
    J = 1e-5 * t ** 0.25 * np.exp(np.random.default_rng(0).normal(0, 0.02, n))
    return CreepData(time_s=t, compliance=J, compliance_sd=0.02 * J if sd else None, source="dense")


def test_creep_is_binned_in_log_time_with_its_weights_stated():
    d = _dense_creep()
    b = d.binned(100)
    assert b.n <= 100 and np.all(np.diff(np.log10(b.time_s)) > 0)
    assert d.time_s.min() <= b.time_s.min() and b.time_s.max() <= d.time_s.max()
    # each interval of log t has the same say (a bin weighs as one point), and the rule says so
    np.testing.assert_array_equal(b.weights, np.ones(b.n))
    assert not b.has_sd and b.counts is None
    from tenscell.io.thinning import binning_rule

    rule = binning_rule(b)
    assert rule.startswith("binned from 7,000 to") and "log10-t" in rule and "weighs as one point" in rule
    assert b.provenance.notes[-1] == rule
    # the power law survives: the local log-log slope of the binned curve is the data's 0.25
    slope = np.polyfit(np.log10(b.time_s), np.log10(b.compliance), 1)[0]
    assert abs(slope - 0.25) < 0.01


def test_creep_binning_with_counts_keeps_the_raw_objective():
    """weighting='counts' (or stated SDs): the objective equals the raw points' up to their within-bin scatter."""
    for d in (_dense_creep(), _dense_creep(sd=True)):
        b = d.binned(100, weighting="counts")

        def objective(data, A, a):
            return float(np.sum(((np.log10(data.compliance) - np.log10(A * data.time_s ** a)) * data.weights) ** 2))

        diffs = [objective(d, A, a) - objective(b, A, a) for A, a in ((1e-5, 0.25), (1.2e-5, 0.2), (0.8e-5, 0.3))]
        assert np.ptp(diffs) < 0.02 * objective(d, 0.8e-5, 0.3)


def test_the_fit_bins_creep_as_the_command_says(tmp_path, read_only):
    p = tmp_path / "dense_creep.csv"
    d = _dense_creep(3000)
    p.write_text("time_s,creep_compliance_per_Pa\n" + "".join(f"{a},{b}\n" for a, b in zip(d.time_s, d.compliance)))
    done, _ = fit_reads(p, "--max-points", 50, tmp_path=tmp_path)
    assert isinstance(done, Loaded) and done.datasets[0].n <= 50
    assert any("binned to" in line and "in log time" in line for line in done.lines)


# ---- every file of ../shared/data through `tenscell fit` -----------------------------------------------------
#: what a walker answers when a file's message asks for a flag (the file's units, from its PROVENANCE.md)
ANSWERS = {
    "creep_ps145_data.csv": {"--units time": "s", "--units compliance": "1/Pa"},  # seconds and 1/Pa (rheojax)
    "examples_data_oscillation_foods_oscillation_chia_data.csv": {"--units modulus": "Pa"},
    "frequency_sweep_tts.txt": {"--temperature": "30"},
}
#: a sweep of fewer points than the per-tendon fit's 37 parameters: the message asks for fewer parameters
FEWER = {"--tendons": "uniform"}
#: files tenscell fit refuses in one line, and why (a phrase of the message)
REFUSED = {
    "battistella2022_oocyte_afm_stress_relaxation.csv": "are not a layout tenscell recognises",  # force, not J
    "battistella2022_oocyte_afm_stress_relaxation_meta.csv": "are not a layout tenscell recognises",  # metadata
    "ggf_hl60_optical_stretcher_creep.csv": "not a number: an empty field",  # frames before the step have no J
    "xie2024_afm_single_cells_long.csv": "names 60 cells or samples",  # 105 cells: fit-population
    "xie2024_afm_single_cells_wide.csv": "are not a layout tenscell recognises",  # one row per cell
}


def _shared_files() -> list[Path]:
    if not SHARED.is_dir():
        return []
    files = sorted(p for p in (SHARED / "instrument-exports").iterdir() if p.suffix != ".md")
    files += sorted((SHARED / "real-cells").glob("*.csv"))
    files += sorted((SHARED / "real-cells" / "xie2024_population").glob("*/cell_*.csv"))
    return files


def _asked(err: str) -> set[str]:
    """The flags a message asks for: '--units modulus', '--temperature', '--tendons' (fewer parameters)..."""
    return (set(re.findall(r"(--units \w+)=UNIT", err)) | ({"--temperature"} if "--temperature C" in err else set())
            | ({"--tendons"} if "fewer parameters: --tendons uniform" in err else set()))


@needs_shared
def test_every_shared_file_loads_with_the_flags_its_message_asks_for_or_is_refused(tmp_path, read_only):
    files = _shared_files()
    assert len(files) >= 119  # 6 exports, 8 measured-cell tables, 105 cells
    loaded, refusals = [], []
    for path in files:
        result, err = fit_reads(path, tmp_path=tmp_path)
        if isinstance(result, Loaded):
            loaded.append(path.name)
            continue
        assert result == 2 and err.count("\n") == 1 and path.name in err and "Traceback" not in err, (path, err)
        if path.name in REFUSED:
            assert REFUSED[path.name] in err, (path, err)
            refusals.append(path.name)
            continue
        flags: list[str] = []
        while not isinstance(result, Loaded):  # answer what each message asks, and only that
            asked = _asked(err)
            answers = {**ANSWERS.get(path.name, {}), **FEWER}
            assert result == 2 and asked and asked <= set(answers), (path.name, asked, err)
            for flag in sorted(asked):
                name, _, quantity = flag.partition(" ")
                flags += [name, f"{quantity}={answers[flag]}" if quantity else answers[flag]]
            assert len(flags) <= 8, (path.name, flags)
            result, err = fit_reads(path, *flags, tmp_path=tmp_path)
        again = result
        assert isinstance(again, Loaded), (path, flags, err)
        loaded.append(path.name)
    assert set(refusals) == set(REFUSED) and len(loaded) == len(files) - len(REFUSED)


@needs_shared
def test_the_measured_files_read_right():
    """Spot checks against the files themselves: units converted, steps chosen, nothing dropped silently."""
    ie = SHARED / "instrument-exports"
    tts = read_data(ie / "frequency_sweep_tts.txt", temperature=30)
    assert tts.provenance.step_name == "Frequency sweep (30.0 °C)" and tts.n == 17
    assert 1e4 < tts.G_storage.min() < tts.G_storage.max() < 1e10  # MPa in the file, Pa here: a polymer
    with pytest.raises(DataError, match=r"line 538: column 'Loss modulus': G'' -29.8684 must be > 0"):
        read_data(ie / "frequency_sweep_tts.txt", temperature=-40)  # step 20 holds one negative G''
    creep = read_data(ie / "creep_ps145_data.csv", time_unit="s", compliance_unit="1/Pa")
    assert creep.n == 7199 and isinstance(creep, CreepData)
    chia = read_data(ie / "examples_data_oscillation_foods_oscillation_chia_data.csv", modulus_unit="Pa")
    assert chia.frequency_hz.max() == pytest.approx(100 / (2 * math.pi))  # Angular Frequency: rad/s
    cell = read_data(SHARED / "real-cells" / "xie2024_population" / "MCF-10A" / "cell_01.csv")
    assert cell.n == 6 and cell.provenance.layout == "tenscell CSV"


def test_read_data_takes_a_bundled_name_as_the_command_line_does():
    """``read_data("bundled:fabry2001")`` is the bundled set itself (the CLI's spelling works in Python too); the
    options that say how to read a file are refused in one line naming the option."""
    from tenscell.io.data import bundled
    from tenscell.io.readers import read_data

    got, want = read_data("bundled:Fabry2001"), bundled("fabry2001")
    np.testing.assert_array_equal(got.frequency_hz, want.frequency_hz)
    np.testing.assert_array_equal(got.G_storage, want.G_storage)
    assert got.source == want.source
    with pytest.raises(DataError, match="step=1 says how to read a file"):
        read_data("bundled:fabry2001", step=1)
    with pytest.raises(DataError, match="fabry2001, 'stamenovic2002'|names|bundled"):
        read_data("bundled:nosuch")

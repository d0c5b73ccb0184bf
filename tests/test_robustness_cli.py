"""Robustness of the command line, part two: every check before the work, costs announced or refused.

Each refusal runs ``tenscell.cli.main`` in this process and must give exit status 2, one line on stderr
naming what the user typed (the flag, the file, the node), nothing on stdout, and nothing created: no
output set and no ``.partial`` work directory. Where "nothing computed" could hide behind a quick
refusal, the computation itself is replaced by a function that fails the test when called. No test
here bounds a wall-clock time.
"""
from __future__ import annotations

import json
import socket
import threading
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tenscell.cli import main

ROWS = "".join(f"{f},{100 * f ** 0.2},{10 * f ** 0.2}\n" for f in (0.1, 0.3, 1, 3, 10, 30, 100))
MODULI = "frequency_Hz,G_storage_Pa,G_loss_Pa\n" + ROWS
CREEP = "time_s,creep_compliance_per_Pa\n" + "".join(f"{t},{1e-3 * t ** 0.2}\n" for t in (0.01, 0.1, 1, 10, 100))


@pytest.fixture
def here(tmp_path, monkeypatch):
    """A working directory with a moduli file, a creep file and a file where a directory is expected."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("TENSCELL_PROGRESS", raising=False)
    (tmp_path / "m.csv").write_text(MODULI)
    (tmp_path / "creep.csv").write_text(CREEP)
    (tmp_path / "afile").write_text("not a directory\n")
    return tmp_path


def _created(root: Path) -> list[str]:
    """What a refused command must not leave: output sets (a manifest) and work directories."""
    return sorted(str(p.relative_to(root)) for p in root.rglob("*")
                  if p.name == "manifest.json" or p.name.endswith(".partial") or p.name.startswith("o"))


def refused(argv, capsys, root: Path, *words: str) -> str:
    """Exit 2, one line naming ``words``, nothing on stdout, nothing created under ``root``."""
    before = _created(root)
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert code == 2, (argv, code, err)
    assert out == "", (argv, out)
    assert err.count("\n") == 1 and err.endswith("\n"), (argv, err)
    assert "Traceback" not in err, err
    for w in words:
        assert w in err, (argv, w, err)
    assert _created(root) == before, (argv, "created", set(_created(root)) - set(before))
    return err


# ---- output locations ---------------------------------------------------------------------------
@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux /proc")
@pytest.mark.parametrize("argv", [
    ["fit", "m.csv", "--out", "/proc/x"],
    ["show", "paper", "--save", "/proc/x.json", "--out", "o"],
    ["synth-population", "--cells", "2", "--out", "/proc/x"],
    ["fit-population", ".", "--out", "o", "--work-dir", "/proc/w"],
])
def test_an_output_location_that_cannot_be_created_is_refused_first(argv, capsys, here):
    """/proc passes a permission check as root; only an actual mkdir tells (it failed after the fit)."""
    flag = next(a for a in argv if a.startswith("/proc"))
    err = refused(argv, capsys, here, flag)
    assert "staging" not in err


@pytest.mark.parametrize("argv, words", [
    (["show", "paper", "--out", ""], ["--out", "empty"]),
    (["fit", "m.csv", "--out", " "], ["--out", "empty"]),
    (["show", "paper", "--save", ""], ["--save", "empty"]),
    (["fit-population", ".", "--out", "o", "--work-dir", ""], ["--work-dir", "empty"]),
    (["fit-population", ".", "--out", "o", "--work-dir", "afile"], ["--work-dir afile", "not a directory"]),
    (["fit-population", ".", "--out", "afile/o"], ["--out", "afile", "not a directory"]),
])
def test_output_flags_name_what_was_typed(argv, words, capsys, here):
    refused(argv, capsys, here, *words)


def test_the_default_work_directory_is_named_when_it_is_a_file(capsys, here):
    (here / "o.partial").write_text("x")
    refused(["fit-population", ".", "--out", "o"], capsys, here, "o.partial", "beside --out", "not a directory")


# ---- contradictory or meaningless flags ---------------------------------------------------------
@pytest.mark.parametrize("argv, words", [
    (["fit", "m.csv", "--tendons", "uniform", "--max-decades", "2", "--out", "o"], ["--max-decades", "uniform"]),
    (["fit", "m.csv", "--min-prestress-elasticity", "2", "--out", "o"], ["--min-prestress-elasticity", "(0, 1]"]),
    (["fit", "creep.csv", "--holdout", "1:10", "--out", "o"], ["--holdout", "creep.csv"]),
    (["fit", "m.csv", "./m.csv", "--out", "o"], ["m.csv", "twice"]),
    (["fit", "m.csv", "--prestress", "m.csv=1e300", "--out", "o"], ["--prestress", "Pa"]),
    (["fit", "m.csv", "--prestress", "m.csv=1", "--prestress", "m.csv=2", "--out", "o"], ["--prestress", "one"]),
    (["fit", "m.csv", "--bound", "EA=1e-300:1", "--out", "o"], ["--bound", "EA: 1e-300 N"]),
    (["fit", "m.csv", "--bound", "L=1e-3:1e20", "--out", "o"], ["--bound", "L: 1e+20 m"]),
    (["synth-population", "--cells", "1", "--conditions", "a", "b", "c", "--out", "o"], ["--cells 1", "a, b, c"]),
    (["synth-population", "--cells", "4", "--conditions", "a", "a", "--out", "o"], ["--conditions", "a given twice"]),
    (["synth-population", "--cells", "4", "--conditions", "a:Q=2", "--out", "o"], ["--conditions", "a:Q=2"]),
    (["creep", "--window", "10:100", "--out", "o"], ["--window 10:100", "0 of the 61"]),
    (["simulate", "--amplitude", "1,2", "--control", "displacement", "--freq", "1", "--out", "o"],
     ["--control displacement"]),
    (["simulate", "--amplitude", "1", "--freq", "1", "--samples", "8", "--out", "o"], ["--samples"]),
    (["creep", "--velocity-scale", "1", "--out", "o"], ["--velocity-scale", "--beta"]),
    (["study", "no-if", "--starts", "3", "--out", "o"], ["--starts", "compactness"]),
    (["study", "references", "--draws", "3", "--out", "o"], ["--draws", "sensitivity"]),
    (["study", "compactness", "missing.csv", "--out", "o"], ["missing.csv"]),
])
def test_contradictions_are_refused_before_the_work(argv, words, capsys, here):
    """One line each; `study compactness` with a missing file no longer prints its stage line first."""
    refused(argv, capsys, here, *words)


def test_prestress_of_a_file_speaks_in_pa_not_in_the_internal_scale(capsys, here):
    err = refused(["fit", "m.csv", "--prestress", "m.csv=1e300", "--out", "o"], capsys, here)
    assert "bounds['s']" not in err and "1e+300 Pa" in err


# ---- structure files ----------------------------------------------------------------------------
@pytest.fixture
def paper_file(here):
    import tenscell

    cell = tenscell.paper_cell()
    path = here / "paper.json"
    tenscell.io.save_structure(path, cell.structure, EA=1.0, c=1.0, T0=cell.T0)
    return json.loads(path.read_text())


def _write(here, doc, name):
    (here / name).write_text(json.dumps(doc))
    return name


def test_a_tendon_pushing_in_the_stated_self_stress_is_refused(capsys, here, paper_file):
    paper_file["tendons"][3]["T0"] = -0.2
    err = refused(["show", _write(here, paper_file, "neg.json"), "--out", "o"], capsys, here, "neg.json", "tendon 3",
                  "T0 = -0.2")
    assert "flip the signs" not in err


def test_a_self_stress_with_every_sign_flipped_gets_the_sign_hint(capsys, here, paper_file):
    for t in paper_file["tendons"]:
        t["T0"] = -t["T0"]
    refused(["show", _write(here, paper_file, "flip.json"), "--out", "o"], capsys, here, "flip.json", "flip the signs")


def test_a_stated_t0_that_is_not_a_self_stress_is_refused_not_replaced(capsys, here, paper_file):
    """Before, show searched for another self-stress silently and drew that structure."""
    paper_file["tendons"][0]["T0"] = 5.0
    refused(["show", _write(here, paper_file, "off.json"), "--out", "o"], capsys, here, "off.json",
            "not a self-stress", "omit T0")


def test_an_absurd_coordinate_names_file_and_node(capsys, here, paper_file):
    node = paper_file["nodes"][4]
    node["xyz"][0] = 1e308
    err = refused(["show", _write(here, paper_file, "far.json"), "--out", "o"], capsys, here, "far.json", "node 4",
                  repr(node["name"]))
    assert "infs or NaNs" not in err


def test_an_absurd_stiffness_in_a_structure_file_names_the_tendon(capsys, here, paper_file):
    paper_file["tendons"][2]["EA"] = 1e300
    refused(["show", _write(here, paper_file, "stiff.json"), "--out", "o"], capsys, here, "stiff.json", "tendon 2",
            "EA")


@pytest.mark.parametrize("flags, words", [(["--L", "2"], ["--L 2", "built-in"]),
                                          (["--size", "2x2"], ["--size", "built-in"])])
def test_built_in_options_with_a_file_are_refused(flags, words, capsys, here, paper_file):
    """They were ignored: the file gives its own geometry."""
    refused(["show", _write(here, paper_file, "p.json"), *flags, "--out", "o"], capsys, here, *words)


def test_a_struts_compression_in_t0_is_allowed():
    """Elastic struts (family "strut") may carry negative T0: only tendons are checked."""
    from tenscell.io.structure_files import _check_tensions
    from tenscell.model.structure import StructureError

    _check_tensions(__import__("numpy").array([1.0, -2.0]), ["actin", "strut"])
    with pytest.raises(StructureError, match="tendon 1"):
        _check_tensions(__import__("numpy").array([1.0, -2.0]), ["actin", "actin"])


# ---- populations: schedulers, truth files, work directories, nothing fitted ---------------------
@pytest.fixture(scope="module")
def population(tmp_path_factory):
    root = tmp_path_factory.mktemp("pop")
    assert main(["synth-population", "--cells", "3", "--out", str(root / "pop"), "--seed", "1"]) == 0
    return root / "pop"


@pytest.fixture
def no_fitting(monkeypatch):
    """Fail the test if the population's fits start."""
    import tenscell.population.run as run

    def forbidden(*a, **k):
        raise AssertionError("fit_population was called: the check came after the work")

    monkeypatch.setattr(run, "fit_population", forbidden)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_an_unreachable_scheduler_is_refused_before_anything_is_created(capsys, here, population, no_fitting):
    address = f"tcp://127.0.0.1:{_free_port()}"
    refused(["fit-population", population, "--out", "o", "--scheduler", address], capsys, here, address)
    refused(["large-study", "monte-carlo", "--draws", "5", "--out", "o", "--scheduler", address], capsys, here,
            address)


@pytest.mark.parametrize("reply", [b"", b"\xff" * 16], ids=["silent", "not Dask"])
def test_a_port_that_does_not_speak_dask_is_refused(reply, capsys, here, population, no_fitting):
    """A proxy or another service accepts the connection: the start of Dask's handshake is what tells."""
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    done = threading.Event()

    def serve():
        conn, _ = server.accept()
        conn.sendall(reply)
        done.wait(10)
        conn.close()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        refused(["fit-population", population, "--out", "o", "--scheduler", f"tcp://127.0.0.1:{port}"], capsys, here,
                f"127.0.0.1:{port}")
    finally:
        done.set()
        thread.join(10)
        server.close()


def test_a_scheduler_file_without_an_address_is_refused(capsys, here, population, no_fitting):
    (here / "sched.json").write_text("{}")
    refused(["fit-population", population, "--out", "o", "--scheduler", "sched.json"], capsys, here, "sched.json",
            "scheduler file")


@pytest.mark.parametrize("content, words", [
    (None, ["--truth t.csv", "no such file"]),
    ("", ["--truth t.csv", "not a CSV"]),
    ("garbage\n1\n", ["--truth t.csv", "'cell'"]),
    ("cell,P_N\nnobody,1\n", ["--truth t.csv", "none of its 1 cells"]),
])
def test_the_truth_file_is_read_and_checked_before_any_fit(content, words, capsys, here, population, no_fitting):
    if content is not None:
        (here / "t.csv").write_text(content)
    refused(["fit-population", population, "--out", "o", "--truth", "t.csv", "--workers", "0"], capsys, here, *words)


FAST = ["--workers", "0", "--starts", "1", "--hops", "0"]


def test_a_leftover_work_directory_is_named_and_kept(capsys, here, population):
    """A killed run (SIGKILL) left OUT.partial/ with its settings only; it may as well belong to a run still under
    way, so a new run is refused naming it (and how to go on) and leaves it as it was."""
    (here / "o.partial" / "cells").mkdir(parents=True)
    (here / "o.partial" / "run.json").write_text("{}")
    refused(["fit-population", population, "--out", "o", *FAST], capsys, here, "o.partial", "--resume")
    assert (here / "o.partial" / "run.json").read_text() == "{}"


def test_a_run_stopped_before_its_first_record_leaves_no_work_directory(capsys, here, population, monkeypatch):
    import tenscell.population.run as run

    def stopped(sources, *, work_dir, **kw):
        Path(work_dir, "cells").mkdir(parents=True)
        Path(work_dir, "run.json").write_text("{}")
        raise KeyboardInterrupt

    monkeypatch.setattr(run, "fit_population", stopped)
    assert main(["fit-population", str(population), "--out", "o", *FAST]) == 130
    assert not (here / "o.partial").exists() and not (here / "o").exists()
    assert "--resume" not in capsys.readouterr().err  # nothing to resume


def test_a_run_stopped_after_its_last_record_says_how_to_resume_and_resumes(capsys, here, population, monkeypatch):
    """Ctrl-C while the results are written (every cell fitted): the --resume line, the records kept; --resume then
    writes the set without fitting a cell again."""
    from tenscell.population.table import PopulationResult

    write = PopulationResult.write

    def interrupted(self, *a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(PopulationResult, "write", interrupted)
    assert main(["fit-population", str(population), "--out", "o", *FAST]) == 130
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "interrupted" in err and "--resume" in err and "o.partial" in err, err
    assert not (here / "o").exists() and len(list((here / "o.partial" / "cells").glob("*.json"))) == 3
    monkeypatch.setattr(PopulationResult, "write", write)
    assert main(["fit-population", str(population), "--out", "o", *FAST, "--resume"]) == 0
    assert "3 cell record(s) came from an interrupted run" in (here / "o" / "report.md").read_text()
    assert not (here / "o.partial").exists()


def test_a_population_in_which_nothing_was_fitted_fails_and_keeps_the_previous_set(capsys, here, population):
    assert main(["fit-population", str(population), "--out", "o", *FAST]) == 0
    before = {p.name: p.read_bytes() for p in (here / "o").iterdir()}
    bad = here / "bad"
    bad.mkdir()
    for k in range(2):  # one point each: every fit fails on its data
        (bad / f"c{k}.csv").write_text("frequency_Hz,G_storage_Pa,G_loss_Pa\n1,1,1\n")
    capsys.readouterr()
    assert main(["fit-population", str(bad), "--out", "o", *FAST]) == 1
    err = "".join(line for line in capsys.readouterr().err.splitlines(True) if not line.startswith("tenscell: "))
    assert err.count("\n") == 1 and "none of the 2 cells was fitted" in err and "c0" in err, err
    assert {p.name: p.read_bytes() for p in (here / "o").iterdir()} == before
    assert not (here / "o.partial").exists()


# ---- cost: announced from a measured rate, refused beyond the machine ---------------------------
def test_a_four_month_monte_carlo_is_refused_up_front(capsys, here):
    """At most ~10^4 draws/s on one worker even on a fast core: 10^9 draws are beyond a day."""
    err = refused(["large-study", "monte-carlo", "--draws", "1000000000", "--workers", "1", "--out", "o"], capsys,
                  here, "--draws", "estimated", "per draw × 1,000,000,000 draws", "24 h")
    assert "measured" in err


def test_a_large_study_announces_its_estimate_first(capsys, here):
    assert main(["large-study", "monte-carlo", "--draws", "8", "--chunk", "4", "--workers", "0", "--out", "o"]) == 0
    lines = capsys.readouterr().err.splitlines()
    assert lines[0].startswith("tenscell: estimated") and "per draw × 8 draws" in lines[0], lines
    assert lines[-1].startswith("tenscell large-study monte-carlo: 8 rows")


def test_a_sweep_study_writes_its_medians(capsys, here):
    """The parts were moved into the output set before medians.csv was computed from them (a traceback)."""
    assert main(["large-study", "sweep", "--prestress", "1,10", "--heterogeneity", "0,0.5", "--realizations", "2",
                 "--freq", "0.1,1,10", "--workers", "0", "--out", "o"]) == 0
    rows = (here / "o" / "medians.csv").read_text().splitlines()
    assert len(rows) == 1 + 2 * 2 * 3
    assert "estimated" in capsys.readouterr().err


def test_simulate_refuses_a_sweep_beyond_a_day_before_simulating(capsys, here, monkeypatch):
    """The rate is replaced by 10 s per cycle (nothing is simulated): 3 simulations (the first amplitude, then the
    sweep of two) × 10,000 cycles are 3.5 days."""
    import tenscell.cli.dynamics as dyn

    monkeypatch.setattr(dyn, "measure", lambda fn, **kw: 10.0)
    refused(["simulate", "--amplitude", "1,2", "--cycles", "10000", "--samples", "64", "--freq", "1", "--out", "o"],
            capsys, here,
            "--amplitude × --cycles", "estimated 3.5 days", "10 s per cycle")


def test_simulate_announces_the_adaptive_range(capsys, here, monkeypatch):
    import tenscell.cli.dynamics as dyn
    from tenscell.cli import _cost

    monkeypatch.setattr(dyn, "measure", lambda fn, **kw: 0.5)
    monkeypatch.setattr(dyn, "check", lambda cost, flag, **kw: (_ for _ in ()).throw(ValueError(cost.line())))
    err = refused(["simulate", "--amplitude", "1,2,5", "--freq", "1", "--out", "o"], capsys, here)
    # 4 simulations (the first amplitude, then the sweep of 3) × 2 to 400 cycles × 0.5 s
    assert f"estimated 4 s to {_cost.duration(4 * 400 * 0.5)}" in err and "2 to 400 adaptive cycles" in err


def test_fit_population_refuses_beyond_a_day(capsys, here, population, monkeypatch, no_fitting):
    import tenscell.cli.population as pop

    monkeypatch.setattr(pop, "measure", lambda fn, **kw: 1e5)  # 1e5 s per cell: 3 cells on one worker
    refused(["fit-population", population, "--out", "o", "--workers", "1"], capsys, here, "INPUT", "estimated",
            "3 cells")


def test_synth_population_refuses_more_memory_than_the_machine(capsys, here, monkeypatch):
    from tenscell.cli import _cost

    monkeypatch.setattr(_cost, "total_memory", lambda: 1e6)
    refused(["synth-population", "--cells", "1000", "--out", "o"], capsys, here, "--cells", "memory")


def test_cost_lines_and_limits(tmp_path, monkeypatch):
    from tenscell.cli import _cost
    from tenscell.cli._cost import BUDGET_S, Cost, check, duration

    assert [duration(s) for s in (12e-3, 3.4, 150.0, 5.1 * 3600, 124 * 86400)] == \
        ["12 ms", "3.4 s", "2.5 min", "5.1 h", "124 days"]
    cost = Cost("draw", 10_000, 0.012, 2)
    assert cost.seconds == pytest.approx(60.0)
    assert cost.line() == "estimated 60 s (measured 12 ms per draw × 10,000 draws / 2 workers)"
    assert check(cost, "--draws") is cost
    with pytest.raises(ValueError, match=r"^--draws: estimated .* more than the 24 h"):
        check(Cost("draw", 10_000, BUDGET_S, 2), "--draws")
    # an external cluster: core time, not refused on time (its size is its own)
    assert "of one core's time" in check(Cost("draw", 10**9, 1.0, None), "--draws").line()
    monkeypatch.setattr(_cost, "total_memory", lambda: 1e9)
    with pytest.raises(ValueError, match="memory"):
        check(Cost("cell", 1, 1.0, memory_bytes=0.9e9), "--cells")
    monkeypatch.setattr(_cost, "_free_bytes", lambda path: 1e6)
    with pytest.raises(ValueError, match="free where"):
        check(Cost("cell", 1, 1.0, disk_bytes=2e6), "--cells", disk_at=tmp_path / "o")


# ---- structure files with extreme values (hypothesis) -------------------------------------------
def _paper_doc():
    import tenscell
    from tenscell.io.structure_files import structure_to_dict

    cell = tenscell.paper_cell()
    return structure_to_dict(cell.structure, EA=1.0, c=1.0, T0=cell.T0)


_extreme = st.one_of(st.floats(allow_nan=False, allow_infinity=False, width=64),
                     st.sampled_from([1e308, -1e308, 1e-308, 5e-324, 1e100, 1e-100, 1e6, 1e7, 0.0, -0.0]))


@pytest.mark.filterwarnings("error::RuntimeWarning")  # an overflow on the way is a value that escaped the checks
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(node=st.integers(0, 9), axis=st.integers(0, 2), xyz=_extreme, tendon=st.integers(0, 32),
       key=st.sampled_from(["EA", "c", "T0"]), value=_extreme)
def test_extreme_values_in_a_structure_file_are_read_and_used_or_refused_naming_the_file(
        tmp_path, node, axis, xyz, tendon, key, value):
    """Every value either passes the reader's checks and gives a finite summary, or is refused by the reader with
    the file named (one line), or the stated T0 is not a self-stress (show refuses that naming the file); a
    value that reached numpy unchecked ("array must not contain infs or NaNs") fails here."""
    import math

    from tenscell.io.structure_files import load_structure_file
    from tenscell.model.equilibrium import NotPrestressableError, equilibrate
    from tenscell.model.structure import StructureError
    from tenscell.summary import summarize

    doc = _paper_doc()
    doc["nodes"][node]["xyz"][axis] = xyz
    doc["tendons"][tendon][key] = value
    path = tmp_path / "x.json"
    path.write_text(json.dumps(doc))
    try:
        sf = load_structure_file(path)
    except StructureError as err:
        assert str(err).startswith("x.json: ") and "\n" not in str(err), err
        return
    try:
        target = equilibrate(sf.structure, "local", T0=sf.T0)
    except NotPrestressableError:
        return  # show refuses it, naming the file (test_a_stated_t0_that_is_not_a_self_stress_...)
    summary, cell, lin = summarize(target, EA=sf.EA, c=sf.c)
    if lin is not None:
        assert all(math.isfinite(v) for v in cell.T0)


def test_a_live_dask_scheduler_passes_the_preflight(tmp_path):
    """The handshake check accepts a real scheduler, by address and by scheduler file (and never waits for it)."""
    distributed = pytest.importorskip("distributed")
    from tenscell.population.scheduler import reach_scheduler

    with distributed.LocalCluster(n_workers=0, protocol="tcp", host="127.0.0.1", dashboard_address=None,
                                  scheduler_port=0) as cluster:
        reach_scheduler(cluster.scheduler_address)
        (tmp_path / "sched.json").write_text(json.dumps({"address": cluster.scheduler_address}))
        reach_scheduler(str(tmp_path / "sched.json"))


def test_creep_with_many_output_times_announces_a_lower_bound(capsys, here, monkeypatch):
    """The rate (replaced here: nothing is timed) is that of the state at one output time, without the integration."""
    import tenscell.cli.dynamics as dyn

    monkeypatch.setattr(dyn, "measure", lambda fn, **kw: 1.0)
    refused(["creep", "--amplitude", "0.1,1", "--points", "50000", "--out", "o"], capsys, here, "--amplitude × --points",
            "estimated 28 h", "100,000 output times", "at least")


# ---- data files after options ---------------------------------------------------------------------
def test_data_files_may_follow_options(capsys, here):
    """`study NAME --flag V DATA`: the files after the options reach the command (argparse alone left them
    unrecognized), which then judges them: here a mechanism that does not exist, named in the one line."""
    err = refused(["study", "mechanisms", "--mechanisms", "nope", "m.csv", "--out", "o"], capsys, here, "nope")
    assert "unrecognized" not in err
    # files on both sides of the options keep the order typed; a stray option is still refused by the parser
    err = refused(["study", "no-if", "--draws", "3", "m.csv"], capsys, here, "takes no data files", "m.csv")
    refused(["study", "mechanisms", "m.csv", "--no-such-flag"], capsys, here, "--no-such-flag")


# ---- checks before work (issue 28): output locations, standard output, where an integration starts ------------
def _chattr(flag: str, path: Path) -> bool:
    import shutil
    import subprocess

    if shutil.which("chattr") is None:
        return False
    return subprocess.run(["chattr", flag, str(path)], capture_output=True).returncode == 0


def test_an_immutable_output_set_is_refused_before_the_work(capsys, here):
    """It was discovered after the whole fit, as a bare '[Errno 1] Operation not permitted'."""
    assert main(["show", "paper", "--out", "o"]) == 0
    capsys.readouterr()
    before = {p.name: p.read_bytes() for p in (here / "o").iterdir()}
    if not _chattr("+i", here / "o"):
        pytest.skip("chattr +i is not available here (needs Linux, a file system with inode flags and the "
                    "CAP_LINUX_IMMUTABLE capability)")
    try:
        code = main(["show", "paper", "--out", "o"])
        out, err = capsys.readouterr()
    finally:
        _chattr("-i", here / "o")
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert "--out o" in err and "immutable" in err and "Errno" not in err
    assert {p.name: p.read_bytes() for p in (here / "o").iterdir()} == before


def test_a_set_that_cannot_be_swapped_in_names_the_flag_and_keeps_the_previous_one(tmp_path, monkeypatch):
    import errno

    from tenscell.io import outputs

    target = tmp_path / "o"
    with outputs.OutputSet(target, command="tenscell x", flag="--out") as d:
        (d / "a.txt").write_text("old")
    monkeypatch.setattr(outputs, "_exchange", lambda a, b: False)

    def refuse(src, dst):
        raise PermissionError(errno.EPERM, "Operation not permitted", str(src))

    monkeypatch.setattr(outputs.os, "rename", refuse)
    expected = r"^--out .*o: the new set could not be put in place \(Operation not permitted\); the previous one"
    with pytest.raises(outputs.OutputLocationError, match=expected), \
            outputs.OutputSet(target, command="tenscell x", flag="--out") as d:
        (d / "a.txt").write_text("new")
    assert (target / "a.txt").read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["o"]  # no staging left


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (Linux)")
@pytest.mark.parametrize("redirect", ["> /dev/full", ">&-", "1</dev/null"], ids=["full", "closed", "read-only"])
def test_a_standard_output_that_cannot_take_the_results_is_refused_first(redirect, tmp_path):
    """`tenscell moduli > /dev/full` showed its progress first and failed at the end."""
    import shlex
    import subprocess
    import sys

    env = {**__import__("os").environ, "TENSCELL_PROGRESS": "1"}
    cmd = f"{shlex.quote(sys.executable)} -m tenscell moduli --freq 0.01:100:200 --prestress 1,2,3 {redirect}"
    run = subprocess.run(cmd, shell=True, capture_output=False, stderr=subprocess.PIPE, text=True, env=env,
                         cwd=tmp_path, timeout=120)
    assert run.returncode == 2, run.stderr
    assert run.stderr.count("\n") == 1 and "standard output" in run.stderr and "Errno" not in run.stderr, run.stderr


def test_a_load_the_integration_cannot_start_is_refused_from_its_first_state():
    """check_start evaluates the state the integration starts from: its refusal is what the integration would meet
    at once, and the amplitude it offers starts."""
    import re

    import tenscell as tc
    from tenscell.dynamics import SimulationError, SineForce, StepForce, creep_response, oscillatory_response
    from tenscell.dynamics.checks import check_start
    from tenscell.laws import voigt_law

    cell = tc.paper_cell()
    law = voigt_law(cell, P=1000.0, EA=1.0, c=1.0)
    for load, run in ((SineForce(1e9, 1.0), lambda: oscillatory_response(cell, law, 1e9, 1.0, cycles=2)),
                      (StepForce(1e9), lambda: creep_response(cell, law, 1e9, [1e-3, 1e-2]))):
        with pytest.raises(SimulationError) as refusal:
            check_start(cell, law, load)
        with pytest.raises(SimulationError, match="singular"):
            run()  # the integration meets it too, at its first step
        limit = float(re.search(r"starts up to about ([0-9.e+]+) N", str(refusal.value)).group(1))
        check_start(cell, law, type(load)(limit, 1.0) if isinstance(load, SineForce) else StepForce(limit))
        with pytest.raises(SimulationError):
            check_start(cell, law, type(load)(1.5 * limit, 1.0) if isinstance(load, SineForce) else
                        StepForce(1.5 * limit))
    check_start(cell, law, SineForce(1.0, 1.0), slack="error")  # a small load passes untouched

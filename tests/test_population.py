"""Populations on Dask: determinism, nothing lost (bad files, killed workers, interrupted runs), recovery.

One local cluster of two worker processes serves the module (started once);
fits use a fast setting (4 starts, no basin hopping) on small populations.
Tests wait on events (a worker is busy, a record is written, the workers are
up), never for a fixed time; their bounds (:data:`HANG`) only keep a broken
run from hanging the suite, and no test asserts how long anything took.
"""
from __future__ import annotations

import math
import os
import random
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tenscell.population import (
    PopulationFitOptions, cell_seed, fit_population, read_sources, recovery, synth_population,
)
from tenscell import _parallel
from tenscell.population import _engine
from tenscell.population.run import WorkDirError, fit_cell
from tenscell.population.sources import CellSource, SourceError

FAST = PopulationFitOptions(starts=4, hops=0)
#: seconds after which a wait is a hang, not a slow machine (a loaded machine takes minutes, not hours)
HANG = 600.0
VOLATILE = ["time_s", "source"]  # wall time, and the file path (differs between copies of the data)


def cli(argv) -> int:
    """Exit status of the tenscell command."""
    from tenscell.cli import main

    return main([str(a) for a in argv])


def same_table(a: pd.DataFrame, b: pd.DataFrame) -> None:
    a = a.drop(columns=VOLATILE).sort_values("cell").reset_index(drop=True)
    b = b.drop(columns=VOLATILE).sort_values("cell").reset_index(drop=True)
    pd.testing.assert_frame_equal(a, b, check_exact=True, check_dtype=False)  # a file stores 13 as int


@pytest.fixture(scope="module")
def population():
    return synth_population(10, conditions=["control", "histamine:P=2"], seed=11)


@pytest.fixture(scope="module")
def pop_dir(tmp_path_factory, population):
    d = tmp_path_factory.mktemp("pop")
    population.write(d)
    (d / "control" / "broken.csv").write_text("frequency_Hz,G_storage_Pa\n1,2\n")
    return d


@pytest.fixture(scope="module")
def client():
    with _engine.cluster(workers=2) as c:
        yield c


@pytest.fixture(scope="module")
def serial(pop_dir):
    """The reference: every cell fitted in this process, sources in shuffled order."""
    srcs = list(read_sources(pop_dir))
    random.Random(3).shuffle(srcs)
    return fit_population(srcs, options=FAST, seed=7, workers=0, progress=False)


# ---- synthetic populations ---------------------------------------------------------------------
def test_synthetic_tensegrity_cells_are_the_model(population):
    """Noise-free synthetic data equal the linear model at the recorded generating parameters."""
    import tenscell

    pop = synth_population(3, noise=0.0, seed=2)
    cell = tenscell.paper_cell()
    fams = np.asarray(cell.structure.families)
    for c, row in zip(pop.cells, pop.parameters.itertuples(index=False)):
        EA = np.where(fams == "actin", row.EA_actin_N, row.EA_intermediate_filament_N)
        Gs, Gl = tenscell.moduli(tenscell.linearize(cell, P=row.P_N, EA=EA, c=row.c_Ns_per_m), c.data.frequency_hz)
        assert np.allclose(c.data.G_storage, Gs, rtol=1e-12)
        assert np.allclose(c.data.G_loss, Gl, rtol=1e-12)
    # conditions scale the medians; cells alternate between conditions; ids carry the condition
    t = population.parameters
    assert list(t["condition"][:4]) == ["control", "histamine", "control", "histamine"]
    assert all(cid.startswith(cond + "/") for cid, cond in zip(t["cell"], t["condition"]))
    assert population.medians["P"] == synth_population(2, seed=11).medians["P"]


def test_synthetic_powerlaw_slope_and_validation():
    pop = synth_population(4, model="powerlaw", noise=0.0, seed=1)
    t = pop.parameters
    assert np.allclose(t["storage_slope"], t["x"] - 1, atol=1e-6)  # G' of the law has slope x − 1 exactly
    with pytest.raises(ValueError, match="condition"):
        synth_population(4, conditions=["a:Q=2"])
    with pytest.raises(ValueError, match="cells"):
        synth_population(0)


# ---- sources -----------------------------------------------------------------------------------
def test_sources_directory_glob_and_long_table(tmp_path, pop_dir, population):
    srcs = read_sources(pop_dir)
    ids = [s.cell for s in srcs]
    assert "control/broken" in ids and len(ids) == 11 and not any("_generating" in i for i in ids)
    by_id = {s.cell: s for s in srcs}
    first = population.cells[0]
    assert by_id[first.cell].condition == "control"
    assert np.array_equal(by_id[first.cell].load().G_storage, first.data.G_storage)

    globbed = read_sources(str(pop_dir / "*" / "cell-*.csv"))  # conditions: the directories under the fixed part
    assert [(s.cell, s.condition) for s in globbed] == sorted((c.cell, c.condition) for c in population.cells)
    flat = read_sources(str(pop_dir / "histamine" / "*.csv"))
    assert len(flat) == 5 and all(s.condition == "" and s.cell.startswith("cell-") for s in flat)

    rows = []
    for c in population.cells[:4]:
        for f, gs, gl in zip(c.data.frequency_hz, c.data.G_storage, c.data.G_loss):
            rows.append({"cell": c.cell, "condition": c.condition, "frequency_Hz": f, "G_storage_Pa": gs,
                         "G_loss_Pa": gl})
    long = pd.DataFrame(rows)
    for path in (tmp_path / "long.csv", tmp_path / "long.parquet"):
        long.to_csv(path, index=False) if path.suffix == ".csv" else long.to_parquet(path)
        tab = read_sources(path)
        assert [s.cell for s in tab] == [c.cell for c in population.cells[:4]]
        assert [s.condition for s in tab] == [c.condition for c in population.cells[:4]]
        for s, c in zip(tab, population.cells[:4]):
            assert np.array_equal(s.load().G_loss, c.data.G_loss)

    with pytest.raises(SourceError, match="no such"):
        read_sources(tmp_path / "missing")
    with pytest.raises(SourceError, match="no cells"):
        read_sources(str(tmp_path / "*.nothing"))


def test_cell_seed_is_stable_and_distinct():
    # SHA-256, not Python's salted hash: the same in every process
    code = "from tenscell.population import cell_seed; print(cell_seed(7, 'control/cell-0001'))"
    other = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert int(other.stdout) == cell_seed(7, "control/cell-0001")
    assert len({cell_seed(s, c) for s in (0, 1) for c in ("a", "b", "c")}) == 6


# ---- the per-cell fit --------------------------------------------------------------------------
def test_fit_cell_derivatives_against_finite_differences(population):
    """The table's ∂lnG'/∂lnP and ∂lnG'/∂lnf (analytic, sum rule over c) match central differences."""
    import tenscell
    from tenscell.population.run import _summarize

    data = population.cells[0].data
    res = tenscell.fit(data, seed=1, progress=False, **FAST.fit_kwargs(tenscell.paper_cell()))
    s = _summarize(res, data)
    f0, h = s["f_ref_Hz"], 1e-4
    P = res.prestress_model()[0]

    def Gp(P_, f_):
        return tenscell.moduli(res.model.linear(P_N=P_), [f_])[0][0]

    e_P = (math.log(Gp(P * math.exp(h), f0)) - math.log(Gp(P * math.exp(-h), f0))) / (2 * h)
    slope = (math.log(Gp(P, f0 * math.exp(h))) - math.log(Gp(P, f0 * math.exp(-h)))) / (2 * h)
    assert s["prestress_elasticity_storage"] == pytest.approx(e_P, abs=1e-6)
    assert s["storage_slope"] == pytest.approx(slope, abs=1e-6)
    assert s["G_storage_ref_Pa"] == pytest.approx(res.moduli([f0])[0][0], rel=1e-12)


def test_fit_cell_records_errors_and_prestress_sweeps():
    from tenscell.io.data import bundled

    bad = fit_cell(CellSource("x", "", "x.csv", text="frequency_Hz,G_storage_Pa,G_loss_Pa\n1,-2,3\n"), 1, FAST)
    assert bad["status"] == "data_error" and "x.csv, line 2" in bad["error"] and "negative" in bad["error"]
    few = fit_cell(CellSource("y", "", "y.csv", text="frequency_Hz,G_storage_Pa,G_loss_Pa\n1,2,3\n2,3,4\n"), 1, FAST)
    one = fit_cell(CellSource("w", "", "w.csv", text="frequency_Hz,G_storage_Pa,G_loss_Pa\n1,2,3\n"), 1, FAST)
    assert one["status"] == "data_error" and "one frequency" in one["error"]  # not a sweep (tenscell.io.checks)
    assert few["status"] == "fit_error" and "fewer than" in few["error"]
    sweep = fit_cell(CellSource("z", "", "stamenovic", data=bundled("stamenovic2002")), 1, FAST)
    assert sweep["status"] == "ok" and sweep["kind"] == "prestress" and sweep["prestress_ref_Pa"] > 0
    assert "s" in sweep["parameters"]


# ---- runs: determinism, failures, resume, killed workers, external scheduler ---------------------
def test_cluster_run_survives_a_killed_worker_and_equals_serial_run(serial, pop_dir, client):
    """2 workers, one SIGKILLed while it fits: Dask reruns its task; the table is complete and equals the
    in-process run of the shuffled sources; a malformed file is recorded with its error."""
    pids = client.run(os.getpid)
    box = {}
    run = threading.Thread(target=lambda: box.update(r=fit_population(pop_dir, options=FAST, seed=7, client=client,
                                                                        progress=False)))
    run.start()
    deadline = time.monotonic() + HANG
    victim = None
    while victim is None and time.monotonic() < deadline:
        busy = [w for w, tasks in client.processing().items() if tasks]
        victim = busy[0] if busy else None
        time.sleep(0.02)
    assert victim is not None, "no task started"
    os.kill(pids[victim], signal.SIGKILL)
    run.join(timeout=HANG)
    assert not run.is_alive()
    par = box["r"]
    same_table(serial.table, par.table)
    assert list(par.table["cell"]) == [s.cell for s in read_sources(pop_dir)]  # input order
    t = par.table.set_index("cell")
    assert t.loc["control/broken", "status"] == "data_error"
    assert "missing required column" in t.loc["control/broken", "error"]
    assert (t.drop(index="control/broken")["status"] == "ok").all()
    client.wait_for_workers(2, timeout=HANG)
    assert pids[victim] not in client.run(os.getpid).values()  # the worker really died and was replaced


def test_resume_after_interruption_gives_the_same_table(serial, pop_dir, client, tmp_path):
    work = tmp_path / "work"
    srcs = read_sources(pop_dir)
    # an interrupted run: only the first cells got their records
    first = fit_population(list(srcs[:4]), options=FAST, seed=7, workers=0, work_dir=work, progress=False)
    assert len([p for p in (work / "cells").glob("*.json") if not p.name.startswith(".")]) == 4
    assert first.n_resumed == 0
    with pytest.raises(WorkDirError, match="resume"):
        fit_population(pop_dir, options=FAST, seed=7, workers=0, work_dir=work)
    with pytest.raises(WorkDirError, match="seed"):
        fit_population(pop_dir, options=FAST, seed=8, workers=0, work_dir=work, resume=True)
    resumed = fit_population(pop_dir, options=FAST, seed=7, client=client, work_dir=work, resume=True,
                             progress=False)
    assert resumed.n_resumed == 4
    same_table(serial.table, resumed.table)


def test_external_scheduler_on_loopback(serial, population, tmp_path):
    """`dask scheduler` + `dask worker` started separately (127.0.0.1 only), used by the CLI's --scheduler."""
    small = tmp_path / "pop"
    small.mkdir()
    for c in population.cells[:3]:
        from tenscell.io.data import write_csv
        (small / c.cell).parent.mkdir(exist_ok=True)
        write_csv(c.data, small / f"{c.cell}.csv")
    dask = str(Path(sys.executable).with_name("dask"))
    sched_file = tmp_path / "scheduler.json"
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    procs = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                               "--scheduler-file", str(sched_file)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        deadline = time.monotonic() + HANG
        # the scheduler creates its file first and fills it after: wait for the address, not the file
        while time.monotonic() < deadline and not (sched_file.is_file() and '"address"' in sched_file.read_text()):
            time.sleep(0.1)
        assert '"tcp://127.0.0.1:' in sched_file.read_text()
        procs.append(subprocess.Popen([dask, "worker", "--scheduler-file", str(sched_file), "--nthreads", "1",
                                       "--host", "127.0.0.1", "--no-dashboard", "--no-nanny"], env=env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        out = tmp_path / "fits"
        code = cli(["fit-population", str(small), "--out", str(out), "--scheduler", str(sched_file),
                     "--starts", str(FAST.starts), "--hops", str(FAST.hops), "--seed", "7"])
        assert code == 0
        ref = serial.table[serial.table["cell"].isin([c.cell for c in population.cells[:3]])]
        same_table(ref, pd.read_parquet(out / "population.parquet"))
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=60)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


# ---- recovery, outputs, CLI --------------------------------------------------------------------
def test_recovery_of_the_generating_distribution(serial, population):
    """Fitted medians per condition recover the generating medians; the histamine condition doubles P."""
    rec = recovery(serial.table, population.parameters).set_index(["condition", "quantity"])
    err = rec["median_error"]
    for cond in ("control", "histamine"):
        for q, tol in (("c_Ns_per_m", 0.02), ("G_storage_ref_Pa", 0.02), ("G_loss_ref_Pa", 0.02),
                       ("P_N", 0.15), ("EA_actin_N", 0.15), ("EA_intermediate_filament_N", 0.5)):
            assert abs(err[(cond, q)]) < tol, (cond, q, err[(cond, q)])
        assert abs(err[(cond, "storage_slope")]) < 0.01
    t = serial.table[serial.table["status"] == "ok"]
    ratio = t.groupby("condition")["P_N"].median()
    gen = population.parameters.groupby("condition")["P_N"].median()
    assert math.log10(ratio["histamine"] / ratio["control"]) == pytest.approx(
        math.log10(gen["histamine"] / gen["control"]), abs=0.2)


def test_cli_synth_fit_resume_and_outputs(tmp_path, monkeypatch):
    from tenscell.population.table import read_table

    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    pop, fits = tmp_path / "pop", tmp_path / "fits"
    assert cli(["synth-population", "--cells", "6", "--out", pop, "--seed", "2", "--conditions", "a", "b:c=2"]) == 0
    assert (pop / "_generating_parameters.csv").is_file() and (pop / "manifest.json").is_file()
    # Ctrl-C during a run (a separate process): exit 130, no output set, the finished records kept
    work = Path(str(fits) + ".partial")
    fast = ["--workers", "0", "--starts", str(FAST.starts), "--hops", str(FAST.hops)]
    proc = subprocess.Popen([sys.executable, "-m", "tenscell", "fit-population", str(pop), "--out", str(fits), *fast],
                            stderr=subprocess.PIPE, text=True)
    def records():  # finished records (not atomic_path's temporary .*.json files)
        return [p for p in work.glob("cells/*.json") if not p.name.startswith(".")]

    deadline = time.monotonic() + HANG
    while not records() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=HANG)
    assert proc.returncode == 130 and "--resume" in err
    assert not fits.exists()
    n_done = len(records())
    assert 1 <= n_done < 6
    assert cli(["fit-population", pop, "--out", fits, *fast]) == 2  # a leftover run is not overwritten
    assert cli(["fit-population", pop, "--out", fits, *fast, "--resume"]) == 0
    assert not work.exists()
    names = set(os.listdir(fits))
    assert {"population.csv", "population.parquet", "summary.csv", "cells.jsonl", "report.md", "parameters.png",
            "moduli.png", "recovery.csv", "manifest.json", "report.html"} <= names
    page = (fits / "report.html").read_text(encoding="utf-8")  # the report's text with both figures, inline
    assert page.count('src="data:image/png;base64,') == 2 and "interrupted run" in page
    csv, pq = read_table(fits / "population.csv"), read_table(fits / "population.parquet")
    pd.testing.assert_frame_equal(csv, pq, check_dtype=False)
    assert len(pq) == 6 and f"{n_done} cell record(s) came from an interrupted run" in (fits / "report.md").read_text()
    rec = pd.read_csv(fits / "recovery.csv").set_index(["condition", "quantity"])["median_error"]
    assert abs(rec[("a", "c_Ns_per_m")]) < 0.02 and abs(rec[("b", "c_Ns_per_m")]) < 0.02  # the condition's c ×2
    assert set(pq["condition"]) == {"a", "b"}
    # bad input: one line, exit 2, nothing computed
    assert cli(["fit-population", str(tmp_path / "none"), "--out", str(tmp_path / "o2")]) == 2
    assert cli(["fit-population", str(pop), "--out", str(tmp_path / "o3"), "--scheduler", "nowhere"]) == 2
    assert not (tmp_path / "o2").exists() and not (tmp_path / "o3").exists()


def test_import_tenscell_does_not_import_dask():
    code = ("import sys, tenscell, tenscell.population; tenscell.population.synth_population; "
            "print(any(m.split('.')[0] in ('dask', 'distributed', 'pyarrow') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


# ---- large studies ------------------------------------------------------------------------------
def test_monte_carlo_draws_is_the_monte_carlo_loop():
    """The per-draw pure function gives monte_carlo's numbers for monte_carlo's own factors."""
    from tenscell.sensitivity import monte_carlo, monte_carlo_draws

    mc = monte_carlo(6, seed=3, progress=False)
    cs, cl, reasons = monte_carlo_draws(mc.factors)
    assert np.array_equal(cs, mc.change_storage, equal_nan=True) and np.array_equal(cl, mc.change_loss, equal_nan=True)
    assert tuple(reasons) == mc.reasons


def test_monte_carlo_study_streams_resumes_and_is_deterministic(tmp_path, client):
    from tenscell.population.studies import monte_carlo_study, read_study
    from tenscell.sensitivity import monte_carlo_draws

    f = np.logspace(-1, 2, 7)
    kw = dict(spread=0.1, parameters="material", f_hz=f, chunk=5, seed=4, progress=False)
    a = monte_carlo_study(20, tmp_path / "a", workers=0, **kw)
    assert a.n_parts == 4 and a.n_rows == 20
    df = read_study(tmp_path / "a")
    assert list(df["draw"]) == list(range(20))
    factors = df[[c for c in df.columns if c.startswith("factor_")]].to_numpy()
    cs, _, _ = monte_carlo_draws(factors, parameters="material", f_hz=f)
    assert np.array_equal(cs, df["change_storage"].to_numpy(), equal_nan=True)
    # an interrupted study (two parts lost) resumed on the cluster: the same rows
    for p in sorted((tmp_path / "a" / "parts").glob("*.parquet"))[1:3]:
        p.unlink()
    b = monte_carlo_study(20, tmp_path / "a", client=client, resume=True, **kw)
    assert b.n_resumed == 2
    pd.testing.assert_frame_equal(df, read_study(tmp_path / "a"))
    assert b.summary == a.summary
    with pytest.raises(ValueError, match="different settings"):
        monte_carlo_study(20, tmp_path / "a", workers=0, resume=True, **{**kw, "seed": 5})


def test_sweep_study_homogeneous_rows_are_the_model(tmp_path):
    import tenscell
    from tenscell.population.studies import sweep_study

    f = np.logspace(-1, 1, 3)
    r = sweep_study([10.0, 100.0], [0.0, 1.0], tmp_path / "s", f_hz=f, realizations=3, workers=0, progress=False)
    df = r.to_dataframe()
    assert len(df) == r.n_rows == 2 * 2 * 3 * 3
    hom = df[(df["heterogeneity_decades"] == 0) & (df["prestress_N"] == 10.0)]
    Gs, Gl = tenscell.moduli(tenscell.linearize(tenscell.paper_cell(), P=10.0, EA=1.0, c=1.0), f)
    for _, g in hom.groupby("realization"):
        assert np.allclose(g["G_storage_Pa"], Gs, rtol=1e-12) and np.allclose(g["G_loss_Pa"], Gl, rtol=1e-12)
    het = df[df["heterogeneity_decades"] == 1.0].groupby("realization")["G_storage_Pa"].first()
    assert het.nunique() == 3  # heterogeneous realizations differ
    med = r.medians()
    assert len(med) == 2 * 2 * 3 and (med["G_storage_Pa_q25"] <= med["G_storage_Pa_q75"]).all()


def test_cli_large_study(tmp_path, monkeypatch):
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    out = tmp_path / "mc"
    assert cli(["large-study", "monte-carlo", "--draws", "6", "--chunk", "3", "--parameters", "material",
                 "--out", str(out), "--workers", "0"]) == 0
    assert {"parts", "study.json", "summary.json", "report.md", "manifest.json"} <= set(os.listdir(out))
    assert len(os.listdir(out / "parts")) == 2 and not Path(str(out) + ".partial").exists()
    assert "6 draws" in (out / "report.md").read_text()
    assert cli(["large-study", "sweep", "--prestress", "1,10", "--heterogeneity", "0,-1", "--out",
                 str(tmp_path / "sw")]) == 2


def test_scheduler_address_forms(tmp_path):
    f = tmp_path / "scheduler.json"
    f.write_text("{}")
    assert _engine.check_scheduler("tcp://127.0.0.1:8786") == "tcp://127.0.0.1:8786"
    assert _engine.check_scheduler("127.0.0.1:8786") == "127.0.0.1:8786"
    assert _engine.check_scheduler(str(f)) == str(f)
    for bad in ("", "nowhere", "tcp://host:port", str(tmp_path / "missing.json")):
        with pytest.raises(ValueError, match="--scheduler"):
            _engine.check_scheduler(bad)


# ---- the engine: where tasks run, batching ----------------------------------------------------------
def _use(cpus: int, busy: float) -> "_parallel.CpuUse":
    return _parallel.CpuUse(wall_s=1.0, cpu_s=1.0, cpus=cpus, busy_elsewhere=busy, source="test")


def test_a_cluster_only_where_it_pays():
    """No cluster without two free CPUs or for work that would not pay each worker's start-up; a long run on a
    quiet machine gets one worker per free CPU; a cluster chosen is estimated faster by the margin."""
    big = 10**4  # tasks of 1 s: hours of work
    assert _engine.plan(big, 1.0, _use(1, 0.0)).workers == 0  # one CPU
    for cpus in (2, 4, 16):
        assert _engine.plan(big, 1.0, _use(cpus, cpus - 1.0)).workers == 0  # one CPU free: this process has it
        assert _engine.plan(big, 1.0, _use(cpus, float(cpus))).workers == 0  # every CPU busy elsewhere
        assert _engine.plan(big, 1.0, _use(cpus, 0.0)).workers == cpus  # quiet: one worker per CPU
        assert _engine.plan(big, 1.0, _use(cpus, 2.2)).workers <= max(0, round(cpus - 2.2))
    # the workers' start-up must be paid by their share of the work
    least = 2 * _engine.WORK_PER_START * _engine.WORKER_START_CPU_S
    assert _engine.plan(1, 0.99 * least, _use(8, 0.0)).workers == 0
    for tasks, t, cpus, busy in ((200, 0.17, 2, 0.0), (10**5, 0.01, 8, 3.0), (40, 5.0, 4, 1.0)):
        p = _engine.plan(tasks, t, _use(cpus, busy))
        assert p.workers >= 2 and p.cluster_s * (1 + _engine.PAY_MARGIN) <= p.here_s
        assert p.workers * _engine.WORK_PER_START * _engine.WORKER_START_CPU_S <= tasks * t
    # more load elsewhere never asks for more workers
    for cpus in (2, 4, 8):
        n = [_engine.plan(200, 0.5, _use(cpus, b)).workers for b in np.linspace(0, cpus, 17)]
        assert all(a >= b for a, b in zip(n, n[1:])), n


def test_an_ensemble_of_a_thousand_assignments_stays_here_at_any_load():
    # 20 chunks of 50 assignments at 0.14 s CPU each (3 prestresses x 61 frequencies, measured): four run while
    # the engine samples, the other 16 (2.2 s of CPU) never pay a cluster's start-up
    for cpus in (2, 4, 8, 64):
        for busy in np.linspace(0.0, cpus, 9):
            assert _engine.plan(16, 0.14, _use(cpus, float(busy))).workers == 0


def test_plan_says_what_it_measured_and_decided():
    here = _engine.plan(16, 0.14, _use(2, 0.3)).describe()
    assert "16 more tasks of 0.14 s CPU" in here and "0.3 busy" in here and "in this process" in here
    away = _engine.plan(200, 0.17, _use(2, 0.0)).describe()
    assert "cluster of 2 workers" in away and "\n" not in away
    assert "(one CPU)" in _engine.plan(10**4, 1.0, _use(1, 0.0)).describe()
    assert "fewer than 2 CPUs are free" in _engine.plan(10**4, 1.0, _use(4, 2.8)).describe()
    assert "start-up" in _engine.plan(16, 0.14, _use(4, 0.0)).describe()


def test_batch_size():
    """Batches never starve a worker thread and hold about TASK_SECONDS of CPU."""
    for n, t, threads in ((1, 0.2, 2), (199, 0.2, 2), (10**5, 1e-4, 2), (40, 5.0, 8)):
        k = _engine.batch_size(n, t, threads)
        assert 1 <= k and (k == 1 or n // k >= 4 * threads)
    assert _engine.batch_size(10**4, 0.2, 2) == round(_engine.TASK_SECONDS / 0.2)


def test_cpu_window_subtracts_this_process_from_the_busy_time(monkeypatch):
    """Over 1 s on 2 CPUs (200 ticks), 150 busy ticks of which this process's 0.5 s is 50: the others used 1 CPU."""
    ticks = iter([(1000, 5000), (1150, 5200)])
    clock = iter([10.0, 11.0])
    cpu = iter([3.0, 3.5])
    monkeypatch.setattr(_parallel, "_affinity", lambda: {0, 1})
    monkeypatch.setattr(_parallel, "_cpu_ticks", lambda cpus: next(ticks))
    monkeypatch.setattr(_parallel, "_CLK_TCK", 100.0)
    monkeypatch.setattr(_parallel.time, "perf_counter", lambda: next(clock))
    monkeypatch.setattr(_parallel.time, "process_time", lambda: next(cpu))
    use = _parallel.CpuWindow().stop()
    assert (use.source, use.cpus, use.wall_s, use.cpu_s) == ("/proc/stat", 2, 1.0, 0.5)
    assert use.busy_elsewhere == pytest.approx(1.0) and use.free == pytest.approx(1.0)


def test_cpu_window_sees_this_process_and_the_others():
    """This process's own busy loop is not counted as other work; a busy child process is."""
    w = _parallel.CpuWindow()
    t = time.process_time()
    while time.process_time() - t < 0.2:  # 0.2 s of this process's CPU, however long a loaded machine takes
        pass
    mine = w.stop()
    assert mine.cpu_s >= 0.2 and 0.0 <= mine.busy_elsewhere <= mine.cpus
    # others' share and this process's together fill at most every CPU (10 ms ticks: a little rounding)
    assert mine.busy_elsewhere + mine.cpu_s / mine.wall_s <= mine.cpus + 0.25
    if mine.source != "/proc/stat" or mine.cpus < 2:
        pytest.skip("no /proc/stat or one CPU: the load average stands in for the measurement")
    spin = subprocess.Popen([sys.executable, "-c", "import time\nt = time.time()\nwhile time.time() - t < 5: pass"])
    try:
        time.sleep(0.3)  # the child is up and spinning
        w = _parallel.CpuWindow()
        time.sleep(0.5)
        other = w.stop()
    finally:
        spin.kill()
        spin.wait()
    # the spinning child keeps about one CPU busy; whatever else runs on the machine only adds to it
    assert other.busy_elsewhere >= 0.7 and other.cpu_s < 0.05


def test_small_work_runs_here_and_says_so(population):
    """With no workers asked for, two quick cells are fitted in this process, announced in one line."""
    lines = []
    srcs = read_sources(population)[:2]
    r = fit_population(list(srcs), options=FAST, seed=7, progress=False, notify=lines.append)
    assert r.n_workers == 0 and len(lines) == 1 and "in this process" in lines[0] and "\n" not in lines[0]
    ref = fit_population(list(srcs), options=FAST, seed=7, workers=0, progress=False, notify=lines.append)
    same_table(ref.table, r.table)
    assert len(lines) == 1  # workers=0 is the user's choice: nothing to announce


def test_batch_sizes_shrink_toward_the_end():
    """Guided batches: every item once, none above the batch, never growing, and the last tasks small enough that
    no worker thread is left running a full batch alone."""
    for n, batch, threads in ((199, 11, 2), (23, 4, 1), (5, 50, 8), (10**4, 10, 2), (1, 3, 2)):
        sizes = _engine.batch_sizes(n, batch, threads)
        assert sum(sizes) == n and max(sizes) <= batch and min(sizes) >= 1
        assert all(a >= b for a, b in zip(sizes, sizes[1:]))
        left = n - np.cumsum([0, *sizes[:-1]])
        assert all(k <= max(1, -(-int(r) // (2 * threads))) for k, r in zip(sizes, left))
    assert _engine.batch_sizes(199, 11, 2)[:10] == [11] * 10 and _engine.batch_sizes(199, 11, 2)[-1] == 1


def test_batched_stream_yields_every_item_once(client):
    """Items batched into Dask tasks come back once each, with their own tags (any batch size)."""
    items = [(i, (i, 2)) for i in range(23)]
    for batch in (1, 4, 23, 50):
        got = dict(_engine.stream(client, pow, items, batch=batch))
        assert got == {i: i ** 2 for i in range(23)}


# ---- Ctrl-C on Dask commands: one line, no traceback from any process, nothing left running ---------------
def _group(pgid: int) -> list[tuple[int, str, str]]:
    """(pid, state, command line) of the live processes of a process group (zombies excluded)."""
    out = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            stat = (d / "stat").read_text()
            cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        fields = stat.rsplit(")", 1)[1].split()
        if int(fields[2]) == pgid and fields[0] != "Z":
            out.append((int(d.name), fields[0], cmd))
    return out


def _dask_workers(pgid: int) -> int:
    return sum("spawn_main" in cmd for _, _, cmd in _group(pgid))


def _ctrl_c(argv, ready) -> tuple[int, str]:
    """Run ``tenscell ARGV`` in its own process group; once ``ready(pgid)``, SIGINT the whole group.

    That is what a terminal's Ctrl-C does: every process of the foreground group,
    Dask's workers included, gets the signal. Returns (exit status, stderr) once
    no process of the group is left running.
    """
    env = {**os.environ, "TENSCELL_PROGRESS": "0"}
    proc = subprocess.Popen([sys.executable, "-m", "tenscell", *map(str, argv)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, start_new_session=True, env=env)
    deadline = time.monotonic() + HANG
    while proc.poll() is None and not ready(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert proc.poll() is None, "the run ended before it could be interrupted"
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=HANG)
    while _group(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _group(proc.pid), f"left running: {_group(proc.pid)}"
    return proc.returncode, err


def test_workers_never_see_ctrl_c(client):
    """SIGINT sent to the workers themselves changes nothing: they hold it blocked (a worker that took it
    would die with a KeyboardInterrupt traceback and be replaced by its nanny under a new pid)."""
    pids = client.run(os.getpid)
    for pid in pids.values():
        os.kill(pid, signal.SIGINT)
    for address, pid in pids.items():  # a task pinned to each worker still runs there, in the same process
        fut = client.submit(os.getpid, pure=False, workers=[address], allow_other_workers=False)
        assert fut.result(timeout=HANG) == pid
    assert client.run(os.getpid) == pids  # the same workers, none replaced


def _one_interrupt_line(err: str, kept: bool) -> None:
    """stderr: the command's own lines from before the interrupt (its cost estimate), then exactly one line for
    the interrupt (naming --resume when finished results were kept), and nothing from any other process (no
    traceback, no Dask log or warning)."""
    lines = err.splitlines()
    assert lines and "interrupted" in lines[-1] and ("--resume" in lines[-1]) == kept, err
    assert all(line.startswith("tenscell") and "interrupted" not in line for line in lines[:-1]), err
    assert "Traceback" not in err and "8787" not in err, err


@pytest.fixture(scope="module")
def big_population(tmp_path_factory):
    d = tmp_path_factory.mktemp("bigpop") / "pop"
    assert cli(["synth-population", "--cells", "40", "--out", d, "--seed", "5"]) == 0
    return d


@pytest.fixture
def port_8787_taken():
    """Port 8787 (Dask's dashboard default) held by someone else for the test."""
    import socket

    with socket.socket() as s:
        try:
            s.bind(("127.0.0.1", 8787))
            s.listen()
        except OSError:
            pass  # already taken: all the better
        yield


@pytest.mark.parametrize("moment", ["starting", "working"])
def test_ctrl_c_on_fit_population_is_one_line(big_population, tmp_path, port_8787_taken, moment):
    """Ctrl-C to the whole group while the workers start, or while they fit: exit 130, exactly one line on
    stderr (the command's), no traceback from any process, no port warning, nothing left running, the
    finished records kept for --resume."""
    out = tmp_path / "fits"
    records = Path(str(out) + ".partial") / "cells"

    def ready(pgid):
        if moment == "starting":
            return _dask_workers(pgid) >= 1
        return _dask_workers(pgid) >= 2 and any(not p.name.startswith(".") for p in records.glob("*.json"))

    code, err = _ctrl_c(["fit-population", big_population, "--out", out, "--workers", "2",
                         "--starts", FAST.starts, "--hops", FAST.hops], ready)
    assert code == 130
    kept = any(not p.name.startswith(".") for p in records.glob("*.json"))
    _one_interrupt_line(err, kept)
    assert kept or not records.parent.exists()  # a run that finished nothing leaves nothing behind
    assert not out.exists()


def test_ctrl_c_on_large_study_is_one_line(tmp_path, port_8787_taken):
    out = tmp_path / "mc"
    parts = Path(str(out) + ".partial") / "parts"

    def ready(pgid):
        return _dask_workers(pgid) >= 2 and any(parts.glob("part-*.parquet"))

    code, err = _ctrl_c(["large-study", "monte-carlo", "--draws", "300000", "--chunk", "500", "--out", out,
                         "--workers", "2"], ready)
    assert code == 130
    _one_interrupt_line(err, kept=True)


def test_a_population_shows_itself_in_a_notebook(serial):
    # _repr_html_: cells per condition (fitted / converged / failed) and the per-condition medians, escaped
    html = serial._repr_html_()
    t = serial.table
    assert html.startswith('<div class="tenscell-repr">') and f"PopulationResult: {serial.n_cells} cells" in html
    for cond in set(t["condition"]):
        assert f"<td style=\"text-align: left\">{cond or '(none)'}</td>" in html
    assert "interquartile range" in html and "<script" not in html

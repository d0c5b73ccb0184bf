"""One fitting stack: every `tenscell fit` flag works for every model family, every --from-fit consumer takes (or
refuses in one line) every fit.json, and a fit crosses process boundaries safely.

The models here are one of each family: the paper's Voigt cell (homogeneous, for speed), a mechanism with Voigt
tendons, a mechanism with internal dynamics (springpot tendons) and a structure-free formula. The fits are as short
as the search allows (``--starts 1 --tolerance 1``: the first step meets it); what is checked is that each flag
reached the fit, which the output set records.
"""
from __future__ import annotations

import dataclasses
import json
import pickle
import threading
from pathlib import Path

import numpy as np
import pytest

from tenscell.cli import main as cli_main
from tenscell.fitting import fit, get_model
from tenscell.fitting.models.formulas import structural_damping_moduli
from tenscell.io.data import RheologyData, bundled

DATA = Path(__file__).parent / "data"
#: one model of each family, with a parameter name or kind of its own for --bound and --fix
FAMILIES = {
    "voigt-uniform": {"bound": "c=1e-6:1e6", "fix": "L=1"},
    "voigt-compact": {"bound": "EA_actin=1e-6:1e6", "fix": "c_actin=0.5"},
    "springpot+visc": {"bound": "exponent=0.05:0.95", "fix": "eta_cytoplasm=0.1"},
    "structural-damping+newtonian": {"bound": "alpha=0.05:0.95", "fix": "eta=0.2"},
}
QUICK = ["--starts", "1", "--tolerance", "1", "--baseline-starts", "1", "--validate", "no"]


def _custom_table(path: Path) -> Path:
    """A frequency sweep in rad/s and kPa under headers tenscell does not know (needs --columns and --units)."""
    f = np.logspace(-1, 2, 12)
    G = structural_damping_moduli(2 * np.pi * f, 300.0, 1.2, 0.05)
    rows = ["w;Gp;Gpp"] + [f"{2 * np.pi * a:.8g};{b / 1e3:.8g};{c / 1e3:.8g}" for a, b, c in zip(f, G.real, G.imag)]
    path.write_text("\n".join(rows) + "\n")
    return path


def _run(args, capsys):
    code = cli_main(args)
    return code, capsys.readouterr()


@pytest.mark.parametrize("model", FAMILIES)
def test_reading_flags_reach_every_model(tmp_path, capsys, model):
    """--columns, --units (a custom table), --step (a multi-step TRIOS export): read the same for every model."""
    table = _custom_table(tmp_path / "mine.csv")
    out = tmp_path / "a"
    code, cap = _run(["fit", str(table), "--model", model, "--columns", "frequency=w", "--columns", "storage=Gp",
                      "--columns", "loss=Gpp", "--units", "frequency=rad/s", "--units", "modulus=kPa",
                      *QUICK, "--out", str(out)], capsys)
    assert code in (0, 1), cap.err
    doc = json.loads((out / "fit.json").read_text())
    assert doc["model_name"] == model and doc["n_points"] == 12
    f0 = doc["datasets"][0]
    assert f0["n_points"] == 12
    out = tmp_path / "b"
    code, cap = _run(["fit", str(DATA / "trios_lims_temperature_steps.txt"), "--model", model, "--step", "1",
                      *QUICK, "--out", str(out)], capsys)
    assert code in (0, 1), cap.err
    assert json.loads((out / "fit.json").read_text())["n_points"] == 9


@pytest.mark.parametrize("model", FAMILIES)
def test_search_space_flags_reach_every_model(tmp_path, capsys, model):
    """--bound and --fix take each model's own names and kinds; --holdout scores every model on held-out points."""
    out = tmp_path / "fit"
    flags = FAMILIES[model]
    code, cap = _run(["fit", "bundled:fabry2001", "--model", model, "--bound", flags["bound"], "--fix", flags["fix"],
                      "--holdout", "30:1000", *QUICK, "--out", str(out)], capsys)
    assert code in (0, 1), cap.err
    doc = json.loads((out / "fit.json").read_text())
    fixed_name, fixed_value = flags["fix"].split("=")
    par = {p["name"]: p for p in doc["parameters"]}
    assert par[fixed_name]["vary"] is False and par[fixed_name]["value"] == pytest.approx(float(fixed_value))
    key, rng = flags["bound"].split("=")
    lo, hi = (float(x) for x in rng.split(":"))
    bounded = [p for p in doc["parameters"] if p["vary"] and key in (p["name"], _kind(model, p["name"]))]
    assert bounded and all(lo * (1 - 1e-9) <= p["value"] <= hi * (1 + 1e-9) for p in bounded)
    comp = doc["model_comparison"]
    assert comp["holdout_Hz"] == [30.0, 1000.0] and comp["n_holdout_points"] > 0
    assert all(m["holdout_rms_log10_error"] is not None for m in comp["models"])


def _kind(model: str, name: str) -> str:
    pr = get_model(model).problem(bundled("fabry2001"))
    return pr.kinds[pr.names.index(name)]


@pytest.mark.parametrize("model", FAMILIES)
def test_bad_bound_and_fix_are_refused_before_fitting_for_every_model(tmp_path, capsys, model):
    out = tmp_path / "fit"
    for bad, word in ((["--bound", "nosuch=1:2"], "--bound nosuch=1:2"), (["--fix", "nosuch=1"], "--fix nosuch=1")):
        code, cap = _run(["fit", "bundled:fabry2001", "--model", model, *bad, "--out", str(out)], capsys)
        assert code == 2 and word in cap.err and len(cap.err.strip().splitlines()) == 1, cap.err
        assert not out.exists()


def test_ensemble_with_workers_for_a_distributed_mechanism_and_refused_elsewhere(tmp_path, capsys):
    out = tmp_path / "fit"
    code, cap = _run(["fit", "bundled:fabry2001", "--model", "voigt-lognormal-damping", "--ensemble", "6",
                      "--workers", "0", *QUICK, "--out", str(out)], capsys)
    assert code in (0, 1), cap.err
    assert (out / "ensemble.csv").exists() and (out / "ensemble.md").exists()
    for model in FAMILIES:
        code, cap = _run(["fit", "bundled:fabry2001", "--model", model, "--ensemble", "6", "--out",
                          str(tmp_path / "x")], capsys)
        assert code == 2 and "--ensemble" in cap.err and "distribution" in cap.err, cap.err


@pytest.mark.parametrize("model", ["voigt-compact", "structural-damping+newtonian"])
def test_the_result_does_not_depend_on_jobs(model):
    data = bundled("fabry2001")
    a = fit(data, model=model, starts=3, seed=5, jobs=1, hops=2, progress=False)
    b = fit(data, model=model, starts=3, seed=5, jobs=2, hops=2, progress=False)
    np.testing.assert_array_equal(a.theta, b.theta)


# ---- every --from-fit consumer takes every fit.json, or refuses it in one line -----------------------------
@pytest.fixture(scope="module")
def fits(tmp_path_factory):
    root = tmp_path_factory.mktemp("fits")
    out = {}
    for model in FAMILIES:
        target = root / model.replace("+", "_")
        assert cli_main(["fit", "bundled:fabry2001", "--model", model, *QUICK, "--out", str(target)]) in (0, 1)
        out[model] = target / "fit.json"
    return out


#: what each consumer does with each family: "ok", or a word of its one-line refusal
CONSUMERS = {
    "moduli": {"voigt-uniform": "ok", "voigt-compact": "ok", "springpot+visc": "ok",
               "structural-damping+newtonian": "ok"},
    # the fitted Voigt cell's creep and simulation: tests/test_fit_cli.py (the time domain of a stiff fitted cell
    # takes minutes; the Voigt-law mechanism runs the same code path here)
    "creep": {"voigt-compact": "ok", "springpot+visc": "internal dynamics",
              "structural-damping+newtonian": "structure-free"},
    "simulate": {"voigt-compact": "ok", "springpot+visc": "internal dynamics",
                 "structural-damping+newtonian": "structure-free"},
    "show": {"voigt-uniform": "ok", "voigt-compact": "ok", "springpot+visc": "ok",
             "structural-damping+newtonian": "structure-free"},
}
_ARGS = {"moduli": ["--freq", "0.1,10"], "creep": ["--amplitude", "0.1", "--points", "5"],
         "simulate": ["--amplitude", "0.01", "--freq", "1", "--cycles", "2"], "show": []}


@pytest.mark.parametrize("command", CONSUMERS)
@pytest.mark.parametrize("model", FAMILIES)
def test_every_consumer_takes_every_fit(fits, tmp_path, capsys, command, model):
    if model not in CONSUMERS[command]:
        pytest.skip("the fitted Voigt cell in the time domain: tests/test_fit_cli.py")
    out = [] if command == "moduli" else ["--out", str(tmp_path / "o")]
    code, cap = _run([command, "--from-fit", str(fits[model]), *_ARGS[command], *out], capsys)
    expected = CONSUMERS[command][model]
    if expected == "ok":
        assert code == 0, cap.err
    else:
        assert code == 2 and expected in cap.err and len(cap.err.strip().splitlines()) == 1, cap.err
        assert "Traceback" not in cap.err


def test_moduli_from_fit_labels_rows_with_the_data_prestress(tmp_path, capsys):
    """Without --prestress, a fit whose data stated their prestress answers at the data's median (Pa)."""
    out = tmp_path / "fit"
    assert cli_main(["fit", "bundled:stamenovic2002", "--model", "voigt-compact", *QUICK, "--out", str(out)]) in (0, 1)
    capsys.readouterr()
    assert cli_main(["moduli", "--from-fit", str(out / "fit.json"), "--freq", "0.1"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("prestress_Pa,")
    median = float(np.median(bundled("stamenovic2002").prestress))
    assert float(lines[1].split(",")[0]) == pytest.approx(median)


def _damaged(doc: dict, how: str) -> dict:
    doc = json.loads(json.dumps(doc))
    m = doc["model"]
    if how == "schema":
        doc["schema"] = 99
    elif how == "format":
        m["format"] = "someone-else"
    elif how == "missing":
        key = next(iter(m.get("values", {"structure": 0})))
        m.get("values", m).pop(key)
    elif how == "negative":
        if "values" in m:
            m["values"][next(iter(m["values"]))] = -1.0
        else:
            m["P_N" if m.get("P_N") is not None else "s_m2"] = -1.0
    elif how == "exponent":
        m["values"]["alpha"] = 2.0
    return doc


@pytest.mark.parametrize("how,word", [("schema", "schema 99"), ("format", "not a tenscell fitted model"),
                                      ("missing", "missing"), ("negative", "> 0"),
                                      ("exponent", "(0, 1")])
@pytest.mark.parametrize("model", ["voigt-uniform", "springpot+visc", "structural-damping+newtonian"])
def test_damaged_or_foreign_fit_json_is_refused_naming_the_field(fits, tmp_path, capsys, how, word, model):
    if how == "exponent" and model == "voigt-uniform":
        pytest.skip("the Voigt cell has no exponent")
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(_damaged(json.loads(fits[model].read_text()), how)))
    code, cap = _run(["moduli", "--from-fit", str(path), "--freq", "1"], capsys)
    assert code == 2 and word in cap.err and str(path) in cap.err, cap.err
    assert len(cap.err.strip().splitlines()) == 1 and "Traceback" not in cap.err


def test_a_fit_of_another_model_is_refused_where_a_voigt_cell_is_needed(fits, tmp_path, capsys):
    code, cap = _run(["study", "sensitivity", "--from-fit", str(fits["springpot+visc"]), "--out",
                      str(tmp_path / "s")], capsys)
    assert code == 2 and "not a fit of the Voigt cell" in cap.err, cap.err


# ---- a result crosses a process boundary while this process fills its caches --------------------------------
def test_a_result_pickles_its_fields_only_even_while_its_caches_fill():
    """A worker pickles the FitResult (the figure) while this process computes its analyses (the report): the
    pickled state is the dataclass fields, read one by one, never the cache dict being filled (the race of the
    README fit line: `dictionary changed size during iteration`)."""
    data = RheologyData(frequency_hz=np.logspace(-1, 1, 6),
                        G_storage=np.array([100, 120, 150, 190, 240, 300.0]),
                        G_loss=np.array([30, 36, 45, 60, 80, 110.0]), source="synthetic")
    result = fit(data, model="voigt-compact", starts=1, hops=0, progress=False)
    fields = {f.name for f in dataclasses.fields(result)}
    for _ in range(2):  # the race showed within the first two rounds when it was there
        fresh = dataclasses.replace(result)
        done = threading.Event()

        def fill(r=fresh, ev=done):
            _ = r.fits, r.identifiability(), r.derived, r.time_to_tolerance_s
            ev.set()

        worker = threading.Thread(target=fill)
        worker.start()
        while not done.is_set():
            state = pickle.loads(pickle.dumps(fresh)).__dict__
            assert set(state) <= fields | {"derived", "fits", "_identifiability", "time_to_tolerance_s", "prestress"}
        worker.join()
        assert set(fresh.__getstate__()) == fields
        again = pickle.loads(pickle.dumps(fresh))
        np.testing.assert_array_equal(again.theta, fresh.theta)
        assert again.derived.values.keys() == fresh.derived.values.keys()

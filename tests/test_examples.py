"""Gallery examples that read files run as written: the instrument export from tests/data, and the population of
measured cells says why it stops where ../shared/data is absent (a user's clone). The docs build runs them all."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _run(script: Path, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "MPLBACKEND": "Agg", "TENSCELL_PROGRESS": "0"}
    return subprocess.run([sys.executable, str(script)], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=600)


def test_the_population_example_says_why_it_stops_without_the_shared_data(tmp_path):
    clone = tmp_path / "clone" / "examples"  # no ../shared beside this clone
    clone.mkdir(parents=True)
    shutil.copy(EXAMPLES / "plot_population_measured.py", clone)
    run = _run(clone / "plot_population_measured.py", tmp_path)
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith("skipped: ") and "is absent" in run.stdout and "no licence" in run.stdout
    assert len(run.stdout.strip().splitlines()) == 1  # nothing fitted, nothing else printed


def test_the_instrument_example_reads_and_refuses_as_it_says(tmp_path):
    run = _run(EXAMPLES / "plot_instrument_export.py", tmp_path)
    assert run.returncode == 0, run.stderr
    out = run.stdout
    assert out.count("TA TRIOS LIMS export, step") == 4  # three steps read, and fit.json's provenance of the last
    assert "refused:" in out and "one frequency" in out and "accept='one-frequency'" in out
    assert "Anton Paar RheoCompass export, interval 2 of 2" in out

"""The tutorial notebook runs top to bottom (docs/tutorial.ipynb)."""
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

NOTEBOOK = Path(__file__).resolve().parent.parent / "docs" / "tutorial.ipynb"


def test_tutorial_runs_and_shows_short_results(monkeypatch, tmp_path):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    assert not any(c.get("outputs") for c in nb.cells if c.cell_type == "code"), "commit the notebook without outputs"
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    texts = [o["data"]["text/plain"] for c in nb.cells if c.cell_type == "code" for o in c.outputs
             if "text/plain" in o.get("data", {})]
    reprs = [t for t in texts if t.startswith("<") and not t.startswith("<Figure")]
    assert reprs and all(len(t) < 800 for t in reprs), [len(t) for t in reprs]  # no flood of text
    printed = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs)
    assert "converged: True" in printed  # the fit reached its tolerance

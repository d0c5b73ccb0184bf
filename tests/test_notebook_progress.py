"""A default fit in a Jupyter notebook shows progress and never a traceback, with or without ipywidgets.

Run in a real kernel (nbclient + ipykernel): tqdm's notebook bar without ipywidgets used to fail half-built and its
``__del__`` printed ``Exception ignored in: tqdm.__del__ ... 'tqdm_notebook' object has no attribute 'disp'``.
"""
import importlib.util
import os
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

DATA = Path(__file__).parent / "data"
#: makes `import ipywidgets` fail inside the kernel, as on an installation without it
HIDE_WIDGETS = "import sys\nsys.modules['ipywidgets'] = None"


def _run(cells: list[str]) -> list[dict]:
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in cells])
    env = {k: v for k, v in os.environ.items() if k != "TENSCELL_PROGRESS"}  # the default: a person watching
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3", allow_errors=False,
                                     resources={"metadata": {"path": str(DATA)}})
    old = dict(os.environ)
    os.environ.clear()
    os.environ.update(env)
    try:
        client.execute()
    finally:
        os.environ.clear()
        os.environ.update(old)
    return [o for cell in nb.cells for o in cell.get("outputs", [])]


def _text(outputs) -> str:
    parts = []
    for o in outputs:
        parts.append(o.get("text", ""))
        parts.extend(str(v) for v in o.get("data", {}).values())
        parts.extend(o.get("traceback", []))
    return "\n".join(parts)


FIT = ["import tenscell as tc",
       "data = tc.read_data('trios_lims_temperature_steps.txt', temperature=25)\n"
       "r = tc.fit(data, model='voigt-uniform', starts=2)\nprint('rms', r.rms_log10_error)",
       "import gc; gc.collect(); print('done')"]


@pytest.mark.parametrize("widgets", [False, True], ids=["without ipywidgets", "with ipywidgets"])
def test_default_fit_in_a_notebook(widgets):
    if widgets and importlib.util.find_spec("ipywidgets") is None:
        pytest.skip("ipywidgets is not installed here")
    outputs = _run(([] if widgets else [HIDE_WIDGETS]) + FIT)
    text = _text(outputs)
    assert "Traceback" not in text and "Exception ignored" not in text and "Error" not in text, text
    assert "rms" in text and "done" in text
    widget = any("application/vnd.jupyter.widget-view+json" in o.get("data", {}) for o in outputs)
    assert widget == widgets  # the widget bar exactly when ipywidgets imports; the text bar otherwise
    if not widgets:
        assert any(o.get("name") == "stderr" and "fit (voigt-uniform)" in o.get("text", "") for o in outputs)

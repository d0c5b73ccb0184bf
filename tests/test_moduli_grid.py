"""`tenscell moduli` through the grid, and the prestress loop's fast path: the same numbers as the per-model path.

The command computes every (P, f) point with one :func:`tenscell.frequency_response` (one batched eigensolve)
instead of one model per prestress; a loop of :func:`tenscell.linearize` recognises the tendons its cell's
prestress family already serves and skips their validation. Both must change the work only: the numbers are
those of one model at a time, to rounding (the CSV keeps 10 digits).
"""
from __future__ import annotations

import csv
import io
import sys

import numpy as np
import pytest

import tenscell
from tenscell.cli import main

PRESTRESSES = np.linspace(300.0, 4000.0, 12)
FREQ = "0.01:1000:9"


def _csv(capsys, argv):
    code = main(argv)
    out = capsys.readouterr()
    assert code == 0 and out.err == "", out.err
    rows = list(csv.reader(io.StringIO(out.out)))
    assert rows[0] == ["prestress_Pa", "frequency_Hz", "G_storage_Pa", "G_loss_Pa"]
    return np.array(rows[1:], dtype=float)


@pytest.mark.parametrize("extra, cell_of", [
    ([], lambda: tenscell.paper_cell()),
    (["--EA", "2.5", "--c", "0.3", "--delta-deg", "48"], lambda: tenscell.paper_cell(delta=np.radians(48.0))),
    (["--no-if"], lambda: tenscell.paper_cell(intermediate_filaments=False)),  # singular C0: the per-model route
])
def test_moduli_command_gives_the_per_model_numbers(capsys, extra, cell_of):
    data = _csv(capsys, ["moduli", "--prestress", ",".join(f"{p:g}" for p in PRESTRESSES), "--freq", FREQ, *extra])
    f = np.logspace(-2, 3, 9)
    assert data.shape == (PRESTRESSES.size * f.size, 4)
    np.testing.assert_array_equal(data[:, 0], np.repeat([float(f"{p:g}") for p in PRESTRESSES], f.size))
    EA = float(extra[extra.index("--EA") + 1]) if "--EA" in extra else 1.0
    c = float(extra[extra.index("--c") + 1]) if "--c" in extra else 1.0
    cell = cell_of()
    for i, P in enumerate(PRESTRESSES):
        Gp, Gpp = tenscell.moduli(tenscell.linearize(cell, float(f"{P:g}"), EA, c), f)
        rows = data[i * f.size:(i + 1) * f.size]
        # 10 significant digits in the file: the two routes agree to rounding (1e-13) far below that
        np.testing.assert_allclose(rows[:, 2], Gp, rtol=1e-9)
        np.testing.assert_allclose(rows[:, 3], Gpp, rtol=1e-9)


def test_moduli_command_writes_each_value_to_ten_digits(capsys):
    code = main(["moduli", "--prestress", "1234.5", "--freq", "0.5"])
    out = capsys.readouterr().out.splitlines()
    assert code == 0 and len(out) == 2
    Gp, Gpp = tenscell.moduli(tenscell.linearize(tenscell.paper_cell(), 1234.5), [0.5])
    assert out[1] == f"{1234.5:.10g},{0.5:.10g},{Gp[0]:.10g},{Gpp[0]:.10g}"  # one prestress: the same model


def test_prestress_loop_fast_path_is_the_general_path(monkeypatch):
    """A second loop over the same tendons (the kept family recognised, no validation) gives the first loop's
    models: same K0, rest lengths, law, modes and moduli; changed or invalid tendons leave the fast path."""
    cell = tenscell.paper_cell()
    f = np.logspace(-2, 3, 7)
    EA = np.linspace(0.5, 2.0, cell.m)
    first = [tenscell.linearize(cell, P, EA, 0.7) for P in PRESTRESSES]  # the first builds the family
    linearize_module = sys.modules["tenscell.linear.linearize"]  # (the package's name is the function)
    validated = []
    real = linearize_module.positive_array
    monkeypatch.setattr(linearize_module, "positive_array", lambda *a, **k: validated.append(a[0]) or real(*a, **k))
    again = [tenscell.linearize(cell, P, EA.copy(), 0.7) for P in PRESTRESSES]  # equal values: the fast path
    assert validated == []  # recognised, not validated again
    for a, b in zip(first, again):
        assert b.pencil.family is not None and b.pencil.family[0] is a.pencil.family[0]
        for name in ("K0", "C0", "H0", "D0", "l0", "EA", "c"):
            np.testing.assert_array_equal(getattr(b, name), getattr(a, name))
        np.testing.assert_array_equal(b.law.l0, a.law.l0)
        np.testing.assert_array_equal(tenscell.compliance(b, f), tenscell.compliance(a, f))
    # the rest lengths are Eq. 11's: the law gives tensions P·T0 at the reference
    np.testing.assert_allclose(again[3].law.elastic(cell.lengths), again[3].tensions, rtol=1e-12, atol=1e-12)
    bad = EA.copy()
    bad[0] = -1.0
    with pytest.raises(ValueError, match="EA"):
        tenscell.linearize(cell, 1000.0, bad, 0.7)  # different values: validated again, and refused
    with pytest.raises(tenscell.linear.NotPositiveDefiniteError):
        tenscell.linearize(tenscell.paper_cell(delta=np.radians(44.0)), 1000.0)

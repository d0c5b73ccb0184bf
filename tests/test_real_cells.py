"""Reading the measured cells (tenscell.studies.real_cells) from ../shared/data/real-cells.

The data are never in the repository; the tests that read them skip, saying why, where the folder is absent
(a user's clone). A missing folder given explicitly is an error, never a skip.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tenscell.io.creep_data import CreepData
from tenscell.io.data import RheologyData
from tenscell.studies.real_cells import (FACTS, XIE_LINES, RealCellsMissing, hl60_creep, oocyte_relaxation,
                                         real_cells_directory, xie_cells, xie_median)

REAL = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "real-cells"
needs_data = pytest.mark.skipif(not REAL.is_dir(), reason=f"the measured-cell data are not at {REAL} "
                                                           "(they are not shipped: no licence)")


def test_a_missing_folder_is_one_clear_error(tmp_path):
    with pytest.raises(RealCellsMissing, match="does not exist") as err:
        xie_cells("MCF-10A", tmp_path / "nowhere")
    assert str(tmp_path / "nowhere") in str(err.value)
    assert isinstance(err.value, FileNotFoundError)
    with pytest.raises(RealCellsMissing, match="not found"):
        hl60_creep(tmp_path)  # the folder exists, the file does not


def test_a_bad_line_is_refused(tmp_path):
    with pytest.raises(ValueError, match="MCF-10A"):
        xie_median("HeLa", tmp_path)


def test_facts_name_the_biases():
    text = " ".join(t for v in FACTS.values() for t in v)
    for phrase in ("monotonically", "drag correction", "1 Hz", "One HL60 cell", "probe radius", "bootstrap"):
        assert phrase in text


@needs_data
def test_xie_cells_carry_their_measurements():
    counts = {"MCF-10A": 59, "MDA-MB-436": 46}
    for line in XIE_LINES:
        cells = xie_cells(line, REAL)
        assert len(cells) == counts[line]
        assert [c.index for c in cells] == sorted(c.index for c in cells)
        for c in cells:
            assert c.line == line and isinstance(c.data, RheologyData)
            assert 1 <= c.data.n <= 6 and set(c.data.frequency_hz) <= {1.0, 3.0, 10.0, 30.0, 100.0, 200.0}
            assert c.aspect_ratio >= 1.0 and c.area > 0 and c.hertz_modulus_pa > 0


@needs_data
def test_medians_are_the_medians_of_the_complete_cells():
    """The median files are over the cells positive at all 6 frequencies: recompute them from the cell files."""
    for line in XIE_LINES:
        med = xie_median(line, REAL)
        assert med.has_sd and med.n == 6
        full = [c.data for c in xie_cells(line, REAL) if c.data.n == 6]
        Gs = np.median([d.G_storage for d in full], axis=0)
        Gl = np.median([d.G_loss for d in full], axis=0)
        assert np.allclose(Gs, med.G_storage, rtol=1e-4) and np.allclose(Gl, med.G_loss, rtol=1e-4)


@needs_data
def test_hl60_creep_and_oocyte_relaxation():
    c = hl60_creep(REAL)
    assert isinstance(c, CreepData) and c.time_s.size == 48
    o = oocyte_relaxation(REAL)
    assert o.force_n.shape == (15, o.time_s.size) and len(o.curves) == 15
    t, shape = o.shape()
    assert shape[0] == 1.0 and t[0] > 0
    assert shape[-1] < 0.5 and np.all(shape > 0)  # the force relaxes to about a fifth over 28 s


@needs_data
def test_the_default_directory_is_relative_to_the_working_directory(tmp_path, monkeypatch):
    """From a project folder with ../shared/data/real-cells beside it, the default finds the data."""
    (tmp_path / "shared" / "data").mkdir(parents=True)
    (tmp_path / "shared" / "data" / "real-cells").symlink_to(REAL, target_is_directory=True)
    (tmp_path / "project").mkdir()
    monkeypatch.chdir(tmp_path / "project")
    assert real_cells_directory().resolve() == REAL.resolve()
    assert xie_median("MCF-10A").n == 6
    monkeypatch.chdir(tmp_path)
    with pytest.raises(RealCellsMissing, match="does not exist"):
        xie_median("MCF-10A")

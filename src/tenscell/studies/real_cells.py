"""Measured cells: reading the real-cell reference data and the facts a report must state about them.

The files live outside the repository (several state no licence, so they are
never copied into it): by default in ``../shared/data/real-cells`` relative to
the working directory (:data:`DEFAULT_DIRECTORY`), or wherever ``directory``
says. A missing folder or file raises :class:`RealCellsMissing` with one line
that names it — never a silent skip. Its ``PROVENANCE.md`` is the source of
everything stated here.

What is read:

* :func:`xie_cells` — AFM oscillatory spectra of single adherent cells, 1–200 Hz
  (Xie et al., Soft Matter 2024; MCF-10A and MDA-MB-436), one
  :class:`XieCell` per cell with its aspect ratio, spread area and Hertz
  modulus (from each file's header comment);
* :func:`xie_median` — the per-line medians (their sd columns are bootstrap
  standard errors *of the median*, not the cell-to-cell spread);
* :func:`hl60_creep` — optical-stretcher creep J(t) of one HL60 cell (ggf);
* :func:`oocyte_relaxation` — AFM stress relaxation of one oocyte (Battistella
  et al. 2022), force only: :class:`OocyteRelaxation` gives its *shape*.

:data:`FACTS` holds, per data set, what its numbers cannot tell (selection,
instrument, one cell), for every report that uses them.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._errors import TenscellError

if TYPE_CHECKING:
    from ..io.data import RheologyData

__all__ = ["DEFAULT_DIRECTORY", "XIE_LINES", "XIE_FREQUENCIES_HZ", "HL60_POINTS", "FACTS", "RealCellsMissing", "XieCell", "OocyteRelaxation",
           "real_cells_directory", "xie_cells", "xie_median", "hl60_creep", "oocyte_relaxation"]

#: where the real-cell data are looked for by default, relative to the working directory
DEFAULT_DIRECTORY = Path("..") / "shared" / "data" / "real-cells"
#: the cell lines of the Xie et al. 2024 data
XIE_LINES = ("MCF-10A", "MDA-MB-436")
#: the frequencies (Hz) at which every cell of both lines was measured (PROVENANCE.md: 1, 3, 10, 30, 100, 200 Hz);
#: a cell's file holds them all but the points its header says were dropped (G' or G'' <= 0)
XIE_FREQUENCIES_HZ = (1.0, 3.0, 10.0, 30.0, 100.0, 200.0)
#: the points of the HL60 creep file (PROVENANCE.md: 48 points, t = 0.15-4 s)
HL60_POINTS = 48

_POPULATION = "xie2024_population"
_MEDIAN = "xie2024_median_{line}.csv"
_HL60 = "ggf_hl60_creep_tenscell.csv"
_OOCYTE = "battistella2022_oocyte_afm_stress_relaxation.csv"

#: what each data set cannot tell: stated in every report that uses it (from PROVENANCE.md)
FACTS = {
    "xie2024": (
        "Measured: AFM oscillatory indentation at a 1 nN set point, 1-200 Hz, single adherent cells (Xie et al., "
        "Soft Matter 2024); no licence stated, so the data stay outside the repository.",
        "Selection: per cell the authors kept the curve nearest the median Hertz modulus among curves whose G' and "
        "G'' rise monotonically with frequency, so non-monotone cells and curves are absent by construction.",
        "Instrument: the probe geometry and the hydrodynamic-drag correction are not documented; part of the rise of "
        "G'' at 100-200 Hz may be instrumental.",
        "The 1 Hz points are the least reliable (11 rows with G' <= 0 and 22 with G'' <= 0 there; such points are "
        "dropped from the per-cell files).",
        "No prestress is measured for these cells: a model's prestress is fitted, not anchored.",
    ),
    "xie2024_median": (
        "The medians are over the cells whose G' and G'' are positive at all 6 frequencies (57 of 59 MCF-10A, 25 of "
        "46 MDA-MB-436); their sd columns are bootstrap standard errors of the median, not the cell-to-cell spread.",
    ),
    "hl60": (
        "One HL60 cell (a leukaemia line, not an adherent cell), one optical-stretcher step (ggf example data, MIT); "
        "J = strain / GGF with the ggf 0.4.0 (Boyde 2009) optical stress model: the modulus scale depends on it.",
    ),
    "oocyte": (
        "One oocyte (Battistella et al. 2022, Fig. 5d, cell 1; afmformats example data, MIT): AFM force at constant "
        "piezo height over 30 s, 15 curves. The probe radius is not in the files, so the force cannot be turned into "
        "a modulus: only the shape of the relaxation (force over its initial value) can be compared.",
    ),
}


class RealCellsMissing(TenscellError, FileNotFoundError):
    """The real-cell reference data (a folder or one of its files) are not where they were looked for."""


def real_cells_directory(directory=None) -> Path:
    """The real-cell data folder (default :data:`DEFAULT_DIRECTORY`), checked to exist.

    Raises
    ------
    RealCellsMissing
        Naming the folder looked for (resolved) and how to point elsewhere.
    """
    path = Path(DEFAULT_DIRECTORY if directory is None else directory)
    if not path.is_dir():
        raise RealCellsMissing(
            f"real-cell data folder {path} (resolved: {path.resolve()}) does not exist: the measured-cell data are "
            f"not shipped with tenscell (no licence); place the shared reference data there or give its directory")
    return path


def _file(directory, *parts) -> Path:
    path = real_cells_directory(directory).joinpath(*parts)
    if not path.exists():
        raise RealCellsMissing(f"{path}: not found in the real-cell data folder (see its PROVENANCE.md)")
    return path


@dataclass(frozen=True, eq=False, repr=False)
class XieCell:
    """One cell of Xie et al. 2024: its spectrum and what was measured about it.

    Attributes
    ----------
    line : str
        Cell line (``"MCF-10A"`` or ``"MDA-MB-436"``).
    index : int
        The cell's index in the source table.
    data : RheologyData
        G', G'' at 1-200 Hz (non-positive moduli dropped by the extraction).
    aspect_ratio : float
        Elongation of the cell's outline (long / short axis), dimensionless.
    area : float
        Spread area, in the source's unit (undocumented; the values, about 90-300, suggest µm²).
    hertz_modulus_pa : float
        The authors' Hertz-model Young's modulus (Pa) of the same curve.
    """

    line: str
    index: int
    data: RheologyData
    aspect_ratio: float
    area: float
    hertz_modulus_pa: float

    def __repr__(self) -> str:
        return (f"<XieCell {self.line} #{self.index}: {self.data.n} frequencies, aspect ratio {self.aspect_ratio:g}, "
                f"area {self.area:g}, Hertz modulus {self.hertz_modulus_pa:g} Pa>")


_HEADER = re.compile(r"cell_line=(?P<line>\S+)\s+cell_index=(?P<index>\d+)\s+aspect_ratio=(?P<ar>[-+.\deE]+)\s+"
                     r"area=(?P<area>[-+.\deE]+)\s+hertz_E_Pa=(?P<ym>[-+.\deE]+)(?:.*?(?P<dropped>\d+) point\(s\) "
                     r"with G<=0 dropped)?")


def _reference(path: Path, reader):
    """``reader(path)``, a file of the reference data: a refusal says to restore the file (these data are read as
    they are, never "anyway")."""
    from ..io.checks import ACCEPT_HINT
    from ..io.data import DataError

    try:
        return reader(path)
    except DataError as err:
        problem = str(err).split(ACCEPT_HINT, 1)[0]
        raise DataError(f"{problem}; the reference data must be as their PROVENANCE.md says: restore the file") from None


def _xie_cell(path: Path) -> XieCell:
    from ..io.data import DataError, read_csv

    data = _reference(path, read_csv)
    for c in data.comments:
        m = _HEADER.search(c)
        if m:
            _check_frequencies(path, data, int(m["dropped"] or 0))
            return XieCell(line=m["line"], index=int(m["index"]), data=data, aspect_ratio=float(m["ar"]),
                           area=float(m["area"]), hertz_modulus_pa=float(m["ym"]))
    raise DataError(f"{path}: no header comment with cell_line, cell_index, aspect_ratio, area and hertz_E_Pa")


def _check_frequencies(path, data, dropped: int = 0) -> None:
    """DataError unless ``data`` holds the line's frequencies (:data:`XIE_FREQUENCIES_HZ`), each once, but the
    ``dropped`` ones (a file cut short, a row lost or doubled would otherwise be read as a cell's spectrum)."""
    from ..io.data import DataError

    f = [float(x) for x in data.frequency_hz]
    known = [x for x in f if any(abs(x - g) <= 1e-9 * g for g in XIE_FREQUENCIES_HZ)]
    missing = [g for g in XIE_FREQUENCIES_HZ if not any(abs(x - g) <= 1e-9 * g for x in f)]
    if len(known) == len(f) == len(set(f)) and len(missing) == dropped:
        return
    extra = sorted(set(f) - set(known))
    said = f"its header says {dropped} point(s) dropped" if dropped else "its header says none was dropped"
    raise DataError(f"{path}: holds {len(f)} points at {', '.join(f'{x:g}' for x in f)} Hz; the line was measured at "
                    f"{', '.join(f'{g:g}' for g in XIE_FREQUENCIES_HZ)} Hz and {said}"
                    + (f" (missing: {', '.join(f'{g:g}' for g in missing)} Hz)" if missing else "")
                    + (f" (not the line's: {', '.join(f'{x:g}' for x in extra)} Hz)" if extra else "")
                    + ": a file cut short or edited?")


def _line(line: str) -> str:
    if line not in XIE_LINES:
        raise ValueError(f"line must be one of {', '.join(XIE_LINES)}, got {line!r}")
    return line


def xie_cells(line: str, directory=None) -> tuple[XieCell, ...]:
    """Every cell of one line (Xie et al. 2024), in the order of their indices.

    Raises
    ------
    RealCellsMissing
        The folder or the line's subfolder is missing, or holds no cell file.
    DataError
        A cell file without its header comment or with bad values.
    """
    folder = _file(directory, _POPULATION, _line(line))
    files = sorted(folder.glob("cell_*.csv"))
    if not files:
        raise RealCellsMissing(f"{folder}: no cell_NN.csv files")
    cells = sorted((_xie_cell(p) for p in files), key=lambda c: c.index)
    return tuple(cells)


def xie_median(line: str, directory=None):
    """The median spectrum of one line (RheologyData with the bootstrap standard errors of the median as sd)."""
    from ..io.data import read_csv

    path = _file(directory, _MEDIAN.format(line=_line(line)))
    data = _reference(path, read_csv)
    _check_frequencies(path, data)  # the medians are over cells measured at all six frequencies
    return data


def hl60_creep(directory=None):
    """The HL60 optical-stretcher creep curve, 0.15-4 s after the step (CreepData, J in 1/Pa)."""
    from ..io.creep_data import read_creep_csv

    from ..io.data import DataError

    path = _file(directory, _HL60)
    data = _reference(path, read_creep_csv)
    if data.n != HL60_POINTS:
        raise DataError(f"{path}: holds {data.n} points; the file of PROVENANCE.md has {HL60_POINTS} (t = 0.15-4 s): "
                        "a file cut short or edited?")
    return data


@dataclass(frozen=True, eq=False, repr=False)
class OocyteRelaxation:
    """AFM stress relaxation of one oocyte: force at constant piezo height, per curve (shape only).

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Time since the start of the pause (s), the bins common to all curves.
    force_n : ndarray, shape (curves, n)
        Mean force in each time bin (N).
    curves : tuple of str
    source : str
    """

    time_s: np.ndarray
    force_n: np.ndarray
    curves: tuple
    source: str

    def shape(self, t_ref: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(t, F/F(t_ref))``: the median over curves of each curve's force over its force at ``t_ref``.

        ``t_ref`` (s) defaults to the first bin after t = 0 (the force at t = 0 includes the end of the approach);
        the times returned are those at and after it. Only this shape is comparable with a model: the probe radius
        (and so the modulus scale) is unknown.
        """
        t = self.time_s
        i0 = int(np.argmax(t > 0)) if t_ref is None else int(np.argmin(np.abs(t - float(t_ref))))
        ratio = self.force_n[:, i0:] / self.force_n[:, i0:i0 + 1]
        return t[i0:], np.median(ratio, axis=0)

    def __repr__(self) -> str:
        return (f"<OocyteRelaxation: {len(self.curves)} curves, {self.time_s.size} time bins "
                f"{self.time_s[0]:g}-{self.time_s[-1]:g} s; force only (shape)>")


def oocyte_relaxation(directory=None) -> OocyteRelaxation:
    """The oocyte's stress-relaxation curves (Battistella et al. 2022), binned as in the file.

    Raises
    ------
    RealCellsMissing
    DataError
        Curves with different time bins, or non-finite values.
    """
    import pandas as pd

    from ..io.data import DataError

    path = _file(directory, _OOCYTE)
    df = pd.read_csv(path, comment="#")
    need = {"curve", "t_since_pause_start_s", "force_N"}
    if not need <= set(df.columns):
        raise DataError(f"{path}: needs the columns {', '.join(sorted(need))}")
    curves = tuple(dict.fromkeys(df["curve"]))
    groups = [df[df["curve"] == c] for c in curves]
    t = groups[0]["t_since_pause_start_s"].to_numpy(float)
    if any(g.shape[0] != t.size or not np.allclose(g["t_since_pause_start_s"].to_numpy(float), t) for g in groups):
        raise DataError(f"{path}: the curves do not share one set of time bins")
    F = np.array([g["force_N"].to_numpy(float) for g in groups])
    if not (np.all(np.isfinite(F)) and np.all(np.isfinite(t))):
        raise DataError(f"{path}: non-finite time or force")
    return OocyteRelaxation(time_s=t, force_n=F, curves=curves, source=str(path))

"""Data cells do not show, built on the grids, prestresses and noise of data they do show.

A model that fits a data set should be asked whether it would have fitted its
opposite as well: if a mechanism fits a stiffness that does not depend on the
prestress as closely as it fits one that does, its fit to the real trend says
nothing about the trend. This module builds such *unlike* data sets from given
ones, keeping everything but the trend under test:

``"prestress-independent"``
    stiffness independent of prestress. At each frequency, the smooth trend of
    log G' and log G'' against log P (a least-squares quadratic, a line for
    fewer than 4 prestresses) is replaced by its value at the median prestress:
    ``G_unlike = G · Ĝ(P_med)/Ĝ(P)``.
``"exponent-rising"``
    a power-law exponent that rises with prestress (cells show it constant or
    falling: Stamenović et al., J Appl Physiol 96:1600, 2004). With
    ``δ(P) = Δ·(x − ½)``, ``x = log(P/P_min)/log(P_max/P_min)``, every point is
    multiplied by the power law ``(iω/iω_c)^δ = (f/f_c)^δ·e^{iπδ/2}``
    (``f_c`` the geometric mean frequency of the data): the local exponent of G' and
    G'' changes by δ and the phase of G* turns by πδ/2, as for a structural-damping
    law whose exponent changed by δ; at one frequency only the loss tangent changes.
    The exponent's change over the data's prestress range thus grows by ``Δ``
    (default :data:`DEFAULT_EXPONENT_RISE`): data whose exponent falls by 0.03 (the
    bundled Stamenović lines, read through their loss tangent) become data whose
    exponent rises by 0.03.
``"loss-independent-of-prestress"``
    G″ independent of prestress while G′ keeps its trend: at each frequency the
    trend of log G″ against log P is replaced by its value at the median prestress
    (as ``"prestress-independent"`` does for both). A structure whose prestress acts
    through the geometric stiffness P·Kp alone turns that one elastic term into the
    trends of G′ *and* G″ (its modes couple them); data with only G′'s trend ask
    whether it can part them.
``"flat-loss-tangent"``
    the loss tangent G″/G′ independent of prestress, G′ unchanged: at each
    frequency the trend of log(G″/G′) against log P is replaced by its value at
    the median prestress (G″ follows G′). Cells' loss tangent falls as the
    prestress rises (the bundled Stamenović lines: 0.33 → 0.27), and so does a
    power-law exponent read from it; on these lines it does not. Not one of
    :data:`UNLIKE_KINDS` but training lines for the exponent test: a model trained
    on them whose G′ exponent still falls with prestress gets the fall from its
    structure, not from the lines.

Both are smooth multiplicative factors, so each point keeps its own deviation
from the data's trend (the data's noise, if any), its standard deviations
(relative: the sd columns scale with the moduli) and its grid. A data set at a
single prestress (a frequency sweep that states none, or one value) has no
prestress trend to change and is returned as it is; in a joint set, only the
prestress sweeps change. The unlike set's ``source`` says what it is.
"""
from __future__ import annotations

import math

import numpy as np

from .._checks import finite_scalar
from ..io.data import DataError, RheologyData

__all__ = ["UNLIKE_KINDS", "FLAT_LOSS_TANGENT", "DATA_KINDS", "DEFAULT_EXPONENT_RISE", "unlike_data", "unlike_sets",
           "varies_with_prestress"]

#: the kinds of unlike data sets a model is judged on (module docstring)
UNLIKE_KINDS = ("prestress-independent", "exponent-rising", "loss-independent-of-prestress")
#: lines with a flat loss tangent: training lines of the exponent test (module docstring)
FLAT_LOSS_TANGENT = "flat-loss-tangent"
#: every kind :func:`unlike_data` builds
DATA_KINDS = (*UNLIKE_KINDS, FLAT_LOSS_TANGENT)
#: Δ of ``"exponent-rising"``: what is added to the exponent's change over the data's prestress range
#: (dimensionless): twice the fall of the bundled Stamenović lines (loss tangent 0.33 -> 0.27: exponent 0.20 -> 0.17),
#: so that their unlike set rises by as much as they fall
DEFAULT_EXPONENT_RISE = 0.06


def varies_with_prestress(data: RheologyData) -> bool:
    """Whether a data set states more than one prestress (only then has it a prestress trend to change)."""
    return data.prestress is not None and np.unique(data.prestress).size > 1


def _trend(logp: np.ndarray, logg: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The smooth trend of log G against log P (quadratic, or a line below 4 prestresses) evaluated at ``at``."""
    deg = 2 if np.unique(logp).size >= 4 else 1
    coef = np.polyfit(logp, logg, deg)
    return np.polyval(coef, at)


def _flat_factor(data: RheologyData, values: np.ndarray) -> np.ndarray:
    """Per point, the factor that moves each frequency's trend of log ``values`` against log P to its value at the
    median prestress (1 at a frequency with one prestress: nothing to flatten)."""
    assert data.prestress is not None
    logp = np.log(data.prestress)
    p_med = math.log(float(np.median(np.unique(data.prestress))))
    out = np.ones(data.n)
    for f in np.unique(data.frequency_hz):
        sel = data.frequency_hz == f
        if np.unique(logp[sel]).size < 2:
            continue
        lg = np.log(values[sel])
        out[sel] = np.exp(_trend(logp[sel], lg, np.array([p_med]))[0] - _trend(logp[sel], lg, logp[sel]))
    return out


def _flatten(data: RheologyData) -> tuple[np.ndarray, np.ndarray]:
    """``"prestress-independent"``: factors (G', G'') that move each frequency's trend to the median prestress."""
    return _flat_factor(data, data.G_storage), _flat_factor(data, data.G_loss)


def _exponent_rise(data: RheologyData, rise: float) -> tuple[np.ndarray, np.ndarray]:
    """``"exponent-rising"``: factors (G', G'') of ``G* → G*·(f/f_c)^δ(P)·e^{iπδ(P)/2}`` (module docstring)."""
    assert data.prestress is not None
    lp = np.log(data.prestress)
    x = (lp - lp.min()) / (lp.max() - lp.min())
    delta = rise * (x - 0.5)
    f_c = math.exp(float(np.mean(np.log(np.unique(data.frequency_hz)))))
    G = (data.G_storage + 1j * data.G_loss) * (data.frequency_hz / f_c) ** delta * np.exp(0.5j * math.pi * delta)
    if np.any(G.real <= 0) or np.any(G.imag <= 0):
        raise DataError(f"{data.source}: an exponent rise of {rise:g} over the prestress range turns a point's G' or "
                        "G'' negative (its phase leaves 0-90°); ask for a smaller rise")
    return G.real / data.G_storage, G.imag / data.G_loss


def unlike_data(data: RheologyData, kind: str, *, exponent_rise: float = DEFAULT_EXPONENT_RISE) -> RheologyData:
    """An unlike version of one data set (module docstring); a data set at one prestress comes back as it is.

    Parameters
    ----------
    data : RheologyData
    kind : one of :data:`DATA_KINDS`
    exponent_rise : float
        ``Δ`` of ``"exponent-rising"``: added to the exponent's change from the lowest to the highest
        prestress (dimensionless, > 0).

    Returns
    -------
    RheologyData
        Same frequencies, prestresses and relative standard deviations; ``source`` names the kind and the
        original source, and ``comments`` say how it was built.

    Raises
    ------
    ValueError
        An unknown kind or a non-positive rise.
    DataError
        A rise that turns a modulus negative.
    """
    if kind not in DATA_KINDS:
        raise ValueError(f"kind must be one of {', '.join(DATA_KINDS)}, got {kind!r}")
    rise = finite_scalar("exponent_rise", exponent_rise, "a finite number > 0 (dimensionless)")
    if rise <= 0:
        raise ValueError(f"exponent_rise must be > 0 (dimensionless), got {exponent_rise!r}")
    if not varies_with_prestress(data):
        return data
    if kind == "prestress-independent":
        fs, fl = _flatten(data)
        how = ("the trend of log G', log G'' against log P (quadratic fit per frequency) replaced by its value at "
               "the median prestress; each point keeps its deviation from the trend")
    elif kind == "loss-independent-of-prestress":
        fs, fl = np.ones(data.n), _flat_factor(data, data.G_loss)
        how = ("the trend of log G'' against log P (quadratic fit per frequency) replaced by its value at the median "
               "prestress, G' unchanged; each point keeps its deviation from the trend")
    elif kind == FLAT_LOSS_TANGENT:
        fs, fl = np.ones(data.n), _flat_factor(data, data.G_loss / data.G_storage)
        how = ("the trend of the log loss tangent log(G''/G') against log P (quadratic fit per frequency) replaced by "
               "its value at the median prestress, G' unchanged; each point keeps its deviation from the trend")
    else:
        fs, fl = _exponent_rise(data, rise)
        how = (f"every point multiplied by (i f/f_c)^d(P), d rising linearly in log P from {-rise / 2:+g} to "
               f"{rise / 2:+g}: the power-law exponent's change over the prestress range grows by {rise:g}")
    scale = (lambda sd, fac: None if sd is None else sd * fac)  # noqa: E731
    return RheologyData(
        frequency_hz=data.frequency_hz, G_storage=data.G_storage * fs, G_loss=data.G_loss * fl,
        prestress=data.prestress, G_storage_sd=scale(data.G_storage_sd, fs), G_loss_sd=scale(data.G_loss_sd, fl),
        source=f"unlike data ({kind}) built from {data.source}",
        comments=(f"Unlike data ({kind}): not what cells show; built by tenscell.studies.falsification from "
                  f"{data.source}.", how.capitalize() + ".", *data.comments))


def unlike_sets(datasets, kinds=UNLIKE_KINDS, *, exponent_rise: float = DEFAULT_EXPONENT_RISE) -> dict:
    """Every unlike version of a joint set: ``{kind: tuple of RheologyData}`` (only prestress sweeps change).

    Raises
    ------
    ValueError
        If no data set states more than one prestress (there is no prestress trend to change), or an unknown kind.
    """
    from ..fitting.parameters import as_datasets

    ds = as_datasets(datasets)
    if not any(isinstance(d, RheologyData) and varies_with_prestress(d) for d in ds):
        raise ValueError("unlike data need a data set with more than one stated prestress (a prestress sweep): "
                         f"none of {', '.join(d.source for d in ds)} has one")
    return {k: tuple(unlike_data(d, k, exponent_rise=exponent_rise) if isinstance(d, RheologyData) else d
                     for d in ds) for k in kinds}

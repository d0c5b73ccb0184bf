"""The house look, the axes helpers every plot function shares, and :func:`save`.

Nothing here chooses a backend or touches the global ``rcParams``: the style
is applied through :func:`matplotlib.pyplot.rc_context` only while tenscell
creates and fills a figure of its own. When the caller passes ``ax=`` (or
``axes=``) the drawing follows the caller's settings.
"""
from __future__ import annotations

import functools
import inspect
from contextlib import contextmanager, nullcontext
from typing import Any, Callable, Iterable, Iterator, Sequence, TypeVar

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..io.outputs import atomic_path

__all__ = ["STYLE", "style", "styled", "colors", "new_axes", "new_panels", "moduli_panels", "figure_of", "save",
           "png_bytes", "label_moduli", "wrap", "legend_outside", "legend_below"]

#: rcParams applied (as a context, never globally) to figures tenscell creates
STYLE: dict[str, Any] = {
    "font.size": 10,
    "axes.labelsize": 10,
    "axes.titlesize": 10,
    "legend.fontsize": 8,
    "figure.dpi": 150,
    "savefig.dpi": 200,
    "axes.grid": True,
    "grid.alpha": 0.3,
}

F = TypeVar("F", bound=Callable[..., Any])


def style():
    """A context manager applying :data:`STYLE` (``with plotting.style(): ...``)."""
    return plt.rc_context(STYLE)


def styled(func: F) -> F:
    """Run ``func`` inside :func:`style` when it makes its own figure (its ``ax``/``axes`` arguments are None)."""
    sig = inspect.signature(func)
    names = [n for n in ("ax", "axes") if n in sig.parameters]

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        bound = sig.bind_partial(*args, **kwargs).arguments
        given = any(bound.get(n) is not None for n in names)
        with nullcontext() if given else style():
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


def wrap(text: str, width_in: float, fontsize: float = 10.0) -> str:
    """``text`` broken into lines that fit ``width_in`` inches at ``fontsize`` points (a title stays inside its
    figure or panel instead of running past the edge)."""
    import textwrap

    chars = max(12, int(width_in * 72.0 / (0.58 * fontsize)))
    return "\n".join(textwrap.fill(part, chars) for part in str(text).split("\n"))


def legend_outside(ax: Axes, *args: Any, **kw: Any):
    """A legend to the right of ``ax``, outside the data area (constrained layout makes room for it); ``args``
    and ``kw`` as for :meth:`~matplotlib.axes.Axes.legend`."""
    return ax.legend(*args, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, **kw)


def legend_below(axes: Any, ncols: int | None = None):
    """One legend for a figure's panels, below them (constrained layout makes room): every label once, in the order
    the panels first draw it (``axes``: a sequence or array of Axes)."""
    entries: dict[str, Any] = {}
    for a in np.asarray(axes, dtype=object).ravel():
        for handle, label in zip(*a.get_legend_handles_labels()):
            entries.setdefault(label, handle)
    fig = figure_of(axes)
    if ncols is None:  # as many columns as labels of about the mean length fit across the figure
        size = plt.rcParams["legend.fontsize"]
        points = size if isinstance(size, (int, float)) else 8.0
        per = (np.mean([len(k) for k in entries]) if entries else 1.0) * 0.55 * points / 72.0 + 0.6
        ncols = int(min(len(entries), 4, max(1, fig.get_figwidth() // per)))
    cols = max(1, ncols)
    return fig.legend(list(entries.values()), list(entries), loc="outside lower center", ncols=cols,
                      frameon=False)


def colors(n: int) -> np.ndarray:
    """``n`` colours along viridis (dark to yellow-green), shape (n, 4)."""
    return plt.cm.viridis(np.linspace(0.0, 0.9, n))


def new_axes(ax: Axes | None = None, figsize: tuple[float, float] = (5.6, 4.2), projection: str | None = None) -> Any:
    """``ax`` itself, or the axes of a new figure of size ``figsize`` (inches).

    Typed ``Any``: an Axes, or an Axes3D for ``projection="3d"``.
    """
    if ax is not None:
        if projection is not None and getattr(ax, "name", None) != projection:
            raise ValueError(f"ax: this plot needs a {projection!r} axes (add_subplot(projection={projection!r}))")
        return ax
    fig = plt.figure(figsize=figsize, layout="constrained")
    return fig.add_subplot(projection=projection)


def new_panels(axes: Sequence[Axes] | None, n: int, figsize: tuple[float, float], *, title: str | None = None,
               vertical: bool = False, **subplots_kw) -> np.ndarray:
    """``n`` axes as an array: the caller's (checked for count) or a new figure's, titled ``title``."""
    if axes is not None:
        out = np.asarray(axes, dtype=object).ravel()
        if out.size != n:
            raise ValueError(f"axes: this plot draws {n} panel(s), got {out.size} axes")
        return out
    shape = (n, 1) if vertical else (1, n)
    fig, out = plt.subplots(*shape, figsize=figsize, layout="constrained", squeeze=False, **subplots_kw)
    if title:
        fig.suptitle(wrap(title, 0.95 * figsize[0], plt.rcParams["figure.titlesize"] if isinstance(
            plt.rcParams["figure.titlesize"], (int, float)) else 12.0))
    return out.ravel()


def moduli_panels(title: str | None = None, figsize: tuple[float, float] = (8.0, 3.4)) -> tuple[Figure, np.ndarray]:
    """A new figure with two side-by-side axes for G' (left) and G'' (right): ``(fig, axes)``."""
    with style():
        axes = new_panels(None, 2, figsize, title=title)
    return axes[0].figure, axes


def label_moduli(axes: Iterable[Axes], xlabel: str) -> None:
    """Label a G' | G'' pair of axes."""
    for ax, name in zip(axes, ("G′", "G″")):
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"{name} (Pa)")


def figure_of(obj: Any) -> Figure:
    """The figure behind a Figure, an Axes, or an array/sequence of Axes."""
    if isinstance(obj, Figure):
        return obj
    first = np.asarray(obj, dtype=object).ravel()
    if first.size and isinstance(first[0], Axes):
        fig = first[0].figure
        while not isinstance(fig, Figure):  # a subfigure: its figure is the one saved
            fig = fig.figure
        return fig
    raise TypeError(f"save: expected a Figure or Axes, got {type(obj).__name__}")


@contextmanager
def _closing(fig: Any) -> Iterator[Figure]:
    """The figure behind ``fig`` (see :func:`figure_of`), closed when the block ends, whatever happens."""
    figure = figure_of(fig)
    try:
        yield figure
    finally:
        plt.close(figure)


def save(fig: Any, path) -> None:
    """Save a figure atomically (PNG, PDF or SVG by extension) and close it.

    ``fig`` may be a Figure or what a plot function returned (an Axes or an
    array of Axes).
    """
    with _closing(fig) as figure, atomic_path(path) as tmp:
        figure.savefig(tmp, format=str(path).rsplit(".", 1)[-1])


def png_bytes(fig: Any) -> bytes:
    """The figure as PNG bytes (what :func:`save` writes to a ``.png``), and close it.

    For figures drawn in a worker process and written by the main one.
    """
    import io

    buffer = io.BytesIO()
    with _closing(fig) as figure:
        figure.savefig(buffer, format="png")
    return buffer.getvalue()

"""Progress: one convention for terminals, notebooks and logs.

Every long computation in tenscell takes ``progress: bool | None``:

``None`` (the default)
    a bar when someone is watching — a terminal on stderr or a Jupyter
    notebook — and nothing otherwise;
``True``
    always a bar;
``False``
    silent.

The environment variable ``TENSCELL_PROGRESS=0`` silences every bar and
stage line (for batch jobs and test suites); ``TENSCELL_PROGRESS=1`` forces
on the bars left to decide (``None``) — never one a caller turned off: the
searches inside a profile or a held-out refit run without a bar of their own
(each would close as a blank line in a log), under the one bar that says what
is being done.
"""
from __future__ import annotations

import os
import sys
from typing import Any, Iterable

__all__ = ["progress_bar", "stage", "wants_progress", "in_notebook"]


def in_notebook() -> bool:
    """True inside a Jupyter kernel (where stderr is not a terminal but a person is watching)."""
    shell = sys.modules.get("IPython")
    if shell is None:
        return False
    try:
        ip = shell.get_ipython()
    except Exception:  # pragma: no cover - IPython internals
        return False
    return ip is not None and type(ip).__name__ == "ZMQInteractiveShell"


def wants_progress(progress: bool | None) -> bool:
    """Resolve a ``progress`` argument to show-or-not (see the module docstring)."""
    env = os.environ.get("TENSCELL_PROGRESS", "").strip()
    if env == "0" or progress is False:
        return False
    if env == "1" or progress:
        return True
    return in_notebook() or sys.stderr.isatty()


def progress_bar(iterable: Iterable[Any] | None = None, *, total: int | None = None, desc: str = "",
                 unit: str = "it", progress: bool | None = None, leave: bool = False):
    """A tqdm bar (the notebook widget in Jupyter when ipywidgets is installed, text on stderr elsewhere), or a
    silent one.

    Returns a tqdm object in every case, so callers use ``update``, ``close``,
    ``set_postfix`` and iteration the same way whether it shows or not.
    """
    show = wants_progress(progress)
    if show and in_notebook() and _widgets():
        from tqdm.notebook import tqdm as bar
        return bar(iterable, total=total, desc=desc, unit=unit, leave=leave)
    # without ipywidgets (not a dependency) the text bar: tqdm.notebook would fail half-built, and the
    # half-built bar's __del__ printed a traceback into the notebook at every fit
    from tqdm import tqdm as bar
    return bar(iterable, total=total, desc=desc, unit=unit, leave=leave, file=sys.stderr, disable=not show)


def _widgets() -> bool:
    """True when the notebook widget bar can be built: ipywidgets imports (any failure means the text bar)."""
    try:
        import ipywidgets  # noqa: F401
    except Exception:  # ImportError, or a broken or mismatched installation
        return False
    return True


def stage(message: str, *, progress: bool | None = None, stream=None) -> None:
    """Print one stage line (``tenscell: message``) on stderr unless progress is silenced.

    Stage lines are what a log file sees of a long command; on a terminal they
    sit between the bars. ``progress=None`` prints them (a log wants them even
    though no terminal is watching); ``False`` or ``TENSCELL_PROGRESS=0`` does not.
    """
    env = os.environ.get("TENSCELL_PROGRESS", "").strip()
    if progress is False or env == "0":
        return
    print(f"tenscell: {message}", file=stream or sys.stderr, flush=True)

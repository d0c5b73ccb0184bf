"""BLAS threads on tenscell's hot paths, decided in one place.

The matrices of a cell model are small (tens of coordinates) or sparse; their
factorizations, eigensolves and triangular solves gain nothing from several
BLAS threads, and on a shared machine they lose a lot (measured here: complex
sparse solves ran 80–120× slower with several OpenBLAS threads, the fitter's
evaluations about 10×, and a 24×24 triangular solve 8 ms against 46 µs). So
every hot path — linearization and its check, the pencil's own decompositions
(Cholesky, modes, resolvent, solves), compliance and moduli, creep and
relaxation, Lanczos runs, fits, elasticities, identifiability, model
comparison — runs with **one** BLAS thread, and the caller's own setting is
restored on return.

Override it, for instance for dense models of thousands of coordinates on an
idle many-core machine:

* the environment variable ``TENSCELL_THREADS`` (an integer ≥ 1, or ``all``
  to leave the BLAS libraries' own setting untouched), read at each call;
* :func:`set_threads` (``None`` goes back to the environment/default);
* the context manager :func:`threads`, e.g. ``with tenscell._threads.threads(4): ...``.

Hot paths are marked with :func:`hot_path`; nested hot paths set the limit
once (a thread-local depth counter), so the overhead is paid per public call.
"""
from __future__ import annotations

import contextlib
import functools
import os
import sys
import threading

__all__ = ["ENV_VAR", "DEFAULT_THREADS", "thread_count", "set_threads", "threads", "limited", "hot_path"]

ENV_VAR = "TENSCELL_THREADS"
#: BLAS threads on hot paths unless overridden
DEFAULT_THREADS = 1

_local = threading.local()
_override: int | str | None = None
_controller = None


def _parse(value, where: str) -> int | None:
    if value is None:
        return None
    if isinstance(value, str):
        v = value.strip().lower()
        if v in ("all", "auto", "none", ""):
            return None if v else DEFAULT_THREADS
        try:
            value = int(v)
        except ValueError:
            raise ValueError(f"{where} must be a whole number >= 1 or 'all', got {value!r}") from None
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ValueError(f"{where} must be a whole number >= 1 or 'all', got {value!r}")
    return value


def thread_count() -> int | None:
    """BLAS threads the hot paths will use; None means "leave the libraries' setting alone"."""
    if _override is not None:
        return None if isinstance(_override, str) else _override  # "all": leave the libraries alone
    env = os.environ.get(ENV_VAR)
    return DEFAULT_THREADS if env is None else _parse(env, ENV_VAR)


def set_threads(n: int | str | None) -> None:
    """Set the BLAS threads for tenscell's hot paths: an integer ≥ 1, ``"all"`` (no limit) or None (default)."""
    global _override
    _override = None if n is None else ("all" if _parse(n, "threads") is None else _parse(n, "threads"))


@contextlib.contextmanager
def threads(n: int | str | None):
    """Within the block, hot paths use ``n`` BLAS threads (see :func:`set_threads`)."""
    global _override
    before = _override
    set_threads(n)
    try:
        yield
    finally:
        _override = before


def _blas_libraries():
    """threadpoolctl's controllers of the loaded BLAS libraries (looked up once, again if more load later)."""
    global _controller
    # a module imported since the last look may have brought its own BLAS (cvxopt does)
    if _controller is None or _controller[0] != len(sys.modules):
        from threadpoolctl import ThreadpoolController

        libs = [lc for lc in ThreadpoolController().lib_controllers if lc.user_api == "blas"]
        _controller = (len(sys.modules), libs)
    return _controller[1]


class limited:
    """Context manager: run the block with the hot-path thread count (once, however deeply nested).

    Sets each BLAS library's thread count directly (a few C calls) rather
    than through ``threadpool_limits``, which inspects the process at every
    use (about 40 µs, as much as a small model's whole response). A class
    rather than a generator: a loop of small models enters it per call.

    A BLAS library loaded inside the block (scipy brings its own OpenBLAS when
    its linear algebra is first imported) is limited by the next nested entry,
    and every library is restored when the outermost block ends.
    """

    __slots__ = ("_depth",)

    def __enter__(self):
        self._depth = depth = getattr(_local, "depth", 0)
        if depth == 0:
            _local.n, _local.changed, _local.paths, _local.seen = thread_count(), [], set(), None
        if _local.n is not None:
            libs = _blas_libraries()
            if libs is not _local.seen:  # the first entry, or a library loaded since the last look
                _limit(libs, _local.n)
                _local.seen = libs
        _local.depth = depth + 1
        return self

    def __exit__(self, *exc) -> None:
        _local.depth = self._depth
        if self._depth == 0:
            for lc, old in _local.changed:
                lc.set_num_threads(old)
            _local.changed, _local.seen = [], None


def _limit(libs, n: int) -> None:
    """Each library of ``libs`` not yet limited in this block set to ``n`` threads, its setting kept to restore."""
    for lc in libs:
        if lc.filepath in _local.paths:
            continue
        _local.paths.add(lc.filepath)
        old = lc.num_threads
        if old != n:
            lc.set_num_threads(n)
            _local.changed.append((lc, old))


def hot_path(fn):
    """Decorator: run ``fn`` under :func:`limited`."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        if getattr(_local, "depth", 0):
            return fn(*args, **kwargs)
        with limited():
            return fn(*args, **kwargs)

    return wrapper

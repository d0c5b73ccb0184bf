"""A Dask worker plugin: modules every worker imports when it starts (a replacement worker too).

Kept apart from :mod:`._engine` because it subclasses a Dask class, and Dask is
imported only when a cluster is used.
"""
from __future__ import annotations

import importlib

from distributed.diagnostics.plugin import WorkerPlugin

__all__ = ["Imports"]


class Imports(WorkerPlugin):
    """Import ``modules`` in the worker before its first task (so a task's time is its work's)."""

    def __init__(self, modules: tuple[str, ...]):
        self.modules = tuple(modules)

    def setup(self, worker) -> None:
        for name in self.modules:
            importlib.import_module(name)

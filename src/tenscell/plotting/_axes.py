"""The axes a result's ``plot(ax=None)`` draws on."""
from __future__ import annotations

__all__ = ["axes_or_new"]


def axes_or_new(ax=None):
    """``ax``, or the axes of a new figure when None (the current backend decides where it shows)."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(constrained_layout=True)
    return ax

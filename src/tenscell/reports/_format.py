"""Formatting shared by every report: numbers, percentages, Markdown tables."""
from __future__ import annotations

import math
from typing import Iterable, Sequence

__all__ = ["num", "pct", "table"]


def num(x, digits: int = 4) -> str:
    """A number with ``digits`` significant figures; 'n/a' for None or NaN, '∞' for infinities."""
    if x is None:
        return "n/a"
    x = float(x)
    if math.isnan(x):
        return "n/a"
    if math.isinf(x):
        return "∞" if x > 0 else "−∞"
    return f"{x:.{digits}g}"


def pct(x, digits: int = 2) -> str:
    """A fraction as a percentage (0.1234 → '12.34%'); 'n/a' for None or NaN."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    return f"{100.0 * float(x):.{digits}f}%"


def table(header: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    """A Markdown table; cells are str() of the values (format numbers with :func:`num` first)."""
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines) + "\n"

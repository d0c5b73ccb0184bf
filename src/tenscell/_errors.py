"""The base of every error tenscell raises on purpose (a leaf module: anything may import it).

``except tenscell.TenscellError`` catches them all; each class keeps the
built-in base that describes its kind (most are also a ``ValueError``: bad
input or a model that does not exist at these parameters), so code written
against those bases keeps working.

Options named in messages
-------------------------
A message that asks the user to give an option (``give modulus_unit=`` in
Python, ``--units modulus=UNIT`` on the command line) marks it with
:func:`option` instead of spelling it. ``str(err)`` of a :class:`TenscellError`
spells every marked option as the Python keyword; the command line spells the
same message with its flags (:func:`spelled` with a table of flag spellings,
``tenscell.cli._args.FLAG_SPELLING``), in one place. A message built from
another with an f-string (``f"{err}"``) carries the Python spelling.
"""
from __future__ import annotations

from typing import Mapping

__all__ = ["TenscellError", "NotPositiveDefiniteError", "CapabilityError", "option", "spelled", "raw_message"]

# the marks around an option named in a message: start, name/value separator, end (control characters that
# never occur in a file name or a header a message quotes: readers refuse control characters in headers)
_START, _SEP, _END = "\x02", "\x1f", "\x03"


def option(name: str, value: object = None) -> str:
    """An option a message names (``name``, with the value given or asked for), spelled by the interface.

    ``option("modulus_unit")`` reads ``modulus_unit=`` in Python and ``--units modulus=UNIT`` on the command
    line; ``option("modulus_unit", "kPa")`` reads ``modulus_unit='kPa'`` and ``--units modulus=kPa``.
    """
    if value is None:
        return f"{_START}{name}{_SEP}{_SEP}{_END}"
    python = repr(value) if isinstance(value, str) else str(value)
    return f"{_START}{name}{_SEP}{python}{_SEP}{value}{_END}"


def spelled(text: str, flags: Mapping[str, str] | None = None) -> str:
    """``text`` with every :func:`option` mark spelled: as a Python keyword, or by ``flags``.

    ``flags`` maps an option name to its command-line spelling, a template with ``{value}`` (``"--units
    modulus={value}"``) and, after a ``|``, what ``{value}`` reads when the message gives none (``"UNIT"``);
    an option missing from ``flags`` keeps its Python spelling.
    """
    if _START not in text:
        return text
    out, rest = [], text
    while _START in rest:
        head, _, tail = rest.partition(_START)
        body, _, rest = tail.partition(_END)
        name, _, values = body.partition(_SEP)
        python, _, value = values.partition(_SEP)
        template = None if flags is None else flags.get(name)
        if template is None:
            out.append(f"{head}{name}={python}")
        else:
            form, _, default = template.partition("|")
            out.append(head + form.format(value=value or default))
    return "".join(out) + rest


def raw_message(err: BaseException) -> str:
    """The message of ``err`` with its option marks unspelled (for :func:`spelled` with another table)."""
    return Exception.__str__(err)


class TenscellError(Exception):
    """Base class of every error tenscell raises on purpose."""

    def __str__(self) -> str:
        return spelled(Exception.__str__(self))


class CapabilityError(TenscellError, ValueError):
    """A member or an analysis asked of a model that does not have it: the tendons of a structure-free formula, the
    Voigt cell's stiffness layout of a mechanism's fit, the ensemble of a model without a distributed property...

    The one error every such request raises (what a fitted model has is declared by its
    :class:`tenscell.fitting.models.base.Capabilities`); the message names the member, the model and, where there is
    one, what to use instead.
    """


class NotPositiveDefiniteError(TenscellError, ValueError):
    """A matrix that must be positive definite is not: for K0, the reference is not a stable equilibrium.

    Attributes
    ----------
    column : int or None
        Column (of the reordered matrix) at which a sparse Cholesky
        factorization stopped; None for dense matrices.
    """

    def __init__(self, message: str, column: int | None = None):
        super().__init__(message)
        self.column = column

"""Helpers shared by the studies."""
from __future__ import annotations

import numpy as np

from .._checks import positive_array

__all__ = ["grid", "evaluation_probe", "PROBE_EVALUATIONS", "name_list"]

#: evaluations of the residuals' Jacobian one probe makes (the problem is built once per probe)
PROBE_EVALUATIONS = 10


def grid(name, values, unit):
    """A 1-D grid of positive values (``unit`` for the message)."""
    return np.atleast_1d(positive_array(name, values, unit=unit)).ravel()


def name_list(given) -> tuple[str, ...]:
    """Names from a sequence or from the command line's comma list (``"a, b"``), blanks dropped."""
    return tuple(n.strip() for n in (given.split(",") if isinstance(given, str) else given) if n.strip())


def evaluation_probe(spec, data):
    """The calibration probe of a study's fit tasks, whose weights count the model evaluations they are expected to
    take (:mod:`tenscell.studies.protocol`): model ``spec``'s problem on ``data`` built (a fit does it once), and
    the work timed returned — :data:`PROBE_EVALUATIONS` evaluations of its Jacobian at its initial guess, with the
    BLAS threads the search uses."""
    from .._threads import limited
    from ..fitting.entry import prepare

    problem = spec.problem(*prepare(data, None, 100, spec))
    theta = problem.initial_guess(np.random.default_rng(0))

    def evaluations() -> None:
        with limited():
            for _ in range(PROBE_EVALUATIONS):
                problem.jacobian(theta)

    return evaluations

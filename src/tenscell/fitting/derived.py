"""Numbers a fit's report derives from the fitted parameters, each with its standard error.

The report of a fit shows more than the parameters: the model's log-log
slopes, its straight lines against prestress, the prestress elasticities and
share, the predicted creep and its exponent, the spread of the stiffnesses.
Each is a function ``g(θ)`` of the fitted ln-parameters, so each has the
first-order (delta-method) standard error

    se(g)² = ∇gᵀ Σ ∇g,    Σ = σ²·(JᵀJ)⁺,

with Σ the covariance of the analysed ln-parameters that also gives their own
standard errors (:meth:`tenscell.fitting.identifiability.Identifiability.propagate`).
The gradient ``∇g`` is a **forward finite difference** in each analysed
ln-parameter with step :data:`STEP` (every quantity is recomputed at ``θ + h eₖ``
by the same functions the report uses; no second copy of the physics). Forward,
not central: one evaluation per parameter instead of two halves the report's
cost (0.9 s of the fit command for a per-tendon fit), for a relative error of
about ``STEP`` in a standard error printed to two or three digits. A
quantity the data do not determine (its gradient reaches a combination the data
do not see), or whose errors cannot be estimated (σ unknown), has no standard
error and says so ("not determined"). With the strut-length gauge removed L is
held at its fitted value, as for the parameters, and a gauge-dependent quantity
(a prestress in N, a stiffness in N) carries the error of its gauge-invariant
combination (P/L², EA/L²), which its note names.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._results import plus_minus

if TYPE_CHECKING:
    from .result import FitResult

__all__ = ["DerivedQuantities", "derived_quantities", "STEP"]

#: step (ln units: 1e-5 is a 0.001 % change) of the forward differences. The truncation error is about
#: STEP/2 ≈ 5e-6 of the gradient (relative, for quantities whose log is smooth on the scale of a parameter's
#: e-fold), the rounding error about 1e-13/STEP ≈ 1e-8 (the moduli come from eigensolves good to ~1e-13): both
#: far below the two or three digits a standard error is printed with
STEP = 1e-5

#: quantities in N at the fitted L and the gauge-invariant combination whose error they carry
_GAUGE_NOTES = {"reference_prestress_N": "(of P/L²)", "creep_prestress_N": "(of P/L²)",
                "stiffness_spread": "(of EA/L²)"}


@dataclass(frozen=True, eq=False, repr=False)
class DerivedQuantities:
    """Derived numbers with their standard errors (delta method, finite-difference gradients).

    Attributes
    ----------
    values : dict of str to ndarray
        Each quantity's values at the fitted parameters (for the report's, keys and units in
        :func:`tenscell.fitting.result.report_quantities`).
    stderr : dict of str to ndarray
        Their standard errors in the same units; NaN where not determined.
    notes : dict of str to tuple of str
        Per value: "" or why there is no error / which combination the error is of.
    """

    values: dict
    stderr: dict
    notes: dict

    def error(self, key: str, i: int = 0) -> tuple[float | None, str]:
        """``(standard error or None, note)`` of value ``i`` of quantity ``key``."""
        se = float(self.stderr[key][i])
        return (se if math.isfinite(se) else None), self.notes[key][i]

    def text(self, key: str, i: int = 0, unit: str = "", digits: int = 4, *, ln: bool = False) -> str:
        """Value ``i`` of ``key`` as ``"value +/- stderr (percent) unit"`` (lmfit's convention) or
        ``"value +/- not determined (why)"``; ``ln=True`` for a positive quantity set by ln-parameters (a large
        error is then a factor ×/÷, :func:`tenscell._results.plus_minus`)."""
        se, note = self.error(key, i)
        return plus_minus(float(self.values[key][i]), se, unit, note, digits, ln=ln)

    def to_dict(self) -> dict:
        """JSON-ready: per quantity, its values, standard errors (null when not determined) and notes."""
        return {k: {"value": [float(x) for x in v],
                    "stderr": [float(e) if math.isfinite(e) else None for e in self.stderr[k]],
                    "note": list(self.notes[k])} for k, v in self.values.items()}


def _at(result: FitResult, theta: np.ndarray) -> FitResult:
    """The fit with its free ln-parameters moved to ``theta`` (its derived properties recomputed on use)."""
    return dataclasses.replace(result, theta=theta, parameters=result.problem.parameters(theta))


#: parameters per task handed to a worker (a task it has not started can be taken back)
_CHUNK = 4


def _moved(result: FitResult, quantities, columns, step: float):
    """``quantities`` at θ + step·e_i for each free-parameter index i of ``columns`` (a list of dicts), or None
    when the model cannot be evaluated there. Module-level: a worker process runs a share of the columns."""
    out = []
    for i in columns:
        theta = np.array(result.theta, dtype=float)
        theta[i] += step
        try:
            out.append(quantities(_at(result, theta)))
        except (ValueError, ArithmeticError, np.linalg.LinAlgError):
            return None  # the model cannot be evaluated next to the optimum (e.g. at a stability edge)
    return out


def derived_quantities(result: FitResult, quantities, step: float = STEP, executor=None) -> DerivedQuantities:
    """The values of ``quantities(result)`` with their delta-method standard errors.

    Parameters
    ----------
    result : FitResult
    quantities : callable
        ``FitResult -> dict of str to array``, e.g. :func:`tenscell.fitting.result.report_quantities` (the
        numbers of the fit report); module-level when ``executor`` is given (it is pickled).
    step : float
        Forward-difference step in each analysed ln-parameter (see :data:`STEP`).
    executor : object with ``submit``, optional
        A worker (e.g. :func:`tenscell._parallel.background`) that evaluates up to half of the moved parameter
        vectors, in chunks, while this process evaluates the other half; chunks it has not started by then are
        evaluated here. The result does not depend on it.

    Returns
    -------
    DerivedQuantities
        Gradients by forward finite differences (1 evaluation of ``quantities`` per analysed
        parameter), errors by :meth:`~tenscell.fitting.identifiability.Identifiability.propagate`.
    """
    ident = result.identifiability()
    names = list(result.problem.names)
    free_index = np.cumsum(np.asarray(result.problem.free, dtype=bool)) - 1
    columns = [int(free_index[names.index(name)]) for name in ident.names]
    half = len(columns) // 2 if executor is not None else 0
    # the worker's half in small chunks: any chunk it has not started when this process is done with its own half
    # (the worker may still be busy with earlier work) is taken back and computed here
    chunks = [columns[i:min(i + _CHUNK, half)] for i in range(0, half, _CHUNK)]
    tasks = [executor.submit(_moved, result, quantities, chunk, step) for chunk in chunks] if half else []
    values = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in quantities(result).items()}
    mine = _moved(result, quantities, columns[half:], step)
    parts = [_moved(result, quantities, chunk, step) if task.cancel() else task.result()
             for chunk, task in zip(chunks, tasks)]
    theirs = [side for p in parts if p is not None for side in p]
    failed = mine is None or any(p is None for p in parts)
    grads = {k: np.full((v.size, ident.n_analysed), np.nan) for k, v in values.items()}
    if not failed:
        for j, side in enumerate([*theirs, *mine]):
            for k in values:
                grads[k][:, j] = (np.asarray(side[k], dtype=float).ravel() - values[k].ravel()) / step
    stderr, notes = {}, {}
    for k, v in values.items():
        errs = []
        for row in range(v.size):
            se, note = ident.propagate(grads[k][row]) if not failed else (
                None, "(the model cannot be evaluated next to the optimum)")
            if se is not None and ident.gauge_removed and k in _GAUGE_NOTES and not (
                    k == "stiffness_spread" and row == 2):
                note = _GAUGE_NOTES[k]
            errs.append((math.nan if se is None else se, note))
        stderr[k] = np.array([e for e, _ in errs])
        notes[k] = tuple(n for _, n in errs)
    return DerivedQuantities(values=values, stderr=stderr, notes=notes)

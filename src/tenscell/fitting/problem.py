"""The problem protocol: what every fittable model gives the search and the result.

A model (:class:`tenscell.fitting.models.base.FitModel`) is a frozen
specification; against data sets it builds a :class:`Problem`, which holds
plain arrays only (so that it can be sent to worker processes) and answers

* the **layout**: ``names``, ``units``, ``kinds``, ``descriptions``, the
  log-space ``lower``/``upper`` bounds, the ``free`` mask and the fixed
  log-values ``fixed_log``; the data's ``y_obs``, ``weights``,
  ``dataset_index``, ``sources`` and prestress groups (``group_map``,
  ``group_log_offset``, ``group_measured``, ``group_index``);
* the **evaluation** the search shares between residuals and Jacobian:
  ``_evaluate_constrained(phi, jac)`` (None where the model is not a stable,
  passive cell), then ``_residuals_from``, ``_jacobian_from`` and
  ``_penalty_from`` on that evaluation; ``residuals(theta)`` and
  ``jacobian(theta)`` follow;
* the **search's moves**: ``initial_guess(rng)`` and ``perturb(theta, rng)``;
* **anywhere**: ``moduli_at(theta, f_hz, P_N)``, the model's G′, G″ at any
  frequencies and model prestresses (``dataset_moduli_at`` those of one data set's own parameters, where a model
  has parameters per data set: :mod:`tenscell.fitting.models.population`);
* what the **result** reads: ``fitted(theta, result)`` (the fitted model,
  :mod:`tenscell.fitting.fitted`), ``report_quantities(result)`` (the numbers
  the report derives, each given a standard error by
  :mod:`~tenscell.fitting.derived`), ``summary(result)`` (the model's own
  entries of fit.json), ``stiffness_spread(theta)``,
  ``assignment_spread(theta)``, ``describe()`` and ``identifiability(theta, ...)``.

A problem whose Jacobian is block-sparse (many data sets, each with parameters of its own) says so by
``sparse_jacobian = True``: ``_jacobian_from`` then returns a :mod:`scipy.sparse` matrix and the search solves
its trust-region steps iteratively (LSMR), at a cost linear in the number of nonzeros.

Every fit is in natural-log parameters: ``theta`` holds the logs of the free
parameters in the order of ``names``; ``phi`` those of all parameters.
Residuals are ``w·(log10 model − log10 data)``: the G′ block, the G″ block,
then creep points (log10 J).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from .._errors import CapabilityError
from .parameters import Parameters
from .time_series import TimeLayout

__all__ = ["Problem", "centred_start", "central_difference", "log_residual_blocks", "draw_start", "jitter", "LN10",
           "PENALTY"]

LN10 = math.log(10.0)
#: a residual (decades) returned where the model is not a stable, passive cell (K0 not positive definite, G' or
#: G'' <= 0): finite, so that the trust-region solver simply rejects the step
PENALTY = 10.0


class Problem:
    """The parameter and residual layout every fit problem shares, and the protocol of the module docstring.

    Subclasses are frozen dataclasses (:class:`~tenscell.fitting.models.voigt.FitProblem`,
    :class:`~tenscell.fitting.models.mechanism.MechanismProblem`,
    :class:`~tenscell.fitting.models.formulas.FormulaProblem`,
    :class:`~tenscell.fitting.models.population.PopulationProblem`); they declare the fields below and implement the
    evaluation, the moves and the result hooks. The parameters are one object built by the model's layout,
    ``params`` (:class:`~tenscell.fitting.parameters.Parameters`, lmfit's ``Parameters``); ``names``, ``units``,
    ``descriptions``, ``kinds``, ``lower``, ``upper``, ``free`` and ``fixed_log`` read it, and :meth:`holding` gives
    the same problem with some of them replaced. Every field is a plain value or array: problems are pickled to the
    search's worker processes.
    """

    params: Parameters  # every parameter: names, units, kinds, descriptions, bounds, what is fixed
    weights: np.ndarray
    omega: np.ndarray
    y_obs: np.ndarray
    dataset_index: np.ndarray
    sources: tuple
    group_map: np.ndarray
    group_log_offset: np.ndarray
    group_measured: np.ndarray
    group_index: np.ndarray
    #: the time points of creep and relaxation data, their contour nodes and weights
    #: (:class:`~tenscell.fitting.time_series.TimeLayout`); None without time data (the Voigt cell's creep has its
    #: own modal route: :meth:`time_points`, :meth:`time_model`)
    time: TimeLayout | None = None
    # and every subclass has ``cell``: the reference cell (None for a structure-free formula)
    #: ``_jacobian_from`` returns a scipy.sparse matrix (the search then solves its steps by LSMR)
    sparse_jacobian = False

    # -- the model ------------------------------------------------------------------------
    @property
    def spec(self):
        """The :class:`~tenscell.fitting.models.base.FitModel` this problem was built from."""
        raise NotImplementedError

    def describe(self) -> str:
        """One line: what is fitted (the model and its structure)."""
        return self.spec.description

    @property
    def label(self) -> str:
        """A short name of the model for tables and legends."""
        return self.spec.name

    @property
    def comparison_name(self) -> str:
        """The model's row name in a comparison table (:mod:`tenscell.fitting.scores`)."""
        return self.spec.name

    @property
    def report_sections(self) -> tuple:
        """Names of the report sections of this kind of model beside the ones every fit has
        (:data:`tenscell.reports.fit.SECTIONS`)."""
        return ()

    # -- layout: read from the parameters (:class:`~tenscell.fitting.parameters.Parameters`) ----------
    @property
    def names(self) -> tuple:
        """All parameter names."""
        return self.params.names

    @property
    def units(self) -> tuple:
        """Each parameter's unit."""
        return self.params.units

    @property
    def descriptions(self) -> tuple:
        """What each parameter is, in words."""
        return self.params.descriptions

    @property
    def kinds(self) -> tuple:
        """Each parameter's kind (bounds and starts)."""
        return self.params.kinds

    @property
    def lower(self) -> np.ndarray:
        """Log lower bounds of all parameters (read-only)."""
        return self.params.lower

    @property
    def upper(self) -> np.ndarray:
        """Log upper bounds of all parameters (read-only)."""
        return self.params.upper

    @property
    def free(self) -> np.ndarray:
        """Which parameters are free (read-only)."""
        return self.params.free

    @property
    def fixed_log(self) -> np.ndarray:
        """Log values of all parameters: the fixed ones', and the free ones' references (read-only)."""
        return self.params.fixed_log

    def holding(self, *, free=None, fixed_log=None, lower=None, upper=None):
        """The same problem with the parameters' free mask, log values or log bounds replaced (a refit with some
        parameters held, a profile point)."""
        return dataclasses.replace(self, params=self.params.replaced(free=free, fixed_log=fixed_log, lower=lower,
                                                                     upper=upper))

    @property
    def n_params(self) -> int:
        """Number of all parameters (free and fixed)."""
        return len(self.names)

    @property
    def n_free(self) -> int:
        """Number of free parameters (length of ``theta``)."""
        return int(self.free.sum())

    @property
    def n_points(self) -> int:
        """Number of moduli data points, all data sets together."""
        return int(self.omega.size)

    @property
    def n_residuals(self) -> int:
        """Number of data residuals."""
        return int(self.y_obs.size)

    @property
    def n_datasets(self) -> int:
        """Number of data sets fitted together."""
        return len(self.sources)

    @property
    def n_groups(self) -> int:
        """Number of distinct model prestresses."""
        return int(self.group_map.shape[0])

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Log-space bounds of the free parameters."""
        return self.lower[self.free], self.upper[self.free]

    @property
    def prestress_slice(self) -> slice:
        """Positions of the prestress parameters in :attr:`names`."""
        raise NotImplementedError

    def full(self, theta) -> np.ndarray:
        """Log values of all parameters from the free ones."""
        phi = self.fixed_log.copy()
        phi[self.free] = theta
        return phi

    def values(self, theta) -> np.ndarray:
        """Parameter values (SI units) of all parameters, in the order of ``names``."""
        return np.exp(self.full(theta))

    def rows(self, dataset: int) -> np.ndarray:
        """Positions of data set ``dataset``'s residuals: its G' rows then its G'' rows, or its time rows."""
        if self.time is not None and dataset in self.time.dataset:
            return 2 * self.n_points + self.time.rows(dataset)
        pts = np.flatnonzero(self.dataset_index == dataset)
        return np.concatenate([pts, self.n_points + pts])

    def point_rows(self, dataset: int) -> np.ndarray:
        """The residual row of each point of a time data set (−1 for a shape's reference time, which is no
        residual); :meth:`rows` for moduli."""
        if self.time is None or dataset not in self.time.dataset:
            return self.rows(dataset)
        pts = self.time.points(dataset)
        where = np.full(self.time.n, -1)
        where[self.time.residual] = np.arange(self.time.n_residuals)
        return np.where(where[pts] >= 0, 2 * self.n_points + where[pts], -1)

    @property
    def residual_scale(self) -> np.ndarray:
        """Per data residual, how its log10 moves when every stiffness-like parameter and the prestress are scaled
        by λ together: by +log10 λ (moduli, a relaxation modulus), −log10 λ (a creep compliance), not at all (a
        relaxation's shape). What a start's centring undoes (:func:`centred_start`)."""
        n_time = self.n_residuals - 2 * self.n_points
        t = self.time
        if t is None:
            tail = -np.ones(n_time)  # the Voigt cell's time data are creep
        else:
            res = t.residual
            tail = np.where(t.reference[res] >= 0, 0.0, np.where(t.relaxation[res], 1.0, -1.0))
        return np.concatenate([np.ones(2 * self.n_points), tail])

    def parameters(self, theta) -> tuple:
        """The parameters as :class:`tenscell.fitting.FitParameter` records (SI units)."""
        from .records import FitParameter

        vals = self.values(theta)
        lo, hi = np.exp(self.lower), np.exp(self.upper)
        return tuple(
            FitParameter(name=n, value=float(v), lower=float(a), upper=float(b), unit=u, vary=bool(fr), description=d)
            for n, v, a, b, u, fr, d in zip(self.names, vals, lo, hi, self.units, self.free, self.descriptions)
        )

    def group_prestress(self, theta) -> np.ndarray:
        """Model prestress (N) of each prestress group."""
        phi = self.full(theta)
        return np.exp(self.group_log_offset + self.group_map @ phi[self.prestress_slice])

    def model_prestress(self, theta, prestress_pa) -> np.ndarray:
        """Model prestress (N) of measured prestresses ``prestress_pa`` (Pa): ``s·prestress_pa`` for a problem
        with a prestress scale ``s`` (some data set stated its prestress); ValueError otherwise."""
        if "s" not in self.names:
            raise ValueError("no data set of this fit stated its prestress, so prestress (Pa) has no model "
                             "equivalent; use the fitted P (N)")
        return float(self.values(theta)[self.names.index("s")]) * np.asarray(prestress_pa, dtype=float)

    # -- the gauge and the search's coordinates --------------------------------------------
    def gauge(self) -> np.ndarray:
        """An exact gauge of the moduli in log-parameter space (zeros: none)."""
        return np.zeros(self.n_params)

    @property
    def n_model_parameters(self) -> int:
        """Free parameters less the exact gauge, if any, and less the common scale of the moduli when every data set
        is a relaxation's shape (the residuals cannot see it: :attr:`~.time_series.TimeLayout.scale_blind`): what
        AIC and BIC count."""
        g = self.gauge()
        moved = g != 0
        blind = self.time is not None and not self.n_points and self.time.scale_blind
        return self.n_free - (1 if moved.any() and np.all(self.free[moved]) else 0) - int(blind)

    def coordinate_map(self) -> np.ndarray:
        """Search coordinates to free log-parameters: ``theta = T @ u`` (identity unless a model says otherwise)."""
        return np.eye(self.n_free)

    def coordinate_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of the search coordinates."""
        return self.bounds

    def to_coordinates(self, theta) -> np.ndarray:
        """Search coordinates of free log-parameters ``theta``."""
        return np.asarray(theta, dtype=float).copy()

    @property
    def n_penalties(self) -> int:
        """One-sided penalty residuals appended after the data's (the Voigt cell's activity constraints); 0."""
        return 0

    @property
    def n_creep(self) -> int:
        """Time residuals (creep and relaxation points; they follow the moduli's); 0 for moduli only."""
        return 0 if self.time is None else self.time.n_residuals

    def time_points(self, dataset: int) -> np.ndarray:
        """Positions among the time points (:meth:`time_model`) of data set ``dataset``'s."""
        assert self.time is not None, "only asked of a problem with time data"
        return self.time.points(dataset)

    @property
    def time_group(self) -> np.ndarray:
        """The prestress group of every time point."""
        assert self.time is not None, "only asked of a problem with time data"
        return self.time.group

    def time_model(self, theta) -> np.ndarray:
        """The model's time function at every time point: creep compliance J(t) (1/Pa), relaxation modulus G(t)
        (Pa), or for a shape G(t)/G(t_ref); NaN where the model is not a stable cell."""
        raise NotImplementedError

    def creep(self, theta) -> np.ndarray:
        """Model creep compliance (1/Pa) at the creep points (models that fit creep data)."""
        return self.time_model(theta)

    # -- evaluation (subclasses implement the first three) --------------------------------------
    def _evaluate_constrained(self, phi, jac: bool):
        raise NotImplementedError

    def _residuals_from(self, out) -> np.ndarray:
        raise NotImplementedError

    def _jacobian_from(self, out) -> np.ndarray:
        raise NotImplementedError

    def _penalty_from(self, out, jac: bool):
        """Penalty residuals and their Jacobian (none by default)."""
        return np.zeros(0), (np.zeros((0, self.n_free)) if jac else None)

    def _evaluate_cells(self, cells, phis, jac: bool) -> tuple:
        """What :meth:`_evaluate_constrained` gives for each of ``cells`` (problems of this one's model and layout,
        e.g. a population's) at its own log-parameters ``phis[c]``: one by one here; a model whose kernel evaluates
        many cells at once overrides it (:func:`tenscell.fitting.models.mechanism_kernel.evaluate_cells`)."""
        return tuple(pb._evaluate_constrained(phi, jac) for pb, phi in zip(cells, phis))

    def _moduli_of(self, out):
        """``(G*, dG*/dφ or None)`` at the data points (Pa; complex; dφ over every parameter) held in an evaluation
        ``out`` of moduli data (one :meth:`_evaluate_constrained` gives), or None where the evaluation found no stable
        cell: what :meth:`_residuals_from` and :meth:`_jacobian_from` make ``w·(log10 model − log10 data)`` and its
        Jacobian of. A population stacks its cells' (:class:`~tenscell.fitting.models.population.PopulationProblem`);
        a model whose problems may be a population's base implements it."""
        raise NotImplementedError

    def residuals(self, theta) -> np.ndarray:
        """Weighted data residuals ``w·(log10 model − log10 data)`` at free log-parameters ``theta``."""
        return self._residuals_from(self._evaluate_constrained(self.full(theta), jac=False))

    def jacobian(self, theta) -> np.ndarray:
        """Jacobian of :meth:`residuals` by the free log-parameters, shape (n_residuals, n_free)."""
        return self._jacobian_from(self._evaluate_constrained(self.full(theta), jac=True))

    def jacobian_fd(self, theta, step: float = 1e-5) -> np.ndarray:
        """Central finite differences of :meth:`residuals` (the slow reference)."""
        return central_difference(self.residuals, theta, step)

    def feasible(self, theta) -> bool:
        """The model's constraints hold at ``theta`` (none by default: True)."""
        return True

    def rms(self, theta) -> float:
        """RMS of the unweighted log10 residuals of all data sets (decades)."""
        r = self.residuals(theta) / self.weights
        return float(np.sqrt(np.mean(r**2)))

    def dataset_rms(self, theta) -> np.ndarray:
        """RMS of the unweighted log10 residuals of each data set (decades), shape (n_datasets,)."""
        return self.dataset_rms_of(self.residuals(theta) / self.weights)

    def dataset_rms_of(self, r) -> np.ndarray:
        """:meth:`dataset_rms` of unweighted log10 residuals ``r`` already evaluated (decades)."""
        return np.array([math.sqrt(float(np.mean(r[self.rows(k)] ** 2))) for k in range(self.n_datasets)])

    # -- the search's moves ---------------------------------------------------------------------
    def initial_guess(self, rng: np.random.Generator) -> np.ndarray:
        """A start: free log-parameters placed on the data."""
        raise NotImplementedError

    def perturb(self, theta, rng: np.random.Generator) -> np.ndarray:
        """A basin-hopping move from free log-parameters ``theta``."""
        raise NotImplementedError

    # -- anywhere, and what the result reads ---------------------------------------------------
    def moduli(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """Model G', G'' (Pa) at the data points; NaN where the model is not a stable cell."""
        raise NotImplementedError

    def moduli_at(self, theta, f_hz, P_N) -> tuple[np.ndarray, np.ndarray]:
        """Model G', G'' (Pa) at frequencies ``f_hz`` (Hz) and model prestresses ``P_N`` (N), broadcast together."""
        raise NotImplementedError

    def dataset_moduli_at(self, theta, f_hz, P_N, dataset: int) -> tuple[np.ndarray, np.ndarray]:
        """Like :meth:`moduli_at`, with the parameters of data set ``dataset`` (the same for every data set unless
        the model has parameters per data set)."""
        return self.moduli_at(theta, f_hz, P_N)

    def identifiability(self, theta, *, sigma_known: bool = False, rtol: float = 1e-8):
        """What the data determine at ``theta`` (:func:`tenscell.fitting.identifiability.identifiability`)."""
        from .identifiability import identifiability

        return identifiability(self, theta, sigma_known=sigma_known, rtol=rtol)

    def fitted(self, theta, result):
        """The fitted model (:mod:`tenscell.fitting.fitted`) at ``theta``; ``result`` gives the data's prestresses."""
        raise NotImplementedError

    def report_quantities(self, result) -> dict:
        """Every number the report derives from the parameters, as flat arrays (given ± by :mod:`.derived`)."""
        return {}

    def summary(self, result) -> dict:
        """The model's own entries of fit.json (beside the entries every fit has)."""
        return {}

    def stiffness_spread(self, theta) -> tuple[float, float, float] | None:
        """(min, max, decades) of the tendon stiffnesses (N, N, -); None for a model without tendons."""
        return None

    def stiffness_at_bound(self, theta) -> bool:
        """Whether a tendon stiffness parameter sits at a bound (the span of the stiffnesses is then set by the bound
        box); False for a model whose stiffnesses are not laid out per tendon or family (the default)."""
        return False

    def stiffness_bound(self) -> tuple[float | None, bool]:
        """``(D, binding)``: the bound D (decades) the fit put on the spread of the stiffnesses, and whether it
        constrains them (narrower than their bounds); ``(None, False)`` without one."""
        return None, False

    def stiffness_spread_interior(self, theta) -> tuple[float, float, float] | None:
        """Like :meth:`stiffness_spread`, over the tendons not at a bound (None: not applicable, or all at one)."""
        return None

    def prestress_activity(self, result, reference_frequency_hz: float = 0.1):
        """Is the prestress doing anything? Defined for the Voigt cell (:mod:`tenscell.fitting.prestress`)."""
        raise CapabilityError(f"the prestress activity analysis is defined for the Voigt cell, not for "
                              f"{self.spec.name} (its prestress dependence: result.structure)")

    def assignment_spread(self, theta) -> tuple[float, float]:
        """Largest sd (decades) of G', G'' between the assignments of a distributed property (0, 0: none)."""
        return 0.0, 0.0


def centred_start(problem: Problem, out, phi: np.ndarray, scalable: np.ndarray) -> float | None:
    """Score one candidate start the way every search ranks them, and centre it on the data.

    ``out`` is ``problem``'s evaluation at ``phi`` (natural-log parameters). Scaling every stiffness-like
    parameter (``scalable``) together by k scales G by k exactly, so the mean log10 residual is removed by
    shifting them (``phi`` is changed in place) and the start is scored by the RMS of what is left (decades).
    Returns None when the evaluation failed or hit the penalty.
    """
    r = problem._residuals_from(out) / problem.weights
    if out is None or np.any(np.abs(r) >= PENALTY):
        return None
    sign = problem.residual_scale
    if np.all(sign == 1.0):  # moduli only
        phi[scalable] -= float(np.mean(r)) * LN10
        return float(np.sqrt(np.mean((r - np.mean(r)) ** 2)))
    # time data: a creep compliance moves against the moduli, a shape not at all (Problem.residual_scale)
    shift = float(np.dot(sign, r) / np.dot(sign, sign)) if np.any(sign) else 0.0
    phi[scalable] -= shift * LN10
    return float(np.sqrt(np.mean((r - sign * shift) ** 2)))


def central_difference(fun, theta, step: float) -> np.ndarray:
    """Central finite differences of ``fun`` at ``theta``, one column per entry of ``theta``."""
    theta = np.asarray(theta, dtype=float)
    cols = []
    for k in range(theta.size):
        e = np.zeros_like(theta)
        e[k] = step
        cols.append((fun(theta + e) - fun(theta - e)) / (2 * step))
    return np.stack(cols, axis=-1)


def log_residual_blocks(G, dG) -> np.ndarray:
    """``d log10 G' / dθ`` over ``d log10 G'' / dθ`` from complex moduli ``G`` (N,) and ``dG`` (N, p)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(np.vstack([dG.real / (G.real[:, None] * LN10), dG.imag / (G.imag[:, None] * LN10)]))


def draw_start(problem: Problem, rng: np.random.Generator, scalable_kinds, candidates: int = 24) -> np.ndarray:
    """A start: the best of ``candidates`` log-uniform draws in the middle of the bounds, scaled onto the data.

    Every parameter of a ``scalable_kinds`` kind (and a prestress parameter) scaled by λ scales G* by λ, so the
    mean log residual of a draw is removed by one shift (:func:`~tenscell.fitting.problem.centred_start`).
    """
    lo, hi = problem.lower, problem.upper
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    scal = np.array([k in scalable_kinds or k in ("s", "P") for k in problem.kinds]) & problem.free
    phis = np.tile(problem.fixed_log, (candidates, 1))
    for phi in phis:  # the draws in the order they were always drawn, then evaluated together
        draw = mid + rng.uniform(-0.6, 0.6, mid.size) * half
        phi[problem.free] = draw[problem.free]
    best = None
    for phi, out in zip(phis, problem._evaluate_cells((problem,) * candidates, phis, jac=False)):
        score = centred_start(problem, out, phi, scal)
        if score is None:
            continue
        if best is None or score < best[0]:
            best = (score, phi)
    phi = best[1] if best is not None else problem.fixed_log.copy()
    return np.clip(phi[problem.free], lo[problem.free], hi[problem.free])


def jitter(problem: Problem, theta, rng: np.random.Generator) -> np.ndarray:
    """A basin-hopping move: every free log-parameter jittered by about half a decade, within the bounds."""
    lo, hi = problem.bounds
    step = np.minimum(0.5 * LN10, 0.25 * (hi - lo))
    return np.clip(np.asarray(theta) + rng.normal(0.0, 1.0, theta.size) * step, lo, hi)

from .._deprecated import moved_away  # noqa: E402

__getattr__ = moved_away(__name__)  # the public names of 0.2.0 that moved away: a DeprecationWarning names their home

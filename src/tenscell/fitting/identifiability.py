"""What the data determine: rank, standard errors and correlations of a fit.

At the optimum the weighted residuals ``r(θ)`` (decades of log10 G, divided by
the data's standard deviation where one is given) have the analytic Jacobian
``J = ∂r/∂θ`` with respect to the natural logarithms θ of the free parameters.
Linearized, a change ``δθ`` changes the residuals by ``J·δθ``; so

* the singular values ``s_k`` of ``J`` say how strongly the data see the
  parameter combination along the right singular vector ``v_k``: moving it by
  one e-fold changes the residuals by ``s_k`` (decades);
* with independent Gaussian errors of standard deviation σ in the residuals,
  the covariance of θ is ``σ²·(JᵀJ)⁺`` and a combination ``v_k·θ`` has the
  standard error ``σ/s_k`` (in ln units: 0.1 ≈ ±10 %).

σ is 1 when every data point has a standard deviation (the residuals are then
already in units of it); otherwise it is estimated from the residuals,
``σ² = Σr²/(n − rank)`` (like ``scipy.optimize.curve_fit`` with
``absolute_sigma=False``).

Parameters are left out of the analysis when they are fixed or sit at a bound
(an active bound is a constraint, not an estimate). The strut length L is an
exact gauge when P (or s), every c and L are free: ``(P, EA, c, L) ->
(λ²P, λ²EA, λc, λL)`` leaves G unchanged (:meth:`FitProblem.gauge`), so the
data cannot determine L. The gauge is removed by holding L at its fitted
value; every other parameter then stands for its gauge-invariant combination
``EA/L²``, ``c/L``, ``P/L²`` (``s/L²``), which is how they are labelled.

Singular values below ``rtol`` times the largest count as zero: those
combinations are not seen at all. A parameter whose unit vector has more than
:data:`NULL_SHARE` of its length in that unseen subspace is not determined
(its standard error is reported as infinite): moving along the unseen
directions within the bounds changes it by more than a few per cent.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._results import format_repr
from .._threads import hot_path

__all__ = ["Identifiability", "Combination", "identifiability", "combinations", "sigma_estimate", "errors_from_covariance", "simple_exponent", "GAUGE",
           "NULL_SHARE", "SIMPLE_EXPONENTS"]

#: the exact strut-length invariance of the linear moduli
GAUGE = "(P, EA, c, L) -> (λ²P, λ²EA, λc, λL)"
#: largest share of a parameter's unit vector in the unseen subspace for it to count as determined
NULL_SHARE = 0.01


@dataclass(frozen=True)
class Combination:
    """A product of powers of parameters, ``Π name^exponent``, with its standard error.

    Attributes
    ----------
    exponents : tuple of (str, float)
        Parameter labels (``"c/L"``, ``"EA[3]/L²"`` when the gauge was removed,
        plain names otherwise) and exponents; the largest exponent in absolute
        value is ±1.
    singular_value : float
        How strongly the residuals respond (decades per e-fold of the combination).
    standard_error : float
        Standard error of ``ln Π name^exponent`` (ln units; 0.1 ≈ ±10 %), or
        None if the noise level is unknown.
    value : float or None
        The product's value at the fit (SI units of its factors), for a combination of
        :meth:`Identifiability.identified`; None for a singular vector of :attr:`Identifiability.combinations`
        (for those, ``singular_value`` is the singular value itself; for an identified pair it is the
        equivalent one, σ over the standard error).
    factor_errors : tuple of (str, float)
        The factors' own standard errors of ln (inf: not determined), for an identified combination.
    """

    exponents: tuple
    singular_value: float
    standard_error: float | None
    value: float | None = None
    factor_errors: tuple = ()

    def words(self) -> str:
        """``"beta·s"``, ``"EA[3]/L² · s^-0.5"``: the product in plain notation (exponents of ±1 not written)."""
        parts = []
        for n, e in sorted(self.exponents, key=lambda t: -abs(t[1])):
            name = f"({n})" if "/" in n and abs(e) != 1 else n
            if abs(e - 1) <= 1e-9:
                parts.append(name)
            elif abs(e + 1) <= 1e-9:
                parts.append(f"1/{name}" if not parts else f"/{name}")
            else:
                parts.append(f"{name}^{e:.2g}")
        text = ""
        for p in parts:
            text += p if p.startswith("/") or not text else f"·{p}"
        return text

    def text(self, min_exponent: float = 0.1, max_terms: int = 6) -> str:
        """``"(c/L)^1 · (EA[4]/L²)^0.41 ..."``: terms with ``|exponent| >= min_exponent``, largest first."""
        terms = sorted(self.exponents, key=lambda t: -abs(t[1]))
        shown = [(n, e) for n, e in terms if abs(e) >= min_exponent][:max_terms]
        text = " · ".join(f"({n})^{e:.2g}" if "/" in n else f"{n}^{e:.2g}" for n, e in shown)
        rest = len([1 for _, e in terms if abs(e) >= 1e-3]) - len(shown)
        return text + (f" · (… {rest} smaller)" if rest > 0 else "")

    def to_dict(self) -> dict:
        """JSON-ready dict."""
        out = {"exponents": dict(self.exponents), "singular_value": self.singular_value,
               "standard_error_ln": self.standard_error, "text": self.text()}
        if self.value is not None:
            out.update(value=self.value, words=self.words(),
                       factor_standard_errors_ln={n: (None if se is None or not math.isfinite(se) else se)
                                                  for n, se in self.factor_errors})
        return out


@dataclass(frozen=True, eq=False, repr=False)
class Identifiability:
    """Local identifiability of a fit's parameters (linearized at the optimum).

    Attributes
    ----------
    names : tuple of str
        Parameters analysed (free, not at a bound; L left out when it is a
        gauge), in problem order.
    labels : tuple of str
        The same, in gauge-invariant form when the gauge was removed (``"c/L"``,
        ``"EA[3]/L²"``, ``"P/L²"``).
    values : ndarray, shape (p,)
        Their values: of the labelled combination when the gauge was removed
        (``EA/L²`` in N/m², ``c/L`` in N·s/m², ``P/L²`` in N/m², ``s/L²``
        dimensionless), else of the plain parameter (SI units).
    singular_values : ndarray, shape (min(n, p),)
        Of the weighted Jacobian with respect to the ln-parameters, descending
        (decades of residual per e-fold).
    rank : int
        Singular values above ``rtol`` times the largest.
    rtol : float
    gauge_removed : bool
        True when L was an exact gauge and was held at its fitted value.
    excluded : tuple of (str, str)
        ``(name, reason)`` of the free parameters left out: ``"lower bound"``,
        ``"upper bound"`` or ``"gauge"``.
    fixed : tuple of str
        Parameters the user fixed.
    n_residuals : int
    sigma : float or None
        Standard deviation of the weighted residuals used for the errors;
        None when it cannot be estimated (no standard deviations in the data
        and as many seen combinations as residuals).
    sigma_source : str
        ``"data standard deviations"``, ``"residuals"`` or ``"unknown"``.
    dof : int
        ``n_residuals − rank``.
    chi2 : float
        Sum of squared weighted residuals.
    standard_errors : ndarray, shape (p,)
        Of the ln-parameters (ln units; 0.1 ≈ ±10 %); inf when not
        determined, NaN when σ is unknown.
    null_share : ndarray, shape (p,)
        Length of each parameter's unit vector in the unseen subspace.
    correlation : ndarray, shape (p, p)
        Correlation matrix of the ln-parameters (NaN rows for undetermined ones).
    combinations : tuple of Combination
        The seen combinations (right singular vectors), best determined first.
    leverage : ndarray, shape (n_residuals,)
        Diagonal of the hat matrix ``J (JᵀJ)⁺ Jᵀ`` (the squared row norms of
        the seen left singular vectors; they sum to the rank): the fitted
        model at residual i has the standard error ``σ·sqrt(leverage_i)`` in
        weighted units (:meth:`tenscell.fitting.FitResult.model_standard_errors`).
    directions : ndarray, shape (p, p), optional
        Right singular vectors of the Jacobian (columns, in the order of
        :attr:`singular_values`, then the unseen ones): what :meth:`propagate`
        needs for the covariance of a derived quantity.
    """

    names: tuple
    labels: tuple
    values: np.ndarray
    singular_values: np.ndarray
    rank: int
    rtol: float
    gauge_removed: bool
    excluded: tuple
    fixed: tuple
    n_residuals: int
    sigma: float | None
    sigma_source: str
    dof: int
    chi2: float
    standard_errors: np.ndarray
    null_share: np.ndarray
    correlation: np.ndarray
    combinations: tuple
    leverage: np.ndarray | None = None
    directions: np.ndarray | None = None

    @property
    def n_analysed(self) -> int:
        """Number of parameters analysed."""
        return len(self.names)

    def determined(self, within: float = 0.1) -> np.ndarray:
        """Mask of the parameters whose standard error (ln units) is at most ``within`` (0.1 ≈ ±10 %)."""
        return np.isfinite(self.standard_errors) & (self.standard_errors <= within)

    def n_combinations_within(self, within: float = 0.1) -> int:
        """How many independent combinations have a standard error at most ``within`` (ln units)."""
        return sum(c.standard_error is not None and c.standard_error <= within for c in self.combinations)

    def relative_error(self, name: str) -> tuple[float | None, str]:
        """``(standard error relative to the value, note)`` of the parameter ``name``.

        The relative error is the standard error of its ln (first order: of
        ``value × (1 ± se)``); None, with the reason in ``note``, when the
        parameter was fixed, sits at a bound, is the gauge L, lies in a
        combination the data do not see, or σ is unknown. With the gauge
        removed the note says which combination the error is of
        (``"of EA[3]/L²"``).
        """
        if name in self.fixed:
            return None, "(fixed)"
        for n, reason in self.excluded:
            if n == name:
                return None, ("(gauge: the data fix only EA/L², c/L, P/L²)" if reason == "gauge"
                              else f"(at its {reason}: not an estimate)")
        if name not in self.names:
            return None, "(not analysed)"
        i = self.names.index(name)
        se = float(self.standard_errors[i])
        if math.isnan(se):
            return None, "(σ unknown: as many seen combinations as residuals)"
        if not math.isfinite(se):
            return None, "(not determined: in a combination the data do not see)"
        return se, (f"(of {self.labels[i]})" if self.labels[i] != name else "")

    def propagate(self, gradient) -> tuple[float | None, str]:
        """Standard error of a quantity g derived from the parameters, and a note (first order, the delta method).

        ``se(g)² = ∇gᵀ Σ ∇g`` with ``Σ = σ²·(JᵀJ)⁺`` the covariance of the analysed ln-parameters (the one
        behind :attr:`standard_errors`), ``∇g = ∂g/∂θ`` (shape (p,), over :attr:`names`, θ their natural logs;
        the caller computes it, exactly or by finite differences). By the rule of :attr:`standard_errors`, g is
        not determined when more than :data:`NULL_SHARE` of its gradient lies in the combinations the data do
        not see. Returns ``(None, note)`` then, or when σ is unknown or the directions were not kept.
        """
        g = np.asarray(gradient, dtype=float).reshape(-1)
        if self.directions is None or g.size != self.n_analysed:
            return None, "(not available: no covariance of these parameters)"
        if not np.all(np.isfinite(g)):
            return None, "(its gradient is not finite)"
        norm = float(np.linalg.norm(g))
        if norm == 0.0:  # set by fixed parameters or ones at a bound alone: a constraint, not an estimate
            return None, "(set by fixed parameters or bounds alone: not an estimate)"
        c = self.directions.T @ g
        if float(np.linalg.norm(c[self.rank:])) > NULL_SHARE * norm:
            return None, "(depends on a combination the data do not see)"
        if self.sigma is None:
            return None, "(σ unknown: as many seen combinations as residuals)"
        s = self.singular_values[:self.rank]
        return float(self.sigma * np.sqrt(np.sum((c[:self.rank] / s) ** 2))), ""

    def identified(self, within: float = 0.1) -> tuple[Combination, ...]:
        """Products of two parameters the data determine although neither factor is: ``beta·s``, ``EA/c``.

        For every pair of analysed parameters whose own standard errors exceed ``within`` (ln units), the
        combination ``x^a·y^b`` (largest |exponent| 1) with the smallest standard error is found in closed form
        (the smaller eigenvector of the pair's 2×2 covariance, the unseen combinations excluded) and kept when it
        is determined within ``within`` and at least twice as well as its better factor. A parameter enters at most
        one kept pair, the best determined first. Exponents within 0.05 of ±½, ±1 or ±2 are rounded to them when
        the rounded product is determined as well. Each combination carries its value (of the labels: the
        gauge-invariant ones when the gauge was removed) and its factors' own standard errors.
        """
        if self.directions is None or self.sigma is None or self.rank == 0:
            return ()
        V, s = self.directions, self.singular_values[:self.rank]
        cov = (V[:, :self.rank] / s**2) @ V[:, :self.rank].T
        unseen = V[:, self.rank:] @ V[:, self.rank:].T
        penalty = 1e6 * float(np.max(np.diag(cov)))  # excludes the unseen combinations from the minimum
        se = np.asarray(self.standard_errors, dtype=float)
        loose = [i for i in range(self.n_analysed) if not se[i] <= within]
        found = []
        for a, i in enumerate(loose):
            for j in loose[a + 1:]:
                combo = self._pair(i, j, cov + penalty * unseen, within)
                if combo is not None:
                    found.append(combo)
        kept: list[Combination] = []
        used: set[str] = set()
        for c in sorted(found, key=lambda c: float(c.standard_error or 0.0)):
            names = {n for n, _ in c.exponents}
            if not names & used:
                kept.append(c)
                used |= names
        return tuple(kept)

    def _pair(self, i: int, j: int, q: np.ndarray, within: float) -> Combination | None:
        """The best-determined product of parameters ``i`` and ``j`` (see :meth:`identified`), or None."""
        a, b, c = float(q[i, i]), float(q[i, j]), float(q[j, j])
        if b == 0.0:
            return None
        lam = 0.5 * (a + c) - math.hypot(0.5 * (a - c), b)  # the smaller eigenvalue of [[a, b], [b, c]]
        v = np.array([b, lam - a]) if abs(lam - a) >= abs(lam - c) else np.array([lam - c, b])
        v = v / v[int(np.argmax(np.abs(v)))]
        if float(np.min(np.abs(v))) < 0.1:  # one parameter alone, not a product
            return None
        snapped = np.array([simple_exponent(x) for x in v])
        best = None
        for e in (snapped, v) if not np.array_equal(snapped, v) else (v,):
            g = np.zeros(self.n_analysed)
            g[[i, j]] = e
            err, _ = self.propagate(g)
            if err is not None and err <= within and err <= 0.5 * min(self.standard_errors[i], self.standard_errors[j]):
                best = (e, err)
                break
        if best is None:
            return None
        e, err = best
        k = [i, j]
        value = float(np.exp(np.sum(e * np.log(self.values[k]))))
        return Combination(exponents=tuple((self.labels[n], float(x)) for n, x in zip(k, e)),
                           singular_value=float(self.sigma or 1.0) / err if err > 0 else math.inf, standard_error=err,
                           value=value, factor_errors=tuple((self.labels[n], float(self.standard_errors[n]))
                                                            for n in k))

    def strong_correlations(self, threshold: float = 0.9) -> list[tuple[str, str, float]]:
        """``(label_a, label_b, ρ)`` for determined pairs with ``|ρ| >= threshold``, strongest first."""
        ok = np.isfinite(self.standard_errors)
        out = []
        for i in range(self.n_analysed):
            for j in range(i + 1, self.n_analysed):
                rho = self.correlation[i, j]
                if ok[i] and ok[j] and abs(rho) >= threshold:
                    out.append((self.labels[i], self.labels[j], float(rho)))
        return sorted(out, key=lambda t: -abs(t[2]))

    def __repr__(self) -> str:
        s = self.singular_values
        ratio = f"{s[-1] / s[0]:.2g}" if s.size and s[0] > 0 else "-"
        sig = "unknown" if self.sigma is None else f"{self.sigma:.3g} ({self.sigma_source})"
        return format_repr(
            "Identifiability",
            f"{self.n_analysed} parameters analysed against {self.n_residuals} residuals; rank {self.rank} "
            f"(rtol {self.rtol:g}); smallest/largest singular value {ratio}",
            f"gauge removed: {'yes (L held; others as EA/L², c/L, P/L²)' if self.gauge_removed else 'no'}",
            f"σ = {sig}; {int(self.determined().sum())} parameter(s) and {self.n_combinations_within()} "
            "combination(s) determined within ±10 %",
        )

    def to_dict(self) -> dict:
        """JSON-ready dict (non-finite numbers as None)."""
        def num(x):
            return float(x) if np.isfinite(x) else None

        return {
            "parameters": [
                {"name": n, "label": lab, "value": float(v), "standard_error_ln": num(se),
                 "factor": num(math.exp(se)) if np.isfinite(se) and se < 700 else None,
                 "null_share": float(ns)}
                for n, lab, v, se, ns in zip(self.names, self.labels, self.values, self.standard_errors,
                                             self.null_share)
            ],
            "singular_values": self.singular_values.tolist(),
            "rank": self.rank,
            "rtol": self.rtol,
            "gauge": GAUGE,
            "gauge_removed": self.gauge_removed,
            "excluded": [{"name": n, "reason": r} for n, r in self.excluded],
            "fixed": list(self.fixed),
            "n_residuals": self.n_residuals,
            "sigma": self.sigma,
            "sigma_source": self.sigma_source,
            "dof": self.dof,
            "chi2": self.chi2,
            "correlation": [[num(x) for x in row] for row in self.correlation],
            "combinations": [c.to_dict() for c in self.combinations],
            "identified_combinations": [c.to_dict() for c in self.identified()],
            "determined_within_10_percent": [lab for lab, d in zip(self.labels, self.determined()) if d],
        }


#: exponents an identified combination's are rounded to when within 0.05 of one (and the product stays determined)
SIMPLE_EXPONENTS = (-2.0, -1.0, -0.5, 0.5, 1.0, 2.0)


def simple_exponent(x: float) -> float:
    """``x`` rounded to the nearest of :data:`SIMPLE_EXPONENTS` when within 0.05 of it, else ``x``."""
    near = min(SIMPLE_EXPONENTS, key=lambda e: abs(e - x))
    return near if abs(near - x) <= 0.05 else float(x)


def _gauge_label(name: str, power: float) -> str:
    if power == 0:
        return name
    return f"{name}/L" if power == 1 else f"{name}/L²"


@hot_path
def identifiability(problem, theta, *, sigma_known: bool = False, rtol: float = 1e-8) -> Identifiability:
    """Rank, standard errors, correlations and determined combinations of a fit at ``theta``.

    Parameters
    ----------
    problem : FitProblem
        Provides ``jacobian``, ``residuals``, ``parameters``, ``names``,
        ``free`` and ``gauge``.
    theta : array_like, shape (n_free,)
        The fitted free ln-parameters.
    sigma_known : bool
        True when every residual is weighted by a standard deviation given with
        the data (σ = 1); otherwise σ is estimated from the residuals.
    rtol : float
        Singular values below ``rtol`` times the largest count as zero.

    Returns
    -------
    Identifiability
    """
    theta = np.asarray(theta, dtype=float)
    if not 0 < rtol < 1:
        raise ValueError(f"rtol must lie in (0, 1), got {rtol!r}")
    pars = problem.parameters(theta)
    free = np.asarray(problem.free, dtype=bool)
    g = problem.gauge()
    # an exact gauge only if it moves something and nothing it moves is fixed (a mechanism has none: g = 0)
    gauge = bool(np.any(g != 0) and np.all(free[g != 0]))
    l_index = problem.n_params - 1
    keep, excluded = _kept(pars, free, gauge, l_index)
    gauge_removed = gauge and any(r == "gauge" for _, r in excluded)
    J = problem.jacobian(theta)[:, keep[free]]
    r = problem.residuals(theta)
    n = r.size
    names = tuple(problem.names[i] for i in np.flatnonzero(keep))
    labels = tuple(_gauge_label(nm, g[i] if gauge_removed else 0) for nm, i in zip(names, np.flatnonzero(keep)))
    # with the gauge removed each parameter stands for its gauge-invariant combination: report that value
    L_fit = pars[l_index].value
    values = np.array([pars[i].value / (L_fit ** g[i] if gauge_removed else 1.0) for i in np.flatnonzero(keep)])

    U, s, Vt = np.linalg.svd(J, full_matrices=True) if J.size else (None, np.zeros(0), np.zeros((0, 0)))
    rank = int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0 else 0
    chi2 = float(r @ r)
    dof = n - rank
    sigma, source = sigma_estimate(sigma_known, chi2, dof)
    V = Vt.T
    se, null_share, corr = _uncertainties(V, s, rank, values.size, sigma)
    return Identifiability(
        names=names, labels=labels, values=values, singular_values=s, rank=rank, rtol=rtol,
        gauge_removed=gauge_removed, excluded=tuple(excluded),
        fixed=tuple(problem.names[i] for i in np.flatnonzero(~free)), n_residuals=n, sigma=sigma,
        sigma_source=source, dof=dof, chi2=chi2, standard_errors=se, null_share=null_share, correlation=corr,
        combinations=combinations(V, s, rank, labels, sigma),
        leverage=np.sum(U[:, :rank] ** 2, axis=1) if U is not None else np.zeros(n),
        directions=V,
    )


def _kept(pars, free: np.ndarray, gauge: bool, l_index: int) -> tuple[np.ndarray, list[tuple[str, str]]]:
    """Which parameters are analysed (free, not at a bound, not L under a gauge), and why the others are not."""
    keep = np.zeros(len(free), dtype=bool)
    excluded = []
    for i, p in enumerate(pars):
        if not free[i]:
            continue
        if p.at_bound is not None:
            excluded.append((p.name, f"{p.at_bound} bound"))
        elif gauge and i == l_index:
            excluded.append((p.name, "gauge"))
        else:
            keep[i] = True
    return keep, excluded


def sigma_estimate(sigma_known: bool, chi2: float, dof: int) -> tuple[float | None, str]:
    """The residuals' standard deviation and where it comes from (None when it cannot be estimated)."""
    if sigma_known:
        return 1.0, "data standard deviations"
    if dof > 0:
        return math.sqrt(chi2 / dof), "residuals"
    return None, "unknown"


def _uncertainties(V: np.ndarray, s: np.ndarray, rank: int, p: int,
                   sigma: float | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Standard errors (ln), null-space shares and correlations of the ``p`` analysed parameters."""
    seen, unseen = V[:, :rank], V[:, rank:]
    null_share = np.sqrt(np.sum(unseen**2, axis=1)) if p else np.zeros(0)
    cov_unit = (seen / s[:rank] ** 2) @ seen.T if rank else np.zeros((p, p))  # (JᵀJ)⁺ truncated at the rank
    se, corr = errors_from_covariance(cov_unit, null_share, sigma)
    return se, null_share, corr


def errors_from_covariance(cov_unit: np.ndarray, null_share: np.ndarray,
                           sigma: float | None) -> tuple[np.ndarray, np.ndarray]:
    """Standard errors of ln (inf where more than :data:`NULL_SHARE` of a parameter lies in the unseen combinations,
    NaN where σ is unknown) and correlations, from a covariance in units of σ² and the null-space shares."""
    d = np.sqrt(np.clip(np.diag(cov_unit), 0.0, None))
    determinable = null_share <= NULL_SHARE
    se = np.where(determinable, d * (sigma if sigma is not None else np.nan), np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = cov_unit / np.outer(d, d)
    corr[~determinable, :] = np.nan
    corr[:, ~determinable] = np.nan
    return se, corr


def combinations(V: np.ndarray, s: np.ndarray, rank: int, labels: tuple[str, ...],
                  sigma: float | None) -> tuple[Combination, ...]:
    """The ``rank`` determined combinations of the labels, one per nonzero singular value."""
    combos = []
    for k in range(rank):
        v = V[:, k]
        scale = float(np.abs(v).max())
        # over the labels: with the gauge removed they are the gauge-invariant EA/L², c/L, P/L²
        terms = tuple((lab, float(e / scale)) for lab, e in zip(labels, v) if abs(e / scale) >= 1e-6)
        se_k = None if sigma is None else sigma / (s[k] * scale)
        combos.append(Combination(exponents=terms, singular_value=float(s[k]), standard_error=se_k))
    return tuple(combos)

"""Modal sums: the retardation spectrum of a pencil and what is computed from it.

``C0 v = τ K0 v`` with ``VᵀK0V = I`` (τ ≥ 0 in s, τ = 0 for a mode the
tendons do not damp) gives, for the load ``b = −H0`` and the probe ``D0``,

    J(s) = D0 (K0 + s·C0)⁻¹ b = Σ_k ρ_k / (1 + s·τ_k),  ρ_k = (D0·v_k)(b·v_k),

which serves the compliance at every frequency (:func:`modal_compliance`),
creep and relaxation at every time, and the relaxation spectrum
``λ = 1/τ`` (:class:`RelaxationSpectrum`, :func:`relaxation_spectrum`).
Dense pencils give every mode (:class:`Modes`); sparse ones the Ritz pairs of
a Lanczos run (:mod:`tenscell.linear.krylov`), a spectrum of the same form.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._threads import hot_path

__all__ = ["Modes", "modal_compliance", "RelaxationSpectrum", "relaxation_spectrum", "ZERO_TIME"]

#: a retardation time below this fraction of the longest counts as zero (an undamped mode)
ZERO_TIME = 1e-12


class Modes:
    """``C0 v = τ K0 v`` for a dense pencil: ``J(s) = Σ ρ_k/(1 + s·τ_k)``.

    Attributes
    ----------
    tau : ndarray, shape (n,)
        Retardation times τ_k (s), ascending, ≥ 0 (0 for undamped modes).
    vectors : ndarray, shape (n, n)
        K0-orthonormal eigenvectors as columns (``VᵀK0V = I``); built on first use when the record
        was made with ``make_vectors`` (a compliance needs only τ and ρ).
    weights : ndarray, shape (n,)
        ``ρ_k = (D0·v_k)(b·v_k)`` (m/N), ``b = −H0``.
    """

    __slots__ = ("tau", "weights", "_vectors", "_make_vectors")

    def __init__(self, tau: np.ndarray, vectors: np.ndarray | None = None, weights: np.ndarray | None = None, *,
                 make_vectors=None):
        if weights is None or (vectors is None) == (make_vectors is None):
            raise TypeError("Modes needs tau, weights and either vectors or make_vectors")
        self.tau, self.weights = tau, weights
        self._vectors, self._make_vectors = vectors, make_vectors

    @property
    def vectors(self) -> np.ndarray:
        """K0-orthonormal eigenvectors as columns, shape (n, n)."""
        if self._vectors is None:
            self._vectors, self._make_vectors = self._make_vectors(), None
        return self._vectors


def modal_compliance(tau: np.ndarray, rho: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``J(iω) = Σ_k ρ_k/(1 + iωτ_k)`` (m/N) for ``tau``, ``rho`` of shape (..., n) and ω (rad/s) of shape (nf,).

    Real arithmetic: one batched ``(2 × n)(n × nf)`` product gives both parts.
    Returns shape (..., nf).
    """
    tau, rho = np.asarray(tau), np.asarray(rho)
    den = np.multiply.outer(tau * tau, w * w)
    den += 1.0
    np.divide(1.0, den, out=den)  # the same correctly rounded 1/x as np.reciprocal, which numpy does not vectorize (2× slower)
    weights = np.empty(rho.shape[:-1] + (2, rho.shape[-1]))
    weights[..., 0, :] = rho
    np.multiply(rho, tau, out=weights[..., 1, :])
    parts = weights @ den
    J = np.empty(parts.shape[:-2] + (w.size,), dtype=complex)
    J.real = parts[..., 0, :]
    np.multiply(parts[..., 1, :], -w, out=J.imag)  # written in place: no complex temporaries
    return J


def ritz_is_zero(tau: np.ndarray) -> np.ndarray:
    """Which retardation times count as zero (:data:`ZERO_TIME` of the longest): modes the tendons do not damp."""
    return tau <= ZERO_TIME * max(float(tau.max()) if tau.size else 0.0, 1e-300)


# ---- the relaxation spectrum -----------------------------------------------------------------------
@dataclass(frozen=True, eq=False, repr=False)
class RelaxationSpectrum:
    """Modes of the linear model: ``J(ω) = Σ_k r_k / (λ_k + iω)``.

    Attributes
    ----------
    rates : ndarray, shape (k,)
        Relaxation rates λ_k (1/s), ascending; ``K0 v = λ C0 v``. Dense
        models: all n of them; sparse models: the Ritz values of the Lanczos
        run from the load (the modes the load excites, converged so that
        ``J`` agrees with the full model to ``error_estimate``).
    residues : ndarray, shape (k,)
        ``r_k = (D0·v_k)(−H0·v_k)`` (m/(N·s)); non-negative when probe = load.
    modes : ndarray, shape (n, k)
        C0-orthonormal eigenvectors as columns. For sparse models these are
        the Ritz vectors, exact eigenvectors only where a Ritz pair has
        converged: a cluster of (nearly) equal rates, such as a lattice's
        identical local modes, is represented by fewer Ritz pairs carrying its
        total weight (what J needs; see :func:`tenscell.summary.relaxation_modes` for
        converged slowest modes).
    error_estimate : float
        Relative accuracy of the spectrum's ``J`` (0 for the dense, exact decomposition).
    """

    rates: np.ndarray
    residues: np.ndarray
    modes: np.ndarray
    error_estimate: float = 0.0

    @property
    def times(self) -> np.ndarray:
        """Relaxation times τ_k = 1/λ_k (s)."""
        return 1.0 / self.rates

    @property
    def weights(self) -> np.ndarray:
        """Compliance weights ``r_k/λ_k`` (m/N): each mode's share of the static compliance."""
        return self.residues / self.rates

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from .._results import format_repr, span

        return format_repr(
            f"RelaxationSpectrum: {self.rates.size} modes",
            f"rates λ {span(self.rates, '1/s')} (times {span(self.times, 's')})",
            f"static compliance Σ r/λ = {self.weights.sum():.6g} m/N; relative error of J {self.error_estimate:.2g}",
        )

    def to_dataframe(self):
        """One row per mode: ``rate_per_s, time_s, residue_m_per_Ns, weight_m_per_N``."""
        from .._results import dataframe

        return dataframe({"rate_per_s": self.rates, "time_s": self.times, "residue_m_per_Ns": self.residues,
                          "weight_m_per_N": self.weights})

    def plot(self, ax=None, **kw):
        """Each mode's compliance weight r/λ (m/N) against its relaxation time 1/λ (s), as stems."""
        from .._results import plotter

        spectrum_stems = plotter("spectrum_stems")

        return spectrum_stems(self.times, self.weights, ax=ax, xlabel="relaxation time 1/λ (s)",
                              ylabel="compliance weight r/λ (m/N)", **kw)


@hot_path
def relaxation_spectrum(lin) -> RelaxationSpectrum:
    """Solve ``K0 v = λ C0 v`` (rates λ in 1/s, ``vᵀC0v = 1``), dense or sparse.

    Dense models: the full spectrum from the model's one modal decomposition.
    Sparse models: the load-excited part, from the model's Lanczos run
    (:meth:`Pencil.retardation`); it needs probe = load.

    Raises
    ------
    ValueError
        If C0 is singular (e.g. the cell without intermediate filaments, whose
        damping leaves a mechanism undamped), so that some λ is infinite; or
        for a sparse model whose probe is not its load.
    """
    pencil = lin.pencil
    if not pencil.sparse:
        m = pencil.modes
        tau, rho, err = m.tau, m.weights, 0.0
        V = m.vectors
    else:
        if not pencil.probe_is_load:
            raise ValueError(
                f"the relaxation spectrum of the sparse model {lin.cell.describe()} is computed from the load; "
                "its probe is not the load (use creep_spectrum, whose retardation spectrum covers this case)"
            )
        err = pencil.retardation()[2]
        run = pencil.lanczos_runs(pencil.retardation_shift)[0]
        tau, rho = pencil._run_spectrum(run)  # in the order of the Ritz values θ, ascending
        V = run.ritz_vectors(np.arange(tau.size))
    if tau.size == 0 or np.any(ritz_is_zero(tau)):
        raise ValueError(
            f"the damping matrix C0 of {lin.cell.describe()} is singular (not positive definite), "
            "so the relaxation spectrum K0 v = λ C0 v is not defined; compliance() handles this case"
        )
    rates = 1.0 / tau
    # to C0-normalization: dense vectors are K0-normalized (vᵀC0v = τ), Ritz vectors Kσ-normalized (uᵀC0u = θ)
    V = V / np.sqrt(tau if not pencil.sparse else tau / (1.0 + pencil.retardation_shift * tau))
    order = np.argsort(rates)
    return RelaxationSpectrum(rates=rates[order], residues=(rho / tau)[order], modes=V[:, order],
                              error_estimate=err)


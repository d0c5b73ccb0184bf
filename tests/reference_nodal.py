"""Independent nodal reference implementation of the 30-element tensegrity cell.

This module is deliberately written WITHOUT using any code from ``tenscell``.
It describes the structure by the Cartesian positions of its movable nodes and
treats the six rigid struts as holonomic constraints (Lagrange multipliers),
which is a formulation completely different from the generalized (angle)
coordinates used by the library.  It is used by ``test_invariance.py`` to
cross-check the library's transfer function J(omega) = z/F.

Node numbering used here (13 nodes):

    0  A1    1  A2    2  A3        (fixed anchors, base triangle)
    3  C1    4  C2    5  C3        (free ends of the anchored struts A_i C_i)
    6  B1    7  B2    8  B3        (ends of the free struts B_i D_i)
    9  D1   10  D2   11  D3
   12  N                            (centre node)

Movable nodes are 3..12 (10 nodes, 30 coordinates), in that order.

Struts (head, tail), constraint g = |x_head - x_tail|^2 - L^2:
    (C1, A1), (C2, A2), (C3, A3), (B1, D1), (B2, D2), (B3, D3)

Tendon order: the 21 actin tendons (sorted node pairs, lexicographic order),
followed by the 12 intermediate filaments from strut ends 0..11 to N.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import null_space

N_NODES = 13
FIXED = (0, 1, 2)
MOVABLE = tuple(range(3, 13))
CENTRE = 12
NAMES = ("A1", "A2", "A3", "C1", "C2", "C3", "B1", "B2", "B3", "D1", "D2", "D3", "N")
STRUTS = ((3, 0), (4, 1), (5, 2), (6, 9), (7, 10), (8, 11))
DELTA_REGULAR = math.atan(math.sqrt(2.0))


def _u(delta: float, alpha: float) -> np.ndarray:
    return np.array(
        [math.sin(delta) * math.cos(alpha), math.sin(delta) * math.sin(alpha), math.cos(delta)]
    )


def reference_nodes(alpha: float, delta: float, L: float = 1.0) -> np.ndarray:
    """(13, 3) node positions of the reference member q0(alpha, delta)."""
    s = L * math.sqrt(3.0 / 8.0)
    A = np.array(
        [
            [-s / 2.0, -s / (2.0 * math.sqrt(3.0)), 0.0],
            [0.0, s / math.sqrt(3.0), 0.0],
            [s / 2.0, -s / (2.0 * math.sqrt(3.0)), 0.0],
        ]
    )
    az = (alpha, alpha + 4.0 * math.pi / 3.0, alpha + 2.0 * math.pi / 3.0)
    U = np.array([_u(delta, a) for a in az])
    C = A + L * U
    z0s = [(U[i] @ A[i] + L / 2.0) / math.cos(delta) for i in range(3)]
    assert max(z0s) - min(z0s) < 1e-12 * max(1.0, abs(z0s[0])), z0s
    O = np.array([0.0, 0.0, z0s[0]])
    # point reflection through O: B1D1 <-> A3C3, B2D2 <-> A1C1, B3D3 <-> A2C2
    partner = (2, 0, 1)
    B = np.array([2.0 * O - A[p] for p in partner])
    D = np.array([2.0 * O - C[p] for p in partner])
    X = np.vstack([A, C, B, D, O[None, :]])
    return X


def sphere_centre(alpha: float, delta: float, L: float = 1.0) -> np.ndarray:
    return reference_nodes(alpha, delta, L)[CENTRE].copy()


def tendon_pairs(L: float = 1.0):
    """Tendon topology: list of (a, b) node pairs and list of family strings.

    Actin tendons are identified on the regular member as strut-end pairs at
    distance s = L*sqrt(3/8); the 3 base edges (fixed-fixed) are dropped.
    """
    X = reference_nodes(0.0, DELTA_REGULAR, L)
    s = L * math.sqrt(3.0 / 8.0)
    strut_set = {frozenset(p) for p in STRUTS}
    actin = []
    for a in range(12):
        for b in range(a + 1, 12):
            if abs(np.linalg.norm(X[a] - X[b]) - s) < 1e-9 * L:
                assert frozenset((a, b)) not in strut_set
                actin.append((a, b))
    counts = np.zeros(12, int)
    for a, b in actin:
        counts[a] += 1
        counts[b] += 1
    assert len(actin) == 24 and np.all(counts == 4), (len(actin), counts)
    actin = [p for p in actin if not (p[0] in FIXED and p[1] in FIXED)]
    assert len(actin) == 21
    ifs = [(a, CENTRE) for a in range(12)]
    pairs = actin + ifs
    families = ["actin"] * len(actin) + ["intermediate_filament"] * len(ifs)
    return pairs, families


def _dof(node: int) -> int:
    """Index of the first coordinate of a movable node in the 30-vector."""
    return 3 * (node - 3)


def equilibrium_matrix(X: np.ndarray, pairs) -> np.ndarray:
    """(30, 33 + 6) matrix: columns = unit tendon tensions, then unit strut
    compressions; rows = net force on movable nodes."""
    nt = len(pairs)
    A = np.zeros((30, nt + len(STRUTS)))
    for j, (a, b) in enumerate(pairs):
        e = (X[b] - X[a]) / np.linalg.norm(X[b] - X[a])
        if a >= 3:
            A[_dof(a) : _dof(a) + 3, j] += e  # tension pulls a towards b
        if b >= 3:
            A[_dof(b) : _dof(b) + 3, j] -= e
    for k, (h, t) in enumerate(STRUTS):
        e = (X[h] - X[t]) / np.linalg.norm(X[h] - X[t])
        if h >= 3:
            A[_dof(h) : _dof(h) + 3, nt + k] += e  # compression pushes apart
        if t >= 3:
            A[_dof(t) : _dof(t) + 3, nt + k] -= e
    return A


def self_stress(alpha: float, delta: float, L: float = 1.0, return_struts: bool = False):
    """Unit self-stress T0 (33,) with all IF tensions equal, ||T0|| = 1, positive.

    Returns (T0, S0) if return_struts, with S0 the strut compressions of the same
    state (same scaling).
    """
    X = reference_nodes(alpha, delta, L)
    pairs, fam = tendon_pairs(L)
    A = equilibrium_matrix(X, pairs)
    if_idx = [j for j, f in enumerate(fam) if f == "intermediate_filament"]
    rows = []
    for j in if_idx[1:]:
        r = np.zeros(A.shape[1])
        r[j] = 1.0
        r[if_idx[0]] = -1.0
        rows.append(r)
    M = np.vstack([A, np.array(rows)])
    ns = null_space(M, rcond=1e-10)
    if ns.shape[1] != 1:
        raise ValueError(f"self-stress space with equal IFs has dimension {ns.shape[1]}")
    v = ns[:, 0]
    nt = len(pairs)
    T = v[:nt]
    scale = np.linalg.norm(T)
    T = T / scale
    S = v[nt:] / scale
    # sign: tensions positive (use the largest-magnitude entry to decide)
    if T[np.argmax(np.abs(T))] < 0:
        T, S = -T, -S
    if return_struts:
        return T, S
    return T


def _broadcast(v, n):
    v = np.asarray(v, float)
    if v.ndim == 0:
        return np.full(n, float(v))
    assert v.shape == (n,)
    return v


def _lengths(X, pairs):
    return np.array([np.linalg.norm(X[b] - X[a]) for a, b in pairs])


def _full(xm: np.ndarray, X0: np.ndarray) -> np.ndarray:
    X = X0.copy()
    X[3:] = xm.reshape(10, 3)
    return X


def tendon_forces(X: np.ndarray, pairs, l0, EA) -> np.ndarray:
    """(30,) nodal forces of the elastic tendons T = EA (l/l0 - 1) on movable nodes."""
    f = np.zeros(30)
    for j, (a, b) in enumerate(pairs):
        d = X[b] - X[a]
        l = np.linalg.norm(d)
        T = EA[j] * (l / l0[j] - 1.0)
        e = d / l
        if a >= 3:
            f[_dof(a) : _dof(a) + 3] += T * e
        if b >= 3:
            f[_dof(b) : _dof(b) + 3] -= T * e
    return f


def constraint_values(X: np.ndarray, L: float) -> np.ndarray:
    return np.array([np.sum((X[h] - X[t]) ** 2) - L**2 for h, t in STRUTS])


def constraint_jacobian(X: np.ndarray) -> np.ndarray:
    """G = dg/dx, (6, 30), g_k = |x_h - x_t|^2 - L^2."""
    G = np.zeros((len(STRUTS), 30))
    for k, (h, t) in enumerate(STRUTS):
        d = X[h] - X[t]
        if h >= 3:
            G[k, _dof(h) : _dof(h) + 3] += 2.0 * d
        if t >= 3:
            G[k, _dof(t) : _dof(t) + 3] -= 2.0 * d
    return G


def constraint_hessian(mu: np.ndarray) -> np.ndarray:
    """sum_k mu_k d2g_k/dx2, (30, 30)."""
    H = np.zeros((30, 30))
    I = np.eye(3)
    for k, (h, t) in enumerate(STRUTS):
        for p, sp in ((h, 1.0), (t, -1.0)):
            for q, sq in ((h, 1.0), (t, -1.0)):
                if p >= 3 and q >= 3:
                    H[_dof(p) : _dof(p) + 3, _dof(q) : _dof(q) + 3] += 2.0 * mu[k] * sp * sq * I
    return H


def _assemble_pair(K, a, b, k3):
    for p, sp in ((a, 1.0), (b, -1.0)):
        for q, sq in ((a, 1.0), (b, -1.0)):
            if p >= 3 and q >= 3:
                K[_dof(p) : _dof(p) + 3, _dof(q) : _dof(q) + 3] += sp * sq * k3


class NodalModel:
    """Linearized nodal model about q0(alpha, delta) with prestress P."""

    def __init__(self, alpha, delta, L=1.0, P=1000.0, EA=1.0, c=1.0):
        self.alpha, self.delta, self.L, self.P = alpha, delta, L, P
        self.X0 = reference_nodes(alpha, delta, L)
        self.pairs, self.families = tendon_pairs(L)
        nt = len(self.pairs)
        self.EA = _broadcast(EA, nt)
        self.c = _broadcast(c, nt)
        self.T0 = self_stress(alpha, delta, L)
        self.T = P * self.T0
        self.l = _lengths(self.X0, self.pairs)
        self.l0 = self.l * self.EA / (self.T + self.EA)
        # equilibrium with Lagrange multipliers: f_tendons + G^T mu = 0
        self.G = constraint_jacobian(self.X0)
        f = tendon_forces(self.X0, self.pairs, self.l0, self.EA)
        self.f_ref = f
        mu, *_ = np.linalg.lstsq(self.G.T, -f, rcond=None)
        self.mu = mu
        self.eq_residual = f + self.G.T @ mu
        # tangent stiffness of the tendon potential V = sum 1/2 (EA/l0)(l - l0)^2
        Kx = np.zeros((30, 30))
        Cx = np.zeros((30, 30))
        for j, (a, b) in enumerate(self.pairs):
            d = self.X0[b] - self.X0[a]
            lj = np.linalg.norm(d)
            e = d / lj
            ee = np.outer(e, e)
            k3 = (self.EA[j] / self.l0[j]) * ee + (self.T[j] / lj) * (np.eye(3) - ee)
            _assemble_pair(Kx, a, b, k3)
            _assemble_pair(Cx, a, b, self.c[j] * ee)
        self.Kx, self.Cx = Kx, Cx
        # Lagrangian L = V - F.x - mu.g  =>  Hessian = Kx - sum mu_k d2g_k
        self.Z = null_space(self.G)  # (30, 24)
        self.K_full = Kx - constraint_hessian(mu)
        self.K_red = self.Z.T @ self.K_full @ self.Z
        self.C_red = self.Z.T @ Cx @ self.Z
        b = np.zeros(30)
        b[_dof(6) + 2] = 0.5  # B1 z
        b[_dof(9) + 2] = 0.5  # D1 z
        self.b = b
        self.bz = self.Z.T @ b

    def strut_compressions(self):
        """Axial compression force of each strut, S_k = 2 L mu_k."""
        return 2.0 * self.L * self.mu

    def compliance(self, f_hz):
        f_hz = np.asarray(f_hz, float)
        out = np.empty(f_hz.shape, complex)
        for idx, fh in np.ndenumerate(f_hz):
            w = 2.0 * math.pi * fh
            q = np.linalg.solve(self.K_red + 1j * w * self.C_red, self.bz)
            out[idx] = self.bz @ q
        return out

    def moduli(self, f_hz):
        G = (0.5 / self.L) / self.compliance(f_hz)
        return G.real, G.imag

    # ---- nonlinear static problem (for finite-difference checks) ----------
    def static_solve(self, F: float, tol: float = 1e-13, maxit: int = 50):
        """Nonlinear constrained equilibrium under vertical force F at the
        centre of B1D1.  Newton on (x, mu) with a finite-difference Jacobian of
        the exact nonlinear residual.  Returns the 30-vector of movable coords."""
        x = self.X0[3:].reshape(-1).copy()
        mu = self.mu.copy()
        Fext = F * self.b  # F/2 at B1 and F/2 at D1 (z components)

        def resid(y):
            xm, m = y[:30], y[30:]
            X = _full(xm, self.X0)
            r1 = tendon_forces(X, self.pairs, self.l0, self.EA) + Fext + constraint_jacobian(X).T @ m
            r2 = constraint_values(X, self.L)
            return np.concatenate([r1, r2])

        y = np.concatenate([x, mu])
        scale = max(1.0, np.max(np.abs(self.T)))
        for _ in range(maxit):
            r = resid(y)
            if np.max(np.abs(r)) < tol * scale:
                break
            Jm = np.empty((36, 36))
            h = 1e-7 * self.L
            for i in range(36):
                yp = y.copy()
                ym = y.copy()
                hi = h if i < 30 else 1e-7 * max(1.0, abs(y[i]))
                yp[i] += hi
                ym[i] -= hi
                Jm[:, i] = (resid(yp) - resid(ym)) / (2 * hi)
            y = y - np.linalg.solve(Jm, r)
        else:
            raise RuntimeError("static Newton did not converge")
        return y[:30], y[30:], np.max(np.abs(resid(y)))


def compliance(alpha, delta, L, P, EA, c, f_hz):
    """J(omega) = z/F (m/N) for vertical load at the centre of B1D1."""
    return NodalModel(alpha, delta, L, P, EA, c).compliance(f_hz)

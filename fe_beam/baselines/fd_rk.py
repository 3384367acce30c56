"""Finite differences in space + adaptive Runge-Kutta in time: the source paper's own scheme.

A plain numpy/scipy reference solver for the planar large-displacement beam of
docs/theory.md (eqs. 4-6 of the source paper), independent of FEniCSx. It is used to cross-validate
and benchmark the finite-element statics and the generalised-alpha dynamics.

Discretisation
--------------
Uniform nodes ``x_i = i h`` (``i = 0..N``, ``h = L/N``) carry ``u_i, v_i, theta_i``. The strains
live at the midpoints ``x_{i+1/2}`` (a staggered grid)::

    a      = 1 + (u_{i+1} - u_i)/h          (= 1 + u')
    b      = (v_{i+1} - v_i)/h              (= v')
    th     = (theta_i + theta_{i+1})/2
    kappa  = (theta_{i+1} - theta_i)/h
    1 + e  = a cos(th) + b sin(th)
    g      = b cos(th) - a sin(th)
    eps    = ((1 + e)^2 + g^2 - 1)/2 = (a^2 + b^2 - 1)/2

and the discrete strain energy is ``E_h(q) = sum_mid h W(eps, e, g, kappa)``. The internal
forces are ``-grad E_h`` (analytic, vectorised chain rule), the masses are lumped
(``rhoA h``, ``rhoI h`` at interior nodes, half of that at the two end nodes). The semi-discrete
equations ``M q'' + C q' + grad E_h(q) = f(t)`` are the energy-consistent, second-order central
difference form of eqs. (4)-(6); with the midpoint rule for the shear/axial terms the scheme is
locking-free (it equals linear elements with one-point integration).

The vector of unknowns is ``q = [u_0..u_N, v_0..v_N, theta_0..theta_N]`` (length ``3 (N+1)``).
Supports are homogeneous: constrained entries of ``q`` are zero.
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.integrate
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

LAWS = ("nonstandard", "reissner")
SUPPORTS = ("clamped-free", "pinned-roller")
RK_METHODS = ("RK45", "DOP853")

__all__ = [
    "FDBeamParameters",
    "FDResult",
    "LAWS",
    "SUPPORTS",
    "constant_one",
    "external_force",
    "free_dofs",
    "hessian",
    "internal_force",
    "linear_frequencies",
    "linear_modes",
    "lumped_damping",
    "lumped_mass",
    "midpoint_strains",
    "nodes",
    "simulate",
    "solve_static",
    "split",
    "strain_energy",
    "tip",
]


def constant_one(t: float) -> float:
    """Default load time function, ``f(t) = 1``."""
    return 1.0


# ------------------------------------------------------------------------------------------------
# Parameters
# ------------------------------------------------------------------------------------------------
def _check_real(name: str, value, *, positive: bool = False, nonnegative: bool = False) -> None:
    """Raise ValueError unless ``value`` is a finite real number with the requested sign."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"FDBeamParameters.{name} must be a real number, got {value!r}")
    if not math.isfinite(float(value)):
        raise ValueError(f"FDBeamParameters.{name} must be finite, got {value!r}")
    if positive and not value > 0:
        raise ValueError(f"FDBeamParameters.{name} must be > 0, got {value!r}")
    if nonnegative and not value >= 0:
        raise ValueError(f"FDBeamParameters.{name} must be >= 0, got {value!r}")


@dataclass(frozen=True)
class FDBeamParameters:
    """Beam, discretisation and loads of the finite-difference reference solver.

    Parameters
    ----------
    L : float
        Reference length (> 0).
    n_intervals : int
        Number of grid intervals N (>= 2); nodes ``x_i = i L / N``.
    EA, GA, EI : float
        Axial, shear (shear correction already included) and bending stiffness (> 0).
    EI3, EI4 : float
        ``E I3`` (any sign) and ``E I4`` (>= 0), third and fourth moments of the section; only
        used by the non-standard law.
    rhoA, rhoI : float
        Mass and rotary inertia per unit length (>= 0; both must be > 0 for dynamics).
    c : float
        Viscous damping per unit length on ``u_t`` and ``v_t`` (>= 0), as in eqs. (4)-(5).
    law : {"nonstandard", "reissner"}
        Strain energy density (see :func:`strain_energy`).
    supports : {"clamped-free", "pinned-roller"}
        ``clamped-free``: ``u = v = theta = 0`` at ``x = 0``. ``pinned-roller``: ``u = v = 0`` at
        ``x = 0`` and ``v = 0`` at ``x = L``; ``theta`` free at both ends.
    Px, Py : float
        Dead tip force at ``x = L``, global components.
    M : float
        Tip moment at ``x = L`` (counterclockwise positive).
    qx, qy : float
        Distributed dead force per unit reference length, global components.
    load_time : callable
        ``f(t)``; every load is multiplied by it in :func:`simulate` (default ``f = 1``).
    """

    L: float
    n_intervals: int
    EA: float
    GA: float
    EI: float
    EI3: float = 0.0
    EI4: float = 0.0
    rhoA: float = 0.0
    rhoI: float = 0.0
    c: float = 0.0
    law: str = "nonstandard"
    supports: str = "clamped-free"
    Px: float = 0.0
    Py: float = 0.0
    M: float = 0.0
    qx: float = 0.0
    qy: float = 0.0
    load_time: Callable[[float], float] = constant_one

    def __post_init__(self) -> None:
        n = self.n_intervals
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
            raise ValueError(f"FDBeamParameters.n_intervals must be an integer >= 2, got {n!r}")
        for name in ("L", "EA", "GA", "EI"):
            _check_real(name, getattr(self, name), positive=True)
        for name in ("EI4", "rhoA", "rhoI", "c"):
            _check_real(name, getattr(self, name), nonnegative=True)
        for name in ("EI3", "Px", "Py", "M", "qx", "qy"):
            _check_real(name, getattr(self, name))
        if self.law not in LAWS:
            raise ValueError(f"FDBeamParameters.law must be one of {LAWS}, got {self.law!r}")
        if self.supports not in SUPPORTS:
            raise ValueError(
                f"FDBeamParameters.supports must be one of {SUPPORTS}, got {self.supports!r}"
            )
        if not callable(self.load_time):
            raise ValueError(
                f"FDBeamParameters.load_time must be callable t -> float, got {self.load_time!r}"
            )

    @property
    def h(self) -> float:
        """Grid spacing ``h = L / N``."""
        return self.L / self.n_intervals

    @property
    def n_dofs(self) -> int:
        """Number of entries of ``q``: ``3 (N + 1)``."""
        return 3 * (self.n_intervals + 1)


# ------------------------------------------------------------------------------------------------
# Layout helpers
# ------------------------------------------------------------------------------------------------
def nodes(params: FDBeamParameters) -> np.ndarray:
    """Node coordinates ``x_i = i h``, ``i = 0..N``."""
    return np.linspace(0.0, params.L, params.n_intervals + 1)


def split(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Views ``(u, v, theta)`` of ``q = [u_0..u_N, v_0..v_N, theta_0..theta_N]`` (last axis)."""
    q = np.asarray(q, dtype=float)
    n1 = q.shape[-1] // 3
    return q[..., :n1], q[..., n1 : 2 * n1], q[..., 2 * n1 :]


def tip(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tip quantities ``(u(L), v(L), theta(L))`` of one state or a stack of states."""
    u, v, th = split(q)
    return u[..., -1], v[..., -1], th[..., -1]


def free_dofs(params: FDBeamParameters) -> np.ndarray:
    """Boolean mask of the unconstrained entries of ``q`` (see ``FDBeamParameters.supports``)."""
    n1 = params.n_intervals + 1
    free = np.ones(3 * n1, dtype=bool)
    if params.supports == "clamped-free":
        free[[0, n1, 2 * n1]] = False
    else:  # pinned-roller
        free[[0, n1, 2 * n1 - 1]] = False
    return free


def _nodal_weights(params: FDBeamParameters) -> np.ndarray:
    """Lumping weights ``w_i = h`` at interior nodes and ``h/2`` at the end nodes."""
    w = np.full(params.n_intervals + 1, params.h)
    w[[0, -1]] *= 0.5
    return w


def lumped_mass(params: FDBeamParameters) -> np.ndarray:
    """Diagonal of the lumped mass: ``[rhoA w, rhoA w, rhoI w]``, ``w_i = h`` (``h/2`` at ends)."""
    w = _nodal_weights(params)
    return np.concatenate([params.rhoA * w, params.rhoA * w, params.rhoI * w])


def lumped_damping(params: FDBeamParameters) -> np.ndarray:
    """Diagonal of the lumped viscous damping: ``[c w, c w, 0]`` (no rotational damping)."""
    w = _nodal_weights(params)
    return np.concatenate([params.c * w, params.c * w, np.zeros_like(w)])


def external_force(params: FDBeamParameters, factor: float = 1.0) -> np.ndarray:
    """Nodal dead-load vector ``factor * f``.

    ``f_u = qx w + Px delta_iN``, ``f_v = qy w + Py delta_iN``, ``f_theta = M delta_iN``, with
    the lumping weights ``w_i = h`` (``h/2`` at the end nodes). It is the gradient of the external
    work ``f . q``.
    """
    w = _nodal_weights(params)
    fu, fv, fth = params.qx * w, params.qy * w, np.zeros_like(w)
    fu[-1] += params.Px
    fv[-1] += params.Py
    fth[-1] += params.M
    return factor * np.concatenate([fu, fv, fth])


# ------------------------------------------------------------------------------------------------
# Strains and strain energy
# ------------------------------------------------------------------------------------------------
def midpoint_strains(params: FDBeamParameters, q: np.ndarray) -> dict[str, np.ndarray]:
    """Strain measures at the N midpoints.

    Returns a dict with ``a = 1 + u'``, ``b = v'``, ``th`` (midpoint rotation), ``kappa``,
    ``c = cos th``, ``s = sin th``, ``E1 = 1 + e = a c + b s``, ``g = b c - a s`` and
    ``eps = (a^2 + b^2 - 1)/2``, all of shape ``(N,)``.
    """
    nodal = np.asarray(q, dtype=float).reshape(3, params.n_intervals + 1)
    diff = np.diff(nodal, axis=1) * (1.0 / params.h)
    a, b, kappa = 1.0 + diff[0], diff[1], diff[2]
    th = 0.5 * (nodal[2, :-1] + nodal[2, 1:])
    c, s = np.cos(th), np.sin(th)
    return {
        "a": a,
        "b": b,
        "th": th,
        "kappa": kappa,
        "c": c,
        "s": s,
        "E1": a * c + b * s,
        "g": b * c - a * s,
        "eps": 0.5 * (a * a + b * b - 1.0),
    }


def _energy_density(params: FDBeamParameters, st: dict[str, np.ndarray]) -> np.ndarray:
    """Strain energy per unit reference length at the midpoints.

    nonstandard: ``W = EA eps^2/2 + GA g^2/2 + EI k^2 ((1+e)^2 + eps)/2 + EI3 k^3 (1+e)/2
    + EI4 k^4/8``; reissner: ``W_R = EA e^2/2 + GA g^2/2 + EI k^2/2``.
    """
    E1, g, eps, k = st["E1"], st["g"], st["eps"], st["kappa"]
    p = params
    if p.law == "reissner":
        return 0.5 * (p.EA * (E1 - 1.0) ** 2 + p.GA * g**2 + p.EI * k**2)
    return (
        0.5 * p.EA * eps**2
        + 0.5 * p.GA * g**2
        + 0.5 * p.EI * k**2 * (E1**2 + eps)
        + 0.5 * p.EI3 * k**3 * E1
        + 0.125 * p.EI4 * k**4
    )


def _energy_gradient_z(params: FDBeamParameters, st: dict[str, np.ndarray]) -> np.ndarray:
    """First partials of W with respect to ``z = (eps, E1, g, kappa)``, shape ``(4, N)``.

    nonstandard::

        W_eps = EA eps + EI k^2/2,    W_E1 = EI k^2 E1 + EI3 k^3/2,    W_g = GA g,
        W_k   = EI k (E1^2 + eps) + 3/2 EI3 k^2 E1 + EI4 k^3/2;

    reissner: ``W_eps = 0``, ``W_E1 = EA (E1 - 1)``, ``W_g = GA g``, ``W_k = EI k``.
    """
    E1, g, eps, k = st["E1"], st["g"], st["eps"], st["kappa"]
    p = params
    if p.law == "reissner":
        return np.array([np.zeros_like(k), p.EA * (E1 - 1.0), p.GA * g, p.EI * k])
    k2 = k * k
    return np.array(
        [
            p.EA * eps + 0.5 * p.EI * k2,
            k2 * (p.EI * E1 + 0.5 * p.EI3 * k),
            p.GA * g,
            k * (p.EI * (E1 * E1 + eps) + 1.5 * p.EI3 * k * E1 + 0.5 * p.EI4 * k2),
        ]
    )


def _energy_hessian_z(params: FDBeamParameters, st: dict[str, np.ndarray]) -> np.ndarray:
    """Second partials of W with respect to ``z = (eps, E1, g, kappa)``, shape ``(4, 4, N)``.

    nonstandard: ``W_eps,eps = EA``, ``W_eps,k = EI k``, ``W_E1,E1 = EI k^2``,
    ``W_E1,k = 2 EI k E1 + 3/2 EI3 k^2``, ``W_g,g = GA``,
    ``W_k,k = EI (E1^2 + eps) + 3 EI3 k E1 + 3/2 EI4 k^2``, others zero;
    reissner: ``diag(0, EA, GA, EI)``.
    """
    E1, eps, k = st["E1"], st["eps"], st["kappa"]
    p = params
    Wzz = np.zeros((4, 4) + k.shape)
    Wzz[2, 2] = p.GA
    if p.law == "reissner":
        Wzz[1, 1] = p.EA
        Wzz[3, 3] = p.EI
        return Wzz
    Wzz[0, 0] = p.EA
    Wzz[0, 3] = Wzz[3, 0] = p.EI * k
    Wzz[1, 1] = p.EI * k**2
    Wzz[1, 3] = Wzz[3, 1] = 2.0 * p.EI * k * E1 + 1.5 * p.EI3 * k**2
    Wzz[3, 3] = p.EI * (E1**2 + eps) + 3.0 * p.EI3 * k * E1 + 1.5 * p.EI4 * k**2
    return Wzz


def strain_energy(params: FDBeamParameters, q: np.ndarray) -> float:
    """Discrete strain energy ``E_h(q) = sum_mid h W(eps, e, g, kappa)``."""
    return float(params.h * np.sum(_energy_density(params, midpoint_strains(params, q))))


def _local_gradient(Wz: np.ndarray, st: dict[str, np.ndarray]) -> np.ndarray:
    """``dW/dy`` for ``y = (a, b, th, kappa)``, shape ``(4, N)``.

    With ``eps_a = a, eps_b = b``, ``E1_a = c, E1_b = s, E1_th = g``,
    ``g_a = -s, g_b = c, g_th = -E1``::

        W_a = W_eps a + W_E1 c - W_g s,   W_b = W_eps b + W_E1 s + W_g c,
        W_th = W_E1 g - W_g E1,           W_kappa = W_k.
    """
    a, b, c, s, E1, g = st["a"], st["b"], st["c"], st["s"], st["E1"], st["g"]
    We, WE1, Wg, Wk = Wz
    return np.array([We * a + WE1 * c - Wg * s, We * b + WE1 * s + Wg * c, WE1 * g - Wg * E1, Wk])


def internal_force(params: FDBeamParameters, q: np.ndarray) -> np.ndarray:
    """Gradient ``dE_h/dq`` (the internal force vector; the force on the nodes is its negative).

    With ``a_i = 1 + (u_{i+1} - u_i)/h``, ``th_i = (theta_i + theta_{i+1})/2`` and
    ``kappa_i = (theta_{i+1} - theta_i)/h``::

        dE_h/du_j     = W_a(j-1/2) - W_a(j+1/2)           (same for v with W_b)
        dE_h/dtheta_j = W_k(j-1/2) - W_k(j+1/2) + h/2 (W_th(j-1/2) + W_th(j+1/2))

    where terms at non-existent midpoints are dropped (see :func:`_local_gradient` for ``W_y``).
    """
    st = midpoint_strains(params, q)
    Wa, Wb, Wth, Wk = _local_gradient(_energy_gradient_z(params, st), st)
    n1 = params.n_intervals + 1
    grad = np.zeros(3 * n1)
    gu, gv, gth = grad[:n1], grad[n1 : 2 * n1], grad[2 * n1 :]
    gu[1:] += Wa
    gu[:-1] -= Wa
    gv[1:] += Wb
    gv[:-1] -= Wb
    half = 0.5 * params.h * Wth
    gth[1:] += Wk + half
    gth[:-1] += half - Wk
    return grad


def _local_hessian(Wz: np.ndarray, Wzz: np.ndarray, st: dict[str, np.ndarray]) -> np.ndarray:
    """``d2W/dy2`` for ``y = (a, b, th, kappa)``, shape ``(N, 4, 4)``.

    ``W_yy = J^T W_zz J + W_eps eps_yy + W_E1 E1_yy + W_g g_yy`` with ``J = dz/dy`` and the
    non-zero second derivatives ``eps_aa = eps_bb = 1``, ``E1_ath = -s, E1_bth = c,
    E1_thth = -E1``, ``g_ath = -c, g_bth = -s, g_thth = -g``.
    """
    a, b, c, s, E1, g = st["a"], st["b"], st["c"], st["s"], st["E1"], st["g"]
    n = a.shape[0]
    J = np.zeros((n, 4, 4))
    J[:, 0, 0], J[:, 0, 1] = a, b
    J[:, 1, 0], J[:, 1, 1], J[:, 1, 2] = c, s, g
    J[:, 2, 0], J[:, 2, 1], J[:, 2, 2] = -s, c, -E1
    J[:, 3, 3] = 1.0
    H = np.einsum("nzi,zwn,nwj->nij", J, Wzz, J)
    We, WE1, Wg, _ = Wz
    H[:, 0, 0] += We
    H[:, 1, 1] += We
    H[:, 0, 2] += -WE1 * s - Wg * c
    H[:, 1, 2] += WE1 * c - Wg * s
    H[:, 2, 0] = H[:, 0, 2]
    H[:, 2, 1] = H[:, 1, 2]
    H[:, 2, 2] += -WE1 * E1 - Wg * g
    return H


def hessian(params: FDBeamParameters, q: np.ndarray) -> scipy.sparse.csr_matrix:
    """Analytic Hessian ``d2E_h/dq2`` (tangent stiffness), sparse, all ``3 (N+1)`` dofs.

    ``K = sum_mid h B^T W_yy B`` with ``B = dy/dq_local`` for the local dofs
    ``(u_i, u_{i+1}, v_i, v_{i+1}, theta_i, theta_{i+1})``.
    """
    st = midpoint_strains(params, q)
    Hy = _local_hessian(_energy_gradient_z(params, st), _energy_hessian_z(params, st), st)
    h, n, n1 = params.h, params.n_intervals, params.n_intervals + 1
    B = np.array(
        [
            [-1 / h, 1 / h, 0, 0, 0, 0],
            [0, 0, -1 / h, 1 / h, 0, 0],
            [0, 0, 0, 0, 0.5, 0.5],
            [0, 0, 0, 0, -1 / h, 1 / h],
        ]
    )
    Ke = h * np.einsum("ai,nab,bj->nij", B, Hy, B)
    j = np.arange(n)
    dofs = np.stack([j, j + 1, n1 + j, n1 + j + 1, 2 * n1 + j, 2 * n1 + j + 1], axis=1)
    rows = np.repeat(dofs, 6, axis=1).ravel()
    cols = np.tile(dofs, (1, 6)).ravel()
    K = scipy.sparse.coo_matrix((Ke.ravel(), (rows, cols)), shape=(3 * n1, 3 * n1))
    return K.tocsr()


# ------------------------------------------------------------------------------------------------
# Statics
# ------------------------------------------------------------------------------------------------
def _scaled_norm(params: FDBeamParameters, dq: np.ndarray) -> float:
    """``max(|du|/L, |dv|/L, |dtheta|)``: a dimensionless size of a displacement increment."""
    du, dv, dth = split(dq)
    return float(max(np.max(np.abs(du)), np.max(np.abs(dv))) / params.L + np.max(np.abs(dth)))


def _newton(params, q, factor, free, tol, max_iter):
    """Newton iterations on ``grad E_h(q) = factor f`` over the free dofs; ``(q, converged)``."""
    f = external_force(params, factor)
    for _ in range(max_iter):
        r = (internal_force(params, q) - f)[free]
        K = hessian(params, q)[free][:, free].tocsc()
        dq = np.zeros_like(q)
        dq[free] = -scipy.sparse.linalg.spsolve(K, r)
        if not np.all(np.isfinite(dq)):
            return q, False
        q = q + dq
        if _scaled_norm(params, dq) < tol:
            return q, True
    return q, False


def solve_static(
    params: FDBeamParameters,
    load_factor: float = 1.0,
    steps: int = 10,
    *,
    tol: float = 1e-10,
    max_iter: int = 25,
    max_correction: float = 0.25,
    max_cutbacks: int = 12,
) -> np.ndarray:
    """Static equilibrium ``grad E_h(q) = lambda f`` by Newton's method with load stepping.

    The load factor goes from 0 to ``load_factor`` in ``steps`` equal increments. Each step starts
    from a secant predictor; a step is rejected and halved if Newton fails or if the converged
    solution differs from the predictor by more than ``max_correction`` (scaled norm
    ``max|du, dv|/L + max|dtheta|``), which keeps the path on the branch connected to the
    unloaded state. Returns the full ``q`` (constrained entries zero).
    """
    if steps < 1:
        raise ValueError(f"solve_static: steps must be >= 1, got {steps!r}")
    free = free_dofs(params)
    q_prev = np.zeros(params.n_dofs)
    q_prev2, lam_prev, dlam_prev = None, 0.0, None
    dlam = load_factor / steps
    cuts = 0
    while abs(load_factor - lam_prev) > 1e-14 * max(1.0, abs(load_factor)):
        dlam = math.copysign(min(abs(dlam), abs(load_factor - lam_prev)), load_factor)
        q_pred = q_prev.copy()
        if q_prev2 is not None:
            q_pred += (dlam / dlam_prev) * (q_prev - q_prev2)
        q_new, ok = _newton(params, q_pred.copy(), lam_prev + dlam, free, tol, max_iter)
        if not ok or _scaled_norm(params, q_new - q_pred) > max_correction:
            cuts += 1
            if cuts > max_cutbacks:
                raise RuntimeError(
                    f"solve_static: no convergence at load factor {lam_prev + dlam:.6g} after "
                    f"{max_cutbacks} step cutbacks"
                )
            dlam *= 0.5
            continue
        q_prev2, q_prev = q_prev, q_new
        lam_prev, dlam_prev = lam_prev + dlam, dlam
    return q_prev


# ------------------------------------------------------------------------------------------------
# Linearised vibration
# ------------------------------------------------------------------------------------------------
def linear_modes(
    params: FDBeamParameters, count: int, q_ref: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Lowest natural frequencies (Hz) and mode shapes of the linearised discrete system.

    Solves ``K phi = omega^2 M phi`` on the free dofs with ``K = d2E_h/dq2`` at ``q_ref``
    (default: undeformed state, no prestress) and the lumped ``M``; ``f = omega / (2 pi)``.
    For a positive definite ``K`` the inverse problem ``M phi = mu K phi``, ``mu = 1/omega^2``,
    is solved for its largest ``mu`` (accurate even when ``EA/EI`` and ``GA/rhoI`` make the
    direct problem hopelessly ill-conditioned); otherwise the direct problem is used.
    Returns ``(f, phi)`` with ``phi`` of shape ``(count, 3 (N+1))``, mass-normalised
    (``phi M phi^T = I``), ascending in frequency.
    """
    if params.rhoA <= 0 or params.rhoI <= 0:
        raise ValueError(
            f"linear_modes needs FDBeamParameters.rhoA > 0 and rhoI > 0, got rhoA={params.rhoA!r},"
            f" rhoI={params.rhoI!r}"
        )
    free = free_dofs(params)
    nf = int(free.sum())
    if not 1 <= count <= nf:
        raise ValueError(f"linear_modes: count must be in [1, {nf}], got {count!r}")
    q_ref = np.zeros(params.n_dofs) if q_ref is None else np.asarray(q_ref, dtype=float)
    K = hessian(params, q_ref)[free][:, free].toarray()
    m = lumped_mass(params)[free]
    try:
        mu, vec = scipy.linalg.eigh(np.diag(m), K, subset_by_index=[nf - count, nf - 1])
        omega2, vec = 1.0 / mu[::-1], vec[:, ::-1]
    except scipy.linalg.LinAlgError:  # K not positive definite: direct problem
        omega2, vec = scipy.linalg.eigh(K, np.diag(m), subset_by_index=[0, count - 1])
        if omega2[0] < 0:
            raise ValueError(
                f"linear_modes: unstable reference state (omega^2 = {omega2[0]:.3e} < 0)"
            ) from None
    vec = vec / np.sqrt(np.einsum("ik,i,ik->k", vec, m, vec))
    phi = np.zeros((count, params.n_dofs))
    phi[:, free] = vec.T
    return np.sqrt(omega2) / (2.0 * math.pi), phi


def linear_frequencies(
    params: FDBeamParameters, count: int, q_ref: np.ndarray | None = None
) -> np.ndarray:
    """Lowest ``count`` natural frequencies in Hz, ascending (see :func:`linear_modes`)."""
    return linear_modes(params, count, q_ref)[0]


# ------------------------------------------------------------------------------------------------
# Dynamics
# ------------------------------------------------------------------------------------------------
@dataclass
class FDResult:
    """Output of :func:`simulate` at the requested times.

    Attributes
    ----------
    t : (n_t,) times.  q, qdot : (n_t, 3 (N+1)) full states.
    tip_u, tip_v, tip_theta : (n_t,) tip histories.
    kinetic : ``q_dot^T M q_dot / 2``.  strain : ``E_h(q)``.
    external_work : ``int_0^t f(s) . q_dot ds``.  dissipated : ``int_0^t q_dot^T C q_dot ds``.
    nfev : number of right-hand-side evaluations.  wall_time : seconds.
    success, message : from ``scipy.integrate.solve_ivp``.
    """

    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    tip_u: np.ndarray
    tip_v: np.ndarray
    tip_theta: np.ndarray
    kinetic: np.ndarray
    strain: np.ndarray
    external_work: np.ndarray
    dissipated: np.ndarray
    nfev: int
    wall_time: float
    success: bool
    message: str

    @property
    def energy_balance(self) -> np.ndarray:
        """``K + E_h - W_ext + D``: constant in time for an exact solution."""
        return self.kinetic + self.strain - self.external_work + self.dissipated


def _initial_state(params, q, name, free):
    """Full-length copy of an initial state; constrained entries must be zero."""
    if q is None:
        return np.zeros(params.n_dofs)
    q = np.array(q, dtype=float)
    if q.shape != (params.n_dofs,):
        raise ValueError(f"simulate: {name} must have shape ({params.n_dofs},), got {q.shape}")
    if np.any(q[~free] != 0.0):
        raise ValueError(f"simulate: {name} must vanish at the constrained dofs")
    return q


def simulate(
    params: FDBeamParameters,
    q0: np.ndarray | None,
    qdot0: np.ndarray | None,
    t_end: float,
    t_eval: np.ndarray | None = None,
    method: str = "RK45",
    rtol: float = 1e-8,
    atol: float = 1e-10,
    max_step: float = np.inf,
) -> FDResult:
    """Integrate ``M q'' + C q' + grad E_h(q) = f_load(t) f`` by the method of lines.

    First-order system over the free dofs ``y = (q, q_dot, W_ext, D)`` with
    ``dW_ext/dt = f_load(t) f . q_dot`` and ``dD/dt = q_dot^T C q_dot``, integrated by
    ``scipy.integrate.solve_ivp`` (explicit adaptive Runge-Kutta: ``RK45`` or ``DOP853``).
    ``q0``/``qdot0``: full-length vectors (None = zero). ``t_eval`` defaults to 201 equally spaced
    times in ``[0, t_end]``.
    """
    if method not in RK_METHODS:
        raise ValueError(f"simulate: method must be one of {RK_METHODS}, got {method!r}")
    if params.rhoA <= 0 or params.rhoI <= 0:
        raise ValueError(
            f"simulate needs FDBeamParameters.rhoA > 0 and rhoI > 0, got rhoA={params.rhoA!r}, "
            f"rhoI={params.rhoI!r}"
        )
    if not t_end > 0:
        raise ValueError(f"simulate: t_end must be > 0, got {t_end!r}")
    free = free_dofs(params)
    nf = int(free.sum())
    q_full = _initial_state(params, q0, "q0", free)
    qd0 = _initial_state(params, qdot0, "qdot0", free)
    m_inv = 1.0 / lumped_mass(params)[free]
    cdiag = lumped_damping(params)[free]
    f0 = external_force(params)[free]
    load_time = params.load_time
    t_eval = np.linspace(0.0, t_end, 201) if t_eval is None else np.asarray(t_eval, dtype=float)

    def rhs(t, y):
        q_full[free] = y[:nf]
        vel = y[nf : 2 * nf]
        f = load_time(t) * f0
        acc = m_inv * (f - internal_force(params, q_full)[free] - cdiag * vel)
        return np.concatenate([vel, acc, [f @ vel, vel @ (cdiag * vel)]])

    y0 = np.concatenate([q_full[free], qd0[free], [0.0, 0.0]])
    start = _time.perf_counter()
    sol = scipy.integrate.solve_ivp(
        rhs,
        (0.0, t_end),
        y0,
        method=method,
        t_eval=t_eval,
        rtol=rtol,
        atol=atol,
        max_step=max_step,
    )
    wall = _time.perf_counter() - start
    nt = sol.t.size
    q = np.zeros((nt, params.n_dofs))
    qdot = np.zeros((nt, params.n_dofs))
    q[:, free] = sol.y[:nf].T
    qdot[:, free] = sol.y[nf : 2 * nf].T
    mass = lumped_mass(params)
    tu, tv, tth = tip(q)
    return FDResult(
        t=sol.t,
        q=q,
        qdot=qdot,
        tip_u=tu,
        tip_v=tv,
        tip_theta=tth,
        kinetic=0.5 * np.einsum("ti,i,ti->t", qdot, mass, qdot),
        strain=np.array([strain_energy(params, qi) for qi in q]),
        external_work=sol.y[2 * nf],
        dissipated=sol.y[2 * nf + 1],
        nfev=int(sol.nfev),
        wall_time=wall,
        success=bool(sol.success),
        message=str(sol.message),
    )

"""Closed-form reference solutions used by demos, tests and benchmarks."""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.optimize import brentq
from scipy.special import ellipe, ellipeinc, ellipkinc, ellipkm1

__all__ = [
    "ElasticaColumn",
    "ElasticaTip",
    "SnapThroughPath",
    "elastica_clamped_free",
    "elastica_clamped_free_at_load",
    "elastica_pinned_pinned",
    "elastica_pinned_pinned_at_load",
    "elastica_tip_load",
    "snap_through_symmetric",
    "timoshenko_cantilever_deflection",
]


@dataclass(frozen=True)
class ElasticaTip:
    """Tip of a cantilever elastica under a dead transverse tip load, k = P L^2 / EI.

    shortening = -u_tip / L, deflection = |v_tip| / L, rotation = |theta_tip| (rad).
    """

    k: float
    shortening: float
    deflection: float
    rotation: float


def elastica_tip_load(k: float) -> ElasticaTip:
    """Inextensible, unshearable cantilever under a dead tip load (Mattiasson 1981).

    With alpha the tip rotation, p^2 = (1 + sin alpha) / 2 and sin(phi1) = 1 / (p sqrt 2):

        sqrt(k)         = F(pi/2, p) - F(phi1, p)
        x_tip / L       = sqrt(2 sin(alpha) / k)
        deflection / L  = 1 - 2 (E(pi/2, p) - E(phi1, p)) / sqrt(k)

    (F, E incomplete elliptic integrals of the first and second kind, modulus p).
    """
    if not (k > 0 and math.isfinite(k)):
        raise ValueError(f"k must be > 0, got {k!r}")

    def parts(alpha):
        m = (1 + math.sin(alpha)) / 2
        phi1 = math.asin(min(1.0, 1 / math.sqrt(2 * m)))
        return m, phi1

    def residual(alpha):
        m, phi1 = parts(alpha)
        return ellipkinc(math.pi / 2, m) - ellipkinc(phi1, m) - math.sqrt(k)

    alpha = brentq(residual, 1e-12, math.pi / 2 - 1e-12, xtol=1e-15, rtol=1e-15, maxiter=200)
    m, phi1 = parts(alpha)
    x_tip = math.sqrt(2 * math.sin(alpha) / k)
    deflection = 1 - 2 * (ellipeinc(math.pi / 2, m) - ellipeinc(phi1, m)) / math.sqrt(k)
    return ElasticaTip(k, 1 - x_tip, deflection, alpha)


def timoshenko_cantilever_deflection(P: float, L: float, EI: float, kGA: float) -> float:
    """Small-load tip deflection of a shear-deformable cantilever: P L^3/(3 EI) + P L/(k G A)."""
    return P * L**3 / (3 * EI) + P * L / kGA


# --- post-buckling of the inextensible elastica (Euler's elastica, axial end load) ----------


@dataclass(frozen=True)
class ElasticaColumn:
    """A buckled inextensible, unshearable column under an axial compressive end load P.

    ``load_ratio`` = P / P_cr (P_cr the Euler load of the same supports), ``rotation`` the end
    rotation alpha (rad: tip rotation of the clamped-free column, rotation at either pin of
    the pinned-pinned one), ``shortening`` = (L - chord) / L, ``deflection`` = largest lateral
    deflection / L (at the free tip, or at midspan between pins).
    """

    rotation: float
    load_ratio: float
    shortening: float
    deflection: float


def _elastica_half_wave(alpha: float) -> tuple[float, float, float]:
    """K(k), E(k) and k = sin(alpha/2) of the elastica with inflexion angle alpha.

    Timoshenko & Gere, Theory of Elastic Stability (1961), section 2.7: for the cantilever of
    length l, sqrt(P/EI) l = K(k), tip deflection 2 k l / K, chord l (2 E / K - 1).
    K(1 - m) is evaluated through ellipkm1(cos^2(alpha/2)) so that alpha -> 180 deg stays
    accurate."""
    if not (0.0 <= alpha < math.pi):
        raise ValueError(f"the end rotation must be in [0, pi) rad, got {alpha!r}")
    k = math.sin(alpha / 2)
    K = float(ellipkm1(math.cos(alpha / 2) ** 2))
    E = float(ellipe(k * k))
    return K, E, k


def elastica_clamped_free(alpha: float) -> ElasticaColumn:
    """Clamped-free column under an axial tip load, as a function of the tip rotation alpha
    (rad, 0 <= alpha < pi): P / P_cr = 4 K(k)^2 / pi^2 with P_cr = pi^2 EI / (4 L^2),
    shortening / L = 2 - 2 E(k) / K(k), tip deflection / L = 2 k / K(k), k = sin(alpha/2)."""
    K, E, k = _elastica_half_wave(alpha)
    return ElasticaColumn(alpha, 4 * K * K / math.pi**2, 2 - 2 * E / K, 2 * k / K)


def elastica_pinned_pinned(alpha: float) -> ElasticaColumn:
    """Pinned-pinned column (ends free to approach): two clamped-free halves of length L/2
    joined at midspan, so P / P_cr = 4 K^2 / pi^2 with P_cr = pi^2 EI / L^2, the same
    shortening / L = 2 - 2 E / K and midspan deflection / L = k / K."""
    K, E, k = _elastica_half_wave(alpha)
    return ElasticaColumn(alpha, 4 * K * K / math.pi**2, 2 - 2 * E / K, k / K)


def _at_load(column, load_ratio: float) -> ElasticaColumn:
    if not (load_ratio >= 1.0 and math.isfinite(load_ratio)):
        raise ValueError(f"the load ratio P/P_cr must be >= 1 (buckled), got {load_ratio!r}")
    if load_ratio == 1.0:
        return column(0.0)
    top = math.pi * (1 - 1e-16)
    return column(brentq(lambda a: column(a).load_ratio - load_ratio, 0.0, top,
                         xtol=1e-15, rtol=1e-15, maxiter=300))


def elastica_clamped_free_at_load(load_ratio: float) -> ElasticaColumn:
    """`elastica_clamped_free` at a given P / P_cr >= 1 (the buckled branch)."""
    return _at_load(elastica_clamped_free, load_ratio)


def elastica_pinned_pinned_at_load(load_ratio: float) -> ElasticaColumn:
    """`elastica_pinned_pinned` at a given P / P_cr >= 1 (the buckled branch)."""
    return _at_load(elastica_pinned_pinned, load_ratio)


# --- snap-through of the buckled clamped-clamped elastica (bistable beam) --------------------


@dataclass(frozen=True)
class SnapThroughPath:
    """Symmetric equilibrium branch of a clamped-clamped inextensible elastica whose ends were
    brought together by ``shortening`` L and which is then pushed at midspan by a transverse
    point force F toward its mirror image; lengths in L, forces in EI / L^2.

    ``deflection``: midspan height (positive on the side of the initial buckle), ``force``: F
    (positive pushing the midspan toward -deflection), ``axial``: the compressive end force P.
    ``limit_deflection``, ``limit_force``: the largest F of the branch (the force-control limit
    point, where the symmetric beam snaps)."""

    shortening: float
    deflection: object
    force: object
    axial: object
    limit_deflection: float
    limit_force: float


def snap_through_symmetric(shortening: float, points: int = 61) -> SnapThroughPath:
    """The symmetric branch from the first buckled shape (F = 0, P ~ 4 pi^2 EI/L^2, midspan
    height Y0) to beyond its next zero-force state (the buckled third mode 1 - cos(6 pi x/L):
    F = 0, P ~ 36 pi^2 EI/L^2, height ~ -Y0/3), by shooting on the half beam 0 <= s <= L/2
    (mirror symmetry at midspan), continued in the midspan height with a secant predictor.

    Unknowns theta(s), kappa(s), x(s), y(s) and the constant internal force (n_x, n_y) exerted
    by the part beyond s on the part before it (no distributed load):

        theta' = kappa,  EI kappa' = n_x sin(theta) - n_y cos(theta),  x' = cos, y' = sin

    from theta(0) = x(0) = y(0) = 0 with the shooting unknowns kappa(0), n_x, n_y chosen so
    that theta(L/2) = 0, x(L/2) = (1 - shortening) L / 2 and y(L/2) = Y (scipy solve_ivp,
    DOP853 at rtol 1e-12, and a Newton solve); the half beam carries half the point force:
    F = -2 n_y, P = -n_x. Independent of fe_beam's finite elements (no dolfinx)."""
    import numpy as np
    from scipy.integrate import solve_ivp
    from scipy.optimize import minimize_scalar

    d = float(shortening)
    if not (0.0 < d < 0.5):
        raise ValueError(f"shortening must be in (0, 0.5), got {shortening!r}")

    def end(q):
        kappa0, nx, ny = q

        def rhs(_s, y):
            return [y[1], nx * math.sin(y[0]) - ny * math.cos(y[0]), math.cos(y[0]),
                    math.sin(y[0])]

        r = solve_ivp(rhs, (0.0, 0.5), [0.0, kappa0, 0.0, 0.0], method="DOP853",
                      rtol=1e-11, atol=1e-13)
        return r.y[:, -1]

    def solve(q, last):
        """Newton on the three end conditions, central-difference Jacobian."""
        def residual(q):
            b = end(q)
            return np.array([b[0], b[2] - (1 - d) / 2, last(b, q)])

        q = np.array(q, dtype=float)
        for _ in range(30):
            r = residual(q)
            if np.abs(r).max() < 1e-12:
                return q
            h = 1e-6 * (1 + np.abs(q))
            jacobian = np.column_stack([(residual(q + hi * e) - residual(q - hi * e)) / (2 * hi)
                                        for hi, e in zip(h, np.eye(3))])
            q = q - np.linalg.solve(jacobian, r)
        raise RuntimeError(f"snap_through_symmetric: no convergence (residual {r})")

    amplitude = 2 * math.sqrt(d) / math.pi  # small-shortening first mode (1 - cos 2 pi x)/2
    q = solve(np.array([amplitude * 2 * math.pi**2, -4 * math.pi**2, 0.0]),
              lambda b, q: q[2])  # F = 0
    y0 = float(end(q)[3])
    heights = np.linspace(y0, -0.45 * y0, points)
    states = [q]
    for height in heights[1:]:
        guess = 2 * states[-1] - states[-2] if len(states) > 1 else states[-1]
        states.append(solve(guess, lambda b, q, h=height: b[3] - h))
    states = np.array(states)
    force, axial = -2 * states[:, 2], -states[:, 1]
    top = int(np.argmax(force))
    if top in (0, len(force) - 1):
        raise RuntimeError("snap_through_symmetric: no force maximum inside the branch")

    def negative_force(height):
        return 2 * solve(states[top], lambda b, q: b[3] - height)[2]

    best = minimize_scalar(negative_force, bracket=tuple(heights[top - 1: top + 2]),
                           tol=1e-12)
    return SnapThroughPath(d, heights, force, axial, float(best.x), float(-best.fun))

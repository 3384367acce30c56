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
    "SpatialRodShape",
    "circle_under_tendon",
    "elastica_clamped_free",
    "elastica_clamped_free_at_load",
    "elastica_pinned_pinned",
    "elastica_pinned_pinned_at_load",
    "elastica_tip_load",
    "helix_under_end_moment",
    "lateral_torsional_buckling_cantilever",
    "lateral_torsional_buckling_constant",
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


# --- spatial rods (MODEL.md section 8): helix, lateral-torsional buckling, tendon circle -----


def _rotation(axis_angle):
    """Rodrigues: the rotation matrix exp(phi^) of the rotation vector ``phi``."""
    import numpy as np

    phi = np.asarray(axis_angle, dtype=float)
    theta = float(np.linalg.norm(phi))
    hat = np.array([[0.0, -phi[2], phi[1]], [phi[2], 0.0, -phi[0]], [-phi[1], phi[0], 0.0]])
    if theta < 1e-8:
        return np.eye(3) + hat + 0.5 * hat @ hat
    return (np.eye(3) + math.sin(theta) / theta * hat
            + (1 - math.cos(theta)) / theta**2 * hat @ hat)


@dataclass(frozen=True)
class SpatialRodShape:
    """Centreline and frame of a spatial rod at the abscissae ``s``.

    ``position`` (n, 3) r(s), ``frame`` (n, 3, 3) R(s) (columns d1, d2, d3), ``tip_position``
    r(L), ``tip_frame`` R(L); ``curvature`` the centreline curvature, ``twist_rate`` the rate of
    the body twist about d1 added to the rigid rotation (helix), ``radius``, ``pitch`` (axial
    advance per reference length, helix) and ``axis`` (unit helix or circle axis).
    """

    s: object
    position: object
    frame: object
    tip_position: object
    tip_frame: object
    curvature: float
    twist_rate: float
    radius: float
    pitch: float
    axis: object


def helix_under_end_moment(L: float, EI: float, GJ: float, M, s=None) -> SpatialRodShape:
    """Straight isotropic Kirchhoff rod (inextensible, unshearable, EI_y = EI_z = EI, torsion
    GJ) clamped at s = 0 (r = 0, R = I) under a dead end moment ``M`` (world 3-vector), no force.

    Derivation. With no force n = 0, so m' = 0: m = M everywhere. The strain is
    u = C^-1 R^T M, C = diag(GJ, EI, EI) = EI I + (GJ - EI) e1 e1^T, and the world angular rate
    w = R u = M / EI + (1/GJ - 1/EI) (t . M) t, t = d1. Hence t' = w x t = (M / EI) x t: t.M =
    |M| cos(alpha) is constant (alpha the angle between M and e1) and t precesses about
    a = M / |M| at the rate kappa = |M| / EI, so

        R(s) = exp(s (M/EI)^) exp(s c e1^),    c = |M| cos(alpha) (1/GJ - 1/EI)

    (check: R' = (M/EI)^ R + R (c e1)^ = (M/EI + c t)^ R = w^ R). The centreline is the
    integral of t(s) = exp(kappa s a^) e1:

        r(s) = sin(kappa s)/kappa e1 + (1 - cos(kappa s))/kappa (a x e1)
               + (s - sin(kappa s)/kappa) cos(alpha) a,

    a helix about the line through (a x e1) / kappa along a, of radius sin(alpha) / kappa,
    advancing cos(alpha) along a per unit length, with curvature |t'| = kappa sin(alpha) =
    |(u2, u3)|. For GJ = EI the body twist vanishes (c = 0) and R(s) is the rigid rotation
    exp(s (M/EI)^).

    ``s``: abscissae (default 101 points on [0, L]). Returns a :class:`SpatialRodShape`
    (``curvature`` = |M| sin(alpha) / EI the bending curvature, ``twist_rate`` = c, ``radius``,
    ``pitch`` = cos(alpha), ``axis`` = a).
    """
    import numpy as np

    for name, value in (("L", L), ("EI", EI), ("GJ", GJ)):
        if not (value > 0 and math.isfinite(value)):
            raise ValueError(f"{name} must be > 0, got {value!r}")
    M = np.asarray(M, dtype=float)
    if M.shape != (3,) or not np.all(np.isfinite(M)):
        raise ValueError(f"M must be a finite 3-vector, got {M!r}")
    s = np.linspace(0.0, L, 101) if s is None else np.atleast_1d(np.asarray(s, dtype=float))
    e1 = np.array([1.0, 0.0, 0.0])
    size = float(np.linalg.norm(M))
    if size == 0.0:
        pos = np.outer(s, e1)
        frames = np.repeat(np.eye(3)[None], len(s), axis=0)
        return SpatialRodShape(s, pos, frames, np.array([L, 0.0, 0.0]), np.eye(3), 0.0, 0.0,
                               math.inf, 1.0, e1)
    a = M / size
    kappa = size / EI
    cos_a = float(a @ e1)
    c = size * cos_a * (1 / GJ - 1 / EI)
    side = np.cross(a, e1)

    def shape(si):
        ks = kappa * si
        sinc = si * (math.sin(ks) / ks if ks != 0 else 1.0)
        vers = si * ((1 - math.cos(ks)) / ks if ks != 0 else 0.0)
        return sinc * e1 + vers * side + (si - sinc) * cos_a * a, \
            _rotation(si * M / EI) @ _rotation(si * c * e1)

    pos = np.array([shape(si)[0] for si in s])
    frames = np.array([shape(si)[1] for si in s])
    tip_r, tip_R = shape(float(L))
    sin_a = math.sqrt(max(0.0, 1 - cos_a**2))
    return SpatialRodShape(s, pos, frames, tip_r, tip_R, size * sin_a / EI, c, sin_a / kappa,
                           cos_a, a)


def lateral_torsional_buckling_constant() -> float:
    """The constant 4.0126 of :func:`lateral_torsional_buckling_cantilever`, computed.

    Timoshenko & Gere, Theory of Elastic Stability (1961), section 6.3: a narrow cantilever with
    a load P at the centroid of its end section, lateral twist phi(x), x measured from the
    free end. The torque balance of the slightly twisted beam (strong-axis bending stiffness
    taken infinite) gives

        GJ phi'' + P^2 x^2 / EI_y phi = 0,   phi'(0) = 0 (free end),  phi(L) = 0 (clamp).

    The solutions of y'' + g^2 x^2 y = 0 are sqrt(x) Z_{+-1/4}(g x^2 / 2) with g^2 =
    P^2 / (EI_y GJ); phi'(0) = 0 keeps sqrt(x) J_{-1/4}(g x^2 / 2) (the J_{1/4} branch starts
    like x), and phi(L) = 0 requires J_{-1/4}(gamma) = 0 with gamma = g L^2 / 2 =
    P L^2 / (2 sqrt(EI_y GJ)). The first root gamma_1 = 2.00629... gives
    P_cr = 2 gamma_1 sqrt(EI_y GJ) / L^2 = 4.0126 sqrt(EI_y GJ) / L^2.
    """
    from scipy.special import jv

    gamma = brentq(lambda x: jv(-0.25, x), 1.5, 2.5, xtol=1e-15, rtol=1e-15)
    return 2.0 * gamma


def lateral_torsional_buckling_cantilever(L: float, EIy: float, GJ: float) -> float:
    """Critical tip load P_cr = 4.0126 sqrt(EI_y GJ) / L^2 of a narrow cantilever loaded at the
    centroid of its free end in the plane of its stiff axis (Timoshenko & Gere 1961, 6.3; the
    constant is computed in :func:`lateral_torsional_buckling_constant`).

    EI_y is the lateral (weak-axis) bending stiffness, E int z^2 dA with the load along y (the h
    direction) and b << h. The classical result neglects the in-plane deflection (EI_z -> inf)
    and warping; the pre-buckling in-plane deflection of a finite EI_z raises P_cr by a relative
    amount of order EI_y / EI_z.
    """
    for name, value in (("L", L), ("EIy", EIy), ("GJ", GJ)):
        if not (value > 0 and math.isfinite(value)):
            raise ValueError(f"{name} must be > 0, got {value!r}")
    return lateral_torsional_buckling_constant() * math.sqrt(EIy * GJ) / L**2


def circle_under_tendon(L: float, EI, EA, tau: float, y: float, z: float,
                        s=None) -> SpatialRodShape:
    """Straight uniform rod, clamped at s = 0 (R = I), with one straight tendon at constant
    body offset (0, y, z) from the base to the tip, tension ``tau``.

    Cut rod and tendon together at s: the part beyond carries no external load. The tendon
    stays parallel to d1 (shown below), so the balance of the part beyond s, loaded by -n, -m at
    r and by the cut tendon's pull -tau d1
    at R r_i, gives n = -tau d1 (compression tau: v1 = 1 - tau / EA, no shear, so a shearable
    rod gives the same) and m = -(R r_i) x tau d1 = tau R (e1 x r_i):

        m_b = tau (0, -z, y),   u = (0, -tau z / EI_y, tau y / EI_z)  (constant, u1 = 0),

    so R(s) = exp(s u^) and, u being perpendicular to r_i and e1, u x r_i is along d1: the
    tendon tangent w = v + u x r_i is along d1 indeed. The centreline is a circle of curvature
    |u| / v1 (per deformed length) in the plane normal to u (the offset's plane for an isotropic
    section, EI_y = EI_z; a +y offset bends toward +y: u3 > 0):

        r(s) = v1 [sin(k s)/k e1 + (1 - cos(k s))/k (a x e1)],   k = |u|, a = u / k.

    ``EI``: EI (isotropic) or (EI_y, EI_z). ``EA``: None (or inf) for the inextensible rod.
    Returns a :class:`SpatialRodShape` (``curvature`` = k / v1, ``radius`` = v1 / k,
    ``twist_rate`` = 0, ``pitch`` = 0, ``axis`` = a).
    """
    import numpy as np

    if np.ndim(EI) == 0:
        EIy = EIz = float(EI)
    else:
        EIy, EIz = (float(v) for v in EI)
    for name, value in (("L", L), ("EI_y", EIy), ("EI_z", EIz)):
        if not (value > 0 and math.isfinite(value)):
            raise ValueError(f"{name} must be > 0, got {value!r}")
    if not (tau >= 0 and math.isfinite(tau)):
        raise ValueError(f"tau must be >= 0, got {tau!r}")
    v1 = 1.0 if EA is None or math.isinf(EA) else 1.0 - tau / float(EA)
    if not v1 > 0:
        raise ValueError(f"tau / EA must be < 1, got {tau!r} / {EA!r}")
    s = np.linspace(0.0, L, 101) if s is None else np.atleast_1d(np.asarray(s, dtype=float))
    e1 = np.array([1.0, 0.0, 0.0])
    u = np.array([0.0, -tau * z / EIy, tau * y / EIz])
    k = float(np.linalg.norm(u))
    if k == 0.0:
        pos = v1 * np.outer(s, e1)
        frames = np.repeat(np.eye(3)[None], len(s), axis=0)
        return SpatialRodShape(s, pos, frames, v1 * L * e1, np.eye(3), 0.0, 0.0, math.inf, 0.0,
                               e1)
    a = u / k
    side = np.cross(a, e1)

    def shape(si):
        return v1 * (math.sin(k * si) / k * e1 + (1 - math.cos(k * si)) / k * side), \
            _rotation(si * u)

    pos = np.array([shape(si)[0] for si in s])
    frames = np.array([shape(si)[1] for si in s])
    tip_r, tip_R = shape(float(L))
    return SpatialRodShape(s, pos, frames, tip_r, tip_R, k / v1, 0.0, v1 / k, 0.0, a)

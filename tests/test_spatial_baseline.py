"""Tests of the spatial Cosserat reference solver (fe_beam.baselines.spatial_shooting) and of the
spatial closed forms of fe_beam.analytic (helix, lateral-torsional buckling, tendon circle)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fe_beam.analytic import (
    circle_under_tendon,
    elastica_tip_load,
    helix_under_end_moment,
    lateral_torsional_buckling_cantilever,
    lateral_torsional_buckling_constant,
)
from fe_beam.baselines import shooting as planar
from fe_beam.baselines import spatial_shooting as ss
from fe_beam.baselines.spatial_shooting import Tendon, solve_cantilever


def _angle_error(a, b) -> float:
    """Rotation angle of ``a^T b`` (from its skew part: accurate for small angles)."""
    d = a.T @ b
    sin = 0.5 * np.linalg.norm([d[2, 1] - d[1, 2], d[0, 2] - d[2, 0], d[1, 0] - d[0, 1]])
    return math.atan2(sin, (np.trace(d) - 1.0) / 2.0)


# ------------------------------------------------------------------------------------------------
# (i) the plane
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("k", [1.0, 10.0])
def test_planar_tip_force_matches_elastica(k):
    """Kirchhoff rod, dead tip force -k EI / L^2 e2: the elliptic-integral elastica
    (fe_beam.analytic.elastica_tip_load); the rod stays in the x-y plane."""
    L, EI = 2.0, 3.0
    sol = solve_cantilever(
        L, 1.0, 1.0, 5.0, 7.0, EI, tip_force=(0, -k * EI / L**2, 0), extensible=False,
        shearable=False,
    )
    ref = elastica_tip_load(k)
    assert abs(sol.tip_position[0] - L * (1 - ref.shortening)) < 1e-8 * L
    assert abs(sol.tip_position[1] + L * ref.deflection) < 1e-8 * L
    theta = math.atan2(sol.tip_frame[1, 0], sol.tip_frame[0, 0])
    assert abs(theta + ref.rotation) < 1e-8
    assert np.abs(sol.position[:, 2]).max() < 1e-12 * L
    assert np.abs(sol.frame[:, :, 2] - [0, 0, 1]).max() < 1e-12
    assert np.abs(sol.v - [1, 0, 0]).max() == 0.0  # the constraints hold exactly
    # dead load: the clamp carries the load and its moment
    assert np.abs(sol.base_force - [0, k * EI / L**2, 0]).max() < 1e-9 * k * EI / L**2
    moment = np.cross(sol.tip_position, [0, -k * EI / L**2, 0])
    assert np.abs(sol.base_moment + moment).max() < 1e-9 * k * EI / L


@pytest.mark.parametrize("anchor", [None, 0.07])
def test_planar_tendon_matches_planar_baseline(anchor):
    """A tendon with a linear offset along y on an extensible, unshearable rod == the planar
    finger solver (fe_beam.baselines.shooting, "reference" curvature, uniform section)."""
    L, B, H, E = 0.1, 0.02, 0.015, 0.6e6
    t2d = planar.Tendon(tension=2.5, offset_base=0.006, offset_tip=0.002, anchor=anchor)
    finger = planar.TaperedFinger(
        length=L, width=B, height_base=H, height_tip=H, young=E, tendons=(t2d,),
        curvature="reference",
    )
    ref = planar.solve_finger(finger)
    EA, EI = finger.ea(0.0)[0], finger.ej(0.0)[0]
    t3d = Tendon(2.5, lambda s: (0.006 - 0.04 * s, 0.0 * s), anchor=anchor)
    sol = solve_cantilever(L, EA, 1.0, 1.0, 1.0, EI, shearable=False, tendons=(t3d,))
    assert abs(sol.tip_position[0] - (L + ref.tip_u)) < 1e-9 * L
    assert abs(sol.tip_position[1] - ref.tip_v) < 1e-9 * L
    theta = math.atan2(sol.tip_frame[1, 0], sol.tip_frame[0, 0])
    assert abs(theta - ref.tip_theta) < 1e-9
    assert abs(sol.tendon_lengths[0] - ref.tendon_lengths[0]) < 1e-9 * L
    assert np.abs(sol.position[:, 2]).max() < 1e-12 * L


# ------------------------------------------------------------------------------------------------
# (ii) the helix under a dead end moment
# ------------------------------------------------------------------------------------------------
HELIX_M = np.array([1.2, 0.8, -0.5])


@pytest.mark.parametrize("constrained", [True, False], ids=["kirchhoff", "simo-reissner"])
def test_helix_under_end_moment(constrained):
    """Dead end moment with components along and across the axis, GJ != EI: the closed form
    r(s), R(s) = exp(s M^/EI) exp(s c e1^) along the whole rod."""
    L, EI, GJ = 1.5, 1.0, 0.7
    sol = solve_cantilever(
        L, 50.0, 20.0, GJ, EI, EI, tip_moment=HELIX_M, extensible=not constrained,
        shearable=not constrained,
    )
    ref = helix_under_end_moment(L, EI, GJ, HELIX_M, s=sol.s)
    assert np.abs(sol.position - ref.position).max() < 1e-8 * L
    assert max(_angle_error(a, b) for a, b in zip(sol.frame, ref.frame)) < 1e-8
    assert np.abs(sol.tip_position - ref.tip_position).max() < 1e-8 * L
    assert _angle_error(sol.tip_frame, ref.tip_frame) < 1e-8
    # the twist really differs from the rigid rotation exp(s M^/EI) (the check has teeth)
    rigid = helix_under_end_moment(L, EI, EI, HELIX_M).tip_frame
    assert _angle_error(sol.tip_frame, rigid) > 0.1
    # the internal moment is M everywhere, the force zero
    assert np.abs(sol.moment - HELIX_M).max() < 1e-9
    assert np.abs(sol.force).max() < 1e-9


def test_helix_closed_form_is_a_kirchhoff_equilibrium():
    """The closed form itself: R^T r' = e1, R^T R' = u^ with C u = R^T M (finite differences)."""
    L, EI, GJ = 1.5, 1.0, 0.7
    h = 1e-5
    s = np.array([0.3, 0.9, 1.4])
    mid = helix_under_end_moment(L, EI, GJ, HELIX_M, s=s)
    plus = helix_under_end_moment(L, EI, GJ, HELIX_M, s=s + h)
    minus = helix_under_end_moment(L, EI, GJ, HELIX_M, s=s - h)
    C = np.array([GJ, EI, EI])
    for i in range(len(s)):
        R = mid.frame[i]
        rp = (plus.position[i] - minus.position[i]) / (2 * h)
        uhat = R.T @ (plus.frame[i] - minus.frame[i]) / (2 * h)
        u = np.array([uhat[2, 1], uhat[0, 2], uhat[1, 0]])
        assert np.abs(R.T @ rp - [1, 0, 0]).max() < 1e-8
        assert np.abs(C * u - R.T @ HELIX_M).max() < 1e-8


def test_follower_loads_reproduce_the_dead_solution():
    """A follower load equal to the dead solution's tip load in tip axes gives the same rod."""
    L, EI, GJ = 1.5, 1.0, 0.7
    dead = solve_cantilever(L, 50.0, 20.0, GJ, EI, 1.3 * EI, tip_force=(0.2, 0.3, -0.4),
                            tip_moment=HELIX_M)
    R = dead.tip_frame
    follower = solve_cantilever(L, 50.0, 20.0, GJ, EI, 1.3 * EI, tip_force=R.T @ [0.2, 0.3, -0.4],
                                tip_moment=R.T @ HELIX_M, follower=True)
    assert np.abs(follower.position - dead.position).max() < 1e-9 * L
    assert _angle_error(follower.tip_frame, dead.tip_frame) < 1e-9
    assert np.abs(follower.tip_load - dead.tip_load).max() < 1e-9


# ------------------------------------------------------------------------------------------------
# (iii) Bathe-Bolourchi 45-degree bend
# ------------------------------------------------------------------------------------------------
def saint_venant_j_rectangle(t: float, w: float, terms: int = 200) -> float:
    """J = t^3 w / 3 (1 - 192 t / (pi^5 w) sum_{n odd} tanh(n pi w / 2t) / n^5), t <= w."""
    n = np.arange(1, 2 * terms, 2)
    series = np.sum(np.tanh(n * math.pi * w / (2 * t)) / n**5)
    return t**3 * w / 3 * (1 - 192 * t / (math.pi**5 * w) * series)


# Simo & Vu-Quoc (1986), 8 elements; the "converged" literature value at 600
SVQ = {300.0: (58.84, 22.33, 40.08), 600.0: (47.23, 15.79, 53.37)}
CONVERGED_600 = (47.20, 15.61, 53.40)


def _bend(P, J, rtol=1e-12):
    """45-degree arc of radius 100 in the x-y plane (u0 = (0, 0, 1/100), toward +y), unit square
    section, E = 1e7, G = 5e6, k = 5/6, dead tip load P e3."""
    R0 = 100.0
    E, G, A, I = 1e7, 5e6, 1.0, 1.0 / 12
    return solve_cantilever(
        R0 * math.pi / 4, E * A, 5 / 6 * G * A, G * J, E * I, E * I, tip_force=(0, 0, P),
        u0=(0, 0, 1 / R0), rtol=rtol,
    )


def test_saint_venant_torsion_constant_of_the_unit_square():
    assert abs(saint_venant_j_rectangle(1.0, 1.0) - 0.1406) < 5e-5


def test_bathe_bolourchi_bend():
    """J = 1/6 (the data set of Simo & Vu-Quoc and of BeamDyn's test: GJ = 8.333e5) and the
    Saint-Venant J = 0.1406: the tips at P = 300, 600 lie within 0.5 of the published ones
    (J = 1/6 within 0.15). Unloaded, the tip is on the arc."""
    unloaded = _bend(0.0, 1 / 6)
    arc = 100 * np.array([math.sin(math.pi / 4), 1 - math.cos(math.pi / 4), 0.0])
    assert np.abs(unloaded.tip_position - arc).max() < 1e-9 * 100
    for J, tol in ((1 / 6, 0.15), (saint_venant_j_rectangle(1.0, 1.0), 0.5)):
        for P, ref in SVQ.items():
            tip = _bend(P, J).tip_position
            print(f"Bathe-Bolourchi J={J:.6f} P={P:.0f}: tip = ({tip[0]:.6f}, {tip[1]:.6f}, "
                  f"{tip[2]:.6f})")
            assert np.abs(tip - ref).max() < tol
            if P == 600.0:
                assert np.abs(tip - CONVERGED_600).max() < 0.5


def test_bathe_bolourchi_converges_with_tolerance():
    a = _bend(600.0, 1 / 6, rtol=1e-9).tip_position
    b = _bend(600.0, 1 / 6, rtol=1e-12).tip_position
    assert np.abs(a - b).max() < 1e-7 * 100


# ------------------------------------------------------------------------------------------------
# (iv) tendons
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("offset", [(0.004, 0.0), (0.0, -0.003), (0.003, -0.002)])
@pytest.mark.parametrize(
    "extensible, shearable", [(False, False), (True, False), (True, True)]
)
def test_constant_offset_tendon_is_a_circle(offset, extensible, shearable):
    """Straight tendon at constant offset on a straight rod: the circle of circle_under_tendon
    (curvature tau |offset| / EI in the offset's plane, compression tau / EA)."""
    L, EI, EA, tau = 0.1, 2.5e-3, 177.0, 1.5
    sol = solve_cantilever(
        L, EA, 53.0, 1.7e-3, EI, EI, tendons=(Tendon(tau, offset),), extensible=extensible,
        shearable=shearable,
    )
    ref = circle_under_tendon(L, EI, EA if extensible else None, tau, *offset, s=sol.s)
    assert np.abs(sol.position - ref.position).max() < 1e-8 * L
    assert _angle_error(sol.tip_frame, ref.tip_frame) < 1e-8
    # it bends toward the offset
    direction = np.array([0.0, *offset]) / np.linalg.norm(offset)
    assert sol.tip_position @ direction > 0.1 * ref.curvature * L**2
    # internal moment tau |offset| everywhere, compression tau; tendons only: no clamp reaction
    assert np.abs(np.linalg.norm(sol.moment, axis=1) - tau * np.linalg.norm(offset)).max() < 1e-9
    assert np.abs(np.linalg.norm(sol.force, axis=1) - tau).max() < 1e-9 * tau
    assert np.abs(sol.base_force).max() < 1e-9 * tau
    assert np.abs(sol.base_moment).max() < 1e-9 * tau * L


def test_circle_under_tendon_sign_convention():
    """+y offset: u3 > 0 (k_z > 0), the rod curls toward +y; +z offset: toward +z."""
    c = circle_under_tendon(1.0, 1.0, None, 0.5, 0.1, 0.0)
    assert c.tip_position[1] > 0 and abs(c.tip_position[2]) < 1e-15
    assert c.axis @ [0, 0, 1] == pytest.approx(1.0)
    c = circle_under_tendon(1.0, 1.0, 100.0, 0.5, 0.0, 0.1)
    assert c.tip_position[2] > 0 and abs(c.tip_position[1]) < 1e-15
    assert c.radius == pytest.approx((1 - 0.5 / 100.0) / 0.05)


# The soft helical-tendon rod: L = 0.1 m, circle d = 15 mm, E = 1 MPa, nu = 0.5 (G = E / 3),
# k = 6 (1 + nu) / (7 + 6 nu) = 0.9 (Cowper), J = 2 I; tendon r = 4 mm turning by 90 degrees.
SOFT_L = 0.1
_D, _E, _G = 0.015, 1e6, 1e6 / 3
_A, _I = math.pi * _D**2 / 4, math.pi * _D**4 / 64
SOFT = dict(L=SOFT_L, EA=_E * _A, GA=0.9 * _G * _A, GJ=_G * 2 * _I, EIy=_E * _I, EIz=_E * _I)
_W = math.pi / (2 * SOFT_L)


def _helical(tau, analytic=False, anchor=None):
    def offset(s):
        return 0.004 * np.cos(_W * s), 0.004 * np.sin(_W * s)

    if not analytic:
        return Tendon(tau, offset, anchor=anchor)
    return Tendon(
        tau,
        offset,
        anchor=anchor,
        d_offset=lambda s: (-0.004 * _W * math.sin(_W * s), 0.004 * _W * math.cos(_W * s)),
        dd_offset=lambda s: (-0.004 * _W**2 * math.cos(_W * s), -0.004 * _W**2 * math.sin(_W * s)),
    )


HELICAL_TIP_2N = (0.0973510604, 0.0130054894, 0.0070590246)  # recorded, tau = 2 N


def test_helical_tendon():
    """Convergence with the integrator tolerance, complex-step derivatives == analytic ones,
    global equilibrium (tendons only: the clamp reaction vanishes), the recorded tip."""
    tau = 2.0
    fine = solve_cantilever(**SOFT, tendons=(_helical(tau),), rtol=1e-12)
    coarse = solve_cantilever(**SOFT, tendons=(_helical(tau),), rtol=1e-9)
    exact = solve_cantilever(**SOFT, tendons=(_helical(tau, analytic=True),), rtol=1e-12)
    tip = fine.tip_position
    print(f"helical tendon tau={tau}: tip = ({tip[0]:.10f}, {tip[1]:.10f}, {tip[2]:.10f})")
    assert np.abs(coarse.tip_position - tip).max() < 1e-9 * SOFT_L
    assert np.abs(exact.tip_position - tip).max() < 1e-12 * SOFT_L
    assert np.abs(tip - HELICAL_TIP_2N).max() < 2e-10
    # n(0+) = -tau t(0), m(0+) = -(R r_i)(0) x tau t(0): the tendon's loads have zero resultant
    assert np.abs(fine.base_force).max() < 1e-10 * tau
    assert np.abs(fine.base_moment).max() < 1e-10 * tau * SOFT_L
    assert np.linalg.norm(fine.n0) == pytest.approx(tau, rel=1e-3)
    # the tendon turns the bending plane: the tip leaves the x-y plane toward +z
    assert tip[1] > 0 and tip[2] > 0


def test_offset_callable_without_complex_support():
    """An offset written with ``math`` (no complex step possible): central differences."""
    ref = solve_cantilever(**SOFT, tendons=(_helical(1.0, analytic=True),))
    plain = Tendon(1.0, lambda s: (0.004 * math.cos(_W * s), 0.004 * math.sin(_W * s)))
    sol = solve_cantilever(**SOFT, tendons=(plain,))
    assert np.abs(sol.tip_position - ref.tip_position).max() < 1e-8 * SOFT_L


def test_tendon_sum_and_anchor():
    """Two tendons, one anchored at mid-length: beyond the anchor the rod carries only the
    other tendon's loads, and the clamp reaction still vanishes."""
    tendons = (_helical(1.0, anchor=0.05), Tendon(0.7, (-0.003, 0.002)))
    sol = solve_cantilever(**SOFT, tendons=tendons)
    assert np.abs(sol.base_force).max() < 1e-9
    assert np.abs(sol.base_moment).max() < 1e-9 * SOFT_L
    beyond = sol.s > 0.0501
    assert np.abs(np.linalg.norm(sol.force[beyond], axis=1) - 0.7).max() < 1e-9
    mom = 0.7 * math.hypot(0.003, 0.002)
    assert np.abs(np.linalg.norm(sol.moment[beyond], axis=1) - mom).max() < 1e-9


# ------------------------------------------------------------------------------------------------
# Energy: the solutions make the total potential stationary (independent of the ODEs)
# ------------------------------------------------------------------------------------------------
def _hat(a):
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def _expm_so3(phi):
    th = np.linalg.norm(phi)
    P = _hat(phi)
    if th < 1e-12:
        return np.eye(3) + P
    return np.eye(3) + math.sin(th) / th * P + (1 - math.cos(th)) / th**2 * P @ P


def _right_jacobian(phi):
    th = np.linalg.norm(phi)
    P = _hat(phi)
    if th < 1e-8:
        return np.eye(3) - 0.5 * P
    return np.eye(3) - (1 - math.cos(th)) / th**2 * P + (th - math.sin(th)) / th**3 * P @ P


def _first_variation(sol, stiff, tendons, tip_force, u0, direction, eps=1e-5, nodes=60):
    """(dPi/deps, sum of the |d/deps| of its parts) for r + eps dr, exp(eps Phi^) R, with
    dr = L (s/L)^2 a + L sin(pi s / L) b, Phi = (s/L)^2 c; Pi = int W ds + sum tau_i l_i - F.r(L),
    l_i = int_0^L_i |v + u x r_i + r_i'| ds (r_i' by central differences), Gauss quadrature on
    the pieces between anchors; d/deps by Richardson-extrapolated central differences (the
    perturbed strains are exact: v = R^T E^T (r' + eps dr'), u = u + R^T J_r(eps Phi) eps Phi',
    E = exp(eps Phi^), J_r the right Jacobian of SO(3))."""
    L = sol.length
    a, b, c = direction
    D = np.array([stiff["EA"], stiff["GA"], stiff["GA"]])
    C = np.array([stiff["GJ"], stiff["EIy"], stiff["EIz"]])
    xg, wg = np.polynomial.legendre.leggauss(nodes)
    cuts = sorted({0.0, L, *[t.s_anchor(L) for t in tendons]})
    pts, wts = [], []
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        pts.extend(lo + (hi - lo) * (xg + 1) / 2)
        wts.extend((hi - lo) / 2 * wg)
    data = []
    for s in pts:
        R = sol.R(s)
        v, u = sol.strains(s)
        data.append((s, R, v, u))

    def offset(t, s, h=1e-6 * L):
        if not callable(t.offset):
            return np.array([0.0, *t.offset]), np.zeros(3)
        f = lambda x: np.array([0.0, *[float(np.real(q)) for q in t.offset(x)]])  # noqa: E731
        return f(s), (f(s + h) - f(s - h)) / (2 * h)

    offs = [[offset(t, s) for s in pts] for t in tendons]

    def parts(e):
        strain = tendon = 0.0
        for k, ((s, R, v, u), w) in enumerate(zip(data, wts)):
            phi = e * (s / L) ** 2 * c
            dphi = e * 2 * s / L**2 * c
            drp = e * (2 * s / L * a + math.pi * math.cos(math.pi * s / L) * b)
            Ex = _expm_so3(phi)
            v_e = R.T @ Ex.T @ (R @ v + drp)
            u_e = u + R.T @ (_right_jacobian(phi) @ dphi)
            dv, du = v_e - [1, 0, 0], u_e - u0
            strain += w * 0.5 * (dv @ (D * dv) + du @ (C * du))
            for t, off in zip(tendons, offs):
                if s < t.s_anchor(L):
                    r_i, rp = off[k]
                    tendon += w * t.tension * np.linalg.norm(v_e + np.cross(u_e, r_i) + rp)
        work = np.asarray(tip_force) @ (sol.tip_position + e * L * a)
        return np.array([strain, tendon, -work])

    d1 = (parts(eps) - parts(-eps)) / (2 * eps)
    d2 = (parts(2 * eps) - parts(-2 * eps)) / (4 * eps)
    d = (4 * d1 - d2) / 3
    return d.sum(), np.abs(d).sum()


DIRECTIONS = [
    (np.array([0.0, 0.3, -0.2]), np.array([0.1, 0.0, 0.2]), np.array([0.5, -0.4, 0.3])),
    (np.array([0.2, -0.1, 0.1]), np.array([0.0, 0.3, -0.1]), np.array([-0.2, 0.6, 0.1])),
    (np.array([0.05, 0.0, 0.0]), np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])),
]


def test_tendon_loads_make_the_potential_stationary():
    """Rucker-Webster loads vs an energy argument: the first variation of the total potential
    (strain energy + tau * deformed tendon length, computed by quadrature on the solution)
    vanishes; at 1% more tension (the wrong solution) it does not."""
    stiff = {k: SOFT[k] for k in ("EA", "GA", "GJ", "EIy", "EIz")}
    tendons = (_helical(2.0, analytic=True), Tendon(0.8, (-0.003, 0.002), anchor=0.06))
    sol = solve_cantilever(**SOFT, tendons=tendons)
    wrong = solve_cantilever(
        **SOFT, tendons=(_helical(2.02, analytic=True), Tendon(0.808, (-0.003, 0.002), 0.06))
    )
    for direction in DIRECTIONS:
        dpi, size = _first_variation(sol, stiff, tendons, (0, 0, 0), np.zeros(3), direction)
        assert abs(dpi) < 1e-8 * size
    dpi, size = _first_variation(wrong, stiff, tendons, (0, 0, 0), np.zeros(3), DIRECTIONS[0])
    assert abs(dpi) > 1e-3 * size


def test_bend_makes_the_potential_stationary():
    """The same energy check for the initially curved, dead-loaded Bathe-Bolourchi bend."""
    sol = _bend(600.0, 1 / 6)
    stiff = dict(EA=1e7, GA=5 / 6 * 5e6, GJ=5e6 / 6, EIy=1e7 / 12, EIz=1e7 / 12)
    u0 = np.array([0, 0, 0.01])
    for direction in DIRECTIONS[:2]:
        dpi, size = _first_variation(sol, stiff, (), (0, 0, 600.0), u0, direction)
        assert abs(dpi) < 1e-8 * size
    wrong = _bend(606.0, 1 / 6)
    dpi, size = _first_variation(wrong, stiff, (), (0, 0, 600.0), u0, DIRECTIONS[0])
    assert abs(dpi) > 1e-3 * size


# ------------------------------------------------------------------------------------------------
# Lateral-torsional buckling
# ------------------------------------------------------------------------------------------------
def test_lateral_torsional_buckling_constant():
    """2 x (first zero of J_{-1/4}) = 4.0126 (Timoshenko & Gere)."""
    assert round(lateral_torsional_buckling_constant(), 4) == 4.0126
    assert lateral_torsional_buckling_cantilever(2.0, 3.0, 5.0) == pytest.approx(
        4.0126 * math.sqrt(15.0) / 4.0, rel=1e-5
    )


def test_lateral_torsional_buckling_by_shooting():
    """The shooting Jacobian at the in-plane solution of a narrow Kirchhoff cantilever
    (EI_z = 1e4 EI_y) under a centroidal tip load along -y becomes singular at P_cr: its
    determinant changes sign between 0.998 and 1.002 P_cr, and not below."""
    L, EIy, GJ, EIz = 1.0, 1.0, 0.6, 1e4
    p_cr = lateral_torsional_buckling_cantilever(L, EIy, GJ)

    def det(P):
        sol = solve_cantilever(L, 1.0, 1.0, GJ, EIy, EIz, tip_force=(0, -P, 0), extensible=False,
                               shearable=False, steps=1)
        rod = sol._rod
        base = np.concatenate([sol.n0, sol.m0])

        def res(z):
            return ss._tip_residual(rod, ss._integrate(rod, z, 1e-11)[0])

        jac = np.column_stack(
            [(res(base + h) - res(base - h)) / 2e-6 for h in 1e-6 * np.eye(6)]
        )
        return np.linalg.det(jac)

    below = det(0.998 * p_cr)
    assert below * det(1.002 * p_cr) < 0
    assert below * det(0.99 * p_cr) > 0

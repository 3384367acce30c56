"""Tests of the tendon-driven finger reference solver (fe_beam.baselines.shooting)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.integrate

from fe_beam.baselines.shooting import (
    TaperedFinger,
    Tendon,
    default_finger,
    looped_tendon,
    solve_finger,
    tension_for_pull_in,
    tension_for_tip_angle,
    with_tension,
)

L = 0.1


def _uniform(tension, delta=0.005, **kw):
    """Uniform 20 x 15 mm section, one tendon at constant offset ``delta``."""
    tendon = Tendon(tension=tension, offset_base=delta, offset_tip=delta)
    return TaperedFinger(height_base=0.015, height_tip=0.015, tendons=(tendon,), **kw)


def _kinked_two_tendons():
    """Two tendons: piecewise linear with kinks, entry > 0 and anchor < L; and a linear one."""
    t1 = Tendon(
        tension=1.5,
        points=((0.0, 0.005), (0.03, 0.007), (0.06, 0.003), (0.1, 0.004)),
        entry=0.01,
        anchor=0.08,
    )
    t2 = Tendon(tension=0.7, offset_base=-0.006, offset_tip=-0.002, entry=0.02)
    return TaperedFinger(tendons=(t1, t2))


# ------------------------------------------------------------------------------------------------
# Exact solutions: constant offset
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["shooting", "cut"])
@pytest.mark.parametrize("curvature", ["reference", "deformed"])
@pytest.mark.parametrize("tension", [0.3, 3.0, 20.0])
def test_constant_offset_inextensible_is_circular_arc(method, curvature, tension):
    """EJ kappa = tau delta exactly; the tip lies on the arc (sin kL / k, (1 - cos kL) / k)."""
    delta = 0.005
    finger = _uniform(tension, delta, extensible=False, curvature=curvature)
    sol = solve_finger(finger, method=method)
    k = tension * delta / finger.ej(0.0)[0]
    assert np.abs(sol.curvature_b_reference / k - 1.0).max() < 1e-8
    assert np.abs(sol.curvature_b_deformed / k - 1.0).max() < 1e-8
    assert abs(sol.tip_u + L - math.sin(k * L) / k) < 1e-8 * L
    assert abs(sol.tip_v - (1.0 - math.cos(k * L)) / k) < 1e-8 * L
    assert abs(sol.tip_theta - k * L) < 1e-8
    assert np.all(sol.axial_strain == 0.0)


@pytest.mark.parametrize("method", ["shooting", "cut"])
@pytest.mark.parametrize("curvature", ["reference", "deformed"])
def test_constant_offset_extensible_is_stretched_arc(method, curvature):
    """Extensible: q = -tau / EA; m = EJ kappa = tau delta; theta' = kappa (reference) or
    (1 + q) kappa (deformed); the axis is an arc of length (1 + q) L."""
    tension, delta = 5.0, 0.005
    finger = _uniform(tension, delta, curvature=curvature)
    sol = solve_finger(finger, method=method)
    q = -tension / finger.ea(0.0)[0]
    kappa = tension * delta / finger.ej(0.0)[0]
    theta_p = kappa if curvature == "reference" else (1.0 + q) * kappa
    rho = (1.0 + q) / theta_p
    assert np.abs(sol.axial_strain / q - 1.0).max() < 1e-8
    assert np.abs(sol.curvature_b_reference / theta_p - 1.0).max() < 1e-8
    assert abs(sol.tip_u + L - rho * math.sin(theta_p * L)) < 1e-8 * L
    assert abs(sol.tip_v - rho * (1.0 - math.cos(theta_p * L))) < 1e-8 * L


# ------------------------------------------------------------------------------------------------
# Equilibrium checks independent of the ODEs
# ------------------------------------------------------------------------------------------------
def _energy(finger, x, theta_p, q):
    """Pi = int 1/2 EJ theta'^2 + 1/2 EA q^2 dx + tau l, l = int sqrt((1+q-delta theta')^2 +
    delta'^2) dx (one tendon from 0 to L, linear offset), by Simpson's rule."""
    (t,) = finger.tendons
    delta = t.offset_base + (t.offset_tip - t.offset_base) * x / L
    delta_p = (t.offset_tip - t.offset_base) / L
    ej = np.array([finger.ej(v)[0] for v in x])
    ea = np.array([finger.ea(v)[0] for v in x])
    w = np.hypot(1.0 + q - delta * theta_p, delta_p)
    dens = 0.5 * ej * theta_p**2 + 0.5 * ea * q**2 + t.tension * w
    return scipy.integrate.simpson(dens, x=x)


def _first_variations(finger, sol, eps=1e-4):
    """dPi/deps by central differences along smooth variations (theta, q) + eps (eta, zeta),
    eta(0) = 0, normalised by int |EJ theta' eta'| + |EA q zeta| dx."""
    x = sol.x
    variations = [
        (np.ones_like(x), np.zeros_like(x)),
        (np.cos(math.pi * x / L), np.zeros_like(x)),
        (x / L, np.sin(2 * math.pi * x / L)),
        (np.sin(3 * math.pi * x / L), np.cos(math.pi * x / L)),
    ]
    ej = np.array([finger.ej(v)[0] for v in x])
    ea = np.array([finger.ea(v)[0] for v in x])
    out = []
    for deta, zeta in variations:
        if not finger.extensible:
            zeta = np.zeros_like(x)
        scale_tp = eps * np.abs(sol.curvature_b_reference).max()
        scale_q = eps * max(np.abs(sol.axial_strain).max(), 1e-6)
        plus = _energy(
            finger,
            x,
            sol.curvature_b_reference + scale_tp * deta,
            sol.axial_strain + scale_q * zeta,
        )
        minus = _energy(
            finger,
            x,
            sol.curvature_b_reference - scale_tp * deta,
            sol.axial_strain - scale_q * zeta,
        )
        d_pi = (plus - minus) / 2.0
        norm = scipy.integrate.simpson(
            np.abs(ej * sol.curvature_b_reference * scale_tp * deta)
            + np.abs(ea * sol.axial_strain * scale_q * zeta),
            x=x,
        )
        out.append(abs(d_pi) / norm)
    return np.array(out)


@pytest.mark.parametrize(
    "extensible, curvature",
    [(True, "reference"), (False, "reference"), (False, "deformed")],
)
def test_total_potential_is_stationary(extensible, curvature):
    """The first variation of int W dx + tau l vanishes at the solved default finger (and does
    not for the solution at 1% more tension: the check has teeth)."""
    finger = default_finger(2.0, extensible=extensible, curvature=curvature)
    sol = solve_finger(finger, n_points=2001)
    assert _first_variations(finger, sol).max() < 1e-7
    wrong = solve_finger(with_tension(finger, 2.02), n_points=2001)
    assert _first_variations(finger, wrong).max() > 1e-3


# ------------------------------------------------------------------------------------------------
# Two independent formulations agree
# ------------------------------------------------------------------------------------------------
def _assert_same(a, b, tol):
    scale_m = np.abs(b.moment).max()
    scale_n = max(np.abs(b.axial_force).max(), 1e-12)
    assert np.abs(a.position - b.position).max() < tol * L
    assert np.abs(a.theta - b.theta).max() < tol
    assert np.abs(a.moment - b.moment).max() < tol * scale_m
    assert np.abs(a.axial_force - b.axial_force).max() < tol * scale_n
    assert np.abs(a.shear_force - b.shear_force).max() < tol * scale_n
    assert np.abs(a.tendon_lengths - b.tendon_lengths).max() < tol * L


@pytest.mark.parametrize(
    "finger",
    [
        default_finger(2.0),
        default_finger(30.0, curvature="reference"),
        _kinked_two_tendons(),
        TaperedFinger(
            tendons=(
                Tendon(
                    tension=1.0,
                    offset_fn=(
                        lambda x: 0.006 + 0.002 * np.sin(30 * x),
                        lambda x: 0.06 * np.cos(30 * x),
                    ),
                ),
            )
        ),
    ],
    ids=["default", "curled", "kinked-two-tendons", "callable"],
)
def test_shooting_matches_cut(finger):
    """Distributed loads + point loads + free-tip shooting == cut through rod and tendons."""
    _assert_same(solve_finger(finger), solve_finger(finger, method="cut"), 1e-8)


def test_entry_and_anchor_bound_the_loaded_region():
    """Before the first entry the rod is unloaded and straight; tendon 0 ends at its anchor."""
    sol = solve_finger(_kinked_two_tendons(), n_points=101)
    outside = sol.x < 0.01
    tol = 1e-9  # the shooting's base reactions are zero to solver tolerance only
    assert np.abs(sol.theta[outside]).max() < tol * np.abs(sol.theta).max()
    assert np.abs(sol.axial_force[outside]).max() < tol * np.abs(sol.axial_force).max()
    assert np.abs(sol.moment[outside]).max() < tol * np.abs(sol.moment).max()
    assert np.isnan(sol.tendon_paths[0][sol.x > 0.0801]).all()
    assert np.all(sol.moment[~outside] != 0.0)


def test_opposed_tendons_cancel_bending():
    """Equal tensions at +-delta: no bending, pure compression N = -2 tau alpha / w."""
    tau = 3.0
    tendons = (
        Tendon(tension=tau, offset_base=0.008, offset_tip=0.004),
        Tendon(tension=tau, offset_base=-0.008, offset_tip=-0.004),
    )
    sol = solve_finger(TaperedFinger(tendons=tendons), n_points=51)
    assert np.abs(sol.theta).max() < 1e-12
    assert np.abs(sol.position[:, 1]).max() < 1e-12 * L
    q = sol.axial_strain
    n_expected = -2 * tau * (1 + q) / np.hypot(1 + q, 0.004 / L)
    assert np.abs(sol.axial_force - n_expected).max() < 1e-9 * tau


# ------------------------------------------------------------------------------------------------
# Limits and options
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("curvature", ["reference", "deformed"])
def test_stiff_extensible_tends_to_inextensible(curvature):
    inex = solve_finger(default_finger(2.0, extensible=False, curvature=curvature))
    stiff = solve_finger(default_finger(2.0, ea_factor=1e6, curvature=curvature))
    soft = solve_finger(default_finger(2.0, curvature=curvature))
    tip = np.array([inex.tip_u, inex.tip_v, inex.tip_theta * L])
    assert np.abs(np.array([stiff.tip_u, stiff.tip_v, stiff.tip_theta * L]) - tip).max() < 1e-6 * L
    assert np.abs(np.array([soft.tip_u, soft.tip_v, soft.tip_theta * L]) - tip).max() > 1e-4 * L


def test_reference_and_deformed_curvature_coincide_when_inextensible():
    ref = solve_finger(default_finger(5.0, extensible=False, curvature="reference"))
    dfm = solve_finger(default_finger(5.0, extensible=False, curvature="deformed"))
    _assert_same(ref, dfm, 1e-10)
    ext_ref = solve_finger(default_finger(5.0, curvature="reference"))
    ext_dfm = solve_finger(default_finger(5.0, curvature="deformed"))
    assert abs(ext_ref.tip_theta - ext_dfm.tip_theta) > 1e-4


def test_looped_symmetric_equals_double_tension():
    tau = 1.2
    left, right = looped_tendon(0.004, 0.008, 0.004, 0.008, L, tau)
    assert left.profile(L)(0.0, 0.0)[0] == 0.008 and left.profile(L)(L, L)[0] == 0.004
    looped = solve_finger(TaperedFinger(tendons=(left, right)))
    single = solve_finger(default_finger(2 * tau))
    assert abs(looped.tip_u - single.tip_u) < 1e-10 * L
    assert abs(looped.tip_v - single.tip_v) < 1e-10 * L
    assert abs(looped.tip_theta - single.tip_theta) < 1e-10
    assert np.allclose(looped.pull_in, single.pull_in[0], rtol=1e-9, atol=0)


def test_figure_3_8_trends():
    """Fig. 3.8: torsion and curvature about n vanish; curvature about b and |q| grow tipward."""
    sol = solve_finger(default_finger(1.0), n_points=21)
    assert np.all(sol.torsion == 0.0) and np.all(sol.curvature_n == 0.0)
    assert np.all(np.diff(sol.curvature_b_deformed) > 0)
    assert np.all(np.diff(np.abs(sol.axial_strain)) > 0)
    assert np.all(sol.compression > 0)


# ------------------------------------------------------------------------------------------------
# Inverse problems
# ------------------------------------------------------------------------------------------------
def test_tension_for_tip_angle_reproduces_forward():
    finger = default_finger(0.0)
    target = solve_finger(with_tension(finger, 0.7)).tip_theta
    tau = tension_for_tip_angle(target, finger)
    assert abs(tau - 0.7) < 1e-8
    assert abs(solve_finger(with_tension(finger, tau)).tip_theta - target) < 1e-10


def test_tension_for_pull_in_reproduces_forward():
    left, right = looped_tendon(0.004, 0.008, 0.003, 0.007, L, 0.0)
    finger = TaperedFinger(tendons=(left, right))
    target = float(np.sum(solve_finger(with_tension(finger, 1.3)).pull_in))
    tau = tension_for_pull_in(target, finger)
    assert abs(tau - 1.3) < 1e-8
    assert abs(np.sum(solve_finger(with_tension(finger, tau)).pull_in) - target) < 1e-12


# ------------------------------------------------------------------------------------------------
# Validation
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "make, field",
    [
        (lambda: TaperedFinger(length=0.0), "length"),
        (lambda: TaperedFinger(width=-1.0), "width"),
        (lambda: TaperedFinger(height_tip=float("nan")), "height_tip"),
        (lambda: TaperedFinger(young="soft"), "young"),
        (lambda: TaperedFinger(ea_factor=0), "ea_factor"),
        (lambda: TaperedFinger(curvature="lagrangian"), "curvature"),
        (lambda: TaperedFinger(extensible=1), "extensible"),
        (lambda: TaperedFinger(tendons=(1,)), "tendons"),
        (lambda: Tendon(tension=-1.0, offset_base=0.0, offset_tip=0.0), "tension"),
        (lambda: Tendon(tension=1.0), "offset"),
        (
            lambda: Tendon(tension=1.0, offset_base=0.0, offset_tip=0.0, points=((0, 0), (1, 0))),
            "offset",
        ),
        (lambda: Tendon(tension=1.0, points=((0, 0), (0, 1))), "points"),
        (lambda: Tendon(tension=1.0, offset_fn=(math.sin,)), "offset_fn"),
        (
            lambda: Tendon(tension=1.0, offset_base=0.0, offset_tip=0.0, entry=0.05, anchor=0.04),
            "anchor",
        ),
        (
            lambda: TaperedFinger(
                tendons=(Tendon(tension=1.0, offset_base=0.0, offset_tip=0.0, anchor=0.2),)
            ),
            "anchor",
        ),
        (
            lambda: TaperedFinger(tendons=(Tendon(tension=1.0, points=((0.0, 0.0), (0.05, 0.0))),)),
            "points",
        ),
        (lambda: solve_finger(default_finger(), method="fd"), "method"),
        (lambda: solve_finger(default_finger(), n_points=1), "n_points"),
        (lambda: solve_finger(default_finger(), rtol=0.1), "rtol"),
        (lambda: tension_for_tip_angle(float("inf")), "target_theta"),
        (lambda: looped_tendon(0.004, 0.008, 0.004, 0.008, -1.0, 1.0), "length"),
    ],
)
def test_bad_parameters_raise(make, field):
    with pytest.raises(ValueError, match=field):
        make()

"""Verification of the 1D large-deflection statics (issue: foundation)."""

import math

import numpy as np
import pytest
from beam_cases import NU, E, bending_stiffness, cantilever, tip
from mpi4py import MPI

from fe_beam import BeamModel, Discretisation, Loads, Material, ModelOptions, Section, Supports
from fe_beam.analytic import elastica_tip_load, timoshenko_cantilever_deflection

H = 0.01
EI = bending_stiffness(H)


def observed_orders(sizes, errors):
    sizes, errors = np.log(np.asarray(sizes, float)), np.log(np.abs(errors))
    return -np.diff(errors) / np.diff(sizes)


@pytest.mark.parametrize("k", [1, 2, 5, 10])
def test_elastica_matches_mattiasson(mattiasson, k):
    """Reissner law + inextensible-unshearable = Euler elastica; tip within 1e-4 of Mattiasson."""
    end = tip(cantilever(elements=20, tip_force=(0.0, -k * EI)), steps=10)
    i = mattiasson["k"].index(k)
    assert -end["u"] == pytest.approx(mattiasson["shortening"][i], abs=1e-4)
    assert -end["v"] == pytest.approx(mattiasson["deflection"][i], abs=1e-4)
    assert -end["theta"] == pytest.approx(mattiasson["rotation"][i], abs=1e-4)


def test_nonstandard_law_tends_to_elastica_as_beam_gets_thin():
    """MODEL.md 6: the constrained non-standard law is M = EI k + EI4 k^3 / 2, which tends to the
    elastica as h/L -> 0 (difference O((h/L)^2))."""
    exact = elastica_tip_load(5.0)
    differences = []
    for h in (0.1, 0.05, 0.025):
        end = tip(
            cantilever(
                "nonstandard", h=h, elements=16, tip_force=(0.0, -5.0 * bending_stiffness(h))
            )
        )
        differences.append(abs(-end["v"] - exact.deflection))
    assert differences[0] > 5e-4  # the law is not the elastica at h/L = 0.1 ...
    slenderness = [1 / 0.1, 1 / 0.05, 1 / 0.025]
    assert observed_orders(slenderness, differences) == pytest.approx([2, 2], abs=0.15)


def test_tip_moment_rolls_beam_into_full_circle():
    """M = 2 pi EI / L bends an inextensible beam into a closed circle."""
    model = cantilever(elements=40, tip_moment=2 * math.pi * EI)
    end = tip(model, steps=10)
    assert end["theta"] == pytest.approx(2 * math.pi, abs=1e-9)
    assert math.hypot(1.0 + end["u"], end["v"]) < 1e-6


def test_nonstandard_circle_approaches_closed_circle_as_h_shrinks():
    gaps = []
    for h in (0.02, 0.01):
        model = cantilever(
            "nonstandard",
            "inextensible",
            h=h,
            elements=40,
            tip_moment=2 * math.pi * bending_stiffness(h),
        )
        end = tip(model, steps=10)
        gaps.append(math.hypot(1.0 + end["u"], end["v"]))
    assert gaps[1] < gaps[0] / 3


@pytest.mark.parametrize("law", ["reissner", "nonstandard"])
@pytest.mark.parametrize("slenderness", [10, 1e2, 1e3, 1e4])
@pytest.mark.parametrize("degree", [1, 2])
def test_no_shear_or_membrane_locking(law, slenderness, degree):
    """8 elements, small tip load: deflection within 0.1% of PL^3/(3EI) + PL/(kGA) for degree 2;
    degree 1 (one-point rule) has the known discretisation error PL^3/(3EI) / (4 n^2) instead,
    whatever L/h (a locking element would be off by orders of magnitude at L/h = 1e4)."""
    h = 1.0 / slenderness
    ei, ga = bending_stiffness(h), E / (2 * (1 + NU)) * h * h
    load = 1e-5 * ei
    model = cantilever(law, "none", elements=8, degree=degree, h=h, tip_force=(0.0, load))
    expected = timoshenko_cantilever_deflection(load, 1.0, ei, ga)
    tolerance = 1e-3 if degree == 2 else 1 / (4 * 8**2) + 1e-4
    assert tip(model, steps=1)["v"] == pytest.approx(expected, rel=tolerance)


@pytest.mark.parametrize("degree, order", [(1, 2), (2, 4)])
def test_convergence_order_of_tip_error(degree, order):
    """Tip error of the elastica (k = 2) vs the elliptic-integral solution, under refinement."""
    exact = elastica_tip_load(2.0)
    sizes = [4, 8, 16] if degree == 2 else [8, 16, 32]
    errors = [
        abs(
            -tip(cantilever(elements=n, degree=degree, tip_force=(0.0, -2 * EI)))["v"]
            - exact.deflection
        )
        for n in sizes
    ]
    rates = observed_orders(sizes, errors)
    assert rates == pytest.approx([order] * len(rates), abs=0.25)


@pytest.mark.parametrize("law", ["reissner", "nonstandard"])
def test_uniform_tension_patch_test(law):
    """Axial tip force on 3 elements: uniform strain, exact to round-off."""
    area, force = H * H, 0.02 * E * H * H
    model = cantilever(law, "none", elements=3, degree=1, tip_force=(force, 0.0))
    end = tip(model, steps=1)
    if law == "reissner":
        stretch = 1 + force / (E * area)
    else:  # force along the axis = EA eps (1 + u'), eps = ((1 + u')^2 - 1) / 2
        stretch = np.roots([0.5, 0.0, -0.5, -force / (E * area)]).real.max()
    assert end["u"] == pytest.approx(stretch - 1, rel=1e-10)
    assert abs(end["v"]) < 1e-14 and abs(end["theta"]) < 1e-14


def follower_elastica(k: float) -> dict:
    """Elastica (L = EI = 1) under a tip force k normal to the tip section, by shooting: with
    the tip angle alpha the force is the dead force k (-sin alpha, cos alpha), so
    theta'' = -k cos(theta - alpha), theta(0) = 0, theta'(1) = 0, and alpha = theta(1)."""
    from scipy.integrate import solve_ivp
    from scipy.optimize import fsolve

    def shoot(unknowns):
        curvature0, alpha = unknowns
        solution = solve_ivp(
            lambda s, y: [y[1], -k * math.cos(y[0] - alpha), math.cos(y[0]), math.sin(y[0])],
            (0.0, 1.0), [0.0, curvature0, 0.0, 0.0], rtol=1e-12, atol=1e-14)
        return solution.y[:, -1]

    def mismatch(unknowns):
        end = shoot(unknowns)
        return [end[1], end[0] - unknowns[1]]

    curvature0, alpha = fsolve(mismatch, [k, k / 2], xtol=1e-13)
    end = shoot([curvature0, alpha])
    return {"theta": alpha, "u": end[2] - 1.0, "v": end[3]}


@pytest.mark.parametrize(("k", "dead_difference"), [(1.0, 0.0345), (3.0, 0.413)])
def test_follower_tip_force_matches_the_follower_elastica(k, dead_difference):
    """A follower force stays normal to the tip: against an independent shooting solution of
    the same elastica, 40 P2 elements (measured 5e-10 at k = 1, 8e-9 at k = 3; 16x less than
    with 20: fourth order). The dead load of the same size gives another tip angle."""
    exact = follower_elastica(k)
    end = tip(cantilever(elements=40, tip_force=(0.0, k * EI), follower=True))
    for key in ("u", "v", "theta"):
        assert end[key] == pytest.approx(exact[key], abs=3e-8), key
    dead = tip(cantilever(elements=20, tip_force=(0.0, k * EI)))
    assert exact["theta"] - dead["theta"] == pytest.approx(dead_difference, rel=0.01)


def test_tapered_custom_and_shape_sections_agree():
    """A tapered rectangle and the equivalent custom section give the same tip."""
    b, h0, h1 = 0.02, 0.02, 0.01
    loads = Loads(tip_force=(0.0, 0.05))
    common = dict(
        material=Material(6e5, nu=0.45),
        options=ModelOptions("reissner"),
        mesh=Discretisation(30, 2),
        supports=Supports(),
        loads=loads,
    )
    rectangle = BeamModel(0.1, Section("rectangle", {"b": b, "h": h0}, {"h": h1}), **common)
    end = tip(rectangle)
    # Uniform section with the tip's height bends more than the tapered one, base height less.
    stiff = tip(BeamModel(0.1, Section("rectangle", {"b": b, "h": h0}), **common))
    soft = tip(BeamModel(0.1, Section("rectangle", {"b": b, "h": h1}), **common))
    assert stiff["v"] < end["v"] < soft["v"]


def test_prescribed_end_rotation():
    """Clamped-clamped beam whose end x = L is turned by pi/2: exact for the elastica is a
    pure-bending arc when u, v at x = L are free in the axial direction only via a roller."""
    model = BeamModel(
        1.0,
        Section("rectangle", {"b": H, "h": H}),
        Material(E, nu=NU),
        ModelOptions("reissner", "inextensible-unshearable"),
        Discretisation(20, 2),
        Supports("clamped", ("theta",), prescribed_xL={"theta": math.pi / 2}),
    )
    end = tip(model)
    assert end["theta"] == pytest.approx(math.pi / 2, abs=1e-12)
    radius = 1.0 / (math.pi / 2)
    assert 1.0 + end["u"] == pytest.approx(radius, abs=1e-6)
    assert end["v"] == pytest.approx(radius, abs=1e-6)


@pytest.mark.mpi
def test_parallel_equals_serial():
    """The same problem on all ranks together and on each rank alone agrees to 1e-10."""
    model = cantilever(
        "nonstandard", "none", elements=24, tip_force=(0.0, -4 * EI), tip_moment=0.5 * EI
    )
    together = tip(model, comm=MPI.COMM_WORLD)
    alone = tip(model, comm=MPI.COMM_SELF)
    for key in ("u", "v", "theta"):
        assert together[key] == pytest.approx(alone[key], rel=1e-10, abs=1e-12)


# --- other loads and sections --------------------------------------------------------------------
GA = E / (2 * (1 + NU)) * H * H


@pytest.mark.parametrize("law", ["reissner", "nonstandard"])
def test_distributed_load_matches_timoshenko(law):
    """Small uniform load q on a cantilever: v(L) = q L^4 / (8 EI) + q L^2 / (2 GA)."""
    q = 1e-5 * EI
    model = cantilever(law, "none", elements=8, distributed=(0.0, q))
    expected = q / (8 * EI) + q / (2 * GA)
    end = tip(model, steps=1)
    assert end["v"] == pytest.approx(expected, rel=2e-4)
    assert end["theta"] == pytest.approx(q / (6 * EI), rel=2e-4)


def test_gravity_is_the_distributed_weight_at_large_deflection():
    """rho A g per unit length, deflected far from linear (q L^3 / EI = 8)."""
    from dataclasses import replace

    rho, g = 1000.0, -9.81
    weight = rho * H * H * g
    base = cantilever("nonstandard", "none", elements=16)
    scale = 8 * EI / abs(weight)  # gravity scaled through the density: same weight
    heavy = replace(base, material=Material(E, nu=NU, rho=rho * scale),
                    loads=Loads(gravity=(0.0, g)))
    loaded = replace(base, loads=Loads(distributed=(0.0, weight * scale)))
    by_gravity, by_load = tip(heavy, steps=8), tip(loaded, steps=8)
    assert by_gravity["v"] < -0.5  # large deflection
    for key in ("u", "v", "theta"):
        assert by_gravity[key] == pytest.approx(by_load[key], rel=1e-12, abs=1e-14)


@pytest.mark.parametrize("law", ["reissner", "nonstandard"])
def test_simply_supported_uniform_load(law):
    """Pinned-roller, small uniform load: end rotation q L^3 / (24 EI) (shear does not change
    it); the roller end slides in by the second-order shortening only."""
    from dataclasses import replace

    q = -1e-5 * EI
    model = replace(cantilever(law, "none", elements=8, distributed=(0.0, q)),
                    supports=Supports("pinned", "roller"))
    end = tip(model, steps=1)
    assert end["theta"] == pytest.approx(-q / (24 * EI), rel=1e-4)
    assert end["v"] == 0.0
    assert abs(end["u"]) < 1e-6 * abs(q / (24 * EI))


def test_t_section_in_pure_bending_has_the_uniform_state_of_the_nonstandard_law():
    """Tip moment on a T-section (I3 != 0): N = 0 and T = 0 everywhere, so gamma = 0, and the
    uniform (eps, kappa) solve N(eps, kappa) = 0, M(eps, kappa) = M0 with the MODEL.md laws
    (the I3 and I4 terms couple stretching to bending). The tip is on the circle of radius
    lambda / kappa: theta = kappa L, u = lambda sin(kappa L) / kappa - L, v = lambda (1 -
    cos(kappa L)) / kappa."""
    from dataclasses import replace

    from scipy.optimize import fsolve

    section = Section("t-section", {"b": 0.1, "h": 0.1, "tf": 0.02, "tw": 0.02})
    p = section.properties(0.0)
    moment = 2.0 * E * p.I  # kappa about 2 / m, kappa h ~ 0.2: I3, I4 terms matter
    assert abs(p.I3) * 2.0 > 0.02 * p.I  # I3 kappa / I: a few per cent of coupling

    def laws(unknowns):
        eps, kappa = unknowns
        stretch = math.sqrt(2 * eps + 1)
        normal = (eps / stretch * E * p.A + 3 / (2 * stretch) * kappa**2 * E * p.I
                  + kappa**3 * E * p.I3 / (2 * stretch**2))
        bending = ((3 * eps + 1) * kappa * E * p.I + 1.5 * stretch * kappa**2 * E * p.I3
                   + 0.5 * kappa**3 * E * p.I4)
        return [normal, bending - moment]

    eps, kappa = fsolve(laws, [0.0, moment / (E * p.I)], xtol=1e-13)
    assert np.allclose(laws([eps, kappa]), 0.0, atol=1e-9 * moment)
    stretch = math.sqrt(2 * eps + 1)
    exact = (stretch * math.sin(kappa) / kappa - 1.0, stretch * (1 - math.cos(kappa)) / kappa)
    errors = []
    for elements in (10, 20):
        model = replace(cantilever("nonstandard", "none", elements=elements, tip_moment=moment),
                        section=section)
        end = tip(model, steps=4)
        assert end["theta"] == pytest.approx(kappa, rel=1e-9)  # theta is linear: exact in P2
        errors.append(math.hypot(end["u"] - exact[0], end["v"] - exact[1]))
    print(f"T-section circle: eps = {eps:.4e}, kappa = {kappa:.6f}, tip errors {errors}")
    assert errors[1] < 1e-7 and errors[1] < errors[0] / 8  # the arc's P2 interpolation error

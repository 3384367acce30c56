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


def test_follower_tip_force_stays_normal_to_tip():
    """A follower force normal to the tip section bends a beam more than the same dead force."""
    dead = tip(cantilever(elements=20, tip_force=(0.0, 3 * EI)))
    follower = tip(cantilever(elements=20, tip_force=(0.0, 3 * EI), follower=True))
    assert follower["theta"] > dead["theta"] + 0.3


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

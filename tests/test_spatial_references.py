"""The spatial finite-element rod against the independent shooting solver
(`fe_beam.baselines.spatial_shooting`, numpy/scipy, its tendon loads derived the Rucker-Webster
way, not from an energy), with observed convergence orders."""

import json
import math

import numpy as np
import pytest
from mpi4py import MPI
from tomlio import dump_toml

from fe_beam.baselines.spatial_shooting import Tendon, solve_cantilever
from fe_beam.cli import main
from fe_beam.config.finger import parse_finger
from fe_beam.config.schema import parse_static
from fe_beam.model.settings import LoadStepping
from fe_beam.solvers.rod_static import StaticContinuation

# --- Bathe & Bolourchi's 45-degree bend (R = 100, unit square, E = 1e7, G = 5e6) ---------------
K_SHEAR = 5 / 6


def bend_config(elements, degree=2):
    return {
        "beam": {"length": 100 * math.pi / 4, "initial_curvature": [0.0, 0.0, 0.01]},
        "section": {"shape": "custom", "A": 1.0, "I": 1 / 12, "I_y": 1 / 12, "J": 1 / 6,
                    "b": 1.0, "h": 1.0},
        "material": {"E": 1e7, "G": 5e6},
        "model": {"kinematics": "spatial", "law": "reissner", "shear_correction": K_SHEAR},
        "mesh": {"elements": elements, "degree": degree},
        "loads": {"tip_force": [0.0, 0.0, 600.0], "steps": 6},
    }


def fe_tip(config, steps=6):
    run = StaticContinuation(parse_static(config), MPI.COMM_WORLD)
    try:
        run.advance(1.0, LoadStepping(steps=steps))
        return np.array(run.problem.end_values()["position"])
    finally:
        run.destroy()


@pytest.fixture(scope="module")
def bend_reference():
    return solve_cantilever(100 * math.pi / 4, 1e7, K_SHEAR * 5e6, 5e6 / 6, 1e7 / 12, 1e7 / 12,
                            tip_force=(0.0, 0.0, 600.0), u0=(0.0, 0.0, 0.01), steps=6,
                            rtol=1e-12).tip_position


@pytest.mark.parametrize("degree, order", [(1, 2.0), (2, 4.0)])
def test_bathe_bolourchi_bend_converges_to_the_shooting_solution(bend_reference, degree, order):
    """The tip at P = 600 converges to the shooting solver's at the observed order 2 (P1) and
    4 (P2, the Gauss rule of p points is superconvergent at the nodes); on the finest mesh
    within 1e-6 of the bend's radius."""
    meshes = (8, 16, 32) if degree == 2 else (16, 32, 64)
    errors = [np.abs(fe_tip(bend_config(n, degree)) - bend_reference).max() for n in meshes]
    rates = [math.log2(a / b) for a, b in zip(errors, errors[1:], strict=False)]
    assert min(rates) > order - 0.3, (errors, rates)
    assert errors[-1] < (1e-4 if degree == 2 else 1e-2), errors


# --- the helical tendon (Rucker-Webster) -------------------------------------------------------
L, D, E, TAU = 0.1, 0.015, 1e6, 2.0
RADIUS = 0.004


def helix(s):
    return (RADIUS * np.cos(np.pi * s / (2 * L)), RADIUS * np.sin(np.pi * s / (2 * L)))


@pytest.fixture(scope="module")
def helical_reference():
    area, inertia = math.pi * D**2 / 4, math.pi * D**4 / 64
    G = E / (2 * (1 + 0.45))
    return solve_cantilever(L, E * area, 0.9 * G * area, G * 2 * inertia, E * inertia,
                            E * inertia, tendons=(Tendon(TAU, helix),), steps=6, rtol=1e-12)


def finger(elements):
    return {
        "beam": {"length": L},
        "section": {"shape": "circle", "d": D},
        "material": {"E": E, "nu": 0.45},
        "model": {"kinematics": "spatial", "law": "reissner", "shear_correction": 0.9},
        "mesh": {"elements": elements},
        "tendons": [{"name": "helix", "offset_y": f"{RADIUS}*cos(pi*s/(2*L))",
                     "offset_z": f"{RADIUS}*sin(pi*s/(2*L))", "tension": TAU}],
        "loads": {"steps": 6},
        "output": {"plots": False, "xdmf": False},
    }


def test_helical_tendon_against_rucker_webster(tmp_path, helical_reference):
    """`fe-beam finger` with a helical tendon (its potential tau * length, differentiated by
    UFL) against the Rucker-Webster loads integrated by shooting: the tip to 1e-7 L on 32
    elements, converging at order 4, and out of the x-y plane toward +z as the helix ends
    there."""
    errors = []
    for elements in (8, 16, 32):
        path = tmp_path / f"f{elements}.toml"
        path.write_text(dump_toml(finger(elements)))
        out = tmp_path / f"out{elements}"
        assert main(["finger", str(path), "--out", str(out), "--quiet"]) == 0
        tip = json.loads((out / "summary.json").read_text())["steps"][-1]["tip"]
        errors.append(np.abs(np.array(tip["position"]) - helical_reference.tip_position).max())
        assert tip["w"] > 0.1 * abs(tip["v"]) > 0
    assert errors[-1] < 1e-7 * L, errors
    assert math.log2(errors[1] / errors[2]) > 3.5, errors


def test_tendon_at_an_anchor_short_of_the_tip(tmp_path):
    """Two tendons, one anchored at 0.6 L (a constant offset) and the helix to the tip: the
    anchor's point load and the kink it gives the other tendon, against the shooting solver."""
    area, inertia = math.pi * D**2 / 4, math.pi * D**4 / 64
    G = E / (2 * (1 + 0.45))
    reference = solve_cantilever(
        L, E * area, 0.9 * G * area, G * 2 * inertia, E * inertia, E * inertia,
        tendons=(Tendon(TAU, helix), Tendon(0.7, (-0.003, 0.002), anchor=0.6 * L)), steps=6,
        rtol=1e-12).tip_position
    config = finger(32)
    config["tendons"].append({"name": "short", "offset_y": -0.003, "offset_z": 0.002,
                              "anchor": 0.6 * L, "tension": 0.7})
    run = StaticContinuation(parse_finger(config)[0], MPI.COMM_WORLD)
    try:
        run.advance(1.0, LoadStepping(steps=6))
        tip = np.array(run.problem.end_values()["position"])
    finally:
        run.destroy()
    assert np.abs(tip - reference).max() < 1e-6 * L


# --- other loads ---------------------------------------------------------------------------------
def stiff_rod(changes):
    config = {
        "beam": {"length": 1.0},
        "section": {"shape": "rectangle", "b": 0.03, "h": 0.05},
        "material": {"E": 1e7, "nu": 0.3},
        "model": {"kinematics": "spatial", "law": "reissner"},
        "mesh": {"elements": 32},
        "loads": {"steps": 8},
    }
    for dotted, value in changes.items():
        table, key = dotted.split(".", 1)
        config[table][key] = value
    return config


def stiffness():
    from fe_beam.model.sections import Section

    p = Section("rectangle", {"b": 0.03, "h": 0.05}).spatial_properties()
    E, G = 1e7, 1e7 / 2.6
    return dict(EA=E * p.A, GA=G * p.A, GJ=G * p.J, EIy=E * p.Iy, EIz=E * p.Iz)


@pytest.mark.parametrize("loads", [
    {"tip_force": (2.0, -8.0, 5.0), "tip_moment": (0.4, -0.3, 0.6), "follower": True},
    {"tip_force": (0.0, 3.0, -4.0), "tip_moment": (1.2, 0.5, -0.4), "follower": False},
    {"distributed": (0.5, -6.0, 4.0)},
])
def test_loads_against_the_shooting_solver(loads):
    """Follower and dead tip forces and moments (the dead moment's non-symmetric tangent) and a
    distributed load on a rectangle (b != h, GJ the series): the tip converges to the shooting
    solver's at order 4 (16, 32 P2 elements), within 1e-6 L on 32."""
    reference = solve_cantilever(1.0, **stiffness(), steps=8, rtol=1e-12, **loads)
    changes = {f"loads.{k}": list(v) if isinstance(v, tuple) else v for k, v in loads.items()}
    errors = []
    for elements in (16, 32):
        config = stiff_rod(changes)
        config["mesh"]["elements"] = elements
        errors.append(np.abs(fe_tip(config, steps=8) - reference.tip_position).max())
    assert errors[1] < 1e-6, errors
    assert math.log2(errors[0] / errors[1]) > 3.7, errors


def test_planar_roll_up_beyond_one_turn():
    """A tip moment about z rolling the rod 1.56 times around (|theta| = 9.8 > 2 pi): in the
    plane the rotation vector is exact; the tip on the circle of curvature M / EI, with the
    note about the parametrisation."""
    EI = 1e7 * 0.03 * 0.05**3 / 12
    config = stiff_rod({"loads.tip_moment": [0.0, 0.0, 9.8 * EI]})
    config["model"]["constraint"] = "inextensible-unshearable"
    run = StaticContinuation(parse_static(config), MPI.COMM_WORLD)
    try:
        run.advance(1.0, LoadStepping(steps=20))
        tip = np.array(run.problem.end_values()["position"])
        notes = list(run.notes)
    finally:
        run.destroy()
    assert tip == pytest.approx([math.sin(9.8) / 9.8, (1 - math.cos(9.8)) / 9.8, 0.0], abs=1e-6)
    assert any("1.8 pi" in note for note in notes)

"""Coulomb friction of the planar rod on rigid obstacles (issue 23), against closed forms.

(a) Stick, then slip: a cantilever's tip pressed on a floor by a downward tip force P (the
normal force N = P - 3 EI g / L^3, g the gap), then pulled along the floor by an axial tip force
T: while T < mu N the tip sticks (it does not move along the floor: the floor takes T, the rod
none); from T = mu N on it slips: the friction force is mu N and the rest, T - mu N, stretches
the rod (u_tip = (T - mu N) L / EA).
(b) Capstan: a thin, inextensible rod clamped at x = 0, wrapped over a disc by a dead tip force
T1 hanging vertically, then dragged over the disc by pulling the clamp away: the whole wrap
slips and the clamp's tension is T2 = T1 exp(mu phi), phi the wrap angle.
Every converged step keeps its penetration below the stated tolerance.
"""

import math

import pytest

from fe_beam.config.registry import validate
from fe_beam.solvers.rod_static import StaticContinuation

L, B, H = 1.0, 0.01, 0.01
EI = 1.0
E = 12 * EI / (B * H**3)
EA = E * B * H
MU = 0.3
TOLERANCE = 1e-9


def run_of(config: dict) -> StaticContinuation:
    return StaticContinuation(validate("static", config).parsed)


def check_penetration(run, tolerance):
    for entry in run.contact.summary():
        assert entry["contact_point_penetration"] <= tolerance, entry


@pytest.mark.mpi
def test_pressed_tip_sticks_below_mu_n_and_slips_at_it():
    gap, press = 1e-4, 1.0
    config = {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "unshearable"},
        "mesh": {"elements": 40, "degree": 2},
        "loads": {"tip_force": [0.0, -press], "steps": 2},
        "solver": {"atol": 1e-10},
        "obstacles": [{"shape": "plane", "name": "floor", "point": [0.0, -gap - H / 2],
                       "normal": [0.0, 1.0], "friction": MU}],
        "contact": {"penetration_tolerance": TOLERANCE},
        "output": {"xdmf": False, "plots": False},
    }
    parsed = validate("static", config).parsed
    run = StaticContinuation(parsed)
    run.advance(1.0, parsed.stepping)
    check_penetration(run, TOLERANCE)
    (floor,) = run.contact.summary()
    normal = floor["force"][1] - floor["friction_force"][1]
    # the propped cantilever: the floor carries P - 3 EI g / L^3 at the tip
    assert normal == pytest.approx(press - 3 * EI * gap / L**3, rel=1e-3)
    tip = run.problem.end_values("xL")
    start_u, start_corner = tip["u"], corner_x(tip)
    start_friction = floor["friction_force"][0]
    # stick: the corner touching the floor is held; T at the centreline is shared by the rod
    # (axially, EA / L) and the floor, the corner's lever h/2 rotating the propped tip
    # (theta = M L / 4 EI): the floor's share is 1 / (1 + EA h^2 / (16 EI)) of T
    share = 1 / (1 + EA * H**2 / (16 * EI))
    onset = (MU * normal + start_friction) / share  # the pull at which |F_t| reaches mu N
    records = []

    def pull(value: float) -> None:
        run.problem.tip_force.value[:] = [value, -press]

    def record(step) -> None:
        (entry,) = run.contact.summary()
        records.append((step.load_factor, entry, run.problem.end_values("xL")))

    run.advance_along(pull, 0.0, 1.5 * onset, parsed.stepping.__class__(steps=15),
                      on_converged=record)
    stuck = slipping = 0
    worst = {"stick": 0.0, "slip": 0.0, "penetration": 0.0}
    for index, (pulled, entry, tip) in enumerate(records):
        assert entry["contact_point_penetration"] <= TOLERANCE, entry
        worst["penetration"] = max(worst["penetration"], entry["contact_point_penetration"])
        n = entry["force"][1] - entry["friction_force"][1]
        # the friction moment (h/2) F_t on the propped tip changes N by 3 M / 2L
        assert n == pytest.approx(normal, rel=5e-3)
        friction = entry["friction_force"][0]
        if pulled < 0.99 * onset:
            # stick: |F_t| < mu N, the contact point does not move along the floor (a stuck
            # point keeps each step's slip below the tolerance)
            assert abs(friction) < MU * n
            assert friction - start_friction == pytest.approx(-share * pulled, rel=1e-2)
            assert abs(corner_x(tip) - start_corner) <= (index + 1) * TOLERANCE, (pulled, tip)
            assert entry["slip"] == []
            worst["stick"] = max(worst["stick"], abs(corner_x(tip) - start_corner))
            stuck += 1
        elif pulled > 1.01 * onset:
            # slip: the friction force is mu N, the rest of T stretches the rod
            assert friction == pytest.approx(-MU * n, rel=1e-3)
            worst["slip"] = max(worst["slip"], abs(friction / (MU * n) + 1))
            moved = tip["u"] - start_u
            assert moved == pytest.approx((pulled - MU * n - start_friction) * L / EA,
                                          rel=2e-2)
            assert corner_x(tip) - start_corner > 100 * TOLERANCE
            assert entry["slip"] == [[L, L]]
            slipping += 1
    assert stuck >= 5 and slipping >= 3, (stuck, slipping)
    print("friction on a floor:", worst)


def corner_x(tip: dict) -> float:
    """x of the tip section's lower corner (the contact point on the floor)."""
    return L + tip["u"] + H / 2 * math.sin(tip["theta"])


@pytest.mark.mpi
def test_capstan_over_a_disc():
    """A thin inextensible rod (h = R / 100, EI / (T1 R^2) = 1e-2) clamped at x = 0 level with
    the disc's top, wrapped a quarter turn over it by a dead tip force T1 hanging vertically
    (frictionless approach), then dragged over the disc (friction on) by pulling the clamp away:
    the whole contact slips and the clamp's tension is T2 = T1 exp(mu phi R / (R + h/2)) with
    phi = pi/2 - the capstan formula, with the friction acting at the inner surface (radius R)
    and the tension at the centreline (R + h/2): the moment balance about the disc's centre.
    The bending boundary layers (length sqrt(EI/T1) = R / 10) leave ~1e-3."""
    from fe_beam.solvers.newton import LoadStepping

    radius, thin, tension, bending = 0.1, 0.001, 1.0, 1e-4
    length, centre, pull = 0.4, 0.1, 0.02
    config = {
        "beam": {"length": length},
        "section": {"shape": "rectangle", "b": thin, "h": thin},
        "material": {"E": 12 * bending / thin**4, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable"},
        "mesh": {"elements": 100, "degree": 2},
        "loads": {"tip_force": [0.0, -tension], "prescribed_x0": {"u": -pull}, "steps": 1},
        "obstacles": [{"shape": "cylinder", "name": "disc", "friction": MU, "radius": radius,
                       "point": [centre, -radius - thin / 2 - 1e-5]}],
        "contact": {"penetration_tolerance": 1e-8, "penalty": 100.0, "max_updates": 200},
        "output": {"xdmf": False, "plots": False},
    }
    run = run_of(config)
    problem = run.problem

    def load(value: float) -> None:  # the tip force alone (the clamp stays put)
        problem.load_factor.value = value

    def load_log(value: float) -> None:  # 0.01 ... 1: the wrap grows with log(T)
        problem.load_factor.value = 0.01 * 100.0**value

    run.contact.set_friction(0, 0.0)
    run.advance_along(load, 0.0, 0.01, LoadStepping(steps=10))
    run.advance_along(load_log, 0.0, 1.0, LoadStepping(steps=20))
    run.contact.set_friction(0, MU)
    states = []

    def record(step) -> None:
        check_penetration(run, 1e-8)
        states.append((run.contact.summary()[0], problem.end_reaction("x0"),
                       problem.end_values("xL")))

    run.advance_along(problem.set_prescribed_factor, 0.0, 1.0, LoadStepping(steps=4),
                      on_converged=record)
    disc, clamp, tip = states[-1]
    assert disc["slip"] == disc["active"]  # the whole contact slides
    phi = -tip["theta"]  # the hanging leg's direction; the clamped leg is horizontal
    assert phi == pytest.approx(math.pi / 2, abs=1e-5)
    ratio = math.hypot(clamp["Fx"], clamp["Fy"]) / tension
    expected = math.exp(MU * phi * radius / (radius + thin / 2))
    print(f"capstan: T2/T1 = {ratio:.6f}, exp(mu phi R/(R + h/2)) = {expected:.6f} "
          f"({ratio / expected - 1:.2e}), exp(mu phi) = {math.exp(MU * phi):.6f} "
          f"({ratio / math.exp(MU * phi) - 1:.2e})")
    assert ratio == pytest.approx(expected, rel=2.5e-3)
    # the rod's equilibrium: clamp + disc + tip force = 0
    assert clamp["Fx"] + disc["force"][0] == pytest.approx(0.0, abs=1e-6)
    assert clamp["Fy"] + disc["force"][1] - tension == pytest.approx(0.0, abs=1e-6)

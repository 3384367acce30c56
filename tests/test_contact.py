"""Contact of the planar rod with rigid obstacles (issue 23), against closed forms.

(a) Small deflection: a cantilever under a uniform load q above a frictionless plane at a
surface gap g: no contact below q1 = 8 EI g / L^4; the tip reaction R = 3 q L / 8 - 3 EI g / L^3
for q1 < q < 9 q1 (tip contact only); above 9 q1 the rod lies on the plane over [a, L] with
a = (72 EI g / q)^(1/4) (the free span [0, a] is clamped at 0 and has v = -g, v' = 0, M = 0 at
a: EI v(a) = -q a^4 / 72), the plane carrying q (L - a) + q a / 3 = q L - 2 q a / 3.
(b) Large deflection: an elastica (Reissner, inextensible-unshearable) pushed by a dead tip
force P onto a floor placed where the elliptic-integral elastica at P_touch = 2 EI / L^2 puts
the tip section's lower corner: beyond P_touch the shape stays that of P_touch and the floor
carries P - P_touch.
Every converged step keeps its penetration below the stated tolerance.
"""

import math

import pytest

from fe_beam.analyses.static import solve_static
from fe_beam.analytic import elastica_tip_load
from fe_beam.config.registry import validate

L, B, H = 1.0, 0.01, 0.01
EI = 1.0
E = 12 * EI / (B * H**3)
GAP = 1e-4
Q1 = 8 * EI * GAP / L**4
TOLERANCE = 1e-9


def cantilever(q: float, steps: int, elements: int = 100, **contact) -> dict:
    return {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable"},
        "mesh": {"elements": elements, "degree": 2},
        "loads": {"distributed": [0.0, -q], "steps": steps},
        # the residual's round-off floor is EA eps: loads of 1e-4 N/m need an absolute floor
        "solver": {"atol": 1e-10},
        "obstacles": [{"shape": "plane", "name": "floor", "point": [0.0, -GAP - H / 2],
                       "normal": [0.0, 1.0]}],
        "contact": {"penetration_tolerance": TOLERANCE, **contact},
        "output": {"xdmf": False, "plots": False},
    }


def solve(config: dict):
    result = solve_static(validate("static", config).parsed, None, progress=False,
                          record_shapes=False)
    assert result.status == "converged", result.message
    for step in result.steps:
        for entry in step["contact"]:
            assert entry["contact_point_penetration"] <= TOLERANCE_OF(config), step
    return result


def TOLERANCE_OF(config):  # noqa: N802
    return config["contact"]["penetration_tolerance"]


@pytest.mark.mpi
def test_cantilever_below_first_touch_has_no_contact():
    result = solve(cantilever(0.9 * Q1, steps=2))
    final = result.steps[-1]
    assert final["contact"][0]["force"] == [0.0, 0.0]
    assert final["contact"][0]["active"] == []
    # the free cantilever: v_tip = -q L^4 / (8 EI) = -0.9 g
    assert final["tip"]["v"] == pytest.approx(-0.9 * GAP, rel=1e-6)


@pytest.mark.mpi
def test_cantilever_on_a_plane_tip_reaction_then_contact_interval():
    q = 20 * Q1
    result = solve(cantilever(q, steps=10))
    checked = {"tip": 0, "interval": 0}
    h_e = L / 100
    for step in result.steps:
        load = step["load_factor"] * q
        entry = step["contact"][0]
        force = entry["force"][1]
        assert abs(entry["force"][0]) <= 1e-9 * abs(force) + 1e-15
        if Q1 * 1.01 < load < 9 * Q1 * 0.99:
            reaction = 3 * load * L / 8 - 3 * EI * GAP / L**3
            assert force == pytest.approx(reaction, rel=1e-3)
            assert entry["active"] == [[L, L]]  # the tip alone
            # the reaction acts at x = L: its moment about the origin is L R
            assert entry["moment"] == pytest.approx(L * reaction, rel=1e-3)
            assert step["tip"]["v"] == pytest.approx(-GAP, abs=TOLERANCE)
            checked["tip"] += 1
        elif load > 9 * Q1 * 1.01:
            start = (72 * EI * GAP / load) ** 0.25
            assert force == pytest.approx(load * L - 2 * load * start / 3, rel=1e-3)
            (interval,) = entry["active"]
            assert interval[1] == L
            assert abs(interval[0] - start) <= 2 * h_e, (interval, start)
            checked["interval"] += 1
    assert checked["tip"] >= 3 and checked["interval"] >= 5, checked


@pytest.mark.mpi
def test_elastica_pushed_on_a_floor_keeps_the_touching_shape():
    # a thin section: the floor pushes at the tip section's corner, h/2 from the axis, whose
    # moment (h/2) sin(alpha) R the elliptic-integral reference leaves out: O(h/L) = 6e-4 of R
    # at h = L/1000 (thinner sections reach the Newton test's round-off floor, EA eps)
    thin = 1e-3
    k_touch = 2.0
    touch = elastica_tip_load(k_touch)
    floor = -touch.deflection * L - thin / 2 * math.cos(touch.rotation)
    config = {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": thin, "h": thin},
        "material": {"E": 12 * EI / thin**4, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable"},
        "mesh": {"elements": 40, "degree": 2},
        "loads": {"tip_force": [0.0, -3.0 * EI / L**2], "steps": 5},
        "obstacles": [{"shape": "plane", "point": [0.5, floor], "normal": [0.0, 1.0]}],
        "contact": {"penetration_tolerance": 1e-7},
        "output": {"xdmf": False, "plots": False},
    }
    result = solve(config)
    beyond = 0
    for step in result.steps:
        load = 3.0 * step["load_factor"]
        entry = step["contact"][0]
        if load < k_touch * 0.99:
            assert entry["force"] == [0.0, 0.0]
            continue
        beyond += 1
        assert entry["force"][1] == pytest.approx(load - k_touch, rel=1e-3)
        assert entry["active"] == [[L, L]]
        assert step["tip"]["u"] == pytest.approx(-touch.shortening * L, abs=1e-5 * L)
        assert step["tip"]["v"] == pytest.approx(-touch.deflection * L, abs=1e-5 * L)
        assert step["tip"]["theta"] == pytest.approx(-touch.rotation, abs=2e-4)
    assert beyond >= 2


def test_obstacle_far_away_is_never_touched():
    config = cantilever(20 * Q1, steps=2)
    config["obstacles"] = [{"shape": "sphere", "center": [0.5, 3.0], "radius": 0.5},
                           config["obstacles"][0]]
    result = solve(config)
    far, floor = result.steps[-1]["contact"]
    assert far["force"] == [0.0, 0.0] and far["active"] == [] and far["max_penetration"] == 0
    assert floor["force"][1] > 0


def test_a_load_step_does_not_jump_through_a_thin_obstacle():
    """A thin plate below the tip and one load step that would carry the tip far below it:
    the step is cut back (the tunnelling check) and the rod ends up resting on the plate."""
    config = cantilever(0.0, steps=1, elements=20)
    config["loads"] = {"tip_force": [0.0, -3.0 * EI * 0.1 / L**3 * 10], "steps": 1}
    config["solver"]["max_increment"] = 1.0
    config["obstacles"] = [{"shape": "box", "name": "plate", "min": [0.8, -0.021],
                            "max": [1.2, -0.02]}]
    config["contact"] = {"penetration_tolerance": 1e-7}
    result = solve(config)
    final = result.steps[-1]
    plate = final["contact"][0]
    assert plate["force"][1] > 0
    assert final["tip"]["v"] > -0.02 - H / 2 - 1e-6  # above the plate, not through it

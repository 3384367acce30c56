"""Contact in arc-length path following (`fe-beam path` with [[obstacles]]; issue 23 item 2).

(a) The elastica pushed onto a frictionless floor by a dead tip force (tests/test_contact.py's
case (b)), traced by arc length: beyond P_touch = 2 EI / L^2 the shape stays that of P_touch
(the elliptic-integral elastica) and the floor carries P - P_touch; the last path point agrees
with load stepping (`fe-beam static`) at the same load.
(b) The bistable beam of examples/snap_through.toml traced through its two limit points and
its bifurcations, then stopped by a floor below the inverted state: the critical points are
those of the path without the floor, and once the midspan rests on the floor (v = v*) the floor
carries what the point force adds beyond the force that holds the free beam at v*, F_hold:
F_floor = F_hold - F_point (the beam is held at v* by the two together), F_hold from the path
without the floor where it passes v*.
(b') A finger closing on a bottle, its tendon tension the path parameter: each point in
contact agrees with `fe-beam finger` at the same tension.
(c) A uniform load that would press a large part of a cantilever onto a plane in one step: the
step is cut back until no step changes the contact state of more than [contact]
max_active_change of the contact points (load stepping and arc length); with the limit off the
same step is taken at once.
Every point keeps its penetration below the tolerance; bad inputs exit 2.
"""

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

import fe_beam
from fe_beam.analytic import elastica_tip_load
from fe_beam.config.registry import validate
from fe_beam.errors import ConfigError

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
L, EI = 1.0, 1.0


def _penetration_below_tolerance(summary: dict, tolerance: float) -> None:
    for point in summary["path"]:
        for entry in point["contact"]:
            assert entry["contact_point_penetration"] <= tolerance, point


# --- (a) the elastica on a floor -----------------------------------------------------------------
THIN = 1e-3
K_TOUCH = 2.0


def _elastica(**path) -> dict:
    touch = elastica_tip_load(K_TOUCH)
    floor = -touch.deflection * L - THIN / 2 * math.cos(touch.rotation)
    return {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": THIN, "h": THIN},
        "material": {"E": 12 * EI / THIN**4, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable"},
        "mesh": {"elements": 40, "degree": 2},
        "loads": {"tip_force": [0.0, -3.0 * EI / L**2], "steps": 5},
        "obstacles": [{"shape": "plane", "name": "floor", "point": [0.5, floor],
                       "normal": [0.0, 1.0]}],
        "contact": {"penetration_tolerance": 1e-7},
        "path": {"arc_length": 0.1, "max_steps": 30, **path},
        "output": {"xdmf": False, "plots": False},
    }


@pytest.mark.mpi
def test_elastica_path_onto_a_floor_matches_closed_form_and_load_stepping():
    config = _elastica()
    summary = fe_beam.run("path", config)
    assert summary["status"] == "converged", summary["message"]
    _penetration_below_tolerance(summary, 1e-7)
    touch = elastica_tip_load(K_TOUCH)
    beyond = 0
    for point in summary["path"]:
        load = 3.0 * point["load_factor"]
        (entry,) = point["contact"]
        if load < K_TOUCH:
            assert entry["force"] == [0.0, 0.0] and entry["active"] == []
            continue
        beyond += 1
        # the floor carries P - P_touch (the corner's moment: O(h/L), test_contact.py)
        assert entry["force"][1] == pytest.approx(load - K_TOUCH, rel=1e-3)
        assert entry["active"] == [[L, L]]
        assert point["tip"]["u"] == pytest.approx(-touch.shortening * L, abs=1e-5 * L)
        assert point["tip"]["v"] == pytest.approx(-touch.deflection * L, abs=1e-5 * L)
        assert point["tip"]["theta"] == pytest.approx(-touch.rotation, abs=2e-4)
    assert beyond >= 2
    # load stepping at the path's last load factor: the same equilibrium
    last = summary["path"][-1]
    static = copy.deepcopy(config)
    del static["path"]
    static["loads"]["tip_force"] = [0.0, -3.0 * EI / L**2 * last["load_factor"]]
    stepped = fe_beam.run("static", static)
    assert stepped["status"] == "converged", stepped["message"]
    final = stepped["steps"][-1]
    for key in ("u", "v", "theta"):
        assert last["tip"][key] == pytest.approx(final["tip"][key], abs=1e-7)
    # the force within what the penetration tolerance leaves open: k_end tol = 6.4e-3 N here
    # (k_end = penalty EI / h_e^3 at the tip's corner), measured 3.5e-5 relative
    assert last["contact"][0]["force"][1] == pytest.approx(final["contact"][0]["force"][1],
                                                           rel=2e-4)


def test_spatial_rod_path_onto_a_plane_keeps_the_touching_force_and_matches_load_stepping():
    """A spatial cantilever (circular section: its true shape, the end face a disc) pushed by
    a dead tip force onto a plane below it: once the tip rests on the plane, the end face's
    lowest rim point is on the plane at every path point (not the centreline a radius above
    it: the tip is tilted by phi), the plane's force acts there (its reported moment about the
    origin is rim x F), and the last point agrees with `fe-beam static` at the same load. The
    touching force P - F_plane is not constant (as it would be for a force at the
    centreline): the rim point lies e = rho sin(phi) behind the tip, so the plane's force F
    adds a couple F e to the tip force, and with the tip held on the plane the linear
    cantilever needs dP_touch/dF = -3 e / (2 L) (e and phi small: 1e-3 here)."""
    from fe_beam.model.spatial import rotation_matrix

    force, rho, floor = 0.02, 0.005, -0.1
    config = {
        "beam": {"length": L},
        "section": {"shape": "circle", "d": 2 * rho},
        "material": {"E": 1e7, "nu": 0.3},
        "model": {"law": "reissner", "kinematics": "spatial"},
        "mesh": {"elements": 16, "degree": 2},
        "loads": {"tip_force": [0.0, 0.0, -force], "steps": 5},
        "obstacles": [{"shape": "plane", "point": [0.0, 0.0, floor],
                       "normal": [0.0, 0.0, 1.0]}],
        "contact": {"penetration_tolerance": 1e-7},
        "path": {"arc_length": 0.1, "max_steps": 40},
        "output": {"xdmf": False, "plots": False},
    }
    summary = fe_beam.run("path", config)
    assert summary["status"] == "converged", summary["message"]
    _penetration_below_tolerance(summary, 1e-7)
    pressed = [p for p in summary["path"] if p["contact"][0]["active"]]
    assert len(pressed) >= 3
    n = np.array([0.0, 0.0, 1.0])
    touching, plane, offsets = [], [], []
    for point in pressed:
        entry = point["contact"][0]
        assert entry["active"] == [[L, L]]
        d1 = np.array(rotation_matrix(point["tip"]["rotation_vector"]))[:, 0]
        tip = np.array([L + point["tip"]["u"], point["tip"]["v"], point["tip"]["w"]])
        toward = -n + (n @ d1) * d1  # the end face's direction of steepest descent
        rim = tip + rho * toward / np.linalg.norm(toward)
        assert rim[2] == pytest.approx(floor, abs=1e-7)
        F = np.array(entry["force"])
        assert np.asarray(entry["moment"]) == pytest.approx(np.cross(rim, F),
                                                            abs=1e-9 * np.linalg.norm(F))
        touching.append(force * point["load_factor"] - F[2])
        plane.append(F[2])
        offsets.append(tip[0] - rim[0])
    e = np.array(offsets)
    assert np.all(e > 0.5 * rho * 0.1)  # tilted: the rim point behind the tip
    slope = np.diff(touching) / np.diff(plane)
    expected = -1.5 * 0.5 * (e[1:] + e[:-1]) / L
    assert slope == pytest.approx(expected, rel=0.05)
    last = summary["path"][-1]
    static = copy.deepcopy(config)
    del static["path"]
    static["loads"]["tip_force"] = [0.0, 0.0, -force * last["load_factor"]]
    stepped = fe_beam.run("static", static)["steps"][-1]
    for key in ("u", "v", "w"):  # both within the penetration tolerance of the plane
        assert last["tip"][key] == pytest.approx(stepped["tip"][key], abs=1e-7)
    assert last["contact"][0]["force"][2] == pytest.approx(stepped["contact"][0]["force"][2],
                                                           rel=1e-5)


def test_where_contact_begins_the_tangent_is_oriented_to_press_on():
    """`ContactSet.orientation` at the elastica's first state on the floor: a tangent that
    pushes the tip on (load up) presses (+1), its reverse lifts off (-1); no opinion once the
    contact is the accepted state's (0)."""
    from fe_beam.solvers.continuation import ArcLength
    from fe_beam.solvers.newton import LoadStepping
    from fe_beam.solvers.rod_static import StaticContinuation

    config = _elastica()
    del config["path"]
    run = StaticContinuation(validate("static", config).parsed)
    run.advance(0.6, LoadStepping(steps=3))  # P = 1.8 < P_touch = 2: clear of the floor
    clear = run.contact.save()
    run.advance(0.8, LoadStepping(steps=2))
    assert run.contact.summary()[0]["force"][1] > 0
    engine = run.engine()
    engine.parameter = run.load_factor
    engine.prepare_arc_length(ArcLength(increment=0.1))
    tangent, along = engine._tangent
    assert along > 0  # the load rises along it
    assert run.contact.orientation(tangent) == 0  # the contact is the accepted state's
    run.contact._pressed = clear[2]  # as if the step had come from the clear state
    assert run.contact.orientation(tangent) == 1
    tangent.scale(-1.0)
    assert run.contact.orientation(tangent) == -1
    run.destroy()


# --- (b) through limit points onto a floor -------------------------------------------------------
V_FLOOR = -0.07  # the midspan's rest on the floor: on the inverted, stable branch


def _snap(floor: bool) -> dict:
    config = tomllib.loads((EXAMPLES / "snap_through.toml").read_text())
    config["path"].update(max_steps=80, max_load_factor=0.9)
    config["output"] = {"xdmf": False, "plots": True}
    if floor:
        h = config["section"]["h"]
        config["obstacles"] = [{"shape": "plane", "name": "floor",
                                "point": [0.0, V_FLOOR - h / 2], "normal": [0.0, 1.0]}]
    return config


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="dense stability: serial")
def test_snap_through_path_through_limit_points_is_stopped_by_a_floor(tmp_path):
    free = fe_beam.run("path", _snap(False))
    config = _snap(True)
    # the point force at midspan presses the vertex x = L/2, between the contact points, about
    # 4x the tolerance into the floor (3.9e-5 m): the surface_penetration certificate fails the
    # strict run (exit 3); lenient, the rest of the answer is checked here
    summary = fe_beam.run("path", config, out=tmp_path, **{"checks.strict": False})
    assert free["status"] == "converged" and summary["status"] == "converged", \
        summary["message"]
    surface = {c["name"]: c for c in summary["checks"]}["surface_penetration"]
    assert not surface["passed"] and surface["value"] < 5e-3 * config["section"]["h"]
    tolerance = 1e-3 * config["section"]["h"]  # the default penetration tolerance
    _penetration_below_tolerance(summary, tolerance)
    # the floor is below every state before the inverted branch: the same critical points
    found = [(c["kind"], c["load_factor"]) for c in summary["critical_points"]]
    expected = [(c["kind"], c["load_factor"]) for c in free["critical_points"]]
    assert [k for k, _ in found] == [k for k, _ in expected] == \
        ["bifurcation", "limit", "limit", "bifurcation"]
    for (_, got), (_, want) in zip(found, expected, strict=True):
        assert got == pytest.approx(want, abs=1e-6)
    # F_hold: the point force of the free path where its midspan passes v, interpolated
    # (cubic in v) between the free path's points on the inverted branch
    force0 = config["loads"]["point_forces"][0][2]  # the force at load factor 1 (along y)
    branch = [(p["point"]["v"], p["load_factor"]) for p in free["path"]
              if p["stable"] and p["point"]["v"] < -0.06]
    v, lam = np.array(branch).T
    fit = np.polyfit(v, lam, 3)
    # the reference is no better than the midspan's place: a state within the penetration
    # tolerance of the floor holds F_hold(v) within |dF_hold/dv| tolerance (the fit's slope)
    slope = np.polyval(np.polyder(fit), V_FLOOR) * force0
    place_error = abs(slope) * tolerance
    pressed = [p for p in summary["path"] if p["contact"][0]["active"]]
    assert len(pressed) >= 3
    worst = 0.0
    for point in pressed:
        entry = point["contact"][0]
        # the floor (+y) and the point force together hold the midspan where it is (the
        # free beam's force there: F_hold)
        carried = (np.polyval(fit, point["point"]["v"]) - point["load_factor"]) * force0
        worst = max(worst, abs(entry["force"][1] / carried - 1))
        # the gap is measured at the contact points (Gauss points and ends), here the two on
        # either side of the midspan node, 0.003 L away, where the point force kinks the rod:
        # the node itself dips 3.9e-5 m (0.4 % of h) below the floor's surface
        assert point["point"]["v"] == pytest.approx(V_FLOOR, abs=5e-5)
        assert abs(entry["force"][0]) <= 1e-6
        assert entry["active"] == [[pytest.approx(0.497, abs=0.01),
                                    pytest.approx(0.503, abs=0.01)]]
        assert entry["force"][1] == pytest.approx(carried, rel=5e-3, abs=place_error)
    print(f"snap-through onto a floor: {len(pressed)} points in contact, floor force vs "
          f"F_hold - F_point: {worst:.2e} relative")
    # the free beam would have gone below the floor at the last load factor
    assert free["path"][-1]["point"]["v"] < V_FLOOR - 1e-3
    assert (tmp_path / "deformed_shapes.png").is_file()
    assert (tmp_path / "obstacles.vtu").is_file()
    header = (tmp_path / "path.csv").read_text().splitlines()[0].split(",")
    assert {"contact0_Fy", "contact0_max_penetration", "contact0_pressure_peak"} <= set(header)


# --- (b') a finger closing on a bottle: parameter = tension ----------------------------------
def _finger() -> dict:
    config = tomllib.loads((EXAMPLES / "finger.toml").read_text())
    config.pop("inverse")
    config["mesh"]["elements"] = 20
    config["loads"]["steps"] = 8
    config["obstacles"] = [{"shape": "cylinder", "name": "bottle", "point": [0.09, 0.032],
                            "radius": 0.015}]
    config["contact"] = {"penetration_tolerance": 1e-7, "max_updates": 200}
    config["output"] = {"xdmf": False, "plots": False}
    return config


@pytest.mark.mpi
def test_finger_closing_on_a_bottle_along_the_tension_matches_fe_beam_finger():
    config = _finger()
    config["path"] = {"parameter": "tension", "arc_length": 0.1, "max_load_factor": 1.5}
    summary = fe_beam.run("path", config)
    assert summary["status"] == "converged", summary["message"]
    _penetration_below_tolerance(summary, 1e-7)
    pressed = [p for p in summary["path"] if p["contact"][0]["active"]]
    assert len(pressed) >= 2 and summary["path"][0]["contact"][0]["force"] == [0.0, 0.0]
    assert summary["path"][-1]["tension"] == pytest.approx(3.0, rel=1e-12)  # 1.5 x 2 N
    worst = {"tip": 0.0, "force": 0.0}
    for point in pressed:
        finger = _finger()
        finger["tendons"][0]["tension"] = point["tension"]
        swept = fe_beam.run("finger", finger)
        assert swept["status"] == "converged", swept["message"]
        step = swept["steps"][-1]
        for key in ("u", "v"):
            assert point["tip"][key] == pytest.approx(step["tip"][key], abs=1e-7)
            worst["tip"] = max(worst["tip"], abs(point["tip"][key] - step["tip"][key]))
        assert point["tip"]["theta"] == pytest.approx(step["tip"]["theta"], abs=1e-5)
        force, reference = (np.array(p["contact"][0]["force"]) for p in (point, step))
        assert np.linalg.norm(force - reference) <= 1e-4 * np.linalg.norm(reference)
        worst["force"] = max(worst["force"],
                             np.linalg.norm(force - reference) / np.linalg.norm(reference))
    print(f"finger on a bottle, path vs fe-beam finger: {worst}")


# --- (c) a step that would press much of the rod onto a plane ----------------------------------
H, GAP = 0.01, 1e-4
Q1 = 8 * EI * GAP / L**4  # the uniform load that first makes the tip touch


def _pressed(limit: float | None, q: float = 100 * Q1, **extra) -> dict:
    """tests/test_contact.py's cantilever above a plane at the gap g under q: above 9 q1 it
    lies on the plane over [a, L], a = (72 EI g / q)^(1/4) (0.55 L at q = 100 q1)."""
    contact = {"penetration_tolerance": 1e-7, "max_updates": 200}
    if limit is not None:
        contact["max_active_change"] = limit
    return {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": H, "h": H},
        "material": {"E": 12 * EI / (H * H**3), "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable"},
        "mesh": {"elements": 20, "degree": 2},
        "loads": {"distributed": [0.0, -q], "steps": 1},
        "solver": {"atol": 1e-10, "max_increment": 1.0},
        "obstacles": [{"shape": "plane", "name": "floor", "point": [0.0, -GAP - H / 2],
                       "normal": [0.0, 1.0]}],
        "contact": contact,
        "output": {"xdmf": False, "plots": False},
        **extra,
    }


def _lengths(records) -> list[float]:
    return [sum(b - a for a, b in r["contact"][0]["active"]) for r in records]


def test_a_step_that_presses_much_of_the_rod_at_once_is_cut_back():
    h_e = L / 20
    q = 100 * Q1
    length = L - (72 * EI * GAP / q) ** 0.25  # the contact interval [a, L] at q
    free = fe_beam.run("static", _pressed(1.0))  # the limit off: the whole load in one step
    assert free["status"] == "converged", free["message"]
    assert len(free["steps"]) == 1
    assert _lengths(free["steps"])[0] == pytest.approx(length, abs=h_e)  # 0.45 L at once
    limited = fe_beam.run("static", _pressed(None))  # the default limit, 0.2
    assert limited["status"] == "converged", limited["message"]
    lengths = [0.0] + _lengths(limited["steps"])
    assert len(limited["steps"]) >= 3
    for before, after in zip(lengths[:-1], lengths[1:], strict=True):
        assert abs(after - before) <= 0.2 * L + h_e, lengths
    assert lengths[-1] == pytest.approx(length, abs=h_e)
    # arc length: every path point within the limit as well (0.1 here)
    path = fe_beam.run("path", _pressed(0.1, path={"arc_length": 0.5, "max_steps": 60,
                                                    "max_arc_length": 4.0}))
    assert path["status"] == "converged", path["message"]
    _penetration_below_tolerance(path, 1e-7)
    lengths = _lengths(path["path"])
    assert lengths[-1] == pytest.approx(length, abs=h_e)
    for before, after in zip(lengths[:-1], lengths[1:], strict=True):
        assert abs(after - before) <= 0.1 * L + h_e, lengths
    print(f"max_active_change: static {len(limited['steps'])} steps, path "
          f"{len(path['path']) - 1} points, contact lengths {lengths}")


# --- bad inputs --------------------------------------------------------------------------------
@pytest.mark.parametrize(("change", "needle"), [
    (lambda c: c["obstacles"][0].update(friction=0.3), "friction"),
    (lambda c: c["path"].update(branch_switch="positive"), "branch_switch"),
    (lambda c: c["contact"].update(max_active_change=0.0), "max_active_change"),
    (lambda c: c["contact"].update(max_active_change=1.5), "max_active_change"),
    (lambda c: c["obstacles"][0].update(point=[0.5, 0.0]), "intersects"),
    (lambda c: c["obstacles"][0].update(position=["0", "-0.1 * load_factor"]), "moves"),
])
def test_bad_contact_inputs_of_the_path_are_one_sentence(change, needle):
    config = _elastica()
    change(config)
    with pytest.raises(ConfigError, match=needle):
        validate("path", config)


def test_the_solid_path_refuses_obstacles():
    config = tomllib.loads((EXAMPLES / "finger_solid.toml").read_text())
    config["path"] = {}
    config["obstacles"] = [{"shape": "plane", "point": [0.0, -1.0, 0.0],
                            "normal": [0.0, 1.0, 0.0]}]
    with pytest.raises(ConfigError, match="obstacles"):
        validate("path", config)


def test_bad_path_input_exits_2_from_the_command_line(tmp_path):
    from fe_beam.cli import main

    config = tmp_path / "bad.toml"
    config.write_text(
        '[beam]\nlength = 1.0\n[section]\nshape = "rectangle"\nb = 0.01\nh = 0.01\n'
        '[material]\nE = 1e7\nnu = 0.3\n[loads]\ntip_force = [0.0, -1.0]\n[path]\n'
        '[[obstacles]]\nshape = "plane"\npoint = [0.0, -0.5]\nnormal = [0.0, 1.0]\n'
        'friction = 0.2\n')
    assert main(["path", str(config), "--out", str(tmp_path / "out")]) == 2

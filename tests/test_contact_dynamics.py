"""Moving obstacles and contact in ``fe-beam dynamic`` (issue 23), against closed forms and
independent solutions.

Statics, an obstacle moved along the load path (``position`` in ``load_factor``):
(a) a small disc under the tip of a cantilever raised by d: the reaction 3 EI d / L^3;
(b) a plane inclined at 60 degrees moved by D = 0.4 L onto the tip's lower corner: the
elastica under a dead corner force along the plane's normal whose corner lies on the plane,
solved independently here by shooting (scipy), converging at the rate of the P2 elements.

Dynamics (generalised-alpha):
(c) a free rod sliding on a floor with mu stops after v0^2 / (2 mu g) at v0 / (mu g);
frictionless, its horizontal momentum is kept; a floor moving with velocity V drags a rod at
rest with mu g until it reaches V at V / (mu g) (the slip is relative to the obstacle);
(d) a cantilever released under gravity with damping onto a plane settles to the static
contact solution (``fe-beam static``, and the closed form R = 3 q L / 8 - 3 EI g / L^3);
(e) with rho_inf = 1 and no damping the mechanical energy does not grow through the impacts;
every accepted step keeps its penetration below the tolerance.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve
from tomlio import dump_toml

import fe_beam
from fe_beam.analyses.static import solve_static
from fe_beam.cli import main
from fe_beam.config.registry import validate

L, B, H = 1.0, 0.01, 0.01
EI = 1.0
E = 12 * EI / (B * H**3)
G = 9.81


def cantilever(obstacle: dict, elements: int = 10, steps: int = 4,
               tolerance: float = 1e-8) -> dict:
    return {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable"},
        "mesh": {"elements": elements, "degree": 2},
        "loads": {"steps": steps},
        "solver": {"atol": 1e-10},
        "obstacles": [obstacle],
        "contact": {"penetration_tolerance": tolerance},
        "output": {"xdmf": False, "plots": False},
    }


def solve(config: dict):
    result = solve_static(validate("static", config).parsed, None, progress=False,
                          record_shapes=False)
    assert result.status == "converged", result.message
    tolerance = config["contact"]["penetration_tolerance"]
    for step in result.steps:
        assert step["contact"][0]["contact_point_penetration"] <= tolerance, step
    return result


# --- statics: an obstacle moved along the load path -------------------------------------------
@pytest.mark.mpi
def test_disc_raised_under_the_tip_reaction_is_3_EI_d_over_L3():
    gap, d, radius = 1e-3, 0.01, 0.005
    disc = {"shape": "cylinder", "name": "pusher", "radius": radius,
            "point": [L, -H / 2 - gap - radius], "position": ["0", f"{gap + d}*load_factor"]}
    result = solve(cantilever(disc, elements=20, steps=4))
    final = result.steps[-1]
    entry = final["contact"][0]
    assert entry["translation"] == pytest.approx([0.0, gap + d], abs=1e-15)
    # small deflection (d = L/100): linear theory to O(d^2), the penetration 1e-8
    assert final["tip"]["v"] == pytest.approx(d, rel=2e-4)
    assert entry["force"][1] == pytest.approx(3 * EI * d / L**3, rel=1e-3)
    assert abs(entry["force"][0]) < 1e-2 * entry["force"][1]
    # the obstacle reported where it is at the last step
    assert result.obstacles[0].point == pytest.approx((L, -H / 2 - radius + d), abs=1e-12)
    # and the first step has it a quarter of the way
    assert result.steps[0]["contact"][0]["translation"][1] == pytest.approx((gap + d) / 4)


PSI = math.radians(60.0)
NORMAL = np.array([-math.sin(PSI), math.cos(PSI)])
CORNER_GAP = 1e-3
PLANE_POINT = np.array([L, -H / 2]) - CORNER_GAP * NORMAL
LIFT = 0.4


def elastica_pushed_by_a_plane(lift: float, guess) -> tuple[float, np.ndarray]:
    """(force F, tip (x, y, theta)) of the inextensible elastica clamped at 0 whose tip's lower
    corner r(L) - h/2 d rests on the plane (PLANE_POINT + (0, lift), NORMAL), pushed by the
    dead force F NORMAL there (the moment -h/2 d x F NORMAL about the centreline's end):
    EI theta'' = P_x sin theta - P_y cos theta, theta(0) = 0, EI theta'(L) = M; shooting on
    (theta'(0), F)."""
    point = PLANE_POINT + np.array([0.0, lift])

    def shoot(unknowns):
        k0, force = unknowns
        p = force * NORMAL

        def rhs(_, y):
            return [math.cos(y[2]), math.sin(y[2]), y[3],
                    (p[0] * math.sin(y[2]) - p[1] * math.cos(y[2])) / EI]

        end = solve_ivp(rhs, (0.0, L), [0.0, 0.0, 0.0, k0], rtol=1e-12, atol=1e-14).y[:, -1]
        d = np.array([-math.sin(end[2]), math.cos(end[2])])
        moment = -H / 2 * (d[0] * p[1] - d[1] * p[0])
        corner = end[:2] - H / 2 * d
        return [EI * end[3] - moment, (corner - point) @ NORMAL], end

    unknowns = fsolve(lambda u: shoot(u)[0], guess, xtol=1e-13)
    residual, end = shoot(unknowns)
    assert max(abs(r) for r in residual) < 1e-10
    return float(unknowns[1]), end[:3]


def test_plane_moved_onto_the_tip_large_deflection_against_the_elastica():
    plane = {"shape": "plane", "name": "pusher", "point": PLANE_POINT.tolist(),
             "normal": NORMAL.tolist(), "position": ["0", f"{LIFT}*load_factor"]}
    errors = []
    for elements in (5, 10):
        final = solve(cantilever(plane, elements=elements, steps=10)).steps[-1]
        entry = final["contact"][0]
        force = float(np.dot(entry["force"], NORMAL))
        assert entry["active"] == [[L, L]]  # the tip's corner only
        reference, tip = elastica_pushed_by_a_plane(LIFT, [final["tip"]["theta"], force])
        assert tip[1] > 0.3 * L  # large: the tip rises 0.3 L and turns 0.47 rad
        assert final["tip"]["v"] == pytest.approx(tip[1], abs=2e-6)
        assert final["tip"]["u"] == pytest.approx(tip[0] - L, abs=2e-6)
        assert final["tip"]["theta"] == pytest.approx(tip[2], abs=1e-5)
        errors.append(abs(force / reference - 1))
    # measured: 1.25e-5, 7.8e-7 (then 3.7e-8, 3.0e-9 with 20, 40 elements): order ~4
    assert errors[1] < 2e-6
    assert math.log2(errors[0] / errors[1]) > 3.0


# --- dynamics ------------------------------------------------------------------------------------
def free_rod(friction: float, velocity=(1.0, 0.0, 0.0), floor_motion: dict | None = None,
             t_end: float = 0.3, dt: float = 0.005, spatial: bool = False) -> dict:
    """A free rod of L = 0.2 m lying on a floor (1e-7 m below it) under gravity: its face
    h (along y) down, H / 2 below the centreline for both kinematics (the spatial contact
    is the section's true shape, not its circumscribed tube)."""
    reach = H / 2
    floor = {"shape": "plane", "name": "floor", "point": [0.0, -reach - 1e-7]
             + ([0.0] if spatial else []), "normal": [0.0, 1.0] + ([0.0] if spatial else []),
             **({"friction": friction} if friction else {}), **(floor_motion or {})}
    config = {
        "beam": {"length": 0.2},
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": 1e6, "nu": 0.3, "rho": 1000.0},
        "model": {"law": "reissner"},
        "mesh": {"elements": 8, "degree": 2},
        "supports": {"x0": "free", "xL": "free"},
        "loads": {"gravity": [0.0, -G] + ([0.0] if spatial else [])},
        "initial": {"velocity": list(velocity)},
        "time": {"t_end": t_end, "dt": dt, "rho_inf": 0.8, "output_every": 1},
        "obstacles": [floor],
        "contact": {"penetration_tolerance": 1e-6},
        "output": {"xdmf": False, "plots": False},
    }
    if spatial:
        config["model"]["kinematics"] = "spatial"
    return config


def run_dynamic(config: dict) -> dict:
    summary = fe_beam.run("dynamic", config)
    assert summary["status"] == "completed", summary["message"]
    tolerance = config["contact"]["penetration_tolerance"]
    for record in summary["history"]:  # every accepted step is an output here
        for entry in record["contact"]:
            assert entry["contact_point_penetration"] <= tolerance, record
    return summary


@pytest.mark.mpi
def test_sliding_rod_stops_after_v0_squared_over_2_mu_g():
    v0, mu = 1.0, 0.5
    summary = run_dynamic(free_rod(mu, velocity=(v0, 0.0, 0.0)))
    stop_time, stop_distance = v0 / (mu * G), v0**2 / (2 * mu * G)
    t = np.array([h["t"] for h in summary["history"]])
    u = np.array([h["tip"]["u"] for h in summary["history"]])
    expected = np.where(t < stop_time, v0 * t - mu * G * t**2 / 2, stop_distance)
    # measured: 1.0e-5 m at most (0.01 % of the distance), the stop within one step
    assert np.max(np.abs(u - expected)) < 2e-4 * stop_distance
    assert u[-1] == pytest.approx(stop_distance, rel=2e-4)
    weight = 1000.0 * B * H * 0.2 * G
    sliding = np.array([h["contact"][0]["force"] for h in summary["history"]
                        if 0.02 < h["t"] < stop_time - 0.01])
    # Coulomb: the friction is mu times the normal force at every step, against the motion;
    # the normal force carries the weight (the rod rocks after the 1e-7 m drop and settles:
    # 5 % at first, measured 1e-3 in the last ten steps of sliding and 1.5e-4 in the last five)
    assert np.all(np.abs(sliding[:, 0] / sliding[:, 1] + mu) < 1e-6)
    assert np.mean(sliding[:, 1]) == pytest.approx(weight, rel=1e-3)
    assert np.all(np.abs(sliding[-5:, 1] / weight - 1) < 1e-3)


def test_frictionless_sliding_keeps_the_horizontal_velocity():
    v0 = 1.0
    summary = run_dynamic(free_rod(0.0, velocity=(v0, 0.0, 0.0), t_end=0.1))
    mass = 1000.0 * B * H * 0.2
    for record in summary["history"]:
        assert record["momenta"]["momentum_x"] == pytest.approx(mass * v0, rel=1e-9)
        assert record["tip"]["u"] == pytest.approx(v0 * record["t"], abs=1e-9)
        assert record["contact"][0]["force"][0] == 0.0


def test_moving_floor_drags_the_rod_until_it_moves_with_it():
    speed, mu = 0.5, 0.5
    summary = run_dynamic(free_rod(mu, velocity=(0.0, 0.0, 0.0),
                                   floor_motion={"velocity": [speed, 0.0]}, t_end=0.2))
    catch = speed / (mu * G)  # the slip relative to the floor stops here
    t = np.array([h["t"] for h in summary["history"]])
    u = np.array([h["tip"]["u"] for h in summary["history"]])
    expected = np.where(t < catch, mu * G * t**2 / 2,
                        mu * G * catch**2 / 2 + speed * (t - catch))
    assert np.max(np.abs(u - expected)) < 2e-3 * speed * t[-1]
    # stuck from then on: it moves with the floor (its axial vibration, excited by the
    # catch, makes the momentum oscillate by 0.2 %)
    momentum = np.array([h["momenta"]["momentum_x"] for h in summary["history"]
                         if h["t"] > catch + 0.03])
    assert np.mean(momentum) == pytest.approx(1000.0 * B * H * 0.2 * speed, rel=1e-3)
    assert np.max(np.abs(momentum / (1000.0 * B * H * 0.2 * speed) - 1)) < 5e-3
    last = summary["history"][-1]
    assert last["contact"][0]["translation"] == pytest.approx([speed * t[-1], 0.0])


GAP = 0.01
Q = 3 * 8 * EI * GAP / L**4  # 3 q1: the tip rests on the plane (q1 < q < 9 q1)
RHO = Q / (B * H * G)


def falling_cantilever(**tables) -> dict:
    config = cantilever({"shape": "plane", "name": "floor", "point": [0.0, -GAP - H / 2],
                         "normal": [0.0, 1.0]}, elements=10, tolerance=1e-7)
    config["material"]["rho"] = RHO
    config["loads"] = {"gravity": [0.0, -G], "steps": 4}
    config["solver"] = {"atol": 1e-12}
    return config | tables


def test_damped_cantilever_settles_to_the_static_contact_solution():
    static = fe_beam.run("static", falling_cantilever())
    assert static["status"] == "converged"
    at_rest = static["steps"][-1]
    reaction = 3 * Q * L / 8 - 3 * EI * GAP / L**3
    assert at_rest["contact"][0]["force"][1] == pytest.approx(reaction, rel=1e-4)
    summary = run_dynamic(falling_cantilever(
        time={"t_end": 2.0, "dt": 0.01, "rho_inf": 0.8, "output_every": 10},
        damping={"c": 0.5}))
    last = summary["history"][-1]
    # measured at t = 2 s (7 periods, damping 0.5 of critical, the contact chattering at
    # 1e-4): the force 6e-5 from the static one, the tip 7e-8 m (the tolerance 1e-7 m)
    assert last["contact"][0]["force"][1] == pytest.approx(
        at_rest["contact"][0]["force"][1], rel=3e-4)
    assert last["tip"]["v"] == pytest.approx(at_rest["tip"]["v"], abs=2e-7)
    assert last["tip"]["theta"] == pytest.approx(at_rest["tip"]["theta"], abs=1e-5)


def test_energy_does_not_grow_through_the_impacts():
    summary = run_dynamic(falling_cantilever(
        time={"t_end": 0.4, "dt": 0.002, "rho_inf": 1.0, "output_every": 1}))
    energies = [h["energies"] for h in summary["history"]]
    # kinetic + strain - the work of gravity: 0 at the start; contact may only take energy
    mechanical = np.array([e["kinetic"] + e["strain"] - (e["external_work"] - e["contact_work"])
                           for e in energies])
    impacts = sum(1 for a, b in zip(summary["history"][:-1], summary["history"][1:],
                                    strict=True)
                  if not a["contact"][0]["active"] and b["contact"][0]["active"])
    assert impacts >= 2
    # bound: the largest contact force times the penetration tolerance (the energy a step's
    # admissible penetration could give back)
    force = max(abs(h["contact"][0]["force"][1]) for h in summary["history"])
    assert np.max(mechanical) <= force * 1e-7
    # measured: the contact at t_{n+1} takes energy (a third of the kinetic energy at the
    # first impact); before the first touch the energy is kept to 1.3e-4 of the kinetic energy
    # (the implicit midpoint rule on the geometrically nonlinear rod)
    first = next(i for i, h in enumerate(summary["history"]) if h["contact"][0]["active"])
    kinetic = max(e["kinetic"] for e in energies[:first + 1])
    assert np.max(np.abs(mechanical[:first])) < 5e-4 * kinetic
    assert mechanical[-1] < -0.1 * kinetic


def test_spatial_rod_slides_on_a_floor():
    v0 = 1.0
    summary = run_dynamic(free_rod(0.0, velocity=(v0, 0.0, 0.0, 0.0, 0.0, 0.0), t_end=0.05,
                                   spatial=True))
    mass = 1000.0 * B * H * 0.2
    weight = mass * G
    last = summary["history"][-1]
    assert last["momenta"]["momentum_x"] == pytest.approx(mass * v0, rel=1e-9)
    assert last["tip"]["u"] == pytest.approx(v0 * last["t"], abs=1e-9)
    # the rod rocks between its face's two edges (the support function's kink at n.d3 = 0:
    # -5 .. +8 % of the weight from step to step): the mean carries it (measured +0.8 %)
    forces = np.array([h["contact"][0]["force"] for h in summary["history"][1:]])
    assert np.mean(forces[:, 1]) == pytest.approx(weight, rel=2e-2)
    assert np.all(forces[:, 0] == 0.0) and np.all(forces[:, 2] == 0.0)


def test_dynamic_contact_outputs(tmp_path):
    config = free_rod(0.5, t_end=0.02)
    config["output"] = {"xdmf": True, "plots": True}
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(config))
    out = tmp_path / "out"
    assert main(["dynamic", str(path), "--out", str(out), "--quiet"]) == 0
    header = (out / "history.csv").read_text().splitlines()[0].split(",")
    for column in ("contact0_Fx", "contact0_Fy", "contact0_moment", "contact0_max_penetration",
                   "contact0_pressure_peak"):
        assert column in header
    assert (out / "obstacles.vtu").exists() and (out / "dynamics.png").exists()
    xdmf = (out / "beam.xdmf").read_text()
    assert "contact_gap_0" in xdmf


# --- configuration mistakes: exit 2, one sentence ---------------------------------------------
def dynamic_cli(tmp_path, config, capsys, command="dynamic"):
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(config))
    capsys.readouterr()
    code = main([command, str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err and err.count("\n") == 1, err
    assert not (tmp_path / "out" / "summary.json").exists()
    return err


def with_floor(config: dict, **keys) -> dict:
    config = dict(config)
    config["obstacles"] = [{**config["obstacles"][0], **keys}]
    return config


@pytest.mark.parametrize("keys, words", [
    ({"velocity": [1.0, 0.0, 0.0]}, ("velocity", "2 numbers")),
    ({"position": ["t"]}, ("position", "2 numbers or formulas in t")),
    ({"position": ["t", "oops(t)"]}, ("position", "oops")),
    ({"position": ["0", "-sqrt(0.01 - t)"]}, ("position", "t = 0.01")),
    ({"position": ["0", "load_factor"]}, ("position", "load_factor")),
    ({"velocity": [1.0, 0.0], "position": ["t", "0"]}, ("velocity or position", "not both")),
    ({"position": ["0", "0.5 - t"]}, ("intersects the undeformed rod", "t = 0")),
    ({"velocity": ["fast", 0.0]}, ("velocity",)),
])
def test_bad_motion_in_dynamics_exits_2(tmp_path, capsys, keys, words):
    err = dynamic_cli(tmp_path, with_floor(free_rod(0.0, t_end=0.02), **keys), capsys)
    assert "[[obstacles]] 'floor'" in err, err
    for word in words:
        assert word in err, err


@pytest.mark.parametrize("tables, words", [
    ({"time": {"t_end": 0.02, "dt": 0.005, "scheme": "energy-conserving"}},
     ("energy-conserving", "generalized-alpha")),
    ({"time": {"t_end": 0.02, "dt": 0.005, "scheme": "fd-rk45"}}, ("fd-rk45",)),
    ({"initial": {"from_static": True}}, ("from_static",)),
])
def test_dynamic_contact_unsupported_settings_exit_2(tmp_path, capsys, tables, words):
    config = falling_cantilever(time={"t_end": 0.02, "dt": 0.005}) | tables
    err = dynamic_cli(tmp_path, config, capsys)
    for word in words:
        assert word in err, err


@pytest.mark.parametrize("keys, words", [
    ({"velocity": [0.0, 1.0]}, ("velocity", "fe-beam dynamic only", "load_factor")),
    ({"position": ["0", "t"]}, ("position", "unknown name")),
    ({"position": ["0", "1/(load_factor - 0.5)"]}, ("position", "load_factor = 0.5")),
    ({"position": [0.0, 1.0, 0.0]}, ("position", "2 numbers")),
])
def test_bad_motion_in_statics_exits_2(tmp_path, capsys, keys, words):
    disc = {"shape": "cylinder", "name": "floor", "radius": 0.005, "point": [L, -0.0101]}
    err = dynamic_cli(tmp_path, with_floor(cantilever(disc), **keys), capsys, "static")
    for word in words:
        assert word in err, err


def test_the_3d_solid_refuses_moving_obstacles():
    from fe_beam.config.contact import parse_contact
    from fe_beam.errors import ConfigError

    wall = {"shape": "plane", "name": "wall", "point": [0.0, -0.1, 0.0],
            "normal": [0.0, 1.0, 0.0], "velocity": [0.0, 1.0, 0.0]}
    with pytest.raises(ConfigError, match=r"\[\[obstacles\]\] 'wall' velocity: moving "
                                          "obstacles are available for the rods"):
        parse_contact({"obstacles": [wall]}, None, solid=True)


def test_spatial_dynamic_contact_draws_the_obstacles(tmp_path):
    """A spatial rod's dynamics with obstacles draws its last state with the obstacles in
    three views and 3D (deformed_shapes.png), besides the tip trajectory."""
    config = free_rod(0.0, velocity=(1.0, 0.0, 0.0, 0.0, 0.0, 0.0), t_end=0.01, spatial=True)
    config["output"] = {"xdmf": False, "plots": True}
    path = tmp_path / "s.toml"
    path.write_text(dump_toml(config))
    out = tmp_path / "out"
    assert main(["dynamic", str(path), "--out", str(out), "--quiet"]) == 0
    for name in ("deformed_shapes.png", "dynamics.png", "obstacles.vtu"):
        assert (out / name).stat().st_size > 1000, name

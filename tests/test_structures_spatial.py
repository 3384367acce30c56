"""Spatial serial chains of rods joined rigidly ([[rods]] with [model] kinematics = "spatial";
issue 29, MODEL.md section 9: R = R_inc R0 per rod, a rigid joint = equal positions and equal
incremental rotations).

References: the same rod without joints (and the same rod turned in space), the planar chain's
own solution, Castigliano's unit-load method (an L-frame pushed out of its plane) and the
independent shooting solver `fe_beam.baselines.spatial_frame_shooting` across the corner."""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest
from mpi4py import MPI
from mpilaunch import mpirun_command

import fe_beam
from fe_beam.baselines.spatial_frame_shooting import SpatialFrame, solve_spatial_frame
from fe_beam.cli import main
from fe_beam.config import validate
from fe_beam.errors import ConfigError

E, NU = 2.0e7, 0.3
B, H = 0.02, 0.03


def _base(constraint: str = "none", elements: int = 8, spatial: bool = True) -> dict:
    return {
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": NU},
        "model": {"law": "reissner", "constraint": constraint}
        | ({"kinematics": "spatial"} if spatial else {}),
        "mesh": {"elements": elements, "degree": 2},
        "loads": {"steps": 4},
        "output": {"xdmf": False, "plots": False},
    }


def _torsion_constant(terms: int) -> float:
    """Saint-Venant's J of the b x h rectangle, its series summed over ``terms`` odd n (the
    package sums it to convergence: `fe_beam.model.sections.rectangle_torsion_constant`)."""
    t, w = min(B, H), max(B, H)
    series = sum(math.tanh(n * math.pi * w / (2 * t)) / n**5 for n in range(1, 2 * terms, 2))
    return t**3 * w / 3 * (1 - 192 * t / (math.pi**5 * w) * series)


def _stiffness(terms: int = 20_000):
    """(EA, GA, GJ, EI_y, EI_z): h along d2 (y), b along d3 (z); shear correction 1 (the
    [model] default)."""
    G = E / (2 * (1 + NU))
    return (E * B * H, G * B * H, G * _torsion_constant(terms), E * H * B**3 / 12,
            E * B * H**3 / 12)


def _frame(direction, normal=None):
    d1 = np.array(direction, float)
    d2 = np.array(normal, float) if normal is not None else np.cross([0, 0, 1.0], d1)
    d2 = d2 / np.linalg.norm(d2)
    return np.column_stack([d1, d2, np.cross(d1, d2)])


# --- a straight rod split into two rods is the rod ----------------------------------------------
@pytest.mark.parametrize("turned", [False, True])
def test_split_spatial_rod_is_the_rod(turned):
    """A clamped rod under a tip force with three components and a tip moment; split in two
    rods joined rigidly, along x (``turned`` False) or along a skew direction with a skew
    normal (the loads turned with it: the solution is the rod's turned by R0)."""
    length, elements = 1.0, 8
    EA, GA, GJ, EIy, EIz = _stiffness()
    force = np.array([0.2, -1.0, 0.6]) * EIz / length**2
    moment = np.array([0.3, 0.2, -0.4]) * EIz / length
    single = _base(elements=elements)
    single["beam"] = {"length": length}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    single["loads"] |= {"tip_force": force.tolist(), "tip_moment": moment.tolist()}
    Q = (_frame(np.array([1.0, 2.0, 2.0]) / 3, np.array([2.0, 1.0, -2.0]) / 3) if turned
         else np.eye(3))
    start = np.array([0.3, -0.2, 0.5]) if turned else np.zeros(3)
    split = _base(elements=elements // 2)
    rods = []
    for k, name in enumerate("ab"):
        rod = {"name": name, "start": (start + k * length / 2 * Q[:, 0]).tolist(),
               "direction": Q[:, 0].tolist(), "length": length / 2}
        if turned:
            rod["normal"] = Q[:, 1].tolist()
        rods.append(rod)
    rods[0]["supports"] = {"x0": "clamped"}
    rods[1]["loads"] = {"point_forces": [[length / 2, *(Q @ force)]],
                        "point_moments": [[length / 2, *(Q @ moment)]]}
    split["rods"] = rods
    split["joints"] = [{"name": "j", "at": ["a:end", "b:start"]}]
    one = fe_beam.run("static", single)
    two = fe_beam.run("static", split)
    assert one["status"] == two["status"] == "converged"
    tip1, tip2 = one["steps"][-1]["tip"], two["steps"][-1]["tip"]
    d1 = np.array([tip1[k] for k in "uvw"])
    d2 = np.array([tip2[k] for k in "uvw"])
    assert np.linalg.norm(d1) > 0.1 * length  # a large deflection
    tolerance = 1e-12 if not turned else 1e-10
    assert np.linalg.norm(Q @ d1 - d2) <= tolerance * length, (d1, d2)
    R1, R2 = np.array(tip1["R"]), np.array(tip2["R"])
    assert np.abs(Q @ R1 - R2).max() <= tolerance
    rod_b = two["steps"][-1]["rods"]["b"]
    assert np.allclose(rod_b["tip"], start + Q @ (np.array([length, 0, 0]) + d1),
                       atol=tolerance * length, rtol=0)
    assert np.abs(np.array(rod_b["tip_frame"]) - Q @ R1).max() <= tolerance
    # the joint carries the rest: the tip wrench about the deformed joint (a free body)
    # (forces exactly; moments to the rotation-vector interpolation's defect, which is not
    # objective: measured 1.1e-7 relative with 4 elements on the part beyond the joint)
    joint = two["steps"][-1]["joints"]["j"]
    corner = np.array(two["steps"][-1]["rods"]["a"]["tip"])
    tip = np.array(rod_b["tip"])
    assert np.allclose(joint["force"], Q @ force, atol=1e-10 * np.linalg.norm(force), rtol=0)
    expected = Q @ moment + np.cross(tip - corner, Q @ force)
    defect = np.linalg.norm(np.array(joint["moment"]) - expected) / np.linalg.norm(expected)
    assert defect <= 1e-6, defect


# --- the planar chain is the spatial chain in its plane -----------------------------------------
def _planar_l_frame(a, b, force, elements, spatial):
    config = _base(elements=elements, spatial=spatial)
    z = [0.0] if spatial else []
    config["rods"] = [
        {"name": "column", "start": [0.0, 0.0, *z], "direction": [0.0, 1.0, *z],
         "length": a, "supports": {"x0": "clamped"}},
        {"name": "beam", "start": [b, a, *z], "direction": [-1.0, 0.0, *z], "length": b,
         "loads": {"point_forces": [[0.0, *force, *z]],
                   "point_moments": [[0.5 * b, 0.4 * force[1] * b, *([0.0, 0.0] if spatial
                                                                      else [])]]}}]
    if spatial:  # the planar moment about z
        config["rods"][1]["loads"]["point_moments"] = [[0.5 * b, 0.0, 0.0,
                                                        0.4 * force[1] * b]]
    config["joints"] = [{"name": "corner", "at": ["beam:end", "column:end"]}]
    return config


def test_planar_l_frame_with_spatial_kinematics_is_the_planar_chain():
    """A clamped L-frame in the xy plane (the beam given reversed, a mid-span moment): the
    spatial chain gives the planar chain's rod ends and joint force and moment."""
    a, b = 0.9, 0.6
    _, _, _, _, EIz = _stiffness()
    force = [0.6 * EIz / a**2, -2.0 * EIz / a**2]
    planar = fe_beam.run("static", _planar_l_frame(a, b, force, 6, False))
    spatial = fe_beam.run("static", _planar_l_frame(a, b, force, 6, True))
    assert planar["status"] == spatial["status"] == "converged"
    p, s = planar["steps"][-1], spatial["steps"][-1]
    assert math.hypot(p["tip"]["u"], p["tip"]["v"]) > 0.2 * b  # large
    for name in ("column", "beam"):
        assert s["rods"][name]["tip"][:2] == pytest.approx(p["rods"][name]["tip"], abs=1e-8)
        assert abs(s["rods"][name]["tip"][2]) <= 1e-12
        angle = p["rods"][name]["tip_angle"]
        frame = np.array(s["rods"][name]["tip_frame"])
        assert frame[:2, 0] == pytest.approx([math.cos(angle), math.sin(angle)], abs=1e-8)
    jp, js = p["joints"]["corner"], s["joints"]["corner"]
    scale = math.hypot(*force)
    assert js["force"][:2] == pytest.approx(jp["force"], abs=1e-8 * scale)
    assert js["moment"][2] == pytest.approx(jp["moment"], abs=1e-8 * scale * a)
    assert abs(js["force"][2]) + abs(js["moment"][0]) + abs(js["moment"][1]) <= 1e-12 * scale


# --- the L-frame pushed out of its plane ------------------------------------------------------
def _out_of_plane(length, P, elements, constraint="inextensible-unshearable"):
    config = _base(constraint, elements)
    config["rods"] = [
        {"name": "a", "start": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0],
         "length": length, "supports": {"x0": "clamped"}},
        {"name": "b", "start": [length, 0.0, 0.0], "direction": [0.0, 1.0, 0.0],
         "length": length, "loads": {"point_forces": [[length, *P]]}}]
    config["joints"] = [{"name": "corner", "at": ["a:end", "b:start"]}]
    config["loads"]["steps"] = 1
    return config


def test_l_frame_out_of_plane_is_castigliano():
    """Two members of length L at a right angle, clamped, a force P along z at the free end:
    w = P L^3 (2 / (3 EI) + 1 / (GJ)) (unshearable, inextensible; EI the out-of-plane
    bending stiffness, E I_y on both members since d3 = z). The discrete solution is exact for
    this linear moment field at 1, 2 and 4 elements per member (no order to observe): the
    error is the small load's nonlinear terms. GJ: J's series summed to convergence (the
    package summed 12 terms until issue 28: 2.7e-7 relative, 1.7e-7 of w here)."""
    length = 0.5
    _, _, GJ, EIy, _ = _stiffness()
    P = 1e-7 * EIy / length**2
    w = P * length**3 * (2 / (3 * EIy) + 1 / GJ)
    exact = P * length**3 * (2 / (3 * EIy) + 1 / _stiffness(1000)[2])
    errors = []
    for elements in (1, 2, 4):
        summary = fe_beam.run("static", _out_of_plane(length, [0.0, 0.0, P], elements))
        assert summary["status"] == "converged"
        errors.append(abs(summary["steps"][-1]["tip"]["w"] - w) / w)
    assert max(errors) <= 1e-9, errors
    assert abs(summary["steps"][-1]["tip"]["w"] - exact) <= 3e-7 * exact
    # the reaction at the corner: the force P and the moment P L about -x (on a's end)
    joint = summary["steps"][-1]["joints"]["corner"]
    roundoff = 10 * np.finfo(float).eps * _stiffness()[0]  # 10 eps EA: the residual's
    assert joint["force"] == pytest.approx([0.0, 0.0, P], abs=max(1e-9 * P, roundoff))
    assert joint["moment"] == pytest.approx([P * length, 0.0, 0.0], abs=1e-6 * P * length)


def test_l_frame_large_out_of_plane_load_against_shooting():
    """A large out-of-plane force (with an in-plane part) and a tip moment on a clamped
    L-frame (Reissner law, extensible and shearable), against the independent shooting
    solver across the rigid corner; the error decreases as h^4."""
    length = 0.5
    EA, GA, GJ, EIy, EIz = _stiffness()
    force = np.array([0.3, -0.5, 2.0]) * EIy / length**2
    moment = np.array([0.2, 0.3, 0.1]) * EIy / length
    reference = solve_spatial_frame(SpatialFrame(
        (_frame([1.0, 0, 0]), _frame([0, 1.0, 0])), (length, length), (EA, GA, GJ, EIy, EIz),
        force=tuple(force), moment=tuple(moment)))
    r_end, R_end = reference[-1][0], reference[-1][1]
    assert abs(r_end[2]) > 0.3 * length  # large
    errors = []
    for elements in (4, 8, 16):
        config = _out_of_plane(length, force.tolist(), elements, "none")
        config["rods"][1]["loads"]["point_moments"] = [[length, *moment]]
        config["loads"]["steps"] = 6
        summary = fe_beam.run("static", config)
        assert summary["status"] == "converged"
        step = summary["steps"][-1]
        errors.append(np.linalg.norm(np.array(step["rods"]["b"]["tip"]) - r_end) / length)
        assert np.abs(np.array(step["rods"]["b"]["tip_frame"]) - R_end).max() <= 40 * errors[-1]
    # measured: 1.8e-5, 1.2e-6, 7.4e-8 of L with 4, 8, 16 elements per member (order 4.0)
    assert errors[-1] <= 1e-7, errors
    assert errors[0] / errors[1] > 10 and errors[1] / errors[2] > 10, errors
    corner = reference[0]
    joint = step["joints"]["corner"]
    # measured with 16 elements per member: force 1.7e-12, moment 3.8e-8 (relative)
    assert np.linalg.norm(np.array(joint["force"]) - corner[2]) <= 1e-10 * np.linalg.norm(force)
    assert np.linalg.norm(np.array(joint["moment"]) - corner[3]) <= 2e-7 * np.linalg.norm(
        corner[3])


# --- mistakes -----------------------------------------------------------------------------------
def _valid() -> dict:
    return _out_of_plane(1.0, [0.0, 0.0, 1.0], 2)


MISTAKES = [
    (lambda c: c["rods"][0].update(normal=[0.0, 0.0, 2.0]), "normal must be a unit vector"),
    (lambda c: c["rods"][0].update(normal=[0.6, 0.8, 0.0]), "orthogonal to direction"),
    (lambda c: c["rods"][0].update(normal=[0.0, 1.0]), "normal must be three numbers"),
    (lambda c: c["rods"][0].update(start=[0.0, 0.0]), "start must be [x, y, z]"),
    (lambda c: c["rods"][1]["loads"].update(point_forces=[[1.0, 0.0, 1.0]]),
     "[x, Px, Py, Pz]"),
    (lambda c: c["rods"][1].update(supports={"xL": "roller"}), "\"roller\" is planar"),
    (lambda c: (c["rods"][1].update(direction=[0.0, 0.6, 0.8], start=[1.0, 0.0, 0.0]),
                c["rods"][1].update(supports={"xL": "pinned"}),
                c["rods"][0].update(supports={"x0": "pinned"})),
     "not a coordinate axis"),
    (lambda c: c["rods"][0].update(supports={"x0": "pinned"}), "free to move as a rigid body"),
    (lambda c: c["model"].update(law="hyperelastic"), "hyperelastic"),
    # an end holding no component reads "free" (not "()"), a partial one as its list
    (lambda c: c["rods"][0].update(supports={"x0": []}), "(free at its start, free at its end)"),
    (lambda c: c["rods"][0].update(supports={"x0": ["u", "v", "w"]}),
     "([\"u\", \"v\", \"w\"] at its start, free at its end)"),
]


@pytest.mark.parametrize("change, words", MISTAKES)
def test_spatial_structure_mistakes_are_one_sentence(change, words):
    config = copy.deepcopy(_valid())
    change(config)
    with pytest.raises(ConfigError) as error:
        validate("static", config)
    assert words in str(error.value), str(error.value)


def test_planar_structure_refuses_normal():
    config = _planar_l_frame(1.0, 1.0, [0.0, -1.0], 2, False)
    config["rods"][0]["normal"] = [0.0, 0.0, 1.0]
    with pytest.raises(ConfigError, match="normal is the spatial section's d2"):
        validate("static", config)


def _toml_value(value) -> str:
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    return repr(float(value)) if isinstance(value, float) else str(value)


def _toml(config: dict) -> str:
    """Tables and arrays of tables of ``config`` as TOML (values inline)."""
    lines = []
    for name, value in config.items():
        entries = value if isinstance(value, list) else [value]
        for entry in entries:
            lines.append(f"[[{name}]]" if isinstance(value, list) else f"[{name}]")
            lines += [f"{k} = {_toml_value(v)}" for k, v in entry.items()]
    return "\n".join(lines) + "\n"


def test_cli_writes_spatial_chain_outputs(tmp_path):
    """The CLI: exit 0, the per-rod and per-joint CSV columns, the XDMF with the rod tag."""
    config = _out_of_plane(0.5, [0.0, 0.0, 0.1], 2)
    config["output"] = {"xdmf": True, "plots": False}
    path = tmp_path / "frame.toml"
    path.write_text(_toml(config))
    assert main(["static", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    header = (tmp_path / "out" / "load_displacement.csv").read_text().splitlines()[0]
    for column in ("rod_b_z", "joint_corner_Fz", "joint_corner_Mx"):
        assert column in header.split(",")
    assert "rod" in (tmp_path / "out" / "beam.xdmf").read_text()
    config["rods"][0]["normal"] = [1.0, 0.0, 0.0]
    path.write_text(_toml(config))
    assert main(["static", str(path), "--out", str(tmp_path / "bad"), "--quiet"]) == 2


# --- Lee's frame in space ---------------------------------------------------------------------
def _lee(spatial: bool, held_out_of_plane: bool = True) -> dict:
    """examples/lee_frame.toml, planar or with spatial kinematics (3-vectors; the pins hold
    the out-of-plane motions w, theta_x, theta_y, or with ``held_out_of_plane`` False only
    the position and the member's twist: "pinned"). Held out of plane, the section is 10
    times wider (b along z: the out-of-plane stiffnesses E I_y and G J 100 and 14 times E I_z)
    and the load 10 times larger (the same P L^2 / E I_z)."""
    import tomllib

    with open("examples/lee_frame.toml", "rb") as handle:
        config = tomllib.load(handle)
    config["mesh"]["elements"] = 4
    config["path"]["max_steps"] = 14
    config["output"] = {"xdmf": False, "plots": False}
    if held_out_of_plane:
        config["section"]["b"] *= 10
        for rod in config["rods"]:
            if "loads" in rod:
                rod["loads"]["point_forces"] = [[x, 10 * px, 10 * py] for x, px, py in
                                                rod["loads"]["point_forces"]]
    if not spatial:
        return config
    config["model"]["kinematics"] = "spatial"
    pin = (["u", "v", "w", "theta_x", "theta_y"] if held_out_of_plane else "pinned")
    for rod in config["rods"]:
        rod["start"] = rod["start"] + [0.0]
        rod["direction"] = rod["direction"] + [0.0]
        rod["supports"] = {end: pin for end in rod["supports"]}
        if "loads" in rod:
            rod["loads"]["point_forces"] = [row + [0.0] for row in
                                            rod["loads"]["point_forces"]]
    return config


def test_lee_frame_path_in_space_is_the_planar_path(tmp_path):
    """fe-beam path on Lee's frame with spatial kinematics, the pins holding the out-of-plane
    motions and the section wide out of plane: the planar frame's limit point and its path
    points' rods and corner force, to 1e-8. (The square section of examples/lee_frame.toml
    buckles out of its plane first: near 9.3 EI/L^2 with the pins holding w, theta_x, theta_y
    (the column sways against the beam's out-of-plane bending and torsion), near 1.3 EI/L^2
    with "pinned" alone, which holds each member's twist only: the frame turns about the line
    of its pins against the column's torsion. The path reports these bifurcations.)"""
    planar = fe_beam.run("path", _lee(False), tmp_path / "planar")
    spatial = fe_beam.run("path", _lee(True), tmp_path / "spatial")
    limits = [[c["load_factor"] for c in s["critical_points"] if c["kind"] == "limit"]
              for s in (planar, spatial)]
    assert limits[0] and limits[1], (planar["critical_points"], spatial["critical_points"])
    assert limits[1][0] == pytest.approx(limits[0][0], rel=1e-8)
    assert not [c for c in spatial["critical_points"] if c["kind"] == "bifurcation"]
    for p, s in zip(planar["path"], spatial["path"], strict=False):
        assert s["load_factor"] == pytest.approx(p["load_factor"], abs=1e-8)
        for name in ("column", "beam"):
            assert s["rods"][name]["tip"][:2] == pytest.approx(p["rods"][name]["tip"],
                                                               abs=1e-8)
        assert s["joints"]["corner"]["force"][:2] == pytest.approx(
            p["joints"]["corner"]["force"], abs=1e-10)
        assert s["joints"]["corner"]["moment"][2] == pytest.approx(
            p["joints"]["corner"]["moment"], abs=1e-10)
    fork = fe_beam.run("path", _lee(True, held_out_of_plane=False), tmp_path / "fork")
    first = [c for c in fork["critical_points"] if c["kind"] == "bifurcation"]
    assert first and first[0]["load_factor"] < 3.0, fork["critical_points"]


def test_fixed_body_clamps_a_spatial_chain():
    """A fixed body joined to the chain's start is the clamped support; its force and moment
    on the rod balance the end wrench about the base."""
    length = 0.5
    EIz = _stiffness()[4]
    force = np.array([0.3, -0.5, 1.0]) * EIz / length**2
    supported = _out_of_plane(length, force.tolist(), 4, "none")
    held = copy.deepcopy(supported)
    del held["rods"][0]["supports"]
    held["bodies"] = [{"name": "ground", "position": [0.0, 0.0, 0.0], "fixed": True}]
    held["joints"].append({"name": "base", "at": ["body:ground", "a:start"]})
    one = fe_beam.run("static", supported)["steps"][-1]
    two = fe_beam.run("static", held)["steps"][-1]
    assert two["rods"]["b"]["tip"] == pytest.approx(one["rods"]["b"]["tip"], abs=1e-14)
    base = two["joints"]["base"]  # on the body (named first), from the rod
    tip = np.array(two["rods"]["b"]["tip"])
    assert np.allclose(base["force"], force, rtol=1e-9, atol=0)
    # the moment to the rotation-vector interpolation's defect (measured 7e-7 relative)
    defect = np.linalg.norm(np.array(base["moment"]) - np.cross(tip, force))
    assert defect <= 1e-5 * np.linalg.norm(np.cross(tip, force)), defect


@pytest.mark.mpi
@pytest.mark.skipif(mpirun_command(2) is None or MPI.COMM_WORLD.size > 1,
                    reason="needs mpirun and a serial parent")
def test_two_ranks_give_the_serial_spatial_chain(tmp_path):
    """``mpirun -n 2 fe-beam static`` of a spatial L-frame: the same rods and joints."""
    from test_mpi_errors import fe_beam as fe_beam_job

    length = 0.5
    EIy = _stiffness()[3]
    config = _out_of_plane(length, [0.2 * EIy, -0.3 * EIy, 1.5 * EIy], 4, "none")
    alone = fe_beam.run("static", config)["steps"][-1]
    process, _ = fe_beam_job(tmp_path, config, "--out", str(tmp_path / "two"))
    assert process.returncode == 0, process.stderr
    together = json.loads((tmp_path / "two" / "summary.json").read_text())["steps"][-1]
    for name in ("a", "b"):
        assert together["rods"][name]["tip"] == pytest.approx(alone["rods"][name]["tip"],
                                                              abs=1e-11)
    for key in ("force", "moment"):
        assert together["joints"]["corner"][key] == pytest.approx(
            alone["joints"]["corner"][key], rel=1e-9, abs=1e-12)


def test_xdmf_moves_the_line_onto_the_spatial_chain(tmp_path):
    """beam.xdmf: the mesh's points (s, 0, 0) plus `displacement` are the deformed chain (each
    rod's end where `rods` has it), `d1`..`d3` the world directors (R_inc R0), `rod` the
    cell's rod."""
    import h5py

    length = 0.5
    EIy = _stiffness()[3]
    config = _out_of_plane(length, [0.2 * EIy, -0.3 * EIy, 1.5 * EIy], 3, "none")
    config["output"] = {"xdmf": True, "plots": False}
    summary = fe_beam.run("static", config, tmp_path / "out")
    with h5py.File(tmp_path / "out" / "beam.h5", "r") as h5:
        points = np.asarray(h5["Mesh"]["mesh"]["geometry"])[:, 0]

        def last(name):
            return np.asarray(h5["Function"][name][str(max(int(k) for k in
                                                           h5["Function"][name]))])

        displacement, rod = last("displacement"), last("rod").ravel()
        directors = [last(f"d{i}") for i in (1, 2, 3)]
    placed = points[:, None] * np.array([1.0, 0.0, 0.0]) + displacement[:, :3]
    rods = summary["steps"][-1]["rods"]
    for name, s in (("a", length), ("b", 2 * length)):
        at = int(np.argmin(np.abs(points - s)))
        assert placed[at] == pytest.approx(rods[name]["tip"], abs=1e-12)
    at = int(np.argmin(np.abs(points - 2 * length)))
    frame = np.array(rods["b"]["tip_frame"])
    for i in range(3):
        assert directors[i][at, :3] == pytest.approx(frame[:, i], abs=1e-12)
    assert sorted(set(rod.tolist())) == [0.0, 1.0] and np.count_nonzero(rod == 1.0) == 3

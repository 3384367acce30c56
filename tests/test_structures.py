"""Planar serial chains of rods joined rigidly ([[rods]], [[joints]], [[bodies]]; issue 29).

References: the same rod without joints (a split rod is the rod), Castigliano's unit-load
method with bending, axial and shear energy (an L-frame under a small tip force), and the
independent shooting solver `fe_beam.baselines.frame_shooting` (large loads; Lee's frame's
limit point)."""

from __future__ import annotations

import copy
import dataclasses
import json
import math

import numpy as np
import pytest
from mpi4py import MPI
from mpilaunch import mpirun_command

import fe_beam
from fe_beam.baselines import frame_shooting
from fe_beam.cli import main
from fe_beam.config import validate
from fe_beam.errors import ConfigError

E, NU = 2.0e7, 0.3
B, H = 0.02, 0.05


def _base(law: str = "reissner", constraint: str = "none", elements: int = 8) -> dict:
    return {
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": NU},
        "model": {"law": law, "constraint": constraint},
        "mesh": {"elements": elements, "degree": 2},
        "loads": {"steps": 4},
        "output": {"xdmf": False, "plots": False},
    }


def _stiffness():
    area, inertia = B * H, B * H**3 / 12
    G = E / (2 * (1 + NU))
    return E * inertia, E * area, G * area


def _l_frame(a: float, b: float, force, elements: int = 8, reversed_beam: bool = False,
             law: str = "reissner") -> dict:
    """A column (0, 0) -> (0, a), clamped at its start, and a beam (0, a) -> (b, a) joined
    rigidly at the corner, a point force at the beam's free end."""
    config = _base(law, elements=elements)
    beam = ({"name": "beam", "start": [b, a], "direction": [-1.0, 0.0], "length": b,
             "loads": {"point_forces": [[0.0, *force]]}}
            if reversed_beam else
            {"name": "beam", "start": [0.0, a], "direction": [1.0, 0.0], "length": b,
             "loads": {"point_forces": [[b, *force]]}})
    config["rods"] = [{"name": "column", "start": [0.0, 0.0], "direction": [0.0, 1.0],
                       "length": a, "supports": {"x0": "clamped"}}, beam]
    config["joints"] = [{"name": "corner", "kind": "rigid",
                         "at": ["column:end", "beam:end" if reversed_beam else "beam:start"]}]
    return config


# --- a straight rod split into two rods is the rod ----------------------------------------------
@pytest.mark.parametrize("loads", [
    {"tip_force": [0.3, -2.0]},
    {"distributed": [0.5, -3.0]},
])
def test_split_rod_is_the_rod(loads):
    length, elements = 1.0, 10
    single = _base(elements=elements)
    single["beam"] = {"length": length}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    single["loads"] |= loads
    split = _base(elements=elements // 2)
    split["rods"] = [
        {"name": "a", "start": [0.0, 0.0], "direction": [1.0, 0.0], "length": length / 2,
         "supports": {"x0": "clamped"}},
        {"name": "b", "start": [length / 2, 0.0], "direction": [1.0, 0.0],
         "length": length / 2}]
    split["joints"] = [{"name": "j", "at": ["a:end", "b:start"]}]
    if "tip_force" in loads:
        split["rods"][1]["loads"] = {"point_forces": [[length / 2, *loads["tip_force"]]]}
    else:
        split["loads"] |= loads
    one = fe_beam.run("static", single)
    two = fe_beam.run("static", split)
    assert one["status"] == two["status"] == "converged"
    tip1, tip2 = one["steps"][-1]["tip"], two["steps"][-1]["tip"]
    scale = max(abs(tip1["u"]), abs(tip1["v"]), abs(tip1["theta"]))
    assert scale > 1e-2  # a large deflection
    for key in ("u", "v", "theta"):
        assert abs(tip1[key] - tip2[key]) <= 1e-12 * scale, (key, tip1[key], tip2[key])
    rods = two["steps"][-1]["rods"]
    assert rods["b"]["tip"] == pytest.approx([length + tip1["u"], tip1["v"]], abs=1e-12)
    assert rods["b"]["tip_angle"] == pytest.approx(tip1["theta"], abs=1e-12)


# --- the L-frame ------------------------------------------------------------------------------
def test_l_frame_small_load_is_castigliano():
    """Tip displacement of a clamped L-frame under a small downward tip force P, by the
    unit-load method with the Reissner law's bending, axial and shear energies:
    v = -P (b^3 / (3 EI) + b / GA + a b^2 / EI + a / EA), u = P a^2 b / (2 EI)."""
    a, b = 0.8, 0.6  # stubby members: shear and axial terms are ~1e-3 of the bending ones
    EI, EA, GA = _stiffness()
    P = 1e-8 * EI / b**2  # the nonlinear terms: 7e-9, 1.3e-8 relative (measured)
    summary = fe_beam.run("static", _l_frame(a, b, [0.0, -P], elements=8))
    assert summary["status"] == "converged"
    tip = summary["steps"][-1]["tip"]
    v = -P * (b**3 / (3 * EI) + b / GA + a * b**2 / EI + a / EA)
    u = P * a**2 * b / (2 * EI)
    shear_and_axial = P * (b / GA + a / EA)
    assert abs(tip["v"] - v) <= 1e-7 * abs(v)
    assert abs(tip["v"] - v) < 1e-4 * shear_and_axial  # the shear and axial terms are resolved
    assert abs(tip["u"] - u) <= 1e-7 * abs(u)


def test_l_frame_large_load_against_shooting_and_joint_equilibrium():
    """A large tip force on a clamped L-frame (Reissner law, extensible and shearable) against
    the independent shooting solver across the rigid corner; the corner's reported force and
    moment balance the beam as a free body."""
    a, b = 1.0, 0.7
    EI, EA, GA = _stiffness()
    force = [0.8 * EI / a**2, -2.5 * EI / a**2]
    summary = fe_beam.run("static", _l_frame(a, b, force, elements=24))
    assert summary["status"] == "converged"
    step = summary["steps"][-1]
    frame = frame_shooting.Frame((a, b), (math.pi / 2, 0.0), EI, EA, GA, (0.0, 0.0),
                                 "clamped", "free", ((a + b, *force),))
    reference = frame_shooting.solve_frame(frame, 1.0).end()
    tip = step["rods"]["beam"]["tip"]
    size = math.hypot(reference[0] - b, reference[1] - a)
    assert size > 0.3 * b  # large
    # measured: 1.3e-5, 7.8e-7, 4.9e-8 with 6, 12, 24 elements per rod (order 4)
    assert math.hypot(tip[0] - reference[0], tip[1] - reference[1]) <= 1e-7 * b
    assert step["rods"]["beam"]["tip_angle"] == pytest.approx(reference[2], abs=2e-8)
    assert step["tip"]["theta"] == pytest.approx(reference[2], abs=2e-8)  # theta0 = 0 there
    # the corner: the beam pushes the column's end with the tip force and its moment
    corner = step["rods"]["column"]["tip"]
    joint = step["joints"]["corner"]
    assert joint["force"] == pytest.approx(force, rel=1e-9, abs=1e-9 * EI)
    moment = (tip[0] - corner[0]) * force[1] - (tip[1] - corner[1]) * force[0]
    assert joint["moment"] == pytest.approx(moment, rel=1e-9)
    # the column's end angle: the beam's start angle minus the right angle of the corner
    column_end = frame_shooting.solve_frame(frame, 1.0).state(a)
    assert step["rods"]["column"]["tip_angle"] == pytest.approx(column_end[2], abs=2e-8)


def test_reversed_rod_is_the_same_frame():
    """The beam given from its free end to the corner (joined "column:end" to "beam:end", its
    point force at x = 0 of its own arc length) is the same frame."""
    a, b = 1.0, 0.5
    EI, _, _ = _stiffness()
    force = [0.4 * EI, -1.2 * EI]
    forward = fe_beam.run("static", _l_frame(a, b, force))["steps"][-1]
    backward = fe_beam.run("static", _l_frame(a, b, force, reversed_beam=True))["steps"][-1]
    # the beam's own end is now the corner
    assert backward["rods"]["beam"]["tip"] == pytest.approx(
        forward["rods"]["column"]["tip"], abs=1e-11)
    assert backward["rods"]["column"]["tip"] == pytest.approx(
        forward["rods"]["column"]["tip"], abs=1e-11)
    assert backward["tip"]["u"] == pytest.approx(forward["rods"]["beam"]["tip"][0] - b,
                                                 abs=1e-11)
    assert backward["tip"]["v"] == pytest.approx(forward["rods"]["beam"]["tip"][1] - a,
                                                 abs=1e-11)
    # the joint's force is on the first end it names (the column's end) either way
    assert backward["joints"]["corner"]["force"] == pytest.approx(
        forward["joints"]["corner"]["force"], rel=1e-9)


def test_fixed_body_clamps_the_chain_end():
    """A fixed body joined rigidly to the column's start is the clamped support."""
    a, b = 1.0, 0.5
    EI, _, _ = _stiffness()
    force = [0.2 * EI, -0.7 * EI]
    supported = _l_frame(a, b, force)
    held = copy.deepcopy(supported)
    del held["rods"][0]["supports"]
    held["bodies"] = [{"name": "ground", "position": [0.0, 0.0], "fixed": True}]
    held["joints"].append({"name": "base", "kind": "rigid",
                           "at": ["column:start", "body:ground"]})
    one = fe_beam.run("static", supported)["steps"][-1]
    two = fe_beam.run("static", held)["steps"][-1]
    assert two["rods"]["beam"]["tip"] == pytest.approx(one["rods"]["beam"]["tip"], abs=1e-14)
    # the ground holds the whole frame: its force and moment on the column's start balance
    # the tip force about the base
    tip = two["rods"]["beam"]["tip"]
    base = two["joints"]["base"]
    assert base["force"] == pytest.approx([-force[0], -force[1]], rel=1e-9)
    assert base["moment"] == pytest.approx(-(tip[0] * force[1] - tip[1] * force[0]), rel=1e-9)
    # the body named first: the force and moment on the body (the reaction's opposite)
    held["joints"][-1]["at"] = ["body:ground", "column:start"]
    flipped = fe_beam.run("static", held)["steps"][-1]["joints"]["base"]
    assert flipped["force"] == pytest.approx(force, rel=1e-9)
    assert flipped["moment"] == pytest.approx(-base["moment"], rel=1e-9)


# --- Lee's frame ------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def lee_limit():
    return frame_shooting.limit_load(frame_shooting.lee_frame(), 1.2, step=0.05, rtol=1e-10)


def test_lee_frame_limit_point(tmp_path, lee_limit):
    """fe-beam path on examples/lee_frame.toml (the elastica: inextensible, unshearable) finds
    the limit point of Lee's frame at about 18.5 EI / L^2 (literature 18.48-18.55), within
    1e-4 of the shooting solver's limit (18.558747; measured 18.560122, 18.558874, 18.558752
    with 8, 16, 32 elements per member: order about 4)."""
    summary = fe_beam.run("path", "examples/lee_frame.toml", tmp_path / "out",
                          **{"mesh.elements": 16})
    limits = [c for c in summary["critical_points"] if c["kind"] == "limit"]
    assert limits, summary["critical_points"]
    found = limits[0]["load_factor"]  # P L^2 / EI (examples/lee_frame.toml)
    reference, _ = lee_limit
    assert abs(found - 18.5) < 0.1
    assert abs(found - reference) <= 1e-4 * reference, (found, reference)
    # path.csv: the rods' ends and the corner's force per point, as in summary.json
    import csv

    rows = list(csv.DictReader(open(tmp_path / "out" / "path.csv")))
    last = summary["path"][-1]
    assert float(rows[-1]["rod_column_x"]) == last["rods"]["column"]["tip"][0]
    assert float(rows[-1]["joint_corner_Fy"]) == last["joints"]["corner"]["force"][1]
    assert float(rows[-1]["joint_corner_M"]) == last["joints"]["corner"]["moment"]
    # the column pinned at the origin as a free body: the corner's moment on it balances the
    # moment of the corner's force about the pin (the multipliers' forces included)
    for point in summary["path"][1:]:
        (x, y), joint = point["rods"]["column"]["tip"], point["joints"]["corner"]
        fx, fy = joint["force"]
        assert joint["moment"] == pytest.approx(-(x * fy - y * fx), abs=1e-9 * abs(fy))


# --- mistakes and what this version does not do ------------------------------------------------
def _lee_config() -> dict:
    import tomllib

    with open("examples/lee_frame.toml", "rb") as stream:
        config = tomllib.load(stream)
    del config["path"]
    return config


def _edit(change):
    config = _lee_config()
    change(config)
    return config


MISTAKES = [
    (lambda c: c["joints"][0].update(at=["colum:end", "beam:start"]), "unknown rod 'colum'"),
    (lambda c: c["joints"][0].update(at=["column:top", "beam:start"]), "names no end"),
    (lambda c: c["rods"][1].update(start=[0.0, 1.1]), "0.1 m apart"),
    (lambda c: c["rods"][0].update(direction=[0.0, 2.0]), "must be a unit vector"),
    (lambda c: c["rods"][0].update(direction=[0.0, 0.0]), "must be a unit vector"),
    (lambda c: c["rods"][0].update(direction=[0.0, 1.0000002]), "of length 1.0000002"),
    # a moment at a clamped chain end is the support's (as a force at a held end): refused
    (lambda c: c["rods"][0].update(supports={"x0": "clamped"},
                                   loads={"point_moments": [[0.0, 0.3]]}),
     "'column' loads.point_moments: a moment at the rod's x0 end, clamped there"),
    (lambda c: (c["rods"][0].update(supports={}),
                c["rods"][1].update(supports={"xL": "clamped"},
                                    loads={"point_moments": [[1.0, -0.2]]})),
     "'beam' loads.point_moments: a moment at the rod's xL end"),
    (lambda c: c["rods"][1].update(name="column"), "name 'column' is given twice"),
    (lambda c: c["joints"][0].update(at=["column:end"]), "two or more ends"),
    (lambda c: c.update(beam={"length": 1.0}), "[beam] with [[rods]]"),
    (lambda c: c["rods"][0].update(lenght=1.0), "unknown key 'lenght'"),
    (lambda c: c["joints"][0].update(kind="ball"), "kind = \"ball\" is spatial"),
    (lambda c: c["rods"][1].update(supports={}), "free to move as a rigid body"),
    (lambda c: c["rods"][0].update(loads={"point_forces": [[0.0, 1.0, 0.0]]}),
     "would be taken by the support"),
    # the key as written (x0 / xL), not the model's "start" / "end"
    (lambda c: c["rods"][1].update(supports={"xL": "welded"}), "'beam' supports.xL must be one"),
    (lambda c: c["rods"][0].update(supports={"x0": "hinged"}), "'column' supports.x0 must be"),
    # the range of lengths a single rod's [beam] length has, per rod and for the whole chain
    (lambda c: c["rods"][1].update(length=2e-7), "'beam' length = 2e-07 m is outside the range"),
    (lambda c: (c["rods"][0].update(length=7e5), c["rods"][1].update(start=[0.0, 7e5],
                                                                    length=6e5)),
     "the rods' lengths sum to 1.3e+06 m"),
]
UNSUPPORTED = [
    (lambda c: c["joints"][0].update(kind="hinge"), "kind = 'hinge' is not supported yet"),
    (lambda c: c["model"].update(kinematics="spatial"),
     "[model] kinematics = \"spatial\" takes three components"),
    (lambda c: (c["rods"].append({"name": "arm", "start": [0.0, 1.0], "direction": [-1.0, 0.0],
                                  "length": 0.5}),
                c["joints"].append({"name": "t", "at": ["arm:start", "column:end"]})),
     "column:end is already joined (by 'corner'); name every end meeting at a point in one "
     "joint"),
    (lambda c: c.update(bodies=[{"name": "palm", "position": [0.0, 0.0], "fixed": ["x"]}]),
     "partly fixed bodies are not supported yet"),
    (lambda c: c.update(tendons=[{"name": "t", "tension": 1.0}]),
     "[[tendons]] with [[rods]] is not supported yet"),
    (lambda c: c["loads"].update(tip_force=[0.0, 1.0]) if "loads" in c
     else c.update(loads={"tip_force": [0.0, 1.0]}), "[loads] tip_force with [[rods]]"),
]


@pytest.mark.parametrize("change, words", MISTAKES + UNSUPPORTED)
def test_structure_mistakes_are_one_sentence(change, words):
    with pytest.raises(ConfigError) as error:
        validate("static", _edit(change))
    assert words in str(error.value), str(error.value)


@pytest.mark.parametrize("command", ["finger", "solid", "compare", "validity"])
def test_other_commands_refuse_a_structure(command):
    with pytest.raises(ConfigError, match=f"fe-beam {command} does not run a structure"):
        validate(command, _lee_config())


def test_cli_exit_code_2(tmp_path, capsys):
    path = tmp_path / "frame.toml"
    path.write_text(open("examples/lee_frame.toml").read().replace(
        'kind = "rigid"', 'kind = "hinge"'))
    assert main(["path", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    assert "not supported yet" in capsys.readouterr().err
    assert main(["finger", "examples/lee_frame.toml", "--out", str(tmp_path / "m"),
                 "--quiet"]) == 2


def test_set_overrides_reach_the_rods():
    config = _lee_config()
    parsed = validate("static", fe_beam.config.apply_overrides(
        config, ["rods.1.length=2.0", "rods.1.loads.point_forces=[[1.5, 0.0, -1.0]]"])).parsed
    structure = parsed.model.structure
    assert structure.rods[1].length == 2.0
    assert parsed.model.length == 3.0
    assert parsed.model.loads.point_forces == ((2.5, 0.0, -1.0),)
    assert np.isclose(structure.reference_point(3.0)[0], 2.0)


@pytest.mark.parametrize("assignment, words", [
    # a misspelt rod name: the message offers the names as well as the indices
    ("rods.colum.length=2.0", "by its name (column, beam)"),
    ("joints.knee.kind=rigid", "by its name (corner)"),
    # an array of tables the file does not have: not "write [[bodies]], not [bodies]"
    ("bodies.0.position=[0.0, 0.0]", "the config has no [[bodies]] to index"),
])
def test_set_mistakes_on_the_structure_tables(assignment, words):
    with pytest.raises(ConfigError) as error:
        fe_beam.config.apply_overrides(_lee_config(), [assignment])
    assert words in str(error.value), str(error.value)


@pytest.mark.mpi
@pytest.mark.skipif(mpirun_command(2) is None or MPI.COMM_WORLD.size > 1,
                    reason="needs mpirun (and a serial pytest)")
def test_two_ranks_give_the_serial_structure(tmp_path):
    """``mpirun -n 2 fe-beam static`` of an L-frame: the same rods and joints as one rank."""
    from test_mpi_errors import fe_beam as fe_beam_job

    EI, _, _ = _stiffness()
    config = _l_frame(1.0, 0.6, [0.3 * EI, -1.5 * EI], elements=6)
    alone = fe_beam.run("static", config)["steps"][-1]
    process, _ = fe_beam_job(tmp_path, config, "--out", str(tmp_path / "two"))
    assert process.returncode == 0, process.stderr
    together = json.loads((tmp_path / "two" / "summary.json").read_text())["steps"][-1]
    for name in ("column", "beam"):
        assert together["rods"][name]["tip"] == pytest.approx(alone["rods"][name]["tip"],
                                                              abs=1e-11)
    assert together["joints"]["corner"]["force"] == pytest.approx(
        alone["joints"]["corner"]["force"], rel=1e-9)
    assert together["joints"]["corner"]["moment"] == pytest.approx(
        alone["joints"]["corner"]["moment"], rel=1e-9)


def test_joint_force_is_on_the_first_named_end():
    """Naming the beam's start first reports the force and moment on the beam: the opposite
    of those on the column's end."""
    EI, _, _ = _stiffness()
    config = _l_frame(1.0, 0.5, [0.3 * EI, -0.9 * EI], elements=4)
    swapped = copy.deepcopy(config)
    swapped["joints"][0]["at"] = ["beam:start", "column:end"]
    one = fe_beam.run("static", config)["steps"][-1]["joints"]["corner"]
    two = fe_beam.run("static", swapped)["steps"][-1]["joints"]["corner"]
    assert two["force"] == pytest.approx([-f for f in one["force"]], rel=1e-12)
    assert two["moment"] == pytest.approx(-one["moment"], rel=1e-12)


def test_one_rotated_rod_is_the_rotated_rod():
    """A structure of one rod along (cos a, sin a) under the rotated tip force is the rod
    along x under the force, turned by a (the reference angle in the kinematics)."""
    EI, _, _ = _stiffness()
    angle, length = 0.7, 0.9
    force = np.array([0.2 * EI, -1.1 * EI])
    turn = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    straight = _base(elements=6)
    straight["beam"] = {"length": length}
    straight["supports"] = {"x0": "clamped", "xL": "free"}
    straight["loads"]["tip_force"] = force.tolist()
    turned = _base(elements=6)
    turned["rods"] = [{"name": "r", "start": [0.3, -0.2], "direction": turn[:, 0].tolist(),
                       "length": length, "supports": {"x0": "clamped"},
                       "loads": {"point_forces": [[length, *(turn @ force)]]}}]
    tip = fe_beam.run("static", straight)["steps"][-1]["tip"]
    rod = fe_beam.run("static", turned)["steps"][-1]["rods"]["r"]
    expected = np.array([0.3, -0.2]) + turn @ np.array([length + tip["u"], tip["v"]])
    assert rod["tip"] == pytest.approx(expected.tolist(), abs=1e-12)
    assert rod["tip_angle"] == pytest.approx(angle + tip["theta"], abs=1e-12)


def test_xdmf_moves_the_line_onto_the_chain(tmp_path):
    """beam.xdmf: the mesh's points (s, 0) plus `displacement` are the deformed chain (each
    rod's end where `rods` has it), and `rod` names each cell's rod."""
    import h5py

    EI, _, _ = _stiffness()
    config = _l_frame(1.0, 0.5, [0.3 * EI, -0.9 * EI], elements=4)
    config["output"] = {"xdmf": True, "plots": False}
    summary = fe_beam.run("static", config, tmp_path / "out")
    with h5py.File(tmp_path / "out" / "beam.h5", "r") as h5:
        points = np.asarray(h5["Mesh"]["mesh"]["geometry"])[:, 0]
        last = lambda name: np.asarray(  # noqa: E731
            h5["Function"][name][str(max(int(k) for k in h5["Function"][name]))])
        displacement, rod = last("displacement"), last("rod").ravel()
    placed = points[:, None] * np.array([1.0, 0.0]) + displacement[:, :2]
    rods = summary["steps"][-1]["rods"]
    for name, s in (("column", 1.0), ("beam", 1.5)):
        at = int(np.argmin(np.abs(points - s)))
        assert placed[at] == pytest.approx(rods[name]["tip"], abs=1e-12)
    assert sorted(set(rod.tolist())) == [0.0, 1.0] and np.count_nonzero(rod == 1.0) == 4


def test_frame_shooting_small_load_is_castigliano():
    """The shooting baseline itself: an L-frame under a small tip force (Reissner law) against
    the unit-load method; the section force just before the tip is the tip force."""
    a, b = 0.8, 0.6
    EI, EA, GA = _stiffness()
    P = 1e-7 * EI / b**2
    frame = frame_shooting.Frame((a, b), (math.pi / 2, 0.0), EI, EA, GA, (0.0, 0.0),
                                 "clamped", "free", ((a + b, 0.0, -P),))
    end = frame_shooting.solve_frame(frame).end()
    v = -P * (b**3 / (3 * EI) + b / GA + a * b**2 / EI + a / EA)
    u = P * a**2 * b / (2 * EI)
    assert end[1] - a == pytest.approx(v, rel=1e-6)
    assert end[0] - b == pytest.approx(u, rel=1e-6)
    assert end[3:] == pytest.approx([0.0, -P, 0.0], abs=1e-9 * P)


def test_rods_with_their_own_section_and_material_against_shooting():
    """A column of another height and a beam of another material (the rods' own section and
    material tables over the top level's) under a large tip force, against shooting with the
    members' own EI, EA, GA."""
    a, b = 1.0, 0.8
    h_column, E_beam, nu_beam = 0.035, 5.0e7, 0.45
    config = _l_frame(a, b, [0.0, 0.0], elements=24)
    config["rods"][0]["section"] = {"h": h_column}
    config["rods"][1]["material"] = {"E": E_beam, "nu": nu_beam}
    EI, EA, GA = _stiffness()
    column = (E * B * h_column**3 / 12, E * B * h_column, E / (2 * (1 + NU)) * B * h_column)
    beam = (E_beam * B * H**3 / 12, E_beam * B * H, E_beam / (2 * (1 + nu_beam)) * B * H)
    force = [0.5 * column[0], -2.0 * column[0]]
    config["rods"][1]["loads"] = {"point_forces": [[b, *force]]}
    step = fe_beam.run("static", config)["steps"][-1]
    frame = frame_shooting.Frame((a, b), (math.pi / 2, 0.0), (column[0], beam[0]),
                                 (column[1], beam[1]), (column[2], beam[2]), (0.0, 0.0),
                                 "clamped", "free", ((a + b, *force),))
    reference = frame_shooting.solve_frame(frame).end()
    tip = step["rods"]["beam"]["tip"]
    assert math.hypot(reference[0] - b, reference[1] - a) > 0.3 * b  # large
    assert math.hypot(tip[0] - reference[0], tip[1] - reference[1]) <= 2e-7 * b
    # the same frame with the top level's section and material everywhere is another one
    uniform = frame_shooting.solve_frame(dataclasses.replace(frame, EI=EI, EA=EA, GA=GA)).end()
    assert math.hypot(tip[0] - uniform[0], tip[1] - uniform[1]) > 1e-2 * b


def test_a_moment_at_a_pinned_chain_end_is_a_load():
    """A moment at a pinned end (Lee's column start) turns the end: it is accepted."""
    config = _lee_config()
    config["rods"][0]["loads"] = {"point_moments": [[0.0, 0.3]]}
    assert validate("static", config).parsed.model.loads.point_moments == ((0.0, 0.3),)


@pytest.mark.parametrize("change, words", [
    (lambda c: c["rods"][0].update(section={"shape": "circle", "d": 0.02}),
     "a shape different from [section] shape is not supported yet"),
    (lambda c: c["rods"][0].update(section={"h_tip": 0.02}), "tapered rod"),
    (lambda c: c["rods"][0].update(material={"rho": 1000.0}), "density different"),
    (lambda c: c["rods"][0].update(model={"law": "nonstandard"}), "own law or constraint"),
    (lambda c: c["rods"][0].update(section={"h": -0.01}), "[[rods]] 'column' section:"),
    # nu and G both in the rod's own table (named once, not "material: material:")
    (lambda c: c["rods"][1].update(material={"G": 2e6, "nu": 0.25}),
     "[[rods]] 'beam' material: give exactly one of nu"),
])
def test_rods_own_tables_mistakes(change, words):
    with pytest.raises(ConfigError) as error:
        validate("static", _edit(change))
    assert words in str(error.value), str(error.value)


@pytest.mark.parametrize("own, other", [({"G": 2e6}, "nu"), ({"nu": 0.1}, "G")])
def test_rods_own_nu_or_g_replaces_the_top_levels_other(own, other):
    """A rod's own G over a top-level nu (or its own nu over a top-level G) is the rod's
    shear modulus: the two are alternatives (it was refused: "give exactly one of nu or G")."""
    config = _lee_config()
    E = config["material"]["E"]
    config["material"].pop("nu")
    config["material"].update({"nu": 0.3} if other == "nu" else {"G": E / 2.6})
    config["rods"][1]["material"] = own
    rods = validate("static", config).parsed.model.structure.rods
    expected = own["G"] if "G" in own else E / (2 * (1 + own["nu"]))
    assert rods[1].material == pytest.approx((E, expected), rel=1e-14)
    assert rods[0].material == pytest.approx((E, E / 2.6), rel=1e-14)


def test_three_rods_in_any_order_and_orientation_are_the_rod():
    """A cantilever cut in three rods listed out of order, the middle one given from its end
    (joined end to end and start to start), and the clamped rod last in the chain's order:
    the chain is found, and its free end is the single rod's tip."""
    length = 0.9
    single = _base(elements=9)
    single["beam"] = {"length": length}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    single["loads"] |= {"tip_force": [0.4, -1.5], "distributed": [0.0, -1.0]}
    split = _base(elements=3)
    split["loads"] |= {"distributed": [0.0, -1.0]}
    split["rods"] = [
        {"name": "middle", "start": [0.6, 0.0], "direction": [-1.0, 0.0], "length": 0.3},
        {"name": "last", "start": [0.6, 0.0], "direction": [1.0, 0.0], "length": 0.3,
         "loads": {"point_forces": [[0.3, 0.4, -1.5]]}},
        {"name": "first", "start": [0.0, 0.0], "direction": [1.0, 0.0], "length": 0.3,
         "supports": {"x0": "clamped"}}]
    split["joints"] = [{"name": "j2", "at": ["last:start", "middle:start"]},
                       {"name": "j1", "at": ["middle:end", "first:end"]}]
    tip = fe_beam.run("static", single)["steps"][-1]["tip"]
    step = fe_beam.run("static", split)["steps"][-1]
    assert step["rods"]["last"]["tip"] == pytest.approx([length + tip["u"], tip["v"]],
                                                        abs=1e-12)
    assert step["tip"]["theta"] == pytest.approx(tip["theta"], abs=1e-12)
    # the middle rod's own end is the first joint: its angle is the rod's (pi) + theta there
    assert step["rods"]["middle"]["tip"] == pytest.approx(step["rods"]["first"]["tip"],
                                                          abs=1e-14)
    assert step["rods"]["middle"]["tip_angle"] == pytest.approx(
        math.pi + step["rods"]["first"]["tip_angle"], abs=1e-14)

"""``fe-beam compare`` / ``validity`` / ``solid`` with the spatial rod (issue 22, item 6): the 3D
solid against the spatial rod (``[model] kinematics = "spatial"``) by the backbone distance
d = max_x |r_rod - r_solid| / L over the three components and the tip frame angle (of
R_rod^T R_solid). (a) a finger with a helical tendon at small tension: d < 1 % L; (b) a planar
in-plane case through the spatial rod gives the planar compare's numbers; (c) 2 ranks = serial;
(d) mistakes exit 2 with one sentence."""

import contextlib
import copy
import csv
import io
import json
import math
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI
from tomlio import dump_toml

from fe_beam.cli import main

L = 0.1
HELIX = {"name": "helix", "offset_y": "0.004*cos(pi*s/(2*L))",
         "offset_z": "0.004*sin(pi*s/(2*L))", "tension": 1.0}
# a 15 mm square finger, E = 1 MPa, nu = 0.45, neo-Hookean; P2 tetrahedra of h / 2 (the sizes of
# tests/solid/test_solid_driver.py); 1 N on the helix: tip deflection ~4 % L, strains < 1 %
FINGER = {
    "beam": {"length": L},
    "section": {"shape": "rectangle", "b": 0.015, "h": 0.015},
    "material": {"E": 1.0e6, "nu": 0.45, "rho": 1070.0},
    "model": {"kinematics": "spatial"},
    "mesh": {"elements": 20, "degree": 2},
    "loads": {"steps": 2},
    "solid": {"material": "neo-hookean", "mesh_size": 0.0075, "order": 2},
    "output": {"xdmf": False, "plots": False},
    "tendons": [HELIX],
    "compare": {"tensions": [0.5, 1.0]},
}
# the planar finger of tests/solid/test_compare.py (in-plane tendon, tapered)
PLANAR = {
    "beam": {"length": L},
    "section": {"shape": "rectangle", "b": 0.02, "h": 0.02, "h_tip": 0.01},
    "material": {"E": 0.6e6, "nu": 0.45, "rho": 1070.0},
    "model": {"law": "nonstandard"},
    "mesh": {"elements": 20, "degree": 2},
    "loads": {"steps": 3},
    "solid": {"material": "neo-hookean", "mesh_size": 0.01, "order": 2},
    "output": {"xdmf": False, "plots": False},
    "tendons": [{"name": "flexor", "offset_base": 0.008, "offset_tip": 0.004, "tension": 2.0}],
    "compare": {"tensions": [1.0, 2.0], "laws": ["nonstandard", "reissner"]},
}
LAWS = ("nonstandard", "reissner")


def edited(base: dict, **tables) -> dict:
    """``base`` with tables updated: ``edited(c, model={"law": "reissner"})``; None drops."""
    config = copy.deepcopy(base)
    for name, value in tables.items():
        if value is None:
            config.pop(name, None)
        elif isinstance(value, dict):
            config[name] = {**config.get(name, {}), **value}
        else:
            config[name] = value
    return config


def run_cli(command: str, folder: Path, config: dict, *extra) -> tuple[int, str, str, Path]:
    """``fe-beam <command>`` in-process: (exit code, stdout, stderr, output folder)."""
    comm = MPI.COMM_WORLD
    folder = Path(comm.bcast(str(folder) if comm.rank == 0 else None, root=0))
    path = folder / "c.toml"
    if comm.rank == 0:
        folder.mkdir(parents=True, exist_ok=True)
        path.write_text(dump_toml(config))
    comm.barrier()
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(stdout):
        code = main([command, str(path), "--out", str(folder / "out"), "--quiet", *extra])
    return code, stdout.getvalue(), stderr.getvalue(), folder / "out"


# --- the tip frame measure ------------------------------------------------------------------------
def test_tip_frame_angle_is_exact_near_zero_and_planar_rods_rotate_about_z():
    from scipy.spatial.transform import Rotation

    from fe_beam.analyses.solid_rod import planar_angle, tip_frame

    base = Rotation.from_rotvec([0.3, -0.5, 0.7]).as_matrix()
    for angle in (1e-10, 1e-6, 0.3, 3.0):
        axis = np.array([1.0, 2.0, -2.0]) / 3
        solid = base @ Rotation.from_rotvec(angle * axis).as_matrix()
        frame = tip_frame({"R": base.tolist()}, {"R": solid.tolist()})
        # arccos((tr - 1) / 2) has no digits left below ~1e-8; the quaternion keeps them
        assert frame["angle"] == pytest.approx(angle, rel=1e-6)
        assert np.allclose(frame["rotation_vector"], angle * axis, rtol=1e-6, atol=0)
    # a planar rod's frame: the rotation by theta about z
    solid = Rotation.from_rotvec([0.0, 0.0, 0.4]).as_matrix()
    assert tip_frame({"theta": 0.4}, {"R": solid.tolist()})["angle"] < 1e-15
    assert tip_frame({"theta": 0.1}, {"R": solid.tolist()})["angle"] == pytest.approx(0.3)
    assert planar_angle(solid.tolist()) == pytest.approx(0.4, rel=1e-14)


# --- (a) the helical finger: the 3D solid vs the spatial rod --------------------------------------
@pytest.fixture(scope="module")
def helix_run(tmp_path_factory):
    config = edited(FINGER, output={"plots": True})
    started = time.perf_counter()
    code, stdout, stderr, out = run_cli("compare", tmp_path_factory.mktemp("helix"), config)
    seconds = time.perf_counter() - started
    assert code == 0, stderr
    return out, json.loads((out / "summary.json").read_text()), stdout, stderr, seconds


def test_helical_tendon_spatial_rod_within_1_percent_of_the_solid(helix_run):
    out, summary, stdout, stderr, seconds = helix_run
    assert summary["status"] == "converged"
    # the hyperelastic section law is planar only: left out of the default laws, with a note
    assert summary["laws"] == list(LAWS)
    assert any("planar only" in note for note in summary["notes"])
    assert "planar only" in stderr
    assert summary["model"]["rod"]["kinematics"] == "spatial"
    rows = summary["table"]
    assert [r["tension"] for r in rows] == pytest.approx([0.5, 1.0])
    solid = rows[-1]["solid"]["tip"]
    # the helix (y, z) = (r, 0) at the base to (0, r) at the tip pulls toward +y and +z
    assert solid["v"] > 0.02 * L and solid["w"] > 0.01 * L
    rotation = np.linalg.norm(solid["rotation_vector"])
    lines = []
    for law in LAWS:
        d = [r["rod"][law]["distance_over_L"] for r in rows]
        angles = [r["rod"][law]["tip_frame_angle"] for r in rows]
        rod = rows[-1]["rod"][law]
        tip = rod["tip"]
        assert rod["status"] == "converged"
        assert {"u", "v", "w", "R", "rotation_vector", "position", "theta"} <= set(tip)
        assert set(rod["backbone"]) == {"x", "u", "v", "w"}
        assert rod["backbone"]["w"][-1] == pytest.approx(tip["w"], rel=1e-8)
        lines.append(f"{law}: d = {[f'{100 * x:.3g} %' for x in d]} of L, tip frame angle "
                     f"{[f'{a:.3g}' for a in angles]} rad (solid tip rotation {rotation:.3g} "
                     f"rad), tip w rod {tip['w']:.4g} / solid {solid['w']:.4g} m")
        assert max(d) < 0.01, (law, d)
        assert 0 < d[0] < d[1]  # the departure grows with the tension
        # the same deflection out of the plane and the same tip frame, to a few %
        assert tip["w"] == pytest.approx(solid["w"], rel=0.1)
        assert tip["v"] == pytest.approx(solid["v"], rel=0.1)
        assert angles[-1] < 0.1 * rotation
        frame = np.array(tip["R"])
        assert np.allclose(frame @ frame.T, np.eye(3), atol=1e-12)
        assert summary["departures"][law]["above_1_percent"] is None
        # (the solid's tip is the tip face's mean displacement, its backbone the sections'
        # area centroids: the two differ slightly)
        assert 0 < rod["tip_distance_over_L"] < 0.01
    print(f"helical finger, 1 N, compare {seconds:.1f} s:\n  " + "\n  ".join(lines))
    assert "tip frame angle" in stdout and "w " in stdout


def test_helical_compare_csv_and_plots(helix_run):
    out, summary, *_ = helix_run
    with (out / "compare.csv").open(newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 2
    # the planar columns are kept; w and the tip frame angle are added
    assert {"load_factor", "tension_0", "solid_tip_u", "solid_tip_v", "solid_tip_theta",
            "solid_tip_w"} <= set(rows[0])
    for law in LAWS:
        assert {f"{law}_tip_{k}" for k in ("u", "v", "theta", "w", "frame_angle")} \
            | {f"{law}_distance_over_L"} <= set(rows[0])
        entry = summary["table"][1]["rod"][law]
        assert float(rows[1][f"{law}_tip_w"]) == pytest.approx(entry["tip"]["w"])
        assert float(rows[1][f"{law}_tip_frame_angle"]) == pytest.approx(entry["tip_frame_angle"])
    for name in ("backbones.png", "tip_vs_tension.png"):
        assert (out / name).stat().st_size > 1000, name


def test_solid_command_runs_the_spatial_rod_alongside(tmp_path, helix_run):
    """``fe-beam solid``: the spatial rod beside the solid (no longer skipped), its distance
    and tip frame angle, rod.xdmf with (u, v, w) and the rotation vector."""
    _, compared, *_ = helix_run
    config = edited(FINGER, compare=None, output={"xdmf": True})
    code, stdout, stderr, out = run_cli("solid", tmp_path, config)
    assert code == 0, stderr
    summary = json.loads((out / "summary.json").read_text())
    rod = summary["rod"]
    assert rod["status"] == "converged" and rod["law"] == "nonstandard"
    assert "w" in rod["steps"][-1]["tip"] and "w" in rod["backbone"]
    distance = rod["distance_to_solid"]
    reference = compared["table"][-1]["rod"]["nonstandard"]
    # the same equilibria (the compare sweep reaches them in two segments)
    assert distance["max_over_L"] == pytest.approx(reference["distance_over_L"], rel=1e-3)
    assert distance["tip_frame_angle"] == pytest.approx(reference["tip_frame_angle"], rel=1e-3)
    assert "tip frame angle" in stdout
    if MPI.COMM_WORLD.rank == 0:
        root = ET.parse(out / "rod.xdmf").getroot()
        names = {a.get("Name") for a in root.iter("Attribute")}
        assert names == {"displacement", "rotation_vector"}
        last = list(root.iter("Grid"))[-1]
        values = np.array(last.find("Attribute").find("DataItem").text.split(), float)
        assert values.reshape(-1, 3)[-1, 2] == pytest.approx(rod["steps"][-1]["tip"]["w"])


def test_validity_maps_the_spatial_rod(tmp_path, helix_run):
    """One point of ``fe-beam validity`` on the helical finger: compare's numbers at full load,
    the tip error over u, v, w, the tip frame angle and the w columns of validity.csv."""
    _, compared, *_ = helix_run
    config = edited(FINGER, compare=None, validity={"x": "tendons.0.tension", "x_values": [1.0]})
    code, _, stderr, out = run_cli("validity", tmp_path, config)
    assert code == 0, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["kinematics"] == "spatial" and summary["laws"] == list(LAWS)
    point = summary["points"][0]
    reference = compared["table"][-1]["rod"]
    for law in LAWS:
        rod = point["rod"][law]
        assert rod["backbone_distance"] == pytest.approx(reference[law]["distance_over_L"],
                                                         rel=1e-3)
        assert rod["tip_frame_angle"] == pytest.approx(reference[law]["tip_frame_angle"],
                                                       rel=1e-3)
        assert rod["tip_error"]["frame_angle"] == rod["tip_frame_angle"]
        assert rod["tip_error"]["distance_over_L"] == pytest.approx(
            reference[law]["tip_distance_over_L"], rel=1e-3)
    if MPI.COMM_WORLD.rank == 0:
        with (out / "validity.csv").open(newline="") as stream:
            row = next(csv.DictReader(stream))
        assert float(row["solid_tip_w"]) == pytest.approx(point["solid"]["tip"]["w"])
        for law in LAWS:
            assert float(row[f"{law}_tip_w"]) == pytest.approx(point["rod"][law]["tip"]["w"])
            assert float(row[f"{law}_tip_frame_angle"]) == pytest.approx(
                point["rod"][law]["tip_frame_angle"])
            assert float(row[f"{law}_backbone_distance"]) < 0.01


# --- (b) a planar case through the spatial rod: the planar compare's numbers ---------------------
def test_in_plane_tendon_through_the_spatial_rod_gives_the_planar_compare():
    from fe_beam.analyses.compare import run_compare

    runs = {kind: run_compare(edited(PLANAR, model={"kinematics": kind}), None, MPI.COMM_WORLD,
                              progress=False) for kind in ("planar", "spatial")}
    assert runs["planar"]["status"] == runs["spatial"]["status"] == "converged"
    worst = 0.0
    for a, b in zip(runs["planar"]["table"], runs["spatial"]["table"], strict=True):
        assert a["solid"] == b["solid"]  # the solid side identical
        for law in LAWS:
            planar, spatial = a["rod"][law], b["rod"][law]
            for key in ("u", "v", "theta"):
                worst = max(worst, abs(planar["tip"][key] - spatial["tip"][key]) / L)
            assert abs(spatial["tip"]["w"]) < 1e-12 * L
            for key in ("u", "v"):
                worst = max(worst, np.abs(np.subtract(planar["backbone"][key],
                                                      spatial["backbone"][key])).max() / L)
            for key in ("distance_over_L", "tip_distance_over_L", "tip_frame_angle"):
                worst = max(worst, abs(planar[key] - spatial[key]))
    print(f"planar finger through the spatial rod: largest difference {worst:.3g} (of L, rad)")
    assert worst < 1e-8
    for law in LAWS:
        assert runs["planar"]["departures"][law]["max_distance_over_L"] == pytest.approx(
            runs["spatial"]["departures"][law]["max_distance_over_L"], rel=1e-8, abs=1e-12)


# --- (c) 2 ranks = serial ------------------------------------------------------------------------
@pytest.mark.mpi
def test_spatial_compare_two_ranks_equal_serial():
    if MPI.COMM_WORLD.size == 1:
        pytest.skip("run under mpirun -n 2 to compare a serial and a parallel solve")
    from fe_beam.analyses.compare import run_compare

    config = edited(FINGER, compare={"tensions": [1.0], "laws": ["reissner"]})
    parallel = run_compare(config, None, MPI.COMM_WORLD, progress=False)
    serial = run_compare(config, None, MPI.COMM_SELF, progress=False)
    assert parallel["status"] == serial["status"] == "converged"
    assert parallel["dofs"] == serial["dofs"] and parallel["rod_dofs"] == serial["rod_dofs"]
    a, b = serial["table"][-1], parallel["table"][-1]
    for key in ("u", "v", "w"):
        assert a["solid"]["tip"][key] == pytest.approx(b["solid"]["tip"][key], rel=1e-8)
    ra, rb = a["rod"]["reissner"], b["rod"]["reissner"]
    for key in ("u", "v", "w", "theta"):
        assert ra["tip"][key] == pytest.approx(rb["tip"][key], rel=1e-8, abs=1e-14)
    assert np.allclose(ra["tip"]["R"], rb["tip"]["R"], rtol=0, atol=1e-10)
    for key in ("u", "v", "w"):
        assert np.allclose(ra["backbone"][key], rb["backbone"][key], rtol=0, atol=1e-10)
    assert ra["distance_over_L"] == pytest.approx(rb["distance_over_L"], rel=1e-6)
    assert ra["tip_frame_angle"] == pytest.approx(rb["tip_frame_angle"], rel=1e-5, abs=1e-10)


# --- (d) mistakes: exit 2 and one sentence ------------------------------------------------------
VALIDITY = {"x": "tendons.0.tension", "x_values": [0.5, 1.0]}
MISTAKES = [
    ("compare", edited(FINGER, compare={"laws": ["hyperelastic", "reissner"]}),
     "[compare] laws: the hyperelastic section law is planar only"),
    ("validity", edited(FINGER, validity=VALIDITY | {"laws": ["hyperelastic"]}),
     "[validity] laws: the hyperelastic section law is planar only"),
    ("compare", edited(FINGER, model={"law": "hyperelastic"}),
     "[model] law = \"hyperelastic\" is not available for kinematics = \"spatial\""),
    ("compare", edited(FINGER, model=None), 'needs [model] kinematics = "spatial"'),
    ("solid", edited(FINGER, model={"kinematics": "3d"}), "[model] kinematics must be"),
    ("compare", edited(FINGER, model=None, tendons=[{"offset_y": 0.004, "tension": 1.0}],
                       compare={}, loads={"tip_force": [0.0, 0.0, 0.01]}),
     '[loads] tip_force must be planar'),
    ("refine --levels 3 --quantity tip.theta", edited(FINGER, solid=None, compare=None),
     "--quantity: tip.theta is not a quantity of a spatial rod; choose from tip.u, tip.v, "
     "tip.w, tip.r"),
]


@pytest.mark.parametrize(("command", "config", "fragment"), MISTAKES,
                         ids=[f"{c.split()[0]}-{i}" for i, (c, _, _) in enumerate(MISTAKES)])
def test_mistakes_exit_2_with_one_sentence(tmp_path, command, config, fragment):
    command, *extra = command.split()
    code, _, stderr, out = run_cli(command, tmp_path, config, *extra)
    assert code == 2, stderr
    if MPI.COMM_WORLD.rank == 0:
        lines = stderr.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in stderr, stderr
        assert fragment in lines[0], (fragment, stderr)
    assert not (out / "summary.json").exists()


def test_the_spatial_rod_takes_the_tip_force_along_z():
    """With the spatial rod a tip force with a z component is compared (the planar rod's compare
    refuses it, above); validity maps a spatial rod with its two laws."""
    from fe_beam.config.compare import parse_compare
    from fe_beam.config.validity import parse_validity

    parsed = parse_compare(edited(FINGER, tendons=None, compare=None,
                                  loads={"tip_force": [0.0, 0.01, 0.02]}))
    assert parsed.spatial and parsed.solid.rod.model.loads.tip_force == (0.0, 0.01, 0.02)
    assert parsed.solid.tip_force == (0.0, 0.01, 0.02)
    mapped = parse_validity(edited(FINGER, validity=VALIDITY))
    assert mapped.kinematics == "spatial" and mapped.laws == LAWS
    assert all(p.parsed.spatial and p.parsed.laws == LAWS for p in mapped.points)
    assert math.isclose(mapped.points[1].parsed.solid.tendon_loads[0].tension, 1.0)


# --- fe-beam refine on a spatial rod --------------------------------------------------------------
def test_refine_a_spatial_cantilever_observed_order(tmp_path):
    """A cantilever under a tip force with y and z components (large deflection): degree 2 rod
    elements converge at the nodes with order 4 (as the planar rod's), for the tip's w and |r|."""
    config = {"beam": {"length": 1.0}, "section": {"shape": "rectangle", "b": 0.02, "h": 0.01},
              "material": {"E": 2.0e11, "nu": 0.3},
              "model": {"kinematics": "spatial", "law": "reissner"},
              "mesh": {"elements": 3, "degree": 2},
              "loads": {"tip_force": [0.0, -3000.0, 2000.0], "steps": 5},
              "output": {"xdmf": False, "plots": False}}
    code, stdout, stderr, out = run_cli("refine", tmp_path, config, "--levels", "4")
    assert code == 0, stderr
    summary = json.loads((out / "refinement.json").read_text())
    assert summary["quantities"] == ["tip.u", "tip.v", "tip.w", "tip.r"]
    assert [r["elements"] for r in summary["levels"]] == [3, 6, 12, 24]
    for quantity in ("tip.w", "tip.r"):
        result = summary["analysis"][quantity]
        print(f"spatial cantilever {quantity}: observed order {result['order']:.3f}, "
              f"extrapolated {result['extrapolated']:.10g} m")
        assert result["order"] == pytest.approx(4.0, abs=0.3)
    last = summary["levels"][-1]["values"]
    assert last["tip.w"] > 0.25 and last["tip.v"] < -0.7  # out of both planes, large
    u, v, w = (last[f"tip.{k}"] for k in "uvw")
    assert last["tip.r"] == pytest.approx(math.sqrt((1 + u) ** 2 + v**2 + w**2), rel=1e-12)

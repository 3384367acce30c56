"""``fe-beam compare``, ``fe-beam validity`` and the solid's outputs with [[obstacles]]: the tendon
finger of tests/solid/test_solid_driver.py bends up into a roof y = 11 mm (as
tests/test_solid_contact.py's roof test). The rod's and the solid's roof forces agree within the
free finger's 1D-vs-3D tip difference; compare's entries are those of ``fe-beam solid`` and of
``fe-beam finger`` (the rod alone, the same roof in 2D); the contact pressure written to
solid.xdmf, integrated over the solid's surface, is the summary's force; validity maps the
contact-force difference; bad inputs exit 2."""

import copy
import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from mpi4py import MPI

from fe_beam.config.compare import parse_compare
from fe_beam.config.validity import parse_validity
from fe_beam.errors import ConfigError

ROOF, TOLERANCE = 0.011, 2e-5


def finger(**changes) -> dict:
    from tests.solid.test_solid_driver import FINGER

    config = copy.deepcopy(FINGER) | {"output": {"xdmf": False, "plots": False}}
    return config | changes


def roofed(**changes) -> dict:
    return finger(**({"obstacles": [{"shape": "plane", "name": "roof",
                                     "point": [0.0, ROOF, 0.0], "normal": [0.0, -1.0, 0.0]}],
                      "contact": {"penetration_tolerance": TOLERANCE}} | changes))


def cli(tmp_path: Path, command: str, config: dict, name: str):
    from tests.solid.test_solid_driver import run_cli, shared_folder

    return run_cli(command, shared_folder(tmp_path) / name, config)


def surface_integral(h5: Path, name: str, step: int) -> tuple[float, float]:
    """(integral of the nodal field ``name`` of output step ``step`` over the boundary of the
    tetrahedral mesh in ``h5`` (P1: exact for the linear interpolant), the boundary's area): the
    boundary triangles are the tetrahedra's faces that appear once, after merging the nodes
    that several ranks wrote (same coordinates)."""
    with h5py.File(h5, "r") as f:
        x = f["Mesh/mesh/geometry"][()]
        cells = f["Mesh/mesh/topology"][()]
        values = f[f"Function/{name}/{step}"][()].ravel()
    _, first, merged = np.unique(np.round(x, 12), axis=0, return_index=True,
                                 return_inverse=True)
    merged = merged.ravel()
    cells = merged[cells]
    faces = np.vstack([cells[:, [0, 1, 2]], cells[:, [0, 1, 3]], cells[:, [0, 2, 3]],
                       cells[:, [1, 2, 3]]])
    key = np.sort(faces, axis=1)
    unique, count = np.unique(key, axis=0, return_counts=True)
    boundary = unique[count == 1]
    node_value = np.zeros(merged.max() + 1)
    node_value[merged] = values  # duplicates carry the same value
    points = x[first]
    a, b, c = (points[boundary[:, k]] for k in range(3))
    areas = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    mean = node_value[boundary].mean(axis=1)
    return float(np.sum(areas * mean)), float(np.sum(areas))


@pytest.mark.mpi
def test_compare_in_contact_agrees_with_the_solid_the_rod_alone_and_the_xdmf(tmp_path):
    """One sweep point (the full tension): the roof's force on each rod and on the 3D finger
    differ by less than the free finger's 1D-vs-3D tip deflection; the compare entries equal
    ``fe-beam solid``'s (the same configuration and load steps) and the non-standard rod's
    those of ``fe-beam finger`` with the roof in 2D; solid.xdmf's contact_pressure_0 integrated
    over the surface is |F| (a plane: F = n int p dA), and contact_gap_0 is >= -tolerance."""
    import fe_beam

    code, stdout, stderr, out = cli(tmp_path, "compare", roofed(
        compare={"steps": 1, "laws": ["nonstandard", "reissner"]},
        output={"xdmf": False, "plots": True}), "compare")
    assert code == 0, stderr
    summary = json.loads((out / "summary.json").read_text())
    row = summary["table"][-1]
    solid = row["solid"]["contact"][0]
    assert solid["name"] == "roof" and solid["force"][1] < 0
    assert 0 < solid["max_penetration"] <= TOLERANCE
    code, _, stderr, free_out = cli(tmp_path, "compare", finger(
        compare={"steps": 1, "laws": ["nonstandard", "reissner"]}), "free")
    assert code == 0, stderr
    free = json.loads((free_out / "summary.json").read_text())["table"][-1]
    for law in ("nonstandard", "reissner"):
        rod = row["rod"][law]
        free_difference = (abs(free["rod"][law]["tip"]["v"] - free["solid"]["tip"]["v"])
                           / abs(free["solid"]["tip"]["v"]))
        F_rod, F_solid = np.array(rod["contact"][0]["force"] + [0.0]), np.array(solid["force"])
        expected = np.linalg.norm(F_rod - F_solid) / max(np.linalg.norm(F_rod),
                                                         np.linalg.norm(F_solid))
        print(f"{law}: roof force rod {F_rod[1]:.6g} N, solid {F_solid[1]:.6g} N: "
              f"{rod['contact_force_difference'][0]:.2%} apart (free tip deflection: "
              f"{free_difference:.2%}); contact lengths rod {rod['contact'][0]['contact_length']}"
              f", solid {solid['contact_length']} (extent {solid['extent']})")
        assert rod["contact_force_difference"][0] == pytest.approx(expected, rel=1e-12)
        assert rod["max_contact_force_difference"] == rod["contact_force_difference"][0]
        assert rod["contact_force_difference"][0] < free_difference
        assert rod["contact"][0]["contact_point_penetration"] <= TOLERANCE
        assert summary["departures"][law]["max_contact_force_difference"] == pytest.approx(
            rod["contact_force_difference"][0])
        assert rod["distance_over_L"] < 0.01
    # the tip presses on the roof: a point contact at x = L for the rod and the solid
    assert solid["extent"][1] == pytest.approx(0.1, abs=1e-12)
    assert row["rod"]["nonstandard"]["contact"][0]["active"][-1][1] == pytest.approx(0.1)
    if MPI.COMM_WORLD.rank == 0:
        header = (out / "compare.csv").read_text().splitlines()[0].split(",")
        for column in ("solid_contact0_Fy", "solid_contact0_length", "nonstandard_contact0_Fy",
                       "reissner_contact0_length", "reissner_contact0_force_difference"):
            assert column in header
        assert (out / "contact.png").exists() and (out / "backbones.png").exists()
        assert "contact with 'roof'" in stdout

    # fe-beam solid, the same configuration: the same solid entries, and the XDMF fields
    code, _, stderr, solid_out = cli(tmp_path, "solid", roofed(
        output={"xdmf": True, "plots": True}), "solid")
    assert code == 0, stderr
    alone = json.loads((solid_out / "summary.json").read_text())["steps"][-1]["contact"][0]
    for key in ("force", "active_area", "max_penetration", "pressure_peak", "extent",
                "contact_length"):
        print(f"compare vs solid {key}: {np.max(np.abs(np.subtract(alone[key], solid[key])))}")
        assert np.allclose(alone[key], solid[key], rtol=1e-8, atol=1e-14), key
    if MPI.COMM_WORLD.rank == 0:
        steps = len(json.loads((solid_out / "summary.json").read_text())["steps"])
        integral, area = surface_integral(solid_out / "solid.h5", "contact_pressure_0", steps)
        print(f"XDMF: int p dA = {integral:.12g} N vs |F| = {np.linalg.norm(alone['force']):.12g} "
              f"N (surface {area:.6g} m^2)")
        assert integral == pytest.approx(np.linalg.norm(alone["force"]), rel=1e-6)
        # the boundary found in the file is the finger's: two tapered faces, two trapezoids,
        # the clamped and the tip face (L = 0.1, b = 0.02, h = 0.02 -> 0.01)
        faces = (2 * np.hypot(0.1, 0.005) * 0.02 + 2 * 0.1 * 0.015 + 0.02 * 0.02
                 + 0.02 * 0.01)
        assert area == pytest.approx(faces, rel=1e-9)
        with h5py.File(solid_out / "solid.h5", "r") as f:
            gap = f[f"Function/contact_gap_0/{steps}"][()]
            pressure = f[f"Function/contact_pressure_0/{steps}"][()]
        assert gap.min() >= -TOLERANCE and pressure.min() >= 0
        assert 0 < pressure.max() <= alone["pressure_peak"] * (1 + 1e-9)
        header = (solid_out / "load_displacement.csv").read_text().splitlines()[0]
        assert "contact0_Fy" in header and "contact0_length" in header
        assert (solid_out / "backbone.png").exists()
        import meshio

        surface = meshio.read(solid_out / "obstacles.vtu")  # the roof: on the plane y = ROOF
        assert np.abs(surface.points[:, 1] - ROOF).max() < 1e-12

    # the rod alone: fe-beam finger with the roof in 2D
    rod_config = {k: v for k, v in finger().items() if k != "solid"} | {
        "obstacles": [{"shape": "plane", "name": "roof", "point": [0.0, ROOF],
                       "normal": [0.0, -1.0]}],
        "contact": {"penetration_tolerance": TOLERANCE}}
    rod = fe_beam.run("finger", rod_config)["steps"][-1]["contact"][0]
    compared = row["rod"]["nonstandard"]["contact"][0]
    print(f"compare vs finger: {np.subtract(compared['force'], rod['force'])}")
    assert np.allclose(compared["force"], rod["force"], rtol=1e-6)
    assert compared["active"] == rod["active"]


def test_validity_maps_the_contact_force_difference(tmp_path):
    """One point (the full tension) with [validity] metric = "contact_force_difference": the
    point's difference is compare's, the CSV has the column, the statement counts it."""
    from fe_beam.analyses.validity import run_validity

    raw = roofed(validity={"x": "tendons.0.tension", "x_values": [2.0],
                           "laws": ["reissner"], "metric": "contact_force_difference"})
    summary = run_validity(raw, tmp_path, MPI.COMM_SELF, progress=False)
    assert summary["status"] == "converged", summary["message"]
    point = summary["points"][0]["rod"]["reissner"]
    solid = summary["points"][0]["solid"]["contact"][0]
    rod = point["contact"][0]
    F_rod = np.array(rod["force"] + [0.0])
    expected = np.linalg.norm(F_rod - solid["force"]) / max(np.linalg.norm(F_rod),
                                                           np.linalg.norm(solid["force"]))
    print(f"validity: contact force difference {point['contact_force_difference']:.4g}")
    assert point["contact_force_difference"] == pytest.approx(expected, rel=1e-12)
    assert 0 < point["contact_force_difference"] < 0.05
    departures = summary["departures"]["reissner"]
    assert departures["metric"] == summary["metric"] == "contact_force_difference"
    assert departures["max_contact_force_difference"] == point["contact_force_difference"]
    assert departures["below_5_percent"] == 1
    assert "F_rod - F_solid" in departures["statement"]
    assert departures["max_backbone_distance"] == point["backbone_distance"]
    header = (tmp_path / "validity.csv").read_text().splitlines()[0].split(",")
    assert "reissner_contact_force_difference" in header


def test_the_contact_measures():
    """`force_difference` and `active_length` on hand-computed values."""
    from fe_beam.analyses.compare import active_length, force_difference

    assert force_difference([3.0, 4.0], [0.0, 0.0, 0.0]) == 1.0
    assert force_difference([0.0, 0.0], [0.0, 0.0, 0.0]) == 0.0
    assert force_difference([0.0, -1.0], [0.0, -1.0, 0.0]) == 0.0
    assert force_difference([0.0, -1.0, 0.0], [0.0, -0.8, 0.6]) == pytest.approx(
        np.sqrt(0.04 + 0.36))
    assert force_difference([0.0, -2.0], [0.0, -1.0, 0.0]) == pytest.approx(0.5)
    assert active_length([[0.1, 0.1]]) == 0.0
    assert active_length([[0.02, 0.05], [0.07, 0.1]]) == pytest.approx(0.06)


# --- bad inputs: one sentence, exit 2 -----------------------------------------------------------
def test_planar_sections_of_the_obstacles():
    """The planar rod of compare reads the z = 0 sections of obstacles that are the same in
    every plane z = const across the finger."""
    raw = roofed(obstacles=[
        {"shape": "plane", "name": "roof", "point": [0.0, ROOF, 0.0],
         "normal": [0.0, -1.0, 0.0]},
        {"shape": "cylinder", "name": "post", "point": [0.05, -0.05, 0.0], "radius": 0.02},
        {"shape": "box", "name": "table", "min": [0.0, -0.1, -0.02], "max": [0.2, -0.05, 0.02]}])
    rod = parse_compare(raw).solid.rod
    assert [o.dim for o in rod.obstacles] == [2, 2, 2]
    assert rod.obstacles[0].normal == (0.0, -1.0) and rod.obstacles[1].radius == 0.02
    assert rod.obstacles[2].min == (0.0, -0.1) and rod.obstacles[2].max == (0.2, -0.05)


@pytest.mark.parametrize("obstacle, fragment", [
    ({"shape": "sphere", "center": [0.05, 0.05, 0.0], "radius": 0.02}, "same in every plane"),
    ({"shape": "plane", "point": [0.0, ROOF, 0.0], "normal": [0.0, -1.0, 0.3]},
     "same in every plane"),
    ({"shape": "box", "min": [0.0, 0.02, -0.005], "max": [0.1, 0.03, 0.005]},
     "same in every plane"),
    ({"shape": "plane", "point": [0.0, ROOF, 0.0], "normal": [0.0, -1.0, 0.0],
      "friction": 0.3}, "friction"),
])
def test_compare_refuses_obstacles_the_planar_rod_cannot_read(tmp_path, obstacle, fragment):
    from tests.solid.test_solid_driver import assert_usage_error

    config = roofed(obstacles=[obstacle | {"name": "thing"}])
    code, _, stderr, _ = cli(tmp_path, "compare", config, "bad")
    assert_usage_error(code, stderr, "compare", fragment)


def test_compare_takes_a_spatial_rod_under_a_roof_clear_of_its_flat_side():
    """The roof at 11 mm is clear of the section's flat side (h/2 = 10 mm): the spatial rod
    is compared (the tube of its circumradius, 14 mm, was refused until issue 28); a roof at
    9 mm cuts the section, and the refusal names its extent."""
    parse_compare(roofed(model={"law": "nonstandard", "kinematics": "spatial"}))
    low = roofed(model={"law": "nonstandard", "kinematics": "spatial"})
    low["obstacles"][0]["point"] = [0.0, 0.009, 0.0]
    with pytest.raises(ConfigError, match="intersects the undeformed rod.*0.02 x 0.02 m"):
        parse_compare(low)


def test_validity_refuses_the_contact_metric_without_obstacles():
    with pytest.raises(ConfigError, match="needs \\[\\[obstacles\\]\\]"):
        parse_validity(finger(validity={"x": "tendons.0.tension", "x_values": [1.0],
                                        "metric": "contact_force_difference"}))
    with pytest.raises(ConfigError, match="metric must be one of"):
        parse_validity(roofed(validity={"x": "tendons.0.tension", "x_values": [1.0],
                                        "metric": "force"}))

"""Outputs of contact (issue 23, item 4): the gap and pressure fields in beam.xdmf, the
obstacles as a ParaView surface (obstacles.vtu), obstacles in the pictures.

beam.xdmf holds per obstacle i ``contact_gap_i`` (P1: the signed gap of the rod's surface at
the vertices, the UFL gap interpolated) and ``contact_pressure_i`` (DG0: the largest line
pressure at the cell's contact points). At the end state the largest cell pressure is the
summary's pressure_peak (the same numbers: to round-off), and the deepest vertex gap agrees
with max_penetration to within the penetration tolerance (the summary's is taken over the
contact points and the two ends, the field's over the vertices: both are below the
tolerance, their difference is the gap's variation between a vertex and the Gauss points).
"""

import json
import math
import re
from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest

from fe_beam.analyses.static import solve_static
from fe_beam.config.registry import validate

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
L = 1.0
EI = 1.0
GAP = 1e-4
Q1 = 8 * EI * GAP / L**4
TOLERANCE = 1e-7


def planar(q: float) -> dict:
    b = h = 0.01
    return {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": b, "h": h},
        "material": {"E": 12 * EI / (b * h**3), "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable"},
        "mesh": {"elements": 40, "degree": 2},
        "loads": {"distributed": [0.0, -q], "steps": 4},
        "solver": {"atol": 1e-10},
        "obstacles": [{"shape": "plane", "name": "floor", "point": [0.0, -GAP - h / 2],
                       "normal": [0.0, 1.0]},
                      {"shape": "sphere", "name": "ball", "center": [0.5, 0.3],
                       "radius": 0.1}],
        "contact": {"penetration_tolerance": TOLERANCE},
        "output": {"xdmf": True, "plots": True},
    }


def spatial(q: float, angle: float = 0.7) -> dict:
    d = 0.01
    c, s = math.cos(angle), math.sin(angle)
    offset = GAP + d / 2
    return {
        "beam": {"length": L},
        "section": {"shape": "circle", "d": d},
        "material": {"E": EI / (math.pi * d**4 / 64), "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable",
                  "kinematics": "spatial"},
        "mesh": {"elements": 40, "degree": 2},
        "loads": {"distributed": [0.0, -q * c, -q * s], "steps": 4},
        "solver": {"atol": 1e-12},
        "obstacles": [{"shape": "plane", "name": "floor",
                       "point": [0.0, -offset * c, -offset * s], "normal": [0.0, c, s]},
                      {"shape": "sphere", "name": "ball", "center": [0.5, 0.3, 0.3],
                       "radius": 0.1},
                      {"shape": "cylinder", "name": "post", "point": [0.8, 0.4, 0.0],
                       "axis": [0.0, 0.0, 1.0], "radius": 0.05, "length": 0.2}],
        "contact": {"penetration_tolerance": TOLERANCE},
        "output": {"xdmf": True, "plots": True},
    }


def run(config: dict, out):
    result = solve_static(validate("static", config).parsed, out, progress=False)
    assert result.status == "converged", result.message
    return result


def last_fields(out) -> dict:
    index = (out / "beam.xdmf").read_text()
    names = set(re.findall(r'Attribute Name="(contact_[a-z]+_\d+)"', index))
    with h5py.File(out / "beam.h5", "r") as h5:
        fields = {}
        for name in names:
            group = h5["Function"][name]
            fields[name] = np.asarray(group[str(max(int(k) for k in group))])
    return fields


def check_fields(result, out, count: int) -> dict:
    fields = last_fields(out)
    assert set(fields) == {f"contact_{kind}_{i}" for kind in ("gap", "pressure")
                           for i in range(count)}
    measured = {}
    for i, entry in enumerate(result.steps[-1]["contact"]):
        gap, pressure = fields[f"contact_gap_{i}"].ravel(), fields[f"contact_pressure_{i}"]
        assert np.all(pressure >= 0)
        peak = float(np.max(pressure))
        assert peak == pytest.approx(entry["pressure_peak"], rel=1e-12, abs=1e-12)
        penetration = max(0.0, float(-np.min(gap)))
        assert abs(penetration - entry["max_penetration"]) <= TOLERANCE
        measured[i] = (peak, entry["pressure_peak"], penetration, entry["max_penetration"],
                       float(np.min(gap)))
    return measured


def check_surfaces(out, config: dict, dim: int) -> None:
    mesh = meshio.read(out / "obstacles.vtu")
    which = mesh.cell_data["obstacle"][0]
    triangles = mesh.cells_dict["triangle"]
    assert set(which) == set(range(len(config["obstacles"])))
    for i, obstacle in enumerate(config["obstacles"]):
        points = mesh.points[np.unique(triangles[which == i])]
        if obstacle["shape"] == "plane":
            normal = np.zeros(3)
            normal[:dim] = obstacle["normal"]
            point = np.zeros(3)
            point[:dim] = obstacle["point"]
            assert np.max(np.abs((points - point) @ (normal / np.linalg.norm(normal)))) < 1e-12
            assert len(points) > 4
        elif obstacle["shape"] == "sphere":
            centre = np.zeros(3)
            centre[:dim] = obstacle["center"]
            radius = np.linalg.norm(points - centre, axis=1)
            assert np.allclose(radius, obstacle["radius"], rtol=1e-12)
        elif obstacle["shape"] == "cylinder":
            rel = points - np.array(obstacle["point"])
            axis = np.array(obstacle["axis"], dtype=float)
            radial = rel - np.outer(rel @ axis, axis)
            assert np.allclose(np.linalg.norm(radial, axis=1), obstacle["radius"], rtol=1e-12)
            assert np.max(np.abs(rel @ axis)) == pytest.approx(obstacle["length"] / 2)


def test_planar_contact_fields_surfaces_and_pictures(tmp_path):
    config = planar(20 * Q1)
    result = run(config, tmp_path)
    measured = check_fields(result, tmp_path, 2)
    assert measured[0][0] > 0  # the floor carries a line pressure (a contact interval)
    assert measured[1][0] == 0.0 and measured[1][4] > 0.1  # the ball is not touched
    check_surfaces(tmp_path, config, 2)
    assert (tmp_path / "deformed_shapes.png").stat().st_size > 10_000


def test_spatial_contact_fields_surfaces_and_pictures(tmp_path):
    config = spatial(20 * Q1)
    result = run(config, tmp_path)
    measured = check_fields(result, tmp_path, 3)
    assert measured[0][0] > 0
    check_surfaces(tmp_path, config, 3)
    assert (tmp_path / "deformed_shapes.png").stat().st_size > 10_000


FINGERS = {
    "planar": ("finger.toml", """
[[obstacles]]
shape = "cylinder"
name = "bottle"
point = [0.09, 0.032]
radius = 0.015
"""),
    "spatial": ("spatial_finger.toml", """
[[obstacles]]
shape = "sphere"
name = "ball"
center = [0.095, 0.008, 0.024]
radius = 0.0135

[[obstacles]]
shape = "plane"
name = "table"
point = [0.0, -0.03, 0.0]
normal = [0.0, 1.0, 0.0]
"""),
}


@pytest.mark.parametrize("kind", sorted(FINGERS))
def test_finger_with_obstacles_writes_fields_surfaces_and_backbone(tmp_path, kind):
    """The finger presses on the obstacle: beam.xdmf carries its gap and pressure,
    obstacles.vtu is written, the backbone figure (with the obstacles) is written."""
    from fe_beam.cli import main

    example, obstacles = FINGERS[kind]
    text = (EXAMPLES / example).read_text().replace("steps = 20", "steps = 8")
    config = tmp_path / "finger.toml"
    config.write_text(text.replace("elements = 40", "elements = 20") + obstacles)
    out = tmp_path / "out"
    code = main(["finger", str(config), "--out", str(out), "--quiet",
                 "--set", "output.plots=true"])
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    touched = summary["steps"][-1]["contact"][0]
    # it touches (the section's true shape, a 15 mm square: the ball is 3.5 mm larger than
    # for the tube of the circumradius, 10.6 mm)
    assert touched["pressure_peak"] > 0 or touched["end_forces"][1] > 0
    count = 1 if kind == "planar" else 2
    fields = last_fields(out)
    assert set(fields) == {f"contact_{k}_{i}" for k in ("gap", "pressure")
                           for i in range(count)}
    gap = fields["contact_gap_0"]
    # the default penetration tolerance: 1e-3 of the thinnest section height, >= 1e-5 m here
    assert abs(max(0.0, float(-np.min(gap))) - touched["max_penetration"]) <= 1e-5
    assert len(meshio.read(out / "obstacles.vtu").points) > 0
    assert (out / "fig3_9_backbone.png").stat().st_size > 10_000

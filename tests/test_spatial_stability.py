"""Lateral-torsional buckling of a spatial rod (issue 22): `fe-beam buckling` and the
bifurcation that `fe-beam path` locates, against Timoshenko & Gere's narrow cantilever under a
tip load at the centroid, P_cr = 4.0126 sqrt(E I_y G J) / L^2 (pre-buckling in-plane bending
neglected: exact as I_y / I_z -> 0; the observed excess scales as (b / h)^2)."""

import json
import math

import pytest
from tomlio import dump_toml

from fe_beam.cli import main
from fe_beam.model.sections import Section

E, NU, L, H = 2e11, 0.3, 1.0, 0.1
G = E / (2 * (1 + NU))


def config(b, elements=24, **tables):
    base = {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": b, "h": H},
        "material": {"E": E, "nu": NU},
        "model": {"kinematics": "spatial", "law": "reissner"},
        "mesh": {"elements": elements},
        "loads": {"tip_force": [0.0, -1000.0, 0.0]},
        "output": {"plots": False},
    }
    return base | tables


def timoshenko(b):
    p = Section("rectangle", {"b": b, "h": H}).spatial_properties()
    return 4.0126 * math.sqrt(E * p.Iy * G * p.J) / L**2


def run(tmp_path, command, data, name):
    path = tmp_path / f"{name}.toml"
    path.write_text(dump_toml(data))
    out = tmp_path / name
    assert main([command, str(path), "--out", str(out), "--quiet"]) == 0
    return json.loads((out / "summary.json").read_text())


def test_lateral_torsional_buckling_of_a_narrow_cantilever(tmp_path):
    ratios = {}
    for b in (0.005, 0.0025):
        summary = run(tmp_path, "buckling", config(b, buckling={"count": 1}), f"b{b}")
        critical = -summary["critical_loads"][0]["tip_force"][1]
        ratios[b] = critical / timoshenko(b)
    # within 0.1% for b/h = 0.025, and the excess of the pre-buckling bending ~ (b / h)^2
    assert ratios[0.0025] == pytest.approx(1.0, abs=1e-3)
    excess = [ratios[b] - 1 for b in (0.005, 0.0025)]
    assert excess[0] > 0 and excess[1] > 0
    assert math.log2(excess[0] / excess[1]) == pytest.approx(2.0, abs=0.1)


def test_path_bifurcation_is_the_buckling_load(tmp_path):
    """The arc-length path of the same cantilever branches at the buckling command's load."""
    buckling = run(tmp_path, "buckling", config(0.005, buckling={"count": 1}), "buckling")
    path = run(tmp_path, "path", config(0.005, path={"max_load_factor": 1.2,
                                                    "arc_length": 0.1}), "path")
    forks = [c for c in path["critical_points"] if c["kind"] == "bifurcation"]
    assert len(forks) == 1
    assert forks[0]["load_factor"] == pytest.approx(buckling["load_factors"][0], rel=3e-5)
    header = (tmp_path / "path" / "path.csv").read_text().splitlines()[0].split(",")
    assert "tip_w" in header and "tip_rotation_x" in header

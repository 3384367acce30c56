"""Contact with the edges and corners of a box (frictionless). The section-wise gap of a box is
the largest face-plane distance: exact on a face, but a rod pressed onto an edge or corner
would be pushed along a side face's normal (a spurious axial force that changes with the
mesh). Such a contact is refused (`fe_beam.fem.contact.box_edge_contact`): the load stepping
stops with exit 3, the last good state and a reason naming the box; never a converged step
with that force. A rod's tip resting on a box's top face (a face contact) still carries the
exact reaction.
"""

import json

import numpy as np
import pytest

from fe_beam.analyses.static import solve_static
from fe_beam.cli import main
from fe_beam.config.registry import validate
from fe_beam.fem.contact import box_edge_contact
from fe_beam.model.obstacles import Box

CORNER = """
[beam]
length = 1.0
[section]
shape = "rectangle"
b = 0.01
h = 0.01
[material]
E = 2e11
nu = 0.3
[model]
law = "nonstandard"
[mesh]
elements = 10
degree = 2
[loads]
tip_force = [0, -833.333]
steps = 10
[[obstacles]]
shape = "box"
name = "block"
center = [0.8, -0.2]
size = [0.1, 0.05]
[output]
xdmf = false
plots = false
"""


def run(tmp_path, text: str) -> tuple[int, dict]:
    path = tmp_path / "corner.toml"
    path.write_text(text)
    out = tmp_path / "out"
    code = main(["static", str(path), "--out", str(out), "--quiet"])
    return code, json.loads((out / "summary.json").read_text())


@pytest.mark.parametrize("spatial", [False, True])
def test_a_rod_pressed_onto_a_box_corner_stops_with_exit_3(tmp_path, spatial):
    """The reproduction of the defect: before, exit 0 with F = (784, 674) N (planar, 49
    degrees from vertical where the rod's normal is 22) or (3648, 0, 0) N (spatial)."""
    text = CORNER
    if spatial:
        text = (text.replace('law = "nonstandard"', 'law = "reissner"\nkinematics = "spatial"')
                .replace("[0, -833.333]", "[0, -833.333, 0]")
                .replace("[0.8, -0.2]", "[0.8, -0.2, 0.0]")
                .replace("[0.1, 0.05]", "[0.1, 0.05, 0.1]"))
    code, summary = run(tmp_path, text)
    assert code == 3
    assert summary["status"] == "failed"
    # refused as an edge contact, or (where the corner sits between two contact points, the
    # planar case) as an obstacle reaching into the rod between the contact points
    message = summary["message"]
    assert ("edge or corner of box 'block'" in message and "not be normal to the rod" in message
            or "'block' reaches" in message and "between the contact points" in message), message
    # the last good state: before the rod reached the corner
    assert summary["steps"][-1]["load_factor"] < 1.0
    assert all(max(abs(f) for f in step["contact"][0]["force"]) == 0.0
               for step in summary["steps"])


def test_edge_detection_flags_a_tilted_section_at_the_edge_only():
    box = Box(name="b", min=(0.0, -1.0), max=(1.0, 0.0))
    theta = np.radians(20.0)
    d = np.array([[-np.sin(-theta), np.cos(-theta)]] * 3)
    t = np.stack([d[:, 1], -d[:, 0]], axis=1)
    # sections whose lower end sits on the top face: mid-face, near the right edge; tilted
    r = np.array([[0.5, 0.0], [0.995, 0.0], [0.0, 0.0]]) + 0.005 * d
    flags, angles = box_edge_contact(box, r, t, 0.005, 0.005, d, spacing=0.001)
    assert flags.tolist() == [False, True, True]
    assert angles[0] == pytest.approx(20.0)
    # flat on the face near its edge: the force is normal to the rod: accepted
    flat_d, flat_t = np.array([[0.0, 1.0]]), np.array([[1.0, 0.0]])
    flags, _ = box_edge_contact(box, np.array([[0.995, 0.005]]), flat_t, 0.005, 0.005, flat_d,
                                spacing=0.001)
    assert not flags.any()
    # spatial: the tube across the top face's edge, tilted 20 degrees in the xy plane
    cube = Box(name="c", dim=3, min=(0.0, -1.0, -0.5), max=(1.0, 0.0, 0.5))
    tangent = np.array([[np.cos(theta), -np.sin(theta), 0.0]] * 2)
    flags, _ = box_edge_contact(cube, np.array([[0.5, 0.005, 0.0], [0.998, 0.005, 0.0]]),
                                tangent, 0.005, 0.005, spacing=0.001)
    assert flags.tolist() == [False, True]


L, B, H = 1.0, 0.01, 0.01
EI = 1.0
E = 12 * EI / (B * H**3)
GAP = 1e-3


def test_a_tip_resting_on_a_box_top_face_carries_the_exact_reaction():
    """Small deflection: the tip load P on a cantilever whose tip section touches the box's top
    face after a deflection GAP: the box carries R = P - 3 EI GAP / L^3 (tip contact), normal
    to the face."""
    touch = 3 * EI * GAP / L**3
    load = 2 * touch
    config = {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable"},
        "mesh": {"elements": 20, "degree": 2},
        "loads": {"tip_force": [0.0, -load], "steps": 2},
        "solver": {"atol": 1e-10},
        "obstacles": [{"shape": "box", "name": "block", "min": [0.8, -0.2],
                       "max": [1.2, -GAP - H / 2]}],
        "contact": {"penetration_tolerance": 1e-9},
        "output": {"xdmf": False, "plots": False},
    }
    result = solve_static(validate("static", config).parsed, None, progress=False,
                          record_shapes=False)
    assert result.status == "converged", result.message
    entry = result.steps[-1]["contact"][0]
    assert entry["force"][1] == pytest.approx(load - touch, rel=2e-3)
    assert abs(entry["force"][0]) < 1e-3 * entry["force"][1]

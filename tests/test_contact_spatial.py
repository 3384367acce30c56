"""Contact of the spatial rod (issue 23): the section is a tube of its circumradius about the
centreline. The planar small-deflection case (a cantilever under uniform q above a plane at
gap g: tip reaction R = 3 q L / 8 - 3 EI g / L^3 for q1 < q < 9 q1, q1 = 8 EI g / L^4) run as a
spatial rod with the plane and the load rotated about x by an angle: the same reaction as the
planar rod's, rotated. Every converged step keeps its penetration below the stated tolerance.
"""

import math

import numpy as np
import pytest

from fe_beam.analyses.static import solve_static
from fe_beam.config.registry import validate

L, D = 1.0, 0.01
EI = 1.0
E = EI / (math.pi * D**4 / 64)
GAP = 1e-4
Q1 = 8 * EI * GAP / L**4
TOLERANCE = 1e-11
ANGLE = 0.7


def cantilever(q: float, spatial: bool, angle: float = 0.0) -> dict:
    c, s = math.cos(angle), math.sin(angle)
    offset = GAP + D / 2
    if spatial:
        load = [0.0, -q * c, -q * s]
        plane = {"point": [0.0, -offset * c, -offset * s], "normal": [0.0, c, s]}
    else:
        load = [0.0, -q]
        plane = {"point": [0.0, -offset], "normal": [0.0, 1.0]}
    return {
        "beam": {"length": L},
        "section": {"shape": "circle", "d": D},
        "material": {"E": E, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable"}
        | ({"kinematics": "spatial"} if spatial else {}),
        "mesh": {"elements": 40, "degree": 2},
        "loads": {"distributed": load, "steps": 4},
        "solver": {"atol": 1e-12},
        "obstacles": [{"shape": "plane", "name": "floor", **plane}],
        "contact": {"penetration_tolerance": TOLERANCE},
        "output": {"xdmf": False, "plots": False},
    }


def final_contact(config: dict) -> dict:
    result = solve_static(validate("static", config).parsed, None, progress=False,
                          record_shapes=False)
    assert result.status == "converged", result.message
    for step in result.steps:
        for entry in step["contact"]:
            assert entry["max_penetration"] <= TOLERANCE, step
    return result.steps[-1]["contact"][0]


@pytest.mark.mpi
def test_spatial_cantilever_on_a_rotated_plane_matches_the_planar_reaction():
    q = 4 * Q1
    planar = final_contact(cantilever(q, spatial=False))
    reaction = 3 * q * L / 8 - 3 * EI * GAP / L**3
    assert planar["force"][1] == pytest.approx(reaction, rel=1e-3)
    spatial = final_contact(cantilever(q, spatial=True, angle=ANGLE))
    normal = np.array([0.0, math.cos(ANGLE), math.sin(ANGLE)])
    expected = planar["force"][1] * normal
    force = np.array(spatial["force"])
    error = np.abs(force - expected).max() / abs(planar["force"][1])
    # about the origin: the tip reaction at (L, 0, 0) gives L e1 x R n
    moment = np.array(spatial["moment"])
    expected_moment = np.cross([L, 0.0, 0.0], expected)
    moment_error = np.abs(moment - expected_moment).max() / abs(planar["moment"])
    print(f"spatial vs planar reaction: {error:.2e}, moment {moment_error:.2e}; planar vs "
          f"closed form {planar['force'][1] / reaction - 1:.2e}")
    assert error <= 1e-6
    assert moment_error <= 1e-6
    assert spatial["active"] == [[L, L]]
    assert spatial["end_forces"][1] == pytest.approx(planar["end_forces"][1], rel=1e-6)

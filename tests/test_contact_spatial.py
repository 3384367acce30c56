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
            # the solver's guarantee at the contact points (the whole surface may dip
            # deeper between them at a first touch: `max_penetration`, the certificate)
            assert entry["contact_point_penetration"] <= config["contact"][
                "penetration_tolerance"], step
    print("final whole-surface penetration", result.steps[-1]["contact"][0]["max_penetration"])
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


def test_spatial_rod_on_a_cylinder_along_a_coordinate_axis_matches_the_rotated_problem():
    """A cylinder whose axis is a coordinate axis (the vertical bottle of a grasp; once a
    code-generation failure of FFCx 0.5 on the literal zeros of the projected vector): the
    spatial rod under a tip force in the x-y plane pressed onto a cylinder along z gives the
    same contact force as the whole problem rotated by 0.7 rad about x (a generic axis), and
    the planar rod against the disc of the same radius to the sampling difference of the two
    contact models (the tube about the centreline vs the section segment: 0.9 % here)."""
    radius, centre = 0.05, (0.6, -0.05 - D / 2 - 2e-3)
    c, s = math.cos(ANGLE), math.sin(ANGLE)

    def config(spatial: bool, angle: float = 0.0) -> dict:
        c, s = math.cos(angle), math.sin(angle)
        rotate = (lambda v: [v[0], c * v[1] - s * v[2], s * v[1] + c * v[2]]) if spatial \
            else (lambda v: v[:2])
        config = cantilever(0.0, spatial)
        config["loads"] = {"tip_force": rotate([0.0, -20.0 * EI, 0.0]), "steps": 8}
        config["mesh"]["elements"] = 20
        config["contact"] = {"penetration_tolerance": 1e-7, "penalty": 10.0,
                             "max_updates": 200}
        config["obstacles"] = [{"shape": "cylinder", "name": "bottle", "radius": radius,
                                "point": rotate([centre[0], centre[1], 0.0]),
                                **({"axis": rotate([0.0, 0.0, 1.0])} if spatial else {})}]
        return config

    along_z = final_contact(config(True))
    rotated = final_contact(config(True, ANGLE))
    planar = final_contact(config(False))
    assert np.linalg.norm(along_z["force"]) > 1.0  # it presses
    back = [rotated["force"][0], c * rotated["force"][1] + s * rotated["force"][2],
            -s * rotated["force"][1] + c * rotated["force"][2]]
    assert along_z["force"] == pytest.approx(back, rel=1e-6, abs=1e-9)
    assert along_z["force"][2] == 0.0
    assert along_z["force"][:2] == pytest.approx(planar["force"], rel=1.5e-2)

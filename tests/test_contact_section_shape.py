"""Spatial contact with the section's true shape (issue 28, item 4): the gap of a rectangle to
a plane is its nearest corner (the support function in the current directors d2, d3), the
distance to a sphere or an infinite cylinder is that of the section rectangle, the end faces
are flat. The numpy twin `section_distance` against brute-force sampling of the section;
the configuration check accepts an obstacle just beyond the flat end; a planar problem run
as a spatial rod gives the planar contact force."""

import math

import numpy as np
import pytest

from fe_beam.errors import ConfigError
from fe_beam.model.obstacles import (
    Box,
    Cylinder,
    Plane,
    Sphere,
    check_clear_of_rod,
    distance,
    section_distance,
    section_parts,
)
from fe_beam.model.sections import Section


def _frame(angles):
    """An orthonormal frame (d1, d2, d3) from three rotation angles (x, then y, then z)."""
    a, b, c = angles
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rz = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
    R = rz @ ry @ rx
    return R[:, 0], R[:, 1], R[:, 2]


def _sampled(obstacle, r, d2, d3, b, h, count=401):
    """min of the signed distance over a dense grid of the section rectangle h x b."""
    s, t = np.meshgrid(np.linspace(-h / 2, h / 2, count), np.linspace(-b / 2, b / 2, count))
    points = r + s.reshape(-1, 1) * d2 + t.reshape(-1, 1) * d3
    return float(np.min(distance(obstacle, points)))


B, H = 0.013, 0.007  # a rectangle not square, b along d3, h along d2
RECTANGLE = Section("rectangle", {"b": B, "h": H})


@pytest.mark.parametrize("angles", [(0.3, -0.4, 1.1), (1.2, 0.2, -0.7), (0.0, 0.0, 0.25)])
def test_rotated_rectangle_gap_to_a_plane_is_its_nearest_corner(angles):
    d1, d2, d3 = _frame(angles)
    normal = np.array([0.2, 0.9, -0.4])
    normal /= np.linalg.norm(normal)
    plane = Plane(point=(0.1, -0.02, 0.03), normal=tuple(normal), dim=3)
    r = np.array([[0.3, 0.01, -0.005]])
    gap = section_distance(plane, r, d1, d2, d3, section_parts(RECTANGLE, 0.0))[0]
    corners = [r[0] + s * H / 2 * d2 + t * B / 2 * d3 for s in (-1, 1) for t in (-1, 1)]
    nearest = min(float(distance(plane, c[None])[0]) for c in corners)
    assert gap == pytest.approx(nearest, rel=1e-13, abs=1e-16)
    # not the tube of the circumradius: the corner formula differs from it here
    tube = float(distance(plane, r)[0]) - math.hypot(B, H) / 2
    assert gap - tube > 1e-4


@pytest.mark.parametrize("obstacle", [
    Sphere(center=(0.31, 0.024, 0.006), radius=0.012, dim=3),
    Cylinder(point=(0.29, 0.03, 0.0), radius=0.015, axis=(0.3, -0.2, 1.0), dim=3),
    Cylinder(point=(0.3, 0.0, 0.0), radius=0.002, axis=(1.0, 0.4, 0.1), dim=3),  # pierces
    Box(min=(0.28, 0.012, -0.05), max=(0.4, 0.05, 0.05), dim=3),
])
def test_rotated_rectangle_distance_to_sphere_cylinder_box_is_the_sampled_minimum(obstacle):
    d1, d2, d3 = _frame((0.5, -0.3, 0.8))
    r = np.array([0.3, 0.0, 0.0])
    gap = section_distance(obstacle, r[None], d1, d2, d3, section_parts(RECTANGLE, 0.0))[0]
    sampled = _sampled(obstacle, r, d2, d3, B, H)
    if isinstance(obstacle, Box):  # the largest face-plane distance: conservative
        assert gap <= sampled + 1e-12
        return
    # exact: the sampled minimum is above it by at most the grid's resolution
    assert sampled - 2e-5 <= gap <= sampled + 1e-12


def test_obstacle_just_beyond_the_flat_end_is_accepted():
    """A wall 2 mm beyond the end face of a thick rectangular rod (the tube of its
    circumradius, 11 mm, would reach through it) is clear; a wall 2 mm inside is refused,
    naming the section's extent."""
    section = Section("rectangle", {"b": 0.02, "h": 0.012})
    length = 0.3
    wall = Plane(point=(length + 0.002, 0.0, 0.0), normal=(-1.0, 0.0, 0.0), dim=3)
    check_clear_of_rod(wall, section, length)
    ball = Sphere(center=(length + 0.004, 0.009, 0.0), radius=0.003, dim=3)  # off the corner
    check_clear_of_rod(ball, section, length)
    inside = Plane(point=(length - 0.002, 0.0, 0.0), normal=(-1.0, 0.0, 0.0), dim=3)
    with pytest.raises(ConfigError, match="0.02 x 0.012 m"):
        check_clear_of_rod(inside, section, length)
    side = Plane(point=(0.0, -0.0059, 0.0), normal=(0.0, 1.0, 0.0), dim=3)
    with pytest.raises(ConfigError, match="intersects"):
        check_clear_of_rod(side, section, length)
    check_clear_of_rod(Plane(point=(0.0, -0.0061, 0.0), normal=(0.0, 1.0, 0.0), dim=3),
                       section, length)


def test_touching_obstacle_is_not_minus_zero_inside():
    section = Section("rectangle", {"b": 0.02, "h": 0.01})
    touching = Plane(point=(0.0, 0.005, 0.0), normal=(0.0, -1.0, 0.0), dim=3)
    with pytest.raises(ConfigError, match="touches the undeformed rod") as error:
        check_clear_of_rod(touching, section, 0.3)
    assert "-0 m" not in str(error.value)


# --- planar problems run as spatial rods ---------------------------------------------------------
def _cantilever(spatial: bool, obstacle: dict, section: dict, force: float) -> dict:
    return {
        "beam": {"length": 1.0},
        "section": section,
        "material": {"E": 2e9, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "none"}
        | ({"kinematics": "spatial"} if spatial else {}),
        "mesh": {"elements": 12, "degree": 2},
        "loads": {"tip_force": [0.0, -force] + ([0.0] if spatial else []), "steps": 4},
        "solver": {"atol": 1e-12},
        "obstacles": [obstacle | (
            {"point": obstacle["point"] + [0.0]} if spatial and "point" in obstacle else {})
            | ({"center": obstacle["center"] + [0.0]} if spatial and "center" in obstacle
               else {})
            | ({"normal": obstacle["normal"] + [0.0]} if spatial and "normal" in obstacle
               else {})
            | ({"axis": [0.0, 0.0, 1.0]} if spatial and obstacle["shape"] == "cylinder"
               else {})],
        "contact": {"penetration_tolerance": 1e-9, "max_updates": 200},
        "output": {"xdmf": False, "plots": False},
    }


def _contact(config: dict) -> dict:
    from fe_beam.analyses.static import solve_static
    from fe_beam.config.registry import validate

    result = solve_static(validate("static", config).parsed, None, progress=False,
                          record_shapes=False)
    assert result.status == "converged", result.message
    return result.steps[-1]["contact"][0]


# a rectangle 30 x 6 mm (b along z, h along y: the tube of its circumradius, 15.3 mm, would
# touch 12 mm early); a tilted floor under the tip (the corner of the end face touches), a
# disc (cylinder along z) and a ball under the span
SECTION = {"shape": "rectangle", "b": 0.03, "h": 0.006}
CASES = {
    "tilted plane": {"shape": "plane", "name": "floor", "point": [1.0, -0.02],
                     "normal": [-0.02, 1.0]},
    "cylinder": {"shape": "cylinder", "name": "bottle", "point": [0.7, -0.043], "radius": 0.035},
    "sphere": {"shape": "sphere", "name": "ball", "center": [0.6, -0.06], "radius": 0.05},
}


@pytest.mark.parametrize("case", list(CASES))
def test_planar_problem_run_as_spatial_gives_the_planar_contact_force(case):
    obstacle = CASES[case]
    planar = _contact(_cantilever(False, obstacle, SECTION, 0.15))
    spatial = _contact(_cantilever(True, obstacle, SECTION, 0.15))
    assert math.hypot(*planar["force"]) > 0.01  # it presses
    print(case, planar["force"], spatial["force"])
    assert spatial["force"][:2] == pytest.approx(planar["force"], rel=1e-6, abs=1e-9)
    assert abs(spatial["force"][2]) <= 1e-9 * math.hypot(*planar["force"])
    assert spatial["end_forces"] == pytest.approx(planar["end_forces"], rel=1e-6, abs=1e-9)


# --- the contact certificates (issue 28, section 1) ----------------------------------------------
def test_contact_certificates_pass_and_fail_on_purpose(monkeypatch, tmp_path):
    """surface_penetration and contact_force_balance are in the summary of a spatial rod's
    static run and pass; a penetration beyond the tolerance found between the contact points
    (the certificate's quantity scaled on purpose) or a force that does not balance the
    pressures turn the run "failed" (strict) and stay visible (lenient)."""
    import fe_beam
    from fe_beam.fem.contact import ContactSet

    config = _cantilever(True, CASES["tilted plane"], SECTION, 0.15)
    summary = fe_beam.run("static", config, tmp_path / "pass")
    checks = {c["name"]: c for c in summary["checks"]}
    assert summary["status"] == "converged"
    assert checks["surface_penetration"]["passed"] and checks["contact_force_balance"]["passed"]
    # the configured 1e-9 holds at the contact points; the whole surface is certified to
    # the default 1e-3 of the section (6 um), and here it is within the configured one
    assert checks["surface_penetration"]["tolerance"] == pytest.approx(6e-6)
    assert checks["surface_penetration"]["value"] <= 1e-9
    assert checks["contact_force_balance"]["value"] <= 1e-9
    original = ContactSet.surface

    def broken(add_depth, add_balance):
        def surface(self, state=None):
            return [dict(c, penetration=c["penetration"] + add_depth,
                         balance=c["balance"] + add_balance) for c in original(self, state)]
        return surface

    monkeypatch.setattr(ContactSet, "surface", broken(1e-5, 0.0))
    summary = fe_beam.run("static", config, tmp_path / "deep")
    assert summary["status"] == "failed" and "surface_penetration" in summary["message"]
    monkeypatch.setattr(ContactSet, "surface", broken(0.0, 1e-3))
    summary = fe_beam.run("static", config, tmp_path / "force")
    assert summary["status"] == "failed" and "contact_force_balance" in summary["message"]
    summary = fe_beam.run("static", config, tmp_path / "lenient", **{"checks.strict": False})
    assert summary["status"] == "converged" and summary["checks_passed"] is False


def _finger(spatial: bool) -> dict:
    three = [0.0] if spatial else []
    return {
        "beam": {"length": 0.08},
        "section": {"shape": "rectangle", "b": 0.008, "h": 0.018, "h_tip": 0.009},
        "material": {"E": 1.2e6, "nu": 0.45},
        "model": {"law": "nonstandard"} | ({"kinematics": "spatial"} if spatial else {}),
        "mesh": {"elements": 8, "degree": 2},
        "tendons": [{"name": "flexor", "offset_base": 0.007, "offset_tip": 0.003,
                     "tension": 3.0}],
        "loads": {"steps": 6},
        "obstacles": [{"shape": "plane", "name": "ceiling", "point": [0.0, 0.013] + three,
                       "normal": [0.0, -1.0] + three}],
        "contact": {"penetration_tolerance": 1e-9},
        "output": {"xdmf": False, "plots": False},
    }


def test_tapered_finger_under_a_ceiling_spatial_equals_planar(tmp_path):
    """A tendon finger (tapered rectangle 8 mm wide, 18 -> 9 mm high) bending into a ceiling:
    the spatial rod presses with the planar rod's force (the tube of the circumradius, 9.8 mm
    against h/2 = 9 mm at the base, pressed harder), and its summary carries the checks."""
    import fe_beam

    planar = fe_beam.run("finger", _finger(False), tmp_path / "planar")
    spatial = fe_beam.run("finger", _finger(True), tmp_path / "spatial")
    assert planar["status"] == spatial["status"] == "converged", spatial["message"]
    force = planar["steps"][-1]["contact"][0]["force"]
    assert abs(force[1]) > 0.05
    assert spatial["steps"][-1]["contact"][0]["force"][:2] == pytest.approx(force, rel=1e-6,
                                                                             abs=1e-12)
    for summary in (planar, spatial):
        names = {c["name"]: c["passed"] for c in summary["checks"]}
        assert names["surface_penetration"] and names["contact_force_balance"]


@pytest.mark.parametrize("obstacle", [
    Plane(point=(0.0, -0.03, 0.01), normal=(0.3, 1.0, -0.5), dim=3),
    Sphere(center=(0.31, 0.03, 0.004), radius=0.01, dim=3),
    Cylinder(point=(0.29, -0.035, 0.0), radius=0.02, axis=(0.2, 0.1, 1.0), dim=3),
])
def test_t_section_and_disc_against_sampling(obstacle):
    """A T-section (web and flange rectangles about the centroid) and a disc (circle section:
    exact on planes and spheres; its tube on a cylinder, a lower bound) against the sampled
    minimum over the rotated section."""
    d1, d2, d3 = _frame((0.4, 0.3, -0.6))
    r = np.array([0.3, 0.0, 0.0])
    tee = Section("t-section", {"b": 0.03, "h": 0.024, "tf": 0.004, "tw": 0.006})
    parts = section_parts(tee, 0.0)
    gap = section_distance(obstacle, r[None], d1, d2, d3, parts)[0]
    sampled = min(_sampled(obstacle, r + offset * d2, d2, d3, 2 * a3, 2 * a2, count=201)
                  for offset, a2, a3 in parts["rectangles"])
    assert sampled - 3e-5 <= gap <= sampled + 1e-12
    disc = section_distance(obstacle, r[None], d1, d2, d3, {"disc": 0.01})[0]
    phi, rho = np.meshgrid(np.linspace(0, 2 * np.pi, 721), np.linspace(0, 0.01, 101))
    points = (r + (rho * np.cos(phi)).reshape(-1, 1) * d2
              + (rho * np.sin(phi)).reshape(-1, 1) * d3)
    sampled = float(np.min(distance(obstacle, points)))
    if isinstance(obstacle, Cylinder):
        assert disc <= sampled + 1e-12
    else:
        assert sampled - 2e-5 <= disc <= sampled + 1e-12

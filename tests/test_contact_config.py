"""[[obstacles]] and [contact]: every mistake exits 2 with one sentence naming the key."""

import pytest
from test_config import BASE, run_cli, usage_error

from fe_beam.config.registry import validate

FLOOR = {"shape": "plane", "point": [0.0, -0.01], "normal": [0.0, 1.0]}


def with_obstacles(*obstacles, **tables):
    return {**BASE, "obstacles": list(obstacles), **tables}


@pytest.mark.parametrize("obstacle, words", [
    ({**FLOOR, "normal": [0.0, 0.0]}, ("normal", "zero vector")),
    ({"shape": "sphere", "center": [0.5, 1.0], "radius": -0.1}, ("radius", "> 0")),
    ({"shape": "cylinder", "point": [0.5, 1.0], "radius": 0.0}, ("radius", "> 0")),
    ({"shape": "blob", "point": [0.0, 1.0]}, ("shape", "plane, cylinder, sphere, box")),
    ({**FLOOR, "point": [0.0, -0.01, 0.0]}, ("point", "2 numbers")),
    ({**FLOOR, "point": [0.0, -0.001]}, ("intersects the undeformed rod", "x = ")),
    ({"shape": "sphere", "center": [0.5, 0.009], "radius": 0.004}, ("intersects",)),
    ({"shape": "box", "min": [0.2, -0.1], "max": [0.3, 0.2]}, ("intersects",)),
    ({"shape": "box", "min": [0.2, -0.1], "max": [0.3, -0.2]}, ("max must exceed min",)),
    ({"shape": "box", "min": [0.2, -0.1]}, ("max", "go together")),
    ({**FLOOR, "radius": 1.0}, ("radius", "does not apply")),
    ({**FLOOR, "colour": "red"}, ("unknown key", "colour")),
    ({"shape": "plane", "point": [0.0, -1.0]}, ("needs normal",)),
    ({**FLOOR, "friction": -0.1}, ("friction", ">= 0")),
    ({**FLOOR, "friction": "high"}, ("friction",)),
])
def test_bad_obstacle_exits_2(tmp_path, capsys, obstacle, words):
    code, err, out, path = run_cli(tmp_path, with_obstacles(obstacle), capsys=capsys)
    message = usage_error(code, err, path)
    assert "[[obstacles]]" in message, message
    for word in words:
        assert word in message, message
    assert not (out / "summary.json").exists()


@pytest.mark.parametrize("contact, key", [
    ({"penetration_tolerance": -1.0}, "penetration_tolerance"),
    ({"penalty": 0.0}, "penalty"),
    ({"penalty": 1e12}, "at most 1e+06"),
    ({"penetration_tolerance": 1.0}, "more than a tenth of its thinnest section"),
    ({"force_tolerance": 0.0}, "force_tolerance"),
    ({"force_tolerance": 2.0}, "force_tolerance"),
    ({"max_updates": 0}, "max_updates"),
    ({"typo": 1}, "typo"),
])
def test_bad_contact_settings_exit_2(tmp_path, capsys, contact, key):
    code, err, _, path = run_cli(tmp_path, with_obstacles(FLOOR, contact=contact),
                                 capsys=capsys)
    assert key in usage_error(code, err, path)


def test_contact_without_obstacles_and_obstacles_as_one_table(tmp_path, capsys):
    code, err, _, path = run_cli(tmp_path, {**BASE, "contact": {"penalty": 1.0}}, capsys=capsys)
    assert "no [[obstacles]]" in usage_error(code, err, path)
    code, err, _, path = run_cli(tmp_path, {**BASE, "obstacles": FLOOR}, capsys=capsys)
    assert "double brackets" in usage_error(code, err, path)


def test_obstacles_parsed_in_order_with_defaults():
    parsed = validate("static", with_obstacles(
        FLOOR, {"shape": "box", "name": "plate", "center": [0.5, 0.5], "size": [0.2, 0.1]},
        {"shape": "cylinder", "point": [0.5, 1.0], "radius": 0.2})).parsed
    names = [o.name for o in parsed.obstacles]
    assert names == ["obstacle1", "plate", "obstacle3"]
    plate = parsed.obstacles[1]
    assert plate.min == pytest.approx((0.4, 0.45)) and plate.max == pytest.approx((0.6, 0.55))
    assert parsed.contact.penalty == 1.0
    # default tolerance: 1e-3 of the section height
    assert parsed.contact.tolerance(parsed.model.section) == pytest.approx(1e-5)


def test_a_command_that_ignores_obstacles_refuses_them():
    from fe_beam.config.registry import check_command_tables
    from fe_beam.errors import ConfigError

    with pytest.raises(ConfigError, match=r"does not use \[\[obstacles\]\]"):
        check_command_tables("modes", with_obstacles(FLOOR))
    assert check_command_tables("static", with_obstacles(FLOOR)) == []
    assert check_command_tables("dynamic", with_obstacles(FLOOR)) == []


SPATIAL = {**BASE, "model": {"kinematics": "spatial", "law": "reissner", "constraint": "none"},
           "loads": {"tip_force": [0.0, -1.0, 0.0], "steps": 2}}
SPATIAL_FLOOR = {"shape": "plane", "point": [0.0, -0.01, 0.0], "normal": [0.0, 1.0, 0.0]}


@pytest.mark.parametrize("obstacle, words", [
    ({"shape": "sphere", "center": [0.5, 0.3, 0.0], "radius": 0.1, "friction": 0.3},
     ("friction", "plane or an infinite cylinder")),
    (FLOOR, ("point", "3 numbers")),
    # the section's flat face (h/2 = 0.005 m) reaches y = -0.005; the refusal names it
    ({**SPATIAL_FLOOR, "point": [0.0, -0.0049, 0.0]}, ("intersects the undeformed rod",
                                                       "0.01 x 0.01 m")),
    ({"shape": "cylinder", "point": [0.5, 0.0, 0.0], "radius": 0.1, "axis": [0, 0, 1],
      "length": 0.2}, ("intersects",)),
    ({"shape": "cylinder", "point": [0.5, 0.3, 0.0], "radius": 0.1, "axis": [0, 0, 0]},
     ("axis", "zero vector")),
])
def test_bad_spatial_obstacle_exits_2(tmp_path, capsys, obstacle, words):
    code, err, _, path = run_cli(tmp_path, {**SPATIAL, "obstacles": [obstacle]}, capsys=capsys)
    message = usage_error(code, err, path)
    for word in words:
        assert word in message, message


def test_spatial_obstacles_parse_in_3d():
    parsed = validate("static", {**SPATIAL, "obstacles": [
        {**SPATIAL_FLOOR, "point": [0.0, -0.0075, 0.0]},
        # a short cylinder beside the rod, clear of it though its infinite axis line is not
        {"shape": "cylinder", "point": [0.5, 0.2, 0.0], "radius": 0.05, "axis": [0, 1, 0],
         "length": 0.1}]}).parsed
    floor, post = parsed.obstacles
    assert floor.dim == 3 and post.length == 0.1 and post.axis == (0.0, 1.0, 0.0)


def test_finite_cylinder_distance():
    import numpy as np

    from fe_beam.model.obstacles import Cylinder, distance

    post = Cylinder(dim=3, point=(0.0, 0.0, 0.0), radius=1.0, axis=(0, 0, 1), length=2.0)
    points = np.array([[2.0, 0, 0], [0, 0, 3.0], [2.0, 0, 3.0], [0.5, 0, 0], [0, 0, 0.5]])
    assert distance(post, points) == pytest.approx([1.0, 2.0, 5**0.5, -0.5, -0.5])


@pytest.mark.parametrize("section, obstacle, words", [
    # a floor exactly at the lower face of a 6 mm high strip: it touches (was: "its surface
    # is -0 m inside"), and the message names the section's extent it used
    ({"shape": "rectangle", "b": 0.02, "h": 0.006}, {**FLOOR, "point": [0.0, -0.003]},
     ("touches the undeformed rod", "the section reaching from y = -0.003 to 0.003 m")),
    # a T-section (flange on top): its centroid lies (0.016 * 0.004 * 0.008 + 0.02 * 0.004 *
    # 0.018) / 1.44e-4 = 0.013556 m above the web's foot, 0.006444 m below the flange's top
    ({"shape": "t-section", "b": 0.02, "h": 0.02, "tf": 0.004, "tw": 0.004},
     {**FLOOR, "point": [0.0, -0.006]},
     ("intersects the undeformed rod", "0.007556 m inside the obstacle",
      "from y = -0.01356 to 0.006444 m")),
])
def test_obstacle_on_the_undeformed_rod_names_the_section_extent(tmp_path, capsys, section,
                                                                  obstacle, words):
    code, err, _, path = run_cli(tmp_path, {**with_obstacles(obstacle), "section": section},
                                 capsys=capsys)
    message = usage_error(code, err, path)
    for word in words:
        assert word in message, message
    assert "-0 m" not in message and "is -" not in message, message


def test_spatial_obstacle_on_the_rod_names_the_section(tmp_path, capsys):
    """The spatial refusal names the extent it used: the section's true shape (a 6 x 16 mm
    rectangle, h = 16 mm along y: its flat face at y = -0.008; the tube of its circumradius,
    0.008544 m, was used until issue 28)."""
    floor = {**SPATIAL_FLOOR, "point": [0.0, -0.0075, 0.0]}
    config = {**SPATIAL, "section": {"shape": "rectangle", "b": 0.006, "h": 0.016},
              "obstacles": [floor]}
    code, err, _, path = run_cli(tmp_path, config, capsys=capsys)
    message = usage_error(code, err, path)
    assert "the rectangle 0.006 x 0.016 m (b x h)" in message, message
    assert "0.0005 m inside" in message, message

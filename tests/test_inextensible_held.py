"""A straight inextensible rod whose supports hold u at both ends (issue 28, small items): the
supports fix the length the constraint fixes, so the rod cannot bend; it failed at the first
increment (DIVERGED_LINEAR_SOLVE) or, with MUMPS's null pivots, returned an arbitrary axial
force with exit 0. It is refused up front (exit 2, one sentence); the cases that can deform
(one end free axially, a curved rod, a prescribed shortening, no inextensibility) are not."""

from __future__ import annotations

import copy

import pytest

from fe_beam.cli import main
from fe_beam.config.schema import parse_static
from fe_beam.errors import ConfigError


def _config(kinematics: str, constraint: str, x0, xL, loads: dict) -> dict:
    return {
        "beam": {"length": 0.7},
        "section": {"shape": "circle", "d": 0.004} if kinematics == "spatial" else
        {"shape": "rectangle", "b": 0.02, "h": 0.003},
        "material": {"E": 7.0e10, "nu": 0.33},
        "model": {"kinematics": kinematics, "law": "nonstandard", "constraint": constraint},
        "mesh": {"elements": 4},
        "supports": {"x0": x0, "xL": xL},
        "loads": loads,
    }


HELD = [
    ("planar", "inextensible", "pinned", "pinned", {"point_forces": [[0.3, 0.0, -2.0]]}),
    ("planar", "inextensible-unshearable", "clamped", ["u", "v"],
     {"distributed": [0.0, 5.0]}),
    ("spatial", "inextensible", "clamped", "pinned", {"distributed": [0.0, 0.0, -3.0]}),
    ("spatial", "inextensible-unshearable", "pinned", ["u", "v", "w", "theta_x"],
     {"point_moments": [[0.35, 0.2, 0.0, 0.0]]}),
]


@pytest.mark.parametrize("case", HELD, ids=lambda c: f"{c[0]}-{c[1]}-{c[3]}")
def test_held_length_is_refused(case):
    with pytest.raises(ConfigError, match=r"straight inextensible rod held along its axis at "
                       r"both ends.*free u at one end"):
        parse_static(_config(*case))


@pytest.mark.parametrize("case", [
    # one end free along the axis: the rod can bend
    ("planar", "inextensible", "pinned", "roller", {"point_forces": [[0.3, 0.0, -2.0]]}),
    ("spatial", "inextensible", "clamped", ["v", "w"], {"distributed": [0.0, 0.0, -3.0]}),
    # no inextensibility: the axial strain takes the length change
    ("planar", "unshearable", "clamped", "clamped", {"distributed": [0.0, 5.0]}),
    ("spatial", "none", "clamped", "clamped", {"distributed": [0.0, 0.0, -3.0]}),
], ids=lambda c: f"{c[0]}-{c[1]}-{c[3]}")
def test_rods_that_can_deform_are_accepted(case):
    parse_static(_config(*case))


def test_curved_rod_and_prescribed_shortening_are_accepted():
    arch = _config("spatial", "inextensible", "clamped", "clamped",
                   {"distributed": [0.0, -3.0, 0.0]})
    arch["beam"]["initial_curvature"] = [0.0, 0.0, 1.5]
    parse_static(arch)
    shortened = _config("planar", "inextensible", "clamped", ["theta"],
                        {"end_displacement": [-0.01, 0.0]})
    parse_static(shortened)


def test_held_length_exits_2_through_the_cli(tmp_path, capsys):
    config = copy.deepcopy(_config(*HELD[2]))
    lines = []
    for name, values in config.items():
        lines.append(f"[{name}]")
        lines += [f"{key} = {value!r}".replace("'", '"') for key, value in values.items()]
    path = tmp_path / "held.toml"
    path.write_text("\n".join(lines) + "\n")
    assert main(["static", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    assert "free u at one end" in capsys.readouterr().err

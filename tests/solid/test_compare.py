"""``fe-beam compare``: configuration mistakes (exit code 2), the departure measure, and a coarse
tension sweep of the finger (3D solid vs the rod with the non-standard and Reissner laws)."""

import csv
import json

import numpy as np
import pytest
from test_solid_driver import DROP, FINGER, assert_usage_error, edited, run_cli, shared_folder

from fe_beam.analyses.compare import RODS, crossing, matched_law, parse_compare, rod_at

SWEEP = edited(FINGER, {"compare": {"tensions": [1.0, 2.0]}})

BAD = [
    ({"compare.tensions": [2.0, 1.0]}, "[compare] tensions"),
    ({"compare.tensions": [0.0, 1.0]}, "[compare] tensions"),
    ({"compare.tensions": []}, "[compare] tensions"),
    ({"compare.tensions": ["one"]}, "[compare] tensions"),
    ({"compare.tensions": 2.0}, "[compare] tensions"),
    ({"compare.steps": 3}, "[compare] give one of"),
    ({"compare.tensions": DROP, "compare.load_factors": [0.5, 1.5]}, "[compare] load_factors"),
    ({"compare.tensions": DROP, "compare.steps": 0}, "[compare] steps"),
    ({"compare.laws": ["euler"]}, "[compare] laws"),
    ({"compare.laws": []}, "[compare] laws"),
    ({"compare.laws": ["reissner", "reissner"]}, "[compare] laws"),
    ({"compare.tension": [1.0]}, "tension"),
    ({"tendons.tension": DROP, "tendons.pull_in": 0.001}, "tension-controlled"),
    ({"tendons": [FINGER["tendons"][0], dict(FINGER["tendons"][0], name="second")]},
     "exactly one"),
    ({"tendons": DROP}, "[[tendons]]"),
    ({"compare.tensions": DROP, "loads.tip_force": [0.0, 0.1, 0.1]}, "planar"),
    ({"solid.order": 4}, "[solid] order"),
]


@pytest.mark.parametrize("changes, fragment", BAD, ids=[str(i) for i in range(len(BAD))])
def test_config_mistake_exits_2_naming_the_key(tmp_path, changes, fragment):
    code, _, stderr, out = run_cli("compare", shared_folder(tmp_path), edited(SWEEP, changes))
    assert_usage_error(code, stderr, "compare", fragment)
    assert not (out / "summary.json").exists()


def test_sweep_definitions():
    by_tension = parse_compare(edited(SWEEP, {"compare.tensions": [0.5, 1.0, 4.0]}))
    assert by_tension.load_factors == pytest.approx((0.125, 0.25, 1.0))
    assert by_tension.solid.tendon_loads[0].tension == 4.0 and by_tension.tension_axis
    by_steps = parse_compare(edited(SWEEP, {"compare": {"steps": 4, "laws": ["reissner"]}}))
    assert by_steps.load_factors == pytest.approx((0.25, 0.5, 0.75, 1.0))
    assert by_steps.laws == ("reissner",) and by_steps.solid.tendon_loads[0].tension == 2.0
    default = parse_compare(edited(SWEEP, {"compare": {}}))
    assert default.load_factors == pytest.approx((0.2, 0.4, 0.6, 0.8, 1.0))
    scaled = rod_at(default.solid.rod, "reissner", 0.25)
    assert scaled.model.options.law == "reissner" and scaled.tendons[0].tension == 0.5


@pytest.mark.parametrize("formulation, volumetric", [("displacement", "simo_taylor"),
                                                     ("mixed-up", "quadratic")])
def test_hyperelastic_rod_is_the_solid_material(formulation, volumetric):
    """By default the rods include the section law of the solid's own material: the same law
    and constants, and the volumetric energy of the solid's formulation (u-p: quadratic)."""
    config = parse_compare(edited(SWEEP, {"solid.formulation": formulation,
                                          "solid.material": "yeoh", "solid.c20": 2e4}))
    assert config.laws == RODS == ("hyperelastic", "nonstandard", "reissner")
    solid_law = config.solid.material
    rod = rod_at(config.solid.rod, "hyperelastic", 0.5, config.solid)
    law = rod.model.options.hyperelastic
    assert rod.model.options.law == "hyperelastic" and law == matched_law(config.solid)
    assert law.name == solid_law.name == "yeoh" and law.volumetric == volumetric
    assert law.coefficients() == solid_law.coefficients()
    assert law.coefficients()["c20"] == 2e4
    # the rod's E and G are the law's small-strain ones (BeamModel refuses anything else)
    assert rod.model.material.E == pytest.approx(law.young_modulus, rel=1e-12)
    assert rod.tendons[0].tension == pytest.approx(1.0)


def test_svk_solid_hyperelastic_rod_equals_the_non_standard_rod(tmp_path):
    """The section law of an SVK solid is the non-standard law: identical rods in compare."""
    config = edited(SWEEP, {"solid.material": "svk", "compare.tensions": [2.0],
                            "compare.laws": ["hyperelastic", "nonstandard"],
                            "output.xdmf": False, "output.plots": False})
    code, _, stderr, out = run_cli("compare", shared_folder(tmp_path), config)
    assert code == 0, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["model"]["rod"]["hyperelastic"]["material"] == "svk"
    row = summary["table"][-1]["rod"]
    for key in ("u", "v", "theta"):
        a, b = row["hyperelastic"]["tip"][key], row["nonstandard"]["tip"][key]
        assert abs(a - b) <= 1e-10 * 0.1, (key, a, b)
    assert row["hyperelastic"]["distance_over_L"] == pytest.approx(
        row["nonstandard"]["distance_over_L"], rel=1e-8)


def test_crossing_interpolates_from_the_unloaded_state():
    assert crossing([0.5, 1.0], [0.004, 0.02], 0.01) == {
        "load_factor": pytest.approx(0.5 + 0.5 * 0.006 / 0.016), "first_sweep_point_above": 1.0}
    assert crossing([0.5, 1.0], [0.02, 0.03], 0.01)["load_factor"] == pytest.approx(0.25)
    assert crossing([0.5, 1.0], [0.002, 0.004], 0.01) is None
    assert crossing([0.5, 1.0], [None, 0.03], 0.01)["load_factor"] == 1.0


@pytest.fixture(scope="module")
def sweep_run(tmp_path_factory):
    folder = shared_folder(tmp_path_factory.mktemp("sweep"))
    code, _, stderr, out = run_cli("compare", folder, SWEEP)
    assert code == 0, stderr
    return out, json.loads((out / "summary.json").read_text())


def test_table_and_departures(sweep_run):
    out, summary = sweep_run
    assert summary["status"] == "converged" and summary["dofs"] > 0
    rows = summary["table"]
    assert [r["tension"] for r in rows] == pytest.approx([1.0, 2.0])
    for row in rows:
        assert set(row["solid"]["tip"]) == {"u", "v", "theta", "w", "R", "rotation_vector"}
        for law in ("nonstandard", "reissner"):
            rod = row["rod"][law]
            assert rod["status"] == "converged"
            assert set(rod["tip"]) == {"u", "v", "theta"}
            assert 0 < rod["distance_over_L"] < 0.05, (row["tension"], law)
    for law in ("nonstandard", "reissner"):
        d = [r["rod"][law]["distance_over_L"] for r in rows]
        print(f"{law}: max_x |r_rod - r_solid| / L = {d} at tensions 1, 2 N")
        assert d[0] < d[1]  # the rods depart from the solid as the finger bends more
        entry = summary["departures"][law]
        assert entry["max_distance_over_L"] == pytest.approx(max(d))
        assert {"above_1_percent", "above_5_percent", "statement"} <= set(entry)
        above = entry["above_1_percent"]
        if max(d) > 0.01:
            assert 0 < above["tension"] <= 2.0
        else:
            assert above is None
        assert entry["above_5_percent"] is None  # max d < 5 % (checked above)
        assert law in entry["statement"]
    # the default rods include the section law of the solid's material (neo-Hookean, u-p not
    # given: displacement formulation, simo_taylor)
    assert summary["laws"] == ["hyperelastic", "nonstandard", "reissner"]
    hyper = summary["model"]["rod"]["hyperelastic"]
    assert hyper["material"] == "neo-hookean" and hyper["volumetric"] == "simo_taylor"
    assert hyper["coefficients"]["mu"] == pytest.approx(0.6e6 / 2.9, rel=1e-12)
    for row in rows:
        rod = row["rod"]["hyperelastic"]
        assert rod["status"] == "converged" and 0 < rod["distance_over_L"] < 0.05
    # the two rod laws are different models (O((h/L)^2) apart)
    a, b = (rows[-1]["rod"][law]["tip"]["theta"] for law in ("nonstandard", "reissner"))
    assert a != pytest.approx(b, rel=1e-6)


def test_csv_and_plots(sweep_run):
    out, summary = sweep_run
    with (out / "compare.csv").open(newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 2
    assert {"load_factor", "tension_0", "solid_tip_v", "nonstandard_tip_theta",
            "reissner_distance_over_L"} <= set(rows[0])
    assert float(rows[1]["nonstandard_distance_over_L"]) == pytest.approx(
        summary["table"][1]["rod"]["nonstandard"]["distance_over_L"])
    for name in ("backbones.png", "tip_vs_tension.png"):
        assert (out / name).stat().st_size > 1000, name


def test_solid_equilibrium_is_certified(sweep_run):
    """issue 28: the solid's global equilibrium over every step of the sweep (a tendon-only
    finger: no net reaction at the clamp)."""
    _, summary = sweep_run
    (check,) = summary["checks"]
    assert check["name"] == "solid_global_equilibrium" and check["passed"]
    assert check["value"] < 1e-8
    for row in summary["table"]:
        balance = row["solid"]["equilibrium"]
        assert np.linalg.norm(balance["reaction_force"]) < 1e-8 * row["tension"]
        assert balance["scale"] == pytest.approx(row["tension"], rel=1e-12)

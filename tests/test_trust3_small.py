"""Issue 20, item 5: the small ones (messages, labels, notes)."""

import json
import signal
from pathlib import Path

import numpy as np
import pytest
from test_validity import run_cli, with_map

from fe_beam import runctl

ROOT = Path(__file__).resolve().parents[1]


def test_validity_ctrl_c_says_which_points_are_done(tmp_path, monkeypatch):
    """A 3 x 1 map interrupted while its third point runs (the inner compare's Interrupted,
    which says "load factor 0 of the sweep"): the closing line and the summary say 2 of 3
    points are done and which."""
    from fe_beam.analyses import validity

    solved = []

    def stand_in(point, config, comm):
        solved.append(point.name)
        if len(solved) == 3:  # as fe_beam.analyses.compare.run_compare stops its solid sweep
            stop = runctl.Interrupted(signal.SIGINT)
            stop.stopped("load factor 0 of the sweep", "after load factor 0")
            raise stop
        tip = {"u": -0.001 * point.x, "v": 0.01 * point.x, "theta": 0.1 * point.x}
        rod = {"status": "converged", "message": "", "tip": tip,
               "tip_error": {"distance_over_L": 0.0, "rotation": 0.0}, "backbone_distance": 0.0}
        return {"i": point.i, "j": point.j, "x": point.x, "y": point.y, "hash": point.hash,
                "status": "converged", "message": "",
                "solid": {"tip": tip, "dofs": 1, "mesh_size": 0.01, "discretisation_error": None},
                "rod": {law: dict(rod) for law in config.laws}}

    monkeypatch.setattr(validity, "solve_point", stand_in)
    config = with_map(x_values=[0.2, 0.4, 0.6])
    del config["validity"]["second_mesh_ratio"]
    config["output"]["plots"] = False
    code, _, stderr, out = run_cli("validity", tmp_path, config)
    assert code == 130, stderr
    line = [x for x in stderr.splitlines() if x.startswith("fe-beam: interrupted")]
    assert len(line) == 1, stderr
    assert "load factor 0" not in line[0], line[0]
    assert "2 of 3 validity points done" in line[0] and "0_0, 1_0" in line[0], line[0]

    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert "2 of 3 points done (0_0, 1_0)" in summary["message"], summary["message"]


def _captured_calibration_figure(tmp_path, monkeypatch, load_column):
    """calibration.png's figure, kept from plt.close (the plot of
    `fe_beam.analyses.calibrate._plot`)."""
    from fe_beam.analyses import calibrate
    from fe_beam.exports import outputs
    real = outputs._pyplot()
    kept = []

    class Keeping:
        def __getattr__(self, name):
            return getattr(real, name)

        def close(self, figure=None):
            kept.append(figure)

    monkeypatch.setattr(outputs, "_pyplot", lambda: Keeping())
    monkeypatch.setattr(calibrate, "_pyplot", lambda: Keeping())  # bound at its import
    loads = np.array([0.6, 1.2, 1.8])  # N (tension column, tendons.0.tension = 1.2) or factors
    factors = loads / 1.2 if load_column == "tension" else loads
    data = calibrate.CalibrationData(load_column, loads, {
        "tip_u": -0.002 * factors, "tip_v": 0.008 * factors, "tip_theta": 0.25 * factors})
    curves = {float(f): {"x": [0.0, 0.1], "y": [0.0, 0.01 * f],
                         "tip": [-0.002 * f, 0.008 * f, 0.25 * f]} for f in factors}
    calibrate._plot(tmp_path / "calibration.png", data, curves, factors,
                    {"parameters": {"material.E": 6e5}})
    real.close(kept[0])
    return kept[0], loads, factors


def test_calibration_plot_units_and_load_axis(tmp_path, monkeypatch):
    for column in ("tension", "load_factor"):
        figure, loads, factors = _captured_calibration_figure(tmp_path, monkeypatch, column)
        panels = [a for a in figure.axes if a.get_title().startswith("tip")]
        assert len(panels) == 1
        tip = panels[0]
        twins = [a for a in figure.axes if a is not tip and a.bbox.bounds == tip.bbox.bounds]
        assert len(twins) == 1, "tip_theta [rad] on its own axis"
        angle = twins[0]
        assert "mm" in tip.get_ylabel() and "rad" in angle.get_ylabel()
        labels = {line.get_label(): line for line in tip.get_lines()}
        assert set(labels) == {"tip_u model", "tip_u data", "tip_v model", "tip_v data"}
        assert [line.get_label() for line in angle.get_lines()] == ["tip_theta model",
                                                                    "tip_theta data"]
        # values: mm on the left axis, rad on the right one, against the data's load column
        np.testing.assert_allclose(labels["tip_v data"].get_ydata(), 8.0 * factors, rtol=1e-12)
        np.testing.assert_allclose(angle.get_lines()[1].get_ydata(), 0.25 * factors, rtol=1e-12)
        np.testing.assert_allclose(labels["tip_u data"].get_xdata(), loads, rtol=1e-12)
        if column == "tension":
            assert "tension" in tip.get_xlabel() and "[N]" in tip.get_xlabel()
        else:
            assert tip.get_xlabel() == "load factor"


def _design_rod(**design):
    return {"beam": {"length": 0.7}, "section": {"shape": "rectangle", "b": 0.015, "h": 0.01},
            "material": {"E": 2.0e7, "nu": 0.3}, "model": {"law": "reissner"},
            "mesh": {"elements": 4, "degree": 2}, "loads": {"tip_moment": 0.02, "steps": 4},
            "output": {"plots": False, "xdmf": False}, "design": design}


def test_design_prints_the_minimised_tension_itself(tmp_path, capsys):
    """objective = "tension": min M with theta_tip = 0.7, h in [9, 11] mm: M = theta E b h^3 /
    (12 L) at h = 9 mm; the line shows M (not M / 0.04, the scaled objective)."""
    import re

    from tomlio import dump_toml

    from fe_beam.cli import main

    target, h_lo, top = 0.7, 0.009, 0.04
    config = _design_rod(variables=["loads.tip_moment", "section.h"],
                         bounds=[[0.002, top], [h_lo, 0.011]], objective="tension",
                         tip_angle=target)
    path = tmp_path / "design.toml"
    path.write_text(dump_toml(config))
    capsys.readouterr()
    assert main(["design", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    line = capsys.readouterr().out
    exact = target * 2.0e7 * 0.015 * h_lo**3 / (12 * 0.7)
    found = re.search(r"objective loads\.tip_moment = ([0-9.e+-]+) \(minimised\)", line)
    assert found, line
    assert abs(float(found.group(1)) - exact) <= 1e-5 * exact, (line, exact)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    minimised = summary["objective"]["minimised"]
    assert minimised["name"] == "loads.tip_moment"
    assert abs(minimised["value"] - exact) <= 1e-7 * exact
    assert abs(summary["objective"]["value"] - minimised["value"] / top) <= 1e-15


def test_design_says_finite_differences_with_a_fibre_strain_limit():
    from mpi4py import MPI

    from fe_beam.analyses.design import run_design

    limited = run_design(_design_rod(variables=["section.h"], bounds=[[0.006, 0.02]],
                                     objective="tip_pose", target={"theta": 0.9},
                                     max_fibre_strain=0.004), None, MPI.COMM_WORLD)
    assert limited["gradient"] == "finite-difference"
    assert any("max_fibre_strain" in n and "finite differences" in n
               for n in limited["notes"]), limited["notes"]
    free = run_design(_design_rod(variables=["section.h"], bounds=[[0.006, 0.02]],
                                  objective="tip_pose", target={"theta": 0.9}), None,
                      MPI.COMM_WORLD)
    assert not any("finite differences" in n for n in free["notes"]), free["notes"]


def test_snap_through_critical_points_report_the_pushed_point(tmp_path, capsys):
    """A point-force path (a clamped-clamped beam buckled by 1.2 % shortening, pushed at
    x = 0.4 L): every critical point has the pushed point's u, v, theta (the clamped tip does
    not move), lying between those of the two path points around it; the line says so."""
    import tomllib

    from tomlio import dump_toml

    from fe_beam.cli import main

    config = tomllib.loads((ROOT / "examples" / "snap_through.toml").read_text())
    config["mesh"]["elements"] = 12
    config["material"]["E"] = 2.0e7
    config["loads"]["end_displacement"] = [-0.012, 0.0]
    config["loads"]["point_forces"] = [[0.4, 0.0, -100 * 2.0e7 * 1e-8 / 12]]
    config["path"]["max_steps"] = 45
    config["output"]["plots"] = False
    path = tmp_path / "snap.toml"
    path.write_text(dump_toml(config))
    capsys.readouterr()
    code = main(["path", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    out = capsys.readouterr().out
    assert code == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    points = summary["path"]
    critical = summary["critical_points"]
    assert len(critical) >= 2 and any(c["kind"] == "limit" for c in critical)
    for c in critical:
        assert c["point"]["x"] == 0.4
        assert abs(c["point"]["v"]) > 1e-3  # the pushed point, not the clamped tip (v = 0)
        # the path point just before the critical point and the one after it (in path order)
        lf = c["load_factor"]
        # (a limit point's load factor is beyond both: within two steps of them)
        pairs = [(a, b) for a, b in zip(points, points[1:], strict=False)
                 if max(abs(lf - a["load_factor"]), abs(lf - b["load_factor"]))
                 <= 2 * abs(a["load_factor"] - b["load_factor"]) + 1e-9
                 and min(a["point"]["v"], b["point"]["v"]) - 1e-9 <= c["point"]["v"]
                 <= max(a["point"]["v"], b["point"]["v"]) + 1e-9]
        assert pairs, (c, [(p["load_factor"], p["point"]["v"]) for p in points])
    lines = [x for x in out.splitlines() if " point at load factor " in x]
    assert len(lines) == len(critical) and all("point x = 0.4 m" in x for x in lines), out


@pytest.mark.mpi
def test_finger_progress_bar_counts_the_load_steps(monkeypatch):
    """steps = 3: the bar's total is 3 steps and it reaches 3 (was 0..1, shown "0/1")."""
    from fe_beam.analyses.finger import parse_finger
    from fe_beam.analyses.static import solve_static
    from fe_beam.solvers import continuation

    bars = []

    class Recording:
        def __init__(self, comm, total, label, enabled=True, unit=""):
            self.total, self.values = total, []
            bars.append(self)

        def update(self, value, message=""):
            self.values.append(value)

        def note(self, message):
            pass

        def close(self):
            pass

    monkeypatch.setattr(continuation, "ProgressBar", Recording)
    config, _ = parse_finger({"mesh": {"elements": 6, "degree": 2}, "loads": {"steps": 3},
                              "tendons": [{"name": "t", "offset_base": 0.006,
                                           "offset_tip": 0.003, "tension": 0.8}],
                              "output": {"plots": False, "xdmf": False}})
    result = solve_static(config, None, progress=True, record_shapes=False)
    assert result.status == "converged"
    assert len(bars) == 1 and bars[0].total == 3
    assert bars[0].values == pytest.approx([1.0, 2.0, 3.0], rel=1e-12)


CALIBRATION_FINGER = {"beam": {"length": 0.1},
                      "section": {"shape": "rectangle", "b": 0.02, "h": 0.02, "h_tip": 0.01},
                      "material": {"E": 0.6e6, "nu": 0.45},
                      "mesh": {"elements": 6, "degree": 2}, "loads": {"steps": 4},
                      "tendons": [{"offset_base": 0.008, "offset_tip": 0.004, "tension": 1.9}],
                      "solver": {"rtol": 1e-12}}


@pytest.mark.mpi
def test_calibrate_continues_from_lower_loads_when_the_start_has_no_equilibrium():
    """Data of E = 0.6 MPa at tensions 0.4 .. 1.9 N; start E = 0.07 MPa: the non-standard
    law's largest moment (0.703 EI/h at the tip) is below 1.9 N x 4 mm there, so the start
    has no equilibrium at the highest tensions. The fit starts from the lower tensions and
    recovers E; a start with no equilibrium even at 0.4 N is refused in one sentence."""
    from fe_beam.analyses.calibrate import CalibrationData, CalibrationSpec, calibrate
    from fe_beam.analyses.sensitivity import RodSensitivity
    from fe_beam.config import ConfigError

    parameters = ("material.E",)
    tensions = np.array([0.4, 0.9, 1.4, 1.9])
    model = RodSensitivity(CALIBRATION_FINGER, parameters)
    try:
        model.set_values(np.array([0.6e6]))
        columns = {c: [] for c in ("tip_u", "tip_v", "tip_theta")}
        for tension in tensions:
            model.solve(tension / 1.9)
            for c, value in zip(columns, model.outputs(list(columns)), strict=True):
                columns[c].append(value)
        data = CalibrationData("tension", tensions, {k: np.array(v) for k, v in
                                                     columns.items()})
        model.set_values(np.array([0.07e6]))
        summary = calibrate(None, data, CalibrationSpec(parameters), model=model)
        assert summary["status"] == "converged", summary["message"]
        assert abs(summary["parameters"]["material.E"] - 0.6e6) <= 1e-6 * 0.6e6
        assert summary["initial"]["material.E"] == 0.07e6
        assert any("no equilibrium at tension" in n and "continued" in n
                   for n in summary["notes"]), summary["notes"]
        model.set_values(np.array([0.004e6]))
        with pytest.raises(ConfigError, match="no equilibrium even at the data's lowest load"):
            calibrate(None, data, CalibrationSpec(parameters), model=model)
    finally:
        model.destroy()

"""fe-beam design: known optima (Reissner rod under a tip moment: theta_tip = M L / (E I)
exactly), the KKT conditions at the optimum, and bad [design] tables (exit 2, one sentence)."""

import copy
import json

import numpy as np
import pytest
from mpi4py import MPI
from tomlio import dump_toml

from fe_beam.analyses.design import parse_design, run_design
from fe_beam.cli import main
from fe_beam.errors import ConfigError

E, B, L = 1.0e7, 0.02, 1.0


def rod(moment=0.01, h=0.01, **design) -> dict:
    return {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": B, "h": h},
        "material": {"E": E, "nu": 0.3},
        "model": {"law": "reissner"},
        "mesh": {"elements": 3, "degree": 2},
        "loads": {"tip_moment": moment, "steps": 4},
        "output": {"plots": False, "xdmf": False},
        "design": design,
    }


def tip_angle(moment, h):
    return moment * L / (E * B * h**3 / 12)


def test_height_for_a_target_tip_angle():
    """min (theta - theta*)^2 over h: h* = (12 M L / (E b theta*))^(1/3)."""
    moment, target = 0.013, 1.1
    summary = run_design(rod(moment, variables=["section.h"], bounds=[[0.005, 0.02]],
                             objective="tip_pose", target={"theta": target}), None,
                         MPI.COMM_WORLD)
    exact = (12 * moment * L / (E * B * target)) ** (1 / 3)
    assert summary["status"] == "converged"
    assert summary["variables"]["section.h"] == pytest.approx(exact, rel=1e-7)
    assert summary["kkt_residual"] < 1e-6
    assert summary["gradient"] in ("adjoint", "finite-difference")
    assert summary["tip"]["theta"] == pytest.approx(target, rel=1e-8)


def test_least_moment_for_a_tip_angle_sits_on_a_bound():
    """min M subject to theta_tip = theta*, h in [h_lo, h_hi]: M = theta* E b h^3 / (12 L) is
    smallest at h = h_lo (an active bound and an active equality: nonzero multipliers)."""
    target, h_lo = 0.9, 0.008
    config = rod(0.02, h=0.01, variables=["loads.tip_moment", "section.h"],
                 bounds=[[0.001, 0.05], [h_lo, 0.012]], objective="tension", tip_angle=target)
    summary = run_design(config, None, MPI.COMM_WORLD)
    assert summary["status"] == "converged"
    assert summary["variables"]["section.h"] == pytest.approx(h_lo, rel=1e-9)
    exact = target * E * B * h_lo**3 / (12 * L)
    assert summary["variables"]["loads.tip_moment"] == pytest.approx(exact, rel=1e-7)
    assert abs(summary["constraints"]["tip_angle"]["residual"]) < 1e-8
    kkt = summary["kkt"]
    assert kkt["kkt_residual"] < 1e-6
    assert "lower section.h" in kkt["active"]
    assert all(abs(m) > 1e-6 for m in kkt["multipliers"])


def test_fibre_strain_limit_is_active():
    """Target theta* = 1.2 needs h* (unconstrained); the extreme fibre strain h theta / (2 L)
    must stay below a limit that h* breaks: the optimum is where the limit holds with
    equality, h_c = sqrt(6 M / (E b limit))."""
    moment, target, limit = 0.01, 1.2, 0.003
    summary = run_design(rod(moment, variables=["section.h"], bounds=[[0.005, 0.02]],
                             objective="tip_pose", target={"theta": target},
                             max_fibre_strain=limit), None, MPI.COMM_WORLD)
    free = (12 * moment * L / (E * B * target)) ** (1 / 3)
    assert free * tip_angle(moment, free) / (2 * L) > limit  # the limit binds
    critical = np.sqrt(6 * moment / (E * B * limit))
    assert summary["variables"]["section.h"] == pytest.approx(critical, rel=1e-6)
    assert summary["constraints"]["max_fibre_strain"]["value"] == pytest.approx(limit, rel=1e-6)
    assert summary["kkt_residual"] < 1e-6
    assert summary["kkt"]["multipliers"][0] > 0


def test_finger_offset_for_a_tip_pose(tmp_path):
    """A finger: the tip offset of the tendon that puts the tip at the angle that a known
    offset gives (computed independently by solve_static)."""
    from fe_beam.analyses.finger import parse_finger
    from fe_beam.analyses.static import solve_static

    finger = {"mesh": {"elements": 4, "degree": 2}, "output": {"plots": True, "xdmf": False},
              "model": {"law": "reissner", "constraint": "unshearable"},
              "tendons": [{"name": "flexor", "offset_base": 0.008, "offset_tip": 0.003,
                           "tension": 1.5}]}
    truth = copy.deepcopy(finger)
    truth["tendons"][0]["offset_tip"] = 0.0045
    parsed, _ = parse_finger(truth)
    theta = solve_static(parsed, None, progress=False, record_shapes=False).steps[-1]["tip"][
        "theta"]
    config = finger | {"design": {"variables": ["tendons.0.offset_tip"],
                                  "bounds": [[0.0, 0.0049]], "objective": "tip_pose",
                                  "target": {"theta": theta}}}
    summary = run_design(config, tmp_path, MPI.COMM_WORLD)
    assert summary["variables"]["tendons.0.offset_tip"] == pytest.approx(0.0045, rel=1e-6)
    assert summary["kkt_residual"] < 1e-6
    written = json.loads((tmp_path / "summary.json").read_text())
    assert written["variables"] == summary["variables"]
    assert (tmp_path / "design.png").is_file()


BAD = [
    ({"variables": ["section.q"], "bounds": [[0.1, 1]], "objective": "tip_pose",
      "target": {"theta": 1}}, "not a dimension"),
    ({"variables": ["wing.span"], "bounds": [[0.1, 1]], "objective": "tip_pose",
      "target": {"theta": 1}}, "not a design variable"),
    ({"variables": ["section.shape"], "bounds": [[0.1, 1]], "objective": "tip_pose",
      "target": {"theta": 1}}, "not numeric"),
    ({"variables": ["model.law"], "bounds": [[0.1, 1]], "objective": "tip_pose",
      "target": {"theta": 1}}, "not a numeric design variable"),
    ({"variables": ["section.h"], "bounds": [[0.02, 0.005]], "objective": "tip_pose",
      "target": {"theta": 1}}, "must be <"),
    ({"variables": ["section.h"], "bounds": [[0.005]], "objective": "tip_pose",
      "target": {"theta": 1}}, "one [low, high] pair"),
    ({"variables": ["section.h"], "bounds": [[0.02, 0.03]], "objective": "tip_pose",
      "target": {"theta": 1}}, "outside its bounds"),
    ({"variables": ["section.h"], "bounds": [[0.005, 0.02]], "objective": "fastest",
      "target": {"theta": 1}}, "objective must be one of"),
    ({"variables": ["section.h"], "bounds": [[0.005, 0.02]], "objective": "tension",
      "tip_angle": 1.0}, "exactly one of"),
    ({"variables": ["section.h"], "bounds": [[0.005, 0.02]], "objective": "tip_pose",
      "target": {"phi": 1}}, "needs target"),
    ({"variables": ["section.h"], "bounds": [[0.005, 0.02]], "objective": "tip_pose",
      "target": {"theta": 1}, "step": 3}, "unknown key"),
    ({"variables": ["section.h"], "bounds": {"section.b": [0.005, 0.02]},
      "objective": "tip_pose", "target": {"theta": 1}}, "missing 'section.h'"),
    ({"variables": ["section.h"], "bounds": [[0.005, "big"]], "objective": "tip_pose",
      "target": {"theta": 1}}, "one [low, high] pair"),
]


def test_bounds_as_a_table():
    design, _ = parse_design(rod(variables=["section.h", "loads.tip_moment"],
                                 bounds={"loads.tip_moment": [0.0, 0.1],
                                         "section.h": [0.005, 0.02]},
                                 objective="tip_pose", target={"theta": 1.0}))
    assert design.bounds.tolist() == [[0.005, 0.02], [0.0, 0.1]]


@pytest.mark.parametrize("design, words", BAD)
def test_bad_design_tables(design, words):
    with pytest.raises(ConfigError, match=words.replace("[", r"\[")):
        parse_design(rod(**design))


def test_cli_bad_design_exits_2(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(dump_toml(rod(variables=["section.q"], bounds=[[0.1, 1]],
                                  objective="tip_pose", target={"theta": 1.0})))
    assert main(["design", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "section.q" in err and "Traceback" not in err


def test_cli_design_writes_summary(tmp_path):
    path = tmp_path / "good.toml"
    path.write_text(dump_toml(rod(variables=["section.h"], bounds=[[0.005, 0.02]],
                                  objective="tip_pose", target={"theta": 0.8})))
    assert main(["design", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    exact = (12 * 0.01 * L / (E * B * 0.8)) ** (1 / 3)
    assert summary["variables"]["section.h"] == pytest.approx(exact, rel=1e-7)
    assert summary["gradient"] in ("adjoint", "finite-difference")


@pytest.mark.mpi
def test_design_on_two_ranks():
    """The same optimum on every rank of a partitioned rod (collective solves and reductions)."""
    moment, target = 0.011, 0.9
    config = rod(moment, variables=["section.h"], bounds=[[0.005, 0.02]], objective="tip_pose",
                 target={"theta": target})
    config["mesh"]["elements"] = 6
    summary = run_design(config, None, MPI.COMM_WORLD)
    exact = (12 * moment * L / (E * B * target)) ** (1 / 3)
    assert summary["variables"]["section.h"] == pytest.approx(exact, rel=1e-7)
    assert summary["kkt_residual"] < 1e-6
    values = MPI.COMM_WORLD.allgather(summary["variables"]["section.h"])
    assert all(v == values[0] for v in values)


def test_taper_of_an_untapered_rod():
    """section.h_tip of a uniform rod: the taper starts from h. Pure moment on a linear taper
    h0 -> h1: theta = 6 M L (h0 + h1) / (E b h0^2 h1^2); the optimum h1 for a target angle
    (the FE answer converges to it with the mesh: 12 degree-2 elements, 1e-5)."""
    from scipy.optimize import brentq

    moment, h0, target = 0.01, 0.01, 0.8
    config = rod(moment, h=h0, variables=["section.h_tip"], bounds=[[0.005, 0.02]],
                 objective="tip_pose", target={"theta": target})
    config["mesh"]["elements"] = 12
    summary = run_design(config, None, MPI.COMM_WORLD)
    exact = brentq(lambda h1: 6 * moment * L * (h0 + h1) / (E * B * h0**2 * h1**2) - target,
                   0.005, 0.02)
    assert summary["variables"]["section.h_tip"] == pytest.approx(exact, rel=1e-5)
    assert summary["tip"]["theta"] == pytest.approx(target, rel=1e-8)
    assert summary["kkt_residual"] < 1e-6


def test_unreachable_target_is_said():
    """A tip angle the bounds cannot reach: the misfit's optimum is at the bound h = h_hi (a
    valid constrained optimum) and the summary and the command say that the target is not
    reached (was: "design converged" and nothing else)."""
    moment, h_hi = 0.01, 0.02
    reachable = tip_angle(moment, h_hi)  # the smallest tip angle within the bounds
    target = 0.5 * reachable
    config = rod(moment, variables=["section.h"], bounds=[[0.005, h_hi]],
                 objective="tip_pose", target={"theta": target})
    summary = run_design(copy.deepcopy(config), None, MPI.COMM_WORLD)
    assert summary["variables"]["section.h"] == pytest.approx(h_hi, rel=1e-9)
    assert summary["tip"]["theta"] == pytest.approx(reachable, rel=1e-6)
    assert len(summary["notes"]) == 1
    note = summary["notes"][0]
    assert "target is not reached" in note and "upper section.h" in note
    # a reached target: no note
    config["design"]["target"] = {"theta": 1.5 * reachable}
    assert run_design(config, None, MPI.COMM_WORLD)["notes"] == []


def test_unreachable_target_note_on_the_command_line(tmp_path, capfd):
    moment, h_hi = 0.01, 0.02
    config = rod(moment, variables=["section.h"], bounds=[[0.005, h_hi]],
                 objective="tip_pose", target={"theta": 0.5 * tip_angle(moment, h_hi)})
    path = tmp_path / "design.toml"
    path.write_text(dump_toml(config))
    assert main(["design", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    err = capfd.readouterr().err
    assert "note: the target is not reached" in err
    saved = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert saved["notes"] and "not reached" in saved["notes"][0]


def test_custom_section_dimension_is_refused_with_one_sentence(tmp_path, capfd):
    """A custom section's A and I are compiled into the forms (its height sqrt(12 I / A)):
    exit 2 naming the variable (was: internal error, exit 1, after building the model).
    material.E of the same model is a valid variable."""
    config = rod(0.01, variables=["section.I"], bounds=[[1e-10, 1e-8]], objective="tip_pose",
                 target={"theta": 0.5})
    config["section"] = {"shape": "custom", "A": B * 0.01, "I": B * 0.01**3 / 12}
    path = tmp_path / "design.toml"
    path.write_text(dump_toml(config))
    assert main(["design", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capfd.readouterr().err.strip()
    assert "'section.I' cannot be a design variable" in err and len(err.splitlines()) == 1
    config["design"].update(variables=["material.E"], bounds=[[1e6, 1e8]])
    summary = run_design(config, None, MPI.COMM_WORLD)
    assert summary["status"] == "converged"
    assert summary["variables"]["material.E"] == pytest.approx(
        0.01 * L / (0.5 * B * 0.01**3 / 12), rel=1e-7)


def test_trial_design_without_equilibrium_exits_3(tmp_path, capfd, monkeypatch):
    """A trial design the solver finds no equilibrium for ends the command with exit 3 and one
    line saying so (was: 'internal error', exit 1)."""
    from fe_beam.solvers import realtime

    update = realtime.RealtimeSolver.update
    calls = []

    def failing(self, *args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise realtime.UpdateFailed("no equilibrium at the new values (test)", 0.0)
        return update(self, *args, **kwargs)

    monkeypatch.setattr(realtime.RealtimeSolver, "update", failing)
    config = rod(0.01, variables=["section.h"], bounds=[[0.005, 0.02]], objective="tip_pose",
                 target={"theta": 0.5})
    path = tmp_path / "design.toml"
    path.write_text(dump_toml(config))
    assert main(["design", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 3
    err = capfd.readouterr().err.strip()
    assert "no equilibrium for a trial design" in err and len(err.splitlines()) == 1, err


def test_the_design_prints_the_command_that_reproduces_its_answer(tmp_path, capsys):
    """A finger design varying a dimension of the default section (no [section] table): the
    command it prints (and writes as summary.json's ``reproduce``) re-runs its answer; was:
    ``--set section.h=...`` made a section of h alone (exit 2, "section.b is required")."""
    import shlex

    path = tmp_path / "taper.toml"
    path.write_text(dump_toml({
        "mesh": {"elements": 4, "degree": 2}, "loads": {"steps": 5},
        "output": {"plots": False, "xdmf": False},
        "tendons": [{"offset_base": 0.007, "offset_tip": 0.003, "tension": 3.0}],
        "design": {"variables": ["section.h"], "bounds": [[0.014, 0.03]],
                   "objective": "tip_pose", "target": {"theta": 0.5}}}))
    out = tmp_path / "out"
    assert main(["design", str(path), "--out", str(out), "--quiet",
                 "--set", "material.E=0.7e6"]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    command = summary["reproduce"]
    assert f"reproduce the answer with: {command}" in printed
    words = shlex.split(command)
    assert words[:3] == ["fe-beam", "finger", str(path)]
    assert "material.E=0.7e6" in words  # the run's own override, kept
    assert summary["tip"]["theta"] == pytest.approx(0.5, abs=1e-8)
    assert main(words[1:] + ["--out", str(tmp_path / "again"), "--quiet"]) == 0
    again = json.loads((tmp_path / "again" / "summary.json").read_text())
    assert again["steps"][-1]["tip"]["theta"] == pytest.approx(0.5, abs=1e-8)
    for key in ("u", "v"):
        assert again["steps"][-1]["tip"][key] == pytest.approx(summary["tip"][key], rel=1e-7)


def test_an_override_of_a_defaulted_table_applies_to_the_default():
    from fe_beam.config.finger import DEFAULT_FINGER, override_defaults
    from fe_beam.config.schema import apply_overrides

    given = {"tendons": [{"offset_base": 0.008, "offset_tip": 0.004, "tension": 1.0}]}
    changed = apply_overrides(given, ["section.h_tip=0.009"],
                              override_defaults("design", given))
    assert changed["section"] == {**DEFAULT_FINGER["section"], "h_tip": 0.009}
    own = {**given, "section": {"shape": "circle", "d": 0.01}}  # the file's table: kept whole
    assert apply_overrides(own, ["section.d=0.02"], override_defaults("finger", own))[
        "section"] == {"shape": "circle", "d": 0.02}
    rod = {"section": {"shape": "rectangle", "b": 0.01, "h": 0.01}}  # no finger: no defaults
    assert override_defaults("static", rod) is None
    assert apply_overrides({}, ["tendons.0.tension=3.0"], override_defaults("finger", {}))[
        "tendons"][0] == {**DEFAULT_FINGER["tendons"][0], "tension": 3.0}


def _tube_under_a_tip_force():
    """A steel tube under a tip force and gravity whose force is the design variable."""
    return {
        "beam": {"length": 0.6},
        "section": {"shape": "tube", "d": 0.012, "t": 0.001},
        "material": {"E": 2.1e11, "nu": 0.29, "rho": 7800.0},
        "model": {"law": "nonstandard"},
        "mesh": {"elements": 3, "degree": 2},
        "loads": {"tip_force": [0.0, -5.0], "gravity": [0.0, -9.81], "steps": 2},
        "output": {"plots": False, "xdmf": False},
        "design": {"variables": ["loads.tip_force.1"], "bounds": [[-60.0, 0.0]],
                   "objective": "tip_pose", "target": {"theta": -0.05}},
    }


def test_the_design_answer_carries_its_global_equilibrium(tmp_path):
    """The answer of `fe-beam design` is a static equilibrium: it carries the
    global_equilibrium check (it carried no check before)."""
    path = tmp_path / "tube.toml"
    path.write_text(dump_toml(_tube_under_a_tip_force()))
    assert main(["design", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    (check,) = [c for c in summary["checks"] if c["name"] == "global_equilibrium"]
    assert check["passed"] and check["value"] <= check["tolerance"]
    assert summary["status"] == "converged" and summary["checks_passed"] is True


def test_a_design_answer_out_of_balance_fails_with_exit_3(tmp_path, monkeypatch):
    """A load the balance misses by 2 % (monkeypatched): status "failed", exit 3."""
    from fe_beam.fem import equilibrium

    original = equilibrium._body
    monkeypatch.setattr(equilibrium, "_body",
                        lambda problem, factor: original(problem, 1.02 * factor))
    path = tmp_path / "tube.toml"
    path.write_text(dump_toml(_tube_under_a_tip_force()))
    assert main(["design", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 3
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "failed" and "global_equilibrium" in summary["message"]

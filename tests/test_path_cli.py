"""`fe-beam path` (fe_beam.analyses.path.run_path, fe_beam.config.path): the clamped-free elastica
example
against the elliptic-integral solution, a finger's tendon-tension path against fe-beam finger,
outputs that agree with each other, and one-sentence exit 2 for bad [path] input."""

import csv
import json
import math
from pathlib import Path

import pytest
from mpi4py import MPI
from tomlio import dump_toml

import fe_beam
from fe_beam.analytic import elastica_clamped_free
from fe_beam.cli import main
from fe_beam.config.schema import load_config

serial = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="dense stability: serial")

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _write(path: Path, config: dict) -> Path:
    path.write_text(dump_toml(config))
    return path


@pytest.fixture(scope="module")
def elastica(tmp_path_factory):
    out = tmp_path_factory.mktemp("elastica") / "out"
    assert main(["path", str(EXAMPLES / "elastica_path.toml"), "--out", str(out),
                 "--quiet"]) == 0
    return out, json.loads((out / "summary.json").read_text())


@serial
def test_elastica_example_bifurcates_at_euler_and_follows_the_elastica(elastica):
    out, summary = elastica
    config = load_config(EXAMPLES / "elastica_path.toml")
    E, b, h = config["material"]["E"], config["section"]["b"], config["section"]["h"]
    L, force = config["beam"]["length"], -config["loads"]["tip_force"][0]
    euler = math.pi**2 * E * b * h**3 / 12 / (4 * L**2)
    assert summary["status"] == "converged", summary["message"]
    (point,) = summary["critical_points"]
    assert point["kind"] == "bifurcation"
    assert point["load_factor"] == pytest.approx(euler / force, rel=2e-6)
    assert point["mode"] == {"file": "critical_modes.xdmf", "index": 1}
    fundamental = [p for p in summary["path"] if p["branch"] == 0]
    assert all(p["stable"] == (p["load_factor"] < euler / force) for p in fundamental)
    assert all(p["energy_decreasing_directions"] == (0 if p["stable"] else 1)
               for p in fundamental)
    buckled = [p for p in summary["path"] if p["branch"] == 1]
    assert len(buckled) > 10 and all(p["stable"] for p in buckled)
    largest = 0.0
    for p in buckled:
        alpha = abs(p["tip"]["theta"])
        largest = max(largest, math.degrees(alpha))
        exact = elastica_clamped_free(alpha)
        assert p["load_factor"] * force / euler == pytest.approx(exact.load_ratio, rel=2e-5)
        assert -p["tip"]["u"] / L == pytest.approx(exact.shortening, abs=1e-5)
        assert abs(p["tip"]["v"]) / L == pytest.approx(exact.deflection, abs=1e-5)
    assert largest > 150
    for name in ("path.csv", "path.png", "path.xdmf", "critical_modes.xdmf"):
        assert (out / name).is_file(), name


@serial
def test_csv_and_summary_agree(elastica):
    out, summary = elastica
    with open(out / "path.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == len(summary["path"])
    for row, point in zip(rows, summary["path"], strict=True):
        assert int(row["index"]) == point["index"] and int(row["branch"]) == point["branch"]
        assert float(row["load_factor"]) == point["load_factor"]
        for key in ("u", "v", "theta"):
            assert float(row[f"tip_{key}"]) == point["tip"][key]
        assert row["stable"] == str(point["stable"])


def _finger(tmp_path, **path):
    config = load_config(EXAMPLES / "finger.toml")
    config.pop("inverse")
    config["path"] = {"parameter": "tension", "max_load_factor": 1.0, "arc_length": 0.2,
                      "max_steps": 30} | path
    return config


@serial
@pytest.mark.parametrize("tip_force", [None, [0.0, -0.3]])
def test_tendon_tension_path_equals_fe_beam_finger(tmp_path, tip_force):
    """The tension of the flexor from 0 to 2 N (with a tip force: held in full, the path
    starting from the state it bends alone) equals fe-beam finger at the path's tensions."""
    from fe_beam.analyses.finger import run_finger
    from fe_beam.config import validate

    config = _finger(tmp_path)
    if tip_force:
        config.setdefault("loads", {})["tip_force"] = tip_force
    out = tmp_path / "out"
    assert main(["path", str(_write(tmp_path / "finger.toml", config)), "--out", str(out),
                 "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "converged" and summary["critical_points"] == []
    path = summary["path"]
    assert path[-1]["load_factor"] == 1.0 and path[-1]["tension"] == 2.0
    assert all(p["stable"] and p["energy_decreasing_directions"] == 0 for p in path)
    assert len(path) >= 4
    for point in (path[len(path) // 2], path[-1]):
        finger = json.loads(json.dumps(config))
        finger.pop("path")
        finger["tendons"][0]["tension"] = point["tension"]
        result, _ = run_finger(validate("finger", finger).parsed[0], None, progress=False)
        tip = result.steps[-1]["tip"]
        for key in ("u", "v", "theta"):
            assert point["tip"][key] == pytest.approx(tip[key], abs=1e-8 * max(1.0, abs(
                tip[key]))), key
    assert path[-1]["tip"]["theta"] - path[0]["tip"]["theta"] > 0.05  # the tendon bends it
    if tip_force:
        assert path[0]["tip"]["theta"] < -0.1  # the tip force alone, tendon slack


@serial
def test_end_displacement_path_equals_fe_beam_static(tmp_path):
    """parameter = "end_displacement": the prescribed tip deflection scaled from 0 to 1 ends
    where fe-beam static (load stepping) ends."""
    from fe_beam.analyses.static import solve_static
    from fe_beam.config import validate

    config = load_config(EXAMPLES / "elastica_path.toml")
    config["model"]["constraint"] = "none"
    config["loads"] = {"end_displacement": [-0.05, 0.3]}
    config["path"] = {"parameter": "end_displacement", "arc_length": 0.25, "max_steps": 30}
    out = tmp_path / "out"
    assert main(["path", str(_write(tmp_path / "d.toml", config)), "--out", str(out),
                 "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "converged" and summary["path"][-1]["load_factor"] == 1.0
    config.pop("path")
    tip = solve_static(validate("static", config).parsed, None, progress=False).steps[-1]["tip"]
    assert tip["theta"] > 0.2
    for key in ("u", "v", "theta"):
        assert summary["path"][-1]["tip"][key] == pytest.approx(tip[key], abs=1e-9), key


@serial
@pytest.mark.parametrize("changes, key", [
    ({"path": {"arc_length": 0.0}}, "arc_length"),
    ({"path": {"arc_length": -0.1}}, "arc_length"),
    ({"path": {"max_steps": 0}}, "max_steps"),
    ({"path": {"max_steps": 2.5}}, "max_steps"),
    ({"path": {"max_load_factor": "big"}}, "max_load_factor"),
    ({"path": {"parameter": "time"}}, "parameter"),
    ({"path": {"branch_switch": "sideways"}}, "branch_switch"),
    ({"path": {"arc_lenght": 0.1}}, "arc_lenght"),
    ({"path": {"parameter": "tension"}}, "tendons"),
    ({"path": {"parameter": "end_displacement"}}, "end_displacement"),
    ({"loads": {"tip_force": [0.0, 0.0]}}, "[loads]"),
    ({"loads": {"tip_force": [-0.02, 0.0], "follower": True}}, "stability is not checked"),
    ({"solid": {"mesh_size": 0.01}}, "locates no bifurcation"),
    ({"mesh": {"elements": 200}}, "critical mode is not computed with"),
    ({"tendons": [{"name": "t", "offset_base": 0.002, "offset_tip": 0.002,
                   "pull_in": 0.001}]}, "pull-in"),
])
def test_bad_path_input_exits_2(tmp_path, capsys, changes, key):
    config = load_config(EXAMPLES / "elastica_path.toml")
    for table, values in changes.items():
        if isinstance(values, dict):
            config.setdefault(table, {}).update(values)
        else:
            config[table] = values
    path = _write(tmp_path / "bad.toml", config)
    assert main(["path", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    error = capsys.readouterr().err.strip()
    assert key in error and "Traceback" not in error and error.count("\n") == 0, error
    assert not (tmp_path / "out" / "summary.json").exists()


@serial
def test_tension_path_of_a_missing_tendon_exits_2(tmp_path, capsys):
    config = _finger(tmp_path, tendon=3)
    assert main(["path", str(_write(tmp_path / "f.toml", config)), "--out",
                 str(tmp_path / "out"), "--quiet"]) == 2
    assert "tendon = 3" in capsys.readouterr().err


@serial
def test_tension_path_whose_pre_state_fails_exits_3_with_the_reason(tmp_path, capsys):
    """The other loads (a tip force far beyond what the finger carries) are load-stepped first:
    when that fails the run ends with exit 3 and the reason (it was an internal error)."""
    config = _finger(tmp_path)
    config.setdefault("loads", {})["tip_force"] = [0.0, 1e5]
    out = tmp_path / "out"
    assert main(["path", str(_write(tmp_path / "f.toml", config)), "--out", str(out),
                 "--quiet"]) == 3
    assert "tendon slack was not reached" in capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["path"] == []


@serial
def test_interrupted_path_leaves_a_readable_summary(tmp_path):
    """SIGINT between path points: exit 130, summary.json says "interrupted" and holds the
    points so far, path.csv the same points."""
    import os
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "out"
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, FE_BEAM_PROGRESS="0")
    env["PYTHONPATH"] = os.pathsep.join([str(root), env.get("PYTHONPATH", "")]).rstrip(
        os.pathsep)
    process = subprocess.Popen(
        [str(Path(sys.executable).parent / "fe-beam"), "path",
         str(EXAMPLES / "elastica_path.toml"), "--set", "path.max_steps=100000", "--set",
         "path.max_load_factor=1e6", "--set", "path.max_arc_length=1.0", "--out", str(out),
         "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 120
    summary = {}
    while len(summary.get("path", [])) < 3:
        assert process.poll() is None and time.monotonic() < deadline, process.communicate()
        time.sleep(0.05)
        if (out / "summary.json").exists():
            summary = json.loads((out / "summary.json").read_text())
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 130, stderr
    assert "Traceback" not in stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert len(summary["path"]) >= 3
    with open(out / "path.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [float(r["load_factor"]) for r in rows] == [p["load_factor"] for p in summary["path"]]


@serial
def test_both_branches_are_mirror_images_on_the_elastica(tmp_path):
    """branch_switch = "both": the column buckles to +v (branch 1) and to -v (branch 2), each
    on the elastica (load vs |end rotation|)."""
    config = load_config(EXAMPLES / "elastica_path.toml")
    config["path"] |= {"branch_switch": "both", "max_steps": 14, "max_load_factor": 1.05}
    out = tmp_path / "out"
    assert main(["path", str(_write(tmp_path / "both.toml", config)), "--out", str(out),
                 "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "converged", summary["message"]
    assert [c["kind"] for c in summary["critical_points"]] == ["bifurcation"]
    euler = math.pi**2 * 1e7 * 0.01**4 / 12 / 4 / 0.02
    signs = {}
    for branch in (1, 2):
        points = [p for p in summary["path"] if p["branch"] == branch]
        assert len(points) > 3
        signs[branch] = {math.copysign(1.0, p["tip"]["v"]) for p in points}
        for p in points:
            exact = elastica_clamped_free(abs(p["tip"]["theta"]))
            assert p["load_factor"] / euler == pytest.approx(exact.load_ratio, rel=2e-5)
            assert p["stable"]
        assert points[-1]["load_factor"] == pytest.approx(1.05, abs=1e-12)
    assert len(signs[1]) == len(signs[2]) == 1 and signs[1] == {-s for s in signs[2]}
    one, two = ([p for p in summary["path"] if p["branch"] == b] for b in (1, 2))
    for a, b in zip(one, two, strict=False):  # the same steps, mirrored
        assert b["load_factor"] == pytest.approx(a["load_factor"], rel=1e-9)
        assert b["tip"]["v"] == pytest.approx(-a["tip"]["v"], abs=1e-9)


@serial
def test_a_path_that_cannot_go_on_exits_3_with_the_last_good_point(tmp_path, capsys):
    """A stocky extensible column kept on its straight (unstable) path is squeezed until
    1 + e = 0 (axial force EA at load factor 2): exit 3, the reason in the message, the points
    up to there in summary.json and path.csv."""
    config = load_config(EXAMPLES / "elastica_path.toml")
    config["model"]["constraint"] = "none"
    config["mesh"]["elements"] = 2
    config["section"] |= {"b": 0.1, "h": 0.1}
    config["loads"]["tip_force"] = [-0.5 * 1e7 * 0.01, 0.0]  # EA / 2
    config["path"] |= {"branch_switch": "none", "max_load_factor": 10.0, "arc_length": 0.5}
    out = tmp_path / "out"
    assert main(["path", str(_write(tmp_path / "stocky.toml", config)), "--out", str(out),
                 "--quiet"]) == 3
    error = capsys.readouterr().err
    assert "inadmissible" in error and "Traceback" not in error
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "1 + e" in summary["message"]
    last = summary["path"][-1]
    assert 1.9 < last["load_factor"] < 2.0  # Reissner: N = EA e, e -> -1 at lambda = 2
    with open(out / "path.csv", newline="") as handle:
        assert len(list(csv.DictReader(handle))) == len(summary["path"])
    assert (out / "path.png").is_file()


@serial
def test_path_model_layer_imports_no_fe_stack():
    import subprocess
    import sys

    code = ("import sys, fe_beam.config.path; "
            "from fe_beam.config import validate, load_config;"
            f"validate('path', load_config({str(EXAMPLES / 'elastica_path.toml')!r}));"
            "print([m for m in ('dolfinx', 'petsc4py', 'mpi4py', 'ufl') if m in sys.modules])")
    root = Path(__file__).resolve().parents[1]
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            cwd=root, env={"PYTHONPATH": str(root)}, check=True)
    assert result.stdout.strip() == "[]"


@serial
def test_solid_path_ends_where_fe_beam_solid_ends(tmp_path):
    """The 3D finger (coarse, linear elements): the arc-length path in the load factor ends at
    load factor 1 on the state `fe-beam solid` reaches by load stepping; stability not
    checked (null, with a note)."""
    config = load_config(EXAMPLES / "finger_solid.toml")
    config.pop("compare")
    config["solid"] |= {"mesh_size": 0.02, "order": 1}
    config["mesh"]["elements"] = 8
    solid = _write(tmp_path / "solid.toml", config)
    assert main(["solid", str(solid), "--out", str(tmp_path / "solid"), "--quiet"]) == 0
    reference = json.loads((tmp_path / "solid" / "summary.json").read_text())["steps"][-1]
    config["path"] = {"arc_length": 0.25, "max_steps": 20}
    path = _write(tmp_path / "path.toml", config)
    assert main(["path", str(path), "--out", str(tmp_path / "path"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "path" / "summary.json").read_text())
    assert summary["status"] == "converged" and summary["model"] == "solid"
    last = summary["path"][-1]
    assert last["load_factor"] == reference["load_factor"] == 1.0
    assert len(summary["path"]) >= 3 and last["stable"] is None
    assert any("not checked" in note for note in summary["notes"])
    assert reference["tip"]["theta"] > 0.05
    for key in ("u", "v", "theta"):
        assert last["tip"][key] == pytest.approx(reference["tip"][key], abs=1e-9), key
    assert (tmp_path / "path" / "path.xdmf").is_file()


@pytest.mark.mpi
def test_path_on_two_ranks_equals_the_serial_path(tmp_path_factory):
    """An imperfect column (small lateral tip force, no bifurcation) on the ranks of
    COMM_WORLD equals the path on one rank, stability counts included (sparse in parallel)."""
    from fe_beam.analyses.path import run_path

    comm = MPI.COMM_WORLD
    config = load_config(EXAMPLES / "elastica_path.toml")
    config["loads"]["tip_force"] = [-0.02, 0.001]
    config["path"] |= {"branch_switch": "none", "max_load_factor": 1.5, "max_steps": 30}
    reference = run_path(config, None, MPI.COMM_SELF, progress=False)
    out = Path(comm.bcast(str(tmp_path_factory.mktemp("mpi")) if comm.rank == 0 else None))
    summary = run_path(config, out / "out", comm, progress=False)
    assert summary["status"] == reference["status"] == "converged"
    assert [p["load_factor"] for p in summary["path"]] == pytest.approx(
        [p["load_factor"] for p in reference["path"]], rel=1e-9)
    for a, b in zip(summary["path"], reference["path"], strict=True):
        for key in ("u", "v", "theta"):
            assert a["tip"][key] == pytest.approx(b["tip"][key], abs=1e-9)
    assert reference["path"][-1]["tip"]["theta"] > 0.5
    # the sparse inertia on several ranks: the same counts as the dense one on one rank
    assert [p["energy_decreasing_directions"] for p in summary["path"]] == [
        p["energy_decreasing_directions"] for p in reference["path"]]
    if comm.size > 1:
        assert any("sparse inertia" in note for note in summary["notes"])


@serial
def test_limit_point_of_the_nonstandard_law_is_reported(tmp_path):
    """Pure bending of the unconstrained non-standard law, M = EI kappa (1 - 0.3 h^2 kappa^2):
    the tip moment's maximum 2 / (3 sqrt(0.9)) EI / h is a limit point, reported with kind
    "limit" at that load factor (1e-6); the path beyond it is unstable."""
    E, h = 1.0e7, 0.2
    EI = E * h**4 / 12
    config = {
        "beam": {"length": 1.0}, "section": {"shape": "rectangle", "b": h, "h": h},
        "material": {"E": E, "nu": 0.3}, "model": {"law": "nonstandard"},
        "mesh": {"elements": 8, "degree": 2}, "loads": {"tip_moment": 0.5 * EI / h},
        "path": {"max_load_factor": 2.0, "arc_length": 0.1, "max_arc_length": 10.0,
                 "max_steps": 24},
    }
    out = tmp_path / "out"
    assert main(["path", str(_write(tmp_path / "m.toml", config)), "--out", str(out),
                 "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    (point,) = summary["critical_points"]
    assert point["kind"] == "limit" and "mode" not in point
    assert point["load_factor"] == pytest.approx(2 / (3 * math.sqrt(0.9)) / 0.5, rel=1e-6)
    beyond = [p for p in summary["path"] if p["tip"]["theta"] > point["tip"]["theta"]]
    assert beyond and not any(p["stable"] for p in beyond)
    assert all(p["stable"] for p in summary["path"] if p not in beyond)
    assert (out / "path.png").is_file()


def test_a_path_ended_by_max_steps_below_max_load_factor_says_so():
    """max_steps reached before max_load_factor: the status stays "converged" (a path study
    ends where the user bounded it), and the message says where and how to go on."""
    config = {"beam": {"length": 1.0}, "section": {"shape": "rectangle", "b": 0.01, "h": 0.01},
              "material": {"E": 2e11, "nu": 0.3}, "mesh": {"elements": 4, "degree": 2},
              "loads": {"tip_force": [0.0, -100.0]},
              "path": {"arc_length": 0.05, "max_arc_length": 1.0, "max_steps": 3},
              "output": {"xdmf": False, "plots": False}}
    summary = fe_beam.run("path", config)
    assert summary["status"] == "converged"
    last = summary["path"][-1]["load_factor"]
    assert last < 1.0
    assert "max_steps = 3" in summary["message"] and f"{last:.6g}" in summary["message"]

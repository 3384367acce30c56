"""``fe-beam static``: outputs of a run, --set, exit code 3 on a load that cannot converge, and
command-line mistakes (exit code 2, one sentence, no traceback)."""

import contextlib
import csv
import io
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest
from test_config import BASE, EI, dump_toml, edited, run_cli, usage_error

from fe_beam.cli import main

VENV_BIN = Path(sys.executable).parent


def run_in_process(folder: Path, config: dict, *extra):
    """Run ``fe-beam static`` in-process; returns (exit code, stderr, output folder)."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "c.toml"
    path.write_text(dump_toml(config))
    out = folder / "out"
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(["static", str(path), "--out", str(out), "--quiet", *extra])
    return code, err.getvalue(), out


def read_csv(path: Path) -> list[dict]:
    with path.open(newline="") as stream:
        return list(csv.DictReader(stream))


# --- a converged run -----------------------------------------------------------------------------
CANTILEVER = edited({"loads.steps": 10, "output.plots": True})


@pytest.fixture(scope="module")
def cantilever_run(tmp_path_factory):
    code, err, out = run_in_process(tmp_path_factory.mktemp("cantilever"), CANTILEVER)
    assert code == 0, err
    return out, json.loads((out / "summary.json").read_text())


def test_summary_structure(cantilever_run):
    _, summary = cantilever_run
    assert summary["status"] == "converged"
    assert isinstance(summary["wall_time_s"], float) and summary["wall_time_s"] > 0
    # mixed P2 (u, v, theta) on 8 elements: 3 * (2 * 8 + 1) dofs, no multipliers
    assert summary["dofs"] == 3 * (2 * 8 + 1)
    steps = summary["steps"]
    assert len(steps) >= 10  # at most 1/steps per increment
    for step in steps:
        assert set(step) >= {"load_factor", "tip", "newton_iterations"}
        assert set(step["tip"]) == {"u", "v", "theta"}
        assert all(isinstance(step["tip"][k], float) for k in ("u", "v", "theta"))
        assert isinstance(step["newton_iterations"], int) and step["newton_iterations"] >= 1
    factors = [s["load_factor"] for s in steps]
    assert all(0 < a < b for a, b in zip(factors, factors[1:], strict=False))
    assert all(b - a <= 0.1 + 1e-12 for a, b in zip([0.0] + factors, factors, strict=False))


def test_last_step_reaches_full_load(cantilever_run):
    _, summary = cantilever_run
    assert summary["steps"][-1]["load_factor"] == pytest.approx(1.0, abs=1e-12)
    tip = summary["steps"][-1]["tip"]
    # downward tip load: the tip goes down, rotates clockwise and the beam shortens
    assert tip["v"] < 0 and tip["theta"] < 0 and tip["u"] < 0


def test_last_step_load_factor_is_exactly_one(cantilever_run):
    _, summary = cantilever_run
    assert summary["steps"][-1]["load_factor"] == 1.0


def test_csv_matches_summary(cantilever_run):
    out, summary = cantilever_run
    rows = read_csv(out / "load_displacement.csv")
    assert len(rows) == len(summary["steps"])
    for row, step in zip(rows, summary["steps"], strict=True):
        assert float(row["load_factor"]) == step["load_factor"]
        for k in ("u", "v", "theta"):
            assert float(row[f"tip_{k}"]) == step["tip"][k]
        assert int(row["newton_iterations"]) == step["newton_iterations"]


def test_xdmf_and_plots_are_written(cantilever_run):
    out, summary = cantilever_run
    xdmf = (out / "beam.xdmf").read_text()
    times = sorted({float(t) for t in re.findall(r'<Time Value="([^"]+)"', xdmf)})
    assert times == pytest.approx([s["load_factor"] for s in summary["steps"]], rel=1e-15)
    for name in ("u", "v", "theta"):
        assert f'Attribute Name="{name}"' in xdmf
    for png in ("deformed_shapes.png", "load_displacement.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_set_override_changes_the_result(cantilever_run, tmp_path):
    _, base = cantilever_run
    code, err, out = run_in_process(
        tmp_path, CANTILEVER, "--set", "section.h=0.02", "--set", "output.plots=false"
    )
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["model"]["section"]["h"] == 0.02
    assert not (out / "deformed_shapes.png").exists()
    # 8x stiffer section under the same force: a much smaller deflection than the h = 0.01 beam
    stiff, soft = summary["steps"][-1]["tip"], base["steps"][-1]["tip"]
    assert abs(stiff["v"]) < 0.5 * abs(soft["v"])
    # k = P L^2 / EI = 2 / 8 = 0.25: just below linear theory v = P L^3 / (3 EI) (geometric
    # stiffening of the elastica is under 2 % at this load)
    linear = 2.0 * EI / (3 * 8 * EI)
    assert 0.98 * linear < -stiff["v"] < linear


# --- a load that cannot converge: exit code 3 ----------------------------------------------------
H, L = 0.01, 0.1
LIMIT = 2 / (3 * math.sqrt(0.9))  # max of k (1 - 0.3 k^2), k = h kappa: M_max = LIMIT * EI / h
M0 = 1.5 * LIMIT * EI / H
OVERLOAD = edited(
    {
        "beam.length": L,
        "loads.tip_force": [0.0, 0.0],
        "loads.tip_moment": M0,
        "loads.steps": 10,
        "solver.min_increment": 1e-3,
        "solver.max_rotation_jump": 50.0,
    }
)


@pytest.fixture(scope="module")
def overload_run(tmp_path_factory):
    code, err, out = run_in_process(tmp_path_factory.mktemp("overload"), OVERLOAD)
    return code, err, out, json.loads((out / "summary.json").read_text())


def test_overload_exits_3_naming_last_converged_factor(overload_run):
    code, err, _, summary = overload_run
    assert code == 3, err
    assert "Traceback" not in err
    match = re.search(r"last converged load factor ([0-9.eE+-]+)", err)
    assert match, err
    assert float(match.group(1)) == pytest.approx(summary["steps"][-1]["load_factor"], rel=1e-5)


def test_overload_summary_has_failed_status_and_converged_steps(overload_run):
    _, _, out, summary = overload_run
    assert summary["status"] == "failed"
    assert "last converged load factor" in summary["message"]
    steps = summary["steps"]
    assert steps, "the converged steps before the limit must be kept"
    factors = [s["load_factor"] for s in steps]
    assert all(a < b for a, b in zip(factors, factors[1:], strict=False))
    # no equilibrium beyond M_max = 0.703 EI/h (MODEL.md 6); stepping got close to it
    assert 0.9 * LIMIT < factors[-1] * M0 * H / EI <= LIMIT * (1 + 1e-6)
    assert len(read_csv(out / "load_displacement.csv")) == len(steps)
    assert (out / "beam.xdmf").is_file()


def test_overload_recorded_steps_are_pure_bending_equilibria(overload_run):
    """Every recorded step is a converged state: uniform curvature kappa = theta_tip / L with
    lambda M0 = EI kappa (1 - 0.3 h^2 kappa^2) (MODEL.md 6, non-standard law, rectangle)."""
    _, _, _, summary = overload_run
    for step in summary["steps"]:
        kappa = step["tip"]["theta"] / L
        moment = EI * kappa * (1 - 0.3 * H**2 * kappa**2)
        assert moment == pytest.approx(step["load_factor"] * M0, rel=1e-6)


# --- command-line mistakes -----------------------------------------------------------------------
@pytest.mark.parametrize(
    "assignment",
    ["section.h", "h=0.02", "section=0.02", "section..h=1", ".h=1", "=1", "beam.length.x=1"],
)
def test_malformed_set_exits_2(tmp_path, capsys, assignment):
    code, err, out, path = run_cli(tmp_path, BASE, "--set", assignment, capsys=capsys)
    message = usage_error(code, err, path)
    assert "--set" in message and assignment in message, message
    assert not out.exists()


def test_missing_config_file_exits_2(tmp_path, capsys):
    path = tmp_path / "nowhere.toml"
    code = main(["static", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    message = usage_error(code, capsys.readouterr().err, path)
    assert "nowhere.toml" in message and "does not exist" in message


@pytest.mark.parametrize(
    "text", ["[beam\nlength = 1.0\n", "[beam]\nlength = \n", "[beam]\nlength = 1.0\nlength = 2.0\n"]
)
def test_invalid_toml_exits_2(tmp_path, capsys, text):
    code, err, _, path = run_cli(tmp_path, text, capsys=capsys)
    assert "not valid TOML" in usage_error(code, err, path)


def test_non_utf8_config_exits_2(tmp_path, capsys):
    path = tmp_path / "latin1.toml"
    path.write_bytes(dump_toml(BASE).replace("[beam]", "# \xe9l\xe9ment\n[beam]").encode("latin-1"))
    try:
        code = main(["static", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    except UnicodeDecodeError:
        pytest.fail("UnicodeDecodeError escaped from fe_beam.cli.main")
    assert "TOML" in usage_error(code, capsys.readouterr().err, path)


def test_out_is_an_existing_file_exits_2(tmp_path, capsys):
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(edited({"loads.steps": 1, "output.plots": False})))
    out = tmp_path / "taken"
    out.write_text("not a folder")
    try:
        code = main(["static", str(path), "--out", str(out), "--quiet"])
    except OSError as error:
        pytest.fail(f"{type(error).__name__} escaped from fe_beam.cli.main")
    assert "--out" in usage_error(code, capsys.readouterr().err, path)


def test_out_below_a_file_exits_2_before_solving(tmp_path, capsys):
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(edited({"loads.steps": 1, "output.plots": False})))
    (tmp_path / "taken").write_text("not a folder")
    code = main(["static", str(path), "--out", str(tmp_path / "taken" / "run"), "--quiet"])
    message = usage_error(code, capsys.readouterr().err, path)
    assert "--out" in message and "is a file" in message, message


def test_real_process_exits_2_without_traceback(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(edited({"material.E": -1.0})))
    process = subprocess.run(
        [str(VENV_BIN / "fe-beam"), "static", str(path), "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert process.returncode == 2, process.stderr
    assert "Traceback" not in process.stderr
    assert process.stderr.count("\n") == 1, process.stderr
    assert "material.E" in process.stderr
    assert not (tmp_path / "out").exists()

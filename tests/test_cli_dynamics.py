"""``fe-beam dynamic`` and ``fe-beam modes``: a run's outputs and the exit-2 contract for
mistakes in the [time], [damping], [initial], [modes] tables and in load formulas."""

import json
import re
from pathlib import Path

import pytest
from test_config import BASE, dump_toml

from fe_beam.cli import main

DYNAMIC = {
    **BASE,
    "material": {"E": 1.0e7, "nu": 0.3, "rho": 1000.0},
    "section": {"shape": "rectangle", "b": 0.02, "h": 0.02},
    "loads": {"tip_force": [0.0, -0.2], "steps": 3, "time_function": "0"},
    "output": {"xdmf": False, "plots": False},
    "initial": {"from_static": True},
    "time": {"t_end": 0.2, "dt": 0.01, "rho_inf": 0.9},
    "mesh": {"elements": 6, "degree": 2},
}


def run(tmp_path, command, config, capsys, *extra):
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(config))
    out = tmp_path / "out"
    capsys.readouterr()
    code = main([command, str(path), "--out", str(out), "--quiet", *extra])
    return code, capsys.readouterr().err, out, path


def with_change(table, key, value):
    config = {name: dict(values) for name, values in DYNAMIC.items()}
    config.setdefault(table, {})[key] = value
    return config


def test_dynamic_run_writes_history(tmp_path, capsys):
    code, err, out, _ = run(tmp_path, "dynamic", DYNAMIC, capsys)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed"
    history = summary["history"]
    assert history[0]["t"] == 0.0 and history[-1]["t"] == pytest.approx(0.2)
    # released from the static state: starts at rest, bent, and moves up
    assert history[0]["tip"]["v"] < -0.1
    assert history[-1]["tip"]["v"] > history[0]["tip"]["v"]
    energies = history[-1]["energies"]
    total0 = history[0]["energies"]["strain"]
    assert energies["kinetic"] + energies["strain"] == pytest.approx(total0, rel=0.02)
    assert (out / "history.csv").read_text().count("\n") == len(history) + 1


def test_modes_run_writes_frequencies(tmp_path, capsys):
    config = with_change("modes", "count", 3)
    code, err, out, _ = run(tmp_path, "modes", config, capsys)
    assert code == 0, err
    frequencies = json.loads((out / "summary.json").read_text())["frequencies_hz"]
    assert len(frequencies) == 3
    # Euler-Bernoulli first cantilever frequency of this beam (L/h = 50: shear is negligible)
    EI, rho_area = 1.0e7 * 0.02**4 / 12, 1000.0 * 0.02**2
    first = 1.8751040687119611**2 * (EI / rho_area) ** 0.5 / (2 * 3.141592653589793)
    assert frequencies[0] == pytest.approx(first, rel=1e-3)


def test_modes_count_beyond_the_model_is_noted(tmp_path, capsys):
    """6 P2 elements, clamped: 3 x 13 - 3 = 36 free dofs, so exactly 36 modes (the Dirichlet
    rows' spurious pair, K = 1 against M = 0, is not one)."""
    code, err, out, _ = run(tmp_path, "modes", with_change("modes", "count", 500), capsys)
    assert code == 0, err
    found = len(json.loads((out / "summary.json").read_text())["frequencies_hz"])
    assert found == 36
    assert f"count = 500 asked for more modes than were found ({found}" in err


@pytest.mark.parametrize(
    ("table", "key", "value", "needle"),
    [
        ("time", "dt", 5.0, "time.dt"),
        ("time", "t_end", -1.0, "time.t_end"),
        ("time", "rho_inf", 1.5, "time.rho_inf"),
        ("time", "scheme", "rk4", "time.scheme"),
        ("time", "output_every", 0, "time.output_every"),
        ("time", "bogus", 1, "bogus"),
        ("damping", "c", -1.0, "damping.c"),
        ("damping", "kelvin_voigt", "x", "kelvin_voigt"),
        ("loads", "time_function", "__import__('os').system('true')", "__import__"),
        ("loads", "time_function", "t +", "not a formula"),
        ("loads", "time_function", "sin(q)", "unknown name 'q'"),
        ("material", "rho", 0.0, "rho"),
    ],
)
def test_dynamic_mistakes_exit_2(tmp_path, capsys, table, key, value, needle):
    code, err, out, path = run(tmp_path, "dynamic", with_change(table, key, value), capsys)
    assert code == 2, err
    assert "Traceback" not in err and err.count("\n") == 1, err
    assert err.startswith(f"fe-beam dynamic: error in {path}: "), err
    assert needle in err, err


def test_missing_time_table_exit_2(tmp_path, capsys):
    config = {name: values for name, values in DYNAMIC.items() if name != "time"}
    code, err, _, _ = run(tmp_path, "dynamic", config, capsys)
    assert code == 2 and "[time]" in err and "Traceback" not in err, err


@pytest.mark.parametrize("count", [0, -2, 2.5, "four"])
def test_modes_count_mistakes_exit_2(tmp_path, capsys, count):
    code, err, _, _ = run(tmp_path, "modes", with_change("modes", "count", count), capsys)
    assert code == 2 and re.search(r"modes\]? ?\.?count", err) and "Traceback" not in err, err


@pytest.mark.parametrize("example", ["release.toml", "spin_up.toml", "finger_dynamics.toml",
                                     "flying_spaghetti.toml"])
def test_examples_run(tmp_path, capsys, example):
    path = Path(__file__).parents[1] / "examples" / example
    out = tmp_path / "out"
    code = main(["dynamic", str(path), "--out", str(out), "--quiet", "--set", "time.t_end=0.1",
                 "--set", "output.xdmf=false", "--set", "output.plots=false"])
    assert code == 0, capsys.readouterr().err
    history = json.loads((out / "summary.json").read_text())["history"]
    assert history[-1]["t"] == pytest.approx(0.1)

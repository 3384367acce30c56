"""Inadmissible states (axial stretch 1 + e <= 0) are rejected, and strains outside the range
the model is meant for are reported (issue 9, item 2).

Axial compression of a cantilever by P (straight, so the states are known in closed form):
- Reissner: N = EA e, so e = -P / EA; the stretch 1 + e reaches 0 at P = EA: beyond load
  factor EA / P the only "solutions" are turned inside out;
- non-standard: the axial force lambda W_eps = EA lambda (lambda^2 - 1) / 2 is largest in
  compression at lambda = 1/sqrt(3), EA / (3 sqrt 3) = 0.1925 EA: no equilibrium beyond it.
"""

from __future__ import annotations

import json
import math
import re

import pytest
from mpi4py import MPI
from test_config import BASE, dump_toml

from fe_beam import (
    BeamModel,
    Discretisation,
    Loads,
    LoadStepping,
    Material,
    ModelOptions,
    Section,
    SolverSettings,
    Supports,
    runctl,
)
from fe_beam.analyses.static import solve_static
from fe_beam.cli import main
from fe_beam.fem.rod import StrainRange
from fe_beam.model.studies import StaticConfig

E, D = 1.0e7, 0.02  # a circular section (the case was a square)
AREA = math.pi * D**2 / 4
EA = E * AREA


def _compression(law: str, factor: float, elements: int = 12, steps: int = 5) -> BeamModel:
    return BeamModel(1.0, Section("circle", {"d": D}), Material(E, nu=0.3, rho=1000.0),
                     ModelOptions(law, "none"), Discretisation(elements, 2),
                     Supports("clamped", "free"), Loads(tip_force=(-factor * EA, 0.0)))


def _static(model, steps=5):
    config = StaticConfig(model, SolverSettings(), LoadStepping(steps=steps))
    return solve_static(config, None, MPI.COMM_WORLD, progress=False)


def _last_factor(message: str) -> float:
    match = re.search(r"last converged load factor ([0-9.eE+-]+)", message)
    assert match, message
    return float(match.group(1))


@pytest.mark.mpi
def test_reissner_beyond_ea_stops_at_the_last_admissible_factor():
    """P = 1.4 EA: 1 + e = 1 - 1.4 lambda; the last admissible load factor is just below
    1 / 1.4 and every recorded state has 1 + e > 0 (on 1 or 2 ranks)."""
    result = _static(_compression("reissner", 1.4))
    assert result.status == "failed"
    assert "inadmissible" in result.message
    last = _last_factor(result.message)
    assert 0.99 / 1.4 < last < 1 / 1.4
    assert result.steps[-1]["load_factor"] == pytest.approx(last, rel=1e-5)
    assert result.steps[-1]["tip"]["u"] > -1.0  # not folded beyond the clamp
    assert result.strain_range["min_stretch"] > 0


@pytest.mark.mpi
def test_nonstandard_compression_past_its_limit_is_not_reported_converged():
    """P = 0.6 EA (the issue: 0.5 EA gave u = -5.7 m, 'converged'): stops below the axial
    limit force EA / (3 sqrt 3), the last recorded state admissible."""
    result = _static(_compression("nonstandard", 0.6), steps=4)
    assert result.status == "failed"
    last = _last_factor(result.message)
    limit = 1 / (3 * math.sqrt(3)) / 0.6
    assert 0.97 * limit < last <= limit
    assert -1.0 < result.steps[-1]["tip"]["u"] < 0
    assert result.strain_range["min_stretch"] > 0


def _run_cli(tmp_path, command, config, capsys):
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(config))
    out = tmp_path / "out"
    capsys.readouterr()
    runctl.WARNED.clear()  # one CLI run per process: notes warned by an earlier test print again
    code = main([command, str(path), "--out", str(out), "--quiet"])
    return code, capsys.readouterr().err, json.loads((out / "summary.json").read_text())


def _config(law: str, tip_force, **tables) -> dict:
    config = {name: dict(values) for name, values in BASE.items()}
    config["section"] = {"shape": "circle", "d": D}
    config["material"] = {"E": E, "nu": 0.3, "rho": 1000.0}
    config["model"] = {"law": law, "constraint": "none"}
    config["loads"] = {"tip_force": list(tip_force), "steps": 5}
    config["output"] = {"xdmf": False, "plots": False}
    for name, values in tables.items():
        config.setdefault(name, {}).update(values)
    return config


def test_cli_compression_exit_3_names_the_last_admissible_factor(tmp_path, capsys):
    code, err, summary = _run_cli(tmp_path, "static", _config("reissner", [-1.4 * EA, 0.0]),
                                  capsys)
    assert code == 3, err
    assert "Traceback" not in err
    assert summary["status"] == "failed"
    last = _last_factor(err)
    assert 0.99 / 1.4 < last < 1 / 1.4
    assert summary["steps"][-1]["load_factor"] == pytest.approx(last, rel=1e-5)
    assert "inadmissible" in summary["message"]


def test_dynamic_step_into_an_inadmissible_state_is_rejected(tmp_path, capsys):
    """A sudden compression of 1.5 EA (Reissner): the axial wave folds the tip element; the
    time steps are cut back and the run ends with exit 3 at the last admissible time."""
    config = _config("reissner", [-1.5 * EA, 0.0],
                     loads={"time_function": "1"},
                     time={"t_end": 0.01, "dt": 0.001, "rho_inf": 0.9},
                     mesh={"elements": 6, "degree": 2})
    code, err, summary = _run_cli(tmp_path, "dynamic", config, capsys)
    assert code == 3, err
    assert summary["status"] == "failed"
    assert "inadmissible" in summary["message"]
    match = re.search(r"last converged time ([0-9.eE+-]+)", summary["message"])
    assert match, summary["message"]
    assert summary["history"][-1]["t"] == pytest.approx(float(match.group(1)), rel=1e-5)
    assert 0 < summary["history"][-1]["t"] < 0.01
    assert summary["strain_range"]["min_stretch"] > 0


def test_large_tension_is_noted_but_converges(tmp_path, capsys):
    """Tension 0.15 EA, non-standard: eps ~ 0.14 > 0.1: exit 0, a note in summary and stderr."""
    code, err, summary = _run_cli(tmp_path, "static", _config("nonstandard", [0.15 * EA, 0.0]),
                                  capsys)
    assert code == 0, err
    assert summary["status"] == "converged"
    assert any("|eps|" in note for note in summary["notes"]), summary["notes"]
    assert "warning" in err and "|eps|" in err
    assert summary["strain_range"]["max_abs_eps"] > 0.1


def test_ordinary_run_has_no_notes(tmp_path, capsys):
    code, err, summary = _run_cli(tmp_path, "static", _config("nonstandard", [0.0, -2e-3 * EA]),
                                  capsys)
    assert code == 0, err
    assert summary["notes"] == []
    assert "warning" not in err


def test_bending_near_the_largest_moment_is_noted():
    """Non-standard pure bending of a square h: M(kappa) = EI kappa (1 - 0.3 h^2 kappa^2),
    largest at kappa* = 1 / (h sqrt 0.9), M* = 0.703 EI / h. M = 0.97 M* needs
    kappa ~ 0.87 kappa* (> 80 %): noted; M = 0.5 M* (kappa ~ 0.36 kappa*): not noted."""
    h, length = 0.01, 0.05
    EI = E * h**4 / 12
    m_max = 2 / 3 * EI / (h * math.sqrt(0.9))
    notes = {}
    for share in (0.5, 0.97):
        model = BeamModel(length, Section("rectangle", {"b": h, "h": h}), Material(E, nu=0.3),
                          ModelOptions("nonstandard", "none"), Discretisation(20, 2),
                          Supports("clamped", "free"), Loads(tip_moment=share * m_max))
        result = _static(model, steps=10)
        assert result.status == "converged", result.message
        notes[share] = result.notes
        # the condensed tangent of the law vs the closed form EI (1 - (kappa / kappa*)^2)
        kappa = result.steps[-1]["tip"]["theta"] / length  # uniform curvature
        kappa_star = 1 / (h * math.sqrt(0.9))
        expected = 1 - (kappa / kappa_star) ** 2
        assert result.strain_range["min_bending_tangent"] == pytest.approx(expected, rel=1e-6)
    assert notes[0.5] == []
    assert any("limit curvature" in note for note in notes[0.97]), notes[0.97]


def test_strain_range_thresholds():
    assert StrainRange(0.5, 0.0, 0.0).inadmissible() is None
    assert "inadmissible" in StrainRange(0.0, 0.0, 0.0).inadmissible()
    assert "inadmissible" in StrainRange(float("nan"), 0.0, 0.0).inadmissible()
    assert StrainRange(1.0, 0.099, 0.099, 0.37).warnings() == []
    assert len(StrainRange(1.0, 0.101, 0.0).warnings()) == 1
    assert len(StrainRange(1.0, 0.0, 0.101).warnings()) == 1
    assert len(StrainRange(1.0, 0.0, 0.0, 0.35).warnings()) == 1


def test_finger_compressed_past_its_stretch_stops_at_the_last_admissible_factor(tmp_path,
                                                                                capsys):
    """`fe-beam finger` (tendons) with a Reissner law and a tip thrust of 1.4 EA at the tip
    section: the same rejection and exit 3 as `fe-beam static`."""
    from pathlib import Path

    example = Path(__file__).resolve().parents[1] / "examples" / "finger.toml"
    text = example.read_text().split("[inverse]")[0]
    text = text.replace('law = "nonstandard"', 'law = "reissner"')
    text = text.replace("elements = 40", "elements = 10")
    ea_tip = 0.6e6 * 0.02 * 0.01
    text = text.replace("[loads]", f"[loads]\ntip_force = [{-1.4 * ea_tip!r}, 0.0]")
    path = tmp_path / "finger.toml"
    path.write_text(text + "\n[output]\nplots = false\nxdmf = false\n")
    capsys.readouterr()
    code = main(["finger", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 3, err
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert "inadmissible" in summary["message"]
    assert summary["steps"][-1]["load_factor"] == pytest.approx(_last_factor(err), rel=1e-5)
    assert summary["strain_range"]["min_stretch"] > 0


def _column_modes_config(law: str, factor: float) -> dict:
    config = _config(law, [-factor * EA, 0.0], mesh={"elements": 8, "degree": 2})
    config["modes"] = {"count": 3, "prestress": True}
    return config


@pytest.mark.parametrize("command", ["modes", "dynamic"])
def test_prestate_past_the_axial_limit_fails_with_exit_3(tmp_path, capsys, command):
    """A modal or dynamic run about a static pre-state that has no admissible equilibrium
    (non-standard, P = 0.3 EA > EA / (3 sqrt 3)) is an analysis that did not complete: exit 3
    (not a configuration error, not an internal error), status failed, the last converged
    pre-state's load factor (just below 0.1925 / 0.3) named and written."""
    config = _column_modes_config("nonstandard", 0.3)
    if command == "dynamic":
        config["initial"] = {"from_static": True}
        config["time"] = {"t_end": 0.01, "dt": 0.001}
        config["loads"]["time_function"] = "1"
    code, err, summary = _run_cli(tmp_path, command, config, capsys)
    assert code == 3, err
    assert "Traceback" not in err and "internal error" not in err and "error in" not in err
    assert summary["status"] == "failed"
    last = _last_factor(summary["message"])
    limit = 1 / (3 * math.sqrt(3)) / 0.3
    assert 0.97 * limit < last <= limit
    assert summary["prestate"]["load_factor"] == pytest.approx(last, rel=1e-5)
    # straight compression: e = u' uniform, the tip shortening of the last admissible state
    assert -1.0 < summary["prestate"]["tip"]["u"] < 0
    assert summary["strain_range"]["min_stretch"] > 0
    assert any("|eps|" in note for note in summary["notes"])
    assert "warning" in err and "|eps|" in err
    if command == "modes":
        assert summary["frequencies_hz"] == []


def test_modes_about_a_strongly_compressed_prestate_warn_about_the_strain(tmp_path, capsys):
    """Reissner, P = 0.2 EA: e = -0.2, eps = ((0.8)^2 - 1) / 2 = -0.18 in the pre-state: the
    modes are computed (exit 0) but the strain is reported (summary notes + stderr warning)."""
    code, err, summary = _run_cli(tmp_path, "modes", _column_modes_config("reissner", 0.2),
                                  capsys)
    assert code == 0, err
    assert summary["strain_range"]["max_abs_eps"] == pytest.approx(0.18, rel=1e-6)
    assert any("|eps| = 0.18" in note for note in summary["notes"]), summary["notes"]
    assert "warning: the axial strain reaches |eps| = 0.18" in err
    assert err.count("|eps| = 0.18") == 1


@pytest.mark.parametrize("law", ["reissner", "nonstandard"])
def test_finite_difference_scheme_stops_at_the_first_inadmissible_state(tmp_path, capsys, law):
    """The paper's FD + Runge-Kutta scheme (scheme = fd-rk45) has no step to reject: under a
    sudden compression of 2 EA the wave front turns the tip intervals inside out within a few
    outputs (1 + e = 1 - 2 on a linear front). It used to report every output, inside-out
    ones included, as completed with exit 0; now the outputs stop at the last admissible one,
    exit 3, with the strain warning."""
    config = _config(law, [-2.0 * EA, 0.0], loads={"time_function": "1"},
                     time={"t_end": 0.002, "dt": 0.0002, "scheme": "fd-rk45"},
                     mesh={"elements": 5, "degree": 2})
    code, err, summary = _run_cli(tmp_path, "dynamic", config, capsys)
    assert code == 3, err
    assert summary["status"] == "failed" and "inadmissible" in summary["message"]
    assert 0 < len(summary["history"]) < 11
    assert summary["strain_range"]["min_stretch"] > 0
    # the tip of the last admissible output has not passed through its neighbour node
    assert summary["history"][-1]["tip"]["u"] > -0.2
    assert "warning" in err and "|eps|" in err


def test_finite_difference_scheme_without_static_pre_state_exit_3(tmp_path, capsys):
    """fd-rk45 from a static pre-state beyond the non-standard axial limit (0.3 EA >
    EA / (3 sqrt 3)): exit 3 and status failed (it used to be an internal error, exit 1)."""
    config = _config("nonstandard", [-0.3 * EA, 0.0], loads={"time_function": "1"},
                     time={"t_end": 0.002, "dt": 0.0002, "scheme": "fd-rk45"},
                     initial={"from_static": True}, mesh={"elements": 5, "degree": 2})
    code, err, summary = _run_cli(tmp_path, "dynamic", config, capsys)
    assert code == 3, err
    assert "internal error" not in err and "Traceback" not in err
    assert summary["status"] == "failed" and "static pre-state" in summary["message"]

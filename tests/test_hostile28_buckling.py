"""Issue 28, hostile pass: `fe-beam buckling` of a spatial rod under a dead moment.

A dead moment on a spatial rod has no potential (its work M . T(theta) dtheta), so the nonlinear
path's stability cannot confirm a linearised factor; the linearisation in the rotation vector
about the twisted pre-state is not even an estimate there. Greenhill's shaft, clamped at both
ends (the far end free to slide and twist) under an axial tip torque, buckles at
M = 8.99 EI / L (883 N m for a 10 mm steel shaft of 1 m): the command printed 6.32 N m as the
buckling torque, exit 0, while `fe-beam modes` with that pre-state at 10 N m found the shaft
stable with its first frequency unchanged to 3e-4. The estimates are no longer reported as
buckling loads (load_factors empty, linearised_load_factors kept, a message naming the
commands that check a load)."""

from __future__ import annotations

import json
import math

from tomlio import dump_toml

from fe_beam.cli import main

# an aluminium shaft (other material and section than the measured case)
E, NU, D, L = 7.0e10, 0.33, 0.008, 0.8


def shaft(torque: float) -> dict:
    return {"beam": {"length": L}, "section": {"shape": "circle", "d": D},
            "material": {"E": E, "nu": NU},
            "model": {"law": "reissner", "kinematics": "spatial"},
            "mesh": {"elements": 8, "degree": 2},
            "supports": {"x0": "clamped", "xL": ["v", "w", "theta_y", "theta_z"]},
            "loads": {"tip_force": [0.0, 0.0, 0.0], "tip_moment": [torque, 0.0, 0.0],
                      "steps": 2},
            "buckling": {"count": 1},
            "output": {"xdmf": False, "plots": False}}


def test_a_dead_torque_on_a_spatial_shaft_reports_no_unconfirmed_buckling_load(tmp_path,
                                                                              capsys):
    EI = E * math.pi * D**4 / 64
    greenhill = 8.99 * EI / L
    torque = 0.01 * greenhill
    path = tmp_path / "shaft.toml"
    path.write_text(dump_toml(shaft(torque)))
    code = main(["buckling", str(path), "--out", str(tmp_path / "out")])
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    # the linearised estimate is far below Greenhill's torque: it must not be a buckling load
    assert summary["linearised_load_factors"], summary
    assert summary["linearised_load_factors"][0] * torque < 0.1 * greenhill
    assert code == 0 and summary["status"] == "completed"
    assert summary["load_factors"] == [] and summary["critical_loads"] == []
    assert summary["reversed_load_factors"] == []
    assert "no confirmed buckling load" in summary["message"]
    printed = capsys.readouterr().out
    assert "no confirmed buckling load" in printed and "fe-beam modes" in printed

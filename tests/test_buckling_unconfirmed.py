"""`fe-beam buckling` with a load the path cannot confirm (issue 28, small items; section 1:
"a factor the path does not confirm is not printed as a buckling load"). A dead moment on a
spatial rod has no potential (its work depends on the rotation's path): the tangent is not
symmetric, the path's stability cannot confirm a critical point, and the command printed the
linearised factors as buckling loads with no check and no note. It now labels them linearised
estimates, NOT confirmed (printed header, a note naming why and the path command, summary
keys load_factors_confirmed = false, unconfirmed_reason, linearised_load_factors)."""

from __future__ import annotations

import json

import pytest
from tomlio import dump_toml

from fe_beam.cli import main


def _rod(loads: dict) -> dict:
    return {"beam": {"length": 0.6}, "section": {"shape": "rectangle", "b": 0.004, "h": 0.02},
            "material": {"E": 7.0e10, "nu": 0.33},
            "model": {"kinematics": "spatial", "law": "nonstandard"},
            "mesh": {"elements": 6}, "loads": loads, "buckling": {"count": 1},
            "output": {"xdmf": False, "plots": False}}


def _buckling(tmp_path, raw, capsys):
    path = tmp_path / "rod.toml"
    path.write_text(dump_toml(raw))
    out = tmp_path / "out"
    assert main(["buckling", str(path), "--out", str(out)]) == 0
    printed = capsys.readouterr()
    return json.loads((out / "summary.json").read_text()), printed.out, printed.err


@pytest.mark.parametrize("loads", [
    {"point_moments": [[0.6, 0.0, 40.0, 0.0]]},      # a dead moment about y at the tip
    {"point_moments": [[0.4, 0.0, 0.0, -25.0]], "tip_moment": [0.0, 0.0, -10.0]},
], ids=["point-moment-y", "moments-z"])
def test_dead_moment_factors_are_labelled_unconfirmed(tmp_path, capsys, loads):
    """No buckling load is reported (the linearisation about a twisted state is not even an
    estimate: tests/test_hostile28_buckling.py): the estimates stay in linearised_*, labelled."""
    summary, out, err = _buckling(tmp_path, _rod(loads), capsys)
    assert summary["status"] == "completed"
    assert summary["load_factors_confirmed"] is False
    assert summary["unconfirmed_reason"] == "a dead moment on a spatial rod"
    assert summary["linearised_load_factors"], summary
    assert summary["load_factors"] == [] and summary["reversed_load_factors"] == []
    assert "no confirmed buckling load" in summary["message"]
    assert "fe-beam path" in summary["message"] and "fe-beam path" in out


def test_conservative_load_is_confirmed_not_labelled(tmp_path, capsys):
    """A dead force (a potential): the path confirms, no "unconfirmed" label."""
    EI = 7.0e10 * 0.02 * 0.004**3 / 12
    raw = _rod({"tip_force": [-2.0 * 2.4674 * EI / 0.36, 0.0, 0.0]})
    raw["loads"]["tip_force"][1] = 1e-3  # a slight imperfection
    summary, out, _ = _buckling(tmp_path, raw, capsys)
    assert "load_factors_confirmed" not in summary
    assert "NOT confirmed" not in out

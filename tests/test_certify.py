"""The run-time certificates' verdict (`fe_beam.certify`): a failed check never leaves a run
"converged" (strict) nor silent (lenient); the config key [checks] strict is validated."""

import math

import pytest

from fe_beam import certify
from fe_beam.config.schema import check_values
from fe_beam.errors import ConfigError


def test_entry_passes_only_finite_values_within_tolerance():
    assert certify.entry("a", 1e-9, 1e-8)["passed"]
    assert not certify.entry("a", 2e-8, 1e-8)["passed"]
    assert not certify.entry("a", math.nan, 1.0)["passed"]
    assert not certify.entry("a", math.inf, math.inf)["passed"]
    assert not certify.entry("a", 0.0, 1.0, passed=False)["passed"]


def test_strict_failure_turns_success_into_failed():
    summary = {"status": "converged", "message": "",
               "checks": [certify.entry("global_equilibrium", 1e-3, 1e-8, detail="sum F",
                                        remedy="refine the mesh"),
                          certify.entry("stability", 0, 0)]}
    settled, lines = certify.settle(summary, strict=True)
    assert settled["status"] == "failed"
    assert "global_equilibrium" in settled["message"] and "refine the mesh" in settled["message"]
    assert settled["checks_passed"] is False
    assert len(lines) == 1


def test_lenient_failure_is_a_visible_warning():
    summary = {"status": "completed", "notes": [],
               "checks": [certify.entry("energy_balance", 0.2, 0.01)]}
    settled, lines = certify.settle(summary, strict=False)
    assert settled["status"] == "completed"
    assert settled["checks_passed"] is False and settled["checks_strict"] is False
    assert any("energy_balance" in note for note in settled["notes"])
    assert lines


def test_passing_checks_leave_the_run_alone():
    summary = {"status": "converged", "checks": [certify.entry("x", 0.0, 1e-12)]}
    settled, lines = certify.settle(dict(summary), strict=True)
    assert settled["status"] == "converged" and settled["checks_passed"] is True and not lines


def test_strict_key_is_validated():
    check_values({"checks": {"strict": False}})
    assert certify.strict_of({"checks": {"strict": False}}) is False
    assert certify.strict_of({}) is True
    with pytest.raises(ConfigError, match=r"\[checks\] strict"):
        check_values({"checks": {"strict": "no"}})
    with pytest.raises(ConfigError, match="unknown key"):
        check_values({"checks": {"strickt": True}})


# --- the verdict through the CLI and fe_beam.run: a stand-in driver reports a failed check ---
CASE = {"beam": {"length": 1.0}, "section": {"b": 0.1, "h": 0.01},
        "material": {"E": 1e9, "nu": 0.3}, "mesh": {"elements": 2, "degree": 1},
        "loads": {"tip_force": [0.0, -1.0]}}


def _stand_in(passed: bool):
    """A stand-in static driver (installed in sys.modules, where `fe_beam.cli.analysis` looks
    first) whose run claims success with one check."""
    import types

    from fe_beam.analyses.result import Result
    from fe_beam.exports.outputs import atomic_write_json

    def run(validated, out, comm, progress=True, echo=None):
        summary = {"status": "converged", "message": "", "notes": [],
                   "checks": [certify.entry("global_equilibrium", 0.0 if passed else 0.5, 1e-8)]}
        if out is not None:
            out.mkdir(parents=True, exist_ok=True)
            atomic_write_json(out / "summary.json", summary)
        return Result("static", summary, 0, [])

    return types.SimpleNamespace(run=run)


@pytest.mark.parametrize("out", [True, False])
def test_failed_check_is_a_failed_run(monkeypatch, tmp_path, out):
    import json
    import sys

    import fe_beam

    monkeypatch.setitem(sys.modules, "fe_beam.analyses.static", _stand_in(passed=False))
    folder = tmp_path / "run" if out else None
    summary = fe_beam.run("static", CASE, out=folder)
    assert summary["status"] == "failed" and summary["checks_passed"] is False
    assert "global_equilibrium" in summary["message"]
    if out:  # the file says the same
        assert json.loads((folder / "summary.json").read_text())["status"] == "failed"
    lenient = fe_beam.run("static", CASE, out=folder, **{"checks.strict": False})
    assert lenient["status"] == "converged" and lenient["checks_passed"] is False
    assert any("global_equilibrium" in note for note in lenient["notes"])
    monkeypatch.setitem(sys.modules, "fe_beam.analyses.static", _stand_in(passed=True))
    assert fe_beam.run("static", CASE, out=folder)["status"] == "converged"


def test_cli_exit_code_of_a_failed_check(monkeypatch, tmp_path, capsys):
    import sys

    from tomlio import dump_toml

    from fe_beam import cli

    path = tmp_path / "case.toml"
    path.write_text(dump_toml(CASE))
    monkeypatch.setitem(sys.modules, "fe_beam.analyses.static", _stand_in(passed=False))
    code = cli.main(["static", str(path), "--out", str(tmp_path / "o"), "--quiet"])
    assert code == 3
    assert "not certified" in capsys.readouterr().err


def test_line_says_why_a_check_failed():
    assert "exceeds" in certify.line(certify.entry("a", 2.0, 1.0))
    forced = certify.line(certify.entry("b", 0.0, 0.0, passed=False))
    assert "failed" in forced and "exceeds" not in forced
    assert "<=" in certify.line(certify.entry("c", 0.5, 1.0))

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

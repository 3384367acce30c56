"""Load steps that grow (`[solver] max_increment`, `easy_iterations`) on the rod and the finger:
the keys reach the run whatever sets the number of steps, bad combinations are usage errors,
a vetoed grown step is retried at the first increment, and growth never changes the answer."""

import copy
from pathlib import Path

import numpy as np
import pytest

from fe_beam.config.finger import parse_finger
from fe_beam.config.schema import load_config, parse_static
from fe_beam.config.transient import parse_dynamic
from fe_beam.errors import ConfigError

EXAMPLES = Path(__file__).parents[1] / "examples"


def finger_raw(tendon_steps=None, **solver) -> dict:
    raw = load_config(EXAMPLES / "finger.toml")
    if tendon_steps is not None:
        raw["tendons"][0]["steps"] = tendon_steps
    raw.setdefault("solver", {}).update(solver)
    return raw


def test_finger_max_increment_counts_the_tendons_steps():
    """A tendon asking for 40 steps with loads.steps = 20: the first increment is 1/40, so
    max_increment 0.04 is allowed (it was refused against loads.steps) and 0.05 lets steps
    grow (it was silently reset to one step)."""
    raw = finger_raw(40)
    assert raw["loads"]["steps"] < 40
    assert parse_finger(copy.deepcopy(raw))[0].stepping.max_increment == pytest.approx(1 / 40)
    for value in (0.04, 0.05):
        stepping = parse_finger(finger_raw(40, max_increment=value))[0].stepping
        assert stepping.steps == 40 and stepping.max_increment == pytest.approx(value)
    with pytest.raises(ConfigError, match="max_increment.*tendons' steps = 40"):
        parse_finger(finger_raw(40, max_increment=0.02))


def test_dynamic_finger_prestate_keeps_max_increment():
    raw = load_config(EXAMPLES / "finger_dynamics.toml")
    raw.setdefault("solver", {})["max_increment"] = 0.5
    config = parse_dynamic(raw)
    assert config.static.stepping.max_increment == pytest.approx(0.5)


@pytest.mark.parametrize("solver, words", [
    ({"adaptive": False, "max_increment": 0.5}, "needs adaptive = true"),
    ({"easy_iterations": 0}, "easy_iterations must be an integer >= 1"),
    ({"easy_iterations": 2.5}, "easy_iterations"),
    ({"max_increment": 1.5}, "max_increment must be between"),
])
def test_growth_settings_mistakes(solver, words):
    raw = load_config(EXAMPLES / "cantilever.toml")
    raw["solver"] = solver
    with pytest.raises(ConfigError, match=words):
        parse_static(raw)


def test_steps_mistake_is_named_before_max_increment():
    raw = load_config(EXAMPLES / "cantilever.toml")
    raw["loads"]["steps"] = 0
    raw["solver"] = {"max_increment": 0.5}
    with pytest.raises(ConfigError) as error:
        parse_static(raw)
    assert "steps" in str(error.value) and "max_increment" not in str(error.value)


def run_static(raw: dict):
    from fe_beam.analyses.static import solve_static

    result = solve_static(parse_static(raw), progress=False)
    assert result.status != "failed", result.message
    return result.steps[-1]["tip"], result.steps


def test_easy_iterations_lets_the_cantilever_grow_to_the_same_answer():
    """The cantilever takes 5-6 Newton iterations per step, above the default easy count (4),
    so max_increment alone does not grow its steps; with easy_iterations = 8 it does, and the
    tip is that of the fixed steps (each is an equilibrium solved to the Newton tolerance)."""
    raw = load_config(EXAMPLES / "cantilever.toml")
    raw["output"] = {"xdmf": False, "plots": False}
    fixed_tip, fixed = run_static(copy.deepcopy(raw))
    raw["solver"] = {"max_increment": 1.0}
    _, same = run_static(copy.deepcopy(raw))
    raw["solver"]["easy_iterations"] = 8
    grown_tip, grown = run_static(copy.deepcopy(raw))
    assert len(same) == len(fixed) == raw["loads"]["steps"]
    assert len(grown) < len(fixed)
    for key in ("u", "v", "theta"):
        assert grown_tip[key] == pytest.approx(fixed_tip[key], rel=1e-7, abs=1e-12)


def test_vetoed_grown_step_is_retried_at_the_first_increment(monkeypatch):
    """A branch-jump veto cuts the grown step back to no less than the first increment (the
    step load control without growth takes): every accepted increment stays >= 1/steps."""
    from fe_beam.solvers import continuation

    vetoes = []
    jump = continuation.Continuation._branch_jump

    def always(self, *args):
        jump(self, *args)
        vetoes.append(1)
        return "branch jump: forced by the test"

    monkeypatch.setattr(continuation.Continuation, "_branch_jump", always)
    raw = load_config(EXAMPLES / "cantilever.toml")
    raw["output"] = {"xdmf": False, "plots": False}
    raw["solver"] = {"max_increment": 1.0, "easy_iterations": 8}
    _, steps = run_static(raw)
    factors = np.array([0.0] + [s["load_factor"] for s in steps])
    assert vetoes, "no grown step was tried"
    n = raw["loads"]["steps"]
    assert np.all(np.diff(factors) >= 1 / n - 1e-12)
    assert len(steps) == n

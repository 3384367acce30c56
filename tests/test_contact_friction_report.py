"""The friction force a contact report gives is the one the solver applied (issue 28): after a
step is accepted (`ContactSet.commit`) the summary, made after the commit, used to read the
stuck points' traction lambda_t - k s with the next step's reference points already in place
(s = 0) and so the stale multiplier of the last update: off by k s (measured 5e-5 of the
friction force on a pressed tip held over several steps, 2 % elsewhere). The reference is the
reaction-derived contact force: minus the sum of the support reactions and the applied loads
(`fe_beam.fem.equilibrium.rod_wrenches` without contact), to round-off."""

import numpy as np
import pytest

from fe_beam.analyses.certificates import EQUILIBRIUM_FLOOR, equilibrium_entry
from fe_beam.config.registry import validate
from fe_beam.fem.equilibrium import rod_wrenches
from fe_beam.model.settings import LoadStepping
from fe_beam.solvers.rod_static import StaticContinuation

L, B, H = 1.0, 0.01, 0.01
E = 12 / (B * H**3)  # EI = 1
MU = 0.3
RADIUS = {False: H / 2, True: np.hypot(B, H) / 2}  # planar: h/2, spatial: the circumradius


def config(spatial: bool, tip: list, steps: int, elements: int = 8) -> dict:
    z = [0.0] if spatial else []
    return {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "unshearable",
                  **({"kinematics": "spatial"} if spatial else {})},
        "mesh": {"elements": elements, "degree": 2},
        "loads": {"tip_force": tip + z, "steps": steps},
        "solver": {"atol": 1e-10},
        "obstacles": [{"shape": "plane", "name": "floor",
                       "point": [0.0, -1e-4 - RADIUS[spatial]] + z,
                       "normal": [0.0, 1.0] + z, "friction": MU}],
        "contact": {"penetration_tolerance": 1e-9},
        "output": {"xdmf": False, "plots": False},
    }


def reported_against_applied(spatial: bool, tip: list, steps: int) -> list:
    """Per accepted step: (reported contact entry, the reaction-derived contact force)."""
    parsed = validate("static", config(spatial, tip, steps)).parsed
    run = StaticContinuation(parsed)
    records = []

    def record(step) -> None:
        (entry,) = run.contact.summary()
        applied = -sum(term.force for term in rod_wrenches(run.problem, None))
        check = equilibrium_entry(run.problem, 1e-12, [entry])
        records.append((entry, applied, check, run.contact.summary()))

    run.advance(1.0, LoadStepping(steps=steps), on_converged=record)
    return records


@pytest.mark.parametrize("spatial", [False, pytest.param(True, marks=pytest.mark.slow)],
                         ids=["planar", "spatial"])
def test_stuck_friction_report_is_the_applied_traction(spatial):
    """A cantilever's tip pressed on a floor over three steps (cut back by the contact's
    step control): the tip sticks from the first touch on (the corner rolls: friction far
    below mu N, no slip interval at the end), and the friction force reported at each step is
    the reaction-derived one to 1e-9 of the contact force; the global equilibrium with the
    reported forces balances to round-off. The planar tip slips at its first touch (mu N): a
    slipping step's report is checked too."""
    records = reported_against_applied(spatial, [0.0, -1.0], 3)
    assert len(records) >= 3
    assert records[-1][0]["slip"] == []  # stuck
    slipped = False
    for entry, applied, check, again in records:
        normal = np.asarray(entry["force"]) - np.asarray(entry["friction_force"])
        friction = np.asarray(entry["friction_force"])
        dim = len(friction)
        bound = MU * np.linalg.norm(normal)
        if entry["slip"]:  # the first touch slips: mu N
            slipped = True
            assert np.linalg.norm(friction) == pytest.approx(bound, rel=1e-9)
        assert 0 < np.linalg.norm(friction) <= bound * (1 + 1e-9)
        scale = 1.0  # the full tip load [N]: Newton atol 1e-10 bounds the round-off
        assert np.abs(friction[0] - applied[0]) <= 1e-9 * scale, (friction, applied)
        assert np.abs(np.asarray(entry["force"]) - applied[:dim]).max() <= 1e-9 * scale
        assert check["value"] <= EQUILIBRIUM_FLOOR, check["detail"]  # 1e-7; stale: 7e-7
        assert again == [entry]  # reporting twice changes nothing
    if not spatial:
        assert slipped  # a slipping step's report is right too

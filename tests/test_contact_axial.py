"""A rod pushed along its axis into a wall (issue 28, section 3): the end's default
augmentation stiffness follows the stiffness the contact acts against, the axial EA / h_e as
well as the bending EI / h_e^3, so the Uzawa updates converge in a few solves per step and the
wall carries the push beyond first touch: R = P - EA g / L (the rod's elongation closes the gap
g at P_touch = EA g / L, then the tip stays on the wall)."""

import numpy as np
import pytest

from fe_beam.analyses.static import solve_static
from fe_beam.config.registry import validate

L, B, H, E = 0.5, 0.02, 0.005, 7.0e10
EA = E * B * H
GAP = 4e-6
P_TOUCH = EA * GAP / L
P = 3.5 * P_TOUCH
STEPS = 7


def pushed(law: str, angle: float = 0.0) -> dict:
    """The tip force P along the axis (``angle``: the wall's normal tilted by it in the x-y
    plane, a wall met obliquely by the flat end face's corner)."""
    normal = [-np.cos(angle), np.sin(angle)]
    return {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": 0.33},
        "model": {"law": law},
        "mesh": {"elements": 6, "degree": 2},
        "supports": {"x0": "clamped", "xL": "free"},
        "loads": {"tip_force": [P, 0.0], "steps": STEPS},
        "obstacles": [{"shape": "plane", "name": "wall", "point": [L + GAP, 0.0],
                       "normal": normal}],
        "output": {"xdmf": False, "plots": False},
    }


@pytest.mark.parametrize("law", ["nonstandard", "reissner"])
def test_axial_push_into_a_wall_converges_in_few_iterations_with_the_right_force(law):
    result = solve_static(validate("static", pushed(law)).parsed, None, progress=False,
                          record_shapes=False)
    assert result.status == "converged", result.message
    steps = result.steps
    # no cut-backs, and a few Newton solves per step (before: ~75 per step, 36 steps)
    assert len(steps) == STEPS
    iterations = [step["newton_iterations"] for step in steps]
    assert np.mean(iterations) < 15, iterations
    for step in steps:
        load = step["load_factor"] * P
        force = -step["contact"][0]["force"][0]
        expected = max(load - P_TOUCH, 0.0)
        # the force tolerance 1e-3 of the contact force (floor: EI / L^2)
        assert abs(force - expected) <= 2e-3 * max(expected, 1.0), (step["load_factor"], force,
                                                                     expected)
        assert step["contact"][0]["force"][1] == pytest.approx(0.0, abs=1e-9 * P)

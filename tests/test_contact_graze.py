"""A first touch exactly at the end of a load step (issue 28, section 3): a cantilever under a
uniform load q above a plane whose gap g closes at q1 = 8 EI g / L^4, the load steps ending at
q1. The accepted state grazes the plane with no pressure; the next step starts with the
grazing points active (`fe_beam.fem.contact.ContactSet.restore`) instead of sinking the rod
through the plane and releasing the active set point by point over tens of updates. The
propped cantilever's tip reaction then follows R = 3 q L / 8 - 3 EI g / L^3 (small
deflection, q1 < q < 9 q1)."""

import pytest

from fe_beam.analyses.static import solve_static
from fe_beam.config.registry import validate

L, B, H, E = 1.0, 0.01, 0.01, 7.0e10
EI = E * B * H**3 / 12
GAP = 8e-3
Q1 = 8 * EI * GAP / L**4


@pytest.mark.parametrize("law, steps", [("nonstandard", 3), ("reissner", 4)])
def test_a_first_touch_at_a_step_end_takes_few_iterations_and_the_right_reaction(law, steps):
    q = steps * Q1  # the touch ends the first step
    config = {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": 0.3},
        "model": {"law": law},
        "mesh": {"elements": 24, "degree": 2},
        "loads": {"distributed": [0.0, -q], "steps": steps},
        "obstacles": [{"shape": "plane", "name": "floor", "point": [0.0, -GAP - H / 2],
                       "normal": [0.0, 1.0]}],
        "output": {"xdmf": False, "plots": False},
    }
    result = solve_static(validate("static", config).parsed, None, progress=False,
                          record_shapes=False)
    assert result.status == "converged", result.message
    assert [s["load_factor"] for s in result.steps] == pytest.approx(
        [(i + 1) / steps for i in range(steps)])  # no cut-back
    touch, after = result.steps[0], result.steps[1]
    assert touch["contact"][0]["force"][1] <= 1e-4 * q * L  # a graze
    # before: 32 Newton iterations (the active set released point by point); after: 9
    assert after["newton_iterations"] <= 15, after["newton_iterations"]
    for step in result.steps[1:]:
        load = step["load_factor"] * q
        reaction = 3 * load * L / 8 - 3 * EI * GAP / L**3
        # small deflection: g / L = 8e-3 leaves a geometric correction of order (g / L)
        assert step["contact"][0]["force"][1] == pytest.approx(reaction, rel=2e-2)


def test_a_first_touch_of_a_post_under_a_mesh_vertex_at_a_step_end():
    """A cylinder (a post of radius 0.1 m) under the mesh vertex x = a = L / 2 of a uniformly
    loaded cantilever, touched exactly at the end of the first step: the next steps follow the
    cantilever propped at a, R = 3 EI (v_q(a) - g) / a^3 with v_q(a) = q a^2 (6 L^2 - 4 L a +
    a^2) / (24 EI), in few iterations (before: 20 in the step after the touch; after: 9)."""
    a, radius, gap, steps = L / 2, 0.1, 2e-3, 3
    touch = 24 * EI * gap / (a**2 * (6 * L**2 - 4 * L * a + a**2))
    q = steps * touch
    config = {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": 0.3},
        "model": {"law": "nonstandard"},
        "mesh": {"elements": 24, "degree": 2},
        "loads": {"distributed": [0.0, -q], "steps": steps},
        "obstacles": [{"shape": "cylinder", "name": "post",
                       "point": [a, -H / 2 - gap - radius], "radius": radius}],
        "output": {"xdmf": False, "plots": False},
    }
    result = solve_static(validate("static", config).parsed, None, progress=False,
                          record_shapes=False)
    assert result.status == "converged", result.message
    assert len(result.steps) == steps
    assert result.steps[1]["newton_iterations"] <= 14, result.steps[1]["newton_iterations"]
    for step in result.steps[1:]:
        load = step["load_factor"] * q
        free = load * a**2 * (6 * L**2 - 4 * L * a + a**2) / (24 * EI)
        reaction = 3 * EI * (free - gap) / a**3
        assert step["contact"][0]["force"][1] == pytest.approx(reaction, rel=2e-2)

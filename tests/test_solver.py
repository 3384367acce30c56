"""Newton convergence tests of `fe_beam.solver`: what counts as converged must not depend on
the load-step size, the predictor, round-off or a zero load."""

from dataclasses import replace

import numpy as np
import pytest
from beam_cases import bending_stiffness, cantilever, solve
from mpi4py import MPI

from fe_beam import BeamProblem, Loads, LoadStepping, Material, SolverSettings
from fe_beam.config import StaticConfig
from fe_beam.solver import NonlinearProblem, SNESSolver
from fe_beam.static import solve_static

EI = bending_stiffness(0.01)


def test_zero_load_converges_at_once_to_the_reference_state():
    result = solve(cantilever(tip_force=(0.0, 0.0)), steps=3)
    assert all(step["newton_iterations"] <= 1 for step in result.steps)
    assert all(value == 0.0 for value in result.steps[-1]["tip"].values())


@pytest.mark.parametrize("constraint", ["inextensible-unshearable", "none"])
def test_answer_does_not_depend_on_the_number_of_load_steps(constraint):
    """The secant predictor breaks the constraints (rows in other units than forces); the
    residual test is relative to the plain load increment, so 2 and 10 steps agree to
    round-off (they differed by 1e-7 L when rtol was relative to the predicted state)."""
    tips = [solve(cantilever(constraint=constraint, elements=16, tip_force=(0.0, -2 * EI)),
                  steps=steps).steps[-1]["tip"] for steps in (2, 10)]
    for key in ("u", "v", "theta"):
        assert tips[0][key] == pytest.approx(tips[1][key], abs=1e-10)


@pytest.mark.parametrize("elements", [64, 128])
def test_round_off_floor_of_a_stiff_constrained_beam_is_accepted(elements):
    """Steel, degree 2, multipliers: the residual stalls at round-off above rtol times the first
    residual; Newton stagnation far below the load step's residual counts as converged."""
    model = cantilever(elements=elements, tip_force=(0.0, -2 * EI))
    steel = replace(model, material=Material(2.0e11, nu=0.3),
                    loads=Loads(tip_force=(0.0, -2 * bending_stiffness(0.01) * 2.0e4)))
    config = StaticConfig(steel, SolverSettings(), LoadStepping(steps=10))
    result = solve_static(config, None, progress=False, record_shapes=False)
    assert result.status == "converged", result.message
    reference = solve(cantilever(elements=elements, tip_force=(0.0, -2 * EI)))
    assert result.steps[-1]["tip"]["v"] == pytest.approx(reference.steps[-1]["tip"]["v"],
                                                         rel=1e-10)


def test_tiny_state_converges_on_the_step_size():
    """A state of 1e-9 L: the residual is at round-off level from the start; the step test,
    measured against the beam length, accepts it after one or two iterations."""
    problem = BeamProblem(cantilever(tip_force=(0.0, -1e-9 * EI)), MPI.COMM_WORLD)
    problem.set_load_factor(1.0)
    solver = SNESSolver(NonlinearProblem(problem.residual, problem.w, problem.bcs),
                        SolverSettings(), state_scale=1.0)
    iterations = solver.solve()
    assert iterations <= 3
    tip = problem.end_values()
    assert tip["v"] == pytest.approx(-1e-9 / 3, rel=1e-4)
    assert np.isfinite(tip["theta"])
    solver.destroy()

"""Newton convergence tests of `fe_beam.solvers.newton`: what counts as converged must not depend on
the load-step size, the predictor, round-off or a zero load."""

from dataclasses import replace

import numpy as np
import pytest
from beam_cases import bending_stiffness, cantilever, solve
from mpi4py import MPI

from fe_beam import BeamProblem, Loads, LoadStepping, Material, SolverSettings
from fe_beam.analyses.static import solve_static
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers.newton import NonlinearProblem, SNESSolver

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


def _tiny_cantilever_solver(linear_solver, prefix):
    problem = BeamProblem(cantilever(constraint="none", elements=4, tip_force=(0.0, -0.1 * EI)),
                          MPI.COMM_WORLD)
    problem.set_load_factor(1.0)
    return SNESSolver(NonlinearProblem(problem.residual, problem.w, problem.bcs),
                      SolverSettings(linear_solver=linear_solver), prefix=prefix, state_scale=1.0)


def test_a_destroyed_solver_leaves_no_options_behind():
    """Options of one solver must not leak into the next one with the same prefix (LU after
    MUMPS used to factorise with MUMPS), nor pile up towards PETSc's 512-option limit."""
    from petsc4py import PETSc

    count = len(PETSc.Options().getAll())
    first = _tiny_cantilever_solver("mumps", "reused_prefix_")
    first.solve()
    assert first.snes.getKSP().getPC().getFactorSolverType() == "mumps"
    first.destroy()
    assert len(PETSc.Options().getAll()) == count
    second = _tiny_cantilever_solver("lu", "reused_prefix_")
    second.solve()
    assert second.snes.getKSP().getPC().getFactorSolverType() == "petsc"
    second.destroy()
    assert len(PETSc.Options().getAll()) == count


def test_linear_solve_leaves_no_options_behind():
    import ufl
    from dolfinx import fem
    from petsc4py import PETSc

    from fe_beam.fem import compat

    mesh = compat.create_interval(MPI.COMM_WORLD, 8, 1.0)
    space = compat.function_space(mesh, compat.element(mesh, "Lagrange", 1))
    target = fem.Function(space)
    trial, test = ufl.TrialFunction(space), ufl.TestFunction(space)
    count = len(PETSc.Options().getAll())
    for _ in range(3):
        compat.solve_linear(trial * test * ufl.dx, 2.0 * test * ufl.dx, [], target)
    assert len(PETSc.Options().getAll()) == count
    assert np.allclose(compat.local_array(target), 2.0, atol=1e-12)


def test_a_singular_system_is_a_failed_solve_not_a_crash():
    """Free-free statics (the CLI refuses it; the API does not): PETSc's factorisation error
    becomes a failed load step, and load stepping reports the last converged load factor."""
    from fe_beam import Supports

    model = replace(cantilever(tip_force=(0.0, -1e-3 * EI)), supports=Supports("free", "free"))
    config = StaticConfig(model, SolverSettings(), LoadStepping(steps=2))
    result = solve_static(config, None, progress=False, record_shapes=False)
    assert result.status == "failed"
    assert "PETSc error" in result.message and "last converged load factor 0" in result.message


@pytest.mark.parametrize("linear_solver", ["lu", "gmres-ilu", "gamg"])
def test_other_linear_solvers_give_the_mumps_answer(linear_solver):
    """Unconstrained beam, L/h = 100: every linear solver lands on the same equilibrium."""
    model = cantilever(constraint="none", elements=16, tip_force=(0.0, -3 * EI))
    reference = solve(model, steps=4).steps[-1]["tip"]
    other = solve(model, steps=4, linear_solver=linear_solver).steps[-1]["tip"]
    for key in ("u", "v", "theta"):
        assert other[key] == pytest.approx(reference[key], rel=1e-8, abs=1e-12)


class _Comm:
    def __init__(self, size):
        self.size = size


@pytest.mark.parametrize(("saddle_point", "ranks", "chosen"),
                         [(False, 1, "lu"), (True, 1, "mumps"), (False, 2, "mumps")])
def test_auto_linear_solver_takes_lu_only_where_it_is_safe(saddle_point, ranks, chosen):
    settings = SolverSettings()
    assert settings.linear_solver == "auto"
    assert settings.for_problem(saddle_point, _Comm(ranks)).linear_solver == chosen
    assert SolverSettings(linear_solver="mumps").for_problem(False, _Comm(1)).linear_solver == (
        "mumps")


@pytest.mark.parametrize(("constraint", "factor"), [("none", "petsc"),
                                                     ("inextensible-unshearable", "mumps")])
def test_static_runs_factorise_with_the_resolved_solver(constraint, factor):
    from fe_beam.analyses.static import StaticContinuation

    model = cantilever(constraint=constraint, elements=4, tip_force=(0.0, -EI))
    run = StaticContinuation(StaticConfig(model, SolverSettings(), LoadStepping(steps=1)),
                             MPI.COMM_SELF)
    run.advance(1.0, LoadStepping(steps=1))
    assert run.snes.snes.getKSP().getPC().getFactorSolverType() == factor
    run.destroy()

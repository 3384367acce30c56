"""Issue 20, item 1: a RealtimeSolver after an UpdateFailed (or any failed Newton) must go on
giving the equilibria of a fresh solve: a diverged trial must leave no trace (round-off floor
of the convergence test, the dense LU of the predictor, the tendon set's values); a tendon
moved outside the section is refused."""

from dataclasses import replace

import numpy as np
import pytest
from mpi4py import MPI

from fe_beam.analyses.finger import parse_finger
from fe_beam.analyses.static import solve_static
from fe_beam.config import ConfigError
from fe_beam.solvers.realtime import RealtimeSolver, UpdateFailed, set_parameters

# the two answers agree to the Newton tolerance (rtol 1e-11 of the load steps' residual)
TOL = 1e-8


def finger(elements=12) -> object:
    """The chapter's finger (non-standard law, tapered, one tendon), another mesh than the
    example's 40 elements."""
    config, _ = parse_finger({"mesh": {"elements": elements, "degree": 2},
                              "loads": {"steps": 10}, "solver": {"rtol": 1e-11},
                              "output": {"plots": False, "xdmf": False}})
    return config


def fresh_tip(config, comm=MPI.COMM_WORLD) -> dict:
    result = solve_static(config, None, comm, progress=False, record_shapes=False)
    assert result.status == "converged", result.message
    return result.steps[-1]["tip"]


def residual(solver) -> float:
    return solver.run.snes.residual_norm()


def assert_fresh(solver, tip, config, comm=MPI.COMM_WORLD):
    reference = fresh_tip(config, comm)
    for key in ("u", "v", "theta"):
        scale = 1.0 if key == "theta" else config.model.length
        assert abs(tip[key] - reference[key]) <= TOL * scale, (key, tip[key], reference[key])
    # and the state is an equilibrium to the solver's own tolerance
    assert residual(solver) <= solver.run.snes.snes.getTolerances()[1] * 10


@pytest.mark.mpi
@pytest.mark.parametrize("check", [True, False])
def test_tensions_after_a_failed_update_are_fresh_equilibria(check):
    """2.5 N, then 8000 N (no equilibrium reachable: UpdateFailed), then 0.9, 0.9, 1.6 N: each
    answer equals solve_static of that tension, and the residual is at the tolerance (before
    the fix the failed trial's residuals, ~1e11, raised the stagnation floor and a Newton
    that had stalled at ||F|| ~ 1e5 was accepted, exit 0)."""
    comm = MPI.COMM_WORLD
    config = finger()
    with RealtimeSolver(config, comm, check=check) as solver:
        solver.update(tensions=[2.5])
        with pytest.raises(UpdateFailed):
            solver.update(tensions=[8000.0])
        assert solver.config.tendons[0].tension == 2.5
        for tension in (0.9, 0.9, 1.6):
            tip = solver.update(tensions=[tension])
            assert_fresh(solver, tip, set_parameters(config, {"tendons.0.tension": tension}),
                         comm)
            assert solver.tendons.tendons[0].tension == tension  # the tendon set follows


@pytest.mark.mpi
def test_loads_after_a_failed_tip_force_are_fresh_equilibria():
    """A tip moment beyond the non-standard law's largest one (0.703 EI/h at the tip: 0.07 N m)
    fails; then a tip force and a tension are fresh equilibria."""
    comm = MPI.COMM_WORLD
    config = finger(elements=10)
    with RealtimeSolver(config, comm, check=False) as solver:
        solver.update(tensions=[1.4])
        with pytest.raises(UpdateFailed):
            solver.update(loads={"tip_moment": 0.3})
        tip = solver.update(loads={"tip_force": (0.0, -0.3)})
        target = replace(config, model=replace(config.model, loads=replace(
            config.model.loads, tip_force=(0.0, -0.3))))
        target = set_parameters(target, {"tendons.0.tension": 1.4})
        assert_fresh(solver, tip, target, comm)
        tip = solver.update(tensions=[2.2])
        assert_fresh(solver, tip, set_parameters(target, {"tendons.0.tension": 2.2}), comm)


@pytest.mark.mpi
def test_offset_outside_the_section_is_refused():
    """h_tip = 10 mm: an offset of 6 mm at the tip (or 11 mm at the base, h = 20 mm) lies
    outside; the solver keeps its equilibrium and values; an offset inside is still solved."""
    comm = MPI.COMM_WORLD
    config = finger(elements=8)
    with RealtimeSolver(config, comm) as solver:
        before = solver.tip()
        for key, value in (("tendons.0.offset_tip", 0.006), ("tendons.0.offset_base", -0.011)):
            with pytest.raises(ConfigError, match="outside the section"):
                solver.update(parameters={key: value})
            assert solver.tip() == before
        # a thinner tip that leaves the tendon (4 mm at the tip) outside: refused too
        with pytest.raises(ConfigError, match="outside the section"):
            solver.update(parameters={"section.h_tip": 0.006})
        tip = solver.update(parameters={"tendons.0.offset_tip": 0.0045})
        assert_fresh(solver, tip, set_parameters(config, {"tendons.0.offset_tip": 0.0045}), comm)
        assert np.isfinite(tip["theta"])

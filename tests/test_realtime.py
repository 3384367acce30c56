"""Real-time re-solves (fe_beam.solvers.realtime): warm-started updates equal fresh solve_static
runs,
the load-stepping fallback, a clear failure, and the cache of built problems."""

from dataclasses import replace

import numpy as np
import pytest
from beam_cases import NU, E
from mpi4py import MPI

from fe_beam import (
    BeamModel,
    Discretisation,
    Loads,
    LoadStepping,
    Material,
    ModelOptions,
    Section,
    SolverSettings,
    Supports,
    realtime,
)
from fe_beam.analyses.finger import parse_finger
from fe_beam.analyses.static import solve_static
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers.realtime import RealtimeSolver, UpdateFailed, set_parameters

TOL = 1e-10


def rod(law="nonstandard", constraint="none", elements=6, tip_force=(0.0, -2.0), moment=0.0,
        section=None, solver=None, steps=4) -> StaticConfig:
    model = BeamModel(
        1.0, section or Section("rectangle", {"b": 0.02, "h": 0.01}, {"h": 0.008}),
        Material(E, nu=NU), ModelOptions(law, constraint), Discretisation(elements, 2),
        Supports("clamped", "free"), Loads(tip_force=tip_force, tip_moment=moment))
    return StaticConfig(model, solver or SolverSettings(), LoadStepping(steps=steps))


def finger(**model) -> StaticConfig:
    """The chapter's finger, 4 elements; Newton to rtol 1e-11 (at the default 1e-9 the two
    answers agree to the Newton tolerance, ~1e-10 rad here, and the test would measure it)."""
    config, _ = parse_finger({"model": model or {"law": "reissner", "constraint": "unshearable"},
                              "mesh": {"elements": 4, "degree": 2}, "solver": {"rtol": 1e-11},
                              "output": {"plots": False, "xdmf": False}})
    return config


def fresh(config: StaticConfig, comm=MPI.COMM_WORLD, monkeypatch=None):
    """solve_static of ``config`` on a newly built problem: (tip, owned state array)."""
    states = []
    if monkeypatch is not None:
        monkeypatch.setenv("FE_BEAM_PROBLEM_CACHE", "0")
    try:
        result = solve_static(config, None, comm, progress=False, record_shapes=False,
                              on_step=lambda p, e: states.append(p.w.x.array.copy()))
    finally:
        if monkeypatch is not None:
            monkeypatch.delenv("FE_BEAM_PROBLEM_CACHE")
    assert result.status == "converged", result.message
    return result.steps[-1]["tip"], states[-1]


def assert_same(tip, state, reference, scale):
    ref_tip, ref_state = reference
    for key in ("u", "v", "theta"):  # displacements within 1e-10 L, the angle 1e-10 rad
        bound = TOL * (1.0 if key == "theta" else scale)
        assert abs(tip[key] - ref_tip[key]) <= bound, (key, tip[key], ref_tip[key])
    assert np.max(np.abs(state - ref_state), initial=0.0) <= TOL * max(
        1.0, np.max(np.abs(ref_state), initial=0.0))


def test_cached_solve_static_is_a_fresh_one(monkeypatch):
    """A second cold solve of the same kind of model reuses the built problem (a cache hit)
    and gives the numbers of a newly built one, for other numbers in every Constant."""
    first = rod()
    solve_static(first, None, progress=False, record_shapes=False)
    other = replace(first, model=replace(
        first.model, material=Material(2.5 * E, nu=0.2),
        section=Section("rectangle", {"b": 0.015, "h": 0.012}, {"h": 0.007}),
        loads=Loads(tip_force=(0.3, -4.0), tip_moment=0.02, distributed=(0.0, -1.0))))
    hits = realtime.cache_info()["hits"]
    tip, state = fresh(other)
    assert realtime.cache_info()["hits"] == hits + 1
    reference = fresh(other, monkeypatch=monkeypatch)
    assert realtime.cache_info()["hits"] == hits + 1  # the cache was off
    assert abs(reference[0]["v"]) > 0.05  # a large deflection
    assert_same(tip, state, reference, 1.0)


def test_cache_key_separates_structures():
    base = rod()
    assert realtime.structure_key(base, MPI.COMM_WORLD) == realtime.structure_key(
        set_parameters(base, {"section.h": 0.02, "material.E": 1e9}), MPI.COMM_WORLD)
    for changed in (rod(elements=7), rod(law="reissner"), rod(constraint="inextensible"),
                    rod(section=Section("circle", {"d": 0.01}))):
        assert realtime.structure_key(changed, MPI.COMM_WORLD) != realtime.structure_key(
            base, MPI.COMM_WORLD)


def test_rod_updates_equal_solve_static(monkeypatch):
    config = rod()
    changes = [
        {"loads": {"tip_force": (0.0, -3.0)}},
        {"loads": {"tip_force": (0.5, -3.5), "tip_moment": -0.05}},
        {"parameters": {"section.h": 0.011, "section.h_tip": 0.009}},
        {"parameters": {"material.E": 1.3 * E}, "loads": {"tip_force": (0.0, -1.0)}},
    ]
    with RealtimeSolver(config) as solver:
        for change in changes:
            target = solver.target(**change)
            tip = solver.update(**change)
            assert_same(tip, solver.state(), fresh(target, monkeypatch=monkeypatch), 1.0)
        assert solver.statistics["fallbacks"] == 0


def test_finger_tension_updates_equal_solve_static(monkeypatch):
    config = finger()
    with RealtimeSolver(config) as solver:
        assert solver.dense
        for tension in (1.0, 2.5, 0.3, 1.7):
            tip = solver.update(tensions=[tension])
            target = set_parameters(config, {"tendons.0.tension": tension})
            assert solver.tension_values()[0] == tension
            assert_same(tip, solver.state(), fresh(target, monkeypatch=monkeypatch), 0.1)
        # tendon offsets are parameters too (re-interpolated, new rest lengths)
        change = {"parameters": {"tendons.0.offset_tip": 0.0045, "tendons.0.offset_base": 0.007}}
        target = solver.target(**change)
        tip = solver.update(**change)
        assert_same(tip, solver.state(), fresh(target, monkeypatch=monkeypatch), 0.1)
        assert solver.config.tendons[0].tension == 1.7


def test_fallback_load_stepping(monkeypatch):
    """Newton limited to 4 iterations cannot jump from a small to a large tip load; the update
    then load-steps from the last equilibrium and still ends on solve_static's answer."""
    config = rod(tip_force=(0.0, -0.1), solver=SolverSettings(max_it=4), steps=2)
    with RealtimeSolver(config) as solver:
        tip = solver.update(loads={"tip_force": (0.0, -12.0)})
        assert solver.statistics["fallbacks"] == 1
        reference = fresh(replace(solver.config, solver=SolverSettings(),
                                  stepping=LoadStepping(steps=20)), monkeypatch=monkeypatch)
        assert abs(reference[0]["theta"]) > 1.0
        assert_same(tip, solver.state(), reference, 1.0)


def test_update_without_equilibrium_fails_clearly():
    """Beyond the non-standard law's largest moment (M* = 0.703 EI / h for a rectangle) there
    is no equilibrium: UpdateFailed, and the last equilibrium is kept."""
    h, b = 0.01, 0.02
    config = rod(tip_force=(0.0, 0.0), moment=0.1, section=Section("rectangle",
                                                                   {"b": b, "h": h}))
    limit = 0.703 * E * b * h**3 / 12 / h
    with RealtimeSolver(config) as solver:
        before, state = solver.tip(), solver.state()
        with pytest.raises(UpdateFailed, match="no equilibrium at the new values"):
            solver.update(loads={"tip_moment": 1.5 * limit})
        assert solver.tip() == before
        assert np.array_equal(solver.state(), state)
        assert solver.config.model.loads.tip_moment == 0.1
        solver.update(loads={"tip_moment": 0.2})  # still usable
        assert solver.tip()["theta"] > before["theta"]


def test_bad_updates_are_refused():
    with RealtimeSolver(rod()) as solver:
        with pytest.raises(KeyError, match="not a parameter"):
            solver.update(parameters={"mesh.elements": 3})
        with pytest.raises(KeyError, match="loads are"):
            solver.update(loads={"torque": 1.0})


@pytest.mark.mpi
def test_realtime_updates_on_two_ranks():
    comm = MPI.COMM_WORLD
    config = finger(law="nonstandard")
    with RealtimeSolver(config, comm) as solver:
        for tension in (1.2, 2.6):
            tip = solver.update(tensions=[tension])
            target = set_parameters(config, {"tendons.0.tension": tension})
            reference, state = fresh(target, comm)
            assert_same(tip, solver.state(), (reference, state), 0.1)
            alone, _ = fresh(target, MPI.COMM_SELF)
            for key in ("u", "v", "theta"):
                assert abs(tip[key] - alone[key]) <= TOL * 0.1


def test_cached_solvers_leave_no_options_behind():
    """A cached MUMPS solver's options must not leak into a later solver of the same prefix
    (a serial unconstrained rod resolves "auto" to PETSc's own LU)."""
    realtime.clear_cache()
    solve_static(rod(law="reissner", constraint="inextensible"), None, progress=False,
                 record_shapes=False)
    plain = rod(elements=5)
    solve_static(plain, None, progress=False, record_shapes=False)
    run = realtime.acquire(plain, MPI.COMM_WORLD)
    try:
        pc = run.snes.snes.getKSP().getPC()
        assert pc.getType() == "lu"
        if MPI.COMM_WORLD.size == 1:
            assert pc.getFactorSolverType() == "petsc"
    finally:
        realtime.release(run)

"""The continuation engine (`fe_beam.solvers.continuation`): arc-length through limit points
against a
closed form, load control vs arc-length on the rod, failure reasons, snapshot/restore/step."""

import math

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.solvers.continuation import (
    ArcLength,
    Continuation,
    ContinuationFailed,
    bordered_solve,
)
from fe_beam.solvers.newton import LoadStepping, LoadSteppingFailed, SolveFailed

# --- a 2-dof problem with a closed-form path --------------------------------------------------
#   R(x, lambda) = [f(x0) - lambda, 2 x1 - x0],  f(u) = u^3/2 - 3u^2/2 + u (a von Mises truss
#   in reduced form): the path is lambda = f(u), x1 = u/2, with a limit point at
#   u = 1 -+ 1/sqrt(3), lambda = +-1/(3 sqrt 3) and the snap-back branch between them.


def f(u):
    return 0.5 * u**3 - 1.5 * u**2 + u


def df(u):
    return 1.5 * u**2 - 3 * u + 1


LIMIT_U = (1 - 1 / math.sqrt(3), 1 + 1 / math.sqrt(3))
LIMIT_LAMBDA = 1 / (3 * math.sqrt(3))


class _Newton:
    def __init__(self, owner):
        self.owner = owner
        self.linear_iterations = 0

    def solve(self):
        p = self.owner
        b = p.state_vector.duplicate()
        dx = b.duplicate()
        for iteration in range(1, 26):
            A = p.jacobian(p.state_vector)
            p.ksp.setOperators(A)
            p.residual(p.state_vector, b)
            b.scale(-1)
            p.ksp.solve(b, dx)
            p.state_vector.axpy(1.0, dx)
            p.residual(p.state_vector, b)
            if b.norm() < 1e-13 and dx.norm() < 1e-8:
                return iteration
            if not np.all(np.isfinite(p.state_array)):
                break
        raise SolveFailed("toy Newton diverged")

    def residual_norm(self):
        b = self.owner.state_vector.duplicate()
        self.owner.residual(self.owner.state_vector, b)
        return b.norm()


class Toy:
    """The 2-dof `fe_beam.solvers.continuation.ParameterProblem`."""

    def __init__(self, veto=None):
        self.comm = MPI.COMM_SELF
        self.state_vector = PETSc.Vec().createSeq(2, comm=PETSc.COMM_SELF)
        self.state_vector.set(0.0)
        self.A = PETSc.Mat().createAIJ([2, 2], nnz=2, comm=PETSc.COMM_SELF)
        self.A.setUp()
        self._ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        self._ksp.setType("preonly")
        self._ksp.getPC().setType("lu")
        self.solver = _Newton(self)
        self.metric = None
        self.value = 0.0
        self.veto = veto

    @property
    def state_array(self):
        return self.state_vector.getArray()

    @property
    def ksp(self):
        return self._ksp

    def set_parameter(self, value):
        self.value = float(value)

    def check_step(self, previous, current):
        return None if self.veto is None else self.veto(current)

    def residual(self, x, b):
        u, w = x.getArray()
        b.setArray([f(u) - self.value, 2 * w - u])

    def jacobian(self, x):
        u = x.getArray()[0]
        self.A.setValues([0, 1], [0, 1], [[df(u), 0.0], [-1.0, 2.0]])
        self.A.assemble()
        return self.A

    def parameter_derivative(self, x, out):
        out.setArray([-1.0, 0.0])


@pytest.mark.parametrize("constraint", ["riks", "crisfield"])
def test_arc_length_traces_both_limit_points_of_the_closed_form_path(constraint):
    toy = Toy()
    engine = Continuation(toy)
    seen = []
    engine.on_step = seen.append
    points = engine.arc_length_path(ArcLength(increment=0.02, constraint=constraint,
                                              max_arc_length=0.04, max_steps=400,
                                              max_load_factor=0.5))
    assert seen == points
    u = np.array([p.state[0] for p in points])
    lam = np.array([p.load_factor for p in points])
    # every point on the closed-form path
    np.testing.assert_allclose(lam[:-1], f(u[:-1]), atol=1e-10)
    np.testing.assert_allclose([p.state[1] for p in points], u / 2, atol=1e-10)
    # through both limit points without turning back: u increases monotonically to the end
    assert np.all(np.diff(u) > 0)
    assert u[0] > 0 and u[-1] > LIMIT_U[1]
    # the landed last point is on lambda = max_load_factor exactly
    assert lam[-1] == pytest.approx(0.5, abs=1e-12)
    assert f(u[-1]) == pytest.approx(0.5, abs=1e-10)
    # the tangent's dlambda/ds has the sign of f'(u): it turns at both limit points
    t_lam = np.array([p.tangent_parameter for p in points[:-1]])
    clear = np.abs(df(u[:-1])) > 1e-3
    assert np.all(np.sign(t_lam[clear]) == np.sign(df(u[:-1][clear])))
    assert np.any(t_lam < 0)
    rising = lam[u < 1]  # up to the first limit point and a little beyond
    assert 0.99 * LIMIT_LAMBDA < rising.max() <= LIMIT_LAMBDA + 1e-12
    assert -LIMIT_LAMBDA - 1e-12 <= lam.min() < -0.99 * LIMIT_LAMBDA


def test_load_control_stops_at_the_limit_point_with_a_reason():
    toy = Toy()
    engine = Continuation(toy)
    with pytest.raises(ContinuationFailed) as info:
        engine.load_control(0.3, LoadStepping(steps=10, min_increment=1e-4))
    failure = info.value
    assert isinstance(failure, LoadSteppingFailed)
    assert failure.kind == "step_too_small"
    assert failure.reason == "toy Newton diverged"
    # the last converged state is restored: below the limit load, on the path
    assert failure.parameter == engine.parameter == toy.value
    assert LIMIT_LAMBDA - 1e-3 < failure.parameter <= LIMIT_LAMBDA
    assert f(toy.state_array[0]) == pytest.approx(failure.parameter, abs=1e-12)
    assert failure.attempted > LIMIT_LAMBDA


def test_arc_length_cut_back_gives_the_vetoes_reason_and_restores_the_last_point():
    toy = Toy(veto=lambda x: "u beyond 0.3" if x[0] > 0.3 else None)
    engine = Continuation(toy)
    with pytest.raises(ContinuationFailed) as info:
        engine.arc_length_path(ArcLength(increment=0.05, max_steps=50))
    failure = info.value
    assert failure.kind == "step_too_small"
    assert failure.reason == "u beyond 0.3"
    u = toy.state_array[0]
    assert 0.3 - 1e-3 < u <= 0.3
    assert failure.parameter == pytest.approx(f(u), abs=1e-12)
    assert engine.parameter == failure.parameter
    # not adaptive: the first failed step ends it
    toy = Toy(veto=lambda x: "u beyond 0.3" if x[0] > 0.3 else None)
    with pytest.raises(ContinuationFailed) as info:
        Continuation(toy).arc_length_path(ArcLength(increment=0.2, adaptive=False))
    assert info.value.kind == "not_adaptive" and toy.value == info.value.parameter


def test_snapshot_restore_step_and_solve_at_round_trip():
    toy = Toy()
    engine = Continuation(toy)
    engine.prepare_arc_length(ArcLength(increment=0.05))
    engine.step(0.2)
    start = engine.snapshot()
    first = engine.step(0.3)
    after_first = engine.snapshot()
    engine.restore(start)
    assert np.array_equal(toy.state_array, start.state) and toy.value == start.parameter
    again = engine.step(0.3)
    assert np.array_equal(again.state, first.state) and again.load_factor == first.load_factor
    np.testing.assert_array_equal(engine.snapshot().tangent[0], after_first.tangent[0])
    # a fixed-parameter solve from the snapshot lands on the same equilibrium
    point = engine.solve_at(first.load_factor, start)
    np.testing.assert_allclose(point.state, first.state, atol=1e-12)
    # branch switching hook: the next step's Riks plane is normal to the given direction
    # (x1 alone): x1 moves by exactly the step, the rest follows from R = 0
    engine.restore(start)
    engine.set_predictor_direction(np.array([0.0, 2.0]), 0.0)
    switched = engine.step(0.01)
    assert switched.state[1] == pytest.approx(start.state[1] + 0.01, abs=1e-12)
    assert switched.load_factor == pytest.approx(f(2 * switched.state[1]), abs=1e-12)
    assert engine._direction is None  # used once


def test_bordered_solve_matches_a_dense_solve():
    rng = np.random.default_rng(1)
    n, m = 6, 2
    K = rng.normal(size=(n, n)) + n * np.eye(n)
    C, D, E = rng.normal(size=(n, m)), rng.normal(size=(n, m)), rng.normal(size=(m, m))
    f0, h = rng.normal(size=n), rng.normal(size=m)
    A = PETSc.Mat().createDense([n, n], array=K.copy(), comm=PETSc.COMM_SELF)
    A.assemble()
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOperators(A)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")

    def vec(a):
        return PETSc.Vec().createWithArray(a.copy(), comm=PETSc.COMM_SELF)

    out = vec(np.zeros(n))
    y = bordered_solve(ksp, vec(f0), [vec(c) for c in C.T], [vec(d) for d in D.T], E, h, out)
    full = np.block([[K, C], [D.T, E]])
    expected = np.linalg.solve(full, np.concatenate([f0, h]))
    np.testing.assert_allclose(np.concatenate([out.getArray(), y]), expected, rtol=1e-12)


# --- the rod -------------------------------------------------------------------------------------


def _rod_run(model, tendons=(), comm=MPI.COMM_WORLD):
    from fe_beam import SolverSettings
    from fe_beam.analyses.static import StaticContinuation
    from fe_beam.model.studies import StaticConfig

    config = StaticConfig(model, SolverSettings(), LoadStepping(steps=4), tendons=tuple(tendons))
    return StaticContinuation(config, comm)


def _tip_array(run):
    tip = run.problem.end_values("xL")
    return np.array([tip["u"], tip["v"], tip["theta"]])


ROD_CASES = {
    # large deflection under a dead tip force (tip rotation ~ 1.2 rad), with and without
    # multipliers
    "tip force, none": dict(constraint="none", tip_force=(0.0, -5 * 1e7 * 1e-8 / 12)),
    "tip force, inextensible-unshearable": dict(constraint="inextensible-unshearable",
                                                tip_force=(0.0, -5 * 1e7 * 1e-8 / 12)),
}


@pytest.mark.parametrize("case", list(ROD_CASES))
def test_rod_arc_length_agrees_with_load_control_on_the_stable_path(case):
    from beam_cases import cantilever

    model = cantilever(elements=12, **ROD_CASES[case])
    reference = _rod_run(model)
    arc = _rod_run(model)
    try:
        reference.advance(1.0, LoadStepping(steps=4))
        expected = _tip_array(reference)
        engine = arc.engine()
        points = engine.arc_length_path(ArcLength(increment=0.2, max_load_factor=1.0))
        assert points[-1].load_factor == 1.0
        assert len(points) >= 3
        assert np.all(np.diff([p.load_factor for p in points]) > 0)
        np.testing.assert_allclose(_tip_array(arc), expected, atol=1e-8, rtol=0)
        # an intermediate arc-length point against load control to its load factor
        middle = points[len(points) // 2]
        reference.restart()
        reference.advance(middle.load_factor, LoadStepping(steps=3))
        np.testing.assert_allclose(compat_state(reference), middle.state, atol=1e-8, rtol=0)
    finally:
        reference.destroy()
        arc.destroy()


@pytest.mark.mpi
def test_rod_arc_length_in_parallel_equals_serial():
    """The same arc-length path on all ranks together and on each rank alone: same steps, same
    load factors and tips to 1e-8 (each point is a Newton solve stopped at its tolerance, and
    the sums of 2 ranks round differently: 1.1e-10 apart was seen on the PyPI stack)."""
    from beam_cases import cantilever

    model = cantilever(elements=16, **ROD_CASES["tip force, inextensible-unshearable"])
    paths = []
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        run = _rod_run(model, comm=comm)
        try:
            points = run.engine().arc_length_path(ArcLength(increment=0.3, max_load_factor=1.0))
            paths.append(([p.load_factor for p in points], _tip_array(run)))
        finally:
            run.destroy()
    (together, tip_together), (alone, tip_alone) = paths
    assert len(together) == len(alone) and together[-1] == 1.0
    np.testing.assert_allclose(together, alone, rtol=1e-8)
    np.testing.assert_allclose(tip_together, tip_alone, rtol=1e-8, atol=1e-12)


def compat_state(run):
    from fe_beam.fem import compat

    return compat.local_array(run.problem.w).copy()


def test_rod_displacement_control_by_arc_length_matches_load_control():
    """The parameter scales a prescribed end value (tip deflection of a propped cantilever):
    dR/dlambda lives on the Dirichlet row."""
    from dataclasses import replace

    from beam_cases import cantilever

    from fe_beam import Supports

    model = cantilever(elements=12, constraint="none")
    model = replace(model, supports=Supports("clamped", "pinned", prescribed_xL={"v": -0.4}))
    reference, arc = _rod_run(model), _rod_run(model)
    try:
        reference.advance(1.0, LoadStepping(steps=4))
        points = arc.engine().arc_length_path(ArcLength(increment=0.25, max_load_factor=1.0))
        assert points[-1].load_factor == 1.0
        assert _tip_array(arc)[1] == pytest.approx(-0.4, abs=1e-12)
        np.testing.assert_allclose(compat_state(arc), compat_state(reference), atol=1e-8)
    finally:
        reference.destroy()
        arc.destroy()


def test_rod_tendon_tension_as_the_parameter():
    """Arc length in the tension of one tendon to T equals load control of the load factor with
    tension T (the tension-controlled finger)."""
    from beam_cases import cantilever

    from fe_beam.fem.tendons import Tendon

    tension = 2.0
    tendon = Tendon(paths=(((0.0, 0.004), (1.0, 0.004)),), tension=tension)
    model = cantilever(elements=12, constraint="none")
    reference, arc = _rod_run(model, [tendon]), _rod_run(model, [tendon])
    try:
        reference.advance(1.0, LoadStepping(steps=4))
        engine = Continuation(arc.parameter_problem("tension", 0))
        points = engine.arc_length_path(ArcLength(increment=0.5, max_load_factor=tension))
        assert points[-1].load_factor == tension
        assert float(arc.tendons.tensions[0].value) == tension
        assert _tip_array(reference)[2] > 0.3  # a real bend
        np.testing.assert_allclose(_tip_array(arc), _tip_array(reference), atol=1e-8)
    finally:
        reference.destroy()
        arc.destroy()


# --- the 3D solid --------------------------------------------------------------------------------


@pytest.mark.parametrize("formulation", ["displacement", "mixed"])
def test_solid_arc_length_step_matches_load_control(formulation):
    from fe_beam.solid import (
        Discretization,
        FingerGeometry,
        MeshSizes,
        NeoHookean,
        SolidFingerProblem,
        create_finger_mesh,
    )

    finger = create_finger_mesh(FingerGeometry(10.0, 1.0, 1.0),
                                MeshSizes(1.0, clamp=1.0, clamp_distance=1.0), MPI.COMM_WORLD)
    problem = SolidFingerProblem(finger, NeoHookean.from_young(1.0, 0.3),
                                 tip_force=(0.0, 3e-4, 0.0),
                                 discretization=Discretization(formulation))
    engine = problem.engine()
    start = engine.snapshot()
    engine.prepare_arc_length(ArcLength(increment=1.0))
    point = engine.step(engine.arc_length)
    assert 0.5 < point.load_factor < 1.5 and point.iterations >= 2  # a nonlinear step
    assert problem.load_factor == point.load_factor
    tip = problem.tip_displacement()
    assert tip[1] > 0.05 * 10.0
    arc_state = point.state
    engine.restore(start)
    engine.load_control(point.load_factor, LoadStepping(steps=2))
    from fe_beam.fem import compat

    scale = np.abs(arc_state).max()
    np.testing.assert_allclose(compat.local_array(problem.w), arc_state, atol=1e-8 * scale)
    np.testing.assert_allclose(problem.tip_displacement(), tip, atol=1e-8 * 10.0)
    problem.snes_solver.destroy()


def test_rod_parameter_derivative_matches_a_central_difference():
    """dR/dlambda (the affine two-point difference) against the central difference of the
    residual, on a loaded, tendon-pulled state with a prescribed end value."""
    from dataclasses import replace

    from beam_cases import cantilever

    from fe_beam import Supports
    from fe_beam.fem.tendons import Tendon
    from fe_beam.solvers.continuation import NonlinearParameterProblem

    tendon = Tendon(paths=(((0.0, 0.004), (1.0, 0.002)),), tension=1.5)
    model = cantilever(elements=8, constraint="inextensible-unshearable",
                       tip_force=(0.0, -2e-3), tip_moment=1e-3)
    model = replace(model, supports=Supports("clamped", ("theta",), prescribed_xL={"theta": 0.3}))
    run = _rod_run(model, [tendon])
    try:
        run.advance(0.7, LoadStepping(steps=2))
        exact = run.parameter_problem()
        central = NonlinearParameterProblem(run.solver, run._set_load_factor, affine=False,
                                            step=1e-4, parameter=0.7)
        exact.value = 0.7
        x = central.state_vector
        a, b = x.duplicate(), x.duplicate()
        exact.parameter_derivative(x, a)
        central.parameter_derivative(x, b)
        assert a.norm() > 0
        b.axpy(-1.0, a)
        assert b.norm() <= 1e-9 * a.norm()
        # the Dirichlet row of theta(L) carries -0.3
        assert a.getArray()[run.problem.component_dofs("theta", "xL")] == pytest.approx(
            [-0.3] * len(run.problem.component_dofs("theta", "xL")))
    finally:
        run.destroy()


def test_arc_length_refuses_pull_in_control_and_the_bordered_pull_in_keeps_the_length():
    """Pull-in control is a bordered constraint of the fixed-parameter Newton: the reached
    pull-in is the prescribed one to 1e-10 L; arc length on it is refused with a reason."""
    from beam_cases import cantilever

    from fe_beam.fem.tendons import Tendon

    tendon = Tendon(paths=(((0.0, 0.004), (1.0, 0.004)),), pull_in=0.002)
    run = _rod_run(cantilever(elements=10, constraint="none"), [tendon])
    try:
        run.advance(1.0, LoadStepping(steps=2))
        assert run.tendons.pull_ins()[0] == pytest.approx(0.002, abs=1e-10)
        # the tension found makes the rod's residual vanish (equilibrium at that tension)
        assert float(run.tendons.tensions[0].value) > 0
        assert run.snes.residual_norm() < 1e-8 * float(run.tendons.tensions[0].value)
        with pytest.raises(ValueError, match="pull-in"):
            run.engine().arc_length_path(ArcLength())
    finally:
        run.destroy()


@pytest.mark.parametrize("offset, compressed", [(0.004, True), (-0.004, False)])
def test_pull_in_needing_a_compressive_tension_is_noted(offset, compressed):
    """A tip force bending the rod toward the tendon shortens its path: holding pull_in = 0 then
    needs a pushing (negative) tension, which a tendon cannot give. The bordered pull-in solves
    it (exit 0, formerly without a word); summary notes say so. Away from the tendon: a pulling
    tension and no note."""
    from beam_cases import cantilever

    from fe_beam import SolverSettings
    from fe_beam.analyses.static import solve_static
    from fe_beam.fem.tendons import Tendon
    from fe_beam.model.studies import StaticConfig

    tendon = Tendon(paths=(((0.0, offset), (1.0, offset)),), pull_in=0.0)
    model = cantilever(elements=8, constraint="none", tip_force=(0.0, 1e-3))
    config = StaticConfig(model, SolverSettings(), LoadStepping(steps=2), tendons=(tendon,))
    result = solve_static(config, out=None, progress=False)
    assert result.status == "converged"
    tension = result.steps[-1]["tensions"][0]
    assert (tension < 0) == compressed and abs(tension) > 1e-3
    notes = [n for n in result.notes if "compressive tension" in n]
    assert len(notes) == int(compressed)

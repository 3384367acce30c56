"""Speed of the 3D solid (issue 10) without changing its answers: the tendon anchor plate's
Jacobian entries are preallocated (no PETSc malloc at the first assembly, same matrix)."""

import copy
import json
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.solid import (
    Discretization,
    FingerGeometry,
    MeshSizes,
    NeoHookean,
    SaintVenantKirchhoff,
    SolidFingerProblem,
    TendonLoad,
    TendonPath,
    create_finger_mesh,
)
from fe_beam.solvers.newton import (
    LoadStepping,
    LoadSteppingFailed,
    SolverSettings,
    preallocated_matrix,
)

GEOMETRY = FingerGeometry(0.1, 0.02, 0.02, 0.01,
                          tendons=(TendonPath.from_offsets(0.1, 0.008, 0.004),))
MATERIAL = NeoHookean.from_young(0.6e6, 0.45)


@pytest.fixture(scope="module")
def finger():
    return create_finger_mesh(GEOMETRY, MeshSizes(0.01), MPI.COMM_WORLD)


def deformed_state(problem) -> PETSc.Vec:
    """A non-trivial state (mm-sized displacements, kPa-sized pressures), owned + ghosts."""
    x = compat.vector_of(problem.w).copy()
    start, end = x.getOwnershipRange()
    x.array[: end - start] = 1e-3 * np.sin(np.arange(start, end))
    x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    return x


@pytest.mark.mpi
@pytest.mark.parametrize("formulation", ["mixed", "displacement"])
def test_anchor_plate_jacobian_is_preallocated_and_unchanged(finger, formulation):
    problem = SolidFingerProblem(
        finger, MATERIAL, tendons=[TendonLoad(tension=2.0)],
        discretization=Discretization(formulation),
        solver=SolverSettings(linear_solver="mumps"), prefix=f"speed_{formulation}_")
    assert problem.cables[0].patch_dofs is not None  # the anchor plate couples the tip face
    problem.set_load_factor(1.0)
    nl = problem.problem
    x = deformed_state(problem)
    nl.jacobian(None, x, nl.A, nl.A)
    assert nl.A.getInfo()["mallocs"] == 0
    # the same Jacobian in dolfinx's own matrix, which allocates the cable's entries as it goes
    reference = compat.create_matrix(nl.jacobian_form)
    reference.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    nl.jacobian(None, x, reference, reference)
    assert reference.getInfo()["mallocs"] > 0  # the couplings are outside the form's pattern
    difference = reference.copy()
    difference.axpy(-1.0, nl.A, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    assert difference.norm() <= 1e-14 * reference.norm()
    assert reference.norm() > 0
    for m in (reference, difference):
        m.destroy()
    x.destroy()
    problem.snes_solver.destroy()


def test_preallocated_matrix_holds_exactly_the_pattern_and_the_groups():
    """A 1D P1 Laplacian (tridiagonal) plus a group coupling the first, middle and last dofs."""
    import ufl
    from dolfinx import fem, mesh

    msh = mesh.create_unit_interval(MPI.COMM_WORLD, 8)
    V = compat.function_space(msh, compat.element(msh, "Lagrange", 1))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    form = fem.form(ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx)
    n = V.dofmap.index_map.size_global
    group = np.array([0, n // 2, n - 1])
    A = preallocated_matrix(compat.create_matrix(form), form, [group])
    start, end = A.getOwnershipRange()
    compat.assemble_matrix(A, form)
    A.setValues([r for r in group if start <= r < end], group.tolist(),
                np.ones((sum(start <= r < end for r in group), 3)),
                addv=PETSc.InsertMode.ADD_VALUES)
    A.assemble()
    assert A.getInfo()["mallocs"] == 0
    dense = np.zeros((n, n))
    rows = A.getValuesCSR()
    for i, r in enumerate(range(start, end)):
        dense[r, rows[1][rows[0][i]:rows[0][i + 1]]] = 1
    dense = MPI.COMM_WORLD.allreduce(dense, op=MPI.SUM)
    # stored entries: the P1 pattern of the interval (|i - j| <= 1 in the mesh's own vertex
    # order) plus the group's 3 x 3 block, nothing else
    assert dense.sum() == A.getInfo()["nz_used"]
    assert np.all(dense[np.ix_(group, group)] == 1)
    assert dense.sum() <= (3 * n - 2) + 9


# --- load steps that grow: `[solver] max_increment` and the engine's branch-jump guard --------
def svk_bar(tip_force: float, **solver) -> dict:
    """A square SVK bar (nu = 0: uniaxial, the rod's model) under an axial dead tip force."""
    h = 0.05
    return {
        "beam": {"length": 0.1}, "section": {"b": h, "h": h},
        "material": {"E": 1.0e6, "nu": 0.0}, "mesh": {"elements": 4},
        "loads": {"tip_force": [tip_force * 1.0e6 * h * h, 0.0], "steps": 4},
        "solver": {"max_it": 8, "min_increment": 0.05, **solver},
        "solid": {"material": "svk", "mesh_size": h}, "output": {"plots": False},
    }


def run(tmp_path, config):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent / "solid"))
    from test_solid_driver import run_cli, shared_folder

    code, _, stderr, out = run_cli("solid", shared_folder(tmp_path), config)
    summary = json.loads((out / "summary.json").read_text()) if code != 2 else None
    return code, stderr, summary


@pytest.fixture(scope="module")
def bar():
    """A square bar (h = 0.05, L = 0.1), one element across."""
    geometry = FingerGeometry(0.1, 0.05, 0.05, 0.05, tendons=())
    return create_finger_mesh(geometry, MeshSizes(0.05), MPI.COMM_WORLD)


def svk_solve(bar, tip_force: float, **stepping):
    """The SVK bar (nu = 0: uniaxial) under an axial dead tip force tip_force * E A."""
    h, E = 0.05, 1.0e6
    problem = SolidFingerProblem(
        bar, SaintVenantKirchhoff.from_young(E, 0.0), tip_force=(tip_force * E * h * h, 0, 0),
        solver=SolverSettings(linear_solver="mumps", max_it=8),
        prefix=f"speed_svk_{len(stepping)}_")
    try:
        return problem, problem.solve(LoadStepping(steps=4, min_increment=0.05, **stepping))
    finally:
        problem.snes_solver.destroy()


@pytest.mark.mpi
def test_grown_steps_do_not_jump_past_a_limit_point(bar, monkeypatch):
    """SVK under compression has no equilibrium beyond 2 / (3 sqrt 3) E A = 0.19245 E A
    (stretch 1/sqrt 3): steps allowed to grow to the whole ramp jump past that limit load onto
    another branch and converge (load factor 1 reached, without the guard); the guard cuts
    them back and the ramp stops below the limit load."""
    from fe_beam.solvers import continuation

    with pytest.raises(LoadSteppingFailed) as failure:
        svk_solve(bar, -0.3, max_increment=1.0)
    assert 0 < failure.value.last_load_factor < 0.19245 / 0.3
    vetoes = []
    jump = continuation.Continuation._branch_jump

    def counted(self, *args):
        verdict = jump(self, *args)
        vetoes.append(verdict)
        return verdict

    monkeypatch.setattr(continuation.Continuation, "_branch_jump", counted)
    with pytest.raises(LoadSteppingFailed):
        svk_solve(bar, -0.3, max_increment=1.0)
    assert any(v is not None and "branch jump" in v for v in vetoes)
    # without the guard the same ramp "converges" past the limit load: what the guard prevents
    monkeypatch.setattr(continuation, "BRANCH_JUMP", np.inf)
    svk_solve(bar, -0.3, max_increment=1.0)


@pytest.mark.parametrize("value", [0.1, 1.5, 0.0])
def test_max_increment_outside_one_step_and_the_ramp_is_a_usage_error(tmp_path, value):
    code, stderr, _ = run(tmp_path, svk_bar(0.2, max_increment=value))
    assert code == 2, stderr
    if MPI.COMM_WORLD.rank == 0:
        assert "max_increment" in stderr and "Traceback" not in stderr
        assert len(stderr.strip().splitlines()) == 1


@pytest.mark.mpi
def test_solid_run_steps_grow_up_to_max_increment():
    """`[solver] max_increment` reaches the solid's load stepping (`parse_solid`,
    `SolidRun.advance`): the stretched SVK bar takes fewer steps than `loads.steps` to 1 and
    ends at its closed-form equilibrium (no branch-jump veto on a smooth path)."""
    from fe_beam.analyses.solid import SolidRun
    from fe_beam.config.solid import parse_solid

    config = parse_solid(svk_bar(0.2, max_increment=1.0))
    assert config.stepping.max_increment == 1.0
    run = SolidRun(config)
    records = []
    run.advance(1.0, config.stepping, on_step=records.append)
    assert 1 < len(records) < 4 and run.load_factor == 1.0
    # the equilibrium of uniaxial SVK (homogeneous, exact in P2): N / (E A) = (s^2 - 1) s / 2
    # with the stretch s = 1 + u / L
    tip = run.problem.tip_displacement()
    stretch = 1 + tip[0] / 0.1
    assert 0.5 * (stretch**2 - 1) * stretch == pytest.approx(0.2, rel=1e-8)
    assert np.abs(tip[1:]).max() <= 1e-10 * tip[0]
    run.problem.snes_solver.destroy()


@pytest.mark.parametrize("tendon_steps", [None, 10])
def test_max_increment_is_kept_with_tendons(tendon_steps):
    """A config with tendons goes through the finger's parsing, which sets the load steps from
    the tendons' own `steps`: a given `[solver] max_increment` must survive it (it was silently
    reset to one step, so `fe-beam solid` never grew its steps on a tendon-driven finger), at
    least one step long; without the key the steps still never grow."""
    from fe_beam.config.schema import load_config
    from fe_beam.config.solid import parse_solid

    raw = load_config(Path(__file__).parents[1] / "examples" / "finger_solid.toml")
    if tendon_steps is not None:
        raw["tendons"][0]["steps"] = tendon_steps
    steps = max(raw["loads"]["steps"], tendon_steps or 0)
    assert parse_solid(copy.deepcopy(raw)).stepping.max_increment == pytest.approx(1 / steps)
    raw["solver"] = {"max_increment": 0.4}
    assert parse_solid(copy.deepcopy(raw)).stepping.max_increment == pytest.approx(0.4)
    from fe_beam.config.finger import parse_finger

    rod = {k: v for k, v in raw.items() if k not in ("solid", "compare")}
    assert parse_finger(rod)[0].stepping.max_increment == pytest.approx(0.4)

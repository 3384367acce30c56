"""Speed of the 3D solid (issue 10) without changing its answers: the tendon anchor plate's
Jacobian entries are preallocated (no PETSc malloc at the first assembly, same matrix)."""

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam import compat
from fe_beam.solid import (
    Discretization,
    FingerGeometry,
    MeshSizes,
    NeoHookean,
    SolidFingerProblem,
    TendonLoad,
    TendonPath,
    create_finger_mesh,
)
from fe_beam.solver import SolverSettings, preallocated_matrix

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

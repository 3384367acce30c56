"""Every dolfinx-version-specific call of fe_beam lives here (written against dolfinx 0.5.2).

A move to a newer dolfinx (0.6+: ``functionspace``, ``x.array``, ``dolfinx.io.gmshio`` renames,
``petsc.assemble_*`` moves) should touch this file only.
"""

from __future__ import annotations

import dolfinx
import dolfinx.fem.petsc as fem_petsc
import numpy as np
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI
from petsc4py import PETSc

__all__ = [
    "DOLFINX_VERSION",
    "XDMFFile",
    "apply_lifting",
    "assemble_matrix",
    "assemble_vector",
    "create_interval",
    "create_interval_from_vertices",
    "create_matrix",
    "create_vector",
    "cell_vertex_x",
    "function_space",
    "gmsh_model_to_mesh",
    "local_array",
    "facet_vertex_coordinates",
    "locate_dofs_geometrical",
    "owned_bc_dofs",
    "locate_entities",
    "locate_entities_boundary",
    "meshtags",
    "set_bc",
    "sub_space_collapsed",
    "vector_of",
]

DOLFINX_VERSION = dolfinx.__version__
XDMFFile = dolfinx.io.XDMFFile

assemble_vector = fem_petsc.assemble_vector
assemble_matrix = fem_petsc.assemble_matrix
apply_lifting = fem_petsc.apply_lifting
set_bc = fem_petsc.set_bc
create_matrix = fem_petsc.create_matrix
create_vector = fem_petsc.create_vector


def create_interval(comm: MPI.Comm, n_cells: int, length: float) -> mesh.Mesh:
    """Uniform interval mesh of [0, length] (geometric dimension 1)."""
    return mesh.create_interval(comm, n_cells, [0.0, length])


def create_interval_from_vertices(comm: MPI.Comm, vertices: np.ndarray) -> mesh.Mesh:
    """Interval mesh with the given increasing vertex coordinates (built on rank 0, distributed)."""
    if comm.rank == 0:
        points = np.asarray(vertices, dtype=np.float64).reshape(-1, 1)
        cells = np.column_stack([np.arange(len(points) - 1), np.arange(1, len(points))])
    else:
        points, cells = np.empty((0, 1)), np.empty((0, 2))
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", "interval", 1, dim=1))
    return mesh.create_mesh(comm, cells.astype(np.int64), points, domain)


def cell_vertex_x(msh: mesh.Mesh) -> np.ndarray:
    """(local cells, 2) x coordinates of the two vertices of each local cell of an interval
    mesh (owned and ghost cells)."""
    dofmap = msh.geometry.dofmap
    nodes = np.asarray(getattr(dofmap, "array", dofmap)).reshape(-1, 2)
    return msh.geometry.x[nodes, 0]


def function_space(msh: mesh.Mesh, element) -> fem.FunctionSpace:
    """Function space from a UFL element (FiniteElement, VectorElement or MixedElement)."""
    return fem.FunctionSpace(msh, element)


def sub_space_collapsed(space: fem.FunctionSpace, index: int):
    """(collapsed sub-space, map from its dofs to the parent's dofs)."""
    return space.sub(index).collapse()


def vector_of(function: fem.Function) -> PETSc.Vec:
    """The PETSc vector holding a Function's dofs (owned + ghosts)."""
    return function.vector


def local_array(function: fem.Function) -> np.ndarray:
    """Writable numpy view of a Function's local dofs (owned + ghosts)."""
    return function.x.array


def locate_dofs_geometrical(spaces, marker):
    return fem.locate_dofs_geometrical(spaces, marker)


def locate_entities(msh: mesh.Mesh, dim: int, marker):
    return mesh.locate_entities(msh, dim, marker)


def locate_entities_boundary(msh: mesh.Mesh, dim: int, marker):
    return mesh.locate_entities_boundary(msh, dim, marker)


def meshtags(msh: mesh.Mesh, dim: int, entities: np.ndarray, values: np.ndarray):
    order = np.argsort(entities)
    return mesh.meshtags(msh, dim, entities[order].astype(np.int32), values[order].astype(np.int32))


def gmsh_model_to_mesh(model, comm: MPI.Comm, rank: int = 0, gdim: int = 3):
    """(mesh, cell tags, facet tags) from an in-memory gmsh model."""
    from dolfinx.io import gmshio

    return gmshio.model_to_mesh(model, comm, rank, gdim=gdim)


def facet_vertex_coordinates(msh: mesh.Mesh, facets: np.ndarray) -> np.ndarray:
    """(k, 3, 3) coordinates of the three vertices of each local triangle facet."""
    from dolfinx.cpp.mesh import entities_to_geometry

    facets = np.asarray(facets, dtype=np.int32)
    if len(facets) == 0:
        return np.zeros((0, 3, 3))
    cpp_mesh = getattr(msh, "_mesh", getattr(msh, "_cpp_object", msh))  # 0.5: _mesh
    nodes = entities_to_geometry(cpp_mesh, msh.topology.dim - 1, facets, False)
    return msh.geometry.x[nodes[:, :3]]


def owned_bc_dofs(bcs) -> np.ndarray:
    """Sorted local indices (block size expanded) of the owned dofs fixed by ``bcs``."""
    rows = [bc.dof_indices()[0][: bc.dof_indices()[1]] for bc in bcs]
    return np.unique(np.concatenate(rows)) if rows else np.empty(0, dtype=np.int32)


def solve_linear(a, L, bcs, target: fem.Function) -> fem.Function:
    """Solve the linear variational problem a(x, v) = L(v) into ``target`` (direct, MUMPS).

    Configured programmatically rather than through dolfinx's LinearProblem, whose options
    stay in PETSc's global database (512 entries at most) long after the solve.
    """
    bilinear, linear = fem.form(a), fem.form(L)
    matrix = fem_petsc.assemble_matrix(bilinear, bcs=bcs)
    matrix.assemble()
    rhs = fem_petsc.assemble_vector(linear)
    fem_petsc.apply_lifting(rhs, [bilinear], bcs=[bcs])
    rhs.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    fem_petsc.set_bc(rhs, bcs)
    ksp = PETSc.KSP().create(target.function_space.mesh.comm)
    ksp.setOperators(matrix)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.solve(rhs, target.vector)
    target.x.scatter_forward()
    for petsc_object in (ksp, matrix, rhs):
        petsc_object.destroy()
    return target


def interpolation_expression(expr: ufl.core.expr.Expr, space: fem.FunctionSpace) -> fem.Expression:
    """A compiled expression that can be interpolated into ``space``."""
    points = space.element.interpolation_points
    if callable(points):  # later dolfinx versions turned it into a method
        points = points()
    return fem.Expression(expr, points)


# --- solid ---


def bounding_box_tree(msh: mesh.Mesh, dim: int):
    """Bounding-box tree of the local entities of dimension ``dim``."""
    from dolfinx import geometry

    return geometry.BoundingBoxTree(msh, dim)


def first_colliding_cells(msh: mesh.Mesh, tree, points: np.ndarray) -> np.ndarray:
    """For each point (n, 3), the first local cell containing it, or -1."""
    from dolfinx import geometry

    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    candidates = geometry.compute_collisions(tree, points)
    colliding = geometry.compute_colliding_cells(msh, candidates, points)
    cells = np.full(len(points), -1, dtype=np.int32)
    for i in range(len(points)):
        links = colliding.links(i)
        if len(links) > 0:
            cells[i] = links[0]
    return cells


def expression(expr: ufl.core.expr.Expr, reference_points: np.ndarray) -> fem.Expression:
    """A compiled expression evaluated at fixed points of the reference cell."""
    return fem.Expression(expr, np.asarray(reference_points, dtype=np.float64))


def evaluate_expression(compiled: fem.Expression, msh: mesh.Mesh, cells: np.ndarray) -> np.ndarray:
    """Values (n_cells, n_points * value_size) of a compiled expression in local ``cells``."""
    return compiled.eval(np.asarray(cells, dtype=np.int32))

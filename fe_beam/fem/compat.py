"""Every dolfinx/ufl/basix/petsc4py-version-specific call of fe_beam lives here.

Two stacks are supported: Debian bookworm's dolfinx 0.5.2 (legacy ``ufl.FiniteElement`` elements,
``fem.FunctionSpace``, ``Function.vector``, ``dolfinx.io.gmshio``) and PyPI's dolfinx 0.10/0.11
(``basix.ufl`` elements, ``fem.functionspace``, ``x.petsc_vec``, ``dolfinx.io.gmsh``,
``apply_lifting(alpha=)``, ``assemble_matrix(diag=)``). The rest of the package calls the
functions below only (``tests/test_compat.py`` greps for the version-specific names), so a move
to another dolfinx touches this file only.
"""

from __future__ import annotations

import functools
import sys
import time
from pathlib import Path

import dolfinx
import dolfinx.fem.petsc as fem_petsc
import numpy as np
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI
from petsc4py import PETSc
from ufl.algorithms.apply_algebra_lowering import apply_algebra_lowering
from ufl.algorithms.apply_derivatives import apply_derivatives

__all__ = [
    "DOLFINX_VERSION",
    "LEGACY",
    "POINT_RTOL",
    "XDMFFile",
    "apply_lifting",
    "atan2",
    "assemble_matrix",
    "assemble_vector",
    "cell_dofs",
    "create_interval",
    "create_interval_from_vertices",
    "create_matrix",
    "vector_for_form",
    "cell_vertex_x",
    "clear_stale_jit_lock",
    "element",
    "element_degree",
    "function_space",
    "geometry_cell_nodes",
    "geometry_degree",
    "gmsh_initialize",
    "gmsh_model_to_mesh",
    "local_array",
    "facet_vertex_coordinates",
    "locate_dofs_geometrical",
    "mixed_element",
    "owned_bc_dofs",
    "push_quiet_petsc_error_handler",
    "usable_after_petsc_error",
    "locate_entities",
    "locate_entities_boundary",
    "meshtags",
    "quadrature_element",
    "set_bc",
    "sub_space_collapsed",
    "vector_element",
    "vector_of",
    "vtk_permutation",
]

DOLFINX_VERSION = dolfinx.__version__
# dolfinx before 0.6: legacy UFL elements, fem.FunctionSpace, Function.vector, gmshio
LEGACY = tuple(int(p) for p in DOLFINX_VERSION.split(".")[:2]) < (0, 6)


# --- CPython's singledispatchmethod leak (gh-127750) ------------------------------------------
#: CPython 3.12.0-3.12.8 and 3.13.0-3.13.1 cache the bound method of every instance a
#: ``functools.singledispatchmethod`` is looked up on, in a WeakKeyDictionary whose values hold
#: the instance: nothing is ever freed. UFL's DAG traversers (``apply_derivatives``, dolfinx
#: 0.10+) are such instances, and each keeps the forms it differentiated, their functions and
#: meshes, and the meshes' MPI communicators (MPICH allows 2048 per process): a long session (the
#: PyPI stack's test suite, a design study in one process) ran out of them and crashed.
SINGLEDISPATCHMETHOD_LEAKS = (sys.version_info[:2] == (3, 12) and sys.version_info[2] < 9) or (
    sys.version_info[:2] == (3, 13) and sys.version_info[2] < 2)


def _uncached_get(self, obj, cls=None):
    """``singledispatchmethod.__get__`` as CPython 3.12.9 / 3.13.2 fixed it: no cache."""
    dispatch = self.dispatcher.dispatch
    funcname = getattr(self.func, "__name__", "singledispatchmethod method")

    def _method(*args, **kwargs):
        if not args:
            raise TypeError(f"{funcname} requires at least 1 positional argument")
        return dispatch(args[0].__class__).__get__(obj, cls)(*args, **kwargs)

    _method.__isabstractmethod__ = self.__isabstractmethod__
    _method.register = self.register
    functools.update_wrapper(_method, self.func)
    return _method


def fix_singledispatchmethod_leak() -> bool:
    """Replace the leaking ``singledispatchmethod.__get__`` on the affected CPython versions
    (every instance, also those UFL made at import, looks it up on the class). Idempotent;
    True when the patch is (now) in place."""
    if not SINGLEDISPATCHMETHOD_LEAKS:
        return False
    functools.singledispatchmethod.__get__ = _uncached_get
    return True


fix_singledispatchmethod_leak()
XDMFFile = dolfinx.io.XDMFFile
DirichletBC = fem.DirichletBCMetaClass if LEGACY else fem.DirichletBC
create_matrix = fem_petsc.create_matrix


def set_bc(b: PETSc.Vec, bcs, x0: PETSc.Vec | None = None, scale: float = 1.0) -> None:
    """b[dofs] = scale (g - x0[dofs]) on the owned Dirichlet dofs (x0 = 0 when None)."""
    keyword = "scale" if LEGACY else "alpha"
    fem_petsc.set_bc(b, bcs, x0, **{keyword: scale})


def assemble_vector(*args, **kwargs) -> PETSc.Vec:
    """``assemble_vector(form)`` (a new vector) or ``assemble_vector(b, form)`` (into ``b``)."""
    return fem_petsc.assemble_vector(*args, **kwargs)


def assemble_matrix(*args, bcs=None, diagonal: float = 1.0) -> PETSc.Mat:
    """``assemble_matrix(form, bcs=, diagonal=)`` or ``assemble_matrix(A, form, bcs=)``;
    ``diagonal`` is the value on the rows and columns of the Dirichlet dofs."""
    keyword = "diagonal" if LEGACY else "diag"
    return fem_petsc.assemble_matrix(*args, bcs=[] if bcs is None else bcs,
                                     **{keyword: diagonal})


def apply_lifting(b: PETSc.Vec, forms, bcs, x0=None, scale: float = 1.0) -> None:
    """b -= scale A (g - x0) for the Dirichlet values g (dolfinx's lifting)."""
    keyword = "scale" if LEGACY else "alpha"
    extra = {} if x0 is None else {"x0": x0}
    fem_petsc.apply_lifting(b, forms, bcs=bcs, **extra, **{keyword: scale})


def create_vector(form) -> PETSc.Vec:
    """A (ghosted) PETSc vector for the compiled linear ``form``."""
    if LEGACY:
        return fem_petsc.create_vector(form)
    return fem_petsc.create_vector(form.function_spaces[0])


vector_for_form = create_vector


# --- elements and spaces ---


def _cell(msh: mesh.Mesh):
    return msh.ufl_cell() if LEGACY else msh.basix_cell()


def element(msh: mesh.Mesh, family: str, degree: int):
    """Scalar element (``"Lagrange"``, ``"DG"``) on the cells of ``msh``."""
    if LEGACY:
        return ufl.FiniteElement(family, msh.ufl_cell(), degree)
    import basix.ufl

    return basix.ufl.element(family, _cell(msh), degree)


def vector_element(msh: mesh.Mesh, family: str, degree: int, dim: int | None = None):
    """Vector element with ``dim`` components (default: the geometric dimension)."""
    dim = msh.geometry.dim if dim is None else dim
    if LEGACY:
        return ufl.VectorElement(family, msh.ufl_cell(), degree, dim=dim)
    import basix.ufl

    return basix.ufl.element(family, _cell(msh), degree, shape=(dim,))


def mixed_element(elements):
    """Mixed element of the given sub-elements (in order)."""
    if LEGACY:
        return ufl.MixedElement(list(elements))
    import basix.ufl

    return basix.ufl.mixed_element(list(elements))


def quadrature_element(msh: mesh.Mesh, degree: int):
    """Scalar quadrature element of the default rule of ``degree`` (Gauss-Jacobi)."""
    if LEGACY:
        return ufl.FiniteElement("Quadrature", msh.ufl_cell(), degree, quad_scheme="default")
    import basix.ufl

    return basix.ufl.quadrature_element(_cell(msh), value_shape=(), scheme="default",
                                        degree=degree)


def function_space(msh: mesh.Mesh, element) -> fem.FunctionSpace:
    """Function space from an element of `element`, `vector_element` or `mixed_element`."""
    if LEGACY:
        return fem.FunctionSpace(msh, element)
    return fem.functionspace(msh, element)


def element_degree(space: fem.FunctionSpace) -> int:
    """Polynomial degree of the element of ``space``."""
    element = space.ufl_element()
    degree = element.degree
    return int(degree() if callable(degree) else degree)


def geometry_degree(msh: mesh.Mesh) -> int:
    """Degree of the coordinate element of ``msh`` (1: straight cells, 2: quadratic)."""
    element = msh.ufl_domain().ufl_coordinate_element()
    degree = element.degree
    return int(degree() if callable(degree) else degree)


def geometry_cell_nodes(msh: mesh.Mesh) -> np.ndarray:
    """(local cells incl. ghosts, nodes per cell) geometry node indices of each cell."""
    if LEGACY:
        dofmap = msh.geometry.dofmap
        offsets = dofmap.offsets
        per_cell = int(offsets[1] - offsets[0]) if len(offsets) > 1 else 1
        return dofmap.array.reshape(-1, per_cell)
    geometry = msh.geometry
    dofmaps = getattr(geometry, "dofmaps", None)  # 0.10+: one per cell type
    if dofmaps is None:
        return np.asarray(geometry.dofmap)
    return np.asarray(dofmaps[0] if not callable(dofmaps) else dofmaps(0))


def cell_dofs(space: fem.FunctionSpace) -> np.ndarray:
    """(local cells incl. ghosts, dofs per cell) block dof indices of each cell."""
    dofmap_list = space.dofmap.list
    if LEGACY:
        return dofmap_list.array.reshape(-1, space.dofmap.dof_layout.num_dofs)
    return np.asarray(dofmap_list)


def vtk_permutation(cell_type, nodes_per_cell: int) -> np.ndarray:
    """dolfinx's node order -> VTK's (``perm_vtk``)."""
    from dolfinx.cpp.io import perm_vtk

    return np.asarray(perm_vtk(cell_type, nodes_per_cell))


def atan2(y, x):
    """UFL's two-argument arctangent (``ufl.atan_2`` up to ufl 2023.1, ``ufl.atan2`` later)."""
    function = getattr(ufl, "atan_2", None) or ufl.atan2
    return function(y, x)


def push_quiet_petsc_error_handler() -> None:
    """Push PETSc's error handler that prints nothing (``PETSc.Sys.popErrorHandler`` undoes it):
    ``"ignore"`` up to PETSc 3.18, ``"return"`` later."""
    name = "ignore" if PETSc.Sys.getVersion() < (3, 19) else "return"
    PETSc.Sys.pushErrorHandler(name)


def usable_after_petsc_error(vector: PETSc.Vec) -> PETSc.Vec:
    """``vector`` after a PETSc error unwound a solve that used it. Newer PETSc (3.25 here) leaves
    the solution vector of an aborted ``SNESSolve`` locked read-only (the next copy into it fails):
    a fresh vector of the same layout there; the vector itself on older PETSc."""
    if PETSc.Sys.getVersion() < (3, 19):
        return vector
    fresh = vector.duplicate()
    try:
        vector.destroy()
    except PETSc.Error:
        pass
    return fresh


def create_interval(comm: MPI.Comm, n_cells: int, length: float) -> mesh.Mesh:
    """Uniform interval mesh of [0, length] (geometric dimension 1)."""
    return mesh.create_interval(comm, n_cells, [0.0, length])


def create_interval_from_vertices(comm: MPI.Comm, vertices: np.ndarray, gaps=()) -> mesh.Mesh:
    """Interval mesh with the given increasing vertex coordinates (built on rank 0, distributed);
    no cell inside the ``gaps`` ((a, b), ...): the mesh's separate pieces."""
    if comm.rank == 0:
        points = np.asarray(vertices, dtype=np.float64).reshape(-1, 1)
        cells = np.column_stack([np.arange(len(points) - 1), np.arange(1, len(points))])
        middle = 0.5 * (points[:-1, 0] + points[1:, 0])
        for a, b in gaps:
            cells = cells[~((middle > a) & (middle < b))]
            middle = middle[~((middle > a) & (middle < b))]
    else:
        points, cells = np.empty((0, 1)), np.empty((0, 2))
    if LEGACY:
        domain = ufl.Mesh(ufl.VectorElement("Lagrange", "interval", 1, dim=1))
        return mesh.create_mesh(comm, cells.astype(np.int64), points, domain)
    import basix.ufl

    domain = ufl.Mesh(basix.ufl.element("Lagrange", "interval", 1, shape=(1,)))
    # shared-facet ghosts, as create_interval and dolfinx 0.5's create_mesh: 0.10+'s
    # create_mesh ghosts nothing, so the vertex where two ranks' parts meet is an exterior
    # facet on both, and an interior-facet integral there (a point load) was lost on 2 ranks
    partitioner = (mesh.create_cell_partitioner(mesh.GhostMode.shared_facet, 2)
                   if comm.size > 1 else None)
    return mesh.create_mesh(comm, cells.astype(np.int64), domain, points,
                            partitioner=partitioner)


def cell_vertex_x(msh: mesh.Mesh) -> np.ndarray:
    """(local cells, 2) x coordinates of the two vertices of each local cell of an interval
    mesh (owned and ghost cells)."""
    return msh.geometry.x[geometry_cell_nodes(msh), 0]


def sub_space_collapsed(space: fem.FunctionSpace, index: int):
    """(collapsed sub-space, map from its dofs to the parent's dofs)."""
    sub, dofs = space.sub(index).collapse()
    if LEGACY:
        return sub, dofs
    return sub, np.concatenate([np.asarray(d, dtype=np.int32).reshape(-1) for d in dofs])


def vector_of(function: fem.Function) -> PETSc.Vec:
    """The PETSc vector holding a Function's dofs (owned + ghosts)."""
    return function.vector if LEGACY else function.x.petsc_vec


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


def gmsh_initialize() -> None:
    """``gmsh.initialize()`` that keeps Python's SIGINT handler: gmsh's Python API since 4.9
    (PyPI's 4.15; Debian has 4.8) sets SIGINT to the default action unless
    ``interruptible=False``, which would kill a run instead of fe_beam's clean interruption."""
    import inspect

    import gmsh

    if "interruptible" in inspect.signature(gmsh.initialize).parameters:
        gmsh.initialize(interruptible=False)
    else:
        gmsh.initialize()


def gmsh_model_to_mesh(model, comm: MPI.Comm, rank: int = 0, gdim: int = 3):
    """(mesh, cell tags, facet tags) from an in-memory gmsh model."""
    if LEGACY:
        from dolfinx.io import gmshio

        return gmshio.model_to_mesh(model, comm, rank, gdim=gdim)
    from dolfinx.io import gmsh as dolfinx_gmsh

    data = dolfinx_gmsh.model_to_mesh(model, comm, rank, gdim=gdim)
    return data.mesh, data.cell_tags, data.facet_tags


def facet_vertex_coordinates(msh: mesh.Mesh, facets: np.ndarray) -> np.ndarray:
    """(k, 3, 3) coordinates of the three vertices of each local triangle facet."""
    facets = np.asarray(facets, dtype=np.int32)
    if len(facets) == 0:
        return np.zeros((0, 3, 3))
    if LEGACY:
        from dolfinx.cpp.mesh import entities_to_geometry

        cpp_mesh = getattr(msh, "_mesh", getattr(msh, "_cpp_object", msh))  # 0.5: _mesh
        nodes = entities_to_geometry(cpp_mesh, msh.topology.dim - 1, facets, False)
    else:
        nodes = mesh.entities_to_geometry(msh, msh.topology.dim - 1, facets, False)
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
    return solve_compiled(fem.form(a), fem.form(L), bcs, target)


def solve_compiled(bilinear, linear, bcs, target: fem.Function) -> fem.Function:
    """`solve_linear` of compiled forms (``fem.form``: a solve repeated without compiling)."""
    matrix = assemble_matrix(bilinear, bcs=bcs)
    matrix.assemble()
    rhs = assemble_vector(linear)
    apply_lifting(rhs, [bilinear], bcs=[bcs])
    rhs.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    fem_petsc.set_bc(rhs, bcs)
    ksp = PETSc.KSP().create(target.function_space.mesh.comm)
    ksp.setOperators(matrix)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.solve(rhs, vector_of(target))
    target.x.scatter_forward()
    for petsc_object in (ksp, matrix, rhs):
        petsc_object.destroy()
    return target


def interpolation_expression(expr: ufl.core.expr.Expr, space: fem.FunctionSpace) -> fem.Expression:
    """A compiled expression that can be interpolated into ``space``."""
    points = space.element.interpolation_points
    if callable(points):  # later dolfinx versions turned it into a method
        points = points()
    return fem.Expression(_derivatives_applied(expr), points)


def _derivatives_applied(expr: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """``expr`` with its derivatives (``ufl.diff``, ``ufl.derivative``) carried out.

    FFCx 0.5 numbers an Expression's constants after applying the derivatives, dolfinx 0.5.2
    packs those of the expression as given: a ``fem.Constant`` the differentiation removes
    (a stiffness of a term that does not depend on the variable) shifts every later constant
    into the wrong slot (issue 28, item 5: the moment M = dW/dkappa was E G b^3 / 12 kappa,
    1e6..1e18 too large). Differentiated beforehand, both lists are the same. Harmless on the
    later stacks (FFCx would apply the same rules itself)."""
    return apply_derivatives(apply_algebra_lowering(ufl.as_ufl(expr)))


# --- solid ---


def bounding_box_tree(msh: mesh.Mesh, dim: int):
    """Bounding-box tree of the local entities of dimension ``dim``."""
    from dolfinx import geometry

    if LEGACY:
        return geometry.BoundingBoxTree(msh, dim)
    return geometry.bb_tree(msh, dim)


#: relative tolerance of point location: a point within this fraction of a cell's size of the
#: cell counts as in it (a point on a shared facet or vertex belongs to one of its cells)
POINT_RTOL = 1e-8


def first_colliding_cells(msh: mesh.Mesh, tree, points: np.ndarray,
                          rtol: float = POINT_RTOL) -> np.ndarray:
    """For each point (n, 3), the first local cell containing it, or -1.

    dolfinx's ``compute_colliding_cells`` accepts a candidate cell of the bounding-box tree only
    when its GJK distance to the point is below an absolute 1e-10 m (0.5.2: squared distance
    < 1e-20), while GJK stops on a relative criterion: a point within ~1e-9 m of a facet shared
    by millimetre cells (an interior point, all barycentric coordinates >= 0) comes back at a
    distance of ~6e-10 m from every cell sharing the facet and is lost. A point none of the
    candidates claims is therefore located again among the candidates with a tolerance relative
    to the cell's size: by its barycentric coordinates (straight simplex cells: the cell whose
    smallest coordinate is largest, accepted down to -``rtol``, with the distance off the
    cell's plane at most ``rtol`` times its size), else by GJK's distance at most ``rtol``
    times the cell's size.
    """
    from dolfinx import geometry

    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)

    def candidates_of(where):
        if LEGACY:
            return geometry.compute_collisions(tree, where)
        return geometry.compute_collisions_points(tree, where)

    candidates = candidates_of(points)
    colliding = geometry.compute_colliding_cells(msh, candidates, points)
    cells = np.full(len(points), -1, dtype=np.int32)
    for i in range(len(points)):
        links = colliding.links(i)
        if len(links) > 0:
            cells[i] = links[0]
    missing = np.flatnonzero(cells < 0)
    if len(missing) and rtol > 0:
        for i in missing:
            cells[i] = _closest_candidate(msh, candidates.links(int(i)), points[i], rtol)
    return cells


def _closest_candidate(msh: mesh.Mesh, candidates: np.ndarray, point: np.ndarray,
                       rtol: float) -> int:
    """The candidate cell holding ``point`` to the relative tolerance ``rtol``, or -1."""
    from dolfinx import geometry

    candidates = np.asarray(candidates, dtype=np.int32)
    if len(candidates) == 0:
        return -1
    tdim = msh.topology.dim
    x = msh.geometry.x
    nodes = geometry_cell_nodes(msh)
    best, best_score = -1, -np.inf
    simplex = geometry_degree(msh) == 1 and nodes.shape[1] == tdim + 1
    for cell in candidates:
        vertices = x[nodes[cell]]
        size = float(np.max(np.ptp(vertices, axis=0)))
        if simplex:
            edges = (vertices[1:] - vertices[0]).T  # (3, tdim)
            local, *_ = np.linalg.lstsq(edges, point - vertices[0], rcond=None)
            off_plane = float(np.linalg.norm(edges @ local - (point - vertices[0])))
            if off_plane > rtol * size:
                continue
            score = float(min(1.0 - local.sum(), local.min()))
            if score >= -rtol and score > best_score:
                best, best_score = int(cell), score
        else:
            distance = float(np.sqrt(geometry.squared_distance(
                msh, tdim, np.array([cell], dtype=np.int32), point.reshape(1, 3))[0]))
            if distance <= rtol * size and -distance > best_score:
                best, best_score = int(cell), -distance
    return best


def expression(expr: ufl.core.expr.Expr, reference_points: np.ndarray) -> fem.Expression:
    """A compiled expression evaluated at fixed points of the reference cell."""
    return fem.Expression(_derivatives_applied(expr),
                          np.asarray(reference_points, dtype=np.float64))


def evaluate_expression(compiled: fem.Expression, msh: mesh.Mesh, cells: np.ndarray) -> np.ndarray:
    """Values (n_cells, n_points * value_size) of a compiled expression in local ``cells``."""
    cells = np.asarray(cells, dtype=np.int32)
    return compiled.eval(cells) if LEGACY else compiled.eval(msh, cells)


# --- JIT look-ups ------------------------------------------------------------------------------
# a C file older than this without its ".c.cached" marker is a lock left by a killed compile
STALE_JIT_LOCK_SECONDS = 600.0


def clear_stale_jit_lock(cache_dir, module_name, age: float = STALE_JIT_LOCK_SECONDS) -> bool:
    """Remove FFCx's lock of ``module_name`` in ``cache_dir`` if a killed process left it.

    FFCx claims a module by creating ``<module>.c`` exclusively, compiles it, and then writes
    ``<module>.c.cached``; a process that finds the ``.c`` file waits (10 s by default) for the
    marker and then fails with "JIT compilation timed out". A run killed mid-compile (Ctrl-C,
    a batch system's time limit) leaves the ``.c`` file without its marker, and every later run
    that needs the form fails. A compile writes its C file seconds before the marker, so a file
    older than ``age`` seconds without a marker is such a lock: it is removed (True). Errors
    (another process removed it first, a read-only cache) leave it to FFCx."""
    c_file = Path(str(cache_dir)).expanduser() / f"{module_name}.c"
    try:
        if (c_file.with_suffix(".c.cached").exists()
                or time.time() - c_file.stat().st_mtime < age):
            return False
        c_file.unlink()
    except OSError:
        return False
    return True


def _memoize_jit_lookups() -> None:
    """Remember the compiled modules FFCx has found in its disk cache in this process.

    FFCx looks a form up by building a new `importlib.machinery.FileFinder` on its cache
    directory, which lists the whole directory every time: with a cache of ~30 000 files (a
    shared machine after some weeks) that is ~40 ms per form, most of building a small rod
    problem whose forms are all compiled already (issue 22, item 8: 0.13-0.32 s instead of
    ~0.1 s for a spatial cantilever). A module's name is the hash of its form and options, so
    the same name in the same directory is the same module: found once, it is reused.
    FE_BEAM_JIT_MEMO=0 switches this off. Before a look-up, a lock left by a killed compile is
    removed (`clear_stale_jit_lock`)."""
    import os

    memo = os.environ.get("FE_BEAM_JIT_MEMO", "1") != "0"
    try:
        from ffcx.codegeneration import jit as ffcx_jit
    except ImportError:  # pragma: no cover - another FFCx layout: nothing to speed up
        return
    lookup = getattr(ffcx_jit, "get_cached_module", None)
    if lookup is None or getattr(lookup, "_fe_beam_memo", False):
        return
    found: dict = {}

    def get_cached_module(module_name, object_names, cache_dir, *args, **kwargs):
        key = (str(module_name), tuple(object_names), str(cache_dir))
        if key in found:
            return found[key]
        clear_stale_jit_lock(cache_dir, module_name)
        result = lookup(module_name, object_names, cache_dir, *args, **kwargs)
        if memo and result[0] is not None:  # found (None: the caller compiles it now)
            found[key] = result
        return result

    get_cached_module._fe_beam_memo = True
    ffcx_jit.get_cached_module = get_cached_module


_memoize_jit_lookups()

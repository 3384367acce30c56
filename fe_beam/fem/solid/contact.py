"""Contact of the 3D solid with rigid obstacles (docs/theory.md, Contact of the 3D solid):
frictionless, augmented Lagrangian on the exterior facets.

Gap. A boundary point X of the reference body sits at x = X + u(X); its gap to an obstacle is
the signed distance g(x) of `fe_beam.fem.contact.point_gap` (the same formulas as the rod's,
in 3D coordinates), g >= 0 admissible.

Enforcement, per obstacle (Alart-Curnier / Rockafellar, the rod's density
`fe_beam.fem.contact.augmented_lagrangian_density`):

    Pi_c = int_{dOmega_0} 1/(2k) (<lambda - k g>_+^2 - lambda^2) dA,

integrated over the whole exterior boundary of the reference body (the clamp does not move)
with its own quadrature rule (``[contact] quadrature_degree``, default 2 p for P_p
displacements: 4 for P2, 6 points per triangle). Its variation is -int p dg dA with the nominal
contact pressure p = <lambda - k g>_+ >= 0 [N per reference m^2]. The multiplier lambda is a
P1 Lagrange field whose vertices on the exterior facets carry it (zero elsewhere; not P2: the
vertex functions of a P2 triangle integrate to zero, so a P2 vertex multiplier pushes with no
net force), updated at the vertices by Uzawa,
lambda <- <lambda - k g>_+ (`SolidContact.update`), between Newton solves
(`fe_beam.solvers.contact.ContactSolver`); with lambda = 0 the first solve is the plain penalty
k/2 <-g>_+^2. Newton solves the semi-smooth problem directly (the Heaviside step in its
Jacobian).

Penalty: k = penalty * mu / h [Pa/m], mu the law's small-strain shear modulus and h the mesh's
element size (``[solid] mesh_size``): a pressure mu squeezes a layer of one element by about
1 / penalty of its thickness before the Uzawa updates remove the penetration.

Measured per obstacle (`SolidContact.summary`): the force the obstacle exerts on the solid
F = int p grad g dA (grad g the obstacle's outward normal at x, UFL's derivative of g), the
active area int [p > 0] dA (reference), the peak pressure max p at the vertices of the
exterior facets (where lambda lives) and the largest penetration max(-g) at the vertices and
between them: at the P3 nodes of the exterior facets and, for a sphere, its depth into the
deformed facets (flat triangles through their P2 nodes, `triangle_distance`); a converged
step is accepted only with max_penetration <= the tolerance. Between the vertices the surface
is held by the penalty alone (a P1 multiplier cannot cancel a midpoint's own penetration, which
stays about p / k): when only those points are above the tolerance, `SolidContact.update`
grows k (4 x per update, up to MAX_GROWTH x in one solve); where the mesh cannot follow the
obstacle at all (a ball touching a coarse mesh inside a facet: its sagitta between the
quadrature points) the step is rejected, never accepted with a penetration above the
tolerance (docs/theory.md, Contact of the 3D solid: Between the vertices).
"""

from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem

from fe_beam.errors import ConfigError
from fe_beam.fem import compat
from fe_beam.fem.contact import augmented_lagrangian_density, contact_pressure, point_gap
from fe_beam.fem.mpi import assemble_scalar, global_max
from fe_beam.model.obstacles import ContactSettings, Sphere

__all__ = ["MAX_GROWTH", "SolidContact", "solid_contact_density", "solid_gap", "solid_traction",
           "triangle_distance"]

#: the largest penalty growth of one solve (`SolidContact.update`)
MAX_GROWTH = 4.0**6


def triangle_distance(point: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The distance (numpy) of ``point`` (3,) to each flat triangle of ``triangles`` (n, 3, 3):
    to its projection on the triangle's plane when that falls inside, else to the nearest
    edge."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    normal = np.cross(b - a, c - a)
    area2 = np.einsum("ij,ij->i", normal, normal)
    unit = normal / np.sqrt(np.maximum(area2, 1e-300))[:, None]
    height = np.einsum("ij,ij->i", point - a, unit)
    foot = point - height[:, None] * unit
    inside = np.ones(len(triangles), dtype=bool)
    for p, q in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(q - p, foot - p), normal) >= 0
    edges = []
    for p, q in ((a, b), (b, c), (c, a)):
        d = q - p
        t = np.clip(np.einsum("ij,ij->i", point - p, d)
                    / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0.0, 1.0)
        edges.append(np.linalg.norm(point - (p + t[:, None] * d), axis=1))
    return np.where(inside, np.abs(height), np.min(edges, axis=0))


# --- pure functions returning UFL ---------------------------------------------------------------
def solid_gap(obstacle, X, u):
    """Signed distance (UFL) of the deformed boundary point x = X + u to the obstacle."""
    return point_gap(obstacle, X + u)


def solid_contact_density(obstacle, X, u, multiplier, k):
    """The augmented-Lagrangian energy density per reference area (module docstring)."""
    return augmented_lagrangian_density(multiplier, solid_gap(obstacle, X, u), k)


def solid_traction(obstacle, X, u, multiplier, k):
    """The nominal traction the obstacle exerts on the solid, p grad g(x) (UFL vector)."""
    x = ufl.variable(X + u)
    gap = point_gap(obstacle, x)
    return contact_pressure(multiplier, gap, k) * ufl.diff(gap, x)


class SolidContact:
    """Multipliers, energy and measurements of the solid's contact with ``obstacles``.

    The interface of `fe_beam.fem.contact.ContactSet` that `fe_beam.solvers.contact.ContactSolver`
    uses: ``tolerance``, ``settings``, ``restore``, ``commit``, ``evaluate``, ``update``,
    ``max_penetration``, ``max_separation``.
    """

    def __init__(self, obstacles, settings: ContactSettings | None, mesh, u, degree: int,
                 shear_modulus: float, element_size: float, tolerance: float):
        self.obstacles = tuple(obstacles)
        self.settings = settings or ContactSettings()
        self.tolerance = float(tolerance)
        self.mesh, self.u = mesh, u
        self.comm = mesh.comm
        self.k = self.settings.penalty * float(shear_modulus) / float(element_size)
        self.quadrature_degree = self.settings.quadrature_degree or 2 * degree
        self.Q = compat.function_space(mesh, compat.element(mesh, "Lagrange", 1))
        #: the gap is measured at the P_p nodes (vertices and, for P2, edge midpoints)
        self.Q_nodes = compat.function_space(mesh, compat.element(mesh, "Lagrange", degree))
        fdim = mesh.topology.dim - 1
        facets = compat.locate_entities_boundary(mesh, fdim,
                                                 lambda x: np.full(x.shape[1], True))
        self._boundary, self._owned = self._masks(self.Q, facets)
        self._boundary_nodes, self._owned_nodes = self._masks(self.Q_nodes, facets)
        #: the gap between the vertices: at the nodes of P3 on the exterior facets (the
        #: vertices, two points on each edge, each facet's centroid)
        self.Q_between = compat.function_space(mesh, compat.element(mesh, "Lagrange", 3))
        self._boundary_between, self._owned_between = self._masks(self.Q_between, facets)
        #: a sphere can press into a facet between all its sample points: its deepest
        #: penetration into the deformed boundary, the flat triangles through the P_p nodes
        #: of each exterior facet (P2: 4 per facet, through its vertices and edge midpoints;
        #: `triangle_distance`)
        self._spheres = [i for i, o in enumerate(self.obstacles) if isinstance(o, Sphere)]
        if self._spheres:
            owned = facets[facets < mesh.topology.index_map(fdim).size_local]
            a, b, c = np.moveaxis(compat.facet_vertex_coordinates(mesh, owned), 1, 0)
            if degree >= 2:
                ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
                pieces = [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
            else:
                pieces = [(a, b, c)]
            self._triangles = np.concatenate([np.stack(p, axis=1) for p in pieces])
            from scipy.spatial import cKDTree

            coordinates = self.Q_nodes.tabulate_dof_coordinates()
            _, index = cKDTree(coordinates).query(self._triangles.reshape(-1, 3))
            self._triangle_dofs = index.reshape(-1, 3)
            self._vertex_u = fem.Function(self.Q_nodes)
            self._vertex_u_expr = [compat.interpolation_expression(u[c], self.Q_nodes)
                                   for c in range(3)]
        self.ds = ufl.Measure("ds", domain=mesh,
                              metadata={"quadrature_degree": self.quadrature_degree})
        X = ufl.SpatialCoordinate(mesh)
        self.multipliers = [fem.Function(self.Q, name=f"lambda_{o.name}") for o in obstacles]
        self._gaps = [fem.Function(self.Q) for _ in obstacles]
        self._gap_expr = [compat.interpolation_expression(solid_gap(o, X, u), self.Q)
                          for o in self.obstacles]
        self._node_gaps = [fem.Function(self.Q_nodes) for _ in obstacles]
        self._node_gap_expr = [compat.interpolation_expression(solid_gap(o, X, u),
                                                               self.Q_nodes)
                               for o in self.obstacles]
        self._between_gaps = [fem.Function(self.Q_between) for _ in obstacles]
        self._between_gap_expr = [compat.interpolation_expression(solid_gap(o, X, u),
                                                                  self.Q_between)
                                  for o in self.obstacles]
        k = fem.Constant(mesh, float(self.k))
        self._k = k
        #: the penalty's growth beyond ``k`` in the current solve (`update`)
        self.growth = 1.0
        self.energy = sum(solid_contact_density(o, X, u, lam, k) * self.ds
                          for o, lam in zip(self.obstacles, self.multipliers, strict=True))
        self._force = [[fem.form(solid_traction(o, X, u, lam, k)[i] * self.ds)
                        for i in range(3)]
                       for o, lam in zip(self.obstacles, self.multipliers, strict=True)]
        self._moment = [[fem.form(ufl.cross(X + u, solid_traction(o, X, u, lam, k))[i] * self.ds)
                         for i in range(3)]
                        for o, lam in zip(self.obstacles, self.multipliers, strict=True)]
        self._area = [fem.form(ufl.conditional(ufl.gt(contact_pressure(lam, solid_gap(o, X, u),
                                                                       k), 0), 1.0, 0.0)
                               * self.ds)
                      for o, lam in zip(self.obstacles, self.multipliers, strict=True)]
        self._committed = self._copy()
        self.check_clear()

    @staticmethod
    def _masks(space, facets):
        """(on the exterior facets, owned) masks of the local dofs of a scalar space."""
        dofs = fem.locate_dofs_topological(space, space.mesh.topology.dim - 1, facets)
        boundary = np.zeros(len(compat.local_array(fem.Function(space))), dtype=bool)
        boundary[dofs] = True
        return boundary, np.arange(len(boundary)) < space.dofmap.index_map.size_local

    # --- state ------------------------------------------------------------------------------
    def _copy(self):
        return [compat.local_array(lam).copy() for lam in self.multipliers]

    def restore(self) -> None:
        """Multipliers back to those of the last accepted state (`commit`), the penalty back
        to ``k`` (every solve starts from them)."""
        for lam, saved in zip(self.multipliers, self._committed, strict=True):
            compat.local_array(lam)[:] = saved
        self._set_growth(1.0)

    def _set_growth(self, growth: float) -> None:
        self.growth = float(growth)
        self._k.value = self.k * self.growth

    def commit(self) -> None:
        self._committed = self._copy()

    def _nodal_gaps(self, nodes: bool | str = False) -> list[np.ndarray]:
        values = []
        functions, expressions = ((self._node_gaps, self._node_gap_expr) if nodes is True else
                                  (self._between_gaps, self._between_gap_expr)
                                  if nodes == "between" else (self._gaps, self._gap_expr))
        for gap, expr in zip(functions, expressions, strict=True):
            gap.interpolate(expr)
            values.append(compat.local_array(gap).copy())
        return values

    def check_clear(self) -> None:
        """ConfigError when an obstacle touches or intersects the undeformed solid (a node of
        the mesh on or inside it); called before any load (u = 0)."""
        for obstacle, gap in zip(self.obstacles, self._nodal_gaps(nodes=True), strict=True):
            mine = gap[self._owned_nodes]
            worst = float(mine.min()) if len(mine) else np.inf
            worst = -global_max(self.comm, -worst)
            if not worst > 0:
                raise ConfigError(
                    f"{obstacle.where} the {obstacle.shape} intersects the undeformed solid "
                    f"(a node of the mesh is {-worst:.4g} m inside it); move it clear of the "
                    "body (0 <= x <= L, |y| <= h(x)/2, |z| <= b/2)")
        # an obstacle smaller than the elements can sit inside the body with no node inside
        # it: its centre (a cylinder's axis point, a box's centre) in a cell of the mesh
        tree = compat.bounding_box_tree(self.mesh, self.mesh.topology.dim)
        for obstacle in self.obstacles:
            centre = getattr(obstacle, "center", None)
            if centre is None and obstacle.shape == "cylinder":
                centre = obstacle.point
            if centre is None:  # a plane: its half-space holds a node when it cuts the body
                continue
            inside = int(np.any(compat.first_colliding_cells(self.mesh, tree,
                                                             np.asarray(centre)) >= 0))
            if self.comm.allreduce(inside) > 0:
                raise ConfigError(
                    f"{obstacle.where} the {obstacle.shape} lies inside the undeformed solid "
                    f"(its centre {tuple(float(c) for c in centre)} is in the body); move it "
                    "clear of the body (0 <= x <= L, |y| <= h(x)/2, |z| <= b/2)")

    def evaluate(self) -> dict:
        """Gaps, pressures and the largest penetration at the exterior-facet vertices (the
        multipliers'; owned nodes, MPI-reduced), and the largest penetration between them
        (``between``: at the P3 nodes of the exterior facets); ``penetration`` is the larger
        of the two."""
        gaps = self._nodal_gaps()
        k = self.k * self.growth
        pressures = [np.where(self._boundary, np.maximum(
            compat.local_array(lam) - k * g, 0.0), 0.0)
                     for lam, g in zip(self.multipliers, gaps, strict=True)]
        vertices = [global_max(self.comm, float(np.max(
            np.where(self._boundary & self._owned, -g, 0.0), initial=0.0))) for g in gaps]
        between = [float(np.max(np.where(self._boundary_between & self._owned_between, -g, 0.0),
                                initial=0.0)) for g in self._nodal_gaps("between")]
        if self._spheres:
            deformed = self._triangles.copy()
            for c, expr in enumerate(self._vertex_u_expr):
                self._vertex_u.interpolate(expr)
                deformed[:, :, c] += compat.local_array(self._vertex_u)[self._triangle_dofs]
            for i in self._spheres:
                sphere = self.obstacles[i]
                if len(deformed):
                    inside = sphere.radius - triangle_distance(np.array(sphere.center), deformed)
                    between[i] = max(between[i], float(np.max(inside)))
        between = [global_max(self.comm, b) for b in between]
        penetration = [max(a, b) for a, b in zip(vertices, between, strict=True)]
        peak = [global_max(self.comm, float(np.max(np.where(self._owned, p, 0.0),
                                                      initial=0.0))) for p in pressures]
        return {"gaps": gaps, "pressures": pressures, "penetration": penetration,
                "vertex_penetration": vertices, "between": between,
                "pressure_peak": peak, "active_changes": 0, "friction_changes": 0}

    def max_penetration(self, state: dict | None = None) -> float:
        state = self.evaluate() if state is None else state
        return max(state["penetration"], default=0.0)

    def max_separation(self, state: dict | None = None) -> float:
        """0: the solid's complementarity is not checked beyond the penetration."""
        return 0.0

    def update(self, state: dict | None = None, multipliers: bool = True) -> None:
        """Uzawa: lambda <- <lambda - k g>_+ at the exterior-facet nodes; when the vertices
        are within the tolerance and the points between them are not (a curved obstacle
        pressed into a facet, the residual p / k between the vertices of a P1 multiplier),
        the penalty grows 4 x (up to MAX_GROWTH x k in one solve; then the step is rejected
        as before)."""
        state = self.evaluate() if state is None else state
        for lam, p in zip(self.multipliers, state["pressures"], strict=True):
            compat.local_array(lam)[:] = p
        if (max(state["vertex_penetration"], default=0.0) <= self.tolerance
                < max(state["between"], default=0.0) and self.growth < MAX_GROWTH):
            self._set_growth(min(4.0 * self.growth, MAX_GROWTH))

    def summary(self, state: dict | None = None) -> list[dict]:
        """One entry per obstacle: force [N] (on the solid), active_area [m^2, reference],
        max_penetration [m], pressure_peak [Pa, nominal], extent ([x0, x1]: the reference x
        range of the exterior-facet vertices that carry pressure, None without any: the contact
        patch along the backbone, `contact_extent`) and contact_length = x1 - x0 [m]
        (collective)."""
        state = self.evaluate() if state is None else state
        entries = []
        for i, obstacle in enumerate(self.obstacles):
            extent = self.contact_extent(state["pressures"][i])
            entries.append({
                "name": obstacle.name,
                "force": [assemble_scalar(f) for f in self._force[i]],
                "active_area": assemble_scalar(self._area[i]),
                "max_penetration": state["penetration"][i],
                "pressure_peak": state["pressure_peak"][i],
                "extent": extent,
                "contact_length": 0.0 if extent is None else extent[1] - extent[0],
            })
        return entries

    def moments(self) -> list[np.ndarray]:
        """Per obstacle, the moment about the origin of the force it exerts on the solid,
        int (X + u) x t dA (deformed positions; collective)."""
        return [np.array([assemble_scalar(f) for f in forms]) for forms in self._moment]

    def contact_extent(self, pressure: np.ndarray) -> list[float] | None:
        """[min x, max x] of the reference positions of the owned exterior-facet vertices
        where ``pressure`` (local P1 values) is > 0, over the ranks; None when none is."""
        if not hasattr(self, "_x_nodes"):
            self._x_nodes = self.Q.tabulate_dof_coordinates()[:, 0].copy()
        pressed = self._x_nodes[:len(pressure)][(pressure > 0) & self._boundary & self._owned]
        low = -global_max(self.comm, -float(pressed.min()) if len(pressed) else -np.inf)
        high = global_max(self.comm, float(pressed.max()) if len(pressed) else -np.inf)
        return [low, high] if np.isfinite(low) and np.isfinite(high) else None

    def output_fields(self, state: dict | None = None) -> tuple[list[np.ndarray],
                                                                list[np.ndarray]]:
        """(gaps, pressures) for the XDMF: per obstacle the local P1 values (the multiplier
        space, ``Q``) of the signed gap [m] at every vertex and of the nominal contact pressure
        [Pa] at the exterior-facet vertices (0 elsewhere), the lumped L2 projection of the
        quadrature-point pressure p = <lambda - k g>_+ on the boundary,
        p_i = int p phi_i dA / int phi_i dA (`lumped_pressures`): its surface integral is int p
        dA, the force's (a plane: F = n int p dA), also for a patch narrower than the
        elements (there the vertices' <lambda - k g>_+, whose maximum is pressure_peak, spread
        over whole elements would overstate it). Collective."""
        state = self.evaluate() if state is None else state
        return state["gaps"], self.lumped_pressures()

    def lumped_pressures(self) -> list[np.ndarray]:
        """Per obstacle, the local P1 values int p phi_i dA / int phi_i dA at the vertices of
        the exterior facets (0 elsewhere); forms compiled on the first call. Collective."""
        from petsc4py import PETSc

        if getattr(self, "_lumped", None) is None:
            v = ufl.TestFunction(self.Q)
            X = ufl.SpatialCoordinate(self.mesh)
            self._lumped = (
                [fem.form(contact_pressure(lam, solid_gap(o, X, self.u), self._k) * v * self.ds)
                 for o, lam in zip(self.obstacles, self.multipliers, strict=True)],
                fem.form(v * self.ds))

        def local(form) -> np.ndarray:
            vector = compat.assemble_vector(form)
            vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            with vector.localForm() as values:
                array = np.array(values.array, dtype=float)
            vector.destroy()
            return array

        forms, mass_form = self._lumped
        mass = local(mass_form)
        carries = mass > 0
        result = []
        for form in forms:
            force = local(form)
            result.append(np.where(carries, force / np.where(carries, mass, 1.0), 0.0))
        return result

"""A planar serial chain of rods (`fe_beam.model.structure.Structure`) on one interval mesh.

The mesh coordinate s is the arc length along the chain (the rods laid end to end). Each rod has
a reference angle theta0 (a DG0 field, one value per rod) and the reference position
X(s) = origin + (s - s0) (cos theta0, sin theta0) (P1: linear on each element, continuous). The
unknowns (u, v) are world displacements and theta the incremental rotation: the world rotation
is theta0 + theta (MODEL.md section 9), r' = X' + (u', v') and the strains are those of the
single rod with r' rotated into the rod's reference frame, R(-theta0) r'. A rigid joint is the
shared vertex: (u, v, theta) are continuous there.

Outputs: each rod's own end (position, world angle) and each joint's force and moment, the
force the part of the chain after the joint exerts on the part before it: the residual of the
cells before the joint at the joint's dofs (their discrete equilibrium, world axes), reported
on the first end named in the joint's ``at``.
"""

from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.fem.mpi import global_sum

__all__ = ["ChainGeometry", "chain_vertices"]


def chain_vertices(structure) -> tuple[np.ndarray, tuple[float, ...]]:
    """(increasing vertex coordinates of the chain: each rod's uniform elements in chain order,
    the joints' coordinates)."""
    parts = [np.zeros(1)]
    for segment in structure.chain:
        rod = structure.rods[segment.rod]
        parts.append(segment.s0 + np.linspace(0.0, segment.length, rod.elements + 1)[1:])
    vertices = np.concatenate(parts)
    joints = structure.boundaries()
    for s in joints:  # the joint vertex exactly at its coordinate
        vertices[int(np.argmin(np.abs(vertices - s)))] = s
    return vertices, joints


class ChainGeometry:
    """The reference geometry of a chain on a problem's mesh: ``theta0`` (DG0), ``rod`` (DG0:
    the rod's index in [[rods]]), the reference position ``reference`` (a UFL 2-vector of P1
    fields) and numeric look-ups."""

    def __init__(self, problem):
        self.problem = problem
        self.structure = problem.model.structure
        mesh = problem.mesh
        cellwise = compat.function_space(mesh, compat.element(mesh, "DG", 0))
        self.theta0 = fem.Function(cellwise, name="theta0")
        self.rod = fem.Function(cellwise, name="rod")
        x = compat.cell_vertex_x(mesh)
        middle = x.mean(axis=1)
        dofs = compat.cell_dofs(cellwise)[: len(middle), 0]
        segments = [self.structure.segment_at(m) for m in middle]
        self.theta0.x.array[dofs] = [seg.theta0 for seg in segments]
        self.rod.x.array[dofs] = [seg.rod for seg in segments]
        self._segment_of_cell = np.array([self.structure.chain.index(seg) for seg in segments],
                                         dtype=int)
        nodal = compat.function_space(mesh, compat.element(mesh, "Lagrange", 1))
        self.X, self.Y = fem.Function(nodal, name="X"), fem.Function(nodal, name="Y")
        points = nodal.tabulate_dof_coordinates()[:, 0]
        where = [self.structure.reference_point(s) for s in points]
        self.X.x.array[:] = [p[0] for p in where]
        self.Y.x.array[:] = [p[1] for p in where]
        self.reference = ufl.as_vector([self.X, self.Y])
        self._joint_form = None
        self._indicator = None

    def cellwise(self, values) -> fem.Function:
        """A DG0 field whose value on each cell is ``values[i]`` of the cell's rod i."""
        field = fem.Function(self.theta0.function_space)
        dofs = compat.cell_dofs(field.function_space)[: len(self._segment_of_cell), 0]
        rods = np.array([self.structure.chain[k].rod for k in self._segment_of_cell], dtype=int)
        field.x.array[dofs] = np.asarray(values, dtype=float)[rods]
        field.x.scatter_forward()
        return field

    def section_dims(self) -> dict | None:
        """{dimension: DG0 field} of the rods' own sections (None: the top-level section)."""
        rods = self.structure.rods
        if not rods[0].section:
            return None
        names = [name for name, _ in rods[0].section]
        self._section_fields = {name: self.cellwise([dict(rod.section)[name] for rod in rods])
                                for name in names}
        return self._section_fields

    def moduli(self) -> tuple | None:
        """(E, G) DG0 fields of the rods' own materials (None: the top-level material)."""
        rods = self.structure.rods
        if not rods[0].material:
            return None
        self._moduli_fields = (self.cellwise([rod.material[0] for rod in rods]),
                               self.cellwise([rod.material[1] for rod in rods]))
        return self._moduli_fields

    def set_rod_values(self, old, new, fraction: float = 1.0) -> None:
        """Rewrite the rods' own section and moduli fields with the values of structure
        ``old`` + ``fraction`` (``new`` - ``old``) (same `Structure.compiled_key`)."""
        def mixed(a, b):
            a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
            return b if fraction == 1.0 else a + fraction * (b - a)

        fields = getattr(self, "_section_fields", None)
        for name, field in (fields or {}).items():
            values = mixed([dict(rod.section)[name] for rod in old.rods],
                           [dict(rod.section)[name] for rod in new.rods])
            field.x.array[:] = self.cellwise(values).x.array
        moduli = getattr(self, "_moduli_fields", None)
        for k, field in enumerate(moduli or ()):
            values = mixed([rod.material[k] for rod in old.rods],
                           [rod.material[k] for rod in new.rods])
            field.x.array[:] = self.cellwise(values).x.array
        self.structure = new

    # --- kinematics -----------------------------------------------------------------------------
    def world_tangent(self, u, v):
        """r' = X' + (u', v') in world axes."""
        return ufl.as_vector([ufl.cos(self.theta0) + u.dx(0), ufl.sin(self.theta0) + v.dx(0)])

    def local_tangent(self, tangent):
        """R(-theta0) r': the tangent in the rod's reference frame."""
        c, s = ufl.cos(self.theta0), ufl.sin(self.theta0)
        return ufl.as_vector([c * tangent[0] + s * tangent[1], -s * tangent[0] + c * tangent[1]])

    def local_displacement_tangent(self, u, v):
        """(1 + cos theta0 u' + sin theta0 v', -sin theta0 u' + cos theta0 v')."""
        c, s = ufl.cos(self.theta0), ufl.sin(self.theta0)
        return ufl.as_vector([1 + c * u.dx(0) + s * v.dx(0), -s * u.dx(0) + c * v.dx(0)])

    # --- outputs --------------------------------------------------------------------------------
    def position(self, s: float) -> tuple[float, float, float]:
        """(x, y, theta) world of the chain point s (a vertex; collective)."""
        values = self.problem.point_values(s)
        X, Y = self.structure.reference_point(s)
        return X + values["u"], Y + values["v"], values["theta"]

    def rods(self) -> dict:
        """{rod name: {tip: [x, y], tip_angle}}: each rod's own end ("rod:end") in world axes,
        its section's world angle there (the rod's direction + theta). Collective."""
        result = {}
        for index, rod in enumerate(self.structure.rods):
            s, _ = self.structure.rod_tip(index)
            x, y, theta = self.position(s)
            result[rod.name] = {"tip": [float(x), float(y)],
                                "tip_angle": float(rod.angle + theta)}
        return result

    def _compile_joint_form(self):
        problem = self.problem
        cellwise = self.theta0.function_space
        self._indicator = fem.Function(cellwise)
        chi = self._indicator
        u, v, theta, multipliers = problem.fields()
        s = problem.strains(u, v, theta)
        energy = chi * problem.law_energy(s) * problem.dx_energy
        if multipliers:
            energy += chi * sum(value * getattr(s, n) for n, value in multipliers.items()) \
                * problem.dx_energy
        body = problem.distributed + problem.rho * problem.section_props.A * problem.gravity
        energy -= chi * problem.load_factor * ufl.dot(body, ufl.as_vector([u, v])) \
            * problem.dx_loads
        test = ufl.TestFunction(problem.space)
        self._joint_form = fem.form(ufl.derivative(energy, problem.w, test))
        self._joint_dofs = {}
        for joint in self.structure.joints_on_chain:
            self._joint_dofs[joint.name] = [problem.point_dofs(n, joint.s, f"joint "
                                                               f"'{joint.name}' at")
                                            for n in ("u", "v", "theta")]

    def joints(self) -> dict:
        """{joint name: {force: [Fx, Fy], moment}}: the force and moment (world axes) on the
        first end named in the joint's ``at``, from the rest of the chain, or from the fixed
        body (the support's reaction at that chain end) (collective)."""
        result = {}
        for name, end, rod_first in self.structure.body_joints:
            reaction = self.problem.end_reaction(end)
            sign = 1.0 if rod_first else -1.0
            result[name] = {"force": [sign * reaction["Fx"], sign * reaction["Fy"]],
                            "moment": sign * reaction["M"]}
        if not self.structure.joints_on_chain:
            return result
        if self._joint_form is None:
            self._compile_joint_form()
        dofs = compat.cell_dofs(self._indicator.function_space)[: len(self._segment_of_cell), 0]
        for joint in self.structure.joints_on_chain:
            self._indicator.x.array[:] = 0.0
            self._indicator.x.array[dofs] = (self._segment_of_cell <= joint.segment)
            vector = compat.assemble_vector(self._joint_form)
            vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            values = vector.getArray(readonly=True)
            comm = self.problem.comm
            fx, fy, m = (float(global_sum(comm, values[d].sum()))
                         for d in self._joint_dofs[joint.name])
            vector.destroy()
            sign = 1.0 if joint.first_before else -1.0
            result[joint.name] = {"force": [sign * fx, sign * fy], "moment": sign * m}
        return result

    def shape(self, values: dict | None) -> dict | None:
        """A gathered line shape (``x``, ``u``, ``v`` at the vertices; `vertex_values`) with
        ``u``, ``v`` replaced by X + u - x, Y + v: plots that draw (x + u, v) draw the chain."""
        if values is None:
            return None
        x = np.asarray(values["x"], dtype=float)
        X = np.array([self.structure.reference_point(s)[0] for s in x])
        Y = np.array([self.structure.reference_point(s)[1] for s in x])
        shaped = dict(values)
        shaped["u"] = X + np.asarray(values["u"]) - x
        shaped["v"] = Y + np.asarray(values["v"])
        return shaped


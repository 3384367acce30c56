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

import math

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.fem.mpi import global_sum
from fe_beam.model.spatial import rotation_matrix

__all__ = ["ChainGeometry", "chain_vertices"]


def chain_vertices(structure) -> tuple[np.ndarray, tuple[float, ...]]:
    """(increasing vertex coordinates of the chain: each rod's uniform elements in chain order,
    the joints' coordinates)."""
    parts, end = [], None
    for segment in structure.chain:
        rod = structure.rods[segment.rod]
        first = 0 if end is None or segment.s0 > end else 1  # a piece's first vertex
        parts.append(segment.s0 + np.linspace(0.0, segment.length, rod.elements + 1)[first:])
        end = segment.s0 + segment.length
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
        self._cellwise = cellwise
        curved = any(seg.curvature for seg in self.structure.chain)
        # the reference angle: constant on each straight rod (DG0), linear on an arc (DG1)
        angles = compat.function_space(mesh, compat.element(mesh, "DG", 1)) if curved \
            else cellwise
        self.theta0 = fem.Function(angles, name="theta0")
        self.rod = fem.Function(cellwise, name="rod")
        x = compat.cell_vertex_x(mesh)
        middle = x.mean(axis=1)
        dofs = compat.cell_dofs(cellwise)[: len(middle), 0]
        segments = [self.structure.segment_at(m) for m in middle]
        if curved:
            where = angles.tabulate_dof_coordinates()[:, 0]
            for cell, seg in enumerate(segments):
                for dof in compat.cell_dofs(angles)[cell]:
                    self.theta0.x.array[dof] = seg.angle_at(where[dof])
        else:
            self.theta0.x.array[dofs] = [seg.theta0 for seg in segments]
        self.rod.x.array[dofs] = [seg.rod for seg in segments]
        self._segment_of_cell = np.array([self.structure.chain.index(seg) for seg in segments],
                                         dtype=int)
        nodal = compat.function_space(mesh, compat.element(mesh, "Lagrange", 1))
        self.spatial = bool(getattr(problem, "spatial", False))
        names = ("X", "Y", "Z") if self.spatial else ("X", "Y")
        coordinates = [fem.Function(nodal, name=n) for n in names]
        points = nodal.tabulate_dof_coordinates()[:, 0]
        where = [self.structure.reference_point(s) for s in points]
        for i, function in enumerate(coordinates):
            function.x.array[:] = [p[i] for p in where]
        self.X, self.Y = coordinates[0], coordinates[1]
        self.reference = ufl.as_vector(coordinates)
        if self.spatial:
            # R0: the reference directors (columns d1, d2, d3) of each cell's rod, DG0
            self._frame = [[fem.Function(cellwise, name=f"R0_{i}{j}") for j in range(3)]
                           for i in range(3)]
            for i in range(3):
                for j in range(3):
                    self._frame[i][j].x.array[dofs] = [seg.frame[j][i] for seg in segments]
                    self._frame[i][j].x.scatter_forward()
            self.frame0 = ufl.as_matrix([[self._frame[i][j] for j in range(3)]
                                         for i in range(3)])
        self._joint_form = None
        self._indicator = None

    def cellwise(self, values) -> fem.Function:
        """A DG0 field whose value on each cell is ``values[i]`` of the cell's rod i."""
        field = fem.Function(self._cellwise)
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

    def rod_field(self, index: int, table: str, name: str):
        """(the DG0 field of rod ``index``'s own ``table`` ("section": a dimension name;
        "material": "E" or "G") value, the DG0 indicator of the rod's cells), or None when the
        rods do not carry their own fields of it (parameters of one rod: calibrate)."""
        if table == "section":
            field = (getattr(self, "_section_fields", None) or {}).get(name)
        else:
            moduli = getattr(self, "_moduli_fields", None)
            field = None if moduli is None or name not in ("E", "G") \
                else moduli[0 if name == "E" else 1]
        if field is None:
            return None
        indicator = self.cellwise([1.0 if i == index else 0.0
                                   for i in range(len(self.structure.rods))])
        return field, indicator

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

    # --- spatial kinematics (MODEL.md section 9: R = R_inc R0) ---------------------------------
    def spatial_tangent(self, d):
        """r' = R0 e1 + d' in world axes (d the world displacement)."""
        return ufl.as_vector([self.frame0[i, 0] + d[i].dx(0) for i in range(3)])

    def spatial_rates(self, d, theta, rotation, curvature):
        """(v, u) = (R^T r', R^T R' as a vector) with R = R_inc R0, R_inc = ``rotation(theta)``:
        R0 is constant on each rod, so u = R0^T u_inc, u_inc = ``curvature(theta)`` (the
        body curvature of R_inc)."""
        R = ufl.dot(rotation(theta), self.frame0)
        return (ufl.dot(R.T, self.spatial_tangent(d)),
                ufl.dot(self.frame0.T, curvature(theta)))

    def frame_at(self, s: float, side: str = "after") -> np.ndarray:
        """R0 (columns d1, d2, d3) of the chain's segment at s (the one before s with
        ``side`` = "before": a chain's last end)."""
        segments = self.structure.chain
        segment = self.structure.segment_at(s)
        if side == "before" and segment.s0 >= s - 1e-12 * self.structure.length \
                and segments.index(segment) > 0:
            segment = segments[segments.index(segment) - 1]
        return np.array(segment.frame, dtype=float).T

    # --- outputs --------------------------------------------------------------------------------
    def position(self, s: float) -> tuple:
        """(x, y, theta) world of the chain point s (a vertex; collective); spatial: (position
        3-vector, rotation vector of R_inc)."""
        values = self.problem.point_values(s)
        reference = self.structure.reference_point(s)
        if self.spatial:
            position = np.array(reference) + np.array([values[n] for n in ("u", "v", "w")])
            return position, np.array([values[f"theta_{k}"] for k in "xyz"])
        X, Y = reference
        return X + values["u"], Y + values["v"], values["theta"]

    def rods(self) -> dict:
        """{rod name: {tip: [x, y], tip_angle}}: each rod's own end ("rod:end") in world axes,
        its section's world angle there (the rod's direction + theta). Spatial: {tip: [x, y,
        z], tip_frame}: the rows of R = R_inc R0 of the rod (its columns the directors d1,
        d2, d3 in world axes). Collective."""
        if self.spatial:
            result = {}
            for index, rod in enumerate(self.structure.rods):
                s, _ = self.structure.rod_tip(index)
                position, vector = self.position(s)
                frame = np.array(rotation_matrix(vector)) @ np.array(rod.frame, dtype=float).T
                result[rod.name] = {"tip": [float(c) for c in position],
                                    "tip_frame": frame.tolist()}
            return result
        result = {}
        for index, rod in enumerate(self.structure.rods):
            s, _ = self.structure.rod_tip(index)
            x, y, theta = self.position(s)
            result[rod.name] = {"tip": [float(x), float(y)],
                                "tip_angle": float(rod.angle + theta)}
        return result

    def _compile_spatial_joint_form(self):
        problem = self.problem
        self._indicator = fem.Function(self._cellwise)
        chi = self._indicator
        d, theta, multipliers = problem.fields()
        s = problem.strains((d, theta))
        energy = chi * problem.law_energy(s) * problem.dx_energy
        if multipliers:
            energy += chi * sum(value * s.constrained(n) for n, value in multipliers.items()) \
                * problem.dx_energy
        body = problem.distributed + problem.rho * problem.section_props.A * problem.gravity
        energy -= chi * problem.load_factor * ufl.dot(body, d) * problem.dx_loads
        self._finish_joint_form(energy, problem.components)

    def _compile_joint_form(self):
        if self.spatial:
            return self._compile_spatial_joint_form()
        problem = self.problem
        self._indicator = fem.Function(self._cellwise)
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
        self._finish_joint_form(energy, ("u", "v", "theta"))

    def _finish_joint_form(self, energy, components) -> None:
        """The joint residual form (the variation of ``energy``, the elements before a joint
        weighted by the indicator) and, per joint, its dofs of ``components``."""
        problem = self.problem
        test = ufl.TestFunction(problem.space)
        self._joint_form_ufl = ufl.derivative(energy, problem.w, test)
        self._joint_form = fem.form(self._joint_form_ufl)
        self._joint_dofs = {
            joint.name: [problem.point_dofs(n, joint.s, f"joint '{joint.name}' at")
                         for n in components]
            for joint in self.structure.joints_on_chain}

    def joints(self) -> dict:
        """{joint name: {force: [Fx, Fy], moment}}: the force and moment (world axes) on the
        first end named in the joint's ``at``, from the rest of the chain, or from the fixed
        body (the support's reaction at that chain end) (collective)."""
        result = {}
        for name, end, rod_first in self.structure.body_joints:
            reaction = self.problem.end_reaction(end)
            sign = 1.0 if rod_first else -1.0
            if self.spatial:
                vector = self.problem.end_values(end)["rotation_vector"]
                conjugate = np.array([reaction[f"M_theta_{k}"] for k in "xyz"])
                moment = np.linalg.solve(_spin(vector).T, conjugate)
                result[name] = {"force": [sign * reaction[k] for k in ("Fx", "Fy", "Fz")],
                                "moment": [float(sign * m) for m in moment]}
                continue
            result[name] = {"force": [sign * reaction["Fx"], sign * reaction["Fy"]],
                            "moment": sign * reaction["M"]}
        ties, inner = self.structure.ties, self.structure.inner_body_joints
        carried = self.structure.free_body_joints
        if carried:
            values = self.problem.raw_residual()
            for name, s, rod_first, body in carried:
                # the body's force and moment on the rod end: the rod's own cells' residual
                # there (the body's loads, applied at its first end, added back)
                wrench = self._end_wrench(values, s)
                load = self._body_load(body, s)
                sign = 1.0 if rod_first else -1.0
                result[name] = {"force": [sign * (f + p) for f, p in
                                          zip(wrench["force"], load[0], strict=True)],
                                "moment": sign * (wrench["moment"] + load[1])}
        if ties or inner:
            # the force and moment the rest of the structure exerts on a tied end: the
            # residual of its own rod's cells there (no Dirichlet rows at tied dofs)
            values = self.problem.raw_residual()
            for tie in ties:
                result[tie.name] = self._end_wrench(values, tie.ends[0][0])
            for name, s, rod_first in inner:
                wrench = self._end_wrench(values, s)
                sign = 1.0 if rod_first else -1.0
                result[name] = {"force": [sign * f for f in wrench["force"]],
                                "moment": ([sign * m for m in wrench["moment"]] if self.spatial
                                           else sign * wrench["moment"])}
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
            sums = [float(global_sum(comm, values[d].sum()))
                    for d in self._joint_dofs[joint.name]]
            vector.destroy()
            sign = 1.0 if joint.first_before else -1.0
            if self.spatial:
                # the rotation rows are conjugate to the rotation vector: r_theta = T^T m
                _, rotation_vector = self.position(joint.s)
                moment = np.linalg.solve(_spin(rotation_vector).T, np.array(sums[3:]))
                result[joint.name] = {"force": [sign * f for f in sums[:3]],
                                      "moment": [float(sign * m) for m in moment]}
                continue
            fx, fy, m = sums
            result[joint.name] = {"force": [sign * fx, sign * fy], "moment": sign * m}
        return result

    # --- joint forces in motion (fe-beam dynamic) ---------------------------------------------
    def joints_in_motion(self, inertia) -> dict:
        """`joints` of a moving chain: the residual of the elements before each joint now with
        their inertia, ``inertia(test)`` (a UFL form linear in the test function: the inertia
        and damping forces' virtual work of the current state, velocity and acceleration), so
        that the force on the part before is the rest's: applied loads + support reaction -
        its momentum rate. A joint to a fixed body reports the support's reaction with the
        inertia of the whole chain (the consistent mass couples the held end to its
        neighbours). Compiled once (``inertia`` must keep returning the same form);
        collective."""
        if getattr(self, "_motion_form", None) is None:
            self._compile_motion_form(inertia)
        result = {}
        dofs = compat.cell_dofs(self._motion_indicator.function_space)[
            : len(self._segment_of_cell), 0]
        for name, end, rod_first in self.structure.body_joints:
            self._motion_indicator.x.array[:] = 1.0
            sums = self._motion_sums(self._motion_end_dofs[name])
            result[name] = self._joint_entry(sums, 1.0 if rod_first else -1.0,
                                             self.problem.end_values(end))
        for joint in self.structure.joints_on_chain:
            self._motion_indicator.x.array[:] = 0.0
            self._motion_indicator.x.array[dofs] = (self._segment_of_cell <= joint.segment)
            sums = self._motion_sums(self._joint_dofs[joint.name])
            values = self.problem.point_values(joint.s) if self.spatial else None
            result[joint.name] = self._joint_entry(sums, 1.0 if joint.first_before else -1.0,
                                                   values)
        return result

    def _compile_motion_form(self, inertia) -> None:
        if self._joint_form is None:
            self._compile_joint_form()
        problem = self.problem
        self._motion_indicator = fem.Function(self.theta0.function_space)
        test = ufl.TestFunction(problem.space)
        static = self._joint_form_ufl
        weighted = ufl.replace(static, {self._indicator: self._motion_indicator})
        moving = _weighted(inertia(test), self._motion_indicator)
        self._motion_form = fem.form(weighted + moving)
        components = problem.components[:6] if self.spatial else ("u", "v", "theta")
        self._motion_end_dofs = {
            name: [problem.component_dofs(n, end) for n in components]
            for name, end, _ in self.structure.body_joints}

    def _motion_sums(self, dof_lists) -> list:
        vector = compat.assemble_vector(self._motion_form)
        vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        values = vector.getArray(readonly=True)
        sums = [float(global_sum(self.problem.comm, values[d].sum())) for d in dof_lists]
        vector.destroy()
        return sums

    def _joint_entry(self, sums, sign: float, values) -> dict:
        """{force, moment} of a joint's residual sums (world axes; spatial: the rotation rows
        turned into the moment, m = T(theta)^-T r_theta, ``values`` holding theta)."""
        if self.spatial:
            vector = (values["rotation_vector"] if "rotation_vector" in values
                      else [values[f"theta_{k}"] for k in "xyz"])
            moment = np.linalg.solve(_spin(vector).T, np.array(sums[3:6]))
            return {"force": [sign * f for f in sums[:3]],
                    "moment": [float(sign * m) for m in moment]}
        return {"force": [sign * sums[0], sign * sums[1]], "moment": sign * sums[2]}

    # --- ties (joints that are not shared vertices) --------------------------------------------
    def _global_dof(self, name: str, s: float, what: str) -> int:
        """The global index (in the state vector) of component ``name`` at the vertex s."""
        problem = self.problem
        local = problem.point_dofs(name, s, what)
        start = compat.vector_of(problem.w).getOwnershipRange()[0]
        mine = int(local[0]) + start + 1 if len(local) else 0
        return int(problem.comm.allreduce(mine)) - 1

    def tie_pairs(self) -> np.ndarray:
        """(slave, master) global dof pairs of the structure's ties: each tied component of
        every end after the first equals the first end's (collective)."""
        pairs = []
        for tie in self.structure.ties + self.structure.body_ties:
            (s_first, _), *others = tie.ends
            for name in tie.components:
                master = self._global_dof(name, s_first, f"joint '{tie.name}' at")
                for s, _ in others:
                    pairs.append((self._global_dof(name, s, f"joint '{tie.name}' at"), master))
        return np.array(pairs, dtype=np.int64).reshape(-1, 2)

    def describe_mechanism(self, values) -> str:
        """One sentence naming the mechanism whose zero-stiffness mode is ``values`` (the local
        array of the state vector's owned dofs): the pin or ball joint about which the rods
        turn relative to each other, or else the piece of the structure that moves as a rigid
        body (collective)."""
        comm, problem = self.problem.comm, self.problem
        rotations = [n for n in problem.components if n.startswith("theta")]

        def at(name, s):
            return float(global_sum(comm, values[problem.point_dofs(name, s)].sum()))

        owned = np.concatenate([problem.component_dofs(n) for n in rotations])
        largest = comm.allreduce(float(np.max(np.abs(values[owned]), initial=0.0)), op=MPI.MAX)
        best, relative = None, 0.0
        for tie in self.structure.ties:
            free = [n for n in rotations if n not in tie.components]
            if not free:
                continue
            first = np.array([at(n, tie.ends[0][0]) for n in free])
            for s, _ in tie.ends[1:]:
                jump = float(np.linalg.norm(np.array([at(n, s) for n in free]) - first))
                if jump > relative:
                    best, relative = (tie, free), jump
        if best is not None and relative > 1e-3 * largest:
            tie, free = best
            return (f"the structure is a mechanism: joint '{tie.name}' ({tie.kind}, at "
                    f"{', '.join(end for _, end in tie.ends)}) lets the rods turn about it "
                    f"with no stiffness (free dof: the relative rotation {', '.join(free)}); "
                    "hold the rods (supports, a rigid joint) so that no part can turn freely")
        motion = [n for n in problem.components]
        magnitude = {}
        for index, rod in enumerate(self.structure.rods):
            s, _ = self.structure.rod_tip(index)
            magnitude[rod.name] = max(abs(at(n, s)) for n in motion)
        rod = max(magnitude, key=magnitude.get)
        for tie in self.structure.body_ties:
            if any(end.partition(":")[0] == rod for _, end in tie.ends):
                return (f"the structure is a mechanism: the free body '{tie.name}' (and the "
                        f"rods joined to it, {', '.join(end for _, end in tie.ends)}) moves "
                        "as a rigid body with no stiffness (free dofs: its x, y, theta); hold "
                        "it (fixed = true) or support a rod joined to it")
        return (f"the structure is a mechanism: rod '{rod}' (and what is joined to it) moves "
                "as a rigid body with no stiffness (free dofs: its rigid motion); support it or "
                "join it rigidly")

    def _body_load(self, name: str, s: float) -> tuple:
        """(force, moment) of free body ``name`` applied at the rod end s (its first end)."""
        tie = next(t for t in self.structure.body_ties if t.name == name)
        body = self.structure.body(name)
        if abs(s - tie.ends[0][0]) > 1e-12 * self.structure.length:
            return [0.0, 0.0], 0.0
        return list(body.force or (0.0, 0.0)), body.moment

    def bodies(self) -> dict:
        """{body name: {position, rotation, force, moment}} of the free bodies: the pose of
        its reference point (world axes; rotation: the incremental angle) and the resultant
        force and moment on it (its loads and the rod ends' forces on it: zero at
        equilibrium; collective)."""
        result = {}
        ties = self.structure.body_ties
        values = self.problem.raw_residual() if ties else None
        for tie in ties:
            body = self.structure.body(tie.name)
            x, y, theta = self.position(tie.ends[0][0])
            force, moment = np.zeros(2), 0.0
            for s, _ in tie.ends:  # -sum of the ends' residuals: the loads less the rods'
                wrench = self._end_wrench(values, s)
                force -= np.array(wrench["force"])
                moment -= wrench["moment"]
            result[body.name] = {"position": [float(x), float(y)], "rotation": float(theta),
                                 "force": [float(f) for f in force], "moment": float(moment)}
        return result

    def _end_wrench(self, values, s: float) -> dict:
        """{force, moment} from the residual ``values`` at the vertex s (world axes)."""
        comm = self.problem.comm
        sums = [float(global_sum(comm, values[self.problem.point_dofs(n, s)].sum()))
                for n in self.problem.components]
        if self.spatial:
            _, rotation_vector = self.position(s)
            moment = np.linalg.solve(_spin(rotation_vector).T, np.array(sums[3:]))
            return {"force": sums[:3], "moment": [float(m) for m in moment]}
        return {"force": sums[:2], "moment": sums[2]}

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
        if self.spatial:
            shaped["w"] = (np.array([self.structure.reference_point(s)[2] for s in x])
                           + np.asarray(values["w"]))
        elif len(self.structure.pieces) > 1:  # a break in the drawn line between pieces
            order = np.argsort(x)
            breaks = [int(np.searchsorted(x[order], b)) for (_, b) in
                      [(a[1], b[0]) for a, b in zip(self.structure.pieces,
                                                    self.structure.pieces[1:])]]
            for key in ("x", "u", "v"):
                shaped[key] = np.insert(np.asarray(shaped[key], dtype=float)[order], breaks,
                                        np.nan)
        return shaped


def _weighted(form, weight):
    """The form with each integrand multiplied by ``weight``."""
    return ufl.Form([integral.reconstruct(integrand=weight * integral.integrand())
                     for integral in form.integrals()])


def _skew(vector) -> np.ndarray:
    t = np.asarray(vector, dtype=float)
    return np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])


def _spin(vector) -> np.ndarray:
    """T(theta) = I + b Theta + c Theta^2 (the spatial spin of a varied rotation vector)."""
    t = float(np.linalg.norm(vector))
    b = (1 - math.cos(t)) / t**2 if t > 1e-4 else 0.5 - t * t / 24
    c = (t - math.sin(t)) / t**3 if t > 1e-3 else 1 / 6 - t * t / 120
    K = _skew(vector)
    return np.eye(3) + b * K + c * K @ K


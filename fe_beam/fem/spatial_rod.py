"""The spatial rod as a finite-element problem (docs/theory.md, Spatial rods): the mixed space
of the centreline displacement d (3), the rotation vector theta (3) and the constraints'
multipliers, supports, loads and the residual, all forms compiled once.

Unknowns: d = r - X with X = (x, 0, 0) the straight reference axis, theta with R = exp(theta^)
(`fe_beam.fem.rotations`). Strains v = R^T r', u = T(-theta) theta' - u0. The energy and the
constraints use p Gauss points per element (as the planar rod: uniformly reduced integration,
locking-free), the loads a full rule; multipliers are discontinuous of degree p - 1.

An initially curved rod (u0 != 0) starts from its stress-free shape: r0' = R0 e1, R0' = R0 u0^,
R0(0) = I, integrated at the nodes; the load factor 0 state is then solved exactly
(`SpatialRodProblem.relax`), and reported displacements are measured from it.
"""

from __future__ import annotations

import math

import numpy as np
import ufl
from dolfinx import fem

from fe_beam.fem import compat
from fe_beam.fem.mpi import assemble_scalar
from fe_beam.fem.rod import BeamProblem, StrainRange
from fe_beam.fem.rotations import (
    angular_velocity,
    curvature,
    lagrangian_inertia,
    profile_expression,
    rotation,
    rotational_kinetic_energy,
    rotational_mass,
    spin_map,
)
from fe_beam.model.spatial import (
    SPATIAL_COMPONENTS,
    SPATIAL_CONSTRAINED,
    SpatialNonStandard,
    SpatialReissner,
    SpatialRodModel,
    SpatialStrains,
    rotation_matrix,
)

__all__ = ["MODE_FAMILIES", "SpatialRodProblem", "rotation_vector_of", "spin_matrix",
           "stress_free_shape"]

#: the families of the spatial rod's modes (`SpatialRodProblem.mode_shares`)
MODE_FAMILIES = ("axial", "torsion", "bending about y", "bending about z")

#: a note when the rotation vector's length passes this (its parametrisation is singular at 2 pi)
ROTATION_NOTE = 1.8 * math.pi


def rotation_vector_of(matrix: np.ndarray, near: np.ndarray | None = None) -> np.ndarray:
    """The rotation vector of a rotation matrix, the one of the family theta + 2 pi k n
    nearest ``near`` (continuity along the rod)."""
    matrix = np.asarray(matrix, dtype=float)
    cos_t = np.clip((np.trace(matrix) - 1) / 2, -1.0, 1.0)
    t = math.acos(cos_t)
    axial = np.array([matrix[2, 1] - matrix[1, 2], matrix[0, 2] - matrix[2, 0],
                      matrix[1, 0] - matrix[0, 1]]) / 2
    if t < 1e-8:
        vector = axial
    elif math.pi - t < 1e-6:
        # near pi: the axis from the symmetric part
        symmetric = (matrix + np.eye(3)) / 2
        axis = symmetric[int(np.argmax(np.diag(symmetric)))]
        axis = axis / np.linalg.norm(axis)
        if np.dot(axis, axial) < 0:
            axis = -axis
        vector = t * axis
    else:
        vector = t / math.sin(t) * axial
    if near is None:
        return vector
    norm = np.linalg.norm(vector)
    axis = vector / norm if norm > 0 else (near / max(np.linalg.norm(near), 1e-300))
    candidates = [vector + 2 * math.pi * k * axis for k in range(-3, 4)]
    return min(candidates, key=lambda c: np.linalg.norm(c - near))


def spin_matrix(vector, sign: float = 1.0) -> np.ndarray:
    """T(sign theta) = I + sign b Theta + c Theta^2 of a rotation vector (floats)."""
    theta = np.asarray(vector, dtype=float)
    t = float(np.linalg.norm(theta))
    b = (1 - math.cos(t)) / t**2 if t > 1e-4 else 0.5 - t * t / 24
    c = (t - math.sin(t)) / t**3 if t > 1e-3 else 1 / 6 - t * t / 120
    K = np.array([[0, -theta[2], theta[1]], [theta[2], 0, -theta[0]], [-theta[1], theta[0], 0]])
    return np.eye(3) + sign * b * K + c * K @ K


def stress_free_shape(model: SpatialRodModel, xs: np.ndarray, substeps: int = 64):
    """(r0, theta0) at the sorted stations ``xs`` of a rod of intrinsic curvature u0(s):
    R0' = R0 u0^, r0' = R0 e1, R0(0) = I, r0(0) = 0 (RK4 on the rotation with re-projection;
    exact for constant u0 to round-off)."""
    profiles = model.initial_curvature

    def u0(s):
        return np.array([p(s) for p in profiles])

    R = np.eye(3)
    r = np.zeros(3)
    positions, vectors = [], []
    previous_x, previous_theta = 0.0, np.zeros(3)
    for x in xs:
        span = x - previous_x
        if span > 0:
            h = span / substeps
            s = previous_x
            for _ in range(substeps):
                # the exact increment of a constant curvature over h, at the midpoint's u0
                k = u0(s + h / 2)
                step = np.array(rotation_matrix(h * k))
                # r' = R0 e1 integrated exactly over the arc of constant curvature
                r = r + R @ _arc_chord(h, k)
                R = R @ step
                s += h
            u_, _, vt = np.linalg.svd(R)
            R = u_ @ vt
        previous_x = x
        previous_theta = rotation_vector_of(R, previous_theta)
        positions.append(r.copy())
        vectors.append(previous_theta.copy())
    return np.array(positions), np.array(vectors)


def dead_moment_work(moment, theta, dtheta):
    """Virtual work of a dead moment ``moment`` (world axes) on the rotation vector ``theta``
    varied by ``dtheta``: M . T(theta) dtheta, T the tangent operator (the spatial spin)."""
    return ufl.dot(moment, ufl.dot(spin_map(theta), dtheta))


def _arc_chord(h: float, k: np.ndarray) -> np.ndarray:
    """int_0^h exp(s k^) e1 ds = h T(h k) e1 (the chord of an arc of constant curvature)."""
    theta = h * k
    t = float(np.linalg.norm(theta))
    b = (1 - math.cos(t)) / t**2 if t > 1e-4 else 0.5 - t * t / 24
    c = (t - math.sin(t)) / t**3 if t > 1e-3 else 1 / 6 - t * t / 120
    K = np.array([[0, -theta[2], theta[1]], [theta[2], 0, -theta[0]], [-theta[1], theta[0], 0]])
    T = np.eye(3) + b * K + c * K @ K
    return h * T @ np.array([1.0, 0.0, 0.0])


class SpatialRodProblem(BeamProblem):
    """Finite-element set-up of a `fe_beam.model.spatial.SpatialRodModel`: space, unknown,
    Dirichlet conditions, residual (the planar `BeamProblem`'s point location, ends, supports
    and bookkeeping are shared; the physics is its own)."""

    components = SPATIAL_COMPONENTS
    spatial = True
    reaction_keys = tuple(zip(("Fx", "Fy", "Fz", "M_theta_x", "M_theta_y", "M_theta_z"),
                              SPATIAL_COMPONENTS, strict=True))

    def __init__(self, model: SpatialRodModel, comm, breakpoints=(), extra_energy=None,
                 extra_work=None):
        self.reference_tip = np.zeros(3)
        super().__init__(model, comm, breakpoints, extra_energy, extra_work)
        if self.curved:
            self._set_stress_free_guess()

    @property
    def curved(self) -> bool:
        """An initial curvature: the stress-free shape is not the straight reference."""
        return self.model.curved

    # --- set-up ----------------------------------------------------------------------------
    def _constrained_strains(self) -> tuple:
        return SPATIAL_CONSTRAINED[self.model.options.constraint]

    def _make_constants(self) -> None:
        m, sec = self.model, self.model.section
        dims, dims_tip, x = self._material_constants()
        self.x = x
        E, G = self.E, self.G
        if self.chain is not None:  # rods with their own sections or materials: DG0 fields
            dims = self.chain.section_dims() or dims
            E, G = self.chain.moduli() or (E, G)
        self.law_moduli = (E, G)  # constants, or DG0 fields of a chain's rods
        p = sec.spatial_properties(x / m.length, dims, dims_tip, tanh=ufl.tanh)
        self.section_props = p
        if m.options.law == "reissner":
            self.law = SpatialReissner(E * p.A, self.k_shear * G * p.A, G * p.J,
                                       E * p.Iy, E * p.Iz)
        else:
            self.law = SpatialNonStandard(E, G, p.moments, p.J)
        self.intrinsic = ufl.as_vector([profile_expression(c, self.mesh)
                                        for c in m.initial_curvature])
        loads = m.loads
        vector = lambda value: fem.Constant(self.mesh, np.array(value, dtype=float))  # noqa: E731
        self.tip_force = vector(loads.tip_force)
        self.tip_moment = vector(loads.tip_moment)
        self.distributed = vector(loads.distributed)
        self.gravity = vector(loads.gravity)

    def _dirichlet_conditions(self):
        if self.curved:
            for end in ("x0", "xL"):
                values = getattr(self.model.supports, f"prescribed_{end}")
                if any(values.values()):
                    raise ValueError(
                        "prescribed end values (loads.prescribed_*, end_displacement, "
                        "end_rotation) of a rod with an initial_curvature are not supported "
                        "yet: its stress-free end is not at the straight reference's")
            if self.model.supports.fixed("x0") not in ((), SPATIAL_COMPONENTS):
                raise ValueError("a rod with an initial_curvature needs supports.x0 = "
                                 "\"clamped\" or \"free\" (its stress-free shape starts from "
                                 "the frame at x = 0)")
        held = {}
        if self.curved and self.model.supports.fixed("xL"):
            # the end x = L held where the stress-free rod has it
            r0, theta0 = stress_free_shape(self.model, np.array([self.model.length]))
            held = dict(zip(SPATIAL_COMPONENTS, np.concatenate(
                [r0[0] - np.array([self.model.length, 0, 0]), theta0[0]]), strict=True))
        bcs, prescribed = [], []
        for end in ("x0", "xL"):
            values = getattr(self.model.supports, f"prescribed_{end}")
            for name in self.model.supports.fixed(end):
                index = self.components.index(name)
                sub, _ = compat.sub_space_collapsed(self.space, index)
                dofs = compat.locate_dofs_geometrical(
                    (self.space.sub(index), sub), self.end_markers[end])
                self.point_dofs(name, self.end_x[end], f"support {end} at")  # exactly one
                value = fem.Function(sub)
                if end == "xL" and name in held:
                    value.x.array[:] = held[name]
                bcs.append(fem.dirichletbc(value, dofs, self.space.sub(index)))
                if values.get(name, 0.0) != 0.0:
                    prescribed.append((value, float(values[name])))
        return bcs, prescribed

    def _set_stress_free_guess(self) -> None:
        """The state at the stress-free shape's nodal values (then `relax` solves it)."""
        array = compat.local_array(self.w)
        for index in range(len(SPATIAL_COMPONENTS)):
            sub, parent = compat.sub_space_collapsed(self.space, index)
            xs = sub.tabulate_dof_coordinates()[:, 0]
            order = np.argsort(xs)
            r0, theta0 = stress_free_shape(self.model, xs[order])
            values = np.concatenate([r0 - np.outer(xs[order], [1, 0, 0]), theta0], axis=1)
            column = np.empty(len(xs))
            column[order] = values[:, index]
            array[np.asarray(parent)] = column

    def relaxed(self) -> None:
        """The current state (solved at load factor 0) is the reference of the displacements."""
        values = super().end_values("xL")
        self.reference_tip = np.array([values[n] for n in ("u", "v", "w")])

    # --- physics -----------------------------------------------------------------------------
    def fields(self):
        """(d, theta, multiplier dict) of the current state (UFL vectors)."""
        parts = ufl.split(self.w)
        d = ufl.as_vector(parts[0:3])
        theta = ufl.as_vector(parts[3:6])
        return d, theta, dict(zip(self.multipliers, parts[6:], strict=True))

    def state_parts(self):
        d, theta, _ = self.fields()
        return d, theta

    def strains(self, parts) -> SpatialStrains:
        d, theta = parts
        if self.chain is not None:  # a chain of rods: R = R_inc R0 (fe_beam.fem.structure)
            v, u = self.chain.spatial_rates(d, theta, rotation, curvature)
            u = u - self.intrinsic
            return SpatialStrains(tuple(v[i] for i in range(3)), tuple(u[i] for i in range(3)))
        tangent = ufl.as_vector([1 + d[0].dx(0), d[1].dx(0), d[2].dx(0)])
        R = rotation(theta)
        v = ufl.dot(R.T, tangent)
        u = curvature(theta) - self.intrinsic
        return SpatialStrains(tuple(v[i] for i in range(3)), tuple(u[i] for i in range(3)))

    def frame_rates(self, parts):
        """(v, u) = (R^T r', the total curvature T(-theta) theta') as UFL 3-vectors."""
        d, theta = parts
        if self.chain is not None:
            return self.chain.spatial_rates(d, theta, rotation, curvature)
        tangent = ufl.as_vector([1 + d[0].dx(0), d[1].dx(0), d[2].dx(0)])
        return ufl.dot(rotation(theta).T, tangent), curvature(theta)

    def tendon_length_density(self, parts, offsets):
        """|p'| of a tendon at body offset r_i = (0, y(x), z(x)): p = r + R r_i, so
        R^T p' = v + u x r_i + r_i' (docs/theory.md, Tendons routed anywhere)."""
        y, z = offsets
        v, u = self.frame_rates(parts)
        r_i = ufl.as_vector([0, y, z])
        r_i_prime = ufl.as_vector([0, y.dx(0), z.dx(0)])
        body = v + ufl.cross(u, r_i) + r_i_prime
        return ufl.sqrt(ufl.dot(body, body))

    def law_energy(self, s):
        return self.law.energy(s)

    def stored_energy(self, parts):
        total = self.law_energy(self.strains(parts)) * self.dx_energy
        if self.extra_energy is not None:
            total += self.extra_energy(self, parts)
        return total

    def dead_load_work(self, parts):
        """Work of the dead forces (the dead moment has no potential: `moment_virtual_work`)."""
        d, _ = parts
        lam = self.load_factor
        body = self.distributed + self.rho * self.section_props.A * self.gravity
        work = lam * ufl.dot(body, d) * self.dx_loads
        if not self.model.loads.follower:
            work += lam * ufl.dot(self.tip_force, d) * self.ds_tip
        return work + lam * self.point_work(self.point_forces, lambda force: ufl.dot(force, d))

    def constraint_term(self, parts, multipliers):
        if not multipliers:
            return 0
        s = self.strains(parts)
        return sum(value * s.constrained(n) for n, value in multipliers.items()) * self.dx_energy

    def potential(self):
        d, theta, multipliers = self.fields()
        parts = (d, theta)
        return (self.stored_energy(parts) + self.constraint_term(parts, multipliers)
                - self.dead_load_work(parts))

    def nonconservative_work(self, parts, test):
        """Virtual work of the tip moment (dead: M . T(theta) dtheta, the spatial spin; follower:
        (R M) . T(theta) dtheta), of the point moments (dead, the same term at their points)
        and of a follower tip force (R F) . dd."""
        d, theta = parts
        pieces = ufl.split(test)
        dd, dtheta = ufl.as_vector(pieces[0:3]), ufl.as_vector(pieces[3:6])
        follower = self.model.loads.follower
        R = rotation(theta)
        moment = ufl.dot(R, self.tip_moment) if follower else self.tip_moment
        work = dead_moment_work(moment, theta, dtheta)
        if follower:
            work += ufl.dot(ufl.dot(R, self.tip_force), dd)
        work = work * self.ds_tip
        if self.point_moments:
            work += self.point_work(self.point_moments,
                                    lambda point: dead_moment_work(point, theta, dtheta))
        return self.load_factor * work

    def _residual(self):
        test = ufl.TestFunction(self.space)
        residual = ufl.derivative(self.potential(), self.w, test)
        loads = self.model.loads
        if self.moment_loads or loads.follower:
            residual -= self.nonconservative_work(self.state_parts(), test)
        if self.extra_work is not None:
            residual -= self.extra_work(self, self.state_parts(), test)
        return residual

    @property
    def moment_loads(self) -> bool:
        """A tip moment or point moments act (their work has no potential)."""
        loads = self.model.loads
        return bool(any(loads.tip_moment) or any(any(m[1:]) for m in loads.point_moments))

    @property
    def conservative(self) -> bool:
        """The loads derive from a potential (a symmetric tangent): no tip moment, no
        follower force."""
        return not (self.moment_loads or self.model.loads.follower
                    or self.extra_work is not None)

    def multiplier_dofs(self) -> np.ndarray:
        parts = [np.asarray(compat.sub_space_collapsed(self.space, 6 + i)[1])
                 for i in range(len(self.multipliers))]
        return np.concatenate(parts) if parts else np.empty(0, dtype=np.int32)

    def rotation_dofs(self) -> np.ndarray:
        return np.concatenate([self.component_dofs(n) for n in SPATIAL_COMPONENTS[3:]])

    # --- quantities of interest ----------------------------------------------------------------
    def end_values(self, end: str = "xL") -> dict:
        """{u, v, w, R, rotation_vector, position} at an end: u, v, w the displacement from the
        reference (the stress-free shape of a curved rod), R the end frame (rows of the matrix
        whose columns are the directors d1, d2, d3 in world axes)."""
        values = super().end_values(end)
        displacement = np.array([values[n] for n in ("u", "v", "w")])
        x = self.model.length if end == "xL" else 0.0
        if self.chain is not None:  # world position and rotation R_inc R0 of the chain's end
            vector = [values[n] for n in SPATIAL_COMPONENTS[3:]]
            frame = np.array(rotation_matrix(vector)) @ self.chain.frame_at(
                x, "before" if end == "xL" else "after")
            position = np.array(self.reference_point(x)) + displacement
            return {"u": float(displacement[0]), "v": float(displacement[1]),
                    "w": float(displacement[2]), "R": frame.tolist(),
                    "rotation_vector": [float(c) for c in vector],
                    "position": [float(c) for c in position]}
        reference = self.reference_tip if end == "xL" else np.zeros(3)
        vector = [values[n] for n in SPATIAL_COMPONENTS[3:]]
        return {"u": float(displacement[0] - reference[0]),
                "v": float(displacement[1] - reference[1]),
                "w": float(displacement[2] - reference[2]),
                "R": rotation_matrix(vector),
                "rotation_vector": [float(c) for c in vector],
                "position": [float(x + displacement[0]), float(displacement[1]),
                             float(displacement[2])]}

    def output_expressions(self) -> dict:
        """UFL expressions of the strains and section resultants for output (not for
        solving): v1, v2, v3 (v = R^T r'), twist, curvature_y, curvature_z (u - u0), and the
        section force n1, n2, n3 = dW/dv (the constraint multipliers' terms included) and
        moment m1, m2, m3 = dW/du in the section frame (d1, d2, d3): the force and moment the
        part beyond x exerts on the part before it, R n and R m in world axes."""
        d, theta, multipliers = self.fields()
        s = self.strains((d, theta))
        v = ufl.variable(ufl.as_vector(s.v))
        u = ufl.variable(ufl.as_vector(s.u))
        varied = SpatialStrains(tuple(v[i] for i in range(3)), tuple(u[i] for i in range(3)))
        energy = self.law_energy(varied)
        energy += sum((value * varied.constrained(n) for n, value in multipliers.items()),
                      ufl.zero())
        force, moment = ufl.diff(energy, v), ufl.diff(energy, u)
        return {"v1": s.v[0], "v2": s.v[1], "v3": s.v[2], "twist": s.u[0],
                "curvature_y": s.u[1], "curvature_z": s.u[2],
                **{f"n{i + 1}": force[i] for i in range(3)},
                **{f"m{i + 1}": moment[i] for i in range(3)}}

    def section_variations(self, probes) -> list:
        """The variations (dv, du) of the strains v = R^T r' and u in the directions
        ``probes`` (functions of the space, e.g. a unit rotation of one end vertex), UFL
        scalars in the order dv1, dv2, dv3, du1, du2, du3 per probe: with the section forces
        n = dW/dv and m = dW/du the internal virtual work is int n . dv + m . du dx."""
        d, theta, _ = self.fields()
        s = self.strains((d, theta))
        v, u = ufl.as_vector(s.v), ufl.as_vector(s.u)
        columns = []
        for probe in probes:
            dv = ufl.derivative(v, self.w, probe)
            du = ufl.derivative(u, self.w, probe)
            columns += [dv[i] for i in range(3)] + [du[i] for i in range(3)]
        return columns

    def reference_point(self, x: float) -> tuple[float, float, float]:
        """The reference position (X, Y, Z) of the axis point x (the chain's, or (x, 0, 0))."""
        if self.chain is None:
            return float(x), 0.0, 0.0
        return self.model.structure.reference_point(x)

    def directors(self):
        """R's columns d1, d2, d3 (UFL 3-vectors) of the current state (R = R_inc R0 on a
        chain of rods)."""
        _, theta, _ = self.fields()
        R = rotation(theta)
        if self.chain is not None:
            R = ufl.dot(R, self.chain.frame0)
        return [ufl.as_vector([R[i, j] for i in range(3)]) for j in range(3)]

    def strain_range(self) -> StrainRange:
        """Extremes over the energy rule's Gauss points (collective): min v1 (the stretch along
        the section normal: <= 0 is a rod turned inside out), max |eps|, the largest shear angle
        atan(|(v2, v3)| / v1); the rotation vector's length beyond 1.8 pi gets a note
        (`rotation_note`)."""
        if not hasattr(self, "_strain_expression"):
            d, theta, _ = self.fields()
            s = self.strains((d, theta))
            shear = ufl.sqrt(s.v[1] ** 2 + s.v[2] ** 2)
            columns = [s.v[0], s.eps, compat.atan2(shear, s.v[0]), ufl.sqrt(ufl.dot(theta, theta))]
            reference, _ = self.energy_rule()
            self._strain_expression = compat.expression(ufl.as_vector(columns), reference)
        cells = np.arange(self.mesh.topology.index_map(1).size_local, dtype=np.int32)
        values = compat.evaluate_expression(self._strain_expression, self.mesh, cells)
        values = values.reshape(-1, 4)
        local = np.full(4, np.inf)
        if len(values):
            with np.errstate(invalid="ignore"):
                local[0] = np.min(np.where(np.isfinite(values[:, 0]), values[:, 0], -np.inf))
                local[1] = -np.max(np.abs(values[:, 1]))
                local[2] = -np.max(np.abs(values[:, 2]))
                local[3] = -np.max(values[:, 3])
        from mpi4py import MPI

        reduced = np.empty_like(local)
        self.comm.Allreduce(local, reduced, op=MPI.MIN)
        reduced = np.where(np.isnan(reduced), -np.inf, reduced)
        self.largest_rotation = float(-reduced[3])
        return StrainRange(float(reduced[0]), float(-reduced[1]), float(-reduced[2]), None)

    def rotation_note(self) -> str | None:
        """A note (always the same sentence: said once per run) when the last strain range's
        largest rotation vector passed ROTATION_NOTE."""
        if getattr(self, "largest_rotation", 0.0) > ROTATION_NOTE:
            return (f"the rotation vector's length passes {ROTATION_NOTE:.3g} rad (1.8 pi), near "
                    "2 pi where its parametrisation is singular: a state out of a single plane "
                    "is ill-conditioned there (a planar roll-up is not)")
        return None

    def strain_energy_form(self) -> fem.Form:
        return fem.form(self.law_energy(self.strains(self.state_parts())) * self.dx_energy)

    # --- inertia (docs/theory.md, Spatial rods: dynamics and modes) ------------------------------
    motion_count = 6
    translations = 3

    def motion_parts(self, pieces):
        """(d, theta) of the first six scalar pieces of a mixed function."""
        return ufl.as_vector(pieces[0:3]), ufl.as_vector(pieces[3:6])

    def body_inertia(self):
        """rho J, J = diag(I_p, I_y, I_z) in the body frame (I_p = I_y + I_z: the polar moment
        of the section's area about the centroid; the torsional stiffness uses the Saint-Venant
        J instead)."""
        p = self.section_props
        inertia = self.rho * ufl.as_matrix([[p.Iy + p.Iz, 0, 0], [0, p.Iy, 0], [0, 0, p.Iz]])
        if self.chain is not None:  # R = R_inc R0: omega = R0^T omega_inc, so R0 J R0^T
            return ufl.dot(self.chain.frame0, ufl.dot(inertia, self.chain.frame0.T))
        return inertia

    def _pieces(self, test):
        if isinstance(test, (list, tuple)):
            return test
        return ufl.split(test)

    def mass_work(self, parts, acceleration, test):
        """rho A d_tt . dd + M(theta) theta_tt . dtheta, M = T(-theta)^T rho J T(-theta)
        (``parts`` = (d, theta); ``acceleration``, ``test``: pieces or a test function)."""
        t = self._pieces(test)
        a = acceleration
        _, theta = parts
        rho_area = self.rho * self.section_props.A
        dd, dtheta = ufl.as_vector(t[0:3]), ufl.as_vector(t[3:6])
        a_d, a_theta = ufl.as_vector(a[0:3]), ufl.as_vector(a[3:6])
        mass = rotational_mass(theta, self.body_inertia())
        return (rho_area * ufl.dot(a_d, dd)
                + ufl.dot(ufl.dot(mass, a_theta), dtheta)) * self.dx_mass

    def velocity_inertia_work(self, parts, rates, test):
        """g(theta, theta_t) . dtheta: the part of d/dt dT/dtheta_t - dT/dtheta quadratic in
        theta_t (`fe_beam.fem.rotations.lagrangian_inertia`)."""
        t = self._pieces(test)
        _, theta = parts
        _, g = lagrangian_inertia(theta, ufl.as_vector(rates[3:6]), self.body_inertia())
        return ufl.dot(g, ufl.as_vector(t[3:6])) * self.dx_mass

    def kinetic_energy(self, parts, rates):
        """int 1/2 rho A |d_t|^2 + 1/2 omega . rho J omega, omega = T(-theta) theta_t."""
        _, theta = parts
        d_t, theta_t = ufl.as_vector(rates[0:3]), ufl.as_vector(rates[3:6])
        rho_area = self.rho * self.section_props.A
        return (0.5 * rho_area * ufl.dot(d_t, d_t)
                + rotational_kinetic_energy(theta, theta_t, self.body_inertia())) * self.dx_mass

    def momentum_densities(self, parts, rates) -> dict:
        """Linear momentum rho A r_t and the angular momentum about the origin
        r x rho A r_t + R rho J omega (world components), per unit length."""
        d, theta = parts
        d_t, theta_t = ufl.as_vector(rates[0:3]), ufl.as_vector(rates[3:6])
        rho_area = self.rho * self.section_props.A
        r = ufl.as_vector([self.x + d[0], d[1], d[2]])
        if self.chain is not None:  # a chain of rods: its reference position
            r = self.chain.reference + d
        linear = rho_area * d_t
        spin = ufl.dot(rotation(theta), ufl.dot(self.body_inertia(),
                                                angular_velocity(theta, theta_t)))
        angular = ufl.cross(r, linear) + spin
        values = {f"momentum_{k}": linear[i] for i, k in enumerate("xyz")}
        values.update({f"angular_momentum_{k}": angular[i] for i, k in enumerate("xyz")})
        return values

    def mass_form(self):
        """The mass about the current state (the undeformed or a static pre-state): the second
        derivative of the kinetic energy in the velocities at zero velocity."""
        trial, test = ufl.TrialFunction(self.space), ufl.TestFunction(self.space)
        d, theta, _ = self.fields()
        return self.mass_work((d, theta), ufl.split(trial), test)

    @property
    def nonpotential_loads(self) -> bool:
        return not self.conservative

    def bending_stiffness(self):
        p = self.section_props
        return self.E * ufl.min_value(p.Iy, p.Iz)

    def rigid_motion_candidates(self) -> list:
        """Translations e_i and rotations about the origin about e_i of the current state:
        dd = e_i x r, dtheta = T(theta)^-1 e_i (the spatial spin e_i), multipliers unchanged."""
        subs = [compat.sub_space_collapsed(self.space, i) for i in range(6)]
        dofs = [np.asarray(parent) for _, parent in subs]
        x = subs[0][0].tabulate_dof_coordinates()[:, 0]
        state = compat.local_array(self.w)
        where = np.array([self.reference_point(s) for s in x]).reshape(-1, 3)
        position = where + np.stack([state[dofs[i]] for i in range(3)], axis=1)
        theta = np.stack([state[dofs[3 + i]] for i in range(3)], axis=1)
        inverse = np.array([np.linalg.inv(spin_matrix(t)) for t in theta]).reshape(-1, 3, 3)
        candidates = []
        for k in range(6):
            function = fem.Function(self.space)
            array = compat.local_array(function)
            if k < 3:
                array[dofs[k]] = 1.0
            else:
                axis = np.eye(3)[k - 3]
                moved = np.cross(axis, position)
                rates = inverse @ axis
                for i in range(3):
                    array[dofs[i]] = moved[:, i]
                    array[dofs[3 + i]] = rates[:, i]
            candidates.append(function)
        return candidates

    def mode_shares(self, shape) -> dict:
        """The shares of a mode's kinetic energy (its mass norm) by family, in the current
        state's section frame (d1, d2, d3): with dr = R^T dd the displacement in that frame,
        axial (rho A dr_1^2), torsion (rho I_p omega_1^2), bending about y (rho A dr_3^2 +
        rho I_y omega_2^2), bending about z (rho A dr_2^2 + rho I_z omega_3^2), omega =
        T(-theta) dtheta the body rotation about the current state; and "transverse", the share
        of dr_2, dr_3 in the translational part. Straight (theta = 0) these are the reference
        axes' u, v, w; about a bent pre-state a bending mode moves normal to the bent axis
        (in reference axes along x where the rod is turned by more than 45 degrees)."""
        if self.chain is not None:
            return self._chain_mode_shares(shape)
        pieces = ufl.split(shape)
        _, theta, _ = self.fields()
        omega = angular_velocity(theta, ufl.as_vector(pieces[3:6]))
        body = ufl.dot(rotation(theta).T, ufl.as_vector(pieces[0:3]))
        p, rho = self.section_props, self.rho
        rho_area = rho * p.A
        integrands = {
            "axial": rho_area * body[0] ** 2,
            "torsion": rho * (p.Iy + p.Iz) * omega[0] ** 2,
            "bending about y": rho_area * body[2] ** 2 + rho * p.Iy * omega[1] ** 2,
            "bending about z": rho_area * body[1] ** 2 + rho * p.Iz * omega[2] ** 2,
            "transverse": p.A * (body[1] ** 2 + body[2] ** 2),
            "translation": p.A * (body[0] ** 2 + body[1] ** 2 + body[2] ** 2),
        }
        values = {k: assemble_scalar(fem.form(v * self.dx_mass)) for k, v in integrands.items()}
        total = sum(values[k] for k in MODE_FAMILIES)
        shares = {k: values[k] / total if total > 0 else 0.0 for k in MODE_FAMILIES}
        shares["transverse"] = (values["transverse"] / values["translation"]
                                if values["translation"] > 0 else 0.0)
        return shares

    def _chain_mode_shares(self, shape) -> dict:
        """Along a chain of rods a member's rigid motion along its axis (the beam of a swaying
        frame) is no axial deformation: the shares are those of the shape's linearised strain
        energy, each rod's strains in its own frame (dv, du the variations of v = R^T r' and
        u about the current state): axial EA dv1^2, torsion GJ du1^2, bending about y
        EI_y du2^2 + k GA dv3^2, bending about z EI_z du3^2 + k GA dv2^2; "transverse" the
        share not in stretching."""
        d, theta, _ = self.fields()
        s = self.strains((d, theta))
        dv = ufl.derivative(ufl.as_vector(s.v), self.w, shape)
        du = ufl.derivative(ufl.as_vector(s.u), self.w, shape)
        p = self.section_props
        E, G = self.law_moduli
        shear = self.k_shear * G * p.A
        integrands = {
            "axial": E * p.A * dv[0] ** 2,
            "torsion": G * p.J * du[0] ** 2,
            "bending about y": E * p.Iy * du[1] ** 2 + shear * dv[2] ** 2,
            "bending about z": E * p.Iz * du[2] ** 2 + shear * dv[1] ** 2,
        }
        values = {k: assemble_scalar(fem.form(v * self.dx_energy)) for k, v in integrands.items()}
        total = sum(values.values())
        shares = {k: values[k] / total if total > 0 else 0.0 for k in MODE_FAMILIES}
        shares["transverse"] = 1.0 - shares["axial"] if total > 0 else 0.0
        return shares

    def mode_kind(self, shares: dict) -> str:
        """The family with the largest share."""
        return max(MODE_FAMILIES, key=lambda k: shares[k])

    def velocity_to_rates(self, values: list) -> list:
        """Initial velocities [u_t, v_t, w_t, w_x, w_y, w_z] at the dofs, (w_x, w_y, w_z) the
        sections' angular velocity in world axes: theta_t = T(theta)^-1 w (the identity at
        theta = 0)."""
        subs = [np.asarray(compat.sub_space_collapsed(self.space, 3 + i)[1]) for i in range(3)]
        state = compat.local_array(self.w)
        theta = np.stack([state[d] for d in subs], axis=1)
        spin = np.stack([np.asarray(values[3 + i], dtype=float) for i in range(3)], axis=1)
        rates = np.array([np.linalg.solve(spin_matrix(t), w) for t, w in zip(theta, spin,
                                                                             strict=True)])
        rates = rates.reshape(-1, 3)
        return list(values[:3]) + [rates[:, i] for i in range(3)]

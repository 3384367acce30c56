"""Energy-momentum time integration of the spatial rod: `[time] scheme = "energy-conserving"`
with `[model] kinematics = "spatial"` (docs/theory.md, Spatial rods: the energy-momentum
scheme). The spatial counterpart of `fe_beam.solvers.energy_momentum.EnergyMomentum`, after
Simo, Tarnow & Doblare (1995) and Romero & Armero (2002).

State at t_n: the nodal displacements d_n and velocities v_n; at the Gauss points of the energy
rule the rotation Lambda_n (a matrix) and the material curvature K_n (Lambda' = Lambda K^); at
the points of the mass rule the rotation Lambda_n and the body angular velocity W_n. The
unknowns of a step are d_{n+1}, the nodal spatial Cayley parameter psi of the rotation
increment (interpolated like theta) and the multipliers. With c^2 = 1/(1 + |psi|^2/4),
cay(psi) = I + c^2 (psi^ + psi^ psi^ / 2):

    Lambda_{n+1} = cay(psi) Lambda_n,          K_{n+1} = K_n + Lambda_n^T H(psi) psi',
    H(psi) = c^2 (I - psi^/2),                 W_{n+1} = 2 Lambda_n^T psi / dt - W_n,
    v_{n+1} = 2 (d_{n+1} - d_n) / dt - v_n,

pointwise at the Gauss points (exactly Lambda_{n+1}' = Lambda_{n+1} K_{n+1}^). The material
strains pi = (Gamma = Lambda^T r', K - K0) change by Delta pi = L(Delta d, psi) exactly, with the
strain variation (linear in the test (dd, dphi))

    L_Gamma = Lambda_n^T A(psi) (dd' - dphi x r'_m),   A(psi) = c^2 (I - psi^/2 + psi psi^T/4),
    L_K     = Lambda_n^T H(psi) dphi'                  (r'_m = (r'_n + r'_{n+1}) / 2),

which vanishes on translations and on the rigid rotations (e x r_m, e) about the midpoint. The
balance, tested with (dd, dphi),

    rho A (v_{n+1} - v_n)/dt . dd + (pi_{n+1} - pi_n)/dt . dphi + int S_d . L dx
      + int mu . L_c dx + c (Delta d / dt) . dd - f_{n+1/2} . dd - M_{n+1/2} . (phi/|psi|) dphi = 0,

pi = Lambda rho J W the spatial angular momentum density, S_d the Gonzalez discrete gradient of
W in strain space, phi = 2 atan(|psi|/2) (the dead moment does the work M . (phi psi/|psi|), the
rotation vector of the increment). Testing with (Delta d, psi) gives kinetic + stored energy
change = work of the dead loads - dissipated work exactly (the rotational part: psi . (pi_{n+1} -
pi_n) = dt (T_{n+1} - T_n) since cay(Psi) Psi = Psi); testing with translations and with
(e x r_m, e) gives the linear and angular momentum balances exactly. Second order in dt.

The nodal rotation vector of the problem's state (what the outputs read) follows the nodes'
rotations Lambda = cay(psi) Lambda_n, continuous along the rod and re-parametrised at x = 0
beyond 1.5 pi (`_nodal_vectors`): it is output only, the scheme never evaluates T(theta), and
passes |theta| = 2 pi.

A follower tip force and moment (tip frame) act as R_m F and R_m M, R_m = (Lambda_n +
Lambda_{n+1})/2 at the tip, their work over the step (R_m F . Delta d + R_m M . phi n) booked as
applied: the balance stays exact. Not taken (ConfigError): tendons, chains of rods, prescribed
end motions, Kelvin-Voigt damping, contact.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import basix
import numpy as np
import ufl
from dolfinx import fem

from fe_beam.errors import ConfigError
from fe_beam.fem import compat
from fe_beam.fem.mpi import assemble_scalar, global_max
from fe_beam.fem.rod import StrainRange, StrainWatch
from fe_beam.fem.rotations import curvature, rotation, skew
from fe_beam.fem.spatial_rod import SpatialRodProblem, rotation_vector_of
from fe_beam.model.spatial import SPATIAL_COMPONENTS, SpatialStrains, rotation_matrix
from fe_beam.solvers.dynamics import Damping, StepDriver, TimeSettings
from fe_beam.solvers.energy_momentum import start_state
from fe_beam.solvers.newton import NonlinearProblem, SNESSolver, SolveFailed, SolverSettings

__all__ = ["SpatialEnergyMomentum", "cayley", "MAX_ROTATION_INCREMENT"]

# a step whose rotation increment reaches this anywhere is rejected (cut back), as the planar
# scheme's: the Cayley parameter 2 tan(|Dtheta|/2) grows without bound towards pi
MAX_ROTATION_INCREMENT = 2.0
# |Delta pi|_D^2 below which the discrete gradient is the midpoint gradient
SMALL_INCREMENT = 1e-16
SERIES = 1e-3  # |psi| below which 2 atan(|psi|/2)/|psi| is its series
#: the length of the output's rotation vector at x = 0 beyond which it is re-parametrised
REPARAMETRISE = 1.5 * math.pi


def cayley(psi: np.ndarray) -> np.ndarray:
    """cay(psi) of an array (..., 3) of Cayley parameters: (..., 3, 3)."""
    psi = np.asarray(psi, dtype=float)
    S = np.zeros(psi.shape[:-1] + (3, 3))
    S[..., 0, 1], S[..., 0, 2], S[..., 1, 2] = -psi[..., 2], psi[..., 1], -psi[..., 0]
    S[..., 1, 0], S[..., 2, 0], S[..., 2, 1] = psi[..., 2], -psi[..., 1], psi[..., 0]
    c2 = 1.0 / (1.0 + np.einsum("...i,...i", psi, psi) / 4)
    return np.eye(3) + c2[..., None, None] * (S + 0.5 * S @ S)


def _orthonormal(matrices: np.ndarray) -> np.ndarray:
    """The nearest rotations (polar factor) of (..., 3, 3): removes the round-off drift."""
    u, _, vt = np.linalg.svd(matrices)
    return u @ vt


class _PointStore:
    """Values at the points of one quadrature rule (all local cells), as scalar Quadrature
    functions (for the forms) and (cells, points, ...) arrays (for the updates)."""

    def __init__(self, mesh, degree: int, components: int):
        self.space = compat.function_space(mesh, compat.quadrature_element(mesh, degree))
        self.points = basix.make_quadrature(basix.CellType.interval, degree)[0]
        self.functions = [fem.Function(self.space) for _ in range(components)]
        self.cells = np.arange(mesh.topology.index_map(1).size_local, dtype=np.int32)
        self.dofs = compat.cell_dofs(self.space)[: len(self.cells)]
        self.mesh = mesh

    def evaluate(self, compiled, size: int) -> np.ndarray:
        """A compiled expression at the points: (cells, points, size)."""
        values = compat.evaluate_expression(compiled, self.mesh, self.cells)
        return np.asarray(values).reshape(len(self.cells), len(self.points), size)

    def get(self) -> np.ndarray:
        """(cells, points, components) of the stored functions."""
        return np.stack([f.x.array[self.dofs] for f in self.functions], axis=-1)

    def set(self, values: np.ndarray) -> None:
        for index, function in enumerate(self.functions):
            function.x.array[self.dofs] = values[..., index]
            function.x.scatter_forward()

    def matrix(self, start: int = 0):
        return ufl.as_matrix([[self.functions[start + 3 * i + j] for j in range(3)]
                              for i in range(3)])

    def three_vector(self, start: int):
        return ufl.as_vector([self.functions[start + i] for i in range(3)])


class SpatialEnergyMomentum(StepDriver):
    """Energy-momentum integration of a `SpatialRodProblem` (its laws through
    ``problem.law_energy``, constraints, tapered and curved rods, supports, dead loads and dead
    moments). Same interface as `fe_beam.solvers.energy_momentum.EnergyMomentum`."""

    def __init__(self, problem: SpatialRodProblem, settings: TimeSettings,
                 damping: Damping = Damping(),  # noqa: B008
                 load_function: Callable[[float], float] = lambda t: 1.0,
                 motion_function: Callable[[float], float] | None = None,
                 solver_settings: SolverSettings | None = None):
        model = problem.model
        if model.material.rho <= 0:
            raise ValueError("dynamics needs material.rho > 0")
        why = refusal(problem, damping)
        if why:
            raise ConfigError(why)
        self.problem = problem
        self.settings = settings
        self.damping = damping
        self.load_function = load_function
        self.motion_function = motion_function or load_function
        self.time = 0.0
        self.watch = StrainWatch()
        self._trial_range = None
        mesh, space = problem.mesh, problem.space
        degree = model.mesh.degree
        self.energy_degree, self.mass_degree = 2 * degree - 1, 2 * degree + 2
        # energy rule: Lambda (9), K (3); mass rule: Lambda (9), W (3)
        self.at_energy = _PointStore(mesh, self.energy_degree, 12)
        self.at_mass = _PointStore(mesh, self.mass_degree, 12)
        for index, function in enumerate(self.at_energy.functions):
            setattr(self, f"_energy_store_{index}", function)
        for index, function in enumerate(self.at_mass.functions):
            setattr(self, f"_mass_store_{index}", function)
        # the Gauss-point terms get their own integration domain (every cell, tag 1), as the
        # planar scheme's (`EnergyMomentum`): one quadrature rule per kernel
        cells = np.arange(mesh.topology.index_map(1).size_local
                          + mesh.topology.index_map(1).num_ghosts, dtype=np.int32)
        tags = compat.meshtags(mesh, 1, cells, np.ones(len(cells), dtype=np.int32))
        self.dx_gauss = ufl.Measure("dx", domain=mesh, subdomain_data=tags, subdomain_id=1,
                                    metadata={"quadrature_degree": self.energy_degree})
        self.q_old, self.v_old, self.unknown = (fem.Function(space) for _ in range(3))
        const = lambda value: fem.Constant(mesh, float(value))  # noqa: E731
        self.dt = const(settings.dt)
        self.c = const(damping.c)
        self.follower = bool(model.loads.follower)
        self.tip_rotation = fem.Constant(mesh, np.eye(3))  # Lambda_n at x = L (follower loads)
        self.bcs, self._bc_values = self._dirichlet_conditions()
        self._build_forms()
        self.solver = SNESSolver(NonlinearProblem(self.residual, self.unknown, self.bcs),
                                 (solver_settings or SolverSettings()).for_problem(
                                     problem.saddle_point, problem.comm),
                                 prefix="fe_beam_spatial_energy_momentum_",
                                 state_scale=model.length)

    # --- forms -----------------------------------------------------------------------------------
    @property
    def dx_mass(self):
        return ufl.dx(metadata={"quadrature_degree": self.mass_degree})

    def _build_forms(self) -> None:
        p = self.problem
        dt = self.dt
        new, old, vel = (ufl.split(f) for f in (self.unknown, self.q_old, self.v_old))
        e1 = ufl.as_vector([1.0, 0.0, 0.0])
        d0, d1 = ufl.as_vector(old[0:3]), ufl.as_vector(new[0:3])
        psi = ufl.as_vector(new[3:6])
        t0, t1 = e1 + d0.dx(0), e1 + d1.dx(0)
        tm = (t0 + t1) / 2
        eye = ufl.Identity(3)
        S = skew(psi)
        c2 = 1 / (1 + ufl.dot(psi, psi) / 4)
        A = c2 * (eye - S / 2 + ufl.outer(psi, psi) / 4)
        H = c2 * (eye - S / 2)
        cay = eye + c2 * (S + S * S / 2)
        lam_e, kappa_e = self.at_energy.matrix(), self.at_energy.three_vector(9)
        lam_m, spin_m = self.at_mass.matrix(), self.at_mass.three_vector(9)
        intrinsic = p.intrinsic

        def variation(dd_prime, dphi, dphi_prime):
            gamma = ufl.dot(lam_e.T, ufl.dot(A, dd_prime - ufl.cross(dphi, tm)))
            kappa = ufl.dot(lam_e.T, ufl.dot(H, dphi_prime))
            return [gamma[i] for i in range(3)] + [kappa[i] for i in range(3)]

        v0 = ufl.dot(lam_e.T, t0)
        pi0 = [v0[i] for i in range(3)] + [kappa_e[i] - intrinsic[i] for i in range(3)]
        dpi = variation(d1.dx(0) - d0.dx(0), psi, psi.dx(0))
        pi1 = [a + b for a, b in zip(pi0, dpi, strict=True)]

        def energy(pi):
            return p.law_energy(SpatialStrains(tuple(pi[0:3]), tuple(pi[3:6])))

        middle = [ufl.variable((a + b) / 2) for a, b in zip(pi0, pi1, strict=True)]
        gradient = [ufl.diff(energy(middle), m) for m in middle]
        props = p.section_props
        metric = [1.0, 1.0, 1.0] + [(props.Iy + props.Iz) / props.A] * 3
        norm2 = sum(m * d**2 for m, d in zip(metric, dpi, strict=True))
        excess = energy(pi1) - energy(pi0) - sum(g * d for g, d in zip(gradient, dpi,
                                                                       strict=True))
        coefficient = ufl.conditional(ufl.gt(norm2, SMALL_INCREMENT),
                                      excess / ufl.max_value(norm2, SMALL_INCREMENT), 0.0)
        stress = [g + coefficient * m * d for g, m, d in zip(gradient, metric, dpi, strict=True)]

        test = ufl.TestFunction(p.space)
        tp = ufl.split(test)
        dd, dphi = ufl.as_vector(tp[0:3]), ufl.as_vector(tp[3:6])
        test_variation = variation(dd.dx(0), dphi, dphi.dx(0))
        rho_area = p.rho * props.A
        inertia = p.body_inertia()
        increment = d1 - d0
        velocity0 = ufl.as_vector(vel[0:3])
        acceleration = 2 * (increment - dt * velocity0) / dt**2  # (v1 - v0)/dt
        spin1 = 2 * ufl.dot(lam_m.T, psi) / dt - spin_m  # W_{n+1}
        momentum0 = ufl.dot(lam_m, ufl.dot(inertia, spin_m))
        momentum1 = ufl.dot(cay, ufl.dot(lam_m, ufl.dot(inertia, spin1)))
        dx_e, dx_m = self.dx_gauss, self.dx_mass
        residual = (rho_area * ufl.dot(acceleration, dd)
                    + ufl.dot(momentum1 - momentum0, dphi) / dt
                    + self.c * ufl.dot(increment / dt, dd)) * dx_m
        residual += sum(s * v for s, v in zip(stress, test_variation, strict=True)) * dx_e
        for offset, name in enumerate(p.multipliers):
            multiplier, check = new[6 + offset], tp[6 + offset]
            if name == "eps":
                variation_c = ufl.dot(tm, dd.dx(0))
                value = (ufl.dot(t1, t1) - 1) / 2
            else:
                index = {"g2": 1, "g3": 2}[name]
                variation_c, value = test_variation[index], pi1[index]
            residual += (multiplier * variation_c + check * value) * dx_e
        # dead forces at the step's mean load factor on dd (linear: exact discrete gradient);
        # dead moments on (phi/|psi|) dphi, phi = 2 atan(|psi|/2)
        residual -= p.dead_load_work((dd, None))
        # follower tip force and moment (tip frame): R_m F, R_m M with R_m = (Lambda_n +
        # Lambda_{n+1}) / 2 at the tip, their work over the step booked as applied (`accept`)
        turned = ufl.dot((eye + cay) / 2, self.tip_rotation)
        size = ufl.sqrt(ufl.dot(psi, psi))
        small = ufl.lt(size, SERIES)
        safe = ufl.conditional(small, 1.0, size)
        size2 = ufl.dot(psi, psi)
        ratio = ufl.conditional(small, 1 - size2 / 12 + size2**2 / 80,
                                2 * ufl.atan(safe / 2) / safe)
        moment_work = self._moment_work(ratio * dphi, turned)
        if self.follower:
            moment_work += p.load_factor * ufl.dot(ufl.dot(turned, p.tip_force), dd) * p.ds_tip
        if moment_work is not None:
            residual -= moment_work
        self.residual = residual
        # the work of the moments and follower loads over the step: tested with the increment
        step_work = self._moment_work(ratio * psi, turned)
        if self.follower:
            step_work += p.load_factor * ufl.dot(ufl.dot(turned, p.tip_force),
                                                 increment) * p.ds_tip
        self._moment_step_work = fem.form(step_work) if step_work is not None else None
        # point updates (evaluated on the candidate before it is accepted), as expressions of
        # the nodal fields only (the stored point values are combined in numpy)
        self._psi_e = compat.expression(ufl.as_vector([psi[i] for i in range(3)]
                                                      + [psi.dx(0)[i] for i in range(3)]),
                                        self.at_energy.points)
        self._psi_m = compat.expression(psi, self.at_mass.points)
        self._tangent_e = compat.expression(t1, self.at_energy.points)
        state = ufl.split(p.w)
        theta_state = ufl.as_vector(state[3:6])
        R = rotation(theta_state)
        self._initial_e = compat.expression(
            ufl.as_vector([R[i, j] for i in range(3) for j in range(3)]
                          + [curvature(theta_state)[i] for i in range(3)]),
            self.at_energy.points)
        omega = ufl.as_vector(ufl.split(self.v_old)[3:6])  # world angular velocity (initial)
        self._initial_m = compat.expression(
            ufl.as_vector([R[i, j] for i in range(3) for j in range(3)]
                          + [ufl.dot(R.T, omega)[i] for i in range(3)]),
            self.at_mass.points)
        x = ufl.SpatialCoordinate(p.mesh)[0]
        position = ufl.as_vector([x + old[0], old[1], old[2]])
        linear = rho_area * ufl.as_vector(vel[0:3])
        spin_momentum = ufl.dot(lam_m, ufl.dot(inertia, spin_m))
        angular = ufl.cross(position, linear) + spin_momentum
        strain_state = [ufl.dot(lam_e.T, t0)[i] for i in range(3)] + [
            kappa_e[i] - intrinsic[i] for i in range(3)]
        self.forms = {
            "kinetic": fem.form((0.5 * rho_area * ufl.dot(velocity0, velocity0)
                                 + 0.5 * ufl.dot(spin_m, ufl.dot(inertia, spin_m))) * dx_m),
            "strain": fem.form(energy(strain_state) * dx_e),
            "load_potential": fem.form(p.dead_load_work((d0, None))),
            "damping_work": fem.form(self.c * ufl.dot(increment, increment) / dt * dx_m),
        }
        self.momentum_names = tuple([f"momentum_{k}" for k in "xyz"]
                                    + [f"angular_momentum_{k}" for k in "xyz"])
        for i, k in enumerate("xyz"):
            self.forms[f"momentum_{k}"] = fem.form(linear[i] * dx_m)
            self.forms[f"angular_momentum_{k}"] = fem.form(angular[i] * dx_m)

    def _moment_work(self, rotation_increment, turned):
        """Virtual work of the tip moment (dead: world axes; follower: ``turned`` times it,
        the tip frame) and the dead point moments at the step's load factor on a rotation
        vector (None without moments and follower loads)."""
        p = self.problem
        if not (p.moment_loads or self.follower):
            return None
        moment = ufl.dot(turned, p.tip_moment) if self.follower else p.tip_moment
        work = ufl.dot(moment, rotation_increment) * p.ds_tip
        if p.point_moments:
            work += p.point_work(p.point_moments,
                                 lambda moment: ufl.dot(moment, rotation_increment))
        return p.load_factor * work

    def _dirichlet_conditions(self):
        """Held components: d_{n+1} = d_n, psi = 0 (prescribed motions are refused)."""
        p = self.problem
        bcs, values = [], []
        for end in ("x0", "xL"):
            for name in p.model.supports.fixed(end):
                index = SPATIAL_COMPONENTS.index(name)
                sub, _ = compat.sub_space_collapsed(p.space, index)
                dofs = compat.locate_dofs_geometrical((p.space.sub(index), sub),
                                                      p.end_markers[end])
                value = fem.Function(sub)
                bcs.append(fem.dirichletbc(value, dofs, p.space.sub(index)))
                values.append((value, index, np.asarray(dofs[0]), np.asarray(dofs[1])))
        return bcs, values

    def _set_boundary_values(self) -> None:
        old = compat.local_array(self.q_old)
        for value, index, parent, collapsed in self._bc_values:
            value.x.array[collapsed] = old[parent] if index < 3 else 0.0

    # --- state --------------------------------------------------------------------------------
    def _rotation_columns(self) -> list[np.ndarray]:
        if not hasattr(self, "_rotation_dof_columns"):
            self._rotation_dof_columns = [
                np.asarray(compat.sub_space_collapsed(self.problem.space, 3 + i)[1])
                for i in range(3)]
        return self._rotation_dof_columns

    def _nodes(self) -> None:
        """The x of the rotation's local nodes (ghosts included) and the number owned."""
        if not hasattr(self, "_node_x"):
            sub, _ = compat.sub_space_collapsed(self.problem.space, 3)
            self._node_x = sub.tabulate_dof_coordinates()[:, 0].copy()
            self._node_owned = sub.dofmap.index_map.size_local

    def _set_tip_rotation(self) -> None:
        """Lambda_n of the node at x = L (follower loads), from the rank that owns it."""
        if not self.follower:
            return
        self._nodes()
        owned = self._node_owned
        length = self.problem.model.length
        found = np.flatnonzero(np.abs(self._node_x[:owned] - length) <= 1e-10 * length)
        local = np.zeros(10)
        if len(found):
            local[:9] = self._nodal_rotations[found[0]].ravel()
            local[9] = 1.0
        total = self.problem.comm.allreduce(local)
        self.tip_rotation.value[:] = (total[:9] / max(total[9], 1.0)).reshape(3, 3)

    def _nodal_vectors(self, rotations: np.ndarray, previous: np.ndarray) -> np.ndarray:
        """The nodal rotation vectors of the rotations (local nodes, ghosts included) that the
        outputs read: continuous along the rod (each node's the member of theta + 2 pi k n
        nearest its neighbour's towards x = 0), the node at x = 0 continuous in time and
        re-parametrised, theta -> theta (1 - 2 pi / |theta|) (the same rotation), when its
        length passes `REPARAMETRISE`: the interpolated vectors stay away from |theta| = 2 pi,
        where the chart's interpolation would not be the rotations'."""
        p = self.problem
        self._nodes()
        owned = self._node_owned
        gathered = p.comm.allgather((self._node_x[:owned], rotations[:owned],
                                     previous[:owned]))
        xs = np.concatenate([g[0] for g in gathered])
        matrices = np.concatenate([g[1] for g in gathered]).reshape(-1, 3, 3)
        before = np.concatenate([g[2] for g in gathered]).reshape(-1, 3)
        order = np.argsort(xs, kind="stable")
        vectors = np.empty((len(xs), 3))
        first = order[0]
        base = rotation_vector_of(matrices[first], near=before[first])
        size = float(np.linalg.norm(base))
        if size > REPARAMETRISE:
            base = base * (1 - 2 * math.pi / size)
        vectors[first] = base
        for previous_index, index in zip(order[:-1], order[1:], strict=True):
            vectors[index] = rotation_vector_of(matrices[index], near=vectors[previous_index])
        sorted_x = xs[order]
        local = order[np.clip(np.searchsorted(sorted_x, self._node_x), 0, len(xs) - 1)]
        return vectors[local]

    def initialise(self, velocity: Callable | None = None) -> None:
        """Start from ``problem.w`` at t = 0 with initial velocities ``velocity(x) -> (u_t,
        v_t, w_t, omega_x, omega_y, omega_z)`` (omega the sections' angular velocity in world
        axes, as `GeneralizedAlpha.initialise`)."""
        p = self.problem
        self.time = 0.0
        p.set_prescribed_factor(self.motion_function(0.0))
        start_state(p, self.q_old, self.v_old, velocity, 6)
        self.v_old.x.scatter_forward()
        energy = self.at_energy.evaluate(self._initial_e, 12)
        energy[..., :9] = _orthonormal(energy[..., :9].reshape(
            energy.shape[:-1] + (3, 3))).reshape(energy.shape[:-1] + (9,))
        self.at_energy.set(energy)
        mass = self.at_mass.evaluate(self._initial_m, 12)
        self.at_mass.set(mass)
        state = compat.local_array(p.w)
        theta = np.stack([state[c] for c in self._rotation_columns()], axis=1)
        self._nodal_rotations = np.array([rotation_matrix(t) for t in theta],
                                         dtype=float).reshape(-1, 3, 3)
        self._set_tip_rotation()
        self._work = 0.0
        self._dissipated = 0.0
        self._load_energy = self._unit_load_energy()
        self.energy0 = self.energies()

    def _load_mid(self, t_old: float, t_new: float) -> float:
        return 0.5 * (self.load_function(t_old) + self.load_function(t_new))

    def step(self, dt: float) -> int:
        """Advance by dt (raises SolveFailed; the accepted state stays in q_old, v_old and the
        point stores)."""
        p = self.problem
        t_old, t_new = self.time, self.time + dt
        self.dt.value = dt
        p.load_factor.value = self._load_mid(t_old, t_new)
        self._set_boundary_values()
        unknown, old = compat.local_array(self.unknown), compat.local_array(self.q_old)
        unknown[:] = old
        columns = self._rotation_columns()
        rotation_dofs = np.concatenate(columns)
        unknown[rotation_dofs] = 0.0  # psi: same-displacement predictor
        iterations = self.solver.solve()
        psi = np.stack([unknown[c] for c in columns], axis=1)
        largest = global_max(p.comm, float(np.max(np.linalg.norm(psi, axis=1), initial=0.0)))
        limit = 2 * math.tan(MAX_ROTATION_INCREMENT / 2)
        if not largest < limit:
            raise SolveFailed(f"rotation increment {2 * math.atan(largest / 2):.3g} rad >= "
                              f"{MAX_ROTATION_INCREMENT:g} rad in one step")
        rotations = _orthonormal(cayley(psi) @ self._nodal_rotations)
        theta = self._nodal_vectors(rotations, np.stack([old[c] for c in columns], axis=1))
        state = unknown.copy()
        for i, c in enumerate(columns):
            state[c] = theta[:, i]
        compat.local_array(p.w)[:] = state
        self._trial_range = self._strain_range()  # collective
        reason = self._trial_range.inadmissible()
        if reason is not None:
            raise SolveFailed(reason)
        v_old = compat.local_array(self.v_old)
        velocity = 2 * (unknown - old) / dt - v_old
        velocity[rotation_dofs] = 2 * unknown[rotation_dofs] / dt - v_old[rotation_dofs]
        velocity[p.multiplier_dofs()] = 0.0
        self._candidate = (state, velocity, rotations, t_old, t_new)
        return iterations

    def _strain_range(self) -> StrainRange:
        """Extremes of the scheme's strains v = Lambda_{n+1}^T r'_{n+1} over the energy rule's
        points (collective): min v1, max |eps|, the largest shear angle (the nodal rotation
        vector of the output is not what the scheme integrates)."""
        values = self.at_energy.evaluate(self._psi_e, 6)
        lam = self.at_energy.get()[..., :9].reshape(values.shape[:-1] + (3, 3))
        lam_new = cayley(values[..., :3]) @ lam
        tangent = self.at_energy.evaluate(self._tangent_e, 3)
        v = np.einsum("...ji,...j->...i", lam_new, tangent).reshape(-1, 3)
        local = np.full(3, -np.inf)
        if len(v):
            local[0] = -float(np.min(v[:, 0]))
            local[1] = float(np.max(np.abs((np.sum(v**2, axis=1) - 1) / 2)))
            local[2] = float(np.max(np.abs(np.arctan2(np.hypot(v[:, 1], v[:, 2]), v[:, 0]))))
        reduced = np.array([global_max(self.problem.comm, float(x)) for x in local])
        return StrainRange(float(-reduced[0]), float(reduced[1]), float(reduced[2]), None)

    def local_error(self) -> float:
        """dt^2/2 |a_{n+1/2} - a_p| over the displacements (a_p the previous step's mean
        acceleration; 0 at the first step): the planar scheme's estimate, translations only."""
        _, velocity, _, t_old, t_new = self._candidate
        dt = t_new - t_old
        acceleration = (velocity - compat.local_array(self.v_old)) / dt
        translation = np.concatenate([np.asarray(compat.sub_space_collapsed(
            self.problem.space, i)[1]) for i in range(3)])
        previous = getattr(self, "_a_prev", None)
        previous = np.zeros_like(acceleration) if previous is None else previous
        local = float(np.max(np.abs(acceleration - previous)[translation], initial=0.0))
        return global_max(self.problem.comm, local) * dt**2 / 2

    def accept(self) -> None:
        state, velocity, rotations, t_old, t_new = self._candidate
        dt = t_new - t_old
        self._a_prev = (velocity - compat.local_array(self.v_old)) / dt
        self._dissipated += assemble_scalar(self.forms["damping_work"])
        load_mid = self._load_mid(t_old, t_new)
        if self._moment_step_work is not None:  # at the step's load factor (still set)
            self._work += assemble_scalar(self._moment_step_work)
        # the point updates, before the state moves on
        values = self.at_energy.evaluate(self._psi_e, 6)
        psi, psi_prime = values[..., :3], values[..., 3:]
        stored = self.at_energy.get()
        lam = stored[..., :9].reshape(stored.shape[:-1] + (3, 3))
        c2 = 1.0 / (1.0 + np.einsum("...i,...i", psi, psi) / 4)
        h_psi = c2[..., None] * (psi_prime - 0.5 * np.cross(psi, psi_prime))
        kappa = stored[..., 9:] + np.einsum("...ji,...j->...i", lam, h_psi)
        lam_new = _orthonormal(cayley(psi) @ lam)
        self.at_energy.set(np.concatenate([lam_new.reshape(lam.shape[:-2] + (9,)), kappa],
                                          axis=-1))
        psi = self.at_mass.evaluate(self._psi_m, 3)
        stored = self.at_mass.get()
        lam = stored[..., :9].reshape(stored.shape[:-1] + (3, 3))
        spin = 2 * np.einsum("...ji,...j->...i", lam, psi) / dt - stored[..., 9:]
        lam_new = _orthonormal(cayley(psi) @ lam)
        self.at_mass.set(np.concatenate([lam_new.reshape(lam.shape[:-2] + (9,)), spin],
                                        axis=-1))
        compat.local_array(self.q_old)[:] = state
        compat.local_array(self.v_old)[:] = velocity
        self.q_old.x.scatter_forward()
        self.v_old.x.scatter_forward()
        self._nodal_rotations = rotations
        self._set_tip_rotation()
        load_energy = self._unit_load_energy()
        self._work += load_mid * (load_energy - self._load_energy)
        self._load_energy = load_energy
        self.time = t_new
        if self._trial_range is not None:
            self.watch.observe(self._trial_range)

    #: the scheme conserves energy to the Newton tolerance: the balance is judged both ways
    energy_tolerance = 1e-6
    conserving = True
    _state_functions = ("q_old", "v_old") + tuple(
        f"_energy_store_{i}" for i in range(12)) + tuple(f"_mass_store_{i}" for i in range(12))
    _state_attributes = ("time", "_a_prev", "_work", "_dissipated", "_load_energy",
                         "_nodal_rotations")

    def _rotation_note(self) -> str:
        """No rotation-vector chart here: nothing to say about |theta| = 2 pi."""
        return ""

    def reject(self) -> None:
        p = self.problem
        self._set_tip_rotation()  # of the accepted state (also after a restored snapshot)
        compat.local_array(p.w)[:] = compat.local_array(self.q_old)
        p.load_factor.value = self.load_function(self.time)

    def energies(self) -> dict:
        kinetic = assemble_scalar(self.forms["kinetic"])
        strain = assemble_scalar(self.forms["strain"])
        values = {"kinetic": kinetic, "strain": strain, "external_work": self._work,
                  "dissipated": self._dissipated}
        start = getattr(self, "energy0", None)
        initial = start["kinetic"] + start["strain"] if start else kinetic + strain
        values["balance_residual"] = kinetic + strain + self._dissipated - self._work - initial
        return values


def refusal(problem, damping) -> str | None:
    """Why the spatial energy-momentum scheme does not take ``problem`` (a sentence), or
    None."""
    model = problem.model
    scheme = "[time] scheme = \"energy-conserving\" for spatial rods"
    if getattr(problem, "chain", None) is not None:
        return f"{scheme} does not take chains of rods yet; use scheme = \"generalized-alpha\""
    if problem.extra_energy is not None or problem.extra_work is not None:
        return f"{scheme} takes no [[tendons]]; use scheme = \"generalized-alpha\""
    if damping.kelvin_voigt:
        return f"{scheme} takes the viscous [damping] c only, not kelvin_voigt"
    for end in ("x0", "xL"):
        if any(getattr(model.supports, f"prescribed_{end}").values()):
            return (f"{scheme} takes no prescribed end motions (supports {end}); use "
                    "scheme = \"generalized-alpha\"")
    return None

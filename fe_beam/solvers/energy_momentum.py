"""Energy-momentum time integration of the rod: `[time] scheme = "energy-conserving"`
(docs/theory.md, Time integration, "Energy-conserving scheme").

State at t_n: r = (x + u, v) and the velocities (u_t, v_t, w = theta_t) as finite-element fields,
and the rotation and curvature (theta_q, kappa_q) at the Gauss points of the energy rule. The
unknowns of a step are r_{n+1}, the nodal Cayley parameter psi = 2 tan(Dtheta / 2) of the
rotation increment (interpolated like theta) and the multipliers. With c^2 = 1/(1 + psi^2/4):

    r_{n+1} - r_n = dt (v_n + v_{n+1}) / 2,      psi = dt (w_n + w_{n+1}) / 2,
    theta_{n+1} = theta_n + 2 atan(psi / 2),     kappa_{n+1} = kappa_n + c^2 psi'

(pointwise at the Gauss points: exactly theta_{n+1}' = kappa_{n+1}). The strains
pi = (1 + e, g, eps, kappa), Gamma = (1 + e, g) = R(-theta) r', eps = (|r'|^2 - 1)/2, change by
Delta pi = L(Delta r, psi) exactly, with the strain variation (linear in the test (dr, dth))

    L_Gamma = c^2 R(-theta_n) (I - psi/2 J) [dr' - dth J r'_m],  L_eps = r'_m . dr',
    L_kappa = c^2 dth'                                            (r'_m = (r'_n + r'_{n+1})/2)

which vanishes on translations and on the rigid rotation (J r_m, 1) about the midpoint. The
balance, tested with (dr, dth),

    rho A (v_{n+1} - v_n)/dt . dr + rho I (w_{n+1} - w_n)/dt dth + int (S_d + S_v) . L dx
      + int mu . L_c dx + c v_m . dr - f_{n+1/2} . dr - M_{n+1/2} (phi/psi) dth = 0,

with S_d the Gonzalez discrete gradient of W in strain space (S_d . Delta pi = W(pi_{n+1}) -
W(pi_n)), S_v the Kelvin-Voigt stress eta (0, GA, EA, EI) Delta pi / dt, the constrained strains
enforced at t_{n+1}, phi = 2 atan(psi/2) (the tip moment does the work M Delta theta). Testing
with (Delta r, psi) gives kinetic + stored energy change = work of the dead loads - dissipated
work exactly; testing with translations and with (J r_m, 1) gives the linear and angular
momentum balances exactly. A follower tip force is applied at the midpoint state (its direction
at theta_{n+1/2}); its work over a step, f(theta_{n+1/2}) . Delta r, is in external_work, so the
balance stays exact with follower loads too. Tendons (tension control) are load potentials in
the strains (``tendons``: `fe_beam.fem.tendons.TendonSet.strain_potentials`). rho_inf is not used.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import basix
import numpy as np
import ufl
from dolfinx import fem

from fe_beam.errors import ConfigError
from fe_beam.fem import compat
from fe_beam.fem.kinematics import Strains, strains
from fe_beam.fem.mpi import assemble_scalar, global_max
from fe_beam.fem.rod import COMPONENTS, BeamProblem, StrainWatch
from fe_beam.fem.tendons import strain_tendon_length_density as tendon_length_density
from fe_beam.solvers.dynamics import Damping, StepDriver, TimeSettings
from fe_beam.solvers.newton import NonlinearProblem, SNESSolver, SolveFailed, SolverSettings

__all__ = ["EnergyMomentum", "MAX_ROTATION_INCREMENT", "tendon_length_density"]

# a step whose rotation increment reaches this anywhere is rejected (cut back): the Cayley
# parameter 2 tan(Dtheta/2) grows without bound towards pi
MAX_ROTATION_INCREMENT = 2.0
# |Delta pi|_D^2 below which the discrete gradient is the midpoint gradient (the neglected
# W(pi1) - W(pi0) - grad W(pi_mid) . Delta pi is O(|Delta pi|^3) ~ 1e-24 of the stiffness)
SMALL_INCREMENT = 1e-16
SERIES = 1e-3  # |psi| below which 2 atan(psi/2)/psi is its series 1 - psi^2/12 + psi^4/80


def start_state(problem, q_old, v_old, velocity: Callable | None, count: int) -> None:
    """The energy-momentum schemes' state at t = 0: ``q_old`` the problem's state, ``v_old``
    zero or the first ``count`` components of ``velocity(x)`` interpolated on their spaces."""
    compat.local_array(q_old)[:] = compat.local_array(problem.w)
    compat.local_array(v_old)[:] = 0.0
    if velocity is None:
        return
    for index in range(count):
        sub, dofs = compat.sub_space_collapsed(problem.space, index)
        values = fem.Function(sub)
        values.interpolate(lambda x, i=index: np.asarray(velocity(x)[i], dtype=float)
                           * np.ones(x.shape[1]))
        compat.local_array(v_old)[np.asarray(dofs)] = values.x.array


def _rotate_back(cos_t, sin_t, vector):
    """R(-theta) vector."""
    return ufl.as_vector([vector[0] * cos_t + vector[1] * sin_t,
                          vector[1] * cos_t - vector[0] * sin_t])


def _perp(vector):
    """J vector (rotation by +90 degrees)."""
    return ufl.as_vector([-vector[1], vector[0]])


class EnergyMomentum(StepDriver):
    """Energy-momentum integration of a `BeamProblem` (all laws through
    ``problem.energy_density``, all constraints, tapered sections, prescribed end motions).

    Same interface as `fe_beam.solvers.dynamics.GeneralizedAlpha`: ``initialise``, ``run``,
    ``energies``, ``momenta``; ``settings.rho_inf`` is ignored.
    """

    def __init__(self, problem: BeamProblem, settings: TimeSettings, damping: Damping = Damping(),
                 load_function: Callable[[float], float] = lambda t: 1.0,
                 motion_function: Callable[[float], float] | None = None,
                 solver_settings: SolverSettings | None = None,
                 potentials: Sequence[tuple[Callable, Callable[[float], float]]] = (),
                 tendons=None):
        """``potentials``: load potentials that are functions of the strains, e.g. a tendon's
        tau l: pairs (density, time_function) with density(strains) the potential per unit
        length at the energy Gauss points at factor 1 (a `fe_beam.fem.kinematics.Strains` of UFL
        expressions; see `tendon_length_density`), scaled in each step by the mean of
        time_function over the step; their work (minus the change of the potential) is part of
        external_work.

        ``tendons``: a `fe_beam.fem.tendons.TendonSet` (tension control only) on ``problem``, whose
        energy must not be the problem's extra_energy: each tendon is a potential tau_i(t) l_i
        in the strains (`TendonSet.strain_potentials`, its own time function), its work is
        also reported as ``tendon_work`` and its length of the state by `tendon_lengths`."""
        if problem.model.material.rho <= 0:
            raise ValueError("dynamics needs material.rho > 0")
        if problem.extra_energy is not None:
            raise ConfigError("[time] scheme = energy-conserving takes tendons as potentials in "
                              "the strains, not as the problem's extra_energy (pass tendons=)")
        if tendons is not None and any(t.controlled_by_pull_in for t in tendons.tendons):
            raise ConfigError("[time] scheme = energy-conserving: [[tendons]] take a tension, "
                              "not a pull_in (use scheme = \"generalized-alpha\" for pull-in "
                              "control)")
        self.tendons = tendons
        potentials = list(potentials)
        self._tendon_indices = []
        if tendons is not None:
            start = len(potentials)
            potentials += tendons.strain_potentials(problem)
            self._tendon_indices = list(range(start, len(potentials)))
        self.problem = problem
        self.settings = settings
        self.damping = damping
        self.load_function = load_function
        self.motion_function = motion_function or load_function
        self.time = 0.0
        self.watch = StrainWatch()
        self._trial_range = None
        space, mesh = problem.space, problem.mesh
        degree = 2 * problem.model.mesh.degree - 1  # the energy rule (problem.dx_energy)
        self.gauss_space = compat.function_space(mesh, compat.quadrature_element(mesh, degree))
        self._gauss_points = basix.make_quadrature(basix.CellType.interval, degree)[0]
        self.theta_q, self.kappa_q = (fem.Function(self.gauss_space) for _ in range(2))
        # The Gauss-point terms get their own integration domain (every cell, tag 1): FFCx
        # (0.5) merges the integrals of one domain into one kernel, and a Quadrature-element
        # coefficient in a kernel with several rules was evaluated wrongly (degree 1: the
        # kinetic and stored energy changes no longer matched the residual; the scheme lost its
        # exact balance).
        cells = np.arange(mesh.topology.index_map(1).size_local
                          + mesh.topology.index_map(1).num_ghosts, dtype=np.int32)
        tags = compat.meshtags(mesh, 1, cells, np.ones(len(cells), dtype=np.int32))
        self.dx_gauss = ufl.Measure("dx", domain=mesh, subdomain_data=tags, subdomain_id=1,
                                    metadata={"quadrature_degree": degree})
        self.q_old, self.v_old, self.unknown = (fem.Function(space) for _ in range(3))
        const = lambda value: fem.Constant(mesh, float(value))  # noqa: E731
        self.dt = const(settings.dt)
        self.c = const(damping.c)
        self.eta = const(damping.kelvin_voigt)
        self.potentials = [(density, timing, const(0.0)) for density, timing in potentials]
        self.bcs, self._bc_values = self._dirichlet_conditions()
        self._build_forms()
        self.solver = SNESSolver(NonlinearProblem(self.residual, self.unknown, self.bcs),
                                 (solver_settings or SolverSettings()).for_problem(
                                     problem.saddle_point, problem.comm),
                                 prefix="fe_beam_energy_momentum_",
                                 state_scale=problem.model.length)

    # --- forms -----------------------------------------------------------------------------------
    @property
    def dx_mass(self):
        return ufl.dx(metadata={"quadrature_degree": 2 * self.problem.model.mesh.degree + 2})

    def _strains(self, tangent, cos_t, sin_t, kappa):
        gamma = _rotate_back(cos_t, sin_t, tangent)
        return [gamma[0], gamma[1], (ufl.dot(tangent, tangent) - 1) / 2, kappa]

    def _energy(self, pi, potentials: bool = True):
        """The energy density of the step: the rod law's W(pi) plus the load potentials at
        their mean factors."""
        energy = self.problem.energy_density(Strains(*pi))
        if potentials:
            for density, _, factor in self.potentials:
                energy += factor * density(Strains(*pi))
        return energy

    def _build_forms(self) -> None:
        p = self.problem
        dt = self.dt
        new, old, vel = (ufl.split(f) for f in (self.unknown, self.q_old, self.v_old))
        psi = new[2]
        chain = getattr(p, "chain", None)
        if chain is None:
            theta0 = 0
            tangent = lambda parts: ufl.as_vector([1 + parts[0].dx(0), parts[1].dx(0)])  # noqa: E731
        else:  # a chain of rods: r' = X' + (u', v'), theta_q the world angle theta0 + theta
            theta0 = chain.theta0
            tangent = lambda parts: chain.world_tangent(parts[0], parts[1])  # noqa: E731
        t0, t1 = tangent(old), tangent(new)
        tm = (t0 + t1) / 2
        increment = ufl.as_vector([new[0] - old[0], new[1] - old[1]])
        den = 1 + psi**2 / 4
        c2 = 1 / den  # cos^2(Dtheta/2)
        cos_phi, sin_phi = (1 - psi**2 / 4) / den, psi / den  # of Dtheta = 2 atan(psi/2)
        cos0, sin0 = ufl.cos(self.theta_q), ufl.sin(self.theta_q)
        cos1, sin1 = cos0 * cos_phi - sin0 * sin_phi, sin0 * cos_phi + cos0 * sin_phi
        pi0 = self._strains(t0, cos0, sin0, self.kappa_q)
        pi1 = self._strains(t1, cos1, sin1, self.kappa_q + c2 * psi.dx(0))

        def variation(dr_prime, dth, dth_prime):
            a = dr_prime - dth * _perp(tm)
            gamma = c2 * _rotate_back(cos0, sin0, a - psi / 2 * _perp(a))
            return [gamma[0], gamma[1], ufl.dot(tm, dr_prime), c2 * dth_prime]

        dpi = variation(ufl.as_vector([increment[0].dx(0), increment[1].dx(0)]), psi, psi.dx(0))
        middle = [ufl.variable((a + b) / 2) for a, b in zip(pi0, pi1, strict=True)]
        w_mid = self._energy(middle)
        gradient = [ufl.diff(w_mid, m) for m in middle]
        props, k = p.section_props, p.stiffness
        metric = [1.0, 1.0, 1.0, props.I / props.A]  # kappa scaled by the radius of gyration
        norm2 = sum(m * d**2 for m, d in zip(metric, dpi, strict=True))
        excess = (self._energy(pi1) - self._energy(pi0)
                  - sum(g * d for g, d in zip(gradient, dpi, strict=True)))
        coefficient = ufl.conditional(ufl.gt(norm2, SMALL_INCREMENT),
                                      excess / ufl.max_value(norm2, SMALL_INCREMENT), 0.0)
        stress = [g + coefficient * m * d for g, m, d in zip(gradient, metric, dpi, strict=True)]
        viscous_moduli = [0.0, k.GA, k.EA, k.EI]
        kv_stress = [self.eta / dt * m * d for m, d in zip(viscous_moduli, dpi, strict=True)]

        test = ufl.TestFunction(p.space)
        tp = ufl.split(test)
        dr = ufl.as_vector([tp[0], tp[1]])
        test_variation = variation(ufl.as_vector([tp[0].dx(0), tp[1].dx(0)]), tp[2],
                                   tp[2].dx(0))
        rho_area, rho_inertia = p.rho * props.A, p.rho * props.I
        v0, w0 = ufl.as_vector([vel[0], vel[1]]), vel[2]
        velocity_mid = increment / dt
        acceleration = 2 * (increment - dt * v0) / dt**2  # (v1 - v0)/dt
        angular = (2 * psi / dt - 2 * w0) / dt  # (w1 - w0)/dt
        dx_e, dx_m = self.dx_gauss, self.dx_mass
        residual = (rho_area * ufl.dot(acceleration, dr) + rho_inertia * angular * tp[2]
                    + self.c * ufl.dot(velocity_mid, dr)) * dx_m
        if self.damping.kelvin_voigt > 0:
            stress = [s + v for s, v in zip(stress, kv_stress, strict=True)]
        residual += sum(s * v for s, v in zip(stress, test_variation, strict=True)) * dx_e
        index = {"g": 1, "eps": 2}
        for offset, name in enumerate(p.multipliers):
            multiplier, check = new[3 + offset], tp[3 + offset]
            residual += (multiplier * test_variation[index[name]]
                         + check * pi1[index[name]]) * dx_e
        # dead loads at the mean load factor of the step (problem.load_factor): the rod's own
        # dead-load work (`BeamProblem.dead_load_work`: every dead load, point forces included)
        # on the variation (Delta r, phi'(psi) psi): it is linear in the state, so this is its
        # exact discrete gradient; the tip moment works through d phi = phi'(psi) d psi
        safe = ufl.conditional(ufl.lt(abs(psi), SERIES), 1.0, psi)
        ratio = ufl.conditional(ufl.lt(abs(psi), SERIES), 1 - psi**2 / 12 + psi**4 / 80,
                                2 * ufl.atan(safe / 2) / safe)
        residual -= p.dead_load_work((tp[0], tp[1], ratio * tp[2]))
        self._follower_work = None
        if p.model.loads.follower:
            # theta_n + atan(psi/2) = (theta_n + theta_{n+1}) / 2 exactly (|Dtheta| < pi)
            theta_mid = old[2] + ufl.atan(psi / 2)
            mid = ((old[0] + new[0]) / 2, (old[1] + new[1]) / 2, theta_mid)
            residual -= p.follower_virtual_work(mid, test)
            # its work over an accepted step: the same force times (Delta u, Delta v)
            self._step_state, self._step_increment = (fem.Function(p.space) for _ in range(2))
            self._follower_work = fem.form(p.follower_virtual_work(
                tuple(ufl.split(self._step_state)[:3]), self._step_increment))
        self.residual = residual
        # state update at the Gauss points (evaluated on the candidate before it is accepted)
        points = self._gauss_points
        self._update = (compat.expression(self.theta_q + 2 * ufl.atan(psi / 2), points),
                        compat.expression(self.kappa_q + c2 * psi.dx(0), points))
        self._initial_gauss = (compat.expression(old[2] + theta0, points),
                               compat.expression(old[2].dx(0), points))
        if chain is None:
            X, Y = ufl.SpatialCoordinate(p.mesh)[0], 0
        else:  # the reference position of the chain
            X, Y = chain.reference[0], chain.reference[1]
        q, v = old, vel
        damping_work = self.c * ufl.dot(increment, increment) / dt * dx_m
        if self.damping.kelvin_voigt > 0:
            damping_work += sum(s * d for s, d in zip(kv_stress, dpi, strict=True)) * dx_e
        self.potential_forms = [fem.form(density(Strains(*pi0)) * dx_e)
                                for density, _, _ in self.potentials]
        self.forms = {
            "kinetic": fem.form(0.5 * (rho_area * (v[0] ** 2 + v[1] ** 2)
                                       + rho_inertia * v[2] ** 2) * dx_m),
            "strain": fem.form(self._energy(pi0, potentials=False) * dx_e),
            "load_potential": fem.form(p.dead_load_work(tuple(q[:3]))),
            "damping_work": fem.form(damping_work),
            "momentum_x": fem.form(rho_area * v[0] * dx_m),
            "momentum_y": fem.form(rho_area * v[1] * dx_m),
            "angular_momentum": fem.form((rho_area * ((X + q[0]) * v[1] - (Y + q[1]) * v[0])
                                          + rho_inertia * v[2]) * dx_m),
        }

    def _dirichlet_conditions(self):
        """Conditions on the step's unknowns: u, v at t_{n+1}; psi from theta(t_{n+1})."""
        p = self.problem
        bcs, values = [], []
        for end in ("x0", "xL"):
            prescribed = getattr(p.model.supports, f"prescribed_{end}")
            for name in p.model.supports.fixed(end):
                index = COMPONENTS.index(name)
                sub, _ = compat.sub_space_collapsed(p.space, index)
                dofs = compat.locate_dofs_geometrical((p.space.sub(index), sub),
                                                      p.end_markers[end])
                value = fem.Function(sub)
                bcs.append(fem.dirichletbc(value, dofs, p.space.sub(index)))
                values.append((value, name, float(prescribed.get(name, 0.0)),
                               np.asarray(dofs[0]), np.asarray(dofs[1])))
        return bcs, values

    def _set_boundary_values(self, t_new: float) -> None:
        factor = self.motion_function(t_new)
        old = compat.local_array(self.q_old)
        for value, name, target, parent, collapsed in self._bc_values:
            if name == "theta":
                value.x.array[collapsed] = 2 * np.tan((factor * target - old[parent]) / 2)
            else:
                value.x.array[collapsed] = factor * target

    # --- state --------------------------------------------------------------------------------
    def _gauss_values(self, compiled) -> tuple[np.ndarray, np.ndarray]:
        cells = np.arange(self.problem.mesh.topology.index_map(1).size_local, dtype=np.int32)
        values = compat.evaluate_expression(compiled, self.problem.mesh, cells)
        dofs = compat.cell_dofs(self.gauss_space)[: len(cells)]
        return dofs.ravel(), np.asarray(values).reshape(-1)

    def _set_gauss(self, pairs) -> None:
        for function, (dofs, values) in zip((self.theta_q, self.kappa_q), pairs, strict=True):
            function.x.array[dofs] = values
            function.x.scatter_forward()

    def initialise(self, velocity: Callable | None = None) -> None:
        """Start from ``problem.w`` at t = 0 with initial velocities ``velocity(x) -> (u_t, v_t,
        theta_t)`` (as `GeneralizedAlpha.initialise`)."""
        p = self.problem
        self.time = 0.0
        p.set_prescribed_factor(self.motion_function(0.0))
        start_state(p, self.q_old, self.v_old, velocity, 3)
        self._set_gauss([self._gauss_values(c) for c in self._initial_gauss])
        self._a_prev = self._initial_acceleration()
        self._work = 0.0
        self._dissipated = 0.0
        self._load_energy = self._unit_load_energy()
        self._potential_values = [assemble_scalar(form) for form in self.potential_forms]
        self._potential_work = [0.0] * len(self.potentials)
        self.energy0 = self.energies()

    def _initial_acceleration(self) -> np.ndarray:
        """M a0 = f_ext - f_int - C v0 (only the first step's error estimate uses it)."""
        p = self.problem
        trial, test = ufl.TrialFunction(p.space), ufl.TestFunction(p.space)
        a, t = ufl.split(trial), ufl.split(test)
        props = p.section_props
        mass = (p.rho * props.A * (a[0] * t[0] + a[1] * t[1])
                + p.rho * props.I * a[2] * t[2]) * self.dx_mass
        for index in range(3, len(a)):
            mass += a[index] * t[index] * ufl.dx
        u, v, theta, _ = p.fields()
        state = (u, v, theta)
        saved = float(p.load_factor.value)
        p.load_factor.value = self.load_function(0.0)
        force = ufl.derivative(p.stored_energy(state) - p.dead_load_work(state), p.w, test)
        vel = ufl.split(self.v_old)
        force += self.c * (vel[0] * t[0] + vel[1] * t[1]) * self.dx_mass
        for density, timing, _ in self.potentials:  # at the Gauss points: theta_q = theta
            force += timing(0.0) * ufl.derivative(density(strains(*state)) * self.dx_gauss,
                                                  p.w, test)
        if p.model.loads.follower:
            force -= p.follower_virtual_work(state, test)
        target = fem.Function(p.space)
        p.set_prescribed_factor(0.0)
        compat.solve_linear(mass, -force, p.bcs, target)
        p.set_prescribed_factor(self.motion_function(0.0))
        p.load_factor.value = saved
        values = compat.local_array(target).copy()
        values[p.multiplier_dofs()] = 0.0
        return values

    def _load_mid(self, t_old: float, t_new: float) -> float:
        return 0.5 * (self.load_function(t_old) + self.load_function(t_new))

    def step(self, dt: float) -> int:
        """Advance by dt (raises SolveFailed; the accepted state is kept in q_old, v_old)."""
        p = self.problem
        t_old, t_new = self.time, self.time + dt
        self.dt.value = dt
        p.load_factor.value = self._load_mid(t_old, t_new)
        for _, timing, factor in self.potentials:
            factor.value = 0.5 * (timing(t_old) + timing(t_new))
        p.set_prescribed_factor(self.motion_function(t_new))
        self._set_boundary_values(t_new)
        unknown, old = compat.local_array(self.unknown), compat.local_array(self.q_old)
        unknown[:] = old
        unknown[self._theta_dofs()] = 0.0  # psi: same-displacement predictor
        iterations = self.solver.solve()
        psi = unknown[self._theta_dofs()]
        largest = global_max(p.comm, float(np.max(np.abs(psi), initial=0.0)))
        limit = 2 * math.tan(MAX_ROTATION_INCREMENT / 2)
        if not largest < limit:
            raise SolveFailed(f"rotation increment {2 * math.atan(largest / 2):.3g} rad >= "
                              f"{MAX_ROTATION_INCREMENT:g} rad in one step")
        state = unknown.copy()
        theta = self._theta_dofs()
        state[theta] = old[theta] + 2 * np.arctan(psi / 2)
        compat.local_array(p.w)[:] = state
        self._trial_range = p.strain_range()  # collective
        reason = self._trial_range.inadmissible()
        if reason is not None:
            raise SolveFailed(reason)
        velocity = 2 * (unknown - old) / dt - compat.local_array(self.v_old)
        velocity[theta] = 2 * psi / dt - compat.local_array(self.v_old)[theta]
        velocity[p.multiplier_dofs()] = 0.0
        self._candidate = (state, velocity, t_old, t_new)
        return iterations

    def _acceleration(self) -> np.ndarray:
        _, velocity, t_old, t_new = self._candidate
        return (velocity - compat.local_array(self.v_old)) / (t_new - t_old)

    def local_error(self) -> float:
        """Distance of the step's end to the second-order predictor q_n + dt v_n + dt^2/2 a_p
        (a_p: the previous step's mean acceleration, a(0) at the first step): exactly
        dt^2/2 |a_{n+1/2} - a_p| ~ dt^3/2 |q'''| (max over u, v, L*theta)."""
        _, _, t_old, t_new = self._candidate
        dt = t_new - t_old
        difference = np.abs(self._acceleration() - self._a_prev)
        scale = np.ones_like(difference)
        scale[self._theta_dofs()] = self.problem.model.length
        motion = self._motion_dofs()
        local = float(np.max(difference[motion] * scale[motion], initial=0.0))
        return global_max(self.problem.comm, local) * dt**2 / 2

    def accept(self) -> None:
        state, velocity, t_old, t_new = self._candidate
        self._a_prev = self._acceleration()
        self._dissipated += assemble_scalar(self.forms["damping_work"])
        gauss = [self._gauss_values(c) for c in self._update]  # before the state moves on
        load_mid = self._load_mid(t_old, t_new)
        if self._follower_work is not None:  # at the step's load factor (still set)
            old = compat.local_array(self.q_old)
            compat.local_array(self._step_state)[:] = (old + state) / 2
            compat.local_array(self._step_increment)[:] = state - old
            self._work += assemble_scalar(self._follower_work)
        compat.local_array(self.q_old)[:] = state
        compat.local_array(self.v_old)[:] = velocity
        self._set_gauss(gauss)
        load_energy = self._unit_load_energy()
        self._work += load_mid * (load_energy - self._load_energy)
        self._load_energy = load_energy
        for index, (_, _, factor) in enumerate(self.potentials):
            value = assemble_scalar(self.potential_forms[index])
            work = -float(factor.value) * (value - self._potential_values[index])
            self._work += work
            self._potential_work[index] += work
            self._potential_values[index] = value
        self.time = t_new
        if self._trial_range is not None:
            self.watch.observe(self._trial_range)

    #: the scheme conserves energy to the Newton tolerance: the balance is judged both ways
    energy_tolerance = 1e-6
    conserving = True
    _state_functions = ("q_old", "v_old", "theta_q", "kappa_q")
    _state_attributes = ("time", "_a_prev", "_work", "_dissipated", "_load_energy",
                         "_potential_values", "_potential_work")

    def reject(self) -> None:
        p = self.problem
        compat.local_array(p.w)[:] = compat.local_array(self.q_old)
        p.load_factor.value = self.load_function(self.time)
        p.set_prescribed_factor(self.motion_function(self.time))

    def energies(self) -> dict:
        kinetic = assemble_scalar(self.forms["kinetic"])
        strain = assemble_scalar(self.forms["strain"])
        values = {"kinetic": kinetic, "strain": strain, "external_work": self._work,
                  "dissipated": self._dissipated}
        if self.tendons is not None:
            values["tendon_work"] = sum(self._potential_work[i] for i in self._tendon_indices)
        start = getattr(self, "energy0", None)
        initial = start["kinetic"] + start["strain"] if start else kinetic + strain
        values["balance_residual"] = kinetic + strain + self._dissipated - self._work - initial
        return values

    def tendon_lengths(self) -> np.ndarray:
        """l_i of the tendons on the accepted state (its Gauss-point rotation and curvature:
        the lengths whose changes give tendon_work)."""
        return np.array([self._potential_values[i] for i in self._tendon_indices])


"""Nonlinear beam dynamics with the generalised-alpha method (Chung & Hulbert 1993).

With rho_inf in [0, 1] (docs/theory.md, Time integration):

    alpha_m = (2 rho_inf - 1)/(rho_inf + 1),  alpha_f = rho_inf/(rho_inf + 1)
    gamma   = 1/2 - alpha_m + alpha_f,         beta  = (1 - alpha_m + alpha_f)^2 / 4
    a_{n+1} = (q_{n+1} - q_n - dt v_n) / (beta dt^2) - (1 - 2 beta)/(2 beta) a_n
    v_{n+1} = v_n + dt ((1 - gamma) a_n + gamma a_{n+1})

and the balance M a_{n+1-alpha_m} + C v_{n+1-alpha_f} + f_int(q_{n+1-alpha_f}) =
f_ext(t_{n+1-alpha_f}) with x_{n+1-alpha} = (1 - alpha) x_{n+1} + alpha x_n. The internal forces
are the derivative of the same stored energy as in statics, evaluated at q_{n+1-alpha_f};
constraints (multiplier fields) are enforced at t_{n+1}. rho_inf = 1 is the implicit midpoint
rule: energy-conserving for linear problems and exactly momentum-conserving.

The problem supplies the inertia (`BeamProblem.mass_work`, `velocity_inertia_work`,
`kinetic_energy`, `momentum_densities`): constant for the planar rod; for the spatial rod
(`fe_beam.fem.spatial_rod.SpatialRodProblem`, q = (d, theta) with theta the rotation vector,
treated as a vector of R^3) the Lagrangian inertia M(theta) a + g(theta, v) of the exact
kinetic energy, at q_{n+1-alpha_f}, v_{n+1-alpha_f}, a_{n+1-alpha_m} (docs/theory.md, Spatial
rods: inertia, modes and generalised-alpha on the rotation vector).

Contact with rigid obstacles (``contact``, a `fe_beam.fem.contact.ContactSet`): the gap is a
constraint of the state at t_{n+1}, like the multiplier fields (the accepted state meets the
penetration tolerance), with the obstacles at their place at t_{n+1}; the augmented-Lagrangian
pressure (and the planar friction traction) enter the residual at q_{n+1}, and the Uzawa /
active-set wrapper `fe_beam.solvers.contact.ContactSolver` wraps the step's Newton solve as it
wraps a static load step; friction's slip is that of the step, the reference points being the
contact points of the last accepted step (docs/theory.md, Contact in dynamics).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
import ufl
from dolfinx import fem

from fe_beam.fem import compat
from fe_beam.fem.kinematics import axis_tangent, strains_from_gradient
from fe_beam.fem.mpi import assemble_scalar, global_max
from fe_beam.fem.rod import BeamProblem, StrainWatch
from fe_beam.model.settings import SCHEMES, Damping, TimeSettings  # noqa: F401
from fe_beam.progress import ProgressBar
from fe_beam.solvers.contact import ContactSolver
from fe_beam.solvers.newton import NonlinearProblem, SNESSolver, SolveFailed, SolverSettings
from fe_beam.solvers.pull_in import PullInSolver

__all__ = ["Damping", "DynamicsFailed", "GeneralizedAlpha", "StepDriver", "TimeSettings",
           "alpha_parameters"]

#: the dynamic contact stiffness k relative to the step's inertia stiffness rho A / (beta dt^2)
CONTACT_INERTIA_FACTOR = 10.0


class DynamicsFailed(RuntimeError):
    """Time stepping gave up (the state of ``last_time`` is kept)."""

    def __init__(self, message: str, last_time: float):
        super().__init__(message)
        self.last_time = last_time


def alpha_parameters(rho_inf: float) -> dict:
    """alpha_m, alpha_f, gamma, beta of the generalised-alpha method."""
    alpha_m = (2 * rho_inf - 1) / (rho_inf + 1)
    alpha_f = rho_inf / (rho_inf + 1)
    gamma = 0.5 - alpha_m + alpha_f
    beta = 0.25 * (1 - alpha_m + alpha_f) ** 2
    return {"alpha_m": alpha_m, "alpha_f": alpha_f, "gamma": gamma, "beta": beta}


def strain_rates(parts, rates):
    """Directional derivatives (eps, g, kappa) of the strains at ``parts`` along ``rates``."""
    u, v, theta = parts
    stretch_x, stretch_y = (ufl.variable(c) for c in axis_tangent(u, v))
    angle, curvature = ufl.variable(theta), ufl.variable(theta.dx(0))
    s = strains_from_gradient(ufl.as_vector([stretch_x, stretch_y]), angle, curvature)
    du, dv, dtheta = rates
    directions = ((stretch_x, du.dx(0)), (stretch_y, dv.dx(0)), (angle, dtheta),
                  (curvature, dtheta.dx(0)))

    def rate(quantity):
        return sum(ufl.diff(quantity, variable) * direction for variable, direction in directions)

    return rate(s.eps), rate(s.g), rate(s.kappa)


class StepDriver:
    """The step-size driver shared by the time integrators (`GeneralizedAlpha`,
    `fe_beam.solvers.energy_momentum.EnergyMomentum`): cut-back on a failed step, optional local
    error
    control. A subclass provides ``problem``, ``settings``, ``time`` and ``step(dt)`` (raises
    SolveFailed), ``reject()``, ``accept()``, ``local_error()``."""


    def momenta(self) -> dict:
        """Linear and angular momentum of the current state (the schemes' ``forms``: planar
        momentum_x, momentum_y, angular_momentum; spatial momentum_x, _y, _z and
        angular_momentum_x, _y, _z, about the origin)."""
        names = getattr(self, "momentum_names", ("momentum_x", "momentum_y", "angular_momentum"))
        return {name: assemble_scalar(self.forms[name]) for name in names}

    def _unit_load_energy(self) -> float:
        """Dead-load work at load factor 1 on the last accepted state (the
        schemes' ``forms["load_potential"]``)."""
        saved = float(self.problem.load_factor.value)
        self.problem.load_factor.value = 1.0
        value = assemble_scalar(self.forms["load_potential"])
        self.problem.load_factor.value = saved
        return value

    def _theta_dofs(self) -> np.ndarray:
        """Local dofs (ghosts included) of theta in the state."""
        if not hasattr(self, "_theta"):
            indices = [i for i, name in enumerate(self.problem.components)
                       if name.startswith("theta")]
            self._theta = np.concatenate([
                np.asarray(compat.sub_space_collapsed(self.problem.space, i)[1])
                for i in indices])
        return self._theta

    def _motion_dofs(self) -> np.ndarray:
        """Local dofs of the displacements and rotations (not the multipliers)."""
        if not hasattr(self, "_motion"):
            dofs = [np.asarray(compat.sub_space_collapsed(self.problem.space, i)[1])
                    for i in range(self.problem.motion_count)]
            self._motion = np.concatenate(dofs)
        return self._motion
    def run(self, on_output: Callable[[float, int], None] | None = None,
            progress: bool = True) -> dict:
        """Integrate to t_end; ``on_output(t, step)`` after every ``output_every`` steps."""
        s = self.settings
        dt, steps, rejected, newton = s.dt, 0, 0, 0
        length = self.problem.model.length
        bar = ProgressBar(self.problem.comm, total=s.t_end, label="time", enabled=progress,
                          unit="s")
        started = time.perf_counter()
        if on_output is not None:
            on_output(self.time, 0)
        try:
            while self.time < s.t_end * (1 - 1e-12):
                trial = min(dt, s.t_end - self.time)
                try:
                    iterations = self.step(trial)
                except SolveFailed as failure:
                    self.reject()
                    rejected += 1
                    dt = trial / 2
                    if dt < s.smallest_step:
                        raise DynamicsFailed(
                            f"time step fell below {s.smallest_step:.3g} s at t = "
                            f"{self.time:.6g} s ({failure}); last converged time "
                            f"{self.time:.6g} s", self.time) from None
                    bar.note(f"t = {self.time:.4g} s: step cut to {dt:.3g} s ({failure})")
                    continue
                if s.adaptive:
                    error = self.local_error()
                    allowed = s.tol * length
                    factor = 0.9 * (allowed / max(error, 1e-300)) ** (1 / 3)
                    if error > allowed and trial > s.smallest_step:
                        self.reject()
                        rejected += 1
                        dt = max(trial * max(0.2, factor), s.smallest_step)
                        continue
                    dt = min(trial * min(2.0, max(0.2, factor)), s.largest_step)
                elif dt < s.dt and iterations <= 4:
                    dt = min(2 * dt, s.dt)  # grow back after a cut-back
                self.accept()
                steps += 1
                newton += iterations
                bar.update(self.time, f"t = {self.time:.4g} s, dt = {trial:.3g} s")
                if on_output is not None and (steps % s.output_interval == 0
                                              or self.time >= s.t_end * (1 - 1e-12)):
                    on_output(self.time, steps)
        finally:
            bar.close()
        return {"steps": steps, "rejected_steps": rejected, "newton_iterations": newton,
                "wall_time_s": time.perf_counter() - started}


class GeneralizedAlpha(StepDriver):
    """Generalised-alpha time integration of a `BeamProblem` (all laws and constraints).

    ``load_function(t)`` scales every load, ``motion_function(t)`` the prescribed end values.
    """

    def __init__(self, problem: BeamProblem, settings: TimeSettings, damping: Damping = Damping(),  # noqa: B008
                 load_function: Callable[[float], float] = lambda t: 1.0,
                 motion_function: Callable[[float], float] | None = None,
                 solver_settings: SolverSettings | None = None, tendons=None, contact=None):
        """``tendons``: the problem's `fe_beam.fem.tendons.TendonSet` (its energy hook is in the
        problem's stored energy), tensions tension_i f_i(t) (``set_time_functions``);
        ``contact``: a `fe_beam.fem.contact.ContactSet` of obstacles (not in the problem's
        stored energy: its terms are added here, at t_{n+1})."""
        if problem.model.material.rho <= 0:
            raise ValueError("dynamics needs material.rho > 0")
        self.problem = problem
        self.settings = settings
        self.damping = damping
        self.load_function = load_function
        self.motion_function = motion_function or load_function
        self.tendons = tendons
        self.contact = contact
        section = problem.model.section
        self._line_mass = float(problem.model.material.rho) * max(
            float(section.properties(s).A) for s in (0.0, 1.0))
        space, mesh = problem.space, problem.mesh
        self.q_old, self.v_old, self.a_old = (fem.Function(space) for _ in range(3))
        params = alpha_parameters(settings.rho_inf)
        self.params = params
        const = lambda value: fem.Constant(mesh, float(value))  # noqa: E731
        self.dt = const(settings.dt)
        alpha_m, alpha_f, beta, gamma = (const(params[k]) for k in ("alpha_m", "alpha_f",
                                                                     "beta", "gamma"))
        self.c = const(damping.c)
        self.eta = const(damping.kelvin_voigt)
        self.time = 0.0
        # extremes of the strains over the accepted states (`fe_beam.fem.rod.StrainRange`)
        self.watch = StrainWatch()
        self._trial_range = None
        w_parts = ufl.split(problem.w)
        q, v, a = (ufl.split(f) for f in (self.q_old, self.v_old, self.a_old))
        dt = self.dt
        n = problem.motion_count
        a_new = [(w_parts[i] - q[i] - dt * v[i]) / (beta * dt**2) - (1 - 2 * beta) / (2 * beta)
                 * a[i] for i in range(n)]
        v_new = [v[i] + dt * ((1 - gamma) * a[i] + gamma * a_new[i]) for i in range(n)]
        q_mid = problem.motion_parts([(1 - alpha_f) * w_parts[i] + alpha_f * q[i]
                                      for i in range(n)])
        v_mid = tuple((1 - alpha_f) * v_new[i] + alpha_f * v[i] for i in range(n))
        a_mid = tuple((1 - alpha_m) * a_new[i] + alpha_m * a[i] for i in range(n))
        test = ufl.TestFunction(space)
        # the inertia at the alpha-weighted state, velocity and acceleration: constant mass
        # (planar), or the spatial rod's M(theta) theta_tt + g(theta, theta_t)
        self.residual = (
            self.inertia(a_mid, test, q_mid, v_mid)
            + self.dissipation(q_mid, v_mid, test)
            # d/dw of Pi(q_mid) is (1 - alpha_f) Pi'(q_mid): divide it out (rho_inf is fixed).
            + (1 / (1 - params["alpha_f"])) * ufl.derivative(
                problem.stored_energy(q_mid) - problem.dead_load_work(q_mid), problem.w, test)
            + self._constraints(test)
        )
        if problem.nonpotential_loads:
            self.residual -= problem.nonconservative_work(q_mid, test)
        if contact is not None:
            self.residual += self._contact_residual(test)
        self.solver = SNESSolver(NonlinearProblem(self.residual, problem.w, problem.bcs),
                                 (solver_settings or SolverSettings()).for_problem(
                                     problem.saddle_point, problem.comm),
                                 prefix="fe_beam_dynamic_",
                                 state_scale=problem.model.length)
        if tendons is not None and any(t.controlled_by_pull_in for t in tendons.tendons):
            # pull-in control: the tensions (applied at t_{n+1-alpha_f}) are unknowns that make
            # the tendon lengths at t_{n+1} the prescribed ones (Newton with the dynamic tangent)
            self.solver = PullInSolver(self.solver, tendons)
        if contact is not None:
            self.solver = ContactSolver(self.solver, contact)
        self._energy_forms()

    # --- forms -----------------------------------------------------------------------------------
    def _contact_residual(self, direction):
        """The contact terms at the state q_{n+1} (``problem.w``) along ``direction`` (the test
        function, or a displacement for the work): -(the contact forces' virtual work)."""
        p, contact = self.problem, self.contact
        state = p.state_parts() if p.spatial else p.fields()[:3]
        term = ufl.derivative(contact.energy(p, state), p.w, direction)
        if contact.frictional:
            term -= contact.work(p, state, direction)
        return term

    @property
    def dx_mass(self):
        return self.problem.dx_mass

    def inertia(self, acceleration, test, state=None, velocity=None):
        """The inertia's virtual work (`BeamProblem.mass_work` + `velocity_inertia_work`)."""
        p = self.problem
        work = p.mass_work(state, acceleration, test)
        if velocity is not None:
            quadratic = p.velocity_inertia_work(state, velocity, test)
            if quadratic is not None:
                work += quadratic
        return work

    def dissipation(self, state, velocity, test):
        """Virtual work of viscous (c, on the translations) and Kelvin-Voigt (eta, planar)
        damping."""
        t = ufl.split(test) if not isinstance(test, (list, tuple)) else test
        work = self.c * sum(velocity[i] * t[i] for i in range(self.problem.translations)) \
            * self.dx_mass
        if self.damping.kelvin_voigt > 0:
            k = self.problem.stiffness
            rates = strain_rates(state, velocity)
            variations = strain_rates(state, t[:3])
            moduli = (k.EA, k.GA, k.EI)
            terms = zip(moduli, rates, variations, strict=True)
            work += self.eta * sum(m * r * d for m, r, d in terms) * self.problem.dx_energy
        return work

    def _constraints(self, test):
        p = self.problem
        *parts, multipliers = p.fields()
        term = p.constraint_term(tuple(parts), multipliers)
        return ufl.derivative(term, p.w, test) if multipliers else 0

    def _energy_forms(self) -> None:
        p = self.problem
        n = p.motion_count
        # The damping work of a step is exactly what the scheme applies: the force at the
        # alpha-weighted state and velocity times the displacement increment.
        self._step_state, self._step_velocity, self._step_increment = (
            fem.Function(p.space) for _ in range(3))
        q, v = p.motion_parts(ufl.split(self.q_old)), ufl.split(self.v_old)[:n]
        dx = self.dx_mass
        self.forms = {
            "kinetic": fem.form(p.kinetic_energy(q, v)),
            "strain": fem.form(p.stored_energy(q)),
            "load_potential": fem.form(p.dead_load_work(q)),
            "damping_work": fem.form(self.dissipation(
                p.motion_parts(ufl.split(self._step_state)), ufl.split(self._step_velocity)[:n],
                self._step_increment)),
        }
        momenta = p.momentum_densities(q, v)
        self.momentum_names = tuple(momenta)
        self.forms.update({name: fem.form(density * dx) for name, density in momenta.items()})
        if p.nonpotential_loads:  # the nonconservative load the step applied times the increment
            self.forms["follower_work"] = fem.form(p.nonconservative_work(
                p.motion_parts(ufl.split(self._step_state)), self._step_increment))
        if self.contact is not None:  # the contact forces of the accepted state times the step
            self.forms["contact_work"] = fem.form(-self._contact_residual(self._step_increment))

    # --- state --------------------------------------------------------------------------------
    def initialise(self, velocity: Callable | None = None) -> None:
        """Start from the current ``problem.w`` (e.g. a static solution) at t = 0, with initial
        velocities ``velocity(x) -> (u_t, v_t, theta_t)`` arrays (spatial rods: (u_t, v_t, w_t,
        omega_x, omega_y, omega_z), omega the sections' angular velocity in world axes:
        `SpatialRodProblem.velocity_to_rates`), and the consistent initial acceleration
        M a0 = f_ext - f_int - C v0 (- g(q0, v0), the spatial rod's velocity terms)."""
        self.time = 0.0
        self._set_time_values(0.0, 0.0)
        compat.local_array(self.q_old)[:] = compat.local_array(self.problem.w)
        compat.local_array(self.v_old)[:] = 0.0
        if velocity is not None:
            values, places = [], []
            for index in range(self.problem.motion_count):
                sub, dofs = compat.sub_space_collapsed(self.problem.space, index)
                function = fem.Function(sub)
                function.interpolate(lambda x, i=index: np.asarray(velocity(x)[i], dtype=float)
                                     * np.ones(x.shape[1]))
                values.append(function.x.array.copy())
                places.append(np.asarray(dofs))
            rates = self.problem.velocity_to_rates(values)
            for dofs, rate in zip(places, rates, strict=True):
                compat.local_array(self.v_old)[dofs] = rate
        self._initial_acceleration()
        self._work = 0.0
        self._dissipated = 0.0
        self._contact_work = 0.0
        self._load_energy = self._unit_load_energy()
        self._tendon_work = 0.0
        self._tendon_lengths = self.tendons.lengths() if self.tendons is not None else None
        self.energy0 = self.energies()

    def _initial_acceleration(self) -> None:
        p = self.problem
        n = p.motion_count
        trial, test = ufl.TrialFunction(p.space), ufl.TestFunction(p.space)
        a_parts, t = ufl.split(trial), ufl.split(test)
        *parts, _ = p.fields()
        state = tuple(parts)
        mass = self.inertia(a_parts[:n], test, state)
        for index in range(n, len(a_parts)):  # multipliers: identity, their "acceleration" is 0
            mass += a_parts[index] * t[index] * ufl.dx
        velocity = tuple(ufl.split(self.v_old)[:n])
        force = ufl.derivative(p.stored_energy(state) - p.dead_load_work(state), p.w, test)
        force += self.dissipation(state, velocity, test)
        quadratic = p.velocity_inertia_work(state, velocity, test)
        if quadratic is not None:
            force += quadratic
        if p.nonpotential_loads:
            force -= p.nonconservative_work(state, test)
        # Fixed dofs have zero acceleration: solve with all prescribed values set to zero.
        p.set_prescribed_factor(0.0)
        compat.solve_linear(mass, -force, p.bcs, self.a_old)
        p.set_prescribed_factor(self.motion_function(0.0))
        compat.local_array(self.a_old)[p.multiplier_dofs()] = 0.0

    def _set_time_values(self, t_new: float, t_old: float) -> None:
        p = self.problem
        p.set_prescribed_factor(self.motion_function(t_new))
        alpha_f = self.params["alpha_f"]
        p.load_factor.value = ((1 - alpha_f) * self.load_function(t_new)
                               + alpha_f * self.load_function(t_old))
        if self.contact is not None:  # the obstacles' gap is a constraint at t_{n+1}
            self.contact.move(t_new)
        if self.tendons is not None:  # tensions at t_{n+1-alpha_f}, like the loads
            self.tendons.set_time(t_new, t_old, alpha_f)
            if isinstance(self.solver, PullInSolver):  # pull-ins at t_{n+1}, like motions
                self.solver.set_load_factor(self.tendons.pull_in_factors(t_new))

    def step(self, dt: float) -> int:
        """Advance by dt (raises SolveFailed, state unchanged in q_old/v_old/a_old)."""
        t_old, t_new = self.time, self.time + dt
        self.dt.value = dt
        self._set_time_values(t_new, t_old)
        if self.contact is not None:
            # augmentation well above the step's inertia stiffness rho A / (beta dt^2): a few
            # Uzawa updates reach the tolerance (the converged state does not depend on k)
            self.contact.set_stiffness(max(self.contact.base_stiffness, CONTACT_INERTIA_FACTOR
                                           * self._line_mass / (self.params["beta"] * dt**2)))
        w = compat.local_array(self.problem.w)
        q, v, a = (compat.local_array(f) for f in (self.q_old, self.v_old, self.a_old))
        w[:] = q  # same-displacement predictor: robust when accelerations jump (releases)
        iterations = self.solver.solve()
        # a state with 1 + e <= 0 anywhere is not one of a real beam: a failed step (cut back)
        self._trial_range = self.problem.strain_range()  # collective: on every rank
        reason = self._trial_range.inadmissible()
        if reason is None and self.contact is not None:  # through a thin obstacle: cut back
            flags = self.problem.comm.allgather(self.contact.tunnelled())
            reason = next((r for r in flags if r), None)
        if reason is not None:
            raise SolveFailed(reason)
        beta, gamma = self.params["beta"], self.params["gamma"]
        a_new = (w - q - dt * v) / (beta * dt**2) - (1 - 2 * beta) / (2 * beta) * a
        v_new = v + dt * ((1 - gamma) * a + gamma * a_new)
        self._candidate = (w.copy(), v_new, a_new, t_old, t_new)
        return iterations

    def local_error(self) -> float:
        """Zienkiewicz-Xie estimate dt^2 |beta - 1/6| |a_{n+1} - a_n| (max over u, v, L*theta)."""
        _, _, a_new, t_old, t_new = self._candidate
        dt = t_new - t_old
        difference = np.abs(a_new - compat.local_array(self.a_old))
        scale = np.ones_like(difference)
        scale[self._theta_dofs()] = self.problem.model.length
        local = float(np.max(difference[self._motion_dofs()] * scale[self._motion_dofs()],
                             initial=0.0))
        return global_max(self.problem.comm, local) * dt**2 * abs(self.params["beta"] - 1 / 6)

    def accept(self) -> None:
        w, v_new, a_new, t_old, t_new = self._candidate
        alpha_f = self.params["alpha_f"]
        q_old, v_old = compat.local_array(self.q_old), compat.local_array(self.v_old)
        compat.local_array(self._step_state)[:] = (1 - alpha_f) * w + alpha_f * q_old
        compat.local_array(self._step_velocity)[:] = (1 - alpha_f) * v_new + alpha_f * v_old
        compat.local_array(self._step_increment)[:] = w - q_old
        self._dissipated += assemble_scalar(self.forms["damping_work"])
        if "follower_work" in self.forms:  # at the step's load factor (still set)
            self._work += assemble_scalar(self.forms["follower_work"])
        if self.contact is not None:  # the step's contact forces (at t_{n+1}), then commit
            work = assemble_scalar(self.forms["contact_work"])
            self._contact_work += work
            self._work += work
            self.contact.commit()
        load_mid = ((1 - alpha_f) * self.load_function(t_new)
                    + alpha_f * self.load_function(t_old))
        compat.local_array(self.q_old)[:] = w
        compat.local_array(self.v_old)[:] = v_new
        compat.local_array(self.a_old)[:] = a_new
        load_energy = self._unit_load_energy()
        self._work += load_mid * (load_energy - self._load_energy)
        self._load_energy = load_energy
        if self.tendons is not None:  # problem.w is the accepted state; tensions of the step
            lengths = self.tendons.lengths()
            step = self.tendons.step_work(self._tendon_lengths, lengths)
            self._tendon_work += step
            self._work += step
            self._tendon_lengths = lengths
        self.time = t_new
        if self._trial_range is not None:
            self.watch.observe(self._trial_range)

    def reject(self) -> None:
        compat.local_array(self.problem.w)[:] = compat.local_array(self.q_old)
        self._set_time_values(self.time, self.time)

    def energies(self) -> dict:
        kinetic = assemble_scalar(self.forms["kinetic"])
        if self.tendons is not None:  # the rod's energy: the tendon potential is work
            with self.tendons.slack():
                strain = assemble_scalar(self.forms["strain"])
        else:
            strain = assemble_scalar(self.forms["strain"])
        values = {"kinetic": kinetic, "strain": strain, "external_work": self._work,
                  "dissipated": self._dissipated}
        if self.tendons is not None:
            values["tendon_work"] = self._tendon_work
        if self.contact is not None:
            values["contact_work"] = self._contact_work
        start = getattr(self, "energy0", None)
        initial = start["kinetic"] + start["strain"] if start else kinetic + strain
        values["balance_residual"] = (kinetic + strain + self._dissipated - self._work - initial)
        return values



def period_from_crossings(times: np.ndarray, signal: np.ndarray) -> float:
    """Mean period from upward zero crossings (linear interpolation between samples)."""
    signal = signal - np.mean(signal)
    crossings = []
    for i in range(len(signal) - 1):
        if signal[i] < 0 <= signal[i + 1]:
            fraction = -signal[i] / (signal[i + 1] - signal[i])
            crossings.append(times[i] + fraction * (times[i + 1] - times[i]))
    if len(crossings) < 2:
        return math.nan
    return float(np.mean(np.diff(crossings)))

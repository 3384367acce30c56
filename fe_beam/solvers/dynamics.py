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

import copy
import dataclasses
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

__all__ = ["Damping", "DynamicsFailed", "EnergyGuard", "GeneralizedAlpha", "MomentumWatch",
           "StepDriver", "TimeSettings", "alpha_parameters"]

#: the dynamic contact stiffness k relative to the step's inertia stiffness rho A / (beta dt^2)
#: (times [contact] penalty): measured on a silicone strip landing on a floor, the Uzawa updates
#: contract by 0.63 each at 10 (the contact points outnumber the displacement dofs: the rod
#: resists a pressure pattern more stiffly than its inertia alone) and by 0.07 at 100
CONTACT_INERTIA_FACTOR = 100.0

#: the energy-balance certificate of generalised-alpha: kinetic + strain + dissipated - external
#: work - initial energy, relative to the largest of these terms so far (an energy gain; for the
#: non-dissipative rho_inf = 1 without contact, either sign)
ENERGY_TOLERANCE = 2e-2
#: the share of the energy tolerance one step may spend: its fraction dt / t_end of the run,
#: but at least this (a step that spends more is halved)
ENERGY_STEP_SHARE = 0.05
#: the energy scale below which nothing is judged, relative to E A_max L (the strain energy of
#: an axial strain of about 1.4e-6): a rod at rest has no energy to judge a balance against
ENERGY_FLOOR = 1e-12
#: the most halvings of the given step the energy balance may ask for before the run stops
ENERGY_HALVINGS = 6
#: free flight (no supports, loads, damping c, tendons or contact): the drift of the linear and
#: angular momenta relative to their scale, per scheme kind (conserving / dissipative)
MOMENTUM_TOLERANCE = {"conserving": 1e-6, "dissipative": 1e-2}


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


def strain_rates(parts, rates, chain=None):
    """Directional derivatives (eps, g, kappa) of the strains at ``parts`` along ``rates``
    (``chain``: a chain of rods' `fe_beam.fem.structure.ChainGeometry`, each rod's tangent in
    its own frame, R(-theta0) r')."""
    u, v, theta = parts
    du, dv, dtheta = rates
    if chain is None:
        tangent, moved = axis_tangent(u, v), (du.dx(0), dv.dx(0))
    else:
        tangent = chain.local_displacement_tangent(u, v)
        c, s_ = ufl.cos(chain.theta0), ufl.sin(chain.theta0)
        moved = (c * du.dx(0) + s_ * dv.dx(0), -s_ * du.dx(0) + c * dv.dx(0))
    stretch_x, stretch_y = (ufl.variable(c) for c in tangent)
    angle, curvature = ufl.variable(theta), ufl.variable(theta.dx(0))
    s = strains_from_gradient(ufl.as_vector([stretch_x, stretch_y]), angle, curvature)
    directions = ((stretch_x, moved[0]), (stretch_y, moved[1]), (angle, dtheta),
                  (curvature, dtheta.dx(0)))

    def rate(quantity):
        return sum(ufl.diff(quantity, variable) * direction for variable, direction in directions)

    return rate(s.eps), rate(s.g), rate(s.kappa)


class EnergyGuard:
    """The energy balance of a time integration (the certificate ``energy_balance``): the
    residual R = kinetic + strain + dissipated - external work - initial energy
    (`StepDriver.energies` "balance_residual") relative to the scale S, the largest of
    |kinetic|, |strain|, |external work|, |dissipated| and the initial energy over the run.

    ``conserving`` schemes (energy-conserving, generalised-alpha with rho_inf = 1 and no contact)
    have no numerical dissipation: |R| is judged. Dissipative ones (rho_inf < 1, contact) lose
    energy by design, and the loss is measured, not bounded: ``numerical_dissipation`` =
    max(-R, 0) (the energy the scheme removed beyond the damping and contact work it accounts
    for); a gain R > 0 is an error of the scheme (no discrete force creates energy) and is
    judged.

    Each step: its change of the judged R may spend its share of the tolerance, tolerance * S *
    max(dt / t_end, `ENERGY_STEP_SHARE`) (S so far, at least `ENERGY_FLOOR` E A L), and may
    not raise it above tolerance * S; a step that does is halved, as long
    as halving helps (the halved step spends less than half as much: a start-up transient whose
    relative error does not shrink with dt is accepted, and judged at the end). The certificate
    is the largest judged R over the steps relative to the run's S."""

    def __init__(self, energies: dict, tolerance: float, conserving: bool, t_end: float,
                 enabled: bool = True, floor: float = 0.0):
        self.tolerance, self.conserving, self.t_end = tolerance, conserving, t_end
        self.enabled = enabled
        self.initial = energies["kinetic"] + energies["strain"]
        self.residual = energies.get("balance_residual", 0.0)
        self.scale = self._scale(energies, floor)
        self.worst = 0.0  # the largest judged R (J) over the accepted steps
        self.worst_time = 0.0
        self.dissipation = 0.0  # max(-R, 0) of the last accepted step
        self.failed = None  # {t, reason} of the step that stopped the run
        self.unresolved = 0  # steps accepted although refining them did not help
        self._trial = None

    def _scale(self, energies: dict, previous: float) -> float:
        terms = [abs(energies.get(k, 0.0)) for k in ("kinetic", "strain", "external_work",
                                                     "dissipated")]
        return max(previous, abs(self.initial), *terms)

    def judged(self, residual: float) -> float:
        """The part of R the balance judges (J)."""
        return abs(residual) if self.conserving else max(residual, 0.0)

    def judge(self, energies: dict, dt: float, t: float) -> tuple[str | None, float]:
        """The accepted candidate's energies at time t after a step dt: (None or why the step
        fails, the share of the step's tolerance it spent). The candidate is kept for
        `commit`."""
        residual = energies["balance_residual"]
        scale = self._scale(energies, self.scale)
        self._trial = (residual, scale, t)
        if not self.enabled:
            return None, 0.0
        if not math.isfinite(residual):
            return "the energy balance is not a finite number", math.inf
        change = self.judged(residual) - self.judged(self.residual)
        share = self.tolerance * max(dt / self.t_end, ENERGY_STEP_SHARE) * scale
        spent = max(change, 0.0) / share if share > 0 else 0.0
        if spent > 1:
            return (f"the step changed the energy balance by {change / scale:.3g} of the largest "
                    f"energy term, more than its share {share / scale:.3g} of the tolerance "
                    f"{self.tolerance:.3g}"), spent
        if change > 0 and self.judged(residual) > self.tolerance * scale:
            return (f"the energy balance reaches {self.judged(residual) / scale:.3g} of the "
                    f"largest energy term > {self.tolerance:.3g}"), max(spent, 1.0)
        return None, spent

    def within_total(self) -> bool:
        """Whether the candidate's judged R stays within the run's tolerance (an impact step,
        whose energy change does not shrink with dt, is judged so)."""
        residual, scale, _ = self._trial
        return self.judged(residual) <= self.tolerance * scale

    def refuse(self, verdict: str, t: float, spent: float) -> None:
        """The step at time t failed the balance at the smallest step (the run stops, or keeps
        it under [checks] strict = false), having spent ``spent`` times its share: the
        certificate's value is then at least the tolerance times that."""
        residual, scale, _ = self._trial
        self.failed = self.failed or {"t": t, "reason": verdict}
        self.scale = max(self.scale, scale)
        if self.judged(residual) > self.worst:
            self.worst, self.worst_time = self.judged(residual), t
        self.floor = max(getattr(self, "floor", 0.0), self.tolerance * spent)

    def commit(self) -> None:
        residual, scale, t = self._trial
        self.residual, self.scale = residual, scale
        if self.judged(residual) > self.worst:
            self.worst, self.worst_time = self.judged(residual), t
        self.dissipation = max(-residual, 0.0)

    def report(self) -> dict:
        scale = self.scale
        value = self.worst / scale if scale > 0 else (0.0 if self.worst == 0 else math.inf)
        value = max(value, getattr(self, "floor", 0.0))
        return {"value": value, "tolerance": self.tolerance, "t": self.worst_time,
                "conserving": self.conserving, "checked": self.enabled, "scale": scale,
                "failed": self.failed, "unresolved_steps": self.unresolved,
                "numerical_dissipation": self.dissipation,
                "relative_numerical_dissipation": self.dissipation / scale if scale else 0.0}


class MomentumWatch:
    """The linear and angular momenta over free flight (the certificates ``linear_momentum``
    and ``angular_momentum``): steps with no supports, no load at either end of the step, no
    viscous damping c, tendons or contact. The drift from the momenta at the start of each
    free-flight phase, relative to the scale max(|P_0|, sqrt(2 m K_0)) (linear) and max(|L_0|,
    R sqrt(2 m K_0)) (angular, R the rod's reach from the origin), m the rod's mass."""

    def __init__(self, tolerance: float):
        self.tolerance = tolerance
        self.reference = None
        self.worst = {"linear": 0.0, "angular": 0.0}
        self.steps = 0
        self.time = None  # the first free-flight time

    def start(self, momenta: dict, mass: float, kinetic: float, reach: float, t: float) -> None:
        linear = np.array([v for k, v in momenta.items() if not k.startswith("angular")])
        angular = np.array([v for k, v in momenta.items() if k.startswith("angular")])
        speed = math.sqrt(max(2 * mass * kinetic, 0.0))
        self.reference = (linear, angular, max(float(np.linalg.norm(linear)), speed),
                          max(float(np.linalg.norm(angular)), reach * speed))
        if self.time is None:
            self.time = t

    def stop(self) -> None:
        self.reference = None

    def observe(self, momenta: dict) -> None:
        linear0, angular0, scale_p, scale_l = self.reference
        linear = np.array([v for k, v in momenta.items() if not k.startswith("angular")])
        angular = np.array([v for k, v in momenta.items() if k.startswith("angular")])
        self.steps += 1
        for key, now, then, scale in (("linear", linear, linear0, scale_p),
                                      ("angular", angular, angular0, scale_l)):
            drift = float(np.max(np.abs(now - then), initial=0.0))
            value = drift / scale if scale > 0 else (0.0 if drift == 0 else math.inf)
            self.worst[key] = max(self.worst[key], value)

    def report(self) -> dict | None:
        if not self.steps:
            return None
        return {"linear": self.worst["linear"], "angular": self.worst["angular"],
                "tolerance": self.tolerance, "steps": self.steps, "from": self.time}


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

    # --- joint forces of a moving chain (fe_beam.fem.structure.ChainGeometry) -----------------
    def end_acceleration(self) -> None:
        """Solve the consistent acceleration of the current state (``problem.w``, v_old at
        the problem's load factor): M a = f_ext - f_int - C v - g(q, v) (the equations of
        motion at the state's time; the fixed dofs at zero). Its inertia is what the joint
        forces of a moving chain take (`end_inertia_work`): the elements before a joint then
        balance exactly with the rest of the structure."""
        p = self.problem
        if getattr(self, "_end_forms", None) is None:
            n = p.motion_count
            self._end_a = fem.Function(p.space)
            trial, test = ufl.TrialFunction(p.space), ufl.TestFunction(p.space)
            a_parts, t = ufl.split(trial), ufl.split(test)
            *parts, multipliers = p.fields()
            state = tuple(parts)
            mass = p.mass_work(state, a_parts[:n], test)
            for index in range(n, len(a_parts)):  # multipliers: identity
                mass += a_parts[index] * t[index] * ufl.dx
            velocity = tuple(ufl.split(self.v_old)[:n])
            force = ufl.derivative(p.stored_energy(state) - p.dead_load_work(state), p.w, test)
            if multipliers:
                force += ufl.derivative(p.constraint_term(state, multipliers), p.w, test)
            force += self.dissipation(state, velocity, test)
            quadratic = p.velocity_inertia_work(state, velocity, test)
            if quadratic is not None:
                force += quadratic
            if p.nonpotential_loads:
                force -= p.nonconservative_work(state, test)
            self._end_forms = (fem.form(mass), fem.form(-force))
        p.set_prescribed_factor(0.0)
        compat.solve_compiled(*self._end_forms, p.bcs, self._end_a)
        p.set_prescribed_factor(self.motion_function(self.time))
        compat.local_array(self._end_a)[p.multiplier_dofs()] = 0.0

    def end_inertia_work(self, test):
        """The inertia and damping forces' virtual work of the current state, v_old and the
        acceleration of `end_acceleration` (UFL)."""
        p = self.problem
        n = p.motion_count
        *parts, _ = p.fields()
        state = tuple(parts)
        velocity = tuple(ufl.split(self.v_old)[:n])
        acceleration = tuple(ufl.split(self._end_a)[:n])
        work = p.mass_work(state, acceleration, test)
        quadratic = p.velocity_inertia_work(state, velocity, test)
        if quadratic is not None:
            work += quadratic
        return work + self.dissipation(state, velocity, test)

    def dissipation(self, state, velocity, test):
        """Virtual work of viscous (c, on the translations) and Kelvin-Voigt (eta, planar)
        damping."""
        t = ufl.split(test) if not isinstance(test, (list, tuple)) else test
        work = self.c * sum(velocity[i] * t[i] for i in range(self.problem.translations)) \
            * self.dx_mass
        if self.damping.kelvin_voigt > 0:
            k = self.problem.stiffness
            chain = getattr(self.problem, "chain", None)
            rates = strain_rates(state, velocity, chain)
            variations = strain_rates(state, t[:3], chain)
            moduli = (k.EA, k.GA, k.EI)
            terms = zip(moduli, rates, variations, strict=True)
            work += self.eta * sum(m * r * d for m, r, d in terms) * self.problem.dx_energy
        return work

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
    #: the relative energy-balance tolerance (`EnergyGuard`) and whether the scheme conserves
    #: energy without numerical dissipation (a subclass or instance may say otherwise)
    energy_tolerance = ENERGY_TOLERANCE
    #: whether a step that fails the energy balance at the smallest step stops the run (else it
    #: is kept and the certificate fails: [checks] strict = false)
    energy_stop = True

    @property
    def conserving(self) -> bool:
        return False

    def energy_measured(self) -> bool:
        """Whether kinetic + strain + dissipated - external work is the whole balance: not with
        prescribed non-zero end motions (their reactions' work is not measured)."""
        return not getattr(self.problem, "_prescribed", None)

    def free_flight(self, t_old: float, t_new: float) -> bool:
        """A step with no supports, no load at either end, no viscous damping, tendons or
        contact: the momenta are constants of the motion."""
        p = self.problem
        unloaded = ((self.load_function(t_old) == 0 and self.load_function(t_new) == 0)
                    or _no_loads(getattr(p.model, "loads", None)))
        return (not p.bcs and self.damping.c == 0 and getattr(self, "tendons", None) is None
                and getattr(self, "contact", None) is None and unloaded)

    def _mass_and_reach(self) -> tuple[float, float]:
        """The rod's mass (rho A_max L) and its reach from the origin (L + |tip position|)."""
        model = self.problem.model
        length = model.length
        area = max(float(model.section.properties(s).A) for s in (0.0, 1.0))
        tip = self.problem.end_values("xL")
        position = np.array([length + tip["u"], tip["v"], tip.get("w", 0.0)])
        return float(model.material.rho) * area * length, length + float(np.linalg.norm(position))

    # --- the state of the accepted step, to take a step back (energy refinement) -----------
    #: the Functions and attributes that hold the accepted state (subclasses extend)
    _state_functions: tuple = ("q_old", "v_old")
    _state_attributes: tuple = ("time",)

    def _snapshot(self) -> dict:
        functions = {name: compat.local_array(getattr(self, name)).copy()
                     for name in self._state_functions}
        attributes = {name: copy.deepcopy(getattr(self, name)) for name in self._state_attributes
                      if hasattr(self, name)}
        return {"functions": functions, "attributes": attributes,
                "watch": copy.copy(getattr(self.watch, "worst", None))}

    def _restore(self, snapshot: dict) -> None:
        for name, values in snapshot["functions"].items():
            function = getattr(self, name)
            compat.local_array(function)[:] = values
            function.x.scatter_forward()
        for name, value in snapshot["attributes"].items():
            setattr(self, name, value)
        self.watch.worst = snapshot["watch"]

    def _commit(self) -> None:
        """The accepted step passed its checks (a subclass commits what cannot be undone)."""

    def _rotation_note(self) -> str:
        """For a spatial rod whose rotation vector nears its singularity |theta| = 2 pi (where
        generalised-alpha on the rotation vector breaks down): a clause saying so."""
        p = self.problem
        if not getattr(p, "spatial", False):
            return ""
        w = compat.local_array(p.w)
        parts = [np.asarray(compat.sub_space_collapsed(p.space, i)[1])
                 for i, name in enumerate(p.components) if name.startswith("theta")]
        if len(parts) != 3:
            return ""
        local = float(np.max(np.sqrt(sum(w[d] ** 2 for d in parts)), initial=0.0))
        largest = global_max(p.comm, local)
        if largest < 1.5 * math.pi:
            return ""
        return (f"; the rotation vector reaches |theta| = {largest:.3g} rad, near its "
                "singularity 2 pi, where the rotation-vector scheme is not fit")

    def run(self, on_output: Callable[[float, int], None] | None = None,
            progress: bool = True) -> dict:
        """Integrate to t_end; ``on_output(t, step)`` after every ``output_every`` steps.

        Every accepted step is judged by the energy balance (`EnergyGuard`): a step that fails
        it is taken back and halved (at most `ENERGY_HALVINGS` times below the given dt, and
        grows back after 4 good steps); at the smallest step the run stops (DynamicsFailed, the
        state the last accepted one). The certificates' values are in the returned ``checks``.
        """
        s = self.settings
        dt, steps, rejected, newton, refined = s.dt, 0, 0, 0, 0
        length = self.problem.model.length
        model = self.problem.model
        floor = ENERGY_FLOOR * float(model.material.E) * model.length * max(
            float(model.section.properties(x).A) for x in (0.0, 1.0))
        guard = EnergyGuard(self.energies(), self.energy_tolerance, self.conserving, s.t_end,
                            enabled=self.energy_measured(), floor=floor)
        momentum = MomentumWatch(MOMENTUM_TOLERANCE["conserving" if self.conserving
                                                    else "dissipative"])
        self.guard, self.momentum_watch = guard, momentum
        smallest_energy_step = max(s.smallest_step, s.dt / 2**ENERGY_HALVINGS)
        calm = 0  # accepted steps since the last energy refinement
        refused = None  # (time, spent share) of the last step the energy balance refused
        bar = ProgressBar(self.problem.comm, total=s.t_end, label="time", enabled=progress,
                          unit="s")
        started = time.perf_counter()
        if on_output is not None:
            on_output(self.time, 0)
        try:
            while self.time < s.t_end * (1 - 1e-12):
                trial = min(dt, s.t_end - self.time)
                free = self.free_flight(self.time, self.time + trial)
                if free and momentum.reference is None:
                    mass, reach = self._mass_and_reach()
                    momentum.start(self.momenta(), mass, self.energies()["kinetic"], reach,
                                   self.time)
                elif not free:
                    momentum.stop()
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
                    next_dt = min(trial * min(2.0, max(0.2, factor)), s.largest_step)
                elif dt < s.dt and iterations <= 4 and calm >= 4:
                    next_dt = min(2 * dt, s.dt)  # grow back after a cut-back
                else:
                    next_dt = dt
                saved, t_start = self._snapshot(), self.time
                self.accept()
                verdict, spent = guard.judge(self.energies(), trial, self.time)
                if verdict is not None and refused is not None and refused[0] == t_start \
                        and spent > 0.5 * refused[1]:
                    # halving did not help (a start-up transient, self-similar in dt): accept
                    guard.unresolved += 1
                    verdict = None
                if verdict is not None and getattr(self, "impact", False) \
                        and guard.within_total():
                    # an impact enforced at t_{n+1} exchanges energy in proportion to the
                    # contacting points' kinetic energy at any dt (where in the step the touch
                    # falls): halving does not help; the whole tolerance judges it
                    guard.unresolved += 1
                    verdict = None
                if (verdict is not None and not self.energy_stop
                        and trial / 2 < smallest_energy_step * (1 - 1e-9)):
                    # [checks] strict = false: the step is kept, the certificate fails
                    guard.refuse(verdict, self.time, spent)
                    verdict = None
                if verdict is not None:
                    t_failed, where = self.time, self._rotation_note()
                    self._restore(saved)
                    self.reject()
                    rejected += 1
                    refined += 1
                    calm = 0
                    refused = (self.time, spent)
                    if trial / 2 < smallest_energy_step * (1 - 1e-9):
                        guard.refuse(verdict + where, t_failed, spent)
                        self.run_info = {"steps": steps, "rejected_steps": rejected,
                                         "energy_refinements": refined,
                                         "newton_iterations": newton}
                        raise DynamicsFailed(
                            f"the energy balance check failed at t = {t_failed:.6g} s with the "
                            f"step {trial:.3g} s ({verdict}{where}; steps down to "
                            f"{smallest_energy_step:.3g} s tried); the integration is not "
                            f"trustworthy beyond t = {self.time:.6g} s, the last good state "
                            + ("(with [[obstacles]]: rho_inf = 1, whose impacts gain no "
                               "energy; the energy-conserving scheme takes no obstacles)"
                               if getattr(self, "contact", None) is not None else
                               "(use a smaller [time] dt, or scheme = \"energy-conserving\", "
                               "which has no rotation-vector singularity)"), self.time)
                    dt = trial / 2
                    bar.note(f"t = {self.time:.4g} s: step cut to {dt:.3g} s ({verdict})")
                    continue
                refused = None
                guard.commit()
                self._commit()
                if free:
                    momentum.observe(self.momenta())
                dt = next_dt
                calm += 1
                steps += 1
                newton += iterations
                bar.update(self.time, f"t = {self.time:.4g} s, dt = {trial:.3g} s")
                if on_output is not None and (steps % s.output_interval == 0
                                              or self.time >= s.t_end * (1 - 1e-12)):
                    on_output(self.time, steps)
        finally:
            bar.close()
        return {"steps": steps, "rejected_steps": rejected, "energy_refinements": refined,
                "newton_iterations": newton, "wall_time_s": time.perf_counter() - started}

    def certificates(self) -> dict:
        """The energy balance and the free-flight momenta of the run so far (`run` sets them:
        empty before)."""
        guard = getattr(self, "guard", None)
        if guard is None:
            return {}
        momentum = self.momentum_watch.report()
        return {"energy_balance": guard.report()} | (
            {"momentum": momentum} if momentum is not None else {})


def _no_loads(loads) -> bool:
    """Every load of ``loads`` (a model's loads dataclass) is zero or absent: a run without
    [loads] is in free flight whatever its time function (flags such as follower aside)."""
    if loads is None or not dataclasses.is_dataclass(loads):
        return False

    def zero(value) -> bool:
        if value is None or isinstance(value, bool):
            return True
        if isinstance(value, (int, float)):
            return value == 0
        if isinstance(value, (list, tuple)):
            return all(zero(item) for item in value)
        return False

    return all(zero(getattr(loads, f.name)) for f in dataclasses.fields(loads))


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
        self._contact_dissipated = 0.0
        self._last_residual = 0.0
        self._impacted = False
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
        force += self._constraints(test)  # a constrained rod's multipliers (a static start)
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
            self.contact.set_stiffness(max(
                self.contact.base_stiffness, self.contact.settings.penalty
                * CONTACT_INERTIA_FACTOR * self._line_mass / (self.params["beta"] * dt**2)))
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
        impact = False
        if self.contact is not None:
            # the contact's work is that of the scheme's forces, F_c(q_{n+1}) . (q_{n+1} - q_n),
            # except in an impact (a point pressed that was not): there it is not the energy
            # the contact exchanges (the impulse's acceleration enters the alpha-weighted
            # inertia, so K_{n+1} - K_n differs from it by O(1): measured +0.8 % of the largest
            # energy term, a spurious gain); booked instead: the work of the moving obstacles,
            # F_c . (c_{n+1} - c_n), and (below) the energy the step lost as the contact's
            # dissipation (a gain stays in the residual, where the energy balance judges it)
            scheme = assemble_scalar(self.forms["contact_work"])
            impact = scheme != 0.0 and self.contact.new_contact()
            work = self._obstacle_motion_work(t_old, t_new) if impact else scheme
            self._contact_work += work
            self._work += work
        load_mid = ((1 - alpha_f) * self.load_function(t_new)
                    + alpha_f * self.load_function(t_old))
        # an impact step and the one after it (which still carries the impulse's acceleration)
        # are judged against the whole tolerance (`run`)
        self.impact, self._impacted = impact or self._impacted, impact
        if impact:
            # the impulse makes a_{n+1} of the order of the velocity jump / (gamma dt); carried
            # into the next step's alpha-weighted inertia it acts as a spurious force (measured:
            # an energy gain of 1 % of the largest energy term right after a strip lands, at
            # every dt). The step after an impact starts from the step's mean acceleration
            # (v_{n+1} - v_n) / dt: exact for a smooth constant one (a rod sliding on landing)
            a_new = (v_new - v_old) / (t_new - t_old)
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
        if self.contact is not None:
            self._book_contact_loss(impact)

    def _obstacle_motion_work(self, t_old: float, t_new: float) -> float:
        """The work of the moving obstacles' contact forces (at t_{n+1}) over their
        displacement in the step (0 for fixed obstacles)."""
        work = 0.0
        for i, obstacle in enumerate(self.contact.obstacles):
            if obstacle.motion is None:
                continue
            shift = (np.asarray(obstacle.translation(t_new), dtype=float)
                     - np.asarray(obstacle.translation(t_old), dtype=float))
            if np.any(shift):
                work += float(self.contact.resultant(i) @ shift)
        return work

    def _book_contact_loss(self, impact: bool) -> None:
        """An impact step that lowered the balance residual: the loss is the contact's
        dissipation (`contact_dissipated`, taken from `contact_work`, so R is back to its
        value before the step; a gain is left in R, where the energy balance judges it). The
        impact of this scheme is inelastic (docs/theory.md)."""
        residual = self.energies()["balance_residual"]
        loss = self._last_residual - residual
        if impact and loss > 0:
            self._contact_dissipated += loss
            self._contact_work -= loss
            self._work -= loss
            residual += loss
        self._last_residual = residual

    _state_functions = ("q_old", "v_old", "a_old")
    _state_attributes = ("time", "_work", "_dissipated", "_contact_work", "_load_energy",
                         "_contact_dissipated", "_last_residual", "_impacted",
                         "_tendon_work", "_tendon_lengths")

    @property
    def conserving(self) -> bool:
        """rho_inf = 1 (no numerical dissipation) and no contact (whose scheme dissipates)."""
        return self.settings.rho_inf == 1 and self.contact is None

    def _commit(self) -> None:
        if self.contact is not None:  # the accepted state's pressures and references
            self.contact.commit()

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
            values["contact_dissipated"] = self._contact_dissipated
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

"""Frictionless tendons (docs/theory.md, Tendons): potential tau * l with l = int |r_c'| dx.

The tendon path in the body frame is r_c = r + delta(x) d(theta), d = (-sin theta, cos theta),
between an entry x_a and an anchor x_b; positive delta lies on the +d side, so pulling a tendon
with positive offset bends the beam counterclockwise (toward +y). Differentiating tau * l gives
the anchor point load and the distributed centripetal load of a curved path automatically
(Camarillo 2008; Rucker & Webster 2011). A tendon may have several branches with one tension
(the chapter's loop: left and right branches joined across the tip); l is then their sum.

Tension control: tau = load factor * tension. Displacement control: the pull-in
l_0 - l = load factor * pull_in is prescribed and tau is a global unknown of the same Newton
system as the beam (bordered with g_i = dl_i/dw: `PullInSolver`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Sequence

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.fem.mpi import assemble_scalar
from fe_beam.fem.rotations import profile_expression
from fe_beam.model.tendons import Path, Tendon, looped_tendon  # noqa: F401  (re-exported)

__all__ = ["Tendon", "TendonSet", "looped_tendon", "strain_tendon_length_density",
           "tendon_length_density"]


def tendon_length_density(w_parts, delta, delta_prime):
    """|r_c'| with r_c' = r' + delta' d + delta d', d' = -theta' (cos theta, sin theta)."""
    u, v, theta = w_parts
    cos_t, sin_t = ufl.cos(theta), ufl.sin(theta)
    kappa = theta.dx(0)
    tangent_x = 1 + u.dx(0) - delta_prime * sin_t - delta * kappa * cos_t
    tangent_y = v.dx(0) + delta_prime * cos_t - delta * kappa * sin_t
    return ufl.sqrt(tangent_x**2 + tangent_y**2)


def strain_tendon_length_density(s, delta, delta_prime):
    """|r_c'| of a tendon at offset delta(x) in terms of the strains (the body-frame form of
    `tendon_length_density`, from a `fe_beam.fem.kinematics.Strains` ``s``):
    sqrt((1 + e - delta kappa)^2 + (g + delta')^2)."""
    return ufl.sqrt((s.one_plus_e - delta * s.kappa) ** 2 + (s.g + delta_prime) ** 2)


class TendonSet:
    """The tendons of one problem: tension constants, length forms and the energy hook."""

    def __init__(self, tendons: Sequence[Tendon], length: float):
        for tendon in tendons:
            tendon.validate_for(length)
        self.tendons = tuple(tendons)
        self.length = length
        self.tensions: list[fem.Constant] = []
        self.length_forms: list[fem.Form] = []
        self.length_ufl: list[ufl.Form] = []
        self.gradient_forms: list[fem.Form] = []
        self.rest_lengths = np.zeros(len(self.tendons))
        self._problem = None

    @property
    def breakpoints(self) -> tuple[float, ...]:
        points = set()
        for tendon in self.tendons:
            points |= {tendon.entry, tendon.anchor}
            if tendon.routing is None:  # a routing is smooth: its samples are no kinks
                points |= {x for path in tendon.paths for x, _ in path}
        return tuple(sorted(points))

    def energy(self, problem, parts):
        """sum_i tau_i l_i of the state ``parts`` (BeamProblem's extra_energy hook)."""
        if self._problem is not problem:
            self._attach(problem)
        return sum(tension * self._length(parts, i) for i, tension in enumerate(self.tensions))

    def _length(self, parts, index: int):
        inside, deltas = self._geometry[index]
        if getattr(self._problem, "spatial", False):
            density = sum((self._problem.tendon_length_density(parts, offsets)
                           for offsets in deltas), ufl.zero())
            return inside * density * self._problem.dx_energy
        if getattr(self._problem, "chain", None) is not None:
            # a chain of rods: the body-frame form, the strains in each rod's own frame (its
            # section director at the world angle theta0 + theta)
            strains = self._problem.strains(*parts)
            density = sum((strain_tendon_length_density(strains, delta, delta.dx(0))
                           for delta in deltas), ufl.zero())
            return inside * density * self._problem.dx_energy
        density = sum(
            (tendon_length_density(parts, delta, delta.dx(0)) for delta in deltas), ufl.zero()
        )
        # The tendon length uses the strain energy's Gauss rule: where constraints hold (at those
        # points) it sees exactly the constrained kinematics, e.g. |r_c'| = 1 - delta kappa.
        return inside * density * self._problem.dx_energy

    def _attach(self, problem) -> None:
        """Offsets, indicators, tension constants and length forms on the problem's mesh."""
        self._problem = problem
        mesh = problem.mesh
        offsets = compat.function_space(mesh, compat.element(mesh, "Lagrange", 1))
        indicator_space = compat.function_space(mesh, compat.element(mesh, "DG", 0))
        self._geometry = []
        for tendon in self.tendons:
            inside = fem.Function(indicator_space)
            inside.interpolate(lambda x, t=tendon: ((x[0] > t.entry) & (x[0] < t.anchor)) * 1.0)
            deltas = []
            routing = getattr(tendon, "routing", None)
            if not getattr(problem, "spatial", False):
                routing = None  # the planar rod reads the sampled paths of a routing
            if routing is not None:
                # the formulas themselves: exact offsets and derivatives in the forms
                deltas.append(tuple(profile_expression(profile, mesh) for profile in routing))
            for path in tendon.paths if routing is None else ():
                delta = fem.Function(offsets)
                xs, ds = np.array([p[0] for p in path]), np.array([p[1] for p in path])
                delta.interpolate(lambda x, xs=xs, ds=ds: np.interp(x[0], xs, ds))
                deltas.append((delta, fem.Constant(mesh, 0.0)) if getattr(problem, "spatial", False)
                              else delta)
            self._geometry.append((inside, deltas))
            self.tensions.append(fem.Constant(mesh, 0.0))
        parts = problem.state_parts() if getattr(problem, "spatial", False) \
            else problem.fields()[:3]
        test = ufl.TestFunction(problem.space)
        for index in range(len(self.tendons)):
            length = self._length(parts, index)
            self.length_ufl.append(length)
            self.length_forms.append(fem.form(length))
            self.gradient_forms.append(fem.form(ufl.derivative(length, problem.w, test)))
        self.rest_lengths = self.lengths()

    def strain_potentials(self, problem) -> list[tuple[Callable, Callable[[float], float]]]:
        """The tendons as load potentials in the strains, for
        `fe_beam.solvers.energy_momentum.EnergyMomentum` (``potentials``): one pair (density,
        tension)
        per tendon, density(strains) = inside * sum over its branches of the body-frame length
        density (the same offsets and entry/anchor indicator as `lengths`; its integral over the
        energy rule is l_i) and tension(t) = tau_i(t) (`tension_at`; 0 for pull-in control)."""

        if self._problem is not problem:
            self._attach(problem)
        pairs = []
        for index, (inside, deltas) in enumerate(self._geometry):
            def density(s, inside=inside, deltas=deltas):
                return inside * sum((strain_tendon_length_density(s, delta, delta.dx(0))
                                     for delta in deltas), ufl.zero())

            pairs.append((density, lambda t, i=index: float(self.tension_at(t)[i])))
        return pairs

    def lengths(self) -> np.ndarray:
        return np.array([assemble_scalar(form) for form in self.length_forms])

    def pull_ins(self) -> np.ndarray:
        return self.rest_lengths - self.lengths()

    def tension_values(self) -> np.ndarray:
        return np.array([float(t.value) for t in self.tensions])

    def set_tension_controlled(self, load_factor: float) -> None:
        for tendon, constant in zip(self.tendons, self.tensions, strict=True):
            if not tendon.controlled_by_pull_in:
                constant.value = load_factor * tendon.tension

    # --- time-dependent tensions (dynamics; scheme-agnostic) ---------------------------------
    def set_time_functions(self, functions: Sequence[Callable[[float], float]]) -> None:
        """f_i(t) scaling tendon i's tension in time (one per tendon)."""
        if len(functions) != len(self.tendons):
            raise ValueError(f"need {len(self.tendons)} time functions, got {len(functions)}")
        self.time_functions = tuple(functions)

    def tension_at(self, t: float) -> np.ndarray:
        """tau_i(t) = tension_i f_i(t) of the tension-controlled tendons (0 for pull-in ones)."""
        functions = getattr(self, "time_functions", None) or (lambda t: 1.0,) * len(self.tendons)
        return np.array([0.0 if tendon.controlled_by_pull_in else tendon.tension * float(f(t))
                         for tendon, f in zip(self.tendons, functions, strict=True)])

    def set_time(self, t_new: float, t_old: float | None = None, alpha: float = 0.0) -> np.ndarray:
        """Set the tension constants of the tension-controlled tendons to the weighted value
        (1 - alpha) tau(t_new) + alpha tau(t_old) that a step from t_old to t_new applies
        (generalised-alpha: alpha = alpha_f; the midpoint rule: 1/2; t_old None: tau(t_new)).
        Returns the tensions set."""
        values = self.tension_at(t_new)
        if t_old is not None and alpha:
            values = (1 - alpha) * values + alpha * self.tension_at(t_old)
        for tendon, constant, value in zip(self.tendons, self.tensions, values, strict=True):
            if not tendon.controlled_by_pull_in:
                constant.value = float(value)
        return values

    def pull_in_factors(self, t: float) -> np.ndarray:
        """f_i(t) of the pull-in controlled tendons (in order): their pull-in is pull_in_i f_i(t)
        (`PullInSolver.set_load_factor` takes the array)."""
        functions = getattr(self, "time_functions", None) or (lambda t: 1.0,) * len(self.tendons)
        return np.array([float(f(t)) for tendon, f in zip(self.tendons, functions, strict=True)
                         if tendon.controlled_by_pull_in])

    def applied_tensions(self, t: float) -> np.ndarray:
        """Tensions to report at time t: tau_i(t) of the tension-controlled tendons, the current
        (solved) tension of the pull-in controlled ones."""
        values = self.tension_at(t)
        for i, tendon in enumerate(self.tendons):
            if tendon.controlled_by_pull_in:
                values[i] = float(self.tensions[i].value)
        return values

    def step_work(self, lengths_old: np.ndarray, lengths_new: np.ndarray) -> float:
        """Work the tendons do on the rod over a step: -sum_i tau_i (l_i,new - l_i,old), tau_i the
        tension constants the step applied (the tendon potential tau l is conservative at fixed
        tau, so this is exact for a constant tension and second order otherwise)."""
        change = np.asarray(lengths_new) - np.asarray(lengths_old)
        return float(-np.dot(self.tension_values(), change))

    def slack(self):
        """Context manager: all tensions 0 inside (the rod's own energy from a form that
        includes the tendon potential, which is linear in the tensions); restored after."""
        @contextlib.contextmanager
        def zero():
            saved = self.tension_values()
            for constant in self.tensions:
                constant.value = 0.0
            try:
                yield
            finally:
                for constant, value in zip(self.tensions, saved, strict=True):
                    constant.value = float(value)

        return zero()

    def gradient(self, index: int, bcs) -> PETSc.Vec:
        """g_i = dl_i/dw with Dirichlet rows zeroed."""
        vector = compat.create_vector(self.gradient_forms[index])
        with vector.localForm() as local:
            local.set(0.0)
        compat.assemble_vector(vector, self.gradient_forms[index])
        vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        compat.set_bc(vector, bcs, scale=0.0)
        return vector

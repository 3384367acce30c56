"""Frictionless contact of the planar rod with rigid obstacles (docs/theory.md, Contact with
rigid obstacles): gaps as UFL, the augmented-Lagrangian energy, and `ContactSet`, which holds
the multipliers and measures the contact state.

Gap. The section at x is the segment S(x) = {r + eta d : -below(x) <= eta <= above(x)} with
r = (x + u, v) the centreline, d = (-sin theta, cos theta) the section director and
below/above the section's extents (`fe_beam.model.obstacles.section_extents`: h(x)/2 each
side for a rectangle, also when tapered). The gap g(x) is the signed distance of S(x) to the
obstacle (`segment_gap`): for a plane the nearer end of the segment, i.e. the centreline offset
by the half-height on the side facing the obstacle; for a disc (planar cylinder or sphere) the
segment's point nearest the centre; for a box the largest face-plane distance. g >= 0 is
admissible. The numpy twins used by the configuration checks are in `fe_beam.model.obstacles`.

Enforcement (augmented Lagrangian, Alart-Curnier / Rockafellar): per obstacle the potential

    Pi_c = int 1/(2k) (<lambda - k g>_+^2 - lambda^2) dx
           + sum over the rod's two ends of 1/(2 k_e) (<lambda_e - k_e g_e>_+^2 - lambda_e^2)

with the multiplier lambda (a line pressure [N/m]) in a quadrature space of the contact rule
and one multiplier lambda_e [N] per end (the end sections are corners that touch first: the
elastica pushed on a floor touches with its tip's corner, which no interior Gauss point sees).
Its variation is -p dg with p = <lambda - k g>_+ >= 0: the pressure pushes the rod out. The
Uzawa update lambda <- p (`ContactSet.update`) between Newton solves drives the penetration to
zero, so the method is exact in the limit whatever k (`fe_beam.solvers.contact.ContactSolver`).

Newton never sees the kink of <.>_+: each Newton solve holds an active set chi (0/1 at every
contact point and end) fixed and solves the smooth problem with the energy
1/(2k) (chi (lambda - k g)^2 - lambda^2) (`active_set_density`); after it chi is set to
[lambda - k g > 0] (a primal-dual active-set step) and the solve repeated until chi no longer
changes, when p = chi (lambda - k g) = <lambda - k g>_+ exactly and the state solves the
augmented-Lagrangian equations. (Plain Newton on the C1 residual cycled between active sets
when a load step crossed the first touch: its first iterate overshoots deep into the obstacle.)

Quadrature: the contact integral has its own Gauss-Legendre rule of degree ``q`` (default 4 p
for elements of degree p: 2p + 1 points per element, e.g. 5 for P2), not the nodes alone: a P2
centreline may pass through an obstacle between nodes; the gap is measured (and the multipliers
live) at exactly these points and at the two ends.
"""

from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from fe_beam.fem import compat
from fe_beam.fem.mpi import global_sum
from fe_beam.model.obstacles import (
    Box,
    ContactSettings,
    Cylinder,
    Obstacle,
    Plane,
    Sphere,
    section_extents,
    segment_distance,
)

__all__ = ["ContactSet", "active_set_density", "augmented_lagrangian_density",
           "contact_pressure", "director",
           "point_gap", "positive_part", "segment_gap"]


# --- pure functions returning UFL ---------------------------------------------------------------
def positive_part(value):
    """<value>_+ = max(value, 0) (its derivative is the Heaviside step: C1 energy)."""
    return ufl.conditional(ufl.gt(value, 0), value, 0)


# min and max through abs, not conditionals: their derivatives keep no conditional with a Zero
# branch (FFCx 0.5 fails on those: a box face's gap does not depend on one coordinate)
def _smaller(a, b):
    return (a + b - abs(a - b)) / 2


def _larger(a, b):
    return (a + b + abs(a - b)) / 2


def director(theta):
    """The section director d = (-sin theta, cos theta)."""
    return ufl.as_vector([-ufl.sin(theta), ufl.cos(theta)])


def point_gap(obstacle: Obstacle, p):
    """Signed distance (UFL) of the point p (a UFL vector of ``obstacle.dim`` components) to the
    obstacle, >= 0 outside (`fe_beam.model.obstacles.distance`). Dimension-agnostic."""
    if isinstance(obstacle, Plane):
        return ufl.dot(p - ufl.as_vector(obstacle.point), ufl.as_vector(obstacle.normal))
    if isinstance(obstacle, (Sphere, Cylinder)):
        centre = ufl.as_vector(obstacle.center if isinstance(obstacle, Sphere)
                               else obstacle.point)
        rel = p - centre
        if isinstance(obstacle, Cylinder) and obstacle.dim == 3:
            axis = ufl.as_vector(obstacle.axis)
            rel = rel - ufl.dot(rel, axis) * axis
        return ufl.sqrt(ufl.dot(rel, rel)) - obstacle.radius
    if isinstance(obstacle, Box):
        gaps = [ufl.dot(p - ufl.as_vector(point), ufl.as_vector(normal))
                for point, normal in obstacle.faces()]
        result = gaps[0]
        for gap in gaps[1:]:
            result = _larger(result, gap)
        return result
    raise TypeError(f"not an obstacle: {obstacle!r}")


def _plane_segment_gap(point, normal, r, d, below, above):
    n = ufl.as_vector(normal)
    dn = ufl.dot(d, n)
    return ufl.dot(r - ufl.as_vector(point), n) + _smaller(above * dn, -below * dn)


def segment_gap(obstacle: Obstacle, r, d, below, above):
    """Signed distance (UFL) of the section segment r + eta d, eta in [-below, above], to the
    obstacle: the gap of the rod's surface (module docstring). Plane: exact; disc: exact (the
    segment's point nearest the centre, eta clipped to the section); box: the largest
    face-plane distance (exact on the faces, conservative near the corners)."""
    if isinstance(obstacle, Plane):
        return _plane_segment_gap(obstacle.point, obstacle.normal, r, d, below, above)
    if isinstance(obstacle, (Sphere, Cylinder)):
        centre = ufl.as_vector(obstacle.center if isinstance(obstacle, Sphere)
                               else obstacle.point)
        eta = _larger(_smaller(ufl.dot(centre - r, d), above), -below)
        return point_gap(obstacle, r + eta * d)
    if isinstance(obstacle, Box):
        gaps = [_plane_segment_gap(point, normal, r, d, below, above)
                for point, normal in obstacle.faces()]
        result = gaps[0]
        for gap in gaps[1:]:
            result = _larger(result, gap)
        return result
    raise TypeError(f"not an obstacle: {obstacle!r}")


def contact_pressure(multiplier, gap, k):
    """p = <lambda - k g>_+ (>= 0; zero where the point is clear of the obstacle)."""
    return positive_part(multiplier - k * gap)


def augmented_lagrangian_density(multiplier, gap, k):
    """1/(2k) (<lambda - k g>_+^2 - lambda^2): its variation is -p dg, p the contact pressure;
    at lambda = 0 the plain penalty k/2 <-g>_+^2."""
    return (contact_pressure(multiplier, gap, k) ** 2 - multiplier**2) / (2 * k)


def active_set_density(multiplier, active, gap, k):
    """1/(2k) (chi (lambda - k g)^2 - lambda^2) at a fixed active set chi (0 or 1): smooth; equal
    to `augmented_lagrangian_density` where chi = [lambda - k g > 0], and its variation
    -chi (lambda - k g) dg the same."""
    return (active * (multiplier - k * gap) ** 2 - multiplier**2) / (2 * k)


# --- the obstacles of one problem ----------------------------------------------------------------
class ContactSet:
    """The obstacles of one `fe_beam.fem.rod.BeamProblem`: multipliers, the energy hook
    (``energy(problem, parts)``, like `fe_beam.fem.tendons.TendonSet`), the Uzawa update and
    the measured contact state. Built before the problem; attached on the first ``energy``."""

    def __init__(self, obstacles, settings: ContactSettings | None, model):
        self.obstacles = tuple(obstacles)
        self.settings = settings or ContactSettings()
        self.model = model
        self.tolerance = self.settings.tolerance(model.section)
        self._problem = None

    # --- set-up ------------------------------------------------------------------------------
    def energy(self, problem, parts):
        """sum over the obstacles of the augmented-Lagrangian potential of the state ``parts``."""
        if self._problem is not problem:
            self._attach(problem)
        u, v, theta = parts
        total = 0
        for i, _ in enumerate(self.obstacles):
            gap = self._gap(i, u, v, theta)
            total += active_set_density(self.multipliers[i], self.active[i], gap,
                                        self.k) * self.dx
            for e, measure in enumerate(self._end_measures):
                total += active_set_density(self.end_multipliers[i][e], self.end_active[i][e],
                                            gap, self.k_end) * measure
        return total

    def _attach(self, problem) -> None:
        self._problem = problem
        mesh, model = problem.mesh, self.model
        degree = self.settings.quadrature_degree or 4 * model.mesh.degree
        self.degree = degree
        import basix

        self.points, _ = basix.make_quadrature(basix.CellType.interval, degree)
        self.space = compat.function_space(mesh, compat.quadrature_element(mesh, degree))
        # own integration domain (tag 1) so that the quadrature coefficient sits in a kernel
        # with one rule (`fe_beam.solvers.energy_momentum`: FFCx 0.5 merges the integrals of one
        # domain, and evaluated such coefficients wrongly in kernels with several rules)
        index_map = mesh.topology.index_map(1)
        cells = np.arange(index_map.size_local + index_map.num_ghosts, dtype=np.int32)
        tags = compat.meshtags(mesh, 1, cells, np.ones(len(cells), dtype=np.int32))
        self.dx = ufl.Measure("dx", domain=mesh, subdomain_data=tags, subdomain_id=1,
                              metadata={"quadrature_degree": degree})
        self._end_measures = (problem.ds_start, problem.ds_tip)
        # k = penalty EI_min / h_e^4 (line pressure per unit gap), k_e = k h_e at the ends
        inertia = min(float(model.section.properties(s).I) for s in (0.0, 1.0))
        bending = float(model.material.E) * inertia
        h_e = float(problem.h_min)
        self.k_value = self.settings.penalty * bending / h_e**4
        self.k = fem.Constant(mesh, self.k_value)
        self.k_end = fem.Constant(mesh, self.k_value * h_e)
        self.multipliers = [fem.Function(self.space, name=f"contact_multiplier_{i}")
                            for i in range(len(self.obstacles))]
        self.end_multipliers = [[fem.Constant(mesh, 0.0), fem.Constant(mesh, 0.0)]
                                for _ in self.obstacles]
        self.active = [fem.Function(self.space, name=f"contact_active_{i}")
                       for i in range(len(self.obstacles))]
        self.end_active = [[fem.Constant(mesh, 0.0), fem.Constant(mesh, 0.0)]
                           for _ in self.obstacles]
        x = ufl.SpatialCoordinate(mesh)[0]
        self._s = x / model.length
        u, v, theta, _ = problem.fields()
        self._build_measures(problem, u, v, theta, x)
        self._committed = self._copy()
        self._positions = None

    def _extents(self):
        problem = self._problem
        return section_extents(self.model.section, self._s, problem.section_dims,
                               problem.section_dims_tip)

    def _gap(self, i, u, v, theta):
        x = ufl.SpatialCoordinate(self._problem.mesh)[0]
        below, above = self._extents()
        r = ufl.as_vector([x + u, v])
        return segment_gap(self.obstacles[i], r, director(theta), below, above)

    def _build_measures(self, problem, u, v, theta, x) -> None:
        """Compiled expressions at the contact points and forms of the resultants."""
        below, above = self._extents()
        r = ufl.variable(ufl.as_vector([x + u, v]))
        angle = ufl.variable(theta)
        columns = [x, r[0], r[1], -ufl.sin(theta), ufl.cos(theta), below, above]
        resultant_forms, end_gap_forms = [], []
        for i, obstacle in enumerate(self.obstacles):
            gap = segment_gap(obstacle, r, director(angle), below, above)
            columns.append(gap)
            g_r, g_theta = ufl.diff(gap, r), ufl.diff(gap, angle)
            moment_density = r[0] * g_r[1] - r[1] * g_r[0] + g_theta
            densities = (g_r[0], g_r[1], moment_density)
            # the pressure of the fixed-active-set energy: <lambda - k g>_+ once chi is
            # consistent (converged steps)
            pressure = self.active[i] * (self.multipliers[i] - self.k * gap)
            forms = []
            for density in densities:
                form = pressure * density * self.dx
                for e, measure in enumerate(self._end_measures):
                    form += self.end_active[i][e] * (self.end_multipliers[i][e]
                                                     - self.k_end * gap) * density * measure
                forms.append(fem.form(form))
            resultant_forms.append(forms)
            end_gap_forms.append([fem.form(gap * measure) for measure in self._end_measures])
        self._columns = len(columns)
        self._expression = compat.expression(ufl.as_vector(columns), self.points)
        self._resultant_forms = resultant_forms
        self._end_gap_forms = end_gap_forms
        index_map = problem.mesh.topology.index_map(1)
        self._owned_cells = np.arange(index_map.size_local, dtype=np.int32)
        self._dofs = compat.cell_dofs(self.space)[: len(self._owned_cells)].ravel()

    # --- state -------------------------------------------------------------------------------
    def _copy(self):
        return ([m.x.array.copy() for m in self.multipliers],
                [[float(c.value) for c in ends] for ends in self.end_multipliers])

    def _set(self, copy) -> None:
        """Multipliers from a copy, and the active set they imply (lambda > 0)."""
        interior, ends = copy
        for function, active, values in zip(self.multipliers, self.active, interior,
                                            strict=True):
            function.x.array[:] = values
            function.x.scatter_forward()
            active.x.array[:] = values > 0
            active.x.scatter_forward()
        for constants, flags, values in zip(self.end_multipliers, self.end_active, ends,
                                            strict=True):
            for constant, flag, value in zip(constants, flags, values, strict=True):
                constant.value = value
                flag.value = 1.0 if value > 0 else 0.0

    def restore(self) -> None:
        """Multipliers back to those of the last accepted state (`commit`)."""
        self._set(self._committed)

    def commit(self) -> None:
        """The current state is accepted: its pressures start the next solve (warm start) and
        its surface positions are the reference of the tunnelling check."""
        state = self.evaluate()
        interior = []
        for i, _ in enumerate(self.obstacles):
            values = self.multipliers[i].x.array.copy()
            values[self._dofs] = state["pressure"][i]
            interior.append(values)
        ends = [list(state["end_pressure"][i]) for i in range(len(self.obstacles))]
        self._committed = (interior, ends)  # ghosts: set by `_set`'s scatter
        self._positions = state["local"]

    def reset(self) -> None:
        """No contact: zero multipliers (the unloaded state)."""
        if self._problem is None:
            return
        for function in self.multipliers + self.active:
            function.x.array[:] = 0.0
        for ends in self.end_multipliers + self.end_active:
            for constant in ends:
                constant.value = 0.0
        self._committed = self._copy()
        self._positions = None

    def evaluate(self) -> dict:
        """The contact state of the current iterate (collective): per obstacle the gaps and
        pressures at the owned contact points (``gap``, ``pressure``: lists of arrays, in the
        order of the quadrature space's dofs), at the ends (``end_gap``, ``end_pressure``:
        [x = 0, x = L]), and the local point data (``local``: x, r, d, below, above)."""
        values = compat.evaluate_expression(self._expression, self._problem.mesh,
                                            self._owned_cells)
        values = np.asarray(values).reshape(-1, self._columns)
        k, k_end = self.k_value, self.k_value * float(self._problem.h_min)
        gaps, pressures, end_gaps, end_pressures = [], [], [], []
        changes = 0  # points whose active set disagrees with their pressure
        tiny = 1e-6 * k * self.tolerance  # pressures below it are round-off
        for i, _ in enumerate(self.obstacles):
            gap = values[:, 7 + i]
            trial = self.multipliers[i].x.array[self._dofs] - k * gap
            chi = self.active[i].x.array[self._dofs] > 0.5
            changes += int(np.count_nonzero((chi & (trial < -tiny)) | (~chi & (trial > tiny))))
            gaps.append(gap)
            pressures.append(np.maximum(trial, 0.0))
            ends = np.array([global_sum(self._problem.comm, fem.assemble_scalar(form))
                             for form in self._end_gap_forms[i]])
            end_gaps.append(ends)
            trial = np.array([float(c.value) for c in self.end_multipliers[i]]) - k_end * ends
            chi = np.array([float(c.value) for c in self.end_active[i]]) > 0.5
            if self._problem.comm.rank == 0:  # the ends are global numbers: counted once
                changes += int(np.count_nonzero((chi & (trial < -tiny * float(
                    self._problem.h_min))) | (~chi & (trial > tiny * float(self._problem.h_min)))))
            end_pressures.append(np.maximum(trial, 0.0))
        local = {"x": values[:, 0], "r": values[:, 1:3], "d": values[:, 3:5],
                 "below": values[:, 5], "above": values[:, 6]}
        changes = int(self._problem.comm.allreduce(changes, op=MPI.SUM))
        return {"gap": gaps, "pressure": pressures, "end_gap": end_gaps,
                "end_pressure": end_pressures, "local": local, "active_changes": changes}

    def max_penetration(self, state: dict | None = None) -> float:
        """max over all obstacles, contact points and ends of <-g>_+ (global) [m]."""
        return self._largest(state, lambda gap, pressure: -gap)

    def max_separation(self, state: dict | None = None) -> float:
        """max of g over the pressed points (p > 0) (global) [m]: > 0 breaks the
        complementarity p g = 0 (a point pushed while clear of the obstacle)."""
        return self._largest(state, lambda gap, pressure: np.where(pressure > 0, gap, 0.0))

    def _largest(self, state, measure) -> float:
        state = state or self.evaluate()
        local = 0.0
        for gap, pressure, end, end_pressure in zip(state["gap"], state["pressure"],
                                                    state["end_gap"], state["end_pressure"],
                                                    strict=True):
            if len(gap):
                local = max(local, float(np.max(measure(gap, pressure))))
            local = max(local, float(np.max(measure(end, end_pressure))))
        return self._problem.comm.allreduce(max(local, 0.0), op=MPI.MAX)

    def update(self, state: dict | None = None, multipliers: bool = True) -> None:
        """The active set chi <- [lambda - k g > 0] at every contact point and end and, with
        ``multipliers``, the Uzawa update lambda <- <lambda - k g>_+."""
        state = state or self.evaluate()
        k, k_end = self.k_value, self.k_value * float(self._problem.h_min)
        for i, function in enumerate(self.multipliers):
            lam = function.x.array[self._dofs]
            trial = lam - k * state["gap"][i]
            self.active[i].x.array[self._dofs] = trial > 0
            self.active[i].x.scatter_forward()
            if multipliers:
                function.x.array[self._dofs] = state["pressure"][i]
                function.x.scatter_forward()
            for e, (constant, flag) in enumerate(zip(self.end_multipliers[i],
                                                     self.end_active[i], strict=True)):
                trial = float(constant.value) - k_end * float(state["end_gap"][i][e])
                flag.value = 1.0 if trial > 0 else 0.0
                if multipliers:
                    constant.value = float(state["end_pressure"][i][e])

    def tunnelled(self) -> str | None:
        """Why the step from the last accepted state (the undeformed rod before the first) to
        the current one is rejected: a contact point whose straight path between the two
        passes deeper than a quarter of the section into an obstacle (a load step that jumped
        through a thin one), sampled finer than half the thinnest section or box. Local (the
        caller agrees over ranks); a false alarm (a path cutting a disc's chord) only cuts the
        step back."""
        after = self.evaluate()["local"]
        before = self._positions
        if before is None:  # the undeformed rod
            r = np.column_stack([after["x"], np.zeros_like(after["x"])])
            d = np.tile([0.0, 1.0], (len(r), 1))
            before = {"r": r, "d": d}
        if not len(after["x"]):
            return None
        thickness = float(np.min(after["below"] + after["above"]))
        thinnest = min([thickness] + [min(np.array(o.max) - np.array(o.min))
                                      for o in self.obstacles if isinstance(o, Box)])
        moved = float(np.max(np.linalg.norm(after["r"] - before["r"], axis=1)))
        samples = int(min(2000, max(8, np.ceil(2 * moved / thinnest))))
        depth = max(10 * self.tolerance, 0.25 * thickness)
        for obstacle in self.obstacles:
            for t in np.linspace(0.0, 1.0, samples + 1)[1:-1]:
                r = (1 - t) * before["r"] + t * after["r"]
                d = (1 - t) * before["d"] + t * after["d"]
                d = d / np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]
                gap = segment_distance(obstacle, r, d, after["below"], after["above"])
                if np.min(gap) < -depth:
                    j = int(np.argmin(gap))
                    return (f"contact: the load step moved the rod through obstacle "
                            f"{obstacle.name!r} (near x = {after['x'][j]:.4g} m)")
        return None

    def summary(self, state: dict | None = None) -> list[dict]:
        """Per obstacle, in the order given: {name, force [Fx, Fy] (the obstacle on the rod,
        global axes) [N], moment (about the origin, counterclockwise) [N m], active (contact
        intervals [[x0, x1], ...] in the reference x) [m], max_penetration [m],
        pressure_peak (largest line pressure at the contact points) [N/m], end_forces
        (the point forces at x = 0 and x = L) [N]}. Collective."""
        state = state or self.evaluate()
        comm = self._problem.comm
        x_all = np.concatenate(comm.allgather(state["local"]["x"]))
        order = np.argsort(x_all, kind="stable")
        result = []
        for i, obstacle in enumerate(self.obstacles):
            resultants = [global_sum(comm, fem.assemble_scalar(form))
                          for form in self._resultant_forms[i]]
            pressure = np.concatenate(comm.allgather(state["pressure"][i]))
            gap = np.concatenate(comm.allgather(state["gap"][i]))
            ends = state["end_pressure"][i]
            peak = float(np.max(pressure)) if len(pressure) else 0.0
            end_gap = state["end_gap"][i]
            active = _intervals(
                np.concatenate([[0.0], x_all[order], [self.model.length]]),
                np.concatenate([[ends[0] > 0], pressure[order] > 0.0, [ends[1] > 0]]),
                np.concatenate([[end_gap[0] <= self.tolerance], gap[order] <= self.tolerance,
                                [end_gap[1] <= self.tolerance]]))
            penetration = max(0.0, float(np.max(-gap)) if len(gap) else 0.0,
                              float(np.max(-state["end_gap"][i])))
            result.append({
                "name": obstacle.name,
                "force": [float(resultants[0]), float(resultants[1])],
                "moment": float(resultants[2]),
                "active": active,
                "max_penetration": penetration,
                "pressure_peak": peak,
                "end_forces": [float(e) for e in ends],
            })
        return result


def _intervals(x: np.ndarray, active: np.ndarray, touching: np.ndarray) -> list:
    """Runs of consecutive active (pressed) points, sorted by x, as [[x_first, x_last], ...];
    two runs are joined when every point between them touches (``touching``: gap within the
    tolerance: unloaded points of one contact zone, to which the augmented-Lagrangian updates
    have not spread the pressure). The callers put the rod's ends first and last."""
    active = np.array(active, dtype=bool)
    on = np.flatnonzero(active)
    for first, last in zip(on[:-1], on[1:], strict=True):
        if last > first + 1 and np.all(touching[first + 1:last]):
            active[first + 1:last] = True
    runs, start = [], None
    for j, flag in enumerate(active):
        if flag and start is None:
            start = j
        if not flag and start is not None:
            runs.append([float(x[start]), float(x[j - 1])])
            start = None
    if start is not None:
        runs.append([float(x[start]), float(x[-1])])
    return runs

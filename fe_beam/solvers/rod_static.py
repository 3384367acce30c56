"""The rod's static continuation: a configuration's problem and solver built once, whose load
factor moves by load stepping, with the step checks (rotation jump, admissibility) and the
stability of its equilibria (`fe_beam.solvers.critical.spectrum`); the up-front work limits.
The driver of ``fe-beam static`` is `fe_beam.analyses.static`."""

from __future__ import annotations

import numpy as np
import scipy.sparse
import scipy.sparse.linalg
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam import runctl
from fe_beam.fem import compat
from fe_beam.fem.contact import ContactSet
from fe_beam.fem.equilibrium import residual_floor
from fe_beam.fem.rod import BeamProblem, StrainWatch
from fe_beam.fem.spatial_rod import SpatialRodProblem
from fe_beam.fem.tendons import TendonSet
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers.contact import ContactSolver
from fe_beam.solvers.continuation import Continuation, NonlinearParameterProblem
from fe_beam.solvers.critical import STABILITY_MAX_DOFS, STABILITY_ZERO, spectrum  # noqa: F401
from fe_beam.solvers.newton import (
    LoadSteppingFailed,
    NonlinearProblem,
    SNESSolver,
    SolveFailed,
    StepResult,
    rotation_jump_check,
)
from fe_beam.solvers.pull_in import PullInSolver

__all__ = ["STABILITY_MAX_DOFS", "STABILITY_ZERO", "StaticContinuation", "beam_dofs_estimate",
           "check_beam_work"]


class StaticContinuation:
    """A configuration's problem and solver, built once, whose load factor can be moved from
    its current converged value to any other by load stepping (``advance``): continuation for
    inverse problems and parameter sweeps, where each new equilibrium starts from the last."""

    def __init__(self, config: StaticConfig, comm=MPI.COMM_WORLD,
                 problem: BeamProblem | None = None, prefix: str = "fe_beam_static_",
                 tendons: TendonSet | None = None):
        """``problem``: an existing problem of ``config.model`` to load (e.g. the static
        pre-state of a dynamic run); built from ``config`` when None. With tendons, a given
        problem needs its `TendonSet` (``tendons``: the one whose energy it holds)."""
        if problem is not None and config.tendons and tendons is None:
            raise ValueError("StaticContinuation: a given problem with tendons needs its tendons")
        if problem is not None and config.obstacles:
            raise ValueError("StaticContinuation: contact with obstacles needs its own problem")
        self.config = config
        self.tendons = tendons or (TendonSet(config.tendons, config.model.length)
                                   if config.tendons else None)
        self.contact = (ContactSet(config.obstacles, config.contact, config.model)
                        if config.obstacles else None)
        energies = [part.energy for part in (self.tendons, self.contact) if part is not None]
        self.problem = problem or build_problem(
            config.model,
            comm,
            breakpoints=self.tendons.breakpoints if self.tendons else (),
            extra_energy=_summed(energies),
            extra_work=self.contact.work if self.contact is not None and
            self.contact.frictional else None,
        )
        self.snes = SNESSolver(
            NonlinearProblem(self.problem.residual, self.problem.w, self.problem.bcs,
                             ties=self.problem.chain.tie_pairs()
                             if getattr(self.problem, "chain", None) is not None else None),
            config.solver.for_problem(self.problem.saddle_point, self.problem.comm),
            prefix=prefix,
            state_scale=config.model.length,
            residual_floor=residual_floor(self.problem),
        )
        self.solver = PullInSolver(self.snes, self.tendons) if self.tendons else self.snes
        if self.contact is not None:
            self.solver = ContactSolver(self.solver, self.contact)
        self.load_factor = 0.0
        # extremes of the strains over the converged states (notes when out of range)
        self.watch = StrainWatch()
        self._trial_range = None
        #: notes of the run beyond the strain range (e.g. a spatial rotation near 2 pi)
        self.notes: list[str] = []
        if getattr(self.problem, "curved", False):
            self._relax()

    def mechanism(self) -> str | None:
        """A structure with ties (pins, loops, T junctions, pieces): one sentence naming its
        mechanism when the reduced tangent at the reference state is singular (a zero
        eigenvalue of the Jacobi-scaled P^T K P by sparse shift-invert on every rank; the joint
        or the rod and the free dof), else None. Computed once (collective)."""
        if hasattr(self, "_mechanism"):
            return self._mechanism
        self._mechanism = None
        nonlinear = self.snes.problem
        chain = getattr(self.problem, "chain", None)
        if chain is None or not chain.structure.tied \
                or self.problem.global_dofs > MECHANISM_MAX_DOFS:
            return None
        state = compat.vector_of(self.problem.w).copy()
        factor = self.load_factor
        try:
            self.problem.set_load_factor(0.0)
            A = nonlinear.symmetric_tangent(state)
            matrix, start = gathered_sparse(A)
        finally:
            self.problem.set_load_factor(factor)
            state.destroy()
        scale = np.sqrt(np.abs(matrix.diagonal()))
        scale[scale == 0.0] = 1.0
        D = scipy.sparse.diags(1.0 / scale)
        scaled = D @ (0.5 * (matrix + matrix.T)) @ D
        largest = max(float(abs(scaled).sum(axis=1).max()), 1.0)  # >= every |eigenvalue|
        # the eigenvalue nearest zero (shift-invert about a shift below round-off)
        values, vectors = scipy.sparse.linalg.eigsh(scaled.tocsc(), k=1,
                                                    sigma=-1e-3 * MECHANISM_TOLERANCE * largest,
                                                    which="LM")
        if abs(values[0]) > MECHANISM_TOLERANCE * largest:
            return None
        kernel = vectors[:, 0] / scale
        full = kernel.copy()
        if nonlinear.ties is not None:  # the prolonged mode: P z
            full[nonlinear.ties.slaves] = kernel[nonlinear.ties.masters]
        owned = compat.vector_of(self.problem.w).getLocalSize()
        local = np.zeros(len(compat.local_array(self.problem.w)))
        local[:owned] = full[start:start + owned]
        self._mechanism = chain.describe_mechanism(local)
        return self._mechanism

    def _relax(self) -> None:
        """An initially curved spatial rod: solve the load factor 0 state from the stress-free
        shape's nodal values (the discrete stress-free state), the reference of displacements
        and of the tendons' rest lengths."""
        self._set_load_factor(0.0)
        try:
            self.solver.solve()
        except SolveFailed as failure:
            raise LoadSteppingFailed(f"the stress-free state of the curved rod: {failure}") \
                from None
        self.problem.relaxed()
        if self.tendons:
            self.tendons.rest_lengths = self.tendons.lengths()
        self._relaxed_state = compat.local_array(self.problem.w).copy()

    def _set_load_factor(self, value: float) -> None:
        self.problem.set_load_factor(value)
        if self.contact is not None:  # moving obstacles along the load path
            self.contact.move(value)
        if self.tendons:
            self.tendons.set_tension_controlled(value)
            self.solver.set_load_factor(value)

    def advance(self, target: float, stepping, on_converged=None, progress: bool = False,
                label: str = "load") -> None:
        """Load-step from the current load factor to ``target`` (load control of the engine
        `fe_beam.solvers.continuation.Continuation`); ``on_converged(step)`` gets the actual load
        factor. Raises `LoadSteppingFailed` (a `fe_beam.solvers.continuation.ContinuationFailed`)
        with
        the last converged state kept (and ``load_factor`` at its value)."""
        reason = self.mechanism()
        if reason is not None:
            raise LoadSteppingFailed(reason, float(self.load_factor), [])
        engine = self.engine()
        engine.parameter = float(self.load_factor)

        def converged(step: StepResult) -> None:
            self.load_factor = step.load_factor
            self._accepted(step, on_converged)

        engine.load_control(target, stepping, on_converged=converged, progress=progress,
                            label=label)

    def _accepted(self, step: StepResult, on_converged=None) -> None:
        """An accepted step: the strain range observed (the contact state was committed by
        the engine: `adapter`)."""
        if self._trial_range is not None:
            self.watch.observe(self._trial_range)
        if on_converged is not None:
            on_converged(step)

    def advance_along(self, set_parameter, start: float, target: float, stepping,
                      on_converged=None, label: str = "parameter") -> None:
        """Load-step another parameter (``set_parameter(value)``, e.g. one load's constant or
        the prescribed end values' factor, at the current load factor) from ``start`` to
        ``target``: a non-proportional load path after ``advance``, with the same step checks
        and the contact state committed at every accepted step (friction is load-path
        dependent: pressing first, then pulling). Raises `LoadSteppingFailed` with the last
        converged state kept."""
        adapter = self.adapter(set_parameter, parameter=start)
        adapter.arc_length_ready = False
        engine = Continuation(adapter, start)
        engine.load_control(target, stepping,
                            on_converged=lambda step: self._accepted(step, on_converged),
                            progress=False, label=label)

    def parameter_problem(self, parameter: str = "load_factor", tendon: int = 0
                          ) -> NonlinearParameterProblem:
        """This problem as a `fe_beam.solvers.continuation.ParameterProblem`: the parameter is the
        load
        factor (every load, tension-controlled tendon and prescribed end value scaled by it:
        with prescribed end values only, this is displacement control) or, with
        ``parameter="tension"``, the tension [N] of tendon ``tendon`` alone (the other tendons
        keep their tensions). The arc metric weighs u and v by 1/L^2, theta by 1 and the
        multipliers by 0; the step check vetoes rotation jumps and inadmissible states.
        Pull-in controlled tendons: load control only."""
        if parameter == "load_factor":
            setter = self._set_load_factor
        elif parameter == "tension":
            if not self.tendons or not 0 <= tendon < len(self.tendons.tendons):
                raise ValueError(f"parameter 'tension': no tendon {tendon}")
            if self.tendons.tendons[tendon].controlled_by_pull_in:
                raise ValueError(f"parameter 'tension': tendon {tendon} is pull-in controlled")
            constant = self.tendons.tensions[tendon]

            def setter(value: float) -> None:
                constant.value = float(value)
        else:
            raise ValueError(f"parameter must be 'load_factor' or 'tension', got {parameter!r}")
        adapter = self.adapter(setter)
        adapter.arc_length_ready = not (self.tendons and any(
            t.controlled_by_pull_in for t in self.tendons.tendons)) and not (
            self.contact is not None and (self.contact.frictional
                                          or any(getattr(self.contact, "moving", ()))))
        return adapter

    def adapter(self, set_parameter, checked: bool = True, parameter: float = 0.0
                ) -> NonlinearParameterProblem:
        """A `fe_beam.solvers.continuation.ParameterProblem` of this problem whose parameter
        ``set_parameter(value)`` moves: the arc metric, the step checks (``checked``) and, with
        obstacles, the contact state committed at every accepted point and kept in the
        engine's snapshots. Frictionless contact: load control and arc length (the contact
        updates wrap the corrector, `fe_beam.solvers.contact.ContactSolver.solve_with`)."""
        contact = self.contact
        hooks = ({} if contact is None else
                 {"accept": contact.commit, "save": contact.save, "load": contact.load,
                  "orient": contact.orientation})
        return NonlinearParameterProblem(self.solver, set_parameter,
                                         check_step=self._step_check() if checked else None,
                                         metric=self._metric(), parameter=parameter, **hooks)

    def engine(self) -> Continuation:
        """The continuation engine of the load factor (built once; its state is this problem's)."""
        if getattr(self, "_engine", None) is None:
            self._engine = Continuation(self.parameter_problem(), self.load_factor)
        return self._engine

    def _metric(self):
        metric = compat.vector_of(self.problem.w).duplicate()
        weights = np.zeros(metric.getLocalSize())
        length = self.config.model.length
        for name in self.problem.components:
            weight = 1.0 if name.startswith("theta") else 1 / length**2
            dofs = self.problem.component_dofs(name)
            weights[dofs] = weight
        metric.getArray()[:] = weights
        return metric

    def _step_check(self):
        """Reject a converged step that jumped branch (rotation jump) or is inadmissible
        (1 + e <= 0 somewhere: `fe_beam.fem.rod.StrainRange`); collective on all ranks."""
        rotation = rotation_jump_check(self.problem.rotation_dofs(),
                                       self.config.max_rotation_jump)

        def check(previous, current):
            reason = rotation(previous, current)
            self._trial_range = self.problem.strain_range()  # collective: on every rank
            note = getattr(self.problem, "rotation_note", lambda: None)()
            if note and note not in self.notes:
                self.notes.append(note)
            reason = reason or self._trial_range.inadmissible()
            if self.contact is not None:  # collective: on every rank, whatever its reason
                tunnel, change = self.contact.tunnelled(), self.contact.large_change()
                reason = reason or tunnel or change
            return reason

        return check

    def stability(self) -> dict | None:
        """Is the current equilibrium stable? The inertia of the tangent stiffness (dense for
        serial problems up to STABILITY_MAX_DOFS dofs, else a sparse parallel MUMPS LDL^T:
        `fe_beam.solvers.inertia`); None when the loads are not conservative (follower forces,
        pull-in
        control).

        With multipliers, the tangent stiffness is restricted to the directions that keep the
        constraints. A negative eigenvalue is a direction in which the energy decreases: the
        beam would buckle or snap away from this state.
        """
        result = spectrum(self)
        if result is None:
            return None
        return {"stable": result.unstable == 0, "energy_decreasing_directions": result.unstable}

    def restart(self) -> None:
        """Back to the unloaded reference state."""
        relaxed = getattr(self, "_relaxed_state", None)
        compat.local_array(self.problem.w)[:] = 0.0 if relaxed is None else relaxed
        self.load_factor = 0.0
        if self.contact is not None:
            self.contact.reset()

    def destroy(self) -> None:
        self.snes.destroy()


#: the largest structure whose mechanisms are looked for (a sparse shift-invert eigenproblem of
#: the gathered tangent on every rank)
MECHANISM_MAX_DOFS = 200_000
#: a zero eigenvalue of the Jacobi-scaled reduced tangent (relative to its infinity norm; measured:
#: 2e-16 for a pin in a cantilever, 1.3e-7 for a ring of 4 x 8 quadratic elements)
MECHANISM_TOLERANCE = 1e-13


def gathered_sparse(A: PETSc.Mat) -> tuple:
    """(the whole matrix ``A`` as a scipy CSR matrix on every rank, this rank's first row)."""
    start, _ = A.getOwnershipRange()
    ai, aj, av = A.getValuesCSR()
    comm = A.getComm().tompi4py()
    parts = comm.allgather((start, np.asarray(ai), np.asarray(aj), np.asarray(av)))
    size = A.getSize()[0]
    rows = np.concatenate([np.repeat(np.arange(first, first + len(r) - 1), np.diff(r))
                           for first, r, _, _ in parts])
    cols = np.concatenate([c for _, _, c, _ in parts])
    vals = np.concatenate([v for _, _, _, v in parts])
    return scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(size, size)), start


def build_problem(model, comm, breakpoints=(), extra_energy=None, extra_work=None):
    """The finite-element problem of a rod model: `SpatialRodProblem` for a spatial model
    (``[model] kinematics = "spatial"``), `BeamProblem` for a planar one."""
    kind = SpatialRodProblem if getattr(model, "kinematics", "planar") == "spatial" \
        else BeamProblem
    return kind(model, comm, breakpoints=breakpoints, extra_energy=extra_energy,
                extra_work=extra_work)


def _summed(energies):
    """One extra_energy hook from several (tendons, contact); None without any."""
    if not energies:
        return None
    if len(energies) == 1:
        return energies[0]
    return lambda problem, parts: sum(energy(problem, parts) for energy in energies)


def beam_dofs_estimate(config: StaticConfig) -> int:
    """Unknowns of the rod model of ``config``: the displacements and rotations and one field
    per constrained strain."""
    mesh = config.model.mesh
    if getattr(config.model, "kinematics", "planar") == "spatial":
        fields = 6 + {"inextensible": 1, "unshearable": 2,
                      "inextensible-unshearable": 3}.get(config.model.options.constraint, 0)
        return int(fields * (mesh.elements * mesh.degree + 1))
    fields = 3 + {"inextensible": 1, "unshearable": 1,
                  "inextensible-unshearable": 2}.get(config.model.options.constraint, 0)
    return int(fields * (mesh.elements * mesh.degree + 1))


def check_beam_work(config: StaticConfig, steps: float, comm, what: str = " of load stepping",
                    quiet: bool = False) -> list[str]:
    """Up-front limits (`fe_beam.runctl.check_work`): raises `fe_beam.runctl.TooLarge` on work
    beyond them unless ``[solver] allow_large = true``; warns on stderr (unless ``quiet``) and
    returns the warnings for the summary's ``notes``."""
    allow = bool((config.raw.get("solver") or {}).get("allow_large", False))
    notes = runctl.check_work(steps, beam_dofs_estimate(config), allow, what)
    if not quiet:
        runctl.warn(comm, notes)
    return notes

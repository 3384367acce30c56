"""One continuation engine: load control, displacement control and arc-length (docs/theory.md,
Path following).

A *parameter problem* (`ParameterProblem`) is a discretised residual R(x, lambda) = 0 whose load
parameter lambda is a mechanical load factor, a tendon tension or a prescribed end value. The
engine `Continuation` moves along its equilibrium path:

- `Continuation.load_control`: lambda is stepped, x solved by the problem's fixed-parameter
  Newton (`fe_beam.solvers.newton.SNESSolver`), with secant predictor, cut-back and growth (the
  behaviour of the former ``run_load_stepping``, bit for bit). Displacement control is the same
  strategy on a problem whose parameter scales prescribed end values (the rod's
  ``[loads] prescribed_x0/xL`` are scaled by the load factor).
- `Continuation.arc_length`: Riks' normal-plane (default) or Crisfield's spherical constraint
  with the load-parameter scaling psi, tangent predictor, adaptive arc length and automatic
  direction through limit points; each corrector iteration is one `bordered_solve`.

Failures raise `ContinuationFailed` (a `fe_beam.solvers.newton.LoadSteppingFailed`) with the last
converged state restored and the cause in ``reason``: never parse the message.
Pure PETSc/numpy: the problem adapters live next to their problems
(`fe_beam.analyses.static.StaticContinuation.parameter_problem`, `fe_beam.solvers.solid`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.model.settings import LoadStepping
from fe_beam.progress import ProgressBar
from fe_beam.solvers.newton import (
    STAGNATION_RTOL,
    LoadSteppingFailed,
    SNESSolver,
    SolveFailed,
    StepResult,
    _agreed,
)

__all__ = [
    "ArcLength",
    "BorderedConstraintSolver",
    "CallbackProblem",
    "Continuation",
    "ContinuationFailed",
    "ContinuationPoint",
    "NonlinearParameterProblem",
    "ParameterProblem",
    "Snapshot",
    "bordered_solve",
]


# --- failures and points -----------------------------------------------------------------------


class ContinuationFailed(LoadSteppingFailed):
    """The engine gave up; the last converged state (``parameter``) has been restored.

    ``reason``: why the last tries failed (the SNES reason, the step check's veto, ...);
    ``kind``: "step_too_small" (cut back below the smallest step), "not_adaptive" (a failed
    step without adaptation), "step" (a single `Continuation.step` or `Continuation.solve_at`
    failed); ``attempted``: the parameter of the last try; ``parameter``: the restored one.
    ``last_load_factor`` (of `LoadSteppingFailed`) is the load-control fraction reached (the
    parameter itself for a ramp 0 -> 1)."""

    def __init__(self, message: str, last_load_factor: float, results: list, *,
                 reason: str, kind: str, parameter: float, attempted: float):
        super().__init__(message, last_load_factor, results)
        self.reason = reason
        self.kind = kind
        self.parameter = parameter
        self.attempted = attempted


@dataclass
class ContinuationPoint(StepResult):
    """One converged point of the path (a `fe_beam.solvers.newton.StepResult` with more).

    ``load_factor`` is the parameter value (also ``parameter``); ``fraction``: the load-control
    fraction of the segment (1.0 at its end); ``arc_length``: the step's (scaled) arc length
    (0 under load control); ``tangent_parameter``: dlambda/ds of the unit tangent at the point
    (its sign changes at a limit point; None under load control); ``state``: a copy of the
    local dofs (owned + ghosts) of the converged state."""

    fraction: float = 1.0
    arc_length: float = 0.0
    tangent_parameter: float | None = None
    state: np.ndarray | None = field(default=None, repr=False)

    @property
    def parameter(self) -> float:
        return self.load_factor


@dataclass
class Snapshot:
    """A converged state: local dofs, parameter, unit tangent (x part as local array, lambda
    part) or None, and the arc length the next adaptive step would try."""

    state: np.ndarray
    parameter: float
    tangent: tuple[np.ndarray, float] | None
    arc_length: float | None
    #: the problem's own state beside x (`NonlinearParameterProblem.save_state`: e.g. the
    #: committed contact multipliers), None without one
    extra: object = None


@dataclass
class ArcLength:
    """Arc-length settings.

    ``increment``: the load-factor increment the first step would make under load control
    (sets the first arc length); ``psi``: load-parameter scaling of the arc metric
    ds^2 = |dx|_W^2 + psi^2 dlambda^2 (None: |dx/dlambda|_W of the first tangent, so that
    state and load share the first step equally); ``constraint``: "riks" (normal plane of the
    predictor) or "crisfield" (sphere, consistently linearised); ``direction``: sign of the first
    step's dlambda; ``max_steps`` / ``max_load_factor`` (|lambda| beyond it ends the run, the
    last point is then moved onto lambda = +-max_load_factor when the path crosses it with
    dlambda/ds != 0) / ``min_load_factor`` stop the path (no failure). Adaptation: a step
    whose corrector needs ``easy_iterations`` or fewer iterations lets the next grow by
    ``grow_factor`` (up to ``max_arc_length``, default 10 x the first); a failed step is retried
    ``cut_factor`` times shorter down to ``min_arc_length`` (default 1e-5 x the first)."""

    increment: float = 0.1
    psi: float | None = None
    constraint: str = "riks"
    direction: int = 1
    max_steps: int = 100
    max_load_factor: float = 1.0
    min_load_factor: float = -math.inf
    max_arc_length: float | None = None
    min_arc_length: float | None = None
    cut_factor: float = 0.5
    grow_factor: float = 1.5
    easy_iterations: int = 4
    adaptive: bool = True
    max_it: int | None = None

    def __post_init__(self):
        if not (self.increment > 0 and math.isfinite(self.increment)):
            raise ValueError(f"arc length: increment must be > 0, got {self.increment!r}")
        if self.constraint not in ("riks", "crisfield"):
            raise ValueError(f"arc length: constraint must be riks or crisfield, got "
                             f"{self.constraint!r}")
        if self.direction not in (1, -1):
            raise ValueError(f"arc length: direction must be 1 or -1, got {self.direction!r}")
        if not (isinstance(self.max_steps, int) and self.max_steps >= 1):
            raise ValueError(f"arc length: max_steps must be an integer >= 1, got "
                             f"{self.max_steps!r}")
        if self.psi is not None and not (self.psi >= 0 and math.isfinite(self.psi)):
            raise ValueError(f"arc length: psi must be >= 0, got {self.psi!r}")
        if not (0 < self.cut_factor < 1) or self.grow_factor < 1:
            raise ValueError("arc length: need 0 < cut_factor < 1 and grow_factor >= 1")


# --- the problem protocol -----------------------------------------------------------------------


class ParameterProblem(Protocol):
    """A problem with a load parameter, as the engine sees it.

    Load control needs ``comm``, ``solver``, ``state_vector``, ``state_array``,
    ``set_parameter`` and ``check_step``; arc-length also ``residual``, ``jacobian``, ``ksp``,
    ``parameter_derivative`` and ``metric``. `NonlinearParameterProblem` implements it for a
    `fe_beam.solvers.newton.SNESSolver`.
    """

    #: the fixed-parameter Newton: ``solve() -> iterations`` (raises
    #: `fe_beam.solvers.newton.SolveFailed`) that solves in place from the state,
    # ``linear_iterations``,
    #: optional ``residual_norm()`` and ``set_reference_residual(value)``
    #: (see `fe_beam.solvers.newton.SNESSolver`)
    solver: object
    #: the MPI communicator of the state
    comm: object
    #: the PETSc Vec of the state (ghosted or sequential; the engine updates ghosts)
    state_vector: PETSc.Vec
    #: writable numpy view of the state's local entries (owned + ghosts)
    state_array: np.ndarray

    def set_parameter(self, value: float) -> None:
        """Apply the parameter value (loads, tensions, prescribed values)."""

    def check_step(self, previous: np.ndarray, current: np.ndarray) -> str | None:
        """Veto a converged step (reason) or accept it (None); local arrays, may be local."""

    def residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """R(x, lambda) at the current parameter into b (Dirichlet rows: x - g(lambda))."""

    def jacobian(self, x: PETSc.Vec) -> PETSc.Mat:
        """dR/dx at x, assembled (identity Dirichlet rows and columns)."""

    @property
    def ksp(self) -> PETSc.KSP:
        """The linear solver of the fixed-parameter Newton (its operator is set by the engine)."""

    def parameter_derivative(self, x: PETSc.Vec, out: PETSc.Vec) -> None:
        """dR/dlambda at x and the current parameter into ``out``."""

    @property
    def metric(self) -> PETSc.Vec | None:
        """Diagonal weights W of the arc metric |dx|_W^2 = sum W_i dx_i^2 (None: all 1)."""


class NonlinearParameterProblem:
    """A `ParameterProblem` from a `fe_beam.solvers.newton.SNESSolver` (or a solver wrapping one,
    with
    ``.solver`` or ``.snes``) and a ``set_parameter`` callable.

    ``parameter_derivative`` is the central difference R(x, lambda + 1/2) - R(x, lambda - 1/2)
    when ``affine``: exact when the residual is a polynomial of degree <= 2 in the parameter at
    fixed x. Every dead load, follower load, tendon tension and prescribed end value of the rod
    and of the solid is linear in its factor; the Dirichlet lifting term K_ib(x, lambda)
    (g(lambda) - x_b) of `fe_beam.solvers.newton.NonlinearProblem` is then at most quadratic (a
    one-sided
    difference of width 1 would be wrong by dK_ib/dlambda g there). Otherwise
    (``affine=False``) the central finite difference (R(lambda + h) - R(lambda - h)) / 2h with
    h = ``step`` max(1, |lambda|), second-order accurate.
    ``metric``: diagonal weights of the arc metric (e.g. 1/L on displacements, 1 on rotations,
    0 on multipliers and pressures); ``check_step(previous, current)`` vetoes converged steps.
    ``orient(tangent) -> int``: see `orient_tangent`.
    ``accept()``, ``save() -> object`` and ``load(saved)``: the problem's state beside x (e.g.
    the contact multipliers and active set of `fe_beam.fem.contact.ContactSet`): ``accept`` when
    the engine accepts a point (every strategy), ``save`` / ``load`` with the engine's
    `Continuation.snapshot` / `Continuation.restore` (critical-point bisections, landings).
    """

    def __init__(self, solver, set_parameter: Callable[[float], None],
                 check_step: Callable[[np.ndarray, np.ndarray], str | None] | None = None,
                 metric: PETSc.Vec | None = None, affine: bool = True, step: float = 1e-6,
                 parameter: float = 0.0, accept: Callable[[], None] | None = None,
                 save: Callable[[], object] | None = None,
                 load: Callable[[object], None] | None = None,
                 orient: Callable[[PETSc.Vec], int] | None = None):
        self.solver = solver
        self._set = set_parameter
        self._check = check_step
        self._accept, self._save, self._load = accept, save, load
        self._orient = orient
        self.affine = affine
        self.step = step
        self.metric = metric
        self.value = float(parameter)
        self.snes_solver = _snes_solver(solver)
        self.nonlinear = self.snes_solver.problem
        self.w = self.nonlinear.w
        self.comm = self.w.function_space.mesh.comm

    @property
    def state_vector(self) -> PETSc.Vec:
        return compat.vector_of(self.w)

    @property
    def state_array(self) -> np.ndarray:
        return compat.local_array(self.w)

    def set_parameter(self, value: float) -> None:
        self.value = float(value)
        self._set(value)

    def check_step(self, previous, current):
        return None if self._check is None else self._check(previous, current)

    def accept_state(self) -> None:
        """The engine accepted the current point."""
        if getattr(self, "_accept", None) is not None:
            self._accept()

    def save_state(self):
        """The problem's state beside x (None without one)."""
        return None if getattr(self, "_save", None) is None else self._save()

    def orient_tangent(self, tangent: PETSc.Vec) -> int:
        """-1: the new point's unit tangent (its x part ``tangent``) must be reversed, +1:
        kept, 0: no opinion (then it continues the predictor's direction). E.g. at a point
        where the rod came into contact, the direction that presses on (the path turns at a
        contact corner: `fe_beam.fem.contact.ContactSet.orientation`)."""
        orient = getattr(self, "_orient", None)
        return 0 if orient is None else int(orient(tangent))

    def load_state(self, saved) -> None:
        if getattr(self, "_load", None) is not None and saved is not None:
            self._load(saved)

    def residual(self, x, b):
        self.nonlinear.residual(None, x, b)

    def jacobian(self, x):
        A = self.nonlinear.A
        self.nonlinear.jacobian(None, x, A, A)
        return A

    @property
    def ksp(self):
        return self.snes_solver.snes.getKSP()

    def parameter_derivative(self, x, out):
        value = self.value
        other = out.duplicate()
        try:
            if self.affine:  # exact for any polynomial of degree <= 2 in the parameter
                high, low, scale = value + 0.5, value - 0.5, 1.0
            else:
                h = self.step * max(1.0, abs(value))
                high, low, scale = value + h, value - h, 1.0 / (2 * h)
            self._set(high)
            self.residual(x, out)
            self._set(low)
            self.residual(x, other)
            out.axpy(-1.0, other)
            out.scale(scale)
        finally:
            self._set(value)
            other.destroy()


class CallbackProblem(NonlinearParameterProblem):
    """The load-control-only problem of ``run_load_stepping(solver, set_load_factor, ...)``: any
    object with ``solve()``, ``linear_iterations`` and ``problem.w`` will do."""

    def __init__(self, solver, set_parameter, check_step=None):
        self.solver = solver
        self._set = set_parameter
        self._check = check_step
        self.affine, self.step, self.metric, self.value = True, 1e-6, None, 0.0
        self.w = solver.problem.w
        self.comm = self.w.function_space.mesh.comm
        try:
            self.snes_solver = _snes_solver(solver)
            self.nonlinear = self.snes_solver.problem
        except AttributeError:
            self.snes_solver = self.nonlinear = None
        self.arc_length_ready = self.nonlinear is not None


def _difficulty(solver, iterations: int) -> int:
    """The Newton iterations that judge a step easy or hard: those of the hardest solve at
    fixed contact multipliers when the solver wraps contact (`ContactSolver.hardest_solve`),
    else all of them."""
    hardest = getattr(solver, "hardest_solve", None)
    return iterations if hardest is None else hardest


def _snes_solver(solver):
    """The SNESSolver inside ``solver`` (itself, or its ``.solver`` / ``.inner``)."""
    seen = solver
    for _ in range(4):
        if hasattr(seen, "snes") and hasattr(seen, "problem") and hasattr(seen.snes, "getKSP"):
            return seen
        seen = getattr(seen, "solver", None) or getattr(seen, "inner", None)
        if seen is None:
            break
    raise AttributeError(f"no SNESSolver in {type(solver).__name__}")


# --- the bordered solve ---------------------------------------------------------------------------


def bordered_solve(ksp: PETSc.KSP, rhs: PETSc.Vec, columns: Sequence[PETSc.Vec],
                   rows: Sequence[PETSc.Vec], corner, rhs_extra, out: PETSc.Vec,
                   responses: Sequence[PETSc.Vec] | None = None) -> np.ndarray:
    """Solve the bordered system

        [ K    C ] [x]   [f]
        [ D^T  E ] [y] = [h],   C = [c_1 .. c_m], D = [d_1 .. d_m], E (m x m),

    with m + 1 solves of K through ``ksp`` (its operator set by the caller): K z = f,
    K Z = C, then the m x m Schur system (E - D^T Z) y = h - D^T z and x = z - Z y.
    Returns y; x goes into ``out``. ``responses`` (m vectors), if given, receive Z = K^-1 C
    (e.g. the tangent). Raises `fe_beam.solvers.newton.SolveFailed` when a solve or the Schur system
    fails (K or the bordered matrix singular). Collective; K's Dirichlet rows must be
    identity rows with zero entries in ``columns``' Dirichlet rows when x's are prescribed.
    """
    m = len(columns)
    corner = np.atleast_2d(np.asarray(corner, dtype=float)).reshape(m, m)
    rhs_extra = np.atleast_1d(np.asarray(rhs_extra, dtype=float)).reshape(m)
    own = responses is None
    Z = [rhs.duplicate() for _ in range(m)] if own else list(responses)
    try:
        _ksp_solve(ksp, rhs, out)
        for c, z in zip(columns, Z, strict=True):
            _ksp_solve(ksp, c, z)
        schur = corner - np.array([[d.dot(z) for z in Z] for d in rows]).reshape(m, m)
        reduced = rhs_extra - np.array([d.dot(out) for d in rows])
        try:
            y = np.linalg.solve(schur, reduced)
        except np.linalg.LinAlgError:
            raise SolveFailed("bordered system singular (Schur complement)") from None
        if not np.all(np.isfinite(y)):
            raise SolveFailed("bordered system singular (Schur complement)")
        for z, value in zip(Z, y, strict=True):
            out.axpy(-float(value), z)
        return y
    finally:
        if own:
            for z in Z:
                z.destroy()


def _ksp_solve(ksp, b, x) -> None:
    try:
        ksp.solve(b, x)
    except PETSc.Error as error:
        raise SolveFailed(f"PETSc error {error.ierr} in a linear solve") from None
    if ksp.getConvergedReason() < 0:
        raise SolveFailed(f"linear solve diverged (KSP reason {ksp.getConvergedReason()})")


# --- constraints with global unknowns: pull-in control ------------------------------------------


class BorderedConstraintSolver:
    """Fixed-parameter Newton on the state x and m global unknowns tau (tendon tensions) with
    m scalar constraints c(x) = l(x) - target = 0 (pull-in control), all in one Newton system:

        [ K    dR/dtau ] [dx  ]     [ R(x, tau) ]
        [ G^T  0       ] [dtau] = - [ c(x)      ],   G = dc/dx = dl/dx,

    each iteration one `bordered_solve` (m + 1 solves of K through the SNES's KSP). dR/dtau is
    the unit-width central difference of the residual in each tau_j (exact: the residual is
    linear in a tension, its Dirichlet lifting at most quadratic). Same interface as
    `fe_beam.solvers.newton.SNESSolver` (``solve()``, ``linear_iterations``, ``residual_norm()``,
    ``set_reference_residual()``, ``problem``, ``snes``, ``destroy()``), so load stepping and
    time stepping drive it unchanged.

    Callbacks: ``get_tensions() -> array``, ``set_tensions(array)``, ``lengths(x) -> array``,
    ``gradients(x) -> list of Vec`` (dl_i/dx, Dirichlet rows zeroed), ``targets() -> array``.
    Converged when |c_i| <= ``length_tolerance`` and ||R|| meets the SNES settings' rtol
    against max(||R|| at the start, ||sum_j tau_j dR/dtau_j|| of the iterate) (or their step
    and round-off tests); ``nonnegative``: tensions are clipped at 0 after each update (a
    cable cannot push); ``unloaded()`` (optional) True means the equilibrium is x = 0 (set, no
    iterations).
    Raises `fe_beam.solvers.newton.SolveFailed` with the start (x, tau) restored.
    """

    def __init__(self, solver, get_tensions, set_tensions, lengths, gradients, targets,
                 length_tolerance: float, max_it: int | None = None,
                 nonnegative: bool = False, unloaded=None, name: str = "pull-in control"):
        self.solver = solver
        self.inner = solver
        self.snes = solver.snes
        self.problem = solver.problem
        self.get_tensions, self.set_tensions = get_tensions, set_tensions
        self.lengths, self.gradients, self.targets = lengths, gradients, targets
        self.length_tolerance = float(length_tolerance)
        settings = getattr(solver, "settings", None)
        self.max_it = max_it or getattr(settings, "max_it", 25)
        self.rtol = getattr(settings, "rtol", 1e-9)
        self.stol = getattr(settings, "stol", 1e-11)
        self.atol = getattr(settings, "atol", 1e-300)
        self.nonnegative = nonnegative
        self.unloaded = unloaded
        self.name = name
        self.linear_iterations = 0
        self._reference: float | None = None
        self._largest = 0.0

    def residual_norm(self) -> float:
        return self.solver.residual_norm()

    def set_reference_residual(self, value: float | None) -> None:
        self._reference = value

    def destroy(self) -> None:
        self.solver.destroy()

    def _tension_columns(self, x, tensions) -> list:
        columns = []
        b = x.duplicate()
        try:
            for j in range(len(tensions)):
                column = x.duplicate()
                for shift, target in ((0.5, column), (-0.5, b)):
                    trial = np.array(tensions, dtype=float)
                    trial[j] += shift
                    self.set_tensions(trial)
                    self.problem.residual(None, x, target)
                column.axpy(-1.0, b)
                columns.append(column)
        finally:
            self.set_tensions(tensions)
            b.destroy()
        return columns

    def solve(self) -> int:
        problem = self.problem
        x = compat.vector_of(problem.w)
        start_x = x.copy()
        start_tau = np.array(self.get_tensions(), dtype=float)
        reference, self._reference = self._reference, None
        try:
            return self._solve(x, reference)
        except (SolveFailed, np.linalg.LinAlgError) as error:
            start_x.copy(x)
            _ghost_update(x)
            self.set_tensions(start_tau)
            raise SolveFailed(f"{self.name}: {error}") from None
        finally:
            start_x.destroy()

    def _solve(self, x, reference) -> int:
        problem = self.problem
        if self.unloaded is not None and self.unloaded():
            x.set(0.0)
            _ghost_update(x)
            return 0
        b = x.duplicate()
        dx = x.duplicate()
        previous, step_norm, linear = None, math.inf, 0
        try:
            for iteration in range(self.max_it + 1):
                tensions = np.array(self.get_tensions(), dtype=float)
                problem.residual(None, x, b)
                fnorm = b.norm()
                if not math.isfinite(fnorm):
                    raise SolveFailed("residual not a number")
                mismatch = np.asarray(self.lengths(x), dtype=float) - self.targets()
                columns = self._tension_columns(x, tensions)
                try:
                    # the tendon forces sum_j tau_j dR/dtau_j: the load scale of the residual
                    load = x.duplicate()
                    load.set(0.0)
                    for tau, column in zip(tensions, columns, strict=True):
                        load.axpy(tau, column)
                    scale = load.norm()
                    load.destroy()
                    if iteration == 0:
                        initial = fnorm if reference is None else min(fnorm, reference)
                    measure = max(initial, scale)
                    self._largest = max(self._largest, measure)
                    constrained = bool(np.all(np.abs(mismatch) <= self.length_tolerance))
                    if iteration > 0 and constrained and (
                            fnorm <= self.atol or fnorm <= self.rtol * measure
                            or (iteration >= 2 and fnorm > 0.5 * previous
                                and fnorm <= STAGNATION_RTOL * self._largest)
                            or step_norm <= self.stol * max(x.norm(),
                                                            getattr(self.solver, "state_scale",
                                                                    0.0))):
                        self.linear_iterations = linear
                        return iteration
                    if iteration == self.max_it:
                        break
                    previous = fnorm
                    A = problem.A
                    problem.jacobian(None, x, A, A)
                    ksp = self.snes.getKSP()
                    ksp.setOperators(A)
                    rows = self.gradients(x)
                    try:
                        b.scale(-1.0)
                        m = len(columns)
                        change = bordered_solve(ksp, b, columns, rows, np.zeros((m, m)),
                                                -mismatch, dx)
                    finally:
                        for row in rows:
                            row.destroy()
                    linear += (m + 1) * max(1, ksp.getIterationNumber())
                finally:
                    for column in columns:
                        column.destroy()
                step_norm = dx.norm()
                x.axpy(1.0, dx)
                _ghost_update(x)
                tensions = tensions + change
                if self.nonnegative:
                    tensions = np.maximum(tensions, 0.0)
                self.set_tensions(tensions)
            raise SolveFailed(f"no convergence in {self.max_it} Newton iterations")
        finally:
            b.destroy()
            dx.destroy()


# --- the engine ---------------------------------------------------------------------------------


class Continuation:
    """Path following on a `ParameterProblem` from its current (converged) state.

    ``parameter``: the parameter value of the current state. ``on_step(point)``: called after
    every accepted point of any strategy (load control, `arc_length_path`, `step`, `solve_at`)
    with a `ContinuationPoint` (collective).
    """

    def __init__(self, problem: ParameterProblem, parameter: float = 0.0,
                 on_step: Callable[[ContinuationPoint], None] | None = None):
        self.problem = problem
        self.parameter = float(parameter)
        self.on_step = on_step
        self.comm = problem.comm
        self._tangent: tuple[PETSc.Vec, float] | None = None  # unit tangent at the state
        self._direction: tuple[PETSc.Vec, float] | None = None  # forced next predictor
        self.arc_length: float | None = None  # the next adaptive step's length
        self.psi: float | None = None
        self._count = 0

    # --- state ------------------------------------------------------------------------------
    @property
    def state(self) -> np.ndarray:
        """Writable local dofs (owned + ghosts) of the problem's state."""
        return self.problem.state_array

    def snapshot(self) -> Snapshot:
        """Copy of (state, parameter, tangent, next arc length)."""
        tangent = None
        if self._tangent is not None:
            tangent = (self._tangent[0].getArray().copy(), self._tangent[1])
        save = getattr(self.problem, "save_state", None)
        return Snapshot(self.state.copy(), self.parameter, tangent, self.arc_length,
                        None if save is None else save())

    def restore(self, snapshot: Snapshot) -> None:
        """Back to a snapshot (state, parameter applied to the problem, tangent)."""
        self.state[:] = snapshot.state
        self.parameter = snapshot.parameter
        self.problem.set_parameter(snapshot.parameter)
        load = getattr(self.problem, "load_state", None)
        if load is not None:
            load(snapshot.extra)
        self.arc_length = snapshot.arc_length
        if snapshot.tangent is None:
            self._tangent = None
        else:
            vector = self._new_vector()
            vector.getArray()[:] = snapshot.tangent[0]
            self._tangent = (vector, snapshot.tangent[1])

    def set_predictor_direction(self, vector, parameter: float = 0.0) -> None:
        """The next arc-length step (`step` / `arc_length`) predicts along (vector, parameter)
        (normalised in the arc metric) instead of the tangent, e.g. a critical mode for branch
        switching; its Riks plane is normal to that direction. ``vector``: a PETSc Vec of the
        state's layout or the owned part of the state as an array."""
        direction = self._new_vector()
        if isinstance(vector, PETSc.Vec):
            vector.copy(direction)
        else:
            direction.getArray()[:] = np.asarray(vector, dtype=float)[: direction.getLocalSize()]
        self._ensure_psi()
        norm = math.sqrt(self._dot(direction, direction) + self.psi**2 * parameter**2)
        if norm == 0:
            raise ValueError("set_predictor_direction: zero direction")
        direction.scale(1.0 / norm)
        self._direction = (direction, parameter / norm)

    # --- load control (and displacement control) ---------------------------------------------
    def load_control(self, target: float, stepping: LoadStepping | None = None,
                     on_converged: Callable[[ContinuationPoint], None] | None = None,
                     progress: bool = False, label: str = "load") -> list[ContinuationPoint]:
        """Step the parameter from its current value to ``target``: ``stepping.steps`` equal
        fractions of the way to start with, secant predictor, a failed or vetoed step retried
        ``cut_factor`` shorter, easy steps grown (`fe_beam.solvers.newton.LoadStepping`). Each step
        calls ``on_converged(point)`` then ``on_step(point)``. Raises `ContinuationFailed` with
        the last converged state restored (message as the former ``run_load_stepping``'s,
        in fractions of the way)."""
        stepping = stepping or LoadStepping()
        problem, solver = self.problem, self.problem.solver
        start = self.parameter
        span = float(target) - start

        def value(fraction: float) -> float:
            return start + fraction * span

        state = self.state
        results: list[ContinuationPoint] = []
        lam, increment = 0.0, 1.0 / stepping.steps
        previous = state.copy()
        before_previous, previous_increment = None, None
        # the bar counts load steps (the configured ones: "2/4"; a cut-back step shows its
        # fraction of one), not the fraction of the way ("0/1" for any number of steps)
        bar = ProgressBar(self.comm, total=stepping.steps, label=label, enabled=progress,
                          unit="step")
        failures: list[str] = []  # why the tries since the last converged step failed
        size = _StepSize(increment, stepping.min_increment, stepping.max_increment,
                         stepping.cut_factor, stepping.grow_factor, stepping.easy_iterations,
                         stepping.adaptive)
        self._tangent = None
        # steps that may grow beyond the first increment could jump past a limit point onto
        # another branch and still converge: checked against the secant predictor
        # (only steps longer than the first increment: shorter ones are what load control
        # without growth takes, and a state that barely moved would make every step's
        # deviation look large)
        first = increment
        guarded = stepping.adaptive and size.largest > increment * (1 + 1e-9)
        try:
            while lam < 1.0 - 1e-12:
                increment = size.value = min(size.value, 1.0 - lam)
                # Summed increments drift (0.1 * 10 != 1.0): the last step lands exactly on 1.
                target_fraction = 1.0 if lam + increment >= 1.0 - 1e-12 else lam + increment
                problem.set_parameter(value(target_fraction))
                if before_previous is not None:
                    # the residual of the plain load increment, before the predictor moves x
                    reference = getattr(solver, "set_reference_residual", None)
                    if reference is not None:
                        reference(solver.residual_norm())
                    state[:] = previous + (increment / previous_increment) * (
                        previous - before_previous
                    )
                started = time.perf_counter()
                failure = None
                try:
                    iterations = solver.solve()
                except SolveFailed as error:
                    failure = str(error)
                if failure is None:
                    failure = _agreed(self.comm, problem.check_step(previous, state))
                jumped = False
                if (failure is None and guarded and before_previous is not None
                        and increment > first * (1 + 1e-9)):
                    failure = self._branch_jump(before_previous, previous, state,
                                                increment / previous_increment)
                    jumped = failure is not None
                if failure is not None:
                    state[:] = previous
                    problem.set_parameter(value(lam))
                    failures.append(failure)
                    kind = size.cut()
                    if jumped and kind is None:
                        # a vetoed grown step is retried no shorter than the first increment
                        # (what load control without growth takes; never vetoed again)
                        size.value = max(size.value, first)
                    if kind is not None:
                        reason = _failure_reasons(failures)
                        raise ContinuationFailed(
                            f"load stepping stopped at load factor {target_fraction:.6g} "
                            f"({reason}); last converged load factor {lam:.6g}",
                            lam, results, reason=reason, kind=kind,
                            parameter=value(lam), attempted=value(target_fraction))
                    bar.note(f"cut back to increment {size.value:.3g} ({failure})")
                    continue
                failures.clear()
                before_previous, previous_increment = previous, increment
                previous = state.copy()
                lam = target_fraction
                self.parameter = value(lam)
                self._accept_state()
                point = ContinuationPoint(
                    len(results) + 1, self.parameter, iterations, solver.linear_iterations,
                    time.perf_counter() - started, fraction=lam, state=previous.copy())
                results.append(point)
                if on_converged is not None:
                    on_converged(point)
                self._emit(point)
                bar.update(lam * stepping.steps,
                           f"{label} factor {lam:.4f}, {iterations} Newton its")
                size.converged(_difficulty(solver, iterations))
        finally:
            bar.close()
        return results

    def _branch_jump(self, before_previous: np.ndarray, previous: np.ndarray,
                     current: np.ndarray, ratio: float) -> str | None:
        """Veto (reason) of a converged load step that left the path: its change of state
        deviates from the secant predictor ratio (previous - before_previous) by more than
        `BRANCH_JUMP` times the predictor's size (in the arc metric; owned entries). On a
        smooth path the deviation is O(increment) of the predictor (it vanishes for a linear
        problem); a state that jumped past a limit point onto another branch deviates by far
        more. No verdict after a step that did not move the state (nothing to compare with:
        e.g. a slack tendon's first steps)."""
        n = self.problem.state_vector.getLocalSize()
        metric = self.problem.metric
        weights = 1.0 if metric is None else metric.getArray(readonly=True)[:n]
        predicted = ratio * (previous[:n] - before_previous[:n])
        deviation = current[:n] - previous[:n] - predicted
        sums = np.array([np.sum(weights * predicted**2), np.sum(weights * deviation**2),
                         np.sum(weights * previous[:n] ** 2)])
        sums = self.comm.allreduce(sums, op=MPI.SUM)
        predicted_norm, deviation_norm, state_norm = np.sqrt(sums)
        if not predicted_norm > 1e-12 * state_norm or predicted_norm == 0:
            return None
        if deviation_norm > BRANCH_JUMP * predicted_norm:
            return (f"branch jump: the step's change of state deviates from the secant "
                    f"predictor by {deviation_norm / predicted_norm:.3g} times its size "
                    f"(> {BRANCH_JUMP:g})")
        return None

    # --- fixed parameter ----------------------------------------------------------------------
    def solve_at(self, parameter: float, snapshot: Snapshot | None = None,
                 predictor: bool = True, emit: bool = True) -> ContinuationPoint:
        """Equilibrium at a fixed parameter by the problem's Newton, from ``snapshot`` (or the
        current state); with ``predictor`` and a tangent with dlambda != 0 the start is moved
        along it. On success the engine is at the new point (tangent recomputed when the
        problem supports it); raises `ContinuationFailed` (kind "step") with the start restored.
        """
        if snapshot is not None:
            self.restore(snapshot)
        start = self.snapshot()
        started = time.perf_counter()
        if predictor and self._tangent is not None and self._tangent[1] != 0:
            t, t_lam = self._tangent
            shift = (parameter - self.parameter) / t_lam
            self._axpy_state(shift, t)
        self.problem.set_parameter(parameter)
        try:
            iterations = self.problem.solver.solve()
        except SolveFailed as error:
            self.restore(start)
            raise ContinuationFailed(
                f"no equilibrium at parameter {parameter:.6g} ({error})", start.parameter, [],
                reason=str(error), kind="step", parameter=start.parameter,
                attempted=parameter) from None
        self.parameter = float(parameter)
        old = self._tangent
        if _has_arc_interface(self.problem):
            self._tangent = self._unit_tangent(old)
        return self._accept(iterations, started, 0.0, emit)

    # --- arc length -------------------------------------------------------------------------
    def prepare_arc_length(self, settings: ArcLength) -> None:
        """Tangent at the current state (sign: ``settings.direction`` on dlambda, or the old
        tangent's), psi and the first arc length (unless already set). Called by
        `arc_length`; call it before the first `step` of a fresh engine."""
        if not _has_arc_interface(self.problem):
            raise ValueError(f"{type(self.problem).__name__}: arc-length needs the residual, "
                             "Jacobian and parameter derivative (not available here, e.g. under "
                             "pull-in control)")
        self._settings = settings
        if self._tangent is None:
            self._tangent = self._unit_tangent(None, settings.direction,
                                               psi_from=settings.psi)
        else:
            self._ensure_psi(settings.psi)
        if self.arc_length is None:
            t_lam = abs(self._tangent[1])
            self.arc_length = settings.increment / max(t_lam, 1e-300) if t_lam > 0 else \
                settings.increment
            self._first_arc = self.arc_length

    def step(self, size: float, settings: ArcLength | None = None,
             emit: bool = True) -> ContinuationPoint:
        """One arc-length step of length ``size`` from the current state (no adaptation, no
        retry): tangent predictor (or the direction of `set_predictor_direction`), then the
        bordered Newton corrector. On success the engine is at the new point with its tangent
        oriented along the path; raises `ContinuationFailed` (kind "step") with the start
        restored."""
        settings = settings or getattr(self, "_settings", None) or ArcLength()
        if self._tangent is None or self.psi is None:
            self.prepare_arc_length(settings)
        start = self.snapshot()
        started = time.perf_counter()
        direction = self._direction or self._tangent
        try:
            iterations = self._wrapped_corrector(direction, size, settings, start)
            reason = _agreed(self.comm, self.problem.check_step(start.state, self.state))
            if reason is None and _wrapped(self.problem):
                reason = self._left_the_step(start, size)
            if reason is not None:
                raise SolveFailed(reason)
        except SolveFailed as error:
            attempted = self.parameter
            self.restore(start)
            raise ContinuationFailed(
                f"arc-length step of {size:.3g} from parameter {start.parameter:.6g} failed "
                f"({error})", start.parameter, [], reason=str(error), kind="step",
                parameter=start.parameter, attempted=attempted) from None
        reference = direction
        self._direction = None
        self._tangent = self._unit_tangent(reference)
        orient = getattr(self.problem, "orient_tangent", None)
        if orient is not None and orient(self._tangent[0]) < 0:
            # a corner of the path (e.g. contact began): the problem knows the way on
            self._tangent[0].scale(-1.0)
            self._tangent = (self._tangent[0], -self._tangent[1])
        return self._accept(iterations, started, size, emit)

    def arc_length_path(self, settings: ArcLength | None = None,
                        on_converged: Callable[[ContinuationPoint], None] | None = None,
                        progress: bool = False, label: str = "arc length"
                        ) -> list[ContinuationPoint]:
        """Follow the path by arc-length steps until ``max_steps`` or |lambda| beyond
        ``max_load_factor`` (or below ``min_load_factor``); adaptive length (grow on easy
        steps, cut back on failures: `step` does one try). Returns the points; raises
        `ContinuationFailed` (kind "step_too_small" or "not_adaptive", last point restored)
        when the length falls below ``min_arc_length``."""
        settings = settings or ArcLength()
        self.prepare_arc_length(settings)
        first = getattr(self, "_first_arc", self.arc_length)
        size = _StepSize(self.arc_length, settings.min_arc_length or 1e-5 * first,
                         settings.max_arc_length or 10 * first, settings.cut_factor,
                         settings.grow_factor, settings.easy_iterations, settings.adaptive)
        points: list[ContinuationPoint] = []
        failures: list[str] = []
        bar = ProgressBar(self.comm, total=settings.max_steps, label=label, enabled=progress)
        try:
            while len(points) < settings.max_steps:
                before = self.snapshot()
                try:
                    point = self.step(size.value, settings, emit=False)
                except ContinuationFailed as failure:
                    failures.append(failure.reason)
                    kind = size.cut()
                    if kind is not None:
                        reason = _failure_reasons(failures)
                        raise ContinuationFailed(
                            f"arc length stopped at parameter {self.parameter:.6g} ({reason})",
                            self.parameter, points, reason=reason, kind=kind,
                            parameter=self.parameter, attempted=failure.attempted) from None
                    bar.note(f"cut back to arc length {size.value:.3g} ({failure.reason})")
                    continue
                failures.clear()
                size.converged(_difficulty(self.problem.solver, point.iterations))
                self.arc_length = size.value
                beyond = (point.load_factor > settings.max_load_factor
                          or point.load_factor < settings.min_load_factor)
                if beyond:
                    point = self._land(before, point, settings)
                    self.arc_length = size.value
                points.append(point)
                if on_converged is not None:
                    on_converged(point)
                self._emit(point)
                bar.update(len(points), f"parameter {point.load_factor:.4g}, "
                           f"{point.iterations} Newton its")
                if beyond:
                    break
        finally:
            bar.close()
        return points

    # alias: the strategy's name
    arc_length_control = arc_length_path

    # --- internals --------------------------------------------------------------------------
    def _land(self, before: Snapshot, point: ContinuationPoint, settings: ArcLength):
        """Move a point that crossed the parameter bound onto it (fixed-parameter solve from the
        point before, along its tangent) when the tangent there is not at a limit point."""
        bound = settings.max_load_factor if point.load_factor > settings.max_load_factor \
            else settings.min_load_factor
        if before.tangent is None or before.tangent[1] == 0 or not math.isfinite(bound):
            return point
        reached = self.snapshot()
        try:
            landed = self.solve_at(bound, before, emit=False)
        except ContinuationFailed:
            self.restore(reached)
            return point
        self._count -= 1  # the landed point replaces the crossing one
        landed.index = point.index
        landed.arc_length = point.arc_length
        return landed

    def _accept_state(self) -> None:
        accept = getattr(self.problem, "accept_state", None)
        if accept is not None:
            accept()

    def _accept(self, iterations: int, started: float, size: float,
                emit: bool = True) -> ContinuationPoint:
        self._accept_state()
        self._count += 1
        t_lam = None if self._tangent is None else self._tangent[1]
        point = ContinuationPoint(self._count, self.parameter, iterations,
                                  getattr(self.problem.solver, "linear_iterations", 0),
                                  time.perf_counter() - started, arc_length=size,
                                  tangent_parameter=t_lam, state=self.state.copy())
        if emit:
            self._emit(point)
        return point

    def _emit(self, point: ContinuationPoint) -> None:
        if self.on_step is not None:
            self.on_step(point)

    def _new_vector(self) -> PETSc.Vec:
        return self.problem.state_vector.duplicate()

    def _dot(self, a: PETSc.Vec, b: PETSc.Vec) -> float:
        metric = self.problem.metric
        if metric is None:
            return a.dot(b)
        weighted = a.copy()
        weighted.pointwiseMult(weighted, metric)
        try:
            return weighted.dot(b)
        finally:
            weighted.destroy()

    def _weighted(self, a: PETSc.Vec) -> PETSc.Vec:
        weighted = a.copy()
        if self.problem.metric is not None:
            weighted.pointwiseMult(weighted, self.problem.metric)
        return weighted

    def _axpy_state(self, alpha: float, vector: PETSc.Vec) -> None:
        x = self.problem.state_vector
        x.axpy(alpha, vector)
        _ghost_update(x)

    def _ensure_psi(self, psi: float | None = None) -> None:
        if self.psi is None:
            self.psi = 1.0 if psi is None else float(psi)

    def _unit_tangent(self, reference, direction: int = 1, psi_from: float | None = None):
        """Unit tangent (t, t_lambda) at the current state: K t = -dR/dlambda t_lambda,
        normalised in the arc metric; its sign makes the inner product with ``reference``
        positive (or t_lambda's sign ``direction`` without one)."""
        problem = self.problem
        x = problem.state_vector
        derivative = self._new_vector()
        t = self._new_vector()
        try:
            problem.parameter_derivative(x, derivative)
            A = problem.jacobian(x)
            ksp = problem.ksp
            ksp.setOperators(A)
            _ksp_solve(ksp, derivative, t)
        finally:
            derivative.destroy()
        t.scale(-1.0)
        if self.psi is None:
            if psi_from is not None:
                self.psi = float(psi_from)
            else:
                norm = math.sqrt(self._dot(t, t))
                self.psi = norm if norm > 0 else 1.0
        norm = math.sqrt(self._dot(t, t) + self.psi**2)
        t.scale(1.0 / norm)
        t_lam = 1.0 / norm
        if reference is not None:
            sign = self._dot(t, reference[0]) + self.psi**2 * t_lam * reference[1]
        else:
            sign = direction * t_lam
        if sign < 0:
            t.scale(-1.0)
            t_lam = -t_lam
        return t, t_lam

    def _left_the_step(self, start: Snapshot, size: float) -> str | None:
        """Veto of a wrapped corrector's point farther than `WRAPPED_REACH` arc lengths from
        the start (arc metric): the wrapper's updates (e.g. contact that stops the path) change
        the equations under a fixed Riks plane, which may then meet the path again far away
        (e.g. back on the branch the step came along)."""
        n = self.problem.state_vector.getLocalSize()
        metric = self.problem.metric
        weights = 1.0 if metric is None else metric.getArray(readonly=True)[:n]
        change = self.state[:n] - start.state[:n]
        squared = self.comm.allreduce(float(np.sum(weights * change**2)), op=MPI.SUM)
        distance = math.sqrt(squared + self.psi**2 * (self.parameter - start.parameter) ** 2)
        if distance > WRAPPED_REACH * size:
            return (f"arc length: the corrector ended {distance / size:.3g} arc lengths from the "
                    f"step's start (more than {WRAPPED_REACH:g}: it left the step)")
        return None

    def _wrapped_corrector(self, direction, size: float, settings: ArcLength,
                           start: Snapshot) -> int:
        """The corrector, inside the problem's solver wrapper when it has one (``solve_with``:
        e.g. `fe_beam.solvers.contact.ContactSolver`, whose active-set and Uzawa updates then
        wrap the corrector as they wrap Newton under load control): the first call predicts
        from the start, every later one corrects again from the current iterate on the same
        arc constraint (x_n, lambda_n of ``start``) at the wrapper's updated active set and
        multipliers."""
        wrapper = getattr(getattr(self.problem, "solver", None), "solve_with", None)
        if wrapper is None:
            return self._corrector(direction, size, settings)
        calls = []

        def corrector() -> int:
            origin = start if calls else None
            calls.append(1)
            return self._corrector(direction, size, settings, origin)

        return wrapper(corrector)

    def _corrector(self, direction, size: float, settings: ArcLength,
                   origin: Snapshot | None = None) -> int:
        """Predictor x_n + size t, lambda_n + size t_lambda, then Newton on
        R(x, lambda) = 0 and the arc constraint, each iteration one `bordered_solve`.
        ``origin``: (x_n, lambda_n) of the constraint when the corrector starts again from
        the current iterate (no predictor); None: they are the current state."""
        problem = self.problem
        t, t_lam = direction
        psi2 = self.psi**2
        x = problem.state_vector
        x0 = x.copy()
        lam0 = self.parameter
        if origin is not None:
            x0.getArray()[:] = origin.state[: x0.getLocalSize()]
            lam0 = origin.parameter
        solver = getattr(problem, "snes_solver", None)
        snes_settings = getattr(solver, "settings", None)
        rtol = getattr(snes_settings, "rtol", 1e-9)
        stol = getattr(snes_settings, "stol", 1e-11)
        atol = getattr(snes_settings, "atol", 1e-300)
        max_it = settings.max_it or getattr(snes_settings, "max_it", 25)
        scale = getattr(solver, "state_scale", 0.0)
        b = self._new_vector()
        derivative = self._new_vector()
        dx = self._new_vector()
        row = self._weighted(t)
        delta = self._new_vector()
        try:
            if origin is None:
                self._axpy_state(size, t)
                lam = lam0 + size * t_lam
            else:
                lam = self.parameter
            self.parameter = lam
            problem.set_parameter(lam)
            problem.parameter_derivative(x, derivative)
            reference = abs(size * t_lam) * derivative.norm()
            largest, previous, step_norm = 0.0, None, math.inf
            for iteration in range(max_it + 1):
                problem.residual(x, b)
                fnorm = b.norm()
                if not math.isfinite(fnorm):
                    raise SolveFailed("arc-length corrector: residual not a number")
                x.copy(delta)
                delta.axpy(-1.0, x0)
                if settings.constraint == "riks":
                    constraint = row.dot(delta) + psi2 * t_lam * (lam - lam0) - size
                    crow, corner = row, psi2 * t_lam
                else:
                    wdelta = self._weighted(delta)
                    constraint = 0.5 * (wdelta.dot(delta) + psi2 * (lam - lam0) ** 2 - size**2)
                    crow, corner = wdelta, psi2 * (lam - lam0)
                if iteration == 0:
                    reference = reference if reference > 0 else fnorm
                    largest = max(fnorm, reference)
                small_constraint = abs(constraint) <= 1e-8 * max(size, 1e-300) * (
                    size if settings.constraint == "crisfield" else 1.0)
                if iteration > 0 and small_constraint and (
                        fnorm <= atol or fnorm <= rtol * reference
                        or (iteration >= 2 and previous is not None and fnorm > 0.5 * previous
                            and fnorm <= STAGNATION_RTOL * largest)
                        or step_norm <= stol * max(x.norm(), scale)):
                    return iteration
                if iteration == max_it:
                    break
                previous = fnorm
                if iteration > 0:
                    problem.parameter_derivative(x, derivative)
                A = problem.jacobian(x)
                ksp = problem.ksp
                ksp.setOperators(A)
                b.scale(-1.0)
                y = bordered_solve(ksp, b, [derivative], [crow], [[corner]], [-constraint], dx)
                if crow is not row:
                    crow.destroy()
                step_norm = dx.norm()
                self._axpy_state(1.0, dx)
                lam += float(y[0])
                self.parameter = lam
                problem.set_parameter(lam)
            raise SolveFailed(f"arc-length corrector did not converge in {max_it} iterations")
        finally:
            for vector in (b, derivative, dx, row, delta, x0):
                vector.destroy()


def _ghost_update(x: PETSc.Vec) -> None:
    if x.getType() != PETSc.Vec.Type.SEQ:
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)


#: a wrapped corrector's point (`Continuation._wrapped_corrector`: e.g. with contact) farther
#: than this many arc lengths from the step's start is rejected (cut back)
WRAPPED_REACH = 2.0


def _wrapped(problem) -> bool:
    return getattr(getattr(problem, "solver", None), "solve_with", None) is not None


def _has_arc_interface(problem) -> bool:
    return getattr(problem, "arc_length_ready", True) and hasattr(
        problem, "parameter_derivative")


#: a grown load step whose change of state deviates from the secant predictor by more than
#: this multiple of the predictor (arc metric) is taken for a jump to another branch and cut
#: back (`Continuation.load_control`, only when steps may grow beyond the first increment)
BRANCH_JUMP = 1.0


class _StepSize:
    """Step-size adaptation, one place for load control and arc length: ``cut()`` after a
    failed try (returns the failure kind when no smaller try is allowed, else None),
    ``converged(iterations)`` after an accepted one (grows after easy steps)."""

    def __init__(self, value, smallest, largest, cut_factor, grow_factor, easy, adaptive):
        self.value = float(value)
        self.smallest, self.largest = smallest, largest
        self.cut_factor, self.grow_factor, self.easy = cut_factor, grow_factor, easy
        self.adaptive = adaptive

    def cut(self) -> str | None:
        if not self.adaptive:
            return "not_adaptive"
        if self.value * self.cut_factor < self.smallest:
            return "step_too_small"
        self.value *= self.cut_factor
        return None

    def converged(self, iterations: int) -> None:
        if self.adaptive and iterations <= self.easy:
            self.value = min(self.value * self.grow_factor, self.largest)


def _failure_reasons(failures: list[str]) -> str:
    """The last failure, and the other kinds of failure of the larger tries before it (e.g. an
    inadmissible state beyond a step that then no longer converged)."""
    last = failures[-1]
    kinds, earlier = {last.split(":")[0].split("(")[0]}, []
    for reason in reversed(failures[:-1]):
        kind = reason.split(":")[0].split("(")[0]
        if kind not in kinds:
            kinds.add(kind)
            earlier.append(reason)
    return last if not earlier else f"{last}; larger steps: {'; '.join(earlier[:2])}"


def run_load_stepping(
    solver: SNESSolver,
    set_load_factor: Callable[[float], None],
    stepping: LoadStepping | None = None,
    on_converged: Callable[[StepResult], None] | None = None,
    reject_step: Callable[[np.ndarray, np.ndarray], str | None] | None = None,
    progress: bool = True,
    label: str = "load",
) -> list[StepResult]:
    """Ramp the load factor from 0 to 1, solving at each step: load control of
    `fe_beam.solvers.continuation.Continuation` (`Continuation.load_control`) on ``solver`` and
    ``set_load_factor``.

    The first guess of each step is the secant extrapolation of the last two converged states.
    ``reject_step(previous, current)`` (local dof arrays) may veto a converged step, e.g. one that
    jumped to another equilibrium branch; it is then cut back like a diverged step.
    Raises `LoadSteppingFailed` (a `fe_beam.solvers.continuation.ContinuationFailed`, with
    ``reason``;
    the last converged state restored in ``w``) when the increment falls below
    ``stepping.min_increment``.
    """
    engine = Continuation(CallbackProblem(solver, set_load_factor, reject_step), 0.0)
    return engine.load_control(1.0, stepping, on_converged=on_converged, progress=progress,
                               label=label)

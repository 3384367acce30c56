"""Nonlinear solves with PETSc SNES, and load stepping with cut-back.

`NonlinearProblem` holds compiled forms and assembles residual and Jacobian (plus optional non-UFL
contributions such as a 3D tendon cable); `SNESSolver` drives PETSc SNES with a unique options
prefix; `run_load_stepping` ramps a load factor from 0 to 1 with automatic cut-back on divergence,
step growth on easy steps and a branch check. Nothing here writes files.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from fe_beam.errors import (  # noqa: F401  (their home; re-exported)
    ConfigError,
    LoadSteppingFailed,
    SolveFailed,
)
from fe_beam.fem import compat
from fe_beam.model.settings import (  # noqa: F401  (their home; re-exported)
    LINE_SEARCHES,
    LINEAR_SOLVERS,
    SADDLE_POINT_WORKSPACE,
    LoadStepping,
    SolverSettings,
    check_option_names,
)

__all__ = [
    "LoadStepping",
    "LoadSteppingFailed",
    "NonlinearProblem",
    "SNESSolver",
    "SolveFailed",
    "SolverSettings",
    "StepResult",
]

_PETSC_ERRORS = {56: "not supported", 62: "invalid argument", 63: "out of range or not a "
                 "number", 86: "unknown type"}


def check_petsc_options(options: dict, where: str = "solver.petsc_options") -> None:
    """Raise ConfigError (a ValueError) naming the first option PETSc rejects (an unknown solver
    type, a value that is not a number, ...), by configuring a throw-away SNES on this process
    with it. PETSc ignores unknown option names, so misspelt names cannot be detected here.
    Options already accepted are not checked again."""
    try:
        check_option_names(options, where)
    except ValueError as error:
        raise ConfigError(str(error)) from None
    key = (where, tuple(sorted((str(k), repr(v)) for k, v in options.items())))
    if key in _ACCEPTED:
        return
    _check_with_petsc(options, where)
    _ACCEPTED.add(key)


_ACCEPTED: set = set()


def _check_with_petsc(options: dict, where: str) -> None:
    database = PETSc.Options()
    prefix = "fe_beam_option_check_"
    snes = PETSc.SNES().create(PETSc.COMM_SELF)
    snes.setOptionsPrefix(prefix)
    compat.push_quiet_petsc_error_handler()  # the ValueError below says it better than PETSc
    try:
        for key, value in options.items():
            database[prefix + key] = value
            try:
                snes.setFromOptions()
                snes.getKSP().setFromOptions()
            except PETSc.Error as error:
                reason = _PETSC_ERRORS.get(error.ierr, f"PETSc error code {error.ierr}")
                raise ConfigError(
                    f"{where}.{key} = {value!r}: PETSc rejects it ({reason})"
                ) from None
            finally:
                database.delValue(prefix + key)
    finally:
        PETSc.Sys.popErrorHandler()
        snes.destroy()


class Contribution(Protocol):
    """A non-UFL term added to residual and Jacobian (global indices, ADD_VALUES)."""

    def add_to_residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None: ...

    def add_to_jacobian(self, x: PETSc.Vec, A: PETSc.Mat) -> None: ...

    # optional: ``jacobian_couplings() -> list[np.ndarray]``, groups of global indices each
    # coupled all-to-all in the Jacobian (whatever the state and load): `NonlinearProblem` then
    # preallocates them (see `preallocated_matrix`)


class NonlinearProblem:
    """Residual F(w; dw) = 0 with Dirichlet conditions, forms compiled once.

    Parameters
    ----------
    residual : UFL form linear in the test function.
    w : the unknown Function (updated in place by the solver).
    bcs : Dirichlet conditions on w's space.
    jacobian : UFL bilinear form; the Gateaux derivative of ``residual`` when None.
    contributions : non-UFL terms (see `Contribution`).
    """

    def __init__(
        self,
        residual: ufl.Form,
        w: fem.Function,
        bcs: Sequence[compat.DirichletBC] = (),
        jacobian: ufl.Form | None = None,
        contributions: Sequence[Contribution] = (),
        ties: np.ndarray | None = None,
    ):
        """``ties``: (slave, master) pairs of global dof indices (`Ties`): the joints that
        are not shared mesh vertices (fe_beam.fem.structure)."""
        if jacobian is None:
            jacobian = ufl.derivative(residual, w, ufl.TrialFunction(w.function_space))
        self.w = w
        self.bcs = list(bcs)
        self.contributions = list(contributions)
        self.residual_form = fem.form(residual)
        self.jacobian_form = fem.form(jacobian)
        self.b = compat.create_vector(self.residual_form)
        self.A = compat.create_matrix(self.jacobian_form)
        couplings = [group for term in self.contributions
                     for group in getattr(term, "jacobian_couplings", lambda: [])()]
        if couplings:
            # entries outside the form's sparsity pattern (a cable's anchor plate couples a
            # whole face): each one would be a PETSc malloc at the first assembly, each
            # reallocating the whole matrix (68 s on a 92k-DOF finger); preallocate them
            A, self.A = self.A, preallocated_matrix(self.A, self.jacobian_form, couplings)
            A.destroy()
        self._bc_rows = self._owned_bc_rows()
        self.ties = None
        if ties is not None and len(ties):
            self.ties = Ties(np.asarray(ties, dtype=np.int64).reshape(-1, 2), self.b)
            self._J = self.A  # the full tangent; SNES gets the tied one
            compat.assemble_matrix(self._J, self.jacobian_form, bcs=self.bcs)
            self._J.assemble()
            self.A = self.ties.tied_matrix(self._J)

    def _owned_bc_rows(self) -> np.ndarray:
        start = self.b.getOwnershipRange()[0]
        return (compat.owned_bc_dofs(self.bcs) + start).astype(PETSc.IntType)

    def _set_state(self, x: PETSc.Vec) -> None:
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        x.copy(compat.vector_of(self.w))
        compat.vector_of(self.w).ghostUpdate(
            addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD
        )

    def residual(self, snes, x: PETSc.Vec, b: PETSc.Vec) -> None:
        self._set_state(x)
        with b.localForm() as b_local:
            b_local.set(0.0)
        compat.assemble_vector(b, self.residual_form)
        compat.apply_lifting(b, [self.jacobian_form], bcs=[self.bcs], x0=[x], scale=-1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        if self.contributions:
            for term in self.contributions:
                term.add_to_residual(x, b)
            b.assemble()
        compat.set_bc(b, self.bcs, x, -1.0)
        if self.ties is not None:
            self.ties.tie_residual(x, b)

    def jacobian(self, snes, x: PETSc.Vec, A: PETSc.Mat, P: PETSc.Mat) -> None:
        if self.ties is not None:
            self._full_jacobian(x, self._J)
            self.ties.tie_jacobian(self._J, A)
            return
        self._full_jacobian(x, A)

    def symmetric_tangent(self, x: PETSc.Vec) -> PETSc.Mat:
        """The tangent at ``x`` as a symmetric matrix (stability, inertia): the Jacobian, or
        with ties the reduced P^T J P (a unit diagonal at the tied-away dofs, as at Dirichlet
        rows). Owned by the problem: do not destroy."""
        self.jacobian(None, x, self.A, self.A)
        if self.ties is None:
            return self.A
        return self.ties.reduced(self._J)

    def _full_jacobian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        A.zeroEntries()
        compat.assemble_matrix(A, self.jacobian_form, bcs=self.bcs)
        if self.contributions:
            A.assemble(PETSc.Mat.AssemblyType.FLUSH)
            for term in self.contributions:
                term.add_to_jacobian(x, A)
            A.assemble()
            # The contributions know nothing of Dirichlet rows: restore identity rows/columns.
            A.zeroRowsColumns(self._bc_rows, diag=1.0)
        A.assemble()


class Ties:
    """Joints as ties between dofs: each slave dof s equals its master m (merged into one
    unknown). With P the prolongation (full dofs = P reduced dofs, the slave's column the
    master's) the equations are P^T F = 0 at the masters and the other dofs, and x_s - x_m = 0
    at the slaves: the residual Q F + C x and the Jacobian Q J + C, Q = P^T with zero slave
    rows, C the constraint rows. Newton on them is Newton on the reduced system P^T F(P y) = 0
    (the constraints are linear: exact after the first iteration), and every state, step and
    tangent keeps the ties, so load stepping, arc length and the predictors need nothing else.
    `reduced` gives the symmetric P^T J P for inertia counts. Any number of ranks (PETSc
    matrix products; a master and its slave may live on different ranks)."""

    def __init__(self, pairs: np.ndarray, b: PETSc.Vec):
        comm = b.getComm()
        start, end = b.getOwnershipRange()
        n, N = end - start, b.getSize()
        slaves, masters = pairs[:, 0], pairs[:, 1]
        self.slaves, self.masters = slaves, masters
        is_slave = np.zeros(n, dtype=bool)
        mine = (slaves >= start) & (slaves < end)
        is_slave[slaves[mine] - start] = True

        def matrix(rows):
            M = PETSc.Mat().createAIJ(((n, N), (n, N)), comm=comm)
            M.setPreallocationNNZ((4, 4))
            M.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
            for i, j, value in rows:
                M.setValue(int(i), int(j), value, addv=PETSc.InsertMode.ADD_VALUES)
            M.assemble()
            return M

        owned = np.arange(start, end)
        keep = owned[~is_slave]
        merge = [(m, s, 1.0) for s, m in zip(slaves, masters, strict=True)
                 if start <= m < end]
        self.Q = matrix([(i, i, 1.0) for i in keep] + merge)
        self.P = matrix([(i, i, 1.0) for i in keep]
                        + [(s, m, 1.0) for s, m in zip(slaves, masters, strict=True)
                           if start <= s < end])
        mine_pairs = [(s, m) for s, m in zip(slaves, masters, strict=True) if start <= s < end]
        self.C = matrix([(s, s, 1.0) for s, _ in mine_pairs]
                        + [(s, m, -1.0) for s, m in mine_pairs])
        self.D = matrix([(s, s, 1.0) for s, _ in mine_pairs])
        self._tmp = b.duplicate()
        self._QJ = None
        self._PtJP = None

    def tie_residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """b <- Q b + C x."""
        self.Q.mult(b, self._tmp)
        self.C.multAdd(x, self._tmp, b)

    def _merged(self, J: PETSc.Mat) -> PETSc.Mat:
        if self._QJ is None:
            self._QJ = self.Q.matMult(J)
        else:
            self.Q.matMult(J, result=self._QJ)
        return self._QJ

    def tied_matrix(self, J: PETSc.Mat) -> PETSc.Mat:
        """A matrix with the pattern of Q J + C (for SNES), holding its values."""
        A = self._merged(J).copy()
        A.axpy(1.0, self.C, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        return A

    def tie_jacobian(self, J: PETSc.Mat, A: PETSc.Mat) -> None:
        """A <- Q J + C (J the assembled full Jacobian)."""
        merged = self._merged(J)
        A.zeroEntries()
        A.axpy(1.0, merged, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        A.axpy(1.0, self.C, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        A.assemble()

    def reduced(self, J: PETSc.Mat) -> PETSc.Mat:
        """P^T J P + D (D: ones at the slaves), symmetric when J is."""
        if self._PtJP is not None:
            self._PtJP.destroy()
        product = J.PtAP(self.P)
        product.axpy(1.0, self.D, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        self._PtJP = product
        return product

    def prolong(self, vector: PETSc.Vec) -> None:
        """vector <- P vector (the slaves take their masters' values)."""
        self.P.mult(vector, self._tmp)
        self._tmp.copy(vector)


def preallocated_matrix(A: PETSc.Mat, form, couplings: Sequence[np.ndarray]) -> PETSc.Mat:
    """A new matrix like ``A`` (dolfinx's, of bilinear ``form``: sizes, type, block size and
    local-to-global maps) whose nonzero pattern is the form's plus every pair (i, j) of each
    group of global indices in ``couplings`` (rows owned by this rank kept), filled with
    zeros: assembling the form and adding those entries then allocates nothing. ``A`` is
    assembled once (zeros of the pattern included) to read the form's pattern."""
    compat.assemble_matrix(A, form)
    A.assemble()
    start, end = A.getOwnershipRange()
    ai, aj, _ = A.getValuesCSR()
    ai, aj = np.asarray(ai, dtype=np.int64), np.asarray(aj, dtype=np.int64)
    n_rows, n_cols = end - start, A.getSize()[1]
    rows, cols = [], []
    for group in couplings:
        group = np.unique(np.asarray(group, dtype=np.int64).reshape(-1))
        mine = group[(group >= start) & (group < end)]
        rows.append(np.repeat(mine - start, len(group)))
        cols.append(np.tile(group, len(mine)))
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    counts = np.diff(ai)
    row_of = np.repeat(np.arange(n_rows, dtype=np.int64), counts)
    touched = np.zeros(n_rows, dtype=bool)
    touched[rows] = True
    keep = ~touched[row_of]
    # merged (row, column) keys of the touched rows, sorted by row then column
    keys = np.unique(np.concatenate([row_of[~keep] * n_cols + aj[~keep], rows * n_cols + cols]))
    new_rows = np.concatenate([row_of[keep], keys // n_cols])
    new_cols = np.concatenate([aj[keep], keys % n_cols])
    order = np.argsort(new_rows, kind="stable")  # columns stay sorted within each row
    new_counts = np.bincount(new_rows, minlength=n_rows)
    indptr = np.concatenate([[0], np.cumsum(new_counts)]).astype(PETSc.IntType)
    M = PETSc.Mat().create(comm=A.getComm())
    M.setSizes(A.getSizes(), bsize=A.getBlockSize())
    M.setType(A.getType())
    M.setPreallocationCSR((indptr, new_cols[order].astype(PETSc.IntType)))
    M.setLGMap(*A.getLGMap())
    M.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
    M.setOption(PETSc.Mat.Option.KEEP_NONZERO_PATTERN, True)
    M.assemble()
    return M


# A Newton iteration that stalls below this fraction of the load steps' residuals has reached
# the round-off floor of the residual (a stiff axial term, a multiplier field): accept it.
STAGNATION_RTOL = 1e-6
_EPS = float(np.finfo(float).eps)


class SNESSolver:
    """PETSc SNES on a `NonlinearProblem`, configured through one options prefix."""

    _instances = 0

    def __init__(
        self,
        problem: NonlinearProblem,
        settings: SolverSettings | None = None,
        prefix: str | None = None,
        near_nullspace: PETSc.NullSpace | None = None,
        state_scale: float = 0.0,
        residual_floor: tuple[float, float] = (0.0, 0.0),
    ):
        """``residual_floor``: the residual's round-off floor, (absolute [N], stiffness [N/m]):
        a Newton iteration that has stopped converging (the residual no longer halves) at or
        below max(absolute, machine epsilon x stiffness x the state's norm) is converged
        (`fe_beam.fem.equilibrium.residual_floor`); (0, 0): none."""
        self.problem = problem
        self.state_scale = float(state_scale)
        self.residual_floor = tuple(float(v) for v in residual_floor)
        self.settings = settings or SolverSettings()
        check_petsc_options(self.settings.petsc_options)  # ConfigError before any solve
        if prefix is None:
            SNESSolver._instances += 1
            prefix = f"fe_beam_{SNESSolver._instances}_"
        if not prefix.endswith("_"):
            raise ValueError(f"PETSc options prefix must end with '_', got {prefix!r}")
        self.prefix = prefix
        comm = problem.w.function_space.mesh.comm
        self.snes = PETSc.SNES().create(comm)
        self.snes.setOptionsPrefix(prefix)
        options = PETSc.Options()
        self._option_keys = [prefix + key for key in self.settings.options()]
        for key, value in self.settings.options().items():
            options[prefix + key] = value
        self.snes.setFunction(problem.residual, problem.b)
        self.snes.setJacobian(problem.jacobian, problem.A)
        if near_nullspace is not None:
            problem.A.setNearNullSpace(near_nullspace)
        self.snes.setFromOptions()
        self.snes.getKSP().setFromOptions()
        self._initial_fnorm = 0.0
        self._reference_fnorm: float | None = None
        self._largest_fnorm = 0.0
        # through a weak reference: PETSc keeps its callbacks where Python's garbage collector
        # cannot see them, and a bound method would keep this solver (its problem, mesh and
        # their MPI communicators) alive until the process ends (MPICH allows 2048
        # communicators per process: a long session or test suite ran out of them)
        self.snes.setConvergenceTest(_WeakConvergenceTest(self))
        # petsc4py 3.18 (Debian) keeps an unreferenced SNES (with its Python callbacks: the
        # problem, its mesh) alive: a dropped serial solver destroys it (on several ranks
        # destroying is collective: petsc4py's delayed destroy, fe_beam.cli.free_parallel_garbage)
        weakref.finalize(self, _destroy_if_serial, self.snes)
        self._x = problem.b.duplicate()
        self.linear_iterations = 0

    def _converged(self, snes, iteration, norms):
        """PETSc's default test, except that the step test ||dx|| < stol max(||x||, scale)
        measures the step against the problem's size (e.g. the beam length), not only against
        the state: a state near zero (tiny vibration, zero load) has a residual at round-off
        level that rtol can never reduce, and a relative step test that is never met either."""
        xnorm, step_norm, fnorm = norms
        rtol, atol, stol, max_it = snes.getTolerances()
        reason = PETSc.SNES.ConvergedReason
        if not math.isfinite(fnorm):
            return reason.DIVERGED_FNORM_NAN
        previous, self._last_fnorm = getattr(self, "_last_fnorm", fnorm), fnorm
        if iteration == 0:
            reference = self._reference_fnorm
            self._initial_fnorm = fnorm if reference is None else min(fnorm, reference)
            # the largest residual of this solve, committed to _largest_fnorm only when it
            # converges (`commit_scale`): a diverged trial (a huge first residual far from
            # equilibrium) must not raise the round-off floor below, which would then accept
            # unconverged states of later solves
            self._trial_largest_fnorm = max(self._largest_fnorm, self._initial_fnorm)
            return reason.CONVERGED_FNORM_ABS if fnorm <= atol else reason.ITERATING
        if fnorm <= atol:
            return reason.CONVERGED_FNORM_ABS
        if fnorm <= rtol * self._initial_fnorm:
            return reason.CONVERGED_FNORM_RELATIVE
        # Round-off floor: quadratic convergence has stopped (the residual no longer halves)
        # far below the largest load-step residual this solver has seen (a cut-back step can be
        # so small that its own first residual is already near the floor).
        # The absolute floor of the problem (its stiffness times machine epsilon) holds even
        # when the load-step residuals are themselves small: a slender stiff rod with a
        # constraint (h/L = 1e-4: a load of 1e-9 EA) stagnates at EA eps, which no relative
        # test reaches.
        largest = max(self._largest_fnorm, getattr(self, "_trial_largest_fnorm", 0.0))
        absolute, stiffness = self.residual_floor
        floor = max(STAGNATION_RTOL * max(largest, atol), absolute,
                    _EPS * stiffness * xnorm)
        if iteration >= 2 and fnorm > 0.5 * previous and fnorm <= floor:
            return reason.CONVERGED_FNORM_RELATIVE
        if step_norm <= stol * max(xnorm, self.state_scale):
            return reason.CONVERGED_SNORM_RELATIVE
        if iteration >= max_it:
            return reason.DIVERGED_MAX_IT
        return reason.ITERATING

    def commit_scale(self) -> None:
        """A converged solve's first residual joins the largest load-step residual seen (the
        scale of the round-off floor of `_converged`)."""
        self._largest_fnorm = max(self._largest_fnorm, getattr(self, "_trial_largest_fnorm", 0.0))
        self._trial_largest_fnorm = 0.0

    def residual_norm(self) -> float:
        """||F(w)|| at the current state and loads (global)."""
        x = compat.vector_of(self.problem.w).copy()
        b = self.problem.b.duplicate()
        try:
            self.problem.residual(self.snes, x, b)
            return b.norm()
        finally:
            x.destroy()
            b.destroy()

    def set_reference_residual(self, value: float | None) -> None:
        """rtol of the next solve is measured against min(||F(start)||, value): a predictor
        that breaks the constraints inflates the starting residual (its rows carry other units
        than forces), and the test would then accept a residual of the size of the load step."""
        self._reference_fnorm = value

    def solve(self) -> int:
        """Solve from the current state of ``w``: Newton iterations, or raises SolveFailed."""
        w_vec = compat.vector_of(self.problem.w)
        w_vec.copy(self._x)
        try:
            self.snes.solve(None, self._x)
        except PETSc.Error as error:  # e.g. a factorisation that breaks down: a failed step
            self._x = compat.usable_after_petsc_error(self._x)
            raise SolveFailed(f"PETSc error {error.ierr} in the Newton solve") from None
        finally:
            self._reference_fnorm = None
        reason = self.snes.getConvergedReason()
        self.linear_iterations = self.snes.getLinearSolveIterations()
        if reason <= 0:
            raise SolveFailed(f"SNES diverged ({_reason_name(reason)})")
        self.commit_scale()
        self._x.copy(w_vec)
        w_vec.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        return self.snes.getIterationNumber()

    def destroy(self) -> None:
        """Free PETSc objects and remove this solver's options from PETSc's global database,
        so a later solver with the same prefix starts from its own settings only and long
        sessions do not run into PETSc's limit on the number of options."""
        self.snes.destroy()
        self._x.destroy()
        options = PETSc.Options()
        for key in self._option_keys:
            options.delValue(key)
        self._option_keys = []


class _WeakConvergenceTest:
    """``solver._converged`` called through a weak reference to ``solver`` (see
    `SNESSolver.__init__`)."""

    def __init__(self, solver: SNESSolver):
        self._solver = weakref.ref(solver)

    def __call__(self, snes, iteration, norms):
        solver = self._solver()
        if solver is None:  # its SNES outlived it (not in fe_beam's use): stop
            return PETSc.SNES.ConvergedReason.DIVERGED_FUNCTION_DOMAIN
        return solver._converged(snes, iteration, norms)


def _destroy_if_serial(snes: PETSc.SNES) -> None:
    if snes.handle and snes.getComm().getSize() == 1:
        snes.destroy()


def _reason_name(reason: int) -> str:
    names = {
        value: name
        for name, value in vars(PETSc.SNES.ConvergedReason).items()
        if isinstance(value, int)
    }
    return f"{names.get(reason, 'UNKNOWN')} = {reason}"


@dataclass
class StepResult:
    """One converged load step."""

    index: int
    load_factor: float
    iterations: int
    linear_iterations: int
    wall_time_s: float


def _agreed(comm, reason: str | None) -> str | None:
    """All ranks reject a step if any one does (reject_step may look at local data only)."""
    reasons = comm.allgather(reason)
    rejected = [r for r in reasons if r]
    return rejected[0] if rejected else None


def rotation_jump_check(rotation_dofs: np.ndarray, max_jump: float):
    """A ``reject_step`` that vetoes steps whose rotation changed by more than ``max_jump`` rad.

    The equilibrium path of a slender beam is followed step by step; a converged step whose
    rotations jump by far more than the load increment warrants has usually landed on another
    (e.g. looped) branch.
    """
    if not (max_jump > 0 and math.isfinite(max_jump)):
        raise ValueError(f"max rotation jump must be > 0, got {max_jump!r}")

    def check(previous: np.ndarray, current: np.ndarray) -> str | None:
        if rotation_dofs.size == 0:
            return None
        jump = float(np.max(np.abs(current[rotation_dofs] - previous[rotation_dofs])))
        if jump > max_jump:
            return f"rotation jumped by {jump:.3g} rad > {max_jump:.3g} in one step"
        return None

    return check

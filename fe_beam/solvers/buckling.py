"""Linear (eigenvalue) buckling of the rod and of the 3D solid about the undeformed or a
prestressed state (docs/theory.md, Linear buckling).

With R(w, lambda) the residual and K_T = dR/dw its tangent, the state w(lambda) of the load path
through the prestress state w_p = w(p) has the load derivative w1 = dw/dlambda, solved from

    K_T(w_p, p) w1 = -dR/dlambda(w_p, p)        (w1 = d(prescribed values)/dlambda on supports)

and the tangent changes along the path at the rate

    K_geo = dK_T(w(lambda), lambda)/dlambda = D_w K_T(w_p, p)[w1] + dK_T/dlambda|_w.

The first term is UFL's exact directional derivative of the Jacobian form (a trilinear form with
w1 as a coefficient); the second, the explicit dependence on the load factor (follower tip
forces, tendon tensions), is the central difference (K_T(w_p, p + 1) - K_T(w_p, p - 1)) / 2,
exact because every load enters the residual affinely; it is zero for dead loads and skipped.
The buckling load factors are lambda_c = p + mu with mu the eigenvalues of

    (K_T + mu K_geo) phi = 0,

the smallest positive ones first (SLEPc, shift-and-invert about 0: K_T is factorised once,
MUMPS). At p = 0 this is the classical linearised buckling problem of the linear prestress; at
p close to a critical load mu -> 0 and lambda_c is exact to O(mu^2): repeating with prestress =
the last estimate converges to the bifurcation of the nonlinear problem (the extensible, shear-
deformable column included). Dirichlet rows: K_T 1 on the diagonal, K_geo 0 (infinite
eigenvalues, far from the target; pairs living on the fixed dofs are dropped as in
fe_beam/modes.py); multiplier rows (constraints): K_geo 0 there too, the saddle-point K_T
factorised by MUMPS with the same extra workspace as the static solves.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.fem.mpi import global_max, global_sum
from fe_beam.model.loads import scaled
from fe_beam.solvers.inertia import (
    InertiaFactor,
    rod_unstable_count,
    solid_unstable_count,
)
from fe_beam.solvers.newton import SADDLE_POINT_WORKSPACE, LoadStepping, LoadSteppingFailed

__all__ = ["Buckling", "LinearisedProblem", "PathCheck", "PathCritical", "buckling_modes",
           "confirm_on_path", "default_search_limit", "rod_buckling",
           "solid_buckling"]

# eigenvalues whose imaginary part is below this fraction of their modulus are real
IMAGINARY_TOLERANCE = 1e-6
MAX_EXTRA = 64  # widen the search for positive eigenvalues at most to count + this


@dataclass
class Buckling:
    """Buckling load factors (ascending, multiples of the applied load, > prestress) and their
    mode shapes (max |displacement dof| = 1); ``prestress``: the load factor of the state
    linearised about; ``negative``: load factors below the prestress found on the way (the
    loads reversed), ascending in magnitude."""

    load_factors: list[float]
    shapes: list[fem.Function]
    prestress: float = 0.0
    negative: list[float] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


@dataclass
class LinearisedProblem:
    """What the eigenvalue solver needs of a problem with a load parameter: its mixed space,
    state ``w``, residual form, Dirichlet conditions, ``set_load_factor`` (loads and prescribed
    values), ``set_prescribed_factor`` (prescribed values only), the current load factor, the
    dofs that are displacements (normalisation) and whether the tangent depends on the load
    factor at fixed state (``explicit``: follower loads, tendon tensions)."""

    space: object
    w: fem.Function
    residual: object
    bcs: list
    set_load_factor: object
    set_prescribed_factor: object
    load_factor: float
    displacement_dofs: np.ndarray
    comm: MPI.Comm
    saddle_point: bool = False
    explicit: bool = False
    jacobian: object = None
    # symmetric K_T and K_geo (conservative loads): positive factors are verified by the
    # inertia of K_T + lambda K_geo (`_InertiaCount`); False (follower loads): not verified
    conservative: bool = True
    #: a structure's joints as ties (`fe_beam.solvers.newton.Ties`): the reduced pencil
    #: (P^T K_T P, P^T K_geo P), the shapes P y
    ties: object = None


class BucklingFailed(ArithmeticError):
    """The linearised buckling problem cannot be set up or solved at the given state (exit 3:
    an analysis failure, not a user mistake nor an internal error)."""


def _assemble_vector(form) -> PETSc.Vec:
    vector = compat.assemble_vector(form)
    vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    return vector


def load_derivative(problem: LinearisedProblem, K: PETSc.Mat, jacobian_form) -> fem.Function:
    """w1 = dw/dlambda at the current state: K_T w1 = -dR/dlambda, w1 = the load derivative of
    the prescribed values on the Dirichlet dofs (``K``: K_T with 1 on the Dirichlet diagonal)."""
    p = problem.load_factor
    residual = fem.form(problem.residual)
    problem.set_load_factor(p + 1.0)
    plus = _assemble_vector(residual)
    problem.set_load_factor(p - 1.0)
    minus = _assemble_vector(residual)
    rhs = plus.copy()
    rhs.axpy(-1.0, minus)
    rhs.scale(-0.5)  # -dR/dlambda (exact: the residual is affine in the load factor)
    # the prescribed values' rate: the Dirichlet functions at factor 1 minus factor 0
    problem.set_prescribed_factor(1.0)
    compat.apply_lifting(rhs, [jacobian_form], [problem.bcs])
    rhs.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    compat.set_bc(rhs, problem.bcs)
    problem.set_load_factor(p)
    w1 = fem.Function(problem.space)
    ksp = _direct_solver(K, problem.saddle_point, "fe_beam_buckling_w1_")
    if problem.ties is not None:  # the reduced system P^T K P y = P^T rhs, w1 = P y
        reduced = rhs.duplicate()
        problem.ties.P.multTranspose(rhs, reduced)
        ksp.solve(reduced, compat.vector_of(w1))
        reduced.destroy()
        problem.ties.prolong(compat.vector_of(w1))
    else:
        ksp.solve(rhs, compat.vector_of(w1))
    compat.vector_of(w1).ghostUpdate(addv=PETSc.InsertMode.INSERT,
                                     mode=PETSc.ScatterMode.FORWARD)
    reason = ksp.getConvergedReason()
    ksp.destroy()
    for vector in (plus, minus, rhs):
        vector.destroy()
    if reason < 0:
        raise BucklingFailed(
            f"the tangent at the prestress state is singular (PETSc reason {reason}): the state "
            "is critical, or the constraints leave no room for the prescribed end values (an "
            "inextensible rod cannot take an axial end displacement)")
    return w1


def _direct_solver(K: PETSc.Mat, saddle_point: bool, prefix: str) -> PETSc.KSP:
    ksp = PETSc.KSP().create(K.getComm())
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(K)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    if saddle_point:
        option, percent = SADDLE_POINT_WORKSPACE
        PETSc.Options()[f"{prefix}{option}"] = percent
    ksp.setFromOptions()
    return ksp


def geometric_stiffness(problem: LinearisedProblem, w1: fem.Function, jacobian) -> PETSc.Mat:
    """K_geo = D_w K_T[w1] + dK_T/dlambda|_w (module docstring), 0 on the Dirichlet diagonal."""
    directional = fem.form(ufl.derivative(jacobian, problem.w, w1))
    G = compat.assemble_matrix(directional, bcs=problem.bcs, diagonal=0.0)
    G.assemble()
    if problem.explicit:
        p, form = problem.load_factor, fem.form(jacobian)
        problem.set_load_factor(p + 1.0)
        plus = compat.assemble_matrix(form, bcs=problem.bcs, diagonal=0.0)
        plus.assemble()
        problem.set_load_factor(p - 1.0)
        minus = compat.assemble_matrix(form, bcs=problem.bcs, diagonal=0.0)
        minus.assemble()
        problem.set_load_factor(p)
        plus.axpy(-1.0, minus)
        G.axpy(0.5, plus)
        plus.destroy()
        minus.destroy()
    return G


def buckling_modes(problem: LinearisedProblem, count: int, verify: bool = True) -> Buckling:
    """The ``count`` smallest buckling load factors above the current one, and their modes.
    ``verify``: keep only the positive factors that are crossings of the inertia of
    K_T + lambda K_geo (conservative loads); False keeps the pencil's eigenvalues as they are
    (about a nearly critical state the inertia cannot resolve a factor mu ~ 1e-5 x p: the
    estimates that `confirm_on_path` checks on the path itself)."""
    from slepc4py import SLEPc

    if count < 1:
        raise ValueError(f"[buckling] count must be >= 1, got {count}")
    trial = ufl.TrialFunction(problem.space)
    jacobian = problem.jacobian if problem.jacobian is not None else \
        ufl.derivative(problem.residual, problem.w, trial)
    jacobian_form = fem.form(jacobian)
    K = compat.assemble_matrix(jacobian_form, bcs=problem.bcs, diagonal=1.0)
    K.assemble()
    ties, slaves = problem.ties, np.zeros(0, dtype=np.int64)
    if ties is not None:  # joints as ties: the reduced pencil
        full, K = K, ties.reduced(K).copy()
        full.destroy()
        start, end = K.getOwnershipRange()
        slaves = ties.slaves[(ties.slaves >= start) & (ties.slaves < end)] - start
    w1 = load_derivative(problem, K, jacobian_form)
    G = geometric_stiffness(problem, w1, jacobian)
    if ties is not None:
        full, G = G, G.PtAP(ties.P)
        full.destroy()
    B = G.copy()
    B.scale(-1.0)  # K_T phi = mu (-K_geo) phi
    notes: list[str] = []
    fixed = np.concatenate([compat.owned_bc_dofs(problem.bcs).astype(np.int64),
                            slaves.astype(np.int64)])
    scale = global_max(problem.comm, np.max(np.abs(compat.local_array(w1)), initial=0.0))
    if not scale > 0:
        for matrix in (K, G, B):
            matrix.destroy()
        raise ValueError("the applied loads are zero: there is no load to buckle under "
                         "(give [loads] or tendon tensions)")
    extra = 4
    while True:
        pairs = _solve(SLEPc, K, B, count + extra, fixed, problem)
        positive = [(mu, shape) for mu, shape in pairs if mu > 0]
        if len(positive) >= count or extra >= MAX_EXTRA or len(pairs) < count + extra:
            break
        extra *= 2
    positive.sort(key=lambda pair: pair[0])
    negative = sorted((mu for mu, _ in pairs if mu < 0), key=abs)
    if problem.conservative and verify:
        try:
            positive = _verified_positive(SLEPc, K, G, B, positive, pairs, count, fixed,
                                          problem, notes)
        finally:
            for matrix in (K, G, B):
                matrix.destroy()
    else:
        for matrix in (K, G, B):
            matrix.destroy()
    chosen = positive[:count]
    if len(chosen) < count and not (problem.conservative and verify):
        notes.append(f"[buckling] count = {count}: only {len(chosen)} positive buckling load "
                     "factor(s) found (the loads may not compress the structure enough)")
    p = problem.load_factor
    passed = sorted(p + mu for mu in negative if 0 < p + mu < p)
    if passed:  # the prestate is past a critical point: the factors above p are not the first
        notes.append(f"[buckling] prestress = {p:g} is past the critical load factor "
                     f"{passed[0]:.6g} (a linearised factor below the prestress): the state "
                     "linearised about "
                     "is beyond a bifurcation or limit of the path from 0, and load_factors "
                     "(above the prestress only) do not start with the first buckling load; "
                     "use a prestress below it")
    for index, (_, shape) in enumerate(chosen, start=1):
        if ties is not None:  # every dof's value (the slaves their masters')
            ties.prolong(compat.vector_of(shape))
            compat.vector_of(shape).ghostUpdate(addv=PETSc.InsertMode.INSERT,
                                                mode=PETSc.ScatterMode.FORWARD)
        _normalise(shape, problem.displacement_dofs, problem.comm)
        shape.name = f"buckling_mode_{index}"
    return Buckling([p + mu for mu, _ in chosen], [s for _, s in chosen], p,
                    [p + mu for mu in negative], notes)


# positive factors: an eigenvalue mu of (K_T + mu K_geo) phi = 0 is a crossing of the inertia of
# K_T + lambda K_geo at lambda = mu; a bracket mu (1 -+ VERIFY_WIDTH) must show it
VERIFY_WIDTH = 1e-6
# the search for positive factors beyond those near 0 goes up to this multiple of the largest
# |factor| found there (doubling, then bisection on the inertia count)
SEARCH_RANGE = 1e8


class _InertiaCount:
    """N(lambda) = negative(K_T + lambda K_geo) - negative(K_T): for a stable state (K_T positive
    definite on the constraint-preserving directions) the number of buckling factors in
    (0, lambda) (Sylvester's law on the pencil; the constraint rows add the same m negative
    pivots at every lambda). One sparse LDL^T (MUMPS) per value; collective."""

    def __init__(self, K, G):
        self.K, self.G, self.cache = K, G, {}
        # K_T + lambda K_geo in one matrix of the union pattern, factored by one MUMPS
        # instance (symbolic analysis once: see InertiaFactor)
        self.pencil = K.copy()
        self.pencil.axpy(1.0, G, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        self.factor = InertiaFactor()
        self.base = self._negative(0.0)

    def _negative(self, value: float) -> int:
        subset = PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN
        self.pencil.zeroEntries()
        self.pencil.axpy(1.0, self.K, structure=subset)
        if value:
            self.pencil.axpy(value, self.G, structure=subset)
        return self.factor.count(self.pencil)[0]

    def destroy(self) -> None:
        self.factor.destroy()
        self.pencil.destroy()

    def __call__(self, value: float) -> int:
        if value not in self.cache:
            self.cache[value] = self._negative(value) - self.base
        return self.cache[value]


def _verified_positive(SLEPc, K, G, B, positive, pairs, count, fixed, problem, notes):
    """The first ``count`` positive pairs that are crossings of the inertia of K_T + lambda K_geo
    (round-off pairs of the pencil, e.g. of the constraint rows, are not: dropped, with a note),
    completed by a search (shift-and-invert inside the interval that the inertia count
    brackets) when the one about 0 found fewer or missed one (e.g. behind the many negative
    factors of a fine mesh)."""
    counter = _InertiaCount(K, G)
    try:
        return _verified_by(counter, SLEPc, K, B, positive, pairs, count, fixed, problem, notes)
    finally:
        counter.destroy()


def _verified_by(counter, SLEPc, K, B, positive, pairs, count, fixed, problem, notes):
    """`_verified_positive` with the inertia counts of ``counter``."""
    dropped: list[float] = []

    def verify(candidates):
        """Ascending candidates kept while they are crossings, until ``count`` are kept."""
        kept, index = [], 0
        candidates = sorted(candidates, key=lambda pair: pair[0])
        while index < len(candidates) and len(kept) < count:
            mu = candidates[index][0]
            group = [c for c in candidates[index:] if c[0] <= mu * (1 + VERIFY_WIDTH) ** 2]
            top = group[-1][0]
            available = abs(counter(top * (1 + VERIFY_WIDTH)) - counter(mu * (1 - VERIFY_WIDTH)))
            kept.extend(group[:available])
            dropped.extend(c[0] for c in group[available:])
            index += len(group)
        return kept

    accepted = verify(positive)
    largest = max([abs(mu) for mu, _ in pairs] + [1.0])
    limit = SEARCH_RANGE * largest
    for _ in range(3):
        if len(accepted) >= count:
            upper = accepted[count - 1][0] * (1 + VERIFY_WIDTH)
            if counter(upper) <= count:
                break  # none missed below the count-th one
        else:
            upper = max(largest, accepted[-1][0] * (1 + VERIFY_WIDTH) if accepted else 0.0)
            while counter(upper) < count and upper < limit:
                upper = min(2.0 * upper, limit)
            if counter(upper) <= len(accepted):
                break  # no further crossing below the limit
            if counter(upper) >= count:  # bisect to a tight bracket of the count-th crossing
                lower = 0.0
                for _ in range(40):
                    if upper - lower <= 1e-3 * upper:
                        break
                    middle = 0.5 * (lower + upper)
                    if counter(middle) >= count:
                        upper = middle
                    else:
                        lower = middle
        # every crossing in (0, upper): shift-and-invert about its middle finds them first
        wanted = counter(upper)
        found = _solve_at(SLEPc, K, B, wanted + 4, fixed, problem, 0.5 * upper)
        inside = verify([(mu, shape) for mu, shape in found if 0 < mu < upper])
        if len(inside) <= len([mu for mu, _ in accepted if mu < upper]):
            break  # the search found no more than we had
        accepted = sorted(inside + [pair for pair in accepted if pair[0] >= upper],
                          key=lambda pair: pair[0])[:count]
    p = problem.load_factor
    if dropped:
        shown = ", ".join(f"{p + mu:.6g}" for mu in sorted(set(dropped))[:3])
        notes.append(f"[buckling] {len(set(dropped))} positive eigenvalue(s) of the pencil "
                     f"dropped ({shown}{', ...' if len(set(dropped)) > 3 else ''}): the inertia "
                     "of K_T + lambda K_geo does not change there (round-off, not buckling)")
    if len(accepted) < count:
        notes.append(f"[buckling] count = {count}: only {len(accepted)} positive buckling load "
                     f"factor(s) up to {p + limit:.3g} (checked by the inertia of "
                     "K_T + lambda K_geo): the loads do not buckle the structure further")
    return accepted


def _solve_at(SLEPc, A, B, nev, fixed, problem, target):
    """`_solve` with shift-and-invert about ``target`` instead of 0."""
    attempts = ((None, max(2 * nev + 1, nev + 15)), (None, 3 * nev + 21),
                (SLEPc.EPS.Type.ARNOLDI, 3 * nev + 21))
    for attempt, (kind, ncv) in enumerate(attempts):
        try:
            return _solve_once(SLEPc, A, B, nev, ncv, kind, fixed, problem, target)
        except PETSc.Error:
            if attempt == len(attempts) - 1:
                raise
    return []


def _solve(SLEPc, A, B, nev, fixed, problem):
    """Real eigenpairs (mu, shape) of A x = mu B x nearest 0 (shift-and-invert: A factorised),
    without the pairs of the Dirichlet rows. LAPACK's reordering of the projected Schur form
    can fail on the many zero eigenvalues of the inverted operator (Dirichlet and multiplier
    rows): the solve is then repeated with a larger subspace, then with plain Arnoldi."""
    attempts = ((None, max(2 * nev + 1, nev + 15)), (None, 3 * nev + 21),
                (SLEPc.EPS.Type.ARNOLDI, 3 * nev + 21))
    for attempt, (kind, ncv) in enumerate(attempts):
        try:
            return _solve_once(SLEPc, A, B, nev, ncv, kind, fixed, problem)
        except PETSc.Error:
            if attempt == len(attempts) - 1:
                raise
    return []


def _solve_once(SLEPc, A, B, nev, ncv, kind, fixed, problem, target=0.0):
    eps = SLEPc.EPS().create(problem.comm)
    eps.setOptionsPrefix("fe_beam_buckling_")
    eps.setOperators(A, B)
    eps.setProblemType(SLEPc.EPS.ProblemType.GNHEP)
    if kind is not None:
        eps.setType(kind)
    eps.setDimensions(nev, ncv)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTarget(target)
    transform = eps.getST()
    transform.setType(SLEPc.ST.Type.SINVERT)
    transform.setShift(target)
    ksp = transform.getKSP()
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    if problem.saddle_point:
        option, percent = SADDLE_POINT_WORKSPACE
        PETSc.Options()[f"fe_beam_buckling_st_{option}"] = percent
    eps.setTolerances(1e-12, 300)
    eps.setFromOptions()
    try:
        eps.solve()
    except PETSc.Error:
        eps.destroy()
        raise
    pairs = []
    vector = A.createVecRight()
    for i in range(eps.getConverged()):
        value = complex(eps.getEigenpair(i, vector))
        if not math.isfinite(value.real) or abs(value.imag) > IMAGINARY_TOLERANCE * abs(value):
            continue
        if _lives_on_fixed_dofs(vector, fixed):
            continue
        shape = fem.Function(problem.space)
        vector.copy(compat.vector_of(shape))
        compat.vector_of(shape).ghostUpdate(addv=PETSc.InsertMode.INSERT,
                                            mode=PETSc.ScatterMode.FORWARD)
        pairs.append((value.real, shape))
    vector.destroy()
    eps.destroy()
    pairs.sort(key=lambda pair: pair[0])
    return pairs


def _lives_on_fixed_dofs(vector: PETSc.Vec, fixed: np.ndarray) -> bool:
    array = vector.getArray(readonly=True)
    on_fixed, total = global_sum(vector.getComm().tompi4py(),
                                 np.array([np.sum(array[fixed] ** 2), np.sum(array**2)]))
    return on_fixed > 1e-6 * total


def _normalise(shape: fem.Function, displacement_dofs: np.ndarray, comm) -> None:
    """max |displacement dof| = 1, the largest one positive (a reproducible sign)."""
    array = compat.local_array(shape)
    owned = array[displacement_dofs]
    local_max = float(np.max(np.abs(owned), initial=0.0))
    scale = global_max(comm, local_max)
    if not scale > 0:
        return
    # the sign of the (first) largest entry, from the rank that holds it
    local_sign = 0.0
    if owned.size and local_max == scale:
        local_sign = float(np.sign(owned[int(np.argmax(np.abs(owned)))]))
    candidates = comm.allgather(local_sign)
    sign = next((s for s in candidates if s != 0.0), 1.0)
    array /= sign * scale


# --- the rod ------------------------------------------------------------------------------------
def _rod_linearised(run) -> LinearisedProblem:
    """The rod problem of a `fe_beam.analyses.static.StaticContinuation` at its current load
    factor."""
    problem = run.problem
    dofs = np.concatenate([problem.component_dofs(name) for name in problem.components
                           if not name.startswith("theta")])
    conservative = not problem.model.loads.follower and getattr(problem, "conservative", True)
    return LinearisedProblem(
        space=problem.space, w=problem.w, residual=problem.residual, bcs=problem.bcs,
        set_load_factor=run._set_load_factor, set_prescribed_factor=problem.set_prescribed_factor,
        load_factor=float(run.load_factor), displacement_dofs=dofs, comm=problem.comm,
        saddle_point=problem.saddle_point,
        explicit=bool(not conservative or run.tendons),
        conservative=conservative, ties=run.snes.problem.ties)


def rod_buckling(run, count: int, prestress: float = 0.0, stepping=None,
                 progress: bool = False, verify: bool = True) -> Buckling:
    """Buckling of the rod of ``run`` (a `fe_beam.analyses.static.StaticContinuation`): the state is
    first loaded to ``prestress`` (load stepping; `LoadSteppingFailed` if it is not reached)."""
    if prestress != run.load_factor:
        run.advance(prestress, stepping or run.config.stepping, progress=progress,
                    label="buckling pre-state")
    run._set_load_factor(float(run.load_factor))
    return buckling_modes(_rod_linearised(run), count, verify)


# --- the 3D solid -------------------------------------------------------------------------------
def solid_buckling(run, count: int, prestress: float = 0.0, stepping=None,
                   progress: bool = False, verify: bool = True) -> Buckling:
    """Buckling of the 3D solid of ``run`` (a `fe_beam.analyses.solid.SolidRun`, tip force only:
    its cables' contributions are outside the UFL residual) about the state at ``prestress``."""
    if prestress > run.load_factor:
        run.advance(prestress, stepping or run.config.stepping, progress=progress,
                    label="buckling pre-state")
    elif prestress != run.load_factor:
        raise ValueError("the solid's pre-state is loaded upwards from its current load factor")
    problem = run.problem
    problem.set_load_factor(run.load_factor)
    space = problem.W
    owned = space.dofmap.index_map.size_local * space.dofmap.index_map_bs
    if problem.p is None:
        dofs = np.arange(owned, dtype=np.int32)
    else:
        dofs = np.asarray(compat.sub_space_collapsed(space, 0)[1])
        dofs = dofs[dofs < owned]
    lin = LinearisedProblem(
        space=space, w=problem.w, residual=problem.residual, bcs=problem.bcs,
        set_load_factor=problem.set_load_factor, set_prescribed_factor=lambda value: None,
        load_factor=float(run.load_factor), displacement_dofs=dofs, comm=problem.comm,
        saddle_point=problem.p is not None)
    return buckling_modes(lin, count, verify)


# --- the command ------------------------------------------------------------------------------
def load_scale_record(model, factor: float) -> dict:
    """The rod's applied loads times ``factor`` (those that act, `fe_beam.model.loads`) and its
    prescribed end values: the critical loads."""
    record = scaled(model.loads, factor)
    for end in ("x0", "xL"):
        values = getattr(model.supports, f"prescribed_{end}")
        if values:
            record[f"prescribed_{end}"] = {k: factor * v for k, v in values.items()}
    return record


# --- the critical points of the nonlinear path ----------------------------------------------------
#: a confirmed critical factor's bracket on the path: stable at lo, one more energy-decreasing
#: direction at hi, (hi - lo) <= CONFIRM_TOLERANCE * hi
CONFIRM_TOLERANCE = 1e-4
#: the search for a crossing walks toward the linearised estimate about the last state: this
#: fraction of the way while it is farther than APPROACH_GAP (relative) ...
APPROACH, APPROACH_GAP = 0.8, 0.1
#: ... then past it by this fraction of the gap (at least 1e-3 relative) ...
BRACKET_MARGIN = 0.5
#: ... and at least this multiple of the distance from the prestress already walked (an
#: estimate that keeps running ahead of the path, as about a bent cantilever, is overtaken)
WALK_GROWTH = 0.5
MAX_PATH_TRIALS = 80
#: the default largest load factor checked: max(1, SEARCH_MULTIPLE x the count-th linearised
#: factor about the prestress, SEARCH_MULTIPLE_FIRST x the first)
SEARCH_MULTIPLE = 2.0
SEARCH_MULTIPLE_FIRST = 4.0


@dataclass
class PathCritical:
    """A critical load factor confirmed by the nonlinear path: ``bracket`` (lo, hi) with
    ``unstable_below`` energy-decreasing directions of the tangent at lo and
    ``unstable_above`` > that at hi; ``load_factor``: the linearised estimate about the state
    at lo when it lies in the bracket (error O((hi - lo)^2)), else the bracket's middle;
    ``multiplicity``: unstable_above - unstable_below (coincident factors); ``shapes``: the
    critical modes (linearised about lo)."""

    load_factor: float
    bracket: tuple[float, float]
    unstable_below: int
    unstable_above: int
    shapes: list = field(default_factory=list)

    @property
    def multiplicity(self) -> int:
        return self.unstable_above - self.unstable_below


@dataclass
class PathCheck:
    """What the nonlinear path says of the linearised factors: the ``confirmed`` critical points
    (ascending), ``checked_to``: the largest load factor at which the path was followed and its
    energy-decreasing directions counted, ``unstable_at_start`` (at the prestress),
    ``unstable_at_end`` (at checked_to), ``failure``: why the path could not be followed
    further (None: it reached ``limit``, or ``count`` factors were confirmed)."""

    confirmed: list[PathCritical]
    checked_to: float
    limit: float
    unstable_at_start: int
    unstable_at_end: int
    failure: str | None = None
    trials: int = 0
    #: (lo, x, count at lo, count at x < it): the search stopped where the path lost an
    #: energy-decreasing direction (it left the branch), None otherwise
    left_branch: tuple | None = None


def default_search_limit(first: Buckling, count: int) -> float:
    """The largest load factor the path is followed to when no critical point is confirmed
    before it (module constants SEARCH_MULTIPLE*)."""
    factors = first.load_factors
    candidates = [1.0, 2.0 * abs(first.prestress)]
    if factors:
        candidates += [SEARCH_MULTIPLE_FIRST * factors[0],
                       SEARCH_MULTIPLE * factors[min(count, len(factors)) - 1]]
    return max(candidates)


def confirm_on_path(run, first: Buckling, count: int, limit: float, stepping=None,
                    tolerance: float = CONFIRM_TOLERANCE, progress: bool = False) -> PathCheck:
    """The critical load factors of the nonlinear path of ``run`` (a
    `fe_beam.solvers.rod_static.StaticContinuation` at the state ``first`` was linearised
    about, conservative loads), up to ``count`` of them below ``limit``.

    From the prestress state, the path is followed by load stepping toward the linearised
    estimate about the last state reached (APPROACH of the way while it is far, then just past
    it: BRACKET_MARGIN; at least WALK_GROWTH times the distance already walked), and the
    energy-decreasing directions of the tangent are counted there (the sparse inertia,
    `fe_beam.solvers.inertia`; the 3D solid's: a `fe_beam.analyses.solid.SolidRun`). A state with
    more of them than the last one brackets a critical point; the bracket is narrowed by probes
    on either side of the estimate linearised about its stable end (quadratic convergence) or,
    when that estimate leaves the bracket, by bisection, to ``tolerance`` (relative). The
    search for the next factor starts at the unstable end. A linearised factor that the path
    does not cross is not a critical point (about a bent pre-buckling state it rarely is: a
    cantilever under a transverse tip load never buckles).

    ``stepping``: the load stepping of the walk (its initial steps per walk; probes near a
    bracket take one step, cut back on failure). The run is left at the last state reached."""
    stepping = stepping or LoadStepping()
    walk = LoadStepping(steps=max(2, min(stepping.steps, 10)),
                        min_increment=min(stepping.min_increment, 1e-4), max_increment=1.0,
                        cut_factor=stepping.cut_factor, grow_factor=stepping.grow_factor,
                        easy_iterations=stepping.easy_iterations, adaptive=True)
    probe = LoadStepping(steps=1, min_increment=1e-4, max_increment=1.0,
                         cut_factor=stepping.cut_factor, grow_factor=stepping.grow_factor,
                         easy_iterations=stepping.easy_iterations, adaptive=True)
    path = _SolidPath(run) if not hasattr(run, "engine") else _RodPath(run)
    start = path.load_factor
    trials = 0

    def state():
        return path.snapshot()

    def back_to(snapshot) -> None:
        path.restore(snapshot)

    def reach(target: float, how) -> int:
        nonlocal trials
        trials += 1
        path.advance(target, how, progress)
        return path.unstable()

    cache: dict[float, Buckling | None] = {}

    def estimate(wanted: int = 2) -> Buckling | None:
        """The linearised factors above the current state (at least the first ``wanted``;
        one solve per state)."""
        here = path.load_factor
        known = cache.get(here, False)
        if known is not False and (known is None or len(known.load_factors) >= wanted):
            return known
        try:
            found = path.estimate(max(2, wanted))
        except BucklingFailed:
            found = None
        cache[here] = found if found is not None and found.load_factors else None
        return cache[here]

    lo, n_lo, lo_state = start, path.unstable(), state()
    result = PathCheck([], start, limit, n_lo, n_lo)
    linear = first if first.load_factors else None
    if first.prestress == start:
        cache[start] = linear
    failure = None
    while len(result.confirmed) < count and failure is None:
        # 1. bracket: walk up the path until the count of energy-decreasing directions grows
        hi = None
        while trials < MAX_PATH_TRIALS:
            guess = linear.load_factors[0] if linear is not None else math.inf
            gap = guess - lo
            if gap > APPROACH_GAP * abs(guess):  # far: toward the estimate, stopping short
                target = lo + APPROACH * gap
            else:  # near: just past it (its error is quadratic in the gap)
                target = guess + max(BRACKET_MARGIN * gap, 1e-3 * abs(guess))
            target = max(target, lo + WALK_GROWTH * max(lo - start, 0.0),
                         lo + 1e-3 * max(abs(lo), abs(limit)))
            target = min(target, limit)
            if not target > lo:
                break
            try:
                n = reach(target, walk)
            except LoadSteppingFailed as stopped:
                failure = (f"the path could not be followed from load factor {lo:.8g} to "
                           f"{target:.8g} ({stopped}); last converged load factor "
                           f"{path.load_factor:.8g}")
                back_to(lo_state)
                break
            if n > n_lo:
                hi, n_hi, hi_state = target, n, state()
                break
            if n < n_lo:  # restabilised: the load stepping left the branch (an imperfect or
                # a jumped path); what lies above is not the continuation of this branch
                result.left_branch = (lo, target, n_lo, n)
                back_to(lo_state)
                break
            lo, n_lo, lo_state = target, n, state()
            result.checked_to, result.unstable_at_end = lo, n_lo
            if lo >= limit:
                break
            linear = estimate()
        if hi is None:
            if trials >= MAX_PATH_TRIALS and failure is None and result.left_branch is None:
                failure = (f"no crossing bracketed in {MAX_PATH_TRIALS} path trials (the "
                           f"path was followed to load factor {lo:.8g})")
            break
        # 2. narrow the bracket: probes about the estimate linearised at its stable end
        back_to(lo_state)
        linear = estimate(2)
        stale, slow = False, 0
        while hi - lo > tolerance * abs(hi) and trials < MAX_PATH_TRIALS and failure is None:
            width = hi - lo
            guess = min((f for f in (linear.load_factors if linear is not None else [])
                         if lo < f < hi), default=math.nan)
            if stale or not lo < guess < hi:
                points = [0.5 * (lo + hi)]
            else:
                half = 0.25 * tolerance * abs(guess)
                points = [min(guess + half, 0.5 * (guess + hi)),
                          max(guess - half, 0.5 * (guess + lo))]
            moved = False
            for x in points:
                if not lo < x < hi:
                    continue
                back_to(lo_state)
                try:
                    n = reach(x, probe)
                except LoadSteppingFailed as stopped:
                    failure = (f"no equilibrium at load factor {x:.8g} inside the bracket "
                               f"({lo:.8g}, {hi:.8g}) of a critical point ({stopped})")
                    break
                if n > n_lo:
                    hi, n_hi, hi_state = x, n, state()
                else:
                    lo, n_lo, lo_state = x, n, state()
                    moved = True
                    result.checked_to, result.unstable_at_end = lo, n_lo
                    break  # the estimate about the new stable end is better
            back_to(lo_state)
            if failure is None:
                # estimates that do not halve the bracket twice in a row give way to a
                # bisection (the bracket then shrinks at least geometrically)
                slow = slow + 1 if hi - lo > 0.5 * width else 0
                stale = not moved or slow >= 2
                if moved:
                    linear = estimate(2)
        if failure is not None:
            break
        if hi - lo > tolerance * abs(hi):
            failure = (f"the critical point in ({lo:.8g}, {hi:.8g}) was not narrowed to "
                       f"{tolerance:g} in {MAX_PATH_TRIALS} path trials")
            break
        # 3. the critical factor and its modes, linearised about the stable end
        back_to(lo_state)
        multiplicity = n_hi - n_lo
        about = estimate(multiplicity)
        inside = [] if about is None else [
            (f, s) for f, s in zip(about.load_factors, about.shapes, strict=True)
            if lo - tolerance * abs(hi) <= f <= hi + tolerance * abs(hi)]
        factor = inside[0][0] if inside else 0.5 * (lo + hi)
        shapes = [s for _, s in inside][:multiplicity]
        if len(shapes) < multiplicity and about is not None:
            shapes += about.shapes[len(shapes):multiplicity]
        result.confirmed.append(PathCritical(factor, (lo, hi), n_lo, n_hi, shapes))
        # 4. the next one from the unstable end
        back_to(hi_state)
        lo, n_lo, lo_state = hi, n_hi, hi_state
        result.checked_to, result.unstable_at_end = lo, n_lo
        start = lo
        if len(result.confirmed) < count:
            linear = estimate()
    result.failure = failure
    result.trials = trials
    return result


class _RodPath:
    """`confirm_on_path` on a `fe_beam.solvers.rod_static.StaticContinuation`."""

    def __init__(self, run):
        self.run = run
        self.engine = run.engine()
        self.engine.parameter = float(run.load_factor)

    @property
    def load_factor(self) -> float:
        return float(self.run.load_factor)

    def snapshot(self):
        return self.engine.snapshot()

    def restore(self, snapshot) -> None:
        self.engine.restore(snapshot)
        self.run.load_factor = snapshot.parameter

    def advance(self, target: float, stepping, progress: bool) -> None:
        self.run.advance(target, stepping, progress=progress, label="path check")

    def unstable(self) -> int:
        return rod_unstable_count(self.run)

    def estimate(self, count: int) -> Buckling:
        return rod_buckling(self.run, count, self.load_factor, verify=False)


class _SolidPath(_RodPath):
    """`confirm_on_path` on a `fe_beam.analyses.solid.SolidRun` (tip force only)."""

    def __init__(self, run):
        self.run = run
        self.engine = run.problem.engine()
        self.engine.parameter = float(run.load_factor)

    def restore(self, snapshot) -> None:
        self.engine.restore(snapshot)
        self.run.load_factor = snapshot.parameter
        self.run.problem.set_load_factor(snapshot.parameter)

    def unstable(self) -> int:
        count = solid_unstable_count(self.run.problem)
        if count is None:
            raise BucklingFailed("the solid's stability is not available (a tensioned cable)")
        return count

    def estimate(self, count: int) -> Buckling:
        return solid_buckling(self.run, count, self.load_factor, verify=False)

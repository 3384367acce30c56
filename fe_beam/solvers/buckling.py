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
from fe_beam.solvers.inertia import InertiaFactor
from fe_beam.solvers.newton import SADDLE_POINT_WORKSPACE

__all__ = ["Buckling", "LinearisedProblem", "buckling_modes", "rod_buckling",
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


def buckling_modes(problem: LinearisedProblem, count: int) -> Buckling:
    """The ``count`` smallest buckling load factors above the current one, and their modes."""
    from slepc4py import SLEPc

    if count < 1:
        raise ValueError(f"[buckling] count must be >= 1, got {count}")
    trial = ufl.TrialFunction(problem.space)
    jacobian = problem.jacobian if problem.jacobian is not None else \
        ufl.derivative(problem.residual, problem.w, trial)
    jacobian_form = fem.form(jacobian)
    K = compat.assemble_matrix(jacobian_form, bcs=problem.bcs, diagonal=1.0)
    K.assemble()
    w1 = load_derivative(problem, K, jacobian_form)
    G = geometric_stiffness(problem, w1, jacobian)
    B = G.copy()
    B.scale(-1.0)  # K_T phi = mu (-K_geo) phi
    notes: list[str] = []
    fixed = compat.owned_bc_dofs(problem.bcs).astype(np.int64)
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
    if problem.conservative:
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
    if len(chosen) < count and not problem.conservative:
        notes.append(f"[buckling] count = {count}: only {len(chosen)} positive buckling load "
                     "factor(s) found (the loads may not compress the structure enough)")
    p = problem.load_factor
    passed = sorted(p + mu for mu in negative if 0 < p + mu < p)
    if passed:  # the prestate is past a critical point: the factors above p are not the first
        notes.append(f"[buckling] prestress = {p:g} is past the critical load factor "
                     f"{passed[0]:.6g} (in reversed_load_factors): the state linearised about "
                     "is beyond a bifurcation or limit of the path from 0, and load_factors "
                     "(above the prestress only) do not start with the first buckling load; "
                     "use a prestress below it")
    for index, (_, shape) in enumerate(chosen, start=1):
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
        conservative=conservative)


def rod_buckling(run, count: int, prestress: float = 0.0, stepping=None,
                 progress: bool = False) -> Buckling:
    """Buckling of the rod of ``run`` (a `fe_beam.analyses.static.StaticContinuation`): the state is
    first loaded to ``prestress`` (load stepping; `LoadSteppingFailed` if it is not reached)."""
    if prestress != run.load_factor:
        run.advance(prestress, stepping or run.config.stepping, progress=progress,
                    label="buckling pre-state")
    run._set_load_factor(float(run.load_factor))
    return buckling_modes(_rod_linearised(run), count)


# --- the 3D solid -------------------------------------------------------------------------------
def solid_buckling(run, count: int, prestress: float = 0.0, stepping=None,
                   progress: bool = False) -> Buckling:
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
    return buckling_modes(lin, count)


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

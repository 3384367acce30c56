"""Sparse, parallel inertia of a symmetric tangent (docs/theory.md, Sparse inertia).

Sylvester's law of inertia: the signs of the pivots of an LDL^T factorisation P A P^T = L D L^T
are those of the eigenvalues of A. MUMPS computes such a factorisation in parallel (PETSc's
Cholesky factor with MUMPS on a symmetric indefinite matrix, ``-mat_mumps_icntl_13 1`` so that
the root front is not split over ScaLAPACK and the global pivot counts are exact), and PETSc's
``MatGetInertia`` returns the (negative, zero, positive) counts.

- Dirichlet rows of the assembled tangent are identity rows: positive pivots, harmless.
- Constraint multipliers (a saddle point [[K, C^T], [C, 0]] with m independent constraint
  rows C): inertia(KKT) = inertia(Z^T K Z) + (m, 0, m), Z a basis of the null space of C
  (Gould 1985; Benzi, Golub & Liesen 2005, Sec. 3.4), so the count of energy-decreasing
  directions on the constraint-preserving directions is negative(KKT) - m.
- The u-p solid (pressure block -M/kappa negative definite): Haynsworth's inertia additivity,
  inertia(A) = inertia(-M/kappa) + inertia(Schur complement), so the count of the condensed
  displacement stiffness is negative(A) - (number of pressure dofs).
"""

from __future__ import annotations

import itertools

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.fem import compat

__all__ = ["InertiaFactor", "constraint_rows", "inertia", "rod_unstable_count",
           "solid_unstable_count"]

_PREFIXES = itertools.count()


def inertia(A: PETSc.Mat, symmetrize: bool = True) -> tuple[int, int, int]:
    """(negative, zero, positive) eigenvalue counts of the symmetric matrix ``A`` (any
    communicator; collective) from a MUMPS LDL^T factorisation. ``symmetrize``: factor
    (A + A^T)/2 (an assembled tangent is symmetric up to round-off; MUMPS reads one
    triangle). Zero counts are MUMPS's null pivots (``icntl 24``) and are only indicative:
    round-off makes a singular pivot small of either sign. One factorisation: counts of many
    matrices of one sparsity pattern should share an `InertiaFactor`."""
    factor = InertiaFactor()
    try:
        return factor.count(A, symmetrize)
    finally:
        factor.destroy()


class InertiaFactor:
    """Inertia counts of symmetric matrices of one sparsity pattern by one MUMPS LDL^T factor:
    the symbolic analysis once, a numerical factorisation per count (`count`, same answer as
    `inertia`). A matrix of another pattern starts the factor anew.

    Why: each MUMPS instance on several ranks keeps MPI communicators after it is destroyed
    (5 with PETSc 3.25 and MPICH, which allows 2048 per process), so a factor per count ran
    long parallel sessions (a path, a buckling search, a test suite) out of communicators."""

    SETTINGS = {"mat_mumps_icntl_13": 1, "mat_mumps_icntl_24": 1}

    def __init__(self):
        self._ksp: PETSc.KSP | None = None
        self._matrix: PETSc.Mat | None = None  # the factored operator (values copied in)
        self._pattern: tuple | None = None
        self._prefix = f"fe_beam_inertia_{next(_PREFIXES)}_"
        self.analyses = 0  # symbolic analyses made (one per pattern)

    def count(self, A: PETSc.Mat, symmetrize: bool = True) -> tuple[int, int, int]:
        """(negative, zero, positive) counts of ``A`` (see `inertia`). Collective."""
        B = _symmetric_part(A) if symmetrize else A
        try:
            pattern = _pattern_of(B)
            if self._matrix is not None and _same_pattern(self._pattern, pattern,
                                                          B.getComm().tompi4py()):
                B.copy(self._matrix, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
            else:
                self.destroy()
                self._matrix = B.copy()
                self._pattern = pattern
                self.analyses += 1
            self._matrix.setOption(PETSc.Mat.Option.SYMMETRIC, True)
            options = PETSc.Options()
            for key, value in self.SETTINGS.items():
                options[self._prefix + key] = value
            try:
                if self._ksp is None:
                    self._ksp = PETSc.KSP().create(self._matrix.getComm())
                    self._ksp.setOptionsPrefix(self._prefix)
                    self._ksp.setOperators(self._matrix)
                    self._ksp.setType("preonly")
                    pc = self._ksp.getPC()
                    pc.setType("cholesky")
                    pc.setFactorSolverType("mumps")
                    self._ksp.setFromOptions()
                # the same matrix with new values: PCSetUp refactors numerically only
                self._ksp.setOperators(self._matrix)
                self._ksp.setUp()
                negative, zero, positive = self._ksp.getPC().getFactorMatrix().getInertia()
            finally:
                for key in self.SETTINGS:
                    options.delValue(self._prefix + key)
        finally:
            if symmetrize:
                B.destroy()
        return int(negative), int(zero), int(positive)

    def destroy(self) -> None:
        """Free the factor (collective)."""
        if self._ksp is not None:
            self._ksp.destroy()
        if self._matrix is not None:
            self._matrix.destroy()
        self._ksp = self._matrix = self._pattern = None


def _symmetric_part(A: PETSc.Mat) -> PETSc.Mat:
    """(A + A^T)/2, a new matrix."""
    B = A.copy()
    T = A.transpose(PETSc.Mat())
    try:
        B.axpy(1.0, T, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    finally:
        T.destroy()
    B.scale(0.5)
    return B


def _pattern_of(A: PETSc.Mat) -> tuple:
    """This rank's sparsity pattern of ``A`` (sizes, owned rows, CSR indices)."""
    rows, columns, _ = A.getValuesCSR()
    return A.getSizes(), A.getOwnershipRange(), np.array(rows), np.array(columns)


def _same_pattern(old: tuple | None, new: tuple, comm) -> bool:
    """Whether ``old`` and ``new`` are the same pattern on every rank of ``comm``."""
    same = old is not None and old[:2] == new[:2] and all(
        a.shape == b.shape and np.array_equal(a, b) for a, b in zip(old[2:], new[2:], strict=True))
    return comm.allreduce(int(same), op=MPI.MIN) == 1


def constraint_rows(A: PETSc.Mat, multiplier_rows: np.ndarray) -> int:
    """Global count of the rows ``multiplier_rows`` (owned rows, global numbering) of ``A``
    that are constraint rows: a zero diagonal and a nonzero entry elsewhere (a Dirichlet
    row of a multiplier is an identity row and is not a constraint)."""
    count = 0
    start = A.getOwnershipRange()[0]
    rows, columns, values = A.getValuesCSR()
    for row in np.asarray(multiplier_rows, dtype=np.int64):
        local = int(row - start)
        span = slice(rows[local], rows[local + 1])
        cols, vals = columns[span], values[span]
        off = vals[cols != row]
        diagonal = vals[cols == row]
        if (diagonal.size == 0 or diagonal[0] == 0.0) and np.any(off != 0.0):
            count += 1
    return int(A.getComm().tompi4py().allreduce(count))


def factor_of(owner) -> InertiaFactor:
    """The `InertiaFactor` kept with ``owner`` (a problem: its tangents share one pattern)."""
    factor = getattr(owner, "_inertia_factor", None)
    if factor is None:
        factor = InertiaFactor()
        owner._inertia_factor = factor
    return factor


def rod_unstable_count(run) -> int:
    """Energy-decreasing directions of the rod's tangent at ``run``'s current state (a
    `fe_beam.analyses.static.StaticContinuation`, conservative loads): negative(KKT) minus the
    number
    of constraint rows. Collective; any number of ranks and dofs."""

    problem, nonlinear = run.problem, run.snes.problem
    state = compat.vector_of(nonlinear.w).copy()
    try:
        A = nonlinear.symmetric_tangent(state)  # with ties: P^T J P
    finally:
        state.destroy()
    owned = problem.space.dofmap.index_map.size_local * problem.space.dofmap.index_map_bs
    local = np.asarray(problem.multiplier_dofs())
    local = local[local < owned]
    start = A.getOwnershipRange()[0]
    m = constraint_rows(A, local + start)
    negative, _, _ = factor_of(nonlinear).count(A)
    return negative - m


def solid_unstable_count(problem) -> int | None:
    """Energy-decreasing directions of the 3D solid's potential at its current state
    (``problem``: a `fe_beam.solvers.solid.SolidFingerProblem`): the inertia of the Hessian of
    the UFL potential (Dirichlet rows identity), minus the pressure dofs of the u-p
    formulation (Haynsworth; with kappa = inf the pressure block is zero and the pressure
    dofs are the m constraint rows, the same subtraction). None while a cable is tensioned
    (its load stiffness is outside the UFL residual, as in
    `fe_beam.solvers.buckling.solid_buckling`).
    Collective; any number of ranks."""
    import ufl
    from dolfinx import fem


    if any(c.tension != 0 for c in problem.cables):
        return None
    form = getattr(problem, "_inertia_hessian", None)
    if form is None:
        form = fem.form(ufl.derivative(problem.residual, problem.w,
                                       ufl.TrialFunction(problem.W)))
        problem._inertia_hessian = form
    A = compat.assemble_matrix(form, bcs=problem.bcs)
    A.assemble()
    try:
        negative, _, _ = factor_of(problem).count(A)
    finally:
        A.destroy()
    pressure = 0
    if problem.p is not None:
        space = problem.W
        owned = space.dofmap.index_map.size_local * space.dofmap.index_map_bs
        dofs = np.asarray(compat.sub_space_collapsed(space, 1)[1])
        pressure = problem.comm.allreduce(int(np.sum(dofs < owned)))
    return negative - pressure

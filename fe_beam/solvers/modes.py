"""Natural frequencies and mode shapes of the beam linearised about its current state.

K x = omega^2 M x with K the tangent of the static residual at ``problem.w`` (the undeformed
state, or a prestressed static solution) and M the consistent mass (rho A on u, v; rho I on
theta). Dirichlet rows (K: 1 on the diagonal, M: 0) and multiplier rows (M: 0) give infinite
eigenvalues, far from the shift-and-invert target (SLEPc, MUMPS).

Nothing at the low end of the spectrum is dropped:

* **Rigid-body modes** (free translations / rotation the supports leave, e.g. 3 for a free-free
  planar beam, 1 for pinned-free) have omega^2 = 0 exactly; numerically their eigenvalue is
  round-off, whose size grows with the stiffness of the model (at L/h = 1e4 and 1000 elements it
  reaches ~1e-3 of the first elastic eigenvalue, of either sign). They are therefore recognised
  by their *shape*, not by a threshold on the eigenvalue: the span of the rigid motions of the
  current state that the supports leave free (translations (1, 0, 0), (0, 1, 0) and the rotation
  (-v, x + u, 1)), whose dimension n_rigid = 3 - rank of the supports is known. The n_rigid
  computed modes with the largest M-share in that span are the rigid-body modes, reported at
  0 Hz.
* **Unstable directions**: omega^2 < -ZERO_TOLERANCE * lambda_ref, with
  lambda_ref = int EI dx / (int rho A dx L^4) the beam's own bending eigenvalue unit (every
  elastic eigenvalue of an unstressed beam is >= 12.36 lambda_ref, the cantilever's
  1.8751^4) and ZERO_TOLERANCE = 1e-6: a state whose lowest eigenvalue lies within a millionth of
  the bending scale of zero is neutral (critical), not unstable. Their number is first counted
  exactly by Sylvester's law of inertia (LDL^T of K - sigma M with MUMPS, minus one negative
  pivot per multiplier row) and the shift sigma is lowered until no eigenvalue lies below it,
  so that shift-and-invert returns the lowest eigenvalues in order, the negative ones included.
  (With free rigid motions the state is the unloaded one, a static pre-state needing supports:
  the inertia would count their round-off, so the non-rigid negative pairs found are counted.
  With follower loads K is not symmetric: no inertia, the pairs found are counted.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.fem.mpi import assemble_scalar, global_max, global_sum
from fe_beam.fem.rod import BeamProblem
from fe_beam.solvers.newton import SADDLE_POINT_WORKSPACE, Ties

__all__ = ["Modes", "UnstableMode", "natural_frequencies", "ZERO_TOLERANCE"]

ZERO_TOLERANCE = 1e-6  # |omega^2| below this times EI / (rho A L^4) counts as zero
MAX_UNSTABLE = 100  # unstable modes computed and written (all are counted)


@dataclass
class UnstableMode:
    """A direction in which the state is unstable: omega^2 = eigenvalue < 0, so a small
    perturbation grows like exp(growth_rate t), growth_rate = sqrt(-eigenvalue) [1/s]."""

    eigenvalue: float
    shape: fem.Function
    transverse_fraction: float
    # imaginary part of omega^2 (non-symmetric stiffness, follower loads): a complex pair
    # omega^2 = a +- i b, b != 0, is flutter: one root omega has Im < 0, the motion grows
    eigenvalue_imag: float = 0.0

    @property
    def growth_rate(self) -> float:
        """The largest |Im omega| of omega^2 = eigenvalue + i eigenvalue_imag [1/s]."""
        if self.eigenvalue_imag:
            return abs((complex(self.eigenvalue, self.eigenvalue_imag) ** 0.5).imag)
        return math.sqrt(max(-self.eigenvalue, 0.0))

    @property
    def kind(self) -> str:
        return "flutter" if self.eigenvalue_imag else "divergence"


@dataclass
class Modes:
    """Frequencies (Hz, ascending: rigid-body modes first at 0 Hz), shapes (max |dof| = 1) and,
    per mode, the share of its translational kinetic energy that is transverse: ~1 for bending,
    ~0 for axial modes. ``unstable`` lists the directions with omega^2 < 0 (most negative first),
    which have no frequency; ``unstable_count`` counts them all (only the first MAX_UNSTABLE are
    computed)."""

    frequencies_hz: list[float]
    shapes: list[fem.Function]
    transverse_fraction: list[float]
    eigenvalues: list[float] = field(default_factory=list)
    kinds: list[str] = field(default_factory=list)
    rigid_body_modes: int = 0
    unstable: list[UnstableMode] = field(default_factory=list)
    unstable_count: int = 0
    notes: list[str] = field(default_factory=list)
    #: per mode, the shares of its mass norm by family (`BeamProblem.mode_shares`; spatial
    #: rods: axial, torsion, bending about y, bending about z, and "transverse")
    shares: list[dict] = field(default_factory=list)
    #: per reported mode, ||K x - lambda M x|| / (||K x|| + |lambda| ||M x||) (`eigenpair_residual`)
    residuals: list[float] = field(default_factory=list)
    #: the largest normalised |x_i^T M x_j| of the reported modes (`mass_orthogonality`); None
    #: for a non-symmetric pencil (follower loads), whose modes are not M-orthogonal
    orthogonality: float | None = None

    def bending(self) -> list[float]:
        """Frequencies of the elastic modes that are mainly transverse (bending)."""
        kinds = self.kinds or ["elastic"] * len(self.frequencies_hz)
        return [f for f, share, kind in zip(self.frequencies_hz, self.transverse_fraction, kinds,
                                            strict=True)
                if share > 0.5 and kind != "rigid" and kind != "torsion"]


def mass_form(problem: BeamProblem):
    """The problem's mass about its current state (`BeamProblem.mass_form`: rho A on u, v,
    rho I on theta; the spatial rod's: rho A and T(-theta)^T rho J T(-theta))."""
    return problem.mass_form()


def bending_eigenvalue_unit(problem: BeamProblem) -> float:
    """lambda_ref = int EI dx / (int rho A dx L^4) [1/s^2]: Omega^2 = omega^2 / lambda_ref."""
    EI = assemble_scalar(fem.form(problem.bending_stiffness() * ufl.dx))
    rho_area = assemble_scalar(fem.form(problem.rho * problem.section_props.A * ufl.dx))
    return EI / (rho_area * problem.model.length**4)


def natural_frequencies(problem: BeamProblem, count: int) -> Modes:
    """The ``count`` lowest natural frequencies (Hz, ascending; rigid-body modes at 0 Hz, all of
    them even beyond ``count``), normalised mode shapes, and every unstable direction."""
    from slepc4py import SLEPc

    if problem.model.material.rho <= 0:
        raise ValueError("modal analysis needs material.rho > 0")
    jacobian = ufl.derivative(problem.residual, problem.w, ufl.TrialFunction(problem.space))
    stiffness_form, mass = fem.form(jacobian), fem.form(mass_form(problem))
    K = compat.assemble_matrix(stiffness_form, bcs=problem.bcs, diagonal=1.0)
    K.assemble()
    M = compat.assemble_matrix(mass, bcs=problem.bcs, diagonal=0.0)
    M.assemble()
    ties, slaves = _structure_ties(problem, K)
    if ties is not None:  # joints as ties: the reduced pencil P^T K P, P^T M P
        reduced_K, reduced_M = ties.reduced(K).copy(), M.PtAP(ties.P)
        K.destroy()
        M.destroy()
        K, M = reduced_K, reduced_M
    notes: list[str] = []
    scale = bending_eigenvalue_unit(problem)
    zero = ZERO_TOLERANCE * scale
    rigid = _rigid_motions(problem, K, M, slaves)
    symmetric = not problem.nonpotential_loads and _is_symmetric(K)
    unstable_count, sigma = None, -scale
    if symmetric:
        counter = _EigenvalueCounter(problem, K, M)
        if not rigid:
            # with free rigid motions the state is the unloaded one (a static pre-state needs
            # supports) and their round-off eigenvalues, of either sign, would be counted
            unstable_count = counter.below(-zero)
        for _ in range(60):  # lower the shift until no eigenvalue lies below it
            if counter.below(sigma) == 0:
                break
            sigma *= 4.0
    else:
        notes.append(f"the stiffness is not symmetric ({nonsymmetric_reason(problem)}): "
                     "unstable directions are those the eigensolver finds, not counted by "
                     "inertia")
    wanted_unstable = min(unstable_count, MAX_UNSTABLE) if unstable_count is not None else 0
    pairs = []
    fixed = np.concatenate([compat.owned_bc_dofs(problem.bcs).astype(np.int64), slaves])
    extra = uncounted = 0
    for _attempt in range(4):
        nev = count + len(rigid) + wanted_unstable + extra + uncounted
        pairs, imaginary = _solve(SLEPc, K, M, sigma, nev, fixed, problem, symmetric)
        found_unstable = sum(1 for value, _ in pairs if value < -zero)
        # without the inertia count (non-symmetric K) the unstable pairs found, complex
        # (flutter) ones included, take places of the `count` frequencies: solve again
        # with that many more
        found_uncounted = len(imaginary) + (found_unstable if unstable_count is None else 0)
        if found_uncounted > uncounted:
            uncounted = found_uncounted
            continue
        if unstable_count is None or found_unstable >= wanted_unstable:
            break
        extra = 2 * extra + 10  # a missed negative eigenvalue: widen the search
    # complex pairs omega^2 = a +- i b (follower loads past the flutter load): one unstable
    # (flutter) mode per pair, never listed as a frequency (each pair: keep the b > 0 member)
    # With a symmetric K (conservative loads) the eigenvalues are real: a complex pair there
    # is an artefact of the singular mass (multiplier and Dirichlet rows), high in the
    # spectrum: dropped, with a note.
    flutter = {id(shape) for _, shape in pairs if imaginary.get(id(shape), 0.0) > 0}
    if symmetric and not rigid:
        # the shift lies below every eigenvalue (counted by inertia): a pair below it is an
        # artefact of the singular mass too (rigid modes' round-off may lie anywhere near 0)
        pairs = [(value, shape) for value, shape in pairs if value >= sigma * (1 + 1e-9)]
    if symmetric and flutter:
        notes.append(f"{len(flutter)} complex eigenvalue pair(s) of the symmetric problem "
                     "(spurious, from the singular mass of the constraint rows) were left out")
        flutter = set()
    pairs = [(value, shape) for value, shape in pairs if imaginary.get(id(shape), 0.0) == 0
             or id(shape) in flutter]
    shares = {id(shape): _rigid_share(shape, rigid, M) for _, shape in pairs}
    for vector in rigid:
        vector.destroy()
    is_rigid = set()
    if rigid:
        ranked = sorted(pairs, key=lambda pair: -shares[id(pair[1])])[: len(rigid)]
        for _value, shape in ranked:
            if shares[id(shape)] > 0.5:
                is_rigid.add(id(shape))
        if len(is_rigid) < len(rigid):
            notes.append(f"the supports leave {len(rigid)} rigid-body motions but only "
                         f"{len(is_rigid)} were found among the computed modes")
    def unstable_pair(value, shape) -> bool:
        return id(shape) in flutter or (value < -zero and id(shape) not in is_rigid)

    found_unstable = sum(1 for value, shape in pairs if unstable_pair(value, shape))
    if unstable_count is None:
        unstable_count = found_unstable
        if found_unstable and problem.multipliers:
            # known limitation: the non-symmetric pencil with the singular mass of the
            # multiplier rows can return spurious negative or complex eigenvalues when many
            # modes are asked for; they are kept (a false alarm rather than a hidden one)
            notes.append(f"the non-symmetric eigenproblem ({nonsymmetric_reason(problem)}) "
                         "with constraint multipliers may report spurious unstable modes "
                         "(more so for large "
                         "[modes] count); confirm them with a smaller count or constraint = "
                         "\"none\"")
    elif found_unstable < wanted_unstable:
        notes.append(f"the inertia counts {unstable_count} unstable directions but the "
                     f"eigensolver found {found_unstable}")
    for _, shape in pairs:
        _normalise(problem, shape)
    reduced = {}
    if ties is not None:  # the shapes of every dof (the slaves their masters' values)
        for _, shape in pairs:
            reduced[id(shape)] = fem.Function(problem.space)
            compat.vector_of(shape).copy(compat.vector_of(reduced[id(shape)]))
            ties.prolong(compat.vector_of(shape))
            compat.vector_of(shape).ghostUpdate(addv=PETSc.InsertMode.INSERT,
                                                mode=PETSc.ScatterMode.FORWARD)

    def pencil_vector(shape):  # the vector of the (reduced) pencil
        return reduced.get(id(shape), shape)
    unstable = [UnstableMode(value, shape, _transverse_share(problem, shape),
                             imaginary.get(id(shape), 0.0))
                for value, shape in pairs if unstable_pair(value, shape)]
    unstable.sort(key=lambda mode: -mode.growth_rate)
    unstable = unstable[:MAX_UNSTABLE]
    for index, mode in enumerate(unstable, start=1):
        mode.shape.name = f"unstable_{index}"
    rigid_pairs = [(0.0, shape) for _, shape in pairs if id(shape) in is_rigid]
    elastic = [(max(value, 0.0), shape) for value, shape in pairs
               if not unstable_pair(value, shape) and id(shape) not in is_rigid]
    if any(value <= zero for value, _ in elastic[:count]):
        notes.append("an eigenvalue is zero within the tolerance (a neutral, critical direction: "
                     "the state is at a stability limit)")
    chosen = rigid_pairs + elastic[: max(count - len(rigid_pairs), 0)]
    for index, (_, shape) in enumerate(chosen, start=1):
        shape.name = f"mode_{index}"
    kinds = []
    family_shares = [problem.mode_shares(shape) for _, shape in chosen]
    transverse = [share["transverse"] for share in family_shares]
    for (_value, shape), share in zip(chosen, family_shares, strict=True):
        kinds.append("rigid" if id(shape) in is_rigid else problem.mode_kind(share))
    frequencies = [math.sqrt(value) / (2 * math.pi) for value, _ in chosen]
    computed = {id(shape): value for value, shape in pairs}
    residuals = [eigenpair_residual(K, M, computed[id(shape)], pencil_vector(shape),
                                    rigid=id(shape) in is_rigid) for _, shape in chosen]
    orthogonality = (mass_orthogonality(M, [pencil_vector(shape) for _, shape in chosen])
                     if symmetric else None)

    K.destroy()
    M.destroy()
    return Modes(frequencies, [s for _, s in chosen], transverse,
                 eigenvalues=[value for value, _ in chosen], kinds=kinds,
                 rigid_body_modes=len(rigid_pairs), unstable=unstable,
                 unstable_count=int(unstable_count), notes=notes, shares=family_shares,
                 residuals=residuals, orthogonality=orthogonality)


def _structure_ties(problem: BeamProblem, K: PETSc.Mat) -> tuple:
    """(`Ties` of a structure's joints that are not shared vertices, or None; the owned local
    indices of their slave dofs)."""
    chain = getattr(problem, "chain", None)
    pairs = chain.tie_pairs() if chain is not None else np.zeros((0, 2), dtype=np.int64)
    if not len(pairs):
        return None, np.zeros(0, dtype=np.int64)
    vector = K.createVecLeft()
    ties = Ties(pairs, vector)
    vector.destroy()
    start, end = K.getOwnershipRange()
    slaves = pairs[:, 0]
    return ties, (slaves[(slaves >= start) & (slaves < end)] - start).astype(np.int64)


def eigenpair_residual(K: PETSc.Mat, M: PETSc.Mat, value: float, shape: fem.Function,
                       rigid: bool = False) -> float:
    """||K x - lambda M x|| / (||K x|| + |lambda| ||M x||) of one eigenpair, lambda the
    eigenvalue the eigensolver returned: a run-time certificate of the pair, independent of
    the eigensolver's own convergence test (0 when x is zero). A ``rigid`` mode (K x and lambda
    both round-off) is measured by its backward error ||K x - lambda M x|| / ((||K|| + |lambda|
    ||M||) ||x||) instead (infinity norms): against the matrices' scale, not its own."""
    x = compat.vector_of(shape)
    kx, mx = K.createVecLeft(), M.createVecLeft()
    K.mult(x, kx)
    M.mult(x, mx)
    if rigid:
        infinity = PETSc.NormType.INFINITY
        scale = (K.norm(infinity) + abs(value) * M.norm(infinity)) * x.norm(infinity)
    else:
        scale = kx.norm() + abs(value) * mx.norm()
    kx.axpy(-value, mx)
    residual = kx.norm(PETSc.NormType.INFINITY) if rigid else kx.norm()
    kx.destroy()
    mx.destroy()
    return float(residual / scale) if scale > 0 else 0.0


def mass_orthogonality(M: PETSc.Mat, shapes: list[fem.Function]) -> float:
    """max over i != j of |x_i^T M x_j| / sqrt(x_i^T M x_i x_j^T M x_j) of the given modes: the
    M-orthogonality the eigenvectors of a symmetric pencil have (0 for fewer than two)."""
    vectors = [compat.vector_of(shape) for shape in shapes]
    products = []
    for x in vectors:
        mx = M.createVecLeft()
        M.mult(x, mx)
        products.append(mx)
    n = len(vectors)
    gram = np.array([[vectors[i].dot(products[j]) for j in range(n)] for i in range(n)])
    for mx in products:
        mx.destroy()
    worst = 0.0
    for i in range(n):
        for j in range(i + 1, n):
            norm = math.sqrt(abs(gram[i, i] * gram[j, j]))
            if norm > 0:
                worst = max(worst, abs(gram[i, j]) / norm)
    return float(worst)


def _solve(SLEPc, K, M, sigma, nev, fixed, problem, symmetric=False):
    """Eigenpairs nearest the shift ``sigma`` (below every eigenvalue: the lowest ones),
    ascending, without the spurious pairs of the Dirichlet rows.

    A symmetric K is solved as a generalised Hermitian problem: with the singular mass
    (Dirichlet and multiplier rows) the non-Hermitian solver returns wrong eigenvalues high in
    the spectrum (e.g. the 45th-50th of a constrained column off by 1-15 %, and different on
    1 and 2 ranks), the Hermitian one with SLEPc's purification the exact ones."""
    eps = SLEPc.EPS().create(problem.comm)
    eps.setOptionsPrefix("fe_beam_modes_")
    eps.setOperators(K, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP if symmetric
                       else SLEPc.EPS.ProblemType.GNHEP)
    eps.setDimensions(nev, max(2 * nev + 1, nev + 10))
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTarget(sigma)
    transform = eps.getST()
    transform.setType(SLEPc.ST.Type.SINVERT)
    transform.setShift(sigma)
    ksp = transform.getKSP()
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    if problem.saddle_point:  # multiplier rows: pivoting beyond MUMPS's default workspace
        option, percent = SADDLE_POINT_WORKSPACE
        PETSc.Options()[f"fe_beam_modes_st_{option}"] = percent
    eps.setTolerances(1e-12, 200)
    eps.setFromOptions()
    eps.solve()
    pairs, imaginary = [], {}
    vector = K.createVecRight()
    for i in range(eps.getConverged()):
        value = complex(eps.getEigenpair(i, vector))
        if math.isfinite(value.real) and not _lives_on_fixed_dofs(vector, fixed):
            shape = fem.Function(problem.space)
            vector.copy(compat.vector_of(shape))
            compat.vector_of(shape).ghostUpdate(addv=PETSc.InsertMode.INSERT,
                                                mode=PETSc.ScatterMode.FORWARD)
            pairs.append((value.real, shape))
            if value.imag != 0.0:  # a complex pair (only with a non-symmetric K)
                imaginary[id(shape)] = value.imag
    vector.destroy()
    eps.destroy()
    pairs.sort(key=lambda pair: pair[0])
    return pairs, imaginary


class _EigenvalueCounter:
    """Number of eigenvalues of K x = lambda M x below sigma (Sylvester): the negative pivots of
    an LDL^T factorisation of K - sigma M (MUMPS), minus one per multiplier row (a saddle point
    with m independent constraint rows has m more negative eigenvalues than the stiffness
    restricted to the constraints), the Dirichlet rows (1 on the diagonal) adding none."""

    def __init__(self, problem: BeamProblem, K: PETSc.Mat, M: PETSc.Mat):
        self.K, self.M, self.comm = K, M, problem.comm
        multipliers = problem.multiplier_dofs()
        owned = problem.space.dofmap.index_map.size_local * problem.space.dofmap.index_map_bs
        self.multipliers = int(global_sum(problem.comm, np.sum(multipliers < owned)))

    def below(self, sigma: float) -> int:
        shifted = self.K.copy()
        shifted.axpy(-sigma, self.M, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        shifted.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        pc = PETSc.PC().create(self.K.getComm())
        try:
            pc.setOperators(shifted)
            pc.setType("cholesky")
            pc.setFactorSolverType("mumps")
            pc.setFactorSetUpSolverType()
            factor = pc.getFactorMatrix()
            factor.setMumpsIcntl(13, 1)  # global inertia on more than one rank
            factor.setMumpsIcntl(24, 1)  # null pivots counted apart (PETSc requires it)
            if self.multipliers:  # pivoting beyond MUMPS's default workspace estimate
                factor.setMumpsIcntl(14, SADDLE_POINT_WORKSPACE[1])
            pc.setUp()
            negative, _, _ = factor.getInertia()
        finally:
            pc.destroy()
            shifted.destroy()
        return max(int(negative) - self.multipliers, 0)


def nonsymmetric_reason(problem) -> str:
    """What makes the stiffness of ``problem`` non-symmetric, in words: a follower force, a
    spatial rod's dead moment (its virtual work M . T(theta) dtheta has no potential), a
    non-potential load of a coupled model, or (none of those) the assembled matrix itself."""
    loads = problem.model.loads
    reasons = []
    if loads.follower:
        reasons.append("a follower tip load")
    if getattr(problem, "spatial", False) and getattr(problem, "moment_loads", False) \
            and not loads.follower:
        reasons.append("a dead moment on a spatial rod: its work M . T(theta) dtheta has no "
                       "potential")
    if getattr(problem, "extra_work", None) is not None:
        reasons.append("contact friction")
    return "; ".join(reasons) or "the assembled tangent is not symmetric"


def _is_symmetric(K: PETSc.Mat) -> bool:
    transpose = K.copy()
    transpose.transpose()
    transpose.axpy(-1.0, K)
    asymmetry, size = transpose.norm(PETSc.NormType.FROBENIUS), K.norm(PETSc.NormType.FROBENIUS)
    transpose.destroy()
    return asymmetry <= 1e-10 * size


def _rigid_motions(problem: BeamProblem, K: PETSc.Mat, M: PETSc.Mat,
                   slaves: np.ndarray = ()) -> list[PETSc.Vec]:
    """M-orthonormal basis of the infinitesimal rigid motions of the current state that the
    supports leave free and that cost no energy (`BeamProblem.rigid_motion_candidates`: planar
    translations (1, 0, 0), (0, 1, 0) and the rotation about the origin (-v, x + u, 1);
    the spatial rod's three translations and three rotations; multipliers unchanged)."""
    candidates = [compat.vector_of(f).copy() for f in problem.rigid_motion_candidates()]
    for candidate in candidates:  # tied slaves: their masters carry them (reduced vectors)
        candidate.getArray()[np.asarray(slaves, dtype=np.int64)] = 0.0
    fixed = compat.owned_bc_dofs(problem.bcs).astype(np.int64)
    # combinations that vanish on the fixed dofs: null space of the (gathered) fixed values
    rows = np.array([c.getArray(readonly=True)[fixed] for c in candidates]).T
    gathered = problem.comm.allgather(rows)
    rows = np.vstack([r for r in gathered if r.size]) if any(r.size for r in gathered) \
        else np.zeros((0, len(candidates)))
    if rows.shape[0]:
        import scipy.linalg

        combinations = scipy.linalg.null_space(rows, rcond=1e-10)
    else:
        combinations = np.eye(len(candidates))
    basis = []
    work, image = K.createVecRight(), K.createVecRight()
    diagonal = K.getDiagonal()
    diagonal.abs()
    for column in combinations.T:
        vector = K.createVecRight()
        vector.set(0.0)
        for weight, candidate in zip(column, candidates, strict=True):
            vector.axpy(weight, candidate)
        # zero energy? |r.K r| against the diagonal's r.|diag K| r (round-off scale)
        K.mult(vector, image)
        energy = abs(vector.dot(image))
        work.pointwiseMult(diagonal, vector)
        if energy > 1e-8 * abs(vector.dot(work)):
            vector.destroy()
            continue
        for other in basis:  # Gram-Schmidt in the M inner product
            M.mult(other, work)
            vector.axpy(-vector.dot(work), other)
        M.mult(vector, work)
        norm = math.sqrt(max(vector.dot(work), 0.0))
        if norm > 0:
            vector.scale(1.0 / norm)
            basis.append(vector)
    for c in candidates:
        c.destroy()
    work.destroy()
    image.destroy()
    diagonal.destroy()
    return basis


def _rigid_share(shape: fem.Function, rigid: list[PETSc.Vec], M: PETSc.Mat) -> float:
    """Share of the shape's M-norm^2 in the span of the (M-orthonormal) rigid motions."""
    if not rigid:
        return 0.0
    x = compat.vector_of(shape)
    mx = M.createVecLeft()
    M.mult(x, mx)
    total = x.dot(mx)
    share = sum(r.dot(mx) ** 2 for r in rigid)
    mx.destroy()
    return share / total if total > 0 else 0.0


def _normalise(problem: BeamProblem, shape: fem.Function) -> None:
    array = compat.local_array(shape)
    scale = global_max(problem.comm, np.max(np.abs(array), initial=0.0))
    if scale > 0:
        array /= scale


def _lives_on_fixed_dofs(vector: PETSc.Vec, fixed: np.ndarray) -> bool:
    """A spurious pair of the Dirichlet rows (K: identity, M: zero): a true mode vanishes on
    the fixed dofs, this one is mostly there."""
    array = vector.getArray(readonly=True)
    on_fixed, total = global_sum(vector.getComm().tompi4py(),
                                 np.array([np.sum(array[fixed] ** 2), np.sum(array**2)]))
    return on_fixed > 1e-6 * total


def _transverse_share(problem: BeamProblem, shape: fem.Function) -> float:
    return problem.mode_shares(shape)["transverse"]

"""3D modal analysis of the solid (``[modes]`` in a ``fe-beam solid`` configuration).

K x = omega^2 M x with K the tangent stiffness of the solid's residual (cables included) at the
undeformed state or at the final loaded state of the sweep, and M the consistent mass
int rho u . v dX on the displacement (none on the pressure of the u-p formulation). As for the
rod (`fe_beam.solvers.modes`): Dirichlet rows have 1 on K's diagonal and 0 on M's, so their
eigenvalues
are infinite, far from the shift-and-invert target (SLEPc, generalised Hermitian, MUMPS); a
computed pair that lives on the fixed dofs is dropped all the same.

u-p formulation: the pressure rows of M are zero, so the pressure is eliminated by the pencil
itself: a finite eigenvalue's pressure is p = C^-1 K_pu u (C the pressure compliance matrix) and
its omega^2 is that of the condensed stiffness K_uu + K_up C^-1 K_pu; the pressure rows only
add infinite eigenvalues. K is then indefinite (one negative eigenvalue per pressure dof):
unstable directions are counted by Sylvester's law of inertia on K (MUMPS LDL^T), minus the
pressure dofs. A loaded state with a direction of omega^2 < 0 is reported (``unstable_count``,
a note); the frequencies listed are the lowest positive ones.

Each mode is labelled by the share of its kinetic energy (int rho |u|^2) in axial motion (u_x),
bending in the x-y plane (u_y: the rod's plane), bending in the x-z plane (u_z) and torsion:
the kinetic energy of the rotation about the x axis, int rho (y^2 + z^2) (curl(u)_x / 2)^2,
which equals the whole energy for a rigid rotation of every section and vanishes for bending
and axial motion. Torsion above 1/2 gives "torsion", else the largest of the three others
("axial", "bending_y", "bending_z").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.fem.mpi import assemble_scalar
from fe_beam.solvers.modes import _is_symmetric, _lives_on_fixed_dofs
from fe_beam.solvers.newton import SADDLE_POINT_WORKSPACE

__all__ = ["ROD_LAWS", "SolidModes",
           "solid_natural_frequencies"]

ROD_LAWS = ("nonstandard", "reissner")
KINDS = ("axial", "bending_y", "bending_z", "torsion")


@dataclass
class SolidModes:
    """The ``count`` lowest natural frequencies (Hz, ascending) of the solid, their eigenvalues
    omega^2, kinds and kinetic-energy shares, the displacement shapes (max |u| = 1) and the
    number of unstable directions (omega^2 < 0, counted by inertia)."""

    frequencies_hz: list[float]
    eigenvalues: list[float]
    kinds: list[str]
    shares: list[dict]
    shapes: list[fem.Function]
    unstable_count: int = 0
    unstable_eigenvalues: list[float] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def _mass_form(problem, rho: float):
    trial, test = ufl.TrialFunction(problem.W), ufl.TestFunction(problem.W)
    if problem.p is not None:
        trial, test = ufl.split(trial)[0], ufl.split(test)[0]
    density = fem.Constant(problem.mesh, PETSc.ScalarType(rho))
    return density * ufl.inner(trial, test) * problem.dx


def solid_natural_frequencies(problem, count: int, rho: float,
                              undeformed: bool = False) -> SolidModes:
    """The ``count`` lowest natural frequencies and mode shapes of the `SolidFingerProblem`
    ``problem`` linearised about its current state (``undeformed``: about u = 0 with every
    load off; the state and load factor are restored). Collective."""
    from slepc4py import SLEPc

    if not rho > 0:
        raise ValueError("modal analysis needs material.rho > 0")
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count!r}")
    state = compat.vector_of(problem.w)
    saved_state, saved_factor = state.copy(), problem.load_factor
    saved_tensions = [cable.tension for cable in problem.cables]
    nonlinear = problem.problem
    try:
        if undeformed:
            state.set(0.0)
            state.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            problem.set_load_factor(0.0)
            for cable in problem.cables:  # pull-in control keeps its tension otherwise
                cable.tension = 0.0
        nonlinear.jacobian(None, state, nonlinear.A, nonlinear.A)
        K = nonlinear.A.copy()
    finally:
        saved_state.copy(state)
        state.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        problem.set_load_factor(saved_factor)
        for cable, tension in zip(problem.cables, saved_tensions, strict=True):
            cable.tension = tension
        saved_state.destroy()
    M = compat.assemble_matrix(fem.form(_mass_form(problem, rho)), bcs=problem.bcs,
                               diagonal=0.0)
    M.assemble()
    notes: list[str] = []

    symmetric = _is_symmetric(K)
    mixed = problem.p is not None
    pressure_dofs = 0
    if mixed:
        pressure_space = compat.sub_space_collapsed(problem.W, 1)[0]
        pressure_dofs = int(pressure_space.dofmap.index_map.size_global)
    unstable = 0
    if symmetric:
        if not undeformed:
            # (undeformed and clamped, K is linear elasticity's: positive definite on u
            # (Korn), one negative eigenvalue per pressure dof in u-p; nothing to count)
            unstable = max(_negative_pivots(K, mixed) - pressure_dofs, 0)
    else:  # not expected (dead tip force, cables of given tension: conservative)
        notes.append("the tangent stiffness is not symmetric: solved as a non-Hermitian problem, "
                     "unstable directions not counted")
    fixed = compat.owned_bc_dofs(problem.bcs).astype(np.int64)
    pairs = _solve(SLEPc, K, M, count + unstable, fixed, problem, symmetric,
                   _lives_on_fixed_dofs)
    K.destroy()
    M.destroy()
    negative = [value for value, _ in pairs if value < 0]
    positive = [(value, shape) for value, shape in pairs if value >= 0][:count]
    if unstable:
        notes.insert(0, f"the state is unstable: {unstable} direction(s) with omega^2 < 0 "
                        "(counted by inertia); the frequencies are the lowest positive ones")
    shapes, shares, kinds = [], [], []
    energy = _EnergyShares(problem, rho)
    for index, (_, shape) in enumerate(positive, start=1):
        displacement = shape.sub(0).collapse() if mixed else shape
        _normalise(displacement)
        displacement.name = f"mode_{index}"
        share = energy(displacement)
        shapes.append(displacement)
        shares.append(share)
        kinds.append(_kind(share))
    if len(positive) < count:
        notes.append(f"[modes] count = {count} asked for more modes than were found "
                     f"({len(positive)})")
    return SolidModes(
        frequencies_hz=[math.sqrt(value) / (2 * math.pi) for value, _ in positive],
        eigenvalues=[float(value) for value, _ in positive],
        kinds=kinds, shares=shares, shapes=shapes, unstable_count=int(unstable),
        unstable_eigenvalues=[float(v) for v in negative], notes=notes,
    )


def _solve(SLEPc, K, M, nev, fixed, problem, symmetric, lives_on_fixed):
    """Eigenpairs of K x = lambda M x nearest 0 (shift-and-invert), ascending, without the
    spurious ones of the Dirichlet rows; asks for more until ``nev`` are found."""
    pairs = []
    wanted = nev
    for _attempt in range(3):
        eps = SLEPc.EPS().create(problem.comm)
        eps.setOptionsPrefix("fe_beam_solid_modes_")
        eps.setOperators(K, M)
        eps.setProblemType(SLEPc.EPS.ProblemType.GHEP if symmetric
                           else SLEPc.EPS.ProblemType.GNHEP)
        eps.setDimensions(wanted, max(2 * wanted + 1, wanted + 15))
        eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
        eps.setTarget(0.0)
        transform = eps.getST()
        transform.setType(SLEPc.ST.Type.SINVERT)
        transform.setShift(0.0)
        ksp = transform.getKSP()
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
        if problem.p is not None:  # saddle point: pivoting beyond MUMPS's default workspace
            option, percent = SADDLE_POINT_WORKSPACE
            PETSc.Options()[f"fe_beam_solid_modes_st_{option}"] = percent
        eps.setTolerances(1e-10, 300)
        eps.setFromOptions()
        eps.solve()
        pairs = []
        vector = K.createVecRight()
        for i in range(eps.getConverged()):
            value = complex(eps.getEigenpair(i, vector))
            if not math.isfinite(value.real) or lives_on_fixed(vector, fixed):
                continue
            shape = fem.Function(problem.W)
            vector.copy(compat.vector_of(shape))
            compat.vector_of(shape).ghostUpdate(addv=PETSc.InsertMode.INSERT,
                                                mode=PETSc.ScatterMode.FORWARD)
            pairs.append((value.real, shape))
        vector.destroy()
        eps.destroy()
        if len(pairs) >= nev:
            break
        wanted += nev - len(pairs) + 5
    pairs.sort(key=lambda pair: pair[0])
    return pairs


def _negative_pivots(K: PETSc.Mat, mixed: bool) -> int:
    """Negative eigenvalues of the symmetric K (Sylvester: negative pivots of LDL^T, MUMPS)."""
    matrix = K.copy()
    matrix.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    pc = PETSc.PC().create(K.getComm())
    try:
        pc.setOperators(matrix)
        pc.setType("cholesky")
        pc.setFactorSolverType("mumps")
        pc.setFactorSetUpSolverType()
        factor = pc.getFactorMatrix()
        factor.setMumpsIcntl(13, 1)  # global inertia on more than one rank
        factor.setMumpsIcntl(24, 1)  # null pivots counted apart (PETSc requires it)
        if mixed:
            factor.setMumpsIcntl(14, SADDLE_POINT_WORKSPACE[1])
        pc.setUp()
        negative, _, _ = factor.getInertia()
    finally:
        pc.destroy()
        matrix.destroy()
    return int(negative)


def _normalise(function: fem.Function) -> None:
    """Scale to max |dof| = 1, the largest-magnitude dof positive (lowest rank wins a tie)."""
    comm = function.function_space.mesh.comm
    array = compat.local_array(function)
    owned = function.function_space.dofmap.index_map.size_local * \
        function.function_space.dofmap.index_map_bs
    local = array[:owned]
    k = int(np.argmax(np.abs(local))) if local.size else -1
    mine = (float(abs(local[k])), float(local[k])) if k >= 0 else (0.0, 0.0)
    gathered = comm.allgather(mine)
    largest = max(gathered, key=lambda item: item[0])
    if largest[0] > 0:
        array *= math.copysign(1.0 / largest[0], largest[1])


class _EnergyShares:
    """Shares of int rho |u|^2 dX of a displacement u: axial (u_x), bending_y (u_y), bending_z
    (u_z), and the torsion share int rho (y^2 + z^2) (curl(u)_x / 2)^2 / int rho |u|^2 (see the
    module); the forms are compiled once, for a work Function that takes each u's values."""

    def __init__(self, problem, rho: float):
        space = compat.sub_space_collapsed(problem.W, 0)[0] if problem.p is not None \
            else problem.W
        self.u = u = fem.Function(space)
        X, dx = ufl.SpatialCoordinate(problem.mesh), problem.dx
        spin = 0.5 * (u[2].dx(1) - u[1].dx(2))
        self.forms = [fem.form(rho * u[i] ** 2 * dx) for i in range(3)] + [
            fem.form(rho * (X[1] ** 2 + X[2] ** 2) * spin**2 * dx)]

    def __call__(self, displacement: fem.Function) -> dict:
        compat.local_array(self.u)[:] = compat.local_array(displacement)
        *parts, torsion = (assemble_scalar(form) for form in self.forms)
        total = sum(parts)
        if not total > 0:
            return dict.fromkeys(KINDS, 0.0)
        return {"axial": parts[0] / total, "bending_y": parts[1] / total,
                "bending_z": parts[2] / total, "torsion": torsion / total}


def _kind(share: dict) -> str:
    if share["torsion"] > 0.5:
        return "torsion"
    return max(("axial", "bending_y", "bending_z"), key=lambda k: share[k])


# --- the rod beside it ---------------------------------------------------------------------------

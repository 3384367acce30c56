"""Natural frequencies and mode shapes of the beam linearised about its current state.

K x = omega^2 M x with K the tangent of the static residual at ``problem.w`` (the undeformed
state, or a prestressed static solution) and M the consistent mass (rho A on u, v; rho I on
theta). Dirichlet rows (K: 1 on the diagonal, M: 0) and multiplier rows (M: 0) give infinite
eigenvalues, far from the shift-and-invert target 0 (SLEPc, MUMPS).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from fe_beam import compat
from fe_beam.beam import BeamProblem
from fe_beam.mpi import global_max, global_sum

__all__ = ["Modes", "natural_frequencies"]


@dataclass
class Modes:
    """Frequencies (Hz, ascending), shapes (max |dof| = 1) and, per mode, the share of its
    translational kinetic energy that is transverse: ~1 for bending, ~0 for axial modes."""

    frequencies_hz: list[float]
    shapes: list[fem.Function]
    transverse_fraction: list[float]

    def bending(self) -> list[float]:
        """Frequencies of the modes that are mainly transverse (bending)."""
        return [f for f, share in zip(self.frequencies_hz, self.transverse_fraction, strict=True)
                if share > 0.5]


def mass_form(problem: BeamProblem):
    trial, test = ufl.TrialFunction(problem.space), ufl.TestFunction(problem.space)
    a, t = ufl.split(trial), ufl.split(test)
    rho_area = problem.rho * problem.section_props.A
    rho_inertia = problem.rho * problem.section_props.I
    dx = ufl.dx(metadata={"quadrature_degree": 2 * problem.model.mesh.degree + 2})
    return (rho_area * (a[0] * t[0] + a[1] * t[1]) + rho_inertia * a[2] * t[2]) * dx


def natural_frequencies(problem: BeamProblem, count: int) -> Modes:
    """The ``count`` lowest natural frequencies (Hz, ascending) and normalised mode shapes."""
    from slepc4py import SLEPc

    if problem.model.material.rho <= 0:
        raise ValueError("modal analysis needs material.rho > 0")
    jacobian = ufl.derivative(problem.residual, problem.w, ufl.TrialFunction(problem.space))
    stiffness_form, mass = fem.form(jacobian), fem.form(mass_form(problem))
    K = compat.assemble_matrix(stiffness_form, bcs=problem.bcs, diagonal=1.0)
    K.assemble()
    M = compat.assemble_matrix(mass, bcs=problem.bcs, diagonal=0.0)
    M.assemble()
    eps = SLEPc.EPS().create(problem.comm)
    eps.setOptionsPrefix("fe_beam_modes_")
    eps.setOperators(K, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GNHEP)
    eps.setDimensions(count, max(2 * count + 1, count + 10))
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTarget(0.0)
    transform = eps.getST()
    transform.setType(SLEPc.ST.Type.SINVERT)
    transform.setShift(0.0)
    ksp = transform.getKSP()
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    eps.setTolerances(1e-12, 200)
    eps.setFromOptions()
    eps.solve()
    pairs = []
    vector = K.createVecRight()
    fixed = compat.owned_bc_dofs(problem.bcs).astype(np.int64)
    for i in range(eps.getConverged()):
        value = eps.getEigenpair(i, vector).real
        if value > 0 and math.isfinite(value) and not _lives_on_fixed_dofs(vector, fixed):
            shape = fem.Function(problem.space, name=f"mode_{len(pairs) + 1}")
            vector.copy(compat.vector_of(shape))
            compat.vector_of(shape).ghostUpdate(addv=PETSc.InsertMode.INSERT,
                                                mode=PETSc.ScatterMode.FORWARD)
            pairs.append((math.sqrt(value) / (2 * math.pi), shape))
    pairs.sort(key=lambda pair: pair[0])
    eps.destroy()
    K.destroy()
    M.destroy()
    pairs = pairs[:count]
    for _, shape in pairs:
        array = compat.local_array(shape)
        scale = global_max(problem.comm, np.max(np.abs(array), initial=0.0))
        if scale > 0:
            array /= scale
    shares = [_transverse_share(problem, shape) for _, shape in pairs]
    return Modes([f for f, _ in pairs], [s for _, s in pairs], shares)


def _lives_on_fixed_dofs(vector: PETSc.Vec, fixed: np.ndarray) -> bool:
    """A spurious pair of the Dirichlet rows (K: identity, M: zero): a true mode vanishes on
    the fixed dofs, this one is mostly there."""
    array = vector.getArray(readonly=True)
    on_fixed, total = global_sum(vector.getComm().tompi4py(),
                                 np.array([np.sum(array[fixed] ** 2), np.sum(array**2)]))
    return on_fixed > 1e-6 * total


def _transverse_share(problem: BeamProblem, shape: fem.Function) -> float:
    from fe_beam.mpi import assemble_scalar

    u, v = ufl.split(shape)[0], ufl.split(shape)[1]
    axial = assemble_scalar(fem.form(problem.section_props.A * u**2 * ufl.dx))
    transverse = assemble_scalar(fem.form(problem.section_props.A * v**2 * ufl.dx))
    return transverse / (axial + transverse) if axial + transverse > 0 else 0.0

"""The energy W of MODEL.md reproduces the paper's constitutive laws N, T, M (eqs. 1-3)."""

import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI

from fe_beam.fem.kinematics import (
    Stiffness,
    nonstandard_energy,
    reissner_energy,
    resultants_from_formulas,
    section_resultants,
    strains_from_angles,
    strains_from_gradient,
)


@pytest.fixture(scope="module")
def unit_mesh():
    return mesh.create_unit_interval(MPI.COMM_SELF, 1)


def evaluate(unit_mesh, expression) -> float:
    """Value of a spatially constant UFL scalar (integral over the unit interval)."""
    return fem.assemble_scalar(fem.form(expression * ufl.dx(domain=unit_mesh)))


def random_states(count=6, seed=1):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield rng.uniform(-0.2, 0.3), rng.uniform(-0.6, 0.6), rng.uniform(-3.0, 3.0)


STIFFNESS = Stiffness(EA=7.0, GA=3.0, EI=1.3, EI3=0.4, EI4=0.25)


@pytest.mark.parametrize("state", list(random_states()))
def test_energy_derivatives_equal_paper_laws(unit_mesh, state):
    eps_value, gamma_value, kappa_value = state
    constant = lambda value: fem.Constant(unit_mesh, value)  # noqa: E731
    eps, gamma, kappa = (ufl.variable(constant(v)) for v in state)
    energy = nonstandard_energy(strains_from_angles(eps, gamma, kappa), STIFFNESS)
    lam = np.sqrt(2 * eps_value + 1)
    derivatives = [
        ufl.diff(energy, eps) / lam,
        ufl.diff(energy, gamma) / lam,
        ufl.diff(energy, kappa),
    ]
    formulas = resultants_from_formulas(eps, gamma, kappa, STIFFNESS)
    for name, derivative, formula in zip("NTM", derivatives, formulas, strict=True):
        got, expected = evaluate(unit_mesh, derivative), evaluate(unit_mesh, formula)
        assert got == pytest.approx(expected, rel=1e-12, abs=1e-12), name
    # A wrong law would not pass: e.g. dropping the I3 term changes M at this state.
    wrong = resultants_from_formulas(eps, gamma, kappa, Stiffness(7.0, 3.0, 1.3, 0.0, 0.25))[2]
    assert abs(evaluate(unit_mesh, wrong) - evaluate(unit_mesh, derivatives[2])) > 1e-6


@pytest.mark.parametrize("state", list(random_states(3, seed=2)))
def test_section_force_decomposes_as_model_says(unit_mesh, state):
    """F = dW/dr' = lambda^2 N t + T n, with N, T the paper's formulas."""
    eps_value, gamma_value, kappa_value = state
    theta_value = 0.7
    lam = np.sqrt(2 * eps_value + 1)
    phi = theta_value + gamma_value
    tangent = ufl.variable(
        ufl.as_vector(
            [fem.Constant(unit_mesh, lam * np.cos(phi)), fem.Constant(unit_mesh, lam * np.sin(phi))]
        )
    )
    kappa = ufl.variable(fem.Constant(unit_mesh, kappa_value))
    theta = fem.Constant(unit_mesh, theta_value)
    energy = nonstandard_energy(strains_from_gradient(tangent, theta, kappa), STIFFNESS)
    normal, shear, moment, _ = section_resultants(energy, tangent, kappa)
    consts = [fem.Constant(unit_mesh, v) for v in state]
    expected = resultants_from_formulas(*consts, STIFFNESS)
    for got, want in zip((normal, shear, moment), expected, strict=True):
        assert evaluate(unit_mesh, got) == pytest.approx(evaluate(unit_mesh, want), rel=1e-10)


def test_laws_agree_to_first_order(unit_mesh):
    """Small strains: both energies have the same Hessian at zero strain (k = 1, I3 = 0)."""
    stiffness = Stiffness(EA=7.0, GA=3.0, EI=1.3, EI3=0.0, EI4=0.25)
    for scale in (1e-3, 1e-4):
        state = [fem.Constant(unit_mesh, scale * v) for v in (0.5, -0.3, 0.8)]
        s = strains_from_angles(*state)
        standard = evaluate(unit_mesh, nonstandard_energy(s, stiffness))
        classical = evaluate(unit_mesh, reissner_energy(s, stiffness))
        assert abs(standard - classical) / classical < 5 * scale

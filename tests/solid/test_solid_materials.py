"""3D hyperelastic laws: small-strain match with linear elasticity, finite-strain formulas,
presets and validation."""

import math

import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.fem.mpi import assemble_scalar
from fe_beam.model import hyperelastic as m

E, NU = 3.0e5, 0.3


@pytest.fixture(scope="module")
def energy_at():
    """W(F) for a constant F, by integrating over the unit cube (volume 1), per law object."""
    msh = mesh.create_unit_cube(MPI.COMM_WORLD, 1, 1, 1)
    F = fem.Constant(msh, np.eye(3, dtype=PETSc.ScalarType))
    forms = {}

    def evaluate(law, value):
        key = id(law)
        if key not in forms:
            forms[key] = (law, fem.form(law.strain_energy(F) * ufl_dx(msh)))
        F.value[:] = value
        return assemble_scalar(forms[key][1])

    return evaluate


def ufl_dx(msh):
    return ufl.dx(domain=msh, metadata={"quadrature_degree": 0})


LAWS = {
    "neo_hookean": m.NeoHookean.from_young(E, NU),
    "neo_hookean_quadratic": m.NeoHookean.from_young(E, NU, volumetric="quadratic"),
    "mooney_rivlin": m.MooneyRivlin.from_young(E, NU, c10_share=0.3),
    "yeoh": m.Yeoh.from_young(E, NU, c20=1e4, c30=-2e3),
    "saint_venant_kirchhoff": m.SaintVenantKirchhoff.from_young(E, NU),
}


@pytest.mark.parametrize("name", LAWS)
def test_small_strain_tangent_is_linear_elasticity(name, energy_at):
    """(W(I + eA) + W(I - eA)) / e^2 -> A:C:A = lambda tr(e)^2 + 2 mu e:e, e = sym A."""
    law = LAWS[name]
    mu = E / (2 * (1 + NU))
    lmbda = E * NU / ((1 + NU) * (1 - 2 * NU))
    assert law.shear_modulus == pytest.approx(mu, rel=1e-12)
    assert law.young_modulus == pytest.approx(E, rel=1e-12)
    assert law.poisson_ratio == pytest.approx(NU, rel=1e-12)
    rng = np.random.default_rng(7)
    eps = 1e-4
    for _ in range(4):
        A = rng.uniform(-1, 1, (3, 3))
        e = 0.5 * (A + A.T)
        expected = lmbda * np.trace(e) ** 2 + 2 * mu * np.tensordot(e, e)
        got = (energy_at(law, np.eye(3) + eps * A) + energy_at(law, np.eye(3) - eps * A)) / eps**2
        assert got == pytest.approx(expected, rel=1e-6)
    assert energy_at(law, np.eye(3)) == pytest.approx(0.0, abs=1e-12 * E)


def test_isochoric_invariants_at_finite_stretch(energy_at):
    """Volume-preserving uniaxial stretch F = diag(s, s^-1/2, s^-1/2): I1 = s^2 + 2/s,
    I2 = 2 s + 1/s^2, and the laws reduce to their textbook incompressible forms."""
    s = 1.8
    F = np.diag([s, s**-0.5, s**-0.5])
    I1, I2 = s**2 + 2 / s, 2 * s + 1 / s**2
    nh = m.NeoHookean(kappa=1e6, mu=2e4)
    mr = m.MooneyRivlin(kappa=1e6, c10=1.1e4, c01=-0.3e4)
    ye = m.Yeoh(kappa=1e6, c10=1e4, c20=800.0, c30=-50.0)
    assert energy_at(nh, F) == pytest.approx(1e4 * (I1 - 3), rel=1e-12)
    assert energy_at(mr, F) == pytest.approx(1.1e4 * (I1 - 3) - 0.3e4 * (I2 - 3), rel=1e-12)
    d = I1 - 3
    assert energy_at(ye, F) == pytest.approx(1e4 * d + 800 * d**2 - 50 * d**3, rel=1e-12)


@pytest.mark.parametrize("volumetric", m.VOLUMETRIC_LAWS)
def test_volumetric_energy_of_pure_dilatation(volumetric, energy_at):
    """F = s I has Ib1 = 3: W = U(J), J = s^3."""
    s, kappa = 1.05, 2e6
    law = m.NeoHookean(kappa=kappa, mu=1e4, volumetric=volumetric)
    J = s**3
    U = {
        "simo_taylor": kappa / 4 * (J**2 - 1 - 2 * math.log(J)),
        "quadratic": kappa / 2 * (J - 1) ** 2,
    }[volumetric]
    assert energy_at(law, s * np.eye(3)) == pytest.approx(U, rel=1e-12)


def test_saint_venant_kirchhoff_matches_its_formula(energy_at):
    law = m.SaintVenantKirchhoff(kappa=5e5, mu=1e5)
    F = np.array([[1.3, 0.2, 0.0], [-0.1, 0.9, 0.05], [0.0, 0.1, 1.1]])
    Eg = 0.5 * (F.T @ F - np.eye(3))
    lmbda = 5e5 - 2e5 / 3
    expected = lmbda / 2 * np.trace(Eg) ** 2 + 1e5 * np.tensordot(Eg, Eg)
    assert energy_at(law, F) == pytest.approx(expected, rel=1e-12)


def test_presets_carry_numbers_source_and_compressibility():
    law = m.silicone("ecoflex-00-30", "neo_hookean", kappa_over_mu=50.0)
    assert isinstance(law, m.NeoHookean)
    assert law.shear_modulus == pytest.approx(2 * 0.008073e6)
    assert law.bulk_modulus == pytest.approx(50 * 2 * 0.008073e6)
    yeoh = m.silicone("elastosil-m4601")
    assert (yeoh.c10, yeoh.c20) == pytest.approx((0.11e6, 0.02e6))
    assert yeoh.kappa == pytest.approx(m.DEFAULT_KAPPA_OVER_MU * 0.22e6)
    assert yeoh.poisson_ratio == pytest.approx(0.495, abs=1e-3)
    mr = m.silicone("dragon-skin-10-medium", "mooney_rivlin")
    assert mr.shear_modulus == pytest.approx(2 * (0.04908 - 0.03511) * 1e6)
    for preset in m.SILICONE_PRESETS.values():
        assert preset.source and "yeoh" in preset.laws
    assert "Marechal" in m.SILICONE_PRESETS["rtv615"].source


@pytest.mark.parametrize(
    "make, field",
    [
        (lambda: m.NeoHookean(kappa=1.0, mu=-1.0), "mu"),
        (lambda: m.NeoHookean(kappa=-1.0, mu=1.0), "kappa"),
        (lambda: m.NeoHookean(kappa=1.0, mu=1.0, volumetric="log"), "volumetric"),
        (lambda: m.MooneyRivlin(kappa=1.0, c10=1.0, c01=-2.0), "shear modulus"),
        (lambda: m.Yeoh(kappa=1.0, c10=0.0), "c10"),
        (lambda: m.NeoHookean.from_young(1.0, 0.5), "nu"),
        (lambda: m.SaintVenantKirchhoff(kappa=math.inf, mu=1.0), "kappa"),
        (lambda: m.silicone("unobtainium"), "silicone name"),
        (lambda: m.silicone("elastosil-m4601", "neo_hookean"), "law"),
    ],
)
def test_validation_names_the_field(make, field):
    with pytest.raises(ValueError, match=field):
        make()

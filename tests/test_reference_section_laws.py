"""Checks of the independent section-law references (tests/reference_section_laws.py).

The references judge the `hyperelastic` rod law, so they are themselves checked against closed
forms (svk fibre = 1/2 E E11^2, incompressible uniaxial energies, small-strain modulus), against
the 3D UFL laws of fe_beam.model.hyperelastic, against the section moments of
fe_beam.model.sections and
the non-standard energy of fe_beam.fem.kinematics, and against finite differences of themselves.
"""

import math

import mpmath
import numpy as np
import pytest
import ufl
from reference_section_laws import (
    fibre_energy_exact,
    fibre_stress_exact,
    fibre_tangent_exact,
    from_solid_law,
    lateral_stretch,
    principal_energy,
    pure_bending,
    section_area,
    section_energy_exact,
    section_gradient_exact,
    section_moment_exact,
    shear_modulus,
    small_strain_modulus,
    svk_pure_bending,
)

from fe_beam.fem.kinematics import Stiffness, Strains, nonstandard_energy
from fe_beam.model.hyperelastic import MooneyRivlin, NeoHookean, SaintVenantKirchhoff, Yeoh
from fe_beam.model.sections import Section

LAWS = [
    ("neo-hookean", {"mu": 1.3}),
    ("mooney-rivlin", {"c10": 0.5, "c01": 0.15}),
    ("mooney-rivlin", {"c10": 0.9, "c01": -0.3}),  # negative c01, as silicone fits give
    ("yeoh", {"c10": 0.6, "c20": 0.08, "c30": -0.004}),
]
SECTIONS = [
    ("rectangle", {"b": 0.7, "h": 1.3}),
    ("circle", {"d": 1.1}),
    ("tube", {"d": 1.2, "t": 0.15}),
    ("t-section", {"b": 1.0, "h": 1.2, "tf": 0.25, "tw": 0.3}),
]


def test_svk_fibre_is_one_half_E_E11_squared():
    E11 = np.array([-0.45, -0.2, 0.0, 0.05, 0.7, 1.6, 3.0])  # 3.0 > 1/(2 nu): formal a^2 < 0
    for mu, bulk in ((1.0, 2.0), (2.5, 40.0), (1.0, 0.5)):
        E = mu * (3 * (bulk - 2 * mu / 3) + 2 * mu) / (bulk - 2 * mu / 3 + mu)
        assert E == pytest.approx(small_strain_modulus("svk", {"mu": mu}, bulk), rel=1e-14, abs=0)
        w = fibre_energy_exact("svk", {"mu": mu}, bulk, "simo_taylor", E11)
        s = fibre_stress_exact("svk", {"mu": mu}, bulk, "simo_taylor", E11)
        np.testing.assert_allclose(w, 0.5 * E * E11**2, rtol=1e-13, atol=1e-16)
        np.testing.assert_allclose(s, E * E11, rtol=1e-13, atol=1e-15)
        nu = (3 * bulk - 2 * mu) / (2 * (3 * bulk + mu))
        np.testing.assert_allclose(lateral_stretch("svk", {"mu": mu}, bulk, "x", E11),
                                   1 - 2 * nu * E11, rtol=1e-13, atol=1e-14)


def test_incompressible_uniaxial_closed_forms():
    stretch = np.array([0.4, 0.8, 1.0, 1.5, 2.5])
    E11 = (stretch**2 - 1) / 2
    ib1, ib2 = stretch**2 + 2 / stretch, 2 * stretch + 1 / stretch**2
    w = fibre_energy_exact("neo-hookean", {"mu": 2.0}, math.inf, "simo_taylor", E11)
    np.testing.assert_allclose(w, 1.0 * (stretch**2 + 2 / stretch - 3), rtol=1e-14, atol=1e-15)
    c10, c01 = 0.4, -0.1
    w = fibre_energy_exact("mooney-rivlin", {"c10": c10, "c01": c01}, math.inf, "x", E11)
    np.testing.assert_allclose(w, c10 * (ib1 - 3) + c01 * (ib2 - 3), rtol=1e-13, atol=1e-15)
    # nominal stress of incompressible neo-Hookean: P = mu (l - 1/l^2) = l s
    s = fibre_stress_exact("neo-hookean", {"mu": 2.0}, math.inf, "x", E11)
    np.testing.assert_allclose(stretch * s, 2.0 * (stretch - 1 / stretch**2), rtol=1e-13,
                               atol=1e-15)


def _ufl_energy(law, F):
    return float(law.strain_energy(ufl.as_matrix(F.tolist()))((0.0, 0.0, 0.0)))


@pytest.mark.parametrize("volumetric", ["simo_taylor", "quadratic"])
def test_principal_energy_matches_the_3d_ufl_laws(volumetric):
    rng = np.random.default_rng(7)
    laws = [NeoHookean(kappa=7.0, mu=1.3, volumetric=volumetric),
            MooneyRivlin(kappa=20.0, c10=0.9, c01=-0.3, volumetric=volumetric),
            Yeoh(kappa=3.0, c10=0.6, c20=0.08, c30=-0.004, volumetric=volumetric),
            SaintVenantKirchhoff(kappa=4.0, mu=1.1)]
    for _ in range(3):
        stretches = rng.uniform(0.6, 1.6, 3)
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))  # F = Q diag(l) R^T has the same stretches
        r, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        F = q @ np.diag(stretches) @ r.T
        if np.linalg.det(F) < 0:
            F = -F  # det < 0 would flip one stretch sign: use -Q
        for law in laws:
            name, coeffs, bulk, vol = from_solid_law(law)
            ref = principal_energy(name, coeffs, bulk, vol, *stretches)
            assert ref == pytest.approx(_ufl_energy(law, F), rel=1e-12, abs=1e-14)


@pytest.mark.parametrize("volumetric", ["simo_taylor", "quadratic"])
@pytest.mark.parametrize("name, coeffs", LAWS)
def test_lateral_stretch_is_stress_free_and_minimises(name, coeffs, volumetric):
    bulk = 15.0 * shear_modulus(name, coeffs)
    for E11 in (-0.35, -0.1, 0.02, 0.4, 1.5):
        a = float(lateral_stretch(name, coeffs, bulk, volumetric, E11))
        l1 = math.sqrt(1 + 2 * E11)

        def W(x, l1=l1):
            return principal_energy(name, coeffs, bulk, volumetric, l1, x, x)

        h = 1e-5 * a
        slope = (W(a + h) - W(a - h)) / (2 * h)
        scale = (W(a + h) - 2 * W(a) + W(a - h)) / h**2 * a
        assert abs(slope) < 1e-8 * scale
        assert W(a) < W(a * 1.01) and W(a) < W(a * 0.99)
        assert fibre_energy_exact(name, coeffs, bulk, volumetric, E11) == pytest.approx(
            W(a), rel=1e-11, abs=0)  # W here is the naive (cancelling) invariant formula


@pytest.mark.parametrize("name, coeffs", LAWS + [("svk", {"mu": 1.0})])
def test_fibre_stress_is_the_derivative_of_the_fibre_energy(name, coeffs):
    for bulk in (4.0, 60.0, math.inf) if name != "svk" else (4.0, 60.0):
        E11 = np.array([-0.3, -0.05, 0.1, 0.8])
        h = 1e-4
        w = [fibre_energy_exact(name, coeffs, bulk, "simo_taylor", E11 + k * h)
             for k in (-2, -1, 1, 2)]
        fd = (w[0] - 8 * w[1] + 8 * w[2] - w[3]) / (12 * h)
        s = fibre_stress_exact(name, coeffs, bulk, "simo_taylor", E11)
        np.testing.assert_allclose(s, fd, rtol=1e-8, atol=1e-10 * shear_modulus(name, coeffs))


@pytest.mark.parametrize("volumetric", ["simo_taylor", "quadratic"])
@pytest.mark.parametrize("name, coeffs", LAWS)
def test_small_strain_modulus_is_the_3d_young_modulus(name, coeffs, volumetric):
    mu0 = shear_modulus(name, coeffs)
    for ratio in (0.5, 3.0, 100.0, math.inf):
        bulk = ratio * mu0
        E = 9 * bulk * mu0 / (3 * bulk + mu0) if ratio != math.inf else 3 * mu0
        tangent = fibre_tangent_exact(name, coeffs, bulk, volumetric, 0.0)
        assert tangent == pytest.approx(E, rel=1e-9, abs=0)
        assert fibre_energy_exact(name, coeffs, bulk, volumetric, 0.0) == pytest.approx(
            0.0, abs=1e-14 * mu0)
        # and the 1/2 E E11^2 behaviour at small strain: O(E11^3) deviation
        e = 1e-3
        w = fibre_energy_exact(name, coeffs, bulk, volumetric, e)
        assert abs(w - 0.5 * E * e**2) < 5 * E * e**3


@pytest.mark.parametrize("shape, dims", SECTIONS)
def test_section_moments_match_fe_beam_sections(shape, dims):
    props = Section(shape, dims).properties(0.0)
    assert section_area(shape, dims) == pytest.approx(props.A, rel=1e-13, abs=0)
    assert section_moment_exact(shape, dims, 1) == pytest.approx(0.0, abs=1e-13 * props.h**3)
    assert section_moment_exact(shape, dims, 2) == pytest.approx(props.I, rel=1e-13, abs=0)
    assert section_moment_exact(shape, dims, 3) == pytest.approx(
        props.I3, rel=1e-12, abs=1e-13 * props.h**5)
    assert section_moment_exact(shape, dims, 4) == pytest.approx(props.I4, rel=1e-13, abs=0)


def test_t_section_has_the_third_moment_of_fe_beam():
    dims = {"b": 1.0, "h": 1.2, "tf": 0.25, "tw": 0.3}
    i3 = section_moment_exact("t-section", dims, 3)
    assert abs(i3) > 1e-3  # a real test of the eta = -y sign, not 0 = 0
    assert i3 == pytest.approx(Section("t-section", dims).properties(0.0).I3, rel=1e-12, abs=0)


@pytest.mark.parametrize("shape, dims", SECTIONS)
def test_svk_section_energy_is_the_nonstandard_energy(shape, dims):
    mu, bulk = 1.2, 9.0
    E = small_strain_modulus("svk", {"mu": mu}, bulk)
    p = Section(shape, dims).properties(0.0)
    k = Stiffness(EA=E * p.A, GA=mu * p.A, EI=E * p.I, EI3=E * p.I3, EI4=E * p.I4)
    rng = np.random.default_rng(3)
    for _ in range(3):
        one_plus_e, g = rng.uniform(0.8, 1.2), rng.uniform(-0.2, 0.2)
        kappa = rng.uniform(-0.5, 0.5) / p.h
        eps = (one_plus_e**2 + g**2 - 1) / 2
        ref = nonstandard_energy(Strains(one_plus_e, g, eps, kappa), k)
        got = section_energy_exact(shape, dims, "svk", {"mu": mu}, bulk, "simo_taylor",
                                   one_plus_e, g, kappa)
        assert got == pytest.approx(ref, rel=1e-11, abs=0)
        # gradient by differentiation under the integral vs the non-standard energy's FD
        grad = section_gradient_exact(shape, dims, "svk", {"mu": mu}, bulk, "simo_taylor",
                                      one_plus_e, g, kappa)
        for i, h in enumerate((1e-5, 1e-5, 1e-5 / p.h)):
            x = [one_plus_e, g, kappa]

            def W(d, i=i, x=x):
                y = list(x)
                y[i] += d
                return nonstandard_energy(Strains(y[0], y[1], (y[0]**2 + y[1]**2 - 1) / 2,
                                                  y[2]), k)

            fd = (W(-2 * h) - 8 * W(-h) + 8 * W(h) - W(2 * h)) / (12 * h)
            assert grad[i] == pytest.approx(fd, rel=1e-8, abs=1e-9 * E * p.A)


@pytest.mark.parametrize("shape, dims", [SECTIONS[2], SECTIONS[3]])
def test_section_gradient_is_the_derivative_of_the_section_energy(shape, dims):
    law = ("yeoh", {"c10": 0.6, "c20": 0.08, "c30": -0.004}, 30.0, "quadratic")
    x = [1.05, 0.07, 0.6]
    grad = section_gradient_exact(shape, dims, *law, *x)
    for i, h in enumerate((1e-4, 1e-4, 1e-4)):
        def W(d, i=i):
            y = list(x)
            y[i] += d
            return section_energy_exact(shape, dims, *law, *y)

        fd = (W(-2 * h) - 8 * W(-h) + 8 * W(h) - W(2 * h)) / (12 * h)
        assert grad[i] == pytest.approx(fd, rel=1e-7, abs=0)


@pytest.mark.parametrize("shape, dims", [SECTIONS[0], SECTIONS[1], SECTIONS[3]])
def test_pure_bending_of_svk_matches_the_nonstandard_closed_form(shape, dims):
    mu, bulk = 1.0, 12.0
    E = small_strain_modulus("svk", {"mu": mu}, bulk)
    p = Section(shape, dims).properties(0.0)
    moment = 0.5 * E * p.I / p.h  # kappa h about 0.5: far from linear
    kappa, one_plus_e = pure_bending(shape, dims, "svk", {"mu": mu}, bulk, "simo_taylor", moment)
    ref = svk_pure_bending(E * p.A, E * p.I, E * p.I3, E * p.I4, moment)
    assert kappa == pytest.approx(ref[0], rel=1e-10, abs=0)
    assert one_plus_e == pytest.approx(ref[1], rel=1e-10, abs=0)
    assert abs(kappa * p.h - 0.5) > 0.01  # the nonlinearity is exercised
    if shape == "rectangle":  # MODEL facts: eps = -3/2 (I/A) kappa^2, M = EI k (1 - 0.3 h^2 k^2)
        eps = (one_plus_e**2 - 1) / 2
        assert eps == pytest.approx(-1.5 * p.I / p.A * kappa**2, rel=1e-10, abs=0)
        bent = E * p.I * kappa * (1 - 0.3 * p.h**2 * kappa**2)
        assert bent == pytest.approx(moment, rel=1e-10, abs=0)


@pytest.mark.parametrize("name, coeffs", LAWS[:2])
def test_pure_bending_is_an_equilibrium_of_the_section_energy(name, coeffs):
    shape, dims = SECTIONS[3]
    bulk = 20.0 * shear_modulus(name, coeffs)
    p = Section(shape, dims).properties(0.0)
    E = small_strain_modulus(name, coeffs, bulk)
    moment = 0.4 * E * p.I / p.h
    kappa, one_plus_e = pure_bending(shape, dims, name, coeffs, bulk, "simo_taylor", moment)
    h = 1e-4

    def W(dp, dk):
        return section_energy_exact(shape, dims, name, coeffs, bulk, "simo_taylor",
                                    one_plus_e + dp, 0.0, kappa + dk)

    dW_dp = (W(-2 * h, 0) - 8 * W(-h, 0) + 8 * W(h, 0) - W(2 * h, 0)) / (12 * h)
    dW_dk = (W(0, -2 * h) - 8 * W(0, -h) + 8 * W(0, h) - W(0, 2 * h)) / (12 * h)
    assert abs(dW_dp) < 1e-7 * E * p.A
    assert dW_dk == pytest.approx(moment, rel=1e-7, abs=0)
    # small moments: the linear beam, M = EI kappa, to O(strain)
    small = 1e-4 * E * p.I / p.h
    k_small, _ = pure_bending(shape, dims, name, coeffs, bulk, "simo_taylor", small)
    assert k_small * E * p.I / small == pytest.approx(1.0, abs=1e-3)
    assert k_small * E * p.I / small != pytest.approx(1.0, abs=1e-9)  # I3: a real O(kappa) term


def _mp_energy(name, coeffs, bulk, volumetric, E11, a):
    """W(l1, a, a) straight from the invariants, in mpmath (call under mpmath.workdps(40))."""
    l1, a = mpmath.sqrt(1 + 2 * mpmath.mpf(E11)), mpmath.mpf(a)
    J = l1 * a * a
    ib1 = J ** (-mpmath.mpf(2) / 3) * (l1**2 + 2 * a**2)
    ib2 = J ** (-mpmath.mpf(4) / 3) * (2 * l1**2 * a**2 + a**4)
    c = {k: mpmath.mpf(v) for k, v in coeffs.items()}
    if name == "neo-hookean":
        w = c["mu"] / 2 * (ib1 - 3)
    elif name == "mooney-rivlin":
        w = c["c10"] * (ib1 - 3) + c["c01"] * (ib2 - 3)
    else:
        d = ib1 - 3
        w = c["c10"] * d + c["c20"] * d**2 + c["c30"] * d**3
    k = mpmath.mpf(bulk)
    if volumetric == "simo_taylor":
        return w + k / 4 * (J**2 - 1 - 2 * mpmath.log(J))
    return w + k / 2 * (J - 1) ** 2


@pytest.mark.parametrize("volumetric", ["simo_taylor", "quadratic"])
@pytest.mark.parametrize("name, coeffs", LAWS)
def test_fibre_energy_keeps_its_digits_at_small_strain(name, coeffs, volumetric):
    """No cancellation: 40-digit evaluation at the same lateral stretch, E11 down to 1e-5 and
    kappa/mu0 up to 1e4 (where J - 1 ~ 1e-9 and the naive U(J) loses 6 digits)."""
    mu0 = shear_modulus(name, coeffs)
    for ratio in (2.0, 1e4):
        bulk = ratio * mu0
        for E11 in (1e-5, -3e-4, 2e-3):
            a = float(lateral_stretch(name, coeffs, bulk, volumetric, E11))
            with mpmath.workdps(40):
                ref = float(_mp_energy(name, coeffs, bulk, volumetric, E11, a))
            got = float(fibre_energy_exact(name, coeffs, bulk, volumetric, E11))
            assert got == pytest.approx(ref, rel=1e-11, abs=0)
    # incompressible neo-Hookean: w = 3/2 mu E^2 - 5/2 mu E^3 + 35/8 mu E^4 + O(E^5)
    for E11 in (1e-5, -1e-4):
        w = fibre_energy_exact("neo-hookean", {"mu": 1.0}, math.inf, "x", E11)
        series = 1.5 * E11**2 - 2.5 * E11**3 + 35 / 8 * E11**4
        assert w == pytest.approx(series, rel=1e-11, abs=0)


@pytest.mark.parametrize("name, coeffs", LAWS)
def test_fibre_stress_keeps_its_digits_at_small_strain(name, coeffs):
    """s = dW/dE11 at the fixed lateral stretch (envelope theorem) vs a 40-digit derivative."""
    mu0 = shear_modulus(name, coeffs)
    for ratio, volumetric in ((2.0, "quadratic"), (1e4, "simo_taylor")):
        bulk = ratio * mu0
        for E11 in (1e-5, -3e-4, 0.3):
            a = float(lateral_stretch(name, coeffs, bulk, volumetric, E11))
            with mpmath.workdps(40):
                ref = float(mpmath.diff(
                    lambda e, a=a, bulk=bulk, v=volumetric: _mp_energy(name, coeffs, bulk, v, e,
                                                                       a),
                    mpmath.mpf(E11)))
            got = float(fibre_stress_exact(name, coeffs, bulk, volumetric, E11))
            assert got == pytest.approx(ref, rel=1e-10, abs=0)

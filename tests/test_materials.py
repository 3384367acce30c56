"""Linear-elastic constants: G from nu, and validation of E, nu, G, rho."""

import math
import re

import pytest

from fe_beam.model.materials import Material


@pytest.mark.parametrize("E, nu", [(2.0e11, 0.3), (70e9, 0.0), (1.0, -0.5), (3.0e6, 0.49)])
def test_shear_modulus_from_poisson_ratio(E, nu):
    m = Material(E=E, nu=nu)
    assert m.shear_modulus == pytest.approx(E / (2 * (1 + nu)), rel=1e-15)
    assert m.poisson_ratio == nu


def test_poisson_ratio_from_shear_modulus():
    m = Material(E=2.0e11, G=80e9)
    assert m.shear_modulus == 80e9
    assert m.poisson_ratio == pytest.approx(0.25, rel=1e-14)


def test_density_default_and_given():
    assert Material(E=1.0, nu=0.3).rho == 0
    assert Material(E=1.0, nu=0.3, rho=7850.0).rho == 7850.0


def _raises(key, **kwargs):
    with pytest.raises(ValueError) as error:
        Material(**kwargs)
    assert re.search(rf"material\.{key}(?![A-Za-z0-9_])", str(error.value)), str(error.value)


@pytest.mark.parametrize("kwargs", [{"E": 1.0}, {"E": 1.0, "nu": 0.3, "G": 0.4}])
def test_exactly_one_of_nu_and_g(kwargs):
    with pytest.raises(ValueError, match=r"material.*\bnu\b.*\bG\b"):
        Material(**kwargs)


@pytest.mark.parametrize("E", [0.0, -1.0, -2.0e11])
def test_young_modulus_must_be_positive(E):
    _raises("E", E=E, nu=0.3)


@pytest.mark.parametrize("nu", [0.5, 0.6, -1.0, -1.5])
def test_poisson_ratio_must_be_in_open_interval(nu):
    _raises("nu", E=1.0, nu=nu)


@pytest.mark.parametrize("nu", [0.4999999, -0.9999999])
def test_poisson_ratio_just_inside_interval_is_accepted(nu):
    assert Material(E=1.0, nu=nu).poisson_ratio == nu


@pytest.mark.parametrize("G", [0.0, -1.0])
def test_shear_modulus_must_be_positive(G):
    _raises("G", E=1.0, G=G)


def test_density_must_not_be_negative():
    _raises("rho", E=1.0, nu=0.3, rho=-1.0)


@pytest.mark.parametrize(
    "key, kwargs",
    [
        ("E", {"E": "2e11", "nu": 0.3}),
        ("E", {"E": None, "nu": 0.3}),
        ("E", {"E": True, "nu": 0.3}),
        ("E", {"E": math.nan, "nu": 0.3}),
        ("E", {"E": math.inf, "nu": 0.3}),
        ("nu", {"E": 1.0, "nu": "0.3"}),
        ("nu", {"E": 1.0, "nu": math.nan}),
        ("nu", {"E": 1.0, "nu": False}),
        ("G", {"E": 1.0, "G": [1.0]}),
        ("rho", {"E": 1.0, "nu": 0.3, "rho": "7850"}),
        ("rho", {"E": 1.0, "nu": 0.3, "rho": math.inf}),
    ],
)
def test_non_numbers_are_rejected(key, kwargs):
    _raises(key, **kwargs)

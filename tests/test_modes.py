"""Modal analysis against Timoshenko / Euler-Bernoulli frequencies (issue: dynamics)."""

import math

import pytest
from beam_cases import RHO, E, dynamic_rod

from fe_beam import BeamProblem, Loads, Supports
from fe_beam.analyses.transient import _static_prestate
from fe_beam.solvers.modes import natural_frequencies

L = 1.0


def rod(h, supports=Supports(), law="reissner", G=None, elements=30, loads=Loads()):
    return dynamic_rod(h, law, supports, elements, loads, G=G)


@pytest.mark.parametrize("slenderness", [200, 20, 10])
def test_cantilever_matches_timoshenko_table(frequencies, slenderness):
    """Omega = omega L^2 sqrt(rhoA/EI) of the first three bending modes within 0.5% (measured
    ~1e-5) of the Timoshenko values (shear coefficient ratio e = E/(kG) = 3.12)."""
    row = next(r for r in frequencies["timoshenko_table"] if r["L_over_rg"] == slenderness)
    h = row["r"] * L * math.sqrt(12)
    modes = natural_frequencies(BeamProblem(rod(h, G=E / row["e"])), 6)
    scale = L**2 * math.sqrt(RHO * h * h / (E * h**4 / 12))
    omegas = [2 * math.pi * f * scale for f in modes.bending()[:3]]
    assert omegas == pytest.approx(row["Omega"][:3], rel=5e-3)
    assert omegas == pytest.approx(row["Omega"][:3], rel=1e-4)  # what we actually reach


def test_pinned_pinned_matches_euler_bernoulli():
    h = 0.005
    model = rod(h, Supports("pinned", "roller"), elements=40)
    modes = natural_frequencies(BeamProblem(model), 4).bending()
    base = math.sqrt(E * h**4 / 12 / (RHO * h * h)) / (2 * math.pi)
    expected = [(n * math.pi / L) ** 2 * base for n in (1, 2, 3)]
    assert modes[:3] == pytest.approx(expected, rel=2e-3)


@pytest.mark.parametrize("law", ["reissner", "nonstandard"])
def test_tension_raises_frequencies_as_string_beam_formula_says(law):
    """Pinned-roller beam under axial tension N: f_n = f_n,EB sqrt(1 + N L^2 / (n^2 pi^2 EI))."""
    h = 0.005
    EI = E * h**4 / 12
    tension = 10 * math.pi**2 * EI / L**2
    model = rod(h, Supports("pinned", "roller"), law=law, elements=40,
                loads=Loads(tip_force=(tension, 0.0)))
    problem = BeamProblem(model)
    from fe_beam.model.studies import StaticConfig

    _static_prestate(problem, StaticConfig(model), progress=False)
    modes = natural_frequencies(problem, 4).bending()
    base = math.sqrt(EI / (RHO * h * h)) / (2 * math.pi)
    expected = [(n * math.pi / L) ** 2 * base * math.sqrt(1 + tension * L**2 / (n * math.pi) ** 2
                                                           / EI) for n in (1, 2, 3)]
    assert modes[:3] == pytest.approx(expected, rel=3e-3)
    unstressed = natural_frequencies(BeamProblem(rod(h, Supports("pinned", "roller"), law=law,
                                                     elements=40)), 2).bending()
    assert modes[0] > 3 * unstressed[0]  # the effect is large: a wrong K would be caught

"""The elastica references of fe_beam.analytic against tabulated values and against independent
numerical integrations (no finite elements)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

from fe_beam.analytic import (
    elastica_clamped_free,
    elastica_clamped_free_at_load,
    elastica_pinned_pinned,
    elastica_pinned_pinned_at_load,
    snap_through_symmetric,
)

# Timoshenko & Gere, Theory of Elastic Stability (2nd ed. 1961), Table 2-7 (clamped-free column):
# tip rotation alpha [deg], P/P_cr, x_tip/L (chord), delta/L (tip deflection), 3 decimals
TIMOSHENKO_GERE = [
    (20, 1.015, 0.970, 0.220),
    (40, 1.063, 0.881, 0.422),
    (60, 1.152, 0.741, 0.593),
    (80, 1.293, 0.560, 0.719),
    (100, 1.518, 0.349, 0.792),
    (120, 1.884, 0.123, 0.803),
    (140, 2.541, -0.107, 0.750),
    (160, 4.029, -0.340, 0.625),
    (176, 9.116, -0.577, 0.421),
]


@pytest.mark.parametrize("row", TIMOSHENKO_GERE, ids=[str(r[0]) for r in TIMOSHENKO_GERE])
def test_clamped_free_matches_the_timoshenko_gere_table(row):
    alpha, load, chord, deflection = row
    column = elastica_clamped_free(math.radians(alpha))
    assert column.load_ratio == pytest.approx(load, rel=1e-3)  # the table's rounding
    assert 1 - column.shortening == pytest.approx(chord, abs=1.5e-3)
    assert column.deflection == pytest.approx(deflection, abs=1.5e-3)


def _shoot(alpha: float, span: float, end: float):
    """theta'' = -lam^2 sin(theta) on [0, span] from theta(0) = alpha, theta'(0) = 0 (a free or
    pinned end: no moment), lam chosen so that theta(span) = end at the first such crossing;
    returns lam^2 and the chord and lateral deflection integrals (solve_ivp, rtol 1e-12)."""

    def run(lam):
        def rhs(_s, y):
            return [y[1], -lam * lam * math.sin(y[0]), math.cos(y[0]), math.sin(y[0])]

        return solve_ivp(rhs, (0.0, span), [alpha, 0.0, 0.0, 0.0], method="DOP853",
                         rtol=1e-12, atol=1e-14, dense_output=True)

    # theta reaches `end` first at lam in (pi/2 span-ish bounds): bracket on the first crossing
    def miss(lam):
        return run(lam).y[0, -1] - end

    quarter = 0.5 * math.pi / span
    lams = np.linspace(0.9 * quarter, 6 * quarter, 120)
    values = [miss(lams[0])]
    for i in range(1, len(lams)):
        values.append(miss(lams[i]))
        if values[-1] * values[-2] < 0:
            lam = brentq(miss, lams[i - 1], lams[i], xtol=1e-15, rtol=1e-15)
            y = run(lam).y[:, -1]
            return lam * lam, y[2], y[3]
    raise AssertionError("no crossing")


@pytest.mark.parametrize("degrees", [30, 120, 172, 178])
def test_clamped_free_against_direct_integration(degrees):
    """From the free tip (rotation alpha, no moment) to the clamp (theta = 0), unit length."""
    alpha = math.radians(degrees)
    lam2, chord, lateral = _shoot(alpha, 1.0, 0.0)
    column = elastica_clamped_free(alpha)
    assert column.load_ratio == pytest.approx(lam2 / (math.pi**2 / 4), rel=1e-9)
    assert column.shortening == pytest.approx(1 - chord, abs=1e-9)
    assert column.deflection == pytest.approx(abs(lateral), abs=1e-9)
    assert elastica_clamped_free_at_load(column.load_ratio).rotation == pytest.approx(
        alpha, abs=1e-9)


@pytest.mark.parametrize("degrees", [45, 150, 175])
def test_pinned_pinned_against_direct_integration(degrees):
    """From one pin (rotation alpha, no moment) to midspan (theta = 0, by symmetry), unit
    length."""
    alpha = math.radians(degrees)
    lam2, half_chord, half_lateral = _shoot(alpha, 0.5, 0.0)
    chord = 2 * half_chord
    column = elastica_pinned_pinned(alpha)
    assert column.load_ratio == pytest.approx(lam2 / math.pi**2, rel=1e-9)
    assert column.shortening == pytest.approx(1 - chord, abs=1e-9)
    assert column.deflection == pytest.approx(abs(half_lateral), abs=1e-9)
    assert elastica_pinned_pinned_at_load(column.load_ratio).rotation == pytest.approx(
        alpha, abs=1e-9)


def test_small_rotation_limits():
    """Koiter's expansion: P/P_cr = 1 + alpha^2/8 + ..., shortening/L = alpha^2/8 (clamped-free)."""
    alpha = 1e-3
    column = elastica_clamped_free(alpha)
    assert column.load_ratio - 1 == pytest.approx(alpha**2 / 8, rel=1e-3)
    assert column.deflection == pytest.approx(2 * alpha / math.pi, rel=1e-6)
    with pytest.raises(ValueError):
        elastica_clamped_free(math.pi)
    with pytest.raises(ValueError):
        elastica_pinned_pinned_at_load(0.9)


def test_snap_through_reference():
    """The symmetric branch: its zero-force states are the buckled first mode (P from the
    elastica with four quarter waves: sqrt(P/EI) L/4 = K(k), shortening 2 - 2 E/K) and,
    for small shortening, the buckled mode 1 - cos(6 pi x/L) (P ~ 36 pi^2, height ~ -Y0/3);
    the force maximum is inside, with F > 0."""
    d = 0.01
    path = snap_through_symmetric(d)
    m = brentq(lambda m: 2 - 2 * ellipe(m) / ellipk(m) - d, 1e-12, 0.9, xtol=1e-15)
    assert path.axial[0] == pytest.approx(16 * ellipk(m) ** 2, rel=1e-8)
    assert path.force[0] == 0.0
    k = math.sqrt(m)
    # midspan height of the first mode: four quarter waves of deflection 2 k (L/4) / K each
    assert path.deflection[0] == pytest.approx(2 * 2 * k * 0.25 / ellipk(m), rel=1e-8)
    crossing = int(np.argmax((path.force[:-1] > 0) & (path.force[1:] <= 0)))
    assert path.deflection[crossing] / path.deflection[0] == pytest.approx(-1 / 3, abs=0.01)
    assert path.axial[crossing] / math.pi**2 == pytest.approx(36, rel=0.02)
    assert path.limit_force >= path.force.max() - 1e-9
    assert 0 < path.limit_deflection < path.deflection[0]

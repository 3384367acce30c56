"""Critical points and branch switching on the rod (fe_beam.solvers.critical,
fe_beam.analyses.path) against the
elliptic-integral elastica (fe_beam.analytic)."""

import math

import pytest
from beam_cases import bending_stiffness, cantilever
from mpi4py import MPI
from scipy.optimize import brentq

from fe_beam import LoadStepping, SolverSettings, Supports
from fe_beam.analyses.path import follow_path
from fe_beam.analytic import elastica_clamped_free, elastica_pinned_pinned
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers.continuation import ArcLength

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="dense stability: serial")


def _follow(model, max_load_factor, branch_switch="positive", **arc):
    from fe_beam.analyses.static import StaticContinuation

    run = StaticContinuation(StaticConfig(model, SolverSettings(), LoadStepping(steps=4)))
    try:
        settings = ArcLength(increment=0.1, max_load_factor=max_load_factor, max_steps=120,
                             max_arc_length=0.3, **arc)
        return follow_path(run, settings, branch_switch)
    finally:
        run.destroy()


def _check(result, reference, rotation_beyond):
    """One bifurcation at lambda = 1 (the Euler load), then the bifurcated branch: load vs end
    rotation to 4 digits beyond `rotation_beyond` degrees, shortening and deflection."""
    assert result.status == "converged", result.message
    point = result.critical_points[0]
    assert point.kind == "bifurcation"
    assert point.load_factor == pytest.approx(1.0, abs=2e-6)
    assert point.bracket[1] - point.bracket[0] <= 1e-6
    assert (point.unstable_before, point.unstable_after) == (0, 1)
    assert point.mode is not None
    fundamental = [p for p in result.path if p["branch"] == 0]
    assert all(p["stable"] == (p["load_factor"] < 1.0) for p in fundamental)
    bifurcated = [p for p in result.path if p["branch"] == 1]
    following = [c.load_factor for c in result.critical_points[1:]] + [math.inf]
    assert len(bifurcated) > 10
    assert all(p["stable"] == (p["load_factor"] < following[0]) for p in bifurcated)
    largest = 0.0
    for p in bifurcated:
        alpha = abs(p["tip"]["theta"])
        largest = max(largest, math.degrees(alpha))
        exact = reference(alpha)
        assert p["load_factor"] == pytest.approx(exact.load_ratio, rel=5e-5)
        yield p, exact
    assert largest > rotation_beyond


def test_clamped_free_bifurcation_branch_switch_and_post_buckling():
    EI = bending_stiffness(0.01)
    critical = math.pi**2 * EI / 4
    model = cantilever(elements=16, tip_force=(-critical, 0.0))
    result = _follow(model, 10.0)
    assert len(result.critical_points) == 1
    for p, exact in _check(result, elastica_clamped_free, 170):
        assert -p["tip"]["u"] == pytest.approx(exact.shortening, abs=5e-5)
        assert abs(p["tip"]["v"]) == pytest.approx(exact.deflection, abs=5e-5)


def test_pinned_pinned_bifurcation_and_post_buckling():
    """Pinned at x = 0, on a roller (v = 0) at x = L: end rotation theta(L), end shortening
    -u(L)."""
    EI = bending_stiffness(0.01)
    critical = math.pi**2 * EI
    model = cantilever(elements=32, tip_force=(-critical, 0.0))
    model = type(model)(model.length, model.section, model.material, model.options, model.mesh,
                        Supports("pinned", "roller"), model.loads)
    result = _follow(model, 10.0)
    for p, exact in _check(result, elastica_pinned_pinned, 170):
        assert -p["tip"]["u"] == pytest.approx(exact.shortening, abs=5e-5)
    # with a dead end load the bifurcated branch loses stability where the ends cross
    # (chord 0: 2 E(k) = K(k)); observed, located by the same bisection
    later = result.critical_points[1:]
    assert [c.kind for c in later] == ["bifurcation"]
    crossing = brentq(lambda a: elastica_pinned_pinned(a).shortening - 1.0, 1.0, 3.0)
    assert later[0].load_factor == pytest.approx(elastica_pinned_pinned(crossing).load_ratio,
                                                 rel=1e-4)


def test_limit_point_of_the_nonstandard_law_under_a_tip_moment():
    """Unconstrained non-standard law, rectangle, pure bending: M = EI kappa (1 - 0.3 h^2
    kappa^2) (docs/theory.md), whose maximum 2 / (3 sqrt(0.9)) EI / h is a limit point of the
    tip-moment path: located to 1e-6, traced through (lambda turns, the branch beyond it is
    unstable)."""
    from fe_beam.analyses.static import StaticContinuation

    h = 0.2
    EI = bending_stiffness(h)
    model = cantilever(h=h, law="nonstandard", constraint="none", elements=8,
                       tip_moment=0.5 * EI / h)
    run = StaticContinuation(StaticConfig(model, SolverSettings(), LoadStepping(steps=4)))
    try:
        result = follow_path(run, ArcLength(increment=0.1, max_load_factor=2.0, max_steps=24,
                                            max_arc_length=1.0), "none")
    finally:
        run.destroy()
    assert result.status == "converged", result.message
    (point,) = result.critical_points
    assert point.kind == "limit"
    expected = 2 / (3 * math.sqrt(0.9)) / 0.5
    assert point.load_factor == pytest.approx(expected, rel=1e-6)
    assert abs(point.bracket[1] - point.bracket[0]) <= 1e-6 * expected
    assert max(p["load_factor"] for p in result.path) <= point.load_factor + 1e-9
    turned = [p for p in result.path if not p["stable"]]
    assert turned and turned[-1]["load_factor"] < result.path[-1]["load_factor"] + 1e-12
    assert all(p["stable"] == (p["tip"]["theta"] < point.tip["theta"]) for p in result.path)

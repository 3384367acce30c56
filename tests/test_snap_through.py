"""Snap-through of the bistable clamped-clamped beam (issue 11): a path with limit points traced
through and back, against the independent shooting solution of the inextensible elastica
(fe_beam.analytic.snap_through_symmetric; docs/theory.md, Snap-through of the buckled beam).

The beam (inextensible and unshearable, so that it is the reference's elastica) is clamped at
both ends, brought to its first buckled shape by the end shortening d held in full, then pushed
down at midspan by a point force whose factor is the path parameter (``[path] parameter =
"point_force"``, `fe_beam.analyses.path.point_force_control`). The straight shortened state is not
an
admissible start for Newton (the linearised inextensibility u' = 0 contradicts u(L) = -d), so
the test starts Newton from the small-shortening first mode (1 - cos 2 pi x) / 2, which is
branch switching into the buckled shape by hand.

Symmetric vs asymmetric snap: the mesh, the start and the load are mirror-symmetric, so the
arc-length path is the symmetric branch (an exact equilibrium branch) all the way, also past
the bifurcation where it becomes unstable against the asymmetric mode. A real beam under force
control snaps through that asymmetric mode at the bifurcation force, below the symmetric limit
force (Vangbo 1998, Pandey et al. 2014): the path reports it as a bifurcation point with one
energy-decreasing direction after it, and the test checks that it comes before the symmetric
limit point; the reference and the comparison are the symmetric branch's."""

import math

import numpy as np
import pytest
from mpi4py import MPI

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="dense stability: serial")

SHORTENING = 0.01
E, B, H, LENGTH = 1.0e7, 0.01, 0.01, 1.0
EI = E * B * H**3 / 12
DEGREE = 2
FORCE = 100.0  # the point force at load factor 1, in EI / L^2


def _config(elements: int) -> dict:
    return {
        "beam": {"length": LENGTH},
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable"},
        "mesh": {"elements": elements, "degree": DEGREE},
        "supports": {"x0": "clamped", "xL": "clamped"},
        "loads": {"end_displacement": [-SHORTENING * LENGTH, 0.0],
                  "point_forces": [[LENGTH / 2, 0.0, -FORCE * EI / LENGTH**2]]},
        "path": {"parameter": "point_force", "max_load_factor": 1.0},
    }


def _buckled_start(problem, d: float) -> None:
    """The first buckled mode of small shortening d (inextensible to first order) as Newton's
    start: v = A (1 - cos 2 pi x) / 2 with A = 2 sqrt(d) / pi, u = -int v'^2 / 2."""
    from fe_beam.fem import compat

    amplitude = 2 * math.sqrt(d) / math.pi
    k = 2 * math.pi / LENGTH

    def u(x):
        return -(amplitude * k / 2) ** 2 / 2 * (x - np.sin(2 * k * x) / (2 * k))

    def v(x):
        return amplitude * (1 - np.cos(k * x)) / 2

    def theta(x):
        return np.arctan2(amplitude * k / 2 * np.sin(k * x),
                          1 - (amplitude * k / 2 * np.sin(k * x)) ** 2 / 2)

    array = compat.local_array(problem.w)
    array[:] = 0.0
    for index, shape in enumerate((u, v, theta)):
        sub, dofs = compat.sub_space_collapsed(problem.space, index)
        x = sub.tabulate_dof_coordinates()[:, 0]
        array[np.asarray(dofs)] = shape(x)


def _snap_path(elements: int, max_steps: int = 70):
    """(points [(load factor, midspan v / L, stable, state, snapshot)], PathResult, run)."""
    from fe_beam.analyses.path import follow_path, point_force_control
    from fe_beam.analyses.static import StaticContinuation
    from fe_beam.config.path import parse_path
    from fe_beam.solvers.continuation import ArcLength

    _, static, _ = parse_path(_config(elements))
    run = StaticContinuation(static, MPI.COMM_SELF)
    _buckled_start(run.problem, SHORTENING)
    point_force_control(run, static, prestate=False)
    engine = run.engine()
    engine.solve_at(0.0, predictor=False)
    points = []
    start = engine.snapshot()

    def on_point(entry, _result):
        mid = run.problem.point_values(LENGTH / 2)
        points.append((entry["load_factor"], mid["v"] / LENGTH, entry["stable"],
                       engine.state.copy()))

    settings = ArcLength(increment=0.05, max_load_factor=1.0, max_steps=max_steps,
                         max_arc_length=0.2)
    # located to 1e-6: `locate_limit` stops on the load-factor width of its bracket, which is
    # small near a limit however long the arc between its ends (1e-4 left the 16-element limit
    # force 1.4e-3 low)
    result = follow_path(run, settings, "none", 1e-6, on_point)
    return points, result, run, start


def _dense_spectrum_is_slow() -> bool:
    from fe_beam.fem import compat

    return not compat.LEGACY


@pytest.fixture(scope="module")
def reference():
    from fe_beam.analytic import snap_through_symmetric

    return snap_through_symmetric(SHORTENING, points=25)


@pytest.mark.skipif(_dense_spectrum_is_slow(), reason="the PyPI stack's dense stability check "
                    "(scipy null_space) takes ~0.5 s per point: 80 s here vs 13 s on Debian")
def test_snap_through_limit_point_and_path_against_elastica(reference):
    """The force-deflection path of the buckled beam pushed at midspan rises from the first
    buckled shape (F = 0, midspan Y0), turns at the limit point, goes through zero at the
    third-mode state (~ -Y0 / 3) into negative forces. Force vs midspan deflection within 1e-3
    (distance to the reference curve in F / F_limit, Y / Y0; measured 5.6e-4), the limit force
    within 1e-3 (measured 2.9e-4 with 32 quadratic elements, 4.5e-3 with 16, 6.4e-2 with 8:
    fourth order), the error shrinking >= 8 times from 16 to 32 elements; before the limit
    point, the asymmetric bifurcation (one energy-decreasing direction after it: where a real
    beam snaps)."""
    from scipy.interpolate import CubicSpline

    # F(Y) of the reference (its heights decrease: a spline in -Y); its first interval, where
    # F rises from 0 to ~0.45 F_limit, is too coarse to interpolate: compared from the second
    # reference height on (the start, F = 0, separately)
    force_at = CubicSpline(-np.asarray(reference.deflection), np.asarray(reference.force))
    low, high = float(reference.deflection[-1]), float(reference.deflection[0])
    errors = {}
    for elements, steps in ((16, 7), (32, 18)):
        points, result, run, _ = _snap_path(elements, max_steps=steps)
        run.destroy()
        assert result.status == "converged", result.message
        limits = [c for c in result.critical_points if c.kind == "limit"]
        assert len(limits) == 1
        errors[elements] = abs(limits[0].load_factor * FORCE / reference.limit_force - 1)
    assert errors[32] < 1e-3, errors
    assert errors[16] > 8 * errors[32], errors
    # the path of the finer mesh: through the limit point and back below zero force
    forces = np.array([p[0] * FORCE for p in points])
    heights = np.array([p[1] for p in points])
    assert heights[0] == pytest.approx(high, rel=1e-4)
    assert forces[0] == 0.0 and forces.max() > 0.99 * reference.limit_force
    assert heights[-1] < low and forces[-1] < 0.9 * float(reference.force[-1])
    inside = (heights >= low) & (heights <= float(reference.deflection[1]))
    assert inside.sum() >= 8, heights
    # distance to the reference curve in (F / F_limit, Y / Y0)
    dense = np.linspace(low, high, 20001)
    curve = np.column_stack([force_at(-dense) / reference.limit_force, dense / high])
    fe = np.column_stack([forces[inside] / reference.limit_force, heights[inside] / high])
    gap = np.sqrt(((fe[:, None, :] - curve[None, :, :]) ** 2).sum(axis=2)).min(axis=1)
    assert gap.max() < 1e-3, gap
    # critical points in order: the asymmetric bifurcation (stable before, one
    # energy-decreasing direction after), then the symmetric limit point
    first = result.critical_points[0]
    assert first.kind == "bifurcation" and first.load_factor < limits[0].load_factor
    assert (first.unstable_before, first.unstable_after) == (0, 1)
    assert all(p[2] == (p[0] < first.load_factor) for p in points
               if p[0] * FORCE < reference.limit_force and p[1] > reference.limit_deflection)


def test_snap_through_load_control_agrees_with_arc_length_on_the_stable_part():
    """The stable part of the path (before the bifurcation) by load control from the same
    buckled state reaches the arc-length states to 1e-8."""
    from fe_beam.solvers.newton import LoadStepping

    points, result, run, start = _snap_path(16, max_steps=3)
    try:
        stable = [p for p in points if p[2] and p[0] > 0]
        assert len(stable) >= 2
        engine = run.engine()
        for factor, _, _, state in stable:
            engine.restore(start)
            engine.load_control(factor, LoadStepping(steps=3))
            assert engine.parameter == pytest.approx(factor, rel=1e-14)
            assert np.linalg.norm(engine.state - state) <= 1e-8 * np.linalg.norm(state)
    finally:
        run.destroy()


def _cli_config(tmp_path, name: str, changes: dict):
    from pathlib import Path

    from tomlio import dump_toml

    from fe_beam.config.schema import load_config

    examples = Path(__file__).resolve().parents[1] / "examples"
    config = load_config(examples / name)
    for key, values in changes.items():
        config.setdefault(key, {}).update(values)
    path = tmp_path / "config.toml"
    path.write_text(dump_toml(config))
    return path


def test_snap_through_example_runs_through_and_back(tmp_path):
    """examples/snap_through.toml (shortened): `fe-beam path` with parameter = "point_force"
    holds the end shortening while the point force grows: the midspan starts on the upper
    buckled state at zero force, the force turns at a limit point, and the beam ends on the
    lower side; summary.json "point" is the midspan."""
    import json

    from fe_beam.cli import main

    path = _cli_config(tmp_path, "snap_through.toml", {"path": {"max_steps": 20}})
    out = tmp_path / "out"
    assert main(["path", str(path), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "converged" and summary["parameter"] == "point_force"
    points = summary["path"]
    assert points[0]["load_factor"] == 0.0 and points[0]["point"]["x"] == 0.5
    assert points[0]["point"]["v"] > 0.05 and points[0]["stable"]
    assert points[0]["tip"]["u"] == pytest.approx(-0.01, abs=1e-12)  # held in full
    assert points[-1]["point"]["v"] < 0 and points[-1]["load_factor"] < 0
    assert [c["kind"] for c in summary["critical_points"]].count("limit") >= 1


@pytest.mark.parametrize("changes, key", [
    ({"loads": {"point_forces": []}}, "point_forces"),
    ({"loads": {"point_forces": [[0.5, 0.0, 0.0]]}}, "point_forces"),
])
def test_point_force_parameter_without_point_forces_exits_2(tmp_path, capsys, changes, key):
    from fe_beam.cli import main

    path = _cli_config(tmp_path, "snap_through.toml", changes)
    assert main(["path", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    error = capsys.readouterr().err.strip()
    assert key in error and "Traceback" not in error and error.count("\n") == 0, error


def test_inextensible_straight_start_exits_3_with_the_reason(tmp_path, capsys):
    """The straight shortened inextensible beam is no start for Newton: exit 3 naming why."""
    from fe_beam.cli import main

    path = _cli_config(tmp_path, "snap_through.toml", {
        "model": {"constraint": "inextensible-unshearable"}, "loads": {"steps": 4}})
    assert main(["path", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 3
    assert "inextensible beam cannot start" in capsys.readouterr().err

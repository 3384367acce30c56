"""[loads] point_forces, end_displacement and end_rotation of the rod: closed forms of the
linear range (Euler-Bernoulli / Timoshenko), pure bending at large rotation, 2 ranks, the
static command's reaction record and the validation (exit 2, one sentence naming the key)."""

from __future__ import annotations

import json

import pytest
from mpi4py import MPI

from fe_beam.analyses.static import StaticContinuation
from fe_beam.cli import main
from fe_beam.config.schema import parse_static
from fe_beam.errors import ConfigError

E, NU, B, H, L = 2.0e11, 0.3, 0.01, 0.02, 1.0
EI = E * B * H**3 / 12
GA = E / (2 * (1 + NU)) * B * H


def config(law="reissner", constraint="none", elements=10, xL="free", **loads):
    return {"beam": {"length": L}, "section": {"shape": "rectangle", "b": B, "h": H},
            "material": {"E": E, "nu": NU}, "model": {"law": law, "constraint": constraint},
            "mesh": {"elements": elements, "degree": 2},
            "supports": {"x0": "clamped", "xL": xL}, "loads": {"steps": 1, **loads}}


def solved(cfg, comm=MPI.COMM_WORLD):
    run = StaticContinuation(parse_static(cfg), comm)
    run.advance(1.0, run.config.stepping)
    return run


@pytest.mark.parametrize("law, constraint", [("reissner", "none"), ("nonstandard", "none"),
                                             ("reissner", "inextensible-unshearable")])
@pytest.mark.parametrize("a", [0.37, 0.5, 1.0])
def test_point_force_deflection_matches_beam_theory(law, constraint, a):
    """Cantilever, small force P at x = a (a vertex is placed there; 0.37 is not on the
    uniform mesh): v(L) = P a^2 (3L - a) / (6 EI) + P a / GA (no shear term when unshearable)."""
    P = 1e-6 * EI / L**2
    run = solved(config(law, constraint, point_forces=[[a, 0.0, P]]))
    expected = P * a**2 * (3 * L - a) / (6 * EI) + (P * a / GA if constraint == "none" else 0)
    tip = run.problem.end_values("xL")
    assert tip["v"] == pytest.approx(expected, rel=1e-8)
    assert tip["theta"] == pytest.approx(P * a**2 / (2 * EI), rel=1e-8)
    run.destroy()


def test_point_forces_superpose_with_a_tip_force():
    """Two interior forces and an axial one: the linear-range sum of the closed forms."""
    P = 1e-6 * EI / L**2
    run = solved(config(point_forces=[[0.25, 0.0, P], [0.6, 0.0, -2 * P], [0.6, 3 * P, 0.0]],
                        tip_force=[0.0, 0.5 * P]))
    expected = sum(p * a**2 * (3 * L - a) / (6 * EI) + p * a / GA
                   for a, p in ((0.25, P), (0.6, -2 * P), (L, 0.5 * P)))
    tip = run.problem.end_values("xL")
    assert tip["v"] == pytest.approx(expected, rel=1e-7)
    assert tip["u"] == pytest.approx(3 * P * 0.6 / (E * B * H), rel=1e-5)
    run.destroy()


@pytest.mark.parametrize("law", ["reissner", "nonstandard"])
def test_end_displacement_reaction_is_the_timoshenko_stiffness(law):
    """A prescribed tip deflection dv: the support's force is dv / (L^3 / 3EI + L / GA); the
    tip rotation that of a tip-loaded cantilever."""
    dv = 1e-6 * L
    run = solved(config(law, end_displacement=[0.0, dv]))
    force = dv / (L**3 / (3 * EI) + L / GA)
    reaction = run.problem.end_reaction("xL")
    assert reaction["Fy"] == pytest.approx(force, rel=1e-6)
    assert reaction["M"] == 0.0
    tip = run.problem.end_values("xL")
    assert tip["v"] == pytest.approx(dv, rel=1e-12)
    assert tip["theta"] == pytest.approx(force * L**2 / (2 * EI), rel=1e-6)
    run.destroy()


def test_end_displacement_axial_reaction():
    du = -1e-6 * L
    run = solved(config("reissner", end_displacement=[du, 0.0]))
    assert run.problem.end_reaction("xL")["Fx"] == pytest.approx(E * B * H * du / L, rel=1e-5)
    run.destroy()


@pytest.mark.parametrize("law", ["reissner", "nonstandard"])
def test_end_rotation_is_pure_bending(law):
    """theta(L) = 1 rad with u, v free: uniform curvature kappa = 1/L, the support's moment
    EI kappa (Reissner, exact at any rotation) or EI kappa (1 - 0.3 h^2 kappa^2) (the
    non-standard law's pure bending of a rectangle, docs/theory.md)."""
    run = solved(config(law, elements=8, end_rotation=1.0, steps=4))
    kappa = 1.0 / L
    moment = EI * kappa * (1 - 0.3 * H**2 * kappa**2 if law == "nonstandard" else 1)
    assert run.problem.end_reaction("xL")["M"] == pytest.approx(moment, rel=1e-6)
    assert run.problem.end_values("xL")["theta"] == pytest.approx(1.0, rel=1e-12)
    run.destroy()


@pytest.mark.mpi
def test_two_ranks_equal_serial():
    P = 1e-3 * EI / L**2
    cfg = config("nonstandard", elements=12, point_forces=[[0.41, 0.0, P]],
                 end_displacement=[0.0, 1e-3])
    together, alone = solved(cfg), solved(cfg, MPI.COMM_SELF)
    for key in ("u", "v", "theta"):
        assert together.problem.end_values("xL")[key] == pytest.approx(
            alone.problem.end_values("xL")[key], rel=1e-10, abs=1e-14)
    assert together.problem.end_reaction("xL")["Fy"] == pytest.approx(
        alone.problem.end_reaction("xL")["Fy"], rel=1e-9)


def test_static_command_records_the_reaction(tmp_path):
    from tomlio import dump_toml

    path = tmp_path / "pushed.toml"
    dv = 1e-6
    path.write_text(dump_toml(config(end_displacement=[0.0, dv], steps=2)))
    out = tmp_path / "out"
    assert main(["static", str(path), "--out", str(out), "--quiet"]) == 0
    steps = json.loads((out / "summary.json").read_text())["steps"]
    assert steps[-1]["reaction_xL"]["Fy"] == pytest.approx(dv / (L**3 / (3 * EI) + L / GA),
                                                           rel=1e-6)
    # half the load factor, half the prescribed deflection (linear range: 1e-8 of nonlinearity)
    assert steps[0]["reaction_xL"]["Fy"] == pytest.approx(steps[-1]["reaction_xL"]["Fy"] / 2,
                                                          rel=1e-6)


@pytest.mark.parametrize("loads, key", [
    ({"point_forces": [[0.0, 0.0, 1.0]]}, "point_forces"),
    ({"point_forces": [[1.2, 0.0, 1.0]]}, "point_forces"),
    ({"point_forces": [[-0.1, 0.0, 1.0]]}, "point_forces"),
    ({"point_forces": [[0.5, 1.0]]}, "point_forces"),
    ({"point_forces": [0.5, 0.0, 1.0]}, "point_forces"),
    ({"end_displacement": [0.1]}, "end_displacement"),
    ({"end_displacement": [0.0, 0.1], "tip_force": [0.0, 1.0]}, "tip_force"),
    ({"end_displacement": [0.1, 0.0], "tip_force": [1.0, 0.0]}, "tip_force"),
    ({"end_rotation": 0.5, "tip_moment": 1.0}, "tip_moment"),
    ({"end_rotation": "a lot"}, "end_rotation"),
    ({"end_rotation": 0.5, "prescribed_xL": {"theta": 1.0}}, "prescribed_xL"),
    ({"end_displacement": [0.0, 0.1], "point_forces": [[L, 0.0, 1.0]]}, "point_forces"),
    ({"end_displacement": [0.0, 0.1], "point_forces": [[L * (1 - 1e-12), 1.0, 0.0]]},
     "point_forces"),
])
def test_bad_point_loads_exit_2(tmp_path, capsys, loads, key):
    from tomlio import dump_toml

    cfg = config(**loads)
    with pytest.raises(ConfigError, match=key):
        parse_static(cfg)
    path = tmp_path / "bad.toml"
    path.write_text(dump_toml(cfg))
    assert main(["static", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    error = capsys.readouterr().err.strip()
    assert key in error and error.count("\n") == 0 and "Traceback" not in error


@pytest.mark.parametrize("a", [1e-12, 1e-9])
def test_force_within_round_off_of_x0_is_applied(a):
    """x0 free, xL clamped, P at x = a ~ 0: the mesh puts no round-off element there, so the
    force sits on the end vertex x = 0 (a boundary facet; was: silently dropped, v(0) = 0 with
    exit 0). v(0) = P b^2 (3L - b) / (6 EI) + P b / GA with b = L - a."""
    P = 1e-6 * EI / L**2
    cfg = config(point_forces=[[a, 0.0, P]])
    cfg["supports"] = {"x0": "free", "xL": "clamped"}
    run = solved(cfg)
    b = L - a
    assert run.problem.end_values("x0")["v"] == pytest.approx(
        P * b**2 * (3 * L - b) / (6 * EI) + P * b / GA, rel=1e-8)
    run.destroy()


@pytest.mark.parametrize("loads, key", [
    ({"point_forces": [[0.05, 0.0, 0.1]]}, "point_forces"),
    ({"end_displacement": [0.0, 0.0]}, "end_displacement"),
    ({"end_rotation": 0.1}, "end_rotation"),
])
def test_solid_refuses_rod_only_end_loads(loads, key):
    """The 3D solid takes tip_force and tendons only: the rod run beside it took these keys
    and the solid dropped them (a 1D-vs-3D comparison of two different problems, exit 0)."""
    from fe_beam.config.solid import parse_solid

    raw = {"beam": {"length": 0.1}, "section": {"shape": "rectangle", "b": 0.02, "h": 0.02},
           "material": {"E": 0.6e6, "nu": 0.45, "rho": 1070.0}, "model": {"law": "reissner"},
           "mesh": {"elements": 4, "degree": 2}, "loads": {"steps": 1, **loads},
           "solid": {"mesh_size": 0.01}}
    with pytest.raises(ConfigError, match=f"loads\\] {key} is not supported by the 3D solid"):
        parse_solid(raw)


def test_fd_dynamics_refuses_point_forces():
    """The FD + Runge-Kutta baseline takes tip and distributed loads only (it dropped them)."""
    from fe_beam.analyses.transient import _run_finite_differences
    from fe_beam.config.transient import parse_dynamic

    cfg = config(point_forces=[[0.5, 0.0, 1.0]])
    cfg["material"]["rho"] = 7850.0
    cfg["time"] = {"t_end": 1e-3, "dt": 1e-4, "scheme": "fd-rk45"}
    with pytest.raises(ConfigError, match="point_forces"):
        _run_finite_differences(parse_dynamic(cfg), None, MPI.COMM_WORLD)


@pytest.mark.parametrize("loads, named", [
    ({"point_forces": [[0.05, 0.0, 0.01]]}, "loads.point_forces"),
    ({"end_rotation": 0.1}, "loads.end_rotation"),
])
def test_calibration_tension_column_refuses_point_loads(loads, named):
    """A tension data column scales every load with tendon 0's tension: point forces and
    end motions were scaled silently."""
    import numpy as np

    from fe_beam.analyses.calibrate import CalibrationData, CalibrationSpec, _load_factors
    from fe_beam.analyses.sensitivity import RodSensitivity

    raw = {"beam": {"length": 0.1},
           "section": {"shape": "rectangle", "b": 0.02, "h": 0.02, "h_tip": 0.01},
           "material": {"E": 0.6e6, "nu": 0.45}, "mesh": {"elements": 4, "degree": 2},
           "loads": {"steps": 2, **loads},
           "tendons": [{"offset_base": 0.008, "offset_tip": 0.004, "tension": 2.0}]}
    model = RodSensitivity(raw, ("material.E",))
    try:
        data = CalibrationData("tension", np.array([1.0, 2.0]),
                               {"tip_theta": np.array([0.2, 0.4])})
        with pytest.raises(ConfigError, match=f"{named} included"):
            _load_factors(model, data, CalibrationSpec(("material.E",)))
    finally:
        model.destroy()


def test_many_point_forces_superpose_quickly():
    """300 forces (at 300 inserted vertices, some at x = L and repeated x): the sum of the
    closed forms; one nodal force field (was: one integral each, ~2 min for 1000 forces)."""
    import time

    import numpy as np

    rng = np.random.default_rng(3)
    xs = np.round(rng.uniform(0.01, 1.0, 296), 6).tolist() + [L, L, 0.5, 0.5]
    P = 1e-8 * EI / L**2
    started = time.perf_counter()
    run = solved(config(point_forces=[[x, 0.0, P] for x in xs]))
    assert time.perf_counter() - started < 30
    expected = sum(P * a**2 * (3 * L - a) / (6 * EI) + P * a / GA for a in xs)
    assert run.problem.end_values("xL")["v"] == pytest.approx(expected, rel=1e-7)
    run.destroy()

"""[loads] point_moments: dead moments at points of the rod (planar [x, M] about z, spatial
[x, Mx, My, Mz] in world axes). Closed forms of a cantilever under a mid-span moment (linear
range, and the exact large-rotation answer: the clamped segment bends into a circular arc, the
rest stays straight) with the observed convergence order, a simply supported beam under an end
moment at x = 0, the spatial rod against the rotated planar answer and a mid-span torque,
2 ranks, the commands and the validation (exit 2, one sentence naming the key)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from mpi4py import MPI

from fe_beam.analyses.static import StaticContinuation
from fe_beam.cli import main
from fe_beam.config.schema import parse_static
from fe_beam.errors import ConfigError

E, NU, B, H, L = 2.0e11, 0.3, 0.01, 0.02, 1.0
EI = E * B * H**3 / 12
D = 0.02  # the spatial rod's circular section: equal bending stiffness about every axis
EI_ROUND = E * math.pi * D**4 / 64
GJ_ROUND = E / (2 * (1 + NU)) * math.pi * D**4 / 32


def config(law="reissner", constraint="none", elements=10, supports=None, spatial=False,
           **loads):
    section = ({"shape": "circle", "d": D} if spatial
               else {"shape": "rectangle", "b": B, "h": H})
    model = {"law": law, "constraint": constraint}
    if spatial:
        model["kinematics"] = "spatial"
    return {"beam": {"length": L}, "section": section, "material": {"E": E, "nu": NU},
            "model": model, "mesh": {"elements": elements, "degree": 2},
            "supports": supports or {"x0": "clamped", "xL": "free"},
            "loads": {"steps": 1, **loads}}


def solved(cfg, comm=MPI.COMM_WORLD):
    run = StaticContinuation(parse_static(cfg), comm)
    run.advance(1.0, run.config.stepping)
    return run


def arc_then_straight(k: float, a: float) -> np.ndarray:
    """Tip of a cantilever with a moment EI k at x = a: [0, a] a circular arc of curvature k
    (the bending moment is the applied one, no force anywhere), [a, L] straight along the
    angle k a."""
    phi = k * a
    return np.array([math.sin(phi) / k + (L - a) * math.cos(phi),
                     (1 - math.cos(phi)) / k + (L - a) * math.sin(phi)])


@pytest.mark.parametrize("law, constraint", [("reissner", "none"), ("nonstandard", "none"),
                                             ("reissner", "inextensible-unshearable")])
@pytest.mark.parametrize("a", [0.37, 0.5])
def test_small_moment_matches_beam_theory(law, constraint, a):
    """Linear range, M at x = a (0.37 between the uniform mesh's vertices: one is placed there;
    0.5 a vertex): theta = M a / EI beyond a, v(L) = M a (L - a/2) / EI (no shear force)."""
    M = -1e-6 * EI / L
    run = solved(config(law, constraint, point_moments=[[a, M]]))
    tip = run.problem.end_values("xL")
    assert tip["theta"] == pytest.approx(M * a / EI, rel=1e-9)
    assert tip["v"] == pytest.approx(M * a * (L - a / 2) / EI, rel=1e-8)
    assert run.problem.point_values(a)["theta"] == pytest.approx(M * a / EI, rel=1e-9)
    run.destroy()


@pytest.mark.parametrize("a", [0.37, 0.5])
def test_large_moment_bends_an_arc_then_a_straight_rest(a):
    """M = 2 EI / L at x = a: the tip within 1e-6 L of the exact position at 20 elements (the
    tip angle 2 a exact), the error falling with order ~4 (degree 2, nodal superconvergence)."""
    k = 2.0 / L
    errors = []
    for elements in (5, 10, 20):
        run = solved(config("reissner", elements=elements, steps=4,
                            point_moments=[[a, k * EI]]))
        tip = run.problem.end_values("xL")
        errors.append(float(np.hypot(*(np.array([L + tip["u"], tip["v"]])
                                       - arc_then_straight(k, a)))))
        assert tip["theta"] == pytest.approx(k * a, rel=1e-12)
        run.destroy()
    assert errors[-1] < 1e-6 * L
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert orders.min() > 3.5, (errors, orders)


def test_moments_superpose_at_ends_and_inside():
    """Simply supported (x0 pinned, xL roller; unshearable: the reactions are shear forces),
    small moments at x = 0 (a boundary vertex), at an interior x = c and at x = L: the end
    slopes of beam theory superposed. A counterclockwise M at x = c gives the bending moment
    EI theta' = -M (L - x) / L + M [x < c], hence theta(0) = M (2 L^2 - 6 L c + 3 c^2) /
    (6 EI L) (v(L) = 0) and theta(L) = M (3 c^2 - L^2) / (6 EI L)."""
    # 1e-5 EI/L: rotations of 1e-5, linear to 1e-10 (at 1e-6 EI/L the PyPI stack's Newton
    # stagnates at the round-off of this pinned-roller constrained rod and stops with exit 3)
    loads = [[0.0, 1e-5 * EI / L], [0.3, -2e-5 * EI / L], [L, 0.5e-5 * EI / L]]
    run = solved(config("reissner", "inextensible-unshearable",
                        supports={"x0": "pinned", "xL": "roller"}, point_moments=loads))
    left = sum(M * (2 * L**2 - 6 * L * c + 3 * c**2) / (6 * EI * L) for c, M in loads)
    right = sum(M * (3 * c**2 - L**2) / (6 * EI * L) for c, M in loads)
    assert run.problem.end_values("x0")["theta"] == pytest.approx(left, rel=1e-8)
    assert run.problem.end_values("xL")["theta"] == pytest.approx(right, rel=1e-8)
    run.destroy()


@pytest.mark.parametrize("a", [0.37, 0.5])
def test_spatial_moment_about_a_tilted_axis_is_the_rotated_planar_arc(a):
    """Round section, M = EI k n with n = Rx(beta) e_z at x = a: the planar arc-then-straight
    answer turned by beta about x (position to 1e-6 L; rotation vector k a n)."""
    k, beta = 1.5 / L, 0.7
    turn = np.array([[1, 0, 0], [0, math.cos(beta), -math.sin(beta)],
                     [0, math.sin(beta), math.cos(beta)]])
    n = turn @ [0.0, 0.0, 1.0]
    run = solved(config(elements=20, spatial=True, steps=4,
                        point_moments=[[a, *(EI_ROUND * k * n)]]))
    tip = run.problem.end_values("xL")
    expected = turn @ np.append(arc_then_straight(k, a), 0.0)
    assert np.abs(np.array(tip["position"]) - expected).max() < 1e-6 * L
    assert np.abs(np.array(tip["rotation_vector"]) - k * a * n).max() < 1e-12
    run.destroy()


def test_spatial_mid_span_torque_and_tip_equivalence():
    """A torque T at x = a twists the rest by T a / GJ (1.2 rad: large, exact); a point moment
    at x = L is the dead tip moment (one term, the same numbers to round-off)."""
    a, twist = 0.45, 1.2
    T = twist * GJ_ROUND / a
    run = solved(config(spatial=True, steps=3, point_moments=[[a, T, 0.0, 0.0]]))
    assert run.problem.end_values("xL")["rotation_vector"] == pytest.approx(
        [twist, 0.0, 0.0], abs=1e-12)
    run.destroy()
    moment = [0.3 * EI_ROUND, -0.8 * EI_ROUND, 0.4 * GJ_ROUND]
    ends = []
    for loads in ({"point_moments": [[L, *moment]]}, {"tip_moment": moment}):
        run = solved(config(spatial=True, steps=3, **loads))
        tip = run.problem.end_values("xL")
        ends.append(np.concatenate([tip["position"], tip["rotation_vector"]]))
        run.destroy()
    assert np.abs(ends[0] - ends[1]).max() < 1e-12
    assert np.abs(ends[0][3:]).max() > 0.3  # a large rotation


@pytest.mark.mpi
@pytest.mark.parametrize("spatial", [False, True])
def test_two_ranks_count_each_moment_once(spatial):
    """A moment at every interior vertex (one of them is where the ranks' parts meet): the
    same tip as one rank, and (planar, linear range) the superposed closed form."""
    elements = 8
    xs = [i * L / elements for i in range(1, elements)]
    scale = 1e-6 * (EI_ROUND if spatial else EI) / L
    moments = ([[x, 0.0, 0.0, scale * (1 + i)] for i, x in enumerate(xs)] if spatial
               else [[x, scale * (1 + i)] for i, x in enumerate(xs)])
    cfg = config(elements=elements, spatial=spatial, point_moments=moments)
    together, alone = solved(cfg), solved(cfg, MPI.COMM_SELF)
    names = ("u", "v", "w") if spatial else ("u", "v", "theta")
    for key in names:
        assert together.problem.end_values("xL")[key] == pytest.approx(
            alone.problem.end_values("xL")[key], rel=1e-10, abs=1e-16)
    if not spatial:
        expected = sum(m * x * (L - x / 2) / EI for x, m in moments)
        assert together.problem.end_values("xL")["v"] == pytest.approx(expected, rel=1e-8)
    together.destroy()
    alone.destroy()


@pytest.mark.parametrize("loads, spatial, message", [
    ({"point_moments": [[1.2, 1.0]]}, False, r"point_moments\[0\]: x = 1.2 is outside"),
    ({"point_moments": [[-0.1, 1.0]]}, False, r"point_moments\[0\]: x = -0.1 is outside"),
    ({"point_moments": [[0.5, 1.0], [0.5, 0.0, 0.0, 1.0]]}, False,
     r"point_moments\[1\] must be \[x, M\].*kinematics = \"spatial\""),
    ({"point_moments": [0.5, 1.0]}, False, r"point_moments\[0\] must be \[x, M\]"),
    ({"point_moments": 1.0}, False, "point_moments must be a list"),
    ({"point_moments": [[0.5, True]]}, False, r"point_moments\[0\] must be"),
    ({"point_moments": [[0.5, 1.0]]}, True, r"point_moments\[0\] must be \[x, Mx, My, Mz\]"),
    ({"point_moments": [[1.5, 0.0, 0.0, 1.0]]}, True, r"point_moments\[0\]: x = 1.5"),
    ({"point_moments": [[L, 1.0]], "end_rotation": 0.1}, False, "end_rotation prescribes"),
])
def test_bad_point_moments_exit_2(tmp_path, capsys, loads, spatial, message):
    from tomlio import dump_toml

    cfg = config(spatial=spatial, **loads)
    with pytest.raises(ConfigError, match=message):
        parse_static(cfg)
    path = tmp_path / "bad.toml"
    path.write_text(dump_toml(cfg))
    assert main(["static", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    error = capsys.readouterr().err.strip()
    assert "point_moments" in error and error.count("\n") == 0 and "Traceback" not in error


def test_fd_dynamics_and_the_solid_refuse_point_moments():
    """The FD + Runge-Kutta baseline and the 3D solid do not apply them: refused (the registry
    flags), not dropped."""
    from fe_beam.analyses.transient import _run_finite_differences
    from fe_beam.config.solid import parse_solid
    from fe_beam.config.transient import parse_dynamic

    cfg = config(point_moments=[[0.5, 1.0]])
    cfg["material"]["rho"] = 7850.0
    cfg["time"] = {"t_end": 1e-3, "dt": 1e-4, "scheme": "fd-rk45"}
    with pytest.raises(ConfigError, match="point_moments"):
        _run_finite_differences(parse_dynamic(cfg), None, MPI.COMM_WORLD)
    raw = config(point_moments=[[0.5, 1.0]])
    raw["solid"] = {"mesh_size": 0.01}
    with pytest.raises(ConfigError, match=r"loads\] point_moments is not supported by the 3D"):
        parse_solid(raw)


@pytest.mark.parametrize("scheme", ["generalized-alpha", "energy-conserving"])
def test_dynamic_step_moment_oscillates_about_the_static_answer(scheme):
    """fe-beam dynamic (undamped, time scale 1: a suddenly applied moment): the tip angle
    oscillates about the static M a / EI up to about twice it; the energy balance holds with
    the point moment's work M theta(a) as the external work (to the scheme's dissipation;
    exactly with the energy-conserving scheme, whose discrete gradient takes the moment)."""
    import fe_beam

    a, M = 0.5, 1e-4 * EI / L
    cfg = config(elements=8, point_moments=[[a, M]])
    cfg["material"]["rho"] = 7850.0
    period = 2 * math.pi / (1.875**2 * math.sqrt(EI / (7850.0 * B * H * L**4)))
    cfg["time"] = {"t_end": 1.5 * period, "dt": period / 60, "scheme": scheme}
    summary = fe_beam.run("dynamic", cfg)
    assert summary["status"] == "completed", summary.get("message")
    angles = np.array([s["tip"]["theta"] for s in summary["history"]])
    times = np.array([s["t"] for s in summary["history"]])
    static = M * a / EI
    # over 1.5 periods the first mode's cosine averages to 0: the mean in time is the static
    # angle (a time mean: the energy certificate may halve some steps)
    mean = np.sum(0.5 * (angles[1:] + angles[:-1]) * np.diff(times)) / (times[-1] - times[0])
    assert mean == pytest.approx(static, rel=0.02)
    assert 1.8 * static < angles.max() < 2.3 * static  # a suddenly applied load: twice
    energies = summary["history"][-1]["energies"]  # the point moment's work is accounted
    assert energies["external_work"] > 0
    allowed = 0.03 if scheme == "generalized-alpha" else 1e-8
    assert abs(energies["balance_residual"]) < allowed * energies["external_work"]


def equilibrium_config(spatial):
    """Moments inside (on vertices of 8 elements, one where 2 ranks meet, and between them),
    at x = L, with a force: the global balance needs each moment once."""
    moments = [[0.375, 40.0], [0.5, -25.0], [0.61, 15.0], [L, 10.0]]
    if spatial:
        moments = [[x, 0.3 * m, -0.5 * m, m] for x, m in moments]
    return config(elements=8, spatial=spatial, steps=3, point_moments=moments,
                  tip_force=[0.0, -30.0] + ([10.0] if spatial else []))


@pytest.mark.parametrize("spatial", [False, True])
def test_point_moments_enter_the_global_equilibrium(spatial):
    """The static run's global_equilibrium check balances the reactions against the point
    moments (without them the imbalance is ~1: exit 3)."""
    import fe_beam

    cfg = equilibrium_config(spatial)
    cfg["output"] = {"xdmf": False, "plots": False}
    summary = fe_beam.run("static", cfg, None)
    assert summary["status"] == "converged", summary.get("message")
    (check,) = [c for c in summary["checks"] if c["name"] == "global_equilibrium"]
    assert check["passed"] and check["value"] < 1e-9


def test_a_point_moment_off_by_one_percent_fails_the_balance(tmp_path, monkeypatch):
    from tomlio import dump_toml

    from fe_beam.fem import equilibrium

    original = equilibrium._point_moments
    monkeypatch.setattr(equilibrium, "_point_moments",
                        lambda problem, factor: original(problem, 1.01 * factor))
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(equilibrium_config(False)))
    assert main(["static", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 3
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "failed" and "global_equilibrium" in summary["message"]


@pytest.mark.mpi
def test_two_ranks_balance_the_point_moments_like_one():
    """Under mpirun -n 2: each point moment's wrench (its nodal values on the owning rank)
    equals the serial one."""
    from fe_beam.fem import equilibrium

    parsed = parse_static(equilibrium_config(True))
    terms = {}
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        run = StaticContinuation(parsed, comm)
        run.advance(1.0, parsed.stepping)
        terms[comm.size] = [t for t in equilibrium.rod_wrenches(run.problem)
                            if t.name.startswith("point moment")]
        run.destroy()
    assert len(terms[1]) == 4
    for world, alone in zip(terms[MPI.COMM_WORLD.size], terms[1], strict=True):
        assert world.name == alone.name
        np.testing.assert_allclose(world.moment, alone.moment, rtol=1e-12)


def test_moments_on_held_ends_keep_the_moment_field_certificates(tmp_path):
    """Clamped at both ends, moments at x = 0, at the end element's vertex and at x = L: the
    written fields' end moments are the reactions plus the moments on the held ends (the
    moment_field checks compared them with the reactions alone: 0.027 and 0.011, exit 3)."""
    from tomlio import dump_toml

    cfg = config(elements=6, supports={"x0": "clamped", "xL": "clamped"}, steps=2,
                 point_moments=[[0.0, 50.0], [L / 6, 100.0], [L, 20.0]])
    path = tmp_path / "held.toml"
    path.write_text(dump_toml(cfg))
    assert main(["static", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    names = {c["name"]: c for c in summary["checks"]}
    for name in ("moment_field_x0", "moment_field_xL", "global_equilibrium"):
        assert names[name]["passed"] and names[name]["value"] < 1e-9, name


@pytest.mark.parametrize("command", ["buckling", "path"])
def test_a_point_moment_alone_is_a_load_to_follow(command):
    """buckling (the reference load) and path (the followed load) accept point moments as
    the only load; all-zero moments are still no load (exit 2, naming point_moments)."""
    from fe_beam.config.buckling import parse_buckling
    from fe_beam.config.path import parse_path

    parse = parse_buckling if command == "buckling" else parse_path
    kind, static, _ = parse(config(point_moments=[[0.5, 1.0]]))
    assert kind == "rod" and static.model.loads.point_moments == ((0.5, 1.0),)
    with pytest.raises(ConfigError, match="point_moments"):
        parse(config(point_moments=[[0.5, 0.0]]))


@pytest.mark.parametrize("spatial", [False, True])
def test_interior_point_force_and_point_moment_together(spatial):
    """A point force and a point moment at different interior points of one rod (UFL refused
    the two interior-vertex measures of different subdomain data: an internal error, exit 1).
    Linear range, inextensible-unshearable, superposition of the closed forms: a force P at a
    and a moment M at c give v(L) = P a^2 (3 L - a) / (6 EI) + M c (2 L - c) / (2 EI)."""
    a, c = 0.37, 0.61
    ei = EI_ROUND if spatial else EI
    P, M = 1e-6 * ei / L**2, -2e-6 * ei / L
    loads = ({"point_forces": [[a, 0.0, P, 0.0]], "point_moments": [[c, 0.0, 0.0, M]]}
             if spatial else {"point_forces": [[a, 0.0, P]], "point_moments": [[c, M]]})
    run = solved(config("reissner", "inextensible-unshearable", spatial=spatial, **loads))
    tip = run.problem.end_values("xL")
    assert tip["v"] == pytest.approx(P * a**2 * (3 * L - a) / (6 * ei)
                                     + M * c * (2 * L - c) / (2 * ei), rel=1e-7)
    run.destroy()

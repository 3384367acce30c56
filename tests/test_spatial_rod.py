"""The spatial rod (issue 22): closed forms, the planar rod embedded in 3D, tendons routed
anywhere, the CLI contract. Each reference is computed here independently of the package
(numpy closed forms) or is the planar rod's own discretisation."""

import copy
import dataclasses
import json
import math

import numpy as np
import pytest
from mpi4py import MPI
from tomlio import dump_toml

from fe_beam.cli import main
from fe_beam.config.schema import parse_static
from fe_beam.errors import ConfigError
from fe_beam.model.laws import NonStandard, Reissner, Stiffness, Strains
from fe_beam.model.sections import Section
from fe_beam.model.settings import LoadStepping
from fe_beam.model.spatial import SpatialNonStandard, SpatialReissner, SpatialStrains
from fe_beam.model.tendons import Tendon
from fe_beam.solvers.rod_static import StaticContinuation
from fe_beam.timefunctions import parse_profile

E, NU = 1.0e7, 0.3
G = E / (2 * (1 + NU))


def expm_skew(vector):
    """exp(a^) by its series (independent of the package's Rodrigues formula)."""
    a = np.asarray(vector, dtype=float)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    result, term = np.eye(3), np.eye(3)
    for k in range(1, 60):
        term = term @ K / k
        result = result + term
    return result


def rotation_about_x(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rod(config_changes=None, **model):
    config = {
        "beam": {"length": 1.0},
        "section": {"shape": "circle", "d": 0.05},
        "material": {"E": E, "nu": NU},
        "model": {"kinematics": "spatial", "law": "reissner",
                  "constraint": "inextensible-unshearable"} | model,
        "mesh": {"elements": 24, "degree": 2},
        "loads": {"steps": 8},
    }
    for dotted, value in (config_changes or {}).items():
        table, key = dotted.split(".", 1)
        config.setdefault(table, {})[key] = value
    return config


def solve(config, tendons=(), comm=MPI.COMM_WORLD, steps=8):
    static = parse_static(config)
    if tendons:
        static = dataclasses.replace(static, tendons=tuple(tendons))
    run = StaticContinuation(static, comm)
    try:
        run.advance(1.0, LoadStepping(steps=steps))
        return run.problem.end_values()
    finally:
        run.destroy()


# --- the laws ----------------------------------------------------------------------------------
@pytest.mark.parametrize("shape, dims", [("rectangle", {"b": 0.02, "h": 0.05}),
                                         ("t-section", {"b": 0.05, "h": 0.06, "tf": 0.01,
                                                        "tw": 0.008}),
                                         ("circle", {"d": 0.03})])
def test_nonstandard_law_in_the_plane_is_the_planar_law(shape, dims):
    """u = (0, 0, kappa), v = (1 + e, g, 0): the spatial non-standard energy equals the planar
    one (section 1 of the model) at random strain states, including I3 != 0 (T-section)."""
    section = Section(shape, dims)
    planar, spatial = section.properties(), section.spatial_properties()
    stiffness = Stiffness(EA=E * planar.A, GA=G * planar.A, EI=E * planar.I, EI3=E * planar.I3,
                          EI4=E * planar.I4)
    law = SpatialNonStandard(E, G, spatial.moments, spatial.J)
    rng = np.random.default_rng(3)
    for _ in range(20):
        e, g, kappa = rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(-30, 30)
        eps = ((1 + e) ** 2 + g**2 - 1) / 2
        expected = NonStandard(stiffness).energy(Strains(1 + e, g, eps, kappa))
        value = law.energy(SpatialStrains((1 + e, g, 0.0), (0.0, 0.0, kappa)))
        assert value == pytest.approx(expected, rel=1e-12)


def test_reissner_law_in_the_plane_is_the_planar_law():
    stiffness = Stiffness(EA=3.0, GA=2.0, EI=5.0, EI3=0.0, EI4=0.0, shear_correction=0.8)
    law = SpatialReissner(3.0, 0.8 * 2.0, 7.0, 11.0, 5.0)
    for e, g, kappa in ((0.01, -0.02, 3.0), (-0.05, 0.03, -1.0)):
        eps = ((1 + e) ** 2 + g**2 - 1) / 2
        expected = Reissner(stiffness).energy(Strains(1 + e, g, eps, kappa))
        assert law.energy(SpatialStrains((1 + e, g, 0.0), (0.0, 0.0, kappa))) == \
            pytest.approx(expected, rel=1e-13)


def test_nonstandard_law_torsion_and_biaxial_bending():
    """Small strains: the spatial non-standard law's quadratic part is the Simo-Reissner law
    with GJ, EI_y, EI_z (its Hessian at the reference state, by finite differences)."""
    section = Section("rectangle", {"b": 0.02, "h": 0.05})
    p = section.spatial_properties()
    law = SpatialNonStandard(E, G, p.moments, p.J)
    step = 1e-5
    for index, expected in ((0, G * p.J), (1, E * p.Iy), (2, E * p.Iz)):
        u = np.zeros(3)
        u[index] = step
        value = law.energy(SpatialStrains((1.0, 0.0, 0.0), tuple(u)))
        assert 2 * value / step**2 == pytest.approx(expected, rel=1e-6)


def test_torsion_constant_of_a_rectangle():
    """J of a rectangle: the square's 0.140577 a^4, the thin strip's t^3 w / 3 (1 - 0.63 t/w)."""
    assert Section("rectangle", {"b": 1.0, "h": 1.0}).spatial_properties().J == \
        pytest.approx(0.1405770, abs=1e-7)
    thin = Section("rectangle", {"b": 0.001, "h": 0.1}).spatial_properties().J
    assert thin == pytest.approx(0.001**3 * 0.1 / 3 * (1 - 0.630 * 0.01), rel=2e-5)


# --- closed forms ------------------------------------------------------------------------------
def helix_tip(M, EI, length):
    """A straight, inextensible, unshearable rod of isotropic bending stiffness EI (any GJ) under
    a dead end moment M: the internal moment is M everywhere, and d1' = (M / EI) x d1, so the
    tangent turns about M at the rate |M| / EI: d1(s) = exp(s M^/EI) e1 and
    r(L) = int_0^L d1 ds (a helix about M), integrated here by the trapezoidal rule on 20001
    points plus Richardson extrapolation."""
    def chord(n):
        s = np.linspace(0, length, n)
        values = np.array([expm_skew(si * np.asarray(M) / EI)[:, 0] for si in s])
        trapezoid = getattr(np, "trapezoid", None) or np.trapz  # numpy 2 renamed it
        return trapezoid(values, s, axis=0)

    coarse, fine = chord(2001), chord(4001)
    return fine + (fine - coarse) / 3, expm_skew(length * np.asarray(M) / EI)[:, 0]


@pytest.mark.parametrize("moment", [[0.3, 0.4, 0.15], [-0.2, 0.1, -0.5], [0.6, 0.0, 0.0]])
def test_helix_under_a_dead_end_moment(moment):
    """Moments with components along and across the axis (GJ = EI / (1 + nu) != EI): the tip
    and its tangent against the closed-form helix, to 1e-8 L."""
    config = rod({"loads.tip_moment": moment})
    tip = solve(config)
    EI = E * math.pi * 0.05**4 / 64
    position, tangent = helix_tip(moment, EI, 1.0)
    assert np.abs(np.array(tip["position"]) - position).max() < 1e-8
    assert np.abs(np.array(tip["R"])[:, 0] - tangent).max() < 1e-8
    R = np.array(tip["R"])
    assert np.abs(R.T @ R - np.eye(3)).max() < 1e-12


def test_pure_torsion_twists_by_the_saint_venant_stiffness():
    """A twisting moment alone: theta_x(L) = M L / (G J) for a rectangle (its series J)."""
    config = rod({"section.shape": "rectangle", "section.b": 0.02, "section.h": 0.05,
                  "loads.tip_moment": [0.5, 0.0, 0.0]})
    del config["section"]["d"]
    tip = solve(config)
    J = Section("rectangle", {"b": 0.02, "h": 0.05}).spatial_properties().J
    assert tip["rotation_vector"][0] == pytest.approx(0.5 / (G * J), rel=1e-10)
    assert abs(tip["v"]) + abs(tip["w"]) < 1e-12


@pytest.mark.parametrize("constraint", ["inextensible-unshearable", "none"])
@pytest.mark.parametrize("offset", [(0.003, -0.004), (0.0, 0.005), (-0.002, 0.0)])
def test_straight_tendon_bends_into_a_circle_in_its_plane(constraint, offset):
    """A straight tendon at a constant offset (y, z): a circle of curvature tau |offset| / EI in
    the plane of the offset, bending toward the tendon (Reissner law; extensible: the axis is
    compressed by tau / EA as well)."""
    config = rod({"beam.length": 0.1, "section.d": 0.015, "material.E": 1e6},
                 constraint=constraint)
    tendon = Tendon(paths=(((0.0, 0.0), (0.1, 0.0)),), tension=1.0)
    object.__setattr__(tendon, "routing", tuple(parse_profile(c) for c in offset))
    tip = solve(config, [tendon])
    EI, EA = 1e6 * math.pi * 0.015**4 / 64, 1e6 * math.pi * 0.015**2 / 4
    y, z = offset
    kappa = math.hypot(y, z) / EI
    stretch = 1 - 1.0 / EA if constraint == "none" else 1.0
    along = stretch * math.sin(kappa * 0.1) / kappa
    across = stretch * (1 - math.cos(kappa * 0.1)) / kappa
    expected = np.array([along, across * y / math.hypot(y, z), across * z / math.hypot(y, z)])
    assert np.abs(np.array(tip["position"]) - expected).max() < 1e-8 * 0.1


# --- the planar rod embedded in 3D -------------------------------------------------------------
def planar_tip(config):
    planar = copy.deepcopy(config)
    planar["model"].pop("kinematics")
    static = parse_static(planar)
    run = StaticContinuation(static, MPI.COMM_WORLD)
    try:
        run.advance(1.0, LoadStepping(steps=8))
        return run.problem.end_values()
    finally:
        run.destroy()


PLANAR_CASES = [
    # law, constraint, section, the angles about x at which the planar answer must hold
    ("reissner", "none", {"shape": "rectangle", "b": 0.05, "h": 0.05}, (0.0, 0.7, 2.0)),
    ("nonstandard", "none", {"shape": "circle", "d": 0.05}, (0.0, 1.1)),
    ("nonstandard", "none", {"shape": "rectangle", "b": 0.03, "h": 0.06}, (0.0, math.pi / 2)),
    ("nonstandard", "inextensible", {"shape": "t-section", "b": 0.06, "h": 0.06, "tf": 0.01,
                                     "tw": 0.01}, (0.0,)),
    ("reissner", "inextensible-unshearable", {"shape": "rectangle", "b": 0.05, "h": 0.05},
     (0.0, -2.5)),
]


@pytest.mark.parametrize("law, constraint, section, angles", PLANAR_CASES)
def test_planar_case_rotated_about_the_axis_equals_the_planar_answer(law, constraint, section,
                                                                     angles):
    """A cantilever under a tip force (P L^2 / EI = 3) and a tip moment in the x-y plane, rotated
    by an angle about x (a rectangle turned by 90 degrees with it: b and h swapped): the
    spatial rod's answer is the planar rod's, rotated, to 1e-8 L."""
    EI = E * Section(section["shape"], {k: v for k, v in section.items() if k != "shape"}
                     ).properties().I
    config = {
        "beam": {"length": 1.0}, "section": dict(section),
        "material": {"E": E, "nu": NU},
        "model": {"kinematics": "spatial", "law": law, "constraint": constraint},
        "mesh": {"elements": 16, "degree": 2},
        "loads": {"tip_force": [0.5 * EI, -3.0 * EI], "tip_moment": 0.4 * EI, "steps": 8},
    }
    reference = planar_tip(config)
    for angle in angles:
        rotated = copy.deepcopy(config)
        Q = rotation_about_x(angle)
        if section["shape"] == "rectangle" and abs(math.sin(angle)) == 1.0:
            rotated["section"]["b"], rotated["section"]["h"] = section["h"], section["b"]
        rotated["loads"]["tip_force"] = list(Q @ np.array([0.5 * EI, -3.0 * EI, 0.0]))
        rotated["loads"]["tip_moment"] = list(Q @ np.array([0.0, 0.0, 0.4 * EI]))
        tip = solve(rotated)
        expected = Q @ np.array([reference["u"], reference["v"], 0.0])
        got = np.array([tip["u"], tip["v"], tip["w"]])
        assert np.abs(got - expected).max() < 1e-8, (angle, got, expected)
        assert np.array(tip["rotation_vector"]) == pytest.approx(
            Q @ np.array([0.0, 0.0, reference["theta"]]), abs=1e-8)


# --- a published benchmark ---------------------------------------------------------------------
BATHE_BOLOURCHI = {
    "beam": {"length": 100 * math.pi / 4, "initial_curvature": [0.0, 0.0, 0.01]},
    # Simo & Vu-Quoc's section: A = 1, I = 1/12 about both axes, J = 1/6 (the polar moment)
    "section": {"shape": "custom", "A": 1.0, "I": 1 / 12, "I_y": 1 / 12, "J": 1 / 6, "b": 1.0,
                "h": 1.0},
    "material": {"E": 1e7, "G": 5e6},
    "model": {"kinematics": "spatial", "law": "reissner"},
    "mesh": {"elements": 16, "degree": 2},
    "loads": {"tip_force": [0.0, 0.0, 600.0], "steps": 10},
}


def test_bathe_bolourchi_bend_against_the_published_tips():
    """The 45-degree bend (R = 100, in the x-y plane) under a tip load normal to its plane: the
    tip at P = 300 and 600 against Simo & Vu-Quoc (1986, 8 elements: (58.84, 22.33, 40.08) and
    (47.23, 15.79, 53.37)), within the spread of published discretisations (0.25)."""
    static = parse_static(BATHE_BOLOURCHI)
    run = StaticContinuation(static, MPI.COMM_WORLD)
    tips = {}
    try:
        for factor in (0.5, 1.0):
            run.advance(factor, LoadStepping(steps=5))
            tips[factor] = np.array(run.problem.end_values()["position"])
    finally:
        run.destroy()
    assert tips[0.5] == pytest.approx([58.84, 22.33, 40.08], abs=0.25)
    assert tips[1.0] == pytest.approx([47.23, 15.79, 53.37], abs=0.25)


def test_curved_rod_relaxes_into_its_stress_free_shape():
    """No load: the ring arc of constant curvature k_z is its own stress-free shape (the tip on
    the circle of radius 1/k_z; P2 converges to it at the observed order 4), and the
    displacements are measured from it."""
    errors = []
    for elements in (12, 24):
        config = rod({"beam.initial_curvature": [0.0, 0.0, 2.0], "mesh.elements": elements},
                     law="nonstandard", constraint="none")
        run = StaticContinuation(parse_static(config), MPI.COMM_WORLD)
        try:
            tip = run.problem.end_values()
        finally:
            run.destroy()
        exact = [math.sin(2.0) / 2, (1 - math.cos(2.0)) / 2, 0.0]
        errors.append(np.abs(np.array(tip["position"]) - exact).max())
        assert tip["rotation_vector"] == pytest.approx([0.0, 0.0, 2.0], abs=1e-10)
        assert abs(tip["u"]) + abs(tip["v"]) + abs(tip["w"]) < 1e-12
    assert errors[1] < 1e-7
    assert math.log2(errors[0] / errors[1]) > 3.5, errors


# --- the command line ----------------------------------------------------------------------------
def run_cli(tmp_path, config, command="static", capsys=None):
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(config))
    out = tmp_path / "out"
    code = main([command, str(path), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err if capsys is not None else ""
    return code, err, out


def test_static_command_writes_the_tip_frame(tmp_path, capsys):
    config = rod({"loads.tip_force": [0.0, 2.0, -3.0], "loads.tip_moment": [0.1, 0.0, 0.0],
                  "output.plots": True})
    code, err, out = run_cli(tmp_path, config, capsys=capsys)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    tip = summary["steps"][-1]["tip"]
    assert set(tip) >= {"u", "v", "w", "R", "rotation_vector"}
    R = np.array(tip["R"])
    assert np.abs(R @ R.T - np.eye(3)).max() < 1e-12
    assert R == pytest.approx(expm_skew(tip["rotation_vector"]), abs=1e-12)
    assert summary["model"]["kinematics"] == "spatial"
    header = (out / "load_displacement.csv").read_text().splitlines()[0].split(",")
    assert header == ["load_factor", "tip_u", "tip_v", "tip_w", "tip_rotation_x",
                      "tip_rotation_y", "tip_rotation_z", "newton_iterations"]
    xdmf = (out / "beam.xdmf").read_text()
    for name in ("displacement", "rotation_vector", "d1", "d2", "d3", "twist"):
        assert f'Name="{name}"' in xdmf
    assert (out / "deformed_shapes.png").stat().st_size > 10_000


@pytest.mark.parametrize("changes, command, message", [
    ({}, "design", "does not run spatial rods yet"),
    ({"model.kinematics": "3d"}, "static", "kinematics must be"),
    ({"model.law": "hyperelastic"}, "static", "not available for kinematics"),
    ({"loads.tip_force": [1.0, 2.0, 3.0, 4.0]}, "static", "tip_force must be a vector"),
    ({"supports.x0": ["u", "phi"]}, "static", "components must be distinct names"),
    ({"supports.x0": "pinned"}, "static", "rigid body"),
    ({"beam.initial_curvature": [0.0, "1/x", 0.0]}, "static", "unknown name"),
    ({"beam.initial_curvature": [0.0, 1.0]}, "static", "initial_curvature must be"),
])
def test_spatial_mistakes_exit_2(tmp_path, capsys, changes, command, message):
    config = rod(changes)
    code, err, _ = run_cli(tmp_path, config, command, capsys)
    assert code == 2, err
    assert message in err and "Traceback" not in err


def test_planar_rod_refuses_spatial_keys():
    config = rod({"loads.tip_force": [1.0, 2.0, 3.0]})
    config["model"]["kinematics"] = "planar"
    with pytest.raises(ConfigError, match="kinematics = \"spatial\""):
        parse_static(config)
    config = rod({"beam.initial_curvature": [0.0, 0.0, 1.0]})
    del config["model"]["kinematics"]
    with pytest.raises(ConfigError, match="initial_curvature needs"):
        parse_static(config)


@pytest.mark.mpi
def test_spatial_rod_in_parallel_equals_serial():
    config = rod({"loads.tip_force": [0.3, 2.0, -3.0], "loads.tip_moment": [0.2, 0.1, 0.0]},
                 law="nonstandard", constraint="none")
    together = solve(config, comm=MPI.COMM_WORLD)
    alone = solve(config, comm=MPI.COMM_SELF)
    for key in ("u", "v", "w"):
        assert together[key] == pytest.approx(alone[key], rel=1e-9, abs=1e-12)
    assert np.array(together["R"]) == pytest.approx(np.array(alone["R"]), abs=1e-10)


@pytest.mark.parametrize("b, h", [(0.02, 0.03), (0.05, 0.05), (0.03, 0.012), (0.004, 0.05)])
def test_torsion_constant_is_the_converged_series(b, h):
    """Saint-Venant's series of J summed to convergence (issue 28, small items): against the
    series summed here term by term with its tanh over 100 000 odd n (remainder < 1e-22).
    Was: 12 terms, J 2.7e-7 (b/h = 2/3), 5.6e-7 (square), 1.3e-7 (0.4) too large."""
    t, w = min(b, h), max(b, h)
    series = math.fsum(math.tanh(n * math.pi * w / (2 * t)) / n**5
                       for n in range(199_999, 0, -2))
    reference = t**3 * w / 3 * (1 - 192 * t / (math.pi**5 * w) * series)
    J = Section("rectangle", {"b": b, "h": h}).spatial_properties().J
    assert J == pytest.approx(reference, rel=2e-15)

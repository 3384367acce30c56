"""Adjoint sensitivities (fe_beam.analyses.sensitivity) against central finite differences of the
converged equilibrium: every parameter kind, rod and finger (tension and pull-in control),
serial and on 2 MPI ranks (``mpirun -n 2 ... -m mpi``)."""

import numpy as np
import pytest

from fe_beam.analyses.sensitivity import RodSensitivity
from fe_beam.errors import ConfigError

TOLERANCE = 1e-6


def finite_differences(model, outputs, step=1e-3):
    """4th-order central differences (steps +-h, +-2h, h = step |p|; at 1e-3 the truncation
    is ~1e-12 and the solver's round-off over h well below 1e-6) of the outputs at load
    factor 1, each parameter in turn; the model is left at its original parameters."""
    start = model.values()
    columns = []
    for k in range(len(start)):
        h = step * (abs(start[k]) if start[k] != 0 else 1.0)
        values = []
        for multiple in (2, 1, -1, -2):
            p = start.copy()
            p[k] += multiple * h
            model.set_values(p)
            model.solve(1.0)
            values.append(model.outputs(outputs))
        columns.append((-values[0] + 8 * values[1] - 8 * values[2] + values[3]) / (12 * h))
    model.set_values(start)
    model.solve(1.0)
    return np.array(columns).T


def check_gradient(raw, parameters, outputs, skip=()):
    """Adjoint vs finite differences: |fd - adjoint| <= 1e-6 max(|adjoint|, floor), the floor
    1e-6 |J| / |p| (an entry far below the natural scale of output over parameter is compared
    at that scale). Returns the largest relative error per parameter."""
    model = RodSensitivity(raw, parameters)
    try:
        model.solve(1.0)
        values = model.outputs(outputs)
        adjoint = model.gradient(outputs)
        fd = finite_differences(model, outputs)
        again = model.gradient(outputs)  # after the parameter round trip: the same state
        p = model.values()
    finally:
        model.destroy()
    np.testing.assert_allclose(again, adjoint, rtol=1e-7, atol=0)
    scale = np.abs(values)[:, None] / np.where(p != 0, np.abs(p), 1.0)[None, :]
    floor = np.maximum(np.abs(adjoint), 1e-6 * scale + 1e-300)
    error = np.abs(fd - adjoint) / floor
    for j, name in enumerate(outputs):
        if name in skip:
            error[j] = 0.0
    worst = error.max(axis=0)
    assert np.all(worst <= TOLERANCE), dict(zip(parameters, worst.tolist(), strict=True))
    # the check can fail: a gradient that is wrong by the tolerance would be noticed
    assert np.any(np.abs(adjoint) > 0)
    return dict(zip(parameters, worst.tolist(), strict=True))


def rod(**changes):
    raw = {"beam": {"length": 1.2},
           "section": {"shape": "rectangle", "b": 0.012, "h": 0.01},
           "material": {"E": 2.0e11, "nu": 0.3, "rho": 7800.0},
           "mesh": {"elements": 6, "degree": 2},
           "loads": {"tip_force": [60.0, -420.0], "tip_moment": 15.0, "distributed": [0.0, -40.0],
                     "gravity": [0.0, -9.81], "steps": 4},
           "solver": {"rtol": 1e-12}}
    for key, value in changes.items():
        table, name = key.split("__")
        raw.setdefault(table, {})[name] = value
    return raw


ROD_OUTPUTS = ["tip_u", "tip_v", "tip_theta", "x@0.5", "y@0.5", "y@0.83"]


@pytest.mark.mpi
def test_rod_material_section_and_load_parameters():
    params = ["material.E", "material.nu", "section.h", "section.b_tip", "loads.tip_force.0",
              "loads.tip_force.1", "loads.tip_moment", "loads.distributed.1", "loads.gravity.1"]
    check_gradient(rod(), params, ROD_OUTPUTS)


@pytest.mark.mpi
def test_rod_shear_modulus_reissner_follower_inextensible():
    """G given (E and G independent), the Reissner law, a follower tip force and the axial
    multiplier of an inextensible rod (mixed formulation)."""
    raw = rod(model__law="reissner", model__constraint="inextensible", loads__follower=True)
    raw["material"] = {"E": 2.0e11, "G": 7.0e10, "rho": 7800.0}
    raw["mesh"]["degree"] = 1
    raw["mesh"]["elements"] = 8
    check_gradient(raw, ["material.E", "material.G", "section.h_tip", "loads.tip_force.1"],
                   ROD_OUTPUTS)


@pytest.mark.mpi
def test_rod_custom_section_and_unshearable():
    raw = rod(model__constraint="unshearable")
    raw["section"] = {"shape": "custom", "A": 1.2e-4, "I": 1.0e-9, "I3": 2.0e-12, "I4": 2.0e-13,
                      "I_tip": 0.6e-9}
    check_gradient(raw, ["section.A", "section.I", "section.I3", "section.I4", "section.I_tip",
                         "section.A_tip"], ROD_OUTPUTS)


@pytest.mark.mpi
def test_t_section_roller_with_prescribed_rotation():
    """A T-section (I3 != 0), clamped with a prescribed end rotation (a Dirichlet value scaled
    by the load factor) and on a roller at x = L, degree 1, distributed load and gravity."""
    raw = rod(supports__x0="clamped", supports__xL="roller")
    raw["section"] = {"shape": "t-section", "b": 0.03, "h": 0.02, "tf": 0.004, "tw": 0.005}
    raw["loads"] = {"distributed": [0.0, -2000.0], "gravity": [0.0, -9.81], "tip_moment": 40.0,
                    "prescribed_x0": {"theta": 0.05}, "steps": 4}
    raw["mesh"] |= {"degree": 1, "elements": 12}
    check_gradient(raw, ["section.b", "section.h", "section.tf", "section.tw_tip", "material.E",
                         "material.rho", "loads.distributed.1", "loads.tip_moment"],
                   ["tip_u", "tip_theta", "x@0.4", "y@0.4", "y@0.77"])


def finger(control="tension"):
    first = {"name": "a", "path": [[0.0, 0.006], [0.04, 0.0055], [0.1, 0.003]]}
    first |= {"pull_in": 0.004} if control == "pull_in" else {"tension": 1.5}
    return {"beam": {"length": 0.1},
            "section": {"shape": "rectangle", "b": 0.02, "h": 0.02, "h_tip": 0.012},
            "material": {"E": 0.6e6, "nu": 0.45},
            "mesh": {"elements": 6, "degree": 2},
            "loads": {"steps": 4, "tip_force": [0.0, -0.2]},
            "tendons": [first,
                        {"offset_base": -0.005, "offset_tip": -0.003, "tension": 0.5,
                         "entry": 0.02},
                        {"paths": [[[0.0, 0.004], [0.1, 0.002]], [[0.0, -0.002], [0.1, 0.0]]],
                         "tension": 0.3}],
            "solver": {"rtol": 1e-12}}


FINGER_OUTPUTS = ["tip_u", "tip_v", "tip_theta", "x@0.06", "y@0.03", "pull_in.0", "pull_in.1",
                  "pull_in.2"]


@pytest.mark.mpi
def test_finger_tension_control():
    params = ["material.E", "section.h_tip", "tendons.0.path.1.1", "tendons.0.path.0.1",
              "tendons.1.offset_base", "tendons.1.offset_tip", "tendons.2.paths.1.0.1",
              "tendons.0.tension", "tendons.1.tension", "loads.tip_force.1"]
    check_gradient(finger(), params, FINGER_OUTPUTS)


@pytest.mark.mpi
def test_finger_pull_in_control():
    """Tendon 0's tension is an unknown set by its pull-in: the bordered adjoint."""
    params = ["tendons.0.pull_in", "material.E", "tendons.0.path.2.1", "tendons.1.offset_tip",
              "tendons.1.tension", "section.h"]
    check_gradient(finger("pull_in"), params, FINGER_OUTPUTS + ["tension.0"],
                   skip=("pull_in.0",))  # prescribed: its exact derivative is 0 or 1


def test_pull_in_derivative_of_prescribed_pull_in():
    model = RodSensitivity(finger("pull_in"), ["tendons.0.pull_in", "material.E"])
    try:
        model.solve(1.0)
        grad = model.gradient(["pull_in.0"])
    finally:
        model.destroy()
    np.testing.assert_allclose(grad[0], [1.0, 0.0], atol=1e-9)


@pytest.mark.parametrize("key, problem", [
    ("material.X", "unknown parameter"),
    ("section.d", "section.d is not in the configuration"),
    ("tendons.5.tension", "there are 3 tendons"),
    ("tendons.0.offset_tip", "given by a path"),
    ("tendons.0.path.7.1", "no such path point"),
    ("tendons.0.path.1.0", "unknown parameter"),
    ("material.G", "gives material.nu"),
])
def test_unusable_parameters(key, problem):
    with pytest.raises(ConfigError, match=problem):
        RodSensitivity(finger(), [key])


def test_point_evaluation_matches_interpolation():
    """x@S, y@S: the deformed backbone between nodes, against dolfinx's own evaluation."""
    from fe_beam.fem import compat

    model = RodSensitivity(rod(), ["material.E"])
    try:
        model.solve(1.0)
        problem = model.problem
        u, v = problem.w.sub(0).collapse(), problem.w.sub(1).collapse()
        tree = compat.bounding_box_tree(problem.mesh, 1)
        for s in (0.0, 0.137, 0.5, 0.91, 1.2):
            point = np.array([[s, 0.0, 0.0]])
            cell = compat.first_colliding_cells(problem.mesh, tree, point)[:1]
            expected = [s + u.eval(point, cell)[0], v.eval(point, cell)[0]]
            got = model.outputs([f"x@{s}", f"y@{s}"])
            np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-15)
    finally:
        model.destroy()


def coarse_solid():
    import tomllib
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "examples" / "finger_solid.toml"
    raw = tomllib.loads(path.read_text())
    raw.pop("compare", None)
    raw["solid"] |= {"mesh_size": 0.01, "order": 1}
    raw["loads"] |= {"tip_force": [0.05, 0.3], "steps": 3}
    raw["solver"] = {"rtol": 1e-12}
    return raw


@pytest.mark.mpi
def test_solid_tip_displacement():
    """The coarse 3D finger: material (neo-Hookean E, nu), tip force, cable tension (a
    non-UFL residual term)."""
    from fe_beam.analyses.sensitivity import SolidSensitivity

    params = ["material.E", "material.nu", "loads.tip_force.0", "loads.tip_force.1",
              "tendons.0.tension"]
    outputs = ["tip_u", "tip_v", "tip_w"]
    model = SolidSensitivity(coarse_solid(), params)
    try:
        model.solve(1.0)
        values = model.outputs(outputs)
        adjoint = model.gradient(outputs)
        fd = finite_differences(model, outputs)
        p = model.values()
    finally:
        model.destroy()
    scale = np.abs(values)[:, None] / np.abs(p)[None, :]
    error = np.abs(fd - adjoint) / np.maximum(np.abs(adjoint), 1e-6 * scale)
    assert np.all(error <= TOLERANCE), error
    assert np.all(np.abs(adjoint[:2]) > 0)


def test_solid_refuses_other_parameters():
    from fe_beam.analyses.sensitivity import SolidSensitivity

    with pytest.raises(ConfigError, match="not a 3D-solid parameter"):
        SolidSensitivity(coarse_solid(), ["section.h"])
    raw = coarse_solid()
    raw["tendons"][0].pop("tension")
    raw["tendons"][0]["pull_in"] = 0.002
    with pytest.raises(ConfigError, match="tension-controlled"):
        SolidSensitivity(raw, ["material.E"])


def test_from_parsed_config_matches_raw():
    from fe_beam.analyses.finger import parse_finger

    raw = finger()
    parsed, _ = parse_finger(raw)
    values = []
    for model in (RodSensitivity(raw, ["material.E", "tendons.1.offset_tip"]),
                  RodSensitivity.from_config(parsed, ["material.E", "tendons.1.offset_tip"])):
        try:
            model.solve(1.0)
            values.append(model.gradient(["tip_theta", "y@0.05"]))
        finally:
            model.destroy()
    np.testing.assert_allclose(values[1], values[0], rtol=1e-12)
    assert np.all(np.abs(values[0]) > 0)


@pytest.mark.mpi
def test_backbone_distances_of_unlabelled_points():
    """Signed distances of points to the deformed backbone (nearest point inside the rod and
    at its tip) against finite differences, and the projection's own consistency."""
    params = ["material.E", "tendons.0.path.1.1", "tendons.1.tension", "section.h_tip"]
    model = RodSensitivity(finger(), params)
    try:
        model.solve(1.0)
        on = model.outputs(["x@0.03", "y@0.03", "x@0.081", "y@0.081", "x@0.1", "y@0.1"])
        on = on.reshape(-1, 2)
        points = on + np.array([[0.001, -0.002], [-0.0005, 0.003], [0.002, 0.001]])
        S, r, t = model.project(on)
        np.testing.assert_allclose(S, [0.03, 0.081, 0.1], atol=1e-9)
        distances, adjoint = model.backbone_distances(points)
        S, r, t = model.project(points)
        assert S[-1] == pytest.approx(0.1)  # beyond the tip: the tip is the nearest point
        np.testing.assert_allclose(np.abs(distances), np.linalg.norm(r - points, axis=1),
                                   rtol=1e-12)
        start, fd = model.values(), []
        for k in range(len(start)):
            h, values = 1e-3 * abs(start[k]), []
            for multiple in (2, 1, -1, -2):
                p = start.copy()
                p[k] += multiple * h
                model.set_values(p)
                model.solve(1.0)
                values.append(model.backbone_distances(points)[0])
            fd.append((-values[0] + 8 * values[1] - 8 * values[2] + values[3]) / (12 * h))
        fd = np.array(fd).T
    finally:
        model.destroy()
    assert np.all(np.abs(fd - adjoint) <= TOLERANCE * np.abs(adjoint)), fd / adjoint - 1


def test_finger_without_section_table_uses_the_finger_defaults():
    """A finger config that leaves [section] to the chapter's defaults: its dimensions are
    parameters too, with the same gradient as when the default table is written out."""
    from fe_beam.config.finger import DEFAULT_FINGER

    tendon = {"tension": 2.0, "offset_base": 0.006, "offset_tip": 0.004}
    implicit = RodSensitivity({"tendons": [tendon]}, ["section.h", "tendons.0.offset_tip"])
    explicit = RodSensitivity({"tendons": [tendon], "section": dict(DEFAULT_FINGER["section"])},
                              ["section.h", "tendons.0.offset_tip"])
    results = []
    for model in (implicit, explicit):
        model.solve()
        results.append(model.gradient(["tip_theta"])[0])
        model.destroy()
    assert np.all(np.abs(results[0]) > 0)
    np.testing.assert_allclose(results[0], results[1], rtol=1e-12)

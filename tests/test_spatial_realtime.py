"""Issue 22, item 8: the real-time solver and the cache of built problems on spatial rods.

A warm re-solve of the spatial finger (helical tendon) equals a fresh `solve_static` of the
same values, also after a failed update; a cache hit never serves a problem of another
structure (everything compiled into a spatial problem's forms is in `structure_key`: a wrong
hit would give a wrong number with exit 0)."""

import copy

import numpy as np
import pytest
from mpi4py import MPI

from fe_beam.analyses.finger import parse_finger
from fe_beam.analyses.static import solve_static
from fe_beam.config.schema import parse_static
from fe_beam.solvers import realtime
from fe_beam.solvers.realtime import RealtimeSolver, UpdateFailed, set_parameters, structure_key

HELIX = {"offset_y": "0.004*cos(pi*s/(2*L))", "offset_z": "0.004*sin(pi*s/(2*L))"}


def finger_dict(elements=20, tension=1.0, **changes) -> dict:
    """The soft spatial finger of tests/test_spatial_baseline.py (L = 0.1 m, circle d = 15 mm,
    E = 1 MPa) with a helical tendon turning by 90 degrees, degree 2; Newton to rtol 1e-11."""
    config = {"beam": {"length": 0.1}, "section": {"shape": "circle", "d": 0.015},
              "material": {"E": 1e6, "nu": 0.45},
              "model": {"kinematics": "spatial", "law": "reissner", "constraint": "unshearable"},
              "mesh": {"elements": elements, "degree": 2}, "loads": {"steps": 4},
              "solver": {"rtol": 1e-11},
              "tendons": [dict(HELIX, tension=tension)],
              "output": {"plots": False, "xdmf": False}}
    for dotted, value in changes.items():
        table, key = dotted.split(".", 1)
        if table == "tendons":
            config["tendons"][0][key] = value
        else:
            config.setdefault(table, {})[key] = value
    return config


def finger(**changes):
    config, _ = parse_finger(finger_dict(**changes))
    return config


def fresh_tip(config, comm=MPI.COMM_WORLD, cache=True, monkeypatch=None) -> dict:
    if not cache:
        monkeypatch.setenv("FE_BEAM_PROBLEM_CACHE", "0")
    try:
        result = solve_static(config, None, comm, progress=False, record_shapes=False)
    finally:
        if not cache:
            monkeypatch.delenv("FE_BEAM_PROBLEM_CACHE")
    assert result.status == "converged", result.message
    return result.steps[-1]["tip"]


def tip_vector(tip) -> np.ndarray:
    return np.array([tip["u"], tip["v"], tip["w"], *tip["rotation_vector"]])


def assert_close(tip, reference, length, tol):
    a, b = tip_vector(tip), tip_vector(reference)
    scale = np.array([length] * 3 + [1.0] * 3)
    assert np.all(np.abs(a - b) <= tol * scale), (a, b)


@pytest.mark.parametrize("check", [True, False])
def test_warm_resolves_after_a_failed_update_are_fresh_solves(check):
    """1.5 N, 1.7 N, then 5000 N (no equilibrium: UpdateFailed, the last one kept), then
    0.6, 0.6, 2.2 N: each answer equals solve_static of that tension to 1e-8 (L, rad), the
    fast path (chord predictor, banded LU of the 326 dofs) included."""
    config = finger()
    length = config.model.length
    with RealtimeSolver(config, check=check) as solver:
        assert solver.dense and solver.problem.global_dofs > realtime.BANDED_MIN_DOFS
        assert_close(solver.tip(), fresh_tip(config), length, 1e-8)
        for tension in (1.5, 1.7):
            tip = solver.update(tensions=[tension])
            assert_close(tip, fresh_tip(set_parameters(config, {"tendons.0.tension": tension})),
                         length, 1e-8)
        before = solver.tip()
        with pytest.raises(UpdateFailed):
            solver.update(tensions=[5000.0])
        assert solver.tip() == before and solver.config.tendons[0].tension == 1.7
        for tension in (0.6, 0.6, 2.2):
            tip = solver.update(tensions=[tension])
            target = set_parameters(config, {"tendons.0.tension": tension})
            assert_close(tip, fresh_tip(target), length, 1e-8)
            assert solver.tendons.tendons[0].tension == tension
        # a tip force with a z component (loads.tip_force.2) on the same structure
        tip = solver.update(parameters={"loads.tip_force.2": -0.05})
        target = set_parameters(target, {"loads.tip_force.2": -0.05})
        assert_close(tip, fresh_tip(target), length, 1e-8)
        assert solver.statistics["fallbacks"] >= 1


def test_a_routed_tendon_refuses_offset_parameters():
    """Its offsets are formulas compiled into the forms: a path offset would be ignored."""
    with pytest.raises(KeyError, match="routed by formulas"):
        set_parameters(finger(elements=4), {"tendons.0.offset_tip": 0.002})


def rod_dict(**changes) -> dict:
    """A small spatial cantilever (circle, Reissner, 4 P2 elements) under a tip force with y
    and z components."""
    config = {"beam": {"length": 1.0}, "section": {"shape": "circle", "d": 0.05},
              "material": {"E": 2e8, "nu": 0.3},
              "model": {"kinematics": "spatial", "law": "reissner", "constraint": "none"},
              "mesh": {"elements": 4, "degree": 2},
              "loads": {"steps": 3, "tip_force": [0.0, -60.0, 40.0]},
              "solver": {"rtol": 1e-11}}
    for dotted, value in changes.items():
        table, key = dotted.split(".", 1)
        if value is None:
            config[table].pop(key, None)
        else:
            config.setdefault(table, {})[key] = value
    return config


# Each: a structure B that differs from A (rod_dict()) in one thing compiled into the forms.
STRUCTURES = {
    "tip moment nonzero": {"loads.tip_moment": [0.5, 0.0, 1.0]},
    "follower": {"loads.follower": True},
    "initial curvature": {"beam.initial_curvature": [0.0, 0.3, 0.0]},
    "initial curvature formula": {"beam.initial_curvature": [0.0, "0.3*s/L", 0.0]},
    "point force": {"loads.point_forces": [[0.5, 0.0, 0.0, 30.0]]},
    "supports": {"supports.xL": ["v"]},
    "law": {"model.law": "nonstandard"},
    "constraint": {"model.constraint": "inextensible-unshearable"},
    "section shape": {"section.shape": "rectangle", "section.d": None, "section.h": 0.05,
                      "section.b": 0.04},
    "degree": {"mesh.degree": 1, "mesh.elements": 8},
    "elements": {"mesh.elements": 5},
    "planar": {"model.kinematics": None, "loads.tip_force": [0.0, -60.0]},
}


def config_of(changes: dict):
    return parse_static(rod_dict(**changes))


def test_structure_key_sees_every_compiled_difference():
    """Cheap: every change of STRUCTURES, of the rectangle's thinner side, of a routing
    formula and of a constant routing's value changes the key; the numbers held by Constants
    (material, loads, tension) do not."""
    comm = MPI.COMM_WORLD
    base = structure_key(config_of({}), comm)
    for name, changes in STRUCTURES.items():
        assert structure_key(config_of(changes), comm) != base, name
    for same in ({"material.E": 3e8}, {"loads.tip_force": [1.0, 2.0, 3.0]},
                 {"section.d": 0.04}, {"loads.tip_moment": [0.0, 0.0, 0.0]}):
        assert structure_key(config_of(same), comm) == base, same
    rectangle = {"section.shape": "rectangle", "section.d": None, "section.h": 0.05}
    assert structure_key(config_of(rectangle | {"section.b": 0.04}), comm) != structure_key(
        config_of(rectangle | {"section.b": 0.06}), comm)  # J's series: b or h the thinner
    key = structure_key(finger(elements=4), comm)
    assert structure_key(finger(elements=4, tension=2.0), comm) == key
    for tendon in ({"tendons.offset_z": "0.004*sin(pi*s/(3*L))"},
                   {"tendons.offset_y": 0.003, "tendons.offset_z": 0.001},):
        assert structure_key(finger(elements=4, **tendon), comm) != key, tendon
    assert structure_key(finger(elements=4, **{"tendons.offset_y": 0.003,
                                               "tendons.offset_z": 0.001}), comm) != \
        structure_key(finger(elements=4, **{"tendons.offset_y": 0.002,
                                            "tendons.offset_z": 0.001}), comm)


@pytest.mark.parametrize("name", ["tip moment nonzero", "follower", "initial curvature formula",
                                  "point force", "supports", "law", "constraint", "degree",
                                  "section shape", "planar"])
def test_a_cache_hit_is_never_another_structure(name, monkeypatch):
    """Solve A, then B (another structure) in the same process: B equals B solved with the
    cache off to 1e-10 (a hit on A's problem would give A's forms with B's numbers)."""
    realtime.clear_cache()
    first = config_of({})
    fresh_tip(first)
    second = config_of(STRUCTURES[name])
    reference = fresh_tip(second, cache=False, monkeypatch=monkeypatch)
    tip = fresh_tip(second)
    for key in ("u", "v"):
        assert abs(tip[key] - reference[key]) <= 1e-10, (key, tip, reference)
    if "rotation_vector" in reference:
        assert_close(tip, reference, 1.0, 1e-10)
    # and a true hit (B again, other numbers) is B's fresh answer too
    hits = realtime.cache_info()["hits"]
    changes = copy.deepcopy(STRUCTURES[name])
    changes["material.E"] = 2.5e8
    third = config_of(changes)
    tip = fresh_tip(third)
    assert realtime.cache_info()["hits"] == hits + 1
    reference = fresh_tip(third, cache=False, monkeypatch=monkeypatch)
    for key in ("u", "v"):
        assert abs(tip[key] - reference[key]) <= 1e-10, (key, tip, reference)
    if "rotation_vector" in reference:
        assert_close(tip, reference, 1.0, 1e-10)


def test_cached_finger_with_another_routing_is_its_own(monkeypatch):
    """The finger with a helix, then with a straight tendon at (3, 1) mm (another routing's
    text): the second equals its cache-off solve to 1e-10."""
    realtime.clear_cache()
    fresh_tip(finger(elements=6))
    other = finger(elements=6, **{"tendons.offset_y": "0.003", "tendons.offset_z": "0.001"})
    reference = fresh_tip(other, cache=False, monkeypatch=monkeypatch)
    assert_close(fresh_tip(other), reference, 0.1, 1e-10)

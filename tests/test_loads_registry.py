"""The load registry (`fe_beam.model.loads`): every field of `Loads` has an entry with its
flags and a `[loads]` key, `given`/`scaled` follow the load kinds, and the commands read the
flags (the FD + RK scheme refuses each load it would drop, the real-time solver updates exactly
the flagged ones)."""

from __future__ import annotations

import dataclasses

import pytest

import fe_beam
from fe_beam.config.schema import SCHEMA
from fe_beam.model.beam import Loads
from fe_beam.model.loads import LOADS, given, scaled, unsupported

EXAMPLE = {
    "beam": {"length": 1.0},
    "section": {"shape": "rectangle", "b": 0.05, "h": 0.05},
    "material": {"E": 1e7, "nu": 0.3, "rho": 1000.0},
    "mesh": {"elements": 6},
    "time": {"t_end": 0.004, "dt": 0.002, "scheme": "fd-rk45"},
}
VALUES = {"tip_force": [0.0, -2.0], "tip_moment": 0.5, "distributed": [0.0, -1.0],
          "gravity": [0.0, -9.81], "point_forces": [[0.5, 0.0, -1.0]],
          "point_moments": [[0.5, 0.2]],
          "end_displacement": [0.0, -0.01], "end_rotation": 0.1}


def test_every_load_field_is_registered_with_a_key():
    fields = [f.name for f in dataclasses.fields(Loads) if f.name != "follower"]
    assert fields == list(LOADS)
    assert set(LOADS) <= set(SCHEMA["loads"])
    assert set(VALUES) == set(LOADS)


def test_given_and_scaled_follow_the_kinds():
    loads = Loads(tip_force=(1.0, 0.0), point_forces=((0.5, 0.0, 2.0), (0.7, 0.0, 0.0)),
                  end_rotation=0.0)
    assert given(loads) == ["tip_force", "point_forces", "end_rotation"]
    assert given(loads, ("point_forces",)) == ["tip_force", "end_rotation"]
    assert scaled(loads, 3.0) == {"tip_force": [3.0, 0.0],
                                  "point_forces": [[0.5, 0.0, 6.0], [0.7, 0.0, 0.0]],
                                  "end_rotation": 0.0}
    assert unsupported(Loads(gravity=(0.0, -9.81), tip_force=(1.0, 0.0)), "fd") == ["gravity"]
    assert given(Loads()) == []


@pytest.mark.parametrize("name", [n for n, kind in LOADS.items() if not kind.fd])
def test_the_fd_scheme_refuses_every_load_it_would_drop(name):
    config = {table: dict(values) for table, values in EXAMPLE.items()}
    config["loads"] = {name: VALUES[name]}
    with pytest.raises(fe_beam.ConfigError, match=r"fd-\*"):
        fe_beam.run("dynamic", config)


def test_the_realtime_solver_updates_exactly_the_flagged_loads():
    from fe_beam.solvers.realtime import RealtimeSolver

    config = fe_beam.validate("static", {table: dict(values) for table, values in
                                         EXAMPLE.items() if table != "time"}).parsed
    flagged = [name for name, kind in LOADS.items() if kind.realtime]
    assert flagged == ["tip_force", "tip_moment", "distributed", "gravity"]
    with RealtimeSolver(config) as solver:
        for name in flagged:
            solver.update(loads={name: VALUES[name]})
            fresh = fe_beam.solve_static(dataclasses.replace(config, model=dataclasses.replace(
                config.model, loads=Loads(**{name: VALUES[name]}))), progress=False)
            tip = fresh.steps[-1]["tip"]
            assert solver.tip()["v"] == pytest.approx(tip["v"], rel=1e-8, abs=1e-14), name
            solver.update(loads={name: [0.0, 0.0] if name != "tip_moment" else 0.0})
        with pytest.raises(KeyError, match="point_forces: the loads are tip_force, tip_moment, "
                                           "distributed and gravity"):
            solver.update(loads={"point_forces": VALUES["point_forces"]})


def test_the_law_registry_lists_every_law_and_the_closed_forms():
    from fe_beam.model.laws import LAW_KINDS, LAWS, ROD_LAWS

    assert tuple(LAW_KINDS) == LAWS
    assert {n: k.closed_form for n, k in LAW_KINDS.items() if k.closed_form} == ROD_LAWS


def test_commands_refuse_a_law_without_the_capability():
    from fe_beam.analyses.sensitivity import RodSensitivity

    config = {table: dict(values) for table, values in EXAMPLE.items()}
    config["model"] = {"law": "hyperelastic", "section_points": 3}
    config["loads"] = {"tip_force": [0.0, -1.0]}
    with pytest.raises(fe_beam.ConfigError, match="fd-.*nonstandard and reissner only.*"
                                                  "hyperelastic"):
        fe_beam.run("dynamic", config)
    static = {k: v for k, v in config.items() if k != "time"}
    with pytest.raises(fe_beam.ConfigError, match='"nonstandard" and "reissner" .*not '
                                                  '"hyperelastic"'):
        RodSensitivity(static, ["material.E"])


def test_a_reused_problem_takes_the_new_point_forces(monkeypatch):
    """Solves that differ only in loads the rod problem does not hold as constants (point
    forces become mesh vertices and form terms) must not share a built problem: the second
    took the first one's forces (a wrong tip, exit 0). Each answer equals a solve with the
    cache of built problems off."""
    config = {table: dict(values) for table, values in EXAMPLE.items() if table != "time"}
    cases = ([], [[0.5, 0.0, -2.0]], [[0.25, 1.0, -3.0]], [])
    cached = []
    for forces in cases:
        config["loads"] = {"point_forces": forces, "tip_force": [0.0, -0.5]}
        cached.append(fe_beam.run("static", config)["steps"][-1]["tip"])
    monkeypatch.setenv("FE_BEAM_PROBLEM_CACHE", "0")
    for forces, tip in zip(cases, cached, strict=True):
        config["loads"] = {"point_forces": forces, "tip_force": [0.0, -0.5]}
        fresh = fe_beam.run("static", config)["steps"][-1]["tip"]
        for key in ("u", "v", "theta"):
            assert tip[key] == pytest.approx(fresh[key], rel=1e-10, abs=1e-15), (forces, key)
    assert len({round(t["v"], 12) for t in cached}) == 3  # the forces change the answer

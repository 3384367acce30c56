"""Stability of the final static equilibrium: the inertia of the tangent stiffness on the
constraint-preserving directions counts the Euler buckling modes a compressed column has
passed, whatever the constraint."""

import math

import pytest
from beam_cases import bending_stiffness, cantilever
from mpi4py import MPI

from fe_beam import LoadStepping, SolverSettings
from fe_beam.analyses.static import StaticContinuation, solve_static
from fe_beam.model.studies import StaticConfig

EI = bending_stiffness(0.01)
EULER = math.pi**2 * EI / 4  # first critical load of the cantilever, L = 1


def final_stability(model):
    run = StaticContinuation(StaticConfig(model, SolverSettings(), LoadStepping(steps=4)),
                             MPI.COMM_SELF)
    try:
        run.advance(1.0, LoadStepping(steps=4))
        return run.stability()
    finally:
        run.destroy()


@pytest.mark.parametrize("constraint", ["none", "inextensible-unshearable", "unshearable"])
@pytest.mark.parametrize(("factor", "modes"), [(0.5, 0), (0.99, 0), (1.01, 1), (3.0, 1),
                                              (15.0, 2), (30.0, 3)])
def test_compressed_column_counts_the_buckling_modes_passed(constraint, factor, modes):
    """Critical loads (2n - 1)^2 P_E: 1, 9, 25, 49 P_E. Without an imperfection Newton stays
    on the straight (trivial) branch, which has one falling direction per mode passed."""
    model = cantilever(constraint=constraint, elements=24, tip_force=(-factor * EULER, 0.0))
    stability = final_stability(model)
    assert stability == {"stable": modes == 0, "energy_decreasing_directions": modes}


@pytest.mark.parametrize("constraint", ["none", "inextensible-unshearable"])
def test_large_deflection_under_tip_load_is_stable(constraint):
    model = cantilever(constraint=constraint, elements=16, tip_force=(0.0, -5 * EI))
    assert final_stability(model) == {"stable": True, "energy_decreasing_directions": 0}


def test_unstable_final_state_is_reported_in_summary_and_cli(tmp_path, capsys):
    from test_config import BASE, dump_toml

    from fe_beam.cli import main

    config = {**BASE, "loads": {"tip_force": [-3 * EULER, 0.0], "steps": 2},
              "output": {"xdmf": False, "plots": False}}
    config["section"] = {"shape": "rectangle", "b": 0.01, "h": 0.01}
    config["material"] = {"E": 1.0e7, "nu": 0.3}
    path = tmp_path / "column.toml"
    path.write_text(dump_toml(config))
    assert main(["static", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    assert "the final equilibrium is unstable" in capsys.readouterr().err
    result = solve_static(StaticConfig(cantilever(tip_force=(-3 * EULER, 0.0)), SolverSettings(),
                                       LoadStepping(steps=2)), None, progress=False)
    assert result.steps[-1]["stability"]["stable"] is False

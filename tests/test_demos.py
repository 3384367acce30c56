"""Demos run as tests and their key numbers are checked."""

import importlib.util
from pathlib import Path

import pytest
from mpi4py import MPI

DEMOS = Path(__file__).resolve().parents[1] / "demos"


def load(name):
    spec = importlib.util.spec_from_file_location(name, DEMOS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_figure2_demo(tmp_path):
    from fe_beam.analytic import elastica_tip_load

    results = load("demo_figure2").main(tmp_path)
    inextensible, extensible = results["a_inextensible"], results["b_extensible"]
    assert [round(10 * s["load_factor"], 9) for s in inextensible.steps] == list(range(1, 11))
    for step in inextensible.steps:  # (a) is the elastica up to O((h/L)^2)
        exact = elastica_tip_load(10 * step["load_factor"])
        assert -step["tip"]["v"] == pytest.approx(exact.deflection, abs=1e-4)
    # (b) stretches and shears: visibly away from the elastica at k = 10
    assert -extensible.steps[-1]["tip"]["v"] > elastica_tip_load(10).deflection + 5e-3
    if MPI.COMM_WORLD.rank == 0:
        for name in (
            "figure2_a_inextensible.png",
            "figure2_b_extensible.png",
            "a_inextensible/beam.xdmf",
            "b_extensible/summary.json",
        ):
            assert (tmp_path / name).stat().st_size > 0


def test_dynamics_demo(tmp_path):
    """demo_dynamics (one tension): the flying beam's linear momentum is the impulse of the
    force (8 * 2.5 = 20 along (0.6, 0.8)) and its momenta stay constant in free flight; the
    finger's first frequency in the dynamics matches fe-beam modes with prestress."""
    results = load("demo_dynamics").main(tmp_path, tensions=[4.0])
    flying = results["flying"]["history"]
    assert results["flying"]["status"] == "completed"
    last = flying[-1]["momenta"]
    assert last["momentum_x"] == pytest.approx(12.0, rel=1e-9)
    assert last["momentum_y"] == pytest.approx(16.0, rel=1e-9)
    free = [h["momenta"]["angular_momentum"] for h in flying if h["t"] >= 5.0]
    assert max(free) - min(free) < 1e-8 * abs(free[0])
    (row,) = results["frequencies"]
    assert row["dynamics_hz"] == pytest.approx(row["modes_hz"], rel=5e-3)
    finger = results["finger"]
    assert finger["status"] == "completed"
    # damped: the finger has settled near the static state at 2 N by t = 1.2 s
    assert finger["history"][-1]["tip"]["theta"] == pytest.approx(
        finger["static"][1.0]["theta"], rel=0.02)
    if MPI.COMM_WORLD.rank == 0:
        for name in ("finger_tip_response.png", "finger_frequency_shift.png",
                     "flying_beam_energy_momentum.png"):
            assert (tmp_path / name).stat().st_size > 0

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

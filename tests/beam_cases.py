"""Small builders shared by the beam tests (not a test module)."""

from mpi4py import MPI

from fe_beam import (
    BeamModel,
    Discretisation,
    Loads,
    LoadStepping,
    Material,
    ModelOptions,
    Section,
    SolverSettings,
    Supports,
)
from fe_beam.config import StaticConfig
from fe_beam.static import solve_static

E = 1.0e7
NU = 0.3


def square(h: float) -> Section:
    return Section("rectangle", {"b": h, "h": h})


def bending_stiffness(h: float) -> float:
    return E * h**4 / 12


def cantilever(
    law="reissner",
    constraint="inextensible-unshearable",
    elements=20,
    degree=2,
    h=0.01,
    length=1.0,
    **loads,
) -> BeamModel:
    return BeamModel(
        length,
        square(h),
        Material(E, nu=NU),
        ModelOptions(law, constraint),
        Discretisation(elements, degree),
        Supports("clamped", "free"),
        Loads(**loads),
    )


def solve(model: BeamModel, steps=10, comm=MPI.COMM_WORLD, **settings):
    config = StaticConfig(model, SolverSettings(**settings), LoadStepping(steps=steps))
    result = solve_static(config, out=None, comm=comm, progress=False)
    assert result.status == "converged", result.message
    return result


def tip(model: BeamModel, **kwargs) -> dict:
    return solve(model, **kwargs).steps[-1]["tip"]

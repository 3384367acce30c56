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
from fe_beam.analyses.static import solve_static
from fe_beam.model.studies import StaticConfig

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


RHO = 1000.0  # the dynamics tests' density (E, L = 1e7 Pa, 1 m as above)


def dynamic_rod(h=0.01, law="reissner", supports=Supports(), elements=12, loads=Loads(), nu=NU,
                G=None) -> BeamModel:
    """Square-section rod with density, for the dynamics and modal tests."""
    material = Material(E, G=G, rho=RHO) if G else Material(E, nu=nu, rho=RHO)
    return BeamModel(1.0, square(h), material, ModelOptions(law), Discretisation(elements, 2),
                     supports, loads)


def solve(model: BeamModel, steps=10, comm=MPI.COMM_WORLD, **settings):
    config = StaticConfig(model, SolverSettings(**settings), LoadStepping(steps=steps))
    result = solve_static(config, out=None, comm=comm, progress=False)
    assert result.status == "converged", result.message
    return result


def tip(model: BeamModel, **kwargs) -> dict:
    return solve(model, **kwargs).steps[-1]["tip"]

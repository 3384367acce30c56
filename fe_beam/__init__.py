"""fe_beam: finite elements (FEniCSx) for slender bodies that bend a lot."""

from fe_beam.beam import (
    BeamModel,
    BeamProblem,
    Discretisation,
    Loads,
    ModelOptions,
    Supports,
)
from fe_beam.materials import Material
from fe_beam.sections import Section, SectionProperties
from fe_beam.solver import (
    LoadStepping,
    LoadSteppingFailed,
    NonlinearProblem,
    SNESSolver,
    SolveFailed,
    SolverSettings,
    run_load_stepping,
)

__version__ = "0.1.0"

__all__ = [
    "BeamModel",
    "BeamProblem",
    "Discretisation",
    "LoadStepping",
    "LoadSteppingFailed",
    "Loads",
    "Material",
    "ModelOptions",
    "NonlinearProblem",
    "SNESSolver",
    "Section",
    "SectionProperties",
    "SolveFailed",
    "SolverSettings",
    "Supports",
    "run_load_stepping",
]

"""fe_beam: finite elements (FEniCSx) for slender bodies that bend a lot."""

import os as _os
import sys as _sys

if _os.path.basename(_sys.argv[0] if _sys.argv else "") == "fe-beam":
    # the command line: SIGINT/SIGTERM during the imports below are deferred too (fe_beam.runctl)
    from fe_beam import runctl as _runctl

    _runctl.defer_signals()
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

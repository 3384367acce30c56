"""fe_beam: finite elements (FEniCSx) for slender bodies that bend a lot."""

import os as _os
import sys as _sys

if _os.path.basename(_sys.argv[0] if _sys.argv else "") == "fe-beam":
    # the command line: SIGINT/SIGTERM during the imports below are deferred too (fe_beam.runctl)
    from fe_beam import runctl as _runctl

    _runctl.defer_signals()
from fe_beam.lazy import lazy_getattr
from fe_beam.materials import Material
from fe_beam.model import (
    BeamModel,
    Discretisation,
    Loads,
    LoadStepping,
    ModelOptions,
    SolverSettings,
    Supports,
)
from fe_beam.sections import Section, SectionProperties

# the finite-element names load dolfinx and PETSc: imported when first used (PEP 562), so that
# `import fe_beam.config` (validation, `fe-beam --help`) does not load the FE stack
_LAZY = {
    "BeamProblem": "fe_beam.beam",
    "LoadSteppingFailed": "fe_beam.solver",
    "NonlinearProblem": "fe_beam.solver",
    "SNESSolver": "fe_beam.solver",
    "SolveFailed": "fe_beam.solver",
    "run_load_stepping": "fe_beam.solver",
}


__getattr__ = lazy_getattr("fe_beam", _LAZY, globals())


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

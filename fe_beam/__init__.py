"""fe_beam: finite elements (FEniCSx) for slender bodies that bend a lot."""

import os as _os
import sys as _sys

if _os.path.basename(_sys.argv[0] if _sys.argv else "") == "fe-beam":
    # the command line: SIGINT/SIGTERM during the imports below are deferred too (fe_beam.runctl)
    from fe_beam import runctl as _runctl

    _runctl.defer_signals()
from fe_beam import _moved
from fe_beam.lazy import lazy_getattr
from fe_beam.model import (
    BeamModel,
    Discretisation,
    Loads,
    LoadStepping,
    ModelOptions,
    SolverSettings,
    Supports,
)
from fe_beam.model.materials import Material
from fe_beam.model.sections import Section, SectionProperties

# the finite-element names load dolfinx and PETSc: imported when first used (PEP 562), so that
# `import fe_beam.config.schema` (validation, `fe-beam --help`) does not load the FE stack
_LAZY = {
    "BeamProblem": "fe_beam.fem.rod",
    "LoadSteppingFailed": "fe_beam.solvers.newton",
    "NonlinearProblem": "fe_beam.solvers.newton",
    "SNESSolver": "fe_beam.solvers.newton",
    "SolveFailed": "fe_beam.solvers.newton",
    "run_load_stepping": "fe_beam.solvers.continuation",
}


_moved.install()  # the import paths before the layers (fe_beam._moved.MOVED)

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

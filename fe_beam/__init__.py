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
from fe_beam.model.spatial import SpatialLoads, SpatialRodModel, SpatialSupports

# the finite-element names load dolfinx and PETSc: imported when first used (PEP 562), so that
# `import fe_beam.config.schema` (validation, `fe-beam --help`) does not load the FE stack
_LAZY = {
    # the front door (fe_beam.api) and the configuration layer
    "run": "fe_beam.api",
    "ConfigError": "fe_beam.errors",
    "load_config": "fe_beam.config.schema",
    "apply_overrides": "fe_beam.config.schema",
    "validate": "fe_beam.config.registry",
    "StaticConfig": "fe_beam.model.studies",
    # drivers and their results (fe_beam.analyses: one per subcommand)
    "solve_static": "fe_beam.analyses.static",
    "StaticResult": "fe_beam.analyses.static",
    "run_finger": "fe_beam.analyses.finger",
    "run_dynamic": "fe_beam.analyses.transient",
    "run_modes": "fe_beam.analyses.transient",
    "DynamicResult": "fe_beam.analyses.transient",
    # problems and engines for scripting
    "StaticContinuation": "fe_beam.solvers.rod_static",
    "SolidFingerProblem": "fe_beam.solvers.solid",
    "RealtimeSolver": "fe_beam.solvers.realtime",
    "RodSensitivity": "fe_beam.analyses.sensitivity",
    "BeamProblem": "fe_beam.fem.rod",
    "SpatialRodProblem": "fe_beam.fem.spatial_rod",
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
    "ConfigError",
    "DynamicResult",
    "RealtimeSolver",
    "RodSensitivity",
    "SolidFingerProblem",
    "StaticConfig",
    "StaticContinuation",
    "StaticResult",
    "apply_overrides",
    "load_config",
    "run",
    "run_dynamic",
    "run_finger",
    "run_modes",
    "solve_static",
    "validate",
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
    "SpatialLoads",
    "SpatialRodModel",
    "SpatialRodProblem",
    "SpatialSupports",
    "run_load_stepping",
]

"""The model layer: what a problem is, as validated dataclasses, with no finite-element code.

Nothing here imports dolfinx, PETSc or mpi4py (a test checks it), so a configuration is
validated (`fe_beam.config.validate`) without loading the finite-element stack. The
finite-element
side (`fe_beam.fem.rod.BeamProblem`, `fe_beam.solvers.newton`, `fe_beam.solid`) takes these objects.

- `fe_beam.model.beam`: BeamModel, ModelOptions, Discretisation, Supports, Loads
- `fe_beam.model.laws`: the rod laws NonStandard, Reissner (energy as a method), Strains, Stiffness
- `fe_beam.model.settings`: SolverSettings, LoadStepping, TimeSettings, Damping
- `fe_beam.model.tendons`: Tendon geometry
- `fe_beam.model.solid`: the 3D finger's geometry, mesh sizes, tendon loads, discretisation
- `fe_beam.config.finger`, `fe_beam.config.transient`, `fe_beam.config.compare`,
  `fe_beam.config.solid`: the configuration parsers of the subcommands
- sections and materials: `fe_beam.model.sections`, `fe_beam.model.materials` (re-exported here)
"""

from fe_beam.model.beam import BeamModel, Discretisation, Loads, ModelOptions, Supports
from fe_beam.model.laws import NonStandard, Reissner, Stiffness, Strains
from fe_beam.model.materials import Material
from fe_beam.model.sections import Section, SectionProperties
from fe_beam.model.settings import Damping, LoadStepping, SolverSettings, TimeSettings
from fe_beam.model.tendons import Tendon

__all__ = [
    "BeamModel",
    "Damping",
    "Discretisation",
    "LoadStepping",
    "Loads",
    "Material",
    "ModelOptions",
    "NonStandard",
    "Reissner",
    "Section",
    "SectionProperties",
    "SolverSettings",
    "Stiffness",
    "Strains",
    "Supports",
    "Tendon",
    "TimeSettings",
]

"""The model layer: what a problem is, as validated dataclasses, with no finite-element code.

Nothing here imports dolfinx, PETSc or mpi4py (a test checks it), so a configuration is
validated (`fe_beam.config.validate`) without loading the finite-element stack. The finite-element
side (`fe_beam.beam.BeamProblem`, `fe_beam.solver`, `fe_beam.solid`) takes these objects.

- `fe_beam.model.beam`: BeamModel, ModelOptions, Discretisation, Supports, Loads
- `fe_beam.model.laws`: the rod laws NonStandard, Reissner (energy as a method), Strains, Stiffness
- `fe_beam.model.settings`: SolverSettings, LoadStepping, TimeSettings, Damping
- `fe_beam.model.tendons`: Tendon geometry
- `fe_beam.model.solid`: the 3D finger's geometry, mesh sizes, tendon loads, discretisation
- `fe_beam.model.finger`, `fe_beam.model.transient`, `fe_beam.model.compare`,
  `fe_beam.solid.config`: the configuration parsers of the subcommands
- sections and materials: `fe_beam.sections`, `fe_beam.materials` (re-exported here)
"""

from fe_beam.materials import Material
from fe_beam.model.beam import BeamModel, Discretisation, Loads, ModelOptions, Supports
from fe_beam.model.laws import NonStandard, Reissner, Stiffness, Strains
from fe_beam.model.settings import Damping, LoadStepping, SolverSettings, TimeSettings
from fe_beam.model.tendons import Tendon
from fe_beam.sections import Section, SectionProperties

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

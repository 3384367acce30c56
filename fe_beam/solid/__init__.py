"""3D continuum cross-check: a gmsh-meshed hyperelastic finger with embedded tendon cables.

    from fe_beam import solid
    finger = solid.create_finger_mesh(solid.FingerGeometry(...), solid.MeshSizes(...))
    problem = solid.SolidFingerProblem(finger, solid.silicone("ecoflex-00-30"), ...)
    results = problem.solve()            # plain dicts / lists
    solid.write_xdmf(problem, "out.xdmf")
"""

from fe_beam.solid.cable import TendonCable, locate_vertex_dofs
from fe_beam.solid.export import DisplacementXDMF, write_xdmf
from fe_beam.solid.geometry import (
    CLAMP_TAG,
    TENDON_TAG0,
    TIP_TAG,
    VOLUME_TAG,
    FingerGeometry,
    FingerMesh,
    MeshSizes,
    TendonPath,
    create_finger_mesh,
    write_msh,
)
from fe_beam.solid.materials import (
    LAWS,
    SILICONE_PRESETS,
    MooneyRivlin,
    NeoHookean,
    SaintVenantKirchhoff,
    SiliconePreset,
    Yeoh,
    silicone,
)
from fe_beam.solid.problem import (
    Discretization,
    SolidFingerProblem,
    TendonLoad,
    evaluate_at_points,
    rigid_body_modes,
)

__all__ = [
    "CLAMP_TAG",
    "LAWS",
    "SILICONE_PRESETS",
    "TENDON_TAG0",
    "TIP_TAG",
    "VOLUME_TAG",
    "DisplacementXDMF",
    "Discretization",
    "FingerGeometry",
    "FingerMesh",
    "MeshSizes",
    "MooneyRivlin",
    "NeoHookean",
    "SaintVenantKirchhoff",
    "SiliconePreset",
    "SolidFingerProblem",
    "TendonCable",
    "TendonLoad",
    "TendonPath",
    "Yeoh",
    "create_finger_mesh",
    "evaluate_at_points",
    "locate_vertex_dofs",
    "rigid_body_modes",
    "silicone",
    "write_msh",
    "write_xdmf",
]

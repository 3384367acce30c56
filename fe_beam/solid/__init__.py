"""3D continuum cross-check: a gmsh-meshed hyperelastic finger with embedded tendon cables.

    from fe_beam import solid
    finger = solid.create_finger_mesh(solid.FingerGeometry(...), solid.MeshSizes(...))
    problem = solid.SolidFingerProblem(finger, solid.silicone("ecoflex-00-30"), ...)
    results = problem.solve()            # plain dicts / lists
    solid.write_xdmf(problem, "out.xdmf")
"""

# every name loads dolfinx (or gmsh) with its module: imported when first used (PEP 562), so that
# the FE-free parts (`fe_beam.config.solid`, `fe_beam.model.hyperelastic`) import without them
from fe_beam.lazy import lazy_getattr

_LAZY = {
    "TendonCable": "fe_beam.fem.solid.cable",
    "locate_vertex_dofs": "fe_beam.fem.solid.cable",
    "DisplacementXDMF": "fe_beam.exports.solid",
    "write_xdmf": "fe_beam.exports.solid",
    "CLAMP_TAG": "fe_beam.fem.solid.geometry",
    "TENDON_TAG0": "fe_beam.fem.solid.geometry",
    "TIP_TAG": "fe_beam.fem.solid.geometry",
    "VOLUME_TAG": "fe_beam.fem.solid.geometry",
    "FingerGeometry": "fe_beam.fem.solid.geometry",
    "FingerMesh": "fe_beam.fem.solid.geometry",
    "MeshSizes": "fe_beam.fem.solid.geometry",
    "TendonPath": "fe_beam.fem.solid.geometry",
    "create_finger_mesh": "fe_beam.fem.solid.geometry",
    "write_msh": "fe_beam.fem.solid.geometry",
    "LAWS": "fe_beam.model.hyperelastic",
    "SILICONE_PRESETS": "fe_beam.model.hyperelastic",
    "MooneyRivlin": "fe_beam.model.hyperelastic",
    "NeoHookean": "fe_beam.model.hyperelastic",
    "SaintVenantKirchhoff": "fe_beam.model.hyperelastic",
    "SiliconePreset": "fe_beam.model.hyperelastic",
    "Yeoh": "fe_beam.model.hyperelastic",
    "silicone": "fe_beam.model.hyperelastic",
    "Discretization": "fe_beam.solvers.solid",
    "SolidFingerProblem": "fe_beam.solvers.solid",
    "TendonLoad": "fe_beam.solvers.solid",
    "evaluate_at_points": "fe_beam.solvers.solid",
    "rigid_body_modes": "fe_beam.solvers.solid",
}


__getattr__ = lazy_getattr("fe_beam.solid", _LAZY, globals())


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

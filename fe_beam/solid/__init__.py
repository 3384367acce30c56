"""3D continuum cross-check: a gmsh-meshed hyperelastic finger with embedded tendon cables.

    from fe_beam import solid
    finger = solid.create_finger_mesh(solid.FingerGeometry(...), solid.MeshSizes(...))
    problem = solid.SolidFingerProblem(finger, solid.silicone("ecoflex-00-30"), ...)
    results = problem.solve()            # plain dicts / lists
    solid.write_xdmf(problem, "out.xdmf")
"""

# every name loads dolfinx (or gmsh) with its module: imported when first used (PEP 562), so that
# the FE-free parts (`fe_beam.solid.config`, `fe_beam.solid.materials`) import without them
from fe_beam.lazy import lazy_getattr

_LAZY = {
    "TendonCable": "fe_beam.solid.cable",
    "locate_vertex_dofs": "fe_beam.solid.cable",
    "DisplacementXDMF": "fe_beam.solid.export",
    "write_xdmf": "fe_beam.solid.export",
    "CLAMP_TAG": "fe_beam.solid.geometry",
    "TENDON_TAG0": "fe_beam.solid.geometry",
    "TIP_TAG": "fe_beam.solid.geometry",
    "VOLUME_TAG": "fe_beam.solid.geometry",
    "FingerGeometry": "fe_beam.solid.geometry",
    "FingerMesh": "fe_beam.solid.geometry",
    "MeshSizes": "fe_beam.solid.geometry",
    "TendonPath": "fe_beam.solid.geometry",
    "create_finger_mesh": "fe_beam.solid.geometry",
    "write_msh": "fe_beam.solid.geometry",
    "LAWS": "fe_beam.solid.materials",
    "SILICONE_PRESETS": "fe_beam.solid.materials",
    "MooneyRivlin": "fe_beam.solid.materials",
    "NeoHookean": "fe_beam.solid.materials",
    "SaintVenantKirchhoff": "fe_beam.solid.materials",
    "SiliconePreset": "fe_beam.solid.materials",
    "Yeoh": "fe_beam.solid.materials",
    "silicone": "fe_beam.solid.materials",
    "Discretization": "fe_beam.solid.problem",
    "SolidFingerProblem": "fe_beam.solid.problem",
    "TendonLoad": "fe_beam.solid.problem",
    "evaluate_at_points": "fe_beam.solid.problem",
    "rigid_body_modes": "fe_beam.solid.problem",
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

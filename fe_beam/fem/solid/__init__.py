"""The 3D finger's finite-element pieces: the gmsh geometry and the tendon cables."""

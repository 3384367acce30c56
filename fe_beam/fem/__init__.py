"""The finite-element layer (dolfinx, UFL, PETSc objects): forms and spaces, no solve loops.

Every dolfinx/ufl/basix/petsc4py version difference lives in `fe_beam.fem.compat`; global
numbers go through `fe_beam.fem.mpi`. Imports the model layer only (and the utilities).
"""

"""Engines: Newton (PETSc SNES), the one continuation engine, critical points, time
integrators, eigen solvers, real-time re-solves. They know no driver and no configuration:
they take model objects and finite-element problems, and write no files."""

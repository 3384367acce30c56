"""Independent reference solvers in plain numpy/scipy (no FEniCSx).

They re-implement the source documents' own numerical methods so that the finite-element model
can be cross-validated and benchmarked against them. They are baselines, not a second product.
"""

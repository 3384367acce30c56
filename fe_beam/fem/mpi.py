"""One MPI-safe place for global numbers: every tip value, energy or norm goes through here."""

from __future__ import annotations

import numpy as np
from dolfinx import fem
from mpi4py import MPI

__all__ = ["global_max", "global_sum", "assemble_scalar", "is_root"]


def global_sum(comm: MPI.Comm, local_value) -> float | np.ndarray:
    """Sum of per-rank values (scalars or equal-shape arrays) over the communicator."""
    if np.ndim(local_value) == 0:
        return comm.allreduce(float(local_value), op=MPI.SUM)
    return comm.allreduce(np.asarray(local_value, dtype=float), op=MPI.SUM)


def global_max(comm: MPI.Comm, local_value: float) -> float:
    return comm.allreduce(float(local_value), op=MPI.MAX)


def assemble_scalar(form: fem.Form) -> float:
    """Assemble a compiled scalar form and reduce it over the mesh communicator."""
    comm = form.mesh.comm
    return global_sum(comm, fem.assemble_scalar(form))


def is_root(comm: MPI.Comm) -> bool:
    return comm.rank == 0

"""XDMF output of the solid finger's displacement (called by the CLI, never by the solve loop).

XDMF stores one field per mesh node, so the displacement is interpolated into the Lagrange
space of the mesh geometry: P1 for linear tetrahedra (``MeshSizes.order = 1``), P2 for quadratic
ones. Use it once (`write_xdmf`) or per load step (`DisplacementXDMF` as ``on_converged`` hook).
The files are written by `fe_beam.exports.outputs.XDMFSeries`: readable at any moment of the run.
"""

from __future__ import annotations

from pathlib import Path

from dolfinx import fem

from fe_beam.exports.outputs import XDMFSeries
from fe_beam.fem import compat

__all__ = ["DisplacementXDMF", "write_xdmf"]


class DisplacementXDMF:
    """An XDMF time series of the displacement of a `SolidFingerProblem` (collective)."""

    def __init__(self, problem, path: str | Path):
        self.problem = problem
        msh = problem.mesh
        degree = compat.geometry_degree(msh)
        space = compat.function_space(msh, compat.vector_element(msh, "Lagrange", degree))
        self.output = fem.Function(space, name="displacement")
        self.path = Path(path)
        self._file = XDMFSeries(msh, self.path)

    def write(self, t: float | None = None, flush: bool | None = True) -> None:
        """Write the current displacement at time ``t`` (default: the current load factor);
        ``flush=None``: to disk at a bounded share of the wall time (see `XDMFSeries`)."""
        self.output.interpolate(self.problem.displacement())
        self._file.write(self.problem.load_factor if t is None else t, [self.output], flush)

    def flush(self) -> None:
        self._file.flush()

    def __call__(self, step=None) -> None:
        self.write(None if step is None else step.load_factor)

    def close(self) -> None:
        self._file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def write_xdmf(problem, path: str | Path) -> None:
    """Write the current displacement of ``problem`` to ``path`` (.xdmf + .h5)."""
    with DisplacementXDMF(problem, path) as out:
        out.write()

"""XDMF output of the solid finger's displacement (called by the CLI, never by the solve loop).

XDMF stores one field per mesh node, so the displacement is interpolated into the Lagrange
space of the mesh geometry: P1 for linear tetrahedra (``MeshSizes.order = 1``), P2 for quadratic
ones. Use it once (`write_xdmf`) or per load step (`DisplacementXDMF` as ``on_converged`` hook).
The files are written by `fe_beam.exports.outputs.XDMFSeries`: readable at any moment of the run.

In contact with [[obstacles]] (the problem's ``contact``, `fe_beam.fem.solid.contact.SolidContact`),
per obstacle i (the order of [[obstacles]]) also ``contact_gap_i`` (the signed gap [m] of the
deformed point x = X + u to the obstacle, at every vertex) and ``contact_pressure_i`` (the
nominal contact pressure [Pa, per reference area] at the exterior-facet vertices, 0 elsewhere:
the lumped L2 projection of the quadrature-point pressure <lambda - k g>_+, so that its surface
integral is the summary's int p dA, `SolidContact.output_fields`), both nodal (P1, as the
multipliers; interpolated into the geometry's space).
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
        self.contact = getattr(problem, "contact", None)
        self._contact = []  # (carrier in the multipliers' P1 space, gap, pressure)
        if self.contact is not None:
            scalar = compat.function_space(msh, compat.element(msh, "Lagrange", degree))
            for i in range(len(self.contact.obstacles)):
                self._contact.append(
                    (fem.Function(self.contact.Q), fem.Function(scalar, name=f"contact_gap_{i}"),
                     fem.Function(scalar, name=f"contact_pressure_{i}")))
        self.path = Path(path)
        self._file = XDMFSeries(msh, self.path)

    def write(self, t: float | None = None, flush: bool | None = True) -> None:
        """Write the current displacement at time ``t`` (default: the current load factor);
        ``flush=None``: to disk at a bounded share of the wall time (see `XDMFSeries`)."""
        self.output.interpolate(self.problem.displacement())
        fields = [self.output]
        if self._contact:
            gaps, pressures = self.contact.output_fields()
            for (carrier, gap, pressure), g, p in zip(self._contact, gaps, pressures,
                                                      strict=True):
                for target, values in ((gap, g), (pressure, p)):
                    compat.local_array(carrier)[:] = values
                    target.interpolate(carrier)
                    fields.append(target)
        self._file.write(self.problem.load_factor if t is None else t, fields, flush)

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

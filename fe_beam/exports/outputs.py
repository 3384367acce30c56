"""Result writers: XDMF for ParaView, summary.json and CSV (atomic), PNG plots.

Writers take Functions/problems and are called from the driver between solves; solvers never
write files. Every file is readable at any moment of a run, even after SIGKILL:

* whole files (summary.json, the XDMF index, plots) are replaced atomically (write a temporary
  file, then rename) and follow the umask like any other file;
* files that grow with the run (the HDF5 data of `XDMFSeries`, the CSV histories of
  `AppendCSV`) are kept as two hidden copies, ``.NAME.a`` and ``.NAME.b``: new steps are appended
  to the copy that is not the visible one, which is then hard-linked into place atomically. A
  copy is never written while it is visible, appending costs O(1) per step, and NAME is always a
  complete, closed file;
* files that are rewritten whole as they grow (summary.json, the XDMF index) are rewritten at
  most once a second and at a bounded share of the wall time (`fe_beam.runctl.Throttle`), and
  always at the end, together with the appends, so all files hold the same steps.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem

from fe_beam import runctl
from fe_beam.exports.plotting import legend_inside
from fe_beam.fem import compat

__all__ = [
    "AppendCSV",
    "BeamXDMFWriter",
    "XDMFSeries",
    "atomic_write_json",
    "atomic_write_text",
    "figure",
    "gather_line",
    "plot_deformed_shapes",
    "section_faces",
    "plot_load_displacement",
    "write_csv",
]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write_text(path: str | Path, text: str) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    runctl.register_output(path)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        # mkstemp makes 0600 files: give the result the mode of any other file (umask)
        os.fchmod(handle, 0o666 & ~_umask())
        with os.fdopen(handle, "w") as stream:
            stream.write(text)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


@contextlib.contextmanager
def _atomic_path(path: str | Path):
    """A temporary name next to ``path`` for a writer that takes a file name (meshio): renamed
    to ``path`` when the block succeeds, removed otherwise."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    runctl.register_output(path)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp{path.suffix}")
    try:
        yield temporary
        os.chmod(temporary, 0o666 & ~_umask())
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def atomic_write_json(path: str | Path, data) -> None:
    atomic_write_text(path, json.dumps(data, indent=2, default=_jsonable) + "\n")


def as_json(data):
    """``data`` as summary.json holds it (tuples as lists, numpy numbers as Python's)."""
    return json.loads(json.dumps(data, default=_jsonable))


def _jsonable(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def write_csv(path: str | Path, header: list[str], rows: list[list]) -> None:
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(header)
    writer.writerows(rows)
    atomic_write_text(path, buffer.getvalue())


class _TwoCopies:
    """A file that only grows, readable at any moment (see the module docstring).

    ``create(path)`` writes the initial content of a copy, ``append(path, items)`` adds items
    to a copy. Rank-local (the caller decides which rank writes)."""

    def __init__(self, path: Path, create, append):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        runctl.register_output(self.path)
        self._append = append
        self.copies = [self.path.with_name(f".{self.path.name}.{tag}") for tag in "ab"]
        create(self.copies[0])
        shutil.copyfile(self.copies[0], self.copies[1])
        self._pending: list[list] = [[], []]
        self._current = 0
        self._publish(0)

    def _publish(self, index: int) -> None:
        temporary = self.path.with_name(f".{self.path.name}.link{os.getpid()}")
        temporary.unlink(missing_ok=True)
        try:
            os.link(self.copies[index], temporary)
        except OSError:  # no hard links on this file system: publish a copy instead
            shutil.copyfile(self.copies[index], temporary)
        os.replace(temporary, self.path)
        self._current = index

    def add(self, items: list) -> None:
        self._pending[0].extend(items)
        self._pending[1].extend(items)

    @property
    def pending(self) -> bool:
        return bool(self._pending[self._current])

    def flush(self) -> None:
        if not self.pending:
            return
        target = 1 - self._current
        self._append(self.copies[target], self._pending[target])
        self._pending[target] = []
        self._publish(target)

    def close(self) -> None:
        self.flush()
        for copy in self.copies:
            copy.unlink(missing_ok=True)  # the visible name keeps the current copy's data


class AppendCSV:
    """A CSV history that gains rows as the run goes: O(1) per row, readable at any moment."""

    def __init__(self, path: str | Path, header: list[str]):
        self.header = list(header)
        self._file = _TwoCopies(Path(path), self._create, self._append_rows)

    def _create(self, path: Path) -> None:
        with open(path, "w", newline="") as stream:
            csv.writer(stream).writerow(self.header)

    @staticmethod
    def _append_rows(path: Path, rows: list) -> None:
        with open(path, "a", newline="") as stream:
            csv.writer(stream).writerows(rows)

    def add(self, rows: list[list], flush: bool = True) -> None:
        self._file.add(rows)
        if flush:
            self._file.flush()

    def flush(self) -> None:
        self._file.flush()

    def close(self) -> None:
        self._file.close()


_XDMF_TOPOLOGY = {("interval", 2): "Polyline", ("interval", 3): "Edge_3",
                  ("triangle", 3): "Triangle", ("triangle", 6): "Triangle_6",
                  ("tetrahedron", 4): "Tetrahedron", ("tetrahedron", 10): "Tetrahedron_10",
                  ("quadrilateral", 4): "Quadrilateral", ("hexahedron", 8): "Hexahedron"}


# HDF5 1.8 file format or later: new-style groups keep their links in a B-tree, so adding a
# step's dataset costs O(1) bytes; the 1.6 format's symbol-table heap is rewritten whole on every
# update (O(steps) per update). Readable by HDF5 >= 1.8 (ParaView, h5py, meshio, dolfinx).
H5_LIBVER = ("v108", "latest")


class XDMFSeries:
    """An XDMF + HDF5 time series written by rank 0 with h5py, readable at any moment.

    Functions are gathered on rank 0: node-centred ones must live in the Lagrange space of the
    mesh geometry (same degree), cell-centred ones in DG0. Each rank contributes its owned cells
    with their own nodes (a node on a partition boundary appears once per rank that has it).
    Layout: ``/Mesh/mesh/geometry`` (n x 3), ``/Mesh/mesh/topology`` (VTK node order) and
    ``/Function/NAME/K`` for output step K; the XDMF index (one temporal collection, readable by
    ParaView, meshio and dolfinx's mesh reader) is rewritten atomically, the HDF5 file grows by
    the two-copy scheme, so both are complete files after an interruption at any moment. The
    index lists the steps that are in the HDF5 file (it may lag it by the steps of one flush).
    """

    def __init__(self, mesh, path: str | Path):
        self.comm = mesh.comm
        self.path = Path(path)
        self.h5_path = self.path.with_suffix(".h5")
        self.root = self.comm.rank == 0
        tdim = mesh.topology.dim
        cells = mesh.topology.index_map(tdim).size_local
        nodes = compat.geometry_cell_nodes(mesh)[:cells]
        per_cell = nodes.shape[1]
        self._nodes, inverse = np.unique(nodes, return_inverse=True)
        self._cell_nodes = inverse.reshape(nodes.shape)
        self._cells = cells
        cell_name = mesh.topology.cell_type.name
        order = np.argsort(compat.vtk_permutation(mesh.topology.cell_type, per_cell))
        topology = self._cell_nodes[:, order].astype(np.int64)
        gathered = self.comm.gather((mesh.geometry.x[self._nodes], topology), root=0)
        self._maps: dict = {}
        self._steps: list[tuple[float, dict]] = []  # in the index: (time, {name: (kind, n)})
        self._buffered: list[tuple[float, dict]] = []
        self._throttle = runctl.Throttle()
        if not self.root:
            return
        shift = np.cumsum([0] + [len(x) for x, _ in gathered])
        self._geometry = np.concatenate([x for x, _ in gathered])
        self._topology = np.concatenate([t + s for (_, t), s in zip(gathered, shift,
                                                                     strict=False)])
        self._topology_type = _XDMF_TOPOLOGY.get((cell_name, per_cell), "Mixed")
        self._h5 = _TwoCopies(self.h5_path, self._create_h5, self._append_h5)
        self._written = 0  # output steps in the HDF5 file (visible copy)
        self._write_index()

    # --- gathering (collective) -----------------------------------------------------------
    def _local_values(self, function) -> tuple[str, np.ndarray]:
        space = function.function_space
        key = id(space)
        if key not in self._maps:
            bs = space.dofmap.index_map_bs
            dofs = compat.cell_dofs(space)[: self._cells]
            per_cell = dofs.shape[1]
            if compat.element_degree(space) == 0:
                self._maps[key] = ("Cell", dofs[:, 0], bs)
            else:
                if per_cell != self._cell_nodes.shape[1]:
                    raise ValueError(f"XDMFSeries: {function.name} is not in the space of the "
                                     "mesh geometry")
                where = np.empty(len(self._nodes), dtype=np.int64)
                where[self._cell_nodes.ravel()] = dofs.ravel()
                self._maps[key] = ("Node", where, bs)
        kind, where, bs = self._maps[key]
        values = function.x.array.reshape(-1, bs)[where].real
        if bs == 2:  # XDMF vectors have three components
            values = np.hstack([values, np.zeros((len(values), 1))])
        return kind, values

    def write(self, t: float, functions, flush: bool | None = None) -> None:
        """Add the values of ``functions`` (name -> Function, or Functions) at time ``t``
        (collective); written to disk now if ``flush``, else by a later `flush`/`close`; by
        default at a bounded share of the wall time (`fe_beam.runctl.Throttle`)."""
        if isinstance(functions, dict):
            functions = list(functions.values())
        local = [(f.name, *self._local_values(f)) for f in functions]
        gathered = self.comm.gather([v for _, _, v in local], root=0)
        if not self.root:
            return
        step = {name: (kind, np.concatenate([part[i] for part in gathered]))
                for i, (name, kind, _) in enumerate(local)}
        self._buffered.append((float(t), step))
        if self._throttle.due() if flush is None else flush:
            self.flush()

    # --- files (rank 0) -----------------------------------------------------------------
    def _create_h5(self, path: Path) -> None:
        import h5py

        with h5py.File(path, "w", libver=H5_LIBVER) as h5:
            h5.create_dataset("/Mesh/mesh/geometry", data=self._geometry)
            h5.create_dataset("/Mesh/mesh/topology", data=self._topology)
            h5.create_group("/Function")

    def _append_h5(self, path: Path, items: list) -> None:
        import h5py

        with h5py.File(path, "a", libver=H5_LIBVER) as h5:
            functions = h5["Function"]
            groups = {}
            for index, step in items:
                for name, (_, values) in step.items():
                    if name not in groups:
                        groups[name] = functions.require_group(name).id
                    # the low-level API: a tenth of the cost of Group.create_dataset
                    values = np.ascontiguousarray(values, dtype=np.float64)
                    space = h5py.h5s.create_simple(values.shape)
                    dataset = h5py.h5d.create(groups[name], str(index).encode(),
                                              h5py.h5t.IEEE_F64LE, space)
                    dataset.write(h5py.h5s.ALL, h5py.h5s.ALL, values)

    def flush(self) -> None:
        """Write the buffered steps (rank 0; a no-op elsewhere)."""
        if not self.root or not self._buffered:
            return
        with self._throttle.timing():
            items = []
            for t, step in self._buffered:
                index = len(self._steps)
                items.append((index, step))
                self._steps.append((t, {n: (k, v.shape) for n, (k, v) in step.items()}))
            self._buffered = []
            self._h5.add(items)
            self._h5.flush()
            self._write_index()

    def _write_index(self) -> None:
        h5 = self.h5_path.name
        n, per_cell = self._topology.shape
        lines = [
            '<?xml version="1.0"?>',
            '<Xdmf Version="3.0" xmlns:xi="http://www.w3.org/2001/XInclude">',
            "  <Domain>",
            '    <Grid Name="mesh" GridType="Uniform">',
            f'      <Topology TopologyType="{self._topology_type}" NumberOfElements="{n}" '
            f'NodesPerElement="{per_cell}">',
            f'        <DataItem Dimensions="{n} {per_cell}" NumberType="Int" Precision="8" '
            f'Format="HDF">{h5}:/Mesh/mesh/topology</DataItem>',
            "      </Topology>",
            '      <Geometry GeometryType="XYZ">',
            f'        <DataItem Dimensions="{len(self._geometry)} 3" Format="HDF">'
            f"{h5}:/Mesh/mesh/geometry</DataItem>",
            "      </Geometry>",
            "    </Grid>",
            '    <Grid Name="TimeSeries" GridType="Collection" CollectionType="Temporal">',
        ]
        include = ('        <xi:include xpointer="xpointer(/Xdmf/Domain/Grid[@Name=\'mesh\']'
                   '/*[self::Topology or self::Geometry])" />')
        for index, (t, step) in enumerate(self._steps):
            lines += [f'      <Grid Name="step_{index}" GridType="Uniform">', include,
                      f'        <Time Value="{t!r}" />']
            for name, (kind, shape) in step.items():
                kind_name = "Vector" if len(shape) > 1 and shape[1] == 3 else "Scalar"
                dims = f"{shape[0]} {shape[1] if len(shape) > 1 else 1}"
                lines += [
                    f'        <Attribute Name="{name}" AttributeType="{kind_name}" '
                    f'Center="{kind}">',
                    f'          <DataItem Dimensions="{dims}" Format="HDF">'
                    f"{h5}:/Function/{name}/{index}</DataItem>",
                    "        </Attribute>",
                ]
            lines.append("      </Grid>")
        lines += ["    </Grid>", "  </Domain>", "</Xdmf>", ""]
        atomic_write_text(self.path, "\n".join(lines))

    def close(self) -> None:
        """Write what is buffered and finish the files (collective)."""
        if self.root:
            self.flush()
            self._h5.close()


def gather_line(problem, functions: dict) -> dict | None:
    """Values of P1 output functions at the mesh vertices, gathered on rank 0 and sorted by x.

    Returns {"x": ..., name: ...} on rank 0, None elsewhere.
    """
    first = next(iter(functions.values()))
    space = first.function_space
    owned = space.dofmap.index_map.size_local
    x = space.tabulate_dof_coordinates()[:owned, 0]
    local = {"x": x} | {name: f.x.array[:owned].copy() for name, f in functions.items()}
    gathered = problem.comm.gather(local, root=0)
    if problem.comm.rank != 0:
        return None
    merged = {key: np.concatenate([part[key] for part in gathered]) for key in local}
    order = np.argsort(merged["x"], kind="stable")
    return {key: value[order] for key, value in merged.items()}


class SectionFields:
    """The strains and section forces of a rod problem as cellwise (DG0) fields, recovered where
    the solver uses them: the L2 projection onto DG0 with the energy's own Gauss rule, i.e. the
    Gauss-weighted mean of the values at the energy's Gauss points (`BeamProblem.energy_rule`).

    With the default degree 2 the energy is integrated with 2 points per element (reduced
    integration, locking-free): the shear strain, and the forces, of the quadratic fields are
    right at the Gauss points only and oscillate between them, so a value sampled at the
    element midpoint is wrong (issue 28, item 6: T = 119 N for a 1 N tip load). The Gauss
    values of a tip-loaded cantilever are the exact (L - x) P and P, so their mean is exact at
    the midpoint: a linear resultant's midpoint value, a constant one's value. Degree 1 (one
    point: the midpoint) is unchanged."""

    def __init__(self, problem, expressions: dict, space):
        mesh = problem.mesh
        reference, weights = problem.energy_rule()
        self.weights = np.asarray(weights, dtype=float)
        self.names = list(expressions)
        self._compiled = compat.expression(
            ufl.as_vector([ufl.as_ufl(e) for e in expressions.values()]), reference)
        owned = mesh.topology.index_map(mesh.topology.dim).size_local
        self._cells = np.arange(owned, dtype=np.int32)
        self._dofs = compat.cell_dofs(space)[:owned, 0]
        self._mesh = mesh
        self.reference = np.asarray(reference, dtype=float).ravel()
        #: the values at the Gauss points of the last update: (owned cells, points, names)
        self.values = np.zeros((owned, len(self.weights), len(self.names)))

    def update(self, functions: list) -> None:
        """Put the recovered values into ``functions`` (DG0, in the order of the names)."""
        values = compat.evaluate_expression(self._compiled, self._mesh, self._cells)
        values = np.asarray(values).reshape(len(self._cells), len(self.weights), len(self.names))
        self.values = values
        means = np.einsum("q,cqf->cf", self.weights, values)
        for i, function in enumerate(functions):
            function.x.array[self._dofs] = means[:, i]
            function.x.scatter_forward()


class BeamXDMFWriter:
    """XDMF time series of a `BeamProblem`: u, v, theta and a displacement vector (P1, at the
    vertices; "Warp By Vector" in ParaView shows the deformed beam), and the strains eps, gamma,
    kappa and resultants N, T, M, axial force (DG0: one value per element, the Gauss-weighted
    mean of their values at the energy's Gauss points, see `SectionFields`).

    ``sections=False`` leaves the strains and resultants out: mode-shape files (buckling,
    critical points, vibration modes) hold normalised shapes, whose nonlinear strains and
    forces mean nothing.

    With ``contact`` (a `fe_beam.fem.contact.ContactSet`), per obstacle i (the order of
    [[obstacles]]) also ``contact_gap_i`` (P1: the signed gap [m] of the rod's surface at the
    vertices, interpolated from the set's UFL expression) and ``contact_pressure_i`` (DG0: the
    largest line pressure [N/m] at the cell's contact points, the values whose maximum is the
    summary's pressure_peak)."""

    def __init__(self, problem, path: str | Path | None, contact=None, sections: bool = True):
        self.problem = problem
        mesh = problem.mesh
        self.functions = {}
        self._expressions = []
        plan = self._plan(problem)
        cellwise = compat.function_space(mesh, compat.element(mesh, "DG", 0))
        self._sections = None
        self.section_names: list[str] = []
        if sections:
            expressions = problem.output_expressions()
            self._sections = SectionFields(problem, expressions, cellwise)
            self.section_names = list(expressions)
        self.contact = contact
        self._pressures = []
        gaps = []
        if contact is not None:
            scalar = next(space for name, _, space in plan if name == "u")  # P1, as u
            gaps = [(name, expr, scalar)
                    for name, expr in contact.output_expressions(problem).items()]
            owned = mesh.topology.index_map(mesh.topology.dim).size_local
            dofs = compat.cell_dofs(cellwise)[:owned, 0]
            for i in range(len(contact.obstacles)):
                function = fem.Function(cellwise, name=f"contact_pressure_{i}")
                self.functions[function.name] = function
                self._pressures.append((function, dofs))
        for name, expr, space in plan + gaps:
            function = fem.Function(space, name=name)
            self.functions[name] = function
            self._expressions.append((function, compat.interpolation_expression(
                ufl.as_ufl(expr), space)))
            if name == plan[-1][0]:  # the section fields after the nodal ones (file order)
                for section in self.section_names:
                    self.functions[section] = fem.Function(cellwise, name=section)
        chain = getattr(problem, "chain", None)
        if chain is not None:  # a chain of rods: the rod of each cell (its index in [[rods]])
            self.functions["rod"] = chain.rod
        self._file = XDMFSeries(mesh, path) if path is not None else None

    def end_moment(self, x_end: float, tolerance: float) -> float | None:
        """The moment at the rod's end ``x_end`` that the written fields M, T, eps imply
        (collective; None without the planar section fields), for a certificate against the
        support's reaction moment (`BeamProblem.end_reaction`, assembled from the residual).

        The rotation row of the end's vertex is the discrete moment equilibrium of the element
        at the end: with phi the degree-p Lagrange basis function of the end vertex and the
        values at the energy's Gauss points (the ones the fields are the means of),

            R_theta = sum_q w_q h (M_q phi'(x_q) - lambda_q T_q phi(x_q)),

        since dW/dtheta = -(r' x F).e_z = -lambda T for every objective law (lambda = |r'| =
        sqrt(1 + 2 eps), T = F.n). Equal to the reaction when no other load acts on the end
        element's rotations (tendons, contact: the caller decides)."""
        if self._sections is None or not {"M", "T", "eps"} <= set(self.section_names):
            return None
        sections = self._sections
        x = compat.cell_vertex_x(self.problem.mesh)[: len(sections.values)]
        local = 0.0
        degree = len(sections.weights)
        for cell in np.flatnonzero(np.min(np.abs(x - x_end), axis=1) <= tolerance):
            a, b = x[cell]
            nodes = a + (b - a) * np.linspace(0.0, 1.0, degree + 1)
            end = int(np.argmin(np.abs(nodes - x_end)))
            others = np.delete(nodes, end)
            points = a + (b - a) * sections.reference
            phi = np.prod([(points - o) / (nodes[end] - o) for o in others], axis=0)
            dphi = sum(np.prod([(points - o) / (nodes[end] - o) for o in others if o != skip],
                               axis=0) / (nodes[end] - skip) for skip in others)
            values = sections.values[cell]
            column = {n: values[:, i] for i, n in enumerate(sections.names)}
            stretch = np.sqrt(1 + 2 * column["eps"])
            local += abs(b - a) * float(np.sum(sections.weights * (
                column["M"] * dphi - stretch * column["T"] * phi)))
        return float(self.problem.comm.allreduce(local))

    @property
    def contact_names(self) -> tuple[list[str], list[str]]:
        """(nodal gap fields, cellwise pressure fields)."""
        if self.contact is None:
            return [], []
        count = len(self.contact.obstacles)
        return ([f"contact_gap_{i}" for i in range(count)],
                [f"contact_pressure_{i}" for i in range(count)])

    @staticmethod
    def _plan(problem) -> list:
        """(name, UFL expression, output space) of every nodal field written (interpolated at
        the vertices; the strains and section forces are `SectionFields`)."""
        mesh = problem.mesh
        scalar = compat.function_space(mesh, compat.element(mesh, "Lagrange", 1))
        vector = compat.function_space(mesh, compat.vector_element(mesh, "Lagrange", 1, dim=2))
        u, v, theta, _ = problem.fields()
        displacement = ufl.as_vector([u, v])
        chain = getattr(problem, "chain", None)
        if chain is not None:  # a chain of rods: from the mesh's (s, 0) to the deformed chain
            x = ufl.SpatialCoordinate(mesh)[0]
            displacement = ufl.as_vector([chain.reference[0] + u - x, chain.reference[1] + v])
        return [
            ("u", u, scalar),
            ("v", v, scalar),
            ("theta", theta, scalar),
            ("displacement", displacement, vector),
        ]

    def update(self) -> None:
        for function, expression in self._expressions:
            function.interpolate(expression)
        if self._sections is not None:
            self._sections.update([self.functions[n] for n in self.section_names])
        if self._pressures:
            for (function, dofs), values in zip(self._pressures, self.contact.cell_pressures(),
                                                strict=True):
                function.x.array[dofs] = values
                function.x.scatter_forward()

    def write(self, time: float, flush: bool | None = None) -> None:
        self.update()
        if self._file is not None:
            self._file.write(time, self.functions, flush)

    def flush(self) -> None:
        """Put every written step into the files now (rank 0; e.g. before an exit)."""
        if self._file is not None:
            self._file.flush()

    def vertex_values(self, update: bool = True) -> dict | None:
        """Current nodal u, v, theta and x, plus element-midpoint profiles under "cells"
        (x, eps, gamma, kappa, N, T, M, axial_force), gathered on rank 0 (None elsewhere).
        ``update=False``: the fields as the last `write` left them (same state, no second
        interpolation)."""
        if update:
            self.update()
        gaps, _ = self.contact_names
        nodal = gather_line(self.problem, {k: self.functions[k]
                                           for k in ("u", "v", "theta", *gaps)})
        cells = {k: f for k, f in self.functions.items()
                 if k not in ("u", "v", "theta", "displacement", *gaps)}
        cellwise = gather_line(self.problem, cells) if cells else None
        if nodal is not None:
            nodal["cells"] = cellwise
        return nodal

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None


@contextlib.contextmanager
def virtual_display():
    """A DISPLAY for VTK/pyvista: the current one, or a private Xvfb for the duration."""
    if os.environ.get("DISPLAY") or shutil.which("Xvfb") is None:
        yield
        return
    number = 90 + os.getpid() % 400
    server = subprocess.Popen(
        ["Xvfb", f":{number}", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.environ["DISPLAY"] = f":{number}"
    try:
        time.sleep(0.5)
        yield
    finally:
        del os.environ["DISPLAY"]
        server.terminate()
        server.wait(timeout=10)


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.figure
    import matplotlib.pyplot as plt

    figure = matplotlib.figure.Figure
    if not hasattr(figure.savefig, "__wrapped__"):
        figure.savefig = _atomic_savefig(figure.savefig)
    return plt


def _atomic_savefig(savefig):
    """Figure.savefig to a file name writes a temporary file and renames it: a plot is never
    seen half-written, whenever the run is interrupted (streams are left alone)."""

    def save(self, fname, *args, **kwargs):
        if not isinstance(fname, (str, os.PathLike)):
            return savefig(self, fname, *args, **kwargs)
        path = Path(fname)
        if path.suffix and "format" not in kwargs:
            kwargs["format"] = path.suffix[1:]
        runctl.register_output(path)
        temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        try:
            result = savefig(self, temporary, *args, **kwargs)
            os.replace(temporary, path)
        except BaseException:
            temporary.unlink(missing_ok=True)
            raise
        return result

    save.__wrapped__ = savefig
    return save


@contextlib.contextmanager
def figure(path: str | Path | None, *args, layout: bool = True, dpi: int = 130, **kwargs):
    """``plt.subplots(*args, **kwargs)`` as (figure, axes); on leaving: ``tight_layout`` (with
    ``layout``), saved to ``path`` (atomically; not when None) and closed."""
    plt = _pyplot()
    drawn, axes = plt.subplots(*args, **kwargs)
    try:
        yield drawn, axes
        if layout:
            drawn.tight_layout()
        if path is not None:
            drawn.savefig(path, dpi=dpi)
    finally:
        plt.close(drawn)


def section_faces(shape: dict, section, length: float):
    """The section's bottom and top faces of a planar deformed shape: (lower, upper) arrays
    (n, 2) of the centreline (x + u, v) offset by y_min(x) and y_max(x) (`Section.y_extent`:
    -h/2 and +h/2 of a symmetric section) along the section's normal d2 = (-sin theta,
    cos theta) at the nodes ``shape["x"]``; None when the section's shape is not known (a
    custom section)."""
    x = np.asarray(shape["x"], dtype=float)
    extents = [section.y_extent(float(s)) for s in x / length]
    if any(e is None for e in extents):
        return None
    low, high = np.array(extents, dtype=float).T
    theta = np.asarray(shape["theta"], dtype=float)
    centre = np.column_stack([x + np.asarray(shape["u"]), np.asarray(shape["v"])])
    normal = np.column_stack([-np.sin(theta), np.cos(theta)])
    return centre + low[:, None] * normal, centre + high[:, None] * normal


def draw_section_faces(axes, shape: dict, section, length: float, colour,
                       fill: bool = False) -> None:
    """The section's outline around a drawn centreline: the bottom and top faces
    (`section_faces`) and the end sections as a thin closed line (a finger touching an
    obstacle with a face is seen touching it), on a light band if ``fill`` (the last shape:
    overlapping bands of every shape would hide each other); nothing without a known
    section."""
    faces = None if section is None else section_faces(shape, section, length)
    if faces is None:
        return
    lower, upper = faces
    outline = np.concatenate([lower, upper[::-1], lower[:1]])
    if fill:
        axes.fill(outline[:, 0], outline[:, 1], color=colour, alpha=0.15, lw=0)
    axes.plot(outline[:, 0], outline[:, 1], color=colour, lw=0.6, alpha=0.8)


def plot_deformed_shapes(
    shapes: list[tuple[str, dict]],
    path: str | Path,
    title: str,
    length: float,
    reference: list[tuple[str, float, float]] = (),
    obstacles=(),
    section=None,
    undeformed=None,
    marks=(),
) -> None:
    """Deformed axes (x + u, y + v) with labels; ``reference`` adds marked tip points;
    ``marks`` (a structure's `drawing_marks`) are drawn on the last shape (`draw_marks`);
    ``obstacles`` (`fe_beam.model.obstacles`) are drawn in grey; ``section`` (a
    `fe_beam.model.sections.Section`) adds each shape's outline (`draw_section_faces`);
    ``undeformed``: the reference axis as points ((x, y), ...) (default the x axis to L: a
    chain of rods gives its corners)."""

    with figure(path, figsize=(7, 5), layout=False) as (_, axes):
        colours = _pyplot().cm.viridis(np.linspace(0, 0.9, max(len(shapes), 1)))
        xs, ys = ([0, length], [0, 0]) if undeformed is None else zip(*undeformed)
        axes.plot(list(xs), list(ys), color="0.7", lw=1, ls="--", label="undeformed")
        for index, ((label, shape), colour) in enumerate(zip(shapes, colours, strict=False)):
            axes.plot(shape["x"] + shape["u"], shape["v"], color=colour, lw=1.8, label=label)
            draw_section_faces(axes, shape, section, length, colour,
                               fill=index == len(shapes) - 1)
        if obstacles:
            draw_obstacles(axes, obstacles, shapes, length)
        for i, (label, x, y) in enumerate(reference):
            axes.plot(x, y, "kx", ms=7, label=label if i == 0 else None)
        if marks and shapes:
            draw_marks(axes, shapes[-1][1], marks)
        # true shape (equal scales) in an axes that keeps its size: the legend fits inside it
        axes.set_aspect("equal", adjustable="datalim")
        axes.set_xlabel("x + u [m]")
        axes.set_ylabel("y + v [m]")
        axes.set_title(title)
        axes.grid(alpha=0.3)
        legend_inside(axes, fontsize=7)


def draw_marks(axes, shape: dict, marks) -> None:
    """A structure's joints (filled: rigid, open: pin), held ends (grey triangles, their
    support or body named) and point forces (red arrows, scaled to a tenth of the drawing)
    where ``shape`` (a structure's line shape: mesh coordinate ``x``, drawn at (x + u, v))
    puts them."""
    s = np.asarray(shape["x"], dtype=float)
    px, py = s + np.asarray(shape["u"], dtype=float), np.asarray(shape["v"], dtype=float)
    finite = np.isfinite(s) & np.isfinite(px) & np.isfinite(py)
    s, px, py = s[finite], px[finite], py[finite]
    if not len(s):
        return
    order = np.argsort(s, kind="stable")
    s, px, py = s[order], px[order], py[order]
    span = max(float(np.ptp(px)), float(np.ptp(py)), 1e-300)

    def where(at):
        k = int(np.argmin(np.abs(s - at)))  # marks sit at vertices
        return px[k], py[k]

    labelled = set()

    def label(kind, text):
        if kind in labelled:
            return None
        labelled.add(kind)
        return text

    for mark in marks:
        x, y = where(mark["s"])
        if mark["kind"] == "joint":
            pin = "(pin)" in mark["label"] or "(ball)" in mark["label"]
            axes.plot(x, y, "o", ms=6, mec="k", mfc="white" if pin else "k", zorder=5,
                      label=label("joint", "joint"))
        elif mark["kind"] in ("support", "body"):
            axes.plot(x, y, "^" if mark["kind"] == "support" else "s", ms=9, mec="0.2",
                      mfc="0.6", zorder=4, label=label(mark["kind"], mark["kind"]))
            axes.annotate(mark["label"], (x, y), xytext=(4, -10), textcoords="offset points",
                          fontsize=6, color="0.3")
        elif mark["kind"] == "force":
            vector = np.asarray(mark["vector"][:2], dtype=float)
            size = float(np.linalg.norm(vector))
            if size == 0.0:
                continue
            d = 0.1 * span * vector / size
            axes.annotate("", (x, y), xytext=(x - d[0], y - d[1]),
                          arrowprops={"arrowstyle": "->", "color": "C3", "lw": 1.5})
            if "force" not in labelled:
                axes.plot([], [], color="C3", lw=1.5, label=label("force", "point force"))


def plot_load_displacement(load_factors, tips: dict, path: str | Path, title: str) -> None:
    with figure(path, figsize=(6, 4)) as (_, axes):
        for name, values in tips.items():
            axes.plot(load_factors, values, marker="o", ms=3, label=name)
        axes.set_xlabel("load factor")
        axes.set_ylabel("tip value [m] / [rad]")
        axes.set_title(title)
        axes.grid(alpha=0.3)
        axes.legend()


def draw_obstacles(axes, obstacles, shapes, length: float) -> None:
    """Planar obstacles as grey patches (a plane as a strip behind its line across the
    drawn region), labelled with their names; the limits stay those of the rod's shapes."""
    from matplotlib import patches

    xs = [np.asarray(s["x"]) + np.asarray(s["u"]) for _, s in shapes] or [np.array([0, length])]
    ys = [np.asarray(s["v"]) for _, s in shapes] or [np.array([0.0])]
    low = np.array([min(x.min() for x in xs), min(y.min() for y in ys)])
    high = np.array([max(x.max() for x in xs), max(y.max() for y in ys)])
    span = max(float(np.max(high - low)), length)
    low, high = low - 0.25 * span, high + 0.25 * span
    for obstacle in obstacles:
        style = {"facecolor": "0.8", "edgecolor": "0.4", "lw": 1, "zorder": 0}
        shape = getattr(obstacle, "shape", "")
        if shape == "plane":
            point, normal = np.array(obstacle.point), np.array(obstacle.normal)
            tangent = np.array([-normal[1], normal[0]])
            reach = 2 * float(np.linalg.norm(high - low))
            a, b = point - reach * tangent, point + reach * tangent
            depth = 0.05 * span * normal
            axes.add_patch(patches.Polygon([a, b, b - depth, a - depth], closed=True, **style))
            anchor = point
        elif shape in ("sphere", "cylinder"):
            centre = obstacle.center if shape == "sphere" else obstacle.point
            axes.add_patch(patches.Circle(centre, obstacle.radius, **style))
            anchor = np.array(centre)
        elif shape == "box":
            size = np.array(obstacle.max) - np.array(obstacle.min)
            axes.add_patch(patches.Rectangle(obstacle.min, size[0], size[1], **style))
            anchor = np.array(obstacle.center)
        else:
            continue
        axes.annotate(obstacle.name, anchor, fontsize=7, color="0.3")
    axes.set_xlim(low[0], high[0])  # the patches reach farther: the rod's region is shown
    axes.set_ylim(low[1], high[1])

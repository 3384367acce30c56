"""Parametric gmsh (OCC) model of the tapered finger with embedded tendons.

Reference configuration (SI units):

    0 <= x <= L,   |y| <= H(x) / 2,   |z| <= B / 2,   H(x) = H0 + (H1 - H0) x / L,

so the origin is the centroid of the clamped face x = 0 and every cross-section is centred on
the x axis. A tendon is a polyline of points (x, y, z) strictly inside the body; it is fragmented
into the volume (``occ.fragment``) so that it lies on mesh edges, which is checked after meshing.

Physical groups: the volume (`VOLUME_TAG`), the clamp face x = 0 (`CLAMP_TAG`), the tip face
x = L (`TIP_TAG`) and one 1D group per tendon (`TENDON_TAG0 + i`).

gmsh runs on one rank only (``rank``); the mesh is distributed by dolfinx and the tendon chains
(ordered vertex coordinates) are broadcast to every rank.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from mpi4py import MPI

from fe_beam.fem import compat
from fe_beam.model.solid import (  # noqa: F401  (their home; re-exported)
    FingerGeometry,
    MeshSizes,
    TendonPath,
    _positive,
)

__all__ = [
    "CLAMP_TAG",
    "TENDON_TAG0",
    "TIP_TAG",
    "VOLUME_TAG",
    "FingerGeometry",
    "FingerMesh",
    "MeshSizes",
    "TendonPath",
    "build_gmsh_model",
    "create_finger_mesh",
    "write_msh",
]

VOLUME_TAG = 1
CLAMP_TAG = 1
TIP_TAG = 2
TENDON_TAG0 = 101


@dataclass
class FingerMesh:
    """The distributed dolfinx mesh, its tags and the tendon chains (identical on all ranks).

    ``tendon_chains[i]`` is an (n_i, 3) array of the reference coordinates of the mesh vertices
    on tendon i, ordered from entry to anchor; consecutive vertices share a mesh edge.
    """

    mesh: object
    cell_tags: object
    facet_tags: object
    geometry: FingerGeometry
    sizes: MeshSizes
    tendon_chains: list[np.ndarray] = field(default_factory=list)

    @property
    def comm(self) -> MPI.Comm:
        return self.mesh.comm


def build_gmsh_model(geometry: FingerGeometry, sizes: MeshSizes, model=None) -> list[list[int]]:
    """Build and mesh the finger in the current gmsh model (gmsh must be initialised).

    Returns, per tendon, the tags of the gmsh curves it consists of. Raises RuntimeError when a
    tendon does not end up on tetrahedron edges.
    """
    import gmsh

    model = model or gmsh.model
    occ = model.occ
    L, B = geometry.length, geometry.width
    H0, H1 = geometry.height_base, geometry.height_tip

    def section_wire(x, h):
        corners = [(x, -h / 2, -B / 2), (x, h / 2, -B / 2), (x, h / 2, B / 2), (x, -h / 2, B / 2)]
        pts = [occ.addPoint(*c) for c in corners]
        lines = [occ.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)]
        return occ.addCurveLoop(lines)

    body = occ.addThruSections([section_wire(0.0, H0), section_wire(L, H1)], makeRuled=True)
    volume = [t for d, t in body if d == 3]
    if len(volume) != 1:
        raise RuntimeError(f"gmsh: expected one volume from the sections, got {body}")
    volume = volume[0]
    occ.synchronize()
    if geometry.tip_radius > 0:
        tip_surface = _face_at_x(model, L, L)
        tip_edges = [abs(t) for d, t in model.getBoundary([(2, tip_surface)], oriented=False)]
        out = occ.fillet([volume], tip_edges, [geometry.tip_radius])
        volume = [t for d, t in out if d == 3][0]
        occ.synchronize()

    tool_lines, owner = [], []
    for i, tendon in enumerate(geometry.tendons):
        pts = [occ.addPoint(*p) for p in tendon.points]
        for a, b in zip(pts[:-1], pts[1:], strict=True):
            tool_lines.append((1, occ.addLine(a, b)))
            owner.append(i)
    tendon_curves: list[list[int]] = [[] for _ in geometry.tendons]
    if tool_lines:
        out, out_map = occ.fragment([(3, volume)], tool_lines)
        volumes = [t for d, t in out if d == 3]
        if len(volumes) != 1:
            raise RuntimeError(f"gmsh: fragmenting the tendons split the body: {volumes}")
        volume = volumes[0]
        for pieces, i in zip(out_map[1:], owner, strict=True):
            tendon_curves[i].extend(t for d, t in pieces if d == 1)
    occ.synchronize()

    clamp, tip = _face_at_x(model, 0.0, L), _face_at_x(model, L, L)
    model.addPhysicalGroup(3, [volume], VOLUME_TAG)
    model.setPhysicalName(3, VOLUME_TAG, "finger")
    model.addPhysicalGroup(2, [clamp], CLAMP_TAG)
    model.setPhysicalName(2, CLAMP_TAG, "clamp")
    model.addPhysicalGroup(2, [tip], TIP_TAG)
    model.setPhysicalName(2, TIP_TAG, "tip")
    for i, curves in enumerate(tendon_curves):
        model.addPhysicalGroup(1, sorted(set(curves)), TENDON_TAG0 + i)
        model.setPhysicalName(1, TENDON_TAG0 + i, geometry.tendons[i].name)

    _size_fields(model, sizes, [c for cs in tendon_curves for c in cs], clamp)
    model.mesh.generate(3)
    if sizes.order == 2:
        gmsh.option.setNumber("Mesh.HighOrderOptimize", 2)
        model.mesh.setOrder(2)
        model.mesh.optimize("HighOrder")
    for i, curves in enumerate(tendon_curves):
        _check_embedded(model, curves, geometry.tendons[i].name)
    return tendon_curves


def _face_at_x(model, x: float, length: float) -> int:
    """The planar surface lying in the plane X = x (OCC pads bounding boxes by ~1e-7)."""
    faces = []
    for _, tag in model.getEntities(2):
        xmin, _, _, xmax, _, _ = model.getBoundingBox(2, tag)
        xc = model.occ.getCenterOfMass(2, tag)[0]
        if xmax - xmin < 1e-3 * length and abs(xc - x) < 1e-6 * length:
            faces.append(tag)
    if len(faces) != 1:
        raise RuntimeError(f"gmsh: expected one face in the plane x = {x}, found {faces}")
    return faces[0]


def _size_fields(model, sizes: MeshSizes, tendon_curves: list[int], clamp: int) -> None:
    import gmsh

    fields = model.mesh.field
    thresholds = []
    for entities, key, size, dist in (
        (tendon_curves, "CurvesList", sizes.tendon, sizes.tendon_distance),
        ([clamp], "SurfacesList", sizes.clamp, sizes.clamp_distance),
    ):
        if not entities or size >= sizes.size:
            continue
        d = fields.add("Distance")
        fields.setNumbers(d, key, entities)
        fields.setNumber(d, "NumPointsPerCurve", 100)
        t = fields.add("Threshold")
        fields.setNumber(t, "InField", d)
        fields.setNumber(t, "SizeMin", size)
        fields.setNumber(t, "SizeMax", sizes.size)
        fields.setNumber(t, "DistMin", dist)
        fields.setNumber(t, "DistMax", 2 * dist)
        thresholds.append(t)
    if thresholds:
        m = fields.add("Min")
        fields.setNumbers(m, "FieldsList", thresholds)
        fields.setAsBackgroundMesh(m)
    gmsh.option.setNumber("Mesh.MeshSizeMax", sizes.size)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)


def _curve_segments(model, curves: list[int]) -> np.ndarray:
    """(n, 2) vertex node tags of the line elements on ``curves`` (mid-edge nodes dropped)."""
    segments = []
    for c in curves:
        types, _, nodes = model.mesh.getElements(1, c)
        for etype, enodes in zip(types, nodes, strict=True):
            n = model.mesh.getElementProperties(etype)[3]
            segments.append(np.asarray(enodes, dtype=np.int64).reshape(-1, n)[:, :2])
    return np.concatenate(segments) if segments else np.empty((0, 2), dtype=np.int64)


def _check_embedded(model, curves: list[int], name: str) -> None:
    """Raise unless every line element of the tendon is an edge of a tetrahedron."""
    segments = np.sort(_curve_segments(model, curves), axis=1)
    types, _, nodes = model.mesh.getElements(3)
    tet_type = [t for t in types if model.mesh.getElementProperties(t)[0].startswith("Tetra")]
    if not tet_type:
        raise RuntimeError("gmsh: no tetrahedra in the mesh")
    k = list(types).index(tet_type[0])
    n = model.mesh.getElementProperties(types[k])[3]
    tets = np.asarray(nodes[k], dtype=np.int64).reshape(-1, n)[:, :4]
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    edges = np.sort(np.concatenate([tets[:, [a, b]] for a, b in pairs]), axis=1)
    big = int(max(edges.max(), segments.max(initial=0))) + 1
    found = np.isin(segments[:, 0] * big + segments[:, 1], edges[:, 0] * big + edges[:, 1])
    if segments.size == 0 or not np.all(found):
        raise RuntimeError(
            f"gmsh: tendon {name!r} is not embedded in the volume mesh "
            f"({int(np.count_nonzero(~found))} of {len(segments)} segments are not tet edges)"
        )


def _ordered_chain(model, curves: list[int], start: np.ndarray) -> np.ndarray:
    """Coordinates of the tendon's vertices in order, walking the segment graph from ``start``."""
    segments = _curve_segments(model, curves)
    neighbours: dict[int, list[int]] = {}
    for a, b in segments.tolist():
        neighbours.setdefault(a, []).append(b)
        neighbours.setdefault(b, []).append(a)
    if any(len(v) > 2 for v in neighbours.values()):
        raise RuntimeError("gmsh: a tendon's line elements do not form a simple chain")
    ends = [n for n, v in neighbours.items() if len(v) == 1]
    coords = {}
    for n in neighbours:
        coords[n] = np.asarray(model.mesh.getNode(n)[0], dtype=float)
    first = min(ends, key=lambda n: np.linalg.norm(coords[n] - start))
    order, previous = [first], None
    while True:
        nxt = [m for m in neighbours[order[-1]] if m != previous]
        if not nxt:
            break
        previous = order[-1]
        order.append(nxt[0])
    if len(order) != len(neighbours):
        raise RuntimeError("gmsh: a tendon's line elements are not connected")
    return np.array([coords[n] for n in order])


def create_finger_mesh(
    geometry: FingerGeometry,
    sizes: MeshSizes,
    comm: MPI.Comm = MPI.COMM_WORLD,
    rank: int = 0,
    verbose: bool = False,
) -> FingerMesh:
    """Mesh the finger with gmsh on ``rank`` and distribute it over ``comm``."""
    import gmsh

    chains, error = None, None
    if comm.rank == rank:
        compat.gmsh_initialize()
        try:
            gmsh.option.setNumber("General.Terminal", 1 if verbose else 0)
            gmsh.model.add("finger")
            curves = build_gmsh_model(geometry, sizes)
            chains = [
                _ordered_chain(gmsh.model, c, geometry.tendons[i].array[0])
                for i, c in enumerate(curves)
            ]
        except Exception as exc:  # reported on every rank below, not left to hang the others
            error = f"{type(exc).__name__}: {exc}"
    error = comm.bcast(error, root=rank)
    if error is not None:
        if comm.rank == rank:
            gmsh.finalize()
        raise RuntimeError(f"gmsh could not mesh the finger: {error}")
    if comm.rank == rank:
        try:
            msh, cell_tags, facet_tags = compat.gmsh_model_to_mesh(gmsh.model, comm, rank, 3)
        finally:
            gmsh.finalize()
    else:
        msh, cell_tags, facet_tags = compat.gmsh_model_to_mesh(None, comm, rank, 3)
    chains = comm.bcast(chains, root=rank)
    return FingerMesh(msh, cell_tags, facet_tags, geometry, sizes, chains)


def write_msh(geometry: FingerGeometry, sizes: MeshSizes, path: str, verbose: bool = True) -> None:
    """Mesh the finger with gmsh (this process only) and write it to a .msh file."""
    import gmsh

    compat.gmsh_initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 1 if verbose else 0)
        gmsh.model.add("finger")
        build_gmsh_model(geometry, sizes)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()

"""Rigid obstacles as surfaces: triangulations for ParaView (``obstacles.vtu``, written once
per run next to ``beam.xdmf``) and for the 3D views of the pictures.

Shapes are read by duck typing (``shape``, ``point``/``normal``, ``center``/``radius``,
``axis``/``length``, ``min``/``max`` of `fe_beam.model.obstacles`); planar rods' 2D obstacles
are lifted to z = 0 and extruded along z (a plane becomes a vertical patch, a cylinder a
cylinder along z, a box a slab, a sphere stays a sphere: its section by z = 0 is the disc the
rod touches). Every vertex lies on the obstacle's surface: a plane patch's signed distance is
0, a sphere's and a cylinder's vertices are at ``radius`` from the centre / axis, a box's on its
faces.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fe_beam.exports.outputs import _atomic_path

__all__ = ["bounding_box", "obstacle_surface", "write_obstacle_surfaces"]


def bounding_box(shapes, length: float, pad: float = 0.25) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) 3-vectors: the box of the deformed centrelines ``shapes`` ((label, dict) of
    x, u, v and w for spatial rods; or none: the reference line [0, L]) and the reference
    line, widened by ``pad`` times its largest side (at least the length) on every side."""
    points = [np.array([[0.0, 0.0, 0.0], [length, 0.0, 0.0]])]
    for _, shape in shapes:
        x = np.asarray(shape["x"]) + np.asarray(shape["u"])
        w = np.asarray(shape["w"]) if "w" in shape else np.zeros_like(x)
        points.append(np.column_stack([x, np.asarray(shape["v"]), w]))
    points = np.vstack(points)
    low, high = points.min(axis=0), points.max(axis=0)
    span = max(float(np.max(high - low)), length)
    return low - pad * span, high + pad * span


def _lift(vector, dim: int) -> np.ndarray:
    v = np.asarray(vector, dtype=float)
    return np.append(v, 0.0) if dim == 2 else v


def _frame(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors orthogonal to the unit ``axis`` and to each other."""
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    first = np.cross(axis, helper)
    first /= np.linalg.norm(first)
    return first, np.cross(axis, first)


def _grid(nu: int, nv: int, closed_u: bool = False) -> np.ndarray:
    """Triangles of an nu x nv grid of points (index u * nv + v); ``closed_u`` wraps u."""
    triangles = []
    for a in range(nu if closed_u else nu - 1):
        b = (a + 1) % nu
        for c in range(nv - 1):
            p, q, r, s = a * nv + c, b * nv + c, b * nv + c + 1, a * nv + c + 1
            triangles += [[p, q, r], [p, r, s]]
    return np.array(triangles, dtype=np.int64)


def _corners(low, high) -> np.ndarray:
    return np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                     for z in (low[2], high[2])])


def obstacle_surface(obstacle, low, high, resolution: int = 48
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(points (n, 3), triangles (m, 3)) of ``obstacle``'s surface; a plane is the patch that
    covers the box [low, high] seen along its normal, an infinite cylinder the part whose
    axial extent covers that box."""
    dim = getattr(obstacle, "dim", len(getattr(obstacle, "point", getattr(obstacle, "center",
                                                                          (0, 0)))))
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    shape = obstacle.shape
    if shape == "plane":
        point, normal = _lift(obstacle.point, dim), _lift(obstacle.normal, dim)
        t1, t2 = _frame(normal)
        rel = _corners(low, high) - point
        a = np.linspace(*(lambda c: (c.min(), c.max()))(rel @ t1), 11)
        b = np.linspace(*(lambda c: (c.min(), c.max()))(rel @ t2), 11)
        points = np.array([point + s * t1 + t * t2 for s in a for t in b])
        return points, _grid(len(a), len(b))
    if shape == "sphere":
        centre, radius = _lift(obstacle.center, dim), obstacle.radius
        polar = np.linspace(0.0, np.pi, resolution // 2 + 1)[1:-1]
        azimuth = np.linspace(0.0, 2 * np.pi, resolution, endpoint=False)
        ring = np.array([[np.sin(p) * np.cos(a), np.sin(p) * np.sin(a), np.cos(p)]
                         for a in azimuth for p in polar])
        points = np.vstack([ring, [[0, 0, 1], [0, 0, -1]]]) * radius + centre
        triangles = [_grid(resolution, len(polar), closed_u=True)]
        top, bottom, n = len(ring), len(ring) + 1, len(polar)
        for a in range(resolution):
            b = (a + 1) % resolution
            triangles.append([[top, b * n, a * n], [bottom, a * n + n - 1, b * n + n - 1]])
        return points, np.vstack(triangles).astype(np.int64)
    if shape == "cylinder":
        centre, radius = _lift(obstacle.point, dim), obstacle.radius
        axis = np.array([0.0, 0.0, 1.0]) if dim == 2 or obstacle.axis is None \
            else np.asarray(obstacle.axis, dtype=float)
        if getattr(obstacle, "length", None) is not None and dim == 3:
            ends = (-obstacle.length / 2, obstacle.length / 2)
        else:
            along = (_corners(low, high) - centre) @ axis
            ends = (along.min(), along.max())
        t1, t2 = _frame(axis)
        azimuth = np.linspace(0.0, 2 * np.pi, resolution, endpoint=False)
        heights = np.linspace(ends[0], ends[1], 9)
        points = np.array([centre + h * axis + radius * (np.cos(a) * t1 + np.sin(a) * t2)
                           for a in azimuth for h in heights])
        return points, _grid(resolution, len(heights), closed_u=True)
    if shape == "box":
        lo, hi = _lift(obstacle.min, dim), _lift(obstacle.max, dim)
        if dim == 2:
            lo[2], hi[2] = low[2], high[2]
        corners = _corners(lo, hi)  # index 4 i + 2 j + k for x, y, z in (lo, hi)
        quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4),
                 (1, 5, 7, 3)]
        triangles = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
        return corners, np.array(triangles, dtype=np.int64)
    raise ValueError(f"obstacle_surface: unknown obstacle shape {shape!r}")


def write_obstacle_surfaces(obstacles, path: str | Path, low, high) -> Path:
    """All ``obstacles`` as one triangulated surface, ``path`` (VTK XML unstructured grid,
    e.g. obstacles.vtu: ParaView opens it next to beam.xdmf), with the cell field
    ``obstacle`` (its index in [[obstacles]]; "Threshold" on it shows one). Rank-local."""
    import meshio


    points, cells, index = [], [], []
    shift = 0
    for i, obstacle in enumerate(obstacles):
        p, t = obstacle_surface(obstacle, low, high)
        points.append(p)
        cells.append(t + shift)
        index.append(np.full(len(t), i, dtype=np.int64))
        shift += len(p)
    mesh = meshio.Mesh(np.vstack(points), [("triangle", np.vstack(cells))],
                       cell_data={"obstacle": [np.concatenate(index)]})
    path = Path(path)
    with _atomic_path(path) as temporary:
        meshio.write(temporary, mesh, file_format="vtu")
    return path

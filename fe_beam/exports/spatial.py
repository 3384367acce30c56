"""Outputs of spatial rods: the XDMF series with the directors as vectors, and pictures with
three views and a 3D view of the deformed centreline and its section frames.

ParaView (docs/usage.md, Spatial rods): open ``beam.xdmf``, "Warp By Vector" with
``displacement``, then "Glyph" (arrows) with ``d2`` or ``d3`` to see the section frames, or "Tube"
on the warped line for the centreline.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import ufl

from fe_beam.exports.obstacles import bounding_box, obstacle_surface
from fe_beam.exports.outputs import BeamXDMFWriter, _pyplot, figure, gather_line
from fe_beam.exports.plotting import legend_inside
from fe_beam.fem import compat

__all__ = ["SpatialXDMFWriter", "plot_spatial_load_displacement", "plot_spatial_shapes"]

NODAL = ("u", "v", "w", "theta_x", "theta_y", "theta_z")


class SpatialXDMFWriter(BeamXDMFWriter):
    """XDMF time series of a `fe_beam.fem.spatial_rod.SpatialRodProblem`: the displacement
    (a 3-vector, P1 at the vertices: "Warp By Vector"), the rotation vector, the directors
    d1, d2, d3 (3-vectors: "Glyph" shows the section frames) and the strains v1, v2, v3 and
    curvatures twist, curvature_y, curvature_z (DG0: the Gauss-weighted mean of their values at
    the energy's Gauss points, see `fe_beam.exports.outputs.SectionFields`)."""

    @staticmethod
    def _plan(problem) -> list:
        mesh = problem.mesh
        scalar = compat.function_space(mesh, compat.element(mesh, "Lagrange", 1))
        vector = compat.function_space(mesh, compat.vector_element(mesh, "Lagrange", 1, dim=3))
        d, theta, _ = problem.fields()
        plan = [(name, d[i] if i < 3 else theta[i - 3], scalar)
                for i, name in enumerate(NODAL)]
        displacement = d
        chain = getattr(problem, "chain", None)
        if chain is not None:  # a chain of rods: from the mesh's (s, 0, 0) to the deformed chain
            x = ufl.SpatialCoordinate(mesh)[0]
            displacement = chain.reference + d - ufl.as_vector([x, 0, 0])
        plan += [("displacement", displacement, vector), ("rotation_vector", theta, vector)]
        return plan + [(f"d{i + 1}", director, vector)
                       for i, director in enumerate(problem.directors())]

    def vertex_values(self, update: bool = True) -> dict | None:
        """Nodal u, v, w, the rotation vector and x, and the directors d2, d3 (arrays of
        shape (n, 3)), gathered on rank 0 sorted by x (None elsewhere)."""
        if update:
            self.update()
        gaps, pressures = self.contact_names
        nodal = gather_line(self.problem, {k: self.functions[k] for k in (*NODAL, *gaps)})
        frames = {}
        for name in ("d2", "d3"):
            function = self.functions[name]
            owned = function.function_space.dofmap.index_map.size_local
            values = function.x.array.reshape(-1, 3)[:owned]
            x = function.function_space.tabulate_dof_coordinates()[:owned, 0]
            gathered = self.problem.comm.gather((x, values), root=0)
            if gathered is not None:
                xs = np.concatenate([g[0] for g in gathered])
                frames[name] = np.concatenate([g[1] for g in gathered])[np.argsort(
                    xs, kind="stable")]
        cells = {k: f for k, f in self.functions.items()
                 if k in self.section_names or k in pressures}
        cellwise = gather_line(self.problem, cells) if cells else None
        if nodal is not None:
            nodal.update(frames)
            nodal["cells"] = cellwise
        return nodal


def plot_spatial_shapes(shapes: list[tuple[str, dict]], path: str | Path, title: str,
                        length: float, offset: np.ndarray | None = None,
                        obstacles=(), undeformed=None) -> None:
    """Deformed centrelines in three views (x-y from above, x-z from the side, y-z along the
    axis) and a 3D view with the section frames' d2 (the h direction) drawn along the last
    shape. ``offset``: the straight reference's displacement to subtract (none here).
    ``obstacles`` (3D `fe_beam.model.obstacles`) are drawn in grey: in the views a sphere as
    its outline circle, a cylinder as its outline (a circle seen along its axis, else a strip
    of its diameter), a box as its rectangle, a plane as its trace through its point with a
    strip on the solid side (left out in a view along which it lies); in the 3D view as
    translucent surfaces (`fe_beam.exports.obstacles.obstacle_surface`), cut to the rod's
    bounding box widened by a quarter. ``undeformed``: the reference polyline's corners (a
    chain of rods; default the straight axis (0, 0, 0)-(length, 0, 0))."""
    plt = _pyplot()
    low, high = bounding_box(shapes, length)
    drawn = plt.figure(figsize=(11, 8.5))
    try:
        colours = plt.cm.viridis(np.linspace(0, 0.9, max(len(shapes), 1)))
        views = [(1, "x", "y", 0, 1), (2, "x", "z", 0, 2), (3, "y", "z", 1, 2)]
        axes_3d = drawn.add_subplot(2, 2, 4, projection="3d")
        extent = np.zeros((0, 3))
        for number, first, second, i, j in views:
            axes = drawn.add_subplot(2, 2, number)
            reference = (np.array([[0, 0, 0], [length, 0, 0]], dtype=float)
                         if undeformed is None else np.asarray(undeformed, dtype=float))
            axes.plot(reference[:, i], reference[:, j], color="0.7", lw=1, ls="--",
                      label="undeformed")
            for (label, shape), colour in zip(shapes, colours, strict=False):
                points = _points(shape)
                axes.plot(points[:, i], points[:, j], color=colour, lw=1.8, label=label)
                axes.plot(points[-1, i], points[-1, j], "o", color=colour, ms=3)
            if obstacles:
                _draw_view_obstacles(axes, obstacles, i, j, low, high)
                axes.set_xlim(low[i], high[i])
                axes.set_ylim(low[j], high[j])
            axes.set_aspect("equal", adjustable="datalim")
            axes.set_xlabel(f"{first} [m]")
            axes.set_ylabel(f"{second} [m]")
            axes.set_title({1: "top view (x-y)", 2: "side view (x-z)",
                            3: "along the axis (y-z)"}[number], fontsize=9)
            axes.grid(alpha=0.3)
            if number == 1:
                legend_inside(axes, fontsize=7)
        for (_, shape), colour in zip(shapes, colours, strict=False):
            points = _points(shape)
            extent = np.vstack([extent, points])
            axes_3d.plot(points[:, 0], points[:, 1], points[:, 2], color=colour, lw=1.8)
        if shapes and "d2" in shapes[-1][1]:
            points = _points(shapes[-1][1])
            frames = shapes[-1][1]
            every = max(1, len(points) // 12)
            scale = 0.06 * length
            for name, colour in (("d2", "tab:red"), ("d3", "tab:blue")):
                arrows = frames[name][::every] * scale
                base = points[::every]
                axes_3d.quiver(base[:, 0], base[:, 1], base[:, 2], arrows[:, 0], arrows[:, 1],
                               arrows[:, 2], color=colour, lw=0.8,
                               label=f"{name} ({'h' if name == 'd2' else 'b'} direction)")
            axes_3d.legend(fontsize=7, loc="upper left")
        if obstacles:
            near_low, near_high = bounding_box(shapes, length, pad=0.1)
            for obstacle in obstacles:
                points, triangles = obstacle_surface(obstacle, near_low, near_high,
                                                     resolution=24)
                axes_3d.plot_trisurf(points[:, 0], points[:, 1], triangles, points[:, 2],
                                     color="0.6", alpha=0.25, edgecolor="0.45",
                                     linewidth=0.2)
        if len(extent):
            centre = (extent.max(axis=0) + extent.min(axis=0)) / 2
            half = max(float(np.ptp(extent, axis=0).max()) / 2, 1e-3 * length)
            axes_3d.set_xlim(centre[0] - half, centre[0] + half)
            axes_3d.set_ylim(centre[1] - half, centre[1] + half)
            axes_3d.set_zlim(centre[2] - half, centre[2] + half)
        axes_3d.set_xlabel("x [m]")
        axes_3d.set_ylabel("y [m]")
        axes_3d.set_zlabel("z [m]")
        axes_3d.set_title("3D view, section frames of the last state", fontsize=9)
        drawn.suptitle(title)
        drawn.tight_layout()
        drawn.savefig(path, dpi=130)
    finally:
        plt.close(drawn)


def _draw_view_obstacles(axes, obstacles, i: int, j: int, low, high) -> None:
    """The obstacles seen along the remaining axis in the view of components (i, j)."""
    from matplotlib import patches

    style = {"facecolor": "0.8", "edgecolor": "0.4", "lw": 1, "zorder": 0}
    reach = 2 * float(np.linalg.norm(np.asarray(high) - np.asarray(low)))
    span = float(np.max(np.asarray(high) - np.asarray(low)))
    for obstacle in obstacles:
        shape = getattr(obstacle, "shape", "")
        if shape == "plane":
            normal = np.array([obstacle.normal[i], obstacle.normal[j]])
            size = float(np.linalg.norm(normal))
            if size < 0.05:  # the plane is seen edge-on in no direction of this view
                continue
            normal /= size
            point = np.array([obstacle.point[i], obstacle.point[j]])
            tangent = np.array([-normal[1], normal[0]])
            a, b = point - reach * tangent, point + reach * tangent
            depth = 0.05 * span * normal
            axes.add_patch(patches.Polygon([a, b, b - depth, a - depth], closed=True, **style))
            anchor = point
        elif shape == "sphere":
            anchor = np.array([obstacle.center[i], obstacle.center[j]])
            axes.add_patch(patches.Circle(anchor, obstacle.radius, **style))
        elif shape == "cylinder":
            anchor = np.array([obstacle.point[i], obstacle.point[j]])
            axis = np.array(obstacle.axis if obstacle.axis is not None else (0.0, 0.0, 1.0))
            along = np.array([axis[i], axis[j]])
            size = float(np.linalg.norm(along))
            if size < 1e-6:
                axes.add_patch(patches.Circle(anchor, obstacle.radius, **style))
            else:
                e = along / size
                half = reach if obstacle.length is None else obstacle.length / 2 * size
                side = obstacle.radius * np.array([-e[1], e[0]])
                axes.add_patch(patches.Polygon(
                    [anchor - half * e - side, anchor + half * e - side,
                     anchor + half * e + side, anchor - half * e + side], closed=True,
                    **style))
        elif shape == "box":
            corner = np.array([obstacle.min[i], obstacle.min[j]])
            size = np.array([obstacle.max[i], obstacle.max[j]]) - corner
            axes.add_patch(patches.Rectangle(corner, size[0], size[1], **style))
            anchor = corner + size / 2
        else:
            continue
        if getattr(obstacle, "name", ""):
            axes.annotate(obstacle.name, anchor, fontsize=7, color="0.3")


def _points(shape: dict) -> np.ndarray:
    return np.column_stack([shape["x"] + shape["u"], shape["v"], shape["w"]])


def plot_spatial_load_displacement(load_factors, tips: dict, path: str | Path,
                                   title: str) -> None:
    """Tip displacements (mm) and the tip rotation vector (rad, on its own axis)."""
    with figure(path, 1, 2, figsize=(10, 4)) as (_, (left, right)):
        for name in ("u", "v", "w"):
            left.plot(load_factors, np.asarray(tips[name]) * 1e3, marker="o", ms=3,
                      label=f"tip {name}")
        left.set_xlabel("load factor")
        left.set_ylabel("tip displacement [mm]")
        left.grid(alpha=0.3)
        left.legend()
        rotation = np.asarray(tips["rotation_vector"])
        for index, name in enumerate(("x", "y", "z")):
            right.plot(load_factors, rotation[:, index], marker="o", ms=3,
                       label=f"rotation vector {name}")
        right.set_xlabel("load factor")
        right.set_ylabel("tip rotation vector [rad]")
        right.grid(alpha=0.3)
        right.legend()
        left.set_title(title, fontsize=9)

"""The 1D rod beside the 3D solid (``fe-beam solid``, ``fe-beam compare``): the same
configuration run through `fe_beam.analyses.static.solve_static`, its backbone at the solid's
stations,
the distance between the two backbones and the rod as an XDMF polyline in the solid's
coordinates.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam.analyses.static import solve_static
from fe_beam.exports.outputs import atomic_write_text
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers.solid import evaluate_at_points

__all__ = ["backbone_distance", "planar_angle", "rod_backbone", "run_rod", "tip_distance",
           "tip_frame", "write_rod_xdmf"]


def rod_backbone(problem, stations) -> dict:
    """Rod displacement (u, v; a spatial rod's also w) at the stations x (exact finite-element
    values, collective)."""
    points = np.zeros((len(stations), 3))
    points[:, 0] = stations
    names = ("u", "v", "w") if getattr(problem, "spatial", False) else ("u", "v")
    data = {"x": [float(x) for x in stations]}
    for index, name in enumerate(names):
        values = evaluate_at_points(problem.w.sub(index).collapse(), points).ravel()
        data[name] = values.tolist()
    return data


def planar_angle(R) -> float:
    """The in-plane angle of a tip frame, atan2(R[1][0], R[0][0]): the angle of its tangent's
    projection on the x-y plane, as the 3D solid's tip ``theta`` (`SolidRun.tip`)."""
    return float(math.atan2(R[1][0], R[0][0]))


def tip_frame(rod_tip: dict, solid_tip: dict) -> dict:
    """The relative rotation R_rod^T R_solid of the solid's tip face against the rod's tip
    frame: its ``rotation_vector`` (in the rod's tip frame; its length is the angle, computed
    through a quaternion, so exact near 0, not arccos((tr - 1) / 2)) and ``angle`` [rad]. A
    planar rod's frame is the rotation by theta about z."""
    from scipy.spatial.transform import Rotation

    if "R" in rod_tip:
        rod = np.asarray(rod_tip["R"], dtype=float)
    else:
        c, s = math.cos(rod_tip["theta"]), math.sin(rod_tip["theta"])
        rod = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    relative = rod.T @ np.asarray(solid_tip["R"], dtype=float)
    vector = Rotation.from_matrix(relative).as_rotvec()
    return {"angle": float(np.linalg.norm(vector)), "rotation_vector": vector.tolist()}


def tip_distance(rod_tip: dict, solid_tip: dict) -> float:
    """|r_rod(L) - r_solid(L)| over the three components (a planar rod's w is 0)."""
    return float(math.sqrt(sum((rod_tip.get(k, 0.0) - solid_tip.get(k, 0.0)) ** 2
                               for k in ("u", "v", "w"))))


def run_rod(static: StaticConfig, stations, comm=MPI.COMM_WORLD, progress: bool = False) -> dict:
    """Run the 1D rod (`fe_beam.analyses.static.solve_static`, nothing written) and return plain
    data:
    status, steps (load factor, tip, tensions; with [[obstacles]] the contact entries), the
    final backbone at ``stations`` and, on rank
    0, the nodal shapes of every step (``frames``, for the rod XDMF). A spatial rod's tip is
    {u, v, w, R, rotation_vector, position} plus ``theta``, the in-plane angle of its frame
    (`planar_angle`: the solid's ``theta``, so that the planar columns stay filled)."""

    holder = {}

    def keep(problem, entry):
        holder["problem"] = problem

    result = solve_static(static, None, comm, progress=progress, on_step=keep)
    model = static.model
    data = {
        "law": model.options.law,
        "constraint": model.options.constraint,
        "E": model.material.E,
        "G": model.material.shear_modulus,
        "status": result.status,
        "message": result.message,
        "dofs": result.dofs,
        "wall_time_s": result.wall_time_s,
        "steps": [
            {k: s[k] for k in ("load_factor", "tip", "tensions", "pull_ins", "contact") if k in s}
            | ({"tip": s["tip"] | {"theta": planar_angle(s["tip"]["R"])}} if "R" in s["tip"]
               else {})
            for s in result.steps
        ],
        "backbone": rod_backbone(holder["problem"], stations) if "problem" in holder else None,
    }
    frames = [(s["load_factor"], shape) for s, (_, shape) in
              zip(result.steps, result.shapes, strict=False)] if comm.rank == 0 else []
    return data | {"frames": frames}


def backbone_distance(rod: dict, solid: dict) -> dict:
    """max over the stations x of |r_rod(x) - r_solid(x)| (deformed centroid positions at the
    same reference x, over the three components: a backbone without ``w`` lies in z = 0), with
    the x where it occurs."""
    ur, vr = np.asarray(rod["u"]), np.asarray(rod["v"])
    us, vs = np.asarray(solid["u"]), np.asarray(solid["v"])
    wr, ws = (np.asarray(b.get("w", np.zeros_like(ur)), dtype=float) for b in (rod, solid))
    distance = np.sqrt((ur - us) ** 2 + (vr - vs) ** 2 + (wr - ws) ** 2)
    k = int(np.argmax(distance))
    return {"max": float(distance[k]), "x": float(solid["x"][k])}


def write_rod_xdmf(path: Path, frames: list) -> None:
    """The rod as a polyline in 3D (x, 0, 0) with nodal ``displacement`` (u, v, 0) and ``theta``
    (a spatial rod: (u, v, w) and its ``rotation_vector``), one time per load factor: an XDMF
    file with inline data (no HDF5), written atomically."""
    if not frames:
        return
    x = np.asarray(frames[0][1]["x"], dtype=float)
    n = len(x)
    geometry = " ".join(f"{xi:.17g} 0 0" for xi in x)
    topology = " ".join(f"{i} {i + 1}" for i in range(n - 1))

    spatial = "theta_x" in frames[0][1]

    def grid(t, shape):
        u, v = (np.asarray(shape[k], dtype=float) for k in ("u", "v"))
        w = np.asarray(shape["w"], dtype=float) if spatial else np.zeros(n)
        displacement = " ".join(f"{a:.17g} {b:.17g} {c:.17g}" for a, b, c in zip(u, v, w,
                                                                                   strict=True))
        if spatial:  # the rotation vector
            vectors = np.column_stack([np.asarray(shape[k], dtype=float)
                                       for k in ("theta_x", "theta_y", "theta_z")])
            rotation = " ".join(f"{a:.17g}" for a in vectors.ravel())
            kind, size, name = "Vector", f"{n} 3", "rotation_vector"
        else:
            rotation = " ".join(f"{a:.17g}" for a in np.asarray(shape["theta"], dtype=float))
            kind, size, name = "Scalar", f"{n}", "theta"
        return (
            f'      <Grid Name="rod" GridType="Uniform">\n'
            f'        <Time Value="{t:.17g}"/>\n'
            f'        <Topology TopologyType="Polyline" NodesPerElement="2" '
            f'NumberOfElements="{n - 1}">\n'
            f'          <DataItem Dimensions="{n - 1} 2" NumberType="Int" Format="XML">'
            f"{topology}</DataItem>\n        </Topology>\n"
            f'        <Geometry GeometryType="XYZ">\n'
            f'          <DataItem Dimensions="{n} 3" Format="XML">{geometry}</DataItem>\n'
            f"        </Geometry>\n"
            f'        <Attribute Name="displacement" AttributeType="Vector" Center="Node">\n'
            f'          <DataItem Dimensions="{n} 3" Format="XML">{displacement}</DataItem>\n'
            f"        </Attribute>\n"
            f'        <Attribute Name="{name}" AttributeType="{kind}" Center="Node">\n'
            f'          <DataItem Dimensions="{size}" Format="XML">{rotation}</DataItem>\n'
            f"        </Attribute>\n      </Grid>\n"
        )

    zero = {k: np.zeros(n) for k in (("u", "v", "w", "theta_x", "theta_y", "theta_z")
                                     if spatial else ("u", "v", "theta"))}
    grids = [grid(0.0, zero)] + [grid(t, shape) for t, shape in frames]
    text = (
        '<?xml version="1.0"?>\n<Xdmf Version="3.0">\n  <Domain>\n'
        '    <Grid Name="rod" GridType="Collection" CollectionType="Temporal">\n'
        + "".join(grids)
        + "    </Grid>\n  </Domain>\n</Xdmf>\n"
    )
    atomic_write_text(path, text)

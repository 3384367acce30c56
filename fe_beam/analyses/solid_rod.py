"""The 1D rod beside the 3D solid (``fe-beam solid``, ``fe-beam compare``): the same
configuration run through `fe_beam.analyses.static.solve_static`, its backbone at the solid's
stations,
the distance between the two backbones and the rod as an XDMF polyline in the solid's
coordinates.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam.analyses.static import solve_static
from fe_beam.exports.outputs import atomic_write_text
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers.solid import evaluate_at_points

__all__ = ["backbone_distance", "rod_backbone", "run_rod", "write_rod_xdmf"]


def rod_backbone(problem, stations) -> dict:
    """Rod displacement (u, v) at the stations x (exact finite-element values, collective)."""
    points = np.zeros((len(stations), 3))
    points[:, 0] = stations
    u = evaluate_at_points(problem.w.sub(0).collapse(), points).ravel()
    v = evaluate_at_points(problem.w.sub(1).collapse(), points).ravel()
    return {"x": [float(x) for x in stations], "u": u.tolist(), "v": v.tolist()}


def run_rod(static: StaticConfig, stations, comm=MPI.COMM_WORLD, progress: bool = False) -> dict:
    """Run the 1D rod (`fe_beam.analyses.static.solve_static`, nothing written) and return plain
    data:
    status, steps (load factor, tip, tensions), the final backbone at ``stations`` and, on rank
    0, the nodal shapes of every step (``frames``, for the rod XDMF)."""

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
            {k: s[k] for k in ("load_factor", "tip", "tensions", "pull_ins") if k in s}
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
    """The rod as a polyline in 3D (x, 0, 0) with nodal ``displacement`` (u, v, 0) and ``theta``,
    one time per load factor: an XDMF file with inline data (no HDF5), written atomically."""
    if not frames:
        return
    x = np.asarray(frames[0][1]["x"], dtype=float)
    n = len(x)
    geometry = " ".join(f"{xi:.17g} 0 0" for xi in x)
    topology = " ".join(f"{i} {i + 1}" for i in range(n - 1))

    def grid(t, shape):
        u, v, theta = (np.asarray(shape[k], dtype=float) for k in ("u", "v", "theta"))
        displacement = " ".join(f"{a:.17g} {b:.17g} 0" for a, b in zip(u, v, strict=True))
        rotation = " ".join(f"{a:.17g}" for a in theta)
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
            f'        <Attribute Name="theta" AttributeType="Scalar" Center="Node">\n'
            f'          <DataItem Dimensions="{n}" Format="XML">{rotation}</DataItem>\n'
            f"        </Attribute>\n      </Grid>\n"
        )

    zero = {"x": x, "u": np.zeros(n), "v": np.zeros(n), "theta": np.zeros(n)}
    grids = [grid(0.0, zero)] + [grid(t, shape) for t, shape in frames]
    text = (
        '<?xml version="1.0"?>\n<Xdmf Version="3.0">\n  <Domain>\n'
        '    <Grid Name="rod" GridType="Collection" CollectionType="Temporal">\n'
        + "".join(grids)
        + "    </Grid>\n  </Domain>\n</Xdmf>\n"
    )
    atomic_write_text(path, text)

"""The hidden-style cases on the running FEniCSx stack, numbers to a JSON file (issue 13).

    python tests/cross_stack.py OUT.json [--only CASE ...] [--mesh MESH.json]

Run by ``tests/test_cross_stack.py`` on Debian's dolfinx 0.5.2 and on PyPI's 0.11, which compares
the two files: the inextensible elastica, a non-standard stocky cantilever (tip force and
moment), the tendon-driven finger with its inverse solve, and the 3D finger at a coarse mesh.
Each case is the ``fe-beam`` command on an inline configuration; every number of its
``summary.json`` except run statistics (wall times, iteration counts) is recorded.

gmsh differs between the stacks (Debian 4.8, PyPI 4.15) and so do its meshes: the 3D case meshes
the finger on the stack that runs first, stores the mesh (vertices, tetrahedra, tagged facets,
tendon chains) in ``--mesh`` and rebuilds the same gmsh model from it on both stacks, so both
solve on one mesh.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import tempfile
from pathlib import Path

ROD = """
[beam]
length = {length}
[section]
shape = "rectangle"
b = {b}
h = {h}
[material]
E = {E}
nu = {nu}
rho = 1000.0
[model]
law = "{law}"
constraint = "{constraint}"
[mesh]
elements = {elements}
degree = {degree}
[supports]
x0 = "clamped"
xL = "free"
[loads]
tip_force = [{fx}, {fy}]
tip_moment = {moment}
steps = {steps}
[output]
xdmf = false
plots = false
"""

FINGER = """
[beam]
length = 0.08
[section]
shape = "rectangle"
b = 0.015
h = 0.018
h_tip = 0.009
[material]
E = 0.9e6
nu = 0.42
rho = 1070.0
[model]
law = "nonstandard"
[mesh]
elements = 24
degree = 2
[[tendons]]
name = "flexor"
offset_base = 0.006
offset_tip = 0.003
tension = 1.3
[loads]
steps = 6
[inverse]
tip_angle = 0.35
[output]
xdmf = false
plots = false
"""

SOLID = """
[beam]
length = 0.1
[section]
shape = "rectangle"
b = 0.02
h = 0.02
h_tip = 0.012
[material]
E = 0.5e6
nu = 0.4
rho = 1070.0
[model]
law = "nonstandard"
[mesh]
elements = 20
degree = 2
[[tendons]]
name = "flexor"
offset_base = 0.007
offset_tip = 0.004
tension = 0.8
[loads]
steps = 3
[solid]
material = "neo-hookean"
formulation = "displacement"
order = 1
mesh_size = 0.01
solver = "mumps"
anchor = "face"
[output]
xdmf = false
plots = false
"""

# name: (fe-beam command, configuration, dimension)
CASES = {
    "elastica_inextensible": ("static", ROD.format(
        length=1.3, b=0.012, h=0.008, E=2.1e11, nu=0.3, law="reissner",
        constraint="inextensible-unshearable", elements=16, degree=2, fx=0.0, fy=-700.0,
        moment=0.0, steps=6), 1),
    "nonstandard_cantilever": ("static", ROD.format(
        length=0.6, b=0.05, h=0.08, E=3.0e6, nu=0.45, law="nonstandard", constraint="none",
        elements=24, degree=1, fx=150.0, fy=-900.0, moment=-40.0, steps=5), 1),
    "finger": ("finger", FINGER, 1),
    "solid_finger": ("solid", SOLID, 3),
}

# run statistics, and the run-time certificates' measured values (round-off sized on a
# converged run; their verdict is compared through the status and exit code)
SKIPPED_KEYS = ("time", "iteration", "wall", "seconds", "dofs", "version", "checks",
                "certificates")


def numbers(tree, path: str = "") -> dict[str, float]:
    """Flat {path: value} of the numbers in a summary, run statistics left out."""
    if isinstance(tree, dict):
        found = {}
        for key, value in tree.items():
            if not any(word in str(key) for word in SKIPPED_KEYS):
                found |= numbers(value, f"{path}/{key}")
        return found
    if isinstance(tree, list):
        found = {}
        for index, value in enumerate(tree):
            found |= numbers(value, f"{path}/{index}")
        return found
    if isinstance(tree, (int, float)) and not isinstance(tree, bool) and math.isfinite(tree):
        return {path: float(tree)}
    return {}


def dump_mesh(finger, path: Path) -> None:
    """Vertices, tetrahedra, clamp and tip triangles and tendon chains of a serial finger mesh."""
    from fe_beam.fem import compat
    from fe_beam.fem.solid.geometry import CLAMP_TAG, TIP_TAG

    msh = finger.mesh
    x = msh.geometry.x
    cells = compat.geometry_cell_nodes(msh)[: msh.topology.index_map(3).size_local]
    index = {tuple(point): i for i, point in enumerate(x.tolist())}
    facets = {}
    for tag in (CLAMP_TAG, TIP_TAG):
        triangles = compat.facet_vertex_coordinates(msh, finger.facet_tags.find(tag))
        facets[str(tag)] = [[index[tuple(p)] for p in t.tolist()] for t in triangles]
    path.write_text(json.dumps({"x": x.tolist(), "cells": cells.tolist(), "facets": facets,
                                "chains": [c.tolist() for c in finger.tendon_chains]}))


def mesh_from_file(path: Path):
    """A ``create_finger_mesh`` that rebuilds the stored mesh as a discrete gmsh model."""
    import numpy as np
    from mpi4py import MPI

    from fe_beam.fem import compat
    from fe_beam.fem.solid.geometry import FingerMesh

    data = json.loads(path.read_text())

    def create(geometry, sizes, comm=MPI.COMM_WORLD, rank=0, verbose=False):
        import gmsh

        if comm.rank != rank:
            msh, cell_tags, facet_tags = compat.gmsh_model_to_mesh(None, comm, rank, 3)
        else:
            compat.gmsh_initialize()
            try:
                gmsh.option.setNumber("General.Terminal", 0)
                gmsh.model.add("stored")
                x = np.asarray(data["x"], dtype=float)
                volume = gmsh.model.addDiscreteEntity(3)
                gmsh.model.mesh.addNodes(3, volume, np.arange(1, len(x) + 1), x.ravel())
                cells = np.asarray(data["cells"]) + 1
                gmsh.model.mesh.addElementsByType(volume, 4, [], cells.ravel())
                gmsh.model.addPhysicalGroup(3, [volume], 1)
                for tag, triangles in data["facets"].items():
                    surface = gmsh.model.addDiscreteEntity(2)
                    gmsh.model.mesh.addElementsByType(
                        surface, 2, [], (np.asarray(triangles) + 1).ravel())
                    gmsh.model.addPhysicalGroup(2, [surface], int(tag))
                msh, cell_tags, facet_tags = compat.gmsh_model_to_mesh(gmsh.model, comm, rank, 3)
            finally:
                gmsh.finalize()
        chains = [np.asarray(c, dtype=float) for c in data["chains"]]
        return FingerMesh(msh, cell_tags, facet_tags, geometry, sizes, chains)

    return create


def use_stored_mesh(path: Path) -> None:
    """Make every fe_beam module that meshes the finger use the mesh in ``path`` (written by
    this stack's gmsh first when the file does not exist)."""
    import importlib
    import pkgutil

    import fe_beam
    from fe_beam.fem.solid import geometry

    for module in pkgutil.walk_packages(fe_beam.__path__, "fe_beam."):
        importlib.import_module(module.name)
    original = geometry.create_finger_mesh
    if not path.exists():
        def first(geometry_, sizes, *args, **kwargs):
            finger = original(geometry_, sizes, *args, **kwargs)
            dump_mesh(finger, path)
            return mesh_from_file(path)(geometry_, sizes, *args, **kwargs)
        replacement = first
    else:
        replacement = mesh_from_file(path)
    for name, module in list(sys.modules.items()):
        if name.startswith("fe_beam") and getattr(module, "create_finger_mesh", None) is original:
            module.create_finger_mesh = replacement


def run_case(name: str, folder: Path) -> dict:
    from fe_beam.cli import main
    from fe_beam.fem import compat

    command, config, dimension = CASES[name]
    path = folder / f"{name}.toml"
    path.write_text(config)
    out = folder / name
    code = main([command, str(path), "--out", str(out), "--quiet"])
    summary = json.loads((out / "summary.json").read_text())
    values = numbers(summary)
    # a strain a constraint holds at zero is round-off (a few 1e-15, differing between two
    # identical runs of different builds), not a result: not compared
    constraint = re.search(r'constraint = "([a-z-]+)"', config)
    constrained = {"inextensible": "max_abs_eps", "unshearable": "max_abs_gamma"}
    for word, key in constrained.items():
        if constraint and word in constraint.group(1):
            values.pop(f"/strain_range/{key}", None)
    return {"exit": code, "status": summary.get("status"), "dimension": dimension,
            "dolfinx": compat.DOLFINX_VERSION, "values": values}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--only", nargs="*", choices=sorted(CASES), default=None)
    parser.add_argument("--mesh", type=Path, default=None,
                        help="the 3D case's mesh: read, or written first when it does not exist")
    args = parser.parse_args(argv)
    if args.mesh is not None:
        use_stored_mesh(args.mesh)
    results = {}
    with tempfile.TemporaryDirectory() as folder:
        for name in args.only or CASES:
            results[name] = run_case(name, Path(folder))
    args.out.write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

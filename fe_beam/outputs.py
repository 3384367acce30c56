"""Result writers: XDMF for ParaView, summary.json and CSV (atomic), PNG plots.

Writers take Functions/problems and are called from the driver between solves; solvers never
write files. Text files are replaced atomically (write to a temporary file, then rename), so an
interrupted run always leaves readable results of the last converged step.
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

from fe_beam import compat

__all__ = [
    "BeamXDMFWriter",
    "atomic_write_json",
    "atomic_write_text",
    "gather_line",
    "plot_deformed_shapes",
    "plot_load_displacement",
    "write_csv",
]


def atomic_write_text(path: str | Path, text: str) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(handle, "w") as stream:
            stream.write(text)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def atomic_write_json(path: str | Path, data) -> None:
    atomic_write_text(path, json.dumps(data, indent=2, default=_jsonable) + "\n")


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


class BeamXDMFWriter:
    """XDMF time series of a `BeamProblem`: u, v, theta and a displacement vector (P1, at the
    vertices; "Warp By Vector" in ParaView shows the deformed beam), and the strains eps, gamma,
    kappa and resultants N, T, M, axial force (DG0, at element midpoints)."""

    def __init__(self, problem, path: str | Path | None):
        self.problem = problem
        mesh = problem.mesh
        cell = mesh.ufl_cell()
        scalar = compat.function_space(mesh, ufl.FiniteElement("Lagrange", cell, 1))
        vector = compat.function_space(mesh, ufl.VectorElement("Lagrange", cell, 1, dim=2))
        cellwise = compat.function_space(mesh, ufl.FiniteElement("DG", cell, 0))
        u, v, theta, _ = problem.fields()
        plan = [
            ("u", u, scalar),
            ("v", v, scalar),
            ("theta", theta, scalar),
            ("displacement", ufl.as_vector([u, v]), vector),
        ]
        plan += [(name, expr, cellwise) for name, expr in problem.output_expressions().items()]
        self.functions = {}
        self._expressions = []
        for name, expr, space in plan:
            function = fem.Function(space, name=name)
            self.functions[name] = function
            self._expressions.append((function, compat.interpolation_expression(expr, space)))
        self._file = None
        if path is not None:
            self._file = compat.XDMFFile(mesh.comm, str(path), "w")
            self._file.write_mesh(mesh)

    def update(self) -> None:
        for function, expression in self._expressions:
            function.interpolate(expression)

    def write(self, time: float) -> None:
        self.update()
        if self._file is not None:
            for function in self.functions.values():
                self._file.write_function(function, time)

    def vertex_values(self) -> dict | None:
        """Current nodal u, v, theta and x, plus element-midpoint profiles under "cells"
        (x, eps, gamma, kappa, N, T, M, axial_force), gathered on rank 0 (None elsewhere)."""
        self.update()
        nodal = gather_line(self.problem, {k: self.functions[k] for k in ("u", "v", "theta")})
        cellwise = gather_line(
            self.problem,
            {
                k: f
                for k, f in self.functions.items()
                if k not in ("u", "v", "theta", "displacement")
            },
        )
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
    import matplotlib.pyplot as plt

    return plt


def plot_deformed_shapes(
    shapes: list[tuple[str, dict]],
    path: str | Path,
    title: str,
    length: float,
    reference: list[tuple[str, float, float]] = (),
) -> None:
    """Deformed axes (x + u, y + v) with labels; ``reference`` adds marked tip points."""
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(7, 5))
    colours = plt.cm.viridis(np.linspace(0, 0.9, max(len(shapes), 1)))
    axes.plot([0, length], [0, 0], color="0.7", lw=1, ls="--", label="undeformed")
    for (label, shape), colour in zip(shapes, colours, strict=False):
        axes.plot(shape["x"] + shape["u"], shape["v"], color=colour, lw=1.8, label=label)
    for i, (label, x, y) in enumerate(reference):
        axes.plot(x, y, "kx", ms=7, label=label if i == 0 else None)
    # true shape (equal scales) in an axes that keeps its size: the legend fits inside it
    axes.set_aspect("equal", adjustable="datalim")
    axes.set_xlabel("x + u [m]")
    axes.set_ylabel("y + v [m]")
    axes.set_title(title)
    axes.grid(alpha=0.3)
    from fe_beam.plotting import legend_inside

    legend_inside(axes, fontsize=7)
    figure.savefig(path, dpi=130)
    plt.close(figure)


def plot_load_displacement(load_factors, tips: dict, path: str | Path, title: str) -> None:
    plt = _pyplot()
    figure, axes = plt.subplots(figsize=(6, 4))
    for name, values in tips.items():
        axes.plot(load_factors, values, marker="o", ms=3, label=name)
    axes.set_xlabel("load factor")
    axes.set_ylabel("tip value [m] / [rad]")
    axes.set_title(title)
    axes.grid(alpha=0.3)
    axes.legend()
    figure.tight_layout()
    figure.savefig(path, dpi=130)
    plt.close(figure)

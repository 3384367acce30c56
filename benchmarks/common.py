"""Helpers shared by the benchmark scripts: quiet set-up, the elastica cantilever, tip errors,
timing, a plain-text table and the JSON results file (``results/benchmarks/<name>.json``)."""

from __future__ import annotations

import datetime
import json
import math
import os
import platform
import statistics
import time
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("FE_BEAM_PROGRESS", "0")

from fe_beam.cli import quiet_jit_logging  # noqa: E402

quiet_jit_logging()

import numpy as np  # noqa: E402
from petsc4py import PETSc  # noqa: E402

from fe_beam import (  # noqa: E402
    BeamModel,
    Discretisation,
    Loads,
    LoadStepping,
    Material,
    ModelOptions,
    Section,
    SolverSettings,
    Supports,
)
from fe_beam.analytic import ElasticaTip  # noqa: E402
from fe_beam.model.studies import StaticConfig  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "results" / "benchmarks"

# The cantilever of the tests (tests/beam_cases.py): L = 1 m, square h = 1 cm, E = 10 MPa.
LENGTH, H, E, NU = 1.0, 0.01, 1.0e7, 0.3
EI = E * H**4 / 12


def cantilever(k: float, elements: int, degree: int = 2, law: str = "reissner",
               constraint: str = "inextensible-unshearable") -> BeamModel:
    """Clamped-free beam with a dead downward tip load P = k EI / L^2 at load factor 1."""
    return BeamModel(
        LENGTH, Section("rectangle", {"b": H, "h": H}), Material(E, nu=NU),
        ModelOptions(law, constraint), Discretisation(elements, degree),
        Supports("clamped", "free"), Loads(tip_force=(0.0, -k * EI / LENGTH**2)),
    )


def static_config(model: BeamModel, steps: int, solver: SolverSettings | None = None,
                  **stepping) -> StaticConfig:
    return StaticConfig(model, solver or SolverSettings(), LoadStepping(steps=steps, **stepping))


def tip_errors(u: float, v: float, theta: float, exact: ElasticaTip,
               length: float = LENGTH) -> dict:
    """Errors of a tip (u, v, theta) vs the elastica (load downward, beam along +x).

    ``position`` is the distance between the computed and the exact tip point over L.
    """
    shortening, deflection, rotation = -u / length, -v / length, -theta
    errors = {
        "shortening": abs(shortening - exact.shortening),
        "deflection": abs(deflection - exact.deflection),
        "rotation": abs(rotation - exact.rotation),
    }
    errors["position"] = math.hypot(errors["shortening"], errors["deflection"])
    return errors


def timed(function: Callable[[], object]) -> tuple[float, object]:
    started = time.perf_counter()
    value = function()
    return time.perf_counter() - started, value


def stats(times: list[float]) -> dict:
    return {"min_s": min(times), "median_s": statistics.median(times), "all_s": times}


def fit_exponent(sizes, values) -> float:
    """Least-squares slope of log(values) against log(sizes)."""
    return float(np.polyfit(np.log(np.asarray(sizes, float)), np.log(np.asarray(values, float)),
                            1)[0])


def table(headers: list[str], rows: list[list]) -> str:
    cells = [[_cell(c) for c in row] for row in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) for i, h in enumerate(headers)]
    lines = ["  ".join(h.rjust(w) for h, w in zip(headers, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in cells]
    return "\n".join(lines)


def _cell(value) -> str:
    if isinstance(value, float):
        return f"{value:.3g}" if abs(value) >= 1e-3 or value == 0 else f"{value:.2e}"
    return str(value)


def forget_petsc_options(prefixes: tuple[str, ...] = ("fe_beam_", "dolfinx_solve_")) -> int:
    """Delete PETSc options left in the global database by earlier solvers; returns how many.

    fe_beam's `SNESSolver` writes its options under a prefix and never removes them, so a later
    solver with the same prefix inherits options it does not set itself (e.g. a "lu" solver after
    a "mumps" one keeps pc_factor_mat_solver_type = mumps); `compat.solve_linear` (dolfinx's
    LinearProblem) adds 3 options under a new prefix per call, and PETSc's database holds 512
    options at most. Benchmarks that build many solvers in one process call this after each.
    """
    options = PETSc.Options()
    names = [name for name in options.getAll() if name.startswith(prefixes)]
    for name in names:
        options.delValue(name)
    return len(names)


def machine() -> dict:
    import dolfinx

    return {
        "date": datetime.date.today().isoformat(),
        "cpus": os.cpu_count(),
        "load_average": os.getloadavg(),
        "python": platform.python_version(),
        "dolfinx": dolfinx.__version__,
        "numpy": np.__version__,
    }


def write_results(name: str, data: dict) -> Path:
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps({"machine": machine()} | data, indent=1, default=float) + "\n")
    return path

"""Path following with critical points and branch switching: the engine of ``fe-beam path``
(docs/theory.md, Critical points and branch switching)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from fe_beam.continuation import ArcLength, ContinuationFailed
from fe_beam.critical import (
    CriticalPoint,
    locate_bifurcation,
    locate_limit,
    spectrum,
    switch_branch,
)

__all__ = ["PathResult", "follow_path"]


@dataclass
class PathResult:
    """Points (``path``: dicts {load_factor, tip, stable, energy_decreasing_directions,
    branch}), located critical points, and, on failure, the reason."""

    path: list[dict] = field(default_factory=list)
    critical_points: list[CriticalPoint] = field(default_factory=list)
    status: str = "running"
    message: str = ""


def follow_path(run, settings: ArcLength, branch_switch: str = "none", tol: float = 1e-6,
                on_point=None, switch_size: float | None = None) -> PathResult:
    """Arc-length continuation of ``run`` (a `fe_beam.static.StaticContinuation` at a converged
    state) one step at a time, locating every limit point (sign change of dlambda/ds) and
    bifurcation point (change of the count of energy-decreasing directions) to ``tol`` in the
    load factor. ``branch_switch``: "none" (stay on the path), "positive" / "negative" (at the
    first bifurcation, switch onto the bifurcated branch along + / - its critical mode and
    follow it). ``on_point(record, result)`` after every accepted point. Stops at
    ``settings.max_steps`` points or beyond ``settings.max_load_factor``; a failure sets
    status "failed" with the last good state kept."""
    engine = run.engine()
    engine.parameter = float(run.load_factor)
    engine.prepare_arc_length(settings)
    result = PathResult()
    one = replace(settings, max_steps=1)
    branch = 0

    def record(point_parameter: float) -> dict:
        found = spectrum(run)
        entry = {
            "load_factor": float(point_parameter),
            "tip": run.problem.end_values("xL"),
            "stable": None if found is None else found.unstable == 0,
            "energy_decreasing_directions": None if found is None else found.unstable,
            "branch": branch,
        }
        result.path.append(entry)
        if on_point is not None:
            on_point(entry, result)
        return entry

    last = record(engine.parameter)
    switched = False
    try:
        while len(result.path) <= settings.max_steps:
            before = engine.snapshot()
            points = engine.arc_length_path(one)
            point = points[-1]
            run.load_factor = engine.parameter
            previous_count = last["energy_decreasing_directions"]
            entry_after = engine.snapshot()
            found = []
            if (before.tangent is not None and point.tangent_parameter is not None
                    and before.tangent[1] * point.tangent_parameter < 0):
                found.append(locate_limit(run, engine, before, point.arc_length, tol))
            current = spectrum(run)
            if (current is not None and previous_count is not None
                    and current.unstable != previous_count and not found):
                found.append(locate_bifurcation(run, engine, before, entry_after,
                                                previous_count, tol))
            result.critical_points.extend(found)
            last = record(engine.parameter)
            beyond = abs(engine.parameter) >= settings.max_load_factor * (1 - 1e-12)
            bifurcations = [c for c in found if c.kind == "bifurcation"]
            if bifurcations and branch_switch in ("positive", "negative") and not switched:
                switched = True
                branch += 1
                size = switch_size or (engine.arc_length or 0.05)
                switch_branch(run, engine, bifurcations[0], size,
                              1 if branch_switch == "positive" else -1)
                last = record(engine.parameter)
                continue
            if beyond or (points and math.isnan(point.load_factor)):
                break
        result.status = "converged"
    except ContinuationFailed as failure:
        run.load_factor = engine.parameter
        result.status, result.message = "failed", str(failure)
    return result

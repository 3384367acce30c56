"""Path following with critical points and branch switching: the engine of ``fe-beam path``
(docs/theory.md, Critical points and branch switching)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from fe_beam import exports, runctl
from fe_beam.analyses.certificates import equilibrium_entry
from fe_beam.analyses.result import Report, Result, exit_code
from fe_beam.analyses.solid import SolidRun, check_solid_work
from fe_beam.analyses.static import (
    STABILITY_MAX_DOFS,
    StaticContinuation,
    beam_dofs_estimate,
    check_beam_work,
    contact_checks,
    contact_columns,
    structure_columns,
    structure_record,
)
from fe_beam.config.path import parse_path
from fe_beam.errors import ConfigError
from fe_beam.exports.obstacles import bounding_box, write_obstacle_surfaces
from fe_beam.exports.outputs import BeamXDMFWriter, figure, plot_deformed_shapes
from fe_beam.exports.solid import DisplacementXDMF
from fe_beam.exports.spatial import SpatialXDMFWriter, plot_spatial_shapes
from fe_beam.fem import compat
from fe_beam.model.loads import given
from fe_beam.model.obstacles import ContactSettings
from fe_beam.progress import ProgressBar
from fe_beam.solvers.continuation import (
    ArcLength,
    Continuation,
    ContinuationFailed,
)
from fe_beam.solvers.critical import (
    CriticalPoint,
    locate_bifurcation,
    locate_limit,
    spectrum,
    switch_branch,
)
from fe_beam.solvers.inertia import solid_unstable_count

__all__ = ["run", "PathResult", "follow_path", "point_force_control"]


@dataclass
class PathResult:
    """Points (``path``: dicts {load_factor, tip, stable, energy_decreasing_directions,
    branch}), located critical points, and, on failure, the reason."""

    path: list[dict] = field(default_factory=list)
    critical_points: list[CriticalPoint] = field(default_factory=list)
    status: str = "running"
    message: str = ""
    #: what the path could not decide (e.g. a stability change across a contact change)
    notes: list[str] = field(default_factory=list)


def follow_path(run, settings: ArcLength, branch_switch: str = "none", tol: float = 1e-6,
                on_point=None, switch_size: float | None = None) -> PathResult:
    """Arc-length continuation of ``run`` (a `fe_beam.analyses.static.StaticContinuation` at a
    converged
    state) one step at a time, locating every limit point (sign change of dlambda/ds) and
    bifurcation point (change of the count of energy-decreasing directions) to ``tol`` in the
    load factor. ``branch_switch``: "none" (stay on the path), "positive" / "negative" (at the
    first bifurcation, switch onto the bifurcated branch along + / - its critical mode and
    follow it; "both": the positive branch, then the negative one, with ``max_steps`` more
    points). ``on_point(record, result)`` after every accepted point. Stops at
    ``settings.max_steps`` points or beyond ``settings.max_load_factor``; a failure sets
    status "failed" with the last good state kept.

    With obstacles (``run.contact``) every point records its ``contact`` (`fe_beam.fem.contact.
    ContactSet.summary`); a change of the unstable count across a step whose contact state
    changed is not located as a bifurcation (the penalised contact stiffness of the points
    that came into or out of contact changes the count too): a note says so."""
    engine = run.engine()
    engine.parameter = float(run.load_factor)
    engine.prepare_arc_length(settings)
    result = PathResult()
    one = replace(settings, max_steps=1)
    contact = getattr(run, "contact", None)
    branch = 0

    def record(point_parameter: float) -> dict:
        found = spectrum(run)
        entry = {
            "load_factor": float(point_parameter),
            "tip": run.problem.end_values("xL"),
            "stable": None if found is None else found.unstable == 0,
            "energy_decreasing_directions": None if found is None else found.unstable,
            "branch": branch,
        } | structure_record(run.problem)
        if contact is not None:
            entry["contact"] = contact.summary()
        result.path.append(entry)
        if on_point is not None:
            on_point(entry, result)
        return entry

    last = record(engine.parameter)
    switched = False
    pending = []  # "both": (bifurcation, size) whose negative branch follows the positive one
    limit = settings.max_steps
    try:
        while True:
            while len(result.path) <= limit:
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
                changed = (current is not None and previous_count is not None
                           and current.unstable != previous_count and not found)
                if changed and contact is not None and contact.changed_between(
                        before.extra, entry_after.extra):
                    changed = False
                    result.notes.append(
                        f"the count of energy-decreasing directions changed from "
                        f"{previous_count} to {current.unstable} between load factors "
                        f"{before.parameter:.6g} and {engine.parameter:.6g}, where the contact "
                        "state changed too: not located as a bifurcation")
                if changed:
                    # a step may cross several: each change of the count is located
                    for crossing in range(abs(current.unstable - previous_count)):
                        found.append(locate_bifurcation(run, engine, before, entry_after,
                                                        previous_count, tol,
                                                        crossing=crossing))
                result.critical_points.extend(found)
                last = record(engine.parameter)
                beyond = abs(engine.parameter) >= settings.max_load_factor * (1 - 1e-12)
                bifurcations = [c for c in found if c.kind == "bifurcation"]
                if (bifurcations and branch_switch in ("positive", "negative", "both")
                        and not switched):
                    switched = True
                    branch += 1
                    size = switch_size or (engine.arc_length or 0.05)
                    if branch_switch == "both":
                        pending.append((bifurcations[0], size))
                    switch_branch(run, engine, bifurcations[0], size,
                                  -1 if branch_switch == "negative" else 1)
                    last = record(engine.parameter)
                    continue
                if beyond or (points and math.isnan(point.load_factor)):
                    break
            if not pending:
                break
            # "both": the branch along - the critical mode, with max_steps points of its own
            critical, size = pending.pop()
            branch += 1
            switch_branch(run, engine, critical, size, -1)
            last = record(engine.parameter)
            limit = len(result.path) + settings.max_steps
        result.status = "converged"
    except ContinuationFailed as failure:
        run.load_factor = engine.parameter
        result.status, result.message = "failed", str(failure)
    return result


def point_force_control(run, static, progress: bool = False, prestate: bool = True):
    """Make the load factor of ``run`` (a `fe_beam.analyses.static.StaticContinuation`) scale the
    point
    forces alone: every other load, tendon tension and prescribed end value is first reached by
    load stepping with the point forces at zero (``prestate``; skipped when there is nothing
    else, or when the caller has put ``run`` at that state itself) and then held in full.
    Installs the engine (``run.engine()``) at load factor 0 and returns the setter
    ``push(factor)`` (``[path] parameter = "point_force"``; docs/theory.md, Snap-through)."""

    loads = static.model.loads
    nodal = run.problem.point_force_fields
    full = [f.x.array.copy() for f in nodal]

    def forces(factor: float) -> None:
        for function, value in zip(nodal, full, strict=True):
            function.x.array[:] = factor * value

    def hold(factor: float) -> None:  # everything else at `factor`, the point forces at 0
        run._set_load_factor(factor)
        forces(0.0)

    def push(factor: float) -> None:  # everything else in full, the point forces at factor
        run._set_load_factor(1.0)
        forces(factor)

    supports = static.model.supports
    others = (any(t.tension for t in static.tendons or ()) or given(loads, ("point_forces",))
              or any(supports.prescribed_x0.values()) or any(supports.prescribed_xL.values()))
    if prestate and others:  # the state without the point forces, from the undeformed one
        Continuation(run.adapter(hold, checked=False), 0.0).load_control(
            1.0, static.stepping, progress=progress, label="path pre-state")
    run._engine = Continuation(run.adapter(push), 0.0)
    run.load_factor = 0.0
    push(0.0)
    return push


# --- the command `fe-beam path` -----------------------------------------------------------------
PATH_CSV = ("index", "branch", "load_factor", "tension", "tip_u", "tip_v", "tip_theta", "stable",
            "energy_decreasing_directions")
#: path.csv of a spatial rod: w and the rotation vector where the planar rod has theta
SPATIAL_PATH_CSV = ("index", "branch", "load_factor", "tension", "tip_u", "tip_v", "tip_w",
                    "tip_rotation_x", "tip_rotation_y", "tip_rotation_z", "stable",
                    "energy_decreasing_directions")


def _tip_value(record: dict, name: str):
    tip = record["tip"]
    if name.startswith("rotation_"):
        return tip["rotation_vector"]["xyz".index(name[-1])]
    return tip[name]


def _path_plot(out, summary: dict) -> None:
    """Load factor vs tip u, v, theta: stable solid, unstable dashed, critical points marked."""

    points = summary.get("path") or []
    if not points:
        return
    where = "tip"
    if all("point" in p for p in points) and summary.get("parameter") != "point_force":
        # a structure: where its first point force pushes (x on the mesh coordinate)
        where = "point"
        forks = summary.get("critical_points", [])
        if any("point" not in c for c in forks):
            where = "tip"
        else:
            points = [dict(p, tip=p["point"]) for p in points]
            summary = dict(summary, critical_points=[dict(c, tip=c["point"]) for c in forks])
    spatial = "w" in points[0]["tip"]
    keys = ("u", "v", "w") if spatial else ("u", "v", "theta")
    name = "load point" if where == "point" else "tip"
    labels = tuple(f"{name} {k} [{'rad' if k == 'theta' else 'm'}]" for k in keys)
    with figure(out / "path.png", 1, 3, figsize=(11, 3.6)) as (_, axes):
        for ax, key, label in zip(axes, keys, labels, strict=True):
            forks = [c for c in summary.get("critical_points", [])
                     if c["kind"] == "bifurcation"]
            for a, b in zip(points[:-1], points[1:], strict=True):
                if a["branch"] != b["branch"]:
                    if not forks:
                        continue
                    # a switched branch starts at the bifurcation it left
                    a = {"tip": forks[0]["tip"], "load_factor": forks[0]["load_factor"],
                         "stable": b["stable"]}
                unstable = a["stable"] is False or b["stable"] is False
                ax.plot([a["tip"][key], b["tip"][key]], [a["load_factor"], b["load_factor"]],
                        "--" if unstable else "-", color=f"C{b['branch'] % 10}", lw=1.3)
            for kind, marker in (("limit", "s"), ("bifurcation", "o")):
                found = [c for c in summary.get("critical_points", []) if c["kind"] == kind]
                if found:
                    ax.plot([c["tip"][key] for c in found], [c["load_factor"] for c in found],
                            marker, color="k", ms=5, ls="none", label=kind)
            ax.set_xlabel(label)
            ax.set_ylabel("load factor")
            ax.grid(alpha=0.3)
        axes[0].plot([], [], "-", color="0.3", label="stable")
        axes[0].plot([], [], "--", color="0.3", label="unstable")
        axes[0].legend(fontsize=7)


def _critical_summary(point, problem, at: float | None) -> dict:
    """A critical point's summary; on a point-force path also the ``point`` {x, u, v, theta}
    where the force pushes (the path's own "point"; the clamped tip of a snap-through beam
    does not move), read from the point's state once (collective)."""
    entry = point.summary()
    if at is None or point.snapshot is None:
        return entry
    values = getattr(point, "_point_values", None)
    if values is None:
        w = compat.local_array(problem.w)
        saved = w.copy()
        try:
            w[:] = point.snapshot.state
            values = {"x": at, **problem.point_values(at)}
        finally:
            w[:] = saved
        point._point_values = values
    entry["point"] = values
    return entry


def _interrupted(summary: dict, stop) -> None:
    """The summary's status and message of a path stopped by a signal after its last point."""
    last = summary["path"][-1]["load_factor"] if summary["path"] else 0.0
    status = stop.stopped(f"load factor {last:.4g}", f"at load factor {last:.6g}")
    summary["status"], summary["message"] = status["status"], status["message"]


def _path_files(out, writer, summary: dict, started: float, plots: bool, comm,
                spatial: bool | None = None, extra_columns=(), draw=None):
    """The export objects of a path run (rod or solid), started: path.xdmf (``writer``, by
    point index), path.csv (``extra_columns`` after the path's: e.g. the contact's),
    summary.json and path.png (and ``draw(summary)``'s pictures), each after every point;
    nothing but the XDMF writer when ``out`` is None. Returns (files, content): ``content()``
    is the summary with its wall time brought up to date."""
    import time


    if spatial is None:  # the solid: planar CSV
        spatial = getattr(getattr(writer, "problem", None), "spatial", False)
    columns = [exports.Column(name, (lambda r, n=name: r[n] if n[:4] != "tip_"
                                     else _tip_value(r, n[4:])))
               for name in (SPATIAL_PATH_CSV if spatial else PATH_CSV)] + list(extra_columns)

    def pictures(summary: dict) -> None:
        if plots:
            _path_plot(out, summary)
            if draw is not None:
                draw(summary)

    def content() -> dict:
        summary["wall_time_s"] = time.perf_counter() - started
        return summary

    files = exports.Exports(
        ([exports.XDMFExport(writer, "index")] if writer is not None else [])
        + ([exports.CSVExport(out / "path.csv", columns),
            exports.SummaryExport(out / "summary.json", content),
            exports.PlotExport(pictures)]
           if out is not None else []), comm, throttle=False)
    files.start(content())
    return files, content


def run_path(config: dict, out, comm=None, progress: bool = True) -> dict:
    """`follow_configured_path` of ``config`` parsed (for scripts that hold the TOML dict)."""
    return follow_configured_path(parse_path(config), out, comm, progress)


def follow_configured_path(parsed, out, comm=None, progress: bool = True) -> dict:
    """`fe-beam path` on a validated configuration (rod or finger): arc-length continuation
    with critical points (`follow_path`); writes summary.json (after every point), path.csv,
    path.png, path.xdmf (states) and critical_modes.xdmf into ``out`` and returns the summary.
    Status "converged" (max_load_factor or max_steps reached), "failed" (exit 3: the last good
    point kept, the reason in ``message``) or "interrupted" (re-raised)."""
    import time

    from mpi4py import MPI


    comm = comm or MPI.COMM_WORLD
    started = time.perf_counter()
    kind, static, settings = parsed
    if kind == "solid":
        return _run_solid_path(static, settings, out, comm, progress, started)
    notes = check_beam_work(static, settings.max_steps, comm, " of path following",
                            quiet=out is None)
    loads = static.model.loads
    dofs = beam_dofs_estimate(static)
    if comm.size > 1 or dofs > STABILITY_MAX_DOFS:
        why = (f"on {comm.size} MPI ranks" if comm.size > 1 else
               f"with {dofs} dofs (more than {STABILITY_MAX_DOFS})")
        if settings.branch_switch != "none":
            raise ConfigError(f"[path] branch_switch = {settings.branch_switch!r}: the critical "
                              f"mode is not computed {why} (the stability is a sparse count "
                              "only); run on one rank with a smaller [mesh], or use "
                              "branch_switch = \"none\"")
        notes.append(f"stability from the sparse inertia {why}: bifurcations are located, "
                     "without their critical mode")
    elif loads.follower:
        notes.append("stability is not checked (follower loads): 'stable' and "
                     "'energy_decreasing_directions' are null and bifurcations are not detected")
    run = StaticContinuation(static, comm, prefix="fe_beam_path_")
    problem = run.problem
    summary: dict = {"status": "running", "message": "", "parameter": settings.parameter,
                     "max_load_factor": settings.max_load_factor, "path": [],
                     "critical_points": [], "dofs": problem.global_dofs, "notes": notes,
                     "wall_time_s": 0.0}
    tension = None
    if settings.parameter == "tension":
        tension = float(static.tendons[settings.tendon].tension)
        summary["tendon"] = {"index": settings.tendon,
                             "name": static.tendons[settings.tendon].name, "tension": tension}
    writing = out is not None
    if writing and comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    xdmf = writing and static.output.xdmf
    kind_of_writer = SpatialXDMFWriter if problem.spatial else BeamXDMFWriter
    writer = kind_of_writer(problem, out / "path.xdmf", contact=run.contact) if xdmf else None
    obstacles = static.obstacles
    # the deformed shapes with the obstacles (path points, every point's shape on rank 0)
    structure = getattr(static.model, "structure", None)
    drawing = writing and static.output.plots and (bool(obstacles) or structure is not None)
    # a structure's path plots where its first point force pushes (its tip may be held)
    load_point = (structure.chain_point_loads()[0][0][0]
                  if structure is not None and structure.chain_point_loads()[0] else None)
    shaper = (writer or kind_of_writer(problem, None, contact=run.contact)) if drawing else None
    shapes: list = []
    if obstacles:
        notes.append("contact: each point's equilibrium satisfies the contact conditions to "
                     "[contact] penetration_tolerance (active-set and Uzawa updates around the "
                     "arc-length corrector); the stability count includes the augmented-"
                     "Lagrangian stiffness of the pressed points, and a change of the count "
                     "across a change of the contact state is not reported as a bifurcation")

    def draw_shapes(_summary: dict) -> None:
        if shapes:
            _path_shapes(out, shapes, static)

    files, content = _path_files(out if writing else None, writer, summary, started,
                                 static.output.plots, comm, spatial=problem.spatial,
                                 extra_columns=contact_columns(len(obstacles), problem.spatial)
                                 + structure_columns(static.model),
                                 draw=draw_shapes if drawing else None)
    bar = ProgressBar(comm, total=settings.max_steps, label="path", enabled=progress)

    def on_point(entry: dict, result: PathResult) -> None:
        record = dict(entry)
        record["index"] = len(summary["path"])
        record["tension"] = None if tension is None else entry["load_factor"] * tension
        if settings.parameter == "point_force":  # where the (first) point force pushes
            at = loads.point_forces[0][0]
            record["point"] = {"x": at, **problem.point_values(at)}
        elif load_point is not None:
            record["point"] = {"x": load_point, **problem.point_values(load_point)}
        summary["path"].append(record)
        at = loads.point_forces[0][0] if settings.parameter == "point_force" else load_point
        summary["critical_points"] = [_critical_summary(c, problem, at)
                                      for c in result.critical_points]
        summary["notes"] = notes + [n for n in result.notes if n not in notes]
        files.on_step(record)
        if shaper is not None:  # after the XDMF export: its fields are this point's
            shape = shaper.vertex_values(update=shaper is not writer)
            if comm.rank == 0 and getattr(problem, "chain", None) is not None:
                shape = problem.chain.shape(shape)  # drawn at the rods' reference placement
            if comm.rank == 0:
                shapes.append((f"load factor {entry['load_factor']:.3g}", shape))
        bar.update(min(len(summary["path"]) - 1, settings.max_steps),
                   f"load factor {entry['load_factor']:.4g}")

    unreached = None
    if tension is not None:
        constant = run.tendons.tensions[settings.tendon]

        def hold(factor: float) -> None:  # everything else at `factor`, this tendon at 0
            run._set_load_factor(factor)
            constant.value = 0.0

        def pull(factor: float) -> None:  # everything else in full, this tendon at factor T
            run._set_load_factor(1.0)
            constant.value = factor * tension

        others = (any(t.tension for i, t in enumerate(static.tendons) if i != settings.tendon)
                  or given(loads))
        if others:  # the state with the tendon slack: load-stepped from the undeformed one
            try:
                Continuation(run.adapter(hold, checked=False), 0.0).load_control(
                    1.0, static.stepping, progress=progress, label="path pre-state")
            except ContinuationFailed as failure:  # exit 3 with the reason, not a traceback
                unreached = ("the state with the other loads and this tendon slack was not "
                             f"reached: {failure}")
        run._engine = Continuation(run.adapter(pull), 0.0)
        pull(0.0)
    if settings.parameter == "point_force":
        try:
            point_force_control(run, static, progress=progress)
        except ContinuationFailed as failure:  # exit 3 with the reason, not a traceback
            unreached = f"the state without the point forces was not reached: {failure}"
            if "inextensible" in static.model.options.constraint:
                unreached += (" (an inextensible beam cannot start from a straight shortened "
                              "state; use constraint = \"unshearable\" or \"none\" and an "
                              "imperfection)")

    arc = ArcLength(**settings.arc_length_settings())
    result = None
    try:
        if unreached is not None:
            summary["status"], summary["message"] = "failed", unreached
            return summary
        result = follow_path(run, arc, settings.branch_switch, settings.tolerance, on_point)
        summary["status"], summary["message"] = result.status, result.message
        last = summary["path"][-1]["load_factor"] if summary["path"] else 0.0
        if (result.status == "converged" and not result.message
                and abs(last) < settings.max_load_factor * (1 - 1e-9)):
            summary["message"] = (f"the path ended after [path] max_steps = "
                                  f"{settings.max_steps} points at load factor {last:.6g}, "
                                  f"before max_load_factor = {settings.max_load_factor:g}: "
                                  "raise max_steps or arc_length to go on")
        if result.status == "failed":
            summary["message"] = (f"path stopped at load factor {run.load_factor:.6g}: "
                                  f"{result.message}")
        if result.status == "converged" and summary["path"]:
            contact = run.contact.summary() if run.contact is not None else None
            tensions = run.tendons.tension_values() if run.tendons else ()
            summary.setdefault("checks", []).append(equilibrium_entry(
                problem, static.solver.rtol, contact, "at the last path point",
                tensions=tensions, contact_tolerance=static.contact.force_tolerance
                if static.obstacles else 0.0))
            if run.contact is not None:
                # every reported point's contact (penetration over the whole surface, force
                # balance), as fe-beam static certifies its last state
                summary["checks"].extend(contact_checks(
                    [e for point in summary["path"] for e in point.get("contact", [])],
                    max(run.contact.tolerance,
                        ContactSettings().tolerance(static.model.section))))
    except runctl.Interrupted as stop:
        _interrupted(summary, stop)
        raise
    finally:
        bar.close()
        if result is not None and writing and static.output.xdmf:
            modes = [(i, c) for i, c in enumerate(result.critical_points) if c.mode is not None]
            state = compat.local_array(problem.w).copy()
            modes_writer = (SpatialXDMFWriter if problem.spatial else BeamXDMFWriter)(
                problem, out / "critical_modes.xdmf", sections=False)  # shapes only
            for number, (index, point) in enumerate(modes, start=1):
                compat.local_array(problem.w)[:] = point.mode
                modes_writer.write(float(number))
                summary["critical_points"][index]["mode"] = {"file": "critical_modes.xdmf",
                                                             "index": number}
            modes_writer.close()
            compat.local_array(problem.w)[:] = state
        if writing and obstacles and comm.rank == 0:
            write_obstacle_surfaces(obstacles, out / "obstacles.vtu",
                                    *bounding_box(shapes, static.model.length))
        files.finish(content())
        run.destroy()
    return summary


def _path_shapes(out, shapes: list, static) -> None:
    """deformed_shapes.png of a path with obstacles: about ten of its points' shapes (the
    last one always) with the obstacles drawn."""
    every = max(1, len(shapes) // 10)
    chosen = shapes[every - 1 :: every]
    if chosen[-1] is not shapes[-1]:
        chosen.append(shapes[-1])
    model = static.model
    title = f"path: {model.options.law} law, constraint {model.options.constraint}"
    structure = getattr(model, "structure", None)
    undeformed = None if structure is None else structure.reference_polyline()
    if getattr(model, "kinematics", "planar") == "spatial":
        plot_spatial_shapes(chosen, out / "deformed_shapes.png", title, model.length,
                            obstacles=static.obstacles, undeformed=undeformed)
    elif structure is not None:
        plot_deformed_shapes(chosen, out / "deformed_shapes.png", title, model.length,
                             obstacles=static.obstacles, undeformed=undeformed,
                             marks=structure.drawing_marks())
    else:
        plot_deformed_shapes(chosen, out / "deformed_shapes.png", title, model.length,
                             obstacles=static.obstacles, section=model.section)


def _run_solid_path(config, settings, out, comm, progress, started) -> dict:
    """`fe-beam path` of the 3D solid: arc length in the load factor (tip force and tensions
    scaled together) from the undeformed state; the stability from the sparse inertia (tip force
    only), no critical points."""


    notes = check_solid_work(config, comm, quiet=out is None)
    notes.append("the 3D solid's stability is the sparse inertia of its potential's Hessian "
                 "(fe_beam.solvers.inertia.solid_unstable_count), not checked while a tendon is "
                 "tensioned (null: the cable stiffness is not in it); critical points are not "
                 "located")
    run = SolidRun(config, comm)
    summary: dict = {"status": "running", "message": "", "model": "solid",
                     "parameter": "load_factor", "max_load_factor": settings.max_load_factor,
                     "path": [], "critical_points": [], "dofs": run.dofs, "notes": notes,
                     "wall_time_s": 0.0}
    writing = out is not None
    if writing and comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    writer = (DisplacementXDMF(run.problem, out / "path.xdmf")
              if writing and config.output.xdmf else None)
    files, content = _path_files(out if writing else None, writer, summary, started,
                                 config.output.plots, comm)
    bar = ProgressBar(comm, total=settings.max_steps, label="path (3D)", enabled=progress)

    def record(load_factor: float) -> None:
        run.load_factor = float(load_factor)
        count = solid_unstable_count(run.problem)
        entry = {"load_factor": float(load_factor), "tip": run.tip(),
                 "stable": None if count is None else count == 0,
                 "energy_decreasing_directions": count, "branch": 0,
                 "index": len(summary["path"]), "tension": None}
        summary["path"].append(entry)
        files.on_step(entry)
        bar.update(min(len(summary["path"]) - 1, settings.max_steps),
                   f"load factor {load_factor:.4g}")

    engine = run.problem.engine()
    engine.parameter = 0.0
    try:
        record(0.0)
        engine.arc_length_path(ArcLength(**settings.arc_length_settings()),
                               on_converged=lambda point: record(point.load_factor))
        summary["status"] = "converged"
    except ContinuationFailed as failure:
        summary["status"] = "failed"
        summary["message"] = f"path stopped at load factor {run.load_factor:.6g}: {failure}"
    except runctl.Interrupted as stop:
        _interrupted(summary, stop)
        raise
    finally:
        bar.close()
        files.finish(content())
    return summary


def run(validated, out, comm=None, progress: bool = True, echo=None) -> Result:
    """``fe-beam path`` (the driver contract, `fe_beam.analyses.result`)."""
    summary = follow_configured_path(validated.parsed, out, comm, progress)
    report = Report(echo)
    for note in summary.get("notes", []):
        report.err(f"fe-beam path: note: {note}")
    for point in summary["critical_points"]:
        # a point-force path: where the force pushes (the path's "point"), not the tip
        tip, where = (point["point"], f"point x = {point['point']['x']:.6g} m") \
            if "point" in point else (point["tip"], "tip")
        last = (f"w = {tip['w']:.6g} m" if "w" in tip else f"theta = {tip['theta']:.6g} rad")
        report.out(f"{point['kind']} point at load factor {point['load_factor']:.8g}: {where} "
                   f"u = {tip['u']:.6g} m, v = {tip['v']:.6g} m, {last}")
    report.out(f"{len(summary['path'])} path points, {summary['dofs']} dofs, "
               f"{summary['wall_time_s']:.2f} s; results in {out}")
    code = exit_code(report, summary, "fe-beam path")
    return Result("path", summary, code, report.lines)

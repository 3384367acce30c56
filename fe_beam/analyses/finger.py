"""Tendon-driven tapered soft finger (the finger chapter; docs/theory.md, Tendons).

The finger is a `BeamModel` plus `[[tendons]]`; every table the user leaves out defaults to the
chapter's finger: L = 0.1 m, B = 0.02 m, H from 0.02 to 0.01 m, one tendon from 8 mm offset at
the base to 4 mm at the tip, silicone with E = 0.6 MPa (nu = 0.45 assumed: the rod model needs
nu < 0.5; it only enters the shear stiffness).
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam import exports, runctl
from fe_beam.analyses.certificates import equilibrium_entry
from fe_beam.analyses.result import Report, Result, closing_of_steps
from fe_beam.analyses.static import StaticResult, contact_line, solve_static
from fe_beam.config.finger import (  # noqa: F401  (their home; re-exported)
    DEFAULT_FINGER,
    INVERSE_KEYS,
    TENDON_KEYS,
    TIP_COMPONENT,
    InverseTarget,
    check_tendon_inside,
    parse_finger,
    parse_tendon,
    with_defaults,
)
from fe_beam.errors import ConfigError
from fe_beam.exports.outputs import (
    atomic_write_json,
    draw_obstacles,
    draw_section_faces,
    virtual_display,
)
from fe_beam.exports.plotting import legend_inside
from fe_beam.exports.spatial import plot_spatial_load_displacement, plot_spatial_shapes
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers import realtime
from fe_beam.solvers.newton import LoadSteppingFailed
from fe_beam.solvers.pull_in import tension_for_target

__all__ = ["DEFAULT_FINGER", "InverseUnreachable", "parse_finger", "run", "run_finger",
           "tension_for_tip_angle"]


def _profile_value(profile):
    """A routing profile as the configuration gave it: the number, or the formula's text (a
    chain's tendon: its rod's own, `fe_beam.model.tendons.RodProfile`)."""
    profile = getattr(profile, "profile", profile)
    return profile.constant if profile.is_constant else profile.text

class InverseUnreachable(ConfigError):
    """The inverse target is not reached by the tendon (a stopped analysis, not an input
    mistake: `run_finger` reports it with status "failed" and exit code 3). ``best``: the
    evaluated (control value, tip value) nearest the target."""

    def __init__(self, message: str, best: tuple[float, float] | None = None):
        super().__init__(message)
        self.best = best


def tension_for_tip_angle(
    config: StaticConfig,
    target: float,
    comm=MPI.COMM_WORLD,
    bracket: tuple[float, float] | None = None,
) -> float:
    """Tension of the (single, tension-controlled) tendon that turns the tip by ``target``."""
    return solve_inverse(config, InverseTarget("tip_angle", target), comm, bracket=bracket)[
        "tension"]


def solve_inverse(
    config: StaticConfig,
    target: InverseTarget,
    comm=MPI.COMM_WORLD,
    sweep: list[dict] | None = None,
    bracket: tuple[float, float] | None = None,
) -> dict:
    """Tension (or pull-in, if the single tendon is pull-in controlled) that puts the tip
    component of ``target`` at its value: Brent's method on full static solves. The converged
    steps of a sweep (``sweep``, e.g. the finger run itself) bracket the answer between two
    neighbouring steps, which saves most of the solves; without them the bracket grows by
    doubling from the tendon's own value."""
    started = time.perf_counter()
    tendon = config.tendons[0]
    control = "pull_in" if tendon.controlled_by_pull_in else "tension"
    unit = "m" if control == "pull_in" else "N"
    evaluations = []
    key = "tensions" if control == "tension" else "pull_ins"
    component = target.component
    reached = [(0.0, 0.0)] + [(float(step[key][0]), float(step["tip"][target.component]))
                              for step in sweep or []]
    # One problem for all trials: the tendon at a reference value, each trial a load factor
    # reached by continuation from the previous equilibrium (a few Newton iterations instead of
    # a full load ramp); from the unloaded state again only if that fails.
    reference = abs(getattr(tendon, control)) or 1.0

    run = realtime.acquire(
        replace(config, tendons=(replace(tendon, **{control: reference}),)), comm
    )

    def solve(value: float) -> dict:
        target = value / reference
        steps = max(1, math.ceil(config.stepping.steps * abs(target - run.load_factor)))
        try:
            run.advance(target, replace(config.stepping, steps=steps))
        except LoadSteppingFailed:
            run.restart()
            try:
                run.advance(target, config.stepping)
            except LoadSteppingFailed:
                raise ConfigError(
                    f"[inverse] no equilibrium at {control} {value:g} {unit}"
                ) from None
        evaluations.append(value)
        tip = run.problem.end_values("xL")
        reached.append((value, float(tip[component])))
        return {
            "tip": tip,
            "tensions": run.tendons.tension_values().tolist(),
            "pull_ins": run.tendons.pull_ins().tolist(),
        }

    def miss(value: float) -> float:
        return solve(value)["tip"][target.component] - target.value

    try:
        if bracket is None:
            bracket = _bracket_from_sweep(sweep or [], control, target)
        if bracket is None:
            bracket = _bracket_by_doubling(solve, target, control, unit,
                                           max(abs(getattr(tendon, control)), 1e-9))
        value = tension_for_target(lambda v: miss(v) + target.value, target.value, bracket)
        final = solve(value)
        check = equilibrium_entry(
            run.problem, config.solver.rtol,
            run.contact.summary() if run.contact is not None else None,
            "at the inverse solve's answer", tensions=final["tensions"],
            contact_tolerance=config.contact.force_tolerance if config.obstacles else 0.0)
    except ConfigError as error:
        # the configuration was valid (the sweep converged): the target is out of reach
        best = min(reached, key=lambda pair: abs(pair[1] - target.value))
        raise InverseUnreachable(str(error), best) from None
    finally:
        realtime.release(run)
    answer = {
        "target": target.key,
        "target_value": target.value,
        "control": control,
        "tension": final["tensions"][0],
        "pull_in": final["pull_ins"][0],
        "tip": final["tip"],
        "evaluations": len(evaluations),
        "wall_time_s": time.perf_counter() - started,
        "check": check,
    }
    if target.key == "tip_angle":
        answer["target_tip_angle"] = target.value
    return answer


def _bracket_by_doubling(solve, target: InverseTarget, control: str, unit: str, start: float):
    """(low, high) values of ``control`` whose tip values straddle the target, doubling from
    ``start`` (the tip is 0 at zero load); a clear ConfigError when the target lies the other
    way or beyond the last value with an equilibrium."""
    low, high, reached = 0.0, start, 0.0
    what = f"[inverse] {target.key} = {target.value:g}"
    while True:
        try:
            now = solve(high)["tip"][target.component]
        except ConfigError:
            if low == 0.0:
                raise
            raise ConfigError(
                f"{what} is not reached: the largest {control} with an equilibrium, {low:g} "
                f"{unit}, gives {reached:.6g}; at {high:g} {unit} load stepping failed"
            ) from None
        if (now - target.value) * (0.0 - target.value) <= 0:
            return low, high
        if now * target.value < 0:
            raise ConfigError(
                f"{what} cannot be reached: the tendon moves the tip the other way "
                f"({target.component} = {now:.6g} at {control} {high:g} {unit})"
            )
        low, high, reached = high, 2 * high, now
        if high > 1e6 * max(start, 1.0):
            raise ConfigError(f"{what} is not reachable by the tendon's {control}")


def _bracket_from_sweep(steps: list[dict], control: str, target: InverseTarget):
    """Two neighbouring swept values of ``control`` whose tip values straddle the target."""
    key = "tensions" if control == "tension" else "pull_ins"
    points = [(0.0, 0.0)] + [(s[key][0], s["tip"][target.component]) for s in steps]
    for (a, qa), (b, qb) in zip(points, points[1:]):
        if (qa - target.value) * (qb - target.value) <= 0 and a != b:
            return (a, b)
    return None


def run_finger(
    config: StaticConfig,
    out: Path | None,
    comm=MPI.COMM_WORLD,
    progress=True,
    target: InverseTarget | float | None = None,
    stability: bool | None = None,
) -> tuple[StaticResult, dict]:
    """The finger's tension (or pull-in) sweep, then the inverse solve if ``target`` is given;
    with ``out``, summary.json, the sweep CSV, XDMF and the chapter's figures are written
    (``result.shapes`` is only recorded then)."""
    extra = {
        "tendons": [
            {
                "name": t.name,
                "paths": t.paths,
                "entry": t.entry,
                "anchor": t.anchor,
                "tension": t.tension,
                "pull_in": t.pull_in,
                # a structure of rods: the tendon's rod (paths, entry, anchor: the chain's s)
                **({"rod": t.rod} if t.rod is not None else {}),
                # a routed tendon (offset_y/offset_z): its profiles as given (paths: sampled)
                **({"routing": {"offset_y": _profile_value(t.routing[0]),
                                "offset_z": _profile_value(t.routing[1])}}
                   if t.routing is not None else {}),
            }
            for t in config.tendons
        ]
    }
    # without files nobody looks at the per-step shapes and profiles: skip them (2.5x faster)
    spatial = getattr(config.model, "kinematics", "planar") == "spatial"
    sweep = ([exports.CSVExport(out / "tension_sweep.csv",
                                sweep_columns(len(config.tendons), len(config.obstacles),
                                              spatial),
                                empty=False)] if out is not None else [])
    result = solve_static(config, out, comm, progress=progress, extra_summary=extra,
                          record_shapes=out is not None, extra_exports=sweep,
                          stability=stability)
    # after the sweep: summary.json again (with the inverse solve) and the chapter's pictures
    draw = (lambda _: plot_finger(out, result, config)) if config.output.plots else None
    after = exports.Exports([exports.SummaryExport(out / "summary.json"),
                             exports.PlotExport(draw) if draw else None]
                            if out is not None and result.steps else [], comm)
    inverse = {}
    if isinstance(target, (int, float)):
        target = InverseTarget("tip_angle", float(target))
    if target is not None and result.status == "converged":
        try:
            inverse = solve_inverse(config, target, comm, sweep=result.steps)
        except InverseUnreachable as error:
            # a stopped analysis (exit 3), its best reached value in the summary
            control = "pull_in" if config.tendons[0].controlled_by_pull_in else "tension"
            result.status, result.message = "failed", str(error)
            inverse = {"target": target.key, "target_value": target.value,
                       "control": control, "status": "failed", "message": str(error)}
            if error.best is not None:
                inverse["best_reached"] = {control: error.best[0],
                                           target.key: error.best[1]}
        except runctl.Interrupted as stop:
            result.extra = result.extra | stop.stopped(
                "the inverse solve (the sweep is complete)", "during the inverse solve")
            after.finish(result.summary())
            raise
    if inverse and "check" in inverse:  # the answer's global equilibrium, with the sweep's
        result.extra.setdefault("checks", []).append(inverse.pop("check"))
    result.extra = result.extra | ({"inverse": inverse} if inverse else {})
    after.finish(result.summary())
    return result, inverse


def sweep_columns(tendons: int, obstacles: int = 0, spatial: bool = False
                  ) -> list[exports.Column]:
    """tension_sweep.csv: load factor, each tendon's tension and pull-in, the tip (spatial
    rods: u, v, w and the rotation vector); with obstacles the grasp: each obstacle's contact
    force on the finger (magnitude and global components, `grasp_force`)."""
    tip = [exports.Column(f"tip_{k}", lambda s, k=k: s["tip"][k]) for k in ("u", "v", "w")] + [
        exports.Column(f"tip_rotation_{k}", lambda s, i=i: s["tip"]["rotation_vector"][i])
        for i, k in enumerate("xyz")] if spatial else exports.tip_columns()
    grasp = []
    for i in range(obstacles):
        grasp += [exports.Column(f"grasp_force_{i}", lambda s, i=i: grasp_force(s)[i])]
        grasp += [exports.Column(f"contact{i}_F{a}", lambda s, i=i, k=k:
                                 s["contact"][i]["force"][k])
                  for k, a in enumerate("xyz" if spatial else "xy")]
    return [exports.Column("load_factor", lambda s: s["load_factor"]),
            *exports.indexed_columns("tension", tendons, lambda s: s["tensions"]),
            *exports.indexed_columns("pull_in", tendons, lambda s: s["pull_ins"]),
            *tip, *grasp]


def grasp_force(step: dict) -> list[float]:
    """|force| [N] each obstacle exerts on the finger at a step (the grasp force)."""
    return [math.hypot(*entry["force"]) for entry in step.get("contact", [])]


def plot_finger(out: Path, result: StaticResult, config: StaticConfig) -> None:
    """The chapter's Figures 3.8 (profiles along s) and 3.9 (backbone), and tension curves."""

    if getattr(config.model, "kinematics", "planar") == "spatial":
        plot_spatial_finger(out, result, config)
        return
    final = result.shapes[-1][1]
    cells = final["cells"]
    profiles = out / "fig3_8_profiles.png"
    with exports.figure(profiles, 2, 2, figsize=(9, 6), sharex=True) as (drawn, axes):
        zero = np.zeros_like(cells["x"])
        panels = [
            ("torsion [1/m]", zero, "(a) torsion: identically 0 in the plane"),
            ("curvature about n [1/m]", zero, "(b) curvature about n: 0 in the plane"),
            ("curvature about b [1/m]", cells["kappa"], "(c) curvature about b"),
            ("compression [N]", -cells["axial_force"], "(d) compression (-axial force)"),
        ]
        _profile_panels(drawn, axes, cells["x"], panels, result.steps[-1]["tensions"])

    with exports.figure(out / "fig3_9_backbone.png", figsize=(6, 5), layout=False) as (_, axis):
        every = max(1, len(result.shapes) // 8)
        shapes = list(zip(result.shapes, result.steps, strict=True))[every - 1 :: every]
        for index, ((_, shape), step) in enumerate(shapes):
            line, = axis.plot(shape["x"] + shape["u"], shape["v"],
                              label=f"tension {step['tensions'][0]:.3g} N")
            if getattr(config.model, "structure", None) is None:  # a chain: the axes only
                draw_section_faces(axis, shape, config.model.section, config.model.length,
                                   line.get_color(), fill=index == len(shapes) - 1)
        if config.obstacles:
            draw_obstacles(axis, result.obstacles or config.obstacles, [s for s, _ in shapes],
                           config.model.length)
        axis.set_aspect("equal", adjustable="datalim")
        axis.set_xlabel("x [m]")
        axis.set_ylabel("y [m]")
        axis.set_title("Backbone in the XY plane (cf. chapter Fig. 3.9a)")
        axis.grid(alpha=0.3)
        legend_inside(axis, fontsize=7)

    tensions = [s["tensions"][0] for s in result.steps]
    with exports.figure(out / "tension_tip.png", 1, 2, figsize=(9, 3.6)) as (_, (left, right)):
        left.plot(tensions, [s["tip"]["theta"] for s in result.steps], "o-", ms=3)
        left.set_xlabel("tension [N]")
        left.set_ylabel("tip angle [rad]")
        right.plot(tensions, [s["tip"]["u"] for s in result.steps], "o-", ms=3, label="tip u")
        right.plot(tensions, [s["tip"]["v"] for s in result.steps], "s-", ms=3, label="tip v")
        right.set_xlabel("tension [N]")
        right.set_ylabel("tip displacement [m]")
        right.legend()
        for axis in (left, right):
            axis.grid(alpha=0.3)
    reason = render_3d_skipped(out / "finger_3d.png", final, config)
    if reason is not None:
        note = f"finger_3d.png was not made: {reason}"
        note_skipped_picture(out, note)
        result.notes.append(note)  # the summary of the run (rank 0, which draws) says it too


def _profile_panels(drawn, axes, x, panels, tension) -> None:
    """The four profiles along s of the chapter's Figure 3.8 (label, values, title each)."""
    for axis, (label, values, title) in zip(axes.flat, panels, strict=True):
        axis.plot(x, values, lw=1.8)
        axis.ticklabel_format(axis="y", useOffset=False)
        axis.set_title(title, fontsize=9)
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    for axis in axes[1]:
        axis.set_xlabel("s [m]")
    drawn.suptitle(f"Profiles along the finger at tension "
                   f"{', '.join(f'{t:.3g}' for t in tension)} N (cf. chapter Fig. 3.8)")


def plot_spatial_finger(out: Path, result: StaticResult, config: StaticConfig) -> None:
    """A spatial finger: the chapter's Figure 3.8 with its three curvatures (torsion, about
    d2, about d3) and the axial strain, the backbone in three views and a 3D view (Fig. 3.9),
    and the tip against the tension."""
    final = result.shapes[-1][1]
    cells = final["cells"]
    with exports.figure(out / "fig3_8_profiles.png", 2, 2, figsize=(9, 6), sharex=True) as (
            drawn, axes):
        panels = [("torsion [1/m]", cells["twist"], "(a) torsion u1"),
                  ("curvature about d2 [1/m]", cells["curvature_y"], "(b) curvature about d2"),
                  ("curvature about d3 [1/m]", cells["curvature_z"], "(c) curvature about d3"),
                  ("axial strain v1 - 1", cells["v1"] - 1, "(d) axial strain")]
        _profile_panels(drawn, axes, cells["x"], panels, result.steps[-1]["tensions"])
    every = max(1, len(result.shapes) // 8)
    shapes = [(f"tension {step['tensions'][0]:.3g} N", shape) for (_, shape), step in list(
        zip(result.shapes, result.steps, strict=True))[every - 1:: every]]
    structure = getattr(config.model, "structure", None)
    undeformed = None if structure is None else [  # a chain: its reference polyline
        structure.reference_point(s, structure.segment_at(min(s, config.model.length)))
        for s in (0.0, *structure.boundaries(), config.model.length)]
    plot_spatial_shapes(shapes, out / "fig3_9_backbone.png",
                        "Backbone (cf. chapter Fig. 3.9)", config.model.length,
                        obstacles=result.obstacles or config.obstacles, undeformed=undeformed)
    tensions = [s["tensions"][0] for s in result.steps]
    tips = {k: [s["tip"][k] for s in result.steps] for k in ("u", "v", "w", "rotation_vector")}
    plot_spatial_load_displacement(tensions, tips, out / "tension_tip.png",
                                   "tip against the first tendon's tension [N]")


def note_skipped_picture(out: Path, note: str) -> None:
    """Say why a picture is missing: on stderr and in summary.json's ``notes``."""
    import json
    import sys

    print(f"fe-beam: note: {note}", file=sys.stderr, flush=True)
    runctl.WARNED.add(note)  # said: the run's report does not repeat it
    path = out / "summary.json"
    try:
        summary = json.loads(path.read_text())
    except (OSError, ValueError):
        return
    notes = summary.get("notes")
    summary["notes"] = (notes if isinstance(notes, list) else []) + [note]
    atomic_write_json(path, summary)


def render_3d(path: Path, shape: dict, config: StaticConfig) -> bool:
    """pyvista tube rendering of the deformed finger with its tendon (Fig. 3.9b); skipped
    (returns False) when pyvista or a virtual screen is not available."""
    return render_3d_skipped(path, shape, config) is None


def render_3d_skipped(path: Path, shape: dict, config: StaticConfig) -> str | None:
    """Render the 3D picture; None when done, else why it was skipped (one sentence)."""
    import os
    import shutil

    try:
        import pyvista
    except ImportError:
        return ("pyvista is not installed (./bootstrap installs it; or pip install "
                "'fe_beam[viz]')")
    if not os.environ.get("DISPLAY") and shutil.which("Xvfb") is None:
        return "no display to render on: set DISPLAY or install Xvfb (apt-get install xvfb)"
    try:
        with virtual_display():
            _render_tube(pyvista, path, shape, config)
    except Exception as error:  # a picture must never fail an analysis
        first = (str(error).strip().splitlines() or [""])[0][:200]
        return f"rendering with pyvista failed ({type(error).__name__}: {first})"
    if not path.is_file():
        return "rendering with pyvista produced no file"
    return None


def _render_tube(pyvista, path: Path, shape: dict, config: StaticConfig) -> None:
    x = shape["x"] + shape["u"]
    y = shape["v"]
    theta = shape["theta"]
    section = config.model.section
    s = shape["x"] / config.model.length
    height = np.array([section.properties(si).h for si in s])
    backbone = np.column_stack([x, y, np.zeros_like(x)])
    plotter = pyvista.Plotter(off_screen=True, window_size=(900, 600))
    body = pyvista.Spline(backbone, len(x) * 3).tube(radius=float(np.mean(height)) / 2)
    plotter.add_mesh(body, color="lightsteelblue", opacity=0.45)
    # a chain of rods: the tube only (its tendons' offsets turn with each rod's angle)
    chain = getattr(config.model, "structure", None) is not None
    for tendon in () if chain else config.tendons:
        for branch in tendon.paths:
            xs, ds = np.array([p[0] for p in branch]), np.array([p[1] for p in branch])
            delta = np.interp(shape["x"], xs, ds)
            inside = (shape["x"] >= tendon.entry - 1e-12) & (shape["x"] <= tendon.anchor + 1e-12)
            points = np.column_stack(
                [x - delta * np.sin(theta), y + delta * np.cos(theta), np.zeros_like(x)]
            )[inside]
            plotter.add_mesh(
                pyvista.Spline(points, len(points) * 3).tube(radius=float(np.mean(height)) / 25),
                color="crimson",
            )
    plotter.view_xy()
    plotter.add_axes()
    plotter.screenshot(str(path))
    plotter.close()


def run(validated, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True,
        echo=None) -> Result:
    """``fe-beam finger`` (the driver contract, `fe_beam.analyses.result`)."""
    parsed, target = validated.parsed
    result, inverse = run_finger(parsed, out, comm, progress=progress, target=target,
                                 stability=True)
    report = Report(echo)
    for step in result.steps[-1:]:
        tip = step["tip"]
        tensions = ", ".join(f"{t:.6g}" for t in step["tensions"])
        pulls = ", ".join(f"{p:.6g}" for p in step["pull_ins"])
        where = (f"w = {tip['w']:.6g} m, rotation vector "
                 f"[{', '.join(f'{c:.6g}' for c in tip['rotation_vector'])}] rad"
                 if "w" in tip else f"theta = {tip['theta']:.6g} rad")
        report.out(f"tension [N] {tensions}; pull-in [m] {pulls}; tip u = {tip['u']:.6g} m, "
                   f"v = {tip['v']:.6g} m, {where}")
        for entry in step.get("contact", []):
            report.out(contact_line(entry))
    if inverse.get("status") == "failed":
        best = inverse.get("best_reached")
        if best:
            report.out(f"inverse: {inverse['target']} = {inverse['target_value']:g} not "
                       f"reached; the nearest was {inverse['target']} = "
                       f"{best[inverse['target']]:.6g} at {inverse['control']} "
                       f"{best[inverse['control']]:.6g}")
    elif inverse:
        report.out(f"inverse: tension {inverse['tension']:.8g} N, pull-in "
                   f"{inverse['pull_in']:.6g} m give {inverse['target']} = "
                   f"{inverse['target_value']:g} ({inverse['evaluations']} solves, "
                   f"{inverse['wall_time_s']:.2f} s)")
    code = closing_of_steps(report, result, out)
    return Result("finger", result.summary(), code, report.lines, result)

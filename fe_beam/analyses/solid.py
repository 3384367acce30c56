"""``fe-beam solid``: the run. `run_solid` validates the configuration
(`fe_beam.config.solid.parse_solid`), runs the rod companion (`fe_beam.analyses.solid_rod`) and the
3D load
stepping (`SolidRun`), and writes the summary, the tables, the XDMF files and the plots.
"""

from __future__ import annotations

import itertools
import math
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam import certify, runctl
from fe_beam.analyses.result import Report, Result, exit_code
from fe_beam.analyses.solid_modes import modes_table, run_solid_modes
from fe_beam.analyses.solid_rod import backbone_distance, run_rod, tip_frame, write_rod_xdmf
from fe_beam.analyses.static import beam_dofs_estimate
from fe_beam.config.solid import SolidConfig, parse_solid, solid_dofs_estimate
from fe_beam.errors import ConfigError
from fe_beam.exports import (
    Column,
    CSVExport,
    Exports,
    PlotExport,
    SummaryExport,
    figure,
    indexed_columns,
    tip_columns,
)
from fe_beam.exports.obstacles import bounding_box, write_obstacle_surfaces
from fe_beam.exports.outputs import _pyplot, write_csv
from fe_beam.exports.solid import DisplacementXDMF
from fe_beam.exports.spatial import _draw_view_obstacles
from fe_beam.fem.solid.geometry import create_finger_mesh
from fe_beam.solvers.continuation import ContinuationFailed
from fe_beam.solvers.newton import LoadStepping, LoadSteppingFailed
from fe_beam.solvers.solid import SolidFingerProblem, stretch_keys


def _import_gmsh() -> None:
    """gmsh (4.8) resets SIGINT to its default action when first imported: import it now, then
    put the deferring handlers of fe_beam.runctl back, so Ctrl-C while meshing ends cleanly."""
    import gmsh  # noqa: F401

    runctl.reassert()


_import_gmsh()

__all__ = ["run", "SolidRun", "check_solid_work", "equilibrium_check", "rotation_vector",
           "run_solid"]

# --- the 3D run ---------------------------------------------------------------------------------

_RUNS = itertools.count(1)


class SolidRun:
    """The meshed 3D finger and its problem, advanced along the load factor in segments.

    ``advance(target)`` ramps the load factor from its current value to ``target`` with the
    load control of `fe_beam.solvers.continuation.Continuation` (cut-back on divergence) and calls
    ``on_step(record)`` after each converged step with the plain-data `record`.
    """

    def __init__(self, config: SolidConfig, comm: MPI.Comm = MPI.COMM_WORLD):
        self.config = config
        self.comm = comm
        self.finger = create_finger_mesh(config.geometry, config.sizes, comm)
        self.problem = SolidFingerProblem(
            self.finger,
            config.material,
            tendons=config.tendon_loads,
            tip_force=config.tip_force,
            discretization=config.discretization,
            solver=config.solver,
            prefix=f"fe_beam_solid{next(_RUNS)}_",
            anchor=config.anchor,
            obstacles=config.obstacles,
            contact=config.contact,
        )
        self.load_factor = 0.0
        self._theta = 0.0

    @property
    def dofs(self) -> int:
        dofmap = self.problem.W.dofmap
        return int(dofmap.index_map.size_global * dofmap.index_map_bs)

    @property
    def cells(self) -> int:
        imap = self.finger.mesh.topology.index_map(3)
        return int(imap.size_global)

    def advance(self, target: float, stepping: LoadStepping, on_step=None,
                progress: bool = False, label: str = "solid") -> None:
        """Load factor from its current value to ``target`` (raises LoadSteppingFailed with the
        last converged state restored)."""
        start = self.load_factor
        span = float(target) - start
        if not span > 0:
            raise ValueError(f"advance: target {target!r} must exceed {start!r}")
        steps = max(1, math.ceil(stepping.steps * span - 1e-9))
        segment = LoadStepping(
            steps=steps,
            min_increment=min(stepping.min_increment / span, 1.0 / steps),
            max_increment=(1.0 / steps if stepping.max_increment * stepping.steps < 1 + 1e-9
                           else min(1.0, max(stepping.max_increment / span, 1.0 / steps))),
            cut_factor=stepping.cut_factor,
            grow_factor=stepping.grow_factor,
            easy_iterations=stepping.easy_iterations + self.problem.extra_easy_iterations,
            adaptive=stepping.adaptive,
        )

        engine = self.problem.engine()
        engine.parameter = start

        def converged(step) -> None:
            self.problem.accept_step()
            self.load_factor = float(target) if step.fraction == 1.0 else step.load_factor
            record = self.record(step.iterations, step.linear_iterations)
            if on_step is not None:
                on_step(record)

        try:
            engine.load_control(target, segment, on_converged=converged, progress=progress,
                                label=label)
        except ContinuationFailed as failure:
            self.problem.set_load_factor(self.load_factor)
            raise ContinuationFailed(
                f"load stepping stopped at load factor {failure.attempted:.6g} "
                f"({failure.reason}); last converged load factor {self.load_factor:.6g}",
                self.load_factor, failure.results, reason=failure.reason, kind=failure.kind,
                parameter=self.load_factor, attempted=failure.attempted,
            ) from None

    def tip(self) -> dict:
        """Tip-face centroid displacement (u, v, w), the in-plane rotation theta (continuous
        along the path) and the tip frame: ``R`` (3 x 3, rows; its columns are the images of
        e_x, e_y, e_z: the tip face's best-fit rotation, `SolidFingerProblem.tip_rotation`) and
        its ``rotation_vector`` (axis times angle, |.| <= pi)."""
        d = self.problem.tip_displacement()
        rotation = self.problem.tip_rotation()
        angle = rotation["angle"]
        self._theta += (angle - self._theta + math.pi) % (2 * math.pi) - math.pi
        R = np.asarray(rotation["matrix"], dtype=float)
        return {"u": float(d[0]), "v": float(d[1]), "theta": float(self._theta),
                "w": float(d[2]), "R": R.tolist(),
                "rotation_vector": rotation_vector(R).tolist()}

    def backbone(self) -> dict:
        data = self.problem.backbone(self.config.stations)
        u = np.asarray(data["displacement"])
        return {"x": list(data["x"]), "u": u[:, 0].tolist(), "v": u[:, 1].tolist(),
                "w": u[:, 2].tolist()}

    def tendon_values(self) -> dict:
        owners = self.config.branch_owner
        if not owners:
            return {}
        count = max(owners) + 1
        tensions = self.problem.tensions()
        lengths = self.problem.tendon_lengths()
        rest = [c.reference_length for c in self.problem.cables]
        per_tendon = [0.0] * count
        pulls = [0.0] * count
        for i, owner in enumerate(owners):
            per_tendon[owner] = float(tensions[i])
            pulls[owner] += float(rest[i] - lengths[i])
        values = {"tensions": per_tendon, "pull_ins": pulls}
        if count == 1:
            values["tension"] = per_tendon[0]
        return values

    def record(self, newton_iterations: int = 0, linear_iterations: int = 0) -> dict:
        """Plain data of the current state (collective)."""
        return {
            "load_factor": self.load_factor,
            **self.tendon_values(),
            "tip": self.tip(),
            "backbone": self.backbone(),
            "newton_iterations": int(newton_iterations),
            "linear_iterations": int(linear_iterations),
            **stretch_keys(self.problem.max_principal_stretches()),
            **({"contact": self.problem.contact.summary()} if self.problem.contact else {}),
            "equilibrium": self.problem.equilibrium(),
        }

    def destroy(self) -> None:
        self.problem.snes_solver.destroy()


def rotation_vector(R: np.ndarray) -> np.ndarray:
    """The rotation vector (axis times angle in [0, pi]) of the rotation matrix ``R``."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(np.asarray(R, dtype=float)).as_rotvec()


# --- the command -------------------------------------------------------------------------------


def run_solid(raw: dict, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True) -> dict:
    """`solid_run` of ``raw`` parsed (for scripts that hold the TOML dict)."""
    return solid_run(parse_solid(raw), out, comm, progress)


def solid_run(parsed, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True) -> dict:
    """Validate ``raw`` (the parsed TOML), run the rod companion and the 3D load stepping, write
    results into ``out`` (if not None) and return the summary dict.

    Raises ConfigError for a mistake in ``raw``; an analysis that stops early returns (and
    writes) the converged steps with ``status = "failed"`` and a ``message``. Collective on
    ``comm``; files are written by its rank 0. ``out`` receives ``summary.json``,
    ``load_displacement.csv``, ``solid.xdmf``/``.h5`` (3D displacement per load factor; in
    contact also ``contact_gap_i`` and ``contact_pressure_i``, `DisplacementXDMF`, and the
    obstacles' surfaces ``obstacles.vtu``),
    ``rod.xdmf`` (the rod in the same coordinates) and, with ``[output] plots``, ``backbone.png``
    and ``load_displacement.png``.
    """
    started = time.perf_counter()
    config = parsed
    notes = check_solid_work(config, comm, quiet=out is None)
    out = None if out is None else Path(out)
    root = comm.rank == 0
    if out is not None and root:
        out.mkdir(parents=True, exist_ok=True)
    summary = {
        "status": "running",
        "message": "",
        "steps": [],
        "dofs": 0,
        "cells": 0,
        "wall_time_s": 0.0,
        "model": config.model_summary(),
        "rod": None,
        "notes": list(config.notes) + notes,
        "tip": None,
    }

    def content() -> dict:
        summary["wall_time_s"] = time.perf_counter() - started
        return summary

    files = Exports(solid_exports(out, config, content) if out is not None else [], comm)
    files.start(content())  # status "running" from the start
    try:
        _run_solid(config, out, comm, progress, summary, files)
    except runctl.Interrupted as stop:
        last = summary["steps"][-1]["load_factor"] if summary["steps"] else 0.0
        summary |= stop.stopped(f"load factor {last:.4g}", f"at load factor {last:.6g}")
        raise
    except ConfigError:
        raise
    except Exception as error:  # the converged steps so far stay; the run is "failed"
        last = summary["steps"][-1]["load_factor"] if summary["steps"] else 0.0
        summary |= {"status": "failed",
                    "message": f"{type(error).__name__}: {error} (stopped after load factor "
                               f"{last:.6g}; the converged steps are written)"}
    finally:
        files.finish(content())  # pictures only for a finished analysis (not interrupted)
    if out is not None:
        comm.barrier()  # the files are complete on return, whichever rank looks
    return summary


def _csv_columns(record: dict | None) -> list[Column]:
    """load_displacement.csv: one ``tension_i`` per tendon of the first record (none without)."""
    count = len(record.get("tensions", [])) if record else 0
    return [
        Column("load_factor", lambda s: s["load_factor"]),
        *indexed_columns("tension", count, lambda s: s.get("tensions", [])),
        *tip_columns(),
        *(Column(key, lambda s, key=key: s[key]) for key in (
            "newton_iterations", "linear_iterations", "max_principal_stretch",
            "max_principal_stretch_bulk")),
        *solid_contact_columns(len(record.get("contact", [])) if record else 0),
    ]


def solid_contact_columns(count: int) -> list[Column]:
    """Per obstacle i (the order of [[obstacles]]): ``contact<i>_F{x,y,z}`` (the force the
    obstacle exerts on the solid [N]), ``contact<i>_active_area`` [m^2], ``contact<i>_length``
    (the patch's extent along x [m]), ``contact<i>_max_penetration`` [m] and
    ``contact<i>_pressure_peak`` [Pa]."""
    columns = []
    for i in range(count):
        columns += [Column(f"contact{i}_F{a}", lambda s, i=i, k=k: s["contact"][i]["force"][k])
                    for k, a in enumerate("xyz")]
        columns += [Column(f"contact{i}_{name}", lambda s, i=i, key=key: s["contact"][i][key])
                    for name, key in (("active_area", "active_area"),
                                      ("length", "contact_length"),
                                      ("max_penetration", "max_penetration"),
                                      ("pressure_peak", "pressure_peak"))]
    return columns


def solid_exports(out: Path, config: SolidConfig, content) -> list:
    """The files of ``fe-beam solid`` in ``out`` (`fe_beam.exports`): load_displacement.csv,
    summary.json (``content()``: the summary as it stands) and, with ``[output] plots``, the
    pictures of a finished run with steps. The 3D states (solid.xdmf) and the rod (rod.xdmf) are
    written by the run itself (collective, once the mesh exists)."""
    return [
        CSVExport(out / "load_displacement.csv", _csv_columns),
        SummaryExport(out / "summary.json", content),
        PlotExport(lambda s: _plot_solid(out, s, config) if s["steps"] else None)
        if config.output.plots else None,
    ]


def check_solid_work(config: SolidConfig, comm, quiet: bool = False) -> list[str]:
    """Up-front limits of `fe_beam.runctl.check_work` for the 3D solid (and its rod)."""
    allow = bool((config.raw.get("solver") or {}).get("allow_large", False))
    notes = runctl.check_work(config.stepping.steps, solid_dofs_estimate(config), allow,
                              " of load stepping", kind="solid")
    if config.rod is not None:
        notes += runctl.check_work(None, beam_dofs_estimate(config.rod), allow)
    if not quiet:
        runctl.warn(comm, notes)
    return notes


def _run_solid(config: SolidConfig, out: Path | None, comm, progress: bool, summary: dict,
               files: Exports) -> dict:
    """The rod companion and the 3D load stepping, filling ``summary``; ``files`` gets the step
    records (`run_solid` starts and finishes it)."""
    root = comm.rank == 0
    rod = None
    if config.rod is not None:
        rod = run_rod(config.rod, config.stations, comm, progress=progress)
        if out is not None and root and config.output.xdmf:
            write_rod_xdmf(out / "rod.xdmf", rod["frames"])
        summary["rod"] = {k: v for k, v in rod.items() if k != "frames"}
    else:
        summary["rod"] = {"status": "skipped", "message": config.rod_note}

    try:
        run = SolidRun(config, comm)
    except RuntimeError as error:  # gmsh could not mesh (e.g. a tendon not on tet edges)
        summary |= {"status": "failed", "message": str(error)}
        return summary
    summary |= {"dofs": run.dofs, "cells": run.cells,
                "linear_solver_resolved": run.problem.linear_solver}
    writer = None
    if out is not None and config.output.xdmf:
        writer = DisplacementXDMF(run.problem, out / "solid.xdmf")
        writer.write(0.0)
        if config.obstacles and root:  # their surfaces, next to solid.xdmf (same coordinates)
            write_obstacle_surfaces(config.obstacles, out / "obstacles.vtu",
                                    *bounding_box([], config.length))

    def on_step(record: dict) -> None:
        summary["steps"].append(record)
        summary["tip"] = record["tip"]  # the last converged state's tip (and frame)
        if writer is not None:
            writer.write(record["load_factor"])
        files.on_step(record)

    try:
        run.advance(1.0, config.stepping, on_step, progress=progress, label="solid")
        summary["status"] = "converged"
        if config.modes is not None:  # [modes]: 3D modal analysis, the rod's beside it

            summary["modes"] = run_solid_modes(run, config, out, comm)
    except LoadSteppingFailed as failure:
        summary |= {"status": "failed", "message": str(failure)}
    finally:
        if writer is not None:
            writer.close()
        run.destroy()
        if summary["steps"]:
            summary.setdefault("checks", []).append(equilibrium_check(summary["steps"]))
    if rod is not None and rod["backbone"] is not None and summary["steps"]:
        last_rod = rod["steps"][-1]["load_factor"] if rod["steps"] else 0.0
        last = summary["steps"][-1]
        if abs(last_rod - last["load_factor"]) < 1e-12:
            distance = backbone_distance(rod["backbone"], last["backbone"])
            frame = tip_frame(rod["steps"][-1]["tip"], last["tip"])
            summary["rod"]["distance_to_solid"] = {
                "load_factor": last["load_factor"],
                "max_over_L": distance["max"] / config.length,
                "x": distance["x"],
                "measure": "max over x of |r_rod(x) - r_solid(x)| / L (deformed centroids)",
                "tip_frame_angle": frame["angle"],
                "tip_frame_rotation_vector": frame["rotation_vector"],
            }
    return summary


#: tolerance of the solid's global equilibrium, relative to the largest load (Newton stops at a
#: residual ~1e-10 of the first one; the clamp's reaction sums it over the clamped face)
EQUILIBRIUM_TOLERANCE = 1e-6


def equilibrium_check(steps: list[dict], tolerance: float | None = None) -> dict:
    """The certificate ``solid_global_equilibrium`` of the converged ``steps``: the largest over
    them of the imbalance of the clamp's reaction, the tip force and the contact forces (forces
    and moments about the origin, the moment over L), relative to the largest load (the tendon
    tensions count as loads for the scale; their cables are internal: `SolidFingerProblem.
    equilibrium`)."""
    tolerance = EQUILIBRIUM_TOLERANCE if tolerance is None else tolerance
    worst = max(steps, key=lambda s: s["equilibrium"]["value"])
    value = worst["equilibrium"]["value"]
    return certify.entry(
        "solid_global_equilibrium", value, tolerance,
        detail=("max over the load steps of max(|R_clamp + F_tip + F_contact|, |moments| / L) / "
                f"largest load (worst at load factor {worst['load_factor']:.4g})"),
        remedy="tighten [solver] rtol, or use [solid] solver = \"mumps\" (an inexact Krylov "
               "solve leaves a larger residual)")


def _write_tables(out: Path, summary: dict) -> None:
    """summary.json and the whole load_displacement.csv of ``summary`` at once (the columns of
    `solid_exports`; kept for callers of the old name)."""
    SummaryExport(out / "summary.json").write(summary)
    steps = summary["steps"]
    columns = _csv_columns(steps[0] if steps else None)
    write_csv(out / "load_displacement.csv", [c.name for c in columns],
              [[c.get(s) for c in columns] for s in steps])


def draw_obstacles_in_view(axis, obstacles, j: int, thickness: float) -> None:
    """The 3D ``obstacles`` in grey in the view (x, component ``j``) of backbones (the section
    centroids): the view widened by the body's ``thickness`` in that direction on both sides
    (an obstacle the surface touches lies within half of it), then kept."""
    (x0, x1), (y0, y1) = axis.get_xlim(), axis.get_ylim()
    y0, y1 = y0 - thickness, y1 + thickness
    _draw_view_obstacles(axis, obstacles, 0, j, np.array([x0, y0]), np.array([x1, y1]))
    axis.set_xlim(x0, x1)
    axis.set_ylim(y0, y1)


def _plot_solid(out: Path, summary: dict, config: SolidConfig) -> None:
    """backbone.png (deformed backbones, 3D and rod) and load_displacement.png (tip u, v, theta
    against the load factor) of ``summary`` (with at least one step)."""
    plt = _pyplot()
    steps = summary["steps"]
    rod = summary.get("rod") or {}
    with figure(out / "backbone.png", figsize=(9, 4.5)) as (_, axis):
        every = max(1, len(steps) // 8)
        chosen = steps[every - 1 :: every]
        if chosen[-1] is not steps[-1]:
            chosen.append(steps[-1])
        colours = plt.cm.viridis(np.linspace(0, 0.9, len(chosen)))
        axis.plot([0, config.length], [0, 0], color="0.7", lw=1, ls="--", label="undeformed")
        for step, colour in zip(chosen, colours, strict=True):
            b = step["backbone"]
            axis.plot(np.add(b["x"], b["u"]), b["v"], color=colour, lw=1.8,
                      label=f"3D, load factor {step['load_factor']:.3g}")
        if rod.get("backbone") and rod.get("steps"):
            b = rod["backbone"]
            axis.plot(np.add(b["x"], b["u"]), b["v"], "k:", lw=1.5,
                      label=f"rod ({rod['law']}), load factor "
                      f"{rod['steps'][-1]['load_factor']:.3g}")
        if config.obstacles:  # seen along z (backbones: the section centroids)
            draw_obstacles_in_view(axis, config.obstacles, 1, config.geometry.height_base)
        axis.set_xlabel("x + u [m]")
        axis.set_ylabel("y + v [m]")
        axis.set_title(f"Backbone: 3D {config.material_name} vs rod")
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))

    with figure(out / "load_displacement.png", 1, 3, figsize=(11, 3.4)) as (_, axes):
        factors = [s["load_factor"] for s in steps]
        rod_steps = rod.get("steps") or []
        for axis, key, unit in zip(axes, ("u", "v", "theta"), ("m", "m", "rad"), strict=True):
            axis.plot(factors, [s["tip"][key] for s in steps], "o-", ms=3, label="3D")
            if rod_steps:
                axis.plot([s["load_factor"] for s in rod_steps],
                          [s["tip"][key] for s in rod_steps], "s--", ms=3,
                          label=f"rod ({rod['law']})")
            axis.set_xlabel("load factor")
            axis.set_ylabel(f"tip {key} [{unit}]")
            axis.grid(alpha=0.3)
            axis.legend(fontsize=7)


def run(validated, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True,
        echo=None) -> Result:
    """``fe-beam solid`` (the driver contract, `fe_beam.analyses.result`)."""
    summary = solid_run(validated.parsed, out, comm, progress)
    report = Report(echo)
    for note in summary.get("notes", []):
        report.err(f"fe-beam solid: note: {note}")
    for step in summary["steps"][-1:]:
        tip = step["tip"]
        report.out(f"load factor {step['load_factor']:.4g}: 3D tip u = {tip['u']:.6g} m, "
                   f"v = {tip['v']:.6g} m, w = {tip.get('w', 0.0):.6g} m, "
                   f"theta = {tip['theta']:.6g} rad, max principal stretch "
                   f"{step['max_principal_stretch']:.4g} "
                   f"({step['max_principal_stretch_bulk']:.4g} away from the tendon ends)")
    rod = summary.get("rod") or {}
    if rod.get("steps"):
        tip = rod["steps"][-1]["tip"]
        w = f"w = {tip['w']:.6g} m, " if "w" in tip else ""
        report.out(f"rod ({rod['law']}), load factor {rod['steps'][-1]['load_factor']:.4g}: "
                   f"tip u = {tip['u']:.6g} m, v = {tip['v']:.6g} m, {w}"
                   f"theta = {tip['theta']:.6g}")
    if "distance_to_solid" in rod:
        report.out(f"rod vs 3D: max_x |r_rod - r_solid| / L = "
                   f"{rod['distance_to_solid']['max_over_L']:.3g}, tip frame angle "
                   f"{rod['distance_to_solid']['tip_frame_angle']:.3g} rad")
    for line in modes_table(summary.get("modes")):  # [modes]: solid vs rod
        report.out(line)
    report.out(f"{len(summary['steps'])} load steps, {summary['dofs']} dofs, "
               f"{summary['wall_time_s']:.2f} s; results in {out}")
    return Result("solid", summary, exit_code(report, summary, "fe-beam"), report.lines)

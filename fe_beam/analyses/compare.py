"""``fe-beam compare``: the 3D solid against the 1D rod over a load or tendon-tension sweep, on the
same geometry and material. The rod laws (``[compare] laws``) default to all three: the section law
of the solid's own material (``hyperelastic``: the uniaxial fibre energy of the 3D law integrated
over the section, `fe_beam.fem.section_laws`; with the u-p formulation the volumetric energy is the
quadratic one that formulation uses), the non-standard law and the Reissner law.

The configuration is the one of ``fe-beam solid`` (`fe_beam.analyses.solid_driver`) plus
``[compare]``
(`COMPARE_KEYS`): the sweep is given as ``tensions`` (of the one tension-controlled tendon; the
loads at load factor 1 are then those at the largest tension), ``load_factors`` in (0, 1], or
``steps`` = n (load factors k / n). The rod's E and G are the small-strain limit of the 3D law.

The 3D solid is ramped once through the sweep; the rod is solved from the unloaded state for each
sweep point and law (`fe_beam.analyses.static.solve_static`). With ``[model] kinematics =
"spatial"`` the rod is the spatial one (`fe_beam.fem.spatial_rod`: tendons routed anywhere, tip
forces with a z component; laws nonstandard and reissner, the hyperelastic section law being
planar only for now: left out of the default laws with a note, refused when asked for); a tendon
out of the x-y plane or a tip force along z with the planar rod is a configuration error. The
departure of a rod from the solid is

    d = max over x of |r_rod(x) - r_solid(x)| / L,

the largest distance between the deformed centroids of the same reference section x (rod: the
axis point r = (x + u, v); solid: the area centroid of the deformed section X = x) over the
``[solid] backbone_points`` stations, relative to the length L. The summary states where along the
sweep d first exceeds 1 % and 5 % (linear interpolation between sweep points, from d = 0 unloaded).

Beside it, per law and sweep point: ``tip_distance_over_L`` = |r_rod(L) - r_solid(L)| / L and the
tip frame, ``tip_frame_angle`` = the angle of R_rod^T R_solid (its ``tip_frame_rotation_vector``,
through a quaternion: exact near 0), R_rod the rod's tip frame (planar rod: the rotation by theta
about z) and R_solid the best-fit rotation of the solid's tip face. A spatial rod's ``tip`` is
{u, v, w, R, rotation_vector, position} plus ``theta`` (the in-plane angle of its tangent, as the
solid's), and compare.csv adds ``solid_tip_w`` and ``<law>_tip_w``.

In contact (``[[obstacles]]``, 3D coordinates, frictionless, and ``[contact]``: the solid's,
`fe_beam.fem.solid.contact`), the rods are solved against the same obstacles: the spatial rod
against the 3D ones, the planar rod against their sections by z = 0
(`fe_beam.config.solid.planar_obstacles`: obstacles the same in every plane z = const across the
finger; any other is a configuration error). Per sweep point the solid's ``contact`` entries
(force, active_area, max_penetration, pressure_peak, extent, contact_length) and each rod's
(force, moment, active, max_penetration, contact_point_penetration, pressure_peak,
contact_length) are in the table, with
per obstacle ``contact_force_difference`` = |F_rod - F_solid| / max(|F_rod|, |F_solid|) (0 when
neither touches; the planar rod's F_z is 0) and the contact lengths: the rod's is the total
length of its active intervals, the solid's the extent along the reference x of its contact
patch (the exterior-facet vertices that carry pressure). See `CONTACT_MEASURE`.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam import exports, runctl
from fe_beam.analyses.result import Report, Result, exit_code
from fe_beam.analyses.solid import SolidRun, draw_obstacles_in_view, equilibrium_check
from fe_beam.analyses.solid_rod import backbone_distance, run_rod, tip_distance, tip_frame
from fe_beam.config.compare import (  # noqa: F401  (their home; re-exported)
    COMPARE_KEYS,
    MEASURE,
    RODS,
    THRESHOLDS,
    CompareConfig,
    _increasing,
    matched_law,
    parse_compare,
    rod_at,
)
from fe_beam.exports.outputs import _pyplot
from fe_beam.solvers.newton import LoadSteppingFailed

__all__ = ["run", "COMPARE_KEYS", "THRESHOLDS", "CompareConfig", "parse_compare", "run_compare"]

TIP_FRAME_MEASURE = (
    "tip_frame_angle = |rotation vector of R_rod^T R_solid| [rad], R_rod the rod's tip frame "
    "(planar rod: the rotation by theta about z), R_solid the best-fit rotation of the solid's "
    "tip face; tip_distance_over_L = |r_rod(L) - r_solid(L)| / L"
)


CONTACT_MEASURE = (
    "contact_force_difference = |F_rod - F_solid| / max(|F_rod|, |F_solid|) per obstacle (0 when "
    "neither touches it; F the force the obstacle exerts on the body, a planar rod's F_z = 0); "
    "contact_length: the rod's total length of its active intervals, the solid's the extent "
    "(max - min) of the reference x of its exterior-facet vertices that carry pressure"
)


def force_difference(rod_force, solid_force) -> float:
    """|F_rod - F_solid| / max(|F_rod|, |F_solid|) over three components (a planar rod's
    [Fx, Fy] gets Fz = 0); 0 when both vanish."""
    rod = np.zeros(3)
    rod[:len(rod_force)] = rod_force
    solid = np.asarray(solid_force, dtype=float)
    scale = max(float(np.linalg.norm(rod)), float(np.linalg.norm(solid)))
    return 0.0 if scale == 0 else float(np.linalg.norm(rod - solid)) / scale


def active_length(intervals) -> float:
    """The total length of a rod's contact intervals [[s0, s1], ...]."""
    return float(sum(b - a for a, b in intervals))


def rod_contact(entries: list[dict], solid: list[dict]) -> dict:
    """A rod's contact entries at a sweep point (``contact_length`` added) and, per obstacle,
    the relative force difference to the solid's and the contact lengths' difference."""
    rod = [{k: e[k] for k in ("name", "force", "moment", "active", "max_penetration",
                              "contact_point_penetration", "pressure_peak") if k in e}
           | {"contact_length": active_length(e["active"])} for e in entries]
    differences = [force_difference(r["force"], s["force"]) for r, s in zip(rod, solid,
                                                                          strict=True)]
    return {"contact": rod, "contact_force_difference": differences,
            "max_contact_force_difference": max(differences, default=0.0),
            "contact_length_difference": [r["contact_length"] - s["contact_length"]
                                          for r, s in zip(rod, solid, strict=True)]}


def crossing(factors, distances, threshold: float) -> dict | None:
    """First load factor at which ``distances`` exceed ``threshold`` (linear interpolation
    between sweep points, starting from 0 at load factor 0), with the first sweep point above."""
    previous_f, previous_d = 0.0, 0.0
    for f, d in zip(factors, distances, strict=True):
        if d is None:
            previous_f, previous_d = f, None
            continue
        if d > threshold:
            if previous_d is None:
                at = f
            else:
                at = previous_f + (threshold - previous_d) / (d - previous_d) * (f - previous_f)
            return {"load_factor": at, "first_sweep_point_above": f}
        previous_f, previous_d = f, d
    return None


def run_compare(raw: dict, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True) -> dict:
    """`compare_run` of ``raw`` parsed (for scripts that hold the TOML dict)."""
    return compare_run(parse_compare(raw), out, comm, progress)


def compare_run(parsed, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True) -> dict:
    """Run the sweep; write ``summary.json``, ``compare.csv`` and the plots into ``out`` (if not
    None, by rank 0) after every sweep point; return the summary dict (``status`` "converged", or
    "failed" when the solid stopped before the end of the sweep)."""
    started = time.perf_counter()
    config = parsed
    solid = config.solid
    out = None if out is None else Path(out)
    root = comm.rank == 0
    if out is not None and root:
        out.mkdir(parents=True, exist_ok=True)
    scale = _tension_scale(config)
    summary = {
        "status": "running",
        "message": "",
        "wall_time_s": 0.0,
        "measure": MEASURE,
        "thresholds": list(THRESHOLDS),
        "laws": list(config.laws),
        "sweep": {"load_factors": list(config.load_factors),
                  "tensions": [scale * f for f in config.load_factors] if scale else None},
        "table": [],
        "departures": {},
        "dofs": 0,
        "rod_dofs": 0,
        "model": solid.model_summary() | {
            "rod": {"E": solid.rod.model.material.E, "G": solid.rod.model.material.shear_modulus,
                    "constraint": solid.rod.model.options.constraint,
                    "elements": solid.rod.model.mesh.elements,
                    "degree": solid.rod.model.mesh.degree,
                    "kinematics": "spatial" if config.spatial else "planar"}},
        "notes": list(config.notes),
        "tip_frame_measure": TIP_FRAME_MEASURE,
    }
    if solid.obstacles:
        summary["contact_measure"] = CONTACT_MEASURE
        summary["obstacles"] = [{"name": o.name, "shape": o.shape} for o in solid.obstacles]
    if "hyperelastic" in config.laws:
        law = matched_law(solid)
        summary["model"]["rod"]["hyperelastic"] = {
            "material": solid.material_name, "coefficients": law.coefficients(),
            "volumetric": law.volumetric}

    def current() -> dict:
        summary["wall_time_s"] = time.perf_counter() - started
        summary["departures"] = _departures(summary["table"], config, scale)
        return summary

    # the solid's sweep points are slow: every file is brought up to date after each
    files = exports.Exports(_exports(out, config, current) if out is not None else [], comm,
                            throttle=False)
    try:
        run = SolidRun(solid, comm)
    except RuntimeError as error:
        summary |= {"status": "failed", "message": str(error)}
        files.finish(current())
        if out is not None:
            comm.barrier()
        return summary
    summary["dofs"] = run.dofs
    summary["linear_solver_resolved"] = run.problem.linear_solver
    files.start(current())  # status "running" from the start
    balances = []  # every converged solid step's equilibrium (the certificate)

    def on_step(record: dict, last: dict) -> None:
        last.update(record)
        balances.append({k: record[k] for k in ("load_factor", "equilibrium")})

    try:
        for factor in config.load_factors:
            last = {}
            try:
                run.advance(factor, solid.stepping, lambda r, last=last: on_step(r, last),
                            progress=progress, label=f"solid to {factor:.3g}")
            except LoadSteppingFailed as failure:
                summary |= {"status": "failed", "message": str(failure)}
                break
            row = {"load_factor": factor}
            row |= {k: last[k] for k in ("tension", "tensions") if k in last}
            row["solid"] = {k: last[k] for k in ("tip", "backbone", "max_principal_stretch",
                                                 "max_principal_stretch_bulk", "contact",
                                                 "equilibrium")
                            if k in last}
            row["rod"] = {}
            for law in config.laws:
                rod = run_rod(rod_at(solid.rod, law, factor, solid), solid.stations, comm)
                summary["rod_dofs"] = rod["dofs"]
                entry = {"status": rod["status"], "message": rod["message"]}
                reached = rod["status"] == "converged" and rod["backbone"] is not None
                if reached:
                    distance = backbone_distance(rod["backbone"], last["backbone"])
                    tip = rod["steps"][-1]["tip"]
                    frame = tip_frame(tip, last["tip"])
                    entry |= {
                        "tip": tip,
                        "backbone": rod["backbone"],
                        "distance_over_L": distance["max"] / solid.length,
                        "distance_x": distance["x"],
                        "tip_distance_over_L": tip_distance(tip, last["tip"]) / solid.length,
                        "tip_frame_angle": frame["angle"],
                        "tip_frame_rotation_vector": frame["rotation_vector"],
                    }
                    if "contact" in last:
                        entry |= rod_contact(rod["steps"][-1]["contact"], last["contact"])
                row["rod"][law] = entry
            summary["table"].append(row)
            files.on_step(row)
        else:
            summary["status"] = "converged"
    except runctl.Interrupted as stop:
        last = summary["table"][-1]["load_factor"] if summary["table"] else 0.0
        summary |= stop.stopped(f"load factor {last:.4g} of the sweep",
                                f"after load factor {last:.6g}")
        raise
    finally:
        run.destroy()
        if balances:  # the solid's global equilibrium over all its steps
            summary["checks"] = [equilibrium_check(balances)]
        files.finish(current())  # pictures unless interrupted (then those of the last point)
    if out is not None:
        comm.barrier()  # the files are complete on return, whichever rank looks
    return summary


def _tension_scale(config: CompareConfig) -> float | None:
    """Tension at load factor 1 when the sweep is over one tendon's tension, else None."""
    if not config.tension_axis:
        return None
    return float(config.solid.rod.tendons[0].tension)


def _departures(rows: list[dict], config: CompareConfig, scale: float | None) -> dict:
    result = {}
    factors = [r["load_factor"] for r in rows]
    for law in config.laws:
        distances = [r["rod"][law].get("distance_over_L") for r in rows]
        known = [d for d in distances if d is not None]
        entry = {"max_distance_over_L": max(known) if known else None}
        words = []
        for threshold in THRESHOLDS:
            found = crossing(factors, distances, threshold) if rows else None
            if found is not None and scale is not None:
                found |= {"tension": scale * found["load_factor"],
                          "first_sweep_tension_above": scale * found["first_sweep_point_above"]}
            key = f"above_{round(threshold * 100)}_percent"
            entry[key] = found
            words.append(_sentence(threshold, found, scale))
        biggest = entry["max_distance_over_L"]
        entry["statement"] = (
            f"rod ({law}) vs 3D solid, d = max_x |r_rod - r_solid| / L: " + "; ".join(words)
            + (f" (largest d in the sweep: {100 * biggest:.3g} %)" if biggest is not None else "")
        )
        if getattr(config.solid, "obstacles", ()):
            found = [(r["rod"][law]["max_contact_force_difference"], r["load_factor"])
                     for r in rows if "max_contact_force_difference" in r["rod"][law]]
            top = max(found, default=None)
            entry["max_contact_force_difference"] = None if top is None else top[0]
            entry["contact_statement"] = (
                f"rod ({law}) vs 3D solid in contact: " + (
                    "no sweep point with a result" if top is None else
                    f"largest |F_rod - F_solid| / max(|F_rod|, |F_solid|) over the obstacles "
                    f"{100 * top[0]:.3g} % (at {sweep_label(top[1] * (scale or 1.0), bool(scale))})"
                ))
        result[law] = entry
    return result


def _sentence(threshold: float, found: dict | None, scale: float | None) -> str:
    what = f"d > {100 * threshold:g} %"
    if found is None:
        return f"{what} nowhere in the sweep"
    if scale is not None:
        return (f"{what} from tension {found['tension']:.4g} N (interpolated; first sweep point "
                f"above: {found['first_sweep_tension_above']:.4g} N)")
    return (f"{what} from load factor {found['load_factor']:.4g} (interpolated; first sweep "
            f"point above: {found['first_sweep_point_above']:.4g})")


def _columns(first: dict | None, laws, spatial: bool = False, obstacles: int = 0
             ) -> list[exports.Column]:
    """compare.csv: the sweep point, the solid's tip, each rod's tip, distance and tip frame
    angle (empty cells where the rod did not converge); a spatial rod adds the tips' w; per
    obstacle i the contact forces and lengths (`_contact_columns`)."""
    count = len(first.get("tensions", [])) if first else 0

    def rod_tip(row: dict, law: str) -> dict:
        return row["rod"][law].get("tip") or {}

    columns = [exports.Column("load_factor", lambda r: r["load_factor"]),
               *exports.indexed_columns("tension", count, lambda r: r["tensions"]),
               *exports.tip_columns("solid_tip_", lambda r: r["solid"]["tip"])]
    if spatial:  # the solid's and the rods' w after the planar columns
        columns.append(exports.Column("solid_tip_w", lambda r: r["solid"]["tip"]["w"]))
    for law in laws:
        columns += [exports.Column(f"{law}_tip_{k}",
                                   lambda r, law=law, k=k: rod_tip(r, law).get(k, ""))
                    for k in ("u", "v", "theta")]
        columns.append(exports.Column(f"{law}_distance_over_L",
                                      lambda r, law=law: r["rod"][law].get("distance_over_L", "")))
        if spatial:
            columns.append(exports.Column(f"{law}_tip_w",
                                          lambda r, law=law: rod_tip(r, law).get("w", "")))
        columns.append(exports.Column(
            f"{law}_tip_frame_angle", lambda r, law=law: r["rod"][law].get("tip_frame_angle", "")))
    return columns + _contact_columns(obstacles, laws, spatial)


def _contact_columns(count: int, laws, spatial: bool) -> list[exports.Column]:
    """Per obstacle i: ``solid_contact<i>_F{x,y,z}``, ``solid_contact<i>_length`` and per law
    ``<law>_contact<i>_F{x,y(,z)}``, ``<law>_contact<i>_length``,
    ``<law>_contact<i>_force_difference`` (empty where the rod did not converge)."""
    columns = []

    def solid(row, i):
        return row["solid"]["contact"][i]

    def rod(row, law, i, key, k=None):
        entry = row["rod"][law]
        if "contact" not in entry:
            return ""
        value = (entry["contact_force_difference"][i] if key == "force_difference"
                 else entry["contact"][i][key])
        return value if k is None else value[k]

    rod_axes = "xyz" if spatial else "xy"
    for i in range(count):
        columns += [exports.Column(f"solid_contact{i}_F{a}",
                                   lambda r, i=i, k=k: solid(r, i)["force"][k])
                    for k, a in enumerate("xyz")]
        columns.append(exports.Column(f"solid_contact{i}_length",
                                      lambda r, i=i: solid(r, i)["contact_length"]))
        for law in laws:
            columns += [exports.Column(f"{law}_contact{i}_F{a}",
                                       lambda r, law=law, i=i, k=k: rod(r, law, i, "force", k))
                        for k, a in enumerate(rod_axes)]
            columns += [exports.Column(f"{law}_contact{i}_length",
                                       lambda r, law=law, i=i: rod(r, law, i, "contact_length")),
                        exports.Column(f"{law}_contact{i}_force_difference",
                                       lambda r, law=law, i=i: rod(r, law, i,
                                                                   "force_difference"))]
    return columns


def _exports(out: Path, config: CompareConfig, content, every_step: bool = True) -> list:
    """summary.json, compare.csv and the pictures (``every_step``: redrawn after each point)."""
    return [exports.SummaryExport(out / "summary.json", content),
            exports.CSVExport(out / "compare.csv",
                              lambda first: _columns(first, config.laws, config.spatial,
                                                     len(getattr(config.solid, "obstacles",
                                                                 ())))),
            exports.PlotExport(lambda summary: _plot(out, summary, config)
                               if summary["table"] and config.solid.output.plots else None,
                               content, every_step)]


def _write_outputs(out: Path, summary: dict, config: CompareConfig) -> None:
    """The files of a finished sweep (``summary``) at once (on the calling rank)."""
    files = exports.Exports(_exports(out, config, lambda: summary, every_step=False))
    for row in summary["table"]:
        files.on_step(row)
    files.finish(summary)


STYLES = {"solid": ("-", "3D solid"), "nonstandard": ("--", "rod, non-standard law"),
          "reissner": (":", "rod, Reissner law"),
          "hyperelastic": ("-.", "rod, section law of the 3D material")}
COLOURS = {"solid": "tab:blue", "nonstandard": "tab:orange", "reissner": "tab:green",
           "hyperelastic": "tab:red"}


def sweep_label(value: float, tension_axis: bool) -> str:
    """A sweep point with its unit: "tension 0.5 N" or "load factor 0.5"."""
    return f"tension {value:.3g} N" if tension_axis else f"load factor {value:.3g}"


def _plot(out: Path, summary: dict, config: CompareConfig) -> None:
    plt = _pyplot()
    rows = summary["table"]
    tensions = summary["sweep"]["tensions"]
    label = "tension [N]" if tensions else "load factor"
    axis_values = [r.get("tension", r["load_factor"]) if tensions else r["load_factor"]
                   for r in rows]
    length = config.solid.length
    obstacles = getattr(config.solid, "obstacles", ())

    views = ((("v", "y + v [m]"), ("w", "z + w [m]")) if getattr(config, "spatial", False)
             else (("v", "y + v [m]"),))
    with exports.figure(out / "backbones.png", 1, len(views), figsize=(9 + 5 * (len(views) - 1),
                                                                       5),
                        squeeze=False) as (_, axes):
        colours = plt.cm.viridis(np.linspace(0, 0.9, len(rows)))
        for axis, (key, text_y) in zip(axes[0], views, strict=True):
            axis.plot([0, length], [0, 0], color="0.7", lw=1, label="undeformed")
            for row, value, colour in zip(rows, axis_values, colours, strict=True):
                models = [("solid", row["solid"].get("backbone"))]
                models += [(law, row["rod"][law].get("backbone")) for law in config.laws]
                for name, backbone in models:
                    if backbone is None:
                        continue
                    style, text = STYLES[name]
                    axis.plot(np.add(backbone["x"], backbone["u"]),
                              backbone.get(key, np.zeros(len(backbone["x"]))), style,
                              color=colour, lw=1.6,
                              label=f"{text}, {sweep_label(value, bool(tensions))}")
            if obstacles:  # the obstacles (3D) seen along the remaining axis
                geometry = config.solid.geometry
                draw_obstacles_in_view(axis, obstacles, 1 if key == "v" else 2,
                                       geometry.height_base if key == "v" else geometry.width)
            axis.set_xlabel("x + u [m]")
            axis.set_ylabel(text_y)
            axis.set_title("Backbones: 3D solid (solid lines) vs rod laws (dashed, dotted)"
                           + (": section centroids, obstacles in grey" if obstacles else "")
                           + (f" ({text_y[0]} view)" if getattr(config, "spatial", False) else ""),
                             fontsize=9)
            axis.grid(alpha=0.3)
        axes[0][-1].legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.01, 1.0))

    with exports.figure(out / "tip_vs_tension.png", 1, 4, figsize=(15, 3.6)) as (_, axes):
        names = [("solid", None)] + [(law, law) for law in config.laws]
        for axis, key, unit in zip(axes[:3], ("u", "v", "theta"), ("m", "m", "rad"), strict=True):
            for name, law in names:
                style, text = STYLES[name]
                points = [
                    (value, (row["solid"] if law is None else row["rod"][law]).get("tip"))
                    for row, value in zip(rows, axis_values, strict=True)
                ]
                xs = [p for p, tip in points if tip]
                ys = [tip[key] for _, tip in points if tip]
                axis.plot(xs, ys, style, marker="o", ms=3, color=COLOURS[name], label=text)
            axis.set_xlabel(label)
            axis.set_ylabel(f"tip {key} [{unit}]")
            axis.grid(alpha=0.3)
            axis.legend(fontsize=7)
        axis = axes[3]
        for law in config.laws:
            style, text = STYLES[law]
            pairs = [(v, r["rod"][law].get("distance_over_L")) for r, v in zip(rows, axis_values,
                                                                                 strict=True)]
            axis.plot([v for v, d in pairs if d is not None],
                      [100 * d for _, d in pairs if d is not None], style, marker="o", ms=3,
                      color=COLOURS[law], label=text)
        for threshold in THRESHOLDS:
            axis.axhline(100 * threshold, color="0.6", lw=0.8)
        axis.set_xlabel(label)
        axis.set_ylabel("max_x |r_rod - r_solid| / L [%]")
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7)
    if obstacles:
        _plot_contact(out, rows, axis_values, label, config)


def _plot_contact(out: Path, rows: list[dict], axis_values, label: str,
                  config: CompareConfig) -> None:
    """contact.png: per obstacle, |F| of the solid and of each rod and the contact lengths
    against the sweep."""
    names = [o.name for o in config.solid.obstacles]
    with exports.figure(out / "contact.png", 1, 2, figsize=(11, 3.8)) as (_, (left, right)):
        for i, name in enumerate(names):
            models = [("solid", lambda r, i=i: r["solid"]["contact"][i])]
            models += [(law, lambda r, law=law, i=i: r["rod"][law]["contact"][i]
                        if "contact" in r["rod"][law] else None) for law in config.laws]
            for model, entry_of in models:
                style, text = STYLES[model]
                points = [(v, entry_of(r)) for r, v in zip(rows, axis_values, strict=True)]
                points = [(v, e) for v, e in points if e is not None]
                xs = [v for v, _ in points]
                left.plot(xs, [float(np.linalg.norm(e["force"])) for _, e in points], style,
                          marker="o", ms=3, color=COLOURS[model], label=f"{text}, {name}")
                right.plot(xs, [1e3 * e["contact_length"] for _, e in points], style,
                           marker="o", ms=3, color=COLOURS[model], label=f"{text}, {name}")
        for axis, text in ((left, "|contact force| [N]"), (right, "contact length [mm]")):
            axis.set_xlabel(label)
            axis.set_ylabel(text)
            axis.grid(alpha=0.3)
            axis.legend(fontsize=7)
        left.set_title("Contact force: 3D solid vs rods", fontsize=9)
        right.set_title("Contact length (rod: active intervals; solid: extent of the patch "
                        "along x)", fontsize=8)


def run(validated, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True,
        echo=None) -> Result:
    """``fe-beam compare`` (the driver contract, `fe_beam.analyses.result`)."""
    summary = compare_run(validated.parsed, out, comm, progress)
    config_spatial = validated.parsed.spatial
    report = Report(echo)
    for note in summary.get("notes", []):
        report.err(f"fe-beam compare: note: {note}")
    for row in summary["table"]:
        where = f"tension {row['tension']:.4g} N" if "tension" in row else (
            f"load factor {row['load_factor']:.4g}")
        solid_tip = row["solid"]["tip"]
        parts = [f"3D theta {solid_tip['theta']:.4g}" + (
            f", w {solid_tip['w']:.4g} m" if config_spatial else "")]
        for law, rod in row["rod"].items():
            if "distance_over_L" in rod:
                parts.append(f"{law} theta {rod['tip']['theta']:.4g}, "
                             + (f"w {rod['tip']['w']:.4g} m, " if config_spatial else "")
                             + f"d/L {rod['distance_over_L']:.3g}, tip frame angle "
                             f"{rod['tip_frame_angle']:.3g} rad")
            else:
                parts.append(f"{law} {rod['status']}")
        report.out(f"{where}: " + "; ".join(parts))
        for i, solid_entry in enumerate(row["solid"].get("contact", [])):
            force = np.linalg.norm(solid_entry["force"])
            words = [f"3D |F| {force:.4g} N, length {solid_entry['contact_length']:.4g} m"]
            for law, rod in row["rod"].items():
                if "contact" in rod:
                    words.append(f"{law} |F| {np.linalg.norm(rod['contact'][i]['force']):.4g} N "
                                 f"({100 * rod['contact_force_difference'][i]:.3g} % apart), "
                                 f"length {rod['contact'][i]['contact_length']:.4g} m")
            report.out(f"  contact with {solid_entry['name']!r}: " + "; ".join(words))
    for entry in summary["departures"].values():
        report.out(entry["statement"])
        if "contact_statement" in entry:
            report.out(entry["contact_statement"])
    report.out(f"{summary['wall_time_s']:.2f} s; results in {out}")
    return Result("compare", summary, exit_code(report, summary, "fe-beam"), report.lines)

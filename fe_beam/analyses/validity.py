"""``fe-beam validity CONFIG.toml --out DIR``: a map of where the rod agrees with the 3D solid.

The configuration is the one of ``fe-beam compare`` plus ``[validity]``
(`fe_beam.config.validity.VALIDITY_KEYS`): two map axes, each a numeric config key and its values.
Every grid point is the configuration with those values, run exactly as ``fe-beam compare`` with
``[compare] load_factors = [1.0]`` (`fe_beam.analyses.compare.run_compare`: the solid at the
configured
mesh and the rod with each law), so its numbers are those of ``fe-beam compare`` at that point.
With ``second_mesh_ratio`` the solid is solved again on a mesh ``ratio`` times finer (or coarser)
for a Richardson estimate of its own discretisation error (docs/theory.md, Validity map).

Per point, with L the length of that point's finger:

- ``backbone_distance`` = max over the stations x of |r_rod(x) - r_solid(x)| / L (as compare),
- ``tip_error`` = {``distance_over_L``: |r_rod(L) - r_solid(L)| / L, ``rotation``: |theta_rod -
  theta_solid| [rad], ``frame_angle``: the angle of R_rod^T R_solid [rad], the tip frames'
  relative rotation}, and ``tip_frame_angle`` (the same, as ``fe-beam compare`` names it),
- with ``[model] kinematics = "spatial"`` the rod is the spatial one (``fe-beam compare``): the
  distances are over the three components, the CSV adds ``solid_tip_w`` and ``<law>_tip_w``,
- the solid's ``discretisation_error`` = {``tip``, ``backbone`` (distances / L), ``rotation``
  [rad]} of the configured mesh, or None without a second mesh,
- with ``[[obstacles]]`` (the rod and the solid in contact, as ``fe-beam compare``):
  ``contact_force_difference`` = the largest over the obstacles of |F_rod - F_solid| /
  max(|F_rod|, |F_solid|), with the solid's and each rod's ``contact`` entries.

``[validity] metric`` chooses what validity.png and the statements' 1 % / 5 % counts show:
``backbone_distance`` (default) or ``contact_force_difference``.

Resumable: every point is written to ``DIR/points/<i>_<j>.json`` (atomically) when it finishes,
with a fingerprint of its configuration; a rerun reuses the finished points whose configuration
is unchanged. A point whose solve fails is recorded with the reason (status "failed"); the map
goes on. Under ``mpirun -n N`` each rank solves its own points on ``MPI.COMM_SELF``.
Files: ``summary.json``, ``validity.csv``, ``validity.png`` and ``points/``.
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam import analyses, certify, runctl
from fe_beam.analyses.result import Report, Result, exit_code
from fe_beam.analyses.solid_rod import tip_distance, tip_frame
from fe_beam.analyses.validity_workers import worker_point, worker_start
from fe_beam.config.compare import parse_compare
from fe_beam.config.validity import (  # noqa: F401  (their home; re-exported)
    VALIDITY_KEYS,
    GridPoint,
    ValidityConfig,
    parse_validity,
    second_mesh,
    third_mesh_ratio,
)
from fe_beam.exports.outputs import atomic_write_json, figure, write_csv
from fe_beam.progress import ProgressBar
from fe_beam.solvers.newton import LoadSteppingFailed

__all__ = ["run", "VALIDITY_KEYS", "parse_validity", "richardson_error", "run_validity"]

THRESHOLDS = (0.01, 0.05)
POINTS = "points"


def richardson_error(configured: np.ndarray, second: np.ndarray, ratio: float,
                     order: float) -> tuple[np.ndarray, np.ndarray]:
    """(estimated error of ``configured``, extrapolated value) from the same quantity on the
    configured mesh h and on h / ``ratio``, for convergence order ``order``: with R the ratio of
    the coarse to the fine size, q* = q_fine + (q_fine - q_coarse) / (R^p - 1); the error of the
    configured value is |q* - q_configured|."""
    configured, second = np.asarray(configured, float), np.asarray(second, float)
    fine, coarse = (second, configured) if ratio > 1 else (configured, second)
    big = max(ratio, 1.0 / ratio)
    extrapolated = fine + (fine - coarse) / (big**order - 1.0)
    return extrapolated - configured, extrapolated


def _point_path(out: Path, point: GridPoint) -> Path:
    return out / POINTS / f"{point.name}.json"


def _finished(out: Path, point: GridPoint) -> dict | None:
    """The stored record of ``point`` when it is complete and of the same configuration."""
    try:
        record = json.loads(_point_path(out, point).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("hash") != point.hash:
        return None
    if record.get("status") not in ("converged", "failed"):
        return None
    return record


def _tip_error(rod_tip: dict, solid_tip: dict, length: float) -> dict:
    """The tip's distance / L (a spatial rod: over u, v, w; a planar one: u, v), the in-plane
    ``rotation`` |theta_rod - theta_solid| and the tip frame's angle (`tip_frame`)."""
    if "w" in rod_tip:
        distance = tip_distance(rod_tip, solid_tip)
    else:
        distance = math.hypot(rod_tip["u"] - solid_tip["u"], rod_tip["v"] - solid_tip["v"])
    return {"distance_over_L": distance / length,
            "rotation": abs(rod_tip["theta"] - solid_tip["theta"]),
            "frame_angle": tip_frame(rod_tip, solid_tip)["angle"]}


def _solve_mesh(point: GridPoint, ratio: float, comm, label: str) -> tuple[dict, object, int]:
    """The point's solid with ``[solid] mesh_size / ratio`` (the code of ``fe-beam compare``:
    `fe_beam.analyses.solid.SolidRun`): (its last record, its configuration, its dofs)."""
    parsed = parse_compare(second_mesh(point.raw, point.parsed, ratio)).solid
    run = analyses.solid.SolidRun(parsed, comm)
    last = {}
    try:
        run.advance(1.0, parsed.stepping, last.update, progress=False, label=label)
        dofs = run.dofs
    finally:
        run.destroy()
    return last, parsed, dofs


def _discretisation_error(point: GridPoint, solid: dict, config: ValidityConfig, comm) -> dict:
    """Solve the point's solid on the second mesh and estimate the configured mesh's error with
    the assumed order; then certify the estimate (`mesh_check`) with a third, coarser mesh
    (sizes h R, h, h / R for a finer second mesh, h R^2, h R, h for a coarser one: cheap)."""
    ratio, order = config.second_mesh_ratio, config.order
    last, parsed, dofs = _solve_mesh(point, ratio, comm, "second mesh")
    length = parsed.length
    tip, other = solid["tip"], last["tip"]
    # the planar map's estimate over (u, v); a spatial rod's over (u, v, w)
    keys = ("u", "v", "theta", "w") if point.parsed.spatial else ("u", "v", "theta")
    error, extrapolated = richardson_error([tip[k] for k in keys], [other[k] for k in keys],
                                           ratio, order)
    a, b = solid["backbone"], last["backbone"]
    du, _ = richardson_error(a["u"], b["u"], ratio, order)
    dv, _ = richardson_error(a["v"], b["v"], ratio, order)
    dw = richardson_error(a["w"], b["w"], ratio, order)[0] if point.parsed.spatial else 0.0
    estimate = {
        "tip": float(np.linalg.norm([error[0], error[1]] + list(error[3:]))) / length,
        "rotation": abs(float(error[2])),
        "backbone": float(np.max(np.sqrt(du**2 + dv**2 + dw**2))) / length,
    }
    third, third_parsed, _ = _solve_mesh(point, third_mesh_ratio(ratio), comm, "third mesh")
    configured = {"tip": tip, "backbone": solid["backbone"]}
    levels = ([third, configured, last] if ratio > 1 else [third, last, configured])
    check = mesh_check(levels, max(ratio, 1.0 / ratio), order, estimate, length,
                       configured_finest=ratio < 1, spatial=point.parsed.spatial,
                       theoretical_order=solid_theoretical_order(point.parsed.solid))
    return estimate | {
        "second_mesh_size": parsed.sizes.size,
        "second_dofs": dofs,
        "second_tip": other,
        "extrapolated_tip": dict(zip(keys, map(float, extrapolated), strict=True)),
        "order": order,
        "measure": "Richardson: |q* - q_h|, q* = q_fine + (q_fine - q_coarse) / (R^p - 1)",
        "mesh_check": check | {"third_mesh_size": third_parsed.sizes.size,
                               "third_tip": third["tip"]},
    }


def solid_theoretical_order(solid) -> float:
    """The highest convergence order a mesh check may use for the 3D solid: degree + 1 (the
    displacements' L2 order of Lagrange elements of that degree)."""
    return float(solid.discretization.degree) + 1.0


#: changes below this (relative: of L for positions, of 1 rad for angles) are round-off
MESH_CHECK_NOISE = 1e-10


#: an observed order below this certifies nothing (the changes barely shrink: noise, or the
#: meshes are not in the asymptotic range)
MIN_OBSERVED_ORDER = 0.5


def mesh_check(levels: list[dict], ratio: float, order: float, estimate: dict, length: float,
               configured_finest: bool, spatial: bool = False,
               theoretical_order: float | None = None) -> dict:
    """Is the reported error (`_discretisation_error`, Richardson with the assumed ``order``)
    an honest bound? ``levels`` are three solid records ({"tip", "backbone"}) on meshes
    h R, h, h / R (coarse to fine, ``ratio`` = R > 1), the configured one the middle level
    (``configured_finest``: the last). Per quantity (the tip position / L, the tip rotation
    theta, the backbone / L: the largest over the stations) with d1, d2 the successive changes
    (vectors for positions):

        p_obs = log(|d1| / |d2|) / log R            (observed order)
        e_obs = |d2| R^p_obs / (R^p_obs - 1)       (middle level) or |d2| / (R^p_obs - 1)
        value = e_obs / (the reported estimate)     (<= 1: the reported error is a bound)

    The bound uses p = min(p_obs, ``theoretical_order``) (the element's order, degree + 1 for
    the solid's displacements: an observed 7.7 of a P2 solid is a lucky cancellation of
    unstructured meshes, and would shrink the bound 10-fold). A change that does not shrink
    (p_obs <= 0), shrinks too slowly (p_obs < `MIN_OBSERVED_ORDER`) or reverses
    (d1 . d2 < 0) has no error bound: value inf. Changes at round-off (`MESH_CHECK_NOISE`)
    give 0. Returns {"value" (the largest), "quantities": {name: {"value", "observed_order",
    "order_used", "changes"}}}."""
    keys = ("u", "v", "w") if spatial else ("u", "v")

    def tip_vector(record):
        return np.array([record["tip"].get(k, 0.0) for k in keys]) / length

    def backbone(record):
        b = record["backbone"]
        return np.array([b[k] for k in keys]).T / length  # (stations, components)

    quantities = {}
    series = {
        "tip": [tip_vector(r) for r in levels],
        "rotation": [np.array([r["tip"]["theta"]]) for r in levels],
        "backbone": [backbone(r) for r in levels],
    }
    for name, (q0, q1, q2) in series.items():
        d1, d2 = q1 - q0, q2 - q1
        n1 = float(np.max(np.linalg.norm(np.atleast_2d(d1), axis=-1)))
        n2 = float(np.max(np.linalg.norm(np.atleast_2d(d2), axis=-1)))
        reported = estimate[name]
        observed = used = None
        if n2 <= MESH_CHECK_NOISE:
            value = 0.0
        elif n1 <= MESH_CHECK_NOISE or float(np.sum(d1 * d2)) <= 0 or n2 >= n1:
            value = math.inf
        else:
            observed = math.log(n1 / n2) / math.log(ratio)
            used = observed if theoretical_order is None else min(observed, theoretical_order)
            if observed < MIN_OBSERVED_ORDER:
                value = math.inf
            else:
                factor = ratio**used - 1.0
                bound = n2 / factor if configured_finest else n2 * ratio**used / factor
                value = bound / reported if reported > 0 else math.inf
        quantities[name] = {"value": value, "observed_order": observed, "order_used": used,
                            "changes": [n1, n2]}
    return {"value": max(q["value"] for q in quantities.values()), "quantities": quantities,
            "order": order}


def solve_point(point: GridPoint, config: ValidityConfig, comm) -> dict:
    """One point of the map (collective on ``comm``): ``fe-beam compare`` at full load, the
    errors, and (``second_mesh_ratio``) the solid on the second mesh."""
    started = time.perf_counter()
    record = {"i": point.i, "j": point.j, "x": point.x, "y": point.y, "hash": point.hash,
              "status": "converged", "message": "", "solid": None, "rod": {}}
    length = point.parsed.solid.length
    try:
        compared = analyses.compare.run_compare(point.raw, None, comm, progress=False)
        if compared["table"]:
            row = compared["table"][-1]
            record["solid"] = {k: row["solid"][k] for k in ("tip", "backbone",
                                                             "max_principal_stretch")} | {
                "dofs": compared["dofs"], "mesh_size": point.parsed.solid.sizes.size,
                "discretisation_error": None} | (
                {"contact": row["solid"]["contact"]} if "contact" in row["solid"] else {})
            for law, rod in row["rod"].items():
                entry = {"status": rod["status"], "message": rod["message"]}
                if "tip" in rod:
                    entry |= {"tip": rod["tip"],
                              "tip_error": _tip_error(rod["tip"], row["solid"]["tip"], length),
                              "backbone_distance": rod["distance_over_L"],
                              "backbone_distance_x": rod["distance_x"],
                              "tip_frame_angle": rod["tip_frame_angle"]}
                    if "contact" in rod:
                        entry |= {"contact_force_difference":
                                  rod["max_contact_force_difference"],
                                  "contact": rod["contact"]}
                elif record["status"] == "converged":
                    record |= {"status": "failed",
                               "message": f"rod ({law}): {rod['message'] or rod['status']}"}
                record["rod"][law] = entry
        if compared["status"] != "converged":
            record |= {"status": "failed", "message": f"solid: {compared['message']}"}
        if record["status"] == "converged" and config.second_mesh_ratio is not None:
            try:
                record["solid"]["discretisation_error"] = _discretisation_error(
                    point, record["solid"], config, comm)
            except Exception as error:  # the second solve is part of the point
                if isinstance(error, runctl.Interrupted):
                    raise
                record |= {"status": "failed",
                           "message": f"solid on the second mesh: {_reason(error)}"}
    except runctl.Interrupted:
        raise
    except Exception as error:  # a solver failure ends this point, not the map
        record |= {"status": "failed", "message": _reason(error)}
    record["wall_time_s"] = time.perf_counter() - started
    return record


def _reason(error: BaseException) -> str:
    if isinstance(error, LoadSteppingFailed):
        return str(error)
    return f"{type(error).__name__}: {error}"


def _summary_point(record: dict) -> dict:
    """A point as summary.json lists it (the backbones stay in the point's file)."""
    entry = {k: record.get(k) for k in ("i", "j", "x", "y", "status", "message")}
    solid = record.get("solid")
    entry["solid"] = None if solid is None else {
        k: solid[k] for k in ("tip", "dofs", "mesh_size", "discretisation_error", "contact")
        if k in solid}
    entry["rod"] = {law: {k: v for k, v in rod.items() if k != "backbone"}
                    for law, rod in record.get("rod", {}).items()}
    return entry


def _collect(out: Path, config: ValidityConfig) -> list[dict]:
    """The finished points on disk, in grid order."""
    found = []
    for point in config.points:
        record = _finished(out, point)
        if record is not None:
            found.append(record)
    return found


def _statements(points: list[dict], config: ValidityConfig, total: int) -> dict:
    """Per law: the points below 1 % and 5 % and the largest departure."""
    result = {}
    metric = config.metric
    for law in config.laws:
        values = [(p["rod"][law][metric], p) for p in points
                  if p["status"] == "converged" and metric in p["rod"].get(law, {})]
        entry = {"points": len(values), "metric": metric}
        if _contact(config):
            forces = [p["rod"][law]["contact_force_difference"] for p in points
                      if p["status"] == "converged"
                      and "contact_force_difference" in p["rod"].get(law, {})]
            entry["max_contact_force_difference"] = max(forces, default=None)
        for threshold in THRESHOLDS:
            entry[f"below_{round(threshold * 100)}_percent"] = sum(d < threshold
                                                                   for d, _ in values)
        distances = [p["rod"][law]["backbone_distance"] for p in points
                     if p["status"] == "converged"
                     and "backbone_distance" in p["rod"].get(law, {})]
        entry["max_backbone_distance"] = max(distances, default=None)
        if values:
            d, p = max(values, key=lambda item: item[0])
            entry["max_at"] = {"x": p["x"], "y": p["y"]}
            where = f"{config.x} = {p['x']:g}" + (
                f", {config.y} = {p['y']:g}" if config.y is not None else "")
            entry["statement"] = (
                f"rod ({law}) vs 3D solid, {METRIC_TEXT[metric]}: d < 1 % at "
                f"{entry['below_1_percent']} and d < 5 % at {entry['below_5_percent']} of "
                f"{len(values)} points (of {total}); largest d = {100 * d:.3g} % at {where}")
        else:
            entry["statement"] = f"rod ({law}): no point with a result"
        result[law] = entry
    return result


#: the statements' and the pictures' words for each [validity] metric
METRIC_TEXT = {
    "backbone_distance": "d = max_x |r_rod - r_solid| / L",
    "contact_force_difference": "d = max over the obstacles of |F_rod - F_solid| / "
                                "max(|F_rod|, |F_solid|)",
}
METRIC_AXIS = {
    "backbone_distance": "max_x |r_rod - r_solid| / L [%]",
    "contact_force_difference": "contact force difference [%]",
}


def _contact(config: ValidityConfig) -> bool:
    """The map's rods and solid are in contact ([[obstacles]])."""
    return bool(config.points) and bool(config.points[0].parsed.solid.obstacles)


def run_validity(raw: dict, out: Path, comm=MPI.COMM_WORLD, progress: bool = True,
                 say=None) -> dict:
    """`validity_run` of ``raw`` parsed (for scripts that hold the TOML dict)."""
    return validity_run(raw, parse_validity(raw), out, comm, progress, say)


def validity_run(raw: dict, parsed, out: Path, comm=MPI.COMM_WORLD, progress: bool = True,
                 say=None) -> dict:
    """Compute the map's unfinished points (each rank its share, on COMM_SELF when there are
    several ranks), writing each into ``out/points`` as it finishes; then summary.json,
    validity.csv and validity.png (rank 0). Returns the summary (every rank)."""
    started = time.perf_counter()
    config = parsed
    out = Path(out)
    root = comm.rank == 0

    def tell(text: str) -> None:
        if root:
            (say or (lambda t: print(t, file=sys.stderr, flush=True)))(text)

    if root:
        (out / POINTS).mkdir(parents=True, exist_ok=True)
    done = [p.name for p in config.points if _finished(out, p) is not None] if root else None
    done = set(comm.bcast(done, root=0) if comm.size > 1 else done)
    todo = [p for p in config.points if p.name not in done]
    if done:
        tell(f"fe-beam validity: {len(done)} of {len(config.points)} points already finished in "
             f"{out / POINTS} (skipped; delete a point's file to recompute it)")
    if root:  # summary.json from the start (status "running")
        _write(out, config, started, "running", "", len(done))
    mine = todo[comm.rank::comm.size]
    local = MPI.COMM_SELF if comm.size > 1 else comm
    bar = ProgressBar(local, total=len(mine), label="validity points", enabled=progress and root,
                      unit="pt")
    computed = 0

    def finished(point: GridPoint, record: dict) -> None:
        nonlocal computed
        atomic_write_json(_point_path(out, point), record)
        computed += 1
        if root:  # summary.json and validity.csv up to date (the points on disk so far)
            _write(out, config, started, "running", "", len(done))
        bar.update(computed, f"{point.name}: {record['status']}")

    workers = min(config.workers, len(mine))
    if workers > 1 and comm.size > 1:
        tell(f"fe-beam validity: note: [validity] workers = {config.workers} is not used under "
             f"mpirun: the {comm.size} ranks share the points")
    try:
        if workers > 1 and comm.size == 1:
            _run_workers(raw, config, mine, workers, finished, comm)
        else:
            for point in mine:
                finished(point, solve_point(point, config, local))
        bar.close()
        if comm.size > 1:  # wait for the other ranks' points, noticing Ctrl-C meanwhile
            request = comm.Ibarrier()
            while not request.Test():
                if runctl.pending():
                    raise runctl.Interrupted(runctl.pending())
                time.sleep(0.05)
    except runctl.Interrupted as stop:
        bar.close()
        # the closing line says which points are done (not the inner compare's "load factor 0
        # of the sweep" of the point that was running)
        finished_now = sorted(p.name for p in config.points if _finished(out, p) is not None) \
            if root else sorted(done)
        total = len(config.points)
        stop.where = f"{len(finished_now)} of {total} validity points done"
        stop.written = (f"the finished points ({_names(finished_now)}; points/<i>_<j>.json, "
                        "reused by a rerun) and summary.json are")
        if root:  # the finished points are on disk; the summary says what is missing
            _write(out, config, started, "interrupted",
                   f"interrupted ({stop.name}) with {len(finished_now)} of {total} points done "
                   f"({_names(finished_now)}); rerun the command to finish the map", len(done))
        raise
    finally:
        bar.close()
    summary = None
    if root:
        summary = _write(out, config, started, None, "", len(done))
    summary = comm.bcast(summary, root=0) if comm.size > 1 else summary
    return summary


def _names(names: list[str], shown: int = 6) -> str:
    """'0_0, 0_1, ...' (at most ``shown``), or 'none'."""
    if not names:
        return "none"
    return ", ".join(names[:shown]) + (f", ... ({len(names) - shown} more)"
                                       if len(names) > shown else "")


def _run_workers(raw: dict, config: ValidityConfig, points: list[GridPoint], workers: int,
                 finished, comm) -> None:
    """Solve ``points`` in ``workers`` new processes
    (`fe_beam.analyses.validity_workers.worker_point`), calling ``finished(point, record)`` here
    as each one ends; Ctrl-C (noticed here: the workers ignore it) ends the workers and raises
    `fe_beam.runctl.Interrupted`."""
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    index = {p.name: k for k, p in enumerate(config.points)}
    executor = ProcessPoolExecutor(max_workers=workers, initializer=worker_start,
                                   mp_context=multiprocessing.get_context("spawn"))
    try:
        pending = {executor.submit(worker_point, raw, index[p.name]): p for p in points}
        while pending:
            done, _ = wait(pending, timeout=0.25, return_when=FIRST_COMPLETED)
            for future in done:
                point = pending.pop(future)
                try:
                    record = future.result()
                except Exception as error:  # the worker process died (BrokenProcessPool)
                    record = {"i": point.i, "j": point.j, "x": point.x, "y": point.y,
                              "hash": point.hash, "status": "failed", "solid": None, "rod": {},
                              "message": f"worker process: {type(error).__name__}: {error}"}
                finished(point, record)
            runctl.check(comm)
    except BaseException:
        for process in list((getattr(executor, "_processes", None) or {}).values()):
            process.kill()  # (a worker handles SIGTERM at its own step boundaries)
        executor.shutdown(wait=False, cancel_futures=True)
        raise
    executor.shutdown(wait=True)


def _write(out: Path, config: ValidityConfig, started: float, status: str | None, message: str,
           skipped: int) -> dict:
    records = _collect(out, config)
    points = [_summary_point(r) for r in records]
    failed = [p for p in points if p["status"] == "failed"]
    total = len(config.points)
    computed = len(points) - skipped
    if status is None:
        status = "failed" if failed or len(points) < total else "converged"
        if len(points) < total:
            message = f"{total - len(points)} of {total} points have no result"
        if failed:
            message = (f"{len(failed)} of {total} points failed (first: {config.x} = "
                       f"{failed[0]['x']:g}"
                       + (f", {config.y} = {failed[0]['y']:g}" if config.y else "")
                       + f": {failed[0]['message']})")
    summary = {
        "status": status,
        "message": message,
        "wall_time_s": time.perf_counter() - started,
        "x": {"key": config.x, "values": list(config.x_values)},
        "y": None if config.y is None else {"key": config.y, "values": list(config.y_values)},
        "laws": list(config.laws),
        "measure": "backbone_distance = max over the backbone stations x of |r_rod(x) - "
                   "r_solid(x)| / L; tip_error = |r_rod(L) - r_solid(L)| / L and |theta_rod - "
                   "theta_solid| [rad]; tip_frame_angle = |rotation vector of R_rod^T R_solid| "
                   "[rad] (the tip frames)" + (
                       "; contact_force_difference = max over the obstacles of |F_rod - "
                       "F_solid| / max(|F_rod|, |F_solid|)" if _contact(config) else ""),
        "metric": config.metric,
        "kinematics": config.kinematics,
        "thresholds": list(THRESHOLDS),
        "second_mesh_ratio": config.second_mesh_ratio,
        "order": config.order,
        "counts": {"total": total, "finished": len(points), "failed": len(failed),
                   "skipped": skipped, "computed": computed},
        "departures": _statements(points, config, total),
        "points": points,
    }
    check = mesh_estimate_check(points)
    if check is not None:
        summary["checks"] = [check]
    atomic_write_json(out / "summary.json", summary)
    _write_csv(out / "validity.csv", points, config)
    if _plots(config) and points and status != "running":
        _plot(out / "validity.png", points, config)
    return summary


def mesh_estimate_check(points: list[dict]) -> dict | None:
    """The certificate ``solid_discretisation_error`` of the map: the largest over the points
    (and the tip, rotation and backbone) of `mesh_check`'s value, the error bound with the
    order observed on three meshes over the reported (assumed-order) estimate; None without
    a second mesh."""
    worst, where = None, None
    for point in points:
        error = (point.get("solid") or {}).get("discretisation_error") or {}
        check = error.get("mesh_check")
        if check is None:
            continue
        for name, quantity in check["quantities"].items():
            value = quantity["value"]
            if worst is None or value > worst:
                worst, where = value, (point, name, quantity)
    if worst is None:
        return None
    point, name, quantity = where
    order = quantity["observed_order"]
    return certify.entry(
        "solid_discretisation_error", worst, 1.0,
        detail=(f"largest over the points of the {name} error bound with the order observed "
                "on three meshes over the reported estimate (assumed order); worst at "
                f"x = {point['x']:g}" + (f", y = {point['y']:g}" if point.get("y") is not None
                                         else "")
                + (f", observed order {order:.3g}" if order is not None
                   else ", the change does not shrink")
                + (f" (capped at the element's {quantity['order_used']:.3g})"
                   if order is not None and quantity.get("order_used") is not None
                   and quantity["order_used"] < order else "")
                + (f" (below {MIN_OBSERVED_ORDER:g}: no bound)"
                   if order is not None and order < MIN_OBSERVED_ORDER else "")),
        remedy="set [validity] order to the observed order (or lower), or refine [solid] "
               "mesh_size until the three meshes are in the asymptotic range")


def _plots(config: ValidityConfig) -> bool:
    return bool(config.points) and config.points[0].parsed.solid.output.plots


def _write_csv(path: Path, points: list[dict], config: ValidityConfig) -> None:
    header = ["i", "j", "x", "y", "status", "solid_tip_u", "solid_tip_v", "solid_tip_theta",
              "solid_dofs", "solid_mesh_size", "solid_error_tip", "solid_error_rotation",
              "solid_error_backbone"]
    spatial = config.kinematics == "spatial"
    if spatial:
        header.append("solid_tip_w")
    for law in config.laws:
        header += [f"{law}_tip_u", f"{law}_tip_v", f"{law}_tip_theta", f"{law}_tip_error",
                   f"{law}_rotation_error", f"{law}_backbone_distance"]
        header += [f"{law}_tip_w"] if spatial else []
        header.append(f"{law}_tip_frame_angle")
        header += [f"{law}_contact_force_difference"] if _contact(config) else []
    header.append("message")
    rows = []
    for p in points:
        solid = p["solid"] or {}
        tip = solid.get("tip") or {}
        error = solid.get("discretisation_error") or {}
        row = [p["i"], p["j"], p["x"], "" if p["y"] is None else p["y"], p["status"],
               tip.get("u", ""), tip.get("v", ""), tip.get("theta", ""), solid.get("dofs", ""),
               solid.get("mesh_size", ""), error.get("tip", ""), error.get("rotation", ""),
               error.get("backbone", "")]
        if spatial:
            row.append(tip.get("w", ""))
        for law in config.laws:
            rod = p["rod"].get(law, {})
            rod_tip = rod.get("tip") or {}
            tip_error = rod.get("tip_error") or {}
            row += [rod_tip.get("u", ""), rod_tip.get("v", ""), rod_tip.get("theta", ""),
                    tip_error.get("distance_over_L", ""), tip_error.get("rotation", ""),
                    rod.get("backbone_distance", "")]
            row += [rod_tip.get("w", "")] if spatial else []
            row.append(tip_error.get("frame_angle", ""))
            row += [rod.get("contact_force_difference", "")] if _contact(config) else []
        row.append(p["message"])
        rows.append(row)
    write_csv(path, header, rows)


def _distance(point: dict, law: str, metric: str = "backbone_distance") -> float:
    """The mapped quantity ([validity] metric) of ``law`` at ``point`` [%] (NaN: none)."""
    rod = point["rod"].get(law, {})
    if point["status"] != "converged" or metric not in rod:
        return math.nan
    return 100 * rod[metric]


def _solid_error(point: dict) -> float:
    error = (point["solid"] or {}).get("discretisation_error")
    return math.nan if not error else 100 * error["backbone"]


def _plot(path: Path, points: list[dict], config: ValidityConfig) -> None:
    """validity.png: a 2-D grid: per law, d [%] coloured, the 1 % and 5 % contours, the points
    (failed: crosses) labelled with the solid's estimated error; a 1-D grid: d against the axis
    with the solid's error as bars; a single point: one bar per law."""
    nx, ny = len(config.x_values), len(config.y_values or (None,))
    laws = config.laws
    if nx >= 2 and ny >= 2:
        _plot_map(path, points, config)
        return
    if nx == 1 and ny == 1:
        with figure(path, figsize=(5, 4)) as (_, axis):
            p = points[0]
            values = [_distance(p, law, config.metric) for law in laws]
            error = _solid_error(p)
            axis.bar(range(len(laws)), values, yerr=None if math.isnan(error) else error,
                     color=[f"C{k}" for k in range(len(laws))], capsize=4)
            axis.set_xticks(range(len(laws)), laws)
            axis.set_yscale("log")
            _threshold_lines(axis)
            axis.set_ylabel(METRIC_AXIS[config.metric])
            axis.set_title(_point_title(config, p) + _error_note(error), fontsize=8)
        return
    key, values, attribute = ((config.x, config.x_values, "x") if nx >= 2
                              else (config.y, config.y_values, "y"))
    with figure(path, figsize=(7, 4.5)) as (_, axis):
        for k, law in enumerate(laws):
            pairs = sorted((p[attribute], _distance(p, law, config.metric), _solid_error(p))
                           for p in points)
            xs = [a for a, _, _ in pairs]
            ds = [d for _, d, _ in pairs]
            es = [0.0 if math.isnan(e) else e for _, _, e in pairs]
            axis.errorbar(xs, ds, yerr=es if any(es) else None, marker="o", ms=4, capsize=3,
                          color=f"C{k}", label=f"rod, {law} law")
        failed = [p[attribute] for p in points if p["status"] != "converged"]
        if failed:
            axis.plot(failed, [1.0] * len(failed), "kx", ms=8, label="failed point")
        _threshold_lines(axis)
        axis.set_xlabel(key)
        axis.set_ylabel(METRIC_AXIS[config.metric])
        axis.set_yscale("log")
        other = "" if config.y is None else (
            f" at {config.x if attribute == 'y' else config.y} = "
            f"{(config.x_values if attribute == 'y' else config.y_values)[0]:g}")
        axis.set_title(f"Rod vs 3D solid{other} (bars: solid mesh error, Richardson)",
                       fontsize=9)
        axis.grid(alpha=0.3, which="both")
        axis.legend(fontsize=7)


def _threshold_lines(axis) -> None:
    for threshold, style in zip(THRESHOLDS, ("--", ":"), strict=True):
        axis.axhline(100 * threshold, color="0.4", ls=style, lw=1,
                     label=f"{100 * threshold:g} %")


def _point_title(config: ValidityConfig, p: dict) -> str:
    text = f"{config.x} = {p['x']:g}"
    return text + (f", {config.y} = {p['y']:g}" if config.y is not None else "")


def _error_note(error: float) -> str:
    return "" if math.isnan(error) else f"\nsolid mesh error ~ {error:.2g} % of L (bar)"


def _plot_map(path: Path, points: list[dict], config: ValidityConfig) -> None:
    import warnings

    from matplotlib.colors import LogNorm

    xs, ys = np.asarray(config.x_values, float), np.asarray(config.y_values, float)
    ix, iy = np.argsort(xs), np.argsort(ys)
    laws = config.laws
    by_index = {(p["i"], p["j"]): p for p in points}
    with figure(path, 1, len(laws), figsize=(5.2 * len(laws), 4.4), squeeze=False) as (_, axes):
        for axis, law in zip(axes[0], laws, strict=True):
            grid = np.full((len(ys), len(xs)), np.nan)
            for (i, j), p in by_index.items():
                grid[j, i] = _distance(p, law, config.metric)
            grid = grid[np.ix_(iy, ix)]
            finite = grid[np.isfinite(grid) & (grid > 0)]
            X, Y = np.meshgrid(xs[ix], ys[iy])
            if finite.size:
                low, high = finite.min(), finite.max()
                norm = LogNorm(vmin=min(low, 0.5), vmax=max(high, 10.0))
                mesh = axis.pcolormesh(X, Y, np.ma.masked_invalid(grid), shading="gouraud"
                                       if np.isfinite(grid).all() else "nearest",
                                       cmap="viridis", norm=norm)
                axis.figure.colorbar(mesh, ax=axis, label=METRIC_AXIS[config.metric])
                with warnings.catch_warnings():  # (no contour where d stays on one side)
                    warnings.simplefilter("ignore")
                    lines = axis.contour(X, Y, np.ma.masked_invalid(grid),
                                         levels=[100 * t for t in THRESHOLDS],
                                         colors=["white", "red"], linewidths=1.5)
                    axis.clabel(lines, fmt=lambda v: f"{v:g} %", fontsize=8)
            for (i, j), p in by_index.items():
                ok = p["status"] == "converged"
                axis.plot(xs[i], ys[j], "o" if ok else "x", color="k", ms=4 if ok else 8)
                error = _solid_error(p)
                if not math.isnan(error):
                    axis.annotate(f"±{error:.2g}%", (xs[i], ys[j]), textcoords="offset points",
                                  xytext=(3, 3), fontsize=6)
            axis.set_xlabel(config.x)
            axis.set_ylabel(config.y)
            note = (" (labels: solid mesh error)" if config.second_mesh_ratio else "")
            axis.set_title(f"rod ({law}) vs 3D solid: 1 % and 5 % contours{note}", fontsize=8)


def run(validated, out: Path, comm=MPI.COMM_WORLD, progress: bool = True,
        echo=None) -> Result:
    """``fe-beam validity`` (the driver contract, `fe_beam.analyses.result`): the map is a
    resumable study, so it needs its folder (``out``)."""
    report = Report(echo)
    summary = validity_run(validated.config, validated.parsed, out, comm, progress,
                           say=report.err)
    for entry in summary["departures"].values():
        report.out(entry["statement"])
    counts = summary["counts"]
    report.out(f"{counts['finished']} of {counts['total']} points ({counts['computed']} "
               f"computed, {counts['skipped']} already finished, {counts['failed']} failed), "
               f"{summary['wall_time_s']:.2f} s; results in {out}")
    code = exit_code(report, summary, "fe-beam validity")
    return Result("validity", summary, code, report.lines)

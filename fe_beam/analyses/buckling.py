"""``fe-beam buckling``: linear buckling load factors and modes of the rod or of the 3D solid
about the undeformed or a loaded state (the engine: `fe_beam.solvers.buckling`)."""

from __future__ import annotations

import math
import time
from pathlib import Path

from mpi4py import MPI

from fe_beam import certify
from fe_beam.analyses.result import EXIT_FAILED, Report, Result
from fe_beam.analyses.solid import SolidRun, check_solid_work
from fe_beam.analyses.static import StaticContinuation, check_beam_work
from fe_beam.config.buckling import parse_buckling
from fe_beam.exports.outputs import BeamXDMFWriter, atomic_write_json
from fe_beam.exports.solid import DisplacementXDMF
from fe_beam.exports.spatial import SpatialXDMFWriter
from fe_beam.fem import compat
from fe_beam.solvers.buckling import (
    CONFIRM_TOLERANCE,
    Buckling,
    confirm_on_path,
    default_search_limit,
    load_scale_record,
    rod_buckling,
    solid_buckling,
)
from fe_beam.solvers.newton import LoadSteppingFailed

__all__ = ["run", "run_buckling"]


def run_buckling(config: dict, out: Path | None, comm=MPI.COMM_WORLD,
                 progress: bool = True) -> dict:
    """`fe-beam buckling` on a validated configuration (rod, finger or 3D solid: [solid]);
    writes summary.json and buckling_modes.xdmf into ``out`` and returns the summary."""

    kind, parsed, settings = parse_buckling(config)
    if kind == "solid":
        return _run_solid(parsed, settings, out, comm, progress)
    return _run_rod(parsed, settings, out, comm, progress)


def _failed(failure, prestress, dofs, started, prestate, out, comm) -> dict:

    summary = {"status": "failed", "message": f"buckling pre-state: {failure}",
               "load_factors": [], "prestress": prestress, "prestate": prestate,
               "dofs": dofs, "notes": [], "wall_time_s": time.perf_counter() - started}
    if out is not None and comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        atomic_write_json(out / "summary.json", summary)
    return summary


def _with_confirmation(summary: dict, extra: dict, checks: list, work_notes: list) -> None:
    """The path confirmation's keys, message and checks (`_confirmed`) and the set-up notes
    into ``summary`` (in place)."""
    message = extra.pop("message", None)
    summary.update(extra)
    if message:
        summary["message"] = message
    if checks:
        summary["checks"] = checks
    summary["notes"] = work_notes + summary["notes"]


def _summary(result: Buckling, settings, dofs: int, started: float, critical: list) -> dict:
    return {
        "status": "completed",
        "message": "",
        "load_factors": result.load_factors,
        "critical_loads": critical,
        "reversed_load_factors": result.negative[: settings.count],
        "prestress": result.prestress,
        "modes": [{"load_factor": f, "shape": {"file": "buckling_modes.xdmf", "index": i}}
                  for i, f in enumerate(result.load_factors, start=1)],
        "dofs": dofs,
        "notes": result.notes,
        "wall_time_s": time.perf_counter() - started,
    }


def _run_rod(static, settings, out, comm, progress) -> dict:

    started = time.perf_counter()
    # up-front limits (fe_beam.runctl; TooLarge: exit 2 unless [solver] allow_large)
    work_notes = check_beam_work(static, static.stepping.steps if settings.prestress else None,
                                 comm, quiet=out is None)
    run = StaticContinuation(static, comm, prefix="fe_beam_buckling_static_")
    problem = run.problem
    try:
        try:
            linear = rod_buckling(run, settings.count, settings.prestress, static.stepping,
                                  progress=progress)
        except LoadSteppingFailed as failure:
            return _failed(failure, settings.prestress, problem.global_dofs, started,
                           {"load_factor": float(run.load_factor),
                            "tip": problem.end_values("xL")}, out, comm)
        prestate_tip = problem.end_values("xL")
        checks, extra = [], {}
        if _confirmable(run):
            result, checks, extra = _confirmed(run, linear, settings, static.stepping,
                                               progress)
        elif getattr(problem, "moment_loads", False) and not static.model.loads.follower:
            result, extra = _unconfirmed_moments(linear, settings)
        else:
            result = linear
            extra = _unconfirmed(run, linear, settings)
        critical = [load_scale_record(static.model, f) for f in result.load_factors]
        if static.model.loads.follower:  # Beck's column: no load factor found, yet unstable
            result.notes.append(
                "follower tip force: a non-conservative load loses stability by flutter "
                "(complex eigenvalues of the dynamic problem), which linear buckling does not "
                "find; an empty or short load_factors list does not mean stable: check with "
                "fe-beam modes (prestress = true) at the loads of interest; the load factors "
                "are the linearised estimates, not confirmed by the path (its stability is not "
                "that of an energy)")
        if run.tendons:
            for record, factor in zip(critical, result.load_factors, strict=True):
                record["tensions"] = [factor * t.tension for t in static.tendons]
        summary = _summary(result, settings, problem.global_dofs, started, critical)
        _with_confirmation(summary, extra, checks, work_notes)
        summary["prestate_tip"] = prestate_tip
        if out is not None:
            if comm.rank == 0:
                out.mkdir(parents=True, exist_ok=True)
            comm.barrier()
            state = compat.local_array(problem.w).copy()
            writer = (SpatialXDMFWriter if problem.spatial else BeamXDMFWriter)(
                problem, out / "buckling_modes.xdmf" if static.output.xdmf else None,
                sections=False)  # normalised shapes: their strains and forces mean nothing
            for index, shape in enumerate(result.shapes, start=1):
                compat.local_array(problem.w)[:] = compat.local_array(shape)
                writer.write(float(index))
            writer.close()
            compat.local_array(problem.w)[:] = state
            if comm.rank == 0:
                atomic_write_json(out / "summary.json", summary)
        return summary
    finally:
        run.destroy()


def _unconfirmed(run, linear: Buckling, settings) -> dict:
    """The summary's keys of factors the path cannot confirm (`_confirmable` false): they stay
    in load_factors (the public key), labelled linearised and unconfirmed, with a note naming
    why (the follower force has its own note on flutter)."""
    loads = run.config.model.loads
    if run.tendons is not None and any(t.controlled_by_pull_in for t in run.tendons.tendons):
        reason = "a tendon controlled by pull-in"
    elif loads.follower:
        reason = "a follower force"
    elif getattr(run.problem, "moment_loads", False):
        reason = "a dead moment on a spatial rod"
    else:
        reason = "a load without a potential"
    if linear.load_factors and not loads.follower:
        linear.notes.append(
            f"the load_factors (and reversed_load_factors) are linearised estimates about "
            f"the state at load factor "
            f"{linear.prestress:g}, not buckling loads confirmed by the nonlinear path: with "
            f"{reason} the tangent is not symmetric and the path's stability (its energy-"
            "decreasing directions) cannot confirm a critical point; follow the path with "
            "fe-beam path (or fe-beam dynamic) to find where the rod loses stability")
    return {"load_factors_confirmed": False, "unconfirmed_reason": reason,
            "linearised_load_factors": list(linear.load_factors),
            "linearised_reversed_load_factors": list(linear.negative[: settings.count])}


def _unconfirmed_moments(linear: Buckling, settings):
    """A dead moment on a spatial rod (work M . T(theta) dtheta, no potential): the path's
    stability cannot confirm a linearised factor, and the linearisation in the rotation vector
    about a twisted pre-state need not approximate one (a shaft clamped at both ends under a
    tip torque gave 6.3 N m where Greenhill's torque is 8.99 EI / L = 883 N m, and modes at
    10 N m were stable): the estimates are kept in linearised_load_factors only."""
    shown = ", ".join(f"{f:.6g}" for f in linear.load_factors) or "none"
    message = ("no confirmed buckling load: a dead moment on a spatial rod has no potential, "
               "so the nonlinear path's stability cannot confirm a critical factor; the "
               f"linearised estimate(s) about the state at load factor {linear.prestress:g} "
               f"({shown}, in linearised_load_factors) are not reported as buckling loads: "
               "check a load with fe-beam modes ([modes] prestress = true) or fe-beam path")
    extra = {"load_factors_confirmed": False,
             "unconfirmed_reason": "a dead moment on a spatial rod",
             "linearised_load_factors": list(linear.load_factors),
             "linearised_reversed_load_factors": list(linear.negative[: settings.count]),
             "message": message}
    return Buckling([], [], linear.prestress, [], list(linear.notes)), extra


def _confirmable(run) -> bool:
    """Is the tangent that of an energy (its inertia counts the energy-decreasing directions)?
    Not with follower loads, pull-in control or a non-conservative law."""
    pull_in = run.tendons is not None and any(
        t.controlled_by_pull_in for t in run.tendons.tendons)
    return not (pull_in or run.config.model.loads.follower
                or not getattr(run.problem, "conservative", True))


def _confirmed(run, linear: Buckling, settings, stepping, progress):
    """The linearised factors about the prestress checked on the nonlinear path
    (`fe_beam.solvers.buckling.confirm_on_path`): the Buckling of the confirmed critical
    factors only, the checks, and the summary's extra keys (docs/notes/commands/buckling.md)."""
    limit = (settings.max_load_factor if settings.max_load_factor is not None
             else default_search_limit(linear, settings.count))
    path = confirm_on_path(run, linear, settings.count, limit, stepping, progress=progress)
    factors, shapes, checks, points = [], [], [], []
    for point in path.confirmed:
        lo, hi = point.bracket
        width = (hi - lo) / abs(hi)
        check = certify.entry(
            "critical_point_confirmed", width, CONFIRM_TOLERANCE,
            detail=(f"load factor {point.load_factor:.8g}: {point.unstable_below} "
                    f"energy-decreasing direction(s) of the tangent on the path at "
                    f"{lo:.8g}, {point.unstable_above} at {hi:.8g} (relative bracket width)"),
            remedy="follow the path with fe-beam path",
            passed=point.unstable_above > point.unstable_below and width <= CONFIRM_TOLERANCE)
        check.update(load_factor=point.load_factor, bracket=[lo, hi],
                     unstable_below=point.unstable_below, unstable_above=point.unstable_above)
        checks.append(check)
        points.append({"load_factor": point.load_factor, "bracket": [lo, hi],
                       "unstable_below": point.unstable_below,
                       "unstable_above": point.unstable_above,
                       "multiplicity": point.multiplicity})
        for index in range(point.multiplicity):
            factors.append(point.load_factor)
            if index < len(point.shapes):
                shapes.append(point.shapes[index])
    factors, shapes = factors[: settings.count], shapes[: settings.count]
    notes = list(linear.notes)
    shown = ", ".join(f"{f:.6g}" for f in linear.load_factors)
    extra = {"linearised_load_factors": list(linear.load_factors),
             "critical_points": points, "path_checked_to": path.checked_to,
             "max_load_factor": limit, "path_trials": path.trials}
    if path.failure is not None:
        checks.append(certify.entry(
            "critical_point_confirmed", math.nan, CONFIRM_TOLERANCE, passed=False,
            detail=f"the nonlinear path could not confirm the critical factors: {path.failure}",
            remedy="follow the path with fe-beam path (a limit point is passed by arc length), "
                   "or lower [buckling] count or max_load_factor"))
    elif len(factors) < settings.count:
        if path.left_branch is not None:
            lo, x, before, after = path.left_branch
            notes.append(f"the path search stopped: between load factors {lo:.6g} and {x:.6g} "
                         f"the energy-decreasing directions went from {before} to {after} (the "
                         "load stepping left the branch, e.g. onto the buckled one of a slightly "
                         "imperfect structure): critical factors above are not confirmed; "
                         "fe-beam path follows the branches")
        gained = path.unstable_at_end - path.unstable_at_start - sum(
            p.multiplicity for p in path.confirmed)
        checks.append(certify.entry(
            "no_critical_point_below_limit", float(gained), 0.0,
            detail=(f"energy-decreasing directions gained on the path from load factor "
                    f"{linear.prestress:g} to {path.checked_to:.8g} besides the confirmed "
                    "critical points")))
        if not factors:
            extra["message"] = (
                f"no buckling up to load factor {path.checked_to:.6g}: the nonlinear path from "
                f"{linear.prestress:g} stays as stable as it starts ({path.unstable_at_start} "
                "energy-decreasing direction(s)); "
                + (f"the linearised estimate(s) {shown} about the state at load factor "
                   f"{linear.prestress:g} are not critical points of the path (a bent "
                   "pre-buckling state need not bifurcate); " if shown else "")
                + "fe-beam path follows the path further")
        else:
            notes.append(f"[buckling] count = {settings.count}: only {len(factors)} critical "
                         f"factor(s) confirmed on the path up to load factor "
                         f"{path.checked_to:.6g} ([buckling] max_load_factor)")
    below = [f for f in linear.load_factors if f < path.checked_to]
    if len(below) > len(factors):
        notes.append(
            f"the nonlinear path confirms {len(factors)} critical point(s) up to load factor "
            f"{path.checked_to:.6g}, where the problem linearised about the state at load "
            f"factor {linear.prestress:g} has {len(below)} factor(s) ("
            + ", ".join(f"{f:.6g}" for f in below) + "): the others are not critical points "
            "of the path (its stability does not change there) and are not reported as "
            "buckling loads (linearised_load_factors)")
    # the path is followed in the load's direction only: the factors of the reversed load are
    # linearised estimates it does not confirm (a bent pre-state's rarely are critical points),
    # so they are not reported as buckling loads of the reversed load
    reversed_ = list(linear.negative[: settings.count])
    extra["linearised_reversed_load_factors"] = reversed_
    if reversed_:
        notes.append(
            "reversed_load_factors is left empty: the factors of the reversed load linearised "
            f"about the state at load factor {linear.prestress:g} ("
            + ", ".join(f"{f:.6g}" for f in reversed_) + ", in "
            "linearised_reversed_load_factors) are not confirmed by the nonlinear path, which "
            "is followed in the load's direction only; run fe-beam buckling with the loads "
            "reversed to confirm them")
    result = Buckling(factors, shapes, linear.prestress, [], notes)
    return result, checks, extra


def _run_solid(config, settings, out, comm, progress) -> dict:

    started = time.perf_counter()
    work_notes = check_solid_work(config, comm, quiet=out is None)
    run = SolidRun(config, comm)
    problem = run.problem
    try:
        result = solid_buckling(run, settings.count, settings.prestress, config.stepping,
                                progress=progress)
    except LoadSteppingFailed as failure:
        return _failed(failure, settings.prestress, run.dofs, started,
                       {"load_factor": float(run.load_factor)}, out, comm)
    checks, extra = [], {}
    try:
        result, checks, extra = _confirmed(run, result, settings, config.stepping, progress)
    except LoadSteppingFailed as failure:  # the path's start could not be restored
        return _failed(failure, settings.prestress, run.dofs, started,
                       {"load_factor": float(run.load_factor)}, out, comm)
    critical = [{"tip_force": [f * c for c in config.tip_force]} for f in result.load_factors]
    summary = _summary(result, settings, run.dofs, started, critical)
    _with_confirmation(summary, extra, checks, work_notes)
    summary["model"] = "solid"
    if out is not None:
        if comm.rank == 0:
            out.mkdir(parents=True, exist_ok=True)
        comm.barrier()
        state = compat.local_array(problem.w).copy()
        if config.output.xdmf:
            with DisplacementXDMF(problem, out / "buckling_modes.xdmf") as writer:
                for index, shape in enumerate(result.shapes, start=1):
                    compat.local_array(problem.w)[:] = compat.local_array(shape)
                    writer.write(float(index))
        compat.local_array(problem.w)[:] = state
        if comm.rank == 0:
            atomic_write_json(out / "summary.json", summary)
    return summary


def run(validated, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True,
        echo=None) -> Result:
    """``fe-beam buckling`` (the driver contract, `fe_beam.analyses.result`)."""
    kind, parsed, settings = validated.parsed
    summary = (_run_solid if kind == "solid" else _run_rod)(parsed, settings, out, comm,
                                                             progress)
    report = Report(echo)
    for note in summary.get("notes", []):
        report.err(f"fe-beam buckling: note: {note}")
    if summary["status"] != "completed":
        report.err(f"fe-beam buckling: {summary['message']}")
        return Result("buckling", summary, EXIT_FAILED, report.lines)
    if not summary["load_factors"] and summary.get("message"):
        report.out(f"fe-beam buckling: {summary['message']}")
    elif "critical_points" in summary:
        report.out(f"{'mode':>4}  {'load factor':>14}  critical points of the nonlinear path "
                   f"(linearised about the state at load factor {summary['prestress']:g}, "
                   "confirmed by the path's stability)")
        brackets = [point for point in summary["critical_points"]
                    for _ in range(point["multiplicity"])]
        for index, (factor, point) in enumerate(
                zip(summary["load_factors"], brackets, strict=False), start=1):
            below = point["unstable_below"]
            # "stable" only where it is (a prestress past a critical point starts unstable)
            state = ("stable" if below == 0 else
                     f"{below} energy-decreasing direction(s)")
            report.out(f"{index:>4}  {factor:>14.8g}  {state} at {point['bracket'][0]:.8g}, "
                       f"{point['unstable_above']} at {point['bracket'][1]:.8g}")
    elif summary.get("load_factors_confirmed") is False:
        report.out(f"{'mode':>4}  {'load factor':>14}  linearised estimates about the state at "
                   f"load factor {summary['prestress']:g}, NOT confirmed by the path "
                   f"({summary['unconfirmed_reason']}): not buckling loads")
        for index, factor in enumerate(summary["load_factors"], start=1):
            report.out(f"{index:>4}  {factor:>14.8g}")
    else:
        report.out(f"{'mode':>4}  {'load factor':>14}  about the state at load factor "
                   f"{summary['prestress']:g}")
        for index, factor in enumerate(summary["load_factors"], start=1):
            report.out(f"{index:>4}  {factor:>14.8g}")
    report.out(f"{summary['dofs']} dofs, {summary['wall_time_s']:.2f} s; results in {out}")
    return Result("buckling", summary, 0, report.lines)

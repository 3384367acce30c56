"""``fe-beam buckling``: linear buckling load factors and modes of the rod or of the 3D solid
about the undeformed or a loaded state (the engine: `fe_beam.solvers.buckling`)."""

from __future__ import annotations

import time
from pathlib import Path

from mpi4py import MPI

from fe_beam.analyses.result import EXIT_FAILED, Report, Result
from fe_beam.analyses.solid import SolidRun, check_solid_work
from fe_beam.analyses.static import StaticContinuation, check_beam_work
from fe_beam.config.buckling import parse_buckling
from fe_beam.exports.outputs import BeamXDMFWriter, atomic_write_json
from fe_beam.exports.solid import DisplacementXDMF
from fe_beam.exports.spatial import SpatialXDMFWriter
from fe_beam.fem import compat
from fe_beam.solvers.buckling import (
    Buckling,
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
            result = rod_buckling(run, settings.count, settings.prestress, static.stepping,
                                  progress=progress)
        except LoadSteppingFailed as failure:
            return _failed(failure, settings.prestress, problem.global_dofs, started,
                           {"load_factor": float(run.load_factor),
                            "tip": problem.end_values("xL")}, out, comm)
        if problem.spatial and result.load_factors:
            result = _on_the_path(run, result, settings, static, progress)
        critical = [load_scale_record(static.model, f) for f in result.load_factors]
        if static.model.loads.follower:  # Beck's column: no load factor found, yet unstable
            result.notes.append(
                "follower tip force: a non-conservative load loses stability by flutter "
                "(complex eigenvalues of the dynamic problem), which linear buckling does not "
                "find; an empty or short load_factors list does not mean stable: check with "
                "fe-beam modes (prestress = true) at the loads of interest")
        if run.tendons:
            for record, factor in zip(critical, result.load_factors, strict=True):
                record["tensions"] = [factor * t.tension for t in static.tendons]
            result.notes.append(
                "tendon loads: the load factors are the linearised-buckling estimate about the "
                "given state (the tendon's tension enters the geometric stiffness); a tendon "
                "that bends the rod gives no bifurcation of the nonlinear path, and these "
                "factors are not verified against a reference: confirm with the stability "
                "check of the static path")
        summary = _summary(result, settings, problem.global_dofs, started, critical)
        summary["notes"] = work_notes + summary["notes"]
        summary["prestate_tip"] = problem.end_values("xL")
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


#: spatial rods: the first factor is re-linearised about these fractions of its estimate (the
#: last repeated; closer, K_T is too near singular for the inertia check of the factor) ...
PATH_FRACTIONS = (0.97, 0.99, 0.995)
#: ... until two estimates agree to this (relative), at most PATH_ITERATIONS times
PATH_TOLERANCE = 1e-7
PATH_ITERATIONS = 8


def _on_the_path(run, first: Buckling, settings, static, progress) -> Buckling:
    """A spatial rod's buckling factors from the state on the nonlinear path just below the
    first critical load (docs/theory.md, Spatial rods: buckling).

    The linear estimate about a state far below the critical load depends on how the rotations
    are parametrised (its third derivatives do), which matters when the critical mode couples
    bending and torsion: a cantilever's lateral-torsional buckling is estimated 12% low about the
    undeformed state with the rotation vector. The critical load of the path does not depend on
    it: the state is loaded to a fraction (PATH_FRACTIONS, toward 1) of the estimate and
    linearised again, until two estimates agree to PATH_TOLERANCE. The factors are then the
    path's (the pre-state steps approach the first critical load: the estimate's error is
    quadratic in the distance)."""
    estimate = first
    history = [first.load_factors[0]]
    for iteration in range(PATH_ITERATIONS):
        fraction = PATH_FRACTIONS[min(iteration, len(PATH_FRACTIONS) - 1)]
        target = fraction * estimate.load_factors[0]
        if not target > settings.prestress:
            break  # the given state is already close to the critical load
        try:
            trial = rod_buckling(run, settings.count, target, static.stepping,
                                 progress=progress)
        except LoadSteppingFailed as failure:
            estimate.notes.append(f"the pre-state toward the critical load failed ({failure}): "
                                  "the factors are the estimate about the last state reached")
            break
        passed = any(0 < f < target for f in trial.negative)
        jumped = trial.load_factors and trial.load_factors[0] > 1.2 * estimate.load_factors[0]
        if not trial.load_factors or passed or jumped or trial.load_factors[0] <= target:
            break  # past the critical load, or its factor lost: keep the estimate from below
        estimate = trial
        history.append(estimate.load_factors[0])
        if abs(history[-1] - history[-2]) <= PATH_TOLERANCE * abs(history[-1]):
            break
    if len(history) > 1:
        estimate.notes.append(
            "spatial rod: the load factors are linearised about the state on the path at load "
            f"factor {float(run.load_factor):.6g} (the linear estimate about the given state was "
            f"{history[0]:.6g}; successive estimates {', '.join(f'{h:.8g}' for h in history)})")
    return estimate


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
    critical = [{"tip_force": [f * c for c in config.tip_force]} for f in result.load_factors]
    summary = _summary(result, settings, run.dofs, started, critical)
    summary["notes"] = work_notes + summary["notes"]
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
    report.out(f"{'mode':>4}  {'load factor':>14}  about the state at load factor "
               f"{summary['prestress']:g}")
    for index, factor in enumerate(summary["load_factors"], start=1):
        report.out(f"{index:>4}  {factor:>14.8g}")
    report.out(f"{summary['dofs']} dofs, {summary['wall_time_s']:.2f} s; results in {out}")
    return Result("buckling", summary, 0, report.lines)

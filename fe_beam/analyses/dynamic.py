"""``fe-beam dynamic``: the driver contract (`fe_beam.analyses.result`) over the time
integration of `fe_beam.analyses.transient.run_dynamic`."""

from __future__ import annotations

from pathlib import Path

from mpi4py import MPI

from fe_beam import certify
from fe_beam.analyses.result import EXIT_FAILED, Report, Result
from fe_beam.analyses.transient import dynamic_summary, run_dynamic

__all__ = ["run"]


def run(validated, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True,
        echo=None) -> Result:
    config = validated.parsed
    result = run_dynamic(config, out, comm, progress=progress,
                         strict=certify.strict_of(getattr(validated, "config", None)))
    report = Report(echo)
    if result.history:
        last = result.history[-1]
        tip = last["tip"]
        if "theta" in tip:
            report.out(f"t = {last['t']:.6g} s: tip u = {tip['u']:.6g} m, v = {tip['v']:.6g} "
                       f"m, theta = {tip['theta']:.6g} rad")
        else:  # a spatial rod: the displacement and the rotation vector
            vector = ", ".join(f"{c:.6g}" for c in tip["rotation_vector"])
            report.out(f"t = {last['t']:.6g} s: tip u = {tip['u']:.6g} m, v = {tip['v']:.6g} "
                       f"m, w = {tip['w']:.6g} m, rotation vector ({vector}) rad")
    report.warn_notes(getattr(result, "notes", None))
    report.out(f"{result.info.get('steps', len(result.history))} time steps, {result.dofs} "
               f"dofs, {result.info.get('wall_time_s', 0.0):.2f} s; results in {out}")
    code = 0
    if result.status != "completed":
        report.err(f"fe-beam: {result.message}")
        code = EXIT_FAILED
    summary = dynamic_summary(result, config, result.info.get("wall_time_s", 0.0))
    return Result("dynamic", summary, code, report.lines, result)

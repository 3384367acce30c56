"""``fe-beam modes``: the driver contract (`fe_beam.analyses.result`) over the modal analysis
of `fe_beam.analyses.transient.run_modes`."""

from __future__ import annotations

from pathlib import Path

from mpi4py import MPI

from fe_beam import runctl
from fe_beam.analyses.result import EXIT_FAILED, Report, Result
from fe_beam.analyses.transient import run_modes

__all__ = ["run"]


def run(validated, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True,
        echo=None) -> Result:
    static, modes = validated.parsed
    summary = run_modes(static, modes, out, comm, progress=progress)
    report = Report(echo)
    if summary["status"] == "failed":  # the static pre-state was not reached
        report.err(f"fe-beam modes: {summary['message']}")
        return Result("modes", summary, EXIT_FAILED, report.lines)
    kinds = summary.get("mode_kinds") or [
        "bending" if share > 0.5 else "axial" for share in summary["transverse_fraction"]]
    for index, (frequency, kind) in enumerate(zip(summary["frequencies_hz"], kinds, strict=True),
                                              start=1):
        label = "rigid body" if kind == "rigid" else kind
        report.out(f"mode {index}: {frequency:.6g} Hz ({label})")
    for index, mode in enumerate(summary.get("unstable_modes", []), start=1):
        imag = mode.get("eigenvalue_imag") or 0.0  # flutter: a complex pair a +- i b
        report.out(f"unstable mode {index}: omega^2 = {mode['eigenvalue']:.6g}"
                   f"{f' +- {abs(imag):.6g} i' if imag else ''} rad^2/s^2 "
                   f"(growth rate {mode['growth_rate']:.6g} 1/s)")
    for note in summary.get("notes", []):
        if note in runctl.WARNED:
            continue  # said as a warning when it arose
        kind = "warning" if note.startswith("the state is unstable") else "note"
        report.err(f"fe-beam modes: {kind}: {note}")
    found = len(summary["frequencies_hz"])
    if found < modes["count"]:
        report.err(f"fe-beam modes: note: [modes] count = {modes['count']} asked for more modes "
                   f"than were found ({found}; the model has {summary['dofs']} dofs)")
    report.out(f"results in {out}")
    return Result("modes", summary, 0, report.lines)

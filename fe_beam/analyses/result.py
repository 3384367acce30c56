"""The driver contract: every subcommand's driver module has

    run(validated, out, comm=MPI.COMM_WORLD, progress=True, echo=None) -> Result

with ``validated`` the `fe_beam.config.Validated` configuration (no second parse where the
driver takes its parsed value), ``out`` the output folder or None (nothing written), and
``echo(stream, text)`` called with each line of the report as it is made (the CLI prints them
on rank 0; `fe_beam.run` keeps them quiet). `Result.summary()` is exactly what summary.json
holds (refine: refinement.json); ``exit_code`` is 0, or 3 when the analysis stopped.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from fe_beam import certify, runctl
from fe_beam.exports.outputs import as_json, atomic_write_json

__all__ = ["EXIT_FAILED", "Report", "Result", "closing_of_steps", "exit_code",
           "failed", "fit_report", "settle_checks", "world"]

EXIT_FAILED = 3


@dataclass
class Result:
    """What a driver's ``run`` returns: its summary, exit code and report, and the driver's own
    result object (``detail``: e.g. `fe_beam.analyses.static.StaticResult`)."""

    command: str
    data: dict
    exit_code: int = 0
    lines: list[tuple[str, str]] = field(default_factory=list)
    detail: object = None

    def __post_init__(self):
        self.data = as_json(self.data)  # what the file holds: lists, plain numbers

    def summary(self) -> dict:
        """summary.json's content."""
        return self.data

    @property
    def status(self) -> str:
        return str(self.data.get("status", ""))


class Report:
    """The lines a run reports ("out": the result, "err": notes, warnings, failures), passed on
    to ``echo`` as they come."""

    def __init__(self, echo: Callable[[str, str], None] | None = None):
        self.lines: list[tuple[str, str]] = []
        self._echo = echo

    def out(self, text: str) -> None:
        self._add("out", text)

    def err(self, text: str) -> None:
        self._add("err", text)

    def _add(self, stream: str, text: str) -> None:
        self.lines.append((stream, text))
        if self._echo is not None:
            self._echo(stream, text)

    def warn_notes(self, notes) -> None:
        """The run's notes as warnings, each once (set-up warnings were said when they arose)."""
        for note in notes or []:
            if note not in runctl.WARNED:
                self.err(f"fe-beam: warning: {note}")


def exit_code(report: Report, summary: dict, who: str, done: str = "converged") -> int:
    """0 for a run whose status is ``done``, else its message after ``who`` and EXIT_FAILED."""
    if summary["status"] != done:
        report.err(f"{who}: {summary['message']}")
        return EXIT_FAILED
    return 0


def fit_report(report: Report, command: str, summary: dict, line: str) -> int:
    """Notes, the result line; EXIT_FAILED when the fit/optimum did not converge."""
    for note in summary.get("notes", []):
        report.err(f"fe-beam {command}: note: {note}")
    report.out(line)
    return exit_code(report, summary, f"fe-beam {command}")


def closing_of_steps(report: Report, result, out) -> int:
    """The closing lines of a load-stepped rod run (static, finger) and its exit code."""
    report.warn_notes(getattr(result, "notes", None))
    stability = result.steps[-1].get("stability") if result.steps else None
    if stability and not stability["stable"]:
        report.err("fe-beam: warning: the final equilibrium is unstable (the tangent stiffness "
                   f"has {stability['energy_decreasing_directions']} direction(s) of decreasing "
                   "energy): the beam would buckle or snap away from it. A small imperfection "
                   "(e.g. a tiny transverse load) lets load stepping follow the stable branch")
    report.out(f"{len(result.steps)} load steps, {result.dofs} dofs, "
               f"{result.wall_time_s:.2f} s; results in {out}")
    if result.status != "converged":
        report.err(f"fe-beam: {result.message}")
        return EXIT_FAILED
    return 0


def failed(command: str, out, comm, message: str, report: Report) -> Result:
    """The result of a run that stopped before its driver wrote a summary (e.g. a trial
    design without equilibrium): status "failed" with ``message``, written as summary.json
    into ``out`` (so no earlier run's summary is left there as this one's), EXIT_FAILED."""
    summary = {"status": "failed", "message": message}
    if out is not None and comm.rank == 0:
        Path(out).mkdir(parents=True, exist_ok=True)
        atomic_write_json(Path(out) / "summary.json", summary)
    return Result(command, summary, EXIT_FAILED, report.lines)


def settle_checks(result: Result, strict: bool, out, comm, echo=None) -> Result:
    """The run-time certificates of a finished run (`fe_beam.certify.settle`): a failed check
    of a run that claims success makes it status "failed" with exit code 3 (``strict``) or a
    warning; the summary file in ``out`` is rewritten whenever the run made checks (with
    ``checks_passed``, as the returned summary has it). Collective (every rank holds the same
    summary)."""
    data, lines = certify.settle(result.data, strict)
    if not data.get("checks"):
        return result
    report = Report(echo)
    for text in lines:
        report.err(f"fe-beam {result.command}: {'not certified' if strict else 'warning'}: "
                   f"{text}")
    result.lines.extend(report.lines)
    result.data = as_json(data)
    if strict and data.get("status") == "failed":
        result.exit_code = EXIT_FAILED
    if out is not None and comm.rank == 0 and Path(out).is_dir():
        atomic_write_json(Path(out) / runctl.SUMMARY_FILES.get(result.command, "summary.json"),
                          result.data)
    return result


def world():
    """MPI's world communicator (the default of a driver given none)."""
    from mpi4py import MPI

    return MPI.COMM_WORLD

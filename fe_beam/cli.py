"""The ``fe-beam`` command line: ``fe-beam COMMAND CONFIG.toml --out DIR [--set key=value ...]``.

Exit codes: 0 success, 2 a mistake in the command line or configuration (one sentence, no
traceback; also: the output folder is in use by another run, or the run is beyond the up-front
limits of fe_beam.runctl without ``[solver] allow_large = true``), 3 the analysis ran but did not
complete (e.g. load stepping gave up; the results of the last converged step are written),
130 interrupted by SIGINT (Ctrl-C), 143 interrupted by SIGTERM: the run stops at the next step
boundary, writes the last converged state with summary status "interrupted" and prints one line.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import gc
import os
import re
import sys
import time
import traceback
from pathlib import Path

from fe_beam import analyses, runctl
from fe_beam.certify import strict_of
from fe_beam.config.calibrate import check_data
from fe_beam.config.finger import override_defaults
from fe_beam.config.registry import REGISTRY, CommandSpec, check_command_tables, validate
from fe_beam.config.schema import apply_overrides, check_partition, check_values, load_config
from fe_beam.errors import ConfigError
from fe_beam.lazy import LazyModule
from fe_beam.logs import quiet_jit_logging
from fe_beam.timefunctions import TimeFunctionError

# The engines the CLI names load dolfinx and PETSc: imported when first used, so that
# ``fe-beam --help`` and a configuration mistake answer without them. The drivers are reached
# through the lazy `fe_beam.analyses` package (`driver`).
newton = LazyModule("fe_beam.solvers.newton")

EXIT_INTERNAL = 1
EXIT_USAGE = 2
EXIT_FAILED = 3

#: The subcommands and their help (`fe_beam.config.registry.REGISTRY`).
COMMANDS = {name: spec.help for name, spec in REGISTRY.items()}


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error (the usage is one --help away)."""

    def error(self, message: str):
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _output_folder(text: str) -> Path:
    if not text.strip():
        raise argparse.ArgumentTypeError("must name a folder; got an empty name")
    if "\0" in text:
        raise argparse.ArgumentTypeError("must name a folder; the name contains a NUL byte")
    return Path(text)


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="fe-beam",
        description="Finite-element analysis of slender bodies that bend a lot.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, spec in REGISTRY.items():
        command = sub.add_parser(name, help=spec.help, description=spec.help)
        command.add_argument("config", help="TOML configuration file")
        command.add_argument(
            "--out", type=_output_folder, default=None,
            help="output folder (default: results/<config name>)",
        )
        command.add_argument(
            "--set",
            action="append",
            default=[],
            metavar="TABLE.KEY=VALUE",
            help="override a config value, e.g. --set section.h=0.01",
        )
        command.add_argument("--quiet", action="store_true", help="no progress bar")
        for flags, keywords in spec.arguments:
            command.add_argument(*flags, **keywords)
    return parser


def analysis(module: str):
    """The driver module ``fe_beam.analyses.<module>``: the one in sys.modules (a stand-in
    installed there replaces it), else imported now through the lazy `fe_beam.analyses`
    package."""
    return sys.modules.get(f"{analyses.__name__}.{module}") or getattr(analyses, module)


def driver(spec: CommandSpec):
    """The function that runs ``spec``'s command (``spec.driver``, "module:function" of
    `fe_beam.analyses`; its module, and with it the finite-element stack, is imported now)."""
    return getattr(analysis(spec.driver_module), spec.driver_function)


def _say(comm, text: str, stream=None) -> None:
    if comm.rank == 0:
        print(text, file=stream or sys.stdout, flush=True)


def report_line(comm, stream: str, text: str) -> None:
    """One line of a driver's report (`fe_beam.analyses.result.Report`), printed on rank 0:
    "out" to stdout, "err" to stderr."""
    _say(comm, text, sys.stderr if stream == "err" else None)


def _check_output_folder(out: Path, comm) -> None:
    """A folder that cannot be made is a usage error, not a crash after the solve. Rank 0 makes
    it (and a probe file in it) and removes what it made: a config that turns out to be wrong
    leaves no empty folder behind."""
    problem = None
    if comm.rank == 0:
        try:
            problem = _output_folder_problem(out)
        except OSError as error:  # e.g. a name too long to look up
            problem = f"--out {out} cannot be used as an output folder ({error.strerror})"
    problem = comm.bcast(problem, root=0)
    if problem:
        raise ConfigError(problem)


def _output_folder_problem(out: Path) -> str | None:
    if out.exists() and not out.is_dir():
        return f"--out {out} exists and is not a folder"
    ancestor = out.absolute()
    while not ancestor.exists():
        ancestor = ancestor.parent
    if ancestor.is_file():
        return f"--out {out}: {ancestor} is a file, not a folder"
    if not ancestor.is_dir():
        return f"--out {out}: {ancestor} is not a folder"
    if not os.access(ancestor, os.W_OK | os.X_OK):
        return f"--out {out}: no permission to write in {ancestor}"
    made = []
    try:
        folder = out.absolute()
        missing = []
        while not folder.exists():
            missing.append(folder)
            folder = folder.parent
        for folder in reversed(missing):
            try:
                folder.mkdir()
            except FileExistsError:  # another run (started together) made it: not ours
                continue
            made.append(folder)
        probe = out / f".fe-beam-probe-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as error:
        return f"--out {out} cannot be used as an output folder ({error.strerror})"
    finally:
        for folder in reversed(made):
            with contextlib.suppress(OSError):
                folder.rmdir()
    return None


# --- errors: one message, and every MPI rank ends ------------------------------------------------
# How long a failing rank waits for the other ranks to fail at the same point (then all return
# normally and rank 0 prints) before it aborts the job (the others are in a collective operation
# that will never complete).
ABORT_GRACE_S = 1.0  # seconds between the last message and MPI_Abort
ERROR_AGREEMENT_S = float(os.environ.get("FE_BEAM_ERROR_WAIT_S", "3"))
_ERROR_COMM = []
USER_ERRNOS = {errno.EACCES, errno.EPERM, errno.ENOENT, errno.ENOSPC, errno.EROFS, errno.ENOTDIR,
               errno.EISDIR, errno.ENAMETOOLONG, errno.EEXIST, errno.EDQUOT, errno.ELOOP}
MAX_MESSAGE = 600


def _error_comm(comm):
    """A private duplicate of ``comm`` for the error agreement (made once, collectively, at the
    start of the first command; never used by the analysis)."""
    if not _ERROR_COMM:
        _ERROR_COMM.append(comm.Dup())
    return _ERROR_COMM[0]


LONG_VALUE = re.compile(r"'[^']{100,}'|\"[^\"]{100,}\"|\S{200,}")


def _shorter(match: re.Match) -> str:
    value = match.group(0)
    return f"{value[:60]}...{value[-15:]}"


def _one_line(text: str) -> str:
    """A message as one line of reasonable length: a value that echoes a huge input (a quoted
    string or an unbroken run of characters) keeps its start and end only."""
    text = LONG_VALUE.sub(_shorter, " ".join(str(text).split()))
    if len(text) > MAX_MESSAGE:
        text = f"{text[:MAX_MESSAGE // 2 - 3]} ... {text[-MAX_MESSAGE // 2 + 3:]}"
    return text


def describe_error(error: BaseException, command: str, config: str) -> tuple[int, str]:
    """(exit code, one-line message) for an exception that ended a command."""
    label = f"fe-beam {command}"
    if isinstance(error, (ConfigError, TimeFunctionError)):
        return EXIT_USAGE, _one_line(f"{label}: error in {config}: {error}")
    if isinstance(error, OSError) and error.errno in USER_ERRNOS and error.filename:
        return EXIT_USAGE, _one_line(
            f"{label}: error: {error.filename}: {error.strerror or error}")
    if isinstance(error, MemoryError):
        return EXIT_FAILED, f"{label}: the analysis ran out of memory (use a coarser model)"
    failure = isinstance(error, ArithmeticError) or type(error).__module__.startswith("petsc4py")
    if failure:
        return EXIT_FAILED, _one_line(
            f"{label}: the analysis failed: {type(error).__name__}: {error}")
    return EXIT_INTERNAL, _one_line(
        f"{label}: internal error ({type(error).__name__}: {error}); please report it with the "
        "configuration (FE_BEAM_DEBUG=1 shows the traceback)")


def end_on_error(comm, code: int, message: str) -> int:
    """Report a failed command once and return its exit code, on every rank. When all ranks
    failed (the usual case: the same check on the same input) rank 0 prints and all return;
    when the others do not join within ERROR_AGREEMENT_S they are stuck in a collective
    operation, and this rank prints and aborts the whole job with ``code``."""
    if comm.size == 1:
        print(message, file=sys.stderr, flush=True)
        return code
    request = _error_comm(comm).Ibarrier()
    deadline = time.monotonic() + ERROR_AGREEMENT_S
    while not request.Test():
        if time.monotonic() > deadline:
            print(message, file=sys.stderr, flush=True)
            sys.stdout.flush()
            # mpirun's I/O forwarder reads our stderr asynchronously; an immediate abort can
            # kill it before it passed the message on (seen with MPICH's hydra under load)
            time.sleep(ABORT_GRACE_S)
            comm.Abort(code)
        time.sleep(0.005)
    code, message = _error_comm(comm).bcast((code, message), root=0)
    if comm.rank == 0:
        print(message, file=sys.stderr, flush=True)
    return code


def run_guarded(comm, command: str, config: str, work) -> int:
    """``work()``'s exit code; any exception becomes one message and an exit code on every
    rank (see end_on_error) instead of a traceback or a hung MPI job."""
    try:
        return work()
    except Exception as error:  # noqa: BLE001 - every error ends with one message
        if os.environ.get("FE_BEAM_DEBUG"):
            traceback.print_exc()
        code, message = describe_error(error, command, config)
    return end_on_error(comm, code, message)


def _parse_arguments(argv, comm) -> argparse.Namespace:
    """Parsed arguments; usage errors and --help are printed by rank 0 only (every rank parses
    the same command line and exits with the same code)."""
    if comm.rank == 0:
        return _parser().parse_args(argv)
    with open(os.devnull, "w") as sink, contextlib.redirect_stdout(sink), \
            contextlib.redirect_stderr(sink):
        return _parser().parse_args(argv)


def _run_locked(args, validated, config: dict, comm) -> int:
    """Run a command holding the lock of its output folder, with SIGINT/SIGTERM noticed at step
    boundaries (fe_beam.runctl): one line on stderr and exit 130/143 instead of a traceback."""
    sessions = []
    try:
        return execute(args, validated, config, comm, sessions.append)
    except (runctl.FolderBusy, runctl.TooLarge) as error:
        _say(comm, f"fe-beam {args.command}: {error}", sys.stderr)
        return EXIT_USAGE
    except runctl.Interrupted as stop:
        wrote = not sessions or sessions[0] is None or bool(sessions[0].files)  # rank 0 prints
        _say(comm, stop.line(args.out, wrote), sys.stderr)
        return stop.exit_code


def main(argv: list[str] | None = None) -> int:
    with runctl.signals_deferred():
        return _main(argv)


# Environment variables set by MPI launchers (Open MPI, MPICH/Hydra, PMIx, Slurm): with none of
# them the process is a serial run, and MPI (with dolfinx and PETSc) is loaded only to run
MPI_LAUNCHER_PREFIXES = ("OMPI_COMM_WORLD_", "PMI_", "PMIX_", "HYDRA_", "MPIEXEC_", "MPI_LOCAL",
                         "SLURM_STEP_", "PALS_", "MV2_COMM_WORLD_", "I_MPI_")


class SerialComm:
    """The one-process communicator of a serial run before MPI is loaded: parsing the command
    line, checking the output folder and validating the configuration need nothing more, so
    ``fe-beam --help`` and a configuration mistake answer without loading mpi4py, dolfinx or
    PETSc."""

    rank = 0
    size = 1

    def bcast(self, value, root: int = 0):
        return value

    def allreduce(self, value, op=None):
        return value

    def barrier(self) -> None:
        return None


def launched_by_mpi() -> bool:
    """Whether an MPI launcher started this process (then MPI is loaded at once: every rank
    must take part in the collective checks)."""
    return any(name.startswith(MPI_LAUNCHER_PREFIXES) for name in os.environ)


def _world():
    # fe-beam handles SIGINT/SIGTERM itself (fe_beam.runctl: last good state written, exit
    # 130/143): PETSc must not install its own handlers (PETSc 3.25 aborts the run on SIGTERM)
    import petsc4py

    petsc4py.init(["fe-beam", "-no_signal_handler"])
    from mpi4py import MPI

    return MPI.COMM_WORLD


# --- MPI communicators: MPICH allows 2048 per process ---------------------------------------------
#: A command does not start with fewer spare communicators than this (exit 2): a solve that runs
#: out of them mid-way ends in MUMPS or PETSc with a crash, not a message.
MIN_SPARE_COMMUNICATORS = 64


class CommunicatorsExhausted(runctl.TooLarge):
    """Too few MPI communicators are left in this process to start a command (exit 2)."""


def spare_communicators(comm, up_to: int = MIN_SPARE_COMMUNICATORS) -> int:
    """How many more communicators this process can make (on every rank of ``comm``), counted
    up to ``up_to``: ``comm`` is duplicated until MPI refuses or ``up_to`` are made, then the
    duplicates are freed. Cheap (``up_to`` MPI_Comm_dup); collective."""
    from mpi4py import MPI

    handler = comm.Get_errhandler()
    comm.Set_errhandler(MPI.ERRORS_RETURN)  # a refused duplicate raises, not aborts
    made = []
    try:
        while len(made) < up_to:
            try:
                made.append(comm.Dup())
            except MPI.Exception:
                break
    finally:
        for duplicate in made:
            duplicate.Free()
        comm.Set_errhandler(handler)
        handler.Free()
    return int(comm.allreduce(len(made), op=MPI.MIN))


def check_communicators(comm, command: str) -> None:
    """CommunicatorsExhausted when fewer than MIN_SPARE_COMMUNICATORS are left. Collective."""
    spare = spare_communicators(comm)
    if spare < MIN_SPARE_COMMUNICATORS:
        raise CommunicatorsExhausted(
            f"only {spare} MPI communicators are left in this process (fewer than "
            f"{MIN_SPARE_COMMUNICATORS}; MPICH allows 2048 per process), too few to start "
            f"'{command}': run it in a new process (a script that runs many commands should "
            "drop their results and call fe_beam.cli.free_parallel_garbage)")


def free_parallel_garbage(comm) -> None:
    """Free the PETSc objects of the commands run so far on several ranks: petsc4py destroys an
    unreferenced object on a communicator of several ranks only collectively, so it waits on
    its communicator's garbage list (with its MPI communicators, of which MPICH allows 2048 per
    process) until ``PETSc.garbage_cleanup``. Collective on ``comm``: every rank calls it at
    the same point (after each command, by the CLI and `fe_beam.run`). A serial run has none."""
    if comm.size == 1:
        return
    gc.collect()  # unreachable cycles holding PETSc objects put them on the garbage lists
    from petsc4py import PETSc

    PETSc.garbage_cleanup(comm)


def check_solver_options(validated) -> None:
    """PETSc's verdict on the configuration's PETSc options (ConfigError naming the first one
    it rejects), before the run starts: the finite-element stack is loaded by now."""
    for options in validated.petsc_options:
        newton.check_petsc_options(options)


def prepare(args, config: dict, comm, notes: list[str]):
    """Every check of a configuration before the run, without the finite-element stack (the
    CLI and `fe_beam.run` alike): values, the tables the command reads (``notes`` gets the
    notes on the others), the partition over ``comm``, the command's parser (`validate`) and
    calibrate's data file. Returns the `Validated` configuration; ConfigError otherwise."""
    check_values(config)
    notes.extend(check_command_tables(args.command, config))
    check_partition(config, comm.size, args.command)
    refine = {"levels": getattr(args, "levels", None), "ratio": getattr(args, "ratio", None),
              "quantities": getattr(args, "quantity", None),
              "data": getattr(args, "data", None), "config_path": str(args.config),
              "overrides": list(getattr(args, "set", None) or [])}
    if args.command == "refine" and "solid" in config:  # the solid driver validates [solid]
        refine["solid_parser"] = getattr(analysis("solid_driver"), "parse_solid", None)
    validated = validate(args.command, config, refine)
    if args.command == "calibrate":  # the data file too, before the FE stack is loaded
        check_data(config, args.data)
    return validated


def run_driver(command: str, validated, config: dict, out, comm, progress: bool, echo):
    """The command's driver on a validated configuration, then the verdict on its run-time
    checks (`fe_beam.analyses.result.settle_checks`, ``[checks] strict`` of ``config``): the
    one way the CLI and `fe_beam.run` run a driver. Returns its `Result`."""
    result = driver(REGISTRY[command])(validated, out, comm, progress=progress, echo=echo)
    return analysis("result").settle_checks(result, strict_of(config), out, comm, echo)


def execute(args, validated, config: dict, comm, on_session=None, on_result=None,
            echo=None) -> int:
    """Run the command's driver (`fe_beam.analyses.result`: ``run(validated, out, comm,
    progress, echo)``) inside the output folder's session (given to ``on_session``); its
    report goes to ``echo(stream, text)`` (default: printed on rank 0), its `Result` to
    ``on_result``; returns its exit code. FolderBusy, TooLarge and Interrupted propagate."""
    check_communicators(comm, args.command)
    with runctl.output_session(args.out, args.command, comm) as session:
        if on_session is not None:
            on_session(session)
        runctl.check(comm, runctl.BEFORE)
        result = run_driver(args.command, validated, config, args.out, comm,
                            progress=not args.quiet,
                            echo=echo if echo is not None else (
                                lambda stream, text: report_line(comm, stream, text)))
        runctl.check(comm, runctl.AFTER)
        if on_result is not None:
            on_result(result)
        return result.exit_code


def _main(argv: list[str] | None = None) -> int:
    comm = _world() if launched_by_mpi() else SerialComm()
    args = _parse_arguments(argv, comm)
    if args.out is None:
        args.out = Path("results") / Path(args.config).stem
    if comm.size > 1:
        _error_comm(comm)
    notes = []

    def work() -> int:
        _check_output_folder(args.out, comm)
        raw = load_config(args.config)
        config = apply_overrides(raw, args.set, override_defaults(args.command, raw))
        validated = prepare(args, config, comm, notes)
        world = _world() if isinstance(comm, SerialComm) else comm
        quiet_jit_logging()
        check_solver_options(validated)
        code = _run_locked(args, validated, config, world)
        free_parallel_garbage(world)  # every rank returned here (an error did not)
        for note in notes if code != EXIT_USAGE else []:  # a usage error is one sentence
            _say(comm, f"fe-beam {args.command}: note: {note}", sys.stderr)
        return code

    return run_guarded(comm, args.command, args.config, work)


if __name__ == "__main__":
    sys.exit(main())

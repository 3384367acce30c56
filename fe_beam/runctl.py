"""Run control: interruption by SIGINT/SIGTERM, the output-folder lock, stale-result clearing,
cost-bounded rewriting of growing files, and the up-front work limits.

Interruption. While a command runs, SIGINT and SIGTERM only set a flag (on every rank: mpirun
forwards both). The flag is looked at collectively (an allreduce) at step boundaries, i.e. in
`fe_beam.progress.ProgressBar.update`, which every load-stepping and time-stepping loop calls after
each converged step on all ranks; `check` then raises `Interrupted` on every rank together. The
drivers catch it, write the last converged state with ``status = "interrupted"`` and re-raise;
the CLI prints one line and exits 130 (SIGINT) or 143 (SIGTERM). A second signal of either kind
ends the process at once (files are still readable: every write is atomic).

Output folder. `OutputSession` holds an exclusive ``fcntl.flock`` on ``DIR/.fe-beam.lock`` (it
records the owner's pid and host; the kernel drops the lock when the owner dies, so a stale lock
is taken over without guessing). Before the first file is written, the files the previous run
recorded in ``DIR/.fe-beam-manifest.json`` (or, without a manifest, the known fe_beam output
names) are removed, so a folder never mixes the results of two runs; files fe_beam did not write
are never touched.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import math
import os
import signal
import socket
import sys
import time
from pathlib import Path

EXIT_SIGINT = 130
EXIT_SIGTERM = 143
LOCK_NAME = ".fe-beam.lock"
#: the file that holds a command's summary (summary.json unless named here)
SUMMARY_FILES = {"refine": "refinement.json"}
MANIFEST_NAME = ".fe-beam-manifest.json"
# output names of fe_beam versions without a manifest (cleared when no manifest exists)
KNOWN_OUTPUTS = (
    "summary.json", "load_displacement.csv", "history.csv", "tension_sweep.csv", "compare.csv",
    "refinement.csv", "refinement.json", "beam.xdmf", "beam.h5", "modes.xdmf", "modes.h5",
    "solid.xdmf", "solid.h5", "rod.xdmf", "beam.gif", "backbone.png", "backbones.png",
    "deformed_shapes.png", "dynamics.png", "fig3_8_profiles.png", "fig3_9_backbone.png",
    "finger_3d.png", "load_displacement.png", "refinement.png", "tension_tip.png",
    "tip_vs_tension.png", "unstable_modes.xdmf", "unstable_modes.h5",
)

BEFORE, AFTER = "<before>", "<after>"  # `Interrupted.where` outside the analysis
_SIGNAL_NAMES = {signal.SIGINT: "SIGINT", signal.SIGTERM: "SIGTERM"}
_pending: int = 0


class Interrupted(Exception):
    """SIGINT/SIGTERM noticed at a step boundary (raised on every rank together)."""

    def __init__(self, signum: int, where: str = ""):
        super().__init__(_SIGNAL_NAMES.get(signum, str(signum)))
        self.signum = signum
        self.where = where
        self.written = ""  # what was written, when not "the last converged step"

    @property
    def name(self) -> str:
        return _SIGNAL_NAMES.get(self.signum, f"signal {self.signum}")

    def stopped(self, where: str, message: str) -> dict:
        """Note ``where`` the run stopped (for the closing line) and return the summary's
        ``status`` and ``message`` ("interrupted by SIGNAL ``message``")."""
        self.where = where
        return {"status": "interrupted", "message": f"interrupted by {self.name} {message}"}

    @property
    def exit_code(self) -> int:
        return EXIT_SIGINT if self.signum == signal.SIGINT else EXIT_SIGTERM

    def line(self, out, wrote: bool = True) -> str:
        """The one line the command line prints (``wrote``: whether any result was written)."""
        if self.where == BEFORE or not wrote:
            where = "" if self.where == BEFORE or not self.where else f" at {self.where}"
            return (f"fe-beam: interrupted{where} ({self.name}) before any result was written; "
                    f"nothing was written to {out}")
        if self.where == AFTER:
            return (f"fe-beam: interrupted ({self.name}) after the analysis ended; the results "
                    f"in {out} are complete")
        where = f" at {self.where}" if self.where else ""
        written = self.written or "results of the last converged step are"
        return f"fe-beam: interrupted{where} ({self.name}); {written} in {out}"


def _handler(signum, frame) -> None:
    global _pending
    session = _session
    if session is not None and not session._cleared and not session.files:
        # still setting up (meshing, compiling, assembling: no step boundary to stop at, for
        # minutes on a large model) and nothing written yet: stop now, nothing is lost
        stop = Interrupted(signum, BEFORE)
        with contextlib.suppress(Exception):
            session.release()
        os.write(2, (stop.line(session.out, False) + "\n").encode())
        os._exit(stop.exit_code)
    if _pending:
        os.write(2, f"fe-beam: {_SIGNAL_NAMES.get(signum, signum)} again: stopping at once\n"
                 .encode())
        os._exit(EXIT_SIGINT if signum == signal.SIGINT else EXIT_SIGTERM)
    _pending = signum


_deferring = 0  # nesting depth of defer_signals / signals_deferred


def defer_signals() -> dict:
    """From now on SIGINT/SIGTERM set a flag for `check` (main thread only); returns the
    previous handlers."""
    global _deferring
    try:
        previous = {s: signal.signal(s, _handler) for s in _SIGNAL_NAMES}
    except ValueError:  # not the main thread: leave the default handling
        return {}
    _deferring += 1
    return previous


def reassert() -> None:
    """Put the deferring handlers back if a library replaced them (``import gmsh`` sets
    SIGINT to its default action, which would kill the run without writing anything)."""
    if _deferring:
        with contextlib.suppress(ValueError):
            for s in _SIGNAL_NAMES:
                if signal.getsignal(s) is not _handler:
                    signal.signal(s, _handler)


@contextlib.contextmanager
def signals_deferred():
    """SIGINT/SIGTERM set a flag for `check` instead of ending the process, for the duration
    (a signal that came before, e.g. while the command imported its modules, stays pending)."""
    global _pending, _deferring
    previous = defer_signals()
    try:
        yield
    finally:
        _pending = 0
        _deferring = max(0, _deferring - (1 if previous else 0))
        for s, handler in previous.items():
            if handler is not _handler:
                signal.signal(s, handler)


def pending() -> int:
    """The signal received on this rank (0 if none)."""
    return _pending


def check(comm, where: str = "") -> None:
    """Collective: raise `Interrupted` on every rank when any rank got SIGINT/SIGTERM."""
    from mpi4py import MPI

    reassert()
    flag = comm.allreduce(_pending, op=MPI.MAX) if comm.size > 1 else _pending
    if flag:
        raise Interrupted(flag, where)


# --- cost-bounded rewriting --------------------------------------------------------------------
class Throttle:
    """When to bring files that grow with the run up to date (summary.json, whose step list
    grows, and with it the CSV and XDMF appends, see `fe_beam.exports.Exports`): the first
    time at once, then at most every ``min_interval`` seconds, and never spending more than
    ``share`` of the wall time on it (a write that took c seconds waits c / share). The work
    per step is O(1) (appends are buffered); whole-file rewrites happen a bounded number of
    times per second, whatever the number of steps."""

    def __init__(self, share: float = 0.1, min_interval: float = 1.0):
        self.share, self.min_interval = share, min_interval
        self._cost = 0.0
        self._last = -math.inf

    def due(self) -> bool:
        waited = time.perf_counter() - self._last
        return waited >= max(self.min_interval, self._cost / self.share)

    @contextlib.contextmanager
    def timing(self):
        started = time.perf_counter()
        try:
            yield
        finally:
            end = time.perf_counter()
            self._cost, self._last = end - started, end


# --- output folder: lock, manifest ------------------------------------------------------------
class FolderBusy(Exception):
    pass


_session: OutputSession | None = None


OWNER_WAIT_S = 1.0  # how long a run that lost the lock waits for the owner to write its pid


def _lock_owner(fd: int) -> list[str]:
    """The owner's "pid host command" from the lock file, read again for up to OWNER_WAIT_S
    while it is empty: the owner writes it right after taking the lock (two runs started
    together would otherwise name "another process" instead of the pid)."""
    deadline = time.monotonic() + OWNER_WAIT_S
    while True:
        os.lseek(fd, 0, os.SEEK_SET)
        owner = os.read(fd, 400).decode(errors="replace").split()
        if owner or time.monotonic() > deadline:
            return owner
        time.sleep(0.01)


class OutputSession:
    """Lock of an output folder for one command (rank 0 only), and the record of its files."""

    def __init__(self, out: Path, command: str):
        self.out = Path(out)
        self.command = command
        self.started = time.time()
        self._fd: int | None = None
        self._created = False
        self._made: list[Path] = []
        self._cleared = False
        self.files: set[str] = set()

    def acquire(self) -> None:
        out = self.out
        folder = out.absolute()
        while not folder.exists():  # the folders this run makes, deepest first
            self._made.append(folder)
            folder = folder.parent
        if self._made:
            out.mkdir(parents=True, exist_ok=True)
            self._created = True
        fd = os.open(out / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            try:
                owner = _lock_owner(fd)
            finally:
                os.close(fd)
            who = f"pid {owner[0]}" if owner else "another process"
            if len(owner) > 1:
                who += f" on {owner[1]}"
            raise FolderBusy(f"--out {out} is in use by another fe-beam run ({who}); wait for "
                             "it to finish or choose another folder") from None
        except OSError:
            pass  # a file system without locks (some network mounts): run unlocked
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()} {socket.gethostname()} {self.command}\n".encode())
        self._fd = fd

    def _previous_files(self) -> list[str]:
        try:
            manifest = json.loads((self.out / MANIFEST_NAME).read_text())
            return [str(name) for name in manifest.get("files", [])]
        except FileNotFoundError:
            return list(KNOWN_OUTPUTS)
        except (OSError, ValueError, AttributeError):
            return list(KNOWN_OUTPUTS)

    def clear_stale(self) -> None:
        """Remove what the previous run in this folder wrote (once, before the first write)."""
        if self._cleared:
            return
        self._cleared = True
        for name in self._previous_files():
            if "/" in name or name in ("", ".", "..", LOCK_NAME):
                continue
            path = self.out / name
            with contextlib.suppress(OSError):
                if path.is_file() or path.is_symlink():
                    path.unlink()
            # leftovers of interrupted atomic writes / two-copy files of that name
            for leftover in self.out.glob(f".{name}.*"):
                with contextlib.suppress(OSError):
                    leftover.unlink()
        self._write_manifest()

    def register(self, path: Path) -> None:
        path = Path(path)
        with contextlib.suppress(ValueError):
            if path.parent.resolve() != self.out.resolve():
                return
            self.clear_stale()
            if path.name not in self.files:
                self.files.add(path.name)
                self._write_manifest()

    def _write_manifest(self) -> None:
        data = {"command": self.command, "pid": os.getpid(), "files": sorted(self.files)}
        temporary = self.out / f".{MANIFEST_NAME}.{os.getpid()}"
        temporary.write_text(json.dumps(data, indent=1) + "\n")
        os.replace(temporary, self.out / MANIFEST_NAME)

    def release(self) -> None:
        # every fe_beam output written during the run (plots included), for the next run to
        # clear; a file of another name that changed meanwhile is the user's, never listed
        with contextlib.suppress(OSError):
            for path in self.out.iterdir():
                if (path.name in KNOWN_OUTPUTS and path.is_file()
                        and path.stat().st_mtime >= self.started - 1.0):
                    self.files.add(path.name)
            if self._cleared or self.files:
                self._write_manifest()
        if self._fd is not None:
            with contextlib.suppress(OSError):
                os.ftruncate(self._fd, 0)
            os.close(self._fd)
            self._fd = None
        if self._created and not self.files:
            # nothing was written (e.g. a configuration error): leave no empty folder behind
            for name in (LOCK_NAME, MANIFEST_NAME):
                with contextlib.suppress(OSError):
                    (self.out / name).unlink()
            for folder in self._made:
                with contextlib.suppress(OSError):
                    folder.rmdir()


def register_output(path) -> None:
    """Called by the writers before writing ``path``: clears stale results on first use."""
    if _session is not None:
        _session.register(Path(path))


@contextlib.contextmanager
def output_session(out: Path, command: str, comm):
    """Lock ``out`` for this command (collective; rank 0 holds the lock). Raises `FolderBusy`
    on every rank when another run holds it."""
    global _session
    session, problem = None, None
    if comm.rank == 0:
        session = OutputSession(out, command)
        try:
            session.acquire()
        except FolderBusy as error:
            problem = str(error)
        except OSError as error:
            problem = f"--out {out}: cannot write there ({error.strerror or error})"
    problem = comm.bcast(problem, root=0) if comm.size > 1 else problem
    if problem:
        raise FolderBusy(problem)
    _session = session
    try:
        yield session
    finally:
        _session = None
        if session is not None:
            session.release()


# --- up-front limits ----------------------------------------------------------------------------
MAX_STEPS = 1_000_000
WARN_STEPS = 100_000
MAX_DOFS = 20_000_000
WARN_DOFS = 2_000_000
# peak memory per unknown: the rod, measured (600k dofs: 470 MB, with the interpreter), and the
# 3D solid with a direct solver (MUMPS fill-in of a 3D stiffness), an order of magnitude more
BYTES_PER_DOF = {"rod": 1_000, "solid": 10_000}


class TooLarge(Exception):
    pass


def available_memory() -> float:
    try:
        with open("/proc/meminfo") as stream:
            for line in stream:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    return math.inf


def check_work(steps: float | None, dofs: float | None, allow_large: bool,
               what: str = "", kind: str = "rod") -> list[str]:
    """Refuse (`TooLarge`, one sentence with the estimate) work beyond sane limits unless
    ``allow_large``; return warnings for work above smaller thresholds."""
    notes, problems = [], []
    memory = BYTES_PER_DOF[kind] * dofs if dofs else 0.0
    if steps is not None and steps > MAX_STEPS:
        problems.append(f"about {steps:.3g} steps{what} (limit {MAX_STEPS:.0e})")
    elif steps is not None and steps > WARN_STEPS:
        notes.append(f"about {steps:.3g} steps{what}: this will take long")
    if dofs is not None and dofs > MAX_DOFS:
        problems.append(f"about {dofs:.3g} dofs (limit {MAX_DOFS:.0e})")
    elif dofs is not None and dofs > WARN_DOFS:
        notes.append(f"about {dofs:.3g} dofs: this will take long")
    available = available_memory()
    if memory > available:
        problems.append(f"about {memory / 1e9:.3g} GB of memory against {available / 1e9:.3g} GB "
                        "available")
    elif memory > 0.5 * available:
        notes.append(f"about {memory / 1e9:.3g} GB of memory (of {available / 1e9:.3g} GB "
                     "available)")
    if problems and not allow_large:
        raise TooLarge("the run is too large: " + ", ".join(problems) + "; set "
                       "[solver] allow_large = true to run it anyway")
    return notes + (problems if allow_large else [])


WARNED: set[str] = set()  # notes already printed by `warn` (the CLI does not repeat them)


def warn(comm, notes: list[str]) -> None:
    WARNED.update(notes)
    if comm.rank == 0:
        for note in notes:
            print(f"fe-beam: warning: {note}", file=sys.stderr, flush=True)

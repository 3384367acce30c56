import json
import logging
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

os.environ.setdefault("FE_BEAM_PROGRESS", "0")
# shared test helpers (tomlio, beam_cases, ...) importable from tests/ and its subfolders
sys.path.insert(0, str(Path(__file__).parent))

REFERENCE = Path(__file__).resolve().parents[1].parent / "shared" / "reference"

_running = {"test": "(collecting)", "sigterm": None}


def pytest_runtest_logstart(nodeid, location):
    _running["test"] = nodeid
    if _GUARDED:
        # PETSc's C-level handler can come back (the PyPI stack's suite ended with its exit
        # code 15 while this guard was installed): put the guard back before every test
        signal.signal(signal.SIGTERM, _stray_sigterm)


def _stray_sigterm(signum, frame):
    """A SIGTERM nobody in the suite meant for the pytest process: say so (which test, the
    process tree) and go on; a second one within a minute ends the run (exit 143)."""
    now = time.monotonic()
    if _running["sigterm"] is not None and now - _running["sigterm"] < 60:
        os.write(2, b"[conftest] second SIGTERM within a minute: stopping\n")
        os._exit(143)
    _running["sigterm"] = now
    try:
        tree = subprocess.run(["ps", "-eo", "pid,ppid,pgid,etime,args", "--forest"],
                              capture_output=True, text=True, timeout=10).stdout
    except Exception as error:  # noqa: BLE001 - a diagnostic only
        tree = f"(ps failed: {error})"
    tree = "\n".join(line for line in tree.splitlines() if not line.endswith("]"))  # no kthreads
    os.write(2, (f"\n[conftest] SIGTERM received by the pytest process {os.getpid()} during "
                 f"{_running['test']}; ignored once. Processes:\n{tree}\n").encode())


def _guard_sigterm() -> None:
    """PETSc's import installs C-level signal handlers, which end the process quietly (PyPI's
    PETSc with MPICH's MPI_ERR_OTHER, exit 15). The PyPI suite's exit 15 was not a signal (it
    was MPICH running out of communicators, tests/test_memory.py); this guard stays so that a
    stray SIGTERM, should one come, names the test and the process tree instead of ending the
    suite silently. The tests that send SIGTERM to this process install fe_beam's own handler
    first and put this one back."""
    if any(name.startswith(("OMPI_COMM_WORLD", "PMI_", "PMIX_", "MPI_LOCALNRANKS"))
           for name in os.environ):
        return  # a rank under mpirun: the launcher's SIGTERM (another rank failed) must end it
    try:
        from petsc4py import PETSc  # noqa: F401  (installs PETSc's handlers: replace them after)
    except ImportError:
        return
    signal.signal(signal.SIGTERM, _stray_sigterm)
    global _GUARDED
    _GUARDED = True


_GUARDED = False
_guard_sigterm()


_UNDER_MPIRUN = any(name.startswith(("OMPI_COMM_WORLD", "PMI_", "PMIX_", "MPI_LOCALNRANKS"))
                    for name in os.environ)


@pytest.fixture(autouse=True)
def _parallel_garbage():
    """Under mpirun: after every test, every rank frees the PETSc objects the test dropped
    (petsc4py destroys those of a communicator of several ranks only collectively; left on
    their garbage lists they hold MPI communicators, of which MPICH allows 2048 per process:
    the PyPI stack's 2-rank suite ran out of them)."""
    yield
    if _UNDER_MPIRUN:
        from mpi4py import MPI

        from fe_beam.cli import free_parallel_garbage

        free_parallel_garbage(MPI.COMM_WORLD)


@pytest.fixture(autouse=True, scope="session")
def _quiet_jit():
    from fe_beam.cli import quiet_jit_logging

    quiet_jit_logging()
    logging.getLogger("UFL").setLevel(logging.WARNING)


def reference(name: str) -> dict:
    path = REFERENCE / name
    if not path.is_file():
        pytest.skip(f"{path} not available (tests read ../shared/reference/)")
    return json.loads(path.read_text())


@pytest.fixture(scope="session")
def mattiasson():
    return reference("elastica_tip_load.json")


@pytest.fixture(scope="session")
def frequencies():
    return reference("cantilever_frequencies.json")

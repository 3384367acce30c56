"""The entry points of ``fe-beam validity``'s worker processes (``[validity] workers`` > 1).

Here, in a module that imports no finite-element code, so that a new ("spawn") worker process,
which imports this module to find them, can start PETSc its own way before dolfinx loads; the
solve (`fe_beam.analyses.validity.solve_point`) is reached through the lazy `fe_beam.analyses`
package once PETSc is set up."""

from __future__ import annotations

from fe_beam import analyses
from fe_beam.config.validity import parse_validity
from fe_beam.logs import quiet_jit_logging

__all__ = ["worker_point", "worker_start"]


def worker_start() -> None:
    """Set up a worker process: Ctrl-C is the parent's to handle (it ends the workers), PETSc
    without its signal handlers, no progress bars, no JIT chatter."""
    import os
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:  # Linux: end with the parent, however it ends (prctl PR_SET_PDEATHSIG = 1)
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, int(signal.SIGKILL))
    except (OSError, AttributeError):
        pass
    os.environ["FE_BEAM_PROGRESS"] = "0"
    import petsc4py

    petsc4py.init(["fe-beam", "-no_signal_handler"])
    quiet_jit_logging()


def worker_point(raw: dict, index: int) -> dict:
    """Solve point ``index`` of the map of ``raw`` in this worker process (on COMM_SELF)."""
    from mpi4py import MPI

    config = parse_validity(raw)
    return analyses.validity.solve_point(config.points[index], config, MPI.COMM_SELF)

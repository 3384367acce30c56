"""The ``mpirun`` of the MPI library mpi4py runs on: Open MPI's on Debian's stack (which refuses
root and more ranks than cores unless told), the venv's own MPICH on the PyPI stack."""

import shutil
import sys
from pathlib import Path

from mpi4py import MPI

OPEN_MPI = "Open MPI" in MPI.Get_library_version()


def mpirun_command(ranks: int, pass_env: tuple[str, ...] = ()) -> list[str] | None:
    """``[mpirun, options..., -n, ranks]`` passing the variables ``pass_env`` to every rank
    (MPICH passes the whole environment anyway); None when there is no matching mpirun."""
    if OPEN_MPI:
        mpirun = shutil.which("mpirun")
        if mpirun is None:
            return None
        forward = [item for name in pass_env for item in ("-x", name)]
        return [mpirun, "--allow-run-as-root", "--oversubscribe", "-n", str(ranks), *forward]
    own = Path(sys.executable).parent / "mpirun"
    mpirun = str(own) if own.exists() else shutil.which("mpiexec")
    return None if mpirun is None else [mpirun, "-n", str(ranks)]

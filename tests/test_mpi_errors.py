"""Errors under ``mpirun -n 2`` (issue 9, item 6): an error on any rank ends every rank within
seconds, with one message and the exit code of its kind (2 user mistake, 3 analysis failure,
1 internal error); never a hang, a traceback per rank or a PETSc segfault.

Each case is a real ``mpirun`` job with a timeout, so a hang fails the test instead of CI."""

import contextlib
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from mpi4py import MPI
from mpilaunch import mpirun_command
from test_config import BASE, dump_toml, edited

TIMEOUT_S = 90  # a job that hangs is killed here; the cases below end in seconds
pytestmark = pytest.mark.skipif(
    mpirun_command(2) is None or MPI.COMM_WORLD.size > 1,
    reason="needs mpirun (and a serial pytest)")
ROOT = Path(__file__).resolve().parents[1]


def mpirun(tmp_path, *command, ranks=2):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]))
    started = time.monotonic()
    # its own session: a launcher that ends its job by signalling the process group (MPICH's
    # hydra) must not reach the pytest process (the PyPI stack's suite ended with exit 15,
    # SIGTERM, at a later test); on a timeout the whole job is killed
    job = subprocess.Popen(
        [*mpirun_command(ranks, pass_env=("PYTHONPATH",)), sys.executable, *command],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path,
        start_new_session=True)
    try:
        stdout, stderr = job.communicate(timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        os.killpg(job.pid, signal.SIGKILL)
        job.communicate()
        raise
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(job.pid, signal.SIGKILL)  # no rank or proxy outlives its test
    process = subprocess.CompletedProcess(job.args, job.returncode, stdout, stderr)
    return process, time.monotonic() - started


def fe_beam(tmp_path, config, *extra, command="static", ranks=2):
    path = tmp_path / "c.toml"
    path.write_text(config if isinstance(config, str) else dump_toml(config))
    return mpirun(tmp_path, "-m", "fe_beam.cli", command, str(path), "--quiet", *extra,
                  ranks=ranks)


def one_message(process) -> str:
    """The job's own messages: exactly one line from fe-beam, no traceback, no PETSc error
    (mpirun's own banner about a non-zero exit code is not ours and may follow)."""
    ours = [line for line in process.stderr.splitlines() if line.startswith("fe-beam")]
    assert len(ours) == 1, process.stderr
    assert "Traceback" not in process.stderr and "PETSC ERROR" not in process.stderr, \
        process.stderr
    return ours[0]


def test_value_that_breaks_the_mesh_ends_both_ranks_with_exit_2(tmp_path):
    process, seconds = fe_beam(tmp_path, BASE, "--out", str(tmp_path / "o"),
                               "--set", "beam.length=1e-40")
    assert process.returncode == 2, process.stderr
    assert "beam" in one_message(process) and "length" in process.stderr
    assert seconds < 60


def test_output_folder_that_cannot_be_made_ends_both_ranks_with_exit_2(tmp_path):
    (tmp_path / "plain").write_text("a file")
    process, _ = fe_beam(tmp_path, BASE, "--out", "/proc/self/fe-beam-out")
    assert process.returncode == 2, process.stderr
    assert "--out" in one_message(process)


@pytest.mark.parametrize("elements, degree", [(1, 2), (1, 1)])
def test_fewer_elements_than_ranks_is_refused_with_exit_2(tmp_path, elements, degree):
    config = edited({"mesh.elements": elements, "mesh.degree": degree})
    process, _ = fe_beam(tmp_path, config, "--out", str(tmp_path / "o"))
    assert process.returncode == 2, process.stderr
    message = one_message(process)
    assert f"elements = {elements}" in message and "2 MPI ranks" in message, message
    assert not (tmp_path / "o" / "summary.json").exists()


@pytest.mark.parametrize("command", ["solid", "compare"])
def test_solid_mesh_coarser_than_the_section_is_refused_on_2_ranks(tmp_path, command):
    """Serially a 3D mesh with elements larger than the cross-section runs; on 2 ranks it gave
    NaN (mesh_size 0.1) or hung (0.05)."""
    config = (ROOT / "examples" / "finger_solid.toml").read_text()
    process, seconds = fe_beam(tmp_path, config, "--out", str(tmp_path / "o"),
                               "--set", "solid.mesh_size=0.04", command=command)
    assert process.returncode == 2, process.stderr
    message = one_message(process)
    assert "mesh_size = 0.04" in message and "2 MPI ranks" in message, message
    assert seconds < 60


def test_as_many_elements_as_ranks_runs(tmp_path):
    config = edited({"mesh.elements": 2, "loads.steps": 1, "output.plots": False,
                     "output.xdmf": False})
    process, _ = fe_beam(tmp_path, config, "--out", str(tmp_path / "o"))
    assert process.returncode == 0, process.stderr
    assert (tmp_path / "o" / "summary.json").is_file()


def test_command_line_mistake_is_printed_once(tmp_path):
    process, _ = fe_beam(tmp_path, BASE, "--out", str(tmp_path / "o"), "--steps", "3")
    assert process.returncode == 2, process.stderr
    assert "--steps" in one_message(process)


INJECT = """
import sys
from mpi4py import MPI
import fe_beam.cli as cli
import fe_beam.analyses.static as static
from fe_beam.config.schema import ConfigError

kind, rank = sys.argv[1], int(sys.argv[2])
solve = static.solve_static


def failing(*args, **kwargs):
    if rank < 0 or MPI.COMM_WORLD.rank == rank:
        raise ConfigError("[loads] injected") if kind == "config" else KeyError("injected")
    return solve(*args, **kwargs)


static.solve_static = failing
sys.exit(cli.main(sys.argv[3:]))
"""


@pytest.mark.parametrize("kind, rank, code", [
    ("config", 1, 2),     # one rank fails while the other is inside the solve: abort, code 2
    ("internal", 0, 1),   # rank 0 fails alone: abort with the internal-error code
    ("config", -1, 2),    # every rank fails at the same point: rank 0 prints, no abort
])
def test_exception_on_some_or_all_ranks_ends_the_job(tmp_path, kind, rank, code):
    script = tmp_path / "inject.py"
    script.write_text(textwrap.dedent(INJECT))
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(edited({"loads.steps": 2})))
    process, seconds = mpirun(tmp_path, str(script), kind, str(rank), "static", str(path),
                              "--out", str(tmp_path / "o"), "--quiet")
    assert process.returncode == code, process.stderr
    message = one_message(process)
    assert "injected" in message, message
    assert ("internal error" in message) == (kind == "internal")
    if rank < 0:  # all ranks agreed: a normal end, no abort
        assert "MPI_ABORT" not in process.stderr, process.stderr
    assert seconds < 60

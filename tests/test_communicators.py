"""MPI communicators are finite (MPICH: 2048 per process): fe_beam must give back those of a
finished run (issue 28, section 4: the PyPI stack's 2-rank suite ran out of them and crashed).

- a dropped solver frees its problem and mesh (the SNES convergence test is called through a
  weak reference: PETSc keeps its callbacks out of Python's garbage collector's sight);
- a command frees its PETSc objects on every rank (`fe_beam.cli.free_parallel_garbage`);
- inertia counts of one sparsity pattern share one MUMPS factor (`InertiaFactor`: each MUMPS
  instance keeps communicators after it is destroyed on PETSc 3.25);
- a command does not start with too few spare communicators (exit 2, one sentence)."""

import gc
import weakref

import numpy as np
import pytest
from beam_cases import bending_stiffness, cantilever
from mpi4py import MPI
from petsc4py import PETSc

import fe_beam
from fe_beam import BeamProblem, SolverSettings, cli
from fe_beam.solvers.inertia import InertiaFactor, inertia
from fe_beam.solvers.newton import NonlinearProblem, SNESSolver

COMM = MPI.COMM_WORLD
# more than MPICH's 2048 (all of them are counted there); Open MPI has many more, and a count
# that reaches the cap measures no loss (a run there does not exhaust it either)
CAP = 2100


def spare(cap: int = CAP) -> int:
    """Communicators this process can still make (up to ``cap``), after freeing the garbage."""
    cli.free_parallel_garbage(COMM)
    gc.collect()
    return cli.spare_communicators(COMM, up_to=cap)


def _solve_and_drop():
    problem = BeamProblem(cantilever(constraint="none", elements=6,
                                     tip_force=(0.0, -0.5 * bending_stiffness(0.01))), COMM)
    problem.set_load_factor(1.0)
    solver = SNESSolver(NonlinearProblem(problem.residual, problem.w, problem.bcs),
                        SolverSettings(), state_scale=1.0)
    assert solver.solve() >= 1
    mesh = problem.w.function_space.mesh
    return weakref.ref(solver), weakref.ref(problem), weakref.ref(mesh)


@pytest.mark.mpi
def test_a_dropped_solver_frees_its_problem_and_mesh():
    """Without `destroy` too: the solver, its problem and its mesh (with the mesh's
    communicators) go once nothing refers to them (the bound convergence test kept them to the
    end of the process)."""
    refs = _solve_and_drop()
    gc.collect()
    cli.free_parallel_garbage(COMM)
    gc.collect()
    # on several ranks the SNES waits on its mesh communicator's garbage list, with the
    # nonlinear problem and mesh its callbacks refer to: the solver and rod problem only
    expected = [True, True, True] if COMM.size == 1 else [True, True, False]
    assert [ref() is None for ref in refs] == expected


@pytest.mark.mpi
def test_a_command_gives_back_its_communicators(tmp_path):
    """Static runs (with their stability count) of one configuration: after the first (whose
    cached problem stays for the next), each run gives back every communicator it made."""
    config = {"beam": {"length": 0.5}, "section": {"shape": "circle", "d": 0.004},
              "material": {"E": 7.0e10, "nu": 0.33},
              "model": {"law": "reissner", "constraint": "none"},
              "mesh": {"elements": 6, "degree": 2},
              "supports": {"x0": "clamped", "xL": "free"},
              "loads": {"tip_force": [0.0, -2.0], "distributed": [0.0, -1.0], "steps": 2},
              "output": {"xdmf": False, "plots": False}}
    out = COMM.bcast(str(tmp_path), root=0)
    fe_beam.run("static", config, out)
    before = spare()
    for _ in range(3):
        assert fe_beam.run("static", config, out)["status"] == "converged"
    assert before - spare() == 0


def _pencil(comm, n: int):
    """Tridiagonal symmetric matrices K and G of one pattern (K positive definite, G not)."""
    K = PETSc.Mat().createAIJ([n, n], comm=comm, nnz=3)
    G = PETSc.Mat().createAIJ([n, n], comm=comm, nnz=3)
    start, end = K.getOwnershipRange()
    for i in range(start, end):
        K[i, i] = 2.0 + 0.01 * i
        G[i, i] = -1.0 - 0.5 * np.sin(i)
        for j in (i - 1, i + 1):
            if 0 <= j < n:
                K[i, j] = -1.0
                G[i, j] = 0.25
    for matrix in (K, G):
        matrix.assemble()
    return K, G


def _dense(A) -> np.ndarray:
    rows, columns, values = A.getValuesCSR()
    start, _ = A.getOwnershipRange()
    n = A.getSize()[0]
    local = np.zeros((n, n))
    for row in range(len(rows) - 1):
        span = slice(rows[row], rows[row + 1])
        local[start + row, columns[span]] = values[span]
    return A.getComm().tompi4py().allreduce(local)


@pytest.mark.mpi
def test_inertia_counts_of_one_pattern_share_one_factor():
    """20 counts of K + lambda G: one symbolic analysis and at most 2 communicators (a factor
    per count kept 5 each with PETSc 3.25's MUMPS); every count equals a fresh factorisation's
    and the signs of the eigenvalues of the dense matrix."""
    n = 40
    K, G = _pencil(COMM, n)
    A = K.copy()
    A.axpy(1.0, G)
    lambdas = np.linspace(0.0, 6.0, 20)
    before = spare()
    factor = InertiaFactor()
    counts = []
    for value in lambdas:
        A.zeroEntries()
        A.axpy(1.0, K, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        A.axpy(value, G, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        counts.append(factor.count(A))
    factor.destroy()
    lost = before - spare()
    assert factor.analyses == 1
    assert lost <= 2, lost
    negatives = [c[0] for c in counts]
    assert negatives[0] == 0 and negatives[-1] > 5, negatives  # the pencil crosses several
    for value, count in zip(lambdas[::4], counts[::4], strict=True):  # fresh: a few (5 each)
        B = K.copy()
        B.axpy(value, G)
        assert inertia(B) == count
        eigenvalues = np.linalg.eigvalsh(_dense(B))
        assert count[0] == int(np.sum(eigenvalues < 0)), (value, eigenvalues[:3])
        assert count[2] == int(np.sum(eigenvalues > 0))
        B.destroy()
    for value, count in zip(lambdas, counts, strict=True):
        B = K.copy()
        B.axpy(value, G)
        eigenvalues = np.linalg.eigvalsh(_dense(B))
        assert count == (int(np.sum(eigenvalues < 0)), 0, int(np.sum(eigenvalues > 0)))
        B.destroy()
    for matrix in (A, K, G):
        matrix.destroy()


def test_a_factor_starts_anew_for_another_pattern():
    K, G = _pencil(COMM, 12)
    factor = InertiaFactor()
    first = factor.count(K)
    wider = K.copy()
    wider.axpy(1e-3, G)  # the same pattern: numerical only
    factor.count(wider)
    assert factor.analyses == 1
    diagonal = PETSc.Mat().createAIJ([12, 12], comm=COMM, nnz=1)
    start, end = diagonal.getOwnershipRange()
    for i in range(start, end):
        diagonal[i, i] = -1.0 if i < 5 else 1.0
    diagonal.assemble()
    assert factor.count(diagonal) == (5, 0, 7)
    assert factor.analyses == 2
    assert factor.count(K) == first and first == (0, 0, 12)
    factor.destroy()
    for matrix in (K, G, wider, diagonal):
        matrix.destroy()


class _Scarce:
    """A communicator of which only ``left`` more duplicates can be made."""

    def __init__(self, comm, left: int):
        self.comm, self.left = comm, left

    def __getattr__(self, name):
        return getattr(self.comm, name)

    def Dup(self):
        if self.left <= 0:
            raise MPI.Exception(MPI.ERR_OTHER)
        self.left -= 1
        return self.comm.Dup()


@pytest.mark.mpi
def test_spare_communicators_counts_to_what_mpi_refuses():
    assert cli.spare_communicators(_Scarce(COMM, 7)) == 7
    assert cli.spare_communicators(_Scarce(COMM, 500)) == cli.MIN_SPARE_COMMUNICATORS
    assert cli.spare_communicators(COMM, up_to=10) == 10


def test_a_command_does_not_start_without_spare_communicators(tmp_path, monkeypatch, capsys):
    """Exit 2 and one sentence (the CLI), ConfigError (fe_beam.run), before any output."""
    monkeypatch.setattr(cli, "spare_communicators", lambda comm, up_to=64: 12)
    config = tmp_path / "c.toml"
    config.write_text('[beam]\nlength = 1.0\n[section]\nshape = "circle"\nd = 0.01\n'
                      '[material]\nE = 1e9\nnu = 0.3\n[loads]\ntip_force = [0.0, -1.0]\n')
    out = tmp_path / "out"
    assert cli.main(["static", str(config), "--out", str(out), "--quiet"]) == 2
    message = capsys.readouterr().err
    assert "only 12 MPI communicators are left" in message and "Traceback" not in message
    assert not (out / "summary.json").exists()
    with pytest.raises(fe_beam.ConfigError, match="only 12 MPI communicators"):
        fe_beam.run("static", str(config), None)

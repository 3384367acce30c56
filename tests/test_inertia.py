"""Sparse, parallel inertia (fe_beam.solvers.inertia, docs/theory.md, Sparse inertia): the MUMPS
LDL^T
pivot counts equal dense eigenvalue counts for plain symmetric matrices, saddle points
(negative(KKT) - m = negative(Z^T K Z)), the rod under every constraint kind on one and two
ranks and beyond the dense size limit, and the 3D column below and past its buckling load."""

import json
import math

import numpy as np
import pytest
import scipy.linalg
from beam_cases import bending_stiffness, cantilever
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam import LoadStepping, SolverSettings
from fe_beam.analyses.static import STABILITY_MAX_DOFS, StaticContinuation
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers.critical import spectrum
from fe_beam.solvers.inertia import inertia, rod_unstable_count, solid_unstable_count

EI = bending_stiffness(0.01)
EULER = math.pi**2 * EI / 4  # first critical load of the cantilever, L = 1
serial = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="dense reference: serial")


def _petsc(dense: np.ndarray) -> PETSc.Mat:
    n = dense.shape[0]
    A = PETSc.Mat().createAIJ((n, n), comm=MPI.COMM_SELF)
    A.setUp()
    rows, cols = np.nonzero(dense)
    for i, j in zip(rows, cols, strict=True):
        A.setValue(int(i), int(j), dense[i, j])
    A.assemble()
    return A


@serial
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_inertia_equals_dense_eigenvalue_signs(seed):
    rng = np.random.default_rng(seed)
    n = 40
    Q = np.linalg.qr(rng.normal(size=(n, n)))[0]
    eigenvalues = rng.uniform(0.1, 2.0, n) * rng.choice([-1.0, 1.0], n)
    dense = Q @ np.diag(eigenvalues) @ Q.T
    dense = 0.5 * (dense + dense.T)
    A = _petsc(dense)
    assert inertia(A) == (int(np.sum(eigenvalues < 0)), 0, int(np.sum(eigenvalues > 0)))
    A.destroy()


@serial
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_saddle_point_count_is_that_of_the_constrained_stiffness(seed):
    """negative([[K, C^T], [C, 0]]) - m = negative(Z^T K Z), Z spanning null(C)."""
    rng = np.random.default_rng(seed)
    n, m = 30, 7
    K = rng.normal(size=(n, n))
    K = K + K.T + 2.0 * np.eye(n)
    C = rng.normal(size=(m, n))
    Z = scipy.linalg.null_space(C)
    expected = int(np.sum(np.linalg.eigvalsh(Z.T @ K @ Z) < 0))
    kkt = np.block([[K, C.T], [C, np.zeros((m, m))]])
    A = _petsc(kkt)
    negative, _, _ = inertia(A)
    A.destroy()
    assert negative - m == expected
    assert 0 < expected < n - m  # a case that can fail: neither definite nor trivially counted


def _run(constraint, factor, comm, elements=24):
    model = cantilever(constraint=constraint, elements=elements,
                       tip_force=(-factor * EULER, 0.0))
    run = StaticContinuation(StaticConfig(model, SolverSettings(), LoadStepping(steps=4)), comm)
    run.advance(1.0, LoadStepping(steps=4))
    return run


# critical loads of the cantilever (2n - 1)^2 P_E: 1, 9, 25 P_E; the straight branch has one
# falling direction per mode passed
CASES = [(0.5, 0), (1.01, 1), (15.0, 2), (30.0, 3)]
CONSTRAINTS = ["none", "inextensible", "unshearable", "inextensible-unshearable"]


@serial
@pytest.mark.parametrize("constraint", CONSTRAINTS)
def test_rod_sparse_count_equals_dense_count(constraint):
    for factor, modes in CASES:
        run = _run(constraint, factor, MPI.COMM_SELF)
        try:
            dense = spectrum(run)
            assert dense.values.size  # the dense eigenvalues, not the sparse fallback
            assert rod_unstable_count(run) == dense.unstable == modes, (factor, modes)
        finally:
            run.destroy()


@pytest.mark.mpi
@pytest.mark.parametrize("constraint", ["none", "inextensible-unshearable"])
def test_rod_count_on_all_ranks_equals_the_serial_dense_count(constraint):
    for factor, modes in [(0.5, 0), (15.0, 2)]:
        run = _run(constraint, factor, MPI.COMM_WORLD)
        try:
            stability = run.stability()  # sparse on several ranks, dense on one
            assert stability == {"stable": modes == 0, "energy_decreasing_directions": modes}
            assert rod_unstable_count(run) == modes
        finally:
            run.destroy()
        reference = _run(constraint, factor, MPI.COMM_SELF)
        try:
            assert spectrum(reference).unstable == modes
        finally:
            reference.destroy()


@pytest.mark.mpi
def test_large_rod_stability_is_checked():
    """Beyond STABILITY_MAX_DOFS the stability comes from the sparse inertia (no mode)."""
    run = _run("inextensible", 15.0, MPI.COMM_WORLD, elements=300)
    try:
        assert run.problem.global_dofs > STABILITY_MAX_DOFS
        found = spectrum(run, with_mode=True)
        assert found.mode is None and found.values.size == 0
        assert run.stability() == {"stable": False, "energy_decreasing_directions": 2}
    finally:
        run.destroy()


# --- the 3D column -------------------------------------------------------------------------
# a rectangular section (b != h): one weakest buckling mode, the other direction far above
COLUMN = {"beam": {"length": 0.2}, "section": {"shape": "rectangle", "b": 0.016, "h": 0.01},
          "material": {"E": 1.0e6, "nu": 0.0}, "model": {"law": "reissner"},
          "mesh": {"elements": 20}, "loads": {"tip_force": [-1.0, 0.0], "steps": 2},
          "solid": {"material": "neo-hookean", "formulation": "displacement", "order": 1,
                    "mesh_size": 0.01},
          "buckling": {"count": 2}}


def _column(formulation="displacement"):
    config = json.loads(json.dumps(COLUMN))
    if formulation == "mixed-up":  # Taylor-Hood P2-P1, coarser (dense reference size)
        config["solid"] |= {"formulation": formulation, "order": 2, "mesh_size": 0.02}
    return config


def _solid_at(config, factor, comm):
    from fe_beam.analyses.solid import SolidRun
    from fe_beam.config.buckling import parse_buckling

    _, parsed, _ = parse_buckling(config)
    run = SolidRun(parsed, comm)
    run.advance(factor, parsed.stepping)
    return run


def _dense_count(problem) -> int:
    """Independent reference: dense eigenvalues of the Hessian (serial), the pressure block
    condensed for the u-p formulation."""
    import ufl
    from dolfinx import fem

    from fe_beam.fem import compat

    form = fem.form(ufl.derivative(problem.residual, problem.w, ufl.TrialFunction(problem.W)))
    A = compat.assemble_matrix(form, bcs=problem.bcs)
    A.assemble()
    dense = A.convert("dense").getDenseArray().copy()
    A.destroy()
    dense = 0.5 * (dense + dense.T)
    if problem.p is not None:
        p = np.asarray(compat.sub_space_collapsed(problem.W, 1)[1])
        u = np.setdiff1d(np.arange(dense.shape[0]), p)
        dense = (dense[np.ix_(u, u)]
                 - dense[np.ix_(u, p)] @ np.linalg.solve(dense[np.ix_(p, p)], dense[np.ix_(p, u)]))
    values = np.linalg.eigvalsh(dense)
    return int(np.sum(values < -1e-10 * np.abs(values).max()))


def _factors(formulation):
    """`fe-beam buckling`'s first load factor of the column (confirmed on the path) and the
    second linearised one about the unloaded state (past the first, the 3D mesh's load
    stepping may leave the straight branch: issue 28 reports only confirmed factors)."""
    from fe_beam.analyses.buckling import run_buckling

    summary = run_buckling(_column(formulation), None, MPI.COMM_SELF, progress=False)
    return summary["load_factors"][0], summary["linearised_load_factors"][1]


@serial
@pytest.mark.parametrize("formulation", ["displacement", "mixed-up"])
def test_3d_column_count_below_and_past_buckling(formulation):
    first, second = _factors(formulation)
    assert second > 1.2 * first
    for factor, expected in [(0.9 * first, 0), (1.1 * first, 1)]:
        run = _solid_at(_column(formulation), factor, MPI.COMM_SELF)
        count = solid_unstable_count(run.problem)
        assert count == _dense_count(run.problem) == expected, (formulation, factor)


@pytest.mark.mpi
def test_3d_column_count_on_all_ranks():
    first = _factors("mixed-up")[0]
    run = _solid_at(_column("mixed-up"), 1.1 * first, MPI.COMM_WORLD)
    assert solid_unstable_count(run.problem) == 1


@pytest.mark.mpi
def test_3d_column_path_reports_stability():
    """`fe-beam path` of the 3D column (tip force only): stable below `fe-beam buckling`'s
    first load factor, one energy-decreasing direction past it (on any number of ranks)."""
    from fe_beam.analyses.path import run_path

    first, second = _factors("displacement")
    config = _column()
    config.pop("buckling")
    config["path"] = {"arc_length": 0.1, "max_steps": 30, "max_load_factor": 1.3 * first}
    summary = run_path(config, None, MPI.COMM_WORLD, progress=False)
    assert summary["status"] == "converged"
    counts = [(p["load_factor"], p["energy_decreasing_directions"], p["stable"])
              for p in summary["path"]]
    assert all(n == (0 if f < first else 1) and s == (n == 0) for f, n, s in counts
               if f < second), counts
    assert {n for _, n, _ in counts} == {0, 1}


@pytest.mark.mpi
def test_bifurcation_located_from_counts_on_all_ranks():
    """A perfect column on the ranks of COMM_WORLD (sparse counts in parallel: bisection on
    the count alone) locates the same bifurcation as on one rank (dense eigenvalue sign)."""
    from pathlib import Path

    from fe_beam.analyses.path import run_path
    from fe_beam.config.schema import load_config

    examples = Path(__file__).resolve().parents[1] / "examples"
    config = load_config(examples / "elastica_path.toml")
    config["loads"]["tip_force"] = [-0.02, 0.0]
    config["path"] |= {"branch_switch": "none", "max_load_factor": 1.5, "max_steps": 30}
    reference = run_path(config, None, MPI.COMM_SELF, progress=False)
    summary = run_path(config, None, MPI.COMM_WORLD, progress=False)
    (expected,) = [c for c in reference["critical_points"] if c["kind"] == "bifurcation"]
    (found,) = [c for c in summary["critical_points"] if c["kind"] == "bifurcation"]
    assert found["load_factor"] == pytest.approx(expected["load_factor"], rel=2e-6)
    # (the step sizes may differ: Newton's iteration counts on the straight branch do)
    assert all(p["energy_decreasing_directions"] == (p["load_factor"] > found["load_factor"])
               for p in summary["path"])

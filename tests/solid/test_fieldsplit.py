"""The scalable solvers of the 3D solid: ``[solid] solver = "fieldsplit"`` (FGMRES + Schur
fieldsplit for the Taylor-Hood u-p formulation, CG + GAMG for the displacement formulation) gives
MUMPS's equilibrium; ``"auto"`` picks MUMPS on small meshes and the iterative solver above
`AUTO_DIRECT_MAX_DOFS`; a bad ``[solid] solver`` is a usage error (exit 2)."""

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc
from test_solid_driver import DROP, FINGER, assert_usage_error, edited, run_cli, shared_folder

from fe_beam.fem import compat
from fe_beam.model.settings import (
    AUTO_DIRECT_MAX_DOFS,
    FIELDSPLIT_OPTIONS,
    SOLID_LINEAR_SOLVERS,
    resolve_solid_solver,
)
from fe_beam.solid import (
    Discretization,
    FingerGeometry,
    MeshSizes,
    NeoHookean,
    SolidFingerProblem,
    TendonLoad,
    TendonPath,
    create_finger_mesh,
)
from fe_beam.solvers.newton import LoadStepping, SolverSettings

# a tapered finger bent by a tendon to a tip rotation of ~0.5 rad (geometrically nonlinear),
# coarse (P2-P1 ~ 2.5k unknowns): nu = 0.49 makes the u-p saddle point a real one
GEOMETRY = FingerGeometry(0.1, 0.02, 0.02, 0.01,
                          tendons=(TendonPath.from_offsets(0.1, 0.008, 0.004),))
MATERIAL = NeoHookean.from_young(0.6e6, 0.49)
TENSION = 2.0


@pytest.fixture(scope="module")
def finger():
    return create_finger_mesh(GEOMETRY, MeshSizes(0.01), MPI.COMM_WORLD)


def solve(finger, formulation: str, solver: str):
    problem = SolidFingerProblem(
        finger, MATERIAL, tendons=[TendonLoad(tension=TENSION)],
        discretization=Discretization(formulation),
        solver=SolverSettings(linear_solver=solver), prefix=f"fieldsplit_test_{solver}_",
    )
    result = problem.solve(LoadStepping(steps=1))
    return problem, result


def relative_difference(a, b, comm) -> float:
    """||a - b|| / ||b|| over all ranks (owned entries)."""
    num = comm.allreduce(float(np.sum((a - b) ** 2)), op=MPI.SUM)
    den = comm.allreduce(float(np.sum(b**2)), op=MPI.SUM)
    return float(np.sqrt(num / den))


@pytest.mark.mpi
@pytest.mark.parametrize("formulation", ["mixed", "displacement"])
def test_fieldsplit_gives_the_mumps_equilibrium(finger, formulation):
    """Same mesh, same load path: the displacement (and pressure) fields agree to 1e-8."""
    direct, _ = solve(finger, formulation, "mumps")
    iterative, result = solve(finger, formulation, "fieldsplit")
    comm = finger.mesh.comm
    pc = iterative.snes_solver.snes.getKSP().getPC()
    expected = "fieldsplit" if formulation == "mixed" else "gamg"
    assert iterative.linear_solver == expected and pc.getType() == expected
    assert direct.snes_solver.snes.getKSP().getPC().getType() == "lu"
    if formulation == "mixed":  # the equilibrium below is reached with a lagged preconditioner
        options = PETSc.Options(iterative.snes_solver.snes.getOptionsPrefix())
        lag = options.getInt("snes_lag_preconditioner", 1)
        assert lag == FIELDSPLIT_OPTIONS["snes_lag_preconditioner"] > 1
    assert all(s["linear_iterations"] > s["iterations"] for s in result["steps"]), (
        "a Krylov solver takes several iterations per Newton step")
    rotation = result["tip_rotation"]
    assert 0.2 < rotation < 1.0, "the test needs a geometrically nonlinear state"
    fields = {"u": (direct.displacement(), iterative.displacement())}
    if formulation == "mixed":
        fields["p"] = (direct.w.sub(1).collapse(), iterative.w.sub(1).collapse())
    for name, (a, b) in fields.items():
        n = a.function_space.dofmap.index_map.size_local * a.function_space.dofmap.index_map_bs
        difference = relative_difference(b.x.array[:n], a.x.array[:n], comm)
        print(f"{formulation} {name}: fieldsplit vs MUMPS relative difference {difference:.2e}")
        assert difference < 1e-8, name
    assert np.allclose(iterative.tip_displacement(), direct.tip_displacement(), rtol=1e-8,
                       atol=1e-8 * np.abs(direct.tip_displacement()).max())
    for p in (direct, iterative):
        p.snes_solver.destroy()


@pytest.mark.mpi
def test_fieldsplit_fields_cover_the_mixed_space_once(finger):
    """The u and p index sets partition W's owned dofs; the u set comes in nodes of 3."""
    problem = SolidFingerProblem(finger, MATERIAL, tendons=[TendonLoad(tension=TENSION)],
                                 discretization=Discretization("mixed"),
                                 solver=SolverSettings(linear_solver="fieldsplit"),
                                 prefix="fieldsplit_test_is_")
    split = problem._fieldsplit
    imap = problem.W.dofmap.index_map
    start = imap.local_range[0]
    u, p = split.is_u.getIndices(), split.is_p.getIndices()
    owned = np.arange(start, start + imap.size_local)
    assert np.array_equal(np.sort(np.concatenate([u, p])), owned)
    assert split.is_u.getBlockSize() == 3
    V0, u_map = compat.sub_space_collapsed(problem.W, 0)
    n_u = V0.dofmap.index_map.size_global * V0.dofmap.index_map_bs
    assert finger.mesh.comm.allreduce(len(u), op=MPI.SUM) == n_u
    # the Schur preconditioner is -(1/mu + 1/kappa) times the pressure mass matrix: its
    # entries sum to -(1/mu + 1/kappa) |Omega|
    S = split.schur_preconditioner
    ones = S.createVecRight()
    ones.set(1.0)
    total = S.createVecLeft()
    S.mult(ones, total)
    scale = 1 / MATERIAL.shear_modulus + 1 / MATERIAL.kappa
    g = GEOMETRY
    volume = g.length * g.width * 0.5 * (g.height_base + g.height_tip)
    assert total.sum() == pytest.approx(-scale * volume, rel=1e-10)
    problem.snes_solver.destroy()


def test_auto_picks_mumps_below_and_the_iterative_solver_above_the_threshold():
    n = AUTO_DIRECT_MAX_DOFS
    for mixed, iterative in ((True, "fieldsplit"), (False, "gamg")):
        assert resolve_solid_solver("auto", mixed, 1000) == "mumps"
        assert resolve_solid_solver("auto", mixed, n) == "mumps"
        assert resolve_solid_solver("auto", mixed, n + 1) == iterative
        assert resolve_solid_solver("auto", mixed, 10 * n) == iterative
        assert resolve_solid_solver("auto", mixed, 500, threshold=100) == iterative
        assert resolve_solid_solver("mumps", mixed, 10 * n) == "mumps"
        assert resolve_solid_solver("fieldsplit", mixed, 10) == iterative
    assert resolve_solid_solver("gamg", False, 10) == "gamg"
    with pytest.raises(ValueError, match="gamg"):
        resolve_solid_solver("gamg", True, 10)
    assert SOLID_LINEAR_SOLVERS == ("auto", "mumps", "gamg", "fieldsplit")


def test_auto_resolves_to_mumps_on_a_small_mesh_and_reports_it(tmp_path):
    config = edited(FINGER, {"solid.formulation": "mixed-up", "loads.steps": 1,
                             "tendons.tension": 0.5, "output": {"xdmf": False, "plots": False}})
    config["solid"].pop("solver", None)  # the default is "auto"
    code, _, stderr, out = run_cli("solid", shared_folder(tmp_path), config)
    assert code == 0, stderr
    import json

    summary = json.loads((out / "summary.json").read_text())
    assert summary["dofs"] < AUTO_DIRECT_MAX_DOFS
    assert summary["linear_solver_resolved"] == "mumps"


@pytest.mark.parametrize("value", ["ilu", "FieldSplit", "hypre"])
def test_bad_solver_exits_2_naming_the_key_and_the_choices(tmp_path, value):
    code, _, stderr, out = run_cli("solid", shared_folder(tmp_path),
                                   edited(FINGER, {"solid.solver": value}))
    assert_usage_error(code, stderr, "solid", "[solid] solver")
    if MPI.COMM_WORLD.rank == 0:
        assert all(name in stderr for name in SOLID_LINEAR_SOLVERS), stderr
        assert repr(value) in stderr
    assert not (out / "summary.json").exists()


@pytest.mark.parametrize("value", ["fieldsplit", "gamg"])
def test_krylov_solver_with_pull_in_control_exits_2(tmp_path, value):
    """The pull-in constraint's bordered Newton stalled with the Krylov solvers (140 tiny load
    steps in 200 s where MUMPS takes 8 in 9 s): refused, naming the key and the tendon."""
    config = edited(FINGER, {"solid.solver": value, "tendons.tension": DROP,
                             "tendons.pull_in": 0.003})
    code, _, stderr, out = run_cli("solid", shared_folder(tmp_path), config)
    assert_usage_error(code, stderr, "solid", "[solid] solver")
    if MPI.COMM_WORLD.rank == 0:
        assert "pull_in" in stderr and "auto" in stderr, stderr
    assert not (out / "summary.json").exists()

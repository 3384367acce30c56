"""The 3D finger problem against beam theory, in parallel, under pull-in control, mixed u-p."""

from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from fe_beam.solid import (
    Discretization,
    FingerGeometry,
    MeshSizes,
    NeoHookean,
    SolidFingerProblem,
    TendonLoad,
    TendonPath,
    create_finger_mesh,
    write_xdmf,
)
from fe_beam.solvers.newton import LoadStepping, SolverSettings

# straight prism, L/H = 10, E = 1 (units drop out of the relative checks)
L, H, B, E = 10.0, 1.0, 1.0, 1.0
INERTIA = B * H**3 / 12


def timoshenko_tip_deflection(P, nu):
    """v = P L^3 / (3 E I) + P L / (k G A), k = 10 (1 + nu) / (12 + 11 nu) (Cowper)."""
    G = E / (2 * (1 + nu))
    k = 10 * (1 + nu) / (12 + 11 * nu)
    return P * L**3 / (3 * E * INERTIA) + P * L / (k * G * B * H)


def prism_tip_load(size, clamp_size, nu, P, comm=MPI.COMM_WORLD, **kw):
    finger = create_finger_mesh(
        FingerGeometry(L, B, H), MeshSizes(size, clamp=clamp_size, clamp_distance=1.0), comm
    )
    problem = SolidFingerProblem(finger, NeoHookean.from_young(E, nu), tip_force=(0, P, 0), **kw)
    return problem, problem.solve(LoadStepping(steps=1))


@pytest.mark.parametrize(
    "nu, tolerance",
    [(0.3, 0.01), (0.0, 5e-4)],  # nu = 0.3: the fully clamped face stiffens the 3D bar ~0.65 %
)
def test_tip_load_matches_timoshenko_and_converges(nu, tolerance):
    P = 1e-5  # v/L ~ 4e-3: geometric nonlinearity ~1e-5, negligible
    exact = timoshenko_tip_deflection(P, nu)
    errors = []
    for size, clamp_size in [(0.7, 0.7), (0.5, 0.25)]:
        problem, result = prism_tip_load(size, clamp_size, nu, P)
        v = result["tip_displacement"][1]
        errors.append(abs(v / exact - 1))
        theta_beam = P * L**2 / (2 * E * INERTIA)
        assert result["tip_rotation"] == pytest.approx(theta_beam, rel=0.01)
        assert problem.tip_area == pytest.approx(B * H, rel=1e-12)
    print(f"nu={nu}: Timoshenko relative errors {errors}")
    assert errors[1] < tolerance
    assert errors[1] < errors[0]


@pytest.fixture(scope="module")
def tendon_bar():
    """Prismatic bar, straight tendon at constant offset delta = H/4 from clamp to tip."""
    delta, nu = 0.25, 0.3
    kappa = 1e-3  # kappa L = 0.01 rad: small
    tau = kappa * E * INERTIA / delta
    geometry = FingerGeometry(L, B, H, tendons=(TendonPath.from_offsets(L, delta, delta),))

    def run(comm, formulation="displacement", material=None, anchor="face", size=0.5):
        finger = create_finger_mesh(geometry, MeshSizes(size, tendon=size / 2), comm)
        problem = SolidFingerProblem(
            finger, material or NeoHookean.from_young(E, nu), tendons=[TendonLoad(tension=tau)],
            discretization=Discretization(formulation), anchor=anchor,
        )
        return problem, problem.solve(LoadStepping(steps=1))

    problem, result = run(MPI.COMM_WORLD)
    return {"kappa": kappa, "tau": tau, "run": run, "problem": problem, "result": result,
            "geometry": geometry}


def fitted_curvature(result, x_min=2.0, x_max=8.0):
    """2 c of the parabola v = a + b x + c x^2 fitted to the backbone away from the ends."""
    x = np.array(result["backbone"]["x"])
    v = np.array(result["backbone"]["centroid"])[:, 1]
    keep = (x >= x_min - 1e-12) & (x <= x_max + 1e-12)
    return 2 * np.polyfit(x[keep], v[keep], 2)[0]


def test_constant_offset_tendon_bends_toward_plus_y_with_beam_curvature(tendon_bar):
    result, kappa = tendon_bar["result"], tendon_bar["kappa"]
    assert result["tip_displacement"][1] > 0 and result["tip_rotation"] > 0
    measured = fitted_curvature(result)
    print(f"tendon curvature {measured:.6g} vs tau delta / EI = {kappa:.6g}")
    assert measured == pytest.approx(kappa, rel=0.02)
    assert result["tip_rotation"] == pytest.approx(kappa * L, rel=0.02)
    # the tendon shortens: l0 - l ~ delta theta_tip + tau L / EA
    assert result["tendon_lengths"][0] < result["tendon_reference_lengths"][0]
    assert result["tensions"] == [pytest.approx(tendon_bar["tau"])]
    assert result["max_principal_stretch"] > 1.0


def test_bulk_mask_leaves_out_the_clamp_edges_the_loaded_tendon_ends_and_the_tendon():
    from fe_beam.solvers.solid import bulk_mask

    geometry = FingerGeometry(L, B, H, height_tip=0.5)  # H(x) = 1 - 0.05 x
    chain = np.array([[0.0, 0.25, 0.0], [5.0, 0.2, 0.0], [L, 0.125, 0.0]])
    points = np.array([
        [0.4, -0.3, 0.0],  # within H(0)/2 of the clamp
        [0.6, -0.3, 0.0],  # near the tendon entry on the clamp: no zone there
        [L - 0.45, -0.3, 0.0],  # within H(L) = 0.5 of the tip face the tendon ends on
        [L - 0.55, -0.3, 0.0],  # just outside that slab
        [5.0, 0.25, 0.0],  # 0.05 from the tendon: inside its tube, radius 0.1 H(5) = 0.075
        [5.0, 0.3, 0.0],  # 0.1 from it: outside the tube
    ])
    assert bulk_mask(points, [chain], geometry).tolist() == [False, True, False, True, False,
                                                            True]


@pytest.mark.parametrize("anchor", ["point", "face"])
def test_bulk_stretch_converges_and_matches_beam_theory(tendon_bar, anchor):
    """Bulk maximum principal strain on two meshes. A point anchor puts the tendon's force on
    one vertex: the largest stretch next to it grows without bound under refinement, and its
    1/r^2 far field still reaches the bulk. The face anchor (a plate) spreads the same force
    and moment: the bulk is then the beam's state, whose largest principal strain is the
    lateral (Poisson) strain of the compressed fibres, nu (kappa H / 2 + tau / (E A))."""
    runs = [tendon_bar["run"](MPI.COMM_WORLD, anchor=anchor, size=size)[1] for size in (0.5, 0.25)]
    strains = {key: [run[key] - 1 for run in runs]
               for key in ("max_principal_stretch", "max_principal_stretch_bulk")}
    print(f"{anchor} anchor, max principal strain, coarse and fine: {strains}")
    anywhere, bulk = strains["max_principal_stretch"], strains["max_principal_stretch_bulk"]
    poisson = 0.3 * (tendon_bar["kappa"] * H / 2 + tendon_bar["tau"] / (E * B * H))
    if anchor == "point":
        assert anywhere[1] > 2 * anywhere[0]
        assert bulk[1] == pytest.approx(bulk[0], rel=0.03)
        assert poisson <= bulk[1] < anywhere[1]
    else:
        assert bulk[1] == pytest.approx(bulk[0], rel=0.01)
        assert bulk[1] == pytest.approx(poisson, rel=0.03)


@pytest.fixture(scope="module")
def coarse_tip_load():
    return prism_tip_load(0.7, 0.7, 0.3, 1e-5)


def test_postprocessing_is_consistent(coarse_tip_load):
    """Backbone at x = L (Gauss points on the tip face) equals the tip-face average, and the
    Kabsch rotation agrees with the averaged deformed normal."""
    problem, result = coarse_tip_load
    tip = problem.backbone([L], n_gauss=6)["displacement"][0]
    scale = np.abs(result["tip_displacement"]).max()
    assert np.allclose(tip, result["tip_displacement"], rtol=0, atol=1e-5 * scale)
    rotation = problem.tip_rotation()
    assert rotation["normal_angle"] == pytest.approx(rotation["angle"], rel=0.02)
    R = np.array(rotation["matrix"])
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-12) and np.linalg.det(R) > 0
    assert result["backbone"]["centroid"][0] == pytest.approx([0, 0, 0], abs=1e-12)


@pytest.mark.mpi
def test_serial_and_parallel_runs_agree(tendon_bar):
    """The same problem on COMM_SELF and on COMM_WORLD (meaningful under mpirun -n 2)."""
    world = tendon_bar["problem"]
    if MPI.COMM_WORLD.size == 1:
        pytest.skip("run under mpirun -n 2 to compare a serial and a parallel solve")
    owners = np.zeros(world.comm.size, dtype=np.int64)
    start, end = world.problem.b.getOwnershipRange()
    owners[world.comm.rank] = np.count_nonzero((world.cables[0].dofs >= start)
                                               & (world.cables[0].dofs < end))
    owners = world.comm.allreduce(owners, op=MPI.SUM)
    assert np.count_nonzero(owners) > 1, "the tendon should cross the rank boundary"
    _, serial = tendon_bar["run"](MPI.COMM_SELF)
    parallel = tendon_bar["result"]
    for key in ("tip_displacement", "tip_rotation", "tendon_lengths", "max_principal_stretch",
                "max_principal_stretch_bulk"):
        a, b = np.asarray(serial[key]), np.asarray(parallel[key])
        print(f"serial vs parallel {key}: max rel diff {np.abs(a - b).max() / np.abs(b).max():.2e}")
        assert np.allclose(a, b, rtol=1e-8, atol=1e-8 * np.abs(b).max()), key
    a = np.array(serial["backbone"]["displacement"])
    b = np.array(parallel["backbone"]["displacement"])
    assert np.allclose(a, b, rtol=0, atol=1e-8 * np.abs(b).max())


def test_mixed_formulation_near_incompressible(tendon_bar):
    """Taylor-Hood P2-P1 at kappa/mu = 500 (nu = 0.499): same beam curvature tau delta/(E I)."""
    mu = 1.0 / 3.0
    material = NeoHookean(kappa=500 * mu, mu=mu)
    _, result = tendon_bar["run"](MPI.COMM_WORLD, "mixed", material)
    kappa = tendon_bar["tau"] * 0.25 / (material.young_modulus * INERTIA)
    measured = fitted_curvature(result)
    print(f"mixed: curvature {measured:.6g} vs {kappa:.6g}")
    assert measured == pytest.approx(kappa, rel=0.02)


@pytest.mark.mpi
def test_pull_in_control_recovers_the_tension():
    """Tapered, rounded finger: solve with tension T, then prescribe the resulting pull-in."""
    tendon = TendonPath.from_offsets(3.0, 0.3, 0.15, x_anchor=2.8)
    geometry = FingerGeometry(3.0, 1.0, 1.0, 0.6, tip_radius=0.15, tendons=(tendon,))
    finger = create_finger_mesh(geometry, MeshSizes(0.4, tendon=0.25))
    material = NeoHookean.from_young(E, 0.3)
    tension = 5e-3
    first = SolidFingerProblem(finger, material, tendons=[TendonLoad(tension=tension)])
    r1 = first.solve(LoadStepping(steps=2))
    pull_in = r1["tendon_reference_lengths"][0] - r1["tendon_lengths"][0]
    assert pull_in > 0 and r1["tip_displacement"][1] > 0
    second = SolidFingerProblem(finger, material, tendons=[TendonLoad(pull_in=pull_in)])
    r2 = second.solve(LoadStepping(steps=2))
    assert r2["tensions"][0] == pytest.approx(tension, rel=1e-7)
    assert np.allclose(r2["tip_displacement"], r1["tip_displacement"], rtol=1e-7, atol=1e-12)
    assert r2["steps"][0]["tensions"][0] == pytest.approx(tension / 2, rel=0.1)


@pytest.mark.mpi
def test_gamg_with_rigid_body_modes_matches_mumps(coarse_tip_load):
    P = 1e-5
    _, direct = coarse_tip_load
    problem, iterative = prism_tip_load(
        0.7, 0.7, 0.3, P, solver=SolverSettings(linear_solver="gamg"), prefix="solid_gamg_"
    )
    assert problem.snes_solver.snes.getKSP().getPC().getType() == "gamg"
    assert np.allclose(iterative["tip_displacement"], direct["tip_displacement"], rtol=1e-6)


def test_xdmf_writer(tendon_bar):
    comm = MPI.COMM_WORLD
    import tempfile

    folder = comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0)
    path = Path(folder) / "finger.xdmf"
    write_xdmf(tendon_bar["problem"], path)
    comm.barrier()
    assert path.is_file() and path.with_suffix(".h5").is_file()
    assert "displacement" in path.read_text()


@pytest.mark.parametrize(
    "make, field",
    [
        (lambda: TendonLoad(tension=-1.0), "tension"),
        (lambda: TendonLoad(tension=1.0, pull_in=0.1), "not both"),
        (lambda: Discretization("hybrid"), "formulation"),
        (lambda: Discretization("mixed", degree=1), "degree"),
        (lambda: FingerGeometry(1.0, 1.0, 0.0), "height_base"),
        (lambda: FingerGeometry(1.0, 1.0, 1.0, tip_radius=0.6), "tip_radius"),
        (lambda: FingerGeometry(1.0, 1.0, 1.0, tendons=(TendonPath.from_offsets(1.0, 0.5, 0.2),)),
         "strictly inside"),
        (lambda: TendonPath(((0, 0, 0), (0, 0, 0))), "distinct"),
        (lambda: MeshSizes(0.1, tendon=0.2), "mesh.tendon"),
        (lambda: MeshSizes(0.1, order=3), "mesh.order"),
    ],
)
def test_validation_names_the_field(make, field):
    with pytest.raises(ValueError, match=field):
        make()

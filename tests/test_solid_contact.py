"""Contact of the 3D solid with rigid obstacles (`fe_beam.fem.solid.contact`): a short block
pushed by a tip force onto a frictionless wall against the linear-elastic bar, the summary's
contact entries, the rejected step, the refusal of an obstacle inside the body, 2 ranks =
serial."""

import json

import numpy as np
import pytest
from mpi4py import MPI

from fe_beam.errors import ConfigError
from fe_beam.model.obstacles import ContactSettings, Plane, Sphere
from fe_beam.model.solid import Discretization
from fe_beam.solid import (
    FingerGeometry,
    MeshSizes,
    NeoHookean,
    SolidFingerProblem,
    create_finger_mesh,
)
from fe_beam.solvers.continuation import ContinuationFailed
from fe_beam.solvers.newton import LoadStepping, SolverSettings

# a short block, clamped at x = 0, its tip face a gap G from a rigid wall at x = L + G
L, B, H, E = 2.0, 1.0, 1.0, 1.0
G = 1e-3
P_TOUCH = E * B * H * G / L  # the tip force that closes the gap (linear bar)
TOLERANCE = 1e-3 * G


def wall(gap=G, length=L):
    return Plane(name="wall", dim=3, point=(length + gap, 0.0, 0.0), normal=(-1.0, 0.0, 0.0))


def block(obstacles, force=2 * P_TOUCH, nu=0.0, size=0.5, comm=MPI.COMM_WORLD,
          formulation="displacement", solver="mumps", settings=None, length=L):
    finger = create_finger_mesh(FingerGeometry(length, B, H), MeshSizes(size), comm)
    return SolidFingerProblem(
        finger, NeoHookean.from_young(E, nu), tip_force=(force, 0.0, 0.0),
        obstacles=obstacles,
        contact=settings or ContactSettings(penetration_tolerance=TOLERANCE),
        discretization=Discretization(formulation, 2) if formulation != "displacement" else None,
        solver=SolverSettings(linear_solver=solver))


def test_block_on_a_frictionless_wall_carries_the_rest_of_the_load():
    """nu = 0 (no lateral strain, the clamp constrains nothing): the bar's tip closes the gap
    at P_touch = E A G / L; beyond it the wall carries R = P - E A G / L, uniformly over the
    tip face (the linear solution is exact in P2; the strain 5e-4 keeps it linear)."""
    problem = block([wall()])
    result = problem.solve(LoadStepping(steps=4))
    first, last = result["steps"][1]["contact"][0], result["contact"][0]
    expected = 2 * P_TOUCH - E * B * H * G / L
    print(f"block on wall: R = {-last['force'][0]:.8g} vs {expected:.8g}, penetration "
          f"{last['max_penetration']:.3g} (tolerance {TOLERANCE:.3g}), area "
          f"{last['active_area']:.6g}, Uzawa updates {problem.solver.updates}")
    assert -last["force"][0] == pytest.approx(expected, rel=2e-3)
    assert np.abs(last["force"][1:]).max() < 1e-9 * expected
    assert abs(first["force"][0]) < 0.02 * expected  # at P = P_touch it just touches
    assert last["active_area"] == pytest.approx(B * H, rel=1e-9)
    assert last["pressure_peak"] == pytest.approx(expected / (B * H), rel=0.01)
    assert 0 < last["max_penetration"] <= TOLERANCE
    for step in result["steps"]:
        assert step["contact"][0]["max_penetration"] <= TOLERANCE
    u_tip = result["tip_displacement"][0]
    assert u_tip == pytest.approx(G, abs=TOLERANCE)


def test_block_with_poisson_mixed_fieldsplit():
    """nu = 0.3, Taylor-Hood u-p with the fieldsplit solver: the wall's force is the bar's to
    3 % (the clamped face stiffens the short bar, ~1.7 % measured at L / H = 2), and the same
    as the displacement formulation with MUMPS on the same mesh to 1 %."""
    mixed = block([wall()], nu=0.3, formulation="mixed", solver="fieldsplit")
    R_mixed = -mixed.solve(LoadStepping(steps=2))["contact"][0]["force"][0]
    plain = block([wall()], nu=0.3)
    result = plain.solve(LoadStepping(steps=2))
    R_plain = -result["contact"][0]["force"][0]
    expected = P_TOUCH
    print(f"nu = 0.3: R mixed/fieldsplit {R_mixed:.6g}, displacement/mumps {R_plain:.6g}, "
          f"bar {expected:.6g}")
    assert mixed.linear_solver == "fieldsplit"
    assert R_mixed == pytest.approx(expected, rel=0.03)
    assert R_mixed < expected  # stiffer than the bar: less left for the wall
    assert R_plain == pytest.approx(R_mixed, rel=0.01)
    assert result["contact"][0]["max_penetration"] <= TOLERANCE


def test_an_obstacle_clear_of_the_solid_carries_nothing():
    """A ball and the wall: the entries come in the order of the obstacles, the ball (clear
    of the deformed block) with zero force and area."""
    ball = Sphere(name="ball", dim=3, center=(1.0, 2.0, 0.0), radius=0.5)
    result = block([ball, wall()]).solve(LoadStepping(steps=2))
    clear, pressed = result["contact"]
    assert [clear["name"], pressed["name"]] == ["ball", "wall"]
    assert clear["force"] == [0.0, 0.0, 0.0] and clear["active_area"] == 0.0
    assert clear["max_penetration"] == 0.0 and clear["pressure_peak"] == 0.0
    assert -pressed["force"][0] == pytest.approx(P_TOUCH, rel=2e-3)


def test_a_step_above_the_tolerance_is_rejected():
    """One Uzawa update with a tolerance below the plain penalty's penetration: no step may be
    accepted with the penetration above it, the load stepping fails."""
    settings = ContactSettings(penetration_tolerance=1e-9, max_updates=1, penalty=1.0)
    problem = block([wall()], settings=settings)
    with pytest.raises(ContinuationFailed):
        problem.solve(LoadStepping(steps=1, min_increment=0.25))


def test_an_obstacle_inside_the_undeformed_solid_is_refused():
    with pytest.raises(ConfigError, match="intersects the undeformed solid"):
        block([wall(gap=-0.1)])


@pytest.mark.mpi
def test_serial_and_parallel_contact_agree():
    """A shorter block (L = B / 2, so that the partition cuts its tip face and the patch spans
    the ranks) with nu = 0.3 on COMM_SELF and on COMM_WORLD (meaningful under mpirun -n 2)."""
    if MPI.COMM_WORLD.size == 1:
        pytest.skip("run under mpirun -n 2 to compare a serial and a parallel solve")
    short = {"nu": 0.3, "length": 0.5, "force": 2 * E * B * H * G / 0.5, "size": 0.35}
    problem = block([wall(length=0.5)], **short)
    parallel = problem.solve(LoadStepping(steps=2))["contact"][0]
    from dolfinx import fem

    local = MPI.COMM_WORLD.allgather(fem.assemble_scalar(problem.contact._area[0]))
    assert np.count_nonzero(local) > 1, f"the contact patch should span the ranks: {local}"
    serial = block([wall(length=0.5)], comm=MPI.COMM_SELF, **short).solve(
        LoadStepping(steps=2))["contact"][0]
    print(f"serial {serial}\nparallel {parallel}")
    for key in ("force", "active_area", "max_penetration", "pressure_peak"):
        assert np.allclose(serial[key], parallel[key], rtol=1e-6,
                           atol=1e-9 * abs(serial["force"][0])), key


# --- fe-beam solid with [[obstacles]] ---------------------------------------------------------
BLOCK = {
    "beam": {"length": L},
    "section": {"shape": "rectangle", "b": B, "h": H},
    "material": {"E": E, "nu": 0.0, "rho": 1.0},
    "loads": {"steps": 2, "tip_force": [2 * P_TOUCH, 0.0]},
    "solid": {"material": "neo-hookean", "mesh_size": 0.5, "order": 2},
    "output": {"xdmf": False, "plots": False},
    "obstacles": [{"shape": "plane", "name": "wall", "point": [L + G, 0.0, 0.0],
                   "normal": [-1.0, 0.0, 0.0]}],
    "contact": {"penetration_tolerance": TOLERANCE},
}


def cli(tmp_path, config):
    from tests.solid.test_solid_driver import run_cli, shared_folder

    folder = shared_folder(tmp_path)
    return run_cli("solid", folder, config)


def test_fe_beam_solid_writes_the_contact_entries_per_step(tmp_path):
    code, _, stderr, out = cli(tmp_path, BLOCK)
    assert code == 0, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "converged"
    assert "obstacles" in summary["rod"]["message"]  # the planar rod reads 2D obstacles
    entries = [step["contact"] for step in summary["steps"]]
    assert len(entries) == 2 and all(len(e) == 1 for e in entries)
    last = entries[-1][0]
    assert set(last) == {"name", "force", "active_area", "max_penetration", "pressure_peak",
                         "extent", "contact_length"}
    assert -last["force"][0] == pytest.approx(P_TOUCH, rel=2e-3)
    assert last["max_penetration"] <= TOLERANCE
    # issue 28: the clamp's reaction, the tip force and the wall's force balance (the wall's
    # force integrated from its traction, apart from the residual)
    (check,) = summary["checks"]
    balance = summary["steps"][-1]["equilibrium"]
    print(f"block on a wall: equilibrium {check['value']:.3g}, reaction "
          f"{balance['reaction_force']}, wall {last['force']}")
    assert check["name"] == "solid_global_equilibrium" and check["passed"]
    assert balance["value"] < 1e-6


@pytest.mark.parametrize("changes, fragment", [
    ({"point": [L - 0.1, 0.0, 0.0]}, "intersects the undeformed solid"),
    ({"friction": 0.3}, "friction"),
    ({"point": [L + G, 0.0]}, "point must be a list of 3 numbers"),
])
def test_fe_beam_solid_refuses_bad_obstacles_with_exit_2(tmp_path, changes, fragment):
    config = json.loads(json.dumps(BLOCK))
    config["obstacles"][0] |= changes
    code, _, stderr, _ = cli(tmp_path, config)
    assert code == 2, stderr
    assert fragment in stderr and "Traceback" not in stderr


def test_a_small_ball_inside_the_solid_with_no_node_in_it_is_refused(tmp_path):
    """A ball smaller than the elements, inside the block away from every node (the node
    check alone let it through, then it pushed on nothing): exit 2, its centre in the body."""
    config = json.loads(json.dumps(BLOCK))
    size = BLOCK["solid"]["mesh_size"]
    config["obstacles"] = [{"shape": "sphere", "name": "ball", "radius": 0.05 * size,
                            "center": [0.5 * L + 0.13 * size, 0.11 * size, 0.07 * size]}]
    code, _, stderr, _ = cli(tmp_path, config)
    assert code == 2, stderr
    assert "lies inside the undeformed solid" in stderr and "Traceback" not in stderr


# --- the solid finger against the rod, both pressing on the same plane -------------------------
def test_solid_finger_and_rod_press_on_the_same_roof_alike():
    """The tendon finger of tests/solid/test_solid_driver.py bends up into a roof y = 11 mm
    (free, its tip rises 14.8 mm in 3D, 15.7 mm as a rod): the roof's force on the 3D finger
    and on the rod (`fe-beam finger`, the same plane in 2D) differ by less than the free
    finger's 1D-vs-3D tip deflection (0.7 % vs 6 %, measured), penetrations within the
    tolerance."""
    import fe_beam
    from fe_beam.analyses.solid_driver import run_solid
    from tests.solid.test_solid_driver import FINGER

    base = json.loads(json.dumps(FINGER)) | {"output": {"xdmf": False, "plots": False}}
    free = run_solid(base, None, progress=False)
    v_solid, v_rod = free["tip"]["v"], free["rod"]["steps"][-1]["tip"]["v"]
    free_difference = abs(v_rod - v_solid) / abs(v_solid)
    roof, tolerance = 0.011, 2e-5
    solid = run_solid(base | {
        "obstacles": [{"shape": "plane", "name": "roof", "point": [0.0, roof, 0.0],
                       "normal": [0.0, -1.0, 0.0]}],
        "contact": {"penetration_tolerance": tolerance}}, None, progress=False)
    rod_config = {k: v for k, v in base.items() if k != "solid"} | {
        "obstacles": [{"shape": "plane", "name": "roof", "point": [0.0, roof],
                       "normal": [0.0, -1.0]}],
        "contact": {"penetration_tolerance": tolerance}}
    rod = fe_beam.run("finger", rod_config)
    assert solid["status"] == "converged" and rod["status"] == "converged"
    F_solid = solid["steps"][-1]["contact"][0]
    F_rod = rod["steps"][-1]["contact"][0]
    difference = abs(F_solid["force"][1] - F_rod["force"][1]) / abs(F_rod["force"][1])
    print(f"roof force: solid {F_solid['force']}, rod {F_rod['force']}: {difference:.2%} "
          f"(free tip deflection 1D vs 3D: {free_difference:.2%})")
    assert F_solid["force"][1] < 0 and F_rod["force"][1] < 0  # the roof pushes down
    assert difference < free_difference
    assert abs(F_solid["force"][0]) < 1e-6 * abs(F_solid["force"][1])  # frictionless roof
    assert 0 < F_solid["max_penetration"] <= tolerance
    assert F_rod["max_penetration"] <= tolerance


def test_the_rod_companion_with_obstacles():
    """The planar rod does not read 3D obstacles, and the spatial rod's contact tube (the
    section's circumradius) may cut an obstacle clear of the solid: the solid then runs alone,
    saying why; a spatial rod clear of the obstacle runs beside it against the same one."""
    from fe_beam.config.solid import parse_solid

    planar = parse_solid(json.loads(json.dumps(BLOCK)))
    assert planar.rod is None and "3D coordinates" in planar.rod_note
    assert planar.obstacles[0].dim == 3 and planar.contact.penetration_tolerance == TOLERANCE
    spatial = json.loads(json.dumps(BLOCK)) | {"model": {"kinematics": "spatial"}}
    cut = parse_solid(spatial)
    assert cut.rod is None and "circumradius" in cut.rod_note
    spatial["obstacles"][0]["point"] = [L + 1.0, 0.0, 0.0]
    beside = parse_solid(spatial)
    assert beside.rod is not None and beside.rod.obstacles == beside.obstacles

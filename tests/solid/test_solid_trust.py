"""Issue 28 (trust, round four), the 3D solid: point location near shared facets (a tolerance
relative to the cell, not dolfinx's absolute 1e-10 m), a failed summary with the converged steps
on any exception, and the global-equilibrium certificate ``solid_global_equilibrium``."""

import json

import numpy as np
import pytest
from dolfinx import fem, mesh
from mpi4py import MPI
from test_solid_driver import edited, run_cli, shared_folder

from fe_beam.analyses import solid as solid_analysis
from fe_beam.analyses.solid_driver import run_solid
from fe_beam.fem import compat
from fe_beam.solvers import solid as solid_solver
from fe_beam.solvers.solid import evaluate_at_points


# --- point location -----------------------------------------------------------------------------
def near_facet_points(msh, count: int, inset: float, seed: int = 3) -> np.ndarray:
    """Interior points of random cells of ``msh`` at barycentric distance ``inset`` from one of
    the cell's facets (shared with a neighbour)."""
    x = msh.geometry.x
    nodes = compat.geometry_cell_nodes(msh)
    owned = msh.topology.index_map(3).size_local
    rng = np.random.default_rng(seed)
    points = []
    for cell in rng.integers(0, owned, count):
        weights = rng.random(4)
        k = rng.integers(4)
        weights[k] = 0.0
        weights *= (1.0 - inset) / weights.sum()
        weights[k] = inset
        points.append(weights @ x[nodes[cell]])
    return np.array(points)


@pytest.fixture(scope="module")
def slab():
    """A thin tetrahedral slab of sub-millimetre cells (not the issue's bar)."""
    return mesh.create_box(MPI.COMM_SELF, [[0.0, -0.003, -0.002], [0.02, 0.003, 0.002]],
                           [24, 6, 5], mesh.CellType.tetrahedron)


@pytest.mark.parametrize("inset", [3e-7, 1e-6, 3e-6])
def test_points_near_a_shared_facet_are_located(slab, inset):
    """dolfinx 0.5.2 rejects an interior point ~1e-9 m from a facet of millimetre cells (GJK's
    distance ~6e-10 m against an absolute 1e-10 m): with the relative tolerance every point
    is found, in a cell whose barycentric coordinates hold it (dolfinx 0.11's own collision
    test pads the cells: it may return the neighbour the point is 1e-6 of a cell outside, where
    evaluating the cell's polynomials is as exact)."""
    points = near_facet_points(slab, 200, inset)
    tree = compat.bounding_box_tree(slab, 3)
    cells = compat.first_colliding_cells(slab, tree, points)
    assert np.all(cells >= 0)
    x, nodes = slab.geometry.x, compat.geometry_cell_nodes(slab)
    for point, cell in zip(points, cells, strict=True):
        vertices = x[nodes[cell]]
        local = np.linalg.solve((vertices[1:] - vertices[0]).T, point - vertices[0])
        assert min(local.min(), 1 - local.sum()) >= (-1e-8 if compat.LEGACY else -1e-5)


def test_lost_points_without_the_tolerance(slab):
    """The mechanism (dolfinx 0.5.2): without the relative tolerance points are lost."""
    if not compat.LEGACY:
        pytest.skip("the absolute GJK tolerance is dolfinx 0.5's")
    points = near_facet_points(slab, 200, 1e-6)
    tree = compat.bounding_box_tree(slab, 3)
    assert np.any(compat.first_colliding_cells(slab, tree, points, rtol=0.0) < 0)


def test_values_near_facets_match_the_exact_field_and_outside_points_are_refused(slab):
    """A quadratic field (exact in P2) evaluated at the near-facet points equals its closed
    form; a point a tenth of a millimetre outside is still refused."""
    V = compat.function_space(slab, compat.vector_element(slab, "Lagrange", 2))
    u = fem.Function(V)

    def field(x):
        return np.vstack([x[0] * x[1], 3.0 * x[2] ** 2 - x[0], 2.0 + x[1] - x[2]])

    u.interpolate(field)
    points = near_facet_points(slab, 100, 1e-6, seed=7)
    values = evaluate_at_points(u, points)
    assert np.allclose(values, field(points.T).T, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="outside the mesh"):
        evaluate_at_points(u, np.array([[0.01, 0.0031, 0.0]]))


# --- the solid run: exceptions and the equilibrium certificate -----------------------------------
#: a stubby steel-like square bar (not the issue's), a tendon along +z and an oblique tip force
BAR = {
    "beam": {"length": 0.06},
    "section": {"shape": "rectangle", "b": 0.015, "h": 0.015},
    "material": {"E": 2.0e6, "nu": 0.3},
    "mesh": {"elements": 6},
    "loads": {"steps": 3, "tip_force": [0.4, -0.3, 0.5]},
    "solid": {"material": "mooney-rivlin", "mesh_size": 0.0075, "order": 2, "solver": "mumps"},
    "tendons": [{"name": "side", "offset_base": 0.004, "offset_tip": 0.004, "tension": 1.5}],
    "output": {"plots": False, "xdmf": False},
}


@pytest.fixture(scope="module")
def bar_run():
    return run_solid(BAR, None, MPI.COMM_WORLD, progress=False)


def test_equilibrium_certificate_passes_and_reaction_balances_the_tip_force(bar_run):
    summary = bar_run
    assert summary["status"] == "converged"
    (check,) = [c for c in summary["checks"] if c["name"] == "solid_global_equilibrium"]
    assert check["passed"] and check["value"] < 1e-8 and check["tolerance"] == 1e-6
    for step in summary["steps"]:
        balance = step["equilibrium"]
        # the tendon is internal: the clamp balances the tip force alone
        applied = step["load_factor"] * np.array(BAR["loads"]["tip_force"])
        assert np.allclose(balance["reaction_force"], -applied, rtol=0, atol=1e-9)
        assert balance["scale"] == pytest.approx(1.5 * step["load_factor"])  # the tension


def test_tendon_only_finger_needs_no_reaction():
    """Tendon alone (pull-in control): the reaction force and moment vanish."""
    config = edited(BAR, {"loads.tip_force": [0.0, 0.0, 0.0], "loads.steps": 2,
                          "tendons.tension": None})
    config["tendons"][0].pop("tension")
    config["tendons"][0]["pull_in"] = 0.002
    summary = run_solid(config, None, MPI.COMM_WORLD, progress=False)
    assert summary["status"] == "converged"
    last = summary["steps"][-1]
    assert last["tensions"][0] > 0.1
    assert np.linalg.norm(last["equilibrium"]["reaction_force"]) < 1e-9 * last["tensions"][0]
    assert np.linalg.norm(last["equilibrium"]["reaction_moment"]) < 1e-9 * last["tensions"][0]
    assert summary["checks"][-1]["passed"]


def test_a_wrong_tip_traction_fails_the_certificate_with_exit_3(tmp_path, monkeypatch):
    """A tip traction 1 % short of the configured force (a wrong tip area) is caught: exit 3,
    status failed, the message names the check; strict = false keeps "converged" with a
    note."""
    measures = solid_solver.SolidFingerProblem._measures

    def short(self):
        measures(self)
        self.tip_area *= 1.01

    monkeypatch.setattr(solid_solver.SolidFingerProblem, "_measures", short)
    config = edited(BAR, {"tendons": None, "loads.steps": 1})
    config.pop("tendons")
    code, _, stderr, out = run_cli("solid", shared_folder(tmp_path / "strict"), config)
    summary = json.loads((out / "summary.json").read_text())
    assert code == 3, stderr
    assert summary["status"] == "failed" and "solid_global_equilibrium" in summary["message"]
    check = summary["checks"][-1]
    assert not check["passed"] and check["value"] == pytest.approx(0.01 / 1.01, rel=1e-3)
    lenient = edited(config, {"checks.strict": False})
    code, _, _, out = run_cli("solid", shared_folder(tmp_path / "lenient"), lenient)
    summary = json.loads((out / "summary.json").read_text())
    assert code == 0 and summary["status"] == "converged" and not summary["checks_passed"]
    assert any("solid_global_equilibrium" in note for note in summary["notes"])


def test_an_exception_after_converged_steps_writes_them_and_a_failed_summary(tmp_path,
                                                                             monkeypatch):
    """Any exception in a step's post-processing (here the backbone's point evaluation on the
    second step) ends the run with exit 3, status "failed", the message, and the first step's
    record in summary.json and load_displacement.csv (was: exit 1, status "running")."""
    backbone = solid_solver.SolidFingerProblem.backbone
    calls = []

    def failing(self, *args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise ValueError("point [1, 2, 3] is outside the mesh")
        return backbone(self, *args, **kwargs)

    monkeypatch.setattr(solid_solver.SolidFingerProblem, "backbone", failing)
    config = edited(BAR, {"loads.steps": 3})
    code, _, stderr, out = run_cli("solid", shared_folder(tmp_path), config)
    assert code == 3, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed"
    assert "ValueError: point [1, 2, 3] is outside the mesh" in summary["message"]
    assert [s["load_factor"] for s in summary["steps"]] == pytest.approx([1 / 3])
    assert summary["tip"] == summary["steps"][0]["tip"]
    assert summary["checks"][-1]["name"] == "solid_global_equilibrium"
    rows = (out / "load_displacement.csv").read_text().strip().splitlines()
    assert len(rows) == 2
    assert solid_analysis.EQUILIBRIUM_TOLERANCE == 1e-6

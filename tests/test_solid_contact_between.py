"""The 3D solid's penetration between the vertices (`fe_beam.fem.solid.contact`): a sphere
pressed into the tip face of a coarse block touches it inside a facet, where no vertex (the
multipliers' nodes) sees it. The contact check measures the gap at the P3 nodes of the exterior
facets and the sphere's depth into the deformed facets (4 flat triangles per P2 facet); where
only the points between the vertices penetrate, the penalty grows; a step that still does not
meet the tolerance is rejected, never reported as converged."""

import numpy as np
import pytest
import ufl
from dolfinx import fem
from mpi4py import MPI

from fe_beam.fem import compat
from fe_beam.fem.solid.contact import triangle_distance
from fe_beam.model.obstacles import ContactSettings, Sphere
from fe_beam.solvers.continuation import ContinuationFailed
from fe_beam.solvers.newton import LoadStepping
from tests.test_solid_contact import P_TOUCH, L, block

GAP, RADIUS = 1e-3, 0.5
# off the face's centre: the sphere meets the coarse tip face (mesh size 0.5) inside a facet
BALL = Sphere(name="ball", dim=3, center=(L + RADIUS + GAP, 0.13, -0.21), radius=RADIUS)


def penetration_at_p4_nodes(problem) -> float:
    """max(-g) of the sphere's gap |x - C| - R at the P4 nodes of the exterior facets (points
    of the deformed P2 surface other than the ones the check uses)."""
    mesh = problem.mesh
    space = compat.function_space(mesh, compat.element(mesh, "Lagrange", 4))
    X = ufl.SpatialCoordinate(mesh)
    rel = X + problem.u - ufl.as_vector(BALL.center)
    gap = fem.Function(space)
    gap.interpolate(compat.interpolation_expression(ufl.sqrt(ufl.dot(rel, rel)) - RADIUS,
                                                    space))
    facets = compat.locate_entities_boundary(mesh, mesh.topology.dim - 1,
                                             lambda x: np.full(x.shape[1], True))
    dofs = fem.locate_dofs_topological(space, mesh.topology.dim - 1, facets)
    local = float(np.max(-compat.local_array(gap)[dofs], initial=0.0))
    return mesh.comm.allreduce(local, op=MPI.MAX)


def test_triangle_distance():
    triangle = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    points = [([0.2, 0.2, 0.5], 0.5), ([2.0, 0.0, 0.0], 1.0), ([-1.0, -1.0, 0.0], 2**0.5),
              ([1.0, 1.0, 1.0], (0.5 + 1.0) ** 0.5)]
    for point, expected in points:
        assert triangle_distance(np.array(point), triangle)[0] == pytest.approx(expected)


@pytest.mark.mpi
def test_a_sphere_between_the_vertices_is_held_within_the_tolerance():
    """Tolerance 3e-3: converged with the sphere's depth into the face, measured at other
    points of the deformed surface, within it, though no vertex touches the sphere (the
    vertex-only check of before saw no penetration at all)."""
    tolerance = 3e-3
    problem = block([BALL], force=10 * P_TOUCH,
                    settings=ContactSettings(penetration_tolerance=tolerance))
    result = problem.solve(LoadStepping(steps=2))
    entry = result["contact"][0]
    state = problem.contact.evaluate()
    independent = penetration_at_p4_nodes(problem)
    print(f"sphere on a coarse block: penetration {entry['max_penetration']:.4g} (vertices "
          f"{state['vertex_penetration'][0]:.3g}, P4 nodes {independent:.4g}), penalty "
          f"growth {problem.contact.growth:g}, force {entry['force']}")
    assert state["vertex_penetration"][0] == 0.0  # no vertex touches the sphere
    assert entry["force"][0] < -0.1 * P_TOUCH  # and yet the sphere pushes back
    assert 0.1 * tolerance < entry["max_penetration"] <= tolerance
    assert independent <= tolerance
    for step in result["steps"]:
        assert step["contact"][0]["max_penetration"] <= tolerance


def test_a_sphere_the_mesh_cannot_hold_is_rejected():
    """Tolerance 1e-4: the coarse facets cannot follow the sphere that closely (the depth
    between the quadrature points stays ~6e-4 whatever the penalty): the load stepping stops
    (exit 3 from fe-beam solid), no step above the tolerance is accepted."""
    problem = block([BALL], force=10 * P_TOUCH,
                    settings=ContactSettings(penetration_tolerance=1e-4, max_updates=12))
    with pytest.raises(ContinuationFailed, match="penetration"):
        problem.solve(LoadStepping(steps=2, min_increment=0.1))

"""Tendon cable: embedding in the mesh, residual and Jacobian vs finite differences of the
energy, each segment counted once in parallel."""

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.solid import (
    FingerGeometry,
    MeshSizes,
    TendonCable,
    TendonPath,
    create_finger_mesh,
)

L = 3.0


@pytest.fixture(scope="module")
def finger():
    tendons = (
        TendonPath.from_offsets(L, 0.3, 0.15, name="straight"),
        TendonPath(((0.0, -0.3, 0.2), (1.2, -0.2, -0.1), (2.8, 0.1, 0.0)), name="kinked"),
    )
    geometry = FingerGeometry(L, 1.0, 1.0, 0.7, tendons=tendons)
    return create_finger_mesh(geometry, MeshSizes(0.5, tendon=0.3, order=1), MPI.COMM_WORLD)


def spaces(msh):
    p1 = compat.function_space(msh, compat.vector_element(msh, "Lagrange", 1))
    p2 = compat.function_space(msh, compat.vector_element(msh, "Lagrange", 2))
    th = compat.function_space(msh, compat.mixed_element(
        [compat.vector_element(msh, "Lagrange", 2), compat.element(msh, "Lagrange", 1)]))
    return {"P1": (p1, p1), "P2": (p2, p2), "Taylor-Hood": (th, th.sub(0))}


def new_vector(space):
    imap, bs = space.dofmap.index_map, space.dofmap.index_map_bs
    v = PETSc.Vec().createMPI((imap.size_local * bs, imap.size_global * bs), comm=space.mesh.comm)
    v.set(0.0)
    return v


def new_matrix(space):
    imap, bs = space.dofmap.index_map, space.dofmap.index_map_bs
    n, N = imap.size_local * bs, imap.size_global * bs
    A = PETSc.Mat().createAIJ([[n, N], [n, N]], comm=space.mesh.comm)
    A.setPreallocationNNZ(60)
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    A.setUp()
    return A


@pytest.mark.mpi
def test_chains_lie_on_mesh_edges(finger):
    """Consecutive chain vertices are mesh vertices joined by an edge of the dolfinx mesh."""
    msh = finger.mesh
    msh.topology.create_connectivity(1, 0)
    e2v = msh.topology.connectivity(1, 0)
    x = msh.geometry.x
    vertex_x = np.empty((msh.topology.index_map(0).size_local
                         + msh.topology.index_map(0).num_ghosts, 3))
    c2v = msh.topology.connectivity(3, 0)
    nodes = compat.geometry_cell_nodes(msh)
    for c in range(msh.topology.index_map(3).size_local):
        vertex_x[c2v.links(c)] = x[nodes[c, :4]]
    edges = e2v.array.reshape(-1, 2)
    mids = 0.5 * (vertex_x[edges[:, 0]] + vertex_x[edges[:, 1]])
    from scipy.spatial import cKDTree

    tree = cKDTree(mids)
    for tendon, chain in zip(finger.geometry.tendons, finger.tendon_chains, strict=True):
        assert np.allclose(chain[0], tendon.array[0]) and np.allclose(chain[-1], tendon.array[-1])
        seg_mid = 0.5 * (chain[1:] + chain[:-1])
        dist, _ = tree.query(seg_mid)
        local = (dist < 1e-10).astype(np.int64)
        found = np.zeros_like(local)
        msh.comm.Allreduce(local, found, op=MPI.MAX)
        assert np.all(found == 1), f"{tendon.name}: segments not on mesh edges"
        length = np.linalg.norm(np.diff(chain, axis=0), axis=1).sum()
        assert length == pytest.approx(tendon.length, rel=1e-12)
        assert len(chain) - 1 >= tendon.length / 0.35  # the tendon size field (0.3) acts


def tip_face_plate(finger, anchor):
    """All tip-face vertices (gathered from every rank) with anchor-plate weights."""
    from fe_beam.solvers.solid import plate_weights

    x = finger.mesh.geometry.x
    local = x[np.abs(x[:, 0] - L) < 1e-12]
    vertices = np.unique(np.concatenate(finger.comm.allgather(local)).round(12), axis=0)
    return vertices, plate_weights(vertices, np.ones(len(vertices)), anchor)


@pytest.mark.mpi
@pytest.mark.parametrize("anchor", ["point", "plate"])
@pytest.mark.parametrize("kind", ["P1", "P2", "Taylor-Hood"])
def test_residual_and_jacobian_match_finite_differences(finger, kind, anchor):
    root, space = spaces(finger.mesh)[kind]
    if anchor == "plate":  # the straight tendon ends on the tip face
        chain = finger.tendon_chains[0]
        patch = tip_face_plate(finger, chain[-1])
        assert len(patch[1]) > 4 and patch[1] @ patch[0] == pytest.approx(chain[-1])
        cable = TendonCable(space, chain, tension=2.5, anchor_patch=patch)
    else:
        cable = TendonCable(space, finger.tendon_chains[1], tension=2.5)
    rng = np.random.default_rng(1 + finger.comm.rank)
    x = new_vector(root)
    x.setArray(rng.uniform(-0.05, 0.05, x.getLocalSize()))
    b = new_vector(root)
    cable.add_to_residual(x, b)
    b.assemble()
    A = new_matrix(root)
    cable.add_to_jacobian(x, A)
    A.assemble()
    h = 1e-6
    for _ in range(3):
        d = new_vector(root)
        d.setArray(rng.uniform(-1, 1, d.getLocalSize()))
        xp, xm = x.copy(), x.copy()
        xp.axpy(h, d)
        xm.axpy(-h, d)
        # gradient: b . d = dPi/dh
        fd = (cable.energy(xp) - cable.energy(xm)) / (2 * h)
        assert b.dot(d) == pytest.approx(fd, rel=1e-7)
        # Hessian: A d = d(b)/dh
        bp, bm = new_vector(root), new_vector(root)
        cable.add_to_residual(xp, bp)
        cable.add_to_residual(xm, bm)
        bp.assemble()
        bm.assemble()
        fd_vec = (bp - bm) / (2 * h)
        Ad = new_vector(root)
        A.mult(d, Ad)
        assert (Ad - fd_vec).norm() <= 1e-6 * fd_vec.norm()
        assert fd_vec.norm() > 0


@pytest.mark.mpi
def test_each_segment_counted_once(finger):
    """Straight tendon, no displacement: dPi/dx_k = tau (t_{k-1} - t_k) vanishes at interior
    vertices and is -tau t / +tau t at entry / anchor, whatever the partition."""
    root, space = spaces(finger.mesh)["P2"]
    tau = 3.0
    cable = TendonCable(space, finger.tendon_chains[0], tension=tau)
    x, b = new_vector(root), new_vector(root)
    cable.add_to_residual(x, b)
    b.assemble()
    start, end = b.getOwnershipRange()
    values = np.zeros(cable.dofs.shape)
    owned = (cable.dofs >= start) & (cable.dofs < end)
    values[owned] = b.getArray(readonly=True)[cable.dofs[owned] - start]
    total = np.zeros_like(values)
    finger.comm.Allreduce(values, total, op=MPI.SUM)
    chain = finger.tendon_chains[0]
    t = (chain[-1] - chain[0]) / np.linalg.norm(chain[-1] - chain[0])
    assert np.allclose(total[0], -tau * t, atol=1e-12)
    assert np.allclose(total[-1], tau * t, atol=1e-12)
    assert np.allclose(total[1:-1], 0.0, atol=1e-12)
    assert cable.energy(x) == pytest.approx(tau * finger.geometry.tendons[0].length, rel=1e-12)
    assert b.sum() == pytest.approx(0.0, abs=1e-12)


def test_cable_rejects_points_off_the_mesh_vertices(finger):
    _, space = spaces(finger.mesh)["P1"]
    with pytest.raises(ValueError, match="tendon point"):
        TendonCable(space, np.array([[0.1234, 0.0101, 0.0], [0.2, 0.0, 0.0]]))

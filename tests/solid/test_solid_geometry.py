"""gmsh finger: shape, physical groups, rounded tip, tendon chains."""

import numpy as np
import pytest
import ufl
from dolfinx import fem
from mpi4py import MPI

from fe_beam.fem.mpi import assemble_scalar
from fe_beam.solid import (
    CLAMP_TAG,
    TIP_TAG,
    FingerGeometry,
    MeshSizes,
    TendonPath,
    create_finger_mesh,
    write_msh,
)

L, B, H0, H1 = 2.0, 0.8, 0.6, 0.4


def measure(finger, integrand=1.0):
    msh = finger.mesh
    ds = ufl.Measure("ds", domain=msh, subdomain_data=finger.facet_tags)
    one = fem.Constant(msh, 1.0)
    return (
        assemble_scalar(fem.form(one * ufl.dx(domain=msh))),
        assemble_scalar(fem.form(one * ds(CLAMP_TAG))),
        assemble_scalar(fem.form(one * ds(TIP_TAG))),
    )


@pytest.mark.parametrize("order", [1, 2])
def test_tapered_prism_volume_faces_and_frame(order):
    tendon = TendonPath.from_offsets(L, 0.2, 0.1, x_entry=0.5, x_anchor=1.5, z=0.1)
    geometry = FingerGeometry(L, B, H0, H1, tendons=(tendon,))
    finger = create_finger_mesh(geometry, MeshSizes(0.3, tendon=0.15, clamp=0.15, order=order))
    volume, clamp, tip = measure(finger)
    assert volume == pytest.approx(B * L * (H0 + H1) / 2, rel=1e-10)
    assert clamp == pytest.approx(B * H0, rel=1e-10)
    assert tip == pytest.approx(B * H1, rel=1e-10)
    x = finger.mesh.geometry.x
    lo, hi = np.empty(3), np.empty(3)
    finger.mesh.comm.Allreduce(x.min(axis=0), lo, op=MPI.MIN)
    finger.mesh.comm.Allreduce(x.max(axis=0), hi, op=MPI.MAX)
    assert np.allclose(lo, [0, -H0 / 2, -B / 2]) and np.allclose(hi, [L, H0 / 2, B / 2])
    chain = finger.tendon_chains[0]
    assert np.allclose(chain[0], [0.5, 0.175, 0.1]) and np.allclose(chain[-1], [1.5, 0.125, 0.1])
    # an interior tendon: all chain vertices on the straight path
    t = (chain - chain[0]) @ (chain[-1] - chain[0]) / np.sum((chain[-1] - chain[0]) ** 2)
    assert np.allclose(chain, chain[0] + t[:, None] * (chain[-1] - chain[0]), atol=1e-12)
    assert np.all(np.diff(t) > 0)


def test_rounded_tip():
    r = 0.1
    geometry = FingerGeometry(L, B, H0, H1, tip_radius=r)
    finger = create_finger_mesh(geometry, MeshSizes(0.2, order=2))
    volume, _, tip = measure(finger)
    assert tip == pytest.approx(geometry.tip_area, rel=1e-10)
    sharp = B * L * (H0 + H1) / 2
    # the four edge fillets remove (1 - pi/4) r^2 per unit length of edge, less at the corners
    per_length = (1 - np.pi / 4) * r**2
    perimeter = 2 * (B + H1)
    assert per_length * (perimeter - 8 * r) < sharp - volume < per_length * perimeter


def test_write_msh(tmp_path):
    if MPI.COMM_WORLD.rank == 0:
        path = tmp_path / "finger.msh"
        geometry = FingerGeometry(L, B, H0, H1, tendons=(TendonPath.from_offsets(L, 0.2, 0.1),))
        write_msh(geometry, MeshSizes(0.4), path, verbose=False)
        text = path.read_text()
        assert '"clamp"' in text and '"tip"' in text and '"tendon"' in text


def test_gmsh_failure_is_raised_on_every_rank():
    geometry = FingerGeometry(L, B, H0, H1)
    with pytest.raises(RuntimeError, match="gmsh could not mesh"):
        create_finger_mesh(geometry, MeshSizes(0.3), _BrokenComm(MPI.COMM_WORLD))


class _BrokenComm:
    """A communicator whose rank 0 claims a gmsh failure (to test error propagation)."""

    def __init__(self, comm):
        self._comm = comm

    def __getattr__(self, name):
        return getattr(self._comm, name)

    def bcast(self, value, root=0):
        if self._comm.rank == root and value is None:
            value = "simulated"
        return self._comm.bcast(value, root=root)

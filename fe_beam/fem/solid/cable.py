"""A tendon as a cable of straight segments between consecutive embedded mesh vertices.

With reference vertex positions X_k, displacements u_k and deformed positions x_k = X_k + u_k,

    l   = sum_k l_k,   l_k = |x_{k+1} - x_k|,   t_k = (x_{k+1} - x_k) / l_k
    Pi  = tau * l                                              (tension control)
    dPi/dx_k      = tau (t_{k-1} - t_k)                        (gradient: residual contribution)
    d2Pi/dx_a dx_b = +-K_k,  K_k = tau / l_k (I - t_k t_k^T)   (Hessian: geometric stiffness)

where segment k couples vertices a = k and b = k + 1 through the blocks [[K, -K], [-K, K]].

Parallel layout: every rank knows the global dof indices of all tendon vertices (3 per vertex);
the vertex displacements are gathered from their owners (allreduce) at each evaluation, and each
rank adds only the rows it owns. Every segment therefore enters exactly once, whatever the
partition. The Hessian couples only dofs of vertices that share a mesh edge, so it fits the
sparsity of the volume Jacobian.

Tendon vertices are mesh vertices, hence their dofs are vertex dofs of any Lagrange space (P1,
P2, or the displacement part of Taylor-Hood).
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.fem.mpi import global_sum

__all__ = ["TendonCable", "locate_vertex_dofs"]


def locate_vertex_dofs(space, points: np.ndarray, tol: float | None = None) -> np.ndarray:
    """Global indices (n, 3) of the displacement dofs at ``points`` (same array on every rank).

    ``space`` is a vector Lagrange space, or the displacement sub-space of a mixed space (e.g.
    ``W.sub(0)``); indices refer to the root space's global numbering (as in its PETSc vectors).
    Raises ValueError when a point is not a dof location of exactly one owner.
    """
    from scipy.spatial import cKDTree

    points = np.asarray(points, dtype=float).reshape(-1, 3)
    comm = space.mesh.comm
    if tol is None:
        extent = np.ptp(points, axis=0).max() if len(points) > 1 else 1.0
        tol = 1e-9 * max(extent, 1e-300)
    imap = space.dofmap.index_map
    bs = space.dofmap.index_map_bs
    n_owned = imap.size_local
    dofs = np.full((len(points), 3), -1, dtype=np.int64)
    for c in range(3):
        sub, parent = compat.sub_space_collapsed(space, c)
        parent = np.asarray(parent, dtype=np.int64)
        coords = sub.tabulate_dof_coordinates()[:, :3]
        owned = parent // bs < n_owned
        if not np.any(owned) or len(points) == 0:
            continue
        tree = cKDTree(coords[owned])
        dist, idx = tree.query(points)
        hit = dist < tol
        local = parent[owned][idx[hit]]
        blocks = imap.local_to_global((local // bs).astype(np.int32)).astype(np.int64)
        glob = blocks * bs + local % bs
        dofs[hit, c] = glob
    found = np.zeros_like(dofs)
    comm.Allreduce((dofs >= 0).astype(np.int64), found, op=MPI.SUM)
    if not np.all(found == 1):
        bad = np.flatnonzero(np.any(found != 1, axis=1))
        raise ValueError(
            f"cable: {len(bad)} tendon point(s) are not dof locations with a single owner, "
            f"first {points[bad[0]]} (found {found[bad[0]].tolist()} times)"
        )
    result = np.empty_like(dofs)
    comm.Allreduce(dofs, result, op=MPI.MAX)
    return result


class TendonCable:
    """Cable energy tau * l of one tendon, as a `fe_beam.solvers.newton` contribution.

    Parameters
    ----------
    space : displacement space (vector Lagrange, or ``W.sub(0)`` of a mixed space).
    points : (n, 3) reference coordinates of the tendon's mesh vertices, entry to anchor.
    tension : tau (N); set ``cable.tension`` between load steps.
    anchor_patch : optional ``(vertices (m, 3), weights (m,))``: the anchor is then not the
        last vertex but the weighted average x_a = sum_j w_j x_j of these mesh vertices (an
        anchor plate), with sum_j w_j = 1 and sum_j w_j X_j = the last point, so that the
        tendon's end force has the same resultant and moment but is spread over the patch
        instead of acting on one vertex (a singularity of the continuum).
    """

    def __init__(self, space, points: np.ndarray, tension: float = 0.0, name: str = "tendon",
                 anchor_patch: tuple[np.ndarray, np.ndarray] | None = None):
        self.points = np.asarray(points, dtype=float).reshape(-1, 3)
        if len(self.points) < 2:
            raise ValueError(f"cable {name!r}: needs at least 2 points, got {len(self.points)}")
        self.comm = space.mesh.comm
        self.name = name
        self.tension = float(tension)
        self.dofs = locate_vertex_dofs(space, self.points)
        self.patch_points = self.patch_dofs = self.patch_weights = None
        if anchor_patch is not None:
            vertices, weights = (np.asarray(a, dtype=float) for a in anchor_patch)
            self.patch_points = vertices.reshape(-1, 3)
            self.patch_weights = weights.reshape(-1)
            anchor = self.patch_weights @ self.patch_points
            scale = np.ptp(self.points, axis=0).max()
            if (len(self.patch_weights) != len(self.patch_points)
                    or abs(self.patch_weights.sum() - 1) > 1e-10
                    or np.abs(anchor - self.points[-1]).max() > 1e-9 * scale):
                raise ValueError(f"cable {name!r}: the anchor patch's weights must sum to 1 "
                                 "and average its vertices to the last point")
            self.patch_dofs = locate_vertex_dofs(space, self.patch_points)
        self._reference_length = self.length_of(self.points)

    # --- geometry ---------------------------------------------------------------------------

    @staticmethod
    def length_of(positions: np.ndarray) -> float:
        """l = sum_k |x_{k+1} - x_k|."""
        return float(np.linalg.norm(np.diff(positions, axis=0), axis=1).sum())

    @property
    def reference_length(self) -> float:
        return self._reference_length

    def _gather(self, x: PETSc.Vec, dofs: np.ndarray) -> np.ndarray:
        start, end = x.getOwnershipRange()
        owned = (dofs >= start) & (dofs < end)
        values = np.zeros(dofs.shape)
        values[owned] = x.getArray(readonly=True)[dofs[owned] - start]
        return global_sum(self.comm, values)

    def displacements(self, x: PETSc.Vec) -> np.ndarray:
        """(n, 3) vertex displacements gathered from the owners of the dofs in ``x``; with an
        anchor patch, the last one is the patch's weighted average."""
        values = self._gather(x, self.dofs)
        if self.patch_dofs is not None:
            values[-1] = self.patch_weights @ self._gather(x, self.patch_dofs)
        return values

    def positions(self, x: PETSc.Vec) -> np.ndarray:
        """Deformed positions x_k = X_k + u_k (the last one: the anchor)."""
        return self.points + self.displacements(x)

    def length(self, x: PETSc.Vec) -> float:
        return self.length_of(self.positions(x))

    def energy(self, x: PETSc.Vec) -> float:
        """Pi = tau * l."""
        return self.tension * self.length(x)

    # --- derivatives (numpy, positions known on every rank) ---------------------------------

    @staticmethod
    def _tangents(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        d = np.diff(positions, axis=0)
        lengths = np.linalg.norm(d, axis=1)
        if np.any(lengths <= 0):
            raise FloatingPointError("cable: a segment has collapsed to zero length")
        return d / lengths[:, None], lengths

    @classmethod
    def length_gradient(cls, positions: np.ndarray) -> np.ndarray:
        """dl/dx_k = t_{k-1} - t_k (n, 3)."""
        t, _ = cls._tangents(positions)
        g = np.zeros_like(positions)
        g[:-1] -= t
        g[1:] += t
        return g

    @classmethod
    def segment_stiffness(cls, positions: np.ndarray) -> np.ndarray:
        """(n-1, 3, 3) blocks K_k / tau = (I - t_k t_k^T) / l_k of the length Hessian."""
        t, lengths = cls._tangents(positions)
        eye = np.eye(3)[None, :, :]
        return (eye - t[:, :, None] * t[:, None, :]) / lengths[:, None, None]

    # --- solver contribution ----------------------------------------------------------------

    def add_to_residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """b += tau dl/du on the rows this rank owns."""
        if self.tension == 0.0:
            return
        g = self.tension * self.length_gradient(self.positions(x))
        start, end = b.getOwnershipRange()
        rows = self.dofs.ravel()
        if self.patch_dofs is not None:  # the anchor's force, spread by the weights
            rows = np.concatenate([self.dofs[:-1].ravel(), self.patch_dofs.ravel()])
            g = np.concatenate([g[:-1], np.outer(self.patch_weights, g[-1])])
        mine = (rows >= start) & (rows < end)
        if np.any(mine):
            b.setValues(
                rows[mine].astype(PETSc.IntType), g.ravel()[mine], addv=PETSc.InsertMode.ADD_VALUES
            )

    def jacobian_couplings(self) -> list[np.ndarray]:
        """Groups of global dofs coupled all-to-all by `add_to_jacobian` (at any state and
        tension): each segment's two vertices, the last one's first vertex with the anchor
        patch (for `fe_beam.solvers.newton.NonlinearProblem`'s preallocation)."""
        groups = []
        for k in range(len(self.dofs) - 1):
            if k == len(self.dofs) - 2 and self.patch_dofs is not None:
                groups.append(np.concatenate([self.dofs[k], self.patch_dofs.ravel()]))
            else:
                groups.append(np.concatenate([self.dofs[k], self.dofs[k + 1]]))
        return groups

    def add_to_jacobian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """A += tau d2l/du2 (segment blocks [[K, -K], [-K, K]]) on the rows this rank owns."""
        if self.tension == 0.0:
            return
        K = self.tension * self.segment_stiffness(self.positions(x))
        start, end = A.getOwnershipRange()
        for k in range(len(K)):
            if k == len(K) - 1 and self.patch_dofs is not None:
                # x_a = sum_j w_j x_j: the anchor's rows and columns spread by the weights
                w = self.patch_weights
                dofs = np.concatenate([self.dofs[k], self.patch_dofs.ravel()])
                block = np.block([[K[k], -np.kron(w[None, :], K[k])],
                                  [-np.kron(w[:, None], K[k]), np.kron(np.outer(w, w), K[k])]])
            else:
                dofs = np.concatenate([self.dofs[k], self.dofs[k + 1]])
                block = np.block([[K[k], -K[k]], [-K[k], K[k]]])
            mine = (dofs >= start) & (dofs < end)
            if not np.any(mine):
                continue
            A.setValues(
                dofs[mine].astype(PETSc.IntType),
                dofs.astype(PETSc.IntType),
                block[mine].ravel(),
                addv=PETSc.InsertMode.ADD_VALUES,
            )

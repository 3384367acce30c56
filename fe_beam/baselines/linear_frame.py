"""Small-displacement planar frames by the direct stiffness method, with rigid and pinned joints.

A plain numpy reference solver, independent of FEniCSx, for structures of straight members
(`fe_beam.model.structure`) under point loads at nodes: each member is one exact two-node
Timoshenko element (bending EI, shear GA, axial EA; the element's stiffness is exact for a
prismatic member loaded at its ends, so the nodal displacements are those of the continuum
linear theory). Nodes have two displacement dofs (u, v, world axes); each member end has a
rotation dof, shared with the other member ends at a node where they are joined rigidly, its
own at a pin. GA = inf is Euler-Bernoulli, EA = inf an inextensible member (by a stiffness
1e8 times the bending one over the length squared: relative error ~1e-8).

    frame = LinearFrame(points, members, EI, EA, GA)       # members: (node i, node j)
    frame.pin(node, member)      # that member's end at ``node`` turns freely (a pin)
    frame.fix(node, "u", "v"[, "theta" of a member])
    frame.load(node, Fx, Fy[, M on a member end's rotation])
    d = frame.solve()            # {"u": array per node, "v": ..., "theta": {(node, member): ...}}
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["LinearFrame"]


def member_stiffness(length: float, EI: float, EA: float, GA: float) -> np.ndarray:
    """The 6 x 6 local stiffness (u1, v1, t1, u2, v2, t2) of a prismatic Timoshenko member."""
    phi = 0.0 if not math.isfinite(GA) else 12 * EI / (GA * length**2)
    L = length
    c = EI / (L**3 * (1 + phi))
    axial = EA / L if math.isfinite(EA) else 1e8 * EI / L**3
    k = np.zeros((6, 6))
    k[np.ix_([0, 3], [0, 3])] = axial * np.array([[1, -1], [-1, 1]])
    bending = c * np.array([[12, 6 * L, -12, 6 * L],
                            [6 * L, (4 + phi) * L**2, -6 * L, (2 - phi) * L**2],
                            [-12, -6 * L, 12, -6 * L],
                            [6 * L, (2 - phi) * L**2, -6 * L, (4 + phi) * L**2]])
    k[np.ix_([1, 2, 4, 5], [1, 2, 4, 5])] = bending
    return k


class LinearFrame:
    """A planar frame of members between ``points`` (see the module's docstring)."""

    def __init__(self, points, members, EI, EA=math.inf, GA=math.inf):
        self.points = [np.asarray(p, dtype=float) for p in points]
        self.members = [tuple(m) for m in members]
        count = len(self.members)
        as_list = lambda value: list(value) if np.ndim(value) else [value] * count  # noqa: E731
        self.EI, self.EA, self.GA = as_list(EI), as_list(EA), as_list(GA)
        self._pinned: set = set()
        self._fixed: list = []
        self._loads: list = []

    def pin(self, node: int, member: int) -> None:
        self._pinned.add((node, member))

    def fix(self, node: int, *components: str, member: int | None = None) -> None:
        for name in components:
            self._fixed.append((node, name, member))

    def load(self, node: int, fx: float = 0.0, fy: float = 0.0, moment: float = 0.0,
             member: int | None = None) -> None:
        self._loads.append((node, fx, fy, moment, member))

    def _numbering(self) -> tuple[dict, int]:
        index, n = {}, 0
        for node in range(len(self.points)):
            index[(node, "u")], index[(node, "v")] = n, n + 1
            n += 2
        for node in range(len(self.points)):
            shared = None
            for k, member in enumerate(self.members):
                if node not in member:
                    continue
                if (node, k) in self._pinned:
                    index[(node, "theta", k)] = n
                    n += 1
                    continue
                if shared is None:
                    shared, n = n, n + 1
                index[(node, "theta", k)] = shared
        return index, n

    def _rotation(self, node: int, member: int | None, index: dict) -> int:
        if member is None:
            member = next(k for k, m in enumerate(self.members) if node in m
                          and (node, k) not in self._pinned)
        return index[(node, "theta", member)]

    def solve(self) -> dict:
        index, n = self._numbering()
        K, F = np.zeros((n, n)), np.zeros(n)
        for k, (i, j) in enumerate(self.members):
            d = self.points[j] - self.points[i]
            length = float(np.linalg.norm(d))
            c, s = d / length
            T = np.zeros((6, 6))
            rotation = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
            T[:3, :3] = T[3:, 3:] = rotation
            ke = T.T @ member_stiffness(length, self.EI[k], self.EA[k], self.GA[k]) @ T
            dofs = [index[(i, "u")], index[(i, "v")], index[(i, "theta", k)],
                    index[(j, "u")], index[(j, "v")], index[(j, "theta", k)]]
            K[np.ix_(dofs, dofs)] += ke
        for node, fx, fy, moment, member in self._loads:
            F[index[(node, "u")]] += fx
            F[index[(node, "v")]] += fy
            if moment:
                F[self._rotation(node, member, index)] += moment
        fixed = set()
        for node, name, member in self._fixed:
            fixed.add(index[(node, name)] if name != "theta"
                      else self._rotation(node, member, index))
        free = np.array([i for i in range(n) if i not in fixed])
        x = np.zeros(n)
        x[free] = np.linalg.solve(K[np.ix_(free, free)], F[free])
        self.reactions = K @ x - F
        self._index = index
        return {"u": np.array([x[index[(p, "u")]] for p in range(len(self.points))]),
                "v": np.array([x[index[(p, "v")]] for p in range(len(self.points))]),
                "theta": {(p, k): x[index[(p, "theta", k)]] for k, m in
                          enumerate(self.members) for p in m}}

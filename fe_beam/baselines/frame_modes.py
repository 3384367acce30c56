"""Natural frequencies of planar frames of straight members: the exact transfer-matrix method
(in-plane motions, `Member`, and motions out of the plane, `OutOfPlaneMember`).

A plain numpy/scipy reference solver, independent of FEniCSx, for the linear vibrations of a
frame of straight, uniform members joined rigidly at nodes (fe_beam's `modes` of a structure of
[[rods]] about the unloaded reference state, Reissner law). Each member is an extensible
Timoshenko beam with rotary inertia, in its own axes (axial ``a``, transverse ``w``, section
rotation ``theta``; time factor exp(i omega t)):

    N = EA a',  V = k GA (w' - theta),  M = EI theta'
    N' = -rho A omega^2 a,  V' = -rho A omega^2 w,  M' = -V - rho I omega^2 theta

(EA = inf or GA = inf: inextensible or unshearable). The state z = (a, w, theta, N, V, M) obeys
z' = A(omega) z with constant A, so a member's exact transfer matrix is expm(A L) (no
discretisation). Unknowns: the start state of each member and the world displacements
(u_x, u_y, theta) of each node. Equations: each member end's displacements equal its node's
(turned into the member's axes), and at each node either its dofs are held (a support) or the
member end forces balance (the force on the node from a member is +F(0) at the member's start,
-F(L) at its end, F the section force of the part beyond on the part before). The frequencies
are the roots of the determinant of that matrix, an entire function of omega (no poles): its
sign changes on a fine scan are bracketed and refined by Brent's method. States are scaled by a
reference length and EI so that the matrix is well conditioned.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

__all__ = ["Member", "OutOfPlaneMember", "frame_frequencies", "determinant", "portal_frame"]

SUPPORTS = {"clamped": (0, 1, 2), "pinned": (0, 1), "free": ()}


@dataclass(frozen=True)
class Member:
    """A straight member from ``start`` at the angle ``angle`` over ``length``; its stiffnesses
    (``EA``, ``GA``: math.inf for the constrained limits; GA includes the shear correction) and
    masses per length (``rho_area`` on the translations, ``rho_inertia`` on the rotation)."""

    start: tuple
    angle: float
    length: float
    EI: float
    EA: float = math.inf
    GA: float = math.inf
    rho_area: float = 1.0
    rho_inertia: float = 0.0

    def end(self) -> tuple[float, float]:
        return (self.start[0] + self.length * math.cos(self.angle),
                self.start[1] + self.length * math.sin(self.angle))


@dataclass(frozen=True)
class OutOfPlaneMember:
    """A member of a frame in the xy plane for its motions out of that plane: the displacement
    w along z, the section's rotation psi about the in-plane normal d2 = e_z x d1 (bending,
    ``EI`` about d2, shear ``GA`` along z with the shear correction, ``rho_inertia`` = rho I
    about d2) and its twist phi about the axis d1 (``GJ``, Saint-Venant; ``rho_polar`` = rho
    I_p). Member equations (time factor exp(i omega t), Q the shear force along z, M the
    moment about d2, T the torque):

        Q = GA (w' + psi),  M = EI psi',  T = GJ phi'
        Q' = -rho A omega^2 w,  M' = Q - rho I omega^2 psi,  T' = -rho I_p omega^2 phi

    (linearised from v = R^T r', u = R^T R': the shear v3 = w' + psi, so M' = +Q here where
    the in-plane M' = -V). The node dofs are (w, theta_x, theta_y) in world axes."""

    start: tuple
    angle: float
    length: float
    EI: float
    GJ: float
    GA: float = math.inf
    rho_area: float = 1.0
    rho_inertia: float = 0.0
    rho_polar: float = 0.0

    def end(self) -> tuple[float, float]:
        return (self.start[0] + self.length * math.cos(self.angle),
                self.start[1] + self.length * math.sin(self.angle))


def _transfer_out_of_plane(member: OutOfPlaneMember, omega: float, scale_length: float,
                           scale_EI: float) -> np.ndarray:
    """expm(A L) of the scaled state (w/Ls, psi, phi, Q Ls^2/EIs, M Ls/EIs, T Ls/EIs)."""
    L0, EI0 = scale_length, scale_EI
    w2 = omega**2
    A = np.zeros((6, 6))
    A[0, 1] = -1.0
    A[0, 3] = 0.0 if math.isinf(member.GA) else EI0 / (member.GA * L0**2)
    A[1, 4] = EI0 / member.EI
    A[2, 5] = EI0 / member.GJ
    A[3, 0] = -member.rho_area * w2 * L0**4 / EI0
    A[4, 3] = 1.0
    A[4, 1] = -member.rho_inertia * w2 * L0**2 / EI0
    A[5, 2] = -member.rho_polar * w2 * L0**2 / EI0
    return scipy.linalg.expm(A * (member.length / L0))


def _nodes(members, tolerance: float) -> tuple[list, list]:
    """The distinct end points and, per member, the indices of its start and end nodes."""
    points, ends = [], []
    for member in members:
        pair = []
        for point in (member.start, member.end()):
            index = next((i for i, p in enumerate(points) if math.dist(p, point) <= tolerance),
                         None)
            if index is None:
                points.append(point)
                index = len(points) - 1
            pair.append(index)
        ends.append(tuple(pair))
    return points, ends


def _transfer(member: Member, omega: float, scale_length: float, scale_EI: float) -> np.ndarray:
    """expm(A L) of the scaled state (a/Ls, w/Ls, theta, N Ls^2/EIs, V Ls^2/EIs, M Ls/EIs)."""
    L0, EI0 = scale_length, scale_EI
    w2 = omega**2
    A = np.zeros((6, 6))
    # d/dx in units of 1/L0: A scaled = L0 * A in the scaled variables
    A[0, 3] = 0.0 if math.isinf(member.EA) else EI0 / (member.EA * L0**2)
    A[1, 2] = 1.0
    A[1, 4] = 0.0 if math.isinf(member.GA) else EI0 / (member.GA * L0**2)
    A[2, 5] = EI0 / member.EI
    A[3, 0] = -member.rho_area * w2 * L0**4 / EI0
    A[4, 1] = -member.rho_area * w2 * L0**4 / EI0
    A[5, 4] = -1.0
    A[5, 2] = -member.rho_inertia * w2 * L0**2 / EI0
    return scipy.linalg.expm(A * (member.length / L0))


def _matrix(members, supports: dict, omega: float, pins=frozenset()) -> np.ndarray:
    """``pins``: {(member index, "start" | "end")}: member ends joined to their node by a pin
    (the end's rotation free, its moment zero)."""
    scale_length = max(m.length for m in members)
    scale_EI = max(m.EI for m in members)
    points, ends = _nodes(members, 1e-9 * scale_length)
    n_members, n_nodes = len(members), len(points)
    size = 6 * n_members + 3 * n_nodes
    matrix = np.zeros((size, size))
    row = 0
    forces = [[] for _ in points]  # per node: (member index, 3x(size) force rows in world axes)
    for k, member in enumerate(members):
        c, s = math.cos(member.angle), math.sin(member.angle)
        if isinstance(member, OutOfPlaneMember):
            T = _transfer_out_of_plane(member, omega, scale_length, scale_EI)
            # world (w, theta_x, theta_y) -> member (w, psi = theta . d2, phi = theta . d1)
            to_local = np.array([[1.0, 0.0, 0.0], [0.0, -s, c], [0.0, c, s]])
        else:
            T = _transfer(member, omega, scale_length, scale_EI)
            # world (ux, uy) -> member axes (a, w): a = c ux + s uy, w = -s ux + c uy
            to_local = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        start = np.zeros((6, size))
        start[:, 6 * k: 6 * k + 6] = np.eye(6)
        finish = T @ start
        for state, node, sign, which in ((start, ends[k][0], 1.0, "start"),
                                          (finish, ends[k][1], -1.0, "end")):
            displacement = state[:3]
            node_columns = slice(6 * n_members + 3 * node, 6 * n_members + 3 * node + 3)
            block = displacement.copy()
            block[:, node_columns] -= to_local
            force = sign * (to_local.T @ state[3:])
            if (k, which) in pins:  # a pin: no rotation equality, no moment
                block[2] = state[5]
                force[2] = 0.0
            matrix[row: row + 3] = block
            row += 3
            forces[node].append(force)
    for node in range(n_nodes):
        held = SUPPORTS[supports.get(node, "free")]
        for dof in range(3):
            if dof in held:
                matrix[row, 6 * n_members + 3 * node + dof] = 1.0
            else:
                matrix[row] = sum(f[dof] for f in forces[node])
            row += 1
    assert row == size
    return matrix


def determinant(members, supports: dict, omega: float) -> float:
    """The determinant of the frame's matrix at the circular frequency ``omega`` [rad/s]."""
    sign, log = np.linalg.slogdet(_matrix(members, supports, omega))
    return float(sign * math.exp(log))


def _support_nodes(members, supports_at: dict) -> dict:
    """{node index: kind} of the supports given as {(x, y): kind}."""
    scale = max(m.length for m in members)
    points, _ = _nodes(members, 1e-9 * scale)
    result = {}
    for where, kind in supports_at.items():
        index = next(i for i, p in enumerate(points) if math.dist(p, where) <= 1e-9 * scale)
        result[index] = kind
    return result


def frame_frequencies(members, supports_at: dict, count: int, omega_max: float,
                      samples: int = 4000, pins=frozenset()) -> list[float]:
    """The ``count`` lowest natural frequencies [Hz] below ``omega_max`` [rad/s] of the frame
    with supports {(x, y): "clamped" | "pinned" | "free"} at nodes (every other node free) and
    ``pins`` {(member index, "start" | "end")} (those member ends pinned to their node).
    The scan's step omega_max / samples must separate the roots (a pair of roots closer than
    a step would be missed: compare the count with the expected one). Members of the kind
    `OutOfPlaneMember` give the frame's motions out of its plane (the held dofs of a node are
    then w, theta_x, theta_y)."""
    supports = _support_nodes(members, supports_at)
    grid = np.linspace(omega_max / samples, omega_max, samples)

    def sign_log(omega):
        return np.linalg.slogdet(_matrix(members, supports, omega, pins))

    values = [sign_log(w) for w in grid]
    roots = []
    for i in range(len(grid) - 1):
        if values[i][0] * values[i + 1][0] < 0:
            reference = 0.5 * (values[i][1] + values[i + 1][1])

            def scaled(omega, reference=reference):
                sign, log = sign_log(omega)
                return sign * math.exp(log - reference)

            root = scipy.optimize.brentq(scaled, grid[i], grid[i + 1], xtol=1e-15 * grid[i + 1],
                                         rtol=4 * np.finfo(float).eps, maxiter=200)
            roots.append(root / (2 * math.pi))
            if len(roots) == count:
                break
    return roots


def portal_frame(height: float, span: float, EI: float, EA: float = math.inf,
                 GA: float = math.inf, rho_area: float = 1.0, rho_inertia: float = 0.0,
                 EI_beam: float | None = None) -> tuple[list, dict]:
    """(members, supports) of a portal frame: a column (0, 0) -> (0, h), a beam to (span, h),
    a column down to (span, 0); both bases clamped."""
    members = [
        Member((0.0, 0.0), math.pi / 2, height, EI, EA, GA, rho_area, rho_inertia),
        Member((0.0, height), 0.0, span, EI if EI_beam is None else EI_beam, EA, GA, rho_area,
               rho_inertia),
        Member((span, height), -math.pi / 2, height, EI, EA, GA, rho_area, rho_inertia),
    ]
    return members, {(0.0, 0.0): "clamped", (span, 0.0): "clamped"}

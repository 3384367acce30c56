"""Independent reference: a spatial serial chain of straight rods joined rigidly, clamped at
its start, dead point forces and moments at its free end, solved by shooting (Reissner law).

Each member k has the reference frame R0_k (columns d1 = its direction, d2, d3) and the
length L_k. The world rotation R(s) is continuous along the chain except that at a rigid
corner the incremental rotation R R0^T is continuous: R jumps to R R0_k^T R0_{k+1}. On a member

    r' = R v,   R' = R u^,   n' = 0,   m' = -r' x n,
    v = e1 + C_n^-1 R^T n,   u = C_m^-1 R^T m,

C_n = diag(EA, GA, GA), C_m = diag(GJ, EI_y, EI_z) (body axes). The unknowns are the clamp's
force n(0) and moment m(0) (6 numbers); at the free end n = P, m = M. Newton with a
finite-difference Jacobian and load continuation; scipy's DOP853 at tight tolerances.
Nothing here uses fe_beam's finite elements.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

__all__ = ["SpatialFrame", "solve_spatial_frame"]


@dataclass(frozen=True)
class SpatialFrame:
    """``frames``: per member the 3x3 R0 (columns d1, d2, d3); ``lengths``; ``stiffness``:
    (EA, GA, GJ, EI_y, EI_z) shared by the members; ``start`` the clamp's position; ``force``
    and ``moment``: the dead end wrench (world axes)."""

    frames: tuple
    lengths: tuple
    stiffness: tuple
    start: tuple = (0.0, 0.0, 0.0)
    force: tuple = (0.0, 0.0, 0.0)
    moment: tuple = (0.0, 0.0, 0.0)


def _hat(a):
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def _integrate(frame: SpatialFrame, n0, m0, rtol: float):
    """(r, R, n, m) at the free end and at every corner, from the clamp's (n0, m0)."""
    EA, GA, GJ, EIy, EIz = frame.stiffness
    cn = np.array([EA, GA, GA])
    cm = np.array([GJ, EIy, EIz])

    def rhs(_, y):
        R = y[3:12].reshape(3, 3)
        n, m = y[12:15], y[15:18]
        v = np.array([1.0, 0.0, 0.0]) + (R.T @ n) / cn
        u = (R.T @ m) / cm
        dr = R @ v
        return np.concatenate([dr, (R @ _hat(u)).ravel(), np.zeros(3), -np.cross(dr, n)])

    R = np.array(frame.frames[0], dtype=float)
    y = np.concatenate([np.array(frame.start, dtype=float), R.ravel(), n0, m0])
    corners = []
    for k, length in enumerate(frame.lengths):
        if k > 0:  # the rigid corner: R R0_{k-1}^T continuous
            R = y[3:12].reshape(3, 3) @ np.array(frame.frames[k - 1]).T @ np.array(
                frame.frames[k])
            y = np.concatenate([y[:3], R.ravel(), y[12:]])
        solution = solve_ivp(rhs, (0.0, length), y, method="DOP853", rtol=rtol,
                             atol=rtol * 1e-2)
        y = solution.y[:, -1]
        corners.append((y[:3].copy(), y[3:12].reshape(3, 3).copy(), y[12:15].copy(),
                        y[15:18].copy()))
    return corners


def solve_spatial_frame(frame: SpatialFrame, steps: int = 8, rtol: float = 1e-12,
                        tol: float = 1e-12):
    """[(r, R, n, m) at each member's end] of the equilibrium (RuntimeError if Newton fails)."""
    force, moment = np.array(frame.force, float), np.array(frame.moment, float)
    z = np.zeros(6)
    scale = max(np.linalg.norm(force) * sum(frame.lengths), np.linalg.norm(moment), 1e-300)
    for step in range(1, steps + 1):
        factor = step / steps

        def residual(z, factor=factor):
            end = _integrate(frame, z[:3], z[3:], rtol)[-1]
            return np.concatenate([(end[2] - factor * force) * sum(frame.lengths),
                                   end[3] - factor * moment]) / scale

        if step == 1:  # the clamp's reactions of the rigid structure as the first guess
            tip = np.array(frame.start, float) + sum(
                np.array(f)[:, 0] * length for f, length in zip(frame.frames, frame.lengths,
                                                                strict=True))
            f = factor * force
            z = np.concatenate([f, factor * moment + np.cross(tip - np.array(frame.start), f)])
        for _ in range(30):
            r = residual(z)
            if np.linalg.norm(r) < tol:
                break
            h = 1e-7 * max(1.0, np.linalg.norm(z))
            J = np.column_stack([(residual(z + h * e) - r) / h for e in np.eye(6)])
            z = z - np.linalg.solve(J, r)
        else:
            raise RuntimeError("spatial frame shooting: Newton did not converge")
    return _integrate(frame, z[:3], z[3:], rtol)

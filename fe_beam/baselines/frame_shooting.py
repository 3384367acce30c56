"""Planar frames of straight rods with rigid corners: Reissner / elastica statics by shooting.

A plain numpy/scipy reference solver, independent of FEniCSx, for serial chains of rods
(`fe_beam.model.structure`): the chain's arc length s in [0, sum L_i], each member i straight in
the reference state at the angle ``angles[i]``; at a rigid corner the section angle phi jumps by
the change of the reference angle, and the position, force and moment are continuous.

State y = (x, y, phi, n_x, n_y, m): position, world section angle, and the force and moment
exerted by the part beyond s on the part before it (world axes). With a1 = (cos phi, sin phi),
d = (-sin phi, cos phi) and the Reissner law (W = EA e^2/2 + GA g^2/2 + EI kappa^2/2):

    r'  = (1 + N / EA) a1 + (T / GA) d,      N = n . a1,  T = n . d
    phi' = m / EI
    n'  = -f,      m' = -(r' x n)_z          (f: dead distributed force per length)

EA = GA = inf is the elastica (inextensible, unshearable). Point forces P at s_p make n jump by
-P. Ends: "clamped" (position and angle held), "pinned" (position held, m = 0), "free"
(n = 0, m = 0). The start's three unknowns are shot and the end's three conditions solved by
`scipy.optimize.root`; `limit_load` finds the largest load on a path parameterised by a
displacement (a limit point of the load), for Lee's frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.integrate
import scipy.optimize

__all__ = ["Frame", "FrameSolution", "lee_frame", "limit_load", "solve_frame"]


@dataclass(frozen=True)
class Frame:
    """Members (lengths, reference angles), stiffnesses (numbers, or tuples: one per member),
    the start point, end conditions and point forces ((s, Px, Py), ...) at the chain's arc
    length s (loads at load factor 1)."""

    lengths: tuple
    angles: tuple
    EI: float | tuple
    EA: float | tuple = math.inf
    GA: float | tuple = math.inf
    start: tuple = (0.0, 0.0)
    start_kind: str = "clamped"
    end_kind: str = "free"
    point_forces: tuple = ()
    distributed: tuple = (0.0, 0.0)

    @property
    def length(self) -> float:
        return float(sum(self.lengths))

    def corners(self) -> list[float]:
        return list(np.cumsum(self.lengths)[:-1])

    def reference_end(self) -> tuple[float, float, float]:
        x, y = self.start
        for length, angle in zip(self.lengths, self.angles, strict=True):
            x, y = x + length * math.cos(angle), y + length * math.sin(angle)
        return x, y, self.angles[-1]


@dataclass
class FrameSolution:
    frame: Frame
    factor: float
    start_values: np.ndarray
    pieces: list = field(default_factory=list)  # (s_a, s_b, dense solution)

    def state(self, s: float) -> np.ndarray:
        """y(s) (the piece that starts at s at a breakpoint)."""
        for a, b, sol in self.pieces:
            if a <= s <= b:
                return sol.sol(s)
        raise ValueError(f"s = {s} outside the frame")

    def end(self) -> np.ndarray:
        a, b, sol = self.pieces[-1]
        return sol.y[:, -1]


def _member(frame: Frame, k: int) -> tuple[float, float, float]:
    """(EI, EA, GA) of member k (each a number for every member, or one per member)."""
    return tuple(float(value[k]) if isinstance(value, (tuple, list)) else float(value)
                 for value in (frame.EI, frame.EA, frame.GA))


def _rhs(frame: Frame, factor: float, k: int = 0):
    fx, fy = (factor * c for c in frame.distributed)
    EI, EA, GA = _member(frame, k)

    def rhs(_s, y):
        _, _, phi, nx, ny, m = y
        c, s = math.cos(phi), math.sin(phi)
        normal, shear = nx * c + ny * s, -nx * s + ny * c
        e = 0.0 if math.isinf(EA) else normal / EA
        g = 0.0 if math.isinf(GA) else shear / GA
        rx, ry = (1 + e) * c - g * s, (1 + e) * s + g * c
        return [rx, ry, m / EI, -fx, -fy, -(rx * ny - ry * nx)]

    return rhs


def _integrate(frame: Frame, factor: float, y0, rtol: float, dense: bool = False):
    """Integrate from s = 0 with y0; returns (end state, pieces)."""
    breaks = sorted(set(frame.corners()) | {float(p[0]) for p in frame.point_forces
                                            if 0 < p[0] < frame.length})
    points = [0.0] + breaks + [frame.length]
    corners = frame.corners()
    y = np.array(y0, dtype=float)
    pieces = []
    for a, b in zip(points[:-1], points[1:], strict=True):
        member = sum(1 for corner in corners if corner <= a + 1e-12 * frame.length)
        rhs = _rhs(frame, factor, member)
        sol = scipy.integrate.solve_ivp(rhs, (a, b), y, method="DOP853", rtol=rtol,
                                        atol=rtol * 1e-3, dense_output=dense)
        y = sol.y[:, -1].copy()
        pieces.append((a, b, sol))
        for k, corner in enumerate(corners):
            if abs(b - corner) <= 1e-12 * frame.length:
                y[2] += frame.angles[k + 1] - frame.angles[k]
        for s_p, px, py in frame.point_forces:
            if abs(b - s_p) <= 1e-12 * frame.length and b < frame.length:
                y[3] -= factor * px
                y[4] -= factor * py
    # point forces at the end: the end's force balance holds n(L-) = P
    end = y.copy()
    for s_p, px, py in frame.point_forces:
        if abs(frame.length - s_p) <= 1e-12 * frame.length:
            end[3] -= factor * px
            end[4] -= factor * py
    return end, pieces


def _start_state(frame: Frame, unknowns) -> list[float]:
    x0, y0 = frame.start
    if frame.start_kind == "clamped":
        m0, nx, ny = unknowns
        return [x0, y0, frame.angles[0], nx, ny, m0]
    if frame.start_kind == "pinned":
        phi, nx, ny = unknowns
        return [x0, y0, phi, nx, ny, 0.0]
    raise ValueError(f"start_kind must be clamped or pinned, got {frame.start_kind!r}")


def _end_residual(frame: Frame, end: np.ndarray) -> np.ndarray:
    X, Y, angle = frame.reference_end()
    if frame.end_kind == "free":
        return np.array([end[3], end[4], end[5]])
    if frame.end_kind == "pinned":
        return np.array([end[0] - X, end[1] - Y, end[5]])
    if frame.end_kind == "clamped":
        return np.array([end[0] - X, end[1] - Y, end[2] - angle])
    raise ValueError(f"end_kind must be free, pinned or clamped, got {frame.end_kind!r}")


def _scales(frame: Frame) -> np.ndarray:
    force = _member(frame, 0)[0] / frame.length**2
    return np.array([force * frame.length, force, force]) if frame.start_kind == "clamped" \
        else np.array([1.0, force, force])


def solve_frame(frame: Frame, factor: float = 1.0, guess=None, rtol: float = 1e-12,
                dense: bool = True, steps: int = 10) -> FrameSolution:
    """The equilibrium at ``factor`` times the loads (shooting from ``guess``: the start's
    unknowns, default the unloaded state; when that fails, from the equilibria at ``steps``
    increasing fractions of the load)."""
    scale = _scales(frame)
    if guess is None:
        guess = [0.0, 0.0, 0.0] if frame.start_kind == "clamped" else [frame.angles[0], 0, 0]
    EI = _member(frame, 0)[0]
    res_scale = np.array([EI / frame.length, EI / frame.length**2, EI / frame.length])
    if frame.end_kind != "free":
        res_scale = np.array([frame.length, frame.length, EI / frame.length])
        if frame.end_kind == "clamped":
            res_scale[2] = 1.0

    def residual(z):
        end, _ = _integrate(frame, factor, _start_state(frame, z * scale), rtol)
        return _end_residual(frame, end) / res_scale

    def shoot(z0):
        found = scipy.optimize.root(residual, z0, method="hybr", options={"xtol": 1e-13})
        return found if np.max(np.abs(found.fun)) <= 1e-10 else None

    found = shoot(np.asarray(guess) / scale)
    if found is None and steps > 1:  # large loads: step the load factor from the guess's
        start = np.asarray(guess, dtype=float)
        for k in range(1, steps + 1):
            start = solve_frame(frame, factor * k / steps, start, rtol, dense=False,
                                steps=1).start_values
        found = shoot(start / scale)
    if found is None:
        raise RuntimeError("frame shooting did not converge")
    values = found.x * scale
    _, pieces = _integrate(frame, factor, _start_state(frame, values), rtol, dense=dense)
    return FrameSolution(frame, factor, values, pieces)


def lee_frame(length: float = 1.0, EI: float = 1.0, at: float = 0.2, EA: float = math.inf,
              GA: float = math.inf, load: float = 1.0) -> Frame:
    """Lee's frame: a column from (0, 0) up to (0, L), a beam from (0, L) to (L, L), rigid
    corner, pinned at (0, 0) and (L, L), a downward load ``load`` at ``at`` L from the corner."""
    return Frame((length, length), (math.pi / 2, 0.0), EI, EA, GA, (0.0, 0.0), "pinned",
                 "pinned", ((length * (1 + at), 0.0, -load),))


def _displacement_controlled(frame: Frame, s_point: float, component: int, target: float,
                             guess, rtol: float):
    """(factor, start unknowns) with the point s_point's ``component`` (0: x, 1: y) at
    ``target``: the load factor is a fourth unknown."""
    EI = _member(frame, 0)[0]
    scale = np.append(_scales(frame), EI / frame.length**2)

    def residual(z):
        values = z * scale
        start = _start_state(frame, values[:3])
        end, pieces = _integrate(frame, values[3], start, rtol, dense=True)
        state = next(sol.sol(s_point) for a, b, sol in pieces if a <= s_point <= b)
        return np.append(_end_residual(frame, end) / np.array([frame.length, frame.length,
                                                               EI / frame.length]),
                         (state[component] - target) / frame.length)

    found = scipy.optimize.root(residual, np.asarray(guess) / scale, method="hybr",
                                options={"xtol": 1e-13})
    if np.max(np.abs(found.fun)) > 1e-10:  # hybr may stop at round-off and call it failure
        raise RuntimeError(f"displacement-controlled shooting failed: {found.message}")
    values = found.x * scale
    return float(values[3]), values


def limit_load(frame: Frame, s_point: float, component: int = 1, step: float = 0.01,
               rtol: float = 1e-11) -> tuple[float, float]:
    """(the largest load factor, the displacement there) along the path on which the point
    s_point moves (``component`` 0: x, 1: y) from its reference position in steps of -``step``
    L until the load factor falls: a limit point of the load, then located by a bounded
    maximisation (to 1e-6 L in the displacement: the load is flat there)."""
    reference = _reference_point(frame, s_point)[component]
    guess = np.array([frame.angles[0], 0.0, 0.0, 0.0])
    if frame.start_kind == "clamped":
        guess[0] = 0.0
    best, values, delta = (-math.inf, 0.0), {}, 0.0
    while True:
        delta -= step * frame.length
        factor, guess = _displacement_controlled(frame, s_point, component, reference + delta,
                                                 guess, rtol)
        values[delta] = guess.copy()
        if factor < best[0]:
            break
        best = (factor, delta)
        if abs(delta) > 2 * frame.length:
            raise RuntimeError("no limit point within a displacement of 2 L")
    factor, delta = best
    start = values[delta]

    def negative(d):
        f, _ = _displacement_controlled(frame, s_point, component, reference + d, start, rtol)
        return -f

    width = step * frame.length
    found = scipy.optimize.minimize_scalar(negative, bounds=(delta - width, delta + width),
                                           method="bounded",
                                           options={"xatol": 1e-6 * frame.length})
    return float(-found.fun), float(found.x)


def _reference_point(frame: Frame, s: float) -> tuple[float, float]:
    x, y = frame.start
    travelled = 0.0
    for length, angle in zip(frame.lengths, frame.angles, strict=True):
        t = min(max(s - travelled, 0.0), length)
        x, y = x + t * math.cos(angle), y + t * math.sin(angle)
        travelled += length
    return x, y

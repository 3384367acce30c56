"""The rod's loads as a registry with capability flags (docs: Architecture, "a new load").

Each entry names a field of `fe_beam.model.beam.Loads` (and the ``[loads]`` key of the same
name) and says what it is and who applies it, so that the commands and engines read flags
instead of keeping their own lists:

- ``kind``: ``"vector"`` (a pair of components), ``"scalar"`` or ``"points"`` (rows ``[x, Px,
  Py]``: the position is not scaled by the load factor);
- ``motion``: a prescribed end displacement or rotation (a Dirichlet condition: displacement
  control), absent (None) unless given;
- ``follower``: can be a follower load (``[loads] follower = true``);
- ``solid``: the 3D solid applies it (`fe_beam.config.solid`);
- ``fd``: the paper's FD + Runge-Kutta schemes apply it (``[time] scheme = "fd-*"``);
- ``realtime``: `fe_beam.solvers.realtime.RealtimeSolver` updates its value in place (a
  ``fem.Constant`` of the rod problem of the same name);
- ``differentiable``: sensitivities exist for its components (`fe_beam.analyses.sensitivity`).

A new load is its field in `Loads`, its entry here and its term in
`fe_beam.fem.rod.BeamProblem.dead_load_work` (which the energy-momentum scheme shares).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["LOADS", "LoadKind", "given", "scaled", "unsupported"]


@dataclass(frozen=True)
class LoadKind:
    name: str
    kind: str
    help: str
    motion: bool = False
    follower: bool = False
    solid: bool = False
    fd: bool = False
    realtime: bool = False
    differentiable: bool = False

    def is_given(self, value) -> bool:
        """Whether a value of this load acts (nonzero)."""
        if value is None:
            return False
        if self.motion:
            return True  # a prescribed motion acts even where it holds a value 0
        if self.kind == "points":
            return any(any(row[1:]) for row in value)
        if self.kind == "vector" or isinstance(value, (list, tuple)):  # spatial: vectors
            return any(value)
        return bool(value)

    def scaled(self, value, factor: float):
        """The value at load factor ``factor`` (point positions are not scaled)."""
        if self.kind == "points":
            return [[row[0], *(factor * c for c in row[1:])] for row in value]
        if self.kind == "vector" or isinstance(value, (list, tuple)):  # spatial: vectors
            return [factor * c for c in value]
        return factor * value


LOADS: dict[str, LoadKind] = {kind.name: kind for kind in (
    LoadKind("tip_force", "vector", "[Px, Py] at x = L [N]", follower=True, solid=True, fd=True,
             realtime=True, differentiable=True),
    LoadKind("tip_moment", "scalar", "moment at x = L [N m], counterclockwise", fd=True,
             realtime=True, differentiable=True),
    LoadKind("distributed", "vector", "[qx, qy] per unit length [N/m]", fd=True, realtime=True,
             differentiable=True),
    LoadKind("gravity", "vector", "[gx, gy] acceleration [m/s^2]", realtime=True,
             differentiable=True),
    LoadKind("point_forces", "points", "[[x, Px, Py], ...] dead forces at 0 < x <= L [m, N]"),
    LoadKind("point_moments", "points", "[[x, M], ...] dead moments about z at 0 <= x <= L "
             "[m, N m] (spatial: [[x, Mx, My, Mz], ...], world axes)"),
    LoadKind("end_displacement", "vector", "[du, dv] prescribed at x = L [m]", motion=True),
    LoadKind("end_rotation", "scalar", "rotation prescribed at x = L [rad]", motion=True),
)}


def given(loads, exclude: tuple[str, ...] = ()) -> list[str]:
    """The names of the loads of ``loads`` (a `Loads`) that act, in registry order."""
    return [name for name, kind in LOADS.items()
            if name not in exclude and kind.is_given(getattr(loads, name))]


def scaled(loads, factor: float) -> dict:
    """{name: value at ``factor``} of the loads that act (e.g. critical loads)."""
    return {name: LOADS[name].scaled(getattr(loads, name), factor) for name in given(loads)}


def unsupported(loads, flag: str) -> list[str]:
    """The acting loads whose capability ``flag`` (solid, fd, realtime, ...) is false."""
    return [name for name in given(loads) if not getattr(LOADS[name], flag)]

"""Tendon geometry as data (docs/theory.md, Tendons): offset paths, entry, anchor, and the
tension or pull-in at load factor 1. Pure Python; the tendon energy and the pull-in solver are
in `fe_beam.fem.tendons`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fe_beam.errors import ConfigError

__all__ = ["Path", "Tendon", "looped_tendon"]

Path = tuple[tuple[float, float], ...]


def _path(points, name: str) -> Path:
    try:
        path = tuple((float(x), float(delta)) for x, delta in points)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a list of [x, offset] pairs, got {points!r}") from None
    xs = [x for x, _ in path]
    if len(path) < 2 or any(b <= a for a, b in zip(xs, xs[1:])):
        raise ValueError(f"{name} needs at least two points with increasing x, got {points!r}")
    if not all(math.isfinite(v) for point in path for v in point):
        raise ValueError(f"{name} must contain finite numbers, got {points!r}")
    return path


@dataclass(frozen=True)
class Tendon:
    """One tendon: offset paths (one per branch, each [(x, delta), ...] in metres, piecewise
    linear), entry and anchor x, and either a tension [N] or a pull-in [m] at load factor 1."""

    paths: tuple[Path, ...]
    entry: float = 0.0
    anchor: float | None = None
    tension: float | None = None
    pull_in: float | None = None
    name: str = "tendon"

    def __post_init__(self):
        paths = tuple(_path(p, f"tendon {self.name!r} path") for p in self.paths)
        if not paths:
            raise ValueError(f"tendon {self.name!r} needs a path")
        object.__setattr__(self, "paths", paths)
        if (self.tension is None) == (self.pull_in is None):
            raise ValueError(
                f"tendon {self.name!r}: give exactly one of tension [N] or pull_in [m]"
            )
        for key in ("tension", "pull_in"):
            value = getattr(self, key)
            if value is not None and (
                isinstance(value, bool)
                or not isinstance(value, (int, float))
                or not math.isfinite(value)
                or value < 0
            ):
                raise ValueError(
                    f"tendon {self.name!r}: {key} must be a number >= 0, got {value!r}"
                )
        anchor = self.anchor if self.anchor is not None else max(p[-1][0] for p in paths)
        if not (0 <= self.entry < anchor):
            raise ValueError(
                f"tendon {self.name!r}: need 0 <= entry < anchor, got entry {self.entry!r}, "
                f"anchor {anchor!r}"
            )
        for path in paths:
            if path[0][0] > self.entry or path[-1][0] < anchor:
                raise ValueError(
                    f"tendon {self.name!r}: its path spans x = {path[0][0]:g} .. {path[-1][0]:g} "
                    f"but must cover entry {self.entry:g} .. anchor {anchor:g}"
                )
        object.__setattr__(self, "anchor", float(anchor))

    @classmethod
    def linear(cls, offset_base: float, offset_tip: float, length: float, **kwargs) -> Tendon:
        """Offset varying linearly from x = 0 to x = L."""
        return cls(paths=(((0.0, offset_base), (length, offset_tip)),), **kwargs)

    @property
    def controlled_by_pull_in(self) -> bool:
        return self.pull_in is not None

    def validate_for(self, length: float) -> None:
        if self.anchor > length * (1 + 1e-12):
            raise ValueError(
                f"tendon {self.name!r}: anchor {self.anchor:g} lies beyond the beam "
                f"(L = {length:g})"
            )


def looped_tendon(
    a_left: float, b_left: float, a_right: float, b_right: float, length: float, **kwargs
) -> Tendon:
    """The chapter's loop (eq. 3.2): left and right branches with base offsets b and anchor
    offsets a, joined across the tip (the crossing lies in the rigid tip section), one tension.

    Eq. 3.2 is printed as d(s) = (a - b) s / L - b, which gives d(0) = -b and d(L) = a - 2b,
    contradicting its own definition (b at the base, a at the anchorage); we use
    delta(x) = b + (a - b) x / L.
    """
    return Tendon(
        paths=(((0.0, b_left), (length, a_left)), ((0.0, b_right), (length, a_right))), **kwargs
    )


def check_tendon_inside(tendon: Tendon, section, length: float) -> None:
    """ConfigError if the tendon's offset leaves the section anywhere between entry and anchor
    (the offset is piecewise linear; the section's extent is sampled finely along x)."""
    xs = np.linspace(tendon.entry, tendon.anchor, 201)
    for path in tendon.paths:
        points = np.array(path, dtype=float)
        stations = np.union1d(xs, points[:, 0][(points[:, 0] >= xs[0]) & (points[:, 0] <= xs[-1])])
        offsets = np.interp(stations, points[:, 0], points[:, 1])
        for x, offset in zip(stations, offsets, strict=True):
            extent = section.y_extent(x / length)
            if extent is None:
                return
            low, high = extent
            margin = 1e-9 * (high - low)
            if not low - margin <= offset <= high + margin:
                raise ConfigError(
                    f"[[tendons]] {tendon.name!r}: offset {offset:.6g} m at x = {x:.6g} m lies "
                    f"outside the section (y from {low:.6g} to {high:.6g} m about its centroid)"
                )

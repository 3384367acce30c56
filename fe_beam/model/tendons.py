"""Tendon geometry as data (docs/theory.md, Tendons): offset paths, entry, anchor, and the
tension or pull-in at load factor 1. Pure Python; the tendon energy and the pull-in solver are
in `fe_beam.fem.tendons`.

A tendon runs either along planar offset paths (piecewise linear y(x), z = 0: ``paths``) or
along a routing anywhere in the section (``routing`` = (y, z), two
`fe_beam.timefunctions.Profile` of the arclength s with the constant L: ``[[tendons]]
offset_y``/``offset_z``). `Tendon.offsets` gives (y, z) for either.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fe_beam.errors import ConfigError

__all__ = ["ROUTING_SAMPLES", "Path", "RodProfile", "Tendon", "check_tendon_inside",
           "looped_tendon", "on_chain", "section_margin"]

Path = tuple[tuple[float, float], ...]
#: intervals between entry and anchor on which a routing is sampled: for its checks (finite,
#: inside the section) and for the planar path a planar rod reads (`Tendon.paths`)
ROUTING_SAMPLES = 400


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


def _routing_length(routing, name: str) -> float:
    try:
        y, z = routing
    except (TypeError, ValueError):
        raise ValueError(f"tendon {name!r}: routing must be a pair (y, z) of profiles of s, "
                         f"got {routing!r}") from None
    if not (callable(y) and callable(z)):
        raise ValueError(f"tendon {name!r}: routing must be a pair (y, z) of profiles of s, "
                         f"got {routing!r}")
    lengths = {float(p.constants["L"]) for p in (y, z) if "L" in getattr(p, "constants", {})}
    if len(lengths) != 1 or not all(math.isfinite(v) and v > 0 for v in lengths):
        raise ValueError(f"tendon {name!r}: the routing's profiles need one constant L > 0 "
                         "(the rod's length), e.g. parse_profile(value, {'L': length})")
    return lengths.pop()


@dataclass(frozen=True)
class Tendon:
    """One tendon: offset paths (one per branch, each [(x, delta), ...] in metres, piecewise
    linear), entry and anchor x, and either a tension [N] or a pull-in [m] at load factor 1.

    ``routing`` = (y, z): a tendon routed anywhere in the section, its body offsets y(s), z(s)
    two `fe_beam.timefunctions.Profile` with the constant ``L`` (the rod's length; anchor
    default). ``paths`` is then derived when not given: y sampled at ROUTING_SAMPLES + 1 points
    from entry to anchor (2 points when y is constant), which is what a planar rod reads; a
    spatial rod, the 3D solid and `offsets` read the routing itself.
    """

    paths: tuple[Path, ...] = ()
    entry: float = 0.0
    anchor: float | None = None
    tension: float | None = None
    pull_in: float | None = None
    name: str = "tendon"
    routing: tuple | None = None
    #: a structure of rods: the name of the rod the tendon runs along (its paths, entry and
    #: anchor then in the chain's arc length s: `on_chain`); None: the single rod
    rod: str | None = None

    def __post_init__(self):
        if self.routing is not None:
            length = _routing_length(self.routing, self.name)
            object.__setattr__(self, "routing", tuple(self.routing))
            if not self.paths:
                anchor = length if self.anchor is None else float(self.anchor)
                if not (0 <= self.entry < anchor):
                    raise ValueError(
                        f"tendon {self.name!r}: need 0 <= entry < anchor, got entry "
                        f"{self.entry!r}, anchor {anchor!r}")
                y = self.routing[0]
                count = 2 if getattr(y, "is_constant", False) else ROUTING_SAMPLES + 1
                xs = np.linspace(float(self.entry), anchor, count)
                object.__setattr__(self, "paths", (tuple((float(x), y(x)) for x in xs),))
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

    @property
    def spatial(self) -> bool:
        """True when the tendon is routed by (y, z) profiles (``routing``), whatever their
        values; `out_of_plane` says whether z is nonzero somewhere."""
        return self.routing is not None

    def offsets(self, x, branch: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Body offsets (y, z) at the reference x (arrays like ``x``): the routing's profiles,
        or the piecewise-linear path ``branch`` with z = 0 for a planar tendon."""
        x = np.asarray(x, dtype=float)
        if self.routing is not None:
            y, z = self.routing
            flat = x.reshape(-1)
            ys = np.array([y(v) for v in flat]).reshape(x.shape)
            zs = np.array([z(v) for v in flat]).reshape(x.shape)
            return ys, zs
        points = np.asarray(self.paths[branch], dtype=float)
        return np.interp(x, points[:, 0], points[:, 1]), np.zeros_like(x)

    def stations(self, samples: int = ROUTING_SAMPLES) -> np.ndarray:
        """``samples`` + 1 equally spaced x from entry to anchor."""
        return np.linspace(self.entry, self.anchor, samples + 1)

    @property
    def out_of_plane(self) -> bool:
        """True when the tendon leaves the plane z = 0 somewhere between entry and anchor
        (sampled at `stations`): a planar rod cannot carry it."""
        if self.routing is None:
            return False
        z = self.routing[1]
        if getattr(z, "is_constant", False):
            return z(0.0) != 0.0
        return bool(np.any(self.offsets(self.stations())[1] != 0.0))

    def validate_for(self, length: float) -> None:
        if self.anchor > length * (1 + 1e-12):
            raise ValueError(
                f"tendon {self.name!r}: anchor {self.anchor:g} lies beyond the beam "
                f"(L = {length:g})"
            )


class RodProfile:
    """A rod's routing profile (`fe_beam.timefunctions.Profile` of the rod's own arc length x)
    read along a chain's arc length s: ``sign`` profile(x(s)), x(s) = ``start`` + ``step`` s
    (step +-1). Evaluates on floats and symbolically (`symbolic`, e.g. UFL: the chain rule
    gives the derivative) like the profile; ``text`` and ``constants`` are the rod's."""

    def __init__(self, profile, start: float, step: float, sign: float):
        self.profile, self.start, self.step, self.sign = profile, start, step, sign
        self.constants = dict(profile.constants)
        self.variable = profile.variable
        self.text = profile.text
        self.constant = None if profile.constant is None else sign * profile.constant

    @property
    def is_constant(self) -> bool:
        return self.constant is not None

    def __call__(self, s: float) -> float:
        return self.sign * self.profile(self.start + self.step * float(s))

    def symbolic(self, s, backend: dict | None):
        if self.constant is not None:
            return self.constant
        return self.sign * self.profile.symbolic(self.start + self.step * s, backend)


def on_chain(tendon: Tendon, segment, rod: str, spatial: bool = False) -> Tendon:
    """The tendon of one rod of a chain (`fe_beam.model.structure.ChainSegment` ``segment``),
    its paths, entry and anchor given in the rod's own arc length x and its offsets in the
    rod's own section frame, as a tendon of the chain: x -> s = `ChainSegment.s_of` (x), and
    on a rod traversed from its end the offsets turned with the chain's frame (the rod's
    turned by pi about its d3: y -> -y, z unchanged). A planar routing is read through its
    sampled paths; ``spatial``: a routing stays a routing, its profiles read along s
    (`RodProfile`)."""
    sign = -1.0 if segment.reversed else 1.0
    ends = sorted((segment.s_of(tendon.entry), segment.s_of(tendon.anchor)))
    common = dict(entry=ends[0], anchor=ends[1], tension=tendon.tension,
                  pull_in=tendon.pull_in, name=tendon.name, rod=rod)
    if spatial and tendon.routing is not None:
        # x(s) = s - s0 on a rod traversed from its start, s0 + L - s from its end
        start, step = ((segment.s0 + segment.length, -1.0) if segment.reversed
                       else (-segment.s0, 1.0))
        y, z = tendon.routing
        routing = (RodProfile(y, start, step, sign), RodProfile(z, start, step, 1.0))
        return Tendon(routing=routing, **common)
    paths = tuple(tuple(sorted((segment.s_of(x), sign * delta) for x, delta in path))
                  for path in tendon.paths)
    return Tendon(paths=paths, **common)


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


def check_tendon_inside(tendon: Tendon, section, length: float, index: int | None = None) -> None:
    """ConfigError if the tendon's offset leaves the section anywhere between entry and anchor
    (the offset is piecewise linear; the section's extent is sampled finely along x). A routed
    tendon (y, z) is sampled at ROUTING_SAMPLES + 1 stations against the whole section
    (`section_margin`); ``index`` (0-based) names it as ``[[tendons]] #k``."""
    if tendon.routing is not None:
        _check_routing_inside(tendon, section, length, index)
        return
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


def section_margin(section, s: float, y, z) -> np.ndarray | None:
    """How far the points (y, z) about the centroid lie inside the section at s = x / L (>= 0:
    inside or on the boundary; in metres, along the nearest bounding direction); None for a
    custom section, whose shape is not known. Rectangles |y| <= h/2, |z| <= b/2; circles and
    tubes y^2 + z^2 <= (d/2)^2; T-sections the web (|z| <= tw/2) and the flange (|z| <= b/2)."""
    y, z = np.asarray(y, dtype=float), np.asarray(z, dtype=float)
    at_s = {n: v + (section.dims_tip.get(n, v) - v) * s for n, v in section.dims.items()}
    if section.shape == "rectangle":
        return np.minimum(at_s["h"] / 2 - np.abs(y), at_s["b"] / 2 - np.abs(z))
    if section.shape in ("circle", "tube"):
        return at_s["d"] / 2 - np.hypot(y, z)
    if section.shape == "t-section":
        low, high = section.y_extent(s)
        b, tf, tw = at_s["b"], at_s["tf"], at_s["tw"]
        in_y = np.minimum(y - low, high - y)
        width = np.where(y >= high - tf, b / 2, tw / 2)
        return np.minimum(in_y, width - np.abs(z))
    return None


def _check_routing_inside(tendon: Tendon, section, length: float, index: int | None) -> None:
    y_profile, z_profile = tendon.routing
    keys = [key for key, p in (("offset_y", y_profile), ("offset_z", z_profile))
            if not (getattr(p, "is_constant", False) and p(0.0) == 0.0)] or ["offset_y"]
    label = (f"[[tendons]] #{index + 1} {'/'.join(keys)} ({tendon.name!r})" if index is not None
             else f"[[tendons]] {tendon.name!r} {'/'.join(keys)}")
    xs = tendon.stations()
    ys, zs = tendon.offsets(xs)
    scale = max(1e-300, float(np.max(np.abs(np.concatenate([ys, zs])), initial=0.0)))
    for x, y, z in zip(xs, ys, zs, strict=True):
        margin = section_margin(section, x / length, y, z)
        if margin is None:
            return
        if margin < -1e-9 * scale:
            raise ConfigError(
                f"{label}: the routing (y, z) = ({y:.6g}, {z:.6g}) m at x = {x:.6g} m lies "
                f"outside the {section.shape} section (by {-float(margin):.3g} m)")

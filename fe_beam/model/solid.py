"""The 3D finger as data: body and tendon geometry, mesh sizes, tendon loads and the
discretisation (docs/theory.md, 3D finger and cable). Pure Python and numpy: gmsh and dolfinx
come in with `fe_beam.fem.solid.geometry` and `fe_beam.solvers.solid`, which re-export these.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "ANCHORS",
    "FORMULATIONS",
    "Discretization",
    "FingerGeometry",
    "MeshSizes",
    "TendonLoad",
    "TendonPath",
    "polyline_deviation",
]

def _positive(owner: str, name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{owner}.{name} must be a finite number > 0, got {value!r}")
    if value <= 0:
        raise ValueError(f"{owner}.{name} must be > 0, got {value!r}")
    return float(value)


def polyline_deviation(polyline, points) -> float:
    """max over ``points`` (m, 3) of the distance to the nearest segment of ``polyline`` (n, 3):
    how far a curve sampled at ``points`` strays from a polyline through it."""
    polyline = np.asarray(polyline, dtype=float)
    points = np.asarray(points, dtype=float)
    best = np.full(len(points), np.inf)
    for a, b in zip(polyline[:-1], polyline[1:], strict=True):
        d = b - a
        t = np.clip((points - a) @ d / (d @ d), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(points - (a + t[:, None] * d), axis=1))
    return float(best.max(initial=0.0))


@dataclass(frozen=True)
class TendonPath:
    """A tendon as a polyline of reference points (x, y, z), from entry to anchor.

    The offset of the tendon from the section centroid is its y coordinate (sections are centred
    on the x axis); a positive offset bends the finger toward +y when pulled.
    """

    points: tuple[tuple[float, float, float], ...]
    name: str = "tendon"

    def __post_init__(self):
        try:
            pts = np.asarray(self.points, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(
                f"tendon.points must be a list of (x, y, z) points, got {self.points!r}"
            ) from None
        if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 2:
            raise ValueError(
                f"tendon.points must hold at least 2 points (x, y, z), got shape {pts.shape}"
            )
        if not np.all(np.isfinite(pts)):
            raise ValueError(f"tendon.points must be finite, got {self.points!r}")
        seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        if np.any(seg <= 1e-12 * max(1.0, float(np.abs(pts).max()))):
            raise ValueError("tendon.points: consecutive points must be distinct")
        object.__setattr__(self, "points", tuple(tuple(float(c) for c in p) for p in pts))

    @classmethod
    def from_offsets(
        cls,
        length: float,
        offset_base: float,
        offset_tip: float,
        x_entry: float = 0.0,
        x_anchor: float | None = None,
        z: float = 0.0,
        name: str = "tendon",
    ) -> TendonPath:
        """Straight tendon with offset delta(x) = offset_base + (offset_tip - offset_base) x / L.

        It runs at height y = delta(x) in the plane z = ``z`` from x_entry to x_anchor (default L).
        """
        length = _positive("tendon", "length", length)
        x_anchor = length if x_anchor is None else float(x_anchor)
        if not (0.0 <= x_entry < x_anchor <= length):
            raise ValueError(
                f"tendon: need 0 <= x_entry < x_anchor <= L = {length}, "
                f"got x_entry={x_entry!r}, x_anchor={x_anchor!r}"
            )

        def delta(x):
            return offset_base + (offset_tip - offset_base) * x / length

        return cls(((x_entry, delta(x_entry), z), (x_anchor, delta(x_anchor), z)), name=name)

    @classmethod
    def from_routing(
        cls,
        offsets,
        x_entry: float,
        x_anchor: float,
        tolerance: float,
        samples: int = 2000,
        name: str = "tendon",
    ) -> TendonPath:
        """A polyline through the curve (x, y(x), z(x)), ``offsets(x) -> (y, z)`` (arrays), from
        x_entry to x_anchor, on equally spaced stations in x: the fewest (a power of 2 of
        segments) with which the curve, sampled at ``samples`` + 1 points, stays within
        ``tolerance`` of the polyline (a straight routing: 2 points)."""
        if not (x_anchor > x_entry):
            raise ValueError(f"tendon {name!r}: need x_entry < x_anchor, got {x_entry!r}, "
                             f"{x_anchor!r}")
        tolerance = _positive("tendon", "tolerance", tolerance)
        dense_x = np.linspace(x_entry, x_anchor, samples + 1)
        dense = np.column_stack([dense_x, *offsets(dense_x)])
        segments = 1
        while True:
            pick = np.linspace(0, samples, segments + 1).round().astype(int)
            points = dense[pick]
            if segments >= samples or polyline_deviation(points, dense) <= tolerance:
                return cls(tuple(map(tuple, points)), name=name)
            segments *= 2

    @property
    def array(self) -> np.ndarray:
        return np.asarray(self.points, dtype=float)

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.diff(self.array, axis=0), axis=1).sum())


@dataclass(frozen=True)
class FingerGeometry:
    """Tapered rectangular finger: length L (x), width B (z), height H(x) linear H0 -> H1 (y).

    ``tip_radius`` > 0 rounds the four edges of the tip face (OCC fillet); the tip face then is
    the flat rectangle left in the middle.
    """

    length: float
    width: float
    height_base: float
    height_tip: float | None = None
    tip_radius: float = 0.0
    tendons: tuple[TendonPath, ...] = ()

    def __post_init__(self):
        for name in ("length", "width", "height_base"):
            _positive("geometry", name, getattr(self, name))
        if self.height_tip is None:
            object.__setattr__(self, "height_tip", float(self.height_base))
        _positive("geometry", "height_tip", self.height_tip)
        r = self.tip_radius
        if isinstance(r, bool) or not isinstance(r, (int, float)) or not (r >= 0):
            raise ValueError(f"geometry.tip_radius must be a number >= 0, got {r!r}")
        limit = 0.5 * min(self.width, self.height_tip, self.length)
        if r >= limit:
            raise ValueError(
                f"geometry.tip_radius must be < min(B, H1, L)/2 = {limit:.6g}, got {r!r}"
            )
        tendons = tuple(self.tendons)
        for i, tendon in enumerate(tendons):
            if not isinstance(tendon, TendonPath):
                raise ValueError(f"geometry.tendons[{i}] must be a TendonPath, got {tendon!r}")
            self._check_inside(i, tendon)
        object.__setattr__(self, "tendons", tendons)

    def height(self, x):
        """H(x) = H0 + (H1 - H0) x / L."""
        return self.height_base + (self.height_tip - self.height_base) * np.asarray(x) / self.length

    def area(self, x):
        """A(x) = B H(x)."""
        return self.width * self.height(x)

    def second_moment(self, x):
        """I(x) = B H(x)^3 / 12 (bending in the x-y plane, about the z axis)."""
        return self.width * self.height(x) ** 3 / 12.0

    @property
    def tip_area(self) -> float:
        """Area of the flat tip face: (B - 2 r)(H1 - 2 d), d = r / tan(alpha / 2).

        alpha is the angle between the tip face and the (tapered) top face, cos alpha =
        m / sqrt(1 + m^2) with m = (H1 - H0) / (2 L); d = r without taper.
        """
        r = self.tip_radius
        m = (self.height_tip - self.height_base) / (2 * self.length)
        alpha = math.acos(m / math.sqrt(1 + m * m))
        return (self.width - 2 * r) * (self.height_tip - 2 * r / math.tan(alpha / 2))

    def _check_inside(self, index: int, tendon: TendonPath) -> None:
        pts = tendon.array
        x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
        L, r = self.length, self.tip_radius
        tol = 1e-12 * L
        margin_y = 0.5 * self.height(np.clip(x, 0, L)) - np.abs(y)
        margin_z = 0.5 * self.width - np.abs(z)
        # the polyline is inside the convex body iff all its points are
        bad = (x < -tol) | (x > L + tol) | (margin_y <= 0) | (margin_z <= 0)
        rounded = x > L - r
        bad |= rounded & ((margin_y < r) | (margin_z < r))
        if np.any(bad):
            k = int(np.flatnonzero(bad)[0])
            raise ValueError(
                f"geometry.tendons[{index}] ({tendon.name!r}): point {tuple(pts[k])} is not "
                f"strictly inside the finger (0 <= x <= L, |y| < H(x)/2, |z| < B/2"
                + (", and inside the flat core where x > L - tip_radius)" if r > 0 else ")")
            )


@dataclass(frozen=True)
class MeshSizes:
    """Target element sizes (gmsh fields), geometric order of the tetrahedra.

    Size ``tendon`` within ``tendon_distance`` of a tendon, ``clamp`` within ``clamp_distance`` of
    the clamped face, growing linearly to ``size`` over the same distance again.
    """

    size: float
    tendon: float | None = None
    tendon_distance: float | None = None
    clamp: float | None = None
    clamp_distance: float | None = None
    order: int = 1

    def __post_init__(self):
        _positive("mesh", "size", self.size)
        for name in ("tendon", "clamp"):
            value = getattr(self, name)
            if value is None:
                object.__setattr__(self, name, float(self.size))
            elif _positive("mesh", name, value) > self.size:
                raise ValueError(f"mesh.{name} must be <= mesh.size = {self.size}, got {value!r}")
        for name in ("tendon_distance", "clamp_distance"):
            value = getattr(self, name)
            if value is None:
                object.__setattr__(self, name, float(self.size))
            else:
                _positive("mesh", name, value)
        if self.order not in (1, 2):
            raise ValueError(f"mesh.order must be 1 or 2, got {self.order!r}")


FORMULATIONS = ("displacement", "mixed")
# where a tendon ending on the tip face pulls: its last mesh vertex, or the whole face as a plate
ANCHORS = ("point", "face")


@dataclass(frozen=True)
class TendonLoad:
    """Tension control (``tension`` T: tau = lambda T) or pull-in control (``pull_in`` d:
    l^0 - l = lambda d, the tension is then an unknown). Give one of them."""

    tension: float = 0.0
    pull_in: float | None = None

    def __post_init__(self):
        t = self.tension
        if isinstance(t, bool) or not isinstance(t, (int, float)) or not (0 <= t < math.inf):
            raise ValueError(f"tendon.tension must be a finite number >= 0, got {t!r}")
        if self.pull_in is not None:
            d = self.pull_in
            if isinstance(d, bool) or not isinstance(d, (int, float)) or not (0 <= d < math.inf):
                raise ValueError(f"tendon.pull_in must be a finite number >= 0, got {d!r}")
            if t != 0:
                raise ValueError(
                    f"tendon: give tension or pull_in, not both (tension={t!r}, pull_in={d!r})"
                )

    @property
    def controlled_by_pull_in(self) -> bool:
        return self.pull_in is not None


@dataclass(frozen=True)
class Discretization:
    """``formulation``: "displacement" (P``degree`` Lagrange) or "mixed" (Taylor-Hood P2-P1).

    ``quadrature_degree`` defaults to 2 * degree.
    """

    formulation: str = "displacement"
    degree: int = 2
    quadrature_degree: int | None = None

    def __post_init__(self):
        if self.formulation not in FORMULATIONS:
            raise ValueError(
                f"discretization.formulation must be one of {', '.join(FORMULATIONS)}, "
                f"got {self.formulation!r}"
            )
        if self.degree not in (1, 2, 3):
            raise ValueError(f"discretization.degree must be 1, 2 or 3, got {self.degree!r}")
        if self.formulation == "mixed" and self.degree != 2:
            raise ValueError(
                f"discretization.degree must be 2 for the mixed (P2-P1) formulation, "
                f"got {self.degree!r}"
            )
        q = self.quadrature_degree
        if q is None:
            object.__setattr__(self, "quadrature_degree", 2 * self.degree)
        elif isinstance(q, bool) or not isinstance(q, int) or q < 1:
            raise ValueError(f"discretization.quadrature_degree must be an integer >= 1, got {q!r}")

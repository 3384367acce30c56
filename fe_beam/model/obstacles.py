"""Rigid obstacles the rod may touch (docs/theory.md, Contact with rigid obstacles): validated
dataclasses in the rod's coordinates, their signed distance functions in numpy (the
configuration checks; `fe_beam.fem.contact` writes the same formulas in UFL), and the contact
settings. No finite-element imports.

Every shape is dimension-agnostic: a planar rod gives 2 components (x, y), a spatial rod 3.
In the plane a cylinder is a circle (axis z) and a sphere is a circle too; ``length`` of a
cylinder and ``axis`` matter for spatial rods only.

Signed distance convention: ``distance(p) >= 0`` outside the obstacle (admissible), < 0 inside.

- plane (point P, unit normal n pointing out of the solid side): (p - P) . n, the solid being
  the half-space behind the plane;
- cylinder / sphere (centre C, radius R): |p - C| - R (a cylinder of ``axis`` a: the distance
  from the axis line, |(p - C) - ((p - C) . a) a| - R; finite ``length`` is a spatial-rod key);
- box (min corner, max corner; or center and size): max over its faces of the face planes'
  distances, max_i (+-(p_i - c_i) - half_i). Exact inside and on the faces (its zero level set
  is the box's boundary), an underestimate outside near the corners (there it is the distance
  to the nearest face's plane, not to the corner): conservative.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from fe_beam.errors import ConfigError
from fe_beam.timefunctions import TimeFunctionError, parse_formula

__all__ = ["MOTION_VARIABLES", "OBSTACLE_SHAPES", "Box", "ContactSettings", "Cylinder", "Motion",
           "Obstacle", "Plane", "Sphere", "check_clear_of_chain", "check_clear_of_rod", "distance",
           "section_circumradius", "section_distance", "section_extents", "section_parts",
           "segment_distance", "translated"]


def _vector(name: str, value, dim: int, where: str) -> tuple[float, ...]:
    if (not isinstance(value, (list, tuple)) or len(value) != dim
            or not all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in value)):
        raise ValueError(f"{where} {name} must be a list of {dim} numbers (the rod's "
                         f"{'x, y' if dim == 2 else 'x, y, z'} coordinates); got {value!r}")
    if not all(math.isfinite(c) for c in value):
        raise ValueError(f"{where} {name} must be finite; got {value!r}")
    return tuple(float(c) for c in value)


def _positive(name: str, value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
            math.isfinite(value) and value > 0):
        raise ValueError(f"{where} {name} must be a number > 0; got {value!r}")
    return float(value)


#: the variable of a moving obstacle's ``position`` formulas: the time in dynamics, the load
#: factor along the load path of statics (fe-beam static, fe-beam finger)
MOTION_VARIABLES = {"time": "t", "load": "load_factor"}


@dataclass(frozen=True)
class Motion:
    """A rigid translation of an obstacle from its configured place: ``velocity`` (numbers,
    [m/s]: c = velocity t) or ``position`` (numbers or formulas in ``variable``, "t" in dynamics
    or "load_factor" in statics, [m]: c = position(variable)); exactly one of them. The
    formulas are the safe ones of `fe_beam.timefunctions`."""

    velocity: tuple | None = None
    position: tuple | None = None
    variable: str = "t"
    dim: int = 2

    def __post_init__(self):
        where = "[[obstacles]]"
        if (self.velocity is None) == (self.position is None):
            raise ValueError(f"{where} give velocity or position (a motion), not both")
        if self.variable not in MOTION_VARIABLES.values():
            raise ValueError(f"{where} the motion's variable must be one of "
                             f"{', '.join(MOTION_VARIABLES.values())}; got {self.variable!r}")
        if self.velocity is not None:
            if self.variable != "t":
                raise ValueError(f"{where} velocity is a rate in time (fe-beam dynamic only); "
                                 f"along a load path give position = formulas in "
                                 f"{self.variable}")
            object.__setattr__(self, "velocity",
                               _vector("velocity", self.velocity, self.dim, where))
            return
        given = self.position
        names = "x, y" if self.dim == 2 else "x, y, z"
        if not isinstance(given, (list, tuple)) or len(given) != self.dim:
            raise ValueError(f"{where} position must be a list of {self.dim} numbers or "
                             f"formulas in {self.variable} (the translation's {names}); got "
                             f"{given!r}")
        parts = []
        for value in given:
            if isinstance(value, bool) or not isinstance(value, (int, float, str)):
                raise ValueError(f"{where} position entries must be numbers or formulas in "
                                 f"{self.variable}; got {value!r}")
            if isinstance(value, str):
                try:
                    parse_formula(value, variable=self.variable)
                except TimeFunctionError as error:
                    raise ValueError(f"{where} position: {error}") from None
            elif not math.isfinite(value):
                raise ValueError(f"{where} position must be finite; got {given!r}")
            parts.append(value if isinstance(value, str) else float(value))
        object.__setattr__(self, "position", tuple(parts))

    def _functions(self):
        cached = self.__dict__.get("_compiled")
        if cached is None:
            cached = tuple(parse_formula(v, variable=self.variable) if isinstance(v, str)
                           else (lambda _, c=v: c) for v in self.position)
            object.__setattr__(self, "_compiled", cached)
        return cached

    def translation(self, value: float) -> np.ndarray:
        """The translation c [m] at the time or load factor ``value``."""
        if self.velocity is not None:
            return np.array(self.velocity) * float(value)
        return np.array([f(float(value)) for f in self._functions()])


@dataclass(frozen=True)
class Obstacle:
    """Base of the shapes: ``name`` (label in outputs), ``dim`` (2: planar rod, 3: spatial),
    ``friction`` (Coulomb's mu), ``motion`` (a `Motion`, None: fixed)."""

    name: str = ""
    dim: int = 2
    friction: float = 0.0
    motion: Motion | None = None

    def translation(self, value: float) -> np.ndarray:
        """The obstacle's translation from its configured place at time / load factor
        ``value`` (zero when it does not move)."""
        if self.motion is None:
            return np.zeros(self.dim)
        return self.motion.translation(value)

    @property
    def where(self) -> str:
        return f"[[obstacles]] {self.name!r}:" if self.name else "[[obstacles]]"

    def __post_init__(self):
        if self.dim not in (2, 3):
            raise ValueError(f"{self.where} dimension must be 2 or 3; got {self.dim!r}")
        mu = self.friction
        if isinstance(mu, bool) or not isinstance(mu, (int, float)) or not (
                math.isfinite(mu) and mu >= 0):
            raise ValueError(f"{self.where} friction must be a number >= 0 (the Coulomb "
                             f"coefficient mu; 0: frictionless); got {mu!r}")
        object.__setattr__(self, "friction", float(mu))


@dataclass(frozen=True)
class Plane(Obstacle):
    """The half-space behind the plane through ``point`` with outward ``normal`` (normalised
    here; the rod lives on the side the normal points to)."""

    point: tuple = (0.0, 0.0)
    normal: tuple = (0.0, 1.0)
    shape: str = field(default="plane", init=False)

    def __post_init__(self):
        super().__post_init__()
        point = _vector("point", self.point, self.dim, self.where)
        normal = np.array(_vector("normal", self.normal, self.dim, self.where))
        size = float(np.linalg.norm(normal))
        if not size > 0:
            raise ValueError(f"{self.where} normal must not be the zero vector; got "
                             f"{list(self.normal)!r}")
        object.__setattr__(self, "point", point)
        object.__setattr__(self, "normal", tuple(float(c) for c in normal / size))


@dataclass(frozen=True)
class Sphere(Obstacle):
    """A ball of ``radius`` about ``center`` (a disc in the plane)."""

    center: tuple = (0.0, 0.0)
    radius: float = 1.0
    shape: str = field(default="sphere", init=False)

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "center", _vector("center", self.center, self.dim, self.where))
        object.__setattr__(self, "radius", _positive("radius", self.radius, self.where))


@dataclass(frozen=True)
class Cylinder(Obstacle):
    """A cylinder of ``radius`` whose axis passes through ``point`` (planar rods: along z, a
    disc in the plane; spatial rods: along ``axis``, infinite unless ``length`` is given)."""

    point: tuple = (0.0, 0.0)
    radius: float = 1.0
    axis: tuple | None = None
    length: float | None = None
    shape: str = field(default="cylinder", init=False)

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "point", _vector("point", self.point, self.dim, self.where))
        object.__setattr__(self, "radius", _positive("radius", self.radius, self.where))
        if self.dim == 2:
            if self.axis is not None and list(self.axis) not in ([0, 0, 1], [0, 0, -1]):
                raise ValueError(f"{self.where} a planar rod's cylinder has its axis along z "
                                 f"(leave axis out); got axis = {list(self.axis)!r}")
            if self.length is not None:
                raise ValueError(f"{self.where} length is for spatial rods only (a planar "
                                 "rod's cylinder is an infinite one, a disc in the plane)")
            object.__setattr__(self, "axis", None)
            return
        axis = np.array(_vector("axis", self.axis if self.axis is not None else (0, 0, 1), 3,
                                self.where))
        size = float(np.linalg.norm(axis))
        if not size > 0:
            raise ValueError(f"{self.where} axis must not be the zero vector")
        object.__setattr__(self, "axis", tuple(float(c) for c in axis / size))
        if self.length is not None:
            object.__setattr__(self, "length", _positive("length", self.length, self.where))


@dataclass(frozen=True)
class Box(Obstacle):
    """An axis-aligned box from ``min`` to ``max`` (corners; or give ``center`` and ``size``
    to `Box.from_center`)."""

    min: tuple = (0.0, 0.0)
    max: tuple = (1.0, 1.0)
    shape: str = field(default="box", init=False)

    def __post_init__(self):
        super().__post_init__()
        low = _vector("min", self.min, self.dim, self.where)
        high = _vector("max", self.max, self.dim, self.where)
        if not all(h > lo for lo, h in zip(low, high, strict=True)):
            raise ValueError(f"{self.where} max must exceed min in every component; got min = "
                             f"{list(low)!r}, max = {list(high)!r}")
        object.__setattr__(self, "min", low)
        object.__setattr__(self, "max", high)

    @classmethod
    def from_center(cls, center, size, name: str = "", dim: int = 2,
                    friction: float = 0.0, motion: Motion | None = None) -> Box:
        where = f"[[obstacles]] {name!r}:" if name else "[[obstacles]]"
        c = np.array(_vector("center", center, dim, where))
        s = np.array(_vector("size", size, dim, where))
        if not np.all(s > 0):
            raise ValueError(f"{where} size must be > 0 in every component; got {list(size)!r}")
        return cls(name=name, dim=dim, min=tuple(c - s / 2), max=tuple(c + s / 2),
                   friction=friction, motion=motion)

    @property
    def center(self) -> tuple:
        return tuple((lo + h) / 2 for lo, h in zip(self.min, self.max, strict=True))

    @property
    def half(self) -> tuple:
        return tuple((h - lo) / 2 for lo, h in zip(self.min, self.max, strict=True))

    def faces(self) -> list[tuple[tuple, tuple]]:
        """(point, outward normal) of each face plane."""
        faces = []
        for i in range(self.dim):
            for sign, corner in ((-1.0, self.min), (1.0, self.max)):
                normal = tuple(sign if j == i else 0.0 for j in range(self.dim))
                faces.append((tuple(corner), normal))
        return faces


OBSTACLE_SHAPES = {"plane": Plane, "cylinder": Cylinder, "sphere": Sphere, "box": Box}


#: the largest `ContactSettings.penalty`: k = 1e6 EI / h_e^4 is already stiffer than the rod
#: at any contact by orders of magnitude; beyond, the Newton systems lose their digits
MAX_PENALTY = 1e6


@dataclass(frozen=True)
class ContactSettings:
    """How contact is enforced (augmented Lagrangian with Uzawa updates: `fe_beam.fem.contact`).

    ``penetration_tolerance`` [m]: the largest penetration a converged step may keep (None: 1e-3
    x the smallest section height); ``penalty``: the augmentation stiffness k relative to the
    rod's element bending stiffness, k = penalty * EI_min / h_e^4 per unit length (h_e the
    smallest element); ``max_updates``: augmented-Lagrangian (Uzawa) updates per load step
    before the step is rejected; ``quadrature_degree``: the contact integral's Gauss rule (None:
    4 p, p the element degree: 2p + 1 points per element); ``max_active_change``: the largest
    share of an obstacle's contact points (the rod's contact quadrature points and its two
    ends) that may come into or out of contact in one accepted step of the rod (load step or
    arc-length point): a step beyond it is cut back (1: no limit); ``force_tolerance``: the
    largest estimated relative error of each obstacle's contact force a converged step may keep
    (the Uzawa updates go on until the multipliers, not only the penetration, have converged)."""

    penetration_tolerance: float | None = None
    penalty: float = 1.0
    max_updates: int = 50
    quadrature_degree: int | None = None
    max_active_change: float = 0.2
    force_tolerance: float = 1e-3

    def __post_init__(self):
        tol = self.penetration_tolerance
        if tol is not None and (isinstance(tol, bool) or not math.isfinite(tol) or tol <= 0):
            raise ValueError(f"[contact] penetration_tolerance must be a length > 0 [m]; got "
                             f"{tol!r}")
        if not (math.isfinite(self.penalty) and 0 < self.penalty <= MAX_PENALTY):
            raise ValueError(f"[contact] penalty must be > 0 and at most {MAX_PENALTY:g} (larger "
                             "values leave the Newton systems to round-off); got "
                             f"{self.penalty!r}")
        if not (isinstance(self.max_updates, int) and 1 <= self.max_updates <= 1000):
            raise ValueError(f"[contact] max_updates must be an integer from 1 to 1000; got "
                             f"{self.max_updates!r}")
        change = self.max_active_change
        if isinstance(change, bool) or not (isinstance(change, (int, float))
                                            and 0 < change <= 1):
            raise ValueError(f"[contact] max_active_change must be a share in (0, 1] of the "
                             f"contact points (1: no limit); got {change!r}")
        rtol = self.force_tolerance
        if isinstance(rtol, bool) or not (isinstance(rtol, (int, float)) and 0 < rtol <= 1):
            raise ValueError(f"[contact] force_tolerance must be a relative error in (0, 1] "
                             f"(1e-3: 0.1 %); got {rtol!r}")
        degree = self.quadrature_degree
        if degree is not None and not (isinstance(degree, int) and 1 <= degree <= 30):
            raise ValueError(f"[contact] quadrature_degree must be an integer from 1 to 30; got "
                             f"{degree!r}")

    def tolerance(self, section) -> float:
        """The penetration tolerance [m] for a rod of ``section``."""
        if self.penetration_tolerance is not None:
            return float(self.penetration_tolerance)
        return 1e-3 * thinnest_height(section)

    def check_tolerance(self, section) -> None:
        """ValueError when the penetration tolerance lets a converged step keep the rod more
        than a tenth of its thinnest section inside an obstacle (a contact that holds nothing)."""
        tol, limit = self.penetration_tolerance, 0.1 * thinnest_height(section)
        if tol is not None and tol > limit:
            raise ValueError(f"[contact] penetration_tolerance = {tol:.3g} m would let a "
                             f"converged step keep the rod that deep inside an obstacle, more "
                             f"than a tenth of its thinnest section; allowed: up to {limit:.3g} "
                             "m (default: 1e-3 of the section)")


def thinnest_height(section) -> float:
    """The smallest height of the rod's section over its length [m] (tapered: the thinner
    end)."""
    below, above = section_extents(section, np.array([0.0, 1.0]))
    return float(np.min(below + above))


def translated(obstacle: Obstacle, offset) -> Obstacle:
    """The obstacle moved rigidly by ``offset`` (its point, centre or corners), for the
    numpy checks and the outputs of a moving obstacle at one time / load factor."""
    c = np.asarray(offset, dtype=float)
    if not np.any(c):
        return obstacle
    shift = lambda p: tuple(float(a) for a in np.asarray(p) + c)  # noqa: E731
    if isinstance(obstacle, Sphere):
        return replace(obstacle, center=shift(obstacle.center))
    if isinstance(obstacle, Box):
        return replace(obstacle, min=shift(obstacle.min), max=shift(obstacle.max))
    return replace(obstacle, point=shift(obstacle.point))


# --- geometry (numpy; the same formulas in UFL live in fe_beam.fem.contact) ---------------------
def section_extents(section, s, dims: dict | None = None, dims_tip: dict | None = None):
    """(below, above) >= 0: how far the section reaches from the centreline toward -d and +d
    at s = x / L (floats, arrays or UFL: plain arithmetic). Rectangle, circle, tube: h/2 each
    side; t-section: its centroid's distances to the web's foot and the flange's top; custom:
    its ``h`` (or sqrt(12 I / A)) / 2 each side."""
    base = section.dims if dims is None else dims
    tip = section.dims_tip if dims_tip is None else dims_tip
    at = {n: v + (tip[n] - v) * s if n in tip else v for n, v in base.items()}
    if section.shape == "t-section":
        b, h, tf, tw = (at[n] for n in ("b", "h", "tf", "tw"))
        web, flange = tw * (h - tf), b * tf
        centroid = (web * (h - tf) / 2 + flange * (h - tf / 2)) / (web + flange)
        return centroid, h - centroid
    half = section.properties(s, dims, dims_tip).h / 2
    return half, half


def section_circumradius(section, s, dims: dict | None = None, dims_tip: dict | None = None):
    """The radius of the spatial rod's contact tube at s = x / L: the section's circumradius
    about the centroid (floats, arrays or UFL): circle and tube d/2, rectangle the
    half-diagonal sqrt(b^2 + h^2)/2, t-section the farthest corner, custom sqrt(y_half^2 +
    z_half^2) of its h and b (b defaulting to h)."""
    base = section.dims if dims is None else dims
    tip = section.dims_tip if dims_tip is None else dims_tip
    at = {n: v + (tip[n] - v) * s if n in tip else v for n, v in base.items()}
    if section.shape in ("circle", "tube"):
        return at["d"] / 2
    if section.shape == "rectangle":
        return (at["b"] ** 2 + at["h"] ** 2) ** 0.5 / 2
    if section.shape == "t-section":
        below, above = section_extents(section, s, dims, dims_tip)
        flange = ((at["b"] / 2) ** 2 + above**2) ** 0.5
        web = ((at["tw"] / 2) ** 2 + below**2) ** 0.5
        return (flange + web + abs(flange - web)) / 2
    h = section.properties(s, dims, dims_tip).h
    b = at.get("b", h)
    return ((h / 2) ** 2 + (b / 2) ** 2) ** 0.5


def section_parts(section, s, dims: dict | None = None, dims_tip: dict | None = None) -> dict:
    """The spatial rod's true section shape in its (d2, d3) plane at s = x / L (floats, arrays
    or UFL: plain arithmetic), about the centroid: ``{"disc": rho}`` (circle and tube: the
    outer circle, d/2) or ``{"rectangles": [(offset, half2, half3), ...]}``, a union of
    rectangles |eta2 - offset| <= half2 along d2 (the h direction), |eta3| <= half3 along d3
    (the b direction): a rectangle h x b; a t-section its web (tw wide, from the foot) and
    flange (b x tf, on the +d2 side, as `section_extents`); a custom section h x b (b
    defaulting to h)."""
    base = section.dims if dims is None else dims
    tip = section.dims_tip if dims_tip is None else dims_tip
    at = {n: v + (tip[n] - v) * s if n in tip else v for n, v in base.items()}
    if section.shape in ("circle", "tube"):
        return {"disc": at["d"] / 2}
    if section.shape == "rectangle":
        return {"rectangles": [(0.0 * at["h"], at["h"] / 2, at["b"] / 2)]}
    if section.shape == "t-section":
        below, _ = section_extents(section, s, dims, dims_tip)
        h, tf = at["h"], at["tf"]
        web = ((h - tf) / 2 - below, (h - tf) / 2, at["tw"] / 2)
        flange = (h - tf / 2 - below, tf / 2, at["b"] / 2)
        return {"rectangles": [web, flange]}
    h = section.properties(s, dims, dims_tip).h
    return {"rectangles": [(0.0 * h, h / 2, at.get("b", h) / 2)]}


def describe_section(section, s: float = 0.0) -> str:
    """The spatial contact surface's section in words (the refusal messages)."""
    parts = section_parts(section, s)
    if "disc" in parts:
        return f"a disc of radius {float(parts['disc']):.4g} m"
    shown = [f"{2 * float(a3):.4g} x {2 * float(a2):.4g} m (b x h)"
             for _, a2, a3 in parts["rectangles"]]
    return "the rectangle " + " and ".join(shown) + " in the section plane"


def _frames(d1, d2, d3, n: int):
    return [np.broadcast_to(np.asarray(d, dtype=float), (n, 3)) for d in (d1, d2, d3)]


def _rectangle_line_distance(w, u, v, a2, a3):
    """min over |s| <= a2, |t| <= a3 of |w + s u + t v| (w, u, v: (n, k) vectors; exact: the
    unconstrained minimiser when inside the rectangle, else the best of the four edges)."""
    uu, vv, uv = (np.sum(u * u, axis=1), np.sum(v * v, axis=1), np.sum(u * v, axis=1))
    wu, wv = np.sum(w * u, axis=1), np.sum(w * v, axis=1)
    best = np.full(len(w), np.inf)
    for sign in (-1.0, 1.0):
        s = sign * a2
        t = np.clip(-(wv + s * uv) / np.maximum(vv, 1e-300), -a3, a3)
        best = np.minimum(best, np.linalg.norm(w + s[:, None] * u + t[:, None] * v, axis=1))
        t = sign * a3
        s = np.clip(-(wu + t * uv) / np.maximum(uu, 1e-300), -a2, a2)
        best = np.minimum(best, np.linalg.norm(w + s[:, None] * u + t[:, None] * v, axis=1))
    det = uu * vv - uv**2
    ok = det > 1e-12 * np.maximum(uu * vv, 1e-300)
    safe = np.where(ok, det, 1.0)
    s0, t0 = (-wu * vv + wv * uv) / safe, (-wv * uu + wu * uv) / safe
    inside = ok & (np.abs(s0) <= a2) & (np.abs(t0) <= a3)
    inner = np.linalg.norm(w + s0[:, None] * u + t0[:, None] * v, axis=1)
    return np.where(inside, np.minimum(inner, best), best)


def section_distance(obstacle: Obstacle, r, d1, d2, d3, parts: dict) -> np.ndarray:
    """Signed distance (numpy) of the spatial rod's section at the centreline points r (n, 3)
    with directors d1 (the section normal), d2, d3 ((n, 3) or (3,)) and its shape ``parts``
    (`section_parts`, entries floats or (n,) arrays) to the obstacle: the minimum over the
    section of the points' signed distances. `fe_beam.fem.contact.section_gap` is the UFL
    twin. Plane: exact (the support function: the nearest corner, or the disc's rim point);
    sphere: exact (the section point nearest the centre); infinite cylinder: exact for
    rectangles (the nearest point of the rectangle to the axis line), for a disc its
    tube (a lower bound of the distance, exact when the axis is along d1); box
    and finite cylinder: the largest of the gaps to the half-spaces (faces, caps) and the
    lateral surface (exact on the faces, below the true distance near edges: conservative).
    The section is flat: at the rod's ends these are the end faces."""
    r = np.atleast_2d(np.asarray(r, dtype=float))
    n = len(r)
    d1, d2, d3 = _frames(d1, d2, d3, n)
    if isinstance(obstacle, Plane):
        return _plane_section_distance(np.array(obstacle.point), np.array(obstacle.normal),
                                       r, d1, d2, d3, parts)
    if isinstance(obstacle, Box):
        gaps = [_plane_section_distance(np.array(p), np.array(m), r, d1, d2, d3, parts)
                for p, m in obstacle.faces()]
        return np.max(gaps, axis=0)
    if isinstance(obstacle, Sphere):
        c = np.array(obstacle.center)
        if "disc" in parts:
            q = c - r
            q = q - np.sum(q * d1, axis=1)[:, None] * d1
            size = np.linalg.norm(q, axis=1)
            scale = np.minimum(1.0, np.asarray(parts["disc"]) / np.maximum(size, 1e-300))
            return np.linalg.norm(c - r - scale[:, None] * q, axis=1) - obstacle.radius
        gaps = []
        for offset, a2, a3 in parts["rectangles"]:
            q = c - r - np.asarray(offset)[..., None] * d2
            s = np.clip(np.sum(q * d2, axis=1), -a2, a2)
            t = np.clip(np.sum(q * d3, axis=1), -a3, a3)
            gaps.append(np.linalg.norm(q - s[:, None] * d2 - t[:, None] * d3, axis=1))
        return np.min(gaps, axis=0) - obstacle.radius
    if isinstance(obstacle, Cylinder):
        a = np.array(obstacle.axis)
        project = lambda x: x - np.outer(x @ a, a)  # noqa: E731
        p = np.array(obstacle.point)
        if "disc" in parts:
            lateral = (np.linalg.norm(project(r - p), axis=1) - np.asarray(parts["disc"])
                       - obstacle.radius)
        else:
            lateral = np.min([_rectangle_line_distance(
                project(r + np.asarray(offset)[..., None] * d2 - p), project(d2), project(d3),
                np.broadcast_to(a2, (n,)), np.broadcast_to(a3, (n,))) for offset, a2, a3
                in parts["rectangles"]], axis=0) - obstacle.radius
        if obstacle.length is None:
            return lateral
        caps = [_plane_section_distance(p + sign * obstacle.length / 2 * a, sign * a,
                                        r, d1, d2, d3, parts) for sign in (-1.0, 1.0)]
        return np.max([lateral] + caps, axis=0)
    raise TypeError(f"not an obstacle: {obstacle!r}")


def _plane_section_distance(point, normal, r, d1, d2, d3, parts):
    base = (r - point) @ normal
    n2, n3 = d2 @ normal, d3 @ normal
    if "disc" in parts:
        return base - np.asarray(parts["disc"]) * np.hypot(n2, n3)
    return np.min([base + np.asarray(offset) * n2 - np.asarray(a2) * np.abs(n2)
                   - np.asarray(a3) * np.abs(n3) for offset, a2, a3 in parts["rectangles"]],
                  axis=0)



def distance(obstacle: Obstacle, points: np.ndarray) -> np.ndarray:
    """Signed distance of points (n, dim) to the obstacle (>= 0 outside)."""
    p = np.atleast_2d(np.asarray(points, dtype=float))
    if isinstance(obstacle, Plane):
        return (p - np.array(obstacle.point)) @ np.array(obstacle.normal)
    if isinstance(obstacle, Sphere):
        return np.linalg.norm(p - np.array(obstacle.center), axis=1) - obstacle.radius
    if isinstance(obstacle, Cylinder):
        rel = p - np.array(obstacle.point)
        if obstacle.dim == 3:
            axis = np.array(obstacle.axis)
            axial = rel @ axis
            rel = rel - np.outer(axial, axis)
            if obstacle.length is not None:  # a solid cylinder centred on its point
                q_r = np.linalg.norm(rel, axis=1) - obstacle.radius
                q_a = np.abs(axial) - obstacle.length / 2
                return (np.minimum(np.maximum(q_r, q_a), 0.0)
                        + np.hypot(np.maximum(q_r, 0.0), np.maximum(q_a, 0.0)))
        return np.linalg.norm(rel, axis=1) - obstacle.radius
    if isinstance(obstacle, Box):
        rel = np.abs(p - np.array(obstacle.center)) - np.array(obstacle.half)
        return rel.max(axis=1)
    raise TypeError(f"not an obstacle: {obstacle!r}")


def segment_distance(obstacle: Obstacle, r: np.ndarray, d: np.ndarray, below, above
                     ) -> np.ndarray:
    """Signed distance of the planar section, the segment r + eta d, eta in [-below, above],
    to the obstacle (the centreline offset by the section's extent toward the obstacle).
    Plane: exact (the nearer end); disc: exact (the segment's point nearest the centre);
    box: the largest face-plane distance of the segment (see the module)."""
    r, d = np.atleast_2d(r), np.atleast_2d(d)
    below, above = np.broadcast_to(below, len(r)), np.broadcast_to(above, len(r))
    if isinstance(obstacle, Plane):
        n = np.array(obstacle.normal)
        dn = d @ n
        return (r - np.array(obstacle.point)) @ n + np.minimum(above * dn, -below * dn)
    if isinstance(obstacle, (Sphere, Cylinder)):
        centre = np.array(obstacle.center if isinstance(obstacle, Sphere) else obstacle.point)
        eta = np.clip(np.sum((centre - r) * d, axis=1), -below, above)
        return distance(obstacle, r + eta[:, None] * d)
    if isinstance(obstacle, Box):
        gaps = []
        for point, normal in obstacle.faces():
            face = Plane(point=point, normal=normal, dim=obstacle.dim)
            gaps.append(segment_distance(face, r, d, below, above))
        return np.max(gaps, axis=0)
    raise TypeError(f"not an obstacle: {obstacle!r}")


def check_clear_of_rod(obstacle: Obstacle, section, length: float, samples: int = 2001) -> None:
    """ConfigError when the obstacle touches or intersects the undeformed rod (the surface:
    the straight centreline (x, 0) with the section's true shape, sampled at ``samples``
    stations along x: planar the section segment, spatial `section_distance` with the flat end
    faces)."""
    x = np.linspace(0.0, length, samples)
    r = np.column_stack([x, np.zeros_like(x)] + ([np.zeros_like(x)] if obstacle.dim == 3
                                                  else []))
    if obstacle.dim == 3:  # the section in the reference frame d1, d2, d3 = x, y, z
        e = np.eye(3)
        gap = section_distance(obstacle, r, e[0], e[1], e[2], section_parts(section, x / length))
    else:
        d = np.zeros_like(r)
        d[:, 1] = 1.0
        below, above = section_extents(section, x / length)
        gap = segment_distance(obstacle, r, d, below, above)
    worst = int(np.argmin(gap))
    if not gap[worst] > 0:
        # the section's extent the check used, at the station that touches
        def at(value) -> float:
            return float(np.broadcast_to(np.asarray(value, dtype=float), x.shape)[worst])

        extent = (f"the section taken as {describe_section(section, x[worst] / length)}, "
                  "with flat end faces" if obstacle.dim == 3 else
                  f"the section reaching from y = {-at(below):.4g} to {at(above):.4g} m")
        depth = -float(gap[worst])
        where = (f"it touches the rod's surface at x = {x[worst]:.4g} m" if depth <= 0 else
                 f"the rod's surface is {depth:.4g} m inside the obstacle at x = {x[worst]:.4g} m")
        verb = "touches" if depth <= 0 else "intersects"
        raise ConfigError(
            f"{obstacle.where} the {obstacle.shape} {verb} the undeformed rod ({where}; "
            f"{extent}); move it clear of the rod (the rod starts straight along x with its "
            "section centred on the x axis)")


def check_clear_of_chain(obstacle: Obstacle, structure, section, samples: int = 401) -> None:
    """ConfigError when the obstacle touches or intersects a chain of rods in its reference
    geometry (`fe_beam.model.structure.Structure`): each rod's straight axis from its start
    along its direction, its section (its own dimensions or ``section``'s) turned with the rod
    (planar: the director at the rod's angle; spatial: its frame d1, d2, d3), sampled at
    ``samples`` stations per rod."""
    for rod in structure.rods:
        x = np.linspace(0.0, rod.length, samples)
        dims = dict(rod.section) if rod.section else None
        r = np.asarray(rod.start)[None, :] + x[:, None] * np.asarray(rod.direction)[None, :]
        if obstacle.dim == 3:
            d1, d2, d3 = rod.frame
            gap = section_distance(obstacle, r, d1, d2, d3,
                                   section_parts(section, x / rod.length, dims))
        else:
            c, s = rod.direction
            d = np.broadcast_to(np.array([-s, c]), r.shape)
            below, above = section_extents(section, x / rod.length, dims)
            gap = segment_distance(obstacle, r, d, below, above)
        worst = int(np.argmin(gap))
        if not gap[worst] > 0:
            depth = -float(gap[worst])
            where = (f"it touches the surface of rod '{rod.name}'" if depth <= 0 else
                     f"the surface of rod '{rod.name}' is {depth:.4g} m inside it")
            raise ConfigError(
                f"{obstacle.where} the {obstacle.shape} "
                f"{'touches' if depth <= 0 else 'intersects'} the undeformed structure ({where}"
                f" at x = {x[worst]:.4g} m from the rod's start, the section turned with the "
                "rod); move it clear of the rods")

"""The spatial rod as data (docs/theory.md, Spatial rods): supports, loads and the
`SpatialRodModel`, and its two closed-form laws, dataclasses with the energy as a method.

Conventions (docs/theory.md, Spatial rods): the reference centreline runs along e1 = x; the
section's ``h`` along y, ``b`` along z. R(s) maps body to world; its columns are the directors
d1 (section normal), d2 (the h direction), d3 (the b direction). With r the deformed centreline

    v = R^T r'          (v - e1: the stretch and the two shears)
    R' = R u^           (u: torsion, curvature about d2, curvature about d3)

and the strain of the curvature is u - u0, u0 = ``initial_curvature`` = [k_twist, k_y, k_z].
In the plane (a rotation theta about z) u3 = theta' = kappa, v1 = 1 + e, v2 = g: every law
reduces to the planar one (`fe_beam.model.laws`).

Pure Python (the laws' arithmetic works on floats and UFL alike; no import of either).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from fe_beam.model.beam import (
    Discretisation,
    ModelOptions,
    _finite,
    _rank,
    check_rod,
    point_rows,
)
from fe_beam.model.materials import Material
from fe_beam.model.sections import MOMENT_ORDERS, Section
from fe_beam.timefunctions import Profile, TimeFunctionError, parse_profile

__all__ = [
    "SPATIAL_COMPONENTS",
    "SPATIAL_CONSTRAINED",
    "SPATIAL_LAWS",
    "SPATIAL_SUPPORT_KINDS",
    "SpatialLoads",
    "SpatialNonStandard",
    "SpatialReissner",
    "SpatialRodModel",
    "SpatialStrains",
    "SpatialSupports",
]

#: the unknowns at a node: the centreline displacement and the rotation vector
SPATIAL_COMPONENTS = ("u", "v", "w", "theta_x", "theta_y", "theta_z")
ROTATIONS = ("theta_x", "theta_y", "theta_z")
SPATIAL_SUPPORT_KINDS = {
    "clamped": SPATIAL_COMPONENTS,
    # a pin holds the position and the twist (a fork support): else the rod spins about its axis
    "pinned": ("u", "v", "w", "theta_x"),
    "roller": ("v", "w"),
    "free": (),
}
#: the constrained strains (multiplier fields) of each constraint
SPATIAL_CONSTRAINED = {
    "none": (),
    "inextensible": ("eps",),
    "unshearable": ("g2", "g3"),
    "inextensible-unshearable": ("eps", "g2", "g3"),
}
#: the laws the spatial rod has (the hyperelastic section law is planar only for now)
SPATIAL_LAWS = ("nonstandard", "reissner")


@dataclass(frozen=True)
class SpatialStrains:
    """v = R^T r' and the curvature strain u - u0 (3-tuples of floats or UFL scalars)."""

    v: tuple
    u: tuple

    @property
    def eps(self):
        """Green-Lagrange axial strain (|v|^2 - 1) / 2 (= (|r'|^2 - 1) / 2)."""
        v1, v2, v3 = self.v
        return (v1**2 + v2**2 + v3**2 - 1) / 2

    def constrained(self, name: str):
        """The strain a constraint holds at zero: eps, g2 = v2 or g3 = v3."""
        return {"eps": self.eps, "g2": self.v[1], "g3": self.v[2]}[name]


@dataclass(frozen=True)
class SpatialReissner:
    """The Simo-Reissner law: n_b = diag(EA, kGA, kGA)(v - e1), m_b = diag(GJ, EI_y, EI_z) u.

    In the plane: 1/2 EA e^2 + 1/2 k GA g^2 + 1/2 EI kappa^2, the planar Reissner law."""

    EA: Any
    GA: Any  # with the shear correction
    GJ: Any
    EIy: Any
    EIz: Any

    def energy(self, s: SpatialStrains):
        v1, v2, v3 = s.v
        u1, u2, u3 = s.u
        return (self.EA * (v1 - 1) ** 2 + self.GA * (v2**2 + v3**2)
                + self.GJ * u1**2 + self.EIy * u2**2 + self.EIz * u3**2) / 2


@dataclass(frozen=True)
class SpatialNonStandard:
    """The non-standard law in space: the Saint-Venant-Kirchhoff fibre energy
    1/2 E E11^2 + 2 G (E12^2 + E13^2) integrated over the section (docs/theory.md).

    A fibre at (y, z) of the section has the body-frame tangent a = v + u x (0, y, z), so

        E11 = (|a|^2 - 1) / 2 = eps + y (v3 u1 - v1 u3) + z (v1 u2 - v2 u1)
              + 1/2 (u2 z - u3 y)^2 + 1/2 u1^2 (y^2 + z^2)

    a polynomial of degree 2 in (y, z) whose square integrates to the section moments
    ``moments[(a, b)]`` = int y^a z^b dA (a + b <= 4). The shears 2 E12 = v2 - u1 z,
    2 E13 = v3 + u1 y integrate to G/2 (A (v2^2 + v3^2) + I_p u1^2); the warping of the section
    replaces the polar moment I_p by the Saint-Venant torsion constant J. In the plane
    (u = (0, 0, kappa), v = (1 + e, g, 0)) this is exactly the planar non-standard energy
    (E11 = eps + eta kappa (1 + e) + eta^2 kappa^2 / 2 with eta = -y)."""

    E: Any
    G: Any
    moments: dict
    J: Any

    def fibre_strain_coefficients(self, s: SpatialStrains) -> dict:
        """E11 = sum_(a, b) c[(a, b)] y^a z^b."""
        v1, v2, v3 = s.v
        u1, u2, u3 = s.u
        return {(0, 0): s.eps, (1, 0): v3 * u1 - v1 * u3, (0, 1): v1 * u2 - v2 * u1,
                (2, 0): (u3**2 + u1**2) / 2, (1, 1): -u2 * u3, (0, 2): (u2**2 + u1**2) / 2}

    def energy(self, s: SpatialStrains):
        c = self.fibre_strain_coefficients(s)
        keys = list(c)
        axial = 0
        for i, p in enumerate(keys):
            for q in keys[i:]:
                moment = self.moments[(p[0] + q[0], p[1] + q[1])]
                if isinstance(moment, (int, float)) and moment == 0:
                    continue  # a symmetric section's odd moments: no term
                axial = axial + (1 if p == q else 2) * c[p] * c[q] * moment
        _, v2, v3 = s.v
        u1 = s.u[0]
        shear = self.moments[(0, 0)] * (v2**2 + v3**2) + self.J * u1**2
        return self.E * axial / 2 + self.G * shear / 2


assert all(key in MOMENT_ORDERS for key in [(a + c, b + d) for a, b in MOMENT_ORDERS
                                             for c, d in MOMENT_ORDERS if a + b + c + d <= 4])


def spatial_support_components(spec, key: str) -> tuple[str, ...]:
    """Fixed components of a spatial support: a kind name, or a list of components of
    u, v, w, theta_x, theta_y, theta_z ("theta" = all three rotations)."""
    if isinstance(spec, str):
        if spec not in SPATIAL_SUPPORT_KINDS:
            raise ValueError(
                f"supports.{key} must be one of {', '.join(SPATIAL_SUPPORT_KINDS)} or a list of "
                f"components from {list(SPATIAL_COMPONENTS)} (\"theta\": all three rotations); "
                f"got {spec!r}")
        return SPATIAL_SUPPORT_KINDS[spec]
    if isinstance(spec, (list, tuple)) and all(isinstance(c, str) for c in spec):
        names = []
        for c in spec:
            names += list(ROTATIONS) if c == "theta" else [c]
        unknown = [c for c in names if c not in SPATIAL_COMPONENTS]
        if unknown or len(set(names)) != len(names):
            raise ValueError(
                f"supports.{key}: components must be distinct names from "
                f"{list(SPATIAL_COMPONENTS)} (or \"theta\" for all three rotations); got "
                f"{list(spec)}")
        return tuple(c for c in SPATIAL_COMPONENTS if c in names)
    raise ValueError(f"supports.{key} must be a support name or a list of components, got "
                     f"{spec!r}")


@dataclass(frozen=True)
class SpatialSupports:
    """End conditions of a spatial rod at x = 0 and x = L (prescribed values of fixed
    components are scaled by the load factor; rotations are rotation-vector components)."""

    x0: str | tuple = "clamped"
    xL: str | tuple = "free"
    prescribed_x0: dict = field(default_factory=dict)
    prescribed_xL: dict = field(default_factory=dict)

    def __post_init__(self):
        for end in ("x0", "xL"):
            fixed = self.fixed(end)
            for name, value in getattr(self, f"prescribed_{end}").items():
                if name not in fixed:
                    raise ValueError(
                        f"loads.prescribed_{end}.{name}: only fixed components can be prescribed "
                        f"(supports.{end} fixes {list(fixed) or 'nothing'})")
                if isinstance(value, bool) or not isinstance(value, (int, float)):
                    raise ValueError(f"loads.prescribed_{end}.{name} must be a number, got "
                                     f"{value!r}")

    def fixed(self, end: str) -> tuple[str, ...]:
        return spatial_support_components(getattr(self, end), end)

    def rigid_motions(self) -> list[str]:
        """The rigid motions the supports leave free: a small rigid motion is
        d = a + w x X, theta = w (X = (x, 0, 0)); each fixed component at x = 0 or x = 1 is
        one equation on (a, w)."""
        rows = {"u": lambda x: (1, 0, 0, 0, 0, 0), "v": lambda x: (0, 1, 0, 0, 0, x),
                "w": lambda x: (0, 0, 1, 0, -x, 0), "theta_x": lambda x: (0, 0, 0, 1, 0, 0),
                "theta_y": lambda x: (0, 0, 0, 0, 1, 0), "theta_z": lambda x: (0, 0, 0, 0, 0, 1)}
        equations = [rows[c](x) for end, x in (("x0", 0.0), ("xL", 1.0)) for c in self.fixed(end)]
        if equations and _rank(equations) == 6:
            return []
        free = []
        if not any(row[0] for row in equations):
            free.append("translation along x (fix u at one end)")
        if not any(row[3] for row in equations):
            free.append("rotation about the rod's axis (fix theta_x at one end, e.g. "
                        "\"pinned\" or \"clamped\")")
        if _rank([(r[1], r[5]) for r in equations]) < 2:
            free.append("translation along y or rotation about z (fix v at both ends, or v and "
                        "theta_z at one end)")
        if _rank([(r[2], r[4]) for r in equations]) < 2:
            free.append("translation along z or rotation about y (fix w at both ends, or w and "
                        "theta_y at one end)")
        return free or ["a rigid motion (the supports' equations are dependent)"]


def _vector(name: str, value, scalar_axis: int | None = None) -> tuple[float, float, float]:
    """A 3-vector from [x, y, z], a planar pair [x, y] (z = 0) or, for moments, a number (the
    planar moment about z)."""
    if scalar_axis is not None and isinstance(value, (int, float)) and not isinstance(value, bool):
        if not _finite(value):
            raise ValueError(f"loads.{name} must be finite, got {value!r}")
        vector = [0.0, 0.0, 0.0]
        vector[scalar_axis] = float(value)
        return tuple(vector)
    ok = (isinstance(value, (list, tuple)) and len(value) in (2, 3)
          and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in value)
          and all(_finite(c) for c in value))
    if not ok:
        what = " (or a number: the moment about z)" if scalar_axis is not None else ""
        raise ValueError(f"loads.{name} must be a vector [x, y, z] of numbers (a planar pair "
                         f"[x, y] means z = 0){what}; got {value!r}")
    return tuple(float(c) for c in value) + (0.0,) * (3 - len(value))


@dataclass(frozen=True)
class SpatialLoads:
    """Loads at load factor 1 (all scaled by the load factor).

    ``tip_force`` and ``tip_moment`` are dead (world components; a dead moment's equilibrium is
    m(L) = M, and its work is not a potential: the tangent is not symmetric) unless
    ``follower``, in which case both are given in the tip frame (d1, d2, d3) and turn with it.
    ``distributed`` is a dead force per unit reference length, ``gravity`` an acceleration.
    ``point_forces``: ((x, Px, Py, Pz), ...). ``point_moments``: dead moments ((x, Mx, My, Mz),
    ...) in world axes at 0 <= x <= L (virtual work M . T(theta) dtheta, as the dead tip
    moment). ``end_displacement`` (3) and ``end_rotation``
    (a rotation vector, 3): the end x = L moved and turned by the load factor times them."""

    tip_force: tuple = (0.0, 0.0, 0.0)
    tip_moment: tuple = (0.0, 0.0, 0.0)
    follower: bool = False
    distributed: tuple = (0.0, 0.0, 0.0)
    gravity: tuple = (0.0, 0.0, 0.0)
    point_forces: tuple = ()
    point_moments: tuple = ()
    end_displacement: tuple | None = None
    end_rotation: tuple | None = None

    def __post_init__(self):
        for name in ("tip_force", "distributed", "gravity"):
            object.__setattr__(self, name, _vector(name, getattr(self, name)))
        object.__setattr__(self, "tip_moment", _vector("tip_moment", self.tip_moment, 2))
        if not isinstance(self.follower, bool):
            raise ValueError(f"loads.follower must be true or false, got {self.follower!r}")
        forces = []
        if not isinstance(self.point_forces, (list, tuple)):
            raise ValueError(f"loads.point_forces must be a list of [x, Px, Py, Pz], got "
                             f"{self.point_forces!r}")
        for index, entry in enumerate(self.point_forces):
            ok = (isinstance(entry, (list, tuple)) and len(entry) in (3, 4)
                  and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in entry)
                  and all(_finite(c) for c in entry))
            if not ok:
                raise ValueError(f"loads.point_forces[{index}] must be [x, Px, Py, Pz] (the "
                                 f"position [m] and the force [N]); got {entry!r}")
            forces.append(tuple(float(c) for c in entry) + (0.0,) * (4 - len(entry)))
        object.__setattr__(self, "point_forces", tuple(forces))
        object.__setattr__(self, "point_moments", point_rows(
            "point_moments", self.point_moments, 4, "[x, Mx, My, Mz] (the position [m] and the "
            "moment in world axes [N m])", "[x, M] is the planar form: a spatial rod takes the "
            "three components"))
        if self.end_displacement is not None:
            object.__setattr__(self, "end_displacement",
                               _vector("end_displacement", self.end_displacement))
        if self.end_rotation is not None:
            object.__setattr__(self, "end_rotation",
                               _vector("end_rotation", self.end_rotation, 2))
        if self.end_displacement is not None and (self.follower or any(self.tip_force)):
            raise ValueError("loads.end_displacement prescribes the tip's position: "
                             "loads.tip_force on it would be taken by the support; give one or "
                             "the other")
        if self.end_rotation is not None and any(self.tip_moment):
            raise ValueError("loads.end_rotation prescribes the tip rotation: loads.tip_moment "
                             "would be taken by the support; give one or the other")

    def end_motion(self) -> dict:
        motion = {}
        if self.end_displacement is not None:
            motion.update(zip(("u", "v", "w"), self.end_displacement, strict=True))
        if self.end_rotation is not None:
            motion.update(zip(ROTATIONS, self.end_rotation, strict=True))
        return motion


def _curvatures(value, length: float) -> tuple[Profile, Profile, Profile]:
    """[k_twist, k_y, k_z]: numbers or formulas of s (and L)."""
    if value is None:
        value = [0.0, 0.0, 0.0]
    if not (isinstance(value, (list, tuple)) and len(value) == 3):
        raise ValueError(f"beam.initial_curvature must be [k_twist, k_y, k_z] (numbers [1/m] "
                         f"or formulas of s and L); got {value!r}")
    profiles = []
    for name, item in zip(("k_twist", "k_y", "k_z"), value, strict=True):
        if isinstance(item, Profile):  # parsed already (dataclasses.replace of a model)
            profiles.append(item)
            continue
        if isinstance(item, bool) or not isinstance(item, (int, float, str)):
            raise ValueError(f"beam.initial_curvature {name} must be a number or a formula of s "
                             f"and L; got {item!r}")
        try:
            profile = parse_profile(item, {"L": length})
            for s in (0.0, length / 2, length):
                profile(s)
        except TimeFunctionError as error:
            raise ValueError(f"beam.initial_curvature {name}: {error}") from None
        profiles.append(profile)
    return tuple(profiles)


@dataclass(frozen=True)
class SpatialRodModel:
    """Everything that defines a spatial rod problem (``[model] kinematics = "spatial"``)."""

    length: float
    section: Section
    material: Material
    options: ModelOptions = field(default_factory=ModelOptions)
    mesh: Discretisation = field(default_factory=Discretisation)
    supports: SpatialSupports = field(default_factory=SpatialSupports)
    loads: SpatialLoads = field(default_factory=SpatialLoads)
    initial_curvature: Any = None
    #: a spatial serial chain of rods (`fe_beam.model.structure.Structure`) laid along
    #: 0 <= x <= length (None: a single straight rod along x)
    structure: Any = None

    kinematics = "spatial"

    def __post_init__(self):
        check_rod(self.length, self.material, self.loads)
        if self.options.law not in SPATIAL_LAWS:
            raise ValueError(f"[model] law = {self.options.law!r} is not available for "
                             f"kinematics = \"spatial\" yet (use {' or '.join(SPATIAL_LAWS)})")
        object.__setattr__(self, "initial_curvature",
                           _curvatures(self.initial_curvature, self.length))
        motion = self.loads.end_motion()
        if motion:
            supports = self.supports
            clash = [n for n in motion if n in supports.prescribed_xL]
            if clash:
                raise ValueError(f"loads.prescribed_xL.{clash[0]} and the end motion both "
                                 "prescribe the same component at x = L; give it once")
            fixed = supports.fixed("xL")
            components = tuple(c for c in SPATIAL_COMPONENTS if c in fixed or c in motion)
            object.__setattr__(self, "supports", SpatialSupports(
                supports.x0, components, dict(supports.prescribed_x0),
                dict(supports.prescribed_xL) | motion))
        self.section.spatial_properties()  # custom sections: I_y and J given

    @property
    def curved(self) -> bool:
        return any(not (p.is_constant and p.constant == 0) for p in self.initial_curvature)

    def stiffness_at(self, s: float = 0.0) -> dict:
        """Section stiffnesses (floats) at s = x / L."""
        p = self.section.spatial_properties(s)
        E, G = self.material.E, self.material.shear_modulus
        return {"EA": E * p.A, "GA": G * p.A, "GJ": G * p.J, "EIy": E * p.Iy, "EIz": E * p.Iz}


def rotation_matrix(vector) -> list[list[float]]:
    """R = exp(theta^) of a rotation vector (floats; Rodrigues' formula)."""
    tx, ty, tz = (float(c) for c in vector)
    t = math.sqrt(tx * tx + ty * ty + tz * tz)
    a = math.sin(t) / t if t > 1e-8 else 1 - t * t / 6
    b = (1 - math.cos(t)) / t**2 if t > 1e-4 else 0.5 - t * t / 24
    k = [[0.0, -tz, ty], [tz, 0.0, -tx], [-ty, tx, 0.0]]
    k2 = [[sum(k[i][m] * k[m][j] for m in range(3)) for j in range(3)] for i in range(3)]
    return [[(1.0 if i == j else 0.0) + a * k[i][j] + b * k2[i][j] for j in range(3)]
            for i in range(3)]

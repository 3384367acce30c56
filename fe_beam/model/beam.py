"""The planar beam as data: the model options (law, constraint), discretisation, supports,
loads and the `BeamModel` that holds them with the section and the material.

Pure Python: no numpy, no finite-element code. `fe_beam.fem.rod.BeamProblem` turns a
`BeamModel` into forms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from fe_beam.model.fibre import FibreLaw
from fe_beam.model.laws import CONSTRAINTS, DEFAULT_SECTION_POINTS, LAWS, MAX_SECTION_POINTS
from fe_beam.model.materials import Material
from fe_beam.model.sections import Section

__all__ = [
    "COMPONENTS",
    "SUPPORT_KINDS",
    "BeamModel",
    "Discretisation",
    "Loads",
    "ModelOptions",
    "Supports",
    "support_components",
]

COMPONENTS = ("u", "v", "theta")
SUPPORT_KINDS = {
    "clamped": ("u", "v", "theta"),
    "pinned": ("u", "v"),
    "roller": ("v",),
    "free": (),
}


@dataclass(frozen=True)
class ModelOptions:
    """Constitutive law, kinematic constraint and (Reissner law only) shear correction k.

    ``law = "hyperelastic"``: ``hyperelastic`` is the 3D law (a
    `fe_beam.model.hyperelastic.HyperelasticLaw`) whose uniaxial fibre energy is integrated over
    the section with ``section_points`` Gauss points per section part (None: the default,
    `fe_beam.fem.section_laws.DEFAULT_SECTION_POINTS`); both are ignored by the other laws.
    """

    law: str = "nonstandard"
    constraint: str = "none"
    shear_correction: float = 1.0
    hyperelastic: Any = None
    section_points: int | None = None

    def __post_init__(self):
        if self.law not in LAWS:
            raise ValueError(f"model.law must be one of {', '.join(LAWS)}; got {self.law!r}")
        if self.law == "hyperelastic" and self.hyperelastic is None:
            raise ValueError("model.law = \"hyperelastic\" needs its 3D material law")
        points = self.section_points
        if points is not None and (not isinstance(points, int) or isinstance(points, bool)
                                   or not 1 <= points <= MAX_SECTION_POINTS):
            raise ValueError(f"[model] section_points must be an integer from 1 to "
                             f"{MAX_SECTION_POINTS}; got {points!r}")
        if self.constraint not in CONSTRAINTS:
            raise ValueError(
                f"model.constraint must be one of {', '.join(CONSTRAINTS)}; got {self.constraint!r}"
            )
        if not (isinstance(self.shear_correction, (int, float)) and 0 < self.shear_correction <= 2):
            raise ValueError(
                f"model.shear_correction must be a number in (0, 2], got {self.shear_correction!r}"
            )

    @property
    def points(self) -> int:
        """Gauss points per section part of the hyperelastic law (the default if not given)."""
        return self.section_points or DEFAULT_SECTION_POINTS


@dataclass(frozen=True)
class Discretisation:
    """Number of elements and the polynomial degree (1 or 2) of u, v, theta."""

    elements: int = 50
    degree: int = 2

    def __post_init__(self):
        if (
            not isinstance(self.elements, int)
            or isinstance(self.elements, bool)
            or self.elements < 1
        ):
            raise ValueError(f"mesh.elements must be an integer >= 1, got {self.elements!r}")
        if self.degree not in (1, 2):
            raise ValueError(f"mesh.degree must be 1 or 2, got {self.degree!r}")


def support_components(spec, key: str) -> tuple[str, ...]:
    """Fixed components of a support: a kind name or an explicit list such as ["u", "theta"]."""
    if isinstance(spec, str):
        if spec not in SUPPORT_KINDS:
            raise ValueError(
                f"supports.{key} must be one of {', '.join(SUPPORT_KINDS)} or a list of "
                f"components from {list(COMPONENTS)}; got {spec!r}"
            )
        return SUPPORT_KINDS[spec]
    if isinstance(spec, (list, tuple)) and all(isinstance(c, str) for c in spec):
        unknown = [c for c in spec if c not in COMPONENTS]
        if unknown or len(set(spec)) != len(spec):
            raise ValueError(
                f"supports.{key}: components must be distinct names from {list(COMPONENTS)}; "
                f"got {list(spec)}"
            )
        return tuple(spec)
    raise ValueError(f"supports.{key} must be a support name or a list of components, got {spec!r}")


@dataclass(frozen=True)
class Supports:
    """End conditions at x = 0 and x = L, with optional prescribed values of fixed components.

    Prescribed values (e.g. ``prescribed_xL = {"theta": 3.14}``) are scaled by the load factor.
    """

    x0: str | tuple = "clamped"
    xL: str | tuple = "free"
    prescribed_x0: dict = field(default_factory=dict)
    prescribed_xL: dict = field(default_factory=dict)

    def __post_init__(self):
        for end in ("x0", "xL"):
            fixed = support_components(getattr(self, end), end)
            for name, value in getattr(self, f"prescribed_{end}").items():
                if name not in fixed:
                    raise ValueError(
                        f"loads.prescribed_{end}.{name}: only fixed components can be prescribed "
                        f"(supports.{end} fixes {list(fixed) or 'nothing'})"
                    )
                if isinstance(value, bool) or not isinstance(value, (int, float)):
                    raise ValueError(
                        f"loads.prescribed_{end}.{name} must be a number, got {value!r}"
                    )

    def fixed(self, end: str) -> tuple[str, ...]:
        return support_components(getattr(self, end), end)

    def rigid_motions(self) -> list[str]:
        """The rigid-body motions these supports leave free (empty: none).

        A small rigid motion is (u, v, theta) = (a, b + w x, w); each fixed component at
        x = 0 or x = L (length 1 here: the rank does not depend on it) is one equation on
        (a, b, w). A static solve needs all three removed: its stiffness is singular otherwise.
        """
        rows = {"u": lambda x: (1.0, 0.0, 0.0), "v": lambda x: (0.0, 1.0, x),
                "theta": lambda x: (0.0, 0.0, 1.0)}
        equations = [rows[c](x) for end, x in (("x0", 0.0), ("xL", 1.0))
                     for c in self.fixed(end)]
        if equations and _rank(equations) == 3:
            return []
        free = []
        if not any(row[0] for row in equations):
            free.append("translation along x (fix u at one end)")
        if _rank([row[1:] for row in equations]) < 2:
            free.append("translation along y or rotation (fix v at both ends, or v and theta "
                        "at one end)")
        return free


def _with_end_motion(supports: Supports, motion: dict) -> Supports:
    """The supports with the end motion's components fixed at x = L and prescribed."""
    clash = [name for name in motion if name in supports.prescribed_xL]
    if clash:
        raise ValueError(f"loads.prescribed_xL.{clash[0]} and loads.end_"
                         f"{'rotation' if clash[0] == 'theta' else 'displacement'} both "
                         "prescribe the same component at x = L; give it once")
    fixed = supports.fixed("xL")
    components = tuple(c for c in COMPONENTS if c in fixed or c in motion)
    prescribed = dict(supports.prescribed_xL) | motion
    return Supports(x0=supports.x0, xL=components, prescribed_x0=dict(supports.prescribed_x0),
                    prescribed_xL=prescribed)


def _rank(rows) -> int:
    """Rank of a small matrix (a list of equal-length rows) by Gaussian elimination with
    partial pivoting (the rows of `Supports.rigid_motions` hold 0, 1 and x in [0, 1])."""
    rows = [list(map(float, row)) for row in rows]
    rank, columns = 0, len(rows[0]) if rows else 0
    for column in range(columns):
        pivot = max(range(rank, len(rows)), key=lambda i: abs(rows[i][column]), default=None)
        if pivot is None or abs(rows[pivot][column]) <= 1e-12:
            continue
        rows[rank], rows[pivot] = rows[pivot], rows[rank]
        for i in range(rank + 1, len(rows)):
            factor = rows[i][column] / rows[rank][column]
            rows[i] = [a - factor * b for a, b in zip(rows[i], rows[rank], strict=True)]
        rank += 1
    return rank


def _finite(value) -> bool:
    """A finite number (Python ints always are; math.isfinite would overflow on huge ones)."""
    return isinstance(value, int) or math.isfinite(value)


def _pair(name: str, value) -> tuple[float, float]:
    ok = (
        isinstance(value, (list, tuple))
        and len(value) == 2
        and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in value)
    )
    if not ok or not all(_finite(c) for c in value):
        hint = (" (3 components need [model] kinematics = \"spatial\")"
                if isinstance(value, (list, tuple)) and len(value) == 3 else "")
        raise ValueError(f"loads.{name} must be a pair of numbers [x, y], got {value!r}{hint}")
    return float(value[0]), float(value[1])


@dataclass(frozen=True)
class Loads:
    """Loads at load factor 1 (all scaled by the load factor during stepping).

    ``tip_force`` is dead (global components) unless ``follower``, in which case its components
    are taken in the tip section's frame (a1 = (cos theta, sin theta), d = (-sin theta, cos theta)),
    equal to the global ones in the undeformed state. ``distributed`` is a dead force per unit
    reference length; ``gravity`` an acceleration (force rho A g per unit length).

    ``point_forces``: dead forces ((x, Px, Py), ...) at points 0 < x <= L (each x becomes a
    mesh vertex). ``point_moments``: dead moments ((x, M), ...) about z (counterclockwise) at
    points 0 <= x <= L (each x a mesh vertex; work M theta(x)). ``end_displacement`` (du, dv)
    and ``end_rotation``: the end x = L moved to
    (u, v) = lambda (du, dv), turned to theta = lambda end_rotation (displacement control: the
    components become Dirichlet conditions at x = L, `BeamModel` adds them to the supports).
    """

    tip_force: tuple = (0.0, 0.0)
    tip_moment: float = 0.0
    follower: bool = False
    distributed: tuple = (0.0, 0.0)
    gravity: tuple = (0.0, 0.0)
    point_forces: tuple = ()
    point_moments: tuple = ()
    end_displacement: tuple | None = None
    end_rotation: float | None = None

    def __post_init__(self):
        for name in ("tip_force", "distributed", "gravity"):
            object.__setattr__(self, name, _pair(name, getattr(self, name)))
        if isinstance(self.tip_moment, bool) or not isinstance(self.tip_moment, (int, float)):
            hint = (" (a vector moment needs [model] kinematics = \"spatial\")"
                    if isinstance(self.tip_moment, (list, tuple)) else "")
            raise ValueError(f"loads.tip_moment must be a number, got {self.tip_moment!r}{hint}")
        if not isinstance(self.follower, bool):
            raise ValueError(f"loads.follower must be true or false, got {self.follower!r}")
        object.__setattr__(self, "point_forces", _point_forces(self.point_forces))
        object.__setattr__(self, "point_moments", point_rows(
            "point_moments", self.point_moments, 2, "[x, M] (two numbers: the position [m] and "
            "the moment about z [N m])", "[x, Mx, My, Mz] needs [model] kinematics = "
            "\"spatial\""))
        if self.end_displacement is not None:
            object.__setattr__(self, "end_displacement",
                               _pair("end_displacement", self.end_displacement))
        rotation = self.end_rotation
        if rotation is not None and (isinstance(rotation, bool)
                                     or not isinstance(rotation, (int, float))
                                     or not _finite(rotation)):
            raise ValueError(f"loads.end_rotation must be a number [rad], got {rotation!r}")
        self._check_end_motion()

    def _check_end_motion(self) -> None:
        """A load on a component the end motion prescribes would be taken by the support, not
        by the beam: refused."""
        if self.end_displacement is not None:
            if self.follower:
                raise ValueError("loads.end_displacement cannot be combined with follower = "
                                 "true (the prescribed end takes the tip force)")
            for index, name in enumerate(("x", "y")):
                if self.tip_force[index] != 0:
                    raise ValueError(
                        f"loads.end_displacement prescribes the tip's {name} displacement: "
                        f"loads.tip_force[{index}] = {self.tip_force[index]!r} on the same "
                        "component would be taken by the support; give one or the other")
        if self.end_rotation is not None and self.tip_moment != 0:
            raise ValueError(f"loads.end_rotation prescribes the tip rotation: loads.tip_moment "
                             f"= {self.tip_moment!r} would be taken by the support; give one or "
                             "the other")

    def end_motion(self) -> dict:
        """{u, v, theta: value at load factor 1} prescribed at x = L by the end motion."""
        motion = {}
        if self.end_displacement is not None:
            motion.update(u=self.end_displacement[0], v=self.end_displacement[1])
        if self.end_rotation is not None:
            motion["theta"] = float(self.end_rotation)
        return motion


def _point_forces(value) -> tuple:
    """((x, Px, Py), ...) as floats (ValueError naming loads.point_forces otherwise)."""
    if not isinstance(value, (list, tuple)):
        raise ValueError(f"loads.point_forces must be a list of [x, Px, Py], got {value!r}")
    forces = []
    for index, entry in enumerate(value):
        ok = (isinstance(entry, (list, tuple)) and len(entry) == 3
              and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in entry)
              and all(_finite(c) for c in entry))
        if not ok:
            raise ValueError(f"loads.point_forces[{index}] must be [x, Px, Py] (three numbers: "
                             f"the position [m] and the force [N]); got {entry!r}")
        forces.append(tuple(float(c) for c in entry))
    return tuple(forces)


def point_rows(name: str, value, size: int, form: str, hint: str = "") -> tuple:
    """``loads.<name>`` as a tuple of rows of ``size`` floats (ValueError naming the key and the
    row's ``form`` otherwise; ``hint`` is added when a row has the other kinematics' size)."""
    if not isinstance(value, (list, tuple)):
        raise ValueError(f"loads.{name} must be a list of rows {form}, got {value!r}")
    rows = []
    for index, entry in enumerate(value):
        ok = (isinstance(entry, (list, tuple)) and len(entry) == size
              and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in entry)
              and all(_finite(c) for c in entry))
        if not ok:
            other = hint and isinstance(entry, (list, tuple)) and len(entry) != size \
                and len(entry) in (2, 4)
            raise ValueError(f"loads.{name}[{index}] must be {form}; got {entry!r}"
                             + (f" ({hint})" if other else ""))
        rows.append(tuple(float(c) for c in entry))
    return tuple(rows)


def check_rod(length, material: Material, loads) -> None:
    """What every rod model checks: a length > 0, gravity with a density, point forces on the
    rod (0 < x <= L), point moments on it (0 <= x <= L), none of them on an end whose motion is
    prescribed; ValueError naming the key otherwise."""
    ok = isinstance(length, (int, float)) and not isinstance(length, bool)
    if not ok or not _finite(length) or length <= 0:
        raise ValueError(f"beam.length must be a number > 0, got {length!r}")
    if material.rho == 0 and any(loads.gravity):
        raise ValueError("loads.gravity needs material.rho > 0")
    for index, force in enumerate(loads.point_forces):
        if not 0 < force[0] <= length:
            raise ValueError(f"loads.point_forces[{index}]: x = {force[0]!r} is outside the beam "
                             f"(0 < x <= L = {length!r})")
    for index, moment in enumerate(loads.point_moments):
        if not 0 <= moment[0] <= length:
            raise ValueError(f"loads.point_moments[{index}]: x = {moment[0]!r} is outside the "
                             f"beam (0 <= x <= L = {length!r})")
        if loads.end_rotation is not None and length - moment[0] <= 1e-9 * length \
                and any(moment[1:]):
            raise ValueError(f"loads.end_rotation prescribes the tip rotation: loads.point_"
                             f"moments[{index}] at x = L would be taken by the support; give "
                             "one or the other")


@dataclass(frozen=True)
class BeamModel:
    """Everything that defines a planar beam problem."""

    length: float
    section: Section
    material: Material
    options: ModelOptions = field(default_factory=ModelOptions)
    mesh: Discretisation = field(default_factory=Discretisation)
    supports: Supports = field(default_factory=Supports)
    loads: Loads = field(default_factory=Loads)
    #: a structure of rods (`fe_beam.model.structure.Structure`, a serial chain laid along
    #: the arc length x of this model), or None for the single straight rod along x
    structure: Any = None

    def __post_init__(self):
        check_rod(self.length, self.material, self.loads)
        for index, (x, px, py) in enumerate(self.loads.point_forces):
            # as loads.tip_force: at the prescribed end the support would take the force
            if self.loads.end_displacement is not None and self.length - x <= 1e-9 * \
                    self.length and (px or py):
                raise ValueError(f"loads.end_displacement prescribes the tip: loads.point_"
                                 f"forces[{index}] at x = L would be taken by the support; "
                                 "give one or the other")
        motion = self.loads.end_motion()
        if motion:
            object.__setattr__(self, "supports", _with_end_motion(self.supports, motion))
        if self.options.law == "hyperelastic":
            self._check_hyperelastic()

    def _check_hyperelastic(self) -> None:
        """The section law needs the profile (custom sections: svk only), and the rod's E and G
        are the 3D law's small-strain ones (every other output uses them)."""
        fibre = FibreLaw.from_solid(self.options.hyperelastic)
        if self.section.shape == "custom" and fibre.material != "svk":
            raise ValueError(
                f"[model] material = \"{fibre.material}\" needs the section's profile: a custom "
                "section (only A, I, I3, I4 known) supports material = \"svk\" alone")
        reason = fibre.unresolved()
        if reason:
            raise ValueError(f"[model] {reason}: use a material with a larger Poisson's ratio")
        pairs = (("E", self.material.E, fibre.young_modulus),
                 ("G", self.material.shear_modulus, fibre.shear_modulus))
        for name, rod, law in pairs:
            if not abs(rod - law) <= 1e-9 * abs(law):
                raise ValueError(
                    f"material.{name} = {rod!r} differs from the small-strain {name} = {law!r} of "
                    "the hyperelastic law: the rod's E and G must be the law's")

    def stiffness_at(self, s: float = 0.0) -> dict:
        """Section stiffnesses (floats) at s = x / L."""
        p = self.section.properties(s)
        E, G = self.material.E, self.material.shear_modulus
        return {"EA": E * p.A, "GA": G * p.A, "EI": E * p.I, "EI3": E * p.I3, "EI4": E * p.I4}

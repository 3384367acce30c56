"""The ``[[obstacles]]`` array of tables and the ``[contact]`` table (`parse_contact`): rigid
obstacles in the rod's coordinates (`fe_beam.model.obstacles`), each checked clear of the
undeformed rod. Read by ``fe-beam static``, ``fe-beam finger`` and ``fe-beam solid`` (3D
coordinates, frictionless, checked against the meshed solid)."""

from __future__ import annotations

from fe_beam.config.keys import NUMBER, Key, _wrap, table
from fe_beam.errors import ConfigError
from fe_beam.model.obstacles import (
    OBSTACLE_SHAPES,
    Box,
    ContactSettings,
    Cylinder,
    Plane,
    Sphere,
    check_clear_of_rod,
)
from fe_beam.timefunctions import shown

__all__ = ["CONTACT_KEYS", "OBSTACLE_KEYS", "SHAPE_KEYS", "parse_contact", "parse_obstacle"]

OBSTACLE_KEYS = {
    "shape": Key((str,), None, "plane | cylinder | sphere | box"),
    "name": Key((str,), None, "label in the outputs (default obstacle<n>)"),
    "point": Key((list,), None, "plane: a point of the plane; cylinder: a point of its axis "
                 "[m] ([x, y] for the planar rod)"),
    "normal": Key((list,), None, "plane: normal pointing out of the obstacle, toward the rod"),
    "center": Key((list,), None, "sphere: centre [m]; box: centre (with size)"),
    "radius": Key(NUMBER, None, "cylinder, sphere: radius [m] (> 0)"),
    "axis": Key((list,), None, "cylinder: axis direction (spatial rods; planar rods: z)"),
    "length": Key(NUMBER, None, "cylinder: finite length [m] (spatial rods; default infinite)"),
    "min": Key((list,), None, "box: lowest corner [m]"),
    "max": Key((list,), None, "box: highest corner [m]"),
    "size": Key((list,), None, "box: edge lengths [m] (with center)"),
    "friction": Key(NUMBER, 0.0, "Coulomb friction coefficient mu >= 0 (0: frictionless; "
                    "rods: planar on any shape, spatial on a plane or an infinite cylinder; "
                    "not the 3D solid)"),
}
#: the keys each shape takes besides shape and name (required ones first)
SHAPE_KEYS = {
    "plane": (("point", "normal"), ()),
    "cylinder": (("point", "radius"), ("axis", "length")),
    "sphere": (("center", "radius"), ()),
    "box": ((), ("min", "max", "center", "size")),
}
CONTACT_KEYS = {
    "penetration_tolerance": Key(NUMBER, None, "largest penetration a converged load step may "
                                 "keep [m] (default 1e-3 x the smallest section height; the 3D "
                                 "solid: x min(h, h_tip, b))"),
    "penalty": Key(NUMBER, 1.0, "augmented-Lagrangian stiffness k relative to the element "
                   "bending stiffness: k = penalty EI / h_e^4 per unit length (the 3D solid: "
                   "k = penalty mu / mesh_size per unit area)"),
    "max_updates": Key((int,), 50, "augmented-Lagrangian (Uzawa) updates per load step before "
                       "the step is cut back (active-set and multiplier updates)"),
    "quadrature_degree": Key((int,), None, "Gauss rule of the contact integral (default 4 x "
                             "the element degree: 2 degree + 1 points per element)"),
}


def parse_obstacle(index: int, given, model, dim: int = 2, solid: bool = False):
    """One obstacle of ``[[obstacles]]`` (#index + 1), checked clear of the undeformed rod
    (``solid``: 3D coordinates, frictionless, checked against the meshed solid later by
    `fe_beam.fem.solid.contact.SolidContact.check_clear`)."""
    if not isinstance(given, dict):
        raise ConfigError(f"[[obstacles]] #{index + 1} must be a table; got {shown(given)}")
    label = given.get("name") if isinstance(given.get("name"), str) else f"#{index + 1}"
    unknown = [k for k in given if k not in OBSTACLE_KEYS]
    if unknown:
        raise ConfigError(f"[[obstacles]] {label}: unknown key {shown(unknown[0])}; allowed: "
                          f"{', '.join(OBSTACLE_KEYS)}")
    values = table({"[obstacles]": given}, "[obstacles]", OBSTACLE_KEYS)
    name = values["name"] or f"obstacle{index + 1}"
    where = f"[[obstacles]] {name!r}"
    shape = values["shape"]
    if shape not in OBSTACLE_SHAPES:
        raise ConfigError(f"{where} shape must be one of {', '.join(OBSTACLE_SHAPES)}; got "
                          f"{shown(shape)}")
    required, optional = SHAPE_KEYS[shape]
    allowed = set(required) | set(optional) | {"shape", "name", "friction"}
    extra = [k for k in given if k not in allowed]
    if extra:
        raise ConfigError(f"{where} key {extra[0]} does not apply to shape = \"{shape}\" "
                          f"(it takes {', '.join(required + optional)})")
    missing = [k for k in required if values[k] is None]
    if missing:
        raise ConfigError(f"{where} shape = \"{shape}\" needs {missing[0]} (it takes "
                          f"{', '.join(required + optional)})")
    mu = values["friction"]
    if solid and mu != 0:
        raise ConfigError(f"{where} friction is available for rods only (the 3D solid's "
                          "contact is frictionless: leave friction out)")
    if dim == 3 and mu != 0 and (shape not in ("plane", "cylinder")
                                 or values["length"] is not None):
        raise ConfigError(f"{where} friction of a spatial rod is available on a plane or an "
                          f"infinite cylinder only (not on a {shape}"
                          f"{' of finite length' if shape == 'cylinder' else ''}: leave "
                          "friction out)")
    if shape == "plane":
        obstacle = _wrap(Plane, name=name, dim=dim, point=values["point"],
                         normal=values["normal"], friction=mu)
    elif shape == "sphere":
        obstacle = _wrap(Sphere, name=name, dim=dim, center=values["center"],
                         radius=values["radius"], friction=mu)
    elif shape == "cylinder":
        obstacle = _wrap(Cylinder, name=name, dim=dim, point=values["point"],
                         radius=values["radius"], axis=values["axis"], length=values["length"],
                         friction=mu)
    else:
        corners = values["min"] is not None or values["max"] is not None
        centred = values["center"] is not None or values["size"] is not None
        if corners == centred:
            raise ConfigError(f"{where} a box takes either min and max (its corners) or center "
                              "and size")
        pair = ("min", "max") if corners else ("center", "size")
        absent = [k for k in pair if values[k] is None]
        if absent:
            raise ConfigError(f"{where} {pair[0]} and {pair[1]} go together; {absent[0]} is "
                              "missing")
        obstacle = (_wrap(Box, name=name, dim=dim, min=values["min"], max=values["max"],
                          friction=mu)
                    if corners else
                    _wrap(Box.from_center, values["center"], values["size"], name, dim, mu))
    if not solid:
        check_clear_of_rod(obstacle, model.section, model.length)
    return obstacle


def parse_contact(config: dict, model, solid: bool = False
                  ) -> tuple[tuple, ContactSettings | None]:
    """(obstacles in the order of [[obstacles]], contact settings or None without obstacles);
    ``solid``: the 3D solid's obstacles (3D coordinates, ``model`` unused)."""
    given = config.get("obstacles")
    if given is None:
        if "contact" in config:
            raise ConfigError("[contact] sets how contact with [[obstacles]] is enforced, and "
                              "the configuration has no [[obstacles]]")
        return (), None
    if isinstance(given, dict):
        raise ConfigError("obstacles must be an array of tables: write each obstacle as "
                          "[[obstacles]] (double brackets), not [obstacles]")
    if not isinstance(given, list) or not given:
        raise ConfigError("[[obstacles]] must list at least one obstacle")
    dim = 3 if solid or getattr(model, "kinematics", "planar") == "spatial" else 2
    obstacles = tuple(parse_obstacle(i, o, model, dim, solid) for i, o in enumerate(given))
    names = [o.name for o in obstacles]
    twice = [n for n in names if names.count(n) > 1]
    if twice:
        raise ConfigError(f"[[obstacles]] name {twice[0]!r} is given to two obstacles; names "
                          "must be unique")
    settings = _wrap(ContactSettings, **table(config, "contact", CONTACT_KEYS))
    return obstacles, settings

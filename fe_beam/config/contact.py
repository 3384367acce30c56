"""The ``[[obstacles]]`` array of tables and the ``[contact]`` table (`parse_contact`): rigid
obstacles in the rod's coordinates (`fe_beam.model.obstacles`), each checked clear of the
undeformed rod. Read by ``fe-beam static``, ``fe-beam finger`` and ``fe-beam solid`` (3D
coordinates, frictionless, checked against the meshed solid)."""

from __future__ import annotations

import numpy as np

from fe_beam.config.keys import NUMBER, Key, _wrap, table
from fe_beam.errors import ConfigError
from fe_beam.model.obstacles import (
    OBSTACLE_SHAPES,
    Box,
    ContactSettings,
    Cylinder,
    Motion,
    Plane,
    Sphere,
    check_clear_of_chain,
    check_clear_of_rod,
    translated,
)
from fe_beam.timefunctions import shown

__all__ = ["CONTACT_KEYS", "MOTION_KEYS", "OBSTACLE_KEYS", "SHAPE_KEYS", "check_motions",
           "parse_contact", "parse_obstacle"]

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
    "velocity": Key((list,), None, "a moving obstacle: constant velocity [m/s] ([vx, vy] planar, "
                    "[vx, vy, vz] spatial; fe-beam dynamic)"),
    "position": Key((list,), None, "a moving obstacle: its translation from the configured "
                    "place [m], numbers or formulas in t (fe-beam dynamic) or in load_factor "
                    "(fe-beam static and finger: the obstacle moves along the load path)"),
}
MOTION_KEYS = ("velocity", "position")
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
                   "bending stiffness: k = penalty EI / h_e^4 per unit length (fe-beam dynamic: "
                   "at least penalty 100 rho A / (beta dt^2), the step's inertia; the 3D solid: "
                   "k = penalty mu / mesh_size per unit area)"),
    "max_updates": Key((int,), 50, "augmented-Lagrangian (Uzawa) updates per load step before "
                       "the step is cut back (active-set and multiplier updates)"),
    "quadrature_degree": Key((int,), None, "Gauss rule of the contact integral (default 4 x "
                             "the element degree: 2 degree + 1 points per element)"),
    "max_active_change": Key(NUMBER, 0.2, "rods: largest share (0 < . <= 1) of an obstacle's "
                             "contact points (quadrature points and the two ends) that may come "
                             "into or out of contact in one load step or path point; a larger "
                             "change is cut back (1: no limit)"),
    "force_tolerance": Key(NUMBER, 1e-3, "rods: largest estimated relative error (0 < . <= 1) "
                           "of each obstacle's contact force a converged step may keep: the "
                           "Uzawa updates go on until the multipliers have converged, not only "
                           "the penetration"),
}


def parse_obstacle(index: int, given, model, dim: int = 2, solid: bool = False,
                   variable: str = "load_factor"):
    """One obstacle of ``[[obstacles]]`` (#index + 1), checked clear of the undeformed rod at
    its start position (``solid``: 3D coordinates, frictionless, fixed, checked against the
    meshed solid later by `fe_beam.fem.solid.contact.SolidContact.check_clear`); a motion's
    formulas are in ``variable`` ("t": fe-beam dynamic, "load_factor": statics)."""
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
    allowed = set(required) | set(optional) | {"shape", "name", "friction", *MOTION_KEYS}
    extra = [k for k in given if k not in allowed]
    if extra:
        raise ConfigError(f"{where} key {extra[0]} does not apply to shape = \"{shape}\" "
                          f"(it takes {', '.join(required + optional)})")
    missing = [k for k in required if values[k] is None]
    if missing:
        raise ConfigError(f"{where} shape = \"{shape}\" needs {missing[0]} (it takes "
                          f"{', '.join(required + optional)})")
    motion = _motion(values, where, dim, solid, variable)
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
                         normal=values["normal"], friction=mu, motion=motion)
    elif shape == "sphere":
        obstacle = _wrap(Sphere, name=name, dim=dim, center=values["center"],
                         radius=values["radius"], friction=mu, motion=motion)
    elif shape == "cylinder":
        obstacle = _wrap(Cylinder, name=name, dim=dim, point=values["point"],
                         radius=values["radius"], axis=values["axis"], length=values["length"],
                         friction=mu, motion=motion)
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
                          friction=mu, motion=motion)
                    if corners else
                    _wrap(Box.from_center, values["center"], values["size"], name, dim, mu,
                          motion))
    if not solid:
        start = _wrap(obstacle.translation, 0.0)
        try:
            if getattr(model, "structure", None) is not None:  # a chain of rods
                check_clear_of_chain(translated(obstacle, start), model.structure,
                                     model.section)
            else:
                check_clear_of_rod(translated(obstacle, start), model.section, model.length)
        except ConfigError as error:
            if motion is None:
                raise
            raise ConfigError(str(error).replace(
                "intersects the undeformed rod", "intersects the undeformed rod at its start "
                f"position ({motion.variable} = 0)", 1)) from None
    return obstacle


def _motion(values: dict, where: str, dim: int, solid: bool, variable: str):
    """The obstacle's `Motion` (None: fixed), in ``variable``."""
    given = [k for k in MOTION_KEYS if values[k] is not None]
    if not given:
        return None
    if solid:
        raise ConfigError(f"{where} {given[0]}: moving obstacles are available for the rods "
                          "(fe-beam static, finger and dynamic), not for the 3D solid; leave "
                          f"{given[0]} out")
    if len(given) == 2:
        raise ConfigError(f"{where} give velocity or position (the obstacle's motion), not "
                          "both")
    if given[0] == "velocity" and variable != "t":
        raise ConfigError(f"{where} velocity is a rate in time, read by fe-beam dynamic only; "
                          "along the load path of statics give position = [formulas in "
                          "load_factor] (the translation at load factor 0 .. 1)")
    try:
        return Motion(velocity=values["velocity"], position=values["position"],
                      variable=variable, dim=dim)
    except ValueError as error:
        raise ConfigError(str(error).replace("[[obstacles]]", where, 1)) from None


MOTION_SAMPLES = 2001  # values of t in [0, t_end] (of the load factor in [0, 1]) checked


def check_motions(obstacles, end: float, model) -> None:
    """ConfigError for a moving obstacle whose position formula cannot be evaluated (or is
    not finite) somewhere in [0, ``end``] (the time span or the load path), sampled at
    MOTION_SAMPLES values; the start position is checked clear of the rod by the parser."""
    for obstacle in obstacles:
        if obstacle.motion is None:
            continue
        where = f"[[obstacles]] {obstacle.name!r}"
        for value in np.linspace(0.0, float(end), MOTION_SAMPLES):
            try:
                offset = obstacle.translation(value)
            except ValueError as error:
                raise ConfigError(f"{where} position: {error}") from None
            if not np.all(np.isfinite(offset)):
                raise ConfigError(f"{where} position is not finite at "
                                  f"{obstacle.motion.variable} = {value:.4g}")


def parse_contact(config: dict, model, solid: bool = False, variable: str = "load_factor"
                  ) -> tuple[tuple, ContactSettings | None]:
    """(obstacles in the order of [[obstacles]], contact settings or None without obstacles);
    ``solid``: the 3D solid's obstacles (3D coordinates, ``model`` unused); ``variable``: that
    of the moving obstacles' position formulas ("t" in dynamics)."""
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
    obstacles = tuple(parse_obstacle(i, o, model, dim, solid, variable)
                      for i, o in enumerate(given))
    names = [o.name for o in obstacles]
    twice = [n for n in names if names.count(n) > 1]
    if twice:
        raise ConfigError(f"[[obstacles]] name {twice[0]!r} is given to two obstacles; names "
                          "must be unique")
    for rod_only in ("max_active_change", "force_tolerance"):
        if solid and rod_only in (config.get("contact") or {}):
            raise ConfigError(f"[contact] {rod_only} applies to the rod's contact only (the 3D "
                              "solid's steps do not use it); leave it out with [solid]")
    settings = _wrap(ContactSettings, **table(config, "contact", CONTACT_KEYS))
    if not solid:
        _wrap(settings.check_tolerance, model.section)
    return obstacles, settings

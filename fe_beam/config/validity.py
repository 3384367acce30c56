"""The configuration of ``fe-beam validity``: the ``[validity]`` table (`VALIDITY_KEYS`) over a
``fe-beam compare`` / ``fe-beam solid`` configuration, and the configuration of every point of the
map (`parse_validity`). Pure Python (no dolfinx, PETSc or MPI): every point's configuration is
validated here, before any solve; `fe_beam.analyses.validity` runs the map.

A map axis is any numeric key of the configuration, written as a dotted path: ``beam.length``,
``section.h_tip``, ``material.nu``, ``solid.mesh_size``, ``tendons.0.tension`` (an index into an
array of tables), ``loads.tip_force.1`` (an index into a list). The key must be in the
configuration or be a key of its table with a default (`fe_beam.config.schema.SCHEMA`, the 3D
solid's
``[solid]``, ``[section]`` and ``[material]`` keys, the ``[[tendons]]`` keys).

Every point is the configuration with the axis values set, run as ``fe-beam compare`` with
``[compare] load_factors = [1.0]`` and the rod laws of ``[validity] laws``: the full load of the
configuration (the sweep keys of ``[compare]``, if any, are not used).
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
from dataclasses import dataclass

from fe_beam.config.compare import RODS, SPATIAL_RODS, CompareConfig, parse_compare
from fe_beam.config.finger import TENDON_KEYS
from fe_beam.config.schema import NUMBER, SCHEMA, ConfigError, Key, check_values, table
from fe_beam.config.solid import MATERIAL_KEYS, SOLID_KEYS, spatial_rod

__all__ = [
    "DEFAULT_LAWS",
    "METRICS",
    "VALIDITY_KEYS",
    "GridPoint",
    "ValidityConfig",
    "config_hash",
    "parse_validity",
    "point_config",
    "resolve_key",
]

DEFAULT_LAWS = ("nonstandard", "reissner")
DEFAULT_ORDER = 1.0
VALIDITY_KEYS = {
    "x": Key((str,), None, "the config key of the map's x axis, a dotted path such as "
             "\"tendons.0.tension\" (required)"),
    "x_values": Key((list,), None, "the values of x (a non-empty list of numbers)"),
    "y": Key((str,), None, "the config key of the y axis (optional: without it a 1-D map)"),
    "y_values": Key((list,), None, "the values of y (a non-empty list of numbers)"),
    "laws": Key((list,), list(DEFAULT_LAWS), "rod laws: nonstandard, reissner, hyperelastic"),
    "second_mesh_ratio": Key(NUMBER, None, "r: the solid is solved again with [solid] mesh_size "
                             "/ r (r = 2: twice as fine) for a Richardson estimate of its error"),
    "order": Key(NUMBER, DEFAULT_ORDER, "convergence order p of the solid assumed by the "
                 "Richardson estimate (default 1: the clamped face's edges limit the order; "
                 "certified on a third, coarser mesh: check solid_discretisation_error)"),
    "workers": Key((int,), 1, "points solved at once in separate processes (serial runs; "
                   "under mpirun the ranks share the points)"),
    "metric": Key((str,), "backbone_distance", "the quantity the map shows (validity.png, the "
                  "statements' 1 % and 5 % counts): backbone_distance (max_x |r_rod - r_solid| / "
                  "L), or contact_force_difference (with [[obstacles]]: the largest over the "
                  "obstacles of |F_rod - F_solid| / max(|F_rod|, |F_solid|))"),
}
#: the quantities a map can show ([validity] metric)
METRICS = ("backbone_distance", "contact_force_difference")
MAX_WORKERS = 64
#: the most points a map may have (every point is a 3D solve; refused before any is parsed)
MAX_POINTS = 1000
#: tables a map axis cannot name (they configure the map itself or are replaced per point)
NOT_AXES = ("validity", "compare", "refine", "output")
#: keys of the 3D solid's tables beyond `SCHEMA` (their defaults exist without being written)
_SECTION_KEYS = ("shape", "b", "h", "h_tip")


@dataclass(frozen=True)
class GridPoint:
    """Point (i, j) of the map: axis values, its whole configuration (as ``fe-beam compare``
    reads it), the parsed one, and the hash that identifies it on resume."""

    i: int
    j: int
    x: float
    y: float | None
    raw: dict
    parsed: CompareConfig
    hash: str

    @property
    def name(self) -> str:
        return f"{self.i}_{self.j}"


@dataclass(frozen=True)
class ValidityConfig:
    x: str
    x_values: tuple[float, ...]
    y: str | None
    y_values: tuple[float, ...] | None
    laws: tuple[str, ...]
    second_mesh_ratio: float | None
    order: float
    points: tuple[GridPoint, ...]
    workers: int = 1
    metric: str = "backbone_distance"

    @property
    def kinematics(self) -> str:
        """The rod's kinematics: "spatial" (``[model] kinematics = "spatial"``) or "planar"."""
        return "spatial" if self.points and self.points[0].parsed.spatial else "planar"

    @property
    def solid(self):
        """The first point's solid configuration (its solver settings are every point's:
        `fe_beam.config.registry.validate` has PETSc check their options)."""
        return self.points[0].parsed.solid


def _known_keys(name: str) -> dict:
    """The keys (with their Key) a table understands when they are not written."""
    if name == "solid":
        return SOLID_KEYS
    if name == "material":
        return MATERIAL_KEYS
    if name == "section":
        return {key: Key(NUMBER, None) for key in _SECTION_KEYS if key != "shape"} | {
            "shape": SCHEMA["section"]["shape"]}
    if name == "tendons":
        return TENDON_KEYS
    return SCHEMA.get(name, {})


def _is_number(value) -> bool:
    return isinstance(value, NUMBER) and not isinstance(value, bool)


def resolve_key(raw: dict, path: str, owner: str) -> None:
    """Check that ``path`` names a numeric key of ``raw`` (given, or known with a default);
    ConfigError naming ``owner`` (e.g. ``[validity] x``) otherwise."""
    parts = path.split(".")
    if len(parts) < 2 or not all(parts):
        raise ConfigError(f"{owner} = {path!r} must be a dotted key path such as "
                          "\"beam.length\" or \"tendons.0.tension\"")
    if parts[0] in NOT_AXES:
        raise ConfigError(f"{owner} = {path!r}: the [{parts[0]}] table cannot be a map axis; "
                          "name a key of the model (e.g. \"beam.length\")")
    known = None  # the Key of the current position, when it is known from a schema
    current = raw.get(parts[0])
    schema = _known_keys(parts[0])
    if current is None and not schema:
        raise ConfigError(f"{owner} = {path!r}: the configuration has no table [{parts[0]}]")
    rest = parts[1:]
    if parts[0] == "tendons":
        if not isinstance(current, list) or not current:
            raise ConfigError(f"{owner} = {path!r}: the configuration has no [[tendons]]")
        index = rest[0]
        if not index.isdigit() or int(index) >= len(current):
            raise ConfigError(f"{owner} = {path!r}: [[tendons]] has {len(current)} entries; "
                              f"address one as tendons.<index 0..{len(current) - 1}>.key")
        current, rest = current[int(index)], rest[1:]
        if not rest:
            raise ConfigError(f"{owner} = {path!r} names a whole tendon; name one of its keys "
                              "(e.g. tendons.0.tension)")
    elif current is None:
        current = {}
    for position, part in enumerate(rest):
        if isinstance(current, dict):
            if part in current:
                current = current[part]
                known = None
            elif position == 0 and part in schema:
                known = schema[part]
                current = copy.deepcopy(known.default)
            else:
                raise ConfigError(f"{owner} = {path!r}: no key {part!r} in that table (neither "
                                  "in the configuration nor among its defaults)")
        elif isinstance(current, list):
            if not part.isdigit() or int(part) >= len(current):
                raise ConfigError(f"{owner} = {path!r}: {part!r} is not an index of a list of "
                                  f"{len(current)} values (0..{len(current) - 1})")
            current, known = current[int(part)], None
        else:
            raise ConfigError(f"{owner} = {path!r}: {part!r} is inside a value that is not "
                              "a table or list")
    numeric = _is_number(current) or (
        current is None and known is not None and set(known.types) <= set(NUMBER))
    if not numeric:
        raise ConfigError(f"{owner} = {path!r} is not a numeric key (its value is "
                          f"{current!r}); a map axis must be a number")


def set_key(raw: dict, path: str, value: float) -> None:
    """Set ``path`` (checked by `resolve_key`) to ``value`` in ``raw`` (in place)."""
    parts = path.split(".")
    target = raw
    for position, part in enumerate(parts[:-1]):
        if isinstance(target, list):
            target = target[int(part)]
            continue
        if part not in target:
            schema = _known_keys(parts[0]) if position == 1 else {}
            default = schema[part].default if part in schema else None
            target[part] = copy.deepcopy(default) if isinstance(default, list) else {}
        target = target[part]
    last = parts[-1]
    if isinstance(target, list):
        target[int(last)] = value
    else:
        target[last] = value


def _values(key: str, values) -> tuple[float, ...]:
    ok = isinstance(values, list) and len(values) >= 1 and all(
        _is_number(v) and math.isfinite(v) for v in values)
    if not ok:
        raise ConfigError(f"[validity] {key} must be a non-empty list of numbers; got {values!r}")
    if len(set(values)) != len(values):
        raise ConfigError(f"[validity] {key} must not repeat a value; got {values!r}")
    return tuple(values)


def config_hash(raw: dict) -> str:
    """A fingerprint of a point's configuration: a finished point is reused only when its
    configuration is the same ([output] aside: it changes no number)."""
    text = json.dumps({k: v for k, v in raw.items() if k != "output"}, sort_keys=True,
                      default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def point_config(raw: dict, laws, settings: dict) -> dict:
    """The ``fe-beam compare`` configuration of one point, from ``raw`` with the axis values
    ``settings`` ({path: value}) set: [validity] removed, [compare] = the full load and the
    map's laws."""
    point = copy.deepcopy(raw)
    point.pop("validity", None)
    compare = point.get("compare") if isinstance(point.get("compare"), dict) else {}
    point["compare"] = {k: v for k, v in compare.items()
                        if k not in ("tensions", "load_factors", "steps", "laws")}
    point["compare"] |= {"load_factors": [1.0], "laws": list(laws)}
    for path, value in settings.items():
        set_key(point, path, value)
    return point


def _axis_value(path: str, value):
    """TOML-like value for the key: integer keys (counts) keep integer values."""
    return int(value) if isinstance(value, int) else float(value)


def parse_validity(raw: dict) -> ValidityConfig:
    """Validate a ``fe-beam validity`` configuration and every point's ``fe-beam compare``
    configuration (ConfigError naming the key)."""
    if not isinstance(raw, dict):
        raise ConfigError("the configuration must be a table")
    if "validity" not in raw:
        raise ConfigError("[validity] is required: x = \"<config key>\", x_values = [...] "
                          "(and optionally y, y_values)")
    given = table(raw, "validity", VALIDITY_KEYS)
    if given["x"] is None:
        raise ConfigError("[validity] x is required: the config key of the map's x axis "
                          "(e.g. \"tendons.0.tension\")")
    if given["x_values"] is None:
        raise ConfigError("[validity] x_values is required: a non-empty list of numbers")
    if (given["y"] is None) != (given["y_values"] is None):
        missing = "y_values" if given["y_values"] is None else "y"
        raise ConfigError(f"[validity] {missing} is required when "
                          f"{'y' if missing == 'y_values' else 'y_values'} is given")
    resolve_key(raw, given["x"], "[validity] x")
    x_values = _values("x_values", given["x_values"])
    y, y_values = given["y"], None
    if y is not None:
        resolve_key(raw, y, "[validity] y")
        if y == given["x"]:
            raise ConfigError(f"[validity] y = {y!r} is the same key as x; choose another")
        y_values = _values("y_values", given["y_values"])
    count = len(x_values) * len(y_values or (None,))
    if count > MAX_POINTS:
        raise ConfigError(f"[validity] x_values and y_values make {count} points; a map takes at "
                          f"most {MAX_POINTS} (every point is a 3D solve)")
    laws = given["laws"]
    if (not isinstance(laws, list) or not laws or any(law not in RODS for law in laws)
            or len(set(laws)) != len(laws)):
        raise ConfigError(f"[validity] laws must be a list of distinct names from "
                          f"{', '.join(RODS)}; got {laws!r}")
    if spatial_rod(raw) and any(law not in SPATIAL_RODS for law in laws):
        raise ConfigError("[validity] laws: the hyperelastic section law is planar only for now, "
                          "so the spatial rod ([model] kinematics = \"spatial\") is mapped with "
                          f"{' and '.join(SPATIAL_RODS)}; got {laws!r}")
    ratio = given["second_mesh_ratio"]
    if ratio is not None and not (0.25 <= ratio <= 4 and abs(ratio - 1) > 1e-3):
        raise ConfigError(f"[validity] second_mesh_ratio must be in [0.25, 4] and not 1 "
                          f"(second mesh_size = mesh_size / ratio); got {ratio!r}")
    order = given["order"]
    if not 0.5 <= order <= 8:
        raise ConfigError(f"[validity] order must be in [0.5, 8]; got {order!r}")
    metric = given["metric"]
    if metric not in METRICS:
        raise ConfigError(f"[validity] metric must be one of {', '.join(METRICS)}; got "
                          f"{metric!r}")
    if metric == "contact_force_difference" and not raw.get("obstacles"):
        raise ConfigError("[validity] metric = \"contact_force_difference\" needs "
                          "[[obstacles]] (the rod and the solid in contact); without them map "
                          "backbone_distance")
    workers = given["workers"]
    if not 1 <= workers <= MAX_WORKERS:
        raise ConfigError(f"[validity] workers must be an integer from 1 to {MAX_WORKERS}; "
                          f"got {workers!r}")

    points = []
    for i, xv in enumerate(x_values):
        for j, yv in enumerate(y_values or (None,)):
            settings = {given["x"]: _axis_value(given["x"], xv)}
            if y is not None:
                settings[y] = _axis_value(y, yv)
            point = point_config(raw, laws, settings)
            where = f"{given['x']} = {xv!r}" + (f", {y} = {yv!r}" if y is not None else "")
            try:
                check_values(point)
                parsed = parse_compare(point)
                if ratio is not None:  # the second mesh and the third (coarsest) one
                    parse_compare(second_mesh(point, parsed, ratio))
                    parse_compare(second_mesh(point, parsed, third_mesh_ratio(ratio)))
            except ConfigError as error:
                raise ConfigError(f"[validity] the point {where}: {error}") from None
            points.append(GridPoint(i, j, float(xv), None if yv is None else float(yv), point,
                                    parsed, config_hash(point | {"__map__": {
                                        "second_mesh_ratio": ratio, "order": order,
                                        "mesh_check": 1}})))
    return ValidityConfig(given["x"], x_values, y, y_values, tuple(laws),
                          None if ratio is None else float(ratio), float(order), tuple(points),
                          workers, metric)


def third_mesh_ratio(ratio: float) -> float:
    """The ``ratio`` (for `second_mesh`) of the third, coarsest mesh that certifies the
    Richardson estimate: sizes h R, h, h / R for a finer second mesh (ratio > 1), h R^2, h R,
    h for a coarser one."""
    return 1.0 / ratio if ratio > 1 else ratio**2


def second_mesh(point: dict, parsed: CompareConfig, ratio: float) -> dict:
    """The point's configuration with ``[solid] mesh_size`` divided by ``ratio``."""
    raw = copy.deepcopy(point)
    raw.setdefault("solid", {})["mesh_size"] = parsed.solid.sizes.size / ratio
    return raw

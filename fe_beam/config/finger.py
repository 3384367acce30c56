"""The finger's configuration: the chapter's default finger, the ``[[tendons]]`` and
``[inverse]`` tables, and `parse_finger` (a `StaticConfig` with tendons). Pure Python and numpy:
`fe_beam.analyses.finger` runs it.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace

from fe_beam.config.schema import (
    NUMBER,
    ConfigError,
    Key,
    StaticConfig,
    _wrap,
    check_max_increment,
    given_max_increment,
    parse_static,
    table,
)
from fe_beam.model.tendons import Tendon, check_tendon_inside

__all__ = [
    "DEFAULT_FINGER",
    "INVERSE_KEYS",
    "TENDON_KEYS",
    "InverseTarget",
    "check_tendon_inside",
    "parse_finger",
    "parse_tendon",
    "with_defaults",
]

DEFAULT_FINGER = {
    "beam": {"length": 0.1},
    "section": {"shape": "rectangle", "b": 0.02, "h": 0.02, "h_tip": 0.01},
    "material": {"E": 0.6e6, "nu": 0.45, "rho": 1070.0},
    "mesh": {"elements": 40, "degree": 2},
    "loads": {"steps": 20},
    "tendons": [{"name": "flexor", "offset_base": 0.008, "offset_tip": 0.004, "tension": 2.0}],
}

TENDON_KEYS = {
    "name": Key((str,), None, "label"),
    "offset_base": Key(NUMBER, None, "offset at x = 0 [m] (+ on the +y side)"),
    "offset_tip": Key(NUMBER, None, "offset at x = L [m]"),
    "path": Key((list,), None, "[[x, offset], ...] in metres, piecewise linear"),
    "paths": Key((list,), None, "several branches with one tension: [[[x, offset], ...], ...]"),
    "entry": Key(NUMBER, 0.0, "x where the tendon enters [m]"),
    "anchor": Key(NUMBER, None, "x where it is anchored [m] (default L)"),
    "tension": Key(NUMBER, None, "tension at load factor 1 [N]"),
    "pull_in": Key(NUMBER, None, "pull-in at load factor 1 [m] (tension becomes unknown)"),
    "steps": Key((int,), None, "number of load steps (the largest over tendons and [loads])"),
}
INVERSE_KEYS = {
    "tip_angle": Key(NUMBER, None, "target tip rotation theta [rad]"),
    "tip_u": Key(NUMBER, None, "target tip displacement u [m] (negative: the tip moves back)"),
    "tip_v": Key(NUMBER, None, "target tip displacement v [m]"),
}
TIP_COMPONENT = {"tip_angle": "theta", "tip_u": "u", "tip_v": "v"}


@dataclass(frozen=True)
class InverseTarget:
    """A target tip value (``key`` one of INVERSE_KEYS) reached by the single tendon's tension
    (or pull-in, for a pull-in-controlled tendon)."""

    key: str
    value: float

    @property
    def component(self) -> str:
        return TIP_COMPONENT[self.key]


def with_defaults(config: dict) -> dict:
    """The user's tables over the chapter's finger (whole tables: a given [section] replaces
    the default one rather than mixing keys of two shapes)."""
    merged = copy.deepcopy(DEFAULT_FINGER)
    for name, value in config.items():
        if name == "loads" and isinstance(value, dict):
            merged["loads"] = {**merged["loads"], **value}
        else:
            merged[name] = copy.deepcopy(value)
    return merged


def parse_tendon(index: int, given: dict, length: float) -> tuple[Tendon, int | None]:
    if not isinstance(given, dict):
        raise ConfigError(f"[[tendons]] #{index + 1} must be a table")
    values = table({"tendon": given}, "tendon", TENDON_KEYS)
    name = values["name"] or f"tendon{index + 1}"
    where = f"[[tendons]] {name!r}"
    linear = values["offset_base"] is not None or values["offset_tip"] is not None
    choices = [linear, values["path"] is not None, values["paths"] is not None]
    if sum(choices) != 1:
        raise ConfigError(f"{where}: give exactly one of offset_base/offset_tip, path or paths")
    if linear:
        if values["offset_base"] is None or values["offset_tip"] is None:
            raise ConfigError(f"{where}: offset_base and offset_tip go together")
        paths = (((0.0, values["offset_base"]), (length, values["offset_tip"])),)
    else:
        paths = (values["path"],) if values["path"] is not None else tuple(values["paths"])
    tendon = _wrap(
        Tendon,
        paths=paths,
        entry=values["entry"],
        anchor=values["anchor"],
        tension=values["tension"],
        pull_in=values["pull_in"],
        name=name,
    )
    _wrap(tendon.validate_for, length)
    return tendon, values["steps"]


def parse_finger(config: dict) -> tuple[StaticConfig, InverseTarget | None]:
    """(static config with tendons, inverse target or None)."""
    config = with_defaults(config)
    tendons_given = config.pop("tendons")
    inverse = table(config, "inverse", INVERSE_KEYS) if "inverse" in config else {}
    config.pop("inverse", None)
    if not isinstance(tendons_given, list) or not tendons_given:
        raise ConfigError("[[tendons]] must list at least one tendon")
    # max_increment is checked against the run's steps, which the tendons may raise (below)
    solver = config.get("solver")
    given = solver.get("max_increment") if isinstance(solver, dict) else None
    static = parse_static(config if given is None else
                          {**config, "solver": {k: v for k, v in solver.items()
                                                if k != "max_increment"}})
    # a tendon's time_function / time_table is read by fe-beam dynamic (noted, not used here)
    timed = ("time_function", "time_table")
    tendons_given = [{k: v for k, v in t.items() if k not in timed} if isinstance(t, dict) else t
                     for t in tendons_given]
    parsed = [parse_tendon(i, t, static.model.length) for i, t in enumerate(tendons_given)]
    for tendon, _ in parsed:
        check_tendon_inside(tendon, static.model.section, static.model.length)
    steps = max([static.stepping.steps] + [s for _, s in parsed if s is not None])
    if steps < 1:
        raise ConfigError(f"[[tendons]] steps must be >= 1, got {steps}")
    check_max_increment(given, steps, static.stepping.steps, static.stepping.adaptive)
    stepping = replace(
        static.stepping,
        steps=steps,
        max_increment=given_max_increment(config, steps),
        min_increment=min(static.stepping.min_increment, 1.0 / steps),
    )
    targets = {key: value for key, value in inverse.items() if value is not None}
    target = None
    if targets:
        if len(targets) != 1:
            raise ConfigError(
                f"[inverse] give exactly one of {', '.join(INVERSE_KEYS)}; got {', '.join(targets)}"
            )
        ((key, value),) = targets.items()
        if len(parsed) != 1:
            raise ConfigError(f"[inverse] {key} needs exactly one tendon, got {len(parsed)}")
        target = InverseTarget(key, float(value))
    return replace(static, tendons=tuple(t for t, _ in parsed), stepping=stepping), target

"""The finger's configuration: the chapter's default finger, the ``[[tendons]]`` and
``[inverse]`` tables, and `parse_finger` (a `StaticConfig` with tendons). Pure Python and numpy:
`fe_beam.analyses.finger` runs it.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace

import numpy as np

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
from fe_beam.model.tendons import ROUTING_SAMPLES, Tendon, check_tendon_inside, on_chain
from fe_beam.timefunctions import Profile, TimeFunctionError, shown

__all__ = [
    "DEFAULT_FINGER",
    "INVERSE_KEYS",
    "TENDON_KEYS",
    "InverseTarget",
    "check_tendon_inside",
    "check_tendons_planar",
    "override_defaults",
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
    "offset_y": Key(NUMBER + (str,), None, "routing anywhere in the section: y offset [m], a "
                    "number or a formula of s and L (e.g. \"0.004*cos(pi*s/(2*L))\"); "
                    "instead of offset_base/offset_tip/path/paths (default 0 with offset_z)"),
    "offset_z": Key(NUMBER + (str,), None, "routing: z offset [m] (along b), a number or a "
                    "formula of s and L (nonzero: needs [model] kinematics = \"spatial\", "
                    "or the 3D solid)"),
    "entry": Key(NUMBER, 0.0, "x where the tendon enters [m]"),
    "anchor": Key(NUMBER, None, "x where it is anchored [m] (default L)"),
    "tension": Key(NUMBER, None, "tension at load factor 1 [N]"),
    "pull_in": Key(NUMBER, None, "pull-in at load factor 1 [m] (tension becomes unknown)"),
    "steps": Key((int,), None, "number of load steps (the largest over tendons and [loads])"),
    "rod": Key((str,), None, "with [[rods]]: the name of the rod the tendon runs along (entry, "
               "anchor, path x from the rod's start, offsets in the rod's own section)"),
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


def override_defaults(command: str, config: dict) -> dict | None:
    """The tables an override of a table the file leaves out applies to
    (`fe_beam.config.schema.apply_overrides`): the chapter's finger for ``fe-beam finger`` and
    every configuration with [[tendons]] (whose left-out tables default to it), else None."""
    if command == "finger" or (isinstance(config, dict) and config.get("tendons")):
        return DEFAULT_FINGER
    return None


def with_defaults(config: dict) -> dict:
    """The user's tables over the chapter's finger (whole tables: a given [section] replaces
    the default one rather than mixing keys of two shapes). A structure of [[rods]] takes no
    defaults of the finger (its rods are given; a tapered section does not apply to them)."""
    if isinstance(config, dict) and "rods" in config:
        return copy.deepcopy(config)
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
    routed = values["offset_y"] is not None or values["offset_z"] is not None
    choices = [linear, values["path"] is not None, values["paths"] is not None, routed]
    if sum(choices) != 1:
        raise ConfigError(f"{where}: give exactly one of offset_base/offset_tip, path, paths or "
                          "offset_y/offset_z")
    routing = None
    if routed:
        routing = _routing(index, name, values, length)
        _check_routing_values(index, name, routing, values["entry"],
                              length if values["anchor"] is None else values["anchor"])
        paths = ()
    elif linear:
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
        routing=routing,
    )
    _wrap(tendon.validate_for, length)
    return tendon, values["steps"]


def _routing(index: int, name: str, values: dict, length: float) -> tuple:
    """(y, z) profiles of offset_y/offset_z (0 where not given), constants {"L": length}."""
    profiles = []
    for key in ("offset_y", "offset_z"):
        value = values[key] if values[key] is not None else 0.0
        try:
            profiles.append(Profile(value, {"L": length}))
        except TimeFunctionError as error:
            raise ConfigError(f"[[tendons]] #{index + 1} {key} ({name!r}): {error}") from None
    return tuple(profiles)


def _check_routing_values(index: int, name: str, routing, entry: float, anchor: float) -> None:
    """ConfigError unless both profiles evaluate to finite numbers at the ROUTING_SAMPLES + 1
    stations from entry to anchor (those of `Tendon.stations`)."""
    for key, profile in zip(("offset_y", "offset_z"), routing, strict=True):
        if profile.is_constant:
            continue
        try:
            for x in np.linspace(entry, anchor, ROUTING_SAMPLES + 1):
                profile(x)
        except TimeFunctionError as error:
            raise ConfigError(
                f"[[tendons]] #{index + 1} {key} ({name!r}): {error} (it must be finite from "
                f"entry {entry:g} to anchor {anchor:g} m)") from None


def _rod_tendon(index: int, given, static: StaticConfig) -> tuple[Tendon, int | None]:
    """A [[tendons]] entry of a structure of [[rods]]: parsed and checked on its rod ``rod``
    (entry, anchor and path x from the rod's start, offsets in the rod's own section), then
    laid on the chain (`fe_beam.model.tendons.on_chain`)."""
    structure = static.model.structure
    names = [rod.name for rod in structure.rods]
    rod_name = given.get("rod") if isinstance(given, dict) else None
    label = repr(given["name"]) if isinstance(given, dict) \
        and isinstance(given.get("name"), str) else f"#{index + 1}"
    if rod_name is None:
        raise ConfigError(f"[[tendons]] {label} needs rod = \"NAME\" with [[rods]] (the rod it "
                          f"runs along: {', '.join(names)})")
    if rod_name not in names:
        raise ConfigError(f"[[tendons]] {label} rod = {shown(rod_name)} names no rod of "
                          f"[[rods]] (rods: {', '.join(names)})")
    rod_index = names.index(rod_name)
    rod = structure.rods[rod_index]
    try:
        tendon, steps = parse_tendon(index, {k: v for k, v in given.items() if k != "rod"},
                                     rod.length)
    except ConfigError as error:
        raise ConfigError(f"[[tendons]] {label} (on rod '{rod_name}', length "
                          f"{rod.length:g} m): {error}") from None
    section = static.model.section
    if rod.section:
        section = replace(section, dims=dict(rod.section))
    try:
        check_tendon_inside(tendon, section, rod.length, index)
    except ConfigError as error:
        raise ConfigError(f"{error} (on rod '{rod_name}', x from its start)") from None
    spatial = getattr(static.model, "kinematics", "planar") == "spatial"
    if tendon.out_of_plane and not spatial:
        check_tendons_planar({"model": {}}, [tendon], index)
    segment = next(seg for seg in structure.chain if seg.rod == rod_index)
    try:
        return on_chain(tendon, segment, rod_name, spatial), steps
    except ValueError as error:
        raise ConfigError(f"[[tendons]] {label} (on rod '{rod_name}'): {error}") from None


def check_tendons_planar(config: dict, tendons, start: int = 0) -> None:
    """ConfigError for a tendon routed out of the plane z = 0 (`Tendon.out_of_plane`) on a
    planar rod (``[model] kinematics`` absent or "planar"); ``tendons[0]`` is the ``[[tendons]]``
    entry ``start`` (0-based)."""
    model = config.get("model")
    kinematics = model.get("kinematics", "planar") if isinstance(model, dict) else "planar"
    if kinematics == "spatial":
        return
    for index, tendon in enumerate(tendons, start):
        if tendon.out_of_plane:
            raise ConfigError(
                f"[[tendons]] #{index + 1} offset_z ({tendon.name!r}): a tendon routed out of "
                f"the x-y plane needs [model] kinematics = \"spatial\" (the rod is "
                f"{shown(kinematics)})")


def parse_finger(config: dict, planar_check: bool = True
                 ) -> tuple[StaticConfig, InverseTarget | None]:
    """(static config with tendons, inverse target or None). ``planar_check`` False lets a
    tendon routed out of the plane through onto a planar rod (the 3D solid parses its tendons
    here and runs without the rod then: `fe_beam.config.solid`)."""
    config = with_defaults(config)
    tendons_given = config.pop("tendons", None)
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
    structure = getattr(static.model, "structure", None)
    if structure is not None:  # a chain of rods: each tendon on its rod
        parsed = [_rod_tendon(i, t, static) for i, t in enumerate(tendons_given)]
    else:
        named = [i for i, t in enumerate(tendons_given)
                 if isinstance(t, dict) and t.get("rod") is not None]
        if named:
            raise ConfigError(f"[[tendons]] #{named[0] + 1} rod names a rod of [[rods]], and "
                              "the configuration has no [[rods]] (a single rod: leave rod out)")
        parsed = [parse_tendon(i, t, static.model.length) for i, t in enumerate(tendons_given)]
        for index, (tendon, _) in enumerate(parsed):
            check_tendon_inside(tendon, static.model.section, static.model.length, index)
        if planar_check:
            check_tendons_planar(config, [t for t, _ in parsed])
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
        if getattr(static.model, "kinematics", "planar") == "spatial":
            raise ConfigError("[inverse] targets the planar tip angle or position; it is not "
                              "available for [model] kinematics = \"spatial\" yet")
        if len(parsed) != 1:
            raise ConfigError(f"[inverse] {key} needs exactly one tendon, got {len(parsed)}")
        target = InverseTarget(key, float(value))
    return replace(static, tendons=tuple(t for t, _ in parsed), stepping=stepping), target

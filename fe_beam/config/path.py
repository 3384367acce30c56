"""The [path] table of `fe-beam path` and the parsing of a path-following configuration (rod,
finger or 3D solid), without the finite-element stack (docs/theory.md, Path following from the
command line)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from fe_beam.config.finger import parse_finger
from fe_beam.config.schema import NUMBER, ConfigError, Key, parse_static, table
from fe_beam.config.solid import parse_solid

__all__ = ["PARAMETERS", "PATH_KEYS", "PathSettings", "parse_path"]

PARAMETERS = ("load_factor", "tension", "end_displacement", "point_force")
BRANCH_SWITCHES = ("none", "positive", "negative", "both")
MAX_PATH_STEPS = 100_000

PATH_KEYS = {
    "parameter": Key((str,), "load_factor", "load_factor | tension | end_displacement | "
                     "point_force (the point forces alone; the other loads held in full)"),
    "max_load_factor": Key(NUMBER, 1.0, "the path ends where |load factor| reaches it (> 0; "
                           "tension: a multiple of the tendon's tension)"),
    "arc_length": Key(NUMBER, 0.1, "load-factor increment of the first arc-length step (> 0)"),
    "max_arc_length": Key(NUMBER, 0.0, "largest arc length as a multiple of the first (0: "
                          "10 times the first)"),
    "max_steps": Key((int,), 100, "largest number of path points (>= 1)"),
    "branch_switch": Key((str,), "none", "none | positive | negative | both: at the "
                         "first bifurcation, follow the bifurcated branch along +/- the critical "
                         "mode (both: + then -)"),
    "tendon": Key((int,), 0, "parameter = tension: index of the tendon (0: the first)"),
    "tolerance": Key(NUMBER, 1e-6, "critical points located to this relative load factor"),
}


@dataclass(frozen=True)
class PathSettings:
    parameter: str = "load_factor"
    max_load_factor: float = 1.0
    arc_length: float = 0.1
    max_arc_length: float = 0.0
    max_steps: int = 100
    branch_switch: str = "none"
    tendon: int = 0
    tolerance: float = 1e-6

    def __post_init__(self):
        if self.parameter not in PARAMETERS:
            raise ConfigError(f"[path] parameter = {self.parameter!r} is not allowed; one of "
                              f"{', '.join(PARAMETERS)}")
        if self.branch_switch not in BRANCH_SWITCHES:
            raise ConfigError(f"[path] branch_switch = {self.branch_switch!r} is not allowed; "
                              f"one of {', '.join(BRANCH_SWITCHES)}")
        for key in ("max_load_factor", "arc_length"):
            value = getattr(self, key)
            if not value > 0:
                raise ConfigError(f"[path] {key} must be > 0; got {value:g}")
        if self.arc_length > self.max_load_factor:
            raise ConfigError(f"[path] arc_length = {self.arc_length:g} is larger than "
                              f"max_load_factor = {self.max_load_factor:g}; give a smaller "
                              "arc_length")
        if self.max_arc_length < 0 or (0 < self.max_arc_length < 1):
            raise ConfigError(f"[path] max_arc_length = {self.max_arc_length:g} must be 0 "
                              "(default: 10) or a multiple >= 1 of the first arc length")
        if not 1 <= self.max_steps <= MAX_PATH_STEPS:
            raise ConfigError(f"[path] max_steps must be an integer from 1 to {MAX_PATH_STEPS}; "
                              f"got {self.max_steps}")
        if not (0 < self.tolerance < 0.1 and math.isfinite(self.tolerance)):
            raise ConfigError(f"[path] tolerance must be in (0, 0.1); got {self.tolerance:g}")

    def arc_length_settings(self, scale: float = 1.0) -> dict:
        """Keyword arguments of `fe_beam.solvers.continuation.ArcLength` (``scale``: parameter units
        per load factor)."""
        first = self.arc_length * scale
        return {"increment": first, "max_load_factor": self.max_load_factor * scale,
                "max_steps": self.max_steps,
                "max_arc_length": first * self.max_arc_length if self.max_arc_length else None}


def parse_path(config: dict):
    """("rod", StaticConfig, PathSettings): [[tendons]] make it a finger (tension-controlled
    tendons only), otherwise the statics configuration; ("solid", SolidConfig, PathSettings)
    with [solid] (load factor only, no stability check). ConfigError (one sentence naming the
    key) for what the path cannot follow."""
    settings = PathSettings(**table(config, "path", PATH_KEYS))
    rest = {key: value for key, value in config.items() if key != "path"}
    if "solid" in rest:
        if "obstacles" in rest:
            raise ConfigError("[[obstacles]] with [solid]: fe-beam path follows the 3D solid "
                              "without contact; run fe-beam solid for the solid in contact, "
                              "or leave out [solid] for the rod's path with obstacles")
        return "solid", _solid(rest, settings), settings
    if rest.get("tendons"):
        static, _ = parse_finger({k: v for k, v in rest.items() if k != "inverse"})
    else:
        static = parse_static(rest)
    tendons = list(static.tendons or ())
    pulled = [t.name for t in tendons if t.controlled_by_pull_in]
    if pulled:
        raise ConfigError(f"[[tendons]] {pulled[0]!r} is pull-in controlled: fe-beam path "
                          "follows tensions only (arc length does not take pull-in control); "
                          "give the tendon a tension instead of pull_in")
    model = static.model
    loads = model.loads
    if static.obstacles:
        _check_contact(static, settings)
    if loads.follower and settings.branch_switch != "none":
        raise ConfigError(f"[path] branch_switch = {settings.branch_switch!r}: with [loads] "
                          "follower = true the stability is not checked, so no bifurcation is "
                          "detected; use branch_switch = \"none\" or dead loads")
    others = (any(loads.tip_force) or loads.tip_moment or any(loads.distributed)
              or any(loads.gravity) or any(f[1] or f[2] for f in loads.point_forces)
              or any(any(m[1:]) for m in loads.point_moments))
    prescribed = loads.end_displacement is not None or loads.end_rotation is not None
    if settings.parameter == "tension":
        if not tendons:
            raise ConfigError("[path] parameter = \"tension\" needs [[tendons]] (none given); "
                              "use parameter = \"load_factor\"")
        if not 0 <= settings.tendon < len(tendons):
            raise ConfigError(f"[path] tendon = {settings.tendon} is not a tendon index; the "
                              f"config has {len(tendons)} tendon(s), indices 0 to "
                              f"{len(tendons) - 1}")
        if not tendons[settings.tendon].tension:
            raise ConfigError(f"[[tendons]] {tendons[settings.tendon].name!r} has no tension: "
                              "parameter = \"tension\" follows multiples of it; give it a "
                              "tension > 0")
    elif settings.parameter == "end_displacement":
        if not prescribed:
            raise ConfigError("[path] parameter = \"end_displacement\" needs [loads] "
                              "end_displacement or end_rotation (none given)")
        if others or any(t.tension for t in tendons):
            raise ConfigError("[path] parameter = \"end_displacement\" scales the prescribed "
                              "end values alone, and [loads] or [[tendons]] also give loads; "
                              "use parameter = \"load_factor\" to scale them all together")
    elif settings.parameter == "point_force":
        if not any(f[1] or f[2] for f in loads.point_forces):
            raise ConfigError("[path] parameter = \"point_force\" needs [loads] point_forces "
                              "with a nonzero force (none given); use parameter = "
                              "\"load_factor\"")
    elif not (others or prescribed or any(t.tension for t in tendons)):
        raise ConfigError("[loads] are all zero: fe-beam path needs a load to follow "
                          "(tip_force, point_forces, point_moments, end_displacement, ... or "
                          "tendon tensions)")
    return "rod", static, settings


def _check_contact(static, settings: PathSettings) -> None:
    """What the rod's path with [[obstacles]] cannot follow: friction (the slip is measured
    from the last accepted point of a load path; the arc-length corrector does not hold the
    stick/slip state), moving obstacles and branch switching (a bifurcation is not told apart
    from a change of the contact state)."""
    rough = [o.name for o in static.obstacles if o.friction > 0]
    if rough:
        raise ConfigError(f"[[obstacles]] {rough[0]!r} has friction > 0: fe-beam path follows "
                          "frictionless contact only; leave friction out, or run fe-beam "
                          "static for frictional contact along a load path")
    moving = [o.name for o in static.obstacles if getattr(o, "motion", None) is not None]
    if moving:
        raise ConfigError(f"[[obstacles]] {moving[0]!r} moves (velocity or position): fe-beam "
                          "path follows fixed obstacles only (the arc length would move it "
                          "with the path parameter); leave its motion out, or run fe-beam "
                          "static for an obstacle moving along the load path")
    if settings.branch_switch != "none":
        raise ConfigError(f"[path] branch_switch = {settings.branch_switch!r} with "
                          "[[obstacles]]: bifurcations are not located in contact (a change of "
                          "the contact state also changes the stability count); use "
                          "branch_switch = \"none\"")


def _solid(rest: dict, settings: PathSettings):
    """The 3D solid's configuration: the load factor scales the tip force and the tendon
    tensions; its stability is counted at every point (sparse inertia; tip force only), but
    critical points are not located and branches not switched."""
    if settings.parameter != "load_factor":
        raise ConfigError(f"[path] parameter = {settings.parameter!r}: the path of the 3D solid "
                          "takes parameter = \"load_factor\" only (tip force and tensions "
                          "scaled together); leave out [solid] for the rod's")
    if settings.branch_switch != "none":
        raise ConfigError(f"[path] branch_switch = {settings.branch_switch!r}: the 3D solid's "
                          "path locates no bifurcation (it only counts unstable directions); "
                          "use branch_switch = \"none\"")
    solid = parse_solid(rest)
    pulled = [name for name, load in zip(solid.tendon_names, solid.tendon_loads, strict=False)
              if load.pull_in]
    if pulled:
        raise ConfigError(f"[[tendons]] {pulled[0]!r} is pull-in controlled: fe-beam path "
                          "follows tensions only (arc length does not take pull-in control); "
                          "give the tendon a tension instead of pull_in")
    if not (any(solid.tip_force) or any(load.tension for load in solid.tendon_loads)):
        raise ConfigError("[loads] tip_force and the tendon tensions are all zero: fe-beam path "
                          "of the 3D solid needs a load to follow")
    return solid

"""The [buckling] table of `fe-beam buckling` and the parsing of a buckling configuration (rod,
finger or 3D solid), without the finite-element stack."""

from __future__ import annotations

from dataclasses import dataclass

from fe_beam.config.finger import parse_finger
from fe_beam.config.schema import NUMBER, ConfigError, Key, parse_static, table
from fe_beam.config.solid import parse_solid

__all__ = ["BUCKLING_KEYS", "BucklingSettings", "parse_buckling"]

BUCKLING_KEYS = {
    "count": Key((int,), 3, "number of buckling load factors and modes (>= 1)"),
    "prestress": Key(NUMBER, 0.0, "load factor of the state linearised about (0: the "
                     "undeformed state)"),
    "max_load_factor": Key(NUMBER, None, "largest load factor up to which the nonlinear path "
                           "is followed to confirm the critical factors (default: max(1, 4 x "
                           "the first, 2 x the count-th linearised factor))"),
}
MAX_BUCKLING_COUNT = 500


@dataclass(frozen=True)
class BucklingSettings:
    """``count`` smallest positive buckling load factors about the state at load factor
    ``prestress`` (multiples of the applied loads), confirmed on the nonlinear path up to
    ``max_load_factor`` (None: a default from the linearised factors)."""

    count: int = 3
    prestress: float = 0.0
    max_load_factor: float | None = None

    def __post_init__(self):
        if not 1 <= self.count <= MAX_BUCKLING_COUNT:
            raise ConfigError(f"[buckling] count must be an integer from 1 to "
                              f"{MAX_BUCKLING_COUNT}; got {self.count}")
        if self.max_load_factor is not None and not self.max_load_factor > self.prestress:
            raise ConfigError(f"[buckling] max_load_factor = {self.max_load_factor:g} must be "
                              f"above the prestress ({self.prestress:g}): it is the largest "
                              "load factor the path is checked to")


def parse_buckling(config: dict) -> tuple[str, object, BucklingSettings]:
    """("rod" | "solid", the command's parsed configuration, settings): [solid] makes it a 3D
    solid analysis (`fe_beam.config.solid.parse_solid`), [[tendons]] a finger (tension-
    controlled tendons only), otherwise the statics configuration."""
    settings = BucklingSettings(**table(config, "buckling", BUCKLING_KEYS))
    rest = {key: value for key, value in config.items() if key != "buckling"}
    if "solid" in rest:
        solid = parse_solid(rest)
        pulled = [name for name, load in zip(solid.tendon_names, solid.tendon_loads, strict=False)
                  if load.tension or load.pull_in]
        if pulled:
            raise ConfigError(f"[[tendons]] {pulled[0]!r}: fe-beam buckling of the 3D solid "
                              "takes the tip force as its load (give the tendons no tension, "
                              "or leave out [solid] for the rod's buckling)")
        if settings.prestress < 0:
            raise ConfigError(f"[buckling] prestress = {settings.prestress:g}: the 3D solid is "
                              "loaded from 0 upwards; give a prestress >= 0")
        if not any(solid.tip_force):
            raise ConfigError("[loads] tip_force is zero: fe-beam buckling of the 3D solid needs "
                              "a tip force to buckle under")
        return "solid", solid, settings
    if rest.get("tendons"):
        static, _ = parse_finger({k: v for k, v in rest.items() if k != "inverse"})
        pulled = [t.name for t in static.tendons if t.controlled_by_pull_in]
        tensioned = [t.name for t in static.tendons if t.tension]
        if tensioned:
            # a tendon that runs along the rod bends it from the first newton of tension: the
            # path has no bifurcation, and the linearised eigenvalues about it are not a
            # buckling load of anything (fe-beam finger's stability check says it is stable)
            raise ConfigError(f"[[tendons]] {tensioned[0]!r} has a tension: fe-beam buckling "
                              "does not take tendon loads (a tendon along the rod bends it "
                              "without a bifurcation, so a linearised buckling load would be "
                              "meaningless); give the tendons no tension and a [loads] load, or "
                              "run fe-beam finger, whose stability check reports unstable "
                              "directions")
        if pulled:
            raise ConfigError(f"[[tendons]] {pulled[0]!r} is pull-in controlled: fe-beam "
                              "buckling needs tension-controlled tendons (give tension, not "
                              "pull_in)")
        return "rod", _loaded(static), settings
    return "rod", _loaded(parse_static(rest)), settings


def _loaded(static):
    """The rod's configuration, if some load or prescribed value is nonzero (ConfigError
    otherwise: nothing to buckle under)."""
    model = static.model
    loads = model.loads
    moment = loads.tip_moment
    given = (any(loads.tip_force) or (any(moment) if isinstance(moment, tuple) else moment)
             or any(loads.distributed)
             or any(loads.gravity) or any(any(f[1:]) for f in loads.point_forces)
             or any(any(m[1:]) for m in loads.point_moments)
             or any(model.supports.prescribed_x0.values())
             or any(model.supports.prescribed_xL.values())
             or any(t.tension for t in static.tendons))
    if not given:
        raise ConfigError("[loads] are all zero: fe-beam buckling needs a load to buckle under "
                          "(tip_force, point_forces, point_moments, end_displacement, ... or "
                          "tendon tensions); "
                          "the load factors are multiples of it")
    return static

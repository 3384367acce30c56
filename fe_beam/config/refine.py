"""``fe-beam refine``'s settings: the ``[refine]`` table and the --levels, --ratio, --quantity
options (`REFINE_ARGUMENTS`), validated into a `RefinementPlan` before anything is solved
(`plan_refinement`; FE-free). The study itself is `fe_beam.analyses.refine`."""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field

from fe_beam.config.finger import parse_finger
from fe_beam.config.schema import parse_static
from fe_beam.config.solid import parse_solid
from fe_beam.errors import ConfigError

__all__ = ["ALL_QUANTITIES", "MAX_LEVELS", "QUANTITIES", "REFINE_ARGUMENTS", "RefinementPlan",
           "SPATIAL_QUANTITIES",
           "add_refine_arguments", "plan_refinement"]

QUANTITIES = ("tip.u", "tip.v", "tip.theta")
#: a spatial rod's quantities (its default): the tip displacement and the distance |r(L)| of the
#: tip from the clamp (r = (L + u, v, w)); a spatial rod has no single tip angle
SPATIAL_QUANTITIES = ("tip.u", "tip.v", "tip.w", "tip.r")
#: every quantity a study may name (the 3D solid reports all of them)
ALL_QUANTITIES = tuple(dict.fromkeys(QUANTITIES + SPATIAL_QUANTITIES))
MAX_LEVELS = 8
MAX_RATIO = 4.0
MAX_ROD_ELEMENTS = 20_000  # finest rod mesh: ~1e5 dofs per load step is already minutes
MAX_SOLID_FACTOR = 8.0  # finest solid mesh_size >= first / 8 (512 times the tetrahedra)
ROD_TABLES_REJECTED = ("time", "initial", "damping", "modes")


@dataclass(frozen=True)
class RefinementPlan:
    """Validated study settings; ``kind`` is "rod", "finger" or "solid"."""

    kind: str
    levels: int
    ratio: float
    quantities: tuple[str, ...]
    base: float  # elements (rod, finger) or mesh_size (solid) of level 0
    length: float | None = None  # rod length, for h = L / elements
    parsed: object = None  # StaticConfig of rods and fingers
    raw: dict = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    @property
    def refined(self) -> str:
        return "solid.mesh_size" if self.kind == "solid" else "mesh.elements"

    def size(self, level: int):
        """elements (int) or mesh_size (float) of a level."""
        if self.kind == "solid":
            return self.base / self.ratio**level
        return int(round(self.base * self.ratio**level))

    def h(self, level: int) -> float:
        return self.size(level) if self.kind == "solid" else self.length / self.size(level)


def _shown(value) -> str:
    return value if isinstance(value, str) and value.strip() else repr(value)


def _parse_levels(text, source: str) -> int:
    value = text
    if isinstance(text, str):
        try:
            value = int(text.strip())
        except ValueError:
            raise ConfigError(
                f"{source} must be an integer from 2 to {MAX_LEVELS}; got {_shown(text)}"
            ) from None
    if isinstance(value, bool) or not isinstance(value, int) or not 2 <= value <= MAX_LEVELS:
        raise ConfigError(f"{source} must be an integer from 2 to {MAX_LEVELS}; got {_shown(text)}")
    return value


def _parse_ratio(text, source: str) -> float:
    value = text
    if isinstance(text, str):
        try:
            value = float(text.strip())
        except ValueError:
            value = None
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not math.isfinite(value)
        or not 1 < value <= MAX_RATIO
    ):
        raise ConfigError(f"{source} must be a number in (1, {MAX_RATIO:g}]; got {_shown(text)}")
    return float(value)


def _parse_quantities(given, source: str, allowed=QUANTITIES, default=QUANTITIES,
                      what: str = "") -> tuple[str, ...]:
    """The quantities named by ``given`` (None: ``default``) among ``allowed``; ``what``
    names the model when a known quantity is not one of ``allowed``."""
    if given is None:
        return default
    items = [given] if isinstance(given, str) else given
    if not isinstance(items, list) or not all(isinstance(i, str) for i in items):
        raise ConfigError(f"{source} must be one of {', '.join(allowed)}; got {given!r}")
    names = [n.strip() for item in items for n in item.split(",") if n.strip()]
    unknown = [n for n in names if n not in allowed]
    if unknown or not names:
        bad = unknown[0] if unknown else given
        if bad in ALL_QUANTITIES and what:
            raise ConfigError(f"{source}: {bad} is not a quantity of {what}; choose from "
                              f"{', '.join(allowed)}")
        raise ConfigError(
            f"{source}: unknown quantity {bad!r}; choose from {', '.join(allowed)}"
        )
    return tuple(dict.fromkeys(names))


def plan_refinement(config: dict, levels=None, ratio=None, quantities=None,
                    solid_parser=parse_solid) -> RefinementPlan:
    """Validate a study before anything is solved; raises `ConfigError` (one sentence).

    CLI values (strings, ``None`` when not given) override an optional ``[refine]`` table
    (``levels``, ``ratio``, ``quantity``) of the configuration. ``solid_parser``: the solid
    driver's validation of a [solid] configuration (`fe_beam.config.solid.parse_solid`; None:
    a driver without one, then [solid] mesh_size must be given).
    """
    config = copy.deepcopy(config)
    settings = config.pop("refine", {})
    if not isinstance(settings, dict):
        raise ConfigError("[refine] must be a table")
    unknown = [k for k in settings if k not in ("levels", "ratio", "quantity")]
    if unknown:
        raise ConfigError(f"[refine] unknown key {unknown[0]!r}; allowed: levels, ratio, quantity")
    if levels is None and "levels" not in settings:
        raise ConfigError(f"--levels is required (an integer from 2 to {MAX_LEVELS})")
    levels = _parse_levels(
        levels if levels is not None else settings["levels"],
        "--levels" if levels is not None else "[refine] levels",
    )
    ratio_source = "--ratio" if ratio is not None else "[refine] ratio"
    ratio = _parse_ratio(ratio if ratio is not None else settings.get("ratio", 2), ratio_source)
    quantity_source = "--quantity" if quantities is not None else "[refine] quantity"
    given = quantities if quantities is not None else settings.get("quantity")
    quantities = _parse_quantities(given, quantity_source, ALL_QUANTITIES)  # the syntax first
    if "solid" in config:
        return _plan_solid(config, levels, ratio, quantities, solid_parser)
    model = config.get("model")
    if isinstance(model, dict) and model.get("kinematics") == "spatial":
        quantities = _parse_quantities(given, quantity_source, SPATIAL_QUANTITIES,
                                       SPATIAL_QUANTITIES, "a spatial rod")
    else:
        quantities = _parse_quantities(given, quantity_source, QUANTITIES, QUANTITIES,
                                       "a planar rod (tip.w and tip.r need [model] kinematics "
                                       "= \"spatial\")")
    present = [name for name in ROD_TABLES_REJECTED if name in config]
    if present:
        raise ConfigError(
            f"refine runs static rod, finger ([[tendons]]) and solid ([solid]) configurations; "
            f"this one has [{present[0]}] (a dynamic or modal analysis)"
        )
    notes = ()
    if "tendons" in config:
        parsed, target = parse_finger(config)
        kind = "finger"
        if target is not None:
            notes = ("[inverse] is ignored: each level runs the forward tension sweep",)
    else:
        parsed, kind = parse_static(config), "rod"
    elements = parsed.model.mesh.elements
    counts = [elements * ratio**k for k in range(levels)]
    structure = getattr(parsed.model, "structure", None)
    if structure is not None and any(abs(ratio**k - round(ratio**k)) > 1e-9 * ratio**k
                                     for k in range(levels)):
        raise ConfigError(f"--ratio {ratio:g} with [[rods]]: every rod's elements are multiplied"
                          " by ratio**k, which must be an integer; use an integer ratio")
    if any(abs(n - round(n)) > 1e-9 * n for n in counts):
        raise ConfigError(
            f"--ratio {ratio:g} with [mesh] elements = {elements} gives a fractional number of "
            f"elements within {levels} levels; use an integer ratio or another elements count"
        )
    if round(counts[-1]) > MAX_ROD_ELEMENTS:
        raise ConfigError(
            f"--levels {levels} with --ratio {ratio:g} needs {round(counts[-1])} elements on the "
            f"finest level (from [mesh] elements = {elements}; at most {MAX_ROD_ELEMENTS})"
        )
    return RefinementPlan(
        kind,
        levels,
        ratio,
        quantities,
        elements,
        length=parsed.model.length,
        parsed=parsed,
        raw=config,
        notes=notes,
    )


def _plan_solid(config: dict, levels: int, ratio: float, quantities,
                solid_parser) -> RefinementPlan:
    """Solid levels divide ``[solid] mesh_size`` (the driver's default when not given) by
    ratio**k; the driver's own validation runs on the first and the finest level up front."""
    factor = ratio ** (levels - 1)
    if factor > MAX_SOLID_FACTOR * (1 + 1e-12):
        raise ConfigError(
            f"--levels {levels} with --ratio {ratio:g} refines the mesh size {factor:g} times "
            f"(at most {MAX_SOLID_FACTOR:g}: the tetrahedra grow with its cube)"
        )
    if not isinstance(config["solid"], dict):
        raise ConfigError("[solid] must be a table")
    parse = solid_parser
    size = config["solid"].get("mesh_size")
    if parse is not None:
        size = parse(config).sizes.size  # fills the default mesh_size
    if isinstance(size, bool) or not isinstance(size, (int, float)) or not size > 0:
        raise ConfigError(
            f"[solid] mesh_size must be a number > 0 to refine (level k uses mesh_size / "
            f"ratio**k); got {size!r}"
        )
    if not math.isfinite(size):
        raise ConfigError(f"[solid] mesh_size must be finite; got {size!r}")
    config["solid"] = dict(config["solid"], mesh_size=float(size))
    if parse is not None:
        finest = copy.deepcopy(config)
        finest["solid"]["mesh_size"] = size / factor
        try:
            parse(finest)  # e.g. the driver's limit on the number of tetrahedra
        except ConfigError as error:
            raise ConfigError(
                f"the finest level ({levels} levels, ratio {ratio:g}) fails: {error}"
            ) from None
    return RefinementPlan("solid", levels, ratio, quantities, float(size), raw=config)


# --- command line --------------------------------------------------------------------------------
#: The options of ``fe-beam refine`` beyond CONFIG, --out, --set and --quiet, as (flags,
#: argparse keywords): parsed as text and validated by `plan_refinement`, so mistakes are
#: one-line errors.
REFINE_ARGUMENTS = (
    (("--levels",), {"default": None, "metavar": "N",
                     "help": f"number of meshes, 2 to {MAX_LEVELS} (3 or more give an observed "
                             "order)"}),
    (("--ratio",), {"default": None, "metavar": "R",
                    "help": "refinement ratio between levels (default 2): elements * R**k or "
                            "mesh_size / R**k"}),
    (("--quantity",), {"action": "append", "default": None, "metavar": "KEY",
                       "help": f"quantity of interest, one of {', '.join(ALL_QUANTITIES)} "
                               f"(default: {', '.join(QUANTITIES)}; a spatial rod: "
                               f"{', '.join(SPATIAL_QUANTITIES)}; tip.r = |r(L)|)"}),
)


def add_refine_arguments(parser) -> None:
    """Add `REFINE_ARGUMENTS` to an argparse parser."""
    for flags, keywords in REFINE_ARGUMENTS:
        parser.add_argument(*flags, **keywords)

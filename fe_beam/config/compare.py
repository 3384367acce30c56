"""The configuration of ``fe-beam compare``: the ``[compare]`` table (the sweep and the rod
laws) over a ``fe-beam solid`` configuration, and the rod configuration of each sweep point
(`rod_at`). Pure Python: `fe_beam.analyses.compare` runs the sweep.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, replace

from fe_beam.config.schema import NUMBER, ConfigError, Key, StaticConfig, table
from fe_beam.config.solid import SolidConfig, parse_solid, spatial_rod
from fe_beam.model.spatial import SPATIAL_LAWS

__all__ = [
    "COMPARE_KEYS",
    "MEASURE",
    "RODS",
    "SPATIAL_RODS",
    "THRESHOLDS",
    "CompareConfig",
    "matched_law",
    "parse_compare",
    "rod_at",
]

RODS = ("hyperelastic", "nonstandard", "reissner")
#: the laws of the spatial rod (`fe_beam.model.spatial.SPATIAL_LAWS`)
SPATIAL_RODS = SPATIAL_LAWS
COMPARE_KEYS = {
    "tensions": Key((list,), None, "increasing tensions [N] of the one tension-controlled tendon"),
    "load_factors": Key((list,), None, "increasing load factors in (0, 1]"),
    "steps": Key((int,), None, "n: the load factors k / n, k = 1 .. n (default 5)"),
    "laws": Key((list,), list(RODS), "rod laws compared with the solid: hyperelastic (the section "
                "law of the solid's material), nonstandard, reissner"),
}
THRESHOLDS = (0.01, 0.05)
MEASURE = (
    "max over the backbone stations x of |r_rod(x) - r_solid(x)| / L, r = deformed centroid of "
    "the reference section x"
)


@dataclass(frozen=True)
class CompareConfig:
    """The solid configuration at load factor 1, the sweep's load factors and the rod laws."""

    solid: SolidConfig
    load_factors: tuple[float, ...]
    laws: tuple[str, ...]
    tension_axis: bool  # True when the sweep is over the tension of a single tendon
    #: set-up notes (the summary's ``notes``): e.g. the laws a spatial rod leaves out
    notes: tuple[str, ...] = ()

    @property
    def spatial(self) -> bool:
        """The rod is the spatial one (``[model] kinematics = "spatial"``)."""
        return getattr(self.solid.rod.model, "kinematics", "planar") == "spatial"


def _increasing(key: str, values, upper: float | None = None) -> tuple[float, ...]:
    ok = isinstance(values, list) and len(values) >= 1 and all(
        isinstance(v, NUMBER) and not isinstance(v, bool) and math.isfinite(v) for v in values
    )
    if not ok:
        raise ConfigError(f"[compare] {key} must be a non-empty list of numbers; got {values!r}")
    values = [float(v) for v in values]
    if values[0] <= 0 or any(b <= a for a, b in zip(values, values[1:])):
        raise ConfigError(f"[compare] {key} must be > 0 and strictly increasing; got {values!r}")
    if upper is not None and values[-1] > upper * (1 + 1e-12):
        raise ConfigError(f"[compare] {key} must be <= {upper:g}; got {values!r}")
    return tuple(values)


def parse_compare(raw: dict) -> CompareConfig:
    """Validate a ``fe-beam compare`` configuration (raises ConfigError naming the key)."""
    if not isinstance(raw, dict):
        raise ConfigError("the configuration must be a table")
    compare = table(raw, "compare", COMPARE_KEYS)
    given = [k for k in ("tensions", "load_factors", "steps") if compare[k] is not None]
    if len(given) > 1:
        raise ConfigError(f"[compare] give one of tensions, load_factors or steps; got "
                          f"{' and '.join(given)}")
    laws = compare["laws"]
    if not laws or any(law not in RODS for law in laws) or len(set(laws)) != len(laws):
        raise ConfigError(
            f"[compare] laws must be a list of distinct names from {', '.join(RODS)}; got {laws!r}"
        )
    notes = []
    if spatial_rod(raw) and "hyperelastic" in laws:
        if "laws" in (raw.get("compare") or {}):
            raise ConfigError(
                "[compare] laws: the hyperelastic section law is planar only for now, so the "
                "spatial rod ([model] kinematics = \"spatial\") compares with "
                f"{' and '.join(SPATIAL_RODS)}; got {laws!r}")
        laws = [law for law in laws if law in SPATIAL_RODS]
        notes.append("[compare] laws: the spatial rod is compared with the non-standard and "
                     "Reissner laws (the hyperelastic section law is planar only for now)")
    raw = copy.deepcopy(raw)
    tension_axis = False
    if compare["tensions"] is not None:
        tensions = _increasing("tensions", compare["tensions"])
        tendons = raw.get("tendons")
        if not isinstance(tendons, list) or len(tendons) != 1 or not isinstance(tendons[0], dict):
            raise ConfigError("[compare] tensions needs exactly one [[tendons]] entry")
        if tendons[0].get("pull_in") is not None:
            raise ConfigError("[compare] tensions needs a tension-controlled tendon "
                              "(the [[tendons]] entry gives pull_in)")
        tendons[0]["tension"] = tensions[-1]
        factors = tuple(t / tensions[-1] for t in tensions)
        tension_axis = True
    elif compare["load_factors"] is not None:
        factors = _increasing("load_factors", compare["load_factors"], upper=1.0)
    else:
        steps = 5 if compare["steps"] is None else compare["steps"]
        if steps < 1:
            raise ConfigError(f"[compare] steps must be an integer >= 1; got {steps!r}")
        factors = tuple((k + 1) / steps for k in range(steps))
    solid = parse_solid(raw, planar_contact_rod=True)
    if solid.rod is None and solid.tip_force[2] != 0:
        raise ConfigError("[loads] tip_force must be planar ([Px, Py]) for fe-beam compare with "
                          "the planar rod (or set [model] kinematics = \"spatial\"); got "
                          f"{list(solid.tip_force)!r}")
    if solid.rod is None:  # a tendon out of the x-y plane
        raise ConfigError(f"fe-beam compare: {solid.rod_note.removeprefix('no rod comparison: ')}"
                          " (the rod is planar)")
    tension_axis = tension_axis or (
        len(solid.rod.tendons) == 1 and not solid.rod.tendons[0].controlled_by_pull_in
    )
    return CompareConfig(solid, factors, tuple(laws), tension_axis, tuple(notes))


def matched_law(solid: SolidConfig):
    """The 3D law of the solid as the rod's hyperelastic section law: the same constants, and
    the volumetric energy the solid's formulation uses (the u-p formulation's is quadratic)."""
    law = solid.material
    if solid.formulation_name == "mixed-up" and law.volumetric != "quadratic":
        law = replace(law, volumetric="quadratic")
    return law


def rod_at(static: StaticConfig, law: str, factor: float, solid: SolidConfig | None = None
           ) -> StaticConfig:
    """The rod configuration with the given law and all loads scaled by ``factor``; the
    ``hyperelastic`` law is the section law of ``solid``'s material (`matched_law`)."""
    model = static.model
    loads = replace(model.loads, tip_force=tuple(factor * f for f in model.loads.tip_force))
    if law == "hyperelastic" and solid is not None:
        options = replace(model.options, law=law, hyperelastic=matched_law(solid))
    else:
        options = replace(model.options, law=law)
    model = replace(model, options=options, loads=loads)
    tendons = tuple(
        replace(t, pull_in=factor * t.pull_in) if t.controlled_by_pull_in
        else replace(t, tension=factor * t.tension)
        for t in static.tendons
    )
    return replace(static, model=model, tendons=tendons)

"""The ``[design]`` table of ``fe-beam design`` (`parse_design`): FE-free checks, a bad table is
a ConfigError (exit 2, one sentence). The optimisation is `fe_beam.analyses.design`."""

from __future__ import annotations

import copy
import math
import re
import shlex
from dataclasses import dataclass, field

import numpy as np

from fe_beam.config.finger import parse_finger, with_defaults
from fe_beam.config.schema import parse_static
from fe_beam.errors import ConfigError

__all__ = ["DesignProblem", "parse_design", "reproduce_command", "with_value"]

OBJECTIVES = ("tip_pose", "backbone", "tension", "grasp_force")
DESIGN_KEYS = ("variables", "bounds", "objective", "target", "points", "tip_angle",
               "max_fibre_strain", "max_iterations", "tolerance")
#: what a grasp_force target may name: the force's magnitude or its normal part [N]
GRASP_COMPONENTS = ("force", "normal")
#: the grasp force's default tolerance, relative to the target
GRASP_RTOL = 1e-3
MATERIAL_KEYS = ("E", "nu", "G", "rho")
SECTION_DIMS = {"rectangle": ("b", "h"), "circle": ("d",), "tube": ("d", "t"),
                "t-section": ("b", "h", "tf", "tw"), "custom": ("A", "I", "I3", "I4")}
FORCE_LIKE = re.compile(r"^(tendons\.\d+\.tension|loads\.tip_moment|loads\.tip_force\.[01])$")
POSITIVE = re.compile(r"^(section\.|material\.(E|G)$)")


@dataclass
class DesignProblem:
    """A parsed [design] table."""

    variables: list[str]
    bounds: np.ndarray  # (n, 2)
    objective: str
    initial: np.ndarray
    target: dict = field(default_factory=dict)
    points: list = field(default_factory=list)
    tip_angle: float | None = None
    max_fibre_strain: float | None = None
    max_iterations: int = 100
    #: grasp_force: the allowed |grasp force - target| [N]
    tolerance: float | None = None

    @property
    def force_variable(self) -> int | None:
        for i, key in enumerate(self.variables):
            if FORCE_LIKE.match(key):
                return i
        return None


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(
        value)


def _initial_value(config: dict, key: str):
    """The configuration's value of a design variable (after the finger's defaults), or a
    ConfigError naming the key: unknown key, or a key whose value is not a number."""
    parts = key.split(".")
    head = parts[0]
    where = f"[design] variables: {key!r}"
    if head == "material" and len(parts) == 2:
        material = config.get("material", {})
        if parts[1] not in MATERIAL_KEYS:
            raise ConfigError(f"{where} is not a design variable; material variables are "
                              f"{', '.join('material.' + k for k in MATERIAL_KEYS)}")
        if parts[1] not in material:
            raise ConfigError(f"{where} is not set in [material] (give it there first)")
        return material[parts[1]]
    if head == "section" and len(parts) == 2:
        section = config.get("section", {})
        shape = section.get("shape", "rectangle")
        name = parts[1]
        dims = SECTION_DIMS.get(shape, ())
        if name == "shape":
            raise ConfigError(f"{where} is not numeric (a section shape): design variables "
                              "must be numbers")
        base = name[:-4] if name.endswith("_tip") else name
        if base not in dims:
            raise ConfigError(f"{where} is not a dimension of section shape {shape!r} "
                              f"(dimensions: {', '.join(dims)} and their _tip values)")
        if name in section:
            return section[name]
        if name.endswith("_tip") and base in section:
            return section[base]  # an untapered dimension starts a taper from its value
        raise ConfigError(f"{where} is not set in [section]")
    if head == "loads" and len(parts) in (2, 3):
        loads = config.get("loads", {})
        if key == "loads.tip_moment":
            return loads.get("tip_moment", 0.0)
        if len(parts) == 3 and parts[1] in ("tip_force", "distributed") and parts[2] in ("0",
                                                                                          "1"):
            return list(loads.get(parts[1], [0.0, 0.0]))[int(parts[2])]
        if len(parts) == 2 and parts[1] in ("follower", "steps"):
            raise ConfigError(f"{where} is not a numeric design variable")
        raise ConfigError(f"{where} is not a design variable; load variables are "
                          "loads.tip_moment, loads.tip_force.0/1, loads.distributed.0/1")
    if head == "tendons" and len(parts) >= 3:
        tendons = config.get("tendons", [])
        if not parts[1].isdigit() or int(parts[1]) >= len(tendons):
            raise ConfigError(f"{where}: the tendon index must be 0 .. {len(tendons) - 1}")
        tendon = tendons[int(parts[1])]
        what = parts[2]
        if what in ("tension", "pull_in", "offset_base", "offset_tip") and len(parts) == 3:
            if what not in tendon:
                raise ConfigError(f"{where} is not set for that tendon")
            return tendon[what]
        if what == "path" and len(parts) == 4 and parts[3].isdigit():
            path = tendon.get("path")
            if not isinstance(path, list) or int(parts[3]) >= len(path):
                raise ConfigError(f"{where}: the tendon has no path point {parts[3]} "
                                  "(path = [[x, offset], ...])")
            return path[int(parts[3])][1]
        if what in ("name", "entry", "anchor", "steps", "paths"):
            raise ConfigError(f"{where} is not a numeric design variable (a tendon's "
                              "tension, pull_in, offset_base, offset_tip or path.<point>)")
        raise ConfigError(f"{where} is not a design variable (a tendon has tension, "
                          "pull_in, offset_base, offset_tip and path.<point>)")
    if head == "rods":
        rods = config.get("rods") if isinstance(config.get("rods"), list) else []
        index = rod_entry(rods, parts[1]) if len(parts) > 1 else None
        if index is None or len(parts) != 4 or parts[2] != "section":
            raise ConfigError(f"{where} is not a design variable of the structure; a rod's "
                              "variables are rods.<name or index>.section.<dimension> (rods: "
                              f"{', '.join(str(r.get('name')) for r in rods)})")
        section = config.get("section", {}) | (rods[index].get("section") or {})
        dims = SECTION_DIMS.get(section.get("shape", "rectangle"), ())
        if parts[3] not in dims or parts[3] not in section:
            raise ConfigError(f"{where}: {parts[3]!r} is not a dimension of the rod's section "
                              f"(dimensions: {', '.join(d for d in dims if d in section)})")
        return section[parts[3]]
    if head in ("model", "mesh", "beam", "supports", "solver", "output"):
        raise ConfigError(f"{where} is not a numeric design variable: the design varies "
                          "section.*, material.*, loads.* and tendons.<i>.* values")
    raise ConfigError(f"{where} is not a design variable; use section.<dim>[_tip], "
                      "material.E/nu/G/rho, loads.tip_moment, loads.tip_force.<k>, "
                      "tendons.<i>.tension/offset_base/offset_tip/path.<j>")


def parse_design(config: dict) -> tuple[DesignProblem, dict]:
    """The [design] table (FE-free checks) and the configuration without it."""
    given = config.get("design")
    if not isinstance(given, dict):
        raise ConfigError("fe-beam design needs a [design] table (variables, bounds, "
                          "objective)")
    unknown = [k for k in given if k not in DESIGN_KEYS]
    if unknown:
        raise ConfigError(f"[design] unknown key {unknown[0]!r}; allowed: "
                          f"{', '.join(DESIGN_KEYS)}")
    rest = {k: v for k, v in config.items() if k != "design"}
    if "tendons" in rest:
        merged = with_defaults(rest)
    else:
        merged = rest
    variables = given.get("variables")
    if not (isinstance(variables, list) and variables
            and all(isinstance(v, str) for v in variables)):
        raise ConfigError("[design] variables must be a non-empty list of keys such as "
                          "[\"section.h_tip\", \"tendons.0.offset_tip\"]")
    if len(set(variables)) != len(variables):
        raise ConfigError("[design] variables must be distinct")
    initial = []
    for key in variables:
        value = _initial_value(merged, key)
        if not _is_number(value):
            raise ConfigError(f"[design] variables: {key!r} is not numeric (its value is "
                              f"{value!r}): design variables must be numbers")
        initial.append(float(value))
    bounds = given.get("bounds")
    if isinstance(bounds, dict):  # {variable = [low, high], ...}
        missing = [v for v in variables if v not in bounds]
        extra = [k for k in bounds if k not in variables]
        if missing or extra:
            what = f"missing {missing[0]!r}" if missing else f"{extra[0]!r} is not a variable"
            raise ConfigError(f"[design] bounds: give one [low, high] for each variable "
                              f"({what})")
        bounds = [bounds[v] for v in variables]
    ok = (isinstance(bounds, list) and len(bounds) == len(variables)
          and all(isinstance(b, list) and len(b) == 2 and all(_is_number(x) for x in b)
                  for b in bounds))
    if not ok:
        raise ConfigError(f"[design] bounds must be one [low, high] pair of numbers per "
                          f"variable ({len(variables)} pairs)")
    bounds = np.array(bounds, dtype=float)
    for key, (low, high), value in zip(variables, bounds, initial, strict=True):
        if not low < high:
            raise ConfigError(f"[design] bounds of {key!r}: low {low:g} must be < high "
                              f"{high:g}")
        positive = POSITIVE.match(key) or key.startswith("rods.")
        if positive and not (low > 0 or key == "section.I3"):
            raise ConfigError(f"[design] bounds of {key!r} must be > 0 (got low {low:g})")
        if not low <= value <= high:
            raise ConfigError(f"[design] the configuration's {key} = {value:g} lies outside "
                              f"its bounds [{low:g}, {high:g}]")
    objective = given.get("objective")
    if objective not in OBJECTIVES:
        raise ConfigError(f"[design] objective must be one of {', '.join(OBJECTIVES)}; got "
                          f"{objective!r}")
    if "rods" in rest:
        _check_structure_design(rest, variables, objective, given)
    problem = DesignProblem(list(variables), bounds, objective, np.array(initial))
    if rest.get("obstacles") is not None and objective != "grasp_force":
        raise ConfigError(f"[design] objective = {objective!r} is not available with "
                          "[[obstacles]] (its gradients do not see contact); with obstacles "
                          "the design targets objective = \"grasp_force\"")
    if objective != "grasp_force" and "tolerance" in given:
        raise ConfigError("[design] tolerance is the grasp force's tolerance [N]: it goes with "
                          "objective = \"grasp_force\" only")
    if objective == "tip_pose":
        target = given.get("target")
        if not (isinstance(target, dict) and target
                and all(k in ("u", "v", "theta") and _is_number(v) for k, v in target.items())):
            raise ConfigError("[design] objective = \"tip_pose\" needs target = {u = .., v = "
                              ".., theta = ..} (any of them, numbers)")
        problem.target = {k: float(v) for k, v in target.items()}
    elif objective == "backbone":
        points = given.get("points")
        if not (isinstance(points, list) and points and all(
                isinstance(p, list) and len(p) == 3 and all(_is_number(x) for x in p)
                for p in points)):
            raise ConfigError("[design] objective = \"backbone\" needs points = [[s, x, y], "
                              "...] (reference arclength s, target position x, y; numbers)")
        problem.points = [tuple(float(x) for x in p) for p in points]
    elif objective == "grasp_force":
        _parse_grasp(problem, given, rest)
    else:
        angle = given.get("tip_angle")
        if not _is_number(angle):
            raise ConfigError("[design] objective = \"tension\" needs tip_angle = <number> "
                              "(rad), the tip angle to hold")
        forces = [v for v in variables if FORCE_LIKE.match(v)]
        if len(forces) != 1:
            raise ConfigError("[design] objective = \"tension\" minimises one force-like "
                              "variable: exactly one of tendons.<i>.tension, loads.tip_moment, "
                              f"loads.tip_force.<k> must be among the variables (got "
                              f"{len(forces)})")
        problem.tip_angle = float(angle)
    strain = given.get("max_fibre_strain")
    if strain is not None:
        if not (_is_number(strain) and strain > 0):
            raise ConfigError(f"[design] max_fibre_strain must be a number > 0, got {strain!r}")
        problem.max_fibre_strain = float(strain)
    iterations = given.get("max_iterations", 100)
    if not (isinstance(iterations, int) and not isinstance(iterations, bool)
            and 1 <= iterations <= 10000):
        raise ConfigError(f"[design] max_iterations must be an integer from 1 to 10000, got "
                          f"{iterations!r}")
    problem.max_iterations = iterations
    return problem, rest


def _parse_grasp(problem: DesignProblem, given: dict, rest: dict) -> None:
    """objective = "grasp_force": target = {obstacle = "<name>", force = F} (|the force the
    obstacle exerts on the rod| at load factor 1 [N]) or {obstacle = .., normal = F} (its
    normal part, without friction), one design variable, tolerance [N] > 0 (default
    GRASP_RTOL x F); the configuration parsed at both bounds (a tendon out of the section or
    an obstacle in the undeformed rod at a bound is a ConfigError naming the bound)."""
    obstacles = rest.get("obstacles")
    if not isinstance(obstacles, list) or not obstacles:
        raise ConfigError("[design] objective = \"grasp_force\" needs [[obstacles]]: the "
                          "grasp force is the force an obstacle exerts on the rod")
    names = [o.get("name", f"obstacle{i + 1}") if isinstance(o, dict) else f"obstacle{i + 1}"
             for i, o in enumerate(obstacles)]
    target = given.get("target")
    usage = ("[design] objective = \"grasp_force\" needs target = {obstacle = \"<name>\", "
             "force = <N>} (or normal = <N>: the normal part alone), the force > 0")
    if not isinstance(target, dict):
        raise ConfigError(usage)
    unknown = [k for k in target if k not in ("obstacle",) + GRASP_COMPONENTS]
    components = [k for k in GRASP_COMPONENTS if k in target]
    if unknown or len(components) != 1:
        raise ConfigError(f"{usage}; got target keys {', '.join(map(repr, target)) or 'none'}")
    component = components[0]
    value = target[component]
    if not (_is_number(value) and value > 0):
        raise ConfigError(f"[design] target {component} must be a number > 0 [N] (the grasp "
                          f"force to reach); got {value!r}")
    name = target.get("obstacle")
    if name is None:
        if len(names) != 1:
            raise ConfigError(f"[design] target obstacle must name one of the [[obstacles]] "
                              f"({', '.join(map(repr, names))})")
        name = names[0]
    if name not in names:
        raise ConfigError(f"[design] target obstacle {name!r} is not an obstacle; the "
                          f"[[obstacles]] are {', '.join(map(repr, names))}")
    if len(problem.variables) != 1:
        raise ConfigError(f"[design] objective = \"grasp_force\" takes exactly one variable "
                          f"(a bracketing root solve on the converged contact states); got "
                          f"{len(problem.variables)}")
    if given.get("max_fibre_strain") is not None:
        raise ConfigError("[design] max_fibre_strain is not available with objective = "
                          "\"grasp_force\" (a root solve of one variable has no room for a "
                          "constraint); leave it out")
    tolerance = given.get("tolerance", GRASP_RTOL * value)
    if not (_is_number(tolerance) and 0 < tolerance < value):
        raise ConfigError(f"[design] tolerance must be a force [N] > 0 and below the target "
                          f"{value:g} N; got {tolerance!r}")
    problem.target = {"obstacle": name, "index": names.index(name), "component": component,
                      "value": float(value)}
    problem.tolerance = float(tolerance)
    key = problem.variables[0]
    finger = bool(rest.get("tendons"))
    base = with_defaults(rest) if finger else rest  # the finger's default tables written out
    for bound, edge in zip(problem.bounds[0], ("low", "high"), strict=True):
        changed = with_value(base, key, float(bound))
        try:
            parse_finger(changed) if finger else parse_static(changed)
        except ConfigError as error:
            raise ConfigError(f"[design] bounds of {key!r}: at its {edge} bound {bound:g}, "
                              f"{error}") from None


def _check_structure_design(rest: dict, variables, objective, given: dict) -> None:
    """What a design of a structure of [[rods]] supports: objective = "tip_pose" of the
    chain's last end, variables rods.<name>.section.<dim> or (when no rod has its own
    section or material table) the top-level section.<dim> and material.*."""
    if objective != "tip_pose":
        raise ConfigError(f"[design] objective = {objective!r} with [[rods]] is not supported "
                          "yet; a structure's design takes objective = \"tip_pose\" (the "
                          "chain's last end)")
    if given.get("max_fibre_strain") is not None:
        raise ConfigError("[design] max_fibre_strain with [[rods]] is not supported yet")
    own = any(isinstance(rod, dict) and (rod.get("section") or rod.get("material"))
              for rod in rest["rods"])
    by_rod = any(v.split(".")[0] == "rods" for v in variables)
    for key in variables:
        head = key.split(".")[0]
        if head == "loads" or head == "tendons":
            raise ConfigError(f"[design] variables: {key!r} with [[rods]] is not supported "
                              "yet (a structure's variables are rods.<name>.section.<dim>, "
                              "section.<dim> and material.*)")
        if head in ("section", "material") and (own or by_rod):
            raise ConfigError(f"[design] variables: {key!r} is a top-level value, which the "
                              "rods with their own section or material (or a rods.<name> "
                              "variable) do not take; use rods.<name>.section.<dim>")


def rod_entry(rods: list, ident: str) -> int | None:
    """The index in [[rods]] of the rod named ``ident`` (or of index ``ident``), else None."""
    if ident.isdigit():
        return int(ident) if int(ident) < len(rods) else None
    return next((i for i, rod in enumerate(rods) if isinstance(rod, dict)
                 and rod.get("name") == ident), None)


def with_value(config: dict, key: str, value: float) -> dict:
    """A copy of the configuration's tables (without [design]) with the design variable
    ``key`` (a key `_initial_value` accepts) set to ``value``."""
    changed = {k: (copy.deepcopy(v) if k in ("section", "material", "loads", "tendons") else v)
               for k, v in config.items()}
    parts = key.split(".")
    head = parts[0]
    if head in ("section", "material"):
        changed.setdefault(head, {})[parts[1]] = value
    elif head == "loads":
        loads = changed.setdefault("loads", {})
        if len(parts) == 2:
            loads[parts[1]] = value
        else:
            pair = list(loads.get(parts[1], [0.0, 0.0]))
            pair[int(parts[2])] = value
            loads[parts[1]] = pair
    elif head == "rods":
        rods = copy.deepcopy(changed["rods"])
        rod = rods[rod_entry(rods, parts[1])]
        rod["section"] = dict(rod.get("section") or {}) | {parts[3]: value}
        changed["rods"] = rods
    elif head == "tendons":
        if not changed.get("tendons"):  # the chapter's default tendon
            changed["tendons"] = with_defaults(changed)["tendons"]
        tendon = changed["tendons"][int(parts[1])]
        if parts[2] == "path":
            path = [list(p) for p in tendon["path"]]
            path[int(parts[3])][1] = value
            tendon["path"] = path
        else:
            tendon[parts[2]] = value
    else:
        raise KeyError(key)
    return changed


def reproduce_command(config: dict, variables: dict, options: dict | None = None) -> str:
    """The command line that re-runs a design's answer: ``fe-beam finger`` (a configuration
    with [[tendons]]) or ``fe-beam static`` on the design's file, with the run's own ``--set``
    overrides (``options["overrides"]``, those of [design] and of the variables left out)
    and one ``--set key=value`` per design variable at its optimum (full precision; an
    override of a table the file leaves out applies to its default,
    `fe_beam.config.schema.apply_overrides`)."""
    options = options or {}
    command = "finger" if config.get("tendons") else "static"
    path = options.get("config_path") or "CONFIG.toml"
    if path == "<dict>":
        path = "CONFIG.toml"
    words = ["fe-beam", command, str(path)]
    for assignment in options.get("overrides") or []:
        key = assignment.split("=", 1)[0].strip()
        if key.split(".")[0] == "design" or key in variables:
            continue
        words += ["--set", assignment]
    for key, value in variables.items():
        words += ["--set", f"{key}={float(value)!r}"]
    return shlex.join(words)

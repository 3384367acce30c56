"""[[rods]], [[joints]] and [[bodies]]: a structure of rods (issue 29) -> `Structure`.

The top-level tables ([section], [material], [model], [mesh], [loads] gravity and distributed)
apply to every rod; a rod's own ``mesh`` replaces [mesh] for it. This slice solves planar serial
chains of rods joined rigidly (`fe_beam.model.structure`); what it does not solve yet is
refused with one sentence (exit 2).
"""

from __future__ import annotations

from fe_beam.config.keys import NUMBER, REQUIRED, SCHEMA, Key, _checked, _wrap
from fe_beam.errors import ConfigError
from fe_beam.model.beam import point_rows
from fe_beam.model.spatial import spatial_support_components
from fe_beam.model.structure import Body, Joint, Rod, Structure
from fe_beam.timefunctions import shown

__all__ = ["BODY_KEYS", "JOINT_KEYS", "ROD_KEYS", "STRUCTURE_TABLES", "is_structure",
           "parse_structure"]

STRUCTURE_TABLES = ("rods", "joints", "bodies")
#: the commands that run a structure of rods in this version
STRUCTURE_COMMANDS = ("static", "path", "modes", "buckling", "dynamic", "refine", "design",
                      "calibrate")
#: the commands that run a spatial structure in this version
SPATIAL_STRUCTURE_COMMANDS = ("static", "path", "modes", "buckling", "dynamic", "refine")
#: the commands that run a structure with ties (pin, ball, T junctions, loops, pieces)
TIED_COMMANDS = ("static", "path", "modes", "buckling")
PLANAR_ONLY = tuple(c for c in STRUCTURE_COMMANDS if c not in SPATIAL_STRUCTURE_COMMANDS)

ROD_KEYS = {
    "name": Key((str,), REQUIRED, "the rod's name (joints name its ends as \"name:start\", "
                "\"name:end\")"),
    "start": Key((list,), None, "reference position of the rod's start [x, y] (spatial: "
                 "[x, y, z]) [m] (default: the origin)"),
    "direction": Key((list,), None, "unit tangent [x, y] (spatial: [x, y, z]) of the reference "
                     "axis (default: along x)"),
    "length": Key(NUMBER, REQUIRED, "the rod's length [m]"),
    "mesh": Key((dict,), None, "{elements, degree} of this rod (default: [mesh])"),
    "supports": Key((dict,), {}, "{x0, xL = clamped | pinned | roller | free} at the rod's "
                    "start and end (default free); spatial: clamped | pinned | free or a list "
                    "of world components from u, v, w, theta_x, theta_y, theta_z"),
    "loads": Key((dict,), {}, "{point_forces = [[x, Px, Py], ...], point_moments = [[x, M], "
                 "...]} (spatial: [[x, Px, Py, Pz]], [[x, Mx, My, Mz]]), x the arc length from "
                 "the rod's start, world axes"),
    "section": Key((dict,), None, "the rod's section (default: [section])"),
    "material": Key((dict,), None, "the rod's material (default: [material])"),
    "model": Key((dict,), None, "the rod's law and constraint (default: [model])"),
    # the interface of issue 29 that this version refuses with a sentence
    "normal": Key((list,), None, "spatial: the section's d2 (h direction), a unit vector "
                  "orthogonal to direction (default: e_z x direction normalised; direction x "
                  "e_x when direction is along z)"),
    "curvature": Key(NUMBER, 0.0, "planar: the constant curvature of the rod's reference "
                     "axis [1/m] (an arc turning left from direction; 0: straight)"),
    "tendons": Key((list,), None, "per-rod tendons (not supported yet)"),
    "initial_curvature": Key((list,), None, "per-rod initial curvature (not supported yet)"),
}
JOINT_KEYS = {
    "name": Key((str,), REQUIRED, "the joint's name (outputs: joints.<name>)"),
    "kind": Key((str,), "rigid", "rigid | pin (planar: equal positions, free rotations) | "
                "ball (spatial: equal positions) (hinge: not supported yet)"),
    "at": Key((list,), REQUIRED, "the joined ends: two or more of \"rod:start\", "
              "\"rod:end\" (or one rod end and \"body:NAME\")"),
    "axis": Key((list,), None, "hinge axis (not supported yet)"),
}
BODY_KEYS = {
    "name": Key((str,), REQUIRED, "the body's name (joints name it as \"body:NAME\")"),
    "position": Key((list,), REQUIRED, "reference point [x, y] (spatial: [x, y, z]) [m]"),
    "fixed": Key((bool, list), True, "true (it clamps the rod end joined to it) or false "
                 "(planar: a free body whose pose is solved for; partly fixed: not supported "
                 "yet)"),
    "offset": Key((list,), None, "a joined end's point in the body frame (not supported yet)"),
    "motion": Key((dict,), None, "prescribed motion (not supported yet)"),
    "shape": Key((str,), None, "obstacle shape (not supported yet)"),
    "radius": Key(NUMBER, None, "obstacle radius (not supported yet)"),
    "mass": Key(NUMBER, None, "mass (not supported yet)"),
    "force": Key((list,), None, "a free body's dead force [Fx, Fy] (world axes) [N]"),
    "moment": Key(NUMBER + (list,), None, "a free body's dead moment M [N m]"),
}
ROD_MESH_KEYS = {"elements": SCHEMA["mesh"]["elements"], "degree": SCHEMA["mesh"]["degree"]}
ROD_SUPPORT_KEYS = ("x0", "xL")
ROD_LOAD_KEYS = ("point_forces", "point_moments")
#: [loads] keys that act on one end or one point of a single rod: per rod with [[rods]]
SINGLE_ROD_LOADS = ("tip_force", "tip_moment", "follower", "point_forces", "point_moments",
                    "prescribed_x0", "prescribed_xL", "end_displacement", "end_rotation")


def is_structure(config: dict) -> bool:
    """The configuration describes a structure ([[rods]], [[joints]] or [[bodies]])."""
    return any(name in config for name in STRUCTURE_TABLES)


def _entries(config: dict, name: str, keys: dict) -> list[dict]:
    """The validated entries of the array of tables [[name]] (defaults filled in)."""
    given = config.get(name, [])
    if isinstance(given, dict):
        raise ConfigError(f"[[{name}]] must be an array of tables: write each as [[{name}]] "
                          f"(double brackets), not [{name}]")
    if not isinstance(given, list) or not all(isinstance(e, dict) for e in given):
        raise ConfigError(f"[[{name}]] must be an array of tables; got {shown(given)}")
    entries = []
    for index, entry in enumerate(given):
        where = f"[[{name}]] #{index + 1}"
        unknown = [k for k in entry if k not in keys]
        if unknown:
            raise ConfigError(f"{where} unknown key {shown(unknown[0])}; allowed: "
                              f"{', '.join(keys)}")
        values = {}
        for key, spec in keys.items():
            if key in entry:
                values[key] = _entry_value(where, key, entry[key], spec)
            elif spec.default is REQUIRED:
                raise ConfigError(f"{where} {key} is required ({spec.doc})")
            else:
                values[key] = spec.default
        entries.append(values)
    return entries


def _entry_value(where: str, key: str, value, spec: Key):
    try:
        return _checked("x", key, value, spec)
    except ConfigError as error:
        raise ConfigError(str(error).replace("[x]", where, 1)) from None


def check_structure_tables(config: dict, command: str) -> None:
    """ConfigError for what a structure cannot be combined with in this version."""
    if not is_structure(config):
        return
    if command not in STRUCTURE_COMMANDS:
        raise ConfigError(f"fe-beam {command} does not run a structure of [[rods]] yet; the "
                          f"commands that do: {', '.join(STRUCTURE_COMMANDS)}")
    if "rods" not in config:
        raise ConfigError("[[joints]] and [[bodies]] need [[rods]] (the rods they join)")
    beam = config.get("beam")
    if isinstance(beam, dict) and beam:
        raise ConfigError("[beam] with [[rods]]: a structure gives each rod's length in "
                          "[[rods]] length; remove [beam]")
    if "supports" in config:
        raise ConfigError("[supports] with [[rods]]: give each rod's end supports in [[rods]] "
                          "supports = {x0 = ..., xL = ...}")
    model = config.get("model")
    spatial = isinstance(model, dict) and model.get("kinematics", "planar") == "spatial"
    if spatial and command not in SPATIAL_STRUCTURE_COMMANDS:
        raise ConfigError(f"fe-beam {command} does not run a spatial structure of [[rods]] yet "
                          "([model] kinematics = \"spatial\"); the commands that do: "
                          f"{', '.join(SPATIAL_STRUCTURE_COMMANDS)} (planar chains also "
                          f"{', '.join(PLANAR_ONLY)})")
    if isinstance(model, dict) and model.get("kinematics", "planar") == "spatial" \
            and model.get("law") == "hyperelastic":
        raise ConfigError("[model] law = \"hyperelastic\" is not available for kinematics = "
                          "\"spatial\" (use \"nonstandard\" or \"reissner\")")
    for name in ("tendons", "obstacles"):
        if config.get(name):
            raise ConfigError(f"[[{name}]] with [[rods]] is not supported yet (a structure "
                              "without tendons and obstacles, or a single rod with [beam])")
    if command == "dynamic":
        scheme = (config.get("time") or {}).get("scheme", "generalized-alpha") \
            if isinstance(config.get("time"), dict) else "generalized-alpha"
        if isinstance(scheme, str) and scheme.startswith("fd-"):
            raise ConfigError(f"[time] scheme = \"{scheme}\" with [[rods]] is not supported "
                              "(its baseline integrates a single rod); use \"generalized-alpha\""
                              " or \"energy-conserving\"")
        initial = config.get("initial")
        if isinstance(initial, dict) and initial.get("angular_velocity") is not None:
            raise ConfigError("[initial] angular_velocity with [[rods]] is not supported yet "
                              "(a spin about x = 0 of a rod along x); give [initial] velocity "
                              "= [u_t, v_t, theta_t], formulas in the chain's arc length x")
    if command not in TIED_COMMANDS and _tied(config):
        raise ConfigError(f"fe-beam {command} does not run a structure with pin or ball "
                          "joints, T junctions, closed loops or separate pieces yet; the "
                          f"commands that do: {', '.join(TIED_COMMANDS)}")
    loads = config.get("loads")
    if isinstance(loads, dict):
        single = [key for key in SINGLE_ROD_LOADS if key in loads]
        if single:
            raise ConfigError(f"[loads] {single[0]} with [[rods]]: give point loads per rod "
                              "([[rods]] loads = {point_forces = [[x, Px, Py]], point_moments "
                              "= [[x, M]]}, spatial [[x, Px, Py, Pz]], [[x, Mx, My, Mz]]); "
                              "[loads] takes gravity and distributed for every rod")


def _tied(config: dict) -> bool:
    """The [[joints]] need ties (not one serial chain of rigid joints between two rods):
    a cheap look at the tables (the full check is `Structure`)."""
    joints = config.get("joints")
    if not isinstance(joints, list):
        return False
    rods = config.get("rods") if isinstance(config.get("rods"), list) else []
    links = 0
    for joint in joints:
        if not isinstance(joint, dict):
            continue
        at = joint.get("at") if isinstance(joint.get("at"), list) else []
        named = [a for a in at if isinstance(a, str) and not a.startswith("body:")]
        if joint.get("kind", "rigid") != "rigid" or len(named) > 2:
            return True
        if len(named) == 2:
            links += 1
            if named[0].partition(":")[0] == named[1].partition(":")[0]:
                return True
    return links >= len(rods) > 0 or (links < len(rods) - 1)


def parse_structure(config: dict, spatial: bool = False) -> Structure:
    """The validated `Structure` of [[rods]], [[joints]], [[bodies]] (ConfigError naming the
    table and key otherwise); ``spatial``: [model] kinematics = "spatial" (3-vectors, rows of
    four numbers). Per-rod section, material and model tables are checked by the caller
    (`fe_beam.config.schema`)."""
    mesh_default = config.get("mesh") if isinstance(config.get("mesh"), dict) else {}
    size = 3 if spatial else 2
    rods = []
    for _index, entry in enumerate(_entries(config, "rods", ROD_KEYS)):
        where = f"[[rods]] '{entry['name']}'"
        for key in ("tendons", "initial_curvature"):
            if entry[key] is not None:
                raise ConfigError(f"{where} {key} is not supported yet (rods without "
                                  "tendons, straight in the reference state)")
        if entry["curvature"] and spatial:
            raise ConfigError(f"{where} curvature is planar (a spatial rod's reference axis is "
                              "straight in this version)")
        if entry["normal"] is not None and not spatial:
            raise ConfigError(f"{where} normal is the spatial section's d2: it needs [model] "
                              "kinematics = \"spatial\" (a planar rod's section turns with "
                              "its direction)")
        form = "[x, y]" if size == 2 else "[x, y, z]"
        for key, default in (("start", [0.0] * size), ("direction", [1.0] + [0.0] * (size - 1))):
            value = entry[key]
            if value is None:
                entry[key] = default
            elif not (isinstance(value, list) and len(value) == size):
                other = ("; three components need [model] kinematics = \"spatial\"" if size == 2
                         else "; [model] kinematics = \"spatial\" takes three components")
                raise ConfigError(f"{where} {key} must be {form}; got {shown(value)}{other}")
        mesh = dict(mesh_default) | (entry["mesh"] or {})
        unknown = [k for k in mesh if k not in ROD_MESH_KEYS]
        if unknown:
            raise ConfigError(f"{where} mesh: unknown key {shown(unknown[0])}; allowed: "
                              "elements, degree")
        mesh = {k: _entry_value(f"{where} mesh", k, mesh.get(k, spec.default), spec)
                for k, spec in ROD_MESH_KEYS.items()}
        if mesh["elements"] < 1 or mesh["degree"] not in (1, 2):
            raise ConfigError(f"{where} mesh: elements must be >= 1 and degree 1 or 2; got "
                              f"elements = {mesh['elements']}, degree = {mesh['degree']}")
        supports = entry["supports"]
        unknown = [k for k in supports if k not in ROD_SUPPORT_KEYS]
        if unknown:
            raise ConfigError(f"{where} supports: unknown key {shown(unknown[0])}; allowed: "
                              "x0 (the rod's start), xL (its end)")
        for key, value in list(supports.items()):
            if spatial and isinstance(value, list):
                try:
                    supports[key] = spatial_support_components(value, key) or "free"
                except ValueError as error:
                    raise ConfigError(f"{where} {error}") from None
                continue
            if not isinstance(value, str):
                lists = " or a list of components" if spatial else ""
                raise ConfigError(f"{where} supports.{key} must be a support name (clamped | "
                                  f"pinned | roller | free{lists}); got {shown(value)}")
        loads = entry["loads"]
        unknown = [k for k in loads if k not in ROD_LOAD_KEYS]
        if unknown:
            raise ConfigError(f"{where} loads: unknown key {shown(unknown[0])}; allowed: "
                              f"{', '.join(ROD_LOAD_KEYS)}")
        try:
            if spatial:
                forces = point_rows("point_forces", loads.get("point_forces", []), 4,
                                    "[x, Px, Py, Pz] (four numbers, world axes)")
                moments = point_rows("point_moments", loads.get("point_moments", []), 4,
                                     "[x, Mx, My, Mz] (four numbers, world axes)")
            else:
                forces = point_rows("point_forces", loads.get("point_forces", []), 3,
                                    "[x, Px, Py] (three numbers)")
                moments = point_rows("point_moments", loads.get("point_moments", []), 2,
                                     "[x, M] (two numbers)")
        except ValueError as error:
            raise ConfigError(f"{where} {error}") from None
        ends = {"x0": "start", "xL": "end"}
        rods.append(_wrap(Rod, entry["name"], entry["start"], entry["direction"],
                          entry["length"], mesh["elements"], mesh["degree"],
                          {ends[k]: v for k, v in supports.items()}, forces, moments,
                          normal=entry["normal"], curvature=entry["curvature"]))
    joints = []
    for entry in _entries(config, "joints", JOINT_KEYS):
        if entry["axis"] is not None:
            raise ConfigError(f"[[joints]] '{entry['name']}' axis is for hinge joints, which "
                              "are not supported yet")
        joints.append(_wrap(Joint, entry["name"], entry["kind"], entry["at"]))
    bodies = []
    for entry in _entries(config, "bodies", BODY_KEYS):
        extra = [k for k in ("offset", "motion", "shape", "radius", "mass")
                 if entry[k] is not None]
        if extra:
            raise ConfigError(f"[[bodies]] '{entry['name']}' {extra[0]} is not supported yet "
                              "(fixed bodies that clamp a rod end, free planar bodies at the "
                              "rod ends joined to them, loaded by force and moment)")
        bodies.append(_wrap(Body, entry["name"], entry["position"], entry["fixed"],
                            entry["force"] or (), entry["moment"] or 0.0))
    return _wrap(Structure, tuple(rods), tuple(joints), tuple(bodies))

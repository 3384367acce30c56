"""TOML configuration: schema, ``--set`` overrides and validation into model dataclasses.

Every user mistake becomes one `ConfigError` sentence that names the key, says what is allowed and
what was given; the CLI prints it and exits with code 2.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import stat
import tomllib
from pathlib import Path

from fe_beam.config.contact import check_motions, parse_contact
from fe_beam.config.keys import (
    NUMBER,
    OTHER_TABLES,
    SCHEMA,
    Key,
    _wrap,
    check_tables,
    table,
)
from fe_beam.config.material_laws import MATERIAL_KEYS, hyperelastic_law
from fe_beam.config.structure import (
    STRUCTURE_TABLES,
    check_structure_tables,
    is_structure,
    parse_structure,
)
from fe_beam.errors import ConfigError
from fe_beam.model.beam import BeamModel, Discretisation, Loads, ModelOptions, Supports
from fe_beam.model.beam import _rank as beam_rank
from fe_beam.model.materials import Material
from fe_beam.model.sections import Section
from fe_beam.model.settings import LoadStepping, SolverSettings
from fe_beam.model.spatial import (
    SPATIAL_SUPPORT_KINDS,
    SpatialLoads,
    SpatialRodModel,
    SpatialSupports,
)
from fe_beam.model.structure import Structure
from fe_beam.model.studies import OutputOptions, StaticConfig
from fe_beam.timefunctions import shown

__all__ = [
    "NUMBER",
    "OTHER_TABLES",
    "SCHEMA",
    "ConfigError",
    "Key",
    "OutputOptions",
    "StaticConfig",
    "apply_overrides",
    "check_values",
    "load_config",
    "parse_static",
]



MAX_CONFIG_BYTES = 256 * 2**20
FILE_KINDS = ((stat.S_ISFIFO, "a named pipe (FIFO)"), (stat.S_ISCHR, "a character device"),
              (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _file_problem(path: Path) -> str | None:
    """Why ``path`` cannot be read as a configuration file (None: it can). Never opens a FIFO
    or a device (reading one could block or never end)."""
    name = shown(str(path), 300)
    try:
        info = path.stat()
    except ValueError:
        return f"config file {name} is not a usable file name (it contains a NUL byte)"
    except FileNotFoundError:
        if path.is_symlink():
            return f"config file {name} is a symbolic link to a file that does not exist"
        return f"config file {name} does not exist"
    except NotADirectoryError:
        blocking = next((parent for parent in path.parents if parent.is_file()), path.parent)
        return (f"config file {name} cannot exist: {shown(str(blocking), 300)} is a file, not a "
                "folder")
    except OSError as error:
        return f"config file {name} cannot be read ({error.strerror})"
    if stat.S_ISDIR(info.st_mode):
        return f"config file {name} is a directory, not a TOML file"
    for test, kind in FILE_KINDS:
        if test(info.st_mode):
            return f"config file {name} is {kind}, not a regular file"
    if not stat.S_ISREG(info.st_mode):
        return f"config file {name} is not a regular file"
    if info.st_size > MAX_CONFIG_BYTES:
        return (f"config file {name} has {info.st_size / 2**20:.0f} MiB; a configuration has at "
                f"most {MAX_CONFIG_BYTES // 2**20} MiB")
    return None


def load_config(path: str | Path) -> dict:
    path = Path(path)
    name = shown(str(path), 300)
    problem = _file_problem(path)
    if problem:
        raise ConfigError(problem)
    try:
        with path.open("rb") as stream:
            return tomllib.load(stream)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, ValueError) as error:
        # ValueError: e.g. an integer of more than 4300 digits
        raise ConfigError(f"{name}: not valid TOML ({shown(str(error), 200)[1:-1]})") from None
    except RecursionError:
        raise ConfigError(f"{name}: not valid TOML (arrays or inline tables nested too "
                          "deeply)") from None
    except OSError as error:
        raise ConfigError(f"config file {name} cannot be read ({error.strerror})") from None


def _parse_value(text: str):
    try:
        return tomllib.loads(f"value = {text}")["value"]
    except (tomllib.TOMLDecodeError, ValueError, RecursionError):
        return text  # a bare word such as reissner (or a value the checks then refuse)


def apply_overrides(config: dict, assignments: list[str], defaults: dict | None = None) -> dict:
    """Apply ``table.key=value`` overrides (values in TOML syntax; bare words are strings).
    Arrays of tables are indexed from 0: ``tendons.0.tension=1.5``, or by a table's ``name``
    (``rods.beam.section.h=0.04``). ``defaults``: the tables a
    command uses for those the file leaves out (the finger's, `fe_beam.config.finger`): an
    override of such a table applies to a copy of its default (``section.h_tip=0.009`` with no
    [section] changes the default section's h_tip, not a new section of h_tip alone)."""
    config = copy.deepcopy(config)
    defaults = defaults or {}
    for assignment in assignments or []:
        if "=" not in assignment:
            raise ConfigError(f"--set {shown(assignment)}: expected table.key=value")
        dotted, text = assignment.split("=", 1)
        names = dotted.strip().split(".")
        if len(names) < 2 or not all(names):
            raise ConfigError(f"--set {shown(assignment)}: expected table.key=value")
        target, position = config, 0
        while position < len(names) - 1:
            name = names[position]
            if position == 0 and name not in target and isinstance(defaults.get(name),
                                                                    (dict, list)):
                target[name] = copy.deepcopy(defaults[name])
            if (name not in target and position + 1 < len(names) - 1
                    and names[position + 1].isdigit()):
                raise ConfigError(f"--set {shown(assignment)}: the config has no [[{name}]] to "
                                  f"index; add the [[{name}]] tables to the file")
            target = target.setdefault(name, {})
            position += 1
            if isinstance(target, list) and all(isinstance(item, dict) for item in target):
                index = names[position]
                named = [i for i, item in enumerate(target) if item.get("name") == index]
                if not index.isdigit() and len(named) == 1:  # a table by its name
                    index = str(named[0])
                if position >= len(names) - 1 or not index.isdigit() or int(index) >= len(target):
                    names_given = [item["name"] for item in target
                                   if isinstance(item.get("name"), str)]
                    by_name = (f" or by its name ({', '.join(names_given)})" if names_given
                               else "")
                    raise ConfigError(
                        f"--set {shown(assignment)}: {shown(name)[1:-1]} is an array of "
                        f"{len(target)} tables; "
                        f"address one as {name}.<index 0..{len(target) - 1}>.key{by_name}"
                    )
                target = target[int(index)]
                position += 1
            elif not isinstance(target, dict):
                raise ConfigError(f"--set {shown(assignment)}: {shown(name)[1:-1]} is not a table")
        target[names[-1]] = _parse_value(text.strip())
    return config



def parse_section(config: dict) -> Section:
    values = table(config, "section", open_keys=lambda key: True)
    shape = values.pop("shape")
    dims, dims_tip = {}, {}
    for key, value in values.items():
        target, name = (dims_tip, key[:-4]) if key.endswith("_tip") else (dims, key)
        if isinstance(value, bool) or not isinstance(value, NUMBER):
            raise ConfigError(f"[section] {shown(key)[1:-1]} must be a number; got {shown(value)}")
        target[name] = value
    orphans = [n for n in dims_tip if n not in dims]
    if orphans:
        raise ConfigError(f"[section] {orphans[0]}_tip given without {orphans[0]}")
    return _wrap(Section, shape, dims, dims_tip)


#: [model] keys of law = "hyperelastic" (the 3D law, and the section quadrature)
HYPERELASTIC_KEYS = ("material", "preset", "mu", "c10", "c01", "c20", "c30", "kappa",
                     "volumetric", "section_points")


def _rod_material(config: dict, model: dict) -> tuple[Material, dict]:
    """The rod's Material and the ModelOptions keywords of the law; with law = "hyperelastic"
    the 3D law of [model] (`fe_beam.config.material_laws.hyperelastic_law`) and E, G its
    small-strain
    ones (E derived from a preset)."""
    law_keys = {key: model.pop(key) for key in HYPERELASTIC_KEYS}
    if model["law"] != "hyperelastic":
        given = [key for key, value in law_keys.items() if value is not None]
        if given:
            raise ConfigError(f"[model] {given[0]} applies to law = \"hyperelastic\" only; got "
                              f"law = {shown(model['law'])}")
        return _wrap(Material, **table(config, "material")), {}
    values = dict(law_keys)
    values["material"] = values["material"] or "neo-hookean"
    values["volumetric"] = values["volumetric"] or "simo_taylor"
    points = values.pop("section_points")
    law = hyperelastic_law(config, values, "model", "law = \"hyperelastic\"")
    rho = table(config, "material", MATERIAL_KEYS)["rho"]
    material = _wrap(Material, E=law.young_modulus, G=law.shear_modulus, rho=rho)
    return material, {"hyperelastic": law, "section_points": points}


def parse_structure_model(config: dict) -> BeamModel:
    """The `BeamModel` of a structure of [[rods]] (a planar serial chain, `fe_beam.model.
    structure`): one model along the chain's arc length, its ends' supports those of the
    chain's end rods, the rods' point loads at chain coordinates; the top-level [section],
    [material], [model] and [loads] gravity / distributed apply to every rod."""
    check_structure_tables(config, "static")
    model = table(config, "model")
    kinematics = model.pop("kinematics")
    if kinematics not in ("planar", "spatial"):
        raise ConfigError(f"[model] kinematics must be \"planar\" or \"spatial\"; got "
                          f"{shown(kinematics)}")
    spatial = kinematics == "spatial"
    structure = parse_structure(config, spatial)
    material, law_options = _rod_material(config, model)
    section = parse_section(config)
    if section.dims_tip:
        raise ConfigError("[section] *_tip (a tapered section) with [[rods]] is not supported "
                          "yet: each rod has the section of [section]")
    structure = _own_sections(config, structure, section, material, model["law"])
    loads = table(config, "loads")
    forces, moments = structure.chain_point_loads()
    for s, *_ in forces:
        if s == 0.0:
            segment = structure.chain[0]
            rod = structure.rods[segment.rod]
            end = "xL" if segment.reversed else "x0"
            raise ConfigError(f"[[rods]] '{rod.name}' loads.point_forces: a force at the rod's "
                              f"{end} end, held by supports.{end} = "
                              f"{structure.end_supports['x0']!r}, would be taken by the support; "
                              "load a free end or a point of a rod")
    rotations = {"theta_x", "theta_y", "theta_z"}
    for s, *values in moments:
        # a moment at a chain end whose support holds the rotation is taken by the support
        for chain_end, at, index in (("x0", 0.0, 0), ("xL", structure.length, -1)):
            kind = structure.end_supports[chain_end]
            held = kind == "clamped" or (isinstance(kind, tuple) and rotations <= set(kind))
            if held and abs(s - at) <= 1e-12 * structure.length and any(values):
                segment = structure.chain[index]
                rod = structure.rods[segment.rod]
                end = ("xL" if segment.reversed else "x0") if index == 0 else \
                    ("x0" if segment.reversed else "xL")
                raise ConfigError(f"[[rods]] '{rod.name}' loads.point_moments: a moment at the "
                                  f"rod's {end} end, clamped there (supports or a fixed body),"
                                  " would be taken by the support; load a free or pinned end "
                                  "or a point of a rod")
    elements = sum(rod.elements for rod in structure.rods)
    supports = structure.end_supports
    common = dict(
        length=structure.length,
        section=section,
        material=material,
        options=_wrap(ModelOptions, **model, **law_options),
        mesh=_wrap(Discretisation, elements=elements, degree=structure.rods[0].degree),
        structure=structure,
    )
    if spatial:
        return _wrap(
            SpatialRodModel, **common,
            supports=_wrap(SpatialSupports, x0=_spatial_chain_support(structure, "x0"),
                           xL=_spatial_chain_support(structure, "xL")),
            loads=_wrap(SpatialLoads, distributed=loads["distributed"], gravity=loads["gravity"],
                        point_forces=forces, point_moments=moments),
        )
    return _wrap(
        BeamModel, **common,
        supports=_wrap(Supports, x0=supports["x0"], xL=supports["xL"]),
        loads=_wrap(Loads, distributed=loads["distributed"], gravity=loads["gravity"],
                    point_forces=forces, point_moments=moments),
    )


def _spatial_chain_support(structure, end: str) -> tuple:
    """The world components a spatial chain's end holds: clamped (all), free (none), pinned
    (the position and the twist about the end rod's direction, which must be a coordinate axis:
    the rotation components are world axes) or the components given."""
    kind = structure.end_supports[end]
    if isinstance(kind, tuple):
        return kind
    segment = structure.chain[0 if end == "x0" else -1]
    rod = structure.rods[segment.rod]
    key = "x0" if (end == "x0") != segment.reversed else "xL"
    if kind == "roller":
        raise ConfigError(f"[[rods]] '{rod.name}' supports.{key} = \"roller\" is planar; a "
                          "spatial chain takes clamped, pinned, free or a list of components "
                          "from u, v, w, theta_x, theta_y, theta_z")
    if kind != "pinned":
        return SPATIAL_SUPPORT_KINDS[kind]
    axis = [i for i, c in enumerate(rod.direction) if abs(abs(c) - 1.0) <= 1e-12]
    if not axis:
        raise ConfigError(f"[[rods]] '{rod.name}' supports.{key} = \"pinned\" holds the twist "
                          "about the rod's direction, which is not a coordinate axis here; give "
                          "the held components as a list (e.g. [\"u\", \"v\", \"w\", "
                          "\"theta_x\"])")
    return ("u", "v", "w", ("theta_x", "theta_y", "theta_z")[axis[0]])


def _own_sections(config: dict, structure, section, material, law: str):
    """The structure with each rod's section dimensions and (E, G) when a rod has its own
    ``section`` or ``material`` table (over the top-level ones: the same shape, no taper, the
    same density); rods' own ``model`` tables are refused."""
    own_section = own_material = False
    dims, moduli = [], []
    for rod, entry in zip(structure.rods, config["rods"], strict=True):
        where = f"[[rods]] '{rod.name}'"
        if entry.get("model") is not None:
            given = config.get("model", {}) if isinstance(config.get("model"), dict) else {}
            if (given | entry["model"]) != given:
                raise ConfigError(f"{where} model: a rod's own law or constraint different from "
                                  "the top-level [model] is not supported yet (every rod takes "
                                  "[model])")
        top = config.get("section", {}) if isinstance(config.get("section"), dict) else {}
        own = entry.get("section") or {}
        if own.get("shape", top.get("shape", "rectangle")) != top.get("shape", "rectangle"):
            raise ConfigError(f"{where} section.shape: a shape different from [section] shape "
                              "is not supported yet (give the rod other dimensions of the same "
                              "shape)")
        try:
            rod_section = parse_section({"section": top | own}) if own else section
        except ConfigError as error:
            raise ConfigError(f"{where} section: {error}") from None
        if rod_section.dims_tip:
            raise ConfigError(f"{where} section: *_tip (a tapered rod) is not supported yet")
        own_section = own_section or rod_section.dims != section.dims
        dims.append(tuple(sorted(rod_section.dims.items())))
        top = config.get("material", {}) if isinstance(config.get("material"), dict) else {}
        own = entry.get("material") or {}
        if own and law == "hyperelastic":
            raise ConfigError(f"{where} material: a rod's own material with [model] law = "
                              "\"hyperelastic\" is not supported yet")
        # a rod's own nu or G replaces the top level's other one (they are alternatives)
        merged = {k: v for k, v in top.items()
                  if not (k in ("nu", "G") and ("nu" in own or "G" in own))} | own
        try:
            rod_material = _wrap(Material, **table({"material": merged}, "material")) \
                if own else material
        except ConfigError as error:
            text = str(error)
            raise ConfigError(f"{where} {text}" if text.startswith(("material", "[material]"))
                              else f"{where} material: {text}") from None
        if rod_material.rho != material.rho:
            raise ConfigError(f"{where} material.rho: a density different from [material] rho "
                              "is not supported yet")
        own_material = own_material or (rod_material.E, rod_material.shear_modulus) != (
            material.E, material.shear_modulus)
        moduli.append((rod_material.E, rod_material.shear_modulus))
    if not (own_section or own_material):
        return structure
    if own_section and law == "hyperelastic":
        raise ConfigError("[[rods]] section: a rod's own section with [model] law = "
                          "\"hyperelastic\" is not supported yet")
    rods = tuple(dataclasses.replace(rod, section=dims[i] if own_section else (),
                                     material=moduli[i] if own_material else ())
                 for i, rod in enumerate(structure.rods))
    return _wrap(Structure, rods, structure.joints, structure.bodies)


def with_rod_sections(model: BeamModel) -> BeamModel:
    """The structure's model with every rod carrying its own section dimensions (those of
    [section] where it has none): piecewise-constant fields a design varies per rod."""
    structure = model.structure
    if model.options.law == "hyperelastic":
        raise ConfigError("[design] rods.<name>.section variables with [model] law = "
                          "\"hyperelastic\" are not supported yet")
    dims = tuple(sorted(model.section.dims.items()))
    rods = tuple(dataclasses.replace(rod, section=rod.section or dims) for rod in structure.rods)
    return dataclasses.replace(model, structure=_wrap(Structure, rods, structure.joints,
                                                      structure.bodies))


def with_rod_materials(model: BeamModel) -> BeamModel:
    """The structure's model with every rod carrying its own (E, G) (those of [material] where
    it has none): piecewise-constant fields a calibration varies per rod."""
    structure = model.structure
    if model.options.law == "hyperelastic":
        raise ConfigError("rods.<name>.material parameters with [model] law = \"hyperelastic\" "
                          "are not supported yet")
    moduli = (model.material.E, model.material.shear_modulus)
    rods = tuple(dataclasses.replace(rod, material=rod.material or moduli)
                 for rod in structure.rods)
    return dataclasses.replace(model, structure=_wrap(Structure, rods, structure.joints,
                                                      structure.bodies))


def structure_rigid_motions(model: BeamModel) -> list[str]:
    """The rigid motions a chain's end supports leave free (empty: none), with the ends at
    their reference positions: a small rigid motion (a, b, w) moves the point (X, Y) by
    (a - w Y, b + w X) and turns it by w (spatial: a + w x X, turned by w)."""
    structure = model.structure
    held = [(structure.reference_point(0.0, structure.chain[0]), model.supports.fixed("x0")),
            (structure.reference_point(model.length, structure.chain[-1]),
             model.supports.fixed("xL"))]
    held += [(structure.reference_point(s), components)
             for s, components, _ in structure.extra_supports]
    if structure.dim == 3:
        scale = structure.length
        equations = []
        for (X, Y, Z), fixed in held:
            rows = {"u": (1, 0, 0, 0, Z, -Y), "v": (0, 1, 0, -Z, 0, X),
                    "w": (0, 0, 1, Y, -X, 0), "theta_x": (0, 0, 0, 1, 0, 0),
                    "theta_y": (0, 0, 0, 0, 1, 0), "theta_z": (0, 0, 0, 0, 0, 1)}
            equations += [tuple(c / scale if i >= 3 else c for i, c in enumerate(rows[n]))
                          for n in fixed]
        if equations and beam_rank(equations) == 6:
            return []
        return ["a rigid-body motion (support the chain's ends: e.g. clamp one)"]
    rows = []
    for (X, Y), fixed in held:
        rows += ([(1.0, 0.0, -Y)] if "u" in fixed else []) + \
            ([(0.0, 1.0, X)] if "v" in fixed else []) + \
            ([(0.0, 0.0, 1.0)] if "theta" in fixed else [])
    if rows and _rank(rows, structure.length) == 3:
        return []
    return ["a rigid-body motion (support the chain's ends: e.g. clamp one, or pin both)"]


def _rank(rows, scale: float) -> int:
    """The rank of the rigid-motion rows, the rotation column scaled by the chain's length."""
    return beam_rank([(a, b, c / scale) for a, b, c in rows])


def parse_model(config: dict) -> BeamModel | SpatialRodModel:
    if is_structure(config):
        return parse_structure_model(config)
    beam = table(config, "beam")
    model = table(config, "model")
    kinematics = model.pop("kinematics")
    if kinematics not in ("planar", "spatial"):
        raise ConfigError(f"[model] kinematics must be \"planar\" or \"spatial\"; got "
                          f"{shown(kinematics)}")
    material, law_options = _rod_material(config, model)
    spatial = kinematics == "spatial"
    if spatial and model["law"] == "hyperelastic":
        raise ConfigError("[model] law = \"hyperelastic\" is not available for kinematics = "
                          "\"spatial\" yet (use \"nonstandard\" or \"reissner\")")
    if not spatial and beam["initial_curvature"] is not None:
        raise ConfigError("[beam] initial_curvature needs [model] kinematics = \"spatial\" (the "
                          "planar rod is straight)")
    supports = table(config, "supports")
    loads = table(config, "loads")
    model_kind, supports_kind, loads_kind = ((SpatialRodModel, SpatialSupports, SpatialLoads)
                                             if spatial else (BeamModel, Supports, Loads))
    extra = {"initial_curvature": beam["initial_curvature"]} if spatial else {}
    return _wrap(
        model_kind,
        length=beam["length"],
        section=parse_section(config),
        material=material,
        options=_wrap(ModelOptions, **model, **law_options),
        mesh=_wrap(Discretisation, **table(config, "mesh")),
        supports=_wrap(
            supports_kind,
            x0=_support(supports["x0"]),
            xL=_support(supports["xL"]),
            prescribed_x0=loads["prescribed_x0"],
            prescribed_xL=loads["prescribed_xL"],
        ),
        loads=_wrap(loads_kind, **{key: loads[key] for key in LOAD_KEYS}),
        **extra,
    )


#: the [loads] keys the model's loads take (planar `Loads` and `SpatialLoads` alike)
LOAD_KEYS = ("tip_force", "tip_moment", "follower", "distributed", "gravity", "point_forces",
             "point_moments", "end_displacement", "end_rotation")


def _support(spec):
    return tuple(spec) if isinstance(spec, list) else spec


def _load_steps(config: dict, steps):
    """The number of initial load steps a run takes: ``loads.steps``, or more when a tendon
    asks for more (`fe_beam.config.finger.parse_finger`); ``steps`` itself when not a count."""
    if not (isinstance(steps, int) and not isinstance(steps, bool)):
        return steps
    tendons = config.get("tendons")
    asked = [t.get("steps") for t in tendons if isinstance(t, dict)] \
        if isinstance(tendons, list) else []
    return max([steps] + [n for n in asked if isinstance(n, int) and not isinstance(n, bool)])


def given_max_increment(config: dict, steps: int) -> float:
    """``[solver] max_increment`` when the user gave it (checked by `parse_solver` against the
    run's load steps), else one step of ``steps`` (never grow beyond the first increment)."""
    solver = config.get("solver")
    given = solver.get("max_increment") if isinstance(solver, dict) else None
    return 1.0 / steps if given is None else max(float(given), 1.0 / steps)


def check_max_increment(largest, count, steps, adaptive) -> None:
    """ConfigError unless ``[solver] max_increment`` (None: not given) is between 1/``count``
    (the run's initial load steps; ``steps`` = loads.steps) and 1, with adaptive steps when it
    lets them grow. Nothing is checked while the step count itself is invalid (named first)."""
    if largest is None or not (isinstance(count, int) and not isinstance(count, bool)
                               and count >= 1):
        return
    if not 1.0 / count <= largest <= 1.0:
        where = (f"loads.steps = {steps}" if count == steps else
                 f"the largest of loads.steps and the tendons' steps = {count}")
        raise ConfigError(f"[solver] max_increment must be between 1/steps ({where}) and 1; "
                          f"got {largest!r}")
    if largest > (1 + 1e-12) / count and not adaptive:
        raise ConfigError("[solver] max_increment above 1/steps lets load steps grow, which "
                          "needs adaptive = true; got adaptive = false")


def parse_solver(config: dict) -> tuple[SolverSettings, LoadStepping, float]:
    solver = table(config, "solver")
    steps = table(config, "loads")["steps"]
    largest = solver.pop("max_increment")
    adaptive = solver.pop("adaptive")
    easy = solver.pop("easy_iterations")
    if not (isinstance(easy, int) and not isinstance(easy, bool) and easy >= 1):
        raise ConfigError(f"[solver] easy_iterations must be an integer >= 1; got {easy!r}")
    check_max_increment(largest, _load_steps(config, steps), steps, adaptive)
    stepping = _wrap(
        LoadStepping,
        steps=steps,
        adaptive=adaptive,
        min_increment=min(solver.pop("min_increment"), 1.0 / max(steps, 1)),
        max_increment=(None if largest is None or not isinstance(steps, int)
                       else max(largest, 1.0 / max(steps, 1))),
        easy_iterations=easy,
    )
    jump = solver.pop("max_rotation_jump")
    solver.pop("allow_large")  # read from the raw table by the drivers (fe_beam.runctl)
    if not jump > 0:
        raise ConfigError(f"[solver] max_rotation_jump must be > 0; got {jump!r}")
    if solver.get("linear_solver") == "fieldsplit":  # the solid's u-p solver: rods have no blocks
        raise ConfigError("[solver] linear_solver = \"fieldsplit\" is the 3D solid's u-p solver "
                          "([solid] solver); the rod takes auto | mumps | lu | gamg | gmres-ilu")
    return _wrap(SolverSettings, **solver), stepping, float(jump)


def _spec(support) -> str:
    """A support as the user wrote it in TOML."""
    if isinstance(support, str):
        return f'"{support}"'
    return "[" + ", ".join(f'"{c}"' for c in support) + "]"


def _chain_end(support) -> str:
    """A chain end's support in a sentence: its name, "free" for a spatial end holding no
    component (an empty tuple), else its components as the user writes them."""
    if isinstance(support, str):
        return support
    return _spec(support) if support else "free"


def parse_static(config: dict, rigid_motion_allowed: bool = False,
                 motion_variable: str = "load_factor") -> StaticConfig:
    """The statics configuration; ``rigid_motion_allowed`` for dynamics and modes, where a
    beam free to move as a rigid body (free-free, flying) is meaningful; ``motion_variable``:
    the variable of moving obstacles' position formulas ("t" in dynamics)."""
    check_tables(config, tuple(SCHEMA) + OTHER_TABLES + STRUCTURE_TABLES)
    model = parse_model(config)
    settings, stepping, jump = parse_solver(config)
    if model.options.constraint != "none" and settings.linear_solver not in ("auto", "mumps"):
        raise ConfigError(
            f"[solver] linear_solver = \"{settings.linear_solver}\" cannot solve the saddle-point "
            f"systems of constraint = \"{model.options.constraint}\" (its multiplier rows have a "
            "zero diagonal); use linear_solver = \"auto\" or \"mumps\", or constraint = \"none\""
        )
    free = (structure_rigid_motions(model) if getattr(model, "structure", None) is not None
            else model.supports.rigid_motions())
    if free and not rigid_motion_allowed and getattr(model, "structure", None) is not None:
        raise ConfigError(
            f"[[rods]] supports: the chain's ends ({_chain_end(model.supports.x0)} at its "
            f"start, {_chain_end(model.supports.xL)} at its end) leave it free to move as a "
            "rigid body; a static equilibrium needs supports that prevent it (clamp one end, "
            "or pin both)")
    if free and not rigid_motion_allowed:
        raise ConfigError(
            f"[supports] x0 = {_spec(model.supports.x0)}, xL = {_spec(model.supports.xL)} leave "
            "the beam "
            f"free to move as a rigid body: {'; '.join(free)}. A static equilibrium needs "
            "supports that prevent it (e.g. x0 = \"clamped\", or x0 = \"pinned\" and "
            "xL = \"roller\")"
        )
    output = OutputOptions(**table(config, "output"))
    obstacles, contact = parse_contact(config, model, variable=motion_variable)
    if motion_variable == "load_factor":
        check_motions(obstacles, 1.0, model)
    return StaticConfig(model, settings, stepping, jump, output, raw=config,
                        obstacles=obstacles, contact=contact)


# --- checks over the whole configuration, before any command reads it ---------------------------
# Magnitudes of nonzero numbers (SI units): beyond them products of a few numbers overflow or
# underflow, or the factorisations meet "zero" pivots; no physical input of a rod is near them.
MAGNITUDES = (1e-30, 1e30)
# Keys whose numbers may be as small or as large as the user likes (tolerances; PETSc's own).
UNBOUNDED = ("tol", "petsc_options", "min_increment")


def _where(path: tuple) -> str:
    """A key path as the user wrote it: ``[loads] prescribed_xL.theta``, ``[loads]
    tip_force[1]``, ``[[tendons]] #2 tension``."""
    head, rest = path[0], list(path[1:])
    if rest and isinstance(rest[0], int):
        text = f"[[{head}]] #{rest.pop(0) + 1}"
    else:
        text = f"[{head}]"
    key = ""
    for part in rest:
        key += f"[{part}]" if isinstance(part, int) else (f".{part}" if key else str(part))
    return f"{text} {key}".strip() if key else text


def check_values(config: dict) -> None:
    """Every number anywhere in the configuration is finite (no nan or inf: no key gives them a
    meaning), fits the 64-bit integers of TOML and, outside tolerances, is 0 or has a magnitude
    in MAGNITUDES; a table
    meant as an array of tables ([[tendons]]) is one. ConfigError naming the key otherwise."""
    if not isinstance(config, dict):
        raise ConfigError("the configuration must be a table")
    tendons = config.get("tendons")
    if isinstance(tendons, dict):
        raise ConfigError(
            "tendons must be an array of tables: write each tendon as [[tendons]] (double "
            "brackets), not [tendons]")
    stack = [((name,), value) for name, value in config.items()]
    while stack:
        path, value = stack.pop()
        if isinstance(value, dict):
            stack.extend((path + (str(key),), item) for key, item in value.items())
            continue
        if isinstance(value, list):
            stack.extend((path + (index,), item) for index, item in enumerate(value))
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            continue
        if isinstance(value, int) and not -(2**63) <= value < 2**63:
            raise ConfigError(f"{_where(path)} = {shown(value)} is too large (TOML integers "
                              "are 64-bit)")
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"{_where(path)} must be a finite number; got {value!r}")
        bounded = not any(part in str(name) for name in path for part in UNBOUNDED)
        low, high = MAGNITUDES
        if bounded and value != 0 and not low <= abs(value) <= high:
            raise ConfigError(f"{_where(path)} = {value:.6g} is out of range: fe-beam takes "
                              f"numbers of magnitude {low:g} to {high:g} (SI units), or 0")
    _check_ranges(config)
    _check_pairs(config)
    if "checks" in config:  # [checks] is read by the CLI for every command
        table(config, "checks")


# Lengths below this are beyond what the mesh generator and point location resolve (they work
# with absolute tolerances near 1e-15 m); above the upper bound a "beam" is not a structure.
LENGTH_RANGE = (1e-6, 1e6)


def _number(config: dict, table_name: str, key: str):
    given = config.get(table_name)
    value = given.get(key) if isinstance(given, dict) else None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return value


def _check_ranges(config: dict) -> None:
    low, high = LENGTH_RANGE
    length = _number(config, "beam", "length")
    if length is not None and length > 0 and not low <= length <= high:
        raise ConfigError(f"[beam] length = {length:g} m is outside the range fe-beam computes "
                          f"with ({low:g} m to {high:g} m)")
    rods = config.get("rods")
    if not isinstance(rods, list):
        return
    # the chain is one mesh of the rods' total length: each rod and the sum in the range
    lengths = [(rod.get("name"), rod.get("length")) for rod in rods if isinstance(rod, dict)]
    lengths = [(name, value) for name, value in lengths
               if isinstance(value, (int, float)) and not isinstance(value, bool)
               and 0 < value < float("inf")]
    for name, value in lengths:
        if not low <= value <= high:
            raise ConfigError(f"[[rods]] {shown(name)} length = {value:g} m is outside the range "
                              f"fe-beam computes with ({low:g} m to {high:g} m)")
    total = sum(value for _, value in lengths)
    if total > high:
        raise ConfigError(f"[[rods]] length: the rods' lengths sum to {total:g} m, beyond the "
                          f"range fe-beam computes with ({low:g} m to {high:g} m for the chain)")


def _check_pairs(config: dict) -> None:
    """Keys that bound each other: the smaller must not exceed the larger."""
    time = config.get("time")
    if not isinstance(time, dict):
        return
    values = {key: _number(config, "time", key) for key in ("min_dt", "dt", "max_dt")}
    order = ("min_dt", "dt", "max_dt")
    for i, small in enumerate(order):
        for large in order[i + 1:]:
            a, b = values[small], values[large]
            if a is not None and b is not None and a > 0 and b > 0 and a > b:
                raise ConfigError(f"[time] {small} = {a:g} s must not exceed {large} = {b:g} s")


def check_partition(config: dict, ranks: int, command: str = "static") -> None:
    """Every MPI rank needs at least one element of the rod mesh (dolfinx 0.5 crashes on a rank
    that owns none), and a 3D solid mesh finer than its cross-section (coarser ones give NaN or
    hang in parallel, while they run serially)."""
    if ranks > 1 and command in ("solid", "compare", "refine", "buckling"):
        _check_solid_partition(config, ranks)
    mesh = config.get("mesh")
    elements = mesh.get("elements", SCHEMA["mesh"]["elements"].default) if isinstance(
        mesh, dict) else SCHEMA["mesh"]["elements"].default
    if (isinstance(elements, int) and not isinstance(elements, bool)
            and 1 <= elements < ranks):
        raise ConfigError(
            f"[mesh] elements = {elements} is fewer than the {ranks} MPI ranks: every rank needs "
            f"at least one element; use elements >= {ranks} or run on fewer ranks")


def _check_solid_partition(config: dict, ranks: int) -> None:
    solid = config.get("solid")
    size = _number(config, "solid", "mesh_size") if isinstance(solid, dict) else None
    dimensions = [value for key in ("b", "h", "h_tip")
                  if (value := _number(config, "section", key)) is not None and value > 0]
    if size is None or not dimensions or size <= max(dimensions):
        return
    raise ConfigError(
        f"[solid] mesh_size = {size:g} m is larger than the cross-section ({max(dimensions):g} m):"
        f" such a coarse 3D mesh does not run on {ranks} MPI ranks; use mesh_size <= "
        f"{max(dimensions):g} m, or run on one rank")

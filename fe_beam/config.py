"""TOML configuration: schema, ``--set`` overrides and validation into model dataclasses.

Every user mistake becomes one `ConfigError` sentence that names the key, says what is allowed and
what was given; the CLI prints it and exits with code 2.
"""

from __future__ import annotations

import copy
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from fe_beam.beam import BeamModel, Discretisation, Loads, ModelOptions, Supports
from fe_beam.materials import Material
from fe_beam.sections import SHAPES, Section
from fe_beam.solver import LoadStepping, SolverSettings

__all__ = [
    "ConfigError",
    "OutputOptions",
    "StaticConfig",
    "apply_overrides",
    "load_config",
    "parse_static",
]


class ConfigError(ValueError):
    """A user mistake in a configuration (message is shown as is, exit code 2)."""


NUMBER = (int, float)
REQUIRED = object()


@dataclass(frozen=True)
class Key:
    types: tuple
    default: object = None
    doc: str = ""


# Tables and keys every command understands; commands read the tables they need. A key not
# listed here is a mistake (typically a typo) and is reported, never ignored.
SCHEMA: dict[str, dict[str, Key]] = {
    "beam": {"length": Key(NUMBER, REQUIRED, "beam length L [m]")},
    "section": {"shape": Key((str,), "rectangle", f"one of {', '.join(SHAPES)}")},
    "material": {
        "E": Key(NUMBER, REQUIRED, "Young's modulus [Pa]"),
        "nu": Key(NUMBER, None, "Poisson's ratio (or give G)"),
        "G": Key(NUMBER, None, "shear modulus [Pa] (or give nu)"),
        "rho": Key(NUMBER, 0.0, "density [kg/m^3]"),
    },
    "model": {
        "law": Key((str,), "nonstandard", "nonstandard | reissner"),
        "constraint": Key(
            (str,), "none", "none | inextensible | unshearable | inextensible-unshearable"
        ),
        "shear_correction": Key(NUMBER, 1.0, "k of the Reissner law"),
    },
    "mesh": {
        "elements": Key((int,), 50, "number of elements"),
        "degree": Key((int,), 2, "1 or 2"),
    },
    "supports": {
        "x0": Key((str, list), "clamped", "clamped | pinned | roller | free | [components]"),
        "xL": Key((str, list), "free", "clamped | pinned | roller | free | [components]"),
    },
    "loads": {
        "tip_force": Key((list,), [0.0, 0.0], "[Px, Py] at x = L [N]"),
        "tip_moment": Key(NUMBER, 0.0, "moment at x = L [N m], counterclockwise"),
        "follower": Key((bool,), False, "tip force follows the tip section"),
        "distributed": Key((list,), [0.0, 0.0], "[qx, qy] per unit length [N/m]"),
        "gravity": Key((list,), [0.0, 0.0], "[gx, gy] acceleration [m/s^2]"),
        "prescribed_x0": Key((dict,), {}, "{u|v|theta = value} of fixed components at x = 0"),
        "prescribed_xL": Key((dict,), {}, "{u|v|theta = value} of fixed components at x = L"),
        "steps": Key((int,), 10, "initial number of load steps"),
        "time_function": Key((str,), None, "dynamic: load scale f(t), a formula in t"),
        "time_table": Key((list,), None, "dynamic: load scale as [[t, f], ...]"),
        "motion_function": Key((str,), None, "dynamic: scale of prescribed end values"),
    },
    "solver": {
        "rtol": Key(NUMBER, 1e-9, "relative residual tolerance"),
        "atol": Key(NUMBER, 1e-300, "absolute residual tolerance (units of the residual)"),
        "stol": Key(NUMBER, 1e-11, "relative step tolerance"),
        "max_it": Key((int,), 25, "Newton iterations per step"),
        "line_search": Key((str,), "basic", "basic | bt | l2 | cp"),
        "linear_solver": Key((str,), "auto", "auto | mumps | lu | gamg | gmres-ilu"),
        "petsc_options": Key((dict,), {}, "any PETSc option, without prefix"),
        "adaptive": Key((bool,), True, "cut back / grow load steps"),
        "min_increment": Key(NUMBER, 1e-5, "smallest load-factor increment"),
        "max_rotation_jump": Key(NUMBER, 1.0, "branch check: largest rotation change per step"),
        "allow_large": Key((bool,), False, "run work beyond the up-front limits (steps, dofs, "
                           "memory; fe_beam.runctl)"),
    },
    "output": {
        "xdmf": Key((bool,), True, "write XDMF for ParaView"),
        "plots": Key((bool,), True, "write PNG plots"),
        "gif": Key((bool,), False, "dynamic: animated GIF of the deformed beam"),
    },
}
# Tables owned by other commands (validated by them).
OTHER_TABLES = (
    "time",
    "initial",
    "damping",
    "modes",
    "tendons",
    "solid",
    "finger",
    "compare",
    "refine",
)


def load_config(path: str | Path) -> dict:
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"config file {str(path)!r} does not exist")
    try:
        with path.open("rb") as stream:
            return tomllib.load(stream)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise ConfigError(f"{path}: not valid TOML ({error})") from None


def _parse_value(text: str):
    try:
        return tomllib.loads(f"value = {text}")["value"]
    except tomllib.TOMLDecodeError:
        return text  # a bare word such as reissner


def apply_overrides(config: dict, assignments: list[str]) -> dict:
    """Apply ``table.key=value`` overrides (values in TOML syntax; bare words are strings).
    Arrays of tables are indexed from 0: ``tendons.0.tension=1.5``."""
    config = copy.deepcopy(config)
    for assignment in assignments or []:
        if "=" not in assignment:
            raise ConfigError(f"--set {assignment!r}: expected table.key=value")
        dotted, text = assignment.split("=", 1)
        names = dotted.strip().split(".")
        if len(names) < 2 or not all(names):
            raise ConfigError(f"--set {assignment!r}: expected table.key=value")
        target, position = config, 0
        while position < len(names) - 1:
            name = names[position]
            target = target.setdefault(name, {})
            position += 1
            if isinstance(target, list) and all(isinstance(item, dict) for item in target):
                index = names[position]
                if position >= len(names) - 1 or not index.isdigit() or int(index) >= len(target):
                    raise ConfigError(
                        f"--set {assignment!r}: {name} is an array of {len(target)} tables; "
                        f"address one as {name}.<index 0..{len(target) - 1}>.key"
                    )
                target = target[int(index)]
                position += 1
            elif not isinstance(target, dict):
                raise ConfigError(f"--set {assignment!r}: {name} is not a table")
        target[names[-1]] = _parse_value(text.strip())
    return config


def _type_name(types: tuple) -> str:
    names = {
        int: "an integer",
        float: "a number",
        str: "a string",
        bool: "true/false",
        list: "a list",
        dict: "a table",
    }
    if set(types) == {int, float}:
        return "a number"
    return " or ".join(names[t] for t in types)


def _checked(table: str, key: str, value, spec: Key):
    ok = isinstance(value, spec.types) and not (isinstance(value, bool) and bool not in spec.types)
    if not ok:
        raise ConfigError(
            f"[{table}] {key} must be {_type_name(spec.types)} ({spec.doc}); got {value!r}"
        )
    if isinstance(value, float) and not math.isfinite(value):
        raise ConfigError(f"[{table}] {key} must be finite; got {value!r}")
    return value


def table(
    config: dict, name: str, schema: dict[str, Key] | None = None, open_keys=lambda key: False
) -> dict:
    """A validated table with defaults filled in (unknown keys and wrong types are errors)."""
    schema = SCHEMA[name] if schema is None else schema
    given = config.get(name, {})
    if not isinstance(given, dict):
        raise ConfigError(f"[{name}] must be a table")
    unknown = [k for k in given if k not in schema and not open_keys(k)]
    if unknown:
        raise ConfigError(f"[{name}] unknown key {unknown[0]!r}; allowed: {', '.join(schema)}")
    values = {}
    for key, spec in schema.items():
        if key in given:
            values[key] = _checked(name, key, given[key], spec)
        elif spec.default is REQUIRED:
            raise ConfigError(f"[{name}] {key} is required ({spec.doc})")
        else:
            values[key] = copy.deepcopy(spec.default)
    values.update({k: v for k, v in given.items() if k not in schema})
    return values


def check_tables(config: dict, known: tuple[str, ...]) -> None:
    unknown = [name for name in config if name not in known]
    if unknown:
        raise ConfigError(f"unknown table [{unknown[0]}]; known tables: {', '.join(known)}")


@dataclass(frozen=True)
class OutputOptions:
    xdmf: bool = True
    plots: bool = True
    gif: bool = False


@dataclass(frozen=True)
class StaticConfig:
    model: BeamModel
    solver: SolverSettings = field(default_factory=SolverSettings)
    stepping: LoadStepping = field(default_factory=LoadStepping)
    max_rotation_jump: float = 1.0
    output: OutputOptions = field(default_factory=OutputOptions)
    tendons: tuple = ()
    raw: dict = field(default_factory=dict)


def _wrap(builder, *args, **kwargs):
    """Run a dataclass constructor, turning its ValueError into a ConfigError."""
    try:
        return builder(*args, **kwargs)
    except ConfigError:
        raise
    except (ValueError, TypeError) as error:
        raise ConfigError(str(error)) from None


def parse_section(config: dict) -> Section:
    values = table(config, "section", open_keys=lambda key: True)
    shape = values.pop("shape")
    dims, dims_tip = {}, {}
    for key, value in values.items():
        target, name = (dims_tip, key[:-4]) if key.endswith("_tip") else (dims, key)
        if isinstance(value, bool) or not isinstance(value, NUMBER):
            raise ConfigError(f"[section] {key} must be a number; got {value!r}")
        target[name] = value
    orphans = [n for n in dims_tip if n not in dims]
    if orphans:
        raise ConfigError(f"[section] {orphans[0]}_tip given without {orphans[0]}")
    return _wrap(Section, shape, dims, dims_tip)


def parse_model(config: dict) -> BeamModel:
    beam = table(config, "beam")
    material = table(config, "material")
    model = table(config, "model")
    mesh = table(config, "mesh")
    supports = table(config, "supports")
    loads = table(config, "loads")
    section = parse_section(config)
    return _wrap(
        BeamModel,
        length=beam["length"],
        section=section,
        material=_wrap(Material, **material),
        options=_wrap(ModelOptions, **model),
        mesh=_wrap(Discretisation, **mesh),
        supports=_wrap(
            Supports,
            x0=_support(supports["x0"]),
            xL=_support(supports["xL"]),
            prescribed_x0=loads["prescribed_x0"],
            prescribed_xL=loads["prescribed_xL"],
        ),
        loads=_wrap(
            Loads,
            tip_force=loads["tip_force"],
            tip_moment=loads["tip_moment"],
            follower=loads["follower"],
            distributed=loads["distributed"],
            gravity=loads["gravity"],
        ),
    )


def _support(spec):
    return tuple(spec) if isinstance(spec, list) else spec


def parse_solver(config: dict) -> tuple[SolverSettings, LoadStepping, float]:
    solver = table(config, "solver")
    steps = table(config, "loads")["steps"]
    stepping = _wrap(
        LoadStepping,
        steps=steps,
        adaptive=solver.pop("adaptive"),
        min_increment=min(solver.pop("min_increment"), 1.0 / max(steps, 1)),
    )
    jump = solver.pop("max_rotation_jump")
    solver.pop("allow_large")  # read from the raw table by the drivers (fe_beam.runctl)
    if not jump > 0:
        raise ConfigError(f"[solver] max_rotation_jump must be > 0; got {jump!r}")
    return _wrap(SolverSettings, **solver), stepping, float(jump)


def _spec(support) -> str:
    """A support as the user wrote it in TOML."""
    if isinstance(support, str):
        return f'"{support}"'
    return "[" + ", ".join(f'"{c}"' for c in support) + "]"


def parse_static(config: dict, rigid_motion_allowed: bool = False) -> StaticConfig:
    """The statics configuration; ``rigid_motion_allowed`` for dynamics and modes, where a
    beam free to move as a rigid body (free-free, flying) is meaningful."""
    check_tables(config, tuple(SCHEMA) + OTHER_TABLES)
    model = parse_model(config)
    settings, stepping, jump = parse_solver(config)
    if model.options.constraint != "none" and settings.linear_solver not in ("auto", "mumps"):
        raise ConfigError(
            f"[solver] linear_solver = \"{settings.linear_solver}\" cannot solve the saddle-point "
            f"systems of constraint = \"{model.options.constraint}\" (its multiplier rows have a "
            "zero diagonal); use linear_solver = \"auto\" or \"mumps\", or constraint = \"none\""
        )
    free = model.supports.rigid_motions()
    if free and not rigid_motion_allowed:
        raise ConfigError(
            f"[supports] x0 = {_spec(model.supports.x0)}, xL = {_spec(model.supports.xL)} leave "
            "the beam "
            f"free to move as a rigid body: {'; '.join(free)}. A static equilibrium needs "
            "supports that prevent it (e.g. x0 = \"clamped\", or x0 = \"pinned\" and "
            "xL = \"roller\")"
        )
    output = OutputOptions(**table(config, "output"))
    return StaticConfig(model, settings, stepping, jump, output, raw=config)

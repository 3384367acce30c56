"""The subcommands of ``fe-beam``, as data: one `CommandSpec` per command in `REGISTRY` (the
CLI's order) with its help, the tables it reads beyond the rod's (`fe_beam.config.keys.SCHEMA`),
its extra command-line arguments, its parser and the name of its driver. `validate` checks a
whole configuration for a command with the command's parser, without the finite-element stack;
`check_command_tables` notes (or refuses) tables the command would ignore. The CLI builds its
argument parser and finds its drivers here (`fe_beam.cli`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from fe_beam.config.buckling import parse_buckling
from fe_beam.config.calibrate import parse_calibrate
from fe_beam.config.compare import parse_compare
from fe_beam.config.design import parse_design
from fe_beam.config.finger import parse_finger
from fe_beam.config.keys import OTHER_TABLES, SCHEMA
from fe_beam.config.path import parse_path
from fe_beam.config.refine import REFINE_ARGUMENTS, plan_refinement
from fe_beam.config.schema import check_values, parse_static
from fe_beam.config.solid import parse_solid
from fe_beam.config.structure import check_structure_tables
from fe_beam.config.transient import parse_dynamic, parse_modes
from fe_beam.config.validity import parse_validity
from fe_beam.errors import ConfigError
from fe_beam.model.settings import SolverSettings

__all__ = ["COMMANDS", "COMMAND_TABLES", "REGISTRY", "CommandSpec", "Validated",
           "check_command_tables", "validate"]


@dataclass(frozen=True)
class CommandSpec:
    """One subcommand. ``tables``: the tables it reads besides the rod's; ``arguments``: its
    command-line options beyond CONFIG, --out, --set and --quiet, as (flags, argparse keywords);
    ``parse(config, options)``: the validated configuration (``options``: the values of
    ``arguments``, by name: refine's "levels", "ratio", "quantities", and its "solid_parser",
    the solid driver's validation, default `fe_beam.config.solid.parse_solid`); ``driver``:
    "module:function" of `fe_beam.analyses` that runs it; ``sorts_tables``: the command sorts
    its tables itself (no `check_command_tables` notes)."""

    name: str
    help: str
    tables: tuple[str, ...]
    parse: Callable[[dict, dict], object]
    driver: str
    arguments: tuple[tuple[tuple[str, ...], dict], ...] = ()
    sorts_tables: bool = False
    #: runs spatial rods (``[model] kinematics = "spatial"``); the others refuse them
    spatial: bool = False

    @property
    def driver_module(self) -> str:
        return self.driver.partition(":")[0]

    @property
    def driver_function(self) -> str:
        return self.driver.partition(":")[2]


def _rod_or_finger(config: dict):
    """The StaticConfig of a rod, or of a finger when the configuration has [[tendons]]."""
    return parse_finger(config)[0] if config.get("tendons") else parse_static(config)


def _parse_calibrate(config: dict, options: dict):
    parsed = _rod_or_finger(config)
    parse_calibrate(config)
    return parsed


def _parse_design(config: dict, options: dict):
    return _rod_or_finger(parse_design(config)[1])


def _parse_refine(config: dict, options: dict):
    return plan_refinement(config, options.get("levels"), options.get("ratio"),
                           options.get("quantities"),
                           solid_parser=options.get("solid_parser", parse_solid))


CALIBRATE_ARGUMENTS = (
    (("--data",), {"required": True, "metavar": "DATA.csv",
                   "help": "measurements (fe_beam.analyses.calibrate: columns)"}),
)

_SPECS = (
    CommandSpec("static", "large-deflection statics of a planar beam (load stepping, SNES)",
                ("obstacles", "contact"), lambda config, options: parse_static(config),
                "static:run", spatial=True),
    CommandSpec("finger", "tendon-driven tapered soft finger (reduced Cosserat rod with "
                          "[[tendons]])",
                ("tendons", "inverse", "obstacles", "contact"),
                lambda config, options: parse_finger(config),
                "finger:run", spatial=True),
    CommandSpec("design", "optimise section sizes, tendon offsets, tensions or loads for a "
                          "target ([design])",
                ("tendons", "design", "inverse", "obstacles", "contact"), _parse_design,
                "design:run"),
    CommandSpec("dynamic", "nonlinear dynamics (generalised-alpha, or the paper's FD + "
                           "Runge-Kutta)",
                ("time", "initial", "damping", "modes", "tendons", "obstacles", "contact"),
                lambda config, options: parse_dynamic(config), "dynamic:run", spatial=True),
    CommandSpec("modes", "natural frequencies and mode shapes (about the undeformed or a static "
                         "state)",
                ("time", "initial", "damping", "modes", "tendons"),
                lambda config, options: parse_modes(config), "modes:run", spatial=True),
    CommandSpec("solid", "3D hyperelastic finger (gmsh, tendon cables), with the 1D rod "
                         "alongside",
                ("tendons", "solid", "compare", "modes", "obstacles", "contact"),
                lambda config, options: parse_solid(config), "solid:run", spatial=True),
    CommandSpec("compare", "tension sweep: 3D solid vs the rod with the non-standard and "
                           "Reissner laws",
                ("tendons", "solid", "compare", "obstacles", "contact"),
                lambda config, options: parse_compare(config),
                "compare:run", spatial=True),
    CommandSpec("validity", "map of where the rod agrees with the 3D solid over two config keys "
                            "([validity])",
                ("tendons", "solid", "compare", "validity", "obstacles", "contact"),
                lambda config, options: parse_validity(config), "validity:run", spatial=True),
    CommandSpec("refine", "mesh-refinement study: observed order and Richardson extrapolation of "
                          "the tip",
                ("tendons", "solid", "refine"), _parse_refine, "refine:run",
                arguments=REFINE_ARGUMENTS, sorts_tables=True, spatial=True),
    CommandSpec("calibrate", "fit rod/finger parameters ([calibrate]) to measured tip poses and "
                             "backbone points (--data DATA.csv), with standard errors",
                ("tendons", "inverse", "calibrate"), _parse_calibrate,
                "calibrate:run", arguments=CALIBRATE_ARGUMENTS),
    CommandSpec("buckling", "linear buckling load factors and modes of the rod or the 3D solid "
                            "([buckling])",
                ("tendons", "solid", "buckling"), lambda config, options: parse_buckling(config),
                "buckling:run", spatial=True),
    CommandSpec("path", "arc-length path following with limit and bifurcation points ([path])",
                ("tendons", "solid", "path", "obstacles", "contact"),
                lambda config, options: parse_path(config),
                "path:run", spatial=True),
)

#: The subcommands, in the order of ``fe-beam --help``.
REGISTRY: dict[str, CommandSpec] = {spec.name: spec for spec in _SPECS}
COMMANDS = tuple(REGISTRY)
# Tables each command reads besides the rod's (SCHEMA). A table another command reads is refused
# when ignoring it would change the answer (tendons pull on the beam; [inverse] asks a question
# the command does not answer) and noted otherwise. refine sorts its configurations itself.
COMMAND_TABLES = {name: spec.tables for name, spec in REGISTRY.items() if not spec.sorts_tables}
#: The order in which the notes name the commands that read a table (that of the notes before
#: the registry, so that they read as they did).
READERS_ORDER = ("design", "static", "finger", "dynamic", "modes", "solid", "compare",
                 "calibrate", "buckling", "validity", "path", "refine")

REFUSED_UNUSED = ("tendons", "inverse", "obstacles", "contact")
#: how to run what a refused table asks for
REFUSED_HINTS = {
    "tendons": "fe-beam finger for a rod pulled by tendons",
    "inverse": "fe-beam finger for the tension that reaches a target",
    "obstacles": ("fe-beam static, fe-beam finger, fe-beam dynamic, fe-beam path, fe-beam "
                  "solid or fe-beam compare for contact with rigid obstacles"),
    "contact": ("fe-beam static, fe-beam finger, fe-beam dynamic, fe-beam path, fe-beam solid "
                "or fe-beam compare for contact with rigid obstacles"),
}
DYNAMIC_LOAD_KEYS = ("time_function", "time_table", "motion_function")


def _readers(name: str) -> str:
    commands = [command for command in READERS_ORDER if name in REGISTRY[command].tables]
    if not commands:
        return "no command"
    listed = commands[0] if len(commands) == 1 else (
        f"{', '.join(commands[:-1])} and {commands[-1]}")
    return f"fe-beam {listed}"


def check_command_tables(command: str, config: dict) -> list[str]:
    """ConfigError for a table the command would silently ignore although it changes the
    answer; notes (sentences) for other tables and keys the command does not use."""
    if command not in COMMAND_TABLES:
        return []
    used = COMMAND_TABLES[command]
    unused: dict[str, list[str]] = {}
    for name in config:
        if name in SCHEMA or name in used or name not in OTHER_TABLES + ("inverse",):
            continue
        if name in REFUSED_UNUSED:
            what = f"[[{name}]]" if name in ("tendons", "obstacles") else f"[{name}]"
            hint = REFUSED_HINTS[name]
            raise ConfigError(
                f"fe-beam {command} does not use {what}, which is read by {_readers(name)}: "
                f"run {hint}, or remove {what}")
        unused.setdefault(_readers(name), []).append(f"[{name}]")
    notes = []
    for readers, names in unused.items():
        listed = names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"
        verb = "is" if len(names) == 1 else "are"
        notes.append(f"{listed} {verb} not used by fe-beam {command} and ignored (read by "
                     f"{readers})")
    loads = config.get("loads")
    if command not in ("dynamic", "modes") and isinstance(loads, dict):
        timed = [key for key in DYNAMIC_LOAD_KEYS if key in loads]
        if timed:
            notes.append(f"[loads] {timed[0]} is read by fe-beam dynamic only; fe-beam {command} "
                         "applies the loads in full")
    tendons = config.get("tendons")
    if command not in ("dynamic", "modes") and isinstance(tendons, list):
        timed = [key for t in tendons if isinstance(t, dict)
                 for key in ("time_function", "time_table") if key in t]
        if timed:
            notes.append(f"[[tendons]] {timed[0]} is read by fe-beam dynamic only; fe-beam "
                         f"{command} applies the tensions in full")
    return notes


# --- one entry point: a whole configuration of any command, without the finite-element stack ----
@dataclass(frozen=True)
class Validated:
    """A configuration validated for ``command``: ``parsed`` is what the command's parser
    returns (`StaticConfig`; finger: (StaticConfig, InverseTarget | None); dynamic:
    `fe_beam.config.transient.DynamicConfig`; modes: (StaticConfig, [modes] table); solid:
    `fe_beam.config.solid.SolidConfig`; compare: `fe_beam.config.compare.CompareConfig`; refine:
    `fe_beam.config.refine.RefinementPlan`). ``petsc_options`` lists the solver settings whose
    PETSc options PETSc itself still has to accept (`fe_beam.solvers.newton.check_petsc_options`,
    where the solver is built: the CLI checks them before the run starts)."""

    command: str
    parsed: object
    petsc_options: tuple[dict, ...] = ()
    #: the configuration it was parsed from (the TOML after --set) and the command's options
    #: (refine: levels, ratio, quantities; calibrate: data): studies that vary configuration
    #: keys (validity, calibrate, design) read them
    config: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)


def _solver_settings(parsed) -> list:
    """The SolverSettings inside a parsed configuration (duck-typed: no imports)."""
    if isinstance(parsed, tuple):
        return [s for part in parsed for s in _solver_settings(part)]
    found = []
    for name in ("solver", "static", "rod", "solid", "parsed"):
        value = getattr(parsed, name, None)
        if isinstance(value, SolverSettings):
            found.append(value)
        elif value is not None and not isinstance(value, (dict, str, int, float)):
            found.extend(_solver_settings(value))
    return found


def validate(command: str, config: dict, refine: dict | None = None) -> Validated:
    """Validate the whole configuration ``config`` (the parsed TOML, after ``--set``) for
    ``command`` as the command's own parser does, raising ConfigError (one sentence naming the
    key) for the first mistake. Imports no dolfinx, PETSc or mpi4py: `fe-beam` answers a
    mistake before loading them. ``refine``: the refine command's --levels, --ratio, --quantity
    (strings or None)."""
    if command not in REGISTRY:
        raise ConfigError(f"unknown command {command!r}; one of {', '.join(COMMANDS)}")
    check_values(config)
    model = config.get("model")
    if isinstance(model, dict) and model.get("kinematics") == "spatial" \
            and not REGISTRY[command].spatial:
        runs = [spec.name for spec in _SPECS if spec.spatial]
        raise ConfigError(f"fe-beam {command} does not run spatial rods yet ([model] kinematics "
                          f"= \"spatial\"); the commands that do: {', '.join(runs)}")
    check_structure_tables(config, command)
    parsed = REGISTRY[command].parse(config, refine or {})
    options = []
    for settings in _solver_settings(parsed):
        if settings.petsc_options and settings.petsc_options not in options:
            options.append(dict(settings.petsc_options))
    return Validated(command, parsed, tuple(options), config, dict(refine or {}))

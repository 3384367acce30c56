"""The subcommand registry (`fe_beam.config.registry`): one entry per ``fe-beam`` command, the
CLI built from it, `validate` on every example, and the notes on tables a command ignores."""

from __future__ import annotations

import argparse
import ast
from pathlib import Path

import pytest

from fe_beam import analyses, cli
from fe_beam.config import REGISTRY, CommandSpec, ConfigError, load_config, validate
from fe_beam.config.compare import CompareConfig
from fe_beam.config.refine import RefinementPlan
from fe_beam.config.registry import COMMAND_TABLES, COMMANDS, READERS_ORDER, check_command_tables
from fe_beam.config.solid import SolidConfig
from fe_beam.config.transient import DynamicConfig
from fe_beam.config.validity import ValidityConfig
from fe_beam.model.studies import StaticConfig

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"

# example -> the commands it is written for, and the type validate() parses it into
EXAMPLE_COMMANDS = {
    "cantilever.toml": {"static": StaticConfig, "refine": RefinementPlan},
    "finger.toml": {"finger": tuple, "refine": RefinementPlan},
    "finger_design.toml": {"design": StaticConfig},
    "finger_grasp.toml": {"finger": tuple},
    "finger_grasp_design.toml": {"design": StaticConfig},
    "finger_wrap.toml": {"finger": tuple},
    "pinch.toml": {"finger": tuple},
    "finger_dynamics.toml": {"dynamic": DynamicConfig, "modes": tuple},
    "finger_solid.toml": {"solid": SolidConfig, "compare": CompareConfig,
                          "refine": RefinementPlan},
    "finger_validity.toml": {"validity": ValidityConfig},
    "flying_spaghetti.toml": {"dynamic": DynamicConfig},
    "release.toml": {"dynamic": DynamicConfig, "modes": tuple},
    "spin_up.toml": {"dynamic": DynamicConfig},
    "column_buckling.toml": {"buckling": tuple},
    "elastica_path.toml": {"path": tuple},
    "lee_frame.toml": {"path": tuple, "static": StaticConfig},
    "ring.toml": {"static": StaticConfig},
    "snap_through.toml": {"path": tuple},
    "spatial_finger.toml": {"finger": tuple},
    "bathe_bolourchi.toml": {"static": StaticConfig},
    "lateral_torsional.toml": {"buckling": tuple, "path": tuple},
    "spatial_tumbling.toml": {"dynamic": DynamicConfig},
    "section_laws/finger_dragon_skin_30.toml": {"solid": SolidConfig, "compare": CompareConfig},
    "section_laws/finger_neo_hookean.toml": {"solid": SolidConfig, "compare": CompareConfig},
}


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(sub.choices)


def test_every_subcommand_has_one_registry_entry_and_back():
    names = [spec.name for spec in REGISTRY.values()]
    assert len(names) == len(set(names))
    assert all(isinstance(spec, CommandSpec) and spec.name == key for key, spec in REGISTRY.items())
    assert list(_subcommands(cli._parser())) == list(REGISTRY)
    assert list(cli.COMMANDS) == list(REGISTRY) == list(COMMANDS)


def test_argparse_subcommands_carry_the_registry_help_and_arguments():
    for name, parser in _subcommands(cli._parser()).items():
        spec = REGISTRY[name]
        assert parser.description == spec.help
        options = {flag for action in parser._actions for flag in action.option_strings}
        for flags, _ in spec.arguments:
            assert set(flags) <= options, (name, flags)
    assert REGISTRY["refine"].arguments and REGISTRY["calibrate"].arguments


def test_drivers_are_named_functions_of_the_analyses_package():
    """Each driver is "module:function" of a module the lazy fe_beam.analyses package serves
    (read from the source: no driver module is imported; defined, imported or served lazily)."""
    for spec in REGISTRY.values():
        module, _, function = spec.driver.partition(":")
        assert module in analyses.DRIVERS and function, spec.driver
        path = ROOT / "fe_beam" / "analyses" / f"{module}.py"
        assert function == "run", spec.driver  # the driver contract (fe_beam.analyses.result)
        tree = ast.parse(path.read_text())
        defined = {node.name for node in tree.body if isinstance(node, ast.FunctionDef)}
        imported = {alias.asname or alias.name for node in tree.body
                    if isinstance(node, ast.ImportFrom) for alias in node.names}
        lazy = {node.value for node in ast.walk(tree)  # served by a PEP 562 __getattr__
                if isinstance(node, ast.Constant) and isinstance(node.value, str)}
        assert function in defined | imported | lazy, spec.driver


def test_tables_are_known_tables():
    from fe_beam.config.keys import OTHER_TABLES

    for spec in REGISTRY.values():
        assert set(spec.tables) <= set(OTHER_TABLES) | {"inverse"}, spec.name
    assert sorted(READERS_ORDER) == sorted(REGISTRY)
    assert "refine" not in COMMAND_TABLES  # refine sorts its tables itself


@pytest.mark.parametrize("example, command", [
    (example, command) for example, commands in EXAMPLE_COMMANDS.items() for command in commands])
def test_validate_every_example_for_its_commands(example, command):
    config = load_config(EXAMPLES / example)
    refine = {"levels": "3"} if command == "refine" else None
    validated = validate(command, config, refine)
    assert validated.command == command
    assert isinstance(validated.parsed, EXAMPLE_COMMANDS[example][command])


def test_every_example_is_covered():
    examples = {str(path.relative_to(EXAMPLES)) for path in EXAMPLES.rglob("*.toml")}
    assert examples == set(EXAMPLE_COMMANDS)
    assert {c for commands in EXAMPLE_COMMANDS.values() for c in commands} == set(REGISTRY) - {
        "calibrate"}  # calibrate needs a DATA.csv besides (tests/test_calibrate.py)


def test_unknown_command():
    with pytest.raises(ConfigError, match="unknown command 'nope'; one of static, finger, "):
        validate("nope", {})


def test_notes_on_unused_tables_unchanged():
    base = load_config(EXAMPLES / "cantilever.toml")
    config = dict(base, time={"dt": 0.1}, solid={"mesh_size": 0.01}, compare={}, refine={},
                  finger={})
    assert check_command_tables("static", config) == [
        "[time] is not used by fe-beam static and ignored (read by fe-beam dynamic and modes)",
        "[solid] is not used by fe-beam static and ignored (read by fe-beam solid, compare, "
        "buckling, validity, path and refine)",
        "[compare] is not used by fe-beam static and ignored (read by fe-beam solid, compare and "
        "validity)",
        "[refine] is not used by fe-beam static and ignored (read by fe-beam refine)",
        "[finger] is not used by fe-beam static and ignored (read by no command)",
    ]
    assert check_command_tables("path", dict(base, modes={}, validity={})) == [
        "[modes] is not used by fe-beam path and ignored (read by fe-beam dynamic, modes and "
        "solid)",
        "[validity] is not used by fe-beam path and ignored (read by fe-beam validity)",
    ]
    assert check_command_tables("refine", dict(base, time={})) == []
    timed = dict(base, loads={"time_function": "t"}, tendons=[{"time_table": []}])
    assert check_command_tables("finger", timed) == [
        "[loads] time_function is read by fe-beam dynamic only; fe-beam finger applies the loads "
        "in full",
        "[[tendons]] time_table is read by fe-beam dynamic only; fe-beam finger applies the "
        "tensions in full",
    ]


def test_tables_that_change_the_answer_are_refused_unchanged():
    base = load_config(EXAMPLES / "cantilever.toml")
    with pytest.raises(ConfigError) as error:
        check_command_tables("static", dict(base, tendons=[{}]))
    assert str(error.value) == (
        "fe-beam static does not use [[tendons]], which is read by fe-beam design, finger, "
        "dynamic, modes, solid, compare, calibrate, buckling, validity, path and refine: run "
        "fe-beam finger for a rod pulled by tendons, or remove [[tendons]]")
    with pytest.raises(ConfigError) as error:
        check_command_tables("solid", dict(base, inverse={}))
    assert str(error.value) == (
        "fe-beam solid does not use [inverse], which is read by fe-beam design, finger and "
        "calibrate: run fe-beam finger for the tension that reaches a target, or remove "
        "[inverse]")

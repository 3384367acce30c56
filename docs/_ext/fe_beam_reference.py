"""Everything the documentation reads from fe_beam's internals, in one place.

The command pages and the configuration reference are generated from what this module returns
(docs/_ext/fe_beam_docs.py). It reads the command registry (`fe_beam.config.registry.REGISTRY`:
each command's tables; its help and arguments through the CLI's parser, which is built from the
registry), the schema (`fe_beam.config.keys.SCHEMA`) and the key tables of the other commands.

Public interface:

* `commands()` -> [(name, help, extra arguments)], extra arguments being the command's own
  options beyond the ones every command takes (`common_arguments()`), each a dict with
  ``flags``, ``metavar``, ``help``, ``required``;
* `tables()` -> {table: {key: (types, default, doc)}}: ``types`` a tuple of type names,
  ``default`` the default value or `REQUIRED`, ``doc`` the help string in the code or None when
  the code has none;
* `command_tables()` -> {command: (tables it reads beyond the common ones)}.
"""

from __future__ import annotations

import argparse

__all__ = [
    "REQUIRED", "command_tables", "commands", "common_arguments", "section_dimensions", "tables",
]


class _Required:
    def __repr__(self) -> str:
        return "required"


#: the default of a key that must be given
REQUIRED = _Required()

#: options every command takes (shown once per page, from the parser)
_COMMON = ("config", "--out", "--set", "--quiet", "-h")


def _argument(action: argparse.Action) -> dict:
    flags = ", ".join(action.option_strings) or (action.metavar or action.dest)
    return {
        "flags": flags,
        "metavar": action.metavar if action.option_strings else None,
        "help": action.help or "",
        "required": bool(action.required),
        "takes_value": action.nargs != 0,
    }


def _subparsers():
    from fe_beam.cli import _parser

    parser = _parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {choice.dest: choice.help for choice in sub._choices_actions}
    return sub.choices, helps


def _is_common(action: argparse.Action) -> bool:
    names = action.option_strings or [action.dest]
    return any(name in _COMMON for name in names)


def commands() -> list[tuple[str, str, list[dict]]]:
    """Every command: (name, one-line help, its own arguments beyond `common_arguments()`)."""
    choices, helps = _subparsers()
    return [
        (name, helps.get(name, ""),
         [_argument(action) for action in parser._actions if not _is_common(action)])
        for name, parser in choices.items()
    ]


def common_arguments() -> list[dict]:
    """The arguments every command takes (CONFIG, --out, --set, --quiet), from the parser."""
    choices, _ = _subparsers()
    first = next(iter(choices.values()))
    return [_argument(action) for action in first._actions
            if _is_common(action) and "-h" not in action.option_strings]


def command_tables() -> dict[str, tuple[str, ...]]:
    """The tables each command reads beyond the common ones of `tables()`'s SCHEMA part."""
    from fe_beam.config.registry import REGISTRY

    return {name: tuple(spec.tables) for name, spec in REGISTRY.items()}


def _type_names(types) -> tuple[str, ...]:
    return tuple(getattr(kind, "__name__", str(kind)) for kind in types)


def _from_keys(keys: dict) -> dict:
    from fe_beam.config.keys import REQUIRED as CODE_REQUIRED

    return {
        name: (_type_names(key.types), REQUIRED if key.default is CODE_REQUIRED else key.default,
               key.doc or None)
        for name, key in keys.items()
    }


def _undocumented(names, types=()) -> dict:
    return {name: (tuple(types), None, None) for name in names}


def tables() -> dict[str, dict[str, tuple]]:
    """{table: {key: (types, default, doc)}} for every configuration table."""
    from fe_beam.config.buckling import BUCKLING_KEYS
    from fe_beam.config.calibrate import CALIBRATE_KEYS
    from fe_beam.config.compare import COMPARE_KEYS
    from fe_beam.config.contact import CONTACT_KEYS, OBSTACLE_KEYS
    from fe_beam.config.design import DESIGN_KEYS
    from fe_beam.config.finger import INVERSE_KEYS, TENDON_KEYS
    from fe_beam.config.keys import NUMBER, SCHEMA
    from fe_beam.config.path import PATH_KEYS
    from fe_beam.config.solid import SOLID_KEYS, SOLID_MODES_KEYS
    from fe_beam.config.structure import BODY_KEYS, JOINT_KEYS, ROD_KEYS
    from fe_beam.config.transient import (
        DAMPING_KEYS,
        INITIAL_KEYS,
        MODES_KEYS,
        TENDON_TIME_KEYS,
        TIME_KEYS,
    )
    from fe_beam.config.validity import VALIDITY_KEYS

    result = {name: _from_keys(keys) for name, keys in SCHEMA.items()}
    # [section]: the shape's dimensions are named by fe_beam.model.sections.SHAPES (no Key, no help)
    for names in section_dimensions().values():
        for name in names:
            result["section"].setdefault(name, (_type_names(NUMBER), None, None))
    result["tendons"] = _from_keys(TENDON_KEYS) | _undocumented(TENDON_TIME_KEYS)
    result["inverse"] = _from_keys(INVERSE_KEYS)
    result["obstacles"] = _from_keys(OBSTACLE_KEYS)
    result["contact"] = _from_keys(CONTACT_KEYS)
    result["time"] = _from_keys(TIME_KEYS)
    result["initial"] = _from_keys(INITIAL_KEYS)
    result["damping"] = _from_keys(DAMPING_KEYS)
    result["modes"] = _from_keys(MODES_KEYS)
    result["modes (fe-beam solid)"] = _from_keys(SOLID_MODES_KEYS)
    result["solid"] = _from_keys(SOLID_KEYS)
    result["compare"] = _from_keys(COMPARE_KEYS)
    result["validity"] = _from_keys(VALIDITY_KEYS)
    result["buckling"] = _from_keys(BUCKLING_KEYS)
    result["path"] = _from_keys(PATH_KEYS)
    result["rods"] = _from_keys(ROD_KEYS)
    result["joints"] = _from_keys(JOINT_KEYS)
    result["bodies"] = _from_keys(BODY_KEYS)
    result["design"] = _undocumented(DESIGN_KEYS)
    result["calibrate"] = _undocumented(CALIBRATE_KEYS)
    return result


def section_dimensions() -> dict[str, tuple[str, ...]]:
    """{section shape: its dimension keys} (fe_beam.model.sections.SHAPES)."""
    from fe_beam.model.sections import OPTIONAL_CUSTOM, SHAPES

    return {shape: tuple(names) + tuple(name for name in OPTIONAL_CUSTOM
                                        if shape == "custom" and name not in names)
            for shape, (_, names) in SHAPES.items()}

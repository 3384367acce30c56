"""The configuration layer: TOML files and ``--set`` overrides, validated into the model
layer's dataclasses, one parser per command. Imports no dolfinx, PETSc or mpi4py.

- `fe_beam.config.keys`: Key, the rod's tables (SCHEMA), the other commands' (OTHER_TABLES),
  `table`
- `fe_beam.config.schema`: check_values, load_config, apply_overrides, the rod's parser
  (`parse_static`), check_partition
- `fe_beam.config.finger`, `transient`, `solid`, `compare`, `buckling`, `path`, `validity`,
  `calibrate`, `design`, `refine`, `material_laws`: the parsers of the other commands
- `fe_beam.config.registry`: the subcommands (`REGISTRY` of `CommandSpec`), `validate`,
  `check_command_tables`
"""

from fe_beam.config.registry import (
    COMMANDS,
    REGISTRY,
    CommandSpec,
    Validated,
    check_command_tables,
    validate,
)
from fe_beam.config.schema import (
    ConfigError,
    OutputOptions,
    StaticConfig,
    apply_overrides,
    check_partition,
    check_values,
    load_config,
    parse_static,
)

__all__ = [
    "COMMANDS",
    "REGISTRY",
    "CommandSpec",
    "ConfigError",
    "OutputOptions",
    "StaticConfig",
    "Validated",
    "apply_overrides",
    "check_command_tables",
    "check_partition",
    "check_values",
    "load_config",
    "parse_static",
    "validate",
]

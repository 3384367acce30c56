"""The configuration layer: TOML files and ``--set`` overrides, validated into the model
layer's dataclasses, one parser per command. Imports no dolfinx, PETSc or mpi4py.

- `fe_beam.config.schema`: Key, table, SCHEMA, check_values, load_config, apply_overrides,
  the rod's parser (`parse_static`) and `validate`
- `fe_beam.config.finger`, `transient`, `solid`, `compare`, `buckling`, `path`, `validity`,
  `material_laws`: the parsers of the other commands
"""

from fe_beam.config.schema import (
    ConfigError,
    OutputOptions,
    StaticConfig,
    apply_overrides,
    check_command_tables,
    check_values,
    load_config,
    parse_static,
    validate,
)

__all__ = [
    "ConfigError",
    "OutputOptions",
    "StaticConfig",
    "apply_overrides",
    "check_command_tables",
    "check_values",
    "load_config",
    "parse_static",
    "validate",
]

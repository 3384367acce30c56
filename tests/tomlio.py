"""TOML text of nested dicts for the configuration tests (tables and arrays of tables)."""

import math


def toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return "nan" if math.isnan(value) else repr(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(value)


def dump_toml(config: dict) -> str:
    """TOML text of ``config`` (tables, and arrays of tables for lists of dicts)."""
    lines = [f"{k} = {toml_value(v)}" for k, v in config.items()
             if not isinstance(v, (dict, list))]
    for name, values in config.items():
        if not isinstance(values, (dict, list)):
            continue
        if isinstance(values, list) and all(isinstance(v, dict) for v in values):
            for entry in values:
                lines.append(f"[[{name}]]")
                lines += [f"{k} = {toml_value(v)}" for k, v in entry.items()]
                lines.append("")
            continue
        lines.append(f"[{name}]")
        lines += [f"{k} = {toml_value(v)}" for k, v in values.items()]
        lines.append("")
    return "\n".join(lines)

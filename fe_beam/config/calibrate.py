"""The ``[calibrate]`` table and the DATA.csv of ``fe-beam calibrate`` (`parse_calibrate`,
`read_data`, `check_data`): FE-free checks, ConfigError with one sentence on any mistake. The fit
is `fe_beam.analyses.calibrate`.

DATA.csv columns: one of ``tension`` / ``load_factor``, and any of ``tip_u``, ``tip_v``,
``tip_theta`` and backbone points ``x``, ``y`` (optionally at reference coordinate ``s``).
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fe_beam.config.finger import with_defaults
from fe_beam.errors import ConfigError

__all__ = ["CALIBRATE_KEYS", "DATA_COLUMNS", "MEASURED", "CalibrationData", "CalibrationSpec",
           "check_data", "parameter_kind", "parse_calibrate", "read_data"]

SECTION_DIMS = ("b", "h", "d", "t", "tf", "tw", "A", "I", "I3", "I4")
DATA_COLUMNS = ("tension", "load_factor", "tip_u", "tip_v", "tip_theta", "s", "x", "y")
MEASURED = ("tip_u", "tip_v", "tip_theta", "x", "y")
CALIBRATE_KEYS = ("parameters", "bounds", "weights")
MAX_DATA_BYTES = 64 * 2**20


def parameter_kind(key) -> str:
    """The kind of a parameter key (material, section, load, tension, pull_in, offset), or a
    `ConfigError` naming what is allowed."""
    if not isinstance(key, str):
        raise ConfigError(f"[calibrate] parameters must be config keys (strings), got {key!r}")
    if key in ("material.E", "material.nu", "material.G", "material.rho"):
        return "material"
    m = re.fullmatch(r"section\.([A-Za-z0-9]+?)(_tip)?", key)
    if m and m.group(1) in SECTION_DIMS:
        return "section"
    m = re.fullmatch(r"rods\.([^.]+)\.(section|material)\.([A-Za-z0-9]+)", key)
    if m and (m.group(2) == "section" and m.group(3) in SECTION_DIMS
              or m.group(2) == "material" and m.group(3) in ("E", "G")):
        return f"rod_{m.group(2)}"
    if key == "loads.tip_moment" or re.fullmatch(r"loads\.(tip_force|distributed|gravity)\.[01]",
                                                 key):
        return "load"
    m = re.fullmatch(r"tendons\.(\d+)\.(.+)", key)
    if m:
        rest = m.group(2)
        if rest in ("tension", "pull_in"):
            return rest
        if rest in ("offset_base", "offset_tip") or re.fullmatch(r"path\.\d+\.1", rest) \
                or re.fullmatch(r"paths\.\d+\.\d+\.1", rest):
            return "offset"
    raise ConfigError(
        f"unknown parameter {key!r}: parameters are material.E|nu|G|rho, section.<dim>[_tip], "
        "loads.tip_force.0|1, loads.tip_moment, loads.distributed.0|1, loads.gravity.0|1, "
        "tendons.<i>.tension|pull_in|offset_base|offset_tip, tendons.<i>.path.<k>.1, "
        "tendons.<i>.paths.<b>.<k>.1 or, with [[rods]], rods.<name>.section.<dim> and "
        "rods.<name>.material.E|G")


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


@dataclass(frozen=True)
class CalibrationSpec:
    """The [calibrate] table: parameters (config keys), bounds {key: (low, high)} and weights
    {data column: weight}."""

    parameters: tuple
    bounds: dict = field(default_factory=dict)
    weights: dict = field(default_factory=dict)


def _config_value(raw: dict, key: str):
    """The number a parameter key names in the raw configuration (None if not given)."""
    node = raw
    for part in key.split("."):
        if isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                return None
            node = node[int(part)]
        elif isinstance(node, dict):
            if part not in node:
                return None
            node = node[part]
        else:
            return None
    return node


def parse_calibrate(raw: dict) -> CalibrationSpec:
    """Validate [calibrate] (FE-free): ConfigError with one sentence on any mistake."""
    table = raw.get("calibrate")
    if not isinstance(table, dict):
        raise ConfigError("fe-beam calibrate needs a [calibrate] table with parameters = "
                          "[\"material.E\", ...]")
    unknown = [k for k in table if k not in CALIBRATE_KEYS]
    if unknown:
        raise ConfigError(f"[calibrate] {unknown[0]} is not a key of [calibrate] (allowed: "
                          f"{', '.join(CALIBRATE_KEYS)})")
    parameters = table.get("parameters")
    if not isinstance(parameters, list) or not parameters:
        raise ConfigError("[calibrate] parameters must be a non-empty list of config keys, got "
                          f"{parameters!r}")
    for key in parameters:
        if not isinstance(key, str):
            raise ConfigError(f"[calibrate] parameters must be config keys (strings), got "
                              f"{key!r}")
        value = _config_value(raw, key)
        if value is not None and not _number(value):
            raise ConfigError(f"[calibrate] parameter {key!r} is not numeric (its value is "
                              f"{value!r}): only numbers can be fitted")
        parameter_kind(key)
    if len(set(parameters)) != len(parameters):
        raise ConfigError("[calibrate] parameters lists a key twice")
    bounds = table.get("bounds", {})
    if not isinstance(bounds, dict):
        raise ConfigError("[calibrate] bounds must be a table {\"key\" = [low, high]}")
    parsed_bounds = {}
    for key, pair in bounds.items():
        if key not in parameters:
            raise ConfigError(f"[calibrate] bounds names {key!r}, which is not in parameters")
        if not (isinstance(pair, list) and len(pair) == 2 and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and not math.isnan(v)
                for v in pair) and pair[0] < pair[1]):
            raise ConfigError(f"[calibrate] bounds.{key} must be [low, high] with low < high, "
                              f"got {pair!r}")
        parsed_bounds[key] = (float(pair[0]), float(pair[1]))
    weights = table.get("weights", {})
    if not isinstance(weights, dict):
        raise ConfigError("[calibrate] weights must be a table {column = weight}")
    for key, value in weights.items():
        if key not in MEASURED:
            raise ConfigError(f"[calibrate] weights.{key}: weights are given per data column, "
                              f"one of {', '.join(MEASURED)}")
        if not _number(value) or value <= 0:
            raise ConfigError(f"[calibrate] weights.{key} must be a number > 0, got {value!r}")
    return CalibrationSpec(tuple(parameters), parsed_bounds,
                           {k: float(v) for k, v in weights.items()})


@dataclass(frozen=True)
class CalibrationData:
    """The measurements: ``load_column`` ("tension" or "load_factor"), one entry per row in
    ``loads``, and per measured column its values (NaN: not measured in that row)."""

    load_column: str
    loads: np.ndarray
    columns: dict
    s: np.ndarray | None = None

    def count(self) -> int:
        """Number of residuals: measured values; a backbone point without ``s`` is one (its
        distance to the backbone)."""
        total = sum(np.count_nonzero(np.isfinite(v)) for v in self.columns.values())
        if self.s is None and "y" in self.columns:
            total -= np.count_nonzero(np.isfinite(self.columns["y"]))
        return int(total)


def read_data(path) -> CalibrationData:
    """Read DATA.csv (FE-free): ConfigError with one sentence on any mistake."""
    path = Path(path)
    name = str(path)
    if not path.is_file():
        raise ConfigError(f"data file {name} does not exist or is not a file")
    if path.stat().st_size > MAX_DATA_BYTES:
        raise ConfigError(f"data file {name} is larger than {MAX_DATA_BYTES // 2**20} MiB")
    try:
        with path.open(newline="", encoding="utf-8-sig") as stream:  # a BOM (Excel) too
            rows = [row for row in csv.reader(stream) if any(c.strip() for c in row)]
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise ConfigError(f"data file {name} cannot be read as CSV ({error})") from None
    if not rows:
        raise ConfigError(f"data file {name} is empty (it needs a header line and rows)")
    header = [c.strip() for c in rows[0]]
    unknown = [c for c in header if c not in DATA_COLUMNS]
    if unknown:
        raise ConfigError(f"data file {name}: unknown column {unknown[0]!r} (columns: "
                          f"{', '.join(DATA_COLUMNS)})")
    if len(set(header)) != len(header):
        raise ConfigError(f"data file {name}: a column appears twice in the header")
    loads = [c for c in ("tension", "load_factor") if c in header]
    if len(loads) != 1:
        raise ConfigError(f"data file {name} needs exactly one of the columns tension or "
                          "load_factor")
    measured = [c for c in MEASURED if c in header]
    if not measured:
        raise ConfigError(f"data file {name} has no measured column (any of "
                          f"{', '.join(MEASURED)})")
    if ("x" in header) != ("y" in header) or ("s" in header and "x" not in header):
        raise ConfigError(f"data file {name}: backbone points need both columns x and y (and "
                          "optionally s, their reference coordinate)")
    table = {c: [] for c in header}
    for number, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise ConfigError(f"data file {name} line {number} has {len(row)} cells, the header "
                              f"{len(header)}")
        for column, cell in zip(header, row, strict=True):
            text = cell.strip()
            if not text and (column in MEASURED or column == "s"):
                table[column].append(math.nan)
                continue
            try:
                value = float(text)
            except ValueError:
                value = None
            if value is None or not math.isfinite(value):
                raise ConfigError(f"data file {name} line {number}: {column} = {text!r} is not a "
                                  "finite number")
            table[column].append(value)
    if len(rows) < 2:
        raise ConfigError(f"data file {name} has a header but no data rows")
    s = np.array(table["s"]) if "s" in table else None
    given = np.isfinite(s) if s is not None else np.isfinite(np.array(table.get("x", [])))
    if "x" in table:
        for column in ("x", "y"):
            if np.any(np.isfinite(np.array(table[column])) != given):
                raise ConfigError(f"data file {name}: x and y (and s) of a backbone point must "
                                  "be given together (a row has one of them empty)")
    load = loads[0]
    values = np.array(table[load])
    if load == "load_factor" and np.any(values < 0) or load == "tension" and np.any(values < 0):
        raise ConfigError(f"data file {name}: {load} must be >= 0")
    return CalibrationData(load, values, {c: np.array(table[c]) for c in measured}, s)

def check_data(raw: dict, data_path) -> tuple[CalibrationSpec, CalibrationData]:
    """[calibrate] and DATA.csv checked together (FE-free: the command calls it before the
    FE stack is loaded): ConfigError with one sentence on any mistake."""
    spec = parse_calibrate(raw)
    data = read_data(data_path)
    if data.count() < len(spec.parameters):
        raise ConfigError(f"{len(spec.parameters)} parameters cannot be fitted to "
                          f"{data.count()} measured values in {data_path} (give at least as "
                          "many data as parameters)")
    merged = raw
    if raw.get("tendons"):
        merged = with_defaults(raw)  # FE-free: the finger's beam length
    length = (merged.get("beam") or {}).get("length") if isinstance(merged, dict) else None
    if data.s is not None and _number(length):
        outside = np.flatnonzero(np.isfinite(data.s) & ((data.s < 0) | (data.s > length)))
        if len(outside):
            raise ConfigError(f"data file {data_path}: s = {data.s[outside[0]]:g} (data row "
                              f"{outside[0] + 1}) lies outside the rod, s in [0, {length:g}] m")
    absent = [c for c in spec.weights if c not in data.columns]
    if absent:
        raise ConfigError(f"[calibrate] weights.{absent[0]}: {data_path} has no column "
                          f"{absent[0]} (columns with data: {', '.join(data.columns)})")
    return spec, data

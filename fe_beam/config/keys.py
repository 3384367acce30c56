"""The vocabulary of a configuration: `Key` (type, default, doc of one key), the rod's tables
(`SCHEMA`), the tables of the other commands (`OTHER_TABLES`) and `table`, which validates one
table against its keys. The lowest module of the config layer: the parsers build on it."""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

from fe_beam.errors import ConfigError
from fe_beam.model.loads import LOADS
from fe_beam.model.sections import SHAPES
from fe_beam.timefunctions import shown

MAX_COUNT = 2**31 - 1  # integer keys are counts (elements, steps, iterations): C ints downstream
NUMBER = (int, float)
REQUIRED = object()


@dataclass(frozen=True)
class Key:
    types: tuple
    default: object = None
    doc: str = ""


# Tables and keys every command understands; commands read the tables they need. A key not
# listed here is a mistake (typically a typo) and is reported, never ignored.
def _load_key(kind) -> Key:
    """The [loads] key of a registered load (`fe_beam.model.loads.LoadKind`)."""
    types = NUMBER if kind.kind == "scalar" else (list,)
    default = None if kind.motion else {"vector": [0.0, 0.0], "scalar": 0.0, "points": []}[
        kind.kind]
    return Key(types, default, kind.help)


SCHEMA: dict[str, dict[str, Key]] = {
    "beam": {"length": Key(NUMBER, REQUIRED, "beam length L [m]"),
             "initial_curvature": Key((list,), None, "spatial: intrinsic curvature [k_twist, "
                                      "k_y, k_z] [1/m], numbers or formulas of s and L")},
    "section": {"shape": Key((str,), "rectangle", f"one of {', '.join(SHAPES)}")},
    "material": {
        "E": Key(NUMBER, REQUIRED, "Young's modulus [Pa]"),
        "nu": Key(NUMBER, None, "Poisson's ratio (or give G)"),
        "G": Key(NUMBER, None, "shear modulus [Pa] (or give nu)"),
        "rho": Key(NUMBER, 0.0, "density [kg/m^3]"),
    },
    "model": {
        "kinematics": Key((str,), "planar", "planar (u, v, theta in the x-y plane) | spatial "
                          "(3D centreline and rotations)"),
        "law": Key((str,), "nonstandard", "nonstandard | reissner | hyperelastic"),
        "constraint": Key(
            (str,), "none", "none | inextensible | unshearable | inextensible-unshearable"
        ),
        "shear_correction": Key(NUMBER, 1.0, "k of the Reissner law"),
        # law = "hyperelastic" only: the 3D law (same keys, meaning and defaults as [solid])
        "material": Key((str,), None, "hyperelastic: neo-hookean (default) | mooney-rivlin | "
                        "yeoh | svk"),
        "preset": Key((str,), None, "hyperelastic: silicone preset (sets the constants)"),
        "mu": Key(NUMBER, None, "hyperelastic: shear modulus [Pa] (neo-hookean, svk)"),
        "c10": Key(NUMBER, None, "hyperelastic: C10 [Pa] (mooney-rivlin, yeoh)"),
        "c01": Key(NUMBER, None, "hyperelastic: C01 [Pa] (mooney-rivlin)"),
        "c20": Key(NUMBER, None, "hyperelastic: C20 [Pa] (yeoh)"),
        "c30": Key(NUMBER, None, "hyperelastic: C30 [Pa] (yeoh)"),
        "kappa": Key(NUMBER, None, "hyperelastic: bulk modulus [Pa] (default from [material] "
                     "nu)"),
        "volumetric": Key((str,), None, "hyperelastic: simo_taylor (default) | quadratic"),
        "section_points": Key((int,), None, "hyperelastic: Gauss points per section part "
                              "(default 6)"),
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
        # the loads of the registry (fe_beam.model.loads), in its order
        "tip_force": _load_key(LOADS["tip_force"]),
        "tip_moment": _load_key(LOADS["tip_moment"]),
        "follower": Key((bool,), False, "tip force follows the tip section"),
        **{name: _load_key(LOADS[name]) for name in ("distributed", "gravity")},
        "prescribed_x0": Key((dict,), {}, "{u|v|theta = value} of fixed components at x = 0"),
        "prescribed_xL": Key((dict,), {}, "{u|v|theta = value} of fixed components at x = L"),
        **{name: _load_key(kind) for name, kind in LOADS.items()
           if name not in ("tip_force", "tip_moment", "distributed", "gravity")},
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
        "max_increment": Key(NUMBER, None, "largest load-factor increment: easy steps grow up "
                             "to it (default 1/steps: never beyond the first increment)"),
        "easy_iterations": Key((int,), 4, "a load step converged in at most this many Newton "
                               "iterations lets the next one grow (up to max_increment)"),
        "max_rotation_jump": Key(NUMBER, 1.0, "branch check: largest rotation change per step"),
        "allow_large": Key((bool,), False, "run work beyond the up-front limits (steps, dofs, "
                           "memory; fe_beam.runctl)"),
    },
    "checks": {
        "strict": Key((bool,), True, "a failed run-time check (equilibrium, energy balance, "
                      "confirmed critical point, penetration ...) stops the run with exit code 3 "
                      "(true) or is reported as a warning in notes (false); summary.json's "
                      "checks lists them either way"),
    },
    "output": {
        "xdmf": Key((bool,), True, "write XDMF for ParaView"),
        "plots": Key((bool,), True, "write PNG plots"),
        "gif": Key((bool,), False, "dynamic: animated GIF of the deformed beam"),
    },
}
# spatial rods take vectors where planar ones take a number
for _name, _doc in (("tip_moment", "moment at x = L [N m]: a number (about z), or [Mx, My, Mz] "
                     "for spatial rods"),
                    ("end_rotation", "rotation prescribed at x = L [rad]: a number (about z), "
                     "or a rotation vector [x, y, z] for spatial rods")):
    SCHEMA["loads"][_name] = Key(NUMBER + (list,), SCHEMA["loads"][_name].default, _doc)

# Tables owned by other commands (validated by them).
OTHER_TABLES = (
    "design",
    "time",
    "initial",
    "damping",
    "modes",
    "tendons",
    "solid",
    "finger",
    "compare",
    "refine",
    "calibrate",
    "buckling",
    "validity",
    "path",
    "obstacles",
    "contact",
)

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
            f"[{table}] {key} must be {_type_name(spec.types)} ({spec.doc}); got {shown(value)}"
        )
    if isinstance(value, float) and not math.isfinite(value):
        raise ConfigError(f"[{table}] {key} must be finite; got {value!r}")
    if spec.types == (int,) and abs(value) > MAX_COUNT:
        raise ConfigError(f"[{table}] {key} = {shown(value)} is out of range ({spec.doc}; an "
                          f"integer from -{MAX_COUNT} to {MAX_COUNT})")
    return value


def table(
    config: dict, name: str, schema: dict[str, Key] | None = None, open_keys=lambda key: False
) -> dict:
    """A validated table with defaults filled in (unknown keys and wrong types are errors)."""
    schema = SCHEMA[name] if schema is None else schema
    given = config.get(name, {})
    if isinstance(given, list):
        raise ConfigError(f"[{name}] must be one table, written [{name}]; the config has an "
                          f"array of tables [[{name}]]")
    if not isinstance(given, dict):
        raise ConfigError(f"[{name}] must be a table; got {shown(given)}")
    unknown = [k for k in given if k not in schema and not open_keys(k)]
    if unknown:
        raise ConfigError(f"[{name}] unknown key {shown(unknown[0])}; allowed: {', '.join(schema)}")
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
        raise ConfigError(f"unknown table [{shown(unknown[0])[1:-1]}]; known tables: "
                          f"{', '.join(known)}")


def _wrap(builder, *args, **kwargs):
    """Run a dataclass constructor, turning its ValueError into a ConfigError."""
    try:
        return builder(*args, **kwargs)
    except ConfigError:
        raise
    except (ValueError, TypeError) as error:
        raise ConfigError(str(error)) from None

MAX_COUNT = 2**31 - 1  # integer keys are counts (elements, steps, iterations): C ints downstream

"""Configuration mistakes, through ``fe_beam.cli.main``: exit code 2, one sentence naming the key.

All of these fail during validation, before any form is compiled, so they are fast.
"""

import copy
import math
import re

import pytest
from tomlio import dump_toml, toml_value  # noqa: F401  (re-exported to the CLI tests)

from fe_beam.cli import main

EI = 2.0e11 * 0.01**4 / 12

BASE = {
    "beam": {"length": 1.0},
    "section": {"shape": "rectangle", "b": 0.01, "h": 0.01},
    "material": {"E": 2.0e11, "nu": 0.3},
    "model": {"law": "nonstandard", "constraint": "none"},
    "mesh": {"elements": 8, "degree": 2},
    "supports": {"x0": "clamped", "xL": "free"},
    "loads": {"tip_force": [0.0, -2.0 * EI], "steps": 5},
    "output": {"xdmf": True, "plots": False},
}
DROP = object()


def edited(changes: dict) -> dict:
    """BASE with ``{"table.key": value or DROP}`` applied."""
    config = copy.deepcopy(BASE)
    for dotted, value in changes.items():
        table, key = dotted.split(".", 1)
        if value is DROP:
            del config[table][key]
        else:
            config.setdefault(table, {})[key] = value
    return config


def run_cli(tmp_path, config, *extra, capsys):
    """Write ``config`` (dict or TOML text) and run ``fe-beam static`` in-process.

    Returns (exit code, stderr, output folder, config path).
    """
    path = tmp_path / "c.toml"
    path.write_text(config if isinstance(config, str) else dump_toml(config))
    out = tmp_path / "out"
    capsys.readouterr()
    code = main(["static", str(path), "--out", str(out), "--quiet", *extra])
    return code, capsys.readouterr().err, out, path


def usage_error(code, err, path) -> str:
    """Check the exit-2 contract and return the message after the standard prefix."""
    assert code == 2, err
    assert "Traceback" not in err
    assert err.endswith("\n") and err.count("\n") == 1, f"not one line: {err!r}"
    prefix = f"fe-beam static: error in {path}: "
    assert err.startswith(prefix), err
    return err[len(prefix) :].strip()


def names_key(message: str, table: str, key: str) -> bool:
    """The message names table.key, either as ``table.key`` or as ``[table] key``."""
    key = re.escape(key)
    pattern = rf"(\b{table}\.{key}|\[{table}\] {key})(?![A-Za-z0-9_])"
    return re.search(pattern, message) is not None


def test_base_config_is_valid():
    """Guard for the cases below: the unedited base config parses (no solve here)."""
    from fe_beam.config.schema import parse_static

    parsed = parse_static(BASE)
    assert parsed.model.mesh.elements == 8
    assert parsed.model.loads.tip_force == (0.0, -2.0 * EI)


CASES = {
    # missing keys
    "missing beam.length": ({"beam.length": DROP}, ("beam", "length")),
    "missing material.E": ({"material.E": DROP}, ("material", "E")),
    # wrong types
    "string for number": ({"material.E": "2e11"}, ("material", "E")),
    "string for length": ({"beam.length": "1 m"}, ("beam", "length")),
    "float for elements": ({"mesh.elements": 8.0}, ("mesh", "elements")),
    "bool for number": ({"beam.length": True}, ("beam", "length")),
    "bool for E": ({"material.E": False}, ("material", "E")),
    "bool for h": ({"section.h": True}, ("section", "h")),
    "string for h": ({"section.h": "0.01"}, ("section", "h")),
    "nan E": ({"material.E": math.nan}, ("material", "E")),
    # values out of range
    "E zero": ({"material.E": 0.0}, ("material", "E")),
    "E negative": ({"material.E": -2.0e11}, ("material", "E")),
    "nu 0.5": ({"material.nu": 0.5}, ("material", "nu")),
    "h zero": ({"section.h": 0.0}, ("section", "h")),
    "h negative": ({"section.h": -0.01}, ("section", "h")),
    "h_tip negative": ({"section.h_tip": -0.01}, ("section", "h_tip")),
    "length zero": ({"beam.length": 0.0}, ("beam", "length")),
    "elements zero": ({"mesh.elements": 0}, ("mesh", "elements")),
    "elements negative": ({"mesh.elements": -3}, ("mesh", "elements")),
    "degree 3": ({"mesh.degree": 3}, ("mesh", "degree")),
    "unknown law": ({"model.law": "kirchhoff"}, ("model", "law")),
    "unknown constraint": ({"model.constraint": "rigid"}, ("model", "constraint")),
    "unknown shape": ({"section.shape": "ellipse"}, ("section", "shape")),
    "unknown dimension": ({"section.d": 0.01}, ("section", "d")),
    "steps zero": ({"loads.steps": 0}, ("loads", "steps")),
    # supports and loads
    "unknown support name": ({"supports.x0": "fixed"}, ("supports", "x0")),
    "support unknown component": ({"supports.xL": ["u", "w"]}, ("supports", "xL")),
    "support repeated component": ({"supports.xL": ["v", "v"]}, ("supports", "xL")),
    "support non-string component": ({"supports.x0": ["u", 1]}, ("supports", "x0")),
    "support number": ({"supports.x0": 1}, ("supports", "x0")),
    "tip_force one value": ({"loads.tip_force": [1.0]}, ("loads", "tip_force")),
    "tip_force three values": ({"loads.tip_force": [1.0, 2.0, 3.0]}, ("loads", "tip_force")),
    "tip_force string": ({"loads.tip_force": "down"}, ("loads", "tip_force")),
    "tip_force scalar": ({"loads.tip_force": -1.0}, ("loads", "tip_force")),
    "tip_force string entry": ({"loads.tip_force": [0.0, "-1"]}, ("loads", "tip_force")),
    "tip_force bool entry": ({"loads.tip_force": [0.0, True]}, ("loads", "tip_force")),
    "prescribed on free component": (
        {"loads.prescribed_xL": {"theta": 1.0}},
        ("loads", "prescribed_xL.theta"),
    ),
    "prescribed on unfixed component": (
        {"supports.x0": "pinned", "loads.prescribed_x0": {"theta": 1.0}},
        ("loads", "prescribed_x0.theta"),
    ),
    "gravity without density": ({"loads.gravity": [0.0, -9.81]}, ("loads", "gravity")),
    # a static solve of a mechanism: its stiffness is singular
    "free-free": ({"supports.x0": "free"}, ("supports", "x0")),
    "roller-roller": ({"supports.x0": "roller", "supports.xL": "roller"}, ("supports", "x0")),
    "pinned-free": ({"supports.x0": "pinned"}, ("supports", "x0")),
    "iterative solver with multipliers": (
        {"solver.linear_solver": "gamg", "model.constraint": "inextensible"},
        ("solver", "linear_solver"),
    ),
    "fieldsplit for the rod": ({"solver.linear_solver": "fieldsplit"}, ("solver", "linear_solver")),
    "PETSc LU with multipliers": (
        {"solver.linear_solver": "lu", "model.constraint": "unshearable"},
        ("solver", "linear_solver"),
    ),
    # PETSc options: PETSc itself is asked
    "unknown KSP type": ({"solver.petsc_options": {"ksp_type": "nonsense"}},
                         ("solver", "petsc_options.ksp_type")),
    "non-numeric PETSc value": ({"solver.petsc_options": {"snes_max_it": "many"}},
                                ("solver", "petsc_options.snes_max_it")),
    "PETSc option with dash": ({"solver.petsc_options": {"-ksp_type": "cg"}},
                               ("solver", "petsc_options")),
}


@pytest.mark.parametrize("x0, xL, free", [
    ("clamped", "free", []), ("pinned", "roller", []), (["theta"], "pinned", []),
    ("free", "free", ["x", "y"]), ("roller", "roller", ["x"]), ("pinned", "free", ["y"]),
    (["u"], ["v"], ["y"]), (["theta"], "roller", ["x"]),
])
def test_rigid_motions_left_free_by_the_supports(x0, xL, free):
    from fe_beam import Supports

    described = Supports(x0, xL).rigid_motions()
    assert [text.split()[2] for text in described] == [f"{axis}" for axis in free]


def test_set_addresses_arrays_of_tables_by_index():
    from fe_beam.config.schema import apply_overrides
    from fe_beam.errors import ConfigError

    config = {"tendons": [{"tension": 1.0}, {"tension": 2.0}]}
    changed = apply_overrides(config, ["tendons.1.tension=3.5", "tendons.0.name=flexor"])
    assert changed["tendons"] == [{"tension": 1.0, "name": "flexor"}, {"tension": 3.5}]
    assert config["tendons"][1]["tension"] == 2.0  # the input is not modified
    for bad in ("tendons.2.tension=1", "tendons.tension=1", "tendons.0=1"):
        with pytest.raises(ConfigError, match=r"array of 2 tables.*tendons\.<index 0\.\.1>"):
            apply_overrides(config, [bad])


def test_supports_free_to_move_are_allowed_for_dynamics_and_modes():
    from fe_beam.analyses.transient import parse_dynamic, parse_modes

    flying = edited({"supports.x0": "free", "material.rho": 1000.0, "time.t_end": 1.0,
                     "time.dt": 0.1})
    assert parse_dynamic(flying).static.model.supports.x0 == "free"
    flying = edited({"supports.x0": "free", "material.rho": 1000.0, "modes.count": 3})
    assert parse_modes(flying)[0].model.supports.x0 == "free"


@pytest.mark.parametrize("changes, key", list(CASES.values()), ids=list(CASES))
def test_bad_input_exits_2_naming_the_key(tmp_path, capsys, changes, key):
    code, err, out, path = run_cli(tmp_path, edited(changes), capsys=capsys)
    message = usage_error(code, err, path)
    assert names_key(message, *key), message
    assert not (out / "summary.json").exists()


def test_unknown_table_is_named(tmp_path, capsys):
    code, err, _, path = run_cli(tmp_path, edited({"materials.E": 1.0}), capsys=capsys)
    assert "[materials]" in usage_error(code, err, path)


@pytest.mark.parametrize(
    "table, typo",
    [("material", "EE"), ("beam", "lenght"), ("solver", "max_iter"), ("output", "png")],
)
def test_typo_key_is_named_with_its_table(tmp_path, capsys, table, typo):
    code, err, _, path = run_cli(tmp_path, edited({f"{table}.{typo}": 1}), capsys=capsys)
    message = usage_error(code, err, path)
    assert f"[{table}]" in message and repr(typo) in message, message


def test_both_nu_and_g_is_explained(tmp_path, capsys):
    code, err, _, path = run_cli(tmp_path, edited({"material.G": 8.0e10}), capsys=capsys)
    message = usage_error(code, err, path)
    assert re.search(r"material.*\bnu\b.*\bG\b", message), message


@pytest.mark.parametrize(
    "assignment, key",
    [
        ("material.E=-1", ("material", "E")),
        ("mesh.degree=3", ("mesh", "degree")),
        ("model.law=kirchhoff", ("model", "law")),  # bare word -> string
        ("mesh.elements=8.5", ("mesh", "elements")),
        ("beam.length=true", ("beam", "length")),
    ],
)
def test_bad_value_through_set_is_reported_like_a_file_value(tmp_path, capsys, assignment, key):
    code, err, _, path = run_cli(tmp_path, BASE, "--set", assignment, capsys=capsys)
    assert names_key(usage_error(code, err, path), *key)


def test_apply_overrides_parses_toml_values_and_bare_words():
    from fe_beam.config.schema import apply_overrides

    config = apply_overrides(
        BASE,
        [
            "section.h=0.02",
            "model.law=reissner",
            "mesh.elements=4",
            "loads.tip_force=[1, -2.5]",
            "output.xdmf=false",
            'solver.petsc_options.snes_monitor=""',
        ],
    )
    assert config["section"]["h"] == 0.02
    assert config["model"]["law"] == "reissner"
    assert config["mesh"]["elements"] == 4 and isinstance(config["mesh"]["elements"], int)
    assert config["loads"]["tip_force"] == [1, -2.5]
    assert config["output"]["xdmf"] is False
    assert config["solver"]["petsc_options"] == {"snes_monitor": ""}
    assert BASE["section"]["h"] == 0.01  # the input is not modified

"""Inputs that used to end in a traceback, a hang, a wrong exit code or silence (issue 9, items
7 and 9): every one is exit 2 with one sentence that names the key, the file or the option.

All of them fail during validation, before any form is compiled, so they are fast."""

import contextlib
import copy
import math
import os
import random
import re
import string
from pathlib import Path

import pytest
from test_cli_dynamics import DYNAMIC
from test_config import BASE, dump_toml, edited, names_key

from fe_beam.cli import main
from fe_beam.config import check_command_tables, check_values, load_config
from fe_beam.errors import ConfigError
from fe_beam.timefunctions import TimeFunctionError, parse_formula

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
FINGER = {**BASE, "tendons": [{"offset_base": 0.003, "offset_tip": 0.003, "tension": 1.0}]}


def run(tmp_path, command, config, capsys, *extra, out=None):
    """``fe-beam COMMAND`` in-process on ``config`` (dict or TOML text); (code, stderr, path)."""
    path = tmp_path / "c.toml"
    path.write_text(config if isinstance(config, str) else dump_toml(config))
    capsys.readouterr()
    code = main([command, str(path), "--out", str(out or tmp_path / "out"), "--quiet", *extra])
    return code, capsys.readouterr().err, path


def one_sentence(code, err, command="static") -> str:
    assert code == 2, err
    assert "Traceback" not in err
    assert err.endswith("\n") and err.count("\n") == 1, f"not one line: {err!r}"
    assert err.startswith(f"fe-beam {command}: error"), err
    return err


def dynamic(table, key, value):
    config = copy.deepcopy(DYNAMIC)
    config.setdefault(table, {})[key] = value
    return config


# --- item 7: values that overflow, underflow or break the mesh ----------------------------------
@pytest.mark.parametrize("changes, key", [
    ({"beam.length": 1e-200}, ("beam", "length")),
    ({"beam.length": 3e-9}, ("beam", "length")),  # below what the mesh resolves
    ({"beam.length": 5e7}, ("beam", "length")),
    ({"section.h": 1e-250}, ("section", "h")),
    ({"material.E": 1e-40}, ("material", "E")),
    ({"material.E": 1e200}, ("material", "E")),
    ({"loads.tip_force": [1e250, 0.0]}, ("loads", "tip_force[0]")),
    ({"loads.tip_moment": -1e45}, ("loads", "tip_moment")),
    ({"loads.distributed": [0.0, 1e-301]}, ("loads", "distributed[1]")),
    ({"mesh.elements": 2**40}, ("mesh", "elements")),
    ({"solver.max_it": 10**12}, ("solver", "max_it")),
    ({"mesh.elements": 12345678901234567890123}, ("mesh", "elements")),  # beyond 64 bits
])
def test_extreme_values_exit_2_naming_the_key(tmp_path, capsys, changes, key):
    code, err, _ = run(tmp_path, "static", edited(changes), capsys)
    assert names_key(one_sentence(code, err), *key), err


def test_tolerances_may_be_tiny(tmp_path):
    check_values(edited({"solver.atol": 1e-300, "solver.min_increment": 1e-200}))


def test_integer_with_thousands_of_digits_in_the_file_exits_2(tmp_path, capsys):
    text = dump_toml(BASE).replace("elements = 8", "elements = " + "7" * 5000)
    code, err, _ = run(tmp_path, "static", text, capsys)
    assert "not valid TOML" in one_sentence(code, err)


@pytest.mark.parametrize("out", ["/proc/self/fe_beam_out/a", "/proc/version/sub",
                                 "/sys/fe_beam_out", "o" * 300])
def test_output_folder_that_cannot_be_made_exits_2(tmp_path, capsys, out):
    code, err, _ = run(tmp_path, "static", BASE, capsys, out=out)
    assert "--out" in one_sentence(code, err)
    assert not Path(out).exists() if len(out) < 255 else True


def test_output_folder_check_leaves_nothing_behind(tmp_path, capsys):
    out = tmp_path / "new" / "deeper"
    code, err, _ = run(tmp_path, "static", edited({"material.E": -1.0}), capsys, out=out)
    assert code == 2, err
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize("formula", [
    "+".join(["2*t"] * 3000),                 # a long sum
    "-" * 700 + "t",                           # deep unary minus, under the length cap
    "sin(" * 300 + "t" + ")" * 300,            # deep calls
    "(" * 400 + "t" + ")" * 400,               # parentheses beyond Python's parser
    "t" + "**t" * 300,                         # deep powers
    "3" * 500 + "*t",                          # a 500-digit literal
    "sin(t)\x00+1",                            # NUL byte
    "t\x1b[2J",                                # terminal escape
    "1e5000*t",                                # literal that is inf
    "floor(1e300)**floor(1e300)",             # integer arithmetic that never ends
])
@pytest.mark.parametrize("key", ["time_function", "motion_function"])
def test_formula_that_broke_the_parser_exits_2(tmp_path, capsys, formula, key):
    config = dynamic("loads", key, formula)
    if key == "motion_function":
        config["loads"]["prescribed_x0"] = {"theta": 0.1}
    code, err, _ = run(tmp_path, "dynamic", config, capsys)
    message = one_sentence(code, err, "dynamic")
    assert len(message) < 400, message


def test_long_fourier_sum_is_a_formula():
    """The depth cap refuses pathological nesting, not a realistic load history."""
    terms = range(1, 101)
    formula = "+".join(f"sin({k}*pi*t)/{k}" for k in terms)
    value = parse_formula(formula)(0.37)
    assert value == pytest.approx(sum(math.sin(k * math.pi * 0.37) / k for k in terms), rel=1e-12)


def test_velocity_formula_in_x_is_bounded_too(tmp_path, capsys):
    config = dynamic("initial", "velocity", ["-" * 400 + "x", 0.0, 0.0])
    config["initial"]["from_static"] = False
    code, err, _ = run(tmp_path, "dynamic", config, capsys)
    assert "[initial] velocity" in one_sentence(code, err, "dynamic")


def test_formula_fuzz_raises_only_time_function_errors():
    rng = random.Random(20261201)
    alphabet = string.printable + "\x00\u2212\u00b2\u00e9\U0001f600ｔ"
    pieces = ["t", "sin(", "exp(", "floor(", ")", "**", "*", "-", "+", "/", "%", "1e308", "9" * 30,
              " if ", " else ", "<", "(", "pi", "e", ",", "min(", "0"]
    for trial in range(3000):
        if trial % 2:
            text = "".join(rng.choice(alphabet) for _ in range(rng.randint(1, 40)))
        else:
            text = "".join(rng.choice(pieces) for _ in range(rng.randint(1, 60)))
        try:
            function = parse_formula(text)
            for t in (0.0, 0.37, 1.0, -2.0, 1e300):
                with contextlib.suppress(TimeFunctionError):
                    assert math.isfinite(function(t))
        except TimeFunctionError as error:
            assert "\n" not in str(error) and len(str(error)) < 400, repr(text)


# --- item 9: validation gaps --------------------------------------------------------------------
@pytest.mark.parametrize("command, config, key", [
    ("static", edited({"supports.x0": "clamped", "loads.prescribed_x0": {"v": math.nan}}),
     ("loads", "prescribed_x0.v")),
    ("static", edited({"supports.xL": "pinned", "loads.prescribed_xL": {"u": -math.inf}}),
     ("loads", "prescribed_xL.u")),
    ("static", edited({"loads.distributed": [math.inf, 0.0]}), ("loads", "distributed[0]")),
    ("static", edited({"solver.petsc_options": {"snes_rtol": math.nan}}),
     ("solver", "petsc_options.snes_rtol")),
    ("dynamic", dynamic("loads", "time_table", [[0.0, 0.0], [math.nan, 1.0]]),
     ("loads", "time_table[1][0]")),
    ("dynamic", dynamic("initial", "velocity", [0.0, math.inf, 0.0]), ("initial", "velocity[1]")),
    ("finger", {**FINGER, "tendons": [{"offset_base": math.nan, "offset_tip": 0.0,
                                       "tension": 1.0}]}, None),
])
def test_nan_and_inf_anywhere_exit_2_naming_the_key(tmp_path, capsys, command, config, key):
    code, err, _ = run(tmp_path, command, config, capsys)
    message = one_sentence(code, err, command)
    assert "finite" in message, message
    if key:
        assert names_key(message, *key), message
    else:
        assert "[[tendons]] #1 offset_base" in message, message


@pytest.mark.parametrize("changes, words", [
    ({"min_dt": 0.008, "max_dt": 0.006, "adaptive": True}, ("min_dt", "max_dt")),
    ({"min_dt": 0.05}, ("min_dt", "dt")),
    ({"max_dt": 0.001, "adaptive": True}, ("dt", "max_dt")),
    ({"dt": 0.02, "max_dt": 0.01}, ("dt", "max_dt")),
])
def test_paired_time_keys_in_the_wrong_order_exit_2(tmp_path, capsys, changes, words):
    config = copy.deepcopy(DYNAMIC)
    config["time"].update(changes)
    code, err, _ = run(tmp_path, "dynamic", config, capsys)
    message = one_sentence(code, err, "dynamic")
    assert all(f" {word} " in message for word in words), message


@pytest.mark.parametrize("command, config, table", [
    ("static", FINGER, "[[tendons]]"),
    ("static", {**BASE, "inverse": {"tip_angle": 0.2}}, "[inverse]"),
])
def test_table_the_command_would_ignore_is_refused(tmp_path, capsys, command, config, table):
    code, err, _ = run(tmp_path, command, config, capsys)
    message = one_sentence(code, err, command)
    assert table in message and "fe-beam finger" in message, message
    assert not (tmp_path / "out" / "summary.json").exists()


def test_unused_tables_are_noted_not_silently_ignored():
    notes = check_command_tables("static", {**DYNAMIC, "solid": {}, "modes": {"count": 2}})
    text = " | ".join(notes)
    for name in ("[time]", "[initial]", "[solid]", "[modes]", "time_function"):
        assert name in text, text
    # one per group of readers ([time], [initial]: dynamic and modes; [modes]: also solid;
    # [solid]), and the [loads] key
    assert len(notes) == 4, notes
    assert check_command_tables("finger", {**FINGER, "compare": {}})[0].startswith("[compare]")


@pytest.mark.parametrize("example, commands", [
    ("cantilever.toml", ("static",)),
    ("finger.toml", ("finger",)),
    ("release.toml", ("dynamic", "modes")),
    ("spin_up.toml", ("dynamic",)),
    ("finger_dynamics.toml", ("dynamic", "modes")),
    ("flying_spaghetti.toml", ("dynamic",)),
    ("finger_solid.toml", ("solid", "compare")),
    ("spatial_finger.toml", ("finger",)),
    ("bathe_bolourchi.toml", ("static",)),
    ("lateral_torsional.toml", ("buckling",)),
    ("finger_grasp.toml", ("finger",)),
    ("pinch.toml", ("finger",)),
    ("finger_wrap.toml", ("finger",)),
    ("finger_grasp_design.toml", ("design",)),
])
def test_examples_pass_the_new_checks_silently(example, commands):
    config = load_config(EXAMPLES / example)
    check_values(config)
    for command in commands:
        assert check_command_tables(command, config) == [], (example, command)


def test_config_path_that_is_not_a_regular_file_says_what_it_is(tmp_path, capsys):
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    (tmp_path / "dir.toml").mkdir()
    (tmp_path / "dangling.toml").symlink_to(tmp_path / "gone.toml")
    (tmp_path / "plain").write_text("x")
    for path, words in [(fifo, "named pipe"), (tmp_path / "dir.toml", "is a directory"),
                        (Path("/dev/zero"), "character device"),
                        (tmp_path / "dangling.toml", "symbolic link"),
                        (tmp_path / "plain" / "c.toml", "is a file")]:
        capsys.readouterr()
        code = main(["static", str(path), "--out", str(tmp_path / "out"), "--quiet"])
        message = one_sentence(code, capsys.readouterr().err)
        assert words in message, message
        assert "does not exist" not in message.replace("a file that does not exist", ""), message


@pytest.mark.parametrize("out", ["", " ", "\t"])
def test_empty_out_exits_2(tmp_path, capsys, out):
    before = sorted(os.listdir(tmp_path))
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(BASE))
    with pytest.raises(SystemExit) as stop:
        main(["static", str(path), "--out", out, "--quiet"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--out" in err and "Traceback" not in err, err
    assert sorted(os.listdir(tmp_path)) == sorted(before + ["c.toml"])


@pytest.mark.parametrize("changes", [
    {"model.law": "k" * 3_000_000},
    {"material.E": "9" * 3_000_000},
    {"section.shape": ["x" * 1000] * 3000},
    {"supports.x0": "p" * 3_000_000},
    {"beam.lenght": 1.0, "beam." + "y" * 100_000: 1.0},
])
def test_huge_values_are_not_echoed_back(tmp_path, capsys, changes):
    code, err, _ = run(tmp_path, "static", edited(changes), capsys)
    message = one_sentence(code, err)
    assert len(message) < 700, len(err)
    assert not re.search(r"(\w)\1{80}", message), message  # no value echoed at length


def test_huge_formula_is_not_echoed_back(tmp_path, capsys):
    code, err, _ = run(tmp_path, "dynamic", dynamic("loads", "time_function", "t+" * 10**6),
                       capsys)
    assert len(one_sentence(code, err, "dynamic")) < 700


@pytest.mark.parametrize("command", ["finger", "static", "solid", "dynamic"])
def test_single_tendons_table_says_to_write_an_array_of_tables(tmp_path, capsys, command):
    text = dump_toml(BASE) + "\n[tendons]\noffset_base = 0.003\noffset_tip = 0.003\ntension = 1.0\n"
    code, err, _ = run(tmp_path, command, text, capsys)
    message = one_sentence(code, err, command)
    assert "[[tendons]]" in message and "array of tables" in message, message


def test_single_table_where_one_is_expected_names_the_mistake():
    with pytest.raises(ConfigError, match=r"\[beam\].*one table.*\[\[beam\]\]"):
        from fe_beam.config.schema import parse_static

        parse_static({**BASE, "beam": [{"length": 1.0}]})


def test_typo_table_still_named():
    code_words = re.compile(r"unknown table \[lods\]")
    with pytest.raises(ConfigError, match=code_words):
        from fe_beam.config.schema import parse_static

        parse_static({**BASE, "lods": {}})


def test_static_on_a_dynamic_config_runs_and_says_what_it_ignored(tmp_path, capsys):
    config = copy.deepcopy(DYNAMIC)
    config["loads"]["steps"] = 1
    code, err, _ = run(tmp_path, "static", config, capsys)
    assert code == 0, err
    lines = err.splitlines()
    assert len(lines) == 2, err  # the ignored tables in one note, the [loads] key in another
    assert all(line.startswith("fe-beam static: note: ") for line in lines), err
    assert "[initial] and [time]" in lines[0] and "time_function" in lines[1], err


@pytest.mark.parametrize("error, code, words", [
    (KeyError("bug"), 1, "internal error"),
    (FloatingPointError("overflow in the residual"), 3, "the analysis failed"),
    (MemoryError(), 3, "out of memory"),
    (OSError(28, "No space left on device", "/full/summary.json"), 2, "/full/summary.json"),
    (ConfigError("[mesh] elements too many"), 2, "[mesh] elements"),
    (TimeFunctionError("'exp(t)' is not finite at t = 800"), 2, "not finite"),
])
def test_any_exception_becomes_one_line_and_its_exit_code(capsys, error, code, words):
    from mpi4py import MPI

    from fe_beam.cli import run_guarded

    def work():
        raise error

    capsys.readouterr()
    assert run_guarded(MPI.COMM_WORLD, "static", "c.toml", work) == code
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("fe-beam static: ") and words in err, err


def test_petsc_error_is_an_analysis_failure(capsys):
    from mpi4py import MPI
    from petsc4py import PETSc

    from fe_beam.cli import run_guarded

    def work():
        PETSc.Mat().createAIJ((2, 2), comm=MPI.COMM_SELF).getValue(5, 5)  # out of range

    capsys.readouterr()
    code = run_guarded(MPI.COMM_WORLD, "static", "c.toml", work)
    err = capsys.readouterr().err
    assert code == 3 and err.count("\n") == 1 and "Traceback" not in err, err

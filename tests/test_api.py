"""The Python front door `fe_beam.run`: the same summary as summary.json of the same CLI run
(every command on its example configuration, made coarse by the same overrides for both; the
numbers bitwise equal, wall times apart), serially and on 2 ranks; mistakes raise
`fe_beam.ConfigError` with the CLI's sentence; ``out=None`` leaves no file behind; the public
names of ``fe_beam.__all__`` resolve."""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import pytest
from test_calibrate import CONFIG as CALIBRATE_CONFIG

import fe_beam
from fe_beam.api import SUMMARY_FILES
from fe_beam.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SOLID_COARSE = {"solid.mesh_size": 0.01, "solid.order": 1, "mesh.elements": 10}

# command, example, overrides (the same for the CLI and the API), extra CLI args / API keywords
CASES = {
    "static": ("static", "cantilever.toml", {"mesh.elements": 10, "loads.steps": 3}, {}),
    "finger": ("finger", "finger.toml", {"mesh.elements": 10}, {}),
    "finger-inverse": ("finger", "finger.toml", {"mesh.elements": 10, "inverse.tip_angle": 0.3},
                       {}),
    "dynamic": ("dynamic", "release.toml", {"mesh.elements": 8, "time.t_end": 0.02}, {}),
    "modes": ("modes", "release.toml", {"mesh.elements": 8}, {}),
    "refine": ("refine", "cantilever.toml", {"mesh.elements": 4, "loads.steps": 2},
               {"levels": 2}),
    "buckling": ("buckling", "column_buckling.toml", {"mesh.elements": 8}, {}),
    "path": ("path", "elastica_path.toml", {"mesh.elements": 8, "path.max_steps": 6}, {}),
    "design": ("design", "finger_design.toml", {"mesh.elements": 8}, {}),
    "solid": ("solid", "finger_solid.toml", SOLID_COARSE, {}),
    "compare": ("compare", "finger_solid.toml", SOLID_COARSE | {"compare.tensions": [1.0]}, {}),
}
MPI_CASES = ("static", "finger", "buckling")
# two identical 2-rank eigenvalue solves (SLEPc + parallel MUMPS) agree to round-off, not bitwise
# (measured: 1.644908547816125 vs 1.6449085478161232 on column_buckling)
PARALLEL_RTOL = 1e-12


def _numbers(value):
    """The summary without what differs between two identical runs (wall times, the folder)
    and the references to files, which a run that writes nothing (``out=None``) has not made
    (e.g. a critical point's ``mode = {file, index}``)."""
    if isinstance(value, dict):
        return {k: _numbers(v) for k, v in value.items()
                if "wall_time" not in k and not k.endswith("_s") and k not in ("out", "folder")
                and not (isinstance(v, dict) and "file" in v)}
    if isinstance(value, list):
        return [_numbers(v) for v in value]
    return value


def _assert_same(a, b, rtol: float, where: str = "summary") -> None:
    """Equal structures; floats equal (rtol = 0) or within rtol relative."""
    if isinstance(a, dict):
        assert set(a) == set(b), where
        for key in a:
            _assert_same(a[key], b[key], rtol, f"{where}.{key}")
    elif isinstance(a, list):
        assert len(a) == len(b), where
        for index, (x, y) in enumerate(zip(a, b)):
            _assert_same(x, y, rtol, f"{where}[{index}]")
    elif isinstance(a, float) and isinstance(b, float) and rtol:
        assert abs(a - b) <= rtol * max(abs(a), abs(b)), (where, a, b)
    else:
        assert a == b, (where, a, b)


def _cli_args(overrides: dict, extra: dict) -> list[str]:
    args = []
    for key, value in overrides.items():
        args += ["--set", f"{key}={json.dumps(value)}"]
    for key, value in extra.items():
        args += [f"--{key}", str(value)]
    return args


def _compare(name: str, tmp: Path, comm=None, rtol: float = 0.0):
    command, example, overrides, extra = CASES[name]
    config = EXAMPLES / example
    out = tmp / "cli"
    code = main([command, str(config), "--out", str(out), "--quiet",
                 *_cli_args(overrides, extra)])
    cli_summary = json.loads((out / SUMMARY_FILES.get(command, "summary.json")).read_text())
    api_summary = fe_beam.run(command, config, comm=comm, **extra, **overrides)
    _assert_same(_numbers(api_summary), _numbers(cli_summary), rtol)
    assert api_summary["status"] == cli_summary["status"]
    return code, api_summary


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in CASES if n not in MPI_CASES])
def test_run_equals_the_cli(name, tmp_path):
    _compare(name, tmp_path)


@pytest.mark.mpi
@pytest.mark.parametrize("name", MPI_CASES)
def test_run_equals_the_cli_on_every_rank(name, tmp_path_factory):
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    tmp = Path(comm.bcast(str(tmp_path_factory.mktemp(name)) if comm.rank == 0 else None))
    code, summary = _compare(name, tmp, comm, PARALLEL_RTOL if comm.size > 1 else 0.0)
    assert code == 0 and summary["status"] in ("converged", "completed")


@pytest.mark.parametrize("overrides, fragment", [
    ({"mesh.elements": -1}, "mesh.elements"),
    ({"material.nu": 0.7}, "nu"),
    ({"loads.tip_force": "up"}, "tip_force"),
])
def test_mistakes_raise_config_error_with_the_cli_sentence(overrides, fragment, tmp_path,
                                                            capsys):
    config = EXAMPLES / "cantilever.toml"
    with pytest.raises(fe_beam.ConfigError) as raised:
        fe_beam.run("static", config, **overrides)
    code = main(["static", str(config), "--out", str(tmp_path / "o"), "--quiet",
                 *_cli_args(overrides, {})])
    printed = capsys.readouterr().err.strip()
    assert code == 2
    assert fragment in str(raised.value)
    assert printed.endswith(str(raised.value)), (printed, str(raised.value))


def test_a_dict_config_and_no_files_left(tmp_path, monkeypatch):
    import tomllib

    config = tomllib.loads((EXAMPLES / "cantilever.toml").read_text())
    before = json.dumps(config, sort_keys=True)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.chdir(tmp_path)  # no results/ folder either: out=None writes nothing
    summary = fe_beam.run("static", config, **{"mesh.elements": 6, "loads.steps": 2})
    assert summary["status"] == "converged" and len(summary["steps"]) == 2
    assert json.dumps(config, sort_keys=True) == before  # the caller's dict is not modified
    assert list(tmp_path.iterdir()) == []  # the private output folder is gone
    with pytest.raises(fe_beam.ConfigError, match="dotted key"):
        fe_beam.run("static", config, elements=6)
    with pytest.raises(fe_beam.ConfigError, match="unknown command|invalid choice|one of"):
        fe_beam.run("statics", config)


def test_every_public_name_resolves():
    for name in fe_beam.__all__:
        assert getattr(fe_beam, name) is not None, name
    assert fe_beam.ConfigError is fe_beam.config.ConfigError


# the configuration of tests/test_calibrate.py's command tests, fitting E alone
CALIBRATION = CALIBRATE_CONFIG.format(parameters='["material.E"]', extra="")


@pytest.mark.slow
def test_run_equals_the_cli_for_calibrate_and_validity(tmp_path):
    """The two commands with inputs beyond the configuration: calibrate's data file (``data=``)
    and validity's map (a resumable study: ``out=None`` runs it in a private folder)."""
    config = tmp_path / "finger.toml"
    config.write_text(CALIBRATION)
    data = tmp_path / "data.csv"
    data.write_text("tension,tip_v,tip_theta\n1.0,0.0078,0.2\n2.0,0.0157,0.41\n")
    assert main(["calibrate", str(config), "--data", str(data), "--out", str(tmp_path / "c"),
                 "--quiet"]) == 0
    cli_summary = json.loads((tmp_path / "c" / "summary.json").read_text())
    _assert_same(_numbers(fe_beam.run("calibrate", config, data=data)), _numbers(cli_summary),
                 0.0)

    # a coarse map whose 3D error estimate cannot be certified (solid_discretisation_error):
    # lenient, so that both entries report the same uncertified numbers with exit 0
    overrides = SOLID_COARSE | {"solid.mesh_size": 0.008, "validity.x_values": [1.0],
                                "validity.y_values": [0.012], "validity.second_mesh_ratio": 0.8,
                                "checks.strict": False}
    example = EXAMPLES / "finger_validity.toml"
    assert main(["validity", str(example), "--out", str(tmp_path / "v"), "--quiet",
                 *_cli_args(overrides, {})]) == 0
    cli_summary = json.loads((tmp_path / "v" / "summary.json").read_text())
    _assert_same(_numbers(fe_beam.run("validity", example, **overrides)),
                 _numbers(cli_summary), 0.0)


def test_numpy_values_and_work_beyond_the_limits(tmp_path):
    """Overrides may be numpy numbers and arrays; work beyond the up-front limits is the CLI's
    exit 2 (`fe_beam.ConfigError` here), with or without an output folder."""
    import numpy as np

    config = EXAMPLES / "cantilever.toml"
    summary = fe_beam.run("static", config, **{"mesh.elements": np.int64(6),
                                                "loads.steps": np.int32(2),
                                                "loads.tip_force": np.array([0.0, -1.0])})
    assert summary["status"] == "converged" and len(summary["steps"]) == 2
    for out in (None, tmp_path / "large"):
        with pytest.raises(fe_beam.ConfigError, match="allow_large"):
            fe_beam.run("static", config, out=out, **{"loads.steps": 2_000_000})


@pytest.mark.parametrize("config", [None, 3.5, ["static.toml"]])
def test_run_without_a_configuration_is_a_config_error(config):
    """fe_beam.run(command, None) raised a bare TypeError from pathlib: a ConfigError of one
    sentence naming what config must be."""
    import fe_beam
    from fe_beam.errors import ConfigError

    with pytest.raises(ConfigError, match="config must be a TOML file's path or a dict") as info:
        fe_beam.run("static", config)
    assert len(str(info.value).splitlines()) == 1
    assert type(config).__name__ in str(info.value)

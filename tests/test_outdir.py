"""Output folders (issue 9, items 5 and 10): one run per folder (a lock naming the owner), stale
results of another command cleared (files fe_beam did not write kept), files that follow the
umask."""

from __future__ import annotations

import json
import os
import re
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

from test_config import BASE, dump_toml, edited

from fe_beam import runctl
from fe_beam.cli import main

ROOT = Path(__file__).resolve().parents[1]
FE_BEAM = Path(sys.executable).parent / "fe-beam"
DYNAMIC = edited({"material.rho": 7850.0, "loads.tip_force": [0.0, -1.0],
                  "output.plots": False}) | {"time": {"t_end": 0.05, "dt": 0.005}}


def _environment() -> dict:
    env = dict(os.environ, FE_BEAM_PROGRESS="0")
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def _start(command: str, config: Path, out: Path, *extra) -> subprocess.Popen:
    return subprocess.Popen([str(FE_BEAM), command, str(config), "--out", str(out), "--quiet",
                             *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=_environment(), start_new_session=True)


def _busy_message(code: int, err: str, pid: int) -> None:
    assert code == 2, err
    assert "Traceback" not in err
    assert err.count("\n") == 1, err
    assert f"pid {pid}" in err and "in use" in err, err


def test_second_run_into_a_busy_folder_exits_2_naming_the_owner(tmp_path):
    config = tmp_path / "long.toml"
    # a run that is still stepping when the second one starts (stopped by SIGTERM below)
    config.write_text(dump_toml(DYNAMIC | {"time": {"t_end": 50.0, "dt": 0.005}}))
    out = tmp_path / "out"
    first = _start("dynamic", config, out)
    try:
        deadline = time.time() + 120
        while not (out / "summary.json").exists():
            assert first.poll() is None, first.communicate()
            assert time.time() < deadline
            time.sleep(0.05)
        before = (out / "summary.json").read_text()
        second = _start("static", config, out, "--set", "loads.steps=1")
        _, err = second.communicate(timeout=120)
        _busy_message(second.returncode, err, first.pid)
        assert json.loads(before)["status"] == "running"
    finally:
        first.send_signal(signal.SIGTERM)
        _, err = first.communicate(timeout=120)
    assert first.returncode == 143, err
    assert json.loads((out / "summary.json").read_text())["status"] == "interrupted"
    assert "history.csv" in os.listdir(out)  # the refused run did not touch the folder


def test_two_runs_started_together_one_runs_one_is_refused(tmp_path):
    config = tmp_path / "c.toml"
    config.write_text(dump_toml(edited({"loads.steps": 3})))
    out = tmp_path / "out"
    runs = [_start("static", config, out) for _ in range(2)]
    results = [(run.pid, *run.communicate(timeout=180), run.returncode) for run in runs]
    codes = sorted(code for *_, code in results)
    assert codes in ([0, 0], [0, 2]), results  # [0, 0]: the first ended before the second began
    for pid, _, err, code in results:
        assert "Traceback" not in err
        if code == 2:
            other = next(p for p, *_ in results if p != pid)
            _busy_message(code, err, other)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "converged" and len(summary["steps"]) == 3


def test_stale_lock_of_a_dead_process_is_taken_over(tmp_path, capsys):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    out = tmp_path / "out"
    out.mkdir()
    (out / runctl.LOCK_NAME).write_text(f"{dead.pid} {os.uname().nodename} static\n")
    config = tmp_path / "c.toml"
    config.write_text(dump_toml(edited({"loads.steps": 2})))
    assert main(["static", str(config), "--out", str(out), "--quiet"]) == 0, \
        capsys.readouterr().err
    assert json.loads((out / "summary.json").read_text())["status"] == "converged"


def test_lock_is_held_while_running_and_released_after(tmp_path):
    import fcntl

    out = tmp_path / "out"
    from mpi4py import MPI

    with runctl.output_session(out, "static", MPI.COMM_SELF):
        owner = (out / runctl.LOCK_NAME).read_text().split()
        assert owner[0] == str(os.getpid())
        fd = os.open(out / runctl.LOCK_NAME, os.O_RDWR)
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                raise AssertionError("the lock was not held")
            except BlockingIOError:
                pass
        finally:
            os.close(fd)
        try:
            with runctl.output_session(out, "dynamic", MPI.COMM_SELF):
                raise AssertionError("a second session took a held lock")
        except runctl.FolderBusy as busy:
            assert f"pid {os.getpid()}" in str(busy)
        (out / "summary.json").write_text("{}")
        runctl.register_output(out / "summary.json")
    with runctl.output_session(out, "static", MPI.COMM_SELF):
        pass  # free again


def test_results_of_another_command_are_cleared_user_files_kept(tmp_path, capsys):
    out = tmp_path / "out"
    config = tmp_path / "d.toml"
    config.write_text(dump_toml(DYNAMIC))
    assert main(["dynamic", str(config), "--out", str(out), "--quiet"]) == 0, \
        capsys.readouterr().err
    assert (out / "history.csv").is_file()
    (out / "my_notes.txt").write_text("mine")
    (out / "extra.csv").write_text("a,b\n")
    static = tmp_path / "s.toml"
    static.write_text(dump_toml(edited({"loads.steps": 2})))
    assert main(["static", str(static), "--out", str(out), "--quiet"]) == 0, \
        capsys.readouterr().err
    names = set(os.listdir(out))
    assert "history.csv" not in names, names  # the dynamic run's history is gone
    assert {"summary.json", "load_displacement.csv", "beam.xdmf", "beam.h5"} <= names
    assert (out / "my_notes.txt").read_text() == "mine" and (out / "extra.csv").is_file()
    assert "history" not in json.loads((out / "summary.json").read_text())
    xdmf = (out / "beam.xdmf").read_text()
    assert len(re.findall("<Time ", xdmf)) == 2  # the static steps only
    # no hidden leftovers of the writers after a completed run
    assert not [n for n in names if n.startswith(".") and not n.startswith(".fe-beam")], names


def test_folder_without_manifest_clears_known_outputs_only(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    for name in ("history.csv", "dynamics.png", "modes.xdmf"):
        (out / name).write_text("old")
    (out / "history_mine.csv").write_text("mine")
    static = tmp_path / "s.toml"
    static.write_text(dump_toml(edited({"loads.steps": 1})))
    assert main(["static", str(static), "--out", str(out), "--quiet"]) == 0, \
        capsys.readouterr().err
    names = set(os.listdir(out))
    assert not names & {"history.csv", "dynamics.png", "modes.xdmf"}, names
    assert (out / "history_mine.csv").read_text() == "mine"


def test_a_configuration_error_leaves_earlier_results_untouched(tmp_path, capsys):
    out = tmp_path / "out"
    static = tmp_path / "s.toml"
    static.write_text(dump_toml(edited({"loads.steps": 1})))
    assert main(["static", str(static), "--out", str(out), "--quiet"]) == 0
    before = {n: (out / n).read_bytes() for n in os.listdir(out) if not n.startswith(".")}
    bad = tmp_path / "bad.toml"
    bad.write_text(dump_toml(edited({"material.E": -1.0})))
    capsys.readouterr()
    assert main(["dynamic", str(bad), "--out", str(out), "--quiet"]) == 2
    after = {n: (out / n).read_bytes() for n in os.listdir(out) if not n.startswith(".")}
    assert after == before


def test_output_files_follow_the_umask(tmp_path, capsys):
    config = tmp_path / "c.toml"
    config.write_text(dump_toml(BASE | {"output": {"xdmf": True, "plots": True}}))
    for mask in (0o022, 0o002):
        out = tmp_path / f"out{mask:o}"
        previous = os.umask(mask)
        try:
            assert main(["static", str(config), "--out", str(out), "--quiet"]) == 0, \
                capsys.readouterr().err
        finally:
            os.umask(previous)
        modes = {p.name: stat.S_IMODE(p.stat().st_mode) for p in out.iterdir()}
        assert {"summary.json", "load_displacement.csv", "beam.xdmf", "beam.h5",
                "deformed_shapes.png"} <= set(modes)
        assert set(modes.values()) == {0o666 & ~mask}, modes


def test_a_user_file_written_during_a_run_is_not_taken_for_an_output(tmp_path, capsys):
    """A file the user puts into the folder while a run writes there is not fe_beam's: the next
    run must not delete it."""
    out = tmp_path / "out"
    static = tmp_path / "s.toml"
    static.write_text(dump_toml(edited({"loads.steps": 2})))
    with runctl.output_session(out, "static", __import__("mpi4py").MPI.COMM_SELF):
        runctl.register_output(out / "summary.json")
        (out / "summary.json").write_text("{}")
        (out / "my_notes.txt").write_text("mine")  # the user, meanwhile
        (out / "run.log").write_text("mine too")
    manifest = json.loads((out / runctl.MANIFEST_NAME).read_text())
    assert manifest["files"] == ["summary.json"], manifest
    assert main(["static", str(static), "--out", str(out), "--quiet"]) == 0, \
        capsys.readouterr().err
    assert (out / "my_notes.txt").read_text() == "mine"
    assert (out / "run.log").read_text() == "mine too"

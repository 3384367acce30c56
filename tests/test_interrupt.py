"""Interrupted runs (issue 9, item 4): a static, a dynamic and a solid run are killed at seeded
random moments with SIGKILL, SIGTERM or SIGINT; afterwards every file opens (json, csv, h5py,
meshio's XDMF reader) and agrees with summary.json, the status is truthful and SIGINT/SIGTERM end
with one line on stderr and exit 130/143."""

from __future__ import annotations

import csv
import json
import math
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
FE_BEAM = Path(sys.executable).parent / "fe-beam"
QUIET = ["--quiet"]
CASES = {
    "static": ["static", str(ROOT / "examples" / "cantilever.toml"), "--set", "mesh.elements=16",
               "--set", "loads.steps=60", "--set", "solver.adaptive=false"],
    "dynamic": ["dynamic", str(ROOT / "examples" / "release.toml"), "--set", "mesh.elements=8",
                "--set", "time.t_end=0.6"],
    "solid": ["solid", str(ROOT / "examples" / "finger_solid.toml"), "--set",
              "solid.mesh_size=0.02", "--set", "solid.order=1", "--set", "loads.steps=6",
              "--set", "mesh.elements=8"],
}
FINAL = {"static": "converged", "dynamic": "completed", "solid": "converged"}
CSV_NAME = {"static": "load_displacement.csv", "dynamic": "history.csv",
            "solid": "load_displacement.csv"}
XDMF_NAME = {"static": "beam.xdmf", "dynamic": "beam.xdmf", "solid": "solid.xdmf"}
RESULTS = set(CSV_NAME.values()) | {"summary.json", "beam.xdmf", "beam.h5", "solid.xdmf",
                                    "solid.h5", "rod.xdmf"}


def _environment() -> dict:
    env = dict(os.environ, FE_BEAM_PROGRESS="0")
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def _start(kind: str, out: Path) -> subprocess.Popen:
    return subprocess.Popen([str(FE_BEAM), *CASES[kind], "--out", str(out), *QUIET],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=_environment(), start_new_session=True)


def _steps(kind: str, summary: dict) -> list[tuple[float, float | None]]:
    """(time or load factor, tip v) of every step in summary.json."""
    if kind == "dynamic":
        return [(h["t"], h["tip"]["v"]) for h in summary["history"]]
    return [(s["load_factor"], s["tip"]["v"]) for s in summary["steps"]]


def _csv_steps(kind: str, path: Path) -> list[tuple[float, float]]:
    with open(path, newline="") as stream:
        rows = list(csv.reader(stream))
    header, body = rows[0], rows[1:]
    assert all(len(row) == len(header) for row in body), f"{path}: a torn row"
    first = "t" if kind == "dynamic" else "load_factor"
    return [(float(r[header.index(first)]), float(r[header.index("tip_v")])) for r in body]


def _xdmf_steps(kind: str, path: Path) -> list[tuple[float, float | None]]:
    """(time, v at the node of largest x) of every step of an XDMF file (meshio reads it and
    the HDF5 data it points to)."""
    steps = []
    with meshio.xdmf.TimeSeriesReader(str(path)) as reader:
        points, cells = reader.read_points_cells()
        assert len(points) and len(cells[0].data)
        tip = np.argmax(points[:, 0])
        for k in range(reader.num_steps):
            t, point_data, _ = reader.read_data(k)
            assert all(np.all(np.isfinite(v)) for v in point_data.values())
            v = None if kind == "solid" else float(np.ravel(point_data["v"])[tip])
            steps.append((float(t), v))
    return steps


def _h5_count(path: Path) -> int:
    with h5py.File(path, "r") as h5:
        assert h5["Mesh/mesh/geometry"].shape[1] == 3
        group = h5["Function"]
        counts = {len(group[name]) for name in group}
        assert len(counts) <= 1, f"{path}: functions with different step counts {counts}"
        return counts.pop() if counts else 0


def _agree(a, b, what: str) -> None:
    for (ta, va), (tb, vb) in zip(a, b, strict=False):
        assert math.isclose(ta, tb, rel_tol=1e-12, abs_tol=1e-14), (what, ta, tb)
        if va is not None and vb is not None:
            assert math.isclose(va, vb, rel_tol=1e-9, abs_tol=1e-12), (what, va, vb)


def check_folder(kind: str, out: Path, code: int, stderr: str, sent: int | None) -> str:
    """Every file in ``out`` opens and agrees with summary.json; returns the status."""
    if code == 1 and sent == signal.SIGINT and stderr.startswith("Fatal Python error: init_"):
        # the interpreter itself was still starting (streams, `site`; on a loaded machine):
        # CPython aborts there before any fe_beam code runs; nothing may have been written
        assert not (out.exists() and any(out.iterdir())), stderr
        return "none"
    assert "Traceback" not in stderr, stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    if code in (130, 143):
        assert code == {signal.SIGINT: 130, signal.SIGTERM: 143}[sent], (code, sent)
        assert len(lines) == 1 and lines[0].startswith("fe-beam: interrupted"), stderr
        assert str(out) in lines[0]
    else:
        # -SIGINT/-SIGTERM: before fe_beam was imported, or once the interpreter finalises
        # after the run (Python then restores the default handlers)
        assert code in (0, -signal.SIGKILL, -signal.SIGTERM, -signal.SIGINT), (code, stderr)
        if code == 0:
            assert not lines, stderr
    files = {p.name for p in out.iterdir()} if out.exists() else set()
    for name in files:
        if name.endswith(".png"):  # complete images only
            data = (out / name).read_bytes()
            assert data.startswith(b"\x89PNG") and data.endswith(b"IEND\xaeB`\x82"), name
    if "summary.json" not in files:
        # stopped before the analysis wrote anything (e.g. while Python imported its modules)
        assert code != 0 and not (files & RESULTS), (code, files)
        return "none"
    summary = json.loads((out / "summary.json").read_text())
    status = summary["status"]
    if code in (-signal.SIGTERM, -signal.SIGINT):
        assert status == FINAL[kind], "SIGINT/SIGTERM must be handled while fe_beam runs"
    if code == 0:
        assert status == FINAL[kind]
    elif code in (130, 143):
        # interrupted, or the signal came after the last step (the results are complete)
        assert status in ("interrupted", FINAL[kind]), status
        assert status == "interrupted" or "after the analysis ended" in lines[0], lines[0]
    else:
        assert status in ("running", FINAL[kind]), status
    reported = _steps(kind, summary)
    table = _csv_steps(kind, out / CSV_NAME[kind]) if CSV_NAME[kind] in files else []
    xdmf = _xdmf_steps(kind, out / XDMF_NAME[kind]) if XDMF_NAME[kind] in files else []
    h5_name = XDMF_NAME[kind].replace(".xdmf", ".h5")
    stored = _h5_count(out / h5_name) if h5_name in files else 0
    if kind == "solid":
        xdmf = xdmf[1:]  # the solid's series starts with the undeformed state
        stored -= 1 if stored else 0
        if "rod.xdmf" in files:
            import xml.etree.ElementTree as ET

            ET.parse(out / "rod.xdmf")
    assert len(xdmf) <= stored, (len(xdmf), stored)
    _agree(reported, table, "summary vs csv")
    _agree(reported, xdmf, "summary vs xdmf")
    _agree(table, xdmf, "csv vs xdmf")
    if status != "running":
        # a finished or interrupted run has written every step everywhere
        assert len(reported) == len(table) == len(xdmf) == stored, (
            len(reported), len(table), len(xdmf), stored)
        assert reported or status == "interrupted"
    if status == "interrupted":
        last = reported[-1][0] if reported else 0.0
        assert f"{last:.4g}" in lines[0] or kind == "dynamic", (last, lines[0])
    return status


def _wait_for_a_step(kind: str, out: Path, process: subprocess.Popen) -> None:
    """Until summary.json of a running run holds a step (or the run ended)."""
    deadline = time.monotonic() + 240
    while process.poll() is None and time.monotonic() < deadline:
        try:
            summary = json.loads((out / "summary.json").read_text())
            if summary.get("status") == "running" and _steps(kind, summary):
                return
        except (OSError, ValueError, KeyError):
            pass
        time.sleep(0.01)


def _signal_all(runs: list[dict]) -> None:
    """Send each run its signal at its moment: ``delay`` seconds after the launch ("launch":
    start-up, imports, meshing) or after summary.json appeared ("writing": the stepping)."""
    waiting = list(runs)
    while waiting:
        now = time.perf_counter()
        for run in list(waiting):
            if run["process"].poll() is not None:
                waiting.remove(run)
                continue
            if run["origin"] is None and (run["mode"] == "launch"
                                          or (run["out"] / "summary.json").exists()):
                run["origin"] = now
            if run["origin"] is not None and now >= run["origin"] + run["delay"]:
                run["process"].send_signal(run["signal"])
                waiting.remove(run)
        time.sleep(0.005)


@pytest.mark.parametrize("kind", list(CASES))
def test_interrupted_runs_leave_readable_results(kind, tmp_path):
    reference = _start(kind, tmp_path / "complete")
    _, stderr = reference.communicate(timeout=300)
    assert check_folder(kind, tmp_path / "complete", reference.returncode, stderr, None) == \
        FINAL[kind]
    stepping = json.loads((tmp_path / "complete" / "summary.json").read_text())["wall_time_s"]
    rng = random.Random(f"issue-9-{kind}")
    plan = []
    for index in range(10):
        mode = "launch" if index % 4 == 0 else "writing"
        # (from 0.3 s: a signal while the interpreter itself starts, before fe_beam is
        # imported, gets Python's default handling)
        delay = rng.uniform(0.3, 4.0) if mode == "launch" else rng.uniform(0.0, 1.5 * stepping)
        plan.append({"mode": mode, "delay": delay, "origin": None, "out": tmp_path / f"run{index}",
                     "signal": rng.choice([signal.SIGKILL, signal.SIGTERM, signal.SIGINT])})
    statuses = []
    for batch in (plan[:5], plan[5:]):
        for run in batch:
            run["process"] = _start(kind, run["out"])
        _signal_all(batch)
        for run in batch:
            _, stderr = run["process"].communicate(timeout=300)
            statuses.append(check_folder(kind, run["out"], run["process"].returncode, stderr,
                                         run["signal"]))
    print(kind, [(r["signal"].name, r["mode"]) for r in plan], statuses)
    # the random plan may miss the stepping phase on a loaded machine: make sure a SIGKILL
    # and a SIGTERM hit runs that are stepping (their first step written)
    for wanted, sent in (("running", signal.SIGKILL), ("interrupted", signal.SIGTERM)):
        if wanted not in statuses:
            out = tmp_path / f"stepping_{wanted}"
            process = _start(kind, out)
            _wait_for_a_step(kind, out, process)
            process.send_signal(sent)
            _, stderr = process.communicate(timeout=300)
            statuses.append(check_folder(kind, out, process.returncode, stderr, sent))
    # the runs must have been hit while they were stepping, not only before or after
    assert "interrupted" in statuses and "running" in statuses, statuses


def _shared_folder(tmp_path: Path) -> Path:
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    return Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0))


@pytest.mark.mpi
@pytest.mark.parametrize("command, stop_at", [("static", 3), ("dynamic", 5)])
def test_a_signal_on_one_rank_stops_all_ranks_at_the_same_step(command, stop_at, tmp_path,
                                                               capsys, monkeypatch):
    """SIGTERM reaches one rank only (the last): every rank stops at the same step boundary,
    the files hold the steps up to it, and the command ends with exit 143 and one line."""
    from mpi4py import MPI
    from test_config import dump_toml, edited

    from fe_beam import progress
    from fe_beam.cli import main

    comm = MPI.COMM_WORLD
    folder = _shared_folder(tmp_path)
    config = edited({"loads.steps": 8, "mesh.elements": 12, "solver.adaptive": False,
                     "output.plots": False, "material.rho": 7850.0})
    if command == "dynamic":
        config["loads"]["tip_force"] = [0.0, -1.0]
        config["time"] = {"t_end": 0.02, "dt": 1e-3, "output_every": 1}
    path = folder / "c.toml"
    if comm.rank == 0:
        path.write_text(dump_toml(config))
    comm.barrier()
    calls = {"n": 0}
    update = progress.ProgressBar.update

    def counting(self, value, message=""):
        calls["n"] += 1
        if calls["n"] == stop_at and comm.rank == comm.size - 1:
            os.kill(os.getpid(), signal.SIGTERM)
        update(self, value, message)

    monkeypatch.setattr(progress.ProgressBar, "update", counting)
    out = folder / "out"
    capsys.readouterr()
    code = main([command, str(path), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert code == 143, err
    assert calls["n"] == stop_at  # no rank went on stepping
    if comm.rank == 0:
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("fe-beam: interrupted"), err
    comm.barrier()
    kind = "dynamic" if command == "dynamic" else "static"
    status = check_folder(kind, out, code, err, signal.SIGTERM) if comm.rank == 0 else None
    assert comm.bcast(status, root=0) == "interrupted"
    summary = json.loads((out / "summary.json").read_text())
    # the dynamic history starts with t = 0; the interrupted step is recorded in both
    assert len(summary["steps" if kind == "static" else "history"]) == \
        (stop_at if kind == "static" else stop_at + 1)


@pytest.mark.parametrize("sent", [signal.SIGINT, signal.SIGTERM])
def test_the_fd_scheme_stops_on_a_signal(sent, tmp_path):
    """The paper's FD + Runge-Kutta scheme (one scipy call for the whole run) heeds SIGINT and
    SIGTERM too: it ignored them (deferred, never looked at) and ran on for minutes."""
    out = tmp_path / "fd"
    process = subprocess.Popen(
        [str(FE_BEAM), "dynamic", str(ROOT / "examples" / "release.toml"), "--set",
         'time.scheme="fd-rk45"', "--set", "time.t_end=1000", "--set", "time.dt=0.05", "--set",
         "mesh.elements=8",
         "--out", str(out), "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, env=_environment())
    deadline = time.monotonic() + 120
    while not (out / "summary.json").exists() and process.poll() is None:
        assert time.monotonic() < deadline
        time.sleep(0.02)
    assert json.loads((out / "summary.json").read_text())["status"] == "running"
    time.sleep(0.5)
    process.send_signal(sent)
    signalled = time.monotonic()
    _, stderr = process.communicate(timeout=60)
    assert time.monotonic() - signalled < 10, "the signal was not heeded"
    assert process.returncode == {signal.SIGINT: 130, signal.SIGTERM: 143}[sent], stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("fe-beam: interrupted"), stderr
    assert "no history" in lines[0] and "last converged step" not in lines[0], stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["history"] == [], summary


def test_a_signal_while_setting_up_a_large_model_stops_at_once(tmp_path):
    """SIGTERM while a large model is set up (mesh, forms, first assembly: no step boundary for
    many seconds) ends the run at once, before anything is written: one line, exit 143, no
    folder left behind. (It used to run on to the end of the first load step.)"""
    out = tmp_path / "big"
    process = subprocess.Popen(
        [str(FE_BEAM), "static", str(ROOT / "examples" / "cantilever.toml"), "--set",
         "mesh.elements=200000", "--out", str(out), "--quiet"], stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True, env=_environment())
    lock = out / ".fe-beam.lock"
    deadline = time.monotonic() + 120
    while not (lock.exists() and lock.stat().st_size) and process.poll() is None:
        assert time.monotonic() < deadline
        time.sleep(0.01)
    time.sleep(0.3)
    assert not (out / "summary.json").exists(), "the set-up was too quick for this test"
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 143, stderr
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert lines[-1].startswith("fe-beam: interrupted") and "before any result" in lines[-1], \
        stderr
    assert "Traceback" not in stderr
    assert not out.exists(), sorted(os.listdir(out))

"""The export interface (`fe_beam.exports`): a fake driver's records become summary.json, a CSV
table and pictures; an interruption midway (in-process, or SIGKILL of the writing process)
leaves readable files holding the steps up to it; on 2 ranks only rank 0 writes."""

import csv
import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fe_beam.exports import (
    Column,
    CSVExport,
    Export,
    Exports,
    PlotExport,
    SummaryExport,
    TableExport,
    XDMFExport,
    figure,
    indexed_columns,
    tip_columns,
)

COLUMNS = [Column("t", lambda r: r["t"]), *tip_columns(),
           *indexed_columns("tension", 2, lambda r: r["tensions"])]


def record(k: int) -> dict:
    """Step k of a fake driver: numbers whose decimal form is not short (repr round trip)."""
    return {"t": k / 7, "tip": {"u": -math.sin(k / 3) / 9, "v": math.cos(k / 11) / 3,
                                "theta": math.pi * k / 13},
            "tensions": [k / 17, 2 ** 0.5 * k]}


def records(count: int) -> list[dict]:
    return [record(k) for k in range(1, count + 1)]


def read_rows(path: Path) -> tuple[list[str], list[list[float]]]:
    with path.open(newline="") as stream:
        header, *rows = list(csv.reader(stream))
    return header, [[float(cell) for cell in row] for row in rows]


def expected_row(r: dict) -> list[float]:
    return [r["t"], r["tip"]["u"], r["tip"]["v"], r["tip"]["theta"], *r["tensions"]]


class Pictures(Export):
    """Counts the draws of a PlotExport (through its ``draw``)."""


def fake_driver(out: Path, count: int, stop_after: int | None = None, throttle: bool = False):
    """A driver loop as the real ones write it: start, on_step per accepted step, finish in a
    ``finally`` with the final status. Returns the draw calls of its PlotExport."""
    steps, drawn = [], []
    summary = {"status": "running", "steps": steps}
    files = Exports([
        CSVExport(out / "history.csv", COLUMNS),
        SummaryExport(out / "summary.json", lambda: summary),
        PlotExport(lambda final: drawn.append(final["status"])),
    ], throttle=throttle)
    files.start(summary)
    try:
        for k in range(1, count + 1):
            steps.append(record(k))
            files.on_step(steps[-1])
            if k == stop_after:
                raise KeyboardInterrupt
        summary["status"] = "converged"
    except KeyboardInterrupt:
        summary["status"] = "interrupted"
        raise
    finally:
        files.finish(summary)
    return drawn


def test_records_become_summary_table_and_pictures(tmp_path):
    drawn = fake_driver(tmp_path, 25, throttle=True)
    header, rows = read_rows(tmp_path / "history.csv")
    assert header == ["t", "tip_u", "tip_v", "tip_theta", "tension_0", "tension_1"]
    assert rows == [expected_row(r) for r in records(25)]  # bit-identical through repr
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "converged" and summary["steps"] == records(25)
    assert drawn == ["converged"]
    # no hidden copies left behind
    assert sorted(p.name for p in tmp_path.iterdir()) == ["history.csv", "summary.json"]


def test_files_are_readable_after_every_step(tmp_path):
    """Without throttling every on_step brings the files up to date: they hold the steps so
    far, complete."""
    steps, summary = [], {"status": "running", "steps": []}
    files = Exports([CSVExport(tmp_path / "h.csv", COLUMNS),
                     SummaryExport(tmp_path / "s.json", lambda: summary)], throttle=False)
    files.start(summary)
    assert read_rows(tmp_path / "h.csv")[1] == []
    for step in records(5):
        steps.append(step)
        summary["steps"] = list(steps)
        files.on_step(step)
        assert read_rows(tmp_path / "h.csv")[1] == [expected_row(r) for r in steps]
        assert json.loads((tmp_path / "s.json").read_text())["steps"] == steps
    files.finish(summary)


def test_interruption_midway_keeps_the_steps_and_draws_nothing(tmp_path):
    with pytest.raises(KeyboardInterrupt):
        fake_driver(tmp_path, 40, stop_after=13, throttle=True)
    _, rows = read_rows(tmp_path / "history.csv")
    assert rows == [expected_row(r) for r in records(13)]
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "interrupted" and len(summary["steps"]) == 13


@pytest.mark.parametrize("status, drawn", [("converged", 1), ("failed", 1), ("completed", 1),
                                            ("interrupted", 0), ("running", 0)])
def test_pictures_only_for_a_finished_analysis(status, drawn):
    calls = []
    Exports([PlotExport(calls.append)]).finish({"status": status})
    assert len(calls) == drawn


def test_pictures_every_step_follow_the_summary():
    summary, calls = {"status": "running", "n": 0}, []
    files = Exports([PlotExport(lambda s: calls.append(s["n"]), lambda: summary,
                                every_step=True)], throttle=False)
    for k in range(3):
        summary["n"] = k
        files.on_step({})
    files.finish(summary | {"status": "interrupted"})  # not redrawn
    assert calls == [0, 1, 2]


def test_csv_width_from_the_first_record(tmp_path):
    def columns(first):
        count = len(first["tensions"]) if first else 0
        return [Column("t", lambda r: r["t"]),
                *indexed_columns("tension", count, lambda r: r["tensions"])]

    files = Exports([CSVExport(tmp_path / "a.csv", columns),
                     CSVExport(tmp_path / "b.csv", COLUMNS, empty=False)])
    files.start(None)
    assert not (tmp_path / "a.csv").exists() and not (tmp_path / "b.csv").exists()
    files.finish(None)
    assert read_rows(tmp_path / "a.csv") == (["t"], [])  # header of a run without records
    assert not (tmp_path / "b.csv").exists()  # empty=False: no table without rows
    files = Exports([CSVExport(tmp_path / "c.csv", columns)])
    for step in records(3):
        files.on_step(step)
    files.finish(None)
    assert read_rows(tmp_path / "c.csv") == (
        ["t", "tension_0", "tension_1"], [[r["t"], *r["tensions"]] for r in records(3)])


def test_table_export_rewrites_the_whole_table(tmp_path):
    values = []
    files = Exports([TableExport(tmp_path / "t.csv",
                                 lambda s: (["k", "share"], [[k, v / sum(s["v"])]
                                                             for k, v in enumerate(s["v"])]),
                                 lambda: {"v": values})], throttle=False)
    for v in (1.0, 3.0):
        values.append(v)
        files.on_step({})
    assert read_rows(tmp_path / "t.csv")[1] == [[0, 0.25], [1, 0.75]]  # the first row changed
    files.finish({"v": [1.0, 1.0]})
    assert read_rows(tmp_path / "t.csv")[1] == [[0, 0.5], [1, 0.5]]


class FakeWriter:
    def __init__(self):
        self.times, self.closed = [], False

    def write(self, t, flush=None):
        self.times.append(t)

    def close(self):
        self.closed = True


def test_xdmf_export_takes_the_time_from_the_record():
    writer = FakeWriter()
    files = Exports([XDMFExport(writer, "load_factor")])
    for f in (0.25, 0.5):
        files.on_step({"load_factor": f})
    files.finish({"status": "failed"})
    assert writer.times == [0.25, 0.5] and writer.closed


def test_figure_is_saved_atomically_and_closed(tmp_path):
    import matplotlib.pyplot as plt

    before = plt.get_fignums()
    with figure(tmp_path / "p.png", 1, 2, figsize=(4, 2)) as (drawn, axes):
        axes[0].plot([0, 1], [1, 0])
        assert len(axes) == 2
    assert (tmp_path / "p.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert plt.get_fignums() == before and not plt.fignum_exists(drawn.number)
    with pytest.raises(RuntimeError), figure(tmp_path / "q.png") as _:
        raise RuntimeError("a failing picture")
    assert not (tmp_path / "q.png").exists() and plt.get_fignums() == before
    assert [p.name for p in tmp_path.iterdir()] == ["p.png"]


KILLED = """
import sys, time
from pathlib import Path
sys.path.insert(0, {tests!r})
from test_exports import fake_driver
print("ready", flush=True)
fake_driver(Path({out!r}), 10**6, throttle=False)
"""


def test_sigkill_midway_leaves_readable_files(tmp_path):
    """The writing process killed at an arbitrary moment: summary.json parses, the CSV is a
    complete table, and both hold the same first steps (CSV one step ahead at most)."""
    code = KILLED.format(tests=str(Path(__file__).parent), out=str(tmp_path))
    process = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                               env=os.environ | {"PYTHONPATH": os.pathsep.join(sys.path)})
    assert process.stdout.readline().strip() == b"ready"
    deadline = time.monotonic() + 30
    while not (tmp_path / "summary.json").exists() and time.monotonic() < deadline:
        time.sleep(0.01)
    time.sleep(0.3)
    process.send_signal(signal.SIGKILL)
    process.wait()
    header, rows = read_rows(tmp_path / "history.csv")
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert header[0] == "t" and len(rows) > 1
    assert rows == [expected_row(r) for r in records(len(rows))]
    assert summary["status"] == "running"
    assert 0 <= len(rows) - len(summary["steps"]) <= 1
    assert summary["steps"] == records(len(summary["steps"]))


@pytest.mark.mpi
def test_rank_zero_writes_collective_exports_on_every_rank(tmp_path):
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    folder = Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0))
    out = folder / "out"
    writer = FakeWriter()
    local = out / f"rank{comm.rank}.json"
    files = Exports([XDMFExport(writer, "t"), SummaryExport(local),
                     CSVExport(out / f"rank{comm.rank}.csv", COLUMNS)], comm)
    files.start({"status": "running"})
    for step in records(4):
        files.on_step(step)
    files.finish({"status": "completed"})
    comm.barrier()
    assert writer.times == [r["t"] for r in records(4)] and writer.closed  # on every rank
    if comm.rank == 0:
        names = sorted(p.name for p in out.iterdir())
        assert names == ["rank0.csv", "rank0.json"]
        assert read_rows(out / "rank0.csv")[1] == [expected_row(r) for r in records(4)]

"""postprocessing/overlay_runs.py on the outputs of real runs, and its error messages."""

import importlib.util
import json
from pathlib import Path

import pytest
from test_config import BASE, dump_toml

from fe_beam.cli import main as fe_beam

SCRIPT = Path(__file__).parents[1] / "postprocessing" / "overlay_runs.py"
spec = importlib.util.spec_from_file_location("overlay_runs", SCRIPT)
overlay = importlib.util.module_from_spec(spec)
spec.loader.exec_module(overlay)


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    folders = []
    for law in ("nonstandard", "reissner"):
        folder = tmp_path_factory.mktemp(law)
        config = {**BASE, "model": {"law": law, "constraint": "none"}}
        (folder / "c.toml").write_text(dump_toml(config))
        assert fe_beam(["static", str(folder / "c.toml"), "--out", str(folder / "out"),
                        "--quiet"]) == 0
        folders.append(folder / "out")
    return folders


def test_overlay_reads_runs_and_writes_png(two_runs, tmp_path):
    out = tmp_path / "overlay.png"
    assert overlay.main([*map(str, two_runs), "--out", str(out)]) == 0
    assert out.stat().st_size > 10_000
    summary = json.loads((two_runs[0] / "summary.json").read_text())
    data = overlay.curves(summary)
    length = summary["model"]["length"]
    assert data["v"][-1] == pytest.approx(summary["steps"][-1]["tip"]["v"] / length)
    assert data["load_factor"][-1] == 1.0


def test_overlay_rejects_missing_and_broken_runs(tmp_path, capsys):
    assert overlay.main([str(tmp_path / "nowhere")]) == 2
    assert "no such file" in capsys.readouterr().err
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "summary.json").write_text("{not json")
    assert overlay.main([str(broken)]) == 2
    assert "not valid JSON" in capsys.readouterr().err
    (broken / "summary.json").write_text(json.dumps({"steps": []}))
    assert overlay.main([str(broken)]) == 2
    assert "no converged load steps" in capsys.readouterr().err

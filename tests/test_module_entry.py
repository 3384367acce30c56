"""``python -m fe_beam`` runs the ``fe-beam`` command (the briefing's and docs' invocation):
a configuration mistake answers with exit 2 and one sentence, as ``fe-beam`` does."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path


def test_python_m_fe_beam_is_the_command(tmp_path):
    config = tmp_path / "c.toml"
    config.write_text("[[rods]]\nname = \"a\"\nlength = \"one\"\n")
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(root))
    done = subprocess.run([sys.executable, "-m", "fe_beam", "static", str(config), "--out",
                           str(tmp_path / "out")], capture_output=True, text=True, env=env,
                          timeout=120)
    assert done.returncode == 2, done.stderr
    assert "[[rods]] #1 length must be a number" in done.stderr

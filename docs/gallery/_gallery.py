"""What the gallery's examples share (not an example: sphinx-gallery skips files named _*):
running a command the way a user types it, and showing the pictures it wrote."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import matplotlib.pyplot as plt

ROOT = next(p for p in Path.cwd().resolve().parents if (p / "examples").is_dir())


def cli_runner(name: str):
    """(run, show, OUT) for the example ``name``: ``run(command, config, out, *sets,
    extra=())`` runs ``fe-beam COMMAND examples/CONFIG --out OUT/out --set ...``, prints the
    command line and what the CLI printed, and returns its summary.json; ``show(out, picture)``
    shows a PNG the run wrote, at its own size. The runs write into the site's build folder,
    never into the repository."""
    folder = ROOT / "docs" / "_build" / "gallery_runs" / name

    def run(command, config, out, *sets, extra=()):
        print("$ fe-beam", command, f"examples/{config}", *(f"--set {s}" for s in sets),
              *extra)
        done = subprocess.run([sys.executable, "-m", "fe_beam.cli", command,
                               str(ROOT / "examples" / config), "--out", str(folder / out),
                               "--quiet", *(f"--set={s}" for s in sets), *extra],
                              capture_output=True, text=True)
        print(done.stdout + done.stderr)
        done.check_returncode()
        return json.loads((folder / out / "summary.json").read_text())

    def show(out, picture, width=None):
        image = plt.imread(folder / out / picture)
        fig, ax = plt.subplots(figsize=(image.shape[1] / 100, image.shape[0] / 100))
        ax.imshow(image)
        ax.set_axis_off()
        fig.subplots_adjust(0, 0, 1, 1)

    return run, show, folder

"""
Validity map: where the rod agrees with the 3D solid
====================================================

``fe-beam validity`` runs ``fe-beam compare`` at full load at every point of a grid over config
keys and draws where the rod's backbone leaves the solid's by 1 % and 5 % of L. Here
``examples/finger_validity.toml`` (tendon tension x tip height, a 3 x 3 map with a 5 mm solid)
on a 3 x 2 grid with a 10 mm solid; every point's solid is solved again on a mesh twice as coarse
for a Richardson estimate of its error (``second_mesh_ratio = 0.5``).
"""

import json
import subprocess
import sys
from pathlib import Path

import matplotlib.pyplot as plt

ROOT = next(p for p in Path.cwd().resolve().parents if (p / "examples").is_dir())
# the runs write into the site's build folder, never into the repository
OUT = ROOT / "docs" / "_build" / "gallery_runs" / "validity"


def fe_beam(command, config, out, *sets, extra=()):
    """Run ``fe-beam COMMAND examples/CONFIG --out OUT --set ...``; return its summary.json."""
    print("$ fe-beam", command, f"examples/{config}", *(f"--set {s}" for s in sets), *extra)
    done = subprocess.run([sys.executable, "-m", "fe_beam.cli", command,
                           str(ROOT / "examples" / config), "--out", str(OUT / out), "--quiet",
                           *(f"--set={s}" for s in sets), *extra], capture_output=True, text=True)
    print(done.stdout + done.stderr)
    done.check_returncode()
    return json.loads((OUT / out / "summary.json").read_text())


def show(out, picture, width=None):
    """Show a PNG the run wrote, at its own size."""
    image = plt.imread(OUT / out / picture)
    fig, ax = plt.subplots(figsize=(image.shape[1] / 100, image.shape[0] / 100))
    ax.imshow(image)
    ax.set_axis_off()
    fig.subplots_adjust(0, 0, 1, 1)

# %%
summary = fe_beam("validity", "finger_validity.toml", "validity", "solid.mesh_size=0.01",
                  "validity.x_values=[1.0, 3.0, 5.0]", "validity.y_values=[0.01, 0.018]")
for point in summary["points"]:
    print(f"tension {point['x']} N, h_tip {point['y']} m: " + ", ".join(
        f"{law} d/L = {rod['backbone_distance']:.2%}" for law, rod in point["rod"].items()))
show("validity", "validity.png")

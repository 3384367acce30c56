"""
Path following through buckling
===============================

``examples/elastica_path.toml``: a column (inextensible elastica, clamped-free) under an axial
tip load, followed by arc length up to four times the load; the bifurcation at the Euler load
pi^2 EI / (4 L^2) is located and the buckled branch followed (``[path] branch_switch =
"positive"``).
"""

import json
import math
import subprocess
import sys
from pathlib import Path

import matplotlib.pyplot as plt

ROOT = next(p for p in Path.cwd().resolve().parents if (p / "examples").is_dir())
# the runs write into the site's build folder, never into the repository
OUT = ROOT / "docs" / "_build" / "gallery_runs" / "path"


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
summary = fe_beam("path", "elastica_path.toml", "path")
EI = 1.0e7 * 0.01**4 / 12
euler = math.pi**2 * EI / 4 / 0.02  # the Euler load as a multiple of the 0.02 N tip force
for point in summary["critical_points"]:
    print(f"{point['kind']} at load factor {point['load_factor']:.5f} (Euler: {euler:.5f})")
path = summary["path"]
fig, ax = plt.subplots(figsize=(7, 4))
for branch in sorted({p["branch"] for p in path}):
    points = [p for p in path if p["branch"] == branch]
    ax.plot([p["tip"]["v"] for p in points], [p["load_factor"] for p in points], ".-",
            label=f"branch {branch}")
ax.axhline(euler, color="k", lw=0.8, ls=":", label="Euler load")
ax.set_xlabel("tip deflection v [m]")
ax.set_ylabel("load factor")
ax.legend()
ax.grid(alpha=0.3)
fig.tight_layout()

# %%
# The run's own picture (``path.png``):
show("path", "path.png")

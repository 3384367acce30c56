"""
Dynamics: release of a bent cantilever
======================================

``examples/release.toml``: a cantilever bent by a tip load (the static pre-state,
``[initial] from_static``) is released at t = 0 and swings freely (generalised-alpha,
``rho_inf = 0.9``). The history in ``summary.json`` holds the tip and the energies at every
output time.
"""

import json
import subprocess
import sys
from pathlib import Path

import matplotlib.pyplot as plt

ROOT = next(p for p in Path.cwd().resolve().parents if (p / "examples").is_dir())
# the runs write into the site's build folder, never into the repository
OUT = ROOT / "docs" / "_build" / "gallery_runs" / "dynamics"


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
summary = fe_beam("dynamic", "release.toml", "release", "mesh.elements=10", "time.t_end=1.0",
                  "time.dt=0.01")
history = summary["history"]
t = [h["t"] for h in history]
fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
top.plot(t, [h["tip"]["v"] for h in history], label="tip v")
top.plot(t, [h["tip"]["u"] for h in history], label="tip u")
top.set_ylabel("tip displacement [m]")
top.legend()
top.grid(alpha=0.3)
for name in ("kinetic", "strain"):
    bottom.plot(t, [h["energies"][name] for h in history], label=name)
bottom.plot(t, [h["energies"]["kinetic"] + h["energies"]["strain"] for h in history], "k--",
            label="kinetic + strain")
bottom.set_xlabel("t [s]")
bottom.set_ylabel("energy [J]")
bottom.legend()
bottom.grid(alpha=0.3)
fig.tight_layout()
print(f"{len(history)} outputs, scheme {summary['scheme']}, rho_inf {summary['rho_inf']}")

# %%
# The picture the run wrote (``dynamics.png``):
show("release", "dynamics.png")

"""
Natural frequencies and mode shapes
===================================

``fe-beam modes`` on the same cantilever (``examples/release.toml``, ``[modes] count = 4``):
the frequencies against Euler-Bernoulli theory, and the shapes read back from ``modes.h5``.
"""

import json
import subprocess
import sys
from pathlib import Path

import h5py
import matplotlib.pyplot as plt
import numpy as np

ROOT = next(p for p in Path.cwd().resolve().parents if (p / "examples").is_dir())
# the runs write into the site's build folder, never into the repository
OUT = ROOT / "docs" / "_build" / "gallery_runs" / "modes"


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
summary = fe_beam("modes", "release.toml", "modes", "mesh.elements=20")
L, E, b, h, rho = 1.0, 1.0e7, 0.02, 0.02, 1000.0
beta_L = np.array([1.87510, 4.69409, 7.85476, 10.99554])
euler_bernoulli = beta_L**2 / (2 * np.pi) * np.sqrt(E * h**2 / 12 / rho) / L**2
for i, (f, fe) in enumerate(zip(summary["frequencies_hz"], euler_bernoulli, strict=False)):
    print(f"mode {i + 1}: {f:8.4f} Hz  (Euler-Bernoulli {fe:8.4f} Hz, {f / fe - 1:+.2%})")

# %%
# The shapes (``modes.xdmf``/``modes.h5``: output step k is mode k):
with h5py.File(OUT / "modes" / "modes.h5") as data:
    x = data["Mesh/mesh/geometry"][:, 0]
    order = np.argsort(x)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for k, f in enumerate(summary["frequencies_hz"]):
        v = data[f"Function/displacement/{k}"][:, 1][order]
        ax.plot(x[order], v / np.abs(v).max(), label=f"{f:.3g} Hz")
ax.set_xlabel("x [m]")
ax.set_ylabel("v (scaled)")
ax.legend(ncol=2)
ax.grid(alpha=0.3)
fig.tight_layout()

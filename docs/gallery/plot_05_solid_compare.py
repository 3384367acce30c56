"""
3D finger and the rod: ``fe-beam solid`` and ``fe-beam compare``
================================================================

The finger as a 3D hyperelastic solid (gmsh mesh, neo-Hookean, the tendon a cable embedded in
the mesh, anchored on the tip face) with the 1D rod alongside, then a tension sweep of the solid
against rods with different section laws. The mesh is coarse (10 mm elements: one across the
tip) so that the page builds fast; the example's 5 mm is closer to converged.
"""

# sphinx_gallery_thumbnail_number = 2

import json
import subprocess
import sys
from pathlib import Path

import matplotlib.pyplot as plt

ROOT = next(p for p in Path.cwd().resolve().parents if (p / "examples").is_dir())
# the runs write into the site's build folder, never into the repository
OUT = ROOT / "docs" / "_build" / "gallery_runs" / "solid_compare"


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
solid = fe_beam("solid", "finger_solid.toml", "solid", "solid.mesh_size=0.01")
last = solid["steps"][-1]
print(f"{solid['dofs']} dofs; tip angle {last['tip']['theta']:.4f} rad at "
      f"{last['tensions'][0]} N; largest bulk principal stretch "
      f"{last['max_principal_stretch_bulk']:.4f}")
show("solid", "backbone.png")

# %%
# The sweep (``[compare] tensions``, here 1 and 2 N; laws of the rod: non-standard and Reissner):
compare = fe_beam("compare", "finger_solid.toml", "compare", "solid.mesh_size=0.01",
                  "compare.tensions=[1.0, 2.0]", 'compare.laws=["nonstandard", "reissner"]')
for row in compare["table"]:
    print(f"{row['tension']} N: 3D tip angle {row['solid']['tip']['theta']:.4f}; " + ", ".join(
        f"{law} d/L = {rod['distance_over_L']:.2%}" for law, rod in row["rod"].items()))
show("compare", "backbones.png")

# %%
show("compare", "tip_vs_tension.png")

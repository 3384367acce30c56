"""
Calibration: fitting E and a tendon offset to measured tips
===========================================================

``fe-beam calibrate CONFIG --data DATA.csv`` fits configuration parameters to measured tip poses
(Gauss-Newton / Levenberg-Marquardt with the adjoint Jacobian). Here the "measurements" are made
by fe_beam itself: the finger of ``examples/finger.toml`` with E = 0.8 MPa is pulled to 0.5 .. 2
N; the fit starts from the file's E = 0.6 MPa and recovers E and the tendon's tip offset.
"""

import json
import subprocess
import sys
from pathlib import Path

import matplotlib.pyplot as plt

ROOT = next(p for p in Path.cwd().resolve().parents if (p / "examples").is_dir())
# the runs write into the site's build folder, never into the repository
OUT = ROOT / "docs" / "_build" / "gallery_runs" / "calibration"


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
# Synthetic data: a forward tension sweep of the "true" finger.
truth = fe_beam("finger", "finger.toml", "truth", "mesh.elements=10", "loads.steps=4",
                "material.E=8e5", "tendons.0.offset_tip=0.005")
data = OUT / "tips.csv"
rows = ["tension,tip_u,tip_v,tip_theta"] + [
    f"{s['tensions'][0]},{s['tip']['u']},{s['tip']['v']},{s['tip']['theta']}"
    for s in truth["steps"]]
data.write_text("\n".join(rows) + "\n")
print(data.read_text())

# %%
# The fit (``[calibrate] parameters`` given on the command line):
fit = fe_beam("calibrate", "finger.toml", "fit", "mesh.elements=10", "loads.steps=4",
              'calibrate.parameters=["material.E", "tendons.0.offset_tip"]',
              extra=("--data", str(data)))
for name, value in fit["parameters"].items():
    error = fit["standard_errors"][name]
    print(f"{name}: {value:.6g} (initial {fit['initial'][name]:.6g}, standard error "
          f"{'-' if error is None else f'{error:.2g}'})")
show("fit", "calibration.png")

"""
Lee's frame through its limit point
===================================

``examples/lee_frame.toml`` ({doc}`/structures`): two members of length L at a right angle,
joined rigidly at the corner, pinned at both far ends, a dead downward load P at L/5 from the
corner on the beam (inextensible, unshearable: the elastica). ``fe-beam path`` follows the
equilibria by arc length through the limit point, located at P L^2 / EI = 18.559 (10 elements
per member; 18.55875 by the shooting solver ``fe_beam.baselines.frame_shooting``, literature
18.48-18.55), the load point 0.406 L down, and on along the unstable branch: the load falls
while the load point first goes on down (snap-through) and then back up (snap-back).
"""

import h5py
import matplotlib.pyplot as plt
import numpy as np
from _gallery import cli_runner

from fe_beam.baselines.frame_shooting import lee_frame, limit_load

fe_beam, show, OUT = cli_runner("lee_frame")

# %%
summary = fe_beam("path", "lee_frame.toml", "path")
limit = next(p for p in summary["critical_points"] if p["kind"] == "limit")
print(f"limit point at P L^2 / EI = {limit['load_factor']:.5f}")

# %%
# The independent reference: the shooting solver across the rigid corner, under displacement
# control of the load point (s = 1.2 along the chain), stops at the largest load.
shooting_load, shooting_v = limit_load(lee_frame(), 1.2, component=1, step=0.02)
print(f"shooting: limit at P L^2 / EI = {shooting_load:.6f}, the load point "
      f"{-shooting_v:.4f} L down")

# %%
# The deformed frames: path.h5 holds each path point's ``displacement``, which moves the
# mesh's line (s, 0) onto the chain (s the arc length along the chain: the column for
# s < 1, the beam beyond): a point is at (s + displacement_x, displacement_y).
with h5py.File(OUT / "path" / "path.h5") as data:
    s = data["Mesh/mesh/geometry"][:, 0]
    order = np.argsort(s)
    shapes = [data[f"Function/displacement/{k}"][:][order]
              for k in range(len(summary["path"]))]
s = s[order]
loaded = int(np.argmin(np.abs(s - 1.2)))  # the load point: 0.2 along the beam
factors = np.array([p["load_factor"] for p in summary["path"]])
stable = np.array([p["stable"] for p in summary["path"]])
deflection = np.array([1.0 - shape[loaded, 1] for shape in shapes])  # downward from y = L

fig, (left, right) = plt.subplots(1, 2, figsize=(11.5, 4.6))
picked = np.linspace(0, len(shapes) - 1, 7).round().astype(int)
colours = plt.cm.viridis(np.linspace(0, 1, len(picked)))
for index, colour in zip(picked, colours, strict=True):
    x, y = s + shapes[index][:, 0], shapes[index][:, 1]
    left.plot(x, y, color=colour, lw=1.8, label=f"P L²/EI = {factors[index]:.1f}")
    left.plot(x[loaded], y[loaded], "v", color=colour, ms=6)
left.plot([0, 0, 1], [0, 1, 1], "k:", lw=1, label="reference")
left.plot([0, 1], [0, 1], "k^", ms=8)  # the pins
left.set_aspect("equal")
left.set_xlabel("x / L")
left.set_ylabel("y / L")
left.set_title("deformed frames along the path")
left.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.0, 0.5))

right.plot(deflection[stable], factors[stable], "o-", ms=3, color="C0", label="stable")
right.plot(deflection[~stable], factors[~stable], "o--", ms=3, color="C1", label="unstable")
top = int(np.argmax(factors))  # the limit's deflection: the top of a parabola through 3 points
a, b, _ = np.polyfit(deflection[top - 1: top + 2], factors[top - 1: top + 2], 2)
right.plot(-b / (2 * a), limit["load_factor"], "ks", ms=8,
           label=f"limit point {limit['load_factor']:.4f}")
right.plot(-shooting_v, shooting_load, "r+", ms=14, mew=2,
           label=f"shooting {shooting_load:.4f}")
right.set_xlabel("downward deflection of the load point / L")
right.set_ylabel("P L² / EI")
right.set_title("load-deflection curve")
right.grid(alpha=0.3)
right.legend(fontsize=8)
fig.tight_layout()

"""
Grasping a cylinder: grasp force, design, pinch and wrap
========================================================

The chapter's finger closes on a 30 mm cylinder (``fe-beam finger`` with ``[[obstacles]]``):
the force the cylinder exerts on the finger against the tendon's tension, the deformed finger
with the cylinder, then ``fe-beam design`` asked for the tendon's base offset that grips with
1 N at 5 N of tension (``objective = "grasp_force"``). The pinch (a symmetric half) and the
wrap are drawn last.
"""

# sphinx_gallery_thumbnail_number = 2

import matplotlib.pyplot as plt
from _gallery import cli_runner

fe_beam, show, OUT = cli_runner("grasp")

# %%
# The tension ramps to 5 N in 10 steps; every step's ``contact`` entry has the force the
# cylinder exerts on the finger (``tension_sweep.csv``: ``grasp_force_0``).
grasp = fe_beam("finger", "finger_grasp.toml", "grasp", "output.plots=true")
tensions = [s["tensions"][0] for s in grasp["steps"]]
forces = [(sum(c * c for c in s["contact"][0]["force"])) ** 0.5 for s in grasp["steps"]]
for tension, force in zip(tensions, forces, strict=True):
    print(f"tension {tension:.2f} N: grasp force {force:.4f} N")
fig, ax = plt.subplots(figsize=(5, 3.5))
ax.plot([0.0] + tensions, [0.0] + forces, "o-")
ax.set_xlabel("tendon tension [N]")
ax.set_ylabel("grasp force on the cylinder [N]")
ax.grid(alpha=0.3)
fig.tight_layout()

# %%
# The finger closing on the cylinder (grey), every second step:
show("grasp", "fig3_9_backbone.png")

# %%
# The design: which base offset of the tendon grips with 1 N at 5 N? A bracketing root solve
# on converged contact states (each trial is the load stepping above):
design = fe_beam("design", "finger_grasp_design.toml", "design", "output.plots=true")
print(design["message"])
for trial in design["history"]:
    print(f"offset_base {trial['variables']['tendons.0.offset_base'] * 1e3:.4f} mm: "
          f"{trial['grasp_force']:.5f} N")
show("design", "design.png")

# %%
# A two-finger pinch as a symmetric half (``examples/pinch.toml``) and a thin finger wrapping
# the cylinder (``examples/finger_wrap.toml``: a contact zone and the tip):
for name in ("pinch", "finger_wrap"):
    run = fe_beam("finger", f"{name}.toml", name, "output.plots=true")
    final = run["steps"][-1]["contact"][0]
    print(f"{name}: force {final['force']} N, contact at x = {final['active']} m")
    show(name, "fig3_9_backbone.png")

"""
Tendon-driven finger and its inverse
====================================

The finger chapter's tapered silicone finger (L = 0.1 m, H 20 -> 10 mm, E = 0.6 MPa) pulled by
one tendon to 2 N (``fe-beam finger``), then the inverse question: which tension puts the tip at
0.3 rad (``[inverse] tip_angle``)?
"""

# sphinx_gallery_thumbnail_number = 3


from _gallery import cli_runner

fe_beam, show, OUT = cli_runner("finger")

# %%
# One run does both: the tension sweep to 2 N and, since the file has ``[inverse] tip_angle =
# 0.3``, the inverse solve. A coarse mesh here (the example has 40 elements and 20 steps):
forward = fe_beam("finger", "finger.toml", "finger", "mesh.elements=10", "loads.steps=5")
for step in forward["steps"]:
    print(f"tension {step['tensions'][0]:.2f} N: tip angle {step['tip']['theta']:.4f} rad")
show("finger", "fig3_8_profiles.png")

# %%
# The tip angle against the tendon tension:
show("finger", "tension_tip.png")

# %%
# The finger in 3D (``finger_3d.png``: pyvista under a virtual screen; the run skips it, and
# says so in ``notes``, when pyvista cannot draw):
if (OUT / "finger" / "finger_3d.png").exists():
    show("finger", "finger_3d.png")
else:
    print("no 3D picture:", forward["notes"])

# %%
# The inverse: the tension that reaches a tip angle of 0.3 rad (``summary.json`` ``inverse``).
# ``--set inverse.tip_angle=0.5`` asks for another angle.
inverse = forward["inverse"]
print(f"tension {inverse['tension']:.4f} N (pull-in {inverse['pull_in'] * 1e3:.3f} mm) puts the "
      f"tip at {inverse['tip']['theta']:.6f} rad, after {inverse['evaluations']} evaluations")

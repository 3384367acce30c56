"""
Spatial rods: a helical tendon, a curved bend, lateral-torsional buckling
=========================================================================

``[model] kinematics = "spatial"`` makes the rod three-dimensional: torsion, two bending
planes, tendons routed anywhere in the section (``offset_y``, ``offset_z`` as formulas of
``s``), loads in any direction and initially curved rods.
"""

import math

from _gallery import cli_runner

fe_beam, show, OUT = cli_runner("spatial")

# %%
# A finger with a tendon winding a quarter turn around its axis: pulling it bends the finger
# out of the x-y plane and twists it. The backbone in three views and in 3D, with the section
# frames (d2: the h direction, d3: the b direction):
finger = fe_beam("finger", "spatial_finger.toml", "finger")
tip = finger["steps"][-1]["tip"]
print("tip displacement [mm]:", [round(1e3 * tip[k], 3) for k in ("u", "v", "w")])
print("tip frame (rows of [d1 d2 d3]):", [[round(c, 4) for c in row] for row in tip["R"]])
show("finger", "fig3_9_backbone.png")

# %%
# The curvatures along the finger: the helix twists it (a)
show("finger", "fig3_8_profiles.png")

# %%
# Bathe & Bolourchi's 45-degree bend under a load normal to its plane, against the tip that
# Simo & Vu-Quoc published (8 elements):
bend = fe_beam("static", "bathe_bolourchi.toml", "bend")
for factor, published in ((0.5, (58.84, 22.33, 40.08)), (1.0, (47.23, 15.79, 53.37))):
    step = min(bend["steps"], key=lambda s, f=factor: abs(s["load_factor"] - f))
    print(f"P = {600 * step['load_factor']:.0f}: tip", [round(c, 2) for c in
                                                       step["tip"]["position"]],
          "published", published)
show("bend", "deformed_shapes.png")

# %%
# Lateral-torsional buckling of a narrow cantilever, against Timoshenko & Gere's
# 4.0126 sqrt(E I_y G J) / L^2 (which neglects the pre-buckling bending: the excess is about
# 1.4 (b/h)^2):
buckling = fe_beam("buckling", "lateral_torsional.toml", "ltb")
E, G, b, h = 2e11, 2e11 / 2.6, 0.005, 0.1
J = b**3 * h / 3 * (1 - 192 * b / (math.pi**5 * h) * sum(
    math.tanh((2 * k + 1) * math.pi * h / (2 * b)) / (2 * k + 1) ** 5 for k in range(12)))
closed = 4.0126 * math.sqrt(E * h * b**3 / 12 * G * J)
print(f"fe-beam buckling: P_cr = {-buckling['critical_loads'][0]['tip_force'][1]:.1f} N; "
      f"Timoshenko & Gere: {closed:.1f} N")

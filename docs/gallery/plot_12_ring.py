"""
A ring pinched across a diameter
================================

``examples/ring.toml`` ({doc}`/structures`): two half rings of radius R (rods with curvature
1/R) joined rigidly at both ends (the second joint closes the loop: a tie), squeezed by two
opposite forces P at the top and bottom (inextensible, unshearable: the elastica). ``fe-beam
path`` follows the ring to P = 3 EI / R^2. For small loads the loaded diameter shortens by
(pi/4 - 2/pi) P R^3 / EI; at large loads the reference is the shooting solver
``fe_beam.baselines.ring_shooting`` (a quarter ring by symmetry, independent of FEniCSx).
"""

import math

import matplotlib.pyplot as plt
import numpy as np
from _gallery import cli_runner

from fe_beam.baselines.ring_shooting import pinched_ring

fe_beam, show, OUT = cli_runner("ring")

# %%
# 16 quadratic elements per half ring. The top load point's ``point`` (where the first point
# force pushes) and the right joint (the structure's ``tip``: it rests on a roller) give the
# two diameters: the ring stays symmetric about both axes, the left joint is pinned.
summary = fe_beam("path", "ring.toml", "path", "mesh.elements=16")
path = summary["path"][1:]
P = np.array([p["load_factor"] for p in path])  # P R^2 / EI
delta = np.array([-2.0 * p["point"]["v"] for p in path])  # the loaded diameter's shortening
widening = np.array([p["tip"]["u"] for p in path])  # the other diameter's lengthening
reference = [pinched_ring(f, 1.0, 1.0) for f in P]
for f, d, w, r in zip(P, delta, widening, reference, strict=True):
    print(f"P R^2/EI = {f:6.3f}: shortening {d:.6f} R (shooting {r['delta']:.6f}), "
          f"widening {w:.6f} R (shooting {r['widening']:.6f})")

# %%
fig, ax = plt.subplots(figsize=(7, 4.2))
ax.plot(P, delta, "o", color="C0", label="loaded diameter, fe-beam path")
ax.plot(P, widening, "s", color="C1", label="other diameter, fe-beam path")
fine = np.linspace(1e-3, P.max(), 60)
shot = [pinched_ring(f, 1.0, 1.0) for f in fine]
ax.plot(fine, [r["delta"] for r in shot], "-", color="C0", lw=1, label="shooting")
ax.plot(fine, [r["widening"] for r in shot], "-", color="C1", lw=1)
ax.plot(fine, (math.pi / 4 - 2 / math.pi) * fine, "k:", lw=1,
        label="(π/4 − 2/π) P R³/EI (small loads)")
ax.set_xlabel("P R² / EI")
ax.set_ylabel("change of diameter / R")
ax.grid(alpha=0.3)
ax.legend(fontsize=8)
fig.tight_layout()

# %%
# The run's own pictures: the deformed rings along the path (joints, supports and the forces
# marked) and the load factor against the top load point's displacement.
show("path", "deformed_shapes.png")
show("path", "path.png")

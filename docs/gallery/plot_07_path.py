"""
Path following through buckling
===============================

``examples/elastica_path.toml``: a column (inextensible elastica, clamped-free) under an axial
tip load, followed by arc length up to four times the load; the bifurcation at the Euler load
pi^2 EI / (4 L^2) is located and the buckled branch followed (``[path] branch_switch =
"positive"``).
"""

import math

import matplotlib.pyplot as plt
from _gallery import cli_runner

fe_beam, show, OUT = cli_runner("path")

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

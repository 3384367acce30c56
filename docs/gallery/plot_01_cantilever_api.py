"""
Figure 2: a cantilever under a growing tip load (Python API)
============================================================

The beam paper's Figure 2 (a): a slender cantilever (L/h = 100) made inextensible and unshearable
with Lagrange multipliers, loaded at the tip to k = P L^2 / EI = 10 in ten steps, against the
elliptic-integral elastica (Mattiasson 1981). This example drives fe_beam from Python:
``fe_beam.run(command, config, out=None, **keys)`` runs one command like ``fe-beam`` does and
returns its ``summary.json`` as a dict; ``keys`` are dotted ``--set`` overrides. With
``out=None`` nothing is written and the dict is the same (the driver's `Result.summary()`).
"""

from pathlib import Path

import matplotlib.pyplot as plt

import fe_beam
from fe_beam.analytic import elastica_tip_load

ROOT = next(p for p in Path.cwd().resolve().parents if (p / "examples").is_dir())
# the runs write into the site's build folder, never into the repository
OUT = ROOT / "docs" / "_build" / "gallery_runs" / "cantilever_api"


# %%
# The configuration is ``examples/cantilever.toml`` (a steel cantilever) with overrides: the
# section of the paper's case (a), the constraint, the load k = 10 and a coarser mesh.
L, E, h = 1.0, 1.0e7, 0.01
EI = E * h**4 / 12
summary = fe_beam.run(
    "static", ROOT / "examples" / "cantilever.toml", out=OUT / "figure2",
    **{"material.E": E, "section.b": h, "section.h": h,
       "model.constraint": "inextensible-unshearable",
       "loads.tip_force": [0.0, -10.0 * EI / L**2], "loads.steps": 10, "mesh.elements": 20},
)
print(summary["status"], f"{summary['dofs']} dofs, {len(summary['steps'])} load steps")

# %%
# The tip at every load level against the elastica:
k = [10.0 * step["load_factor"] for step in summary["steps"]]
exact = [elastica_tip_load(value) for value in k]
fig, ax = plt.subplots(figsize=(7, 4.2))
ax.plot(k, [-s["tip"]["v"] / L for s in summary["steps"]], "o", label="fe_beam  -v/L")
ax.plot(k, [-s["tip"]["u"] / L for s in summary["steps"]], "s", label="fe_beam  -u/L")
ax.plot(k, [e.deflection for e in exact], "-", color="C0", label="elastica")
ax.plot(k, [e.shortening for e in exact], "-", color="C1")
ax.set_xlabel("k = P L² / EI")
ax.set_ylabel("tip displacement / L")
ax.legend()
ax.grid(alpha=0.3)
fig.tight_layout()
worst = max(abs(-s["tip"]["v"] / L - e.deflection) for s, e in zip(summary["steps"], exact))
print(f"largest deflection error: {worst:.2e} L")

# %%
# The deformed shapes the run drew (``deformed_shapes.png`` in the output folder):
picture = plt.imread(OUT / "figure2" / "deformed_shapes.png")
fig, ax = plt.subplots(figsize=(picture.shape[1] / 100, picture.shape[0] / 100))
ax.imshow(picture)
ax.set_axis_off()
fig.subplots_adjust(0, 0, 1, 1)

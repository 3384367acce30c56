"""
Natural frequencies and mode shapes
===================================

``fe-beam modes`` on the same cantilever (``examples/release.toml``, ``[modes] count = 4``):
the frequencies against Euler-Bernoulli theory, and the shapes read back from ``modes.h5``.
"""


import h5py
import matplotlib.pyplot as plt
import numpy as np
from _gallery import cli_runner

fe_beam, show, OUT = cli_runner("modes")

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

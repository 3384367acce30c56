"""
Dynamics: release of a bent cantilever
======================================

``examples/release.toml``: a cantilever bent by a tip load (the static pre-state,
``[initial] from_static``) is released at t = 0 and swings freely (generalised-alpha,
``rho_inf = 0.9``). The history in ``summary.json`` holds the tip and the energies at every
output time.
"""


import matplotlib.pyplot as plt
from _gallery import cli_runner

fe_beam, show, OUT = cli_runner("dynamics")

# %%
summary = fe_beam("dynamic", "release.toml", "release", "mesh.elements=10", "time.t_end=1.0",
                  "time.dt=0.01")
history = summary["history"]
t = [h["t"] for h in history]
fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
top.plot(t, [h["tip"]["v"] for h in history], label="tip v")
top.plot(t, [h["tip"]["u"] for h in history], label="tip u")
top.set_ylabel("tip displacement [m]")
top.legend()
top.grid(alpha=0.3)
for name in ("kinetic", "strain"):
    bottom.plot(t, [h["energies"][name] for h in history], label=name)
bottom.plot(t, [h["energies"]["kinetic"] + h["energies"]["strain"] for h in history], "k--",
            label="kinetic + strain")
bottom.set_xlabel("t [s]")
bottom.set_ylabel("energy [J]")
bottom.legend()
bottom.grid(alpha=0.3)
fig.tight_layout()
print(f"{len(history)} outputs, scheme {summary['scheme']}, rho_inf {summary['rho_inf']}")

# %%
# The picture the run wrote (``dynamics.png``):
show("release", "dynamics.png")

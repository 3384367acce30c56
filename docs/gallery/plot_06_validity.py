"""
Validity map: where the rod agrees with the 3D solid
====================================================

``fe-beam validity`` runs ``fe-beam compare`` at full load at every point of a grid over config
keys and draws where the rod's backbone leaves the solid's by 1 % and 5 % of L. Here
``examples/finger_validity.toml`` (tendon tension x tip height, a 3 x 3 map with a 5 mm solid)
on a 3 x 2 grid with a 10 mm solid; every point's solid is solved again on a mesh twice as coarse
for a Richardson estimate of its error (``second_mesh_ratio = 0.5``).

A 10 mm solid has one element across the finger: the changes between its meshes do not shrink
as an order of convergence says they should, so the map's own error estimate cannot be
certified (the run-time check ``solid_discretisation_error`` fails, and the command would stop
with exit code 3). This quick map runs with ``checks.strict=false``: the numbers are drawn and
the failed check is printed as a warning; the example's own 5 mm map is the one to trust.
"""


from _gallery import cli_runner

fe_beam, show, OUT = cli_runner("validity")

# %%
summary = fe_beam("validity", "finger_validity.toml", "validity", "solid.mesh_size=0.01",
                  "validity.x_values=[1.0, 3.0, 5.0]", "validity.y_values=[0.01, 0.018]",
                  "checks.strict=false")
print("checks passed:", summary.get("checks_passed"))
for point in summary["points"]:
    print(f"tension {point['x']} N, h_tip {point['y']} m: " + ", ".join(
        f"{law} d/L = {rod['backbone_distance']:.2%}" for law, rod in point["rod"].items()))
show("validity", "validity.png")

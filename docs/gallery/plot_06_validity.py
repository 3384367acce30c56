"""
Validity map: where the rod agrees with the 3D solid
====================================================

``fe-beam validity`` runs ``fe-beam compare`` at full load at every point of a grid over config
keys and draws where the rod's backbone leaves the solid's by 1 % and 5 % of L. Here
``examples/finger_validity.toml`` (tendon tension x tip height, a 3 x 3 map with a 5 mm solid)
on a 3 x 2 grid with a 10 mm solid; every point's solid is solved again on a mesh twice as coarse
for a Richardson estimate of its error (``second_mesh_ratio = 0.5``).
"""


from _gallery import cli_runner

fe_beam, show, OUT = cli_runner("validity")

# %%
summary = fe_beam("validity", "finger_validity.toml", "validity", "solid.mesh_size=0.01",
                  "validity.x_values=[1.0, 3.0, 5.0]", "validity.y_values=[0.01, 0.018]")
for point in summary["points"]:
    print(f"tension {point['x']} N, h_tip {point['y']} m: " + ", ".join(
        f"{law} d/L = {rod['backbone_distance']:.2%}" for law, rod in point["rod"].items()))
show("validity", "validity.png")

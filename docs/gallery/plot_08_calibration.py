"""
Calibration: fitting E and a tendon offset to measured tips
===========================================================

``fe-beam calibrate CONFIG --data DATA.csv`` fits configuration parameters to measured tip poses
(Gauss-Newton / Levenberg-Marquardt with the adjoint Jacobian). Here the "measurements" are made
by fe_beam itself: the finger of ``examples/finger.toml`` with E = 0.8 MPa is pulled to 0.5 .. 2
N; the fit starts from the file's E = 0.6 MPa and recovers E and the tendon's tip offset.
"""


from _gallery import cli_runner

fe_beam, show, OUT = cli_runner("calibration")

# %%
# Synthetic data: a forward tension sweep of the "true" finger.
truth = fe_beam("finger", "finger.toml", "truth", "mesh.elements=10", "loads.steps=4",
                "material.E=8e5", "tendons.0.offset_tip=0.005")
data = OUT / "tips.csv"
rows = ["tension,tip_u,tip_v,tip_theta"] + [
    f"{s['tensions'][0]},{s['tip']['u']},{s['tip']['v']},{s['tip']['theta']}"
    for s in truth["steps"]]
data.write_text("\n".join(rows) + "\n")
print(data.read_text())

# %%
# The fit (``[calibrate] parameters`` given on the command line):
fit = fe_beam("calibrate", "finger.toml", "fit", "mesh.elements=10", "loads.steps=4",
              'calibrate.parameters=["material.E", "tendons.0.offset_tip"]',
              extra=("--data", str(data)))
for name, value in fit["parameters"].items():
    error = fit["standard_errors"][name]
    print(f"{name}: {value:.6g} (initial {fit['initial'][name]:.6g}, standard error "
          f"{'-' if error is None else f'{error:.2g}'})")
show("fit", "calibration.png")

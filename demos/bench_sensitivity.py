# # Sensitivity and calibration costs (issue 14's closing-note numbers)
#
# 1. Gradient of one output (adjoint: converged tangent, MUMPS LU, one transposed solve, dR/dp
#    assemblies) against one converged forward update (Newton from the last equilibrium after a
#    1e-3 relative parameter change), for the chapter finger (examples/finger.toml, 40 elements)
#    and the k = 5 cantilever (examples/cantilever.toml).
# 2. Calibration of 2 parameters (E, tendon tip offset) from 4 tip poses of the finger
#    (synthetic data from the model at other parameters), with the forms built once; and the
#    cost of building the model (forms, spaces) once.
#
# Run: `python demos/bench_sensitivity.py` (serial).

import cProfile
import pstats
import time
import tomllib
from pathlib import Path

import numpy as np

from fe_beam.analyses.calibrate import CalibrationData, CalibrationSpec, calibrate
from fe_beam.analyses.sensitivity import RodSensitivity
from fe_beam.cli import quiet_jit_logging

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def best(function, repeat=7):
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        function()
        times.append(time.perf_counter() - started)
    return min(times), float(np.median(times))


def gradient_vs_update(raw, parameters, output):
    model = RodSensitivity(raw, parameters)
    model.solve(1.0)
    start = model.values()
    flip = [1]

    def update():
        flip[0] = -flip[0]
        model.set_values(start * (1 + 1e-3 * flip[0]))
        model.solve(1.0)

    update_time = best(update)
    gradient_time = best(lambda: model.gradient([output]))
    model.destroy()
    return update_time, gradient_time


def main():
    quiet_jit_logging()
    finger = tomllib.loads((EXAMPLES / "finger.toml").read_text())
    finger.pop("inverse")
    cantilever = tomllib.loads((EXAMPLES / "cantilever.toml").read_text())
    cases = [("finger 40 el., 1 parameter", finger, ["material.E"], "tip_theta"),
             ("finger 40 el., 4 parameters", finger,
              ["material.E", "section.h_tip", "tendons.0.offset_tip", "tendons.0.tension"],
              "tip_theta"),
             ("cantilever 40 el., 3 parameters", cantilever,
              ["material.E", "section.h", "loads.tip_force.1"], "tip_v")]
    for name, raw, parameters, output in cases:
        (update, update_median), (gradient, gradient_median) = gradient_vs_update(
            raw, parameters, output)
        print(f"{name}: forward update {1e3 * update:.2f} ms (median {1e3 * update_median:.2f}),"
              f" gradient {1e3 * gradient:.2f} ms (median {1e3 * gradient_median:.2f}): "
              f"ratio {gradient / update:.2f}")

    raw = dict(finger, mesh={"elements": 4, "degree": 2}, loads={"steps": 4})
    params = ("material.E", "tendons.0.offset_tip")
    started = time.perf_counter()
    model = RodSensitivity(raw, params)
    build = time.perf_counter() - started
    truth = np.array([0.6e6, 0.004])
    model.set_values(truth)
    loads, columns = [], {"tip_u": [], "tip_v": [], "tip_theta": []}
    for tension in (0.5, 1.0, 1.5, 2.0):
        model.solve(tension / 2.0)
        for key, value in zip(columns, model.outputs(list(columns)), strict=True):
            columns[key].append(value)
        loads.append(tension)
    data = CalibrationData("tension", np.array(loads), {k: np.array(v) for k, v in
                                                        columns.items()})
    model.set_values(truth * [0.8, 1.25])
    profile = cProfile.Profile()
    started = time.perf_counter()
    profile.enable()
    summary = calibrate(None, data, CalibrationSpec(params), model=model)
    profile.disable()
    elapsed = time.perf_counter() - started
    error = max(abs(summary["parameters"][k] / t - 1) for k, t in zip(params, truth,
                                                                          strict=True))
    print(f"calibration, 2 parameters from 4 tip poses (4 elements): {elapsed:.3f} s, "
          f"{summary['function_evaluations']} evaluations, relative error {error:.1e}; "
          f"building the model once: {build:.2f} s")
    pstats.Stats(profile).sort_stats("cumtime").print_stats(25)
    model.destroy()


if __name__ == "__main__":
    main()

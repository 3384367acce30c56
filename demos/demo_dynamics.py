# # Dynamics demo: the tendon-driven finger in time, and Simo & Vu-Quoc's flying beam
#
# 1. examples/finger_dynamics.toml: the finger's flexor tension stepped to 1 N at t = 0, then
#    ramped to 2 N and held; the tip response against time, with the static tips of fe-beam
#    finger at 1 N and 2 N (the dynamics settles toward them).
# 2. Frequency shift with tension: for several tensions, the first frequency of fe-beam modes
#    with prestress (linearised about the tendon-loaded state) against the frequency measured in
#    the dynamics (start from that static state, lower the tension by 0.5 % over one period of
#    the second mode, which leaves that mode at rest; count the zero crossings of the tip's v).
# 3. examples/flying_spaghetti.toml: energies (kinetic, strain, work of the loads, balance) and
#    linear and angular momenta of the free-flying beam; after the pulse (t > 5) the momenta
#    stay constant and the linear momentum equals the impulse of the force.
#
# Run: `python demos/demo_dynamics.py --out results/dynamics` (about a minute; --full for the
# examples' own meshes and steps and more tensions).

import argparse
import copy
import os
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam.analyses.finger import parse_finger, run_finger
from fe_beam.analyses.transient import parse_dynamic, parse_modes, run_dynamic, run_modes
from fe_beam.cli import quiet_jit_logging
from fe_beam.config.schema import load_config
from fe_beam.exports.outputs import _pyplot
from fe_beam.solvers.dynamics import period_from_crossings

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _static_tip(config: dict, tension: float, comm) -> dict:
    config = copy.deepcopy(config)
    for table in ("time", "damping", "modes", "initial"):
        config.pop(table, None)
    config["tendons"] = [{k: v for k, v in t.items() if k not in ("time_function", "time_table")}
                         for t in config["tendons"]]
    config["tendons"][0]["tension"] = tension
    static, _ = parse_finger(config)
    result, _ = run_finger(static, None, comm, progress=False)
    return result.steps[-1]["tip"]


def finger_response(full: bool, comm) -> dict:
    config = load_config(EXAMPLES / "finger_dynamics.toml")
    config["output"] = {"xdmf": False, "plots": False}
    if not full:
        config["mesh"]["elements"] = 10
        config["time"]["dt"] = 0.004
    result = run_dynamic(parse_dynamic(config), None, comm, progress=False)
    tension = config["tendons"][0]["tension"]
    statics = {f: _static_tip(config, f * tension, comm) for f in (0.5, 1.0)}
    return {"history": result.history, "status": result.status, "static": statics,
            "tension": tension, "config": config}


def frequency_shift(tensions, full: bool, comm) -> list[dict]:
    """f1 of fe-beam modes (prestress) and from the dynamics, at each tension."""
    base = load_config(EXAMPLES / "finger_dynamics.toml")
    base["output"] = {"xdmf": False, "plots": False}
    base.pop("damping", None)
    base["tendons"][0].pop("time_function", None)
    if not full:
        base["mesh"]["elements"] = 10
    rows = []
    for tension in tensions:
        config = copy.deepcopy(base)
        config["tendons"][0]["tension"] = 0.995 * tension
        config["modes"] = {"count": 2, "prestress": True}
        static, modes = parse_modes(config)
        expected, second = run_modes(static, modes, None, comm,
                                     progress=False)["frequencies_hz"][:2]
        period = 1 / expected
        run = copy.deepcopy(base)
        run["tendons"][0]["tension"] = tension
        # lowered linearly over one period of the second mode: that leaves mode 2 at rest
        run["tendons"][0]["time_table"] = [[0.0, 1.0], [1 / second, 0.995], [1e3, 0.995]]
        run["initial"] = {"from_static": True}
        run["time"] = {"t_end": (10.2 if full else 6.2) * period,
                       "dt": period / (100 if full else 60), "rho_inf": 1.0, "output_every": 1}
        history = run_dynamic(parse_dynamic(run), None, comm, progress=False).history
        t = np.array([h["t"] for h in history])
        v = np.array([h["tip"]["v"] for h in history])
        measured = 1 / period_from_crossings(t, v)
        rows.append({"tension": tension, "modes_hz": expected, "dynamics_hz": measured,
                     "tip_angle": history[0]["tip"]["theta"]})
    return rows


def flying_beam(full: bool, comm) -> dict:
    config = load_config(EXAMPLES / "flying_spaghetti.toml")
    config["output"] = {"xdmf": False, "plots": False}
    if not full:
        config["time"]["dt"] = 0.1
    result = run_dynamic(parse_dynamic(config), None, comm, progress=False)
    return {"history": result.history, "status": result.status}


def main(out: Path, full: bool = False, tensions=None) -> dict:
    quiet_jit_logging()
    comm = MPI.COMM_WORLD
    if tensions is None:
        tensions = [0.5, 1, 2, 3, 4, 6, 8] if full else [1, 4, 8]
    results = {"finger": finger_response(full, comm),
               "frequencies": frequency_shift(tensions, full, comm),
               "flying": flying_beam(full, comm)}
    if comm.rank != 0:
        return results
    out.mkdir(parents=True, exist_ok=True)
    plt = _pyplot()

    finger = results["finger"]
    t = [h["t"] for h in finger["history"]]
    figure, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    for key, label in (("theta", "tip angle [rad]"), ("v", "tip v [m]")):
        axis = left if key == "theta" else right
        axis.plot(t, [h["tip"][key] for h in finger["history"]], lw=1.3, label="dynamics")
        for factor, tip in finger["static"].items():
            axis.axhline(tip[key], ls="--", lw=0.9, color="gray")
            axis.annotate(f"static, {factor * finger['tension']:g} N", (t[-1], tip[key]),
                          ha="right", va="bottom", fontsize=8)
        axis.set_xlabel("t [s]")
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    twin = left.twinx()
    twin.plot(t, [h["tendons"]["tensions"][0] for h in finger["history"]], color="crimson",
              lw=0.8, alpha=0.6)
    twin.set_ylabel("tension [N]", color="crimson")
    left.set_title("finger: tension stepped to 1 N, ramped to 2 N")
    right.set_title("tip deflection")
    figure.tight_layout()
    figure.savefig(out / "finger_tip_response.png", dpi=130)
    plt.close(figure)

    rows = results["frequencies"]
    figure, axis = plt.subplots(figsize=(5.5, 4))
    axis.plot([r["tension"] for r in rows], [r["modes_hz"] for r in rows], "o-",
              label="fe-beam modes, prestress")
    axis.plot([r["tension"] for r in rows], [r["dynamics_hz"] for r in rows], "x",
              ms=9, label="dynamics (zero crossings)")
    axis.set_xlabel("tendon tension [N]")
    axis.set_ylabel("first frequency [Hz]")
    axis.set_title("finger: frequency shift with tension")
    axis.grid(alpha=0.3)
    axis.legend()
    figure.tight_layout()
    figure.savefig(out / "finger_frequency_shift.png", dpi=130)
    plt.close(figure)

    flying = results["flying"]["history"]
    t = np.array([h["t"] for h in flying])
    figure, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    energy = {k: np.array([h["energies"][k] for h in flying])
              for k in ("kinetic", "strain", "external_work", "balance_residual")}
    for key, values in energy.items():
        left.plot(t, values, label=key)
    left.set_xlabel("t")
    left.set_ylabel("energy")
    left.set_title("flying beam: energies")
    for key in ("momentum_x", "momentum_y", "angular_momentum"):
        right.plot(t, [h["momenta"][key] for h in flying], label=key)
    right.set_xlabel("t")
    right.set_ylabel("momentum")
    right.set_title("flying beam: momenta (constant after t = 5)")
    for axis in (left, right):
        axis.axvspan(0, 5, color="gold", alpha=0.15, lw=0)
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(out / "flying_beam_energy_momentum.png", dpi=130)
    plt.close(figure)

    print(f"\nfinger: tip angle at t = {finger['history'][-1]['t']:.3g} s: "
          f"{finger['history'][-1]['tip']['theta']:.5f} rad (static at "
          f"{finger['tension']:g} N: {finger['static'][1.0]['theta']:.5f} rad)")
    print(f"\n{'tension [N]':>11} {'tip angle':>10} {'modes [Hz]':>11} {'dynamics [Hz]':>14} "
          f"{'difference':>10}")
    for r in rows:
        print(f"{r['tension']:11.3g} {r['tip_angle']:10.4f} {r['modes_hz']:11.5f} "
              f"{r['dynamics_hz']:14.5f} {r['dynamics_hz'] / r['modes_hz'] - 1:10.2e}")
    after = [h for h in flying if h["t"] >= 5.0]
    spread = {key: max(h["momenta"][key] for h in after) - min(h["momenta"][key] for h in after)
              for key in ("momentum_x", "momentum_y", "angular_momentum")}
    last = flying[-1]
    print(f"\nflying beam: linear momentum ({last['momenta']['momentum_x']:.10g}, "
          f"{last['momenta']['momentum_y']:.10g}) (impulse of the force: (12, 16)); spread in "
          f"free flight: " + ", ".join(f"{k} {v:.2e}" for k, v in spread.items()))
    print(f"  energy balance residual at the end: {last['energies']['balance_residual']:.4g} "
          f"(work {last['energies']['external_work']:.6g})")
    print(f"figures in {out}/")
    return results


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("results/dynamics"))
    parser.add_argument("--full", action="store_true",
                        help="the examples' own meshes and steps, more tensions (several minutes)")
    arguments = parser.parse_args()
    os.environ.setdefault("FE_BEAM_PROGRESS", "1")
    main(arguments.out, full=arguments.full)

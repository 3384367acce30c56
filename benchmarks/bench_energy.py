"""Energy drift on large swings (issue 12): energy-conserving scheme vs generalised-alpha.

Case "swing": the issue's cantilever (L = 1 m, square h = L/200, E = 10 MPa, nu = 0.3,
rho = 1000 kg/m^3, non-standard law, clamped-free), a dead tip load k = P L^2/EI = 2 applied
suddenly at t = 0 and held, no damping, ``--periods`` first-mode periods T1 (Euler-Bernoulli) at
dt = T1/``--steps-per-period``. The energy drift is |kinetic + strain - work of the load| / work
(the balance residual), its largest value over the run (the work is P times the tip travel).

Case "flight": a free-free rod (L/h = 50) pushed at its tip by a force and a moment for 0.2 s
(load factor 1 - t/0.2), then free for ``--flight-time`` s at dt = 0.01 s: the drift of
kinetic + strain after the release, relative to it, and the drift of the angular momentum.

Schemes: "energy-conserving", generalised-alpha rho_inf = 1 (the only non-dissipative choice)
and rho_inf = 0.9 (the default). A run that fails (Newton diverges below the smallest step) is
reported with the time it reached. The cost per step is the wall time of the time stepping
(after a warm-up run of each scheme: JIT excluded) over the number of accepted steps, for the
same problem, dt and Newton tolerance, in one process.

    python benchmarks/bench_energy.py [--periods 100] [--steps-per-period 50] [--elements 16]
                                      [--flight-time 5]
Results: results/benchmarks/energy.json.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np
from common import forget_petsc_options, table, write_results

from fe_beam import (
    BeamModel,
    BeamProblem,
    Discretisation,
    Loads,
    Material,
    ModelOptions,
    Section,
    SolverSettings,
    Supports,
)
from fe_beam.solvers.dynamics import DynamicsFailed, GeneralizedAlpha, TimeSettings
from fe_beam.solvers.energy_momentum import EnergyMomentum

LENGTH, E, NU, RHO = 1.0, 1.0e7, 0.3, 1000.0
SCHEMES = {"energy-conserving": (EnergyMomentum, 0.9),
           "gen-alpha rho_inf=1": (GeneralizedAlpha, 1.0),
           "gen-alpha rho_inf=0.9": (GeneralizedAlpha, 0.9)}


def rod(h: float, elements: int, supports: Supports, loads: Loads) -> BeamModel:
    return BeamModel(LENGTH, Section("rectangle", {"b": h, "h": h}), Material(E, nu=NU, rho=RHO),
                     ModelOptions("nonstandard"), Discretisation(elements, 2), supports, loads)


def first_period(h: float) -> float:
    EI, rho_area = E * h**4 / 12, RHO * h * h
    return 2 * math.pi / (1.8751040687119611**2 * math.sqrt(EI / (rho_area * LENGTH**4)))


def simulate(name: str, model: BeamModel, settings: TimeSettings, load) -> dict:
    scheme, rho_inf = SCHEMES[name]
    settings = TimeSettings(**{**settings.__dict__, "rho_inf": rho_inf})
    problem = BeamProblem(model)
    integrator = scheme(problem, settings, load_function=load,
                        solver_settings=SolverSettings(rtol=1e-10))
    integrator.initialise()
    history = []

    def record(t, step):
        energies, momenta = integrator.energies(), integrator.momenta()
        history.append((t, energies, momenta["angular_momentum"]))

    status = "completed"
    try:
        info = integrator.run(record, progress=False)
    except DynamicsFailed as failure:
        status, info = f"failed at t = {failure.last_time:.4g} s", {}
    finally:
        integrator.solver.destroy()
        forget_petsc_options()
    return {"history": history, "info": info, "status": status, "time": integrator.time}


def swing(name: str, args, warm: bool = False, periods: float | None = None) -> dict:
    h = LENGTH / 200
    EI = E * h**4 / 12
    period = first_period(h)
    model = rod(h, args.elements, Supports(), Loads(tip_force=(0.0, -2.0 * EI / LENGTH**2)))
    periods = 0.2 if warm else (periods or args.periods)
    settings = TimeSettings(t_end=periods * period, dt=period / args.steps_per_period,
                            output_every=max(1, args.steps_per_period // 10))
    run = simulate(name, model, settings, lambda t: 1.0)
    work = max(abs(e["external_work"]) for _, e, _ in run["history"])
    drift = max(abs(e["balance_residual"]) for _, e, _ in run["history"]) / work
    final = run["history"][-1][1]
    return {"status": run["status"], "reached_periods": run["time"] / period,
            "drift": drift, "final_total_over_work": (final["kinetic"] + final["strain"])
            / final["external_work"], **run["info"]}


def flight(name: str, args, warm: bool = False) -> dict:
    h = LENGTH / 50
    model = rod(h, args.elements, Supports("free", "free"),
                Loads(tip_force=(0.3, 1.0), tip_moment=0.3))
    push = 0.2
    t_end = push + (0.1 if warm else args.flight_time)
    run = simulate(name, model, TimeSettings(t_end=t_end, dt=0.01, output_every=1),
                   lambda t: max(0.0, 1.0 - t / push))
    after = [(e["kinetic"] + e["strain"], j) for t, e, j in run["history"] if t > push + 1e-9]
    totals, spins = np.array([a for a, _ in after]), np.array([j for _, j in after])
    return {"status": run["status"], "energy_drift": float(np.max(np.abs(totals - totals[0]))
                                                           / totals[0]),
            "angular_momentum_drift": float(np.max(np.abs(spins - spins[0])) / abs(spins[0])),
            **run["info"]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--periods", type=float, default=100.0)
    parser.add_argument("--steps-per-period", type=int, default=50)
    parser.add_argument("--elements", type=int, default=16)
    parser.add_argument("--flight-time", type=float, default=5.0)
    args = parser.parse_args(argv)
    results = {"settings": vars(args), "swing": {}, "flight": {}}
    for name in SCHEMES:  # warm-up: JIT of every form
        swing(name, args, warm=True)
        flight(name, args, warm=True)
    rows = []
    for name in SCHEMES:
        result = swing(name, args)
        results["swing"][name] = result
        rows.append([name, result["status"], result["reached_periods"], result["drift"],
                     result["final_total_over_work"]])
    print(f"swing: L/h = 200, k = 2 step load, {args.periods:g} T1 at dt = "
          f"T1/{args.steps_per_period}, {args.elements} P2 elements")
    print(table(["scheme", "status", "periods", "max drift", "(K+S)/W end"], rows))
    # cost: the first period of the same swing, where every scheme completes
    rows, cost = [], {}
    for name in SCHEMES:
        result = swing(name, args, periods=1.0)
        per_step = result["wall_time_s"] / result["steps"]
        cost[name] = {"wall_per_step_s": per_step, "steps": result["steps"],
                      "newton_per_step": result["newton_iterations"] / result["steps"]}
        rows.append([name, result["steps"], cost[name]["newton_per_step"], per_step * 1e3])
    results["cost"] = cost
    print("\ncost over the first period")
    print(table(["scheme", "steps", "newton/step", "ms/step"], rows))
    for reference in ("gen-alpha rho_inf=1", "gen-alpha rho_inf=0.9"):
        ratio = cost["energy-conserving"]["wall_per_step_s"] / cost[reference]["wall_per_step_s"]
        results[f"cost_ratio_vs_{reference}"] = ratio
        print(f"cost per step, energy-conserving / {reference}: {ratio:.3g}")
    rows = []
    for name in SCHEMES:
        result = flight(name, args)
        results["flight"][name] = result
        rows.append([name, result["status"], result["energy_drift"],
                     result["angular_momentum_drift"], result.get("steps", 0)])
    print(f"\nflight: free-free L/h = 50, push 0.2 s, then {args.flight_time:g} s free, "
          "dt = 0.01 s")
    print(table(["scheme", "status", "energy drift", "ang. momentum drift", "steps"], rows))
    path = write_results("energy", results)
    print(f"\nwritten {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

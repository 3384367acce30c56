"""Assembly benchmark (issue 29): the cost of a chain of rods against one rod.

A zigzag cantilever of N rods joined rigidly (N = 2, 8, 32; each rod at +-20 degrees to x,
L / N long, total length L = 1 m, section and material of `common.cantilever`, Reissner law,
no constraint, degree 2), clamped at its start, a dead tip force P = 3 EI / L^2 down at its
end; against one straight rod of the same total elements and the same load. Each problem is
built once and solved by load stepping (2 steps) `repeats + 1` times from rest, the cases in
turn (round robin, so that the shared machine's load drifts alike for all); the time per
Newton iteration (residual + Jacobian assembly + MUMPS LU) is a run's wall time over its
iterations, the first run (JIT, caches) left out. The ratios chain / rod are of the minima
of the same run of the script.

    python benchmarks/bench_assembly.py [--repeats 5] [--elements 256 2048]
"""

from __future__ import annotations

import argparse
import math

from common import EI, NU, E, H, stats, table, write_results

from fe_beam import (
    BeamProblem,
    LoadStepping,
    NonlinearProblem,
    SNESSolver,
    SolverSettings,
    run_load_stepping,
)
from fe_beam.config.schema import parse_static

LENGTH = 1.0
ANGLE = math.radians(20.0)
FORCE = 3.0 * EI / LENGTH**2


def _base(elements: int) -> dict:
    return {"section": {"shape": "rectangle", "b": H, "h": H},
            "material": {"E": E, "nu": NU},
            "model": {"law": "reissner", "constraint": "none"},
            "mesh": {"elements": elements, "degree": 2}}


def rod_config(elements: int) -> dict:
    config = _base(elements)
    config["beam"] = {"length": LENGTH}
    config["supports"] = {"x0": "clamped", "xL": "free"}
    config["loads"] = {"tip_force": [0.0, -FORCE]}
    return config


def chain_config(rods: int, elements: int) -> dict:
    """A zigzag of ``rods`` rods of elements / rods elements each."""
    config = _base(elements // rods)
    piece = LENGTH / rods
    start, entries = [0.0, 0.0], []
    for index in range(rods):
        angle = ANGLE if index % 2 == 0 else -ANGLE
        direction = [math.cos(angle), math.sin(angle)]
        entries.append({"name": f"r{index}", "start": list(start), "direction": direction,
                        "length": piece})
        start = [start[0] + piece * direction[0], start[1] + piece * direction[1]]
    entries[0]["supports"] = {"x0": "clamped"}
    entries[-1]["loads"] = {"point_forces": [[piece, 0.0, -FORCE]]}
    config["rods"] = entries
    config["joints"] = [{"name": f"j{i}", "at": [f"r{i}:end", f"r{i + 1}:start"]}
                        for i in range(rods - 1)]
    return config


class Timed:
    """A problem built once and its solver; `run` solves it from rest by load stepping and
    returns the time per Newton iteration."""

    def __init__(self, config: dict):
        static = parse_static(config)
        self.problem = BeamProblem(static.model)
        self.solver = SNESSolver(NonlinearProblem(self.problem.residual, self.problem.w,
                                                  self.problem.bcs), SolverSettings())
        space = self.problem.space
        self.dofs = space.dofmap.index_map.size_global * space.dofmap.index_map_bs
        self.iterations, self.times = 0, []

    def run(self) -> None:
        self.problem.w.x.array[:] = 0.0
        steps = run_load_stepping(self.solver, self.problem.set_load_factor,
                                  LoadStepping(steps=2), progress=False)
        self.iterations = sum(s.iterations for s in steps)
        self.times.append(sum(s.wall_time_s for s in steps) / self.iterations)

    def record(self) -> dict:
        self.solver.destroy()
        return {"dofs": self.dofs, "newton_iterations": self.iterations,
                "seconds_per_iteration": stats(self.times[1:])}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--elements", type=int, nargs="+", default=[256, 2048])
    parser.add_argument("--rods", type=int, nargs="+", default=[2, 8, 32])
    args = parser.parse_args(argv)
    results = []
    for elements in args.elements:
        cases = {"rod": Timed(rod_config(elements))}
        cases |= {f"chain_{n}": Timed(chain_config(n, elements)) for n in args.rods}
        for _ in range(args.repeats + 1):  # round robin: the machine's load drifts alike
            for case in cases.values():
                case.run()
        runs = {name: case.record() for name, case in cases.items()}
        reference = runs["rod"]["seconds_per_iteration"]
        rows = []
        for name, run in runs.items():
            best, median = (run["seconds_per_iteration"][k] for k in ("min_s", "median_s"))
            run["ratio_to_rod"] = best / reference["min_s"]
            run["median_ratio_to_rod"] = median / reference["median_s"]
            rows.append([name.replace("chain_", "") if name != "rod" else "1 (one rod)",
                         elements, run["dofs"], run["newton_iterations"], best * 1e3,
                         median * 1e3, run["ratio_to_rod"], run["median_ratio_to_rod"]])
        print(f"Newton iteration cost, {elements} degree-2 elements in all (Reissner, no "
              "constraint, MUMPS)")
        print(table(["rods", "elements", "dofs", "Newton its", "ms/it (min)", "ms/it (median)",
                     "chain / rod (min)", "(median)"], rows))
        print()
        results.append({"elements": elements, "runs": runs})
    path = write_results("assembly", {"repeats": args.repeats, "sizes": results})
    print(f"results in {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

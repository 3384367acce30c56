"""Statics benchmarks of fe_beam.

a. Mattiasson sweep: Reissner law + inextensible-unshearable cantilever (the Euler elastica),
   100 degree-2 elements, one load-stepping run of 10 steps to k = P L^2 / EI = 10; wall time
   after JIT and the tip errors at every k vs `fe_beam.analytic.elastica_tip_load`.
b. Cost per Newton iteration (residual + Jacobian assembly + MUMPS LU solve) for 10 ... 10^4
   degree-2 elements (non-standard law, no constraint, k = 3 tip load) and the fitted exponent
   of time vs elements.

    python benchmarks/bench_statics.py [--repeats 3] [--sizes 10 100 1000 10000]
                                       [--linear-solver mumps|lu]
"""

from __future__ import annotations

import argparse
import statistics
import sys

from common import (
    cantilever,
    fit_exponent,
    static_config,
    stats,
    table,
    timed,
    tip_errors,
    write_results,
)

from fe_beam import (
    BeamProblem,
    LoadStepping,
    NonlinearProblem,
    SNESSolver,
    SolverSettings,
    run_load_stepping,
)
from fe_beam.analyses.static import solve_static
from fe_beam.analytic import elastica_tip_load

K_MAX = 10.0
SWEEP_ELEMENTS = 100
SWEEP_STEPS = 10


def mattiasson_sweep(repeats: int) -> dict:
    config = static_config(cantilever(K_MAX, SWEEP_ELEMENTS), SWEEP_STEPS)
    solve_static(config, None, progress=False)  # JIT (FFCx forms cached on disk)
    times, result = [], None
    for _ in range(repeats):
        seconds, result = timed(lambda: solve_static(config, None, progress=False))
        assert result.status == "converged", result.message
        times.append(seconds)
    levels = []
    for step in result.steps:
        k = K_MAX * step["load_factor"]
        tip = step["tip"]
        errors = tip_errors(tip["u"], tip["v"], tip["theta"], elastica_tip_load(k))
        levels.append({"k": k, "newton_iterations": step["newton_iterations"], **errors})
    rows = [[f"{lv['k']:.3g}", lv["newton_iterations"], lv["shortening"], lv["deflection"],
             lv["rotation"], lv["position"]] for lv in levels]
    print(f"a. Mattiasson sweep: {SWEEP_ELEMENTS} degree-2 elements, {result.dofs} dofs, "
          f"{len(result.steps)} load steps to k = {K_MAX:g}")
    print(table(["k", "Newton its", "err shortening", "err deflection", "err rotation",
                 "err tip / L"], rows))
    worst = max(max(lv["shortening"], lv["deflection"], lv["rotation"]) for lv in levels)
    print(f"max error over all levels and quantities: {worst:.2e}")
    print(f"wall time after JIT: median {statistics.median(times):.3f} s, "
          f"min {min(times):.3f} s ({repeats} runs)\n")
    return {"elements": SWEEP_ELEMENTS, "degree": 2, "dofs": result.dofs, "levels": levels,
            "max_error": worst, "wall": stats(times)}


def seconds_per_iteration(elements: int, repeats: int, linear_solver: str) -> dict:
    """Load stepping (2 steps to k = 3) on a problem built once; time / Newton iterations."""
    problem = BeamProblem(cantilever(3.0, elements, law="nonstandard", constraint="none"))
    solver = SNESSolver(NonlinearProblem(problem.residual, problem.w, problem.bcs),
                        SolverSettings(linear_solver=linear_solver))
    per_iteration, iterations = [], 0
    try:
        for _ in range(repeats + 1):  # the first run warms caches (and JIT on the first size)
            problem.w.x.array[:] = 0.0
            steps = run_load_stepping(solver, problem.set_load_factor, LoadStepping(steps=2),
                                      progress=False)
            iterations = sum(s.iterations for s in steps)
            per_iteration.append(sum(s.wall_time_s for s in steps) / iterations)
    finally:
        solver.destroy()
    dofs = problem.space.dofmap.index_map.size_global * problem.space.dofmap.index_map_bs
    return {"elements": elements, "dofs": dofs, "newton_iterations": iterations,
            "seconds_per_iteration": stats(per_iteration[1:])}


def newton_scaling(sizes: list[int], repeats: int, linear_solver: str) -> dict:
    runs = [seconds_per_iteration(n, repeats, linear_solver) for n in sizes]
    best = [r["seconds_per_iteration"]["min_s"] for r in runs]
    exponent = fit_exponent(sizes, best)
    # Below ~100 elements a fixed per-iteration cost (Python callbacks, PETSc set-up) dominates.
    large = [(n, t) for n, t in zip(sizes, best, strict=True) if n >= 100]
    exponent_large = fit_exponent(*zip(*large, strict=True)) if len(large) > 1 else None
    rows = [[r["elements"], r["dofs"], r["newton_iterations"],
             r["seconds_per_iteration"]["min_s"] * 1e3,
             r["seconds_per_iteration"]["median_s"] * 1e3,
             r["seconds_per_iteration"]["min_s"] / r["elements"] * 1e6] for r in runs]
    print(f"b. Newton iteration cost (non-standard law, no constraint, degree 2, k = 3, "
          f"linear solver {linear_solver})")
    print(table(["elements", "dofs", "Newton its", "ms/it (min)", "ms/it (median)",
                 "us/it/element"], rows))
    text = f"fitted exponent of time vs elements: {exponent:.2f} over {sizes[0]}-{sizes[-1]}"
    if exponent_large is not None:
        text += f", {exponent_large:.2f} over {large[0][0]}-{large[-1][0]}"
    print(text)
    return {"linear_solver": linear_solver, "runs": runs, "exponent": exponent,
            "exponent_from_100_elements": exponent_large}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000, 10000])
    parser.add_argument("--linear-solver", default="mumps", choices=["mumps", "lu"],
                        help="solver.linear_solver of part b (default mumps, fe_beam's default;"
                        " part a always uses MUMPS: PETSc's own LU has no pivoting for the"
                        " zero diagonal of the multiplier problem)")
    args = parser.parse_args(argv)
    sweep = mattiasson_sweep(args.repeats)
    scaling = newton_scaling(args.sizes, args.repeats, args.linear_solver)
    suffix = "" if args.linear_solver == "mumps" else f"_{args.linear_solver}"
    path = write_results(f"statics{suffix}", {"mattiasson_sweep": sweep,
                                              "newton_scaling": scaling})
    print(f"results: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

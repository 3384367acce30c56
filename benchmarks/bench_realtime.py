"""Real-time re-solves (issue 14): warm-started finger updates vs the shooting baseline, and
cold `solve_static` of the k = 3 cantilever with cached forms vs tuned PyElastica.

a. Finger. The chapter's finger and model as in bench_finger.py (Reissner + unshearable, the
   shooting solver's model), with the fewest degree-2 elements whose tip is within 1e-4 L of a
   converged shooting reference at all 20 tensions 0.1 .. 2 N (and 2x elements also; the
   search of bench_finger.py). `fe_beam.solvers.realtime.RealtimeSolver` is built once at 2 N, then
   updated (i) through the 20 tensions of the sweep (steps of 0.1 N; every tip is checked
   against the reference) and (ii) along a control-rate trajectory, tau(t) = 1.5 + 0.5
   sin(2 pi t), t = 0 .. 1 s sampled at 1 kHz (1000 updates). Baseline: seed 001's shooting
   solver (`fe_beam.baselines.shooting.solve_finger`) at its cheapest rtol within 1e-4 L, one
   solve per tension started from the previous base reactions (continuation), on the same two
   sequences (the trajectory: its first 100 samples). Time per update; ratio shooting / fe_beam
   per repeat, median over alternating repeats. With and without the step check (rotation
   jump, admissibility: ``check=False``).

b. Cantilever, dead tip load k = 3, tip within 1e-3 L and 1e-4 L of the elastica
   (bench_pyelastica.py: its stored PyElastica settings and its fe_beam model: Reissner +
   inextensible-unshearable, fewest degree-2 elements, 2 load steps). `solve_static`
   (record_shapes=False) cold, first of its kind in the process (the problem cache cleared
   before each: building forms from the FFCx disk cache, spaces, SNES) and cold with the cache
   (a second solve of the same kind: the built problem is reused, state reset, numbers
   written in; the iterates are those of a new problem). PyElastica build + integrate,
   alternating, ``--repeats`` times; ratio per repeat, median.

``--profile`` prints a cProfile of 200 finger updates and 20 cached cold solves.

    python benchmarks/bench_realtime.py [--repeats 5] [--profile] [--skip-pyelastica]

Writes results/benchmarks/realtime.json.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import statistics
import sys
import time

import numpy as np
from common import cantilever, static_config, stats, table, timed, write_results  # noqa: F401

from fe_beam.analyses.static import solve_static
from fe_beam.baselines import shooting
from fe_beam.solvers import realtime

TRAJECTORY = 1.5 + 0.5 * np.sin(2 * np.pi * np.arange(1000) / 1000.0)
SHOOTING_TRAJECTORY = 100


def cpu_timed(function):
    """(wall s, CPU s of this process, value)."""
    t0, c0 = time.perf_counter(), time.process_time()
    value = function()
    return time.perf_counter() - t0, time.process_time() - c0, value


def finger_part(repeats: int) -> dict:
    import bench_finger as bf

    _, reference = timed(lambda: bf.shooting_sweep(bf.REFERENCE_RTOL))
    elements, fe_errors = bf.cheapest_fe(reference)
    rtol, sh_errors = bf.cheapest_shooting(reference)
    config = bf.fe_config(elements)
    print(f"finger: {elements} degree-2 elements (sweep error {fe_errors[elements]:.1e} L), "
          f"shooting rtol {rtol:g} ({sh_errors[rtol]:.1e} L)")

    def shooting_run(tensions) -> float:
        guess = None
        t0, c0 = time.perf_counter(), time.process_time()
        for tension in tensions:
            s = shooting.solve_finger(bf.shooting_finger(float(tension)), n_points=2, rtol=rtol,
                                      initial_guess=guess)
            guess = (*s.base_force, s.base_moment)
        return ((time.perf_counter() - t0) / len(tensions),
                (time.process_time() - c0) / len(tensions))

    solvers = {check: realtime.RealtimeSolver(config, check=check) for check in (True, False)}
    # accuracy of the updates along the sweep (vs the converged shooting reference)
    solver = solvers[True]
    tips = np.array([[solver.update(tensions=[t])[k] for k in ("u", "v", "theta")]
                     for t in bf.TENSIONS])
    update_error = float(np.max(np.hypot(tips[:, 0] - reference[:, 0],
                                         tips[:, 1] - reference[:, 1])) / bf.LENGTH)

    def fe_run(solver, tensions) -> float:
        solver.update(tensions=[float(tensions[-1])])
        t0, c0 = time.perf_counter(), time.process_time()
        for tension in tensions:
            solver.update(tensions=[float(tension)])
        return ((time.perf_counter() - t0) / len(tensions),
                (time.process_time() - c0) / len(tensions))

    sequences = {"sweep": (bf.TENSIONS, bf.TENSIONS),
                 "trajectory": (TRAJECTORY, TRAJECTORY[:SHOOTING_TRAJECTORY])}
    times = {f"{name} {who}": [] for name in sequences
             for who in ("shooting", "fe_beam check", "fe_beam no check")}
    for solver in solvers.values():
        fe_run(solver, TRAJECTORY[:50])  # warm-up
    shooting_run(bf.TENSIONS[:2])
    for _ in range(repeats):
        for name, (fe_seq, sh_seq) in sequences.items():
            times[f"{name} shooting"].append(shooting_run(sh_seq))
            times[f"{name} fe_beam check"].append(fe_run(solvers[True], fe_seq))
            times[f"{name} fe_beam no check"].append(fe_run(solvers[False], fe_seq))
    iterations = {check: s.statistics["newton_iterations"] / max(s.statistics["updates"], 1)
                  for check, s in solvers.items()}
    fallbacks = {check: s.statistics["fallbacks"] for check, s in solvers.items()}
    dense = solvers[True].dense
    for s in solvers.values():
        s.close()
    ratios, cpu_ratios = {}, {}
    rows = []
    for key, values in times.items():
        name = key.split(" ")[0]
        wall, cpu = [v[0] for v in values], [v[1] for v in values]
        ratio = ""
        if "fe_beam" in key:
            reference = times[f"{name} shooting"]
            ratios[key] = statistics.median(
                s[0] / f for s, f in zip(reference, wall, strict=True))
            cpu_ratios[key] = statistics.median(
                s[1] / f for s, f in zip(reference, cpu, strict=True))
            ratio = f"{ratios[key]:.0f}x (CPU {cpu_ratios[key]:.0f}x)"
        rows.append([key, statistics.median(wall) * 1e3, min(wall) * 1e3,
                     statistics.median(cpu) * 1e3, 1.0 / statistics.median(wall), ratio])
    print(f"finger updates ({repeats} alternating repeats; fe_beam dense LU: {dense}; "
          f"Newton iterations per update {iterations[True]:.2f}; fallbacks {fallbacks[True]}; "
          f"max tip error of the sweep's updates {update_error:.1e} L)")
    print(table(["", "wall ms/update", "min wall ms", "CPU ms/update", "updates/s",
                 "shooting / this"], rows))
    return {"elements": elements, "shooting_rtol": rtol, "fe_sweep_error": fe_errors[elements],
            "update_tip_error": update_error, "dense_lu": dense,
            "newton_iterations_per_update": iterations[True], "fallbacks": fallbacks[True],
            "wall_per_update": {k: stats([v[0] for v in t]) for k, t in times.items()},
            "cpu_per_update": {k: stats([v[1] for v in t]) for k, t in times.items()},
            "ratios": ratios, "cpu_ratios": cpu_ratios}


def cantilever_part(repeats: int, tolerances) -> dict:
    import bench_pyelastica as bp

    if bp.ea is None:
        print(f"PyElastica not available ({bp.IMPORT_ERROR}): part b skipped")
        return {"status": "unavailable", "reason": bp.IMPORT_ERROR}
    from dataclasses import replace

    bp.run_rod(replace(bp.CHOSEN["1e-3"], final_time=0.01))  # numba JIT
    results = {}
    for tol in tolerances:
        label = bp.tolerance_label(tol)
        chosen = bp.CHOSEN[label]
        n, fe_errors = bp.fe_beam_cheapest(tol)
        config = static_config(cantilever(bp.K, n), bp.FE_STEPS)

        def first_of_kind(config=config):
            realtime.clear_cache()
            return cpu_timed(lambda: solve_static(config, None, progress=False,
                                                  record_shapes=False))

        def cached(config=config):
            return cpu_timed(lambda: solve_static(config, None, progress=False,
                                                  record_shapes=False))

        first_of_kind()
        cached()
        times = {"PyElastica build + integrate": [], "fe_beam solve_static, first of its kind":
                 [], "fe_beam solve_static, cached forms": []}
        rod_error = None
        cpu = {k: [] for k in times}
        for _ in range(repeats):
            c0 = time.process_time()
            rod = bp.run_rod(chosen)
            cpu["PyElastica build + integrate"].append(time.process_time() - c0)
            rod_error = rod["errors"]["position"]
            times["PyElastica build + integrate"].append(rod["wall_s"])
            for name, run in (("fe_beam solve_static, first of its kind", first_of_kind),
                              ("fe_beam solve_static, cached forms", cached)):
                seconds, used, result = run()
                assert result.status == "converged"
                times[name].append(seconds)
                cpu[name].append(used)
        reference = times["PyElastica build + integrate"]
        ratios = {k: statistics.median(p / f for p, f in zip(reference, v, strict=True))
                  for k, v in times.items() if k.startswith("fe_beam")}
        cpu_ratios = {k: statistics.median(
            p / f for p, f in zip(cpu["PyElastica build + integrate"], v, strict=True))
            for k, v in cpu.items() if k.startswith("fe_beam")}
        rows = [[k, statistics.median(v), min(v), statistics.median(cpu[k]),
                 f"{ratios[k]:.1f}x (CPU {cpu_ratios[k]:.1f}x)" if k in ratios else ""]
                for k, v in times.items()]
        print(f"\ncantilever k = {bp.K:g}, tip within {tol:g} L: PyElastica {chosen.elements} "
              f"el., {chosen.steps} steps, error {rod_error:.1e} L; fe_beam {n} degree-2 el., "
              f"error {fe_errors['position']:.1e} L")
        print(table(["", "median wall s", "min wall s", "median CPU s", "PyElastica / this"],
                    rows))
        results[label] = {"fe_elements": n, "fe_error": fe_errors["position"],
                          "pyelastica": {"settings": chosen.__dict__, "error": rod_error},
                          "times": {k: stats(v) for k, v in times.items()},
                          "cpu_times": {k: stats(v) for k, v in cpu.items()},
                          "ratios": ratios, "cpu_ratios": cpu_ratios}
    return results


def profile() -> None:
    import bench_finger as bf

    config = bf.fe_config(3)
    with realtime.RealtimeSolver(config) as solver:
        profiler = cProfile.Profile()
        profiler.enable()
        for tension in TRAJECTORY[:200]:
            solver.update(tensions=[float(tension)])
        profiler.disable()
    out = io.StringIO()
    pstats.Stats(profiler, stream=out).sort_stats("tottime").print_stats(15)
    print("profile of 200 finger updates (3 elements):\n" + out.getvalue())
    cold = static_config(cantilever(3.0, 2), 2)
    solve_static(cold, None, progress=False, record_shapes=False)
    profiler = cProfile.Profile()
    profiler.enable()
    for _ in range(20):
        solve_static(cold, None, progress=False, record_shapes=False)
    profiler.disable()
    out = io.StringIO()
    pstats.Stats(profiler, stream=out).sort_stats("tottime").print_stats(15)
    print("profile of 20 cached cold solve_static (k = 3, 2 elements):\n" + out.getvalue())


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--skip-pyelastica", action="store_true")
    args = parser.parse_args(argv)
    data = {"finger": finger_part(args.repeats)}
    if not args.skip_pyelastica:
        data["cantilever"] = cantilever_part(args.repeats, (1e-3, 1e-4))
    if args.profile:
        profile()
    print(f"results: {write_results('realtime', data)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

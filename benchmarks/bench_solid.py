"""3D finger benchmark (issue 5): Newton iteration cost vs DOFs (MUMPS and GAMG), a full tension
sweep on a >= 100k-DOF mesh, and 1 vs 2 MPI ranks.

The finger is the chapter's finger of `fe_beam.analyses.finger.DEFAULT_FINGER` in 3D
(`fe_beam.solid`):
L = 0.1 m, B = 0.02 m, H 0.02 -> 0.01 m, a straight tendon 8 -> 4 mm above the axis anchored
on the tip face, Neo-Hookean with E = 0.6 MPa, nu = 0.45, P2 displacement formulation, uniform
gmsh sizes (`MeshSizes(size)`), clamp at x = 0.

a. Cost per Newton iteration vs DOFs: for each mesh size a problem is built (gmsh and FFCx are
   not timed) and one load step to a tendon tension of 0.5 N is solved from the straight finger
   (4-5 Newton iterations; the first iteration includes the solver set-up: MUMPS analysis,
   GAMG hierarchy). Seconds per Newton iteration = solve time / Newton iterations; assembly =
   one residual + one Jacobian assembly (timed separately, best of 3). Linear solvers:
   ``mumps`` (fe_beam's default: LU), ``gamg`` (fe_beam's: CG + GAMG with the rigid-body
   near-nullspace, ksp_rtol 1e-10) and ``gamg`` with GMRES instead of CG. Krylov iterations per
   Newton iteration are reported (they must stay bounded under refinement). Exponents are
   least-squares slopes of log(time) vs log(DOFs). MUMPS is skipped on meshes where its
   predicted time per iteration exceeds ``--mumps-cap`` seconds, GMRES above 35k DOFs.
b. Full tension sweep: 20 load steps to 2 N (0.1, 0.2, ... 2 N) on the largest mesh with GAMG
   (CG): total time, Newton and Krylov iterations per step, tip rotation.
c. 1 vs 2 ranks (run under ``mpirun -n 2 ... --ranks``): the load step of part a on the same
   mesh, solved on rank 0 alone (COMM_SELF, rank 1 waiting without spinning) and on both ranks
   (COMM_WORLD), in one run; speed-up = serial / parallel time.

    python benchmarks/bench_solid.py [--quick]                  # a + b (~11 min; --quick ~1.5 min)
    mpirun --allow-run-as-root -n 2 .venv/bin/python benchmarks/bench_solid.py --ranks [--quick]

d-g. The u-p (Taylor-Hood P2-P1) finger of issue 10 (nu = 0.45, tendon to 5 N), MUMPS vs
   ``[solid] solver = "fieldsplit"`` (``--up PART ...``, under mpirun for 2 ranks): ``sweep``
   the full sweep on the 2 mm mesh (~92k DOFs) with fieldsplit, MUMPS timed for its first
   ``--mumps-newton`` Newton iterations and extrapolated to the sweep's Newton iterations;
   ``ranks`` one probe step on 1 and on all ranks; ``scaling`` s per Newton iteration (wall,
   and CPU s per rank by process_time), Krylov its per Newton, peak RSS per rank, meshing
   time and memory and PETSc event times vs DOFs (``--mumps-cap 0``: fieldsplit only); ``nu``
   Krylov its vs nu (0.3 .. 0.4999).

    mpirun --allow-run-as-root -n 2 .venv/bin/python benchmarks/bench_solid.py --up sweep ranks
    nice -n 5 mpirun --allow-run-as-root -n 2 .venv/bin/python benchmarks/bench_solid.py --up
        scaling --mumps-cap 0 --up-sizes 0.005 0.0034 0.002 0.0013 0.00085
"""

from __future__ import annotations

import argparse
import resource
import sys
import time

import numpy as np
from common import fit_exponent, table, write_results
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.analyses.finger import DEFAULT_FINGER
from fe_beam.fem import compat
from fe_beam.solid import (
    Discretization,
    FingerGeometry,
    MeshSizes,
    NeoHookean,
    SolidFingerProblem,
    TendonLoad,
    TendonPath,
    create_finger_mesh,
)
from fe_beam.solvers.continuation import run_load_stepping
from fe_beam.solvers.newton import LoadStepping, SolveFailed, SolverSettings

_d = DEFAULT_FINGER
LENGTH = _d["beam"]["length"]
GEOMETRY = FingerGeometry(
    LENGTH, _d["section"]["b"], _d["section"]["h"], _d["section"]["h_tip"],
    tendons=(TendonPath.from_offsets(LENGTH, _d["tendons"][0]["offset_base"],
                                     _d["tendons"][0]["offset_tip"]),))
MATERIAL = NeoHookean.from_young(_d["material"]["E"], _d["material"]["nu"])
MAX_TENSION = _d["tendons"][0]["tension"]  # 2 N
LEVELS = _d["loads"]["steps"]  # 20
PROBE_TENSION = 0.5  # N, the single load step of parts a and c

# mesh size [m] -> DOFs (P2): 0.007: 5.0k, 0.005: 9.3k, 0.004: 16k, 0.003: 31k, 0.0025: 49k,
# 0.002: 88k, 0.0019: 100.1k, 0.0018: 117k
SIZES = (0.007, 0.005, 0.004, 0.003, 0.0025, 0.0019)
QUICK_SIZES = (0.007, 0.005, 0.004)
SOLVERS = {
    "mumps": SolverSettings(linear_solver="mumps"),
    "gamg": SolverSettings(linear_solver="gamg"),
    "gamg-gmres": SolverSettings(linear_solver="gamg", petsc_options={"ksp_type": "gmres"}),
}
GMRES_MAX_DOFS = 35_000  # GMRES + GAMG only on the smaller meshes (it costs as much as CG)


def dofs_of(problem: SolidFingerProblem) -> int:
    return problem.W.dofmap.index_map.size_global * problem.W.dofmap.index_map_bs


def build(finger, solver: str, tension: float) -> SolidFingerProblem:
    return SolidFingerProblem(finger, MATERIAL, tendons=[TendonLoad(tension=tension)],
                              solver=SOLVERS[solver], prefix=f"bench_solid_{solver}_")


def assembly_time(problem: SolidFingerProblem, repeats: int = 3) -> float:
    """One residual + one Jacobian assembly at the current state (best of ``repeats``)."""
    nl = problem.problem
    x = compat.vector_of(nl.w).copy()
    best = np.inf
    for _ in range(repeats):
        started = time.perf_counter()
        nl.residual(None, x, nl.b)
        nl.jacobian(None, x, nl.A, nl.A)
        best = min(best, time.perf_counter() - started)
    x.destroy()
    return best


def probe_step(finger, solver: str) -> dict:
    """One load step to PROBE_TENSION from the straight finger: time per Newton iteration."""
    problem = build(finger, solver, PROBE_TENSION)
    problem.comm.barrier()
    started = time.perf_counter()
    steps = run_load_stepping(problem.solver, problem.set_load_factor, LoadStepping(steps=1),
                              progress=False)
    seconds = time.perf_counter() - started
    newton = sum(s.iterations for s in steps)
    krylov = sum(s.linear_iterations for s in steps)
    result = {"solver": solver, "dofs": dofs_of(problem), "seconds": seconds,
              "load_steps": len(steps), "newton_iterations": newton,
              "krylov_iterations": krylov, "seconds_per_iteration": seconds / newton,
              "krylov_per_newton": krylov / newton, "assembly_s": assembly_time(problem),
              "tip_displacement": problem.tip_displacement().tolist(),
              "tip_rotation": problem.tip_rotation()["angle"]}
    problem.snes_solver.destroy()
    return result


def mesh(size: float, comm=MPI.COMM_WORLD, measure: dict | None = None):
    """The finger mesh and its wall time; ``measure`` (if given) gets the meshing's CPU
    seconds, RSS before and peak RSS during it of each rank (gmsh runs on rank 0)."""
    reset_peak_rss()
    rss, cpu = rss_gib(), time.process_time()
    started = time.perf_counter()
    finger = create_finger_mesh(GEOMETRY, MeshSizes(size), comm)
    seconds = time.perf_counter() - started
    if measure is not None:
        measure.update({"meshing_cpu_s_per_rank": comm.allgather(time.process_time() - cpu),
                        "meshing_rss_before_gib": comm.allgather(rss),
                        "meshing_peak_rss_gib": comm.allgather(rss_gib("VmHWM"))})
    return finger, seconds


# --- a. cost per Newton iteration -------------------------------------------------------------
def newton_scaling(sizes, mumps_cap: float) -> dict:
    runs = []
    mumps = []  # (dofs, seconds per iteration) so far, to predict the next
    for size in sizes:
        finger, meshing = mesh(size)
        dofs = None
        for solver in ("gamg", "gamg-gmres", "mumps"):
            entry = {"size": size, "meshing_s": meshing}
            if solver == "gamg-gmres" and dofs > GMRES_MAX_DOFS:
                runs.append(entry | {"solver": solver, "skipped": True})
                continue
            if solver == "mumps" and len(mumps) >= 2:
                dofs_guess = dofs
                slope = fit_exponent(*zip(*mumps[-2:], strict=True))
                predicted = mumps[-1][1] * (dofs_guess / mumps[-1][0]) ** slope
                if predicted > mumps_cap:
                    print(f"  size {size:g}: MUMPS predicted {predicted:.0f} s per iteration "
                          "> cap, skipped", flush=True)
                    runs.append(entry | {"solver": solver, "skipped": True,
                                         "predicted_seconds_per_iteration": predicted})
                    continue
            result = probe_step(finger, solver)
            dofs = result["dofs"]
            if solver == "mumps":
                mumps.append((result["dofs"], result["seconds_per_iteration"]))
            runs.append(entry | result)
            print(f"  size {size:g} m, {result['dofs']} DOFs, {solver}: "
                  f"{result['newton_iterations']} Newton its, {result['krylov_per_newton']:.1f} "
                  f"Krylov its / Newton, {result['seconds_per_iteration']:.3g} s / it (assembly "
                  f"{result['assembly_s']:.3g} s)", flush=True)
    exponents = {}
    for solver in SOLVERS:
        done = [r for r in runs if r["solver"] == solver and not r.get("skipped")]
        if len(done) >= 2:
            dofs = [r["dofs"] for r in done]
            exponents[solver] = {
                "time": fit_exponent(dofs, [r["seconds_per_iteration"] for r in done]),
                "time_from_15k": (fit_exponent(*zip(*[(r["dofs"], r["seconds_per_iteration"])
                                                      for r in done if r["dofs"] >= 15000],
                                                    strict=True))
                                  if sum(r["dofs"] >= 15000 for r in done) >= 2 else None),
                "assembly": fit_exponent(dofs, [r["assembly_s"] for r in done]),
                "krylov_per_newton": fit_exponent(dofs, [max(r["krylov_per_newton"], 1e-9)
                                                         for r in done]),
            }
    return {"runs": runs, "exponents": exponents}


def print_scaling(scaling: dict) -> None:
    by_size = {}
    for r in scaling["runs"]:
        by_size.setdefault(r["size"], {})[r["solver"]] = r
    rows = []
    for size, solvers in by_size.items():
        dofs = next((r["dofs"] for r in solvers.values() if "dofs" in r), "-")
        row = [f"{size:g}", dofs]
        for solver in SOLVERS:
            r = solvers.get(solver, {})
            if r.get("skipped") or not r:
                row += ["-", "-"] if solver == "mumps" else ["-", "-", "-"]
                continue
            row.append(r["seconds_per_iteration"])
            if solver != "mumps":
                row.append(f"{r['krylov_per_newton']:.1f}")
            row.append(r["newton_iterations"] if solver == "mumps" else r["assembly_s"])
        rows.append(row)
    print(table(["size m", "DOFs", "MUMPS s/it", "Newton its", "GAMG-CG s/it", "Krylov/Newton",
                 "assembly s", "GAMG-GMRES s/it", "Krylov/Newton", "assembly s"], rows))
    for solver, e in scaling["exponents"].items():
        text = f"exponent {solver}: time/it {e['time']:.2f}"
        if e["time_from_15k"] is not None:
            text += f" ({e['time_from_15k']:.2f} from 15k DOFs)"
        print(text + f", assembly {e['assembly']:.2f}, Krylov its/Newton "
              f"{e['krylov_per_newton']:.2f}")


# --- b. full sweep ----------------------------------------------------------------------------
def full_sweep(size: float, solver: str = "gamg") -> dict:
    finger, meshing = mesh(size)
    problem = build(finger, solver, MAX_TENSION)
    records = []

    def on_step(step):
        records.append({"tension": problem.tensions()[0], "newton": step.iterations,
                        "krylov": step.linear_iterations, "seconds": step.wall_time_s,
                        "tip_rotation": problem.tip_rotation()["angle"]})

    started = time.perf_counter()
    run_load_stepping(problem.solver, problem.set_load_factor, LoadStepping(steps=LEVELS),
                      on_converged=on_step, progress=False)
    seconds = time.perf_counter() - started
    newton = sum(r["newton"] for r in records)
    krylov = sum(r["krylov"] for r in records)
    result = {"size": size, "dofs": dofs_of(problem), "solver": solver, "meshing_s": meshing,
              "seconds": seconds, "load_steps": len(records), "newton_iterations": newton,
              "krylov_iterations": krylov, "steps": records,
              "tip_displacement": problem.tip_displacement().tolist()}
    problem.snes_solver.destroy()
    return result


def print_sweep(sweep: dict) -> None:
    steps = sweep["steps"]
    print(f"b. full sweep, {sweep['dofs']} DOFs, {sweep['solver']}: {sweep['load_steps']} steps "
          f"to {steps[-1]['tension']:g} N in {sweep['seconds']:.1f} s "
          f"(wall of the steps, no post-processing); {sweep['newton_iterations']} Newton its "
          f"({sweep['newton_iterations'] / len(steps):.2f} per step), "
          f"{sweep['krylov_iterations']} Krylov its "
          f"({sweep['krylov_iterations'] / sweep['newton_iterations']:.1f} per Newton); tip "
          f"rotation {steps[-1]['tip_rotation']:.4f} rad")
    rows = [[f"{r['tension']:.2g}", r["newton"], r["krylov"], r["seconds"], r["tip_rotation"]]
            for r in steps]
    print(table(["tension N", "Newton its", "Krylov its", "s", "tip rotation rad"], rows))


# --- c. ranks ---------------------------------------------------------------------------------
def idle_barrier(comm) -> None:
    """A barrier that sleeps instead of spinning (leaves the core to the working rank)."""
    request = comm.Ibarrier()
    while not request.Test():
        time.sleep(0.01)


def ranks(sizes_solvers) -> dict:
    world = MPI.COMM_WORLD
    results = []
    for size, solver in sizes_solvers:
        serial = None
        if world.rank == 0:
            finger, _ = mesh(size, MPI.COMM_SELF)
            serial = probe_step(finger, solver)
            del finger
        idle_barrier(world)
        serial = world.bcast(serial, root=0)
        finger, _ = mesh(size, world)
        parallel = probe_step(finger, solver)
        difference = float(np.max(np.abs(np.subtract(serial["tip_displacement"],
                                                     parallel["tip_displacement"])))
                           / np.max(np.abs(parallel["tip_displacement"])))
        entry = {"size": size, "solver": solver, "dofs": parallel["dofs"], "serial": serial,
                 "parallel": parallel, "ranks": world.size,
                 "speed_up": serial["seconds"] / parallel["seconds"],
                 "speed_up_per_iteration": serial["seconds_per_iteration"]
                 / parallel["seconds_per_iteration"], "tip_relative_difference": difference}
        results.append(entry)
        if world.rank == 0:
            print(f"  {parallel['dofs']} DOFs, {solver}: 1 rank {serial['seconds']:.2f} s "
                  f"({serial['newton_iterations']} Newton, {serial['krylov_iterations']} Krylov "
                  f"its), {world.size} ranks {parallel['seconds']:.2f} s "
                  f"({parallel['newton_iterations']} Newton, {parallel['krylov_iterations']} "
                  f"Krylov its): speed-up {entry['speed_up']:.2f}, tip differs by "
                  f"{difference:.1e} (relative)", flush=True)
    return {"runs": results}


# --- d-g. the u-p (Taylor-Hood) finger: MUMPS vs fieldsplit (issue 10) -----------------------
UP_TENSION = 5.0  # N, the sweep
UP_SWEEP_SIZE = 0.002  # m: ~92k DOFs
UP_STEPS = 10
# easy steps may grow to this many initial increments (`fe-beam solid`: `[solver]
# max_increment`; its default keeps the steps at one increment)
STEP_GROWTH = 4.0
UP_PROBE_TENSION = 1.0  # N, the one load step of the per-iteration timings
# mesh size [m] -> u-p DOFs: 0.006: 6.9k, 0.005: 9.8k, 0.004: 16.7k, 0.003: 36k, 0.002: 92k,
# 0.0015: 0.22M, 0.0013: 0.33M, 0.001: 0.73M
UP_SIZES = (0.005, 0.004, 0.003, 0.002, 0.0015, 0.0013)
UP_NUS = (0.3, 0.45, 0.49, 0.4999)


def peak_rss_gib(comm) -> dict:
    """Peak resident memory of this process and summed over the ranks [GiB] (getrusage)."""
    mine = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # kB on Linux
    return {"max_rank": comm.allreduce(mine, op=MPI.MAX), "sum": comm.allreduce(mine, op=MPI.SUM)}


def up_problem(finger, solver: str, tension: float, nu: float = 0.45,
               max_it: int | None = None) -> SolidFingerProblem:
    settings = SolverSettings(linear_solver=solver)
    if max_it is not None:
        settings = SolverSettings(linear_solver=solver, max_it=max_it)
    return SolidFingerProblem(
        finger, NeoHookean.from_young(MATERIAL.young_modulus, nu),
        tendons=[TendonLoad(tension=tension)], discretization=Discretization("mixed"),
        solver=settings, prefix=f"bench_up_{solver}_")


def rss_gib(field: str = "VmRSS") -> float:
    """Resident memory of this process [GiB] from /proc/self/status: ``VmRSS`` now, ``VmHWM``
    its peak since the last `reset_peak_rss`."""
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 2**20
    return float("nan")


def reset_peak_rss() -> None:
    """Reset VmHWM to the current RSS (Linux: write 5 to /proc/self/clear_refs)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass


# PETSc log events recorded by `up_probe` (wall seconds of rank 0 between the solve's start and
# end; nested calls are counted in each: the fieldsplit PCSetUp contains GAMG's)
PETSC_EVENTS = ("SNESFunctionEval", "SNESJacobianEval", "KSPSolve", "PCSetUp", "PCApply",
                "KSPGMRESOrthog", "MatMult", "MatPtAP", "MatMatMult", "PCGAMGGraph_AGG",
                "PCGAMGCoarse_AGG", "PCGAMGProl_AGG", "PCGAMGOptProl_AGG")


def petsc_event_times() -> dict:
    """{event: (seconds, count)} of the PETSC_EVENTS so far (PETSc.Log.begin() must be on)."""
    out = {}
    for name in PETSC_EVENTS:
        try:
            info = PETSc.Log.Event(name).getPerfInfo()
        except PETSc.Error:  # logging is off
            return {}
        out[name] = (info["time"], info["count"])
    return out


def up_probe(finger, solver: str, nu: float = 0.45, newton_cap: int | None = None) -> dict:
    """One load step to UP_PROBE_TENSION from the straight finger (set-up not timed), or only
    its first ``newton_cap`` Newton iterations: seconds per Newton iteration (the first
    includes the solver set-up: MUMPS analysis, GAMG hierarchy), Krylov its per Newton.
    Also: CPU seconds of each rank (process_time), the wall time of each Newton iteration
    (SNES monitor; entry 0 = the first residual), set-up time and memory."""
    comm = finger.mesh.comm
    comm.barrier()
    reset_peak_rss()
    setup_started, rss_before = time.perf_counter(), rss_gib()
    problem = up_problem(finger, solver, UP_PROBE_TENSION, nu, max_it=newton_cap)
    setup_s = comm.allreduce(time.perf_counter() - setup_started, op=MPI.MAX)
    snes = problem.snes_solver
    stamps = []
    snes.snes.setMonitor(lambda _snes, it, norm: stamps.append(time.perf_counter()))
    problem.set_load_factor(1.0)
    problem.comm.barrier()
    events = petsc_event_times()
    started, cpu = time.perf_counter(), time.process_time()
    converged = True
    try:
        snes.solve()
    except SolveFailed:
        converged = False
    seconds = time.perf_counter() - started
    cpu = problem.comm.allgather(time.process_time() - cpu)
    events = {name: {"seconds": t - events[name][0], "count": c - events[name][1]}
              for name, (t, c) in petsc_event_times().items() if name in events}
    newton = max(snes.snes.getIterationNumber(), 1)
    krylov = snes.snes.getLinearSolveIterations()
    iteration_s = np.diff([started] + stamps).tolist()
    if not converged and newton_cap is None:
        raise RuntimeError(f"{solver}: the probe step did not converge")
    result = {"solver": solver, "resolved": problem.linear_solver, "nu": nu,
              "dofs": dofs_of(problem), "ranks": problem.comm.size, "seconds": seconds,
              "converged": converged, "newton_iterations": newton, "krylov_iterations": krylov,
              "seconds_per_iteration": seconds / newton, "krylov_per_newton": krylov / newton,
              "cpu_s_per_rank": cpu, "cpu_s_per_iteration": max(cpu) / newton,
              "iteration_wall_s": iteration_s, "setup_s": setup_s, "petsc_events": events,
              "rss_before_problem_gib": comm.allgather(rss_before),
              "rss_after_solve_gib": comm.allgather(rss_gib()),
              "peak_rss_problem_gib": comm.allgather(rss_gib("VmHWM")),
              "peak_rss_gib": peak_rss_gib(problem.comm)}
    if len(iteration_s) > 2:  # Newton iterations after the first (no Jacobian mallocs, no
        # set-up of the preconditioner unless it is rebuilt)
        result["seconds_per_later_iteration"] = float(np.mean(iteration_s[2:]))
    if converged:
        result["tip_displacement"] = problem.tip_displacement().tolist()
        result["tip_rotation"] = problem.tip_rotation()["angle"]
    snes.destroy()
    return result


def up_scaling(sizes, mumps_cap: float, mumps_newton: int = 2) -> dict:
    """d. s / Newton iteration and Krylov its / Newton vs DOFs, fieldsplit (full step) and MUMPS
    (its first ``mumps_newton`` iterations, skipped where predicted above ``mumps_cap`` s, and
    always when ``mumps_cap`` <= 0)."""
    world = MPI.COMM_WORLD
    runs, mumps = [], []
    for size in sizes:
        meshing_measure = {}
        finger, meshing = mesh(size, world, meshing_measure)
        split = up_probe(finger, "fieldsplit")
        runs.append({"size": size, "meshing_s": meshing} | meshing_measure | split)
        line = (f"  size {size:g} m, {split['dofs']} DOFs (meshing {meshing:.1f} s, peak RSS "
                f"{max(meshing_measure['meshing_peak_rss_gib']):.2f} GiB): fieldsplit "
                f"{split['seconds_per_iteration']:.3g} s/it wall, "
                f"{split['cpu_s_per_iteration']:.3g} s/it CPU (max rank; CPU per rank "
                f"{' '.join(f'{c:.1f}' for c in split['cpu_s_per_rank'])} s), later its "
                f"{split.get('seconds_per_later_iteration', float('nan')):.3g} s wall, "
                f"first {(split['iteration_wall_s'] + [0, 0])[1]:.3g} s; "
                f"set-up {split['setup_s']:.3g} s; {split['newton_iterations']} "
                f"Newton, {split['krylov_per_newton']:.1f}"
                f" Krylov/Newton, peak RSS per rank "
                f"{' '.join(f'{m:.2f}' for m in split['peak_rss_problem_gib'])} GiB)")
        predicted = None
        if mumps_cap <= 0:
            predicted = float("inf")
        elif len(mumps) >= 2:
            slope = fit_exponent(*zip(*mumps[-2:], strict=True))
            predicted = mumps[-1][1] * (split["dofs"] / mumps[-1][0]) ** slope
        if predicted is not None and predicted > mumps_cap:
            runs.append({"size": size, "solver": "mumps", "skipped": True,
                         "predicted_seconds_per_iteration": predicted
                         if np.isfinite(predicted) else None})
            line += f"; MUMPS predicted {predicted:.0f} s/it, skipped"
        else:
            direct = up_probe(finger, "mumps", newton_cap=mumps_newton)
            runs.append({"size": size, "meshing_s": meshing} | direct)
            mumps.append((direct["dofs"], direct["seconds_per_iteration"]))
            line += (f"; MUMPS {direct['seconds_per_iteration']:.3g} s/it (first "
                     f"{direct['newton_iterations']} its), ratio "
                     f"{direct['seconds_per_iteration'] / split['seconds_per_iteration']:.2f}")
        if world.rank == 0:
            print(line, flush=True)
        del finger
    exponents = {}
    for solver in ("fieldsplit", "mumps"):
        done = [r for r in runs if r["solver"] == solver and not r.get("skipped")]
        if len(done) >= 2:
            dofs = [r["dofs"] for r in done]
            exponents[solver] = {
                "time": fit_exponent(dofs, [r["seconds_per_iteration"] for r in done]),
                "cpu": fit_exponent(dofs, [r["cpu_s_per_iteration"] for r in done]),
                "krylov_per_newton": fit_exponent(dofs, [max(r["krylov_per_newton"], 1e-9)
                                                         for r in done]),
                "peak_rss_max_rank": fit_exponent(dofs, [max(r["peak_rss_problem_gib"])
                                                         for r in done])}
            later = [r for r in done if "seconds_per_later_iteration" in r]
            if len(later) >= 2:
                exponents[solver]["later_iterations"] = fit_exponent(
                    [r["dofs"] for r in later], [r["seconds_per_later_iteration"] for r in later])
    return {"ranks": world.size, "runs": runs, "exponents": exponents}


def up_nu(size: float, nus=UP_NUS) -> dict:
    """e. Krylov its per Newton iteration vs Poisson's ratio (fieldsplit, one probe step)."""
    finger, _ = mesh(size)
    runs = []
    for nu in nus:
        r = up_probe(finger, "fieldsplit", nu=nu)
        runs.append(r)
        if MPI.COMM_WORLD.rank == 0:
            print(f"  nu = {nu:g}: {r['newton_iterations']} Newton, "
                  f"{r['krylov_per_newton']:.1f} Krylov/Newton, "
                  f"{r['seconds_per_iteration']:.3g} s/it", flush=True)
    return {"size": size, "dofs": runs[0]["dofs"], "ranks": MPI.COMM_WORLD.size, "runs": runs}


def up_sweep(size: float, solver: str = "fieldsplit", newton_cap: int | None = None) -> dict:
    """f. The issue's sweep: tendon 0 -> 5 N, UP_STEPS initial steps that grow after easy
    steps (inexact Newton: 2 iterations more than `LoadStepping.easy_iterations`) up to
    STEP_GROWTH initial increments (`fe-beam solid`: ``[solver] max_increment``)."""
    finger, meshing = mesh(size)
    problem = up_problem(finger, solver, UP_TENSION)
    records = []

    def on_step(step):
        records.append({"tension": problem.tensions()[0], "newton": step.iterations,
                        "krylov": step.linear_iterations, "seconds": step.wall_time_s,
                        "tip_rotation": problem.tip_rotation()["angle"]})

    stepping = LoadStepping(steps=UP_STEPS, max_increment=min(1.0, STEP_GROWTH / UP_STEPS),
                            easy_iterations=LoadStepping.easy_iterations
                            + problem.extra_easy_iterations)
    problem.comm.barrier()
    started, cpu = time.perf_counter(), time.process_time()
    run_load_stepping(problem.solver, problem.set_load_factor, stepping, on_converged=on_step,
                      progress=False)
    seconds = time.perf_counter() - started
    cpu = problem.comm.allreduce(time.process_time() - cpu, op=MPI.MAX)
    newton = sum(r["newton"] for r in records)
    krylov = sum(r["krylov"] for r in records)
    result = {"size": size, "dofs": dofs_of(problem), "solver": solver,
              "resolved": problem.linear_solver, "ranks": problem.comm.size,
              "meshing_s": meshing, "seconds": seconds, "cpu_s_max_rank": cpu,
              "load_steps": len(records),
              "newton_iterations": newton, "krylov_iterations": krylov, "steps": records,
              "tip_displacement": problem.tip_displacement().tolist(),
              "peak_rss_gib": peak_rss_gib(problem.comm)}
    problem.snes_solver.destroy()
    return result


def up_main(args) -> int:
    world = MPI.COMM_WORLD
    root = world.rank == 0
    out = {"ranks": world.size}
    PETSc.Log.begin()  # the PETSc events of up_probe
    warm, _ = mesh(0.01, world)
    up_probe(warm, "fieldsplit")
    up_probe(warm, "mumps")
    if "sweep" in args.up:
        if root:
            print(f"f. u-p sweep to {UP_TENSION:g} N, mesh {args.up_sweep_size:g} m, "
                  f"{world.size} rank(s)", flush=True)
        sweep = up_sweep(args.up_sweep_size)
        out["sweep"] = sweep
        # MUMPS: its first Newton iterations on the same mesh, extrapolated to the sweep
        finger, _ = mesh(args.up_sweep_size)
        direct = up_probe(finger, "mumps", newton_cap=args.mumps_newton)
        del finger
        out["sweep_mumps_probe"] = direct
        out["sweep_mumps_extrapolated_s"] = (direct["seconds_per_iteration"]
                                             * sweep["newton_iterations"])
        if root:
            print_sweep(sweep | {"solver": "fieldsplit"})
            print(f"  MUMPS ({world.size} rank(s)): {direct['seconds_per_iteration']:.3g} s per "
                  f"Newton iteration (first {direct['newton_iterations']}), x "
                  f"{sweep['newton_iterations']} Newton its = "
                  f"{out['sweep_mumps_extrapolated_s']:.0f} s extrapolated; fieldsplit "
                  f"{sweep['seconds']:.1f} s; peak RSS {sweep['peak_rss_gib']['sum']:.2f} GiB",
                  flush=True)
    if "ranks" in args.up:
        # 1 vs world.size ranks, one probe step on the sweep mesh, in one run (ratios)
        size = args.up_sweep_size
        serial = None
        if root:
            finger, _ = mesh(size, MPI.COMM_SELF)
            serial = {s: up_probe(finger, s, newton_cap=None if s == "fieldsplit"
                                  else args.mumps_newton) for s in ("fieldsplit", "mumps")}
            del finger
        idle_barrier(world)
        serial = world.bcast(serial, root=0)
        finger, _ = mesh(size, world)
        parallel = {s: up_probe(finger, s, newton_cap=None if s == "fieldsplit"
                                else args.mumps_newton) for s in ("fieldsplit", "mumps")}
        out["ranks_probe"] = {"serial": serial, "parallel": parallel}
        if root:
            rows = [[s, serial[s]["dofs"], serial[s]["seconds_per_iteration"],
                     parallel[s]["seconds_per_iteration"], serial[s]["krylov_per_newton"],
                     parallel[s]["krylov_per_newton"]] for s in serial]
            print(table(["solver", "DOFs", "1 rank s/it", f"{world.size} ranks s/it",
                         "Krylov/Newton 1", f"Krylov/Newton {world.size}"], rows), flush=True)
    if "scaling" in args.up:
        if root:
            print(f"d. u-p cost per Newton iteration vs DOFs, {world.size} rank(s)", flush=True)
        out["scaling"] = up_scaling(args.up_sizes or UP_SIZES, args.mumps_cap, args.mumps_newton)
        if root:
            for solver, e in out["scaling"]["exponents"].items():
                print(f"  exponent {solver}: time/it {e['time']:.2f} wall, {e['cpu']:.2f} CPU, "
                      f"later its {e.get('later_iterations', float('nan')):.2f} wall, "
                      f"Krylov/Newton {e['krylov_per_newton']:.2f}, peak RSS "
                      f"{e['peak_rss_max_rank']:.2f}")
    if "nu" in args.up:
        if root:
            print(f"e. u-p Krylov its vs nu, mesh {args.up_nu_size:g} m", flush=True)
        out["nu"] = up_nu(args.up_nu_size)
    if root:
        path = write_results("solid_up_" + "_".join(args.up) + f"_{world.size}ranks"
                             + args.results_suffix, out)
        print(f"results: {path}")
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small meshes only (~1 min)")
    parser.add_argument("--ranks", action="store_true",
                        help="part c only: run under mpirun -n 2")
    parser.add_argument("--sizes", type=float, nargs="+", help="mesh sizes of part a [m]")
    parser.add_argument("--sweep-size", type=float, help="mesh size of part b [m]")
    parser.add_argument("--mumps-cap", type=float, default=15.0,
                        help="skip MUMPS where a Newton iteration is predicted to take longer")
    parser.add_argument("--up", nargs="+", choices=("sweep", "ranks", "scaling", "nu"),
                        help="u-p finger parts (issue 10): sweep = the 5 N sweep with fieldsplit "
                        "and MUMPS extrapolated, ranks = 1 vs all ranks, scaling = s/it and "
                        "Krylov its vs DOFs, nu = Krylov its vs nu")
    parser.add_argument("--up-sweep-size", type=float, default=UP_SWEEP_SIZE)
    parser.add_argument("--up-sizes", type=float, nargs="+", help="mesh sizes of --up scaling")
    parser.add_argument("--up-nu-size", type=float, default=0.003)
    parser.add_argument("--results-suffix", default="",
                        help="appended to the results file name")
    parser.add_argument("--mumps-newton", type=int, default=2,
                        help="--up: MUMPS Newton iterations timed (then extrapolated)")
    args = parser.parse_args(argv)
    if args.up:
        return up_main(args)
    world = MPI.COMM_WORLD
    root = world.rank == 0
    # JIT (FFCx forms are cached on disk), PETSc and gmsh warm-up on a tiny mesh
    warm, _ = mesh(0.01, world)
    for solver in SOLVERS:
        probe_step(warm, solver)
    if args.ranks:
        if world.size < 2 and root:
            print("warning: --ranks is meant for mpirun -n 2; the comparison is 1 vs 1 rank",
                  file=sys.stderr)
        cases = ([(0.004, "mumps"), (0.004, "gamg")] if args.quick else
                 [(0.003, "mumps"), (0.003, "gamg"), (SIZES[-1], "gamg")])
        if root:
            print(f"c. 1 vs {world.size} ranks: one load step to {PROBE_TENSION:g} N")
        result = ranks(cases)
        if root:
            rows = [[r["dofs"], r["solver"], r["serial"]["seconds"], r["parallel"]["seconds"],
                     f"{r['speed_up']:.2f}", r["serial"]["krylov_per_newton"],
                     r["parallel"]["krylov_per_newton"]] for r in result["runs"]]
            print(table(["DOFs", "solver", "1 rank s", f"{world.size} ranks s", "speed-up",
                         "Krylov/Newton 1", f"Krylov/Newton {world.size}"], rows))
            path = write_results("solid_ranks" + ("_quick" if args.quick else ""), result)
            print(f"results: {path}")
        return 0

    sizes = args.sizes or (QUICK_SIZES if args.quick else SIZES)
    sweep_size = args.sweep_size or (QUICK_SIZES[-1] if args.quick else SIZES[-1])
    print(f"a. cost per Newton iteration: one load step to {PROBE_TENSION:g} N "
          f"(Neo-Hookean, E = {MATERIAL.young_modulus:g} Pa, P2, {world.size} rank(s))")
    scaling = newton_scaling(sizes, args.mumps_cap)
    if root:
        print_scaling(scaling)
    sweep = full_sweep(sweep_size)
    if root:
        print_sweep(sweep)
        path = write_results("solid" + ("_quick" if args.quick else ""),
                             {"ranks": world.size, "scaling": scaling, "sweep": sweep})
        print(f"results: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

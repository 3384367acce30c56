"""Dynamics benchmark (issue 3): large release of a cantilever, generalised-alpha vs FD + RK45.

The problem: a clamped-free square-section cantilever (L = 1 m, E = 10 MPa, nu = 0.3,
rho = 1000 kg/m^3, non-standard law, L/h = 20 ... 200) is deflected statically by a dead tip
load k = P L^2 / EI = 1.5 (tip rotation ~0.64 rad) and released at t = 0. The tip trajectory
(u, v) over two first-mode periods T1 (Euler-Bernoulli) is compared at 201 times (every T1 / 100)
with a converged reference: generalised-alpha, 32 degree-2 elements, 10240 steps (the difference
to 5120 steps is printed; `--cross-check` also compares it with a fine FD-RK45 run). Both methods
must stay within TOL = 1e-3 L of it at every sample time. The released beam swings in its first
bending mode, but modes 2 and 3 carry ~1e-2 L and ~1e-3 L of the tip motion: a trajectory
accurate to 1e-3 L needs them in phase over 2 T1 (79 and 220 rad of their phase).

* fe_beam: `BeamProblem` + static pre-state (`fe_beam.analyses.transient._static_prestate`, 5 load
steps)
  + `GeneralizedAlpha` (rho_inf = 0.9, fixed step, SNES rtol 1e-9), once with fe_beam's default
  linear solver (MUMPS) and once with PETSc's LU (fine here: no multiplier fields). The tip is
  recorded every step and interpolated (cubic spline) to the sample times.
* baseline: the paper's scheme, `fe_beam.baselines.fd_rk` (staggered central differences,
  lumped masses, `solve_static` with 5 load steps, then `simulate` = scipy RK45 with
  atol = rtol * 1e-3 L, as `fe-beam dynamic` with scheme = "fd-rk45" does).

The settings of each method (``CHOSEN``) are the cheapest found by ``--search`` whose trajectory
error is below TOL and, as a guard against lucky cancellations of space and time errors, stays
below TOL with twice the elements / grid intervals (and, for generalised-alpha, with half the
time step). Without ``--search`` the stored settings are checked against the reference and
timed.

An explicit RK45 is limited by the stability of the stiffest mode (the shear-rotation mode of a
section, omega ~ sqrt(12 G / rho) / h), so its cost grows like (L/h)^2 over a fixed number of
bending periods. An FD run predicted (from a probe over 2 % of the horizon) to take longer than
``--fd-cap`` seconds is not run: its time is extrapolated from a longer probe and its accuracy
is not checked.

Times are wall times after JIT (a warm-up first): fe_beam ``repeats`` times with each linear
solver, the FD run, fe_beam ``repeats`` times again; the ratio is FD / median(fe_beam), all in
one process. Results: results/benchmarks/dynamics[_search][_lh<L/h list>][_cap<s>].json.

    python benchmarks/bench_dynamics.py [--slenderness 20 50 100 200] [--repeats 3]
                                        [--fd-cap 300] [--search] [--cross-check]
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np
from common import fit_exponent, forget_petsc_options, stats, table, write_results
from scipy.interpolate import CubicSpline

from fe_beam import (
    BeamModel,
    BeamProblem,
    Discretisation,
    Loads,
    LoadStepping,
    Material,
    ModelOptions,
    Section,
    SolverSettings,
    Supports,
)
from fe_beam.analyses.transient import _static_prestate
from fe_beam.baselines import fd_rk
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers.dynamics import GeneralizedAlpha, TimeSettings

LENGTH, E, NU, RHO = 1.0, 1.0e7, 0.3, 1000.0
K_LOAD = 1.5
PERIODS = 2.0
SAMPLES = 200  # intervals over PERIODS * T1 at which the tip is compared (every T1 / 100)
TOL = 1e-3  # tip trajectory error / L
STATIC_STEPS = 5
RHO_INF = 0.9
REFERENCE = {"elements": 32, "steps": 10240}  # steps over PERIODS * T1
CHECK = {"elements": 32, "steps": 5120}  # half the step: shows how converged the reference is
CROSS_CHECK = {"slenderness": 20, "intervals": 160, "rtol": 1e-8}  # FD, independent

# Found by `--search` on 2026-11-22 (see benchmarks/README.md): L/h -> generalised-alpha
# (degree-2 elements, time steps over the horizon) and FD-RK45 (grid intervals, rtol).
CHOSEN = {
    20: {"ga": (12, 1920), "fd": (40, 1e-3)},
    50: {"ga": (12, 1920), "fd": (60, 1e-4)},
    100: {"ga": (12, 1920), "fd": (60, 1e-4)},
    200: {"ga": (12, 1920), "fd": (60, 1e-4)},  # FD not searched (over the cap): as L/h = 100
}
GA_ELEMENTS = (4, 6, 8, 12, 16, 24)
GA_STEPS = (80, 120, 160, 200, 240, 320, 400, 480, 560, 640, 800, 960, 1120, 1280, 1600, 1920,
            2240, 2560, 3200)
FD_INTERVALS = (20, 40, 60, 80, 120, 160)
FD_RTOLS = (1e-3, 1e-4, 1e-5, 1e-6)


# --- the problem --------------------------------------------------------------------------------
def section_height(slenderness: float) -> float:
    return LENGTH / slenderness


def bending_stiffness(slenderness: float) -> float:
    return E * section_height(slenderness) ** 4 / 12


def first_period(slenderness: float) -> float:
    """Euler-Bernoulli first-mode period of the cantilever."""
    h = section_height(slenderness)
    omega = 1.8751040687119611**2 * math.sqrt(bending_stiffness(slenderness)
                                              / (RHO * h * h * LENGTH**4))
    return 2 * math.pi / omega


def horizon(slenderness: float) -> float:
    return PERIODS * first_period(slenderness)


def sample_times(slenderness: float) -> np.ndarray:
    return np.linspace(0.0, horizon(slenderness), SAMPLES + 1)


def tip_load(slenderness: float) -> float:
    return -K_LOAD * bending_stiffness(slenderness) / LENGTH**2


def beam_model(slenderness: float, elements: int) -> BeamModel:
    h = section_height(slenderness)
    return BeamModel(
        LENGTH, Section("rectangle", {"b": h, "h": h}), Material(E, nu=NU, rho=RHO),
        ModelOptions("nonstandard"), Discretisation(elements, 2), Supports("clamped", "free"),
        Loads(tip_force=(0.0, tip_load(slenderness))),
    )


def fd_parameters(slenderness: float, intervals: int, released: bool) -> fd_rk.FDBeamParameters:
    """The same beam for the FD scheme (shear modulus E / 2(1 + nu), E I4 = E b h^5 / 80)."""
    h = section_height(slenderness)
    area = h * h
    return fd_rk.FDBeamParameters(
        L=LENGTH, n_intervals=intervals, EA=E * area, GA=E / (2 * (1 + NU)) * area,
        EI=bending_stiffness(slenderness), EI3=0.0, EI4=E * h * h**5 / 80, rhoA=RHO * area,
        rhoI=RHO * h**4 / 12, law="nonstandard", Py=tip_load(slenderness),
        load_time=_zero if released else fd_rk.constant_one,
    )


def _zero(t: float) -> float:
    return 0.0


def trajectory_error(tip: np.ndarray, reference: np.ndarray) -> float:
    """max over the sample times of |tip position - reference| / L."""
    return float(np.max(np.hypot(*(tip - reference).T)) / LENGTH)


# --- the two methods -------------------------------------------------------------------------
def run_ga(slenderness: float, elements: int, steps: int, rho_inf: float = RHO_INF,
           linear_solver: str = "mumps") -> dict:
    """Build + static pre-state + generalised-alpha release; tip (u, v) at the sample times."""
    t_end = horizon(slenderness)
    tips = []
    started = time.perf_counter()
    model = beam_model(slenderness, elements)
    problem = BeamProblem(model)
    solver = SolverSettings(linear_solver=linear_solver)
    _static_prestate(problem, StaticConfig(model, solver, LoadStepping(steps=STATIC_STEPS)),
                     progress=False)
    integrator = GeneralizedAlpha(
        problem, TimeSettings(t_end=t_end, dt=t_end / steps, rho_inf=rho_inf, output_every=1),
        load_function=_zero, solver_settings=solver)
    integrator.initialise()
    built = time.perf_counter()

    def record(t, step):
        tip = problem.end_values("xL")
        tips.append((t, tip["u"], tip["v"]))

    info = integrator.run(record, progress=False)
    done = time.perf_counter()
    integrator.solver.destroy()
    forget_petsc_options()  # leaked options would switch solvers and overflow PETSc's table
    # Every step is recorded; a step cut back after a Newton failure shifts the time grid, so
    # the tip is interpolated to the sample times (cubic spline: ~1e-6 L at dt = T1 / 40).
    tips = np.array(tips)
    spline = CubicSpline(tips[:, 0], tips[:, 1:], axis=0)
    dofs = problem.space.dofmap.index_map.size_global * problem.space.dofmap.index_map_bs
    return {"tip": spline(sample_times(slenderness)), "wall_s": done - started,
            "integrate_s": done - built, "steps": info["steps"],
            "rejected_steps": info["rejected_steps"],
            "newton_iterations": info["newton_iterations"], "dofs": dofs}


def run_fd(slenderness: float, intervals: int, rtol: float, fraction: float = 1.0) -> dict:
    """FD static solve + RK45 release; with ``fraction`` < 1 only that part of the horizon (a
    probe to predict the time of the full run)."""
    started = time.perf_counter()
    q0 = fd_rk.solve_static(fd_parameters(slenderness, intervals, False), 1.0, STATIC_STEPS)
    static = time.perf_counter() - started
    times = sample_times(slenderness)
    t_end = times[-1] * fraction
    solution = fd_rk.simulate(fd_parameters(slenderness, intervals, True), q0, None, t_end,
                              times if fraction == 1.0 else np.array([0.0, t_end]),
                              method="RK45", rtol=rtol, atol=rtol * 1e-3 * LENGTH)
    done = time.perf_counter()
    if not solution.success:
        raise RuntimeError(f"FD-RK45 failed: {solution.message}")
    return {"tip": np.column_stack([solution.tip_u, solution.tip_v]), "wall_s": done - started,
            "integrate_s": solution.wall_time, "static_s": static, "rhs_evaluations":
            solution.nfev, "dofs": int(fd_rk.free_dofs(fd_parameters(slenderness, intervals,
                                                                    True)).sum())}


def predict_fd(slenderness: float, intervals: int, rtol: float, fraction: float) -> dict:
    """Run ``fraction`` of the horizon and extrapolate (the step size of an explicit scheme at
    its stability limit is uniform in time, so the cost is linear in the simulated time)."""
    probe = run_fd(slenderness, intervals, rtol, fraction)
    predicted = probe["static_s"] + probe["integrate_s"] / fraction
    return {"fraction": fraction, "probe_s": probe["wall_s"], "predicted_s": predicted,
            "static_s": probe["static_s"],
            "rhs_evaluations_predicted": probe["rhs_evaluations"] / fraction}


# --- reference and search -------------------------------------------------------------------
def reference(slenderness: float) -> dict:
    ref = run_ga(slenderness, REFERENCE["elements"], REFERENCE["steps"])
    check = run_ga(slenderness, CHECK["elements"], CHECK["steps"])
    ref["check_error"] = trajectory_error(check["tip"], ref["tip"])
    return ref


def search_ga(slenderness: float, ref: np.ndarray, verbose: bool = True) -> tuple[tuple, list]:
    """Per element count the fewest steps (from GA_STEPS) reaching TOL, accepted only if twice
    the elements and twice the steps also do; the cheapest by measured wall time. An element
    count is abandoned once its runs take longer than the best candidate so far."""
    log, candidates = [], []
    best = math.inf
    for elements in sorted(GA_ELEMENTS, reverse=True):  # a first candidate prunes the rest
        for steps in GA_STEPS:
            run = run_ga(slenderness, elements, steps)
            error = trajectory_error(run["tip"], ref)
            entry = {"elements": elements, "steps": steps, "error": error,
                     "wall_s": run["wall_s"]}
            log.append(entry)
            if run["wall_s"] > 1.5 * best:
                break
            if not error < TOL:
                continue
            finer_space = trajectory_error(run_ga(slenderness, 2 * elements, steps)["tip"], ref)
            finer_time = trajectory_error(run_ga(slenderness, elements, 2 * steps)["tip"], ref)
            entry |= {"error_2x_elements": finer_space, "error_2x_steps": finer_time}
            if finer_space < TOL and finer_time < TOL:
                wall = min([run["wall_s"]] + [run_ga(slenderness, elements, steps)["wall_s"]
                                               for _ in range(2)])
                entry["wall_s"] = wall
                candidates.append((wall, (elements, steps)))
                best = min(best, wall)
                if verbose:
                    print(f"  GA L/h {slenderness:g}: {elements} elements, {steps} steps: error "
                          f"{error:.2e} (2x elements {finer_space:.2e}, 2x steps "
                          f"{finer_time:.2e}), {wall:.3f} s", flush=True)
                break
    if not candidates:
        raise RuntimeError(f"no generalised-alpha setting reached {TOL:g} L")
    candidates.sort()
    return candidates[0][1], log


def search_fd(slenderness: float, ref: np.ndarray, cap: float,
              verbose: bool = True) -> tuple[tuple | None, list]:
    """Smallest grid, then loosest rtol, reaching TOL (guarded by twice the grid intervals).

    The cost of RK45 here is set by its stability limit (the shear-rotation mode), nearly the
    same for every grid below ~L/h intervals and every loose rtol, so the first grid and rtol
    that pass are the cheapest; grids are tried in increasing order, rtols from loose to tight
    until the error stops improving (then the space error dominates)."""
    log = []
    for intervals in FD_INTERVALS:
        previous = math.inf
        for rtol in FD_RTOLS:
            guess = predict_fd(slenderness, intervals, rtol, 0.02)
            if guess["predicted_s"] > cap:
                log.append({"intervals": intervals, "rtol": rtol, "skipped": True, **guess})
                if verbose:
                    print(f"  FD L/h {slenderness:g}: {intervals} intervals, rtol {rtol:g}: "
                          f"predicted {guess['predicted_s']:.0f} s > cap, not run", flush=True)
                return None, log
            run = run_fd(slenderness, intervals, rtol)
            error = trajectory_error(run["tip"], ref)
            entry = {"intervals": intervals, "rtol": rtol, "error": error,
                     "wall_s": run["wall_s"], "rhs_evaluations": run["rhs_evaluations"]}
            if verbose:
                print(f"  FD L/h {slenderness:g}: {intervals} intervals, rtol {rtol:g}: error "
                      f"{error:.2e}, {run['wall_s']:.1f} s", flush=True)
            if error < TOL:
                finer = run_fd(slenderness, 2 * intervals, rtol)
                entry["error_2x_intervals"] = trajectory_error(finer["tip"], ref)
                log.append(entry)
                if entry["error_2x_intervals"] < TOL:
                    return (intervals, rtol), log
                break
            log.append(entry)
            if error > 0.9 * previous:
                break
            previous = error
    return None, log


# --- timing ---------------------------------------------------------------------------------
def _ga_summary(runs: list[dict], ref: np.ndarray) -> dict:
    wall = [r["wall_s"] for r in runs]
    integrate = [r["integrate_s"] for r in runs]
    return {"steps": runs[0]["steps"], "rejected_steps": runs[0]["rejected_steps"],
            "dofs": runs[0]["dofs"], "newton_iterations": runs[0]["newton_iterations"],
            "error": trajectory_error(runs[0]["tip"], ref), "wall": stats(wall),
            "integrate": stats(integrate)}


def compare(slenderness: float, ga: tuple, fd: tuple, ref: np.ndarray, repeats: int,
            cap: float) -> dict:
    """fe_beam ``repeats`` times (MUMPS, its default, and PETSc's LU), FD once (or predicted from
    a probe), fe_beam ``repeats`` times again."""
    elements, steps = ga
    intervals, rtol = fd
    solvers = ("mumps", "lu")
    runs = {s: [run_ga(slenderness, elements, steps, linear_solver=s) for _ in range(repeats)]
            for s in solvers}
    guess = predict_fd(slenderness, intervals, rtol, 0.02)
    fd_result = {"intervals": intervals, "rtol": rtol, "probe": guess}
    if guess["predicted_s"] <= cap:
        run = run_fd(slenderness, intervals, rtol)
        fd_result |= {"measured": True, "wall_s": run["wall_s"],
                      "integrate_s": run["integrate_s"], "rhs_evaluations":
                      run["rhs_evaluations"], "error": trajectory_error(run["tip"], ref),
                      "dofs": run["dofs"]}
    else:  # a longer probe (about cap / 12 s) for a better extrapolation
        fraction = min(0.25, 0.02 * cap / guess["predicted_s"] * 4)
        guess = predict_fd(slenderness, intervals, rtol, fraction)
        fd_result |= {"measured": False, "probe": guess, "wall_s": guess["predicted_s"],
                      "integrate_s": guess["predicted_s"] - guess["static_s"], "error": None,
                      "rhs_evaluations": guess["rhs_evaluations_predicted"], "dofs": None}
    for s in solvers:
        runs[s] += [run_ga(slenderness, elements, steps, linear_solver=s) for _ in range(repeats)]
    result = {"slenderness": slenderness, "period_s": first_period(slenderness),
              "fd_rk45": fd_result}
    for s in solvers:
        g = _ga_summary(runs[s], ref) | {"elements": elements, "linear_solver": s}
        result["generalized_alpha" + ("" if s == "mumps" else f"_{s}")] = g
        suffix = "" if s == "mumps" else f"_{s}"
        result["ratio" + suffix] = fd_result["wall_s"] / g["wall"]["median_s"]
        result["ratio_integrate" + suffix] = (fd_result["integrate_s"]
                                              / g["integrate"]["median_s"])
    return result


def cross_check(ref: dict) -> dict:
    """The reference against the independent FD scheme on a fine grid with a tight rtol."""
    c = CROSS_CHECK
    run = run_fd(c["slenderness"], c["intervals"], c["rtol"])
    error = trajectory_error(run["tip"], ref["tip"])
    print(f"  cross-check: FD-RK45, {c['intervals']} intervals, rtol {c['rtol']:g}, differs from "
          f"the reference by {error:.1e} L ({run['wall_s']:.0f} s)", flush=True)
    return c | {"difference": error, "wall_s": run["wall_s"]}


def report(result: dict) -> None:
    f = result["fd_rk45"]
    for key, label in (("generalized_alpha", "MUMPS"), ("generalized_alpha_lu", "PETSc LU")):
        g = result[key]
        print(f"  generalised-alpha ({label}): {g['elements']} elements ({g['dofs']} dofs), "
              f"{g['steps']} steps ({g['rejected_steps']} cut), {g['newton_iterations']} Newton "
              f"its, error {g['error']:.2e} L, {g['wall']['median_s']:.3f} s (integration "
              f"{g['integrate']['median_s']:.3f} s)")
    fd_error = f"{f['error']:.2e} L" if f["error"] is not None else "not checked"
    print(f"  FD-RK45: {f['intervals']} intervals, rtol {f['rtol']:g}, "
          f"{f['rhs_evaluations']:.3g} rhs evaluations, error {fd_error}, {f['wall_s']:.1f} s"
          + ("" if f["measured"] else f" (extrapolated from {f['probe']['fraction']:.0%} of the "
             "horizon)"), flush=True)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slenderness", type=float, nargs="+", default=[20, 50, 100, 200])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--fd-cap", type=float, default=300.0,
                        help="FD runs predicted to take longer than this [s] are extrapolated")
    parser.add_argument("--search", action="store_true",
                        help="search the cheapest settings of both methods first (long)")
    parser.add_argument("--cross-check", action="store_true",
                        help=f"compare the reference at L/h = {CROSS_CHECK['slenderness']} with "
                        "a fine FD-RK45 run (~4 min)")
    args = parser.parse_args(argv)
    print(f"release from k = {K_LOAD:g}, {PERIODS:g} first-mode periods, tip compared at "
          f"{SAMPLES + 1} times, tolerance {TOL:g} L")
    run_ga(20, 2, 10)  # JIT (FFCx forms cached on disk)
    results, searches, checks = [], {}, None
    for slenderness in args.slenderness:
        key = int(slenderness) if slenderness == int(slenderness) else slenderness
        ref = reference(slenderness)
        print(f"\nL/h = {slenderness:g}: T1 = {first_period(slenderness):.4g} s; reference "
              f"{REFERENCE['elements']} elements, {ref['steps']} steps ({ref['wall_s']:.1f} s); "
              f"with {CHECK['steps']} steps it differs by {ref['check_error']:.1e} L", flush=True)
        if args.cross_check and slenderness == CROSS_CHECK["slenderness"]:
            checks = cross_check(ref)
        chosen = CHOSEN.get(key, CHOSEN[min(CHOSEN, key=lambda s: abs(s - slenderness))])
        ga, fd = chosen["ga"], chosen["fd"]
        if args.search:
            ga, ga_log = search_ga(slenderness, ref["tip"])
            found, fd_log = search_fd(slenderness, ref["tip"], args.fd_cap)
            fd = found or fd
            searches[key] = {"ga": ga, "fd": found, "ga_log": ga_log, "fd_log": fd_log}
            print(f"  chosen: GA {ga}, FD {found or f'{fd} (not searched: over the cap)'}",
                  flush=True)
        result = compare(slenderness, ga, fd, ref["tip"], args.repeats, args.fd_cap)
        result["reference_check_error"] = ref["check_error"]
        results.append(result)
        report(result)
    rows = []
    for r in results:
        g, f = r["generalized_alpha"], r["fd_rk45"]
        rows.append([f"{r['slenderness']:g}", f"{g['elements']} / {g['steps']}", g["error"],
                     g["wall"]["median_s"], r["generalized_alpha_lu"]["wall"]["median_s"],
                     f"{f['intervals']} / {f['rtol']:g}",
                     f["error"] if f["error"] is not None else "-",
                     f"{f['wall_s']:.3g}{'' if f['measured'] else ' (extrap.)'}",
                     f"{r['ratio']:.0f}x", f"{r['ratio_integrate']:.0f}x",
                     f"{r['ratio_lu']:.0f}x"])
    print("\n" + table(["L/h", "GA el / steps", "GA err / L", "GA s", "GA-LU s", "FD N / rtol",
                        "FD err / L", "FD s", "FD / GA", "integration", "FD / GA-LU"], rows))
    if len(results) > 1:
        slender = [r["slenderness"] for r in results]
        for label, values in (
                ("FD time", [r["fd_rk45"]["wall_s"] for r in results]),
                ("GA time", [r["generalized_alpha"]["wall"]["median_s"] for r in results]),
                ("ratio", [r["ratio"] for r in results])):
            print(f"exponent of {label} vs L/h: {fit_exponent(slender, values):.2f}")
    name = "dynamics" + ("_search" if args.search else "")
    if args.slenderness != parser.get_default("slenderness"):
        name += "_lh" + "-".join(f"{s:g}" for s in args.slenderness)
    if args.fd_cap != parser.get_default("fd_cap"):
        name += f"_cap{args.fd_cap:g}"
    path = write_results(name, {
        "problem": {"length": LENGTH, "E": E, "nu": NU, "rho": RHO, "k": K_LOAD,
                    "periods": PERIODS, "samples": SAMPLES, "tolerance": TOL,
                    "rho_inf": RHO_INF, "reference": REFERENCE, "check": CHECK},
        "cap_s": args.fd_cap, "cross_check": checks, "results": results, "search": searches})
    print(f"results: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""fe_beam vs PyElastica on the elastica cantilever (dead tip load, k = P L^2 / EI = 3).

Both must put the tip within a tolerance (``--tolerance``, default 1e-3 L) of the
elliptic-integral solution (`fe_beam.analytic.elastica_tip_load`):

* PyElastica: a Cosserat rod (circular, slender, stiff in shear and stretch) clamped with
  OneEndFixedBC, EndpointForces at the tip, brought to rest by damped dynamic relaxation
  (PositionVerlet + AnalyticalLinearDamper). Its settings (elements, slenderness L/r, G/E, time
  step, damping, ramp, final time) were chosen by ``--search``: the cheapest that reach the
  tolerance, accepted only if the same rod with twice the elements also does (so the accuracy is
  not a lucky cancellation of discretisation and extensibility errors). Below 1e-3 the search
  grid is scaled to the tolerance (see `search`); the settings found are stored in `CHOSEN`.
* fe_beam: Reissner law + inextensible-unshearable (the elastica exactly), degree 2, the fewest
  elements reaching the tolerance.

Wall times are measured after JIT (numba, FFCx), alternating the two codes in one run.

    python benchmarks/bench_pyelastica.py [--tolerance 1e-3] [--repeats 5]
                                          [--search [--budget S] [--max-run S]]

Writes results/benchmarks/pyelastica_tol<tol>.json (and, at the default tolerance, also
results/benchmarks/pyelastica.json).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import itertools
import math
import statistics
import sys
import time
from dataclasses import asdict, dataclass, replace

import numpy as np
from common import cantilever, static_config, stats, table, timed, tip_errors, write_results

from fe_beam import BeamProblem, LoadStepping, NonlinearProblem, SNESSolver, run_load_stepping
from fe_beam.analyses.static import solve_static
from fe_beam.analytic import elastica_tip_load

K = 3.0
DEFAULT_TOL = 1e-3
EXACT = elastica_tip_load(K)
FE_STEPS = 2

try:
    import elastica as ea
    from elastica.version import VERSION as ELASTICA_VERSION
except Exception as error:  # noqa: BLE001 - any import failure means "not available"
    ea, ELASTICA_VERSION, IMPORT_ERROR = None, None, f"{type(error).__name__}: {error}"
else:
    IMPORT_ERROR = None


@dataclass(frozen=True)
class RodSettings:
    """A PyElastica run, in units of the rod (L = 1) and of its first bending period T1.

    dt = cfl * min(dl, 2 r sqrt(E / 2G)) / c, c = sqrt(E / rho): the explicit stability limit is
    set by the stretch wave over an element or by the shear-rotation mode of a section. The rod
    starts ``clamp_offset`` elements behind the clamp so that the curvature lumped at the first
    Voronoi node acts from x = 0 (with the plain OneEndFixedBC set-up, offset 0, the first
    half-element stays rigid and the tip error is first order, about 0.67 L / n at k = 3).
    """

    elements: int
    slenderness: float  # L / r
    shear_ratio: float  # G / E
    cfl: float
    damping: float  # uniform damping constant / omega_1
    ramp: float  # ramp-up time of the tip load / T1
    final_time: float  # / T1
    clamp_offset: float = 0.5

    E = 1.0e6
    rho = 1.0e3
    length = 1.0

    @property
    def radius(self) -> float:
        return self.length / self.slenderness

    @property
    def EI(self) -> float:
        return self.E * math.pi * self.radius**4 / 4

    @property
    def omega1(self) -> float:
        area = math.pi * self.radius**2
        return 1.875**2 * math.sqrt(self.EI / (self.rho * area * self.length**4))

    @property
    def period(self) -> float:
        return 2 * math.pi / self.omega1

    @property
    def element_length(self) -> float:
        return self.length / (self.elements - self.clamp_offset)

    @property
    def time_step(self) -> float:
        wave = math.sqrt(self.E / self.rho)
        section = 2 * self.radius * math.sqrt(0.5 / self.shear_ratio)
        return self.cfl * min(self.element_length, section) / wave

    @property
    def steps(self) -> int:
        return math.ceil(self.final_time * self.period / self.time_step)


if ea is not None:

    class Simulator(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
        pass


def build_rod(s: RodSettings):
    dl = s.element_length
    simulator = Simulator()
    rod = ea.CosseratRod.straight_rod(
        s.elements, np.array([-s.clamp_offset * dl, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]),
        np.array([0.0, 0.0, 1.0]), s.length + s.clamp_offset * dl, s.radius, s.rho,
        youngs_modulus=s.E, shear_modulus=s.shear_ratio * s.E,
    )
    simulator.append(rod)
    simulator.constrain(rod).using(
        ea.OneEndFixedBC, constrained_position_idx=(0,), constrained_director_idx=(0,)
    )
    load = np.array([0.0, -K * s.EI / s.length**2, 0.0])
    simulator.add_forcing_to(rod).using(
        ea.EndpointForces, np.zeros(3), load, ramp_up_time=s.ramp * s.period
    )
    dt = s.final_time * s.period / s.steps
    simulator.dampen(rod).using(
        ea.AnalyticalLinearDamper, uniform_damping_constant=s.damping * s.omega1, time_step=dt
    )
    simulator.finalize()
    return simulator, rod


def rod_tip_errors(s: RodSettings, rod) -> dict:
    x, y = rod.position_collection[0, -1], rod.position_collection[1, -1]
    if not (np.isfinite(x) and np.isfinite(y)):
        return {"position": math.inf}
    return tip_errors(x - s.length, y, 0.0, EXACT, s.length) | {"rotation": math.nan}


def run_rod(s: RodSettings) -> dict:
    """One PyElastica run to ``final_time``: tip errors and wall times (build + integrate)."""
    started = time.perf_counter()
    simulator, rod = build_rod(s)
    built = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):  # integrate() prints the final time
        ea.integrate(ea.PositionVerlet(), simulator, s.final_time * s.period, s.steps,
                     progress_bar=False)
    done = time.perf_counter()
    return {"errors": rod_tip_errors(s, rod), "wall_s": done - started,
            "integrate_s": done - built, "steps": s.steps}


def settle(s: RodSettings, horizon: float, tol: float, check: float = 0.02) -> dict:
    """Run to ``horizon`` T1, checking the tip every ``check`` T1; ``settle_time`` is the first
    check after which the tip stays within ``tol`` (None if it never does, or blows up)."""
    s = replace(s, final_time=horizon)
    simulator, rod = build_rod(s)
    stepper, t = ea.PositionVerlet(), np.float64(0.0)
    dt = np.float64(s.final_time * s.period / s.steps)
    per_check = max(1, round(check * s.period / dt))
    settled, done, error = None, 0, math.inf
    started = time.perf_counter()
    while done < s.steps:
        for _ in range(per_check):
            t = stepper.step(simulator, t, dt)
        done += per_check
        error = rod_tip_errors(s, rod)["position"]
        if not error < 1.0:  # unstable
            return {"settle_time": None, "error": math.inf, "us_per_step": math.nan,
                    "settle_steps": None, "wall_s": time.perf_counter() - started}
        settled = (settled or done) if error < tol else None
    seconds = time.perf_counter() - started
    settle_time = settled * dt / s.period if settled else None
    return {"settle_time": settle_time, "error": error, "us_per_step": seconds / done * 1e6,
            "settle_steps": settled, "wall_s": seconds}


def tolerance_label(tol: float) -> str:
    """1e-3 -> "1e-3", 2.5e-4 -> "2.5e-4" (file names and `CHOSEN` keys)."""
    mantissa, exponent = f"{tol:.3e}".split("e")
    return f"{mantissa.rstrip('0').rstrip('.')}e{int(exponent)}"


def signed_tip_error(s: RodSettings, rod) -> np.ndarray:
    """(shortening, deflection) of the tip / L minus the elastica's."""
    x, y = rod.position_collection[0, -1], rod.position_collection[1, -1]
    return np.array([-(x - s.length) / s.length - EXACT.shortening,
                     -y / s.length - EXACT.deflection])


def rest_error(s: RodSettings, horizon: float = 3.0) -> np.ndarray:
    """Signed tip error of a rod brought to rest (critical damping 2 omega_1, ``horizon`` T1)."""
    s = replace(s, damping=2.0, final_time=horizon)
    simulator, rod = build_rod(s)
    with contextlib.redirect_stdout(io.StringIO()):
        ea.integrate(ea.PositionVerlet(), simulator, s.final_time * s.period, s.steps,
                     progress_bar=False)
    return signed_tip_error(s, rod)


SCREEN_SLENDERNESS, SCREEN_ELEMENTS, SCREEN_MARGIN = 30, (10, 80), 1.25


def error_model(shear_ratios) -> dict:
    """The two leading parts of the rest error (a 2-vector: shortening, deflection), measured on
    cheap rods (L/r = 30):

    * stretch + shear (softening): e_x(G/E) (30 / (L/r))^2, with e_x the error of an 80-element
      rod less its discretisation part (strains ~ P / EA, P / GA ~ k (r/L)^2);
    * discretisation (stiffening): d_10 (9.5 / (n - 1/2))^2, d_10 from the difference between
      10 and 80 elements at G/E = 1/2 (second order in the element length 1 / (n - 1/2), the
      rod starting half an element behind the clamp).

    Checked at L/r = 100 (n = 20, 40, 80; G/E = 1/2, 2): predicted |e_x + d| within 6 % of the
    measured rest errors (2.6e-5 ... 4.1e-4 L).
    """
    coarse_n, fine_n = SCREEN_ELEMENTS
    base = RodSettings(elements=fine_n, slenderness=SCREEN_SLENDERNESS, shear_ratio=0.5, cfl=0.5,
                       damping=2.0, ramp=0.02, final_time=3.0)
    fine = {g: rest_error(replace(base, shear_ratio=g)) for g in sorted({0.5, *shear_ratios})}
    coarse = rest_error(replace(base, elements=coarse_n))
    ratio = ((coarse_n - 0.5) / (fine_n - 0.5)) ** 2
    d_coarse = (coarse - fine[0.5]) / (1 - ratio)
    return {"stretch_shear": {g: (e - d_coarse * ratio).tolist() for g, e in fine.items()},
            "discretisation": d_coarse.tolist(), "elements": coarse_n,
            "slenderness": SCREEN_SLENDERNESS}


def predicted_errors(model: dict, s: RodSettings) -> tuple[float, float]:
    """Predicted rest errors / L of the rod ``s`` and of the same rod with twice the elements."""
    stretch = np.asarray(model["stretch_shear"][s.shear_ratio]) \
        * (model["slenderness"] / s.slenderness) ** 2
    h = model["elements"] - 0.5
    d = np.asarray(model["discretisation"]) * (h / (s.elements - 0.5)) ** 2
    d2 = np.asarray(model["discretisation"]) * (h / (2 * s.elements - 0.5)) ** 2
    return float(np.linalg.norm(stretch + d)), float(np.linalg.norm(stretch + d2))


def step_cost_model() -> tuple[float, float]:
    """Seconds per PositionVerlet step ~ a + b * elements (two short runs; numba warm)."""
    per_step = []
    for n in (10, 320):
        s = replace(CHOSEN[tolerance_label(DEFAULT_TOL)], elements=n)
        s = replace(s, final_time=2000.5 * s.time_step / s.period)
        per_step.append(run_rod(s)["integrate_s"] / s.steps)
    b = (per_step[1] - per_step[0]) / 310
    return per_step[0] - 10 * b, b


def search(tol: float = DEFAULT_TOL, budget: float = math.inf, max_run: float = math.inf,
           verbose: bool = True) -> tuple[RodSettings, dict]:
    """Cheapest settings reaching ``tol``.

    1) grid over (elements, slenderness, G/E) at damping 2.5 omega_1; 2) in order of cost, keep
    the settings whose rod with 2x elements also settles within ``tol`` (not a lucky
    cancellation of the discretisation error, which stiffens the rod, with the extensibility and
    shear, which soften it), until four are kept; 3) tune damping and ramp for those.

    Below 1e-3 both errors must shrink by 1e-3 / tol, so the element and slenderness axes of the
    grid are scaled by sqrt(1e-3 / tol) (both errors are second order) and the horizons grow by
    0.4 T1 per decade (the damped settling to a smaller error takes longer). Before the grid, the
    two leading errors are measured on cheap rods (`error_model`, ~10 s) and settings predicted
    to miss the tolerance by more than a quarter of it (the model is within ~8 % of measured
    rest errors), with n or with 2n elements, are screened out: they would fail the grid or the
    guard. Grid points run in order of predicted cost (a + b n per step); with a ``budget`` (s)
    the grid stops at half of it and the guard at 3/4 (or at the end if nothing is kept yet),
    and runs predicted to take more than ``max_run`` s are skipped (both logged). Tuning reuses
    the grid run for damping 2.5, ramp 0.02 (same run, deterministic). Returns the choice and a
    log of what was tried."""
    started = time.perf_counter()
    scale = math.sqrt(DEFAULT_TOL / tol)
    later = 0.4 * math.log10(DEFAULT_TOL / tol)
    grid_horizon, guard_horizon = 1.6 + later, 2.0 + later

    def left(fraction: float) -> float:
        return fraction * budget - (time.perf_counter() - started)

    base = RodSettings(elements=10, slenderness=25, shear_ratio=0.5, cfl=0.5, damping=2.5,
                       ramp=0.02, final_time=1.0)
    shear_ratios = (1 / 3, 0.5, 1.0, 2.0)
    log = {"tolerance": tol, "scale": scale, "grid_horizon": grid_horizon,
           "guard_horizon": guard_horizon, "budget_s": budget, "max_run_s": max_run,
           "standard_clamp": [], "error_model": None, "cost_model": None, "grid": [],
           "screened_out": [], "skipped": [], "guard": [], "tuned": []}
    # The plain set-up (no clamp offset) converges at first order only:
    for n in (20, 40, 80):
        s = replace(base, elements=n, slenderness=50, clamp_offset=0.0)
        result = settle(s, horizon=2.0, tol=tol)
        log["standard_clamp"].append({"elements": n, "error_at_2T1": result["error"]})
        if verbose:
            print(f"standard clamp, {n} elements, L/r = 50: tip error {result['error']:.2e}",
                  flush=True)
    model = error_model(shear_ratios)
    a, b = step_cost_model()
    log["error_model"], log["cost_model"] = model, {"a_us": a * 1e6, "b_us": b * 1e6}
    if verbose:
        print("error model (L/r = 30): stretch+shear " + ", ".join(
            f"G/E {g:.3g}: {np.linalg.norm(e):.2e}" for g, e in model["stretch_shear"].items())
            + f"; discretisation, {model['elements']} el.: "
            f"{np.linalg.norm(model['discretisation']):.2e}; "
            f"cost per step {a * 1e6:.1f} + {b * 1e6:.3f} n us", flush=True)

    def predicted_cost(s: RodSettings, horizon: float) -> float:
        return replace(s, final_time=horizon).steps * (a + b * s.elements) * 1.1

    def estimate(result: dict) -> float:
        return result["settle_steps"] * result["us_per_step"] * 1e-6

    points = []
    grid = itertools.product((6, 8, 10, 12, 16, 20, 24, 32), (10, 15, 20, 25, 30, 40, 50),
                             shear_ratios)
    for n, slenderness, shear in grid:
        s = replace(base, elements=round(n * scale), slenderness=round(slenderness * scale),
                    shear_ratio=shear)
        error, refined_error = predicted_errors(model, s)
        entry = asdict(s) | {"predicted_error": error, "predicted_refined_error": refined_error,
                             "predicted_s": predicted_cost(s, grid_horizon)}
        if max(error, refined_error) > SCREEN_MARGIN * tol:
            log["screened_out"].append(entry)
        else:
            points.append((entry["predicted_s"], s, entry))
    points.sort(key=lambda p: p[0])
    if verbose:
        print(f"grid: {len(points) + len(log['screened_out'])} settings, "
              f"{len(log['screened_out'])} screened out; predicted "
              f"{sum(p[0] for p in points):.0f} s for the rest", flush=True)
    candidates = []
    for cost, s, entry in points:
        if cost > max_run or cost > left(0.5):
            log["skipped"].append(entry | {"phase": "grid"})
            continue
        result = settle(s, horizon=grid_horizon, tol=tol)
        log["grid"].append(entry | result)
        if result["settle_time"] is not None:
            candidates.append((estimate(result), s, result))
    candidates.sort(key=lambda c: c[0])
    if verbose:
        print(f"grid: {len(candidates)} of {len(log['grid'])} settings run settle within "
              f"{tol:g} L ({len(log['skipped'])} skipped, predicted > {max_run:g} s or over "
              f"budget); {time.perf_counter() - started:.0f} s", flush=True)
    kept = []
    for cost, s, result in candidates:
        refined = replace(s, elements=2 * s.elements, cfl=0.4)
        guard_cost = predicted_cost(refined, guard_horizon)
        if guard_cost > max_run or guard_cost > left(0.75 if kept else 1.0):
            log["skipped"].append(asdict(s) | {"phase": "guard", "predicted_s": guard_cost})
            continue
        check = settle(refined, horizon=guard_horizon, tol=tol)
        ok = check["settle_time"] is not None
        log["guard"].append(asdict(s) | {"estimate_s": cost, "refined_error": check["error"],
                                         "refined_wall_s": check["wall_s"], "accepted": ok})
        if verbose:
            print(f"  {s.elements} el., L/r {s.slenderness:g}, G/E {s.shear_ratio:.3g}: "
                  f"~{cost:.3f} s; 2x elements: error {check['error']:.2e} "
                  f"{'kept' if ok else 'rejected'}", flush=True)
        if ok:
            kept.append((s, result))
            if len(kept) == 4:
                break
    tuned = []
    for s, grid_result in kept:
        for damping, ramp in itertools.product((1.5, 2.0, 2.5, 3.0, 3.5), (0.02, 0.1)):
            trial = replace(s, damping=damping, ramp=ramp)
            if trial == s:  # the grid run (same horizon): deterministic, not repeated
                result = grid_result
            else:
                cost = predicted_cost(trial, grid_horizon)
                if cost > max_run or cost > left(1.0):
                    log["skipped"].append(asdict(trial) | {"phase": "tuning",
                                                           "predicted_s": cost})
                    continue
                result = settle(trial, horizon=grid_horizon, tol=tol)
            log["tuned"].append(asdict(trial) | result)
            if result["settle_time"] is not None:
                final_time = math.ceil(result["settle_time"] * 100) / 100
                tuned.append((estimate(result), replace(trial, final_time=final_time)))
    if not tuned:
        raise RuntimeError(f"no PyElastica setting reached {tol:g} L and passed the guard")
    tuned.sort(key=lambda c: c[0])
    log["wall_s"] = time.perf_counter() - started
    if verbose:
        print(f"cheapest after tuning damping and ramp: {tuned[0][1]} (~{tuned[0][0]:.3f} s); "
              f"search {log['wall_s']:.0f} s")
    return tuned[0][1], log


# Found by `--search` (see benchmarks/README.md), by tolerance_label(tolerance).
CHOSEN = {
    "1e-3": RodSettings(elements=10, slenderness=30, shear_ratio=0.5, cfl=0.5, damping=2.5,
                        ramp=0.02, final_time=0.98),  # 2026-11-22
    "1e-4": RodSettings(elements=32, slenderness=95, shear_ratio=0.5, cfl=0.5, damping=2.5,
                        ramp=0.02, final_time=1.26),  # 2026-11-22, --budget 900 (430 s used)
    "1e-5": RodSettings(elements=100, slenderness=300, shear_ratio=0.5, cfl=0.5, damping=2.5,
                        ramp=0.1, final_time=1.63),  # 2026-11-22, --budget 900 (cut, 859 s)
}


def fe_beam_cheapest(tol: float, max_elements: int = 256) -> tuple[int, dict]:
    """Fewest degree-2 elements whose tip is within ``tol`` of the elastica."""
    for n in range(1, max_elements + 1):
        result = solve_static(static_config(cantilever(K, n), FE_STEPS), None, progress=False,
                              record_shapes=False)
        tip = result.steps[-1]["tip"]
        errors = tip_errors(tip["u"], tip["v"], tip["theta"], EXACT)
        if result.status == "converged" and errors["position"] < tol:
            return n, errors
    raise RuntimeError(f"fe_beam: no mesh up to {max_elements} elements reached {tol:g} L")


def fe_beam_end_to_end(n: int) -> float:
    """`solve_static` as the CLI runs it without files, on its solve-only path
    (``record_shapes=False``: no output writer, no per-step shapes or profiles)."""
    seconds, result = timed(lambda: solve_static(static_config(cantilever(K, n), FE_STEPS), None,
                                                 progress=False, record_shapes=False))
    assert result.status == "converged", result.message
    return seconds


def fe_beam_build_and_solve(n: int) -> float:
    """Library use: build the problem (forms from the JIT cache) and the solver, step the load."""

    def run():
        p = BeamProblem(cantilever(K, n))
        solver = SNESSolver(NonlinearProblem(p.residual, p.w, p.bcs))
        run_load_stepping(solver, p.set_load_factor, LoadStepping(steps=FE_STEPS), progress=False)
        solver.destroy()

    return timed(run)[0]


class FeBeamSolveOnly:
    """Problem and solver built once; each call re-solves from w = 0 (no set-up, no JIT)."""

    def __init__(self, n: int):
        self.problem = BeamProblem(cantilever(K, n))
        p = self.problem
        self.solver = SNESSolver(NonlinearProblem(p.residual, p.w, p.bcs))

    def __call__(self) -> float:
        p = self.problem
        p.w.x.array[:] = 0.0
        seconds, _ = timed(lambda: run_load_stepping(
            self.solver, p.set_load_factor, LoadStepping(steps=FE_STEPS), progress=False))
        return seconds


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tolerance", type=float, default=DEFAULT_TOL,
                        help="tip position tolerance / L for both codes (default 1e-3)")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--search", action="store_true",
                        help="search the cheapest PyElastica settings first (minutes)")
    parser.add_argument("--budget", type=float, default=math.inf,
                        help="wall-time budget of --search, s (default: none)")
    parser.add_argument("--max-run", type=float, default=math.inf,
                        help="--search skips PyElastica runs predicted to take longer, s")
    args = parser.parse_args(argv)
    tol, label = args.tolerance, tolerance_label(args.tolerance)
    names = [f"pyelastica_tol{label}"] + (["pyelastica"] if tol == DEFAULT_TOL else [])
    if ea is None:
        message = (f"PyElastica is not available ({IMPORT_ERROR}); install it with "
                   "`python -m pip install -c constraints.txt pyelastica`")
        print(message, file=sys.stderr)
        for name in names:
            write_results(name, {"status": "unavailable", "reason": message})
        return 1
    if not args.search and label not in CHOSEN:
        print(f"no stored PyElastica settings for {label} L (stored: {', '.join(CHOSEN)}); "
              "run with --search", file=sys.stderr)
        return 2
    print(f"PyElastica {ELASTICA_VERSION}; elastica k = {K:g}: shortening "
          f"{EXACT.shortening:.6f}, deflection {EXACT.deflection:.6f}; tolerance {tol:g} L")
    run_rod(replace(CHOSEN[tolerance_label(DEFAULT_TOL)], final_time=0.01))  # numba JIT
    log = None
    if args.search:
        chosen, log = search(tol, budget=args.budget, max_run=args.max_run)
    else:
        chosen = CHOSEN[label]
    rod = run_rod(chosen)
    print(f"PyElastica settings: {chosen}\n  dt = {chosen.time_step:.3e} s, T1 = "
          f"{chosen.period:.4g} s, {chosen.steps} steps; "
          f"tip error {rod['errors']['position']:.2e} L; {rod['wall_s']:.2f} s")
    if not rod["errors"]["position"] < tol:
        print("warning: the PyElastica settings miss the tolerance", file=sys.stderr)

    n, fe_errors = fe_beam_cheapest(tol)
    print(f"fe_beam: {n} degree-2 elements, {FE_STEPS} load steps; tip error "
          f"{fe_errors['position']:.2e} L")
    solve_only = FeBeamSolveOnly(n)
    fe_beam_runs = {
        "fe_beam solve_static": lambda: fe_beam_end_to_end(n),
        "fe_beam build + solve": lambda: fe_beam_build_and_solve(n),
        "fe_beam load stepping only": solve_only,
    }
    for run in fe_beam_runs.values():
        run()  # warm up
    times = {"PyElastica build + integrate": [], "PyElastica integrate only": []}
    times |= {name: [] for name in fe_beam_runs}
    for _ in range(args.repeats):  # alternate, so that all see the same machine load
        rod = run_rod(chosen)
        times["PyElastica build + integrate"].append(rod["wall_s"])
        times["PyElastica integrate only"].append(rod["integrate_s"])
        for name, run in fe_beam_runs.items():
            times[name].append(run())
    reference = times["PyElastica build + integrate"]
    speedups = {name: [p / f for p, f in zip(reference, times[name], strict=True)]
                for name in fe_beam_runs}
    mesh = {"PyElastica build + integrate": f"{chosen.elements} el.",
            "fe_beam solve_static": f"{n} el. p=2"}
    error = {"PyElastica build + integrate": rod["errors"]["position"],
             "fe_beam solve_static": fe_errors["position"]}
    rows = [[name, mesh.get(name, ""), error.get(name, ""), statistics.median(t), min(t),
             f"{statistics.median(speedups[name]):.1f}x" if name in speedups else ""]
            for name, t in times.items()]
    print()
    print(table(["code", "mesh", "tip error / L", "median s", "min s",
                 "PyElastica / this"], rows))
    print(f"(ratios: median over {args.repeats} alternating repeats of PyElastica build + "
          "integrate / fe_beam; solve_static with record_shapes=False)")
    data = {
        "status": "ok",
        "pyelastica_version": ELASTICA_VERSION,
        "k": K, "tolerance": tol,
        "pyelastica": {"settings": asdict(chosen), "time_step": chosen.time_step,
                       "steps": chosen.steps, "tip_errors": rod["errors"]},
        "fe_beam": {"elements": n, "degree": 2, "load_steps": FE_STEPS, "tip_errors": fe_errors,
                    "solve_static": "record_shapes=False (solve-only path, no output writer)"},
        "repeats": args.repeats,
        "times": {name: stats(t) for name, t in times.items()},
        "speedup_vs_pyelastica": {name: {"median": statistics.median(r), "all": r}
                                  for name, r in speedups.items()},
        "search": log,
    }
    for name in names:
        print(f"results: {write_results(name, data)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

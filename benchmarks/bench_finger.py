"""Tendon finger benchmark (issue 4): tension sweep and inverse solve, fe_beam vs shooting.

The finger is `fe_beam.analyses.finger.DEFAULT_FINGER` (the chapter's finger: L = 0.1 m, B = 0.02 m,
H 0.02 -> 0.01 m, E = 0.6 MPa, one tendon 8 -> 4 mm, 20 load steps to 2 N). The independent
reference `fe_beam.baselines.shooting` solves the chapter's model: extensible, unshearable,
m = EJ theta' (``curvature="reference"``); fe_beam solves the same model with the Reissner law
and the `unshearable` constraint (as in tests/test_tendons.py). DEFAULT_FINGER's own model (the
non-standard law, shearable, 40 elements: what `fe-beam finger` runs by default) is a slightly
different model; it is timed too, and its distance from the chapter's model is reported.

Sweep: the tip at the 20 tensions 0.1, 0.2, ..., 2 N. Both codes must be within TOL = 1e-4 L
(tip position) of a converged reference (shooting, rtol 1e-12) at every tension:

* fe_beam: the fewest degree-2 elements reaching TOL (and 2x elements also), one load-stepping
  run of 20 steps (each converged step is one tension), default solver settings (MUMPS,
  rtol 1e-9). Timed three ways: the `fe-beam finger` path without files (`run_finger`, which
  also records shapes for the plots), `solve_static(record_shapes=False)` (library use: build +
  solve), and the load stepping alone on a problem built once.
* shooting: the loosest solve_ivp rtol reaching TOL (and rtol / 10 also), 20 `solve_finger`
  calls (n_points = 2, i.e. no sampling), each started from the previous solution's base
  reactions (continuation, in the baseline's favour).

Inverse: the tension that turns the tip by 0.3 rad (examples/finger.toml), by
`fe_beam.analyses.finger.tension_for_tip_angle` (what `fe-beam finger` does for [inverse]
tip_angle: brentq
on full 20-step solves, xtol 1e-12) with the fewest elements whose tension is within 1e-4
(relative) of the reference (and 2x elements also), and by `shooting.tension_for_tip_angle`
(brentq, xtol 1e-14, solve_finger at its default rtol 1e-10). Reference: the shooting inverse
with xtol 1e-15, cross-checked by fe_beam with 40 elements.

Times after JIT; the codes alternate, ``repeats`` times, ratios are medians of per-repeat ratios.

    python benchmarks/bench_finger.py [--repeats 5] [--target 0.3]
"""

from __future__ import annotations

import argparse
import statistics
import sys

import numpy as np
from common import stats, table, timed, write_results

from fe_beam.analyses.finger import (
    DEFAULT_FINGER,
    InverseTarget,
    parse_finger,
    run_finger,
    solve_inverse,
    tension_for_tip_angle,
)
from fe_beam.analyses.static import StaticContinuation, solve_static
from fe_beam.baselines import shooting
from fe_beam.fem.rod import BeamProblem
from fe_beam.fem.tendons import TendonSet
from fe_beam.solvers.continuation import run_load_stepping
from fe_beam.solvers.newton import NonlinearProblem, SNESSolver, rotation_jump_check
from fe_beam.solvers.pull_in import PullInSolver

TOL = 1e-4  # tip position / L
INVERSE_TOL = 1e-4  # relative tension error of the inverse solve
LENGTH = DEFAULT_FINGER["beam"]["length"]
MAX_TENSION = DEFAULT_FINGER["tendons"][0]["tension"]
LEVELS = DEFAULT_FINGER["loads"]["steps"]
TENSIONS = MAX_TENSION * np.arange(1, LEVELS + 1) / LEVELS
REFERENCE_RTOL = 1e-12
FE_ELEMENTS = (1, 2, 3, 4, 5, 6, 8, 10, 12, 16)
SHOOTING_RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
QUIET = {"output": {"plots": False, "xdmf": False}}


# --- the two models -----------------------------------------------------------------------------
def fe_config(elements: int | None = None, chapter_model: bool = True):
    """DEFAULT_FINGER; with ``chapter_model`` the Reissner law + unshearable (the shooting
    solver's model), else its own non-standard law without constraint."""
    given = dict(QUIET)
    if chapter_model:
        given["model"] = {"law": "reissner", "constraint": "unshearable"}
    if elements is not None:
        given["mesh"] = {"elements": elements, "degree": 2}
    config, _ = parse_finger(given)
    return config


def shooting_finger(tension: float) -> shooting.TaperedFinger:
    """DEFAULT_FINGER for the shooting solver (checked field by field)."""
    d = DEFAULT_FINGER
    tendon = d["tendons"][0]
    return shooting.TaperedFinger(
        length=d["beam"]["length"], width=d["section"]["b"], height_base=d["section"]["h"],
        height_tip=d["section"]["h_tip"], young=d["material"]["E"],
        tendons=(shooting.Tendon(tension=tension, offset_base=tendon["offset_base"],
                                 offset_tip=tendon["offset_tip"]),),
        extensible=True, curvature="reference")


# --- sweeps ---------------------------------------------------------------------------------
def shooting_sweep(rtol: float, continuation: bool = True) -> np.ndarray:
    """Tip (u, v, theta) at TENSIONS, one solve_finger per tension."""
    tips, guess = [], None
    for tension in TENSIONS:
        s = shooting.solve_finger(shooting_finger(float(tension)), n_points=2, rtol=rtol,
                                  initial_guess=guess)
        if continuation:
            guess = (*s.base_force, s.base_moment)
        tips.append((s.tip_u, s.tip_v, s.tip_theta))
    return np.array(tips)


def fe_tips(result) -> np.ndarray:
    """Tip (u, v, theta) of a fe_beam sweep, checking that its steps are the 20 tensions."""
    assert result.status == "converged", result.message
    tensions = np.array([s["tensions"][0] for s in result.steps])
    if tensions.shape != TENSIONS.shape or not np.allclose(tensions, TENSIONS, rtol=1e-12):
        raise RuntimeError(f"fe_beam's load steps are not the {LEVELS} tensions: {tensions}")
    return np.array([[s["tip"][k] for k in ("u", "v", "theta")] for s in result.steps])


def fe_sweep(config) -> np.ndarray:
    return fe_tips(solve_static(config, None, progress=False, record_shapes=False))


def sweep_error(tips: np.ndarray, reference: np.ndarray) -> float:
    """max over the tensions of |tip position - reference| / L."""
    return float(np.max(np.hypot(*(tips[:, :2] - reference[:, :2]).T)) / LENGTH)


class FeSolveOnly:
    """`solve_static`'s problem and solver built once; each call re-runs the 20 load steps from
    the straight finger (no set-up, no recording beyond the tip)."""

    def __init__(self, config):
        self.config = config
        self.tendons = TendonSet(config.tendons, config.model.length)
        self.problem = BeamProblem(config.model, breakpoints=self.tendons.breakpoints,
                                   extra_energy=self.tendons.energy)
        p = self.problem
        self.snes = SNESSolver(NonlinearProblem(p.residual, p.w, p.bcs), config.solver,
                               prefix="bench_finger_", state_scale=config.model.length)
        self.solver = PullInSolver(self.snes, self.tendons)
        self.check = rotation_jump_check(p.rotation_dofs(), config.max_rotation_jump)

    def set_load_factor(self, value: float) -> None:
        self.problem.set_load_factor(value)
        self.tendons.set_tension_controlled(value)
        self.solver.set_load_factor(value)

    def __call__(self) -> np.ndarray:
        self.problem.w.x.array[:] = 0.0
        tips = []
        run_load_stepping(self.solver, self.set_load_factor, self.config.stepping,
                          on_converged=lambda step: tips.append(self.problem.end_values("xL")),
                          reject_step=self.check, progress=False)
        return np.array([[t[k] for k in ("u", "v", "theta")] for t in tips])


# --- choosing the settings --------------------------------------------------------------------
def cheapest_fe(reference: np.ndarray) -> tuple[int, dict]:
    errors = {n: sweep_error(fe_sweep(fe_config(n)), reference) for n in FE_ELEMENTS}
    for n in FE_ELEMENTS:
        if errors[n] < TOL and errors.get(2 * n, errors[FE_ELEMENTS[-1]]) < TOL:
            return n, errors
    raise RuntimeError("no element count reached the tolerance")


def cheapest_shooting(reference: np.ndarray) -> tuple[float, dict]:
    errors = {r: sweep_error(shooting_sweep(r), reference) for r in SHOOTING_RTOLS}
    for r in SHOOTING_RTOLS:
        tighter = errors.get(r / 10, errors[SHOOTING_RTOLS[-1]])
        if errors[r] < TOL and tighter < TOL:
            return r, errors
    raise RuntimeError("no rtol reached the tolerance")


# --- inverse ----------------------------------------------------------------------------------
class Counter:
    """Counts calls of a module-level function or a method (patched in place while active)."""

    def __init__(self, module, name):
        self.module, self.name, self.calls = module, name, 0
        self.original = getattr(module, name)

    def __enter__(self):
        def counted(*args, **kwargs):
            self.calls += 1
            return self.original(*args, **kwargs)

        setattr(self.module, self.name, counted)
        return self

    def __exit__(self, *exc):
        setattr(self.module, self.name, self.original)


def inverse_elements(target: float, reference_tension: float) -> tuple[int, dict]:
    """Fewest elements whose inverse tension is within INVERSE_TOL (relative) of the reference,
    twice as many elements also."""
    errors = {}
    for n in FE_ELEMENTS:
        for m in (n, 2 * n):
            if m not in errors:
                tension = tension_for_tip_angle(fe_config(m), target)
                errors[m] = abs(tension / reference_tension - 1)
        if errors[n] < INVERSE_TOL and errors[2 * n] < INVERSE_TOL:
            return n, errors
    raise RuntimeError("no element count reached the inverse tolerance")


def inverse(elements: int, target: float, repeats: int, reference_tension: float) -> dict:
    """Three inverse solves, alternating: fe_beam's `tension_for_tip_angle` (bracket by doubling
    from the tendon's 2 N), fe_beam's `solve_inverse` bracketed by the sweep's steps (what
    `fe-beam finger` does after its sweep; the sweep itself is not timed here) and the shooting
    solver's `tension_for_tip_angle`."""
    config = fe_config(elements)
    sweep = solve_static(config, None, progress=False, record_shapes=False).steps
    goal = InverseTarget("tip_angle", target)
    shooting_base = shooting_finger(MAX_TENSION)
    methods = {
        # fe_beam's trials are continuation moves of one problem (StaticContinuation.advance)
        "fe_beam": (StaticContinuation, "advance",
                    lambda: tension_for_tip_angle(config, target)),
        "fe_beam_bracketed_by_sweep": (StaticContinuation, "advance",
                                       lambda: solve_inverse(config, goal, sweep=sweep)["tension"]),
        "shooting": (shooting, "solve_finger",
                     lambda: shooting.tension_for_tip_angle(target, shooting_base)),
    }
    for _, _, run in methods.values():
        run()  # warm-up
    times = {key: [] for key in methods}
    found = {}
    for _ in range(repeats):
        for key, (module, name, run) in methods.items():
            with Counter(module, name) as count:
                seconds, tension = timed(run)
            times[key].append(seconds)
            found[key] = {"tension": tension, "solves": count.calls,
                          "tension_error": abs(tension - reference_tension),
                          "relative_error": abs(tension / reference_tension - 1)}
    result = {"target_tip_angle": target, "reference_tension": reference_tension,
              "fe_beam_elements": elements}
    for key in methods:
        result[key] = found[key] | {"wall": stats(times[key])}
        result[key]["shooting_over_this"] = statistics.median(
            s / t for s, t in zip(times["shooting"], times[key], strict=True))
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--target", type=float, default=0.3, help="inverse: tip angle [rad]")
    args = parser.parse_args(argv)

    fe_sweep(fe_config(4))  # JIT (FFCx forms cached on disk)
    seconds, reference = timed(lambda: shooting_sweep(REFERENCE_RTOL))
    fine = sweep_error(fe_sweep(fe_config(40)), reference)
    default_model = fe_tips(solve_static(fe_config(chapter_model=False), None, progress=False,
                                         record_shapes=False))
    model_gap = sweep_error(default_model, reference)
    print(f"sweep: {LEVELS} tensions {TENSIONS[0]:g} .. {TENSIONS[-1]:g} N; reference: shooting "
          f"rtol {REFERENCE_RTOL:g} ({seconds:.2f} s), tip at {TENSIONS[-1]:g} N: u = "
          f"{reference[-1, 0]:.6g}, v = {reference[-1, 1]:.6g} m, theta = {reference[-1, 2]:.5f}"
          f" rad;\n  fe_beam with 40 elements differs by {fine:.1e} L; DEFAULT_FINGER's own "
          f"model (non-standard law, shearable) by {model_gap:.1e} L")

    elements, fe_errors = cheapest_fe(reference)
    rtol, sh_errors = cheapest_shooting(reference)
    print(table(["elements", *map(str, FE_ELEMENTS)],
                [["fe_beam err / L", *fe_errors.values()]]))
    print(table(["rtol", *(f"{r:g}" for r in SHOOTING_RTOLS)],
                [["shooting err / L", *sh_errors.values()]]))
    print(f"cheapest within {TOL:g} L: fe_beam {elements} degree-2 elements "
          f"({fe_errors[elements]:.1e} L), shooting rtol {rtol:g} ({sh_errors[rtol]:.1e} L)\n")

    config = fe_config(elements)
    default_config = fe_config(chapter_model=False)
    solve_only = FeSolveOnly(config)
    solve_only()
    runs = {"shooting": [], "shooting_no_continuation": [], "fe_finger_command": [],
            "fe_solve_static": [], "fe_solve_only": [], "fe_default_finger": []}
    for _ in range(args.repeats):
        runs["shooting"].append(timed(lambda: shooting_sweep(rtol))[0])
        runs["shooting_no_continuation"].append(
            timed(lambda: shooting_sweep(rtol, continuation=False))[0])
        runs["fe_finger_command"].append(
            timed(lambda: run_finger(config, None, progress=False))[0])
        runs["fe_solve_static"].append(timed(lambda: fe_sweep(config))[0])
        runs["fe_solve_only"].append(timed(solve_only)[0])
        runs["fe_default_finger"].append(
            timed(lambda: run_finger(default_config, None, progress=False))[0])
    newton = sum(s["newton_iterations"] for s in solve_static(
        config, None, progress=False, record_shapes=False).steps)
    ratios = {key: statistics.median(s / f for s, f in zip(runs["shooting"], runs[key],
                                                          strict=True))
              for key in runs if key.startswith("fe_")}
    labels = {
        "shooting": f"shooting, rtol {rtol:g}, continuation",
        "shooting_no_continuation": f"shooting, rtol {rtol:g}, each from the straight guess",
        "fe_finger_command": f"fe_beam run_finger ({elements} el., as `fe-beam finger`, no files)",
        "fe_solve_static": f"fe_beam solve_static, record_shapes=False ({elements} el.)",
        "fe_solve_only": f"fe_beam load stepping only ({elements} el., {newton} Newton its)",
        "fe_default_finger": "fe_beam run_finger, DEFAULT_FINGER as is (40 el., non-standard)",
    }
    rows = [[labels[k], statistics.median(v), min(v),
             f"{ratios[k]:.1f}x" if k in ratios else ""] for k, v in runs.items()]
    print(f"sweep of {LEVELS} tensions ({args.repeats} alternating repeats)")
    print(table(["", "median s", "min s", "shooting / this"], rows))

    reference_tension = shooting.tension_for_tip_angle(args.target, shooting_finger(MAX_TENSION),
                                                       xtol=1e-15)
    fine_tension = tension_for_tip_angle(fe_config(40), args.target)
    inverse_n, inverse_errors = inverse_elements(args.target, reference_tension)
    inv = inverse(inverse_n, args.target, max(3, args.repeats // 2), reference_tension)
    inv["fe_beam_40_elements_tension"] = fine_tension
    inv["fe_beam_relative_errors"] = inverse_errors
    print(f"\ninverse: tension for a tip angle of {args.target:g} rad; reference "
          f"{reference_tension:.12g} N (fe_beam, 40 elements: {fine_tension:.12g} N); fewest "
          f"elements within {INVERSE_TOL:g} (relative): {inverse_n} (errors "
          + ", ".join(f"{n}: {e:.1e}" for n, e in sorted(inverse_errors.items())) + ")")
    labels = {"fe_beam": f"fe_beam tension_for_tip_angle ({inverse_n} el.)",
              "fe_beam_bracketed_by_sweep": f"fe_beam solve_inverse, bracket from the sweep "
              f"({inverse_n} el.)",
              "shooting": "shooting tension_for_tip_angle"}
    rows = [[labels[k], inv[k]["solves"], inv[k]["relative_error"], inv[k]["wall"]["median_s"],
             f"{inv[k]['shooting_over_this']:.2f}x"] for k in labels]
    print(table(["", "forward solves", "rel. tension error", "median s", "shooting / this"],
                rows))
    path = write_results("finger", {
        "tolerance": TOL, "tensions": TENSIONS.tolist(), "reference_rtol": REFERENCE_RTOL,
        "reference_tip": reference.tolist(), "fe_40_elements_error": fine,
        "default_model_gap": model_gap, "fe_errors": fe_errors, "shooting_errors":
        {f"{k:g}": v for k, v in sh_errors.items()}, "fe_elements": elements,
        "shooting_rtol": rtol, "fe_newton_iterations": newton,
        "sweep": {k: stats(v) for k, v in runs.items()}, "sweep_ratios": ratios,
        "inverse": inv})
    print(f"results: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

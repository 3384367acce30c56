"""fe_beam's spatial rod vs PyElastica (issue 22, item 8), and the real-time re-solve of the
spatial finger.

a. Cantilever (L = 1, circular section, the units of bench_pyelastica.py) under a dead tip
   force of |P| = k EI / L^2, k = 3, at 30 degrees out of the x-y plane:
   P = |P| (0, -cos 30, sin 30). Reference: `fe_beam.baselines.spatial_shooting.solve_cantilever`
   (an independent shooting solver, inextensible-unshearable, rtol 1e-12). Both codes must put
   the tip within the tolerance (1e-3 L and 1e-4 L) of it:

   * PyElastica: the rod and settings of bench_pyelastica.py (`CHOSEN`: found by its
     ``--search`` for the planar elastica at k = 3; a circular rod is isotropic, so the same
     settings bring the rotated problem to the same accuracy: checked here against the 3D
     reference), clamped by OneEndFixedBC, EndpointForces (ramped), AnalyticalLinearDamper,
     PositionVerlet to ``final_time`` (damped dynamic relaxation).
   * fe_beam: ``kinematics = "spatial"``, Reissner law + inextensible-unshearable, degree 2,
     the fewest elements within the tolerance, 2 load steps, default solver settings. Timed as
     a solve of a built problem (`StaticContinuation` reused: restart + load stepping, SNES
     with the default linear solver, MUMPS for these saddle-point systems), the same by a built
     `RealtimeSolver` moved from rest to the load in one update (dense/banded LU without SNES
     dispatch, step check on), build + solve (a new `StaticContinuation`, forms from the JIT
     cache) and `solve_static` (its problem cache: a second solve of the same kind).

   After JIT (numba, FFCx), the codes alternate in one run (``--repeats``); the ratio is the
   median over repeats of (PyElastica build + integrate) / (fe_beam), each pair back to back.

b. The spatial finger (L = 0.1 m, circle d = 15 mm, E = 1 MPa, nu = 0.45, Reissner law +
   unshearable, 20 degree-2 elements, 326 dofs; a helical tendon r = 4 mm turning by 90 degrees,
   tests/test_spatial_realtime.py): `RealtimeSolver` warm re-solves along
   tau(t) = 1.5 + 0.5 sin(2 pi t) N sampled at 1 kHz (``--updates``), with the step check
   (rotation jump + admissibility) and without; the tip against the shooting solver's
   (extensible, unshearable, same stiffnesses) at 1 and 2 N. Then the finger against
   PyElastica (``--finger-tolerance``, default 1e-3 L): PyElastica with the tendon as forces
   (`_tendon_kernel`: the discrete Rucker-Webster loads of the tendon on the current shape,
   recomputed at every step), all codes on the inextensible, shearable rod with PyElastica's
   shear constant (`finger_versus_pyelastica`; PyElastica's EA raised by AXIAL_FACTOR).

    python benchmarks/bench_spatial_pyelastica.py [--repeats 5] [--updates 500]
                                                  [--tolerance 1e-3 1e-4]
                                                  [--finger-tolerance 1e-3]
                                                  [--no-finger-pyelastica]

Writes benchmarks/results/spatial_pyelastica.json. Without PyElastica the script says why
and times fe_beam alone (``"pyelastica": {"status": "unavailable", ...}``).
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import io
import json
import math
import statistics
import sys
import time
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np
from common import machine, stats, table, timed
from mpi4py import MPI

from fe_beam import LoadStepping
from fe_beam.analyses.finger import parse_finger
from fe_beam.analyses.static import solve_static
from fe_beam.baselines.spatial_shooting import Tendon as ShootingTendon
from fe_beam.baselines.spatial_shooting import solve_cantilever
from fe_beam.config.schema import parse_static
from fe_beam.solvers.realtime import RealtimeSolver
from fe_beam.solvers.rod_static import StaticContinuation

RESULTS = Path(__file__).resolve().parent / "results"
K = 3.0
ANGLE = math.radians(30.0)
DIRECTION = np.array([0.0, -math.cos(ANGLE), math.sin(ANGLE)])
FE_STEPS = 2

try:
    import elastica as ea
    from bench_pyelastica import CHOSEN, RodSettings, tolerance_label
    from elastica.version import VERSION as ELASTICA_VERSION
except Exception as error:  # noqa: BLE001 - any import failure means "not available"
    ea, ELASTICA_VERSION, IMPORT_ERROR = None, None, f"{type(error).__name__}: {error}"
    CHOSEN = RodSettings = None

    def tolerance_label(tol: float) -> str:
        mantissa, exponent = f"{tol:.3e}".split("e")
        return f"{mantissa.rstrip('0').rstrip('.')}e{int(exponent)}"
else:
    IMPORT_ERROR = None

# The rod of bench_pyelastica (L = 1, E = 1 MPa) at slenderness L/r = 30 (fe_beam's rod is
# inextensible and unshearable: only EI and GJ matter, and the tip is the same for any r).
E, NU, LENGTH, RADIUS = 1.0e6, 0.0, 1.0, 1.0 / 30


def stiffness() -> dict:
    inertia = math.pi * RADIUS**4 / 4
    G = E / (2 * (1 + NU))
    return {"EI": E * inertia, "GJ": G * 2 * inertia}


def reference() -> np.ndarray:
    """r(L) of the inextensible-unshearable rod (shooting, rtol 1e-12)."""
    k = stiffness()
    force = K * k["EI"] / LENGTH**2 * DIRECTION
    solution = solve_cantilever(LENGTH, 1.0, 1.0, k["GJ"], k["EI"], k["EI"], tip_force=force,
                                extensible=False, shearable=False, rtol=1e-12)
    return np.asarray(solution.tip_position)


# --- fe_beam ---------------------------------------------------------------------------------
def fe_config(elements: int):
    k = stiffness()
    force = (K * k["EI"] / LENGTH**2 * DIRECTION).tolist()
    return parse_static({
        "beam": {"length": LENGTH}, "section": {"shape": "circle", "d": 2 * RADIUS},
        "material": {"E": E, "nu": NU},
        "model": {"kinematics": "spatial", "law": "reissner",
                  "constraint": "inextensible-unshearable"},
        "mesh": {"elements": elements, "degree": 2},
        "loads": {"steps": FE_STEPS, "tip_force": force}})


def fe_tip(run) -> np.ndarray:
    return np.array(run.problem.end_values("xL")["position"])


def fe_cheapest(tol: float, exact: np.ndarray, max_elements: int = 64) -> tuple[int, float]:
    for n in range(1, max_elements + 1):
        run = StaticContinuation(fe_config(n), MPI.COMM_WORLD)
        try:
            run.advance(1.0, LoadStepping(steps=FE_STEPS))
            error = float(np.linalg.norm(fe_tip(run) - exact) / LENGTH)
        finally:
            run.destroy()
        if error < tol:
            return n, error
    raise RuntimeError(f"fe_beam: no mesh up to {max_elements} elements reached {tol:g} L")


class FeSolveOnly:
    """A built problem re-solved from the unloaded state (restart + load stepping)."""

    def __init__(self, n: int):
        self.run = StaticContinuation(fe_config(n), MPI.COMM_WORLD)

    def __call__(self) -> float:
        self.run.restart()
        return timed(lambda: self.run.advance(1.0, LoadStepping(steps=FE_STEPS)))[0]


class FeFromRest:
    """A built `RealtimeSolver` (the dense serial path: banded/dense LU without SNES dispatch,
    chord predictor, step check on) moved from the unloaded state to the tip load by one
    update (Newton from rest; load stepping only if that fails); the way back is not timed."""

    def __init__(self, n: int):
        config = fe_config(n)
        self.force = config.model.loads.tip_force
        loads = replace(config.model.loads, tip_force=(0.0, 0.0, 0.0))
        self.solver = RealtimeSolver(replace(config, model=replace(config.model, loads=loads)))

    def __call__(self) -> float:
        self.solver.update(loads={"tip_force": (0.0, 0.0, 0.0)})
        return timed(lambda: self.solver.update(loads={"tip_force": self.force}))[0]

    def tip(self) -> np.ndarray:
        return fe_tip(self.solver.run)


def fe_build_and_solve(n: int) -> float:
    def run():
        continuation = StaticContinuation(fe_config(n), MPI.COMM_WORLD)
        continuation.advance(1.0, LoadStepping(steps=FE_STEPS))
        continuation.destroy()

    return timed(run)[0]


def fe_solve_static(n: int) -> float:
    seconds, result = timed(lambda: solve_static(fe_config(n), None, progress=False,
                                                 record_shapes=False))
    assert result.status == "converged", result.message
    return seconds


# --- PyElastica ------------------------------------------------------------------------------
def pyelastica_settings(tol: float):
    return CHOSEN[tolerance_label(tol)]


def run_rod(s) -> dict:
    """One PyElastica run (bench_pyelastica's rod and settings, the 3D tip load)."""

    class Simulator(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
        pass

    started = time.perf_counter()
    dl = s.element_length
    simulator = Simulator()
    rod = ea.CosseratRod.straight_rod(
        s.elements, np.array([-s.clamp_offset * dl, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]),
        np.array([0.0, 0.0, 1.0]), s.length + s.clamp_offset * dl, s.radius, s.rho,
        youngs_modulus=s.E, shear_modulus=s.shear_ratio * s.E)
    simulator.append(rod)
    simulator.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,),
                                   constrained_director_idx=(0,))
    load = K * s.EI / s.length**2 * DIRECTION
    simulator.add_forcing_to(rod).using(ea.EndpointForces, np.zeros(3), load,
                                        ramp_up_time=s.ramp * s.period)
    dt = s.final_time * s.period / s.steps
    simulator.dampen(rod).using(ea.AnalyticalLinearDamper,
                                uniform_damping_constant=s.damping * s.omega1, time_step=dt)
    simulator.finalize()
    built = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        ea.integrate(ea.PositionVerlet(), simulator, s.final_time * s.period, s.steps,
                     progress_bar=False)
    done = time.perf_counter()
    return {"tip": rod.position_collection[:, -1].copy(), "wall_s": done - started,
            "integrate_s": done - built, "steps": s.steps}


# --- the finger --------------------------------------------------------------------------------
FINGER = {"beam": {"length": 0.1}, "section": {"shape": "circle", "d": 0.015},
          "material": {"E": 1e6, "nu": 0.45},
          "model": {"kinematics": "spatial", "law": "reissner", "constraint": "unshearable"},
          "mesh": {"elements": 20, "degree": 2}, "loads": {"steps": 4},
          "tendons": [{"offset_y": "0.004*cos(pi*s/(2*L))",
                       "offset_z": "0.004*sin(pi*s/(2*L))", "tension": 1.5}],
          "output": {"plots": False, "xdmf": False}}


def finger_reference(tension: float) -> np.ndarray:
    """The finger's tip by the shooting solver (unshearable, extensible: EA, GJ = G 2I)."""
    d, E_f, nu = 0.015, 1e6, 0.45
    A, inertia = math.pi * d**2 / 4, math.pi * d**4 / 64
    G = E_f / (2 * (1 + nu))
    w = math.pi / (2 * 0.1)
    tendon = ShootingTendon(
        tension, lambda s: (0.004 * np.cos(w * s), 0.004 * np.sin(w * s)),
        d_offset=lambda s: (-0.004 * w * math.sin(w * s), 0.004 * w * math.cos(w * s)),
        dd_offset=lambda s: (-0.004 * w**2 * math.cos(w * s), -0.004 * w**2 * math.sin(w * s)))
    solution = solve_cantilever(0.1, E_f * A, 1.0, G * 2 * inertia, E_f * inertia,
                                E_f * inertia, shearable=False, tendons=(tendon,), rtol=1e-12)
    return np.asarray(solution.tip_position)


def finger_benchmark(updates: int, repeats: int) -> dict:
    config, _ = parse_finger(FINGER)
    tensions = 1.5 + 0.5 * np.sin(2 * np.pi * np.arange(1, updates + 1) / 1000.0)
    out = {"elements": 20, "degree": 2, "updates_per_run": updates, "runs": {}}
    accuracy = {}
    with RealtimeSolver(config) as solver:
        out["dofs"] = solver.problem.global_dofs
        for tension in (1.0, 2.0):
            solver.update(tensions=[tension])
            tip = np.array(solver.problem.end_values()["position"])
            accuracy[f"{tension:g} N"] = float(np.linalg.norm(tip - finger_reference(tension))
                                               / 0.1)
    out["tip_error_vs_shooting_over_L"] = accuracy
    for check in (True, False):
        walls, cpus, iterations = [], [], []
        with RealtimeSolver(config, check=check) as solver:
            solver.update(tensions=[tensions[-1]])
            for _ in range(repeats):
                per_update = []
                before_cpu = time.process_time()
                before_its = solver.statistics["newton_iterations"]
                for tension in tensions:
                    started = time.perf_counter()
                    solver.update(tensions=[tension])
                    per_update.append(time.perf_counter() - started)
                cpus.append((time.process_time() - before_cpu) / updates)
                iterations.append((solver.statistics["newton_iterations"] - before_its)
                                  / updates)
                walls.append(statistics.median(per_update))
            fallbacks = solver.statistics["fallbacks"]
        out["runs"]["check" if check else "no check"] = {
            "median_wall_ms": statistics.median(walls) * 1e3, "min_wall_ms": min(walls) * 1e3,
            "cpu_ms": statistics.median(cpus) * 1e3,
            "newton_per_update": statistics.median(iterations), "fallbacks": fallbacks}
    return out


# --- b. the finger in PyElastica: the tendon as forces ----------------------------------------
# The same rod in all three codes: inextensible and shearable with PyElastica's shear
# constant (GA = 27/28 G A, EI, GJ = G 2I), rho = 1000 kg/m^3 for PyElastica's dynamics.
# PyElastica's rod is extensible, with couples divided by the cube of the stretch (its law is
# not the reference's linear one once the tendon compresses the rod: with EA = E A the 1.1 %
# compression at 2 N puts its converged tip 5e-3 L away); its EA is raised by AXIAL_FACTOR
# (shear_matrix[2, 2]) so that it approximates the inextensible rod (a rod ~1e-4 L away).
AXIAL_FACTOR = 50.0
F_L, F_D, F_E, F_NU, F_RHO, F_TENSION = 0.1, 0.015, 1e6, 0.45, 1000.0, 2.0
F_G = F_E / (2 * (1 + F_NU))
ALPHA_C = 27.0 / 28.0
F_W = math.pi / (2 * F_L)


def helix(s):
    return 0.004 * np.cos(F_W * s), 0.004 * np.sin(F_W * s)


def finger_model_reference(tension: float = F_TENSION) -> np.ndarray:
    """r(L) of the inextensible, shearable finger (shooting, rtol 1e-12)."""
    A, inertia = math.pi * F_D**2 / 4, math.pi * F_D**4 / 64
    tendon = ShootingTendon(
        tension, helix,
        d_offset=lambda s: (-0.004 * F_W * math.sin(F_W * s), 0.004 * F_W * math.cos(F_W * s)),
        dd_offset=lambda s: (-0.004 * F_W**2 * math.cos(F_W * s),
                             -0.004 * F_W**2 * math.sin(F_W * s)))
    solution = solve_cantilever(F_L, F_E * A, ALPHA_C * F_G * A, F_G * 2 * inertia,
                                F_E * inertia, F_E * inertia, tendons=(tendon,),
                                extensible=False, rtol=1e-12)
    return np.asarray(solution.tip_position)


def fe_finger_config(elements: int, tension: float = F_TENSION):
    config = copy.deepcopy(FINGER)
    config["material"] = {"E": F_E, "nu": F_NU}
    config["model"] = {"kinematics": "spatial", "law": "reissner", "constraint": "inextensible",
                       "shear_correction": ALPHA_C}
    config["mesh"] = {"elements": elements, "degree": 2}
    config["loads"] = {"steps": FE_STEPS}
    config["tendons"][0]["tension"] = tension
    return parse_finger(config)[0]


def fe_finger_cheapest(tol: float, exact: np.ndarray) -> tuple[int, float]:
    for n in range(1, 65):
        run = StaticContinuation(fe_finger_config(n), MPI.COMM_WORLD)
        try:
            run.advance(1.0, LoadStepping(steps=FE_STEPS))
            error = float(np.linalg.norm(fe_tip(run) - exact) / F_L)
        finally:
            run.destroy()
        if error < tol:
            return n, error
    raise RuntimeError(f"fe_beam finger: no mesh up to 64 elements reached {tol:g} L")


def _tendon_kernel():
    import numba

    @numba.njit(cache=False)
    def tendon_loads(tau, positions, directors, offsets, forces, torques):
        """Rucker-Webster loads of a frictionless tendon on the current shape, as the
        gradient of tau * l, l the length of the polyline through the tendon's points at the
        element centres (body offsets ``offsets[k]`` in the directors' frame, k < n) and at
        the tip node (offsets[n], the last element's frame): each point force
        F_k = tau (t_k - t_(k-1)) goes half to each node of its element (half to none at the
        tip), its moment (Q^T r) x F to the element's torque (in the material frame)."""
        n = directors.shape[2]
        points = np.empty((3, n + 1))
        arms = np.empty((3, n + 1))
        for k in range(n + 1):
            e = k if k < n else n - 1
            for i in range(3):
                arm = 0.0
                for j in range(3):
                    arm += directors[j, i, e] * offsets[k, j]
                arms[i, k] = arm
                base = 0.5 * (positions[i, k] + positions[i, k + 1]) if k < n \
                    else positions[i, n]
                points[i, k] = base + arm
        previous = np.zeros(3)
        for k in range(n + 1):
            current = np.zeros(3)
            if k < n:
                segment = points[:, k + 1] - points[:, k]
                current = segment / np.sqrt(np.sum(segment * segment))
            force = tau * (current - previous)
            previous = current
            if k < n:
                forces[:, k] += 0.5 * force
                forces[:, k + 1] += 0.5 * force
            else:
                forces[:, n] += force
            e = k if k < n else n - 1
            arm = arms[:, k]
            moment = np.array([arm[1] * force[2] - arm[2] * force[1],
                               arm[2] * force[0] - arm[0] * force[2],
                               arm[0] * force[1] - arm[1] * force[0]])
            for i in range(3):
                local = 0.0
                for j in range(3):
                    local += directors[i, j, e] * moment[j]
                torques[i, e] += local

    return tendon_loads


def finger_rod_settings(elements: int, damping: float = 2.5, ramp: float = 0.02,
                        final_time: float = 2.0):
    return RodSettings(elements=elements, slenderness=F_L / (F_D / 2), shear_ratio=F_G / F_E,
                       cfl=0.5, damping=damping, ramp=ramp, final_time=final_time)


def build_finger_rod(s, kernel):
    """The finger as a PyElastica rod (bench_pyelastica's clamp half an element behind x = 0,
    so that element 0's centre is at s = 0, the tendon's entry), the tendon as forces."""

    class Simulator(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
        pass

    class TendonForces(ea.NoForces):
        """The tendon's loads on the current shape, recomputed at every step (tension ramped
        over ``ramp``)."""

        def __init__(self, tension, offsets, ramp):
            super().__init__()
            self.tension, self.offsets, self.ramp = tension, offsets, ramp

        def apply_forces(self, system, time=0.0):
            factor = min(1.0, float(time) / self.ramp) if self.ramp > 0 else 1.0
            kernel(self.tension * factor, system.position_collection,
                   system.director_collection, self.offsets, system.external_forces,
                   system.external_torques)

        def apply_torques(self, system, time=0.0):
            pass  # added with the forces

    dl = F_L / (s.elements - 0.5)
    rho, E = F_RHO, F_E
    simulator = Simulator()
    # directors: d1 = e_y (fe_beam's h direction), d2 = e_z, d3 = e_x (the tangent)
    rod = ea.CosseratRod.straight_rod(
        s.elements, np.array([-0.5 * dl, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]),
        np.array([0.0, 1.0, 0.0]), F_L + 0.5 * dl, F_D / 2, rho, youngs_modulus=E,
        shear_modulus=F_G)
    rod.shear_matrix[2, 2, :] *= AXIAL_FACTOR  # nearly inextensible
    simulator.append(rod)
    simulator.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,),
                                   constrained_director_idx=(0,))
    stations = np.append(np.arange(s.elements) * dl, F_L)
    y, z = helix(stations)
    offsets = np.ascontiguousarray(np.stack([y, z, np.zeros_like(y)], axis=1))
    A, inertia = math.pi * F_D**2 / 4, math.pi * F_D**4 / 64
    omega1 = 1.875**2 * math.sqrt(E * inertia / (rho * A * F_L**4))
    period = 2 * math.pi / omega1
    dt = s.cfl * min(dl, F_D * math.sqrt(F_E / (2 * F_G))) / math.sqrt(AXIAL_FACTOR * E / rho)
    steps = math.ceil(s.final_time * period / dt)
    dt = s.final_time * period / steps
    simulator.add_forcing_to(rod).using(TendonForces, F_TENSION, offsets, s.ramp * period)
    simulator.dampen(rod).using(ea.AnalyticalLinearDamper,
                                uniform_damping_constant=s.damping * omega1, time_step=dt)
    simulator.finalize()
    return simulator, rod, period, dt, steps


def settle_finger(s, kernel, exact, tol, check=0.02) -> dict:
    simulator, rod, period, dt, steps = build_finger_rod(s, kernel)
    stepper, t = ea.PositionVerlet(), np.float64(0.0)
    per_check = max(1, round(check * period / dt))
    settled, done, error = None, 0, math.inf
    while done < steps:
        for _ in range(per_check):
            t = stepper.step(simulator, t, np.float64(dt))
        done += per_check
        error = float(np.linalg.norm(rod.position_collection[:, -1] - exact) / F_L)
        if not error < 1.0:
            return {"settle_time": None, "error": math.inf}
        settled = (settled or done) if error < tol else None
    return {"settle_time": settled * dt / period if settled else None, "error": error}


def run_finger_rod(s, kernel) -> dict:
    started = time.perf_counter()
    simulator, rod, period, dt, steps = build_finger_rod(s, kernel)
    built = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        ea.integrate(ea.PositionVerlet(), simulator, s.final_time * period, steps,
                     progress_bar=False)
    done = time.perf_counter()
    return {"tip": rod.position_collection[:, -1].copy(), "wall_s": done - started,
            "integrate_s": done - built, "steps": steps}


def pyelastica_finger_settings(tol, kernel, exact, log) -> object:
    """The fewest elements (of a short list) whose rod settles within ``tol`` and whose rod
    with twice the elements does too (bench_pyelastica's guard), then the best of a few
    dampings; final time = the settling time."""
    for n in (6, 8, 12, 16, 24, 32, 48, 64):
        result = settle_finger(finger_rod_settings(n), kernel, exact, tol)
        log.append({"elements": n, "damping": 2.5} | result)
        if result["settle_time"] is None:
            continue
        guard = settle_finger(finger_rod_settings(2 * n), kernel, exact, tol)
        log.append({"elements": 2 * n, "guard_of": n} | guard)
        if guard["settle_time"] is None:
            continue
        best = (result["settle_time"], 2.5)
        for damping in (1.5, 2.0, 3.0, 3.5):
            trial = settle_finger(finger_rod_settings(n, damping=damping), kernel, exact, tol)
            log.append({"elements": n, "damping": damping} | trial)
            if trial["settle_time"] is not None and trial["settle_time"] < best[0]:
                best = (trial["settle_time"], damping)
        return finger_rod_settings(n, damping=best[1],
                                   final_time=math.ceil(best[0] * 100) / 100)
    return None


class FeFingerFromRest:
    """A built `RealtimeSolver` of the finger moved from tension 0 to the tension."""

    def __init__(self, n: int):
        self.solver = RealtimeSolver(fe_finger_config(n, tension=0.0))

    def __call__(self) -> float:
        self.solver.update(tensions=[0.0])
        return timed(lambda: self.solver.update(tensions=[F_TENSION]))[0]


def finger_versus_pyelastica(tol: float, repeats: int) -> dict:
    exact = finger_model_reference()
    n, fe_error = fe_finger_cheapest(tol, exact)
    entry = {"tolerance": tol, "tension": F_TENSION, "reference_tip": exact.tolist(),
             "fe_beam": {"elements": n, "degree": 2, "tip_error_over_L": fe_error}}
    print(f"\nfinger vs PyElastica, {tol:g} L (tension {F_TENSION:g} N; reference tip "
          f"{exact.round(6)}): fe_beam {n} degree-2 elements, tip error {fe_error:.2e} L")
    kernel = _tendon_kernel()
    run_finger_rod(finger_rod_settings(8, final_time=0.01), kernel)  # numba JIT
    log = []
    settings = pyelastica_finger_settings(tol, kernel, exact, log)
    entry["pyelastica_search"] = log
    if settings is None:
        entry["pyelastica"] = {"status": "no setting of the list reached the tolerance"}
        return entry
    solve_only = StaticContinuation(fe_finger_config(n), MPI.COMM_WORLD)

    def fe_solve() -> float:
        solve_only.restart()
        return timed(lambda: solve_only.advance(1.0, LoadStepping(steps=FE_STEPS)))[0]

    def fe_build() -> float:
        def run():
            continuation = StaticContinuation(fe_finger_config(n), MPI.COMM_WORLD)
            continuation.advance(1.0, LoadStepping(steps=FE_STEPS))
            continuation.destroy()
        return timed(run)[0]

    from_rest = FeFingerFromRest(n)
    fe_runs = {"fe_beam solve (built problem)": fe_solve,
               "fe_beam RealtimeSolver from rest": from_rest, "fe_beam build + solve": fe_build}
    for run in fe_runs.values():
        run()
    times = {"PyElastica build + integrate": [], "PyElastica integrate only": []}
    times |= {name: [] for name in fe_runs}
    for _ in range(repeats):
        rod = run_finger_rod(settings, kernel)
        times["PyElastica build + integrate"].append(rod["wall_s"])
        times["PyElastica integrate only"].append(rod["integrate_s"])
        for name, run in fe_runs.items():
            times[name].append(run())
    rod_error = float(np.linalg.norm(rod["tip"] - exact) / F_L)
    solve_only.destroy()
    rest_tip = np.array(from_rest.solver.problem.end_values()["position"])
    entry["fe_beam"]["from_rest_tip_error_over_L"] = float(
        np.linalg.norm(rest_tip - exact) / F_L)
    entry["fe_beam"]["from_rest_statistics"] = dict(from_rest.solver.statistics)
    from_rest.solver.close()
    reference_times = times["PyElastica build + integrate"]
    entry["pyelastica"] = {"settings": asdict(settings), "steps": rod["steps"],
                           "tip_error_over_L": rod_error, "within_tolerance": rod_error < tol}
    entry["times"] = {name: stats(t) for name, t in times.items()}
    entry["speedup_vs_pyelastica"] = {
        name: statistics.median(p / f for p, f in zip(reference_times, times[name], strict=True))
        for name in fe_runs}
    rows = [[name, rod_error if name.startswith("PyElastica build") else
             fe_error if name.startswith("fe_beam solve (") else
             entry["fe_beam"]["from_rest_tip_error_over_L"] if "rest" in name else "",
             statistics.median(t),
             min(t), f"{entry['speedup_vs_pyelastica'][name]:.1f}x"
             if name in entry["speedup_vs_pyelastica"] else ""] for name, t in times.items()]
    print(f"PyElastica: {settings.elements} elements, damping {settings.damping:g} omega_1, "
          f"{settings.final_time:g} T1, {rod['steps']} steps")
    print(table(["code", "tip error / L", "median s", "min s", "PyElastica / this"], rows))
    return entry


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--updates", type=int, default=500)
    parser.add_argument("--tolerance", type=float, nargs="+", default=[1e-3, 1e-4])
    parser.add_argument("--finger-tolerance", type=float, nargs="+", default=[1e-3])
    parser.add_argument("--no-finger-pyelastica", action="store_true")
    args = parser.parse_args(argv)
    exact = reference()
    print(f"reference (shooting, inextensible-unshearable): tip r(L) = {exact.round(6)}; "
          f"k = {K:g}, force at 30 degrees out of the x-y plane")
    data = {"status": "ok", "machine": machine(), "k": K, "force_direction": DIRECTION.tolist(),
            "reference_tip": exact.tolist(), "cantilever": {}}
    if ea is None:
        message = (f"PyElastica is not available ({IMPORT_ERROR}); install it with "
                   "`python -m pip install -c constraints.txt \"pyelastica==1.0.0\"`; "
                   "timing fe_beam alone")
        print(message, file=sys.stderr)
        data["pyelastica"] = {"status": "unavailable", "reason": message}
    else:
        data["pyelastica"] = {"status": "ok", "version": ELASTICA_VERSION}
        run_rod(replace(CHOSEN["1e-3"], final_time=0.01))  # numba JIT
    for tol in args.tolerance:
        label = tolerance_label(tol)
        n, fe_error = fe_cheapest(tol, exact)
        print(f"\n{label} L: fe_beam {n} degree-2 elements, tip error {fe_error:.2e} L")
        solve_only = FeSolveOnly(n)
        from_rest = FeFromRest(n)
        fe_runs = {"fe_beam solve (built problem)": solve_only,
                   "fe_beam RealtimeSolver from rest": from_rest,
                   "fe_beam build + solve": lambda n=n: fe_build_and_solve(n),
                   "fe_beam solve_static (cached)": lambda n=n: fe_solve_static(n)}
        for run in fe_runs.values():
            run()  # warm up (JIT, caches)
        times = {name: [] for name in fe_runs}
        entry = {"fe_beam": {"elements": n, "degree": 2, "load_steps": FE_STEPS,
                             "tip_error_over_L": fe_error}}
        settings = None
        if ea is not None and label in CHOSEN:
            settings = pyelastica_settings(tol)
            times = {"PyElastica build + integrate": [], "PyElastica integrate only": []} | times
            rod_error = math.nan
        for _ in range(args.repeats):  # alternating: the same machine load for all
            if settings is not None:
                rod = run_rod(settings)
                rod_error = float(np.linalg.norm(rod["tip"] - exact) / LENGTH)
                times["PyElastica build + integrate"].append(rod["wall_s"])
                times["PyElastica integrate only"].append(rod["integrate_s"])
            for name, run in fe_runs.items():
                times[name].append(run())
        solve_only.run.destroy()
        entry["fe_beam"]["from_rest_tip_error_over_L"] = float(
            np.linalg.norm(from_rest.tip() - exact) / LENGTH)
        entry["fe_beam"]["from_rest_statistics"] = dict(from_rest.solver.statistics)
        from_rest.solver.close()
        entry["times"] = {name: stats(t) for name, t in times.items()}
        rows = []
        if settings is not None:
            reference_times = times["PyElastica build + integrate"]
            entry["pyelastica"] = {"settings": asdict(settings), "steps": settings.steps,
                                   "time_step": settings.time_step,
                                   "tip_error_over_L": rod_error,
                                   "within_tolerance": bool(rod_error < tol)}
            entry["speedup_vs_pyelastica"] = {
                name: statistics.median(p / f for p, f in zip(reference_times, times[name],
                                                                strict=True))
                for name in fe_runs}
            if not rod_error < tol:
                print(f"warning: PyElastica misses {label} L (error {rod_error:.2e} L)",
                      file=sys.stderr)
        for name, t in times.items():
            error = (rod_error if name.startswith("PyElastica build") else
                     fe_error if name.startswith("fe_beam solve (") else
                     entry["fe_beam"]["from_rest_tip_error_over_L"] if "rest" in name else "")
            ratio = entry.get("speedup_vs_pyelastica", {}).get(name)
            rows.append([name, error, statistics.median(t), min(t),
                         f"{ratio:.1f}x" if ratio else ""])
        print(table(["code", "tip error / L", "median s", "min s", "PyElastica / this"], rows))
        data["cantilever"][label] = entry
    print("\nspatial finger, RealtimeSolver (tau = 1.5 + 0.5 sin(2 pi t), 1 kHz):")
    finger = finger_benchmark(args.updates, max(1, args.repeats // 2 + 1))
    for name, run in finger["runs"].items():
        print(f"  {name}: {run['median_wall_ms']:.3f} ms median wall (min of runs "
              f"{run['min_wall_ms']:.3f}), {run['cpu_ms']:.3f} ms CPU, "
              f"{run['newton_per_update']:.2f} Newton/update, {run['fallbacks']} fallbacks")
    print(f"  tip vs shooting / L: {finger['tip_error_vs_shooting_over_L']}")
    data["finger_realtime"] = finger
    if ea is not None and not args.no_finger_pyelastica:
        data["finger_pyelastica"] = {tolerance_label(tol): finger_versus_pyelastica(
            tol, args.repeats) for tol in args.finger_tolerance}
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / "spatial_pyelastica.json"
    path.write_text(json.dumps(data, indent=1, default=float) + "\n")
    print(f"results: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

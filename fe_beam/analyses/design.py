"""Design (`fe-beam design CONFIG.toml --out DIR`): choose section sizes, tendon offsets,
tensions or loads so that the rod reaches a target, by SLSQP (scipy) with gradients.

The configuration is a rod's (`fe-beam static`) or, with ``[[tendons]]``, a finger's
(`fe-beam finger`), plus::

    [design]
    variables = ["section.h_tip", "tendons.0.offset_tip"]   #
    fe_beam.solvers.realtime.PARAMETER_KEYS
    bounds = [[0.005, 0.02], [0.0, 0.008]]                  # one [low, high] per variable
    # (or a table: bounds = {"section.h_tip" = [0.005, 0.02], ...})
    objective = "tip_pose"        # "tip_pose" | "backbone" | "tension"
    target = {theta = 0.8}        # tip_pose: any of u, v [m], theta [rad]
    # backbone: points = [[s, x, y], ...]: the point at reference arclength s (a mesh vertex)
    #           should be at (x, y) [m]
    # tension:  tip_angle = 0.8: minimise |the one force-like variable| (tendons.<i>.tension,
    #           loads.tip_moment, loads.tip_force.<k>) with the tip angle held at tip_angle
    max_fibre_strain = 0.05       # optional constraint: |eps| + h/2 |kappa| <= this everywhere
    max_iterations = 100
    # grasp_force (with [[obstacles]]): one variable, target = {obstacle = "<name>", force = F}
    #           (or normal = F) [N] at load factor 1, tolerance [N] (default 1e-3 F)

Objectives are made dimensionless: tip_pose = sum over the given components of
((value - target) / scale)^2, scale L for u, v and 1 rad for theta; backbone = the mean of
|r(s_i) - target_i|^2 / L^2; tension = |value| / max(|low|, |high|) of its bounds. Variables
are scaled to [0, 1] by their bounds for the optimiser.

Gradients: central finite differences of equilibria of one `fe_beam.solvers.realtime.RealtimeSolver`
(warm-started, Newton to rtol 1e-12), step 1e-6 of each variable's range (``"gradient":
"finite-difference"`` in summary.json). The adjoint sensitivities of issue 14 item 1 go
behind the same function (`gradients`) when they are available.

summary.json: ``status``, ``message``, ``variables`` ({key: optimum}), ``initial``,
``objective`` ({kind, value}), ``constraints`` ({name: value}, >= 0 feasible for
inequalities, 0 for equalities), ``kkt_residual`` and ``kkt`` (stationarity, feasibility,
dual sign, complementarity, multipliers; scaled variables), ``iterations``, ``evaluations``,
``gradient``, ``tip``, ``history``, ``wall_time_s``, ``reproduce`` (the command line that
re-runs the answer: `fe-beam finger` or `static` on the file with one ``--set`` per variable).
Plot: design.png (initial and optimal
shapes, targets).

Grasp force (``objective = "grasp_force"``, `grasp_design`): no gradient. The grasp force of
a trial is that of the converged contact state of the load stepping of ``fe-beam finger`` (or
``static``) from the straight rod (`GraspEvaluator`: `solve_static`), a non-smooth function of
the one variable (active sets, Uzawa stops); the bounds (or 6 points across them) bracket
F - target, Brent's method finds a trial within ``tolerance``; the answer is re-solved with
the penetration tolerance / GRASP_TIGHTER and must meet the target there too (the force moves
with the penetration the contact keeps). A target outside the forces reached, a force
jumping across it, or one met at the given penetration tolerance only, is status "not
converged" (exit 3). summary.json then
has ``grasp`` ({obstacle, component, target, tolerance, value, initial, contact,
contact_check}),
``checks`` (a met design: ``grasp_force_target``, the design re-solved afresh at its answer
within the tolerance of the target, and that state's static certificates, `grasp_checks`),
``kkt_residual``/``kkt`` null and ``gradient`` "none (bracketing root solve)". The other
objectives refuse ``[[obstacles]]`` (exit 2): their gradients do not see contact.

Validation (`fe_beam.config.design.parse_design`, imported back here) imports no FE code: a bad
[design] table is a ConfigError (exit 2, one sentence).
"""

from __future__ import annotations

import copy
import math
import re
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from fe_beam import analyses, certify
from fe_beam.analyses.certificates import equilibrium_entry
from fe_beam.analyses.result import Report, Result, failed, fit_report, world
from fe_beam.analyses.static import solve_static
from fe_beam.config.design import (
    DesignProblem,
    parse_design,
    reproduce_command,
)
from fe_beam.config.finger import parse_finger, with_defaults
from fe_beam.config.schema import parse_static, with_rod_sections
from fe_beam.errors import ConfigError, UpdateFailed
from fe_beam.exports.outputs import BeamXDMFWriter, _pyplot, atomic_write_json, draw_obstacles
from fe_beam.model.settings import SolverSettings
from fe_beam.solvers.realtime import RealtimeSolver, max_fibre_strain, set_parameters, structure_key

__all__ = ["run", "DesignProblem", "parse_design", "run_design"]

FD_STEP = 1e-6  # of each variable's range
DESIGN_RTOL = 1e-12


# --- evaluation ----------------------------------------------------------------------------------
def _check_in_place(design: DesignProblem, config, comm) -> None:
    """Every variable must change numbers held by Constants only (one solver for all
    evaluations): a custom section's dimensions (its height sqrt(12 I / A)) and those of a
    hyperelastic section rule are compiled into the forms. ConfigError naming the variable."""
    base = structure_key(config, comm)
    for key, initial, (low, high) in zip(design.variables, design.initial, design.bounds,
                                         strict=True):
        try:
            changed = set_parameters(config, {key: high if high != initial else low})
        except (KeyError, ValueError):
            continue  # reported by the solver with its own message
        if structure_key(changed, comm) != base:
            raise ConfigError(f"[design] variables: {key!r} cannot be a design variable of "
                              "this model (a custom section's or a hyperelastic section rule's "
                              "dimensions are compiled into its forms); use a closed-form "
                              "section shape (rectangle, circle, tube, t-section)")


class Evaluator:
    """Objective and constraints of a design at scaled variables t in [0, 1]^n, from one
    `RealtimeSolver` (each evaluation warm-started from the last equilibrium)."""

    def __init__(self, design: DesignProblem, config, comm, raw: dict | None = None):
        """``raw``: the configuration's TOML tables (without [design]): with it, gradients
        come from the adjoint sensitivities (`fe_beam.analyses.sensitivity`) when that module is
        installed and supports the variables and outputs."""
        from dataclasses import replace


        self.design = design
        _check_in_place(design, config, comm)
        solver = replace(config.solver, rtol=min(config.solver.rtol, DESIGN_RTOL))
        self.config = replace(config, solver=solver)
        self.comm = comm
        self.length = float(config.model.length)
        self.solver = RealtimeSolver(self.config, comm)
        self.evaluations = 0
        self._cache: dict = {}
        self.adjoint = _adjoint_model(design, raw, comm) if raw is not None else None
        if design.objective == "backbone":
            for s, _, _ in design.points:
                try:
                    self.solver.problem.point_values(s)
                except RuntimeError:
                    raise ConfigError(f"[design] points: s = {s:g} is not a mesh vertex (use "
                                      "vertices of the uniform mesh, s = k L / elements)"
                                      ) from None

    def values(self, t: np.ndarray) -> dict:
        return dict(zip(self.design.variables, self.x(t), strict=True))

    def x(self, t: np.ndarray) -> np.ndarray:
        low, high = self.design.bounds.T
        return low + np.asarray(t, dtype=float) * (high - low)

    def evaluate(self, t: np.ndarray) -> dict:
        """{"objective": f, "inequality": [...], "equality": [...], "tip": {...}}."""
        key = tuple(np.round(np.asarray(t, dtype=float), 15))
        if key in self._cache:
            return self._cache[key]
        self.solver.update(parameters=self.values(t))
        self.evaluations += 1
        problem, design = self.solver.problem, self.design
        tip = self.solver.tip()
        if design.objective == "tip_pose":
            scale = {"u": self.length, "v": self.length, "theta": 1.0}
            f = sum(((tip[k] - v) / scale[k]) ** 2 for k, v in design.target.items())
        elif design.objective == "backbone":
            total = 0.0
            for s, x, y in design.points:
                p = problem.point_values(s)
                total += ((s + p["u"] - x) ** 2 + (p["v"] - y) ** 2) / self.length**2
            f = total / len(design.points)
        else:
            i = design.force_variable
            f = abs(self.x(t)[i]) / np.max(np.abs(design.bounds[i]))
        inequality, equality = [], []
        if design.max_fibre_strain is not None:
            inequality.append(1.0 - max_fibre_strain(problem) / design.max_fibre_strain)
        if design.objective == "tension":
            equality.append(tip["theta"] - design.tip_angle)
        result = {"objective": float(f), "inequality": inequality, "equality": equality,
                  "tip": tip}
        self._cache[key] = result
        return result

    def close(self) -> None:
        self.solver.close()
        if self.adjoint is not None:
            self.adjoint.destroy()
            self.adjoint = None


def _adjoint_key(key: str) -> str:
    """A design variable's name among the sensitivity module's parameters."""
    parts = key.split(".")
    if parts[0] == "tendons" and len(parts) == 4 and parts[2] == "path":
        return f"{key}.1"  # the offset (second coordinate) of path point j
    return key


def _adjoint_model(design: DesignProblem, raw: dict, comm):
    """A `fe_beam.analyses.sensitivity.RodSensitivity` for the design's variables, or None (module
    not
    installed, or it refuses a variable): the gradients are then finite differences. The
    fibre-strain constraint is not one of its outputs: None too."""
    if design.max_fibre_strain is not None:
        return None
    try:
        sensitivity = analyses.sensitivity
    except ImportError:
        return None
    try:
        return sensitivity.RodSensitivity(raw, [_adjoint_key(k) for k in design.variables], comm)
    except (ConfigError, ValueError, KeyError):
        return None


def _adjoint_gradients(evaluator: Evaluator, t: np.ndarray) -> dict:
    """d(objective, equality)/dt from adjoint gradients of the outputs the objective uses."""
    design, model = evaluator.design, evaluator.adjoint
    x = evaluator.x(t)
    model.set_values(x)
    model.solve(1.0)
    scale_t = design.bounds[:, 1] - design.bounds[:, 0]  # dx/dt
    n = len(t)
    grads = {"objective": np.zeros(n), "inequality": np.zeros((0, n)),
             "equality": np.zeros((0, n))}
    if design.objective == "tip_pose":
        names = [f"tip_{k}" for k in design.target]
        values, jac = model.outputs(names), model.gradient(names)
        scale = {"u": evaluator.length, "v": evaluator.length, "theta": 1.0}
        for (k, target), value, row in zip(design.target.items(), values, jac, strict=True):
            grads["objective"] += 2 * (value - target) / scale[k] ** 2 * row
    elif design.objective == "backbone":
        names = [f"{c}@{s!r}" for s, _, _ in design.points for c in ("x", "y")]
        values, jac = model.outputs(names), model.gradient(names)
        targets = [v for _, x_t, y_t in design.points for v in (x_t, y_t)]
        for value, target, row in zip(values, targets, jac, strict=True):
            grads["objective"] += 2 * (value - target) / evaluator.length**2 * row
        grads["objective"] /= len(design.points)
    else:
        i = design.force_variable
        grads["objective"][i] = np.sign(x[i]) / np.max(np.abs(design.bounds[i]))
        grads["equality"] = model.gradient(["tip_theta"])
    # d/dx -> d/dt
    grads["objective"] = grads["objective"] * scale_t
    grads["equality"] = grads["equality"] * scale_t[None, :]
    return grads


def gradients(evaluator: Evaluator, t: np.ndarray) -> tuple[dict, str]:
    """d(objective, constraints)/dt at t, and how they were computed: "adjoint" (the
    sensitivity module's exact gradients of the outputs, when available: `_adjoint_model`)
    or "finite-difference" (central differences, step FD_STEP of each variable's range,
    inside [0, 1])."""
    t = np.asarray(t, dtype=float)
    if evaluator.adjoint is not None:
        return _adjoint_gradients(evaluator, t), "adjoint"
    base = evaluator.evaluate(t)
    n = len(t)
    grads = {"objective": np.zeros(n),
             "inequality": np.zeros((len(base["inequality"]), n)),
             "equality": np.zeros((len(base["equality"]), n))}
    for i in range(n):
        h = FD_STEP
        up, down = t.copy(), t.copy()
        up[i] = min(t[i] + h, 1.0)
        down[i] = max(t[i] - h, 0.0)
        a, b = evaluator.evaluate(up), evaluator.evaluate(down)
        width = up[i] - down[i]
        grads["objective"][i] = (a["objective"] - b["objective"]) / width
        for kind in ("inequality", "equality"):
            if len(base[kind]):
                grads[kind][:, i] = (np.array(a[kind]) - np.array(b[kind])) / width
    evaluator.evaluate(t)  # back to t (cached: no solve) for the caller
    return grads, "finite-difference"


def kkt(evaluator: Evaluator, t: np.ndarray, active_tol: float = 1e-7) -> dict:
    """First-order optimality at t (scaled variables): multipliers of the equality and active
    inequality constraints and the active bounds by least squares on
    grad f = sum lambda_i grad c_i + mu (bounds); residuals of stationarity (inf-norm),
    primal feasibility, dual sign (inequality lambda >= 0, lower-bound mu >= 0, upper-bound
    mu <= 0) and complementarity; kkt_residual = the largest."""
    values = evaluator.evaluate(t)
    grads, _ = gradients(evaluator, t)
    n = len(t)
    columns, kinds = [], []
    for j, g in enumerate(grads["equality"]):
        columns.append(g)
        kinds.append(("equality", j))
    for j, (c, g) in enumerate(zip(values["inequality"], grads["inequality"], strict=True)):
        if c <= active_tol:
            columns.append(g)
            kinds.append(("inequality", j))
    for i in range(n):
        if t[i] <= active_tol:
            columns.append(np.eye(n)[i])
            kinds.append(("lower", i))
        elif t[i] >= 1 - active_tol:
            columns.append(np.eye(n)[i])
            kinds.append(("upper", i))
    g = grads["objective"]
    if columns:
        matrix = np.array(columns).T
        multipliers, *_ = np.linalg.lstsq(matrix, g, rcond=None)
        stationarity = float(np.max(np.abs(g - matrix @ multipliers)))
    else:
        multipliers, stationarity = np.zeros(0), float(np.max(np.abs(g)))
    sign = 0.0
    for (kind, _), value in zip(kinds, multipliers, strict=True):
        if kind in ("inequality", "lower"):
            sign = max(sign, -value)
        elif kind == "upper":
            sign = max(sign, value)
    feasibility = max([abs(c) for c in values["equality"]]
                      + [max(-c, 0.0) for c in values["inequality"]]
                      + [max(-t.min(), 0.0), max(t.max() - 1, 0.0)], default=0.0)
    complementarity = max([abs(c) * abs(m) for (kind, _), m, c in (
        (k, m, values["inequality"][k[1]]) for k, m in zip(kinds, multipliers, strict=True)
        if k[0] == "inequality")], default=0.0)
    return {
        "stationarity": stationarity, "primal_feasibility": float(feasibility),
        "dual_sign": float(sign), "complementarity": float(complementarity),
        "active": [f"{kind} {evaluator.design.variables[i] if kind in ('lower', 'upper') else i}"
                   for kind, i in kinds],
        "multipliers": [float(m) for m in multipliers],
        "kkt_residual": float(max(stationarity, feasibility, sign, complementarity)),
    }


def optimise(design: DesignProblem, config, comm, raw: dict | None = None) -> dict:
    """SLSQP on the scaled variables; the summary's content (see the module docstring)."""
    from scipy.optimize import minimize

    started = time.perf_counter()
    evaluator = Evaluator(design, config, comm, raw)
    low, high = design.bounds.T
    t0 = (design.initial - low) / (high - low)
    history = []
    gradient_kind = ["finite-difference"]

    def objective(t):
        return evaluator.evaluate(t)["objective"]

    def objective_gradient(t):
        grads, gradient_kind[0] = gradients(evaluator, t)
        return grads["objective"]

    def record(t):
        values = evaluator.evaluate(t)
        history.append({"variables": {k: float(v) for k, v in evaluator.values(t).items()},
                        "objective": values["objective"]})

    constraints = []
    if design.max_fibre_strain is not None:
        constraints.append({"type": "ineq",
                            "fun": lambda t: np.array(evaluator.evaluate(t)["inequality"]),
                            "jac": lambda t: gradients(evaluator, t)[0]["inequality"]})
    if design.objective == "tension":
        constraints.append({"type": "eq",
                            "fun": lambda t: np.array(evaluator.evaluate(t)["equality"]),
                            "jac": lambda t: gradients(evaluator, t)[0]["equality"]})
    initial = evaluator.evaluate(t0)
    record(t0)
    try:
        result = minimize(objective, t0, jac=objective_gradient, method="SLSQP",
                          bounds=[(0.0, 1.0)] * len(t0), constraints=constraints,
                          callback=record,
                          options={"maxiter": design.max_iterations, "ftol": 1e-14})
        t = np.clip(result.x, 0.0, 1.0)
        final = evaluator.evaluate(t)
        conditions = kkt(evaluator, t)
        status = "converged" if result.success else "not converged"
        message = str(result.message)
        iterations = int(result.nit)
        # SLSQP may stop on its line search with a point that is optimal to the accuracy of
        # the gradients: the KKT residual decides
        if not result.success and conditions["kkt_residual"] <= 1e-6:
            status = "converged"
            message += " (the KKT conditions hold to 1e-6)"
        shape = _shape(evaluator)
        evaluator.solver.update(parameters=evaluator.values(t0))
        start_shape = _shape(evaluator)
        evaluator.solver.update(parameters=evaluator.values(t))
        check = _answer_equilibrium(evaluator)
    finally:
        evaluator.close()
    names = []
    if design.max_fibre_strain is not None:
        names.append("max_fibre_strain")
    summary = {
        "status": status,
        "message": message,
        "variables": {k: float(v) for k, v in evaluator.values(t).items()},
        "initial": {k: float(v) for k, v in evaluator.values(t0).items()},
        "bounds": {k: [float(a), float(b)] for k, (a, b) in zip(design.variables,
                                                                design.bounds, strict=True)},
        "objective": {"kind": design.objective, "value": final["objective"],
                      "initial": initial["objective"]} | _minimised(design, evaluator, t, t0),
        "constraints": _constraint_summary(design, final),
        "kkt_residual": conditions["kkt_residual"],
        "kkt": conditions,
        "iterations": iterations,
        "evaluations": evaluator.evaluations,
        "gradient": gradient_kind[0],
        "tip": final["tip"],
        "history": history,
        "wall_time_s": time.perf_counter() - started,
        "notes": _target_notes(design, final, conditions) + _gradient_notes(
            design, gradient_kind[0]),
        "checks": [check],
    }
    return summary | {"_shapes": (start_shape, shape)}


def _answer_equilibrium(evaluator) -> dict:
    """The global equilibrium of the design's answer (the solver's current state) as a check:
    the reactions, the loads, the tendons (internal) and the contact forces balance
    (`fe_beam.analyses.certificates.equilibrium_entry`). Collective."""
    solver, config = evaluator.solver, evaluator.config
    contact = solver.contact.summary() if solver.contact is not None else None
    # the trial solves' tightened rtol (DESIGN_RTOL) does not tighten what SNES's step test
    # lets through: judge the answer as a static run of the default tolerance would be
    return equilibrium_entry(
        solver.problem, max(config.solver.rtol, SolverSettings().rtol), contact,
        "at the design's answer",
        tensions=solver.tension_values(),
        contact_tolerance=config.contact.force_tolerance if config.obstacles else 0.0)


def _minimised(design: DesignProblem, evaluator, t, t0) -> dict:
    """objective = "tension": the minimised variable itself (the objective's value is it
    divided by its largest bound, the scale SLSQP works in)."""
    if design.objective != "tension":
        return {}
    i = design.force_variable
    return {"minimised": {"name": design.variables[i], "value": float(evaluator.x(t)[i]),
                          "initial": float(evaluator.x(t0)[i]),
                          "scale": float(np.max(np.abs(design.bounds[i])))}}


def _gradient_notes(design: DesignProblem, kind: str) -> list[str]:
    """Finite-difference gradients where adjoint ones would otherwise be used: said."""
    if design.max_fibre_strain is None or kind != "finite-difference":
        return []
    n = len(design.variables)
    return [f"[design] max_fibre_strain: the gradients are central finite differences (step "
            f"{FD_STEP:g} of each variable's range, {2 * n} extra equilibria per gradient): the "
            "fibre-strain constraint is not an output of the adjoint sensitivities"]


TARGET_TOLERANCE = 1e-10  # dimensionless objective: a miss of 1e-5 L (or 1e-5 rad)


def _target_notes(design: DesignProblem, values: dict, conditions: dict) -> list[str]:
    """A tip_pose or backbone target that the optimum does not reach (the optimum of the
    misfit within the bounds and constraints is then not the wanted shape): one note naming
    the miss and what stops it."""
    if design.objective not in ("tip_pose", "backbone") or not (
            values["objective"] > TARGET_TOLERANCE):
        return []
    if design.objective == "tip_pose":
        units = {"u": "m", "v": "m", "theta": "rad"}
        miss = ", ".join(f"tip {k} = {values['tip'][k]:.6g} {units[k]} (target {v:.6g})"
                         for k, v in design.target.items())
    else:
        miss = f"rms distance to the target points {math.sqrt(values['objective']):.3g} L"
    limits = [a for a in conditions.get("active", []) if not a.startswith("equality")]
    why = (f"; active: {', '.join(limits)}" if limits else
           " (no bound or constraint is active: a local minimum of the misfit)")
    return [f"the target is not reached: {miss}{why}"]


def _constraint_summary(design: DesignProblem, values: dict) -> dict:
    out = {}
    if design.max_fibre_strain is not None:
        margin = values["inequality"][0]
        out["max_fibre_strain"] = {"limit": design.max_fibre_strain,
                                   "value": design.max_fibre_strain * (1 - margin),
                                   "margin": margin}
    if design.objective == "tension":
        out["tip_angle"] = {"target": design.tip_angle,
                            "value": values["tip"]["theta"],
                            "residual": values["equality"][0]}
    return out


def _shape(evaluator: Evaluator):

    problem = evaluator.solver.problem
    writer = BeamXDMFWriter(problem, None)
    try:
        values = writer.vertex_values()
    finally:
        writer.close()
    chain = getattr(problem, "chain", None)
    return values if chain is None else chain.shape(values)  # a chain: drawn in the plane


def _plot(out: Path, summary: dict, shapes, design: DesignProblem, length: float,
          obstacles=(), tip=None) -> None:
    """``tip``: the reference position of the tip ((length, 0) of a rod)."""
    tip = (length, 0.0) if tip is None else tip

    plt = _pyplot()
    figure, axis = plt.subplots(figsize=(6, 5))
    for shape, label, style in ((shapes[0], "initial", "--"), (shapes[1], "optimum", "-")):
        if shape is not None:
            order = np.argsort(shape["x"])
            axis.plot((shape["x"] + shape["u"])[order], shape["v"][order], style, lw=2,
                      label=label)
    if design.objective == "backbone":
        points = np.array(design.points)
        axis.plot(points[:, 1], points[:, 2], "kx", ms=8, label="target points")
    if design.objective == "tip_pose" and {"u", "v"} <= set(design.target):
        axis.plot(tip[0] + design.target["u"], tip[1] + design.target["v"], "kx", ms=8,
                  label="target tip")
    if obstacles:
        draw_obstacles(axis, obstacles, [(None, s) for s in shapes if s is not None], length)
    axis.set_aspect("equal", adjustable="datalim")
    axis.set_xlabel("x [m]")
    axis.set_ylabel("y [m]")
    text = "\n".join(f"{k} = {v:.4g}" for k, v in summary["variables"].items())
    if "grasp" in summary:
        grasp = summary["grasp"]
        text += (f"\ngrasp force on {grasp['obstacle']!r}: {grasp['value']:.4g} N "
                 f"(target {grasp['target']:.4g} N)")
    axis.set_title(f"design optimum ({summary['status']}):\n{text}", fontsize=8)
    axis.grid(alpha=0.3)
    axis.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(out / "design.png", dpi=130)
    plt.close(figure)


# --- grasp force: a bracketing root solve on converged contact states -------------------------
GRASP_SCAN = 6  # points across the bounds (bounds included) searched for a bracket
GRASP_TIGHTER = 10  # the accuracy check re-solves the design with the tolerance / this


class _GraspMet(Exception):
    """Raised inside the root solve when a trial meets the target to the tolerance."""


def grasp_value(entry: dict, component: str) -> float:
    """The grasp force of an obstacle's contact entry (`fe_beam.fem.contact.ContactSet.summary`):
    |force| (``component`` "force"), or the magnitude of its normal part, force minus its
    friction part ("normal") [N]."""
    force = np.asarray(entry["force"], dtype=float)
    if component == "normal" and "friction_force" in entry:
        force = force - np.asarray(entry["friction_force"], dtype=float)
    return float(np.linalg.norm(force))


class GraspEvaluator:
    """The grasp force of a trial design: the configuration with the one variable set
    (`fe_beam.solvers.realtime.set_parameters`) solved by the load stepping of ``fe-beam
    finger`` / ``fe-beam static`` from the unloaded state (`solve_static`: the same steps, the
    same contact iterations, so a re-run of the designed configuration gives the same force),
    the grasp force read at load factor 1."""

    def __init__(self, design: DesignProblem, config, comm):
        self.design, self.config, self.comm = design, config, comm
        self.key = design.variables[0]
        self.history: list[dict] = []
        self._cache: dict = {}

    def trial(self, x: float):
        return set_parameters(self.config, {self.key: float(x)})

    def evaluate(self, x: float) -> dict:
        """{"grasp": F [N], "miss": F - target, "tip", "contact": the obstacle's entry}."""
        x = float(x)
        if x in self._cache:
            return self._cache[x]
        result = solve_static(self.trial(x), None, self.comm, progress=False,
                              record_shapes=False, stability=False)
        if result.status != "converged":
            reached = result.steps[-1]["load_factor"] if result.steps else 0.0
            raise UpdateFailed(f"{self.key} = {x:.6g}: {result.message}", reached)
        target = self.design.target
        step = result.steps[-1]
        entry = step["contact"][target["index"]]
        grasp = grasp_value(entry, target["component"])
        value = {"x": x, "grasp": grasp, "miss": grasp - target["value"], "tip": step["tip"],
                 "contact": entry}
        self._cache[x] = value
        self.history.append({"variables": {self.key: x}, "grasp_force": grasp,
                             "active": entry["active"]})
        return value

    def tighter(self, x: float, factor: float = GRASP_TIGHTER) -> float:
        """The grasp force of the trial x with the penetration tolerance divided by
        ``factor`` (the same penalty and steps): how far the force is from the exact contact
        (it moves with the penetration the tolerance allows)."""
        config = self.trial(x)
        tolerance = config.contact.tolerance(config.model.section)
        tight = replace(config, contact=replace(config.contact,
                                                penetration_tolerance=tolerance / factor))
        result = solve_static(tight, None, self.comm, progress=False, record_shapes=False,
                              stability=False)
        if result.status != "converged":
            raise UpdateFailed(f"{self.key} = {x:.6g} with [contact] penetration_tolerance = "
                               f"{tolerance / factor:.3g} m (the accuracy check of the grasp "
                               f"force): {result.message}",
                               result.steps[-1]["load_factor"] if result.steps else 0.0)
        entry = result.steps[-1]["contact"][self.design.target["index"]]
        return grasp_value(entry, self.design.target["component"]), tolerance

    def resolve(self, x: float) -> dict:
        """The trial x solved afresh (not from the cache: what `fe-beam finger` / `static`
        with the reported value gives, the ``reproduce`` command): {"grasp": F [N], "checks":
        the state's certificates (global equilibrium with the contact forces, the surface
        penetration, the contact force balance)}. Collective."""
        result = solve_static(self.trial(x), None, self.comm, progress=False,
                              record_shapes=False, stability=False)
        if result.status != "converged" or not result.steps:
            return {"grasp": math.nan, "checks": list(result.checks),
                    "message": result.message}
        entry = result.steps[-1]["contact"][self.design.target["index"]]
        return {"grasp": grasp_value(entry, self.design.target["component"]),
                "checks": list(result.checks), "message": ""}

    def shape(self, x: float):
        """The deformed shape (vertex values) of the trial design at load factor 1 (rank 0)."""
        result = solve_static(self.trial(x), None, self.comm, progress=False,
                              record_shapes=True, stability=False)
        return result.shapes[-1][1] if result.shapes else None


def _bracket(evaluator: GraspEvaluator, low: float, high: float, tolerance: float):
    """(a, b) whose misses have opposite signs, (x, None) for a trial that meets the target,
    or None: the bounds first, then GRASP_SCAN points across them, in order."""
    ends = [evaluator.evaluate(x) for x in (low, high)]
    for value in ends:
        if abs(value["miss"]) <= tolerance:
            return value["x"], None
    if ends[0]["miss"] * ends[1]["miss"] < 0:
        return low, high
    previous = ends[0]
    for x in np.linspace(low, high, GRASP_SCAN)[1:]:
        value = evaluator.evaluate(x)
        if abs(value["miss"]) <= tolerance:
            return value["x"], None
        if previous["miss"] * value["miss"] < 0:
            return previous["x"], value["x"]
        previous = value
    return None


def grasp_design(design: DesignProblem, config, comm) -> dict:
    """The one variable's value within its bounds whose grasp force is the target to the
    tolerance: a bracket from the bounds (or a scan across them), then Brent's method on the
    miss F(x) - target, each evaluation a converged contact state (`GraspEvaluator`). A target
    outside the forces the bounds reach, or a force that jumps across it, is not met:
    status "not converged" (exit 3), never a design that misses it."""
    from scipy.optimize import brentq

    started = time.perf_counter()
    evaluator = GraspEvaluator(design, config, comm)
    key, target, tolerance = evaluator.key, design.target, design.tolerance
    (low, high), x0 = design.bounds[0], float(design.initial[0])
    initial = evaluator.evaluate(x0)
    found = _bracket(evaluator, float(low), float(high), tolerance) \
        if abs(initial["miss"]) > tolerance else (x0, None)
    iterations, met = 0, None
    if found is not None and found[1] is None:
        met = evaluator.evaluate(found[0])
    elif found is not None:
        a, b = found

        def miss(x: float) -> float:
            value = evaluator.evaluate(x)
            if abs(value["miss"]) <= tolerance:
                raise _GraspMet(x)
            return value["miss"]

        before = len(evaluator.history)
        try:
            x = brentq(miss, a, b, xtol=1e-12 * (high - low), maxiter=design.max_iterations)
            best = evaluator.evaluate(x)
        except _GraspMet as stop:
            met = evaluator.evaluate(stop.args[0])
        except RuntimeError:  # brentq's iteration limit
            best = None
        iterations = len(evaluator.history) - before  # Brent's evaluations
    forces = [h["grasp_force"] for h in evaluator.history]
    what = f"the {'normal ' if target['component'] == 'normal' else ''}grasp force of " \
           f"{target['obstacle']!r}"
    if met is not None:
        final, status = met, "converged"
        message = (f"{what} is {met['grasp']:.6g} N at {key} = {met['x']:.6g} (target "
                   f"{target['value']:g} N, tolerance {tolerance:g} N)")
    else:
        tried = min(evaluator._cache.values(), key=lambda v: abs(v["miss"]))
        final, status = tried, "not converged"
        if found is None:
            message = (f"the target is not met: {what} stays between {min(forces):.6g} and "
                       f"{max(forces):.6g} N for {key} in [{low:g}, {high:g}] (target "
                       f"{target['value']:g} N)"
                       + ("; the obstacle is not touched at some of them" if min(forces) == 0
                          else "") + ": widen the bounds or move the obstacle")
        elif best is None:
            message = (f"the target is not met: Brent's method stopped after "
                       f"{design.max_iterations} iterations between {key} = {found[0]:.6g} "
                       f"and {found[1]:.6g} (closest {tried['grasp']:.6g} N at "
                       f"{tried['x']:.6g}; tolerance {tolerance:g} N)")
        else:
            message = (f"the target is not met: {what} jumps across {target['value']:g} N "
                       f"at {key} = {best['x']:.8g} (closest {tried['grasp']:.6g} N at "
                       f"{tried['x']:.8g}; tolerance {tolerance:g} N): the contact state "
                       "changes there; a larger tolerance or other bounds")
    # the grasp force of the discrete contact moves with the penetration the tolerance allows:
    # the design is met only if it holds with a 10x tighter tolerance too
    tight, penetration = evaluator.tighter(final["x"])
    check = {"penetration_tolerance": penetration,
             "tighter_tolerance": penetration / GRASP_TIGHTER, "value": tight,
             "difference": abs(tight - final["grasp"])}
    if status == "converged" and abs(tight - target["value"]) > tolerance:
        status = "not converged"
        message = (f"the target is met to the tolerance only for [contact] "
                   f"penetration_tolerance = {penetration:.3g} m: with "
                   f"{penetration / GRASP_TIGHTER:.3g} m {what} at {key} = {final['x']:.6g} is "
                   f"{tight:.6g} N, {abs(tight - target['value']):.3g} N from the target "
                   f"(tolerance {tolerance:g} N): set a smaller [contact] "
                   "penetration_tolerance (and a larger penalty) or a larger [design] "
                   "tolerance")
    checks = grasp_checks(evaluator, final["x"], target["value"], tolerance, what) \
        if status == "converged" else []
    return {
        "status": status,
        "message": message,
        "variables": {key: final["x"]},
        "initial": {key: x0},
        "bounds": {key: [float(low), float(high)]},
        "objective": {"kind": "grasp_force", "value": final["miss"],
                      "initial": initial["miss"]},
        "grasp": {"obstacle": target["obstacle"], "component": target["component"],
                  "target": target["value"], "tolerance": tolerance,
                  "value": final["grasp"], "initial": initial["grasp"],
                  "contact": final["contact"], "contact_check": check},
        "constraints": {},
        "kkt_residual": None,
        "kkt": None,
        "iterations": iterations,
        "evaluations": len(evaluator.history),
        "gradient": "none (bracketing root solve)",
        "tip": final["tip"],
        "history": evaluator.history,
        "wall_time_s": time.perf_counter() - started,
        "notes": [],
        "checks": checks,
        "_shapes": (x0, final["x"], evaluator),
    }


def grasp_checks(evaluator: GraspEvaluator, x: float, target: float, tolerance: float,
                 what: str) -> list[dict]:
    """The certificates of a grasp design's answer: the design re-solved afresh at the
    reported value (`GraspEvaluator.resolve`, the load stepping the ``reproduce`` command
    runs) must give the target to the design's tolerance (``grasp_force_target``: |F - target|
    [N]), and that state carries the static certificates (``global_equilibrium`` of the
    reactions, loads and contact forces, ``surface_penetration``, ``contact_force_balance``).
    Collective."""
    resolved = evaluator.resolve(x)
    value = abs(resolved["grasp"] - target)
    detail = (f"|{what} re-solved at {evaluator.key} = {x:.8g} - target| [N] "
              f"({resolved['grasp']:.8g} N against {target:.8g} N)")
    if resolved["message"]:
        detail += f"; the re-solve stopped: {resolved['message']}"
    return [certify.entry(
        "grasp_force_target", value, tolerance, detail=detail,
        remedy="the answer does not reproduce: narrow the [design] bounds or set a larger "
               "[design] tolerance; please report it")] + resolved["checks"]


def run_design(config: dict, out: Path | None, comm, progress: bool = False,
               options: dict | None = None) -> dict:
    """Parse, optimise, write summary.json and design.png under ``out``. summary.json's
    ``reproduce`` is the command line that re-runs the answer (`reproduce_command`;
    ``options``: the command's, with the configuration's path and the run's overrides)."""

    design, rest = parse_design(config)
    rest = copy.deepcopy(rest)
    rest.pop("inverse", None)
    if "tendons" in rest:  # the finger's defaults written out (every table explicit)
        rest = with_defaults(rest)
    section = rest.get("section")
    for key in design.variables:
        # a tip value of an untapered dimension: the taper starts from the uniform value (so
        # that the built model has a constant for it)
        match = re.fullmatch(r"section\.(\w+)_tip", key)
        if match and isinstance(section, dict) and key[len("section."):] not in section \
                and match.group(1) in section:
            section[key[len("section."):]] = section[match.group(1)]
    if "tendons" in rest:
        parsed, _ = parse_finger(rest)
    else:
        parsed = parse_static(rest)
    structure = getattr(parsed.model, "structure", None) is not None
    if structure and any(key.split(".")[0] == "rods" for key in design.variables):
        # every rod's section a field the design writes in place
        parsed = replace(parsed, model=with_rod_sections(parsed.model))
    if design.objective == "grasp_force":
        summary = grasp_design(design, parsed, comm)
        start, end, evaluator = summary.pop("_shapes")
        drawn = out is not None and parsed.output.plots
        shapes = (evaluator.shape(start), evaluator.shape(end)) if drawn else (None, None)
    else:
        # a structure: finite-difference gradients (the adjoint sensitivities take one rod)
        summary = optimise(design, parsed, comm, None if structure else rest)
        shapes = summary.pop("_shapes")
    summary["reproduce"] = reproduce_command(config, summary["variables"], options)
    if out is not None and comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        atomic_write_json(out / "summary.json", summary)
        if parsed.output.plots:
            tip = (None if not structure else parsed.model.structure.reference_point(
                parsed.model.length, parsed.model.structure.chain[-1]))
            _plot(out, summary, shapes, design, parsed.model.length, parsed.obstacles, tip)
    return summary


def run(validated, out: Path | None, comm=None, progress: bool = True,
        echo=None) -> Result:
    """``fe-beam design`` (the driver contract, `fe_beam.analyses.result`)."""
    report = Report(echo)
    comm = comm if comm is not None else world()
    try:
        summary = run_design(validated.config, out, comm, progress=progress,
                             options=validated.options)
    except UpdateFailed as failure:  # a trial design without equilibrium
        report.err(f"fe-beam design: no equilibrium for a trial design: {failure} (narrow the "
                   "[design] bounds)")
        return failed("design", out, comm, f"no equilibrium for a trial design: {failure}",
                      report)
    values = ", ".join(f"{k} = {v:.6g}" for k, v in summary["variables"].items())
    if "grasp" in summary:
        grasp = summary["grasp"]
        report.out(f"reproduce the answer with: {summary['reproduce']}")
        code = fit_report(report, "design", summary,
                          f"design {summary['status']}: {values}; "
                          f"{'normal ' if grasp['component'] == 'normal' else ''}grasp force on "
                          f"{grasp['obstacle']!r} {grasp['value']:.6g} N (target "
                          f"{grasp['target']:.6g} N, tolerance {grasp['tolerance']:.2g} N), "
                          f"{summary['evaluations']} contact solves; results in {out}")
        return Result("design", summary, code, report.lines)
    objective = summary["objective"]["value"]
    minimised = summary["objective"].get("minimised")
    shown = (f"{objective:.6g}" if minimised is None else  # the tension, not tension / bound
             f"{minimised['name']} = {minimised['value']:.6g} (minimised)")
    report.out(f"reproduce the answer with: {summary['reproduce']}")
    code = fit_report(report, "design", summary,
                      f"design {summary['status']}: {values}; objective {shown}, KKT "
                      f"residual {summary['kkt_residual']:.2g}, {summary['iterations']} "
                      f"iterations ({summary['gradient']} gradients); results in {out}")
    return Result("design", summary, code, report.lines)

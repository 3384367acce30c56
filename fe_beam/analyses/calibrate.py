"""``fe-beam calibrate``: fit rod or finger parameters to measured tip poses and backbone points
by Gauss-Newton / Levenberg-Marquardt (scipy.optimize.least_squares, trust-region reflective)
with the exact adjoint Jacobian of `fe_beam.analyses.sensitivity.RodSensitivity`; each new parameter
set is solved from the equilibria of the accepted point (the best evaluated so far) at each load
level, never from the last trial's (a far trial leaves states from which Newton can land on a
kinked, non-physical branch), and the returned point is re-solved from the reference state.

Run-time checks (summary ``checks``, `_certified_fit`, `_identifiability`):
``calibrate_best_evaluated`` (the returned point is the best evaluated one),
``calibrate_reference_path`` (its residuals continued from earlier trials equal a fresh load
stepping's) and ``calibrate_identifiable`` (the condition number of J^T J in relative parameters
below `IDENTIFIABLE_TOLERANCE`; beyond it summary ``identifiability`` names the combination the
data determine).

Configuration::

    [calibrate]
    parameters = ["material.E", "tendons.0.offset_tip"]   # config keys
    (fe_beam.analyses.sensitivity)
    bounds = {"material.E" = [1e5, 1e7]}   # optional, per parameter (default: positive for
                                           # moduli, dimensions, tensions; nu in (-1, 0.5))
    weights = {tip_theta = 1.0, x = 10.0, y = 10.0}       # optional, per data column

DATA.csv: a header line, then one row per measurement. One load column, ``tension`` (N, the
tension of tendon 0; load factor = tension / tendons.0.tension, which scales every load, so a
configuration with other loads or loaded tendons needs ``load_factor``) or ``load_factor``; and
any of
``tip_u``, ``tip_v``, ``tip_theta`` (tip displacement [m], rotation [rad]) and ``x``, ``y``
(deformed positions [m] of backbone points; several rows per load). With a column ``s``, each
point is the material point at reference coordinate s [m]: two residuals, x(s) - x and
y(s) - y. Without it, the point is compared with the nearest point of the deformed backbone:
one residual, its signed distance to the backbone (weight: ``weights.x``). An empty cell is
"not measured"; any other cell must be a finite number.

The residuals are weight * (model - data); with m residuals and n parameters the reported
standard errors are sqrt(diag(s^2 (J^T J)^-1)), s^2 = |r|^2 / (m - n) (J the weighted
residuals' Jacobian at the optimum), and ``correlation`` the matching correlation matrix.

The input checks are free of dolfinx and PETSc and live in the config layer
(`fe_beam.config.calibrate`: `parse_calibrate`, `read_data`, `check_data`; imported back here).
"""

from __future__ import annotations

import math
import re
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from fe_beam import analyses, certify
from fe_beam.analyses.result import Report, Result, failed, fit_report, world
from fe_beam.config.calibrate import (
    CalibrationData,
    CalibrationSpec,
    check_data,
    parameter_kind,
    parse_calibrate,
    read_data,
)
from fe_beam.errors import ConfigError, LoadSteppingFailed
from fe_beam.exports.outputs import _pyplot, atomic_write_json
from fe_beam.solvers.newton import SolveFailed

__all__ = ["run", "CalibrationData", "CalibrationSpec", "calibrate", "default_bounds",
           "check_data", "parse_calibrate", "parameter_kind", "read_data",
           "run_calibrate"]


class _Residuals:
    """Weighted residuals and their exact Jacobian at a parameter vector (cached by value)."""

    def __init__(self, model, data: CalibrationData, spec: CalibrationSpec, scale: np.ndarray,
                 load_factors: np.ndarray):
        self.model, self.data, self.spec = model, data, spec
        self.scale = scale
        self.factors = load_factors
        self.levels = sorted(set(load_factors.tolist()))
        self.history: list[dict] = []
        self._cache: dict = {}
        # the accepted point: the best evaluated parameters (scaled), their residuals and
        # equilibria, from which every trial is solved (a branch-safe start)
        self.best: tuple | None = None  # (norm, q, r)
        self.accepted: dict | None = None
        self.failed = 0  # trial points without an equilibrium
        # per level: output names and (row index, column, output index, data value, weight)
        self.plan = {}
        self.points = {}  # per level: backbone points without s (distance residuals)
        for level in self.levels:
            names, entries, points = [], [], []
            for row in np.flatnonzero(load_factors == level):
                for column, values in data.columns.items():
                    value = values[row]
                    if not np.isfinite(value):
                        continue
                    if data.s is None and column in ("x", "y"):
                        if column == "x":
                            points.append((value, data.columns["y"][row]))
                        continue
                    name = (column if column.startswith("tip_")
                            else f"{column}@{float(data.s[row])!r}")
                    if name not in names:
                        names.append(name)
                    entries.append((names.index(name), value,
                                    spec.weights.get(column, 1.0)))
            self.plan[level] = (names, entries)
            self.points[level] = np.array(points).reshape(-1, 2)

    def trial(self, q: np.ndarray, size: int) -> np.ndarray:
        """The residuals at a trial point, or ``size`` infinities when the model has no
        equilibrium there (the point is recorded in the history as failed)."""
        try:
            return self.evaluate(q)[0]
        except (LoadSteppingFailed, SolveFailed):
            self.failed += 1
            self.history.append({"parameters": dict(zip(self.spec.parameters,
                                                        (q * self.scale).tolist(), strict=True)),
                                 "residual_norm": None, "equilibrium": False})
            return np.full(size, np.inf)

    def evaluate(self, q: np.ndarray, fresh: bool = False):
        """Residuals and Jacobian at ``q``: each level solved from the accepted point's
        equilibria (not from the last trial's: a far trial can leave a kinked, non-physical
        state that Newton then continues from), or with ``fresh`` from the reference state by
        load stepping (the certificate of the returned point)."""
        key = tuple(np.asarray(q, dtype=float).tolist())
        if key in self._cache and not fresh:
            return self._cache[key]
        self.model.set_values(q * self.scale)
        self.model.start_from(None if fresh else self.accepted)
        residuals, jacobian = [], []
        for level in self.levels:
            names, entries = self.plan[level]
            self.model.solve(level)
            values = self.model.outputs(names)
            grad = self.model.gradient(names)
            for index, value, weight in entries:
                residuals.append(weight * (values[index] - value))
                jacobian.append(weight * grad[index] * self.scale)
            if len(self.points[level]):
                weight = self.spec.weights.get("x", self.spec.weights.get("y", 1.0))
                distances, rows = self.model.backbone_distances(self.points[level])
                residuals.extend(weight * distances)
                jacobian.extend(weight * rows * self.scale)
        r, jac = np.array(residuals), np.array(jacobian)
        self._cache = {key: (r, jac)}
        norm = float(np.linalg.norm(r))
        self.history.append({"parameters": dict(zip(self.spec.parameters,
                                                    (q * self.scale).tolist(), strict=True)),
                             "residual_norm": norm,
                             "start": "reference" if fresh or self.accepted is None
                             else "accepted"})
        if fresh or self.best is None or norm < self.best[0]:
            self.accept(np.array(q, dtype=float), r)
        return r, jac

    def accept(self, q: np.ndarray, r: np.ndarray) -> None:
        """``q`` (just solved) becomes the accepted point: later trials start from its
        equilibria."""
        self.best = (float(np.linalg.norm(r)), q.copy(), r.copy())
        self.accepted = self.model.saved_states()

    def data_norm(self) -> float:
        """The norm of the weighted data (the scale of the residuals)."""
        total = 0.0
        for level in self.levels:
            total += sum((weight * value) ** 2 for _, value, weight in self.plan[level][1])
            if len(self.points[level]):
                weight = self.spec.weights.get("x", self.spec.weights.get("y", 1.0))
                total += float(np.sum((weight * self.points[level]) ** 2))
        return math.sqrt(total)


def _data_rows(data: CalibrationData, rows: np.ndarray) -> CalibrationData:
    return CalibrationData(data.load_column, data.loads[rows],
                           {k: v[rows] for k, v in data.columns.items()},
                           None if data.s is None else data.s[rows])


def _continue_from_lower_loads(model, data: CalibrationData, spec: CalibrationSpec,
                               scale: np.ndarray, factors: np.ndarray, q: np.ndarray,
                               bounds) -> tuple[np.ndarray, list[str]]:
    """A start (scaled parameters ``q``) without an equilibrium at the data's higher loads:
    fit the data of the loads it reaches, then of those the fitted parameters reach, up to
    all of them; returns the scaled parameters to start the full fit from and a note.
    ConfigError when the start has no equilibrium at the lowest load, or a fit to the lower
    loads reaches no further one."""
    levels = sorted(set(factors.tolist()))
    checks = [_Residuals(model, _data_rows(data, factors == level), spec, scale,
                         factors[factors == level]) for level in levels]

    def reached(x) -> int:
        for count, check in enumerate(checks):
            if not np.all(np.isfinite(check.trial(x, 1))):
                return count
        return len(checks)

    column = "tension" if data.load_column == "tension" else "load factor"
    loads = {level: float(data.loads[factors == level][0]) for level in levels}
    given = ", ".join(f"{k} = {v:.6g}" for k, v in zip(spec.parameters, q * scale,
                                                       strict=True))
    done = reached(q)
    if done == 0:
        raise ConfigError(f"[calibrate] the start values ({given}) have no equilibrium even at "
                          f"the data's lowest load ({column} {loads[levels[0]]:.6g}): give "
                          "start values nearer the data in the configuration")
    first = done
    while done < len(levels):
        rows = factors <= levels[done - 1]
        part = _Residuals(model, _data_rows(data, rows), spec, scale, factors[rows])
        size = len(part.evaluate(q)[0])
        fit = least_squares(lambda x, part=part, size=size: part.trial(x, size), q,
                            jac=lambda x, part=part: part.evaluate(x)[1], bounds=bounds,
                            method="trf", x_scale="jac", max_nfev=100)
        q = fit.x
        further = reached(q)
        if further <= done:
            fitted = ", ".join(f"{k} = {v:.6g}" for k, v in zip(spec.parameters, q * scale,
                                                                strict=True))
            raise ConfigError(
                f"[calibrate] the start values ({given}) have no equilibrium at {column} "
                f"{loads[levels[first]]:.6g}, and the fit to the data up to "
                f"{loads[levels[done - 1]]:.6g} ({fitted}) none at {loads[levels[done]]:.6g}: "
                "give start values nearer the data in the configuration")
        done = further
    return q, [f"the start values ({given}) have no equilibrium at {column} "
               f"{loads[levels[first]]:.6g} and above: the fit started from the data up to "
               f"{loads[levels[first - 1]]:.6g} and was continued to the higher loads"]


def calibrate(raw: dict, data: CalibrationData, spec: CalibrationSpec, comm=None,
              model=None, tolerance: float = 1e-12, curves: bool = False) -> dict:
    """Fit ``spec.parameters`` to ``data`` (collective). Returns the summary dict (parameters,
    standard_errors, correlation, residual_norm, iterations, history, ...). ``model``: an
    existing `RodSensitivity` with ``spec.parameters`` to reuse (its forms and cached
    equilibria; ``raw`` is then not used): the fit starts from its current parameter values,
    else from the configuration's. ``curves``: also the fitted model's backbone and tip at
    every load level (key ``_model``, for the plot)."""
    from mpi4py import MPI

    comm = comm or MPI.COMM_WORLD
    started = time.perf_counter()
    own = model is None
    if own:
        model = analyses.sensitivity.RodSensitivity(raw, spec.parameters, comm)
    try:
        count, size = data.count(), len(spec.parameters)
        if count < size:
            raise ConfigError(f"{size} parameters cannot be fitted to {count} measured values "
                              "(give at least as many data as parameters)")
        if getattr(model.problem, "chain", None) is not None and data.s is None \
                and any(c in data.columns for c in ("x", "y")):
            raise ConfigError("calibrate data of a structure of [[rods]]: give backbone points "
                              "x, y with their column s (the chain's arc length); points "
                              "without s are not supported for [[rods]] yet")
        if list(model.parameters) != list(spec.parameters):
            raise ValueError("calibrate: the model's parameters differ from spec.parameters")
        factors = _load_factors(model, data, spec)
        start = model.values()
        scale = np.where(start != 0, np.abs(start), 1.0)
        limits = [spec.bounds.get(k, default_bounds(k)) for k in spec.parameters]
        low = np.array([lo for lo, _ in limits])
        high = np.array([hi for _, hi in limits])
        if np.any(start < low) or np.any(start > high):
            bad = spec.parameters[int(np.flatnonzero((start < low) | (start > high))[0])]
            raise ConfigError(f"[calibrate] the start value of {bad!r} lies outside its bounds")
        residuals = _Residuals(model, data, spec, scale, factors)
        # the start must have equilibria: one without any at the higher loads is first fitted
        # to the lower loads' data, continued upwards (`_continue_from_lower_loads`; a start
        # with none at the lowest load is refused); a trial parameter set without one gives
        # non-finite residuals, which the trust-region method rejects (it shrinks the region)
        # instead of ending the fit
        q0, start_notes = start / scale, []
        if not np.all(np.isfinite(residuals.trial(q0, 1))):
            residuals.failed, residuals.history = 0, []
            q0, start_notes = _continue_from_lower_loads(model, data, spec, scale, factors, q0,
                                                         (low / scale, high / scale))
        r0, jac0 = residuals.evaluate(q0)
        size_r = len(r0)
        # a parameter the data do not depend on (e.g. material.rho without gravity, or only
        # unloaded data) has no best value: the optimiser would report any number as fitted
        influence = np.linalg.norm(jac0, axis=0)
        dead = np.flatnonzero(~(influence > 1e-12 * max(float(influence.max()), 0.0)))
        if len(dead):
            raise ConfigError(f"[calibrate] parameter {spec.parameters[int(dead[0])]!r} does not "
                              "influence the data (zero sensitivity of every measured value): "
                              "remove it from parameters or give data it changes")
        fit, q, r, jac, certificate_notes, mismatch = _certified_fit(
            residuals, q0, size_r, (low / scale, high / scale), tolerance)
        values = q * scale
        jac_p = jac / scale  # d r / d p
        names = list(spec.parameters)
        # a parameter stopped by its bound is not a least-squares estimate: no standard error
        # for it, and the others' are those with it held there
        # (trust-region iterates stay strictly inside: one close to a bound, 1e-6 of its
        # scale, whose unconstrained Gauss-Newton step points outwards is stopped by it; the
        # step, not the gradient alone: with coupled parameters the gradient of one may point
        # inwards while the joint minimum lies beyond its bound)
        near = 1e-6 * np.maximum(scale, np.abs(np.where(np.isfinite(low), low, 0.0)))
        step = np.linalg.lstsq(jac_p, -r, rcond=None)[0]
        outward = 1e-8 * np.maximum(scale, np.abs(values))
        at_bound = ((np.asarray(fit.active_mask) != 0)
                    | ((values <= low + near) & (step < -outward))
                    | ((values >= high - near) & (step > outward)))
        free = np.flatnonzero(~at_bound)
        identifiability = _identifiability(jac_p[:, free], np.where(
            values[free] != 0, np.abs(values[free]), scale[free]), [names[i] for i in free])
        errors = correlation = None
        if len(free):
            sub_errors, sub_corr = _uncertainty(r, jac_p[:, free], scale[free])
            if sub_errors is not None:
                errors = np.full(size, np.nan)
                errors[free] = sub_errors
                if sub_corr is not None:
                    correlation = np.full((size, size), np.nan)
                    correlation[np.ix_(free, free)] = sub_corr
        bound_notes = [f"{names[i]} ended at its bound "
                       f"[{low[i]:.6g}, {high[i]:.6g}]: no standard error (the data pull it "
                       "further; check the model, the data or the bounds)"
                       for i in np.flatnonzero(at_bound)]
        # a fitted tendon outside the section is a model the configuration itself refuses:
        # the data cannot be reproduced inside it (not a fit to report as converged)
        outside = []
        for k, value in zip(names, values, strict=True):
            extent = _offset_bounds(model, k)
            if extent is not None and not (
                    extent[0] - 1e-9 * (extent[1] - extent[0]) <= value
                    <= extent[1] + 1e-9 * (extent[1] - extent[0])):
                outside.append(f"the fit puts {k} = {value:.6g} m outside the section (y from "
                               f"{extent[0]:.6g} to {extent[1]:.6g} m): this model cannot "
                               "reproduce the data with the tendon inside; check the data or "
                               "give [calibrate] bounds")
        evaluated = [h["residual_norm"] for h in residuals.history
                     if h.get("residual_norm") is not None]
        norm, floor = float(np.linalg.norm(r)), 1e-3 * residuals.data_norm()
        best = min(evaluated) if evaluated else norm
        checks = [
            certify.entry("calibrate_best_evaluated", max(norm - best, 0.0) / max(best, floor),
                          BEST_TOLERANCE,
                          detail="(residual norm of the returned parameters, solved from the "
                                 "reference state, minus the least one evaluated) / that least "
                                 "one",
                          remedy="the fit returned a point worse than one it evaluated: start "
                                 "nearer the data or give [calibrate] bounds"),
            certify.entry("calibrate_reference_path", mismatch, BRANCH_TOLERANCE,
                          detail="|residuals continued from the accepted point - residuals "
                                 "solved from the reference state| / |residuals| at the "
                                 "returned parameters",
                          remedy="the continuation left the physical equilibrium branch: "
                                 "raise [loads] steps or start nearer the data"),
        ]
        if identifiability is not None:
            condition = identifiability["condition_number"]
            condition = math.inf if condition is None else condition
            checks.append(certify.entry(
                "calibrate_identifiable", condition, IDENTIFIABLE_TOLERANCE,
                detail="condition number of J^T J in relative parameters (dp/p)"
                       + ("" if condition <= IDENTIFIABLE_TOLERANCE
                          else f"; {identifiability['sentence']}"),
                remedy="fit fewer parameters (fix one of the combination in the "
                       "configuration) or give data that separate them"))
        summary = {
            "status": "converged" if fit.success and not outside else "not converged",
            "message": outside[0] if outside else str(fit.message),
            "parameters": dict(zip(names, values.tolist(), strict=True)),
            "initial": dict(zip(names, start.tolist(), strict=True)),
            "standard_errors": (dict(zip(names, _or_none(errors), strict=True))
                                if errors is not None else None),
            "correlation": ({a: dict(zip(names, _or_none(row), strict=True))
                             for a, row in zip(names, correlation, strict=True)}
                            if correlation is not None else None),
            "residual_norm": float(np.linalg.norm(r)),
            "residuals": int(len(r)),
            "iterations": int(fit.njev or 0),
            "function_evaluations": int(fit.nfev),
            "history": residuals.history,
            "identifiability": identifiability,
            "checks": checks,
            "wall_time_s": time.perf_counter() - started,
            "notes": start_notes + certificate_notes + bound_notes + ([] if (
                errors is not None or len(free) == 0) else [
                "no standard errors: as many data as parameters, or parameters the data cannot "
                "tell apart (J^T J singular)"]) + ([
                f"{residuals.failed} trial parameter set(s) had no equilibrium (rejected steps)"]
                if residuals.failed else []),
        }
        if curves:
            summary["_model"] = (_fitted_curves(model, residuals), factors)
        return summary
    finally:
        if own:
            model.destroy()


#: the returned point's residual norm may exceed the least evaluated one by this (relative)
BEST_TOLERANCE = 1e-6
#: the returned point's residuals continued from the accepted point and solved from the
#: reference state agree to this (relative to their norm, at least 1e-3 of the data's)
BRANCH_TOLERANCE = 1e-6
#: largest condition number of J^T J in relative parameters (dp/p) of an identifiable fit:
#: beyond it a relative error of the data of 1e-4 (below a good measurement's) can move the
#: weakest combination of the parameters by O(1) (e.g. E and h of a slender rod whose data
#: fix only E h^3: 6.5e9; E and a tendon's offset of a soft finger: 2e4)
IDENTIFIABLE_TOLERANCE = 1e8


def _certified_fit(residuals: _Residuals, q0: np.ndarray, size: int, bounds,
                   tolerance: float, rounds: int = 3):
    """The trust-region fit, certified: every trial is solved from the accepted (best
    evaluated) point's equilibria; the returned point is the best evaluated one (never worse
    than a point already evaluated), re-solved from the reference state by load stepping. When
    that differs from its continued solution (the continuation left the physical branch), the
    fit is restarted from there, up to ``rounds`` times. Returns (least_squares result, q,
    residuals, Jacobian, notes, the relative mismatch of the last re-solve)."""
    notes: list[str] = []
    q = q0
    mismatch = math.inf
    for _ in range(rounds):
        fit = least_squares(lambda x: residuals.trial(x, size), q,
                            jac=lambda x: residuals.evaluate(x)[1], bounds=bounds,
                            method="trf", x_scale="jac", xtol=tolerance, ftol=tolerance,
                            gtol=tolerance, max_nfev=200)
        q = np.array(fit.x, dtype=float)
        continued = residuals.evaluate(q)[0]
        if residuals.best is not None and residuals.best[0] < float(np.linalg.norm(continued)):
            # the optimiser ended worse than a point it evaluated: return that one
            shown = ", ".join(f"{k} = {v:.6g}" for k, v in zip(
                residuals.spec.parameters, q * residuals.scale, strict=True))
            notes.append(f"the optimiser ended at {shown} (residual norm "
                         f"{float(np.linalg.norm(continued)):.6g}), worse than a point it had "
                         f"evaluated (residual norm {residuals.best[0]:.6g}): that point is "
                         "returned")
            q, continued = residuals.best[1].copy(), residuals.best[2]
        r, jac = residuals.evaluate(q, fresh=True)
        floor = 1e-3 * residuals.data_norm()
        mismatch = float(np.linalg.norm(r - continued)) / max(float(np.linalg.norm(r)), floor,
                                                              1e-300)
        if mismatch <= BRANCH_TOLERANCE:
            break
        notes.append(f"the residuals at the fit's point continued from earlier trials differ "
                     f"from those solved from the reference state ({mismatch:.3g} relative): "
                     "the fit was restarted from the reference solution")
    return fit, q, r, jac, notes, mismatch


def _identifiability(jac_p: np.ndarray, scale: np.ndarray, names: list) -> dict | None:
    """Whether the data determine the (free) parameters: the condition number of J^T J in
    relative parameters (dp/p; J = d r / d p scaled by |p|) and, when it is too large, its
    weakest direction (the relative changes of the parameters that leave the residuals
    unchanged to first order) in one sentence. None without free parameters."""
    if jac_p.shape[1] == 0:
        return None
    scaled = jac_p * scale[None, :]
    singular, vt = np.linalg.svd(scaled, full_matrices=False)[1:]
    condition = (float((singular[0] / singular[-1]) ** 2) if singular[-1] > 0
                 else math.inf)
    direction = vt[-1] / np.max(np.abs(vt[-1])) if singular[0] > 0 else vt[-1]
    weakest = {name: float(c) for name, c in zip(names, direction, strict=True)}
    moving = [f"{name} by {c:+.3g}" for name, c in weakest.items() if abs(c) > 1e-3]
    sentence = "the data do not tell the parameters apart"
    if len(names) > 2:
        sentence += (": changing " + " and ".join(moving) + " times a common small relative "
                     "amount leaves every residual unchanged to first order")
    if len(names) == 2 and np.all(scale > 0):
        # p1^u1 p2^u2 with u orthogonal to the weakest direction (in ln p) is what they fix
        u = np.array([direction[1], -direction[0]])
        u = u / u[np.argmax(np.abs(u))]
        if np.min(np.abs(u)) < 1e-3:
            kept = int(np.argmax(np.abs(u)))
            sentence += (f": only {names[kept]} is determined (the data barely depend on "
                         f"{names[1 - kept]})")
        else:
            sentence += (f": only {names[0]}^{u[0]:.3g} * {names[1]}^{u[1]:.3g} is "
                         f"determined (changing {names[0]} by {direction[0]:+.3g} and "
                         f"{names[1]} by {direction[1]:+.3g} times a small relative amount "
                         "leaves every residual unchanged)")
    elif len(names) == 1:
        sentence = f"the data barely depend on {names[0]}"
    return {"condition_number": condition if math.isfinite(condition) else None,
            "smallest_singular_value_relative": float(singular[-1] / singular[0])
            if singular[0] > 0 else 0.0,
            "weakest_direction": weakest, "sentence": sentence}


def _offset_bounds(model, key: str) -> tuple[float, float] | None:
    """The section's extent at the path point of a tendon offset parameter (the
    configuration refuses a tendon outside the section; a fit must not report one), of the
    configuration's section. None for other parameters or a custom section."""
    m = re.fullmatch(r"tendons\.(\d+)\.(offset_base|offset_tip|path\.(\d+)\.1|"
                     r"paths\.(\d+)\.(\d+)\.1)", key)
    if m is None or not getattr(model, "tendons", None):
        return None
    index = int(m.group(1))
    paths = model.tendons.tendons[index].paths
    if m.group(2) in ("offset_base", "offset_tip"):
        branch, point = 0, (0 if m.group(2) == "offset_base" else len(paths[0]) - 1)
    elif m.group(3) is not None:
        branch, point = 0, int(m.group(3))
    else:
        branch, point = int(m.group(4)), int(m.group(5))
    x = float(paths[branch][point][0])
    config = model.config.model
    extent = config.section.y_extent(x / float(config.length))
    return None if extent is None else (float(extent[0]), float(extent[1]))


def _or_none(values) -> list:
    """A list of floats with NaN (no value: a parameter at its bound) as None (JSON null)."""
    return [None if not math.isfinite(v) else float(v) for v in np.asarray(values).tolist()]


def default_bounds(key: str) -> tuple[float, float]:
    """Physical limits of a parameter when [calibrate] bounds does not give any: moduli,
    density, section dimensions (except the signed I3), tensions and pull-ins are positive
    (the trust-region iterates stay strictly inside), Poisson's ratio in (-1, 0.5)."""
    if key == "material.nu":
        return (-1.0, 0.5)
    kind = parameter_kind(key)
    if kind in ("material", "tension", "pull_in", "rod_section", "rod_material") or (
            kind == "section" and not key.startswith("section.I3")):
        return (0.0, np.inf)
    return (-np.inf, np.inf)


def _uncertainty(r: np.ndarray, jac: np.ndarray, scale: np.ndarray):
    """Standard errors and correlation of least squares: covariance s^2 (J^T J)^-1 with
    s^2 = |r|^2 / (m - n), by the SVD of the Jacobian in the scaled parameters p / scale (well
    conditioned whatever the parameters' units). None when m == n (no redundancy) or when the
    data cannot tell the parameters apart (smallest singular value below 1e-12 of the
    largest)."""
    m, n = jac.shape
    if m <= n:
        return None, None
    scaled = jac * scale[None, :]
    _, singular, vt = np.linalg.svd(scaled, full_matrices=False)
    if not singular[-1] > 1e-12 * singular[0]:
        return None, None
    sigma2 = float(r @ r) / (m - n)
    covariance = sigma2 * (vt.T / singular**2) @ vt  # of p / scale
    covariance = covariance * np.outer(scale, scale)
    errors = np.sqrt(np.diag(covariance))
    correlation = covariance / np.outer(errors, errors) if np.all(errors > 0) else None
    return errors, correlation


def _load_factors(model, data: CalibrationData, spec: CalibrationSpec) -> np.ndarray:
    if data.load_column == "load_factor":
        return data.loads.astype(float)
    tendons = model.tendons
    if not tendons:
        raise ConfigError("the data column tension needs a configuration with [[tendons]] "
                          "(use load_factor for other loads)")
    first = tendons.tendons[0]
    if first.controlled_by_pull_in or not first.tension:
        raise ConfigError("the data column tension needs tendon 0 tension controlled with "
                          "tension > 0 (use load_factor otherwise)")
    if "tendons.0.tension" in spec.parameters:
        raise ConfigError("tendons.0.tension cannot be fitted when the data give the tension "
                          "(use a load_factor column)")
    # the load factor scales every load and tendon: a tension column would silently scale the
    # others with tendon 0's tension (e.g. gravity at a quarter for a quarter of the tension)
    loads = model.config.model.loads
    others = [f"loads.{name}" for name, value in (
        ("tip_force", loads.tip_force), ("tip_moment", loads.tip_moment),
        ("distributed", loads.distributed),
        ("gravity", loads.gravity if float(model.config.model.material.rho) else 0.0),
        ("point_forces", [f[1:] for f in loads.point_forces] or 0.0),
        ("point_moments", [m[1:] for m in loads.point_moments] or 0.0),
        ("end_displacement", loads.end_displacement or 0.0),
        ("end_rotation", loads.end_rotation or 0.0))
        if np.any(np.asarray(value, dtype=float) != 0)]
    others += [f"tendons.{i}" for i, t in enumerate(tendons.tendons) if i > 0 and (
        t.controlled_by_pull_in or t.tension)]
    if others:
        raise ConfigError(f"the data column tension scales every load with tendon 0's tension "
                          f"(load factor = tension / tendons.0.tension), {others[0]} included: "
                          "with other loads or tendons give a load_factor column")
    return data.loads / float(first.tension)


def _fitted_curves(model, residuals: _Residuals) -> dict:
    """Model backbones and tip values at every load level (for the plot; collective)."""
    length = model.config.model.length
    stations = np.linspace(0.0, length, 41)
    names = [f"x@{float(s)!r}" for s in stations] + [f"y@{float(s)!r}" for s in stations]
    curves = {}
    for level in residuals.levels:
        model.solve(level)
        values = model.outputs(names + ["tip_u", "tip_v", "tip_theta"])
        curves[level] = {"x": values[:41].tolist(), "y": values[41:82].tolist(),
                         "tip": values[82:].tolist()}
    return curves


def run_calibrate(raw: dict, data_path, out: Path | None, comm, quiet: bool = False) -> dict:
    """The command: validate, fit, write summary.json and calibration.png under ``out``."""
    spec, data = check_data(raw, data_path)
    summary = calibrate(raw, data, spec, comm, curves=True)
    curves, factors = summary.pop("_model")
    summary["data"] = str(data_path)
    if out is not None and comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        atomic_write_json(out / "summary.json", summary)
        _plot(out / "calibration.png", data, curves, factors, summary)
    return summary


def _plot(path: Path, data: CalibrationData, curves: dict, row_factors: np.ndarray,
          summary: dict) -> None:

    plt = _pyplot()
    figure = _calibration_figure(plt, data, curves, row_factors, summary)
    figure.savefig(path, dpi=110)
    plt.close(figure)


def _calibration_figure(plt, data: CalibrationData, curves: dict, row_factors: np.ndarray,
                        summary: dict):
    """The backbone panel and the tip panel: tip_u, tip_v [mm] on the left axis, tip_theta
    [rad] on its own right axis; the horizontal axis is the data's load column (a tension
    column: tendon 0's tension [N] = load factor x tendons.0.tension)."""
    figure, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    levels = sorted(curves)
    factors = np.array([lf for lf in levels])
    for level in levels:
        axes[0].plot(curves[level]["x"], curves[level]["y"], "-", lw=1,
                     label=f"model, load {level:.3g}")
    if "x" in data.columns:
        axes[0].plot(data.columns["x"], data.columns["y"], "k.", label="data")
    axes[0].set_xlabel("x [m]")
    axes[0].set_ylabel("y [m]")
    axes[0].set_aspect("equal", adjustable="datalim")
    axes[0].set_title("backbone: data and fitted model")
    axes[0].legend(fontsize=7)
    scale, xlabel = 1.0, "load factor"
    if data.load_column == "tension":
        measured = np.abs(np.asarray(row_factors, dtype=float)) > 0
        if np.any(measured):
            scale = float(np.median(np.asarray(data.loads)[measured]
                                    / np.asarray(row_factors)[measured]))
            xlabel = "tension of tendon 0 [N]"
    angle = axes[1].twinx()
    handles = []
    for index, column in enumerate(("tip_u", "tip_v", "tip_theta")):
        axis, unit = (angle, 1.0) if column == "tip_theta" else (axes[1], 1e3)
        color = f"C{index}"
        model_values = np.array([curves[level]["tip"][index] for level in levels]) * unit
        handles += axis.plot(factors * scale, model_values, "-", color=color,
                             label=f"{column} model")
        if column in data.columns:
            handles += axis.plot(np.asarray(row_factors) * scale,
                                 np.asarray(data.columns[column]) * unit, "o", color=color,
                                 label=f"{column} data")
    axes[1].set_xlabel(xlabel)
    axes[1].set_ylabel("tip_u, tip_v [mm]")
    angle.set_ylabel("tip_theta [rad]")
    axes[1].set_title("tip: data and fitted model")
    axes[1].legend(handles=handles, fontsize=7)
    fitted = ", ".join(f"{k} = {v:.4g}" for k, v in summary["parameters"].items())
    figure.suptitle(fitted, fontsize=8)
    figure.tight_layout()
    return figure


def run(validated, out: Path | None, comm=None, progress: bool = True,
        echo=None) -> Result:
    """``fe-beam calibrate`` (the driver contract, `fe_beam.analyses.result`); the data file is
    ``validated.options["data"]``."""
    report = Report(echo)
    comm = comm if comm is not None else world()
    try:
        summary = run_calibrate(validated.config, validated.options["data"], out, comm,
                                quiet=not progress)
    except LoadSteppingFailed as failure:
        report.err(f"fe-beam calibrate: no equilibrium for a trial parameter set: {failure}")
        return failed("calibrate", out, comm,
                      f"no equilibrium for a trial parameter set: {failure}", report)
    fitted = ", ".join(f"{k} = {v:.6g}" for k, v in summary["parameters"].items())
    code = fit_report(report, "calibrate", summary,
                      f"fitted {fitted}; residual norm {summary['residual_norm']:.3g}, "
                      f"{summary['iterations']} iterations, {summary['wall_time_s']:.2f} s; "
                      f"results in {out}")
    return Result("calibrate", summary, code, report.lines)

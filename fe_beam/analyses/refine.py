"""Mesh-refinement studies: ``fe-beam refine CONFIG.toml --levels N --out DIR``.

A configuration is solved on ``N`` meshes, each ``ratio`` times finer than the one before: rods
and fingers multiply ``[mesh] elements`` by ``ratio**k``, solids divide ``[solid] mesh_size`` by
it. For each quantity of interest q (final-step tip u, v, theta; a spatial rod's u, v, w and
|r(L)|, ``tip.r``; a solid's any of them) and level k:

    d_k   = q_k - q_{k-1}                                      successive difference
    p_k   = log(|d_{k-1}| / |d_k|) / log(ratio)                observed order (k >= 2)
    q*_k  = q_k + d_k / (ratio**p_k - 1)                       Richardson extrapolation
    e_k   = |q*_k - q_k| = |d_k| / (ratio**p_k - 1)            estimated error of q_k
    c_k   = |q*_k - q*_{k-1}|                                  change of the extrapolation

The numerics are the pure functions `observed_order`, `richardson` and `analyse_sequence` (no I/O,
no MPI); `run_refinement` solves the levels, `write_outputs` writes ``refinement.json``,
``refinement.csv`` and ``refinement.png``; `run_refine_command` is the CLI entry.
"""

from __future__ import annotations

import copy
import math
import sys
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

from fe_beam import analyses, certify, runctl
from fe_beam.analyses.result import EXIT_FAILED, Report, Result, world
from fe_beam.config.refine import (
    QUANTITIES,
    RefinementPlan,
    add_refine_arguments,
    plan_refinement,
)
from fe_beam.errors import ConfigError
from fe_beam.exports import Exports, PlotExport, SummaryExport, TableExport, figure
from fe_beam.progress import ProgressBar

__all__ = [
    "QUANTITIES",
    "LevelAnalysis",
    "RefinementPlan",
    "SequenceAnalysis",
    "add_refine_arguments",
    "analyse_sequence",
    "observed_order",
    "plan_refinement",
    "richardson",
    "run_refine_command",
    "run_refinement",
    "study_summary",
    "format_table",
    "write_outputs",
]

UNITS = {"tip.u": "m", "tip.v": "m", "tip.theta": "rad", "tip.w": "m", "tip.r": "m"}
SOLID_DRIVER = "fe_beam.analyses.solid_driver"  # the solid configurations' driver
NOISE_RTOL = 1e-10  # |d_k| below this fraction of max |q| is round-off / solver noise
MIN_ORDER = 0.5  # below it 1 / (r^p - 1) amplifies noise: coarse meshes, no extrapolation


# --- numerics (pure) ---------------------------------------------------------------------------
def observed_order(
    coarse: float, medium: float, fine: float, ratio: float, noise: float = 0.0
) -> tuple[float | None, str]:
    """Observed order of three successive levels (mesh sizes h, h/r, h/r^2):

        p = log(|medium - coarse| / |fine - medium|) / log(r)

    Returns (p, "") or (None, reason) when p is undefined: a difference at or below ``noise``
    (round-off), successive differences of opposite sign (oscillatory convergence) or a
    difference that does not shrink (not in the asymptotic range). In the last two cases p is
    still returned when finite, with the reason, for information; callers should not
    extrapolate with it.
    """
    if not ratio > 1:
        raise ValueError(f"ratio must be > 1, got {ratio!r}")
    first, second = medium - coarse, fine - medium
    if abs(first) <= noise or abs(second) <= noise:
        return None, "round-off"
    order = math.log(abs(first) / abs(second)) / math.log(ratio)
    if first * second < 0:
        return order, "oscillatory"
    if order <= 0:
        return order, "not converging"
    return order, ""


def richardson(medium: float, fine: float, ratio: float, order: float) -> float:
    """Richardson extrapolation q* = q_f + (q_f - q_m) / (r^p - 1) of two levels h, h/r."""
    if not (ratio > 1 and order > 0):
        raise ValueError(f"need ratio > 1 and order > 0, got {ratio!r}, {order!r}")
    return fine + (fine - medium) / (ratio**order - 1)


@dataclass(frozen=True)
class LevelAnalysis:
    """One level of a sequence: value, difference to the previous level and (k >= 2) observed
    order, extrapolated value, its estimated error |q* - q| and its change from the previous
    level's extrapolation. ``None`` where undefined; ``note`` says why."""

    value: float
    difference: float | None = None
    order: float | None = None
    extrapolated: float | None = None
    error_estimate: float | None = None
    extrapolation_change: float | None = None
    note: str = ""


@dataclass(frozen=True)
class SequenceAnalysis:
    """A whole sequence: per-level rows and the verdict of the finest level."""

    levels: list[LevelAnalysis]
    order: float | None = None
    extrapolated: float | None = None
    error_estimate: float | None = None
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        return asdict(self)


def analyse_sequence(
    values: list[float],
    ratio: float,
    noise_rtol: float = NOISE_RTOL,
    min_order: float = MIN_ORDER,
) -> SequenceAnalysis:
    """Observed orders and Richardson extrapolations of a quantity on meshes h0 / ratio**k.

    Differences below ``noise_rtol * max|q|`` are treated as round-off (order undefined, the
    finest value is then as good as converged). Extrapolation is done only where the observed
    order is defined and at least ``min_order`` and the differences shrink monotonically.
    """
    values = [float(v) for v in values]
    if not values:
        raise ValueError("no values")
    if not ratio > 1:
        raise ValueError(f"ratio must be > 1, got {ratio!r}")
    noise = noise_rtol * max(abs(v) for v in values)
    rows = [LevelAnalysis(values[0])]
    notes: list[str] = []
    previous_extrapolated = None
    for k in range(1, len(values)):
        difference = values[k] - values[k - 1]
        if k == 1:
            rows.append(LevelAnalysis(values[k], difference))
            continue
        order, reason = observed_order(values[k - 2], values[k - 1], values[k], ratio, noise)
        if not reason and order < min_order:
            reason = "low order"
        extrapolated = error = change = None
        if not reason:
            extrapolated = richardson(values[k - 1], values[k], ratio, order)
            error = abs(extrapolated - values[k])
            if previous_extrapolated is not None:
                change = abs(extrapolated - previous_extrapolated)
        rows.append(
            LevelAnalysis(values[k], difference, order, extrapolated, error, change, reason)
        )
        previous_extrapolated = extrapolated
    if len(values) < 3:
        notes.append(f"no observed order: it needs 3 levels, {len(values)} were run")
    for k, row in enumerate(rows):
        if row.note == "round-off":
            notes.append(
                f"level {k}: differences at round-off (|d| <= {noise:.1e}): order undefined"
            )
        elif row.note == "oscillatory":
            notes.append(
                f"level {k}: successive differences change sign (non-monotone convergence): "
                "no extrapolation"
            )
        elif row.note == "not converging":
            notes.append(
                f"level {k}: the difference does not shrink (|d_{k}| >= |d_{k - 1}|): not in the "
                "asymptotic range, no extrapolation"
            )
        elif row.note == "low order":
            notes.append(
                f"level {k}: observed order {row.order:.3g} < {min_order:g}: the meshes are not in "
                "the asymptotic range yet, no extrapolation"
            )
    final = rows[-1]
    orders = [row.order for row in rows[-2:] if row.order is not None and not row.note]
    if len(orders) == 2 and abs(orders[1] - orders[0]) > 0.1 * abs(orders[1]):
        notes.append(
            f"observed order still changes ({orders[0]:.3g} -> {orders[1]:.3g}): "
            "not yet asymptotic, treat the extrapolation with care"
        )
    if final.note == "round-off":
        # converged to round-off: the finest value is the answer, its error below the noise
        return SequenceAnalysis(rows, None, final.value, noise, notes)
    if final.note:
        return SequenceAnalysis(rows, None, None, None, notes)
    return SequenceAnalysis(rows, final.order, final.extrapolated, final.error_estimate, notes)


# --- plan: what each level solves --------------------------------------------------------------
def _solid_driver():
    """The solid driver module: the one in sys.modules (a stand-in installed there replaces it;
    a driver without ``parse_solid`` needs [solid] mesh_size), else imported now through the
    lazy `fe_beam.analyses` package."""
    try:
        return sys.modules.get(SOLID_DRIVER) or analyses.solid_driver
    except ModuleNotFoundError as error:
        raise ConfigError(
            f"[solid] configurations need fe_beam.analyses.solid_driver ({error})") from None


# --- solving the levels --------------------------------------------------------------------------
def _solve_rod(plan: RefinementPlan, level: int, comm) -> dict:

    parsed = plan.parsed
    mesh = replace(parsed.model.mesh, elements=plan.size(level))
    model = replace(parsed.model, mesh=mesh)
    if getattr(model, "structure", None) is not None:  # a chain: every rod's elements
        model = replace(model, structure=model.structure.refined(round(plan.ratio**level)))
    config = replace(parsed, model=model)
    # nothing is written per level: no shapes, only the tip of each converged step
    result = analyses.static.solve_static(config, None, comm, progress=False, record_shapes=False)
    return {
        "status": result.status,
        "message": result.message,
        "tip": result.steps[-1]["tip"] if result.steps else None,
        "load_factor": result.steps[-1]["load_factor"] if result.steps else 0.0,
        "dofs": result.dofs,
        "wall_time_s": result.wall_time_s,
    }


def _solve_solid(plan: RefinementPlan, level: int, comm) -> dict:
    raw = copy.deepcopy(plan.raw)
    raw["solid"]["mesh_size"] = plan.size(level)
    summary = _solid_driver().run_solid(raw, None, comm, progress=False)
    steps = summary.get("steps") or []
    status = summary.get("status", "converged" if steps else "failed")
    return {
        "status": "converged" if status in ("converged", "completed") else str(status),
        "message": summary.get("message", ""),
        "tip": steps[-1]["tip"] if steps else None,
        "load_factor": steps[-1].get("load_factor", 1.0) if steps else 0.0,
        "dofs": summary.get("dofs"),
        "cells": summary.get("cells"),
        "wall_time_s": summary.get("wall_time_s"),
        "checks": list(summary.get("checks") or []),
    }


def tip_value(tip: dict, quantity: str, plan: RefinementPlan) -> float:
    """The value of ``quantity`` ("tip.u" ...) in a tip dict; "tip.r" is |r(L)|, r = (L + u, v,
    w) (a spatial rod's ``position``)."""
    name = quantity.split(".")[1]
    if name != "r":
        return float(tip[name])
    if "position" in tip:
        return float(math.sqrt(sum(c * c for c in tip["position"])))
    length = plan.length if plan.length is not None else float(plan.raw["beam"]["length"])
    return float(math.sqrt((length + tip["u"]) ** 2 + tip["v"] ** 2 + tip.get("w", 0.0) ** 2))


def _level_record(plan: RefinementPlan, level: int, solved: dict) -> dict:
    record = {"level": level, "h": plan.h(level)}
    record["mesh_size" if plan.kind == "solid" else "elements"] = plan.size(level)
    if solved.get("cells") is not None:
        record["cells"] = solved["cells"]
    record |= {
        "dofs": solved["dofs"],
        "wall_time_s": solved["wall_time_s"],
        "status": solved["status"],
        "values": {q: tip_value(solved["tip"], q, plan) for q in plan.quantities}
        if solved["tip"] is not None and solved["status"] == "converged"
        else {},
    }
    if solved.get("checks"):  # the level's own certificates (the solid's equilibrium)
        record["checks"] = solved["checks"]
    if solved["status"] != "converged":
        record["message"] = solved["message"]
    return record


def estimate_check(analysis: dict) -> dict | None:
    """The certificate ``refine_error_estimate``: with 4 levels or more, the error estimated for
    the level before the finest (from its own three levels) must be at least the change to the
    finest level (with monotone convergence the error of a level exceeds its distance to any
    finer one): value = max over the quantities of |d_N| / e_(N-1). None when no quantity has
    such an estimate (3 levels, or no extrapolation at N-1: the notes say why)."""
    worst = None
    for quantity, result in analysis.items():
        levels = result["levels"]
        if len(levels) < 4 or levels[-2]["error_estimate"] is None:
            continue
        change = abs(levels[-1]["difference"])
        estimate = levels[-2]["error_estimate"]
        noise = NOISE_RTOL * max(abs(level["value"]) for level in levels)
        value = 0.0 if change <= noise else (change / estimate if estimate > 0 else math.inf)
        if worst is None or value > worst[0]:
            worst = (value, quantity)
    if worst is None:
        return None
    return certify.entry(
        "refine_error_estimate", worst[0], 1.0,
        detail=(f"|q_N - q_(N-1)| / (the error estimated for level N-1), worst for "
                f"{worst[1]}: the estimate is a bound only if this is <= 1"),
        remedy="the levels are not in the asymptotic range: add a finer level (--levels) "
               "before trusting the extrapolated value and its error")


def study_summary(plan: RefinementPlan, records: list[dict], config_path: str = "") -> dict:
    """The content of refinement.json: settings, levels and the analysis of each quantity."""
    done = [r for r in records if r["values"]]
    analysis = {}
    for quantity in plan.quantities:
        if done:
            result = analyse_sequence([r["values"][quantity] for r in done], plan.ratio)
            analysis[quantity] = result.as_dict() | {"unit": UNITS[quantity]}
    failed = [r for r in records if r["status"] != "converged"]
    checks = [check | {"detail": f"level {r['level']}: {check.get('detail', '')}"}
              for r in records for check in r.get("checks", [])]
    estimate = estimate_check(analysis)
    if estimate is not None:
        checks.append(estimate)
    return {
        "config": config_path,
        "kind": plan.kind,
        "refined": plan.refined,
        "ratio": plan.ratio,
        "levels_requested": plan.levels,
        "quantities": list(plan.quantities),
        "status": "failed" if failed else ("completed" if len(done) == plan.levels else "running"),
        "message": failed[0].get("message", "") if failed else "",
        "notes": list(plan.notes),
        "levels": records,
        "analysis": analysis,
    } | ({"checks": checks} if checks else {})


def run_refinement(
    plan: RefinementPlan,
    out: Path | None,
    comm,
    progress: bool = True,
    config_path: str = "",
    report=None,
) -> dict:
    """Solve every level (coarse to fine), writing the outputs after each; stops at the first
    level that does not converge. Returns the summary (see `study_summary`)."""

    solve = _solve_solid if plan.kind == "solid" else _solve_rod
    bar = ProgressBar(comm, total=plan.levels, label="refine", enabled=progress, unit="level")
    records: list[dict] = []
    summary = study_summary(plan, records, config_path)
    files = Exports(_exports(out, lambda: summary) if out is not None else [], comm,
                    throttle=False)
    try:
        for level in range(plan.levels):
            size = plan.size(level)
            what = f"mesh_size {size:.4g}" if plan.kind == "solid" else f"{size} elements"
            bar.update(level, f"level {level}: {what}")
            record = _level_record(plan, level, solve(plan, level, comm))
            records.append(record)
            summary = study_summary(plan, records, config_path)
            files.on_step(record)
            bar.update(level + 1, f"level {level}: {record['wall_time_s']:.2f} s")
            if getattr(bar, "_bar", None) is not None:
                bar.note(_level_line(record, plan))  # above the bar, not through it
            elif report is not None:
                report(_level_line(record, plan))
            if record["status"] != "converged":
                break
    except runctl.Interrupted as stop:
        summary = study_summary(plan, records, config_path) | stop.stopped(
            f"level {len(records)} of the refinement study", f"during level {len(records)}")
        raise
    finally:
        bar.close()
        files.finish(summary)  # the picture once the study has finished
    return summary


def _level_line(record: dict, plan: RefinementPlan) -> str:
    size = record.get("elements", record.get("mesh_size"))
    values = ", ".join(f"{q} = {v:.10g}" for q, v in record["values"].items())
    head = f"level {record['level']}: {plan.refined.split('.')[1]} {size:g}"
    if record["status"] != "converged":
        return f"{head}: {record['status']} ({record.get('message', '')})"
    return f"{head}, {record['dofs']} dofs, {record['wall_time_s']:.2f} s: {values}"


# --- outputs -----------------------------------------------------------------------------------
def csv_rows(summary: dict) -> tuple[list[str], list[list]]:
    """Header and rows of refinement.csv: one row per level; empty cells where undefined."""
    size_key = "mesh_size" if summary["kind"] == "solid" else "elements"
    header = ["level", "h", size_key, "dofs", "wall_time_s", "status"]
    columns = (
        "value",
        "difference",
        "order",
        "extrapolated",
        "error_estimate",
        "extrapolation_change",
    )
    for quantity in summary["quantities"]:
        header += [f"{quantity}.{c}" for c in columns]
    rows = []
    for k, record in enumerate(summary["levels"]):
        row = [
            record["level"],
            record["h"],
            record[size_key],
            record["dofs"],
            record["wall_time_s"],
            record["status"],
        ]
        for quantity in summary["quantities"]:
            levels = summary["analysis"].get(quantity, {}).get("levels", [])
            cells = levels[k] if k < len(levels) else {}
            row += ["" if cells.get(c) is None else cells[c] for c in columns]
        rows.append(row)
    return header, rows


def _exports(out: Path, content, plot: bool = True) -> list:
    """refinement.json, refinement.csv (rewritten whole: the analysis of earlier levels changes
    with each new one) and, with ``plot``, refinement.png once the study has finished."""

    out = Path(out)
    return [SummaryExport(out / "refinement.json", content),
            TableExport(out / "refinement.csv", csv_rows, content),
            PlotExport(lambda summary: _draw(out, summary)) if plot else None]


def _draw(out: Path, summary: dict) -> None:
    if any(r["values"] for r in summary["levels"]):
        plot_convergence(summary, out / "refinement.png")


def write_outputs(out: Path, summary: dict, plot: bool = True) -> None:
    """refinement.json, refinement.csv (atomic) and, with ``plot``, refinement.png."""

    Exports(_exports(out, lambda: summary, plot=False)).finish(summary)
    if plot:
        _draw(Path(out), summary)


def plot_convergence(summary: dict, path: Path) -> None:
    """Log-log |q_k - q*| (q* the finest extrapolation) and |d_k| against h, one panel per
    quantity, with a line of the observed slope through the finest point."""

    quantities = summary["quantities"]
    done = [r for r in summary["levels"] if r["values"]]
    h = [r["h"] for r in done]
    size = (4.6 * len(quantities), 4.0)
    with figure(path, 1, len(quantities), figsize=size, squeeze=False) as (fig, axes):
        for axis, quantity in zip(axes[0], quantities, strict=True):
            result = summary["analysis"][quantity]
            rows = result["levels"]
            unit = UNITS[quantity]
            best, order = result["extrapolated"], result["order"]
            drawn, errors = False, []
            if best is not None and order is not None:
                errors = [(hk, abs(r["value"] - best)) for hk, r in zip(h, rows, strict=True)]
                errors = [(x, y) for x, y in errors if y > 0]
                if errors:
                    axis.loglog(*zip(*errors, strict=True), "o-", label="|q - q extrapolated|")
                    drawn = True
            differences = [
                (hk, abs(r["difference"]))
                for hk, r in zip(h, rows, strict=True)
                if r["difference"] is not None and r["difference"] != 0
            ]
            if differences:
                axis.loglog(
                    *zip(*differences, strict=True), "s--", mfc="none",
                    label="|q_k - q_(k-1)| at h_k",
                )
                drawn = True
            shown = order if order is not None else table_order(result)[0]
            if shown is not None and drawn:
                order = shown
                anchor_h, anchor = errors[-1] if errors else differences[-1]
                xs = [h[0], h[-1]]
                axis.loglog(  # offset below the data so that neither hides the other
                    xs,
                    [0.3 * anchor * (x / anchor_h) ** order for x in xs],
                    "k:",
                    lw=1,
                    label=f"slope {order:.2f} (observed order)",
                )
            if not drawn:
                axis.text(
                    0.5,
                    0.5,
                    "differences at round-off:\nnothing to plot",
                    ha="center",
                    va="center",
                    transform=axis.transAxes,
                )
            axis.set_title(f"{quantity} [{unit}]\n{table_order(result)[1]}", fontsize=10)
            axis.set_xlabel("element size h [m]")
            axis.set_ylabel(f"error estimate [{unit}]")
            axis.grid(alpha=0.3, which="both")
            if drawn:
                _log_ticks(axis, h)
            if drawn:
                axis.legend(fontsize=7)
        fig.suptitle(
            f"mesh refinement ({summary['refined']}, ratio {summary['ratio']:g})", fontsize=10
        )


def table_order(result: dict) -> tuple[float | None, str]:
    """The observed order as the printed table shows it, and a title text for it: the study's
    order, else the last level with a clean order (then, e.g., round-off at the finest level:
    converged), else "order undefined"."""
    rows = result.get("levels", [])
    if result.get("order") is not None:
        return result["order"], f"observed order {result['order']:.2f}"
    clean = [(k, row) for k, row in enumerate(rows) if row.get("order") is not None
             and not row.get("note")]
    final = rows[-1].get("note") if rows else None
    if clean:
        k, row = clean[-1]
        text = f"observed order {row['order']:.2f} (level {k})"
        if final == "round-off":
            text += ", then round-off"
        elif final:
            text += f", finest level {final}"
        return row["order"], text
    if final == "round-off":
        return None, "converged to round-off"
    return None, "order undefined"


def _log_ticks(axis, h: list[float]) -> None:
    """Readable log-log ticks on less than a decade: the mesh sizes on x, and 1-2-5 steps on y
    when the default decades leave fewer than two labels."""
    from matplotlib.ticker import FixedLocator, LogFormatterSciNotation, LogLocator, NullLocator

    sizes = sorted(set(h))
    axis.xaxis.set_major_locator(FixedLocator(sizes))
    axis.xaxis.set_major_formatter(lambda x, _: f"{x:.3g}")
    axis.xaxis.set_minor_locator(NullLocator())
    for label in axis.get_xticklabels():
        label.set_rotation(30)
    bottom, top = axis.get_ylim()
    if bottom > 0 and top / bottom < 100:
        axis.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        axis.yaxis.set_major_formatter(LogFormatterSciNotation(labelOnlyBase=False))
        axis.yaxis.set_minor_locator(LogLocator(base=10, subs="auto"))
        axis.yaxis.set_minor_formatter(lambda y, _: "")


def _number(value, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def format_table(summary: dict) -> str:
    """The printed study: per quantity a table of levels, then the verdict and notes."""
    size_key = "mesh_size" if summary["kind"] == "solid" else "elements"
    lines = []
    done = [r for r in summary["levels"] if r["values"]]
    for quantity in summary["quantities"]:
        result = summary["analysis"].get(quantity)
        if result is None:
            continue
        unit = UNITS[quantity]
        lines.append(f"{quantity} [{unit}]")
        lines.append(
            f"{'level':>5} {size_key:>10} {'h':>10} {'dofs':>8} {'time s':>8} {'value':>18} "
            f"{'difference':>11} {'order':>6} {'extrapolated':>18} {'est. error':>10}"
        )
        for record, row in zip(done, result["levels"], strict=True):
            size = record[size_key]
            order = row["order"]
            order_text = "-" if order is None else f"{order:.3f}"
            if row["note"] == "round-off":
                order_text = "noise"
            elif row["note"]:
                order_text += "?"
            lines.append(
                f"{record['level']:>5} {size:>10.4g} {record['h']:>10.3e} {record['dofs']!s:>8} "
                f"{_number(record['wall_time_s'], '.2f'):>8} {row['value']:>18.11g} "
                f"{_number(row['difference'], '.3e'):>11} {order_text:>6} "
                f"{_number(row['extrapolated'], '.11g'):>18} "
                f"{_number(row['error_estimate'], '.2e'):>10}"
            )
        if result["order"] is not None:
            lines.append(
                f"  observed order {result['order']:.3f}; extrapolated "
                f"{result['extrapolated']:.11g} {unit} (estimated error of the finest level "
                f"{result['error_estimate']:.2e})"
            )
        elif result["extrapolated"] is not None:
            lines.append(
                f"  converged to round-off: {result['extrapolated']:.11g} {unit} "
                f"(differences <= {result['error_estimate']:.1e})"
            )
        else:
            lines.append("  no observed order at the finest level")
        lines += [f"  note: {note}" for note in result["notes"]]
    lines += [f"note: {note}" for note in summary["notes"]]
    return "\n".join(lines)


def run_refine_command(args, config: dict, comm, say=None) -> int:
    """``fe-beam refine``: 0 done, 3 a level did not converge (ConfigError -> the CLI's exit 2)."""

    def emit(text: str, stream=sys.stdout) -> None:
        if say is not None:
            say(text, stream)
        elif comm.rank == 0:
            print(text, file=stream, flush=True)

    solid_parser = getattr(_solid_driver(), "parse_solid", None) if "solid" in config else None
    plan = plan_refinement(config, args.levels, args.ratio, args.quantity,
                           solid_parser=solid_parser)
    summary = run_refinement(
        plan, args.out, comm, progress=not args.quiet, config_path=str(args.config), report=emit
    )
    emit(format_table(summary))
    total = sum(r["wall_time_s"] or 0.0 for r in summary["levels"])
    emit(f"{len(summary['levels'])} levels, {total:.2f} s; results in {args.out}")
    if summary["status"] != "completed":
        emit(f"fe-beam: refinement stopped: {summary['message']}", sys.stderr)
        return 3
    return 0


def run(validated, out: Path | None, comm=None, progress: bool = True, echo=None) -> Result:
    """``fe-beam refine`` (the driver contract, `fe_beam.analyses.result`): each level's line
    as it finishes, then the table; the summary is refinement.json's."""
    report = Report(echo)
    comm = comm if comm is not None else world()

    def emit(text: str, stream=sys.stdout) -> None:
        (report.err if stream is sys.stderr else report.out)(text)

    summary = run_refinement(validated.parsed, out, comm, progress=progress,
                             config_path=str(validated.options.get("config_path", "")),
                             report=emit)
    report.out(format_table(summary))
    total = sum(r["wall_time_s"] or 0.0 for r in summary["levels"])
    report.out(f"{len(summary['levels'])} levels, {total:.2f} s; results in {out}")
    code = 0
    if summary["status"] != "completed":
        report.err(f"fe-beam: refinement stopped: {summary['message']}")
        code = EXIT_FAILED
    return Result("refine", summary, code, report.lines)

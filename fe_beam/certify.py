"""Run-time certificates: every number a command reports carries a check computed in the same
run (global equilibrium, energy balance, a path-confirmed critical point, the whole-surface
penetration, an eigenpair residual ...).

A driver appends its checks to its summary's ``checks`` list, one `entry` each::

    summary["checks"].append(certify.entry("global_equilibrium", imbalance, 1e-8,
                                           detail="|sum of forces| / largest load",
                                           remedy="raise [mesh] elements"))

and `settle` (called once per run by the CLI and `fe_beam.run`, after the driver) judges them:
with ``[checks] strict = true`` (the default) a failed check turns a "converged" or "completed"
run into status "failed" (exit code 3), its message naming the check; with ``strict = false``
the run keeps its status and the failure is a warning in ``notes`` (and ``checks_passed`` is
false). A run never reports success with a failed check silently.

No FE imports: the entries are plain dicts (summary.json holds them as they are).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

__all__ = ["SUCCESS", "entry", "failures", "line", "settle", "strict_of"]

#: the statuses that claim an answer: a failed check takes them back (strict) or warns
SUCCESS = ("converged", "completed", "found", "reached")


def entry(name: str, value: float, tolerance: float, *, detail: str = "", remedy: str = "",
          passed: bool | None = None) -> dict:
    """One check as summary.json holds it: ``{name, value, tolerance, passed}`` (and ``detail``,
    what was measured, and ``remedy``, what helps when it fails, where given). ``passed``
    defaults to ``value <= tolerance``; a value that is not a finite number never passes."""
    value = float(value)
    tolerance = float(tolerance)
    if passed is None:
        passed = math.isfinite(value) and value <= tolerance
    record = {"name": str(name), "value": value if math.isfinite(value) else str(value),
              "tolerance": tolerance, "passed": bool(passed) and math.isfinite(value)}
    if detail:
        record["detail"] = detail
    if remedy:
        record["remedy"] = remedy
    return record


def failures(checks: Iterable[dict] | None) -> list[dict]:
    """The failed entries of a ``checks`` list."""
    return [check for check in checks or [] if not check.get("passed", False)]


def line(check: dict) -> str:
    """One sentence on a check: its name, value against tolerance, what it measured and what
    helps."""
    value = check["value"]
    shown = f"{value:.3g}" if isinstance(value, float) else str(value)
    passed = check.get("passed")
    above = isinstance(value, float) and value > check["tolerance"]
    relation = "<=" if passed else ("exceeds" if above or not isinstance(value, float)
                                    else "against the tolerance")
    text = (f"check '{check['name']}' {'passed' if passed else 'failed'}: "
            f"{shown} {relation} {check['tolerance']:.3g}")
    if check.get("detail"):
        text += f" ({check['detail']})"
    if not check.get("passed") and check.get("remedy"):
        text += f"; {check['remedy']}"
    return text


def strict_of(config: dict | None) -> bool:
    """``[checks] strict`` of a configuration (validated by the config layer; default true)."""
    table = (config or {}).get("checks")
    if isinstance(table, dict) and isinstance(table.get("strict"), bool):
        return table["strict"]
    return True


def settle(summary: dict, strict: bool = True) -> tuple[dict, list[str]]:
    """Judge ``summary["checks"]`` (in place): ``checks_passed`` is set whenever the run made
    checks; with failures and a success status, strict runs become status "failed" (the
    message names the first failed check, then the run's own message) and lenient ones keep
    their status with a warning per failure in ``notes``. Returns the summary and the lines to
    report (empty when nothing failed)."""
    checks = summary.get("checks")
    if not checks:
        return summary, []
    bad = failures(checks)
    summary["checks_passed"] = not bad
    if not bad:
        return summary, []
    lines = [line(check) for check in bad]
    if summary.get("status") not in SUCCESS:
        return summary, lines  # already stopped: the failures explain it further
    if strict:
        previous = summary.get("message") or ""
        summary["status"] = "failed"
        summary["message"] = (f"the result is not certified: {lines[0]}"
                              + (f" (the solver itself reported: {previous})" if previous else "")
                              + ("; [checks] strict = false reports it as a warning instead"))
        return summary, lines
    summary["checks_strict"] = False
    notes = summary.setdefault("notes", [])
    for text in lines:
        note = f"not certified ([checks] strict = false): {text}"
        if note not in notes:
            notes.append(note)
    return summary, lines

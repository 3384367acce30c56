"""Run-time certificates of a solved rod state (issue 28, section 1): the global equilibrium
(`fe_beam.fem.equilibrium`) and the stability of the final state, as `fe_beam.certify` entries
for a summary's ``checks``."""

from __future__ import annotations

import numpy as np

from fe_beam import certify
from fe_beam.fem.equilibrium import (
    balance,
    curved_moment_allowance,
    rod_wrenches,
    roundoff_force,
    spatial_moment_allowance,
)

__all__ = ["EQUILIBRIUM_FLOOR", "equilibrium_entry", "equilibrium_tolerance", "stability_entry"]

#: the smallest tolerance of the global equilibrium (relative to the largest load): round-off
#: of the assembled reactions and loads of a well-conditioned rod stays below 1e-10
EQUILIBRIUM_FLOOR = 1e-7
#: the tolerance is this multiple of Newton's relative residual tolerance when larger
RTOL_FACTOR = 1e3


def equilibrium_tolerance(rtol: float) -> float:
    """The global equilibrium's tolerance: max(EQUILIBRIUM_FLOOR, RTOL_FACTOR * rtol). A
    converged run passes it by orders of magnitude (measured 1e-12 .. 1e-10); a load off by
    1 %, or Newton stopped at a loose rtol, does not."""
    return max(EQUILIBRIUM_FLOOR, RTOL_FACTOR * float(rtol))


def equilibrium_entry(problem, rtol: float, contact_entries=None, label: str = "",
                      tensions=(), contact_tolerance: float = 0.0) -> dict:
    """The global equilibrium of ``problem``'s current state as a check (collective): the
    supports' reactions, the applied loads on the deformed shape and the contact forces sum to
    zero, forces and moments, relative to the largest force (moments: largest moment or
    force x length; ``tensions``: the tendons' tensions, self-equilibrated on the rod, count
    in the force scale). ``value`` is the larger of the force imbalance and the moment imbalance
    beyond a spatial rod's interpolation allowance
    (`fe_beam.fem.equilibrium.spatial_moment_allowance`, 0 in the plane) and beyond the
    accuracy of the contact forces: the contact iterations stop when an update would change
    them by less than ``contact_tolerance`` (`[contact] force_tolerance`) of themselves, so
    that share of the contact forces and moments is allowed."""
    terms = rod_wrenches(problem, contact_entries)
    internal = float(sum(abs(t) for t in tensions)) if len(tensions) else 0.0
    result = balance(terms, problem.model.length, internal)
    allowance = spatial_moment_allowance(problem)
    curved = curved_moment_allowance(problem)
    contact = [term for term in terms if term.name.startswith("contact")]
    contact_force = contact_moment = 0.0
    if contact and contact_tolerance > 0 and result["force_scale"] > 0:
        contact_force = contact_tolerance * sum(
            float(np.linalg.norm(term.force)) for term in contact) / result["force_scale"]
        contact_moment = contact_tolerance * sum(
            float(np.linalg.norm(term.moment)) for term in contact) / result["moment_scale"]
    # the reactions' round-off (machine epsilon x EA): a tiny load on a stiff rod is balanced
    # only to that (measured 3e-9 N for P = 1e-3 N on a steel rod of EA = 6.3e7 N)
    roundoff = roundoff_force(problem)
    roundoff_f = roundoff / result["force_scale"] if result["force_scale"] > 0 else 0.0
    roundoff_m = (roundoff * problem.model.length / result["moment_scale"]
                  if result["moment_scale"] > 0 else 0.0)
    value = max(result["force"] - contact_force - roundoff_f,
                result["moment"] - allowance - curved - contact_moment - roundoff_m, 0.0)
    where = f" {label}" if label else ""
    detail = (f"|sum of forces| / largest force = {result['force']:.3g}, |sum of moments about "
              f"the origin| / largest moment = {result['moment']:.3g}"
              + (f" (less {allowance:.3g}, the rotation-vector interpolation's allowance)"
                 if allowance else "")
              + (f" (less {curved:.3g}, the curved rods' interpolation allowance)"
                 if curved else "")
              + (f" (less {roundoff_f:.3g}, the reactions' round-off 10 eps EA)"
                 if roundoff_f > 1e-12 else "")
              + (f"; the contact forces' accuracy ([contact] force_tolerance) allows "
                 f"{contact_force:.3g} and {contact_moment:.3g}" if contact_force else "")
              + f"{where}: reactions, applied loads"
              + (", contact forces" if contact_entries else "")
              + " on the deformed shape (tendons are internal)")
    return certify.entry(
        "global_equilibrium", value, equilibrium_tolerance(rtol), detail=detail,
        remedy="lower [solver] rtol (Newton stopped before equilibrium) or refine [mesh] "
               "elements; a persistent imbalance is a defect: please report it")


def stability_entry(stability: dict | None) -> dict | None:
    """The stability (inertia) of the final state as an informational check: it passes
    whatever the count (a run may end legitimately unstable: the run's own warning says so);
    ``value`` is the number of energy-decreasing directions. None when not checked."""
    if not stability:
        return None
    count = int(stability.get("energy_decreasing_directions", 0))
    detail = ("the final state's energy-decreasing directions (0: stable)" if count == 0 else
              f"the final state has {count} energy-decreasing direction(s): unstable, "
              "informational (not a failure)")
    return certify.entry("stability", float(count), float(count), detail=detail, passed=True)

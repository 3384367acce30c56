"""Contact with rigid obstacles as a solver wrapper: Newton at fixed multipliers and a fixed
active set, then active-set updates until the set is consistent with the pressures, and Uzawa
updates of the augmented-Lagrangian multipliers (`fe_beam.fem.contact.ContactSet.update`)
until the largest penetration, and the largest gap of a pressed point (complementarity
p g = 0), are below the tolerance; with friction also until the stick/slip state agrees with
Coulomb's return map, every slip traction is mu p_n of the converged pressure and no stuck point
slipped more than the tolerance. Same interface as
`fe_beam.solvers.newton.SNESSolver`, so the one continuation engine
(`fe_beam.solvers.continuation.Continuation`) still does the load stepping and the cut-backs: a
step whose penetration stays above the tolerance after ``max_updates`` updates raises
`SolveFailed` (a rejected step, never a converged one). Writes no files."""

from __future__ import annotations

import numpy as np

from fe_beam.fem.contact import ContactSet
from fe_beam.model.obstacles import MAX_PENALTY
from fe_beam.solvers.newton import SolveFailed

__all__ = ["ContactSolver"]


class ContactSolver:
    """Uzawa iterations around a fixed-multiplier solver (an `SNESSolver`, or a
    `fe_beam.solvers.pull_in.PullInSolver` with tendons). Every solve starts from the
    multipliers of the last accepted state (`ContactSet.commit`, called by the continuation
    when a step is accepted), so a failed or vetoed try leaves nothing behind."""

    def __init__(self, solver, contact: ContactSet):
        self.solver = solver
        self.problem = solver.problem
        self.contact = contact
        self.linear_iterations = 0
        self.updates = 0  # Uzawa updates of the last solve
        self.penetration = 0.0  # the largest penetration after the last solve [m]
        #: the most Newton iterations one solve at fixed multipliers took in the last
        #: `solve`: the step's difficulty for the step-size control (`iterations` sums the
        #: Uzawa updates' solves, which grow with the force accuracy, not with the step)
        self.hardest_solve = 0

    @property
    def load_factor(self):
        return getattr(self.solver, "load_factor", 0.0)

    @load_factor.setter
    def load_factor(self, value) -> None:
        if hasattr(self.solver, "load_factor"):
            self.solver.load_factor = value

    def residual_norm(self) -> float:
        return self.solver.residual_norm()

    def set_reference_residual(self, value: float | None) -> None:
        self.solver.set_reference_residual(value)

    def set_load_factor(self, value) -> None:
        setter = getattr(self.solver, "set_load_factor", None)
        if setter is not None:
            setter(value)

    def destroy(self) -> None:
        self.solver.destroy()

    def solve(self) -> int:
        """The fixed-multiplier solver's Newton inside the Uzawa and active-set updates."""
        return self.solve_with(self.solver.solve, count_linear=True)

    def solve_with(self, inner, count_linear: bool = False) -> int:
        """The updates around any fixed-multiplier solve ``inner() -> iterations`` that
        raises `SolveFailed` (e.g. the arc-length corrector of
        `fe_beam.solvers.continuation.Continuation.step`, which then corrects again from its
        current iterate at every update): the same acceptance and failures as `solve`."""
        contact = self.contact
        contact.restore()
        iterations, linear = 0, 0
        tolerance = contact.tolerance
        limit = contact.settings.max_updates
        forces_of = getattr(contact, "force_changes", None)
        inaccurate, edge_reason = False, None
        try:
            self.hardest_solve = 0
            for update in range(limit + 1):
                solved = inner()
                iterations += solved
                self.hardest_solve = max(self.hardest_solve, solved)
                linear += self.solver.linear_iterations if count_linear else 0
                state = contact.evaluate()
                penetration = contact.max_penetration(state)
                separation = contact.max_separation(state)
                changes = state["active_changes"]
                sliding = state["friction_changes"]
                self.updates, self.penetration = update, penetration
                geometric = (penetration <= tolerance and separation <= tolerance
                             and changes == 0 and sliding == 0)
                accurate = True
                if forces_of is not None and changes == 0:
                    # the next update would change the pressures by less than force_tolerance
                    # of the force (the rod's force scale EI / L^2 the floor near first touch)
                    forces, change = forces_of(state)
                    accurate = bool(np.all(change <= contact.settings.force_tolerance
                                           * (forces + contact.force_scale)))
                if geometric and accurate:
                    # a converged contact on a box's edge or corner: its force would not be
                    # normal to the rod (`ContactSet.edge_contact`): never accepted
                    edge = getattr(contact, "edge_contact", None)
                    edge_reason = edge(state) if edge is not None else None
                    if edge_reason:
                        break
                    self.linear_iterations = linear
                    return iterations
                inaccurate = geometric
                if update == limit:
                    break
                # a new active set first; the multipliers once the set is consistent
                contact.update(state, multipliers=changes == 0)
        except SolveFailed as error:
            contact.restore()
            raise SolveFailed(f"{error} (contact: after {update} augmented-Lagrangian "
                              "updates)") from None
        contact.restore()
        if edge_reason:
            raise SolveFailed(edge_reason)
        if changes:
            raise SolveFailed(f"contact: the active set still changed at {changes} contact "
                              f"points after {limit} updates")
        if sliding:
            raise SolveFailed(f"contact: the stick/slip state or the friction traction was "
                              f"still inconsistent at {sliding} contact points after {limit} "
                              "updates")
        if inaccurate:
            settings = contact.settings
            hint = (f"raise [contact] max_updates (now {settings.max_updates}), or accept a "
                    f"coarser force: force_tolerance (now {settings.force_tolerance:.3g}, e.g. "
                    "0.05)" + (", or raise penalty (faster updates)"
                               if settings.penalty < MAX_PENALTY else ""))
            raise SolveFailed(f"contact: the contact force was still changing by more than "
                              f"{contact.settings.force_tolerance:.3g} of itself after {limit} "
                              f"augmented-Lagrangian updates ({hint})")
        if penetration > tolerance:
            raise SolveFailed(f"contact: penetration {penetration:.3g} m above the tolerance "
                              f"{tolerance:.3g} m after {limit} augmented-Lagrangian updates")
        raise SolveFailed(f"contact: pressed points {separation:.3g} m clear of the obstacle "
                          f"(above the tolerance {tolerance:.3g} m) after {limit} "
                          "augmented-Lagrangian updates")

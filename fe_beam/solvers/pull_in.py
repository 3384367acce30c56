"""Pull-in control of the rod's tendons (their tensions as global unknowns of the Newton
system, one bordered solve per iteration) and the tension that reaches a target."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from fe_beam.fem.tendons import TendonSet
from fe_beam.solvers.continuation import BorderedConstraintSolver
from fe_beam.solvers.newton import SNESSolver

__all__ = ["PullInSolver", "tension_for_target"]


class PullInSolver:
    """Pull-in control: the tensions of the pull-in controlled tendons are global unknowns of the
    beam's Newton system, with the constraints l_i(w) = l_i^0 - load factor * pull_in_i
    (`fe_beam.solvers.continuation.BorderedConstraintSolver`: one bordered solve per iteration).
    Same
    interface as `SNESSolver` so load stepping and time stepping drive it unchanged."""

    def __init__(
        self, solver: SNESSolver, tendons: TendonSet, tolerance: float = 1e-10, max_it: int = 20
    ):
        self.solver = solver
        self.problem = solver.problem
        self.tendons = tendons
        self.controlled = [i for i, t in enumerate(tendons.tendons) if t.controlled_by_pull_in]
        self.tolerance = tolerance * tendons.length
        self.max_it = max_it
        self.load_factor = 0.0
        self._bordered = BorderedConstraintSolver(
            solver, self._get_tensions, self._set_tensions,
            lambda x: self.tendons.lengths()[self.controlled],
            lambda x: [self.tendons.gradient(i, self.problem.bcs) for i in self.controlled],
            self.targets, self.tolerance, max(max_it, solver.settings.max_it),
        )

    @property
    def linear_iterations(self) -> int:
        if self.controlled:
            return self._bordered.linear_iterations
        return self.solver.linear_iterations

    def _get_tensions(self) -> np.ndarray:
        return np.array([float(self.tendons.tensions[i].value) for i in self.controlled])

    def _set_tensions(self, values) -> None:
        for i, value in zip(self.controlled, values, strict=True):
            self.tendons.tensions[i].value = float(value)

    def residual_norm(self) -> float:
        return self.solver.residual_norm()

    def destroy(self) -> None:
        self.solver.destroy()

    def set_reference_residual(self, value: float | None) -> None:
        self.solver.set_reference_residual(value)
        self._bordered.set_reference_residual(value)

    def set_load_factor(self, value) -> None:
        """Pull-ins are value * pull_in: one factor, or an array (one per controlled tendon)."""
        self.load_factor = value

    def targets(self) -> np.ndarray:
        pulls = np.array([self.tendons.tendons[i].pull_in for i in self.controlled])
        return self.tendons.rest_lengths[self.controlled] - self.load_factor * pulls

    def solve(self) -> int:
        if not self.controlled:
            return self.solver.solve()
        self.solver.set_reference_residual(None)
        return self._bordered.solve()


def tension_for_target(
    solve_with_tension: Callable[[float], float], target: float, bracket: tuple[float, float]
) -> float:
    """Tension at which ``solve_with_tension(tau)`` (e.g. tip angle) equals ``target`` (brentq)."""
    from scipy.optimize import brentq  # scipy loaded when first used

    low, high = bracket
    return brentq(lambda tau: solve_with_tension(tau) - target, low, high, xtol=1e-12, rtol=1e-12)

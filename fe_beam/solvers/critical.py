"""Critical points along an equilibrium path and branch switching (docs/theory.md, Critical
points and branch switching).

Built on the continuation engine `fe_beam.solvers.continuation.Continuation` (its ``snapshot``,
``restore``, ``solve_at``, ``step`` and ``set_predictor_direction``) and on the rod's
`fe_beam.analyses.static.StaticContinuation`:

- a **limit point** is where the load parameter turns: the parameter component of the unit
  tangent changes sign between two accepted points. It is located by bisection on the
  arc length of one step from the point before (`locate_limit`);
- a **bifurcation point** is where the number of energy-decreasing directions (negative
  eigenvalues of the tangent stiffness on the constraint-preserving directions) changes while
  the parameter does not turn. It is located by bisection on the load factor, each trial an
  equilibrium at a fixed parameter from the point before (`locate_bifurcation`), and reported
  with its critical mode (the eigenvector of the smallest eigenvalue there);
- **branch switching** (`switch_branch`): from a bifurcation point, one arc-length step whose
  predictor is the critical mode (either sign), its Riks plane normal to the mode, so the
  corrector lands on the bifurcated branch, not back on the fundamental one.

The tangent's inertia comes from a dense eigenvalue problem (serial, up to
`STABILITY_MAX_DOFS` dofs, the same restriction to constraint-preserving
directions and Jacobi scaling as `fe_beam.analyses.static.StaticContinuation.stability`); on several
ranks or beyond that size from a sparse MUMPS LDL^T factorisation (`fe_beam.solvers.inertia`): the
count only (no eigenvalues, no mode), and bisection then decides on the counts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.sparse

from fe_beam.fem import compat
from fe_beam.solvers.continuation import ContinuationFailed, Snapshot
from fe_beam.solvers.inertia import rod_unstable_count

__all__ = [
    "CriticalPoint",
    "Spectrum",
    "locate_bifurcation",
    "locate_limit",
    "spectrum",
    "switch_branch",
]

# the stability check is a dense eigenvalue problem: O(n^3), a few tenths of a second here
STABILITY_MAX_DOFS = 1500
# relative size (to the largest) below which an eigenvalue of the Jacobi-scaled tangent counts
# as zero. The buckling eigenvalue of a slender column is ~1e-8 of the axial ones at L/h = 100
# and passes zero at the critical load; round-off is ~1e-15. (1e-9 called a column 1.4% past
# its Euler load at L/h = 100 stable.)
STABILITY_ZERO = 1e-13
ZERO = STABILITY_ZERO  # an eigenvalue that counts as zero


@dataclass
class Spectrum:
    """Lowest eigenpairs of the tangent stiffness on the constraint-preserving directions.

    ``unstable``: count of negative eigenvalues (energy-decreasing directions); ``values``:
    the eigenvalues (Jacobi-scaled, ascending); ``mode``: the eigenvector of the eigenvalue of
    smallest magnitude as local dofs of the state (multipliers 0), scaled to unit max over
    the u, v, theta dofs. From the sparse inertia (parallel, large): ``values`` empty and
    ``mode`` None."""

    unstable: int
    values: np.ndarray
    mode: np.ndarray | None = field(default=None, repr=False)


@dataclass
class CriticalPoint:
    """A located critical point: ``kind`` "limit" or "bifurcation", ``load_factor``,
    ``tip`` {u, v, theta}, ``mode`` (local dofs, None for limit points located without it),
    ``bracket`` (the two load factors the bisection ended with), ``snapshot`` of the state
    at the point (the side after it for a bifurcation) and the unstable counts on both
    sides."""

    kind: str
    load_factor: float
    tip: dict
    mode: np.ndarray | None = field(default=None, repr=False)
    bracket: tuple[float, float] = (math.nan, math.nan)
    snapshot: Snapshot | None = field(default=None, repr=False)
    unstable_before: int | None = None
    unstable_after: int | None = None

    def summary(self) -> dict:
        return {"load_factor": self.load_factor, "kind": self.kind, "tip": self.tip}


def spectrum(run, with_mode: bool = False) -> Spectrum | None:
    """The tangent's spectrum at ``run``'s current state (a
    `fe_beam.analyses.static.StaticContinuation`);
    None when not available (follower loads or pull-in control: the tangent is not that of an
    energy). On several ranks or beyond STABILITY_MAX_DOFS dofs: the count from the sparse
    inertia (`fe_beam.solvers.inertia.rod_unstable_count`), no eigenvalues, no mode."""

    problem, nonlinear = run.problem, run.snes.problem
    pull_in = run.tendons is not None and any(
        t.controlled_by_pull_in for t in run.tendons.tendons)
    size = problem.global_dofs
    if pull_in or run.config.model.loads.follower or not getattr(problem, "conservative", True):
        return None
    if problem.comm.size > 1 or size > STABILITY_MAX_DOFS:

        return Spectrum(rod_unstable_count(run), np.empty(0), None)
    state = compat.vector_of(nonlinear.w).copy()
    try:
        rows, columns, values = nonlinear.symmetric_tangent(state).getValuesCSR()
    finally:
        state.destroy()
    tangent = scipy.sparse.csr_matrix((values, columns, rows), shape=(size, size)).toarray()
    tangent = 0.5 * (tangent + tangent.T)
    multiplier = np.zeros(size, dtype=bool)
    multiplier[problem.multiplier_dofs()] = True
    free = ~multiplier
    # Dirichlet rows are identity rows: keep them (eigenvalue 1, never critical)
    stiffness = tangent[free][:, free]
    scale = np.sqrt(np.abs(np.diag(stiffness)))
    scale[scale == 0.0] = 1.0
    stiffness /= scale[:, None] * scale[None, :]
    basis = None
    if multiplier.any():
        constraints = tangent[multiplier][:, free] / scale[None, :]
        norms = np.linalg.norm(constraints, axis=1)
        constraints = constraints[norms > 0] / norms[norms > 0, None]
        basis = scipy.linalg.null_space(constraints)
        stiffness = basis.T @ stiffness @ basis
    if with_mode:
        eigenvalues, vectors = np.linalg.eigh(stiffness)
    else:
        eigenvalues, vectors = np.linalg.eigvalsh(stiffness), None
    unstable = int(np.sum(eigenvalues < -ZERO * np.abs(eigenvalues).max()))
    mode = None
    if with_mode:
        vector = vectors[:, int(np.argmin(np.abs(eigenvalues)))]
        if basis is not None:
            vector = basis @ vector
        full = np.zeros(size)
        full[free] = vector / scale
        kinematic = np.zeros(size, dtype=bool)
        for name in problem.components:
            kinematic[problem.component_dofs(name)] = True
        largest = np.abs(full[kinematic]).max()
        mode = full / largest if largest > 0 else full
        # the sign convention: the largest kinematic entry positive
        if full[kinematic][np.argmax(np.abs(full[kinematic]))] < 0:
            mode = -mode
    return Spectrum(unstable, eigenvalues, mode)


def _tolerance(load_factor: float, tol: float) -> float:
    return tol * max(1.0, abs(load_factor))


def locate_bifurcation(run, engine, before: Snapshot, after: Snapshot, unstable_before: int,
                       tol: float = 1e-6, max_bisections: int = 60,
                       crossing: int = 0) -> CriticalPoint:
    """Bisection on the load factor between two converged states whose unstable counts differ
    (``before`` with ``unstable_before``), each trial an equilibrium at a fixed load factor
    solved from ``before`` (`Continuation.solve_at`), until the bracket is narrower than
    ``tol`` (relative to max(1, |load factor|)). ``crossing``: which change of the count along
    the step (0: the first; a step whose count changes by k > 1 crossed k points, located
    one by one with crossing = 0 .. k-1). The engine is left at ``after``."""
    low, high = before.parameter, after.parameter
    low_state = before
    high_state = after
    engine.restore(after)
    count_after = spectrum(run).unstable
    # the eigenvalue that crosses zero (ascending index) and the sign it has after the point:
    # its own sign decides each trial (no threshold: the located load factor is then limited
    # by round-off, not by ZERO)
    negative_after = count_after > unstable_before
    if not 0 <= crossing < abs(count_after - unstable_before):
        raise ValueError(f"crossing {crossing}: the count changes by "
                         f"{abs(count_after - unstable_before)} in the bracket")
    index = unstable_before + crossing if negative_after else unstable_before - crossing - 1
    # the count on either side of this crossing
    unstable_before = index if negative_after else index + 1
    count_after = index + 1 if negative_after else index
    for _ in range(max_bisections):
        if abs(high - low) <= _tolerance(high, tol):
            break
        middle = 0.5 * (low + high)
        engine.solve_at(middle, low_state, emit=False)
        trial = spectrum(run)
        if trial.values.size:
            crossed = (trial.values[index] < 0) == negative_after
        else:  # the sparse inertia: the count alone (past this crossing or not)
            crossed = (trial.unstable >= count_after if negative_after
                       else trial.unstable <= count_after)
        if not crossed:
            low, low_state = middle, engine.snapshot()
        else:
            high, high_state = middle, engine.snapshot()
    count_high = count_after
    engine.restore(high_state)
    run.load_factor = high
    found = spectrum(run, with_mode=True)
    point = CriticalPoint("bifurcation", 0.5 * (low + high), run.problem.end_values("xL"),
                          found.mode, (low, high), high_state, unstable_before, count_high)
    engine.restore(after)
    run.load_factor = after.parameter
    return point


def locate_limit(run, engine, before: Snapshot, size: float, tol: float = 1e-6,
                 max_bisections: int = 60) -> CriticalPoint:
    """Bisection on the length of one arc-length step from ``before`` (whose tangent has the
    parameter component t0) to the point where that component changes sign (``size``: the
    length of the step that crossed it). Stops when the load factors of the two brackets
    agree to ``tol``. The engine is left where it was (the point after the crossing)."""
    after = engine.snapshot()
    sign = math.copysign(1.0, before.tangent[1])
    low, high = 0.0, float(size)
    low_point, high_point = before, after
    for _ in range(max_bisections):
        if abs(high_point.parameter - low_point.parameter) <= _tolerance(
                high_point.parameter, tol) and high - low < 0.5 * size:
            break
        middle = 0.5 * (low + high)
        engine.restore(before)
        try:
            trial = engine.step(middle, emit=False)
        except ContinuationFailed:
            break
        if math.copysign(1.0, trial.tangent_parameter) == sign:
            low, low_point = middle, engine.snapshot()
        else:
            high, high_point = middle, engine.snapshot()
    # the turning point of lambda(s) between the brackets: the larger |lambda| of the two ends
    best = max((low_point, high_point), key=lambda p: sign * p.parameter)
    engine.restore(best)
    run.load_factor = best.parameter
    point = CriticalPoint("limit", best.parameter, run.problem.end_values("xL"), None,
                          (low_point.parameter, high_point.parameter), best)
    engine.restore(after)
    run.load_factor = after.parameter
    return point


def switch_branch(run, engine, point: CriticalPoint, size: float, direction: int = 1):
    """One arc-length step from the bifurcation ``point`` along ``direction`` x its critical
    mode (predictor normal to the fundamental branch's tangent plane by construction of the
    Riks plane): returns the `fe_beam.solvers.continuation.ContinuationPoint` on the new branch; the
    engine's tangent there then continues along the new branch."""
    if point.mode is None or point.snapshot is None:
        raise ValueError("switch_branch: the critical point has no mode")
    engine.restore(point.snapshot)
    run.load_factor = point.snapshot.parameter
    owned = compat.vector_of(run.problem.w).getLocalSize()
    engine.set_predictor_direction(direction * point.mode[:owned], 0.0)
    new = engine.step(size)
    run.load_factor = engine.parameter
    return new

"""Static analysis driver: problem + solver + load stepping + recorders, for the CLI and demos."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam import exports, runctl
from fe_beam.exports.outputs import BeamXDMFWriter, plot_deformed_shapes, plot_load_displacement
from fe_beam.fem import compat
from fe_beam.fem.rod import BeamProblem, StrainWatch
from fe_beam.fem.tendons import PullInSolver, TendonSet
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers.continuation import Continuation, NonlinearParameterProblem
from fe_beam.solvers.newton import (
    LoadSteppingFailed,
    NonlinearProblem,
    SNESSolver,
    StepResult,
    rotation_jump_check,
)

__all__ = ["StaticContinuation", "StaticResult", "solve_static"]


@dataclass
class StaticResult:
    steps: list[dict] = field(default_factory=list)
    shapes: list[tuple[str, dict]] = field(default_factory=list)
    dofs: int = 0
    wall_time_s: float = 0.0
    status: str = "running"
    message: str = ""
    notes: list[str] = field(default_factory=list)
    strain_range: dict | None = None

    def summary(self, extra: dict | None = None) -> dict:
        """summary.json's content; ``extra["notes"]`` (set-up notes) come before the run's."""
        extra = dict(extra or {})
        notes = list(extra.pop("notes", []))
        data = {
            "status": self.status,
            "message": self.message,
            "steps": self.steps,
            "dofs": self.dofs,
            "wall_time_s": self.wall_time_s,
            "notes": notes + [note for note in self.notes if note not in notes],
        }
        if self.strain_range is not None:
            data["strain_range"] = self.strain_range
        return data | (extra or {})


def _step_record(problem: BeamProblem, step: StepResult) -> dict:
    record = {
        "load_factor": step.load_factor,
        "tip": problem.end_values("xL"),
        "newton_iterations": step.iterations,
    }
    if problem.model.loads.end_motion():  # displacement control: the force it takes
        record["reaction_xL"] = problem.end_reaction("xL")
    return record


# the stability check is a dense eigenvalue problem: O(n^3), a few tenths of a second here
STABILITY_MAX_DOFS = 1500
# relative size (to the largest) below which an eigenvalue of the Jacobi-scaled tangent counts
# as zero. The buckling eigenvalue of a slender column is ~1e-8 of the axial ones at L/h = 100
# and passes zero at the critical load; round-off is ~1e-15. (1e-9 called a column 1.4% past
# its Euler load at L/h = 100 stable.)
STABILITY_ZERO = 1e-13


class StaticContinuation:
    """A configuration's problem and solver, built once, whose load factor can be moved from
    its current converged value to any other by load stepping (``advance``): continuation for
    inverse problems and parameter sweeps, where each new equilibrium starts from the last."""

    def __init__(self, config: StaticConfig, comm=MPI.COMM_WORLD,
                 problem: BeamProblem | None = None, prefix: str = "fe_beam_static_",
                 tendons: TendonSet | None = None):
        """``problem``: an existing problem of ``config.model`` to load (e.g. the static
        pre-state of a dynamic run); built from ``config`` when None. With tendons, a given
        problem needs its `TendonSet` (``tendons``: the one whose energy it holds)."""
        if problem is not None and config.tendons and tendons is None:
            raise ValueError("StaticContinuation: a given problem with tendons needs its tendons")
        self.config = config
        self.tendons = tendons or (TendonSet(config.tendons, config.model.length)
                                   if config.tendons else None)
        self.problem = problem or BeamProblem(
            config.model,
            comm,
            breakpoints=self.tendons.breakpoints if self.tendons else (),
            extra_energy=self.tendons.energy if self.tendons else None,
        )
        self.snes = SNESSolver(
            NonlinearProblem(self.problem.residual, self.problem.w, self.problem.bcs),
            config.solver.for_problem(self.problem.saddle_point, self.problem.comm),
            prefix=prefix,
            state_scale=config.model.length,
        )
        self.solver = PullInSolver(self.snes, self.tendons) if self.tendons else self.snes
        self.load_factor = 0.0
        # extremes of the strains over the converged states (notes when out of range)
        self.watch = StrainWatch()
        self._trial_range = None

    def _set_load_factor(self, value: float) -> None:
        self.problem.set_load_factor(value)
        if self.tendons:
            self.tendons.set_tension_controlled(value)
            self.solver.set_load_factor(value)

    def advance(self, target: float, stepping, on_converged=None, progress: bool = False,
                label: str = "load") -> None:
        """Load-step from the current load factor to ``target`` (load control of the engine
        `fe_beam.solvers.continuation.Continuation`); ``on_converged(step)`` gets the actual load
        factor. Raises `LoadSteppingFailed` (a `fe_beam.solvers.continuation.ContinuationFailed`)
        with
        the last converged state kept (and ``load_factor`` at its value)."""
        engine = self.engine()
        engine.parameter = float(self.load_factor)

        def converged(step: StepResult) -> None:
            self.load_factor = step.load_factor
            if self._trial_range is not None:
                self.watch.observe(self._trial_range)
            if on_converged is not None:
                on_converged(step)

        engine.load_control(target, stepping, on_converged=converged, progress=progress,
                            label=label)

    def parameter_problem(self, parameter: str = "load_factor", tendon: int = 0
                          ) -> NonlinearParameterProblem:
        """This problem as a `fe_beam.solvers.continuation.ParameterProblem`: the parameter is the
        load
        factor (every load, tension-controlled tendon and prescribed end value scaled by it:
        with prescribed end values only, this is displacement control) or, with
        ``parameter="tension"``, the tension [N] of tendon ``tendon`` alone (the other tendons
        keep their tensions). The arc metric weighs u and v by 1/L^2, theta by 1 and the
        multipliers by 0; the step check vetoes rotation jumps and inadmissible states.
        Pull-in controlled tendons: load control only."""
        if parameter == "load_factor":
            setter = self._set_load_factor
        elif parameter == "tension":
            if not self.tendons or not 0 <= tendon < len(self.tendons.tendons):
                raise ValueError(f"parameter 'tension': no tendon {tendon}")
            if self.tendons.tendons[tendon].controlled_by_pull_in:
                raise ValueError(f"parameter 'tension': tendon {tendon} is pull-in controlled")
            constant = self.tendons.tensions[tendon]

            def setter(value: float) -> None:
                constant.value = float(value)
        else:
            raise ValueError(f"parameter must be 'load_factor' or 'tension', got {parameter!r}")
        adapter = NonlinearParameterProblem(self.solver, setter, check_step=self._step_check(),
                                            metric=self._metric())
        adapter.arc_length_ready = not (self.tendons and any(
            t.controlled_by_pull_in for t in self.tendons.tendons))
        return adapter

    def engine(self) -> Continuation:
        """The continuation engine of the load factor (built once; its state is this problem's)."""
        if getattr(self, "_engine", None) is None:
            self._engine = Continuation(self.parameter_problem(), self.load_factor)
        return self._engine

    def _metric(self):
        metric = compat.vector_of(self.problem.w).duplicate()
        weights = np.zeros(metric.getLocalSize())
        length = self.config.model.length
        for name, weight in (("u", 1 / length**2), ("v", 1 / length**2), ("theta", 1.0)):
            dofs = self.problem.component_dofs(name)
            weights[dofs] = weight
        metric.getArray()[:] = weights
        return metric

    def _step_check(self):
        """Reject a converged step that jumped branch (rotation jump) or is inadmissible
        (1 + e <= 0 somewhere: `fe_beam.fem.rod.StrainRange`); collective on all ranks."""
        rotation = rotation_jump_check(self.problem.rotation_dofs(),
                                       self.config.max_rotation_jump)

        def check(previous, current):
            reason = rotation(previous, current)
            self._trial_range = self.problem.strain_range()  # collective: on every rank
            return reason or self._trial_range.inadmissible()

        return check

    def stability(self) -> dict | None:
        """Is the current equilibrium stable? The inertia of the tangent stiffness (dense for
        serial problems up to STABILITY_MAX_DOFS dofs, else a sparse parallel MUMPS LDL^T:
        `fe_beam.solvers.inertia`); None when the loads are not conservative (follower forces,
        pull-in
        control).

        With multipliers, the tangent stiffness is restricted to the directions that keep the
        constraints. A negative eigenvalue is a direction in which the energy decreases: the
        beam would buckle or snap away from this state.
        """
        from fe_beam.solvers.critical import spectrum  # the inertia (critical imports static)

        result = spectrum(self)
        if result is None:
            return None
        return {"stable": result.unstable == 0, "energy_decreasing_directions": result.unstable}

    def restart(self) -> None:
        """Back to the unloaded reference state."""
        compat.local_array(self.problem.w)[:] = 0.0
        self.load_factor = 0.0

    def destroy(self) -> None:
        self.snes.destroy()


def solve_static(
    config: StaticConfig,
    out: Path | None = None,
    comm=MPI.COMM_WORLD,
    progress: bool = True,
    extra_summary: dict | None = None,
    on_step=None,
    record_shapes: bool = True,
    extra_exports: list | None = None,
) -> StaticResult:
    """Run the static load stepping of a configuration; writes results under ``out`` if given.

    Tendons of ``config.tendons`` add their potential; steps then also record ``tensions`` and
    ``pull_ins``. ``on_step(problem, record)`` is called after each converged step (on all ranks),
    e.g. to sample profiles along the beam. ``record_shapes=False`` skips the per-step deformed
    shapes and profiles (``result.shapes``) and the stability check of the final state
    (``steps[-1]["stability"]``, `StaticContinuation.stability`) when nothing is written: a
    solve-only run (benchmarks, sweeps) then costs the Newton iterations alone.

    summary.json (status "running" meanwhile), load_displacement.csv and the XDMF file are
    updated as steps converge, at O(1) cost per step (rows and steps are appended; summary.json
    is rewritten at a bounded share of the wall time). On failure the last converged state is
    written and the result has status "failed"; on SIGINT/SIGTERM (`fe_beam.runctl.Interrupted`)
    it is written with status "interrupted" and the exception is re-raised. ``extra_exports``: more
    `fe_beam.exports.Export` objects fed with the step records (e.g. the finger's sweep table).

    The problem and solver come from `fe_beam.solvers.realtime.acquire`: a second solve of the same
    kind of model (same mesh, law, section shape, supports, ...) reuses the built ones.
    """
    started = time.perf_counter()
    notes = check_beam_work(config, config.stepping.steps, comm, quiet=out is None)
    from fe_beam.solvers import realtime  # a problem of this kind built before is reused (no JIT)

    run = realtime.acquire(config, comm)
    problem, tendons = run.problem, run.tendons
    result = StaticResult(dofs=problem.global_dofs)
    root = comm.rank == 0
    writing = out is not None
    if writing and root:
        out.mkdir(parents=True, exist_ok=True)
    extra = {"model": _model_summary(config)} | (extra_summary or {})
    if notes:
        extra["notes"] = list(extra.get("notes", [])) + notes
    xdmf_path = out / "beam.xdmf" if writing and config.output.xdmf else None
    writer = BeamXDMFWriter(problem, xdmf_path) if (record_shapes or xdmf_path) else None
    states = [exports.XDMFExport(writer, "load_factor")] if writer is not None else []
    files = exports.Exports(states + ([
        exports.CSVExport(out / "load_displacement.csv", CSV_COLUMNS),
        exports.SummaryExport(out / "summary.json", lambda: result.summary(extra)),
        exports.PlotExport(lambda _: _write_plots(out, result, config)
                           if config.output.plots and result.shapes else None),
    ] + list(extra_exports or []) if writing else []), comm)
    files.start(result.summary(extra))  # status "running" from the start

    def record(step: StepResult) -> None:
        entry = _step_record(problem, step)
        if tendons:
            entry |= {
                "tensions": tendons.tension_values().tolist(),
                "pull_ins": tendons.pull_ins().tolist(),
            }
        result.steps.append(entry)
        result.notes, result.strain_range = run.watch.notes(), run.watch.summary()
        if on_step is not None:
            on_step(problem, entry)
        result.wall_time_s = time.perf_counter() - started
        files.on_step(entry)
        if writer is not None and record_shapes:
            shape = writer.vertex_values(update=False)
            if root:
                result.shapes.append((f"load factor {step.load_factor:.3g}", shape))

    try:
        run.advance(1.0, config.stepping, on_converged=record, progress=progress)
        result.status = "converged"
        stability = run.stability() if record_shapes else None
        if stability is not None:
            result.steps[-1]["stability"] = stability
    except LoadSteppingFailed as failure:
        result.status, result.message = "failed", str(failure)
    except runctl.Interrupted as stop:
        last = result.steps[-1]["load_factor"] if result.steps else 0.0
        status = stop.stopped(f"load factor {last:.4g}", f"at load factor {last:.6g}")
        result.status, result.message = status["status"], status["message"]
        raise
    finally:
        realtime.release(run)
        result.notes = run.watch.notes() + compressed_tendon_notes(tendons, result.steps)
        result.strain_range = run.watch.summary()
        result.wall_time_s = time.perf_counter() - started
        files.finish(result.summary(extra))  # pictures unless interrupted
    return result


def compressed_tendon_notes(tendons, steps: list[dict]) -> list[str]:
    """A note per pull-in controlled tendon that needed a compressive (negative) tension at
    some converged step: a tendon cannot push (it would go slack), so those states are not
    the tendon-driven rod's."""
    notes = []
    for i, tendon in enumerate(getattr(tendons, "tendons", None) or ()):
        if not tendon.controlled_by_pull_in:
            continue
        values = [(s["tensions"][i], s["load_factor"]) for s in steps if "tensions" in s]
        scale = max([abs(t) for t, _ in values] + [1e-300])
        pushed = [(t, f) for t, f in values if t < -1e-9 * scale]
        if pushed:
            low, factor = min(pushed)
            notes.append(
                f"tendon '{tendon.name}': its pull_in needs a compressive tension (down to "
                f"{low:.4g} N at load factor {factor:.4g}); a tendon cannot push (it would go "
                "slack), so those states hold only for a rod pushed along the tendon's path")
    return notes


def beam_dofs_estimate(config: StaticConfig) -> int:
    """Unknowns of the rod model of ``config``: u, v, theta and one field per constraint."""
    mesh = config.model.mesh
    fields = 3 + {"inextensible": 1, "unshearable": 1,
                  "inextensible-unshearable": 2}.get(config.model.options.constraint, 0)
    return int(fields * (mesh.elements * mesh.degree + 1))


def check_beam_work(config: StaticConfig, steps: float, comm, what: str = " of load stepping",
                    quiet: bool = False) -> list[str]:
    """Up-front limits (`fe_beam.runctl.check_work`): raises `fe_beam.runctl.TooLarge` on work
    beyond them unless ``[solver] allow_large = true``; warns on stderr (unless ``quiet``) and
    returns the warnings for the summary's ``notes``."""
    allow = bool((config.raw.get("solver") or {}).get("allow_large", False))
    notes = runctl.check_work(steps, beam_dofs_estimate(config), allow, what)
    if not quiet:
        runctl.warn(comm, notes)
    return notes


def hyperelastic_summary(options) -> dict:
    """The hyperelastic law's material, constants, small-strain moduli and section points."""
    from fe_beam.fem.section_laws import SOLID_NAMES

    law = options.hyperelastic
    return {
        "material": SOLID_NAMES[law.name],
        "coefficients": law.coefficients(),
        "volumetric": law.volumetric,
        "small_strain": {"E": law.young_modulus, "nu": law.poisson_ratio,
                         "G": law.shear_modulus, "kappa": law.bulk_modulus},
        "section_points": options.points,
    }


def _model_summary(config: StaticConfig) -> dict:
    m = config.model
    law = {"hyperelastic": hyperelastic_summary(m.options)} if m.options.law == "hyperelastic" \
        else {}
    return {
        "length": m.length,
        "law": m.options.law,
        "constraint": m.options.constraint,
        "elements": m.mesh.elements,
        "degree": m.mesh.degree,
        "section": {
            "shape": m.section.shape,
            **m.section.dims,
            **{f"{k}_tip": v for k, v in m.section.dims_tip.items()},
        },
    } | law


# load_displacement.csv
CSV_COLUMNS = [exports.Column("load_factor", lambda s: s["load_factor"]), *exports.tip_columns(),
               exports.Column("newton_iterations", lambda s: s["newton_iterations"])]
CSV_HEADER = [c.name for c in CSV_COLUMNS]


def _write_plots(out: Path, result: StaticResult, config: StaticConfig) -> None:
    every = max(1, len(result.shapes) // 10)
    shapes = result.shapes[every - 1 :: every]
    if result.shapes[-1] is not shapes[-1]:
        shapes.append(result.shapes[-1])
    m = config.model
    title = f"{m.options.law} law, constraint {m.options.constraint}"
    plot_deformed_shapes(shapes, out / "deformed_shapes.png", title, m.length)
    factors = [s["load_factor"] for s in result.steps]
    tips = {f"tip {k}": [s["tip"][k] for s in result.steps] for k in ("u", "v", "theta")}
    plot_load_displacement(factors, tips, out / "load_displacement.png", title)

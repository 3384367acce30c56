"""Drivers of ``fe-beam dynamic`` and ``fe-beam modes``: config tables, runs and outputs.

Extra tables over the statics config:

    [time]    t_end, dt, rho_inf, adaptive, tol, min_dt, max_dt, output_every,
              scheme = "generalized-alpha" | "energy-conserving" | "fd-rk45" | "fd-dop853"
    [initial] from_static (solve the static problem under [loads] first), velocity =
              ["u_t(x)", "v_t(x)", "theta_t(x)"] formulas in x, angular_velocity (rigid spin)
    [loads]   time_function = "formula in t" or time_table = [[t, f], ...] (scales every load),
              motion_function = "formula in t" (scales prescribed end values; default: same)
    [damping] c, kelvin_voigt
    [modes]   count, prestress (linearise about the static state under [loads])
    [[tendons]] as for fe-beam finger, plus time_function = "formula in t" or time_table =
              [[t, f], ...] scaling the tension or pull-in (default: the [loads] one); the
              static pre-state (from_static, prestress) applies them in full; pull_in only in
              dynamics with generalized-alpha (the tension is then an unknown of each step);
              energy-conserving takes tension-controlled tendons as strain potentials
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam import certify, exports, runctl
from fe_beam.analyses.certificates import equilibrium_entry
from fe_beam.analyses.static import (
    StaticContinuation,
    check_beam_work,
    contact_columns,
    structure_columns,
)
from fe_beam.baselines import fd_rk
from fe_beam.config.transient import (  # noqa: F401  (their home; re-exported)
    DAMPING_KEYS,
    INITIAL_KEYS,
    MODES_KEYS,
    TENDON_SAMPLES,
    TENDON_TIME_KEYS,
    TIME_KEYS,
    TIME_LOAD_KEYS,
    DynamicConfig,
    _check_tendons_pull,
    _functions,
    _parse_tendons,
    _split_time_loads,
    _velocity,
    parse_dynamic,
    parse_modes,
)
from fe_beam.errors import ConfigError
from fe_beam.exports.obstacles import bounding_box, write_obstacle_surfaces
from fe_beam.exports.outputs import (
    BeamXDMFWriter,
    _pyplot,
    atomic_write_json,
    atomic_write_text,
    draw_obstacles,
)
from fe_beam.exports.spatial import SpatialXDMFWriter, plot_spatial_shapes
from fe_beam.fem import compat
from fe_beam.fem.contact import ContactSet
from fe_beam.fem.rod import BeamProblem, StrainRange, StrainWatch
from fe_beam.fem.tendons import TendonSet
from fe_beam.model.laws import LAW_KINDS
from fe_beam.model.loads import unsupported
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers.dynamics import DynamicsFailed, GeneralizedAlpha
from fe_beam.solvers.energy_momentum import EnergyMomentum
from fe_beam.solvers.modes import natural_frequencies
from fe_beam.solvers.newton import (
    LoadSteppingFailed,
)
from fe_beam.solvers.rod_static import build_problem
from fe_beam.solvers.spatial_energy_momentum import SpatialEnergyMomentum

__all__ = ["DynamicConfig", "parse_dynamic", "parse_modes", "run_dynamic", "run_modes"]

def _note_pushing_tendons(tendons, tensions, t: float, notes: list, comm) -> None:
    """Note (once per tendon, also a warning on stderr) a pull-in controlled tendon whose
    solved tension is negative at time t: the model then lets the cable push."""
    for tendon, tension in zip(tendons.tendons, tensions, strict=True):
        start = f"[[tendons]] {tendon.name!r} (pull_in control): its tension"
        if (tendon.controlled_by_pull_in and tension < 0
                and not any(note.startswith(start) for note in notes)):
            note = (f"{start} is {tension:.4g} N < 0 at t = {t:.4g} s: a cable cannot push, "
                    "so from then on the results are of a tendon that pushes (ramp the pull-in "
                    "more slowly or add damping)")
            notes.append(note)
            runctl.warn(comm, [note])


def _tendon_problem(static: StaticConfig, comm):
    """(BeamProblem, TendonSet or None) of a configuration: the tendons' breakpoints are mesh
    vertices and their potential is part of the stored energy."""

    tendons = TendonSet(static.tendons, static.model.length) if static.tendons else None
    problem = build_problem(static.model, comm,
                            breakpoints=tendons.breakpoints if tendons else (),
                            extra_energy=tendons.energy if tendons else None)
    return problem, tendons


def _detach_tendon_energy(problem: BeamProblem) -> None:
    """After the static pre-state (solved with the tendon potential as the problem's
    extra_energy): the energy-conserving scheme takes the tendons as potentials in the strains
    (`TendonSet.strain_potentials`, the same offsets, indicators and Gauss rule, so the
    pre-state is its equilibrium too), and the problem's stored energy becomes the rod's alone;
    its static residual, built with the tendon energy, is dropped (no solver of the scheme
    uses it)."""
    problem.extra_energy = None
    problem.residual = None


def _static_prestate(problem: BeamProblem, static: StaticConfig, progress: bool,
                     watch=None, tendons=None) -> None:
    """Load the problem to the static state of ``static``; ``watch`` (a StrainWatch) sees
    the strains of its converged steps; ``tendons``: the problem's TendonSet (full tension)."""
    run = StaticContinuation(static, problem=problem, prefix="fe_beam_prestate_",
                             tendons=tendons)
    if watch is not None:
        run.watch = watch
    try:
        run.advance(1.0, static.stepping, progress=progress, label="static pre-state")
    except LoadSteppingFailed as failure:
        raise PrestateFailed(f"static pre-state: {failure}", failure.last_load_factor) from None
    finally:
        run.destroy()


def _relax_curved(problem, static: StaticConfig, tendons=None) -> None:
    """An initially curved spatial rod starts from its discrete stress-free state, solved at
    load factor 0 (`fe_beam.solvers.rod_static.StaticContinuation`): the reference of the
    displacements and of the tendons' rest lengths (nothing for a straight rod)."""
    if not getattr(problem, "curved", False):
        return
    try:
        run = StaticContinuation(static, problem=problem, prefix="fe_beam_relax_",
                                 tendons=tendons)
    except LoadSteppingFailed as failure:
        raise PrestateFailed(str(failure), 0.0) from None
    run.destroy()


class PrestateFailed(DynamicsFailed):
    """The static pre-state of a dynamic or modal run could not be reached (no equilibrium,
    or only inadmissible ones, beyond ``load_factor``, whose state the problem keeps)."""

    def __init__(self, message: str, load_factor: float):
        super().__init__(message, 0.0)
        self.load_factor = load_factor


def _prestate_record(problem: BeamProblem, failure: PrestateFailed) -> dict:
    """The last converged pre-state (collective): its load factor and tip."""
    return {"load_factor": failure.load_factor, "tip": problem.end_values("xL")}


@dataclass
class DynamicResult:
    history: list[dict]
    info: dict
    status: str = "completed"
    message: str = ""
    dofs: int = 0
    notes: list = field(default_factory=list)
    strain_range: dict | None = None
    #: the last converged static pre-state of a run whose pre-state failed (summary "prestate")
    prestate: dict | None = None
    #: the run-time certificates (summary "checks", `dynamic_checks`) and their measurements
    checks: list = field(default_factory=list)
    certificates: dict = field(default_factory=dict)


def dynamic_checks(certificates: dict) -> tuple[list, list]:
    """The certificates of a time integration (`StepDriver.certificates`) as summary "checks"
    entries: ``energy_balance`` and, with a free flight, ``linear_momentum`` and
    ``angular_momentum``; and the notes on what was not checked."""
    checks, notes = [], []
    energy = certificates.get("energy_balance")
    if energy and energy["checked"]:
        judged = ("|R|" if energy["conserving"] else
                  "max(R, 0) (rho_inf < 1 or contact dissipate: a loss is numerical dissipation, "
                  f"measured as {energy['numerical_dissipation']:.4g} J = "
                  f"{energy['relative_numerical_dissipation']:.3g} of S at the end)")
        failed = energy.get("failed")
        checks.append(certify.entry(
            "energy_balance", energy["value"], energy["tolerance"],
            passed=False if failed else None,
            detail=(f"largest over the steps of {judged} / S, R = kinetic + strain + dissipated"
                    " - external work - initial energy, S the largest of these terms (at t = "
                    f"{energy['t']:.4g} s); a step failing it was halved"
                    + (f"; it failed first at t = {failed['t']:.6g} s at the smallest step: "
                       f"{failed['reason']}" if failed else "")),
            remedy="a smaller [time] dt, or [time] scheme = \"energy-conserving\"; "
                   "with [[obstacles]] rho_inf = 1 (impacts then gain no energy)"))
    elif energy:
        notes.append("the energy balance is not checked: prescribed end motions do work that "
                     "is not measured (kinetic + strain - external work is not conserved)")
    momentum = certificates.get("momentum")
    if momentum:
        for key in ("linear", "angular"):
            checks.append(certify.entry(
                f"{key}_momentum", momentum[key], momentum["tolerance"],
                detail=(f"largest drift of the {key} momentum over {momentum['steps']} free-"
                        f"flight steps (from t = {momentum['from']:.4g} s: no supports, loads, "
                        "damping c, tendons or contact) relative to its scale"),
                remedy="a smaller [time] dt (rho_inf = 1 conserves the momenta exactly)"))
    return checks, notes


def _config_notes(config: DynamicConfig, out: Path | None, comm) -> list:
    """The configuration's own notes (keys the scheme does not use), said when writing."""
    notes = list(getattr(config, "notes", ()))
    if notes and out is not None:
        runctl.warn(comm, notes)
    return notes


def run_dynamic(config: DynamicConfig, out: Path | None, comm=MPI.COMM_WORLD,
                progress: bool = True, strict: bool = True) -> DynamicResult:
    """Integrate; ``strict`` ([checks] strict): a step that fails the energy balance at the
    smallest step stops the run (exit 3), else it is kept and the certificate fails."""
    if config.time.scheme.startswith("fd-"):
        return _run_finite_differences(config, out, comm)
    started = time.perf_counter()
    steps = config.time.t_end / config.time.dt
    if config.time.adaptive and config.time.max_dt:
        steps = config.time.t_end / max(config.time.dt, config.time.max_dt)
    notes = check_beam_work(config.static, steps, comm, " of time stepping",
                            quiet=out is None)
    notes += _config_notes(config, out, comm)
    if config.time.scheme == "energy-conserving" and config.time.adaptive:
        # measured: a step load on an 8-element cantilever took 59k steps to t = 0.09 s
        note = ("[time] adaptive = true with scheme = \"energy-conserving\": the local error "
                "estimate follows the undamped high-frequency content, so the step can shrink to "
                "the mesh's highest period and the run become very long; the scheme is stable "
                "at any step: prefer a fixed dt (adaptive = false)")
        notes.append(note)
        if out is not None:
            runctl.warn(comm, [note])
    if config.from_static:  # the load steps of the static pre-state count too
        notes += check_beam_work(config.static, config.static.stepping.steps, comm,
                                 " of load stepping (static pre-state)", quiet=out is None)
    problem, tendons = _tendon_problem(config.static, comm)
    xdmf = out / "beam.xdmf" if out is not None and config.static.output.xdmf else None
    watch = StrainWatch()
    try:
        if config.from_static:
            _static_prestate(problem, config.static, progress, watch, tendons)
        else:
            _relax_curved(problem, config.static, tendons)
    except runctl.Interrupted as stop:
        stop.where = "the static pre-state (before the time stepping)"
        raise
    except PrestateFailed as failure:
        # no time stepping: the run failed (exit 3) with the last converged pre-state
        # written (summary "prestate", beam.xdmf at t = 0)
        result = DynamicResult([], {"steps": 0}, status="failed", message=str(failure),
                               dofs=problem.global_dofs, notes=notes + watch.notes(),
                               strain_range=watch.summary())
        result.prestate = _prestate_record(problem, failure)
        writer = _writer(problem, xdmf)
        files = exports.Exports(_history_exports(out, config, writer), comm)
        writer.write(0.0)
        result.info["wall_time_s"] = time.perf_counter() - started
        files.finish(dynamic_summary(result, config, result.info["wall_time_s"]))
        return result
    if tendons is not None:
        tendons.set_time_functions(config.tendon_functions)
    if config.time.scheme == "energy-conserving" and getattr(problem, "spatial", False):
        integrator = SpatialEnergyMomentum(problem, config.time, config.damping,
                                           config.load_function, config.motion_function,
                                           config.static.solver)
    elif config.time.scheme == "energy-conserving":
        if tendons is not None:
            _detach_tendon_energy(problem)
        integrator = EnergyMomentum(problem, config.time, config.damping, config.load_function,
                                    config.motion_function, config.static.solver,
                                    tendons=tendons)
    else:
        obstacles = config.static.obstacles
        contact = (ContactSet(obstacles, config.static.contact, config.static.model)
                   if obstacles else None)
        integrator = GeneralizedAlpha(problem, config.time, config.damping,
                                      config.load_function, config.motion_function,
                                      config.static.solver, tendons=tendons, contact=contact)
    integrator.watch = watch
    integrator.energy_stop = strict
    integrator.initialise(config.velocity)
    root, writing = comm.rank == 0, out is not None
    if writing and root:
        out.mkdir(parents=True, exist_ok=True)
    result = DynamicResult([], {}, status="running", dofs=problem.space.dofmap.index_map.size_global
                           * problem.space.dofmap.index_map_bs, notes=notes)
    contact = getattr(integrator, "contact", None)
    writer = _writer(problem, xdmf, contact)
    shapes = []
    files = exports.Exports(_history_exports(
        out, config, writer,
        lambda: dynamic_summary(result, config, time.perf_counter() - started),
        lambda _: _plot_dynamic(out, result, shapes, config, contact)
        if config.static.output.plots and result.history else None), comm)
    files.start(dynamic_summary(result, config, 0.0))  # status "running"

    def record(t: float, step: int) -> None:
        energies = integrator.energies()
        result.history.append({"t": t, "tip": problem.end_values("xL"), "energies": energies,
                               "momenta": integrator.momenta()})
        if getattr(problem, "chain", None) is not None:  # each rod's end (world axes)
            result.history[-1]["rods"] = problem.chain.rods()
            # the joints' forces at t: the parts' inertia with the state's acceleration
            blended = float(problem.load_factor.value)
            problem.load_factor.value = config.load_function(t)
            integrator.end_acceleration()
            result.history[-1]["joints"] = problem.chain.joints_in_motion(
                integrator.end_inertia_work)
            problem.load_factor.value = blended
        if tendons is not None:  # tensions tau_i(t) and pull-ins l_i(0) - l_i of the state
            pull_ins = (tendons.rest_lengths - integrator.tendon_lengths()
                        if isinstance(integrator, EnergyMomentum) else tendons.pull_ins())
            tensions = tendons.applied_tensions(t)
            result.history[-1]["tendons"] = {"tensions": tensions.tolist(),
                                             "pull_ins": pull_ins.tolist()}
            _note_pushing_tendons(tendons, tensions, t, notes, comm)
        if contact is not None:  # the contact state of the accepted step (obstacles at t)
            result.history[-1]["contact"] = contact.summary()
            result.history[-1]["contact_updates"] = integrator.solver.updates
        result.notes, result.strain_range = notes + watch.notes(), watch.summary()
        files.on_step(result.history[-1])
        if config.static.output.plots:
            shape = writer.vertex_values(update=False)
            if getattr(problem, "chain", None) is not None:  # the plots draw the chain
                shape = problem.chain.shape(shape)
            if root:
                shapes.append((t, shape))

    try:
        result.info = integrator.run(record, progress=progress)
        result.status = "completed"
    except DynamicsFailed as failure:
        result.status, result.message = "failed", str(failure)
        result.info = dict(getattr(integrator, "run_info", None) or result.info)
        if not result.history or integrator.time > result.history[-1]["t"]:
            record(integrator.time, -1)  # the last good state
    except runctl.Interrupted as stop:
        # the state is the last accepted step: record it unless it was the last output
        if not result.history or integrator.time > result.history[-1]["t"]:
            record(integrator.time, -1)
        status = stop.stopped(f"t = {integrator.time:.6g} s", f"at t = {integrator.time:.6g} s")
        result.status, result.message = status["status"], status["message"]
        raise
    finally:
        integrator.solver.destroy()
        result.certificates = integrator.certificates()
        result.checks, unchecked = dynamic_checks(result.certificates)
        for note in unchecked:
            if note not in notes:
                notes.append(note)
        result.notes, result.strain_range = notes + watch.notes(), watch.summary()
        result.info["wall_time_s"] = time.perf_counter() - started
        if contact is not None and writing and root:  # the obstacles at the last state
            write_obstacle_surfaces(contact.placed(), out / "obstacles.vtu",
                                    *bounding_box(shapes, config.static.model.length))
        files.finish(dynamic_summary(result, config, result.info["wall_time_s"]))
    return result


def _run_finite_differences(config: DynamicConfig, out: Path | None, comm) -> DynamicResult:
    """The paper's FD + Runge-Kutta scheme (fe_beam.baselines.fd_rk) on the same config."""

    model = config.static.model
    if not LAW_KINDS[model.options.law].fd:
        laws = " and ".join(name for name, kind in LAW_KINDS.items() if kind.fd)
        raise ConfigError(f"[time] scheme = fd-* has the laws {laws} only (the non-standard "
                          f"and Reissner laws), not [model] law = \"{model.options.law}\"; use "
                          "scheme = \"generalized-alpha\"")
    if model.section.tapered or model.options.constraint != "none":
        raise ConfigError("[time] scheme = fd-*: only uniform sections without constraints")
    supports = {("clamped", "free"): "clamped-free", ("pinned", "roller"): "pinned-roller"}
    key = (model.supports.x0, model.supports.xL)
    if key not in supports or config.damping.kelvin_voigt or config.velocity is not None:
        raise ConfigError("[time] scheme = fd-*: supports clamped/free or pinned/roller, "
                          "viscous damping only, no initial velocity")
    loads = model.loads
    missing = unsupported(loads, "fd")  # fd_rk would drop them (fe_beam.model.loads)
    if loads.follower or "gravity" in missing:
        raise ConfigError("[time] scheme = fd-*: no follower loads or gravity")
    if missing:
        raise ConfigError(f"[time] scheme = fd-* takes no [loads] {missing[0]}; use scheme = "
                          "\"generalized-alpha\"")
    notes = check_beam_work(config.static, config.time.t_end / config.time.dt, comm,
                            " of time stepping (output times)", quiet=out is None)
    # in summary.json only: the fd-* schemes' summary reports rho_inf as it always did, and
    # their interrupted runs print one line
    notes += list(getattr(config, "notes", ()))
    stiffness = model.stiffness_at(0.0)
    props = model.section.properties(0.0)
    k = model.options.shear_correction if model.options.law == "reissner" else 1.0
    params = fd_rk.FDBeamParameters(
        L=model.length, n_intervals=model.mesh.elements * model.mesh.degree,
        EA=stiffness["EA"], GA=k * stiffness["GA"], EI=stiffness["EI"], EI3=stiffness["EI3"],
        EI4=stiffness["EI4"], rhoA=model.material.rho * props.A,
        rhoI=model.material.rho * props.I, c=config.damping.c, law=model.options.law,
        supports=supports[key], Px=loads.tip_force[0], Py=loads.tip_force[1],
        M=loads.tip_moment, qx=loads.distributed[0], qy=loads.distributed[1],
        load_time=_interruptible(config.load_function, comm))
    q0 = None
    if config.from_static:
        try:
            q0 = fd_rk.solve_static(params, 1.0, config.static.stepping.steps)
        except RuntimeError as error:  # no static equilibrium: the analysis failed
            return _fd_failed(config, out, comm, params, f"static pre-state: {error}")
        reason = _fd_strains(params, q0).inadmissible()
        if reason:
            return _fd_failed(config, out, comm, params, f"static pre-state: {reason}")
    times = np.arange(0.0, config.time.t_end + 0.5 * config.time.dt, config.time.dt)
    method = {"fd-rk45": "RK45", "fd-dop853": "DOP853"}[config.time.scheme]
    tolerance = min(config.time.tol, 1e-6)
    summary_file = exports.Exports([exports.SummaryExport(out / "summary.json")]
                                   if out is not None else [], comm)
    summary_file.start({"status": "running", "message": "", "scheme": config.time.scheme,
                        "notes": notes})
    try:
        solution = fd_rk.simulate(params, q0, None, config.time.t_end, times, method=method,
                                  rtol=tolerance, atol=tolerance * 1e-3 * model.length)
    except runctl.Interrupted as stop:
        stop.where = "the FD + Runge-Kutta integration"
        stop.written = ("no history (the scheme writes it at its end): only summary.json, status "
                        "interrupted, is")
        summary_file.finish({
            "status": "interrupted", "history": [], "scheme": config.time.scheme,
            "notes": notes, "message": f"interrupted by {stop.name} during the FD + "
            "Runge-Kutta integration (its history is written at its end)"})
        raise
    history = [{"t": float(t), "tip": {"u": float(u), "v": float(v), "theta": float(th)},
                "energies": {"kinetic": float(kin), "strain": float(strain),
                             "external_work": float(work), "dissipated": float(diss)}}
               for t, u, v, th, kin, strain, work, diss in zip(
                   solution.t, solution.tip_u, solution.tip_v, solution.tip_theta,
                   solution.kinetic, solution.strain, solution.external_work,
                   solution.dissipated, strict=True)]
    result = DynamicResult(history, {"rhs_evaluations": solution.nfev,
                                     "wall_time_s": solution.wall_time},
                           "completed" if solution.success else "failed", solution.message,
                           dofs=int(fd_rk.free_dofs(params).sum()))
    # the explicit scheme has no step to reject: the outputs up to the first inadmissible
    # state (1 + e <= 0 at a midpoint: turned inside out) are kept, and the run failed
    watch = StrainWatch()
    for index, q in enumerate(solution.q):
        strains = _fd_strains(params, q)
        reason = strains.inadmissible()
        if reason:
            last = history[index - 1]["t"] if index else 0.0
            result.history = history[:index]
            result.status = "failed"
            result.message = (f"{reason} at t = {history[index]['t']:.6g} s; last admissible "
                              f"time {last:.6g} s")
            break
        watch.observe(strains)
    result.notes, result.strain_range = notes + watch.notes(), watch.summary()
    runctl.warn(comm, watch.notes())
    _write_dynamic(out, result, config, solution.wall_time, comm, config.static.output.plots)
    return result


def _fd_strains(params, q) -> StrainRange:
    """`StrainRange` of a state of the finite-difference scheme (its midpoint strains)."""

    st = fd_rk.midpoint_strains(params, q)
    gamma = np.arctan2(st["g"], st["E1"])
    return StrainRange(float(np.min(st["E1"])), float(np.max(np.abs(st["eps"]))),
                       float(np.max(np.abs(gamma))))


def _fd_failed(config: DynamicConfig, out: Path | None, comm, params, message: str):

    result = DynamicResult([], {"wall_time_s": 0.0}, "failed", message,
                           dofs=int(fd_rk.free_dofs(params).sum()))
    _write_dynamic(out, result, config, 0.0, comm, plots=False)
    return result


def _interruptible(load_time, comm, every: int = 200):
    """``load_time`` that looks for SIGINT/SIGTERM (`fe_beam.runctl.check`, collective: every
    rank integrates the same system, so every rank calls it equally often) every ``every``
    calls: the FD scheme's right-hand side calls it once per evaluation."""
    calls = [0]

    def checked(t):
        calls[0] += 1
        if calls[0] % every == 0:
            runctl.check(comm)
        return load_time(t)

    return checked


ENERGIES = ("kinetic", "strain", "external_work", "dissipated")


def _writer(problem, path, contact=None, sections: bool = True):
    """The XDMF writer of a rod problem (the spatial rod's has the directors); with
    ``contact`` (a `fe_beam.fem.contact.ContactSet`) the contact fields; ``sections=False``:
    no strains and section forces (mode shapes)."""
    return (SpatialXDMFWriter if problem.spatial else BeamXDMFWriter)(
        problem, path, contact=contact if path is not None else None, sections=sections)


SPATIAL_MOMENTA = tuple(f"momentum_{k}" for k in "xyz") + tuple(
    f"angular_momentum_{k}" for k in "xyz")


def spatial_history_columns(tendons: int) -> list[exports.Column]:
    """history.csv of a spatial rod: t, the tip's u, v, w, rotation vector and frame R (rows
    R11 ... R33), the energies and their sum kinetic + strain, the linear and angular momenta
    (world axes, about the origin), then each tendon's tension and pull-in."""
    return [exports.Column("t", lambda h: h["t"]),
            *[exports.Column(f"tip_{k}", lambda h, k=k: h["tip"][k]) for k in ("u", "v", "w")],
            *[exports.Column(f"tip_rotation_{k}", lambda h, i=i: h["tip"]["rotation_vector"][i])
              for i, k in enumerate("xyz")],
            *[exports.Column(f"tip_R{i + 1}{j + 1}", lambda h, i=i, j=j: h["tip"]["R"][i][j])
              for i in range(3) for j in range(3)],
            *(exports.Column(k, lambda h, k=k: h["energies"][k]) for k in ENERGIES),
            exports.Column("total_energy", lambda h: h["energies"]["kinetic"]
                           + h["energies"]["strain"]),
            *(exports.Column(k, lambda h, k=k: h["momenta"][k]) for k in SPATIAL_MOMENTA),
            *exports.indexed_columns("tension", tendons, lambda h: h["tendons"]["tensions"]),
            *exports.indexed_columns("pull_in", tendons, lambda h: h["tendons"]["pull_ins"])]


def history_columns(tendons: int) -> list[exports.Column]:
    """history.csv: t, the tip, the energies, then tension_i and pull_in_i of each tendon."""
    return [exports.Column("t", lambda h: h["t"]), *exports.tip_columns(),
            *(exports.Column(k, lambda h, k=k: h["energies"][k]) for k in ENERGIES),
            *exports.indexed_columns("tension", tendons, lambda h: h["tendons"]["tensions"]),
            *exports.indexed_columns("pull_in", tendons, lambda h: h["tendons"]["pull_ins"])]


HISTORY_HEADER = [c.name for c in history_columns(0)]


def _history_exports(out: Path | None, config: DynamicConfig, writer=None, content=None,
                     draw=None) -> list:
    """The exports of a time history: XDMF states (``writer``), and with ``out`` history.csv,
    summary.json (``content()`` as the run goes) and the pictures (``draw``)."""
    files = [exports.XDMFExport(writer, "t")] if writer is not None else []
    if out is not None:
        spatial = getattr(config.static.model, "kinematics", "planar") == "spatial"
        columns = (spatial_history_columns if spatial else history_columns)(
            len(config.static.tendons))
        obstacles = len(config.static.obstacles)
        if obstacles:  # each obstacle's force, moment, penetration and peak pressure
            columns = columns + contact_columns(obstacles, spatial)
        # a chain of rods: each rod's end and each joint's force and moment
        columns = columns + structure_columns(config.static.model)
        files += [exports.CSVExport(out / "history.csv", columns),
                  exports.SummaryExport(out / "summary.json", content),
                  exports.PlotExport(draw) if draw is not None else None]
    return files


def dynamic_summary(result: DynamicResult, config: DynamicConfig, wall: float) -> dict:
    return {
        "status": result.status, "message": result.message, "history": result.history,
        "dofs": result.dofs, "wall_time_s": wall, "solver": result.info,
        # rho_inf parametrises generalized-alpha only: null for energy-conserving (new); the
        # fd-* schemes keep the number they always reported (public interface)
        "scheme": config.time.scheme,
        "rho_inf": None if config.time.scheme == "energy-conserving" else config.time.rho_inf,
        "notes": list(result.notes),
    } | ({"checks": [dict(c) for c in result.checks]} if result.checks else {}) | (
        {"certificates": result.certificates} if result.certificates else {}) | (
        {"strain_range": result.strain_range} if result.strain_range else {}) | (
        {"prestate": result.prestate} if result.prestate is not None else {})


def _write_dynamic(out: Path | None, result: DynamicResult, config: DynamicConfig, wall: float,
                   comm, plots: bool) -> None:
    """The files of a history computed in one go (the FD scheme): summary.json, history.csv
    and, with ``plots``, the pictures."""
    draw = (lambda _: _plot_dynamic(out, result, [], config)) if plots else None
    files = exports.Exports(_history_exports(out, config, draw=draw), comm)
    for record in result.history:
        files.on_step(record)
    files.finish(dynamic_summary(result, config, wall))


def _plot_dynamic(out: Path, result: DynamicResult, shapes, config: DynamicConfig,
                  contact=None) -> None:
    t = np.array([h["t"] for h in result.history])
    length = config.static.model.length
    structure = getattr(config.static.model, "structure", None)
    # the tip's reference position: (L, 0) of a rod, the last end of a chain of rods
    tip_x, tip_y = ((length, 0.0) if structure is None
                    else structure.reference_point(length, structure.chain[-1])[:2])
    with exports.figure(out / "dynamics.png", 1, 2, figsize=(10, 4)) as (_, (left, right)):
        left.plot(tip_x + np.array([h["tip"]["u"] for h in result.history]),
                  tip_y + np.array([h["tip"]["v"] for h in result.history]), lw=1.2)
        left.set_xlabel("tip x [m]")
        left.set_ylabel("tip y [m]")
        left.set_title("tip trajectory")
        if contact is not None and not contact.spatial:  # where the last state has them
            last = [shapes[-1]] if shapes else []
            if last:
                left.plot(last[0][1]["x"] + last[0][1]["u"], last[0][1]["v"], lw=1.5,
                          color="k", label=f"t = {last[0][0]:.4g} s")
            draw_obstacles(left, contact.placed(), last, length)
            left.set_title("tip trajectory, last shape and obstacles")
        left.set_aspect("equal", adjustable="datalim")
        for key in ENERGIES:
            right.plot(t, [h["energies"][key] for h in result.history], label=key)
        right.set_xlabel("t [s]")
        right.set_ylabel("energy [J]")
        right.set_title("energies")
        right.legend(fontsize=8)
        for axis in (left, right):
            axis.grid(alpha=0.3)
    if contact is not None and contact.spatial and shapes:  # the last state in 3D, obstacles
        t_last, last = shapes[-1]
        plot_spatial_shapes([(f"t = {t_last:.4g} s", last)], out / "deformed_shapes.png",
                            "last state and the obstacles", length,
                            obstacles=contact.placed())
    if shapes and config.static.output.gif:
        _write_gif(out / "beam.gif", shapes, length)


def _write_gif(path: Path, shapes, length: float) -> None:
    """Animated deformed shapes (skipped when Pillow is not installed)."""
    try:
        from matplotlib.animation import FuncAnimation, PillowWriter
    except ImportError:
        return
    plt = _pyplot()
    frames = shapes[:: max(1, len(shapes) // 60)]
    xs = np.concatenate([s["x"] + s["u"] for _, s in frames])
    ys = np.concatenate([s["v"] for _, s in frames])
    drawn, axis = plt.subplots(figsize=(5, 4))
    (line,) = axis.plot([], [], lw=2)
    margin = 0.05 * length
    axis.set_xlim(xs.min() - margin, xs.max() + margin)
    axis.set_ylim(ys.min() - margin, ys.max() + margin)
    axis.set_aspect("equal")
    axis.grid(alpha=0.3)

    def draw(index):
        t, shape = frames[index]
        line.set_data(shape["x"] + shape["u"], shape["v"])
        axis.set_title(f"t = {t:.4g} s")
        return (line,)

    try:
        FuncAnimation(drawn, draw, frames=len(frames), blit=False).save(
            str(path), writer=PillowWriter(fps=15))
    except Exception:  # an animation must never fail an analysis
        pass
    plt.close(drawn)


def run_modes(static: StaticConfig, modes: dict, out: Path | None, comm=MPI.COMM_WORLD,
              progress: bool = True) -> dict:

    started = time.perf_counter()
    check_beam_work(static, static.stepping.steps if modes["prestress"] else None, comm,
                    quiet=out is None)
    problem, tendons = _tendon_problem(static, comm)
    if out is not None and comm.rank == 0:
        atomic_write_json(out / "summary.json", {"status": "running", "message": ""})
    watch = StrainWatch()
    if modes["prestress"]:
        try:
            _static_prestate(problem, static, progress, watch, tendons)
        except PrestateFailed as failure:
            # no equilibrium (or only inadmissible ones) beyond the last converged factor:
            # the analysis failed (exit 3), no modes of a state that is not an equilibrium
            summary = {"status": "failed", "message": str(failure),
                       "prestate": _prestate_record(problem, failure), "frequencies_hz": [],
                       "transverse_fraction": [], "prestress": True,
                       "dofs": problem.global_dofs, "notes": watch.notes(),
                       "strain_range": watch.summary(),
                       "wall_time_s": time.perf_counter() - started}
            runctl.warn(comm, watch.notes())
            if out is not None and comm.rank == 0:
                atomic_write_json(out / "summary.json", summary)
            return summary
        except runctl.Interrupted as stop:
            status = stop.stopped("the static pre-state", "in the static pre-state")
            if out is not None and comm.rank == 0:
                atomic_write_json(out / "summary.json", status)
            raise
    else:
        problem.set_load_factor(0.0)
        try:
            _relax_curved(problem, static, tendons)
        except PrestateFailed as failure:
            summary = {"status": "failed", "message": str(failure), "frequencies_hz": [],
                       "transverse_fraction": [], "prestress": False,
                       "dofs": problem.global_dofs, "notes": [],
                       "wall_time_s": time.perf_counter() - started}
            if out is not None and comm.rank == 0:
                atomic_write_json(out / "summary.json", summary)
            return summary
    prestate_check = None
    if modes["prestress"]:  # the pre-state's equilibrium, before the modes take the state
        prestate_check = equilibrium_entry(
            problem, static.solver.rtol, label="of the static pre-state",
            tensions=tendons.tension_values() if tendons else ())
    result = natural_frequencies(problem, modes["count"])
    summary = {"status": "completed", "frequencies_hz": result.frequencies_hz,
               "transverse_fraction": result.transverse_fraction,
               "prestress": modes["prestress"], "dofs": problem.space.dofmap.index_map.size_global
               * problem.space.dofmap.index_map_bs,
               "wall_time_s": time.perf_counter() - started}
    summary.update(_modes_summary(result))
    summary["checks"] = ([prestate_check] if prestate_check else []) + mode_checks(result)
    if modes["prestress"]:
        # strains of the pre-state outside the range the model is meant for: warnings
        summary["strain_range"] = watch.summary()
        runctl.warn(comm, watch.notes())
        summary["notes"] = watch.notes() + summary["notes"]
    if not static.output.xdmf:
        for mode in summary["unstable_modes"]:
            mode["shape"] = None  # [output] xdmf = false: no shapes written
    if out is not None:
        if comm.rank == 0:
            out.mkdir(parents=True, exist_ok=True)
        comm.barrier()
        state = compat.local_array(problem.w).copy()
        for name, shapes in (("modes.xdmf", result.shapes),
                             ("unstable_modes.xdmf", [m.shape for m in result.unstable])):
            if name == "unstable_modes.xdmf" and not shapes:
                continue
            writer = _writer(problem, out / name if static.output.xdmf else None,
                             sections=False)  # normalised shapes: no strains or forces
            family = _family_field(problem, writer) if name == "modes.xdmf" else None
            for index, shape in enumerate(shapes, start=1):
                compat.local_array(problem.w)[:] = compat.local_array(shape)
                if family is not None:  # the mode's family, as a code (summary mode_families)
                    family.x.array[:] = MODE_FAMILY_CODES.get(result.kinds[index - 1], -1)
                writer.write(float(index))
            writer.close()
        compat.local_array(problem.w)[:] = state
        if comm.rank == 0:
            atomic_write_json(out / "summary.json", summary)
            _write_modes_csv(out / "modes.csv", summary)
    return summary


#: the eigenpair residual a reported mode must reach (SLEPc converges to 1e-12)
EIGENPAIR_TOLERANCE = 1e-8
#: the largest normalised x_i^T M x_j (i != j) of the reported modes
ORTHOGONALITY_TOLERANCE = 1e-6


def mode_checks(result) -> list[dict]:
    """The run-time certificates of the reported modes (`fe_beam.solvers.modes.Modes`): the
    largest eigenpair residual and, for a symmetric pencil, their M-orthogonality."""
    checks = []
    if result.residuals:
        worst = max(result.residuals)
        index = result.residuals.index(worst) + 1
        checks.append(certify.entry(
            "eigenpair_residual", worst, EIGENPAIR_TOLERANCE,
            detail=f"max over the {len(result.residuals)} reported modes of ||K x - w^2 M x|| "
                   f"/ (||K x|| + w^2 ||M x||) (mode {index})",
            remedy="the eigensolver did not converge: ask for fewer modes ([modes] count) or "
                   "refine less; please report it"))
    if result.orthogonality is not None and len(result.shapes) > 1:
        checks.append(certify.entry(
            "mode_orthogonality", result.orthogonality, ORTHOGONALITY_TOLERANCE,
            detail="max |x_i^T M x_j| / sqrt(x_i^T M x_i x_j^T M x_j), i != j, of the reported "
                   "modes",
            remedy="repeated or clustered frequencies the eigensolver did not separate: ask "
                   "for fewer modes; please report it"))
    return checks


#: the code of each mode's family in modes.xdmf's "family" field
MODE_FAMILY_CODES = {"rigid": 0, "axial": 1, "bending": 2, "torsion": 3, "bending about y": 4,
                     "bending about z": 5}


def _family_field(problem, writer):
    """A constant field "family" added to the spatial rod's mode series (None for planar
    rods, whose kinds are named in summary.json and modes.csv)."""
    if not problem.spatial:
        return None
    from dolfinx import fem

    space = compat.function_space(problem.mesh, compat.element(problem.mesh, "DG", 0))
    function = fem.Function(space, name="family")
    writer.functions["family"] = function
    return function


def _write_modes_csv(path: Path, summary: dict) -> None:
    """modes.csv: one row per mode, its frequency, kind and the shares by family."""
    shares = summary.get("mode_shares") or [{} for _ in summary["frequencies_hz"]]
    keys = sorted({k for share in shares for k in share})
    lines = [",".join(["mode", "frequency_hz", "kind", *[k.replace(" ", "_") + "_share"
                                                        for k in keys]])]
    for index, (frequency, kind, share) in enumerate(zip(
            summary["frequencies_hz"], summary["mode_kinds"], shares, strict=True), start=1):
        lines.append(",".join([str(index), repr(float(frequency)), kind,
                               *[repr(float(share.get(k, 0.0))) for k in keys]]))
    atomic_write_text(path, "\n".join(lines) + "\n")


def _modes_summary(result) -> dict:
    """The summary keys beyond frequencies_hz: eigenvalues omega^2 [rad^2/s^2] and kind
    ("rigid" | "bending" | "axial") of each listed mode, the number of rigid-body modes, every
    unstable direction (omega^2 < 0: eigenvalue, growth_rate = sqrt(-omega^2) [1/s], shape at
    time index k of unstable_modes.xdmf), stable, and notes (also warnings on stderr)."""
    unstable = [{"eigenvalue": mode.eigenvalue, "growth_rate": mode.growth_rate,
                 "eigenvalue_imag": mode.eigenvalue_imag, "kind": mode.kind,
                 "transverse_fraction": mode.transverse_fraction,
                 "shape": {"file": "unstable_modes.xdmf", "index": index}}
                for index, mode in enumerate(result.unstable, start=1)]
    notes = list(result.notes)
    if result.unstable_count:
        rates = ", ".join(f"{mode.growth_rate:.4g}" for mode in result.unstable[:5])
        flutter = sum(1 for mode in result.unstable if mode.eigenvalue_imag)
        kinds = (f"omega^2 < 0 or complex ({flutter} flutter)" if flutter
                 else "omega^2 < 0")
        notes.insert(0, f"the state is unstable: {result.unstable_count} direction(s) with "
                        f"{kinds} (growth rates {rates} 1/s); see unstable_modes")
    if len(result.unstable) < result.unstable_count:
        notes.append(f"only the first {len(result.unstable)} of {result.unstable_count} unstable "
                     "directions are listed and written")
    if result.rigid_body_modes:
        notes.append(f"{result.rigid_body_modes} rigid-body mode(s) (0 Hz): the supports leave "
                     "the beam free to move as a rigid body")
    return {"eigenvalues": result.eigenvalues, "mode_kinds": result.kinds,
            "mode_shares": result.shares,
            "mode_family_codes": MODE_FAMILY_CODES,
            "rigid_body_modes": result.rigid_body_modes, "unstable_modes": unstable,
            "unstable_count": result.unstable_count, "stable": result.unstable_count == 0,
            "notes": notes}
_dynamic_summary = dynamic_summary  # the name tests and scripts used

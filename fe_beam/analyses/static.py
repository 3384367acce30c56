"""Static analysis driver: problem + solver + load stepping + recorders, for the CLI and demos."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam import certify, exports, runctl
from fe_beam.analyses.certificates import equilibrium_entry, stability_entry
from fe_beam.analyses.result import Report, Result, closing_of_steps
from fe_beam.exports.obstacles import bounding_box, write_obstacle_surfaces
from fe_beam.exports.outputs import BeamXDMFWriter, plot_deformed_shapes, plot_load_displacement
from fe_beam.exports.spatial import (
    SpatialXDMFWriter,
    plot_spatial_load_displacement,
    plot_spatial_shapes,
)
from fe_beam.fem.equilibrium import roundoff_force
from fe_beam.fem.rod import BeamProblem
from fe_beam.fem.section_laws import SOLID_NAMES
from fe_beam.model.obstacles import ContactSettings
from fe_beam.model.studies import StaticConfig
from fe_beam.solvers import realtime
from fe_beam.solvers.modes import nonsymmetric_reason
from fe_beam.solvers.newton import (
    LoadSteppingFailed,
    StepResult,
)
from fe_beam.solvers.rod_static import (  # noqa: F401  (the engine's home; re-exported)
    STABILITY_MAX_DOFS,
    STABILITY_ZERO,
    StaticContinuation,
    beam_dofs_estimate,
    check_beam_work,
)

__all__ = ["StaticContinuation", "StaticResult", "contact_checks", "contact_columns",
           "contact_line", "run",
           "solve_static", "structure_columns", "structure_record"]


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
    #: what the driver adds to the summary (the model, set-up notes, the finger's tendons ...)
    extra: dict = field(default_factory=dict)
    #: the obstacles at their place in the last state (moving obstacles: translated)
    obstacles: tuple = ()
    #: run-time certificates (`fe_beam.certify.entry`), summary.json's ``checks`` (after any
    #: the driver adds in ``extra``)
    checks: list[dict] = field(default_factory=list)

    def summary(self, extra: dict | None = None) -> dict:
        """summary.json's content; ``extra["notes"]`` (set-up notes) come before the run's;
        without ``extra``, the driver's own (``self.extra``)."""
        extra = dict(self.extra if extra is None else extra)
        notes = list(extra.pop("notes", []))
        checks = list(self.checks) + list(extra.pop("checks", []))
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
        if checks:
            data["checks"] = checks
        return data | (extra or {})


def contact_line(entry: dict) -> str:
    """One obstacle's contact state as a report line."""
    force = ", ".join(f"{c:.6g}" for c in entry["force"])
    where = ", ".join(f"{a:.4g}..{b:.4g}" for a, b in entry["active"]) or "none"
    friction = ""
    if "friction_force" in entry:
        slip = ", ".join(f"{a:.4g}..{b:.4g}" for a, b in entry["slip"]) or "none"
        friction = (f", friction ({', '.join(f'{c:.6g}' for c in entry['friction_force'])}) N, "
                    f"slipping at x = {slip} m")
    return (f"obstacle '{entry['name']}': force on the rod ({force}) N, contact at "
            f"x = {where} m{friction}, max penetration {entry['max_penetration']:.3g} m")


def _step_record(problem: BeamProblem, step: StepResult) -> dict:
    record = {
        "load_factor": step.load_factor,
        "tip": problem.end_values("xL"),
        "newton_iterations": step.iterations,
    }
    if problem.model.loads.end_motion():  # displacement control: the force it takes
        record["reaction_xL"] = problem.end_reaction("xL")
    return record | structure_record(problem)


def structure_record(problem) -> dict:
    """A chain of rods' per-step outputs: ``rods`` = {name: {tip: [x, y], tip_angle}} (each
    rod's own end, world axes) and ``joints`` = {name: {force: [Fx, Fy], moment}} (on the
    first end the joint names, world axes); {} for a single rod."""
    chain = getattr(problem, "chain", None)
    if chain is None:
        return {}
    record = {"rods": chain.rods(), "joints": chain.joints()}
    if chain.structure.body_ties:  # free bodies
        record["bodies"] = chain.bodies()
    return record


#: the written moment field against the support's reaction moment (relative): an identity of
#: the discrete equilibrium, round-off (measured 1e-15) when both are right
MOMENT_FIELD_TOLERANCE = 1e-9


def moment_field_checks(problem: BeamProblem, writer, run) -> list[dict]:
    """Certificates ``moment_field_x0`` / ``moment_field_xL`` of a rod's written section
    fields: at each end whose rotation is held (spatial: all three components), the end moment
    the fields imply (planar: M, T, eps, `fe_beam.exports.outputs.BeamXDMFWriter.end_moment`;
    spatial: n1..n3, m1..m3, `fe_beam.exports.spatial.SpatialXDMFWriter.end_moment`, from the
    output expressions at the energy's Gauss points) against the support's reaction moment
    (the residual assembled at the end's rotation dofs, the number the global equilibrium is
    made of), relative to the larger of the two and of the reaction forces times L. None
    where another load acts on the end element's rotations (tendons, contact, a tip moment
    or follower force at a held tip; spatial: a point moment at the end) or nothing is
    recorded."""
    if (writer is None or problem.extra_energy is not None
            or problem.extra_work is not None or getattr(run, "contact", None) is not None):
        return []
    writer.update()
    loads, checks = problem.model.loads, []
    spatial = problem.spatial
    roundoff = roundoff_force(problem)  # collective
    rotations = ("theta_x", "theta_y", "theta_z") if spatial else ("theta",)
    for end in ("x0", "xL"):
        fixed = problem.model.supports.fixed(end)
        tip_moment = any(loads.tip_moment) if spatial else bool(loads.tip_moment)
        if not all(name in fixed for name in rotations) or (
                end == "xL" and (tip_moment or loads.follower)):
            continue
        at_end = [m for m in loads.point_moments
                  if abs(m[0] - problem.end_x[end]) <= problem.point_tolerance]
        if spatial and any(any(m[1:]) for m in at_end):
            continue  # a dead moment's work at a turned end: not the reaction's
        implied = writer.end_moment(problem.end_x[end], problem.point_tolerance)
        if implied is None:
            continue
        reaction = problem.end_reaction(end)
        if spatial:
            implied = np.asarray(implied, dtype=float)
            held = np.array([reaction[k] for k in ("M_theta_x", "M_theta_y", "M_theta_z")])
            forces = sum(abs(reaction[k]) for k in ("Fx", "Fy", "Fz"))
            difference = float(np.linalg.norm(implied - held))
            scale = max(float(np.linalg.norm(held)), float(np.linalg.norm(implied)),
                        forces * problem.model.length)
            what = "n, m"
        else:
            # a point moment on the held end acts on its rotation dof beside the support: the
            # end moment of the fields is the reaction's and that moment's sum
            applied = float(problem.load_factor.value) * sum(m for _, m in at_end)
            held = reaction["M"] + applied
            difference = abs(implied - held)
            scale = max(abs(held), abs(implied), abs(reaction["M"]),
                        (abs(reaction["Fx"]) + abs(reaction["Fy"])) * problem.model.length)
            what = "M, T"
        # the section forces' round-off (eps EA, `roundoff_force`) over the end element: the
        # floor of the identity on a very slender rod (h/L = 1e-5: 3e-9 of P L)
        allowance = roundoff * problem.model.length / problem.model.mesh.elements
        value = max(difference - allowance, 0.0) / scale if scale > 0 else 0.0
        checks.append(certify.entry(
            f"moment_field_{end}", value, MOMENT_FIELD_TOLERANCE,
            detail=f"|end moment of the written {what} - support reaction moment at {end}| / "
                   f"scale (raw {difference / scale if scale > 0 else 0.0:.3g}, less the "
                   "section forces' round-off 10 eps EA times the element length)",
            remedy="the fields written for ParaView disagree with the solved equilibrium: "
                   "report it (a compiler or version fault), the tip values are not affected"))
    return checks


def solve_static(
    config: StaticConfig,
    out: Path | None = None,
    comm=MPI.COMM_WORLD,
    progress: bool = True,
    extra_summary: dict | None = None,
    on_step=None,
    record_shapes: bool = True,
    stability: bool | None = None,
    extra_exports: list | None = None,
    certify_equilibrium: bool = True,
) -> StaticResult:
    """Run the static load stepping of a configuration; writes results under ``out`` if given.

    Tendons of ``config.tendons`` add their potential; steps then also record ``tensions`` and
    ``pull_ins``. ``on_step(problem, record)`` is called after each converged step (on all ranks),
    e.g. to sample profiles along the beam. ``record_shapes=False`` skips the per-step deformed
    shapes and profiles (``result.shapes``) and the stability check of the final state
    (``steps[-1]["stability"]``, `StaticContinuation.stability`; ``stability`` True/False
    decides that alone) when nothing is written: a
    solve-only run (benchmarks, sweeps) then costs the Newton iterations alone.

    summary.json (status "running" meanwhile), load_displacement.csv and the XDMF file are
    updated as steps converge, at O(1) cost per step (rows and steps are appended; summary.json
    is rewritten at a bounded share of the wall time). On failure the last converged state is
    written and the result has status "failed"; on SIGINT/SIGTERM (`fe_beam.runctl.Interrupted`)
    it is written with status "interrupted" and the exception is re-raised. ``extra_exports``: more
    `fe_beam.exports.Export` objects fed with the step records (e.g. the finger's sweep table).
    ``certify_equilibrium``: a converged run's summary gets the ``checks`` "global_equilibrium"
    (`fe_beam.analyses.certificates`) and, where the stability was checked, "stability".

    The problem and solver come from `fe_beam.solvers.realtime.acquire`: a second solve of the same
    kind of model (same mesh, law, section shape, supports, ...) reuses the built ones.
    """
    started = time.perf_counter()
    notes = check_beam_work(config, config.stepping.steps, comm, quiet=out is None)

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
    result.extra = extra
    xdmf_path = out / "beam.xdmf" if writing and config.output.xdmf else None
    writer_kind = SpatialXDMFWriter if problem.spatial else BeamXDMFWriter
    writer = (writer_kind(problem, xdmf_path, contact=run.contact if xdmf_path else None)
              if (record_shapes or xdmf_path) else None)
    states = [exports.XDMFExport(writer, "load_factor")] if writer is not None else []
    files = exports.Exports(states + ([
        exports.CSVExport(out / "load_displacement.csv",
                          (SPATIAL_CSV_COLUMNS if problem.spatial else CSV_COLUMNS)
                          + contact_columns(len(config.obstacles), problem.spatial)
                          + structure_columns(config.model)),
        exports.SummaryExport(out / "summary.json", lambda: result.summary(extra)),
        exports.PlotExport(lambda _: _write_plots(out, result, config)
                           if config.output.plots and result.shapes else None),
    ] + list(extra_exports or []) if writing else []), comm)
    files.start(result.summary(extra))  # status "running" from the start

    def record(step: StepResult) -> None:
        entry = _step_record(problem, step)
        if run.contact is not None:
            entry["contact"] = run.contact.summary()
            entry["contact_updates"] = run.solver.updates
        if tendons:
            entry |= {
                "tensions": tendons.tension_values().tolist(),
                "pull_ins": tendons.pull_ins().tolist(),
            }
        result.steps.append(entry)
        result.notes, result.strain_range = run.watch.notes() + run.notes, run.watch.summary()
        if on_step is not None:
            on_step(problem, entry)
        result.wall_time_s = time.perf_counter() - started
        files.on_step(entry)
        if writer is not None and record_shapes:
            shape = writer.vertex_values(update=False)
            if problem.chain is not None:  # the plots draw the chain in the plane
                shape = problem.chain.shape(shape)
            if root:
                result.shapes.append((f"load factor {step.load_factor:.3g}", shape))

    try:
        run.advance(1.0, config.stepping, on_converged=record, progress=progress)
        result.status = "converged"
        result.checks += moment_field_checks(problem, writer, run)
        checked = run.stability() if (record_shapes if stability is None else stability) \
            else None
        if checked is not None:
            result.steps[-1]["stability"] = checked
        elif stability:  # asked for (fe-beam static) but the tangent is not an energy's
            note = unchecked_stability_note(run)
            if note not in run.notes:
                run.notes.append(note)
        if run.contact is not None and result.steps:
            result.checks.extend(contact_checks(
                result.steps[-1].get("contact", []),
                max(run.contact.tolerance, ContactSettings().tolerance(config.model.section))))
        if certify_equilibrium and result.steps:
            checks = result.checks
            checks.append(equilibrium_entry(problem, config.solver.rtol,
                                            result.steps[-1].get("contact"),
                                            tensions=result.steps[-1].get("tensions", ()),
                                            contact_tolerance=config.contact.force_tolerance
                                            if config.obstacles else 0.0))
            stable = stability_entry(checked)
            if stable is not None:
                checks.append(stable)
    except LoadSteppingFailed as failure:
        result.status, result.message = "failed", str(failure)
    except runctl.Interrupted as stop:
        last = result.steps[-1]["load_factor"] if result.steps else 0.0
        status = stop.stopped(f"load factor {last:.4g}", f"at load factor {last:.6g}")
        result.status, result.message = status["status"], status["message"]
        raise
    finally:
        if run.contact is not None:  # the moving obstacles where the last state has them
            result.obstacles = tuple(run.contact.placed())
        realtime.release(run)
        result.notes = run.watch.notes() + run.notes + compressed_tendon_notes(tendons,
                                                                             result.steps)
        result.strain_range = run.watch.summary()
        result.wall_time_s = time.perf_counter() - started
        if writing and root and config.obstacles:
            write_obstacle_surfaces(result.obstacles or config.obstacles, out / "obstacles.vtu",
                                    *bounding_box(result.shapes, config.model.length))
        files.finish(result.summary(extra))  # pictures unless interrupted
    return result


def unchecked_stability_note(run) -> str:
    """Why the final state's stability (`StaticContinuation.stability`) is not checked: the
    tangent is not that of an energy, so its inertia counts nothing."""
    pull_in = run.tendons is not None and any(
        t.controlled_by_pull_in for t in run.tendons.tendons)
    reason = ("pull-in controlled tendons" if pull_in
              else nonsymmetric_reason(run.problem))
    return (f"the stability of the final state is not checked ({reason}); the tangent is not "
            "that of an energy, so its inertia counts nothing: fe-beam modes with [modes] "
            "prestress = true finds unstable directions")


#: the largest relative difference between an obstacle's reported normal force and the one
#: recomputed from the contact pressures and the obstacle's normals (`contact_checks`)
FORCE_BALANCE_TOLERANCE = 1e-6


def contact_checks(entries: list[dict], tolerance: float) -> list[dict]:
    """The contact certificates of the last accepted state (`fe_beam.certify`), over all
    obstacles: ``surface_penetration``, the largest penetration over the rod's whole surface
    (between the contact points, at the vertices, on the end faces; the section's true shape:
    `fe_beam.fem.contact.ContactSet.surface`) against ``tolerance`` (the caller's: the
    penetration tolerance, at least the default 1e-3 of the thinnest section: the solver holds
    a tighter one at the contact points only, between them a P2 centreline on a curved
    obstacle may dip deeper), and
    ``contact_force_balance``, the reported normal force against the pressures times the
    obstacle's normals (relative)."""
    if not entries:
        return []
    depth = max(float(e["max_penetration"]) for e in entries)
    balance = max(float(e.get("force_balance", 0.0)) for e in entries)
    return [
        certify.entry("surface_penetration", depth, tolerance * (1 + 1e-9),
                      detail="largest penetration [m] over the rod's whole surface (between "
                             "the contact points, at the vertices and on the end faces) "
                             "against [contact] penetration_tolerance (at least 1e-3 of the "
                             "thinnest section)",
                      remedy="refine [mesh] elements or raise [contact] quadrature_degree"),
        certify.entry("contact_force_balance", balance, FORCE_BALANCE_TOLERANCE,
                      detail="relative difference of each obstacle's reported normal force "
                             "from its pressures times the obstacle's normals",
                      remedy="lower [contact] force_tolerance"),
    ]


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


def hyperelastic_summary(options) -> dict:
    """The hyperelastic law's material, constants, small-strain moduli and section points."""

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
    if getattr(m, "kinematics", "planar") == "spatial":
        law["kinematics"] = "spatial"
        law["initial_curvature"] = [p.constant if p.is_constant else p.text
                                    for p in m.initial_curvature]
    structure = getattr(m, "structure", None)
    if structure is not None:  # a chain of rods: its rods and joints as given
        law["structure"] = {
            "rods": [{"name": r.name, "start": list(r.start), "direction": list(r.direction),
                      "length": r.length, "elements": r.elements}
                     | ({"normal": list(r.frame[1])} if r.dim == 3 else {})
                     for r in structure.rods],
            "joints": [{"name": j.name, "kind": j.kind, "at": list(j.at)}
                       for j in structure.joints],
            "chain": [structure.rods[seg.rod].name for seg in structure.chain]}
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
    } | law | ({"obstacles": [_obstacle_summary(o) for o in config.obstacles],
                "contact_settings": {
                    "penetration_tolerance": config.contact.tolerance(m.section),
                    "penalty": config.contact.penalty,
                    "max_updates": config.contact.max_updates,
                    "quadrature_degree": config.contact.quadrature_degree or 4 * m.mesh.degree,
                }} if config.obstacles else {})


def _obstacle_summary(obstacle) -> dict:
    import dataclasses

    return {k: (list(v) if isinstance(v, tuple) else v)
            for k, v in dataclasses.asdict(obstacle).items() if v is not None and k != "dim"}


# load_displacement.csv
CSV_COLUMNS = [exports.Column("load_factor", lambda s: s["load_factor"]), *exports.tip_columns(),
               exports.Column("newton_iterations", lambda s: s["newton_iterations"])]
CSV_HEADER = [c.name for c in CSV_COLUMNS]
#: load_displacement.csv of a spatial rod: the tip displacement and rotation vector
SPATIAL_CSV_COLUMNS = [
    exports.Column("load_factor", lambda s: s["load_factor"]),
    *[exports.Column(f"tip_{k}", lambda s, k=k: s["tip"][k]) for k in ("u", "v", "w")],
    *[exports.Column(f"tip_rotation_{k}", lambda s, i=i: s["tip"]["rotation_vector"][i])
      for i, k in enumerate("xyz")],
    exports.Column("newton_iterations", lambda s: s["newton_iterations"])]


def structure_columns(model, joints: bool = True) -> list:
    """A chain of rods' CSV columns: ``rod_<name>_x``, ``_y``, ``_angle`` (each rod's end,
    world axes) and (``joints``) ``joint_<name>_Fx``, ``_Fy``, ``_M`` ([] for a single rod);
    spatial: ``rod_<name>_x``, ``_y``, ``_z`` and ``joint_<name>_Fx``, ``_Fy``, ``_Fz``,
    ``_Mx``, ``_My``, ``_Mz``."""
    structure = getattr(model, "structure", None)
    if structure is None:
        return []
    columns = []
    if structure.dim == 3:  # spatial: each rod's end, each joint's force and moment
        for rod in structure.rods:
            columns += [exports.Column(f"rod_{rod.name}_{k}", lambda r, n=rod.name, i=i:
                                       r["rods"][n]["tip"][i]) for i, k in enumerate("xyz")]
        names = _joint_names(structure)
        for name in names if joints else ():
            columns += [exports.Column(f"joint_{name}_F{k}", lambda r, n=name, i=i:
                                       r["joints"][n]["force"][i]) for i, k in enumerate("xyz")]
            columns += [exports.Column(f"joint_{name}_M{k}", lambda r, n=name, i=i:
                                       r["joints"][n]["moment"][i]) for i, k in enumerate("xyz")]
        return columns
    for rod in structure.rods:
        columns += [
            exports.Column(f"rod_{rod.name}_x", lambda r, n=rod.name: r["rods"][n]["tip"][0]),
            exports.Column(f"rod_{rod.name}_y", lambda r, n=rod.name: r["rods"][n]["tip"][1]),
            exports.Column(f"rod_{rod.name}_angle",
                           lambda r, n=rod.name: r["rods"][n]["tip_angle"])]
    names = _joint_names(structure)
    for name in names if joints else ():
        columns += [
            exports.Column(f"joint_{name}_Fx", lambda r, n=name: r["joints"][n]["force"][0]),
            exports.Column(f"joint_{name}_Fy", lambda r, n=name: r["joints"][n]["force"][1]),
            exports.Column(f"joint_{name}_M", lambda r, n=name: r["joints"][n]["moment"])]
    return columns


def _joint_names(structure) -> list[str]:
    """The joints with outputs: shared vertices, fixed bodies at the mesh's ends, ties and
    fixed bodies inside the mesh."""
    return ([j.name for j in structure.joints_on_chain] + [j[0] for j in structure.body_joints]
            + [t.name for t in structure.ties]
            + [j[0] for j in structure.inner_body_joints]
            + [j[0] for j in structure.free_body_joints])


def contact_columns(count: int, spatial: bool = False) -> list:
    """load_displacement.csv's columns of obstacle i (in the order of [[obstacles]]): the
    force the obstacle exerts on the rod, its moment about the origin (spatial rods: Fz and
    the moment's three components), the largest penetration and line pressure."""
    columns = []
    axes = ("x", "y", "z") if spatial else ("x", "y")
    for i in range(count):
        def part(record, i=i):
            return record["contact"][i]
        columns += [exports.Column(f"contact{i}_F{a}", lambda r, p=part, k=k: p(r)["force"][k])
                    for k, a in enumerate(axes)]
        columns += ([exports.Column(f"contact{i}_M{a}", lambda r, p=part, k=k:
                                    p(r)["moment"][k]) for k, a in enumerate(axes)]
                    if spatial else
                    [exports.Column(f"contact{i}_moment", lambda r, p=part: p(r)["moment"])])
        columns += [
            exports.Column(f"contact{i}_max_penetration", lambda r, p=part:
                           p(r)["max_penetration"]),
            exports.Column(f"contact{i}_pressure_peak", lambda r, p=part: p(r)["pressure_peak"]),
        ]
    return columns


def _write_plots(out: Path, result: StaticResult, config: StaticConfig) -> None:
    every = max(1, len(result.shapes) // 10)
    shapes = result.shapes[every - 1 :: every]
    if result.shapes[-1] is not shapes[-1]:
        shapes.append(result.shapes[-1])
    m = config.model
    title = f"{m.options.law} law, constraint {m.options.constraint}"
    if getattr(m, "kinematics", "planar") == "spatial":
        structure = getattr(m, "structure", None)
        undeformed = None if structure is None else structure.reference_polyline()
        plot_spatial_shapes(shapes, out / "deformed_shapes.png", title, m.length,
                            obstacles=result.obstacles or config.obstacles,
                            undeformed=undeformed)
        factors = [s["load_factor"] for s in result.steps]
        tips = {k: [s["tip"][k] for s in result.steps] for k in ("u", "v", "w",
                                                                  "rotation_vector")}
        plot_spatial_load_displacement(factors, tips, out / "load_displacement.png", title)
        return
    structure = getattr(m, "structure", None)
    if structure is not None:  # a chain: its reference polygon, the axes only
        undeformed = structure.reference_polyline()
        plot_deformed_shapes(shapes, out / "deformed_shapes.png", title, m.length,
                             undeformed=undeformed)
    else:
        plot_deformed_shapes(shapes, out / "deformed_shapes.png", title, m.length,
                             obstacles=result.obstacles or config.obstacles, section=m.section)
    factors = [s["load_factor"] for s in result.steps]
    tips = {f"tip {k}": [s["tip"][k] for s in result.steps] for k in ("u", "v", "theta")}
    plot_load_displacement(factors, tips, out / "load_displacement.png", title)


def run(validated, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True,
        echo=None) -> Result:
    """``fe-beam static`` (the driver contract, `fe_beam.analyses.result`)."""
    result = solve_static(validated.parsed, out, comm, progress=progress, stability=True)
    report = Report(echo)
    for step in result.steps[-1:]:
        tip = step["tip"]
        if "w" in tip:
            rotation = ", ".join(f"{c:.6g}" for c in tip["rotation_vector"])
            report.out(f"load factor {step['load_factor']:.4g}: tip u = {tip['u']:.6g} m, "
                       f"v = {tip['v']:.6g} m, w = {tip['w']:.6g} m, rotation vector "
                       f"[{rotation}] rad")
            for entry in step.get("contact", []):
                report.out(contact_line(entry))
            continue
        report.out(f"load factor {step['load_factor']:.4g}: tip u = {tip['u']:.6g} m, "
                   f"v = {tip['v']:.6g} m, theta = {tip['theta']:.6g} rad")
        for entry in step.get("contact", []):
            report.out(contact_line(entry))
    code = closing_of_steps(report, result, out)
    return Result("static", result.summary(), code, report.lines, result)

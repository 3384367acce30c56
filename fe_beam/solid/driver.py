"""``fe-beam solid``: the 3D hyperelastic finger from the rod's TOML configuration.

The configuration uses the rod's tables (`fe_beam.config`) for the geometry, the material, the
tip force, the load steps and the ``[[tendons]]`` (as in `fe_beam.finger`), plus a ``[solid]``
table (`SOLID_KEYS`) for the 3D law, the formulation and the mesh. The same configuration is also
run through the 1D rod model (`fe_beam.static.solve_static`) with the rod's E and G taken from the
small-strain limit of the 3D law, so that both results can be compared and opened together in
ParaView (same coordinates: x along the finger, y up, z across; the origin is the centroid of the
clamped face, which is where the rod's axis starts).

3D set-up (docs/theory.md, 3D finger and cable): body 0 <= x <= L, |y| <= H(x)/2, |z| <= B/2, with
H(x) = h + (h_tip - h) x / L is clamped at x = 0; ``[loads] tip_force`` is a uniform dead traction
on the tip face; a tendon with offset delta(x) becomes the cable through (x, delta(x), z) with
z = 0 (several branches of one tendon, e.g. a loop: z = B ((k + 1/2)/n - 1/2), k = 0 .. n-1).

Results: `run_solid` returns (and writes into ``out``) a summary whose ``steps`` hold, per
converged load step, the load factor, the tendon tensions, the tip-face centroid displacement and
rotation ``tip = {u, v, theta}``, the backbone (deformed centroids of the sections at the
``backbone_points`` stations), the Newton and linear iterations and the largest principal stretch.
"""

from __future__ import annotations

import copy
import itertools
import math
import re
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam import runctl
from fe_beam.config import (
    NUMBER,
    OTHER_TABLES,
    SCHEMA,
    ConfigError,
    Key,
    OutputOptions,
    StaticConfig,
    _wrap,
    check_tables,
    parse_static,
    table,
)
from fe_beam.material_laws import (  # noqa: F401
    LAW_CONSTANTS,
    MATERIALS,
    _positive,
    hyperelastic_law,
)
from fe_beam.outputs import _pyplot, atomic_write_json, atomic_write_text, write_csv
from fe_beam.solid.export import DisplacementXDMF
from fe_beam.solid.geometry import FingerGeometry, MeshSizes, TendonPath, create_finger_mesh
from fe_beam.solid.materials import SILICONE_PRESETS, VOLUMETRIC_LAWS, HyperelasticLaw
from fe_beam.solid.problem import (
    ANCHORS,
    Discretization,
    SolidFingerProblem,
    TendonLoad,
    evaluate_at_points,
    stretch_keys,
)
from fe_beam.solver import LoadStepping, LoadSteppingFailed, SolverSettings, run_load_stepping
from fe_beam.static import beam_dofs_estimate


def _import_gmsh() -> None:
    """gmsh (4.8) resets SIGINT to its default action when first imported: import it now, then
    put the deferring handlers of fe_beam.runctl back, so Ctrl-C while meshing ends cleanly."""
    import gmsh  # noqa: F401

    runctl.reassert()


_import_gmsh()

__all__ = [
    "SOLID_KEYS",
    "SolidConfig",
    "SolidRun",
    "backbone_distance",
    "parse_solid",
    "rod_backbone",
    "run_rod",
    "run_solid",
    "solid_law",
]

FORMULATIONS = {"displacement": "displacement", "mixed-up": "mixed"}
SOLVERS = ("mumps", "gamg")
#: a mesh estimated to have more tetrahedra than this is refused (a typo in mesh_size)
MAX_CELLS = 5_000_000

SOLID_KEYS: dict[str, Key] = {
    "material": Key((str,), "neo-hookean", "neo-hookean | mooney-rivlin | yeoh | svk"),
    "preset": Key((str,), None, f"silicone preset: {', '.join(sorted(SILICONE_PRESETS))}"),
    "mu": Key(NUMBER, None, "shear modulus [Pa] (neo-hookean, svk)"),
    "c10": Key(NUMBER, None, "C10 [Pa] (mooney-rivlin, yeoh)"),
    "c01": Key(NUMBER, None, "C01 [Pa] (mooney-rivlin)"),
    "c20": Key(NUMBER, None, "C20 [Pa] (yeoh)"),
    "c30": Key(NUMBER, None, "C30 [Pa] (yeoh)"),
    "kappa": Key(NUMBER, None, "bulk modulus [Pa] (default from [material] nu)"),
    "volumetric": Key((str,), "simo_taylor", " | ".join(VOLUMETRIC_LAWS)),
    "formulation": Key((str,), "displacement", "displacement | mixed-up"),
    "order": Key((int,), 2, "polynomial degree of the displacement, 1 or 2"),
    "quadrature_degree": Key((int,), None, "quadrature degree (default 2 * order)"),
    "mesh_size": Key(NUMBER, None, "element size [m] (default min(b, h, h_tip) / 2)"),
    "tendon_refinement": Key(NUMBER, 1.0, "element size near tendons = mesh_size / this (>= 1)"),
    "clamp_refinement": Key(NUMBER, 1.0, "element size near the clamp = mesh_size / this (>= 1)"),
    "refinement_distance": Key(NUMBER, None, "reach of the refinements [m] (default mesh_size)"),
    "solver": Key((str,), "mumps", "mumps | gamg (gamg: displacement formulation only)"),
    "petsc_options": Key((dict,), {}, "PETSc options of the 3D solve, without prefix"),
    "backbone_points": Key((int,), 21, "number of sections sampled along x for the backbone"),
    "anchor": Key((str,), "face", "face | point: a tendon ending on the tip face pulls on the "
                  "whole face as a plate (same force and moment), or on its last vertex"),
}
MATERIAL_KEYS = SCHEMA["material"] | {
    "E": Key(NUMBER, None, "Young's modulus [Pa] (not with a [solid] preset)")
}
#: [loads] keys of the rod that have no 3D counterpart (must keep their defaults)
UNSUPPORTED_LOADS = (
    "tip_moment", "follower", "distributed", "gravity", "prescribed_x0", "prescribed_xL",
    "time_function", "time_table", "motion_function",
)
#: tables that configure only the 3D model or other commands (removed from the rod's config)
SOLID_ONLY_TABLES = ("solid", "compare", "refine")


NEARLY_INCOMPRESSIBLE_NU = 0.49  # above it, the displacement formulation gets a note


@dataclass(frozen=True)
class SolidConfig:
    """A validated ``fe-beam solid`` configuration.

    ``rod`` is the 1D companion (rod's E, G = the 3D law's small-strain limit; planar tip force);
    ``rod_note`` says why it is None (a tip force with a z component). ``branch_owner[i]`` is the
    index of the ``[[tendons]]`` entry that 3D cable i belongs to.
    """

    geometry: FingerGeometry
    sizes: MeshSizes
    material: HyperelasticLaw
    material_name: str
    formulation_name: str
    discretization: Discretization
    solver: SolverSettings
    stepping: LoadStepping
    tendon_loads: tuple[TendonLoad, ...]
    branch_owner: tuple[int, ...]
    tendon_names: tuple[str, ...]
    tip_force: tuple[float, float, float]
    stations: tuple[float, ...]
    output: OutputOptions
    rod: StaticConfig | None
    rod_note: str = ""
    raw: dict = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    anchor: str = "face"

    @property
    def length(self) -> float:
        return self.geometry.length

    def model_summary(self) -> dict:
        g, s, law = self.geometry, self.sizes, self.material
        return {
            "geometry": {"length": g.length, "b": g.width, "h": g.height_base,
                         "h_tip": g.height_tip},
            "material": {
                "law": self.material_name,
                "coefficients": law.coefficients(),
                "volumetric": law.volumetric,
                "small_strain": {"E": law.young_modulus, "nu": law.poisson_ratio,
                                 "G": law.shear_modulus, "kappa": law.bulk_modulus},
            },
            "formulation": self.formulation_name,
            "order": self.discretization.degree,
            "mesh": {"size": s.size, "tendon": s.tendon, "clamp": s.clamp,
                     "tendon_distance": s.tendon_distance, "clamp_distance": s.clamp_distance},
            "linear_solver": self.solver.linear_solver,
            "anchor": self.anchor,
            "tip_force": list(self.tip_force),
            "tendons": [
                {"name": name, "points": [list(p) for p in path.points],
                 "tension": load.tension, "pull_in": load.pull_in}
                for name, path, load in zip(self.tendon_names, g.tendons, self.tendon_loads,
                                            strict=True)
            ],
        }


# --- parsing ------------------------------------------------------------------------------------




def solid_law(raw: dict, solid: dict | None = None) -> HyperelasticLaw:
    """The 3D law of ``[solid]`` (`fe_beam.material_laws.hyperelastic_law`)."""
    solid = table(raw, "solid", SOLID_KEYS) if solid is None else solid
    return hyperelastic_law(raw, solid, "solid", "the 3D solid")


def _section(raw: dict) -> tuple[float, float, float]:
    given = raw.get("section", {})
    if not isinstance(given, dict):
        raise ConfigError("[section] must be a table")
    shape = given.get("shape", "rectangle")
    if shape != "rectangle":
        raise ConfigError(
            f"[section] shape must be \"rectangle\" for the 3D solid (b, h, optional h_tip); "
            f"got {shape!r}"
        )
    for key, value in given.items():
        if key == "shape":
            continue
        if key not in ("b", "h", "h_tip"):
            raise ConfigError(
                f"[section] {key} is not supported by the 3D solid (constant width b, height h "
                "tapering linearly to h_tip); allowed: shape, b, h, h_tip"
            )
        if isinstance(value, bool) or not isinstance(value, NUMBER) or not math.isfinite(value):
            raise ConfigError(f"[section] {key} must be a number; got {value!r}")
        _positive(f"[section] {key}", value)
    for key in ("b", "h"):
        if key not in given:
            raise ConfigError(f"[section] {key} is required for the 3D solid")
    return float(given["b"]), float(given["h"]), float(given.get("h_tip", given["h"]))


def _tip_force(loads: dict) -> tuple[float, float, float]:
    force = loads["tip_force"]
    ok = len(force) in (2, 3) and all(
        isinstance(f, NUMBER) and not isinstance(f, bool) and math.isfinite(f) for f in force
    )
    if not ok:
        raise ConfigError(
            f"[loads] tip_force must be [Px, Py] or [Px, Py, Pz] (finite numbers, N); "
            f"got {force!r}"
        )
    return tuple(float(f) for f in force) + (0.0,) * (3 - len(force))


def _check_rod_only_settings(raw: dict, loads: dict) -> None:
    for key in UNSUPPORTED_LOADS:
        default = SCHEMA["loads"][key].default
        value = loads[key]
        same = value == default
        if isinstance(value, list) and isinstance(default, list):
            same = all(v == 0 for v in value)
        if not same:
            raise ConfigError(
                f"[loads] {key} is not supported by the 3D solid (it takes tip_force, steps and "
                f"[[tendons]]); got {value!r}"
            )
    supports = table(raw, "supports")
    if supports["x0"] != "clamped" or supports["xL"] != "free":
        raise ConfigError(
            "[supports] the 3D solid is clamped at x = 0 and free at x = L (x0 = \"clamped\", "
            f"xL = \"free\"); got x0 = {supports['x0']!r}, xL = {supports['xL']!r}"
        )


def _rod_static(raw: dict, law: HyperelasticLaw, section, tip_force) -> StaticConfig:
    """The rod's StaticConfig: the same tables, E and G from the 3D law's small-strain limit."""
    from fe_beam.finger import parse_finger

    rod = {k: copy.deepcopy(v) for k, v in raw.items() if k not in SOLID_ONLY_TABLES}
    rho = table(raw, "material", MATERIAL_KEYS)["rho"]
    rod["material"] = {"E": law.young_modulus, "G": law.shear_modulus, "rho": rho}
    b, h, h_tip = section
    rod["section"] = {"shape": "rectangle", "b": b, "h": h, "h_tip": h_tip}
    rod["loads"] = dict(rod.get("loads", {})) | {"tip_force": [tip_force[0], tip_force[1]]}
    if "tendons" in rod:
        static, _ = parse_finger(rod)
        return static
    return parse_static(rod)


def _cables(static: StaticConfig, width: float):
    """3D cable paths, loads, owners and names from the rod's parsed tendons."""
    paths, loads, owners, names = [], [], [], []
    for index, tendon in enumerate(static.tendons):
        count = len(tendon.paths)
        if count > 1 and tendon.controlled_by_pull_in:
            raise ConfigError(
                f"[[tendons]] {tendon.name!r}: pull_in with several branches (paths) is not "
                "supported by the 3D solid; give a tension"
            )
        for k, path in enumerate(tendon.paths):
            z = 0.0 if count == 1 else width * ((k + 0.5) / count - 0.5)
            xs = np.array([p[0] for p in path])
            ds = np.array([p[1] for p in path])
            inner = [x for x in xs if tendon.entry < x < tendon.anchor]
            stations = [tendon.entry, *inner, tendon.anchor]
            points = tuple((x, float(np.interp(x, xs, ds)), z) for x in stations)
            name = tendon.name if count == 1 else f"{tendon.name}[{k}]"
            paths.append(_wrap(TendonPath, points, name=name))
            if tendon.controlled_by_pull_in:
                loads.append(TendonLoad(pull_in=float(tendon.pull_in)))
            else:
                loads.append(TendonLoad(tension=float(tendon.tension)))
            owners.append(index)
            names.append(name)
    return tuple(paths), tuple(loads), tuple(owners), tuple(names)


def parse_solid(raw: dict) -> SolidConfig:
    """Validate a configuration for ``fe-beam solid`` (raises ConfigError naming the key)."""
    if not isinstance(raw, dict):
        raise ConfigError("the configuration must be a table")
    if "inverse" in raw:
        raise ConfigError("[inverse] belongs to fe-beam finger (the 3D solid has no inverse "
                          "solve); remove it")
    check_tables(raw, tuple(SCHEMA) + OTHER_TABLES)
    solid = table(raw, "solid", SOLID_KEYS)
    length = table(raw, "beam")["length"]
    _positive("[beam] length", length)
    section = _section(raw)
    loads = table(raw, "loads")
    tip_force = _tip_force(loads)
    _check_rod_only_settings(raw, loads)
    law = solid_law(raw, solid)

    formulation = solid["formulation"]
    if formulation not in FORMULATIONS:
        raise ConfigError(
            f"[solid] formulation must be one of {', '.join(FORMULATIONS)}; got {formulation!r}"
        )
    if solid["order"] not in (1, 2):
        raise ConfigError(f"[solid] order must be 1 or 2; got {solid['order']!r}")
    if formulation == "mixed-up":
        if solid["order"] != 2:
            raise ConfigError("[solid] order must be 2 with formulation = \"mixed-up\" "
                              f"(Taylor-Hood P2-P1); got {solid['order']!r}")
        if not law.supports_mixed:
            raise ConfigError("[solid] formulation = \"mixed-up\" needs an isochoric/volumetric "
                              "split: use material = neo-hookean, mooney-rivlin or yeoh, not svk")
    if solid["anchor"] not in ANCHORS:
        raise ConfigError(f"[solid] anchor must be one of {', '.join(ANCHORS)}; "
                          f"got {solid['anchor']!r}")
    if solid["solver"] not in SOLVERS:
        raise ConfigError(f"[solid] solver must be one of {', '.join(SOLVERS)}; "
                          f"got {solid['solver']!r}")
    if solid["solver"] == "gamg" and formulation != "displacement":
        raise ConfigError("[solid] solver = \"gamg\" needs formulation = \"displacement\"")
    q = solid["quadrature_degree"]
    if q is not None and q < 1:
        raise ConfigError(f"[solid] quadrature_degree must be an integer >= 1; got {q!r}")
    if solid["backbone_points"] < 2:
        raise ConfigError(
            f"[solid] backbone_points must be an integer >= 2; got {solid['backbone_points']!r}"
        )

    b, h, h_tip = section
    size = solid["mesh_size"]
    size = min(b, h, h_tip) / 2 if size is None else _positive("[solid] mesh_size", size)
    if size > length:
        raise ConfigError(f"[solid] mesh_size must be <= [beam] length = {length:g}; got {size!r}")
    for key in ("tendon_refinement", "clamp_refinement"):
        _positive(f"[solid] {key}", solid[key], 1.0, strict=False)
    distance = solid["refinement_distance"]
    distance = size if distance is None else _positive("[solid] refinement_distance", distance)
    estimate = 6 * length * b * (h + h_tip) / 2 / size**3
    if estimate > MAX_CELLS:
        raise ConfigError(
            f"[solid] mesh_size = {size:g} gives about {estimate:.2g} tetrahedra (more than "
            f"{MAX_CELLS:.0e}); use a larger mesh_size"
        )
    sizes = _wrap(
        MeshSizes, size, tendon=size / solid["tendon_refinement"], tendon_distance=distance,
        clamp=size / solid["clamp_refinement"], clamp_distance=distance, order=1,
    )
    rod = _rod_static(raw, law, section, tip_force)
    paths, tendon_loads, owners, names = _cables(rod, b)
    try:
        geometry = FingerGeometry(length, b, h, h_tip, tendons=paths)
    except ValueError as error:
        raise ConfigError(f"[[tendons]] {error}") from None
    discretization = _wrap(Discretization, FORMULATIONS[formulation], solid["order"], q)
    settings = _wrap(
        replace, rod.solver, linear_solver=solid["solver"], petsc_options=solid["petsc_options"]
    )
    planar = tip_force[2] == 0
    notes = []
    if formulation == "displacement" and law.poisson_ratio > NEARLY_INCOMPRESSIBLE_NU:
        notes.append(
            f"[solid] formulation = \"displacement\" with nu = {law.poisson_ratio:.6g}: "
            "displacement elements lock as nu -> 0.5 (too stiff, slow Newton); "
            "formulation = \"mixed-up\" is made for this"
        )
    return SolidConfig(
        geometry=geometry,
        sizes=sizes,
        material=law,
        material_name=solid["material"],
        formulation_name=formulation,
        discretization=discretization,
        solver=settings,
        stepping=rod.stepping,
        tendon_loads=tendon_loads,
        branch_owner=owners,
        tendon_names=names,
        tip_force=tip_force,
        stations=tuple(np.linspace(0.0, length, solid["backbone_points"]).tolist()),
        output=OutputOptions(**table(raw, "output")),
        rod=rod if planar else None,
        rod_note="" if planar else "no rod comparison: the tip force has a z component",
        raw=copy.deepcopy(raw),
        notes=tuple(notes),
        anchor=solid["anchor"],
    )


# --- the 3D run ---------------------------------------------------------------------------------

_RUNS = itertools.count(1)


class SolidRun:
    """The meshed 3D finger and its problem, advanced along the load factor in segments.

    ``advance(target)`` ramps the load factor from its current value to ``target`` with
    `fe_beam.solver.run_load_stepping` (cut-back on divergence) and calls ``on_step(record)``
    after each converged step with the plain-data `record`.
    """

    def __init__(self, config: SolidConfig, comm: MPI.Comm = MPI.COMM_WORLD):
        self.config = config
        self.comm = comm
        self.finger = create_finger_mesh(config.geometry, config.sizes, comm)
        self.problem = SolidFingerProblem(
            self.finger,
            config.material,
            tendons=config.tendon_loads,
            tip_force=config.tip_force,
            discretization=config.discretization,
            solver=config.solver,
            prefix=f"fe_beam_solid{next(_RUNS)}_",
            anchor=config.anchor,
        )
        self.load_factor = 0.0
        self._theta = 0.0

    @property
    def dofs(self) -> int:
        dofmap = self.problem.W.dofmap
        return int(dofmap.index_map.size_global * dofmap.index_map_bs)

    @property
    def cells(self) -> int:
        imap = self.finger.mesh.topology.index_map(3)
        return int(imap.size_global)

    def advance(self, target: float, stepping: LoadStepping, on_step=None,
                progress: bool = False, label: str = "solid") -> None:
        """Load factor from its current value to ``target`` (raises LoadSteppingFailed with the
        last converged state restored)."""
        start = self.load_factor
        span = float(target) - start
        if not span > 0:
            raise ValueError(f"advance: target {target!r} must exceed {start!r}")
        steps = max(1, math.ceil(stepping.steps * span - 1e-9))
        segment = LoadStepping(
            steps=steps,
            min_increment=min(stepping.min_increment / span, 1.0 / steps),
            cut_factor=stepping.cut_factor,
            grow_factor=stepping.grow_factor,
            easy_iterations=stepping.easy_iterations,
            adaptive=stepping.adaptive,
        )

        attempted = [start]

        def set_factor(s: float) -> None:
            value = start + s * span
            if value > self.load_factor:
                attempted[0] = value
            self.problem.set_load_factor(value)

        def converged(step) -> None:
            self.load_factor = float(target) if step.load_factor == 1.0 else (
                start + step.load_factor * span
            )
            record = self.record(step.iterations, step.linear_iterations)
            if on_step is not None:
                on_step(record)

        try:
            run_load_stepping(self.problem.solver, set_factor, segment, on_converged=converged,
                              progress=progress, label=label)
        except LoadSteppingFailed as failure:
            self.problem.set_load_factor(self.load_factor)
            found = re.search(r"\((.*)\); last converged", str(failure))
            reason = found.group(1) if found else str(failure)
            raise LoadSteppingFailed(
                f"load stepping stopped at load factor {attempted[0]:.6g} ({reason}); "
                f"last converged load factor {self.load_factor:.6g}",
                self.load_factor, failure.results,
            ) from None

    def tip(self) -> dict:
        """Tip-face centroid displacement (u, v) and rotation theta (continuous along the path)."""
        d = self.problem.tip_displacement()
        angle = self.problem.tip_rotation()["angle"]
        self._theta += (angle - self._theta + math.pi) % (2 * math.pi) - math.pi
        return {"u": float(d[0]), "v": float(d[1]), "theta": float(self._theta)}

    def backbone(self) -> dict:
        data = self.problem.backbone(self.config.stations)
        u = np.asarray(data["displacement"])
        return {"x": list(data["x"]), "u": u[:, 0].tolist(), "v": u[:, 1].tolist()}

    def tendon_values(self) -> dict:
        owners = self.config.branch_owner
        if not owners:
            return {}
        count = max(owners) + 1
        tensions = self.problem.tensions()
        lengths = self.problem.tendon_lengths()
        rest = [c.reference_length for c in self.problem.cables]
        per_tendon = [0.0] * count
        pulls = [0.0] * count
        for i, owner in enumerate(owners):
            per_tendon[owner] = float(tensions[i])
            pulls[owner] += float(rest[i] - lengths[i])
        values = {"tensions": per_tendon, "pull_ins": pulls}
        if count == 1:
            values["tension"] = per_tendon[0]
        return values

    def record(self, newton_iterations: int = 0, linear_iterations: int = 0) -> dict:
        """Plain data of the current state (collective)."""
        return {
            "load_factor": self.load_factor,
            **self.tendon_values(),
            "tip": self.tip(),
            "backbone": self.backbone(),
            "newton_iterations": int(newton_iterations),
            "linear_iterations": int(linear_iterations),
            **stretch_keys(self.problem.max_principal_stretches()),
        }

    def destroy(self) -> None:
        self.problem.snes_solver.destroy()


# --- the rod companion --------------------------------------------------------------------------


def rod_backbone(problem, stations) -> dict:
    """Rod displacement (u, v) at the stations x (exact finite-element values, collective)."""
    points = np.zeros((len(stations), 3))
    points[:, 0] = stations
    u = evaluate_at_points(problem.w.sub(0).collapse(), points).ravel()
    v = evaluate_at_points(problem.w.sub(1).collapse(), points).ravel()
    return {"x": [float(x) for x in stations], "u": u.tolist(), "v": v.tolist()}


def run_rod(static: StaticConfig, stations, comm=MPI.COMM_WORLD, progress: bool = False) -> dict:
    """Run the 1D rod (`fe_beam.static.solve_static`, nothing written) and return plain data:
    status, steps (load factor, tip, tensions), the final backbone at ``stations`` and, on rank
    0, the nodal shapes of every step (``frames``, for the rod XDMF)."""
    from fe_beam.static import solve_static

    holder = {}

    def keep(problem, entry):
        holder["problem"] = problem

    result = solve_static(static, None, comm, progress=progress, on_step=keep)
    model = static.model
    data = {
        "law": model.options.law,
        "constraint": model.options.constraint,
        "E": model.material.E,
        "G": model.material.shear_modulus,
        "status": result.status,
        "message": result.message,
        "dofs": result.dofs,
        "wall_time_s": result.wall_time_s,
        "steps": [
            {k: s[k] for k in ("load_factor", "tip", "tensions", "pull_ins") if k in s}
            for s in result.steps
        ],
        "backbone": rod_backbone(holder["problem"], stations) if "problem" in holder else None,
    }
    frames = [(s["load_factor"], shape) for s, (_, shape) in
              zip(result.steps, result.shapes, strict=False)] if comm.rank == 0 else []
    return data | {"frames": frames}


def backbone_distance(rod: dict, solid: dict) -> dict:
    """max over the stations x of |r_rod(x) - r_solid(x)| (deformed centroid positions in the
    x-y plane at the same reference x), with the x where it occurs."""
    ur, vr = np.asarray(rod["u"]), np.asarray(rod["v"])
    us, vs = np.asarray(solid["u"]), np.asarray(solid["v"])
    distance = np.hypot(ur - us, vr - vs)
    k = int(np.argmax(distance))
    return {"max": float(distance[k]), "x": float(solid["x"][k])}


def write_rod_xdmf(path: Path, frames: list) -> None:
    """The rod as a polyline in 3D (x, 0, 0) with nodal ``displacement`` (u, v, 0) and ``theta``,
    one time per load factor: an XDMF file with inline data (no HDF5), written atomically."""
    if not frames:
        return
    x = np.asarray(frames[0][1]["x"], dtype=float)
    n = len(x)
    geometry = " ".join(f"{xi:.17g} 0 0" for xi in x)
    topology = " ".join(f"{i} {i + 1}" for i in range(n - 1))

    def grid(t, shape):
        u, v, theta = (np.asarray(shape[k], dtype=float) for k in ("u", "v", "theta"))
        displacement = " ".join(f"{a:.17g} {b:.17g} 0" for a, b in zip(u, v, strict=True))
        rotation = " ".join(f"{a:.17g}" for a in theta)
        return (
            f'      <Grid Name="rod" GridType="Uniform">\n'
            f'        <Time Value="{t:.17g}"/>\n'
            f'        <Topology TopologyType="Polyline" NodesPerElement="2" '
            f'NumberOfElements="{n - 1}">\n'
            f'          <DataItem Dimensions="{n - 1} 2" NumberType="Int" Format="XML">'
            f"{topology}</DataItem>\n        </Topology>\n"
            f'        <Geometry GeometryType="XYZ">\n'
            f'          <DataItem Dimensions="{n} 3" Format="XML">{geometry}</DataItem>\n'
            f"        </Geometry>\n"
            f'        <Attribute Name="displacement" AttributeType="Vector" Center="Node">\n'
            f'          <DataItem Dimensions="{n} 3" Format="XML">{displacement}</DataItem>\n'
            f"        </Attribute>\n"
            f'        <Attribute Name="theta" AttributeType="Scalar" Center="Node">\n'
            f'          <DataItem Dimensions="{n}" Format="XML">{rotation}</DataItem>\n'
            f"        </Attribute>\n      </Grid>\n"
        )

    zero = {"x": x, "u": np.zeros(n), "v": np.zeros(n), "theta": np.zeros(n)}
    grids = [grid(0.0, zero)] + [grid(t, shape) for t, shape in frames]
    text = (
        '<?xml version="1.0"?>\n<Xdmf Version="3.0">\n  <Domain>\n'
        '    <Grid Name="rod" GridType="Collection" CollectionType="Temporal">\n'
        + "".join(grids)
        + "    </Grid>\n  </Domain>\n</Xdmf>\n"
    )
    atomic_write_text(path, text)


# --- driver -------------------------------------------------------------------------------------


def run_solid(raw: dict, out: Path | None, comm=MPI.COMM_WORLD, progress: bool = True) -> dict:
    """Validate ``raw`` (the parsed TOML), run the rod companion and the 3D load stepping, write
    results into ``out`` (if not None) and return the summary dict.

    Raises ConfigError for a mistake in ``raw``; an analysis that stops early returns (and
    writes) the converged steps with ``status = "failed"`` and a ``message``. Collective on
    ``comm``; files are written by its rank 0. ``out`` receives ``summary.json``,
    ``load_displacement.csv``, ``solid.xdmf``/``.h5`` (3D displacement per load factor),
    ``rod.xdmf`` (the rod in the same coordinates) and, with ``[output] plots``, ``backbone.png``
    and ``load_displacement.png``.
    """
    started = time.perf_counter()
    config = parse_solid(raw)
    notes = check_solid_work(config, comm, quiet=out is None)
    out = None if out is None else Path(out)
    root = comm.rank == 0
    if out is not None and root:
        out.mkdir(parents=True, exist_ok=True)
    summary = {
        "status": "running",
        "message": "",
        "steps": [],
        "dofs": 0,
        "cells": 0,
        "wall_time_s": 0.0,
        "model": config.model_summary(),
        "rod": None,
        "notes": list(config.notes) + notes,
    }

    def save() -> None:
        summary["wall_time_s"] = time.perf_counter() - started
        if out is not None and root:
            _write_tables(out, summary)

    save()  # status "running" from the start
    try:
        return _run_solid(config, out, comm, progress, summary, save)
    except runctl.Interrupted as stop:
        last = summary["steps"][-1]["load_factor"] if summary["steps"] else 0.0
        summary |= stop.stopped(f"load factor {last:.4g}", f"at load factor {last:.6g}")
        save()
        raise


def solid_dofs_estimate(config: SolidConfig) -> float:
    """About how many unknowns the 3D mesh will have (before gmsh meshes it): ~1.5 V / h^3
    vertices for tetrahedra of size h, 8 times as many nodes for P2, 3 components."""
    g, sizes = config.geometry, config.sizes
    volume = g.length * g.width * 0.5 * (g.height_base + (g.height_tip or g.height_base))
    h = min(sizes.size, sizes.tendon or sizes.size)
    nodes = 1.5 * volume / h**3 * (8 if config.discretization.degree >= 2 else 1)
    return 3.0 * nodes


def check_solid_work(config: SolidConfig, comm, quiet: bool = False) -> list[str]:
    """Up-front limits of `fe_beam.runctl.check_work` for the 3D solid (and its rod)."""
    allow = bool((config.raw.get("solver") or {}).get("allow_large", False))
    notes = runctl.check_work(config.stepping.steps, solid_dofs_estimate(config), allow,
                              " of load stepping", kind="solid")
    if config.rod is not None:
        notes += runctl.check_work(None, beam_dofs_estimate(config.rod), allow)
    if not quiet:
        runctl.warn(comm, notes)
    return notes


def _run_solid(config: SolidConfig, out: Path | None, comm, progress: bool, summary: dict,
               save) -> dict:
    root = comm.rank == 0
    rod = None
    if config.rod is not None:
        rod = run_rod(config.rod, config.stations, comm, progress=progress)
        if out is not None and root and config.output.xdmf:
            write_rod_xdmf(out / "rod.xdmf", rod["frames"])
        summary["rod"] = {k: v for k, v in rod.items() if k != "frames"}
    else:
        summary["rod"] = {"status": "skipped", "message": config.rod_note}

    try:
        run = SolidRun(config, comm)
    except RuntimeError as error:  # gmsh could not mesh (e.g. a tendon not on tet edges)
        summary |= {"status": "failed", "message": str(error)}
        save()
        if out is not None:
            comm.barrier()
        return summary
    summary |= {"dofs": run.dofs, "cells": run.cells}
    writer = None
    if out is not None and config.output.xdmf:
        writer = DisplacementXDMF(run.problem, out / "solid.xdmf")
        writer.write(0.0)

    def on_step(record: dict) -> None:
        summary["steps"].append(record)
        if writer is not None:
            writer.write(record["load_factor"])
        save()

    try:
        run.advance(1.0, config.stepping, on_step, progress=progress, label="solid")
        summary["status"] = "converged"
    except LoadSteppingFailed as failure:
        summary |= {"status": "failed", "message": str(failure)}
    finally:
        if writer is not None:
            writer.close()
        run.destroy()
    if rod is not None and rod["backbone"] is not None and summary["steps"]:
        last_rod = rod["steps"][-1]["load_factor"] if rod["steps"] else 0.0
        last = summary["steps"][-1]
        if abs(last_rod - last["load_factor"]) < 1e-12:
            distance = backbone_distance(rod["backbone"], last["backbone"])
            summary["rod"]["distance_to_solid"] = {
                "load_factor": last["load_factor"],
                "max_over_L": distance["max"] / config.length,
                "x": distance["x"],
                "measure": "max over x of |r_rod(x) - r_solid(x)| / L (deformed centroids)",
            }
    save()
    if out is not None and root and config.output.plots and summary["steps"]:
        _plot_solid(out, summary, config)
    if out is not None:
        comm.barrier()  # the files are complete on return, whichever rank looks
    return summary


def _write_tables(out: Path, summary: dict) -> None:
    atomic_write_json(out / "summary.json", summary)
    steps = summary["steps"]
    count = len(steps[0].get("tensions", [])) if steps else 0
    header = ["load_factor", *[f"tension_{i}" for i in range(count)], "tip_u", "tip_v",
              "tip_theta", "newton_iterations", "linear_iterations", "max_principal_stretch",
              "max_principal_stretch_bulk"]
    rows = [
        [s["load_factor"], *s.get("tensions", []), s["tip"]["u"], s["tip"]["v"],
         s["tip"]["theta"], s["newton_iterations"], s["linear_iterations"],
         s["max_principal_stretch"], s["max_principal_stretch_bulk"]]
        for s in steps
    ]
    write_csv(out / "load_displacement.csv", header, rows)


def _plot_solid(out: Path, summary: dict, config: SolidConfig) -> None:
    plt = _pyplot()
    steps = summary["steps"]
    rod = summary.get("rod") or {}
    figure, axis = plt.subplots(figsize=(9, 4.5))
    every = max(1, len(steps) // 8)
    chosen = steps[every - 1 :: every]
    if chosen[-1] is not steps[-1]:
        chosen.append(steps[-1])
    colours = plt.cm.viridis(np.linspace(0, 0.9, len(chosen)))
    axis.plot([0, config.length], [0, 0], color="0.7", lw=1, ls="--", label="undeformed")
    for step, colour in zip(chosen, colours, strict=True):
        b = step["backbone"]
        axis.plot(np.add(b["x"], b["u"]), b["v"], color=colour, lw=1.8,
                  label=f"3D, load factor {step['load_factor']:.3g}")
    if rod.get("backbone") and rod.get("steps"):
        b = rod["backbone"]
        axis.plot(np.add(b["x"], b["u"]), b["v"], "k:", lw=1.5,
                  label=f"rod ({rod['law']}), load factor {rod['steps'][-1]['load_factor']:.3g}")
    axis.set_xlabel("x + u [m]")
    axis.set_ylabel("y + v [m]")
    axis.set_title(f"Backbone: 3D {config.material_name} vs rod")
    axis.grid(alpha=0.3)
    axis.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    figure.tight_layout()
    figure.savefig(out / "backbone.png", dpi=130)
    plt.close(figure)

    figure, axes = plt.subplots(1, 3, figsize=(11, 3.4))
    factors = [s["load_factor"] for s in steps]
    rod_steps = rod.get("steps") or []
    for axis, key, unit in zip(axes, ("u", "v", "theta"), ("m", "m", "rad"), strict=True):
        axis.plot(factors, [s["tip"][key] for s in steps], "o-", ms=3, label="3D")
        if rod_steps:
            axis.plot([s["load_factor"] for s in rod_steps], [s["tip"][key] for s in rod_steps],
                      "s--", ms=3, label=f"rod ({rod['law']})")
        axis.set_xlabel("load factor")
        axis.set_ylabel(f"tip {key} [{unit}]")
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(out / "load_displacement.png", dpi=130)
    plt.close(figure)

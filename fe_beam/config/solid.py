"""The configuration of ``fe-beam solid`` (and of the solid in ``fe-beam compare`` and
``fe-beam refine``): the ``[solid]`` table (`SOLID_KEYS`), the rod tables it shares, and
`parse_solid`, which validates a whole configuration into a `SolidConfig`.

Pure Python, numpy and UFL (the 3D laws): no dolfinx, PETSc, MPI or gmsh, so that a mistake is
reported before the finite-element stack loads. The run is in `fe_beam.analyses.solid`, the 1D rod
companion in `fe_beam.analyses.solid_rod`; `fe_beam.analyses.solid_driver` re-exports all three.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field, replace

import numpy as np

from fe_beam.config.contact import parse_contact
from fe_beam.config.finger import parse_finger
from fe_beam.config.material_laws import (  # noqa: F401
    LAW_CONSTANTS,
    MATERIALS,
    _positive,
    hyperelastic_law,
)
from fe_beam.config.schema import (
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
from fe_beam.model.hyperelastic import SILICONE_PRESETS, VOLUMETRIC_LAWS, HyperelasticLaw
from fe_beam.model.loads import LOADS
from fe_beam.model.settings import SOLID_LINEAR_SOLVERS, LoadStepping, SolverSettings
from fe_beam.model.solid import (
    ANCHORS,
    Discretization,
    FingerGeometry,
    MeshSizes,
    TendonLoad,
    TendonPath,
)

__all__ = [
    "MATERIAL_KEYS",
    "SOLID_KEYS",
    "SolidConfig",
    "parse_solid",
    "planar_obstacles",
    "solid_dofs_estimate",
    "solid_law",
    "spatial_rod",
]

FORMULATIONS = {"displacement": "displacement", "mixed-up": "mixed"}
SOLVERS = SOLID_LINEAR_SOLVERS  # auto | mumps | gamg | fieldsplit
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
    "solver": Key((str,), "auto", "auto | mumps | gamg | fieldsplit (auto: MUMPS on small "
                  "meshes, else the iterative solver: gamg = CG + GAMG for displacement, "
                  "fieldsplit = FGMRES + Schur fieldsplit for mixed-up)"),
    "petsc_options": Key((dict,), {}, "PETSc options of the 3D solve, without prefix"),
    "backbone_points": Key((int,), 21, "number of sections sampled along x for the backbone"),
    "anchor": Key((str,), "face", "face | point: a tendon ending on the tip face pulls on the "
                  "whole face as a plate (same force and moment), or on its last vertex"),
}
MATERIAL_KEYS = SCHEMA["material"] | {
    "E": Key(NUMBER, None, "Young's modulus [Pa] (not with a [solid] preset)")
}
#: [loads] keys of the rod that have no 3D counterpart (must keep their defaults): the loads
#: the registry does not flag ``solid`` (fe_beam.model.loads) and the rod's other load keys
UNSUPPORTED_LOADS = tuple(name for name, kind in LOADS.items() if not kind.solid) + (
    "follower", "prescribed_x0", "prescribed_xL", "time_function", "time_table",
    "motion_function",
)
#: tables that configure only the 3D model or other commands (removed from the rod's config)
SOLID_ONLY_TABLES = ("solid", "compare", "refine")


NEARLY_INCOMPRESSIBLE_NU = 0.49  # above it, the displacement formulation gets a note


@dataclass(frozen=True)
class SolidConfig:
    """A validated ``fe-beam solid`` configuration.

    ``rod`` is the 1D companion (rod's E, G = the 3D law's small-strain limit): the spatial rod
    with ``[model] kinematics = "spatial"`` (any tip force and tendon routing), else the planar
    rod, None when the load leaves the x-y plane; ``rod_note`` says why it is None (a tip force
    with a z component, a tendon routed out of the plane). ``branch_owner[i]`` is the
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
    modes: dict | None = None  # [modes]: {"count", "about", "rho"} (`parse_solid_modes`)
    obstacles: tuple = ()  # [[obstacles]] in 3D coordinates (`fe_beam.fem.solid.contact`)
    contact: object = None  # their ContactSettings ([contact]), None without obstacles

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


def solid_law(raw: dict, solid: dict | None = None) -> HyperelasticLaw:
    """The 3D law of ``[solid]`` (`fe_beam.config.material_laws.hyperelastic_law`)."""
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


def spatial_rod(raw: dict) -> bool:
    """The configuration asks for the spatial rod (``[model] kinematics = "spatial"``)."""
    model = raw.get("model")
    return isinstance(model, dict) and model.get("kinematics") == "spatial"


def planar_obstacles(obstacles, width: float) -> list[dict]:
    """The [[obstacles]] tables of the planar rod from the solid's 3D obstacles: their sections
    by the plane z = 0, for obstacles that are the same in every plane z = const across the
    finger (|z| <= ``width`` / 2): a plane whose normal has no z component, a cylinder along z
    (infinite, or spanning the width), a box spanning the width. ConfigError for any other (a
    sphere, a tilted plane or cylinder, a narrower box), naming it."""
    half = width / 2
    tables = []
    for o in obstacles:
        entry = None
        if o.shape == "plane" and abs(o.normal[2]) < 1e-12:
            entry = {"point": list(o.point[:2]), "normal": list(o.normal[:2])}
        elif o.shape == "cylinder" and max(abs(o.axis[0]), abs(o.axis[1])) < 1e-12 and (
                o.length is None
                or (o.point[2] - o.length / 2 <= -half and o.point[2] + o.length / 2 >= half)):
            entry = {"point": list(o.point[:2]), "radius": o.radius}
        elif o.shape == "box" and o.min[2] <= -half and o.max[2] >= half:
            entry = {"min": list(o.min[:2]), "max": list(o.max[:2])}
        if entry is None:
            raise ConfigError(
                f"{o.where} the planar rod reads only obstacles that are the same in every "
                f"plane z = const across the finger (|z| <= {half:g} m: a plane whose normal "
                "has no z component, a cylinder along z, a box spanning the width), which a "
                f"{o.shape} placed so is not; set [model] kinematics = \"spatial\" to compare "
                "with the spatial rod")
        tables.append({"shape": o.shape, "name": o.name} | entry)
    return tables


def _rod_static(raw: dict, law: HyperelasticLaw, section, tip_force) -> StaticConfig:
    """The rod's StaticConfig: the same tables, E and G from the 3D law's small-strain limit
    (the spatial rod, ``[model] kinematics = "spatial"``, takes the tip force's z component)."""
    rod = {k: copy.deepcopy(v) for k, v in raw.items() if k not in SOLID_ONLY_TABLES}
    rho = table(raw, "material", MATERIAL_KEYS)["rho"]
    rod["material"] = {"E": law.young_modulus, "G": law.shear_modulus, "rho": rho}
    b, h, h_tip = section
    rod["section"] = {"shape": "rectangle", "b": b, "h": h, "h_tip": h_tip}
    force = list(tip_force) if spatial_rod(raw) else [tip_force[0], tip_force[1]]
    rod["loads"] = dict(rod.get("loads", {})) | {"tip_force": force}
    if "tendons" in rod:  # a tendon out of the x-y plane: parsed, the rod is left out below
        static, _ = parse_finger(rod, planar_check=False)
        return static
    return parse_static(rod)


#: a routed tendon's polyline stays within this fraction of the tendon's element size of the
#: routing's curve (`TendonPath.from_routing`); the cable then lies on the mesh edges along it
ROUTING_TOLERANCE = 0.01


def _cables(static: StaticConfig, width: float, element: float):
    """3D cable paths, loads, owners and names from the rod's parsed tendons (``element``: the
    element size near tendons)."""
    paths, loads, owners, names = [], [], [], []
    for index, tendon in enumerate(static.tendons):
        if tendon.routing is not None:
            paths.append(_wrap(TendonPath.from_routing, tendon.offsets, tendon.entry,
                               tendon.anchor, ROUTING_TOLERANCE * element, name=tendon.name))
            loads.append(TendonLoad(pull_in=float(tendon.pull_in))
                         if tendon.controlled_by_pull_in
                         else TendonLoad(tension=float(tendon.tension)))
            owners.append(index)
            names.append(tendon.name)
            continue
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


def parse_solid(raw: dict, planar_contact_rod: bool = False) -> SolidConfig:
    """Validate a configuration for ``fe-beam solid`` (raises ConfigError naming the key).

    ``planar_contact_rod`` (``fe-beam compare``): with [[obstacles]] and the planar rod, the rod
    runs against the obstacles' sections by the plane z = 0 (`planar_obstacles`: each must be
    the same in every plane z = const across the finger, else ConfigError); without it the
    planar rod is left out in contact (``rod_note`` says why)."""
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
    obstacles, contact = parse_contact(raw, None, solid=True)
    if obstacles and "modes" in raw:
        raise ConfigError("[modes] with [[obstacles]]: the 3D modal analysis about a state in "
                          "contact is not available yet; remove [modes] or the obstacles")

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
    # the planar rod's obstacles take 2D coordinates: with 3D ones only the spatial rod runs
    # beside the solid in contact
    planar_contact = bool(obstacles) and not spatial_rod(raw)
    rod_raw = ({k: v for k, v in raw.items() if k not in ("obstacles", "contact")}
               if planar_contact else raw)
    if planar_contact and planar_contact_rod:
        rod_raw = dict(raw) | {"obstacles": planar_obstacles(obstacles, b)}
        planar_contact = False
    tube_note = ""
    try:
        rod = _rod_static(rod_raw, law, section, tip_force)
    except ConfigError as error:
        if not (obstacles and "undeformed rod" in str(error)):
            raise
        # the rod's section (its true shape, the solid's own trace) cuts an obstacle the
        # solid's mesh is clear of (the solid checks its nodes): the solid runs alone
        tube_note = f"no rod comparison: {error}"
        rod = _rod_static({k: v for k, v in raw.items() if k not in ("obstacles", "contact")},
                          law, section, tip_force)
    paths, tendon_loads, owners, names = _cables(rod, b, sizes.tendon)
    pulled = [name for name, load in zip(names, tendon_loads, strict=True)
              if load.controlled_by_pull_in]
    if pulled and solid["solver"] in ("gamg", "fieldsplit"):
        # the pull-in constraint's bordered Newton stalls with the Krylov solvers (hundreds of
        # tiny load steps, measured); "auto" takes MUMPS for it
        raise ConfigError(f"[solid] solver = \"{solid['solver']}\" does not work with pull-in "
                          f"control yet ([[tendons]] {pulled[0]!r} has pull_in): use solver = "
                          "\"auto\" or \"mumps\", or give the tendon a tension")
    try:
        geometry = FingerGeometry(length, b, h, h_tip, tendons=paths)
    except ValueError as error:
        raise ConfigError(f"[[tendons]] {error}") from None
    discretization = _wrap(Discretization, FORMULATIONS[formulation], solid["order"], q)
    settings = _wrap(
        replace, rod.solver, linear_solver=solid["solver"], petsc_options=solid["petsc_options"]
    )
    spatial = [t.name for t in rod.tendons if t.out_of_plane]
    # the spatial rod runs beside any solid; the planar one only in the x-y plane
    planar = not tube_note and (spatial_rod(raw) or (tip_force[2] == 0 and not spatial
                                                     and not planar_contact))
    if planar:
        rod_note = ""
    elif tube_note:
        rod_note = tube_note
    elif planar_contact:
        rod_note = ("no rod comparison: [[obstacles]] take 3D coordinates, which the planar rod "
                    "does not read: [model] kinematics = \"spatial\" runs the rod beside the "
                    "solid in contact")
    elif tip_force[2] != 0:
        rod_note = ("no rod comparison: the tip force has a z component, which needs [model] "
                    "kinematics = \"spatial\"")
    else:
        rod_note = (f"no rod comparison: [[tendons]] {spatial[0]!r} is routed out of the x-y "
                    "plane (offset_z), which needs [model] kinematics = \"spatial\"")
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
        rod_note=rod_note,
        raw=copy.deepcopy(raw),
        notes=tuple(notes),
        anchor=solid["anchor"],
        modes=parse_solid_modes(raw, tip_force, tendon_loads),
        obstacles=obstacles,
        contact=contact,
    )


def solid_dofs_estimate(config: SolidConfig) -> float:
    """About how many unknowns the 3D mesh will have (before gmsh meshes it): ~1.5 V / h^3
    vertices for tetrahedra of size h, 8 times as many nodes for P2, 3 components."""
    g, sizes = config.geometry, config.sizes
    volume = g.length * g.width * 0.5 * (g.height_base + (g.height_tip or g.height_base))
    h = min(sizes.size, sizes.tendon or sizes.size)
    nodes = 1.5 * volume / h**3 * (8 if config.discretization.degree >= 2 else 1)
    return 3.0 * nodes


# --- [modes]: 3D modal analysis (fe_beam.solvers.solid_modes)
# ------------------------------------------
SOLID_MODES_KEYS: dict[str, Key] = {
    "count": Key((int,), 6, "number of modes (the lowest natural frequencies)"),
    "about": Key((str,), None, "undeformed | loaded: the state the modes are about (default: "
                 "loaded when the config has a tip force or tendons, else undeformed)"),
}
MODES_ABOUT = ("undeformed", "loaded")


def parse_solid_modes(raw: dict, tip_force, tendon_loads) -> dict | None:
    """The ``[modes]`` table of a solid configuration ({"count", "about", "rho"}; None without
    the table); ConfigError naming the key for a mistake."""
    if "modes" not in raw:
        return None
    modes = table(raw, "modes", SOLID_MODES_KEYS)
    if modes["count"] < 1:
        raise ConfigError(f"[modes] count must be an integer >= 1; got {modes['count']!r}")
    loaded = any(tip_force) or any(t.tension or t.pull_in for t in tendon_loads)
    about = modes["about"] or ("loaded" if loaded else "undeformed")
    if about not in MODES_ABOUT:
        raise ConfigError(f"[modes] about must be one of {', '.join(MODES_ABOUT)}; "
                          f"got {about!r}")
    rho = table(raw, "material", MATERIAL_KEYS)["rho"]
    if not rho > 0:
        raise ConfigError("[material] rho must be > 0 for [modes] (the mass of the modal "
                          f"analysis); got {rho!r}")
    return {"count": int(modes["count"]), "about": about, "rho": float(rho)}

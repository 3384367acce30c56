"""The planar beam as a finite-element problem: mixed (u, v, theta [, multipliers]) space,
supports, loads and the residual of the total potential, all forms compiled once.

Locking: the energy and the constraint terms are integrated with p Gauss points per element
(uniformly reduced integration: exact for the bending term, which is polynomial of degree 2p - 2
in x on a straight element, and locking-free for the membrane and shear terms); loads use a full
rule. Multipliers (axial force for `inextensible`, shear force for `unshearable`) live in
discontinuous Lagrange of degree p - 1, which enforces the constraints at the Gauss points.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from fe_beam.fem import compat
from fe_beam.fem.kinematics import (
    NonStandard,
    Stiffness,
    axis_tangent,
    closed_form_law,
    constrained_strains,
    section_resultants,
    strains,
    strains_from_angles,
    strains_from_gradient,
)
from fe_beam.fem.mpi import assemble_scalar, global_sum
from fe_beam.fem.section_laws import (
    RESOLVED_STRETCHES,
    FibreLaw,
    HyperelasticSectionLaw,
    section_rule,
)
from fe_beam.fem.structure import ChainGeometry, chain_vertices
from fe_beam.model.beam import (  # noqa: F401  (the model's home; re-exported)
    COMPONENTS,
    SUPPORT_KINDS,
    BeamModel,
    Discretisation,
    Loads,
    ModelOptions,
    Supports,
    support_components,
)

__all__ = [
    "BeamModel",
    "BeamProblem",
    "Discretisation",
    "Loads",
    "ModelOptions",
    "StrainRange",
    "StrainWatch",
    "Supports",
]

# points are located within this fraction of the smallest element (global)
POINT_FRACTION = 1e-3


def smallest_cell_size(msh) -> float:
    """The smallest element length of an interval mesh, over all ranks."""
    x = compat.cell_vertex_x(msh)
    local = float(np.min(np.abs(x[:, 1] - x[:, 0]))) if len(x) else np.inf
    return msh.comm.allreduce(local, op=MPI.MIN)


# --- admissibility and the range the model is meant for -----------------------------------------
EPS_WARNING = 0.1  # |eps| beyond this: far outside the small-strain range of the laws
GAMMA_WARNING = 0.1  # rad: |gamma| beyond this: shear far outside the range
BENDING_FRACTION = 0.8  # warn beyond this fraction of the non-standard law's limit curvature


@dataclass(frozen=True)
class StrainRange:
    """Extremes of the strains of one state over all Gauss points of the energy rule.

    ``min_stretch`` = min (1 + e) = min lambda cos(gamma): <= 0 means the axis is folded onto
    itself or turned inside out somewhere: not a state of a real beam (inadmissible).
    ``max_abs_eps``, ``max_abs_gamma``: the largest |eps| and |gamma| (rad).
    ``min_bending_tangent`` (non-standard law without the inextensible constraint, else None):
    the smallest condensed bending tangent K_red / EI, with

        K_red = W_kk - W_ke^2 / W_ee     (W(eps, kappa) at g = 0, the axial strain condensed)
        W = 1/2 EA eps^2 + 1/2 EI kappa^2 (1 + 3 eps) + 1/2 E I3 kappa^3 lambda + 1/8 E I4 kappa^4

    (docs/theory.md, Non-standard energy; (1 + e)^2 = 1 + 2 eps at g = 0). For I3 = 0 and
    no axial force, minimising W over eps gives eps = -3/2 (I/A) kappa^2 and

        M(kappa) = EI kappa (1 - c kappa^2),   c = (9 I^2 / A - I4) / (2 I),

    (rectangle b x h: c = 0.3 h^2), whose maximum, the largest moment the section can carry, is
    at kappa* = 1 / sqrt(3 c) (rectangle: 1.054 / h, M* = 2/3 EI kappa* = 0.703 EI / h). There
    K_red = dM/dkappa = EI (1 - (kappa / kappa*)^2): K_red / EI < 1 - 0.8^2 = 0.36 is exactly
    |kappa| > 0.8 kappa*. With I3 != 0 or an axial force the same test measures how much bending
    stiffness is left before the limit point (K_red = 0), where there is no equilibrium beyond.

    Laws that integrate a fibre energy over the section profile (``law = "hyperelastic"``, else
    None): ``min_fibre_stretch`` = min (1 + e + eta kappa) over the two extreme fibres of the
    section (<= 0: a fibre folded onto itself, inadmissible like 1 + e <= 0: the fibre energy, a
    function of the stretch squared, cannot see it); ``min_fibre_strain``, ``max_fibre_strain``:
    the extreme fibres' Green strains E11; ``min_fibre_tangent``: the smallest d2w/dE11^2 / E of
    the fibre law over the reached E11 range (<= 0: the fibre law is not convex there, e.g.
    a Mooney-Rivlin fit with C01 < 0 used beyond its range).
    """

    min_stretch: float
    max_abs_eps: float
    max_abs_gamma: float
    min_bending_tangent: float | None = None
    min_fibre_stretch: float | None = None
    min_fibre_strain: float | None = None
    max_fibre_strain: float | None = None
    min_fibre_tangent: float | None = None
    #: the fibre law uses fixed Newton steps (split laws): its stretch range is limited
    fibre_newton: bool = False

    def inadmissible(self) -> str | None:
        """Why the state is not admissible, or None."""
        if not self.min_stretch > 0:
            return (f"inadmissible state: axial stretch 1 + e = {self.min_stretch:.3g} <= 0 "
                    "(the beam would be turned inside out)")
        if self.min_fibre_stretch is not None and not self.min_fibre_stretch > 0:
            return (f"inadmissible state: the extreme fibre's axial stretch 1 + e + eta kappa = "
                    f"{self.min_fibre_stretch:.3g} <= 0 (a fibre of the section would be folded "
                    "onto itself)")
        if self.min_fibre_strain is not None and self.fibre_newton:
            low, high = RESOLVED_STRETCHES
            stretches = [math.sqrt(max(1 + 2 * e, 0.0)) if math.isfinite(e) else math.nan
                         for e in (self.min_fibre_strain, self.max_fibre_strain)]
            if not (low <= stretches[0] and stretches[1] <= high):
                return (f"state outside the range of the hyperelastic fibre law: the extreme "
                        f"fibres' stretch reaches {stretches[0]:.3g} .. {stretches[1]:.3g}, "
                        f"beyond {low:g} .. {high:g} where its Newton steps are resolved")
        return None

    def warnings(self) -> list[str]:
        """Departures from the range the model is meant for (one sentence each)."""
        notes = []
        if self.max_abs_eps > EPS_WARNING:
            notes.append(f"the axial strain reaches |eps| = {self.max_abs_eps:.3g} > "
                         f"{EPS_WARNING:g}: far outside the small-strain range the laws are "
                         "meant for")
        if self.max_abs_gamma > GAMMA_WARNING:
            notes.append(f"the shear angle reaches |gamma| = {self.max_abs_gamma:.3g} rad > "
                         f"{GAMMA_WARNING:g}: far outside the range the laws are meant for")
        limit = 1 - BENDING_FRACTION**2
        if self.min_bending_tangent is not None and self.min_bending_tangent < limit:
            notes.append("the non-standard law's bending tangent drops to "
                         f"{max(self.min_bending_tangent, 0.0):.3g} EI (< {limit:.2g} EI: the "
                         f"curvature beyond {BENDING_FRACTION:.0%} of the law's limit curvature, "
                         "or strong axial compression): near the limit point of the law, "
                         "beyond which there is no equilibrium")
        if self.min_fibre_tangent is not None and not self.min_fibre_tangent > 0:
            notes.append("the hyperelastic fibre law is not convex (d2w/dE11^2 <= 0) inside the "
                         f"reached fibre strain range E11 = {self.min_fibre_strain:.3g} .. "
                         f"{self.max_fibre_strain:.3g}: the material fit is used beyond the "
                         "range where it is stable, and the answer may not be unique")
        return notes


class StrainWatch:
    """The extremes of `StrainRange` over all accepted states of a run, and their notes."""

    def __init__(self):
        self.worst: StrainRange | None = None

    def observe(self, value: StrainRange) -> None:
        if self.worst is None:
            self.worst = value
            return
        w = self.worst

        def extreme(name, pick):
            known = [x for x in (getattr(w, name), getattr(value, name)) if x is not None]
            return pick(known) if known else None

        self.worst = StrainRange(min(w.min_stretch, value.min_stretch),
                                 max(w.max_abs_eps, value.max_abs_eps),
                                 max(w.max_abs_gamma, value.max_abs_gamma),
                                 extreme("min_bending_tangent", min),
                                 extreme("min_fibre_stretch", min),
                                 extreme("min_fibre_strain", min),
                                 extreme("max_fibre_strain", max),
                                 extreme("min_fibre_tangent", min),
                                 w.fibre_newton or value.fibre_newton)

    def notes(self) -> list[str]:
        return self.worst.warnings() if self.worst is not None else []

    def summary(self) -> dict | None:
        """The extremes as a dict (the fibre keys only for laws that integrate a profile)."""
        if self.worst is None:
            return None
        data = dataclasses.asdict(self.worst)
        data.pop("fibre_newton")
        fibre = ("min_fibre_stretch", "min_fibre_strain", "max_fibre_strain", "min_fibre_tangent")
        return {k: v for k, v in data.items() if k not in fibre or v is not None}


def interval_mesh(comm: MPI.Comm, elements: int, length: float, breakpoints=(), vertices=None,
                  fixed=(), gaps=()):
    """Uniform mesh of [0, L] in which every breakpoint is a vertex (the nearest uniform vertex
    moves onto it when closer than a quarter element, otherwise a vertex is inserted).

    A breakpoint within 1e-9 of an element of a vertex that cannot move (an end, or another
    breakpoint) is that vertex: inserting it would create an element of round-off size.

    ``vertices``: the starting vertices instead of the uniform ones (a chain of rods), of which
    ``fixed`` (the joints) never move; no cell inside the ``gaps`` (the pieces of a
    structure)."""
    interior = sorted({float(x) for x in breakpoints if 0 < x < length})
    if not interior and vertices is None:
        return compat.create_interval(comm, elements, length)
    if vertices is None:
        vertices = np.linspace(0.0, length, elements + 1)
        spacing = length / elements
    else:
        vertices = np.array(vertices, dtype=float)
        spacing = float(np.min(np.diff(vertices)))
    placed: set[float] = {float(x) for x in fixed}
    for x in interior:
        nearest = int(np.argmin(np.abs(vertices - x)))
        movable = 0 < nearest < len(vertices) - 1 and vertices[nearest] not in placed
        if abs(vertices[nearest] - x) < spacing / 4 and movable:
            vertices[nearest] = x
            placed.add(x)
        elif abs(vertices[nearest] - x) <= 1e-9 * spacing:
            continue
        else:
            vertices = np.sort(np.append(vertices, x))
            placed.add(x)
    return compat.create_interval_from_vertices(comm, vertices, gaps)


class BeamProblem:
    """Finite-element set-up of a `BeamModel`: space, unknown, Dirichlet conditions, forms.

    The load factor and all material/section numbers are fem.Constant: load steps and parameter
    changes never recompile forms.
    """

    #: the unknowns' names, in the mixed space's order (before the multipliers)
    components = COMPONENTS
    spatial = False
    #: the reference geometry of a chain of rods (`fe_beam.fem.structure.ChainGeometry`)
    chain = None
    #: (key, component) of `end_reaction`
    reaction_keys = (("Fx", "u"), ("Fy", "v"), ("M", "theta"))

    def __init__(
        self,
        model: BeamModel,
        comm: MPI.Comm = MPI.COMM_WORLD,
        breakpoints: tuple[float, ...] = (),
        extra_energy=None,
        extra_work=None,
    ):
        """``breakpoints``: interior x that must be mesh vertices (tendon entries, anchors,
        kinks of tendon paths); ``extra_energy(problem, (u, v, theta))`` returns a UFL form
        added to the stored energy (e.g. tendons); ``extra_work(problem, (u, v, theta),
        test)`` the virtual work of non-potential forces on the rod (e.g. slipping friction),
        subtracted from the residual."""
        self.model = model
        # every point force and moment sits on a mesh vertex (its work is a vertex integral)
        breakpoints = tuple(breakpoints) + tuple(
            f[0] for f in model.loads.point_forces + model.loads.point_moments)
        structure = getattr(model, "structure", None)
        if structure is None:
            self.mesh = interval_mesh(comm, model.mesh.elements, model.length, breakpoints)
        else:  # a chain of rods: each rod's elements, the joints fixed vertices
            vertices, joints = chain_vertices(structure)
            gaps = tuple((a[1], b[0]) for a, b in zip(structure.pieces, structure.pieces[1:]))
            self.mesh = interval_mesh(comm, model.mesh.elements, model.length,
                                      breakpoints + joints, vertices=vertices, fixed=joints,
                                      gaps=gaps)
        self.comm = comm
        degree = model.mesh.degree
        self.multipliers = self._constrained_strains()
        elements = [compat.element(self.mesh, "Lagrange", degree)] * len(self.components)
        elements += [compat.element(self.mesh, "DG", degree - 1)] * len(self.multipliers)
        self.space = compat.function_space(self.mesh, compat.mixed_element(elements))
        self.w = fem.Function(self.space, name="state")
        self.load_factor = fem.Constant(self.mesh, 0.0)
        self.dx_energy = ufl.dx(metadata={"quadrature_degree": 2 * degree - 1})
        self.dx_loads = ufl.dx(metadata={"quadrature_degree": 2 * degree + 2})
        self.chain = None if structure is None else ChainGeometry(self)
        self._make_constants()
        self._mark_ends()
        self._check_breakpoints(breakpoints)
        self._point_force_measures()
        self.bcs, self._prescribed = self._dirichlet_conditions()
        self.bcs += self._inner_supports()
        self.extra_energy = extra_energy
        self.extra_work = extra_work
        self.residual = self._residual()

    # --- set-up pipeline -------------------------------------------------------------------
    def _constrained_strains(self) -> tuple:
        """The strains the constraint holds at zero (a multiplier field each)."""
        return constrained_strains(self.model.options.constraint)

    def _material_constants(self):
        """E, G, rho, the shear correction and the section's dimensions as fem.Constant (the
        sensitivities differentiate the forms by them); returns (dims, dims_tip, x)."""
        m, sec = self.model, self.model.section
        const = lambda value: fem.Constant(self.mesh, float(value))  # noqa: E731
        self.E = const(m.material.E)
        self.G = const(m.material.shear_modulus)
        self.rho = const(m.material.rho)
        self.k_shear = const(m.options.shear_correction)
        dims = {n: const(v) for n, v in sec.dims.items()}
        dims_tip = {n: const(v) for n, v in sec.dims_tip.items()}
        self.section_dims, self.section_dims_tip = dims, dims_tip
        return dims, dims_tip, ufl.SpatialCoordinate(self.mesh)[0]

    def _make_constants(self) -> None:
        m, sec = self.model, self.model.section
        const = lambda value: fem.Constant(self.mesh, float(value))  # noqa: E731
        dims, dims_tip, x = self._material_constants()
        E, G = self.E, self.G
        if self.chain is not None:  # rods with their own sections or materials: DG0 fields
            dims = self.chain.section_dims() or dims
            E, G = self.chain.moduli() or (E, G)
        self.section_props = sec.properties(x / m.length, dims, dims_tip)
        p = self.section_props
        self.stiffness = Stiffness(
            EA=E * p.A,
            GA=G * p.A,
            EI=E * p.I,
            EI3=E * p.I3,
            EI4=E * p.I4,
            shear_correction=self.k_shear,
        )
        self.law = self._make_law(x / m.length, dims, dims_tip)
        self.tip_force = fem.Constant(self.mesh, np.array(m.loads.tip_force, dtype=float))
        self.tip_moment = const(m.loads.tip_moment)
        self.distributed = fem.Constant(self.mesh, np.array(m.loads.distributed, dtype=float))
        self.gravity = fem.Constant(self.mesh, np.array(m.loads.gravity, dtype=float))

    def _make_law(self, s, dims: dict, dims_tip: dict):
        """The constitutive law object: ``energy(strains)`` and ``fibre_stretches(strains)``."""
        options = self.model.options
        if options.law != "hyperelastic":
            return closed_form_law(options.law, self.stiffness)
        fibre = FibreLaw.from_solid(options.hyperelastic)
        constants = {name: fem.Constant(self.mesh, float(value))
                     for name, value in fibre.coefficients.items() if np.isfinite(value)}
        rule = section_rule(self.model.section, options.points, s, dims, dims_tip)
        return HyperelasticSectionLaw(fibre, rule, self.G * self.section_props.A,
                                      self.stiffness, constants)

    def law_energy(self, s):
        """The law's energy density (per unit reference length) of the strains ``s``."""
        return self.law.energy(s)

    def _mark_ends(self) -> None:
        """End markers, the tip measure, and the tolerance every point is located with.

        A point is "at x" when its coordinate is within ``point_tolerance`` = POINT_FRACTION of
        the smallest element (global over the ranks): never more than one vertex or dof of a
        Lagrange space can match, whatever the mesh size or the length (a tolerance relative
        to the length matched several nodes from ~50k elements, and their values were summed).
        """
        length = self.model.length
        self.h_min = smallest_cell_size(self.mesh)
        self.point_tolerance = POINT_FRACTION * self.h_min
        self.end_x = {"x0": 0.0, "xL": float(length)}
        self.end_markers = {end: self.point_marker(x) for end, x in self.end_x.items()}
        tip = compat.locate_entities_boundary(self.mesh, 0, self.end_markers["xL"])
        start = compat.locate_entities_boundary(self.mesh, 0, self.end_markers["x0"])
        structure = getattr(self.model, "structure", None)
        inner = [compat.locate_entities_boundary(self.mesh, 0, self.point_marker(s))
                 for s in (structure.piece_ends() if structure is not None else ())]
        inner = np.unique(np.concatenate(inner)).astype(np.int32) if inner else \
            np.zeros(0, dtype=np.int32)
        order = np.argsort(np.concatenate([start, tip, inner]))
        tags = compat.meshtags(self.mesh, 0, np.concatenate([start, tip, inner])[order],
                               np.concatenate([np.full(len(start), 1), np.full(len(tip), 2),
                                               np.full(len(inner), 3)])[order])
        ends = ufl.Measure("ds", domain=self.mesh, subdomain_data=tags)
        self.ds_tip, self.ds_start = ends(2), ends(1)
        if inner is not None and structure is not None and structure.piece_ends():
            self.ds_pieces = ends(3)
        one = fem.Constant(self.mesh, 1.0)
        measure = global_sum(self.comm, fem.assemble_scalar(fem.form(one * self.ds_tip)))
        if measure != 1.0:
            raise RuntimeError(
                f"the tip x = {length!r} was found on {measure:g} boundary points instead of one"
            )

    def _check_breakpoints(self, breakpoints) -> None:
        """Every interior breakpoint (tendon entry, anchor, kink) is exactly one mesh vertex."""
        owned = self.mesh.topology.index_map(0).size_local
        for x in sorted({float(b) for b in breakpoints if 0 < b < self.model.length}):
            vertices = compat.locate_entities(self.mesh, 0, self.point_marker(x))
            found = int(global_sum(self.comm, np.count_nonzero(vertices < owned)))
            if found != 1:
                raise RuntimeError(f"breakpoint x = {x!r} is {found} mesh vertices instead of "
                                   "exactly one")

    def _point_force_measures(self) -> None:
        """The point forces' and point moments' (measure, nodal field, at an end) lists
        (`_point_measures`)."""
        loads = self.model.loads
        # one interior-vertex measure for the forces and the moments: UFL refuses a form whose
        # integrals of one type have different subdomain data (a point force and a point moment
        # inside the rod); the nodal fields vanish at the other kind's vertices
        interior = [compat.locate_entities(self.mesh, 0, self.point_marker(row[0]))
                    for row in loads.point_forces + loads.point_moments
                    if not self._at_end(row[0])]
        self._interior_measure = None
        if interior:
            self.mesh.topology.create_connectivity(0, 1)
            vertices = np.unique(np.concatenate(interior)).astype(np.int32)
            tags = compat.meshtags(self.mesh, 0, vertices, np.ones(len(vertices), np.int32))
            self._interior_measure = ufl.Measure("dS", domain=self.mesh, subdomain_data=tags)(1)
        self.point_forces, self.point_force_fields = self._point_measures(loads.point_forces)
        self.point_moments, self.point_moment_fields = self._point_measures(loads.point_moments)

    def _at_end(self, x: float) -> bool:
        """x is within round-off of x = 0 or x = L or a structure's piece end (a boundary
        vertex)."""
        return (abs(x - self.model.length) <= self.point_tolerance
                or abs(x) <= self.point_tolerance or self._at_piece_end(x))

    def _at_piece_end(self, x: float) -> bool:
        structure = getattr(self.model, "structure", None)
        ends = structure.piece_ends() if structure is not None else ()
        return any(abs(x - s) <= self.point_tolerance for s in ends)

    def _point_measures(self, rows) -> tuple[list, list]:
        """(measure, nodal value field, at an end) per kind of vertex carrying the point loads
        ``rows`` ((x, components...), ...): interior vertices (interior facets of the interval
        mesh), x = L and x = 0 (boundary facets); and the nodal fields (one per component).

        One nodal (P1) field per component for all the rows: its vertex values are the loads,
        so the work is one vertex integral per kind of vertex however many loads there are (a
        Constant and an integral each took ~2 min for 1000 forces). An interior facet is
        integrated by its owning rank only: a load at a vertex between two ranks counts once."""
        if not rows:
            return [], []
        space = compat.function_space(self.mesh, compat.element(self.mesh, "Lagrange", 1))
        nodal = [fem.Function(space) for _ in rows[0][1:]]  # a field per component
        interior, at = False, set()
        for x, *values in rows:
            dofs = compat.locate_dofs_geometrical(space, self.point_marker(x))
            for function, value in zip(nodal, values, strict=True):
                function.x.array[dofs] += value
            if abs(x - self.model.length) <= self.point_tolerance:
                at.add("tip")
            elif abs(x) <= self.point_tolerance:
                # within round-off of x = 0: the end vertex (interval_mesh inserts no round-off
                # element), a boundary facet, which an interior-facet measure never visits
                at.add("start")
            elif self._at_piece_end(x):  # a boundary vertex inside a structure's mesh
                at.add("pieces")
            else:
                interior = True
        field = ufl.as_vector(nodal)
        measures = []
        if interior:  # the vertices of every interior point load (`_point_force_measures`)
            measures.append((self._interior_measure, field, False))
        for name, measure in (("tip", self.ds_tip), ("start", self.ds_start),
                              ("pieces", getattr(self, "ds_pieces", None))):
            if name in at:
                measures.append((measure, field, True))
        return measures, nodal

    @staticmethod
    def point_work(measures, density):
        """sum over ``measures`` ((measure, field, at an end), ...) of ``density(field)`` at
        the points (the interior vertices' value is continuous: avg is the value)."""
        work = 0
        for measure, field, at_end in measures:
            value = density(field)
            work += (value if at_end else ufl.avg(value)) * measure
        return work

    def point_force_work(self, parts):
        """Work of the point forces (at load factor 1) on the state ``parts``."""
        displacement = ufl.as_vector([parts[0], parts[1]])
        return self.point_work(self.point_forces, lambda force: ufl.dot(force, displacement))

    def point_moment_work(self, parts):
        """Work of the planar point moments (at load factor 1): M theta at each point."""
        theta = parts[2]
        return self.point_work(self.point_moments, lambda moment: moment[0] * theta)

    def point_marker(self, x: float):
        """Marker (for locate_dofs_geometrical / locate_entities) of the point x."""
        tol = self.point_tolerance
        return lambda points: np.abs(points[0] - x) <= tol

    def point_dofs(self, name: str, x: float, what: str = "point") -> np.ndarray:
        """Owned local dofs (in w) of component ``name`` at the mesh point x: exactly one dof
        over all ranks (RuntimeError otherwise: x is not a vertex, or is found twice)."""
        index = self.components.index(name)
        sub, parent_dofs = compat.sub_space_collapsed(self.space, index)
        collapsed = compat.locate_dofs_geometrical(sub, self.point_marker(x))
        dofs = np.asarray(parent_dofs)[collapsed]
        owned = self.space.dofmap.index_map.size_local * self.space.dofmap.index_map_bs
        dofs = dofs[dofs < owned]
        found = int(global_sum(self.comm, len(dofs)))
        if found != 1:
            raise RuntimeError(
                f"{what} x = {x!r}: {name} found at {found} mesh nodes instead of exactly one"
            )
        return dofs

    def _dirichlet_conditions(self):
        bcs, prescribed = [], []
        for end in ("x0", "xL"):
            values = getattr(self.model.supports, f"prescribed_{end}")
            for name in self.model.supports.fixed(end):
                index = self.components.index(name)
                sub, _ = compat.sub_space_collapsed(self.space, index)
                dofs = compat.locate_dofs_geometrical(
                    (self.space.sub(index), sub), self.end_markers[end]
                )
                self.point_dofs(name, self.end_x[end], f"support {end} at")  # exactly one
                value = fem.Function(sub)
                bcs.append(fem.dirichletbc(value, dofs, self.space.sub(index)))
                if values.get(name, 0.0) != 0.0:
                    prescribed.append((value, float(values[name])))
        return bcs, prescribed

    def _inner_supports(self) -> list:
        """Zero Dirichlet conditions at a structure's supported rod ends inside the mesh (a
        piece's end, a shared vertex: `fe_beam.model.structure.Structure.extra_supports`)."""
        structure = getattr(self.model, "structure", None)
        bcs = []
        for s, components, end in getattr(structure, "extra_supports", ()):
            for name in components:
                index = self.components.index(name)
                sub, _ = compat.sub_space_collapsed(self.space, index)
                dofs = compat.locate_dofs_geometrical((self.space.sub(index), sub),
                                                      self.point_marker(s))
                self.point_dofs(name, s, f"support of {end} at")  # exactly one
                bcs.append(fem.dirichletbc(fem.Function(sub), dofs, self.space.sub(index)))
        return bcs

    def inner_reactions(self) -> list:
        """((s, {component: reaction}), ...) at the supported rod ends inside the mesh: the
        residual at their held dofs (the support's force and moment on the rod end;
        collective)."""
        structure = getattr(self.model, "structure", None)
        supports = getattr(structure, "extra_supports", ())
        if not supports:
            return []
        values = self.raw_residual()
        result = []
        for s, components, _ in supports:
            result.append((s, {name: float(global_sum(self.comm, values[
                self.point_dofs(name, s)].sum())) for name in components}))
        return result

    def raw_residual(self) -> np.ndarray:
        """The local array (owned + ghost, summed) of the residual of the current state without
        Dirichlet conditions and ties."""
        if not hasattr(self, "_residual_form"):
            self._residual_form = fem.form(self.residual)
        from petsc4py import PETSc

        vector = compat.assemble_vector(self._residual_form)
        vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        values = vector.getArray(readonly=True).copy()
        vector.destroy()
        return values

    # --- physics -----------------------------------------------------------------------------
    def fields(self):
        """(u, v, theta, multiplier dict) of the current state (UFL)."""
        parts = ufl.split(self.w)
        return parts[0], parts[1], parts[2], dict(zip(self.multipliers, parts[3:], strict=True))

    def strains(self, u, v, theta):
        """The generalised strains of (u, v, theta): the single rod's, or along a chain of rods
        those of the tangent in each rod's reference frame (`fe_beam.fem.structure`)."""
        if self.chain is None:
            return strains(u, v, theta)
        return strains_from_gradient(self.chain.local_displacement_tangent(u, v), theta,
                                     theta.dx(0))

    def reference_point(self, x: float) -> tuple[float, float]:
        """The reference position (X, Y) of the axis point x (the chain's, or (x, 0))."""
        if self.chain is None:
            return float(x), 0.0
        return self.model.structure.reference_point(x)

    def energy_density(self, s):
        """Stored energy per unit reference length of the rod law at the strains ``s`` (a
        `fe_beam.fem.kinematics.Strains`): the one entry point for schemes that need W(strains)."""
        return self.law_energy(s)

    def stored_energy(self, parts):
        """int W dx (+ extra energy such as tendons) of the state ``parts`` = (u, v, theta)."""
        u, v, theta = parts
        total = self.law_energy(self.strains(u, v, theta)) * self.dx_energy
        if self.extra_energy is not None:
            total += self.extra_energy(self, parts)
        return total

    def dead_load_work(self, parts):
        """Work of the dead loads at the current load factor on the state ``parts``."""
        u, v, theta = parts
        lam = self.load_factor
        body = self.distributed + self.rho * self.section_props.A * self.gravity
        work = lam * ufl.dot(body, ufl.as_vector([u, v])) * self.dx_loads
        work += lam * self.tip_moment * theta * self.ds_tip
        if not self.model.loads.follower:
            work += lam * ufl.dot(self.tip_force, ufl.as_vector([u, v])) * self.ds_tip
        if self.point_forces:
            work += lam * self.point_force_work(parts)
        if self.point_moments:
            work += lam * self.point_moment_work(parts)
        return work

    def constraint_term(self, parts, multipliers):
        """int sum_c multiplier_c * strain_c dx (zero without constraints)."""
        if not multipliers:
            return 0  # UFL forms absorb an integer zero; a Zero integrand would have no domain
        s = self.strains(*parts)
        return sum(value * getattr(s, n) for n, value in multipliers.items()) * self.dx_energy

    def follower_virtual_work(self, parts, test):
        """Virtual work of a follower tip force (not derivable from a potential)."""
        theta = parts[2]
        u_t, v_t = ufl.split(test)[0], ufl.split(test)[1]
        a1 = ufl.as_vector([ufl.cos(theta), ufl.sin(theta)])
        d = ufl.as_vector([-ufl.sin(theta), ufl.cos(theta)])
        force = self.tip_force[0] * a1 + self.tip_force[1] * d
        return self.load_factor * ufl.dot(force, ufl.as_vector([u_t, v_t])) * self.ds_tip

    def potential(self):
        """Total potential of the conservative terms: int W + constraints - dead-load work."""
        u, v, theta, multipliers = self.fields()
        parts = (u, v, theta)
        return (
            self.stored_energy(parts)
            + self.constraint_term(parts, multipliers)
            - self.dead_load_work(parts)
        )

    def _residual(self):
        test = ufl.TestFunction(self.space)
        residual = ufl.derivative(self.potential(), self.w, test)
        if self.model.loads.follower:
            residual -= self.follower_virtual_work(self.fields()[:3], test)
        if self.extra_work is not None:
            residual -= self.extra_work(self, self.fields()[:3], test)
        return residual

    @property
    def conservative(self) -> bool:
        """The forces derive from a potential (a symmetric tangent): no follower force, no
        non-potential extra work (slipping friction)."""
        return not (self.model.loads.follower or self.extra_work is not None)

    def set_load_factor(self, value: float) -> None:
        """Scale every load and every prescribed end value by ``value``."""
        self.load_factor.value = value
        self.set_prescribed_factor(value)

    def set_prescribed_factor(self, value: float) -> None:
        """Scale the prescribed end values only (dynamics drives them by their own function)."""
        for function, target in self._prescribed:
            function.x.array[:] = value * target

    @property
    def saddle_point(self) -> bool:
        """Multiplier rows have a zero diagonal: the linear systems need a pivoting solver."""
        return bool(self.multipliers)

    @property
    def global_dofs(self) -> int:
        return self.space.dofmap.index_map.size_global * self.space.dofmap.index_map_bs

    def multiplier_dofs(self) -> np.ndarray:
        """Local dofs (in w, ghosts included) of all multiplier fields."""
        parts = [np.asarray(compat.sub_space_collapsed(self.space, 3 + i)[1])
                 for i in range(len(self.multipliers))]
        return np.concatenate(parts) if parts else np.empty(0, dtype=np.int32)

    # --- quantities of interest ----------------------------------------------------------------
    def component_dofs(self, name: str, end: str | None = None) -> np.ndarray:
        """Owned local dofs (in w) of a component, optionally only the one at an end (on
        exactly one rank; see `point_dofs`)."""
        if end is not None:
            return self.point_dofs(name, self.end_x[end], f"end {end} at")
        index = self.components.index(name)
        _, parent_dofs = compat.sub_space_collapsed(self.space, index)
        parent_dofs = np.asarray(parent_dofs)
        owned = self.space.dofmap.index_map.size_local * self.space.dofmap.index_map_bs
        return parent_dofs[parent_dofs < owned]

    def end_values(self, end: str = "xL") -> dict:
        """{u, v, theta} at an end (MPI-safe: each value is owned by exactly one rank)."""
        if not hasattr(self, "_end_dofs"):
            self._end_dofs = {}
        if end not in self._end_dofs:
            self._end_dofs[end] = {n: self.component_dofs(n, end) for n in self.components}
        return self._values_at(self._end_dofs[end])

    def point_values(self, x: float) -> dict:
        """{u, v, theta} at a mesh vertex x (exactly one owner; RuntimeError if x is not a
        vertex)."""
        return self._values_at({n: self.point_dofs(n, x) for n in self.components})

    def end_reaction(self, end: str = "xL") -> dict:
        """The support's force and moment on the beam at an end, {Fx, Fy, M} (global axes;
        0 on free components): the residual of the current state at the end's dofs. Spatial
        rods: {Fx, Fy, Fz, M_theta_x, M_theta_y, M_theta_z}, the rotation rows the
        work-conjugates of the rotation vector."""
        if not hasattr(self, "_residual_form"):
            self._residual_form = fem.form(self.residual)
        from petsc4py import PETSc

        vector = compat.assemble_vector(self._residual_form)
        vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        values = vector.getArray(readonly=True)
        fixed = self.model.supports.fixed(end)
        result = {}
        for key, name in self.reaction_keys:
            local = values[self.component_dofs(name, end)].sum() if name in fixed else 0.0
            result[key] = float(global_sum(self.comm, local))
        vector.destroy()
        return result

    def _values_at(self, dofs: dict) -> dict:
        values = compat.local_array(self.w)
        return {name: global_sum(self.comm, values[d].sum()) for name, d in dofs.items()}

    def output_expressions(self) -> dict:
        """UFL expressions of the strains and section resultants for output (not for solving)."""
        u, v, theta, multipliers = self.fields()
        if self.chain is None:
            tangent = ufl.variable(axis_tangent(u, v))
            local = tangent
        else:  # F = dW/dr' in world axes: W of the tangent in the rod's frame
            tangent = ufl.variable(self.chain.world_tangent(u, v))
            local = self.chain.local_tangent(tangent)
        kappa = ufl.variable(theta.dx(0))
        s = strains_from_gradient(local, theta, kappa)
        energy = self.law_energy(s)
        energy += sum((value * getattr(s, n) for n, value in multipliers.items()), ufl.zero())
        normal, shear, moment, axial = section_resultants(energy, tangent, kappa)
        plain = self.strains(u, v, theta)
        return {
            "eps": plain.eps,
            "gamma": compat.atan2(plain.g, plain.one_plus_e),
            "kappa": plain.kappa,
            "N": normal,
            "T": shear,
            "M": moment,
            "axial_force": axial,
        }

    def strain_range(self) -> StrainRange:
        """Extremes of the strains of the current state over every energy Gauss point of every
        element, reduced over all ranks (collective): see `StrainRange`."""
        if not hasattr(self, "_strain_expression"):
            self._strain_expression = self._compile_strain_expression()
        compiled, count = self._strain_expression
        cells = np.arange(self.mesh.topology.index_map(1).size_local, dtype=np.int32)
        values = compat.evaluate_expression(compiled, self.mesh, cells).reshape(-1, count)
        fibres = count > 4
        local = np.full(7 if fibres else 4, np.inf)

        def smallest(column):
            return np.min(np.where(np.isfinite(column), column, -np.inf))

        if len(values):
            with np.errstate(invalid="ignore"):
                local[0] = smallest(values[:, 0])
                local[1] = -np.max(np.abs(values[:, 1]))
                local[2] = -np.max(np.abs(values[:, 2]))
                local[3] = smallest(values[:, 3])
                if fibres:
                    local[4] = smallest(values[:, 4:6])
                    local[5] = smallest(values[:, 6:8])
                    local[6] = smallest(-values[:, 6:8])
        reduced = np.empty_like(local)
        self.comm.Allreduce(local, reduced, op=MPI.MIN)
        reduced = np.where(np.isnan(reduced), -np.inf, reduced)
        bending = None if not self._bending_limit_applies() else float(reduced[3])
        fibre = {}
        if fibres:
            low, high = float(reduced[5]), float(-reduced[6])
            fibre = {"min_fibre_stretch": float(reduced[4]), "min_fibre_strain": low,
                     "max_fibre_strain": high,
                     "min_fibre_tangent": self.law.fibre.min_tangent(low, high),
                     "fibre_newton": (self.law.fibre.material != "svk"
                                      and math.isfinite(self.law.fibre.kappa))}
        return StrainRange(float(reduced[0]), float(-reduced[1]), float(-reduced[2]), bending,
                           **fibre)

    def _bending_limit_applies(self) -> bool:
        return (self.model.options.law == "nonstandard"
                and "eps" not in constrained_strains(self.model.options.constraint))

    def _compile_strain_expression(self):
        """[1 + e, eps, gamma, K_red / EI (, the two extreme fibres' 1 + e + eta kappa, their
        two E11)] at the Gauss points of the energy rule."""
        u, v, theta, _ = self.fields()
        s = self.strains(u, v, theta)
        gamma = compat.atan2(s.g, s.one_plus_e)
        if self._bending_limit_applies():
            # the law's own energy W(eps, kappa) at gamma = 0, differentiated by UFL
            eps, kappa = ufl.variable(s.eps), ufl.variable(s.kappa)
            energy = NonStandard(self.stiffness).energy(strains_from_angles(eps, 0.0, kappa))
            w_e, w_k = ufl.diff(energy, eps), ufl.diff(energy, kappa)
            w_ee, w_ek, w_kk = ufl.diff(w_e, eps), ufl.diff(w_e, kappa), ufl.diff(w_k, kappa)
            tangent = (w_kk - w_ek**2 / w_ee) / self.stiffness.EI
        else:
            tangent = ufl.as_ufl(1.0) + 0 * s.eps
        reference, _ = self.energy_rule()
        columns = [s.one_plus_e, s.eps, gamma, tangent]
        stretches = self.law.fibre_stretches(s)
        if stretches:  # the extreme fibres' 1 + e + eta kappa and E11
            columns += stretches + [(x**2 + s.g**2 - 1) / 2 for x in stretches]
        return compat.expression(ufl.as_vector(columns), reference), len(columns)

    def energy_rule(self) -> tuple[np.ndarray, np.ndarray]:
        """The Gauss rule of the energy integrals (``dx_energy``: p Gauss-Legendre points, exact
        to degree 2p - 1) on the reference interval [0, 1]: points (p, 1), weights (p,) summing
        to 1. The solver sees the strains and section forces at these points only."""
        points, weights = np.polynomial.legendre.leggauss(self.model.mesh.degree)
        return ((points + 1) / 2).reshape(-1, 1), weights / 2

    def strain_energy_form(self) -> fem.Form:
        u, v, theta, _ = self.fields()
        return fem.form(self.law_energy(self.strains(u, v, theta)) * self.dx_energy)

    def rotation_dofs(self) -> np.ndarray:
        return self.component_dofs("theta")

    # --- inertia: what dynamics and modes need of a rod (the spatial rod has its own) ----------
    #: the motion components (before the multipliers) and the translations among them
    motion_count = 3
    translations = 2

    def motion_parts(self, pieces):
        """The state ``parts`` of the first `motion_count` scalar pieces of a mixed function."""
        return tuple(pieces[:3])

    @property
    def dx_mass(self):
        return ufl.dx(metadata={"quadrature_degree": 2 * self.model.mesh.degree + 2})

    def mass_work(self, parts, acceleration, test):
        """The inertia's virtual work linear in the acceleration (pieces): rho A on u, v, rho I
        on theta (constant: ``parts`` unused)."""
        rho_area, rho_inertia = self.rho * self.section_props.A, self.rho * self.section_props.I
        t = ufl.split(test) if not isinstance(test, (list, tuple)) else test
        return (rho_area * (acceleration[0] * t[0] + acceleration[1] * t[1])
                + rho_inertia * acceleration[2] * t[2]) * self.dx_mass

    def velocity_inertia_work(self, parts, rates, test):
        """The inertia's part quadratic in the velocities (none: the planar mass is
        constant)."""
        return None

    def kinetic_energy(self, parts, rates):
        rho_area, rho_inertia = self.rho * self.section_props.A, self.rho * self.section_props.I
        return 0.5 * (rho_area * (rates[0] ** 2 + rates[1] ** 2)
                      + rho_inertia * rates[2] ** 2) * self.dx_mass

    def momentum_densities(self, parts, rates) -> dict:
        """Linear momentum (x, y) and the angular momentum about the origin (z), per length."""
        rho_area, rho_inertia = self.rho * self.section_props.A, self.rho * self.section_props.I
        if self.chain is None:
            X, Y = ufl.SpatialCoordinate(self.mesh)[0], 0.0
        else:  # a chain of rods: its reference position
            X, Y = self.chain.reference[0], self.chain.reference[1]
        u, v, _ = parts
        return {"momentum_x": rho_area * rates[0], "momentum_y": rho_area * rates[1],
                "angular_momentum": rho_area * ((X + u) * rates[1] - (Y + v) * rates[0])
                + rho_inertia * rates[2]}

    def mass_form(self):
        """The mass bilinear form (modes)."""
        trial, test = ufl.TrialFunction(self.space), ufl.TestFunction(self.space)
        return self.mass_work(None, ufl.split(trial), test)

    @property
    def nonpotential_loads(self) -> bool:
        """Loads without a potential (a follower force): their virtual work is separate."""
        return bool(self.model.loads.follower)

    def nonconservative_work(self, parts, test):
        return self.follower_virtual_work(parts, test)

    def bending_stiffness(self):
        """EI (UFL): the scale of the bending eigenvalues (modes)."""
        return self.stiffness.EI

    def rigid_motion_candidates(self) -> list:
        """Infinitesimal rigid motions of the current state (Functions): translations
        (1, 0, 0), (0, 1, 0) and the rotation about the origin (-(Y + v), X + u, 1), (X, Y)
        the reference position (x, 0) of a rod, a chain's `reference_point`)."""
        u_space, u_dofs = compat.sub_space_collapsed(self.space, 0)
        v_space, v_dofs = compat.sub_space_collapsed(self.space, 1)
        _, theta_dofs = compat.sub_space_collapsed(self.space, 2)
        u_dofs, v_dofs, theta_dofs = (np.asarray(d) for d in (u_dofs, v_dofs, theta_dofs))
        x = v_space.tabulate_dof_coordinates()[:, 0]
        same_points = np.allclose(u_space.tabulate_dof_coordinates()[:, 0], x)
        y = np.zeros_like(x)
        if self.chain is not None:  # a chain of rods: the reference position (X, Y) of s
            where = np.array([self.reference_point(s) for s in x]).reshape(-1, 2)
            x, y = where[:, 0], where[:, 1]
        state = compat.local_array(self.w)
        candidates = []
        for k in range(3):
            function = fem.Function(self.space)
            array = compat.local_array(function)
            if k == 0:
                array[u_dofs] = 1.0
            elif k == 1:
                array[v_dofs] = 1.0
            elif same_points:  # u and v share one element: their dofs sit at the same points
                array[u_dofs] = -(y + state[v_dofs])
                array[v_dofs] = x + state[u_dofs]
                array[theta_dofs] = 1.0
            candidates.append(function)
        return candidates

    def mode_shares(self, shape) -> dict:
        """{"transverse": the share of the shape's translational energy that is transverse}:
        normal to the current state's section, A (du sin(theta) - dv cos(theta))^2, against
        along it, A (du cos(theta) + dv sin(theta))^2 (the reference axes' u, v when
        straight: a bent pre-state's bending mode moves normal to the bent axis, which in
        reference axes is along x where the rod is turned by more than 45 degrees).

        Along a chain of rods a member's rigid motion along its axis (the beam of a swaying
        portal frame) is no axial deformation: the share is that of the shape's linearised
        strain energy not in stretching, each rod's strains in its own frame (e = c u' + s v',
        g = -s u' + c v' - theta, kappa = theta'; c, s of theta0)."""
        if self.chain is not None:
            u, v, theta = ufl.split(shape)[0], ufl.split(shape)[1], ufl.split(shape)[2]
            c, s = ufl.cos(self.chain.theta0), ufl.sin(self.chain.theta0)
            stiff = self.stiffness
            stretch = stiff.EA * (c * u.dx(0) + s * v.dx(0)) ** 2
            rest = (stiff.shear_correction * stiff.GA * (-s * u.dx(0) + c * v.dx(0) - theta) ** 2
                    + stiff.EI * theta.dx(0) ** 2)
            axial = assemble_scalar(fem.form(stretch * self.dx_energy))
            transverse = assemble_scalar(fem.form(rest * self.dx_energy))
            total = axial + transverse
            return {"transverse": transverse / total if total > 0 else 0.0}
        du, dv = ufl.split(shape)[0], ufl.split(shape)[1]
        _, _, theta, _ = self.fields()
        along = du * ufl.cos(theta) + dv * ufl.sin(theta)
        normal = -du * ufl.sin(theta) + dv * ufl.cos(theta)
        axial = assemble_scalar(fem.form(self.section_props.A * along**2 * ufl.dx))
        transverse = assemble_scalar(fem.form(self.section_props.A * normal**2 * ufl.dx))
        total = axial + transverse
        return {"transverse": transverse / total if total > 0 else 0.0}

    def mode_kind(self, shares: dict) -> str:
        return "bending" if shares["transverse"] > 0.5 else "axial"

    def velocity_to_rates(self, values: list) -> list:
        """Initial velocities (the config's components at the dofs) as rates of the unknowns:
        the planar theta_t is the angular velocity itself."""
        return values

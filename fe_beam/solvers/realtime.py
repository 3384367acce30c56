"""Real-time re-solves: an equilibrium that follows new tensions, loads or parameters without
rebuilding anything, and a cache of built problems that lets a second cold `solve_static` of
the same kind of model skip the form building and JIT look-ups.

Every number of a `fe_beam.fem.rod.BeamProblem` that may change between solves is a
``fem.Constant`` (material, section dimensions, loads, load factor) or a ``fem.Function``
(tendon offsets): changing it never touches the compiled forms. Two things follow:

* `RealtimeSolver`: built once from a `StaticConfig` (rod or finger), solved to its load factor
  1, then ``update(tensions=..., loads=..., parameters=...)`` sets the new values and runs
  Newton from the last equilibrium (warm start; small serial systems: a dense LU and a chord
  predictor with the last tangent, so that a control-rate update is one Newton iteration;
  converged to rtol x the load steps' residual). When Newton fails, or the step check rejects
  the result (rotation jump, inadmissible state), the update falls back to load stepping from
  the last equilibrium to the new values (the values move linearly, with cut-back); when that
  fails too, `UpdateFailed` is raised with the last equilibrium and its values restored.
* `acquire` / `release`: the built problem and solver of a configuration, kept in a small
  cache keyed by everything that shapes the forms and the mesh (`structure_key`: law,
  constraint, mesh, length, section shape, supports, tendon geometry, solver settings, the
  communicator). A hit resets the state to zero and writes the configuration's numbers into
  the constants: the load stepping then starts exactly as on a new problem (same iterates, same
  numbers) without the ~0.02-0.2 s of building forms, spaces and the SNES.

Both work on spatial rods (``kinematics = "spatial"``): the key then also holds the initial
curvature's and a routed tendon's formulas, whether the tip-moment term is in the residual and
the thinner side of a rectangle (`_spatial_key`); the tip is {u, v, w, rotation_vector}. Newton
systems beyond BANDED_MIN_DOFS dofs are factorised in their band (`DenseLU`).

Nothing here writes files.
"""

from __future__ import annotations

import math
import os
from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np
from mpi4py import MPI

from fe_beam.errors import UpdateFailed  # noqa: F401  (its home; re-exported)
from fe_beam.fem import compat
from fe_beam.fem.equilibrium import residual_floor
from fe_beam.fem.kinematics import strains
from fe_beam.fem.rod import BeamProblem
from fe_beam.model.laws import LAW_KINDS
from fe_beam.model.loads import LOADS
from fe_beam.model.studies import StaticConfig
from fe_beam.model.tendons import check_tendon_inside
from fe_beam.solvers.continuation import run_load_stepping
from fe_beam.solvers.newton import LoadSteppingFailed, SolveFailed, StepResult, _agreed
from fe_beam.solvers.rod_static import StaticContinuation

__all__ = [
    "PARAMETER_KEYS",
    "RealtimeSolver",
    "UpdateFailed",
    "acquire",
    "apply_config",
    "cache_info",
    "clear_cache",
    "release",
    "set_parameters",
    "structure_key",
]

# Most cached problems kept (least recently used ones are destroyed beyond it);
# FE_BEAM_PROBLEM_CACHE=0 switches the cache off.
CACHE_SIZE = 8


# --- what shapes the forms -----------------------------------------------------------------------
def _profile_key(profile) -> tuple:
    """A `fe_beam.timefunctions.Profile` as compiled into a form: its formula's text and
    constants (a formula is UFL, its constants numbers in it), or its value (a Constant made
    with it, never updated)."""
    return (getattr(profile, "text", None), getattr(profile, "constant", None),
            tuple(sorted(getattr(profile, "constants", {}).items())), repr(profile))


def _tendon_geometry(tendon) -> tuple:
    """The part of a tendon that shapes the mesh and forms: entry, anchor, the x of its path
    points per branch and its kind of control (the offsets are Functions, the tension a
    Constant); a routed tendon's formulas (compiled into the forms of a spatial rod)."""
    routing = getattr(tendon, "routing", None)
    return (tendon.entry, tendon.anchor, tuple(tuple(x for x, _ in p) for p in tendon.paths),
            tendon.controlled_by_pull_in,
            None if routing is None else tuple(_profile_key(p) for p in routing))


def _spatial_key(model) -> tuple:
    """What a spatial rod compiles beyond a planar one: the initial curvature's formulas (and
    whether the rod is curved: the relaxed reference state), whether the residual has the tip
    moment's virtual work (only when the moment is nonzero, or with follower loads), and
    which side of a rectangle (T-section part) is the thinner (the torsion series' form)."""
    if getattr(model, "kinematics", "planar") != "spatial":
        return ("planar",)
    section = model.section
    thinner = ()
    if section.shape == "rectangle":
        thinner = (section._thinner_first("b", "h"),)
    elif section.shape == "t-section":
        thinner = (section._thinner_first("tw", None), section._thinner_first("tf", "b"))
    return ("spatial", tuple(_profile_key(p) for p in model.initial_curvature),
            bool(model.curved), bool(any(model.loads.tip_moment)), thinner)


def structure_key(config: StaticConfig, comm) -> tuple:
    """Everything of ``config`` that is compiled into forms, spaces or the solver: two
    configurations with the same key differ only in numbers held by Constants (material,
    section dimensions of a closed-form section, loads, tensions, tendon offsets)."""
    model = config.model
    section = model.section
    # A custom section's height and the hyperelastic section rule use the dimensions as
    # numbers: key on all of them there.
    numbers_compiled = section.shape == "custom" or LAW_KINDS[model.options.law].numbers_compiled
    section_key = (repr(section) if numbers_compiled
                   else (section.shape, tuple(sorted(section.dims)),
                         tuple(sorted(section.dims_tip))))
    options = model.options
    return (
        id(comm), comm.size, _spatial_key(model), float(model.length), model.mesh.elements,
        model.mesh.degree,
        options.law, options.constraint, repr(options.hyperelastic), options.section_points,
        section_key, repr(model.supports), bool(model.loads.follower),
        # the loads the problem does not hold as constants (point forces: mesh vertices and
        # forms; end motions: Dirichlet values) are part of its structure
        tuple((name, repr(getattr(model.loads, name))) for name, kind in LOADS.items()
              if not kind.realtime),
        tuple(_tendon_geometry(t) for t in config.tendons), repr(config.solver),
        float(config.max_rotation_jump),
        # obstacles are compiled into the contact forms (and the section's extents with them)
        (repr(config.obstacles), repr(config.contact), repr(section)) if config.obstacles
        else (),
        # a chain of rods: its mesh, reference angles and positions are compiled in (its
        # rods' own section and material numbers are fields, rewritten in place)
        None if getattr(model, "structure", None) is None else model.structure.compiled_key(),
    )


def apply_config(run, config: StaticConfig) -> None:
    """Write the numbers of ``config`` (same `structure_key` as the one ``run`` was built from)
    into the constants of ``run`` (a `fe_beam.analyses.static.StaticContinuation`) and reset it to
    the
    unloaded state at load factor 0, as a newly built one."""
    problem, model = run.problem, config.model
    problem.E.value = float(model.material.E)
    problem.G.value = float(model.material.shear_modulus)
    problem.rho.value = float(model.material.rho)
    problem.k_shear.value = float(model.options.shear_correction)
    for name, value in model.section.dims.items():
        problem.section_dims[name].value = float(value)
    for name, value in model.section.dims_tip.items():
        problem.section_dims_tip[name].value = float(value)
    for name, kind in LOADS.items():  # the loads the rod problem holds as constants
        if kind.realtime:
            getattr(problem, name).value = np.asarray(getattr(model.loads, name), dtype=float)
    if getattr(problem, "chain", None) is not None:  # the rods' own sections and materials
        problem.chain.set_rod_values(model.structure, model.structure)
    problem.model = model
    compat.local_array(problem.w)[:] = 0.0
    if run.tendons is not None:
        _set_tendons(run.tendons, config.tendons)
    run.config = config
    run.load_factor = 0.0
    problem.set_load_factor(0.0)
    run.watch = type(run.watch)()
    run._trial_range = None
    snes = run.snes
    snes._initial_fnorm, snes._largest_fnorm, snes._reference_fnorm = 0.0, 0.0, None
    # the round-off floor of the new numbers (the section and modulus set above)
    snes.residual_floor = residual_floor(problem)
    if hasattr(snes, "_last_fnorm"):
        del snes._last_fnorm
    if run.tendons is not None:
        run.solver.load_factor = 0.0
    if getattr(run, "contact", None) is not None:
        run.contact.reset()
    if getattr(problem, "curved", False):
        # a curved spatial rod: its reference is the relaxed stress-free state, solved again
        # with the new numbers (as a newly built problem does)
        problem._set_stress_free_guess()
        run._relax()


def _set_tendons(tendon_set, tendons) -> None:
    """New tendon values on a built `TendonSet` (same geometry key): tensions/pull-ins, and the
    offsets re-interpolated into its offset Functions; tension constants and rest lengths as
    for a new set (the state must be the unloaded one)."""
    tendons = tuple(tendons)
    spatial = getattr(tendon_set._problem, "spatial", False)
    for tendon, (_, deltas) in zip(tendons, tendon_set._geometry, strict=True):
        if spatial and tendon.routing is not None:
            continue  # its formulas are in the forms (and in the structure key)
        for path, delta in zip(tendon.paths, deltas, strict=True):
            if spatial:
                delta = delta[0]  # (y offset Function, z = 0)
            xs, ds = np.array([p[0] for p in path]), np.array([p[1] for p in path])
            delta.interpolate(lambda x, xs=xs, ds=ds: np.interp(x[0], xs, ds))
    tendon_set.tendons = tendons
    for constant in tendon_set.tensions:
        constant.value = 0.0
    tendon_set.rest_lengths = tendon_set.lengths()


# --- the cache ---------------------------------------------------------------------------------
@dataclass
class _Entry:
    run: object
    comm: object


_CACHE: OrderedDict = OrderedDict()
_STATS = {"hits": 0, "misses": 0}


def _enabled() -> bool:
    return os.environ.get("FE_BEAM_PROBLEM_CACHE", "1") != "0"


def acquire(config: StaticConfig, comm=MPI.COMM_WORLD, prefix: str = "fe_beam_static_"):
    """A `fe_beam.analyses.static.StaticContinuation` of ``config`` at the unloaded state: a cached
    one of
    the same `structure_key` with the configuration's numbers written in, or a new one. Give it
    back with `release` (it is not shared while out). Collective (the same sequence of calls on
    every rank gives the same hits)."""

    key = structure_key(config, comm) + (prefix,)
    entry = _CACHE.pop(key, None) if _enabled() else None
    if entry is not None and entry.comm is comm:
        _STATS["hits"] += 1
        _options(entry.run, present=True)
        apply_config(entry.run, config)
        entry.run._cache_key = key
        return entry.run
    if entry is not None:
        entry.run.destroy()
    _STATS["misses"] += 1
    run = StaticContinuation(config, comm, prefix=prefix)
    run._cache_key = key
    run._cache_comm = comm
    return run


def release(run) -> None:
    """Give back a continuation from `acquire`: kept for the next solve of its kind (the least
    recently used beyond CACHE_SIZE are destroyed), or destroyed when the cache is off."""
    key = getattr(run, "_cache_key", None)
    if key is None or not _enabled():
        run.destroy()
        return
    old = _CACHE.pop(key, None)
    if old is not None and old.run is not run:
        old.run.destroy()
    _options(run, present=False)
    _CACHE[key] = _Entry(run, run._cache_comm)
    while len(_CACHE) > CACHE_SIZE:
        _, evicted = _CACHE.popitem(last=False)
        evicted.run.destroy()


def _options(run, present: bool) -> None:
    """A cached solver's PETSc options leave the global database while it waits (a new solver
    with the same prefix and other settings, e.g. PETSc's LU after MUMPS, must not inherit
    them) and come back while it is used (a factorisation set up later reads them)."""
    from petsc4py import PETSc

    snes = run.snes
    database = PETSc.Options()
    for key, value in snes.settings.options().items():
        if present:
            database[snes.prefix + key] = value
        else:
            database.delValue(snes.prefix + key)


def clear_cache() -> None:
    """Destroy every cached problem (collective: call on all ranks)."""
    while _CACHE:
        _, entry = _CACHE.popitem(last=False)
        entry.run.destroy()
    _STATS.update(hits=0, misses=0)


def cache_info() -> dict:
    return {"size": len(_CACHE), **_STATS}


# --- parameters changed in place -----------------------------------------------------------------
PARAMETER_KEYS = (
    "material.E", "material.nu", "material.G", "material.rho", "section.<dim>",
    "section.<dim>_tip", "loads.tip_moment", "loads.tip_force.0", "loads.tip_force.1",
    "loads.distributed.0", "loads.distributed.1", "tendons.<i>.tension",
    "tendons.<i>.pull_in", "tendons.<i>.offset_base", "tendons.<i>.offset_tip",
    "tendons.<i>.path.<j>",
)


def _rod_index(structure, ident: str) -> int | None:
    """The index of the rod named ``ident`` (or of index ``ident``) in [[rods]], else None."""
    if ident.isdigit():
        return int(ident) if int(ident) < len(structure.rods) else None
    return next((i for i, rod in enumerate(structure.rods) if rod.name == ident), None)


def set_parameters(config: StaticConfig, values: Mapping[str, float]) -> StaticConfig:
    """``config`` with parameters changed, keys as in PARAMETER_KEYS (``section.h``,
    ``section.h_tip`` (a tip value of a dimension without one starts a taper),
    ``tendons.0.offset_tip``, ``tendons.0.path.2`` = the offset of path point 2 of the first
    branch, ...; a structure's ``rods.<name or index>.section.<dim>`` of rods that carry their
    own section fields). Raises KeyError (unknown key) or ValueError (a value the model
    refuses)."""
    model = config.model
    material, section, loads = model.material, model.section, model.loads
    tendons = list(config.tendons)
    for key, value in values.items():
        value = float(value)
        parts = key.split(".")
        head = parts[0]
        if head == "material" and len(parts) == 2 and parts[1] in ("E", "nu", "G", "rho"):
            name = parts[1]
            if name == "nu" and material.nu is None or name == "G" and material.G is None:
                raise KeyError(f"{key}: the material is given by "
                               f"{'G' if name == 'nu' else 'nu'}")
            material = replace(material, **{name: value})
        elif head == "section" and len(parts) == 2:
            name = parts[1]
            dims, tip = dict(section.dims), dict(section.dims_tip)
            if name in dims:
                dims[name] = value
            elif name.endswith("_tip") and name[:-4] in dims:
                tip[name[:-4]] = value
            else:
                raise KeyError(f"{key}: section {section.shape!r} has dimensions "
                               f"{', '.join(dims)} (and their _tip values)")
            section = replace(section, dims=dims, dims_tip=tip)
        elif head == "rods" and len(parts) == 4 and parts[2] in ("section", "material") \
                and getattr(model, "structure", None) is not None \
                and _rod_index(model.structure, parts[1]) is not None:
            structure = model.structure
            index = _rod_index(structure, parts[1])
            rod = structure.rods[index]
            if parts[2] == "section":
                if parts[3] not in dict(rod.section):
                    raise KeyError(f"{key}: rod {rod.name!r} has no own section dimension "
                                   f"{parts[3]!r}")
                structure = structure.with_rod_values(index, section={parts[3]: value})
            else:
                if parts[3] not in ("E", "G") or not rod.material:
                    raise KeyError(f"{key}: a rod's material variables are E and G")
                E, G = rod.material
                structure = structure.with_rod_values(
                    index, material=(value, G) if parts[3] == "E" else (E, value))
            model = replace(model, structure=structure)
        elif head == "loads" and key == "loads.tip_moment":
            loads = replace(loads, tip_moment=value)
        elif head == "loads" and len(parts) == 3 and parts[1] in ("tip_force", "distributed") \
                and parts[2] in ("0", "1", "2")[:len(getattr(loads, parts[1]))]:
            pair = list(getattr(loads, parts[1]))
            pair[int(parts[2])] = value
            loads = replace(loads, **{parts[1]: tuple(pair)})
        elif head == "tendons" and len(parts) >= 3 and parts[1].isdigit() \
                and int(parts[1]) < len(tendons):
            index, what = int(parts[1]), parts[2]
            tendon = tendons[index]
            if what in ("tension", "pull_in") and len(parts) == 3:
                if getattr(tendon, what) is None:
                    raise KeyError(f"{key}: tendon {index} is controlled by "
                                   f"{'pull_in' if what == 'tension' else 'tension'}")
                tendons[index] = replace(tendon, **{what: value})
            elif what in ("offset_base", "offset_tip", "path") and tendon.routing is not None:
                raise KeyError(f"{key}: tendon {index} is routed by formulas (offset_y, "
                               "offset_z), which are compiled into the forms: build a new "
                               "solver for other ones")
            elif what in ("offset_base", "offset_tip") and len(parts) == 3:
                point = 0 if what == "offset_base" else -1
                tendons[index] = replace(tendon, paths=tuple(
                    _with_offset(path, point, value) for path in tendon.paths))
            elif what == "path" and len(parts) == 4 and parts[3].isdigit() \
                    and int(parts[3]) < len(tendon.paths[0]):
                tendons[index] = replace(tendon, paths=(
                    _with_offset(tendon.paths[0], int(parts[3]), value),) + tendon.paths[1:])
            else:
                raise KeyError(f"{key}: a tendon has tension, pull_in, offset_base, "
                               "offset_tip and path.<point>")
        else:
            raise KeyError(f"{key}: not a parameter (known: {', '.join(PARAMETER_KEYS)})")
    model = replace(model, material=material, section=section, loads=loads)
    return replace(config, model=model, tendons=tuple(tendons))


def _with_tension(tendon, value: float):
    """``tendon`` with another tension (finite, >= 0: checked by the caller), without
    re-validating its paths (a routed tendon's 401 sampled points cost ~0.5 ms)."""
    import copy

    changed = copy.copy(tendon)
    object.__setattr__(changed, "tension", float(value))
    return changed


def _with_offset(path, index: int, value: float):
    points = [list(p) for p in path]
    points[index][1] = value
    return tuple(tuple(p) for p in points)


# --- the real-time solver ------------------------------------------------------------------------
# Serial systems up to this many dofs are factorised densely (LAPACK LU with partial pivoting,
# which also handles the zero diagonal of multiplier rows): for the 20-60 dofs of a real-time
# rod, MUMPS's fixed cost per factorisation (~0.5-1 ms) is most of an update.
DENSE_MAX_DOFS = 400


# Above this many dofs `DenseLU` factorises the band of the matrix (reverse Cuthill-McKee
# ordering, LAPACK gbtrf with partial pivoting within the band) instead of the whole of it: a
# rod's tangent is banded (bandwidth ~ 2-4 nodes' dofs), and a dense LU of the 326 dofs of a
# 20-element P2 spatial rod costs ~4.5 ms against ~0.2 ms for its band.
BANDED_MIN_DOFS = 80


class DenseLU:
    """PETSc python preconditioner: direct LU of the (small, serial) operator with partial
    pivoting (which also handles the zero diagonal of multiplier rows): dense (LAPACK getrf)
    up to BANDED_MIN_DOFS dofs, banded (gbtrf, after a reverse Cuthill-McKee ordering) beyond;
    with KSP "preonly" an exact direct solve. ``solve(rhs)`` applies the last factors."""

    factors = None

    def setUp(self, pc) -> None:
        from scipy.linalg import lapack

        operator, _ = pc.getOperators()
        size = operator.getSize()[0]
        rows, columns, values = operator.getValuesCSR()
        # the operator keeps its sparsity pattern (assembled into the same Mat): the dense
        # (or band) positions of its entries are computed once per operator and size
        pattern = getattr(self, "_pattern", None)
        if pattern is None or pattern[0] != (id(operator), size, columns.size):
            pattern = self._pattern = ((id(operator), size, columns.size),
                                       _lu_layout(size, rows, columns))
        layout = pattern[1]
        if layout[0] == "dense":
            dense = np.zeros(size * size)
            dense[layout[1]] = values
            # LAPACK getrf (partial pivoting) straight away: scipy's wrappers cost more than
            # the factorisation of these small matrices
            lu, pivots, info = lapack.dgetrf(dense.reshape(size, size))
            factors = ("dense", lu, pivots)
        else:
            _, flat, shape, kl, ku, order = layout
            band = np.zeros(shape[0] * shape[1])
            band[flat] = values
            lu, pivots, info = lapack.dgbtrf(band.reshape(shape), kl, ku)
            factors = ("band", lu, pivots, kl, ku, order)
        if info != 0 or not np.all(np.isfinite(lu)):
            from petsc4py import PETSc

            raise PETSc.Error(71)  # a zero pivot: the Newton step fails like a failed LU
        self.factors = factors

    def solve(self, rhs):
        """(A^-1 rhs, LAPACK info) with the last factors."""
        from scipy.linalg import lapack

        factors = self.factors
        if factors[0] == "dense":
            return lapack.dgetrs(factors[1], factors[2], rhs)
        _, lu, pivots, kl, ku, order = factors
        permuted, info = lapack.dgbtrs(lu, kl, ku, rhs[order], pivots)
        solution = np.empty_like(permuted)
        solution[order] = permuted
        return solution, info

    def apply(self, pc, x, y) -> None:
        solution, _ = self.solve(x.array_r)
        y.array[:] = solution


def _lu_layout(size: int, rows, columns) -> tuple:
    """Where the CSR entries go: ("dense", flat positions in the size x size array), or
    ("band", flat positions in gbtrf's band storage, its shape, kl, ku, the ordering)."""
    row_of = np.repeat(np.arange(size), np.diff(rows))
    if size < BANDED_MIN_DOFS:
        return ("dense", row_of * size + columns)
    import scipy.sparse as sparse
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    graph = sparse.csr_matrix((np.ones(columns.size), columns, rows), shape=(size, size))
    order = np.asarray(reverse_cuthill_mckee(graph + graph.T, symmetric_mode=True))
    position = np.empty(size, dtype=np.int64)
    position[order] = np.arange(size)
    i, j = position[row_of], position[columns]
    kl, ku = int(np.max(i - j, initial=0)), int(np.max(j - i, initial=0))
    shape = (2 * kl + ku + 1, size)
    # gbtrf's storage: A[i, j] at ab[kl + ku + i - j, j] (the first kl rows: room for fill-in)
    return ("band", (kl + ku + i - j) * size + j, shape, kl, ku, order)


class _OperatorPC:
    """The one method of a PC that `DenseLU.setUp` calls."""

    def __init__(self, matrix):
        self.matrix = matrix

    def getOperators(self):
        return self.matrix, self.matrix


def use_dense_lu(snes) -> DenseLU:
    """Solve the Newton systems of ``snes`` (a `fe_beam.solvers.newton.SNESSolver`) by `DenseLU`."""
    ksp = snes.snes.getKSP()
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("python")
    context = DenseLU()
    pc.setPythonContext(context)
    return context


def _skip_zero_lifting(snes) -> bool:
    """With only zero Dirichlet values (no prescribed end values) and no non-UFL terms, the
    lifting of the residual adds A[:, bc] (0 - x[bc]) = 0 exactly (Newton keeps x[bc] = 0):
    evaluate the residual without it (a tenth of an update's cost). Returns whether done."""
    problem = snes.problem
    beam = getattr(snes, "_beam_problem", None)
    if problem.contributions or beam is None or beam._prescribed:
        return False
    from petsc4py import PETSc

    def residual(snes_, x, b):
        problem._set_state(x)
        with b.localForm() as local:
            local.set(0.0)
        compat.assemble_vector(b, problem.residual_form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        compat.set_bc(b, problem.bcs, x, -1.0)

    snes.snes.setFunction(residual, problem.b)
    return True


class RealtimeSolver:
    """The equilibrium of a configuration, kept up to date under new values.

    ``RealtimeSolver(config)`` builds (or takes from the cache) the problem and solver and
    solves ``config`` by its load stepping. ``update(tensions=, pull_ins=, loads=,
    parameters=)`` then moves to new values: tensions (pull-ins) of the tendons in order (a
    sequence, or {index: value}); loads as {"tip_force": (fx, fy), "tip_moment": m,
    "distributed": (qx, qy), "gravity": (gx, gy)}; any parameter of `set_parameters`
    ({"section.h_tip": ..., "material.E": ..., "tendons.0.offset_tip": ...}). The answer is the
    equilibrium of the configuration with those values, the same as
    `fe_beam.analyses.static.solve_static`
    of it (to the Newton tolerance), found from the last one. ``check=False`` skips the step
    check (rotation jump, admissibility) on the fast path. Use as a context manager or call
    `close`.
    """

    def __init__(self, config: StaticConfig, comm=MPI.COMM_WORLD, check: bool = True,
                 progress: bool = False, dense: bool | None = None,
                 predictor: bool | None = None):
        """``dense``: Newton systems by dense LU (`DenseLU`); default: serial problems up to
        DENSE_MAX_DOFS dofs. ``predictor``: a chord step with the last tangent before Newton
        (dense only; default on there)."""
        self.comm = comm
        self._config, self._tensions = config, None
        self._structure_key = structure_key(config, comm)  # every update keeps it
        self._tip_dofs = None
        self.check = check
        self.run = acquire(config, comm, prefix="fe_beam_realtime_")
        if dense is None:
            dense = comm.size == 1 and self.run.problem.global_dofs <= DENSE_MAX_DOFS
        if dense and comm.size > 1:
            raise ValueError("dense LU is for serial problems")
        self._dense_context = use_dense_lu(self.run.snes) if dense else None
        self.run.snes._beam_problem = self.run.problem
        # serial dense problems: chord predictor before Newton (`_chord_step`)
        self.predictor = bool(dense) if predictor is None else bool(predictor and dense)
        # contact: every solve goes through the contact solver's active-set and Uzawa loop
        # (`fe_beam.solvers.contact.ContactSolver`), never the bare dense Newton, and each
        # accepted state is committed (friction is load-path dependent)
        self.contact = getattr(self.run, "contact", None)
        if self.contact is not None:
            self.predictor = False
        if self.predictor:
            self._work_x = self.run.snes.problem.b.duplicate()
            self._work_f = self.run.snes.problem.b.duplicate()
        self.tendons_pull_in = bool(self.tendons) and any(
            t.controlled_by_pull_in for t in self.tendons.tendons)
        self.dense = dense
        self.statistics = {"updates": 0, "newton_iterations": 0, "fallbacks": 0}
        try:
            self.run.advance(1.0, config.stepping, progress=progress)
        except LoadSteppingFailed as failure:
            release(self.run)
            self.run = None
            raise UpdateFailed(f"no equilibrium of the initial configuration: {failure}",
                               failure.last_load_factor) from None
        self._checker = self.run._step_check()
        self.last_iterations = 0
        # Updates converge to the accuracy of the load stepping: ||F|| <= rtol x the largest
        # load-step residual seen (solve_static's steps stop at rtol x their own first
        # residual, at most that). Relative to an update's own, often tiny, first residual
        # rtol would ask for more than the equilibrium is known to; a change within the
        # tolerance needs no iteration at all.
        snes = self.run.snes
        self._lifting_skipped = _skip_zero_lifting(snes)
        self._residual_function = snes.snes.getFunction()[1][0]
        self._saved_tolerances = snes.snes.getTolerances()
        rtol, atol, stol, max_it = self._saved_tolerances
        scale = snes._largest_fnorm
        if scale > 0 and math.isfinite(scale):
            snes.snes.setTolerances(rtol=rtol, atol=max(atol, rtol * scale), stol=stol,
                                    max_it=max_it)

    # --- state ---------------------------------------------------------------------------------
    @property
    def problem(self):
        return self.run.problem

    @property
    def tendons(self):
        return self.run.tendons

    def tip(self) -> dict:
        """{u, v, theta} at x = L (every rank); a spatial rod: {u, v, w, rotation_vector}
        (the displacement from its reference, the tip's rotation vector; the tip frame R and
        position: ``problem.end_values()``)."""
        problem = self.problem
        spatial = getattr(problem, "spatial", False)
        if self.comm.size > 1:
            values = problem.end_values("xL")
            if spatial:
                return {key: values[key] for key in ("u", "v", "w", "rotation_vector")}
            return values
        dofs = self._tip_dofs
        if dofs is None:
            BeamProblem.end_values(problem, "xL") if spatial else problem.end_values("xL")
            dofs = self._tip_dofs = problem._end_dofs["xL"]
        values = compat.local_array(problem.w)
        tip = {name: float(values[d].sum()) for name, d in dofs.items()}
        if not spatial:
            return tip
        reference = problem.reference_tip
        return {"u": tip["u"] - float(reference[0]), "v": tip["v"] - float(reference[1]),
                "w": tip["w"] - float(reference[2]),
                "rotation_vector": [tip["theta_x"], tip["theta_y"], tip["theta_z"]]}

    def state(self) -> np.ndarray:
        """A copy of the local dof array (ghosts included)."""
        return compat.local_array(self.problem.w).copy()

    def tension_values(self) -> np.ndarray:
        return self.tendons.tension_values() if self.tendons else np.zeros(0)

    # --- updates -------------------------------------------------------------------------------
    def target(self, tensions=None, pull_ins=None, loads: Mapping | None = None,
               parameters: Mapping | None = None) -> StaticConfig:
        """The configuration an update with these values solves."""
        values = dict(parameters or {})
        for what, given in (("tension", tensions), ("pull_in", pull_ins)):
            if given is None:
                continue
            items = given.items() if isinstance(given, Mapping) else enumerate(given)
            for index, value in items:
                values[f"tendons.{index}.{what}"] = value
        config = set_parameters(self.config, values)
        if loads:
            updatable = [name for name, kind in LOADS.items() if kind.realtime]
            unknown = [k for k in loads if k not in updatable]
            if unknown:
                raise KeyError(f"loads.{unknown[0]}: the loads are {', '.join(updatable[:-1])} "
                               f"and {updatable[-1]}")
            model = config.model
            config = replace(config, model=replace(model, loads=replace(model.loads, **loads)))
        if structure_key(config, self.comm) != self._structure_key:
            raise ValueError("the update changes the structure of the model (mesh, law, "
                             "supports, tendon path points): build a new solver")
        if parameters and any(k.startswith(("tendons.", "section.")) for k in parameters):
            # a tendon outside the section is refused as in the configuration
            # (ConfigError, a ValueError; the solver keeps its state)
            for tendon in config.tendons:
                check_tendon_inside(tendon, config.model.section, config.model.length)
        return config

    @property
    def config(self) -> StaticConfig:
        """The configuration whose equilibrium is the current state."""
        if self._tensions is not None:
            values = {f"tendons.{i}.tension": v for i, v in self._tensions.items()}
            self._config = set_parameters(self._config, values)
            self._tensions = None
        return self._config

    @config.setter
    def config(self, value: StaticConfig) -> None:
        self._config, self._tensions = value, None

    def update(self, tensions=None, pull_ins=None, loads=None, parameters=None) -> dict:
        """Move to the equilibrium of the new values; returns the tip {u, v, theta}."""
        if tensions is not None and pull_ins is None and not loads and not parameters:
            fast = self._fast_tensions(tensions)
            if fast is not None:
                return self.solve_config(None, fast)
        return self.solve_config(self.target(tensions, pull_ins, loads, parameters))

    def _fast_tensions(self, tensions) -> dict | None:
        """{index: value} of new tensions of tension-controlled tendons, or None when the
        general path is needed (pull-in control, a bad index or value)."""
        items = tensions.items() if isinstance(tensions, Mapping) else enumerate(tensions)
        tendons = self._config.tendons
        new = {}
        for index, value in items:
            if not (isinstance(index, (int, np.integer)) and 0 <= index < len(tendons)) \
                    or tendons[index].controlled_by_pull_in:
                return None
            value = float(value)
            if not (math.isfinite(value) and value >= 0):
                return None
            new[int(index)] = value
        return new

    def solve_config(self, config: StaticConfig | None, tensions: dict | None = None) -> dict:
        """Move to the equilibrium of ``config`` (same `structure_key`; None with ``tensions``
        = {index: tension}: the current one with those tensions): Newton from the last
        equilibrium, load stepping towards it if that fails; `UpdateFailed` if neither works
        (the last equilibrium and configuration are kept)."""
        previous = self.state()
        state = compat.local_array(self.problem.w)
        if config is None:
            # fast path: only tension constants change
            constants = self.tendons.tensions
            saved = [float(c.value) for c in constants]
            for index, value in tensions.items():
                constants[index].value = value
        else:
            self._apply(self.config, config, 1.0)
        self.statistics["updates"] += 1
        failure = None
        if self.predictor:
            self._chord_step(state)
        try:
            iterations = (self._dense_newton(state) if self.predictor and not self.tendons_pull_in
                          else self.run.solver.solve())
        except SolveFailed as error:
            failure = str(error)
        if failure is None and self.check:
            failure = _agreed(self.comm, self._check(previous, state))
        if failure is None:
            if config is None:
                self._tensions = (self._tensions or {}) | tensions
                # the tendon set's own values too: whatever sets its tensions from them
                # (`TendonSet.set_tension_controlled`) must see the current ones
                tendon_set = self.tendons
                tendon_set.tendons = tuple(
                    _with_tension(t, tensions[i]) if i in tensions else t
                    for i, t in enumerate(tendon_set.tendons))
            else:
                self.config = config
            if self.contact is not None:
                self.contact.commit()
            self.last_iterations = iterations
            self.statistics["newton_iterations"] += iterations
            return self.tip()
        # fallback: load stepping from the last equilibrium to the new values
        self.statistics["fallbacks"] += 1
        self._drop_factors()
        if config is None:
            for constant, value in zip(self.tendons.tensions, saved, strict=True):
                constant.value = value
            config = set_parameters(self.config, {f"tendons.{i}.tension": v
                                                  for i, v in tensions.items()})
        old = self.config
        state[:] = previous
        self._apply(old, config, 0.0)
        reached = [0.0]

        def converged(step: StepResult) -> None:
            reached[0] = step.load_factor
            self.statistics["newton_iterations"] += step.iterations
            if self.contact is not None:
                self.contact.commit()

        stepping = replace(self.config.stepping, adaptive=True)
        try:
            run_load_stepping(self.run.solver, lambda t: self._apply(old, config, t), stepping,
                              on_converged=converged, reject_step=self._check, progress=False)
        except LoadSteppingFailed as error:
            state[:] = previous
            self._apply(old, config, 0.0)
            self._drop_factors()
            raise UpdateFailed(
                f"no equilibrium at the new values: Newton from the last equilibrium failed "
                f"({failure}) and so did load stepping towards them ({error}); the last "
                "equilibrium is kept", reached[0]) from None
        self.config = config
        self.last_iterations = 0
        return self.tip()

    def _dense_newton(self, state) -> int:
        """Newton's method of `fe_beam.solvers.newton.SNESSolver` (full steps, its convergence test
        `SNESSolver._converged` with this solver's tolerances) written out for the small
        dense serial case: the same iterates without PETSc's SNES/KSP/PC dispatch. Raises
        SolveFailed like SNESSolver.solve; the state is only changed on success."""
        from petsc4py import PETSc

        solver = self.run.snes
        nonlinear, snes = solver.problem, solver.snes
        x, f = self._work_x, self._work_f
        x.array[:] = state
        residual = self._residual_function
        residual(snes, x, f)
        fnorm = f.norm()
        iteration, step_norm = 0, 0.0
        reason = solver._converged(snes, 0, (x.norm(), 0.0, fnorm))
        context = self._dense_context
        matrix = nonlinear.A
        try:
            while reason == 0:
                nonlinear.jacobian(snes, x, matrix, matrix)
                context.setUp(_OperatorPC(matrix))
                step, info = context.solve(f.array)
                if info != 0:
                    raise SolveFailed("dense LU solve failed")
                x.array[:] -= step
                step_norm = float(np.linalg.norm(step))
                residual(snes, x, f)
                fnorm = f.norm()
                iteration += 1
                reason = solver._converged(snes, iteration, (x.norm(), step_norm, fnorm))
        except PETSc.Error:
            raise SolveFailed("zero pivot in the dense LU") from None
        finally:
            solver._reference_fnorm = None
        if reason < 0:
            raise SolveFailed(f"Newton diverged (reason {reason})")
        solver.commit_scale()
        state[:] = x.array
        return iteration

    def _drop_factors(self) -> None:
        """Forget the last dense LU after a failed Newton: it is the tangent of a diverged
        iterate, not of the kept equilibrium, and `_chord_step` must not predict with it."""
        if self._dense_context is not None:
            self._dense_context.factors = None

    def _chord_step(self, state) -> None:
        """Predictor: one Newton step at the new values with the last factorised tangent (the
        dense LU of the previous update's last iteration, at a nearly converged state): the
        Newton iterations then start O(change^2) from the answer and one usually suffices. A
        predictor that is not finite is dropped."""
        context = self._dense_context
        if getattr(context, "factors", None) is None:
            return

        x = self._work_x
        x.array[:] = state
        self.run.snes.snes.computeFunction(x, self._work_f)
        step, info = context.solve(self._work_f.array)
        if info == 0 and np.all(np.isfinite(step)):
            state -= step

    def _check(self, previous, current):
        reason = self._checker(previous, current)
        if reason is None and self.run._trial_range is not None:
            self.run.watch.observe(self.run._trial_range)
        return reason

    def _apply(self, old: StaticConfig, new: StaticConfig, fraction: float) -> None:
        """Constants at ``old + fraction (new - old)`` (load factor 1)."""
        problem = self.problem
        a, b = old.model, new.model

        def mix(x, y):
            if fraction == 1.0:  # exactly the new values (not x + (y - x) in round-off)
                return np.asarray(y, dtype=float)
            return np.asarray(x, dtype=float) + fraction * (np.asarray(y, dtype=float)
                                                            - np.asarray(x, dtype=float))

        problem.E.value = float(mix(a.material.E, b.material.E))
        problem.G.value = float(mix(a.material.shear_modulus, b.material.shear_modulus))
        problem.rho.value = float(mix(a.material.rho, b.material.rho))
        for name in a.section.dims:
            problem.section_dims[name].value = float(mix(a.section.dims[name],
                                                         b.section.dims[name]))
        for name in a.section.dims_tip:
            problem.section_dims_tip[name].value = float(mix(a.section.dims_tip[name],
                                                     b.section.dims_tip[name]))
        for name, kind in LOADS.items():
            if kind.realtime:
                getattr(problem, name).value = np.asarray(
                    mix(getattr(a.loads, name), getattr(b.loads, name)), dtype=float)
        if getattr(problem, "chain", None) is not None:  # the rods' own sections, materials
            problem.chain.set_rod_values(a.structure, b.structure, fraction)
        tendons = self.tendons
        if not tendons:
            return
        geometry_changed = any(p != q for s, t in zip(old.tendons, new.tendons, strict=True)
                               for p, q in zip(s.paths, t.paths, strict=True))
        mixed = []
        for s, t in zip(old.tendons, new.tendons, strict=True):
            paths = tuple(tuple((x, float(mix(d0, d1))) for (x, d0), (_, d1) in zip(p, q,
                                                                                  strict=True))
                          for p, q in zip(s.paths, t.paths, strict=True))
            control = "pull_in" if s.controlled_by_pull_in else "tension"
            mixed.append(replace(s, paths=paths,
                                 **{control: float(mix(getattr(s, control),
                                                       getattr(t, control)))}))
        if geometry_changed:
            # new offsets: new interpolants and rest lengths (of the reference state)
            w = compat.local_array(problem.w)
            saved = w.copy()
            relaxed = getattr(self.run, "_relaxed_state", None)  # a curved rod's reference
            w[:] = 0.0 if relaxed is None else relaxed
            tensions = tendons.tension_values()
            _set_tendons(tendons, mixed)
            for constant, value in zip(tendons.tensions, tensions, strict=True):
                constant.value = float(value)
            w[:] = saved
        else:
            tendons.tendons = tuple(mixed)
        tendons.set_tension_controlled(1.0)
        self.run.solver.set_load_factor(1.0)

    # --- clean-up -------------------------------------------------------------------------------
    def close(self) -> None:
        """Give the problem back to the cache (`release`)."""
        if self.run is not None:
            if self._lifting_skipped:
                problem = self.run.snes.problem
                self.run.snes.snes.setFunction(problem.residual, problem.b)
            rtol, atol, stol, max_it = self._saved_tolerances
            self.run.snes.snes.setTolerances(rtol=rtol, atol=atol, stol=stol, max_it=max_it)
            release(self.run)
            self.run = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def max_fibre_strain(problem) -> float:
    """Largest |eps| + h(x)/2 |kappa| over the energy Gauss points (global): the extreme
    fibres' engineering strain of a symmetric section in small strain (collective)."""
    if not hasattr(problem, "_fibre_expression"):
        import ufl


        u, v, theta, _ = problem.fields()
        s = strains(u, v, theta)
        height = problem.section_props.h
        value = abs(s.eps) + height / 2 * abs(s.kappa)
        points, _ = np.polynomial.legendre.leggauss(problem.model.mesh.degree)
        reference = ((points + 1) / 2).reshape(-1, 1)
        problem._fibre_expression = compat.expression(ufl.as_vector([value]), reference)
    cells = np.arange(problem.mesh.topology.index_map(1).size_local, dtype=np.int32)
    values = compat.evaluate_expression(problem._fibre_expression, problem.mesh, cells)
    local = float(np.max(values)) if np.size(values) else -math.inf
    return problem.comm.allreduce(local, op=MPI.MAX)


"""Exact sensitivities of rod and finger outputs by the adjoint method (docs/theory.md,
Sensitivities).

At a converged equilibrium R(w; p) = 0 (Dirichlet rows: w = g, independent of p) an output
J(w; p) has the total derivative

    dJ/dp_k = dJ/dp_k|_w - lambda . dR/dp_k,   K^T lambda = dJ/dw   (lambda = 0 on Dirichlet dofs)

with K = dR/dw the converged tangent (multiplier rows of a constrained rod included): one
transposed solve per output, whatever the number of parameters. dR/dp_k is the UFL derivative
of the residual form with respect to the `fem.Constant` (or `fem.Function`, for tendon offsets)
that carries the parameter: every parameter enters the compiled forms through such a symbol, so a
parameter change never recompiles a form. Pull-in controlled tendons add their tensions as
unknowns and their lengths as constraints: the adjoint system is bordered (Schur complement on
the tensions, one extra transposed solve per controlled tendon).

Parameters are named by their configuration keys:

    material.E, material.nu, material.G, material.rho (through gravity loads)
    section.<dim>, section.<dim>_tip          (b, h, d, t, tf, tw; custom: A, I, I3, I4)
    loads.tip_force.0, loads.tip_force.1, loads.tip_moment, loads.distributed.0|1,
    loads.gravity.0|1
    tendons.<i>.tension, tendons.<i>.pull_in, tendons.<i>.offset_base, tendons.<i>.offset_tip,
    tendons.<i>.path.<k>.1, tendons.<i>.paths.<b>.<k>.1   (offset of path point k)

Outputs: ``tip_u``, ``tip_v``, ``tip_theta``; ``x@S`` and ``y@S`` (deformed position S + u(S),
v(S) of the backbone point at reference coordinate S, any S in [0, L]); ``pull_in.<i>`` (tendon
i: l_i(rest) - l_i) and ``tension.<i>`` (the solved tension of a pull-in controlled tendon).

Use (collective on the communicator)::

    model = RodSensitivity(raw_config, ["material.E", "tendons.0.offset_tip"])
    model.solve(1.0)                           # load stepping from the reference state
    value = model.outputs(["tip_theta"])       # np.ndarray
    grad = model.gradient(["tip_theta"])       # (outputs, parameters)
    model.set_values([6e5, 0.005]); model.solve(1.0)   # continuation from the last equilibrium
"""

from __future__ import annotations

import copy
import dataclasses
import math
import re
from collections.abc import Sequence

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc
from ufl.algorithms import replace

from fe_beam.analyses.calibrate import parameter_kind
from fe_beam.analyses.finger import parse_finger
from fe_beam.analyses.solid_driver import SolidRun, parse_solid
from fe_beam.analyses.static import StaticContinuation
from fe_beam.config.finger import with_defaults
from fe_beam.config.schema import parse_static, with_rod_materials, with_rod_sections
from fe_beam.errors import ConfigError
from fe_beam.fem import compat
from fe_beam.fem.mpi import assemble_scalar, global_sum
from fe_beam.fem.solid.geometry import TIP_TAG
from fe_beam.model.hyperelastic import NeoHookean
from fe_beam.model.laws import LAW_KINDS
from fe_beam.model.loads import LOADS
from fe_beam.solvers.newton import (
    SADDLE_POINT_WORKSPACE,
    LoadStepping,
    LoadSteppingFailed,
    SolveFailed,
    _agreed,
)

__all__ = ["OUTPUT_KEYS", "RodSensitivity", "parameter_kind", "parse_output", "sensitivities"]

OUTPUT_KEYS = ("tip_u", "tip_v", "tip_theta", "x@S", "y@S", "pull_in.<i>", "tension.<i>")
#: the differentiable vector loads (fe_beam.model.loads): their components are parameters
LOAD_VECTORS = {name: name for name, kind in LOADS.items()
                if kind.differentiable and kind.kind == "vector"}


def parse_output(name: str, length: float | None = None) -> tuple:
    """('tip', component) | ('point', 'x'|'y', S) | ('pull_in', i) | ('tension', i)."""
    if name in ("tip_u", "tip_v", "tip_theta"):
        return ("tip", name[4:])
    m = re.fullmatch(r"([xy])@(.+)", str(name))
    if m:
        try:
            s = float(m.group(2))
        except ValueError:
            s = math.nan
        if not math.isfinite(s) or (length is not None and not -1e-12 <= s <= length * (1 + 1e-12)):
            raise ConfigError(f"output {name!r}: the reference coordinate must be a number in "
                              f"[0, L]")
        return ("point", m.group(1), s)
    m = re.fullmatch(r"(pull_in|tension)\.(\d+)", str(name))
    if m:
        return (m.group(1), int(m.group(2)))
    raise ConfigError(f"unknown output {name!r}: outputs are {', '.join(OUTPUT_KEYS)}")


def _prepare_raw(raw: dict, parameters: Sequence[str]) -> dict:
    """A copy of the raw config in which every parameter has its own symbol: a tapered
    dimension ``section.X_tip`` not given becomes X_tip = X (same numbers); a custom section's
    I3 not given becomes 0."""
    raw = copy.deepcopy(raw)
    if raw.get("tendons"):  # the finger's defaults (its section among them) made explicit

        raw = with_defaults(raw)
    section = raw.setdefault("section", {})
    for key in parameters:
        m = re.fullmatch(r"section\.([A-Za-z0-9]+?)(_tip)?", key)
        if not m:
            continue
        name, tip = m.group(1), m.group(2)
        if name == "I3" and section.get("shape") == "custom" and name not in section:
            section[name] = 0.0
        if name not in section:
            raise ConfigError(f"parameter {key!r}: section.{name} is not in the configuration "
                              "(only given dimensions can be parameters)")
        if tip and key[len("section."):] not in section:
            section[f"{name}_tip"] = section[name]
    return raw


class _Parameter:
    """One parameter: its value, how to set it, and the (terminal, direction) pairs through
    which it enters the residual (direction: a UFL expression, the derivative of the terminal
    by the parameter)."""

    def __init__(self, key, kind, get, put, terms, tendon=None, constraint=None):
        self.key, self.kind, self.get, self.put = key, kind, get, put
        self.terms = terms  # list of (terminal, direction)
        self.tendon = tendon
        self.constraint = constraint  # d(pull-in target) / dp factor (pull_in parameters)


class RodSensitivity:
    """A rod (``fe-beam static``) or finger (``fe-beam finger``: with [[tendons]]) problem built
    once, with named parameters that can be changed without recompiling and adjoint gradients
    of outputs with respect to them (module docstring: parameter and output names).

    ``raw``: the configuration as read from TOML (dict); ``kind``: "static" or "finger" (None:
    "finger" when the configuration has [[tendons]]). Raises `ConfigError` for unknown or
    unusable parameters.
    """

    def __init__(self, raw: dict | None, parameters: Sequence[str] = (), comm=MPI.COMM_WORLD,
                 kind: str | None = None, config=None):
        """``config``: an already parsed `fe_beam.config.schema.StaticConfig` (with its tendons)
        instead of ``raw`` (a tapered dimension's ``_tip`` parameter then needs the taper given
        in the section: ``dims_tip``)."""

        self.parameters = list(parameters)
        self._raw = raw
        if len(set(self.parameters)) != len(self.parameters):
            raise ConfigError("[calibrate] parameters: a parameter is listed twice")
        kinds = [parameter_kind(k) for k in self.parameters]
        if config is None:
            config = self._parse(raw, kinds, kind)
        elif not config.tendons and any(k in ("tension", "pull_in", "offset") for k in kinds):
            raise ConfigError("tendon parameters need [[tendons]] (fe-beam finger)")
        if not LAW_KINDS[config.model.options.law].differentiable:
            laws = " and ".join(f'"{n}"' for n, kind in LAW_KINDS.items() if kind.differentiable)
            raise ConfigError(f"sensitivities support model.law = {laws} (not "
                              f"\"{config.model.options.law}\")")
        self.config = config
        self.comm = comm
        self.run = StaticContinuation(config, comm, prefix=f"fe_beam_sens{id(self)}_")
        self.problem = self.run.problem
        self.tendons = self.run.tendons
        if self.tendons:
            # pull-in control: tendon lengths to round-off (gradients are of the exact solution)
            self.run.solver.tolerance = 1e-13 * config.model.length
        self._paths = ([[np.array(p, dtype=float) for p in t.paths] for t in self.tendons.tendons]
                       if self.tendons else [])
        self._params = [self._make_parameter(key, k) for key, k in zip(self.parameters, kinds,
                                                                        strict=True)]
        self.controlled = ([i for i, t in enumerate(self.tendons.tendons)
                            if t.controlled_by_pull_in] if self.tendons else [])
        self._build_forms()
        self._dirty = True  # w is not an equilibrium of the current parameters
        self._version = 0  # counts parameter changes
        # converged equilibria per load factor, with their parameter version (continuation)
        self._states: dict[float, np.ndarray] = {}
        self._versions: dict[float, int] = {}
        self._tension_states: dict[float, np.ndarray] = {}
        self._ksp = None
        self._A = None
        self.stepping = config.stepping

    @classmethod
    def from_config(cls, config, parameters: Sequence[str] = (), comm=MPI.COMM_WORLD):
        """From a parsed `fe_beam.config.schema.StaticConfig` (e.g. of
        `fe_beam.analyses.finger.parse_finger`)."""
        return cls(None, parameters, comm, config=config)

    def _parse(self, raw: dict, kinds: list, kind: str | None):
        kind = kind or ("finger" if raw.get("tendons") else "static")
        raw = _prepare_raw(raw, self.parameters)
        if kind == "finger":

            config, _ = parse_finger({k: v for k, v in raw.items() if k != "calibrate"})
            return config

        if any(k in ("tension", "pull_in", "offset") for k in kinds):
            raise ConfigError("tendon parameters need [[tendons]] (fe-beam finger)")
        config = parse_static(raw)
        if getattr(config.model, "structure", None) is not None:
            # a rod's parameter is the value of its own field: every rod then carries one
            if "rod_section" in kinds:
                config = dataclasses.replace(config, model=with_rod_sections(config.model))
            if "rod_material" in kinds:
                config = dataclasses.replace(config, model=with_rod_materials(config.model))
        return config

    # --- parameters --------------------------------------------------------------------------

    def _make_parameter(self, key: str, kind: str) -> _Parameter:
        p = self.problem
        mesh = p.mesh
        const = lambda v: fem.Constant(mesh, float(v))  # noqa: E731
        if key == "material.rho":
            c = p.rho
            return _Parameter(key, kind, lambda: float(c.value),
                              lambda v: self._set_constant(c, v), [(c, 1.0)])
        if kind == "material":
            name = key.split(".")[1]
            m = self.config.model.material
            if name != "E" and getattr(m, name) is None:
                other = "nu" if name == "G" else "G"
                raise ConfigError(f"parameter {key!r}: the configuration gives material.{other}, "
                                  f"not material.{name}")
            self._moduli = getattr(self, "_moduli", {"E": float(m.E), "nu": m.nu, "G": m.G})
            if name == "E":
                factor = const(0.0)
                par = _Parameter(key, kind, lambda: self._moduli["E"],
                                 lambda v: self._set_modulus("E", v),
                                 [(p.E, 1.0), (p.G, factor)])
                par.g_factor = factor
                return par
            factor = const(0.0)
            par = _Parameter(key, kind, lambda n=name: self._moduli[n],
                             lambda v, n=name: self._set_modulus(n, v), [(p.G, factor)])
            par.g_factor = factor
            return par
        if kind == "section":
            m = re.fullmatch(r"section\.([A-Za-z0-9]+?)(_tip)?", key)
            table = p.section_dims_tip if m.group(2) else p.section_dims
            constant = table.get(m.group(1))
            if constant is None:
                raise ConfigError(f"parameter {key!r} is not a dimension of section shape "
                                  f"{self.config.model.section.shape!r}")
            return _Parameter(key, kind, lambda c=constant: float(c.value),
                              lambda v, c=constant: self._set_constant(c, v),
                              [(constant, 1.0)])
        if kind in ("rod_section", "rod_material"):
            return self._rod_parameter(key, kind)
        if kind == "load":
            parts = key.split(".")
            if parts[1] == "tip_moment":
                c = p.tip_moment
                return _Parameter(key, kind, lambda: float(c.value),
                                  lambda v: self._set_constant(c, v), [(c, 1.0)])
            c, index = getattr(p, LOAD_VECTORS[parts[1]]), int(parts[2])
            if parts[1] == "gravity" and float(self.config.model.material.rho) == 0.0:
                raise ConfigError(f"parameter {key!r} needs material.rho > 0")
            unit = ufl.as_vector([1.0, 0.0] if index == 0 else [0.0, 1.0])
            return _Parameter(key, kind, lambda: float(c.value[index]),
                              lambda v: self._set_component(c, index, v), [(c, unit)])
        # tendons
        m = re.fullmatch(r"tendons\.(\d+)\.(.+)", key)
        index, rest = int(m.group(1)), m.group(2)
        if index >= len(self.tendons.tendons):
            raise ConfigError(f"parameter {key!r}: there are {len(self.tendons.tendons)} "
                              "tendons (numbered from 0)")
        tendon = self.tendons.tendons[index]
        if kind == "tension":
            if tendon.controlled_by_pull_in:
                raise ConfigError(f"parameter {key!r}: tendon {index} is pull-in controlled "
                                  "(its tension is an unknown)")
            return _Parameter(key, kind, lambda: float(self.tendons.tendons[index].tension),
                              lambda v: self._set_tendon(index, tension=float(v)),
                              [(self.tendons.tensions[index], self.problem.load_factor)],
                              tendon=index)
        if kind == "pull_in":
            if not tendon.controlled_by_pull_in:
                raise ConfigError(f"parameter {key!r}: tendon {index} is tension controlled")
            return _Parameter(key, kind, lambda: float(self.tendons.tendons[index].pull_in),
                              lambda v: self._set_tendon(index, pull_in=float(v)), [],
                              tendon=index, constraint=True)
        # offsets: (branch, point)
        branches = self._paths[index]
        if rest in ("offset_base", "offset_tip"):
            if len(branches) != 1 or len(branches[0]) != 2:
                raise ConfigError(f"parameter {key!r}: tendon {index} is given by a path; use "
                                  f"tendons.{index}.path.<k>.1")
            branch, point = 0, (0 if rest == "offset_base" else 1)
        else:
            numbers = [int(n) for n in re.findall(r"\d+", rest)]
            branch, point = (0, numbers[0]) if rest.startswith("path.") else numbers[:2]
            if rest.startswith("path.") and len(branches) != 1:
                raise ConfigError(f"parameter {key!r}: tendon {index} has several paths; use "
                                  f"tendons.{index}.paths.<b>.<k>.1")
            if branch >= len(branches) or point >= len(branches[branch]):
                raise ConfigError(f"parameter {key!r}: tendon {index} has no such path point")
        delta = self._delta(index, branch)
        direction = fem.Function(delta.function_space)
        xs = branches[branch][:, 0].copy()
        hat = np.zeros(len(xs))
        hat[point] = 1.0
        direction.interpolate(lambda x: np.interp(x[0], xs, hat))
        return _Parameter(key, kind, lambda: float(self._paths[index][branch][point, 1]),
                          lambda v: self._set_offset(index, branch, point, v),
                          [(delta, direction)], tendon=index)

    def _rod_parameter(self, key: str, kind: str) -> _Parameter:
        """``rods.<name or index>.section.<dim>`` or ``rods.<name>.material.E|G``: the value
        of one rod's own DG0 field (a chain of rods whose rods carry their own sections or
        materials), entering through the field in the direction of the rod's cells."""
        _, ident, table, name = key.split(".")
        chain = getattr(self.problem, "chain", None)
        structure = getattr(self.config.model, "structure", None)
        if chain is None or structure is None:
            raise ConfigError(f"parameter {key!r} needs [[rods]] (a structure of rods)")
        names = [rod.name for rod in structure.rods]
        index = (int(ident) if ident.isdigit() and int(ident) < len(names)
                 else names.index(ident) if ident in names else None)
        if index is None:
            raise ConfigError(f"parameter {key!r}: no rod {ident!r} in [[rods]] (rods: "
                              f"{', '.join(names)})")
        found = chain.rod_field(index, table, name)
        if found is None:
            what = (f"section dimension {name!r}" if table == "section"
                    else f"material {name}")
            raise ConfigError(f"parameter {key!r}: the rods carry no own {what} (give every "
                              f"rod's own [[rods]] {table} table, or fit the top-level "
                              f"{table}.{name})")
        field, indicator = found
        rod = structure.rods[index]
        value = {"v": float(dict(rod.section)[name] if table == "section"
                            else rod.material[0 if name == "E" else 1])}
        cells = np.flatnonzero(indicator.x.array > 0.5)
        terms = [(field, indicator)]
        # a rod's E moves its G when its material is given by nu (G / E = 1 / (2 (1 + nu)))
        follower = None
        if table == "material" and name == "E" and not self._rod_gives_G(index):
            if f"rods.{ident}.material.G" in self.parameters:
                raise ConfigError(f"parameters {key!r} and 'rods.{ident}.material.G': the rod's "
                                  "material gives nu (G follows E); give its G to fit both")
            follower = (chain.rod_field(index, "material", "G")[0],
                        rod.material[1] / rod.material[0])
            terms.append((follower[0], follower[1] * indicator))

        def put(v, field=field, cells=cells, follower=follower):
            value["v"] = float(v)
            field.x.array[cells] = float(v)
            field.x.scatter_forward()
            if follower is not None:
                follower[0].x.array[cells] = float(v) * follower[1]
                follower[0].x.scatter_forward()

        return _Parameter(key, kind, lambda: value["v"], put, terms)

    def _rod_gives_G(self, index: int) -> bool:
        """Rod ``index``'s material is given by G (its own table's, or [material]'s when its
        own gives neither nu nor G), not by nu."""
        raw = self._raw or {}
        rods = raw.get("rods") or []
        own = (rods[index].get("material") or {}) if index < len(rods) else {}
        if "G" in own or "nu" in own:
            return "G" in own
        top = raw.get("material") or {}
        return "G" in top if raw else self.config.model.material.G is not None

    def _delta(self, index: int, branch: int) -> fem.Function:
        if self.tendons._problem is not self.problem:
            self.tendons._attach(self.problem)
        return self.tendons._geometry[index][1][branch]

    def _set_constant(self, constant, value) -> None:
        constant.value = float(value)

    def _set_component(self, constant, index, value) -> None:
        values = np.array(constant.value, dtype=float)
        values[index] = float(value)
        constant.value = values

    def _set_modulus(self, name: str, value: float) -> None:
        self._moduli[name] = float(value)
        self.problem.E.value = self._moduli["E"]
        self.problem.G.value = self._shear_modulus()

    def _shear_modulus(self) -> float:
        mod = self._moduli
        return mod["G"] if mod["G"] is not None else mod["E"] / (2 * (1 + mod["nu"]))

    def _set_tendon(self, index: int, **changes) -> None:
        tendons = list(self.tendons.tendons)
        tendons[index] = dataclasses.replace(tendons[index], **changes)
        self.tendons.tendons = tuple(tendons)
        self.tendons.set_tension_controlled(float(self.problem.load_factor.value))

    def _set_offset(self, index: int, branch: int, point: int, value: float) -> None:
        path = self._paths[index][branch]
        path[point, 1] = float(value)
        xs, ds = path[:, 0].copy(), path[:, 1].copy()
        self._delta(index, branch).interpolate(lambda x: np.interp(x[0], xs, ds))
        tendons = list(self.tendons.tendons)
        paths = tuple(tuple(map(tuple, p)) for p in self._paths[index])
        tendons[index] = dataclasses.replace(tendons[index], paths=paths)
        self.tendons.tendons = tuple(tendons)
        self.tendons.rest_lengths = self._lengths_at_rest()

    def values(self) -> np.ndarray:
        """Current parameter values (in the order of ``parameters``)."""
        return np.array([p.get() for p in self._params], dtype=float)

    def set_values(self, values) -> None:
        """Change the parameters (forms are not rebuilt); the next `solve` re-solves."""
        values = np.asarray(values, dtype=float).ravel()
        if values.shape != (len(self._params),):
            raise ValueError(f"need {len(self._params)} parameter values, got {values.shape}")
        changed = False
        for par, value in zip(self._params, values, strict=True):
            if par.get() != value:
                par.put(value)
                changed = True
        if changed:
            self._dirty = True
            self._version += 1

    def _update_direction_constants(self) -> None:
        mod = getattr(self, "_moduli", None)
        for par in self._params:
            if par.kind != "material" or par.key == "material.rho":
                continue
            name = par.key.split(".")[1]
            if name == "E":
                par.g_factor.value = 0.0 if mod["G"] is not None else 1 / (2 * (1 + mod["nu"]))
            elif name == "nu":
                par.g_factor.value = -mod["E"] / (2 * (1 + mod["nu"]) ** 2)
            else:
                par.g_factor.value = 1.0

    # --- forms --------------------------------------------------------------------------------
    def _derivative_form(self, form: ufl.Form) -> ufl.Form | None:
        """sum_k selector_k dForm/dp_k (None without parameters entering ``form``)."""
        mesh = self.problem.mesh
        mapping: dict = {}
        variables = []
        for par in self._params:
            t = ufl.variable(fem.Constant(mesh, 0.0))
            variables.append(t)
            for terminal, direction in par.terms:
                mapping[terminal] = mapping.get(terminal, terminal) + t * direction
        if not mapping:
            return None
        replaced = replace(form, mapping)
        integrals = []
        for integral in replaced.integrals():
            integrand = sum((selector * ufl.diff(integral.integrand(), t)
                             for selector, t in zip(self._selectors, variables, strict=True)),
                            ufl.zero())
            integrals.append(integral.reconstruct(integrand=integrand))
        return ufl.Form(integrals)

    def _build_forms(self) -> None:
        mesh = self.problem.mesh
        self._selectors = [fem.Constant(mesh, 0.0) for _ in self._params]
        self._update_direction_constants()
        nonlinear = self.run.snes.problem
        form = self._derivative_form(self.problem.residual)
        self._dR = fem.form(form) if form is not None and form.integrals() else None
        self._dL = []
        if self.tendons:
            for length in self.tendons.length_ufl:
                dform = self._derivative_form(length)
                self._dL.append(fem.form(dform) if dform is not None and dform.integrals()
                                else None)
        self._vector = compat.create_vector(nonlinear.residual_form)

    def _select(self, k: int) -> None:
        """Selector k on, the others off (only the two that change are set)."""
        current = getattr(self, "_selected", None)
        if current == k:
            return
        if current is None:
            for selector in self._selectors:
                selector.value = 0.0
        else:
            self._selectors[current].value = 0.0
        self._selectors[k].value = 1.0
        self._selected = k

    def _residual_derivatives(self) -> list[PETSc.Vec]:
        """dR/dp_k (Dirichlet rows zero), one vector per parameter (reused between calls)."""
        if getattr(self, "_rp", None) is None:
            self._rp = [self._vector.duplicate() for _ in self._params]
        vectors = self._rp
        for k, vec in enumerate(vectors):
            with vec.localForm() as local:
                local.set(0.0)
            if self._dR is not None:
                self._select(k)
                compat.assemble_vector(vec, self._dR)
                vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            compat.set_bc(vec, self.problem.bcs, scale=0.0)
        return vectors

    def _length_derivatives(self, index: int) -> np.ndarray:
        """d l_index / dp_k at the current state (explicit: w fixed)."""
        form = self._dL[index] if self._dL else None
        values = np.zeros(len(self._params))
        if form is None:
            return values
        for k in range(len(self._params)):
            self._select(k)
            values[k] = assemble_scalar(form)
        return values

    def _at_rest(self, function):
        state = compat.local_array(self.problem.w)
        saved = state.copy()
        state[:] = 0.0
        try:
            return function()
        finally:
            state[:] = saved

    def _lengths_at_rest(self) -> np.ndarray:
        return self._at_rest(self.tendons.lengths)

    # --- solving ------------------------------------------------------------------------------
    @property
    def load_factor(self) -> float:
        return float(self.run.load_factor)

    def solve(self, load_factor: float = 1.0, stepping: LoadStepping | None = None) -> None:
        """Equilibrium at ``load_factor`` for the current parameters, continued from the last
        equilibrium: after a parameter change, Newton from the last converged state at this
        load factor (cached per load factor); if that fails, load stepping from the nearest
        converged state, and finally from the reference state. Raises
        `fe_beam.solvers.newton.LoadSteppingFailed` when no equilibrium is found."""

        load_factor = float(load_factor)
        stepping = stepping or self.stepping
        self._update_direction_constants()
        if not self._dirty and load_factor == self.load_factor:
            return
        failed = None
        if load_factor in self._states:
            # a cached equilibrium at this load factor: the answer if it is of the current
            # parameters, else the start of Newton's method (continuation)
            self._restore(load_factor)
            if self._versions[load_factor] == self._version:
                self._dirty = False
                return
            try:
                self._newton()
                self._converged(load_factor)
                return
            except SolveFailed:
                failed, self._dirty = load_factor, True
        if self._dirty:
            # w is no equilibrium of the current parameters: make one at the nearest cached
            # load factor, else start from the reference state
            levels = [lf for lf in self._states if lf != failed]
            if levels:
                nearest = min(levels, key=lambda lf: abs(lf - load_factor))
                self._restore(nearest)
                try:
                    self._newton()
                    self._converged(nearest)
                except SolveFailed:
                    self._restart()
            else:
                self._restart()
        try:
            if abs(load_factor - self.load_factor) > 0:
                self.run.advance(load_factor, self._segment(stepping, load_factor),
                                 progress=False)
        except LoadSteppingFailed:
            if self.load_factor == 0.0:
                raise
            self._restart()
            self.run.advance(load_factor, self._segment(stepping, load_factor), progress=False)
        self._converged(load_factor)

    def _restore(self, load_factor: float) -> None:
        """The cached equilibrium at ``load_factor`` (state and solved tensions) into w."""
        compat.local_array(self.problem.w)[:] = self._states[load_factor]
        self._set_factor(load_factor)
        saved = self._tension_states.get(load_factor)
        if saved is not None:
            for i in self.controlled:
                self.tendons.tensions[i].value = float(saved[i])

    def _segment(self, stepping: LoadStepping, target: float) -> LoadStepping:
        """Load stepping for the segment from the current load factor to ``target``: the
        configured steps per unit load factor."""
        span = abs(target - self.load_factor)
        steps = max(1, math.ceil(stepping.steps * span - 1e-9))
        return LoadStepping(steps=steps, min_increment=min(stepping.min_increment / span,
                                                           1.0 / steps),
                            cut_factor=stepping.cut_factor, grow_factor=stepping.grow_factor,
                            easy_iterations=stepping.easy_iterations,
                            adaptive=stepping.adaptive)

    def _restart(self) -> None:
        self.run.restart()
        self._set_factor(0.0)
        if self.tendons:
            for i in self.controlled:
                self.tendons.tensions[i].value = 0.0
        self._dirty = False

    def _set_factor(self, value: float) -> None:
        self.run._set_load_factor(value)
        self.run.load_factor = value

    def _newton(self) -> None:
        """Newton from the current state (continuation after a parameter change). A result
        that jumped branch (rotations changed by more than max_rotation_jump, e.g. onto a
        looped or collapsed equilibrium of a coarse mesh) or is inadmissible is a failure, as in
        load stepping: the caller then steps the load (was: accepted, a wrong equilibrium)."""

        previous = compat.local_array(self.problem.w).copy()
        self.run.solver.solve()
        checker = self.__dict__.get("_checker")
        if checker is None:
            checker = self._checker = self.run._step_check()
        reason = _agreed(self.comm, checker(previous, compat.local_array(self.problem.w)))
        if reason:
            raise SolveFailed(f"continuation left the equilibrium branch: {reason}")

    def _converged(self, load_factor: float) -> None:
        self._dirty = False
        self.run.load_factor = load_factor
        self._states[load_factor] = compat.local_array(self.problem.w).copy()
        self._versions[load_factor] = self._version
        if self.tendons:
            self._tension_states[load_factor] = self.tendons.tension_values()

    def forget_states(self) -> None:
        """Drop the cached equilibria (continuation then starts from the reference state)."""
        self._states.clear()
        self._versions.clear()
        self._tension_states.clear()
        self._dirty = True

    def saved_states(self) -> dict:
        """A copy of the cached equilibria (per load factor) of the current parameters: the
        start `start_from` restores (e.g. a fit's accepted point)."""
        current = {lf: state.copy() for lf, state in self._states.items()
                   if self._versions[lf] == self._version}
        return {"states": current,
                "tensions": {lf: np.array(t, copy=True) for lf, t in
                             self._tension_states.items() if lf in current}}

    def start_from(self, saved: dict | None) -> None:
        """Continue the next solves from ``saved`` (`saved_states`; None: from the reference
        state) instead of the last solved equilibria: a branch-safe start for a trial
        parameter set (Newton from a far trial's state can land on another, non-physical
        equilibrium branch)."""
        self.forget_states()
        if saved:
            for lf, state in saved["states"].items():
                self._states[lf] = state.copy()
                self._versions[lf] = -1  # a start for Newton's method, not an answer
            self._tension_states.update({lf: np.array(t, copy=True)
                                         for lf, t in saved["tensions"].items()})

    # --- outputs ------------------------------------------------------------------------------
    def outputs(self, names: Sequence[str]) -> np.ndarray:
        """Values of the outputs at the current state (collective)."""
        values, tip = [], None
        for name in names:
            spec = parse_output(name, self.config.model.length)
            if spec[0] == "tip":
                tip = tip or self.problem.end_values("xL")
                values.append(tip[spec[1]])
            elif spec[0] == "point":
                dofs, weights = self._point_weights(spec[1], spec[2])
                local = compat.local_array(self.problem.w)
                value = float(np.dot(local[dofs], weights)) if len(dofs) else 0.0
                reference = self.problem.reference_point(spec[2])  # (s, 0) of a rod
                values.append(global_sum(self.comm, value)
                              + reference[0 if spec[1] == "x" else 1])
            elif spec[0] == "pull_in":
                self._check_tendon(spec[1])
                values.append(float(self.tendons.pull_ins()[spec[1]]))
            else:
                self._check_tendon(spec[1])
                values.append(float(self.tendons.tensions[spec[1]].value))
        return np.array(values, dtype=float)

    def _check_tendon(self, index: int) -> None:
        if not self.tendons or index >= len(self.tendons.tendons):
            raise ConfigError(f"output tendon {index} does not exist")

    def _point_weights(self, component: str, s: float) -> tuple[np.ndarray, np.ndarray]:
        """Local dofs (in w, ghosts included) and weights of u(s) or v(s) on the one rank
        that evaluates it (empty elsewhere): the Lagrange basis of the cell that holds s."""
        cache = self.__dict__.setdefault("_point_cache", {})
        key = (component, s)
        if key in cache:
            return cache[key]
        mesh = self.problem.mesh
        owned = mesh.topology.index_map(1).size_local
        x = compat.cell_vertex_x(mesh)[:owned]
        low, high = np.minimum(x[:, 0], x[:, 1]), np.maximum(x[:, 0], x[:, 1])
        tol = 1e-12 * self.config.model.length
        inside = np.flatnonzero((low - tol <= s) & (s <= high + tol))
        rank = self.comm.rank if len(inside) else self.comm.size
        chosen = self.comm.allreduce(rank, op=MPI.MIN)
        if chosen == self.comm.size:
            raise ConfigError(f"point s = {s!r} lies outside the rod")
        if self.comm.rank != chosen:
            cache[key] = (np.empty(0, dtype=np.int32), np.empty(0))
            return cache[key]
        cell = int(inside[0])
        x0, x1 = x[cell]
        ref = (s - x0) / (x1 - x0)
        degree = self.config.model.mesh.degree
        if degree == 1:
            weights = np.array([1 - ref, ref])
        else:
            weights = np.array([(1 - ref) * (1 - 2 * ref), ref * (2 * ref - 1),
                                4 * ref * (1 - ref)])
        index = 0 if component == "x" else 1
        sub = self.problem.space.sub(index)
        dofs = np.asarray(sub.dofmap.cell_dofs(cell))
        cache[key] = (dofs.astype(np.int32), weights)
        return cache[key]

    def _output_state_derivative(self, spec) -> PETSc.Vec:
        """dJ/dw with Dirichlet rows zero."""
        vec = self._vector.duplicate()
        with vec.localForm() as local:
            local.set(0.0)
            if spec[0] == "tip":
                cache = self.__dict__.setdefault("_tip_dofs", {})
                if spec[1] not in cache:
                    cache[spec[1]] = self.problem.component_dofs(spec[1], "xL")
                local.array[cache[spec[1]]] += 1.0
            elif spec[0] == "point":
                dofs, weights = self._point_weights(spec[1], spec[2])
                np.add.at(local.array, dofs, weights)
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        if spec[0] == "pull_in":
            gradient = self.tendons.gradient(spec[1], self.problem.bcs)
            vec.axpy(-1.0, gradient)
            gradient.destroy()
        compat.set_bc(vec, self.problem.bcs, scale=0.0)
        return vec

    def _output_explicit(self, spec) -> np.ndarray:
        """dJ/dp at fixed state (nonzero for tendon pull-ins: the rest length moves with the
        offsets)."""
        if spec[0] != "pull_in":
            return np.zeros(len(self._params))
        index = spec[1]
        return (self._at_rest(lambda: self._length_derivatives(index))
                - self._length_derivatives(index))

    # --- distance of measured points to the deformed backbone -------------------------------
    def _curve(self):
        """(x0, x1, U, V): per cell of the whole mesh (gathered on every rank, sorted by x0) the
        end coordinates and the u and v dof values (basis order of `_point_weights`)."""
        mesh = self.problem.mesh
        owned = mesh.topology.index_map(1).size_local
        x = compat.cell_vertex_x(mesh)[:owned]
        local = compat.local_array(self.problem.w)
        parts = []
        for index in (0, 1):
            dofmap = self.problem.space.sub(index).dofmap
            cells = np.array([dofmap.cell_dofs(c) for c in range(owned)]).reshape(owned, -1)
            parts.append(local[cells])
        gathered = self.comm.allgather((x, parts[0], parts[1]))
        x = np.concatenate([g[0] for g in gathered])
        U = np.concatenate([g[1] for g in gathered])
        V = np.concatenate([g[2] for g in gathered])
        order = np.argsort(np.minimum(x[:, 0], x[:, 1]))
        return x[order], U[order], V[order]

    def _basis(self, ref):
        ref = np.asarray(ref, dtype=float)
        if self.config.model.mesh.degree == 1:
            return (np.stack([1 - ref, ref], -1), np.stack([-np.ones_like(ref),
                                                            np.ones_like(ref)], -1))
        return (np.stack([(1 - ref) * (1 - 2 * ref), ref * (2 * ref - 1), 4 * ref * (1 - ref)],
                         -1),
                np.stack([4 * ref - 3, 4 * ref - 1, 4 - 8 * ref], -1))

    def project(self, points) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Closest points of the deformed backbone r(S) = (S + u(S), v(S)) to ``points``
        (n, 2) (collective; the same answer on every rank): (S*, r(S*), unit tangent r'/|r'|
        at S*), S* in [0, L]."""
        from scipy.optimize import minimize_scalar

        x, U, V = self._curve()
        length = x[:, 1] - x[:, 0]

        def evaluate(cell, ref):
            phi, dphi = self._basis(ref)
            S = x[cell, 0] + ref * length[cell]
            r = np.array([S + phi @ U[cell], phi @ V[cell]])
            dr = np.array([1 + dphi @ U[cell] / length[cell], dphi @ V[cell] / length[cell]])
            return r, dr

        samples = np.linspace(0.0, 1.0, 9)
        phi, _ = self._basis(samples)
        Sx = x[:, :1] + samples[None, :] * length[:, None]
        X = Sx + U @ phi.T
        Y = V @ phi.T
        results = []
        for p in np.asarray(points, dtype=float).reshape(-1, 2):
            distance = (X - p[0]) ** 2 + (Y - p[1]) ** 2
            best = int(np.argmin(distance.min(axis=1)))
            candidates = []
            for cell in {max(best - 1, 0), best, min(best + 1, len(x) - 1)}:
                found = minimize_scalar(
                    lambda ref, c=cell, p=p: float(np.sum((evaluate(c, ref)[0] - p) ** 2)),
                    bounds=(0.0, 1.0), method="bounded", options={"xatol": 1e-13})
                candidates.append((found.fun, cell, float(found.x)))
            _, cell, ref = min(candidates)
            # polish with Newton on (r - p) . r' = 0 (the bounded search stops near 1e-13)
            for _ in range(3):
                r, dr = evaluate(cell, ref)
                h = 1e-6
                r2, dr2 = evaluate(cell, ref + h)
                ddr = (dr2 - dr) / h * length[cell]
                f = (r - p) @ dr
                df = (dr @ dr + (r - p) @ ddr) * length[cell]
                if df <= 0:
                    break
                ref = float(np.clip(ref - f / df, 0.0, 1.0))
            r, dr = evaluate(cell, ref)
            S = float(x[cell, 0] + ref * length[cell])
            results.append((S, r, dr / np.linalg.norm(dr)))
        S = np.array([item[0] for item in results])
        return S, np.array([item[1] for item in results]), np.array([item[2] for item in results])

    def backbone_distances(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Signed distances of ``points`` (n, 2) to the deformed backbone and their exact
        gradients (n, parameters) (collective). Interior closest point S*: d = n . (r(S*) - p),
        n = (-t_y, t_x) the unit normal; its derivative is n . dr/dp at fixed S (the
        tangential motion of S* and of n do not change d to first order, r - p being parallel
        to n). Closest point at an end: d = sign(n . (r - p)) |r - p| with derivative
        sign (r - p) / |r - p| . dr/dp (exact for |r - p| > 0)."""
        S, r, t = self.project(points)
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        normal = np.stack([-t[:, 1], t[:, 0]], axis=1)
        names = [f"{c}@{float(s)!r}" for s in S for c in ("x", "y")]
        grad = self.gradient(names).reshape(len(S), 2, -1) if len(S) else np.zeros((0, 2, 0))
        length = self.config.model.length
        values, rows = [], []
        for i, (s, point) in enumerate(zip(S, points, strict=True)):
            gap = r[i] - point
            side = float(normal[i] @ gap)
            if 1e-12 * length < s < length * (1 - 1e-12):
                values.append(side)
                rows.append(normal[i] @ grad[i])
            else:
                size = float(np.linalg.norm(gap))
                sign = 1.0 if side >= 0 else -1.0
                values.append(sign * size)
                rows.append(sign * (gap / size) @ grad[i] if size > 0 else normal[i] @ grad[i])
        cache = self.__dict__.get("_point_cache", {})
        if len(cache) > 20000:
            cache.clear()
        return np.array(values), np.array(rows).reshape(len(S), len(self._params))

    # --- the adjoint --------------------------------------------------------------------------
    def _factor(self) -> PETSc.KSP:
        nonlinear = self.run.snes.problem
        if self._A is None:
            self._A = compat.create_matrix(nonlinear.jacobian_form)
            ksp = PETSc.KSP().create(self.comm)
            ksp.setOperators(self._A)
            ksp.setType("preonly")
            pc = ksp.getPC()
            pc.setType("lu")
            pc.setFactorSolverType("mumps")
            pc.setFactorSetUpSolverType()
            pc.getFactorMatrix().setMumpsIcntl(14, SADDLE_POINT_WORKSPACE[1])
            self._ksp = ksp
        x = compat.vector_of(self.problem.w).copy()
        try:
            nonlinear.jacobian(None, x, self._A, self._A)
        finally:
            x.destroy()
        self._ksp.setOperators(self._A)
        self._ksp.setUp()
        return self._ksp

    def gradient(self, names: Sequence[str]) -> np.ndarray:
        """dJ_j/dp_k of the outputs ``names`` at the current equilibrium (collective):
        (len(names), len(parameters))."""
        specs = [parse_output(n, self.config.model.length) for n in names]
        for spec in specs:
            if spec[0] in ("pull_in", "tension"):
                self._check_tendon(spec[1])
        result = np.zeros((len(specs), len(self._params)))
        if not self._params or not specs:
            return result
        self._update_direction_constants()
        ksp = self._factor()
        r_p = self._residual_derivatives()
        adjoint = self._vector.duplicate()
        bordered = self._bordered(ksp) if self.controlled else None
        try:
            for j, spec in enumerate(specs):
                rhs = self._output_state_derivative(spec)
                ksp.solveTranspose(rhs, adjoint)
                explicit = self._output_explicit(spec)
                if bordered is not None:
                    y, gram, c_p = bordered
                    g_dot_z = np.array([g.dot(adjoint) for g in self._gradients])
                    j_tau = np.array([1.0 if spec == ("tension", i) else 0.0
                                      for i in self.controlled])
                    mu = np.linalg.solve(gram, g_dot_z - j_tau)
                    for m, y_m in zip(mu, y, strict=True):
                        adjoint.axpy(-m, y_m)
                    explicit = explicit - mu @ c_p
                result[j] = explicit - np.array([adjoint.dot(r) for r in r_p])
                rhs.destroy()
        finally:
            adjoint.destroy()
            if bordered is not None:
                for vec in bordered[0] + self._gradients:
                    vec.destroy()
        return result

    def _bordered(self, ksp):
        """Pull-in control: Y = K^-T G, G^T Y and the constraints' dC/dp rows
        (C_i = l_i(w) - l_i(rest) + load factor * pull_in_i)."""
        self._gradients = [self.tendons.gradient(i, self.problem.bcs) for i in self.controlled]
        y = []
        for g in self._gradients:
            out = g.duplicate()
            ksp.solveTranspose(g, out)
            y.append(out)
        gram = np.array([[g.dot(y_m) for y_m in y] for g in self._gradients])
        lam = float(self.problem.load_factor.value)
        c_p = np.zeros((len(self.controlled), len(self._params)))
        for row, i in enumerate(self.controlled):
            c_p[row] = (self._length_derivatives(i)
                        - self._at_rest(lambda i=i: self._length_derivatives(i)))
            for k, par in enumerate(self._params):
                if par.kind == "pull_in" and par.tendon == i:
                    c_p[row, k] += lam
        return y, gram, c_p

    def destroy(self) -> None:
        if self._ksp is not None:
            self._ksp.destroy()
            self._A.destroy()
            self._ksp = self._A = None
        for vec in getattr(self, "_rp", None) or []:
            vec.destroy()
        self._rp = None
        self._vector.destroy()
        self.run.destroy()


def sensitivities(raw: dict, outputs: Sequence[str], parameters: Sequence[str],
                  load_factor: float = 1.0, comm=MPI.COMM_WORLD) -> dict:
    """One-shot: {"values": {output: value}, "gradient": {output: {parameter: dJ/dp}}}."""
    model = RodSensitivity(raw, parameters, comm)
    try:
        model.solve(load_factor)
        values = model.outputs(outputs)
        grad = model.gradient(outputs)
    finally:
        model.destroy()
    return {"values": dict(zip(outputs, values.tolist(), strict=True)),
            "gradient": {o: dict(zip(parameters, row.tolist(), strict=True))
                         for o, row in zip(outputs, grad, strict=True)}}


# --- the 3D solid -------------------------------------------------------------------------------
SOLID_PARAMETERS = ("material.E", "material.nu", "loads.tip_force.0", "loads.tip_force.1",
                    "loads.tip_force.2", "tendons.<i>.tension")
SOLID_OUTPUTS = ("tip_u", "tip_v", "tip_w")


class SolidSensitivity:
    """Adjoint sensitivities of the 3D finger (``fe-beam solid``) tip displacement (the tip
    face's area average, outputs ``tip_u``, ``tip_v``, ``tip_w``) with respect to
    ``material.E`` and ``material.nu`` (neo-Hookean law, displacement formulation: mu and
    kappa are the small-strain ones of E, nu), ``loads.tip_force.0|1|2`` and
    ``tendons.<i>.tension`` (tension control). The tendon cables are not UFL forms: their
    residual is tau dl/du (`fe_beam.fem.solid.cable.TendonCable`), linear in the tension, so
    dR/dtau is the cable's own residual at unit tension times the load factor.

    Same interface as `RodSensitivity`: ``values``, ``set_values``, ``solve``, ``outputs``,
    ``gradient``, ``destroy``.
    """

    def __init__(self, raw: dict, parameters: Sequence[str] = (), comm=MPI.COMM_WORLD):

        config = parse_solid({k: v for k, v in raw.items() if k != "calibrate"})
        self.config, self.comm = config, comm
        self.parameters = list(parameters)
        for key in self.parameters:
            if not (key in ("material.E", "material.nu")
                    or re.fullmatch(r"loads\.tip_force\.[012]|tendons\.\d+\.tension", str(key))):
                raise ConfigError(f"parameter {key!r} is not a 3D-solid parameter (allowed: "
                                  f"{', '.join(SOLID_PARAMETERS)})")
        law = config.material
        if not isinstance(law, NeoHookean) or config.discretization.formulation == "mixed":
            if any(k.startswith("material.") for k in self.parameters):
                raise ConfigError("3D sensitivities by material.E / material.nu need the "
                                  "neo-hookean law in the displacement formulation")
        if any(t.controlled_by_pull_in for t in config.tendon_loads):
            raise ConfigError("3D sensitivities need tension-controlled tendons (a pull-in "
                              "controlled cable's tension is an unknown: not supported)")
        self.run = SolidRun(config, comm)
        self.problem = self.run.problem
        self._moduli = {"E": float(law.young_modulus), "nu": float(law.poisson_ratio)}
        self._tensions = [float(t.tension or 0.0) for t in self.problem.tendon_loads]
        self._params = [self._make(key) for key in self.parameters]
        self._selectors = [fem.Constant(self.problem.mesh, 0.0) for _ in self._params]
        self._build_forms()
        self._dirty = True
        self._A = self._ksp = None

    def _make(self, key: str) -> _Parameter:
        p = self.problem
        if key in ("material.E", "material.nu"):
            name = key.split(".")[1]
            factors = {"mu": fem.Constant(p.mesh, 0.0), "kappa": fem.Constant(p.mesh, 0.0)}
            par = _Parameter(key, "material", lambda n=name: self._moduli[n],
                             lambda v, n=name: self._set_modulus(n, v),
                             [(p.coefficients["mu"], factors["mu"]),
                              (p.coefficients["kappa"], factors["kappa"])])
            par.factors = factors
            return par
        m = re.fullmatch(r"loads\.tip_force\.([012])", key)
        if m:
            index = int(m.group(1))
            unit = np.zeros(3)
            unit[index] = 1.0
            scale = fem.Constant(p.mesh, 0.0)  # load factor / tip area
            par = _Parameter(key, "load", lambda: float(p.tip_force[index]),
                             lambda v: self._set_force(index, v),
                             [(p.traction, scale * ufl.as_vector(unit.tolist()))])
            par.scale = scale
            return par
        m = re.fullmatch(r"tendons\.(\d+)\.tension", key)
        if m:
            index = int(m.group(1))
            if index >= len(p.cables) or p.tendon_loads[index].controlled_by_pull_in:
                raise ConfigError(f"parameter {key!r}: no tension-controlled tendon {index} in "
                                  "the 3D finger")
            par = _Parameter(key, "tension", lambda: self._tensions[index],
                             lambda v: self._set_tension(index, v), [], tendon=index)
            return par
        raise ConfigError(f"parameter {key!r} is not a 3D-solid parameter (allowed: "
                          f"{', '.join(SOLID_PARAMETERS)})")

    # parameter changes -------------------------------------------------------------------
    def _set_modulus(self, name, value) -> None:
        self._moduli[name] = float(value)
        E, nu = self._moduli["E"], self._moduli["nu"]
        self.problem.coefficients["mu"].value = E / (2 * (1 + nu))
        self.problem.coefficients["kappa"].value = E / (3 * (1 - 2 * nu))

    def _set_force(self, index, value) -> None:
        self.problem.tip_force = np.array(self.problem.tip_force, dtype=float)
        self.problem.tip_force[index] = float(value)
        self.problem.set_load_factor(self.problem.load_factor)

    def _set_tension(self, index, value) -> None:
        import dataclasses as dc

        self._tensions[index] = float(value)
        loads = self.problem.tendon_loads
        loads[index] = dc.replace(loads[index], tension=float(value))
        self.problem.set_load_factor(self.problem.load_factor)

    def values(self) -> np.ndarray:
        return np.array([p.get() for p in self._params], dtype=float)

    def set_values(self, values) -> None:
        values = np.asarray(values, dtype=float).ravel()
        for par, value in zip(self._params, values, strict=True):
            if par.get() != value:
                par.put(value)
                self._dirty = True

    def _update_direction_constants(self) -> None:
        E, nu = self._moduli["E"], self._moduli["nu"]
        lam = float(self.problem.load_factor)
        for par in self._params:
            if par.key == "material.E":
                par.factors["mu"].value = 1 / (2 * (1 + nu))
                par.factors["kappa"].value = 1 / (3 * (1 - 2 * nu))
            elif par.key == "material.nu":
                par.factors["mu"].value = -E / (2 * (1 + nu) ** 2)
                par.factors["kappa"].value = 2 * E / (3 * (1 - 2 * nu) ** 2)
            elif par.kind == "load":
                par.scale.value = lam / self.problem.tip_area

    def _build_forms(self) -> None:
        form = RodSensitivity._derivative_form(self, self.problem.residual)
        self._dR = fem.form(form) if form is not None and form.integrals() else None
        self._vector = self.problem.problem.b.duplicate()
        ds_tip = self.problem.ds(_tip_tag())
        test = ufl.TestFunction(self.problem.W)
        v = test if self.problem.p is None else ufl.split(test)[0]
        self._tip_forms = [fem.form(v[i] * ds_tip) for i in range(3)]

    def _select(self, k: int) -> None:
        for j, selector in enumerate(self._selectors):
            selector.value = 1.0 if j == k else 0.0

    # solving ---------------------------------------------------------------------------
    def solve(self, load_factor: float = 1.0) -> None:
        """Equilibrium at ``load_factor``: Newton from the last equilibrium at the same load
        factor after a parameter change, load stepping otherwise."""
        load_factor = float(load_factor)
        if not self._dirty and load_factor == self.run.load_factor:
            return
        if self._dirty and self.run.load_factor == load_factor and load_factor > 0:
            self.problem.set_load_factor(load_factor)
            self.problem.solver.solve()
        else:
            if load_factor < self.run.load_factor:
                compat.local_array(self.problem.w)[:] = 0.0
                self.run.load_factor = 0.0
            self.problem.set_load_factor(self.run.load_factor)
            if load_factor > self.run.load_factor:
                self.run.advance(load_factor, self.config.stepping)
        self._dirty = False

    def outputs(self, names: Sequence[str]) -> np.ndarray:
        tip = self.problem.tip_displacement()
        index = {"tip_u": 0, "tip_v": 1, "tip_w": 2}
        for name in names:
            if name not in index:
                raise ConfigError(f"unknown 3D output {name!r}: outputs are "
                                  f"{', '.join(SOLID_OUTPUTS)}")
        return np.array([tip[index[n]] for n in names])

    def gradient(self, names: Sequence[str]) -> np.ndarray:
        self.outputs(names)
        index = {"tip_u": 0, "tip_v": 1, "tip_w": 2}
        self._update_direction_constants()
        nonlinear = self.problem.problem
        if self._A is None:
            self._A = nonlinear.A.duplicate()
            self._A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
            self._ksp = PETSc.KSP().create(self.comm)
            self._ksp.setType("preonly")
            self._ksp.getPC().setType("lu")
            self._ksp.getPC().setFactorSolverType("mumps")
        x = compat.vector_of(self.problem.w).copy()
        nonlinear.jacobian(None, x, self._A, self._A)
        self._ksp.setOperators(self._A)
        self._ksp.setUp()
        bcs = self.problem.bcs
        r_p = []
        lam = float(self.problem.load_factor)
        for k, par in enumerate(self._params):
            vec = self._vector.duplicate()
            with vec.localForm() as local:
                local.set(0.0)
            if par.kind == "tension":
                cable = self.problem.cables[par.tendon]
                saved, cable.tension = cable.tension, lam
                try:
                    cable.add_to_residual(x, vec)
                finally:
                    cable.tension = saved
                vec.assemble()
            elif self._dR is not None:
                self._select(k)
                compat.assemble_vector(vec, self._dR)
                vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            compat.set_bc(vec, bcs, scale=0.0)
            r_p.append(vec)
        result = np.zeros((len(names), len(self._params)))
        adjoint = self._vector.duplicate()
        for j, name in enumerate(names):
            rhs = self._vector.duplicate()
            with rhs.localForm() as local:
                local.set(0.0)
            compat.assemble_vector(rhs, self._tip_forms[index[name]])
            rhs.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            rhs.scale(1.0 / self.problem.tip_area)
            compat.set_bc(rhs, bcs, scale=0.0)
            self._ksp.solveTranspose(rhs, adjoint)
            result[j] = [-adjoint.dot(r) for r in r_p]
            rhs.destroy()
        for vec in r_p + [adjoint, x]:
            vec.destroy()
        return result

    def destroy(self) -> None:
        if self._ksp is not None:
            self._ksp.destroy()
            self._A.destroy()
        self._vector.destroy()
        self.run.destroy()


def _tip_tag() -> int:

    return TIP_TAG

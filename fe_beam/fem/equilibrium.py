"""The global equilibrium of a solved rod state, from quantities independent of the residual
Newton drove to zero (a run-time certificate, issue 28).

The rod as a free body: the support reactions (the assembled residual at the supported dofs,
rows Newton never solves for: what the supports must supply), the applied loads evaluated from
their definitions on the deformed shape (tip force and moment, dead or follower, distributed
loads and gravity, point forces, point moments) and the contact forces of the contact report
must sum to zero, forces and moments (about the origin, with the deformed positions).
Tendons: the potential tau * l is invariant under rigid motions of the rod, so a tendon
anchored in the rod exerts no net force or moment on it (its entry force on a supported node
is part of that support's reaction); it enters the balance as zero.

A Galerkin solution balances exactly for the translations and, in the plane, for the rotation
(the rigid motions lie in the finite-element space): what remains is the Newton residual at the
free dofs and any mismatch between the loads the model defines and those the residual holds.
A spatial rod interpolates rotation vectors, which is not objective: its moment balance carries
a discretisation defect of the interpolation, O(h^2p), which the check discounts
(`spatial_moment_allowance`).

`balance` is plain numpy; `rod_wrenches` gathers the terms of a problem (collective).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from fe_beam.fem import compat
from fe_beam.fem.mpi import assemble_scalar, global_sum
from fe_beam.fem.spatial_rod import spin_matrix
from fe_beam.model.spatial import rotation_matrix

__all__ = ["Wrench", "balance", "curved_moment_allowance", "rod_wrenches", "roundoff_force",
           "spatial_moment_allowance"]

#: the reactions' round-off in units of machine epsilon times the axial stiffness EA (measured
#: 0.2 .. 0.3 on steel rods of 3 to 200 elements, degree 1 and 2, at loads 1e-6 EI/L^2)
ROUNDOFF_FACTOR = 10.0
#: the hyperelastic section law's fibre stresses carry more round-off (the fibre's lateral
#: stretch by closed-form Newton steps, a^2 - 1/a of a ~ 1): its floor is this many times
#: the closed-form laws' (measured: Newton stagnates at 10 .. 35 eps EA at h/L = 1e-4)
HYPERELASTIC_ROUNDOFF = 100.0


@dataclass
class Wrench:
    """One term of the balance: a force [N] (3 components; planar z = 0) and its moment about
    the origin [N m] (3 components; planar only z)."""

    name: str
    force: np.ndarray
    moment: np.ndarray
    #: kept out of the load scale (e.g. the reactions: they balance the loads, not scale them)
    reaction: bool = False
    details: dict = field(default_factory=dict)


def _vector3(values) -> np.ndarray:
    array = np.zeros(3)
    values = np.atleast_1d(np.asarray(values, dtype=float))
    array[: len(values)] = values
    return array


def moment_of(position, force) -> np.ndarray:
    """r x F (3-vectors; planar positions and forces padded with z = 0)."""
    return np.cross(_vector3(position), _vector3(force))


def balance(wrenches: list[Wrench], length: float, internal: float = 0.0) -> dict:
    """The imbalance of a set of wrenches: ``force`` = |sum F| / F_ref, ``moment`` = |sum M| /
    M_ref with F_ref the largest force of a term (the loads and the reactions), ``internal``
    (the largest self-equilibrated force, e.g. the tendon tensions) or the largest moment over
    ``length`` (a couple alone), whichever is largest, and M_ref the
    largest of the terms' moments and F_ref * length; ``imbalance`` the larger of both (0 when
    nothing is loaded). Plain numpy."""
    forces = np.array([w.force for w in wrenches]) if wrenches else np.zeros((1, 3))
    moments = np.array([w.moment for w in wrenches]) if wrenches else np.zeros((1, 3))
    largest_moment = float(np.max(np.linalg.norm(moments, axis=1)))
    # a couple alone (a tip moment) leaves only round-off forces: its moment / length scales them
    f_ref = max(float(np.max(np.linalg.norm(forces, axis=1))), abs(float(internal)),
                largest_moment / float(length))
    m_ref = max(largest_moment, f_ref * float(length))
    total_f, total_m = forces.sum(axis=0), moments.sum(axis=0)
    force = float(np.linalg.norm(total_f)) / f_ref if f_ref > 0 else 0.0
    moment = float(np.linalg.norm(total_m)) / m_ref if m_ref > 0 else 0.0
    return {"imbalance": max(force, moment), "force": force, "moment": moment,
            "force_scale": f_ref, "moment_scale": m_ref,
            "sum_force": total_f.tolist(), "sum_moment": total_m.tolist()}


def spatial_moment_allowance(problem) -> float:
    """The relative moment defect a converged spatial rod may show (rotation-vector
    interpolation is not objective): 10 (Theta h / L)^(2p), Theta the largest nodal rotation
    angle, h / L the element size, p the degree (measured: 9.6e-5, 2.4e-5, 6.1e-6 at p = 1 and
    9.8e-7, 6.2e-8, 3.9e-9 at p = 2 on 4, 8, 16 elements with Theta = 0.3: 30 to 60 times
    below); 0 for a planar rod. Collective."""
    if not getattr(problem, "spatial", False):
        return 0.0
    values = compat.local_array(problem.w)
    dofs = [problem.component_dofs(name) for name in problem.components[3:6]]
    local = float(np.max(np.sqrt(sum(values[d] ** 2 for d in dofs)))) if len(dofs[0]) else 0.0
    largest = problem.comm.allreduce(local, op=MPI.MAX)
    ratio = 1.0 / max(problem.model.mesh.elements, 1)
    return float(10.0 * (largest * ratio) ** (2 * problem.model.mesh.degree))


#: the moment defect of curved rods per (h kappa)^(2p), p = 1, 2 (measured on a ring loaded by
#: a point force: 6.6e-3 and 3.7e-5, whatever the load; the allowance is about 8 and 27 times)
CURVED_ALLOWANCE = {1: 0.05, 2: 1e-3}


def curved_moment_allowance(problem) -> float:
    """The relative moment defect a planar structure with curved rods may show: the rigid
    rotation of an arc is not in the finite-element space (the nodes' exact positions, the
    displacement interpolated), so its discrete moment balance carries a defect
    CURVED_ALLOWANCE[p] (h kappa)^(2p) relative to the largest moment, h the element length and
    kappa the curvature (measured order 2p: 4.6e-4, 1.1e-4, 2.8e-5 with 24, 48, 96 linear
    elements on a ring, 3.5e-5, 2.8e-6, 1.7e-7 with 6, 12, 24 quadratic ones, independent of
    the load); 0 without curved rods."""
    structure = getattr(getattr(problem, "model", None), "structure", None)
    if structure is None:
        return 0.0
    degree = int(problem.model.mesh.degree)
    worst = max((abs(rod.curvature) * rod.length / rod.elements for rod in structure.rods),
                default=0.0)
    return float(CURVED_ALLOWANCE.get(degree, 1e-3) * worst ** (2 * degree))


def roundoff_force(problem) -> float:
    """The round-off of the assembled reactions [N]: the section forces EA eps are evaluated from
    strains that are differences of O(1) numbers, so each carries about machine epsilon times the
    largest of EA and GA (mean section area), whatever the load; a load below about 1e-7 EA
    cannot be balanced better than this. ``ROUNDOFF_FACTOR`` times that. Collective."""
    props = problem.section_props
    area = assemble_scalar(fem.form(props.A * ufl.dx(domain=problem.mesh)))
    area /= float(problem.model.length)
    modulus = max(float(problem.E.value), float(problem.G.value))
    factor = ROUNDOFF_FACTOR * (HYPERELASTIC_ROUNDOFF
                                if problem.model.options.law == "hyperelastic" else 1.0)
    return float(factor * np.finfo(float).eps * modulus * abs(area))


def residual_floor(problem) -> tuple[float, float]:
    """The round-off floor of a rod's Newton residual norm: (an absolute floor [N], a stiffness
    [N/m]). The absolute one is `roundoff_force` over the square root of the dofs (a residual
    at it leaves the sum of the reactions within `roundoff_force`, the global equilibrium's
    allowance); the stiffness is the tangent's scale max(EA, GA) / (element length) (law
    factor included), whose product with machine epsilon and the state's norm is the
    attainable residual of the Newton update (its linear solve's backward error: a fine mesh
    of a stiff slender rod stagnates there, 110 eps EA at 80 elements, h/L = 1e-3).
    Collective."""
    force = roundoff_force(problem)
    elements = max(int(problem.model.mesh.elements), 1)
    stiffness = force / ROUNDOFF_FACTOR / np.finfo(float).eps * elements / float(
        problem.model.length)
    return force / math.sqrt(max(int(problem.global_dofs), 1)), stiffness


def _reactions(problem) -> list[Wrench]:
    result = []
    chain = getattr(problem, "chain", None)
    for s, held in (problem.inner_reactions() if chain is not None else ()):
        # a structure's supported rod ends inside the mesh
        values = problem.point_values(s)
        reference = np.array(problem.reference_point(s))
        get = held.get
        if problem.spatial:
            force = np.array([get("u", 0.0), get("v", 0.0), get("w", 0.0)])
            conjugate = np.array([get(f"theta_{k}", 0.0) for k in "xyz"])
            moment = np.linalg.solve(spin_matrix(np.array(
                [values[f"theta_{k}"] for k in "xyz"])).T, conjugate)
            position = reference + np.array([values["u"], values["v"], values["w"]])
        else:
            force = np.array([get("u", 0.0), get("v", 0.0)])
            moment = np.array([0.0, 0.0, get("theta", 0.0)])
            position = reference + np.array([values["u"], values["v"]])
        result.append(Wrench(f"reaction s = {s:.6g}", _vector3(force),
                             moment_of(position, force) + _vector3(moment), reaction=True))
    for end in ("x0", "xL"):
        if not problem.model.supports.fixed(end):
            continue
        reaction = problem.end_reaction(end)
        values = problem.end_values(end)
        if problem.spatial:
            force = np.array([reaction["Fx"], reaction["Fy"], reaction["Fz"]])
            conjugate = np.array([reaction[f"M_theta_{k}"] for k in "xyz"])
            # the rotation rows are conjugate to the rotation vector: M_theta = T^T m
            spin = spin_matrix(values["rotation_vector"])
            moment = np.linalg.solve(spin.T, conjugate)
            position = np.array(values["position"])
        else:
            force = np.array([reaction["Fx"], reaction["Fy"]])
            moment = np.array([0.0, 0.0, reaction["M"]])
            X, Y = problem.reference_point(problem.end_x[end])
            position = np.array([X + values["u"], Y + values["v"]])
        result.append(Wrench(f"reaction {end}", _vector3(force),
                             moment_of(position, force) + _vector3(moment), reaction=True))
    return result


def _body_forms(problem):
    """(force forms, moment forms) of the distributed load and gravity per unit load factor on
    the current state (built once per problem)."""
    cached = getattr(problem, "_equilibrium_forms", None)
    if cached is not None:
        return cached
    body = problem.distributed + problem.rho * problem.section_props.A * problem.gravity
    x = ufl.SpatialCoordinate(problem.mesh)[0]
    if problem.spatial:
        d = problem.fields()[0]
        position = ufl.as_vector([x + d[0], d[1], d[2]])
        if getattr(problem, "chain", None) is not None:  # a chain: its reference position
            position = problem.chain.reference + d
        forces = [body[i] for i in range(3)]
        moment = ufl.cross(position, body)
        moments = [moment[i] for i in range(3)]
    else:
        u, v = problem.fields()[0], problem.fields()[1]
        forces = [body[0], body[1]]
        if getattr(problem, "chain", None) is not None:  # a chain: its reference position
            X, Y = problem.chain.reference[0], problem.chain.reference[1]
            moments = [(X + u) * body[1] - (Y + v) * body[0]]
        else:
            moments = [(x + u) * body[1] - v * body[0]]
    measure = problem.dx_loads
    cached = ([fem.form(f * measure) for f in forces], [fem.form(m * measure) for m in moments])
    problem._equilibrium_forms = cached
    return cached


def _body(problem, factor: float) -> Wrench | None:
    loads = problem.model.loads
    if not (np.any(loads.distributed) or np.any(loads.gravity)):
        return None
    forces, moments = _body_forms(problem)
    force = factor * np.array([assemble_scalar(f) for f in forces])
    moment = factor * np.array([assemble_scalar(m) for m in moments])
    return Wrench("distributed and gravity", _vector3(force),
                  moment if problem.spatial else np.array([0.0, 0.0, moment[0]]))


def _tip(problem, factor: float) -> list[Wrench]:
    loads = problem.model.loads
    force = np.asarray(problem.tip_force.value, dtype=float).reshape(-1)
    moment = np.asarray(problem.tip_moment.value, dtype=float).reshape(-1)
    if not (np.any(force) or np.any(moment)):
        return []
    values = problem.end_values("xL")
    if problem.spatial:
        position = np.array(values["position"])
        if loads.follower:
            R = np.array(rotation_matrix(values["rotation_vector"]))
            force, moment = R @ force, R @ moment
        moment3 = moment
    else:
        X, Y = problem.reference_point(problem.model.length)
        position = np.array([X + values["u"], Y + values["v"]])
        if loads.follower:
            theta = values["theta"]
            a1 = np.array([np.cos(theta), np.sin(theta)])
            d = np.array([-np.sin(theta), np.cos(theta)])
            force = force[0] * a1 + force[1] * d
        moment3 = np.array([0.0, 0.0, float(moment[0])])
    force, moment3 = factor * force, factor * moment3
    return [Wrench("tip load", _vector3(force), moment_of(position, force) + moment3)]


def _point_sums(problem, rows, fields, factor: float):
    """(x, the nodal fields' owned values summed over the ranks at x, times ``factor``) for
    each position of ``rows`` (a vertex shared by two ranks counts once)."""
    if not rows or not fields:
        return
    space = fields[0].function_space
    owned = space.dofmap.index_map.size_local
    for x in sorted({float(row[0]) for row in rows}):
        dofs = compat.locate_dofs_geometrical(space, problem.point_marker(x))
        dofs = np.asarray(dofs)[np.asarray(dofs) < owned]
        yield x, factor * np.array([global_sum(problem.comm, f.x.array[dofs].sum())
                                    for f in fields])


def _point_forces(problem, factor: float) -> list[Wrench]:
    result = []
    for x, force in _point_sums(problem, problem.model.loads.point_forces,
                                getattr(problem, "point_force_fields", None), factor):
        values = problem.point_values(x)
        if problem.spatial and getattr(problem, "chain", None) is not None:
            position = np.array(problem.reference_point(x)) + np.array(
                [values["u"], values["v"], values["w"]])
        elif problem.spatial:
            position = np.array([x + values["u"], values["v"], values["w"]])
        else:
            X, Y = problem.reference_point(x)
            position = np.array([X + values["u"], Y + values["v"]])
        result.append(Wrench(f"point force at x = {x:g}", _vector3(force),
                             moment_of(position, force)))
    return result


def _point_moments(problem, factor: float) -> list[Wrench]:
    """The point moments (dead, world axes: a couple, the same about every point)."""
    return [Wrench(f"point moment at x = {x:g}", np.zeros(3),
                   moment if problem.spatial else np.array([0.0, 0.0, moment[0]]))
            for x, moment in _point_sums(problem, problem.model.loads.point_moments,
                                         getattr(problem, "point_moment_fields", None), factor)]


def _contact(entries) -> list[Wrench]:
    result = []
    for entry in entries or ():
        moment = entry["moment"]
        moment = (_vector3(moment) if isinstance(moment, (list, tuple))
                  else np.array([0.0, 0.0, float(moment)]))
        result.append(Wrench(f"contact '{entry['name']}'", _vector3(entry["force"]), moment))
    return result


def rod_wrenches(problem, contact_entries=None) -> list[Wrench]:
    """Every term of the rod's balance in its current state (collective): the reactions of the
    supported ends, the applied loads at the problem's current values (load factor times the
    load constants, the point forces' nodal values: what a path's parameter scales), and the
    forces of ``contact_entries`` (`fe_beam.fem.contact.ContactSet.summary`)."""
    factor = float(problem.load_factor.value)
    terms = (_reactions(problem) + _tip(problem, factor) + _point_forces(problem, factor)
             + _point_moments(problem, factor))
    body = _body(problem, factor)
    if body is not None:
        terms.append(body)
    return terms + _contact(contact_entries)

"""Contact of the planar and the spatial rod with rigid obstacles, with Coulomb friction
(docs/theory.md, Contact with rigid obstacles): gaps, contact points and slips as
UFL, the augmented-Lagrangian energy, the slip traction's virtual work, and `ContactSet`, which
holds the multipliers and stick/slip states and measures the contact state.

Spatial rods: the section is its true shape in the plane of the current directors d2, d3
(`section_gap`, `fe_beam.model.obstacles.section_parts`: a rectangle, a union of rectangles
for a t-section, a disc for circles and tubes), flat, so that the rod's ends are flat faces.
The gap to a plane is its support function (a rectangle's nearest corner); to a sphere and to
an infinite cylinder the exact distance of the section rectangle; to a box and a finite
cylinder the largest gap to its faces (caps) and lateral surface (conservative near edges).
`fe_beam.model.obstacles.section_distance` is the numpy twin. Their friction (planes and
infinite cylinders) acts at the section's material point reaching farthest toward the
obstacle (`section_support`), with 2-vector slips in the tangent plane (`spatial_slip`),
tangential multipliers and slip directions (`spatial_stick_density`,
`spatial_slip_traction`, `coulomb_state_2d`).

Certificate (`ContactSet.surface`): the largest penetration over the rod's whole surface,
sampled with the numpy twin between the contact points, at the vertices and on the end
faces, and each obstacle's normal force recomputed from the pressures and the twin's
normals.

Friction (planar): the slip s of a contact point since the last accepted step
(`tangential_slip`), stuck points with the energy `stick_density` (Uzawa on lambda_t),
slipping ones with the traction `slip_traction` = +-mu p_n as virtual work (`ContactSet.work`);
`coulomb_state` updates the stick/slip state between Newton solves.

Gap. The section at x is the segment S(x) = {r + eta d : -below(x) <= eta <= above(x)} with
r = (x + u, v) the centreline, d = (-sin theta, cos theta) the section director and
below/above the section's extents (`fe_beam.model.obstacles.section_extents`: h(x)/2 each
side for a rectangle, also when tapered). The gap g(x) is the signed distance of S(x) to the
obstacle (`segment_gap`): for a plane the nearer end of the segment, i.e. the centreline offset
by the half-height on the side facing the obstacle; for a disc (planar cylinder or sphere) the
segment's point nearest the centre; for a box the largest face-plane distance. g >= 0 is
admissible. The numpy twins used by the configuration checks are in `fe_beam.model.obstacles`.

Enforcement (augmented Lagrangian, Alart-Curnier / Rockafellar): per obstacle the potential

    Pi_c = int 1/(2k) (<lambda - k g>_+^2 - lambda^2) dx
           + sum over the rod's two ends of 1/(2 k_e) (<lambda_e - k_e g_e>_+^2 - lambda_e^2)

with the multiplier lambda (a line pressure [N/m]) in a quadrature space of the contact rule
and one multiplier lambda_e [N] per end (the end sections are corners that touch first: the
elastica pushed on a floor touches with its tip's corner, which no interior Gauss point sees).
Its variation is -p dg with p = <lambda - k g>_+ >= 0: the pressure pushes the rod out. The
Uzawa update lambda <- p (`ContactSet.update`) between Newton solves drives the penetration to
zero, so the method is exact in the limit whatever k (`fe_beam.solvers.contact.ContactSolver`).

Newton never sees the kink of <.>_+: each Newton solve holds an active set chi (0/1 at every
contact point and end) fixed and solves the smooth problem with the energy
1/(2k) (chi (lambda - k g)^2 - lambda^2) (`active_set_density`); after it chi is set to
[lambda - k g > 0] (a primal-dual active-set step) and the solve repeated until chi no longer
changes, when p = chi (lambda - k g) = <lambda - k g>_+ exactly and the state solves the
augmented-Lagrangian equations. (Plain Newton on the C1 residual cycled between active sets
when a load step crossed the first touch: its first iterate overshoots deep into the obstacle.)

Quadrature: the contact integral has its own Gauss-Legendre rule of degree ``q`` (default 4 p
for elements of degree p: 2p + 1 points per element, e.g. 5 for P2), not the nodes alone: a P2
centreline may pass through an obstacle between nodes; the gap is measured (and the multipliers
live) at exactly these points and at the two ends.
"""

from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from fe_beam.fem import compat
from fe_beam.fem.mpi import global_sum
from fe_beam.fem.rotations import rotation
from fe_beam.fem.structure import chain_centreline, chain_reversed, chain_section_dims
from fe_beam.model.obstacles import (
    Box,
    ContactSettings,
    Cylinder,
    Obstacle,
    Plane,
    Sphere,
    section_circumradius,
    section_distance,
    section_extents,
    section_parts,
    segment_distance,
    translated,
)

__all__ = ["EDGE_ANGLE", "ContactSet", "active_set_density", "augmented_lagrangian_density",
           "box_edge_contact",
           "contact_point", "contact_pressure", "director", "coulomb_state",
           "coulomb_state_2d", "friction_return_map", "outward_normal", "plane_tangent_basis",
           "point_gap", "positive_part", "section_facing", "section_gap", "section_support",
           "segment_gap", "slip_traction",
           "spatial_friction_supported", "spatial_outward_normal", "spatial_slip",
           "spatial_slip_traction", "spatial_stick_density", "stick_density",
           "tangential_slip", "tube_gap"]


# --- pure functions returning UFL ---------------------------------------------------------------
def _feature_size(obstacle: Obstacle) -> float:
    """The obstacle's narrowest extent [m] (a plane: infinite)."""
    if isinstance(obstacle, (Sphere, Cylinder)):
        size = 2 * obstacle.radius
        if isinstance(obstacle, Cylinder) and obstacle.length is not None:
            size = min(size, obstacle.length)
        return float(size)
    if isinstance(obstacle, Box):
        return float(min(np.array(obstacle.max) - np.array(obstacle.min)))
    return float("inf")


def positive_part(value):
    """<value>_+ = max(value, 0) (its derivative is the Heaviside step: C1 energy)."""
    return ufl.conditional(ufl.gt(value, 0), value, 0)


# min and max through abs, not conditionals: their derivatives keep no conditional with a Zero
# branch (FFCx 0.5 fails on those: a box face's gap does not depend on one coordinate)
def _smaller(a, b):
    return (a + b - abs(a - b)) / 2


def _larger(a, b):
    return (a + b + abs(a - b)) / 2


def director(theta):
    """The section director d = (-sin theta, cos theta)."""
    return ufl.as_vector([-ufl.sin(theta), ufl.cos(theta)])


def point_gap(obstacle: Obstacle, p):
    """Signed distance (UFL) of the point p (a UFL vector of ``obstacle.dim`` components) to the
    obstacle, >= 0 outside (`fe_beam.model.obstacles.distance`). Dimension-agnostic."""
    if isinstance(obstacle, Plane):
        return ufl.dot(p - ufl.as_vector(obstacle.point), ufl.as_vector(obstacle.normal))
    if isinstance(obstacle, (Sphere, Cylinder)):
        centre = ufl.as_vector(obstacle.center if isinstance(obstacle, Sphere)
                               else obstacle.point)
        rel = p - centre
        if isinstance(obstacle, Cylinder) and obstacle.dim == 3:
            # the radial distance as sqrt(|rel|^2 - axial^2), not |rel - axial a|: an axis
            # along a coordinate axis would leave literal zeros in the projected vector, whose
            # derivatives FFCx 0.5 cannot generate code for
            axial = ufl.dot(rel, ufl.as_vector(obstacle.axis))
            radial = ufl.sqrt(positive_part(ufl.dot(rel, rel) - axial**2) + 1e-300)
            if obstacle.length is not None:
                return _finite_cylinder_gap(axial, radial, obstacle.radius, obstacle.length)
            return radial - obstacle.radius
        return ufl.sqrt(ufl.dot(rel, rel)) - obstacle.radius
    if isinstance(obstacle, Box):
        gaps = [ufl.dot(p - ufl.as_vector(point), ufl.as_vector(normal))
                for point, normal in obstacle.faces()]
        result = gaps[0]
        for gap in gaps[1:]:
            result = _larger(result, gap)
        return result
    raise TypeError(f"not an obstacle: {obstacle!r}")


def _plane_segment_gap(point, normal, r, d, below, above):
    n = ufl.as_vector(normal)
    dn = ufl.dot(d, n)
    return ufl.dot(r - ufl.as_vector(point), n) + _smaller(above * dn, -below * dn)


def segment_gap(obstacle: Obstacle, r, d, below, above):
    """Signed distance (UFL) of the section segment r + eta d, eta in [-below, above], to the
    obstacle: the gap of the rod's surface (module docstring). Plane: exact; disc: exact (the
    segment's point nearest the centre, eta clipped to the section); box: the largest
    face-plane distance (exact on the faces, conservative near the corners)."""
    if isinstance(obstacle, Plane):
        return _plane_segment_gap(obstacle.point, obstacle.normal, r, d, below, above)
    if isinstance(obstacle, (Sphere, Cylinder)):
        centre = ufl.as_vector(obstacle.center if isinstance(obstacle, Sphere)
                               else obstacle.point)
        eta = _larger(_smaller(ufl.dot(centre - r, d), above), -below)
        return point_gap(obstacle, r + eta * d)
    if isinstance(obstacle, Box):
        gaps = [_plane_segment_gap(point, normal, r, d, below, above)
                for point, normal in obstacle.faces()]
        result = gaps[0]
        for gap in gaps[1:]:
            result = _larger(result, gap)
        return result
    raise TypeError(f"not an obstacle: {obstacle!r}")


def contact_pressure(multiplier, gap, k):
    """p = <lambda - k g>_+ (>= 0; zero where the point is clear of the obstacle)."""
    return positive_part(multiplier - k * gap)


def augmented_lagrangian_density(multiplier, gap, k):
    """1/(2k) (<lambda - k g>_+^2 - lambda^2): its variation is -p dg, p the contact pressure;
    at lambda = 0 the plain penalty k/2 <-g>_+^2."""
    return (contact_pressure(multiplier, gap, k) ** 2 - multiplier**2) / (2 * k)


def active_set_density(multiplier, active, gap, k):
    """1/(2k) (chi (lambda - k g)^2 - lambda^2) at a fixed active set chi (0 or 1): smooth; equal
    to `augmented_lagrangian_density` where chi = [lambda - k g > 0], and its variation
    -chi (lambda - k g) dg the same."""
    return (active * (multiplier - k * gap) ** 2 - multiplier**2) / (2 * k)


def tube_gap(obstacle: Obstacle, r, radius):
    """Signed distance (UFL) of the spatial rod's surface, the tube of ``radius`` (the
    section's circumradius) about the centreline point r, to the obstacle: the centreline's
    distance minus the radius (exact for a plane, a sphere and a cylinder; a box: its
    face-plane distance, conservative near edges and corners)."""
    return point_gap(obstacle, r) - radius


def _abs_smooth(value):
    """|value| (its derivative sign(value), 0 at 0: a section face parallel to a plane)."""
    return abs(value)


def _plane_section_gap(point, normal, r, d2, d3, parts):
    """The gap of the section (`fe_beam.model.obstacles.section_parts`) to the half-space
    behind the plane through ``point`` with unit ``normal``: the support function, the
    centreline's distance less the section's reach toward the plane (a rectangle's nearest
    corner: half2 |n.d2| + half3 |n.d3|; a disc's rim: rho |n - (n.d1) d1|)."""
    n = ufl.as_vector(normal) if isinstance(normal, (tuple, list, np.ndarray)) else normal
    p = ufl.as_vector(point) if isinstance(point, (tuple, list, np.ndarray)) else point
    base = ufl.dot(r - p, n)
    n2, n3 = ufl.dot(d2, n), ufl.dot(d3, n)
    if "disc" in parts:
        return base - parts["disc"] * ufl.sqrt(n2**2 + n3**2 + 1e-300)
    result = None
    for offset, a2, a3 in parts["rectangles"]:
        gap = base + offset * n2 - a2 * _abs_smooth(n2) - a3 * _abs_smooth(n3)
        result = gap if result is None else _smaller(result, gap)
    return result


def _clip(value, low, high):
    return _larger(_smaller(value, high), low)


def _edge_parameter(numerator, denominator, bound):
    """clip(-numerator / denominator, -bound, bound) (UFL), the minimiser along an edge,
    written without the division where it saturates: an edge along the axis (denominator 0,
    numerator 0) takes the end bound sign(-numerator) = 0 with a zero derivative, as the
    support function's |n.d| does, instead of 0/0 and a Hessian of 1/denominator."""
    saturated = ufl.ge(abs(numerator), bound * denominator)
    return ufl.conditional(saturated, -bound * ufl.sign(numerator),
                           -numerator / (denominator + 1e-150))


def _rectangle_line_distance(w, u, v, a2, a3):
    """min over |s| <= a2, |t| <= a3 of |w + s u + t v| (UFL; `fe_beam.model.obstacles`
    twin): the best of the four edges, and 0 where the unconstrained minimiser lies inside
    (the line pierces the section)."""
    uu, vv, uv = ufl.dot(u, u), ufl.dot(v, v), ufl.dot(u, v)
    wu, wv = ufl.dot(w, u), ufl.dot(w, v)
    tiny = 1e-300
    # the two opposite edges first: equal in value when the section is symmetric about the
    # axis (a planar problem: d3 along it), whose min is then their mean with its mean
    # derivative exactly (sign(0) = 0), as the plane's |n.d3|; min-of-min in another order
    # would pick one side's out-of-plane derivative by round-off
    pairs = []
    for first in (True, False):
        values = []
        for sign in (-1.0, 1.0):
            if first:
                s = sign * a2
                t = _edge_parameter(wv + s * uv, vv, a3)
            else:
                t = sign * a3
                s = _edge_parameter(wu + t * uv, uu, a2)
            e = w + s * u + t * v
            values.append(ufl.sqrt(ufl.dot(e, e) + tiny))
        pairs.append(_smaller(*values))
    best = _smaller(*pairs)
    det = uu * vv - uv**2
    safe = det + 1e-12 * uu * vv + 1e-24
    s0, t0 = (-wu * vv + wv * uv) / safe, (-wv * uu + wu * uv) / safe
    pierced = ufl.conditional(ufl.And(ufl.gt(det, 1e-12 * uu * vv),
                                      ufl.And(ufl.le(abs(s0), a2), ufl.le(abs(t0), a3))),
                              1.0, 0.0)
    return (1 - pierced) * best


def section_gap(obstacle: Obstacle, r, R, parts, axis=None):
    """Signed distance (UFL) of the spatial rod's section at the centreline point r, rotated
    by R (columns d1, d2, d3) and of the shape ``parts``
    (`fe_beam.model.obstacles.section_parts`), to the obstacle: the section's true shape, flat
    (the end faces at the rod's ends). `fe_beam.model.obstacles.section_distance` is the numpy
    twin and states where it is exact (plane, sphere, infinite cylinder with rectangles) and
    where a lower bound (conservative: a disc on a cylinder at an oblique angle, box and
    finite-cylinder edges). ``axis``: a cylinder's axis as a UFL value (a Constant: FFCx 0.5
    cannot generate the derivatives of the literal zeros a coordinate axis leaves)."""
    d1, d2, d3 = (ufl.as_vector([R[0, c], R[1, c], R[2, c]]) for c in range(3))
    if isinstance(obstacle, Plane):
        return _plane_section_gap(obstacle.point, obstacle.normal, r, d2, d3, parts)
    if isinstance(obstacle, Box):
        result = None
        for point, normal in obstacle.faces():
            gap = _plane_section_gap(point, normal, r, d2, d3, parts)
            result = gap if result is None else _larger(result, gap)
        return result
    if isinstance(obstacle, Sphere):
        c = ufl.as_vector(obstacle.center)
        if "disc" in parts:
            q = c - r
            q = q - ufl.dot(q, d1) * d1
            size = ufl.sqrt(ufl.dot(q, q) + 1e-300)
            scale = _smaller(1.0, parts["disc"] / size)
            e = c - r - scale * q
            return ufl.sqrt(ufl.dot(e, e) + 1e-300) - obstacle.radius
        result = None
        for offset, a2, a3 in parts["rectangles"]:
            q = c - r - offset * d2
            s = _clip(ufl.dot(q, d2), -a2, a2)
            t = _clip(ufl.dot(q, d3), -a3, a3)
            e = q - s * d2 - t * d3
            gap = ufl.sqrt(ufl.dot(e, e) + 1e-300)
            result = gap if result is None else _smaller(result, gap)
        return result - obstacle.radius
    if isinstance(obstacle, Cylinder):
        a = ufl.as_vector(obstacle.axis) if axis is None else axis
        p = ufl.as_vector(obstacle.point)

        def project(x):
            return x - ufl.dot(x, a) * a

        if "disc" in parts:
            w = project(r - p)  # the disc's tube (a lower bound, exact when a = d1)
            lateral = ufl.sqrt(ufl.dot(w, w) + 1e-300) - parts["disc"] - obstacle.radius
        else:
            lateral = None
            for offset, a2, a3 in parts["rectangles"]:
                gap = _rectangle_line_distance(project(r + offset * d2 - p), project(d2),
                                               project(d3), a2, a3)
                lateral = gap if lateral is None else _smaller(lateral, gap)
            lateral = lateral - obstacle.radius
        if obstacle.length is None:
            return lateral
        for sign in (-1.0, 1.0):
            cap = _plane_section_gap(p + sign * obstacle.length / 2 * a, sign * a, r, d2, d3,
                                     parts)
            lateral = _larger(lateral, cap)
        return lateral
    raise TypeError(f"not an obstacle: {obstacle!r}")


def _part_columns(parts) -> list:
    """The section's shape as expression columns (`ContactSet._spatial_local` reads them):
    a disc's radius, or (offset, half2, half3) per rectangle."""
    if "disc" in parts:
        return [parts["disc"]]
    return [value for rectangle in parts["rectangles"] for value in rectangle]


def section_support(R, normal, parts):
    """The body-frame offset (0, eta2, eta3) (UFL) of the section point reaching farthest
    toward -``normal`` (the obstacle's outward normal): the point of the section in contact
    with a plane (a rectangle's corner, or the middle of an edge or face parallel to the
    plane; a disc's rim point), where the spatial friction acts."""
    m = ufl.dot(ufl.transpose(R), -normal)
    if "disc" in parts:
        size = ufl.sqrt(m[1] ** 2 + m[2] ** 2 + 1e-300)
        return ufl.as_vector([0, parts["disc"] * m[1] / size, parts["disc"] * m[2] / size])
    best, eta2, eta3 = None, None, None
    for offset, a2, a3 in parts["rectangles"]:
        reach = offset * m[1] + a2 * abs(m[1]) + a3 * abs(m[2])
        e2, e3 = offset + a2 * ufl.sign(m[1]), a3 * ufl.sign(m[2])
        if best is None:
            best, eta2, eta3 = reach, e2, e3
            continue
        pick = (1 + ufl.sign(reach - best)) / 2
        eta2, eta3 = pick * e2 + (1 - pick) * eta2, pick * e3 + (1 - pick) * eta3
        best = _larger(best, reach)
    return ufl.as_vector([0, eta2, eta3])


def _finite_cylinder_gap(rel_axial, rel_radial, radius, length):
    """Signed distance to a solid cylinder of ``radius`` and ``length`` centred on its point:
    q = (rho - R, |a| - l/2); min(max(q), 0) + |<q>_+| (exact inside and outside)."""
    q_r = rel_radial - radius
    q_a = abs(rel_axial) - length / 2
    outside = ufl.sqrt(positive_part(q_r) ** 2 + positive_part(q_a) ** 2 + 1e-300)
    return _smaller(_larger(q_r, q_a), 0) + outside


def contact_point(obstacle: Obstacle, r, d, below, above):
    """The point of the planar section segment r + eta d, eta in [-below, above], that
    `segment_gap` measures (UFL): a plane's nearer end, a disc's nearest point, the nearer end
    toward the box face whose plane is farthest. Friction acts there."""
    if isinstance(obstacle, Plane):
        return r + _plane_facing_eta(obstacle.normal, d, below, above) * d
    if isinstance(obstacle, (Sphere, Cylinder)):
        centre = ufl.as_vector(obstacle.center if isinstance(obstacle, Sphere)
                               else obstacle.point)
        eta = _larger(_smaller(ufl.dot(centre - r, d), above), -below)
        return r + eta * d
    if isinstance(obstacle, Box):
        gap, eta = _box_face_select(obstacle, r, d, below, above, lambda n: _plane_facing_eta(
            n, d, below, above))
        return r + eta * d
    raise TypeError(f"not an obstacle: {obstacle!r}")


def _plane_facing_eta(normal, d, below, above):
    """eta of the segment's end facing a plane of ``normal``: above when d.n < 0 (no
    conditional: its derivative, sign' = 0, keeps no Zero branch)."""
    dn = ufl.dot(d, ufl.as_vector(normal))
    return (above - below) / 2 - (above + below) / 2 * ufl.sign(dn)


def _box_face_select(obstacle: Box, r, d, below, above, value_of):
    """(the largest face-plane segment gap, ``value_of(normal)`` of that face): the pairwise
    selection weight (1 + sign(g_a - g_b)) / 2 picks the larger face."""
    faces = obstacle.faces()
    gap, value = None, None
    for point, normal in faces:
        g = _plane_segment_gap(point, normal, r, d, below, above)
        v = value_of(normal)
        if gap is None:
            gap, value = g, v
            continue
        pick = (1 + ufl.sign(g - gap)) / 2
        value = pick * v + (1 - pick) * value
        gap = _larger(gap, g)
    return gap, value


def outward_normal(obstacle: Obstacle, p):
    """The obstacle's unit outward normal (UFL) at the planar point p on (or near) its
    surface: a plane's n, a disc's (p - C)/|p - C|, a box's face normal of the largest
    face-plane distance."""
    if isinstance(obstacle, Plane):
        return ufl.as_vector(obstacle.normal)
    if isinstance(obstacle, (Sphere, Cylinder)):
        centre = ufl.as_vector(obstacle.center if isinstance(obstacle, Sphere)
                               else obstacle.point)
        rel = p - centre
        return rel / ufl.sqrt(ufl.dot(rel, rel))
    if isinstance(obstacle, Box):
        faces = obstacle.faces()
        gap, normal = None, None
        for point, n in faces:
            g = ufl.dot(p - ufl.as_vector(point), ufl.as_vector(n))
            if gap is None:
                gap, normal = g, ufl.as_vector(n)
                continue
            pick = (1 + ufl.sign(g - gap)) / 2
            normal = pick * ufl.as_vector(n) + (1 - pick) * normal
            gap = _larger(gap, g)
        return normal
    raise TypeError(f"not an obstacle: {obstacle!r}")


def tangential_slip(obstacle: Obstacle, p, p_reference):
    """The slip s (UFL, planar): the increment of the contact point's tangential position on
    the obstacle from ``p_reference`` (the contact point of the last accepted state) to p,
    along t = (-n_y, n_x) (n the outward normal, t counterclockwise): a plane (p - p0).t
    (exact); a disc R atan2(a0 x a, a0 . a) with a = p - C (the arc length, exact); a box
    (p - p0).t of the current face."""
    if isinstance(obstacle, (Sphere, Cylinder)):
        centre = ufl.as_vector(obstacle.center if isinstance(obstacle, Sphere)
                               else obstacle.point)
        a, a0 = p - centre, p_reference - centre
        return obstacle.radius * compat.atan2(a0[0] * a[1] - a0[1] * a[0], ufl.dot(a0, a))
    n = outward_normal(obstacle, p)
    return ufl.dot(p - p_reference, ufl.as_vector([-n[1], n[0]]))


def stick_density(multiplier, stick, slip, k):
    """The tangential augmented-Lagrangian energy of a stuck point (stick = 1; 0 where the
    point slips or is clear): stick/(2k) ((lambda_t - k s)^2 - lambda_t^2), its variation
    -stick (lambda_t - k s) ds: the Uzawa updates lambda_t <- lambda_t - k s drive the slip of
    a stuck point to zero."""
    return stick * ((multiplier - k * slip) ** 2 - multiplier**2) / (2 * k)


def slip_traction(direction, mu, pressure):
    """The tangential traction of a slipping point (UFL): direction mu p_n, direction = +-1
    (the sign of the trial traction when the point began to slip: against the slip), p_n the
    current normal pressure. Not a potential: its virtual work p_t ds enters the residual
    (`ContactSet.work`), so that Newton sees the bound |p_t| = mu p_n exactly."""
    return direction * mu * pressure


def friction_return_map(trial: np.ndarray, bound: np.ndarray):
    """Coulomb's return map (numpy): (p_t, stuck) with p_t = trial where |trial| <= bound
    (stick), else bound sign(trial) (slip); bound = mu p_n >= 0."""
    trial, bound = np.asarray(trial, dtype=float), np.asarray(bound, dtype=float)
    stuck = (np.abs(trial) <= bound) & (bound > 0)
    return np.where(stuck, trial, np.sign(trial) * bound), stuck


def coulomb_state(trial, slip, pressure, mu, stick, direction, slack: float = 0.0):
    """The next stick/slip state of contact points (numpy; the primal-dual active-set step
    of friction): (stuck, direction, traction). A point that slipped in the last solve
    (stick 0, direction +-1) keeps slipping while it slides against its traction (slip
    direction <= 0), else sticks; any other pressed point sticks while its trial traction
    lambda_t - k s is within mu p_n, else slips along sign(trial). Clear points (p_n = 0):
    neither. traction: the stuck points' trial, the slipping ones' direction mu p_n.
    ``slack`` [m]: a slip this small along the traction still counts as sliding against it
    (round-off of a point that stopped at the verge)."""
    trial, slip, pressure = (np.asarray(a, dtype=float) for a in (trial, slip, pressure))
    bound = mu * pressure
    pressed = pressure > 0
    was_slipping = (np.asarray(stick) < 0.5) & (np.asarray(direction) != 0)
    keeps = was_slipping & (slip * np.asarray(direction) <= slack)
    mapped, stuck_map = friction_return_map(trial, bound)
    stuck = pressed & np.where(was_slipping, ~keeps, stuck_map)
    new_direction = np.where(was_slipping & keeps, np.asarray(direction),
                             np.where(stuck, 0.0, np.sign(trial)))
    new_direction = np.where(pressed & ~stuck, new_direction, 0.0)
    traction = np.where(stuck, np.clip(trial, -bound, bound), new_direction * bound)
    return stuck, new_direction, traction


# --- friction of the spatial rod (the tube's tangent plane) -----------------------------------
def spatial_friction_supported(obstacle: Obstacle) -> bool:
    """Friction of a spatial rod is available on planes and infinite cylinders (their tangent
    planes have a global basis and an exact slip measure; `spatial_slip`)."""
    return isinstance(obstacle, Plane) or (isinstance(obstacle, Cylinder)
                                           and obstacle.length is None)


def plane_tangent_basis(normal) -> tuple[np.ndarray, np.ndarray]:
    """(t1, t2): an orthonormal basis of the plane of unit ``normal`` (3D, numpy): t1 the
    coordinate axis least aligned with n, made orthogonal to it; t2 = n x t1."""
    n = np.asarray(normal, dtype=float)
    e = np.eye(3)[int(np.argmin(np.abs(n)))]
    t1 = e - (e @ n) * n
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n, t1)


def _radial(obstacle: Cylinder, p):
    rel = p - ufl.as_vector(obstacle.point)
    axis = ufl.as_vector(obstacle.axis)
    return rel - ufl.dot(rel, axis) * axis


def spatial_outward_normal(obstacle: Obstacle, p):
    """The unit outward normal (UFL) of a plane or a cylinder at (near) the 3D point p."""
    if isinstance(obstacle, Plane):
        return ufl.as_vector(obstacle.normal)
    if isinstance(obstacle, Cylinder):
        a = _radial(obstacle, p)
        return a / ufl.sqrt(ufl.dot(a, a))
    raise TypeError(f"friction of a spatial rod needs a plane or a cylinder: {obstacle!r}")


def spatial_slip(obstacle: Obstacle, p, p_reference):
    """The slip s (UFL 2-vector) of a spatial rod's contact point: the increment of its
    position on the obstacle's surface from ``p_reference`` (the contact point of the last
    accepted state) to p, in the tangent basis (t1, t2): a plane ((p - p0).t1, (p - p0).t2)
    with the fixed basis of `plane_tangent_basis` (exact); a cylinder of axis a and radius R
    ((p - p0).a, R atan2(a0 x a1 . a, a0 . a1)), a0 and a1 the radial parts of p0 and p
    (the axial and the arc length, exact; t2 = a x n, counterclockwise about a)."""
    if isinstance(obstacle, Plane):
        t1, t2 = plane_tangent_basis(obstacle.normal)
        step = p - p_reference
        return ufl.as_vector([ufl.dot(step, ufl.as_vector(t1)), ufl.dot(step, ufl.as_vector(t2))])
    if isinstance(obstacle, Cylinder):
        axis = ufl.as_vector(obstacle.axis)
        a, a0 = _radial(obstacle, p), _radial(obstacle, p_reference)
        turn = compat.atan2(ufl.dot(ufl.cross(a0, a), axis), ufl.dot(a0, a))
        return ufl.as_vector([ufl.dot(p - p_reference, axis), obstacle.radius * turn])
    raise TypeError(f"friction of a spatial rod needs a plane or a cylinder: {obstacle!r}")


def section_facing(R, normal):
    """The body-frame unit vector m of the section's (d2, d3) plane pointing toward the
    obstacle (UFL): R^T (-n) without its d1 part, normalised. The material point of the tube
    at r + rho R m is the contact point friction acts on."""
    m = ufl.dot(ufl.transpose(R), -normal)
    size = ufl.sqrt(m[1] ** 2 + m[2] ** 2 + 1e-300)
    return ufl.as_vector([0, m[1] / size, m[2] / size])


def spatial_stick_density(multiplier, stick, slip, k):
    """The 2D `stick_density`: stick/(2k) (|lambda_t - k s|^2 - |lambda_t|^2), lambda_t and s
    2-vectors in the tangent basis."""
    trial = multiplier - k * slip
    return stick * (ufl.dot(trial, trial) - ufl.dot(multiplier, multiplier)) / (2 * k)


def spatial_slip_traction(direction, slip, k, mu, pressure, eps):
    """The traction of a slipping point (UFL 2-vector): Coulomb's return map
    mu p_n t/|t| of the trial traction t = mu p_n e - k s, e the unit ``direction`` of the
    last update (the slipping point's multiplier is mu p_n e); regularised by ``eps`` (a
    slipping point's |t| is about mu p_n or more). The updates repeat until e is t/|t|
    again: there the slip is opposite to the friction."""
    bound = mu * pressure
    trial = bound * direction - k * slip
    return bound * trial / ufl.sqrt(ufl.dot(trial, trial) + eps**2)


def coulomb_state_2d(trial, slip, pressure, mu, stick, direction, slack: float = 0.0):
    """`coulomb_state` with 2-vector tractions and slips (numpy, shape (n, 2)): (stuck,
    direction (n, 2), traction (n, 2)). A point that slipped in the last solve keeps slipping
    while it slides against its traction (slip . direction <= slack), its direction the trial
    traction's; any other pressed point sticks while |trial| <= mu p_n, else slips along
    trial/|trial|; stuck points' traction is the trial (scaled back onto the disc if it passed
    it), slipping points' mu p_n direction."""
    trial, slip = (np.asarray(a, dtype=float).reshape(-1, 2) for a in (trial, slip))
    direction = np.asarray(direction, dtype=float).reshape(-1, 2)
    pressure = np.asarray(pressure, dtype=float)
    bound = mu * pressure
    pressed = pressure > 0
    size = np.linalg.norm(trial, axis=1)
    unit = trial / np.maximum(size, 1e-300)[:, None]
    was_slipping = (np.asarray(stick) < 0.5) & (np.linalg.norm(direction, axis=1) > 0.5)
    keeps = was_slipping & (np.sum(slip * direction, axis=1) <= slack)
    stuck = pressed & np.where(was_slipping, ~keeps, (size <= bound) & (bound > 0))
    slipping = pressed & ~stuck
    new_direction = np.where(slipping[:, None], unit, 0.0)
    scale = np.where(size > bound, bound / np.maximum(size, 1e-300), 1.0)
    traction = np.where(stuck[:, None], trial * scale[:, None],
                        new_direction * bound[:, None])
    return stuck, new_direction, traction


#: the largest angle [degrees] between a pressed box face's normal and the rod's surface normal
#: that `box_edge_contact` accepts near an edge or corner
EDGE_ANGLE = 5.0


def box_edge_contact(box: Box, r, tangent, below, above, d=None, spacing: float = 0.0):
    """(flags, angles) per contact point (numpy): is the section at the centreline point r
    (shape (n, dim)) in contact with an edge or corner of the box rather than a face? Planar
    (d given, the section director): the section segment r + eta d, eta in [-below, above];
    spatial (d None): the tube of radius ``below`` (= ``above``). The face whose plane gap is
    the largest (the one `segment_gap` / `tube_gap` measures) is at an edge when another,
    adjacent face's plane gap is within one section thickness (below + above) plus twice
    the ``spacing`` of the contact points too (an edge may pass between two of them); such a
    point is flagged when that face's normal n is more than `EDGE_ANGLE` off the rod's
    surface normal, i.e. |n . t| > sin(EDGE_ANGLE) with t the rod's ``tangent`` (the section
    normal). ``angles``: asin |n . t| [degrees]. A rod flat on a face near its edge, and a rod's
    end corner on a face's interior, are face contacts (not flagged)."""
    r = np.asarray(r, dtype=float)
    below = np.broadcast_to(np.asarray(below, dtype=float), r.shape[:1])
    above = np.broadcast_to(np.asarray(above, dtype=float), r.shape[:1])
    faces = [(np.asarray(p, dtype=float), np.asarray(n, dtype=float)) for p, n in box.faces()]
    gaps = []
    for point, normal in faces:
        plane = (r - point) @ normal
        if d is None:
            gaps.append(plane - below)
        else:
            dn = np.asarray(d, dtype=float) @ normal
            gaps.append(plane + np.minimum(above * dn, -below * dn))
    gaps = np.stack(gaps, axis=1)
    chosen = np.argmax(gaps, axis=1)
    normals = np.stack([n for _, n in faces])
    selected = normals[chosen]
    width = below + above + 2 * spacing
    near = np.zeros(len(r), dtype=bool)
    for f, (_, normal) in enumerate(faces):
        adjacent = np.abs(selected @ normal) < 0.5  # neither the face itself nor its opposite
        near |= adjacent & (gaps[:, f] > -width)
    along = np.abs(np.sum(selected * np.asarray(tangent, dtype=float), axis=1))
    angles = np.degrees(np.arcsin(np.clip(along, 0.0, 1.0)))
    return near & (angles > EDGE_ANGLE), angles


# --- the obstacles of one problem ----------------------------------------------------------------
#: a point of an accepted state whose gap is below this share of the penetration tolerance
#: (below the tolerance where the obstacle is not pressed yet: a first touch) grazes the
#: obstacle: the next solve starts with it active (`ContactSet.restore`)
GRAZING = 1e-2


class ContactSet:
    """The obstacles of one `fe_beam.fem.rod.BeamProblem` (planar: the section segment) or
    `fe_beam.fem.spatial_rod.SpatialRodProblem` (the section's true shape, `section_gap`):
    multipliers, the energy hook (``energy(problem, parts)``, like
    `fe_beam.fem.tendons.TendonSet`), the Uzawa and friction updates and the measured
    contact state. Built before the problem; attached on the first ``energy``."""

    def __init__(self, obstacles, settings: ContactSettings | None, model):
        self.obstacles = tuple(obstacles)
        self.settings = settings or ContactSettings()
        self.model = model
        self.spatial = getattr(model, "kinematics", "planar") == "spatial"
        self.dim = 3 if self.spatial else 2
        self.friction = [float(getattr(o, "friction", 0.0) or 0.0) for o in self.obstacles]
        if self.spatial and any(mu > 0 and not spatial_friction_supported(o)
                                for o, mu in zip(self.obstacles, self.friction, strict=True)):
            raise ValueError("contact: friction of spatial rods is available on planes and "
                             "infinite cylinders only")
        #: the friction state's per-point names (the spatial rod's 2-vectors by component)
        self._names = (("multiplier_0", "multiplier_1", "stick", "direction_0", "direction_1")
                       if self.spatial else ("multiplier", "stick", "direction"))
        self.tolerance = self.settings.tolerance(model.section)
        self._problem = None
        #: the time or load factor of the moving obstacles' translations (`move`)
        self.parameter = 0.0
        self.moving = [o.motion is not None for o in self.obstacles]

    @property
    def frictional(self) -> list[int]:
        return [i for i, mu in enumerate(self.friction) if mu > 0]

    # --- set-up ------------------------------------------------------------------------------
    def energy(self, problem, parts):
        """sum over the obstacles of the augmented-Lagrangian potential of the state
        ``parts`` (normal, and with friction the tangential one of the current stick/slip
        state)."""
        if self._problem is not problem:
            self._attach(problem)
        world = self._geometry(parts)
        total = 0
        for i, obstacle in enumerate(self.obstacles):
            geometry = self._relative(world, i)
            gap = self._gap_of(obstacle, geometry)
            total += active_set_density(self.multipliers[i], self.active[i], gap,
                                        self.k) * self.dx
            for e, measure in enumerate(self._end_measures):
                total += active_set_density(self.end_multipliers[i][e], self.end_active[i][e],
                                            gap, self.k_end) * measure
            if i in self._friction and self.spatial:
                total += self._spatial_stick_energy(i, geometry)
            elif i in self._friction:
                f = self._friction[i]
                point = self._point_of(obstacle, geometry)
                slip = tangential_slip(obstacle, point, ufl.as_vector(f["reference"]))
                total += stick_density(f["multiplier"], f["stick"], slip, self.k) * self.dx
                for e, measure in enumerate(self._end_measures):
                    end = f["ends"][e]
                    slip = tangential_slip(obstacle, point, end["reference"])
                    total += stick_density(end["multiplier"], end["stick"], slip,
                                           self.k_end_friction) * measure
        return total

    def work(self, problem, parts, test):
        """The virtual work of the slipping points' friction, int p_t ds with p_t = direction
        mu p_n (`slip_traction`), p_n the fixed-active-set pressure chi (lambda - k g):
        subtracted from the residual (a non-potential force: the tangent is not symmetric)."""
        if self._problem is not problem:
            self._attach(problem)
        world = self._geometry(parts)
        total = 0
        for i, f in self._friction.items():
            obstacle = self.obstacles[i]
            geometry = self._relative(world, i)
            gap = self._gap_of(obstacle, geometry)
            if self.spatial:
                total += self._spatial_slip_work(i, geometry, gap, problem, test)
                continue
            point = self._point_of(obstacle, geometry)
            pressure = self.active[i] * (self.multipliers[i] - self.k * gap)
            slip = tangential_slip(obstacle, point, ufl.as_vector(f["reference"]))
            total += (1 - f["stick"]) * slip_traction(f["direction"], f["mu"], pressure) \
                * ufl.derivative(slip, problem.w, test) * self.dx
            for e, measure in enumerate(self._end_measures):
                end = f["ends"][e]
                pressure = self.end_active[i][e] * (self.end_multipliers[i][e]
                                                    - self.k_end * gap)
                slip = tangential_slip(obstacle, point, end["reference"])
                total += (1 - end["stick"]) * slip_traction(end["direction"], f["mu"],
                                                            pressure) \
                    * ufl.derivative(slip, problem.w, test) * measure
        return total

    def _geometry(self, parts, variables: bool = False) -> dict:
        """The rod's surface data of the state ``parts``: centreline r and (planar) the
        rotation theta, director d and extents below/above, or (spatial) the tube radius;
        ``variables``: r and theta as UFL variables (for the resultants' densities)."""
        x = ufl.SpatialCoordinate(self._problem.mesh)[0]
        chain = getattr(self._problem, "chain", None)
        if self.spatial:
            d, theta = parts
            r = (ufl.as_vector([x + d[0], d[1], d[2]]) if chain is None
                 else chain_centreline(chain, d))
            if variables:
                r = ufl.variable(r)
            R = rotation(theta)
            if chain is not None:  # a chain of rods: the world rotation R_inc R0
                R = ufl.dot(R, chain.frame0)
            if variables:
                R = ufl.variable(R)
            return {"r": r, "radius": self._radius, "theta": theta, "R": R,
                    "parts": self._parts}
        u, v, theta = parts
        r = ufl.as_vector([x + u, v]) if chain is None else chain_centreline(chain, (u, v))
        if variables:
            r, theta = ufl.variable(r), ufl.variable(theta)
        below, above = self._extents()
        # a chain of rods: the section director at the world angle theta0 + theta
        d = director(theta) if chain is None else director(chain.theta0 + theta)
        return {"r": r, "theta": theta, "d": d, "below": below, "above": above}

    def _relative(self, geometry: dict, i: int) -> dict:
        """The rod's surface data in the frame of obstacle i: a moving obstacle's translation
        c (a Constant: no recompilation as it moves) subtracted from the centreline, so that
        its gap, contact point and slip (relative to the obstacle) are those of the fixed
        shape."""
        if not self.moving[i]:
            return geometry
        return dict(geometry, r=geometry["r"] - self.offsets[i])

    def _gap_of(self, obstacle, geometry):
        if self.spatial:
            return section_gap(obstacle, geometry["r"], geometry["R"], geometry["parts"],
                               self._axes.get(id(obstacle)))
        return segment_gap(obstacle, geometry["r"], geometry["d"], geometry["below"],
                           geometry["above"])

    def _point_of(self, obstacle, geometry):
        return contact_point(obstacle, geometry["r"], geometry["d"], geometry["below"],
                             geometry["above"])

    def _attach(self, problem) -> None:
        self._problem = problem
        mesh, model = problem.mesh, self.model
        degree = self.settings.quadrature_degree or 4 * model.mesh.degree
        self.degree = degree
        import basix

        self.points, self._reference_weights = basix.make_quadrature(basix.CellType.interval,
                                                                     degree)
        self.space = compat.function_space(mesh, compat.quadrature_element(mesh, degree))
        # own integration domain (tag 1) so that the quadrature coefficient sits in a kernel
        # with one rule (`fe_beam.solvers.energy_momentum`: FFCx 0.5 merges the integrals of one
        # domain, and evaluated such coefficients wrongly in kernels with several rules)
        index_map = mesh.topology.index_map(1)
        cells = np.arange(index_map.size_local + index_map.num_ghosts, dtype=np.int32)
        tags = compat.meshtags(mesh, 1, cells, np.ones(len(cells), dtype=np.int32))
        self.dx = ufl.Measure("dx", domain=mesh, subdomain_data=tags, subdomain_id=1,
                              metadata={"quadrature_degree": degree})
        self._end_measures = (problem.ds_start, problem.ds_tip)
        # k = penalty EI_min / h_e^4 (line pressure per unit gap); at the ends the point
        # stiffness k_e = penalty max(EI_min / h_e^3, EA_min / h_e) = k * end_length: an end
        # pushed along the rod's axis (into a wall) acts against the axial stiffness, which
        # for a slender rod is (h_e / h)^2 times the bending one; a penalty below it leaves the
        # Uzawa updates converging at the rate 1 - k_e / (EA / L) (tens of updates per step)
        if self.spatial:
            props = [model.section.spatial_properties(s) for s in (0.0, 1.0)]
            inertia = min(min(float(p.Iz), float(p.Iy)) for p in props)
        else:
            props = [model.section.properties(s) for s in (0.0, 1.0)]
            inertia = min(float(p.I) for p in props)
        area = min(float(p.A) for p in props)
        bending = float(model.material.E) * inertia
        h_e = float(problem.h_min)
        self.k_value = self.settings.penalty * bending / h_e**4
        #: k_e / k [m]: h_e, or h_e (EA h_e^2 / EI) where the axial stiffness is the larger
        self.end_length = h_e * max(1.0, area * h_e**2 / inertia)
        #: the rod's force scale EI_min / L^2 [N]: the floor of the contact forces' accuracy
        #: (`fe_beam.solvers.contact.ContactSolver`: error <= force_tolerance (F + this))
        self.force_scale = bending / float(model.length) ** 2
        self._base_k = self.k_value
        self.k = fem.Constant(mesh, self.k_value)
        self.k_end = fem.Constant(mesh, self.k_value * self.end_length)
        #: the ends' tangential (stick) stiffness k h_e: a slip of an end is resisted by the
        #: rod's bending
        self.friction_end_length = h_e
        self.k_end_friction = fem.Constant(mesh, self.k_value * h_e)
        count = len(self.obstacles)
        self.multipliers = [fem.Function(self.space, name=f"contact_multiplier_{i}")
                            for i in range(count)]
        self.end_multipliers = [[fem.Constant(mesh, 0.0), fem.Constant(mesh, 0.0)]
                                for _ in range(count)]
        self.active = [fem.Function(self.space, name=f"contact_active_{i}")
                       for i in range(count)]
        self.end_active = [[fem.Constant(mesh, 0.0), fem.Constant(mesh, 0.0)]
                           for _ in range(count)]
        # friction: tangential multiplier, stick flag, slip traction and the contact point of
        # the last accepted state, at every contact point and end
        self._friction = {}
        for i in self.frictional:
            if self.spatial:
                self._friction[i] = self._spatial_friction_storage(i)
                continue
            self._friction[i] = {
                "multiplier": fem.Function(self.space, name=f"friction_multiplier_{i}"),
                "stick": fem.Function(self.space, name=f"friction_stick_{i}"),
                "direction": fem.Function(self.space, name=f"friction_direction_{i}"),
                "reference": [fem.Function(self.space, name=f"friction_reference_{i}_{c}")
                              for c in range(self.dim)],
                "mu": fem.Constant(mesh, self.friction[i]),
                "ends": [{"multiplier": fem.Constant(mesh, 0.0),
                          "stick": fem.Constant(mesh, 0.0),
                          "direction": fem.Constant(mesh, 0.0),
                          "reference": fem.Constant(mesh, np.zeros(self.dim))}
                         for _ in range(2)]}
        self.offsets = [fem.Constant(mesh, np.asarray(o.translation(self.parameter), dtype=float))
                        if self.moving[i] else None for i, o in enumerate(self.obstacles)]
        x = ufl.SpatialCoordinate(mesh)[0]
        self._s = x / model.length
        if self.spatial:
            self._radius = section_circumradius(model.section, self._s, self._dims(problem),
                                                problem.section_dims_tip)
            self._parts = section_parts(model.section, self._s, self._dims(problem),
                                        problem.section_dims_tip)
            flip = self._flip(problem)
            if flip is not None:  # a reversed rod: its frame's d2 is the rod's -d2
                self._parts = {"rectangles": [((1 - 2 * flip) * offset, half2, half3)
                                              for offset, half2, half3
                                              in self._parts["rectangles"]]}
            self._axes = {id(o): fem.Constant(mesh, np.asarray(o.axis, dtype=float))
                          for o in self.obstacles if isinstance(o, Cylinder)}
        self._build_measures(problem, x)
        self._set_references(None)
        self._committed = self._copy()
        self._positions = None
        self._pressed = None

    def set_stiffness(self, k: float) -> None:
        """The augmentation stiffness k [N/m per m of gap] (the ends' k h_e): e.g. dynamics,
        whose time step stiffens the rod by its mass / (beta dt^2). The multipliers are
        pressures (independent of k): the converged state does not depend on it."""
        self.k_value = float(k)
        self.k.value = self.k_value
        self.k_end.value = self.k_value * self.end_length
        self.k_end_friction.value = self.k_value * self.friction_end_length

    @property
    def base_stiffness(self) -> float:
        """k of the settings: penalty EI_min / h_e^4."""
        return self._base_k

    def move(self, value: float) -> None:
        """The moving obstacles to their place at time / load factor ``value`` (the
        translation Constants of the compiled forms)."""
        self.parameter = float(value)
        if self._problem is None:
            return
        for i, obstacle in enumerate(self.obstacles):
            if self.moving[i]:
                self.offsets[i].value[:] = obstacle.translation(self.parameter)

    def translations(self) -> list[np.ndarray]:
        """Each obstacle's current translation from its configured place [m]."""
        return [np.array(self.offsets[i].value, dtype=float) if self.moving[i]
                and self._problem is not None else o.translation(self.parameter)
                for i, o in enumerate(self.obstacles)]

    def new_contact(self) -> bool:
        """Whether the current state presses a contact point or end that the last accepted
        state (`commit`) did not press: an impact (collective)."""
        state = self.evaluate(friction=False)
        local = False
        for i in range(len(self.obstacles)):
            now = np.asarray(state["pressure"][i]) > 0
            ends = np.asarray(state["end_pressure"][i]) > 0
            if self._pressed is None:
                before, before_ends = np.zeros_like(now), np.zeros_like(ends)
            else:
                before, before_ends = self._pressed[i]
            local = local or bool(np.any(now & ~before)) or bool(np.any(ends & ~before_ends))
        return bool(self._problem.comm.allreduce(local, op=MPI.LOR))

    def resultant(self, index: int) -> np.ndarray:
        """The force of obstacle ``index`` on the rod in the current forms' state (global
        axes, normal and friction parts) [N]; collective."""
        comm = self._problem.comm
        forms = self._resultant_forms[index]
        force = np.array([global_sum(comm, fem.assemble_scalar(form))
                          for form in forms["normal"][:self.dim]])
        if "friction" in forms:
            force = force + np.array([global_sum(comm, fem.assemble_scalar(form))
                                      for form in forms["friction"][:self.dim]])
        return force

    def placed(self) -> list:
        """The obstacles at their current place (`fe_beam.model.obstacles.translated`): for
        the outputs of moving obstacles."""
        return [translated(o, c) for o, c in zip(self.obstacles, self.translations(),
                                                  strict=True)]

    def set_friction(self, index: int, mu: float) -> None:
        """Change the friction coefficient of obstacle ``index`` (one built with friction > 0)
        along the load path, e.g. a frictionless approach, then friction: mu >= 0."""
        if index not in self._friction:
            raise ValueError(f"contact: obstacle {index} was built without friction")
        if not mu >= 0:
            raise ValueError(f"contact: friction must be >= 0; got {mu!r}")
        self._friction[index]["mu"].value = float(mu)
        self.friction[index] = float(mu)

    def _extents(self):
        problem = self._problem
        below, above = section_extents(self.model.section, self._s, self._dims(problem),
                                       problem.section_dims_tip)
        flip = self._flip(problem)
        if flip is not None:  # a reversed rod: its own sides swapped in the chain's frame
            below, above = flip * above + (1 - flip) * below, flip * below + (1 - flip) * above
        return below, above

    def _flip(self, problem):
        """Along a chain of rods with an asymmetric section (a t-section), the DG0 indicator
        of the rods traversed from their end (`fe_beam.fem.structure.chain_reversed`), else
        None."""
        chain = getattr(problem, "chain", None)
        if chain is None or self.model.section.shape != "t-section":
            return None
        return chain_reversed(chain)

    @staticmethod
    def _dims(problem):
        """The section dimensions of the forms: the problem's, or along a chain of rods with
        their own sections each rod's (DG0 fields, `fe_beam.fem.structure.ChainGeometry`)."""
        chain = getattr(problem, "chain", None)
        return (chain_section_dims(chain) if chain is not None else None) \
            or problem.section_dims

    def _build_measures(self, problem, x) -> None:
        """Compiled expressions at the contact points and forms of the resultants."""
        parts = problem.state_parts() if self.spatial else problem.fields()[:3]
        world = self._geometry(parts, variables=True)
        r = world["r"]
        geometry = world
        columns = [x] + [r[c] for c in range(self.dim)]
        if self.spatial:
            # the section normal d1 = R e1 (the centreline's tangent): `edge_contact`
            R = geometry["R"]
            columns += [geometry["radius"]] + [R[c, j] for j in range(3) for c in range(3)]
            columns += _part_columns(geometry["parts"])
        else:
            columns += [geometry["d"][0], geometry["d"][1], geometry["below"],
                        geometry["above"]]
        self._base_columns = len(columns)
        self._obstacle_columns = []
        resultant_forms, end_forms = [], []
        for i, obstacle in enumerate(self.obstacles):
            geometry = self._relative(world, i)
            gap = self._gap_of(obstacle, geometry)
            where = {"gap": len(columns)}
            columns.append(gap)
            pressure = self.active[i] * (self.multipliers[i] - self.k * gap)
            end_pressures = [self.end_active[i][e] * (self.end_multipliers[i][e]
                                                      - self.k_end * gap) for e in range(2)]
            # densities (force, moment) of a traction p on the "coordinate" g (gap or slip):
            # the force p dg/dr, the moment about the origin r x that (+ p dg/dtheta planar)
            parts_of = [(pressure, end_pressures, gap, "normal")]
            ends_of = {"gap": [fem.form(gap * m) for m in self._end_measures]}
            if i in self._friction and self.spatial:
                self._spatial_friction_measures(i, geometry, columns, where, pressure,
                                                end_pressures, ends_of)
            elif i in self._friction:
                f = self._friction[i]
                point = self._point_of(obstacle, geometry)
                slip = tangential_slip(obstacle, point, ufl.as_vector(f["reference"]))
                where["slip"] = len(columns)
                columns.append(slip)
                where["point"] = len(columns)
                columns += [point[c] for c in range(self.dim)]
                traction = (f["stick"] * (f["multiplier"] - self.k * slip)
                            + (1 - f["stick"]) * slip_traction(f["direction"], f["mu"],
                                                               pressure))
                end_tractions, end_slips = [], []
                for e in range(2):
                    end = f["ends"][e]
                    end_slip = tangential_slip(obstacle, point, end["reference"])
                    end_slips.append(end_slip)
                    end_tractions.append(end["stick"] * (end["multiplier"]
                                                        - self.k_end_friction * end_slip)
                                         + (1 - end["stick"]) * slip_traction(
                                             end["direction"], f["mu"], end_pressures[e]))
                parts_of.append((traction, end_tractions, (slip, end_slips), "friction"))
                ends_of["slip"] = [fem.form(s * m) for s, m in zip(end_slips,
                                                                  self._end_measures,
                                                                  strict=True)]
                ends_of["point"] = [[fem.form(point[c] * m) for c in range(self.dim)]
                                    for m in self._end_measures]
            forms = {}
            if "friction_forms" in ends_of:
                forms["friction"] = ends_of.pop("friction_forms")
            for interior, ends, coordinate, label in parts_of:
                inner, end_coordinates = (coordinate if isinstance(coordinate, tuple)
                                          else (coordinate, [coordinate, coordinate]))
                totals = None
                for p, g, measure in [(interior, inner, self.dx)] + [
                        (ends[e], end_coordinates[e], self._end_measures[e]) for e in range(2)]:
                    densities = self._densities(g, world)
                    terms = [p * density * measure for density in densities]
                    totals = terms if totals is None else [a + b for a, b in
                                                           zip(totals, terms, strict=True)]
                forms[label] = [fem.form(t) for t in totals]
            resultant_forms.append(forms)
            end_forms.append(ends_of)
            self._obstacle_columns.append(where)
        self._columns = len(columns)
        self._expression = compat.expression(ufl.as_vector(columns), self.points)
        # the rod's geometry at points dense enough that no obstacle fits between two of them
        # (`between_points`): an obstacle narrower than the contact points' spacing
        lengths = np.ptp(compat.cell_vertex_x(problem.mesh), axis=1)
        longest = problem.comm.allreduce(float(np.max(lengths)) if len(lengths) else 0.0,
                                         op=MPI.MAX)
        narrowest = min([_feature_size(o) for o in self.obstacles] + [np.inf])
        # at least 17 per element: also the whole-surface penetration (`surface`)
        count = 17 if not np.isfinite(narrowest) else int(np.clip(
            np.ceil(8 * longest / narrowest) + 1, 17, 513))
        self._narrowest = narrowest
        self._dense_expression = compat.expression(
            ufl.as_vector(columns[:self._base_columns]), np.linspace(0.0, 1.0, count)[:, None])
        self._resultant_forms = resultant_forms
        self._end_forms = end_forms
        index_map = problem.mesh.topology.index_map(1)
        self._owned_cells = np.arange(index_map.size_local, dtype=np.int32)
        self._dofs = compat.cell_dofs(self.space)[: len(self._owned_cells)].ravel()
        # each owned contact point's share of the reference length [m] (pressures times these
        # are forces), in the order of ``_dofs``
        lengths = np.ptp(compat.cell_vertex_x(problem.mesh)[: len(self._owned_cells)], axis=1)
        self._weights = (lengths[:, None] * self._reference_weights[None, :]).ravel()
        # the largest distance between neighbouring contact points [m] (within an element
        # and across its ends): a box edge can pass between two of them (`edge_contact`)
        rule = np.sort(np.asarray(self.points, dtype=float).ravel())
        steps = np.concatenate([np.diff(rule), [rule[0] + 1.0 - rule[-1]]])
        self._spacing = float(np.max(lengths, initial=0.0)) * float(np.max(steps))
        self._spacing = float(problem.comm.allreduce(self._spacing, op=MPI.MAX))

    def _densities(self, g, geometry) -> list:
        """Force and moment densities per unit traction on the coordinate g: dg/dr and
        r x dg/dr (+ dg/dtheta planar): dim + (1 planar | 3 spatial) entries."""
        r = geometry["r"]
        g_r = ufl.diff(g, r)
        if self.spatial:
            # the moment the solver applies: the virtual work of p g under a rigid rotation
            # (delta r = w x r, delta d_c = w x d_c) is w . (r x dg/dr + sum_c d_c x dg/dd_c),
            # the section's orientation term the true shape's gap (its support point off
            # the centreline) adds to the centreline's moment
            R = geometry["R"]
            moment = ufl.cross(r, g_r)
            g_R = ufl.diff(g, R)
            for c in range(3):
                moment = moment + ufl.cross(ufl.as_vector([R[j, c] for j in range(3)]),
                                            ufl.as_vector([g_R[j, c] for j in range(3)]))
            return [g_r[c] for c in range(3)] + [moment[c] for c in range(3)]
        return [g_r[0], g_r[1], r[0] * g_r[1] - r[1] * g_r[0] + ufl.diff(g, geometry["theta"])]

    # --- state -------------------------------------------------------------------------------
    def _copy(self):
        """The multipliers and flags (the state a solve starts from)."""
        friction = {i: {n: f[n].x.array.copy() for n in self._names}
                    | {"ends": [{n: float(end[n].value) for n in self._names}
                                for end in f["ends"]]}
                    for i, f in self._friction.items()}
        return ([m.x.array.copy() for m in self.multipliers],
                [[float(c.value) for c in ends] for ends in self.end_multipliers], friction)

    def _set(self, copy) -> None:
        """Multipliers from a copy, and the active set they imply (lambda > 0)."""
        interior, ends, friction = copy
        for function, active, values in zip(self.multipliers, self.active, interior,
                                            strict=True):
            function.x.array[:] = values
            function.x.scatter_forward()
            active.x.array[:] = values > 0
            active.x.scatter_forward()
        for constants, flags, values in zip(self.end_multipliers, self.end_active, ends,
                                            strict=True):
            for constant, flag, value in zip(constants, flags, values, strict=True):
                constant.value = value
                flag.value = 1.0 if value > 0 else 0.0
        for i, f in self._friction.items():
            for name in self._names:
                f[name].x.array[:] = friction[i][name]
                f[name].x.scatter_forward()
            for end, values in zip(f["ends"], friction[i]["ends"], strict=True):
                for name in self._names:
                    end[name].value = values[name]

    def _set_references(self, state: dict | None) -> None:
        """The friction reference points: the contact points of ``state`` (None: the
        undeformed rod's), installed now."""
        self._references = self._reference_values(state)
        self._install_references(self._references)

    def _reference_values(self, state: dict | None) -> dict:
        """Per obstacle with friction, the reference points of the slip: the contact points
        of ``state`` (None: the undeformed rod's), interior and ends, and (spatial) the
        material points facing the obstacle there."""
        references = {}
        if not self._friction:
            return references
        values = None
        for i in self._friction:
            if state is None:
                # the undeformed contact point (x, +-extent): the current (zero) state's
                values = values if values is not None else self.evaluate(friction=False)
                where = self._obstacle_columns[i]["point"]
                points = values["raw"][:, where:where + self.dim].copy()
                ends = [self._assemble_end_point(i, e) for e in range(2)]
            else:
                points = np.array(state["friction"][i]["point"], dtype=float)
                ends = [np.array(p, dtype=float) for p in state["friction"][i]["end_point"]]
            entry = {"points": points, "ends": ends}
            if self.spatial:  # the material points facing the obstacle now
                where = self._obstacle_columns[i]["facing"]
                raw = values["raw"] if state is None else state["raw"]
                entry["body"] = raw[:, where:where + 3].copy()
                entry["end_body"] = [np.array([global_sum(self._problem.comm,
                                                          fem.assemble_scalar(form))
                                               for form in self._end_forms[i]["facing"][e]])
                                     for e in range(2)]
            references[i] = entry
        return references

    def _install_references(self, references: dict) -> None:
        """Put `_reference_values` into the forms' reference functions and constants."""
        for i, entry in references.items():
            f = self._friction[i]
            for c, function in enumerate(f["reference"]):
                function.x.array[self._dofs] = entry["points"][:, c]
                function.x.scatter_forward()
            for end, point in zip(f["ends"], entry["ends"], strict=True):
                end["reference"].value[:] = point
            if self.spatial:
                for c, function in enumerate(f["body"]):
                    function.x.array[self._dofs] = entry["body"][:, c]
                    function.x.scatter_forward()
                for end, body in zip(f["ends"], entry["end_body"], strict=True):
                    end["body"].value[:] = body

    def _assemble_end_point(self, i, e) -> np.ndarray:
        return np.array([global_sum(self._problem.comm, fem.assemble_scalar(form))
                         for form in self._end_forms[i]["point"][e]])

    def restore(self) -> None:
        """Multipliers back to those of the last accepted state (`commit`), the friction's
        reference points to its contact points (a solve measures its slip from them), and its
        active set: the pressed points and those that graze it unpressed (GRAZING).
        A grazing first touch at the end of a load step leaves points at g ~ 0 with no
        pressure; started inactive, the next step's first Newton solve would sink the rod
        through the obstacle and the active set would then chatter back over tens of
        updates; started active, they hold at g = 0 and are released if pulled."""
        self._set(self._committed)
        self._install_references(self._references)
        touching = getattr(self, "_touching", None)
        if touching is not None:
            for i, (interior, ends) in enumerate(touching):
                active = self.active[i]
                active.x.array[self._dofs] = np.maximum(active.x.array[self._dofs], interior)
                active.x.scatter_forward()
                for flag, end in zip(self.end_active[i], ends, strict=True):
                    flag.value = max(float(flag.value), float(end))
        if self.spatial and self._friction:  # a solve starts with the wide regularisation
            self._regularisation.value = float(self.tolerance)

    def commit(self) -> None:
        """The current state is accepted: its pressures and friction tractions start the next
        solve (warm start), its contact points are the friction's reference (the slip of the
        next step is measured from them) and its surface positions the reference of the
        tunnelling check. The new multipliers and references are stored, not installed: until
        the next solve (`restore`) the forms keep the multipliers, stick/slip state and slip
        of the accepted solve, so `summary`, `cell_pressures` and the result files report the
        forces the solver applied (reference points moved now would zero the stuck points'
        slip, and their traction lambda_t - k s would read the stale lambda_t)."""
        state = self.evaluate()
        interior = []
        for i, _ in enumerate(self.obstacles):
            values = self.multipliers[i].x.array.copy()
            values[self._dofs] = state["pressure"][i]
            interior.append(values)
        ends = [list(state["end_pressure"][i]) for i in range(len(self.obstacles))]
        friction = {}
        for i, f in self._friction.items():
            entry = state["friction"][i]
            copies = {}
            for name, values in self._state_values(entry).items():
                array = f[name].x.array.copy()
                array[self._dofs] = values
                copies[name] = array
            copies["ends"] = [{name: float(values[e]) for name, values in
                               self._state_values(entry, "end_").items()} for e in range(2)]
            friction[i] = copies
        self._committed = (interior, ends, friction)  # ghosts: set by `_set`'s scatter
        self._references = self._reference_values(state)
        self._positions = self._dense_local()
        self._positions_offsets = self.translations()
        self._pressed = [(np.asarray(state["pressure"][i]) > 0,
                          np.asarray(state["end_pressure"][i]) > 0)
                         for i in range(len(self.obstacles))]
        self._touching = []
        for i, (interior, ends) in enumerate(self._pressed):
            # not yet pressed (a first touch): every point within the tolerance grazes
            pressed = self._problem.comm.allreduce(bool(interior.any() or ends.any()),
                                                   op=MPI.LOR)
            grazing = (GRAZING if pressed else 1.0) * self.tolerance
            self._touching.append((np.asarray(state["gap"][i]) <= grazing,
                                   np.asarray(state["end_gap"][i]) <= grazing))

    def save(self):
        """The accepted contact state (multipliers, friction state, positions, pressed
        points), for `load` (the continuation engine's snapshots)."""
        if self._problem is None:
            return None
        return (self._committed, self._positions, self._pressed,
                getattr(self, "_positions_offsets", None), getattr(self, "_touching", None),
                self._references)

    def load(self, saved) -> None:
        """Back to a `save`d accepted state (its multipliers and active set in place)."""
        if saved is None or self._problem is None:
            return
        (self._committed, self._positions, self._pressed, offsets, self._touching,
         self._references) = saved
        if offsets is not None:
            self._positions_offsets = offsets
        self.restore()

    def orientation(self, tangent) -> int:
        """The way on at a point where the rod came into contact (points pressed now that
        were not at the last accepted state): +1 when moving the state along ``tangent`` (a
        PETSc Vec of the state's layout, the path's unit tangent) presses the pressed points
        further into the obstacle (their gaps shrink: the pressures grow), -1 when it lifts
        them off (back toward the contact-free path it came from), 0 elsewhere or when the
        gaps do not change (collective). The arc-length engine reverses a tangent with -1: at a
        contact corner the path may turn by more than a right angle, where the predictor's
        direction points the wrong way."""
        state = self.evaluate(friction=False)
        comm = self._problem.comm
        now = [(np.asarray(p) > 0, np.asarray(e) > 0)
               for p, e in zip(state["pressure"], state["end_pressure"], strict=True)]
        before = self._pressed or [(np.zeros_like(p), np.zeros_like(e)) for p, e in now]
        grew = any(np.any(p & ~q) or np.any(e & ~f)
                   for (p, e), (q, f) in zip(now, before, strict=True))
        if not comm.allreduce(bool(grew), op=MPI.LOR):
            return 0
        x = compat.vector_of(self._problem.w)
        largest = tangent.norm(PETSc.NormType.NORM_INFINITY)
        if not largest > 0:
            return 0
        eps = 1e-6 * self.model.length / largest
        saved = compat.local_array(self._problem.w).copy()
        x.axpy(eps, tangent)
        if x.getType() != PETSc.Vec.Type.SEQ:
            x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        try:
            moved = self.evaluate(friction=False)
        finally:
            compat.local_array(self._problem.w)[:] = saved
        local = 0.0
        for i, (pressed, ends) in enumerate(now):
            local -= float(np.sum((moved["gap"][i] - state["gap"][i])[pressed]))
            if comm.rank == 0:
                local -= float(np.sum((moved["end_gap"][i] - state["end_gap"][i])[ends]))
        rate = comm.allreduce(local, op=MPI.SUM)
        scale = eps * largest * 1e-6
        return 0 if abs(rate) <= scale else (1 if rate > 0 else -1)

    def changed_between(self, first, second) -> bool:
        """Do two `save`d states press different contact points (collective)?"""
        def pressed(saved):
            return None if saved is None else saved[2]

        a, b = pressed(first), pressed(second)
        local = False
        if (a is None) != (b is None):
            local = any(np.any(p) or np.any(e) for p, e in (a or b))
        elif a is not None:
            local = any(np.any(p != q) or np.any(e != f)
                        for (p, e), (q, f) in zip(a, b, strict=True))
        return bool(self._problem.comm.allreduce(bool(local), op=MPI.LOR))

    def active_change(self, state: dict | None = None) -> list[float]:
        """Per obstacle, the share of its contact points (the owned quadrature points of all
        ranks and the two ends) pressed now and not in the last accepted state, or the
        reverse (collective)."""
        state = state or self.evaluate(friction=False)
        comm = self._problem.comm
        counts = np.zeros(len(self.obstacles))
        for i in range(len(self.obstacles)):
            now = np.asarray(state["pressure"][i]) > 0
            ends = np.asarray(state["end_pressure"][i]) > 0
            before, ends_before = (self._pressed[i] if self._pressed is not None
                                   else (np.zeros_like(now), np.zeros_like(ends)))
            counts[i] = np.count_nonzero(now != before)
            if comm.rank == 0:  # the ends are global numbers: counted once
                counts[i] += np.count_nonzero(ends != ends_before)
        counts = comm.allreduce(counts, op=MPI.SUM)
        total = comm.allreduce(len(self._dofs), op=MPI.SUM) + 2
        return [float(c) / total for c in counts]

    def large_change(self, state: dict | None = None) -> str | None:
        """Why a converged step is rejected: its active set changed at more than
        ``max_active_change`` of an obstacle's contact points (None: accepted). Collective."""
        limit = self.settings.max_active_change
        if limit >= 1:
            return None
        for obstacle, share in zip(self.obstacles, self.active_change(state), strict=True):
            if share > limit:
                return (f"contact: the step changed the contact state of {share:.0%} of the "
                        f"contact points of obstacle {obstacle.name!r} (more than [contact] "
                        f"max_active_change = {limit:g})")
        return None

    def reset(self) -> None:
        """No contact: zero multipliers and friction states, the configured friction
        coefficients (the unloaded state)."""
        if self._problem is None:
            return
        for function in self.multipliers + self.active:
            function.x.array[:] = 0.0
        for ends in self.end_multipliers + self.end_active:
            for constant in ends:
                constant.value = 0.0
        for i, f in self._friction.items():  # the configured coefficient again
            self.friction[i] = float(self.obstacles[i].friction)
            f["mu"].value = self.friction[i]
            for name in self._names:
                f[name].x.array[:] = 0.0
            for end in f["ends"]:
                for name in self._names:
                    end[name].value = 0.0
        self.move(0.0)
        self._set_references(None)
        self._committed = self._copy()
        self._positions = None
        self._pressed = None
        self._touching = None

    def evaluate(self, friction: bool = True) -> dict:
        """The contact state of the current iterate (collective): per obstacle the gaps and
        pressures at the owned contact points (``gap``, ``pressure``: lists of arrays, in the
        order of the quadrature space's dofs), at the ends (``end_gap``, ``end_pressure``:
        [x = 0, x = L]), the local point data (``local``: x, r and d, below, above (planar)
        or radius (spatial)), ``active_changes`` (points whose active set disagrees with
        their pressure) and, per obstacle with friction, ``friction[i]``: the slip, the
        return-mapped traction and stick flag, the contact points (interior and ends), and
        ``friction_changes`` (points whose stick/slip state or slip traction is not yet
        consistent, or stuck points that slipped more than the tolerance)."""
        values = compat.evaluate_expression(self._expression, self._problem.mesh,
                                            self._owned_cells)
        values = np.asarray(values).reshape(-1, self._columns)
        comm = self._problem.comm
        k, k_end = self.k_value, self.k_value * self.end_length
        gaps, pressures, end_gaps, end_pressures = [], [], [], []
        changes = 0  # points whose active set disagrees with their pressure
        tiny = 1e-6 * k * self.tolerance  # pressures below it are round-off
        for i, _ in enumerate(self.obstacles):
            gap = values[:, self._obstacle_columns[i]["gap"]]
            trial = self.multipliers[i].x.array[self._dofs] - k * gap
            chi = self.active[i].x.array[self._dofs] > 0.5
            changes += int(np.count_nonzero((chi & (trial < -tiny)) | (~chi & (trial > tiny))))
            gaps.append(gap)
            pressures.append(np.maximum(trial, 0.0))
            ends = np.array([global_sum(comm, fem.assemble_scalar(form))
                             for form in self._end_forms[i]["gap"]])
            end_gaps.append(ends)
            trial = np.array([float(c.value) for c in self.end_multipliers[i]]) - k_end * ends
            chi = np.array([float(c.value) for c in self.end_active[i]]) > 0.5
            if comm.rank == 0:  # the ends are global numbers: counted once
                changes += int(np.count_nonzero((chi & (trial < -tiny * self.end_length))
                                                 | (~chi & (trial > tiny * self.end_length))))
            end_pressures.append(np.maximum(trial, 0.0))
        local = {"x": values[:, 0], "r": values[:, 1:1 + self.dim]}
        if self.spatial:
            local.update(self._spatial_local(values))
        else:
            local.update({"d": values[:, 3:5], "below": values[:, 5], "above": values[:, 6]})
        changes = int(comm.allreduce(changes, op=MPI.SUM))
        state = {"gap": gaps, "pressure": pressures, "end_gap": end_gaps,
                 "end_pressure": end_pressures, "local": local, "active_changes": changes,
                 "raw": values, "friction": {}, "friction_changes": 0}
        if friction and self._friction:
            self._evaluate_friction(state, values)
        return state

    def _evaluate_friction(self, state, values) -> None:
        comm = self._problem.comm
        k, k_end = self.k_value, self.k_value * self.friction_end_length
        tolerance = self.tolerance
        changes = 0
        for i, f in self._friction.items():
            if self.spatial:
                changes += self._evaluate_spatial_friction(i, state, values)
                continue
            mu, where = float(f["mu"].value), self._obstacle_columns[i]
            slip = values[:, where["slip"]]
            points = values[:, where["point"]:where["point"] + self.dim]
            stick = f["stick"].x.array[self._dofs]
            direction = f["direction"].x.array[self._dofs]
            trial = f["multiplier"].x.array[self._dofs] - k * slip
            stuck, new_direction, traction = coulomb_state(
                trial, slip, state["pressure"][i], mu, stick, direction, 1e-3 * tolerance)
            changes += self._friction_changes(stick, direction, stuck, new_direction, slip,
                                              state["pressure"][i], tolerance)
            end_slip = np.array([global_sum(comm, fem.assemble_scalar(form))
                                 for form in self._end_forms[i]["slip"]])
            end_point = [self._assemble_end_point(i, e) for e in range(2)]
            ends = f["ends"]
            end_stick = np.array([float(e["stick"].value) for e in ends])
            end_direction = np.array([float(e["direction"].value) for e in ends])
            end_trial = np.array([float(e["multiplier"].value) for e in ends]) - k_end * end_slip
            end_stuck, end_new_direction, end_traction = coulomb_state(
                end_trial, end_slip, state["end_pressure"][i], mu, end_stick, end_direction,
                1e-3 * tolerance)
            if comm.rank == 0:  # the ends are global numbers: counted once
                changes += self._friction_changes(end_stick, end_direction, end_stuck,
                                                  end_new_direction, end_slip,
                                                  state["end_pressure"][i], tolerance)
            state["friction"][i] = {"slip": slip, "point": points, "traction": traction,
                                    "stuck": stuck, "direction": new_direction,
                                    "end_slip": end_slip, "end_point": end_point,
                                    "end_traction": end_traction, "end_stuck": end_stuck,
                                    "end_direction": end_new_direction}
        state["friction_changes"] = int(comm.allreduce(changes, op=MPI.SUM))

    @staticmethod
    def _friction_changes(stick, direction, stuck, new_direction, slip, pressure,
                          tolerance) -> int:
        """Points whose stick/slip state must change, or stuck points that slipped more than
        the tolerance (their multiplier needs an Uzawa update)."""
        used_stuck = np.asarray(stick) > 0.5
        bad = (used_stuck != stuck) | ((~stuck) & (np.asarray(direction) != new_direction)
                                       & (pressure > 0))
        bad |= stuck & (np.abs(slip) > tolerance)
        return int(np.count_nonzero(bad))

    # --- friction of the spatial rod (2-vectors in the tangent plane) --------------------------
    def _direction_size(self, flags):
        """|direction| of the stored slip directions (arrays of the owned points, or a float
        for an end's constants): 1 where the point slipped in the last solve, else 0."""
        if isinstance(flags["stick"], fem.Function):
            if not self.spatial:
                return np.abs(flags["direction"].x.array[self._dofs])
            return np.hypot(flags["direction_0"].x.array[self._dofs],
                            flags["direction_1"].x.array[self._dofs])
        if not self.spatial:
            return abs(float(flags["direction"].value))
        return float(np.hypot(float(flags["direction_0"].value),
                              float(flags["direction_1"].value)))

    def _state_values(self, entry: dict, prefix: str = "") -> dict:
        """The per-point friction state of an evaluated ``entry`` by storage name (``prefix``
        "end_": the two ends')."""
        traction = np.asarray(entry[prefix + "traction"], dtype=float)
        direction = np.asarray(entry[prefix + "direction"], dtype=float)
        stick = np.asarray(entry[prefix + "stuck"]).astype(float)
        if not self.spatial:
            return {"multiplier": traction, "stick": stick, "direction": direction}
        return {"multiplier_0": traction[:, 0], "multiplier_1": traction[:, 1], "stick": stick,
                "direction_0": direction[:, 0], "direction_1": direction[:, 1]}

    def _spatial_friction_storage(self, i: int) -> dict:
        """Tangential multiplier (2 components), stick flag, slip direction (2), the contact
        point of the last accepted state (3) and the body-frame direction of the section's
        point in contact there (3), at every contact point and end."""
        mesh = self._problem.mesh
        if not hasattr(self, "_regularisation"):
            self._regularisation = fem.Constant(mesh, float(self.tolerance))
        storage = {n: fem.Function(self.space, name=f"friction_{n}_{i}") for n in self._names}
        storage["reference"] = [fem.Function(self.space, name=f"friction_reference_{i}_{c}")
                                for c in range(3)]
        storage["body"] = [fem.Function(self.space, name=f"friction_body_{i}_{c}")
                           for c in range(3)]
        storage["mu"] = fem.Constant(mesh, self.friction[i])
        storage["ends"] = [{n: fem.Constant(mesh, 0.0) for n in self._names}
                           | {"reference": fem.Constant(mesh, np.zeros(3)),
                              "body": fem.Constant(mesh, np.zeros(3))} for _ in range(2)]
        return storage

    @staticmethod
    def _vector(flags, name: str):
        return ufl.as_vector([flags[f"{name}_0"], flags[f"{name}_1"]])

    def _spatial_point(self, geometry, body):
        """The tube's material point r + rho R m (m the body-frame direction ``body``)."""
        return geometry["r"] + ufl.dot(rotation(geometry["theta"]), body)

    def _spatial_friction_terms(self, i: int, geometry, pressures, variable: bool = False):
        """Per contact point (interior, then the two ends): (measure, slip 2-vector, stick,
        slipping flag, the slip traction, the point)."""
        f, obstacle = self._friction[i], self.obstacles[i]
        interior = (self.dx, ufl.as_vector(f["body"]), ufl.as_vector(f["reference"]), f,
                    self.k)
        ends = [(measure, end["body"], end["reference"], end, self.k_end_friction)
                for measure, end in zip(self._end_measures, f["ends"], strict=True)]
        terms = []
        for (measure, body, reference, flags, k), pressure in zip([interior] + ends, pressures,
                                                                  strict=True):
            point = self._spatial_point(geometry, body)
            if variable:
                point = ufl.variable(point)
            slip = spatial_slip(obstacle, point, reference)
            multiplier = self._vector(flags, "multiplier")
            slipping = 1 - flags["stick"]  # the direction is zero unless the point slips
            # regularised below a trial traction of k x the tolerance (a slip within the
            # tolerance) in the first solve of a step: Newton at a grazing first touch, where
            # mu p_n and s are both ~0; then 1e-9 of that (`_regularisation`)
            traction = spatial_slip_traction(self._vector(flags, "direction"), slip, k,
                                             f["mu"], pressure, self._regularisation * k)
            terms.append({"measure": measure, "slip": slip, "stick": flags["stick"],
                          "slipping": slipping, "slip_traction": traction,
                          "multiplier": multiplier, "k": k, "point": point})
        return terms

    def _pressures(self, i: int, gap) -> list:
        """The fixed-active-set pressures chi (lambda - k g) of the interior and the ends."""
        return [self.active[i] * (self.multipliers[i] - self.k * gap)] + [
            self.end_active[i][e] * (self.end_multipliers[i][e] - self.k_end * gap)
            for e in range(2)]

    def _spatial_stick_energy(self, i: int, geometry):
        gap = self._gap_of(self.obstacles[i], geometry)
        return sum(spatial_stick_density(t["multiplier"], t["stick"], t["slip"], t["k"])
                   * t["measure"] for t in self._spatial_friction_terms(
                       i, geometry, self._pressures(i, gap)))

    def _spatial_slip_work(self, i: int, geometry, gap, problem, test):
        return sum(t["slipping"] * ufl.dot(t["slip_traction"],
                                           ufl.derivative(t["slip"], problem.w, test))
                   * t["measure"] for t in self._spatial_friction_terms(
                       i, geometry, self._pressures(i, gap)))

    def _spatial_friction_measures(self, i, geometry, columns, where, pressure,
                                   end_pressures, ends_of) -> None:
        """The spatial friction's columns (slip 2, facing point 3, facing body direction 3)
        and forms (the resultant's force and moment, the ends' slips, facing points and
        directions, friction forces)."""
        obstacle = self.obstacles[i]
        R = rotation(geometry["theta"])
        facing = section_support(R, spatial_outward_normal(obstacle, geometry["r"]),
                                 geometry["parts"])
        facing_point = geometry["r"] + ufl.dot(R, facing)
        terms = self._spatial_friction_terms(i, geometry, [pressure] + list(end_pressures),
                                             variable=True)
        where["slip"] = len(columns)
        columns += [terms[0]["slip"][c] for c in range(2)]
        where["point"] = len(columns)
        columns += [facing_point[c] for c in range(3)]
        where["facing"] = len(columns)
        columns += [facing[c] for c in range(3)]
        totals, end_forces = None, []
        for t in terms:
            # the traction p_t (stuck: lambda_t - k s; slipping: the return map) on the
            # coordinates s: the force p_t . ds/dp at the point p, its moment p x that
            traction = (t["stick"] * (t["multiplier"] - t["k"] * t["slip"])
                        + t["slipping"] * t["slip_traction"])
            force = sum(traction[c] * ufl.diff(t["slip"][c], t["point"]) for c in range(2))
            # about the world origin (the point is in a moving obstacle's frame)
            world = t["point"] + self.offsets[i] if self.moving[i] else t["point"]
            moment = ufl.cross(world, force)
            densities = [force[c] for c in range(3)] + [moment[c] for c in range(3)]
            terms_here = [d * t["measure"] for d in densities]
            totals = terms_here if totals is None else [a + b for a, b in zip(
                totals, terms_here, strict=True)]
            if t["measure"] is not self.dx:
                end_forces.append([fem.form(force[c] * t["measure"]) for c in range(3)])
        ends_of["friction_forms"] = [fem.form(total) for total in totals]
        ends_of["end_friction"] = end_forces
        ends_of["slip"] = [[fem.form(t["slip"][c] * t["measure"]) for c in range(2)]
                           for t in terms[1:]]
        ends_of["point"] = [[fem.form(facing_point[c] * m) for c in range(3)]
                            for m in self._end_measures]
        ends_of["facing"] = [[fem.form(facing[c] * m) for c in range(3)]
                             for m in self._end_measures]

    def _evaluate_spatial_friction(self, i: int, state: dict, values) -> int:
        """`_evaluate_friction` of one obstacle of a spatial rod: 2-vector slips and
        tractions, `coulomb_state_2d`; returns the inconsistent points (counted once)."""
        comm = self._problem.comm
        k, k_end = self.k_value, self.k_value * self.friction_end_length
        f, where, tolerance = self._friction[i], self._obstacle_columns[i], self.tolerance
        mu = float(f["mu"].value)

        def pair(flags, name):
            if isinstance(flags[f"{name}_0"], fem.Function):
                return np.column_stack([flags[f"{name}_{c}"].x.array[self._dofs]
                                        for c in range(2)])
            return np.array([float(flags[f"{name}_{c}"].value) for c in range(2)])

        slip = values[:, where["slip"]:where["slip"] + 2]
        points = values[:, where["point"]:where["point"] + 3]
        stick = f["stick"].x.array[self._dofs]
        direction, multiplier = pair(f, "direction"), pair(f, "multiplier")
        multiplier = self._slipping_multiplier(stick, direction, multiplier,
                                               mu * state["pressure"][i])
        stuck, new_direction, traction = coulomb_state_2d(
            multiplier - k * slip, slip, state["pressure"][i], mu, stick, direction,
            1e-3 * tolerance)
        changes = self._spatial_friction_changes(stick, direction, multiplier, stuck,
                                                 new_direction, slip,
                                                 mu * state["pressure"][i], tolerance)
        changes += self._regularisation_deficit(multiplier - k * slip, k,
                                                mu * state["pressure"][i], stuck)
        end_slip = np.array([[global_sum(comm, fem.assemble_scalar(form)) for form in forms]
                             for forms in self._end_forms[i]["slip"]])
        end_point = [self._assemble_end_point(i, e) for e in range(2)]
        end_stick = np.array([float(e["stick"].value) for e in f["ends"]])
        end_direction = np.array([pair(e, "direction") for e in f["ends"]])
        end_multiplier = self._slipping_multiplier(
            end_stick, end_direction, np.array([pair(e, "multiplier") for e in f["ends"]]),
            mu * state["end_pressure"][i])
        end_stuck, end_new_direction, end_traction = coulomb_state_2d(
            end_multiplier - k_end * end_slip, end_slip, state["end_pressure"][i], mu,
            end_stick, end_direction, 1e-3 * tolerance)
        if comm.rank == 0:  # the ends are global numbers: counted once
            changes += self._spatial_friction_changes(
                end_stick, end_direction, end_multiplier, end_stuck, end_new_direction,
                end_slip, mu * state["end_pressure"][i], tolerance)
            changes += self._regularisation_deficit(end_multiplier - k_end * end_slip, k_end,
                                                    mu * state["end_pressure"][i], end_stuck)
        state["friction"][i] = {"slip": slip, "point": points, "traction": traction,
                                "stuck": stuck, "direction": new_direction,
                                "end_slip": end_slip, "end_point": end_point,
                                "end_traction": end_traction, "end_stuck": end_stuck,
                                "end_direction": end_new_direction}
        return changes

    def _regularisation_deficit(self, trial, k, bound, stuck) -> int:
        """Slipping points whose traction in the solve, mu p_n |t| / sqrt(|t|^2 + eps^2)
        (`spatial_slip_traction`), fell short of mu p_n by more than 1e-9 of it: they need a
        solve with the sharp regularisation (`update` sets it)."""
        eps = float(self._regularisation.value) * k
        size = np.linalg.norm(trial, axis=1)
        deficit = 1 - size / np.sqrt(size**2 + eps**2)
        return int(np.count_nonzero((bound > 0) & ~stuck & (deficit > 1e-9)))

    @staticmethod
    def _slipping_multiplier(stick, direction, multiplier, bound):
        """The multipliers the solve used: a slipping point's mu p_n e (its direction e,
        `spatial_slip_traction`), a stuck one's own."""
        slipping = (np.asarray(stick) < 0.5) & (np.linalg.norm(direction, axis=1) > 0.5)
        return np.where(slipping[:, None], np.asarray(bound)[:, None] * direction, multiplier)

    @staticmethod
    def _spatial_friction_changes(stick, direction, multiplier, stuck, new_direction, slip,
                                  bound, tolerance) -> int:
        """Points whose stick/slip state must change, slipping points (with a friction bound
        mu p_n > 0) whose direction e (`spatial_slip_traction`) is not yet the trial's t/|t|
        (the slip not yet opposite to the friction, 1e-6), or stuck points that slipped more
        than the tolerance."""
        used_stuck = np.asarray(stick) > 0.5
        slipping = (bound > 0) & ~stuck
        direction = np.asarray(direction)
        turned = ((np.linalg.norm(direction, axis=1) < 0.5)
                  | (np.linalg.norm(new_direction - direction, axis=1) > 1e-6))
        bad = (used_stuck != stuck) | (slipping & turned)
        bad |= stuck & (np.linalg.norm(slip, axis=1) > tolerance)
        return int(np.count_nonzero(bad))

    def max_penetration(self, state: dict | None = None) -> float:
        """max over all obstacles, contact points and ends of <-g>_+ (global) [m]."""
        return self._largest(state, lambda gap, pressure: -gap)

    def max_separation(self, state: dict | None = None) -> float:
        """max of g over the pressed points (p > 0) (global) [m]: > 0 breaks the
        complementarity p g = 0 (a point pushed while clear of the obstacle)."""
        return self._largest(state, lambda gap, pressure: np.where(pressure > 0, gap, 0.0))

    def _largest(self, state, measure) -> float:
        state = state or self.evaluate()
        local = 0.0
        for gap, pressure, end, end_pressure in zip(state["gap"], state["pressure"],
                                                    state["end_gap"], state["end_pressure"],
                                                    strict=True):
            if len(gap):
                local = max(local, float(np.max(measure(gap, pressure))))
            local = max(local, float(np.max(measure(end, end_pressure))))
        return self._problem.comm.allreduce(max(local, 0.0), op=MPI.MAX)

    def force_changes(self, state: dict) -> tuple[np.ndarray, np.ndarray]:
        """Per obstacle (global numbers, [N]): the normal contact force of the iterate (the
        pressures integrated along the rod, the ends' point forces added) and the change the
        next Uzawa update would make to the pressures (the integral of |p - lambda|, the ends'
        |p - lambda| added): the convergence measure of the augmented-Lagrangian multipliers.
        A penetration below the tolerance alone does not make the force accurate: where the rod
        is stiff against the obstacle (a finger pushing along its axis), a few micrometres of
        penetration at one contact point and as much separation at the next still carry a few
        per cent of the force."""
        comm = self._problem.comm
        forces, changes = [], []
        for i, function in enumerate(self.multipliers):
            pressure = state["pressure"][i]
            change = np.abs(pressure - function.x.array[self._dofs])
            local = np.array([float(np.dot(self._weights, pressure)),
                              float(np.dot(self._weights, change))])
            total = comm.allreduce(local, op=MPI.SUM)
            ends = np.asarray(state["end_pressure"][i], dtype=float)
            end_multipliers = np.array([float(c.value) for c in self.end_multipliers[i]])
            forces.append(total[0] + float(ends.sum()))
            changes.append(total[1] + float(np.abs(ends - end_multipliers).sum()))
        return np.array(forces), np.array(changes)

    def update(self, state: dict | None = None, multipliers: bool = True) -> None:
        """The active set chi <- [lambda - k g > 0] at every contact point and end and, with
        ``multipliers``, the Uzawa update lambda <- <lambda - k g>_+; with friction the
        stick/slip state (`coulomb_state`) and, with ``multipliers``, lambda_t <- p_t."""
        state = state or self.evaluate()
        k, k_end = self.k_value, self.k_value * self.end_length
        for i, function in enumerate(self.multipliers):
            lam = function.x.array[self._dofs]
            trial = lam - k * state["gap"][i]
            self.active[i].x.array[self._dofs] = trial > 0
            self.active[i].x.scatter_forward()
            if multipliers:
                function.x.array[self._dofs] = state["pressure"][i]
                function.x.scatter_forward()
            for e, (constant, flag) in enumerate(zip(self.end_multipliers[i],
                                                     self.end_active[i], strict=True)):
                trial = float(constant.value) - k_end * float(state["end_gap"][i][e])
                flag.value = 1.0 if trial > 0 else 0.0
                if multipliers:
                    constant.value = float(state["end_pressure"][i][e])
        if self.spatial and self._friction:  # the sharp return map from now on
            self._regularisation.value = 1e-9 * float(self.tolerance)
        for i, f in self._friction.items():
            entry = state["friction"][i]
            chosen = {name: values for name, values in self._state_values(entry).items()
                      if multipliers or not name.startswith("multiplier")}
            for name, values in chosen.items():
                f[name].x.array[self._dofs] = values
                f[name].x.scatter_forward()
            for e, end in enumerate(f["ends"]):
                for name, values in self._state_values(entry, "end_").items():
                    if multipliers or not name.startswith("multiplier"):
                        end[name].value = float(values[e])

    def _dense_local(self) -> dict:
        """The rod's geometry (x, r and d, below, above (planar) or radius (spatial)) at the
        dense points of `between_points` of the owned cells."""
        values = compat.evaluate_expression(self._dense_expression, self._problem.mesh,
                                            self._owned_cells)
        values = np.asarray(values).reshape(-1, self._base_columns)
        local = {"x": values[:, 0], "r": values[:, 1:1 + self.dim]}
        if self.spatial:
            local.update(self._spatial_local(values))
        else:
            local.update({"d": values[:, 3:5], "below": values[:, 5], "above": values[:, 6]})
        return local

    def _undeformed_local(self) -> dict:
        """`_dense_local` of the zero state (the reference geometry: a chain of rods)."""
        saved = compat.local_array(self._problem.w).copy()
        compat.local_array(self._problem.w)[:] = 0.0
        try:
            return self._dense_local()
        finally:
            compat.local_array(self._problem.w)[:] = saved

    def _spatial_local(self, values) -> dict:
        """The spatial columns of an evaluated expression: the circumradius, the directors
        (``tangent`` = d1, ``d2``, ``d3``) and the section's ``parts`` per point."""
        local = {"radius": values[:, 4], "tangent": values[:, 5:8], "d2": values[:, 8:11],
                 "d3": values[:, 11:14]}
        if "disc" in self._parts:
            local["parts"] = {"disc": values[:, 14]}
        else:
            local["parts"] = {"rectangles": [tuple(values[:, 14 + 3 * j + c] for c in range(3))
                                             for j in range(len(self._parts["rectangles"]))]}
        return local

    def _surface_gap(self, obstacle, local) -> np.ndarray:
        """The numpy twin of the gap at the points of ``local`` (`_dense_local`, `evaluate`):
        the section's true shape (spatial), the section segment (planar)."""
        if self.spatial:
            return section_distance(obstacle, local["r"], local["tangent"], local["d2"],
                                    local["d3"], local["parts"])
        return segment_distance(obstacle, local["r"], local["d"], local["below"],
                                local["above"])

    def between_points(self) -> str | None:
        """Why the current state is rejected: an obstacle reaching deeper than a quarter of
        the section or of the narrowest obstacle into the rod between the contact points (an
        obstacle narrower than their spacing, e.g. a thin peg), measured at points 1/8 of the
        narrowest obstacle apart (at least 9 per element, the element's ends included).
        Local (the caller agrees over ranks)."""
        local = self._dense_local()
        if not len(local["x"]):
            return None
        x = local["x"]
        thickness = 2 * local["radius"] if self.spatial else local["below"] + local["above"]
        depth = max(10 * self.tolerance, 0.25 * min(float(np.min(thickness)), self._narrowest))
        for obstacle in self.placed():
            gap = self._surface_gap(obstacle, local)
            if np.min(gap) < -depth:
                j = int(np.argmin(gap))
                return (f"contact: obstacle {obstacle.name!r} reaches {-gap[j]:.3g} m into the "
                        f"rod near x = {x[j]:.4g} m, between the contact points (it is "
                        "narrower than their spacing): refine the mesh or raise [contact] "
                        "quadrature_degree")
        return None

    def tunnelled(self) -> str | None:
        """Why the step from the last accepted state (the undeformed rod before the first) to
        the current one is rejected: a contact point whose straight path between the two
        passes deeper than a quarter of the section into an obstacle (a load step that jumped
        through a thin one), sampled finer than half the thinnest section or obstacle, at the
        dense points of `between_points` (which also rejects an obstacle left inside the rod
        between the contact points). Local (the
        caller agrees over ranks); a false alarm (a path cutting a disc's chord) only cuts the
        step back."""
        after = self._dense_local()
        before = self._positions
        now = self.translations()
        then = (getattr(self, "_positions_offsets", None) if before is not None
                else [o.translation(0.0) for o in self.obstacles])
        if before is None and getattr(self._problem, "chain", None) is not None:
            before = self._undeformed_local()  # the undeformed chain of rods
        if before is None:  # the undeformed rod
            r = np.zeros((len(after["x"]), self.dim))
            r[:, 0] = after["x"]
            d = np.tile([0.0, 1.0], (len(r), 1))
            before = {"r": r, "d": d}
        if not len(after["x"]):
            return None
        inside = self.between_points()
        if inside is not None:
            return inside
        thickness = float(np.min(2 * after["radius"] if self.spatial
                                 else after["below"] + after["above"]))
        thinnest = min([thickness] + [_feature_size(o) for o in self.obstacles])
        moved = float(np.max(np.linalg.norm(after["r"] - before["r"], axis=1)))
        moved += max(float(np.linalg.norm(a - b)) for a, b in zip(now, then, strict=True))
        samples = int(min(2000, max(8, np.ceil(2 * moved / thinnest))))
        depth = max(10 * self.tolerance, 0.25 * thinnest)
        for index, fixed in enumerate(self.obstacles):
            for t in np.linspace(0.0, 1.0, samples + 1)[1:-1]:
                obstacle = translated(fixed, (1 - t) * then[index] + t * now[index])
                r = (1 - t) * before["r"] + t * after["r"]
                if self.spatial:  # the section as it is now, at the point on the straight path
                    gap = self._surface_gap(obstacle, dict(after, r=r))
                else:
                    d = (1 - t) * before["d"] + t * after["d"]
                    d = d / np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]
                    gap = segment_distance(obstacle, r, d, after["below"], after["above"])
                if np.min(gap) < -depth:
                    j = int(np.argmin(gap))
                    return (f"contact: the load step moved the rod through obstacle "
                            f"{obstacle.name!r} (near x = {after['x'][j]:.4g} m)")
        return None

    def edge_contact(self, state: dict) -> str | None:
        """Why the converged contact state ``state`` cannot be accepted: a pressed contact
        point of a box in the region of an edge or corner (`box_edge_contact`), where the
        face-plane gap would push the rod along a face normal that is not the rod's surface
        normal (a spurious axial force). None where every box contact is a face contact.
        Collective (the ranks agree)."""
        reasons = []
        local = state["local"]
        for i, obstacle in enumerate(self.placed()):
            if not isinstance(obstacle, Box) or not len(local["x"]):
                continue
            pressed = state["pressure"][i] > 0
            if not np.any(pressed):
                continue
            if self.spatial:
                flags, angles = box_edge_contact(obstacle, local["r"], local["tangent"],
                                                 local["radius"], local["radius"],
                                                 spacing=self._spacing)
            else:
                d = local["d"]
                tangent = np.stack([d[:, 1], -d[:, 0]], axis=1)
                flags, angles = box_edge_contact(obstacle, local["r"], tangent,
                                                 local["below"], local["above"], d,
                                                 spacing=self._spacing)
            flags &= pressed
            if np.any(flags):
                j = int(np.flatnonzero(flags)[np.argmax(angles[flags])])
                reasons.append(
                    f"contact: the rod presses on an edge or corner of box {obstacle.name!r}, "
                    f"which the contact model cannot represent (the force would not be normal "
                    f"to the rod): near x = {local['x'][j]:.4g} m the box face's normal is "
                    f"{angles[j]:.3g} degrees off the rod's surface normal")
                break
        gathered = [r for r in self._problem.comm.allgather(reasons[0] if reasons else None)
                    if r]
        return gathered[0] if gathered else None

    def output_expressions(self, problem) -> dict:
        """Fields for the result files, per obstacle i (in the order of [[obstacles]]):
        ``contact_gap_i``, the signed gap [m] of the rod's surface (planar: the section
        segment, spatial: the tube) as a UFL expression of the state alone (no multipliers:
        it can be interpolated anywhere, e.g. at the vertices); the pressures are at the
        contact points only (`cell_pressures`)."""
        if self._problem is not problem:
            self._attach(problem)
        parts = problem.state_parts() if self.spatial else problem.fields()[:3]
        geometry = self._geometry(parts)
        return {f"contact_gap_{i}": self._gap_of(obstacle, self._relative(geometry, i))
                for i, obstacle in enumerate(self.obstacles)}

    def cell_pressures(self, state: dict | None = None) -> list[np.ndarray]:
        """Per obstacle, the largest line pressure [N/m] over each owned cell's contact
        points (the pressures `summary` reports, pressure_peak being their maximum), in the
        order of the owned cells (local)."""
        state = state or self.evaluate(friction=False)
        cells = len(self._owned_cells)
        return [np.asarray(p).reshape(cells, -1).max(axis=1) if cells else np.zeros(0)
                for p in state["pressure"]]

    def surface(self, state: dict | None = None) -> list[dict]:
        """Per obstacle, the run-time certificate of its contact (collective):
        ``penetration``, the largest penetration [m] over the rod's whole surface, measured
        with the numpy twin of the gap (`fe_beam.model.obstacles.section_distance`: the
        section's true shape; planar: the section segment) at points 1/16 of an element
        apart or closer (`_dense_local`: the vertices and the rod's ends, i.e. its flat end
        faces, included), and at the contact points; ``force`` the obstacle's normal force on
        the rod recomputed from the pressures at the contact points and the ends times the
        numpy twin's gradient (the obstacle's normal at the section's nearest point, by
        central differences), and ``balance`` its relative difference from the reported
        (assembled) normal force."""
        state = state or self.evaluate(friction=False)
        comm = self._problem.comm
        dense = self._dense_local()
        points = state["local"]
        length = float(self.model.length)
        step = 1e-7 * length
        result = []
        for i, obstacle in enumerate(self.placed()):
            depth = 0.0
            if len(dense["x"]):
                depth = max(depth, float(np.max(-self._surface_gap(obstacle, dense))))
            if len(state["gap"][i]):
                depth = max(depth, float(np.max(-state["gap"][i])))
            depth = max(depth, float(np.max(-np.asarray(state["end_gap"][i]))))
            depth = comm.allreduce(depth, op=MPI.MAX)
            force = np.zeros(self.dim)
            pressure = np.asarray(state["pressure"][i])
            if np.any(pressure > 0):
                force += np.sum((self._weights * pressure)[:, None]
                                * self._gradient(obstacle, points, step), axis=0)
            ends = np.asarray(state["end_pressure"][i], dtype=float)
            for e, where in enumerate((0.0, length)):
                # each end is a vertex of one owned cell of one rank: counted once
                at = np.flatnonzero(np.abs(dense["x"] - where) <= 1e-12 * length)[:1]
                if ends[e] > 0 and len(at):
                    force += ends[e] * self._gradient(obstacle, _take(dense, at), step)[0]
            force = comm.allreduce(force, op=MPI.SUM)
            reported = np.array([global_sum(comm, fem.assemble_scalar(form))
                                 for form in self._resultant_forms[i]["normal"][:self.dim]])
            scale = max(float(np.linalg.norm(reported)), float(np.linalg.norm(force)),
                        self.force_scale * 1e-9, 1e-300)
            result.append({"penetration": depth, "force": force,
                           "balance": float(np.linalg.norm(force - reported)) / scale})
        return result

    def _gradient(self, obstacle, local, step: float) -> np.ndarray:
        """d gap / d r (n, dim) of the numpy twin at the points of ``local``, by central
        differences."""
        columns = []
        for c in range(self.dim):
            shift = np.zeros(self.dim)
            shift[c] = step
            plus = self._surface_gap(obstacle, dict(local, r=local["r"] + shift))
            minus = self._surface_gap(obstacle, dict(local, r=local["r"] - shift))
            columns.append((plus - minus) / (2 * step))
        return np.stack(columns, axis=1)

    def summary(self, state: dict | None = None) -> list[dict]:
        """Per obstacle, in the order given: {name, force (the obstacle on the rod, global
        axes: [Fx, Fy] planar, [Fx, Fy, Fz] spatial) [N], moment (about the origin: planar
        the counterclockwise scalar, spatial [Mx, My, Mz]) [N m], active (contact intervals
        [[x0, x1], ...] in the reference x) [m], max_penetration (over the rod's whole
        surface: `surface`) [m], contact_point_penetration (at the contact points and ends,
        where the solver holds the tolerance) [m], force_balance (the normal force recomputed
        from the pressures
        and the obstacle's normals against the reported one, relative), pressure_peak (largest
        line pressure at the contact points) [N/m], end_forces (the normal point forces at
        x = 0 and x = L) [N]}; with friction also friction_force (the tangential part of
        force) [N], slip (intervals of slipping points) [m] and end_friction (the tangential
        point forces at the ends, along t = (-n_y, n_x); spatial: the two ends' friction
        forces as world vectors [[Fx, Fy, Fz], [Fx, Fy, Fz]]) [N]. Collective."""
        state = state or self.evaluate()
        comm = self._problem.comm
        x_all = np.concatenate(comm.allgather(state["local"]["x"]))
        order = np.argsort(x_all, kind="stable")
        certificates = self.surface(state)
        result = []
        for i, obstacle in enumerate(self.obstacles):
            forms = self._resultant_forms[i]
            resultants = np.array([global_sum(comm, fem.assemble_scalar(form))
                                   for form in forms["normal"]])
            friction = None
            if "friction" in forms:
                friction = np.array([global_sum(comm, fem.assemble_scalar(form))
                                     for form in forms["friction"]])
                resultants = resultants + friction
            pressure = np.concatenate(comm.allgather(state["pressure"][i]))
            gap = np.concatenate(comm.allgather(state["gap"][i]))
            ends = state["end_pressure"][i]
            peak = float(np.max(pressure)) if len(pressure) else 0.0
            end_gap = state["end_gap"][i]
            x_line = np.concatenate([[0.0], x_all[order], [self.model.length]])
            touching = np.concatenate([[end_gap[0] <= self.tolerance],
                                       gap[order] <= self.tolerance,
                                       [end_gap[1] <= self.tolerance]])
            pressed = np.concatenate([[ends[0] > 0], pressure[order] > 0.0, [ends[1] > 0]])
            # a rod end that touches (gap within the tolerance), joined to a pressed point by
            # touching points, closes that point's interval: a rod lying on the obstacle up to
            # its free end carries no point force there (M = V = 0), and the points near the
            # end may touch unloaded within the tolerance
            pressed[0] |= _touching_run(pressed, touching)
            pressed[-1] |= _touching_run(pressed[::-1], touching[::-1])
            active = _intervals(x_line, pressed, touching)
            # the penetration over the whole surface (`surface`): between the contact points,
            # the vertices and the end faces too
            penetration = max(0.0, float(np.max(-gap)) if len(gap) else 0.0,
                              float(np.max(-state["end_gap"][i])),
                              certificates[i]["penetration"])
            dim = self.dim
            entry = {
                "name": obstacle.name,
                **({"translation": [float(c) for c in self.offsets[i].value]}
                   if self.moving[i] else {}),
                "force": [float(c) for c in resultants[:dim]],
                "moment": ([float(c) for c in resultants[dim:]] if self.spatial
                           else float(resultants[dim])),
                "active": active,
                "max_penetration": penetration,
                # where the solver holds the tolerance: the contact points and the ends
                "contact_point_penetration": max(
                    0.0, float(np.max(-gap)) if len(gap) else 0.0,
                    float(np.max(-state["end_gap"][i]))),
                "pressure_peak": peak,
                "end_forces": [float(e) for e in ends],
                "force_balance": certificates[i]["balance"],
            }
            if friction is not None:
                f, flags = state["friction"][i], self._friction[i]
                # the stick/slip state of the last solve (committed with an accepted step)
                used = (flags["stick"].x.array[self._dofs] < 0.5) \
                    & (self._direction_size(flags) > 0.5)
                slipping = (pressure > 0) & np.concatenate(comm.allgather(used))
                end_slipping = (np.asarray(ends) > 0) & np.array(
                    [float(e["stick"].value) < 0.5 and self._direction_size(e) > 0.5
                     for e in flags["ends"]])
                entry["friction_force"] = [float(c) for c in friction[:dim]]
                # slipping runs joined across touching points that carry no pressure
                pressed = np.concatenate([[ends[0] > 0], pressure[order] > 0.0,
                                          [ends[1] > 0]])
                entry["slip"] = _intervals(
                    x_line, np.concatenate([[end_slipping[0]], slipping[order],
                                            [end_slipping[1]]]), touching & ~pressed)
                entry["end_friction"] = (
                    [[global_sum(comm, fem.assemble_scalar(form)) for form in forms]
                     for forms in self._end_forms[i]["end_friction"]] if self.spatial
                    else [float(t) for t in f["end_traction"]])
            result.append(entry)
        return result


def _take(local: dict, at) -> dict:
    """The points ``at`` of a `ContactSet._dense_local` / `evaluate` geometry."""
    taken = {k: v[at] for k, v in local.items() if k != "parts"}
    if "parts" in local:
        parts = local["parts"]
        taken["parts"] = ({"disc": parts["disc"][at]} if "disc" in parts else
                          {"rectangles": [tuple(np.asarray(v)[at] for v in rectangle)
                                          for rectangle in parts["rectangles"]]})
    return taken


def _touching_run(pressed: np.ndarray, touching: np.ndarray) -> bool:
    """Does the first point touch, and every point from it to the first pressed one?"""
    on = np.flatnonzero(pressed)
    return bool(len(on) and on[0] > 0 and np.all(touching[:on[0]]))


def _intervals(x: np.ndarray, active: np.ndarray, touching: np.ndarray) -> list:
    """Runs of consecutive active (pressed) points, sorted by x, as [[x_first, x_last], ...];
    two runs are joined when every point between them touches (``touching``: gap within the
    tolerance: unloaded points of one contact zone, to which the augmented-Lagrangian updates
    have not spread the pressure). The callers put the rod's ends first and last."""
    active = np.array(active, dtype=bool)
    on = np.flatnonzero(active)
    for first, last in zip(on[:-1], on[1:], strict=True):
        if last > first + 1 and np.all(touching[first + 1:last]):
            active[first + 1:last] = True
    runs, start = [], None
    for j, flag in enumerate(active):
        if flag and start is None:
            start = j
        if not flag and start is not None:
            runs.append([float(x[start]), float(x[j - 1])])
            start = None
    if start is not None:
        runs.append([float(x[start]), float(x[-1])])
    return runs

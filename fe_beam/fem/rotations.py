"""Finite rotations as pure functions returning UFL (docs/theory.md, Spatial rods).

The spatial rod's rotation field is the rotation vector theta (R = exp(theta^), Rodrigues):

    R      = I + a Theta + b Theta^2,           Theta = theta^ (the skew matrix of theta)
    u      = T(-theta) theta'                   (R^T R' = u^: the body-frame curvature)
    dphi   = T(theta) dtheta                    (dR R^T = dphi^: the spatial spin of a variation)
    T(th)  = I + b Theta + c Theta^2

with t = |theta|, a = sin t / t, b = (1 - cos t) / t^2, c = (t - sin t) / t^3. The coefficients
are even functions of t, evaluated from t^2: below t^2 = SERIES_BELOW by their Taylor series (no
0/0 at theta = 0, and exact derivatives there), above it by the closed forms (the switch is a UFL
conditional; both branches agree to round-off at the switch).

Why the rotation vector: it is three unknowns with no constraint, every term is a UFL function
of the unknowns (the energy is differentiated by UFL: exact tangents), and a rotation about a
fixed axis n, theta = phi n, gives R = exp(phi n^) and u = phi' n exactly: a planar problem
embedded in 3D is the planar discretisation itself. Its limit is |theta| = 2 pi, where T is
singular (the perpendicular part of the curvature map vanishes): states beyond 1.8 pi get a note.
"""

from __future__ import annotations

import math

import ufl

__all__ = ["SERIES_BELOW", "UFL_FUNCTIONS", "angular_velocity", "coefficients", "curvature",
           "lagrangian_inertia", "profile_expression", "rotation", "rotational_kinetic_energy",
           "rotational_mass", "skew", "spin_map"]

#: t^2 below which the Taylor series of a, b, c are used (t < 0.1: truncation < 1e-17)
SERIES_BELOW = 1e-2
#: the formula backend of `fe_beam.timefunctions.Profile.symbolic` in UFL
UFL_FUNCTIONS = {
    "sin": ufl.sin, "cos": ufl.cos, "tan": ufl.tan, "exp": ufl.exp, "log": ufl.ln,
    "sqrt": ufl.sqrt, "abs": abs, "tanh": ufl.tanh, "asin": ufl.asin, "acos": ufl.acos,
    "atan": ufl.atan, "sinh": ufl.sinh, "cosh": ufl.cosh,
    "min": ufl.min_value, "max": ufl.max_value,
    "step": lambda x: ufl.conditional(ufl.ge(x, 0), 1.0, 0.0),
    "conditional": ufl.conditional, "lt": ufl.lt, "le": ufl.le, "gt": ufl.gt, "ge": ufl.ge,
}


def profile_expression(profile, mesh):
    """A `fe_beam.timefunctions.Profile` of s as UFL on an interval mesh (s = x): the formula
    itself (exact derivatives), or a Constant when it does not depend on s."""
    from dolfinx import fem

    value = profile.symbolic(ufl.SpatialCoordinate(mesh)[0], UFL_FUNCTIONS)
    if isinstance(value, (int, float)):
        return fem.Constant(mesh, float(value))
    return value


def skew(a):
    """a^ (a x b = a^ b)."""
    return ufl.as_matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def _series(t2, terms):
    return sum(coefficient * t2**k for k, coefficient in enumerate(terms))


def coefficients(theta):
    """(a, b, c) of the rotation vector ``theta`` (see the module docstring)."""
    t2 = ufl.dot(theta, theta)
    t = ufl.sqrt(t2)
    small = ufl.lt(t2, SERIES_BELOW)
    a = ufl.conditional(small, _series(t2, [1 / math.factorial(2 * k + 1) * (-1) ** k
                                            for k in range(6)]), ufl.sin(t) / t)
    b = ufl.conditional(small, _series(t2, [1 / math.factorial(2 * k + 2) * (-1) ** k
                                            for k in range(6)]), (1 - ufl.cos(t)) / t2)
    c = ufl.conditional(small, _series(t2, [1 / math.factorial(2 * k + 3) * (-1) ** k
                                            for k in range(6)]), (t - ufl.sin(t)) / (t2 * t))
    return a, b, c


def rotation(theta):
    """R = exp(theta^) (Rodrigues)."""
    a, b, _ = coefficients(theta)
    Theta = skew(theta)
    return ufl.Identity(3) + a * Theta + b * Theta * Theta


def spin_map(theta, sign: float = 1.0):
    """T(sign theta) = I + sign b Theta + c Theta^2."""
    _, b, c = coefficients(theta)
    Theta = skew(theta)
    return ufl.Identity(3) + sign * b * Theta + c * Theta * Theta


def curvature(theta):
    """u with R^T R' = u^ (body frame): T(-theta) theta'."""
    return ufl.dot(spin_map(theta, -1.0), theta.dx(0))


# --- rotational inertia (docs/theory.md, Spatial rods: dynamics) -------------------------------
def angular_velocity(theta, rate):
    """The body angular velocity omega (R^T R_t = omega^) of a rotation vector ``theta``
    moving at ``rate`` = theta_t: T(-theta) theta_t (the curvature's map, in time)."""
    return ufl.dot(spin_map(theta, -1.0), rate)


def rotational_kinetic_energy(theta, rate, inertia):
    """1/2 omega . J omega per unit length, J = ``inertia`` (3 x 3, body frame)."""
    omega = angular_velocity(theta, rate)
    return 0.5 * ufl.dot(omega, ufl.dot(inertia, omega))


def rotational_mass(theta, inertia):
    """The mass matrix of the rotation vector, M(theta) = T(-theta)^T J T(-theta): the
    kinetic energy is 1/2 theta_t . M(theta) theta_t."""
    T = spin_map(theta, -1.0)
    return ufl.dot(T.T, ufl.dot(inertia, T))


def lagrangian_inertia(theta, rate, inertia):
    """(M(theta), g(theta, theta_t)) with d/dt dT/dtheta_t - dT/dtheta = M theta_tt + g: the
    inertia force of the exact rotational kinetic energy T in the rotation-vector chart,
    differentiated by UFL (g: the gyroscopic and chart terms, quadratic in theta_t)."""
    th, rt = ufl.variable(theta), ufl.variable(rate)
    energy = rotational_kinetic_energy(th, rt, inertia)
    momentum = ufl.diff(energy, rt)
    g = ufl.dot(ufl.diff(momentum, th), rt) - ufl.diff(energy, th)
    return rotational_mass(theta, inertia), g

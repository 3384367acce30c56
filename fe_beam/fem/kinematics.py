"""Kinematics and constitutive laws of the planar beam, as pure functions returning UFL.

Notation (docs/theory.md, Kinematics), with ' = d/dx along the reference axis:

    1 + e = (1 + u') cos(theta) + v' sin(theta)      (= lambda cos gamma)
    g     = v' cos(theta) - (1 + u') sin(theta)      (= lambda sin gamma)
    eps   = ((1 + u')^2 + v'^2 - 1) / 2              (Green-Lagrange axial strain)
    kappa = theta'

The laws themselves (`NonStandard`, `Reissner`: dataclasses with the energy as a method) live in
`fe_beam.model.laws` and are re-exported here with the kinematics.

Only polynomial and trigonometric functions of the unknowns enter the solved forms: no sqrt or
atan2, which would be singular or branch-cut sensitive. Output-only quantities (gamma, N, T) use
them.
"""

from __future__ import annotations

import ufl

from fe_beam.model.laws import (
    CONSTRAINTS,
    LAWS,
    ROD_LAWS,
    NonStandard,
    Reissner,
    Stiffness,
    Strains,
    closed_form_law,
    constrained_strains,
    nonstandard_energy,
    reissner_energy,
    strain_energy,
)

__all__ = [
    "CONSTRAINTS",
    "ClosedFormLaw",
    "LAWS",
    "ROD_LAWS",
    "NonStandard",
    "Reissner",
    "closed_form_law",
    "constrained_strains",
    "Stiffness",
    "Strains",
    "nonstandard_energy",
    "reissner_energy",
    "resultants_from_formulas",
    "strain_energy",
    "strains",
    "strains_from_gradient",
]

def strains_from_gradient(axis_tangent, theta, kappa) -> Strains:
    """Strains from r' = (1 + u', v') (a UFL 2-vector), the rotation theta and kappa = theta'."""
    stretch_x, stretch_y = axis_tangent[0], axis_tangent[1]
    cos_t, sin_t = ufl.cos(theta), ufl.sin(theta)
    return Strains(
        one_plus_e=stretch_x * cos_t + stretch_y * sin_t,
        g=stretch_y * cos_t - stretch_x * sin_t,
        eps=(stretch_x**2 + stretch_y**2 - 1) / 2,
        kappa=kappa,
    )


def axis_tangent(u, v):
    """r' = (1 + u', v')."""
    return ufl.as_vector([1 + u.dx(0), v.dx(0)])


def strains(u, v, theta) -> Strains:
    """Generalised strains of the displacement field (u, v, theta)."""
    return strains_from_gradient(axis_tangent(u, v), theta, theta.dx(0))


#: the laws of a closed form, by name (was a class; `closed_form_law` returns the law object)
ClosedFormLaw = closed_form_law


def resultants_from_formulas(eps, gamma, kappa, k: Stiffness):
    """N, T, M (source paper eqs. 1-3; docs/theory.md, Non-standard energy) of (eps, gamma, kappa).

    N = sin^2(g)/l GA + eps/l EA + (1 + 2 cos^2 g)/(2 l) kappa^2 EI + cos(g)/(2 l^2) kappa^3 EI3
    T = l sin(g) cos(g) GA - l sin(g) cos(g) kappa^2 EI - sin(g)/2 kappa^3 EI3
    M = (eps + (2 eps + 1) cos^2 g) kappa EI + 3/2 l cos(g) kappa^2 EI3 + 1/2 kappa^3 EI4
    with l = lambda = sqrt(2 eps + 1) and g = gamma. Used to verify the energy, not to solve.
    """
    lam = ufl.sqrt(2 * eps + 1)
    sin_g, cos_g = ufl.sin(gamma), ufl.cos(gamma)
    normal = (
        sin_g**2 / lam * k.GA
        + eps / lam * k.EA
        + (1 + 2 * cos_g**2) / (2 * lam) * kappa**2 * k.EI
        + cos_g / (2 * lam**2) * kappa**3 * k.EI3
    )
    shear = (
        lam * sin_g * cos_g * k.GA
        - lam * sin_g * cos_g * kappa**2 * k.EI
        - sin_g / 2 * kappa**3 * k.EI3
    )
    moment = (
        (eps + (2 * eps + 1) * cos_g**2) * kappa * k.EI
        + 1.5 * lam * cos_g * kappa**2 * k.EI3
        + 0.5 * kappa**3 * k.EI4
    )
    return normal, shear, moment


def strains_from_angles(eps, gamma, kappa) -> Strains:
    """Strains in terms of (eps, gamma, kappa): 1 + e = lambda cos(gamma), g = lambda sin(gamma)."""
    lam = ufl.sqrt(2 * eps + 1)
    return Strains(lam * ufl.cos(gamma), lam * ufl.sin(gamma), eps, kappa)


def section_resultants(energy_of_gradient, tangent, kappa):
    """Section force and moment from an energy written in r' and kappa (output only).

    F = dW/dr' (global components) = lambda^2 N t + T n, M = dW/dkappa; returns
    (N, T, M, axial force lambda^2 N = F.t) with t = r'/lambda, n = (-t_y, t_x).
    ``tangent`` and ``kappa`` must be ufl.variable objects used inside ``energy_of_gradient``.
    """
    force = ufl.diff(energy_of_gradient, tangent)
    moment = ufl.diff(energy_of_gradient, kappa)
    stretch = ufl.sqrt(ufl.dot(tangent, tangent))
    unit_t = tangent / stretch
    unit_n = ufl.as_vector([-unit_t[1], unit_t[0]])
    axial = ufl.dot(force, unit_t)
    return axial / stretch**2, ufl.dot(force, unit_n), moment, axial

"""Kinematics and constitutive laws of the planar beam, as pure functions returning UFL.

Notation (docs/theory.md, Kinematics), with ' = d/dx along the reference axis:

    1 + e = (1 + u') cos(theta) + v' sin(theta)      (= lambda cos gamma)
    g     = v' cos(theta) - (1 + u') sin(theta)      (= lambda sin gamma)
    eps   = ((1 + u')^2 + v'^2 - 1) / 2              (Green-Lagrange axial strain)
    kappa = theta'

Only polynomial and trigonometric functions of the unknowns enter the solved forms: no sqrt or
atan2, which would be singular or branch-cut sensitive. Output-only quantities (gamma, N, T) use
them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import ufl

__all__ = [
    "CONSTRAINTS",
    "ClosedFormLaw",
    "LAWS",
    "Stiffness",
    "Strains",
    "nonstandard_energy",
    "reissner_energy",
    "resultants_from_formulas",
    "strain_energy",
    "strains",
    "strains_from_gradient",
]

LAWS = ("nonstandard", "reissner", "hyperelastic")
CONSTRAINTS = ("none", "inextensible", "unshearable", "inextensible-unshearable")


@dataclass(frozen=True)
class Strains:
    """Generalised strains at a point.

    ``one_plus_e`` = lambda cos(gamma), ``g`` = lambda sin(gamma), ``eps``, ``kappa``.
    """

    one_plus_e: Any
    g: Any
    eps: Any
    kappa: Any


@dataclass(frozen=True)
class Stiffness:
    """Section stiffnesses (UFL or floats): EA, GA, EI, E*I3, E*I4; k = shear correction."""

    EA: Any
    GA: Any
    EI: Any
    EI3: Any
    EI4: Any
    shear_correction: Any = 1.0


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


def nonstandard_energy(s: Strains, k: Stiffness):
    """W = 1/2 EA eps^2 + 1/2 GA g^2 + 1/2 EI kappa^2 ((1+e)^2 + eps)
    + 1/2 E I3 kappa^3 (1+e) + 1/8 E I4 kappa^4  (per unit reference length)."""
    return (
        k.EA * s.eps**2 / 2
        + k.GA * s.g**2 / 2
        + k.EI * s.kappa**2 * (s.one_plus_e**2 + s.eps) / 2
        + k.EI3 * s.kappa**3 * s.one_plus_e / 2
        + k.EI4 * s.kappa**4 / 8
    )


def reissner_energy(s: Strains, k: Stiffness):
    """W_R = 1/2 EA e^2 + 1/2 k GA g^2 + 1/2 EI kappa^2."""
    e = s.one_plus_e - 1
    return k.EA * e**2 / 2 + k.shear_correction * k.GA * s.g**2 / 2 + k.EI * s.kappa**2 / 2


def strain_energy(law: str, s: Strains, k: Stiffness):
    """Energy density of the named law ("nonstandard" or "reissner"; the "hyperelastic" law
    needs its material and section: `fe_beam.section_laws.HyperelasticSectionLaw`)."""
    if law == "nonstandard":
        return nonstandard_energy(s, k)
    if law == "reissner":
        return reissner_energy(s, k)
    if law == "hyperelastic":
        raise ValueError("law = \"hyperelastic\" has no closed form in the section stiffnesses: "
                         "use fe_beam.section_laws.HyperelasticSectionLaw")
    raise ValueError(f"model.law must be one of {', '.join(LAWS)}; got {law!r}")


@dataclass(frozen=True)
class ClosedFormLaw:
    """A law whose energy is a closed form in the section stiffnesses ("nonstandard",
    "reissner"): ``energy(strains)`` = strain_energy(name, strains, stiffness)."""

    name: str
    stiffness: Stiffness

    def energy(self, s: Strains):
        return strain_energy(self.name, s, self.stiffness)

    def fibre_stretches(self, s: Strains) -> list:
        """The extreme fibres' axial stretches (none: the law does not integrate a profile)."""
        return []


def constrained_strains(constraint: str) -> tuple[str, ...]:
    """Strain measures a constraint sets to zero: 'eps' (lambda = 1), 'g' (gamma = 0)."""
    return {
        "none": (),
        "inextensible": ("eps",),
        "unshearable": ("g",),
        "inextensible-unshearable": ("eps", "g"),
    }[constraint]


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

"""Rod section laws from a 3D hyperelastic material: the uniaxial fibre energy of the 3D law
integrated over the cross-section (``[model] law = "hyperelastic"``).

Fibre strain (docs/theory.md, Section laws from 3D hyperelastic materials): a fibre at the
transverse coordinate eta (eta = -y, about the centroid) has the Green strain

    E11(eta) = eps + eta kappa (1 + e) + eta^2 kappa^2 / 2,
    1 + 2 E11 = (1 + e + eta kappa)^2 + g^2 = lambda_f^2          (fibre stretch lambda_f),

and the rod energy per unit reference length is

    W(eps, g, kappa) = int_A w(E11(eta)) dA + 1/2 G A g^2  ~  sum_j W_j w(E11(eta_j)) + G A g^2 / 2

with w the fibre energy per unit reference volume, G = mu0 the law's small-strain shear modulus
(E12 = g / 2 as in the non-standard law, no shear correction) and (eta_j, W_j) a Gauss rule of
the section (`section_rule`).

Fibre law (lateral assumption): the rod's sides are traction free, so each fibre is in uniaxial
stress: its lateral stretch is the one that makes the lateral stress vanish, with the 3D law's
own compressibility. For the isochoric/volumetric split laws (neo-Hookean, Mooney-Rivlin, Yeoh)
write F = J^(1/3) diag(a, a^(-1/2), a^(-1/2)) with a = lambda_f J^(-1/3); then

    w(lambda_f) = min_J [W_iso(Ib1, Ib2) + U(J)],   Ib1 = a^2 + 2/a,  Ib2 = 2a + 1/a^2,

and dw/dJ = 0 is solved by `NEWTON_STEPS` Newton steps written in closed form (UFL arithmetic,
also valid on floats and numpy arrays) from the small-strain guess J0 = lambda_f^(1 - 2 nu0). The
small-strain fibre modulus is then the 3D law's E = 9 kappa mu0 / (3 kappa + mu0) (an
incompressible fibre, J = 1, would give 3 mu0: 3.4 % stiffer at nu = 0.45); kappa = inf gives
J = 1 exactly. Saint-Venant-Kirchhoff is in uniaxial stress with w = 1/2 E E11^2 exactly,
E = mu (3 lambda + 2 mu) / (lambda + mu): integrated over the section it is the non-standard law.

Only ufl, numpy and math are imported: no dolfinx, no petsc4py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fe_beam.model.fibre import (  # noqa: F401  (their home; re-exported)
    CONSTANTS,
    FIBRE_MATERIALS,
    NEWTON_STEPS,
    RESOLVED_STRETCHES,
    RESOLVED_TOLERANCE,
    SOLID_NAMES,
    FibreLaw,
    _is_ufl,
    _sqrt,
    _z_minus_log1p,
    fibre_strain,
)
from fe_beam.model.laws import DEFAULT_SECTION_POINTS, MAX_SECTION_POINTS, NonStandard

__all__ = [
    "DEFAULT_SECTION_POINTS",
    "FIBRE_MATERIALS",
    "MAX_SECTION_POINTS",
    "NEWTON_STEPS",
    "FibreLaw",
    "HyperelasticSectionLaw",
    "SectionRule",
    "fibre_strain",
    "section_rule",
]

@dataclass(frozen=True)
class SectionRule:
    """Fibre positions eta_j (about the centroid, eta = -y) and weights W_j (area elements)."""

    etas: tuple
    weights: tuple
    extremes: tuple = ()

    def integrate(self, function):
        """sum_j W_j f(eta_j)."""
        return sum(w * function(eta) for eta, w in zip(self.etas, self.weights, strict=True))


def _legendre(n: int):
    points, weights = np.polynomial.legendre.leggauss(n)
    return [float(p) for p in points], [float(w) for w in weights]


def _chebyshev_second(n: int):
    """Nodes and weights of int_{-1}^{1} f(t) sqrt(1 - t^2) dt (exact for degree 2n - 1)."""
    angles = [(i + 1) * math.pi / (n + 1) for i in range(n)]
    return ([math.cos(t) for t in angles],
            [math.pi / (n + 1) * math.sin(t) ** 2 for t in angles])


def _strip(width, y_low, y_high, centroid, n):
    """Gauss-Legendre points of a rectangle width x [y_low, y_high]: eta = -(y - centroid)."""
    points, weights = _legendre(n)
    half, middle = (y_high - y_low) / 2, (y_high + y_low) / 2
    return ([-(middle + half * p - centroid) for p in points],
            [width * half * w for w in weights])


def _disc(radius, n, sign=1.0):
    points, weights = _chebyshev_second(n)
    return [radius * p for p in points], [sign * 2 * radius**2 * w for w in weights]


def section_rule(section, points: int, s=0.0, dims: dict | None = None,
                 dims_tip: dict | None = None) -> SectionRule | None:
    """The Gauss rule of ``section`` (a `fe_beam.model.sections.Section`) at s = x / L with
    ``points`` points per part (dims as in `Section.properties`: UFL symbols allowed); None for
    a custom section, whose profile is not known.

    rectangle: Gauss-Legendre in y; circle: Gauss-Chebyshev of the second kind (the width
    2 sqrt(r^2 - y^2) is its weight function, so polynomials in eta of degree 2n - 1 are exact);
    tube: the outer disc minus the inner one; t-section: web and flange rectangles about the
    centroid.
    """
    if section.shape == "custom":
        return None
    base = section.dims if dims is None else dims
    tip = section.dims_tip if dims_tip is None else dims_tip
    at = {n: v + (tip[n] - v) * s if n in tip else v for n, v in base.items()}
    if section.shape == "rectangle":
        etas, weights = _strip(at["b"], -at["h"] / 2, at["h"] / 2, 0.0, points)
        extremes = (-at["h"] / 2, at["h"] / 2)
    elif section.shape == "circle":
        etas, weights = _disc(at["d"] / 2, points)
        extremes = (-at["d"] / 2, at["d"] / 2)
    elif section.shape == "tube":
        outer, inner = _disc(at["d"] / 2, points), _disc(at["d"] / 2 - at["t"], points, -1.0)
        etas, weights = outer[0] + inner[0], outer[1] + inner[1]
        extremes = (-at["d"] / 2, at["d"] / 2)
    elif section.shape == "t-section":
        b, h, tf, tw = (at[n] for n in ("b", "h", "tf", "tw"))
        web, flange = tw * (h - tf), b * tf
        centroid = (web * (h - tf) / 2 + flange * (h - tf / 2)) / (web + flange)
        first = _strip(tw, 0.0 * h, h - tf, centroid, points)
        second = _strip(b, h - tf, h, centroid, points)
        etas, weights = first[0] + second[0], first[1] + second[1]
        extremes = (centroid - h, centroid)
    else:
        raise ValueError(f"no section rule for shape {section.shape!r}")
    return SectionRule(tuple(etas), tuple(weights), extremes)


@dataclass(frozen=True)
class HyperelasticSectionLaw:
    """W(strains) = sum_j W_j w(E11(eta_j)) + GA g^2 / 2 (per unit reference length).

    ``rule`` None (custom section): only svk, whose integral is the non-standard law of the
    section moments in ``stiffness`` (a `fe_beam.fem.kinematics.Stiffness` with E of the fibre law).
    ``constants`` maps the fibre law's constant names to UFL values (or is None: floats).
    """

    fibre: FibreLaw
    rule: SectionRule | None
    GA: Any
    stiffness: Any = None
    constants: dict | None = None

    def __post_init__(self):
        if self.rule is None and self.fibre.material != "svk":
            raise ValueError(
                f"material = \"{self.fibre.material}\" needs the section's profile: a custom "
                "section (only A, I, I3, I4) supports material = \"svk\" alone")

    def energy(self, s):
        """Energy density of the strains ``s`` (`fe_beam.fem.kinematics.Strains`)."""
        if self.rule is None:

            return NonStandard(self.stiffness).energy(s)
        fibres = self.rule.integrate(
            lambda eta: self.fibre.energy(fibre_strain(s, eta), self.constants))
        return fibres + self.GA * s.g**2 / 2

    def fibre_stretches(self, s) -> list:
        """1 + e + eta kappa at the two extreme fibres of the section (the axial part of the
        fibre stretch; <= 0: the fibre is folded onto itself, which the energy, a function of
        the stretch squared, cannot see); empty for a custom section."""
        if self.rule is None:
            return []
        return [s.one_plus_e + eta * s.kappa for eta in self.rule.extremes]

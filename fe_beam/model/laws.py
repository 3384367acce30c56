"""Rod laws as small dataclasses with the energy as a method (docs/theory.md, Non-standard
energy and Reissner law).

A law holds its section stiffnesses (`Stiffness`: floats or UFL values) and gives the stored
energy per unit reference length of the generalised strains (`Strains`) with ``energy(s)``;
``fibre_stretches(s)`` lists the extreme fibres' stretches of laws that integrate a section
profile (none here; `fe_beam.fem.section_laws.HyperelasticSectionLaw` does). Only arithmetic on the
strains enters: the classes import no UFL and no finite-element code.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

__all__ = [
    "CONSTRAINTS",
    "DEFAULT_SECTION_POINTS",
    "LAWS",
    "MAX_SECTION_POINTS",
    "LAW_KINDS",
    "LawKind",
    "ROD_LAWS",
    "NonStandard",
    "Reissner",
    "Stiffness",
    "Strains",
    "closed_form_law",
    "constrained_strains",
    "nonstandard_energy",
    "reissner_energy",
    "strain_energy",
]

LAWS = ("nonstandard", "reissner", "hyperelastic")
CONSTRAINTS = ("none", "inextensible", "unshearable", "inextensible-unshearable")
#: default Gauss points per section part of the hyperelastic section law (rectangle, circle;
#: tube and T: twice as many points): measured quadrature error ~5e-10 at fibre strains of
#: +-26%, far less at moderate strains (`fe_beam.fem.section_laws`)
DEFAULT_SECTION_POINTS = 6
MAX_SECTION_POINTS = 64


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


@dataclass(frozen=True)
class NonStandard:
    """The non-standard law of the source paper:

    W = 1/2 EA eps^2 + 1/2 GA g^2 + 1/2 EI kappa^2 ((1+e)^2 + eps)
        + 1/2 E I3 kappa^3 (1+e) + 1/8 E I4 kappa^4   (per unit reference length).
    """

    stiffness: Stiffness
    name: ClassVar[str] = "nonstandard"

    def energy(self, s: Strains):
        k = self.stiffness
        return (
            k.EA * s.eps**2 / 2
            + k.GA * s.g**2 / 2
            + k.EI * s.kappa**2 * (s.one_plus_e**2 + s.eps) / 2
            + k.EI3 * s.kappa**3 * s.one_plus_e / 2
            + k.EI4 * s.kappa**4 / 8
        )

    def fibre_stretches(self, s: Strains) -> list:
        """The extreme fibres' axial stretches (none: the law does not integrate a profile)."""
        return []


@dataclass(frozen=True)
class Reissner:
    """Reissner's law: W_R = 1/2 EA e^2 + 1/2 k GA g^2 + 1/2 EI kappa^2."""

    stiffness: Stiffness
    name: ClassVar[str] = "reissner"

    def energy(self, s: Strains):
        k = self.stiffness
        e = s.one_plus_e - 1
        return k.EA * e**2 / 2 + k.shear_correction * k.GA * s.g**2 / 2 + k.EI * s.kappa**2 / 2

    def fibre_stretches(self, s: Strains) -> list:
        return []


#: the laws whose energy is a closed form in the section stiffnesses, by config name
ROD_LAWS = {law.name: law for law in (NonStandard, Reissner)}


@dataclass(frozen=True)
class LawKind:
    """A rod law (``[model] law``) and what supports it: ``fd`` the paper's FD + Runge-Kutta
    schemes, ``differentiable`` the adjoint sensitivities, ``numbers_compiled`` whether its
    constants are compiled into the forms (a real-time update of them rebuilds the problem)."""

    name: str
    help: str
    closed_form: type | None = None
    fd: bool = False
    differentiable: bool = False
    numbers_compiled: bool = False


#: the rod laws with their capability flags (a new law: its dataclass and one entry here)
LAW_KINDS: dict[str, LawKind] = {kind.name: kind for kind in (
    LawKind("nonstandard", "the non-standard hyperelastic energy (2nd, 3rd, 4th moments)",
            NonStandard, fd=True, differentiable=True),
    LawKind("reissner", "the classical Reissner law EA, kGA, EI", Reissner, fd=True,
            differentiable=True),
    LawKind("hyperelastic", "the uniaxial fibre energy of a 3D hyperelastic law integrated "
            "over the section", numbers_compiled=True),
)}


def closed_form_law(name: str, stiffness: Stiffness):
    """The law ``name`` ("nonstandard" or "reissner") of these stiffnesses."""
    if name in ROD_LAWS:
        return ROD_LAWS[name](stiffness)
    if name == "hyperelastic":
        raise ValueError("law = \"hyperelastic\" has no closed form in the section stiffnesses: "
                         "use fe_beam.fem.section_laws.HyperelasticSectionLaw")
    raise ValueError(f"model.law must be one of {', '.join(LAWS)}; got {name!r}")


def nonstandard_energy(s: Strains, k: Stiffness):
    """`NonStandard` energy of the strains ``s`` (a function, for existing callers)."""
    return NonStandard(k).energy(s)


def reissner_energy(s: Strains, k: Stiffness):
    """`Reissner` energy of the strains ``s`` (a function, for existing callers)."""
    return Reissner(k).energy(s)


def strain_energy(law: str, s: Strains, k: Stiffness):
    """Energy density of the named law (`closed_form_law`)."""
    return closed_form_law(law, k).energy(s)


def constrained_strains(constraint: str) -> tuple[str, ...]:
    """Strain measures a constraint sets to zero: 'eps' (lambda = 1), 'g' (gamma = 0)."""
    return {
        "none": (),
        "inextensible": ("eps",),
        "unshearable": ("g",),
        "inextensible-unshearable": ("eps", "g"),
    }[constraint]

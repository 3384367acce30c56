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
import ufl

from fe_beam.model.laws import DEFAULT_SECTION_POINTS, MAX_SECTION_POINTS
from fe_beam.model.materials import small_strain_poisson, small_strain_young

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

#: Newton steps on dw/dJ = 0 (measured against the root-found fibre energy, every split law and
#: volumetric function, nu = 0.3 .. 0.4999: 3 steps 3.5e-12 relative over stretches 0.5 .. 2 and
#: ~1e-14 over 0.7 .. 1.4; 4 steps 4e-15, but the compiled forms' size and compile time grow
#: with every step, differentiated twice by UFL)
NEWTON_STEPS = 3
#: fibre stretches over which the fixed Newton steps are checked (`FibreLaw.unresolved`) and
#: outside which a state is refused (`fe_beam.fem.rod.StrainRange.inadmissible`): beyond them the
#: steps are not converged (measured: 60 % energy error at stretch 0.1 for nu = 0.45)
RESOLVED_STRETCHES = (0.5, 2.0)
#: largest relative departure of the fixed-step fibre energy from a converged solve allowed there
RESOLVED_TOLERANCE = 1e-9
FIBRE_MATERIALS = ("neo-hookean", "mooney-rivlin", "yeoh", "svk")
#: the 3D law's name (fe_beam.model.hyperelastic) -> the config name
SOLID_NAMES = {"neo_hookean": "neo-hookean", "mooney_rivlin": "mooney-rivlin", "yeoh": "yeoh",
               "saint_venant_kirchhoff": "svk"}
CONSTANTS = {"neo-hookean": ("mu",), "mooney-rivlin": ("c10", "c01"),
             "yeoh": ("c10", "c20", "c30"), "svk": ("mu",)}


def _is_ufl(*values) -> bool:
    return any(isinstance(v, ufl.core.expr.Expr) for v in values)


def _sqrt(value):
    return ufl.sqrt(value) if _is_ufl(value) else np.sqrt(value)


#: |z| below which z - ln(1 + z) is summed as its series (16 terms: error < 1e-15 relative)
SERIES_BOUND = 0.1
SERIES_TERMS = 16


def _z_minus_log1p(z):
    """z - ln(1 + z) without cancellation at small z: the series sum_{n>=2} (-1)^n z^n / n
    (Horner) where |z| < SERIES_BOUND, the closed form elsewhere."""
    series = 0.0
    for n in range(SERIES_TERMS + 1, 1, -1):
        series = (series + (-1) ** n / n) * z
    series = series * z
    if _is_ufl(z):
        # compiled forms: the closed form (the series and its branch multiply the generated
        # code; the cancellation it avoids only touches the energy's last digits at |z| < 1e-8)
        return z - ufl.ln(1 + z)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(np.abs(z) < SERIES_BOUND, series, z - np.log1p(z))


def fibre_strain(s, eta):
    """E11 of the fibre at eta: eps + eta kappa (1 + e) + eta^2 kappa^2 / 2 (``s``: Strains)."""
    return s.eps + eta * s.kappa * s.one_plus_e + eta**2 * s.kappa**2 / 2


@dataclass(frozen=True)
class FibreLaw:
    """The uniaxial-stress fibre energy w(E11) of a 3D hyperelastic law (see the module doc).

    ``material``: one of FIBRE_MATERIALS; ``coefficients``: floats, the constants of CONSTANTS
    and ``kappa`` (bulk modulus, may be inf except for svk); ``volumetric``: "simo_taylor" or
    "quadratic" (U(J) of the split laws; ignored by svk).
    """

    material: str
    coefficients: dict
    volumetric: str = "simo_taylor"
    newton_steps: int = NEWTON_STEPS

    def __post_init__(self):
        if self.material not in FIBRE_MATERIALS:
            raise ValueError(f"fibre law material must be one of {', '.join(FIBRE_MATERIALS)}; "
                             f"got {self.material!r}")
        missing = [k for k in CONSTANTS[self.material] + ("kappa",) if k not in self.coefficients]
        if missing:
            raise ValueError(f"fibre law {self.material}: missing constant {missing[0]}")
        if self.volumetric not in ("simo_taylor", "quadratic"):
            raise ValueError(f"fibre law volumetric must be simo_taylor or quadratic; got "
                             f"{self.volumetric!r}")
        if not self.shear_modulus > 0:
            raise ValueError(f"fibre law {self.material}: the small-strain shear modulus must be "
                             f"> 0; got {self.shear_modulus!r}")
        if not self.kappa > 0 or (self.material == "svk" and math.isinf(self.kappa)):
            raise ValueError(f"fibre law {self.material}: kappa must be > 0"
                             + (" and finite" if self.material == "svk" else ""))

    @classmethod
    def from_solid(cls, law, newton_steps: int = NEWTON_STEPS) -> FibreLaw:
        """The fibre law of a `fe_beam.model.hyperelastic.HyperelasticLaw` (duck-typed)."""
        coefficients = dict(law.coefficients())
        return cls(SOLID_NAMES[law.name], coefficients, law.volumetric, newton_steps)

    # --- small-strain constants ----------------------------------------------------------------
    @property
    def kappa(self) -> float:
        return float(self.coefficients["kappa"])

    @property
    def shear_modulus(self) -> float:
        """mu0, the small-strain shear modulus."""
        c = self.coefficients
        return float({"neo-hookean": lambda: c["mu"], "svk": lambda: c["mu"],
                      "mooney-rivlin": lambda: 2 * (c["c10"] + c["c01"]),
                      "yeoh": lambda: 2 * c["c10"]}[self.material]())

    @property
    def young_modulus(self) -> float:
        """E = 9 kappa mu0 / (3 kappa + mu0) (3 mu0 when kappa = inf): the fibre's modulus at
        E11 = 0 (for svk exactly mu (3 lambda + 2 mu) / (lambda + mu), the same number)."""
        return small_strain_young(self.shear_modulus, self.kappa)

    @property
    def poisson_ratio(self) -> float:
        return small_strain_poisson(self.shear_modulus, self.kappa)

    # --- energy -------------------------------------------------------------------------------
    def _values(self, c: dict | None) -> dict:
        return dict(self.coefficients) if c is None else {**self.coefficients, **c}

    def _psi(self, c, a):
        """(W_iso, dW_iso/da, d2W_iso/da2) of the isochoric stretch a (uniaxial)."""
        d1 = (a - 1) ** 2 * (a + 2) / a  # Ib1 - 3 = a^2 + 2/a - 3
        i1p, i1pp = 2 * a - 2 / a**2, 2 + 4 / a**3
        if self.material == "neo-hookean":
            half = c["mu"] / 2
            return half * d1, half * i1p, half * i1pp
        if self.material == "mooney-rivlin":
            d2 = (a - 1) ** 2 * (2 * a + 1) / a**2  # Ib2 - 3 = 2a + 1/a^2 - 3
            i2p, i2pp = 2 - 2 / a**3, 6 / a**4
            return (c["c10"] * d1 + c["c01"] * d2, c["c10"] * i1p + c["c01"] * i2p,
                    c["c10"] * i1pp + c["c01"] * i2pp)
        p1 = c["c10"] + 2 * c["c20"] * d1 + 3 * c["c30"] * d1**2
        p11 = 2 * c["c20"] + 6 * c["c30"] * d1
        return (c["c10"] * d1 + c["c20"] * d1**2 + c["c30"] * d1**3, p1 * i1p,
                p11 * i1p**2 + p1 * i1pp)

    def _volumetric(self, c, d):
        """(U, J U', d(J U')/dJ) at J = 1 + d, written in d = J - 1 so that nearly
        incompressible laws (J - 1 ~ 1e-5) keep their digits."""
        k = c["kappa"]
        if self.volumetric == "simo_taylor":
            z = d * (2 + d)  # J^2 - 1
            return k / 4 * _z_minus_log1p(z), k / 2 * z, k * (1 + d)
        return k / 2 * d**2, k * d * (1 + d), k * (1 + 2 * d)

    def volume_change(self, stretch_squared, c: dict | None = None):
        """J - 1 of the uniaxial-stress state of fibre stretch^2 (``newton_steps`` Newton steps
        on J dw/dJ = -a W_iso'(a) / 3 + J U'(J) = 0 from J0 = lambda^(1 - 2 nu0))."""
        c = self._values(c)
        if math.isinf(self.kappa):
            return 0 * stretch_squared
        root = _sqrt(stretch_squared)
        d = stretch_squared ** ((1 - 2 * self.poisson_ratio) / 2) - 1
        for _ in range(self.newton_steps):
            J = 1 + d
            a = root * J ** (-1.0 / 3.0)
            _, wp, wpp = self._psi(c, a)
            _, ju, ju_prime = self._volumetric(c, d)
            residual = -a * wp / 3 + ju
            slope = (wp + a * wpp) * a / (9 * J) + ju_prime
            d = d - residual / slope
        return d

    def energy(self, E11, c: dict | None = None):
        """w(E11) per unit reference volume (UFL, float or numpy array); ``c`` maps constant
        names to UFL values (e.g. fem.Constant) to keep the numbers out of compiled forms."""
        v = self._values(c)
        if self.material == "svk":
            lame = v["kappa"] - 2 * v["mu"] / 3
            young = v["mu"] * (3 * lame + 2 * v["mu"]) / (lame + v["mu"])
            return young * E11**2 / 2
        stretch_squared = 1 + 2 * E11
        if math.isinf(self.kappa):
            return self._psi(v, _sqrt(stretch_squared))[0]
        d = self.volume_change(stretch_squared, c)
        a = _sqrt(stretch_squared) * (1 + d) ** (-1.0 / 3.0)
        return self._psi(v, a)[0] + self._volumetric(v, d)[0]


    def unresolved(self) -> str | None:
        """Why the fixed Newton steps do not give this law's fibre energy over the stretches
        RESOLVED_STRETCHES (a converged solve of 60 steps is the reference), or None."""
        if self.material == "svk" or math.isinf(self.kappa):
            return None  # closed forms
        stretches = np.linspace(*RESOLVED_STRETCHES, 61)
        strains = (stretches**2 - 1) / 2
        converged = FibreLaw(self.material, self.coefficients, self.volumetric, 60)
        with np.errstate(all="ignore"):
            got = np.array([float(self.energy(e)) for e in strains])
            want = np.array([float(converged.energy(e)) for e in strains])
            error = np.abs(got - want) / np.maximum(np.abs(want), 1e-300)
        bad = ~np.isfinite(got) | ~np.isfinite(want) | (error > RESOLVED_TOLERANCE)
        if not bad.any():
            return None
        at = float(stretches[np.argmax(bad)])
        return (f"the uniaxial-stress fibre law of {self.material} (nu0 = "
                f"{self.poisson_ratio:.4g}, {self.volumetric}) is not resolved by its "
                f"{self.newton_steps} Newton steps at fibre stretch {at:.3g} (the range "
                f"{RESOLVED_STRETCHES[0]:g} .. {RESOLVED_STRETCHES[1]:g} must be)")

    def tangent(self, E11, step: float = 1e-4):
        """d2w/dE11^2 (floats or numpy arrays; central differences, ~1e-9 E accurate)."""
        E11 = np.asarray(E11, dtype=float)
        energy = lambda x: np.asarray(self.energy(x), dtype=float)  # noqa: E731
        return (energy(E11 + step) - 2 * energy(E11) + energy(E11 - step)) / step**2

    def min_tangent(self, low: float, high: float, samples: int = 65) -> float | None:
        """min d2w/dE11^2 / E over E11 in [low, high] (None if the range is not one of real
        fibres: 1 + 2 E11 <= 0 or not finite)."""
        if not (math.isfinite(low) and math.isfinite(high) and 1 + 2 * low > 4e-4):
            return None
        grid = np.linspace(low, max(low, high), samples)
        with np.errstate(all="ignore"):
            values = self.tangent(grid) / self.young_modulus
        return float(np.min(values)) if np.all(np.isfinite(values)) else None


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
            from fe_beam.model.laws import NonStandard

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

"""The uniaxial-stress fibre energy of a 3D hyperelastic law (`FibreLaw`), in floats or, when
its arguments are UFL expressions, in UFL: the material of the ``hyperelastic`` rod law, whose
section integration is `fe_beam.fem.section_laws` (docs/theory.md, Section laws)."""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass

import numpy as np

from fe_beam.model.materials import small_strain_poisson, small_strain_young

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
    """Whether any value is a UFL expression (none can be while UFL is not loaded: validating a
    configuration does not load it)."""
    ufl = sys.modules.get("ufl")
    return ufl is not None and any(isinstance(v, ufl.core.expr.Expr) for v in values)


def _sqrt(value):
    return sys.modules["ufl"].sqrt(value) if _is_ufl(value) else np.sqrt(value)


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
        return z - sys.modules["ufl"].ln(1 + z)
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

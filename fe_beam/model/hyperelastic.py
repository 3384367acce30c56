"""3D hyperelastic laws (pure UFL functions of F) and silicone presets.

All laws except Saint-Venant-Kirchhoff are split into an isochoric and a volumetric part,

    W(F) = W_iso(Ib1, Ib2) + U(J),   J = det F,  C = F^T F,
    Ib1 = J^(-2/3) tr C,   Ib2 = J^(-4/3) (tr(C)^2 - tr(C^2)) / 2,

with the volumetric energy (``volumetric``)

    "simo_taylor":  U(J) = kappa/4 (J^2 - 1 - 2 ln J)      (default; U -> inf as J -> 0)
    "quadratic":    U(J) = kappa/2 (J - 1)^2                (Abaqus, kappa = 2/D1)

Both have U(1) = U'(1) = 0 and U''(1) = kappa, so at small strain every law is linear elasticity
with shear modulus mu0 (below) and bulk modulus kappa, i.e. E = 9 kappa mu0 / (3 kappa + mu0),
nu = (3 kappa - 2 mu0) / (2 (3 kappa + mu0)). The mixed u-p (Taylor-Hood) formulation replaces
U(J) by p (J - 1) - p^2 / (2 kappa) whatever ``volumetric`` says (that is the quadratic U after
eliminating p; kappa = inf gives exact incompressibility).

Units: SI (Pa). The presets copy numbers from /work/shared/reference/materials.json (MPa there)
together with their provenance; the package never reads that file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from fe_beam.lazy import LazyModule
from fe_beam.model.materials import small_strain_poisson, small_strain_young

# UFL is imported when a law's energy is first built: validating a configuration does not load it
ufl = LazyModule("ufl")

__all__ = [
    "LAWS",
    "HyperelasticLaw",
    "SILICONE_PRESETS",
    "MooneyRivlin",
    "NeoHookean",
    "SaintVenantKirchhoff",
    "SiliconePreset",
    "Yeoh",
    "isochoric_invariants",
    "mooney_rivlin_energy",
    "neo_hookean_energy",
    "saint_venant_kirchhoff_energy",
    "silicone",
    "volumetric_energy",
    "yeoh_energy",
]

VOLUMETRIC_LAWS = ("simo_taylor", "quadratic")


# --- pure UFL functions -------------------------------------------------------------------------


def isochoric_invariants(F):
    """(Ib1, Ib2, J): Ib1 = J^(-2/3) I1, Ib2 = J^(-4/3) I2, I1 = tr C, I2 = (I1^2 - tr C^2)/2."""
    C = F.T * F
    J = ufl.det(F)
    I1 = ufl.tr(C)
    I2 = 0.5 * (I1**2 - ufl.tr(C * C))
    return J ** (-2.0 / 3.0) * I1, J ** (-4.0 / 3.0) * I2, J


def volumetric_energy(J, kappa, law: str = "simo_taylor"):
    """U(J) = kappa/4 (J^2 - 1 - 2 ln J) ("simo_taylor") or kappa/2 (J - 1)^2 ("quadratic")."""
    if law == "simo_taylor":
        return kappa / 4 * (J**2 - 1 - 2 * ufl.ln(J))
    if law == "quadratic":
        return kappa / 2 * (J - 1) ** 2
    raise ValueError(f"volumetric law must be one of {VOLUMETRIC_LAWS}, got {law!r}")


def neo_hookean_energy(F, mu):
    """W_iso = mu/2 (Ib1 - 3)."""
    Ib1, _, _ = isochoric_invariants(F)
    return mu / 2 * (Ib1 - 3)


def mooney_rivlin_energy(F, c10, c01):
    """W_iso = C10 (Ib1 - 3) + C01 (Ib2 - 3);  mu0 = 2 (C10 + C01)."""
    Ib1, Ib2, _ = isochoric_invariants(F)
    return c10 * (Ib1 - 3) + c01 * (Ib2 - 3)


def yeoh_energy(F, c10, c20, c30):
    """W_iso = C10 (Ib1 - 3) + C20 (Ib1 - 3)^2 + C30 (Ib1 - 3)^3;  mu0 = 2 C10."""
    Ib1, _, _ = isochoric_invariants(F)
    d = Ib1 - 3
    return c10 * d + c20 * d**2 + c30 * d**3


def saint_venant_kirchhoff_energy(F, lmbda, mu):
    """W = lambda/2 (tr E)^2 + mu tr(E^2),  E = (F^T F - I)/2 (no isochoric split)."""
    E = 0.5 * (F.T * F - ufl.Identity(F.ufl_shape[0]))
    return lmbda / 2 * ufl.tr(E) ** 2 + mu * ufl.tr(E * E)


# --- validated laws -----------------------------------------------------------------------------


def _number(owner: str, name: str, value, positive: bool = False, allow_inf: bool = False):
    ok = not isinstance(value, bool) and isinstance(value, (int, float)) and not math.isnan(value)
    if ok and not allow_inf:
        ok = math.isfinite(value)
    if ok and positive:
        ok = value > 0
    if not ok:
        what = "a number > 0" if positive else "a finite number"
        if allow_inf:
            what += " (or inf)"
        raise ValueError(f"{owner}.{name} must be {what}, got {value!r}")
    return float(value)


def _young_to_moduli(owner: str, E, nu) -> tuple[float, float]:
    """(mu, kappa) = (E / (2 (1 + nu)), E / (3 (1 - 2 nu)))."""
    E = _number(owner, "E", E, positive=True)
    nu = _number(owner, "nu", nu)
    if not (-1 < nu < 0.5):
        raise ValueError(f"{owner}.nu must be in (-1, 0.5), got {nu!r}")
    return E / (2 * (1 + nu)), E / (3 * (1 - 2 * nu))


@dataclass(frozen=True)
class HyperelasticLaw:
    """Base of the laws: bulk modulus ``kappa`` (Pa; inf only with the mixed formulation).

    Subclasses provide ``coefficients()`` (name -> float, Pa), ``shear_modulus`` (mu0) and
    ``isochoric_energy(F, c)``; ``strain_energy(F, c)`` = W_iso + U(J). Pass ``c`` (e.g. a dict
    of ``fem.Constant``) to keep the values out of the compiled form.
    """

    kappa: float
    volumetric: str = "simo_taylor"

    name = "law"
    supports_mixed = True

    def __post_init__(self):
        _number(self.name, "kappa", self.kappa, positive=True, allow_inf=True)
        if self.volumetric not in VOLUMETRIC_LAWS:
            raise ValueError(
                f"{self.name}.volumetric must be one of {', '.join(VOLUMETRIC_LAWS)}, "
                f"got {self.volumetric!r}"
            )
        if self.shear_modulus <= 0:
            raise ValueError(
                f"{self.name}: the small-strain shear modulus must be > 0, "
                f"got {self.shear_modulus!r} from {self.coefficients()}"
            )

    # subclasses define coefficients(), shear_modulus and isochoric_energy(F, c)

    @property
    def bulk_modulus(self) -> float:
        return float(self.kappa)

    @property
    def young_modulus(self) -> float:
        """E = 9 kappa mu / (3 kappa + mu) (= 3 mu when kappa = inf)."""
        return small_strain_young(self.shear_modulus, self.kappa)

    @property
    def poisson_ratio(self) -> float:
        """nu = (3 kappa - 2 mu) / (2 (3 kappa + mu)) (= 1/2 when kappa = inf)."""
        return small_strain_poisson(self.shear_modulus, self.kappa)

    def strain_energy(self, F, c: dict | None = None):
        """W(F) = W_iso(F) + U(J); ``c`` maps coefficient names to UFL values (default: floats)."""
        c = self.coefficients() if c is None else c
        if math.isinf(self.kappa):
            raise ValueError(f"{self.name}: kappa = inf needs the mixed u-p formulation")
        return self.isochoric_energy(F, c) + volumetric_energy(ufl.det(F), c["kappa"],
                                                               self.volumetric)


@dataclass(frozen=True)
class NeoHookean(HyperelasticLaw):
    """Compressible Neo-Hookean: W = mu/2 (Ib1 - 3) + U(J)."""

    mu: float = field(default=None, kw_only=True)
    name = "neo_hookean"

    def __post_init__(self):
        _number(self.name, "mu", self.mu, positive=True)
        super().__post_init__()

    @classmethod
    def from_young(cls, E: float, nu: float, **kw) -> NeoHookean:
        mu, kappa = _young_to_moduli(cls.name, E, nu)
        return cls(kappa=kappa, mu=mu, **kw)

    @property
    def shear_modulus(self) -> float:
        return float(self.mu)

    def coefficients(self) -> dict[str, float]:
        return {"mu": float(self.mu), "kappa": float(self.kappa)}

    def isochoric_energy(self, F, c: dict | None = None):
        c = self.coefficients() if c is None else c
        return neo_hookean_energy(F, c["mu"])


@dataclass(frozen=True)
class MooneyRivlin(HyperelasticLaw):
    """W = C10 (Ib1 - 3) + C01 (Ib2 - 3) + U(J), mu0 = 2 (C10 + C01).

    C01 < 0 (as uniaxial fits often give) is accepted as long as mu0 > 0; such a law is not
    Drucker-stable beyond the fitted range.
    """

    c10: float = field(default=None, kw_only=True)
    c01: float = field(default=0.0, kw_only=True)
    name = "mooney_rivlin"

    def __post_init__(self):
        _number(self.name, "c10", self.c10)
        _number(self.name, "c01", self.c01)
        super().__post_init__()

    @classmethod
    def from_young(cls, E: float, nu: float, c10_share: float = 0.5, **kw) -> MooneyRivlin:
        """mu = E/(2(1+nu)) split as C10 = c10_share mu/2, C01 = (1 - c10_share) mu/2."""
        if not (0.0 <= c10_share <= 1.0):
            raise ValueError(f"mooney_rivlin.c10_share must be in [0, 1], got {c10_share!r}")
        mu, kappa = _young_to_moduli(cls.name, E, nu)
        return cls(kappa=kappa, c10=c10_share * mu / 2, c01=(1 - c10_share) * mu / 2, **kw)

    @property
    def shear_modulus(self) -> float:
        return 2 * (self.c10 + self.c01)

    def coefficients(self) -> dict[str, float]:
        return {"c10": float(self.c10), "c01": float(self.c01), "kappa": float(self.kappa)}

    def isochoric_energy(self, F, c: dict | None = None):
        c = self.coefficients() if c is None else c
        return mooney_rivlin_energy(F, c["c10"], c["c01"])


@dataclass(frozen=True)
class Yeoh(HyperelasticLaw):
    """W = C10 (Ib1 - 3) + C20 (Ib1 - 3)^2 + C30 (Ib1 - 3)^3 + U(J), mu0 = 2 C10."""

    c10: float = field(default=None, kw_only=True)
    c20: float = field(default=0.0, kw_only=True)
    c30: float = field(default=0.0, kw_only=True)
    name = "yeoh"

    def __post_init__(self):
        _number(self.name, "c10", self.c10, positive=True)
        _number(self.name, "c20", self.c20)
        _number(self.name, "c30", self.c30)
        super().__post_init__()

    @classmethod
    def from_young(cls, E: float, nu: float, c20: float = 0.0, c30: float = 0.0, **kw) -> Yeoh:
        """All of mu = E/(2(1+nu)) goes to C10 = mu/2 (C20, C30 do not act at small strain)."""
        mu, kappa = _young_to_moduli(cls.name, E, nu)
        return cls(kappa=kappa, c10=mu / 2, c20=c20, c30=c30, **kw)

    @property
    def shear_modulus(self) -> float:
        return 2 * self.c10

    def coefficients(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in ("c10", "c20", "c30", "kappa")}

    def isochoric_energy(self, F, c: dict | None = None):
        c = self.coefficients() if c is None else c
        return yeoh_energy(F, c["c10"], c["c20"], c["c30"])


@dataclass(frozen=True)
class SaintVenantKirchhoff(HyperelasticLaw):
    """W = lambda/2 (tr E)^2 + mu tr(E^2), lambda = kappa - 2 mu / 3 (no split; displacement only).

    ``volumetric`` is ignored. SVK softens and loses stability in strong compression.
    """

    mu: float = field(default=None, kw_only=True)
    name = "saint_venant_kirchhoff"
    supports_mixed = False

    def __post_init__(self):
        _number(self.name, "mu", self.mu, positive=True)
        _number(self.name, "kappa", self.kappa, positive=True)
        super().__post_init__()

    @classmethod
    def from_young(cls, E: float, nu: float, **kw) -> SaintVenantKirchhoff:
        mu, kappa = _young_to_moduli(cls.name, E, nu)
        return cls(kappa=kappa, mu=mu, **kw)

    @property
    def shear_modulus(self) -> float:
        return float(self.mu)

    @property
    def lame_lambda(self) -> float:
        return self.kappa - 2 * self.mu / 3

    def coefficients(self) -> dict[str, float]:
        return {"mu": float(self.mu), "kappa": float(self.kappa)}

    def isochoric_energy(self, F, c=None):
        raise ValueError("saint_venant_kirchhoff has no isochoric/volumetric split (no mixed u-p)")

    def strain_energy(self, F, c: dict | None = None):
        c = self.coefficients() if c is None else c
        return saint_venant_kirchhoff_energy(F, c["kappa"] - 2 * c["mu"] / 3, c["mu"])


LAWS = {
    "neo_hookean": NeoHookean,
    "mooney_rivlin": MooneyRivlin,
    "yeoh": Yeoh,
    "saint_venant_kirchhoff": SaintVenantKirchhoff,
}


# --- silicone presets ---------------------------------------------------------------------------

_MARECHAL = (
    "Marechal et al., Soft Robotics 2021, doi:10.1089/soro.2019.0115; raw tensile data "
    "LucMarechal/Soft-Robotics-Materials-Database @ 8ff66c3 (ODbL), incompressible uniaxial fits "
    "for stretch <= 2 made for fe_beam (materials.json 'marechal_raw_data_fits'); strain is "
    "crosshead-derived, stiffness likely underestimated vs datasheets; MR fits have C01 < 0"
)
_SOROTOKI = (
    "BJCaasenbrood/SorotokiCode @ ca7a079, +preset/+material/*.m (Yeoh, MPa); "
    "materials.json 'repo_values'"
)
_POLYGERINOS = (
    "Elastosil M4601 Yeoh C10 = 0.11 MPa, C20 = 0.02 MPa, widely attributed to Polygerinos et al., "
    "IEEE T-RO 31(3):778-789, 2015 (second-hand, to be verified in the paper); density from the "
    "Wacker datasheet, second-hand"
)


@dataclass(frozen=True)
class SiliconePreset:
    """Fitted coefficients of one silicone (Pa), per law name, with where they come from."""

    name: str
    laws: dict
    source: str
    density: float | None = None


def _mpa(**c) -> dict:
    return {k: v * 1e6 for k, v in c.items()}


def _marechal(name, nh, mr, yeoh, density=1070.0):
    laws = {
        "neo_hookean": _mpa(c10=nh),
        "mooney_rivlin": _mpa(c10=mr[0], c01=mr[1]),
        "yeoh": _mpa(c10=yeoh[0], c20=yeoh[1], c30=yeoh[2]),
    }
    return SiliconePreset(name, laws, _MARECHAL, density)


SILICONE_PRESETS: dict[str, SiliconePreset] = {
    p.name: p
    for p in (
        _marechal("ecoflex-00-10", 0.003981, (0.005162, -0.002),
                  (0.003566, 0.0002175, -2.037e-05), 1040.0),
        _marechal("ecoflex-00-30", 0.008073, (0.01009, -0.00342),
                  (0.00718, 0.0006188, -0.0001136)),
        _marechal("ecoflex-00-50", 0.01121, (0.01435, -0.005332),
                  (0.009895, 0.0008514, -0.0001398)),
        _marechal("dragon-skin-10-medium", 0.02818, (0.04908, -0.03511),
                  (0.02045, 0.004473, -0.0005341)),
        _marechal("dragon-skin-20", 0.0802, (0.1431, -0.1066),
                  (0.05536, 0.0148, -0.002042), 1080.0),
        _marechal("dragon-skin-30", 0.1113, (0.1798, -0.1151),
                  (0.08656, 0.0138, -0.001466), 1080.0),
        _marechal("mold-star-20t", 0.06245, (0.08805, -0.04299),
                  (0.05397, 0.004072, -0.0001844), None),
        _marechal("rtv615", 0.2014, (0.3193, -0.1998), (0.1658, 0.01284, 0.0009442), None),
        _marechal("sortaclear-40", 0.1521, (0.1934, -0.06994),
                  (0.1391, 0.005253, 8.736e-05), None),
        SiliconePreset("ecoflex-00-30-sorotoki", {"yeoh": _mpa(c10=0.017, c20=-0.0002,
                                                               c30=2.3e-05)}, _SOROTOKI, 1070.0),
        SiliconePreset("ecoflex-00-50-sorotoki", {"yeoh": _mpa(c10=0.0145, c20=0.0001, c30=0.0)},
                       _SOROTOKI, 1070.0),
        SiliconePreset("dragon-skin-10-sorotoki", {"yeoh": _mpa(c10=0.036, c20=0.00025,
                                                                c30=2.3e-05)}, _SOROTOKI, 1070.0),
        SiliconePreset("dragon-skin-30-sorotoki", {"yeoh": _mpa(c10=0.1536, c20=0.0016, c30=0.0)},
                       _SOROTOKI, 1070.0),
        SiliconePreset("elastosil-m4601", {"yeoh": _mpa(c10=0.11, c20=0.02, c30=0.0)},
                       _POLYGERINOS, 1130.0),
    )
}

#: kappa / mu0 assumed by `silicone` (nu = 0.495): an assumption, not a measurement. Suitable
#: for the mixed u-p formulation; the displacement formulation wants 10-50 (nu 0.45-0.49).
DEFAULT_KAPPA_OVER_MU = 100.0


def silicone(
    name: str,
    law: str = "yeoh",
    kappa_over_mu: float = DEFAULT_KAPPA_OVER_MU,
    volumetric: str = "simo_taylor",
):
    """The preset ``name`` as a law object, with bulk modulus kappa = kappa_over_mu * mu0."""
    if name not in SILICONE_PRESETS:
        raise ValueError(
            f"silicone name must be one of {', '.join(sorted(SILICONE_PRESETS))}, got {name!r}"
        )
    preset = SILICONE_PRESETS[name]
    if law not in preset.laws:
        raise ValueError(
            f"silicone {name!r}: law must be one of {', '.join(preset.laws)}, got {law!r}"
        )
    kappa_over_mu = _number("silicone", "kappa_over_mu", kappa_over_mu, positive=True,
                            allow_inf=True)
    coeffs = preset.laws[law]
    mu0 = {"neo_hookean": lambda c: 2 * c["c10"],
           "mooney_rivlin": lambda c: 2 * (c["c10"] + c["c01"]),
           "yeoh": lambda c: 2 * c["c10"]}[law](coeffs)
    kappa = kappa_over_mu * mu0
    if law == "neo_hookean":
        return NeoHookean(kappa=kappa, mu=mu0, volumetric=volumetric)
    return LAWS[law](kappa=kappa, volumetric=volumetric, **coeffs)

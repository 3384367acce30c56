"""Linear-elastic constants of the rod models (the 3D laws live in fe_beam.solid)."""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Material", "small_strain_poisson", "small_strain_young"]


def _number(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"material.{name} must be a finite number, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class Material:
    """Young's modulus E, and Poisson's ratio nu or shear modulus G (exactly one); density rho.

    G = E / (2 (1 + nu)) when nu is given.
    """

    E: float
    nu: float | None = None
    G: float | None = None
    rho: float = 0.0

    def __post_init__(self):
        if _number("E", self.E) <= 0:
            raise ValueError(f"material.E must be > 0, got {self.E!r}")
        if (self.nu is None) == (self.G is None):
            raise ValueError(
                "material: give exactly one of nu (Poisson's ratio) or G (shear modulus)"
            )
        if self.nu is not None and not (-1 < _number("nu", self.nu) < 0.5):
            raise ValueError(f"material.nu must be in (-1, 0.5), got {self.nu!r}")
        if self.G is not None and _number("G", self.G) <= 0:
            raise ValueError(f"material.G must be > 0, got {self.G!r}")
        if _number("rho", self.rho) < 0:
            raise ValueError(f"material.rho must be >= 0, got {self.rho!r}")

    @property
    def shear_modulus(self) -> float:
        if self.G is not None:
            return float(self.G)
        return self.E / (2 * (1 + self.nu))

    @property
    def poisson_ratio(self) -> float:
        if self.nu is not None:
            return float(self.nu)
        return self.E / (2 * self.shear_modulus) - 1


def small_strain_young(mu: float, kappa: float) -> float:
    """Young's modulus of shear modulus mu and bulk modulus kappa: 9 kappa mu / (3 kappa + mu)
    (3 mu when kappa = inf)."""
    return 3 * mu if math.isinf(kappa) else 9 * kappa * mu / (3 * kappa + mu)


def small_strain_poisson(mu: float, kappa: float) -> float:
    """Poisson's ratio (3 kappa - 2 mu) / (2 (3 kappa + mu)) (1/2 when kappa = inf)."""
    return 0.5 if math.isinf(kappa) else (3 * kappa - 2 * mu) / (2 * (3 * kappa + mu))

"""Closed-form reference solutions used by demos, tests and benchmarks."""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.optimize import brentq
from scipy.special import ellipeinc, ellipkinc

__all__ = ["ElasticaTip", "elastica_tip_load", "timoshenko_cantilever_deflection"]


@dataclass(frozen=True)
class ElasticaTip:
    """Tip of a cantilever elastica under a dead transverse tip load, k = P L^2 / EI.

    shortening = -u_tip / L, deflection = |v_tip| / L, rotation = |theta_tip| (rad).
    """

    k: float
    shortening: float
    deflection: float
    rotation: float


def elastica_tip_load(k: float) -> ElasticaTip:
    """Inextensible, unshearable cantilever under a dead tip load (Mattiasson 1981).

    With alpha the tip rotation, p^2 = (1 + sin alpha) / 2 and sin(phi1) = 1 / (p sqrt 2):

        sqrt(k)         = F(pi/2, p) - F(phi1, p)
        x_tip / L       = sqrt(2 sin(alpha) / k)
        deflection / L  = 1 - 2 (E(pi/2, p) - E(phi1, p)) / sqrt(k)

    (F, E incomplete elliptic integrals of the first and second kind, modulus p).
    """
    if not (k > 0 and math.isfinite(k)):
        raise ValueError(f"k must be > 0, got {k!r}")

    def parts(alpha):
        m = (1 + math.sin(alpha)) / 2
        phi1 = math.asin(min(1.0, 1 / math.sqrt(2 * m)))
        return m, phi1

    def residual(alpha):
        m, phi1 = parts(alpha)
        return ellipkinc(math.pi / 2, m) - ellipkinc(phi1, m) - math.sqrt(k)

    alpha = brentq(residual, 1e-12, math.pi / 2 - 1e-12, xtol=1e-15, rtol=1e-15, maxiter=200)
    m, phi1 = parts(alpha)
    x_tip = math.sqrt(2 * math.sin(alpha) / k)
    deflection = 1 - 2 * (ellipeinc(math.pi / 2, m) - ellipeinc(phi1, m)) / math.sqrt(k)
    return ElasticaTip(k, 1 - x_tip, deflection, alpha)


def timoshenko_cantilever_deflection(P: float, L: float, EI: float, kGA: float) -> float:
    """Small-load tip deflection of a shear-deformable cantilever: P L^3/(3 EI) + P L/(k G A)."""
    return P * L**3 / (3 * EI) + P * L / kGA

"""A circular ring pinched across a diameter: the inextensible, unshearable elastica by shooting.

A plain numpy/scipy reference solver, independent of FEniCSx. A ring of radius R and bending
stiffness EI is squeezed by two opposite forces P along a diameter. By the two symmetries one
quarter suffices: from the loaded point (s = 0, the tangent at right angles to the load) to the
point a quarter of the circumference away (s = pi R / 2), where the tangent is parallel to the
load. The horizontal force across both cuts vanishes (the half ring's equilibrium across the
loaded diameter), so the section force is P / 2 along the load everywhere, and the bending
moment M(s) = M0 - (P / 2) x(s), x the distance from the loaded diameter. With the section angle
phi (phi = 0 at s = 0, the reference phi0 = -s / R):

    x' = cos phi,  y' = sin phi,  phi' = -1 / R + M / EI

and the one unknown M0 is shot for phi(pi R / 2) = -pi / 2. The loaded diameter shortens by
``delta`` = 2 (R + y(pi R / 2)) (y measured from the loaded point), the other lengthens by
2 (x(pi R / 2) - R). For small loads delta = (pi / 4 - 2 / pi) P R^3 / EI.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.integrate
import scipy.optimize

__all__ = ["pinched_ring"]


def _quarter(M0: float, P: float, R: float, EI: float):
    def rhs(_s, state):
        x, y, phi = state
        return [math.cos(phi), math.sin(phi), -1.0 / R + (M0 - 0.5 * P * x) / EI]

    return scipy.integrate.solve_ivp(rhs, (0.0, 0.5 * math.pi * R), [0.0, 0.0, 0.0],
                                     method="DOP853", rtol=1e-13, atol=1e-14 * R)


def pinched_ring(P: float, R: float, EI: float) -> dict:
    """{delta (the loaded diameter's shortening), widening (the other's lengthening), M0
    (the moment at the loaded points), M1 (at the other two), phi_side} of a ring pinched by
    P (P > 0 squeezes)."""
    guess = P * R / math.pi  # the linear theory's moment at the load

    def mismatch(M0):
        return float(_quarter(M0, P, R, EI).y[2, -1] + 0.5 * math.pi)

    # bracket the root about the linear theory's moment, then Brent's method to round-off
    # (a Newton-type root finder stalled at some loads: "not making good progress")
    low, high, width = 0.5 * guess, 1.5 * guess, abs(guess) + EI / R * 1e-12
    for _ in range(60):
        if mismatch(low) * mismatch(high) <= 0.0:
            break
        low, high, width = low - width, high + width, 2.0 * width
    else:
        raise RuntimeError("pinched ring shooting: no moment at the load closes the quarter")
    M0 = float(scipy.optimize.brentq(mismatch, low, high, xtol=1e-15 * (abs(guess) + EI / R),
                                     rtol=4 * np.finfo(float).eps, maxiter=200))
    x, y, phi = _quarter(M0, P, R, EI).y[:, -1]
    return {"delta": float(2 * (R + y)), "widening": float(2 * (x - R)), "M0": M0,
            "M1": float(M0 - 0.5 * P * x), "phi_side": float(phi)}


if __name__ == "__main__":  # the small-load limit
    EI, R = 1.0, 1.0
    for P in (1e-6, 1e-3, 1.0):
        ring = pinched_ring(P, R, EI)
        print(P, ring["delta"] / (P * R**3 / EI), math.pi / 4 - 2 / math.pi, ring)
    np.set_printoptions(precision=12)

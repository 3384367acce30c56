"""Closed-form buckling loads of the planar column (docs/theory.md, Linear buckling): the
bifurcation of the straight compressed state of the rod's own kinematics,

    EI_eff theta'' + c3 (P theta + R) = 0,    v' = c1 theta + c2 R,

with the coefficients of each law and constraint (R: the transverse end reaction). Independent of
the finite-element code: only the formulas and scipy's root finder."""

from __future__ import annotations

import math

from scipy.optimize import brentq

CASES = {  # (supports x0, supports xL)
    "clamped-free": ("clamped", "free"),
    "pinned-pinned": ("pinned", "roller"),
    "clamped-clamped": ("clamped", ["v", "theta"]),
}


def coefficients(law: str, constraint: str, EA: float, GA: float, EI: float, P: float):
    """(c1, c2, c3, EI_eff) at the compressive end force P."""
    if constraint == "inextensible-unshearable":
        return 1.0, 0.0, 1.0, EI
    if constraint == "inextensible":  # Engesser: the shear force is the multiplier's too
        c = GA / (GA - P)
        return c, 1.0 / (GA - P), c, EI
    if constraint != "none":
        raise ValueError(constraint)
    if law == "reissner":  # N = EA e: 1 + e = 1 - P/EA (Haringx with extension)
        a = 1.0 - P / EA
        return P / GA + a, 1.0 / GA, 1.0 + P / GA - P / EA, EI
    # non-standard law: EA eps a = -P, eps = (a^2 - 1)/2 (Green strain), W_eps r'.d = eps EA g
    a = brentq(lambda s: EA * (s * s - 1) / 2 * s + P, 1 / math.sqrt(3), 1.0 + 1e-12)
    eps = (a * a - 1) / 2
    beta = 1.0 / (GA + EA * eps)
    return beta * P + a, beta, GA * a * beta, EI * (a * a + eps)


def _k(law, constraint, EA, GA, EI, P):
    c1, c2, c3, EI_eff = coefficients(law, constraint, EA, GA, EI, P)
    return math.sqrt(c3 * P / EI_eff), c1, c2


def critical_loads(case: str, law: str, constraint: str, EA: float, GA: float, EI: float,
                   L: float, count: int = 3) -> list[float]:
    """The ``count`` lowest critical compressive end forces P."""

    def load_for(kL: float) -> float:  # the P whose k L is kL (k grows with P)
        def gap(P):
            return _k(law, constraint, EA, GA, EI, P)[0] * L - kL

        low = high = kL**2 * EI / L**2 / 4
        while gap(high) < 0:  # bracket: k grows with P
            low, high = high, min(high * 1.5, (high + limit) / 2)
            if high - low < 1e-12 * high:
                return math.inf  # no such mode below the law's limit
        return brentq(gap, low, high, xtol=1e-14 * high, rtol=1e-14)

    # the largest compressive force of the straight state (non-standard law: the Green strain's
    # EA eps (1 + e) peaks at 1 + e = 1/sqrt(3)); the shear terms need P < GA
    if constraint == "inextensible-unshearable":
        limit = math.inf
    elif constraint == "inextensible":
        limit = GA
    elif law == "reissner":
        limit = min(GA, EA)
    else:
        limit = min(GA, EA / (3 * math.sqrt(3)))
    limit = limit if math.isfinite(limit) else 1e12 * EI / L**2

    if case == "clamped-free":
        loads = [load_for((2 * n - 1) * math.pi / 2) for n in range(1, count + 1)]
    elif case == "pinned-pinned":
        loads = [load_for(n * math.pi) for n in range(1, count + 1)]
    else:
        loads = _clamped_clamped(load_for, law, constraint, EA, GA, EI, L, count)
    return [P for P in loads if math.isfinite(P)]


def _clamped_clamped(load_for, law, constraint, EA, GA, EI, L, count):
    loads = [load_for(2 * math.pi * m) for m in range(1, count + 1)]

    def antisymmetric(P: float) -> float:
        k, c1, c2 = _k(law, constraint, EA, GA, EI, P)
        half = k * L / 2
        return math.tan(half) - half * (1 - c2 * P / c1)

    for m in range(1, count + 1):  # kL/2 in (m pi, (m + 1/2) pi)
        low = load_for(2 * m * math.pi + 1e-9)
        high = load_for((2 * m + 1) * math.pi - 1e-6)
        if not math.isfinite(high):
            break
        loads.append(brentq(antisymmetric, low, high))
    return sorted(loads)[:count]

"""Independent numpy/scipy references for rod section laws derived from 3D hyperelastic laws.

Nothing here uses UFL, dolfinx or fe_beam (``from_solid_law`` only reads the public attributes
of an ``fe_beam.model.hyperelastic`` law object by duck typing). The references are written from the
formulas of docs/theory.md, section "Section laws from 3D hyperelastic materials", and are meant
to judge an implementation, so they favour accuracy over speed: root finding by ``brentq`` with
tight tolerances and adaptive ``scipy.integrate.quad`` over the exact section profile.

Material arguments, in this order everywhere (``law`` below means these four):

    law_name    "neo-hookean" | "mooney-rivlin" | "yeoh" | "svk" (also the fe_beam.solid names
                "neo_hookean", "mooney_rivlin", "saint_venant_kirchhoff")
    coeffs      dict (Pa): neo-hookean {"mu"} (or {"c10"}, mu = 2 c10); mooney-rivlin
                {"c10", "c01"}; yeoh {"c10", "c20", "c30"} (missing ones = 0); svk {"mu"}
    bulk        bulk modulus kappa (Pa); math.inf = incompressible (not for svk)
    volumetric  "simo_taylor": U = kappa/4 (J^2 - 1 - 2 ln J); "quadratic": U = kappa/2 (J - 1)^2
                (ignored by svk, whose W = lambda/2 (tr E)^2 + mu tr E^2, lambda = kappa - 2 mu/3)

In the section functions the material bulk modulus is called ``bulk`` and ``kappa`` is the rod
curvature; in ``principal_energy``/``fibre_*`` the third argument is the bulk modulus.

Fibre law (uniaxial stress, traction-free sides): the fibre stretch is l1 = sqrt(1 + 2 E11); the
lateral stretches l2 = l3 = a make W(l1, a, a) stationary in a (zero lateral stress), found by
``brentq`` on dW/da = 0 in a bracket around the incompressible guess a = l1^(-1/2) that is widened
until the sign changes; for bulk = inf, a = l1^(-1/2) exactly (J = 1). For svk the unknown is
a^2 (W is quadratic in the lateral Green strain), so the stationary point exists for every E11,
also where the formal a^2 = 1 - 2 nu E11 is negative (E11 > 1/(2 nu)); the result is then the
closed form 1/2 E E11^2 with E = mu (3 lambda + 2 mu)/(lambda + mu).
The fibre energy is evaluated without cancellation at small strain (J - 1 and the isochoric
stretch by expm1/log1p, U(J) in J - 1, Ib1 - 3 and Ib2 - 3 as products), so it keeps ~1e-13
relative accuracy down to E11 ~ 1e-4, also for kappa/mu0 ~ 1e4.
The fibre stress s = dw/dE11 (2nd Piola-Kirchhoff) follows from the envelope theorem:
s = (dW/dl1 at fixed a) / l1 (for bulk = inf the constraint a = l1^(-1/2) is differentiated).

Section: eta is the transverse coordinate with eta = -y (y about the centroid, along the
director d), E11(eta) = eps + eta kappa (1 + e) + eta^2 kappa^2 / 2 with
eps = ((1 + e)^2 + g^2 - 1)/2, i.e. 1 + 2 E11 = (1 + e + eta kappa)^2 + g^2; the rod energy per
unit length is W = int w(E11(eta)) dA + 1/2 mu0 A g^2 (mu0 = small-strain shear modulus).
Shapes and dimension names as in fe_beam/sections.py: rectangle (b, h), circle (d),
tube (d, t), t-section (b, h, tf, tw; web from y = 0 to h - tf, flange of width b on top).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy import integrate, optimize

__all__ = [
    "LAW_NAMES",
    "fibre_energy_exact",
    "fibre_stress_exact",
    "fibre_tangent_exact",
    "from_solid_law",
    "lateral_stretch",
    "principal_energy",
    "pure_bending",
    "section_area",
    "section_energy_exact",
    "section_gradient_exact",
    "section_moment_exact",
    "shear_modulus",
    "small_strain_modulus",
    "svk_pure_bending",
]

_ALIASES = {
    "neo-hookean": "neo-hookean",
    "neo_hookean": "neo-hookean",
    "mooney-rivlin": "mooney-rivlin",
    "mooney_rivlin": "mooney-rivlin",
    "yeoh": "yeoh",
    "svk": "svk",
    "saint_venant_kirchhoff": "svk",
}
LAW_NAMES = ("neo-hookean", "mooney-rivlin", "yeoh", "svk")
QUAD = {"epsabs": 0.0, "epsrel": 1e-12, "limit": 200}


# --- material -----------------------------------------------------------------------------------


def _name(law_name: str) -> str:
    if law_name not in _ALIASES:
        raise ValueError(f"unknown law {law_name!r}; one of {', '.join(_ALIASES)}")
    return _ALIASES[law_name]


def _c(coeffs: dict, key: str) -> float:
    return float(coeffs.get(key, 0.0))


def shear_modulus(law_name: str, coeffs: dict) -> float:
    """mu0: neo-hookean mu (= 2 c10), mooney-rivlin 2 (c10 + c01), yeoh 2 c10, svk mu."""
    name = _name(law_name)
    if name in ("neo-hookean", "svk"):
        return float(coeffs["mu"]) if "mu" in coeffs else 2 * _c(coeffs, "c10")
    if name == "mooney-rivlin":
        return 2 * (_c(coeffs, "c10") + _c(coeffs, "c01"))
    return 2 * _c(coeffs, "c10")


def small_strain_modulus(law_name: str, coeffs: dict, bulk: float) -> float:
    """Young's modulus of the linearised law: E = 9 kappa mu0 / (3 kappa + mu0) (3 mu0 if inf)."""
    mu0 = shear_modulus(law_name, coeffs)
    return 3 * mu0 if math.isinf(bulk) else 9 * bulk * mu0 / (3 * bulk + mu0)


def from_solid_law(law) -> tuple:
    """(law_name, coeffs, bulk, volumetric) of an fe_beam.model.hyperelastic law object."""
    coeffs = {k: v for k, v in law.coefficients().items() if k != "kappa"}
    return _name(law.name), coeffs, float(law.kappa), law.volumetric


def _iso(name: str, coeffs: dict, i1m3, i2m3):
    """(W_iso, dW/dIb1, dW/dIb2) of the isochoric part, from Ib1 - 3 and Ib2 - 3."""
    if name == "neo-hookean":
        mu = shear_modulus(name, coeffs)
        return mu / 2 * i1m3, mu / 2 + 0 * i1m3, 0 * i1m3
    if name == "mooney-rivlin":
        c10, c01 = _c(coeffs, "c10"), _c(coeffs, "c01")
        return c10 * i1m3 + c01 * i2m3, c10 + 0 * i1m3, c01 + 0 * i1m3
    c10, c20, c30 = _c(coeffs, "c10"), _c(coeffs, "c20"), _c(coeffs, "c30")
    d = i1m3
    return c10 * d + c20 * d**2 + c30 * d**3, c10 + 2 * c20 * d + 3 * c30 * d**2, 0 * i1m3


def _z_minus_log1p(z: float) -> float:
    """z - ln(1 + z), by its series where |z| < 1e-2 (no cancellation)."""
    if abs(z) < 1e-2:
        return sum((-1) ** n * z**n / n for n in range(2, 14))
    return z - math.log1p(z)


def _vol_energy_d(bulk: float, volumetric: str, d: float) -> float:
    """U at J = 1 + d, written in d so that it keeps its digits near J = 1:
    J^2 - 1 - 2 ln J = z - ln(1 + z) with z = d (2 + d)."""
    if volumetric == "simo_taylor":
        return bulk / 4 * _z_minus_log1p(d * (2 + d))
    if volumetric == "quadratic":
        return bulk / 2 * d**2
    raise ValueError(f"unknown volumetric law {volumetric!r}")


def _uniaxial_energy(name, coeffs, bulk, volumetric, E11: float, a: float) -> float:
    """W(l1, a, a) of a split law without cancellation at small strain: J - 1 = expm1(ln l1 +
    2 ln a), isochoric stretch alpha = l1 J^(-1/3) (lateral alpha^(-1/2)),
    Ib1 - 3 = (alpha - 1)^2 (alpha + 2)/alpha, Ib2 - 3 = (alpha - 1)^2 (2 alpha + 1)/alpha^2."""
    log_l1 = 0.5 * math.log1p(2 * E11)
    d = 0.0 if math.isinf(bulk) else math.expm1(log_l1 + 2 * math.log(a))
    am1 = math.expm1(log_l1 - math.log1p(d) / 3)
    alpha = 1 + am1
    w = _iso(name, coeffs, am1**2 * (alpha + 2) / alpha, am1**2 * (2 * alpha + 1) / alpha**2)[0]
    return float(w) + (0.0 if math.isinf(bulk) else _vol_energy_d(bulk, volumetric, d))


def _vol(bulk: float, volumetric: str, J):
    """(U(J), U'(J))."""
    if volumetric == "simo_taylor":
        return bulk / 4 * (J**2 - 1 - 2 * np.log(J)), bulk / 2 * (J - 1 / J)
    if volumetric == "quadratic":
        return bulk / 2 * (J - 1) ** 2, bulk * (J - 1)
    raise ValueError(f"unknown volumetric law {volumetric!r}")


def _svk_lame(coeffs: dict, bulk: float) -> tuple[float, float]:
    if math.isinf(bulk):
        raise ValueError("svk needs a finite bulk modulus")
    mu = shear_modulus("svk", coeffs)
    return bulk - 2 * mu / 3, mu


def principal_energy(law_name, coeffs, kappa, volumetric, l1, l2, l3):
    """3D strain energy density W from the principal stretches (numpy, broadcasting).

    J = l1 l2 l3, I1 = l1^2 + l2^2 + l3^2, I2 = l1^2 l2^2 + l2^2 l3^2 + l3^2 l1^2,
    Ib1 = J^(-2/3) I1, Ib2 = J^(-4/3) I2; W = W_iso(Ib1, Ib2) + U(J) (kappa = inf: U dropped,
    the caller must pass J = 1). svk: W = lambda/2 (sum E_i)^2 + mu sum E_i^2, E_i = (l_i^2 - 1)/2.
    """
    name = _name(law_name)
    l1, l2, l3 = (np.asarray(x, dtype=float) for x in (l1, l2, l3))
    if name == "svk":
        lam, mu = _svk_lame(coeffs, kappa)
        e1, e2, e3 = ((x**2 - 1) / 2 for x in (l1, l2, l3))
        return lam / 2 * (e1 + e2 + e3) ** 2 + mu * (e1**2 + e2**2 + e3**2)
    J = l1 * l2 * l3
    i1 = l1**2 + l2**2 + l3**2
    i2 = l1**2 * l2**2 + l2**2 * l3**2 + l3**2 * l1**2
    w_iso = _iso(name, coeffs, J ** (-2 / 3) * i1 - 3, J ** (-4 / 3) * i2 - 3)[0]
    if math.isinf(kappa):
        return w_iso
    return w_iso + _vol(kappa, volumetric, J)[0]


def _uniaxial_derivatives(name, coeffs, bulk, volumetric, l1, a, log_l1=None):
    """(dW/dl1 at fixed a, dW/da at fixed l1) of W(l1, a, a) (compressible isochoric laws).

    Written without cancellation near l1 = a = 1: the isochoric parts reduce to multiples of
    l1^2 - a^2 and the pressure to J - 1 = expm1(ln l1 + 2 ln a) (``log_l1`` = ln l1 from
    log1p(2 E11)/2 if given, which keeps the digits the float l1 = sqrt(1 + 2 E11) loses):
    dW/dl1 = 4/3 (l1^2 - a^2)/l1 (W1 J^-2/3 + W2 J^-4/3 a^2) + U'(J) a^2,
    dW/da  = 4/3 (a^2 - l1^2) (W1 J^-2/3 / a + W2 J^-4/3 a) + U'(J) 2 l1 a.
    """
    d = math.expm1((math.log(l1) if log_l1 is None else log_l1) + 2 * math.log(a))
    J = 1 + d
    i1 = l1**2 + 2 * a**2
    i2 = 2 * l1**2 * a**2 + a**4
    j23, j43 = J ** (-2 / 3), J ** (-4 / 3)
    _, w1, w2 = _iso(name, coeffs, j23 * i1 - 3, j43 * i2 - 3)
    if volumetric == "simo_taylor":
        dvol = bulk / 2 * d * (2 + d) / J  # kappa/2 (J - 1/J)
    elif volumetric == "quadratic":
        dvol = bulk * d
    else:
        raise ValueError(f"unknown volumetric law {volumetric!r}")
    diff = (l1 - a) * (l1 + a)
    d_l1 = 4 / 3 * diff / l1 * (w1 * j23 + w2 * j43 * a**2) + dvol * a * a
    d_a = -4 / 3 * diff * (w1 * j23 / a + w2 * j43 * a) + dvol * 2 * l1 * a
    return d_l1, d_a


def _stretch(E11: float) -> float:
    if not E11 > -0.5:
        raise ValueError(f"fibre strain E11 = {E11!r} <= -1/2 (no real stretch)")
    return math.sqrt(1 + 2 * E11)


def _lateral_scalar(name, coeffs, bulk, volumetric, E11: float) -> float:
    """Lateral stretch a (svk: a^2, possibly negative) of uniaxial stress."""
    l1 = _stretch(E11)
    if name == "svk":
        lam, mu = _svk_lame(coeffs, bulk)
        e1 = E11

        def dwdt(t):  # t = a^2, lateral Green strain (t - 1)/2, d/dt of W(E1, et, et)
            et = (t - 1) / 2
            return (lam * (e1 + 2 * et) + 2 * mu * et)

        return optimize.brentq(dwdt, -1e3 - 10 * abs(E11), 1e3 + 10 * abs(E11),
                               xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=500)
    a0 = l1**-0.5
    if math.isinf(bulk):
        return a0

    log_l1 = 0.5 * math.log1p(2 * E11)

    def f(a):
        return _uniaxial_derivatives(name, coeffs, bulk, volumetric, l1, a, log_l1)[1]

    lo, hi = a0, a0
    for _ in range(200):
        if f(lo) <= 0:
            break
        lo /= 1.5
    for _ in range(200):
        if f(hi) >= 0:
            break
        hi *= 1.5
    if not (f(lo) <= 0 <= f(hi)):
        raise RuntimeError(f"no zero-lateral-stress state bracketed at E11 = {E11}")
    if lo == hi:
        return lo
    return optimize.brentq(f, lo, hi, xtol=1e-15 * a0, rtol=4 * np.finfo(float).eps,
                           maxiter=500)


def lateral_stretch(law_name, coeffs, kappa, volumetric, E11):
    """Lateral stretch a = l2 = l3 of uniaxial stress at fibre strain E11 (svk: returns a^2)."""
    name = _name(law_name)
    return np.vectorize(lambda e: _lateral_scalar(name, coeffs, kappa, volumetric, e),
                        otypes=[float])(E11)


def _fibre_scalar(name, coeffs, bulk, volumetric, E11: float) -> tuple[float, float]:
    """(w, s = dw/dE11) at a scalar E11."""
    l1 = _stretch(E11)
    if name == "svk":
        lam, mu = _svk_lame(coeffs, bulk)
        et = (_lateral_scalar(name, coeffs, bulk, volumetric, E11) - 1) / 2
        w = lam / 2 * (E11 + 2 * et) ** 2 + mu * (E11**2 + 2 * et**2)
        return w, lam * (E11 + 2 * et) + 2 * mu * E11
    if math.isinf(bulk):
        w = _uniaxial_energy(name, coeffs, bulk, volumetric, E11, l1**-0.5)
        _, w1, w2 = _iso(name, coeffs, l1**2 + 2 / l1 - 3, 2 * l1 + 1 / l1**2 - 3)
        dw_dl1 = w1 * (2 * l1 - 2 / l1**2) + w2 * (2 - 2 / l1**3)
        return w, float(dw_dl1 / l1)
    a = _lateral_scalar(name, coeffs, bulk, volumetric, E11)
    w = _uniaxial_energy(name, coeffs, bulk, volumetric, E11, a)
    d_l1 = _uniaxial_derivatives(name, coeffs, bulk, volumetric, l1, a,
                                 0.5 * math.log1p(2 * E11))[0]
    return float(w), float(d_l1 / l1)


def fibre_energy_exact(law_name, coeffs, kappa, volumetric, E11):
    """Fibre energy w(E11) of uniaxial stress (lateral tractions free), vectorised over E11."""
    name = _name(law_name)
    return np.vectorize(lambda e: _fibre_scalar(name, coeffs, kappa, volumetric, e)[0],
                        otypes=[float])(E11)


def fibre_stress_exact(law_name, coeffs, kappa, volumetric, E11):
    """s = dw/dE11 (envelope theorem: dW/dl1 at the stationary lateral stretch, over l1)."""
    name = _name(law_name)
    return np.vectorize(lambda e: _fibre_scalar(name, coeffs, kappa, volumetric, e)[1],
                        otypes=[float])(E11)


def fibre_tangent_exact(law_name, coeffs, kappa, volumetric, E11, h: float = 1e-3):
    """ds/dE11 by a 4th-order central difference of ``fibre_stress_exact`` (step h).

    Accuracy: truncation O(h^4) plus the stress round-off over h; the stress is accurate to
    about 1e-16 kappa/mu0 relative (the pressure kappa (J - 1) from a root-found J), so for
    kappa/mu0 up to 1e4 the tangent is good to about 1e-9 relative.
    """
    E11 = np.asarray(E11, dtype=float)
    s = [fibre_stress_exact(law_name, coeffs, kappa, volumetric, E11 + k * h)
         for k in (-2, -1, 1, 2)]
    return (s[0] - 8 * s[1] + 8 * s[2] - s[3]) / (12 * h)


# --- sections -----------------------------------------------------------------------------------


def _t_geometry(dims):
    b, h, tf, tw = (float(dims[k]) for k in ("b", "h", "tf", "tw"))
    web, flange = tw * (h - tf), b * tf
    yc = (web * (h - tf) / 2 + flange * (h - tf / 2)) / (web + flange)
    return b, h, tf, tw, yc


def _integrate(shape: str, dims: dict, f) -> float:
    """int f(eta) dA over the section (eta = -y about the centroid), adaptive quad."""
    with warnings.catch_warnings():
        # quad reports round-off when the requested 1e-12 is at the level of w's own accuracy
        warnings.simplefilter("ignore", integrate.IntegrationWarning)
        return _integrate_profile(shape, dims, f)


def _integrate_profile(shape: str, dims: dict, f) -> float:
    if shape == "rectangle":
        b, h = float(dims["b"]), float(dims["h"])
        return b * integrate.quad(f, -h / 2, h / 2, **QUAD)[0]
    if shape in ("circle", "tube"):
        def disc(r):  # width 2 sqrt(r^2 - eta^2) = 2 (eta + r)^(1/2) (r - eta)^(1/2)
            return 2 * integrate.quad(f, -r, r, weight="alg", wvar=(0.5, 0.5), **QUAD)[0]

        r = float(dims["d"]) / 2
        return disc(r) if shape == "circle" else disc(r) - disc(r - float(dims["t"]))
    if shape == "t-section":
        b, h, tf, tw, yc = _t_geometry(dims)
        # y about the centroid: web [-yc, h - tf - yc], flange [h - tf - yc, h - yc]; eta = -y
        web = tw * integrate.quad(f, -(h - tf - yc), yc, **QUAD)[0]
        flange = b * integrate.quad(f, -(h - yc), -(h - tf - yc), **QUAD)[0]
        return web + flange
    raise ValueError(f"shape {shape!r} has no profile (rectangle, circle, tube, t-section)")


def section_area(shape: str, dims: dict) -> float:
    """A = int dA (by the same quadrature)."""
    return _integrate(shape, dims, lambda eta: 1.0)


def section_moment_exact(shape: str, dims: dict, n: int) -> float:
    """int eta^n dA about the centroid (n = 2, 3, 4 give I, I3, I4 of fe_beam.model.sections)."""
    return _integrate(shape, dims, lambda eta: eta**n)


def _fibre_strain(one_plus_e, g, kappa, eta):
    eps = (one_plus_e**2 + g**2 - 1) / 2
    return eps + eta * kappa * one_plus_e + eta**2 * kappa**2 / 2


def section_energy_exact(shape, dims, law_name, coeffs, bulk, volumetric, one_plus_e, g, kappa):
    """W(1 + e, g, kappa) = int w(E11(eta)) dA + 1/2 mu0 A g^2 (scalars)."""
    name = _name(law_name)

    def f(eta):
        return _fibre_scalar(name, coeffs, bulk, volumetric,
                             _fibre_strain(one_plus_e, g, kappa, eta))[0]

    shear = 0.5 * shear_modulus(name, coeffs) * section_area(shape, dims) * g**2
    return _integrate(shape, dims, f) + shear


def section_gradient_exact(shape, dims, law_name, coeffs, bulk, volumetric, one_plus_e, g,
                           kappa) -> tuple[float, float, float]:
    """(dW/d(1+e), dW/dg, dW/dkappa), differentiated under the integral:
    dE11/d(1+e) = 1 + e + eta kappa, dE11/dg = g, dE11/dkappa = eta (1 + e + eta kappa)."""
    name = _name(law_name)

    def s(eta):
        return _fibre_scalar(name, coeffs, bulk, volumetric,
                             _fibre_strain(one_plus_e, g, kappa, eta))[1]

    d_p = _integrate(shape, dims, lambda eta: s(eta) * (one_plus_e + eta * kappa))
    d_k = _integrate(shape, dims, lambda eta: s(eta) * eta * (one_plus_e + eta * kappa))
    area = section_area(shape, dims)
    d_g = (_integrate(shape, dims, s) + shear_modulus(name, coeffs) * area) * g
    return d_p, d_g, d_k


def pure_bending(shape, dims, law_name, coeffs, bulk, volumetric, moment,
                 guess: tuple[float, float] | None = None) -> tuple[float, float]:
    """(kappa, 1 + e) of a uniform rod bent by an end moment: g = 0, N = 0, M = moment.

    At g = 0, 1 + e = sqrt(1 + 2 eps), so W_eps = 0 <=> dW/d(1+e) = 0 and M = dW/dkappa.
    Solved with scipy.optimize.root (hybr) on the scaled residuals
    (dW/d(1+e) / EA, (dW/dkappa - moment) / EI), E the small-strain modulus, from the
    linear guess kappa = moment/EI, 1 + e = 1 (or ``guess``); returns the state if the
    residuals are below 1e-12, else raises.
    """
    E = small_strain_modulus(law_name, coeffs, bulk)
    area, inertia = section_area(shape, dims), section_moment_exact(shape, dims, 2)

    def residual(x):
        k, p = x
        d_p, _, d_k = section_gradient_exact(shape, dims, law_name, coeffs, bulk, volumetric,
                                             p, 0.0, k)
        return [d_p / (E * area), (d_k - moment) / (E * inertia) * math.sqrt(inertia / area)]

    x0 = guess if guess is not None else (moment / (E * inertia), 1.0)
    sol = optimize.root(residual, x0, method="hybr", tol=1e-14)
    if max(abs(r) for r in residual(sol.x)) > 1e-12:
        raise RuntimeError(f"pure bending did not converge: {sol.message}")
    return float(sol.x[0]), float(sol.x[1])


def svk_pure_bending(EA, EI, EI3, EI4, moment) -> tuple[float, float]:
    """(kappa, 1 + e) of pure bending of the non-standard (svk) law, from its closed form.

    W(eps, kappa) = 1/2 EA eps^2 + 1/2 EI kappa^2 (1 + 3 eps) + 1/2 EI3 kappa^3 (1 + e)
    + 1/8 EI4 kappa^4 with 1 + e = sqrt(1 + 2 eps) (g = 0). W_eps = 0 gives
    EA eps + 3/2 EI kappa^2 + 1/2 EI3 kappa^3 / (1 + e) = 0 (eps(kappa) by brentq on the
    increasing side of this function; for EI3 = 0
    eps = -3/2 EI/EA kappa^2), and M = EI kappa (1 + 3 eps) + 3/2 EI3 kappa^2 (1 + e)
    + 1/2 EI4 kappa^3 = moment is solved for the kappa nearest moment/EI on the loading branch.
    """
    def eps_of(k):
        if EI3 == 0:
            return -1.5 * EI / EA * k**2

        def f(eps):
            return EA * eps + 1.5 * EI * k**2 + 0.5 * EI3 * k**3 / math.sqrt(1 + 2 * eps)

        lo = -0.5 + 1e-12
        if EI3 * k**3 > 0:  # f is not monotone: bracket from its minimum (the fold side is not
            # a state of the loading branch)
            lo = max(lo, ((0.5 * EI3 * k**3 / EA) ** (2 / 3) - 1) / 2)
        return optimize.brentq(f, lo, 10.0, xtol=1e-16, rtol=4 * np.finfo(float).eps)

    def m_of(k):
        eps = eps_of(k)
        return (EI * k * (1 + 3 * eps) + 1.5 * EI3 * k**2 * math.sqrt(1 + 2 * eps)
                + 0.5 * EI4 * k**3)

    # march along the loading branch from 0 to the first kappa where M reaches the moment
    k_lin = moment / EI
    step, k = k_lin / 50, 0.0
    while (m_of(k + step) - moment) * math.copysign(1, moment) < 0:
        k += step
        if abs(k) > 50 * abs(k_lin):
            raise RuntimeError("moment beyond the largest the section can carry")
    k = optimize.brentq(lambda q: m_of(q) - moment, min(k, k + step), max(k, k + step),
                        xtol=1e-16, rtol=4 * np.finfo(float).eps)
    return k, math.sqrt(1 + 2 * eps_of(k))

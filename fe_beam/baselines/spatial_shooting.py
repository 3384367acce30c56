"""Spatial (3D) geometrically exact Cosserat cantilever solved by shooting.

A plain numpy/scipy reference solver, independent of FEniCSx and of the rest of fe_beam (it
imports nothing from the package), for the spatial rod of docs MODEL.md section 8. It is used to
verify the finite-element spatial rod.

Model
-----
Reference centreline along ``e1 = x``, ``s in [0, L]``; the section's ``h`` runs along ``y``,
``b`` along ``z``. ``R(s)`` maps body to world; its columns are the directors ``d1`` (section
normal), ``d2`` (``h`` direction), ``d3`` (``b`` direction). Clamped at ``s = 0``
(``r = 0``, ``R = I``), free at ``s = L``. Strains::

    v = R^T r'              (v - e1: stretch and the two shears)
    R' = R u^               (u = (torsion, curvature about d2, curvature about d3))

Simo-Reissner law with constant intrinsic curvature ``u0 = (k_twist, k_y, k_z)``::

    n_b = R^T n = diag(EA, GA, GA) (v - e1),     m_b = R^T m = diag(GJ, EIy, EIz) (u - u0)

``GA`` is the shear stiffness ``k G A`` (the shear correction factor is the caller's choice).
Constrained variants: ``extensible=False`` fixes ``v1 = 1``, ``shearable=False`` fixes
``v2 = v3 = 0`` (both: the Kirchhoff rod, ``v = e1``); the matching components of ``n_b`` are
then reactions. ``n``, ``m`` (world axes) are the force and moment exerted by the part beyond
``s`` on the part before it::

    n' + f = 0,     m' + r' x n + l = 0

with ``f``, ``l`` the distributed force and moment per reference length (dead, world axes) plus
the tendon loads below. The tip carries a dead (world) or follower (tip-frame) force and moment:
``n(L+) = F``, ``m(L+) = M`` (follower: ``F = R(L) F_b``, ``M = R(L) M_b``).

Tendons (Rucker & Webster 2011, IEEE T-RO 27(6), "Statics and dynamics of continuum robots
with general tendon routing and external loading")
-----------------------------------------------------------------------------------------
Tendon ``i``: body offset ``r_i(s) = (0, y_i(s), z_i(s))``, tension ``tau_i``, from the entry
``s = 0`` to the anchor ``s = L_i <= L``, frictionless. World path ``p_i = r + R r_i``::

    p_i' = R w_i,   w_i = v + u x r_i + r_i'        (body components)

The tendon pulls the rod with the distributed force ``f_i = tau_i (p_i' / |p_i'|)'`` and moment
``(R r_i) x f_i``; at the anchor with the point force ``-tau_i t_i(L_i)``, ``t_i = p_i'/|p_i'|``,
and its moment ``(R r_i) x (-tau_i t_i)``; there the resultants, hence the strains, jump, so
a tendon that continues past another's anchor is kinked and adds the point force
``tau_j (t_j(L_i+) - t_j(L_i-))`` (solved by fixed-point iteration). ``f_i`` depends on
``u'`` and ``v'``; Rucker & Webster write it (body components) as
``f_i^b = a_i + A_i v' - A_i r_i^ u'`` with::

    A_i = -tau_i (w_i^)^2 / |w_i|^3 = tau_i (I - w w^T / |w|^2) / |w|
    a_i = A_i (u x w_i + u x r_i' + r_i'')

and solve the explicit linear system (with ``A = sum A_i``, ``G = -sum A_i r_i^``,
``B = sum r_i^ A_i``, ``H = -sum r_i^ A_i r_i^``, ``a = sum a_i``, ``b = sum r_i^ a_i``)::

    [ K_se + A    G        ] [v']   [ -u x n_b - R^T f - a          ]
    [ B           K_bt + H ] [u'] = [ -u x m_b - v x n_b - R^T l - b ]

at every right-hand-side evaluation (``K_se = diag(EA, GA, GA)``, ``K_bt = diag(GJ, EIy, EIz)``).
Constrained components of ``v`` have ``v' = 0`` (their rows and columns are replaced by the
identity). The solver then integrates ``n' = -f - R sum f_i^b``,
``m' = -R (v x n_b) - l - R sum r_i x f_i^b``.

At the entry ``s = 0`` the tendon's potential ``tau l`` also gives the point force
``+tau t_i(0)`` at ``p_i(0)``: it is applied at the clamp, so it only enters the reported clamp
reaction (``base_force``, ``base_moment``), not the shape. The internal resultants at ``0+`` are
``n0``, ``m0``. With the entry force counted, the tendon loads on the rod have zero resultant:
for a rod loaded by tendons only the clamp reaction vanishes.

Offsets are given as numbers (constant) or callables of ``s`` returning ``(y, z)``; their
derivatives may be given, else they are computed by the complex step (``r_i'`` exactly,
``r_i''`` by the complex second-derivative formula ``Im[f(s + h w) + f(s - h w)] / h^2``,
``w = exp(i pi / 4)``, error ``O(h^4)``), with a fallback to central differences for callables
that do not accept complex arguments.

Method
------
Shooting: the state ``y = (r, q, n, m, l_i)`` (``q`` the unit quaternion of ``R``, renormalised
whenever ``R`` is formed; ``l_i`` the tendon lengths) is integrated from ``s = 0`` with the six
unknown internal resultants ``n(0+), m(0+)`` (``scipy.integrate.solve_ivp``, DOP853), segment by
segment between anchors (the anchor forces are jumps of ``n`` and ``m``), and the six tip
conditions are solved by Newton-Broyden iterations on the scaled residual (finite-difference
Jacobian, re-used between substeps and refreshed when convergence is slow), with
``scipy.optimize.root`` (``hybr``) as the fallback. The strains follow from the resultants,
``u = u0 + K_bt^-1 R^T m``, ``v = e1 + K_se^-1 R^T n`` (free components). Large loads are
reached by continuation in the load factor (all loads and tensions scaled together; ``u0`` is
not), each substep starting from a secant prediction of the previous two; substeps are halved
on failure. Intermediate substeps use a looser tolerance (``rtol <= 1e-9``), the last one the
requested ``rtol``; the final scaled tip residual is below ``max(1e-12, 10 rtol)``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.integrate
import scipy.optimize

__all__ = [
    "CantileverSolution",
    "Tendon",
    "quaternion_to_matrix",
    "solve_cantilever",
]

_E1 = np.array([1.0, 0.0, 0.0])
_OMEGA = complex(math.cos(math.pi / 4), math.sin(math.pi / 4))


# ------------------------------------------------------------------------------------------------
# Validation helpers
# ------------------------------------------------------------------------------------------------
def _check_real(name: str, value, *, positive: bool = False, nonnegative: bool = False) -> float:
    """Return ``float(value)``; raise ``ValueError`` naming ``name`` unless it is a finite real
    (with the sign rule)."""
    ok = isinstance(value, int | float | np.floating | np.integer) and not isinstance(value, bool)
    if not ok or not math.isfinite(float(value)):
        raise ValueError(f"{name} must be a finite real number, got {value!r}")
    if positive and not value > 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    if nonnegative and not value >= 0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return float(value)


def _vec3(name: str, value) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be a finite 3-vector, got {value!r}")
    return arr


# ------------------------------------------------------------------------------------------------
# Rotations
# ------------------------------------------------------------------------------------------------
def _hat(a) -> np.ndarray:
    """Skew matrix ``a^`` with ``a^ b = a x b``."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def _cross(a, b) -> np.ndarray:
    """``a x b`` for 3-vectors (much cheaper than ``np.cross`` on tiny arrays)."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def quaternion_to_matrix(q) -> np.ndarray:
    """Rotation matrix of the quaternion ``q = (w, x, y, z)`` (normalised first)."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _quat_rate(q, u) -> np.ndarray:
    """``q' = q (0, u) / 2`` (body angular rate ``u``, ``R' = R u^``)."""
    w, x, y, z = q
    a, b, c = u
    return 0.5 * np.array(
        [
            -x * a - y * b - z * c,
            w * a + y * c - z * b,
            w * b + z * a - x * c,
            w * c + x * b - y * a,
        ]
    )


# ------------------------------------------------------------------------------------------------
# Tendons
# ------------------------------------------------------------------------------------------------
def _as_offset_fn(value, name):
    if callable(value):
        return value
    arr = np.asarray(value, dtype=float)
    if arr.shape != (2,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be (y, z) numbers or a callable s -> (y, z), got {value!r}")
    return None


@dataclass(frozen=True)
class Tendon:
    """A frictionless tendon at constant tension ``tension`` [N] from ``s = 0`` to ``anchor``.

    Parameters
    ----------
    tension : float
        ``tau >= 0``.
    offset : (y, z) or callable
        Body offset ``r_i = (0, y, z)``: two numbers (constant offset) or a callable
        ``s -> (y(s), z(s))`` (numpy functions, so that it accepts complex ``s`` for the
        complex-step derivatives).
    anchor : float or None
        ``L_i`` (``None``: the tip ``L``).
    d_offset, dd_offset : callable or None
        ``s -> (y', z')`` and ``s -> (y'', z'')``; computed if omitted (module docstring).

    A tendon at ``+y`` offset bends the rod toward ``+y`` (``u3 > 0``).
    """

    tension: float
    offset: tuple[float, float] | Callable = (0.0, 0.0)
    anchor: float | None = None
    d_offset: Callable | None = None
    dd_offset: Callable | None = None

    def __post_init__(self):
        _check_real("tension", self.tension, nonnegative=True)
        if self.anchor is not None:
            _check_real("anchor", self.anchor, positive=True)
        if _as_offset_fn(self.offset, "offset") is None:
            object.__setattr__(self, "offset", tuple(float(v) for v in self.offset))
        for name in ("d_offset", "dd_offset"):
            fn = getattr(self, name)
            if fn is not None and not callable(fn):
                raise ValueError(f"{name} must be a callable s -> (., .), got {fn!r}")

    def s_anchor(self, length: float) -> float:
        """Anchor abscissa (``L`` when ``anchor`` is ``None``)."""
        return float(length if self.anchor is None else self.anchor)


class _Profile:
    """``s -> (r_i, r_i', r_i'')`` as body 3-vectors (first component zero)."""

    def __init__(self, tendon: Tendon, length: float):
        self.const = None if callable(tendon.offset) else np.array([0.0, *tendon.offset])
        self.f = tendon.offset
        self.df = tendon.d_offset
        self.ddf = tendon.dd_offset
        self.h1 = 1e-20 * length
        self.h2 = 1e-3 * length
        self.hfd = 2e-3 * length
        self.complex_ok = True

    def _call(self, fn, s):
        val = fn(s)
        return np.array([0.0, val[0], val[1]], dtype=complex if np.iscomplexobj(s) else float)

    def _complex_first(self, fn, s):
        """``(fn(s), fn'(s))`` by the complex step (one call)."""
        z = self._call(fn, complex(s, self.h1))
        return z.real, z.imag / self.h1

    def _fd(self, fn, s, order):
        h = self.hfd
        vals = [self._call(fn, s + k * h) for k in (-2, -1, 1, 2)]
        if order == 1:
            return (vals[0] - 8 * vals[1] + 8 * vals[2] - vals[3]) / (12 * h)
        mid = self._call(fn, s)
        return (-vals[0] + 16 * vals[1] - 30 * mid + 16 * vals[2] - vals[3]) / (12 * h * h)

    def __call__(self, s: float):
        if self.const is not None:
            return self.const, np.zeros(3), np.zeros(3)
        if self.complex_ok:
            try:
                return self._complex(s)
            except (TypeError, ValueError):
                self.complex_ok = False
        r = self._call(self.f, s)
        rp = self._call(self.df, s) if self.df is not None else self._fd(self.f, s, 1)
        if self.ddf is not None:
            rpp = self._call(self.ddf, s)
        elif self.df is not None:
            rpp = self._fd(self.df, s, 1)
        else:
            rpp = self._fd(self.f, s, 2)
        return r, rp, rpp

    def _complex(self, s):
        if self.df is not None:
            r = self._call(self.f, s)
            rp = self._call(self.df, s)
            if self.ddf is not None:
                return r, rp, self._call(self.ddf, s)
            return r, rp, self._complex_first(self.df, s)[1]
        r, rp = self._complex_first(self.f, s)
        if self.ddf is not None:
            return r, rp, self._call(self.ddf, s)
        h = self.h2
        zp = self._call(self.f, s + h * _OMEGA)
        zm = self._call(self.f, s - h * _OMEGA)
        return r, rp, (zp.imag + zm.imag) / (h * h)


# ------------------------------------------------------------------------------------------------
# The problem
# ------------------------------------------------------------------------------------------------
@dataclass
class _Rod:
    L: float
    K_se: np.ndarray  # diag(EA, GA, GA)
    K_bt: np.ndarray  # diag(GJ, EIy, EIz)
    free: np.ndarray  # bool mask of free v components
    u0: np.ndarray
    f: np.ndarray
    l: np.ndarray
    F: np.ndarray
    M: np.ndarray
    follower: bool
    taus: np.ndarray
    anchors: np.ndarray
    profiles: list
    scale_f: float

    def scaled(self, lam: float) -> _Rod:
        new = _Rod(**self.__dict__)
        new.f, new.l, new.F, new.M = lam * self.f, lam * self.l, lam * self.F, lam * self.M
        new.taus = lam * self.taus
        return new


def _strains(rod: _Rod, R, n, m):
    """``(n_b, m_b, v, u)`` from the world resultants."""
    n_b = R.T @ n
    m_b = R.T @ m
    u = rod.u0 + m_b / rod.K_bt
    v = _E1.copy()
    v[rod.free] += n_b[rod.free] / rod.K_se[rod.free]
    return n_b, m_b, v, u


def _tendon_w(v, u, prof_s):
    r_i, rp, _ = prof_s
    w = v + _cross(u, r_i) + rp
    nw = float(np.linalg.norm(w))
    if not nw > 0.0:
        raise RuntimeError("tendon path degenerates (|p_i'| = 0)")
    return w, nw


def _rhs_factory(rod: _Rod, active: Sequence[int]):
    n_t = len(rod.taus)
    eye3 = np.eye(3)
    fixed = np.flatnonzero(~rod.free)

    def rhs(s, y):
        q = y[3:7]
        R = quaternion_to_matrix(q)
        n, m = y[7:10], y[10:13]
        n_b, m_b, v, u = _strains(rod, R, n, m)
        dy = np.zeros(13 + n_t)
        dy[0:3] = R @ v
        dy[3:7] = _quat_rate(q / np.linalg.norm(q), u)
        if not active:
            dy[7:10] = -rod.f
            dy[10:13] = -R @ _cross(v, n_b) - rod.l
            return dy
        # Rucker & Webster's linear system for (v', u')
        mat = np.zeros((6, 6))
        mat[0:3, 0:3] = np.diag(rod.K_se)
        mat[3:6, 3:6] = np.diag(rod.K_bt)
        a_sum = np.zeros(3)
        b_sum = np.zeros(3)
        terms = []
        for k in active:
            prof_s = rod.profiles[k](s)
            r_i, rp, rpp = prof_s
            w, nw = _tendon_w(v, u, prof_s)
            what = w / nw
            A = rod.taus[k] * (eye3 - np.outer(what, what)) / nw
            a = A @ (_cross(u, w) + _cross(u, rp) + rpp)
            rh = _hat(r_i)
            mat[0:3, 0:3] += A
            mat[0:3, 3:6] -= A @ rh
            mat[3:6, 0:3] += rh @ A
            mat[3:6, 3:6] -= rh @ A @ rh
            a_sum += a
            b_sum += _cross(r_i, a)
            terms.append((r_i, A, rh, a))
            dy[13 + k] = nw
        rhs_v = -_cross(u, n_b) - R.T @ rod.f - a_sum
        rhs_u = -_cross(u, m_b) - _cross(v, n_b) - R.T @ rod.l - b_sum
        vec = np.concatenate([rhs_v, rhs_u])
        for j in fixed:  # v_j = const: v_j' = 0
            mat[j, :] = 0.0
            mat[:, j] = 0.0
            mat[j, j] = 1.0
            vec[j] = 0.0
        sol = np.linalg.solve(mat, vec)
        vp, up = sol[0:3], sol[3:6]
        f_t = np.zeros(3)
        l_t = np.zeros(3)
        for r_i, A, rh, a in terms:
            fi = a + A @ vp - A @ (rh @ up)
            f_t += fi
            l_t += _cross(r_i, fi)
        dy[7:10] = -rod.f - R @ f_t
        dy[10:13] = -R @ (_cross(v, n_b) + l_t) - rod.l
        return dy

    return rhs


def _segments(rod: _Rod) -> list[tuple[float, float]]:
    L = rod.L
    pts = sorted({0.0, L, *[float(a) for a in rod.anchors]})
    merged = [pts[0]]
    for p in pts[1:]:
        if p - merged[-1] > 1e-12 * L:
            merged.append(p)
    merged[-1] = L
    return list(zip(merged[:-1], merged[1:]))


def _active(rod: _Rod, a: float, b: float) -> list[int]:
    mid = 0.5 * (a + b)
    return [k for k in range(len(rod.taus)) if rod.anchors[k] > mid and rod.taus[k] >= 0.0]


def _tendon_tangent(rod: _Rod, k: int, s: float, y):
    """World unit tangent ``t_k`` and world offset ``R r_k`` at ``s`` for state ``y``."""
    R = quaternion_to_matrix(y[3:7])
    _, _, v, u = _strains(rod, R, y[7:10], y[10:13])
    prof_s = rod.profiles[k](s)
    w, nw = _tendon_w(v, u, prof_s)
    return R @ (w / nw), R @ prof_s[0]


def _anchor_jump(rod: _Rod, b: float, y_minus, ending, continuing):
    """Point loads at ``s = b`` where the tendons ``ending`` are anchored.

    Each ending tendon pulls the rod with ``-tau_k t_k(b-)`` at ``p_k``; ``n(b+) = n(b-) +
    tau_k t_k``, ``m(b+) = m(b-) + (R r_k) x tau_k t_k``. The resultants jump, so do the strains,
    and the tendons that continue past ``b`` are kinked there: each adds the point force
    ``tau_j (t_j(b+) - t_j(b-))`` at ``p_j``, which depends on the resultants at ``b+``
    (fixed-point iteration).
    """
    y = np.array(y_minus, dtype=float)
    for k in ending:
        t_k, rr = _tendon_tangent(rod, k, b, y_minus)
        y[7:10] += rod.taus[k] * t_k
        y[10:13] += _cross(rr, rod.taus[k] * t_k)
    if not continuing:
        return y
    fixed = y[7:13].copy()
    before = {j: _tendon_tangent(rod, j, b, y_minus) for j in continuing}
    scale = 1e-15 * (1.0 + np.abs(fixed).max())
    for _ in range(200):
        new = fixed.copy()
        for j in continuing:
            t_plus, rr = _tendon_tangent(rod, j, b, y)
            kink = rod.taus[j] * (t_plus - before[j][0])
            new[0:3] -= kink
            new[3:6] -= _cross(rr, kink)
        done = np.abs(new - y[7:13]).max() <= scale
        y[7:13] = new
        if done:
            return y
    raise RuntimeError(f"kink loads at s = {b:.6g}: fixed-point iteration did not converge")


def _integrate(rod: _Rod, base, rtol: float, dense: bool = False):
    """Integrate from ``s = 0`` with ``base = (n(0+), m(0+))``; return ``y(L+)`` and the
    per-segment ``solve_ivp`` results."""
    n_t = len(rod.taus)
    L = rod.L
    y = np.zeros(13 + n_t)
    y[3] = 1.0
    y[7:13] = base
    fs = rod.scale_f
    atol = 1e-3 * rtol * np.concatenate([[L] * 3, [1.0] * 4, [fs] * 3, [fs * L] * 3, [L] * n_t])
    sols = []
    for a, b in _segments(rod):
        active = _active(rod, a, b)
        sol = scipy.integrate.solve_ivp(
            _rhs_factory(rod, active),
            (a, b),
            y,
            method="DOP853",
            rtol=rtol,
            atol=atol,
            dense_output=dense,
        )
        if not sol.success:
            raise RuntimeError(f"solve_ivp failed on [{a:.6g}, {b:.6g}]: {sol.message}")
        sols.append((a, b, active, sol))
        y = sol.y[:, -1].copy()
        ending = [k for k in active if abs(rod.anchors[k] - b) <= 1e-12 * L]
        if ending and b < L * (1 - 1e-12):
            y = _anchor_jump(rod, b, y, ending, [k for k in active if k not in ending])
        elif ending:
            y = _anchor_jump(rod, b, y, ending, [])
    return y, sols


def _tip_residual(rod: _Rod, y_tip) -> np.ndarray:
    F, M = rod.F, rod.M
    if rod.follower:
        R = quaternion_to_matrix(y_tip[3:7])
        F, M = R @ F, R @ M
    fs = rod.scale_f
    return np.concatenate([(y_tip[7:10] - F) / fs, (y_tip[10:13] - M) / (fs * rod.L)])


class _Converged(Exception):
    """Raised from inside the root finder's residual once the tip conditions hold."""

    def __init__(self, z):
        super().__init__()
        self.z = z


def _fd_jacobian(residual, z, r, h: float = 1e-7) -> np.ndarray:
    """Forward-difference Jacobian of ``residual`` at ``z`` (``r = residual(z)``)."""
    jac = np.empty((len(r), len(z)))
    for j in range(len(z)):
        dz = np.zeros(len(z))
        dz[j] = h
        jac[:, j] = (residual(z + dz) - r) / h
    return jac


def _newton(residual, z, jac, tol: float, max_iter: int = 15):
    """Newton-Broyden iterations from ``z`` (``jac``: a Jacobian estimate or ``None``).

    Returns ``(z, jac)`` or ``None``. The step is halved while it does not reduce the residual;
    the Jacobian is recomputed by finite differences when convergence is slow.
    """
    r = residual(z)
    if jac is None:
        jac = _fd_jacobian(residual, z, r)
    fresh = True
    for _ in range(max_iter):
        size = np.abs(r).max()
        if size < tol:
            return z, jac
        try:
            dz = np.linalg.solve(jac, -r)
        except np.linalg.LinAlgError:
            return None
        lam = 1.0
        while True:
            z_new = z + lam * dz
            r_new = residual(z_new)
            if np.abs(r_new).max() < size or lam < 1.0 / 16:
                break
            lam *= 0.5
        step = z_new - z
        jac = jac + np.outer(r_new - r - jac @ step, step) / (step @ step)
        slow = np.abs(r_new).max() > 0.1 * size
        z, r = z_new, r_new
        if slow and not fresh:
            jac, fresh = _fd_jacobian(residual, z, r), True
        else:
            fresh = False
    return (z, jac) if np.abs(r).max() < tol else None


def _shoot(rod: _Rod, guess, rtol: float, tol: float, jac=None):
    """Solve the tip conditions for ``(n(0+), m(0+))``; returns ``(base, jac)`` or ``None``.

    Newton-Broyden iterations on the scaled residual (``jac``: the scaled Jacobian of a nearby
    solve, re-used), with ``scipy.optimize.root`` (``hybr``) as the fallback. The residual is
    accepted as soon as its largest component is below ``tol``.
    """
    scale = np.array([rod.scale_f] * 3 + [rod.scale_f * rod.L] * 3)

    def residual(z):
        try:
            y_tip, _ = _integrate(rod, z * scale, rtol)
        except (RuntimeError, np.linalg.LinAlgError):
            return np.full(6, 1e6)
        return _tip_residual(rod, y_tip)

    z0 = np.asarray(guess, dtype=float) / scale
    out = _newton(residual, z0, jac, tol)
    if out is not None:
        return out[0] * scale, out[1]

    def stopping(z):
        res = residual(z)
        if np.abs(res).max() < tol:
            raise _Converged(np.array(z, dtype=float))
        return res

    try:
        res = scipy.optimize.root(stopping, z0, method="hybr", options={"xtol": 1e-14})
    except _Converged as done:
        return done.z * scale, None
    if np.all(np.isfinite(res.fun)) and np.abs(res.fun).max() < tol:
        return res.x * scale, None
    return None


# ------------------------------------------------------------------------------------------------
# Results
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class CantileverSolution:
    """Static solution sampled on a uniform grid ``s`` (the anchors' left limits at jumps).

    Attributes
    ----------
    s : (n,) reference arclength.
    position : (n, 3) centreline ``r(s)``.
    frame : (n, 3, 3) ``R(s)`` (columns ``d1, d2, d3``).
    force, moment : (n, 3) internal ``n(s)``, ``m(s)`` (world axes).
    v, u : (n, 3) strains (body): ``v = R^T r'``, ``u`` with ``R' = R u^``.
    tip_position : (3,) ``r(L)``;  tip_frame : (3, 3) ``R(L)``.
    n0, m0 : (3,) internal resultants at ``0+`` (world), the shooting unknowns.
    base_force, base_moment : (3,) the clamp's reaction on the rod (moment about ``r(0) = 0``),
        including the tendon entry forces ``tau t_i(0)`` at ``p_i(0)``:
        ``base_force = -n0 - sum tau_i t_i(0)``,
        ``base_moment = -m0 - sum (R r_i)(0) x tau_i t_i(0)``.
    tendon_lengths : (k,) deformed tendon lengths ``int_0^L_i |p_i'| ds``.
    tip_load : (6,) the tip force and moment actually applied (world; follower loads rotated).
    length : ``L``.

    ``r(s)``, ``R(s)``, ``resultants(s)`` and ``strains(s)`` evaluate the integrator's dense
    output (7th order) anywhere in ``[0, L]``.
    """

    s: np.ndarray
    position: np.ndarray
    frame: np.ndarray
    force: np.ndarray
    moment: np.ndarray
    v: np.ndarray
    u: np.ndarray
    tip_position: np.ndarray
    tip_frame: np.ndarray
    n0: np.ndarray
    m0: np.ndarray
    base_force: np.ndarray
    base_moment: np.ndarray
    tendon_lengths: np.ndarray
    tip_load: np.ndarray
    length: float
    _rod: _Rod = field(repr=False, compare=False)
    _sols: list = field(repr=False, compare=False)

    def _state(self, s: float) -> np.ndarray:
        s = float(s)
        if not -1e-12 * self.length <= s <= self.length * (1 + 1e-12):
            raise ValueError(f"s must lie in [0, {self.length!r}], got {s!r}")
        for a, b, _, sol in self._sols:
            if s <= b:
                return sol.sol(min(max(s, a), b))
        return self._sols[-1][3].sol(self.length)

    def r(self, s: float) -> np.ndarray:
        """Centreline ``r(s)``."""
        return self._state(s)[0:3].copy()

    def R(self, s: float) -> np.ndarray:
        """Frame ``R(s)``."""
        return quaternion_to_matrix(self._state(s)[3:7])

    def resultants(self, s: float) -> tuple[np.ndarray, np.ndarray]:
        """``(n(s), m(s))`` in world axes."""
        y = self._state(s)
        return y[7:10].copy(), y[10:13].copy()

    def strains(self, s: float) -> tuple[np.ndarray, np.ndarray]:
        """``(v(s), u(s))`` in body axes."""
        y = self._state(s)
        _, _, v, u = _strains(self._rod, quaternion_to_matrix(y[3:7]), y[7:10], y[10:13])
        return v, u


def _solution(rod: _Rod, base, rtol: float, n_points: int) -> CantileverSolution:
    y_tip, sols = _integrate(rod, base, rtol, dense=True)
    L = rod.L
    s = np.linspace(0.0, L, n_points)
    ys = np.zeros((n_points, 13 + len(rod.taus)))
    for i, si in enumerate(s):
        for a, b, _, sol in sols:
            if si <= b or b == L:
                ys[i] = sol.sol(min(max(si, a), b))
                break
    frames = np.array([quaternion_to_matrix(q) for q in ys[:, 3:7]])
    vs, us = np.zeros((n_points, 3)), np.zeros((n_points, 3))
    for i in range(n_points):
        _, _, vs[i], us[i] = _strains(rod, frames[i], ys[i, 7:10], ys[i, 10:13])
    y0 = sols[0][3].y[:, 0]
    n0, m0 = y0[7:10].copy(), y0[10:13].copy()
    bf, bm = -n0, -m0
    for k in range(len(rod.taus)):
        t_k, rr = _tendon_tangent(rod, k, 0.0, y0)
        bf = bf - rod.taus[k] * t_k
        bm = bm - _cross(rr, rod.taus[k] * t_k)
    R_tip = quaternion_to_matrix(y_tip[3:7])
    F, M = (R_tip @ rod.F, R_tip @ rod.M) if rod.follower else (rod.F, rod.M)
    return CantileverSolution(
        s=s,
        position=ys[:, 0:3],
        frame=frames,
        force=ys[:, 7:10],
        moment=ys[:, 10:13],
        v=vs,
        u=us,
        tip_position=y_tip[0:3].copy(),
        tip_frame=R_tip,
        n0=n0,
        m0=m0,
        base_force=bf,
        base_moment=bm,
        tendon_lengths=y_tip[13:].copy(),
        tip_load=np.concatenate([F, M]),
        length=L,
        _rod=rod,
        _sols=sols,
    )


# ------------------------------------------------------------------------------------------------
# Driver
# ------------------------------------------------------------------------------------------------
def solve_cantilever(
    L: float,
    EA: float,
    GA: float,
    GJ: float,
    EIy: float,
    EIz: float,
    tip_force: Sequence[float] = (0.0, 0.0, 0.0),
    tip_moment: Sequence[float] = (0.0, 0.0, 0.0),
    follower: bool = False,
    u0: Sequence[float] = (0.0, 0.0, 0.0),
    distributed: Sequence[float] = (0.0, 0.0, 0.0),
    extensible: bool = True,
    shearable: bool = True,
    tendons: Sequence[Tendon] = (),
    *,
    distributed_moment: Sequence[float] = (0.0, 0.0, 0.0),
    steps: int = 4,
    rtol: float = 1e-12,
    n_points: int = 201,
    initial_guess: Sequence[float] | None = None,
) -> CantileverSolution:
    """Static equilibrium of a clamped-free spatial Cosserat rod (module docstring).

    Parameters
    ----------
    L : float
        Length.
    EA, GA, GJ, EIy, EIz : float
        Axial, shear (``k G A``), torsional and bending stiffnesses (``EIy`` about ``d2``,
        ``EIz = E int y^2 dA`` about ``d3``, the planar one). ``EA`` / ``GA`` are unused when
        ``extensible`` / ``shearable`` is ``False``.
    tip_force, tip_moment : 3-vectors
        World axes (dead), or tip-frame components when ``follower`` is ``True``.
    follower : bool
        Tip force and moment turn with the tip frame.
    u0 : 3-vector
        Constant intrinsic curvature ``(k_twist, k_y, k_z)``.
    distributed, distributed_moment : 3-vectors
        Dead force and moment per reference length (world axes).
    extensible, shearable : bool
        ``False`` constrains ``v1 = 1`` / ``v2 = v3 = 0``.
    tendons : sequence of Tendon
    steps : int
        Number of load substeps of the continuation (>= 1; halved on failure).
    rtol : float
        ``solve_ivp`` relative tolerance of the final solve (absolute tolerances are ``1e-3 rtol``
        times the natural scales).
    n_points : int
        Size of the uniform output grid (>= 2).
    initial_guess : (6,) ``(n(0+), m(0+))``, optional
        Skips the continuation: a single solve at the full load from this guess (falls back to
        the continuation if it fails).
    """
    L = _check_real("L", L, positive=True)
    stiff = {
        k: _check_real(k, val, positive=True)
        for k, val in (("EA", EA), ("GA", GA), ("GJ", GJ), ("EIy", EIy), ("EIz", EIz))
    }
    flags = (("follower", follower), ("extensible", extensible), ("shearable", shearable))
    for name, flag in flags:
        if not isinstance(flag, bool):
            raise ValueError(f"{name} must be a bool, got {flag!r}")
    if not isinstance(steps, int | np.integer) or isinstance(steps, bool) or steps < 1:
        raise ValueError(f"steps must be an integer >= 1, got {steps!r}")
    if not isinstance(n_points, int | np.integer) or isinstance(n_points, bool) or n_points < 2:
        raise ValueError(f"n_points must be an integer >= 2, got {n_points!r}")
    rtol = _check_real("rtol", rtol, positive=True)
    if rtol > 1e-4:
        raise ValueError(f"rtol must be <= 1e-4, got {rtol!r}")
    tendons = tuple(tendons)
    if not all(isinstance(t, Tendon) for t in tendons):
        raise ValueError(f"tendons must be Tendon instances, got {tendons!r}")
    for k, t in enumerate(tendons):
        if t.s_anchor(L) > L * (1 + 1e-12):
            raise ValueError(f"tendons[{k}].anchor must be <= L = {L!r}, got {t.anchor!r}")
    F = _vec3("tip_force", tip_force)
    M = _vec3("tip_moment", tip_moment)
    f = _vec3("distributed", distributed)
    lm = _vec3("distributed_moment", distributed_moment)
    k_bt = np.array([stiff["GJ"], stiff["EIy"], stiff["EIz"]])
    taus = np.array([t.tension for t in tendons], dtype=float)
    scale_f = max(
        float(np.linalg.norm(F)),
        float(np.linalg.norm(M)) / L,
        float(np.linalg.norm(f)) * L,
        float(np.linalg.norm(lm)),
        float(taus.sum()),
        float(k_bt.min()) / L**2,
    )
    rod = _Rod(
        L=L,
        K_se=np.array([stiff["EA"], stiff["GA"], stiff["GA"]]),
        K_bt=k_bt,
        free=np.array([extensible, shearable, shearable]),
        u0=_vec3("u0", u0),
        f=f,
        l=lm,
        F=F,
        M=M,
        follower=follower,
        taus=taus,
        anchors=np.array([min(t.s_anchor(L), L) for t in tendons], dtype=float),
        profiles=[_Profile(t, L) for t in tendons],
        scale_f=scale_f,
    )
    tol_final = max(1e-12, 10 * rtol)
    if initial_guess is not None:
        guess = np.asarray(initial_guess, dtype=float)
        if guess.shape != (6,):
            raise ValueError(f"initial_guess must be (n(0+), m(0+)), got {initial_guess!r}")
        out = _shoot(rod, guess, rtol, tol_final)
        if out is not None:
            return _solution(rod, out[0], rtol, n_points)
    base = _continuation(rod, steps, rtol, tol_final)
    return _solution(rod, base, rtol, n_points)


def _continuation(rod: _Rod, steps: int, rtol: float, tol_final: float) -> np.ndarray:
    """Load-factor continuation from the unloaded rod; returns ``(n(0+), m(0+))`` at ``lam = 1``.

    Each substep starts from the secant prediction of the last two solutions and re-uses the
    last Jacobian; a failed substep is retried with half the increment.
    """
    rtol_mid = max(rtol, 1e-9)
    history = [(0.0, np.zeros(6))]
    lam, dlam, jac = 0.0, 1.0 / steps, None
    for _ in range(80):
        target = min(1.0, lam + dlam)
        last = target >= 1.0
        if len(history) >= 2:
            (l0, b0), (l1, b1) = history[-2], history[-1]
            guess = b1 + (b1 - b0) * (target - l1) / (l1 - l0)
        else:
            guess = history[-1][1]
        out = _shoot(
            rod.scaled(target), guess, rtol if last else rtol_mid, tol_final if last else 1e-8, jac
        )
        if out is None:
            dlam *= 0.5
            jac = None
            if dlam < 1e-4:
                break
            continue
        lam = target
        base, jac = out
        history.append((lam, base))
        if last:
            return base
    raise RuntimeError(f"shooting did not converge (reached load factor {lam:.4g})")

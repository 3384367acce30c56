"""Tendon-driven tapered finger: linear Cosserat statics solved by shooting.

A plain numpy/scipy reference solver, independent of FEniCSx, for the finger chapter's own model
(chapter eqs. 3.1-3.9; docs/theory.md, Tendons). It is used to verify the finite-element
tendon model.

Model
-----
Planar rod in the x-y plane, reference arclength ``x in [0, L]``, clamped at ``x = 0``
(``r = 0``, ``theta = 0``), free at ``x = L``. Unshearable (section normal = axis tangent)::

    r'     = (1 + q) t,           t = (cos theta, sin theta),   d = (-sin theta, cos theta)
    N      = n . t = EA q         (q = 0 exactly when ``extensible=False``; N is then a reaction)
    m      = EJ_b kappa,          kappa = theta'            ("reference" curvature)
                                  kappa = theta' / (1 + q)  ("deformed", the chapter's eq. 3.1)

with a tapered rectangle ``H(x) = H0 + (H1 - H0) x / L``, ``A = B H``, ``J_b = B H^3 / 12``
(eq. 3.9). ``n`` and ``m`` are the force and moment exerted by the part beyond ``x`` on the part
before it; equilibrium (eq. 3.4, planar) reads ``n' + f = 0``, ``m' + (r' x n)_z + l = 0``.

Tendons (docs/theory.md, Tendons): path ``r_c = r + delta(x) d`` for ``x in (x_a, x_b)``, constant
tension ``tau``, potential ``tau * l`` with ``l = int |r_c'| dx``. Writing
``r_c' = alpha t + beta d`` with ``alpha = 1 + q - delta theta'``, ``beta = delta'`` and
``w = |r_c'|``, the unit tendon tangent is ``t_c = (alpha t + beta d) / w`` and the tendon angle
is ``psi = theta + atan2(beta, alpha)``. The loads on the rod are (Camarillo 2008, Rucker &
Webster 2011): a distributed force ``tau t_c' = tau psi' t_c^perp`` at ``r_c`` (its moment about
the axis is ``tau psi' delta beta / w``), a point force ``-tau t_c(x_b)`` at the anchor, a point
force ``+tau t_c(x_a)`` at the entry, and ``tau (t_c(x+) - t_c(x-))`` at every kink of a piecewise
linear offset. Several tendons superpose.

Two solution methods (``method=``), derived independently and compared in the tests:

``"shooting"`` (default)
    Integrate ``(r, theta, n, m, l_i)`` from the base with the unknown base reactions
    ``n(0+), m(0+)`` (``scipy.integrate.solve_ivp``) and solve the free-tip conditions
    ``n(L+) = 0``, ``m(L+) = 0`` with ``scipy.optimize.root``. The distributed tendon load
    depends on ``theta''`` and ``q'``, which depend on the load itself; the dependence is affine
    and is solved exactly at every right-hand-side evaluation. Point loads at breakpoints are
    applied as jumps of ``n`` and ``m`` (an implicit relation, solved by fixed-point iteration).
``"cut"``
    Cut rod and tendons together at ``x``: the free part beyond the cut carries no external load,
    so ``n = -sum tau t_c`` and ``m = sum tau delta alpha / w`` (only tendons active at ``x``).
    With the constitutive law this is a local algebraic system for ``(theta', q)`` (Newton), and
    ``theta``, ``r``, ``l`` follow by quadrature (``solve_ivp``).

The looped routing of the chapter (eq. 3.2) is two branches anchored at the tip with the same
tension (:func:`looped_tendon`); the crossing segment lies in the rigid tip section.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
import scipy.integrate
import scipy.optimize

CURVATURES = ("reference", "deformed")
METHODS = ("shooting", "cut")

__all__ = [
    "CURVATURES",
    "METHODS",
    "FingerSolution",
    "TaperedFinger",
    "Tendon",
    "default_finger",
    "looped_tendon",
    "rest_lengths",
    "solve_finger",
    "tension_for_pull_in",
    "tension_for_tip_angle",
    "with_tension",
]


# ------------------------------------------------------------------------------------------------
# Validation helpers
# ------------------------------------------------------------------------------------------------
def _check_real(name: str, value, *, positive: bool = False, nonnegative: bool = False) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``value`` is a finite real (with sign rule)."""
    ok = isinstance(value, int | float | np.floating | np.integer) and not isinstance(value, bool)
    if not ok or not math.isfinite(float(value)):
        raise ValueError(f"{name} must be a finite real number, got {value!r}")
    if positive and not value > 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    if nonnegative and not value >= 0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")


# ------------------------------------------------------------------------------------------------
# Tendons and offset profiles
# ------------------------------------------------------------------------------------------------
class _PiecewiseLinear:
    """``delta(x)`` piecewise linear through points ``(x_k, delta_k)``; ``delta'' = 0``."""

    def __init__(self, xs: Sequence[float], ds: Sequence[float]):
        self.xs = np.asarray(xs, dtype=float)
        self.ds = np.asarray(ds, dtype=float)
        self.kinks = tuple(float(v) for v in self.xs[1:-1])

    def __call__(self, x: float, ref: float) -> tuple[float, float, float]:
        """Return ``(delta, delta', delta'')`` at ``x`` on the piece that contains ``ref``."""
        i = int(np.searchsorted(self.xs, ref, side="right")) - 1
        i = min(max(i, 0), len(self.xs) - 2)
        slope = (self.ds[i + 1] - self.ds[i]) / (self.xs[i + 1] - self.xs[i])
        return float(self.ds[i] + slope * (x - self.xs[i])), float(slope), 0.0


class _Smooth:
    """``delta`` from user callables; ``delta''`` by central differences if not given."""

    kinks: tuple[float, ...] = ()

    def __init__(self, fns: tuple[Callable, ...], h: float):
        self.f, self.df = fns[0], fns[1]
        self.d2f = fns[2] if len(fns) > 2 else None
        self.h = h

    def __call__(self, x: float, ref: float) -> tuple[float, float, float]:
        """Return ``(delta, delta', delta'')`` at ``x`` (``ref`` is unused)."""
        if self.d2f is not None:
            d2 = float(self.d2f(x))
        else:
            d2 = (float(self.df(x + self.h)) - float(self.df(x - self.h))) / (2.0 * self.h)
        return float(self.f(x)), float(self.df(x)), d2


@dataclass(frozen=True)
class Tendon:
    """A frictionless tendon at constant tension, offset ``delta(x)`` along ``d``.

    Give exactly one offset description:

    - ``offset_base``, ``offset_tip``: ``delta(x) = b + (a - b) x / L`` (``b`` at ``x = 0``,
      ``a`` at ``x = L``);
    - ``points``: ``((x_0, delta_0), (x_1, delta_1), ...)``, piecewise linear, ``x_k`` increasing
      and covering ``[entry, anchor]``;
    - ``offset_fn``: ``(delta, delta')`` or ``(delta, delta', delta'')`` callables of ``x``
      (``delta''`` by central differences if omitted; only the shooting method needs it).

    Positive offsets lie on the ``+d`` side: pulling bends the rod counterclockwise (toward +y).

    Parameters
    ----------
    tension : float
        ``tau >= 0`` [N].
    entry, anchor : float
        ``x_a`` (default 0) and ``x_b`` (default ``None`` = the tip ``L``), ``x_a < x_b``.
    """

    tension: float
    offset_base: float | None = None
    offset_tip: float | None = None
    points: tuple[tuple[float, float], ...] | None = None
    offset_fn: tuple[Callable, ...] | None = None
    entry: float = 0.0
    anchor: float | None = None

    def __post_init__(self):
        _check_real("tension", self.tension, nonnegative=True)
        _check_real("entry", self.entry, nonnegative=True)
        if self.anchor is not None:
            _check_real("anchor", self.anchor, positive=True)
            if not self.anchor > self.entry:
                raise ValueError(
                    f"anchor must be > entry ({self.entry!r}), got anchor={self.anchor!r}"
                )
        linear = self.offset_base is not None or self.offset_tip is not None
        given = [linear, self.points is not None, self.offset_fn is not None]
        if sum(given) != 1:
            raise ValueError(
                "offset: give exactly one of (offset_base, offset_tip), points, offset_fn; "
                f"got offset_base={self.offset_base!r}, offset_tip={self.offset_tip!r}, "
                f"points={self.points!r}, offset_fn={self.offset_fn!r}"
            )
        if linear:
            _check_real("offset_base", self.offset_base)
            _check_real("offset_tip", self.offset_tip)
        if self.points is not None:
            pts = tuple((float(a), float(b)) for a, b in self.points)
            xs = [p[0] for p in pts]
            if len(pts) < 2 or not all(math.isfinite(v) for p in pts for v in p):
                raise ValueError(
                    f"points must be >= 2 finite (x, delta) pairs, got {self.points!r}"
                )
            if any(b <= a for a, b in zip(xs[:-1], xs[1:], strict=True)):
                raise ValueError(f"points: x must be strictly increasing, got x = {xs!r}")
            object.__setattr__(self, "points", pts)
        if self.offset_fn is not None:
            fns = tuple(self.offset_fn)
            if len(fns) not in (2, 3) or not all(callable(f) for f in fns):
                raise ValueError(
                    "offset_fn must be (delta, delta') or (delta, delta', delta'') callables, "
                    f"got {self.offset_fn!r}"
                )
            object.__setattr__(self, "offset_fn", fns)

    def x_b(self, length: float) -> float:
        """Anchor abscissa ``x_b`` (``L`` when ``anchor`` is ``None``)."""
        return float(length if self.anchor is None else self.anchor)

    def profile(self, length: float):
        """The offset ``delta`` as a callable ``(x, ref) -> (delta, delta', delta'')``."""
        if self.points is not None:
            return _PiecewiseLinear([p[0] for p in self.points], [p[1] for p in self.points])
        if self.offset_fn is not None:
            return _Smooth(self.offset_fn, 1e-5 * length)
        return _PiecewiseLinear([0.0, length], [self.offset_base, self.offset_tip])


def looped_tendon(
    a_l: float, b_l: float, a_r: float, b_r: float, length: float, tension: float
) -> tuple[Tendon, Tendon]:
    """The chapter's looped tendon (eq. 3.2) as two branches anchored at the tip.

    Each branch runs from offset ``b`` at the base to offset ``a`` at the anchorage (the chapter's
    definition of ``a`` and ``b``): ``d(x) = b + (a - b) x / L``. (The printed eq. 3.2,
    ``(a - b) s / L - b``, does not satisfy ``d(0) = b``, ``d(L) = a``; for the chapter's finger it
    would put the tendon outside the section.) Offsets are the planar (along ``n``) components,
    signed as in :class:`Tendon`. Both branches carry the same cable ``tension``; the crossing
    segment lies in the rigid tip section and adds no net load. If an actuator pulls both cable
    ends together with force ``T``, pass ``tension = T / 2``.

    Returns
    -------
    (left, right) : tuple of Tendon
    """
    _check_real("length", length, positive=True)
    left = Tendon(tension=tension, offset_base=b_l, offset_tip=a_l)
    right = Tendon(tension=tension, offset_base=b_r, offset_tip=a_r)
    return left, right


# ------------------------------------------------------------------------------------------------
# The finger
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TaperedFinger:
    """Tapered rectangular silicone finger with tendons.

    ``H(x) = H0 + (H1 - H0) x / L``, ``EA = ea_factor E B H``, ``EJ_b = E B H^3 / 12``.

    Parameters
    ----------
    length, width, height_base, height_tip, young : float
        ``L``, ``B``, ``H0``, ``H1``, ``E`` (SI, all > 0).
    tendons : sequence of Tendon
    extensible : bool
        ``False``: ``q = 0`` exactly (the axial force is a reaction).
    curvature : {"reference", "deformed"}
        ``m = EJ theta'`` or ``m = EJ theta' / (1 + q)`` (chapter's eq. 3.1).
    ea_factor : float
        Multiplies ``EA`` (> 0; large values approach the inextensible limit).
    """

    length: float = 0.1
    width: float = 0.02
    height_base: float = 0.02
    height_tip: float = 0.01
    young: float = 0.6e6
    tendons: tuple[Tendon, ...] = ()
    extensible: bool = True
    curvature: str = "deformed"
    ea_factor: float = 1.0

    def __post_init__(self):
        for name in ("length", "width", "height_base", "height_tip", "young", "ea_factor"):
            _check_real(name, getattr(self, name), positive=True)
        if not isinstance(self.extensible, bool):
            raise ValueError(f"extensible must be a bool, got {self.extensible!r}")
        if self.curvature not in CURVATURES:
            raise ValueError(f"curvature must be one of {CURVATURES}, got {self.curvature!r}")
        tendons = tuple(self.tendons)
        if not all(isinstance(t, Tendon) for t in tendons):
            raise ValueError(f"tendons must be Tendon instances, got {self.tendons!r}")
        tol = 1e-12 * self.length
        for k, t in enumerate(tendons):
            x_b = t.x_b(self.length)
            if t.entry >= self.length or x_b > self.length + tol:
                raise ValueError(
                    f"tendons[{k}]: entry/anchor must lie in [0, length={self.length!r}], "
                    f"got entry={t.entry!r}, anchor={x_b!r}"
                )
            if t.points is not None and (
                t.points[0][0] > t.entry + tol or t.points[-1][0] < x_b - tol
            ):
                raise ValueError(
                    f"tendons[{k}].points must cover [entry, anchor] = [{t.entry!r}, {x_b!r}], "
                    f"got x from {t.points[0][0]!r} to {t.points[-1][0]!r}"
                )
        object.__setattr__(self, "tendons", tendons)

    def height(self, x: float) -> float:
        """``H(x) = H0 + (H1 - H0) x / L``."""
        return self.height_base + (self.height_tip - self.height_base) * x / self.length

    def ea(self, x: float) -> tuple[float, float]:
        """``(EA, dEA/dx)`` with ``EA = ea_factor E B H``."""
        c = self.ea_factor * self.young * self.width
        return c * self.height(x), c * (self.height_tip - self.height_base) / self.length

    def ej(self, x: float) -> tuple[float, float]:
        """``(EJ_b, dEJ_b/dx)`` with ``EJ_b = E B H^3 / 12``."""
        h = self.height(x)
        c = self.young * self.width / 12.0
        return c * h**3, 3.0 * c * h**2 * (self.height_tip - self.height_base) / self.length


def default_finger(tension: float = 1.0, **overrides) -> TaperedFinger:
    """The chapter's finger: ``L = 0.1``, ``B = 0.02``, ``H: 0.02 -> 0.01`` m, ``E = 0.6`` MPa.

    One tendon from ``delta = 8`` mm at the base to 4 mm at the tip, anchored at the tip, with the
    given ``tension`` [N]. ``overrides`` replace :class:`TaperedFinger` fields (e.g.
    ``curvature="reference"``, ``extensible=False``).
    """
    tendon = Tendon(tension=tension, offset_base=0.008, offset_tip=0.004)
    params = dict(tendons=(tendon,))
    params.update(overrides)
    return TaperedFinger(**params)


def with_tension(
    finger: TaperedFinger, tension: float, tendons: Sequence[int] | None = None
) -> TaperedFinger:
    """Copy of ``finger`` with the tension of ``tendons`` (indices; default all) set."""
    idx = range(len(finger.tendons)) if tendons is None else tendons
    new = list(finger.tendons)
    for k in idx:
        new[k] = replace(new[k], tension=tension)
    return replace(finger, tendons=tuple(new))


# ------------------------------------------------------------------------------------------------
# Kinematics of one tendon
# ------------------------------------------------------------------------------------------------
def _tendon_frame(stretch: float, theta_p: float, delta: float, delta_p: float):
    """``alpha = 1 + q - delta theta'``, ``beta = delta'``, ``w = sqrt(alpha^2 + beta^2)``.

    ``r_c' = alpha t + beta d``; ``t_c = (alpha t + beta d) / w``.
    """
    alpha = stretch - delta * theta_p
    if alpha <= 0.0:
        raise RuntimeError(
            f"tendon path folds over (1 + q - delta theta' = {alpha:.3g} <= 0): load too large"
        )
    return alpha, delta_p, math.hypot(alpha, delta_p)


def _segments(finger: TaperedFinger) -> list[tuple[float, float]]:
    """Intervals between breakpoints (0, L, entries, anchors, offset kinks)."""
    L = finger.length
    pts = {0.0, L}
    for t in finger.tendons:
        x_a, x_b = t.entry, t.x_b(L)
        pts.update((x_a, x_b))
        pts.update(k for k in t.profile(L).kinks if x_a < k < x_b)
    xs = sorted(pts)
    merged = [xs[0]]
    for v in xs[1:]:
        if v - merged[-1] > 1e-12 * L:
            merged.append(v)
    merged[-1] = L
    return list(zip(merged[:-1], merged[1:], strict=True))


def _active(finger: TaperedFinger, mid: float | None):
    """Indices of tendons active on the segment with midpoint ``mid`` (``None``: none)."""
    if mid is None:
        return []
    L = finger.length
    return [k for k, t in enumerate(finger.tendons) if t.entry < mid < t.x_b(L)]


def rest_lengths(finger: TaperedFinger) -> np.ndarray:
    """Tendon lengths of the straight unloaded finger, ``l_0 = int sqrt(1 + delta'^2) dx``."""
    L = finger.length
    out = np.zeros(len(finger.tendons))
    for a, b in _segments(finger):
        mid = 0.5 * (a + b)
        for k in _active(finger, mid):
            prof = finger.tendons[k].profile(L)
            val, _ = scipy.integrate.quad(
                lambda x, p=prof, m=mid: math.sqrt(1.0 + p(x, m)[1] ** 2),
                a,
                b,
                epsabs=0,
                epsrel=1e-13,
            )
            out[k] += val
    return out


# ------------------------------------------------------------------------------------------------
# Constitutive law
# ------------------------------------------------------------------------------------------------
def _section_state(finger: TaperedFinger, x: float, theta: float, nx: float, ny: float, m: float):
    """From the resultants: ``N = n.t``, ``T = n.d``, ``q = N/EA``, ``theta'``, ``kappa``.

    ``kappa = m / EJ``; ``theta' = kappa`` ("reference") or ``(1 + q) kappa`` ("deformed").
    """
    c, s = math.cos(theta), math.sin(theta)
    N = nx * c + ny * s
    T = -nx * s + ny * c
    q = N / finger.ea(x)[0] if finger.extensible else 0.0
    kappa = m / finger.ej(x)[0]
    theta_p = kappa if finger.curvature == "reference" else (1.0 + q) * kappa
    return N, T, q, kappa, theta_p


# ------------------------------------------------------------------------------------------------
# Method 1: shooting on the full equilibrium equations
# ------------------------------------------------------------------------------------------------
def _shooting_rhs(finger: TaperedFinger, profiles, active, mid: float):
    """Right-hand side ``y' = F(x, y)`` on one segment, ``y = (rx, ry, theta, nx, ny, m, l_k)``.

    ``n' = -f``, ``m' = -(1 + q) T - l_z``, ``r' = (1 + q) t``, ``l_k' = w_k`` with
    ``f = sum tau psi' t_c^perp`` and ``l_z = sum tau psi' delta beta / w``, where
    ``psi' = theta' + (alpha beta' - beta alpha') / w^2``, ``alpha' = q' - delta' theta' -
    delta theta''``; ``theta''`` and ``q'`` follow from differentiating the constitutive law and
    depend affinely on the ``psi'`` (solved exactly).
    """
    taus = [finger.tendons[k].tension for k in active]
    n_t = len(finger.tendons)
    reference = finger.curvature == "reference"

    def rhs(x, y):
        theta, nx, ny, m = y[2], y[3], y[4], y[5]
        N, T, q, kappa, theta_p = _section_state(finger, x, theta, nx, ny, m)
        stretch = 1.0 + q
        ea, dea = finger.ea(x)
        ej, dej = finger.ej(x)
        geo = []
        for k in active:
            delta, delta_p, delta_pp = profiles[k](x, mid)
            alpha, beta, w = _tendon_frame(stretch, theta_p, delta, delta_p)
            geo.append((delta, delta_p, delta_pp, alpha, beta, w))

        def loads(psi_p):
            f_t = f_d = l_z = 0.0
            for tau, pp, (delta, _, _, alpha, beta, w) in zip(taus, psi_p, geo, strict=True):
                f_t -= tau * pp * beta / w
                f_d += tau * pp * alpha / w
                l_z += tau * pp * delta * beta / w
            m_p = -stretch * T - l_z
            q_p = ((-f_t + theta_p * T) - N * dea / ea) / ea if finger.extensible else 0.0
            kappa_p = m_p / ej - m * dej / ej**2
            theta_pp = kappa_p if reference else q_p * kappa + stretch * kappa_p
            new = [
                theta_p
                + (alpha * delta_pp - beta * (q_p - delta_p * theta_p - delta * theta_pp)) / w**2
                for delta, delta_p, delta_pp, alpha, beta, w in geo
            ]
            return np.array(new), f_t, f_d, m_p

        # psi' = A + B psi' (affine): identify A and B, then solve (I - B) psi' = A.
        n_a = len(active)
        base = loads(np.zeros(n_a))[0]
        mat = np.empty((n_a, n_a))
        for j in range(n_a):
            mat[:, j] = loads(np.eye(n_a)[j])[0] - base
        psi_p = np.linalg.solve(np.eye(n_a) - mat, base) if n_a else np.zeros(0)
        _, f_t, f_d, m_p = loads(psi_p)
        c, s = math.cos(theta), math.sin(theta)
        dy = np.zeros(6 + n_t)
        dy[0], dy[1], dy[2] = stretch * c, stretch * s, theta_p
        dy[3] = -(f_t * c - f_d * s)
        dy[4] = -(f_t * s + f_d * c)
        dy[5] = m_p
        for k, g in zip(active, geo, strict=True):
            dy[6 + k] = g[5]
        return dy

    return rhs


def _tangent_terms(finger, profiles, active, mid, x, y):
    """``sum tau t_c`` (global) and ``sum tau delta (d x t_c)`` for tendons in ``active``."""
    theta = y[2]
    _, _, q, _, theta_p = _section_state(finger, x, theta, y[3], y[4], y[5])
    c, s = math.cos(theta), math.sin(theta)
    fx = fy = mz = 0.0
    for k in active:
        tau = finger.tendons[k].tension
        delta, delta_p, _ = profiles[k](x, mid)
        alpha, beta, w = _tendon_frame(1.0 + q, theta_p, delta, delta_p)
        fx += tau * (alpha * c - beta * s) / w
        fy += tau * (alpha * s + beta * c) / w
        mz -= tau * delta * alpha / w  # d x t_c = -alpha / w
    return fx, fy, mz


def _jump(finger, profiles, x0, y_minus, mid_left, mid_right):
    """Point loads at a breakpoint: ``P = sum tau (t_c(x0+) - t_c(x0-))`` applied at ``r_c``.

    ``n(x0+) = n(x0-) - P``, ``m(x0+) = m(x0-) - sum tau delta d x (t_c+ - t_c-)``; ``t_c(x0+)``
    depends on ``n(x0+), m(x0+)`` (fixed-point iteration).
    """
    left = _active(finger, mid_left)
    right = _active(finger, mid_right)
    fl = _tangent_terms(finger, profiles, left, mid_left, x0, y_minus)
    y = np.array(y_minus, dtype=float)
    scale = 1e-15 * (1.0 + np.abs(y_minus[3:6]).max())
    for _ in range(200):
        fr = _tangent_terms(finger, profiles, right, mid_right, x0, y)
        new = np.array(y_minus[3:6]) - (np.array(fr) - np.array(fl))
        done = np.abs(new - y[3:6]).max() <= scale
        y[3:6] = new
        if done:
            return y
    raise RuntimeError(f"point load at x = {x0:.6g}: fixed-point iteration did not converge")


def _integrate(finger, profiles, segments, base, rtol, dense=False):
    """Integrate from ``x = 0`` with base reactions ``base = (n_x, n_y, m)`` at ``0+``.

    Returns the state at ``L+`` (after the tip point loads) and the per-segment solutions.
    """
    n_t = len(finger.tendons)
    L = finger.length
    scale_f = _force_scale(finger)
    atol = 1e-2 * rtol * np.array([L, L, 1.0, scale_f, scale_f, scale_f * L] + [L] * n_t)
    y = np.zeros(6 + n_t)
    y[3:6] = base
    sols = []
    mids = [0.5 * (a + b) for a, b in segments]
    for i, (a, b) in enumerate(segments):
        if i > 0:
            y = _jump(finger, profiles, a, y, mids[i - 1], mids[i])
        active = _active(finger, mids[i])
        sol = scipy.integrate.solve_ivp(
            _shooting_rhs(finger, profiles, active, mids[i]),
            (a, b),
            y,
            method="DOP853",
            rtol=rtol,
            atol=atol,
            dense_output=dense,
        )
        if not sol.success:
            raise RuntimeError(f"solve_ivp failed on [{a:.6g}, {b:.6g}]: {sol.message}")
        sols.append(sol)
        y = sol.y[:, -1].copy()
    y = _jump(finger, profiles, L, y, mids[-1], None)
    return y, sols


def _force_scale(finger: TaperedFinger) -> float:
    """Force scale ``max(sum tau, EJ(0) / L^2)`` for tolerances and residuals."""
    return max(sum(t.tension for t in finger.tendons), finger.ej(0.0)[0] / finger.length**2)


def _straight_guess(finger: TaperedFinger, profiles) -> np.ndarray:
    """Base reactions of the cut formula evaluated on the straight rod (``theta' = q = 0``)."""
    y = np.zeros(6 + len(finger.tendons))
    mid = 0.5 * _segments(finger)[0][1]
    fx, fy, mz = _tangent_terms(finger, profiles, _active(finger, mid), mid, 0.0, y)
    return np.array([-fx, -fy, -mz])


def _shoot(finger, profiles, segments, rtol, guess):
    """Solve ``n(L+) = 0``, ``m(L+) = 0`` for the base reactions; returns them."""
    f_s = _force_scale(finger)
    scale = np.array([f_s, f_s, f_s * finger.length])

    def residual(z):
        y_tip, _ = _integrate(finger, profiles, segments, z * scale, rtol)
        return y_tip[3:6] / scale

    try:
        res = scipy.optimize.root(
            residual, np.asarray(guess) / scale, method="hybr", options={"xtol": 1e-13}
        )
    except RuntimeError:  # an iterate left the admissible range (tendon path folding over)
        return None
    if np.abs(res.fun).max() < 1e-12:  # hybr may report "no progress" at round-off level
        return res.x * scale
    return None


def _solve_shooting(finger, rtol, guess):
    profiles = [t.profile(finger.length) for t in finger.tendons]
    segments = _segments(finger)
    if guess is None:
        guess = _straight_guess(finger, profiles)
    base = _shoot(finger, profiles, segments, rtol, guess)
    if base is None:  # continuation in the tensions
        base = np.zeros(3)
        for lam in np.linspace(0.1, 1.0, 10):
            scaled = replace(
                finger, tendons=tuple(replace(t, tension=lam * t.tension) for t in finger.tendons)
            )
            base = _shoot(scaled, profiles, segments, rtol, base)
            if base is None:
                raise RuntimeError(f"shooting did not converge at load factor {lam:.2f}")
    _, sols = _integrate(finger, profiles, segments, base, rtol, dense=True)
    return profiles, segments, sols


# ------------------------------------------------------------------------------------------------
# Method 2: cut through rod and tendons (local algebraic law + quadrature)
# ------------------------------------------------------------------------------------------------
def _cut_local(finger: TaperedFinger, x: float, terms, guess=None) -> tuple[float, float]:
    """Solve ``m = sum tau delta alpha / w`` and ``N = EA q = -sum tau alpha / w`` for
    ``(theta', q)`` by Newton, with ``m = EJ theta'`` or ``EJ theta' / (1 + q)``.

    ``terms`` is a list of ``(tau, delta, delta')``.
    """
    if not terms:
        return 0.0, 0.0
    ej = finger.ej(x)[0]
    ea = finger.ea(x)[0]
    ext = finger.extensible
    deformed = finger.curvature == "deformed"
    if guess is None:
        guess = (
            sum(t * d for t, d, _ in terms) / ej,
            -sum(t for t, _, _ in terms) / ea if ext else 0.0,
        )
    tp, q = guess
    for _ in range(100):
        c = 1.0 + q if deformed else 1.0
        r1, r2 = ej * tp / c, ea * q if ext else 0.0
        j11, j12, j21, j22 = ej / c, (-ej * tp / c**2 if deformed else 0.0), 0.0, ea
        for tau, delta, delta_p in terms:
            alpha, beta, w = _tendon_frame(1.0 + q, tp, delta, delta_p)
            g, dg = alpha / w, beta**2 / w**3  # d(alpha/w)/d alpha
            r1 -= tau * delta * g
            j11 += tau * delta**2 * dg
            j12 -= tau * delta * dg
            r2 += tau * g
            j21 -= tau * delta * dg
            j22 += tau * dg
        if ext:
            det = j11 * j22 - j12 * j21
            dtp, dq = (r1 * j22 - r2 * j12) / det, (j11 * r2 - j21 * r1) / det
        else:
            dtp, dq = r1 / j11, 0.0
        tp, q = tp - dtp, q - dq
        if abs(dtp) * finger.length <= 1e-15 * (1.0 + abs(tp) * finger.length) and abs(dq) <= 1e-15:
            return tp, q
    raise RuntimeError(f"cut method: local Newton did not converge at x = {x:.6g}")


def _cut_terms(finger, profiles, active, mid, x):
    return [(finger.tendons[k].tension,) + profiles[k](x, mid)[:2] for k in active]


def _solve_cut(finger, rtol):
    profiles = [t.profile(finger.length) for t in finger.tendons]
    segments = _segments(finger)
    n_t = len(finger.tendons)
    L = finger.length
    atol = 1e-2 * rtol * np.array([L, L, 1.0] + [L] * n_t)
    y = np.zeros(3 + n_t)
    sols = []
    for a, b in segments:
        mid = 0.5 * (a + b)
        active = _active(finger, mid)

        def rhs(x, z, active=active, mid=mid):
            terms = _cut_terms(finger, profiles, active, mid, x)
            tp, q = _cut_local(finger, x, terms)
            dz = np.zeros(3 + n_t)
            dz[0], dz[1], dz[2] = (1.0 + q) * math.cos(z[2]), (1.0 + q) * math.sin(z[2]), tp
            for k, (_, delta, delta_p) in zip(active, terms, strict=True):
                dz[3 + k] = _tendon_frame(1.0 + q, tp, delta, delta_p)[2]
            return dz

        sol = scipy.integrate.solve_ivp(
            rhs, (a, b), y, method="DOP853", rtol=rtol, atol=atol, dense_output=True
        )
        if not sol.success:
            raise RuntimeError(f"solve_ivp failed on [{a:.6g}, {b:.6g}]: {sol.message}")
        sols.append(sol)
        y = sol.y[:, -1].copy()
    return profiles, segments, sols


# ------------------------------------------------------------------------------------------------
# Results
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FingerSolution:
    """Static solution sampled on a uniform grid ``x`` (right limits at breakpoints, ``L-`` at
    the tip).

    Attributes
    ----------
    x : (n,) reference abscissa.
    position : (n, 2) axis ``r(x)``.
    theta : (n,) section rotation.
    curvature_b_reference : (n,) ``theta'`` (per reference length).
    curvature_b_deformed : (n,) ``kappa = theta' / (1 + q)`` (per deformed length).
    curvature_n, torsion : (n,) identically zero in plane (Fig. 3.8 a, b).
    axial_strain : (n,) ``q``.
    axial_force : (n,) ``N = n . t`` (negative: compression, Fig. 3.8 d).
    shear_force : (n,) ``T = n . d``.
    moment : (n,) ``m``.
    tendon_paths : tuple of (n, 2) ``r_c(x)`` (NaN outside ``[x_a, x_b]``).
    tendon_lengths, rest_lengths : (k,) ``l`` and ``l`` of the straight finger.
    base_force, base_moment : reactions ``n(0+)``, ``m(0+)``.
    method : str
    length : float, ``L`` (for ``tip_u``).
    """

    x: np.ndarray
    position: np.ndarray
    theta: np.ndarray
    curvature_b_reference: np.ndarray
    curvature_b_deformed: np.ndarray
    curvature_n: np.ndarray
    torsion: np.ndarray
    axial_strain: np.ndarray
    axial_force: np.ndarray
    shear_force: np.ndarray
    moment: np.ndarray
    tendon_paths: tuple[np.ndarray, ...]
    tendon_lengths: np.ndarray
    rest_lengths: np.ndarray
    base_force: np.ndarray
    base_moment: float
    method: str
    length: float = 0.0

    @property
    def compression(self) -> np.ndarray:
        """``-N``."""
        return -self.axial_force

    @property
    def pull_in(self) -> np.ndarray:
        """``l(0) - l(tau)`` per tendon."""
        return self.rest_lengths - self.tendon_lengths

    @property
    def tip_u(self) -> float:
        """``r_x(L) - L``."""
        return float(self.position[-1, 0] - self.length)

    @property
    def tip_v(self) -> float:
        """``r_y(L)``."""
        return float(self.position[-1, 1])

    @property
    def tip_theta(self) -> float:
        """``theta(L)``."""
        return float(self.theta[-1])


def _sample(finger, profiles, segments, sols, method, n_points) -> FingerSolution:
    """Evaluate the dense solutions on a uniform grid and post-process."""
    L = finger.length
    n_t = len(finger.tendons)
    x = np.linspace(0.0, L, n_points)
    starts = np.array([a for a, _ in segments])
    seg_of = np.clip(np.searchsorted(starts, x, side="right") - 1, 0, len(segments) - 1)
    out = {k: np.zeros(n_points) for k in ("th", "tp", "q", "N", "T", "m")}
    pos = np.zeros((n_points, 2))
    paths = [np.full((n_points, 2), np.nan) for _ in range(n_t)]
    for i, xi in enumerate(x):
        s = seg_of[i]
        mid = 0.5 * sum(segments[s])
        active = _active(finger, mid)
        y = sols[s].sol(xi)
        theta = y[2]
        if method == "shooting":
            N, T, q, _, tp = _section_state(finger, xi, theta, y[3], y[4], y[5])
            m = y[5]
        else:
            tp, q = _cut_local(finger, xi, _cut_terms(finger, profiles, active, mid, xi))
            fx, fy = _cut_force(finger, profiles, active, mid, xi, theta, q, tp)
            c, s_ = math.cos(theta), math.sin(theta)
            N, T = -(fx * c + fy * s_), -(-fx * s_ + fy * c)
            m = finger.ej(xi)[0] * (tp / (1.0 + q) if finger.curvature == "deformed" else tp)
        out["th"][i], out["tp"][i], out["q"][i] = theta, tp, q
        out["N"][i], out["T"][i], out["m"][i] = N, T, m
        pos[i] = y[0], y[1]
        for k, t in enumerate(finger.tendons):
            if t.entry - 1e-12 * L <= xi <= t.x_b(L) + 1e-12 * L:
                delta = profiles[k](xi, min(max(xi, t.entry), t.x_b(L)))[0]
                paths[k][i] = y[0] - delta * math.sin(theta), y[1] + delta * math.cos(theta)
    y_end = sols[-1].y[:, -1]
    lengths = np.array(y_end[6:] if method == "shooting" else y_end[3:], dtype=float)
    zeros = np.zeros(n_points)
    c0, s0 = math.cos(out["th"][0]), math.sin(out["th"][0])
    n0, t0 = out["N"][0], out["T"][0]
    base_force = np.array([n0 * c0 - t0 * s0, n0 * s0 + t0 * c0])
    return FingerSolution(
        x=x,
        position=pos,
        theta=out["th"],
        curvature_b_reference=out["tp"],
        curvature_b_deformed=out["tp"] / (1.0 + out["q"]),
        curvature_n=zeros,
        torsion=zeros.copy(),
        axial_strain=out["q"],
        axial_force=out["N"],
        shear_force=out["T"],
        moment=out["m"],
        tendon_paths=tuple(paths),
        tendon_lengths=lengths,
        rest_lengths=rest_lengths(finger),
        base_force=base_force,
        base_moment=float(out["m"][0]),
        method=method,
        length=L,
    )


def _cut_force(finger, profiles, active, mid, x, theta, q, theta_p):
    """``sum tau t_c`` in global components for given ``theta``, ``q``, ``theta'``."""
    c, s = math.cos(theta), math.sin(theta)
    fx = fy = 0.0
    for k in active:
        tau = finger.tendons[k].tension
        delta, delta_p, _ = profiles[k](x, mid)
        alpha, beta, w = _tendon_frame(1.0 + q, theta_p, delta, delta_p)
        fx += tau * (alpha * c - beta * s) / w
        fy += tau * (alpha * s + beta * c) / w
    return fx, fy


def solve_finger(
    finger: TaperedFinger,
    *,
    method: str = "shooting",
    n_points: int = 201,
    rtol: float = 1e-10,
    initial_guess: Sequence[float] | None = None,
) -> FingerSolution:
    """Static equilibrium of a tendon-driven finger.

    Parameters
    ----------
    finger : TaperedFinger
    method : {"shooting", "cut"}
        See the module docstring.
    n_points : int
        Size of the uniform output grid (>= 2).
    rtol : float
        Relative tolerance of ``solve_ivp`` (DOP853), in ``(0, 1e-3]``.
    initial_guess : (n_x, n_y, m) at the base, optional
        Shooting only (e.g. ``(*sol.base_force, sol.base_moment)`` of a nearby solution).
    """
    if not isinstance(finger, TaperedFinger):
        raise ValueError(f"finger must be a TaperedFinger, got {type(finger).__name__}")
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if not isinstance(n_points, int | np.integer) or isinstance(n_points, bool) or n_points < 2:
        raise ValueError(f"n_points must be an integer >= 2, got {n_points!r}")
    _check_real("rtol", rtol, positive=True)
    if rtol > 1e-3:
        raise ValueError(f"rtol must be <= 1e-3, got {rtol!r}")
    if initial_guess is not None and np.shape(initial_guess) != (3,):
        raise ValueError(f"initial_guess must be (n_x, n_y, m), got {initial_guess!r}")
    if method == "shooting":
        profiles, segments, sols = _solve_shooting(finger, rtol, initial_guess)
    else:
        profiles, segments, sols = _solve_cut(finger, rtol)
    return _sample(finger, profiles, segments, sols, method, n_points)


# ------------------------------------------------------------------------------------------------
# Inverse problems
# ------------------------------------------------------------------------------------------------
def _tension_for(measure, target, finger, tendons, bracket, method, xtol, name):
    """Find ``tau`` with ``measure(solve(finger with tau)) = target`` (``brentq`` on a bracket).

    Without ``bracket`` the upper end doubles from ``EJ(0) / (L max|delta|)`` until the sign
    changes (``measure`` must vanish at ``tau = 0``).
    """
    _check_real(name, target)
    if not finger.tendons:
        raise ValueError("finger.tendons must not be empty for an inverse solve")

    def f(tau):
        sol = solve_finger(with_tension(finger, float(tau), tendons), method=method, n_points=2)
        return measure(sol) - target

    if bracket is None:
        L = finger.length
        d_max = max(abs(t.profile(L)(x, x)[0]) for t in finger.tendons for x in (t.entry, L / 2))
        lo, hi = 0.0, finger.ej(0.0)[0] / (L * max(d_max, 1e-3 * L))
        f_lo = -target
        if f_lo == 0.0:
            return 0.0
        for _ in range(30):
            if np.sign(f(hi)) != np.sign(f_lo):
                break
            lo, hi = hi, 2.0 * hi
        else:
            raise ValueError(f"{name}={target!r} not reached for tension up to {hi:.3g} N")
    else:
        lo, hi = bracket
        _check_real("bracket[0]", lo, nonnegative=True)
        _check_real("bracket[1]", hi, positive=True)
    return float(scipy.optimize.brentq(f, lo, hi, xtol=xtol, rtol=1e-13))


def tension_for_tip_angle(
    target_theta: float,
    finger: TaperedFinger | None = None,
    *,
    tendons: Sequence[int] | None = None,
    bracket: tuple[float, float] | None = None,
    method: str = "shooting",
    xtol: float = 1e-14,
) -> float:
    """Tension of ``tendons`` (indices, default all) giving ``theta(L) = target_theta``."""
    finger = default_finger() if finger is None else finger
    return _tension_for(
        lambda s: s.tip_theta,
        target_theta,
        finger,
        tendons,
        bracket,
        method,
        xtol,
        "target_theta",
    )


def tension_for_pull_in(
    target: float,
    finger: TaperedFinger | None = None,
    *,
    tendons: Sequence[int] | None = None,
    bracket: tuple[float, float] | None = None,
    method: str = "shooting",
    xtol: float = 1e-14,
) -> float:
    """Tension of ``tendons`` (indices, default all) whose summed pull-in ``l(0) - l(tau)``
    equals ``target`` [m]."""
    finger = default_finger() if finger is None else finger
    idx = list(range(len(finger.tendons))) if tendons is None else list(tendons)
    return _tension_for(
        lambda s: float(np.sum(s.pull_in[idx])),
        target,
        finger,
        tendons,
        bracket,
        method,
        xtol,
        "target",
    )

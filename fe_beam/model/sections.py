"""Cross-sections: area A and the 2nd, 3rd and 4th moments I, I3, I4 about the centroid.

Sign convention (docs/theory.md, Conventions): eta is the transverse coordinate along the director
d = (-sin theta, cos theta) with the sign that makes positive curvature stretch fibres at positive
eta, i.e. eta = -y for y measured along d. Hence I3 = int eta^3 dA = -int y^3 dA: a T-section with
its flange on the +d side (the side toward which positive curvature bends the beam) has I3 > 0.

Every dimension may vary linearly along the beam: give ``<name>_tip`` (e.g. ``h_tip``) beside
``<name>``. The property formulas are polynomial/rational in the dimensions, so they evaluate on
floats, numpy arrays and UFL expressions alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

__all__ = ["SHAPES", "Section", "SectionProperties", "SpatialSectionProperties",
           "layered_properties", "rectangle_torsion_constant"]


@dataclass(frozen=True)
class SectionProperties:
    """A, I, I3, I4 (floats, arrays or UFL expressions) and the section height h."""

    A: Any
    I: Any
    I3: Any
    I4: Any
    h: Any


def layered_properties(layers) -> tuple:
    """(A, I, I3, I4) of a section made of stacked rectangles ``(width, y_bottom, y_top)``.

    int y^n dA over a layer = width (y_top^{n+1} - y_bottom^{n+1}) / (n + 1); moments are then
    shifted to the centroid, and eta = -y gives I3 = -int y^3 dA.
    """

    def moment(n, shift=0.0):
        return sum(
            w * ((top - shift) ** (n + 1) - (bottom - shift) ** (n + 1)) / (n + 1)
            for w, bottom, top in layers
        )

    area = moment(0)
    centroid = moment(1) / area
    return area, moment(2, centroid), -moment(3, centroid), moment(4, centroid)


def _rectangle(b, h):
    return b * h, b * h**3 / 12, 0.0 * b, b * h**5 / 80, h


def _circle(d):
    r = d / 2
    return math.pi * r**2, math.pi * r**4 / 4, 0.0 * d, math.pi * r**6 / 8, d


def _tube(d, t):
    outer, inner = _circle(d), _circle(d - 2 * t)
    return tuple(o - i for o, i in zip(outer[:4], inner[:4], strict=True)) + (d,)


def _t_section(b, h, tf, tw):
    # Web from y = 0 to h - tf, flange on top (the +d side), from h - tf to h.
    area, inertia, i3, i4 = layered_properties([(tw, 0.0, h - tf), (b, h - tf, h)])
    return area, inertia, i3, i4, h


def _odd_inverse_fifth_powers(first: int, last: int = 4001) -> float:
    """sum 1 / n^5 over odd n >= ``first`` (odd): the terms up to ``last`` summed smallest
    first, the rest by the midpoint rule's integral 1 / (8 (last + 1)^4) (its error is
    O(last^-6), 1e-22 here)."""
    return math.fsum(1.0 / n**5 for n in range(last, first - 1, -2)) + 1.0 / (8 * (last + 1)**4)


#: the odd terms of the torsion series summed with their tanh; beyond them tanh(n pi w / 2t)
#: is 1 in double precision (1 - tanh(25 pi / 2) = 1e-34, w >= t) and the rest of the series
#: is the constant `_TORSION_TAIL`
TORSION_TERMS = 12
_TORSION_TAIL = _odd_inverse_fifth_powers(2 * TORSION_TERMS + 1)


def rectangle_torsion_constant(b, h, tanh=math.tanh, terms: int = TORSION_TERMS):
    """Saint-Venant torsion constant of a b x h rectangle (t = min, w = max):

        J = t^3 w / 3 (1 - 192 t / (pi^5 w) sum_{n odd} tanh(n pi w / 2t) / n^5)

    (Timoshenko & Goodier), summed to convergence: the first ``terms`` odd n with their tanh,
    the rest with tanh = 1 (exact in double from n = 25 on) as the constant sum of 1 / n^5
    (`_odd_inverse_fifth_powers`; its remainder is below 1e-20 relative). Was: 12 terms only,
    a J 2.7e-7 (relative) too large at b/h = 2/3, 4e-7 for a square. ``b`` and ``h`` may be
    UFL expressions with ``tanh`` = ufl.tanh; which of them is the thinner is decided on their
    float values by the caller (`Section.spatial_properties`) and passed in order: here ``b``
    <= ``h`` is assumed when ``b`` is not a float."""
    if isinstance(b, (int, float)) and isinstance(h, (int, float)) and b > h:
        b, h = h, b
    t, w = b, h
    tail = (_TORSION_TAIL if terms == TORSION_TERMS
            else _odd_inverse_fifth_powers(2 * terms + 1))
    series = sum(tanh((2 * k + 1) * math.pi * w / (2 * t)) / (2 * k + 1) ** 5
                 for k in range(terms)) + tail
    return t**3 * w / 3 * (1 - 192 * t / (math.pi**5 * w) * series)


def _disk_moment(r, a: int, b: int):
    """int y^a z^b dA over a disk of radius r about its centre."""
    if a % 2 or b % 2:
        return 0.0 * r
    value = 2 * math.gamma((a + 1) / 2) * math.gamma((b + 1) / 2) / (
        (a + b + 2) * math.gamma((a + b + 2) / 2))
    return value * r ** (a + b + 2)


def _symmetric_moment(width, n: int):
    """int_{-width/2}^{width/2} z^n dz."""
    if n % 2:
        return 0.0 * width
    return 2 * (width / 2) ** (n + 1) / (n + 1)


#: the (a, b) of the section moments int y^a z^b dA the spatial non-standard law needs
MOMENT_ORDERS = tuple((a, n - a) for n in range(5) for a in range(n + 1))


@dataclass(frozen=True)
class SpatialSectionProperties:
    """A, I_z = int y^2 dA (the planar I), I_y = int z^2 dA, the Saint-Venant torsion constant
    J, the moments ``moments[(a, b)]`` = int y^a z^b dA about the centroid for a + b <= 4
    (y along the h direction d2, z along the b direction d3; the planar I3 = -moments[(3, 0)],
    I4 = moments[(4, 0)]), and the extents ``y_half``/``z_half`` (the largest |y|, |z|)."""

    A: Any
    Iz: Any
    Iy: Any
    J: Any
    moments: dict
    y_half: Any
    z_half: Any


SHAPES = {
    "rectangle": (_rectangle, ("b", "h")),
    "circle": (_circle, ("d",)),
    "tube": (_tube, ("d", "t")),
    "t-section": (_t_section, ("b", "h", "tf", "tw")),
    "custom": (None, ("A", "I", "I3", "I4")),
}
OPTIONAL_CUSTOM = ("I3", "I4", "h", "I_y", "J", "I4_z", "I22", "b")
#: custom keys the spatial rod reads (the others are the planar ones)
SPATIAL_CUSTOM = ("I_y", "J", "I4_z", "I22", "b")


@dataclass(frozen=True)
class Section:
    """A cross-section family; ``dims`` at x = 0 and optional ``dims_tip`` at x = L."""

    shape: str
    dims: dict
    dims_tip: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.shape not in SHAPES:
            raise ValueError(
                f"section.shape must be one of {', '.join(SHAPES)}; got {self.shape!r}"
            )
        required = SHAPES[self.shape][1]
        optional = OPTIONAL_CUSTOM if self.shape == "custom" else ()
        for name in required:
            if name not in self.dims and name not in optional:
                raise ValueError(f"section.{name} is required for shape = {self.shape!r}")
        for name in list(self.dims) + list(self.dims_tip):
            if name not in required and name not in optional:
                allowed = ", ".join(dict.fromkeys(list(required) + list(optional)))
                raise ValueError(
                    f"section.{name} is not a dimension of shape {self.shape!r} "
                    f"(allowed: {allowed})"
                )
        for where, values in (("", self.dims), ("_tip", self.dims_tip)):
            for name, value in values.items():
                if not isinstance(value, (int, float)) or isinstance(value, bool):
                    raise ValueError(f"section.{name}{where} must be a number, got {value!r}")
                signed = self.shape == "custom" and name == "I3"
                if not math.isfinite(value) or (value <= 0 and not signed):
                    raise ValueError(f"section.{name}{where} must be > 0, got {value!r}")
        self._check_geometry(self.dims, "")
        self._check_geometry({**self.dims, **self.dims_tip}, "_tip")

    def _check_geometry(self, dims: dict, where: str) -> None:
        if self.shape == "tube" and 2 * dims["t"] >= dims["d"]:
            raise ValueError(f"section.t{where} must be < d/2 (wall thicker than the radius)")
        if self.shape == "t-section":
            if dims["tf"] >= dims["h"]:
                raise ValueError(f"section.tf{where} must be < h")
            if dims["tw"] > dims["b"]:
                raise ValueError(f"section.tw{where} must be <= b (web wider than the flange)")

    @property
    def tapered(self) -> bool:
        return any(self.dims_tip.get(k, v) != v for k, v in self.dims.items())

    def properties(self, s=0.0, dims: dict | None = None, dims_tip: dict | None = None):
        """Section properties at s = x / L (float, numpy array or UFL expression).

        ``dims``/``dims_tip`` override the stored values with same-named symbols (e.g.
        fem.Constant), so that compiled forms do not depend on the numbers.
        """
        base = self.dims if dims is None else dims
        tip = self.dims_tip if dims_tip is None else dims_tip
        at_s = {n: v + (tip[n] - v) * s if n in tip else v for n, v in base.items()}
        if self.shape == "custom":
            height = at_s.get("h", math.sqrt(12 * self.dims["I"] / self.dims["A"]))
            i3, i4 = at_s.get("I3", 0.0), at_s.get("I4", 0.0)
            return SectionProperties(at_s["A"], at_s["I"], i3, i4, height)
        function, names = SHAPES[self.shape]
        return SectionProperties(*function(*(at_s[n] for n in names)))

    def spatial_properties(self, s=0.0, dims: dict | None = None,
                           dims_tip: dict | None = None, tanh=math.tanh):
        """`SpatialSectionProperties` at s = x / L (floats or UFL expressions, as
        `properties`; ``tanh`` for the rectangle's torsion series, e.g. ufl.tanh).

        J: rectangle by its series (`rectangle_torsion_constant`), circle and tube exactly
        (the polar moment), T-section as the sum of its two rectangles' J (flange b x tf and
        web tw x (h - tf): the thin-walled open-section value, which neglects the junction);
        custom sections take ``I_y`` and ``J`` (required by the spatial rod) and the optional
        fourth moments ``I4_z`` = int z^4 dA and ``I22`` = int y^2 z^2 dA (0 when not given,
        like the planar I3 and I4)."""
        base = self.dims if dims is None else dims
        tip = self.dims_tip if dims_tip is None else dims_tip
        at_s = {n: v + (tip[n] - v) * s if n in tip else v for n, v in base.items()}
        moments = {}
        if self.shape == "rectangle":
            b, h = at_s["b"], at_s["h"]
            for a, c in MOMENT_ORDERS:
                moments[(a, c)] = _symmetric_moment(h, a) * _symmetric_moment(b, c)
            thin_first = self._thinner_first("b", "h")
            J = rectangle_torsion_constant(*((b, h) if thin_first else (h, b)), tanh=tanh)
            y_half, z_half = h / 2, b / 2
        elif self.shape in ("circle", "tube"):
            d = at_s["d"]
            for a, c in MOMENT_ORDERS:
                moments[(a, c)] = _disk_moment(d / 2, a, c)
                if self.shape == "tube":
                    moments[(a, c)] = moments[(a, c)] - _disk_moment(d / 2 - at_s["t"], a, c)
            J = moments[(2, 0)] + moments[(0, 2)]
            y_half = z_half = d / 2
        elif self.shape == "t-section":
            b, h, tf, tw = (at_s[n] for n in ("b", "h", "tf", "tw"))
            layers = [(tw, 0.0 * h, h - tf), (b, h - tf, h)]
            area = sum(w * (top - bottom) for w, bottom, top in layers)
            centroid = sum(w * (top**2 - bottom**2) / 2 for w, bottom, top in layers) / area
            for a, c in MOMENT_ORDERS:
                moments[(a, c)] = sum(
                    ((top - centroid) ** (a + 1) - (bottom - centroid) ** (a + 1)) / (a + 1)
                    * _symmetric_moment(w, c) for w, bottom, top in layers)
            web = rectangle_torsion_constant(tw, h - tf, tanh=tanh) if self._thinner_first(
                "tw", None, h - tf) else rectangle_torsion_constant(h - tf, tw, tanh=tanh)
            flange = rectangle_torsion_constant(tf, b, tanh=tanh) if self._thinner_first(
                "tf", "b") else rectangle_torsion_constant(b, tf, tanh=tanh)
            J = web + flange
            y_half = h - centroid if not isinstance(h, (int, float)) else max(
                h - centroid, centroid)
            z_half = b / 2
        else:  # custom
            planar = self.properties(s, dims, dims_tip)
            for name in ("I_y", "J"):
                if name not in at_s:
                    raise ValueError(f"section.{name} is required by the spatial rod for a "
                                     "custom section (I_y = int z^2 dA, J the torsion "
                                     "constant)")
            moments = {key: 0.0 for key in MOMENT_ORDERS}
            moments[(0, 0)], moments[(2, 0)], moments[(0, 2)] = planar.A, planar.I, at_s["I_y"]
            moments[(3, 0)] = -planar.I3
            moments[(4, 0)] = planar.I4
            moments[(0, 4)] = at_s.get("I4_z", 0.0)
            moments[(2, 2)] = at_s.get("I22", 0.0)
            J = at_s["J"]
            y_half = planar.h / 2
            z_half = at_s.get("b", math.sqrt(12 * self.dims["I_y"] / self.dims["A"])) / 2
        return SpatialSectionProperties(moments[(0, 0)], moments[(2, 0)], moments[(0, 2)], J,
                                        moments, y_half, z_half)

    def _thinner_first(self, first: str, second: str | None, second_value=None) -> bool:
        """Is dimension ``first`` the thinner one (on the float values at both ends)? A taper
        whose thinner side changes along the rod is refused (its J series would switch); an
        end where both are equal (e.g. a square base tapering to a flat tip) goes either way."""
        answers = set()
        for values in (self.dims, {**self.dims, **self.dims_tip}):
            a = values[first]
            if second is not None:
                other = values[second]
            else:
                other = values["h"] - values["tf"]
            if a != other:
                answers.add(a < other)
        if not answers:
            return True
        if len(answers) > 1:
            raise ValueError(f"section: {first} and {second or 'h - tf'} swap which is the "
                             "thinner along the taper; the torsion constant of such a taper is "
                             "not supported")
        return answers.pop()

    def y_extent(self, s: float) -> tuple[float, float] | None:
        """(lowest, highest) y of the section at s = x / L, about its centroid; None for a
        custom section, whose shape is not known."""
        at_s = {n: v + (self.dims_tip.get(n, v) - v) * s for n, v in self.dims.items()}
        if self.shape == "rectangle":
            return -at_s["h"] / 2, at_s["h"] / 2
        if self.shape in ("circle", "tube"):
            return -at_s["d"] / 2, at_s["d"] / 2
        if self.shape == "t-section":
            b, h, tf, tw = (at_s[n] for n in ("b", "h", "tf", "tw"))
            web, flange = tw * (h - tf), b * tf
            centroid = (web * (h - tf) / 2 + flange * (h - tf / 2)) / (web + flange)
            return -centroid, h - centroid
        return None

    def height(self) -> float:
        """Largest section height along the beam (slenderness L/h uses it)."""
        heights = [self.properties(0.0).h, self.properties(1.0).h]
        return float(max(heights))

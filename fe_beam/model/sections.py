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

__all__ = ["SHAPES", "Section", "SectionProperties", "layered_properties"]


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


SHAPES = {
    "rectangle": (_rectangle, ("b", "h")),
    "circle": (_circle, ("d",)),
    "tube": (_tube, ("d", "t")),
    "t-section": (_t_section, ("b", "h", "tf", "tw")),
    "custom": (None, ("A", "I", "I3", "I4")),
}
OPTIONAL_CUSTOM = ("I3", "I4", "h")


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

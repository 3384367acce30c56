"""Cross-section properties against an independent numerical integration over the shape.

Convention (MODEL.md): moments about the centroid, eta = -y with y along the section director,
so I3 = int eta^3 dA = -int (y - yc)^3 dA.
"""

import math
import re

import numpy as np
import pytest

from fe_beam.model.sections import Section

RTOL = 1e-10


# --- independent quadrature --------------------------------------------------------------------
def _gauss(a, b, n):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (b - a) * x + 0.5 * (a + b), 0.5 * (b - a) * w


def strips(pieces, n=12):
    """Points/weights over stacked strips (width, y_bottom, y_top): dA = width(y) dy."""
    ys, ws = [], []
    for width, bottom, top in pieces:
        y, w = _gauss(bottom, top, n)
        ys.append(y)
        ws.append(width * w)
    return np.concatenate(ys), np.concatenate(ws)


def annulus(r_in, r_out, y0=0.0, n_r=16, n_phi=96):
    """Points/weights over an annulus (r_in = 0: a disc) centred at y0, in polar coordinates."""
    rho, w_rho = _gauss(r_in, r_out, n_r)
    phi, w_phi = _gauss(0.0, 2.0 * math.pi, n_phi)
    R, P = np.meshgrid(rho, phi, indexing="ij")
    W = np.outer(w_rho, w_phi) * R  # dA = rho drho dphi
    return (y0 + R * np.sin(P)).ravel(), W.ravel()


def central_moments(y, w):
    area = w.sum()
    yc = (w * y).sum() / area
    eta = -(y - yc)
    return {
        "A": area,
        "I": (w * eta**2).sum(),
        "I3": (w * eta**3).sum(),
        "I4": (w * eta**4).sum(),
    }


def t_section_points(b, h, tf, tw, y0=-0.37):
    """Web of width tw below a flange of width b on the +y side; origin deliberately off."""
    y0 = y0 * h
    return strips([(tw, y0, y0 + h - tf), (b, y0 + h - tf, y0 + h)])


CASES = {
    "rectangle": ({"b": 0.03, "h": 0.07}, lambda d: strips([(d["b"], 0.11, 0.11 + d["h"])])),
    "circle": ({"d": 0.05}, lambda d: annulus(0.0, d["d"] / 2, y0=0.2)),
    "tube": ({"d": 0.05, "t": 0.004}, lambda d: annulus(d["d"] / 2 - d["t"], d["d"] / 2, y0=-0.1)),
    "t-section": (
        {"b": 0.1, "h": 0.08, "tf": 0.012, "tw": 0.006},
        lambda d: t_section_points(d["b"], d["h"], d["tf"], d["tw"]),
    ),
}


@pytest.mark.parametrize("shape", list(CASES))
def test_properties_match_numerical_integration(shape):
    dims, points = CASES[shape]
    expected = central_moments(*points(dims))
    p = Section(shape, dims).properties(0.0)
    scale = expected["A"] ** 0.5  # a length of the section
    for name in ("A", "I", "I4"):
        assert getattr(p, name) == pytest.approx(expected[name], rel=RTOL, abs=0), name
    if shape == "t-section":
        assert p.I3 == pytest.approx(expected["I3"], rel=RTOL, abs=0)
    else:  # symmetric sections: I3 vanishes (only round-off in the quadrature)
        assert abs(expected["I3"]) < 1e-12 * expected["A"] * scale**3
        assert abs(p.I3) <= 1e-12 * expected["A"] * scale**3


FIBRES = {  # lowest and highest fibre of the CASES geometries, in their own coordinates
    "rectangle": lambda d: (0.11, 0.11 + d["h"]),
    "circle": lambda d: (0.2 - d["d"] / 2, 0.2 + d["d"] / 2),
    "tube": lambda d: (-0.1 - d["d"] / 2, -0.1 + d["d"] / 2),
    "t-section": lambda d: (-0.37 * d["h"], 0.63 * d["h"]),
}


@pytest.mark.parametrize("shape", list(CASES))
def test_y_extent_is_the_fibre_range_about_the_centroid(shape):
    """Lowest and highest fibre about the centroid (the quadrature's centroid is exact)."""
    dims, points = CASES[shape]
    y, w = points(dims)
    centroid = (w * y).sum() / w.sum()
    bottom, top = FIBRES[shape](dims)
    extent = Section(shape, dims).y_extent(0.0)
    assert extent == pytest.approx((bottom - centroid, top - centroid), rel=1e-12, abs=1e-15)


def test_y_extent_of_a_tapered_and_of_a_custom_section():
    tapered = Section("rectangle", {"b": 0.02, "h": 0.02}, {"h": 0.01})
    assert tapered.y_extent(0.5) == pytest.approx((-0.0075, 0.0075))
    assert Section("custom", {"A": 1e-4, "I": 1e-9}).y_extent(0.0) is None


@pytest.mark.parametrize("b, h", [(0.01, 0.01), (0.02, 0.005), (1.0, 3.0)])
def test_rectangle_closed_form(b, h):
    p = Section("rectangle", {"b": b, "h": h}).properties()
    assert p.A == pytest.approx(b * h, rel=1e-14)
    assert p.I == pytest.approx(b * h**3 / 12, rel=1e-14)
    assert p.I4 == pytest.approx(b * h**5 / 80, rel=1e-14)
    assert p.I3 == 0
    assert p.h == h


def test_section_heights():
    assert Section("circle", {"d": 0.05}).properties().h == 0.05
    assert Section("tube", {"d": 0.05, "t": 0.01}).properties().h == 0.05
    t_section = Section("t-section", {"b": 0.1, "h": 0.08, "tf": 0.01, "tw": 0.01})
    assert t_section.properties().h == 0.08


def test_t_section_with_flange_on_plus_y_has_positive_i3():
    """MODEL.md sign convention: with the flange on +y the centroid sits near the flange and the
    web reaches far to y < yc, i.e. eta = -(y - yc) > 0, so I3 = int eta^3 dA > 0."""
    dims = {"b": 0.1, "h": 0.08, "tf": 0.012, "tw": 0.006}
    p = Section("t-section", dims).properties()
    assert p.I3 > 0
    # and a section of the mirror image (flange on -y) would have the opposite sign
    y, w = t_section_points(**dims)
    mirrored = central_moments(-y, w)
    assert mirrored["I3"] == pytest.approx(-p.I3, rel=RTOL)


def test_custom_section_passes_properties_through():
    p = Section("custom", {"A": 2.0e-4, "I": 3.0e-9, "I3": -4.0e-12, "I4": 5.0e-14}).properties()
    assert (p.A, p.I, p.I3, p.I4) == (2.0e-4, 3.0e-9, -4.0e-12, 5.0e-14)


def test_custom_section_optional_higher_moments_default_to_zero():
    p = Section("custom", {"A": 1.0e-4, "I": 1.0e-4 * 0.02**2 / 12}).properties()
    assert p.I3 == 0 and p.I4 == 0
    assert p.h == pytest.approx(0.02, rel=1e-12)  # equivalent rectangle height sqrt(12 I / A)


TAPERED = [
    ("rectangle", {"b": 0.02, "h": 0.04}, {"h": 0.01}),
    ("rectangle", {"b": 0.02, "h": 0.04}, {"b": 0.05, "h": 0.01}),
    ("circle", {"d": 0.05}, {"d": 0.02}),
    ("tube", {"d": 0.05, "t": 0.005}, {"d": 0.03, "t": 0.002}),
    (
        "t-section",
        {"b": 0.1, "h": 0.08, "tf": 0.012, "tw": 0.006},
        {"b": 0.06, "h": 0.05, "tf": 0.01, "tw": 0.004},
    ),
]


@pytest.mark.parametrize("shape, root, tip", TAPERED)
@pytest.mark.parametrize("s", [0.0, 0.5, 1.0])
def test_tapered_equals_uniform_section_of_interpolated_dimensions(shape, root, tip, s):
    at_s = {n: v + s * (tip.get(n, v) - v) for n, v in root.items()}
    got = Section(shape, root, tip).properties(s)
    want = Section(shape, at_s).properties()
    for name in ("A", "I", "I3", "I4", "h"):
        assert getattr(got, name) == pytest.approx(getattr(want, name), rel=1e-12, abs=1e-30)
    # and independently of the uniform-section code path
    expected = central_moments(*CASES[shape][1](at_s))
    assert got.I == pytest.approx(expected["I"], rel=RTOL)
    assert got.I4 == pytest.approx(expected["I4"], rel=RTOL)


def test_tapered_properties_on_arrays_and_flag():
    section = Section("rectangle", {"b": 0.02, "h": 0.04}, {"h": 0.01})
    s = np.array([0.0, 0.25, 1.0])
    p = section.properties(s)
    h = 0.04 + s * (0.01 - 0.04)
    np.testing.assert_allclose(p.I, 0.02 * h**3 / 12, rtol=1e-13)
    np.testing.assert_allclose(p.I4, 0.02 * h**5 / 80, rtol=1e-13)
    assert section.tapered
    assert not Section("rectangle", {"b": 0.02, "h": 0.04}, {"h": 0.04}).tapered
    assert section.height() == 0.04


BAD = [
    ("ellipse", {"b": 0.01, "h": 0.01}, {}, "section.shape"),
    ("rectangle", {"b": 0.01}, {}, "section.h"),
    ("t-section", {"b": 0.1, "h": 0.08, "tw": 0.01}, {}, "section.tf"),
    ("rectangle", {"b": 0.01, "h": -0.01}, {}, "section.h"),
    ("rectangle", {"b": 0.01, "h": 0.0}, {}, "section.h"),
    ("rectangle", {"b": math.nan, "h": 0.01}, {}, "section.b"),
    ("rectangle", {"b": 0.01, "h": math.inf}, {}, "section.h"),
    ("rectangle", {"b": 0.01, "h": "0.01"}, {}, "section.h"),
    ("rectangle", {"b": 0.01, "h": True}, {}, "section.h"),
    ("rectangle", {"b": 0.01, "h": 0.01, "d": 0.01}, {}, "section.d"),
    ("circle", {"d": 0.01, "t": 0.001}, {}, "section.t"),
    ("rectangle", {"b": 0.01, "h": 0.01}, {"h": 0.0}, "section.h_tip"),
    ("rectangle", {"b": 0.01, "h": 0.01}, {"t": 0.01}, "section.t"),
    ("tube", {"d": 0.02, "t": 0.01}, {}, "section.t"),
    ("tube", {"d": 0.02, "t": 0.015}, {}, "section.t"),
    ("tube", {"d": 0.02, "t": 0.002}, {"d": 0.004}, "section.t_tip"),
    ("t-section", {"b": 0.1, "h": 0.08, "tf": 0.08, "tw": 0.01}, {}, "section.tf"),
    ("t-section", {"b": 0.1, "h": 0.08, "tf": 0.09, "tw": 0.01}, {}, "section.tf"),
    ("custom", {"I": 1e-9}, {}, "section.A"),
    ("custom", {"A": 1e-4, "I": -1e-9}, {}, "section.I"),
]


@pytest.mark.parametrize("shape, dims, tip, key", BAD)
def test_invalid_sections_raise_naming_the_key(shape, dims, tip, key):
    with pytest.raises(ValueError) as error:
        Section(shape, dims, tip)
    # the key as a whole word (section.t must not be satisfied by section.tf or section.t_tip)
    assert re.search(rf"{re.escape(key)}(?![A-Za-z0-9_])", str(error.value)), str(error.value)

"""The planar pictures draw the section's outline (issue 28: a finger touching a bottle with its
upper face looked as if it missed it): `section_faces` gives the faces at y_min and y_max of the
section along the section normal d2 = (-sin theta, cos theta) of the deformed state."""

from __future__ import annotations

import numpy as np
import pytest

from fe_beam.exports import outputs
from fe_beam.exports.outputs import section_faces
from fe_beam.model.sections import Section

LENGTH = 0.1


def shape(count: int = 9) -> dict:
    """A bent, shifted and stretched state (theta is not the centreline's slope: shear)."""
    x = np.linspace(0.0, LENGTH, count)
    return {"x": x, "u": -0.1 * x**2 / LENGTH, "v": 0.3 * x**2 / LENGTH,
            "theta": 1.3 * x / LENGTH + 0.05 * np.sin(40 * x)}


def test_tapered_rectangle_faces_are_the_centreline_plus_minus_half_the_height_along_d2():
    """h from 0.02 to 0.01: lower/upper = centreline -/+ h(x)/2 (-sin theta, cos theta)."""
    section = Section("rectangle", {"b": 0.02, "h": 0.02}, {"h": 0.01})
    state = shape()
    lower, upper = section_faces(state, section, LENGTH)
    half = (0.02 + (0.01 - 0.02) * state["x"] / LENGTH) / 2
    centre = np.column_stack([state["x"] + state["u"], state["v"]])
    d2 = np.column_stack([-np.sin(state["theta"]), np.cos(state["theta"])])
    assert np.abs(upper - (centre + half[:, None] * d2)).max() < 1e-15
    assert np.abs(lower - (centre - half[:, None] * d2)).max() < 1e-15
    # the faces are h apart along d2 and the centreline is midway
    assert np.linalg.norm(upper - lower, axis=1) == pytest.approx(2 * half, rel=1e-12)


def test_t_section_faces_are_measured_from_the_centroid():
    """An asymmetric section: the faces at -c and h - c of the centroid c (not +-h/2)."""
    b, h, tf, tw = 0.03, 0.02, 0.004, 0.005
    section = Section("t-section", {"b": b, "h": h, "tf": tf, "tw": tw})
    web, flange = tw * (h - tf), b * tf
    c = (web * (h - tf) / 2 + flange * (h - tf / 2)) / (web + flange)
    state = shape(5)
    lower, upper = section_faces(state, section, LENGTH)
    d2 = np.column_stack([-np.sin(state["theta"]), np.cos(state["theta"])])
    centre = np.column_stack([state["x"] + state["u"], state["v"]])
    assert np.abs(lower - (centre - c * d2)).max() < 1e-15
    assert np.abs(upper - (centre + (h - c) * d2)).max() < 1e-15


def test_custom_section_has_no_outline_and_the_plot_draws_one_per_shape(tmp_path, monkeypatch):
    custom = Section("custom", {"A": 1e-4, "I": 1e-9})
    assert section_faces(shape(), custom, LENGTH) is None
    calls = []
    real = outputs.section_faces
    monkeypatch.setattr(outputs, "section_faces",
                        lambda *args: calls.append(args) or real(*args))
    rectangle = Section("rectangle", {"b": 0.02, "h": 0.02})
    shapes = [("a", shape()), ("b", shape())]
    outputs.plot_deformed_shapes(shapes, tmp_path / "s.png", "t", LENGTH, section=rectangle)
    outputs.plot_deformed_shapes(shapes, tmp_path / "c.png", "t", LENGTH, section=custom)
    outputs.plot_deformed_shapes(shapes, tmp_path / "n.png", "t", LENGTH)
    assert len(calls) == 4 and all((tmp_path / n).exists() for n in ("s.png", "c.png", "n.png"))

"""Planar chains of rods ([[rods]], issue 29) in fe-beam modes, buckling, dynamic.

References: the same rod without joints (a split rod is the rod, also turned in the plane),
the exact transfer-matrix frequencies of `fe_beam.baselines.frame_modes` (extensible
Timoshenko members with rotary inertia: the Reissner law's linear vibrations) and the
classical sway-buckling equation of a fixed-base portal frame."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.optimize
from mpi4py import MPI
from mpilaunch import mpirun_command

import fe_beam
from fe_beam.baselines import frame_modes

E, NU, RHO = 2.0e7, 0.3, 1000.0
B, H = 0.02, 0.05


def _base(elements: int, constraint: str = "none", b: float = B, h: float = H) -> dict:
    return {
        "section": {"shape": "rectangle", "b": b, "h": h},
        "material": {"E": E, "nu": NU, "rho": RHO},
        "model": {"law": "reissner", "constraint": constraint},
        "mesh": {"elements": elements, "degree": 2},
        "output": {"xdmf": False, "plots": False},
    }


def _members(height, span, b=B, h=H):
    area, inertia = b * h, b * h**3 / 12
    G = E / (2 * (1 + NU))
    return frame_modes.portal_frame(height, span, E * inertia, E * area, G * area, RHO * area,
                                    RHO * inertia)


def _portal(elements: int, height: float, span: float, **base) -> dict:
    config = _base(elements, **base)
    config["rods"] = [
        {"name": "left", "start": [0.0, 0.0], "direction": [0.0, 1.0], "length": height,
         "supports": {"x0": "clamped"}},
        {"name": "beam", "start": [0.0, height], "direction": [1.0, 0.0], "length": span},
        # the right column given top-down from its base: the chain runs it reversed
        {"name": "right", "start": [span, 0.0], "direction": [0.0, 1.0], "length": height,
         "supports": {"x0": "clamped"}}]
    config["joints"] = [{"name": "k1", "at": ["left:end", "beam:start"]},
                        {"name": "k2", "at": ["right:end", "beam:end"]}]
    return config


# --- modes -------------------------------------------------------------------------------------
@pytest.mark.parametrize("direction", [(1.0, 0.0), (0.6, 0.8)])
def test_modes_split_rod_is_the_rod(direction):
    """A cantilever split into two rods joined rigidly, laid along any direction, has the
    single rod's frequencies and kinds to round-off."""
    length, elements = 1.0, 10
    single = _base(elements) | {"modes": {"count": 6}}
    single["beam"] = {"length": length}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    split = _base(elements // 2) | {"modes": {"count": 6}}
    middle = [0.4 * direction[0], 0.4 * direction[1]]
    split["rods"] = [
        {"name": "a", "start": [0.0, 0.0], "direction": list(direction), "length": 0.4,
         "mesh": {"elements": 4}, "supports": {"x0": "clamped"}},
        {"name": "b", "start": middle, "direction": list(direction), "length": 0.6,
         "mesh": {"elements": 6}}]
    split["joints"] = [{"name": "j", "at": ["a:end", "b:start"]}]
    one, two = fe_beam.run("modes", single), fe_beam.run("modes", split)
    assert one["status"] == two["status"] == "completed"
    assert one["mode_kinds"] == two["mode_kinds"]
    assert "axial" in one["mode_kinds"]
    f1, f2 = np.array(one["frequencies_hz"]), np.array(two["frequencies_hz"])
    assert np.max(np.abs(f1 - f2) / f1) <= 1e-10, (f1, f2)


def test_modes_portal_frame_against_transfer_matrices():
    """A fixed-base portal frame's six lowest frequencies against the exact transfer-matrix
    solution of its members (same law: extensible, shearable, rotary inertia), converging at
    order 4 in the element count; the sway mode (the beam moves along its axis, the columns
    bend) is a bending mode."""
    height, span = 1.0, 1.2
    members, supports = _members(height, span)
    reference = np.array(frame_modes.frame_frequencies(members, supports, 6, 2 * math.pi * 20))
    assert len(reference) == 6
    errors = []
    for elements in (4, 8):
        summary = fe_beam.run("modes", _portal(elements, height, span) | {"modes": {"count": 6}})
        assert summary["status"] == "completed"
        assert summary["mode_kinds"] == ["bending"] * 6
        errors.append(np.abs(np.array(summary["frequencies_hz"]) - reference) / reference)
    # measured: 3.5e-6, 9.1e-5, 2.0e-4, 2.3e-4, 1.0e-3, 1.5e-3 with 8 elements per rod
    assert np.all(errors[1] < [5e-6, 1.2e-4, 2.6e-4, 3e-4, 1.3e-3, 2e-3]), errors[1]
    orders = np.log2(errors[0] / errors[1])
    assert np.all((orders > 3.5) & (orders < 4.5)), orders


def test_modes_free_l_frame_rigid_motions():
    """A free-free L-frame away from the origin: three rigid-body modes at 0 Hz (the rotation
    about the origin through each rod's reference position) and the elastic frequencies of
    the transfer-matrix solution."""
    a, b, x0 = 0.7, 0.5, (0.3, -0.2)
    config = _base(8) | {"modes": {"count": 6}}
    config["rods"] = [
        {"name": "column", "start": list(x0), "direction": [0.0, 1.0], "length": a},
        {"name": "beam", "start": [x0[0], x0[1] + a], "direction": [1.0, 0.0], "length": b}]
    config["joints"] = [{"name": "corner", "at": ["column:end", "beam:start"]}]
    summary = fe_beam.run("modes", config)
    assert summary["status"] == "completed"
    assert summary["rigid_body_modes"] == 3
    assert summary["frequencies_hz"][:3] == [0.0, 0.0, 0.0]
    assert not [n for n in summary.get("notes", []) if "were found" in n]
    members = [frame_modes.Member(x0, math.pi / 2, a, *_stiff()),
               frame_modes.Member((x0[0], x0[1] + a), 0.0, b, *_stiff())]
    reference = frame_modes.frame_frequencies(members, {}, 3, 2 * math.pi * 40)
    found = np.array(summary["frequencies_hz"][3:])
    # measured: 8.9e-6, 1.7e-4, 2.5e-4 (8 elements per rod)
    assert np.max(np.abs(found - reference) / reference) < 3.2e-4, (found, reference)


def _stiff():
    area, inertia = B * H, B * H**3 / 12
    G = E / (2 * (1 + NU))
    return E * inertia, E * area, G * area, RHO * area, RHO * inertia


def test_frame_modes_baseline_is_euler_bernoulli_in_the_slender_limit():
    """The transfer-matrix solver itself: an inextensible, unshearable cantilever without
    rotary inertia (split in two members at an angle of the plane) has the Euler-Bernoulli
    roots beta_n^2 sqrt(EI / rho A) / L^2."""
    angle = 0.3
    first = frame_modes.Member((0.0, 0.0), angle, 0.4, 1.0)
    second = frame_modes.Member(first.end(), angle, 0.6, 1.0)
    found = frame_modes.frame_frequencies([first, second], {(0.0, 0.0): "clamped"}, 3, 100.0)
    roots = [scipy.optimize.brentq(lambda x: math.cos(x) * math.cosh(x) + 1, lo, lo + 1.5)
             for lo in (1.0, 4.0, 7.2)]
    expected = [r**2 / (2 * math.pi) for r in roots]
    assert found == pytest.approx(expected, rel=1e-12)


# --- buckling ----------------------------------------------------------------------------------
def _loaded_portal(elements: int, height: float, span: float, force: float, beam_h: float):
    """A fixed-base portal frame (elastica members) with a dead downward force on each column
    top; the beam of section height ``beam_h``."""
    config = _portal(elements, height, span, constraint="inextensible-unshearable")
    config["rods"][1]["section"] = {"h": beam_h}
    for index in (0, 2):
        config["rods"][index]["loads"] = {"point_forces": [[height, 0.0, -force]]}
    return config | {"buckling": {"count": 2}}


def test_buckling_portal_frame_sway_against_closed_form():
    """The sway buckling of a fixed-base portal frame (inextensible, unshearable members, no
    pre-buckling bending): each column is fixed at its base, free to sway at its top with zero
    shear and restrained there by the beam bent antisymmetrically (end stiffness 6 EI_b / L):
    EI w'' + P w = P a, w = a (1 - cos k x) gives tan(k h) = -(k h) EI_c L / (6 EI_b h),
    k^2 = P / EI_c (k h between pi/2, the free cantilever, and pi, the rigid beam). Order 4 in
    the element count; the factor is confirmed on the nonlinear path."""
    height, span, beam_h = 1.0, 1.5, 0.04
    EI_c, EI_b = E * B * H**3 / 12, E * B * beam_h**3 / 12
    kh = scipy.optimize.brentq(
        lambda x: math.tan(x) + x * EI_c * span / (6 * EI_b * height),
        math.pi / 2 + 1e-9, math.pi - 1e-12, xtol=1e-15)
    force = EI_c / height**2
    expected = kh**2  # the load factor of P = EI_c / h^2
    errors = []
    for elements in (4, 8):
        summary = fe_beam.run("buckling", _loaded_portal(elements, height, span, force, beam_h))
        assert summary["status"] == "completed", summary["message"]
        assert summary["checks_passed"]
        assert any(c["name"] == "critical_point_confirmed" for c in summary["checks"])
        errors.append((summary["load_factors"][0] - expected) / expected)
    # measured: 2.4e-4, 1.5e-5 (9.7e-7 with 16); from above (the finite elements are stiffer)
    assert 0 < errors[1] < 2e-5, errors
    assert 3.5 < math.log2(errors[0] / errors[1]) < 4.5, errors


@pytest.mark.parametrize("direction", [(0.0, 1.0), (-0.8, 0.6)])
def test_buckling_split_column_is_the_column(direction):
    """A clamped column under an axial end force, split into two rods joined rigidly and laid
    along any direction, has the single column's buckling factors to round-off."""
    length, force = 1.0, 1.0
    single = _base(10) | {"buckling": {"count": 3}}
    single["beam"] = {"length": length}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    single["loads"] = {"tip_force": [-force, 0.0]}
    split = _base(5) | {"buckling": {"count": 3}}
    split["rods"] = [
        {"name": "a", "start": [0.0, 0.0], "direction": list(direction), "length": 0.5,
         "supports": {"x0": "clamped"}},
        {"name": "b", "start": [0.5 * direction[0], 0.5 * direction[1]],
         "direction": list(direction), "length": 0.5,
         "loads": {"point_forces": [[0.5, -force * direction[0], -force * direction[1]]]}}]
    split["joints"] = [{"name": "j", "at": ["a:end", "b:start"]}]
    one, two = fe_beam.run("buckling", single), fe_beam.run("buckling", split)
    assert one["status"] == two["status"] == "completed"
    f1, f2 = np.array(one["load_factors"]), np.array(two["load_factors"])
    assert len(f1) == len(f2) == 3
    assert np.max(np.abs(f1 - f2) / f1) <= 1e-9, (f1, f2)
    l1, l2 = np.array(one["linearised_load_factors"]), np.array(two["linearised_load_factors"])
    assert np.max(np.abs(l1 - l2) / l1) <= 1e-10, (l1, l2)


# --- dynamic -----------------------------------------------------------------------------------
def _dynamic(elements: int, scheme: str, t_end: float = 0.03, dt: float = 0.01) -> dict:
    return _base(elements) | {"time": {"t_end": t_end, "dt": dt, "scheme": scheme}}


@pytest.mark.parametrize("scheme", ["generalized-alpha", "energy-conserving"])
def test_dynamic_split_rod_is_the_rod(scheme):
    """A cantilever under a suddenly applied end force, split into two rods joined rigidly and
    laid along a direction at an angle alpha, moves as the single rod along x turned by alpha,
    to round-off at every step."""
    c, s = 0.6, 0.8
    force = (0.5, -20.0)
    single = _dynamic(10, scheme)
    single["beam"] = {"length": 1.0}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    single["loads"] = {"tip_force": list(force)}
    split = _dynamic(5, scheme)
    turned = [c * force[0] - s * force[1], s * force[0] + c * force[1]]
    split["rods"] = [
        {"name": "a", "start": [0.0, 0.0], "direction": [c, s], "length": 0.5,
         "supports": {"x0": "clamped"}},
        {"name": "b", "start": [0.5 * c, 0.5 * s], "direction": [c, s], "length": 0.5,
         "loads": {"point_forces": [[0.5, *turned]]}}]
    split["joints"] = [{"name": "j", "at": ["a:end", "b:start"]}]
    one, two = fe_beam.run("dynamic", single), fe_beam.run("dynamic", split)
    assert one["status"] == two["status"] == "completed"
    assert [h["t"] for h in one["history"]] == [h["t"] for h in two["history"]]
    scale = max(abs(one["history"][-1]["tip"]["v"]), 1e-3)
    assert scale > 0.05  # a large motion (0.076 of the length)
    for a, b in zip(one["history"], two["history"], strict=True):
        u, v = a["tip"]["u"], a["tip"]["v"]
        assert abs(b["tip"]["u"] - (c * u - s * v)) <= 1e-11 * scale
        assert abs(b["tip"]["v"] - (s * u + c * v)) <= 1e-11 * scale
        assert abs(b["tip"]["theta"] - a["tip"]["theta"]) <= 1e-11 * scale
        for key in ("kinetic", "strain"):
            assert b["energies"][key] == pytest.approx(a["energies"][key], rel=1e-10)
        # each step's rods: b's end is the chain's end, a's end the joint
        assert b["rods"]["b"]["tip"] == pytest.approx(
            [c + b["tip"]["u"], s + b["tip"]["v"]], abs=1e-12)
        assert b["rods"]["b"]["tip_angle"] == pytest.approx(math.atan2(s, c)
                                                            + a["tip"]["theta"], abs=1e-10)


@pytest.mark.parametrize("scheme", ["generalized-alpha", "energy-conserving"])
def test_dynamic_split_rod_with_kelvin_voigt_damping_is_the_rod(scheme):
    """Kelvin-Voigt damping of a cantilever split into two rods along y (suddenly applied end
    force): the single rod's motion turned and its dissipated energy, at every step. (The
    generalised-alpha damping took the strain rates of a rod along x: the split rod's tip
    moved 0.0088 where the rod's moved 0.074.)"""
    force = (0.5, -20.0)
    single = _dynamic(10, scheme) | {"damping": {"kelvin_voigt": 2e-3}}
    single["beam"] = {"length": 1.0}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    single["loads"] = {"tip_force": list(force)}
    split = _dynamic(5, scheme) | {"damping": {"kelvin_voigt": 2e-3}}
    split["rods"] = [
        {"name": "a", "start": [0.0, 0.0], "direction": [0.0, 1.0], "length": 0.5,
         "supports": {"x0": "clamped"}},
        {"name": "b", "start": [0.0, 0.5], "direction": [0.0, 1.0], "length": 0.5,
         "loads": {"point_forces": [[0.5, -force[1], force[0]]]}}]
    split["joints"] = [{"name": "j", "at": ["a:end", "b:start"]}]
    one, two = fe_beam.run("dynamic", single), fe_beam.run("dynamic", split)
    assert one["status"] == two["status"] == "completed"
    assert one["history"][-1]["energies"]["dissipated"] > 0.05 * one["history"][-1]["energies"][
        "kinetic"]  # 8 %
    for a, b in zip(one["history"], two["history"], strict=True):
        # measured: 1e-16
        assert b["tip"]["u"] == pytest.approx(-a["tip"]["v"], abs=1e-11)
        assert b["tip"]["v"] == pytest.approx(a["tip"]["u"], abs=1e-11)
        assert b["energies"]["dissipated"] == pytest.approx(a["energies"]["dissipated"],
                                                            rel=1e-9, abs=1e-15)


def test_dynamic_l_frame_released_from_a_static_load_conserves_energy():
    """A clamped L-frame released from the static deflection under a small end force
    (energy-conserving scheme): the stored energy at release is Clapeyron's P . delta / 2 of
    the static state, and kinetic + strain energy keep it (energy_balance at round-off)."""
    a, b = 0.8, 0.6
    EI = E * B * H**3 / 12
    force = [0.0, -1e-6 * EI / b**2]  # the nonlinear terms: 2.4e-5 relative at 1e-4
    config = _dynamic(6, "energy-conserving", t_end=0.08, dt=0.004)
    config["rods"] = [
        {"name": "column", "start": [0.0, 0.0], "direction": [0.0, 1.0], "length": a,
         "supports": {"x0": "clamped"}},
        {"name": "beam", "start": [0.0, a], "direction": [1.0, 0.0], "length": b,
         "loads": {"point_forces": [[b, *force]]}}]
    config["joints"] = [{"name": "corner", "at": ["column:end", "beam:start"]}]
    config["loads"] = {"time_function": "0", "steps": 2}
    config["initial"] = {"from_static": True}
    summary = fe_beam.run("dynamic", config)
    assert summary["status"] == "completed"
    energy = next(c for c in summary["checks"] if c["name"] == "energy_balance")
    assert energy["passed"] and energy["value"] < 1e-9, energy
    start = summary["history"][0]
    clapeyron = 0.5 * (force[1] * start["tip"]["v"])
    assert start["energies"]["strain"] == pytest.approx(clapeyron, rel=1e-6)
    for entry in summary["history"]:
        total = entry["energies"]["kinetic"] + entry["energies"]["strain"]
        assert total == pytest.approx(clapeyron, rel=1e-6)
    assert max(h["energies"]["kinetic"] for h in summary["history"]) > 0.3 * clapeyron


@pytest.mark.parametrize("scheme", ["generalized-alpha", "energy-conserving"])
def test_dynamic_free_chain_without_loads_certifies_its_momenta(scheme):
    """A free chain with no [loads] at all (the time function left at its default 1) is in
    free flight: the run certifies its momenta (they were left unchecked unless
    time_function = "0"). A reversed rod joined start to start, set turning."""
    config = _dynamic(4, scheme, t_end=0.01, dt=0.002)
    config["rods"] = [
        {"name": "b", "start": [1.0, 0.2], "direction": [-1.0, 0.0], "length": 0.6},
        {"name": "a", "start": [1.0, 0.2], "direction": [0.0, 1.0], "length": 0.4}]
    config["joints"] = [{"name": "j", "at": ["b:start", "a:start"]}]
    config["initial"] = {"velocity": ["0", "0.5 * x", "0"]}
    config.pop("loads", None)
    summary = fe_beam.run("dynamic", config)
    assert summary["status"] == "completed"
    names = {c["name"]: c for c in summary["checks"]}
    assert names["linear_momentum"]["passed"] and names["angular_momentum"]["passed"], names


@pytest.mark.parametrize("scheme", ["generalized-alpha", "energy-conserving"])
def test_dynamic_free_l_frame_momenta(scheme):
    """A free L-frame away from the origin, its sections set spinning (theta_t = w x, x the
    chain's arc length): no load, so its momenta are constants: linear 0, angular about the
    origin int rho I theta_t dx = rho I w L^2 / 2 (the reference position of each rod in the
    moment arm), certified by the run."""
    a, b, spin = 0.7, 0.5, 20.0
    config = _dynamic(6, scheme, t_end=0.02, dt=0.002)
    config["rods"] = [
        {"name": "column", "start": [0.3, -0.2], "direction": [0.0, 1.0], "length": a},
        {"name": "beam", "start": [0.3, 0.5], "direction": [1.0, 0.0], "length": b}]
    config["joints"] = [{"name": "corner", "at": ["column:end", "beam:start"]}]
    config["initial"] = {"velocity": ["0", "0", f"{spin} * x"]}
    config["loads"] = {"time_function": "0"}
    summary = fe_beam.run("dynamic", config)
    assert summary["status"] == "completed"
    names = {c["name"]: c for c in summary["checks"]}
    assert names["linear_momentum"]["passed"] and names["angular_momentum"]["passed"]
    expected = RHO * B * H**3 / 12 * spin * (a + b) ** 2 / 2
    # measured: 9.5e-10 (the Newton tolerance; a straight free rod: 4.6e-10), 1.1e-5
    # (generalised-alpha does not balance the angular momentum exactly)
    tolerance = 3e-9 if scheme == "energy-conserving" else 3e-5
    for entry in summary["history"]:
        assert entry["momenta"]["angular_momentum"] == pytest.approx(expected, rel=tolerance)


def test_dynamic_refuses_what_chains_do_not_run(tmp_path):
    from fe_beam.config import validate
    from fe_beam.errors import ConfigError

    config = _dynamic(4, "fd-rk45")
    config["rods"] = [{"name": "a", "length": 1.0, "supports": {"x0": "clamped"}}]
    with pytest.raises(ConfigError, match="scheme = \"fd-rk45\" with \\[\\[rods\\]\\]"):
        validate("dynamic", config)
    config = _dynamic(4, "generalized-alpha")
    config["rods"] = [{"name": "a", "length": 1.0, "supports": {"x0": "clamped"}}]
    config["initial"] = {"angular_velocity": 1.0}
    with pytest.raises(ConfigError, match="angular_velocity with \\[\\[rods\\]\\]"):
        validate("dynamic", config)


# --- refine ------------------------------------------------------------------------------------
def test_refine_l_frame_refines_every_rod_at_order_four():
    """fe-beam refine of a clamped L-frame under a large end force (Reissner law): each level
    doubles every rod's elements (rods of 3 and 5 elements: 8, 16, 32 in all), the tip's
    observed order is 4, and the extrapolated tip is the independent shooting solution's."""
    from fe_beam.baselines import frame_shooting

    a, b = 1.0, 0.7
    area, inertia = B * H, B * H**3 / 12
    EI, EA, GA = E * inertia, E * area, E / (2 * (1 + NU)) * area
    force = [0.8 * EI / a**2, -2.5 * EI / a**2]
    config = _base(3) | {"loads": {"steps": 4}, "refine": {"levels": 3}}
    config["rods"] = [
        {"name": "column", "start": [0.0, 0.0], "direction": [0.0, 1.0], "length": a,
         "supports": {"x0": "clamped"}},
        {"name": "beam", "start": [0.0, a], "direction": [1.0, 0.0], "length": b,
         "mesh": {"elements": 5}, "loads": {"point_forces": [[b, *force]]}}]
    config["joints"] = [{"name": "corner", "at": ["column:end", "beam:start"]}]
    summary = fe_beam.run("refine", config)
    assert summary["status"] == "completed"
    assert [level["elements"] for level in summary["levels"]] == [8, 16, 32]
    frame = frame_shooting.Frame((a, b), (math.pi / 2, 0.0), EI, EA, GA, (0.0, 0.0),
                                 "clamped", "free", ((a + b, *force),))
    x, y, angle = frame_shooting.solve_frame(frame, 1.0).end()[:3]
    reference = {"tip.u": x - b, "tip.v": y - a, "tip.theta": angle}
    for name, value in reference.items():
        analysis = summary["analysis"][name]
        assert 3.7 < analysis["order"] < 4.3, (name, analysis["order"])
        finest = analysis["levels"][-1]["value"]
        # the finest level within its estimated error; the extrapolation closer still
        assert abs(finest - value) <= 2 * analysis["error_estimate"], (name, finest, value)
        assert abs(analysis["extrapolated"] - value) < 0.2 * abs(finest - value), name


def test_refine_refuses_a_fractional_ratio_with_rods():
    from fe_beam.config import validate
    from fe_beam.errors import ConfigError

    config = _base(4) | {"refine": {"levels": 3, "ratio": 1.5}}
    config["rods"] = [{"name": "a", "length": 1.0, "supports": {"x0": "clamped"},
                       "loads": {"point_forces": [[1.0, 0.0, -1.0]]}}]
    with pytest.raises(ConfigError, match="ratio 1.5 with \\[\\[rods\\]\\]"):
        validate("refine", config)


# --- two ranks ---------------------------------------------------------------------------------
@pytest.mark.mpi
@pytest.mark.skipif(mpirun_command(2) is None or MPI.COMM_WORLD.size > 1,
                    reason="needs mpirun (and a serial pytest)")
@pytest.mark.parametrize("command", ["modes", "buckling"])
def test_two_ranks_give_the_serial_portal_frame(tmp_path, command):
    """``mpirun -n 2 fe-beam modes | buckling`` of a portal frame: one rank's numbers."""
    from test_mpi_errors import fe_beam as fe_beam_job

    if command == "modes":
        config = _portal(6, 1.0, 1.2) | {"modes": {"count": 4}}
        key = "frequencies_hz"
    else:
        config = _loaded_portal(6, 1.0, 1.5, E * B * H**3 / 12, 0.04)
        key = "linearised_load_factors"
    alone = fe_beam.run(command, config)
    process, _ = fe_beam_job(tmp_path, config, "--out", str(tmp_path / "two"), command=command)
    assert process.returncode == 0, process.stderr
    together = json.loads((tmp_path / "two" / "summary.json").read_text())
    assert np.allclose(together[key], alone[key], rtol=1e-9, atol=0), (together[key], alone[key])
    if command == "modes":
        assert together["mode_kinds"] == alone["mode_kinds"]


# --- design ------------------------------------------------------------------------------------
def test_design_a_rod_section_by_name():
    """fe-beam design of an L-frame's beam height (rods.beam.section.h: a field of the beam
    only, written in place) so that the frame's end is at a target deflection: a fresh static
    run of the answer (--set rods.beam.section.h, the rod by its name) reaches the target, and
    only the beam's section changed (the column's is the top-level one)."""
    EI = E * B * H**3 / 12
    config = _base(6) | {"loads": {"steps": 2}}
    config["rods"] = [
        {"name": "column", "start": [0.0, 0.0], "direction": [0.0, 1.0], "length": 1.0,
         "supports": {"x0": "clamped"}},
        {"name": "beam", "start": [0.0, 1.0], "direction": [1.0, 0.0], "length": 0.7,
         "loads": {"point_forces": [[0.7, 0.0, -0.5 * EI]]}}]
    config["joints"] = [{"name": "corner", "at": ["column:end", "beam:start"]}]
    target = -0.31
    config["design"] = {"variables": ["rods.beam.section.h"], "bounds": [[0.03, 0.08]],
                        "objective": "tip_pose", "target": {"v": target}}
    summary = fe_beam.run("design", config)
    assert summary["status"] == "converged", summary["message"]
    h = summary["variables"]["rods.beam.section.h"]
    assert 0.03 < h < 0.08 and abs(h - H) > 1e-3
    assert summary["reproduce"].endswith(f"--set rods.beam.section.h={h!r}")
    plain = {k: v for k, v in config.items() if k != "design"}
    answer = fe_beam.run("static", fe_beam.config.apply_overrides(
        plain, [f"rods.beam.section.h={h!r}"]))
    tip = answer["steps"][-1]["tip"]
    assert tip["v"] == pytest.approx(summary["tip"]["v"], abs=1e-9)
    assert tip["u"] == pytest.approx(summary["tip"]["u"], abs=1e-9)
    assert tip["v"] == pytest.approx(target, abs=1e-6)
    # the column kept its section: the same frame with the column's own h changed differs
    other = fe_beam.config.apply_overrides(plain, [f"rods.beam.section.h={h!r}",
                                                   f"rods.column.section.h={h!r}"])
    assert abs(fe_beam.run("static", other)["steps"][-1]["tip"]["v"] - tip["v"]) > 1e-2


@pytest.mark.parametrize(("change", "words"), [
    ({"objective": "backbone", "points": [[1.0, 0.0, 1.0]]}, "objective = 'backbone' with"),
    ({"variables": ["section.h"], "bounds": [[0.03, 0.08]]}, None),
    ({"variables": ["rods.beam.section.h", "section.b"], "bounds": [[0.03, 0.08],
                                                                   [0.01, 0.03]]},
     "top-level value"),
    ({"variables": ["rods.nobody.section.h"]}, "not a design variable of the structure"),
])
def test_design_of_a_structure_refuses_what_it_does_not_run(change, words):
    from fe_beam.config import validate
    from fe_beam.errors import ConfigError

    config = _base(4)
    config["rods"] = [
        {"name": "column", "start": [0.0, 0.0], "direction": [0.0, 1.0], "length": 1.0,
         "supports": {"x0": "clamped"}},
        {"name": "beam", "start": [0.0, 1.0], "direction": [1.0, 0.0], "length": 0.7,
         "loads": {"point_forces": [[0.7, 0.0, -1.0]]}}]
    config["joints"] = [{"name": "corner", "at": ["column:end", "beam:start"]}]
    config["design"] = {"variables": ["rods.beam.section.h"], "bounds": [[0.03, 0.08]],
                        "objective": "tip_pose", "target": {"v": -0.3}} | change
    if words is None:  # the top-level section of rods without their own: allowed
        validate("design", config)
        return
    with pytest.raises(ConfigError, match=words):
        validate("design", config)


def test_dynamic_history_has_each_rods_end(tmp_path):
    """history.csv gains rod_<name>_x, _y, _angle (each rod's end, world axes), the values
    of summary.json's history "rods"."""
    config = _dynamic(3, "generalized-alpha", t_end=0.02, dt=0.01)
    config["rods"] = [
        {"name": "column", "start": [0.0, 0.0], "direction": [0.0, 1.0], "length": 0.8,
         "supports": {"x0": "clamped"}, "loads": {"point_forces": [[0.8, 2.0, 0.0]]}},
        {"name": "beam", "start": [0.0, 0.8], "direction": [1.0, 0.0], "length": 0.6}]
    config["joints"] = [{"name": "corner", "at": ["column:end", "beam:start"]}]
    summary = fe_beam.run("dynamic", config, tmp_path / "out")
    assert summary["status"] == "completed"
    lines = (tmp_path / "out" / "history.csv").read_text().splitlines()
    header, last = lines[0].split(","), [float(x) for x in lines[-1].split(",")]
    rods = summary["history"][-1]["rods"]
    for name in ("column", "beam"):
        row = [last[header.index(f"rod_{name}_{k}")] for k in ("x", "y", "angle")]
        assert row == pytest.approx([*rods[name]["tip"], rods[name]["tip_angle"]], rel=1e-12)
    assert rods["beam"]["tip"][0] == pytest.approx(0.6 + summary["history"][-1]["tip"]["u"])
    assert abs(rods["column"]["tip"][0]) > 1e-4  # it moved


@pytest.mark.parametrize("command", ["design", "calibrate"])
def test_spatial_chains_are_refused_in_design_and_calibrate(command):
    from fe_beam.config import validate
    from fe_beam.errors import ConfigError

    config = _base(4)
    config["model"] = {"law": "reissner", "kinematics": "spatial"}
    config["rods"] = [{"name": "a", "start": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0],
                       "length": 1.0, "supports": {"x0": "clamped"}}]
    with pytest.raises(ConfigError, match=f"fe-beam {command} does not run (a )?spatial"):
        validate(command, config)


# --- joint forces in motion --------------------------------------------------------------------
def _joint_balance_recorder(monkeypatch, records):
    """Wrap `ChainGeometry.joints_in_motion` to record, beside each reported joint force, the
    balance of the part after the joint as a free body from the state's acceleration a (the
    scheme's `end_acceleration`): its applied end force P at t minus its momentum rate
    int rho A a, and the moment about the joint's point likewise with the sections' rotary
    inertia rho I theta_tt. The reported force is the residual of the elements before the
    joint: an independent sum over the other elements."""
    import ufl
    from dolfinx import fem

    from fe_beam.fem import compat
    from fe_beam.fem.rod import assemble_scalar
    from fe_beam.fem.structure import ChainGeometry

    original = ChainGeometry.joints_in_motion

    def recording(self, inertia):
        result = original(self, inertia)
        problem, integrator = self.problem, inertia.__self__
        joint = self.structure.joints_on_chain[0]
        after = fem.Function(self.theta0.function_space)
        dofs = compat.cell_dofs(after.function_space)[: len(self._segment_of_cell), 0]
        after.x.array[dofs] = self._segment_of_cell > joint.segment
        a = ufl.split(integrator._end_a)
        u, v = problem.fields()[0], problem.fields()[1]
        X, Y = self.reference[0], self.reference[1]
        x_c, y_c, _ = self.position(joint.s)
        rho_area = problem.rho * problem.section_props.A
        rho_inertia = problem.rho * problem.section_props.I
        rate = [assemble_scalar(fem.form(after * rho_area * a[i] * problem.dx_mass))
                for i in range(2)]
        spin = assemble_scalar(fem.form(after * (
            rho_area * ((X + u - x_c) * a[1] - (Y + v - y_c) * a[0]) + rho_inertia * a[2])
            * problem.dx_mass))
        records.append((result[joint.name], rate, spin, (x_c, y_c)))
        return result

    monkeypatch.setattr(ChainGeometry, "joints_in_motion", recording)


def _swinging_frame(scheme: str, force) -> dict:
    """A clamped L-frame (column 0.8 along y, beam 0.6 along x; 6 elements per rod) under a
    suddenly applied force at the beam's end, 5 steps of 2 ms."""
    config = _dynamic(6, scheme, t_end=0.01, dt=0.002)
    config["rods"] = [
        {"name": "column", "start": [0.0, 0.0], "direction": [0.0, 1.0], "length": 0.8,
         "supports": {"x0": "clamped"}},
        {"name": "beam", "start": [0.0, 0.8], "direction": [1.0, 0.0], "length": 0.6,
         "loads": {"point_forces": [[0.6, *force]]}}]
    config["joints"] = [{"name": "corner", "at": ["column:end", "beam:start"]}]
    return config


@pytest.mark.parametrize("scheme", ["generalized-alpha", "energy-conserving"])
def test_dynamic_joint_force_is_the_balance_of_the_part_beyond(monkeypatch, tmp_path, scheme):
    """Each step's joint force and moment in fe-beam dynamic (a clamped L-frame swinging under
    a suddenly applied end force) equal the balance of the part beyond the joint as a free
    body: the end force minus its momentum rate, and the moment about the joint, to
    round-off; the inertia is a large part of it. history.csv has the columns."""
    force = np.array([3.0, -8.0])
    records = []
    _joint_balance_recorder(monkeypatch, records)
    summary = fe_beam.run("dynamic", _swinging_frame(scheme, force), tmp_path)
    assert summary["status"] == "completed"
    history = summary["history"]
    assert len(records) == len(history) >= 6
    worst, inertia = 0.0, 0.0
    for entry, (reported, rate, spin, corner) in zip(history, records, strict=True):
        assert entry["joints"]["corner"] == reported
        expected = force - np.array(rate)
        tip = np.array(entry["rods"]["beam"]["tip"])
        arm = tip - np.array(corner)
        moment = float(arm[0] * force[1] - arm[1] * force[0]) - spin  # NumPy 2: no 2D cross
        inertia = max(inertia, np.linalg.norm(rate) / np.linalg.norm(force))
        worst = max(worst, np.linalg.norm(np.array(reported["force"]) - expected)
                    / np.linalg.norm(force),
                    abs(reported["moment"] - moment) / (0.6 * np.linalg.norm(force)))
    assert inertia > 0.3, inertia  # the momentum rate is a large part of the force
    # measured: 1.1e-15 (generalised-alpha), 7.9e-16 (energy-conserving)
    assert worst < 1e-12, worst
    lines = (tmp_path / "history.csv").read_text().splitlines()
    header, last = lines[0].split(","), [float(x) for x in lines[-1].split(",")]
    assert last[header.index("joint_corner_Fy")] == pytest.approx(
        history[-1]["joints"]["corner"]["force"][1], rel=1e-12)


def test_dynamic_fixed_body_reaction_balances_the_whole_frame(monkeypatch):
    """The swinging L-frame held by a fixed body joined to the column's start: each step's
    base joint (the ground's force on the column) is the whole frame's momentum rate minus the
    end force, int rho A a - P, to round-off (the consistent mass couples the held end to its
    neighbours: the reaction takes their inertia)."""
    from dolfinx import fem

    from fe_beam.fem.rod import assemble_scalar
    from fe_beam.fem.structure import ChainGeometry

    rates = []
    original = ChainGeometry.joints_in_motion

    def recording(self, inertia):
        result = original(self, inertia)
        problem, integrator = self.problem, inertia.__self__
        a = integrator._end_a.sub(0), integrator._end_a.sub(1)
        rates.append([assemble_scalar(fem.form(problem.rho * problem.section_props.A * a_i
                                               * problem.dx_mass)) for a_i in a])
        return result

    monkeypatch.setattr(ChainGeometry, "joints_in_motion", recording)
    force = np.array([3.0, -8.0])
    config = _swinging_frame("generalized-alpha", force)
    del config["rods"][0]["supports"]
    config["bodies"] = [{"name": "ground", "position": [0.0, 0.0], "fixed": True}]
    config["joints"].append({"name": "base", "at": ["column:start", "body:ground"]})
    summary = fe_beam.run("dynamic", config)
    assert summary["status"] == "completed"
    assert len(rates) == len(summary["history"])
    for entry, rate in zip(summary["history"], rates, strict=True):
        expected = np.array(rate) - force
        # measured: 1e-15 of |P|
        assert np.linalg.norm(np.array(entry["joints"]["base"]["force"]) - expected) \
            <= 1e-12 * np.linalg.norm(force), (entry["joints"]["base"], expected)


# --- calibrate ---------------------------------------------------------------------------------
def _calibration_frame(column_E: float, beam_h: float) -> dict:
    """A clamped L-frame (column 0.8 along y, beam 0.6 along x, 6 elements per rod, Reissner
    law) under a large end force; the column of its own modulus, the beam of its own height."""
    config = _base(6)
    EI = E * B * H**3 / 12
    config["rods"] = [
        {"name": "column", "start": [0.0, 0.0], "direction": [0.0, 1.0], "length": 0.8,
         "supports": {"x0": "clamped"}, "material": {"E": column_E, "nu": NU}},
        {"name": "beam", "start": [0.0, 0.8], "direction": [1.0, 0.0], "length": 0.6,
         "section": {"h": beam_h},
         "loads": {"point_forces": [[0.6, 0.3 * EI, -2.0 * EI]]}}]
    config["joints"] = [{"name": "corner", "at": ["column:end", "beam:start"]}]
    config["loads"] = {"steps": 2}
    config["solver"] = {"rtol": 1e-12}
    return config


def test_calibrate_rod_parameters_by_name(tmp_path):
    """fe-beam calibrate of a chain: the column's E and the beam's h recovered from the end's
    pose and a point of the column (chain coordinate s) at two load levels, the synthetic
    data from fe-beam static of the true frame; the start 20 % and 11 % off."""
    truth = {"rods.column.material.E": 2.5e7, "rods.beam.section.h": 0.045}
    static = fe_beam.run("static", _calibration_frame(2.5e7, 0.045))
    assert static["status"] == "converged"
    rows = []
    for step in static["steps"]:
        tip = step["tip"]
        rows.append(f"{step['load_factor']!r},{tip['u']!r},{tip['v']!r},{tip['theta']!r},,,")
        corner = step["rods"]["column"]["tip"]  # the column's end: s = 0.8
        rows.append(f"{step['load_factor']!r},,,,0.8,{corner[0]!r},{corner[1]!r}")
    assert abs(static["steps"][-1]["tip"]["v"]) > 0.1  # a large deflection
    data = tmp_path / "data.csv"
    data.write_text("load_factor,tip_u,tip_v,tip_theta,s,x,y\n" + "\n".join(rows) + "\n")
    config = _calibration_frame(2.0e7, 0.04) | {"calibrate": {"parameters": list(truth)}}
    summary = fe_beam.run("calibrate", config, tmp_path / "out", data=data)
    assert summary["status"] == "converged", summary.get("message")
    for key, value in truth.items():
        # measured: 1.6e-14 (E), 2.2e-16 (h)
        assert summary["parameters"][key] == pytest.approx(value, rel=1e-10), summary["parameters"]


@pytest.mark.parametrize("keys, words", [
    (["rods.roof.section.h"], "no rod 'roof'"),
    (["rods.column.material.E", "rods.column.material.G"], "G follows E"),
    (["rods.beam.material.nu"], "unknown parameter"),
    (["rods.beam.section.h"], "points without s"),
])
def test_calibrate_refuses_rod_parameters_it_cannot_fit(tmp_path, keys, words):
    from fe_beam.errors import ConfigError

    config = _calibration_frame(2.0e7, 0.04) | {"calibrate": {"parameters": keys}}
    data = tmp_path / "data.csv"
    data.write_text("load_factor,tip_u,tip_v\n1.0,0.02,-0.1\n" if "without s" not in words
                    else "load_factor,x,y\n1.0,0.5,0.7\n1.0,0.6,0.7\n")
    with pytest.raises(ConfigError, match=words):
        fe_beam.run("calibrate", config, None, data=data)

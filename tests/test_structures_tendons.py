"""Tendons on chains of rods ([[tendons]] with rod = "NAME"; issue 29, "Tendons stay per
rod"): a tendon runs along one rod, its entry, anchor and path x from the rod's start and its
offsets in the rod's own section; `fe-beam finger` and `fe-beam path` sweep every rod's
tendons, the tip being the chain's last end.

References: the single rod with the tendon over the same span (a rod split in two with the
tendon on the second rod only is the rod), and MODEL.md section 2 / 8's check case: a straight
tendon at constant offset delta on an inextensible, unshearable rod bends it into a circle
with EI kappa = tau delta (the internal moment tau |delta|), here on the second rod of a chain
whose first rod is clamped at an angle and joined rigidly at another (the first rod carries
none of the tendon's load: its forces are internal to the second rod)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import fe_beam
from fe_beam.config import validate
from fe_beam.errors import ConfigError

E, B, H = 1.0e6, 0.02, 0.01
EI = E * B * H**3 / 12
ANGLE, TURN = 0.7, 1.1  # the first rod's direction and the joint's angle [rad]
LA, LB = 0.04, 0.06


def _base(elements: int = 10, constraint: str = "inextensible-unshearable") -> dict:
    return {"section": {"shape": "rectangle", "b": B, "h": H},
            "material": {"E": E, "nu": 0.3},
            "model": {"law": "reissner", "constraint": constraint},
            "mesh": {"elements": elements, "degree": 2}, "loads": {"steps": 4},
            "output": {"xdmf": False, "plots": False}}


@pytest.mark.parametrize("constraint, control", [("inextensible-unshearable", "tension"),
                                                 ("none", "tension"), ("none", "pull_in")])
def test_split_rod_with_a_tendon_on_its_second_rod_is_the_rod(constraint, control):
    """A tapered tendon path from x = 0.04 to the tip of a 0.1 m cantilever: the single rod,
    and the rod split at x = 0.04 with the tendon on the second rod (its x from that rod's
    start), give the same tip to round-off (the same mesh: 8 + 12 elements)."""
    tau = 0.5
    single = _base(20, constraint)
    single["beam"] = {"length": LA + LB}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    single["tendons"] = [{"name": "t", "path": [[LA, 0.003], [LA + LB, -0.001]],
                          "entry": LA, "tension": tau}]
    split = _base(10, constraint)
    split["rods"] = [
        {"name": "a", "start": [0.0, 0.0], "direction": [1.0, 0.0], "length": LA,
         "supports": {"x0": "clamped"}, "mesh": {"elements": 8}},
        {"name": "b", "start": [LA, 0.0], "direction": [1.0, 0.0], "length": LB,
         "mesh": {"elements": 12}}]
    split["joints"] = [{"name": "j", "at": ["a:end", "b:start"]}]
    split["tendons"] = [{"name": "t", "rod": "b", "path": [[0.0, 0.003], [LB, -0.001]],
                         "tension": tau}]
    if control == "pull_in":  # the pull-in of the tendon (its tension the multiplier)
        for config in (single, split):
            config["tendons"][0].pop("tension")
            config["tendons"][0]["pull_in"] = 2e-4
    one, two = fe_beam.run("finger", single), fe_beam.run("finger", split)
    assert one["status"] == two["status"] == "converged", two.get("message")
    tip1, tip2 = one["steps"][-1]["tip"], two["steps"][-1]["tip"]
    scale = max(abs(tip1[k]) for k in ("u", "v", "theta"))
    assert abs(tip1["theta"]) > 1e-2
    for key in ("u", "v", "theta"):
        assert abs(tip1[key] - tip2[key]) <= 1e-12 * scale, (key, tip1[key], tip2[key])
    assert two["steps"][-1]["tensions"] == pytest.approx(one["steps"][-1]["tensions"],
                                                         rel=1e-12)
    assert two["steps"][-1]["pull_ins"] == pytest.approx(one["steps"][-1]["pull_ins"],
                                                         rel=1e-12)
    assert all(c["passed"] for c in two["checks"]), two["checks"]


def _turned_chain(delta: float, tau: float, reversed_rod: bool) -> dict:
    """Rod a clamped at the origin along ANGLE, rod b joined rigidly at ANGLE + TURN, a
    tendon at constant offset along the whole of b (``reversed_rod``: b given from its far end
    toward the joint, the offset in its own frame then -delta for the same tendon line)."""
    phi = ANGLE + TURN
    joint = np.array([LA * math.cos(ANGLE), LA * math.sin(ANGLE)])
    along = np.array([math.cos(phi), math.sin(phi)])
    config = _base()
    rod_b = ({"name": "b", "start": list(joint + LB * along), "direction": list(-along),
              "length": LB} if reversed_rod else
             {"name": "b", "start": list(joint), "direction": list(along), "length": LB})
    config["rods"] = [{"name": "a", "start": [0.0, 0.0],
                       "direction": [math.cos(ANGLE), math.sin(ANGLE)], "length": LA,
                       "supports": {"x0": "clamped"}}, rod_b]
    config["joints"] = [{"name": "j", "at": ["a:end", "b:end" if reversed_rod else "b:start"]}]
    offset = -delta if reversed_rod else delta
    config["tendons"] = [{"name": "flexor", "rod": "b", "offset_base": offset,
                          "offset_tip": offset, "tension": tau}]
    return config, joint, phi


@pytest.mark.parametrize("delta, reversed_rod", [(0.003, False), (-0.002, False),
                                                 (0.003, True)])
def test_constant_offset_tendon_on_a_turned_rod_bends_it_into_a_circle(delta, reversed_rod):
    tau = 0.5
    config, joint, phi = _turned_chain(delta, tau, reversed_rod)
    result = fe_beam.run("finger", config)
    assert result["status"] == "converged", result.get("message")
    step = result["steps"][-1]
    kappa = tau * delta / EI  # EI kappa = tau delta: the internal moment tau |delta|
    end_angle = phi + kappa * LB
    end = joint + np.array([math.sin(end_angle) - math.sin(phi),
                            math.cos(phi) - math.cos(end_angle)]) / kappa
    tip = step["tip"]
    print(f"delta {delta}, reversed {reversed_rod}: kappa {tip['theta'] / LB:.12g} vs "
          f"{kappa:.12g}")
    assert tip["theta"] == pytest.approx(kappa * LB, rel=1e-10)
    # rod a carries none of the tendon's load: its own end (the joint) stays in place
    assert step["rods"]["a"]["tip"] == pytest.approx(joint, abs=1e-14)
    position = (np.array(step["rods"]["b"]["tip"]) if not reversed_rod
                else end)  # reversed: rod b's own end is the joint; the chain's end below
    reference = np.array(config["rods"][1]["start"]) if reversed_rod else joint + LB * np.array(
        [math.cos(phi), math.sin(phi)])
    chain_end = reference + np.array([tip["u"], tip["v"]])
    assert chain_end == pytest.approx(end, abs=1e-10 * LB)
    assert position == pytest.approx(end, abs=1e-10 * LB)
    assert step["joints"]["j"]["moment"] == pytest.approx(0.0, abs=1e-12 * tau * abs(delta))


def test_tendon_on_a_rod_with_its_own_section_bends_it_with_its_own_stiffness():
    config, _, _ = _turned_chain(0.002, 0.5, False)
    config["rods"][1]["section"] = {"h": 0.006}
    result = fe_beam.run("finger", config)
    assert result["status"] == "converged", result.get("message")
    stiffness = E * B * 0.006**3 / 12
    assert result["steps"][-1]["tip"]["theta"] == pytest.approx(0.5 * 0.002 / stiffness * LB,
                                                                rel=1e-10)


def test_path_sweeps_a_chain_tendon_along_the_circle():
    """`fe-beam path` (parameter = "tension") on the turned chain: every point is the circle
    of its tension (theta at the chain's end = tau delta LB / EI)."""
    delta = 0.003
    config, _, _ = _turned_chain(delta, 0.2, False)
    config["path"] = {"parameter": "tension", "max_load_factor": 3.0, "arc_length": 0.5}
    result = fe_beam.run("path", config)
    assert result["status"] == "converged", result.get("message")
    points = [p for p in result["path"] if p["load_factor"] > 0]
    assert len(points) >= 3
    for index, point in enumerate(points):
        tau = point["tension"]
        # the path's first point reports its load factor 1e-7 off its state (also on a
        # single rod: 8.8e-8; the engine's, not the chain's); the others to round-off
        assert point["tip"]["theta"] == pytest.approx(tau * delta * LB / EI,
                                                      rel=1e-6 if index == 0 else 1e-12)


MISTAKES = [
    (lambda c: c["tendons"][0].update(rod="c"), "rod = 'c' names no rod of [[rods]] (rods: a, b)"),
    (lambda c: c["tendons"][0].pop("rod"), "needs rod = \"NAME\" with [[rods]]"),
    (lambda c: c["tendons"][0].update(anchor=0.07),
     "(on rod 'b', length 0.06 m): tendon 'flexor': its path spans x = 0 .. 0.06 but must "
     "cover entry 0 .. anchor 0.07"),
    (lambda c: (c["tendons"][0].pop("offset_base"), c["tendons"][0].pop("offset_tip"),
                c["tendons"][0].update(path=[[0.0, 0.002], [0.08, 0.002]])),
     "(on rod 'b', length 0.06 m): tendon 'flexor': anchor 0.08 lies beyond the beam"),
    (lambda c: c["tendons"][0].update(offset_base=0.006),
     "outside the section (y from -0.005 to 0.005 m about its centroid) (on rod 'b'"),
    # the rod's own section
    (lambda c: c["rods"][1].update(section={"h": 0.005}),
     "offset 0.003 m at x = 0 m lies outside the section (y from -0.0025 to 0.0025 m about "
     "its centroid) (on rod 'b', x from its start)"),
]


@pytest.mark.parametrize("change, words", MISTAKES)
def test_chain_tendon_mistakes_are_one_sentence(change, words):
    config, _, _ = _turned_chain(0.003, 0.5, False)
    change(config)
    with pytest.raises(ConfigError) as error:
        validate("finger", config)
    assert words in str(error.value), str(error.value)


def test_rod_key_without_rods_and_other_commands_are_refused():
    config = _base()
    config["beam"] = {"length": 0.1}
    config["supports"] = {"x0": "clamped", "xL": "free"}
    config["tendons"] = [{"name": "t", "rod": "b", "offset_base": 0.002, "offset_tip": 0.002,
                          "tension": 0.1}]
    with pytest.raises(ConfigError, match="rod names a rod of \\[\\[rods\\]\\], and the "
                                          "configuration has no \\[\\[rods\\]\\]"):
        validate("finger", config)
    chain, _, _ = _turned_chain(0.003, 0.5, False)
    with pytest.raises(ConfigError, match="\\[\\[tendons\\]\\] with \\[\\[rods\\]\\] in "
                                          "fe-beam dynamic is not supported yet"):
        validate("dynamic", chain)


def test_every_rods_tendons_are_swept():
    """A tendon on each rod of the turned chain (each internal to its rod): each rod bends
    into its own circle, EI kappa_i = tau_i delta_i, at every step of the finger's sweep
    (one load factor for all), and the chain's end turns by the sum of the two rods'
    angles."""
    config, _, _ = _turned_chain(0.003, 0.5, False)
    config["tendons"].append({"name": "extensor", "rod": "a", "offset_base": -0.002,
                              "offset_tip": -0.002, "tension": 0.3})
    result = fe_beam.run("finger", config)
    assert result["status"] == "converged", result.get("message")
    assert len(result["steps"]) == 4
    for step in result["steps"]:
        tau_b, tau_a = step["tensions"]
        kappa_a, kappa_b = tau_a * -0.002 / EI, tau_b * 0.003 / EI
        assert step["rods"]["a"]["tip_angle"] == pytest.approx(ANGLE + kappa_a * LA,
                                                               rel=1e-12)
        assert step["tip"]["theta"] == pytest.approx(kappa_a * LA + kappa_b * LB, rel=1e-10)
        joint = np.array([math.sin(ANGLE + kappa_a * LA) - math.sin(ANGLE),
                          math.cos(ANGLE) - math.cos(ANGLE + kappa_a * LA)]) / kappa_a
        assert step["rods"]["a"]["tip"] == pytest.approx(joint, abs=1e-12)
    assert result["steps"][-1]["tensions"] == pytest.approx([0.5, 0.3], rel=1e-15)


# --- spatial chains ---------------------------------------------------------------------------
def _rotation(vector) -> np.ndarray:
    vector = np.asarray(vector, dtype=float)
    angle = float(np.linalg.norm(vector))
    k = vector / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


@pytest.mark.parametrize("axis, reversed_rod", [("z", False), ("z", True), ("y", True)])
def test_spatial_chain_tendon_bends_its_rod_into_a_circle(axis, reversed_rod):
    """A spatial chain: rod a clamped with a skew frame, rod b joined rigidly with another
    (``reversed_rod``: b given from its far end, its direction and normal turned, the offset
    y then of the other sign); a tendon at constant offset along b's d3 (offset_z) or d2
    (offset_y) bends b into the circle of curvature tau |offset| / EI about its d2 or d3, in
    the plane of the offset: the chain's end on that circle, its rotation kappa LB; rod a
    unloaded."""
    tau, offset = 0.5, 0.004 if axis == "z" else 0.003
    frame_a = _rotation([0.2, -0.4, 0.6])
    frame_b = _rotation([0.5, 0.3, -0.2]) @ frame_a
    config = _base()
    config["model"]["kinematics"] = "spatial"
    joint = frame_a[:, 0] * LA
    rod_b = ({"name": "b", "start": list(joint + LB * frame_b[:, 0]),
              "direction": list(-frame_b[:, 0]), "normal": list(-frame_b[:, 1]), "length": LB}
             if reversed_rod else
             {"name": "b", "start": list(joint), "direction": list(frame_b[:, 0]),
              "normal": list(frame_b[:, 1]), "length": LB})
    config["rods"] = [{"name": "a", "start": [0.0, 0.0, 0.0], "direction": list(frame_a[:, 0]),
                       "normal": list(frame_a[:, 1]), "length": LA,
                       "supports": {"x0": "clamped"}}, rod_b]
    config["joints"] = [{"name": "j", "at": ["a:end", "b:end" if reversed_rod else "b:start"]}]
    y = (-offset if reversed_rod else offset) if axis == "y" else 0.0
    z = offset if axis == "z" else 0.0
    config["tendons"] = [{"name": "t", "rod": "b", "offset_y": y, "offset_z": z,
                          "tension": tau}]
    result = fe_beam.run("finger", config)
    assert result["status"] == "converged", result.get("message")
    step = result["steps"][-1]
    stiffness = E * (H * B**3 if axis == "z" else B * H**3) / 12
    kappa = tau * offset / stiffness
    toward = frame_b[:, 2] if axis == "z" else frame_b[:, 1]
    end = (joint + math.sin(kappa * LB) / kappa * frame_b[:, 0]
           + (1 - math.cos(kappa * LB)) / kappa * toward)
    tip = step["tip"]
    error = np.abs(np.array(tip["position"]) - end).max() / LB
    print(f"spatial {axis}, reversed {reversed_rod}: end {error:.2e} of LB, rotation "
          f"{np.linalg.norm(tip['rotation_vector']) / (kappa * LB) - 1:.2e}")
    assert error <= 1e-8
    assert np.linalg.norm(tip["rotation_vector"]) == pytest.approx(kappa * LB, rel=1e-8)
    assert step["rods"]["a"]["tip"] == pytest.approx(joint, abs=1e-12)


@pytest.mark.parametrize("reversed_rod", [False, True])
def test_spatial_chain_tendon_routed_by_formulas_is_the_rod(reversed_rod):
    """A tendon routed by formulas of the rod's own s (offset_y, offset_z) on the second rod
    of a spatial rod split in two (forward, or given from its far end with the formulas of
    its own s and y of the other sign) equals the single rod with the formulas shifted to
    its s: the same tip to round-off; the summary keeps the rod's own formulas."""
    y = "0.002*cos(pi*s/(2*L))"
    z = "-0.003 + 0.002*s/L"
    single = _base(20, "none")
    single["model"]["kinematics"] = "spatial"
    single["beam"] = {"length": LA + LB}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    shifted = {"offset_y": f"0.002*cos(pi*(s - {LA})/(2*{LB}))",
               "offset_z": f"-0.003 + 0.002*(s - {LA})/{LB}"}
    single["tendons"] = [{"name": "t", "entry": LA, "anchor": LA + LB, "tension": 0.4}
                         | shifted]
    split = _base(10, "none")
    split["model"]["kinematics"] = "spatial"
    rod_b = ({"name": "b", "start": [LA + LB, 0.0, 0.0], "direction": [-1.0, 0.0, 0.0],
              "normal": [0.0, -1.0, 0.0], "length": LB, "mesh": {"elements": 12}}
             if reversed_rod else
             {"name": "b", "start": [LA, 0.0, 0.0], "direction": [1.0, 0.0, 0.0],
              "length": LB, "mesh": {"elements": 12}})
    split["rods"] = [
        {"name": "a", "start": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0], "length": LA,
         "supports": {"x0": "clamped"}, "mesh": {"elements": 8}}, rod_b]
    split["joints"] = [{"name": "j", "at": ["a:end", "b:end" if reversed_rod else "b:start"]}]
    own = ({"offset_y": "-0.002*cos(pi*(L - s)/(2*L))", "offset_z": "-0.003 + 0.002*(L - s)/L"}
           if reversed_rod else {"offset_y": y, "offset_z": z})
    split["tendons"] = [{"name": "t", "rod": "b", "tension": 0.4} | own]
    one, two = fe_beam.run("finger", single), fe_beam.run("finger", split)
    assert one["status"] == two["status"] == "converged", two.get("message")
    tip1, tip2 = one["steps"][-1]["tip"], two["steps"][-1]["tip"]
    scale = float(np.linalg.norm(tip1["rotation_vector"]))
    assert scale > 1e-2
    assert tip2["position"] == pytest.approx(tip1["position"], abs=1e-11 * (LA + LB))
    assert tip2["rotation_vector"] == pytest.approx(tip1["rotation_vector"], abs=1e-11 * scale)
    assert two["tendons"][0]["routing"] == own
    assert two["tendons"][0]["rod"] == "b"


def test_spatial_split_rod_with_a_tendon_on_its_second_rod_is_the_rod():
    """The spatial rod (Reissner law, extensible and shearable) with a tendon at a constant
    offset (y, z) from x = LA to the tip, and the rod split at LA with the tendon on the
    second rod: the same tip position and rotation to round-off."""
    single = _base(20, "none")
    single["model"]["kinematics"] = "spatial"
    single["beam"] = {"length": LA + LB}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    tendon = {"name": "t", "offset_y": 0.002, "offset_z": -0.003, "tension": 0.4}
    single["tendons"] = [tendon | {"entry": LA}]
    split = _base(10, "none")
    split["model"]["kinematics"] = "spatial"
    split["rods"] = [
        {"name": "a", "start": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0], "length": LA,
         "supports": {"x0": "clamped"}, "mesh": {"elements": 8}},
        {"name": "b", "start": [LA, 0.0, 0.0], "direction": [1.0, 0.0, 0.0], "length": LB,
         "mesh": {"elements": 12}}]
    split["joints"] = [{"name": "j", "at": ["a:end", "b:start"]}]
    split["tendons"] = [tendon | {"rod": "b"}]
    one, two = fe_beam.run("finger", single), fe_beam.run("finger", split)
    assert one["status"] == two["status"] == "converged", two.get("message")
    tip1, tip2 = one["steps"][-1]["tip"], two["steps"][-1]["tip"]
    scale = float(np.linalg.norm(tip1["rotation_vector"]))
    assert scale > 1e-2
    assert tip2["position"] == pytest.approx(tip1["position"], abs=1e-12 * (LA + LB))
    assert tip2["rotation_vector"] == pytest.approx(tip1["rotation_vector"], abs=1e-12 * scale)


def test_split_finger_pressing_a_disc_is_the_rod():
    """A tendon and an obstacle together (a finger closing on a disc): the rod split at LA
    with the tendon on its second rod presses the disc with the single rod's force, to
    round-off; the tendon's forces are internal and the contact force in the equilibrium
    certificate."""
    tendon = {"name": "t", "offset_base": 0.003, "offset_tip": 0.003, "tension": 3.0}
    disc = [{"shape": "cylinder", "name": "disc", "point": [0.07, 0.026], "radius": 0.02}]
    contact = {"penetration_tolerance": 1e-7}
    single = _base(20, "none")
    single["beam"] = {"length": LA + LB}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    single["tendons"] = [{"name": "t", "path": [[LA, 0.003], [LA + LB, 0.003]], "entry": LA,
                          "tension": 3.0}]
    split = _base(10, "none")
    split["rods"] = [
        {"name": "a", "start": [0.0, 0.0], "direction": [1.0, 0.0], "length": LA,
         "supports": {"x0": "clamped"}, "mesh": {"elements": 8}},
        {"name": "b", "start": [LA, 0.0], "direction": [1.0, 0.0], "length": LB,
         "mesh": {"elements": 12}}]
    split["joints"] = [{"name": "j", "at": ["a:end", "b:start"]}]
    split["tendons"] = [tendon | {"rod": "b"}]
    for config in (single, split):
        config["obstacles"], config["contact"] = disc, contact
    one, two = fe_beam.run("finger", single), fe_beam.run("finger", split)
    assert one["status"] == two["status"] == "converged", two.get("message")
    assert all(c["passed"] for c in two["checks"]), two["checks"]
    force1 = np.array(one["steps"][-1]["contact"][0]["force"])
    force2 = np.array(two["steps"][-1]["contact"][0]["force"])
    assert np.linalg.norm(force1) > 1e-2  # pressed
    assert force2 == pytest.approx(force1, abs=1e-10 * np.linalg.norm(force1))
    tip1, tip2 = one["steps"][-1]["tip"], two["steps"][-1]["tip"]
    for key in ("u", "v", "theta"):
        assert tip2[key] == pytest.approx(tip1[key], abs=1e-10 * abs(tip1["theta"]))


def test_inverse_tip_angle_of_a_chain_finger_is_the_circles_tension():
    """`[inverse] tip_angle` on the turned chain: the tension that turns the chain's end by
    the target is EI theta / (delta LB) (the circle), to the inverse solve's tolerance."""
    delta, target = 0.003, 0.05
    config, _, _ = _turned_chain(delta, 0.5, False)
    config["inverse"] = {"tip_angle": target}
    result = fe_beam.run("finger", config)
    assert result["status"] == "converged", result.get("message")
    assert result["inverse"]["tension"] == pytest.approx(EI * target / (delta * LB), rel=1e-9)

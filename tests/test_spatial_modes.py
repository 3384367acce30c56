"""Modes of the spatial rod (issue 22, item 5): torsion and both bending families against
closed forms computed here, the planar rod's own frequencies, the rigid-body modes, and the
outputs naming each mode's family.

Mass: rho A on d, T(-theta)^T rho diag(I_p, I_y, I_z) T(-theta) on theta with I_p = I_y + I_z
(the polar moment of the section area; the torsional stiffness is G J, J Saint-Venant's).
"""

import csv
import json
import math

import numpy as np
import pytest
from mpi4py import MPI
from tomlio import dump_toml

from fe_beam.analyses.transient import run_modes
from fe_beam.cli import main
from fe_beam.config.transient import parse_modes

E, NU, RHO = 1.0e7, 0.3, 1000.0
G = E / (2 * (1 + NU))
L = 1.0


def config(b, h, x0="clamped", xL="free", elements=24, count=12, kinematics="spatial",
           law="reissner", constraint="none"):
    return {"beam": {"length": L}, "section": {"shape": "rectangle", "b": b, "h": h},
            "material": {"E": E, "nu": NU, "rho": RHO},
            "model": {"kinematics": kinematics, "law": law, "constraint": constraint},
            "mesh": {"elements": elements, "degree": 2}, "supports": {"x0": x0, "xL": xL},
            "modes": {"count": count}}


def modes_of(cfg):
    static, modes = parse_modes(cfg)
    summary = run_modes(static, modes, None, MPI.COMM_WORLD, progress=False)
    return static, summary


def family(summary, kind):
    return [f for f, k in zip(summary["frequencies_hz"], summary["mode_kinds"], strict=True)
            if k == kind]


def properties(static):
    return static.model.section.spatial_properties()


def rectangle_torsion_constant(t, w, terms=200):
    """J of a t x w rectangle (t <= w) by its series (MODEL.md section 8), computed here."""
    series = sum(math.tanh(n * math.pi * w / (2 * t)) / n**5 for n in range(1, 2 * terms, 2))
    return t**3 * w / 3 * (1 - 192 * t / (math.pi**5 * w) * series)


# --- torsion ----
@pytest.mark.parametrize("supports, orders", [(("clamped", "free"), (1, 3, 5)),
                                              (("free", "free"), (2, 4, 6))])
def test_torsional_frequencies(supports, orders):
    """Saint-Venant torsion, G J theta'' = rho I_p theta_tt: clamped-free
    f_n = (n pi / 2L) sqrt(G J / rho I_p) / 2 pi, n odd; free-free the same with n even
    (n pi / L for n = 1, 2, ...: both ends twist-free), after the 6 rigid-body modes.
    Measured (24 P2 elements): 1e-9, 4e-7, 6e-6 relative for the first three."""
    b, h = 0.02, 0.05
    static, summary = modes_of(config(b, h, *supports, count=30))
    p = properties(static)
    assert p.J == pytest.approx(rectangle_torsion_constant(b, h), rel=1e-10)
    speed = math.sqrt(G * p.J / (RHO * (p.Iy + p.Iz)))
    expected = [n * math.pi / (2 * L) * speed / (2 * math.pi) for n in orders]
    found = family(summary, "torsion")
    assert found[:3] == pytest.approx(expected, rel=2e-5)
    assert found[0] == pytest.approx(expected[0], rel=1e-6)
    rigid = 6 if supports == ("free", "free") else 0
    assert summary["rigid_body_modes"] == rigid
    assert summary["mode_kinds"][:rigid] == ["rigid"] * rigid
    assert all(f == 0.0 for f in summary["frequencies_hz"][:rigid])


# --- bending: both families ----
def test_both_bending_families_of_a_slender_cantilever_are_euler_bernoulli():
    """b != h: bending about y (w, I_y = h b^3/12) and about z (v, I_z = b h^3/12) differ;
    each is f = beta_n^2 sqrt(E I / rho A) / (2 pi L^2) to the rotary-inertia and shear effect
    O((n h/L)^2) (L/h = 400; measured -2e-6, -3e-5, -6e-5 at most for n = 1, 2, 3)."""
    b, h = 0.0015, 0.0025
    static, summary = modes_of(config(b, h, count=10, elements=30))
    p = properties(static)
    assert p.Iy == pytest.approx(h * b**3 / 12) and p.Iz == pytest.approx(b * h**3 / 12)
    roots = (1.8751040687, 4.6940911330, 7.8547574382)
    for kind, inertia in (("bending about y", p.Iy), ("bending about z", p.Iz)):
        expected = [r**2 * math.sqrt(E * inertia / (RHO * p.A)) / (2 * math.pi * L**2)
                    for r in roots]
        found = family(summary, kind)[:3]
        assert found == pytest.approx(expected, rel=2e-4), kind
    assert family(summary, "bending about y")[0] < family(summary, "bending about z")[0]


def timoshenko_simply_supported(n, EI, kGA, rhoA, rhoI):
    """The lower root omega of the simply supported Timoshenko beam's mode n (w = W sin kx,
    phi = Phi cos kx): (rhoA w^2 - kGA k^2)(rhoI w^2 - EI k^2 - kGA) = (kGA k)^2."""
    k = n * math.pi / L
    a = rhoA * rhoI
    b = -(rhoA * (EI * k**2 + kGA) + rhoI * kGA * k**2)
    c = kGA * k**2 * (EI * k**2 + kGA) - (kGA * k) ** 2
    return math.sqrt((-b - math.sqrt(b * b - 4 * a * c)) / (2 * a))


def test_stocky_rod_bending_is_timoshenko_in_both_planes():
    """L/h = 8 simply supported (pinned x0, roller xL): both families against the Timoshenko
    frequencies (shear k G A, rotary inertia rho I) computed here; Euler-Bernoulli is off by
    percents there (measured: within 4e-6 of Timoshenko; mode 2 is 3.5 % (y) and 8 % (z) from
    Euler-Bernoulli)."""
    b, h = 0.08, 0.125
    static, summary = modes_of(config(b, h, "pinned", "roller", count=14, elements=30))
    p = properties(static)
    kGA = static.model.options.shear_correction * G * p.A
    for kind, inertia in (("bending about y", p.Iy), ("bending about z", p.Iz)):
        expected = [timoshenko_simply_supported(n, E * inertia, kGA, RHO * p.A, RHO * inertia)
                    / (2 * math.pi) for n in (1, 2)]
        found = family(summary, kind)[:2]
        assert found == pytest.approx(expected, rel=1e-4), kind
        euler = (2 * math.pi / L) ** 2 * math.sqrt(E * inertia / (RHO * p.A)) / (2 * math.pi)
        assert abs(found[1] / euler - 1) > 0.02  # the stocky case is not Euler-Bernoulli


# --- the plane ----
@pytest.mark.parametrize("law", ["reissner", "nonstandard"])
def test_in_plane_family_is_the_planar_rods_spectrum(law):
    """The planar rod's frequencies (bending and axial) are the spatial rod's in-plane ones
    (bending about z, axial) to 1e-8 relative (measured 3e-14 reissner, 2e-11 nonstandard):
    the same discretisation."""
    b, h = 0.03, 0.02
    _, planar = modes_of(config(b, h, kinematics="planar", law=law, count=6))
    _, spatial = modes_of(config(b, h, law=law, count=14))
    in_plane = [f for f, k in zip(spatial["frequencies_hz"], spatial["mode_kinds"], strict=True)
                if k in ("bending about z", "axial")]
    assert len(in_plane) >= 6
    assert in_plane[:6] == pytest.approx(planar["frequencies_hz"], rel=1e-8)
    kinds = [k for k in spatial["mode_kinds"] if k in ("bending about z", "axial")][:6]
    assert kinds == ["bending about z" if k == "bending" else k for k in planar["mode_kinds"]]


def test_prestressed_in_plane_family_is_the_planar_rods():
    """Linearised about a static pre-state (`[modes] prestress = true`: a cantilever bent by
    a tip force, P L^2 / E I_z = 10, theta_0 = theta_0(x) e3): the in-plane modes of
    the spatial rod are the planar rod's about the same state, to 1e-8 relative."""
    b, h = 0.03, 0.02
    changes = {"loads": {"tip_force": [0.0, 2.0], "steps": 8}}
    planar_cfg = config(b, h, kinematics="planar", count=5) | changes
    spatial_cfg = config(b, h, count=12) | changes
    planar_cfg["modes"]["prestress"] = spatial_cfg["modes"]["prestress"] = True
    _, planar = modes_of(planar_cfg)
    _, spatial = modes_of(spatial_cfg)
    assert planar["status"] == spatial["status"] == "completed"
    in_plane = [f for f, k in zip(spatial["frequencies_hz"], spatial["mode_kinds"], strict=True)
                if k in ("bending about z", "axial")]
    assert in_plane[:5] == pytest.approx(planar["frequencies_hz"], rel=1e-8)


def test_curved_free_rod_has_six_rigid_modes():
    """An initially curved rod (a ring arc of curvature 2/m, free-free) starts from its relaxed
    stress-free state: its rigid motions about the curved state (d = e_i x r,
    theta_t = T(theta)^-1 e_i) are the 6 zero modes, the elastic ones positive."""
    cfg = config(0.02, 0.03, "free", "free", count=9)
    cfg["beam"]["initial_curvature"] = [0.0, 0.0, 2.0]
    _, summary = modes_of(cfg)
    assert summary["rigid_body_modes"] == 6
    assert summary["mode_kinds"][:6] == ["rigid"] * 6
    assert min(summary["frequencies_hz"][6:]) > 0.1


# --- outputs ----
def test_modes_command_names_each_family(tmp_path, capsys):
    """fe-beam modes on a spatial rod: exit 0, stdout, summary.json (mode_kinds,
    mode_shares), modes.csv (frequency, kind, shares) and modes.xdmf (the directors and a
    "family" code per mode) name the family of each mode."""
    cfg = config(0.04, 0.05, "free", "free", elements=12, count=20)
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(cfg))
    out = tmp_path / "out"
    assert main(["modes", str(path), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "(torsion)" in printed and "(bending about y)" in printed
    summary = json.loads((out / "summary.json").read_text())
    kinds = summary["mode_kinds"]
    assert kinds[:6] == ["rigid"] * 6
    assert {"torsion", "bending about y", "bending about z"} <= set(kinds)
    for kind, share in zip(kinds[6:], summary["mode_shares"][6:], strict=True):
        assert share[kind] > 0.9  # each elastic mode is (nearly) one family
    rows = list(csv.DictReader((out / "modes.csv").open()))
    assert [r["kind"] for r in rows] == kinds
    assert [float(r["frequency_hz"]) for r in rows] == pytest.approx(summary["frequencies_hz"])
    assert {"torsion_share", "bending_about_y_share", "bending_about_z_share",
            "axial_share"} <= set(rows[0])
    xdmf = (out / "modes.xdmf").read_text()
    assert 'Name="family"' in xdmf and 'Name="d2"' in xdmf
    assert summary["mode_family_codes"]["torsion"] == 3


def test_other_commands_still_refuse_spatial_rods(tmp_path, capsys):
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(config(0.02, 0.05)))
    assert main(["design", str(path), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "dynamic" in err and "modes" in err and err.count("\n") == 1


@pytest.mark.mpi
def test_two_ranks_match_serial():
    if MPI.COMM_WORLD.size == 1:
        pytest.skip("run under mpirun -n 2 to compare a serial and a parallel solve")
    cfg = config(0.02, 0.05, "free", "free", elements=12, count=14)
    static, modes = parse_modes(cfg)
    parallel = run_modes(static, modes, None, MPI.COMM_WORLD, progress=False)
    serial = run_modes(static, modes, None, MPI.COMM_SELF, progress=False)
    assert parallel["mode_kinds"] == serial["mode_kinds"]
    assert parallel["rigid_body_modes"] == serial["rigid_body_modes"] == 6
    assert np.allclose(parallel["frequencies_hz"][6:], serial["frequencies_hz"][6:], rtol=1e-8)



@pytest.mark.parametrize("kinematics, loads, words", [
    ("spatial", {"tip_moment": [0.0, 0.3, 0.2]}, "a dead moment on a spatial rod"),
    ("planar", {"tip_force": [0.0, 0.5], "follower": True}, "a follower tip load"),
])
def test_non_symmetric_note_names_its_cause(kinematics, loads, words):
    """A spatial rod's dead end moment makes the stiffness non-symmetric (its work has no
    potential): the note names that, not "follower loads" (was: "(follower loads)" for a dead
    moment); a planar follower force is still named as such."""
    cfg = config(0.02, 0.01, kinematics=kinematics, elements=6, count=3)
    cfg["loads"] = loads | {"steps": 2}
    cfg["modes"]["prestress"] = True
    _, summary = modes_of(cfg)
    assert summary["status"] == "completed"
    notes = [n for n in summary["notes"] if "not symmetric" in n]
    assert len(notes) == 1 and words in notes[0], summary["notes"]
    if kinematics == "spatial":
        assert "follower" not in notes[0]


@pytest.mark.parametrize("kinematics, direction, inertia, bending", [
    ("planar", (0.0, 1.0), lambda b, h: b * h**3 / 12, "bending"),
    ("spatial", (0.0, 0.0, -1.0), lambda b, h: h * b**3 / 12, "bending about y"),
])
def test_bent_prestate_modes_are_labelled_in_the_section_frame(kinematics, direction, inertia,
                                                                bending):
    """Modes about a cantilever bent by a tip force to a tip angle of 1.215 rad (70 deg;
    P L^2 / EI = 5): the family shares are measured in the pre-state's section frame, so the
    first mode of the bent family is bending (was: "axial", 0.42 of its translation normal
    to the reference axis and 0.58 along x); unloaded the shares are the reference axes'
    (1 for the bending modes) and the first four labels are the same as about the bent
    state."""
    b, h = 0.03, 0.02
    kinds, shares = [], []
    for factor in (0.0, 5.0):
        cfg = config(b, h, kinematics=kinematics, elements=12, count=4)
        cfg["loads"] = {"tip_force": [c * factor * E * inertia(b, h) / L**2 for c in direction],
                        "steps": 10}
        cfg["modes"]["prestress"] = True
        _, summary = modes_of(cfg)
        assert summary["status"] == "completed", summary["message"]
        kinds.append(summary["mode_kinds"][:4])
        shares.append(summary["mode_shares"][:4])
    straight, bent = kinds
    assert bending in bent[:2] and bent == straight, kinds
    first = bent.index(bending)
    assert shares[1][first]["transverse"] > 0.9, shares[1][first]
    if kinematics == "spatial":
        assert shares[1][first][bending] > 0.9
    for kind, share in zip(straight, shares[0], strict=True):
        assert share["transverse"] == pytest.approx(1.0, abs=1e-12), share
        if kinematics == "spatial":
            assert share[kind] == pytest.approx(1.0, abs=1e-12)

"""Spatial chains of rods ([[rods]] with [model] kinematics = "spatial", issue 29) in fe-beam
modes, buckling and dynamic.

References: the same rod without joints (a straight rod split into two rods joined rigidly,
laid along a skew direction with a skew `normal`, is the rod turned by its frame R0) and the
exact transfer-matrix frequencies of `fe_beam.baselines.frame_modes` for the motions of a planar
frame in and out of its plane (Timoshenko bending with rotary inertia, Saint-Venant torsion
with the polar inertia: the spatial Reissner law's linear vibrations)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from mpi4py import MPI
from mpilaunch import mpirun_command

import fe_beam
from fe_beam.baselines import frame_modes

E, NU, RHO = 2.0e7, 0.3, 1000.0
B, H = 0.02, 0.03


def _base(elements: int, b: float = B, h: float = H) -> dict:
    return {
        "section": {"shape": "rectangle", "b": b, "h": h},
        "material": {"E": E, "nu": NU, "rho": RHO},
        "model": {"law": "reissner", "kinematics": "spatial"},
        "mesh": {"elements": elements, "degree": 2},
        "output": {"xdmf": False, "plots": False},
    }


def _frame(direction, normal) -> np.ndarray:
    d1, d2 = np.array(direction, float), np.array(normal, float)
    d1, d2 = d1 / np.linalg.norm(d1), d2 / np.linalg.norm(d2)
    return np.column_stack([d1, d2, np.cross(d1, d2)])


#: a skew frame: d1 along (1, 2, 2)/3, d2 = (2, 1, -2)/3 (not the default normal)
SKEW = _frame([1.0, 2.0, 2.0], [2.0, 1.0, -2.0])
START = np.array([0.3, -0.2, 0.5])


def _single_and_split(table: str | None = None, count: int = 0):
    """A clamped rod of length 1 along x (10 elements) and the same rod along SKEW split into
    rods of 0.4 (4 elements) and 0.6 (6 elements) joined rigidly."""
    single = _base(10)
    single["beam"] = {"length": 1.0}
    single["supports"] = {"x0": "clamped", "xL": "free"}
    split = _base(4)
    split["rods"] = [
        {"name": "a", "start": START.tolist(), "direction": SKEW[:, 0].tolist(),
         "normal": SKEW[:, 1].tolist(), "length": 0.4, "mesh": {"elements": 4},
         "supports": {"x0": "clamped"}},
        {"name": "b", "start": (START + 0.4 * SKEW[:, 0]).tolist(),
         "direction": SKEW[:, 0].tolist(), "normal": SKEW[:, 1].tolist(), "length": 0.6,
         "mesh": {"elements": 6}}]
    split["joints"] = [{"name": "j", "at": ["a:end", "b:start"]}]
    if table:
        single[table] = {"count": count}
        split[table] = {"count": count}
    return single, split


# --- modes -------------------------------------------------------------------------------------
def test_modes_split_skew_rod_is_the_rod():
    """The split rod along SKEW has the single rod's eight frequencies (bending about both
    axes, torsion) and mode kinds: the rotary and polar inertia turn with R0."""
    single, split = _single_and_split("modes", 8)
    one, two = fe_beam.run("modes", single), fe_beam.run("modes", split)
    assert one["status"] == two["status"] == "completed"
    assert one["mode_kinds"] == two["mode_kinds"]
    assert {"bending about y", "bending about z", "torsion"} <= set(one["mode_kinds"])
    f1, f2 = np.array(one["frequencies_hz"]), np.array(two["frequencies_hz"])
    # measured: 3e-11 (the eigensolver's tolerance); without R0 in the inertia: 2e-1
    assert np.max(np.abs(f1 - f2) / f1) <= 1e-9, (f1, f2)


def _torsion_constant(b: float, h: float, terms: int = 20_000) -> float:
    """Saint-Venant's J of the b x h rectangle, its series summed term by term (the package sums
    it to convergence: `fe_beam.model.sections.rectangle_torsion_constant`)."""
    t, w = min(b, h), max(b, h)
    series = sum(math.tanh(n * math.pi * w / (2 * t)) / n**5 for n in range(1, 2 * terms, 2))
    return t**3 * w / 3 * (1 - 192 * t / (math.pi**5 * w) * series)


def _l_frame_members(a, b, sections, moduli):
    """The in-plane and out-of-plane members of the L-frame (column (0, 0) -> (0, a), beam
    (0, a) -> (b, a)), each with its section (b, h) and moduli (E, G): h in the plane."""
    inplane, outplane = [], []
    for (start, angle, length), (bb, hh), (EE, GG) in zip(
            (((0.0, 0.0), math.pi / 2, a), ((0.0, a), 0.0, b)), sections, moduli, strict=True):
        area, Iz, Iy = bb * hh, bb * hh**3 / 12, hh * bb**3 / 12
        inplane.append(frame_modes.Member(start, angle, length, EE * Iz, EE * area, GG * area,
                                          RHO * area, RHO * Iz))
        outplane.append(frame_modes.OutOfPlaneMember(
            start, angle, length, EE * Iy, GG * _torsion_constant(bb, hh), GG * area,
            RHO * area, RHO * Iy, RHO * (Iy + Iz)))
    return inplane, outplane


def _l_frame(elements: int, a: float, b: float, beam_h: float, beam_E: float) -> dict:
    """The clamped L-frame turned in space by SKEW (each member's normal the turned in-plane
    normal e_z x d1), the beam of its own section height and modulus."""
    config = _base(elements, b=0.02, h=0.05) | {"modes": {"count": 8}}
    rods = []
    for name, start, direction, length in (("column", [0, 0, 0], [0, 1, 0], a),
                                           ("beam", [0, a, 0], [1, 0, 0], b)):
        d1 = np.array(direction, float)
        rods.append({"name": name, "start": (SKEW @ np.array(start, float) + START).tolist(),
                     "direction": (SKEW @ d1).tolist(),
                     "normal": (SKEW @ np.cross([0, 0, 1.0], d1)).tolist(), "length": length})
    rods[0]["supports"] = {"x0": "clamped"}
    rods[1]["section"] = {"h": beam_h}
    rods[1]["material"] = {"E": beam_E, "nu": NU}
    config["rods"] = rods
    config["joints"] = [{"name": "corner", "at": ["column:end", "beam:start"]}]
    return config


def test_modes_spatial_l_frame_against_transfer_matrices():
    """A clamped L-frame turned in space (the beam of another section and modulus): the eight
    lowest frequencies, motions in and out of the frame's plane (bending coupled with torsion
    through the corner), against the exact transfer-matrix roots of its members, converging at
    order 4 in the element count."""
    a, b, beam_h, beam_E = 0.8, 0.6, 0.04, 3.0e7
    G = E / (2 * (1 + NU))
    inplane, outplane = _l_frame_members(a, b, [(0.02, 0.05), (0.02, beam_h)],
                                         [(E, G), (beam_E, beam_E / (2 * (1 + NU)))])
    omega_max = 2 * math.pi * 40
    inside = frame_modes.frame_frequencies(inplane, {(0.0, 0.0): "clamped"}, 8, omega_max, 800)
    outside = frame_modes.frame_frequencies(outplane, {(0.0, 0.0): "clamped"}, 8, omega_max,
                                            800)
    reference = np.array(sorted(inside + outside)[:8])
    assert len(reference) == 8 and len(outside) >= 4 and len(inside) >= 3
    errors = []
    for elements in (4, 8):
        summary = fe_beam.run("modes", _l_frame(elements, a, b, beam_h, beam_E))
        assert summary["status"] == "completed"
        assert "torsion" in summary["mode_kinds"]
        errors.append(np.abs(np.array(summary["frequencies_hz"]) - reference) / reference)
    # measured (8 elements per rod): 9.6e-7, 8.6e-7, 5.2e-6, 5.5e-6, 1.5e-4, 3.4e-4, 1.6e-4,
    # 1.3e-3 (4: 1.5e-5 ... 1.9e-2); order 3.90-4.00
    assert np.all(errors[1] < [2e-6, 2e-6, 1e-5, 1e-5, 3e-4, 6e-4, 3e-4, 2e-3]), errors[1]
    orders = np.log2(errors[0] / errors[1])
    assert np.all((orders > 3.5) & (orders < 4.5)), orders


def test_out_of_plane_baseline_is_bending_and_torsion_of_a_cantilever():
    """One out-of-plane member, clamped, turned in the plane: the Euler-Bernoulli cantilever's
    bending roots and the shaft's torsion (k + 1/2) pi sqrt(GJ / rho I_p) / L, to 1e-12; and a
    member split in two is the member (shear and rotary inertia included)."""
    EI, GJ, rho_area, rho_polar, length, angle = 2.0, 1.5, 0.7, 0.01, 1.3, 0.4
    member = frame_modes.OutOfPlaneMember((0.0, 0.0), angle, length, EI, GJ, math.inf,
                                          rho_area, 0.0, rho_polar)
    found = frame_modes.frame_frequencies([member], {(0.0, 0.0): "clamped"}, 4,
                                          2 * math.pi * 10, 1000)
    roots = [1.8751040687119611, 4.694091132974175]
    bending = [r**2 * math.sqrt(EI / rho_area) / length**2 / (2 * math.pi) for r in roots]
    torsion = [(k + 0.5) * math.pi * math.sqrt(GJ / rho_polar) / length / (2 * math.pi)
               for k in range(2)]
    assert found == pytest.approx(sorted(bending + torsion), rel=1e-12)
    c, s = math.cos(angle), math.sin(angle)
    parts = [frame_modes.OutOfPlaneMember((0.0, 0.0), angle, 0.5, EI, GJ, 3.0, rho_area, 0.002,
                                          rho_polar),
             frame_modes.OutOfPlaneMember((0.5 * c, 0.5 * s), angle, length - 0.5, EI, GJ, 3.0,
                                          rho_area, 0.002, rho_polar)]
    whole = [frame_modes.OutOfPlaneMember((0.0, 0.0), angle, length, EI, GJ, 3.0, rho_area,
                                          0.002, rho_polar)]
    clamped, top = {(0.0, 0.0): "clamped"}, 2 * math.pi * 10
    assert frame_modes.frame_frequencies(parts, clamped, 4, top, 1000) == pytest.approx(
        frame_modes.frame_frequencies(whole, clamped, 4, top, 1000), rel=1e-12)


# --- buckling ----------------------------------------------------------------------------------
def test_buckling_split_skew_column_is_the_column():
    """The clamped column under an axial end force, split along SKEW: the single column's
    buckling factors (about both section axes), linearised and confirmed on the path."""
    single, split = _single_and_split("buckling", 3)
    single["loads"] = {"tip_force": [-1.0, 0.0, 0.0]}
    split["rods"][1]["loads"] = {"point_forces": [[0.6, *(-SKEW[:, 0])]]}
    one, two = fe_beam.run("buckling", single), fe_beam.run("buckling", split)
    assert one["status"] == two["status"] == "completed"
    f1, f2 = np.array(one["load_factors"]), np.array(two["load_factors"])
    assert len(f1) == len(f2) == 3
    # measured: 1.3e-10
    assert np.max(np.abs(f1 - f2) / f1) <= 1e-9, (f1, f2)
    l1, l2 = np.array(one["linearised_load_factors"]), np.array(two["linearised_load_factors"])
    assert np.max(np.abs(l1 - l2) / l1) <= 1e-9, (l1, l2)


# --- dynamic -----------------------------------------------------------------------------------
def test_dynamic_split_skew_rod_is_the_rod():
    """A suddenly applied end force and moment (three components each): the split rod along
    SKEW moves as the single rod turned by SKEW, at every step (generalised-alpha)."""
    single, split = _single_and_split()
    force, moment = np.array([0.2, -6.0, 3.0]), np.array([0.1, 0.05, -0.08])
    single["loads"] = {"tip_force": force.tolist(), "tip_moment": moment.tolist()}
    split["rods"][1]["loads"] = {"point_forces": [[0.6, *(SKEW @ force)]],
                                 "point_moments": [[0.6, *(SKEW @ moment)]]}
    for config in (single, split):
        config["time"] = {"t_end": 0.02, "dt": 0.01, "scheme": "generalized-alpha"}
    one, two = fe_beam.run("dynamic", single), fe_beam.run("dynamic", split)
    assert one["status"] == two["status"] == "completed"
    assert [h["t"] for h in one["history"]] == [h["t"] for h in two["history"]]
    scale = np.linalg.norm([one["history"][-1]["tip"][k] for k in "uvw"])
    assert scale > 0.02  # a large motion
    for a, b in zip(one["history"], two["history"], strict=True):
        d1 = np.array([a["tip"][k] for k in "uvw"])
        d2 = np.array([b["tip"][k] for k in "uvw"])
        # measured: 4e-16 of the length
        assert np.linalg.norm(SKEW @ d1 - d2) <= 1e-11, (a["t"], d1, d2)
        assert np.abs(SKEW @ np.array(a["tip"]["R"]) - np.array(b["tip"]["R"])).max() <= 1e-11
        for key in ("kinetic", "strain"):
            assert b["energies"][key] == pytest.approx(a["energies"][key], rel=1e-10, abs=1e-14)
        assert b["rods"]["b"]["tip"] == pytest.approx(b["tip"]["position"], abs=1e-12)


def test_dynamic_spatial_chain_writes_its_outputs(tmp_path):
    """fe-beam dynamic of a spatial chain with XDMF and pictures: each step's rods and joints
    (force, moment: 3-vectors), history.csv's rod_<name>_x.._z and joint_<name>_Fx.._Mz, the
    XDMF field rod, and the trajectory picture (it drew the chain's 3D end as a 2D point and
    stopped)."""
    _, split = _single_and_split()
    split["rods"][1]["loads"] = {"point_forces": [[0.6, 0.0, 0.0, -1.0]]}
    split["time"] = {"t_end": 0.02, "dt": 0.01}
    split["output"] = {"xdmf": True, "plots": True}
    summary = fe_beam.run("dynamic", split, tmp_path)
    assert summary["status"] == "completed"
    last = summary["history"][-1]
    assert len(last["joints"]["j"]["force"]) == len(last["joints"]["j"]["moment"]) == 3
    assert abs(last["joints"]["j"]["force"][2]) > 0.1
    lines = (tmp_path / "history.csv").read_text().splitlines()
    header, row = lines[0].split(","), [float(x) for x in lines[-1].split(",")]
    assert row[header.index("joint_j_Mx")] == pytest.approx(last["joints"]["j"]["moment"][0],
                                                            rel=1e-12)
    assert row[header.index("rod_a_z")] == pytest.approx(last["rods"]["a"]["tip"][2], rel=1e-12)
    assert 'Attribute Name="rod"' in (tmp_path / "beam.xdmf").read_text()
    assert (tmp_path / "dynamics.png").exists()


def test_modes_free_spatial_l_frame_rigid_motions():
    """The L-frame turned in space and free: six rigid-body modes at 0 Hz (the rotations
    about the origin through each rod's reference position) and the elastic frequencies of
    the transfer-matrix solution of the free-free frame, in and out of its plane."""
    a, b, beam_h, beam_E = 0.8, 0.6, 0.04, 3.0e7
    G = E / (2 * (1 + NU))
    inplane, outplane = _l_frame_members(a, b, [(0.02, 0.05), (0.02, beam_h)],
                                         [(E, G), (beam_E, beam_E / (2 * (1 + NU)))])
    omega_max = 2 * math.pi * 40
    reference = sorted(frame_modes.frame_frequencies(inplane, {}, 4, omega_max, 800)
                       + frame_modes.frame_frequencies(outplane, {}, 4, omega_max, 800))[:4]
    config = _l_frame(8, a, b, beam_h, beam_E) | {"modes": {"count": 10}}
    config["rods"][0].pop("supports")
    summary = fe_beam.run("modes", config)
    assert summary["status"] == "completed"
    assert summary["rigid_body_modes"] == 6
    assert summary["frequencies_hz"][:6] == [0.0] * 6
    found = np.array(summary["frequencies_hz"][6:])
    errors = np.abs(found - reference) / reference
    # measured: 8.8e-6, 1.5e-4, 2.5e-4, 1.6e-4 (8 elements per rod)
    assert np.max(errors) < 4e-4, (found, reference, errors)


def test_dynamic_spatial_joint_force_is_the_balance_of_the_part_beyond(monkeypatch):
    """The split skew rod under a suddenly applied end force: each step's joint force equals
    the end force minus the momentum rate int rho A a of the part beyond the joint (a free
    body; a the state's acceleration, `end_acceleration`), to round-off."""
    import ufl
    from dolfinx import fem

    from fe_beam.fem import compat
    from fe_beam.fem.mpi import assemble_scalar
    from fe_beam.fem.structure import ChainGeometry

    records = []
    original = ChainGeometry.joints_in_motion

    def recording(self, inertia):
        result = original(self, inertia)
        problem, integrator = self.problem, inertia.__self__
        joint = self.structure.joints_on_chain[0]
        after = fem.Function(self.theta0.function_space)
        dofs = compat.cell_dofs(after.function_space)[: len(self._segment_of_cell), 0]
        after.x.array[dofs] = self._segment_of_cell > joint.segment
        a = ufl.split(integrator._end_a)
        rate = [assemble_scalar(fem.form(after * problem.rho * problem.section_props.A * a[i]
                                         * problem.dx_mass)) for i in range(3)]
        records.append((result[joint.name]["force"], rate))
        return result

    monkeypatch.setattr(ChainGeometry, "joints_in_motion", recording)
    _, split = _single_and_split()
    force = SKEW @ np.array([0.2, -6.0, 3.0])
    split["rods"][1]["loads"] = {"point_forces": [[0.6, *force]],
                                 "point_moments": [[0.6, *(SKEW @ [0.1, 0.05, -0.08])]]}
    split["time"] = {"t_end": 0.02, "dt": 0.005}
    summary = fe_beam.run("dynamic", split)
    assert summary["status"] == "completed"
    assert len(records) == len(summary["history"]) >= 5
    for reported, rate in records:
        # measured: 1e-15 of |P|
        assert np.linalg.norm(np.array(reported) - (force - np.array(rate))) \
            <= 1e-12 * np.linalg.norm(force)
    assert max(np.linalg.norm(rate) for _, rate in records) > 0.3 * np.linalg.norm(force)


@pytest.mark.mpi
@pytest.mark.skipif(mpirun_command(2) is None or MPI.COMM_WORLD.size > 1,
                    reason="needs mpirun (and a serial pytest)")
@pytest.mark.parametrize("command", ["modes", "dynamic"])
def test_two_ranks_give_the_serial_spatial_chain(tmp_path, command):
    """``mpirun -n 2 fe-beam modes | dynamic`` of the split skew rod: one rank's frequencies
    and kinds, or history (end, joints' force and moment)."""
    from test_mpi_errors import fe_beam as fe_beam_job

    _, config = _single_and_split("modes" if command == "modes" else None, 6)
    if command == "dynamic":
        config["rods"][1]["loads"] = {"point_forces": [[0.6, 0.0, 0.0, -1.0]]}
        config["time"] = {"t_end": 0.01, "dt": 0.005}
    alone = fe_beam.run(command, config)
    process, _ = fe_beam_job(tmp_path, config, "--out", str(tmp_path / "two"), command=command)
    assert process.returncode == 0, process.stderr
    together = json.loads((tmp_path / "two" / "summary.json").read_text())
    if command == "modes":
        assert np.allclose(together["frequencies_hz"], alone["frequencies_hz"], rtol=1e-9)
        assert together["mode_kinds"] == alone["mode_kinds"]
        return
    assert len(together["history"]) == len(alone["history"])
    for a, b in zip(alone["history"], together["history"], strict=True):
        assert b["rods"]["b"]["tip"] == pytest.approx(a["rods"]["b"]["tip"], abs=1e-12)
        for key in ("force", "moment"):
            assert b["joints"]["j"][key] == pytest.approx(a["joints"]["j"][key], rel=1e-9,
                                                          abs=1e-12)


def test_dynamic_free_spatial_l_frame_angular_momentum():
    """A free L-frame off the origin set turning rigidly (velocity w x X, the sections' angular
    velocity w): its angular momentum about the origin, int X x rho A (w x X) + R0 rho J R0^T w
    ds (each rod's reference position in the arm, its sections' inertia turned by its frame),
    against a quadrature of the rods' reference lines; linear momentum rho A w x int X; both
    kept by the run (its momentum checks pass)."""
    a, b, start, w = 0.7, 0.5, np.array([0.3, -0.2, 0.1]), np.array([1.0, 2.0, 0.5])
    config = _base(4) | {"time": {"t_end": 0.004, "dt": 0.002}}
    config["rods"] = [
        {"name": "column", "start": start.tolist(), "direction": [0.0, 1.0, 0.0], "length": a},
        {"name": "beam", "start": (start + [0, a, 0]).tolist(), "direction": [1.0, 0.0, 0.0],
         "length": b}]
    config["joints"] = [{"name": "corner", "at": ["column:end", "beam:start"]}]
    X = f"({start[0]} + (x - {a} if x > {a} else 0))"
    Y = f"({start[1]} + (x if x <= {a} else {a}))"
    Z = f"{start[2]}"
    config["initial"] = {"velocity": [f"{w[1]} * {Z} - {w[2]} * {Y}",
                                      f"{w[2]} * {X} - {w[0]} * {Z}",
                                      f"{w[0]} * {Y} - {w[1]} * {X}", *map(str, w)]}
    config["loads"] = {"time_function": "0"}
    summary = fe_beam.run("dynamic", config)
    assert summary["status"] == "completed"
    checks = {c["name"]: c for c in summary["checks"]}
    assert checks["linear_momentum"]["passed"] and checks["angular_momentum"]["passed"]
    rho_area, Iy, Iz = RHO * B * H, H * B**3 / 12, B * H**3 / 12
    J = RHO * np.diag([Iy + Iz, Iy, Iz])
    nodes, weights = np.polynomial.legendre.leggauss(4)
    angular, linear = np.zeros(3), np.zeros(3)
    for origin, d1, length in ((start, np.array([0.0, 1, 0]), a),
                               (start + [0, a, 0], np.array([1.0, 0, 0]), b)):
        R0 = _frame(d1, np.cross([0, 0, 1.0], d1))
        for node, weight in zip(nodes, weights, strict=True):
            point = origin + (node + 1) / 2 * length * d1
            dl = weight * length / 2
            angular += dl * (rho_area * np.cross(point, np.cross(w, point)) + R0 @ J @ R0.T @ w)
            linear += dl * rho_area * np.cross(w, point)
    first = summary["history"][0]["momenta"]
    # measured: 1e-16 relative
    assert [first[f"angular_momentum_{k}"] for k in "xyz"] == pytest.approx(angular, rel=1e-12)
    assert [first[f"momentum_{k}"] for k in "xyz"] == pytest.approx(linear, rel=1e-12)


# --- refine ------------------------------------------------------------------------------------
def test_refine_spatial_l_frame_at_order_four():
    """fe-beam refine of the clamped L-frame pushed out of its plane (large force with in-plane
    parts, Reissner law): every rod's elements doubled (6, 12, 24 in all), the end's observed
    order 4 in u, v, w, and the finest level within its estimated error of the independent
    shooting solution across the corner (`fe_beam.baselines.spatial_frame_shooting`), the
    Richardson extrapolation closer still."""
    from fe_beam.baselines.spatial_frame_shooting import SpatialFrame, solve_spatial_frame

    length = 0.5
    G = E / (2 * (1 + NU))
    EA, GA, GJ = E * B * H, G * B * H, G * _torsion_constant(B, H)
    EIy, EIz = E * H * B**3 / 12, E * B * H**3 / 12
    force = np.array([0.3, -0.5, 2.0]) * EIy / length**2
    reference = solve_spatial_frame(SpatialFrame(
        (_frame([1.0, 0, 0], [0, 1.0, 0]), _frame([0, 1.0, 0], [-1.0, 0, 0])),
        (length, length), (EA, GA, GJ, EIy, EIz), force=tuple(force)))
    expected = np.array(reference[-1][0]) - [length, length, 0.0]
    config = _base(3) | {"loads": {"steps": 6}, "refine": {"levels": 3}}
    config["rods"] = [
        {"name": "a", "start": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0], "length": length,
         "supports": {"x0": "clamped"}},
        {"name": "b", "start": [length, 0.0, 0.0], "direction": [0.0, 1.0, 0.0],
         "length": length, "loads": {"point_forces": [[length, *force]]}}]
    config["joints"] = [{"name": "corner", "at": ["a:end", "b:start"]}]
    summary = fe_beam.run("refine", config)
    assert summary["status"] == "completed"
    assert [level["elements"] for level in summary["levels"]] == [6, 12, 24]
    assert abs(expected[2]) > 0.5 * length  # large
    for name, value in zip(("tip.u", "tip.v", "tip.w"), expected, strict=True):
        analysis = summary["analysis"][name]
        # measured: orders 3.98, 3.90, 3.89
        assert 3.7 < analysis["order"] < 4.3, (name, analysis["order"])
        finest = analysis["levels"][-1]["value"]
        assert abs(finest - value) <= 2 * analysis["error_estimate"], (name, finest, value)
        assert abs(analysis["extrapolated"] - value) < 0.2 * abs(finest - value), name

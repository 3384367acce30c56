"""Tendons routed anywhere in the section (issue 22, items 4 and 6): ``[[tendons]] offset_y`` /
``offset_z`` as numbers or formulas of s and L, their checks (formulas, inside the section,
planar rods refuse a tendon out of the x-y plane), and the 3D solid with cables along them: a
helical tendon on mesh edges that bends the finger out of the x-y plane, a straight tendon at
offset_z that gives the offset_y answer rotated by 90 degrees, 2 ranks = serial."""

import contextlib
import copy
import io
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI
from tomlio import dump_toml

from fe_beam.cli import main
from fe_beam.config.finger import parse_finger
from fe_beam.config.solid import ROUTING_TOLERANCE, parse_solid
from fe_beam.config.transient import parse_dynamic
from fe_beam.errors import ConfigError
from fe_beam.model.solid import polyline_deviation
from fe_beam.model.tendons import Tendon
from fe_beam.timefunctions import parse_profile

L, R_HELIX = 0.1, 0.004
HELIX = {"name": "helix", "offset_y": "0.004*cos(pi*s/(2*L))",
         "offset_z": "0.004*sin(pi*s/(2*L))", "tension": 0.2}
# the chapter's tapered finger, coarse (the sizes of tests/solid/test_solid_driver.py)
SOLID = {
    "beam": {"length": L},
    "section": {"shape": "rectangle", "b": 0.02, "h": 0.02, "h_tip": 0.01},
    "material": {"E": 0.6e6, "nu": 0.45, "rho": 1070.0},
    "loads": {"steps": 2},
    "solid": {"material": "neo-hookean", "mesh_size": 0.01, "order": 2},
    "output": {"xdmf": False, "plots": False},
    "tendons": [HELIX],
}
ROD = {"beam": {"length": L},
       "section": {"shape": "rectangle", "b": 0.02, "h": 0.02, "h_tip": 0.01},
       "material": {"E": 0.6e6, "nu": 0.45}, "mesh": {"elements": 20}}


def with_tendon(base: dict, **tendon) -> dict:
    config = copy.deepcopy(base)
    config["tendons"] = [{"tension": 0.2, **tendon}]
    return config


def run_cli(command: str, folder: Path, config: dict) -> tuple[int, str]:
    """``fe-beam <command>`` in-process: (exit code, stderr)."""
    folder = Path(MPI.COMM_WORLD.bcast(str(folder) if MPI.COMM_WORLD.rank == 0 else None))
    path = folder / "c.toml"
    if MPI.COMM_WORLD.rank == 0:
        folder.mkdir(parents=True, exist_ok=True)
        path.write_text(dump_toml(config))
    MPI.COMM_WORLD.barrier()
    stderr = io.StringIO()
    with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
        code = main([command, str(path), "--out", str(folder / "out"), "--quiet"])
    return code, stderr.getvalue()


# --- (a) configuration ---------------------------------------------------------------------------
BAD_ROUTINGS = [
    ({"offset_y": "0.004*cos(q*s)"}, "#1 offset_y", "unknown name 'q'"),
    ({"offset_z": "0.004*sin(pi*s/(2*M))"}, "#1 offset_z", "unknown name 'M'"),
    ({"offset_y": "__import__('os')"}, "#1 offset_y", "not allowed"),
    ({"offset_y": "0.001/(s - 0.05)"}, "#1 offset_y", "cannot be evaluated at s = 0.05"),
    ({"offset_y": "1e300*exp(s*1e4)"}, "#1 offset_y", "not finite"),
    ({"offset_y": "exp(s*1e5)"}, "#1 offset_y", "math range error"),
    ({"offset_y": "0.004*(", "offset_z": 0.0}, "#1 offset_y", "not a formula"),
    ({"offset_y": 0.011}, "#1 offset_y", "outside the rectangle section"),
    # inside at the base (h = 0.02), outside at the tip (h_tip = 0.01)
    ({"offset_y": "0.008*s/L"}, "#1 offset_y", "outside the rectangle section"),
    ({"offset_z": "0.0101*s/L"}, "#1 offset_z", "outside the rectangle section"),
    ({"offset_y": 0.004, "offset_base": 0.004, "offset_tip": 0.004}, "exactly one of", ""),
    ({"offset_z": 0.004, "path": [[0, 0.004], [0.1, 0.004]]}, "exactly one of", ""),
]


@pytest.mark.parametrize(("tendon", "where", "fragment"), BAD_ROUTINGS)
def test_bad_routings_are_config_errors(tendon, where, fragment):
    for parse, base in ((lambda c: parse_finger(c), ROD), (parse_solid, SOLID)):
        with pytest.raises(ConfigError) as error:
            parse(with_tendon(base, **tendon))
        message = str(error.value)
        assert where in message and fragment in message, message
        assert message.startswith("[[tendons]]"), message


def test_routing_checks_follow_the_section_shape():
    def parse(section, **tendon):
        return parse_finger(with_tendon(ROD | {"section": section}, **tendon),
                            planar_check=False)[0].tendons[0]

    circle = {"shape": "circle", "d": 0.02}
    parse(circle, offset_y=0.007, offset_z=0.007)  # |(y, z)| = 0.0099 < r = 0.01
    with pytest.raises(ConfigError, match="outside the circle section"):
        parse(circle, offset_y=0.0075, offset_z=0.0075)  # inside the bounding square
    tube = {"shape": "tube", "d": 0.02, "t": 0.002}
    parse(tube, offset_y="0.0099*cos(2*pi*s/L)", offset_z="0.0099*sin(2*pi*s/L)")
    with pytest.raises(ConfigError, match="outside the tube section"):
        parse(tube, offset_y="0.0101*cos(2*pi*s/L)", offset_z="0.0101*sin(2*pi*s/L)")
    # T: web 2 mm wide from the bottom up to 16 mm, flange 20 mm wide from 16 to 20 mm; the
    # centroid 15.14 mm above the bottom: the flange spans y = 0.86 .. 4.86 mm about it
    tee = {"shape": "t-section", "b": 0.02, "h": 0.02, "tf": 0.004, "tw": 0.002}
    parse(tee, offset_y=0.003, offset_z=0.009)  # in the flange
    parse(tee, offset_y=-0.01, offset_z=0.0009)  # in the web
    with pytest.raises(ConfigError, match="outside the t-section section"):
        parse(tee, offset_y=-0.005, offset_z=0.002)  # beside the web
    with pytest.raises(ConfigError, match="outside the t-section section"):
        parse(tee, offset_y=0.0055, offset_z=0.0)  # above the flange


def test_planar_rod_refuses_an_out_of_plane_tendon():
    expected = 'needs [model] kinematics = "spatial"'
    for tendon in (HELIX, {"offset_z": 0.003, "tension": 1.0},
                   {"offset_y": 0.003, "offset_z": "0.002*s/L", "tension": 1.0}):
        for parse in (lambda c: parse_finger(c), parse_dynamic):
            config = with_tendon(ROD, **tendon)
            if parse is parse_dynamic:
                config |= {"time": {"t_end": 0.01, "dt": 0.001},
                           "material": ROD["material"] | {"rho": 1000.0}}
            with pytest.raises(ConfigError, match=r"#1 offset_z .*needs \[model\] kinematics"):
                parse(config)
            assert expected in str(pytest.raises(ConfigError, parse, config).value)
    # in the plane: a planar rod takes it (offset_z = 0 given or not)
    for tendon in ({"offset_y": 0.003, "offset_z": 0.0}, {"offset_y": "0.008 - 0.004*s/L"}):
        static, _ = parse_finger(with_tendon(ROD, **tendon))
        assert static.tendons[0].spatial and not static.tendons[0].out_of_plane


def test_planar_rod_takes_an_in_plane_routing():
    """offset_y as a formula on the planar rod: a linear one is offset_base/offset_tip (the
    rod's P1 offset is then exact), a curved one the path through the same mesh vertices; no
    mesh vertex is added for the routing's samples."""
    import fe_beam

    base = ROD | {"loads": {"steps": 3}, "output": {"plots": False, "xdmf": False}}
    curve = "0.006 + 0.002*cos(pi*s/L)"
    nodes = [[x, 0.006 + 0.002 * np.cos(np.pi * x / L)] for x in np.linspace(0, L, 21)]
    pairs = [({"offset_base": 0.008, "offset_tip": 0.004}, {"offset_y": "0.008 - 0.004*s/L"}),
             ({"path": nodes}, {"offset_y": curve, "offset_z": 0.0})]
    for given, routed in pairs:
        a, b = (fe_beam.run("finger", with_tendon(base, **t, tension=1.0)) for t in (given, routed))
        assert a["status"] == b["status"] == "converged" and a["dofs"] == b["dofs"]
        for key in ("u", "v", "theta"):
            assert b["steps"][-1]["tip"][key] == pytest.approx(a["steps"][-1]["tip"][key],
                                                               rel=1e-12)
    assert b["tendons"][0]["routing"] == {"offset_y": curve, "offset_z": 0.0}


def test_config_errors_exit_2_from_the_cli(tmp_path):
    cases = [
        ("finger", with_tendon(ROD, offset_y="0.004*cos(q*s)"), "offset_y"),
        ("finger", with_tendon(ROD, **HELIX), 'needs [model] kinematics = "spatial"'),
        ("solid", with_tendon(SOLID, offset_z=0.0102), "outside the rectangle section"),
        ("solid", with_tendon(SOLID, offset_y="1/(s-0.05)"), "cannot be evaluated"),
        ("compare", with_tendon(SOLID, **HELIX), 'needs [model] kinematics = "spatial"'),
    ]
    for k, (command, config, fragment) in enumerate(cases):
        code, stderr = run_cli(command, tmp_path / str(k), config)
        assert code == 2, stderr
        if MPI.COMM_WORLD.rank == 0:
            lines = stderr.strip().splitlines()
            assert len(lines) == 1 and "Traceback" not in stderr, stderr
            assert fragment in lines[0], (fragment, stderr)


def test_tendon_routing_as_data():
    y, z = (parse_profile(text, {"L": L}) for text in (HELIX["offset_y"], HELIX["offset_z"]))
    helix = Tendon(routing=(y, z), tension=1.0, entry=0.02, name="helix")
    assert helix.spatial and helix.out_of_plane and helix.anchor == L
    x = np.linspace(0.02, L, 7)
    ys, zs = helix.offsets(x)
    assert np.allclose(ys, R_HELIX * np.cos(np.pi * x / (2 * L)), rtol=0, atol=1e-16)
    assert np.allclose(zs, R_HELIX * np.sin(np.pi * x / (2 * L)), rtol=0, atol=1e-16)
    # the planar view (paths): y sampled from entry to anchor
    path = np.array(helix.paths[0])
    assert path[0, 0] == 0.02 and path[-1, 0] == L and len(path) > 100
    planar = Tendon.linear(0.008, 0.004, L, tension=1.0)
    assert not planar.spatial and not planar.out_of_plane
    ys, zs = planar.offsets([0.0, 0.05, 0.1])
    assert ys.tolist() == pytest.approx([0.008, 0.006, 0.004]) and zs.tolist() == [0, 0, 0]


# --- (b), (c), (d) the 3D solid ------------------------------------------------------------------
def helix_curve(xs):
    return np.column_stack([xs, R_HELIX * np.cos(np.pi * xs / (2 * L)),
                            R_HELIX * np.sin(np.pi * xs / (2 * L))])


def test_helical_cable_lies_on_mesh_edges_along_the_helix():
    from fe_beam.fem.solid.geometry import create_finger_mesh

    config = parse_solid(SOLID)
    assert config.rod is None and "kinematics" in config.rod_note
    polyline = config.geometry.tendons[0].array
    tolerance = ROUTING_TOLERANCE * config.sizes.tendon
    curve = helix_curve(np.linspace(0, L, 4001))
    assert polyline_deviation(polyline, curve) <= tolerance
    assert 3 <= len(polyline) <= 65
    # meshing checks that every cable segment is a tetrahedron edge (_check_embedded)
    chain = create_finger_mesh(config.geometry, config.sizes, MPI.COMM_WORLD).tendon_chains[0]
    assert len(chain) > len(polyline)
    assert np.allclose(chain[0], [0, R_HELIX, 0]) and np.allclose(chain[-1], [L, 0, R_HELIX])
    assert np.all(np.diff(chain[:, 0]) > 0)
    # the chain's vertices lie on the polyline, hence within its tolerance of the helix, and
    # the helix is as close to the chain (the chain has every polyline vertex)
    assert polyline_deviation(polyline, chain) < 1e-12
    radius = np.hypot(chain[:, 1], chain[:, 2])
    assert np.abs(radius - R_HELIX).max() <= tolerance
    assert polyline_deviation(chain, curve) <= tolerance * (1 + 1e-9)
    print(f"helix: {len(polyline)} polyline points, {len(chain)} chain vertices, "
          f"curve-to-chain {polyline_deviation(chain, curve):.3g} m "
          f"(tolerance {tolerance:.3g} m = {ROUTING_TOLERANCE} x element size)")


def test_helical_tendon_bends_the_finger_out_of_the_plane():
    from fe_beam.analyses.solid import run_solid

    summary = run_solid(SOLID, None, MPI.COMM_WORLD, progress=False)
    assert summary["status"] == "converged"
    tip = summary["tip"]
    assert tip is summary["steps"][-1]["tip"] or tip == summary["steps"][-1]["tip"]
    print(f"helix, 0.2 N: tip u {tip['u']:.4g}, v {tip['v']:.4g}, w {tip['w']:.4g} m, "
          f"rotation vector {np.round(tip['rotation_vector'], 5).tolist()}")
    # the tendon runs from (y, z) = (r, 0) at the base to (0, r) at the tip: it pulls the tip
    # toward +y (its first half) and +z (its second half): both deflections positive
    assert tip["v"] > 0 and tip["w"] > 0
    assert tip["w"] > 1e-3 * L  # well out of the x-y plane (not mesh noise)
    backbone = summary["steps"][-1]["backbone"]
    assert set(backbone) == {"x", "u", "v", "w"}
    assert backbone["w"][0] == pytest.approx(0.0, abs=1e-12)
    assert backbone["w"][-1] > 0.5 * tip["w"]
    # the tip frame: a rotation; its tangent (first column) tilts toward +y and +z
    R = np.array(tip["R"])
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-12) and np.linalg.det(R) == pytest.approx(1)
    assert R[1, 0] > 0 and R[2, 0] > 0
    assert tip["theta"] == pytest.approx(np.arctan2(R[1, 0], R[0, 0]), abs=1e-12)
    phi = np.array(tip["rotation_vector"])
    assert np.linalg.norm(phi) == pytest.approx(np.arccos((np.trace(R) - 1) / 2), rel=1e-6)
    assert phi[2] > 0 and phi[1] < 0  # about +z (toward +y) and -y (toward +z)
    assert summary["steps"][-1]["max_principal_stretch_bulk"] < 1.01  # small strains


def test_offset_z_is_offset_y_rotated_by_90_degrees():
    """A square section, a straight tendon at y = d or at z = d: the rotation by 90 degrees
    about x (y -> z, z -> -y) maps one onto the other, so (u, v, w) and the rotation vector at
    z = d are (u, -w, v) and Q phi of those at y = d; the meshes differ (the cable is embedded
    in each), the answers to 6e-4 of the deflection at mesh_size = h/2 (2e-4 at h/4)."""
    from fe_beam.analyses.solid import run_solid

    square = copy.deepcopy(SOLID)
    square["section"] = {"shape": "rectangle", "b": 0.02, "h": 0.02}
    runs = {}
    for key in ("offset_y", "offset_z"):
        summary = run_solid(with_tendon(square, **{key: 0.006, "tension": 0.5}), None,
                            MPI.COMM_WORLD, progress=False)
        assert summary["status"] == "converged"
        runs[key] = summary
    a, b = (runs[k]["tip"] for k in ("offset_y", "offset_z"))
    assert runs["offset_y"]["rod"]["status"] != "skipped"  # the planar rod ran beside it
    assert runs["offset_z"]["rod"]["status"] == "skipped"
    scale = a["v"]
    assert scale > 0.01 * L
    rotated = np.array([a["u"], -a["w"], a["v"]])
    difference = np.abs(np.array([b["u"], b["v"], b["w"]]) - rotated) / scale
    Q = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    angle = np.abs(np.array(b["rotation_vector"]) - Q @ np.array(a["rotation_vector"]))
    ba, bb = (runs[k]["steps"][-1]["backbone"] for k in ("offset_y", "offset_z"))
    backbone = max(np.abs(np.subtract(bb["w"], ba["v"])).max(),
                   np.abs(np.add(bb["v"], ba["w"])).max()) / scale
    print(f"swap: tip {difference.tolist()}, backbone {backbone:.3g} of v = {scale:.4g} m; "
          f"rotation vector {angle.max():.3g} rad of {np.linalg.norm(a['rotation_vector']):.4g}")
    assert difference.max() < 2e-3 and backbone < 2e-3
    assert angle.max() < 2e-3 * np.linalg.norm(a["rotation_vector"])


@pytest.mark.mpi
def test_helix_two_ranks_equal_serial():
    if MPI.COMM_WORLD.size == 1:
        pytest.skip("run under mpirun -n 2 to compare a serial and a parallel solve")
    from fe_beam.analyses.solid import run_solid

    parallel = run_solid(SOLID, None, MPI.COMM_WORLD, progress=False)
    serial = run_solid(SOLID, None, MPI.COMM_SELF, progress=False)
    assert parallel["dofs"] == serial["dofs"]
    for a, b in zip(serial["steps"], parallel["steps"], strict=True):
        assert a["load_factor"] == b["load_factor"]
        for key in ("u", "v", "w", "theta"):
            assert a["tip"][key] == pytest.approx(b["tip"][key], rel=1e-8, abs=1e-14)
        assert np.allclose(a["tip"]["R"], b["tip"]["R"], rtol=0, atol=1e-10)
        for key in ("v", "w"):
            assert np.allclose(a["backbone"][key], b["backbone"][key], rtol=0, atol=1e-9)

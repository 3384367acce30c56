"""3D modal analysis of ``fe-beam solid`` (`fe_beam.solvers.solid_modes`, ``[modes]``): a slender
straight bar (the finger geometry with h_tip = h, no tendons) against Timoshenko beam theory
(bending in both planes, solved here from the clamped-free Timoshenko equations), the axial rod
and Saint-Venant torsion (closed forms), convergence under mesh refinement, the CLI run with its
summary, XDMF and table, the u-p formulation, serial vs 2 ranks, and mistakes in [modes]."""

import copy
import json
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
from mpi4py import MPI
from test_solid_driver import assert_usage_error, run_cli, shared_folder

from fe_beam.config.solid import parse_solid

E, NU, RHO = 1.0e6, 0.3, 1000.0
L, B, H = 0.2, 0.015, 0.01  # slender: L / H = 20, L / B = 13.3; B != H: distinct bending planes
BAR = {
    "beam": {"length": L},
    "section": {"shape": "rectangle", "b": B, "h": H},
    "material": {"E": E, "nu": NU, "rho": RHO},
    "mesh": {"elements": 20, "degree": 2},
    "loads": {"steps": 1},
    "solid": {"material": "neo-hookean", "mesh_size": H / 2, "order": 2},
    "output": {"xdmf": False, "plots": False},
    "modes": {"count": 8},
}


def bar(**changes) -> dict:
    config = copy.deepcopy(BAR)
    for dotted, value in changes.items():
        name, key = dotted.split("__")
        config.setdefault(name, {})[key] = value
    return config


# --- independent references ---------------------------------------------------------------------
def shear_coefficient(nu: float) -> float:
    """Cowper's shear coefficient of a rectangle."""
    return 10 * (1 + nu) / (12 + 11 * nu)


def timoshenko_bending_hz(width: float, depth: float) -> float:
    """First clamped-free bending frequency of a Timoshenko beam deflecting along ``depth``:
    the first root of det(Phi(L)[M, Q rows; M0, Q0 columns]) = 0, Phi the transfer matrix of
    w' = psi + Q / (k G A), psi' = M / (E I), M' = -Q - rho I w^2 psi, Q' = -rho A w^2 w from
    the clamp (w = psi = 0) to the free end (M = Q = 0)."""
    G, A, I = E / (2 * (1 + NU)), width * depth, width * depth**3 / 12
    k = shear_coefficient(NU)
    scale = np.diag([1.0, L, L**2 / (E * I), L**3 / (E * I)])  # dimensionless state

    def det(omega: float) -> float:
        system = np.array([[0, 1, 0, 1 / (k * G * A)], [0, 0, 1 / (E * I), 0],
                           [0, -RHO * I * omega**2, 0, -1], [-RHO * A * omega**2, 0, 0, 0]])
        phi = scale @ scipy.linalg.expm(system * L) @ np.linalg.inv(scale)
        return float(np.linalg.det(phi[2:, 2:]))

    unit = math.sqrt(E * I / (RHO * A * L**4))  # Euler-Bernoulli: first root at 1.8751^2
    grid = np.linspace(1.0, 6.0, 200) * unit
    values = [det(w) for w in grid]
    for a, b, fa, fb in zip(grid[:-1], grid[1:], values[:-1], values[1:], strict=True):
        if fa * fb < 0:
            return scipy.optimize.brentq(det, a, b, xtol=1e-13 * b) / (2 * math.pi)
    raise AssertionError("no Timoshenko root found")


def torsion_constant(a: float, b: float) -> float:
    """Saint-Venant torsion constant of an a x b rectangle (series)."""
    a, b = max(a, b), min(a, b)
    series = sum(math.tanh(n * math.pi * a / (2 * b)) / n**5 for n in range(1, 400, 2))
    return a * b**3 * (1 / 3 - 64 / math.pi**5 * b / a * series)


def references() -> dict:
    G = E / (2 * (1 + NU))
    polar = B * H * (B**2 + H**2) / 12
    return {
        "bending_y": timoshenko_bending_hz(B, H),
        "bending_z": timoshenko_bending_hz(H, B),
        "axial": math.sqrt(E / RHO) / (4 * L),
        "torsion": math.sqrt(G * torsion_constant(B, H) / (RHO * polar)) / (4 * L),
    }


def test_references_are_right():
    """The reference formulas themselves: Euler-Bernoulli limit and a known torsion constant."""
    assert torsion_constant(1.0, 1.0) == pytest.approx(0.1406, abs=1e-4)
    assert torsion_constant(2.0, 1.0) == pytest.approx(0.229 * 2, rel=2e-3)
    euler = 1.8751040687**2 * math.sqrt(E * B * H**3 / 12 / (RHO * B * H * L**4)) / (2 * math.pi)
    ratio = references()["bending_y"] / euler
    assert 0.99 < ratio < 1.0  # shear and rotary inertia lower it, a little at L / H = 20


def first_of_each_kind(result) -> dict:
    first = {}
    for frequency, kind in zip(result.frequencies_hz, result.kinds, strict=True):
        first.setdefault(kind, frequency)
    return first


def bar_modes(size: float, comm=MPI.COMM_WORLD, **changes):
    from fe_beam.analyses.solid import SolidRun
    from fe_beam.solvers.solid_modes import solid_natural_frequencies

    config = parse_solid(bar(solid__mesh_size=size, **changes))
    run = SolidRun(config, comm)
    try:
        return solid_natural_frequencies(run.problem, config.modes["count"], config.modes["rho"],
                                         undeformed=True), run.dofs
    finally:
        run.destroy()


def test_straight_bar_matches_timoshenko_and_converges():
    """First bending modes in both planes, first axial and torsional mode within 1 % of beam
    theory on the finer mesh; each frequency decreases under refinement (a conforming Galerkin
    approximation bounds the eigenvalues from above) toward the reference."""
    reference = references()
    errors, frequencies = [], []
    for size in (H / 2, H / 3):
        result, _ = bar_modes(size)
        assert result.notes == [] and result.unstable_count == 0  # symmetric, stable
        first = first_of_each_kind(result)
        assert set(first) == set(reference), result.kinds
        errors.append({k: first[k] / reference[k] - 1 for k in reference})
        frequencies.append(first)
        # labels are clean: each mode's own kind carries most of its kinetic energy
        for kind, share in zip(result.kinds, result.shares, strict=True):
            assert share[kind] > 0.9, (kind, share)
    coarse, fine = errors
    for kind in reference:
        assert abs(fine[kind]) < 0.01, (kind, fine)
        assert frequencies[1][kind] < frequencies[0][kind], kind
        assert abs(fine[kind]) < abs(coarse[kind]), (kind, coarse, fine)
    # the slowest to converge, torsion, visibly so
    assert abs(coarse["torsion"]) > 1.5 * abs(fine["torsion"])


def test_mixed_up_gives_the_same_frequencies():
    """u-p (Taylor-Hood): the pressure is eliminated by the singular mass; the frequencies
    equal the displacement formulation's to the difference of the two discretisations, and no
    spurious (pressure) eigenvalue appears below the physical ones."""
    displacement, _ = bar_modes(H, solid__material="neo-hookean")
    mixed, _ = bar_modes(H, solid__formulation="mixed-up")
    assert mixed.kinds == displacement.kinds
    assert mixed.unstable_count == 0
    assert np.allclose(mixed.frequencies_hz, displacement.frequencies_hz, rtol=5e-3)


def test_undeformed_modes_of_a_loaded_run():
    """about = "undeformed" after a sweep (a tendon under pull-in control, whose tension the
    load factor does not set): the modes of the unloaded bar, and the loaded state is left as
    it was; the loaded state's modes differ."""
    from fe_beam.analyses.solid import SolidRun
    from fe_beam.solvers.solid_modes import solid_natural_frequencies

    config = bar(solid__mesh_size=H, modes__count=3)
    config["tendons"] = [{"name": "t", "offset_base": 0.003, "offset_tip": 0.003,
                          "pull_in": 2e-4}]
    config = parse_solid(config)
    run = SolidRun(config, MPI.COMM_WORLD)
    try:
        fresh = solid_natural_frequencies(run.problem, 3, RHO, undeformed=True)
        run.advance(1.0, config.stepping)
        tip, tension = run.tip(), run.problem.tensions()
        assert tension[0] > 0.01
        undeformed = solid_natural_frequencies(run.problem, 3, RHO, undeformed=True)
        assert run.tip() == tip and run.problem.tensions() == tension
        assert run.problem.load_factor == 1.0
        loaded = solid_natural_frequencies(run.problem, 3, RHO)
    finally:
        run.destroy()
    assert np.allclose(undeformed.frequencies_hz, fresh.frequencies_hz, rtol=1e-9)
    assert loaded.unstable_count == 0
    # the tendon's pull changes the tangent (a tendon along the bar does not soften it like a
    # dead compression: its geometric stiffness pulls the bar back), well beyond round-off
    assert abs(loaded.frequencies_hz[0] / fresh.frequencies_hz[0] - 1) > 1e-4


def test_cli_writes_modes_summary_xdmf_and_table(tmp_path):
    """fe-beam solid with [modes] and an axial tip tension: modes about the loaded state by
    default (the tension stiffens bending: P L^2 / EI = 1.6 raises the first frequency by a
    quarter), the rod's (both laws, prestressed) beside them, modes.xdmf with one time per
    mode, the table on stdout."""
    config = bar(solid__mesh_size=H, modes__count=4, output__xdmf=True)
    config["loads"]["tip_force"] = [0.05, 0.0]
    code, stdout, stderr, out = run_cli("solid", shared_folder(tmp_path), config)
    assert code == 0, stderr
    if MPI.COMM_WORLD.rank != 0:
        return
    modes = json.loads((out / "summary.json").read_text())["modes"]
    assert modes["about"] == "loaded" and modes["load_factor"] == 1.0
    assert modes["notes"] == [] and modes["unstable_count"] == 0
    assert len(modes["frequencies_hz"]) == 4 and modes["frequencies_hz"] == sorted(
        modes["frequencies_hz"])
    assert set(modes["rod_frequencies_hz"]) == {"nonstandard", "reissner"}
    for law in ("nonstandard", "reissner"):
        rod = modes["rod_frequencies_hz"][law]
        assert len(rod) == 4
        matched = modes["rod"][law]["matched_hz"]
        first = modes["kinds"].index("bending_y")
        assert matched[first] == rod[0]  # the rod's first mode is its first bending mode
        # slender bar: rod and solid agree on the first in-plane bending mode within 1 %
        assert modes["rod"][law]["relative_difference"][first] == pytest.approx(
            rod[0] / modes["frequencies_hz"][first] - 1)
        assert abs(modes["rod"][law]["relative_difference"][first]) < 0.01
        assert matched[modes["kinds"].index("bending_z")] is None
    # the loaded state, not the undeformed one: well above the unloaded bar's frequency
    assert modes["frequencies_hz"][modes["kinds"].index("bending_y")] > 1.2 * references()[
        "bending_y"]
    grids = ET.parse(out / "modes.xdmf").getroot().iter("Grid")
    times = [float(t.get("Value")) for g in grids for t in g.findall("Time")]
    assert times == [1.0, 2.0, 3.0, 4.0]
    assert "solid [Hz]" in stdout and "nonstandard [Hz]" in stdout and "reissner" in stdout
    assert f"{modes['frequencies_hz'][0]:.6g}" in stdout


@pytest.mark.parametrize("changes, fragment", [
    ({"modes__count": 0}, "[modes] count"),
    ({"modes__count": -3}, "[modes] count"),
    ({"modes__count": 2.5}, "[modes] count"),
    ({"modes__count": "six"}, "[modes] count"),
    ({"modes__about": "deformed"}, "[modes] about"),
    ({"modes__shift": 1.0}, "shift"),
    ({"material__rho": 0.0}, "[material] rho"),
])
def test_bad_modes_input_exits_2(tmp_path, changes, fragment):
    code, _, stderr, _ = run_cli("solid", shared_folder(tmp_path), bar(**changes))
    assert_usage_error(code, stderr, "solid", fragment)


def test_modes_without_rho_exits_2(tmp_path):
    config = bar()
    del config["material"]["rho"]
    code, _, stderr, _ = run_cli("solid", shared_folder(tmp_path), config)
    assert_usage_error(code, stderr, "solid", "[material] rho")


def test_about_defaults():
    assert parse_solid(bar()).modes["about"] == "undeformed"
    loaded = bar()
    loaded["loads"]["tip_force"] = [0.0, 1e-3]
    assert parse_solid(loaded).modes["about"] == "loaded"
    assert parse_solid(bar(modes__about="loaded")).modes["about"] == "loaded"
    without = bar()
    del without["modes"]
    assert parse_solid(without).modes is None


@pytest.mark.mpi
def test_two_ranks_match_serial():
    if MPI.COMM_WORLD.size == 1:
        pytest.skip("run under mpirun -n 2 to compare a serial and a parallel solve")
    parallel, dofs = bar_modes(H / 2, MPI.COMM_WORLD)
    serial, serial_dofs = bar_modes(H / 2, MPI.COMM_SELF)
    assert dofs == serial_dofs
    assert parallel.kinds == serial.kinds
    assert np.allclose(parallel.frequencies_hz, serial.frequencies_hz, rtol=1e-8)


def test_linear_tetrahedra_get_a_locking_note(tmp_path):
    """order = 1 locks in bending (a coarse P1 bar's first bending frequency came out 1.7x
    Euler-Bernoulli's): the frequencies are reported with a note saying so."""
    config = bar(solid__mesh_size=H, solid__order=1, modes__count=2)
    code, _, stderr, out = run_cli("solid", shared_folder(tmp_path), config)
    assert code == 0, stderr
    if MPI.COMM_WORLD.rank == 0:
        modes = json.loads((out / "summary.json").read_text())["modes"]
        assert any("order = 1" in note and "lock" in note for note in modes["notes"])
        assert modes["frequencies_hz"][0] > references()["bending_z"]

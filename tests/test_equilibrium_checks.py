"""Run-time certificates of statics and modes (issue 28, section 1): the global equilibrium of
every static solve (reactions + loads on the deformed shape + contact = 0, tendons internal),
the stability as an informational check, and the modes' eigenpair residual and M-orthogonality.
Each passes on converged runs and fails (status "failed", exit 3) when broken on purpose."""

import copy
import json

import numpy as np
import pytest
from mpi4py import MPI
from mpilaunch import mpirun_command

import fe_beam
from fe_beam.analyses import certificates, transient
from fe_beam.cli import main
from fe_beam.config import parse_static
from fe_beam.fem import equilibrium
from fe_beam.solvers import modes as modes_solver
from fe_beam.solvers.rod_static import StaticContinuation

BASE = {"beam": {"length": 0.8}, "section": {"shape": "rectangle", "b": 0.015, "h": 0.006},
        "material": {"E": 7e10, "nu": 0.33, "rho": 2700.0},
        "model": {"law": "reissner"}, "mesh": {"elements": 5, "degree": 2},
        "supports": {"x0": "clamped", "xL": "free"},
        "loads": {"tip_force": [4.0, -20.0], "tip_moment": 3.0, "steps": 3},
        "output": {"xdmf": False, "plots": False}}


def spatial(config):
    config = copy.deepcopy(config)
    config["model"]["kinematics"] = "spatial"
    loads = config["loads"]
    for key, extra in (("tip_force", 6.0), ("distributed", -2.0), ("gravity", 3.0)):
        if key in loads:
            loads[key] = list(loads[key]) + [extra]
    if "tip_moment" in loads:
        loads["tip_moment"] = [1.0, -0.5, loads["tip_moment"]]
    if "point_forces" in loads:
        loads["point_forces"] = [list(row) + [2.5] for row in loads["point_forces"]]
    return config


def case(name):
    config = copy.deepcopy(BASE)
    if name == "gravity":
        config["loads"] = {"gravity": [1.0, -9.81], "distributed": [3.0, -15.0],
                           "point_forces": [[0.3, 5.0, -8.0], [0.8, 0.0, 4.0]], "steps": 3}
    elif name == "follower":
        config["loads"] = {"tip_force": [-2.0, -40.0], "follower": True, "steps": 4}
    return config


def checks(summary, name="global_equilibrium"):
    return [c for c in summary.get("checks", []) if c["name"] == name]


@pytest.mark.parametrize("kinematics", ["planar", "spatial"])
@pytest.mark.parametrize("name", ["tip", "gravity", "follower"])
def test_converged_static_runs_balance(name, kinematics):
    config = case(name) if kinematics == "planar" else spatial(case(name))
    summary = fe_beam.run("static", config, None)
    assert summary["status"] == "converged"
    (check,) = checks(summary)
    assert check["passed"] and check["tolerance"] == pytest.approx(1e-6)
    assert check["value"] < 1e-9  # orders of magnitude below the tolerance
    if name == "gravity" or (name == "tip" and kinematics == "planar"):  # conservative
        assert checks(summary, "stability")[0]["passed"]


def test_balance_is_plain_statics():
    """Two forces and a couple: the sums and the scales of `balance` by hand."""
    terms = [equilibrium.Wrench("a", np.array([0.0, -2.0, 0.0]),
                                equilibrium.moment_of([1.0, 0.0], [0.0, -2.0])),
             equilibrium.Wrench("b", np.array([0.0, 2.0, 0.0]), np.array([0.0, 0.0, 2.0]))]
    result = equilibrium.balance(terms, 1.0)
    assert result["imbalance"] == 0.0
    terms[1].force = np.array([0.0, 2.02, 0.0])
    result = equilibrium.balance(terms, 1.0)
    assert result["force"] == pytest.approx(0.02 / 2.02) and result["moment"] == 0.0


@pytest.mark.parametrize("kinematics", ["planar", "spatial"])
def test_a_load_off_by_one_percent_fails_with_exit_3(tmp_path, monkeypatch, kinematics):
    from tomlio import dump_toml

    config = case("gravity") if kinematics == "planar" else spatial(case("gravity"))
    original = equilibrium._body

    def scaled(problem, factor):
        return original(problem, 1.01 * factor)

    monkeypatch.setattr(equilibrium, "_body", scaled)
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(config))
    assert main(["static", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 3
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "failed" and "global_equilibrium" in summary["message"]
    assert not checks(summary)[0]["passed"]


def test_newton_stopped_early_fails(tmp_path):
    """PETSc told to stop at a relative residual of 1e-2 (behind the configured rtol's back):
    the imbalance shows and the run is not "converged"."""
    config = case("tip")
    config["solver"] = {"petsc_options": {"snes_rtol": 1e-2, "snes_stol": 1e-2}}
    config["loads"]["steps"] = 1
    summary = fe_beam.run("static", config, None)
    (check,) = checks(summary)
    assert not check["passed"] and check["value"] > 1e-5
    assert summary["status"] == "failed"


def test_lenient_run_keeps_its_status_with_a_note(monkeypatch):
    monkeypatch.setattr(certificates, "equilibrium_tolerance", lambda rtol: 1e-30)
    monkeypatch.setattr(certificates, "roundoff_force", lambda problem: 0.0)
    summary = fe_beam.run("static", case("tip"), None, **{"checks.strict": False})
    assert summary["status"] == "converged" and summary["checks_passed"] is False
    assert any("global_equilibrium" in note for note in summary["notes"])


def test_an_unstable_final_state_is_informational():
    entry = certificates.stability_entry({"stable": False, "energy_decreasing_directions": 2})
    assert entry["passed"] and entry["value"] == 2.0 and "informational" in entry["detail"]
    assert certificates.stability_entry(None) is None


FINGER = {"beam": {"length": 0.09}, "section": {"shape": "rectangle", "b": 0.018, "h": 0.015,
                                                 "h_tip": 0.009},
          "material": {"E": 0.8e6, "nu": 0.45, "rho": 1100.0}, "model": {"law": "nonstandard"},
          "mesh": {"elements": 8, "degree": 2},
          "tendons": [{"name": "t", "offset_base": 0.006, "offset_tip": 0.003, "tension": 1.5}],
          "loads": {"steps": 4, "gravity": [0.0, -9.81]},
          "output": {"xdmf": False, "plots": False}}


def test_finger_with_a_tendon_balances():
    """The sweep's last state and the inverse solve's answer (the tendon's tension sets the
    force scale: a tendon alone loads the rod with no net force)."""
    config = copy.deepcopy(FINGER)
    config["inverse"] = {"tip_angle": 0.2}
    summary = fe_beam.run("finger", config, None)
    assert summary["status"] == "converged" and "inverse" in summary
    sweep, answer = checks(summary)
    assert "inverse" in answer["detail"]
    for check in (sweep, answer):
        assert check["passed"] and check["value"] < 1e-9


@pytest.mark.parametrize("kinematics", ["planar", "spatial"])
def test_prescribed_end_motions_balance_through_their_reactions(kinematics):
    """Both ends held, the end x = L moved and turned: two reactions and gravity (spatial: the
    turned end's rotation rows converted to moments by T^-T)."""
    config = copy.deepcopy(BASE)
    config["loads"] = {"end_displacement": [-0.02, 0.05], "end_rotation": 0.4,
                       "gravity": [0.0, -9.81], "steps": 3}
    if kinematics == "spatial":
        config = spatial(config)
        config["loads"] |= {"end_displacement": [-0.02, 0.05, 0.03],
                            "end_rotation": [0.3, 0.1, 0.4]}
    summary = fe_beam.run("static", config, None)
    assert summary["status"] == "converged"
    (check,) = checks(summary)
    assert check["passed"] and check["value"] < 1e-9


def test_contact_forces_enter_the_balance(monkeypatch):
    config = copy.deepcopy(FINGER)
    config["loads"] = {"steps": 6}
    config["tendons"][0]["tension"] = 3.0
    config["obstacles"] = [{"shape": "plane", "name": "ceiling", "point": [0.0, 0.018],
                            "normal": [0.0, -1.0]}]
    summary = fe_beam.run("finger", config, None)
    assert summary["status"] == "converged"
    force = summary["steps"][-1]["contact"][0]["force"]
    assert abs(force[1]) > 1e-3  # it touches
    (check,) = checks(summary)
    assert check["passed"] and check["value"] < 1e-8, check
    # the contact force left out: a visible imbalance, the run fails
    monkeypatch.setattr(equilibrium, "_contact", lambda entries: [])
    summary = fe_beam.run("finger", config, None)
    assert summary["status"] == "failed" and not checks(summary)[0]["passed"]


def test_path_records_the_balance_of_its_last_point():
    config = copy.deepcopy(BASE)
    config["loads"] = {"tip_force": [0.0, -20.0]}
    config["path"] = {"max_load_factor": 1.0, "arc_length": 0.3, "max_steps": 3}
    summary = fe_beam.run("path", config, None)
    (check,) = checks(summary)
    assert check["passed"] and check["value"] < 1e-7  # the arc-length corrector's tolerance


MODES = {**copy.deepcopy(BASE), "modes": {"count": 5, "prestress": True}}


@pytest.mark.parametrize("kinematics", ["planar", "spatial"])
@pytest.mark.parametrize("x0", ["clamped", "free"])
def test_modes_are_certified(kinematics, x0):
    config = copy.deepcopy(MODES)
    config["supports"]["x0"] = x0
    if x0 == "free":
        config["loads"], config["modes"]["prestress"] = {}, False
    config = spatial(config) if kinematics == "spatial" else config
    summary = fe_beam.run("modes", config, None)
    assert summary["status"] == "completed"
    by_name = {c["name"]: c for c in summary["checks"]}
    assert by_name["eigenpair_residual"]["value"] < 1e-9
    # a symmetric pencil (no follower, no spatial tip moment): M-orthogonal modes
    symmetric = not (kinematics == "spatial" and config["loads"].get("tip_moment"))
    assert ("mode_orthogonality" in by_name) == symmetric
    if symmetric:
        assert by_name["mode_orthogonality"]["value"] < 1e-8
    assert all(c["passed"] for c in summary["checks"])
    assert ("global_equilibrium" in by_name) == (x0 == "clamped")


def test_modes_failing_checks_fail_the_run(tmp_path, monkeypatch):
    from tomlio import dump_toml

    path = tmp_path / "m.toml"
    path.write_text(dump_toml(MODES))
    monkeypatch.setattr(transient, "EIGENPAIR_TOLERANCE", 1e-16)
    assert main(["modes", str(path), "--out", str(tmp_path / "a"), "--quiet"]) == 3
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert summary["status"] == "failed" and "eigenpair_residual" in summary["message"]
    monkeypatch.setattr(transient, "EIGENPAIR_TOLERANCE", 1e-8)
    monkeypatch.setattr(modes_solver, "mass_orthogonality", lambda M, shapes: 1e-3)
    assert main(["modes", str(path), "--out", str(tmp_path / "b"), "--quiet"]) == 3
    summary = json.loads((tmp_path / "b" / "summary.json").read_text())
    assert "mode_orthogonality" in summary["message"]


@pytest.mark.mpi
def test_two_ranks_balance_like_one():
    """Under mpirun -n 2: the reactions and loads of the balance summed over the ranks equal
    the serial ones."""
    parsed = parse_static(spatial(case("gravity")))
    terms = {}
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        run = StaticContinuation(parsed, comm)
        run.advance(1.0, parsed.stepping)
        terms[comm.size] = equilibrium.rod_wrenches(run.problem)
        run.destroy()
    for world, alone in zip(terms[MPI.COMM_WORLD.size], terms[1], strict=True):
        assert world.name == alone.name
        np.testing.assert_allclose(world.force, alone.force, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(world.moment, alone.moment, rtol=1e-9, atol=1e-12)


@pytest.mark.skipif(mpirun_command(2) is None or MPI.COMM_WORLD.size > 1,
                    reason="needs mpirun (and a serial pytest)")
def test_two_rank_job_reports_the_serial_imbalance(tmp_path):
    """``mpirun -n 2 fe-beam static`` of a spatial rod whose Newton is stopped early (a visible
    imbalance): the same global_equilibrium value as one rank, and both exit 3."""
    from test_mpi_errors import fe_beam as fe_beam_job
    from tomlio import dump_toml

    config = spatial(case("gravity"))
    config["solver"] = {"petsc_options": {"snes_rtol": 1e-2, "snes_stol": 1e-2}}
    config["loads"]["steps"] = 1
    (tmp_path / "one").mkdir()
    path = tmp_path / "one" / "c.toml"
    path.write_text(dump_toml(config))
    assert main(["static", str(path), "--out", str(tmp_path / "one" / "out"), "--quiet"]) == 3
    alone = checks(json.loads((tmp_path / "one" / "out" / "summary.json").read_text()))[0]
    process, _ = fe_beam_job(tmp_path, config, "--out", str(tmp_path / "two"))
    assert process.returncode == 3, process.stderr
    together = checks(json.loads((tmp_path / "two" / "summary.json").read_text()))[0]
    assert not alone["passed"] and not together["passed"]
    assert together["value"] == pytest.approx(alone["value"], rel=1e-6)


def test_a_couple_alone_is_measured_against_its_own_scale():
    """A tip moment alone: the reactions' forces are round-off, the force scale is M / L."""
    config = copy.deepcopy(BASE)
    config["loads"] = {"tip_moment": 5.0, "steps": 2}
    summary = fe_beam.run("static", config, None)
    (check,) = checks(summary)
    assert check["passed"] and check["value"] < 1e-9
    terms = [equilibrium.Wrench("couple", np.zeros(3), np.array([0.0, 0.0, 2.0])),
             equilibrium.Wrench("reaction", np.array([1e-15, 0.0, 0.0]),
                                np.array([0.0, 0.0, -2.0]))]
    assert equilibrium.balance(terms, 0.5)["force"] == pytest.approx(1e-15 / 4.0)


def _tiny_load_on_a_stiff_rod(kinematics):
    """A steel round bar (EA = 6.3e7 N, non-standard law) under a tip load of 1e-3 N (2.5e-6
    EI/L^2): the strains are differences of O(1) numbers, so the reactions carry round-off of
    about eps EA = 1.4e-8 N, 1e-5 of the load (measured 3.3e-9 N)."""
    config = copy.deepcopy(BASE)
    config["beam"]["length"] = 2.0
    config["section"] = {"shape": "circle", "d": 0.02}
    config["material"] = {"E": 2e11, "nu": 0.3}
    config["model"] = {"law": "nonstandard"}
    config["mesh"]["elements"] = 3
    config["loads"] = {"tip_force": [0.0, -1e-3], "steps": 1}
    if kinematics == "planar":
        return config
    config = spatial(config)
    config["loads"]["tip_force"] = [0.0, -1e-3, 0.0]
    return config


@pytest.mark.parametrize("kinematics", ["planar", "spatial"])
def test_a_tiny_load_on_a_stiff_rod_is_balanced_to_round_off(kinematics):
    """The certificate allows the reactions' round-off (10 eps EA): a correct linear solve of a
    load far below EA is certified (it failed at 3.3e-6 > 1e-6 before), and the deflection is
    P L^3 / 3 EI + P L / GA."""
    config = _tiny_load_on_a_stiff_rod(kinematics)
    summary = fe_beam.run("static", config, None)
    assert summary["status"] == "converged", summary.get("message")
    (check,) = checks(summary)
    assert check["passed"]
    area, inertia = np.pi * 0.02**2 / 4, np.pi * 0.02**4 / 64
    expected = 1e-3 * 2.0**3 / (3 * 2e11 * inertia) + 1e-3 * 2.0 / (2e11 / 2.6 * area)
    assert summary["steps"][-1]["tip"]["v"] == pytest.approx(-expected, rel=1e-6)


def test_a_tiny_load_off_by_one_percent_still_fails(monkeypatch):
    """The round-off allowance does not hide a wrong load: 1 % of 1e-3 N is 70 times the
    round-off."""
    original = equilibrium._tip

    def scaled(problem, factor):
        return original(problem, 1.01 * factor)

    monkeypatch.setattr(equilibrium, "_tip", scaled)
    summary = fe_beam.run("static", _tiny_load_on_a_stiff_rod("planar"), None)
    (check,) = checks(summary)
    assert summary["status"] == "failed" and not check["passed"]
    # 1 % of the load less the round-off allowance (10 eps EA / P = 1.4e-4)
    assert 0.0097 < check["value"] < 0.01 / 1.01

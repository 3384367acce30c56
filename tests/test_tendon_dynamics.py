"""Tendons in ``fe-beam dynamic`` and ``fe-beam modes`` (issue 12, item 2): the static limit of
a slow tension ramp is the finger's equilibrium, small oscillations about a tendon-loaded state
have the prestressed modal frequency, the tendon's work closes the energy balance, and bad
tendon input is refused with one sentence (exit 2); pull-in control (the tension an unknown)
reaches the finger's equilibrium and balances its work too."""

import copy
import csv
import json
import math

import numpy as np
import pytest
from test_config import dump_toml

from fe_beam.analyses.finger import parse_finger, run_finger
from fe_beam.analyses.transient import parse_dynamic, parse_modes, run_dynamic, run_modes
from fe_beam.cli import main
from fe_beam.solvers.dynamics import period_from_crossings

LENGTH = 0.1
# the chapter's finger (examples/finger.toml) on a coarser mesh
FINGER = {
    "beam": {"length": LENGTH},
    "section": {"shape": "rectangle", "b": 0.02, "h": 0.02, "h_tip": 0.01},
    "material": {"E": 0.6e6, "nu": 0.45, "rho": 1070.0},
    "model": {"law": "nonstandard"},
    "mesh": {"elements": 10, "degree": 2},
    "supports": {"x0": "clamped", "xL": "free"},
    "loads": {"steps": 10},
    "tendons": [{"name": "flexor", "offset_base": 0.008, "offset_tip": 0.004, "tension": 2.0}],
    "output": {"xdmf": False, "plots": False},
}


def finger(**tables):
    config = copy.deepcopy(FINGER)
    for name, values in tables.items():
        config.setdefault(name, {}).update(values)
    return config


def static_tip(config):
    static, _ = parse_finger(copy.deepcopy(config))
    result, _ = run_finger(static, None, progress=False)
    assert result.status == "converged", result.message
    return result.steps[-1]["tip"]


def prestressed_frequencies(config, prestress=True):
    config = copy.deepcopy(config)
    config["modes"] = {"count": 2, "prestress": prestress}
    static, modes = parse_modes(config)
    summary = run_modes(static, modes, None, progress=False)
    assert summary["status"] == "completed"
    return summary["frequencies_hz"]


def test_slow_ramp_reaches_the_finger_equilibrium():
    """A smooth ramp of the tension to 2 N over 0.1 s, then hold, with near-critical viscous
    damping of the first mode (f1 = 8.1 Hz): the transient decays by ~5.7x every 0.05 s, so
    after 0.4 s of hold the tip is the static finger's (fe-beam finger) to < 1e-6 L (measured
    6e-8 L). Half-way (t = 0.1) it is far from it: the run is dynamic."""
    expected = static_tip(FINGER)
    config = finger(damping={"c": 28.0}, time={"t_end": 0.5, "dt": 0.005, "rho_inf": 0.5})
    config["tendons"][0]["time_function"] = "0.5*(1 - cos(pi*t/0.1)) if t < 0.1 else 1"
    result = run_dynamic(parse_dynamic(config), None, progress=False)
    assert result.status == "completed", result.message
    final = result.history[-1]
    assert final["t"] == pytest.approx(0.5)
    assert final["tendons"]["tensions"] == [pytest.approx(2.0, rel=1e-14)]
    error = max(abs(final["tip"]["u"] - expected["u"]), abs(final["tip"]["v"] - expected["v"]),
                LENGTH * abs(final["tip"]["theta"] - expected["theta"]))
    assert error < 1e-6 * LENGTH
    middle = min(result.history, key=lambda h: abs(h["t"] - 0.1))
    assert abs(middle["tip"]["v"] - expected["v"]) > 1e-3 * LENGTH
    assert expected["theta"] > 0.3  # a large bend, not a linear case


def test_small_oscillations_have_the_prestressed_frequency():
    """Reissner law, tension 8 N (tip angle ~ 1 rad): prestress raises f1 from 8.12 to 8.89 Hz.
    Start from the static state at 8 N, lower the tension to 7.96 N: the tip oscillates about
    the 7.96 N state at the first frequency of fe-beam modes (prestress) at 7.96 N, to 0.5%
    (measured -0.09%: the midpoint rule's period elongation (omega dt)^2 / 12 at dt = T/60)."""
    base = finger(model={"law": "reissner"})
    base["tendons"][0]["tension"] = 8.0
    at_rest = prestressed_frequencies(base, prestress=False)[0]
    reference = copy.deepcopy(base)
    reference["tendons"][0]["tension"] = 7.96
    expected, second = prestressed_frequencies(reference)
    assert abs(expected / at_rest - 1) > 0.05  # the prestress matters: the test can tell
    period = 1 / expected
    config = copy.deepcopy(base)
    config["initial"] = {"from_static": True}
    config["time"] = {"t_end": 6.2 * period, "dt": period / 60, "rho_inf": 1.0,
                      "output_every": 1}
    # to 7.96 N linearly over one period of the second mode, which leaves that mode at rest
    config["tendons"][0]["time_table"] = [[0.0, 1.0], [1 / second, 0.995], [1.0, 0.995]]
    result = run_dynamic(parse_dynamic(config), None, progress=False)
    assert result.status == "completed", result.message
    t = np.array([h["t"] for h in result.history])
    theta = np.array([h["tip"]["theta"] for h in result.history])
    assert 0.5 < theta[0] and np.ptp(theta) < 0.05 * theta[0]  # small oscillations, bent state
    # the tip's v: its first-mode content dominates (theta carries much of mode 2)
    v = np.array([h["tip"]["v"] for h in result.history])
    measured = 1 / period_from_crossings(t, v)
    print(f"f1: dynamics {measured:.6g} Hz, modes {expected:.6g} Hz, at rest {at_rest:.6g} Hz")
    assert measured == pytest.approx(expected, rel=5e-3)


def test_tendon_work_closes_the_energy_balance():
    """Tension stepped 0 -> 0.5 -> 1 N (a uniform rod, straight tendon), no damping,
    rho_inf = 1: the balance residual (kinetic + strain - tendon work) is a small fraction of
    the work and falls faster than dt^1.5 (measured 2.3e-3 -> 3e-4 of the work from dt = 2 ms
    to 1 ms; a dead tip moment of the same size: 2.5e-4 -> 5e-5)."""
    config = {
        "beam": {"length": LENGTH},
        "section": {"shape": "rectangle", "b": 0.02, "h": 0.01},
        "material": {"E": 0.6e6, "nu": 0.45, "rho": 1070.0},
        "model": {"law": "nonstandard"},
        "mesh": {"elements": 8, "degree": 2},
        "supports": {"x0": "clamped", "xL": "free"},
        "loads": {"time_function": "0.5*step(t - 0.01) + 0.5*step(t - 0.1)"},
        "tendons": [{"offset_base": 0.003, "offset_tip": 0.003, "tension": 1.0}],
    }
    residuals = []
    for dt in (0.002, 0.001):
        run = copy.deepcopy(config)
        run["time"] = {"t_end": 0.2, "dt": dt, "rho_inf": 1.0}
        result = run_dynamic(parse_dynamic(run), None, progress=False)
        assert result.status == "completed", result.message
        final = result.history[-1]
        energies = final["energies"]
        work = energies["external_work"]
        assert energies["tendon_work"] == work  # the only load
        assert energies["dissipated"] == 0.0
        # the work is of the size tau * pull-in (the tendon shortened by the pull-in)
        assert 0.3 * final["tendons"]["pull_ins"][0] < work < 1.5 * final["tendons"]["pull_ins"][0]
        residuals.append(max(abs(h["energies"]["balance_residual"]) for h in result.history)
                         / work)
    assert residuals[1] < 1e-3
    assert residuals[0] / residuals[1] > 2**1.5


def run_cli(tmp_path, command, config, capsys):
    path = tmp_path / "c.toml"
    path.write_text(dump_toml(config))
    out = tmp_path / "out"
    capsys.readouterr()
    code = main([command, str(path), "--out", str(out), "--quiet"])
    return code, capsys.readouterr().err, out


def test_cli_dynamic_with_tendons_writes_tensions(tmp_path, capsys):
    config = finger(time={"t_end": 0.02, "dt": 0.005}, initial={"from_static": True})
    config["tendons"][0]["time_function"] = "1 + 0.5*t/0.02"
    code, err, out = run_cli(tmp_path, "dynamic", config, capsys)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    first, last = summary["history"][0], summary["history"][-1]
    assert first["tip"] == pytest.approx(static_tip(FINGER), rel=1e-8, abs=1e-12)
    assert last["tendons"]["tensions"] == [pytest.approx(3.0)]
    rows = list(csv.DictReader((out / "history.csv").open()))
    assert float(rows[-1]["tension_0"]) == pytest.approx(3.0)
    assert float(rows[0]["pull_in_0"]) > 0  # the pre-state is already pulled in
    assert math.isclose(float(rows[-1]["pull_in_0"]), last["tendons"]["pull_ins"][0])


@pytest.mark.parametrize("change, words", [
    ({"time_function": "sin(t"}, ["'flexor'", "time_function", "never closed"]),
    ({"time_function": "x + 1"}, ["'flexor'", "time_function", "unknown name 'x'"]),
    ({"time_table": [[0, 1], [0, 2]]}, ["'flexor'", "time_table", "increasing"]),
    ({"tensoin": 2.0}, ["'flexor'", "unknown key 'tensoin'", "time_function"]),
])
@pytest.mark.parametrize("command", ["dynamic", "modes"])
def test_bad_tendon_input_exits_2_with_one_sentence(tmp_path, capsys, change, words, command):
    config = finger(time={"t_end": 0.02, "dt": 0.005})
    config["tendons"][0].update(change)
    config["tendons"][0] = {k: v for k, v in config["tendons"][0].items() if v is not None}
    code, err, _ = run_cli(tmp_path, command, config, capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1, err
    for word in words:
        assert word in err, err
    assert "Traceback" not in err


def test_modes_refuse_pull_in(tmp_path, capsys):
    """A pull-in controlled tendon holds its length: linearising with a fixed tension would give
    wrong frequencies, so fe-beam modes refuses it (fe-beam dynamic solves for the tension)."""
    config = finger(modes={"count": 2, "prestress": True})
    config["tendons"][0] = {**{k: v for k, v in config["tendons"][0].items() if k != "tension"},
                            "pull_in": 0.001}
    code, err, _ = run_cli(tmp_path, "modes", config, capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "'flexor'" in err and "pull_in" in err and "fe-beam modes" in err, err


def pull_in_finger(pull_in=0.003):
    config = copy.deepcopy(FINGER)
    del config["tendons"][0]["tension"]
    config["tendons"][0]["pull_in"] = pull_in
    return config


def test_slow_pull_in_ramp_reaches_the_finger_equilibrium():
    """Pull-in control (the tension an unknown of every step, Newton with the dynamic tangent):
    a smooth ramp of the pull-in to 3 mm, then hold, near-critical damping: the tip and the
    tension at t = 0.5 are fe-beam finger's with that pull-in (measured 1e-11 L, 1e-9 N)."""
    config = pull_in_finger()
    static, _ = parse_finger(copy.deepcopy(config))
    expected = run_finger(static, None, progress=False)[0].steps[-1]
    config["damping"] = {"c": 28.0}
    config["time"] = {"t_end": 0.5, "dt": 0.005, "rho_inf": 0.5}
    config["tendons"][0]["time_function"] = "0.5*(1 - cos(pi*t/0.1)) if t < 0.1 else 1"
    result = run_dynamic(parse_dynamic(config), None, progress=False)
    assert result.status == "completed", result.message
    final = result.history[-1]
    error = max(abs(final["tip"]["u"] - expected["tip"]["u"]),
                abs(final["tip"]["v"] - expected["tip"]["v"]),
                LENGTH * abs(final["tip"]["theta"] - expected["tip"]["theta"]))
    assert error < 1e-6 * LENGTH
    assert final["tendons"]["tensions"][0] == pytest.approx(expected["tensions"][0], rel=1e-6)
    assert expected["tensions"][0] > 1.0  # a real pull
    # the pull-in is prescribed at every step (to the tension Newton's tolerance, 1e-10 L)
    for h in result.history:
        target = 0.003 * (0.5 * (1 - math.cos(math.pi * h["t"] / 0.1)) if h["t"] < 0.1 else 1)
        assert h["tendons"]["pull_ins"][0] == pytest.approx(target, abs=1e-9 * LENGTH)


def test_pull_in_work_closes_the_energy_balance():
    """Pull-in ramped to 3 mm over 0.05 s, no damping, rho_inf = 1: the tendon's work
    -sum tau (l_{n+1} - l_n) with the solved tensions balances kinetic + strain energy to
    second order in dt (measured 5.1e-4 -> 1.3e-4 of the work from dt = 2 ms to 1 ms)."""
    residuals = []
    for dt in (0.002, 0.001):
        config = pull_in_finger()
        config["tendons"][0]["time_function"] = "0.5*(1 - cos(pi*t/0.05)) if t < 0.05 else 1"
        config["time"] = {"t_end": 0.2, "dt": dt, "rho_inf": 1.0}
        result = run_dynamic(parse_dynamic(config), None, progress=False)
        assert result.status == "completed", result.message
        work = result.history[-1]["energies"]["external_work"]
        assert work > 0
        residuals.append(max(abs(h["energies"]["balance_residual"]) for h in result.history)
                         / work)
    assert residuals[1] < 1e-3
    assert residuals[0] / residuals[1] > 2**1.5


def test_fd_scheme_refuses_tendons(tmp_path, capsys):
    config = finger(time={"t_end": 0.02, "dt": 0.005, "scheme": "fd-rk45"})
    code, err, _ = run_cli(tmp_path, "dynamic", config, capsys)
    assert code == 2 and "[[tendons]]" in err and "fd-rk45" in err, err


def test_generalized_alpha_refuses_tendons_with_constraints(tmp_path, capsys):
    """Constraints hold at t_{n+1}, the tendon's axial pull acts at t_{n+1-alpha_f}: measured
    first-order errors (balance residual 15-80% of the work), so the combination is refused;
    fe-beam modes (no time stepping) takes it."""
    config = finger(time={"t_end": 0.02, "dt": 0.005},
                    model={"constraint": "inextensible-unshearable"})
    code, err, _ = run_cli(tmp_path, "dynamic", config, capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "constraint" in err and "[[tendons]]" in err and "rho_inf = 0" in err, err
    config["modes"] = {"count": 2, "prestress": True}
    code, err, out = run_cli(tmp_path, "modes", config, capsys)
    assert code == 0, err


def test_finger_notes_a_tendon_time_function(tmp_path, capsys):
    """fe-beam finger on a dynamics config: the tension applies in full, the time function is
    noted as read by fe-beam dynamic only (not refused, not silently dropped)."""
    config = finger()
    config["tendons"][0]["time_function"] = "min(t, 1)"
    code, err, out = run_cli(tmp_path, "finger", config, capsys)
    assert code == 0, err
    assert "[[tendons]] time_function is read by fe-beam dynamic only" in err, err
    tip = json.loads((out / "summary.json").read_text())["steps"][-1]["tip"]
    assert tip == pytest.approx(static_tip(FINGER), rel=1e-10, abs=1e-14)


def test_constrained_tendon_is_the_equivalent_tip_moment():
    """Inextensible-unshearable rod, straight tendon at constant offset delta: at the Gauss
    points the tendon length is L - delta theta(L), so tau l is the potential of a dead tip
    moment tau delta. With rho_inf = 0 (forces and constraints both at t_{n+1}; allowed) the
    tendon-pulled run and the dead-moment run are the same run: tip histories, work and balance
    residuals agree to round-off (measured 1.5e-13 m), under a stepped tension."""
    base = {
        "beam": {"length": LENGTH},
        "section": {"shape": "rectangle", "b": 0.02, "h": 0.01},
        "material": {"E": 0.6e6, "nu": 0.45, "rho": 1070.0},
        "model": {"law": "nonstandard", "constraint": "inextensible-unshearable"},
        "mesh": {"elements": 8, "degree": 2},
        "supports": {"x0": "clamped", "xL": "free"},
        "loads": {"time_function": "0.5*step(t - 0.01) + 0.5*step(t - 0.1)"},
        "time": {"t_end": 0.2, "dt": 0.002, "rho_inf": 0.0},
    }
    delta, tension = 0.003, 1.0
    pulled = copy.deepcopy(base)
    pulled["tendons"] = [{"offset_base": delta, "offset_tip": delta, "tension": tension}]
    moment = copy.deepcopy(base)
    moment["loads"]["tip_moment"] = tension * delta
    runs = [run_dynamic(parse_dynamic(c), None, progress=False) for c in (pulled, moment)]
    assert all(r.status == "completed" for r in runs)
    assert runs[0].history[-1]["tip"]["theta"] > 0.3
    for a, b in zip(runs[0].history, runs[1].history, strict=True):
        for key in ("u", "v"):
            assert a["tip"][key] == pytest.approx(b["tip"][key], abs=1e-10 * LENGTH)
        assert a["tip"]["theta"] == pytest.approx(b["tip"]["theta"], abs=1e-9)
        for key in ("external_work", "balance_residual", "kinetic", "strain"):
            assert a["energies"][key] == pytest.approx(b["energies"][key], rel=1e-7,
                                                       abs=1e-12), key


@pytest.mark.mpi
def test_tendon_dynamics_parallel_equals_serial():
    """A pull-in and a tension-controlled tendon, from the static pre-state: the same history
    on all ranks (COMM_WORLD) as on one (COMM_SELF)."""
    from mpi4py import MPI

    config = finger(time={"t_end": 0.03, "dt": 0.005}, initial={"from_static": True})
    config["tendons"][0].update({"tension": 1.0, "time_function": "1 + 10*t"})
    config["tendons"].append({"name": "extensor", "offset_base": -0.008, "offset_tip": -0.004,
                              "pull_in": 0.0005, "time_function": "1 - 20*t"})
    runs = [run_dynamic(parse_dynamic(copy.deepcopy(config)), None, comm, progress=False)
            for comm in (MPI.COMM_WORLD, MPI.COMM_SELF)]
    for a, b in zip(runs[0].history, runs[1].history, strict=True):
        for key in ("u", "v", "theta"):
            assert a["tip"][key] == pytest.approx(b["tip"][key], rel=1e-9, abs=1e-14)
        assert a["tendons"]["tensions"] == pytest.approx(b["tendons"]["tensions"], rel=1e-8)
        assert a["energies"]["external_work"] == pytest.approx(b["energies"]["external_work"],
                                                               rel=1e-8, abs=1e-16)


# --- [time] scheme = "energy-conserving": each tendon a potential tau_i(t) l_i in the strains ---
EC = {"scheme": "energy-conserving"}


@pytest.mark.parametrize("constraint", ["none", "inextensible-unshearable"])
def test_energy_conserving_slow_ramp_reaches_the_finger_equilibrium(constraint):
    """As for generalised-alpha: a smooth ramp to 2 N over 0.1 s, then hold, near-critical
    viscous damping of the first mode, and a little Kelvin-Voigt damping for the high modes
    (the scheme has no numerical damping; c does not damp rotary inertia): at t = 0.6 the tip is
    fe-beam finger's (same constraint) to < 1e-6 L (measured 4e-8 L); constraints with tendons
    need no restriction here (forces and constraints at the same step states)."""
    static = finger(model={"constraint": constraint})
    expected = static_tip(static)
    config = finger(damping={"c": 28.0, "kelvin_voigt": 1e-4},
                    time={"t_end": 0.6, "dt": 0.005, **EC},
                    model={"constraint": constraint})
    config["tendons"][0]["time_function"] = "0.5*(1 - cos(pi*t/0.1)) if t < 0.1 else 1"
    result = run_dynamic(parse_dynamic(config), None, progress=False)
    assert result.status == "completed", result.message
    final = result.history[-1]
    assert final["tendons"]["tensions"] == [pytest.approx(2.0, rel=1e-14)]
    error = max(abs(final["tip"]["u"] - expected["u"]), abs(final["tip"]["v"] - expected["v"]),
                LENGTH * abs(final["tip"]["theta"] - expected["theta"]))
    assert error < 1e-6 * LENGTH
    assert expected["theta"] > 0.3
    middle = min(result.history, key=lambda h: abs(h["t"] - 0.1))
    assert abs(middle["tip"]["v"] - expected["v"]) > 1e-3 * LENGTH
    # damped: the energy lost is the dissipated work (exact balance)
    energies = final["energies"]
    assert energies["tendon_work"] == energies["external_work"] > 0
    assert abs(energies["balance_residual"]) < 1e-9 * energies["external_work"]


@pytest.mark.parametrize("constraint", ["none", "inextensible"])
def test_energy_conserving_tendon_work_balances_to_round_off(constraint):
    """No damping. Constant tension from rest (a conservative load): kinetic + strain
    + tau l stays its initial value to 1e-9 (l from the history's pull-ins); a tension stepped
    0 -> 1 -> 2 N at two step sizes: the balance residual is < 1e-9 of the tendon's work
    (generalised-alpha: 1e-3 at best, second order). Under a ramped tension the tip follows
    generalised-alpha's (rho_inf = 1, dt = 0.25 ms) to 1e-3 L at dt = 0.5 ms."""
    model = {"constraint": constraint}
    constant = finger(time={"t_end": 0.15, "dt": 0.003, **EC}, model=model)
    result = run_dynamic(parse_dynamic(constant), None, progress=False)
    assert result.status == "completed", result.message
    tau = constant["tendons"][0]["tension"]
    start = result.history[0]["energies"]
    assert start["kinetic"] == start["strain"] == 0.0
    scale = max(h["energies"]["kinetic"] for h in result.history)
    assert scale > 1e-4  # it swings
    for h in result.history:  # kinetic + strain + tau (l - l0), l0 - l = pull-in
        total = h["energies"]["kinetic"] + h["energies"]["strain"] - tau * h["tendons"][
            "pull_ins"][0]
        assert abs(total) < 1e-9 * scale
        assert h["energies"]["tendon_work"] == pytest.approx(
            tau * h["tendons"]["pull_ins"][0], rel=1e-9, abs=1e-12 * scale)
    for dt in (0.002, 0.001):
        config = finger(time={"t_end": 0.06, "dt": dt, **EC}, model=model)
        config["tendons"][0]["time_function"] = "0.5*step(t - 0.005) + 0.5*step(t - 0.03)"
        result = run_dynamic(parse_dynamic(config), None, progress=False)
        assert result.status == "completed", result.message
        work = result.history[-1]["energies"]["external_work"]
        assert work > 0 and result.history[-1]["tendons"]["tensions"] == [pytest.approx(2.0)]
        assert max(abs(h["energies"]["balance_residual"]) for h in result.history) < 1e-9 * work
    if constraint != "none":
        return
    # the motion itself: a ramped tension, against generalised-alpha at half the step
    # (measured 4.7e-4 L; the scheme's own error at dt/2 is 1.1e-4 L: second order)
    tips = []
    for time_settings in ({"dt": 0.0005, **EC}, {"dt": 0.00025, "rho_inf": 1.0}):
        config = finger(time={"t_end": 0.06, "output_every": 1, **time_settings}, model=model)
        config["tendons"][0]["time_function"] = "min(t/0.01, 1)"
        result = run_dynamic(parse_dynamic(config), None, progress=False)
        assert result.status == "completed", result.message
        tips.append({round(h["t"], 9): h["tip"] for h in result.history})
    common = [t for t in tips[0] if t in tips[1]]
    assert len(common) > 100
    worst = max(max(abs(tips[0][t][k] - tips[1][t][k]) for k in "uv") for t in common)
    assert worst < 1e-3 * LENGTH
    assert max(abs(tips[0][t]["v"]) for t in common) > 0.1 * LENGTH


def test_energy_conserving_cli_from_static_with_tendons(tmp_path, capsys):
    """fe-beam dynamic, energy-conserving, from the static pre-state (solved with the tendon
    energy; the scheme then takes the tendons as strain potentials): the pre-state is the
    scheme's equilibrium (the tip stays the finger's to round-off at constant tension); a
    later rise of the tension moves it; summary.json has rho_inf null (generalised-alpha only)."""
    config = finger(time={"t_end": 0.03, "dt": 0.005, **EC}, initial={"from_static": True})
    config["tendons"][0]["time_function"] = "1 if t < 0.0125 else 1.5"
    code, err, out = run_cli(tmp_path, "dynamic", config, capsys)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scheme"] == "energy-conserving" and summary["rho_inf"] is None
    expected = static_tip(FINGER)
    history = summary["history"]
    for h in history:
        if h["t"] < 0.0125:
            assert h["tip"] == pytest.approx(expected, rel=1e-10, abs=1e-14)
            assert h["energies"]["kinetic"] < 1e-20
    assert abs(history[-1]["tip"]["v"] - expected["v"]) > 1e-4 * LENGTH
    assert history[-1]["tendons"]["tensions"] == [pytest.approx(3.0)]
    assert history[0]["tendons"]["pull_ins"][0] > 0  # the pre-state is already pulled in
    rows = list(csv.DictReader((out / "history.csv").open()))
    assert float(rows[-1]["pull_in_0"]) == pytest.approx(history[-1]["tendons"]["pull_ins"][0])
    config["time"] = {"t_end": 0.01, "dt": 0.005}
    code, err, out = run_cli(tmp_path, "dynamic", config, capsys)
    assert code == 0, err
    assert json.loads((out / "summary.json").read_text())["rho_inf"] == 0.9


def test_energy_conserving_refuses_pull_in(tmp_path, capsys):
    config = pull_in_finger()
    config["time"] = {"t_end": 0.02, "dt": 0.005, **EC}
    code, err, _ = run_cli(tmp_path, "dynamic", config, capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "'flexor'" in err and "pull_in" in err and "energy-conserving" in err, err
    assert "Traceback" not in err


@pytest.mark.mpi
def test_energy_conserving_tendons_parallel_equals_serial():
    """Two tension-controlled tendons with their own time functions, from the static
    pre-state, energy-conserving: the same history on all ranks as on one."""
    from mpi4py import MPI

    config = finger(time={"t_end": 0.03, "dt": 0.005, **EC}, initial={"from_static": True})
    config["tendons"][0].update({"tension": 1.0, "time_function": "1 + 10*t"})
    config["tendons"].append({"name": "extensor", "offset_base": -0.008, "offset_tip": -0.004,
                              "tension": 0.5, "time_function": "1 - 20*t"})
    runs = [run_dynamic(parse_dynamic(copy.deepcopy(config)), None, comm, progress=False)
            for comm in (MPI.COMM_WORLD, MPI.COMM_SELF)]
    assert all(r.status == "completed" for r in runs)
    for a, b in zip(runs[0].history, runs[1].history, strict=True):
        for key in ("u", "v", "theta"):
            assert a["tip"][key] == pytest.approx(b["tip"][key], rel=1e-9, abs=1e-14)
        assert a["tendons"]["pull_ins"] == pytest.approx(b["tendons"]["pull_ins"], rel=1e-9)
        for key in ("external_work", "tendon_work", "balance_residual"):
            assert a["energies"][key] == pytest.approx(b["energies"][key], rel=1e-8, abs=1e-16)
    work = runs[0].history[-1]["energies"]["external_work"]
    assert abs(runs[0].history[-1]["energies"]["balance_residual"]) < 1e-9 * abs(work)


@pytest.mark.parametrize("timing, when", [
    ({"time_function": "sin(40*t)"}, "0.0785"),  # negative from pi/40 on
    ({"time_table": [[0, 1], [0.01, 1], [0.02, -0.5]]}, "0.01"),
])
@pytest.mark.parametrize("scheme", ["generalized-alpha", "energy-conserving"])
def test_tendon_time_function_that_pushes_is_refused(tmp_path, capsys, timing, when, scheme):
    """A cable cannot push: tension * f(t) < 0 inside [0, t_end] is refused up front (exit 2,
    one sentence naming the tendon and the key), as a negative tension is in fe-beam finger
    (it used to run silently as a compressed tendon)."""
    config = finger(time={"t_end": 0.1, "dt": 0.005, "scheme": scheme})
    config["tendons"][0].update(timing)
    code, err, _ = run_cli(tmp_path, "dynamic", config, capsys)
    key = next(iter(timing))
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1, err
    assert "'flexor'" in err and key in err and "negative" in err, err
    assert f"t = {when}" in err, err
    assert "Traceback" not in err


def test_pull_in_step_that_makes_the_tendon_push_is_noted(tmp_path, capsys):
    """A pull-in stepped to 2 mm without damping overshoots: the solved tension becomes
    negative (the cable would have to push). The run completes but says so, once, in the
    summary notes and on stderr; a slow, damped ramp (tension > 0 throughout) has no such note."""
    config = pull_in_finger(0.002)
    config["mesh"]["elements"] = 6
    config["tendons"][0]["time_function"] = "1"
    config["time"] = {"t_end": 0.06, "dt": 0.002, "rho_inf": 0.9}
    code, err, out = run_cli(tmp_path, "dynamic", config, capsys)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    tensions = [h["tendons"]["tensions"][0] for h in summary["history"]]
    first = next(h["t"] for h, v in zip(summary["history"], tensions, strict=True) if v < 0)
    assert min(tensions) < -0.1  # independently: the cable really pushes in this run
    notes = [n for n in summary["notes"] if "'flexor'" in n and "cannot push" in n]
    assert len(notes) == 1, summary["notes"]
    assert f"t = {first:.4g} s" in notes[0]
    assert err.count("cannot push") == 1, err
    config["tendons"][0]["time_function"] = "0.5*(1 - cos(pi*t/0.06))"
    config["damping"] = {"c": 28.0}
    code, err, out = run_cli(tmp_path, "dynamic", config, capsys)
    summary = json.loads((out / "summary.json").read_text())
    assert code == 0 and min(h["tendons"]["tensions"][0] for h in summary["history"]) >= 0
    assert not any("cannot push" in n for n in summary["notes"]) and "cannot push" not in err


@pytest.mark.parametrize("scheme, expected", [
    ("generalized-alpha", 0.7), ("fd-rk45", 0.7), ("fd-dop853", 0.7), ("energy-conserving", None)])
def test_summary_rho_inf_of_every_scheme(scheme, expected):
    """summary.json "rho_inf" is a public key: the fd-* schemes report the configured number as
    they did before the energy-conserving scheme (null only for that new scheme)."""
    from fe_beam.analyses.transient import DynamicResult, _dynamic_summary
    raw = finger(time={"t_end": 0.01, "dt": 0.005, "scheme": scheme, "rho_inf": 0.7})
    config = parse_dynamic({k: v for k, v in raw.items() if k != "tendons"})
    summary = _dynamic_summary(DynamicResult([], {}), config, 0.0)
    assert summary["scheme"] == scheme
    assert summary["rho_inf"] == expected

"""A damped soft strip bending under gravity onto a floor in ``fe-beam dynamic`` with the
default [contact] settings (issue 28, section 3): it lands (a run of impacts along the strip),
comes to rest on the floor with the static contact force, and the energy balance books the
contact's losses as ``contact_dissipated`` (and judges any gain)."""

import pytest

import fe_beam

L, B, H, E, RHO, G = 0.1, 0.01, 0.002, 5e6, 1200.0, 9.81
GAP = 0.005  # floor below the undeformed lower face: the strip lands on its outer fifth


def strip(**tables) -> dict:
    config = {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": B, "h": H},
        "material": {"E": E, "nu": 0.45, "rho": RHO},
        "model": {"law": "reissner"},
        "mesh": {"elements": 8},
        "loads": {"gravity": [0.0, -G]},
        "obstacles": [{"shape": "plane", "name": "floor", "point": [0.0, -H / 2 - GAP],
                       "normal": [0.0, 1.0]}],
        "output": {"xdmf": False, "plots": False},
    }
    return config | tables


DROP = {"time": {"t_end": 1.5, "dt": 0.01}, "damping": {"c": 0.5}}


@pytest.fixture(scope="module")
def drop():
    return fe_beam.run("dynamic", strip(**DROP))


def test_the_strip_lands_and_rests_with_the_static_contact_force(drop):
    static = fe_beam.run("static", strip())
    assert static["status"] == "converged", static["message"]
    assert drop["status"] == "completed", drop["message"]
    at_rest, last = static["steps"][-1]["contact"][0], drop["history"][-1]
    weight = RHO * B * H * L * G
    # the floor carries a share of the weight (the clamp the rest)
    assert 0.1 * weight < at_rest["force"][1] < weight
    energies = last["energies"]
    assert energies["kinetic"] < 1e-6 * energies["strain"]  # at rest
    # the force settles to the static one within what [contact] force_tolerance (1e-3 of the
    # force plus EI / L^2, 0.13 % here) and the last slow rocking allow: measured 1.5e-3 for
    # the mean over the last 0.3 s, 3.9e-3 at the last step
    settled = [h["contact"][0]["force"][1] for h in drop["history"] if h["t"] > 1.2]
    assert sum(settled) / len(settled) == pytest.approx(at_rest["force"][1], rel=3e-3)
    assert last["contact"][0]["force"][1] == pytest.approx(at_rest["force"][1], rel=6e-3)
    assert last["contact"][0]["active"][0][1] == pytest.approx(L)
    assert last["tip"]["v"] == pytest.approx(static["steps"][-1]["tip"]["v"], abs=2e-6)


def test_the_contact_losses_are_booked_and_the_balance_certified(drop):
    last = drop["history"][-1]["energies"]
    check = next(c for c in drop["checks"] if c["name"] == "energy_balance")
    assert check["passed"] and check["value"] < 2e-2
    # the landing dissipates: the impacts' loss is booked (not hidden in the residual) ...
    assert last["contact_dissipated"] > 0.1 * last["external_work"]
    assert last["contact_work"] < -0.9 * last["contact_dissipated"]  # a fixed floor
    # ... and the books close: kinetic + strain + damping = gravity's work + the contact's
    gravity = last["external_work"] - last["contact_work"]
    closed = (last["kinetic"] + last["strain"] + last["dissipated"] - gravity
              - last["contact_work"])
    assert closed == pytest.approx(last["balance_residual"], abs=1e-12 * gravity)
    assert abs(last["balance_residual"]) < 2e-2 * gravity


def test_a_stopped_contact_step_names_what_helps():
    """The message of a step whose contact force does not settle names max_updates and
    force_tolerance (raising the penalty alone did not help the issue's drop)."""
    config = strip(time={"t_end": 0.2, "dt": 0.01, "min_dt": 0.005}, damping={"c": 0.5},
                   contact={"max_updates": 8, "force_tolerance": 1e-12},
                   checks={"strict": False})
    summary = fe_beam.run("dynamic", config)
    assert summary["status"] == "failed"
    message = summary["message"]
    assert "max_updates (now 8)" in message and "force_tolerance (now 1e-12" in message


def bar_falling_flat(speed: float, touch: float, dt: float, rho_inf: float = 1.0) -> dict:
    """A stiff free steel bar (no gravity) falling flat at ``speed`` onto a floor it reaches at
    t = ``touch``."""
    side = 0.008
    return {
        "beam": {"length": 0.15},
        "section": {"shape": "rectangle", "b": side, "h": side},
        "material": {"E": 2e11, "nu": 0.3, "rho": 7850.0},
        "model": {"law": "reissner"},
        "mesh": {"elements": 4},
        "supports": {"x0": "free", "xL": "free"},
        "initial": {"velocity": [0.0, -speed, 0.0]},
        "time": {"t_end": 10 * dt + touch, "dt": dt, "rho_inf": rho_inf, "output_every": 1},
        "obstacles": [{"shape": "plane", "name": "floor",
                       "point": [0.0, -side / 2 - speed * touch], "normal": [0.0, 1.0]}],
        "output": {"xdmf": False, "plots": False},
    }


@pytest.mark.parametrize("fraction", [0.75, 0.1])
def test_an_impact_keeps_the_velocity_2s_minus_1_and_books_the_loss(fraction):
    """The gap enforced at t_{n+1} (rho_inf = 1: gamma / beta = 2): a point touching a fraction
    s of the way through a step leaves it with (2 s - 1) times its velocity; the lost kinetic
    energy is `contact_dissipated` and the balance closes to round-off."""
    speed, dt = 0.5, 1e-3
    summary = fe_beam.run("dynamic", bar_falling_flat(speed, (3 + fraction) * dt, dt))
    assert summary["status"] == "completed", summary["message"]
    mass = 7850.0 * 0.008**2 * 0.15
    first, last = summary["history"][0]["energies"], summary["history"][-1]
    rebound = last["momenta"]["momentum_y"] / mass
    assert rebound == pytest.approx(abs(2 * fraction - 1) * speed, rel=1e-3)
    energies = last["energies"]
    kept = energies["kinetic"] + energies["strain"]
    # the books close: K0 + the contact's work = what is kept (+ R, round-off) ...
    assert first["kinetic"] + energies["contact_work"] == pytest.approx(
        kept + energies["balance_residual"], abs=1e-9 * first["kinetic"])
    # ... and the contact's work is the impact's loss (the release step's force times its
    # increment adds 2e-7 of K0)
    assert energies["contact_dissipated"] == pytest.approx(first["kinetic"] - kept,
                                                           rel=1e-6)
    assert abs(energies["balance_residual"]) < 1e-9 * first["kinetic"]
    check = next(c for c in summary["checks"] if c["name"] == "energy_balance")
    assert check["passed"]


def test_an_impacts_energy_gain_is_still_judged(monkeypatch):
    """rho_inf = 0.9: right after a bounce the generalised-alpha scheme gains energy (the
    impulse in its acceleration history; measured 2.6 % of the kinetic energy at the worst
    step, 0.7 % at the end, here): an impact is exempt from halving, not from the check. The
    run fails with the default tolerance 2e-2 and passes with 5e-2."""
    from fe_beam.solvers.dynamics import StepDriver

    config = bar_falling_flat(0.5, 3.3e-3, 1e-3, rho_inf=0.9)
    failed = fe_beam.run("dynamic", config)
    assert failed["status"] == "failed"
    assert "energy_balance" in failed["message"]
    assert failed["history"][-1]["energies"]["balance_residual"] > 0  # a gain, booked nowhere
    monkeypatch.setattr(StepDriver, "energy_tolerance", 5e-2)
    passed = fe_beam.run("dynamic", config)
    check = next(c for c in passed["checks"] if c["name"] == "energy_balance")
    assert passed["status"] == "completed" and check["passed"]
    assert 0.02 < check["value"] < 0.05

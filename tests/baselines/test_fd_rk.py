"""Verification of the finite-difference + Runge-Kutta reference solver (fe_beam.baselines.fd_rk).

References are external (Mattiasson's elastica table, Euler-Bernoulli frequency equation,
closed-form linear and pure-bending solutions) or exact identities (energy balance, gradients).
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from fe_beam.baselines import fd_rk

REFERENCE = Path("/work/shared/reference")


def _load_json(name):
    path = REFERENCE / name
    if not path.exists():
        pytest.skip(f"reference file {path} not available")
    return json.loads(path.read_text())


def _slender(n, law="reissner", **kw):
    """Unit cantilever, EI = 1, nearly inextensible and unshearable (EA = GA = 1e7 EI/L^2)."""
    return fd_rk.FDBeamParameters(L=1.0, n_intervals=n, EA=1e7, GA=1e7, EI=1.0, law=law, **kw)


def _dynamic(law="reissner", alpha=400.0, n=8, **kw):
    """Coarse, moderately slender beam (L/r = sqrt(alpha)) so explicit RK stays cheap."""
    return fd_rk.FDBeamParameters(
        L=1.0, n_intervals=n, EA=alpha, GA=alpha, EI=1.0, rhoA=1.0, rhoI=1.0 / alpha, law=law, **kw
    )


def _zero(t):
    return 0.0


# ------------------------------------------------------------------------------------------------
# Derivatives of the discrete energy
# ------------------------------------------------------------------------------------------------
def _random_state(params, seed):
    rng = np.random.default_rng(seed)
    x = fd_rk.nodes(params)
    theta = 2.5 * np.sin(1.3 * x) + 0.1 * rng.standard_normal(x.size)  # rotations of ~2.5 rad
    u = 0.4 * (np.cos(theta) - 1.0) * x + 0.05 * rng.standard_normal(x.size)
    v = 0.4 * np.sin(theta) * x + 0.05 * rng.standard_normal(x.size)
    return np.concatenate([u, v, theta])


@pytest.mark.parametrize("law", fd_rk.LAWS)
def test_internal_force_is_gradient_of_strain_energy(law):
    p = fd_rk.FDBeamParameters(
        L=1.7, n_intervals=9, EA=40.0, GA=15.0, EI=2.0, EI3=0.4, EI4=0.3, law=law
    )
    q = _random_state(p, seed=1)
    grad = fd_rk.internal_force(p, q)
    step = 1e-6
    fd = np.array(
        [
            (fd_rk.strain_energy(p, q + step * e) - fd_rk.strain_energy(p, q - step * e))
            / (2 * step)
            for e in np.eye(p.n_dofs)
        ]
    )
    err = np.linalg.norm(grad - fd) / np.linalg.norm(fd)
    print(f"{law}: gradient rel. error {err:.2e}")
    assert err < 1e-6


@pytest.mark.parametrize("law", fd_rk.LAWS)
def test_hessian_is_derivative_of_internal_force(law):
    p = fd_rk.FDBeamParameters(
        L=1.7, n_intervals=9, EA=40.0, GA=15.0, EI=2.0, EI3=-0.4, EI4=0.3, law=law
    )
    q = _random_state(p, seed=2)
    K = fd_rk.hessian(p, q).toarray()
    step = 1e-6
    fd = np.array(
        [
            (fd_rk.internal_force(p, q + step * e) - fd_rk.internal_force(p, q - step * e))
            / (2 * step)
            for e in np.eye(p.n_dofs)
        ]
    )
    err = np.linalg.norm(K - fd) / np.linalg.norm(fd)
    print(f"{law}: Hessian rel. error {err:.2e}")
    assert err < 1e-6
    assert np.allclose(K, K.T, rtol=0, atol=1e-12 * np.abs(K).max())


# ------------------------------------------------------------------------------------------------
# Statics
# ------------------------------------------------------------------------------------------------
def _mattiasson(k):
    ref = _load_json("elastica_tip_load.json")
    i = ref["k"].index(k)
    return np.array([ref["shortening"][i], ref["deflection"][i], ref["rotation"][i]])


def _tip_magnitudes(params):
    """(shortening, deflection, |rotation|) / L for a downward tip load."""
    u, v, th = fd_rk.tip(fd_rk.solve_static(params))
    assert v < 0 and th < 0 and u < 0  # downward load: the tip moves down, toward the clamp
    return np.array([-u, -v, -th]) / np.array([params.L, params.L, 1.0])


@pytest.mark.parametrize("k", [1, 2, 5])
def test_static_cantilever_tip_load_matches_mattiasson_second_order(k):
    expected = _mattiasson(k)
    ns = (25, 50, 100)
    errors = np.array([_tip_magnitudes(_slender(n, Py=-k)) - expected for n in ns])
    orders = np.log2(np.abs(errors[:-1] / errors[1:]))
    print(f"k={k}: errors at N=100 {errors[-1]}, orders {orders.ravel()}")
    assert np.all(np.abs(errors[-1]) < 1e-4)
    assert np.all(np.abs(orders - 2.0) < 0.3)


def test_static_nonstandard_law_slender_rectangle_matches_elastica():
    # rectangle with r^2 = I/A = EI/EA: I3 = 0, I4 = b h^5/80 = (3/20) h^2 I with h^2 = 12 r^2
    EA = 1e7
    p = _slender(100, law="nonstandard", EI4=0.15 * 12.0 / EA, Py=-2.0)
    err = _tip_magnitudes(p) - _mattiasson(2)
    print(f"nonstandard, k=2: errors {err}")
    assert np.all(np.abs(err) < 1e-4)


def test_static_tip_moment_rolls_beam_into_circular_arc():
    phi, L, EI = 1.5 * math.pi, 2.0, 3.0  # phi = M L / EI
    R = L / phi
    exact = np.array([R * math.sin(phi) - L, R * (1 - math.cos(phi))])
    errors = []
    for n in (40, 80):
        p = fd_rk.FDBeamParameters(
            L=L, n_intervals=n, EA=1e6, GA=1e6, EI=EI, law="reissner", M=phi * EI / L
        )
        u, v, th = fd_rk.tip(fd_rk.solve_static(p))
        assert abs(th - phi) < 1e-9  # uniform curvature M/EI is exact on the staggered grid
        errors.append(np.abs(np.array([u, v]) - exact) / L)
    orders = np.log2(errors[0] / errors[1])
    print(f"moment: position errors at N=80 {errors[1]}, orders {orders}")
    assert np.all(errors[1] < (phi / 80) ** 2 / 24)  # midpoint rule on the arc
    assert np.all(np.abs(orders - 2.0) < 0.3)


def test_static_distributed_load_small_deflection_matches_beam_theory():
    q, L, EI = -1e-4, 1.0, 1.0
    p = _slender(50, qy=q)
    _, v, th = fd_rk.tip(fd_rk.solve_static(p, steps=1))
    v_exact, th_exact = q * L**4 / (8 * EI), q * L**3 / (6 * EI)
    print(f"distributed: rel. errors v {v / v_exact - 1:.2e}, theta {th / th_exact - 1:.2e}")
    assert abs(v / v_exact - 1) < 1e-3
    assert abs(th / th_exact - 1) < 1e-3


# ------------------------------------------------------------------------------------------------
# Linear vibration
# ------------------------------------------------------------------------------------------------
def test_linear_frequencies_cantilever_match_euler_bernoulli():
    beta_l = np.array(_load_json("cantilever_frequencies.json")["euler_bernoulli_betaL"][:3])
    EI, rhoA, L = 2.0, 0.5, 1.3
    p = fd_rk.FDBeamParameters(
        L=L,
        n_intervals=100,
        EA=1e7 * EI / L**2,
        GA=1e7 * EI / L**2,
        EI=EI,
        rhoA=rhoA,
        rhoI=1e-9 * rhoA * L**2,
        law="reissner",
    )
    f = fd_rk.linear_frequencies(p, 3)
    f_eb = beta_l**2 * math.sqrt(EI / (rhoA * L**4)) / (2 * math.pi)
    rel = f / f_eb - 1
    print(f"cantilever frequency rel. errors {rel}")
    assert np.all(np.diff(f) > 0)
    assert np.all(np.abs(rel) < 5e-3)


def test_linear_frequencies_pinned_roller_match_simply_supported():
    EI, rhoA, L = 1.0, 1.0, 1.0
    p = fd_rk.FDBeamParameters(
        L=L,
        n_intervals=100,
        EA=1e7,
        GA=1e7,
        EI=EI,
        rhoA=rhoA,
        rhoI=1e-9,
        law="reissner",
        supports="pinned-roller",
    )
    f = fd_rk.linear_frequencies(p, 3)
    f_exact = (np.arange(1, 4) * math.pi) ** 2 * math.sqrt(EI / (rhoA * L**4)) / (2 * math.pi)
    rel = f / f_exact - 1
    print(f"simply supported frequency rel. errors {rel}")
    assert np.all(np.abs(rel) < 5e-3)


# ------------------------------------------------------------------------------------------------
# Dynamics
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("law", fd_rk.LAWS)
def test_undamped_release_conserves_energy(law):
    p = _dynamic(law, Py=-3.0, load_time=_zero)  # static shape under P, released at t = 0
    q0 = fd_rk.solve_static(p)
    period = 1.0 / fd_rk.linear_frequencies(p, 1)[0]
    res = fd_rk.simulate(p, q0, None, 3 * period, method="DOP853", rtol=1e-9, atol=1e-11)
    energy = res.kinetic + res.strain
    drift = np.max(np.abs(energy - energy[0])) / energy[0]
    print(f"{law}: energy drift {drift:.2e}, nfev {res.nfev}, wall {res.wall_time:.2f} s")
    assert res.success
    assert drift < 1e-6
    assert res.kinetic.max() > 0.5 * energy[0]  # it really oscillates (large amplitude)
    assert res.tip_v.max() > 0.5 * abs(fd_rk.tip(q0)[1])
    assert np.all(res.external_work == 0.0)


def test_suddenly_applied_loads_energy_balance():
    p = _dynamic("nonstandard", EI4=1e-3, Py=-1.0, qx=0.3, M=0.5)
    res = fd_rk.simulate(p, None, None, 1.5, method="DOP853", rtol=1e-9, atol=1e-11)
    imbalance = np.max(np.abs(res.energy_balance)) / res.external_work.max()
    print(f"step load: energy imbalance {imbalance:.2e}, nfev {res.nfev}")
    assert res.external_work.max() > 0
    assert imbalance < 1e-6


def test_viscous_damping_log_decrement_first_mode():
    zeta = 0.02
    base = _dynamic("reissner")
    f1, phi = fd_rk.linear_modes(base, 1)
    omega = 2 * math.pi * f1[0]
    c = 2 * zeta * base.rhoA * omega
    p = _dynamic("reissner", c=c)
    mode = phi[0] / fd_rk.tip(phi[0])[1] * 1e-3 * p.L  # first mode, tip amplitude 1e-3 L
    t_d = 2 * math.pi / (omega * math.sqrt(1 - zeta**2))
    t_eval = np.linspace(0.0, 4.2 * t_d, 2001)
    res = fd_rk.simulate(p, mode, None, t_eval[-1], t_eval, method="DOP853", rtol=1e-9, atol=1e-13)
    v, t, dt = res.tip_v, res.t, t_eval[1] - t_eval[0]
    i = np.flatnonzero((v[1:-1] > v[:-2]) & (v[1:-1] >= v[2:])) + 1
    frac = 0.5 * (v[i - 1] - v[i + 1]) / (v[i - 1] - 2 * v[i] + v[i + 1])  # parabolic peak
    t_peak = np.concatenate([[0.0], t[i] + frac * dt])
    v_peak = np.concatenate([[v[0]], v[i] - 0.25 * (v[i - 1] - v[i + 1]) * frac])
    assert t_peak.size >= 5
    slope = np.polyfit(t_peak, np.log(v_peak), 1)[0]
    period = np.mean(np.diff(t_peak))
    delta = -slope * period
    zeta_measured = delta / math.sqrt(4 * math.pi**2 + delta**2)
    # modal damping ratio of the discrete mode (rotary inertia is undamped, ~1 % of its energy)
    m_phi = phi[0] * fd_rk.lumped_damping(p) @ phi[0] / (2 * omega)
    balance = np.max(np.abs(res.energy_balance - res.energy_balance[0])) / res.energy_balance[0]
    print(
        f"zeta measured {zeta_measured:.5f} vs c/(2 rhoA omega) {zeta} "
        f"({zeta_measured / zeta - 1:+.2%}), vs modal {m_phi:.5f} "
        f"({zeta_measured / m_phi - 1:+.2%}); period error {period / t_d - 1:.1e}; "
        f"energy balance {balance:.1e}; nfev {res.nfev}"
    )
    assert abs(zeta_measured / zeta - 1) < 0.03
    assert abs(zeta_measured / m_phi - 1) < 0.003
    assert abs(period / t_d - 1) < 1e-3
    assert balance < 1e-6


# ------------------------------------------------------------------------------------------------
# Parameter validation
# ------------------------------------------------------------------------------------------------
GOOD = dict(L=1.0, n_intervals=10, EA=1.0, GA=1.0, EI=1.0)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("L", 0.0),
        ("n_intervals", 1),
        ("n_intervals", 10.0),
        ("EA", 0.0),
        ("EA", -1.0),
        ("GA", float("nan")),
        ("EI", -2.0),
        ("EI4", -1.0),
        ("rhoA", -1.0),
        ("rhoI", -1.0),
        ("c", -0.1),
        ("Py", float("inf")),
        ("law", "hookean"),
        ("supports", "clamped-clamped"),
        ("load_time", 3.0),
    ],
)
def test_bad_parameters_raise_value_error_naming_the_field(field, value):
    with pytest.raises(ValueError, match=rf"\b{field}\b"):
        fd_rk.FDBeamParameters(**{**GOOD, field: value})


def test_dynamics_requires_positive_inertia():
    p = fd_rk.FDBeamParameters(**GOOD, rhoA=1.0)
    with pytest.raises(ValueError, match="rhoI"):
        fd_rk.simulate(p, None, None, 1.0)
    with pytest.raises(ValueError, match="rhoI"):
        fd_rk.linear_frequencies(p, 1)

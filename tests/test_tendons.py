"""Verification of the tendon-driven finger (reduced Cosserat model, MODEL.md section 2)."""

import json
from dataclasses import replace

import numpy as np
import pytest
import ufl
from beam_cases import NU, E, square
from dolfinx import fem
from mpi4py import MPI

from fe_beam import BeamModel, BeamProblem, Discretisation, LoadStepping, Material, ModelOptions
from fe_beam.analyses.finger import parse_finger
from fe_beam.analyses.static import solve_static
from fe_beam.baselines.shooting import default_finger, solve_finger
from fe_beam.fem.tendons import Tendon, TendonSet, looped_tendon
from fe_beam.model.studies import StaticConfig

LENGTH, H = 0.1, 0.01
EI = E * H**4 / 12


def uniform_rod(law="reissner", constraint="inextensible-unshearable", elements=10, degree=2):
    return BeamModel(
        LENGTH,
        square(H),
        Material(E, nu=NU),
        ModelOptions(law, constraint),
        Discretisation(elements, degree),
    )


def run(model, tendons, steps=5, comm=MPI.COMM_WORLD):
    config = StaticConfig(model, stepping=LoadStepping(steps=steps), tendons=tuple(tendons))
    result = solve_static(config, None, comm, progress=False)
    assert result.status == "converged", result.message
    return result


@pytest.mark.parametrize("degree", [1, 2])
@pytest.mark.parametrize("law", ["reissner", "nonstandard"])
def test_constant_offset_gives_uniform_curvature(degree, law):
    """Inextensible-unshearable, uniform section: EI kappa = tau delta at every tension (the
    non-standard law: EI kappa + E I4 kappa^3 / 2 = tau delta, MODEL.md section 6)."""
    delta, tension = 0.003, 20.0
    result = run(
        uniform_rod(law, degree=degree), [Tendon.linear(delta, delta, LENGTH, tension=tension)]
    )
    ei4 = E * H * H**5 / 80 if law == "nonstandard" else 0.0
    for step in result.steps:
        moment = step["tensions"][0] * delta
        kappa = step["tip"]["theta"] / LENGTH
        assert EI * kappa + ei4 * kappa**3 / 2 == pytest.approx(moment, rel=1e-8)
    if MPI.COMM_WORLD.rank == 0:
        kappa_cells = result.shapes[-1][1]["cells"]["kappa"]
        assert np.ptp(kappa_cells) < 1e-8 * np.abs(kappa_cells).max()
    assert result.steps[-1]["tip"]["theta"] > 0  # positive offset bends toward +y


@pytest.fixture(scope="module")
def chapter_reference():
    """The chapter's finger by the independent shooting solver, with our definitions
    (curvature per reference length, extensible, unshearable)."""
    return {
        tau: solve_finger(default_finger(tension=tau, curvature="reference"))
        for tau in (0.5, 2.0, 5.0)
    }


def finger_config(elements=10, degree=2, **tendon):
    tendon = {"offset_base": 0.008, "offset_tip": 0.004, "tension": 5.0} | tendon
    tendon = {key: value for key, value in tendon.items() if value is not None}
    config, _ = parse_finger(
        {
            "model": {"law": "reissner", "constraint": "unshearable"},
            "mesh": {"elements": elements, "degree": degree},
            "loads": {"steps": 10},
            "tendons": [tendon],
        }
    )
    return config


def tip_errors(result, reference):
    errors = []
    for step in result.steps:
        for tension, solution in reference.items():
            if abs(step["tensions"][0] - tension) < 1e-9:
                errors.append(
                    max(
                        abs(step["tip"]["u"] - solution.tip_u),
                        abs(step["tip"]["v"] - solution.tip_v),
                    )
                    / LENGTH
                )
    assert len(errors) == len(reference)
    return errors


def test_chapter_finger_matches_shooting_reference(chapter_reference):
    result = solve_static(finger_config(), None, progress=False)
    assert max(tip_errors(result, chapter_reference)) < 1e-4


@pytest.mark.parametrize("degree, order", [(1, 2), (2, 4)])
def test_tip_converges_with_theoretical_order(chapter_reference, degree, order):
    errors = [
        max(
            tip_errors(
                solve_static(finger_config(n, degree), None, progress=False), chapter_reference
            )
        )
        for n in (5, 10, 20)
    ]
    rates = -np.diff(np.log(errors)) / np.log(2)
    assert rates == pytest.approx([order, order], abs=0.2)


def test_pull_in_control_reproduces_tension_control():
    by_tension = solve_static(finger_config(20, tension=3.0), None, progress=False).steps[-1]
    config = finger_config(20, tension=None, pull_in=by_tension["pull_ins"][0])
    by_pull_in = solve_static(config, None, progress=False).steps[-1]
    assert by_pull_in["tensions"][0] == pytest.approx(3.0, rel=1e-7)
    for key in ("u", "v", "theta"):
        assert by_pull_in["tip"][key] == pytest.approx(by_tension["tip"][key], rel=1e-7)


def test_symmetric_loop_equals_single_tendon_at_twice_the_tension():
    model = uniform_rod("nonstandard", "none", elements=16)
    loop = run(model, [looped_tendon(0.002, 0.004, 0.002, 0.004, LENGTH, tension=1.5)])
    single = run(model, [Tendon.linear(0.004, 0.002, LENGTH, tension=3.0)])
    for key in ("u", "v", "theta"):
        assert loop.steps[-1]["tip"][key] == pytest.approx(single.steps[-1]["tip"][key], rel=1e-9)


def test_tendon_entry_inside_the_finger_leaves_base_segment_straight():
    """A tendon entering at x = L/2 loads only [L/2, L]: the base half stays straight."""
    model = uniform_rod("reissner", "none", elements=20)
    result = run(model, [Tendon.linear(0.003, 0.003, LENGTH, entry=LENGTH / 2, tension=5.0)])
    if MPI.COMM_WORLD.rank == 0:
        cells = result.shapes[-1][1]["cells"]
        base = cells["x"] < LENGTH / 2
        assert np.abs(cells["kappa"][base]).max() < 1e-9 * np.abs(cells["kappa"]).max()


def test_tendon_gradient_and_hessian_match_finite_differences():
    """g = d(l)/dw and its derivative, against central differences of the length."""
    model = uniform_rod("nonstandard", "none", elements=6)
    tendons = TendonSet(
        [Tendon(paths=(((0.0, 0.004), (0.05, 0.001), (LENGTH, 0.003)),), tension=1.0)], LENGTH
    )
    problem = BeamProblem(model, MPI.COMM_SELF, tendons.breakpoints, tendons.energy)
    rng = np.random.default_rng(3)
    state = problem.w.x.array
    state[:] = 0.02 * rng.standard_normal(state.size)
    gradient = fem.assemble_vector(tendons.gradient_forms[0]).array.copy()
    length = tendons.length_ufl[0]
    hessian_form = fem.form(ufl.derivative(ufl.derivative(length, problem.w), problem.w))
    hessian = fem.assemble_matrix(hessian_form).to_dense()
    direction = rng.standard_normal(state.size)
    step = 1e-6
    base = state.copy()

    def length_at(x):
        state[:] = x
        return tendons.lengths()[0]

    def gradient_at(x):
        state[:] = x
        return fem.assemble_vector(tendons.gradient_forms[0]).array.copy()

    numeric = (length_at(base + step * direction) - length_at(base - step * direction)) / (2 * step)
    assert gradient @ direction == pytest.approx(numeric, rel=1e-7)
    numeric_h = (gradient_at(base + step * direction) - gradient_at(base - step * direction)) / (
        2 * step
    )
    assert np.allclose(
        hessian @ direction, numeric_h, rtol=1e-6, atol=1e-8 * np.abs(numeric_h).max()
    )


def test_finger_cli_defaults_to_the_chapter_finger(tmp_path):
    from fe_beam.cli import main

    config = tmp_path / "empty.toml"
    config.write_text("[output]\nplots = false\nxdmf = false\n")
    assert main(["finger", str(config), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    if MPI.COMM_WORLD.rank == 0:
        import json

        summary = json.loads((tmp_path / "out" / "summary.json").read_text())
        last = summary["steps"][-1]
        assert last["tensions"] == [pytest.approx(2.0)] and last["pull_ins"][0] > 0
        assert last["tip"]["theta"] > 0.3


@pytest.mark.parametrize(
    "tendon, words",
    [
        (
            {"offset_base": 0.008, "offset_tip": 0.004, "tension": 1.0, "pull_in": 0.001},
            "exactly one of tension",
        ),
        ({"offset_base": 0.008, "tension": 1.0}, "offset_base and offset_tip"),
        ({"offset_base": 0.008, "offset_tip": 0.004, "tension": -1.0}, "tension must be"),
        ({"offset_base": 0.008, "offset_tip": 0.004, "tension": 1.0, "anchor": 0.2}, "anchor 0.2"),
        ({"path": [[0.0, 0.01], [0.0, 0.02]], "tension": 1.0}, "increasing x"),
        ({"offset_base": 0.008, "offset_tip": 0.004, "tension": 1.0, "colour": "red"}, "colour"),
    ],
)
def test_finger_cli_rejects_bad_tendons(tmp_path, capsys, tendon, words):
    from fe_beam.cli import main

    lines = ["[[tendons]]"] + [f"{k} = {v!r}".replace("'", '"') for k, v in tendon.items()]
    config = tmp_path / "bad.toml"
    config.write_text("\n".join(lines) + "\n")
    assert main(["finger", str(config), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    assert words in capsys.readouterr().err


def test_inverse_tension_reaches_target_angle():
    from fe_beam.analyses.finger import tension_for_tip_angle

    config = replace(finger_config(10), stepping=LoadStepping(steps=4))
    tension = tension_for_tip_angle(config, 0.25, bracket=(0.0, 5.0))
    config = replace(config, tendons=(replace(config.tendons[0], tension=tension),))
    assert solve_static(config, None, progress=False).steps[-1]["tip"]["theta"] == pytest.approx(
        0.25, abs=1e-9
    )


@pytest.mark.parametrize(("control", "key", "value"),
                         [("tension", "tip_v", 0.015), ("pull_in", "tip_u", -0.002),
                          ("pull_in", "tip_angle", 0.2)])
def test_inverse_reaches_tip_targets_with_either_control(control, key, value):
    """The inverse finds the tension or pull-in that puts the tip component on the target; the
    sweep brackets it, and a fresh forward solve at the answer lands on the target to 1e-9."""
    from fe_beam.analyses.finger import TIP_COMPONENT, InverseTarget, solve_inverse

    tendon = {"tension": 5.0} if control == "tension" else {"tension": None, "pull_in": 0.005}
    config = replace(finger_config(10, **tendon), stepping=LoadStepping(steps=5))
    sweep = solve_static(config, None, progress=False).steps
    answer = solve_inverse(config, InverseTarget(key, value), sweep=sweep)
    assert answer["control"] == control
    assert answer["evaluations"] <= 12
    assert answer["tip"][TIP_COMPONENT[key]] == pytest.approx(value, abs=1e-9)
    forward = replace(config, tendons=(replace(config.tendons[0], tension=answer["tension"],
                                               pull_in=None),))
    tip = solve_static(forward, None, progress=False).steps[-1]["tip"]
    assert tip[TIP_COMPONENT[key]] == pytest.approx(value, abs=1e-9)


@pytest.mark.parametrize(
    ("inverse", "tendons", "words"),
    [
        ({"tip_angle": 0.2, "tip_v": 0.01}, 1, "exactly one of tip_angle, tip_u, tip_v"),
        ({"tip_angle": 0.2}, 2, "needs exactly one tendon"),
        ({"tip_w": 0.2}, 1, "tip_w"),
        ({"tip_angle": "big"}, 1, "tip_angle"),
    ],
)
def test_inverse_config_mistakes(tmp_path, capsys, inverse, tendons, words):
    from fe_beam.cli import main

    lines = []
    for index in range(tendons):
        lines += ["[[tendons]]", f"offset_base = {0.008 - 0.016 * index}",
                  f"offset_tip = {0.004 - 0.008 * index}", "tension = 1.0"]
    lines += ["[inverse]"] + [f"{k} = {v!r}".replace("'", '"') for k, v in inverse.items()]
    config = tmp_path / "bad.toml"
    config.write_text("\n".join(lines) + "\n")
    assert main(["finger", str(config), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err, err


@pytest.mark.parametrize(("target", "control", "words"), [
    (-0.3, "tension", "cannot be reached: the tendon moves the tip the other way"),
    (10.0, "tension", "is not reached: the largest tension with an equilibrium"),
    (-0.2, "pull_in", "cannot be reached: the tendon moves the tip the other way"),
])
def test_unreachable_inverse_target_is_a_stopped_analysis(tmp_path, capsys, target, control,
                                                          words):
    """A target the tendon cannot reach is no input mistake: exit 3, summary.json status
    "failed" with the message and the best reached value (was: exit 2 with status
    "converged" left in summary.json); the best reached value is what a forward solve at its
    tension gives."""
    from fe_beam.cli import main

    amount = "tension = 1.0" if control == "tension" else "pull_in = 0.002"
    config = tmp_path / "far.toml"
    config.write_text("[mesh]\nelements = 6\n[loads]\nsteps = 4\n[[tendons]]\n"
                      f"offset_base = 0.008\noffset_tip = 0.004\n{amount}\n"
                      f"[inverse]\ntip_angle = {target}\n")
    out = tmp_path / "out"
    assert main(["finger", str(config), "--out", str(out), "--quiet"]) == 3
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and words in summary["message"]
    inverse = summary["inverse"]
    assert inverse["status"] == "failed" and inverse["control"] == control
    best = inverse["best_reached"]
    reached = [0.0] + [step["tip"]["theta"] for step in summary["steps"]]
    assert abs(best["tip_angle"] - target) <= min(abs(r - target) for r in reached) + 1e-12
    if target > 0:  # beyond the sweep: a forward solve at the best tension gives its angle
        assert best["tension"] > summary["steps"][-1]["tensions"][0]
        forward = tmp_path / "forward.toml"
        forward.write_text(config.read_text().split("[inverse]")[0].replace(
            amount, f"tension = {best['tension']!r}"))
        assert main(["finger", str(forward), "--out", str(tmp_path / "fw"), "--quiet"]) == 0
        tip = json.loads((tmp_path / "fw" / "summary.json").read_text())["steps"][-1]["tip"]
        assert tip["theta"] == pytest.approx(best["tip_angle"], rel=1e-6)


@pytest.mark.parametrize(("tendon", "where"), [
    ({"offset_base": 0.011, "offset_tip": 0.004}, "x = 0 m"),  # base half-height 0.01
    ({"offset_base": 0.0, "offset_tip": -0.0051}, "offset -0.00507"),  # tip: 0.005, first
    # sampled station outside: x = 0.0995 m
    ({"path": [[0.0, 0.0], [0.05, -0.0076], [0.1, 0.0]]}, "x = 0.05 m"),  # 0.0075 at x = L/2
])
def test_tendon_outside_the_section_is_refused(tmp_path, capsys, tendon, where):
    from fe_beam.cli import main

    lines = ["[[tendons]]", *[f"{k} = {v!r}" for k, v in tendon.items()], "tension = 1.0"]
    config = tmp_path / "outside.toml"
    config.write_text("\n".join(lines) + "\n")
    assert main(["finger", str(config), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "outside the section" in err and where in err, err


@pytest.mark.mpi
def test_finger_parallel_equals_serial():
    config = finger_config(24, tension=4.0)
    together = solve_static(config, None, MPI.COMM_WORLD, progress=False).steps[-1]
    alone = solve_static(config, None, MPI.COMM_SELF, progress=False).steps[-1]
    for key in ("u", "v", "theta"):
        assert together["tip"][key] == pytest.approx(alone["tip"][key], rel=1e-10)
    assert together["pull_ins"][0] == pytest.approx(alone["pull_ins"][0], rel=1e-10)

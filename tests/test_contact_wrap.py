"""A rod pressed around a rigid cylinder (issue 23), against closed forms.

The rod is clamped at x = 0 tangent to a cylinder of radius R below it (its lower surface on the
cylinder's top: the centreline on the circle of radius Rc = R + h/2). In a contact zone the rod
follows the cylinder, curvature 1/Rc, so its moment is EI/Rc there: constant, hence no shear,
no axial force and no pressure inside the zone (p = -N/Rc with N = 0): the load reaches the
cylinder at the zone's edge only.

(a) An end moment alone never wraps the rod: the force-free span beside a contact zone carries
the end moment unchanged, so a zone needs M = M* = EI/Rc exactly. Below M* the rod curls on a
circle of radius EI/M > Rc, clear of the cylinder; above it the tip curls tighter than the
cylinder and rests on it at the tip alone (no contact length: the closed form of the contact
length vs the moment is 0 for every M != M*).
(b) A dead tip force F (small slopes, R >> L): below F1 = EI/(Rc L) no contact beyond the
tangency; above, the rod lies on the cylinder over [0, a] and touches it with the point force F at
x = a, where the free span [a, L], a cantilever under F, has the moment F (L - a) = EI/Rc:
a = L - EI/(F Rc); the clamp carries the moment EI/Rc and no force.
"""

import pytest

from fe_beam.config.registry import validate
from fe_beam.solvers.newton import LoadStepping
from fe_beam.solvers.rod_static import StaticContinuation

L, H, EI = 1.0, 0.01, 1.0


def rod(radius: float, loads: dict, elements: int, tolerance: float, **contact) -> dict:
    return {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": H, "h": H},
        "material": {"E": 12 * EI / H**4, "nu": 0.3},
        "model": {"law": "reissner", "constraint": "inextensible-unshearable"},
        "mesh": {"elements": elements, "degree": 2},
        "loads": loads,
        "solver": {"atol": 1e-10},
        "obstacles": [{"shape": "cylinder", "name": "mandrel", "radius": radius,
                       "point": [0.0, -radius - H / 2 - 1e-7]}],
        "contact": {"penetration_tolerance": tolerance, **contact},
        "output": {"xdmf": False, "plots": False},
    }


def load_path(config: dict, steps: int):
    parsed = validate("static", config).parsed
    run = StaticContinuation(parsed)
    records = []

    def record(step) -> None:
        (entry,) = run.contact.summary()
        tolerance = config["contact"]["penetration_tolerance"]
        assert entry["contact_point_penetration"] <= tolerance, entry
        records.append((step.load_factor, entry, run.problem.end_reaction("x0"),
                        run.problem.end_values("xL")))

    run.advance(1.0, LoadStepping(steps=steps), on_converged=record)
    return records


@pytest.mark.parametrize("factor", [0.9, 1.1])
def test_an_end_moment_does_not_wrap_the_rod(factor):
    radius = 0.5
    moment = factor * EI / (radius + H / 2)
    records = load_path(rod(radius, {"tip_moment": -moment, "steps": 10}, 40, 1e-8), 10)
    load, entry, _, tip = records[-1]
    assert load == 1.0
    if factor < 1:  # the free circle of radius EI/M, clear of the cylinder
        assert entry["force"] == [0.0, 0.0] and entry["active"] == []
        assert tip["theta"] == pytest.approx(-moment * L / EI, rel=1e-6)
    else:  # pressed at the tip alone: no contact zone
        assert entry["active"] == [[L, L]]
        assert entry["end_forces"][1] > 0


@pytest.mark.mpi
def test_a_tip_force_wraps_the_rod_over_a_length_a():
    radius, elements = 20.0, 50
    rc = radius + H / 2
    f1 = EI / (rc * L)
    top = 4 * f1
    config = rod(radius, {"tip_force": [0.0, -top], "steps": 8}, elements, 1e-8,
                 penalty=10.0, max_updates=200)
    checked = 0
    worst = {"edge": 0.0, "force": 0.0, "clamp_moment": 0.0}
    for load, entry, clamp, _ in load_path(config, 8):
        force = load * top
        if force < 1.2 * f1:
            continue
        a = L - EI / (force * rc)
        # the cylinder takes the whole tip force, at the edge of the zone
        assert entry["force"][1] == pytest.approx(force, rel=2e-3)
        worst["force"] = max(worst["force"], abs(entry["force"][1] / force - 1))
        edge = entry["active"][-1]
        middle = (edge[0] + edge[1]) / 2
        assert abs(middle - a) <= 0.5 * L / elements, (entry["active"], a)
        worst["edge"] = max(worst["edge"], abs(middle - a))
        # the clamp: the moment EI/Rc of the wrapped zone, no force
        assert abs(clamp["M"]) == pytest.approx(EI / rc, rel=5e-3)
        worst["clamp_moment"] = max(worst["clamp_moment"], abs(abs(clamp["M"]) * rc / EI - 1))
        assert abs(clamp["Fy"]) <= 5e-3 * force
        checked += 1
    assert checked >= 4, checked
    print("wrap by a tip force:", worst)

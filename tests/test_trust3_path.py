"""Issue 20, item 3: `fe-beam path` locates every bifurcation a step crosses (the count of
energy-decreasing directions may change by more than one in one step): each located load
factor is the closed-form bifurcation of the straight column (tests/column_closed_forms)."""

import pytest
from column_closed_forms import critical_loads
from mpi4py import MPI

from fe_beam.analyses.path import run_path

E, NU = 7.0e10, 0.33


def column(supports, length, b, h, elements, arc, top, force=-1000.0):
    return {"beam": {"length": length}, "section": {"shape": "rectangle", "b": b, "h": h},
            "material": {"E": E, "nu": NU}, "model": {"law": "reissner", "constraint": "none"},
            "mesh": {"elements": elements, "degree": 2},
            "supports": {"x0": supports[0], "xL": supports[1]},
            "loads": {"tip_force": [force, 0.0], "steps": 4},
            "path": {"arc_length": arc, "max_arc_length": 1.0, "max_load_factor": top,
                     "tolerance": 1e-9},
            "output": {"plots": False, "xdmf": False}}


def closed(case, length, b, h, count, force=1000.0):
    G = E / (2 * (1 + NU))
    loads = critical_loads(case, "reissner", "none", E * b * h, G * b * h, E * b * h**3 / 12,
                           length, count)
    return [P / force for P in loads]


@pytest.mark.mpi
@pytest.mark.parametrize("case, supports, length, b, h, elements, arc, top, count", [
    # cantilever: factors 0.288, 2.59, 7.19; the first step (to 3) crosses two
    ("clamped-free", ("clamped", "free"), 1.0, 0.02, 0.01, 64, 3.0, 8.0, 3),
    # pinned-roller: factors 1.80, 7.19, 16.2; the first step (to 20) crosses all three
    ("pinned-pinned", ("pinned", "roller"), 0.8, 0.02, 0.01, 64, 20.0, 21.0, 3),
])
def test_every_bifurcation_of_a_long_step_is_located(tmp_path, case, supports, length, b, h,
                                                     elements, arc, top, count):
    summary = run_path(column(supports, length, b, h, elements, arc, top),
                       tmp_path if MPI.COMM_WORLD.rank == 0 else None, MPI.COMM_WORLD,
                       progress=False)
    assert summary["status"] == "converged", summary["message"]
    located = [c["load_factor"] for c in summary["critical_points"]
               if c["kind"] == "bifurcation"]
    expected = closed(case, length, b, h, count)
    assert all(e < top for e in expected)
    assert len(located) == count, (located, expected)
    for found, exact in zip(sorted(located), expected, strict=True):
        assert abs(found - exact) <= 2e-6 * exact, (found, exact)
    # the path's own counts: 0 before the step, `count` after it (crossed in one step)
    counts = [p["energy_decreasing_directions"] for p in summary["path"]]
    assert counts[0] == 0 and counts[1] == (2 if case == "clamped-free" else count), counts

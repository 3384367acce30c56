"""An obstacle narrower than the spacing of the rod's contact points (a thin peg between two
Gauss points): the rod must not pass through it with exit 0 and a zero contact force. The
rod's geometry is checked at points 1/8 of the narrowest obstacle apart, at every accepted
state and along the straight path of every load step (`ContactSet.between_points`,
`ContactSet.tunnelled`): a state with the peg inside the rod is rejected, and when the contact
points cannot hold the peg, the run stops with exit 3 and says why."""

import json
import math

from tomlio import dump_toml

from fe_beam.analyses.static import solve_static
from fe_beam.cli import main
from fe_beam.config.registry import validate

L, H = 1.0, 0.01
EI = 2e11 * H**4 / 12


def cantilever(peg_x: float, radius: float, force: float) -> dict:
    return {
        "beam": {"length": L},
        "section": {"shape": "rectangle", "b": H, "h": H},
        "material": {"E": 2e11, "nu": 0.3},
        "model": {"law": "reissner"},
        "mesh": {"elements": 10, "degree": 2},
        "loads": {"tip_force": [0.0, -force], "steps": 4},
        "obstacles": [{"shape": "cylinder", "name": "peg", "radius": radius,
                       "point": [peg_x, -(H / 2 + 0.002 + radius)]}],
        "output": {"xdmf": False, "plots": False},
    }


def test_a_peg_between_the_contact_points_is_not_passed_through(tmp_path):
    # x = 0.41: between the Gauss points 0.4047 and 0.4231 of the fifth element; the free
    # cantilever's deflection there at 40 N is 17.4 mm: over the peg and 3.4 mm beyond
    config = cantilever(0.41, 0.001, 40.0)
    deflection = 40.0 * 0.41**2 * (3 * L - 0.41) / (6 * EI)
    assert deflection > 0.002 + 2 * 0.001 + H  # the free rod would sweep right over it
    path = tmp_path / "peg.toml"
    path.write_text(dump_toml(config))
    out = tmp_path / "out"
    code = main(["static", str(path), "--out", str(out), "--quiet"])
    summary = json.loads((out / "summary.json").read_text())
    if code == 0:  # held: the peg carries the rod, below the tolerance
        entry = summary["steps"][-1]["contact"][0]
        assert math.hypot(*entry["force"]) > 1.0
    else:
        assert code == 3
        assert "between the contact points" in summary["message"]
        assert summary["steps"], "the last good state is written"


def test_a_peg_on_a_contact_point_still_converges_exactly():
    """The check rejects nothing the contact points hold: the same peg at the element's middle
    Gauss point, under a load that presses the rod onto it by less than it can bear, converges
    with the penetration below the tolerance (and the free rod above it is untouched)."""
    config = cantilever(0.45, 0.001, 2.0)  # 0.87 mm: clear of the peg
    result = solve_static(validate("static", config).parsed, None, progress=False,
                          record_shapes=False)
    assert result.status == "converged", result.message
    assert result.steps[-1]["contact"][0]["force"] == [0.0, 0.0]

"""The same hidden-style cases give the same numbers on Debian's dolfinx 0.5.2 and on PyPI's
0.11 (issue 13): ``tests/cross_stack.py`` runs on this interpreter and on the other stack's venv
(``.venv-pypi`` seen from Debian's, ``.venv`` seen from PyPI's; ``FE_BEAM_OTHER_PYTHON``
overrides), then every recorded number agrees to 1e-10 relative (1D) and 1e-8 (3D, one mesh)."""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from mpi4py import MPI

from fe_beam.fem import compat

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "tests" / "cross_stack.py"
TOLERANCE = {1: 1e-10, 3: 1e-8}
# Quantities whose largest magnitude is below this (SI units) are round-off zeros, e.g. the
# axial strain of an inextensible rod (~1e-15): compared with this scale, i.e. to 1e-15
# absolute in 1D.
ZERO_SCALE = 1e-5


def other_python() -> Path | None:
    given = os.environ.get("FE_BEAM_OTHER_PYTHON")
    if given:
        return Path(given)
    venv = ".venv-pypi" if compat.LEGACY else ".venv"
    return ROOT / venv / "bin" / "python"


def differences(mine: dict, theirs: dict) -> list[str]:
    """What disagrees between two cross_stack.py results: exit codes, statuses, the set of
    numbers, and each number beyond the tolerance of its case's dimension, relative to the
    largest magnitude of its quantity (the path with the step and point indices dropped), or
    ZERO_SCALE when that is smaller."""
    problems = []
    for case, a in mine.items():
        b = theirs.get(case)
        if b is None:
            problems.append(f"{case}: missing on the other stack")
            continue
        if (a["exit"], a["status"]) != (b["exit"], b["status"]) or a["exit"] != 0:
            problems.append(f"{case}: exit/status {a['exit']}/{a['status']} vs "
                            f"{b['exit']}/{b['status']}")
        if set(a["values"]) != set(b["values"]):
            problems.append(f"{case}: different numbers recorded: "
                            f"{sorted(set(a['values']) ^ set(b['values']))[:5]}")
            continue
        scale: dict[str, float] = {}  # quantity -> max(ZERO_SCALE, its largest magnitude)
        for path, value in a["values"].items():
            quantity = re.sub(r"/\d+", "/#", path)
            scale[quantity] = max(scale.get(quantity, ZERO_SCALE), abs(value),
                                  abs(b["values"][path]))
        tolerance = TOLERANCE[a["dimension"]]
        for path, value in a["values"].items():
            quantity = re.sub(r"/\d+", "/#", path)
            if abs(value - b["values"][path]) > tolerance * scale[quantity]:
                problems.append(f"{case}{path}: {value!r} vs {b['values'][path]!r} "
                                f"(tolerance {tolerance:g} x {scale[quantity]:.3g})")
    return problems


def run(python: Path, out: Path, mesh: Path) -> dict:
    env = dict(os.environ, FE_BEAM_PROGRESS="0", OMP_NUM_THREADS="1",
               PYTHONPATH=os.pathsep.join([str(ROOT), *filter(None, [os.environ.get(
                   "PYTHONPATH")])]))
    process = subprocess.run([str(python), str(SCRIPT), str(out), "--mesh", str(mesh)],
                             capture_output=True, text=True, env=env, cwd=out.parent,
                             timeout=1800)
    assert process.returncode == 0, process.stderr[-3000:]
    return json.loads(out.read_text())


def test_differences_sees_a_change_beyond_the_tolerance():
    base = {"c1": {"exit": 0, "status": "converged", "dimension": 1,
                   "values": {"/steps/0/tip/u": -0.2, "/steps/1/tip/u": -0.5}},
            "c3": {"exit": 0, "status": "converged", "dimension": 3,
                   "values": {"/steps/0/tip/v": 0.01}}}
    assert differences(base, json.loads(json.dumps(base))) == []
    moved = json.loads(json.dumps(base))
    moved["c1"]["values"]["/steps/0/tip/u"] *= 1 + 3e-10  # 1.2e-10 of the scale 0.5
    assert len(differences(base, moved)) == 1
    moved = json.loads(json.dumps(base))
    moved["c1"]["values"]["/steps/0/tip/u"] *= 1 + 1e-10  # 4e-11 of the scale: equal
    moved["c3"]["values"]["/steps/0/tip/v"] *= 1 + 5e-9
    assert differences(base, moved) == []
    moved["c3"]["values"]["/steps/0/tip/v"] *= 1 + 2e-8
    assert len(differences(base, moved)) == 1
    moved = json.loads(json.dumps(base))
    moved["c1"]["values"]["/steps/0/eps"] = base["c1"]["values"]["/steps/0/eps"] = 7e-15
    moved["c1"]["values"]["/steps/0/eps"] = 7.6e-15  # round-off zeros
    assert differences(base, moved) == []
    moved["c1"]["values"]["/steps/0/eps"] = 3e-15
    assert len(differences(base, moved)) == 1
    moved = json.loads(json.dumps(base))
    moved["c3"]["status"] = "failed"
    assert len(differences(base, moved)) == 1


@pytest.mark.slow
@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial: it runs both stacks itself")
def test_same_numbers_on_both_stacks(tmp_path):
    other = other_python()
    if not other.exists():
        stack = "FE_BEAM_STACK=pypi ./bootstrap install" if compat.LEGACY else "./bootstrap install"
        pytest.skip(f"the other FEniCSx stack is not installed ({other} missing: {stack}; "
                    "the PyPI stack needs a Python >= 3.12)")
    mesh = tmp_path / "finger_mesh.json"  # meshed by this stack's gmsh, used by both
    mine = run(Path(sys.executable), tmp_path / "mine.json", mesh)
    theirs = run(other, tmp_path / "theirs.json", mesh)
    versions = {mine[case]["dolfinx"] for case in mine}, {theirs[c]["dolfinx"] for c in theirs}
    assert versions[0].isdisjoint(versions[1]), f"one stack compared with itself: {versions}"
    assert set(mine) == {"elastica_inextensible", "nonstandard_cantilever", "finger",
                         "solid_finger"}
    problems = differences(mine, theirs)
    assert not problems, "\n".join(problems[:20])

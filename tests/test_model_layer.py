"""The model layer and `fe_beam.config.schema` are free of the finite-element stack: validating any
configuration, ``fe-beam --help`` and a configuration mistake load neither dolfinx, nor PETSc,
nor MPI (checked in a fresh interpreter); PETSc judges PETSc options where a solver is built."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("dolfinx", "petsc4py", "mpi4py", "slepc4py", "basix", "ffcx", "gmsh")
#: the commands each example is meant for (its header says which)
EXAMPLES = {
    "cantilever.toml": ("static", "refine"),
    "finger.toml": ("finger", "refine"),
    "finger_dynamics.toml": ("dynamic", "modes"),
    "finger_solid.toml": ("solid", "compare", "refine"),
    "flying_spaghetti.toml": ("dynamic",),
    "release.toml": ("dynamic", "modes"),
    "spin_up.toml": ("dynamic",),
    "spatial_finger.toml": ("finger",),
    "bathe_bolourchi.toml": ("static",),
    "lateral_torsional.toml": ("buckling", "path"),
    "section_laws/finger_dragon_skin_30.toml": ("solid", "compare"),
    "section_laws/finger_neo_hookean.toml": ("solid", "compare"),
}


def run_python(code: str) -> dict:
    """Run ``code`` in a fresh interpreter (no MPI launcher in its environment) and return the
    JSON it prints on its last line."""
    from fe_beam.cli import MPI_LAUNCHER_PREFIXES

    env = {k: v for k, v in os.environ.items() if not k.startswith(MPI_LAUNCHER_PREFIXES)}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, cwd=ROOT, timeout=120)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


LOADED = f"[m for m in {HEAVY!r} if m in sys.modules]"


def test_every_example_validates_without_the_fe_stack():
    code = f"""
import json, sys
from fe_beam.config import apply_overrides, load_config, validate
done = []
for name, commands in {EXAMPLES!r}.items():
    config = load_config("examples/" + name)
    for command in commands:
        refine = {{"levels": "3"}} if command == "refine" else None
        validated = validate(command, config, refine)
        done.append([name, command, type(validated.parsed).__name__])
print(json.dumps({{"done": done, "loaded": {LOADED}}}))
"""
    result = run_python(code)
    assert result["loaded"] == []
    assert len(result["done"]) == sum(len(c) for c in EXAMPLES.values())
    kinds = {(name, command): kind for name, command, kind in result["done"]}
    assert kinds["cantilever.toml", "static"] == "StaticConfig"
    assert kinds["finger.toml", "finger"] == "tuple"
    assert kinds["finger_dynamics.toml", "dynamic"] == "DynamicConfig"
    assert kinds["finger_solid.toml", "solid"] == "SolidConfig"
    assert kinds["finger_solid.toml", "compare"] == "CompareConfig"
    assert kinds["cantilever.toml", "refine"] == "RefinementPlan"


def test_model_modules_import_no_fe_stack():
    code = f"""
import json, sys
import fe_beam, fe_beam.config.schema, fe_beam.model, fe_beam.model.beam, fe_beam.model.laws
import fe_beam.model.settings, fe_beam.model.tendons, fe_beam.model.solid, fe_beam.config.finger
import fe_beam.config.transient, fe_beam.config.compare, fe_beam.config.solid
import fe_beam.analyses.solid_driver
import fe_beam.config.refine
from fe_beam.analyses.solid_driver import parse_solid
print(json.dumps({{"loaded": {LOADED}}}))
"""
    assert run_python(code)["loaded"] == []


@pytest.mark.parametrize("argv, code", [
    (["--help"], 0),
    (["static", "examples/cantilever.toml", "--out", "{out}", "--set", "beam.length=-1"], 2),
    (["solid", "examples/finger_solid.toml", "--out", "{out}", "--set", "solid.order=3"], 2),
    (["dynamic", "examples/release.toml", "--out", "{out}", "--set", "time.dt=-1"], 2),
])
def test_help_and_config_mistakes_answer_without_the_fe_stack(tmp_path, argv, code):
    argv = [a.replace("{out}", str(tmp_path / "out")) for a in argv]
    script = f"""
import contextlib, io, json, sys
from fe_beam.cli import main
err = io.StringIO()
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
    try:
        code = main({argv!r})
    except SystemExit as stop:
        code = stop.code
print(json.dumps({{"code": code, "err": err.getvalue(), "loaded": {LOADED}}}))
"""
    result = run_python(script)
    assert result["code"] == code, result
    assert result["loaded"] == []
    if code == 2:
        assert result["err"].count("\n") == 1 and "error in examples/" in result["err"], result
    assert not (tmp_path / "out").exists()


def test_solver_settings_check_no_petsc_options_until_a_solver_is_built():
    """Creating or replacing SolverSettings does not ask PETSc (nor load it); the solver's
    check does, with the message the configuration tests expect."""
    code = f"""
import dataclasses, json, sys
from fe_beam.model.settings import SolverSettings
bad = SolverSettings(petsc_options={{"ksp_type": "nonsense"}})
bad = dataclasses.replace(bad, rtol=1e-8)
before = {LOADED}
from fe_beam.config.schema import ConfigError
from fe_beam.solvers.newton import check_petsc_options
try:
    check_petsc_options(bad.petsc_options)
    message = None
except ConfigError as error:
    message = str(error)
check_petsc_options({{"ksp_type": "cg", "snes_max_it": 7}})
print(json.dumps({{"before": before, "message": message}}))
"""
    result = run_python(code)
    assert result["before"] == []
    assert result["message"] == ("solver.petsc_options.ksp_type = 'nonsense': PETSc rejects it "
                                 "(unknown type)")


def test_solver_settings_refuse_malformed_options_at_once():
    from fe_beam.model.settings import SolverSettings

    with pytest.raises(ValueError, match="without the leading '-'"):
        SolverSettings(petsc_options={"-ksp_type": "cg"})
    with pytest.raises(ValueError, match="string or a number"):
        SolverSettings(petsc_options={"ksp_type": ["cg"]})


STRAINS = [(1.02, 0.03, 0.0201, 4.0), (0.97, -0.2, -0.01, -11.0), (1.0, 0.0, 0.0, 0.0)]
STIFFNESS = dict(EA=3.0e5, GA=1.1e5, EI=2.5, EI3=-0.03, EI4=4.0e-4, shear_correction=0.8)


@pytest.mark.parametrize("one_plus_e, g, eps, kappa", STRAINS)
def test_law_objects_give_the_energies_of_their_formulas(one_plus_e, g, eps, kappa):
    """NonStandard and Reissner (dataclasses, energy as a method) against the energies written
    out here: W = 1/2 EA eps^2 + 1/2 GA g^2 + 1/2 EI k^2 ((1+e)^2 + eps) + 1/2 EI3 k^3 (1+e)
    + 1/8 EI4 k^4 and W_R = 1/2 EA e^2 + 1/2 k_s GA g^2 + 1/2 EI k^2."""
    from fe_beam.fem.kinematics import strain_energy
    from fe_beam.model.laws import (
        ROD_LAWS,
        NonStandard,
        Reissner,
        Stiffness,
        Strains,
        closed_form_law,
    )

    s, k = Strains(one_plus_e, g, eps, kappa), Stiffness(**STIFFNESS)
    c = STIFFNESS
    nonstandard = (0.5 * c["EA"] * eps**2 + 0.5 * c["GA"] * g**2
                   + 0.5 * c["EI"] * kappa**2 * (one_plus_e**2 + eps)
                   + 0.5 * c["EI3"] * kappa**3 * one_plus_e + c["EI4"] * kappa**4 / 8)
    reissner = (0.5 * c["EA"] * (one_plus_e - 1) ** 2
                + 0.5 * c["shear_correction"] * c["GA"] * g**2 + 0.5 * c["EI"] * kappa**2)
    assert NonStandard(k).energy(s) == pytest.approx(nonstandard, rel=1e-14, abs=1e-300)
    assert Reissner(k).energy(s) == pytest.approx(reissner, rel=1e-14, abs=1e-300)
    assert set(ROD_LAWS) == {"nonstandard", "reissner"}
    for name, law in ROD_LAWS.items():
        assert isinstance(closed_form_law(name, k), law)
        assert strain_energy(name, s, k) == law(k).energy(s)  # the old entry point, same number
        assert law(k).fibre_stretches(s) == []
    with pytest.raises(ValueError, match="no closed form"):
        closed_form_law("hyperelastic", k)
    with pytest.raises(ValueError, match="model.law must be one of"):
        closed_form_law("kirchhoff", k)
    assert math.isfinite(nonstandard)

"""Issue 20, item 4: a [time] key that the chosen scheme does not use is said, not silently
ignored: rho_inf with scheme = "energy-conserving" (a warning and a summary note) and with
the fd-* schemes (a summary note)."""

import json

import pytest
from mpi4py import MPI
from tomlio import dump_toml

from fe_beam.cli import main


def cantilever(scheme, **time):
    return {"beam": {"length": 0.5}, "section": {"shape": "rectangle", "b": 0.02, "h": 0.004},
            "material": {"E": 7e10, "nu": 0.33, "rho": 2700.0},
            "model": {"law": "reissner", "constraint": "none"},
            "mesh": {"elements": 4, "degree": 2},
            "supports": {"x0": "clamped", "xL": "free"},
            "loads": {"tip_force": [0.0, -2.0], "time_function": "1"},
            "time": {"t_end": 0.004, "dt": 0.002, "scheme": scheme, **time},
            "output": {"plots": False, "xdmf": False}}


def run(tmp_path, config, capsys):
    path = tmp_path / "c.toml"
    if MPI.COMM_WORLD.rank == 0:
        path.write_text(dump_toml(config))
    MPI.COMM_WORLD.barrier()
    out = tmp_path / "out"
    capsys.readouterr()
    code = main(["dynamic", str(path), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert (out / "summary.json").exists(), (code, err)
    summary = json.loads((out / "summary.json").read_text())
    return code, err, summary


@pytest.mark.parametrize("scheme, time, noted", [
    ("energy-conserving", {"rho_inf": 0.6}, True),
    ("energy-conserving", {}, False),
    ("fd-rk45", {"rho_inf": 0.3}, True),
    ("generalized-alpha", {"rho_inf": 0.6}, False),
])
def test_rho_inf_unused_by_the_scheme_is_said(tmp_path, capsys, scheme, time, noted):
    code, err, summary = run(tmp_path, cantilever(scheme, **time), capsys)
    assert code == 0, err
    notes = [n for n in summary["notes"] if n.startswith("[time] rho_inf")]
    if noted:
        assert len(notes) == 1, summary["notes"]
        assert f"scheme = \"{scheme}\"" in notes[0] and "generalized-alpha" in notes[0]
        assert f"{time['rho_inf']!r}" in notes[0]
        if MPI.COMM_WORLD.rank == 0 and scheme == "energy-conserving":
            assert "rho_inf" in err and "ignored" in err  # fd-*: in summary.json only
    else:
        assert notes == [], notes
        assert "rho_inf" not in err

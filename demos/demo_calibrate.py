# # Calibration demo: the rod's E and tendon tip offset fitted to the 3D solid's backbone
#
# 1. `fe-beam solid` on a coarse 3D finger (examples/finger_solid.toml with mesh_size 0.01 m,
#    quadratic elements, ~2400 dofs: seconds; --full uses the example's own mesh): a sweep, with
#    the deformed backbone (section centroids at 11 stations) at each tension. This is real 3D
#    output, not synthetic data.
# 2. The backbone becomes DATA.csv (tension, s, x, y) and `fe-beam calibrate` fits the rod's
#    material.E and tendons.0.offset_tip (start: the 3D law's small-strain E and the solid's
#    tendon offset) with the exact adjoint Jacobian.
# 3. The fitted rod is compared with the nominal one: the backbone misfit before and after,
#    and the standard errors and correlation of the two parameters. The fitted values are the
#    rod's *effective* E and offset: they absorb what the rod does not model (the section's
#    in-plane deformation, the anchor plate, the coarse 3D mesh's stiffness).
#
# Run: `python demos/demo_calibrate.py --out results/calibrate_demo`.

import argparse
import copy
import csv
import json
import tomllib
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fe_beam.cli import main as fe_beam
from fe_beam.cli import quiet_jit_logging

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "finger_solid.toml"
PARAMETERS = ["material.E", "tendons.0.offset_tip"]


def solid_config(full: bool) -> dict:
    raw = tomllib.loads(EXAMPLE.read_text())
    raw.pop("compare", None)
    raw["solid"]["backbone_points"] = 11
    if not full:
        raw["solid"] |= {"mesh_size": 0.01}
    raw["loads"]["steps"] = 4
    return raw


def toml_text(raw: dict) -> str:
    """A small TOML writer for the tables used here (numbers, strings, lists, [[tendons]])."""
    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{" + ", ".join(f"{json.dumps(k)} = {value(x)}" for k, x in v.items()) + "}"
        return repr(float(v)) if isinstance(v, float) else str(v)

    lines = []
    for name, table in raw.items():
        if isinstance(table, list):
            for entry in table:
                lines.append(f"[[{name}]]")
                lines += [f"{k} = {value(v)}" for k, v in entry.items()]
        else:
            lines.append(f"[{name}]")
            lines += [f"{k} = {value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


def main(out: Path, full: bool = False) -> dict:
    comm = MPI.COMM_WORLD
    quiet_jit_logging()
    out = Path(out)
    raw = solid_config(full)
    solid_toml = out / "finger_solid.toml"
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        solid_toml.write_text(toml_text(raw))
    comm.barrier()
    assert fe_beam(["solid", str(solid_toml), "--out", str(out / "solid"), "--quiet"]) == 0
    summary = json.loads((out / "solid" / "summary.json").read_text())

    # 3D backbone -> DATA.csv (the clamp station s = 0 carries no information)
    data = out / "backbone.csv"
    rows = []
    for step in summary["steps"]:
        backbone = step["backbone"]
        for s, u, v in zip(backbone["x"], backbone["u"], backbone["v"], strict=True):
            if s > 0:
                rows.append([step["tension"], s, s + u, v])
    if comm.rank == 0:
        with data.open("w", newline="") as stream:
            writer = csv.writer(stream)
            writer.writerow(["tension", "s", "x", "y"])
            writer.writerows(rows)

    # the rod: the solid's [section], [material], [[tendons]], [beam] (its own [mesh])
    rod = {k: copy.deepcopy(raw[k]) for k in ("beam", "section", "material", "tendons", "loads")}
    rod["mesh"] = {"elements": 20, "degree": 2}
    rod["calibrate"] = {"parameters": PARAMETERS, "weights": {"x": 1000.0, "y": 1000.0}}
    rod_toml = out / "finger_rod.toml"
    if comm.rank == 0:
        rod_toml.write_text(toml_text(rod))
    comm.barrier()
    assert fe_beam(["calibrate", str(rod_toml), "--data", str(data), "--out",
                    str(out / "calibration"), "--quiet"]) == 0
    fit = json.loads((out / "calibration" / "summary.json").read_text())
    start = fit["history"][0]
    result = {
        "nominal": start["parameters"],
        "fitted": fit["parameters"],
        "standard_errors": fit["standard_errors"],
        "correlation": fit["correlation"]["material.E"]["tendons.0.offset_tip"],
        "rms_before_m": start["residual_norm"] / 1000 / np.sqrt(2 * len(rows)),
        "rms_after_m": fit["residual_norm"] / 1000 / np.sqrt(2 * len(rows)),
        "iterations": fit["iterations"],
        "points": len(rows),
        "data": "fe-beam solid output (3D neo-Hookean finger, coarse mesh)",
    }
    if comm.rank == 0:
        (out / "demo_calibrate.json").write_text(json.dumps(result, indent=2))
        print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("results/calibrate_demo"))
    parser.add_argument("--full", action="store_true", help="the example's own 3D mesh")
    arguments = parser.parse_args()
    main(arguments.out, arguments.full)

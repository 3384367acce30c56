"""Section-law study: the tendon-driven finger as a 3D hyperelastic solid against the rod with the
section law of the same material, the non-standard law and the Reissner law (issue 15).

    FE_BEAM_PROGRESS=0 .venv/bin/python postprocessing/section_law_study.py --out results/laws
    FE_BEAM_PROGRESS=0 mpirun -n 2 .venv/bin/python postprocessing/section_law_study.py --out ...

Each case is one `fe-beam compare` run (``examples/section_laws/*.toml`` with overrides): the 3D
solid over the tension sweep 1 .. 5 N and, at every tension, the rod with each law. The study is
resumable: a case whose ``summary.json`` is complete is read, not run again; a complete 3D sweep
that lacks a rod law (e.g. computed before that law existed) only gets the missing rods. Writes
``section_laws.png`` (tip rotation vs tension, and the rods' errors), ``section_laws.md`` (the
table of the README) and ``section_laws.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from mpi4py import MPI

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fe_beam.analyses import compare as cmp  # noqa: E402
from fe_beam.analyses.solid_driver import backbone_distance, run_rod  # noqa: E402
from fe_beam.config.schema import apply_overrides, load_config  # noqa: E402
from fe_beam.exports.outputs import atomic_write_json, atomic_write_text  # noqa: E402

EXAMPLES = ROOT / "examples" / "section_laws"
LAWS = ("hyperelastic", "nonstandard", "reissner")
LABELS = {"hyperelastic": "rod, section law of the 3D material", "nonstandard": "rod, non-standard",
          "reissner": "rod, Reissner"}
STYLE = {"hyperelastic": ("--", "tab:red"), "nonstandard": ("-.", "tab:orange"),
         "reissner": (":", "tab:green")}

#: (name, group, config file, overrides); a group is one material, its cases are 3D meshes
CASES = [
    ("nh_4mm", "neo-Hookean (E = 0.6 MPa)", "finger_neo_hookean.toml", ["solid.mesh_size=0.004"]),
    ("nh_2mm", "neo-Hookean (E = 0.6 MPa)", "finger_neo_hookean.toml", ["solid.mesh_size=0.002"]),
    ("ds30_nh_4mm", "Dragon Skin 30, neo-Hookean", "finger_dragon_skin_30.toml",
     ["solid.material=neo-hookean"]),
    ("mr_4mm", "Mooney-Rivlin (E = 0.6 MPa, C10 = C01)", "finger_neo_hookean.toml",
     ["solid.material=mooney-rivlin"]),
    ("ds30_yeoh_4mm", "Dragon Skin 30, Yeoh", "finger_dragon_skin_30.toml",
     ["solid.material=yeoh"]),
]


def case_config(case) -> dict:
    _, _, name, overrides = case
    return apply_overrides(load_config(EXAMPLES / name), overrides)


def complete(summary: dict | None, config: cmp.CompareConfig) -> bool:
    return (summary is not None and summary.get("status") == "converged"
            and len(summary.get("table", [])) == len(config.load_factors))


def add_missing_rods(summary: dict, config: cmp.CompareConfig, out: Path, comm) -> dict:
    """Rods of the laws the saved (complete) sweep lacks, against its saved 3D rows."""
    solid = config.solid
    for row in summary["table"]:
        for law in config.laws:
            if law in row["rod"]:
                continue
            rod = run_rod(cmp.rod_at(solid.rod, law, row["load_factor"], solid), solid.stations,
                          comm)
            entry = {"status": rod["status"], "message": rod["message"]}
            if rod["status"] == "converged" and rod["backbone"] is not None:
                distance = backbone_distance(rod["backbone"], row["solid"]["backbone"])
                entry |= {"tip": rod["steps"][-1]["tip"], "backbone": rod["backbone"],
                          "distance_over_L": distance["max"] / solid.length,
                          "distance_x": distance["x"]}
            row["rod"][law] = entry
    summary["laws"] = list(config.laws)
    scale = cmp._tension_scale(config)
    summary["departures"] = cmp._departures(summary["table"], config, scale)
    if comm.rank == 0:
        cmp._write_outputs(out, summary, config)
    comm.barrier()
    return summary


def run_case(case, root: Path, comm, progress: bool, no_solid: bool = False) -> dict | None:
    raw = case_config(case)
    config = cmp.parse_compare(raw)
    out = root / case[0]
    path = out / "summary.json"
    summary = json.loads(path.read_text()) if path.exists() else None
    if no_solid:  # the sweep points the 3D solid reached (e.g. an unfinished fine mesh)
        if summary is None or not summary.get("table"):
            return None
        return add_missing_rods(summary, config, out, comm)
    if complete(summary, config):
        if all(law in row["rod"] for row in summary["table"] for law in config.laws):
            return summary
        return add_missing_rods(summary, config, out, comm)
    return cmp.run_compare(raw, out, comm, progress=progress)


def rows_of(summary: dict) -> list[dict]:
    """Per sweep point: tension, 3D tip theta, and per law the tip theta and d / L."""
    rows = []
    for row in summary["table"]:
        entry = {"tension": row.get("tension", row["load_factor"]),
                 "solid_theta": row["solid"]["tip"]["theta"], "rods": {}}
        for law, rod in row["rod"].items():
            if rod.get("tip"):
                entry["rods"][law] = {"theta": rod["tip"]["theta"],
                                      "distance_over_L": rod["distance_over_L"]}
        rows.append(entry)
    return rows


def table(results: dict) -> tuple[str, list[dict]]:
    """The README table: per case, the largest rod-vs-3D distances over the sweep."""
    lines = ["| 3D material | 3D mesh | 3D dofs | tensions | 3D tip rotation at the last | "
             + " | ".join(f"{law}: tip rotation error, max d/L" for law in LAWS) + " |",
             "|---" * (5 + len(LAWS)) + "|"]
    records = []
    for case in CASES:
        name, group = case[0], case[1]
        if name not in results:
            continue
        summary = results[name]
        rows = rows_of(summary)
        mesh = summary["model"].get("mesh", {}).get("size")
        last = rows[-1]
        record = {"case": name, "material": group, "mesh_size": mesh, "dofs": summary["dofs"],
                  "solid_tip_theta": last["solid_theta"], "laws": {}}
        cells = [group, f"{1e3 * mesh:g} mm" if mesh else "?", str(summary["dofs"]),
                 ", ".join(f"{r['tension']:g}" for r in rows) + " N",
                 f"{last['solid_theta']:.4f} rad"]
        for law in LAWS:
            errors = [abs(r["rods"][law]["theta"] - r["solid_theta"]) / abs(r["solid_theta"])
                      for r in rows if law in r["rods"]]
            distances = [r["rods"][law]["distance_over_L"] for r in rows if law in r["rods"]]
            if len(errors) < len(rows):
                cells.append("failed")
                continue
            record["laws"][law] = {"max_tip_rotation_error": max(errors),
                                   "max_distance_over_L": max(distances),
                                   "tip_theta_at_end": last["rods"][law]["theta"]}
            cells.append(f"{100 * max(errors):.2f} %, {100 * max(distances):.2f} %")
        lines.append("| " + " | ".join(cells) + " |")
        records.append(record)
    text = "\n".join(lines) + (
        "\n\nTip rotation error: max over the sweep points of |theta_rod - theta_3D| / "
        "theta_3D; d/L: max over the sweep and the backbone of |r_rod - r_3D| / L.\n")
    return text, records


def plot(results: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = list(dict.fromkeys(case[1] for case in CASES if case[0] in results))
    figure, axes = plt.subplots(2, len(groups), figsize=(4.2 * len(groups), 7.0), squeeze=False)
    for column, group in enumerate(groups):
        top, bottom = axes[0, column], axes[1, column]
        cases = [case for case in CASES if case[1] == group and case[0] in results]
        # the rods against the 3D sweep with the most points, the finest mesh among those
        finest = min(cases, key=lambda c: (-len(results[c[0]]["table"]),
                                           results[c[0]]["model"]["mesh"]["size"]))
        for case in cases:
            summary = results[case[0]]
            rows = rows_of(summary)
            mesh = 1e3 * summary["model"]["mesh"]["size"]
            grey = "black" if case is finest else "0.55"
            top.plot([0] + [r["tension"] for r in rows], [0] + [r["solid_theta"] for r in rows],
                     "-", marker="o", ms=4, color=grey, label=f"3D solid, mesh {mesh:g} mm")
        rows = rows_of(results[finest[0]])
        for law in LAWS:
            style, colour = STYLE[law]
            points = [(r["tension"], r["rods"][law]["theta"], r["solid_theta"]) for r in rows
                      if law in r["rods"]]
            if not points:
                continue
            tension, theta, solid = (np.array(v) for v in zip(*points, strict=True))
            top.plot(np.r_[0, tension], np.r_[0, theta], style, color=colour, lw=1.6,
                     label=LABELS[law])
            bottom.plot(tension, 100 * (theta - solid) / solid, style, marker="o", ms=3,
                        color=colour, label=LABELS[law])
        top.set_title(group, fontsize=10)
        top.set_xlabel("tendon tension [N]")
        top.set_ylabel("tip rotation [rad]")
        top.grid(alpha=0.3)
        top.legend(fontsize=7)
        mesh = 1e3 * results[finest[0]]["model"]["mesh"]["size"]
        bottom.axhline(0.0, color="black", lw=0.8)
        bottom.set_xlabel("tendon tension [N]")
        bottom.set_ylabel(f"(theta_rod - theta_3D) / theta_3D [%] (3D mesh {mesh:g} mm)")
        bottom.grid(alpha=0.3)
        bottom.legend(fontsize=7)
    figure.tight_layout()
    partial = path.with_name(f".{path.name}.partial.png")
    figure.savefig(partial, dpi=130)
    plt.close(figure)
    partial.replace(path)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="output folder")
    parser.add_argument("--cases", nargs="*", default=None,
                        help=f"subset of the cases ({', '.join(c[0] for c in CASES)})")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    parser.add_argument("--no-solid", action="store_true",
                        help="never run the 3D solid: use the sweep points already computed")
    args = parser.parse_args(argv)
    comm = MPI.COMM_WORLD
    chosen = [c for c in CASES if args.cases is None or c[0] in args.cases]
    unknown = set(args.cases or []) - {c[0] for c in CASES}
    if unknown:
        parser.error(f"unknown cases: {', '.join(sorted(unknown))}")
    results = {}
    for case in chosen:
        summary = run_case(case, args.out, comm, progress=not args.quiet,
                           no_solid=args.no_solid)
        if summary is None:
            print(f"{case[0]}: no 3D results yet", file=sys.stderr)
            continue
        if summary.get("status") != "converged" and not (args.no_solid and summary["table"]):
            print(f"{case[0]}: {summary.get('status')} ({summary.get('message')})",
                  file=sys.stderr)
            continue
        results[case[0]] = summary
    if comm.rank == 0 and results:
        text, records = table(results)
        atomic_write_text(args.out / "section_laws.md", text)
        atomic_write_json(args.out / "section_laws.json", {"cases": records})
        plot(results, args.out / "section_laws.png")
        print(text)
    return 0 if len(results) == len(chosen) else 1


if __name__ == "__main__":
    sys.exit(main())

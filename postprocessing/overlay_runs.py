"""Overlay the load-displacement curves of several `fe-beam static` / `fe-beam finger` runs.

    /usr/bin/python3 postprocessing/overlay_runs.py results/run_a results/run_b --out overlay.png

Each argument is an output folder (or its summary.json). The tip u, v (divided by the beam
length when the summary records it) and theta are plotted against the load factor, one line per
run, labelled with the folder name or with ``--labels``. Reads only summary.json: it works on
the results of an interrupted run as well (every converged step is already there).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


class RunError(ValueError):
    """A folder that does not hold a readable fe-beam summary."""


def load_run(path: Path) -> dict:
    summary_path = path / "summary.json" if path.is_dir() else path
    try:
        summary = json.loads(summary_path.read_text())
    except FileNotFoundError:
        message = f"{summary_path}: no such file (is {path} an fe-beam output folder?)"
        raise RunError(message) from None
    except json.JSONDecodeError as error:
        raise RunError(f"{summary_path}: not valid JSON ({error.msg})") from None
    steps = summary.get("steps")
    if not isinstance(steps, list) or not steps:
        raise RunError(f"{summary_path}: no converged load steps recorded")
    return summary


def curves(summary: dict) -> dict:
    """Load factors and tip u, v (over L when known) and theta of a summary."""
    length = summary.get("model", {}).get("length", 1.0)
    steps = summary["steps"]
    return {
        "load_factor": [s["load_factor"] for s in steps],
        "u": [s["tip"]["u"] / length for s in steps],
        "v": [s["tip"]["v"] / length for s in steps],
        "theta": [s["tip"]["theta"] for s in steps],
        "scaled": "model" in summary,
    }


def plot(runs: list[tuple[str, dict]], out: Path) -> None:
    figure, axes = plt.subplots(1, 3, figsize=(13, 4))
    for label, data in runs:
        for axis, key in zip(axes, ("u", "v", "theta"), strict=True):
            axis.plot(data["load_factor"], data[key], marker=".", label=label)
    scaled = all(data["scaled"] for _, data in runs)
    names = ("tip u / L", "tip v / L", "tip theta [rad]") if scaled else (
        "tip u [m]", "tip v [m]", "tip theta [rad]")
    for axis, name in zip(axes, names, strict=True):
        axis.set_xlabel("load factor")
        axis.set_ylabel(name)
        axis.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    figure.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(out, dpi=130)
    plt.close(figure)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path, help="output folders or summary.json files")
    parser.add_argument("--out", type=Path, default=Path("overlay.png"), help="PNG to write")
    parser.add_argument("--labels", nargs="+", help="one label per run (default: folder names)")
    args = parser.parse_args(argv)
    if args.labels and len(args.labels) != len(args.runs):
        print(f"overlay_runs: {len(args.labels)} labels for {len(args.runs)} runs",
              file=sys.stderr)
        return 2
    labels = args.labels or [p.name if p.is_dir() else p.parent.name for p in args.runs]
    try:
        runs = [(label, curves(load_run(path))) for label, path in zip(labels, args.runs,
                                                                         strict=True)]
    except RunError as error:
        print(f"overlay_runs: {error}", file=sys.stderr)
        return 2
    plot(runs, args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

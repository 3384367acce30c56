"""The 3D solid's modes in ``fe-beam solid`` (``[modes]``): the solid's frequencies (the engine:
`fe_beam.solvers.solid_modes`) beside the rod's with each law, matched by kind, the XDMF of the
mode shapes and the table the command prints."""

from __future__ import annotations

from dataclasses import replace

from dolfinx import fem

from fe_beam.analyses.transient import run_modes
from fe_beam.exports import Exports, XDMFExport
from fe_beam.exports.outputs import XDMFSeries
from fe_beam.fem import compat
from fe_beam.solvers.solid_modes import ROD_LAWS, solid_natural_frequencies

__all__ = ["modes_table", "rod_frequencies", "run_solid_modes"]


def rod_frequencies(static, count: int, loaded: bool, comm) -> dict:
    """The rod's lowest ``count`` frequencies with each law of ROD_LAWS
    (`fe_beam.analyses.transient.run_modes`, about the loaded static state when ``loaded``):
    {law: {"frequencies_hz", "kinds", "status", "message"}}."""

    result = {}
    for law in ROD_LAWS:
        model = static.model
        rod = replace(static, model=replace(model, options=replace(model.options, law=law)))
        summary = run_modes(rod, {"count": count, "prestress": loaded}, None, comm,
                            progress=False)
        result[law] = {"status": summary["status"], "message": summary.get("message", ""),
                       "frequencies_hz": list(summary.get("frequencies_hz", [])),
                       "kinds": list(summary.get("mode_kinds", []))}
    return result


def _matched(kinds: list[str], rod: dict) -> list[float | None]:
    """For each solid mode, the rod frequency of the same order among the rod's modes of the
    same kind (solid bending_y <-> rod bending, axial <-> axial); None for the out-of-plane
    bending and torsion modes, which a planar rod does not have."""
    pools = {"bending_y": [f for f, k in zip(rod["frequencies_hz"], rod["kinds"], strict=True)
                           if k == "bending"],
             "axial": [f for f, k in zip(rod["frequencies_hz"], rod["kinds"], strict=True)
                       if k == "axial"]}
    used = dict.fromkeys(pools, 0)
    matched = []
    for kind in kinds:
        if kind in pools and used[kind] < len(pools[kind]):
            matched.append(pools[kind][used[kind]])
            used[kind] += 1
        else:
            matched.append(None)
    return matched


# --- the command's part -------------------------------------------------------------------------


def run_solid_modes(run, config, out, comm) -> dict:
    """Modes of the `fe_beam.analyses.solid.SolidRun` ``run`` after its sweep, as configured by
    ``config.modes`` ({"count", "about"}), the rod's beside them, and ``modes.xdmf`` in ``out``
    (one time index per mode). Returns the ``modes`` entry of summary.json. Collective."""

    count, about = config.modes["count"], config.modes["about"]
    rho = config.modes["rho"]
    result = solid_natural_frequencies(run.problem, count, rho,
                                       undeformed=about == "undeformed")
    entry = {
        "status": "completed",
        "about": about,
        "load_factor": 0.0 if about == "undeformed" else run.load_factor,
        "count": count,
        "frequencies_hz": result.frequencies_hz,
        "eigenvalues": result.eigenvalues,
        "kinds": result.kinds,
        "energy_shares": result.shares,
        "unstable_count": result.unstable_count,
        "unstable_eigenvalues": result.unstable_eigenvalues,
        "rod_frequencies_hz": None,
        "rod": None,
        "shapes": None,
        "notes": list(result.notes),
    }
    if config.discretization.degree == 1:
        entry["notes"].append("[solid] order = 1: linear tetrahedra lock in bending, so the "
                              "bending frequencies come out too high (far too high on a coarse "
                              "mesh); use order = 2 for modes")
    if about == "loaded" and any(t.controlled_by_pull_in for t in config.tendon_loads):
        entry["notes"].append("tendons under pull-in control: the modes hold their converged "
                              "tensions constant (a motor holding the force, not the length)")
    spatial = config.rod is not None and getattr(config.rod.model, "kinematics",
                                                 "planar") == "spatial"
    if spatial:
        entry["notes"].append("no rod frequencies: the modes of the spatial rod ([model] "
                              "kinematics = \"spatial\") are not beside the solid's yet")
    elif config.rod is not None:
        # more rod modes than asked: the planar rod has no out-of-plane bending or torsion, so
        # its bending and axial modes that match the solid's lie further up its list
        rod = rod_frequencies(config.rod, 2 * count + 2, about == "loaded", comm)
        entry["rod_frequencies_hz"] = {law: r["frequencies_hz"][:count] for law, r in rod.items()}
        entry["rod"] = {
            law: {"status": r["status"], "message": r["message"], "kinds": r["kinds"][:count],
                  "matched_hz": (matched := _matched(result.kinds, r)),
                  "relative_difference": [None if f is None else f / s - 1.0
                                          for f, s in zip(matched, result.frequencies_hz,
                                                          strict=True)]}
            for law, r in rod.items()
        }
    else:
        entry["notes"].append(f"no rod frequencies: {config.rod_note}")
    if out is not None and config.output.xdmf and result.shapes:
        msh = run.problem.mesh
        degree = compat.geometry_degree(msh)
        space = compat.function_space(msh, compat.vector_element(msh, "Lagrange", degree))
        output = fem.Function(space, name="mode")

        class _Writer:
            def __init__(self):
                self.series = XDMFSeries(msh, out / "modes.xdmf")

            def write(self, t, flush=None):
                self.series.write(t, [output], flush)

            def close(self):
                self.series.close()

        files = Exports([XDMFExport(_Writer(), "mode")], comm, throttle=False)
        files.start()
        for index, shape in enumerate(result.shapes, start=1):
            output.interpolate(shape)
            files.on_step({"mode": float(index)})
        files.finish()
        entry["shapes"] = {"file": "modes.xdmf", "field": "mode",
                           "time": "mode number (1, 2, ...)", "normalised": "max |u| = 1"}
    return entry


def modes_table(modes: dict | None) -> list[str]:
    """The stdout table of ``summary["modes"]``: solid vs rod frequencies (both laws) and the
    relative difference rod / solid - 1."""
    if not modes or not modes.get("frequencies_hz"):
        return []
    rod = modes.get("rod") or {}
    laws = [law for law in ROD_LAWS if law in rod]
    header = f"{'mode':>4}  {'kind':<10} {'solid [Hz]':>12}"
    for law in laws:
        header += f"  {law + ' [Hz]':>17} {'diff':>8}"
    lines = [f"modes about the {modes['about']} state (load factor {modes['load_factor']:.4g}):",
             header]
    for i, (f, kind) in enumerate(zip(modes["frequencies_hz"], modes["kinds"], strict=True)):
        line = f"{i + 1:>4}  {kind:<10} {f:>12.6g}"
        for law in laws:
            g, d = rod[law]["matched_hz"][i], rod[law]["relative_difference"][i]
            line += (f"  {'-':>17} {'-':>8}" if g is None else f"  {g:>17.6g} {d:>+8.2%}")
        lines.append(line)
    if modes.get("rod"):
        lines.append("(diff = rod / solid - 1; the planar rod has no out-of-plane bending "
                     "(bending_z) or torsion modes)")
    lines += [f"note: {note}" for note in modes.get("notes", [])]
    return lines

"""What users see in the pictures (issue 9, item 10): legends inside their axes, units in the
legend labels, refinement titles that agree with the printed table, readable log-log ticks, and
a reason whenever the finger's 3D picture is not made."""

import json
import sys
from pathlib import Path
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
from matplotlib.figure import Figure  # noqa: E402

from fe_beam.cli import main  # noqa: E402

EXAMPLES = Path(__file__).parents[1] / "examples"


@pytest.fixture
def saved(monkeypatch):
    """Every figure saved during the test, inspected just before it is written:
    {file name: [(title, legend inside the axes?, legend labels, x tick labels), ...]}."""
    record = {}
    original = Figure.savefig

    def inspect(figure, path, *args, **kwargs):
        figure.canvas.draw()  # tick labels and legend positions as they will be written
        renderer = figure.canvas.get_renderer()
        panels = []
        for axes in figure.axes:
            legend = axes.get_legend()
            inside, labels = True, []
            if legend is not None:
                box, frame = legend.get_window_extent(renderer), axes.get_window_extent(renderer)
                inside = (box.x0 >= frame.x0 - 1 and box.x1 <= frame.x1 + 1
                          and box.y0 >= frame.y0 - 1 and box.y1 <= frame.y1 + 1)
                labels = [text.get_text() for text in legend.get_texts()]
            low, high = axes.get_xlim()
            ticks = [tick.label1.get_text() for tick in axes.xaxis.get_major_ticks()
                     if tick.label1.get_visible() and tick.label1.get_text()
                     and min(low, high) <= tick.get_loc() <= max(low, high)]
            panels.append((axes.get_title(), inside, labels, ticks))
        record[Path(path).name.split(".png")[0].lstrip(".") + ".png"] = panels
        return original(figure, path, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", inspect)
    return record


@pytest.mark.parametrize("shapes", [
    # nearly straight and flat (the finger's first load steps), 19 labelled curves
    [(f"load factor {k / 19:.3g}", 0.1 * k / 19 * 0.16) for k in range(1, 20)],
    # large deflection, curled past vertical, 10 curves
    [(f"load factor {k / 10:.3g}", 4.0 * k / 10) for k in range(1, 11)],
])
def test_deformed_shapes_legend_inside_axes(tmp_path, saved, shapes):
    from fe_beam.exports.outputs import plot_deformed_shapes

    x = np.linspace(0.0, 1.0, 60)
    drawn = []
    for label, curvature in shapes:  # arcs of constant curvature (the tip-moment elastica)
        angle = curvature * x
        u = (np.sin(angle) / curvature if curvature else x) - x
        v = (1 - np.cos(angle)) / curvature if curvature else 0 * x
        drawn.append((label, {"x": x, "u": u, "v": v}))
    plot_deformed_shapes(drawn, tmp_path / "deformed_shapes.png", "test", 1.0,
                         [("reference tip", 0.5, 0.5)])
    (title, inside, labels, _), = saved["deformed_shapes.png"]
    assert inside, labels
    assert len(labels) == len(shapes) + 2  # + undeformed, reference


def test_finger_pictures_legends_inside_and_3d_skip_is_explained(tmp_path, saved, monkeypatch,
                                                                 capsys):
    """Another finger than the example's (13 steps, 1.5 N, 30 elements); pyvista made
    unimportable: the run says why the 3D picture is missing, on stderr and in notes."""
    monkeypatch.setitem(sys.modules, "pyvista", None)  # import pyvista -> ImportError
    out = tmp_path / "finger"
    code = main(["finger", str(EXAMPLES / "finger.toml"), "--out", str(out), "--quiet",
                 "--set", "loads.steps=13", "--set", "tendons.0.tension=1.5",
                 "--set", "mesh.elements=30", "--set", "inverse.tip_angle=0.2"])
    err = capsys.readouterr().err
    assert code == 0, err
    for name in ("deformed_shapes.png", "fig3_9_backbone.png"):
        for title, inside, labels, _ in saved[name]:
            assert inside, (name, title, labels)
    labels = saved["fig3_9_backbone.png"][0][2]
    assert labels and all(label.startswith("tension ") and label.endswith(" N")
                          for label in labels)
    assert not (out / "finger_3d.png").exists()
    notes = json.loads((out / "summary.json").read_text())["notes"]
    assert any("finger_3d.png" in n and "pyvista is not installed" in n for n in notes), notes
    assert "finger_3d.png was not made: pyvista is not installed" in err


def test_finger_3d_skip_without_display(tmp_path, monkeypatch):
    """pyvista importable (a stand-in) but no DISPLAY and no Xvfb: the reason names both."""
    import shutil

    from fe_beam.analyses import finger

    monkeypatch.setitem(sys.modules, "pyvista", SimpleNamespace())
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.setattr(shutil, "which", lambda name: None)
    reason = finger.render_3d_skipped(tmp_path / "f.png", {}, None)
    assert reason is not None and "DISPLAY" in reason and "Xvfb" in reason


def test_compare_legend_labels_carry_units(tmp_path, saved):
    from fe_beam.analyses import compare

    assert compare.sweep_label(0.5, True) == "tension 0.5 N"
    assert compare.sweep_label(0.25, False) == "load factor 0.25"
    x = np.linspace(0, 0.1, 5)
    backbone = {"x": list(x), "u": [0.0] * 5, "v": list(0.1 * x**2)}
    tip = {"u": -0.001, "v": 0.01, "theta": 0.2}
    rows = [{"load_factor": f, "tension": 2.0 * f,
             "solid": {"backbone": backbone, "tip": tip},
             "rod": {"nonstandard": {"backbone": backbone, "tip": tip, "distance_over_L": 0.01}}}
            for f in (0.25, 1.0)]
    config = SimpleNamespace(laws=("nonstandard",), solid=SimpleNamespace(length=0.1))
    compare._plot(tmp_path, {"table": rows, "sweep": {"tensions": [0.5, 2.0]}}, config)
    labels = saved["backbones.png"][0][2]
    assert "3D solid, tension 0.5 N" in labels and "rod, non-standard law, tension 2 N" in labels
    compare._plot(tmp_path, {"table": rows, "sweep": {"tensions": None}}, config)
    assert "3D solid, load factor 0.25" in saved["backbones.png"][0][2]


def refinement_summary(values: dict, h0=0.025, ratio=2.0):
    from fe_beam.analyses.refine import analyse_sequence

    count = len(next(iter(values.values())))
    levels = [{"level": k, "h": h0 / ratio**k, "elements": 40 * 2**k, "dofs": 243 * 2**k,
               "wall_time_s": 0.1, "values": {q: v[k] for q, v in values.items()}}
              for k in range(count)]
    return {"kind": "rod", "quantities": list(values), "levels": levels, "notes": [],
            "refined": "mesh.elements",
            "ratio": ratio, "analysis": {q: analyse_sequence(v, ratio).as_dict()
                                         for q, v in values.items()}}


def test_refinement_title_matches_the_table_and_ticks_are_readable(tmp_path, saved):
    """4th order down to round-off at the finest level (the table: 4.000 then "noise"); another
    quantity of clean 2nd order; the x ticks name every mesh size on a sub-decade range."""
    from fe_beam.analyses.refine import format_table, plot_convergence

    exact = -0.7138618424
    quartic = [exact + 1.1e-8 * 16 ** -k for k in range(3)] + [exact + 2e-11]
    quadratic = [1.2 + 0.3 * 4.0 ** -k for k in range(4)]
    summary = refinement_summary({"tip.v": quartic, "tip.theta": quadratic})
    table = format_table(summary)
    assert " 4.000 " in table and "noise" in table
    plot_convergence(summary, tmp_path / "refinement.png")
    (title_v, _, _, ticks_v), (title_theta, _, _, ticks_theta) = saved["refinement.png"]
    assert "order 4.00" in title_v and "undefined" not in title_v
    assert "round-off" in title_v
    assert "order 2.00" in title_theta
    assert len(ticks_v) >= 3 and len(ticks_theta) >= 3, (ticks_v, ticks_theta)
    # the labels are the mesh sizes
    assert {float(t) for t in ticks_theta} >= {0.025, 0.0125, 0.00625}


def test_refinement_title_says_undefined_only_when_no_level_has_an_order(tmp_path, saved):
    from fe_beam.analyses.refine import plot_convergence

    summary = refinement_summary({"tip.u": [0.1, 0.2, 0.15, 0.18]})  # oscillating
    plot_convergence(summary, tmp_path / "refinement.png")
    title = saved["refinement.png"][0][0]
    assert "order undefined" in title

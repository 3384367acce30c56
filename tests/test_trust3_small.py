"""Issue 20, item 5: the small ones (messages, labels, notes)."""

import json
import signal

from test_validity import run_cli, with_map

from fe_beam import runctl


def test_validity_ctrl_c_says_which_points_are_done(tmp_path, monkeypatch):
    """A 3 x 1 map interrupted while its third point runs (the inner compare's Interrupted,
    which says "load factor 0 of the sweep"): the closing line and the summary say 2 of 3
    points are done and which."""
    from fe_beam import validity

    solved = []

    def stand_in(point, config, comm):
        solved.append(point.name)
        if len(solved) == 3:  # as fe_beam.compare.run_compare stops its solid sweep
            stop = runctl.Interrupted(signal.SIGINT)
            stop.stopped("load factor 0 of the sweep", "after load factor 0")
            raise stop
        tip = {"u": -0.001 * point.x, "v": 0.01 * point.x, "theta": 0.1 * point.x}
        rod = {"status": "converged", "message": "", "tip": tip,
               "tip_error": {"distance_over_L": 0.0, "rotation": 0.0}, "backbone_distance": 0.0}
        return {"i": point.i, "j": point.j, "x": point.x, "y": point.y, "hash": point.hash,
                "status": "converged", "message": "",
                "solid": {"tip": tip, "dofs": 1, "mesh_size": 0.01, "discretisation_error": None},
                "rod": {law: dict(rod) for law in config.laws}}

    monkeypatch.setattr(validity, "solve_point", stand_in)
    config = with_map(x_values=[0.2, 0.4, 0.6])
    del config["validity"]["second_mesh_ratio"]
    config["output"]["plots"] = False
    code, _, stderr, out = run_cli("validity", tmp_path, config)
    assert code == 130, stderr
    line = [x for x in stderr.splitlines() if x.startswith("fe-beam: interrupted")]
    assert len(line) == 1, stderr
    assert "load factor 0" not in line[0], line[0]
    assert "2 of 3 validity points done" in line[0] and "0_0, 1_0" in line[0], line[0]

    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert "2 of 3 points done (0_0, 1_0)" in summary["message"], summary["message"]

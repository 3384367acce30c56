"""``fe-beam solid``: the 3D hyperelastic finger from the rod's TOML configuration.

The configuration uses the rod's tables (`fe_beam.config.schema`) for the geometry, the material,
the
tip force, the load steps and the ``[[tendons]]`` (as in `fe_beam.analyses.finger`), plus a
``[solid]``
table (`SOLID_KEYS`) for the 3D law, the formulation and the mesh. The same configuration is also
run through the 1D rod model (`fe_beam.analyses.static.solve_static`) with the rod's E and G taken
from the
small-strain limit of the 3D law, so that both results can be compared and opened together in
ParaView (same coordinates: x along the finger, y up, z across; the origin is the centroid of the
clamped face, which is where the rod's axis starts).

The code lives in three parts, re-exported here:

- `fe_beam.config.solid`: the ``[solid]`` table and `parse_solid` (no finite-element code;
  imported with this module),
- `fe_beam.analyses.solid`: `run_solid`, `SolidRun` and the files it writes,
- `fe_beam.analyses.solid_rod`: the rod companion (`run_rod`, `backbone_distance`,
`write_rod_xdmf`);

the last two load dolfinx (and gmsh) when one of their names is first used.

3D set-up (docs/theory.md, 3D finger and cable): body 0 <= x <= L, |y| <= H(x)/2, |z| <= B/2, with
H(x) = h + (h_tip - h) x / L is clamped at x = 0; ``[loads] tip_force`` is a uniform dead traction
on the tip face; a tendon with offset delta(x) becomes the cable through (x, delta(x), z) with
z = 0 (several branches of one tendon, e.g. a loop: z = B ((k + 1/2)/n - 1/2), k = 0 .. n-1).

Results: `run_solid` returns (and writes into ``out``) a summary whose ``steps`` hold, per
converged load step, the load factor, the tendon tensions, the tip-face centroid displacement and
rotation ``tip = {u, v, theta}``, the backbone (deformed centroids of the sections at the
``backbone_points`` stations), the Newton and linear iterations and the largest principal stretch.
"""

from __future__ import annotations

from fe_beam.config.solid import (  # noqa: F401
    FORMULATIONS,
    MATERIAL_KEYS,
    MAX_CELLS,
    NEARLY_INCOMPRESSIBLE_NU,
    SOLID_KEYS,
    SOLID_ONLY_TABLES,
    SOLVERS,
    UNSUPPORTED_LOADS,
    SolidConfig,
    _cables,
    _check_rod_only_settings,
    _rod_static,
    _section,
    _tip_force,
    parse_solid,
    solid_dofs_estimate,
    solid_law,
)
from fe_beam.lazy import lazy_getattr

__all__ = [
    "SOLID_KEYS",
    "SolidConfig",
    "SolidRun",  # noqa: F822 (lazy, below)
    "backbone_distance",  # noqa: F822 (lazy, below)
    "parse_solid",
    "rod_backbone",  # noqa: F822 (lazy, below)
    "run_rod",  # noqa: F822 (lazy, below)
    "run_solid",  # noqa: F822 (lazy, below)
    "solid_law",
]

# names of the run and the rod companion: loaded with dolfinx when first used (PEP 562)
_LAZY = {
    "SolidRun": "fe_beam.analyses.solid",
    "check_solid_work": "fe_beam.analyses.solid",
    "run_solid": "fe_beam.analyses.solid",
    "_run_solid": "fe_beam.analyses.solid",
    "_write_tables": "fe_beam.analyses.solid",
    "_plot_solid": "fe_beam.analyses.solid",
    "rod_backbone": "fe_beam.analyses.solid_rod",
    "run_rod": "fe_beam.analyses.solid_rod",
    "backbone_distance": "fe_beam.analyses.solid_rod",
    "write_rod_xdmf": "fe_beam.analyses.solid_rod",
}


__getattr__ = lazy_getattr("fe_beam.analyses.solid_driver", _LAZY, globals())

"""One driver per subcommand (``fe-beam COMMAND``): what a run computes, records and writes.

The drivers load dolfinx and PETSc with their modules: this package imports them when first
used (PEP 562), so that ``from fe_beam import analyses`` stays light.
"""

import importlib

DRIVERS = ("static", "finger", "transient", "compare", "validity", "refine", "calibrate",
           "design", "path", "buckling", "sensitivity", "solid", "solid_rod", "solid_driver",
           "solid_modes", "dynamic", "modes", "result")


def __getattr__(name: str):
    if name in DRIVERS:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

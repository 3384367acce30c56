"""The import paths of fe_beam before its modules moved into layers (model, config, fem,
solvers, exports, analyses), so that scripts written against them keep working. An old name
that moved whole is the moved module itself (``import fe_beam.static`` is
`fe_beam.analyses.static`: attributes, monkeypatches and isinstance checks are shared); one
that was split (a tuple: e.g. `fe_beam.buckling`, whose engine is `fe_beam.solvers.buckling`
and whose driver is `fe_beam.analyses.buckling`) is a module that finds each name in the
parts, in order. New code imports the new paths; this table is kept for users' scripts
(`tests/test_old_import_paths.py` checks every public name of the old modules)."""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import types

MOVED = {
    "fe_beam.beam": "fe_beam.fem.rod",
    "fe_beam.buckling": ("fe_beam.solvers.buckling", "fe_beam.analyses.buckling"),
    "fe_beam.calibrate": ("fe_beam.analyses.calibrate", "fe_beam.config.calibrate"),
    "fe_beam.compare": "fe_beam.analyses.compare",
    "fe_beam.compat": "fe_beam.fem.compat",
    "fe_beam.continuation": "fe_beam.solvers.continuation",
    "fe_beam.critical": "fe_beam.solvers.critical",
    "fe_beam.design": ("fe_beam.analyses.design", "fe_beam.config.design"),
    "fe_beam.dynamics": "fe_beam.solvers.dynamics",
    "fe_beam.energy_momentum": "fe_beam.solvers.energy_momentum",
    "fe_beam.finger": "fe_beam.analyses.finger",
    "fe_beam.inertia": "fe_beam.solvers.inertia",
    "fe_beam.laws": "fe_beam.fem.kinematics",
    "fe_beam.material_laws": "fe_beam.config.material_laws",
    "fe_beam.materials": "fe_beam.model.materials",
    "fe_beam.model.buckling": "fe_beam.config.buckling",
    "fe_beam.model.compare": "fe_beam.config.compare",
    "fe_beam.model.finger": "fe_beam.config.finger",
    "fe_beam.model.path": "fe_beam.config.path",
    "fe_beam.model.transient": "fe_beam.config.transient",
    "fe_beam.model.validity": "fe_beam.config.validity",
    "fe_beam.modes": "fe_beam.solvers.modes",
    "fe_beam.mpi": "fe_beam.fem.mpi",
    "fe_beam.outputs": "fe_beam.exports.outputs",
    "fe_beam.path": "fe_beam.analyses.path",
    "fe_beam.plotting": "fe_beam.exports.plotting",
    "fe_beam.realtime": "fe_beam.solvers.realtime",
    "fe_beam.refine": ("fe_beam.analyses.refine", "fe_beam.config.refine"),
    "fe_beam.section_laws": ("fe_beam.fem.section_laws", "fe_beam.model.fibre"),
    "fe_beam.sections": "fe_beam.model.sections",
    "fe_beam.sensitivity": "fe_beam.analyses.sensitivity",
    "fe_beam.solid.cable": "fe_beam.fem.solid.cable",
    "fe_beam.solid.config": "fe_beam.config.solid",
    "fe_beam.solid.driver": "fe_beam.analyses.solid_driver",
    "fe_beam.solid.export": "fe_beam.exports.solid",
    "fe_beam.solid.geometry": "fe_beam.fem.solid.geometry",
    "fe_beam.solid.materials": "fe_beam.model.hyperelastic",
    "fe_beam.solid.modes": ("fe_beam.solvers.solid_modes", "fe_beam.analyses.solid_modes"),
    "fe_beam.solid.problem": "fe_beam.solvers.solid",
    "fe_beam.solid.rod": "fe_beam.analyses.solid_rod",
    "fe_beam.solid.run": "fe_beam.analyses.solid",
    "fe_beam.solver": ("fe_beam.solvers.newton", "fe_beam.solvers.continuation"),
    "fe_beam.static": "fe_beam.analyses.static",
    "fe_beam.tendons": ("fe_beam.fem.tendons", "fe_beam.solvers.pull_in"),
    "fe_beam.transient": "fe_beam.analyses.transient",
    "fe_beam.validity": "fe_beam.analyses.validity",
}


class MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds an old module name and loads it as the module it moved to (the same object:
    attributes, monkeypatches and isinstance checks are shared)."""

    def find_spec(self, fullname, path=None, target=None):
        if fullname in MOVED:
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        target = MOVED[spec.name]
        if isinstance(target, str):
            return importlib.import_module(target)
        parts = [importlib.import_module(name) for name in target]
        module = types.ModuleType(spec.name, parts[0].__doc__)

        def attribute(name: str):
            for part in parts:
                if hasattr(part, name):
                    return getattr(part, name)
            raise AttributeError(f"module {spec.name!r} has no attribute {name!r}")

        module.__getattr__ = attribute
        module.__all__ = sorted({n for part in parts for n in getattr(part, "__all__", ())})
        return module

    def exec_module(self, module) -> None:
        return None


def install() -> None:
    """Put the finder first on sys.meta_path (once)."""
    if not any(isinstance(finder, MovedModules) for finder in sys.meta_path):
        sys.meta_path.insert(0, MovedModules())

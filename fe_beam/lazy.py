"""Module attributes imported when first used (PEP 562), so that light imports (config
validation, `fe-beam --help`) do not load dolfinx and PETSc."""

from __future__ import annotations

import importlib


def lazy_getattr(module: str, names: dict[str, str], namespace: dict):
    """A module ``__getattr__`` that imports ``names[name]`` (a module path) on first use and
    caches the attribute in ``namespace`` (the module's globals())."""

    def attribute(name: str):
        if name in names:
            value = getattr(importlib.import_module(names[name]), name)
            namespace[name] = value
            return value
        raise AttributeError(f"module {module!r} has no attribute {name!r}")

    return attribute


class LazyModule:
    """A stand-in for a third-party module that imports it on first attribute access, e.g.
    ``ufl = LazyModule("ufl")`` in a model module: validating a configuration builds the law
    dataclasses without loading UFL, building a law's energy loads it."""

    def __init__(self, name: str):
        self._name = name

    def __getattr__(self, attribute: str):
        return getattr(importlib.import_module(self._name), attribute)

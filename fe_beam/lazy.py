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

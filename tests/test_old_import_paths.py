"""Scripts written against fe_beam before the layers keep working: every public name (the old
modules' ``__all__``, recorded from the last commit before the move in
tests/data/old_public_names.json) resolves through its old import path (`fe_beam._moved`), and a
module that moved whole is the same module object under both names."""

from __future__ import annotations

import importlib
import json
from pathlib import Path

import pytest

OLD = json.loads((Path(__file__).parent / "data" / "old_public_names.json").read_text())


@pytest.mark.parametrize("module", sorted(OLD))
def test_every_old_public_name_resolves(module):
    old = importlib.import_module(module)
    missing = [name for name in OLD[module] if not hasattr(old, name)]
    assert not missing, f"{module}: {missing}"


def test_a_module_moved_whole_is_the_same_object():
    import fe_beam.static

    import fe_beam.analyses.static

    assert fe_beam.static is fe_beam.analyses.static
    from fe_beam.buckling import rod_buckling, run_buckling  # split: engine and driver

    from fe_beam.solvers.buckling import rod_buckling as engine

    assert rod_buckling is engine and run_buckling.__module__ == "fe_beam.analyses.buckling"

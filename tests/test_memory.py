"""Long sessions keep nothing of the runs they finished.

CPython 3.12.0-3.12.8 and 3.13.0-3.13.1 keep every instance a ``functools.singledispatchmethod``
was looked up on (gh-127750). UFL's derivative traversers on dolfinx 0.10+ are such instances,
and each kept its forms, their meshes and the meshes' MPI communicators. MPICH allows 2048 per
process, so the PyPI stack's serial suite failed after ~750 tests and then crashed (exit 15, a
segfault). `fe_beam.fem.compat` puts CPython's fix in place on those versions.
"""

import copy
import functools
import gc
import tomllib
import weakref
from pathlib import Path

import pytest
from mpi4py import MPI

import fe_beam
from fe_beam import cli
from fe_beam.fem import compat

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


class _Traverser:
    @functools.singledispatchmethod
    def process(self, o):
        return ("object", o)

    @process.register(int)
    def _(self, o):
        return ("int", o)


def test_a_singledispatchmethod_keeps_no_instance_alive():
    """An instance whose singledispatchmethod was called is freed with its last reference."""
    assert compat.fix_singledispatchmethod_leak() == compat.SINGLEDISPATCHMETHOD_LEAKS
    traverser = _Traverser()
    assert traverser.process(3) == ("int", 3) and traverser.process("a") == ("object", "a")
    alive = weakref.ref(traverser)
    del traverser
    gc.collect()
    assert alive() is None


@pytest.mark.parametrize("command", ["static", "modes"])
def test_runs_in_one_process_give_back_their_communicators(command, monkeypatch, tmp_path):
    """Three runs of other meshes (the problem cache off): no MPI communicator is left behind
    (each leaked 7 to 22 before the fix)."""
    monkeypatch.setenv("FE_BEAM_PROBLEM_CACHE", "0")
    base = tomllib.loads((EXAMPLES / "cantilever.toml").read_text())
    comm = MPI.COMM_WORLD

    def run(elements):
        config = copy.deepcopy(base)
        config.setdefault("mesh", {})["elements"] = elements
        fe_beam.run(command, config)
        gc.collect()
        return cli.spare_communicators(comm, up_to=4096)

    first = run(6)  # imports, compiled forms and caches of the first run are not a leak
    after = [run(elements) for elements in (7, 8, 9)]
    assert after == [first] * 3, (first, after)

"""A C file left by a killed FFCx compile no longer blocks later runs (issue 28, section 4)."""

import os
import time

from ffcx.codegeneration import jit as ffcx_jit

from fe_beam.fem import compat


def _lock(directory, name, age):
    path = directory / f"{name}.c"
    path.write_text("/* interrupted */")
    then = time.time() - age
    os.utime(path, (then, then))
    return path


def test_only_old_locks_without_marker_are_removed(tmp_path):
    stale = _lock(tmp_path, "libffcx_forms_stale", 2 * compat.STALE_JIT_LOCK_SECONDS)
    fresh = _lock(tmp_path, "libffcx_forms_fresh", 1.0)  # another process compiling now
    done = _lock(tmp_path, "libffcx_forms_done", 2 * compat.STALE_JIT_LOCK_SECONDS)
    (tmp_path / "libffcx_forms_done.c.cached").write_text("")
    assert compat.clear_stale_jit_lock(tmp_path, "libffcx_forms_stale")
    assert not compat.clear_stale_jit_lock(tmp_path, "libffcx_forms_fresh")
    assert not compat.clear_stale_jit_lock(tmp_path, "libffcx_forms_done")
    assert not compat.clear_stale_jit_lock(tmp_path, "libffcx_forms_absent")
    assert not stale.exists() and fresh.exists() and done.exists()


def test_ffcx_claims_a_module_whose_lock_is_stale(tmp_path):
    """Without the clean-up FFCx waits for the marker and raises TimeoutError."""
    name = "libffcx_forms_fe_beam_stale_lock_test"
    _lock(tmp_path, name, 2 * compat.STALE_JIT_LOCK_SECONDS)
    start = time.perf_counter()
    found = ffcx_jit.get_cached_module(name, ["form_0"], tmp_path, 2)
    assert found == (None, None)  # not cached: this process compiles it
    assert time.perf_counter() - start < 1.0
    assert (tmp_path / f"{name}.c").exists()  # claimed again by this process

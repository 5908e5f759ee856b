"""control/jit.py: a kernel's cache entry is refused once any module of the control package
changed (numba alone checks only the kernel's own file, not the compiled functions it calls)."""

from __future__ import annotations

import importlib.util
import sys

from compliant_docking.control import jit


def _module_with_a_kernel(tmp_path, name):
    path = tmp_path / f"{name}.py"
    path.write_text(
        "from compliant_docking.control.jit import kernel\n\n\n"
        "@kernel\ndef plus_one(x):\n    return x + 1.0\n"
    )
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def test_the_digest_follows_every_source_of_the_package(tmp_path):
    (tmp_path / "lie").mkdir()
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "lie" / "b.py").write_text("y = 2\n")
    before = jit.sources_digest(tmp_path)
    assert jit.sources_digest(tmp_path) == before
    (tmp_path / "lie" / "b.py").write_text("y = 3\n")  # a file a kernel's callee lives in
    assert jit.sources_digest(tmp_path) != before
    assert jit.sources_digest() == jit.SOURCES_DIGEST


def test_a_cache_entry_from_other_sources_is_refused(tmp_path):
    module = _module_with_a_kernel(tmp_path, "kernel_cache_probe")
    try:
        assert module.plus_one(1.0) == 2.0  # compiles and writes the cache entry
        cache_file = module.plus_one._cache._cache_file
        stamp = cache_file._source_stamp
        assert stamp[1] == jit.SOURCES_DIGEST
        assert cache_file._load_index(), "the entry just written is loaded back"
        cache_file._source_stamp = (stamp[0], "another digest")  # as after an edit elsewhere
        assert cache_file._load_index() == {}, "numba would recompile"
    finally:
        sys.modules.pop("kernel_cache_probe", None)


def test_the_controllers_kernels_carry_the_digest():
    from compliant_docking.control import kernel_blocks, se3_kernel
    from compliant_docking.control.hqp import kernel as hqp_kernel

    kernels = [
        obj
        for module in (kernel_blocks, se3_kernel, hqp_kernel)
        for obj in vars(module).values()
        if hasattr(obj, "_cache") and hasattr(obj, "py_func")
    ]
    assert len(kernels) >= 8
    for k in kernels:
        assert k._cache._cache_file._source_stamp[1] == jit.SOURCES_DIGEST, k.py_func.__name__

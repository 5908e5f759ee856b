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
        "@kernel\ndef plus_one(x):\n    return x + 1.0\n\n\n"
        "@kernel\ndef times_three(x):\n    return 3.0 * x\n"
    )
    return _load(path, name)


def _load(path, name):
    """The module at ``path`` imported afresh, as a new process would: new dispatchers that
    find their machine code in the cache beside the file."""
    sys.modules.pop(name, None)
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


def _cache_files(tmp_path, function: str, suffix: str):
    return sorted((tmp_path / "__pycache__").glob(f"*.{function}-*{suffix}"))


def test_a_truncated_cache_entry_is_compiled_again_and_said(tmp_path, capsys):
    """A data file cut short (a full disk, a copy that stopped): numba alone raised
    "pickle data was truncated" at every run until ``__pycache__`` was deleted."""
    module = _module_with_a_kernel(tmp_path, "truncated_probe")
    try:
        assert module.plus_one(1.0) == 2.0  # compiled, cached
        [data] = _cache_files(tmp_path, "plus_one", ".nbc")
        data.write_bytes(data.read_bytes()[:200])
        fresh = _load(tmp_path / "truncated_probe.py", "truncated_probe")
        assert fresh.plus_one(1.0) == 2.0
        err = capsys.readouterr().err
        assert "numba: the cached machine code of truncated_probe.plus_one is unusable (" in err
        assert "compiling it again" in err
        again = _load(tmp_path / "truncated_probe.py", "truncated_probe")
        assert again.plus_one(1.0) == 2.0 and sum(again.plus_one.stats.cache_hits.values()) == 1
        assert capsys.readouterr().err == ""  # the entry was replaced: a plain cache hit
    finally:
        sys.modules.pop("truncated_probe", None)


def test_a_corrupt_cache_index_is_compiled_again_and_said(tmp_path, capsys):
    module = _module_with_a_kernel(tmp_path, "index_probe")
    try:
        assert module.plus_one(1.0) == 2.0
        [index] = _cache_files(tmp_path, "plus_one", ".nbi")
        index.write_bytes(index.read_bytes()[:10])
        fresh = _load(tmp_path / "index_probe.py", "index_probe")
        assert fresh.plus_one(1.0) == 2.0
        assert "index_probe.plus_one is unusable" in capsys.readouterr().err
        again = _load(tmp_path / "index_probe.py", "index_probe")
        assert again.plus_one(1.0) == 2.0 and sum(again.plus_one.stats.cache_hits.values()) == 1
    finally:
        sys.modules.pop("index_probe", None)


def test_another_functions_cache_entry_is_never_run(tmp_path, capsys):
    """The data files of two kernels swapped: numba alone ran the other kernel's code
    (plus_one(3) gave 9, with no error)."""
    module = _module_with_a_kernel(tmp_path, "swapped_probe")
    try:
        assert module.plus_one(3.0) == 4.0 and module.times_three(3.0) == 9.0
        [a] = _cache_files(tmp_path, "plus_one", ".nbc")
        [b] = _cache_files(tmp_path, "times_three", ".nbc")
        a_bytes, b_bytes = a.read_bytes(), b.read_bytes()
        a.write_bytes(b_bytes)
        b.write_bytes(a_bytes)
        fresh = _load(tmp_path / "swapped_probe.py", "swapped_probe")
        assert fresh.plus_one(3.0) == 4.0 and fresh.times_three(3.0) == 9.0
        err = capsys.readouterr().err
        assert "swapped_probe.plus_one is unusable (it holds the code of times_three)" in err
        assert "swapped_probe.times_three is unusable (it holds the code of plus_one)" in err
    finally:
        sys.modules.pop("swapped_probe", None)


def test_an_unwritable_cache_is_said_and_the_kernel_still_runs(tmp_path, capsys, monkeypatch):
    module = _module_with_a_kernel(tmp_path, "unwritable_probe")
    try:
        cache_file = module.plus_one._cache._cache_file

        def refuse(*args):
            raise PermissionError("read-only file system")

        monkeypatch.setattr(cache_file, "_save_index", refuse)
        monkeypatch.setattr(cache_file, "_save_data", refuse)
        assert module.plus_one(1.0) == 2.0
        assert "could not cache the machine code of unwritable_probe.plus_one" in capsys.readouterr().err
    finally:
        sys.modules.pop("unwritable_probe", None)


def test_numbas_private_cache_objects_are_still_there():
    """jit.py relies on numba's private cache objects in one place (_checked_cache): if numba
    changes them, this fails first, naming what is gone."""
    import numba

    dispatcher = numba.njit(cache=True)(lambda x: x)
    cache = dispatcher._cache
    for owner, names in (
        (cache, ("load_overload", "save_overload", "flush", "_cache_file")),
        (cache._cache_file, ("_source_stamp", "_load_index", "_save_index", "_save_data")),
    ):
        for name in names:
            assert hasattr(owner, name), f"numba {numba.__version__}: {type(owner).__name__}.{name} is gone"
    assert dispatcher(1.0) == 1.0
    [found] = dispatcher.overloads.values()
    assert found.fndesc.qualname == dispatcher.py_func.__qualname__ and found.signature.args

"""The sweep's loky workers: what sweep/workers.py relies on is still in the installed joblib."""

from __future__ import annotations

from compliant_docking.sweep import workers


def test_the_installed_joblib_offers_what_the_workers_module_relies_on():
    """Fails first when a joblib release changes a non-public object sweep/workers.py uses."""
    assert workers.problems() == [], "\n".join(workers.problems())


def test_a_changed_joblib_is_named(monkeypatch):
    from joblib._parallel_backends import LokyBackend
    from joblib.externals.loky import reusable_executor

    monkeypatch.setattr(LokyBackend, "_prepare_worker_env", lambda self: {})
    monkeypatch.delattr(reusable_executor, "_executor")
    found = workers.problems()
    assert len(found) == 2 and all("joblib" in p and "sweep/workers.py" in p for p in found)
    assert "_prepare_worker_env('self',)" in found[0] and "_executor" in found[1]

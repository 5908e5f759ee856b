"""A missing optional feature names its extra in one line (compliant_docking/extras.py)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from compliant_docking import extras
from compliant_docking.run.runner import execute
from tests.helpers import REPO_ROOT, make_cfg


def test_require_names_the_missing_modules_and_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "av", None)  # as if PyAV were not installed
    with pytest.raises(extras.MissingExtra) as err:
        extras.require("video", "av", "json")
    message = str(err.value)
    assert message.startswith("render=video needs av (the `video` extra): ")
    assert "pip install 'compliant-docking[video]'" in message and "pip install -e '.[video]'" in message
    assert "\n" not in message
    extras.require("video", "json")  # present: nothing happens


def test_every_extra_named_by_a_hint_is_an_extra_of_the_package():
    import tomllib

    declared = tomllib.loads((REPO_ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert set(extras.EXTRAS) <= set(declared)


def test_a_video_without_its_extra_says_which_extra_and_keeps_the_results(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "av", None)
    cfg = make_cfg("task.duration=0.2", "task.progress=false", "render=video")
    record = execute(cfg, tmp_path, figures=False, echo=False)
    assert "the `video` extra" in record["video_error"]
    assert (tmp_path / "timeseries.parquet").is_file()


def test_a_cluster_launcher_without_its_extra_is_refused_naming_the_extra(tmp_path):
    code = (
        "import sys\n"
        "sys.modules['hydra_plugins.hydra_submitit_launcher'] = None\n"
        "from compliant_docking.cli import main\n"
        f"sys.exit(main(['-m', 'hydra/launcher=submitit_local', 'controller=impedance,hqp', "
        f"'hydra.sweep.dir={tmp_path / 'sweep'}']))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO_ROOT, capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 2
    assert "(the `cluster` extra): pip install 'compliant-docking[cluster]'" in result.stderr
    assert not (tmp_path / "sweep").exists()

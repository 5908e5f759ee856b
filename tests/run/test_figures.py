"""Per-run figures: a single run draws them, a sweep job does not unless ``figures=true``,
and a job that draws nothing never imports matplotlib."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest
from omegaconf import OmegaConf

from compliant_docking.run.figures import wanted
from tests.helpers import REPO_ROOT, SHORT_SWEEP


@pytest.mark.parametrize(
    "value, sweep, expected",
    [(None, False, True), (None, True, False), (True, True, True), (False, False, False)],
)
def test_figures_null_means_single_runs_draw_and_sweep_jobs_do_not(value, sweep, expected):
    assert wanted(OmegaConf.create({"figures": value}), sweep=sweep) is expected


def test_a_job_that_draws_nothing_never_imports_matplotlib(tmp_path):
    """Through the command line, in one fresh process: a single run with figures=false and a
    sweep job (default: no figures) leave matplotlib unimported; figures=true in a sweep
    draws the job's figures (and so imports it)."""
    short = [*SHORT_SWEEP, "task.duration=0.2"]  # 0.2 s of each run: what is drawn, not what docks
    code = textwrap.dedent(f"""
        import json, sys
        from compliant_docking.cli import main

        def drawn():
            return any(m == "matplotlib" or m.startswith(("matplotlib.", "scienceplots")) for m in sys.modules)

        seen = {{}}
        quiet = ["hydra/launcher=basic", "hydra.callbacks.sweep.figures=false"]
        main([*{short!r}, "figures=false", "hydra.run.dir={tmp_path / "single"}"])
        seen["single run, figures=false"] = drawn()
        main(["-m", *{short!r}, *quiet, "hydra.sweep.dir={tmp_path / "sweep"}"])
        seen["sweep job"] = drawn()
        main(["-m", *{short!r}, *quiet, "figures=true", "hydra.sweep.dir={tmp_path / "drawn"}"])
        seen["sweep job, figures=true"] = drawn()
        print(json.dumps(seen))
    """)
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO_ROOT, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr[-3000:]
    seen = json.loads(result.stdout.strip().splitlines()[-1])
    assert seen == {"single run, figures=false": False, "sweep job": False, "sweep job, figures=true": True}
    assert not (tmp_path / "single" / "figures").exists()
    assert (tmp_path / "single" / "metrics.json").is_file()
    assert len(list((tmp_path / "sweep").glob("*/metrics.json"))) == 1
    assert not list((tmp_path / "sweep").glob("*/figures"))
    [job] = [p for p in (tmp_path / "drawn").iterdir() if p.is_dir() and p.name[0].isdigit()]
    assert sorted(p.name for p in (job / "figures").iterdir()) == [
        "contact_force.png",
        "joint_torques.png",
        "tcp_tracking.png",
        "tracking_error.png",
    ]

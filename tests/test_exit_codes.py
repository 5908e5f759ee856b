"""The exit status: one table (compliant_docking/exit_codes.py, docs/exit_codes.md, the
README and ``--help``), the same meaning in every command, each status pinned in-process."""

import json
import re
import signal

import pytest

from compliant_docking import exit_codes
from compliant_docking.run import interrupt
from tests.helpers import REPO_ROOT, cli_in_process

#: a short run of the default docking (the plug stops 0.1 m short of the seat: not docked)
SHORT = (
    "trajectory.duration=0.2",
    "task.settle_time=0.1",
    "task.press_duration=0.1",
    "task.progress=false",
    "figures=false",
)


def test_the_statuses_are_distinct_and_say_what_happened():
    codes = [exit_codes.OK, exit_codes.FAILED, exit_codes.REFUSED, exit_codes.NOT_DOCKED]
    assert codes == [0, 1, 2, 3]
    assert [exit_codes.interrupted(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)] == [
        130,
        143,
        129,
    ]
    assert interrupt.exit_status(KeyboardInterrupt()) == 130
    assert interrupt.exit_status(interrupt.Stopped(signal.SIGTERM)) == 143


def test_the_table_is_the_same_in_the_docs_the_readme_and_the_help(capsys):
    from compliant_docking.cli import USAGE

    docs = (REPO_ROOT / "docs" / "exit_codes.md").read_text()
    rows = dict(re.findall(r"^\| \*\*([\d /]+)\*\* \| ([a-z ]+) \|", docs, flags=re.M))
    assert rows == {
        "0": "ok",
        "1": "failed",
        "2": "refused",
        "3": "not docked",
        "130 / 143 / 129": "interrupted",
    }
    readme = (REPO_ROOT / "README.md").read_text()
    assert "(docs/exit_codes.md)" in readme
    for code, words in [("0", "docked"), ("1", "failed"), ("2", "refused"), ("3", "not docked")]:
        assert re.search(rf"^\| {code} \| [^|]*{words}", readme, flags=re.M), code
        assert re.search(rf"^  {code} +[^\n]*{words}", USAGE, flags=re.M), code
    assert "130 / 143 / 129" in USAGE and "docs/exit_codes.md" in USAGE


def test_a_refused_run_exits_2_and_writes_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, err = cli_in_process(capsys, *SHORT, "controller.kk=1")
    assert code == exit_codes.REFUSED and "controller.kk" in err
    code, err = cli_in_process(capsys, *SHORT, "physics.timestep=-1")
    assert code == exit_codes.REFUSED and "physics.timestep" in err
    assert not (tmp_path / "runs").exists()  # a refused sweep: tests/sweep/test_guard.py


def test_a_failed_run_exits_1_and_an_undocked_one_3(tmp_path, monkeypatch, capsys):
    """Failed: the socket beyond the arm's reach (the start pose has no inverse
    kinematics), recorded as status failed. Not docked: a run that ends 0.2 s into its
    stroke, far from the seat."""
    monkeypatch.chdir(tmp_path)
    code, _ = cli_in_process(capsys, *SHORT, f"hydra.run.dir={tmp_path / 'far'}", "target.pos=[3.0,0.0,0.2]")
    assert code == exit_codes.FAILED == 1  # the documented number, not only the name
    far = json.loads((tmp_path / "far" / "metrics.json").read_text())
    assert far["status"] == "failed" and "inverse kinematics" in far["error"]
    code, _ = cli_in_process(capsys, *SHORT, f"hydra.run.dir={tmp_path / 'short'}")
    assert code == exit_codes.NOT_DOCKED == 3
    short = json.loads((tmp_path / "short" / "metrics.json").read_text())
    assert short["status"] == "ok" and short["success"] is False
    assert short["gate_failures"].startswith("not seated: ")


@pytest.mark.parametrize(
    ("module", "argv"),
    [
        ("compliant_docking.report", ["{tmp}/nowhere"]),
        ("compliant_docking.results.findings", ["{tmp}/nowhere"]),
        ("compliant_docking.results.convergence", ["{tmp}/nowhere", "--vary", "physics.timestep"]),
        ("compliant_docking.interface", ["--export-keyed", "{tmp}/cad", "--sides", "2"]),
        ("compliant_docking.interface", ["{tmp}/none.stl", "{tmp}/none.stl", "--out", "{tmp}/out"]),
    ],
)
def test_the_other_commands_refuse_with_2(module, argv, tmp_path, capsys):
    import importlib

    main = importlib.import_module(module).main
    try:
        code = main([a.format(tmp=tmp_path) for a in argv])
    except SystemExit as exc:  # argparse's own refusals
        code = exc.code
    assert code == exit_codes.REFUSED, capsys.readouterr().err
    assert not (tmp_path / "out").exists() and not (tmp_path / "cad").exists()

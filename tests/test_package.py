"""The package outside its checkout: what the wheel carries, how it finds its configs and
robots, how a user adds config options from outside it, and the built wheel itself in a
fresh virtualenv (docs/extending.md, README's "Installing the package")."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

import compliant_docking
from compliant_docking import ASSETS_DIR, CONF_DIR, resolve_path
from tests.helpers import REPO_ROOT, cli_in_process_output

#: the package's Python packages, as pyproject.toml lists them for the wheel
DECLARED = tomllib.loads((REPO_ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]


def _env() -> dict:
    return {**os.environ, "PYTHONUNBUFFERED": "1"}


def test_the_wheel_lists_every_package_of_the_checkout():
    """A sub-package missing from pyproject's list would be missing from the wheel."""
    found = {
        ".".join(p.parent.relative_to(REPO_ROOT).parts)
        for root in ("compliant_docking", "hydra_plugins")
        for p in (REPO_ROOT / root).rglob("__init__.py")
        if "__pycache__" not in p.parts
    }
    mapped = {"compliant_docking.conf", "compliant_docking.assets", "hydra_plugins"}
    assert set(DECLARED) == found | mapped


def test_configs_and_robots_are_found_through_the_package_not_the_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert (CONF_DIR / "config.yaml").is_file() and (ASSETS_DIR / "iiwa14" / "iiwa14.xml").is_file()
    # in the checkout (an editable install) they are the checkout's folders
    assert CONF_DIR == REPO_ROOT / "conf" and ASSETS_DIR == REPO_ROOT / "assets"
    assert not (Path(compliant_docking.__file__).parent / "conf").exists()  # not siblings in the source


def test_a_relative_path_is_the_working_directorys_first_then_the_packaged_assets(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    name = "assets/interfaces/keyed_cad/tool.xml"
    assert resolve_path(name) == ASSETS_DIR / "interfaces" / "keyed_cad" / "tool.xml"  # not here: packaged
    own = tmp_path / name
    own.parent.mkdir(parents=True)
    own.write_text("<mujoco/>")
    assert resolve_path(name) == own  # the working directory's own file wins
    assert resolve_path("elsewhere/tool.xml") == tmp_path / "elsewhere" / "tool.xml"  # not under assets/
    assert resolve_path(own) == own  # absolute


def test_a_missing_fragment_names_every_place_looked_in(tmp_path, monkeypatch):
    from compliant_docking.config import load_config
    from compliant_docking.sim.scene import build_scene
    from compliant_docking.sim.settings import sim_settings

    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError) as err:
        build_scene(sim_settings(load_config("tool.mjcf=assets/interfaces/nothing/tool.xml")))
    message = str(err.value)
    assert "tool.mjcf: no such file 'assets/interfaces/nothing/tool.xml'" in message
    assert str(tmp_path / "assets/interfaces/nothing/tool.xml") in message
    assert str(ASSETS_DIR / "interfaces/nothing/tool.xml") in message


# --------------------------------------------------------------- a user's own config options
#: docs/extending.md's example, file by file (the test writes them as the docs show them)
USER_CONF = {
    "my_conf/controller/stiff_impedance.yaml": """\
        # controller=stiff_impedance: the impedance law with stiffer, more damped gains
        defaults:
          - impedance        # this group's option (conf/controller/impedance.yaml)
          - _self_
        name: stiff_impedance
        k: 150.0
        d: 140.0
        """,
    "my_conf/tool/wide_plug.yaml": """\
        # tool=wide_plug: the cone plug, 2 mm wider
        defaults:
          - cone_plug
          - _self_
        name: wide_plug
        geometry:
          radius: 0.012
        """,
    "my_conf/target/wide_socket.yaml": """\
        # target=wide_socket: the cone socket, its bore following the plug, more clearance
        defaults:
          - cone_socket
          - _self_
        name: wide_socket
        geometry:
          radial_clearance: 0.0006
        """,
}


def _write_user_conf(root: Path) -> Path:
    for name, text in USER_CONF.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text))
    return root / "my_conf"


def test_the_documented_user_config_example_is_the_one_tested():
    doc = (REPO_ROOT / "docs" / "extending.md").read_text()
    for name, text in USER_CONF.items():
        assert name in doc
        assert textwrap.dedent(text).strip() in doc, f"docs/extending.md no longer shows {name} as tested"


def test_user_options_from_outside_the_package_run_and_sweep(tmp_path, monkeypatch, capsys):
    """The README's way to add a controller and an interface without editing the package:
    --config-dir for a run and a search path for a sweep, both through the command's main in
    this process, from another directory. A sweep composes every job's config where it is
    launched, on the default pool too (sweep/pool.py sends the composed configs to its
    workers), so Hydra's basic launcher here composes the jobs as the pool would."""
    conf = _write_user_conf(tmp_path)
    short = ("task.duration=0.5", "task.progress=false")
    monkeypatch.chdir(tmp_path)
    code, out, err = cli_in_process_output(
        capsys, "--config-dir", str(conf), "controller=stiff_impedance", "tool=wide_plug",
        "target=wide_socket", *short, "figures=false", f"hydra.run.dir={tmp_path / 'run'}",
    )  # fmt: skip
    assert code in (0, 3), out[-2000:] + err[-2000:]  # 3: a 0.5 s run is not seated
    config = (tmp_path / "run" / ".hydra" / "config.yaml").read_text()
    assert "name: stiff_impedance" in config and "k: 150.0" in config and "radius: 0.012" in config
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["status"] in ("ok", "incomplete") and metrics["error"] is None

    code, out, err = cli_in_process_output(
        capsys, "-m", f"hydra.searchpath=[file://{conf}]", "controller=impedance,stiff_impedance",
        *short, "hydra/launcher=basic", "hydra.callbacks.sweep.figures=false",
        f"hydra.sweep.dir={tmp_path / 'sweep'}",
    )  # fmt: skip
    assert code == 0, out[-2000:] + err[-2000:]
    jobs = sorted(p.parent.name for p in (tmp_path / "sweep").glob("*/metrics.json"))
    assert [j.split(",")[0] for j in jobs] == ["0_controller=impedance", "1_controller=stiff_impedance"]
    assert "k: 150.0" in (tmp_path / "sweep" / jobs[1] / ".hydra" / "config.yaml").read_text()


# --------------------------------------------------------------- the wheel
def _copy_checkout(dest: Path) -> Path:
    """The files git would commit (tracked, and new ones not ignored): what a clone builds."""
    listed = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard"],
        cwd=REPO_ROOT, capture_output=True, text=True, check=True,
    ).stdout.splitlines()  # fmt: skip
    for name in listed:
        source = REPO_ROOT / name
        if source.is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, dest / name)
    return dest


@pytest.mark.wheel
def test_the_built_wheel_installs_into_a_fresh_virtualenv_and_runs_outside_the_checkout(tmp_path):
    """Build the wheel, install it with its core dependencies into a new virtualenv (pip's
    cache may serve them) and, from a folder that is not the checkout, run the default
    docking, a 2-job sweep and ``report``."""
    source = _copy_checkout(tmp_path / "source")
    wheels = tmp_path / "wheels"
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "-w", str(wheels), str(source)],
        check=True, timeout=600, capture_output=True,
    )  # fmt: skip
    (wheel,) = wheels.glob("compliant_docking-*.whl")
    venv = tmp_path / "venv"
    base = getattr(sys, "_base_executable", sys.executable)
    subprocess.run([base, "-m", "venv", str(venv)], check=True, timeout=300)
    python = venv / "bin" / "python"
    install = subprocess.run(
        [str(python), "-m", "pip", "install", "--quiet", str(wheel)],
        capture_output=True,
        text=True,
        timeout=1200,
    )
    assert install.returncode == 0, install.stderr[-3000:]

    work = tmp_path / "elsewhere"
    work.mkdir()
    env = {k: v for k, v in _env().items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    where = subprocess.run(
        [str(python), "-c", "import json, compliant_docking as c, importlib.metadata as m; print(json.dumps("
         "[c.__file__, str(c.CONF_DIR), str(c.resolve_path('assets/interfaces/keyed_cad/tool.xml')), "
         "c.__version__, m.version('compliant-docking')]))"],
        cwd=work, capture_output=True, text=True, check=True, env=env,
    )  # fmt: skip
    package, conf, fragment, version, dist_version = json.loads(where.stdout)
    installed = str(venv / "lib")
    assert package.startswith(installed) and conf.startswith(installed) and fragment.startswith(installed)
    assert Path(fragment).is_file() and version == dist_version == compliant_docking.__version__

    cli = str(venv / "bin" / "compliant-docking")
    run = subprocess.run([cli], cwd=work, capture_output=True, text=True, timeout=600, env=env)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]  # the default docking docks
    (metrics,) = (work / "runs").glob("*/*/metrics.json")
    record = json.loads(metrics.read_text())
    assert record["success"] is True and record["git_commit"] is None  # not a checkout
    assert (metrics.parent / "figures" / "contact_force.png").is_file()

    sweep_dir = work / "sweep"
    sweep = subprocess.run(
        [cli, "-m", "task.misalignment.x=0.0,0.0005", f"hydra.sweep.dir={sweep_dir}"],
        cwd=work, capture_output=True, text=True, timeout=600, env=env,
    )  # fmt: skip
    assert sweep.returncode == 0, sweep.stdout[-2000:] + sweep.stderr[-2000:]
    assert len(list(sweep_dir.glob("*/metrics.json"))) == 2 and (sweep_dir / "summary.md").is_file()

    (sweep_dir / "summary.md").unlink()
    report = subprocess.run(
        [str(python), "-m", "compliant_docking.report", str(sweep_dir)],
        cwd=work, capture_output=True, text=True, timeout=600, env=env,
    )  # fmt: skip
    assert report.returncode == 0, report.stdout[-2000:] + report.stderr[-2000:]
    assert (sweep_dir / "summary.md").is_file()

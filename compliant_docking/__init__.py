"""compliant-docking: simulate a robot arm docking a plug into a socket under compliant control.

MuJoCo simulates the physics and contact, Pinocchio gives the controllers the arm's
dynamics, Hydra composes the experiment from config groups. Entry point:
``python -m compliant_docking [overrides]``; results: :func:`compliant_docking.results.load_runs`.

Importing this package is cheap and has no side effect: heavy libraries (mujoco,
pinocchio, proxsuite, matplotlib) are imported by the modules that need them, inside the
job, and the OpenGL backend is chosen when a video is rendered (compliant_docking/gl.py).

The config tree and the robot models ship with the package: ``compliant_docking.conf``
and ``compliant_docking.assets`` are the checkout's top-level ``conf/`` and ``assets/``
(a package-dir mapping in pyproject.toml), found through the import system, so an
editable install and an installed wheel find them alike.
"""

from importlib.util import find_spec
from pathlib import Path

__version__ = "0.1.0"


def _data_dir(name: str) -> Path:
    """The folder of the data package ``compliant_docking.<name>`` (not imported: only found)."""
    spec = find_spec(f"{__name__}.{name}")
    if spec is None or not spec.submodule_search_locations:
        raise ImportError(f"compliant_docking.{name} is missing: the installation is incomplete")
    return Path(next(iter(spec.submodule_search_locations)))


#: Hydra configuration tree (``conf/`` of the checkout).
CONF_DIR = _data_dir("conf")
#: Robot models and other static assets (``assets/`` of the checkout).
ASSETS_DIR = _data_dir("assets")


def resolve_path(path: str | Path) -> Path:
    """Where a file named in a config (``robot.mjcf``, ``tool.mjcf``, ``target.mjcf``) is.

    Absolute paths pass through. A relative path is taken from the working directory
    when the file is there; otherwise one that starts with ``assets/`` is taken from the
    package's assets (:data:`ASSETS_DIR`), so ``assets/iiwa14/iiwa14.xml`` names the
    packaged robot from any directory, in a checkout or an installed wheel. Otherwise the
    working-directory path is returned (it does not exist: the caller reports it with
    :func:`looked_in`).
    """
    p = Path(path).expanduser()
    if p.is_absolute():
        return p
    here = Path.cwd() / p
    if here.exists() or not p.parts or p.parts[0] != "assets":
        return here
    packaged = ASSETS_DIR.joinpath(*p.parts[1:])
    return packaged if packaged.exists() else here


def looked_in(path: str | Path) -> str:
    """The places :func:`resolve_path` looked for ``path`` (for 'no such file' messages)."""
    p = Path(path).expanduser()
    if p.is_absolute():
        return str(p)
    places = [str(Path.cwd() / p)]
    if p.parts and p.parts[0] == "assets":
        places.append(str(ASSETS_DIR.joinpath(*p.parts[1:])))
    return " or ".join(places)

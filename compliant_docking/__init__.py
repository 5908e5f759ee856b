"""compliant-docking: simulate a robot arm docking a plug into a socket under compliant control.

MuJoCo simulates the physics and contact, Pinocchio gives the controllers the arm's
dynamics, Hydra composes the experiment from config groups. Entry point:
``python -m compliant_docking [overrides]``; results: :func:`compliant_docking.results.load_runs`.

Importing this package is cheap on purpose: heavy libraries (mujoco, pinocchio,
proxsuite, matplotlib) are imported by the modules that need them, inside the job.
"""

from pathlib import Path

from compliant_docking import gl as _gl

# MuJoCo binds its OpenGL backend (MUJOCO_GL) when it is first imported: decide it here,
# before any module of the package imports mujoco (compliant_docking/gl.py).
_gl.configure()

__version__ = "0.1.0"

#: Repository root (the package is installed in editable mode from a checkout).
REPO_ROOT = Path(__file__).resolve().parent.parent
#: Robot models and other static assets.
ASSETS_DIR = REPO_ROOT / "assets"
#: Hydra configuration tree.
CONF_DIR = REPO_ROOT / "conf"


def resolve_path(path: str | Path) -> Path:
    """Absolute paths pass through; relative ones are taken from the repository root."""
    p = Path(path)
    return p if p.is_absolute() else REPO_ROOT / p

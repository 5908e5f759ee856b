"""The optional features and the extras that install them: one hint for every missing one.

The core install (``pip install compliant-docking``) runs a docking and a local sweep with
its figures and summary. Everything else is an extra of pyproject.toml; a feature whose
extra is missing stops with one line naming it (:func:`require`, :class:`MissingExtra`),
e.g. ``render=video needs av (the `video` extra): pip install 'compliant-docking[video]'
(in a checkout: pip install -e '.[video]')``.
"""

from __future__ import annotations

from importlib import import_module

#: extra → what needs it (the first words of the hint)
EXTRAS = {
    "cluster": "hydra/launcher=submitit_slurm (or submitit_local)",
    "video": "render=video",
    "tune": "hydra/sweeper=optuna (+experiment=tune)",
    "logger": "+logger=mlflow",
    "cad": "the CAD converter (python -m compliant_docking.interface)",
    "notebook": "make notebook",
    "env": "the Gymnasium environment (compliant_docking.env)",
}


class MissingExtra(ImportError):
    """An optional dependency is not installed; the message is the one-line hint."""


def hint(extra: str, missing: str) -> str:
    """The one line naming the feature, what is missing and the extra that installs it."""
    return (
        f"{EXTRAS[extra]} needs {missing} (the `{extra}` extra): "
        f"pip install 'compliant-docking[{extra}]' (in a checkout: pip install -e '.[{extra}]')"
    )


def require(extra: str, *modules: str) -> None:
    """Import ``modules``; raise :class:`MissingExtra` with :func:`hint` naming those that fail."""
    missing = []
    for module in modules:
        try:
            import_module(module)
        except ImportError:
            missing.append(module)
    if missing:
        raise MissingExtra(hint(extra, " and ".join(missing)))

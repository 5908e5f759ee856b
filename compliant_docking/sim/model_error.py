"""The controller's model against the plant: what the ``model_error`` config group changes.

The plant (MuJoCo) is never touched. The controller gets its own Pinocchio arm, built from
the same MJCF with believed inertial parameters, and the friction and damping it assumes:

- tool: mass × ``tool_mass_scale``, rotational inertia about its centre of mass ×
  ``tool_inertia_scale``, centre of mass + ``tool_com_offset_m`` (tool axes). The F/T
  sensor's payload compensation uses the believed tool too (compliant_docking/sim/sensor.py),
  so a payload error reads as a force, as it does on a real robot;
- arm links: mass and rotational inertia × ``link_mass_scale`` (a uniform density error);
- rotor inertia (armature) in the mass matrix × ``armature_scale``;
- the joint friction (MuJoCo's frictionloss) and damping the controllers' feed-forward and
  the momentum observer assume × ``friction_scale``, ``damping_scale``.

Each value is fixed, or drawn uniformly from its ``*_range`` with ``seed`` (default
``task.misalignment.seed``) from its own stream ``SeedSequence([seed, 100 + index])``, so
the draw of one quantity does not depend on which others are drawn and a seed gives the
same errors to every controller (common random numbers).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from compliant_docking.config.robustness import MODEL_ERROR_SCALARS, ModelErrorConfig
from compliant_docking.sim.misalignment import uniform_draw

if TYPE_CHECKING:
    from compliant_docking.sim.scene import Scene
    from compliant_docking.sim.settings import SimSettings

#: the scalar quantities, in the order of their random streams (100 + index)
SCALARS = tuple(name for name, _ in MODEL_ERROR_SCALARS)
#: the random streams of the centre-of-mass offset's axes
COM_STREAMS = (110, 111, 112)
#: flat keys recorded in metrics.json
RECORD_KEYS = (
    *(f"model_error_{name}" for name in SCALARS),
    "model_error_tool_com_offset_m",
    "model_error_tool_mass_kg",
    "model_error_seed",
)


@dataclass(frozen=True)
class ModelError:
    """One realised model error (believed = scale × true; CoM: believed − true)."""

    tool_mass_scale: float = 1.0
    tool_inertia_scale: float = 1.0
    link_mass_scale: float = 1.0
    friction_scale: float = 1.0
    damping_scale: float = 1.0
    armature_scale: float = 1.0
    tool_com_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [m], tool (dock) axes
    seed: int | None = None  # the seed of the draw; None when nothing was drawn

    @property
    def tool_changed(self) -> bool:
        return self.tool_mass_scale != 1.0 or self.tool_inertia_scale != 1.0 or any(self.tool_com_offset)

    @property
    def inertia_changed(self) -> bool:
        """Whether the controller's Pinocchio model differs from the plant's."""
        return self.tool_changed or self.link_mass_scale != 1.0 or self.armature_scale != 1.0

    def believed_tool(self, tool):
        """The tool (``RigidTool``) the controller believes; ``tool`` itself when exact."""
        if not self.tool_changed:
            return tool
        return replace(
            tool,
            mass=tool.mass * self.tool_mass_scale,
            inertia=np.asarray(tool.inertia, float) * self.tool_inertia_scale,
            com=np.asarray(tool.com, float) + np.asarray(self.tool_com_offset, float),
        )

    def adjust_links(self, model) -> None:
        """Scale the arm's link inertias and armature of a Pinocchio model in place (before
        the tool is appended to the flange)."""
        import pinocchio as pin

        if self.link_mass_scale != 1.0:
            s = self.link_mass_scale
            for j in range(1, model.njoints):
                inertia = model.inertias[j]
                model.inertias[j] = pin.Inertia(inertia.mass * s, inertia.lever.copy(), inertia.inertia * s)
        if self.armature_scale != 1.0:
            model.armature = model.armature * self.armature_scale

    def record(self, tool_mass: float | None = None) -> dict:
        """The flat metrics.json keys (:data:`RECORD_KEYS`); ``tool_mass``: the plant's tool
        mass [kg], for the believed − true mass."""
        out: dict = {f"model_error_{name}": float(getattr(self, name)) for name in SCALARS}
        out["model_error_tool_com_offset_m"] = float(np.linalg.norm(self.tool_com_offset))
        out["model_error_tool_mass_kg"] = (
            None if tool_mass is None else float(tool_mass * (self.tool_mass_scale - 1.0))
        )
        out["model_error_seed"] = self.seed
        return out


def draw(settings: ModelErrorConfig | None) -> ModelError:
    """The model error of ``settings`` (the ``model_error`` group, typed; None: exact). Fixed
    values pass through; a quantity with a ``*_range`` is drawn uniformly from it."""
    if settings is None:
        return ModelError()
    seed = int(settings.seed or 0)
    values: dict = {}
    drawn = False
    for index, name in enumerate(SCALARS):
        bounds = getattr(settings, f"{name}_range")
        if bounds is None:
            values[name] = float(getattr(settings, name))
        else:
            values[name] = uniform_draw(seed, 100 + index, float(bounds[0]), float(bounds[1]))
            drawn = True
    bounds = settings.tool_com_offset_m_range
    if bounds is None:
        com = tuple(float(c) for c in settings.tool_com_offset_m)
    else:
        com = tuple(uniform_draw(seed, s, float(bounds[0]), float(bounds[1])) for s in COM_STREAMS)
        drawn = True
    return ModelError(**values, tool_com_offset=com, seed=seed if drawn else None)  # type: ignore[arg-type]


def believed_arm(settings: SimSettings, scene: Scene, error: ModelError):
    """The controller's Pinocchio arm (``ArmModel``) for ``error``; None when it is the plant's."""
    if not error.inertia_changed:
        return None
    from compliant_docking import resolve_path
    from compliant_docking.sim.models import ArmModel, mount_placement

    return ArmModel(
        resolve_path(settings.robot.mjcf),
        settings.robot.ee_site,
        mount_placement(settings.tool.mount_pos, settings.tool.mount_quat, "tool.mount_quat"),
        error.believed_tool(scene.arm.tool),
        scene.gravity,
        adjust=error.adjust_links,
    )


def record_for(settings: SimSettings | None, tool_mass: float | None = None) -> dict:
    """The model-error keys of metrics.json for the run's ``settings`` (never raises: null
    when invalid; None: the config's nodes are not the schema's)."""
    if settings is None:
        return dict.fromkeys(RECORD_KEYS)
    try:
        return draw(settings.model_error).record(tool_mass)
    except Exception:
        return dict.fromkeys(RECORD_KEYS)
